//! `wavemill offsets`: the rough-to-fine intermediate shapes of a part (issue 4). Remesh and
//! analyse the part as `levels` does, take level j's truncated surface (details of levels ≥ j
//! zeroed, at the finest connectivity) with its exact deviation bound, and build the nested,
//! verified offsets of [`crate::offset`]: `offset-<j>.glb` (vertex colour = excess) and the
//! figures of every shape.

use std::time::Instant;

use serde::Serialize;

use super::levels::{AnalysedHierarchy, analyse_hierarchy, elapsed_ms, wavelet_error};
use super::samples::NamedFile;
use crate::error::{Error, JobError, Result};
use crate::mesh::Mesh;
use crate::mesh::io::GlbBuilder;
use crate::multires::{RemeshOptions, WaveletOptions};
use crate::offset::{
    OffsetOptions, OffsetShape, ShapeReport, ShapeSpec, local_fit, nested_offsets_opt,
};

/// `offsets.json`.
#[derive(Clone, Debug, Serialize)]
pub struct OffsetsReport {
    pub input_triangles: usize,
    pub tool_radius_mm: f64,
    /// Levels of the hierarchy (0..=finest) and the finest level's measured two-sided
    /// Hausdorff distance to the part, which every bound includes.
    pub hierarchy_levels: usize,
    pub finest_hausdorff_mm: f64,
    pub shapes: Vec<ShapeSummary>,
    /// Every shape passed every check.
    pub verified: bool,
    /// Milliseconds; the only run-dependent part.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub timings_ms: Option<OffsetsTimings>,
}

#[derive(Clone, Debug, Serialize)]
pub struct ShapeSummary {
    /// Index of the shape (order of the allowances) and the hierarchy level it offsets.
    pub shape: usize,
    pub level: usize,
    pub file: String,
    #[serde(flatten)]
    pub figures: ShapeReport,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub timings_ms: Option<ShapeTimings>,
}

#[derive(Clone, Debug, Serialize)]
pub struct ShapeTimings {
    pub build: f64,
    pub verify: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct OffsetsTimings {
    pub remesh: f64,
    pub analysis: f64,
    pub offsets: f64,
}

/// Most hierarchy levels above the base that stock-to-leave shapes may ask for: each level
/// multiplies the triangles by 4 (6 levels: 4096 times the base).
pub const MAX_SHAPE_LEVELS: u32 = 6;

/// Checks stock-to-leave `allowances` (mm, ≥ 0, each below the one before) and returns how many
/// hierarchy levels above the base their shapes use: `max_levels` when given, else one per
/// allowance after the first; at most [`MAX_SHAPE_LEVELS`].
pub fn levels_for_allowances(allowances: &[f64], max_levels: Option<u32>) -> Result<u32> {
    if let Some((i, a)) = allowances
        .iter()
        .enumerate()
        .find(|&(i, &a)| !(a.is_finite() && a >= 0.0) || (i > 0 && a >= allowances[i - 1]))
    {
        return Err(Error::Usage(format!(
            "allowance {} ({a}) must be a number of mm >= 0, smaller than the one before",
            i + 1
        )));
    }
    let levels = max_levels.unwrap_or(allowances.len().saturating_sub(1) as u32);
    if levels > MAX_SHAPE_LEVELS {
        return Err(Error::Usage(format!(
            "{} allowances need {levels} levels above the base, at most {MAX_SHAPE_LEVELS} \
             (each level multiplies the triangles by 4)",
            allowances.len()
        )));
    }
    Ok(levels)
}

/// The level surfaces and bounds for `allowances`: shape i offsets level min(i, finest), with
/// bound = exact L∞ deviation of that level's truncated surface from the finest level + the
/// finest level's fit to the part (the larger of its Hausdorff distance and its largest local
/// fit), and per vertex as local bounds |deviation at v| + the finest level's local fit at v.
pub fn level_specs(
    part: &Mesh,
    analysed: &AnalysedHierarchy,
    allowances: &[f64],
) -> Result<Vec<(usize, ShapeSpec)>> {
    let finest_level = analysed.hierarchy.levels.len() - 1;
    let triangles = analysed.wavelets.finest_triangles().to_vec();
    let finest = Mesh {
        positions: analysed.hierarchy.finest().mesh.positions.clone(),
        triangles: triangles.clone(),
    };
    // Half the finest level's mean edge: the fit varies from one level triangle to the next.
    let spacing = 0.5 * (2.0 * finest.surface_area() / finest.triangles.len().max(1) as f64).sqrt();
    let fit = local_fit(part, &finest, spacing);
    let finest_fit = fit
        .iter()
        .copied()
        .fold(analysed.hierarchy.finest().hausdorff, f64::max);
    allowances
        .iter()
        .enumerate()
        .map(|(i, &allowance)| {
            let level = i.min(finest_level);
            let positions = analysed
                .wavelets
                .synthesise_truncated(&analysed.analysed, level)
                .map_err(wavelet_error)?;
            let deviation = analysed
                .wavelets
                .deviation_to_finest(&analysed.analysed, level)
                .map_err(wavelet_error)?;
            // The deviation is linear over each finest triangle, so a part point near a point
            // of triangle t is within max |deviation| of t's corners + the finest fit there.
            let vertex_bounds = deviation
                .per_vertex
                .iter()
                .zip(&fit)
                .map(|(d, f)| d.norm() + f)
                .collect();
            Ok((
                level,
                ShapeSpec {
                    surface: Mesh {
                        positions,
                        triangles: triangles.clone(),
                    },
                    allowance,
                    bound: deviation.linf + finest_fit,
                    vertex_bounds: Some(vertex_bounds),
                },
            ))
        })
        .collect()
}

/// The k-disk least-squares update brings the coarse levels 2-4x closer to the part, so the
/// shapes built on them are that much tighter.
fn tight_levels() -> WaveletOptions {
    WaveletOptions::default().with_kdisk_update(true)
}

/// The shapes' specifications for `allowances` on the hierarchy of `part` (remeshed and
/// analysed as `offsets` does), for callers that build the shapes themselves (benches,
/// other planners): one per allowance, coarsest first.
pub fn offset_specs(
    part: &Mesh,
    remesh: &RemeshOptions,
    allowances: &[f64],
) -> Result<Vec<ShapeSpec>> {
    let analysed = analyse_hierarchy(part, remesh, &tight_levels())?;
    Ok(level_specs(part, &analysed, allowances)?
        .into_iter()
        .map(|(_, spec)| spec)
        .collect())
}

/// The verified stock-to-leave shapes of `part` for `allowances` (coarsest first), each with
/// the hierarchy level it offsets: what `plan` semi-finishes to.
pub fn stock_shapes(
    part: &Mesh,
    remesh: &RemeshOptions,
    allowances: &[f64],
) -> Result<Vec<(usize, OffsetShape)>> {
    let analysed = analyse_hierarchy(part, remesh, &tight_levels())?;
    let specs = level_specs(part, &analysed, allowances)?;
    let plain: Vec<ShapeSpec> = specs.iter().map(|(_, s)| s.clone()).collect();
    let shapes = nested_offsets_opt(part, &plain, &OffsetOptions::default()).map_err(|error| {
        Error::Offset {
            what: "stock-to-leave shapes".into(),
            error,
        }
    })?;
    Ok(specs
        .into_iter()
        .map(|(level, _)| level)
        .zip(shapes)
        .collect())
}

/// Blue (no excess) through green to red (excess = `scale` or more), linear RGBA.
fn excess_colour(excess: f64, scale: f64) -> [f32; 4] {
    let s = if scale > 0.0 {
        (excess / scale).clamp(0.0, 1.0)
    } else {
        0.0
    } as f32;
    if s < 0.5 {
        [0.0, 2.0 * s, 1.0 - 2.0 * s, 1.0]
    } else {
        [2.0 * s - 1.0, 2.0 - 2.0 * s, 0.0, 1.0]
    }
}

/// The GLB of a shape: its mesh coloured by excess, red at twice its bound (the issue's
/// target for the maximum) or at its maximum excess when the bound is zero.
pub fn shape_glb(name: &str, shape: &OffsetShape) -> Result<Vec<u8>> {
    let scale = if shape.report.bound_mm > 0.0 {
        2.0 * shape.report.bound_mm
    } else {
        shape.report.max_excess_mm
    };
    let colours: Vec<[f32; 4]> = shape
        .vertex_excess
        .iter()
        .map(|&e| excess_colour(e, scale))
        .collect();
    let mut glb = GlbBuilder::new();
    glb.add_triangles(name, &shape.mesh, [0.8, 0.8, 0.8, 1.0], Some(&colours))
        .map_err(|error| Error::Glb {
            file: name.to_string(),
            error,
        })?;
    Ok(glb.build())
}

/// What `offsets` makes: the shapes, their files and the report.
#[derive(Clone, Debug)]
pub struct OffsetsOutput {
    pub shapes: Vec<OffsetShape>,
    /// `offset-<j>.glb`.
    pub files: Vec<NamedFile>,
    pub report: OffsetsReport,
}

/// Builds the shapes of `part` (prepared: welded, manifold, oriented) for `allowances`
/// (strictly decreasing, mm) with their `offset-<j>.glb` files and the report. A shape that
/// failed its verification is in the report with `verified: false`; the caller decides.
pub fn offsets(
    part: &Mesh,
    remesh: &RemeshOptions,
    allowances: &[f64],
    options: &OffsetOptions,
    timings: bool,
) -> Result<OffsetsOutput> {
    if allowances.is_empty() {
        return Err(Error::JobFile(JobError::Invalid {
            key: "allowances".into(),
            reason: "is empty: give at least one allowance".into(),
        }));
    }
    let analysed = analyse_hierarchy(part, remesh, &tight_levels())?;
    let specs = level_specs(part, &analysed, allowances)?;
    let t = Instant::now();
    let plain: Vec<ShapeSpec> = specs.iter().map(|(_, s)| s.clone()).collect();
    let shapes = nested_offsets_opt(part, &plain, options).map_err(|error| Error::Offset {
        what: "offsets".into(),
        error,
    })?;
    let offsets_ms = elapsed_ms(t);
    let mut files = Vec::new();
    let mut summaries = Vec::new();
    for (i, ((level, _), shape)) in specs.iter().zip(&shapes).enumerate() {
        let file = format!("offset-{i}.glb");
        files.push((file.clone(), shape_glb(&format!("offset-{i}"), shape)?));
        summaries.push(ShapeSummary {
            shape: i,
            level: *level,
            file,
            figures: shape.report.clone(),
            timings_ms: timings.then_some(ShapeTimings {
                build: (shape.report.build_s * 1e4).round() / 10.0,
                verify: (shape.report.verify_s * 1e4).round() / 10.0,
            }),
        });
    }
    let report = OffsetsReport {
        input_triangles: part.triangles.len(),
        tool_radius_mm: options.tool_radius,
        hierarchy_levels: analysed.hierarchy.levels.len(),
        finest_hausdorff_mm: analysed.hierarchy.finest().hausdorff,
        verified: shapes.iter().all(|s| s.report.verified),
        shapes: summaries,
        timings_ms: timings.then_some(OffsetsTimings {
            remesh: analysed.remesh_ms,
            analysis: analysed.analysis_ms,
            offsets: offsets_ms,
        }),
    };
    Ok(OffsetsOutput {
        shapes,
        files,
        report,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn allowances_give_their_levels_or_say_what_is_wrong() {
        assert_eq!(levels_for_allowances(&[1.0, 0.5, 0.0], None).unwrap(), 2);
        assert_eq!(levels_for_allowances(&[0.3], Some(4)).unwrap(), 4);
        for (allowances, max, says) in [
            (&[0.5, 1.0][..], None, "allowance 2 (1)"),
            (&[f64::NAN][..], None, "allowance 1 (NaN)"),
            (&[-0.1][..], None, "allowance 1 (-0.1)"),
            (
                &[1.0][..],
                Some(7),
                "need 7 levels above the base, at most 6",
            ),
        ] {
            let e = levels_for_allowances(allowances, max)
                .unwrap_err()
                .to_string();
            assert!(e.contains(says), "{allowances:?}: {e}");
        }
    }
}
