//! Semi-finishing to stock-to-leave shapes (issue 4 point 5; DESIGN.md §3.4, seed 004 ch. 5
//! step 3): before the finishing passes, the ball is driven over each intermediate shape Sⱼ
//! of the part's hierarchy, coarsest first, with the same plane sections, axis choice,
//! smoothing, linking and verification as finishing, but with Sⱼ in place of the part.
//!
//! Why this leaves aⱼ: the ball centre is kept at r or more from Sⱼ (the finishing placement
//! against Sⱼ's exact f64 distance), and every point of Sⱼ is verified to be aⱼ or more from
//! the part, so the ball stays aⱼ or more off the part. Nothing here trusts that argument: each
//! operation is re-verified against its shape and, independently, its ball centres are
//! measured against the part itself.
//!
//! The shank, holder and table are checked against Sⱼ, which holds the part, and — after
//! roughing from a blank — against the material the operations before actually left (the
//! planning stock model, [`crate::collide::PartCollider::with_material`]): the rest under an
//! overhang or in a corner no end mill reached is not inside any offset shape.

use std::sync::Arc;

use serde::Serialize;

use super::setup::PlanSetup;
use crate::access::RayScene;
use crate::collide::PartCollider;
use crate::error::{Error, Result};
use crate::geom::{MoveKind, Toolpath};
use crate::offset::OffsetShape;
use crate::path::{self, FinishingOptions};
use crate::stock::clearance::MaterialClearance;
use crate::verify::{PoseChecks, verify};

/// One semi-finishing operation in `report.json`: the shape it machined to and what the checks
/// measured (mm).
#[derive(Clone, Debug, Serialize)]
pub struct SemiFinishSummary {
    /// Stock to leave, aⱼ.
    pub allowance_mm: f64,
    /// The hierarchy level the shape offsets, and its deviation bound eⱼ.
    pub level: usize,
    pub bound_mm: f64,
    pub shape_triangles: usize,
    /// The shape's own verification (issue 4 point 2) and tightness.
    pub shape_verified: bool,
    pub shape_min_clearance_minus_allowance_mm: f64,
    pub shape_mean_excess_mm: f64,
    pub shape_max_excess_mm: f64,
    pub scallop_height_mm: f64,
    pub drive_planes: usize,
    pub drive_points: usize,
    pub unreachable: usize,
    pub unreachable_by_reason: std::collections::BTreeMap<String, usize>,
    pub segments: usize,
    pub cutting_length_mm: f64,
    /// min over poses and chord midpoints of (ball centre to the shape − r): ≥ −tolerance.
    pub min_clearance_to_shape_mm: f64,
    /// min over poses and chord midpoints of (ball centre to the part − r) − aⱼ, measured on
    /// the part itself: ≥ −tolerance means the stock left is at least the allowance.
    pub min_stock_left_minus_allowance_mm: f64,
}

/// One semi-finishing operation, planned: its moves, what its checks measured, and what they
/// found wrong, if anything (the plan then must not be run).
pub struct SemiFinishPlan {
    pub toolpath: Toolpath,
    pub summary: SemiFinishSummary,
    pub failure: Option<String>,
}

/// Plans one semi-finishing operation at `scallop_height` over `shape` — level `level` of the
/// part's hierarchy, offset to hold the part at the shape's allowance — with `setup`'s tool,
/// axes, linking and margins, and checks it on the shape and, independently, on the part.
pub fn semi_finish_operation(
    setup: &PlanSetup,
    level: usize,
    shape: &OffsetShape,
    scallop_height: f64,
    material: Option<Arc<MaterialClearance>>,
    advance: &(dyn Fn() + Sync),
) -> Result<SemiFinishPlan> {
    let tolerance = setup.finishing.tolerance;
    let figures = &shape.report;
    let mut failure = None;
    if !figures.verified {
        failure.get_or_insert(format!(
            "the stock-to-leave shape for {} mm did not verify",
            figures.allowance_mm
        ));
    }
    let collider = PartCollider::new(&shape.mesh)
        .map_err(|error| Error::Collider {
            what: format!("stock-to-leave shape {} mm", figures.allowance_mm),
            error,
        })?
        .with_table(setup.table);
    let collider = match material {
        Some(material) => collider.with_material(material),
        None => collider,
    };
    let rays = RayScene::new(&shape.mesh);
    let reachable = |axis: &crate::geom::Vector3| setup.reachable(axis);
    let finishing_ctx = setup.finishing_context(&collider, &rays, &reachable);
    let options = FinishingOptions {
        scallop_height,
        ..setup.finishing.clone()
    };
    let tool = &setup.prepared_tool;
    let passes = path::finishing_passes(&shape.mesh, &finishing_ctx, &options, advance);
    let (toolpath, linking) = path::link(
        &passes.segments,
        &collider,
        tool,
        setup.tool.id,
        &setup.link,
    );
    let on_shape = verify(
        &toolpath,
        &collider,
        tool,
        setup.search,
        PoseChecks::Everything,
    );
    if let Err(e) = on_shape.passes(
        tolerance,
        setup.margins.shank,
        setup.margins.holder,
        setup.table.margin,
    ) {
        failure.get_or_insert(format!(
            "semi-finishing to {} mm: {e}",
            figures.allowance_mm
        ));
    }
    // What it leaves on the part: its bodies were checked against the shape, which encloses
    // the part.
    let on_part = verify(
        &toolpath,
        &setup.collider,
        tool,
        setup.search,
        PoseChecks::BallOnly,
    );
    let stock_left = on_part
        .min_cutter_clearance
        .min(on_part.min_chord_clearance)
        - figures.allowance_mm;
    if stock_left < -tolerance {
        failure.get_or_insert(format!(
            "semi-finishing to {} mm leaves only {:.4} mm on the part",
            figures.allowance_mm,
            stock_left + figures.allowance_mm
        ));
    }
    let cutting_length_mm = toolpath
        .moves
        .windows(2)
        .filter(|w| w[1].kind == MoveKind::Cut)
        .map(|w| (w[1].pose.tip - w[0].pose.tip).norm())
        .sum();
    let summary = SemiFinishSummary {
        allowance_mm: figures.allowance_mm,
        level,
        bound_mm: figures.bound_mm,
        shape_triangles: figures.triangles,
        shape_verified: figures.verified,
        shape_min_clearance_minus_allowance_mm: figures.min_clearance_minus_allowance_mm,
        shape_mean_excess_mm: figures.mean_excess_mm,
        shape_max_excess_mm: figures.max_excess_mm,
        scallop_height_mm: scallop_height,
        drive_planes: passes.planes,
        drive_points: passes.drive_points,
        unreachable: passes.unreachable.len(),
        unreachable_by_reason: path::unreachable_by_reason(&passes.unreachable),
        segments: linking.segments,
        cutting_length_mm,
        min_clearance_to_shape_mm: on_shape
            .min_cutter_clearance
            .min(on_shape.min_chord_clearance),
        min_stock_left_minus_allowance_mm: stock_left,
    };
    Ok(SemiFinishPlan {
        toolpath,
        summary,
        failure,
    })
}
