//! Linking cut segments into one toolpath: retract along the tool axis to a safe plane, move
//! there, plunge along the next axis.
//!
//! The safe plane is perpendicular to the tool axis at `safe_distance` from the machine's pivot
//! (where the rotary axes meet). For a machine whose tool points along machine +Z that is the
//! plane machine Z = `safe_distance`, whatever the rotary angles: with `safe_distance` larger
//! than the part's reach from the pivot, the tool is clear of the part there for every rotary
//! position, so the positioning moves between segments are safe however the controller
//! interpolates them. The moves along the axis (retract and plunge) are checked exactly: the
//! tool's bodies extended along the axis up to the safe plane must clear the part; segment ends
//! that fail are trimmed.
//!
//! Rapids keep `rapid_margin` between the ball and the part. Along the axis the ball leaves
//! the surface slowly where the axis is tilted far from the normal (a blade wall cut with a
//! steep lead), so the feed part of the retract and of the approach is lengthened beyond
//! `clearance` until the rest of the way to the safe plane keeps that margin.

use rayon::prelude::*;
use serde::Serialize;

use super::CutSegment;
use crate::collide::{PartCollider, PreparedTool};
use crate::geom::{Direction, Point3, angle_between, slerp};
use crate::geom::{Move, MoveKind, ToolPose, Toolpath};

/// Where and how fast to link.
#[derive(Clone, Debug, PartialEq)]
pub struct LinkOptions {
    /// The pivot of the rotary axes in the part frame.
    pub pivot: Point3,
    /// Distance of the safe plane from the pivot along the tool axis, mm.
    pub safe_distance: f64,
    /// Rapid down to this far above the entry point (along the axis), then feed in, mm.
    pub clearance: f64,
    pub cut_feed: f64,
    pub approach_feed: f64,
    pub retract_feed: f64,
    pub rapid_feed: f64,
    /// Least distance between the ball and the part along rapids, mm.
    pub rapid_margin: f64,
    /// Longest short link, mm between the ball centres: the next segment starting this near
    /// is reached by lifting a little along the axis, moving across at the retract feed and
    /// plunging, where all of that is checked clear, instead of by way of the safe plane.
    /// 0: every segment is left to the safe plane.
    pub max_short_link: f64,
    /// How much closer than its radius the ball may come to the part along a move, mm (the
    /// planner's chord tolerance): a next segment starting within the ball's radius is reached
    /// by cutting straight across where that move keeps it.
    pub chord_tolerance: f64,
}

/// How far up the axis a short link lifts, tried in order, in multiples of the ball radius.
const SHORT_LINK_LIFTS: [f64; 3] = [0.5, 1.5, 5.0];

/// Largest axis turn along a short link, degrees: beyond it the control's interpolation of
/// the rotary axes strays too far from the turn checked here.
const SHORT_LINK_MAX_TURN_DEG: f64 = 30.0;

/// What linking changed.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct LinkReport {
    pub segments: usize,
    /// Cut poses removed from segment ends because the tool could not retract or plunge there.
    pub trimmed_poses: usize,
    /// Segments left with fewer than two poses after trimming.
    pub dropped_segments: usize,
    /// Segments reached from the one before by cutting straight across, by a short lifted
    /// link, and by way of the safe plane.
    pub links_across: usize,
    pub short_links: usize,
    pub safe_plane_retracts: usize,
}

/// Links `segments` in order into one toolpath for `tool`.
pub fn link(
    segments: &[CutSegment],
    part: &PartCollider,
    tool: &PreparedTool,
    tool_id: u32,
    options: &LinkOptions,
) -> (Toolpath, LinkReport) {
    let mut path = Toolpath {
        tool_id,
        moves: Vec::new(),
    };
    let mut report = LinkReport::default();
    let along = |pose: &ToolPose, distance: f64| ToolPose {
        tip: pose.tip + pose.axis.into_inner() * distance,
        axis: pose.axis,
    };
    let to_safe = |pose: &ToolPose| {
        (options.safe_distance - (pose.tip - options.pivot).dot(&pose.axis)).max(0.0)
    };
    let can_leave = |pose: &ToolPose| {
        let sweep = to_safe(pose);
        part.check_ball_sweep(tool, pose, sweep).is_ok()
            && part.check_bodies_swept(tool, pose, sweep).is_ok()
    };
    let feed_length = |pose: &ToolPose| {
        feed_lift(
            part,
            pose,
            tool.ball_radius,
            to_safe(pose),
            options.rapid_margin,
        )
        .max(options.clearance)
        .min(to_safe(pose))
    };
    // Trimming is the expensive part (long swept bodies); segments are independent.
    let kept: Vec<(usize, usize)> = segments
        .par_iter()
        .map(|segment| {
            let poses = &segment.poses;
            let start = poses.iter().position(&can_leave).unwrap_or(poses.len());
            let end = poses
                .iter()
                .rposition(&can_leave)
                .map_or(start, |i| (i + 1).max(start));
            (start, end)
        })
        .collect();
    // The segments kept, and for each the lift of the short link into the next one, if any.
    let ends: Vec<(ToolPose, ToolPose)> = segments
        .iter()
        .zip(&kept)
        .filter(|(_, (start, end))| end - start >= 2)
        .map(|(segment, &(start, end))| (segment.poses[start], segment.poses[end - 1]))
        .collect();
    let short: Vec<Option<Link>> = (0..ends.len())
        .into_par_iter()
        .map(|i| {
            let next = ends.get(i + 1)?;
            short_link(part, tool, &ends[i].1, &next.0, options)
        })
        .collect();
    let mut arriving: Option<Link> = None;
    let mut k = 0;
    for (segment, &(start, end)) in segments.iter().zip(&kept) {
        let poses = &segment.poses;
        report.trimmed_poses += poses.len() - (end - start);
        if end - start < 2 {
            report.dropped_segments += 1;
            continue;
        }
        report.segments += 1;
        let (entry, exit) = (poses[start], poses[end - 1]);
        let mv = |pose, kind, feed| Move { pose, kind, feed };
        match arriving.take() {
            Some(Link::Across) => {
                // Across at the cut feed, but an approach: the pass it enters starts here
                // (its direction may be the other way round, as in a zig-zag).
                report.links_across += 1;
                path.moves
                    .push(mv(entry, MoveKind::Approach, options.cut_feed));
            }
            Some(Link::Lifted(lift)) => {
                report.short_links += 1;
                path.moves.push(mv(
                    along(&entry, lift),
                    MoveKind::Retract,
                    options.retract_feed,
                ));
                path.moves
                    .push(mv(entry, MoveKind::Approach, options.approach_feed));
            }
            None => {
                report.safe_plane_retracts += 1;
                path.moves.push(mv(
                    along(&entry, to_safe(&entry)),
                    MoveKind::Rapid,
                    options.rapid_feed,
                ));
                path.moves.push(mv(
                    along(&entry, feed_length(&entry)),
                    MoveKind::Rapid,
                    options.rapid_feed,
                ));
                path.moves
                    .push(mv(entry, MoveKind::Approach, options.approach_feed));
            }
        }
        for pose in &poses[start + 1..end] {
            path.moves.push(mv(*pose, MoveKind::Cut, options.cut_feed));
        }
        match short[k] {
            Some(Link::Across) => arriving = Some(Link::Across),
            Some(Link::Lifted(lift)) => {
                path.moves.push(mv(
                    along(&exit, lift),
                    MoveKind::Retract,
                    options.retract_feed,
                ));
                arriving = Some(Link::Lifted(lift));
            }
            None => {
                path.moves.push(mv(
                    along(&exit, feed_length(&exit)),
                    MoveKind::Retract,
                    options.retract_feed,
                ));
                path.moves.push(mv(
                    along(&exit, to_safe(&exit)),
                    MoveKind::Rapid,
                    options.rapid_feed,
                ));
            }
        }
        k += 1;
    }
    (path, report)
}

/// How a segment is reached from the one before.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Link {
    /// Straight across, cutting: the next segment starts within the ball's radius and the
    /// move keeps the ball within the chord tolerance.
    Across,
    /// Up this far along the axis, across, and down.
    Lifted(f64),
}

/// The lift of a short link from `exit` to `entry`, if one is short enough and clear: up
/// `lift` along the exit's axis, straight across to `lift` above the entry along its axis
/// (the axis turning evenly), down to the entry. The ball keeps the rapid margin from the part
/// along the move across and does not touch it along the lifts; shank, holder and table are
/// checked along the lifts as swept bodies and across at poses no more than a fifth of the
/// ball radius and one degree apart.
fn short_link(
    part: &PartCollider,
    tool: &PreparedTool,
    exit: &ToolPose,
    entry: &ToolPose,
    options: &LinkOptions,
) -> Option<Link> {
    let r = tool.ball_radius;
    let centre = |p: &ToolPose, lift: f64| p.tip + p.axis.into_inner() * (r + lift);
    let turn = angle_between(&exit.axis, &entry.axis).to_degrees();
    let distance = (centre(exit, 0.0) - centre(entry, 0.0)).norm();
    if distance > options.max_short_link || turn > SHORT_LINK_MAX_TURN_DEG {
        return None;
    }
    let bodies_clear = |a: &Point3, b: &Point3| {
        let steps = ((b - a).norm() / (0.2 * r)).max(turn).ceil().max(1.0) as usize;
        (0..=steps).all(|s| {
            let t = s as f64 / steps as f64;
            let axis = Direction::new_normalize(slerp(&exit.axis, &entry.axis, t));
            let c = a + (b - a) * t;
            part.check_bodies(
                tool,
                &ToolPose {
                    tip: c - axis.into_inner() * r,
                    axis,
                },
            )
            .is_ok()
        })
    };
    let (a, b) = (centre(exit, 0.0), centre(entry, 0.0));
    if distance <= r
        && turn <= 5.0
        && !part
            .surface()
            .segment_within(&a, &b, r - options.chord_tolerance)
        && bodies_clear(&a, &b)
    {
        return Some(Link::Across);
    }
    SHORT_LINK_LIFTS
        .iter()
        .map(|k| k * r)
        .find(|&lift| {
            let (a, b) = (centre(exit, lift), centre(entry, lift));
            part.check_ball_sweep(tool, exit, lift).is_ok()
                && part.check_ball_sweep(tool, entry, lift).is_ok()
                && part.check_bodies_swept(tool, exit, lift).is_ok()
                && part.check_bodies_swept(tool, entry, lift).is_ok()
                && !part
                    .surface()
                    .segment_within(&a, &b, r + options.rapid_margin)
                && bodies_clear(&a, &b)
        })
        .map(Link::Lifted)
}

/// How far up the axis from `pose` the ball must be fed before the rest of the way, up to
/// `to_safe`, keeps `margin` from the part. Sampled every `h` from the safe plane down: the
/// distance to the part changes by at most `h/2` between a sample and the nearer of its
/// neighbours (it is 1-Lipschitz), so samples at `r + 1.25·margin + h/2` or more keep the whole
/// stretch between them at `r + 1.25·margin` (the quarter is room for the back-simulation's own
/// error bound on rapids).
fn feed_lift(part: &PartCollider, pose: &ToolPose, r: f64, to_safe: f64, margin: f64) -> f64 {
    let h = (0.5 * margin).clamp(0.01, 1.0);
    let needed = r + 1.25 * margin + 0.5 * h;
    let samples = (to_safe / h).ceil().max(1.0) as usize;
    let axis = pose.axis.into_inner();
    let centre = |s: f64| pose.tip + axis * (r + s);
    for k in (0..=samples).rev() {
        let s = (k as f64 * h).min(to_safe);
        if part.surface().any_within(&centre(s), needed) {
            return ((k + 1) as f64 * h).min(to_safe);
        }
    }
    0.0
}
