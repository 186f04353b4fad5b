//! Exact point/segment geometry for lines and circular arcs: distances, tangents, bounding
//! boxes and winding numbers. Shared by the biarc fitter (error measurement) and the region
//! builder (crossing and containment tests).

use std::f64::consts::{PI, TAU};

use crate::contour::geometry::{Point2, Segment, Vector2};
use crate::contour::segops;
pub(crate) use crate::contour::segops::{cross, seg_end, seg_start};

/// `x` reduced to [0, 2π).
pub(crate) fn wrap_tau(x: f64) -> f64 {
    let r = x.rem_euclid(TAU);
    if r >= TAU { 0.0 } else { r }
}

/// Whether the direction from an arc's centre towards `q` lies within the arc's sweep
/// (inclusive), and the angular offset from the arc's start in the sweep direction.
pub(crate) fn arc_param(center: Point2, start: Point2, sweep: f64, q: Point2) -> (bool, f64) {
    let a0 = (start.y - center.y).atan2(start.x - center.x);
    let b = (q.y - center.y).atan2(q.x - center.x);
    let rel = if sweep >= 0.0 {
        wrap_tau(b - a0)
    } else {
        wrap_tau(a0 - b)
    };
    (rel <= sweep.abs(), rel)
}

/// Distance from `p` to a segment.
pub(crate) fn dist_point_segment(p: Point2, s: &Segment) -> f64 {
    segops::point_distance(p, s).0
}

/// Unit tangent (direction of travel) of a segment at a point `q` on it.
pub(crate) fn tangent_at(s: &Segment, q: Point2) -> Vector2 {
    match *s {
        Segment::Line { start, end } => {
            let d = end - start;
            let n = d.norm();
            if n > 0.0 {
                d / n
            } else {
                Vector2::new(1.0, 0.0)
            }
        }
        Segment::Arc { center, sweep, .. } => {
            let r = q - center;
            let n = r.norm();
            let radial = if n > 0.0 {
                r / n
            } else {
                Vector2::new(1.0, 0.0)
            };
            let left = Vector2::new(-radial.y, radial.x);
            if sweep > 0.0 { left } else { -left }
        }
    }
}

/// The point at fraction `f` of a segment's length.
pub(crate) fn point_on_segment(s: &Segment, f: f64) -> Point2 {
    segops::point_at(s, f)
}

/// Signed curvature of a segment in its direction of travel (positive turning left).
pub(crate) fn curvature(s: &Segment) -> f64 {
    match *s {
        Segment::Line { .. } => 0.0,
        Segment::Arc { radius, sweep, .. } => sweep.signum() / radius,
    }
}

/// Axis-aligned bounding box `[xmin, ymin, xmax, ymax]` of a segment.
pub(crate) fn seg_bbox(s: &Segment) -> [f64; 4] {
    let b = segops::bbox(s);
    [b.min.x, b.min.y, b.max.x, b.max.y]
}

/// Angle subtended at `p` by the segment, exact for arcs: the chord's angle plus a full turn
/// when `p` lies in the circular segment between chord and arc (the closed curve arc + reversed
/// chord then winds once around `p`).
pub(crate) fn subtended_angle(p: Point2, s: &Segment) -> f64 {
    match *s {
        Segment::Line { start, end } => {
            let (u, v) = (start - p, end - p);
            cross(u, v).atan2(u.dot(&v))
        }
        Segment::Arc {
            start,
            end,
            center,
            radius,
            sweep,
        } => {
            let (u, v) = (start - p, end - p);
            // cross(u, v) equals cross(end − start, p − start): the same number decides the
            // chord angle and the side of the chord, so the two cannot disagree by rounding.
            let side = cross(u, v);
            let dot = u.dot(&v);
            if side == 0.0 && dot < 0.0 {
                // On the chord between the endpoints: the arc sweeps half a turn around p on
                // its bulging side.
                return PI * sweep.signum();
            }
            let base = side.atan2(dot);
            let inside_disk = (p - center).norm() < radius;
            // A counter-clockwise arc bulges to the right of its chord, a clockwise one to the
            // left; the circular segment is the part of the disk on that side.
            let in_segment = inside_disk && if sweep > 0.0 { side < 0.0 } else { side > 0.0 };
            if in_segment {
                base + TAU * sweep.signum()
            } else {
                base
            }
        }
    }
}

/// Winding number of a closed sequence of segments around `p` (`p` must not lie on it).
pub(crate) fn winding_number<'a>(
    segments: impl IntoIterator<Item = &'a Segment>,
    p: Point2,
) -> i64 {
    let total: f64 = segments.into_iter().map(|s| subtended_angle(p, s)).sum();
    (total / TAU).round() as i64
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contour::geometry::{Contour, Vertex};

    fn circle(cx: f64, cy: f64, r: f64) -> Contour {
        Contour {
            vertices: vec![
                Vertex {
                    point: Point2::new(cx + r, cy),
                    bulge: 1.0,
                },
                Vertex {
                    point: Point2::new(cx - r, cy),
                    bulge: 1.0,
                },
            ],
        }
    }

    #[test]
    fn winding_of_circle_matches_distance_to_centre() {
        let c = circle(1.0, 2.0, 3.0);
        let segs: Vec<Segment> = c.segments().collect();
        for i in 0..200 {
            let a = i as f64 * 0.731;
            let rr = 0.05 + (i as f64 * 0.377).fract() * 6.0;
            let p = Point2::new(1.0 + rr * a.cos(), 2.0 + rr * a.sin());
            if (rr - 3.0).abs() < 1e-9 {
                continue;
            }
            let expected = i64::from(rr < 3.0);
            assert_eq!(winding_number(&segs, p), expected, "rr={rr}");
        }
        // Reversed orientation gives −1 inside.
        let rev = Contour {
            vertices: vec![
                Vertex {
                    point: Point2::new(4.0, 2.0),
                    bulge: -1.0,
                },
                Vertex {
                    point: Point2::new(-2.0, 2.0),
                    bulge: -1.0,
                },
            ],
        };
        let segs: Vec<Segment> = rev.segments().collect();
        assert_eq!(winding_number(&segs, Point2::new(1.5, 2.5)), -1);
    }

    #[test]
    fn distance_to_arc_and_bbox() {
        // Quarter arc of the unit circle from (1,0) to (0,1), counter-clockwise.
        let s = Segment::new(
            Point2::new(1.0, 0.0),
            Point2::new(0.0, 1.0),
            (PI / 8.0).tan(),
        );
        let p = Point2::new(2.0 * (PI / 5.0).cos(), 2.0 * (PI / 5.0).sin());
        assert!((dist_point_segment(p, &s) - 1.0).abs() < 1e-12);
        // Outside the sweep: nearest is an endpoint.
        let q = Point2::new(0.0, -2.0);
        assert!((dist_point_segment(q, &s) - 5.0f64.sqrt()).abs() < 1e-12);
        let bb = seg_bbox(&Segment::new(
            Point2::new(1.0, 0.0),
            Point2::new(-1.0, 0.0),
            1.0,
        ));
        assert!((bb[3] - 1.0).abs() < 1e-12 && bb[1].abs() < 1e-12);
        assert!((bb[0] + 1.0).abs() < 1e-12 && (bb[2] - 1.0).abs() < 1e-12);
        let t = tangent_at(&s, Point2::new(1.0, 0.0));
        assert!((t - Vector2::new(0.0, 1.0)).norm() < 1e-12);
    }
}
