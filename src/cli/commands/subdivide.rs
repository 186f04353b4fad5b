//! `wavemill subdivide`: Loop subdivision of a mesh.

use std::path::PathBuf;

use clap::Args;

use crate::cli::values::*;
use crate::cli::{check_output_file, load};
use crate::error::{Error, Result};
use crate::job::{self};
use crate::mesh::io::{GlbBuilder, write_obj};
use crate::mesh::{PrepareOptions, prepare};
use crate::multires;

#[derive(Args, Debug)]
pub struct SubdivideArgs {
    /// Part file: a mesh (.stl, .obj, .gltf, .glb) or IGES surfaces (.igs, .iges).
    pub part: PathBuf,
    /// Number of 1-to-4 subdivision steps, 0 to 8.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(0..=8))]
    pub levels: u32,
    /// Treat edges whose faces meet at more than this angle (degrees) as sharp creases.
    #[arg(long, value_parser = face_angle)]
    pub crease_angle: Option<f64>,
    /// Refuse to make more triangles than this (each level multiplies them by 4; a triangle
    /// of the result costs about 100 bytes while it is built).
    #[arg(long, default_value_t = 20_000_000)]
    pub max_triangles: u64,
    /// Units of the input file: mm, m or in.
    #[arg(long, default_value = "mm", value_parser = units)]
    pub units: String,
    /// Output file; `.obj` or `.glb`.
    #[arg(long)]
    pub out: PathBuf,
}

/// Runs the command.
pub fn run(args: &SubdivideArgs) -> Result<()> {
    let name = args.part.display().to_string();
    let extension = args
        .out
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if !matches!(extension.as_deref(), Some("obj" | "glb")) {
        return Err(Error::Usage(format!(
            "--out {}: the output must end in .obj or .glb",
            args.out.display()
        )));
    }
    check_output_file(&args.out)?;
    let raw = load(&args.part, &args.units)?;
    let mesh_error = |reason: String| Error::Mesh {
        file: name.clone(),
        reason,
    };
    let (mesh, _) =
        prepare(&raw.mesh, &PrepareOptions::default()).map_err(|e| mesh_error(e.to_string()))?;
    let triangles = mesh.triangles.len() as f64 * 4f64.powi(args.levels as i32);
    if triangles > args.max_triangles as f64 {
        return Err(Error::TooLarge {
            what: format!(
                "subdividing {name} ({} triangles) {} times",
                mesh.triangles.len(),
                args.levels
            ),
            estimate: format!(
                "{triangles:.3e} triangles (about {:.1} GB)",
                triangles * 1e-7
            ),
            limit: format!("{} triangles", args.max_triangles),
            advice: "use fewer --levels".into(),
            limit_key: "--max-triangles".into(),
        });
    }
    let creases = match args.crease_angle {
        Some(angle) => multires::detect_creases(&mesh, angle),
        None => multires::Creases::none(),
    };
    let (fine, _) = multires::loop_subdivide(&mesh, &creases, args.levels)
        .map_err(|e| mesh_error(e.to_string()))?;
    let bytes = if extension.as_deref() == Some("obj") {
        write_obj(
            &fine,
            &format!("wavemill subdivide: {name}, {} Loop levels", args.levels),
        )
    } else {
        let mut glb = GlbBuilder::new();
        glb.add_triangles("subdivided", &fine, [0.72, 0.74, 0.78, 1.0], None)
            .map_err(|error| Error::Glb {
                file: name.clone(),
                error,
            })?;
        glb.build()
    };
    job::write_atomically(&args.out, &bytes)?;
    say!(
        "{name}: {} -> {} triangles ({} levels, {} crease edges) -> {}",
        mesh.triangles.len(),
        fine.triangles.len(),
        args.levels,
        creases.len(),
        args.out.display()
    );
    Ok(())
}
