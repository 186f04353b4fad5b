//! Machining-time estimate from the posted blocks: one model for every program, 5-axis or
//! planar.
//!
//! Per block (from the previous block's joints): linear length `L` (machine coordinates, what
//! the controller actually moves: `|Δ(X, Y, Z)|` for a straight block, the helix
//! `√((r·θ)² + ΔZ²)` for an arc of radius `r` and sweep `θ`) and rotary travel
//! `R = max(|ΔA|, |ΔC|)` (degrees). Time = `max(L / F, R / ω)` with `F` the move's feed (the
//! rapid rate for rapids) and `ω` the maximum rotary speed. A pure rotary feed block (`L` below
//! 1e-9 mm) is timed at `max(R / F, R / ω)`, as G94 controllers read F as degrees/min there.
//! Each block may also pay a fixed dwell (the block-processing delay seed 004 §1.2 counts for
//! 2.5D programs; 0 for the 5-axis jobs). Acceleration is ignored, so the estimate is a lower
//! bound. The first block has no known start: only its dwell.

use serde::{Deserialize, Serialize};

use super::ArcXY;
use super::dialect::FeedMode;
use super::kinematics::Joints;
use crate::geom::{Move, MoveKind, ToolPose};

/// Seconds per move kind.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TimeEstimate {
    /// Rapid (G0) time, seconds.
    pub rapid_s: f64,
    /// Approach time, seconds.
    pub approach_s: f64,
    /// Cutting time, seconds.
    pub cut_s: f64,
    /// Retract time, seconds.
    pub retract_s: f64,
    /// Block-processing dwell, seconds (absent from reports when 0).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub dwell_s: f64,
    /// Blocks skipped because their feed was not finite and positive.
    pub invalid_feed_blocks: usize,
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

impl TimeEstimate {
    /// Total seconds.
    pub fn total_s(&self) -> f64 {
        self.rapid_s + self.approach_s + self.cut_s + self.retract_s + self.dwell_s
    }

    /// Adds `other`'s times and skipped blocks (another stretch of the same program).
    pub fn merge(&mut self, other: &TimeEstimate) {
        self.rapid_s += other.rapid_s;
        self.approach_s += other.approach_s;
        self.cut_s += other.cut_s;
        self.retract_s += other.retract_s;
        self.dwell_s += other.dwell_s;
        self.invalid_feed_blocks += other.invalid_feed_blocks;
    }

    pub(super) fn add(&mut self, kind: MoveKind, s: f64) {
        match kind {
            MoveKind::Rapid => self.rapid_s += s,
            MoveKind::Approach => self.approach_s += s,
            MoveKind::Cut => self.cut_s += s,
            MoveKind::Retract => self.retract_s += s,
        }
    }
}

/// The machine figures the estimate needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeModel {
    /// Fastest rotary motion, degrees/min; a non-positive value ignores rotary limits.
    pub max_rotary_deg_per_min: f64,
    /// Fixed time each motion block costs on top of its motion, seconds (≥ 0).
    pub dwell_per_block_s: f64,
}

/// Linear length (mm) below which a block counts as pure rotary.
const PURE_ROTARY_EPS_MM: f64 = 1e-9;

/// Linear length (mm) the control travels from `from` to `to`, along the arc when there is one.
pub fn block_length(from: &Joints, to: &Joints, arc: Option<&ArcXY>) -> f64 {
    let Some(arc) = arc else {
        return (to.xyz() - from.xyz()).norm();
    };
    let [cx, cy] = arc.center;
    let a0 = (from.y - cy).atan2(from.x - cx);
    let a1 = (to.y - cy).atan2(to.x - cx);
    let mut sweep = if arc.ccw {
        (a1 - a0).rem_euclid(std::f64::consts::TAU)
    } else {
        (a0 - a1).rem_euclid(std::f64::consts::TAU)
    };
    if sweep == 0.0 {
        sweep = std::f64::consts::TAU; // an arc that ends where it starts is a full circle
    }
    let radius = (from.x - cx).hypot(from.y - cy);
    (radius * sweep).hypot(to.z - from.z)
}

/// Seconds of motion of one block (no dwell; see the module docs), or `None` when its feed is
/// not finite and positive.
pub fn block_seconds(
    from: &Joints,
    m: &Move,
    to: &Joints,
    arc: Option<&ArcXY>,
    max_rotary_deg_per_min: f64,
) -> Option<f64> {
    if !(m.feed.is_finite() && m.feed > 0.0) {
        return None;
    }
    let lin = block_length(from, to, arc);
    let rot = (to.a - from.a).abs().max((to.c - from.c).abs());
    let rot_min = if max_rotary_deg_per_min > 0.0 {
        rot / max_rotary_deg_per_min
    } else {
        0.0
    };
    let minutes = if lin < PURE_ROTARY_EPS_MM && m.kind != MoveKind::Rapid {
        (rot / m.feed).max(rot_min)
    } else {
        (lin / m.feed).max(rot_min)
    };
    Some(60.0 * minutes)
}

/// Estimates the machining time of posted blocks `(move, joints, arc)` (see the module docs).
pub fn estimate_blocks<'a>(
    blocks: impl IntoIterator<Item = (&'a Move, &'a Joints, Option<&'a ArcXY>)>,
    model: &TimeModel,
) -> TimeEstimate {
    let mut est = TimeEstimate::default();
    let mut previous: Option<&Joints> = None;
    for (m, j, arc) in blocks {
        est.dwell_s += model.dwell_per_block_s;
        if let Some(from) = previous {
            match block_seconds(from, m, j, arc, model.max_rotary_deg_per_min) {
                Some(s) => est.add(m.kind, s),
                None => est.invalid_feed_blocks += 1,
            }
        }
        previous = Some(j);
    }
    est
}

/// Estimates the machining time of a linearised program posted with feed per minute (no
/// dwell). `max_rotary_deg_per_min` must be positive; a non-positive value ignores rotary
/// limits.
pub fn estimate_time(program: &[(Move, Joints)], max_rotary_deg_per_min: f64) -> TimeEstimate {
    estimate_blocks(
        program.iter().map(|(m, j)| (m, j, None)),
        &TimeModel {
            max_rotary_deg_per_min,
            dwell_per_block_s: 0.0,
        },
    )
}

/// Minutes an inverse-time (`G93`) feed block from `from` (pose and joints) to `m` (at
/// joints `to`) lasts, as the post prints it (`F` = 1 / these minutes) and the control runs
/// it: the longer of the part-frame motion of the tip and of the control point
/// `control_point_mm` up the axis at the block's feed, and the largest rotary move at
/// `max_rotary_deg_per_min`. Not the machine's linear travel: on a table-table machine a
/// block that turns the table moves X, Y, Z far more than the tool moves over the part.
pub fn inverse_time_minutes(
    from: (&ToolPose, &Joints),
    m: &Move,
    to: &Joints,
    control_point_mm: f64,
    max_rotary_deg_per_min: f64,
) -> f64 {
    let (pose, joints) = from;
    let centre = |p: &ToolPose| p.tip + p.axis.into_inner() * control_point_mm;
    let distance = (m.pose.tip - pose.tip)
        .norm()
        .max((centre(&m.pose) - centre(pose)).norm());
    let turn = (to.a - joints.a).abs().max((to.c - joints.c).abs());
    (distance / m.feed.max(1e-9)).max(turn / max_rotary_deg_per_min)
}

/// The inverse-time `F` a block lasting `minutes` is posted with (1/min), as printed: a
/// block too short to time at the printed resolution gets the fastest F printable rather
/// than an infinite one, and lasts what that F says.
pub fn posted_inverse_time_feed(minutes: f64) -> f64 {
    let f = (1.0 / minutes.max(1e-9)).min(MAX_INVERSE_TIME_FEED);
    let printed = super::format::fixed(f, super::format::INVERSE_TIME_DECIMALS);
    printed.parse().unwrap_or(f)
}

/// The fastest inverse-time `F` posted, 1/min.
const MAX_INVERSE_TIME_FEED: f64 = 1e6;

/// Estimates the machining time of a linearised program as posted in `feed` mode (no dwell):
/// per minute as [`estimate_time`]; in inverse time every feed block lasts what its `F`
/// says as printed ([`inverse_time_minutes`], [`posted_inverse_time_feed`]) and rapids as
/// per minute. `max_rotary_deg_per_min` must be
/// positive.
pub fn estimate_time_posted(
    program: &[(Move, Joints)],
    feed: FeedMode,
    control_point_mm: f64,
    max_rotary_deg_per_min: f64,
) -> TimeEstimate {
    if feed == FeedMode::PerMinute {
        return estimate_time(program, max_rotary_deg_per_min);
    }
    let mut est = TimeEstimate::default();
    for pair in program.windows(2) {
        let ((from, from_joints), (m, to)) = (&pair[0], &pair[1]);
        if !(m.feed.is_finite() && m.feed > 0.0) {
            est.invalid_feed_blocks += 1;
            continue;
        }
        let seconds = if m.kind == MoveKind::Rapid {
            block_seconds(from_joints, m, to, None, max_rotary_deg_per_min).unwrap_or(0.0)
        } else {
            // What the block's F says, as printed: on the blower 760 blocks shorter than
            // 1e-6 min last 6e-5 s each at the fastest F printable.
            60.0 / posted_inverse_time_feed(inverse_time_minutes(
                (&from.pose, from_joints),
                m,
                to,
                control_point_mm,
                max_rotary_deg_per_min,
            ))
        };
        est.add(m.kind, seconds);
    }
    est
}
