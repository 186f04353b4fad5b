//! The innermost shape: a closed level surface pushed out by a small distance t along
//! conservative vertex directions.
//!
//! Vertex v moves by t·mᵥ with mᵥ = nᵥ / minₖ(nᵥ·nₖ) over its faces k (nᵥ the angle-weighted
//! normal), so mᵥ·nₖ ≥ 1 for every face around it: each moved triangle lies at least t in front
//! of the plane of the triangle it came from. Near a sharp edge minₖ(nᵥ·nₖ) goes to zero; it is
//! capped so that no vertex travels more than [`MAX_STRETCH`]·t, and what the cap gives away the
//! verification finds and pushes out. The offset is refused (the caller then uses the distance
//! grid, which cannot fold) where a triangle would turn over.

use crate::geom::{Point3, Vector3};
use crate::mesh::Mesh;

/// At most this many times the offset distance per vertex (minₖ(nᵥ·nₖ) ≥ 1/4, faces within
/// ≈ 75° of the vertex normal).
const MAX_STRETCH: f64 = 4.0;

/// Unit angle-weighted vertex normals (zero at an isolated or degenerate vertex).
pub(super) fn vertex_normals(mesh: &Mesh) -> Vec<Vector3> {
    let mut normals = vec![Vector3::zeros(); mesh.positions.len()];
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let n = mesh.face_normal(t);
        let p = mesh.corners(t);
        for k in 0..3 {
            let angle =
                crate::geom::angle_between(&(p[(k + 1) % 3] - p[k]), &(p[(k + 2) % 3] - p[k]));
            normals[tri[k] as usize] += n * angle;
        }
    }
    for n in &mut normals {
        let len = n.norm();
        if len > 0.0 {
            *n /= len;
        }
    }
    normals
}

/// The surface offset by `distance[v]` at each vertex, or `None` when a triangle would flip.
/// (With distances that vary, each point of a moved triangle is still in front of its old plane
/// by at least the smallest of its corners' distances.)
pub(super) fn normal_offset(surface: &Mesh, distance: &[f64]) -> Option<Mesh> {
    let normals = vertex_normals(surface);
    let mut least = vec![1.0f64; surface.positions.len()];
    for (t, tri) in surface.triangles.iter().enumerate() {
        let n = surface.face_normal(t);
        for &v in tri {
            least[v as usize] = least[v as usize].min(normals[v as usize].dot(&n));
        }
    }
    let positions: Vec<Point3> = surface
        .positions
        .iter()
        .zip(normals.iter().zip(&least).zip(distance))
        .map(|(p, ((n, k), d))| p + n * (d / k.max(1.0 / MAX_STRETCH)))
        .collect();
    let moved = Mesh {
        positions,
        triangles: surface.triangles.clone(),
    };
    // A degenerate triangle (zero normal) has no orientation to lose; only real ones count.
    let flips = (0..surface.triangles.len()).any(|t| {
        let before = surface.face_normal(t);
        before != Vector3::zeros() && moved.face_normal(t).dot(&before) <= 0.0
    });
    (!flips).then_some(moved)
}
