//! The in-process stock: where material is, as a tri-dexel model (DESIGN.md §3.7; seed 004
//! ch. 5 steps 7–8), and its removal by swept cutters.
//!
//! Three grids of parallel lines ("dexels"), one along each axis, a line through the centre of
//! every `spacing` × `spacing` cell of the stock's box seen along that axis. Each line holds the
//! intervals of material on it ([`spans`]). Three directions, not one, so that walls of any
//! orientation and undercuts (5-axis) are sampled at the spacing: a vertical wall is thin for
//! the Z grid but crossed squarely by the X or Y one.
//!
//! * Blanks: a box ([`Stock::block`]), a cylinder about any axis ([`Stock::cylinder`]), a closed
//!   mesh ([`Stock::from_mesh`]: each triangle rasterised onto the three grids with a
//!   tie-breaking rule, so a line through a shared edge or vertex counts it once, and the
//!   crossings paired inside/outside).
//! * Removal ([`Stock::remove`]): each line crossing a swept solid loses the exact interval of
//!   it inside the solid ([`sweep::LineInterval`]: closed forms, no sampled poses), so a thin
//!   wall is cut or left exactly where its lines are. In parallel over lines; each line's result
//!   depends on nothing else, so any thread count gives the same model.
//! * Queries: [`Stock::is_material`] (two of the three grids' nearest lines agree),
//!   [`Stock::volume`] (the mean of the three grids' integrals).
//!
//! The model's error is in the directions across the lines: a surface is known to within the
//! spacing between lines, exactly along them.

pub mod clearance;
pub mod convex;
pub mod cutter;
pub mod replay;
pub mod resample;
pub mod rest;
pub mod simulate;
pub mod slide;
pub mod spans;
pub mod surface;
pub mod sweep;

mod mesh_blank;

use rayon::prelude::*;

use crate::geom::{Aabb, Point3, Vector3};
use crate::mesh::Mesh;
use spans::{Span, Spans};
use sweep::LineInterval;

/// Default largest number of dexel lines (all three grids): about 2.4 GB of lines at one span
/// each. A finer model is refused before it is allocated.
pub const DEFAULT_MAX_DEXELS: usize = 100_000_000;

/// Why a stock cannot be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum StockError {
    /// The spacing is not a positive finite number.
    #[error("the dexel spacing must be a positive number of mm, got {0}")]
    Spacing(f64),
    /// The blank's size is not finite, or the blank is empty.
    #[error("the blank is empty or not finite: {0}")]
    Blank(String),
    /// A saved stock cannot be read.
    #[error("not a saved wavemill stock: {0}")]
    Format(String),
    /// The model would hold more lines than the limit.
    #[error(
        "a {size} mm blank at a {spacing} mm spacing needs {dexels} dexel lines, above the limit of {limit}"
    )]
    TooLarge {
        /// The blank's size, as text.
        size: String,
        /// The spacing asked for, mm.
        spacing: f64,
        /// Lines the model would need.
        dexels: usize,
        /// The limit.
        limit: usize,
    },
}

/// The indices of the lattice points `origin + i·spacing`, `i < count`, lying in `[lo, hi]`.
fn lattice_range(
    origin: f64,
    spacing: f64,
    count: usize,
    lo: f64,
    hi: f64,
) -> std::ops::Range<usize> {
    let first = ((lo - origin) / spacing).ceil().max(0.0);
    let last = ((hi - origin) / spacing).floor();
    if !(first.is_finite() && last.is_finite()) || last < first {
        return 0..0;
    }
    let first = first as usize;
    let last = (last as usize).min(count.saturating_sub(1));
    if first > last { 0..0 } else { first..last + 1 }
}

/// One of the three dexel grids: lines along `axis`, one per cell across it.
#[derive(Clone, Debug, PartialEq)]
pub struct DexelGrid {
    axis: usize,
    /// The two axes across the lines: `(axis + 1) % 3`, `(axis + 2) % 3`.
    across: [usize; 2],
    /// Where the first line crosses the two `across` axes (a cell centre).
    origin: [f64; 2],
    /// Lines along each `across` axis.
    counts: [usize; 2],
    spacing: f64,
    /// Line `(i, j)` at index `i + counts[0] · j`.
    lines: Vec<Spans>,
}

impl DexelGrid {
    fn new(axis: usize, bounds: &Aabb, spacing: f64) -> Self {
        let across = [(axis + 1) % 3, (axis + 2) % 3];
        let count = |a: usize| (((bounds.max[a] - bounds.min[a]) / spacing).ceil() as usize).max(1);
        let counts = [count(across[0]), count(across[1])];
        // Centre the lattice on the box so the lines sit symmetrically inside it.
        let origin = [0, 1].map(|k| {
            let a = across[k];
            0.5 * (bounds.min[a] + bounds.max[a]) - 0.5 * (counts[k] as f64 - 1.0) * spacing
        });
        DexelGrid {
            axis,
            across,
            origin,
            counts,
            spacing,
            lines: vec![Spans::new(); counts[0] * counts[1]],
        }
    }

    /// The direction of the lines (0 = X, 1 = Y, 2 = Z).
    pub fn axis(&self) -> usize {
        self.axis
    }

    /// Lines along each axis across them.
    pub fn counts(&self) -> [usize; 2] {
        self.counts
    }

    /// A point of line `(i, j)` (its coordinate along the line is 0).
    pub fn line_point(&self, i: usize, j: usize) -> Point3 {
        let mut p = Point3::origin();
        p[self.across[0]] = self.origin[0] + i as f64 * self.spacing;
        p[self.across[1]] = self.origin[1] + j as f64 * self.spacing;
        p
    }

    /// The material on line `(i, j)`.
    pub fn spans(&self, i: usize, j: usize) -> &Spans {
        &self.lines[i + self.counts[0] * j]
    }

    /// The index range of lines whose `across[k]` coordinate lies in `[lo, hi]`.
    fn index_range(&self, k: usize, lo: f64, hi: f64) -> std::ops::Range<usize> {
        lattice_range(self.origin[k], self.spacing, self.counts[k], lo, hi)
    }

    /// The nearest line to `p` across, if `p` is over the grid.
    fn nearest(&self, p: &Point3) -> Option<usize> {
        let mut index = [0usize; 2];
        for k in 0..2 {
            let x = ((p[self.across[k]] - self.origin[k]) / self.spacing).round();
            if !(x >= 0.0 && x < self.counts[k] as f64) {
                return None;
            }
            index[k] = x as usize;
        }
        Some(index[0] + self.counts[0] * index[1])
    }

    /// Σ length of material × spacing²: this grid's estimate of the volume.
    fn volume(&self) -> f64 {
        let total: f64 = self.lines.iter().map(spans::length).sum();
        total * self.spacing * self.spacing
    }
}

/// The in-process stock: three dexel grids over the blank's box (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct Stock {
    bounds: Aabb,
    spacing: f64,
    grids: [DexelGrid; 3],
}

impl Stock {
    /// Empty grids over `bounds` at `spacing`, refused above `max_dexels` lines.
    fn empty(bounds: &Aabb, spacing: f64, max_dexels: usize) -> Result<Self, StockError> {
        if !(spacing.is_finite() && spacing > 0.0) {
            return Err(StockError::Spacing(spacing));
        }
        let e = bounds.extent();
        if bounds.is_empty() || !e.iter().all(|v| v.is_finite()) {
            return Err(StockError::Blank(format!("box {bounds:?}")));
        }
        let cells =
            |a: f64, b: f64| ((a / spacing).ceil().max(1.0)) * ((b / spacing).ceil().max(1.0));
        let dexels = cells(e.y, e.z) + cells(e.z, e.x) + cells(e.x, e.y);
        if dexels > max_dexels as f64 {
            return Err(StockError::TooLarge {
                size: format!("{:.3} × {:.3} × {:.3}", e.x, e.y, e.z),
                spacing,
                dexels: dexels.min(usize::MAX as f64) as usize,
                limit: max_dexels,
            });
        }
        Ok(Stock {
            bounds: *bounds,
            spacing,
            grids: [0, 1, 2].map(|axis| DexelGrid::new(axis, bounds, spacing)),
        })
    }

    /// Fills every line with the spans `line(axis, point)` gives (in parallel, per line).
    fn fill(&mut self, line: impl Fn(usize, &Point3) -> Spans + Sync) {
        for grid in &mut self.grids {
            let (axis, g) = (grid.axis, &*grid);
            let filled: Vec<Spans> = (0..g.lines.len())
                .into_par_iter()
                .map(|k| line(axis, &g.line_point(k % g.counts[0], k / g.counts[0])))
                .collect();
            grid.lines = filled;
        }
    }

    /// A rectangular block filling `bounds`.
    pub fn block(bounds: &Aabb, spacing: f64, max_dexels: usize) -> Result<Self, StockError> {
        let mut stock = Self::empty(bounds, spacing, max_dexels)?;
        let b = *bounds;
        stock.fill(|axis, _| {
            std::iter::once(Span {
                start: b.min[axis],
                end: b.max[axis],
            })
            .collect()
        });
        Ok(stock)
    }

    /// A solid cylinder of `radius` about the line through `base` along the unit `axis`, from
    /// `base` to `base + length · axis`.
    pub fn cylinder(
        base: &Point3,
        axis: &Vector3,
        radius: f64,
        length: f64,
        spacing: f64,
        max_dexels: usize,
    ) -> Result<Self, StockError> {
        let k = axis.normalize();
        let finite = radius.is_finite() && length.is_finite() && k.iter().all(|v| v.is_finite());
        if !(finite && radius > 0.0 && length > 0.0) {
            return Err(StockError::Blank(format!(
                "cylinder of radius {radius} and length {length} along {axis:?}"
            )));
        }
        let bounds = sweep::discs_bounds(base, &k, [(0.0, radius), (length, radius)]);
        let mut stock = Self::empty(&bounds, spacing, max_dexels)?;
        let base = *base;
        stock.fill(|line_axis, p| {
            cylinder_interval(line_axis, p, &base, &k, radius, length)
                .map(|(start, end)| Span { start, end })
                .into_iter()
                .collect()
        });
        Ok(stock)
    }

    /// The solid a closed, consistently oriented mesh bounds (see the module docs).
    pub fn from_mesh(mesh: &Mesh, spacing: f64, max_dexels: usize) -> Result<Self, StockError> {
        let bounds = mesh.aabb();
        let mut stock = Self::empty(&bounds, spacing, max_dexels)?;
        for grid in &mut stock.grids {
            mesh_blank::fill_grid(grid, mesh);
        }
        Ok(stock)
    }

    /// The box the model covers.
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// The distance between neighbouring lines, mm.
    pub fn spacing(&self) -> f64 {
        self.spacing
    }

    /// The grid of lines along `axis` (0 = X, 1 = Y, 2 = Z).
    pub fn grid(&self, axis: usize) -> &DexelGrid {
        &self.grids[axis]
    }

    /// Dexel lines in all three grids.
    pub fn line_count(&self) -> usize {
        self.grids.iter().map(|g| g.lines.len()).sum()
    }

    /// The material volume, mm³: the mean of the three grids' integrals.
    pub fn volume(&self) -> f64 {
        self.grids.iter().map(DexelGrid::volume).sum::<f64>() / 3.0
    }

    /// `true` when `p` is material: inside a span of the nearest line of at least two of the
    /// three grids. Outside the model's box, nothing is material.
    pub fn is_material(&self, p: &Point3) -> bool {
        let votes = self
            .grids
            .iter()
            .filter(|g| {
                g.nearest(p)
                    .is_some_and(|k| spans::contains(&g.lines[k], p[g.axis]))
            })
            .count();
        votes >= 2
    }

    /// Removes the solid from every line crossing it; returns the volume removed (mm³, the mean
    /// of the three grids' estimates, as [`Stock::volume`]).
    pub fn remove(&mut self, solid: &dyn LineInterval) -> f64 {
        self.remove_recording(solid, None)
    }

    /// [`Stock::remove`], also collecting the ends of every removed piece (points on the
    /// solid's surface, inside the material it took) into `ends`, in a fixed order.
    pub fn remove_recording(
        &mut self,
        solid: &dyn LineInterval,
        mut ends: Option<&mut Vec<Point3>>,
    ) -> f64 {
        let record = ends.is_some();
        let b = solid.bounds();
        // 1 nm: below it an interval is round-off, not material (f64 resolves 1e-14 mm at 100 mm).
        let min_span = 1e-6;
        let mut removed = 0.0;
        for grid in &mut self.grids {
            let (axis, across, spacing) = (grid.axis, grid.across, grid.spacing);
            let is = grid.index_range(0, b.min[across[0]], b.max[across[0]]);
            let js = grid.index_range(1, b.min[across[1]], b.max[across[1]]);
            if is.is_empty() || js.is_empty() {
                continue;
            }
            let (n0, origin) = (grid.counts[0], grid.origin);
            let rows = &mut grid.lines[js.start * n0..js.end * n0];
            // Row sums (and ends) in row order: the same whatever the thread count.
            let per_row: Vec<(f64, Vec<Point3>)> = rows
                .par_chunks_mut(n0)
                .enumerate()
                .map(|(r, row)| {
                    let j = js.start + r;
                    let mut length = 0.0;
                    let mut on_row = Point3::origin();
                    on_row[across[1]] = origin[1] + j as f64 * spacing;
                    let mut row_ends = Vec::new();
                    let Some((lo, hi)) = solid.row_range(axis, across[0], &on_row) else {
                        return (0.0, row_ends);
                    };
                    let first = ((lo - origin[0]) / spacing).ceil().max(is.start as f64);
                    let last = ((hi - origin[0]) / spacing)
                        .floor()
                        .min(is.end as f64 - 1.0);
                    if first.partial_cmp(&last) == Some(std::cmp::Ordering::Greater)
                        || first.is_nan()
                        || last.is_nan()
                    {
                        return (0.0, row_ends);
                    }
                    let (first, last) = (first as usize, last as usize);
                    for (i, line) in row.iter_mut().enumerate().take(last + 1).skip(first) {
                        // Lines with no material where the solid can be along them are
                        // skipped before any geometry (most lines a tool's shank crosses).
                        let mut p = Point3::origin();
                        p[across[0]] = origin[0] + i as f64 * spacing;
                        p[across[1]] = origin[1] + j as f64 * spacing;
                        let Some((lo, hi)) = solid.range_over(axis, &p, &p) else {
                            continue;
                        };
                        if !line.iter().any(|s| s.end > lo && s.start < hi) {
                            continue;
                        }
                        if let Some((t0, t1)) = solid.line_interval(axis, &p) {
                            length +=
                                spans::subtract_recording(line, t0, t1, min_span, &mut |a, b| {
                                    if record {
                                        for t in [a, b] {
                                            let mut q = p;
                                            q[axis] = t;
                                            row_ends.push(q);
                                        }
                                    }
                                });
                        }
                    }
                    (length, row_ends)
                })
                .collect();
            removed += per_row.iter().map(|r| r.0).sum::<f64>() * spacing * spacing;
            if let Some(ends) = ends.as_deref_mut() {
                for (_, row_ends) in per_row {
                    ends.extend(row_ends);
                }
            }
        }
        removed / 3.0
    }
}

/// Material found inside a solid that must not touch it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Touch {
    /// How deep the material is inside the solid, mm, as the caller's depth function measures
    /// it at the middle of a run of material along a line (the deepest run's).
    pub depth_mm: f64,
    /// The middle of that run.
    pub at: Point3,
}

impl Stock {
    /// The box of the material: a bound of everything [`Stock::touching`] can find, now and
    /// after any removal.
    pub fn material_bounds(&self) -> Aabb {
        let mut b = Aabb::empty();
        for grid in &self.grids {
            for j in 0..grid.counts[1] {
                for i in 0..grid.counts[0] {
                    let line = &grid.lines[i + grid.counts[0] * j];
                    if let (Some(first), Some(last)) = (line.first(), line.last()) {
                        let mut p = grid.line_point(i, j);
                        p[grid.axis] = first.start;
                        b.grow(&p);
                        p[grid.axis] = last.end;
                        b.grow(&p);
                    }
                }
            }
        }
        b
    }

    /// Material inside `solid`, without removing it: for each run of material inside it along
    /// a line, `depth` at the run's middle (a convex solid's chord is deepest near its middle);
    /// the deepest, or `None` when the solid is clear of material. Runs shorter than 1 nm are
    /// round-off.
    pub fn touching(
        &self,
        solid: &dyn LineInterval,
        depth: impl Fn(&Point3) -> f64,
    ) -> Option<Touch> {
        let b = solid.bounds();
        let mut best: Option<Touch> = None;
        for grid in &self.grids {
            let (axis, across, spacing) = (grid.axis, grid.across, grid.spacing);
            let is = grid.index_range(0, b.min[across[0]], b.max[across[0]]);
            for j in grid.index_range(1, b.min[across[1]], b.max[across[1]]) {
                for i in is.clone() {
                    let line = &grid.lines[i + grid.counts[0] * j];
                    if !line
                        .iter()
                        .any(|s| s.end > b.min[axis] && s.start < b.max[axis])
                    {
                        continue;
                    }
                    let mut p = Point3::origin();
                    p[across[0]] = grid.origin[0] + i as f64 * spacing;
                    p[across[1]] = grid.origin[1] + j as f64 * spacing;
                    let Some((t0, t1)) = solid.line_interval(axis, &p) else {
                        continue;
                    };
                    for s in line {
                        let (lo, hi) = (s.start.max(t0), s.end.min(t1));
                        if hi - lo > 1e-6 {
                            // As the replay does: the deepest of the overlap's ends and middle.
                            for t in [lo, 0.5 * (lo + hi), hi] {
                                let mut at = p;
                                at[axis] = t;
                                let d = depth(&at);
                                if best.is_none_or(|b| d > b.depth_mm) {
                                    best = Some(Touch { depth_mm: d, at });
                                }
                            }
                        }
                    }
                }
            }
        }
        best
    }
}

impl Stock {
    /// Removes the cutting body of a ball-end mill swept along every move of `toolpath` (each
    /// split as [`cutter::BallEndBody::sweep`] does, within `tolerance`); returns the volume
    /// each move removed, mm³, in the toolpath's order (the first move, which only says where
    /// the tool starts, removes nothing). Rapids remove material too: a rapid that removes any
    /// went through material.
    pub fn remove_toolpath(
        &mut self,
        toolpath: &crate::geom::Toolpath,
        body: &cutter::BallEndBody,
        tolerance: f64,
    ) -> Vec<f64> {
        self.remove_sweeps(toolpath, &|from, to| body.sweep(from, to, tolerance))
    }

    /// [`Stock::remove_toolpath`] for any cutting body (flat, bull-nose, tapered).
    pub fn remove_cutting(
        &mut self,
        toolpath: &crate::geom::Toolpath,
        body: &cutter::CuttingBody,
        tolerance: f64,
    ) -> Vec<f64> {
        self.remove_sweeps(toolpath, &|from, to| body.sweep(from, to, tolerance))
    }

    fn remove_sweeps(
        &mut self,
        toolpath: &crate::geom::Toolpath,
        sweep: &(
             dyn Fn(&crate::geom::ToolPose, &crate::geom::ToolPose) -> Vec<cutter::SweptSolid>
                 + Sync
         ),
    ) -> Vec<f64> {
        let mut removed = vec![0.0; toolpath.moves.len()];
        let pairs: Vec<_> = toolpath.moves.windows(2).collect();
        for (c, batch) in pairs.chunks(replay::BATCH).enumerate() {
            let work: Vec<replay::MoveWork<cutter::SweptSolid>> = batch
                .par_iter()
                .map(|pair| replay::MoveWork {
                    cut: sweep(&pair[0].pose, &pair[1].pose),
                    ..Default::default()
                })
                .collect();
            let outcomes = replay::replay(self, None, &work, 0);
            for (k, outcome) in outcomes.into_iter().enumerate() {
                removed[c * replay::BATCH + k + 1] = outcome.removed_mm3;
            }
        }
        removed
    }

    /// The model as bytes ([`Stock::from_bytes`] reads them back): a magic word, the spacing,
    /// the box, then per grid its lines' span counts and spans, little-endian.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::new();
        out.extend_from_slice(MAGIC);
        let mut f = |v: f64| out.extend_from_slice(&v.to_le_bytes());
        f(self.spacing);
        for i in 0..3 {
            f(self.bounds.min[i]);
        }
        for i in 0..3 {
            f(self.bounds.max[i]);
        }
        for grid in &self.grids {
            for line in &grid.lines {
                out.extend_from_slice(&(line.len() as u32).to_le_bytes());
                for span in line {
                    out.extend_from_slice(&span.start.to_le_bytes());
                    out.extend_from_slice(&span.end.to_le_bytes());
                }
            }
        }
        out
    }

    /// Reads a model written by [`Stock::to_bytes`]; refuses anything else (wrong magic,
    /// truncated, spans out of order) with a reason, never a panic. `max_dexels` bounds the
    /// grids the header may ask for.
    pub fn from_bytes(bytes: &[u8], max_dexels: usize) -> Result<Self, StockError> {
        let bad = |why: &str| StockError::Format(why.to_string());
        let rest = bytes
            .strip_prefix(MAGIC.as_slice())
            .ok_or_else(|| bad("the file does not start with the stock magic word"))?;
        let mut reader = Reader { bytes: rest };
        let spacing = reader.f64()?;
        let min = Point3::new(reader.f64()?, reader.f64()?, reader.f64()?);
        let max = Point3::new(reader.f64()?, reader.f64()?, reader.f64()?);
        let mut stock = Self::empty(&Aabb { min, max }, spacing, max_dexels)?;
        for grid in &mut stock.grids {
            for line in &mut grid.lines {
                let count = reader.u32()? as usize;
                if count > reader.bytes.len() / 16 {
                    return Err(bad("a line claims more spans than the file holds"));
                }
                let mut last = f64::NEG_INFINITY;
                for _ in 0..count {
                    let (start, end) = (reader.f64()?, reader.f64()?);
                    if !(start > last && end > start && end.is_finite()) {
                        return Err(bad("spans out of order or not finite"));
                    }
                    last = end;
                    line.push(Span { start, end });
                }
            }
        }
        if !reader.bytes.is_empty() {
            return Err(bad("bytes left after the last line"));
        }
        Ok(stock)
    }
}

/// The first bytes of a saved stock (format version 1).
const MAGIC: &[u8; 8] = b"WMSTOCK1";

/// Reads little-endian numbers off the front of a byte slice.
struct Reader<'a> {
    bytes: &'a [u8],
}

impl Reader<'_> {
    fn take<const N: usize>(&mut self) -> Result<[u8; N], StockError> {
        let (head, tail) = self
            .bytes
            .split_first_chunk::<N>()
            .ok_or_else(|| StockError::Format("the file ends early".into()))?;
        self.bytes = tail;
        Ok(*head)
    }

    fn f64(&mut self) -> Result<f64, StockError> {
        Ok(f64::from_le_bytes(self.take()?))
    }

    fn u32(&mut self) -> Result<u32, StockError> {
        Ok(u32::from_le_bytes(self.take()?))
    }
}

/// The line `p + t·e_axis` inside the solid cylinder of `radius` about `base + s·k`,
/// `0 ≤ s ≤ length` (`k` unit).
fn cylinder_interval(
    axis: usize,
    p: &Point3,
    base: &Point3,
    k: &Vector3,
    radius: f64,
    length: f64,
) -> Option<(f64, f64)> {
    let mut o = *p;
    o[axis] = 0.0;
    let mut u = Vector3::zeros();
    u[axis] = 1.0;
    let w = o - base;
    // Radial: |w + t u − ((w + t u)·k) k|² ≤ r².
    let (wk, uk) = (w.dot(k), k[axis]);
    let a = 1.0 - uk * uk;
    let b = w[axis] - wk * uk;
    let c = w.norm_squared() - wk * wk - radius * radius;
    let (mut lo, mut hi) = if a <= 1e-15 {
        if c > 0.0 {
            return None;
        }
        (f64::NEG_INFINITY, f64::INFINITY)
    } else {
        let disc = b * b - a * c;
        if disc < 0.0 {
            return None;
        }
        let s = disc.sqrt();
        ((-b - s) / a, (-b + s) / a)
    };
    // Axial: 0 ≤ wk + t uk ≤ length.
    if uk.abs() > 1e-15 {
        let (t0, t1) = ((0.0 - wk) / uk, (length - wk) / uk);
        lo = lo.max(t0.min(t1));
        hi = hi.min(t0.max(t1));
    } else if !(0.0..=length).contains(&wk) {
        return None;
    }
    (lo < hi).then_some((lo, hi))
}

#[cfg(test)]
mod tests;
