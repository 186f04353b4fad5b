//! Arc-length sampling of closed line/arc curves and exact sub-chains between two arc lengths.

use crate::contour::geometry::{Contour, Point2, Segment, Vertex};
use crate::contour::segops::{point_at, sub_segment};

/// Points of the closed curve every ~`step` mm of arc length (at least 8, an equal spacing
/// that divides the length), with their arc lengths from the first vertex.
pub fn sample_closed(c: &Contour, step: f64) -> Vec<(Point2, f64)> {
    let segs: Vec<Segment> = c.segments().collect();
    let total = c.length();
    if !(total > 0.0 && step > 0.0) {
        return Vec::new();
    }
    let count = ((total / step).ceil() as usize).clamp(8, 1_000_000);
    let h = total / count as f64;
    let mut out = Vec::with_capacity(count);
    let mut seg = 0;
    let mut seg_start = 0.0;
    for k in 0..count {
        let a = k as f64 * h;
        while seg + 1 < segs.len() && seg_start + segs[seg].length() < a {
            seg_start += segs[seg].length();
            seg += 1;
        }
        let len = segs[seg].length();
        let t = if len > 0.0 {
            (a - seg_start) / len
        } else {
            0.0
        };
        out.push((point_at(&segs[seg], t), a));
    }
    out
}

/// The piece of the closed curve from arc length `from` to `to` (from < to ≤ from + length,
/// both may exceed the length: they wrap), as vertices of an open chain: each vertex starts a
/// segment with its bulge, the last vertex is the end point.
pub fn sub_chain(c: &Contour, from: f64, to: f64) -> Vec<Vertex> {
    let segs: Vec<Segment> = c.segments().collect();
    let total = c.length();
    let mut out: Vec<Vertex> = Vec::new();
    if total.is_nan() || total <= 0.0 || to <= from {
        return out;
    }
    let mut start = 0.0;
    let mut last = None;
    // Walk the segments at most twice around (the piece may wrap).
    for _ in 0..3 {
        for seg in &segs {
            let len = seg.length();
            let (a, b) = (start, start + len);
            start = b;
            let (lo, hi) = (from.max(a), to.min(b));
            if hi > lo && len > 0.0 {
                let (p, q, bulge) = sub_segment(seg, (lo - a) / len, (hi - a) / len);
                if (q - p).norm() > 1e-12 {
                    out.push(Vertex { point: p, bulge });
                    last = Some(q);
                }
            }
            if b >= to {
                if let Some(q) = last {
                    out.push(Vertex {
                        point: q,
                        bulge: 0.0,
                    });
                }
                return out;
            }
        }
    }
    if let Some(q) = last {
        out.push(Vertex {
            point: q,
            bulge: 0.0,
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contour::parallel::tests::{circle, rect};
    use std::f64::consts::PI;

    #[test]
    fn samples_are_equally_spaced_along_the_curve() {
        let c = circle(0.0, 0.0, 10.0, true);
        let s = sample_closed(&c, 0.1);
        let n = s.len();
        assert_eq!(n, (20.0 * PI / 0.1).ceil() as usize);
        for w in s.windows(2) {
            assert!(((w[0].0).coords.norm() - 10.0).abs() < 1e-9);
            assert!((w[1].1 - w[0].1 - 20.0 * PI / n as f64).abs() < 1e-9);
        }
    }

    #[test]
    fn sub_chains_have_the_right_length_and_wrap() {
        let c = rect(0.0, 0.0, 10.0, 5.0, true);
        let piece = sub_chain(&c, 5.0, 22.0);
        let len: f64 = piece
            .windows(2)
            .map(|w| Segment::new(w[0].point, w[1].point, w[0].bulge).length())
            .sum();
        assert!((len - 17.0).abs() < 1e-12);
        assert_eq!(piece[0].point, Point2::new(5.0, 0.0));
        // Wrapping past the start (length 30): 28 → 30 down the left side, then 0 → 3.
        let wrap = sub_chain(&c, 28.0, 33.0);
        assert_eq!(wrap[0].point, Point2::new(0.0, 2.0));
        assert_eq!(wrap.last().map(|v| v.point), Some(Point2::new(3.0, 0.0)));
        let circle_half = sub_chain(&circle(0.0, 0.0, 1.0, true), 0.0, PI);
        let l: f64 = circle_half
            .windows(2)
            .map(|w| Segment::new(w[0].point, w[1].point, w[0].bulge).length())
            .sum();
        assert!((l - PI).abs() < 1e-12);
    }
}
