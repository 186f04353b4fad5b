//! Helpers shared by the outline tests.

use std::path::PathBuf;

use super::curves::Curve;
use super::segmath::{dist_point_segment, point_on_segment};
use crate::contour::geometry::{Point2, Segment, Shape, Vertex};

/// The segments of an open chain of vertices ending at `end`.
pub fn chain_segments(vs: &[Vertex], end: Point2) -> Vec<Segment> {
    (0..vs.len())
        .map(|i| {
            let to = vs.get(i + 1).map_or(end, |v| v.point);
            Segment::new(vs[i].point, to, vs[i].bulge)
        })
        .collect()
}

/// Largest distance from `n + 1` evenly spaced points of the true curve to the approximation.
pub fn curve_to_approx_distance(
    c: &dyn Curve,
    t0: f64,
    t1: f64,
    vs: &[Vertex],
    end: Point2,
    n: usize,
) -> f64 {
    let segs = chain_segments(vs, end);
    (0..=n)
        .map(|i| {
            let q = c.eval(t0 + (t1 - t0) * i as f64 / n as f64).p;
            segs.iter()
                .map(|s| dist_point_segment(q, s))
                .fold(f64::INFINITY, f64::min)
        })
        .fold(0.0, f64::max)
}

/// Largest distance from 20,001 evenly spaced points of `curve` over `[t0, t1]` to the
/// contours of `s`.
pub fn curve_to_shape_distance(curve: &dyn Curve, t0: f64, t1: f64, s: &Shape) -> f64 {
    let segs: Vec<Segment> = s.contours.iter().flat_map(|c| c.segments()).collect();
    (0..=20_000)
        .map(|i| {
            let q = curve.eval(t0 + (t1 - t0) * i as f64 / 20_000.0).p;
            segs.iter()
                .map(|sg| dist_point_segment(q, sg))
                .fold(f64::INFINITY, f64::min)
        })
        .fold(0.0, f64::max)
}

/// Largest distance from points along the approximation to a dense polyline of the curve.
pub fn approx_to_curve_distance(
    c: &dyn Curve,
    t0: f64,
    t1: f64,
    vs: &[Vertex],
    end: Point2,
    n: usize,
) -> f64 {
    let poly: Vec<Segment> = (0..n)
        .map(|i| {
            let a = c.eval(t0 + (t1 - t0) * i as f64 / n as f64).p;
            let b = c.eval(t0 + (t1 - t0) * (i + 1) as f64 / n as f64).p;
            Segment::Line { start: a, end: b }
        })
        .collect();
    let mut worst: f64 = 0.0;
    for s in chain_segments(vs, end) {
        for k in 0..=16 {
            let q = point_on_segment(&s, k as f64 / 16.0);
            let d = poly
                .iter()
                .map(|l| dist_point_segment(q, l))
                .fold(f64::INFINITY, f64::min);
            worst = worst.max(d);
        }
    }
    worst
}

pub fn total_area(s: &Shape) -> f64 {
    s.contours.iter().map(|c| c.signed_area()).sum()
}

/// `../shared/testdata/outlines` beside the crate (or `$WAVEMILL_TESTDATA/outlines`), `None`
/// with a message when it is missing (a newcomer's clone has no `../shared`).
pub fn outlines_dir() -> Option<PathBuf> {
    let base = std::env::var_os("WAVEMILL_TESTDATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/testdata"))
        });
    let dir = base.join("outlines");
    if dir.is_dir() {
        Some(dir)
    } else {
        eprintln!("skipping: test data folder {} is missing", dir.display());
        None
    }
}
