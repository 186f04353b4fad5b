use nalgebra::Point3;

use super::{cube, cube_obj, scratch_dir, signed_volume};
use crate::mesh::io::{Format, MeshIoError, RawMesh, Units, read_mesh, read_mesh_bytes};

fn load(text: &str) -> Result<RawMesh, MeshIoError> {
    read_mesh_bytes(
        text.as_bytes(),
        Format::Obj,
        "part.obj",
        None,
        Units::Millimetres,
    )
}

#[test]
fn quads_triangulate_and_vertices_stay_shared_across_groups() {
    let r = load(&cube_obj()).unwrap();
    assert_eq!(r.mesh.triangles.len(), 12);
    assert_eq!(
        r.mesh.positions.len(),
        8,
        "one model: groups do not duplicate vertices"
    );
    assert!(
        (signed_volume(&r.mesh) - 24.0).abs() < 1e-12,
        "fan keeps the quad's winding"
    );
    assert!(r.warnings.is_empty(), "{:?}", r.warnings);
    let mut sorted = r.mesh.positions.clone();
    sorted.sort_by(|a, b| {
        a.coords
            .as_slice()
            .partial_cmp(b.coords.as_slice())
            .unwrap()
    });
    let mut want = cube().positions;
    want.sort_by(|a, b| {
        a.coords
            .as_slice()
            .partial_cmp(b.coords.as_slice())
            .unwrap()
    });
    assert_eq!(sorted, want);
}

#[test]
fn missing_mtl_next_to_a_real_file_does_not_fail() {
    let dir = scratch_dir("obj_mtl");
    std::fs::write(dir.join("cube.OBJ"), cube_obj()).unwrap();
    let r = read_mesh(&dir.join("cube.OBJ"), Units::Inches).unwrap();
    assert_eq!(r.mesh.triangles.len(), 12);
    assert!((signed_volume(&r.mesh) - 24.0 * 25.4f64.powi(3)).abs() < 1e-6);
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn negative_indices_polygons_lines_and_points() {
    let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 1.5 0\n\
                f -5 -4 -3 -2 -1\nl 1 2\np 3\nf 1 2\n";
    let r = load(text).unwrap();
    assert_eq!(r.mesh.triangles.len(), 3, "pentagon → fan of 3");
    assert_eq!(r.warnings.len(), 3, "{:?}", r.warnings);
    // w divides (tobj), and we get f64 precision (tobj `use_f64`).
    let r = load("v 2 4 6 2\nv 0.1 0.2 0.30000000000000004\nv 0 0 1\nf 1 2 3\n").unwrap();
    assert_eq!(r.mesh.positions[0], Point3::new(1.0, 2.0, 3.0));
    assert_eq!(
        r.mesh.positions[1],
        Point3::new(0.1, 0.2, 0.30000000000000004)
    );
}

#[test]
fn errors_name_line_face_and_index() {
    let base = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    match load(&format!("{base}f 1 2 4\n")).unwrap_err() {
        MeshIoError::IndexOutOfRange {
            face,
            index,
            location,
            ..
        } => assert_eq!((face, index, location.as_str()), (1, 4, "line 5")),
        e => panic!("{e}"),
    }
    for bad in ["f 0 1 2", "f 1 2 -4", "f 1 2 99999999999999999999"] {
        assert!(load(&format!("{base}{bad}\n")).is_err(), "{bad}");
    }
    match load("v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n").unwrap_err() {
        MeshIoError::NonFinite {
            vertex, location, ..
        } => assert_eq!((vertex, location.as_str()), (1, "line 2")),
        e => panic!("{e}"),
    }
    let e = load("v 0 0\nf 1 1 1\n").unwrap_err();
    assert!(matches!(e, MeshIoError::Syntax { line: 1, .. }), "{e}");
    let e = load("v 0 0 0\nf 1 x 1\n").unwrap_err();
    assert!(matches!(e, MeshIoError::Syntax { line: 2, .. }), "{e}");
    assert!(matches!(load("v 0 0 0\n"), Err(MeshIoError::Empty { .. })));
    assert!(matches!(load(""), Err(MeshIoError::Empty { .. })));
    // A huge negative texture index used to overflow inside tobj; the vt lines never reach it.
    let r = load("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/-9223372036854775807 2/1 3/1\n");
    assert_eq!(r.unwrap().mesh.triangles.len(), 1);
    // Non-UTF-8 names and comments are fine.
    let mut bytes = b"o \xff\xfe\n# \xc3\x28\n".to_vec();
    bytes.extend_from_slice(base.as_bytes());
    let r = read_mesh_bytes(&bytes, Format::Obj, "x.obj", None, Units::Millimetres).unwrap();
    assert_eq!(r.mesh.triangles.len(), 1);
}
