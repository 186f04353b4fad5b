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

mod commands;
mod values;

use std::path::Path;

use clap::{Parser, Subcommand};

pub use commands::access::AccessArgs;
pub use commands::contour::{ContourArgs, Direction};
pub use commands::info::InfoArgs;
pub use commands::lens::LensArgs;
pub use commands::levels::LevelsArgs;
pub use commands::offsets::OffsetsArgs;
pub use commands::plan::PlanArgs;
pub use commands::rough::RoughArgs;
pub use commands::rough_boxes::RoughBoxesArgs;
pub use commands::sample::{SampleArgs, SampleKind};
pub use commands::simulate::SimulateArgs;
pub use commands::subdivide::SubdivideArgs;
pub use commands::tessellate::TessellateArgs;
pub use commands::tools::ToolsArgs;

use crate::error::{Error, Result};
use crate::job;
use crate::mesh::{PrepareOptions, prepare};
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
    /// Print what a part file contains: size, topology, problems, units guess.
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
    /// Run a program (CL data or posted G-code) on a blank with a ball, flat, bull-nose or
    /// tapered cutter: material removed per move, gouges into the part, rapids through
    /// material, shank and holder collisions, rest material (tri-dexel stock).
    Simulate(SimulateArgs),
    /// Rough a part from its blank in layers (3-axis) down to its verified offset shape with a
    /// library tool: ramped entries, posted, read back and checked (shape, part, tri-dexel
    /// stock with the whole tool).
    Rough(RoughArgs),
    /// Rough an IGES part by seed 002's convex-hull boxes: its Bézier patches boxed, the stock
    /// sliced at the boxes' tops (thick layers split by de Casteljau, thin ones merged), each
    /// pocket bounded by the union of the boxes; posted, read back and checked against every
    /// box; with --compare beside the uniform route.
    RoughBoxes(RoughBoxesArgs),
    /// Tessellate an IGES part (trimmed NURBS and revolved surfaces) into one welded mesh
    /// within a chord tolerance, and measure how far it is from the surfaces.
    Tessellate(TessellateArgs),
    /// Turn a freeform lens (seed 003): the surface (IGES face or TOML description) into a
    /// nose-radius-compensated polar R × θ grid and a spiral slow-tool-servo X/Z/C program,
    /// both read back and checked against the surface.
    Lens(LensArgs),
}

/// Runs the parsed command; returns the process exit code.
pub fn run(cli: Cli) -> i32 {
    let result = match cli.command {
        Command::Info(a) => commands::info::run(&a),
        Command::Sample(a) => commands::sample::run(&a),
        Command::Plan(a) => commands::plan::run(&a),
        Command::Subdivide(a) => commands::subdivide::run(&a),
        Command::Tessellate(a) => commands::tessellate::run(&a),
        Command::Lens(a) => commands::lens::run(&a),
        Command::Levels(a) => commands::levels::run(&a),
        Command::Contour(a) => commands::contour::run(&a),
        Command::Offsets(a) => commands::offsets::run(&a),
        Command::Access(a) => commands::access::run(&a),
        Command::Tools(a) => commands::tools::run(&a),
        Command::Simulate(a) => commands::simulate::run(&a),
        Command::Rough(a) => commands::rough::run(&a),
        Command::RoughBoxes(a) => commands::rough_boxes::run(&a),
    };
    match result {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("error: {e}");
            e.exit_code()
        }
    }
}

/// Checks, before any work, that `path` can be written as one output file: not a folder, and
/// its folder exists or can be made.
pub(crate) fn check_output_file(path: &Path) -> Result<()> {
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
pub(crate) fn load(path: &Path, units: &str) -> Result<crate::mesh::io::RawMesh> {
    let raw = job::load_part(path, units)?;
    for w in &raw.warnings {
        eprintln!("warning: {}: {w}", path.display());
    }
    Ok(raw)
}

/// Reads, welds and orients a part and refuses it, saying why, unless it is a manifold surface
/// (and, with `closed`, a closed one).
pub(crate) fn load_manifold_part(
    path: &Path,
    units: &str,
    closed: bool,
) -> Result<crate::mesh::Mesh> {
    let name = path.display().to_string();
    let raw = load(path, units)?;
    let (mesh, report) =
        prepare(&raw.mesh, &PrepareOptions::default()).map_err(|reason| Error::Mesh {
            file: name.clone(),
            reason: reason.to_string(),
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

pub(crate) fn create_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|source| Error::Io {
        path: dir.display().to_string(),
        source,
    })
}

/// The diameter of a `ball:D` spec; other cutters are refused by name (the 5-axis stages drive
/// a ball centre).
pub(crate) fn ball_diameter(spec: &str) -> Result<f64> {
    match parse_cutter(spec).map_err(|e| Error::Usage(e.to_string()))? {
        Cutter::Ball { diameter, .. } => Ok(diameter),
        other => Err(Error::Usage(format!(
            "tool `{spec}` is a {} cutter: this command drives a ball-end mill (ball:D)",
            other.kind()
        ))),
    }
}

/// The diameter of a `flat:D` spec; other cutters are refused by name (2.5D contours drive a
/// flat end mill's centre).
pub(crate) fn flat_diameter(spec: &str) -> Result<f64> {
    match parse_cutter(spec).map_err(|e| Error::Usage(e.to_string()))? {
        Cutter::Flat { diameter, .. } => Ok(diameter),
        other => Err(Error::Usage(format!(
            "tool `{spec}` is a {} cutter: this command drives a flat end mill (flat:D)",
            other.kind()
        ))),
    }
}

/// The machine flags `plan` and `simulate` share.
#[derive(clap::Args, Debug, Default)]
pub struct MachineArgs {
    /// The machine: a shipped one (trunnion-ac, trunnion-bc, head-table-bc, head-table-ac,
    /// head-head) or a machine definition file (TOML, see data/machines/); overrides the job
    /// file's machine.definition. Without one, the job's table-table A/C machine.
    #[arg(long)]
    pub machine: Option<String>,
    /// Output mode: `joint` (machine axes, linearised) or `tcp` (tool tip in the part frame,
    /// the control's tool-centre-point mode on); overrides the machine's.
    #[arg(long, value_parser = ["joint", "tcp"])]
    pub output: Option<String>,
    /// Feed mode: `per-minute` (G94) or `inverse-time` (G93); overrides the machine's.
    #[arg(long, value_parser = ["per-minute", "inverse-time"])]
    pub feed: Option<String>,
}

/// The machine flags applied to `job`: `--output` and `--feed` (overriding the machine's
/// modes), then `--machine` (a shipped name or a definition file); each flag given is added
/// to `flags`, so later errors name it.
pub(crate) fn apply_machine_flags(
    job: &mut crate::job::Job,
    args: &MachineArgs,
    flags: &mut Vec<(&'static str, &'static str)>,
) -> Result<()> {
    if let Some(o) = &args.output {
        job.machine.output = Some(if o == "tcp" {
            crate::post::OutputMode::Tcp
        } else {
            crate::post::OutputMode::Joint
        });
        flags.push(("machine.output", "--output"));
    }
    if let Some(f) = &args.feed {
        job.machine.feed = Some(if f == "inverse-time" {
            crate::post::FeedMode::InverseTime
        } else {
            crate::post::FeedMode::PerMinute
        });
        flags.push(("machine.feed", "--feed"));
    }
    if let Some(m) = &args.machine {
        flags.push(("machine.definition", "--machine"));
        job.use_machine(m)
            .map_err(|e| name_flags(Error::from(e), flags))?;
    }
    Ok(())
}

/// Names the command-line flag in place of the library's option or job-file key: an option
/// error whose key has a flag becomes a usage error (exit 2) naming the flag, and a limit the
/// user can raise names the flag that raises it. `flags` maps key prefixes to flags.
pub(crate) fn name_flags(error: Error, flags: &[(&str, &str)]) -> Error {
    let flag_of = |key: &str| {
        flags
            .iter()
            .find(|(prefix, _)| key.starts_with(prefix))
            .map(|(_, flag)| *flag)
    };
    match error {
        Error::JobFile(e) => match e.key().and_then(flag_of) {
            Some(flag) => Error::Usage(format!("{flag}: {e}")),
            None => Error::JobFile(e),
        },
        Error::TooLarge {
            what,
            estimate,
            limit,
            advice,
            limit_key,
        } => {
            let limit_key = match flag_of(&limit_key) {
                Some(flag) if limit_key.contains('.') => format!("{limit_key} or {flag}"),
                Some(flag) => flag.to_string(),
                None => limit_key,
            };
            Error::TooLarge {
                what,
                estimate,
                limit,
                advice,
                limit_key,
            }
        }
        other => other,
    }
}

/// `--tool ball:D`: the job's ball diameter, with flutes and shank at least as long and wide.
pub(crate) fn set_tool(job: &mut crate::job::Job, spec: &str) -> Result<()> {
    let diameter = ball_diameter(spec)?;
    job.tool.diameter = diameter;
    job.tool.flute_length = job.tool.flute_length.max(diameter);
    job.tool.shank_diameter = job.tool.shank_diameter.max(diameter);
    Ok(())
}
