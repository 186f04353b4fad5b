//! Principal curvatures per vertex and the convex / concave / saddle trichotomy (seed 001 ch. 4:
//! a ball of radius r gouges a concave region whose smallest radius of curvature is below r).
//!
//! Each vertex's 2-ring is fitted, in the frame of its normal, by the height function
//! w = a·u² + b·uv + c·v² + d·u + e·v (least squares). The principal curvatures are the
//! eigenvalues of that graph's shape operator at the vertex, I⁻¹·II with
//! I = [[1+d², de], [de, 1+e²]] and II = [[2a, b], [b, 2c]] / √(1+d²+e²): exact for any quadric
//! sampled exactly, so a sphere, a cylinder and a saddle are closed-form tests. Sign convention:
//! positive curvature bends away from the outward normal (convex), negative toward it (concave).

use nalgebra::{Matrix2, Matrix5, Vector5};
use serde::Serialize;

use crate::geom::{Vector3, orthonormal_frame};
use crate::mesh::Mesh;

/// The shape class of a point (seed 001 ch. 4), with curvatures within ±`flat` counted as zero.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ShapeClass {
    /// Both principal curvatures ≥ 0, one > 0: any ball touches here alone.
    Convex,
    /// Both ≤ 0, one < 0 (a fillet is concave in one direction): a ball larger than the
    /// concave radius gouges.
    Concave,
    /// One > 0, one < 0: the concave direction limits the ball as in a concave region.
    Saddle,
    /// Both ≈ 0.
    Flat,
}

/// Principal curvatures of one vertex, 1/mm, `min ≤ max`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Curvature {
    pub min: f64,
    pub max: f64,
}

impl Curvature {
    pub fn class(&self, flat: f64) -> ShapeClass {
        match (self.max > flat, self.min < -flat) {
            (true, true) => ShapeClass::Saddle,
            (true, false) => ShapeClass::Convex,
            (false, true) => ShapeClass::Concave,
            (false, false) => ShapeClass::Flat,
        }
    }

    /// The smallest concave radius of curvature, mm (`None` where nothing bends concave).
    pub fn concave_radius(&self, flat: f64) -> Option<f64> {
        (self.min < -flat).then(|| -1.0 / self.min)
    }
}

/// One-ring neighbours of every vertex, sorted (deterministic).
pub fn vertex_neighbours(mesh: &Mesh) -> Vec<Vec<u32>> {
    let mut ring = vec![Vec::new(); mesh.positions.len()];
    for t in &mesh.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            ring[a as usize].push(b);
            ring[b as usize].push(a);
        }
    }
    for r in &mut ring {
        r.sort_unstable();
        r.dedup();
    }
    ring
}

/// Principal curvatures of each vertex from the quadric fit of its 2-ring (3-ring where the
/// 2-ring has fewer than 8 points); `None` where the normal is undefined or the fit is singular.
pub fn vertex_curvatures(
    mesh: &Mesh,
    normals: &[Vector3],
    ring: &[Vec<u32>],
) -> Vec<Option<Curvature>> {
    use rayon::prelude::*;
    (0..mesh.positions.len())
        .into_par_iter()
        .map(|v| {
            let n = normals[v];
            if n.norm() < 0.5 {
                return None;
            }
            let mut near = neighbourhood(ring, v, 2);
            if near.len() < 8 {
                near = neighbourhood(ring, v, 3);
            }
            let p = mesh.positions[v];
            let (t1, t2) = orthonormal_frame(&n);
            let local: Vec<(f64, f64, f64)> = near
                .iter()
                .map(|&q| {
                    let d = mesh.positions[q as usize] - p;
                    (d.dot(&t1), d.dot(&t2), d.dot(&n))
                })
                .collect();
            fit_quadric(&local)
        })
        .collect()
}

/// Vertices within `rings` edges of `v` (without `v`), in a fixed order.
fn neighbourhood(ring: &[Vec<u32>], v: usize, rings: usize) -> Vec<u32> {
    let mut seen = vec![v as u32];
    let mut frontier = vec![v as u32];
    for _ in 0..rings {
        let mut next = Vec::new();
        for &f in &frontier {
            for &w in &ring[f as usize] {
                if !seen.contains(&w) {
                    seen.push(w);
                    next.push(w);
                }
            }
        }
        frontier = next;
    }
    seen.remove(0);
    seen
}

/// Least-squares fit of w = a·u² + b·uv + c·v² + d·u + e·v through the origin, then the
/// principal curvatures of that graph at the origin (module docs).
pub fn fit_quadric(points: &[(f64, f64, f64)]) -> Option<Curvature> {
    if points.len() < 5 {
        return None;
    }
    // Scale the coordinates to unit size, so the normal equations stay well conditioned on
    // tiny and huge neighbourhoods alike; curvatures scale back by 1/s.
    let s = points
        .iter()
        .map(|&(u, v, _)| u.hypot(v))
        .fold(0.0, f64::max);
    if s <= 0.0 {
        return None;
    }
    let mut normal = Matrix5::zeros();
    let mut rhs = Vector5::zeros();
    for &(u, v, w) in points {
        let (u, v, w) = (u / s, v / s, w / s);
        let row = Vector5::new(u * u, u * v, v * v, u, v);
        normal += row * row.transpose();
        rhs += row * w;
    }
    let x = normal.cholesky()?.solve(&rhs);
    let (a, b, c, d, e) = (x[0], x[1], x[2], x[3], x[4]);
    let first = Matrix2::new(1.0 + d * d, d * e, d * e, 1.0 + e * e);
    let second = Matrix2::new(2.0 * a, b, b, 2.0 * c) / (1.0 + d * d + e * e).sqrt();
    let shape = first.try_inverse()? * second;
    let (trace, det) = (shape.trace(), shape.determinant());
    let root = (0.25 * trace * trace - det).max(0.0).sqrt();
    // The height w grows along the outward normal, so a convex surface has negative
    // eigenvalues: flip them to the convex-positive convention.
    let (k1, k2) = (-(0.5 * trace + root) / s, -(0.5 * trace - root) / s);
    Some(Curvature {
        min: k1.min(k2),
        max: k1.max(k2),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Point3;
    use crate::mesh::fixtures::{torus, uv_sphere};

    /// The fixture with its triangles facing out (positive volume).
    fn outward(mut mesh: Mesh) -> Mesh {
        if mesh.signed_volume() < 0.0 {
            for t in &mut mesh.triangles {
                t.swap(1, 2);
            }
        }
        mesh
    }

    fn curvatures(mesh: &Mesh) -> Vec<Option<Curvature>> {
        let normals = mesh.vertex_normals();
        vertex_curvatures(mesh, &normals, &vertex_neighbours(mesh))
    }

    #[test]
    fn exact_quadrics_give_their_closed_form_curvatures() {
        // Samples of z = (x²/R1 + y²/R2)/2 below the tangent plane (normal +z): a convex
        // ellipsoidal cap with curvatures 1/R1, 1/R2; with opposite signs a saddle.
        let grid = |f: &dyn Fn(f64, f64) -> f64| -> Vec<(f64, f64, f64)> {
            let mut pts = Vec::new();
            for i in -2..=2 {
                for j in -2..=2 {
                    if (i, j) != (0, 0) {
                        let (u, v) = (0.3 * i as f64, 0.2 * j as f64);
                        pts.push((u, v, f(u, v)));
                    }
                }
            }
            pts
        };
        let cap = fit_quadric(&grid(&|u, v| -(u * u / 5.0 + v * v / 20.0) / 2.0)).unwrap();
        assert!(
            (cap.max - 0.2).abs() < 1e-9 && (cap.min - 0.05).abs() < 1e-9,
            "{cap:?}"
        );
        let saddle = fit_quadric(&grid(&|u, v| (u * u / 4.0 - v * v / 8.0) / 2.0)).unwrap();
        assert!((saddle.max - 0.125).abs() < 1e-9 && (saddle.min + 0.25).abs() < 1e-9);
        assert_eq!(saddle.class(1e-3), ShapeClass::Saddle);
        // A tilted plane: the linear terms carry the tilt, the curvatures are zero.
        let plane = fit_quadric(&grid(&|u, v| 0.3 * u - 0.1 * v)).unwrap();
        assert!(plane.min.abs() < 1e-9 && plane.max.abs() < 1e-9);
        assert_eq!(plane.class(1e-3), ShapeClass::Flat);
        assert!(fit_quadric(&grid(&|_, _| 0.0)[..4]).is_none());
    }

    #[test]
    fn a_sphere_is_convex_with_curvature_one_over_r_and_concave_turned_inside_out() {
        let r = 25.0;
        let sphere = outward(uv_sphere(r, 48, 96));
        let all = curvatures(&sphere);
        let mut checked = 0;
        for (v, k) in all.iter().enumerate() {
            // Away from the poles, where the UV sphere's fans are irregular.
            if sphere.positions[v].z.abs() > 0.8 * r {
                continue;
            }
            let k = k.unwrap();
            assert!(
                (k.min * r - 1.0).abs() < 0.01 && (k.max * r - 1.0).abs() < 0.01,
                "{k:?}"
            );
            assert_eq!(k.class(1e-3), ShapeClass::Convex);
            checked += 1;
        }
        assert!(checked > 1000);
        // The same sphere seen from inside (a spherical cavity): concave, radius r.
        let mut cavity = sphere.clone();
        for t in &mut cavity.triangles {
            t.swap(1, 2);
        }
        for (v, k) in curvatures(&cavity).iter().enumerate() {
            if cavity.positions[v].z.abs() <= 0.8 * r {
                let k = k.unwrap();
                assert_eq!(k.class(1e-3), ShapeClass::Concave);
                assert!((k.concave_radius(1e-3).unwrap() / r - 1.0).abs() < 0.01);
            }
        }
    }

    #[test]
    fn a_torus_has_the_closed_form_curvatures_of_its_inner_and_outer_equators() {
        // Torus with tube radius b around a circle of radius a: across the tube 1/b; along it
        // cos θ/(a + b cos θ) — convex outside (θ = 0), saddle inside (θ = π).
        let (a, b) = (30.0, 8.0);
        let mesh = outward(torus(a, b, 160, 64));
        let all = curvatures(&mesh);
        let (mut outer, mut inner) = (0, 0);
        for (v, k) in all.iter().enumerate() {
            let p: Point3 = mesh.positions[v];
            let rho = p.x.hypot(p.y);
            let k = k.unwrap();
            if p.z.abs() < 1e-9 && rho > a {
                assert!((k.max - 1.0 / b).abs() < 0.01 / b, "{k:?}");
                assert!((k.min - 1.0 / (a + b)).abs() < 0.02 / (a + b), "{k:?}");
                assert_eq!(k.class(1e-3), ShapeClass::Convex);
                outer += 1;
            } else if p.z.abs() < 1e-9 && rho < a {
                assert!((k.max - 1.0 / b).abs() < 0.01 / b, "{k:?}");
                assert!((k.min + 1.0 / (a - b)).abs() < 0.02 / (a - b), "{k:?}");
                assert_eq!(k.class(1e-3), ShapeClass::Saddle);
                assert!((k.concave_radius(1e-3).unwrap() - (a - b)).abs() < 0.02 * (a - b));
                inner += 1;
            }
        }
        assert!(outer > 100 && inner > 100, "{outer} {inner}");
    }
}
