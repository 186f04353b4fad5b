//! Wavefront OBJ writer.

use std::fmt::Write as _;

use crate::mesh::Mesh;

/// Writes a mesh as OBJ text: a `#` comment header (each line of `comment`, then the counts),
/// `v x y z` in mm with the shortest decimal form that reads back to the same f64, and
/// `f a b c` with 1-based indices. Same mesh ⇒ same bytes.
pub fn write_obj(mesh: &Mesh, comment: &str) -> Vec<u8> {
    let mut s = String::with_capacity(64 + 40 * mesh.positions.len() + 24 * mesh.triangles.len());
    // Writing into a String cannot fail, so the fmt::Results below are ignored.
    let _ = writeln!(s, "# wavemill mesh, units mm");
    for line in comment.lines() {
        let _ = writeln!(s, "# {line}");
    }
    let _ = writeln!(
        s,
        "# {} vertices, {} triangles",
        mesh.positions.len(),
        mesh.triangles.len()
    );
    for p in &mesh.positions {
        let _ = writeln!(s, "v {} {} {}", p.x, p.y, p.z);
    }
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| u64::from(i) + 1);
        let _ = writeln!(s, "f {a} {b} {c}");
    }
    s.into_bytes()
}
