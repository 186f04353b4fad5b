//! `wavemill rough`: 3-axis layer roughing of a part from its blank, down to the part's
//! verified offset shape, with a tool of a library; posted, read back and checked.

use std::path::PathBuf;

use clap::{Args, ValueEnum};

use crate::cli::load;
use crate::cli::values::*;
use crate::error::Result;
use crate::job::{self};

#[derive(Args, Debug)]
pub struct RoughArgs {
    /// Part: a mesh (.stl, .obj, .gltf, .glb) or IGES surfaces (.igs, .iges), closed, standing on its lowest point with its axis
    /// along +Z.
    pub part: PathBuf,
    /// Direction in the part file that should point up the spindle, e.g. `0,1,0` for a part
    /// modelled with its axis along Y; the program is in the part's frame turned so.
    #[arg(long, value_parser = parse_vector)]
    pub up: Option<[f64; 3]>,
    /// Tool library (TOML, one `[[tool]]` table per tool; see data/tools.toml).
    #[arg(long)]
    pub library: PathBuf,
    /// The library tool to rough with [default: the largest flat or bull-nose end mill, the
    /// first that reaches the part's floor if any does].
    #[arg(long)]
    pub tool_id: Option<u32>,
    /// How many smaller end mills of the library rest-rough after the first, each at most 3/4
    /// of the one before it across, only where the stock still holds material [default: 1;
    /// 0 with --conventional].
    #[arg(long)]
    pub rest_tools: Option<usize>,
    /// Material left on the part: roughing stops at its verified offset shape by this much, mm.
    #[arg(long, default_value_t = 0.5, value_parser = positive)]
    pub allowance: f64,
    /// The blank: `box:X0,Y0,Z0,X1,Y1,Z1` or `cylinder:R,Z0,Z1` (about the vertical line
    /// through the part's box centre), mm [default: a cylinder 2 mm wider than the part and
    /// 1 mm above it].
    #[arg(long, value_name = "SPEC", value_parser = blank)]
    pub blank: Option<job::BlankSpec>,
    /// Cutting feed, mm/min.
    #[arg(long, default_value_t = 2000.0, value_parser = positive)]
    pub feed: f64,
    /// Feed of ramped entries, mm/min.
    #[arg(long, default_value_t = 800.0, value_parser = positive)]
    pub entry_feed: f64,
    /// Spindle speed, rev/min.
    #[arg(long, default_value_t = 8000)]
    pub spindle_rpm: u32,
    /// Keep the programmed feeds: no feed control from each move's engagement.
    #[arg(long)]
    pub no_feed_control: bool,
    /// The conventional baseline: equal layers at the largest depth of cut (no extra plane at
    /// the flats), the programmed feeds, and no rest tools unless --rest-tools says so.
    #[arg(long)]
    pub conventional: bool,
    /// The largest depth of cut of every tool, mm [default: each tool's radius]: with
    /// --conventional, the baseline's layer depth, to compare routes that leave the same
    /// material.
    #[arg(long, value_parser = positive)]
    pub layer_depth: Option<f64>,
    /// Widest radial engagement a pass may take, as a share of the tool's diameter: slots and
    /// concave corners heavier than this are cut as trochoidal loops where there is room
    /// [default: 0.5; 1 with --conventional: every pass straight].
    #[arg(long, value_parser = share)]
    pub max_engagement: Option<f64>,
    /// The planner of each layer's passes: exact offsets of the section, far side first, or
    /// seed 004's wavelet passes inside the loose convex hull.
    #[arg(long, value_enum, default_value_t = LayerPathsArg::Offsets)]
    pub layer_paths: LayerPathsArg,
    /// The material's specific cutting force K_t, N/mm² (aluminium 7075: 800, Ti-6Al-4V:
    /// about 2000, Inconel 718: 3000); feed control holds K_t·A·f/(π·D·n) at the target.
    #[arg(long, default_value_t = 800.0, value_parser = positive)]
    pub specific_force: f64,
    /// The mean tangential force feed control holds, N [default: each tool's nominal cut,
    /// half its diameter wide and deep at --feed].
    #[arg(long, value_parser = positive)]
    pub target_force: Option<f64>,
    /// The machine's fastest feed, mm/min: passes through air and light cuts go up to it.
    #[arg(long, default_value_t = 6000.0, value_parser = positive)]
    pub max_feed: f64,
    /// Distance between dexel lines of the stock model the program is run on, mm [default: the
    /// part's box diagonal / 400, within 0.05 to 1 mm].
    #[arg(long, value_parser = positive)]
    pub resolution: Option<f64>,
    /// Units of the part file: mm, m or in.
    #[arg(long, default_value = "mm", value_parser = units)]
    pub units: String,
    /// Leave the run-dependent timings out of rough.json (byte-identical reports).
    #[arg(long)]
    pub no_timings: bool,
    /// Output folder: rough.nc, cl.csv, rough.json, stock.glb (only rough.json when a check
    /// fails; exit 3).
    #[arg(long)]
    pub out: PathBuf,
}

/// `--layer-paths`.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum LayerPathsArg {
    /// Exact offsets of the section at r, r + s, …, far side first.
    Offsets,
    /// Seed 004's wavelet passes within a band of their level, inside the loose convex hull.
    Wavelet,
}

/// Runs the command.
pub fn run(args: &RoughArgs) -> Result<()> {
    job::check_output_dir(&args.out, &job::OutputKind::ROUGH)?;
    let library = crate::tool::ToolLibrary::read(&args.library)?;
    let name = args.part.display().to_string();
    let raw = load(&args.part, &args.units)?;
    let defaults = job::RoughOptions::default();
    let options = job::RoughOptions {
        allowance: args.allowance,
        up: args.up,
        blank: args.blank.clone(),
        tool_id: args.tool_id,
        rest_tools: args
            .rest_tools
            .unwrap_or(if args.conventional { 0 } else { 1 }),
        spindle_rpm: args.spindle_rpm,
        feeds: crate::rough::RoughingFeeds {
            cut: args.feed,
            entry: args.entry_feed,
            ..defaults.feeds.clone()
        },
        resolution: args.resolution,
        uniform_layers: args.conventional,
        max_depth: args.layer_depth,
        max_engagement: args
            .max_engagement
            .unwrap_or(if args.conventional { 1.0 } else { 0.5 }),
        layer_paths: match args.layer_paths {
            LayerPathsArg::Offsets => crate::rough::LayerPaths::Offsets,
            LayerPathsArg::Wavelet => crate::rough::LayerPaths::Wavelet,
        },
        feed_control: (!args.no_feed_control && !args.conventional).then_some(
            crate::feed::CuttingModel {
                specific_force: args.specific_force,
                target_force: args.target_force,
                max_feed: args.max_feed,
                ..Default::default()
            },
        ),
        ..defaults
    };
    if let Some(model) = &options.feed_control {
        model.validate().map_err(crate::error::Error::Usage)?;
    }
    let output = job::rough(&raw, &name, &args.units, &library, &options)?;
    job::write_rough_outputs(&args.out, &output, !args.no_timings)?;
    let r = &output.report;
    say!(
        "{name}: from {}, {} tool(s), {:.1} min; {:.0} of {:.0} mm³ left",
        r.blank,
        r.tools.len(),
        r.estimated_time_s / 60.0,
        r.volume_after_mm3,
        r.blank_volume_mm3
    );
    for t in &r.tools {
        say!(
            "  T{} {} ({}): {} layers, {} moves, {:.1} min, removed {:.0} mm³; rest over the part \
             mean {:.2} mm, max {:.2} mm",
            t.tool.id,
            t.tool.name,
            t.material,
            t.layers.len(),
            t.moves,
            t.estimated_time_s / 60.0,
            t.stock.removed_volume_mm3,
            t.stock.rest.mean_mm,
            t.stock.rest.max_mm
        );
        if let Some(f) = &t.feed_control {
            say!(
                "    feed control: {:.1} → {:.1} min; force max/mean {:.2} → {:.2} (target {:.0} N)",
                f.time_before_s / 60.0,
                f.time_after_s / 60.0,
                f.force_before.max_over_mean,
                f.force_after.max_over_mean,
                f.target_force_n
            );
        }
        if let Some(n) = &t.not_reached {
            say!("    not reached: {}", n.reason);
        }
    }
    let clearance = |f: fn(&job::RoughToolRun) -> f64| {
        r.tools.iter().map(f).fold(f64::INFINITY, f64::min).max(0.0)
    };
    say!(
        "  checks: closest to the offset shape {:.4} mm (posted rounding aside), to the part {:.3} \
         mm; no gouge, rapid through material, or shank or holder touch",
        clearance(|t| t
            .overcut_vs_shape
            .as_ref()
            .map_or(f64::INFINITY, |o| o.min_clearance_mm)),
        clearance(|t| t.overcut_vs_part.min_clearance_mm)
    );
    say!("  wrote {}", args.out.display());
    Ok(())
}
