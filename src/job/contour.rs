//! `wavemill contour`: one 2.5D outline machined two ways — the multiresolution wavelet + loose
//! convex hull paths of seed 004 ch. 3–4 ([`crate::contour::multires`]) and the
//! contour-parallel baseline ([`crate::contour::parallel`]) — with the same tool, stock and
//! stepover, verified and compared side by side (issue #6).
//!
//! The part is an SVG/DXF outline or the Z-section of a closed mesh (`.stl`, `.obj`, `.gltf`,
//! `.glb`, with `z`); the stock is the part's bounding box grown by a margin or a given outline
//! that must contain the part.
//!
//! Outputs (all in memory; [`write_contour_outputs`] writes them atomically): `wavelet.nc`,
//! `contour_parallel.nc`, `compare.json`, `paths.svg`, `paths.png`.
//!
//! Default stepover: 0.4 × D. Below r = D/2, so the baseline leaves no reachable material
//! (see [`crate::contour::parallel`]) and the wavelet passes get a band of (r − s)/2 = 0.05 × D
//! on each side of their nominal level to be simplified in.

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;

use super::output::{OutputKind, write_output_set};
use crate::contour::geometry::{Contour, Vertex};
use crate::contour::geometry::{Point2, Shape};
use crate::contour::material::{engagement, report_cell};
use crate::contour::region::{RegionIndex, check_inside};
use crate::contour::simplify::{OUTLINE_THINNING_TOL, thin_shape};
use crate::contour::{
    CenterPath, ContourError, CutDirection, MultiresOptions, MultiresReport, OutlineOptions,
    ParallelOptions, clearance, contour_parallel, mesh_section, multires_paths, pass_spacing,
    path_stats, read_outline, uncut_area,
};
use crate::error::{Error, JobError, Result};
use crate::mesh::{PrepareOptions, prepare as prepare_mesh};
use crate::post::{ContourProgram, GcodeOptions, PlanarParams};

/// Extensions (lower case) of the part files read as meshes and cut at `--z`; every other
/// file is read as an SVG/DXF outline.
const MESH_EXTENSIONS: [&str; 4] = ["stl", "obj", "gltf", "glb"];

/// The part and a stock outline must stay this far apart, mm (they must not touch).
const STOCK_GAP: f64 = 1e-9;

/// Largest coordinate accepted, mm (1000 km): no machine is near that size, and beyond it the
/// round-off of f64 coordinates (≈ 1e-7 mm) approaches the planners' tolerances. Anything
/// larger is an absurd scale or transform, refused naming the file.
const MAX_COORDINATE_MM: f64 = 1e9;

/// Default of [`ContourJobOptions::max_levels`]: 10,000 offset levels reach 24 m of stock
/// at a 2.4 mm stepover; the test outlines need fewer than 100.
pub const DEFAULT_MAX_LEVELS: usize = 10_000;

/// Default of [`ContourJobOptions::max_outline_vertices`]. The offset engine's work grows
/// with about the square of the part's vertices left after thinning where the outline is
/// all corners (measured on stars of narrow spikes, release build: 10,000 vertices 4.8 s and
/// 0.35 GB, 20,000 21 s and 1.1 GB, 40,000 over 120 s and 4.3 GB); smooth outlines thin to a
/// few thousand (a 100,000-point smooth star: 1.6 s).
pub const DEFAULT_MAX_OUTLINE_VERTICES: usize = 25_000;

/// The stock the region to machine is cut from.
#[derive(Clone, Debug, PartialEq)]
pub enum StockSpec {
    /// The part's bounding box grown by this margin, mm (≥ 0).
    Margin(f64),
    /// A closed outline (SVG or DXF, read like an outline part, with the same scale) that
    /// contains the part.
    Outline(PathBuf),
}

impl StockSpec {
    /// The `--stock` text of this stock, for reports.
    fn describe(&self) -> String {
        match self {
            StockSpec::Margin(m) => format!("margin:{m}"),
            StockSpec::Outline(p) => format!("outline:{}", file_name(p)),
        }
    }
}

/// Options of [`contour_compare`].
#[derive(Clone, Debug, PartialEq)]
pub struct ContourJobOptions {
    /// Flat end mill diameter D, mm.
    pub tool_diameter: f64,
    /// The stock: a rectangle around the part, or a given outline.
    pub stock: StockSpec,
    /// Height of the section plane, mm, when the part is a mesh (required then, refused for
    /// outline files).
    pub z: Option<f64>,
    /// Units of a mesh part: mm, m or in.
    pub units: String,
    /// Stepover, mm; `None` = 0.4 × D (see the module docs).
    pub stepover: Option<f64>,
    /// Band half-width τ of the wavelet passes around their level, mm; `None` =
    /// max(0, (r − s)/2). Wider bands give coarser passes and need adaptive curves (§3.5).
    pub band: Option<f64>,
    /// Outline scale (one outline unit = `scale` mm); outline files only (meshes: `units`).
    pub scale: f64,
    /// Which way the roughing passes may run (both methods).
    pub direction: CutDirection,
    /// Machine parameters and the time model.
    pub machine: PlanarParams,
    /// Keep the run-dependent `timings_ms` in `compare.json`.
    pub timings: bool,
    /// Largest number of offset levels (stock extent over stepover) a run may plan; a larger
    /// estimate is refused before any planning with [`Error::TooLarge`].
    pub max_levels: usize,
    /// Largest number of part vertices left after thinning (the offset engine's input); a
    /// larger part is refused before any planning with [`Error::TooLarge`].
    pub max_outline_vertices: usize,
}

impl ContourJobOptions {
    /// Tool diameter and stock margin; default stepover, scale 1, mm, no section plane,
    /// default machine, timings on.
    pub fn new(tool_diameter: f64, stock_margin: f64) -> Self {
        Self {
            tool_diameter,
            stock: StockSpec::Margin(stock_margin),
            z: None,
            units: "mm".into(),
            stepover: None,
            band: None,
            scale: 1.0,
            direction: CutDirection::default(),
            machine: PlanarParams::default(),
            timings: true,
            max_levels: DEFAULT_MAX_LEVELS,
            max_outline_vertices: DEFAULT_MAX_OUTLINE_VERTICES,
        }
    }
}

/// The figures of one method in `compare.json`.
#[derive(Clone, Debug, Serialize)]
pub struct MethodFigures {
    /// min distance tool centre → part − r over the cutting moves, mm (≥ −1e-6: no overcut).
    pub min_clearance_minus_r_mm: f64,
    pub uncut_area_mm2: f64,
    /// Pass length, mm (feed links are reported apart).
    pub cutting_length_mm: f64,
    pub feed_link_length_mm: f64,
    pub passes: usize,
    pub nc_blocks: usize,
    pub machining_time_min: f64,
    /// Largest and 95th-percentile distance between a pass and the next pass toward the
    /// part, mm (sampled; see `verify::pass_spacing`).
    pub pass_spacing_max_mm: f64,
    pub pass_spacing_max_at: [f64; 2],
    pub pass_spacing_p95_mm: f64,
    /// Links made by retract, rapid and plunge (each 3 blocks and a plunge at feed).
    pub rapid_links: usize,
    /// Traverses at cutting depth through the air beside the stock (one block each, at the
    /// rapid rate), and the area they removed on the material map (nothing, as planned).
    pub traverse_links: usize,
    pub traverse_area_mm2: f64,
    /// Radial engagement replayed on a material map (`contour::material`, cells of
    /// min(r, s)/16, averaged over r of travel): the passes' largest, 99th-percentile and mean
    /// engagement (mean = area removed by the passes / pass length), mm, and the feed links'
    /// largest (a step-over link meets up to a full-width slot for a moment).
    pub engagement_max_mm: f64,
    pub engagement_max_at: [f64; 2],
    pub engagement_p99_mm: f64,
    pub engagement_mean_mm: f64,
    pub link_engagement_max_mm: f64,
    /// Area removed by the passes, by the plunges and by the feed links, mm² (on the map).
    pub pass_area_mm2: f64,
    pub entry_area_mm2: f64,
    pub link_area_mm2: f64,
    /// Most material one plunge went into, mm² (π r² = straight down into uncut stock).
    pub entry_area_max_mm2: f64,
    /// The time split of the model: feed (cut, feed links, plunges), rapid, block dwell.
    pub feed_min: f64,
    pub rapid_min: f64,
    pub dwell_min: f64,
}

/// Relative differences, wavelet vs contour-parallel, percent (negative = wavelet smaller).
#[derive(Clone, Debug, Serialize)]
pub struct Differences {
    pub cutting_length_pct: f64,
    pub nc_blocks_pct: f64,
    pub machining_time_pct: f64,
    pub uncut_area_mm2: f64,
}

/// Milliseconds per stage; the only run-dependent part of `compare.json`.
#[derive(Clone, Debug, Serialize)]
pub struct ContourTimings {
    pub read: f64,
    pub wavelet: f64,
    pub contour_parallel: f64,
    pub verify: f64,
}

/// `compare.json`.
#[derive(Clone, Debug, Serialize)]
pub struct CompareReport {
    pub outline: String,
    pub tool_diameter_mm: f64,
    pub stepover_mm: f64,
    /// `margin:M` or `outline:FILE`, as given.
    pub stock: String,
    /// Cut direction of the roughing passes, both methods: `climb` or `mixed`.
    pub cut_direction: String,
    /// Height of the section plane when the part is a mesh, mm.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub section_z_mm: Option<f64>,
    pub scale: f64,
    /// (stock − part) area, mm², and that area divided by the stepover: the length a path
    /// with passes exactly one stepover apart would need, mm.
    pub region_area_mm2: f64,
    pub area_over_stepover_mm: f64,
    /// Machine model: feed mm/min, dwell s per block, rapid mm/min.
    pub feed_mm_per_min: f64,
    pub dwell_s_per_block: f64,
    pub rapid_mm_per_min: f64,
    pub uncut_row_step_mm: f64,
    pub contour_parallel: MethodFigures,
    pub wavelet: MethodFigures,
    pub wavelet_vs_parallel: Differences,
    pub wavelet_planner: PlannerFigures,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub timings_ms: Option<ContourTimings>,
}

/// What the multiresolution planner did.
#[derive(Clone, Debug, Serialize)]
pub struct PlannerFigures {
    pub band_tolerance_mm: f64,
    /// Largest measured deviation of a part level's passes from its exact offset, mm.
    pub max_pass_deviation_mm: f64,
    /// Adaptive curves (seed 004 §3.5, eq. 3.3) inserted where consecutive part levels ended
    /// up more than max(r, s) apart, and the offset loops they made.
    pub adaptive_curves: usize,
    pub adaptive_loops: usize,
    pub part_levels: usize,
    pub hull_levels: usize,
    pub hull_legs: usize,
    pub loose_hull_legs: usize,
    pub wavelet_loops: usize,
    pub exact_loops: usize,
    pub corners: usize,
    pub smooth_regions: usize,
    pub non_smooth_regions: usize,
    pub wavelet_levels_dropped: u32,
}

impl From<&MultiresReport> for PlannerFigures {
    fn from(r: &MultiresReport) -> Self {
        Self {
            band_tolerance_mm: r.tolerance,
            max_pass_deviation_mm: r.max_deviation,
            adaptive_curves: r.adaptive_curves,
            adaptive_loops: r.adaptive_loops,
            part_levels: r.part_levels,
            hull_levels: r.hull_levels,
            hull_legs: r.hull_legs,
            loose_hull_legs: r.loose_hull_legs,
            wavelet_loops: r.wavelet_loops,
            exact_loops: r.exact_fallbacks,
            corners: r.corners,
            smooth_regions: r.smooth_regions,
            non_smooth_regions: r.non_smooth_regions,
            wavelet_levels_dropped: r.levels_dropped,
        }
    }
}

/// Everything `wavemill contour --compare` writes, in memory.
#[derive(Clone, Debug)]
pub struct ContourComparison {
    pub wavelet_nc: String,
    pub parallel_nc: String,
    pub report: CompareReport,
    pub svg: String,
    pub png: Vec<u8>,
}

impl ContourComparison {
    /// `compare.json` text.
    pub fn json(&self) -> String {
        serde_json::to_string_pretty(&self.report).unwrap_or_default() + "\n"
    }
}

fn ms(t: Instant) -> f64 {
    (t.elapsed().as_secs_f64() * 1e5).round() / 100.0
}

fn contour_error(file: &str) -> impl Fn(ContourError) -> Error + '_ {
    move |error| Error::Contour {
        file: file.to_string(),
        error,
    }
}

/// An option out of its range, named as the options struct names it (the CLI names its flag).
fn invalid_option(key: &str, reason: String) -> Error {
    Error::JobFile(JobError::Invalid {
        key: key.to_string(),
        reason,
    })
}

/// An option that does not fit the file it applies to.
fn invalid_for_file(file: &str, key: &str, reason: String) -> Error {
    Error::JobFile(JobError::InFile {
        file: file.to_string(),
        error: Box::new(JobError::Invalid {
            key: key.to_string(),
            reason,
        }),
    })
}

/// The inputs of a run, read and checked.
struct Prepared {
    file: String,
    part: Shape,
    stock: Shape,
    r: f64,
    s: f64,
    row_step: f64,
    read_ms: f64,
    /// The section height, when the part is a mesh.
    z: Option<f64>,
}

fn prepare(outline: &Path, opts: &ContourJobOptions) -> Result<Prepared> {
    let file = outline.display().to_string();
    let d = opts.tool_diameter;
    if !(d.is_finite() && d > 0.0) {
        return Err(invalid_option(
            "tool_diameter",
            format!("= {d}: must be > 0 mm"),
        ));
    }
    let s = opts.stepover.unwrap_or(0.4 * d);
    if !(s.is_finite() && s > 0.0 && s <= d) {
        return Err(invalid_option(
            "stepover",
            format!("= {s}: must satisfy 0 < stepover ≤ tool diameter {d}"),
        ));
    }
    if let Some(b) = opts.band
        && !(b.is_finite() && b >= 0.0)
    {
        return Err(invalid_option(
            "band",
            format!("= {b}: must be a finite number of mm ≥ 0"),
        ));
    }
    if !(opts.scale.is_finite() && opts.scale > 0.0) {
        return Err(invalid_option(
            "scale",
            format!(
                "= {}: must be a positive finite number (mm per outline unit)",
                opts.scale
            ),
        ));
    }
    if let StockSpec::Margin(margin) = &opts.stock
        && !(margin.is_finite() && *margin >= 0.0)
    {
        return Err(invalid_option(
            "stock",
            format!("margin {margin}: the margin must be ≥ 0 mm"),
        ));
    }
    let t = Instant::now();
    let outline_opts = OutlineOptions {
        scale: opts.scale,
        ..Default::default()
    };
    let (part, z) = read_part(outline, opts, &outline_opts)?;
    let stock = match &opts.stock {
        StockSpec::Margin(margin) => stock_around(&part, *margin).ok_or_else(|| Error::Mesh {
            file: file.clone(),
            reason: "the outline has no points".into(),
        })?,
        StockSpec::Outline(path) => {
            let stock = read_outline(path, &outline_opts)?;
            check_inside(&part, &stock, STOCK_GAP).map_err(|e| Error::Mesh {
                file: file_name(path),
                reason: format!(
                    "the part {} {} at ({:.4}, {:.4}) mm; the part must lie inside the stock",
                    file_name(outline),
                    e.reason,
                    e.at.x,
                    e.at.y
                ),
            })?;
            stock
        }
    };
    check_coordinates(&part, &file)?;
    check_coordinates(&stock, &file)?;
    let bounds = stock_bounds(&stock);
    check_levels(&file, bounds, s, opts.max_levels)?;
    check_outline_vertices(&file, &part, opts.max_outline_vertices)?;
    Ok(Prepared {
        file,
        part,
        stock,
        r: 0.5 * d,
        s,
        row_step: (bounds.1.x - bounds.0.x).max(bounds.1.y - bounds.0.y) / 4000.0,
        read_ms: ms(t),
        z,
    })
}

/// Refuses coordinates that are not finite or beyond [`MAX_COORDINATE_MM`] (an absurd
/// `--scale` or SVG transform), naming the file.
fn check_coordinates(shape: &Shape, file: &str) -> Result<()> {
    let largest = shape
        .contours
        .iter()
        .flat_map(|c| &c.vertices)
        .map(|v| v.point.x.abs().max(v.point.y.abs()))
        .fold(
            0.0,
            |a: f64, b| if b.is_nan() { f64::INFINITY } else { a.max(b) },
        );
    if largest <= MAX_COORDINATE_MM {
        return Ok(());
    }
    Err(Error::Mesh {
        file: file.to_string(),
        reason: format!(
            "coordinates reach {largest:.3e} mm, beyond {MAX_COORDINATE_MM:.0e} mm (no machine \
             is that large); check the scale and the file's units and transforms"
        ),
    })
}

/// Refuses a run whose offset levels — the stock's extent over the stepover, the passes each
/// planner makes outward from the part — are estimated above `max_levels`, before any of them
/// is computed (each is an offset of the whole part, so work and memory grow with them).
fn check_levels(file: &str, bounds: (Point2, Point2), s: f64, max_levels: usize) -> Result<()> {
    let extent = (bounds.1 - bounds.0).norm();
    let levels = (extent / s).ceil() + 1.0;
    if levels <= max_levels as f64 {
        return Ok(());
    }
    Err(Error::TooLarge {
        what: format!("{file}: a stock {extent:.4e} mm across at a stepover of {s:.4} mm"),
        estimate: format!("{levels:.3e} offset levels"),
        limit: format!("{max_levels} levels"),
        advice: "check the scale and the stepover".into(),
        limit_key: "max_levels".into(),
    })
}

/// Refuses a part whose outline, thinned as the offset engine will see it, keeps more than
/// `limit` vertices (see [`DEFAULT_MAX_OUTLINE_VERTICES`]), before any offset is computed.
fn check_outline_vertices(file: &str, part: &Shape, limit: usize) -> Result<()> {
    let thinned = thin_shape(part, OUTLINE_THINNING_TOL);
    let vertices: usize = thinned.contours.iter().map(|c| c.vertices.len()).sum();
    if vertices <= limit {
        return Ok(());
    }
    let given: usize = part.contours.iter().map(|c| c.vertices.len()).sum();
    Err(Error::TooLarge {
        what: format!(
            "{file}: a part outline of {given} vertices, {vertices} of them corners the offset \
             engine must keep (within {OUTLINE_THINNING_TOL} mm)"
        ),
        estimate: format!("{vertices} vertices (offset work grows with their square)"),
        limit: format!("{limit} vertices"),
        advice: "simplify the outline".into(),
        limit_key: "max_outline_vertices".into(),
    })
}

/// Refuses a path without a cutting pass: the stock leaves nothing to machine around the
/// part (no program is written).
fn check_something_to_cut(p: &Prepared, path: &CenterPath, name: &str) -> Result<()> {
    if !path.passes().is_empty() {
        return Ok(());
    }
    Err(Error::NothingToCut(format!(
        "{}: the {name} path has no pass: no material of the stock lies outside the part \
         (a stock margin of 0, or a stock outline that hugs the part?)",
        p.file
    )))
}

fn file_name(path: &Path) -> String {
    path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

/// The part: an SVG/DXF outline, or the section of a mesh (chosen by the extension) at
/// `opts.z`, which a mesh needs and an outline refuses. Returns the shape and the Z used.
fn read_part(
    path: &Path,
    opts: &ContourJobOptions,
    outline_opts: &OutlineOptions,
) -> Result<(Shape, Option<f64>)> {
    let name = file_name(path);
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    let is_mesh = ext.as_deref().is_some_and(|e| MESH_EXTENSIONS.contains(&e));
    if !is_mesh {
        if let Some(z) = opts.z {
            return Err(invalid_for_file(
                &name,
                "z",
                format!(
                    "= {z} applies to mesh parts (.stl, .obj, .gltf, .glb) only; an outline \
                     file is already planar"
                ),
            ));
        }
        let part = read_outline(path, outline_opts)?;
        return Ok((part, None));
    }
    let Some(z) = opts.z else {
        return Err(invalid_for_file(
            &name,
            "z",
            "is needed for a mesh part: the height (mm) of the plane that cuts the outline \
             from it"
                .into(),
        ));
    };
    if opts.scale != 1.0 {
        return Err(invalid_for_file(
            &name,
            "scale",
            "applies to outline files; give a mesh's units instead".into(),
        ));
    }
    let raw = super::load_part(path, &opts.units)?;
    // Welding joins the triangles of STL-like files, so the section can chain them.
    let (mesh, _) =
        prepare_mesh(&raw.mesh, &PrepareOptions::default()).map_err(|reason| Error::Mesh {
            file: name.clone(),
            reason: reason.to_string(),
        })?;
    let part = mesh_section(&mesh, z, outline_opts.tolerance, &name)?;
    Ok((part, Some(z)))
}

/// Verifies and measures one path; refuses a path that cuts into the part. Returns the
/// figures, the G-code and the (stock − part) area of the uncut-area quadrature.
fn method_figures(
    p: &Prepared,
    path: &CenterPath,
    machine: &PlanarParams,
    name: &str,
) -> Result<(MethodFigures, String, f64)> {
    let file = p.file.as_str();
    let program =
        ContourProgram::new(path, machine, &GcodeOptions::default()).map_err(|error| {
            Error::ContourPost {
                file: file.to_string(),
                error,
            }
        })?;
    let st = program.stats();
    let c = clearance(path, &p.part).map_err(contour_error(file))?;
    if c.clearance < -1e-6 {
        return Err(Error::Verification(format!(
            "{file}: the {name} path cuts {:.6} mm into the part at ({:.4}, {:.4})",
            -c.clearance, c.at.x, c.at.y
        )));
    }
    let u = uncut_area(path, &p.part, &p.stock, Some(p.row_step)).map_err(contour_error(file))?;
    let sp = pass_spacing(path, &p.part, 0.5 * p.s, 0.25 * p.s).map_err(contour_error(file))?;
    let ps = path_stats(path);
    let e = engagement(path, &p.part, &p.stock, report_cell(p.r, p.s), p.r)
        .map_err(contour_error(file))?;
    Ok((
        MethodFigures {
            min_clearance_minus_r_mm: c.clearance,
            uncut_area_mm2: u.uncut,
            cutting_length_mm: ps.cut_length,
            feed_link_length_mm: ps.feed_link_length,
            passes: ps.passes,
            nc_blocks: st.blocks,
            machining_time_min: st.total_minutes,
            pass_spacing_max_mm: sp.max,
            pass_spacing_max_at: [sp.max_at.x, sp.max_at.y],
            pass_spacing_p95_mm: sp.p95,
            rapid_links: ps.rapid_links,
            traverse_links: ps.traverse_links,
            traverse_area_mm2: e.traverse_area,
            engagement_max_mm: e.pass_max,
            engagement_max_at: [e.pass_max_at.x, e.pass_max_at.y],
            engagement_p99_mm: e.pass_p99,
            engagement_mean_mm: e.pass_mean,
            link_engagement_max_mm: e.link_max,
            pass_area_mm2: e.pass_area,
            entry_area_mm2: e.entry_area,
            link_area_mm2: e.link_area,
            entry_area_max_mm2: e.entry_max,
            feed_min: st.feed_minutes,
            rapid_min: st.rapid_minutes,
            dwell_min: st.dwell_minutes,
        },
        program.to_gcode(&program.header(&file_name(Path::new(file)))),
        u.region,
    ))
}

fn multires_options(p: &Prepared, opts: &ContourJobOptions) -> MultiresOptions {
    let mut m = MultiresOptions::new(p.r, p.s);
    m.tolerance = opts.band;
    m.direction = opts.direction;
    m
}

/// Reads `outline` and plans, verifies and posts the multiresolution path only (no baseline):
/// its G-code and figures.
pub fn contour_wavelet(
    outline: &Path,
    opts: &ContourJobOptions,
) -> Result<(String, MethodFigures)> {
    let p = prepare(outline, opts)?;
    let plan = multires_paths(&p.part, &p.stock, &multires_options(&p, opts))
        .map_err(contour_error(&p.file))?;
    check_something_to_cut(&p, &plan.path, "wavelet")?;
    let (figures, nc, _) = method_figures(&p, &plan.path, &opts.machine, "wavelet")?;
    Ok((nc, figures))
}

/// Reads `outline`, plans both methods, verifies and compares them.
pub fn contour_compare(outline: &Path, opts: &ContourJobOptions) -> Result<ContourComparison> {
    let p = prepare(outline, opts)?;
    let (file, part, stock, r, s) = (&p.file, &p.part, &p.stock, p.r, p.s);
    let t = Instant::now();
    let plan =
        multires_paths(part, stock, &multires_options(&p, opts)).map_err(contour_error(file))?;
    let t_wavelet = ms(t);
    let t = Instant::now();
    let base = contour_parallel(
        part,
        stock,
        &ParallelOptions {
            direction: opts.direction,
            ..ParallelOptions::new(r, s)
        },
    )
    .map_err(contour_error(file))?;
    let t_parallel = ms(t);
    check_something_to_cut(&p, &plan.path, "wavelet")?;
    check_something_to_cut(&p, &base, "contour-parallel")?;

    let t = Instant::now();
    let (wf, wavelet_nc, region) = method_figures(&p, &plan.path, &opts.machine, "wavelet")?;
    let (pf, parallel_nc, _) = method_figures(&p, &base, &opts.machine, "contour-parallel")?;
    let t_verify = ms(t);
    let pct = |a: f64, b: f64| if b != 0.0 { 100.0 * (a - b) / b } else { 0.0 };
    let diff = Differences {
        cutting_length_pct: pct(wf.cutting_length_mm, pf.cutting_length_mm),
        nc_blocks_pct: pct(wf.nc_blocks as f64, pf.nc_blocks as f64),
        machining_time_pct: pct(wf.machining_time_min, pf.machining_time_min),
        uncut_area_mm2: wf.uncut_area_mm2 - pf.uncut_area_mm2,
    };
    let report = CompareReport {
        outline: outline
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default(),
        tool_diameter_mm: 2.0 * r,
        stepover_mm: s,
        stock: opts.stock.describe(),
        cut_direction: match opts.direction {
            CutDirection::Climb => "climb",
            CutDirection::Mixed => "mixed",
        }
        .into(),
        section_z_mm: p.z,
        scale: opts.scale,
        region_area_mm2: region,
        area_over_stepover_mm: region / s,
        feed_mm_per_min: opts.machine.feed,
        dwell_s_per_block: opts.machine.dwell_per_block,
        rapid_mm_per_min: opts.machine.rapid,
        uncut_row_step_mm: p.row_step,
        contour_parallel: pf,
        wavelet: wf,
        wavelet_vs_parallel: diff,
        wavelet_planner: PlannerFigures::from(&plan.report),
        timings_ms: opts.timings.then_some(ContourTimings {
            read: p.read_ms,
            wavelet: t_wavelet,
            contour_parallel: t_parallel,
            verify: t_verify,
        }),
    };
    let picture =
        super::contour_picture::Picture::new(part, stock, &base, &plan.path, &plan.loose_hull);
    Ok(ContourComparison {
        wavelet_nc,
        parallel_nc,
        report,
        svg: picture.svg(),
        png: picture.png(1600).map_err(|e| Error::Io {
            path: format!("{file}: the paths picture"),
            source: std::io::Error::other(e.to_string()),
        })?,
    })
}

/// Writes the five outputs of [`contour_compare`] into `dir` as one set, replacing an earlier
/// run's (see `job::output`).
pub fn write_contour_outputs(dir: &Path, c: &ContourComparison) -> Result<()> {
    write_output_set(
        dir,
        &OutputKind::CONTOUR,
        &[
            ("wavelet.nc".to_string(), c.wavelet_nc.clone().into_bytes()),
            (
                "contour_parallel.nc".to_string(),
                c.parallel_nc.clone().into_bytes(),
            ),
            ("compare.json".to_string(), c.json().into_bytes()),
            ("paths.svg".to_string(), c.svg.clone().into_bytes()),
            ("paths.png".to_string(), c.png.clone()),
        ],
    )
}

fn stock_bounds(stock: &Shape) -> (Point2, Point2) {
    let idx = RegionIndex::new(stock);
    idx.boundary()
        .bounds()
        .map_or((Point2::origin(), Point2::origin()), |b| (b.min, b.max))
}

/// The part's bounding box (exact for arcs) grown by `margin`, as a counter-clockwise
/// rectangle.
fn stock_around(part: &Shape, margin: f64) -> Option<Shape> {
    let b = RegionIndex::new(part).boundary().bounds()?;
    let (lo, hi) = (b.min, b.max);
    let (x0, y0, x1, y1) = (lo.x - margin, lo.y - margin, hi.x + margin, hi.y + margin);
    Some(Shape {
        contours: vec![Contour {
            vertices: vec![
                Vertex::line(x0, y0),
                Vertex::line(x1, y0),
                Vertex::line(x1, y1),
                Vertex::line(x0, y1),
            ],
        }],
    })
}
