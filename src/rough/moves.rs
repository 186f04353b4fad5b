//! From planar passes to tool moves: arcs as straight moves that never come closer to their
//! centre than the arc (the polygon circumscribed about it), and ramped entries along a pass.

use crate::contour::geometry::{Point2, Segment};
use crate::contour::region::RegionIndex;
use crate::contour::toolpath::Pass;
use crate::geom::Point3;

/// The pass as points joined by straight moves, within `tolerance` of its arcs and outside
/// them. An offset arc is centred on the part's corner it goes round; a chord would cut in
/// toward that corner by its sagitta, while the circumscribed polygon's sides are tangent to
/// the arc and so stay at the arc's radius or farther.
pub fn pass_points(pass: &Pass, tolerance: f64) -> Vec<Point2> {
    let mut points = vec![pass.start()];
    for seg in pass.segments() {
        match seg {
            Segment::Line { end, .. } => points.push(end),
            Segment::Arc {
                end,
                center,
                radius,
                sweep,
                start,
            } => {
                // Each side's outward deviation is radius (1 / cos(step / 2) − 1) ≤ tolerance.
                let max_step = 2.0 * (radius / (radius + tolerance)).clamp(-1.0, 1.0).acos();
                let n = ((sweep.abs() / max_step.max(1e-6)).ceil() as usize).max(1);
                let step = sweep / n as f64;
                let outer = radius / (0.5 * step).cos();
                let a0 = (start.y - center.y).atan2(start.x - center.x);
                for k in 0..n {
                    let a = a0 + (k as f64 + 0.5) * step;
                    points.push(Point2::new(
                        center.x + outer * a.cos(),
                        center.y + outer * a.sin(),
                    ));
                }
                points.push(end);
            }
        }
    }
    points.dedup_by(|a, b| (*a - *b).norm() < 1e-9);
    points
}

/// The stretches of the polyline `points` along which a tool of radius `r` keeps off
/// `keep_out` (outside it, and `r` or more from its boundary), in order. Each side is cut
/// into pieces at most `step` long, and a piece is kept or dropped whole, so a run ends
/// within `step` of where the tool would first touch.
pub fn clear_runs(
    points: &[Point2],
    keep_out: &RegionIndex,
    r: f64,
    step: f64,
) -> Vec<Vec<Point2>> {
    let clear = |a: Point2, b: Point2| {
        !keep_out.contains(a)
            && !keep_out.contains(b)
            && keep_out
                .boundary()
                .nearest(&Segment::Line { start: a, end: b })
                .is_none_or(|n| n.distance >= r)
    };
    let mut runs: Vec<Vec<Point2>> = Vec::new();
    let mut current: Vec<Point2> = Vec::new();
    for w in points.windows(2) {
        let pieces = (((w[1] - w[0]).norm() / step.max(1e-6)).ceil() as usize).max(1);
        for k in 0..pieces {
            let a = w[0] + (w[1] - w[0]) * (k as f64 / pieces as f64);
            let b = if k + 1 == pieces {
                w[1]
            } else {
                w[0] + (w[1] - w[0]) * ((k + 1) as f64 / pieces as f64)
            };
            if clear(a, b) {
                if current.is_empty() {
                    current.push(a);
                }
                // Inside a side, only where a run starts or stops needs a point.
                if k + 1 == pieces {
                    current.push(b);
                }
            } else if !current.is_empty() {
                if current.last() != Some(&a) {
                    current.push(a);
                }
                runs.push(std::mem::take(&mut current));
            }
        }
    }
    if current.len() > 1 {
        runs.push(current);
    }
    runs.retain(|run| run.len() > 1);
    runs
}

/// Length of a polyline.
pub fn polyline_length(points: &[Point2]) -> f64 {
    points.windows(2).map(|w| (w[1] - w[0]).norm()).sum()
}

/// The point `distance` along the polyline from its start (its end beyond its length).
pub(super) fn point_along(points: &[Point2], distance: f64) -> Point2 {
    let mut left = distance;
    for w in points.windows(2) {
        let len = (w[1] - w[0]).norm();
        if left <= len && len > 0.0 {
            return w[0] + (w[1] - w[0]) * (left / len);
        }
        left -= len;
    }
    *points.last().unwrap_or(&Point2::origin())
}

/// The polyline's vertices strictly between `from` and `to` (distances along it), in the
/// direction of travel, followed by the point at `to`.
pub(super) fn walk(points: &[Point2], from: f64, to: f64) -> Vec<(Point2, f64)> {
    let mut out = Vec::new();
    let mut at = 0.0;
    let (lo, hi) = (from.min(to), from.max(to));
    let mut inner = Vec::new();
    for w in points.windows(2) {
        at += (w[1] - w[0]).norm();
        if at > lo + 1e-12 && at < hi - 1e-12 {
            inner.push((w[1], at));
        }
    }
    if to < from {
        inner.reverse();
    }
    out.extend(inner);
    out.push((point_along(points, to), to));
    out
}

/// A ramped entry along the start of a pass: from above `points[0]` at `from_z` down to
/// `to_z` at no more than `slope` (dz per mm of travel), going back and forth along the first
/// `max_leg` mm of the pass, then back to `points[0]` at `to_z`. Every point lies above the
/// pass, so the entry cuts only what the pass itself will. Empty when the pass is too short
/// to ramp along (the caller plunges or retracts).
pub fn ramp_along(
    points: &[Point2],
    from_z: f64,
    to_z: f64,
    slope: f64,
    max_leg: f64,
) -> Vec<Point3> {
    let leg = polyline_length(points).min(max_leg);
    if leg < 1e-3 || from_z <= to_z {
        return Vec::new();
    }
    let mut out = Vec::new();
    let mut z = from_z;
    let mut at = 0.0;
    let mut forward = true;
    while z > to_z {
        let target = if forward { leg } else { 0.0 };
        for (p, d) in walk(points, at, target) {
            let dz = (d - at).abs() * slope;
            at = d;
            z = (z - dz).max(to_z);
            out.push(Point3::new(p.x, p.y, z));
            if z <= to_z {
                break;
            }
        }
        forward = !forward;
    }
    // Clean the bottom of the ramp back to the start.
    if at > 0.0 {
        for (p, _) in walk(points, at, 0.0) {
            out.push(Point3::new(p.x, p.y, to_z));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contour::geometry::Vertex;

    /// A quarter arc of radius 5 becomes points none of which is closer than 5 to the centre
    /// and none farther than 5 + tolerance; the sides stay outside the arc.
    #[test]
    fn arcs_become_circumscribed_polygons_within_the_tolerance() {
        let bulge = (std::f64::consts::FRAC_PI_2 / 4.0).tan();
        let pass = Pass::open(
            vec![
                Vertex {
                    point: Point2::new(5.0, 0.0),
                    bulge,
                },
                Vertex::line(0.0, 5.0),
            ],
            5.0,
        )
        .expect("pass");
        let tol = 0.01;
        let points = pass_points(&pass, tol);
        assert!(points.len() > 4);
        assert_eq!(points[0], Point2::new(5.0, 0.0));
        assert!((points[points.len() - 1] - Point2::new(0.0, 5.0)).norm() < 1e-12);
        for w in points.windows(2) {
            for k in 0..=10 {
                let p = w[0] + (w[1] - w[0]) * (k as f64 / 10.0);
                let r = p.coords.norm();
                assert!(r >= 5.0 - 1e-9 && r <= 5.0 + tol + 1e-9, "{r}");
            }
        }
    }

    /// A line passing a 2 × 2 square 2 mm to its side: a tool of radius 3 touches it where
    /// |x| < 1 + √(3² − 2²); the runs stop within a step of that, and a line far off is one run.
    #[test]
    fn runs_stop_where_the_tool_would_reach_the_keep_out() {
        use crate::contour::geometry::{Contour, Shape, Vertex};
        let square = Shape {
            contours: vec![Contour {
                vertices: vec![
                    Vertex::line(-1.0, 2.0),
                    Vertex::line(1.0, 2.0),
                    Vertex::line(1.0, 4.0),
                    Vertex::line(-1.0, 4.0),
                ],
            }],
        };
        let keep_out = RegionIndex::new(&square);
        let line = [Point2::new(-10.0, 0.0), Point2::new(10.0, 0.0)];
        let step = 0.05;
        let runs = clear_runs(&line, &keep_out, 3.0, step);
        assert_eq!(runs.len(), 2, "{runs:?}");
        let reach = 1.0 + 5f64.sqrt();
        assert_eq!(runs[0][0], line[0]);
        assert_eq!(*runs[1].last().expect("end"), line[1]);
        let stop = runs[0].last().expect("stop").x;
        let restart = runs[1][0].x;
        assert!(stop <= -reach && stop > -reach - step, "{stop}");
        assert!(restart >= reach && restart < reach + step, "{restart}");
        let far = [Point2::new(-10.0, -2.0), Point2::new(10.0, -2.0)];
        assert_eq!(clear_runs(&far, &keep_out, 3.0, step), vec![far.to_vec()]);
    }

    /// A ramp descends at the slope, turns at the leg's end, reaches the depth and comes back
    /// to the start; every point lies over the pass.
    #[test]
    fn a_ramp_goes_back_and_forth_at_its_slope() {
        let points = vec![
            Point2::new(0.0, 0.0),
            Point2::new(10.0, 0.0),
            Point2::new(10.0, 10.0),
        ];
        let ramp = ramp_along(&points, 5.0, 0.0, 0.1, 30.0);
        // 50 mm of travel: 20 out along the pass, 20 back, 10 out again, then 10 back flat.
        let mut previous = Point3::new(0.0, 0.0, 5.0);
        let mut travel = 0.0;
        for p in &ramp {
            let d = ((p.x - previous.x).powi(2) + (p.y - previous.y).powi(2)).sqrt();
            assert!(previous.z - p.z <= 0.1 * d + 1e-12, "too steep at {p:?}");
            assert!(
                p.y.abs() < 1e-12 || (p.x - 10.0).abs() < 1e-12,
                "off the pass: {p:?}"
            );
            travel += d;
            previous = *p;
        }
        assert!((travel - 60.0).abs() < 1e-9, "{travel}");
        assert_eq!(ramp.last().copied(), Some(Point3::new(0.0, 0.0, 0.0)));
        assert!(ramp_along(&points[..1], 5.0, 0.0, 0.1, 30.0).is_empty());
    }
}
