//! The no-overcut check of a vertical-axis program against the shape it roughs to, exact and
//! independent of how the program was planned (the envelope grid, the offset engine).
//!
//! A tool whose axis is +Z and whose widest radius below the holder is R occupies at most the
//! upright cylinder of radius R standing on its tip. Along a straight move from `a` to `b` it
//! stays inside the union of those cylinders, which lies above min(a.z, b.z) and within R of
//! the segment ab seen from above. So a move is clear of the shape when every triangle, cut
//! to the part above that height, is at least R from the segment in the plane: a conservative
//! test (it ignores that a ramp is higher than its low end), computed in closed form per
//! triangle. The flat end resting on a flat face at its own height is not an overcut, nor is
//! one that stands less than the tolerance above it: the program is posted rounded, so a tip
//! planned on a flat at 18.5000000000003 mm is written at 18.5, and the flat's sides must not
//! then count as standing beside the tool.

use rayon::prelude::*;

use crate::contour::geometry::Segment;
use crate::contour::segops::point_distance;
use crate::geom::{Point2, Point3, Toolpath, closest_points_of_segments};
use crate::mesh::Mesh;

/// A move the check found too close to the shape.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Overcut {
    /// Index of the move in the program.
    pub move_index: usize,
    /// How much closer than R the tool came, mm.
    pub depth_mm: f64,
}

/// What [`overcuts`] found.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct OvercutReport {
    pub moves_checked: usize,
    /// Every move closer than R − `tolerance`, in program order.
    pub overcuts: Vec<Overcut>,
    /// The smallest clearance of any move (distance in the plane minus R), mm; `+∞` when no
    /// triangle stands within reach.
    pub min_clearance_mm: f64,
}

/// Triangles bucketed by their footprint on a square grid, for the moves' neighbourhood
/// queries, with each triangle's footprint box and top kept to skip it without clipping.
struct Buckets {
    origin: (f64, f64),
    size: f64,
    width: usize,
    height: usize,
    cells: Vec<Vec<u32>>,
    footprints: Vec<Footprint>,
}

/// A triangle's box seen from above, and its highest corner.
#[derive(Clone, Copy)]
struct Footprint {
    lo: (f64, f64),
    hi: (f64, f64),
    top: f64,
}

impl Buckets {
    fn new(mesh: &Mesh, size: f64) -> Buckets {
        let b = mesh.aabb();
        let width = ((b.max.x - b.min.x) / size).floor() as usize + 1;
        let height = ((b.max.y - b.min.y) / size).floor() as usize + 1;
        let mut buckets = Buckets {
            origin: (b.min.x, b.min.y),
            size,
            width,
            height,
            cells: vec![Vec::new(); width * height],
            footprints: Vec::with_capacity(mesh.triangles.len()),
        };
        for t in 0..mesh.triangles.len() {
            let c = mesh.corners(t);
            let lo = (
                c.iter().map(|p| p.x).fold(f64::INFINITY, f64::min),
                c.iter().map(|p| p.y).fold(f64::INFINITY, f64::min),
            );
            let hi = (
                c.iter().map(|p| p.x).fold(f64::NEG_INFINITY, f64::max),
                c.iter().map(|p| p.y).fold(f64::NEG_INFINITY, f64::max),
            );
            let top = c.iter().map(|p| p.z).fold(f64::NEG_INFINITY, f64::max);
            buckets.footprints.push(Footprint { lo, hi, top });
            let ((i0, j0), (i1, j1)) = (buckets.index(lo), buckets.index(hi));
            for j in j0..=j1 {
                for i in i0..=i1 {
                    buckets.cells[i + j * width].push(t as u32);
                }
            }
        }
        buckets
    }

    fn index(&self, p: (f64, f64)) -> (usize, usize) {
        let i = ((p.0 - self.origin.0) / self.size).floor();
        let j = ((p.1 - self.origin.1) / self.size).floor();
        (
            i.clamp(0.0, (self.width - 1) as f64) as usize,
            j.clamp(0.0, (self.height - 1) as f64) as usize,
        )
    }

    /// The cells that may hold a triangle within `reach` of the segment ab (seen from above),
    /// each with a lower bound of the planar distance from the segment to anything in it,
    /// nearest first. A triangle is in every cell its box overlaps, so its distance is at
    /// least the smallest bound of those cells.
    fn cells_near(&self, a: (f64, f64), b: (f64, f64), reach: f64) -> Vec<(f64, usize)> {
        let lo = (a.0.min(b.0), a.1.min(b.1));
        let hi = (a.0.max(b.0), a.1.max(b.1));
        let (i0, j0) = self.index((lo.0 - reach, lo.1 - reach));
        let (i1, j1) = self.index((hi.0 + reach, hi.1 + reach));
        let half_diagonal = self.size * std::f64::consts::FRAC_1_SQRT_2;
        let mut out = Vec::with_capacity((i1 - i0 + 1) * (j1 - j0 + 1));
        for j in j0..=j1 {
            for i in i0..=i1 {
                let centre = (
                    self.origin.0 + (i as f64 + 0.5) * self.size,
                    self.origin.1 + (j as f64 + 0.5) * self.size,
                );
                let bound = (planar_point_segment_distance(centre, a, b) - half_diagonal).max(0.0);
                out.push((bound, i + j * self.width));
            }
        }
        out.sort_unstable_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
        out
    }
}

/// Distance in the plane from `p` to the segment ab.
fn planar_point_segment_distance(p: (f64, f64), a: (f64, f64), b: (f64, f64)) -> f64 {
    let point = |q: (f64, f64)| Point2::new(q.0, q.1);
    point_distance(
        point(p),
        &Segment::Line {
            start: point(a),
            end: point(b),
        },
    )
    .0
}

/// A lower bound of the planar distance from the segment ab to anything in the box lo–hi: the
/// larger of the gap between the boxes and the distance to the box's centre less its half
/// diagonal.
fn box_distance_bound(a: (f64, f64), b: (f64, f64), lo: (f64, f64), hi: (f64, f64)) -> f64 {
    let gap_x = (lo.0 - a.0.max(b.0)).max(a.0.min(b.0) - hi.0).max(0.0);
    let gap_y = (lo.1 - a.1.max(b.1)).max(a.1.min(b.1) - hi.1).max(0.0);
    let gap = (gap_x * gap_x + gap_y * gap_y).sqrt();
    let centre = (0.5 * (lo.0 + hi.0), 0.5 * (lo.1 + hi.1));
    let half_diagonal = 0.5 * ((hi.0 - lo.0).powi(2) + (hi.1 - lo.1).powi(2)).sqrt();
    gap.max(planar_point_segment_distance(centre, a, b) - half_diagonal)
}

/// Checks every move of `toolpath` (axis +Z, tool radius `radius` below the holder) against
/// `shape`; moves closer than `radius − tolerance` are overcuts. Moves whose axis is not +Z
/// are reported as overcuts of infinite depth: this check cannot clear them.
pub fn overcuts(shape: &Mesh, toolpath: &Toolpath, radius: f64, tolerance: f64) -> OvercutReport {
    let buckets = Buckets::new(shape, radius.max(1.0) * 2.0);
    let clearances: Vec<f64> = (1..toolpath.moves.len())
        .into_par_iter()
        .map(|k| {
            let (a, b) = (&toolpath.moves[k - 1].pose, &toolpath.moves[k].pose);
            let upright = |axis: &crate::geom::Direction| axis.z > 1.0 - 1e-12;
            if !upright(&a.axis) || !upright(&b.axis) {
                return f64::NEG_INFINITY;
            }
            move_clearance(shape, &buckets, &a.tip, &b.tip, radius, tolerance)
        })
        .collect();
    let overcuts = clearances
        .iter()
        .enumerate()
        .filter(|(_, c)| **c < -tolerance)
        .map(|(k, c)| Overcut {
            move_index: k + 1,
            depth_mm: -c,
        })
        .collect();
    OvercutReport {
        moves_checked: clearances.len(),
        overcuts,
        min_clearance_mm: clearances.iter().copied().fold(f64::INFINITY, f64::min),
    }
}

/// Distance in the plane from the segment ab to the nearest part of a triangle more than
/// `tolerance` above min(a.z, b.z), minus `radius` (`+∞` if nothing stands within reach).
fn move_clearance(
    shape: &Mesh,
    buckets: &Buckets,
    a: &Point3,
    b: &Point3,
    radius: f64,
    tolerance: f64,
) -> f64 {
    let floor = a.z.min(b.z) + tolerance.max(0.0);
    let (pa, pb) = (Point3::new(a.x, a.y, 0.0), Point3::new(b.x, b.y, 0.0));
    let (a2, b2) = ((a.x, a.y), (b.x, b.y));
    // Cells nearest first, and a cell or triangle skipped once its lower bound cannot beat
    // the nearest found: the answer is the minimum over every triangle in reach, as if each
    // were clipped and measured, at a fraction of the cost on long moves.
    let mut nearest = f64::INFINITY;
    for (bound, cell) in buckets.cells_near(a2, b2, radius) {
        if bound >= nearest {
            break;
        }
        for &t in &buckets.cells[cell] {
            let footprint = &buckets.footprints[t as usize];
            if footprint.top <= floor
                || box_distance_bound(a2, b2, footprint.lo, footprint.hi) >= nearest
            {
                continue;
            }
            let above = clip_above(&shape.corners(t as usize), floor);
            nearest = nearest.min(planar_distance(&pa, &pb, &above));
            if nearest == 0.0 {
                return -radius;
            }
        }
    }
    nearest - radius
}

/// The part of the triangle strictly above `floor` (its closure), projected to z = 0.
fn clip_above(corners: &[Point3; 3], floor: f64) -> Vec<Point3> {
    let mut out = Vec::with_capacity(4);
    for k in 0..3 {
        let (p, q) = (corners[k], corners[(k + 1) % 3]);
        if p.z > floor {
            out.push(Point3::new(p.x, p.y, 0.0));
        }
        if (p.z > floor) != (q.z > floor) {
            let t = (floor - p.z) / (q.z - p.z);
            let c = p + (q - p) * t;
            out.push(Point3::new(c.x, c.y, 0.0));
        }
    }
    out
}

/// Distance in the plane between the segment pq and the convex polygon `poly` (z = 0): zero
/// when they meet.
fn planar_distance(p: &Point3, q: &Point3, poly: &[Point3]) -> f64 {
    if poly.len() >= 3 && (contains(poly, p) || contains(poly, q)) {
        return 0.0;
    }
    let n = poly.len();
    let mut best = f64::INFINITY;
    for k in 0..n {
        let (a, b) = (&poly[k], &poly[(k + 1) % n]);
        let (x, y) = closest_points_of_segments(p, q, a, b);
        best = best.min((x - y).norm());
        if n == 1 {
            break;
        }
    }
    best
}

/// Whether `p` lies in the convex polygon (either orientation, boundary included).
fn contains(poly: &[Point3], p: &Point3) -> bool {
    let n = poly.len();
    let mut sign = 0.0;
    for k in 0..n {
        let (a, b) = (&poly[k], &poly[(k + 1) % n]);
        let cross = (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x);
        if cross != 0.0 {
            if sign != 0.0 && cross.signum() != sign {
                return false;
            }
            sign = cross.signum();
        }
    }
    sign != 0.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::{Direction, Move, MoveKind, ToolPose, Vector3};

    fn centred_cube() -> Mesh {
        let mut cube = crate::mesh::fixtures::cuboid(10.0, 10.0, 10.0);
        for p in &mut cube.positions {
            *p -= Vector3::new(5.0, 5.0, 5.0);
        }
        cube
    }

    fn path(points: &[[f64; 3]]) -> Toolpath {
        Toolpath {
            tool_id: 1,
            moves: points
                .iter()
                .map(|p| Move {
                    pose: ToolPose {
                        tip: Point3::new(p[0], p[1], p[2]),
                        axis: Direction::new_normalize(Vector3::z()),
                    },
                    kind: MoveKind::Cut,
                    feed: 1000.0,
                })
                .collect(),
        }
    }

    /// A 10 mm cube centred at the origin (z from −5 to 5) and a tool of radius 3: the
    /// clearance of a move beside it is its distance to the cube's side minus 3, whatever the
    /// height, and a move above the top clears it.
    #[test]
    fn clearances_beside_and_above_a_cube_are_the_closed_form() {
        let cube = centred_cube();
        for (x, z, want) in [(9.0, 0.0, 1.0), (8.0, -4.0, 0.0), (7.0, 4.9, -1.0)] {
            let report = overcuts(&cube, &path(&[[x, -20.0, z], [x, 20.0, z]]), 3.0, 1e-9);
            assert!(
                (report.min_clearance_mm - want).abs() < 1e-12,
                "{x} {z}: {report:?}"
            );
            assert_eq!(report.overcuts.len(), usize::from(want < 0.0));
        }
        // Resting on the top face is not an overcut; 1 µm below it is one of 3 mm + 4 mm.
        let report = overcuts(&cube, &path(&[[0.0, 0.0, 5.0], [4.0, 0.0, 5.0]]), 3.0, 1e-9);
        assert!(report.overcuts.is_empty(), "{report:?}");
        let report = overcuts(
            &cube,
            &path(&[[0.0, 0.0, 4.999], [4.0, 0.0, 4.999]]),
            3.0,
            1e-9,
        );
        assert_eq!(report.overcuts.len(), 1);
    }

    /// A tip posted rounded onto a flat the shape has a hair higher (here 3e-13 mm) rests on
    /// it; one the tolerance below it cuts into the flat, and its sides count.
    #[test]
    fn a_tip_rounded_onto_a_flat_rests_on_it() {
        let mut cube = centred_cube();
        for p in &mut cube.positions {
            p.z += 3e-13;
        }
        let over_the_edge = |z: f64| path(&[[0.0, 0.0, z], [4.0, 0.0, z]]);
        let report = overcuts(&cube, &over_the_edge(5.0), 3.0, 0.001);
        assert!(report.overcuts.is_empty(), "{report:?}");
        let report = overcuts(&cube, &over_the_edge(5.0 - 0.002), 3.0, 0.001);
        assert_eq!(report.overcuts.len(), 1, "{report:?}");
    }

    /// A ramp's low end counts: a ramp from above the cube down beside it is judged at its
    /// bottom.
    #[test]
    fn a_ramp_is_judged_at_its_low_end_and_tilted_axes_are_refused() {
        let cube = centred_cube();
        let report = overcuts(
            &cube,
            &path(&[[0.0, 0.0, 20.0], [7.5, 0.0, 0.0]]),
            3.0,
            1e-9,
        );
        assert_eq!(
            report.overcuts.len(),
            1,
            "the swept cylinders meet the cube"
        );
        let mut tilted = path(&[[20.0, 0.0, 0.0], [21.0, 0.0, 0.0]]);
        tilted.moves[1].pose.axis = Direction::new_normalize(Vector3::new(0.1, 0.0, 1.0));
        let report = overcuts(&cube, &tilted, 3.0, 1e-9);
        assert_eq!(report.overcuts[0].depth_mm, f64::INFINITY);
    }

    /// The culled search finds what measuring every triangle finds: on a tilted torus, for
    /// moves anywhere round it, the clearance is the brute-force minimum over all triangles
    /// when that is within reach, and no nearer than it otherwise.
    #[test]
    fn culled_clearances_agree_with_every_triangle_measured() {
        let mut torus = crate::mesh::fixtures::torus(12.0, 4.0, 48, 24);
        for p in &mut torus.positions {
            *p = Point3::new(p.x + 0.3 * p.z, p.y, p.z + 0.2 * p.x);
        }
        let radius = 3.0;
        let buckets = Buckets::new(&torus, 2.0 * radius);
        let brute = |a: &Point3, b: &Point3| {
            let floor = a.z.min(b.z);
            let (pa, pb) = (Point3::new(a.x, a.y, 0.0), Point3::new(b.x, b.y, 0.0));
            (0..torus.triangles.len())
                .map(|t| torus.corners(t))
                .filter(|c| c.iter().any(|p| p.z > floor))
                .map(|c| planar_distance(&pa, &pb, &clip_above(&c, floor)))
                .fold(f64::INFINITY, f64::min)
        };
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        let mut next = move || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..400 {
            let mut point = || {
                Point3::new(
                    40.0 * next() - 20.0,
                    40.0 * next() - 20.0,
                    16.0 * next() - 8.0,
                )
            };
            let (a, b) = (point(), point());
            let want = brute(&a, &b);
            let got = move_clearance(&torus, &buckets, &a, &b, radius, 0.0) + radius;
            if want <= radius {
                // Up to round-off: two triangles sharing the nearest edge measure it a unit
                // in the last place apart, and the bound may skip the second.
                assert!((got - want).abs() <= 1e-12, "{a} {b}: {got} against {want}");
            } else {
                assert!(got >= want, "{a} {b}: {got} < {want}");
            }
        }
    }
}
