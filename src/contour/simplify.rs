//! Outline thinning before offsetting: runs of straight edges are reduced, by a greedy chord
//! walk, to the vertices that matter within a tolerance far below any machining tolerance.
//!
//! Outlines exported from drawings or mesh sections often carry tens of thousands of
//! vertices a few µm apart. cavalier_contours' fuzzy comparisons (1e-5…1e-4 mm) are of the
//! same order as such edges: on a 100,000-vertex smooth star its offset at 3 mm came back as
//! 1,248 loops, some crossing the part, and its work grows faster than the vertex count.
//! Only the offset engine sees the thinned outline; everything that judges a path (overcut,
//! uncut area, the finishing distance, see [`super::cavc::offset_region_cleared`]) measures
//! against the outline as read, so thinning can cost at most [`OUTLINE_THINNING_TOL`] of
//! material on the finishing pass and never an overcut. Arcs are kept as they are, and so is
//! every vertex of an outline without removable ones (the closed-form fixtures).

use crate::contour::geometry::{Contour, Point2, Segment, Shape, Vertex};
use crate::contour::segops::point_distance;

/// Largest distance of a removed vertex from the thinned outline, mm.
pub const OUTLINE_THINNING_TOL: f64 = 1e-4;

/// `shape` with each contour thinned to within `tol` (see the module docs).
pub fn thin_shape(shape: &Shape, tol: f64) -> Shape {
    Shape {
        contours: shape
            .contours
            .iter()
            .map(|c| thin_contour(c, tol))
            .collect(),
    }
}

/// One contour thinned: a vertex is kept when an arc starts or ends at it, or when the chord
/// from the last kept vertex past it would leave a removed vertex farther than `tol` away.
pub fn thin_contour(contour: &Contour, tol: f64) -> Contour {
    let v = &contour.vertices;
    let n = v.len();
    if n < 4 {
        return contour.clone();
    }
    let is_arc = |i: usize| v[i % n].bulge != 0.0;
    let mut keep = vec![false; n];
    // Fixed vertices: ends of arcs; without any, the first vertex closes the polygon's run.
    let mut fixed: Vec<usize> = (0..n).filter(|&i| is_arc(i) || is_arc(i + n - 1)).collect();
    if fixed.is_empty() {
        fixed.push(0);
    }
    for &a in &fixed {
        keep[a] = true;
    }
    for (k, &start) in fixed.iter().enumerate() {
        if is_arc(start) {
            continue; // the run from `start` is one arc: nothing in between
        }
        let end = fixed[(k + 1) % fixed.len()];
        let end = if end <= start { end + n } else { end };
        thin_run(v, start, end, tol, &mut keep);
    }
    Contour {
        vertices: (0..n).filter(|&i| keep[i]).map(|i| v[i]).collect(),
    }
}

/// A chord spans at most this many edges, so a run costs O(run × this) however straight it
/// is (a 100,000-point straight edge keeps one vertex in this many).
const MAX_CHORD_EDGES: usize = 256;

/// Marks in `keep` the vertices of the open straight run `start..=end` (indices modulo the
/// vertex count) that a greedy chord walk keeps: each chord from the last kept vertex is
/// extended while every vertex it passes stays within `tol` of it.
fn thin_run(v: &[Vertex], start: usize, end: usize, tol: f64, keep: &mut [bool]) {
    let n = v.len();
    let at = |i: usize| v[i % n].point;
    let mut anchor = start;
    while anchor + 1 < end {
        let mut reach = anchor + 1;
        let limit = end.min(anchor + MAX_CHORD_EDGES);
        for b in anchor + 2..=limit {
            let (p, q) = (at(anchor), at(b));
            if (anchor + 1..b).any(|i| point_segment_distance(at(i), p, q) > tol) {
                break;
            }
            reach = b;
        }
        keep[reach % n] = true;
        anchor = reach;
    }
}

/// Distance of `x` from the straight segment `p`–`q`.
fn point_segment_distance(x: Point2, p: Point2, q: Point2) -> f64 {
    point_distance(x, &Segment::Line { start: p, end: q }).0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn polygon(points: &[(f64, f64)]) -> Contour {
        Contour {
            vertices: points.iter().map(|&(x, y)| Vertex::line(x, y)).collect(),
        }
    }

    #[test]
    fn a_square_keeps_its_corners_and_loses_collinear_vertices() {
        let c = polygon(&[
            (0.0, 0.0),
            (5.0, 0.0),
            (10.0, 0.0),
            (10.0, 10.0),
            (0.0, 10.0),
            (0.0, 4.0),
        ]);
        let t = thin_contour(&c, OUTLINE_THINNING_TOL);
        let pts: Vec<(f64, f64)> = t.vertices.iter().map(|v| (v.point.x, v.point.y)).collect();
        assert_eq!(
            pts,
            vec![(0.0, 0.0), (10.0, 0.0), (10.0, 10.0), (0.0, 10.0)]
        );
        assert!((t.signed_area() - c.signed_area()).abs() < 1e-12);
    }

    /// Every removed vertex lies within the tolerance of the thinned outline, and a dense
    /// circle polygon thins to about the count its chord error allows (n ≈ π/√(2 tol / R)).
    #[test]
    fn removed_vertices_stay_within_the_tolerance() {
        let (n, radius, tol) = (20_000, 30.0, 1e-3);
        let c = polygon(
            &(0..n)
                .map(|k| {
                    let a = k as f64 * std::f64::consts::TAU / n as f64;
                    (radius * a.cos(), radius * a.sin())
                })
                .collect::<Vec<_>>(),
        );
        let t = thin_contour(&c, tol);
        let bound = (std::f64::consts::PI / (2.0 * tol / radius).sqrt()).ceil() as usize;
        assert!(
            t.vertices.len() <= 2 * bound && t.vertices.len() >= bound / 2,
            "{} vertices, chord bound {bound}",
            t.vertices.len()
        );
        let segs: Vec<(Point2, Point2)> = (0..t.vertices.len())
            .map(|i| {
                (
                    t.vertices[i].point,
                    t.vertices[(i + 1) % t.vertices.len()].point,
                )
            })
            .collect();
        for v in &c.vertices {
            let d = segs
                .iter()
                .map(|&(p, q)| point_segment_distance(v.point, p, q))
                .fold(f64::INFINITY, f64::min);
            assert!(
                d <= tol,
                "vertex {:?} is {d} from the thinned outline",
                v.point
            );
        }
    }

    #[test]
    fn arcs_and_their_ends_are_kept() {
        let mut c = polygon(&[
            (0.0, 0.0),
            (1.0, 0.0),
            (2.0, 0.0),
            (2.0, 2.0),
            (1.0, 2.0),
            (0.0, 2.0),
        ]);
        c.vertices[3].bulge = 0.5; // arc from (2,2) to (1,2)
        let t = thin_contour(&c, OUTLINE_THINNING_TOL);
        let pts: Vec<(f64, f64)> = t.vertices.iter().map(|v| (v.point.x, v.point.y)).collect();
        assert_eq!(
            pts,
            vec![(0.0, 0.0), (2.0, 0.0), (2.0, 2.0), (1.0, 2.0), (0.0, 2.0)]
        );
        assert_eq!(t.vertices[2].bulge, 0.5);
    }
}
