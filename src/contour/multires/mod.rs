//! Multiresolution contour paths with loose-convex-hull roughing (seed 004 ch. 3–4): exact
//! offsets close to the part, wavelet-approximated offsets farther out, offsets of the loose
//! convex hull (lines and arcs only) outside it.
//!
//! # The passes
//!
//! * **Level 0** is the exact offset of the part at r (the finishing pass; "the wavelet method
//!   results in exact offsets close to the object boundary", §3.8).
//! * **Levels k ≥ 1 inside the loose hull**: the exact offset O_k at ℓ_k = r + k·s is
//!   approximated by [`smooth::approximate_loop`] — corners by multi-scale curvature (§3.1),
//!   segmentation by ν = l/m (§3.2), least-squares B-spline fit per region with the corners
//!   kept, decomposition of the non-smooth regions to coarser levels (eq. 2.16) within the
//!   eq. 3.1 bound (§3.3–3.4), then lines and arcs. Instead of offsetting a coarse control
//!   polygon by d₁ = r + e (Tiller–Hanson, §3.4) the coarse curve approximates the EXACT offset
//!   and e is the approximation's own error budget τ: the pass lies in the band
//!   [ℓ_k − τ, ℓ_k + τ] around the part. That band is then CHECKED EXACTLY — the smallest
//!   distance of every line/arc to the part (closed form) must be ≥ max(r, ℓ_k − τ) and the
//!   sampled two-sided distance to O_k ≤ τ; a loop failing either is replaced by O_k itself
//!   (pushed back onto the exact offset).
//! * **The loose convex hull** H ([`hull`], §4.1) of the part, offset by δ = r + m·s with arcs
//!   at its corners (Fig. 4.4), gives the roughing passes outside H; the part levels k ≥ 1
//!   are clipped to H (§4.2 — we clip the final line/arc passes exactly against the hull
//!   instead of subdividing Bézier curves against the hull polygon).
//! * The first hull pass (δ = r) is left out where it runs within η = 1 µm of the finishing
//!   pass (where the part lies on its hull) — the material there is the finishing pass's.
//! * Everything is clipped to the stock grown by r, like the baseline
//!   ([`crate::contour::parallel`]), ordered far side first and linked by the baseline's
//!   shared code.
//!
//! # Coverage
//!
//! With τ = (r − s)/2 (the default when s < r) a point at distance t from the part lies within
//! r of a pass: some level has ℓ_k ∈ [t − r + τ, t − τ] (an interval of length r − 2τ = s), the
//! straight segment from the point to its nearest part point crosses that level's pass at a
//! point whose distance to the part is within τ of ℓ_k, hence at most t − ℓ_k + τ ≤ r from
//! the point — the baseline's argument ([`crate::contour::verify`]) with the band; for a
//! point inside H with t ≥ r that crossing lies inside H too (H is convex and contains the part), so
//! clipping the part levels to H keeps it. Points with t < r are swept by level 0, which is
//! not clipped to H (only to the stock). Outside H the hull passes cover everything: H is
//! convex, a point t from H is within r of the hull pass at any δ ∈ [t − r, t + r], and
//! s ≤ 2r. When s ≥ r the default τ is
//! 0 and the part levels are the exact offsets; the hull passes still simplify the roughing.
//! The adaptive curves of §3.5 (eq. 3.2–3.3) fill the gaps that offsetting a coarse control
//! polygon by r + e leaves; with the band construction the spacing of consecutive part levels
//! is at most s + 2τ ≤ r by construction, so no adaptive curve is needed and none is added
//! (the fractional levels of eq. 3.2 are in [`crate::contour::wavelet::fractional`]). The
//! uncut area is measured by the `contour` command against the baseline's.
//!
//! # Pass spacing
//!
//! Consecutive part levels are at most s + 2τ apart, consecutive hull passes s. Where a part
//! level is cut off at H, the next pass outward is the first hull pass, r outside H: the
//! geometric gap there reaches about r + s (reported as `pass_spacing_max_mm` by the `contour`
//! command; its 95th percentile stays s). Coverage does not suffer (see above), and since the
//! hull passes are cut first (far side first) the band between them and H is already cleared
//! when the part levels are cut.

pub mod corners;
pub mod hull;
pub mod sample;
pub mod smooth;

use crate::contour::bvh::SegmentBvh;
use crate::contour::cavc::offset_region;
use crate::contour::error::{ContourError, Result};
use crate::contour::geometry::{Contour, Point2, Shape};
use crate::contour::parallel::{CLIP_EPS, Piece, Setup, clip_loop, link, order_pieces, setup};
use crate::contour::region::RegionIndex;
use crate::contour::toolpath::CenterPath;
use corners::CornerOptions;
use sample::sample_closed;

/// Offset loops with at most this many segments are kept exact: a B-spline region becomes at
/// least two arcs per Bézier span, so there is nothing to gain.
const MIN_SEGMENTS_TO_SIMPLIFY: usize = 24;

/// η: pieces of the first hull pass closer than r + η to the part duplicate the finishing
/// pass and are dropped, mm.
const DUPLICATE_TOL: f64 = 1e-3;

/// Options of [`multires_paths`]; [`MultiresOptions::new`] gives the documented defaults.
#[derive(Clone, Debug, PartialEq)]
pub struct MultiresOptions {
    /// Flat end mill radius r, mm (> 0).
    pub tool_radius: f64,
    /// Stepover s between consecutive nominal levels, mm (0 < s ≤ 2r).
    pub stepover: f64,
    /// Band half-width τ of the wavelet passes around their nominal level, mm; `None` =
    /// max(0, (r − s)/2), the largest that keeps the baseline's coverage argument.
    pub tolerance: Option<f64>,
    /// Corner detection (§3.1).
    pub corners: CornerOptions,
    /// Hull legs shorter than this are deleted or combined (§4.1), mm; `None` = 4s.
    pub hull_min_leg: Option<f64>,
    /// How far the loose hull may reach beyond the convex hull, mm; `None` = s (one more
    /// pass of air at most).
    pub hull_max_growth: Option<f64>,
    /// Longest straight link made at cutting depth, mm; `None` = 2r.
    pub max_feed_link: Option<f64>,
    /// Upper bound on the number of levels of each family.
    pub max_levels: usize,
}

impl MultiresOptions {
    /// Options with tool radius `r` and stepover `s`, every other option at its default.
    pub fn new(tool_radius: f64, stepover: f64) -> Self {
        Self {
            tool_radius,
            stepover,
            tolerance: None,
            corners: CornerOptions::default(),
            hull_min_leg: None,
            hull_max_growth: None,
            max_feed_link: None,
            max_levels: 100_000,
        }
    }
}

/// What the planner did, for reports.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MultiresReport {
    /// Band half-width τ used, mm.
    pub tolerance: f64,
    /// Part levels (including level 0) and hull levels that produced passes.
    pub part_levels: usize,
    pub hull_levels: usize,
    /// Legs of the convex hull and of the loose hull.
    pub hull_legs: usize,
    pub loose_hull_legs: usize,
    /// Offset loops approximated by wavelets and kept, and those left exact because the
    /// approximation was not simpler or failed the exact check.
    pub wavelet_loops: usize,
    pub exact_fallbacks: usize,
    /// Corner points found, smooth / non-smooth regions, wavelet levels dropped (all loops).
    pub corners: usize,
    pub smooth_regions: usize,
    pub non_smooth_regions: usize,
    pub levels_dropped: u32,
    /// Segments of the exact offset loops and of the loops used instead (before clipping).
    pub exact_segments: usize,
    pub used_segments: usize,
}

/// The planned path, its report and the loose hull (counter-clockwise polygon).
#[derive(Clone, Debug, PartialEq)]
pub struct MultiresPlan {
    pub path: CenterPath,
    pub report: MultiresReport,
    pub loose_hull: Vec<Point2>,
}

/// Plans the multiresolution path that removes `stock − part` (see the module docs).
pub fn multires_paths(part: &Shape, stock: &Shape, opts: &MultiresOptions) -> Result<MultiresPlan> {
    let (r, s) = (opts.tool_radius, opts.stepover);
    let Setup {
        max_feed_link,
        part_index,
        clip_index,
    } = setup(part, stock, r, s, opts.max_feed_link)?;
    let tol = opts.tolerance.unwrap_or((0.5 * (r - s)).max(0.0));
    if !(tol.is_finite() && tol >= 0.0) {
        return Err(ContourError::InvalidOption {
            name: "tolerance",
            value: tol,
            reason: "must be a finite number of mm ≥ 0",
        });
    }
    let min_leg = opts.hull_min_leg.unwrap_or(4.0 * s);
    let max_growth = opts.hull_max_growth.unwrap_or(s);
    for (name, value) in [("hull_min_leg", min_leg), ("hull_max_growth", max_growth)] {
        if !(value.is_finite() && value >= 0.0) {
            return Err(ContourError::InvalidOption {
                name,
                value,
                reason: "must be a finite number of mm ≥ 0",
            });
        }
    }
    let mut report = MultiresReport {
        tolerance: tol,
        ..Default::default()
    };

    let hull = hull::convex_hull(&hull::enclosing_points(part));
    if hull.len() < 3 {
        return Err(ContourError::BadContour {
            what: "part",
            index: 0,
            reason: "has no area (its convex hull is degenerate)".into(),
        });
    }
    let loose = hull::loose_hull(&hull, min_leg, max_growth);
    report.hull_legs = hull.len();
    report.loose_hull_legs = loose.len();
    let loose_shape = Shape {
        contours: vec![Contour {
            vertices: loose
                .iter()
                .map(|p| crate::contour::geometry::Vertex::line(p.x, p.y))
                .collect(),
        }],
    };
    let loose_index = RegionIndex::new(&loose_shape);
    // The part levels are clipped to the loose hull itself (grown by CLIP_EPS against
    // round-off): material inside H is covered by the part level crossing the straight
    // segment to its nearest part point, and that segment stays inside the convex H.
    let hull_clip = RegionIndex::new(&Shape {
        contours: vec![hull::hull_offset(&loose, CLIP_EPS)],
    });

    let mut pieces: Vec<Piece> = Vec::new();
    // Part levels, clipped to the stock and to the loose hull.
    let mut k = 0;
    loop {
        if k > opts.max_levels {
            return Err(ContourError::TooManyLevels {
                levels: opts.max_levels,
                reached: r + k as f64 * s,
            });
        }
        let level = r + k as f64 * s;
        let mut found = false;
        for exact in offset_region(part, level, "part")? {
            let used = if k == 0 || tol <= 0.0 {
                exact.clone()
            } else {
                approximate_checked(&exact, level, tol, r, s, opts, &part_index, &mut report)
            };
            report.exact_segments += exact.vertices.len();
            report.used_segments += used.vertices.len();
            // Level 0 is the whole finishing pass: material within r of the part is swept by
            // the level-r point beyond it, which may lie outside H.
            let clips: &[(&RegionIndex, bool)] = if k == 0 {
                &[(&clip_index, true)]
            } else {
                &[(&clip_index, true), (&hull_clip, true)]
            };
            for pass in clip_loop(&used, clips, level)? {
                found = true;
                pieces.push(Piece { level: k, pass });
            }
        }
        // The clip region (stock ∩ grown hull) is convex for a rectangular stock, so once a
        // level misses it every farther level does too.
        if !found {
            break;
        }
        report.part_levels += 1;
        k += 1;
    }
    // Hull levels from δ = r outward, until one misses the stock and the whole stock is
    // within δ of the hull.
    let probes: Vec<Point2> = stock
        .contours
        .iter()
        .flat_map(|c| c.vertices.iter().map(|v| v.point))
        .collect();
    let finish_zone = RegionIndex::new(&Shape {
        contours: offset_region(part, r + DUPLICATE_TOL, "part")?,
    });
    let base = k;
    let mut m = 0;
    loop {
        if m > opts.max_levels {
            return Err(ContourError::TooManyLevels {
                levels: opts.max_levels,
                reached: r + m as f64 * s,
            });
        }
        let delta = r + m as f64 * s;
        let ring = hull::hull_offset(&loose, delta);
        let mut found = false;
        // Where the part lies on the hull, the first hull pass runs along the finishing pass:
        // its points within r + η of the part are within η of the finishing pass (they are
        // outside the part grown by r), so they are left out.
        let clips: &[(&RegionIndex, bool)] = if m == 0 {
            &[(&clip_index, true), (&finish_zone, false)]
        } else {
            &[(&clip_index, true)]
        };
        for pass in clip_loop(&ring, clips, delta)? {
            found = true;
            pieces.push(Piece {
                level: base + m,
                pass,
            });
        }
        if found {
            report.hull_levels += 1;
        } else if probes
            .iter()
            .all(|&p| loose_index.signed_distance(p) < delta)
        {
            break;
        }
        m += 1;
    }
    let ordered = order_pieces(pieces, s + 2.0 * tol);
    let path = link(ordered, &part_index, r, max_feed_link)?;
    Ok(MultiresPlan {
        path,
        report,
        loose_hull: loose,
    })
}

/// The wavelet approximation of the exact offset loop `exact` at `level`, when it passes the
/// exact band check; else `exact`.
#[allow(clippy::too_many_arguments)]
fn approximate_checked(
    exact: &Contour,
    level: f64,
    tol: f64,
    r: f64,
    s: f64,
    opts: &MultiresOptions,
    part: &RegionIndex,
    report: &mut MultiresReport,
) -> Contour {
    // A loop of a few lines and arcs is as simple as any approximation of it.
    if exact.vertices.len() <= MIN_SEGMENTS_TO_SIMPLIFY {
        report.exact_fallbacks += 1;
        return exact.clone();
    }
    // Sampling step: fine enough for the tolerance and for corners at the stepover's scale.
    let step = (0.25 * s)
        .min(exact.length() / 64.0)
        .max(exact.length() / 20_000.0);
    let (approx, stats) = smooth::approximate_loop(exact, tol, step, &opts.corners);
    // Already simpler than any approximation (a few lines and arcs): keep it exact.
    if approx.vertices.len() >= exact.vertices.len() {
        report.exact_fallbacks += 1;
        return exact.clone();
    }
    report.corners += stats.corners;
    report.smooth_regions += stats.smooth_regions;
    report.non_smooth_regions += stats.non_smooth_regions;
    report.levels_dropped += stats.levels_dropped;
    let floor = r.max(level - tol) - 1e-9;
    let near_ok = approx.segments().all(|seg| {
        part.boundary()
            .nearest(&seg)
            .is_none_or(|n| n.distance >= floor)
    }) && approx
        .vertices
        .first()
        .is_some_and(|v| !part.contains(v.point));
    let same_turn = approx.signed_area().signum() == exact.signed_area().signum();
    let ok = near_ok && same_turn && within(&approx, exact, tol) && within(exact, &approx, tol);
    if ok {
        report.wavelet_loops += 1;
        approx
    } else {
        report.exact_fallbacks += 1;
        exact.clone()
    }
}

/// Whether every sample of `a` (every tol/4 of length) lies within `tol` of `b`.
fn within(a: &Contour, b: &Contour, tol: f64) -> bool {
    let bvh = SegmentBvh::new(b.segments().collect());
    let step = (0.25 * tol).max(a.length() / 200_000.0);
    sample_closed(a, step)
        .iter()
        .all(|(p, _)| bvh.nearest_point(*p).is_some_and(|n| n.distance <= tol))
}

#[cfg(test)]
mod tests;
