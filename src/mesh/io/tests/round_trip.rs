use nalgebra::Point3;
use proptest::prelude::*;
use serde_json::Value;

use super::{cube, soup, tetra};
use crate::mesh::Mesh;
use crate::mesh::io::{
    Format, GlbBuilder, GlbError, MeshIoError, RawMesh, Units, read_mesh_bytes, write_obj,
};

fn load(bytes: &[u8], format: Format) -> Result<RawMesh, MeshIoError> {
    read_mesh_bytes(bytes, format, "round-trip", None, Units::Millimetres)
}

fn f32_close(a: &Point3<f64>, b: &Point3<f64>) -> bool {
    (0..3).all(|k| (a[k] - b[k]).abs() <= 1e-6 * a[k].abs().max(b[k].abs()).max(1e-30))
}

prop_compose! {
    /// A random indexed mesh (possibly with unused vertices and repeated indices).
    fn arb_mesh()(n in 1usize..40)(
        positions in prop::collection::vec(
            prop::array::uniform3(prop_oneof![
                -1e4f64..1e4,
                Just(0.0),
                Just(-0.0),
                (-1e-3f64..1e-3),
            ]), n),
        triangles in prop::collection::vec(prop::array::uniform3(0..n as u32), 1..60),
    ) -> Mesh {
        Mesh {
            positions: positions.into_iter().map(Point3::from).collect(),
            triangles,
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn obj_round_trip_is_exact(m in arb_mesh()) {
        let bytes = write_obj(&m, "round trip\nsecond line");
        prop_assert_eq!(&bytes, &write_obj(&m, "round trip\nsecond line"));
        let r = load(&bytes, Format::Obj).unwrap();
        // tobj renumbers vertices by first use; the triangles' positions are bit-exact.
        prop_assert_eq!(soup(&r.mesh), soup(&m));
    }

    #[test]
    fn glb_round_trip_keeps_indices_and_f32_positions(m in arb_mesh()) {
        let mut b = GlbBuilder::new();
        b.add_triangles("part", &m, [0.5, 0.5, 0.5, 1.0], None).unwrap();
        let bytes = b.build();
        prop_assert_eq!(&bytes, &b.build());
        let r = load(&bytes, Format::Glb).unwrap();
        prop_assert_eq!(&r.mesh.triangles, &m.triangles);
        prop_assert_eq!(r.mesh.positions.len(), m.positions.len());
        for (a, b) in r.mesh.positions.iter().zip(&m.positions) {
            prop_assert!(f32_close(a, b), "{} vs {}", a, b);
        }
    }
}

#[test]
fn obj_text_is_as_documented() {
    let text = String::from_utf8(write_obj(&tetra(), "tetra")).unwrap();
    assert!(text.starts_with("# wavemill mesh, units mm\n# tetra\n# 4 vertices, 4 triangles\n"));
    assert!(
        text.contains("\nv 1 0 0\n") && text.contains("\nf 1 3 2\n"),
        "{text}"
    );
    let r = load(text.as_bytes(), Format::Obj).unwrap();
    assert_eq!(soup(&r.mesh), soup(&tetra()));
}

fn glb_json(bytes: &[u8]) -> Value {
    assert_eq!(&bytes[..4], b"glTF");
    assert_eq!(u32::from_le_bytes(bytes[4..8].try_into().unwrap()), 2);
    assert_eq!(
        u32::from_le_bytes(bytes[8..12].try_into().unwrap()) as usize,
        bytes.len()
    );
    let jlen = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    assert_eq!(&bytes[16..20], b"JSON");
    assert_eq!(jlen % 4, 0);
    let json = &bytes[20..20 + jlen];
    if 20 + jlen < bytes.len() {
        let blen = u32::from_le_bytes(bytes[20 + jlen..24 + jlen].try_into().unwrap()) as usize;
        assert_eq!(&bytes[24 + jlen..28 + jlen], b"BIN\0");
        assert_eq!(blen % 4, 0);
        assert_eq!(28 + jlen + blen, bytes.len());
    }
    serde_json::from_slice(json).unwrap()
}

#[test]
fn glb_structure_materials_colours_and_lines() {
    let red = [1.0, 0.0, 0.0, 1.0];
    let grey = [0.8, 0.8, 0.8, 0.5];
    let c = cube();
    let colours: Vec<[f32; 4]> = (0..8).map(|i| [i as f32 / 8.0, 0.0, 1.0, 1.0]).collect();
    let mut b = GlbBuilder::new();
    b.add_triangles("cube", &c, grey, Some(&colours))
        .unwrap()
        .add_triangles("tetra", &tetra(), red, None)
        .unwrap()
        .add_lines(
            "segments",
            &[[Point3::origin(), Point3::new(0.0, 0.0, 9.0)]],
            red,
        )
        .unwrap()
        .add_polylines(
            "path",
            &[vec![
                Point3::new(0.0, 0.0, 1.0),
                Point3::new(1.0, 0.0, 1.0),
                Point3::new(1.0, 1.0, 1.0),
            ]],
            grey,
        )
        .unwrap();
    let bytes = b.build();
    let j = glb_json(&bytes);
    assert_eq!(j["asset"]["generator"], "wavemill");
    assert_eq!(j["asset"]["version"], "2.0");
    assert_eq!(j["scene"], 0);
    assert_eq!(j["nodes"].as_array().unwrap().len(), 4);
    assert_eq!(j["scenes"][0]["nodes"].as_array().unwrap().len(), 4);
    let mats = j["materials"].as_array().unwrap();
    assert_eq!(mats.len(), 2, "one material per distinct colour");
    assert_eq!(
        mats[0]["pbrMetallicRoughness"]["baseColorFactor"].to_string(),
        "[0.8,0.8,0.8,0.5]"
    );
    assert_eq!(mats[0]["alphaMode"], "BLEND");
    let modes: Vec<u64> = j["meshes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["primitives"][0]["mode"].as_u64().unwrap())
        .collect();
    assert_eq!(modes, [4, 4, 1, 1]);
    assert!(j["meshes"][0]["primitives"][0]["attributes"]["COLOR_0"].is_u64());
    let pos = &j["accessors"][j["meshes"][0]["primitives"][0]["attributes"]["POSITION"]
        .as_u64()
        .unwrap() as usize];
    assert_eq!(pos["min"].to_string(), "[0.0,0.0,0.0]");
    assert_eq!(pos["max"].to_string(), "[2.0,3.0,4.0]");
    // The polyline: 3 points, 2 segments.
    let idx =
        &j["accessors"][j["meshes"][3]["primitives"][0]["indices"].as_u64().unwrap() as usize];
    assert_eq!(idx["count"], 4);

    // Reading it back: triangles of both meshes, the line sets skipped with warnings.
    let r = load(&bytes, Format::Glb).unwrap();
    assert_eq!(r.mesh.triangles.len(), 16);
    assert_eq!(r.warnings.len(), 2, "{:?}", r.warnings);
    let mut both = c.clone();
    let t = tetra();
    both.triangles
        .extend(t.triangles.iter().map(|x| x.map(|i| i + 8)));
    both.positions.extend(t.positions);
    assert_eq!(r.mesh, both, "small integers are exact in f32");
}

#[test]
fn glb_edge_cases() {
    // Nothing added: still a valid file with an empty scene.
    let bytes = GlbBuilder::new().build();
    let j = glb_json(&bytes);
    assert!(j.get("buffers").is_none() && j.get("nodes").is_none());
    let e = load(&bytes, Format::Glb).unwrap_err();
    assert!(matches!(e, MeshIoError::Empty { .. }), "{e}");
    // Bad input to the builder is an error, not a panic or a broken file.
    let mut b = GlbBuilder::new();
    let mut bad = tetra();
    bad.triangles.push([0, 1, 4]);
    assert!(matches!(
        b.add_triangles("x", &bad, [1.0; 4], None),
        Err(GlbError::IndexOutOfRange { index: 4, .. })
    ));
    let mut nan = tetra();
    nan.positions[2].y = f64::NAN;
    assert!(matches!(
        b.add_triangles("x", &nan, [1.0; 4], None),
        Err(GlbError::NonFinite { vertex: 2, .. })
    ));
    let mut huge = tetra();
    huge.positions[1].x = 1e300; // finite in f64, not in f32
    assert!(b.add_triangles("x", &huge, [1.0; 4], None).is_err());
    assert!(matches!(
        b.add_triangles("x", &tetra(), [1.0; 4], Some(&[[1.0; 4]; 3])),
        Err(GlbError::ColourCount { .. })
    ));
    assert!(
        b.add_lines("x", &[[Point3::origin(); 2]], [f32::NAN; 4])
            .is_err()
    );
    let single: Vec<Vec<Point3<f64>>> = vec![vec![Point3::origin()]];
    b.add_polylines("dots", &single, [1.0; 4]).unwrap();
    assert!(
        b.build() == GlbBuilder::new().build(),
        "failed and empty parts add nothing"
    );
}
