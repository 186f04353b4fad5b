//! The classic contour-parallel baseline of issue #6 (the method seed 004 compares against in
//! Table 3.1 and Table 4.1): tool-centre passes are the EXACT offsets of the part boundary at
//! distances r, r + s, r + 2s, … (r = tool radius, s = stepover), made of lines and arcs by
//! `cavalier_contours`.
//!
//! # Variant (decided for this crate)
//!
//! Seed 004 (§1, Fig. 1.2; §3, step 5) machines "a complex 2D profile from rectangular stock …
//! similar to pocket machining with an island except that the wall effects are ignored", with the
//! offsets generated "progressively outwards" from the object. That is the variant used here:
//!
//! * level ℓₖ = r + k·s is the boundary of the part grown by ℓₖ (Minkowski sum with a disc). The
//!   part's holes are pockets: growing the part shrinks them, so the same offsets are the
//!   inward pocket passes — one rule for outer profiles and pockets;
//! * the stock boundary is not a wall (the tool may leave the stock), so each level is CLIPPED
//!   to the stock grown by r − ε (ε = [`CLIP_EPS`]): a centre farther than r from the stock cuts
//!   nothing, so clipping there removes only air cutting;
//! * levels continue until a level is entirely clipped away AND every stock contour's first
//!   vertex is nearer than ℓ to the part; then, the stock being connected to the part region,
//!   the whole stock lies within ℓ_last + s of the part.
//!
//! Coverage (proved in the crate docs of `verify`, checked by its tests): a point at distance t
//! from the part is swept by any level ℓ ∈ [t − r, t] (walk from the point straight to its
//! nearest part point: the distance drops at unit rate, and the first level crossed is a
//! boundary point of the grown part). So s ≤ r leaves no reachable material uncut on any part;
//! for a convex part (or a pocket's straight walls) levels in [t, t + r] also work and s ≤ 2r
//! suffices away from concave corners; larger s leaves the classic cusps in corners (measured
//! by [`crate::contour::verify::uncut_area`]). Material closer than r to the part that no disc outside
//! the part can reach (inside concave corners, slots narrower than 2r) stays uncut by any
//! method.
//!
//! # Ordering
//!
//! Passes are cut from the FAR side towards the part: a pass at level k may be cut only after
//! every pass at level k + 1 lying within s of it. For an outer profile that is outside-in
//! (conventional roughing: every pass engages a band of at most s with cleared air behind it,
//! the tool is never trapped, and the last pass at ℓ = r is the finishing contour); inside a
//! pocket the same rule goes centre-out, ending on the pocket wall. Among the passes allowed
//! next, the one with the nearest entry point is taken (greedy nearest neighbour; a closed pass
//! is entered at its point nearest to the tool). Passes run against the offset orientation,
//! the part on their right: the material a pass cuts lies between it and the part, so it is on
//! the cutter's right, where a clockwise (M3) cutter's teeth move against the feed — climb
//! milling (the cutter left of the wall, as G41). With
//! [`CutDirection::Mixed`] (the default) an open roughing pass — an offset loop cut off by the
//! stock — is entered at its nearer end instead: neighbouring fragments then join by a short
//! link at depth rather than by a retract, rapid and plunge each (zig-zag: half of them
//! conventional). Closed passes and the finishing passes (level r) always stay climb;
//! [`CutDirection::Climb`] keeps every pass climb.
//!
//! # Linking
//!
//! A link that stays at least r from the part (checked exactly) is made at cutting depth
//! when it is at most `max_feed_link` long ([`Link::Feed`]; default: the tool diameter, so it
//! engages at most a full-width slot), or when it runs through the air beside the stock —
//! r from the stock and within the band the passes already reach into ([`Link::Traverse`] at
//! the rapid rate; typically between fragments cut off at the same stock edge). Otherwise the
//! tool retracts, rapids and plunges ([`Link::Rapid`]).

use crate::contour::bvh::SegmentBvh;
use crate::contour::cavc::{offset_region, offset_region_cleared, validate_shape};
use crate::contour::error::{ContourError, Result, require_positive};
use crate::contour::geometry::{Contour, Point2, Segment, Shape, Vertex};
use crate::contour::region::RegionIndex;
use crate::contour::segops::{
    bbox, intersections, point_at, point_distance, segment_distance, sub_segment,
};
use crate::contour::simplify::{OUTLINE_THINNING_TOL, thin_shape};
use crate::contour::toolpath::{CenterPath, CutDirection, Link, Pass};

/// The stock is grown by r − `CLIP_EPS` for clipping: a level lying exactly r from the stock
/// (e.g. the first level of a part whose outline is the stock's) touches the stock in a line
/// and cuts nothing; shrinking the clip region by 10 nm keeps such passes out robustly.
pub const CLIP_EPS: f64 = 1e-5;

/// A feed link may pass this much closer than r to the part (round-off only).
const LINK_TOL: f64 = 1e-9;

/// Options of [`contour_parallel`].
#[derive(Clone, Debug, PartialEq)]
pub struct ParallelOptions {
    /// Flat end mill radius r, mm (> 0).
    pub tool_radius: f64,
    /// Stepover s between consecutive levels, mm (0 < s ≤ 2r). s ≤ r guarantees no reachable
    /// material is left; larger values leave cusps in concave corners.
    pub stepover: f64,
    /// Longest straight link made at cutting depth, mm; `None` = tool diameter 2r.
    pub max_feed_link: Option<f64>,
    /// Which way the roughing passes may run.
    pub direction: CutDirection,
    /// Upper bound on the number of offset levels (guards absurd stock/stepover ratios).
    pub max_levels: usize,
}

impl ParallelOptions {
    /// Options with tool radius `r` and stepover `s`, default link and level limits.
    pub fn new(tool_radius: f64, stepover: f64) -> Self {
        Self {
            tool_radius,
            stepover,
            max_feed_link: None,
            direction: CutDirection::default(),
            max_levels: 100_000,
        }
    }
}

/// A clipped level piece awaiting ordering: `level` counts outward from the part (0 = the
/// finishing level), consecutive levels at most one stepover apart.
pub(crate) struct Piece {
    pub(crate) level: usize,
    pub(crate) pass: Pass,
}

/// What both planners need first: validated options and shapes, the part index and the stock
/// clip region (the stock grown by r − [`CLIP_EPS`]).
pub(crate) struct Setup {
    pub(crate) r: f64,
    pub(crate) max_feed_link: f64,
    pub(crate) stock_index: RegionIndex,
    pub(crate) part_index: RegionIndex,
    pub(crate) clip_index: RegionIndex,
    /// The part as the offset engine sees it: thinned within [`OUTLINE_THINNING_TOL`]; paths
    /// are judged against `part_index`, the part as given.
    pub(crate) offset_part: Shape,
}

/// How far beyond the stock the passes are kept: r − [`CLIP_EPS`] (a centre farther than r from
/// the stock cuts nothing).
fn clip_distance(r: f64) -> f64 {
    (r - CLIP_EPS).max(0.5 * r)
}

pub(crate) fn setup(
    part: &Shape,
    stock: &Shape,
    r: f64,
    s: f64,
    max_feed_link: Option<f64>,
) -> Result<Setup> {
    require_positive("tool_radius", r, "must be a positive finite number of mm")?;
    if !(s.is_finite() && s > 0.0 && s <= 2.0 * r) {
        return Err(ContourError::InvalidOption {
            name: "stepover",
            value: s,
            reason: "must satisfy 0 < stepover ≤ 2 × tool_radius",
        });
    }
    let max_feed_link = max_feed_link.unwrap_or(2.0 * r);
    if max_feed_link.is_nan() || max_feed_link < 0.0 {
        return Err(ContourError::InvalidOption {
            name: "max_feed_link",
            value: max_feed_link,
            reason: "must be ≥ 0 mm",
        });
    }
    validate_shape(part, "part")?;
    validate_shape(stock, "stock")?;

    let part_index = RegionIndex::new(part);
    let clip = Shape {
        contours: offset_region(stock, clip_distance(r), "stock")?,
    };
    let clip_index = RegionIndex::new(&clip);

    Ok(Setup {
        r,
        max_feed_link,
        stock_index: RegionIndex::new(stock),
        part_index,
        clip_index,
        offset_part: thin_shape(part, OUTLINE_THINNING_TOL),
    })
}

/// Plans the contour-parallel path that removes `stock − part` (see the module docs for the
/// variant, ordering and linking).
pub fn contour_parallel(part: &Shape, stock: &Shape, opts: &ParallelOptions) -> Result<CenterPath> {
    let r = opts.tool_radius;
    let s = opts.stepover;
    let setup = setup(part, stock, r, s, opts.max_feed_link)?;
    let (part_index, clip_index) = (&setup.part_index, &setup.clip_index);
    let offset_part = &setup.offset_part;

    // Far bound of the stock from the part: every stock point is within `reach` of the part's
    // first vertex, hence of the part.
    let anchor = part.contours[0].vertices[0].point;
    let reach = stock
        .contours
        .iter()
        .flat_map(|c| c.segments())
        .map(|seg| match seg {
            Segment::Line { start, end } => (start - anchor).norm().max((end - anchor).norm()),
            Segment::Arc { center, radius, .. } => (center - anchor).norm() + radius,
        })
        .fold(0.0, f64::max);
    let k_max = ((reach / s).ceil() as usize).saturating_add(2);
    if k_max > opts.max_levels {
        return Err(ContourError::TooManyLevels {
            levels: opts.max_levels,
            reached: reach,
        });
    }
    let probes: Vec<Point2> = stock.contours.iter().map(|c| c.vertices[0].point).collect();

    let mut pieces: Vec<Piece> = Vec::new();
    for k in 0..=k_max {
        // The finishing level is measured and moved out by any shortfall of the offset
        // engine (see `offset_region_cleared`); the others may come inside their nominal
        // distance by as much without touching the part.
        let (loops, level) = if k == 0 {
            offset_region_cleared(offset_part, part_index.boundary(), r, "part")?
        } else {
            let level = r + k as f64 * s;
            (offset_region(offset_part, level, "part")?, level)
        };
        let mut found = false;
        for l in &loops {
            for pass in clip_loop(l, &[(clip_index, true)], level)? {
                found = true;
                pieces.push(Piece { level: k, pass });
            }
        }
        if !found
            && probes
                .iter()
                .all(|&p| part_index.signed_distance(p) < level)
        {
            break;
        }
    }
    let ordered = order_pieces(pieces, s, opts.direction);
    setup.link(ordered)
}

/// Splits a closed offset loop where it crosses the clip region's boundary and keeps the runs
/// inside (midpoint test). A loop entirely inside stays one closed pass.
/// With several clip regions `(region, keep_inside)`, the runs inside every region marked
/// `true` and outside every region marked `false` are kept.
pub(crate) fn clip_loop(
    c: &Contour,
    clips: &[(&RegionIndex, bool)],
    offset: f64,
) -> Result<Vec<Pass>> {
    let segs: Vec<Segment> = c.segments().collect();
    // (segment index, t0, t1) pieces in loop order.
    let mut parts: Vec<(usize, f64, f64)> = Vec::new();
    for (i, seg) in segs.iter().enumerate() {
        let mut ts: Vec<f64> = Vec::new();
        for (clip, _) in clips {
            let clip_segs = clip.boundary().segments();
            for j in clip.boundary().candidates_near(&bbox(seg), 0.0) {
                for h in intersections(seg, &clip_segs[j]) {
                    if h.ta > 1e-12 && h.ta < 1.0 - 1e-12 {
                        ts.push(h.ta);
                    }
                }
            }
        }
        ts.sort_by(f64::total_cmp);
        ts.dedup_by(|a, b| (*a - *b).abs() <= 1e-12);
        let mut prev = 0.0;
        for t in ts.into_iter().chain(std::iter::once(1.0)) {
            parts.push((i, prev, t));
            prev = t;
        }
    }
    let inside: Vec<bool> = parts
        .iter()
        .map(|&(i, t0, t1)| {
            let mid = point_at(&segs[i], 0.5 * (t0 + t1));
            clips
                .iter()
                .all(|(clip, inside)| clip.contains(mid) == *inside)
        })
        .collect();
    if inside.iter().all(|&b| b) {
        return Ok(vec![Pass::closed(c.vertices.clone(), offset)?]);
    }
    let Some(first_out) = inside.iter().position(|&b| !b) else {
        return Ok(Vec::new());
    };
    let n = parts.len();
    let mut out = Vec::new();
    let mut run: Vec<(usize, f64, f64)> = Vec::new();
    for step in 1..=n {
        let idx = (first_out + step) % n;
        if inside[idx] {
            run.push(parts[idx]);
        }
        if (!inside[idx] || step == n) && !run.is_empty() {
            out.push(run_to_pass(&segs, &run, offset)?);
            run.clear();
        }
    }
    Ok(out)
}

fn run_to_pass(segs: &[Segment], run: &[(usize, f64, f64)], offset: f64) -> Result<Pass> {
    let mut vertices = Vec::with_capacity(run.len() + 1);
    let mut last = None;
    for &(i, t0, t1) in run {
        let (a, b, bulge) = sub_segment(&segs[i], t0, t1);
        vertices.push(Vertex { point: a, bulge });
        last = Some(b);
    }
    if let Some(b) = last {
        vertices.push(Vertex {
            point: b,
            bulge: 0.0,
        });
    }
    Pass::open(vertices, offset)
}

/// Orders pieces far-side first (a piece waits for every piece of a farther level within s of
/// it), nearest entry next; closed passes are re-started at their point nearest to the tool,
/// and with [`CutDirection::Mixed`] open roughing pieces (level > 0) are entered at their
/// nearer end. The pieces come as offsets, the part on their left; they leave climb, the part
/// on their right.
pub(crate) fn order_pieces(pieces: Vec<Piece>, s: f64, direction: CutDirection) -> Vec<Pass> {
    let n = pieces.len();
    if n == 0 {
        return Vec::new();
    }
    // Far side first, the material a pass cuts lies between it and the part: the part on the
    // right of the travel puts the material on the cutter's right, where a clockwise (M3)
    // cutter's teeth move against the feed — climb milling.
    let pieces: Vec<Piece> = pieces
        .into_iter()
        .map(|p| Piece {
            level: p.level,
            pass: p.pass.reversed(),
        })
        .collect();
    let max_level = pieces.iter().map(|p| p.level).max().unwrap_or(0);
    // One BVH per level over that level's pass segments, remembering the owning piece.
    let mut level_owner: Vec<Vec<usize>> = vec![Vec::new(); max_level + 1];
    let mut level_bvh: Vec<SegmentBvh> = Vec::with_capacity(max_level + 1);
    for (lv, owners) in level_owner.iter_mut().enumerate() {
        let mut segs = Vec::new();
        for (pi, p) in pieces.iter().enumerate().filter(|(_, p)| p.level == lv) {
            for seg in p.pass.segments() {
                segs.push(seg);
                owners.push(pi);
            }
        }
        level_bvh.push(SegmentBvh::new(segs));
    }
    let thr = s * (1.0 + 1e-6) + 1e-6;
    let mut children: Vec<Vec<usize>> = vec![Vec::new(); n];
    let mut pending = vec![0usize; n];
    for (pi, p) in pieces.iter().enumerate() {
        // Every farther level, not only the next: where a level is cut off (by the stock, or
        // by the hull in the multiresolution paths) the next pass outward can be a level or
        // more farther out, and its material must still go first.
        let mut parents: Vec<usize> = Vec::new();
        for (up, owners) in level_bvh.iter().zip(&level_owner).skip(p.level + 1) {
            for seg in p.pass.segments() {
                for j in up.candidates_near(&bbox(&seg), thr) {
                    let owner = owners[j];
                    if !parents.contains(&owner)
                        && segment_distance(&seg, &up.segments()[j]).0 <= thr
                    {
                        parents.push(owner);
                    }
                }
            }
        }
        pending[pi] = parents.len();
        for q in parents {
            children[q].push(pi);
        }
    }

    let piece_level: Vec<usize> = pieces.iter().map(|p| p.level).collect();
    let mixed = direction == CutDirection::Mixed;
    let mut done = vec![false; n];
    let mut passes: Vec<Option<Pass>> = pieces.into_iter().map(|p| Some(p.pass)).collect();
    let mut order = Vec::with_capacity(n);
    let mut current: Option<Point2> = None;
    for _ in 0..n {
        // (key, piece, where to enter it)
        type Choice = (f64, usize, Entry);
        let mut best: Option<Choice> = None;
        for i in (0..n).filter(|&i| !done[i] && pending[i] == 0) {
            let Some(pass) = passes[i].as_ref() else {
                continue;
            };
            let reversible = mixed && piece_level[i] > 0;
            let (key, entry) = match current {
                // First pass: the farthest level, lowest index.
                None => (-(piece_level[i] as f64), Entry::Start),
                Some(pos) => entry_point(pass, pos, reversible),
            };
            if best.as_ref().is_none_or(|b| key < b.0) {
                best = Some((key, i, entry));
            }
        }
        let Some((_, i, entry)) = best else { break };
        done[i] = true;
        for &c in &children[i] {
            pending[c] -= 1;
        }
        let Some(mut pass) = passes[i].take() else {
            break;
        };
        match entry {
            Entry::Start => {}
            Entry::End => pass = pass.reversed(),
            Entry::Closed { segment, t } => pass = restart_closed(&pass, segment, t),
        }
        current = Some(pass.end());
        order.push(pass);
    }
    order
}

/// Where the tool enters a pass.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Entry {
    /// At its start, as planned.
    Start,
    /// At its end: the open pass is cut backwards.
    End,
    /// A closed pass, at parameter `t` of segment `segment`.
    Closed { segment: usize, t: f64 },
}

/// Distance from `pos` to where the tool would enter `pass`, and that entry; an open pass is
/// entered at its nearer end when `reversible`.
fn entry_point(pass: &Pass, pos: Point2, reversible: bool) -> (f64, Entry) {
    if !pass.is_closed() {
        let (to_start, to_end) = ((pass.start() - pos).norm(), (pass.end() - pos).norm());
        return if reversible && to_end < to_start {
            (to_end, Entry::End)
        } else {
            (to_start, Entry::Start)
        };
    }
    let mut best = (f64::INFINITY, 0usize, Point2::origin());
    for (i, seg) in pass.segments().enumerate() {
        let (d, q) = point_distance(pos, &seg);
        if d < best.0 {
            best = (d, i, q);
        }
    }
    let segs: Vec<Segment> = pass.segments().collect();
    let t = crate::contour::segops::param_on(&segs[best.1], best.2);
    (best.0, Entry::Closed { segment: best.1, t })
}

/// The closed pass re-started at parameter `t` of segment `seg`.
fn restart_closed(pass: &Pass, seg: usize, t: f64) -> Pass {
    let v = pass.vertices();
    let n = v.len();
    let segs: Vec<Segment> = pass.segments().collect();
    // Snap near-vertex entries so no sliver segment is created.
    let len = segs[seg].length();
    let (seg, t) = if t * len <= 1e-9 {
        (seg, 0.0)
    } else if (1.0 - t) * len <= 1e-9 {
        ((seg + 1) % n, 0.0)
    } else {
        (seg, t)
    };
    let mut out = Vec::with_capacity(n + 1);
    if t == 0.0 {
        out.extend((0..n).map(|j| v[(seg + j) % n]));
    } else {
        let (q, _, tail_bulge) = sub_segment(&segs[seg], t, 1.0);
        let (_, _, head_bulge) = sub_segment(&segs[seg], 0.0, t);
        out.push(Vertex {
            point: q,
            bulge: tail_bulge,
        });
        out.extend((1..n).map(|j| v[(seg + j) % n]));
        out.push(Vertex {
            point: v[seg].point,
            bulge: head_bulge,
        });
    }
    // A re-started copy of a valid closed pass is valid.
    Pass::closed(out, pass.offset()).unwrap_or_else(|_| pass.clone())
}

impl Setup {
    /// Whether the straight move `seg` cuts nothing and goes nowhere the passes do not. It
    /// keeps [`clip_distance`] − [`CLIP_EPS`] from the stock with its midpoint outside (exact:
    /// the tool reaches at most 20 nm into the stock), and no sample of it every
    /// `clip_distance`/8 is farther than `clip_distance` + `clip_distance`/16 from the stock
    /// (the distance is 1-Lipschitz, so the move stays within `clip_distance`/8 of the band the
    /// passes use), so fixtures clear of the passes are clear of it too.
    fn in_air_beside_the_stock(&self, seg: &Segment) -> bool {
        let reach = clip_distance(self.r);
        let off_stock = !self.stock_index.contains(point_at(seg, 0.5))
            && self
                .stock_index
                .boundary()
                .nearest(seg)
                .is_none_or(|n| n.distance >= reach - CLIP_EPS);
        if !off_stock {
            return false;
        }
        let step = reach / 8.0;
        let n = ((seg.length() / step).ceil() as usize).max(1);
        (0..=n).all(|k| {
            self.stock_index
                .boundary_distance(point_at(seg, k as f64 / n as f64))
                <= reach + 0.5 * step
        })
    }

    /// Joins ordered passes. A link that keeps r from the part (exact) stays at cutting depth
    /// when it is at most `max_feed_link` long (a [`Link::Feed`]: a step-over move, engaging at
    /// most a full-width slot for that short distance), or when it runs through the air beside
    /// the stock within the passes' band ([`Self::in_air_beside_the_stock`]): a
    /// [`Link::Traverse`] at the rapid rate, of any length — one NC block instead of a retract,
    /// a rapid and a plunge. Otherwise the tool retracts, rapids and plunges.
    pub(crate) fn link(&self, passes: Vec<Pass>) -> Result<CenterPath> {
        let r = self.r;
        let links = passes
            .windows(2)
            .map(|w| {
                let (from, to) = (w[0].end(), w[1].start());
                let seg = Segment::Line {
                    start: from,
                    end: to,
                };
                let clear = !self.part_index.contains(from)
                    && self
                        .part_index
                        .boundary()
                        .nearest(&seg)
                        .is_none_or(|n| n.distance >= r - LINK_TOL);
                if !clear {
                    Link::Rapid { from, to }
                } else if (to - from).norm() <= self.max_feed_link {
                    Link::Feed { from, to }
                } else if self.in_air_beside_the_stock(&seg) {
                    Link::Traverse { from, to }
                } else {
                    Link::Rapid { from, to }
                }
            })
            .collect();
        CenterPath::new(r, passes, links)
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use std::f64::consts::PI;

    pub(crate) fn circle(cx: f64, cy: f64, r: f64, ccw: bool) -> Contour {
        let b = if ccw { 1.0 } else { -1.0 };
        Contour {
            vertices: vec![
                Vertex {
                    point: Point2::new(cx + r, cy),
                    bulge: b,
                },
                Vertex {
                    point: Point2::new(cx - r, cy),
                    bulge: b,
                },
            ],
        }
    }

    /// Axis-aligned rectangle, counter-clockwise (or clockwise for a hole).
    pub(crate) fn rect(x0: f64, y0: f64, x1: f64, y1: f64, ccw: bool) -> Contour {
        let mut v = vec![
            Vertex::line(x0, y0),
            Vertex::line(x1, y0),
            Vertex::line(x1, y1),
            Vertex::line(x0, y1),
        ];
        if !ccw {
            v.reverse();
        }
        Contour { vertices: v }
    }

    /// A disc of `radius` round the origin (the part) in the square stock of half-side
    /// `half_side`.
    pub(crate) fn disc_in_square(radius: f64, half_side: f64) -> (Shape, Shape) {
        (
            Shape {
                contours: vec![circle(0.0, 0.0, radius, true)],
            },
            Shape {
                contours: vec![rect(-half_side, -half_side, half_side, half_side, true)],
            },
        )
    }

    /// Ordering invariant: a pass is never cut before a pass one level farther out lying within
    /// s of it (the material between them must be cleared from the far side).
    pub(crate) fn assert_far_side_first(path: &CenterPath, s: f64) {
        let passes = path.passes();
        for (i, a) in passes.iter().enumerate() {
            for b in &passes[i + 1..] {
                if b.offset() <= a.offset() {
                    continue;
                }
                let near = a
                    .segments()
                    .any(|x| b.segments().any(|y| segment_distance(&x, &y).0 <= s + 1e-6));
                assert!(
                    !near,
                    "pass at {} cut before the neighbouring pass at {}",
                    a.offset(),
                    b.offset()
                );
            }
        }
    }

    #[test]
    fn circle_in_square_levels_are_concentric_circles() {
        let (part, stock) = disc_in_square(20.0, 30.0);
        let path = contour_parallel(&part, &stock, &ParallelOptions::new(3.0, 4.0)).expect("plan");
        let mut offsets: Vec<f64> = path.passes().iter().map(|p| p.offset()).collect();
        offsets.dedup();
        // Levels 3, 7, …, 23: the stock corner is 30√2 − 20 ≈ 22.43 from the part, so the level
        // 23 (within r of it) is the last one needed; level 27 lies outside the stock + r.
        offsets.sort_by(f64::total_cmp);
        offsets.dedup();
        assert_eq!(offsets, vec![3.0, 7.0, 11.0, 15.0, 19.0, 23.0]);
        for p in path.passes() {
            for seg in p.segments() {
                let Segment::Arc { center, radius, .. } = seg else {
                    panic!("line in a circle offset")
                };
                assert!(center.coords.norm() < 1e-9);
                assert!((radius - 20.0 - p.offset()).abs() < 1e-9);
            }
        }
        assert_far_side_first(&path, 4.0);
        // Corner by corner (23, 19, 15 — clipped, each ending on the stock + r boundary, so
        // traverses through the air beside the stock in between), then the three full circles
        // joined by 4 mm feed links.
        let offs: Vec<f64> = path.passes().iter().map(|p| p.offset()).collect();
        assert_eq!(&offs[..3], &[23.0, 19.0, 15.0]);
        assert_eq!(&offs[12..], &[11.0, 7.0, 3.0]);
        let st = crate::contour::verify::path_stats(&path);
        assert_eq!(
            (st.passes, st.feed_links, st.traverse_links, st.rapid_links),
            (15, 3, 11, 0)
        );
        // Each traverse keeps r from the stock (less 2e-5 mm) and stays within r + r/8 of it,
        // checked densely and independently of the planner's own test.
        let stock_index = RegionIndex::new(&stock);
        for l in path.links() {
            let Link::Traverse { from, to } = *l else {
                continue;
            };
            for k in 0..=1000 {
                let p = from + (to - from) * (k as f64 / 1000.0);
                assert!(!stock_index.contains(p));
                let d = stock_index.boundary_distance(p);
                assert!((3.0 - 2e-5..=3.0 + 3.0 / 8.0).contains(&d), "{d} at {p:?}");
            }
        }
        // The last pass is the full finishing circle at r.
        let last = path.passes().last().expect("passes");
        assert!(last.is_closed() && last.offset() == 3.0);
        assert!((last.length() - 2.0 * PI * 23.0).abs() < 1e-9);
    }

    /// Zig-zag roughing: the same passes as climb-only, some cut backwards, far side still
    /// first, the finishing circle still climb (part on its right), and the corner fragments
    /// joined at depth where climb-only retracts between them.
    #[test]
    fn mixed_direction_reverses_only_open_roughing_passes() {
        let (part, stock) = disc_in_square(20.0, 32.0);
        let plan = |direction| {
            let opts = ParallelOptions {
                direction,
                ..ParallelOptions::new(3.0, 2.4)
            };
            contour_parallel(&part, &stock, &opts).expect("plan")
        };
        let (climb, mixed) = (plan(CutDirection::Climb), plan(CutDirection::Mixed));
        assert_far_side_first(&mixed, 2.4);
        let (cs, ms) = (
            crate::contour::verify::path_stats(&climb),
            crate::contour::verify::path_stats(&mixed),
        );
        assert_eq!(cs.passes, ms.passes);
        assert!((cs.cut_length - ms.cut_length).abs() < 1e-9);
        assert!(
            ms.rapid_links < cs.rapid_links,
            "mixed {} vs climb {} rapid links",
            ms.rapid_links,
            cs.rapid_links
        );
        let mut reversed = 0;
        for p in mixed.passes() {
            if p.is_closed() {
                // Re-started wherever the tool is, but still clockwise round the part.
                let area = Contour {
                    vertices: p.vertices().to_vec(),
                }
                .signed_area();
                assert!(area < 0.0, "closed pass reversed: {p:?}");
                continue;
            }
            let matches = |a: &Pass| {
                climb.passes().iter().any(|q| {
                    (q.start() - a.start()).norm() < 1e-12
                        && (q.end() - a.end()).norm() < 1e-12
                        && (q.length() - a.length()).abs() < 1e-9
                })
            };
            if matches(p) {
                continue;
            }
            assert!(matches(&p.reversed()), "not a climb pass either way: {p:?}");
            assert!(p.offset() > 3.0, "a finishing pass was reversed: {p:?}");
            reversed += 1;
        }
        assert!(reversed > 0);
        // Climb means the part on the right: the finishing circle runs clockwise about the
        // disc's centre.
        for p in mixed.passes().iter().filter(|p| p.offset() == 3.0) {
            for seg in p.segments() {
                let Segment::Arc { center, sweep, .. } = seg else {
                    panic!("line in a circle offset")
                };
                assert!(center.coords.norm() < 1e-9 && sweep < 0.0, "{seg:?}");
            }
        }
    }

    #[test]
    fn options_are_validated() {
        let (part, stock) = disc_in_square(5.0, 10.0);
        let e = contour_parallel(&part, &stock, &ParallelOptions::new(1.0, 2.5)).unwrap_err();
        assert!(e.to_string().contains("stepover"), "{e}");
        let e = contour_parallel(&part, &stock, &ParallelOptions::new(-1.0, 0.5)).unwrap_err();
        assert!(e.to_string().contains("tool_radius"), "{e}");
        let e = contour_parallel(&Shape::default(), &stock, &ParallelOptions::new(1.0, 1.0))
            .unwrap_err();
        assert_eq!(e.to_string(), "part: the shape has no contours");
        let mut o = ParallelOptions::new(0.001, 0.001);
        o.max_levels = 100;
        assert!(matches!(
            contour_parallel(&part, &stock, &o),
            Err(ContourError::TooManyLevels { .. })
        ));
    }

    #[test]
    fn closed_pass_restart_preserves_geometry() {
        let pass = Pass::closed(circle(0.0, 0.0, 2.0, true).vertices, 1.0).expect("pass");
        let (d, entry) = entry_point(&pass, Point2::new(0.0, 5.0), true);
        assert!((d - 3.0).abs() < 1e-12);
        let Entry::Closed { segment, t } = entry else {
            panic!("a closed pass is entered on its loop: {entry:?}")
        };
        let re = restart_closed(&pass, segment, t);
        assert!((re.start() - Point2::new(0.0, 2.0)).norm() < 1e-12);
        assert!((re.length() - pass.length()).abs() < 1e-12);
        assert_eq!(re.segment_count(), 3);
        let area: f64 = Contour {
            vertices: re.vertices().to_vec(),
        }
        .signed_area();
        assert!((area - 4.0 * PI).abs() < 1e-12);
    }
}
