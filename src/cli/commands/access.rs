//! `wavemill access`: visibility maps of a part, and tool axes for query points.

use std::path::PathBuf;

use clap::Args;

use crate::cli::values::*;
use crate::cli::{load, set_tool};
use crate::error::{Error, Result};
use crate::job::{self, Job};

#[derive(Args, Debug)]
pub struct AccessArgs {
    /// Part: a mesh (.stl, .obj, .gltf, .glb) or IGES surfaces (.igs, .iges).
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

/// Runs the command.
pub fn run(args: &AccessArgs) -> Result<()> {
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
    let output = job::access(&raw, &name, &job, &options, query.as_deref())
        .map_err(|e| crate::cli::name_flags(e, &[("directions", "--directions")]))?;
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
