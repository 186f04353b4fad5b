//! `wavemill contour`: 2.5D wavelet contour paths, and the contour-parallel baseline.

use std::path::PathBuf;

use clap::{Args, ValueEnum};

use crate::cli::name_flags;
use crate::cli::values::*;
use crate::error::Result;
use crate::job::{self};

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
    #[arg(long, value_name = "flat:D", value_parser = flat_tool)]
    pub tool: f64,
    /// Stock: `margin:M`, the part's bounding box grown by M mm, or `outline:FILE`, a closed
    /// SVG/DXF outline (same --scale) that contains the part.
    #[arg(long, value_name = "margin:M|outline:FILE", value_parser = stock)]
    pub stock: job::StockSpec,
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

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum Direction {
    /// Every pass climb milling.
    Climb,
    /// Open roughing passes either way (zig-zag), closed and finishing passes climb.
    Mixed,
}

/// The flag that sets each option of [`job::ContourJobOptions`].
const FLAGS: &[(&str, &str)] = &[
    ("tool_diameter", "--tool"),
    ("stock", "--stock"),
    ("z", "--z"),
    ("units", "--units"),
    ("stepover", "--stepover"),
    ("band", "--band"),
    ("scale", "--scale"),
    ("max_levels", "--max-levels"),
    ("max_outline_vertices", "--max-outline-vertices"),
];

/// Runs the command.
pub fn run(args: &ContourArgs) -> Result<()> {
    let mut options = job::ContourJobOptions::new(args.tool, 0.0);
    options.stock = args.stock.clone();
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
        let (nc, figures) =
            job::contour_wavelet(&args.outline, &options).map_err(|e| name_flags(e, FLAGS))?;
        job::write_output_set(
            &args.out,
            &job::OutputKind::CONTOUR,
            &[("wavelet.nc".to_string(), nc.into_bytes())],
        )?;
        figures_line("wavelet", &figures);
        say!("-> {}", args.out.join("wavelet.nc").display());
        return Ok(());
    }
    let c = job::contour_compare(&args.outline, &options).map_err(|e| name_flags(e, FLAGS))?;
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
