//! Channel roughing (issue 20 point 2): the rest that vertical end mills leave under
//! overhangs and between an impeller's blades, taken down with the job's ball, 5-axis, in
//! offset layers of the part.
//!
//! The layers are the offsets the commercial impeller modules call "offset from the hub and
//! blades": layer k holds the ball `a + k·step` mm off the part (a = the operation's stock to
//! leave), the outermost first. A layer is planned like finishing — plane sections, the ball
//! placed by exact f64 distance, an axis chosen inside the machine's reach with the shank and
//! holder clear of the part and of the material still standing, chords refined, linked — with
//! three differences:
//!
//! * **waterlines, from the top down**: the drive planes are horizontal and cut in order of
//!   falling height, so within a layer each pass finds the material above it already taken
//!   wherever the passes above reached. Where a channel is narrower than the layer's ball the
//!   layer does not fit, and the channel's middle waits for a smaller layer; the waterlines
//!   bound how much of it that layer's ball meets at once (the plane spacing, from the scallop
//!   height, rather than the channel's whole depth);
//! * **the ball is held `r + a_k` from the part** ([`crate::path::FinishingContext::allowance`]),
//!   so it leaves `a_k`; each layer after the first cuts at most `step` into what the one before
//!   left, wherever that one reached;
//! * **only where there is material** ([`crate::path::OffsetLayer`]): a drive point is kept
//!   when its ball, shrunk by a quarter step, still meets the planning stock (the exact dexel
//!   test, after a distance-field bound), and within a lead of such a point along the pass.
//!   Most of a layer is air — the end mills roughed it — and is never given an axis.
//!
//! Each layer is taken off the planning stock before the next is planned, so the next layer's
//! shank and holder see what this one left, its air is what this one cut, and its feed control
//! measures the material each move removes. The deepest layer's offset comes from the rest the
//! operations before left (measured over the part's faces); layers beyond `max_layers` are not
//! planned and what they would have cut stays for the finish, which reports it.
//!
//! Every layer is verified on the part (an implementation that shares nothing with the
//! placement: [`crate::verify`]): its ball, at every pose and chord midpoint, is at least
//! `a_k` less the layer's chord tolerance from the part.

use std::collections::BTreeMap;

use serde::Serialize;

use super::config::{OffsetLayers, Operation};
use super::plan_roughing::{BallTakeOff, RoughingContext};
use super::rapids::split_turning_rapids;
use super::setup::PlanSetup;
use crate::error::Result;
use crate::feed::FeedReport;
use crate::geom::{Move, MoveKind, Point3, Toolpath, Vector3};
use crate::mesh::Mesh;
use crate::path::{self, FinishingOptions, OffsetLayer, unreachable_by_reason};
use crate::verify::verify;

/// The loosest chord tolerance of a layer, mm: a layer leaves `a_k` for the next one to take,
/// so its chords need not be as tight as the finish's, only safely inside that.
const LAYER_TOLERANCE_MM: f64 = 0.05;

/// One offset layer of a channel roughing operation, for `report.json`.
#[derive(Clone, Debug, Serialize)]
pub struct ChannelLayerSummary {
    /// The ball is held this far off the part, mm.
    pub allowance_mm: f64,
    pub drive_points: usize,
    /// Drive points left out: nothing to cut within the ball there.
    pub points_in_air: usize,
    pub unreachable: usize,
    pub unreachable_by_reason: BTreeMap<String, usize>,
    pub segments: usize,
    pub cutting_length_mm: f64,
    /// What the layer took off the planning stock, mm³.
    pub removed_mm3: f64,
    /// min over poses and chord midpoints of (ball to the part) − allowance, mm (≥ −the
    /// layer's chord tolerance).
    pub min_stock_left_minus_allowance_mm: f64,
    pub chord_tolerance_mm: f64,
}

/// A channel roughing operation in `report.json`.
#[derive(Clone, Debug, Serialize)]
pub struct ChannelSummary {
    pub operation: String,
    /// The deepest rest over the part before it, mm (area-weighted max over the faces).
    pub rest_before_mm: f64,
    pub step_mm: f64,
    pub scallop_height_mm: f64,
    /// The layers, outermost first.
    pub layers: Vec<ChannelLayerSummary>,
    /// Layers the rest called for beyond `max_layers`, not planned.
    pub layers_left_out: usize,
}

/// A channel roughing operation, planned and taken off the planning stock.
pub struct ChannelPlan {
    pub toolpath: Toolpath,
    pub summary: ChannelSummary,
    /// Feed control per layer (named by its allowance).
    pub feed_control: Vec<(String, FeedReport)>,
    pub rapids_fed: usize,
    pub failure: Option<String>,
}

/// The allowances of the layers, outermost first: from `stock_to_leave` up by `step` until the
/// outermost cuts at most a step into `rest` (the deepest rest now), at most `max_layers`;
/// and how many more the rest would need.
pub fn layer_allowances(
    stock_to_leave: f64,
    rest: f64,
    layers: &OffsetLayers,
) -> (Vec<f64>, usize) {
    // The outermost layer's ball bottoms out at a_K: it cuts rest − a_K, at most one step.
    let needed = ((rest - layers.step - stock_to_leave) / layers.step)
        .ceil()
        .max(0.0) as usize
        + 1;
    let planned = needed.min(layers.max_layers);
    let allowances = (0..planned)
        .rev()
        .map(|k| stock_to_leave + k as f64 * layers.step)
        .collect();
    (allowances, needed - planned)
}

/// Plans `operation` (a `channel-rough`) on `part`, layer by layer, each taken off `context`'s
/// planning stock before the next is planned. `last` is where the operation before left the
/// tool.
#[allow(clippy::too_many_arguments)]
pub fn channel_rough(
    setup: &PlanSetup,
    part: &Mesh,
    operation: &Operation,
    context: &mut RoughingContext,
    take_off: &BallTakeOff,
    last: Option<&Move>,
    split_rapids: bool,
    advance: &(dyn Fn() + Sync),
) -> Result<ChannelPlan> {
    let layers = operation.layers.unwrap_or(OffsetLayers {
        step: setup.prepared_tool.ball_radius,
        max_layers: 1,
    });
    let rest_before = context.deepest_rest(part)?;
    let (allowances, layers_left_out) =
        layer_allowances(operation.stock_to_leave, rest_before, &layers);
    let r = setup.prepared_tool.ball_radius;
    // A ball that would cut less than this into the material is in the air: the skin an
    // end mill's shape leaves over the allowance is not worth a pass of its own.
    let least_cut = 0.25 * layers.step;
    let reachable = |axis: &Vector3| setup.reachable(axis);
    let mut toolpath = Toolpath {
        tool_id: setup.tool.id,
        moves: Vec::new(),
    };
    let mut summaries = Vec::with_capacity(allowances.len());
    let mut feed_control = Vec::new();
    let mut rapids_fed = 0;
    let mut failure = None;
    let mut last = last.copied();
    for &allowance in &allowances {
        let material = context.material();
        let collider = setup.collider.with_material(material.clone());
        let touches =
            |centre: &Point3, radius: f64| !material.ball_is_clear(centre, radius - least_cut);
        let layer = OffsetLayer {
            touches: &touches,
            lead: 2.0 * r,
        };
        let mut ctx = setup.finishing_context(&collider, &setup.rays, &reachable);
        ctx.allowance = allowance;
        ctx.offset_layer = Some(&layer);
        let tolerance = (0.1 * allowance)
            .min(LAYER_TOLERANCE_MM)
            .max(setup.finishing.tolerance);
        // Waterlines from the top down (the planes run along the drive normal).
        let options = FinishingOptions {
            scallop_height: operation.scallop_height,
            tolerance,
            drive_normal: -Vector3::z(),
            ..setup.finishing.clone()
        };
        let passes = path::finishing_passes(part, &ctx, &options, advance);
        let (mut layer_path, _) = path::link(
            &passes.segments,
            &collider,
            &setup.prepared_tool,
            setup.tool.id,
            &setup.link,
        );
        if split_rapids {
            split_turning_rapids(
                &mut layer_path,
                &setup.kinematics,
                super::pipeline::MAX_RAPID_TURN_DEG,
            );
        }
        let on_part = verify(
            &layer_path,
            &setup.collider,
            &setup.prepared_tool,
            setup.search,
        );
        let stock_left = on_part
            .min_cutter_clearance
            .min(on_part.min_chord_clearance)
            - allowance;
        if stock_left < -tolerance {
            failure.get_or_insert(format!(
                "channel roughing's layer at {allowance} mm leaves only {:.4} mm on the part",
                stock_left + allowance
            ));
        }
        let volume_before = context.stock_volume();
        let taken = context.take_off_ball_operation(&mut layer_path, last.as_ref(), take_off);
        rapids_fed += taken.rapids_fed;
        if let Some(report) = taken.feed_control {
            feed_control.push((format!("{} (layer {allowance} mm)", operation.name), report));
        }
        let unreachable_by_reason = unreachable_by_reason(&passes.unreachable);
        summaries.push(ChannelLayerSummary {
            allowance_mm: allowance,
            drive_points: passes.drive_points,
            points_in_air: passes.points_in_air,
            unreachable: passes.unreachable.len(),
            unreachable_by_reason,
            segments: passes.segments.len(),
            cutting_length_mm: cutting_length(&layer_path),
            removed_mm3: volume_before - context.stock_volume(),
            min_stock_left_minus_allowance_mm: stock_left,
            chord_tolerance_mm: tolerance,
        });
        if let Some(m) = layer_path.moves.last() {
            last = Some(*m);
        }
        toolpath.moves.extend(layer_path.moves);
    }
    Ok(ChannelPlan {
        toolpath,
        summary: ChannelSummary {
            operation: operation.name.clone(),
            rest_before_mm: rest_before,
            step_mm: layers.step,
            scallop_height_mm: operation.scallop_height,
            layers: summaries,
            layers_left_out,
        },
        feed_control,
        rapids_fed,
        failure,
    })
}

fn cutting_length(path: &Toolpath) -> f64 {
    path.moves
        .windows(2)
        .filter(|w| w[1].kind == MoveKind::Cut)
        .map(|w| (w[1].pose.tip - w[0].pose.tip).norm())
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layers_reach_the_rest_a_step_at_a_time() {
        let layers = OffsetLayers {
            step: 2.0,
            max_layers: 8,
        };
        // Rest 7 mm over a 0.5 mm allowance: a layer at 4.5 would cut 2.5 mm, more than a
        // step, so the outermost is at 6.5.
        let (a, left) = layer_allowances(0.5, 7.0, &layers);
        assert_eq!(a, vec![6.5, 4.5, 2.5, 0.5]);
        assert_eq!(left, 0);
        // The outermost cuts at most a step: rest − a_K ≤ step.
        assert!(7.0 - a[0] <= 2.0);
        // Exactly on a step: no extra layer.
        let (a, _) = layer_allowances(0.5, 4.5, &layers);
        assert_eq!(a, vec![2.5, 0.5]);
        // No rest beyond the allowance: the one layer at it.
        let (a, _) = layer_allowances(0.5, 0.0, &layers);
        assert_eq!(a, vec![0.5]);
        // Capped: the outermost are left out and counted.
        let (a, left) = layer_allowances(0.5, 40.0, &layers);
        assert_eq!(a.len(), 8);
        assert_eq!(a[0], 14.5);
        assert_eq!(left, 20 - 8);
    }
}
