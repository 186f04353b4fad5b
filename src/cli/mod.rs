//! The `wavemill` command line: a thin shell over the library. Each subcommand parses its
//! arguments, calls one library function, prints a summary and maps errors to exit codes
//! (0 success, 1 bad input or I/O, 2 usage, 3 the planned path failed verification).

mod progress;

use std::path::{Path, PathBuf};

use clap::{Args, Parser, Subcommand, ValueEnum};

use crate::error::{Error, Result};
use crate::job::{self, Job, SamplePart, sample_files};
use crate::mesh::{PrepareOptions, prepare};
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
}

#[derive(Args, Debug)]
pub struct InfoArgs {
    /// Mesh file (.stl, .obj, .gltf, .glb).
    pub part: PathBuf,
    /// Units the file is written in.
    #[arg(long, default_value = "mm")]
    pub units: String,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
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
    #[arg(long)]
    pub tool: Option<String>,
    /// Units of the part file: mm, m or in; overrides the job file.
    #[arg(long)]
    pub units: Option<String>,
    /// Direction in the part file that should point up the C axis, e.g. `0,1,0` for a part
    /// modelled with its axis along Y; overrides the job file.
    #[arg(long, value_delimiter = ',', num_args = 3)]
    pub up: Option<Vec<f64>>,
    /// Scallop height target, mm; overrides the job file.
    #[arg(long)]
    pub scallop: Option<f64>,
    /// Chord and post tolerance, mm; overrides the job file.
    #[arg(long)]
    pub tolerance: Option<f64>,
    /// Worker threads (default: all cores). Outputs are identical for any count.
    #[arg(long)]
    pub threads: Option<usize>,
    /// Leave the run-dependent timings out of report.json (byte-identical reports).
    #[arg(long)]
    pub no_timings: bool,
    /// Output folder.
    #[arg(long)]
    pub out: PathBuf,
}

/// Runs the parsed command; returns the process exit code.
pub fn run(cli: Cli) -> i32 {
    let result = match cli.command {
        Command::Info(a) => info(&a),
        Command::Sample(a) => sample_part(&a),
        Command::Plan(a) => plan(&a),
    };
    match result {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("error: {e}");
            e.exit_code()
        }
    }
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
        println!(
            "{}",
            serde_json::to_string_pretty(&report).unwrap_or_default()
        );
        return Ok(());
    }
    let [x0, y0, z0] = report.bounding_box_min;
    let [x1, y1, z1] = report.bounding_box_max;
    println!("{name}");
    for w in &raw.warnings {
        println!("  warning: {w}");
    }
    println!(
        "  triangles        {} ({} in the file)",
        report.triangles, report.input_triangles
    );
    println!(
        "  welded vertices  {} ({} in the file)",
        report.vertices, report.input_vertices
    );
    println!("  bounding box     [{x0:.4}, {y0:.4}, {z0:.4}] .. [{x1:.4}, {y1:.4}, {z1:.4}] mm");
    println!(
        "  size             {:.4} x {:.4} x {:.4} mm",
        x1 - x0,
        y1 - y0,
        z1 - z0
    );
    println!("  components       {}", report.components);
    println!(
        "  boundary edges   {} ({} holes)",
        report.boundary_edges, report.boundary_loops
    );
    println!(
        "  non-manifold     {} edges, {} vertices",
        report.non_manifold_edges, report.non_manifold_vertices
    );
    println!(
        "  watertight       {}",
        if report.watertight { "yes" } else { "no" }
    );
    match report.genus {
        Some(g) => println!("  genus            {g}"),
        None => println!("  genus            undefined (not a manifold surface)"),
    }
    match report.volume {
        Some(v) => println!("  volume           {v:.4} mm^3"),
        None => println!("  volume           undefined (not closed)"),
    }
    println!("  surface area     {:.4} mm^2", report.surface_area);
    println!(
        "  units guess      {:?} (from the size alone; read as {})",
        report.units_guess, args.units
    );
    let problems = report.problems();
    if problems.is_empty() {
        println!("  problems         none");
    } else {
        println!("  problems:");
        for p in problems {
            println!("    - {p}");
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
    let (mesh, files) = sample_files(&part)?;
    std::fs::create_dir_all(&args.out).map_err(|source| Error::Io {
        path: args.out.display().to_string(),
        source,
    })?;
    for (name, bytes) in &files {
        job::write_atomically(&args.out.join(name), bytes)?;
    }
    println!(
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

fn plan(args: &PlanArgs) -> Result<()> {
    let mut job = match &args.job {
        Some(path) => Job::load(path).map_err(Error::Job)?,
        None => Job::default(),
    };
    if let Some(spec) = &args.tool {
        let Cutter::Ball { diameter, .. } =
            parse_cutter(spec).map_err(|e| Error::Job(e.to_string()))?;
        job.tool.diameter = diameter;
        job.tool.flute_length = job.tool.flute_length.max(diameter);
        job.tool.shank_diameter = job.tool.shank_diameter.max(diameter);
    }
    if let Some(u) = &args.units {
        job.part.units = Some(u.clone());
    }
    if let Some(up) = &args.up {
        job.part.up = Some([up[0], up[1], up[2]]);
    }
    if let Some(s) = args.scallop {
        job.strategy.scallop_height = s;
    }
    if let Some(t) = args.tolerance {
        job.strategy.tolerance = t;
    }
    let part_path: PathBuf = match (&args.part, &job.part.path) {
        (Some(p), _) => p.clone(),
        (None, Some(p)) => p.clone(),
        (None, None) => {
            return Err(Error::Job(
                "no part: give PART or set part.path in the job file".into(),
            ));
        }
    };
    let units = job.part.units.clone().unwrap_or_else(|| "mm".into());
    let threads = args.threads.unwrap_or(0);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| Error::Job(format!("--threads: {e}")))?;
    let name = part_path.display().to_string();
    let observer = progress::Bars::new();
    let output = pool.install(|| -> Result<_> {
        let raw = job::load_part(&part_path, &units)?;
        job::plan(&raw, &name, &units, &job, &observer)
    })?;
    job::write_outputs(&args.out, &output, !args.no_timings)?;
    summarise(&output.report, &args.out);
    Ok(())
}

fn summarise(r: &job::PlanReport, out: &Path) {
    println!("planned {}:", r.part.file);
    println!(
        "  poses            {} cut, {} approach, {} retract, {} rapid ({} NC blocks)",
        r.poses.cut, r.poses.approach, r.poses.retract, r.poses.rapid, r.nc_blocks
    );
    println!("  cutting length   {:.1} mm", r.cutting_length_mm);
    println!(
        "  estimated time   {:.1} min",
        r.estimated_time.total_s / 60.0
    );
    println!(
        "  clearance        cutter {:.6} mm, shank {:.3} mm, holder {:.3} mm (searched to {} mm)",
        r.clearance.min_cutter_clearance,
        r.clearance.min_shank_clearance,
        r.clearance.min_holder_clearance,
        r.clearance.search_distance
    );
    println!(
        "  unreachable      {} of {} drive points",
        r.unreachable.count, r.strategy.drive_points
    );
    println!(
        "  outputs          {}/{{job.nc, cl.csv, report.json, paths.glb}}",
        out.display()
    );
}
