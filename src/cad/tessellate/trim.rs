//! Trim loops into parameter-plane polygons whose edges, carried onto the surface, stay within
//! the chord tolerance of the trimmed boundary.
//!
//! A loop is flattened into its elementary curves (segments, arcs, B-spline pieces), and each
//! is sampled by bisection: an interval is split while the surface point at its middle is
//! farther than the tolerance from the 3D chord, or while the surface along the straight
//! parameter chord (the edge the triangles will use) leaves that chord by more than it.

use nalgebra::{Point2, Point3, Rotation3};

use super::FaceSurface;
use crate::cad::iges::{Curve, Face};

/// Deepest bisection of one interval: 2⁻²⁴ of a piece is far below any tolerance that matters.
const MAX_DEPTH: u32 = 24;

/// Fewest intervals a piece starts with: the surface under a straight trim can still bend.
const MIN_INTERVALS: usize = 4;

/// A boundary vertex: where it is on the surface's parameter plane, and in space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct LoopVertex {
    pub uv: Point2<f64>,
    pub position: Point3<f64>,
}

/// A closed loop of boundary vertices (the last joins the first).
pub(super) type BoundaryLoop = Vec<LoopVertex>;

/// The face's loops, outer first: its trim curves, or its domain's rectangle when it has none.
pub(super) fn face_loops(face: &Face, surface: &FaceSurface, tolerance: f64) -> Vec<BoundaryLoop> {
    let mut loops = Vec::with_capacity(1 + face.holes.len());
    match &face.outer {
        Some(outer) => loops.push(sample_loop(surface, outer, tolerance)),
        None => loops.push(domain_loop(surface, tolerance)),
    }
    for hole in &face.holes {
        loops.push(sample_loop(surface, hole, tolerance));
    }
    loops.retain(|l| l.len() >= 3);
    loops
}

/// The boundary of the parameter rectangle, counter-clockwise.
fn domain_loop(surface: &FaceSurface, tolerance: f64) -> BoundaryLoop {
    let ((u0, u1), (v0, v1)) = surface.domain();
    let corners = [
        Point3::new(u0, v0, 0.0),
        Point3::new(u1, v0, 0.0),
        Point3::new(u1, v1, 0.0),
        Point3::new(u0, v1, 0.0),
    ];
    let sides: Vec<Curve> = (0..4)
        .map(|i| Curve::Line {
            start: corners[i],
            end: corners[(i + 1) % 4],
        })
        .collect();
    sample_loop(surface, &Curve::Composite(sides), tolerance)
}

/// One trim loop as vertices; consecutive repeats (members that meet exactly) and the closing
/// repeat of the first vertex are dropped, gaps between members become edges.
fn sample_loop(surface: &FaceSurface, curve: &Curve, tolerance: f64) -> BoundaryLoop {
    let mut leaves = Vec::new();
    flatten(curve, &mut leaves);
    let mut out: BoundaryLoop = Vec::new();
    for leaf in leaves {
        sample_leaf(surface, leaf, tolerance, &mut out);
    }
    let same =
        |a: &LoopVertex, b: &LoopVertex| (a.uv - b.uv).norm() <= 1e-12 * (1.0 + a.uv.coords.norm());
    out.dedup_by(|b, a| same(a, b));
    while out.len() > 1 && same(&out[0], &out[out.len() - 1]) {
        out.pop();
    }
    out
}

/// A curve that is not a chain: a segment, an arc or a B-spline.
#[derive(Clone, Copy)]
struct Leaf<'a>(&'a Curve);

/// The segments, arcs and B-splines a curve is made of, in order.
fn flatten<'a>(curve: &'a Curve, out: &mut Vec<Leaf<'a>>) {
    match curve {
        Curve::Composite(members) => members.iter().for_each(|m| flatten(m, out)),
        leaf => out.push(Leaf(leaf)),
    }
}

impl Leaf<'_> {
    /// The point at the fraction `s ∈ [0, 1]` of the parameter range, in the parameter plane.
    fn point(self, s: f64) -> Point2<f64> {
        let p = match self.0 {
            Curve::Line { start, end } => start + (end - start) * s,
            Curve::Arc {
                centre,
                start,
                sweep,
                normal,
            } => centre + Rotation3::from_axis_angle(normal, sweep * s) * (start - centre),
            Curve::Nurbs { curve, range } => curve.point(range.0 + (range.1 - range.0) * s),
            // `flatten` makes no composite leaves; a chain's start is its first member's.
            Curve::Composite(members) => members
                .first()
                .map_or(Point3::origin(), |m| Leaf(m).point3(s)),
        };
        Point2::new(p.x, p.y)
    }

    fn point3(self, s: f64) -> Point3<f64> {
        let p = self.point(s);
        Point3::new(p.x, p.y, 0.0)
    }

    /// How many equal intervals sampling starts with, so that bisection cannot miss a wiggle.
    fn initial_intervals(self) -> usize {
        match self.0 {
            Curve::Line { .. } | Curve::Composite(_) => MIN_INTERVALS,
            Curve::Arc { sweep, .. } => {
                ((sweep.abs() / (std::f64::consts::PI / 8.0)).ceil() as usize).max(MIN_INTERVALS)
            }
            Curve::Nurbs { curve, range } => {
                let spans = curve
                    .knots()
                    .windows(2)
                    .filter(|w| w[1] > w[0] && w[1] > range.0 && w[0] < range.1)
                    .count();
                (spans.max(1) * (curve.degree() + 1)).clamp(MIN_INTERVALS, 4096)
            }
        }
    }
}

/// Appends the leaf's vertices from its start up to (not including) its end.
fn sample_leaf(surface: &FaceSurface, leaf: Leaf<'_>, tolerance: f64, out: &mut BoundaryLoop) {
    let vertex = |s: f64| {
        let uv = leaf.point(s);
        LoopVertex {
            uv,
            position: surface.point(uv.x, uv.y),
        }
    };
    let n = leaf.initial_intervals();
    let mut stack: Vec<(f64, LoopVertex, f64, LoopVertex, u32)> = Vec::new();
    let mut previous = vertex(0.0);
    for k in 1..=n {
        let s1 = k as f64 / n as f64;
        let next = vertex(s1);
        stack.push((s1, next, (k - 1) as f64 / n as f64, previous, 0));
        // Depth-first on the right end popped last, so vertices come out in order.
        while let Some((sb, b, sa, a, depth)) = stack.pop() {
            let sm = 0.5 * (sa + sb);
            let m = vertex(sm);
            // Quarter points too: the middle alone misses an S-shaped sag that crosses the
            // chord there.
            let off_chord = |s: f64, uv: Point2<f64>| {
                let chord = a.position + (b.position - a.position) * s;
                let on_curve = if s == 0.5 {
                    m.position
                } else {
                    vertex(sa + (sb - sa) * s).position
                };
                chord_distance(&on_curve, &a.position, &b.position) > tolerance
                    || (surface.point(uv.x, uv.y) - chord).norm() > tolerance
            };
            let split = depth < MAX_DEPTH
                && (a.uv - b.uv).norm() > 1e-13
                && [0.25, 0.5, 0.75]
                    .into_iter()
                    .any(|s| off_chord(s, Point2::from(a.uv.coords * (1.0 - s) + b.uv.coords * s)));
            if split {
                stack.push((sb, b, sm, m, depth + 1));
                stack.push((sm, m, sa, a, depth + 1));
            } else {
                out.push(a);
            }
        }
        previous = next;
    }
}

/// Distance from `p` to the segment `a`–`b`.
pub(super) fn chord_distance(p: &Point3<f64>, a: &Point3<f64>, b: &Point3<f64>) -> f64 {
    let ab = b - a;
    let len2 = ab.norm_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(&ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + ab * t)).norm()
}
