//! The `wavemill` command line: a thin shell over the library. Each subcommand parses its
//! arguments, calls one library function, prints a summary and maps errors to exit codes
//! (0 success, 1 bad input or I/O, 2 usage, 3 the planned path failed verification).

mod progress;

/// `println!` that ignores a closed stdout: `wavemill info PART | head` must end quietly,
/// not panic on the broken pipe.
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout().lock(), $($arg)*);
    }};
}

use std::path::{Path, PathBuf};

use clap::{Args, Parser, Subcommand, ValueEnum};

use crate::error::{Error, Result};
use crate::job::{self, Job, SamplePart, sample_files};
use crate::mesh::io::{GlbBuilder, write_obj};
use crate::mesh::{PrepareOptions, prepare};
use crate::multires;
use crate::sample;
use crate::tool::{Cutter, parse_cutter};

#[derive(Parser, Debug)]
#[command(
    name = "wavemill",
    version,
    about = "Multiresolution 5-axis toolpaths for impellers, blisks and blades"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Print what a mesh file contains: size, topology, problems, units guess.
    Info(InfoArgs),
    /// Generate a sample part (GLB and OBJ), deterministically.
    Sample(SampleArgs),
    /// Plan 5-axis ball-end finishing of a part and write G-code, CL data, a report and a preview.
    Plan(PlanArgs),
    /// Loop-subdivide a mesh N times (plain Loop; creases only when asked) and write OBJ or GLB.
    Subdivide(SubdivideArgs),
    /// Remesh a part to a rough-to-fine hierarchy, analyse it with wavelets, write every level.
    Levels(LevelsArgs),
    /// Visibility maps: from which directions each point of the part can be seen (heat-map GLB,
    /// statistics), and for query points the visible count and the tool axis.
    Access(AccessArgs),
    /// 2.5D profile: multiresolution wavelet + loose convex hull paths (seed 004 ch. 3–4),
    /// verified, as G-code; with --compare also the contour-parallel baseline side by side.
    Contour(ContourArgs),
    /// Build the nested rough-to-fine intermediate shapes (offsets of the levels that never
    /// overcut the part), verify them against the part and write them.
    Offsets(OffsetsArgs),
    /// Propose tools from a library, largest first: which tool finishes which region of the
    /// part (curvature, the largest ball that fits, accessibility of the whole assembly).
    Tools(ToolsArgs),
}

#[derive(Args, Debug)]
pub struct ToolsArgs {
    /// Part mesh (.stl, .obj, .gltf, .glb), closed.
    pub part: PathBuf,
    /// Tool library (TOML, one `[[tool]]` table per tool; see data/tools.toml).
    #[arg(long)]
    pub library: PathBuf,
    /// Units of the part file: mm, m or in.
    #[arg(long, default_value = "mm", value_parser = units)]
    pub units: String,
    /// How far a cutting end may dip into the part, mm.
    #[arg(long, default_value_t = 0.01, value_parser = non_negative)]
    pub tolerance: f64,
    /// At most this many points (vertices, thinned evenly) are evaluated.
    #[arg(long, default_value_t = 20_000, value_parser = clap::value_parser!(u64).range(1..=10_000_000))]
    pub points: u64,
    /// Largest angle between the tool axis and the surface normal, degrees (0 to 90).
    #[arg(long, default_value_t = 90.0, value_parser = tilt)]
    pub max_tilt: f64,
    /// Leave out the machine table (by default the part stands on it at its lowest point and
    /// every tool stays 2 mm above it).
    #[arg(long)]
    pub no_table: bool,
    /// Leave the run-dependent timings out of tools.json (byte-identical reports).
    #[arg(long)]
    pub no_timings: bool,
    /// Output folder: tools.json and tools.glb.
    #[arg(long)]
    pub out: PathBuf,
}

#[derive(Args, Debug)]
pub struct AccessArgs {
    /// Part mesh (.stl, .obj, .gltf, .glb).
    pub part: PathBuf,
    /// Size K of the direction set (subdivided icosahedron): 12, 42, 162, 642, 2562 or 10242.
    #[arg(long, default_value_t = 642)]
    pub directions: usize,
    /// Cutter for the query axes, e.g. `ball:6` (diameter in mm) [default: the job default].
    #[arg(long, value_parser = ball_spec)]
    pub tool: Option<String>,
    /// Query points: CSV with a header x,y,z,nx,ny,nz; writes query.csv with, per point, the
    /// visible directions, K and the chosen tool axis (feed +X projected into the tangent plane).
    #[arg(long)]
    pub query: Option<PathBuf>,
    /// Units of the part file: mm, m or in.
    #[arg(long, default_value = "mm", value_parser = units)]
    pub units: String,
    /// Leave the run-dependent timings out of access.json (byte-identical reports).
    #[arg(long)]
    pub no_timings: bool,
    /// Output folder: access.glb, access.json and, with --query, query.csv.
    #[arg(long)]
    pub out: PathBuf,
}

#[derive(Args, Debug)]
pub struct ContourArgs {
    /// The part: an outline file (.svg or .dxf, one or more closed paths), or a closed mesh
    /// (.stl, .obj, .gltf, .glb) cut at the height given by --z.
    pub outline: PathBuf,
    /// Height of the plane that cuts a mesh part, mm (mesh parts only).
    #[arg(long, allow_negative_numbers = true)]
    pub z: Option<f64>,
    /// Units of a mesh part: mm, m or in.
    #[arg(long, default_value = "mm", value_parser = units)]
    pub units: String,
    /// Flat end mill, `flat:D` with the diameter D in mm.
    #[arg(long)]
    pub tool: String,
    /// Stock: `margin:M`, the part's bounding box grown by M mm, or `outline:FILE`, a closed
    /// SVG/DXF outline (same --scale) that contains the part.
    #[arg(long)]
    pub stock: String,
    /// Stepover between passes, mm (0 < S ≤ D). Default 0.4 × D: below the tool radius, so
    /// contour-parallel offsets leave no reachable material and the wavelet passes have a
    /// band of 0.05 × D each side of their level to be simplified in.
    #[arg(long)]
    pub stepover: Option<f64>,
    /// Band half-width of the wavelet passes around their offset level, mm [default:
    /// (D/2 − S)/2, ≥ 0]. A wider band gives coarser passes; where they end up more than
    /// max(D/2, S) apart, adaptive curves (seed 004 eq. 3.3) are inserted.
    #[arg(long)]
    pub band: Option<f64>,
    /// One outline unit is this many mm (outline files and a stock outline).
    #[arg(long, default_value_t = 1.0)]
    pub scale: f64,
    /// Which way the roughing passes run, both methods. `mixed`: an open roughing pass (an
    /// offset loop cut off by the stock or the hull) starts at its nearer end, so neighbouring
    /// fragments join at depth instead of by a retract each; `climb`: every pass climb.
    /// Closed passes and the finishing contour are always climb (M3 spindle).
    #[arg(long, value_enum, default_value_t = Direction::Mixed)]
    pub direction: Direction,
    /// Also write the contour-parallel baseline (contour_parallel.nc), compare.json and
    /// paths.svg / paths.png with both paths side by side.
    #[arg(long)]
    pub compare: bool,
    /// Leave the run-dependent timings out of compare.json (byte-identical outputs).
    #[arg(long)]
    pub no_timings: bool,
    /// Refuse a run estimated to need more offset levels than this (the stock's extent over
    /// the stepover; each level offsets the whole part), before planning anything.
    #[arg(long, default_value_t = job::DEFAULT_MAX_LEVELS)]
    pub max_levels: usize,
    /// Refuse a part whose outline keeps more vertices than this after thinning within
    /// 0.1 µm (the offset engine's work grows with their square), before planning anything.
    #[arg(long, default_value_t = job::DEFAULT_MAX_OUTLINE_VERTICES)]
    pub max_outline_vertices: usize,
    /// Output folder.
    #[arg(long)]
    pub out: PathBuf,
}

#[derive(Args, Debug)]
pub struct OffsetsArgs {
    /// Mesh file (.stl, .obj, .gltf, .glb): a manifold surface.
    pub part: PathBuf,
    /// Stock to leave per shape, mm, strictly decreasing, e.g. `1.0,0.5,0.2,0`. Shape j
    /// offsets hierarchy level j (the finest level for the shapes beyond it).
    #[arg(
        long,
        value_delimiter = ',',
        required = true,
        allow_negative_numbers = true
    )]
    pub allowances: Vec<f64>,
    /// Ball cutter, e.g. `ball:6` (diameter in mm): the shapes become tool-centre surfaces,
    /// offset by the ball radius as well.
    #[arg(long, value_parser = ball_spec)]
    pub tool: Option<String>,
    /// Units of the input file: mm, m or in.
    #[arg(long, default_value = "mm", value_parser = units)]
    pub units: String,
    /// Fitting tolerance of the finest level, mm (0: always build one level per allowance).
    #[arg(long, default_value_t = 0.0, value_parser = non_negative)]
    pub tolerance: f64,
    /// Triangles of the base (coarsest) mesh.
    #[arg(long, default_value_t = 2000)]
    pub base_triangles: usize,
    /// Stop simplifying the base when a collapse would move the surface more than this, mm.
    /// Absent: `--base-triangles` alone sizes the base (coarse levels, simple rough shapes);
    /// a bound keeps fillets and thin blades, for tighter shapes with more triangles.
    #[arg(long, value_parser = non_negative)]
    pub base_max_error: Option<f64>,
    /// At most this many levels above the base, 0 to 6 (default: one per allowance after the
    /// first; each level multiplies the triangles by 4).
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=6))]
    pub max_levels: Option<u32>,
    /// Edges whose faces meet at more than this angle (degrees) are feature lines.
    #[arg(long, default_value_t = 40.0, value_parser = face_angle)]
    pub crease_angle: f64,
    /// Finest grid the shapes are extracted on: at most this many cells across the part's
    /// bounding box (more: tighter shapes near the part, more triangles and time), 4 to 2000.
    #[arg(long, default_value_t = 300.0, value_parser = grid_cells)]
    pub grid_cells: f64,
    /// Leave the timings out of offsets.json (byte-identical reports).
    #[arg(long)]
    pub no_timings: bool,
    /// Output folder: `offset-<j>.glb` and `offsets.json`.
    #[arg(long)]
    pub out: PathBuf,
}

#[derive(Args, Debug)]
pub struct LevelsArgs {
    /// Mesh file (.stl, .obj, .gltf, .glb): a manifold surface.
    pub part: PathBuf,
    /// Units of the input file: mm, m or in.
    #[arg(long, default_value = "mm", value_parser = units)]
    pub units: String,
    /// Fitting tolerance: two-sided Hausdorff distance of the finest level to the part, mm.
    #[arg(long, default_value_t = 0.01, value_parser = positive)]
    pub tolerance: f64,
    /// Triangles of the base (coarsest) mesh.
    #[arg(long, default_value_t = 2000)]
    pub base_triangles: usize,
    /// Stop simplifying the base earlier when a collapse would move the surface more than
    /// this, mm: keeps thin blades and fillets in the base [default: 3 × tolerance].
    #[arg(long, value_parser = non_negative)]
    pub base_max_error: Option<f64>,
    /// At most this many levels above the base, 0 to 6 (each multiplies the triangles by 4).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(0..=6))]
    pub max_levels: u32,
    /// Edges whose faces meet at more than this angle (degrees) are feature lines, followed
    /// exactly by every level.
    #[arg(long, default_value_t = 40.0, value_parser = face_angle)]
    pub crease_angle: f64,
    /// Tangential relaxation passes over each level's new vertices (each followed by
    /// re-projection onto the part); off by default: it evens the triangles but loosens the fit.
    #[arg(long, default_value_t = 0)]
    pub relax_passes: u32,
    /// Plain lifting, without the k-disk least-squares update that brings the coarse levels
    /// closer to the part (measured: L∞ deviation of the base 2-4x smaller with it).
    #[arg(long)]
    pub plain_lifting: bool,
    /// Leave the timings out of levels.json (byte-identical reports).
    #[arg(long)]
    pub no_timings: bool,
    /// Output folder: `level-<j>.glb` and `levels.json`.
    #[arg(long)]
    pub out: PathBuf,
}

#[derive(Args, Debug)]
pub struct SubdivideArgs {
    /// Mesh file (.stl, .obj, .gltf, .glb).
    pub part: PathBuf,
    /// Number of 1-to-4 subdivision steps, 0 to 8.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(0..=8))]
    pub levels: u32,
    /// Treat edges whose faces meet at more than this angle (degrees) as sharp creases.
    #[arg(long, value_parser = face_angle)]
    pub crease_angle: Option<f64>,
    /// Refuse to make more triangles than this (each level multiplies them by 4; a triangle
    /// of the result costs about 100 bytes while it is built).
    #[arg(long, default_value_t = 20_000_000)]
    pub max_triangles: u64,
    /// Units of the input file: mm, m or in.
    #[arg(long, default_value = "mm", value_parser = units)]
    pub units: String,
    /// Output file; `.obj` or `.glb`.
    #[arg(long)]
    pub out: PathBuf,
}

#[derive(Args, Debug)]
pub struct InfoArgs {
    /// Mesh file (.stl, .obj, .gltf, .glb).
    pub part: PathBuf,
    /// Units the file is written in.
    #[arg(long, default_value = "mm", value_parser = units)]
    pub units: String,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum Direction {
    /// Every pass climb milling.
    Climb,
    /// Open roughing passes either way (zig-zag), closed and finishing passes climb.
    Mixed,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum SampleKind {
    /// A centrifugal impeller: hub with a bore, twisted blades, narrow channels.
    Impeller,
    /// A twisted turbine blade on a root block.
    Blade,
}

#[derive(Args, Debug)]
pub struct SampleArgs {
    pub kind: SampleKind,
    /// Output folder; writes KIND.glb and KIND.obj there.
    #[arg(long, default_value = "data")]
    pub out: PathBuf,
    /// Impeller: number of blades.
    #[arg(long)]
    pub blades: Option<u32>,
    /// Target edge length, mm (smaller = finer mesh).
    #[arg(long)]
    pub resolution: Option<f64>,
}

#[derive(Args, Debug)]
pub struct PlanArgs {
    /// Part mesh (.stl, .obj, .gltf, .glb); overrides the job file's part.
    pub part: Option<PathBuf>,
    /// Job file (TOML); without it the embedded defaults are used.
    #[arg(long)]
    pub job: Option<PathBuf>,
    /// Cutter, e.g. `ball:6` (diameter in mm); overrides the job file.
    #[arg(long, value_parser = ball_spec)]
    pub tool: Option<String>,
    /// Units of the part file: mm, m or in; overrides the job file.
    #[arg(long, value_parser = units)]
    pub units: Option<String>,
    /// Direction in the part file that should point up the C axis, e.g. `0,1,0` for a part
    /// modelled with its axis along Y; overrides the job file.
    #[arg(long, value_parser = parse_vector)]
    pub up: Option<[f64; 3]>,
    /// Scallop height target, mm; overrides the job file.
    #[arg(long, value_parser = positive)]
    pub scallop: Option<f64>,
    /// Tolerance of the posted program, mm: the ball centre stays within it of the part along
    /// every move as the control interpolates it; overrides the job file.
    #[arg(long, value_parser = positive)]
    pub tolerance: Option<f64>,
    /// Worker threads, 1 to 256 (default: all cores). Outputs are identical for any count.
    #[arg(long, value_parser = threads)]
    pub threads: Option<usize>,
    /// Refuse a plan estimated to have more drive points than this (from the part's area, the
    /// stepover and the step); overrides the job file's limits.max_drive_points.
    #[arg(long)]
    pub max_drive_points: Option<u64>,
    /// Leave the run-dependent timings out of report.json (byte-identical reports).
    #[arg(long)]
    pub no_timings: bool,
    /// Output folder.
    #[arg(long)]
    pub out: PathBuf,
}

/// Parses a direction `x,y,z`: three finite numbers, not all zero (any length: it is
/// normalised).
fn parse_vector(text: &str) -> std::result::Result<[f64; 3], String> {
    let parts: Vec<f64> = text
        .split(',')
        .map(|p| p.trim().parse::<f64>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| format!("`{text}`: expected three numbers x,y,z"))?;
    let v = <[f64; 3]>::try_from(parts)
        .map_err(|_| format!("`{text}`: expected three numbers x,y,z"))?;
    job::unit_direction(v)
        .map(|_| v)
        .ok_or_else(|| format!("`{text}`: expected a direction (finite, not all zero)"))
}

// Value parsers: a bad value is a usage error (exit code 2, clap's message names the flag).

/// A finite number > 0.
fn positive(text: &str) -> std::result::Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("`{text}`: expected a positive number")),
    }
}

/// A finite number ≥ 0.
fn non_negative(text: &str) -> std::result::Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
        _ => Err(format!("`{text}`: expected a number >= 0")),
    }
}

/// An angle between two faces, 0 to 180 degrees.
fn face_angle(text: &str) -> std::result::Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(v) if (0.0..=180.0).contains(&v) => Ok(v),
        _ => Err(format!("`{text}`: expected an angle from 0 to 180 degrees")),
    }
}

/// `mm`, `m` or `in` (or their long names).
fn units(text: &str) -> std::result::Result<String, String> {
    text.parse::<crate::mesh::io::Units>()
        .map(|_| text.to_string())
        .map_err(|e| e.to_string())
}

/// Most worker threads accepted: more only costs start-up time (a thread each) and memory.
const MAX_THREADS: usize = 256;

/// A tilt from the normal, 0 to 90 degrees.
fn tilt(text: &str) -> std::result::Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(v) if (0.0..=90.0).contains(&v) => Ok(v),
        _ => Err(format!("`{text}`: expected an angle from 0 to 90 degrees")),
    }
}

/// Grid cells across the part, 4 to 2000.
fn grid_cells(text: &str) -> std::result::Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(v) if (4.0..=2000.0).contains(&v) => Ok(v),
        _ => Err(format!(
            "`{text}`: expected a number of cells from 4 to 2000"
        )),
    }
}

/// A thread count from 1 to [`MAX_THREADS`].
fn threads(text: &str) -> std::result::Result<usize, String> {
    match text.trim().parse::<usize>() {
        Ok(n) if (1..=MAX_THREADS).contains(&n) => Ok(n),
        _ => Err(format!(
            "`{text}`: expected a thread count from 1 to {MAX_THREADS}"
        )),
    }
}

/// A cutter spec `ball:D` for a command that drives a ball-end mill.
fn ball_spec(text: &str) -> std::result::Result<String, String> {
    ball_diameter(text)
        .map(|_| text.to_string())
        .map_err(|e| e.to_string())
}

/// Runs the parsed command; returns the process exit code.
pub fn run(cli: Cli) -> i32 {
    let result = match cli.command {
        Command::Info(a) => info(&a),
        Command::Sample(a) => sample_part(&a),
        Command::Plan(a) => plan(&a),
        Command::Subdivide(a) => subdivide(&a),
        Command::Levels(a) => levels(&a),
        Command::Contour(a) => contour(&a),
        Command::Offsets(a) => offsets(&a),
        Command::Access(a) => access(&a),
        Command::Tools(a) => tools(&a),
    };
    match result {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("error: {e}");
            e.exit_code()
        }
    }
}

fn contour(args: &ContourArgs) -> Result<()> {
    let mut options = job::ContourJobOptions::new(job::parse_flat_tool(&args.tool)?, 0.0);
    options.stock = job::parse_stock(&args.stock)?;
    options.z = args.z;
    options.units = args.units.clone();
    options.stepover = args.stepover;
    options.band = args.band;
    options.scale = args.scale;
    options.direction = match args.direction {
        Direction::Climb => crate::contour::CutDirection::Climb,
        Direction::Mixed => crate::contour::CutDirection::Mixed,
    };
    options.timings = !args.no_timings;
    options.max_levels = args.max_levels;
    options.max_outline_vertices = args.max_outline_vertices;
    job::check_output_dir(&args.out, &job::OutputKind::CONTOUR)?;
    let figures_line = |name: &str, f: &job::MethodFigures| {
        say!(
            "{name:>16}: {:9.1} mm cut, {:6} blocks, {:7.2} min, uncut {:8.2} mm², clearance − r {:+.6} mm, spacing ≤ {:.3} mm, engagement mean {:.2} / max {:.2} mm",
            f.cutting_length_mm,
            f.nc_blocks,
            f.machining_time_min,
            f.uncut_area_mm2,
            f.min_clearance_minus_r_mm,
            f.pass_spacing_max_mm,
            f.engagement_mean_mm,
            f.engagement_max_mm
        );
    };
    if !args.compare {
        let (nc, figures) = job::contour_wavelet(&args.outline, &options)?;
        job::write_output_set(
            &args.out,
            &job::OutputKind::CONTOUR,
            &[("wavelet.nc".to_string(), nc.into_bytes())],
        )?;
        figures_line("wavelet", &figures);
        say!("-> {}", args.out.join("wavelet.nc").display());
        return Ok(());
    }
    let c = job::contour_compare(&args.outline, &options)?;
    job::write_contour_outputs(&args.out, &c)?;
    let r = &c.report;
    figures_line("contour-parallel", &r.contour_parallel);
    figures_line("wavelet", &r.wavelet);
    let d = &r.wavelet_vs_parallel;
    say!(
        "wavelet vs contour-parallel: length {:+.1} %, blocks {:+.1} %, time {:+.1} % -> {}",
        d.cutting_length_pct,
        d.nc_blocks_pct,
        d.machining_time_pct,
        args.out.display()
    );
    Ok(())
}

fn info(args: &InfoArgs) -> Result<()> {
    let raw = job::load_part(&args.part, &args.units)?;
    let name = args.part.display().to_string();
    let (_, report) =
        prepare(&raw.mesh, &PrepareOptions::default()).map_err(|reason| Error::Mesh {
            file: name.clone(),
            reason,
        })?;
    if args.json {
        say!(
            "{}",
            serde_json::to_string_pretty(&report).unwrap_or_default()
        );
        return Ok(());
    }
    let [x0, y0, z0] = report.bounding_box_min;
    let [x1, y1, z1] = report.bounding_box_max;
    say!("{name}");
    for w in &raw.warnings {
        say!("  warning: {w}");
    }
    say!(
        "  triangles        {} ({} in the file)",
        report.triangles,
        report.input_triangles
    );
    say!(
        "  welded vertices  {} ({} in the file)",
        report.vertices,
        report.input_vertices
    );
    say!("  bounding box     [{x0:.4}, {y0:.4}, {z0:.4}] .. [{x1:.4}, {y1:.4}, {z1:.4}] mm");
    say!(
        "  size             {:.4} x {:.4} x {:.4} mm",
        x1 - x0,
        y1 - y0,
        z1 - z0
    );
    say!("  components       {}", report.components);
    say!(
        "  boundary edges   {} ({} holes)",
        report.boundary_edges,
        report.boundary_loops
    );
    say!(
        "  non-manifold     {} edges, {} vertices",
        report.non_manifold_edges,
        report.non_manifold_vertices
    );
    say!(
        "  watertight       {}",
        if report.watertight { "yes" } else { "no" }
    );
    match report.genus {
        Some(g) => say!("  genus            {g}"),
        None => say!("  genus            undefined (not a manifold surface)"),
    }
    match report.volume {
        Some(v) => say!("  volume           {v:.4} mm^3"),
        None => say!("  volume           undefined (not closed)"),
    }
    say!("  surface area     {:.4} mm^2", report.surface_area);
    say!(
        "  units guess      {:?} (from the size alone; read as {})",
        report.units_guess,
        args.units
    );
    let problems = report.problems();
    if problems.is_empty() {
        say!("  problems         none");
    } else {
        say!("  problems:");
        for p in problems {
            say!("    - {p}");
        }
    }
    Ok(())
}

fn sample_part(args: &SampleArgs) -> Result<()> {
    let part = match args.kind {
        SampleKind::Impeller => {
            let mut p = sample::ImpellerParams::default();
            if let Some(b) = args.blades {
                p.blade_count = b;
            }
            if let Some(r) = args.resolution {
                p.resolution = r;
            }
            SamplePart::Impeller(p)
        }
        SampleKind::Blade => {
            let mut p = sample::BladeParams::default();
            if let Some(r) = args.resolution {
                p.resolution = r;
            }
            SamplePart::Blade(p)
        }
    };
    // Only --blades and --resolution can make the parameters invalid: a usage error.
    let (mesh, files) = sample_files(&part).map_err(|e| match e {
        Error::Sample(e @ sample::SampleError::InvalidParameter { .. }) => {
            Error::Usage(format!("--blades / --resolution: {e}"))
        }
        other => other,
    })?;
    std::fs::create_dir_all(&args.out).map_err(|source| Error::Io {
        path: args.out.display().to_string(),
        source,
    })?;
    for (name, bytes) in &files {
        job::write_atomically(&args.out.join(name), bytes)?;
    }
    say!(
        "{}: {} triangles, {} vertices -> {}",
        part.name(),
        mesh.triangles.len(),
        mesh.positions.len(),
        files
            .iter()
            .map(|(n, _)| args.out.join(n).display().to_string())
            .collect::<Vec<_>>()
            .join(", ")
    );
    Ok(())
}

fn subdivide(args: &SubdivideArgs) -> Result<()> {
    let name = args.part.display().to_string();
    let extension = args
        .out
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if !matches!(extension.as_deref(), Some("obj" | "glb")) {
        return Err(Error::Usage(format!(
            "--out {}: the output must end in .obj or .glb",
            args.out.display()
        )));
    }
    check_output_file(&args.out)?;
    let raw = load(&args.part, &args.units)?;
    let mesh_error = |reason: String| Error::Mesh {
        file: name.clone(),
        reason,
    };
    let (mesh, _) = prepare(&raw.mesh, &PrepareOptions::default()).map_err(mesh_error)?;
    let triangles = mesh.triangles.len() as f64 * 4f64.powi(args.levels as i32);
    if triangles > args.max_triangles as f64 {
        return Err(Error::TooLarge {
            what: format!(
                "subdividing {name} ({} triangles) {} times",
                mesh.triangles.len(),
                args.levels
            ),
            estimate: format!(
                "{triangles:.3e} triangles (about {:.1} GB)",
                triangles * 1e-7
            ),
            limit: format!("{} triangles", args.max_triangles),
            how_to_raise: "use fewer --levels or raise --max-triangles".into(),
        });
    }
    let creases = match args.crease_angle {
        Some(angle) => multires::detect_creases(&mesh, angle),
        None => multires::Creases::none(),
    };
    let (fine, _) = multires::loop_subdivide(&mesh, &creases, args.levels)
        .map_err(|e| mesh_error(e.to_string()))?;
    let bytes = if extension.as_deref() == Some("obj") {
        write_obj(
            &fine,
            &format!("wavemill subdivide: {name}, {} Loop levels", args.levels),
        )
    } else {
        let mut glb = GlbBuilder::new();
        glb.add_triangles("subdivided", &fine, [0.72, 0.74, 0.78, 1.0], None)
            .map_err(|e| Error::Job(format!("{name}: {e}")))?;
        glb.build()
    };
    job::write_atomically(&args.out, &bytes)?;
    say!(
        "{name}: {} -> {} triangles ({} levels, {} crease edges) -> {}",
        mesh.triangles.len(),
        fine.triangles.len(),
        args.levels,
        creases.len(),
        args.out.display()
    );
    Ok(())
}

/// Checks, before any work, that `path` can be written as one output file: not a folder, and
/// its folder exists or can be made.
fn check_output_file(path: &Path) -> Result<()> {
    if path.is_dir() {
        return Err(Error::Usage(format!(
            "--out {}: is a folder; name the output file",
            path.display()
        )));
    }
    match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => create_dir(parent),
        _ => Ok(()),
    }
}

/// Reads a part and prints the reader's warnings (units that look wrong, skipped primitives)
/// on stderr, where a script's output stays clean.
fn load(path: &Path, units: &str) -> Result<crate::mesh::io::RawMesh> {
    let raw = job::load_part(path, units)?;
    for w in &raw.warnings {
        eprintln!("warning: {}: {w}", path.display());
    }
    Ok(raw)
}

/// Reads, welds and orients a part and refuses it, saying why, unless it is a manifold surface
/// (and, with `closed`, a closed one).
fn load_manifold_part(path: &Path, units: &str, closed: bool) -> Result<crate::mesh::Mesh> {
    let name = path.display().to_string();
    let raw = load(path, units)?;
    let (mesh, report) =
        prepare(&raw.mesh, &PrepareOptions::default()).map_err(|reason| Error::Mesh {
            file: name.clone(),
            reason,
        })?;
    if report.non_manifold_edges > 0 || report.non_manifold_vertices > 0 {
        return Err(Error::Mesh {
            file: name,
            reason: format!("not a manifold surface: {}", report.problems().join("; ")),
        });
    }
    if closed && !report.watertight {
        return Err(Error::Mesh {
            file: name,
            reason: format!(
                "shapes that enclose the part need a closed, consistently oriented surface \
                 (inside and outside); found: {}",
                report.problems().join("; ")
            ),
        });
    }
    Ok(mesh)
}

fn create_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|source| Error::Io {
        path: dir.display().to_string(),
        source,
    })
}

fn offsets(args: &OffsetsArgs) -> Result<()> {
    if let Some((i, a)) = args
        .allowances
        .iter()
        .enumerate()
        .find(|&(i, &a)| !(a.is_finite() && a >= 0.0) || (i > 0 && a >= args.allowances[i - 1]))
    {
        return Err(Error::Usage(format!(
            "--allowances: value {} ({a}) must be a number of mm >= 0, smaller than the one before",
            i + 1
        )));
    }
    let levels_above_base = args
        .max_levels
        .unwrap_or(args.allowances.len().saturating_sub(1) as u32);
    if levels_above_base > 6 {
        return Err(Error::Usage(format!(
            "--allowances: {} values need {levels_above_base} levels above the base, at most 6 \
             (each level multiplies the triangles by 4); give --max-levels",
            args.allowances.len()
        )));
    }
    let tool_radius = match &args.tool {
        Some(spec) => ball_diameter(spec)? / 2.0,
        None => 0.0,
    };
    job::check_output_dir(&args.out, &job::OutputKind::OFFSETS)?;
    let name = args.part.display().to_string();
    let mesh = load_manifold_part(&args.part, &args.units, true)?;
    let remesh = multires::RemeshOptions {
        tolerance: args.tolerance,
        base_triangles: args.base_triangles.max(4),
        base_max_error: args.base_max_error,
        max_levels: levels_above_base,
        crease_angle_deg: args.crease_angle,
        ..Default::default()
    };
    let options = crate::offset::OffsetOptions {
        max_cells_across: args.grid_cells,
        ..Default::default()
    }
    .with_tool_radius(tool_radius);
    let job::OffsetsOutput {
        mut files, report, ..
    } = job::offsets(&mesh, &remesh, &args.allowances, &options, !args.no_timings)?;
    let json = serde_json::to_string_pretty(&report).unwrap_or_default() + "\n";
    files.push(("offsets.json".to_string(), json.into_bytes()));
    job::write_output_set(&args.out, &job::OutputKind::OFFSETS, &files)?;
    let json_path = args.out.join("offsets.json");
    for s in &report.shapes {
        let f = &s.figures;
        say!(
            "offset {} (level {}): allowance {} mm, bound {:.4} mm, {} triangles, clearance - allowance {:.2e} mm, excess mean {:.4} max {:.4} mm, {}",
            s.shape,
            s.level,
            f.allowance_mm,
            f.bound_mm,
            f.triangles,
            f.min_clearance_minus_allowance_mm,
            f.mean_excess_mm,
            f.max_excess_mm,
            if f.verified {
                "verified"
            } else {
                "NOT VERIFIED"
            }
        );
    }
    if !report.verified {
        return Err(Error::Verification(format!(
            "{name}: a shape still fails its checks after the repairs (see {})",
            json_path.display()
        )));
    }
    say!(
        "{name}: {} shapes -> {}",
        report.shapes.len(),
        args.out.display()
    );
    Ok(())
}

fn levels(args: &LevelsArgs) -> Result<()> {
    job::check_output_dir(&args.out, &job::OutputKind::LEVELS)?;
    let name = args.part.display().to_string();
    let mesh = load_manifold_part(&args.part, &args.units, false)?;
    let options = multires::RemeshOptions {
        tolerance: args.tolerance,
        base_triangles: args.base_triangles.max(4),
        base_max_error: Some(args.base_max_error.unwrap_or(3.0 * args.tolerance)),
        relax_passes: args.relax_passes,
        max_levels: args.max_levels,
        crease_angle_deg: args.crease_angle,
        ..Default::default()
    };
    let wavelet_options =
        multires::WaveletOptions::default().with_kdisk_update(!args.plain_lifting);
    let (mut files, report) = job::levels(&mesh, &options, &wavelet_options, !args.no_timings)?;
    let json = serde_json::to_string_pretty(&report).unwrap_or_default() + "\n";
    files.push(("levels.json".to_string(), json.into_bytes()));
    job::write_output_set(&args.out, &job::OutputKind::LEVELS, &files)?;
    for l in &report.levels {
        say!(
            "level {}: {:>8} triangles, max deviation to finest {:.4} mm, fit to input {:.4} mm",
            l.level,
            l.triangles,
            l.max_deviation_mm,
            l.fitted_hausdorff_mm
        );
    }
    say!(
        "finest level within {:.4} mm of {name} (tolerance {}), reconstruction error {:.2e} mm -> {}",
        report.finest_hausdorff_mm,
        report.tolerance_mm,
        report.reconstruction_error_mm,
        args.out.display()
    );
    Ok(())
}

/// The diameter of a `ball:D` spec; other cutters are refused by name (the 5-axis stages drive
/// a ball centre).
fn ball_diameter(spec: &str) -> Result<f64> {
    match parse_cutter(spec).map_err(|e| Error::Usage(e.to_string()))? {
        Cutter::Ball { diameter, .. } => Ok(diameter),
        other => Err(Error::Usage(format!(
            "tool `{spec}` is a {} cutter: this command drives a ball-end mill (ball:D)",
            other.kind()
        ))),
    }
}

/// `--tool ball:D`: the job's ball diameter, with flutes and shank at least as long and wide.
fn set_tool(job: &mut Job, spec: &str) -> Result<()> {
    let diameter = ball_diameter(spec)?;
    job.tool.diameter = diameter;
    job.tool.flute_length = job.tool.flute_length.max(diameter);
    job.tool.shank_diameter = job.tool.shank_diameter.max(diameter);
    Ok(())
}

fn tools(args: &ToolsArgs) -> Result<()> {
    job::check_output_dir(&args.out, &job::OutputKind::TOOLS)?;
    let library = crate::tool::ToolLibrary::read(&args.library).map_err(Error::Job)?;
    let name = args.part.display().to_string();
    let raw = load(&args.part, &args.units)?;
    let options = crate::tool_choice::ToolChoiceOptions {
        tolerance: args.tolerance,
        max_points: args.points as usize,
        max_tilt_deg: args.max_tilt,
        table_margin: if args.no_table { None } else { Some(2.0) },
        ..Default::default()
    };
    let output = job::tools(
        &raw,
        &name,
        &library,
        &args.library.display().to_string(),
        &options,
        !args.no_timings,
    )?;
    job::write_tools_outputs(&args.out, &output)?;
    let r = &output.report.choice;
    say!(
        "{name}: {} of {} points evaluated; smallest concave radius {}, smallest safe ball {:.3} mm",
        r.points_evaluated,
        r.vertices,
        r.shape
            .min_concave_radius_mm
            .map_or("none".to_string(), |c| format!("{c:.3} mm")),
        r.shape.min_safe_ball_mm
    );
    for t in &r.proposal {
        say!(
            "  T{} {:<28} {:6.2} % of the area, {} region(s)",
            t.id,
            t.name,
            t.percent,
            t.regions
        );
    }
    say!(
        "  unreachable {:6.2} % ({} region(s)) -> {}",
        r.unreachable.percent,
        r.unreachable.regions,
        args.out.display()
    );
    Ok(())
}

fn access(args: &AccessArgs) -> Result<()> {
    let mut job = Job::default();
    if let Some(spec) = &args.tool {
        set_tool(&mut job, spec)?;
    }
    crate::access::level_for_count(args.directions)
        .map_err(|e| Error::Usage(format!("--directions: {e}")))?;
    job::check_output_dir(&args.out, &job::OutputKind::ACCESS)?;
    let query = match &args.query {
        Some(path) => {
            let text = std::fs::read_to_string(path).map_err(|source| Error::Io {
                path: path.display().to_string(),
                source,
            })?;
            Some(job::parse_query_csv(&text, &path.display().to_string())?)
        }
        None => None,
    };
    let name = args.part.display().to_string();
    let raw = load(&args.part, &args.units)?;
    let options = job::AccessOptions {
        directions: args.directions,
        timings: !args.no_timings,
        ..Default::default()
    };
    let output = job::access(&raw, &name, &job, &options, query.as_deref())?;
    job::write_access_outputs(&args.out, &output)?;
    let r = &output.report;
    say!(
        "{name}: {} points x {} directions, {} rays ({:.1}x fewer than brute force's {}), agreement {:.3} % on {} points, visible {:.0} % on average -> {}",
        r.points,
        r.directions,
        r.rays.hierarchical,
        r.rays.saving,
        r.rays.brute_force,
        r.agreement.percent,
        r.agreement.points_checked,
        100.0 * r.visible_fraction.mean,
        args.out.display()
    );
    if let Some(q) = &r.query {
        say!(
            "  {} query points, {} without an axis ({}) -> {}",
            q.points,
            q.without_axis,
            q.tool,
            args.out.join("query.csv").display()
        );
    }
    Ok(())
}

fn plan(args: &PlanArgs) -> Result<()> {
    let mut job = match &args.job {
        Some(path) => Job::load(path).map_err(Error::Job)?,
        None => Job::default(),
    };
    // Flags override the job file; a value they make unusable is a usage error naming the flag.
    let mut flags: Vec<(&str, &str)> = Vec::new();
    if let Some(spec) = &args.tool {
        set_tool(&mut job, spec)?;
        flags.push(("tool.", "--tool"));
        flags.push(("scallop_height", "--tool"));
    }
    if let Some(u) = &args.units {
        job.part.units = Some(u.clone());
    }
    if let Some(up) = args.up {
        job.part.up = Some(up);
    }
    if let Some(s) = args.scallop {
        job.strategy.scallop_height = s;
        flags.push(("strategy.scallop_height", "--scallop"));
    }
    if let Some(t) = args.tolerance {
        job.strategy.tolerance = t;
        flags.push(("strategy.tolerance", "--tolerance"));
    }
    if let Some(n) = args.max_drive_points {
        job.limits.max_drive_points = n;
        flags.push(("limits.max_drive_points", "--max-drive-points"));
    }
    if let Err(e) = job.validate() {
        return Err(match flags.iter().find(|(key, _)| e.contains(key)) {
            Some((_, flag)) => Error::Usage(format!("{flag}: {e}")),
            None => Error::Job(e),
        });
    }
    let part_path: PathBuf = match (&args.part, &job.part.path) {
        (Some(p), _) => p.clone(),
        (None, Some(p)) => p.clone(),
        (None, None) => {
            return Err(Error::Usage(
                "no part: give PART or set part.path in the job file".into(),
            ));
        }
    };
    job::check_output_dir(&args.out, &job::OutputKind::PLAN)?;
    let units = job.part.units.clone().unwrap_or_else(|| "mm".into());
    let threads = args.threads.unwrap_or(0);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| Error::Job(format!("worker threads: {e}")))?;
    let name = part_path.display().to_string();
    let raw = load(&part_path, &units)?;
    let observer = progress::Bars::new();
    let output = pool
        .install(|| job::plan(&raw, &name, &units, &job, &observer))
        .map_err(|e| match e {
            Error::TooLarge {
                what,
                estimate,
                limit,
                how_to_raise,
            } => Error::TooLarge {
                what,
                estimate,
                limit,
                how_to_raise: format!("{how_to_raise} (--max-drive-points)"),
            },
            other => other,
        })?;
    job::write_outputs(&args.out, &output, !args.no_timings)?;
    summarise(&output.report, &args.out);
    Ok(())
}

fn summarise(r: &job::PlanReport, out: &Path) {
    say!("planned {}:", r.part.file);
    say!(
        "  poses            {} cut, {} approach, {} retract, {} rapid ({} NC blocks)",
        r.poses.cut,
        r.poses.approach,
        r.poses.retract,
        r.poses.rapid,
        r.nc_blocks
    );
    say!("  cutting length   {:.1} mm", r.cutting_length_mm);
    say!(
        "  estimated time   {:.1} min",
        r.estimated_time.total_s / 60.0
    );
    say!(
        "  clearance        cutter {:.6} mm, shank {:.3} mm, holder {:.3} mm (searched to {} mm)",
        r.clearance.min_cutter_clearance,
        r.clearance.min_shank_clearance,
        r.clearance.min_holder_clearance,
        r.clearance.search_distance
    );
    say!(
        "  unreachable      {} of {} drive points",
        r.unreachable.count,
        r.strategy.drive_points
    );
    say!(
        "  outputs          {}/{{job.nc, cl.csv, report.json, paths.glb}}",
        out.display()
    );
}
