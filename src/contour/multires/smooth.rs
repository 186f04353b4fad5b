//! Multiresolution approximation of one closed offset curve (seed 004 §3.2–3.4): the curve is
//! cut at its corners into smooth and non-smooth regions; each region is least-squares fitted
//! by an endpoint-interpolating cubic B-spline (the corners between regions are kept exactly);
//! non-smooth regions are then wavelet-decomposed to coarser levels (eq. 2.16) as long as the
//! eq. 3.1 bound says the curve stays within the tolerance, smooth regions keep their fitted
//! level (§3.3: "the smooth regions are left unchanged"); finally every Bézier span is replaced
//! by lines and arcs (biarcs, `contour::input::curves::fit_curve`).
//!
//! The error budget of a region: sampled fit error + Σ eq. 3.1 bounds of the dropped levels
//! ≤ ¾ tol, biarcs the rest (≥ ¼ tol). A region whose exact piece has fewer segments than its
//! approximation is kept exact. The caller checks the result exactly against the part and falls
//! back to the exact curve where the check fails (never trusting the bound alone).

use super::corners::{CornerOptions, Region, detect_corners, segment};
use super::sample::{sample_closed, sub_chain};
use crate::contour::geometry::{Contour, Point2, Vertex};
use crate::contour::input::curves::{Cubic, fit_curve};
use crate::contour::wavelet::{
    Controls, bezier_matrix, count, decompose, deviation_bound, evaluate, fit,
};

/// Finest wavelet level fitted to one region (2^6 + 3 control points): finer fits would give
/// more arcs than the exact offsets have.
const MAX_LEVEL: u32 = 6;

/// What [`approximate_loop`] did, for the report.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LoopStats {
    pub corners: usize,
    pub smooth_regions: usize,
    pub non_smooth_regions: usize,
    /// Regions kept exact: no level up to `MAX_LEVEL` fitted them, or the exact piece had
    /// fewer segments.
    pub exact_regions: usize,
    /// Levels removed by decomposition, over all non-smooth regions.
    pub levels_dropped: u32,
}

/// The closed curve `c` approximated within `tol` (see the module docs); `step` is the sampling
/// step of corner detection and fitting, mm.
pub fn approximate_loop(
    c: &Contour,
    tol: f64,
    step: f64,
    corners: &CornerOptions,
) -> (Contour, LoopStats) {
    let mut stats = LoopStats::default();
    let samples = sample_closed(c, step);
    let length = c.length();
    if samples.len() < 16 || tol.is_nan() || tol <= 0.0 {
        return (c.clone(), stats);
    }
    let pts: Vec<Point2> = samples.iter().map(|s| s.0).collect();
    let at: Vec<f64> = detect_corners(&pts, corners)
        .into_iter()
        .map(|i| samples[i].1)
        .collect();
    stats.corners = at.len();
    let regions = segment(length, &at);
    let mut vertices: Vec<Vertex> = Vec::new();
    for region in &regions {
        if region.smooth {
            stats.smooth_regions += 1;
        } else {
            stats.non_smooth_regions += 1;
        }
        // A region whose exact piece has fewer segments than its approximation stays exact.
        let exact = sub_chain(c, region.from, region.to);
        let piece = match approximate_region(c, region, tol, step, &mut stats) {
            Some(v) if v.len() < exact.len() => v,
            _ => {
                stats.exact_regions += 1;
                exact
            }
        };
        // Each piece ends where the next begins: drop its end vertex.
        let keep = piece.len().saturating_sub(1);
        vertices.extend_from_slice(&piece[..keep]);
    }
    vertices.dedup_by(|b, a| (b.point - a.point).norm() <= 1e-9);
    while vertices.len() > 2
        && vertices
            .first()
            .zip(vertices.last())
            .is_some_and(|(f, l)| (f.point - l.point).norm() <= 1e-9)
    {
        vertices.pop();
    }
    if vertices.len() < 2 {
        return (c.clone(), stats);
    }
    (Contour { vertices }, stats)
}

/// One region fitted and (when non-smooth) decomposed, as an open chain of lines and arcs; `None`
/// when no level fits.
fn approximate_region(
    c: &Contour,
    region: &Region,
    tol: f64,
    step: f64,
    stats: &mut LoopStats,
) -> Option<Vec<Vertex>> {
    let chain = sub_chain(c, region.from, region.to);
    let piece = Contour {
        vertices: chain.clone(),
    };
    // Sample the open chain (the closing segment of `piece` is not part of it).
    let span = region.to - region.from;
    let n = ((span / step).ceil() as usize).max(8);
    let mut points = Vec::with_capacity(n + 1);
    let mut params = Vec::with_capacity(n + 1);
    for k in 0..=n {
        let a = span * k as f64 / n as f64;
        points.push(point_along(&piece, a));
        params.push(k as f64 / n as f64);
    }
    let error = |ctrl: &Controls| {
        points
            .iter()
            .zip(&params)
            .map(|(p, u)| (evaluate(ctrl, *u) - p).norm())
            .fold(0.0, f64::max)
    };
    // Non-smooth regions start finer, to leave room for the decomposition.
    let fit_budget = if region.smooth {
        0.75 * tol
    } else {
        0.25 * tol
    };
    let mut fitted = None;
    for j in 1..=MAX_LEVEL {
        if count(j) * 2 > points.len() {
            break;
        }
        let ctrl = fit(&points, &params, j).ok()?;
        let e = error(&ctrl);
        if e <= fit_budget {
            fitted = Some((ctrl, e));
            break;
        }
    }
    let (mut ctrl, mut used) = fitted?;
    if !region.smooth {
        while ctrl.nrows() > count(1) {
            let Ok((coarse, detail)) = decompose(&ctrl) else {
                break;
            };
            let Ok(bound) = deviation_bound(&detail) else {
                break;
            };
            if used + bound > 0.75 * tol {
                break;
            }
            used += bound;
            ctrl = coarse;
            stats.levels_dropped += 1;
        }
    }
    let j = (0..=MAX_LEVEL).find(|&j| count(j) == ctrl.nrows())?;
    let bez = bezier_matrix(j) * &ctrl;
    let mut out = Vec::new();
    for s in 0..(1usize << j) {
        let p = |i: usize| Point2::new(bez[(4 * s + i, 0)], bez[(4 * s + i, 1)]);
        let cubic = Cubic {
            p: [p(0), p(1), p(2), p(3)],
        };
        out.extend(fit_curve(&cubic, 0.0, 1.0, (tol - used).max(0.25 * tol)));
    }
    out.push(Vertex {
        point: chain.last()?.point,
        bulge: 0.0,
    });
    Some(out)
}

/// Point at arc length `a` along the open chain `piece` (its closing segment ignored).
fn point_along(piece: &Contour, a: f64) -> Point2 {
    let n = piece.vertices.len();
    let mut start = 0.0;
    for (i, seg) in piece.segments().enumerate().take(n.saturating_sub(1)) {
        let len = seg.length();
        if start + len >= a || i + 2 == n {
            let t = if len > 0.0 {
                ((a - start) / len).clamp(0.0, 1.0)
            } else {
                0.0
            };
            return crate::contour::segops::point_at(&seg, t);
        }
        start += len;
    }
    piece.vertices.last().map_or(Point2::origin(), |v| v.point)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contour::bvh::SegmentBvh;

    /// A wavy closed curve made of many short lines: the approximation has far fewer segments
    /// and stays within the tolerance (both ways, sampled).
    #[test]
    fn wavy_loop_gets_fewer_segments_within_tolerance() {
        let vertices: Vec<Vertex> = (0..720)
            .map(|k| {
                let a = k as f64 * std::f64::consts::TAU / 720.0;
                let r = 40.0 + 1.5 * (7.0 * a).sin();
                Vertex::line(r * a.cos(), r * a.sin())
            })
            .collect();
        let c = Contour { vertices };
        let (approx, stats) = approximate_loop(&c, 0.05, 0.5, &CornerOptions::default());
        assert!(
            approx.vertices.len() < 300,
            "{} segments",
            approx.vertices.len()
        );
        assert_eq!(stats.exact_regions, 0);
        let exact = SegmentBvh::new(c.segments().collect());
        let mine = SegmentBvh::new(approx.segments().collect());
        for (p, _) in sample_closed(&approx, 0.05) {
            let d = exact.nearest_point(p).map_or(f64::INFINITY, |n| n.distance);
            assert!(d <= 0.05, "approximation {d} from the curve");
        }
        for (p, _) in sample_closed(&c, 0.05) {
            let d = mine.nearest_point(p).map_or(f64::INFINITY, |n| n.distance);
            assert!(d <= 0.05, "curve {d} from the approximation");
        }
    }
}
