//! `wavemill tools`: propose tools from a library for the regions of a part.

use std::path::PathBuf;

use clap::Args;

use crate::cli::load;
use crate::cli::values::*;
use crate::error::Result;
use crate::job::{self};

#[derive(Args, Debug)]
pub struct ToolsArgs {
    /// Part: a mesh (.stl, .obj, .gltf, .glb) or IGES surfaces (.igs, .iges), closed.
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

/// Runs the command.
pub fn run(args: &ToolsArgs) -> Result<()> {
    job::check_output_dir(&args.out, &job::OutputKind::TOOLS)?;
    let library = crate::tool::ToolLibrary::read(&args.library)?;
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
