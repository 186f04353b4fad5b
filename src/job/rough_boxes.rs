//! `wavemill rough-boxes`: seed 002's roughing of a part read from IGES — the stock sliced at
//! the tops of the convex-hull boxes of its surfaces' Bézier patches, thick layers split by
//! de Casteljau, thin ones merged, each layer's pocket bounded by the union of the boxes
//! above it ([`crate::cad::boxes`], [`crate::rough::boxes`]) — with one flat or bull-nose
//! end mill, posted, read back and checked like `rough`: against every box (the seed's
//! guarantee), against the part's mesh, and on a tri-dexel model of the blank.
//!
//! Beside it, on request, the conventional route the seed compares with: equal layers at the
//! maximum depth, each pocket bounded by the part's own section, the same tool, planned and
//! checked the same way; the two are set side by side in `rough.json`.

use std::sync::Arc;
use std::time::Instant;

use super::blank::BlankSpec;
use super::cad_part::PartSurfaces;
use super::rough::{LayerBound, RoughOptions, RoughOutput, RoughReport, SlicingRow, rough};
use crate::error::{Error, Result};
use crate::mesh::io::RawMesh;
use crate::tool::{Cutter, Section, ToolAssembly, ToolLibrary};

/// What `rough-boxes` is asked to do.
#[derive(Clone, Debug, PartialEq)]
pub struct RoughBoxesOptions {
    /// Blank, feeds, depths of cut, allowance, frame: as for `rough` (its tool choice and
    /// bound are set here).
    pub rough: RoughOptions,
    /// The end mill (flat or bull-nose); it is put in a shrink-fit holder
    /// ([`rougher_assembly`]).
    pub cutter: Cutter,
    /// Length out of the holder, mm; `None`: enough to reach the part's floor with the holder
    /// above the blank ([`rougher_assembly`]).
    pub stickout: Option<f64>,
    /// Boxes wider than this are split before the layers, mm; `f64::INFINITY`: the seed's
    /// model, split only where a layer is too thick.
    pub max_box_width: f64,
    /// How the planes at the box tops become layers.
    pub merge: crate::rough::boxes::LayerMerge,
    /// Also plan equal layers down to the part's own sections with the same tool, and compare.
    pub compare_uniform: bool,
}

impl SlicingRow {
    fn of(route: &'static str, report: &RoughReport, part_volume: f64) -> SlicingRow {
        let tools = &report.tools;
        let last = tools.last();
        SlicingRow {
            route,
            layers: tools.iter().map(|t| t.layers.len()).sum(),
            layers_at_tops: tools
                .iter()
                .flat_map(|t| &t.layers)
                .filter(|l| l.layer.at_flat)
                .count(),
            moves: tools.iter().map(|t| t.moves).sum(),
            cutting_length_mm: tools.iter().map(|t| t.cutting_length_mm).sum(),
            path_length_mm: tools.iter().map(|t| t.path_length_mm).sum(),
            estimated_time_s: report.estimated_time_s,
            material_left_mm3: report.volume_after_mm3 - part_volume,
            rest_mean_mm: last.map_or(0.0, |t| t.stock.rest.mean_mm),
            rest_max_mm: last.map_or(0.0, |t| t.stock.rest.max_mm),
            min_clearance_to_part_mm: tools
                .iter()
                .map(|t| t.overcut_vs_part.min_clearance_mm)
                .fold(f64::INFINITY, f64::min),
        }
    }
}

/// The tool a `rough-boxes` run cuts with: `cutter` as T1 with a shank of its diameter, in a
/// shrink-fit holder (a nose cone from D + 12 to D + 20 mm over 40 mm, then a Ø50 mm body
/// 40 mm long, or D + 30 for a cutter wider than 20 mm), sticking out `stickout` mm: by
/// default the longer of `depth` (from the blank's top to the part's floor) and the flutes,
/// plus the holder's 2 mm margin and 5 mm, rounded up to 5 mm.
pub fn rougher_assembly(cutter: Cutter, stickout: Option<f64>, depth: f64) -> ToolAssembly {
    let d = cutter.diameter();
    let stickout = stickout.unwrap_or_else(|| {
        let needed = depth.max(cutter.flute_length()) + 2.0 + 5.0;
        (needed / 5.0).ceil() * 5.0
    });
    ToolAssembly {
        id: 1,
        name: format!("{} D{d} for convex-hull-box roughing", cutter.kind()),
        cutter,
        neck: None,
        shank_diameter: d,
        stickout,
        holder: vec![
            Section {
                diameter: d + 12.0,
                top_diameter: Some(d + 20.0),
                length: 40.0,
            },
            Section::cylinder((d + 30.0).max(50.0), 40.0),
        ],
    }
}

/// Plans, posts, reads back and checks seed 002's roughing of the part `raw` (the
/// tessellation of `surfaces`, both in the file's frame, in mm), and with `compare_uniform`
/// the uniform route beside it (its figures in the report's `comparison`).
pub fn rough_boxes(
    raw: &RawMesh,
    surfaces: Arc<PartSurfaces>,
    part_name: &str,
    units: &str,
    options: &RoughBoxesOptions,
) -> Result<RoughOutput> {
    if !matches!(
        options.cutter,
        Cutter::Flat { .. } | Cutter::BullNose { .. }
    ) {
        return Err(Error::Usage(format!(
            "the tool is a {} cutter: convex-hull-box roughing cuts with a flat or bull-nose \
             end mill (flat:D or bull:D:R)",
            options.cutter.kind()
        )));
    }
    // The depth the tool must reach, in the frame the part is machined in.
    let upright = match options.rough.up {
        Some(up) => {
            let axis = super::config::unit_direction(up)
                .ok_or_else(|| Error::Usage(format!("up must be a non-zero vector, got {up:?}")))?;
            super::setup::turned_upright(&raw.mesh, &axis)
        }
        None => raw.mesh.clone(),
    };
    let bounds = upright.aabb();
    let blank_top = match options
        .rough
        .blank
        .as_ref()
        .map(|spec| spec.resolved(&upright))
    {
        Some(BlankSpec::Box(b)) => b[5],
        Some(BlankSpec::Cylinder { z1, .. }) => z1,
        Some(BlankSpec::Offset(margin)) => bounds.max.z + margin,
        // A mesh blank's top is not known before it is read: the planner says what the tool
        // does not reach.
        _ => bounds.max.z + 1.0,
    };
    let assembly = rougher_assembly(
        options.cutter,
        options.stickout,
        blank_top.max(bounds.max.z) - bounds.min.z,
    );
    assembly
        .validate()
        .map_err(|e| Error::Usage(format!("the roughing tool: {e}")))?;
    let library = ToolLibrary {
        tools: vec![assembly],
    };
    let boxes_options = RoughOptions {
        tool_id: Some(1),
        rest_tools: 0,
        bound: LayerBound::HullBoxes {
            surfaces,
            max_box_width: options.max_box_width,
            merge: options.merge,
        },
        ..options.rough.clone()
    };
    let mut output = rough(raw, part_name, units, &library, &boxes_options)?;
    if options.compare_uniform {
        let t = Instant::now();
        let uniform_options = RoughOptions {
            uniform_layers: true,
            bound: if options.rough.allowance > 0.0 {
                LayerBound::OffsetShape
            } else {
                LayerBound::Part
            },
            ..boxes_options.clone()
        };
        let uniform = rough(raw, part_name, units, &library, &uniform_options)?;
        let part_volume = crate::mesh::prepare(&upright, &Default::default())
            .map_err(|e| Error::Mesh {
                file: part_name.to_string(),
                reason: e.to_string(),
            })?
            .1
            .volume
            .unwrap_or(0.0);
        let rows = vec![
            SlicingRow::of("hull-boxes", &output.report, part_volume),
            SlicingRow::of("uniform", &uniform.report, part_volume),
        ];
        if let Some(problem) = uniform.failure {
            output.failure = Some(match output.failure {
                Some(first) => format!("{first}; the uniform route: {problem}"),
                None => format!("the uniform route: {problem}"),
            });
        }
        output.report.comparison = Some(rows);
        if let Some(timings) = &mut output.report.timings_ms {
            timings.insert(
                "uniform_route",
                (t.elapsed().as_secs_f64() * 1e4).round() / 10.0,
            );
        }
    }
    Ok(output)
}
