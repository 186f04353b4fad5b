//! `wavemill levels`: the part as a rough-to-fine hierarchy. Remesh to subdivision
//! connectivity, analyse with lifting wavelets, and describe every level: its own coarse mesh
//! (GLB), its exact deviation from the finest level, its detail norms.

use std::time::Instant;

use serde::Serialize;

use super::samples::NamedFile;
use crate::error::{Error, Result};
use crate::mesh::Mesh;
use crate::mesh::io::GlbBuilder;
use crate::multires::{
    Hierarchy, MultiresWavelets, RemeshOptions, WaveletHierarchy, WaveletOptions,
};

/// `levels.json`.
#[derive(Clone, Debug, Serialize)]
pub struct LevelsReport {
    pub input_triangles: usize,
    pub tolerance_mm: f64,
    /// Whether the lifting has the k-disk least-squares update (seed 004 eqs. 2.22–2.24),
    /// which brings the coarse levels closer to the part.
    pub kdisk_update: bool,
    /// Two-sided Hausdorff distance of the finest level to the input (dense samples), mm.
    pub finest_hausdorff_mm: f64,
    /// max |synthesis(analysis(finest)) − finest|, mm: exact invertibility in practice.
    pub reconstruction_error_mm: f64,
    pub levels: Vec<LevelSummary>,
    /// Lossy compression: details shorter than a threshold dropped, and the exact error that
    /// leaves at the finest level.
    pub compression: Vec<CompressionSummary>,
    /// Milliseconds; the only run-dependent part.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub timings_ms: Option<LevelsTimings>,
}

#[derive(Clone, Debug, Serialize)]
pub struct LevelSummary {
    pub level: usize,
    pub vertices: usize,
    pub triangles: usize,
    /// Of the fitted level (before the wavelet analysis), to the input, mm.
    pub fitted_hausdorff_mm: f64,
    /// Its one-sided parts: farthest input point from the level (missed features) and
    /// farthest level point from the input (folds, chords).
    pub input_to_level_mm: f64,
    pub level_to_input_mm: f64,
    /// Where those two are reached (input point, level point), part coordinates.
    pub worst_input_point: [f64; 3],
    pub worst_level_point: [f64; 3],
    /// Finest-connectivity surface with details of levels ≥ j zeroed, minus the finest level:
    /// max and RMS over vertices, mm (the exact L∞ bound of DESIGN.md §3.4).
    pub max_deviation_mm: f64,
    pub rms_deviation_mm: f64,
    /// Norms of the details that refine this level to the next (absent at the finest).
    pub detail_max_mm: Option<f64>,
    pub detail_rms_mm: Option<f64>,
}

#[derive(Clone, Debug, Serialize)]
pub struct CompressionSummary {
    pub threshold_mm: f64,
    pub details_kept: usize,
    pub details_total: usize,
    /// max over finest vertices of |reconstruction − finest|, mm.
    pub max_error_mm: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct LevelsTimings {
    pub remesh: f64,
    pub analysis: f64,
    pub synthesis: f64,
}

/// A part's remeshed hierarchy and its wavelet analysis: what `levels` describes and what
/// `offsets` builds its shapes from.
pub struct AnalysedHierarchy {
    pub hierarchy: Hierarchy,
    pub wavelets: WaveletHierarchy,
    pub analysed: MultiresWavelets,
    /// Milliseconds spent remeshing and analysing.
    pub remesh_ms: f64,
    pub analysis_ms: f64,
}

pub(crate) fn wavelet_error(e: crate::multires::WaveletError) -> Error {
    Error::Wavelets(e)
}

/// Milliseconds since `t`, to 0.1 ms.
pub(crate) fn elapsed_ms(t: Instant) -> f64 {
    (t.elapsed().as_secs_f64() * 1e4).round() / 10.0
}

/// Remeshes `part` (already prepared: welded, manifold, oriented) to a hierarchy and analyses
/// its finest level with lifting wavelets.
pub fn analyse_hierarchy(
    part: &Mesh,
    options: &RemeshOptions,
    wavelet_options: &WaveletOptions,
) -> Result<AnalysedHierarchy> {
    let t = Instant::now();
    let hierarchy = Hierarchy::build(part, options)?;
    let remesh_ms = elapsed_ms(t);
    let base = &hierarchy.levels[0];
    let n = hierarchy.levels.len() - 1;
    let wavelets = WaveletHierarchy::new_opt(
        &base.mesh.triangles,
        base.mesh.positions.len(),
        &base.creases,
        n,
        wavelet_options,
    )
    .map_err(wavelet_error)?;
    let t = Instant::now();
    let analysed = wavelets
        .analyse_all(&hierarchy.finest().mesh.positions)
        .map_err(wavelet_error)?;
    Ok(AnalysedHierarchy {
        hierarchy,
        wavelets,
        analysed,
        remesh_ms,
        analysis_ms: elapsed_ms(t),
    })
}

/// Builds the hierarchy of `part` (already prepared: welded, manifold, oriented) and returns
/// `level-<j>.glb` files and the report.
pub fn levels(
    part: &Mesh,
    options: &RemeshOptions,
    wavelet_options: &WaveletOptions,
    timings: bool,
) -> Result<(Vec<NamedFile>, LevelsReport)> {
    let AnalysedHierarchy {
        hierarchy,
        wavelets,
        analysed,
        remesh_ms,
        analysis_ms,
    } = analyse_hierarchy(part, options, wavelet_options)?;
    let finest = &hierarchy.finest().mesh;
    let t = Instant::now();
    let rebuilt = wavelets.synthesise_all(&analysed).map_err(wavelet_error)?;
    let synthesis_ms = elapsed_ms(t);
    let reconstruction_error = rebuilt
        .iter()
        .zip(&finest.positions)
        .map(|(a, b)| (a - b).norm())
        .fold(0.0, f64::max);
    let stats = analysed.detail_stats();
    let mut files = Vec::new();
    let mut summaries = Vec::new();
    for (j, fitted) in hierarchy.levels.iter().enumerate() {
        let positions = wavelets
            .level_positions(&analysed, j)
            .map_err(wavelet_error)?;
        let triangles = wavelets.triangles(j).map(<[_]>::to_vec).unwrap_or_default();
        let deviation = wavelets
            .deviation_to_finest(&analysed, j)
            .map_err(wavelet_error)?;
        let count = deviation.per_vertex.len().max(1) as f64;
        let rms = (deviation
            .per_vertex
            .iter()
            .map(|d| d.norm_squared())
            .sum::<f64>()
            / count)
            .sqrt();
        let mesh = Mesh {
            positions,
            triangles,
        };
        let mut glb = GlbBuilder::new();
        glb.add_triangles(&format!("level-{j}"), &mesh, [0.72, 0.74, 0.78, 1.0], None)
            .map_err(|error| Error::Glb {
                file: format!("level-{j}.glb"),
                error,
            })?;
        files.push((format!("level-{j}.glb"), glb.build()));
        summaries.push(LevelSummary {
            level: j,
            vertices: mesh.positions.len(),
            triangles: mesh.triangles.len(),
            fitted_hausdorff_mm: fitted.hausdorff,
            input_to_level_mm: fitted.fit.input_to_level,
            level_to_input_mm: fitted.fit.level_to_input,
            worst_input_point: fitted.fit.worst_input_sample.coords.into(),
            worst_level_point: fitted.fit.worst_level_sample.coords.into(),
            max_deviation_mm: deviation.linf,
            rms_deviation_mm: rms,
            detail_max_mm: stats.get(j).map(|s| s.max_norm),
            detail_rms_mm: stats.get(j).map(|s| s.rms_norm),
        });
    }
    let total: usize = analysed.details.iter().map(Vec::len).sum();
    let mut compression = Vec::new();
    for threshold in [0.001, 0.01, 0.1] {
        let (kept_wavelets, kept) = analysed.thresholded(threshold);
        let rebuilt = wavelets
            .synthesise_all(&kept_wavelets)
            .map_err(wavelet_error)?;
        let max_error = rebuilt
            .iter()
            .zip(&finest.positions)
            .map(|(a, b)| (a - b).norm())
            .fold(0.0, f64::max);
        compression.push(CompressionSummary {
            threshold_mm: threshold,
            details_kept: kept,
            details_total: total,
            max_error_mm: max_error,
        });
    }
    let report = LevelsReport {
        input_triangles: part.triangles.len(),
        tolerance_mm: options.tolerance,
        kdisk_update: wavelet_options.kdisk_update,
        finest_hausdorff_mm: hierarchy.finest().hausdorff,
        reconstruction_error_mm: reconstruction_error,
        levels: summaries,
        compression,
        timings_ms: timings.then_some(LevelsTimings {
            remesh: remesh_ms,
            analysis: analysis_ms,
            synthesis: synthesis_ms,
        }),
    };
    Ok((files, report))
}
