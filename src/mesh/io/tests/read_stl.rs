use nalgebra::Point3;

use super::{ascii_stl, binary_stl, cube, signed_volume, soup, tetra};
use crate::mesh::io::{Format, MeshIoError, RawMesh, Units, read_mesh_bytes};

fn load(bytes: &[u8]) -> Result<RawMesh, MeshIoError> {
    read_mesh_bytes(bytes, Format::Stl, "part.stl", None, Units::Millimetres)
}

#[test]
fn ascii_and_binary_of_the_same_cube_agree() {
    let m = cube();
    let a = load(&ascii_stl(&m, "cube")).unwrap();
    let b = load(&binary_stl(&m, "binary cube")).unwrap();
    // A binary header that starts with "solid", like real exporters write.
    let c = load(&binary_stl(&m, "solid cube exported by a CAD system")).unwrap();
    for r in [&a, &b, &c] {
        assert_eq!(r.mesh.triangles.len(), 12);
        assert_eq!(r.mesh.positions.len(), 36, "three new vertices per facet");
        assert_eq!(soup(&r.mesh), soup(&m), "small integers are exact in f32");
        assert!(r.warnings.is_empty(), "{:?}", r.warnings);
        assert!((signed_volume(&r.mesh) - 24.0).abs() < 1e-12);
    }
    assert_eq!(a.mesh, b.mesh);
    assert_eq!(b.mesh, c.mesh);
}

#[test]
fn ascii_is_tolerant_of_case_whitespace_junk_normals_and_several_solids() {
    let text = "\u{feff}  SOLID   first part\r\n\
        FACET NORMAL nan -1.#IND 0\r\n\tOUTER LOOP\r\n\
        VERTEX 0 0 0\r\n VERTEX 1e0 0 0\r\n VERTEX 0 +1.0 .0\r\n ENDLOOP\r\nENDFACET\r\n\
        endsolid first part\r\n\
        solid second\n facet outer loop vertex 0 0 1 vertex 1 0 1 vertex 0 1 1 endloop endfacet\n\
        endsolid";
    let r = load(text.as_bytes()).unwrap();
    assert_eq!(r.mesh.triangles.len(), 2);
    assert_eq!(r.mesh.positions[5], Point3::new(0.0, 1.0, 1.0));
    // Junk after endsolid: loads, with a warning.
    let mut junk = ascii_stl(&tetra(), "t");
    junk.extend_from_slice(b"\0\0\x1a");
    let r = load(&junk).unwrap();
    assert_eq!(
        (r.mesh.triangles.len(), r.warnings.len()),
        (4, 1),
        "{:?}",
        r.warnings
    );
    // Missing endsolid: loads, with a warning.
    let cut = "solid x\nfacet normal 0 0 1 outer loop vertex 0 0 0 vertex 1 0 0 vertex 0 1 0 \
               endloop endfacet\n";
    let r = load(cut.as_bytes()).unwrap();
    assert_eq!(r.mesh.triangles.len(), 1);
    assert_eq!(r.warnings.len(), 1, "{:?}", r.warnings);
}

#[test]
fn ascii_errors_give_the_line() {
    let good = String::from_utf8(ascii_stl(&tetra(), "t")).unwrap();
    // Line 6 is the third vertex of the first facet (tetra's first triangle is 0 2 1).
    let bad = good.replacen("vertex 1 0 0", "vertex 1 0x 0", 1);
    match load(bad.as_bytes()).unwrap_err() {
        MeshIoError::Syntax { line, message, .. } => {
            assert_eq!(line, 6, "{message}");
            assert!(message.contains("0x"), "{message}");
        }
        e => panic!("{e}"),
    }
    // A facet with only two vertices: reported at its `facet` line.
    let two = good.replacen("      vertex 0 1 0\n", "", 1);
    match load(two.as_bytes()).unwrap_err() {
        MeshIoError::Syntax { line, message, .. } => {
            assert_eq!(line, 2);
            assert!(message.contains("2 vertices"), "{message}");
        }
        e => panic!("{e}"),
    }
    let four = good.replacen(
        "      vertex 0 1 0\n",
        "      vertex 0 1 0\n      vertex 0 1 0\n",
        1,
    );
    assert!(
        load(four.as_bytes())
            .unwrap_err()
            .to_string()
            .contains("4 vertices")
    );
    // Non-finite coordinate: names vertex and line.
    let inf = good.replacen("vertex 1 0 0", "vertex 1 inf 0", 1);
    match load(inf.as_bytes()).unwrap_err() {
        MeshIoError::NonFinite {
            vertex, location, ..
        } => assert_eq!((vertex, location.as_str()), (2, "line 6")),
        e => panic!("{e}"),
    }
    let e = load(b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0").unwrap_err();
    assert!(e.to_string().contains("file ends"), "{e}");
    assert!(e.to_string().starts_with("part.stl: "), "{e}");
}

#[test]
fn binary_size_rules() {
    let b = binary_stl(&tetra(), "x");
    // A header that lies about the count (bigger than the file): error, no huge allocation.
    let mut lie = b.clone();
    lie[80..84].copy_from_slice(&u32::MAX.to_le_bytes());
    let e = load(&lie).unwrap_err().to_string();
    assert!(e.contains("4294967295 facets"), "{e}");
    // Truncated body.
    assert!(load(&b[..b.len() - 1]).is_err());
    // Trailing junk is tolerated with a warning.
    let mut pad = b.clone();
    pad.extend_from_slice(&[0u8; 7]);
    let r = load(&pad).unwrap();
    assert_eq!(r.mesh.triangles.len(), 4);
    assert!(r.warnings[0].contains("7 bytes"), "{:?}", r.warnings);
    // "solid" header with a wrong size: the ASCII attempt fails, and the message says both.
    let mut s = binary_stl(&tetra(), "solid x");
    s.push(0);
    let e = load(&s).unwrap_err().to_string();
    assert!(
        e.contains("not ASCII STL") && e.contains("does not match"),
        "{e}"
    );
    // NaN in binary: named by facet and corner.
    let mut nan = b.clone();
    let at = 84 + 50 * 2 + 12 + 12 + 4; // facet 2, corner 1, y
    nan[at..at + 4].copy_from_slice(&f32::NAN.to_le_bytes());
    match load(&nan).unwrap_err() {
        MeshIoError::NonFinite {
            vertex, location, ..
        } => assert_eq!((vertex, location.as_str()), (7, "binary facet 2, corner 1")),
        e => panic!("{e}"),
    }
    // Empty: zero facets, and too short to be anything.
    let mut empty = b[..84].to_vec();
    empty[80..84].fill(0);
    assert!(matches!(load(&empty), Err(MeshIoError::Empty { .. })));
    assert!(matches!(
        load(b"solid empty\nendsolid empty\n"),
        Err(MeshIoError::Empty { .. })
    ));
    assert!(matches!(load(b"abc"), Err(MeshIoError::Invalid { .. })));
    assert!(matches!(load(b""), Err(MeshIoError::Invalid { .. })));
}

#[test]
fn units_scale_positions() {
    let b = binary_stl(&tetra(), "x");
    for (u, s) in [
        (Units::Millimetres, 1.0),
        (Units::Metres, 1000.0),
        (Units::Inches, 25.4),
    ] {
        let r = read_mesh_bytes(&b, Format::Stl, "t.stl", None, u).unwrap();
        assert_eq!(r.mesh.positions[2], Point3::new(s, 0.0, 0.0));
    }
    // Within 1000 km in the file, beyond it in mm; and finite but beyond it.
    let big = "solid x\nfacet outer loop vertex 1e7 0 0 vertex 0 1 0 vertex 0 0 1 endloop \
               endfacet endsolid";
    assert!(load(big.as_bytes()).is_ok());
    let e = read_mesh_bytes(big.as_bytes(), Format::Stl, "t.stl", None, Units::Metres);
    assert!(matches!(e, Err(MeshIoError::NonFinite { vertex: 0, .. })));
    let huge = big.replace("1e7", "1e306");
    let e = read_mesh_bytes(
        huge.as_bytes(),
        Format::Stl,
        "t.stl",
        None,
        Units::Millimetres,
    );
    assert!(matches!(e, Err(MeshIoError::NonFinite { vertex: 0, .. })));
}
