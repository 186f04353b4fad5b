//! The guarantees of a shape, checked and never assumed (issue 4 point 2; DESIGN.md §3.4
//! "always verify with exact distance queries against the part and push out where a check
//! fails"):
//!
//! * clearance: every shape sample is outside the part at distance ≥ a + r (exact f64
//!   closest points; sign by angle-weighted pseudo-normals, a real inside test, unlike parry's
//!   hollow TriMesh);
//! * containment: every part sample is inside the shape at depth ≥ a + r (the same exact test
//!   against the shape, so the shape is checked as a continuous surface, not only at samples);
//! * nesting: every sample of the next (finer) shape is strictly inside this one.
//!
//! A failing sample pushes the vertices of its triangle (shape samples: away from the part) or
//! of the shape triangle nearest to it (part and inner samples: away from the sample) by 1.5×
//! the deficit, and everything is checked again.

use rayon::prelude::*;

use super::PartQuery;
use super::normal_offset::vertex_normals;
use crate::geom::{Point3, Vector3};
use crate::mesh::Mesh;
use crate::mesh::SurfaceDistance;

/// A check passes within this (mm): ten times tighter than the 1e-6 mm the issue asks for, so
/// that the reported figures keep their margin.
pub const CLEARANCE_SLACK_MM: f64 = 1e-7;
/// Each push-out overshoots the measured deficit by half of it plus this (mm).
const PUSH_FACTOR: f64 = 1.5;
const PUSH_EXTRA_MM: f64 = 1e-5;
/// Edge subdivisions of a shape's triangles when sampling: corners, two points per edge and
/// the centroid.
const SHAPE_EDGE_STEPS: usize = 3;

/// Points on a surface and the triangle each lies on.
#[derive(Clone, Debug, Default)]
pub struct Samples {
    pub points: Vec<Point3>,
    pub triangles: Vec<u32>,
}

/// Samples `mesh`: every vertex once, every edge at `steps − 1` inner points once (from the
/// triangle that walks it upward), every triangle at its inner barycentric grid points, and
/// its centroid when the grid has none. `None` means 2 steps.
pub fn sample_surface(mesh: &Mesh, steps: Option<usize>) -> Samples {
    let n = steps.unwrap_or(2).max(1);
    let mut seen = vec![false; mesh.positions.len()];
    let mut samples = Samples::default();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let [a, b, c] = mesh.corners(t);
        let mut push = |p: Point3| {
            samples.points.push(p);
            samples.triangles.push(t as u32);
        };
        for (k, &v) in tri.iter().enumerate() {
            if !std::mem::replace(&mut seen[v as usize], true) {
                push(mesh.corners(t)[k]);
            }
        }
        let corners = [a, b, c];
        for k in 0..3 {
            if tri[k] < tri[(k + 1) % 3] {
                let (p, q) = (corners[k], corners[(k + 1) % 3]);
                for i in 1..n {
                    push(p + (q - p) * (i as f64 / n as f64));
                }
            }
        }
        let mut interior = false;
        for i in 1..n {
            for j in 1..n - i {
                let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                push(a + (b - a) * u + (c - a) * v);
                interior = true;
            }
        }
        if !interior {
            push(Point3::from((a.coords + b.coords + c.coords) / 3.0));
        }
    }
    samples
}

/// The figures of one check (mm).
#[derive(Clone, Debug, Default)]
pub(super) struct Stats {
    pub min_margin: f64,
    pub mean_excess: f64,
    pub max_excess: f64,
    pub min_part_depth: f64,
    pub min_inner_depth: Option<f64>,
}

pub(super) struct Outcome {
    pub shape_samples: Samples,
    pub stats: Stats,
    pub failures_found: usize,
    pub rounds: usize,
    pub verified: bool,
}

/// A failed check: the shape triangle to move, by how much, and which way.
struct Failure {
    triangle: u32,
    deficit: f64,
    direction: Vector3,
}

/// One pass of the three checks: the figures and the failures.
fn check(
    mesh: &Mesh,
    samples: &Samples,
    part: &PartQuery,
    part_samples: &Samples,
    inner: Option<&Samples>,
    clearance: f64,
) -> (Stats, Vec<Failure>) {
    let shape = SurfaceDistance::new(mesh);
    let margins: Vec<(f64, Vector3)> = samples
        .points
        .par_iter()
        .map(|p| {
            let (d, away) = part.signed_distance_and_away(p);
            (d - clearance, away)
        })
        .collect();
    // Depth of a point inside the shape (negative outside), the shape triangle nearest to it
    // and the way that triangle must move to put the point deeper. Inside by ray parity, not
    // by pseudo-normals: extracted shapes may have non-manifold edges, where a pseudo-normal
    // is not a reliable sign.
    let depth = |p: &Point3| {
        shape
            .closest(p, f64::INFINITY)
            .map_or((f64::NEG_INFINITY, 0, Vector3::zeros()), |c| {
                let side = if shape.contains_by_parity(p) {
                    1.0
                } else {
                    -1.0
                };
                let way = if c.distance > 1e-12 {
                    (c.point - p) * (side / c.distance)
                } else {
                    shape.face_normal(c.triangle)
                };
                (side * c.distance, c.triangle, way)
            })
    };
    let part_depths: Vec<(f64, u32, Vector3)> = part_samples.points.par_iter().map(depth).collect();
    let inner_depths: Option<Vec<(f64, u32, Vector3)>> =
        inner.map(|s| s.points.par_iter().map(depth).collect());
    let mut failures = Vec::new();
    let mut stats = Stats {
        min_margin: f64::INFINITY,
        max_excess: f64::NEG_INFINITY,
        min_part_depth: f64::INFINITY,
        ..Stats::default()
    };
    let mut sum = 0.0;
    for (&(m, away), &t) in margins.iter().zip(&samples.triangles) {
        stats.min_margin = stats.min_margin.min(m);
        stats.max_excess = stats.max_excess.max(m);
        sum += m;
        if m < -CLEARANCE_SLACK_MM {
            failures.push(Failure {
                triangle: t,
                deficit: -m,
                direction: away,
            });
        }
    }
    stats.mean_excess = sum / margins.len().max(1) as f64;
    for &(d, t, way) in &part_depths {
        let m = d - clearance;
        stats.min_part_depth = stats.min_part_depth.min(m);
        if m < -CLEARANCE_SLACK_MM {
            failures.push(Failure {
                triangle: t,
                deficit: -m,
                direction: way,
            });
        }
    }
    if let Some(depths) = &inner_depths {
        let mut least = f64::INFINITY;
        for &(d, t, way) in depths {
            least = least.min(d);
            if d <= CLEARANCE_SLACK_MM {
                failures.push(Failure {
                    triangle: t,
                    deficit: CLEARANCE_SLACK_MM - d,
                    direction: way,
                });
            }
        }
        stats.min_inner_depth = Some(least);
    }
    (stats, failures)
}

/// Checks `mesh` and pushes it out where a check fails, up to `max_rounds` times.
pub(super) fn verify_and_repair(
    mesh: &mut Mesh,
    part: &PartQuery,
    part_samples: &Samples,
    inner: Option<&Samples>,
    clearance: f64,
    max_rounds: usize,
) -> Outcome {
    let mut failures_found = 0;
    let mut rounds = 0;
    loop {
        let samples = sample_surface(mesh, Some(SHAPE_EDGE_STEPS));
        let (stats, failures) = check(mesh, &samples, part, part_samples, inner, clearance);
        if rounds == 0 {
            failures_found = failures.len();
        }
        if failures.is_empty() || rounds == max_rounds {
            return Outcome {
                shape_samples: samples,
                stats,
                failures_found,
                rounds,
                verified: failures.is_empty(),
            };
        }
        // Each vertex moves by its largest deficit, the way that failure asks (away from the
        // part, or past the point that should be inside), or along its normal without one.
        let mut push = vec![(0.0f64, Vector3::zeros()); mesh.positions.len()];
        for f in failures {
            for v in mesh.triangles[f.triangle as usize] {
                if f.deficit > push[v as usize].0 {
                    push[v as usize] = (f.deficit, f.direction);
                }
            }
        }
        let normals = vertex_normals(mesh);
        for ((p, n), (d, way)) in mesh.positions.iter_mut().zip(&normals).zip(&push) {
            if *d > 0.0 {
                let way = if *way == Vector3::zeros() { *n } else { *way };
                *p += way * (PUSH_FACTOR * d + PUSH_EXTRA_MM);
            }
        }
        rounds += 1;
    }
}
