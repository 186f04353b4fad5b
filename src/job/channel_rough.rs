//! Channel roughing (issue 20 point 2): the rest that vertical end mills leave under
//! overhangs and between an impeller's blades, taken down with the job's ball, 5-axis, in
//! layers, each planned like finishing — plane sections, the ball placed by exact f64
//! distance, an axis chosen inside the machine's reach with the shank and holder clear of the
//! part and of the material still standing, chords refined, linked — but only where there is
//! material, and taken off the planning stock before the next layer is planned.
//!
//! Two layerings, as the commercial impeller modules offer them:
//!
//! * **shroud to hub** ([`Layering::ShroudToHub`], the default): surfaces interpolated from
//!   the shroud (the top of the material standing) down to the hub, `z = hub + t·(top − hub)`
//!   over every vertical dexel line of the part, the hub being the top of the part's lowest
//!   solid on the line ([`HubField`]); t falls evenly from the top to 0, with as many layers as
//!   keep each within a step of the one above over the part. The ball's bottom follows the
//!   layer (it starts tangent to it, [`crate::path::FinishingContext::lift`] = 0) and is pushed
//!   off the part to r + a where the part is nearer (a = the operation's stock to leave). So
//!   every layer meets at most a step of material from above, whatever the channel's width, and
//!   the last one follows the hub at the allowance. Across a cliff of the hub (a blade's side)
//!   the layer has a hole rather than a wall;
//! * **offsets** ([`Layering::Offset`]) — "offset from the hub and blades": layer k holds the
//!   ball `a + k·step` mm off the part ([`crate::path::FinishingContext::allowance`]), the
//!   outermost first, each cut as waterlines from the top down. Where a channel is narrower
//!   than a layer's ball the layer does not fit, and the channel's middle waits for a smaller
//!   layer.
//!
//! **Only where there is material** ([`crate::path::MaterialFilter`]): a drive point is kept when
//! its ball, shrunk by a quarter step, still meets the planning stock (the exact dexel test,
//! after a distance-field bound), and within a lead of such a point along the pass. Most of a
//! layer is air — the end mills roughed it — and is never given an axis.
//!
//! Each layer is taken off the planning stock before the next is planned, so the next layer's
//! shank and holder see what this one left, its air is what this one cut, and its feed control
//! measures the material each move removes. Layers beyond `max_layers` are not planned (the
//! offsets' outermost, the interpolation's uppermost) and counted; what they would have cut
//! stays for the finish, which reports it.
//!
//! Every layer is verified on the part (an implementation that shares nothing with the
//! placement: [`crate::verify`]): its ball, at every pose and chord midpoint, is at least its
//! allowance less the layer's chord tolerance from the part.

use std::collections::BTreeMap;

use serde::Serialize;

use super::config::{ChannelLayers, Layering, Operation};
use super::plan_roughing::{BallTakeOff, RoughingContext};
use super::rapids::split_turning_rapids;
use super::setup::PlanSetup;
use crate::error::Result;
use crate::feed::FeedReport;
use crate::geom::{Move, Point3, Toolpath, Vector3};
use crate::mesh::Mesh;
use crate::path::{self, FinishingOptions, MaterialFilter, unreachable_by_reason};
use crate::stock::Stock;
use crate::verify::{PoseChecks, verify};

/// The loosest chord tolerance of a layer, mm: a layer leaves `a_k` for the next one to take,
/// so its chords need not be as tight as the finish's, only safely inside that.
const LAYER_TOLERANCE_MM: f64 = 0.05;

/// One layer of a channel roughing operation, for `report.json`.
#[derive(Clone, Debug, Serialize)]
pub struct ChannelLayerSummary {
    /// The ball is held this far off the part, mm.
    pub allowance_mm: f64,
    /// Shroud-to-hub layers: where the layer lies between the hub (0) and the shroud (1).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub height: Option<f64>,
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
    pub layering: Layering,
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
    layers: &ChannelLayers,
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

/// One layer to plan: the surface its passes are driven on, how far the ball stays off the
/// part, and where it starts off the drive surface (see [`crate::path::FinishingContext`]).
struct LayerDrive<'a> {
    drive: std::borrow::Cow<'a, Mesh>,
    allowance: f64,
    lift: f64,
    /// Shroud-to-hub layers: where between the hub (0) and the shroud (1).
    height: Option<f64>,
    drive_normal: Vector3,
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
    let layers = operation.layers.unwrap_or(ChannelLayers {
        step: setup.prepared_tool.ball_radius,
        max_layers: 1,
        layering: Layering::default(),
    });
    let part_model = context.part_model(part)?;
    let rest_before = context.deepest_rest(part, &part_model);
    let a = operation.stock_to_leave;
    // Offsets: waterlines from the top down (the planes run along the drive normal).
    // Shroud to hub: passes across each layer along the job's drive planes.
    let (drives, layers_left_out): (Vec<LayerDrive>, usize) = match layers.layering {
        Layering::Offset => {
            let (allowances, left_out) = layer_allowances(a, rest_before, &layers);
            let drives = allowances
                .into_iter()
                .map(|allowance| LayerDrive {
                    drive: std::borrow::Cow::Borrowed(part),
                    allowance,
                    lift: allowance,
                    height: None,
                    drive_normal: -Vector3::z(),
                })
                .collect();
            (drives, left_out)
        }
        Layering::ShroudToHub => {
            let hub = HubField::of(&part_model, context.floor());
            let top = context.material_top();
            let (heights, left_out) = hub.layer_heights(top, &layers);
            let drives = heights
                .into_iter()
                .map(|t| LayerDrive {
                    drive: std::borrow::Cow::Owned(hub.layer(top, t)),
                    allowance: a,
                    lift: 0.0,
                    height: Some(t),
                    drive_normal: setup.finishing.drive_normal,
                })
                .collect();
            (drives, left_out)
        }
    };
    let r = setup.prepared_tool.ball_radius;
    // A ball that would cut less than this into the material is in the air: the skin an
    // end mill's shape leaves over the allowance is not worth a pass of its own.
    let least_cut = 0.25 * layers.step;
    let reachable = |axis: &Vector3| setup.reachable(axis);
    let mut toolpath = Toolpath {
        tool_id: setup.tool.id,
        moves: Vec::new(),
    };
    let mut summaries = Vec::with_capacity(drives.len());
    let mut feed_control = Vec::new();
    let mut rapids_fed = 0;
    let mut failure = None;
    let mut last = last.copied();
    for layer_drive in &drives {
        let allowance = layer_drive.allowance;
        let material = context.material();
        let collider = setup.collider.with_material(material.clone());
        let touches =
            |centre: &Point3, radius: f64| !material.ball_is_clear(centre, radius - least_cut);
        let layer = MaterialFilter {
            touches: &touches,
            lead: 2.0 * r,
        };
        let mut ctx = setup.finishing_context(&collider, &setup.rays, &reachable);
        ctx.allowance = allowance;
        ctx.lift = layer_drive.lift;
        ctx.material_filter = Some(&layer);
        let tolerance = (0.1 * allowance)
            .min(LAYER_TOLERANCE_MM)
            .max(setup.finishing.tolerance);
        let options = FinishingOptions {
            scallop_height: operation.scallop_height,
            tolerance,
            sag_tolerance: tolerance,
            drive_normal: layer_drive.drive_normal,
            ..setup.finishing.clone()
        };
        let passes = path::finishing_passes(&layer_drive.drive, &ctx, &options, advance);
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
                last.as_ref(),
                setup.program_kinematics().as_ref(),
                super::rapids::MAX_RAPID_TURN_DEG,
            );
        }
        let on_part = verify(
            &layer_path,
            &setup.collider,
            &setup.prepared_tool,
            setup.search,
            PoseChecks::BallOnly,
        );
        let stock_left = on_part
            .min_cutter_clearance
            .min(on_part.min_chord_clearance)
            - allowance;
        let name = match layer_drive.height {
            Some(t) => format!("layer at {:.3} of the way from hub to shroud", t),
            None => format!("layer at {allowance} mm"),
        };
        if stock_left < -tolerance {
            failure.get_or_insert(format!(
                "channel roughing's {name} leaves only {:.4} mm on the part",
                stock_left + allowance
            ));
        }
        let volume_before = context.stock_volume();
        let taken = context.take_off_ball_operation(&mut layer_path, last.as_ref(), take_off);
        rapids_fed += taken.rapids_fed;
        if let Some(report) = taken.feed_control {
            feed_control.push((format!("{} ({name})", operation.name), report));
        }
        summaries.push(ChannelLayerSummary {
            allowance_mm: allowance,
            height: layer_drive.height,
            drive_points: passes.drive_points,
            points_in_air: passes.points_in_air,
            unreachable: passes.unreachable.len(),
            unreachable_by_reason: unreachable_by_reason(&passes.unreachable),
            segments: passes.segments.len(),
            cutting_length_mm: layer_path.cutting_length(),
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
            layering: layers.layering,
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

/// The hub under each vertical dexel line of the part's model: the top of the part's lowest
/// solid on the line, or the floor where the line misses the part (a bore, around the part).
struct HubField {
    /// Line (i, j)'s point at z = 0, and its hub height.
    points: Vec<Point3>,
    hub: Vec<f64>,
    counts: [usize; 2],
    spacing: f64,
    /// The lowest hub over the part (lines that meet it).
    lowest_on_part: f64,
}

impl HubField {
    fn of(part_model: &Stock, floor: f64) -> HubField {
        let grid = part_model.grid(2);
        let counts = grid.counts();
        let mut points = Vec::with_capacity(counts[0] * counts[1]);
        let mut hub = Vec::with_capacity(counts[0] * counts[1]);
        let mut lowest_on_part = f64::INFINITY;
        for j in 0..counts[1] {
            for i in 0..counts[0] {
                points.push(grid.line_point(i, j));
                let h = match grid.spans(i, j).first() {
                    Some(span) => {
                        let h = span.end.max(floor);
                        lowest_on_part = lowest_on_part.min(h);
                        h
                    }
                    None => floor,
                };
                hub.push(h);
            }
        }
        HubField {
            points,
            hub,
            counts,
            spacing: part_model.spacing(),
            lowest_on_part,
        }
    }

    /// The layers' heights between hub (0) and `top` (1), from the top down: evenly spaced so
    /// that no layer lies more than the step below the one above over the part, at most
    /// `max_layers` (the lowest kept: the material left near the top is what the end mills
    /// reach); and how many more the step would need.
    fn layer_heights(&self, top: f64, layers: &ChannelLayers) -> (Vec<f64>, usize) {
        let range = top - self.lowest_on_part;
        if range.is_nan() || range <= 0.0 {
            return (Vec::new(), 0);
        }
        let count = (range / layers.step).ceil().max(1.0) as usize;
        let planned = count.min(layers.max_layers);
        // Layer k lies k/count of the way up; the top one (k = count) is the shroud itself.
        let heights = (0..planned)
            .rev()
            .map(|k| k as f64 / count as f64)
            .collect();
        (heights, count - planned)
    }

    /// The layer `t` of the way from the hub up to `top`, as a mesh facing up: one vertex per
    /// line, two triangles per cell of four lines, except across a cliff (corners whose hubs
    /// differ by more than three spacings, a slope over 71°: a blade's side, the bore's edge),
    /// where the layer would stand on a wall rather than follow the hub.
    fn layer(&self, top: f64, t: f64) -> Mesh {
        let positions = self
            .points
            .iter()
            .zip(&self.hub)
            .map(|(p, &h)| Point3::new(p.x, p.y, h + t * (top - h).max(0.0)))
            .collect();
        let [nx, ny] = self.counts;
        let cliff = 3.0 * self.spacing;
        let mut triangles = Vec::new();
        for j in 0..ny.saturating_sub(1) {
            for i in 0..nx.saturating_sub(1) {
                let corners = [
                    i + nx * j,
                    i + 1 + nx * j,
                    i + 1 + nx * (j + 1),
                    i + nx * (j + 1),
                ];
                let (lo, hi) = corners
                    .iter()
                    .map(|&c| self.hub[c])
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), h| {
                        (lo.min(h), hi.max(h))
                    });
                if hi - lo > cliff {
                    continue;
                }
                let [a, b, c, d] = corners.map(|c| c as u32);
                triangles.push([a, b, c]);
                triangles.push([a, c, d]);
            }
        }
        Mesh {
            positions,
            triangles,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layers_reach_the_rest_a_step_at_a_time() {
        let layers = ChannelLayers {
            step: 2.0,
            max_layers: 8,
            layering: Layering::Offset,
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

    /// Two blocks side by side, 2 and 8 mm tall: the hub is each block's top, and a layer
    /// half way to a top at 10 stands at 6 over the low block and 9 over the high one, with no
    /// triangle across the 6 mm cliff between them. The heights run from the top down to the
    /// hub, as many as the deepest channel (10 − 2 over the low block) needs at the step.
    #[test]
    fn shroud_to_hub_layers_follow_the_hub_and_skip_its_cliffs() {
        let low = crate::mesh::fixtures::cuboid(10.0, 10.0, 2.0);
        let mut high = crate::mesh::fixtures::cuboid(10.0, 10.0, 8.0);
        for p in &mut high.positions {
            p.x += 10.0;
        }
        let mut both = low.clone();
        let base = both.positions.len() as u32;
        both.positions.extend(high.positions.iter().copied());
        both.triangles
            .extend(high.triangles.iter().map(|t| t.map(|i| i + base)));
        let model = Stock::from_mesh(&both, 0.5, crate::stock::DEFAULT_MAX_DEXELS).unwrap();
        let hub = HubField::of(&model, 0.0);
        assert_eq!(hub.lowest_on_part, 2.0);
        let layer = hub.layer(10.0, 0.5);
        for p in &layer.positions {
            let want = if p.x < 10.0 { 6.0 } else { 9.0 };
            assert!((p.z - want).abs() < 1e-9, "{p:?}");
        }
        assert!(!layer.triangles.is_empty());
        for t in &layer.triangles {
            let zs = t.map(|i| layer.positions[i as usize].z);
            assert!(
                zs.iter().all(|&z| z == zs[0]),
                "a triangle across the cliff: {zs:?}"
            );
            // Facing up.
            let [a, b, c] = t.map(|i| layer.positions[i as usize]);
            assert!((b - a).cross(&(c - a)).z > 0.0);
        }
        let layers = ChannelLayers {
            step: 3.0,
            max_layers: 16,
            layering: Layering::ShroudToHub,
        };
        let (heights, left) = hub.layer_heights(10.0, &layers);
        assert_eq!(heights, vec![2.0 / 3.0, 1.0 / 3.0, 0.0]);
        assert_eq!(left, 0);
        let (heights, left) = hub.layer_heights(
            10.0,
            &ChannelLayers {
                max_layers: 2,
                ..layers
            },
        );
        assert_eq!(heights, vec![1.0 / 3.0, 0.0]);
        assert_eq!(left, 1);
    }
}
