use nalgebra::{Matrix4, Point3, Rotation3, Translation3, Vector3};
use serde_json::json;

use super::gltf_doc::{Doc, tetra_arrays};
use super::{close, normal, scratch_dir, signed_volume, soup, tetra};
use crate::mesh::io::{Format, MeshIoError, RawMesh, Units, read_mesh, read_mesh_bytes};

fn load(bytes: &[u8], format: Format) -> Result<RawMesh, MeshIoError> {
    read_mesh_bytes(bytes, format, "test.gltf", None, Units::Millimetres)
}

/// A document with the tetrahedron as mesh 0 (indexed TRIANGLES).
fn tetra_doc() -> Doc {
    let mut d = Doc::default();
    let (pts, idx) = tetra_arrays();
    let p = d.positions(&pts);
    let i = d.indices_u16(&idx);
    d.mesh(vec![Doc::prim(p, Some(i), 4)]);
    d
}

#[test]
fn tetra_loads_from_data_uri_glb_and_external_bin_identically() {
    let mut d = tetra_doc();
    d.node(json!({ "mesh": 0 }));
    d.scenes = Some(vec![vec![0]]);
    let a = load(&d.gltf_data_uri(), Format::Gltf).unwrap();
    assert_eq!(a.mesh, tetra(), "indexed as in the file, exact f32 values");
    assert!(a.warnings.is_empty(), "{:?}", a.warnings);
    let b = load(&d.glb(), Format::Glb).unwrap();
    assert_eq!(b.mesh, a.mesh);

    let dir = scratch_dir("external_bin");
    let (json, bin) = d.gltf_external("sub%20dir/tetra%20data.bin");
    std::fs::create_dir_all(dir.join("sub dir")).unwrap();
    std::fs::write(dir.join("sub dir/tetra data.bin"), bin).unwrap();
    std::fs::write(dir.join("tetra.GLTF"), json).unwrap();
    let c = read_mesh(&dir.join("tetra.GLTF"), Units::Millimetres).unwrap();
    assert_eq!(c.mesh, a.mesh);
    // Units scale positions.
    let m = read_mesh(&dir.join("tetra.GLTF"), Units::Metres).unwrap();
    assert_eq!(m.mesh.positions[1], Point3::new(1000.0, 0.0, 0.0));
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn missing_external_buffer_names_the_uri() {
    let mut d = tetra_doc();
    d.node(json!({ "mesh": 0 }));
    d.scenes = Some(vec![vec![0]]);
    let dir = scratch_dir("missing_bin");
    let (json, _) = d.gltf_external("nowhere.bin");
    std::fs::write(dir.join("t.gltf"), &json).unwrap();
    let e = read_mesh(&dir.join("t.gltf"), Units::Millimetres).unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, MeshIoError::Buffer { .. }), "{msg}");
    assert!(
        msg.contains("nowhere.bin") && msg.contains("t.gltf"),
        "{msg}"
    );
    // From memory there is no directory to look in: also an error naming the URI.
    let e = load(&json, Format::Gltf).unwrap_err().to_string();
    assert!(e.contains("nowhere.bin"), "{e}");
    // A buffer file shorter than byteLength.
    std::fs::write(dir.join("nowhere.bin"), [0u8; 8]).unwrap();
    let e = read_mesh(&dir.join("t.gltf"), Units::Millimetres)
        .unwrap_err()
        .to_string();
    assert!(e.contains("byteLength"), "{e}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn nested_trs_and_matrix_transforms_compose_parent_times_local() {
    let mut d = tetra_doc();
    // root: TRS (translate, rotate 90° about z, uniform scale 2) → child: matrix (translate z 5)
    // → grandchild with the mesh: TRS scale (1, 2, 3).
    let q = std::f32::consts::FRAC_1_SQRT_2;
    d.node(
        json!({ "translation": [10.0, 0.0, 0.0], "rotation": [0.0, 0.0, q, q],
                   "scale": [2.0, 2.0, 2.0], "children": [1] }),
    );
    d.node(json!({ "matrix": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,5,1], "children": [2] }));
    d.node(json!({ "mesh": 0, "scale": [1.0, 2.0, 3.0] }));
    d.scenes = Some(vec![vec![0]]);
    let got = load(&d.gltf_data_uri(), Format::Gltf).unwrap();

    let world = Translation3::new(10.0, 0.0, 0.0).to_homogeneous()
        * Rotation3::from_axis_angle(&Vector3::z_axis(), std::f64::consts::FRAC_PI_2)
            .to_homogeneous()
        * Matrix4::new_scaling(2.0)
        * Translation3::new(0.0, 0.0, 5.0).to_homogeneous()
        * Matrix4::new_nonuniform_scaling(&Vector3::new(1.0, 2.0, 3.0));
    let t = tetra();
    assert_eq!(got.mesh.triangles, t.triangles);
    for (g, p) in got.mesh.positions.iter().zip(&t.positions) {
        let want = world.transform_point(p);
        assert!(close(g, &want, 1e-6), "{g} vs {want}");
    }
    // Volume scales by det = 8 · 6.
    assert!((signed_volume(&got.mesh) - 48.0 / 6.0).abs() < 1e-5);
}

#[test]
fn negative_scale_node_keeps_triangles_outward() {
    for scale in [
        [-1.0, 1.0, 1.0],
        [1.0, -2.0, 1.0],
        [-1.0, -1.0, -1.0],
        [-1.0, -1.0, 1.0],
    ] {
        let mut d = tetra_doc();
        d.node(json!({ "children": [1], "scale": [1.0, 1.0, 1.0] }));
        d.node(json!({ "mesh": 0, "scale": scale }));
        d.scenes = Some(vec![vec![0]]);
        let got = load(&d.glb(), Format::Glb).unwrap();
        let det: f64 = scale.iter().product();
        let v = signed_volume(&got.mesh);
        assert!(
            (v - det.abs() / 6.0).abs() < 1e-9,
            "scale {scale:?}: volume {v}"
        );
    }
    // A mirroring matrix in a parent, undone by a mirror in the child: no flip overall.
    let mut d = tetra_doc();
    d.node(json!({ "matrix": [-1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1], "children": [1] }));
    d.node(json!({ "mesh": 0, "scale": [1.0, 1.0, -1.0] }));
    d.scenes = Some(vec![vec![0]]);
    let got = load(&d.glb(), Format::Glb).unwrap();
    assert_eq!(got.mesh.triangles, tetra().triangles);
    assert!((signed_volume(&got.mesh) - 1.0 / 6.0).abs() < 1e-9);
}

/// A 2×3 grid of points in the z = 0 plane, as a strip: 0 1 2 3 4 5 zig-zags up.
fn strip_points() -> Vec<[f32; 3]> {
    (0..6)
        .map(|i| [(i % 2) as f32, (i / 2) as f32, 0.0])
        .collect()
}

#[test]
fn triangle_strip_alternates_winding_and_skips_stitches() {
    let mut d = Doc::default();
    let p = d.positions(&strip_points());
    // 0,1,2,3 then a stitch (3 three times: three degenerate triangles), then 3,4,5, which
    // keeps its orientation because the stitch has an odd length.
    let i = d.indices_u16(&[0, 1, 2, 3, 3, 3, 4, 5]);
    d.mesh(vec![Doc::prim(p, Some(i), 5)]);
    d.node(json!({ "mesh": 0 }));
    d.scenes = Some(vec![vec![0]]);
    let got = load(&d.gltf_data_uri(), Format::Gltf).unwrap();
    assert_eq!(got.mesh.triangles, vec![[0, 1, 2], [1, 3, 2], [3, 5, 4]]);
    for f in 0..3 {
        let n = normal(&got.mesh, f);
        assert!(
            (n - Vector3::z()).norm() < 1e-12,
            "triangle {f}: normal {n}"
        );
    }
    assert!(
        got.warnings.iter().any(|w| w.contains("3 degenerate")),
        "{:?}",
        got.warnings
    );

    // Without indices: 0..count; every other triangle is reversed, so all face +z.
    let mut d = Doc::default();
    let p = d.positions(&strip_points());
    d.mesh(vec![Doc::prim(p, None, 5)]);
    d.node(json!({ "mesh": 0 }));
    d.scenes = Some(vec![vec![0]]);
    let got = load(&d.glb(), Format::Glb).unwrap();
    assert_eq!(got.mesh.triangles.len(), 4);
    for f in 0..4 {
        assert!((normal(&got.mesh, f) - Vector3::z()).norm() < 1e-12);
    }
}

#[test]
fn triangle_fan_turns_around_the_first_vertex() {
    let mut d = Doc::default();
    let mut pts = vec![[0.0f32, 0.0, 0.0]];
    for k in 0..=6 {
        let a = std::f32::consts::TAU * k as f32 / 6.0;
        pts.push([a.cos(), a.sin(), 1.0]);
    }
    let p = d.positions(&pts);
    let i = d.indices_u32(&[0, 1, 2, 3, 4, 5, 6, 7]);
    d.mesh(vec![Doc::prim(p, Some(i), 6)]);
    d.node(json!({ "mesh": 0 }));
    d.scenes = Some(vec![vec![0]]);
    let got = load(&d.gltf_data_uri(), Format::Gltf).unwrap();
    assert_eq!(got.mesh.triangles.len(), 6);
    for (f, t) in got.mesh.triangles.iter().enumerate() {
        assert!(t.contains(&0));
        assert!(normal(&got.mesh, f).z > 0.0, "a CCW fan seen from +z");
    }
}

#[test]
fn lines_and_points_are_skipped_with_a_warning() {
    let mut d = tetra_doc();
    let (pts, _) = tetra_arrays();
    let lp = d.positions(&pts);
    let li = d.indices_u16(&[0, 1, 1, 2]);
    d.meshes[0]["primitives"].as_array_mut().unwrap().extend([
        Doc::prim(lp, Some(li), 1),
        Doc::prim(lp, None, 0),
        Doc::prim(lp, None, 3),
    ]);
    d.node(json!({ "mesh": 0 }));
    d.node(json!({ "mesh": 0, "translation": [5.0, 0.0, 0.0] })); // instanced twice
    d.scenes = Some(vec![vec![0, 1]]);
    let got = load(&d.glb(), Format::Glb).unwrap();
    assert_eq!(got.mesh.triangles.len(), 8);
    assert_eq!(got.mesh.positions.len(), 8);
    assert_eq!(
        got.warnings.len(),
        3,
        "one per primitive, not per instance: {:?}",
        got.warnings
    );
    assert!(got.warnings.iter().any(|w| w.contains("Lines")));
    assert!(got.warnings.iter().any(|w| w.contains("Points")));
    assert!(got.warnings.iter().any(|w| w.contains("LineStrip")));

    // Only lines: an error that says why.
    let mut d = Doc::default();
    let (pts, _) = tetra_arrays();
    let lp = d.positions(&pts);
    d.mesh(vec![Doc::prim(lp, None, 1)]);
    d.node(json!({ "mesh": 0 }));
    d.scenes = Some(vec![vec![0]]);
    let e = load(&d.glb(), Format::Glb).unwrap_err();
    assert!(matches!(e, MeshIoError::Empty { .. }), "{e}");
    assert!(e.to_string().contains("Lines"), "{e}");
}

#[test]
fn scene_choice_default_then_first_then_root_nodes() {
    let mut d = tetra_doc();
    d.node(json!({ "mesh": 0 }));
    d.node(json!({ "mesh": 0, "translation": [0.0, 0.0, 7.0], "children": [2] }));
    d.node(json!({ "mesh": 0, "translation": [0.0, 0.0, 1.0] }));
    // Two scenes, default 0: only node 0.
    d.scenes = Some(vec![vec![0], vec![1]]);
    let got = load(&d.gltf_data_uri(), Format::Gltf).unwrap();
    assert_eq!(got.mesh.triangles.len(), 4);
    assert!(got.warnings.iter().any(|w| w.contains("2 scenes")));
    // No scenes: every root node (0 and 1; 2 is 1's child, at z 8).
    d.scenes = None;
    let got = load(&d.gltf_data_uri(), Format::Gltf).unwrap();
    assert_eq!(got.mesh.triangles.len(), 12);
    let top = got
        .mesh
        .positions
        .iter()
        .map(|p| p.z)
        .fold(f64::MIN, f64::max);
    assert!((top - 9.0).abs() < 1e-12);
}

#[test]
fn node_cycles_and_shared_children_are_errors_not_hangs() {
    let mut d = tetra_doc();
    d.node(json!({ "mesh": 0, "children": [1] }));
    d.node(json!({ "children": [0] }));
    d.scenes = Some(vec![vec![0]]);
    let e = load(&d.gltf_data_uri(), Format::Gltf)
        .unwrap_err()
        .to_string();
    assert!(e.contains("reached twice"), "{e}");
    // A long chain where every node lists the next one twice: 2^60 paths if followed.
    let mut d = tetra_doc();
    for i in 0..60 {
        d.node(json!({ "children": [i + 1, i + 1] }));
    }
    d.node(json!({ "mesh": 0 }));
    d.scenes = Some(vec![vec![0]]);
    assert!(load(&d.gltf_data_uri(), Format::Gltf).is_err());
    // A deep chain is fine (no recursion).
    let mut d = tetra_doc();
    for i in 0..20_000 {
        d.node(json!({ "children": [i + 1] }));
    }
    d.node(json!({ "mesh": 0 }));
    d.scenes = Some(vec![vec![0]]);
    // serde_json's recursion limit does not apply: nodes are a flat array.
    assert_eq!(load(&d.glb(), Format::Glb).unwrap().mesh.triangles.len(), 4);
}

#[test]
fn bad_indices_and_non_finite_positions_are_named() {
    let mut d = Doc::default();
    let (pts, _) = tetra_arrays();
    let p = d.positions(&pts);
    let i = d.indices_u16(&[0, 1, 2, 0, 1, 9]);
    d.mesh(vec![Doc::prim(p, Some(i), 4)]);
    d.node(json!({ "mesh": 0 }));
    d.scenes = Some(vec![vec![0]]);
    match load(&d.glb(), Format::Glb).unwrap_err() {
        MeshIoError::IndexOutOfRange {
            face,
            index,
            vertex_count,
            ..
        } => assert_eq!((face, index, vertex_count), (1, 9, 4)),
        e => panic!("{e}"),
    }

    let mut d = Doc::default();
    let mut pts = tetra_arrays().0;
    pts[2][1] = f32::INFINITY;
    let p = d.positions(&pts);
    d.accessors[p]["max"] = json!([1.0, 1.0, 1.0]); // JSON cannot hold inf
    d.mesh(vec![Doc::prim(p, None, 4)]);
    d.node(json!({ "mesh": 0 }));
    d.scenes = Some(vec![vec![0]]);
    match load(&d.glb(), Format::Glb).unwrap_err() {
        MeshIoError::NonFinite {
            vertex, location, ..
        } => {
            assert_eq!(vertex, 2);
            assert!(location.contains("vertex 2"), "{location}");
        }
        e => panic!("{e}"),
    }
    // Finite in f64 after the node's scale (the transform does not overflow), but no part's
    // coordinate: refused by name.
    let mut d = Doc::default();
    let p = d.positions(&[[0.0, 0.0, 0.0], [3e38, 0.0, 0.0], [0.0, 1.0, 0.0]]);
    d.mesh(vec![Doc::prim(p, None, 4)]);
    d.node(json!({ "mesh": 0, "scale": [1e10, 1.0, 1.0] }));
    d.scenes = Some(vec![vec![0]]);
    match load(&d.glb(), Format::Glb) {
        Err(MeshIoError::NonFinite {
            vertex: 1, value, ..
        }) => assert!(value[0] > 1e48),
        other => panic!("{other:?}"),
    }
}

#[test]
fn sparse_and_quantized_positions() {
    let mut d = tetra_doc();
    d.sparse_replace(0, 3, [0.0, 0.0, 2.0]); // apex moves to z = 2
    d.node(json!({ "mesh": 0 }));
    d.scenes = Some(vec![vec![0]]);
    let got = load(&d.glb(), Format::Glb).unwrap();
    assert_eq!(got.mesh.positions[3], Point3::new(0.0, 0.0, 2.0));
    assert!((signed_volume(&got.mesh) - 2.0 / 6.0).abs() < 1e-12);

    let mut d = Doc::default();
    let p = d.positions_i16(&[[0, 0, 0], [32767, 0, 0], [0, 32767, 0], [0, 0, -32768]]);
    let i = d.indices_u16(&[0, 1, 2]);
    d.mesh(vec![Doc::prim(p, Some(i), 4)]);
    d.node(json!({ "mesh": 0, "scale": [100.0, 100.0, 100.0] }));
    d.scenes = Some(vec![vec![0]]);
    let got = load(&d.gltf_data_uri(), Format::Gltf).unwrap();
    assert_eq!(got.mesh.positions[1], Point3::new(100.0, 0.0, 0.0));
    assert_eq!(got.mesh.positions[3], Point3::new(0.0, 0.0, -100.0));
}

#[test]
fn lying_lengths_are_errors() {
    let mut d = tetra_doc();
    d.node(json!({ "mesh": 0 }));
    d.scenes = Some(vec![vec![0]]);
    // Accessor count far beyond its view.
    let mut big = tetra_doc();
    big.node(json!({ "mesh": 0 }));
    big.scenes = Some(vec![vec![0]]);
    big.accessors[0]["count"] = json!(1_000_000_000_000u64);
    let e = load(&big.glb(), Format::Glb).unwrap_err().to_string();
    assert!(e.contains("accessor 0"), "{e}");
    // A view-less accessor (all zeros) with a huge count.
    let mut z = tetra_doc();
    z.node(json!({ "mesh": 0 }));
    z.scenes = Some(vec![vec![0]]);
    z.accessors[0].as_object_mut().unwrap().remove("bufferView");
    z.accessors[0]["count"] = json!(u64::from(u32::MAX) * 4);
    assert!(load(&z.glb(), Format::Glb).is_err());
    // GLB header length beyond the data, and below the header size.
    let mut glb = d.glb();
    glb[8..12].copy_from_slice(&u32::MAX.to_le_bytes());
    assert!(load(&glb, Format::Glb).is_err());
    glb[8..12].copy_from_slice(&3u32.to_le_bytes());
    assert!(load(&glb, Format::Glb).is_err());
    // Many instances of a 10k-vertex mesh from a small file stop at the output limit.
    let mut many = Doc::default();
    let pts: Vec<[f32; 3]> = (0..10_000).map(|i| [i as f32, 0.0, 0.0]).collect();
    let p = many.positions(&pts);
    many.mesh(vec![Doc::prim(p, None, 4)]);
    for _ in 0..5_000 {
        many.node(json!({ "mesh": 0 }));
    }
    let e = load(&many.glb(), Format::Glb).unwrap_err();
    assert!(matches!(e, MeshIoError::TooLarge { .. }), "{e}");
}

#[test]
fn glb_read_as_gltf_and_back_agree() {
    // The reader looks at the magic bytes, not the extension.
    let mut d = tetra_doc();
    d.node(json!({ "mesh": 0 }));
    d.scenes = Some(vec![vec![0]]);
    let a = load(&d.glb(), Format::Gltf).unwrap();
    let b = load(&d.gltf_data_uri(), Format::Glb).unwrap();
    assert_eq!(soup(&a.mesh), soup(&b.mesh));
}

/// Issue 17 item 13: POSITION declared UNSIGNED_BYTE (the bytes of f32 coordinates read one by
/// one) loaded as a garbage mesh. The core spec allows only FLOAT VEC3.
#[test]
fn integer_positions_without_quantization_are_refused_naming_the_type() {
    let (pts, idx) = tetra_arrays();
    let floats: Vec<u8> = pts.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
    let build = |quantization: bool| {
        let mut d = Doc::default();
        // 12 bytes per vertex read as 3 bytes + 9 bytes of stride: 4 "vertices".
        let p = d.raw_accessor(&floats, 5121, "VEC3", 4, Some(12));
        d.accessors[p]["min"] = json!([0, 0, 0]); // the validator wants bounds on POSITION
        d.accessors[p]["max"] = json!([255, 255, 255]);
        let i = d.indices_u16(&idx);
        d.mesh(vec![Doc::prim(p, Some(i), 4)]);
        d.node(json!({ "mesh": 0 }));
        d.scenes = Some(vec![vec![0]]);
        if quantization {
            d.extensions_required.push("KHR_mesh_quantization");
        }
        d
    };
    let msg = load(&build(false).gltf_data_uri(), Format::Gltf)
        .unwrap_err()
        .to_string();
    for needle in [
        "test.gltf",
        "mesh 0 primitive 0",
        "POSITION",
        "UNSIGNED_BYTE",
        "KHR_mesh_quantization",
    ] {
        assert!(msg.contains(needle), "`{needle}` missing in: {msg}");
    }
    // Declared under KHR_mesh_quantization, the same bytes are what the file says they are:
    // unnormalized u8 coordinates.
    let got = load(&build(true).gltf_data_uri(), Format::Gltf).unwrap();
    for (k, p) in got.mesh.positions.iter().enumerate() {
        let b = &floats[12 * k..12 * k + 3];
        assert_eq!(
            *p,
            Point3::new(f64::from(b[0]), f64::from(b[1]), f64::from(b[2]))
        );
    }
    // UNSIGNED_INT is not a position type even under the extension; nor is VEC2 or VEC4.
    for (ty, dims, stride) in [(5125, "VEC3", 12), (5126, "VEC2", 12), (5126, "VEC4", 16)] {
        let mut d = Doc::default();
        let bytes = vec![0u8; 4 * stride];
        let p = d.raw_accessor(&bytes, ty, dims, 4, Some(stride));
        let n = usize::from(dims.as_bytes()[3] - b'0');
        d.accessors[p]["min"] = json!(vec![0; n]);
        d.accessors[p]["max"] = json!(vec![0; n]);
        d.mesh(vec![Doc::prim(p, None, 4)]);
        d.node(json!({ "mesh": 0 }));
        d.scenes = Some(vec![vec![0]]);
        d.extensions_required.push("KHR_mesh_quantization");
        let msg = load(&d.glb(), Format::Glb).unwrap_err().to_string();
        // (the crate's validator already refuses VEC2 and VEC4 bounds on POSITION)
        assert!(
            msg.contains("test.gltf") && msg.contains("POSITION"),
            "{msg}"
        );
        if ty == 5125 {
            assert!(msg.contains("declared UNSIGNED_INT (5125) VEC3"), "{msg}");
        }
    }
}

#[test]
fn index_accessors_must_be_unsigned_integer_scalars() {
    let (pts, _) = tetra_arrays();
    for (ty, dims, bytes) in [
        (5126, "SCALAR", 1.0f32.to_le_bytes().repeat(3)), // FLOAT
        (5122, "SCALAR", [1u8, 0].repeat(3)),             // SHORT (signed)
        (5123, "VEC3", [1u8, 0].repeat(3)),               // UNSIGNED_SHORT, but VEC3
    ] {
        let mut d = Doc::default();
        let p = d.positions(&pts);
        let count = if dims == "VEC3" { 1 } else { 3 };
        let i = d.raw_accessor(&bytes, ty, dims, count, None);
        d.mesh(vec![Doc::prim(p, Some(i), 4)]);
        d.node(json!({ "mesh": 0 }));
        d.scenes = Some(vec![vec![0]]);
        let msg = load(&d.gltf_data_uri(), Format::Gltf)
            .unwrap_err()
            .to_string();
        assert!(
            msg.contains("test.gltf") && msg.contains("indices are declared") && msg.contains(dims),
            "{msg}"
        );
    }
}
