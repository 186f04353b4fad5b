//! Exact primitives on the line and arc [`Segment`]s of the shared geometry: end points,
//! parametrisation, bounding boxes, intersections and closed-form distances.
//!
//! Everything here is closed-form (no sampling): the verification of issue #6 (overcut of a
//! tool-centre path against the part) and the clipping of offset loops rest on it.
//! The segment-to-segment distance uses the classical critical-pair argument: the minimum
//! distance between two disjoint curves is attained either at an end point of one of them or at
//! an interior pair whose connecting vector is normal to both curves; for a line that means
//! perpendicular to it, for an arc that means radial. All such candidates are enumerated.

use crate::contour::geometry::{Point2, Segment, Vector2};
use crate::geom::Aabb2;
use std::f64::consts::{FRAC_PI_2, TAU};

/// Slack on parameters and angles, to accept points that round-off puts a hair outside.
const PARAM_EPS: f64 = 1e-12;

/// 2D cross product (z component).
pub fn cross(a: Vector2, b: Vector2) -> f64 {
    a.x * b.y - a.y * b.x
}

/// First point of a segment.
pub fn seg_start(s: &Segment) -> Point2 {
    match *s {
        Segment::Line { start, .. } | Segment::Arc { start, .. } => start,
    }
}

/// Last point of a segment.
pub fn seg_end(s: &Segment) -> Point2 {
    match *s {
        Segment::Line { end, .. } | Segment::Arc { end, .. } => end,
    }
}

/// Polar angle of `p` seen from `c`.
pub fn angle_of(c: Point2, p: Point2) -> f64 {
    (p.y - c.y).atan2(p.x - c.x)
}

/// Where the direction of `p` seen from the arc's centre falls on the arc, as a parameter in
/// [0, 1] (0 = start, 1 = end); `None` when it is outside the arc's angular span.
pub fn arc_param(center: Point2, start_angle: f64, sweep: f64, p: Point2) -> Option<f64> {
    if sweep == 0.0 {
        return None;
    }
    let theta = angle_of(center, p);
    let mut delta = if sweep > 0.0 {
        (theta - start_angle).rem_euclid(TAU)
    } else {
        (start_angle - theta).rem_euclid(TAU)
    };
    // Just before the start the remainder is close to 2π; it means "at the start".
    if TAU - delta <= PARAM_EPS {
        delta = 0.0;
    }
    let span = sweep.abs();
    if delta <= span + PARAM_EPS {
        Some((delta / span).min(1.0))
    } else {
        None
    }
}

/// The point at parameter `t` ∈ [0, 1] (arc length proportional); exact end points at 0 and 1.
pub fn point_at(s: &Segment, t: f64) -> Point2 {
    if t <= 0.0 {
        return seg_start(s);
    }
    if t >= 1.0 {
        return seg_end(s);
    }
    match *s {
        Segment::Line { start, end } => start + (end - start) * t,
        Segment::Arc {
            start,
            center,
            radius,
            sweep,
            ..
        } => {
            let a = angle_of(center, start) + t * sweep;
            Point2::new(center.x + radius * a.cos(), center.y + radius * a.sin())
        }
    }
}

/// The part of `s` between parameters `t0 < t1`, as (start, end, bulge).
pub fn sub_segment(s: &Segment, t0: f64, t1: f64) -> (Point2, Point2, f64) {
    let a = point_at(s, t0);
    let b = point_at(s, t1);
    let bulge = match *s {
        Segment::Line { .. } => 0.0,
        Segment::Arc { sweep, .. } => ((t1 - t0) * sweep / 4.0).tan(),
    };
    (a, b, bulge)
}

/// Splits an arc into pieces of at most `max_sweep` radians (a line is returned as is).
pub fn split_arc(s: &Segment, max_sweep: f64) -> Vec<Segment> {
    match *s {
        Segment::Line { .. } => vec![*s],
        Segment::Arc { sweep, .. } => {
            let n = ((sweep.abs() / max_sweep).ceil() as usize).max(1);
            (0..n)
                .map(|i| {
                    let (a, b, bulge) =
                        sub_segment(s, i as f64 / n as f64, (i + 1) as f64 / n as f64);
                    Segment::new(a, b, bulge)
                })
                .collect()
        }
    }
}

/// Exact bounding box of a segment (an arc's box includes the axis extremes it passes).
pub fn bbox(s: &Segment) -> Aabb2 {
    let mut b = Aabb2::point(seg_start(s));
    b.add(seg_end(s));
    if let Segment::Arc {
        start,
        center,
        radius,
        sweep,
        ..
    } = *s
    {
        let a0 = angle_of(center, start);
        for k in 0..4 {
            let ang = k as f64 * FRAC_PI_2;
            if arc_param(
                center,
                a0,
                sweep,
                center + Vector2::new(ang.cos(), ang.sin()),
            )
            .is_some()
            {
                b.add(center + Vector2::new(ang.cos(), ang.sin()) * radius);
            }
        }
    }
    b
}

/// Closest point of segment `s` to `p`, and its distance.
pub fn point_distance(p: Point2, s: &Segment) -> (f64, Point2) {
    match *s {
        Segment::Line { start, end } => {
            let d = end - start;
            let l2 = d.norm_squared();
            let t = if l2 > 0.0 {
                ((p - start).dot(&d) / l2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let q = start + d * t;
            ((p - q).norm(), q)
        }
        Segment::Arc {
            start,
            end,
            center,
            radius,
            sweep,
        } => {
            let v = p - center;
            let rho = v.norm();
            if rho > 0.0 && arc_param(center, angle_of(center, start), sweep, p).is_some() {
                return ((rho - radius).abs(), center + v * (radius / rho));
            }
            let (ds, de) = ((p - start).norm(), (p - end).norm());
            if ds <= de { (ds, start) } else { (de, end) }
        }
    }
}

/// An intersection of two segments: parameters on each and the point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub ta: f64,
    pub tb: f64,
    pub point: Point2,
}

fn line_param(a: Point2, b: Point2, p: Point2) -> f64 {
    let d = b - a;
    let l2 = d.norm_squared();
    if l2 > 0.0 { (p - a).dot(&d) / l2 } else { 0.0 }
}

fn in_unit(t: f64) -> Option<f64> {
    (-PARAM_EPS..=1.0 + PARAM_EPS)
        .contains(&t)
        .then_some(t.clamp(0.0, 1.0))
}

/// Parameter of a point known to lie on `s` (up to round-off).
pub fn param_on(s: &Segment, p: Point2) -> f64 {
    match *s {
        Segment::Line { start, end } => line_param(start, end, p).clamp(0.0, 1.0),
        Segment::Arc {
            start,
            center,
            sweep,
            ..
        } => {
            arc_param(center, angle_of(center, start), sweep, p).unwrap_or_else(|| {
                // Round-off just outside the span: snap to the nearer end.
                let (ds, de) = ((p - start).norm(), (p - seg_end(s)).norm());
                if ds <= de { 0.0 } else { 1.0 }
            })
        }
    }
}

/// All intersection points of two segments. Overlapping collinear lines or co-circular arcs
/// report the end points of their overlap.
pub fn intersections(a: &Segment, b: &Segment) -> Vec<Hit> {
    let mut out = Vec::new();
    match (*a, *b) {
        (Segment::Line { start: a0, end: a1 }, Segment::Line { start: b0, end: b1 }) => {
            let (d1, d2) = (a1 - a0, b1 - b0);
            let denom = cross(d1, d2);
            let scale = d1.norm() * d2.norm();
            if scale == 0.0 {
                return out;
            }
            if denom.abs() > 1e-14 * scale {
                let w = b0 - a0;
                if let (Some(t), Some(u)) =
                    (in_unit(cross(w, d2) / denom), in_unit(cross(w, d1) / denom))
                {
                    out.push(Hit {
                        ta: t,
                        tb: u,
                        point: a0 + d1 * t,
                    });
                }
            } else if cross(b0 - a0, d1).abs() <= 1e-12 * d1.norm() * (1.0 + (b0 - a0).norm()) {
                // Collinear: report the ends of the overlap.
                for p in [a0, a1, b0, b1] {
                    let (ta, tb) = (line_param(a0, a1, p), line_param(b0, b1, p));
                    if let (Some(ta), Some(tb)) = (in_unit(ta), in_unit(tb)) {
                        let hit = Hit { ta, tb, point: p };
                        if !out.iter().any(|h: &Hit| (h.point - p).norm() == 0.0) {
                            out.push(hit);
                        }
                    }
                }
            }
        }
        (Segment::Line { .. }, Segment::Arc { .. }) => {
            for h in line_arc(a, b) {
                out.push(h);
            }
        }
        (Segment::Arc { .. }, Segment::Line { .. }) => {
            for h in line_arc(b, a) {
                out.push(Hit {
                    ta: h.tb,
                    tb: h.ta,
                    point: h.point,
                });
            }
        }
        (
            Segment::Arc {
                start: s1,
                center: c1,
                radius: r1,
                sweep: w1,
                ..
            },
            Segment::Arc {
                start: s2,
                center: c2,
                radius: r2,
                sweep: w2,
                ..
            },
        ) => {
            let (a1, a2) = (angle_of(c1, s1), angle_of(c2, s2));
            let dv = c2 - c1;
            let d = dv.norm();
            let tol = 1e-12 * (1.0 + r1 + r2);
            if d <= tol {
                if (r1 - r2).abs() <= tol {
                    // Co-circular: ends of each arc lying on the other.
                    for p in [s1, seg_end(a), s2, seg_end(b)] {
                        if let (Some(ta), Some(tb)) =
                            (arc_param(c1, a1, w1, p), arc_param(c2, a2, w2, p))
                            && !out.iter().any(|h: &Hit| (h.point - p).norm() == 0.0)
                        {
                            out.push(Hit { ta, tb, point: p });
                        }
                    }
                }
                return out;
            }
            let x = (r1 * r1 - r2 * r2 + d * d) / (2.0 * d);
            let h2 = r1 * r1 - x * x;
            if h2 < 0.0 {
                return out;
            }
            let h = h2.sqrt();
            let u = dv / d;
            let perp = Vector2::new(-u.y, u.x);
            let base = c1 + u * x;
            let cands: &[Point2] = if h == 0.0 {
                &[base]
            } else {
                &[base + perp * h, base - perp * h]
            };
            for &p in cands {
                if let (Some(ta), Some(tb)) = (arc_param(c1, a1, w1, p), arc_param(c2, a2, w2, p)) {
                    out.push(Hit { ta, tb, point: p });
                }
            }
        }
    }
    out
}

/// Intersections of a line (`l`) with an arc (`c`); `ta` is on the line.
fn line_arc(l: &Segment, c: &Segment) -> Vec<Hit> {
    let mut out = Vec::new();
    let (
        Segment::Line { start: a0, end: a1 },
        Segment::Arc {
            start,
            center,
            radius,
            sweep,
            ..
        },
    ) = (*l, *c)
    else {
        return out;
    };
    let d = a1 - a0;
    let f = a0 - center;
    let qa = d.norm_squared();
    if qa == 0.0 {
        return out;
    }
    let qb = 2.0 * f.dot(&d);
    let qc = f.norm_squared() - radius * radius;
    let disc = qb * qb - 4.0 * qa * qc;
    if disc < 0.0 {
        return out;
    }
    let sq = disc.sqrt();
    // Numerically stable pair of roots.
    let q = -0.5 * (qb + qb.signum() * sq);
    let mut roots = if q != 0.0 {
        vec![q / qa, qc / q]
    } else {
        vec![-qb / (2.0 * qa)]
    };
    if sq == 0.0 {
        roots.truncate(1);
    }
    let a_start = angle_of(center, start);
    for t in roots {
        if let Some(t) = in_unit(t) {
            let p = a0 + d * t;
            if let Some(u) = arc_param(center, a_start, sweep, p) {
                out.push(Hit {
                    ta: t,
                    tb: u,
                    point: p,
                });
            }
        }
    }
    out
}

/// Exact minimum distance between two segments, with a closest pair (point on `a`, point on
/// `b`).
pub fn segment_distance(a: &Segment, b: &Segment) -> (f64, Point2, Point2) {
    if let Some(h) = intersections(a, b).first() {
        return (0.0, h.point, h.point);
    }
    let mut best = (f64::INFINITY, seg_start(a), seg_start(b));
    let mut consider = |d: f64, pa: Point2, pb: Point2| {
        if d < best.0 {
            best = (d, pa, pb);
        }
    };
    for p in [seg_start(a), seg_end(a)] {
        let (d, q) = point_distance(p, b);
        consider(d, p, q);
    }
    for p in [seg_start(b), seg_end(b)] {
        let (d, q) = point_distance(p, a);
        consider(d, q, p);
    }
    // Interior-interior critical pairs.
    match (*a, *b) {
        (Segment::Line { .. }, Segment::Line { .. }) => {}
        (Segment::Line { start, end }, Segment::Arc { .. }) => {
            if let Some((d, pl, pc)) = line_arc_interior(start, end, b) {
                consider(d, pl, pc);
            }
        }
        (Segment::Arc { .. }, Segment::Line { start, end }) => {
            if let Some((d, pl, pc)) = line_arc_interior(start, end, a) {
                consider(d, pc, pl);
            }
        }
        (
            Segment::Arc {
                start: s1,
                center: c1,
                radius: r1,
                sweep: w1,
                ..
            },
            Segment::Arc {
                start: s2,
                center: c2,
                radius: r2,
                sweep: w2,
                ..
            },
        ) => {
            let dv = c2 - c1;
            let d = dv.norm();
            // Concentric arcs are covered by the end-point candidates (an end of one lies in the
            // angular span of the other whenever the spans overlap).
            if d > 0.0 {
                let u = dv / d;
                let (a1, a2) = (angle_of(c1, s1), angle_of(c2, s2));
                for p1 in [c1 + u * r1, c1 - u * r1] {
                    if arc_param(c1, a1, w1, p1).is_none() {
                        continue;
                    }
                    for p2 in [c2 + u * r2, c2 - u * r2] {
                        if arc_param(c2, a2, w2, p2).is_some() {
                            consider((p1 - p2).norm(), p1, p2);
                        }
                    }
                }
            }
        }
    }
    best
}

/// Interior-interior candidates between the line a0→a1 and an arc: the arc points whose radius is
/// perpendicular to the line, when they project inside the line segment.
fn line_arc_interior(a0: Point2, a1: Point2, arc: &Segment) -> Option<(f64, Point2, Point2)> {
    let Segment::Arc {
        start,
        center,
        radius,
        sweep,
        ..
    } = *arc
    else {
        return None;
    };
    let d = a1 - a0;
    let l = d.norm();
    if l == 0.0 {
        return None;
    }
    let dir = d / l;
    let normal = Vector2::new(-dir.y, dir.x);
    let a_start = angle_of(center, start);
    let mut best: Option<(f64, Point2, Point2)> = None;
    for q in [center + normal * radius, center - normal * radius] {
        if arc_param(center, a_start, sweep, q).is_none() {
            continue;
        }
        let t = (q - a0).dot(&dir);
        if t < 0.0 || t > l {
            continue;
        }
        let foot = a0 + dir * t;
        let dist = (q - foot).norm();
        if best.is_none_or(|b| dist < b.0) {
            best = Some((dist, foot, q));
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contour::geometry::Vertex;
    use std::f64::consts::PI;

    use crate::geom::SeededRandom;

    fn random_segment(rng: &mut SeededRandom) -> Segment {
        let a = Point2::new(rng.range(-5.0, 5.0), rng.range(-5.0, 5.0));
        let b = Point2::new(rng.range(-5.0, 5.0), rng.range(-5.0, 5.0));
        let bulge = if rng.unit() < 0.3 {
            0.0
        } else {
            rng.range(-3.0, 3.0)
        };
        Segment::new(a, b, bulge)
    }

    fn samples(s: &Segment, n: usize) -> Vec<Point2> {
        (0..=n).map(|i| point_at(s, i as f64 / n as f64)).collect()
    }

    fn on_segment(p: Point2, s: &Segment) -> bool {
        point_distance(p, s).0 < 1e-9
    }

    #[test]
    fn point_at_and_param_round_trip_on_arcs() {
        let s = Segment::new(Point2::new(1.0, 0.0), Point2::new(-1.0, 0.0), 1.0);
        let p = point_at(&s, 0.5);
        assert!((p - Point2::new(0.0, 1.0)).norm() < 1e-12, "{p}");
        assert!((param_on(&s, p) - 0.5).abs() < 1e-12);
        let cw = Segment::new(Point2::new(1.0, 0.0), Point2::new(-1.0, 0.0), -1.0);
        assert!((point_at(&cw, 0.5) - Point2::new(0.0, -1.0)).norm() < 1e-12);
        // A 270° arc (bulge tan(67.5°)) passes through (0,1), (−1,0), (0,−1).
        let big = Segment::new(
            Point2::new(1.0, 0.0),
            Point2::new(0.0, -1.0),
            (1.5 * PI / 4.0).tan(),
        );
        let b = bbox(&big);
        assert!((b.min.x + 1.0).abs() < 1e-12 && (b.max.y - 1.0).abs() < 1e-12);
        assert!((b.min.y + 1.0).abs() < 1e-12 && (b.max.x - 1.0).abs() < 1e-12);
    }

    #[test]
    fn exact_distance_matches_dense_sampling() {
        let mut rng = SeededRandom::new(0x5eed);
        let n = 600;
        for case in 0..300 {
            let (a, b) = (random_segment(&mut rng), random_segment(&mut rng));
            let (d, pa, pb) = segment_distance(&a, &b);
            // The reported pair is real and realises the distance.
            assert!(on_segment(pa, &a) && on_segment(pb, &b), "case {case}");
            assert!(((pa - pb).norm() - d).abs() < 1e-9, "case {case}");
            let (sa, sb) = (samples(&a, n), samples(&b, n));
            let mut sampled = f64::INFINITY;
            for p in &sa {
                for q in &sb {
                    sampled = sampled.min((p - q).norm());
                }
            }
            // Sampled points are real points, so the exact minimum is never above them, and the
            // sampling can miss the true minimum by at most half a spacing on each curve.
            let slack = 0.5 * (a.length() + b.length()) / n as f64;
            assert!(
                d <= sampled + 1e-12,
                "case {case}: exact {d} > sampled {sampled}"
            );
            assert!(
                d >= sampled - slack - 1e-12,
                "case {case}: exact {d} < sampled {sampled}"
            );
        }
    }

    #[test]
    fn interior_interior_arc_cases_are_found() {
        // Two arcs facing each other across a gap: the closest points are interior to both.
        let a = Segment::new(Point2::new(1.0, -1.0), Point2::new(1.0, 1.0), 0.4);
        let b = Segment::new(Point2::new(5.0, 1.0), Point2::new(5.0, -1.0), 0.4);
        let (d, pa, pb) = segment_distance(&a, &b);
        let Segment::Arc {
            center: ca,
            radius: ra,
            ..
        } = a
        else {
            unreachable!()
        };
        let Segment::Arc {
            center: cb,
            radius: rb,
            ..
        } = b
        else {
            unreachable!()
        };
        assert!((d - ((cb - ca).norm() - ra - rb)).abs() < 1e-12, "{d}");
        assert!(pa.y.abs() < 1e-12 && pb.y.abs() < 1e-12);
        // A line above an arc's apex.
        let l = Segment::Line {
            start: Point2::new(-3.0, 2.0),
            end: Point2::new(3.0, 2.0),
        };
        let c = Segment::new(Point2::new(1.0, 0.0), Point2::new(-1.0, 0.0), 1.0);
        let (d, _, q) = segment_distance(&l, &c);
        assert!((d - 1.0).abs() < 1e-12 && (q - Point2::new(0.0, 1.0)).norm() < 1e-12);
        // Crossing gives zero.
        let l2 = Segment::Line {
            start: Point2::new(0.0, -3.0),
            end: Point2::new(0.0, 3.0),
        };
        assert_eq!(segment_distance(&l2, &c).0, 0.0);
    }

    #[test]
    fn intersections_lie_on_both_segments() {
        let mut rng = SeededRandom::new(42);
        let mut found = 0;
        for _ in 0..500 {
            let (a, b) = (random_segment(&mut rng), random_segment(&mut rng));
            for h in intersections(&a, &b) {
                found += 1;
                assert!(on_segment(h.point, &a) && on_segment(h.point, &b));
                assert!((point_at(&a, h.ta) - h.point).norm() < 1e-8);
                assert!((point_at(&b, h.tb) - h.point).norm() < 1e-8);
            }
        }
        assert!(found > 100, "too few intersections exercised: {found}");
        let _ = Vertex::line(0.0, 0.0);
    }
}
