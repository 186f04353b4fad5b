//! A raster model of the material left in the stock while a 2.5D path is cut, to answer a
//! question exact line/arc geometry answers only at great cost: how much fresh material does
//! the tool meet? The radial engagement — the width of uncut material the cutter's side takes
//! across its direction of travel — is what the stepover is meant to bound. [`engagement`]
//! replays a [`CenterPath`] and measures it.
//!
//! # The model
//!
//! The stock minus the part is rasterised on square cells: a cell is material when its centre
//! lies in the stock and outside the part. The tool is a disc of radius r stamped at least every
//! cell width along its moves; a stamp clears the material cells whose centres lie within r
//! of it. The area a stamp clears (cells × cell²) divided by the advance since the previous
//! stamp is the engagement averaged over that step; because one stamp's count is quantised to
//! whole cells, engagement is averaged over a window of travel (`compare.json` uses the tool
//! radius). Plunges (the first stamp after a retract) are booked as entry area, not as
//! engagement.
//!
//! # Why the mean engagement bounds the path length
//!
//! A path whose engagement never exceeds e removes at most e·L along its length L, plus what
//! its plunges remove, so L ≥ (area removed − entry area)/e. Any path that holds its radial
//! engagement to the stepover s is at least (area − entries)/s long; [`Engagement::pass_mean`]
//! shows how close a method comes to that bound.

use crate::contour::cavc::validate_shape;
use crate::contour::error::{ContourError, Result, require_positive};
use crate::contour::geometry::{Point2, Segment, Shape};
use crate::contour::region::RegionIndex;
use crate::contour::segops::point_at;
use crate::contour::toolpath::{CenterPath, Link};
use std::collections::VecDeque;

/// Cell outside the stock or inside the part: nothing to cut.
const AIR: u8 = 0;
/// Uncut stock.
const MATERIAL: u8 = 1;
/// Stock the tool has swept.
const CLEARED: u8 = 2;

/// Largest number of cells of a map (one byte each); a finer cell is coarsened to fit.
pub const MAX_CELLS: usize = 1 << 26;

/// The cell the reports use for tool radius `r` and stepover `s`: min(r, s)/16, fine enough
/// that a pass one stepover from the last measures s within a few hundredths of a mm.
pub fn report_cell(r: f64, s: f64) -> f64 {
    r.min(s) / 16.0
}

/// The material state of the stock on a grid of square cells (see the module docs).
#[derive(Clone, Debug)]
pub struct MaterialMap {
    /// Lower-left corner of cell (0, 0).
    origin: Point2,
    cell: f64,
    width: usize,
    height: usize,
    state: Vec<u8>,
    radius: f64,
}

impl MaterialMap {
    /// The stock minus the part on cells of `cell` mm (coarsened if the grid would exceed
    /// [`MAX_CELLS`]) for a flat end mill of radius `tool_radius`.
    pub fn new(part: &Shape, stock: &Shape, tool_radius: f64, cell: f64) -> Result<Self> {
        validate_shape(part, "part")?;
        Self::of_stock(stock, Some(part), tool_radius, cell)
    }

    /// As [`MaterialMap::new`], with no part inside the stock when `part` is `None` (a facing
    /// layer above everything the part has).
    pub fn of_stock(
        stock: &Shape,
        part: Option<&Shape>,
        tool_radius: f64,
        cell: f64,
    ) -> Result<Self> {
        require_positive(
            "tool_radius",
            tool_radius,
            "must be a positive finite number of mm",
        )?;
        require_positive(
            "cell",
            cell,
            "the material map's cell must be a positive finite number of mm",
        )?;
        validate_shape(stock, "stock")?;
        let stock_index = RegionIndex::new(stock);
        let part_index = part.map(RegionIndex::new);
        let bounds = stock_index
            .boundary()
            .bounds()
            .ok_or(ContourError::EmptyShape { what: "stock" })?
            .expanded(tool_radius + 2.0 * cell);
        let (span_x, span_y) = (bounds.max.x - bounds.min.x, bounds.max.y - bounds.min.y);
        let cell = cell.max((span_x * span_y / MAX_CELLS as f64).sqrt() * (1.0 + 1e-9));
        let width = ((span_x / cell).ceil() as usize).max(1);
        let height = ((span_y / cell).ceil() as usize).max(1);
        let mut map = Self {
            origin: bounds.min,
            cell,
            width,
            height,
            state: vec![AIR; width * height],
            radius: tool_radius,
        };
        for j in 0..height {
            let y = map.origin.y + (j as f64 + 0.5) * cell;
            for (a, b) in inside_spans(&stock_index, y) {
                map.fill_row(j, a, b, MATERIAL);
            }
            for (a, b) in part_index.iter().flat_map(|part| inside_spans(part, y)) {
                map.fill_row(j, a, b, AIR);
            }
        }
        Ok(map)
    }

    /// Side of a cell, mm.
    pub fn cell(&self) -> f64 {
        self.cell
    }

    /// Area of the material not yet swept, mm².
    pub fn material_area(&self) -> f64 {
        self.state.iter().filter(|&&c| c == MATERIAL).count() as f64 * self.cell * self.cell
    }

    /// Sets the cells of row `j` whose centres lie in [a, b) to `value`.
    fn fill_row(&mut self, j: usize, a: f64, b: f64, value: u8) {
        if let Some((lo, hi)) = self.columns(a, b) {
            let row = j * self.width;
            self.state[row + lo..=row + hi].fill(value);
        }
    }

    /// Columns whose cell centres lie in [a, b], clamped to the grid.
    fn columns(&self, a: f64, b: f64) -> Option<(usize, usize)> {
        let lo = ((a - self.origin.x) / self.cell - 0.5).ceil().max(0.0);
        let hi = ((b - self.origin.x) / self.cell - 0.5)
            .floor()
            .min(self.width as f64 - 1.0);
        (lo <= hi).then_some((lo as usize, hi as usize))
    }

    /// Rows with cell centres within `radius` of `p`'s height.
    fn rows_near(&self, p: Point2, radius: f64) -> std::ops::Range<usize> {
        let h = self.cell;
        let lo = ((p.y - radius - self.origin.y) / h - 0.5).ceil().max(0.0);
        let hi = ((p.y + radius - self.origin.y) / h - 0.5)
            .floor()
            .min(self.height as f64 - 1.0);
        if lo <= hi {
            lo as usize..hi as usize + 1
        } else {
            0..0
        }
    }

    /// Columns of row `j` whose cell centres lie within `radius` of `p`.
    fn row_span(&self, j: usize, p: Point2, radius: f64) -> Option<(usize, usize)> {
        let dy = self.origin.y + (j as f64 + 0.5) * self.cell - p.y;
        let w2 = radius * radius - dy * dy;
        if w2 < 0.0 {
            return None;
        }
        let w = w2.sqrt();
        self.columns(p.x - w, p.x + w)
    }

    /// Clears the material cells whose centres lie within r of `p`; returns how many. When the
    /// disc at `previous` was cleared just before, only the cells outside it are visited (on
    /// each row, the new span minus the old one): a step of one cell visits a thin crescent
    /// instead of the whole disc.
    fn stamp(&mut self, p: Point2, previous: Option<Point2>) -> usize {
        let r = self.radius;
        let mut count = 0;
        for j in self.rows_near(p, r) {
            let Some((lo, hi)) = self.row_span(j, p, r) else {
                continue;
            };
            let old = previous.and_then(|q| self.row_span(j, q, r));
            let row = j * self.width;
            let mut clear = |a: usize, b: usize| {
                for c in &mut self.state[row + a..=row + b] {
                    if *c == MATERIAL {
                        *c = CLEARED;
                        count += 1;
                    }
                }
            };
            match old {
                Some((old_lo, old_hi)) if old_lo <= hi && old_hi >= lo => {
                    if lo < old_lo {
                        clear(lo, old_lo - 1);
                    }
                    if old_hi < hi {
                        clear(old_hi + 1, hi);
                    }
                }
                _ => clear(lo, hi),
            }
        }
        count
    }

    /// The area of uncut material within r of `p`, mm², clearing nothing: what a plunge there
    /// would meet.
    pub fn material_within(&self, p: Point2) -> f64 {
        let mut count = 0;
        for j in self.rows_near(p, self.radius) {
            if let Some((lo, hi)) = self.row_span(j, p, self.radius) {
                let row = j * self.width;
                count += self.state[row + lo..=row + hi]
                    .iter()
                    .filter(|&&c| c == MATERIAL)
                    .count();
            }
        }
        count as f64 * self.cell * self.cell
    }

    /// The tool plunges at `p`: clears the disc there and returns the area it cleared.
    pub fn plunge(&mut self, p: Point2) -> f64 {
        self.stamp(p, None) as f64 * self.cell * self.cell
    }

    /// Cuts `seg` from its start (already swept) to its end, feeding `window` with the area
    /// each stamp clears and the advance to it.
    pub fn cut(&mut self, seg: &Segment, window: &mut Window) {
        self.cut_stamps(seg, |fresh, advance, p| window.push(fresh, advance, p));
    }

    /// Cuts `seg` as [`Self::cut`] does, handing each stamp's fresh area, its advance and
    /// where it stood to `each`: stamps at most a cell apart.
    pub fn cut_stamps(&mut self, seg: &Segment, mut each: impl FnMut(f64, f64, Point2)) {
        let len = seg.length();
        let n = ((len / self.cell).ceil() as usize).max(1);
        let area = self.cell * self.cell;
        // The first stamp clears its whole disc: the start of the segment was swept as the end
        // of the move before, whose rounding may differ in the last bit.
        let mut previous = None;
        for k in 1..=n {
            let p = point_at(seg, k as f64 / n as f64);
            let fresh = self.stamp(p, previous) as f64 * area;
            each(fresh, len / n as f64, p);
            previous = Some(p);
        }
    }
}

/// The spans [a, b) of the horizontal line at `y` inside the region (winding number > 0).
fn inside_spans(index: &RegionIndex, y: f64) -> Vec<(f64, f64)> {
    let mut crossings = index.crossings(y);
    crossings.sort_by(|a, b| a.0.total_cmp(&b.0));
    // The winding number of a point is the sum over the crossings to its right.
    let mut winding: i32 = crossings.iter().map(|c| c.1).sum();
    let mut spans = Vec::new();
    let mut from = f64::NEG_INFINITY;
    for &(x, d) in &crossings {
        if winding > 0 && from.is_finite() {
            spans.push((from, x));
        }
        winding -= d;
        from = x;
    }
    spans
}

/// Engagement along one run at cutting depth: the area cleared and the advance of the last
/// stamps spanning at least `span` of travel.
#[derive(Clone, Debug)]
pub struct Window {
    span: f64,
    steps: VecDeque<(f64, f64)>,
    area: f64,
    advance: f64,
    /// Whether a full window has been reported since the run began.
    reported: bool,
    /// Whether to keep every windowed value (for percentiles).
    keep_values: bool,
    last_point: Point2,
    /// Largest windowed engagement of the run and where its window ended.
    pub max: f64,
    pub max_at: Point2,
    /// Every reported windowed engagement (one per stamp once the window is full).
    pub values: Vec<f64>,
    /// Area cleared and length travelled over the whole run.
    pub area_total: f64,
    pub length_total: f64,
}

impl Window {
    /// A fresh run averaged over `span` mm of travel.
    pub fn new(span: f64) -> Self {
        Self {
            keep_values: true,
            ..Self::without_values(span)
        }
    }

    /// [`Self::new`] without the list of values (only the maximum and totals are kept).
    pub fn without_values(span: f64) -> Self {
        Self {
            keep_values: false,
            span,
            steps: VecDeque::new(),
            area: 0.0,
            advance: 0.0,
            reported: false,
            last_point: Point2::origin(),
            max: 0.0,
            max_at: Point2::origin(),
            values: Vec::new(),
            area_total: 0.0,
            length_total: 0.0,
        }
    }

    fn push(&mut self, area: f64, advance: f64, at: Point2) {
        self.steps.push_back((area, advance));
        self.area += area;
        self.advance += advance;
        self.area_total += area;
        self.length_total += advance;
        self.last_point = at;
        while let Some(&(a, d)) = self.steps.front() {
            if self.advance - d >= self.span {
                self.steps.pop_front();
                self.area -= a;
                self.advance -= d;
            } else {
                break;
            }
        }
        if self.advance >= self.span {
            self.report();
        }
    }

    fn report(&mut self) {
        if self.advance > 0.0 {
            let e = self.area / self.advance;
            if self.keep_values {
                self.values.push(e);
            }
            if e > self.max {
                self.max = e;
                self.max_at = self.last_point;
            }
            self.reported = true;
        }
    }

    /// Ends the run: a run shorter than the window reports its own average once.
    pub fn finish(&mut self) {
        if !self.reported {
            self.report();
        }
    }
}

/// What [`engagement`] measured on a path.
#[derive(Clone, Debug, PartialEq)]
pub struct Engagement {
    /// Cell of the map and averaging window, mm.
    pub cell: f64,
    pub window: f64,
    /// Largest windowed engagement along the passes, mm, and where its window ended.
    pub pass_max: f64,
    pub pass_max_at: Point2,
    /// 99th percentile of the passes' windowed engagement, mm.
    pub pass_p99: f64,
    /// Area removed along the passes per mm of pass: their mean engagement, mm.
    pub pass_mean: f64,
    /// Largest engagement of a feed link, mm (a step-over link meets up to a full-width slot
    /// for a short distance).
    pub link_max: f64,
    /// Area removed by the passes, by the plunges and by the feed links, mm².
    pub pass_area: f64,
    pub entry_area: f64,
    pub link_area: f64,
    /// Area the traverses at depth removed, mm²: nothing, if they run through air as planned.
    pub traverse_area: f64,
    /// Most material one plunge went into, mm² (πr² = straight down into uncut stock), and
    /// where.
    pub entry_max: f64,
    pub entry_max_at: Point2,
}

impl Engagement {
    /// Everything the path removed, mm².
    pub fn removed_area(&self) -> f64 {
        self.pass_area + self.entry_area + self.link_area + self.traverse_area
    }
}

/// Replays `path` on a material map of `stock − part` (cells of `cell` mm, engagement averaged
/// over `window` mm of travel, or over a whole pass or link when it is shorter) and measures
/// the tool's engagement on passes and links apart.
pub fn engagement(
    path: &CenterPath,
    part: &Shape,
    stock: &Shape,
    cell: f64,
    window: f64,
) -> Result<Engagement> {
    require_positive(
        "window",
        window,
        "the engagement window must be a positive finite number of mm",
    )?;
    let mut map = MaterialMap::new(part, stock, path.tool_radius(), cell)?;
    let mut values: Vec<f64> = Vec::new();
    let mut e = Engagement {
        cell: map.cell(),
        window,
        pass_max: 0.0,
        pass_max_at: Point2::origin(),
        pass_p99: 0.0,
        pass_mean: 0.0,
        link_max: 0.0,
        pass_area: 0.0,
        entry_area: 0.0,
        link_area: 0.0,
        traverse_area: 0.0,
        entry_max: 0.0,
        entry_max_at: Point2::origin(),
    };
    let mut pass_length = 0.0;
    for (i, pass) in path.passes().iter().enumerate() {
        if i == 0 || matches!(path.links()[i - 1], Link::Rapid { .. }) {
            let fresh = map.plunge(pass.start());
            e.entry_area += fresh;
            if fresh > e.entry_max {
                e.entry_max = fresh;
                e.entry_max_at = pass.start();
            }
        }
        let mut run = Window::new(window);
        for seg in pass.segments() {
            map.cut(&seg, &mut run);
        }
        run.finish();
        if run.max > e.pass_max {
            e.pass_max = run.max;
            e.pass_max_at = run.max_at;
        }
        values.append(&mut run.values);
        e.pass_area += run.area_total;
        pass_length += run.length_total;
        if let Some(link @ (Link::Feed { from, to } | Link::Traverse { from, to })) =
            path.links().get(i)
        {
            let mut run = Window::without_values(window);
            map.cut(
                &Segment::Line {
                    start: *from,
                    end: *to,
                },
                &mut run,
            );
            run.finish();
            if matches!(link, Link::Traverse { .. }) {
                e.traverse_area += run.area_total;
            } else {
                e.link_max = e.link_max.max(run.max);
                e.link_area += run.area_total;
            }
        }
    }
    values.sort_by(f64::total_cmp);
    if let Some(last) = values.len().checked_sub(1) {
        e.pass_p99 = values[((0.99 * last as f64).round() as usize).min(last)];
    }
    if pass_length > 0.0 {
        e.pass_mean = e.pass_area / pass_length;
    }
    Ok(e)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contour::geometry::Vertex;
    use crate::contour::parallel::tests::{circle, disc_in_square, rect};
    use crate::contour::parallel::{ParallelOptions, contour_parallel};
    use crate::contour::toolpath::Pass;
    use std::f64::consts::PI;

    #[test]
    fn the_map_holds_the_stock_minus_the_part() {
        let (part, stock) = disc_in_square(10.0, 30.0);
        let map = MaterialMap::new(&part, &stock, 3.0, 0.05).expect("map");
        let exact = 3600.0 - PI * 100.0;
        assert!(
            (map.material_area() - exact).abs() < 0.002 * exact,
            "{} vs {exact}",
            map.material_area()
        );
    }

    /// One straight slot across a plate clears a band 2r wide (engagement 2r); a second pass
    /// s beside it meets s; a move back along the first pass meets nothing.
    #[test]
    fn parallel_passes_meet_the_stepover() {
        let part = Shape {
            contours: vec![rect(100.0, 100.0, 101.0, 101.0, true)],
        };
        let stock = Shape {
            contours: vec![rect(0.0, 0.0, 60.0, 40.0, true)],
        };
        let (r, s) = (3.0, 2.4);
        let mut map = MaterialMap::new(&part, &stock, r, 0.05).expect("map");
        let line = |y: f64| Segment::Line {
            start: Point2::new(-5.0, y),
            end: Point2::new(65.0, y),
        };
        let mut slot = Window::new(r);
        map.plunge(Point2::new(-5.0, 20.0));
        map.cut(&line(20.0), &mut slot);
        assert!((slot.max - 2.0 * r).abs() < 0.02, "slot {}", slot.max);
        let mut beside = Window::new(r);
        map.cut(&line(20.0 + s), &mut beside);
        assert!((beside.max - s).abs() < 0.02, "beside {}", beside.max);
    }

    /// On a contour-parallel path the engagement never exceeds the stepover (beyond the map's
    /// quantisation), the path removes the whole region, and the mean is the region's area
    /// over the pass length, less what plunges and links took.
    #[test]
    fn contour_parallel_holds_the_stepover() {
        let (part, stock) = disc_in_square(10.0, 30.0);
        let (r, s) = (3.0, 2.4);
        let path = contour_parallel(&part, &stock, &ParallelOptions::new(r, s)).expect("plan");
        let e = engagement(&path, &part, &stock, 0.05, r).expect("engagement");
        assert!(e.pass_max <= s + 0.05, "{e:?}");
        let region = 3600.0 - PI * 100.0;
        assert!((e.removed_area() - region).abs() < 0.003 * region, "{e:?}");
        let pass_length: f64 = path.passes().iter().map(Pass::length).sum();
        assert!((e.pass_mean - e.pass_area / pass_length).abs() < 1e-9);
        assert!(e.pass_mean <= e.pass_p99 + 1e-12 && e.pass_p99 <= e.pass_max);
        // The step-over links move the tool sideways into the next band: briefly more than s.
        assert!(e.link_max > s && e.link_max <= 2.0 * r + 0.05, "{e:?}");
    }

    /// A pass that jumps sideways by more than the stepover is caught.
    #[test]
    fn a_wide_step_is_measured() {
        let part = Shape {
            contours: vec![circle(0.0, 0.0, 10.0, true)],
        };
        let stock = Shape {
            contours: vec![circle(0.0, 0.0, 24.0, true)],
        };
        let r = 3.0;
        let ring = |radius: f64| {
            Pass::closed(
                vec![
                    Vertex {
                        point: Point2::new(radius, 0.0),
                        bulge: 1.0,
                    },
                    Vertex {
                        point: Point2::new(-radius, 0.0),
                        bulge: 1.0,
                    },
                ],
                radius - 10.0,
            )
            .expect("ring")
        };
        // The ring of radius 23 sweeps radii 20..26; the ring of radius 18 then meets the annulus
        // 15..20, 5 mm wide: per mm of its centre line (20² − 15²)/(2·18) mm². The outer ring
        // took (24² − 20²)/(2·23) = 3.83 mm.
        let path = CenterPath::with_rapid_links(r, vec![ring(23.0), ring(18.0)]).expect("path");
        let e = engagement(&path, &part, &stock, 0.05, r).expect("engagement");
        let expected = (400.0 - 225.0) / 36.0;
        assert!((e.pass_max - expected).abs() < 0.03, "{e:?} vs {expected}");
        let region = PI * (576.0 - 225.0);
        assert!((e.removed_area() - region).abs() < 0.003 * region, "{e:?}");
    }
}
