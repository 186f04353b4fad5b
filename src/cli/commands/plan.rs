//! `wavemill plan`: a job planned, verified and posted.

use std::path::{Path, PathBuf};

use clap::Args;

use crate::cli::set_tool;
use crate::cli::values::*;
use crate::error::{Error, Result};
use crate::job::{self, Job};

#[derive(Args, Debug)]
pub struct PlanArgs {
    /// Part: a mesh (.stl, .obj, .gltf, .glb) or IGES surfaces (.igs, .iges); overrides the job file's part.
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
    /// The blank: `cylinder` (the part's bar stock, the default), `box:X0,Y0,Z0,X1,Y1,Z1`,
    /// `cylinder:R,Z0,Z1`, `offset:M`, `mesh:FILE`, or `none` for a part already roughed (only
    /// the ball operations, nothing simulated); overrides the job file's `[stock]` blank.
    #[arg(long)]
    pub blank: Option<String>,
    /// After the end mills, rough the rest they leave under overhangs and between blades with
    /// the ball, 5-axis, in offset layers (`channel-rough`; `[roughing] channel = true`).
    #[arg(long)]
    pub channel: bool,
    #[command(flatten)]
    pub machine: crate::cli::MachineArgs,
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

/// Runs the command.
pub fn run(args: &PlanArgs) -> Result<()> {
    let mut job = match &args.job {
        Some(path) => Job::load(path)?,
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
    if let Some(blank) = &args.blank {
        job.stock.blank = Some(blank.clone());
        flags.push(("stock.blank", "--blank"));
    }
    if args.channel {
        job.roughing.channel = true;
    }
    crate::cli::apply_machine_flags(&mut job, &args.machine, &mut flags)?;
    if let Some(n) = args.max_drive_points {
        job.limits.max_drive_points = n;
        flags.push(("limits.max_drive_points", "--max-drive-points"));
    }
    job.validate()
        .map_err(|e| crate::cli::name_flags(Error::from(e), &flags))?;
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
        .build()?;
    let name = part_path.display().to_string();
    let (raw, surfaces) = job::load_part_with_surfaces(&part_path, &units)?;
    for w in &raw.warnings {
        eprintln!("warning: {name}: {w}");
    }
    let observer = super::super::progress::Bars::new();
    let output = pool
        .install(|| job::plan_with_surfaces(&raw, surfaces, &name, &units, &job, &observer))
        .map_err(|e| {
            // The drive-point limit is named by its flag whether or not it was given.
            let mut run_flags = flags.clone();
            run_flags.push(("limits.max_drive_points", "--max-drive-points"));
            crate::cli::name_flags(e, &run_flags)
        })?;
    job::write_outputs(&args.out, &output, !args.no_timings)?;
    summarise(&output.report, &args.out);
    Ok(())
}

pub(crate) fn summarise(r: &job::PlanReport, out: &Path) {
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
    if !r.machine.unwinds.is_empty() {
        say!(
            "  unwinds          {} (a rotary limit: retract, turn on the safe plane, re-plunge; \
             report.json machine.unwinds)",
            r.machine.unwinds.len()
        );
    }
    say!(
        "  estimated time   {:.1} min",
        r.estimated_time.total_s / 60.0
    );
    let figure = |clearance: Option<f64>, digits: usize| {
        clearance.map_or_else(
            || "not measured".to_string(),
            |c| format!("{c:.digits$} mm"),
        )
    };
    // The flutes are measured along the posted program (the poses leave them to it).
    let flutes = r
        .posted
        .as_ref()
        .and_then(|p| p.flutes.as_ref())
        .map(|f| f.min_feed_clearance_mm)
        .or(r.clearance.min_flutes_clearance);
    say!(
        "  clearance        cutter {:.6} mm, flutes {}, shank {}, holder {} (searched to {} mm)",
        r.clearance.min_cutter_clearance,
        figure(flutes, 4),
        figure(r.clearance.min_shank_clearance, 3),
        figure(r.clearance.min_holder_clearance, 3),
        r.clearance.search_distance
    );
    let reasons: Vec<String> = r
        .unreachable
        .by_reason
        .iter()
        .map(|(why, n)| format!("{why} {n}"))
        .collect();
    say!(
        "  unreachable      {} of {} drive points{}",
        r.unreachable.count,
        r.strategy.drive_points,
        if reasons.is_empty() {
            String::new()
        } else {
            format!(" ({})", reasons.join(", "))
        }
    );
    if let Some(corner) = &r.corner_finishing {
        let reasons: Vec<String> = corner
            .unreachable_by_reason
            .iter()
            .map(|(why, n)| format!("{why} {n}"))
            .collect();
        say!(
            "  corner finish    {}: {:.1} mm of cutting within {:.2} mm of the roots; {} of {} \
             drive points unreachable{}",
            corner.tool,
            corner.cutting_length_mm,
            corner.band_mm,
            corner.unreachable,
            corner.drive_points,
            if reasons.is_empty() {
                String::new()
            } else {
                format!(" ({})", reasons.join(", "))
            }
        );
    }
    let mut outputs = "job.nc, cl.csv, cl.apt, report.json, paths.glb".to_string();
    if r.finish_scallop.is_some() {
        outputs.push_str(", scallop.glb, scallop.png");
    }
    if let Some(stock) = &r.stock {
        say!(
            "  stock            {} blank, {:.0} mm³ (dexels {:.3} mm apart)",
            stock.blank,
            stock.blank_volume_mm3,
            stock.resolution_mm
        );
        for op in &stock.operations {
            say!(
                "    {:<22} removed {:.0} mm³, rest on the part mean {:.2} / max {:.2} mm",
                op.name,
                op.removed_volume_mm3,
                op.rest.mean_mm,
                op.rest.max_mm
            );
        }
        if !stock.operations.is_empty() {
            outputs.push_str(&format!(", stock-1..{}.glb", stock.operations.len()));
        }
    }
    say!("  outputs          {}/{{{outputs}}}", out.display());
}
