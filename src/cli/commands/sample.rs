//! `wavemill sample`: the bundled sample parts, generated.

use std::path::PathBuf;

use clap::{Args, ValueEnum};

use crate::error::{Error, Result};
use crate::job::{self, SamplePart, sample_files};
use crate::sample;

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum SampleKind {
    /// A centrifugal impeller: hub with a bore, twisted blades, narrow channels.
    Impeller,
    /// A twisted turbine blade on a root block.
    Blade,
    /// A 44 mm freeform lens: a rational bicubic patch closed by five planes, as IGES
    /// (lens.igs), for `wavemill lens`.
    Lens,
}

#[derive(Args, Debug)]
pub struct SampleArgs {
    pub kind: SampleKind,
    /// Output folder; writes KIND.glb and KIND.obj there (the lens: lens.igs).
    #[arg(long, default_value = "data")]
    pub out: PathBuf,
    /// Impeller: number of blades.
    #[arg(long)]
    pub blades: Option<u32>,
    /// Target edge length, mm (smaller = finer mesh).
    #[arg(long)]
    pub resolution: Option<f64>,
}

/// Runs the command.
pub fn run(args: &SampleArgs) -> Result<()> {
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
        SampleKind::Lens => return write_lens(args),
        SampleKind::Blade => {
            let mut p = sample::BladeParams::default();
            if let Some(r) = args.resolution {
                p.resolution = r;
            }
            SamplePart::Blade(p)
        }
    };
    // Only --blades and --resolution can make the parameters invalid: a usage error.
    let (mesh, files) = sample_files(&part).map_err(|e| match e {
        Error::Sample(e @ sample::SampleError::InvalidParameter { .. }) => {
            Error::Usage(format!("--blades / --resolution: {e}"))
        }
        other => other,
    })?;
    std::fs::create_dir_all(&args.out).map_err(|source| Error::Io {
        path: args.out.display().to_string(),
        source,
    })?;
    for (name, bytes) in &files {
        job::write_atomically(&args.out.join(name), bytes)?;
    }
    say!(
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

/// `wavemill sample lens`: the freeform lens as IGES.
fn write_lens(args: &SampleArgs) -> Result<()> {
    if args.blades.is_some() || args.resolution.is_some() {
        return Err(Error::Usage(
            "--blades and --resolution apply to the impeller and the blade".into(),
        ));
    }
    let text = sample::lens::freeform_lens_iges()
        .map_err(|e| Error::Internal(format!("the sample lens: {e}")))?;
    std::fs::create_dir_all(&args.out).map_err(|source| Error::Io {
        path: args.out.display().to_string(),
        source,
    })?;
    let path = args.out.join("lens.igs");
    job::write_atomically(&path, text.as_bytes())?;
    say!(
        "lens: a freeform patch and five planes -> {}",
        path.display()
    );
    Ok(())
}
