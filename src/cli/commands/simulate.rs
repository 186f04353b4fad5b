//! `wavemill simulate`: a program (CL data or posted G-code) run on a blank with a ball-end
//! mill, checked against the part.

use std::path::PathBuf;

use clap::Args;

use crate::cli::values::*;
use crate::cli::{load, name_flags};
use crate::error::{Error, Result};
use crate::job::{self};

#[derive(Args, Debug)]
pub struct SimulateArgs {
    /// Part: a mesh (.stl, .obj, .gltf, .glb) or IGES surfaces (.igs, .iges), closed, in the frame of the program.
    pub part: PathBuf,
    /// The program: CL data (a `.csv`, as `plan` writes `cl.csv`: tip, axis, kind, feed,
    /// tool) or posted G-code (any other name, as `plan` writes `job.nc`), read back through
    /// the machine's forward kinematics: the job's `[machine]` with --job, else a table-table
    /// A/C with the part where `plan` puts it by default.
    #[arg(long, visible_alias = "cl")]
    pub program: PathBuf,
    /// The blank: `box:X0,Y0,Z0,X1,Y1,Z1`, `cylinder:R,Z0,Z1` (about the vertical line through
    /// the part's box centre), `offset:M` (the part grown by M mm) or `mesh:FILE` (a closed
    /// mesh), in mm.
    #[arg(long, value_name = "SPEC", value_parser = blank)]
    pub stock: job::BlankSpec,
    /// A job file: its `[tool]` (ball, flutes, shank, stickout, holder) is the tool, and the
    /// shank and holder are checked against the material.
    #[arg(long)]
    pub job: Option<PathBuf>,
    /// The cutter: `ball:D`, `flat:D`, `bull:D:R` (corner radius R) or `taper:D:DEG` (tapered
    /// ball, tip diameter D, half-angle DEG), mm (with --job: a `ball:D` replaces the job's
    /// ball diameter).
    #[arg(long, value_name = "SPEC", value_parser = cutter_spec, required_unless_present = "job")]
    pub tool: Option<String>,
    #[command(flatten)]
    pub machine: crate::cli::MachineArgs,
    /// Fluted length from the tip, mm [default: 3 × D; with --job: the job's].
    #[arg(long, value_parser = positive)]
    pub flute_length: Option<f64>,
    /// Distance between dexel lines, mm [default: the part's box diagonal / 400, within 0.05
    /// to 1 mm]. Memory and time grow as its inverse square.
    #[arg(long, value_parser = positive)]
    pub resolution: Option<f64>,
    /// How deep the tool may go into the part before it is a gouge, mm.
    #[arg(long, default_value_t = 0.01, value_parser = non_negative)]
    pub tolerance: f64,
    /// Refuse a model with more dexel lines than this, before building it.
    #[arg(long, default_value_t = crate::stock::DEFAULT_MAX_DEXELS)]
    pub max_dexels: usize,
    /// Units of the part and of a mesh blank: mm, m or in.
    #[arg(long, default_value = "mm", value_parser = units)]
    pub units: String,
    /// Leave the run-dependent timings out of simulation.json (byte-identical reports).
    #[arg(long)]
    pub no_timings: bool,
    /// Output folder: simulation.json, stock.glb, stock.png.
    #[arg(long)]
    pub out: PathBuf,
}

/// The flag that sets each option of [`job::SimulateOptions`].
const FLAGS: &[(&str, &str)] = &[
    ("stock", "--stock"),
    ("tool", "--tool"),
    ("resolution", "--resolution"),
    ("tolerance", "--tolerance"),
    ("max_dexels", "--max-dexels"),
];

/// Runs the command.
pub fn run(args: &SimulateArgs) -> Result<()> {
    job::check_output_dir(&args.out, &job::OutputKind::SIMULATE)?;
    let mut machine: Option<job::Job> = None;
    let mut cutter_given = None;
    let (diameter, assembly) = match &args.job {
        Some(path) => {
            let mut job = job::Job::load(path)?;
            if let Some(spec) = &args.tool {
                crate::cli::set_tool(&mut job, spec)?;
            }
            if let Some(f) = args.flute_length {
                job.tool.flute_length = f;
            }
            job.validate()
                .map_err(|e| name_flags(Error::from(e), &[("tool.", "--tool")]))?;
            let found = (job.tool.diameter, Some(job.tool.assembly()));
            machine = Some(job);
            found
        }
        None => {
            let spec = args.tool.as_deref().unwrap_or_default();
            let cutter = crate::tool::parse_cutter(spec)
                .map_err(|e| Error::Usage(format!("--tool: {e}")))?;
            cutter_given = Some(cutter);
            (cutter.diameter(), None)
        }
    };
    let name = args.part.display().to_string();
    let raw = load(&args.part, &args.units)?;
    let cl_name = args.program.display().to_string();
    let cl_text = std::fs::read_to_string(&args.program).map_err(|source| Error::Io {
        path: cl_name.clone(),
        source,
    })?;
    let mut options = job::SimulateOptions::new(args.stock.clone(), diameter);
    options.flute_length = args.flute_length;
    options.assembly = assembly;
    options.cutter = cutter_given;
    options.resolution = args.resolution;
    options.tolerance = args.tolerance;
    options.max_dexels = args.max_dexels;
    options.units = args.units.clone();
    options.timings = !args.no_timings;
    let is_cl = args
        .program
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("csv"));
    if !is_cl {
        let mut job = machine.unwrap_or_default();
        let mut flags = vec![("tool.", "--tool")];
        crate::cli::apply_machine_flags(&mut job, &args.machine, &mut flags)?;
        if args.job.is_none() {
            // The job's default ball stands for the tool's length on a machine with head
            // axes; the cutter given is what removes material.
            if let Some(cutter) = cutter_given {
                job.tool.diameter = cutter.diameter();
            }
        }
        // The machine's file and modes are read here, so that a fault names its flag.
        job.machine_definition()
            .map_err(|e| name_flags(Error::from(e), &flags))?;
        options.format = job::ProgramFormat::PostedFor(Box::new(job));
    }
    let bars = super::super::progress::Bars::new();
    let run = job::simulate_program(&raw, &name, &cl_text, &cl_name, &options, &bars)
        .map_err(|e| name_flags(e, FLAGS))?;
    let report = &run.report;
    for w in &report.warnings {
        eprintln!("warning: {w}");
    }
    say!(
        "{} moves: {:.1} mm³ removed, {} gouging move(s) (deepest {:.4} mm), {} rapid(s) through material, {:.1} % of the cutting length in air",
        report.moves,
        report.removed_volume_mm3,
        report.gouge.count,
        report.gouge.max_depth_mm,
        report.rapids_through_material.len(),
        100.0 * report.air_cut_fraction
    );
    say!(
        "rest over the part: max {:.3} mm, mean {:.3} mm, p99 {:.3} mm; depth of cut: axial max {:.3} mm, radial max {:.3} mm",
        report.rest.max_mm,
        report.rest.mean_mm,
        report.rest.p99_mm,
        report.depth_of_cut.axial_mm.max,
        report.depth_of_cut.radial_mm.max
    );
    say!(
        "-> {} (+ stock.glb, stock.png)",
        args.out.join("simulation.json").display()
    );
    job::write_simulation(&args.out, &run)
}
