//! `wavemill tessellate`: an IGES part into one welded mesh within a chord tolerance.

use std::path::PathBuf;

use clap::Args;

use crate::cad::tessellate::TessellateOptions;
use crate::cli::check_output_file;
use crate::cli::values::*;
use crate::error::{Error, Result};
use crate::job;
use crate::mesh::io::{GlbBuilder, write_obj, write_stl};

#[derive(Args, Debug)]
pub struct TessellateArgs {
    /// IGES part (.igs, .iges): its trimmed surfaces, in the file's own unit.
    pub part: PathBuf,
    /// Largest distance between the surfaces and the mesh, mm.
    #[arg(long, default_value_t = 0.01, value_parser = positive)]
    pub tolerance: f64,
    /// Output mesh: `.glb`, `.obj` or `.stl`.
    #[arg(long)]
    pub out: PathBuf,
    /// Samples per triangle side when measuring the deviation (0: do not measure).
    #[arg(long, default_value_t = 4)]
    pub measure: usize,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
}

/// Runs the command.
pub fn run(args: &TessellateArgs) -> Result<()> {
    let name = args.part.display().to_string();
    if !job::is_iges(&args.part) {
        return Err(Error::Usage(format!(
            "{name}: not an IGES file (.igs or .iges); meshes need no tessellation"
        )));
    }
    let extension = args
        .out
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if !matches!(extension.as_deref(), Some("glb" | "obj" | "stl")) {
        return Err(Error::Usage(format!(
            "--out {}: the output must end in .glb, .obj or .stl",
            args.out.display()
        )));
    }
    check_output_file(&args.out)?;
    let options = TessellateOptions {
        tolerance: args.tolerance,
    };
    let part = job::tessellate_iges(&args.part, &options)?;
    let warnings = job::tessellation_warnings(&part, &options);
    let mesh = &part.tessellation.mesh;
    let comment = format!(
        "wavemill tessellate: {name}, {} faces, tolerance {} mm",
        part.model.faces.len(),
        args.tolerance
    );
    let bytes = match extension.as_deref() {
        Some("obj") => write_obj(mesh, &comment),
        Some("stl") => write_stl(mesh, &comment),
        _ => {
            let mut glb = GlbBuilder::new();
            glb.add_triangles("part", mesh, [0.72, 0.74, 0.78, 1.0], None)
                .map_err(|error| Error::Glb {
                    file: args.out.display().to_string(),
                    error,
                })?;
            glb.build()
        }
    };
    job::write_atomically(&args.out, &bytes)?;
    let summary =
        (args.measure > 0).then(|| job::tessellate_summary(&part, &options, args.measure));
    if args.json {
        let value = match &summary {
            Some(s) => serde_json::to_value(s),
            None => serde_json::to_value(&part.tessellation.report),
        }
        .unwrap_or_default();
        say!(
            "{}",
            serde_json::to_string_pretty(&value).unwrap_or_default()
        );
    } else {
        let r = &part.tessellation.report;
        say!("{name}");
        for w in &warnings {
            say!("  warning: {w}");
        }
        say!("  faces            {}", r.faces);
        say!("  triangles        {}", r.triangles);
        say!("  vertices         {}", r.vertices);
        say!(
            "  seams            {} junction vertices, {} vertices and {} edges sewn (widest gap {:.4} mm)",
            r.junction_vertices,
            r.sewn_vertices,
            r.sewn_edges,
            r.widest_sewn_gap
        );
        say!(
            "  open seams       {} ({} edges, {:.3} mm)",
            r.open_seams.len(),
            r.open_seam_edges,
            r.open_seam_length
        );
        say!("  non-manifold     {} edges", r.non_manifold_edges);
        if let Some(s) = &summary {
            say!(
                "  deviation        max {:.4} mm (face {}), rms {:.4} mm over {} samples; tolerance {} mm",
                s.deviation.max,
                s.deviation.worst_face,
                s.deviation.rms,
                s.deviation.samples,
                args.tolerance
            );
        }
        say!("  -> {}", args.out.display());
    }
    for w in &warnings {
        if args.json {
            eprintln!("warning: {name}: {w}");
        }
    }
    Ok(())
}
