//! Corner points by multi-scale curvature (seed 004 §3.1) and the ν = l/m segmentation into
//! smooth and non-smooth regions (§3.2).
//!
//! The closed curve is sampled at equal arc-length steps. Scale i smooths the coordinates with
//! the cubic B-spline kernel (1, 4, 6, 4, 1)/16 dilated by 2^{i−1} ("à trous"), applied on top
//! of scale i − 1 — the discrete B-spline wavelet transform of Wang et al. (1999) the seed
//! adopts; W₁ and W₂ of eq. (25) are the first and second central differences of the smoothed
//! coordinates, and k(u, i) = (W₁x W₂y − W₁y W₂x) / (W₁x² + W₁y²)^{3/2}. Corners are the peaks of
//! |k| at the coarsest scale, moved coarse-to-fine to the peak of each finer scale within the
//! finer scale's support, and kept when the direction turns by at least `min_turn` across the
//! coarsest window ("significant changes in direction").

use crate::contour::geometry::Point2;
use crate::contour::segops::cross;

/// Options of [`detect_corners`].
#[derive(Clone, Debug, PartialEq)]
pub struct CornerOptions {
    /// Number of scales (≥ 1); the coarsest kernel spans about 2^{scales+1} samples.
    pub scales: u32,
    /// Smallest turn of direction across the coarsest window that makes a corner, radians.
    pub min_turn: f64,
}

impl Default for CornerOptions {
    /// Three scales, 30°.
    fn default() -> Self {
        Self {
            scales: 3,
            min_turn: 30f64.to_radians(),
        }
    }
}

/// Curvature (eq. 25) of the closed sample sequence at every scale 1..=`scales`.
fn curvatures(points: &[Point2], scales: u32) -> Vec<Vec<f64>> {
    let n = points.len();
    let mut x: Vec<f64> = points.iter().map(|p| p.x).collect();
    let mut y: Vec<f64> = points.iter().map(|p| p.y).collect();
    let mut out = Vec::new();
    for i in 1..=scales {
        let hole = 1usize << (i - 1);
        let smooth = |v: &[f64]| -> Vec<f64> {
            (0..n)
                .map(|k| {
                    let at = |o: isize| {
                        v[(k as isize + o * hole as isize).rem_euclid(n as isize) as usize]
                    };
                    (at(-2) + 4.0 * at(-1) + 6.0 * at(0) + 4.0 * at(1) + at(2)) / 16.0
                })
                .collect()
        };
        x = smooth(&x);
        y = smooth(&y);
        let k: Vec<f64> = (0..n)
            .map(|k| {
                let (p, q) = ((k + n - 1) % n, (k + 1) % n);
                let (w1x, w1y) = (0.5 * (x[q] - x[p]), 0.5 * (y[q] - y[p]));
                let (w2x, w2y) = (x[q] - 2.0 * x[k] + x[p], y[q] - 2.0 * y[k] + y[p]);
                let den = (w1x * w1x + w1y * w1y).powf(1.5);
                if den > 0.0 {
                    (w1x * w2y - w1y * w2x) / den
                } else {
                    0.0
                }
            })
            .collect();
        out.push(k);
    }
    out
}

/// Indices of the corner points of the closed curve sampled by `points` at (about) equal
/// arc-length steps, in increasing order.
pub fn detect_corners(points: &[Point2], opts: &CornerOptions) -> Vec<usize> {
    let n = points.len();
    let scales = opts.scales.clamp(1, 12);
    let window = 1usize << (scales + 1);
    if n < 2 * window + 1 {
        return Vec::new();
    }
    let ks = curvatures(points, scales);
    let coarse = &ks[ks.len() - 1];
    let mut corners = Vec::new();
    for k in 0..n {
        let here = coarse[k].abs();
        // A strict peak against the earlier neighbours, a weak one against the later ones,
        // so a flat-topped peak yields one candidate.
        let peak = (1..=window).all(|o| {
            let before = coarse[(k + n - o) % n].abs();
            let after = coarse[(k + o) % n].abs();
            here > before && here >= after
        });
        if !peak {
            continue;
        }
        // Coarse to fine: follow the peak into the finer scales.
        let mut at = k;
        for level in (0..ks.len() - 1).rev() {
            let reach = 1usize << (level + 1);
            let fine = &ks[level];
            at = (0..=2 * reach)
                .map(|o| (at + n + o - reach) % n)
                .max_by(|a, b| fine[*a].abs().total_cmp(&fine[*b].abs()).then(b.cmp(a)))
                .unwrap_or(at);
        }
        let (before, after) = (points[(at + n - window) % n], points[(at + window) % n]);
        let (u, v) = (points[at] - before, after - points[at]);
        let turn = cross(u, v).atan2(u.dot(&v)).abs();
        if turn >= opts.min_turn && !corners.contains(&at) {
            corners.push(at);
        }
    }
    corners.sort_unstable();
    corners
}

/// A region of a closed curve between two corner points, by arc length: `from` < `to`, `to`
/// may exceed the curve length (the region wraps past the start).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Region {
    pub from: f64,
    pub to: f64,
    /// Smooth (few corners, §3.2) or non-smooth (corners crowded).
    pub smooth: bool,
}

/// Segments a closed curve of length `length` with corners at arc lengths `corners`
/// (increasing, in [0, length)) by ν = l / m (§3.2): a gap between consecutive corners longer
/// than ν is a smooth region; each maximal run of shorter gaps is one non-smooth region.
/// Without corners the whole curve is one smooth region starting at 0.
pub fn segment(length: f64, corners: &[f64]) -> Vec<Region> {
    let m = corners.len();
    if m == 0 {
        return vec![Region {
            from: 0.0,
            to: length,
            smooth: true,
        }];
    }
    let nu = length / m as f64;
    let gap = |i: usize| {
        let next = if i + 1 < m {
            corners[i + 1]
        } else {
            corners[0] + length
        };
        (corners[i], next)
    };
    let smooth: Vec<bool> = (0..m)
        .map(|i| {
            let (a, b) = gap(i);
            b - a > nu
        })
        .collect();
    // Start the walk at a smooth gap when there is one, so non-smooth runs do not wrap.
    let first = smooth.iter().position(|s| *s).unwrap_or(0);
    let mut out: Vec<Region> = Vec::new();
    for step in 0..m {
        let i = (first + step) % m;
        let (mut a, mut b) = gap(i);
        if i < first {
            a += length;
            b += length;
        }
        match out.last_mut() {
            Some(last) if !last.smooth && !smooth[i] => last.to = b,
            _ => out.push(Region {
                from: a,
                to: b,
                smooth: smooth[i],
            }),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contour::geometry::{Contour, Vertex};
    use crate::contour::multires::sample::sample_closed;

    /// 100 × 60 rectangle: sharp corners at (0,0) and (100,0), rounded (radius 12) at the top.
    fn mixed_rectangle() -> Contour {
        let b = (std::f64::consts::FRAC_PI_2 / 4.0).tan();
        Contour {
            vertices: vec![
                Vertex::line(0.0, 0.0),
                Vertex::line(100.0, 0.0),
                Vertex {
                    point: Point2::new(100.0, 48.0),
                    bulge: b,
                },
                Vertex::line(88.0, 60.0),
                Vertex {
                    point: Point2::new(12.0, 60.0),
                    bulge: b,
                },
                Vertex::line(0.0, 48.0),
            ],
        }
    }

    #[test]
    fn finds_the_sharp_corners_and_not_the_rounded_ones() {
        let c = mixed_rectangle();
        let samples = sample_closed(&c, 0.1);
        let pts: Vec<Point2> = samples.iter().map(|s| s.0).collect();
        let found = detect_corners(&pts, &CornerOptions::default());
        let at: Vec<Point2> = found.iter().map(|&i| pts[i]).collect();
        assert_eq!(at.len(), 2, "corners at {at:?}");
        for want in [Point2::new(0.0, 0.0), Point2::new(100.0, 0.0)] {
            assert!(
                at.iter().any(|p| (p - want).norm() <= 1.0),
                "missing {want:?} in {at:?}"
            );
        }
        // Rotated and started elsewhere: the same corners.
        let (s, co) = (0.6f64.sin(), 0.6f64.cos());
        let mut turned = c.clone();
        turned.vertices.rotate_left(3);
        for v in &mut turned.vertices {
            v.point = Point2::new(
                co * v.point.x - s * v.point.y,
                s * v.point.x + co * v.point.y,
            );
        }
        let pts: Vec<Point2> = sample_closed(&turned, 0.1).iter().map(|s| s.0).collect();
        assert_eq!(detect_corners(&pts, &CornerOptions::default()).len(), 2);
        // A wider window (coarser samples) sees the rounded corners as corners too.
        let pts: Vec<Point2> = sample_closed(&c, 1.0).iter().map(|s| s.0).collect();
        assert_eq!(detect_corners(&pts, &CornerOptions::default()).len(), 4);
    }

    #[test]
    fn segmentation_by_nu() {
        // Length 100, corners crowded around 40..50 and two lone ones.
        let r = segment(100.0, &[0.0, 40.0, 43.0, 46.0, 50.0]);
        // ν = 20: gaps 40 (smooth), 3, 3, 4 (non-smooth run), 50 (smooth).
        assert_eq!(
            r,
            vec![
                Region {
                    from: 0.0,
                    to: 40.0,
                    smooth: true
                },
                Region {
                    from: 40.0,
                    to: 50.0,
                    smooth: false
                },
                Region {
                    from: 50.0,
                    to: 100.0,
                    smooth: true
                },
            ]
        );
        let total: f64 = r.iter().map(|g| g.to - g.from).sum();
        assert!((total - 100.0).abs() < 1e-12);
        assert_eq!(segment(10.0, &[]).len(), 1);
        // Evenly spaced corners: nothing is longer than ν, one non-smooth region all round.
        let even = segment(40.0, &[0.0, 10.0, 20.0, 30.0]);
        assert_eq!(even.len(), 1);
        assert!(!even[0].smooth && (even[0].to - even[0].from - 40.0).abs() < 1e-12);
    }
}
