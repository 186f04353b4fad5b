//! `wavemill info`: what a mesh file contains.

use std::path::PathBuf;

use clap::Args;

use crate::cli::values::*;
use crate::error::{Error, Result};
use crate::job::{self};
use crate::mesh::{PrepareOptions, prepare};

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

/// Runs the command.
pub fn run(args: &InfoArgs) -> Result<()> {
    let raw = job::load_part(&args.part, &args.units)?;
    let name = args.part.display().to_string();
    let (_, report) =
        prepare(&raw.mesh, &PrepareOptions::default()).map_err(|reason| Error::Mesh {
            file: name.clone(),
            reason: reason.to_string(),
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
