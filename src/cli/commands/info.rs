//! `wavemill info`: what a mesh file contains.

use std::path::PathBuf;

use clap::Args;

use crate::cli::values::*;
use crate::error::{Error, Result};
use crate::impeller::{BladeEdges, HubPassage, PassageOptions, PieceKind, RootCorner, blade_edges};
use crate::job::{self};
use crate::mesh::{PrepareOptions, prepare};

#[derive(Args, Debug)]
pub struct InfoArgs {
    /// Part file: a mesh (.stl, .obj, .gltf, .glb) or IGES surfaces (.igs, .iges).
    pub part: PathBuf,
    /// Units the file is written in.
    #[arg(long, default_value = "mm", value_parser = units)]
    pub units: String,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
    /// Write the part coloured by what the impeller recognition found (hub, each blade and
    /// splitter) to this GLB file.
    #[arg(long, value_name = "FILE")]
    pub glb: Option<PathBuf>,
}

/// The JSON report: the mesh's, and the impeller found in it or why there is none.
#[derive(serde::Serialize)]
struct InfoReport<'a> {
    #[serde(flatten)]
    mesh: &'a crate::mesh::MeshReport,
    #[serde(skip_serializing_if = "Option::is_none")]
    impeller: Option<&'a crate::impeller::Impeller>,
    #[serde(skip_serializing_if = "Option::is_none")]
    not_an_impeller: Option<String>,
    /// The main blades' leading and trailing edges (along the hub's meridian).
    #[serde(skip_serializing_if = "Option::is_none")]
    blade_edges: Option<&'a BladeEdges>,
}

/// Runs the command.
pub fn run(args: &InfoArgs) -> Result<()> {
    let raw = job::load_part(&args.part, &args.units)?;
    let name = args.part.display().to_string();
    let (mesh, report) =
        prepare(&raw.mesh, &PrepareOptions::default()).map_err(|reason| Error::Mesh {
            file: name.clone(),
            reason: reason.to_string(),
        })?;
    // Recognition needs inside and outside told apart.
    let impeller = if report.watertight {
        crate::impeller::recognise(&mesh, &Default::default()).map_err(|e| e.to_string())
    } else {
        Err("the mesh is not closed".to_string())
    };
    // The edges run along the hub's meridian: the passage's stations give it.
    let edges = impeller.as_ref().ok().and_then(|found| {
        let options = PassageOptions {
            station_step: 0.25,
            ball_radius: 1.0,
            scallop_height: 0.01,
            overlap: 0.0,
        };
        let passage = HubPassage::new(&mesh, found, &options).ok()?;
        Some(blade_edges(&mesh, found, &passage))
    });
    if let Some(path) = &args.glb {
        let found = impeller.as_ref().map_err(|reason| {
            Error::Usage(format!(
                "--glb {}: {name} is not recognised as an impeller: {reason}",
                path.display()
            ))
        })?;
        let bytes =
            crate::impeller::impeller_glb(&mesh, found, edges.as_ref()).map_err(|error| {
                Error::Glb {
                    file: path.display().to_string(),
                    error,
                }
            })?;
        job::write_atomically(path, &bytes)?;
    }
    if args.json {
        let out = InfoReport {
            mesh: &report,
            impeller: impeller.as_ref().ok(),
            not_an_impeller: impeller.as_ref().err().cloned(),
            blade_edges: edges.as_ref(),
        };
        say!("{}", serde_json::to_string_pretty(&out).unwrap_or_default());
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
    match &impeller {
        Ok(found) => {
            let [ax, ay, az] = found.axis;
            let [cx, cy, cz] = found.centre;
            say!(
                "  impeller         {} blades{}, {}-fold symmetric (turned by a pitch, p99 \
                 {:.4} mm, max {:.4} mm off itself)",
                found.blades,
                if found.splitters > 0 {
                    format!(" and {} splitters", found.splitters)
                } else {
                    String::new()
                },
                found.order,
                found.symmetry_p99_mm,
                found.symmetry_max_mm
            );
            say!(
                "    axis           ({ax:.4}, {ay:.4}, {az:.4}) through ({cx:.3}, {cy:.3}, {cz:.3})"
            );
            say!(
                "    hub            {} triangles, {:.1} mm^2, radius {:.3} .. {:.3} mm",
                found.hub_triangles,
                found.hub_area_mm2,
                found.hub_radius_mm[0],
                found.hub_radius_mm[1]
            );
            if let (Some(low), Some(high)) = (found.shroud.first(), found.shroud.last()) {
                say!(
                    "    shroud         blade tips at radius {:.3} mm (height {:.3}) to {:.3} mm \
                     (height {:.3})",
                    low[1],
                    low[0],
                    high[1],
                    high[0]
                );
            }
            for (kind, label) in [
                (PieceKind::Blade, "blade roots"),
                (PieceKind::Splitter, "splitter roots"),
            ] {
                let roots: Vec<&RootCorner> = found
                    .pieces
                    .iter()
                    .filter(|p| p.kind == kind)
                    .filter_map(|p| p.root.as_ref())
                    .collect();
                if roots.is_empty() {
                    continue;
                }
                let median = |mut v: Vec<f64>| {
                    v.sort_by(f64::total_cmp);
                    v[v.len() / 2]
                };
                let radius = median(roots.iter().map(|r| r.fillet_radius_mm).collect());
                let smallest = roots
                    .iter()
                    .map(|r| r.fillet_radius_min_mm)
                    .fold(f64::INFINITY, f64::min);
                let crease = median(roots.iter().map(|r| r.crease_deg).collect());
                say!(
                    "    {label:<14} {}, crease {crease:.1} deg across the root edges",
                    if radius > 0.0 {
                        format!("fillet radius {radius:.3} mm (smallest {smallest:.3} mm)")
                    } else {
                        "sharp (no ball finishes the corner)".to_string()
                    }
                );
            }
            if let Some(edges) = &edges {
                for (label, curve, area) in [
                    ("leading edge", &edges.leading, edges.leading_area_mm2),
                    ("trailing edge", &edges.trailing, edges.trailing_area_mm2),
                ] {
                    match (curve.first(), curve.last()) {
                        (Some(low), Some(high)) => say!(
                            "    {label:<14} radius {:.3} mm ({:.3} mm above the hub) to {:.3} mm \
                             ({:.3} mm up), {:.1} mm^2 per blade",
                            low[2],
                            low[0],
                            high[2],
                            high[0],
                            area / found.blades.max(1) as f64
                        ),
                        _ => say!("    {label:<14} none found (no loop ends facing the flow)"),
                    }
                }
            }
        }
        Err(reason) => say!("  impeller         no: {reason}"),
    }
    Ok(())
}
