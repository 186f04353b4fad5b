//! A run of moves applied to the models in one parallel sweep over their lines.
//!
//! Removing one move's solids at a time, in parallel over the lines they cross, spends more on
//! scheduling than on geometry: a finishing move crosses a few thousand lines, a fraction of a
//! millisecond of work. Instead the lines are dealt into a fixed number of stripes (row `j` of
//! every grid goes to stripe `j mod STRIPES`), and each stripe runs the whole batch of moves in
//! program order on its own rows. A line's result depends only on the solids that cross it, in
//! order, so every line ends exactly as if the moves had been applied one after another; each
//! move's sums are added stripe by stripe in stripe order, so the numbers do not depend on the
//! thread count either.
//!
//! Per move, in order, on each stripe: the cutting solids come off the stock; the gouge solids
//! come off the part model (the ends of what they take are kept, to measure the gouge); then
//! the bodies that must not cut are checked against the stock's material left after the cut.

use rayon::prelude::*;

use super::sweep::{Frustum, LineInterval, SphereSweptHull};
use super::{DexelGrid, Stock, Touch, spans};
use crate::geom::Point3;
use spans::Spans;

/// Stripes the lines are dealt into: enough for two to eight threads to share evenly, few
/// enough that each stripe's share of a move is more than its bookkeeping.
const STRIPES: usize = 16;

/// Lines per side of a tile: the extent of the material over each tile's lines is taken at
/// the start of a batch, and a row's lines are dismissed a tile at a time when a solid's
/// extent over them misses it (material only shrinks, so the extent stays a bound).
const TILE: usize = 8;

/// Moves per batch: their solids are built before the batch runs, so this bounds the memory
/// they take (a few kB a move) and how often the stripes meet.
pub const BATCH: usize = 4096;

/// 1 nm: below it an interval is round-off, not material (f64 resolves 1e-14 mm at 100 mm).
const MIN_SPAN: f64 = 1e-6;

/// What one move asks of the models.
#[derive(Clone, Debug)]
pub struct MoveWork<S> {
    /// Solids removed from the stock.
    pub cut: Vec<S>,
    /// Solids removed from the part model; what they take is a gouge.
    pub gouge: Vec<S>,
    /// Bodies that must not touch the stock's material.
    pub guards: Vec<Guard>,
    /// The tool's frame at the move's end, to measure the depths of cut in: the tip, the
    /// axis, and the side direction (across the feed and the axis).
    pub frame: Option<CutFrame>,
}

/// A body that must not touch material, over one move: frusta that together hold it at every
/// pose of the move, and one convex cover holding them all. The cover is tested first: most
/// moves keep their shank and holder clear of material, and then one test on a stripe's rows
/// stands for all the frusta.
#[derive(Clone, Debug)]
pub struct Guard {
    /// What the caller groups the touches by (the outcome's `touches[index]`).
    pub index: usize,
    /// Holds every frustum.
    pub cover: SphereSweptHull,
    pub frusta: Vec<Frustum>,
}

/// Where depths of cut are measured from: a point and two unit directions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CutFrame {
    pub tip: Point3,
    pub axis: crate::geom::Vector3,
    pub side: crate::geom::Vector3,
}

/// The extent of the material a move removed, in its [`CutFrame`]: along the axis (the axial
/// depth of cut) and along the side direction (the radial width of cut), `(min, max)` each.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CutExtent {
    pub axial: (f64, f64),
    pub side: (f64, f64),
}

impl CutExtent {
    fn grow(extent: &mut Option<CutExtent>, frame: &CutFrame, q: &Point3) {
        let d = q - frame.tip;
        let (h, s) = (d.dot(&frame.axis), d.dot(&frame.side));
        let e = extent.get_or_insert(CutExtent {
            axial: (h, h),
            side: (s, s),
        });
        e.axial = (e.axial.0.min(h), e.axial.1.max(h));
        e.side = (e.side.0.min(s), e.side.1.max(s));
    }

    fn merge(extent: &mut Option<CutExtent>, other: Option<CutExtent>) {
        if let Some(o) = other {
            let e = extent.get_or_insert(o);
            e.axial = (e.axial.0.min(o.axial.0), e.axial.1.max(o.axial.1));
            e.side = (e.side.0.min(o.side.0), e.side.1.max(o.side.1));
        }
    }

    /// Axial depth of cut, mm.
    pub fn axial_depth(&self) -> f64 {
        self.axial.1 - self.axial.0
    }

    /// Radial width of cut, mm.
    pub fn radial_width(&self) -> f64 {
        self.side.1 - self.side.0
    }
}

impl<S> Default for MoveWork<S> {
    fn default() -> Self {
        MoveWork {
            cut: Vec::new(),
            gouge: Vec::new(),
            guards: Vec::new(),
            frame: None,
        }
    }
}

/// What one move did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MoveOutcome {
    /// Stock volume removed, mm³ (the mean of the three grids).
    pub removed_mm3: f64,
    /// Part volume removed, mm³.
    pub gouge_mm3: f64,
    /// Ends of the part material removed (points on the gouge solids inside the part).
    pub gouge_ends: Vec<Point3>,
    /// The deepest touch of each guard index, by index (`guard_count` entries).
    pub touches: Vec<Option<Touch>>,
    /// The extent of the stock removed, in the move's frame (when it has one and removed
    /// anything).
    pub extent: Option<CutExtent>,
}

/// The extent of material along the lines of each tile of a grid, `(min, max)` (`min > max`
/// for a tile without material).
struct Tiles {
    across: usize,
    extents: Vec<(f64, f64)>,
}

impl Tiles {
    fn of(grid: &DexelGrid) -> Self {
        let [n0, n1] = grid.counts;
        let (across, down) = (n0.div_ceil(TILE), n1.div_ceil(TILE));
        let extents = (0..across * down)
            .into_par_iter()
            .map(|t| {
                let (ti, tj) = (t % across, t / across);
                let mut extent = (f64::INFINITY, f64::NEG_INFINITY);
                for j in tj * TILE..((tj + 1) * TILE).min(n1) {
                    for line in &grid.lines[j * n0 + ti * TILE..j * n0 + ((ti + 1) * TILE).min(n0)]
                    {
                        if let (Some(first), Some(last)) = (line.first(), line.last()) {
                            extent.0 = extent.0.min(first.start);
                            extent.1 = extent.1.max(last.end);
                        }
                    }
                }
                extent
            })
            .collect();
        Tiles { across, extents }
    }
}

/// The rows of one grid that belong to one stripe.
struct Rows<'a> {
    tiles: &'a Tiles,
    axis: usize,
    across: [usize; 2],
    origin: [f64; 2],
    counts: [usize; 2],
    spacing: f64,
    stripe: usize,
    /// Row `stripe + STRIPES·m` at `rows[m]`.
    rows: Vec<&'a mut [Spans]>,
}

impl<'a> Rows<'a> {
    /// Every grid's rows dealt into the stripes.
    fn deal(grids: &'a mut [DexelGrid; 3], tiles: &'a [Tiles; 3]) -> Vec<[Rows<'a>; 3]> {
        let mut stripes: Vec<Vec<Rows<'a>>> = (0..STRIPES).map(|_| Vec::new()).collect();
        for (grid, tiles) in grids.iter_mut().zip(tiles) {
            let mut per_stripe: Vec<Rows<'a>> = (0..STRIPES)
                .map(|stripe| Rows {
                    tiles,
                    axis: grid.axis,
                    across: grid.across,
                    origin: grid.origin,
                    counts: grid.counts,
                    spacing: grid.spacing,
                    stripe,
                    rows: Vec::new(),
                })
                .collect();
            for (j, row) in grid.lines.chunks_mut(grid.counts[0]).enumerate() {
                per_stripe[j % STRIPES].rows.push(row);
            }
            for (stripe, rows) in per_stripe.into_iter().enumerate() {
                stripes[stripe].push(rows);
            }
        }
        stripes
            .into_iter()
            .map(|grids| {
                <[Rows<'a>; 3]>::try_from(grids).unwrap_or_else(|_| unreachable!("three grids"))
            })
            .collect()
    }

    /// Index range of lines whose `across[k]` coordinate lies in `[lo, hi]`.
    fn index_range(&self, k: usize, lo: f64, hi: f64) -> std::ops::Range<usize> {
        super::lattice_range(self.origin[k], self.spacing, self.counts[k], lo, hi)
    }

    /// This stripe's rows with `j` in `range`: `(j, m)` pairs.
    fn rows_in(
        &self,
        range: std::ops::Range<usize>,
    ) -> impl Iterator<Item = (usize, usize)> + use<> {
        let first = range.start.saturating_sub(self.stripe).div_ceil(STRIPES);
        let (stripe, count) = (self.stripe, self.rows.len());
        (first..count)
            .map(move |m| (stripe + STRIPES * m, m))
            .take_while(move |&(j, _)| j < range.end)
    }

    /// The line point of `(i, j)`, its own coordinate 0. Always inlined: it runs once per
    /// line a body's bounds cover, and the tests' opt-level 1 left it a call.
    #[inline(always)]
    fn point(&self, i: usize, j: usize) -> Point3 {
        let mut p = Point3::origin();
        p[self.across[0]] = self.origin[0] + i as f64 * self.spacing;
        p[self.across[1]] = self.origin[1] + j as f64 * self.spacing;
        p
    }

    /// The lines of row `j` a solid's row range covers.
    fn columns(&self, solid: &dyn LineInterval, j: usize) -> std::ops::Range<usize> {
        let mut on_row = Point3::origin();
        on_row[self.across[1]] = self.origin[1] + j as f64 * self.spacing;
        match solid.row_range(self.axis, self.across[0], &on_row) {
            Some((lo, hi)) => self.index_range(0, lo, hi),
            None => 0..0,
        }
    }

    /// Removes `solid` from these rows; the length of material removed. With `ends`, the
    /// ends of every removed piece are pushed onto it.
    fn remove(&mut self, solid: &dyn LineInterval, ends: &mut dyn FnMut(Point3)) -> f64 {
        let b = solid.bounds();
        let (axis, across) = (self.axis, self.across);
        let is = self.index_range(0, b.min[across[0]], b.max[across[0]]);
        let js = self.index_range(1, b.min[across[1]], b.max[across[1]]);
        if is.is_empty() || js.is_empty() {
            return 0.0;
        }
        let mut length = 0.0;
        for (j, m) in self.rows_in(js) {
            // The tiles first, over the box's columns; the solid's outline on the row (a few
            // 2D capsules) only when one of them may hold something to remove.
            let mut columns: Option<std::ops::Range<usize>> = None;
            let mut i = is.start;
            while i < is.end {
                let segment = i..((i / TILE + 1) * TILE).min(is.end);
                i = segment.end;
                if !self.may_meet(solid, j, &segment) {
                    continue;
                }
                let outline = columns.get_or_insert_with(|| self.columns(solid, j));
                let segment = segment.start.max(outline.start)..segment.end.min(outline.end);
                for i in segment {
                    let line = &mut self.rows[m][i];
                    if line.is_empty() {
                        continue;
                    }
                    let mut p = Point3::origin();
                    p[across[0]] = self.origin[0] + i as f64 * self.spacing;
                    p[across[1]] = self.origin[1] + j as f64 * self.spacing;
                    // A cheap bound first: most lines under a finishing tool hold material
                    // only where the solid cannot be.
                    let Some((lo, hi)) = solid.range_over(axis, &p, &p) else {
                        continue;
                    };
                    if !line.iter().any(|s| s.end > lo && s.start < hi) {
                        continue;
                    }
                    if let Some((t0, t1)) = solid.line_interval(axis, &p) {
                        length += spans::subtract_recording(line, t0, t1, MIN_SPAN, &mut |a, b| {
                            for t in [a, b] {
                                let mut q = p;
                                q[axis] = t;
                                ends(q);
                            }
                        });
                    }
                }
            }
        }
        length
    }

    /// Whether `solid` may meet material on the lines `columns` of row `j` (all in one tile):
    /// the solid's extent over them against the tile's material.
    fn may_meet(
        &self,
        solid: &dyn LineInterval,
        j: usize,
        columns: &std::ops::Range<usize>,
    ) -> bool {
        let (lo, hi) = self.tiles.extents[columns.start / TILE + self.tiles.across * (j / TILE)];
        if lo > hi {
            return false;
        }
        let (a, b) = (self.point(columns.start, j), self.point(columns.end - 1, j));
        solid
            .range_over(self.axis, &a, &b)
            .is_some_and(|(t0, t1)| t0 < hi && t1 > lo)
    }

    /// The lines `(i, j, m)` (the `m`-th row here) under `solid`'s box, a tile at a time,
    /// leaving out the tiles whose material its extent over them misses.
    fn lines_near<'s>(
        &'s self,
        solid: &'s dyn LineInterval,
    ) -> impl Iterator<Item = (usize, usize, usize)> + 's {
        let b = solid.bounds();
        let is = self.index_range(0, b.min[self.across[0]], b.max[self.across[0]]);
        let js = self.index_range(1, b.min[self.across[1]], b.max[self.across[1]]);
        let tiles = if is.is_empty() {
            0..0
        } else {
            is.start / TILE..(is.end - 1) / TILE + 1
        };
        self.rows_in(js).flat_map(move |(j, m)| {
            let is = is.clone();
            tiles
                .clone()
                .map(move |t| (t * TILE).max(is.start)..((t + 1) * TILE).min(is.end))
                .filter(move |segment| self.may_meet(solid, j, segment))
                .flat_map(move |segment| segment.map(move |i| (i, j, m)))
        })
    }

    /// Whether any material on these rows lies inside `solid` (by more than round-off).
    fn meets(&self, solid: &dyn LineInterval) -> bool {
        let axis = self.axis;
        self.lines_near(solid).any(|(i, j, m)| {
            let line = &self.rows[m][i];
            if line.is_empty() {
                return false;
            }
            let p = self.point(i, j);
            let Some((lo, hi)) = solid.range_over(axis, &p, &p) else {
                return false;
            };
            line.iter().any(|s| s.end > lo && s.start < hi)
                && solid.line_interval(axis, &p).is_some_and(|(t0, t1)| {
                    line.iter()
                        .any(|s| s.end.min(t1) - s.start.max(t0) > MIN_SPAN)
                })
        })
    }

    /// The deepest material inside `frustum` on these rows (see [`Stock::touching`]).
    fn touching(&self, frustum: &Frustum) -> Option<Touch> {
        let b = frustum.bounds();
        let mut best: Option<Touch> = None;
        for (i, j, m) in self.lines_near(frustum) {
            self.touch_line(frustum, &b, i, j, m, &mut best);
        }
        best
    }

    /// [`Self::touching`] on line `(i, j)`, the `m`-th row here.
    fn touch_line(
        &self,
        frustum: &Frustum,
        b: &crate::geom::Aabb,
        i: usize,
        j: usize,
        m: usize,
        best: &mut Option<Touch>,
    ) {
        let axis = self.axis;
        let line = &self.rows[m][i];
        if !line
            .iter()
            .any(|s| s.end > b.min[axis] && s.start < b.max[axis])
        {
            return;
        }
        let p = self.point(i, j);
        let Some((t0, t1)) = frustum.line_interval(axis, &p) else {
            return;
        };
        for s in line {
            let (lo, hi) = (s.start.max(t0), s.end.min(t1));
            if hi - lo > MIN_SPAN {
                // Depth inside a convex body is concave along a line: the deepest of the
                // overlap's ends and middle is the nearest bound from below at hand.
                for t in [lo, 0.5 * (lo + hi), hi] {
                    let mut at = p;
                    at[axis] = t;
                    let depth_mm = frustum.depth(&at);
                    if best.is_none_or(|b| depth_mm > b.depth_mm) {
                        *best = Some(Touch { depth_mm, at });
                    }
                }
            }
        }
    }
}

/// One stripe's share of one move.
#[derive(Default)]
struct Share {
    removed: f64,
    gouge: f64,
    gouge_ends: Vec<Point3>,
    touches: Vec<Option<Touch>>,
    extent: Option<CutExtent>,
}

/// Applies `work` in order to `stock` (and the gouge solids to `part`, when given); one
/// outcome per move. Guard indices must be below `guard_count`.
pub fn replay<S: LineInterval>(
    stock: &mut Stock,
    part: Option<&mut Stock>,
    work: &[MoveWork<S>],
    guard_count: usize,
) -> Vec<MoveOutcome> {
    let spacing = stock.spacing;
    let part_spacing = part.as_ref().map_or(spacing, |p| p.spacing);
    let stock_tiles = stock.grids.each_ref().map(Tiles::of);
    let part_tiles = part.as_ref().map(|p| p.grids.each_ref().map(Tiles::of));
    let stock_stripes = Rows::deal(&mut stock.grids, &stock_tiles);
    let part_stripes: Vec<Option<[Rows<'_>; 3]>> = match (part, &part_tiles) {
        (Some(part), Some(tiles)) => Rows::deal(&mut part.grids, tiles)
            .into_iter()
            .map(Some)
            .collect(),
        _ => (0..STRIPES).map(|_| None).collect(),
    };
    let shares: Vec<Vec<Share>> = stock_stripes
        .into_par_iter()
        .zip(part_stripes)
        .map(|(mut stock_rows, mut part_rows)| {
            work.iter()
                .map(|w| {
                    let mut share = Share {
                        touches: vec![None; guard_count],
                        ..Share::default()
                    };
                    let mut extent = None;
                    for solid in &w.cut {
                        for rows in stock_rows.iter_mut() {
                            share.removed += rows.remove(solid, &mut |q| {
                                if let Some(frame) = &w.frame {
                                    CutExtent::grow(&mut extent, frame, &q);
                                }
                            });
                        }
                    }
                    share.extent = extent;
                    if let Some(part_rows) = part_rows.as_mut() {
                        let ends = &mut share.gouge_ends;
                        for solid in &w.gouge {
                            for rows in part_rows.iter_mut() {
                                share.gouge += rows.remove(solid, &mut |q| ends.push(q));
                            }
                        }
                    }
                    for guard in &w.guards {
                        for rows in stock_rows.iter().filter(|rows| rows.meets(&guard.cover)) {
                            for frustum in &guard.frusta {
                                if let Some(touch) = rows.touching(frustum) {
                                    let slot = &mut share.touches[guard.index];
                                    if slot.is_none_or(|t| touch.depth_mm > t.depth_mm) {
                                        *slot = Some(touch);
                                    }
                                }
                            }
                        }
                    }
                    share
                })
                .collect()
        })
        .collect();
    // Stripe by stripe, in stripe order, per move.
    let mut outcomes: Vec<MoveOutcome> = (0..work.len())
        .map(|_| MoveOutcome {
            touches: vec![None; guard_count],
            ..MoveOutcome::default()
        })
        .collect();
    for stripe in shares {
        for (outcome, share) in outcomes.iter_mut().zip(stripe) {
            outcome.removed_mm3 += share.removed;
            outcome.gouge_mm3 += share.gouge;
            outcome.gouge_ends.extend(share.gouge_ends);
            CutExtent::merge(&mut outcome.extent, share.extent);
            for (slot, touch) in outcome.touches.iter_mut().zip(share.touches) {
                if let Some(touch) = touch
                    && slot.is_none_or(|t| touch.depth_mm > t.depth_mm)
                {
                    *slot = Some(touch);
                }
            }
        }
    }
    for outcome in &mut outcomes {
        outcome.removed_mm3 *= spacing * spacing / 3.0;
        outcome.gouge_mm3 *= part_spacing * part_spacing / 3.0;
    }
    outcomes
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::{Aabb, Point3, ToolPose, Vector3};
    use crate::stock::DEFAULT_MAX_DEXELS;
    use crate::stock::cutter::{BallEndBody, SweptSolid};

    fn block(spacing: f64) -> Stock {
        let bounds = Aabb::from_points(&[
            Point3::new(-15.0, -12.0, -8.0),
            Point3::new(15.0, 12.0, 6.0),
        ]);
        Stock::block(&bounds, spacing, DEFAULT_MAX_DEXELS).unwrap()
    }

    /// A wandering, turning path through the block, with a shank checked at each end pose.
    fn work() -> Vec<MoveWork<SweptSolid>> {
        let body = BallEndBody::new(4.0, 12.0);
        let pose = |k: usize| {
            let t = k as f64 * 0.35;
            ToolPose {
                tip: Point3::new(-12.0 + 1.1 * t, 5.0 * t.sin(), 1.5 * (0.7 * t).cos()),
                axis: nalgebra::Unit::new_normalize(Vector3::new(
                    0.4 * t.cos(),
                    0.3 * t.sin(),
                    1.0,
                )),
            }
        };
        (1..60)
            .map(|k| {
                let (from, to) = (pose(k - 1), pose(k));
                let shank = |p: &ToolPose| Frustum {
                    base: p.tip,
                    axis: p.axis.into_inner(),
                    from: 6.0,
                    to: 30.0,
                    radius_from: 2.5,
                    radius_to: 2.5,
                };
                MoveWork {
                    cut: body.sweep(&from, &to, 0.01),
                    gouge: body.eroded(0.5).sweep(&from, &to, 0.01),
                    guards: [&from, &to]
                        .iter()
                        .enumerate()
                        .map(|(index, pose)| {
                            let frustum = shank(pose);
                            let k = frustum.axis;
                            Guard {
                                index,
                                cover: SphereSweptHull::new(
                                    &[pose.tip + 6.0 * k, pose.tip + 30.0 * k],
                                    2.5,
                                ),
                                frusta: vec![frustum],
                            }
                        })
                        .collect(),
                    frame: None,
                }
            })
            .collect()
    }

    /// The stripes, run in parallel over a batch, leave every line as the moves applied one
    /// by one do, and report the same volumes, ends and touches.
    #[test]
    fn a_batch_is_the_moves_one_after_another() {
        let work = work();
        let (mut stock, mut part) = (block(0.25), block(0.25));
        let outcomes = replay(&mut stock, Some(&mut part), &work, 2);
        let (mut one_stock, mut one_part) = (block(0.25), block(0.25));
        for (w, outcome) in work.iter().zip(&outcomes) {
            let removed: f64 = w.cut.iter().map(|s| one_stock.remove(s)).sum();
            let mut ends = Vec::new();
            let gouge: f64 = w
                .gouge
                .iter()
                .map(|s| one_part.remove_recording(s, Some(&mut ends)))
                .sum();
            assert!((removed - outcome.removed_mm3).abs() <= 1e-9 * removed.max(1.0));
            assert!((gouge - outcome.gouge_mm3).abs() <= 1e-9 * gouge.max(1.0));
            let sort = |v: &mut Vec<Point3>| {
                v.sort_by(|a, b| {
                    a.coords
                        .as_slice()
                        .partial_cmp(b.coords.as_slice())
                        .unwrap()
                })
            };
            let mut got = outcome.gouge_ends.clone();
            sort(&mut ends);
            sort(&mut got);
            assert_eq!(ends, got);
            for guard in &w.guards {
                let [frustum] = guard.frusta.as_slice() else {
                    unreachable!("one frustum a guard here")
                };
                let depth = one_stock
                    .touching(frustum, |p| frustum.depth(p))
                    .map(|t| t.depth_mm);
                assert_eq!(depth, outcome.touches[guard.index].map(|t| t.depth_mm));
            }
        }
        assert!(
            outcomes.iter().any(|o| o.touches[1].is_some()),
            "the shank meets material"
        );
        assert!(outcomes.iter().any(|o| o.gouge_mm3 > 0.0));
        assert_eq!(stock, one_stock);
        assert_eq!(part, one_part);
    }

    #[test]
    fn a_batch_gives_the_same_bits_on_one_thread_and_two() {
        let work = work();
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| {
                    let (mut stock, mut part) = (block(0.25), block(0.25));
                    let outcomes = replay(&mut stock, Some(&mut part), &work, 2);
                    (stock, part, outcomes)
                })
        };
        let one = run(1);
        let two = run(2);
        assert!(one == two);
        let bits = |o: &[MoveOutcome]| {
            o.iter()
                .map(|m| (m.removed_mm3.to_bits(), m.gouge_mm3.to_bits()))
                .collect::<Vec<_>>()
        };
        assert_eq!(bits(&one.2), bits(&two.2));
    }
}
