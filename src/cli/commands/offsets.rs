//! `wavemill offsets`: the nested stock-to-leave shapes of a part, verified.

use std::path::PathBuf;

use clap::Args;

use crate::cli::values::*;
use crate::cli::{ball_diameter, load_manifold_part};
use crate::error::{Error, Result};
use crate::job::{self};
use crate::multires;

#[derive(Args, Debug)]
pub struct OffsetsArgs {
    /// Part file: a mesh (.stl, .obj, .gltf, .glb) or IGES surfaces (.igs, .iges): a manifold surface.
    pub part: PathBuf,
    /// Stock to leave per shape, mm, strictly decreasing, e.g. `1.0,0.5,0.2,0`. Shape j
    /// offsets hierarchy level j (the finest level for the shapes beyond it).
    #[arg(
        long,
        value_delimiter = ',',
        required = true,
        allow_negative_numbers = true
    )]
    pub allowances: Vec<f64>,
    /// Ball cutter, e.g. `ball:6` (diameter in mm): the shapes become tool-centre surfaces,
    /// offset by the ball radius as well.
    #[arg(long, value_parser = ball_spec)]
    pub tool: Option<String>,
    /// Units of the input file: mm, m or in.
    #[arg(long, default_value = "mm", value_parser = units)]
    pub units: String,
    /// Fitting tolerance of the finest level, mm (0: always build one level per allowance).
    #[arg(long, default_value_t = 0.0, value_parser = non_negative)]
    pub tolerance: f64,
    /// Triangles of the base (coarsest) mesh.
    #[arg(long, default_value_t = 2000)]
    pub base_triangles: usize,
    /// Stop simplifying the base when a collapse would move the surface more than this, mm.
    /// Absent: `--base-triangles` alone sizes the base (coarse levels, simple rough shapes);
    /// a bound keeps fillets and thin blades, for tighter shapes with more triangles.
    #[arg(long, value_parser = non_negative)]
    pub base_max_error: Option<f64>,
    /// At most this many levels above the base, 0 to 6 (default: one per allowance after the
    /// first; each level multiplies the triangles by 4).
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=6))]
    pub max_levels: Option<u32>,
    /// Edges whose faces meet at more than this angle (degrees) are feature lines.
    #[arg(long, default_value_t = 40.0, value_parser = face_angle)]
    pub crease_angle: f64,
    /// Finest grid the shapes are extracted on: at most this many cells across the part's
    /// bounding box (more: tighter shapes near the part, more triangles and time), 4 to 2000.
    #[arg(long, default_value_t = 300.0, value_parser = grid_cells)]
    pub grid_cells: f64,
    /// Leave the timings out of offsets.json (byte-identical reports).
    #[arg(long)]
    pub no_timings: bool,
    /// Output folder: `offset-<j>.glb` and `offsets.json`.
    #[arg(long)]
    pub out: PathBuf,
}

/// Runs the command.
pub fn run(args: &OffsetsArgs) -> Result<()> {
    let levels_above_base = job::levels_for_allowances(&args.allowances, args.max_levels)
        .map_err(|e| Error::Usage(format!("--allowances: {e}; --max-levels sets the levels")))?;
    let tool_radius = match &args.tool {
        Some(spec) => ball_diameter(spec)? / 2.0,
        None => 0.0,
    };
    job::check_output_dir(&args.out, &job::OutputKind::OFFSETS)?;
    let name = args.part.display().to_string();
    let mesh = load_manifold_part(&args.part, &args.units, true)?;
    let remesh = multires::RemeshOptions {
        tolerance: args.tolerance,
        base_triangles: args.base_triangles.max(4),
        base_max_error: args.base_max_error,
        max_levels: levels_above_base,
        crease_angle_deg: args.crease_angle,
        ..Default::default()
    };
    let options = crate::offset::OffsetOptions {
        max_cells_across: args.grid_cells,
        ..Default::default()
    }
    .with_tool_radius(tool_radius);
    let job::OffsetsOutput {
        mut files, report, ..
    } = job::offsets(&mesh, &remesh, &args.allowances, &options, !args.no_timings)
        .map_err(|e| crate::cli::name_flags(e, &[("allowances", "--allowances")]))?;
    let json = serde_json::to_string_pretty(&report).unwrap_or_default() + "\n";
    files.push(("offsets.json".to_string(), json.into_bytes()));
    job::write_output_set(&args.out, &job::OutputKind::OFFSETS, &files)?;
    let json_path = args.out.join("offsets.json");
    for s in &report.shapes {
        let f = &s.figures;
        say!(
            "offset {} (level {}): allowance {} mm, bound {:.4} mm, {} triangles, clearance - allowance {:.2e} mm, excess mean {:.4} max {:.4} mm, {}",
            s.shape,
            s.level,
            f.allowance_mm,
            f.bound_mm,
            f.triangles,
            f.min_clearance_minus_allowance_mm,
            f.mean_excess_mm,
            f.max_excess_mm,
            if f.verified {
                "verified"
            } else {
                "NOT VERIFIED"
            }
        );
    }
    if !report.verified {
        return Err(Error::Verification(format!(
            "{name}: a shape still fails its checks after the repairs (see {})",
            json_path.display()
        )));
    }
    say!(
        "{name}: {} shapes -> {}",
        report.shapes.len(),
        args.out.display()
    );
    Ok(())
}
