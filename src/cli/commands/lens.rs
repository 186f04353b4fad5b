//! `wavemill lens`: a freeform lens surface into its nose-radius-compensated polar grid and a
//! spiral slow-tool-servo program (seed 003), both checked as written.

use std::path::PathBuf;

use clap::Args;

use crate::cli::values::*;
use crate::error::{Error, Result};
use crate::job;
use crate::lathe::{GridOptions, RadialSpacing, SpindleSpeed};

#[derive(Args, Debug)]
#[command(group(clap::ArgGroup::new("radial").required(true).args(["radial_step", "radii"])))]
#[command(group(clap::ArgGroup::new("speed").args(["rpm", "surface_speed"])))]
pub struct LensArgs {
    /// The surface: an IGES file (.igs, .iges; its largest face that is not a plane, or
    /// --face) or a TOML description (sphere, asphere, toric, xy-polynomial, zernike; see
    /// docs/lens.md). The face to cut looks toward +Z.
    pub surface: PathBuf,
    /// Radius of the tool's nose, mm: the program drives the nose centre.
    #[arg(long, value_parser = non_negative)]
    pub nose_radius: f64,
    /// Outer diameter of the grid and the spiral, mm.
    #[arg(long, value_parser = positive)]
    pub diameter: f64,
    /// Radial step of the grid, mm (the seed's `step`).
    #[arg(long, value_parser = positive)]
    pub radial_step: Option<f64>,
    /// Number of radii of the grid, centre and rim included.
    #[arg(long)]
    pub radii: Option<usize>,
    /// Angles per turn of the grid (the seed's `ticks`).
    #[arg(long, default_value_t = 360)]
    pub ticks: usize,
    /// The IGES face to turn, by its DE number.
    #[arg(long)]
    pub face: Option<usize>,
    /// Radial feed per spindle revolution of the spiral, mm.
    #[arg(long, default_value_t = 0.01, value_parser = positive)]
    pub feed_per_rev: f64,
    /// Form tolerance of the program between points, as the control interpolates, mm.
    #[arg(long, default_value_t = 0.0002, value_parser = positive)]
    pub form_tolerance: f64,
    /// Largest angle between two program points, degrees.
    #[arg(long, default_value_t = 5.0, value_parser = positive)]
    pub max_step: f64,
    /// Constant spindle speed, rev/min [default: 300].
    #[arg(long, value_parser = positive)]
    pub rpm: Option<f64>,
    /// Constant surface speed at the nose instead, m/min (capped by --max-rpm).
    #[arg(long, value_parser = positive)]
    pub surface_speed: Option<f64>,
    /// Highest spindle speed with --surface-speed, rev/min.
    #[arg(long, default_value_t = 1000.0, value_parser = positive)]
    pub max_rpm: f64,
    /// The tool's clearance angle, degrees: a surface falling more steeply along the cut is
    /// refused.
    #[arg(long, default_value_t = 10.0, value_parser = positive)]
    pub clearance_angle: f64,
    /// Height of the approach and retract above the highest centre, mm.
    #[arg(long, default_value_t = 2.0, value_parser = positive)]
    pub clearance_height: f64,
    /// Feed of the plunge to the first point, mm/min.
    #[arg(long, default_value_t = 50.0, value_parser = positive)]
    pub plunge_feed: f64,
    /// Also build the seed's Piegl–Tiller offset surface to this tolerance, mm, project the
    /// grid onto it and report its error against the exact compensation (IGES lenses; writes
    /// offset.igs).
    #[arg(long, value_parser = positive)]
    pub piegl_tiller: Option<f64>,
    /// Leave the timings out of lens.json (repeated runs write identical bytes).
    #[arg(long)]
    pub no_timings: bool,
    /// Output folder: grid.csv, grid.bin, lens.nc, lens.json, lens.png (offset.igs).
    #[arg(long)]
    pub out: PathBuf,
}

/// Runs the command.
pub fn run(args: &LensArgs) -> Result<()> {
    job::check_output_dir(&args.out, &job::OutputKind::LENS)?;
    let radial = match (args.radial_step, args.radii) {
        (Some(step), _) => RadialSpacing::Step(step),
        (None, Some(n)) => RadialSpacing::Count(n),
        (None, None) => return Err(Error::Usage("--radial-step or --radii is needed".into())),
    };
    let speed = match args.surface_speed {
        Some(v) => SpindleSpeed::ConstantSurfaceSpeed {
            metres_per_minute: v,
            max_rpm: args.max_rpm,
        },
        None => SpindleSpeed::ConstantRpm(args.rpm.unwrap_or(300.0)),
    };
    let options = job::LensOptions {
        face: args.face,
        grid: GridOptions {
            nose_radius: args.nose_radius,
            diameter: args.diameter,
            radial,
            ticks: args.ticks,
        },
        feed_per_rev: args.feed_per_rev,
        form_tolerance: args.form_tolerance,
        max_step_degrees: args.max_step,
        speed,
        clearance_angle_degrees: args.clearance_angle,
        clearance_height: args.clearance_height,
        plunge_feed: args.plunge_feed,
        offset_tolerance: args.piegl_tiller,
        timings: !args.no_timings,
    };
    let output = job::lens(&args.surface, &options).map_err(|e| {
        crate::cli::name_flags(
            e,
            &[
                ("feed_per_rev", "--feed-per-rev"),
                ("form_tolerance", "--form-tolerance"),
                ("max_step_degrees", "--max-step"),
                ("clearance_height", "--clearance-height"),
                ("plunge_feed", "--plunge-feed"),
                ("clearance_angle_degrees", "--clearance-angle"),
            ],
        )
    })?;
    job::write_lens_outputs(&args.out, &output)?;
    let r = &output.report;
    say!(
        "{}: {} × {} grid, centres within {:.1e} mm of ρ; spiral {} points, {:.1} revolutions, \
         {:.1} min, form error ≤ {:.2e} mm (tolerance {}); wrote {}",
        r.surface_file,
        r.grid.radii,
        r.grid.ticks,
        r.grid.check.max_error,
        r.spiral.points,
        r.spiral.revolutions,
        r.spiral.minutes,
        r.spiral.check.interpolated.max_error,
        r.spiral.form_tolerance,
        args.out.display()
    );
    Ok(())
}
