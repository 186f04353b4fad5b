//! How closely a level surface fits the part, locally: per vertex of the level, the farthest
//! the part comes from the triangles around it (DESIGN.md §3.4 "locally per region").
//!
//! The part is sampled on a lattice in every triangle; each sample is charged to the level
//! triangle closest to it, so every sample p lies within fit(t) of the triangle t it was
//! charged to. A shape built from the tubes of radius c + fit(t) keeps every sample at c or
//! more; between samples the fit is measured, not bounded, like the Hausdorff distance it
//! refines, and the verification of every shape is what guarantees the clearance.

use rayon::prelude::*;

use crate::geom::Point3;
use crate::mesh::Mesh;
use crate::mesh::SurfaceDistance;

/// At most this many part samples (the spacing grows to keep within it).
const MAX_SAMPLES: f64 = 4.0e6;

/// Per vertex of `level`: the largest distance from a part sample to the level triangle it is
/// closest to, over the triangles around the vertex (0 where no sample is closest). The part
/// is sampled at about `spacing` (coarser when that would take more than `MAX_SAMPLES`).
pub fn local_fit(part: &Mesh, level: &Mesh, spacing: f64) -> Vec<f64> {
    let area = part.surface_area();
    let spacing = spacing.max((area / (0.43 * MAX_SAMPLES)).sqrt());
    let level_distance = SurfaceDistance::new(level);
    let charged: Vec<(u32, f64)> = (0..part.triangles.len())
        .into_par_iter()
        .flat_map_iter(|t| {
            lattice(&part.corners(t), spacing)
                .into_iter()
                .filter_map(|p| level_distance.closest(&p, f64::INFINITY))
                .map(|c| (c.triangle, c.distance))
                .collect::<Vec<_>>()
        })
        .collect();
    let mut triangle_fit = vec![0.0f64; level.triangles.len()];
    for (t, d) in charged {
        triangle_fit[t as usize] = triangle_fit[t as usize].max(d);
    }
    let mut vertex_fit = vec![0.0f64; level.positions.len()];
    for (tri, fit) in level.triangles.iter().zip(&triangle_fit) {
        for &v in tri {
            vertex_fit[v as usize] = vertex_fit[v as usize].max(*fit);
        }
    }
    vertex_fit
}

/// The points i/n·(b − a) + j/n·(c − a) + a, i + j ≤ n, with n the fewest steps that keep the
/// longest edge's steps within `spacing`.
fn lattice([a, b, c]: &[Point3; 3], spacing: f64) -> Vec<Point3> {
    let longest = (b - a).norm().max((c - b).norm()).max((a - c).norm());
    let n = (longest / spacing).ceil().clamp(1.0, 256.0) as usize;
    let mut points = Vec::with_capacity((n + 1) * (n + 2) / 2);
    for i in 0..=n {
        for j in 0..=n - i {
            let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
            points.push(a + (b - a) * u + (c - a) * v);
        }
    }
    points
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::fixtures::cuboid;

    /// A level that is the part moved 0.3 along +z: every part sample is 0.3 from the level
    /// (the closest level triangle is the moved copy of its own), whatever the sampling.
    #[test]
    fn a_shifted_copy_fits_by_its_shift() {
        let part = cuboid(10.0, 8.0, 6.0);
        let mut level = part.clone();
        for p in &mut level.positions {
            p.z += 0.3;
        }
        let fit = local_fit(&part, &level, 0.5);
        // Vertices on the top face: the part's top is 0.3 below it; the sides slide along
        // themselves (0 off the faces) but their corners reach the top, which is 0.3 away.
        for (v, f) in fit.iter().enumerate() {
            assert!((f - 0.3).abs() < 1e-9, "vertex {v}: {f}");
        }
    }

    /// Agreement with a brute-force reference: the largest distance from any part sample to
    /// the level is the largest local fit.
    #[test]
    fn the_largest_local_fit_is_the_one_sided_hausdorff_distance() {
        let part = crate::mesh::fixtures::uv_sphere(5.0, 16, 24);
        let level = crate::mesh::fixtures::uv_sphere(5.2, 6, 8);
        let spacing = 0.4;
        let fit = local_fit(&part, &level, spacing);
        let brute = (0..part.triangles.len())
            .flat_map(|t| lattice(&part.corners(t), spacing))
            .map(|p| {
                (0..level.triangles.len())
                    .map(|t| {
                        let [a, b, c] = level.corners(t);
                        (crate::geom::closest_point_on_triangle(&p, &a, &b, &c).0 - p).norm()
                    })
                    .fold(f64::INFINITY, f64::min)
            })
            .fold(0.0, f64::max);
        let largest = fit.iter().copied().fold(0.0, f64::max);
        assert!((largest - brute).abs() < 1e-9, "{largest} vs {brute}");
        assert!(fit.iter().any(|f| *f < largest - 1e-3), "the fit varies");
    }
}
