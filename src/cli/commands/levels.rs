//! `wavemill levels`: the rough-to-fine hierarchy of a part and its wavelet analysis.

use std::path::PathBuf;

use clap::Args;

use crate::cli::load_manifold_part;
use crate::cli::values::*;
use crate::error::Result;
use crate::job::{self};
use crate::multires;

#[derive(Args, Debug)]
pub struct LevelsArgs {
    /// Part file: a mesh (.stl, .obj, .gltf, .glb) or IGES surfaces (.igs, .iges): a manifold surface.
    pub part: PathBuf,
    /// Units of the input file: mm, m or in.
    #[arg(long, default_value = "mm", value_parser = units)]
    pub units: String,
    /// Fitting tolerance: two-sided Hausdorff distance of the finest level to the part, mm.
    #[arg(long, default_value_t = 0.01, value_parser = positive)]
    pub tolerance: f64,
    /// Triangles of the base (coarsest) mesh.
    #[arg(long, default_value_t = 2000)]
    pub base_triangles: usize,
    /// Stop simplifying the base earlier when a collapse would move the surface more than
    /// this, mm: keeps thin blades and fillets in the base [default: 3 × tolerance].
    #[arg(long, value_parser = non_negative)]
    pub base_max_error: Option<f64>,
    /// At most this many levels above the base, 0 to 6 (each multiplies the triangles by 4).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(0..=6))]
    pub max_levels: u32,
    /// Edges whose faces meet at more than this angle (degrees) are feature lines, followed
    /// exactly by every level.
    #[arg(long, default_value_t = 40.0, value_parser = face_angle)]
    pub crease_angle: f64,
    /// Tangential relaxation passes over each level's new vertices (each followed by
    /// re-projection onto the part); off by default: it evens the triangles but loosens the fit.
    #[arg(long, default_value_t = 0)]
    pub relax_passes: u32,
    /// Plain lifting, without the k-disk least-squares update that brings the coarse levels
    /// closer to the part (measured: L∞ deviation of the base 2-4x smaller with it).
    #[arg(long)]
    pub plain_lifting: bool,
    /// Leave the timings out of levels.json (byte-identical reports).
    #[arg(long)]
    pub no_timings: bool,
    /// Output folder: `level-<j>.glb` and `levels.json`.
    #[arg(long)]
    pub out: PathBuf,
}

/// Runs the command.
pub fn run(args: &LevelsArgs) -> Result<()> {
    job::check_output_dir(&args.out, &job::OutputKind::LEVELS)?;
    let name = args.part.display().to_string();
    let mesh = load_manifold_part(&args.part, &args.units, false)?;
    let options = multires::RemeshOptions {
        tolerance: args.tolerance,
        base_triangles: args.base_triangles.max(4),
        base_max_error: Some(args.base_max_error.unwrap_or(3.0 * args.tolerance)),
        relax_passes: args.relax_passes,
        max_levels: args.max_levels,
        crease_angle_deg: args.crease_angle,
        ..Default::default()
    };
    let wavelet_options =
        multires::WaveletOptions::default().with_kdisk_update(!args.plain_lifting);
    let (mut files, report) = job::levels(&mesh, &options, &wavelet_options, !args.no_timings)?;
    let json = serde_json::to_string_pretty(&report).unwrap_or_default() + "\n";
    files.push(("levels.json".to_string(), json.into_bytes()));
    job::write_output_set(&args.out, &job::OutputKind::LEVELS, &files)?;
    for l in &report.levels {
        say!(
            "level {}: {:>8} triangles, max deviation to finest {:.4} mm, fit to input {:.4} mm",
            l.level,
            l.triangles,
            l.max_deviation_mm,
            l.fitted_hausdorff_mm
        );
    }
    say!(
        "finest level within {:.4} mm of {name} (tolerance {}), reconstruction error {:.2e} mm -> {}",
        report.finest_hausdorff_mm,
        report.tolerance_mm,
        report.reconstruction_error_mm,
        args.out.display()
    );
    Ok(())
}
