//! Multiresolution contour paths with loose-convex-hull roughing (seed 004 ch. 3–4): exact
//! offsets close to the part, wavelet-approximated offsets farther out, offsets of the loose
//! convex hull (lines and arcs only) outside it.
//!
//! # The passes
//!
//! * **Level 0** is the exact offset of the part at r, measured and moved out by any shortfall
//!   of the offset engine (the finishing pass; "the wavelet method
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
//!
//! # Adaptive curves (§3.5, eq. 3.3)
//!
//! The argument needs consecutive part levels no more than L = max(r, s) apart where their
//! crossings are worst: G = s + e₁ + e₂ ≤ L, with e₁, e₂ the deviations of the two levels'
//! passes from their exact offsets, MEASURED on the loops used (two-sided, sampled every τ/4;
//! the largest over the loops of a level). With the default τ, e ≤ τ = (r − s)/2 gives G ≤ r
//! and eq. 3.3's count is below one: no curve is added. With a wider band (the `tolerance`
//! option, `--band`) the passes get coarser and G can exceed L; then
//! `adaptive_levels` inserts n = ⌈(G − L)/(L − 2e_a)⌉ curves at fractional levels between
//! the two (eq. 3.3, rounded up, generalised to s ≠ r and to curves with their own band
//! e_a = min(τ, (r − s)/2)). Each is the exact offset at its fractional level, approximated by
//! the same wavelet machinery within e_a, checked exactly like every pass, clipped and linked
//! like the part levels. Where we depart from the seed: its adaptive curve c^{m+t} (eq. 3.2,
//! [`crate::contour::wavelet::fractional`]) interpolates the control points of two scales of
//! one region; our two neighbouring passes are fits of different exact offsets, with their own
//! corners and region splits, so there are no matching control points to interpolate — the
//! fractional LEVEL is interpolated (the offset distance), not the control points. The count
//! is per level (the worst loop of each level decides), not per non-smooth region, so a curve
//! is a whole offset loop, which is safe but not minimal. Measured (docs/contour-2.5d.md): a
//! wider band makes the coarse passes no shorter than the extra curves cost, so the default
//! band stays.
//! The uncut area is measured by the `contour` command against the baseline's.
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
use crate::contour::cavc::{offset_region, offset_region_cleared};
use crate::contour::error::{ContourError, Result};
use crate::contour::geometry::{Contour, Point2, Shape};
use crate::contour::parallel::{CLIP_EPS, Piece, clip_loop, order_pieces, setup};
use crate::contour::region::RegionIndex;
use crate::contour::toolpath::{CenterPath, CutDirection, Pass};
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
    /// Which way the roughing passes may run (as in [`crate::contour::parallel`]).
    pub direction: CutDirection,
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
            direction: CutDirection::default(),
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
    /// Adaptive curves (§3.5): fractional levels inserted between consecutive part levels
    /// whose gap s + e₁ + e₂ exceeds r, and the offset loops they produced (before clipping).
    pub adaptive_curves: usize,
    pub adaptive_loops: usize,
    /// Largest measured deviation e of a part level's passes from its exact offset, mm.
    pub max_deviation: f64,
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
    let setup = setup(part, stock, r, s, opts.max_feed_link)?;
    let (part_index, clip_index) = (&setup.part_index, &setup.clip_index);
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
    // Band of the adaptive curves: the default band, which keeps their own spacing within r.
    let adaptive_band = tol.min((0.5 * (r - s)).max(0.0));
    let ctx = LevelContext {
        offset_part: &setup.offset_part,
        r,
        s,
        opts,
        part_index,
        clip_index,
        hull_clip: &hull_clip,
    };
    // Part levels, clipped to the stock and to the loose hull; `ring` numbers the passes
    // outward (part levels and adaptive curves) for the far-side-first ordering.
    let mut ring = 0;
    let mut previous = (r, 0.0);
    let mut k = 0;
    loop {
        let level = level_distance(k, r, s, opts.max_levels)?;
        // Level 0 is the whole finishing pass, exact and clipped to the stock only: material
        // within r of the part is swept by the level-r point beyond it, which may lie
        // outside H.
        let (level_pieces, e, level) = if k == 0 {
            let (passes, cleared) = ctx.finishing_passes(&mut report)?;
            (passes, 0.0, cleared)
        } else {
            let (passes, e) = ctx.level_passes(level, tol, true, &mut report)?;
            (passes, e, level)
        };
        // A missing level counts as exact: the adaptive curves still close the gap from the
        // last level to where it would have been.
        if k > 0 {
            let (from, e_from) = previous;
            let e_to = if level_pieces.is_empty() { 0.0 } else { e };
            for u in adaptive_levels(from - e_from, level + e_to, r.max(s), adaptive_band) {
                let (extra, _) = ctx.level_passes(u, adaptive_band, true, &mut report)?;
                report.adaptive_curves += 1;
                report.adaptive_loops += extra.len();
                ring += 1;
                pieces.extend(extra.into_iter().map(|pass| Piece { level: ring, pass }));
            }
        }
        // The clip region (stock ∩ grown hull) is convex for a rectangular stock, and
        // connected for any stock around the part, so once a level misses it every farther
        // level does too.
        if level_pieces.is_empty() {
            break;
        }
        if k > 0 {
            ring += 1;
        }
        pieces.extend(
            level_pieces
                .into_iter()
                .map(|pass| Piece { level: ring, pass }),
        );
        report.max_deviation = report.max_deviation.max(e);
        previous = (level, e);
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
        contours: offset_region(&setup.offset_part, r + DUPLICATE_TOL, "part")?,
    });
    let base = ring + 1;
    let mut m = 0;
    loop {
        let delta = level_distance(m, r, s, opts.max_levels)?;
        let ring = hull::hull_offset(&loose, delta);
        let mut found = false;
        // Where the part lies on the hull, the first hull pass runs along the finishing pass:
        // its points within r + η of the part are within η of the finishing pass (they are
        // outside the part grown by r), so they are left out.
        let clips: &[(&RegionIndex, bool)] = if m == 0 {
            &[(clip_index, true), (&finish_zone, false)]
        } else {
            &[(clip_index, true)]
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
    // Neighbouring part levels are up to s + 2τ apart; a part level cut off at H is r from
    // the first hull pass.
    let ordered = order_pieces(pieces, (s + 2.0 * tol).max(r), opts.direction);
    let path = setup.link(ordered)?;
    Ok(MultiresPlan {
        path,
        report,
        loose_hull: loose,
    })
}

/// Fractional levels (distances to the part, mm) of the adaptive curves between two passes
/// whose crossings of a part normal lie at distances ≥ `from` (the inner pass's level minus
/// its deviation e₁) and ≤ `to` (the outer pass's level plus its deviation e₂) — seed 004
/// §3.5, eq. 3.3.
///
/// A point is swept when the pass crossing its normal on the part side lies within r, so the
/// gap G = to − from = s + e₁ + e₂ must not exceed L = max(r, s) (for s > r the baseline's own
/// passes are s apart; only the deviations are to be made up). Eq. 3.3 counts n = (e₁ + e₂)/r
/// curves for the seed's stepover s = r; in general n = ⌈(G − L)/(L − 2e_a)⌉ curves with a
/// band e_a of their own close the gap (n = ⌈(e₁ + e₂)/r⌉ for exact curves and s = r: eq. 3.3
/// rounded up): curve i at from + i·h − (2i − 1)·e_a with h = (G + 2n·e_a)/(n + 1) ≤ L, so
/// every step from the farthest-in crossing of one curve to the farthest-out crossing of the
/// next is h.
fn adaptive_levels(from: f64, to: f64, limit: f64, band: f64) -> Vec<f64> {
    let gap = to - from;
    let reach = limit - 2.0 * band;
    if !(gap > limit * (1.0 + 1e-9) && reach > 0.0) {
        return Vec::new();
    }
    let n = ((gap - limit) / reach).ceil().max(1.0);
    let h = (gap + 2.0 * n * band) / (n + 1.0);
    (1..=n as usize)
        .map(|i| from + i as f64 * h - (2 * i - 1) as f64 * band)
        .collect()
}

/// What computing the passes of one level needs.
struct LevelContext<'a> {
    /// The part as the offset engine sees it (thinned, see `Setup::offset_part`).
    offset_part: &'a Shape,
    r: f64,
    s: f64,
    opts: &'a MultiresOptions,
    part_index: &'a RegionIndex,
    clip_index: &'a RegionIndex,
    hull_clip: &'a RegionIndex,
}

impl LevelContext<'_> {
    /// The passes at distance `level` from the part: its exact offset loops, approximated
    /// within `band` (0 = exact), clipped to the stock and, with `to_hull`, to the loose hull;
    /// and the largest measured deviation e of the loops used from the exact offset.
    fn level_passes(
        &self,
        level: f64,
        band: f64,
        to_hull: bool,
        report: &mut MultiresReport,
    ) -> Result<(Vec<Pass>, f64)> {
        self.passes_from(
            offset_region(self.offset_part, level, "part")?,
            level,
            band,
            to_hull,
            report,
        )
    }

    /// The finishing passes: the part's offset loops at r, moved out by any shortfall of the
    /// offset engine so that none comes nearer the part than r (see
    /// [`offset_region_cleared`]), clipped to the stock only; and the distance used.
    fn finishing_passes(&self, report: &mut MultiresReport) -> Result<(Vec<Pass>, f64)> {
        let (loops, level) =
            offset_region_cleared(self.offset_part, self.part_index.boundary(), self.r, "part")?;
        let (passes, _) = self.passes_from(loops, level, 0.0, false, report)?;
        Ok((passes, level))
    }

    /// [`Self::level_passes`] on given exact offset loops at `level`.
    fn passes_from(
        &self,
        loops: Vec<Contour>,
        level: f64,
        band: f64,
        to_hull: bool,
        report: &mut MultiresReport,
    ) -> Result<(Vec<Pass>, f64)> {
        let mut passes = Vec::new();
        let mut e_max: f64 = 0.0;
        for exact in loops {
            let (used, e) = if band <= 0.0 {
                (exact.clone(), 0.0)
            } else {
                self.approximate_checked(&exact, level, band, report)
            };
            report.exact_segments += exact.vertices.len();
            report.used_segments += used.vertices.len();
            e_max = e_max.max(e);
            let clips: &[(&RegionIndex, bool)] = if to_hull {
                &[(self.clip_index, true), (self.hull_clip, true)]
            } else {
                &[(self.clip_index, true)]
            };
            passes.extend(clip_loop(&used, clips, level)?);
        }
        Ok((passes, e_max))
    }

    /// The wavelet approximation of the exact offset loop `exact` at `level` and its measured
    /// deviation from it, when it passes the exact band check; else `exact` and 0.
    fn approximate_checked(
        &self,
        exact: &Contour,
        level: f64,
        tol: f64,
        report: &mut MultiresReport,
    ) -> (Contour, f64) {
        let keep_exact = |report: &mut MultiresReport| {
            report.exact_fallbacks += 1;
            (exact.clone(), 0.0)
        };
        // A loop of a few lines and arcs is as simple as any approximation of it.
        if exact.vertices.len() <= MIN_SEGMENTS_TO_SIMPLIFY {
            return keep_exact(report);
        }
        // Sampling step: fine enough for the tolerance and for corners at the stepover's
        // scale.
        let step = (0.25 * self.s)
            .min(exact.length() / 64.0)
            .max(exact.length() / 20_000.0);
        let (approx, stats) = smooth::approximate_loop(exact, tol, step, &self.opts.corners);
        // Already simpler than any approximation (a few lines and arcs): keep it exact.
        if approx.vertices.len() >= exact.vertices.len() {
            return keep_exact(report);
        }
        report.corners += stats.corners;
        report.smooth_regions += stats.smooth_regions;
        report.non_smooth_regions += stats.non_smooth_regions;
        report.levels_dropped += stats.levels_dropped;
        let floor = self.r.max(level - tol) - 1e-9;
        let near_ok = approx.segments().all(|seg| {
            self.part_index
                .boundary()
                .nearest(&seg)
                .is_none_or(|n| n.distance >= floor)
        }) && approx
            .vertices
            .first()
            .is_some_and(|v| !self.part_index.contains(v.point));
        let same_turn = approx.signed_area().signum() == exact.signed_area().signum();
        let deviation = if near_ok && same_turn {
            deviation(&approx, exact, tol)
                .zip(deviation(exact, &approx, tol))
                .map(|(a, b)| a.max(b))
        } else {
            None
        };
        match deviation {
            Some(e) => {
                report.wavelet_loops += 1;
                (approx, e)
            }
            None => keep_exact(report),
        }
    }
}

/// The largest distance from a sample of `a` (every tol/4 of length) to `b`, when it is at
/// most `tol`.
fn deviation(a: &Contour, b: &Contour, tol: f64) -> Option<f64> {
    let bvh = SegmentBvh::new(b.segments().collect());
    let step = (0.25 * tol).max(a.length() / 200_000.0);
    let mut worst: f64 = 0.0;
    for (p, _) in sample_closed(a, step) {
        let d = bvh.nearest_point(p)?.distance;
        if d > tol {
            return None;
        }
        worst = worst.max(d);
    }
    Some(worst)
}

/// Distance r + k·s of level `k` from the part, refused past `max_levels` (absurd
/// stock/stepover ratios).
fn level_distance(k: usize, r: f64, s: f64, max_levels: usize) -> Result<f64> {
    if k > max_levels {
        return Err(ContourError::TooManyLevels {
            levels: max_levels,
            reached: r + k as f64 * s,
        });
    }
    Ok(r + k as f64 * s)
}

#[cfg(test)]
mod tests;
