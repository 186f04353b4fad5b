//! Binary STL writer.

use crate::mesh::Mesh;

/// Writes a mesh as binary STL: an 80-byte header (`header`, cut or padded with spaces), the
/// triangle count, and per triangle its unit normal and corners as f32 (mm) with a zero
/// attribute. STL has no shared vertices: readers weld them again. Same mesh ⇒ same bytes.
pub fn write_stl(mesh: &Mesh, header: &str) -> Vec<u8> {
    let mut out = Vec::with_capacity(84 + 50 * mesh.triangles.len());
    let mut head = [b' '; 80];
    // "solid" at the start makes some readers take a binary file for ASCII.
    let text = header.trim_start_matches("solid");
    for (slot, byte) in head.iter_mut().zip(text.bytes()) {
        *slot = byte;
    }
    out.extend_from_slice(&head);
    out.extend_from_slice(&(mesh.triangles.len() as u32).to_le_bytes());
    for t in 0..mesh.triangles.len() {
        let n = mesh.face_normal(t);
        let corners = mesh.corners(t);
        let mut put = |x: f64| out.extend_from_slice(&(x as f32).to_le_bytes());
        for c in [n.x, n.y, n.z] {
            put(if c.is_finite() { c } else { 0.0 });
        }
        for p in corners {
            put(p.x);
            put(p.y);
            put(p.z);
        }
        out.extend_from_slice(&0u16.to_le_bytes());
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::io::{Format, Units, read_mesh_bytes};

    /// A cube written and read back: the same 12 triangles at the same corners (f32-exact
    /// coordinates), and the reader's own check of the header count passes.
    #[test]
    fn a_cube_reads_back() {
        let cube = crate::mesh::fixtures::cuboid(2.0, 3.0, 4.0);
        let bytes = write_stl(&cube, "solid cube");
        assert_eq!(bytes.len(), 84 + 50 * 12);
        assert_ne!(&bytes[..5], b"solid");
        let raw = read_mesh_bytes(&bytes, Format::Stl, "cube.stl", None, Units::Millimetres)
            .expect("reads");
        assert_eq!(raw.mesh.triangles.len(), 12);
        for t in 0..12 {
            assert_eq!(raw.mesh.corners(t), cube.corners(t));
        }
    }
}
