use std::path::Path;

use crate::mesh::io::{Format, MeshIoError, Units, read_mesh};

#[test]
fn format_from_extension_is_case_insensitive() {
    let f = |p: &str| Format::from_path(Path::new(p));
    assert_eq!(f("a/b/part.STL"), Some(Format::Stl));
    assert_eq!(f("part.Obj"), Some(Format::Obj));
    assert_eq!(f("x.gltf"), Some(Format::Gltf));
    assert_eq!(f("x.tar.GLB"), Some(Format::Glb));
    assert_eq!(f("x.ply"), None);
    assert_eq!(f("stl"), None);
}

#[test]
fn units_parse_and_scale() {
    assert_eq!("mm".parse::<Units>().unwrap().scale_to_mm(), 1.0);
    assert_eq!(" M ".parse::<Units>().unwrap().scale_to_mm(), 1000.0);
    assert_eq!("in".parse::<Units>().unwrap().scale_to_mm(), 25.4);
    assert_eq!("inches".parse::<Units>(), Ok(Units::Inches));
    let e = "ft".parse::<Units>().unwrap_err().to_string();
    assert!(e.contains("ft"), "{e}");
    for u in [Units::Millimetres, Units::Metres, Units::Inches] {
        assert_eq!(u.to_string().parse::<Units>(), Ok(u));
    }
}

#[test]
fn read_mesh_errors_name_the_file() {
    let e = read_mesh(Path::new("/nonexistent/dir/part.stl"), Units::Millimetres).unwrap_err();
    assert!(matches!(e, MeshIoError::Io { .. }));
    assert!(
        e.to_string().starts_with("/nonexistent/dir/part.stl: "),
        "{e}"
    );
    let e = read_mesh(Path::new("part.step"), Units::Millimetres).unwrap_err();
    assert!(matches!(e, MeshIoError::UnknownFormat { .. }));
    assert!(e.to_string().starts_with("part.step: "), "{e}");
}
