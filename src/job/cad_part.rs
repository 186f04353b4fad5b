//! IGES parts into the pipeline: read, tessellate within a chord tolerance, and hand on the
//! welded mesh every stage takes; plus the `tessellate` command's outputs.

use std::path::Path;

use crate::cad::iges::{IgesModel, read_iges};
use crate::cad::tessellate::{
    Deviation, TessellateOptions, Tessellation, TessellationReport, tessellate,
};
use crate::error::{Error, Result};
use crate::mesh::io::RawMesh;

/// Whether a path names an IGES file (`.igs`, `.iges`, any case).
pub fn is_iges(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("igs") || e.eq_ignore_ascii_case("iges"))
}

/// Reads an IGES file's faces (in mm, from the file's own unit).
pub fn read_iges_file(path: &Path) -> Result<IgesModel> {
    let file = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|source| Error::Io {
        path: file.clone(),
        source,
    })?;
    // IGES is ASCII; other bytes (an editor's Latin-1 comment) are kept as replacement
    // characters, which only Hollerith strings can hold.
    let text = String::from_utf8_lossy(&bytes);
    read_iges(&text).map_err(|error| Error::Iges { file, error })
}

/// An IGES part tessellated: the model, its mesh and what the tessellation found.
#[derive(Clone, Debug)]
pub struct TessellatedPart {
    /// The faces as read.
    pub model: IgesModel,
    /// Their mesh.
    pub tessellation: Tessellation,
}

/// Reads and tessellates an IGES part.
pub fn tessellate_iges(path: &Path, options: &TessellateOptions) -> Result<TessellatedPart> {
    if !(options.tolerance.is_finite() && options.tolerance > 0.0) {
        return Err(Error::Usage(format!(
            "tessellation tolerance {} mm: must be a positive length",
            options.tolerance
        )));
    }
    let model = read_iges_file(path)?;
    if model.faces.is_empty() {
        return Err(Error::Mesh {
            file: path.display().to_string(),
            reason: format!(
                "no surfaces to tessellate (entities seen but not read: {})",
                skipped_list(&model)
            ),
        });
    }
    let tessellation = tessellate(&model.faces, options).map_err(|error| Error::Tessellate {
        file: path.display().to_string(),
        error,
    })?;
    Ok(TessellatedPart {
        model,
        tessellation,
    })
}

/// `type ×count` for every entity type the reader listed and skipped.
fn skipped_list(model: &IgesModel) -> String {
    if model.skipped.is_empty() {
        return "none".into();
    }
    model
        .skipped
        .iter()
        .map(|(t, n)| format!("{t} ({}) ×{n}", crate::cad::iges::entity_name(*t)))
        .collect::<Vec<_>>()
        .join(", ")
}

/// What a tessellation should tell its user without being asked: entities skipped, seams
/// left open, gaps sewn wider than the tolerance.
pub fn tessellation_warnings(part: &TessellatedPart, options: &TessellateOptions) -> Vec<String> {
    let mut warnings = Vec::new();
    if !part.model.skipped.is_empty() {
        warnings.push(format!(
            "IGES entities skipped (not faces): {}",
            skipped_list(&part.model)
        ));
    }
    let r = &part.tessellation.report;
    if r.open_seam_edges > 0 {
        let at = r.open_seams.first().map_or(String::new(), |s| {
            format!(
                ", the longest {:.3} mm near ({:.3}, {:.3}, {:.3})",
                s.length, s.at[0], s.at[1], s.at[2]
            )
        });
        warnings.push(format!(
            "the faces leave {} open seam(s), {:.3} mm in all{at}: faces missing or apart by more than {:.3} mm",
            r.open_seams.len(),
            r.open_seam_length,
            2.0 * options.tolerance
        ));
    }
    if r.widest_sewn_gap > options.tolerance {
        warnings.push(format!(
            "faces {:.4} mm apart were sewn together; the mesh lies between them",
            r.widest_sewn_gap
        ));
    }
    warnings
}

/// The faces of a part read from IGES beside the mesh the pipeline is given (their tessellation,
/// its triangles in the same order).
#[derive(Clone, Debug, PartialEq)]
pub struct PartSurfaces {
    pub faces: Vec<crate::cad::iges::Face>,
    /// The face of each triangle of the part's mesh.
    pub face_of_triangle: Vec<u32>,
    /// The tessellation's chord tolerance, mm.
    pub tolerance: f64,
}

/// Reads and tessellates an IGES part into the raw mesh the pipeline takes, with warnings.
pub fn load_iges_part(path: &Path, options: &TessellateOptions) -> Result<RawMesh> {
    let part = tessellate_iges(path, options)?;
    let warnings = tessellation_warnings(&part, options);
    Ok(RawMesh {
        mesh: part.tessellation.mesh,
        warnings,
    })
}

/// The `tessellate` command's report.
#[derive(Clone, Debug, serde::Serialize)]
pub struct TessellateSummary {
    /// Faces read.
    pub faces: usize,
    /// Millimetres per unit of the file.
    pub millimetres_per_unit: f64,
    /// The chord tolerance asked for, mm.
    pub tolerance_mm: f64,
    /// The tessellation's own report.
    #[serde(flatten)]
    pub tessellation: TessellationReport,
    /// The measured deviation between mesh and surfaces.
    pub deviation: Deviation,
}

/// Measures a tessellated part's deviation (samples per triangle side: `order`).
pub fn tessellate_summary(
    part: &TessellatedPart,
    options: &TessellateOptions,
    order: usize,
) -> TessellateSummary {
    TessellateSummary {
        faces: part.model.faces.len(),
        millimetres_per_unit: part.model.millimetres_per_unit,
        tolerance_mm: options.tolerance,
        tessellation: part.tessellation.report.clone(),
        deviation: part.tessellation.deviation(&part.model.faces, order),
    }
}
