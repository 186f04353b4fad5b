//! The job's `indexed-rough` operation: the rest the vertical end mills left under overhangs,
//! roughed in indexed (3+2) setups. Where the rest stands is read off the planning stock
//! ([`crate::stock::rest`]), the setups' axes are proposed from its visibility maps
//! ([`crate::rough::setups`], within the machine's reach and the job's tilt limit), and each
//! setup's layers are planned in its own frame ([`crate::rough::indexed`]), in the order
//! proposed, each from what the planning stock holds after the setups before it.
//!
//! Each setup starts and ends on the machine's safe plane (distance `safe_distance` from the
//! pivot along its axis), where the table may turn; the posted moves are checked exactly in
//! each setup's frame like the vertical ones ([`super::plan_roughing::check_posted_roughing`]),
//! against the table, and by the stock run with the whole tool assembly.

use super::config::{Job, Operation};
use super::plan_roughing::{
    IndexedSummary, PlannedRoughing, RoughingContext, RoughingSummary, SetupSummary,
};
use super::rough_stages::{ToolRoughing, library_tool, roughing_options};
use super::setup::PlanSetup;
use crate::error::{Error, JobError, Result};
use crate::feed::{Cutter as FeedCutter, control_feeds};
use crate::geom::{Move, MoveKind, Point3, ToolPose, Toolpath, Vector3};
use crate::mesh::Mesh;
use crate::post::MachineKinematics;
use crate::rough::indexed::{SetupFrame, SetupRoughing, lifted_to, lowest_tip_z, rough_setup};
use crate::rough::setups::{RestPoint, SetupOptions, propose_setups};
use crate::rough::{RoughingFeeds, RoughingTool};
use crate::stock::cutter::CuttingBody;

/// Plans `operation` (an `indexed-rough`) on what `context`'s stock holds now.
pub fn plan_indexed_roughing(
    context: &mut RoughingContext,
    part: &Mesh,
    job: &Job,
    setup: &PlanSetup,
    operation: &Operation,
) -> Result<PlannedRoughing> {
    let fail = |reason: String| {
        Error::JobFile(JobError::Operations(format!(
            "operation '{}': {reason}",
            operation.name
        )))
    };
    let (tool, chosen) = match operation.library_tool {
        Some(id) => library_tool(&context.library, id)?,
        None => {
            let tool = context.previous_tool.clone().ok_or_else(|| {
                fail(
                    "indexed roughing follows a roughing operation (it cuts with its end mill)"
                        .into(),
                )
            })?;
            (
                tool,
                "the end mill of the roughing before it, along tilted axes".to_string(),
            )
        }
    };
    let margin = job.safety.holder_margin;
    let planning = RoughingTool::of(&tool, margin);
    let shape = context.shape(part, operation.stock_to_leave)?;
    let feeds = RoughingFeeds {
        cut: job.roughing.cut_feed,
        entry: job.roughing.entry_feed,
        rapid: job.machine.rapid_feed,
    };
    let how = ToolRoughing {
        holder_margin: margin,
        floor: f64::NEG_INFINITY,
        feeds: &feeds,
        tolerance: job.strategy.tolerance,
        feed_control: None,
        uniform_layers: false,
        max_depth: None,
        max_engagement: job.roughing.max_engagement,
        paths: job.roughing.layer_paths,
        min_depth: None,
    };
    let options = roughing_options(&planning, &tool, &how);

    // Where the rest stands, and how much: triangle centres of the part with more than the
    // stock to leave and two dexel spacings (the model's resolution) standing on them.
    let part_model = context.part_model(part)?;
    let spacing = context.stock.spacing();
    let rest = crate::stock::rest::rest_per_triangle(
        &context.stock,
        part,
        &part_model,
        context.stock.bounds().diagonal(),
    );
    let threshold = operation.stock_to_leave + 2.0 * spacing;
    let (points, rest_of): (Vec<RestPoint>, Vec<f64>) = rest
        .iter()
        .enumerate()
        .filter(|(_, r)| **r > threshold)
        .filter_map(|(t, &r)| {
            let [a, b, c] = part.corners(t);
            let normal = (b - a).cross(&(c - a));
            let area = 0.5 * normal.norm();
            (area > 0.0).then(|| {
                let point = RestPoint {
                    point: a + ((b - a) + (c - a)) / 3.0,
                    normal,
                    weight: (r - operation.stock_to_leave) * area,
                };
                (point, r)
            })
        })
        .unzip();
    let reachable = |d: &Vector3| {
        let pose = ToolPose {
            tip: setup.pivot,
            axis: nalgebra::Unit::new_normalize(*d),
        };
        setup.kinematics.inverse(&pose, None).is_ok()
    };
    let proposal = propose_setups(
        &setup.rays,
        &points,
        reachable,
        &SetupOptions {
            max_setups: job.roughing.indexed_setups,
            min_tilt_deg: 10.0,
            max_tilt_deg: job.roughing.indexed_max_tilt_deg,
            min_share: 0.05,
            level: 3,
            lift: planning.radius + operation.stock_to_leave,
        },
    )
    .map_err(|e| Error::Internal(format!("visibility of the rest: {e}")))?;

    let body = CuttingBody::of(&tool.cutter);
    let to_safe =
        |pose: &ToolPose| (setup.safe_distance - (pose.tip - setup.pivot).dot(&pose.axis)).max(0.0);
    let mut toolpath = Toolpath {
        tool_id: tool.id,
        moves: Vec::new(),
    };
    let mut removed = Vec::new();
    let mut setups = Vec::new();
    let holder_radius = tool
        .bodies()
        .iter()
        .filter(|b| b.role == crate::tool::BodyRole::Holder)
        .map(|b| b.radius_from.max(b.radius_to))
        .fold(planning.radius, f64::max);
    for proposed in &proposal.setups {
        // The rest this setup was proposed for: each point out along its normal to where
        // its material ends.
        let seen: Vec<(Point3, Point3)> = proposed
            .seen
            .iter()
            .map(|&k| {
                let p = &points[k];
                (p.point, p.point + p.normal.normalize() * rest_of[k])
            })
            .collect();
        // Apart by more than the tool's diameter, the rest is cleared zone by zone, each
        // holder clearing only what stands about its own zone.
        let starts: Vec<Point3> = seen.iter().map(|(a, _)| *a).collect();
        let zones: Vec<Vec<(Point3, Point3)>> = clusters(&starts, 2.0 * planning.radius)
            .into_iter()
            .map(|members| members.into_iter().map(|k| seen[k]).collect())
            .collect();
        let axis = Vector3::from(proposed.axis);
        let frame = SetupFrame::new(&axis)
            .ok_or_else(|| Error::Internal(format!("setup axis {axis:?} points down")))?;
        let lowest = lowest_tip_z(
            &tool,
            &frame.axis(),
            setup.table.top_z,
            job.safety.table_margin,
        );
        let planned = rough_setup(
            &shape,
            &context.stock,
            &frame,
            &planning,
            tool.id,
            &SetupRoughing {
                lowest_tip_z: lowest,
                zones: &zones,
                holder_radius,
                body: &body,
                options: &options,
            },
        )
        .map_err(|e| {
            fail(format!(
                "setup along ({:.3}, {:.3}, {:.3}) with T{}: {e}",
                axis.x, axis.y, axis.z, tool.id
            ))
        })?;
        let Some(mut roughing) = planned else {
            continue;
        };
        if !roughing
            .toolpath
            .moves
            .iter()
            .any(|m| m.kind == MoveKind::Cut)
        {
            continue;
        }
        lifted_to(&mut roughing.toolpath, to_safe, feeds.rapid);
        let taken = context
            .stock
            .remove_cutting(&roughing.toolpath, &body, job.strategy.tolerance);
        let joints = setup
            .kinematics
            .inverse(&roughing.toolpath.moves[0].pose, None)
            .map_err(|e| Error::Internal(format!("setup axis {axis:?}: {e}")))?;
        setups.push(SetupSummary {
            axis: proposed.axis,
            tilt_deg: frame.tilt_deg(),
            rotary_deg: [joints.a, joints.c],
            seen_share: proposed.share,
            layers: roughing.layers,
            moves: roughing.toolpath.moves.len(),
            removed_mm3: taken.iter().sum(),
            not_reached: roughing.not_reached,
        });
        toolpath.moves.extend(roughing.toolpath.moves);
        removed.extend(taken);
    }
    if toolpath.moves.is_empty() {
        // Nothing to cut along any allowed axis: the operation stays on the safe plane.
        let centre = part.aabb().center();
        toolpath.moves.push(Move {
            pose: ToolPose {
                tip: Point3::new(centre.x, centre.y, setup.pivot.z + setup.safe_distance),
                axis: nalgebra::Unit::new_normalize(Vector3::z()),
            },
            kind: MoveKind::Rapid,
            feed: feeds.rapid,
        });
        removed.push(0.0);
    }
    let feed_control = job.cutting.model().map(|model| {
        let cutter = FeedCutter {
            diameter: tool.cutter.diameter(),
            spindle_rpm: f64::from(job.roughing.spindle_rpm),
            pass_feed: feeds.cut,
            rapid_feed: feeds.rapid,
            speed_up: true,
        };
        let skin = job.strategy.tolerance * spacing * spacing;
        let (controlled, report) = control_feeds(&toolpath, &removed, &cutter, &model, skin);
        for (m, feed) in toolpath.moves.iter_mut().zip(controlled) {
            m.feed = feed;
        }
        report
    });
    let cutting_length_mm = toolpath.cutting_length();
    Ok(PlannedRoughing {
        summary: RoughingSummary {
            operation: operation.name.clone(),
            tool_id: tool.id,
            tool: tool.describe(),
            chosen,
            planning,
            material: "rest",
            feed_control,
            stock_to_leave_mm: operation.stock_to_leave,
            shape_triangles: shape.triangles.len(),
            layers: Vec::new(),
            not_reached: None,
            moves: toolpath.moves.len(),
            cutting_length_mm,
            indexed: Some(IndexedSummary {
                rest_threshold_mm: threshold,
                proposal,
                setups,
            }),
            overcut_vs_shape: None,
            overcut_vs_part: None,
        },
        tool,
        toolpath,
        bound: super::plan_roughing::PlannedBound::Shape(shape),
    })
}

/// `points` grouped by chains of neighbours within `link` of each other (union–find over a
/// grid of `link`-sized cells), each group in index order, the groups by their first index.
fn clusters(points: &[Point3], link: f64) -> Vec<Vec<usize>> {
    use std::collections::HashMap;
    let cell = |p: &Point3| [p.x, p.y, p.z].map(|v| (v / link).floor() as i64);
    let mut grid: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
    for (k, p) in points.iter().enumerate() {
        grid.entry(cell(p)).or_default().push(k);
    }
    let mut parent: Vec<usize> = (0..points.len()).collect();
    fn root(parent: &mut [usize], mut k: usize) -> usize {
        while parent[k] != k {
            parent[k] = parent[parent[k]];
            k = parent[k];
        }
        k
    }
    for (k, p) in points.iter().enumerate() {
        let c = cell(p);
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let Some(near) = grid.get(&[c[0] + dx, c[1] + dy, c[2] + dz]) else {
                        continue;
                    };
                    for &m in near {
                        if m < k && (points[m] - p).norm() <= link {
                            let (a, b) = (root(&mut parent, k), root(&mut parent, m));
                            parent[a.max(b)] = a.min(b);
                        }
                    }
                }
            }
        }
    }
    let mut groups: Vec<Vec<usize>> = Vec::new();
    let mut group_of: HashMap<usize, usize> = HashMap::new();
    for k in 0..points.len() {
        let r = root(&mut parent, k);
        let g = *group_of.entry(r).or_insert_with(|| {
            groups.push(Vec::new());
            groups.len() - 1
        });
        groups[g].push(k);
    }
    groups
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two rows of points 1 mm apart, 10 mm from each other: two groups at a 2 mm link, one
    /// at 12.
    #[test]
    fn points_chain_into_groups_by_their_link() {
        let points: Vec<Point3> = (0..20)
            .map(|k| Point3::new((k % 10) as f64, 10.0 * (k / 10) as f64, 0.0))
            .collect();
        let groups = clusters(&points, 2.0);
        assert_eq!(
            groups,
            vec![(0..10).collect::<Vec<_>>(), (10..20).collect()]
        );
        assert_eq!(clusters(&points, 12.0).len(), 1);
        assert!(clusters(&[], 1.0).is_empty());
    }
}
