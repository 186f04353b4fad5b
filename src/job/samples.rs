//! The bundled sample parts as files: what `wavemill sample` writes into `data/`.

use crate::error::{Error, Result};
use crate::mesh::Mesh;
use crate::mesh::io::{GlbBuilder, write_obj};
use crate::sample::{self, BladeParams, ImpellerParams};

/// Which sample part.
#[derive(Clone, Debug, PartialEq)]
pub enum SamplePart {
    Impeller(ImpellerParams),
    Blade(BladeParams),
}

impl SamplePart {
    pub fn name(&self) -> &'static str {
        match self {
            SamplePart::Impeller(_) => "impeller",
            SamplePart::Blade(_) => "blade",
        }
    }

    pub fn mesh(&self) -> Result<Mesh> {
        Ok(match self {
            SamplePart::Impeller(p) => sample::impeller(p)?,
            SamplePart::Blade(p) => sample::blade(p)?,
        })
    }
}

/// A file to write: its name and its bytes.
pub type NamedFile = (String, Vec<u8>);

/// The mesh of a sample part and its GLB and OBJ files; deterministic.
pub fn sample_files(part: &SamplePart) -> Result<(Mesh, Vec<NamedFile>)> {
    let name = part.name();
    let mesh = part.mesh()?;
    let mut glb = GlbBuilder::new();
    glb.add_triangles(name, &mesh, [0.72, 0.74, 0.78, 1.0], None)
        .map_err(|error| Error::Glb {
            file: format!("{name}.glb"),
            error,
        })?;
    let obj = write_obj(
        &mesh,
        &format!("wavemill sample {name} (generated, deterministic)"),
    );
    let files = vec![
        (format!("{name}.glb"), glb.build()),
        (format!("{name}.obj"), obj),
    ];
    Ok((mesh, files))
}
