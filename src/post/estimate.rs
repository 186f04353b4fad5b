//! Machining-time estimate from the posted blocks.
//!
//! Per block (from the previous block's joints): linear length `L = |Δ(X, Y, Z)|` (machine
//! coordinates, what the controller actually moves) and rotary travel `R = max(|ΔA|, |ΔC|)`
//! (degrees). Time = `max(L / F, R / ω)` with `F` the move's feed (the rapid rate for rapids)
//! and `ω` the maximum rotary speed. A pure rotary feed block (`L` below 1e-9 mm) is timed at
//! `max(R / F, R / ω)`, as G94 controllers read F as degrees/min there. Acceleration is
//! ignored, so the estimate is a lower bound. The first block has no known start: 0 s.

use serde::{Deserialize, Serialize};

use super::kinematics::Joints;
use crate::geom::{Move, MoveKind};

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
    /// Blocks skipped because their feed was not finite and positive.
    pub invalid_feed_blocks: usize,
}

impl TimeEstimate {
    /// Total seconds.
    pub fn total_s(&self) -> f64 {
        self.rapid_s + self.approach_s + self.cut_s + self.retract_s
    }
}

/// Linear length (mm) below which a block counts as pure rotary.
const PURE_ROTARY_EPS_MM: f64 = 1e-9;

/// Estimates the machining time of posted blocks (see the module docs).
/// `max_rotary_deg_per_min` must be positive; a non-positive value ignores rotary limits.
pub fn estimate_time(program: &[(Move, Joints)], max_rotary_deg_per_min: f64) -> TimeEstimate {
    let mut est = TimeEstimate::default();
    for w in program.windows(2) {
        let (j0, (m, j1)) = (&w[0].1, (&w[1].0, &w[1].1));
        let lin = (j1.xyz() - j0.xyz()).norm();
        let rot = (j1.a - j0.a).abs().max((j1.c - j0.c).abs());
        if !(m.feed.is_finite() && m.feed > 0.0) {
            est.invalid_feed_blocks += 1;
            continue;
        }
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
        let s = 60.0 * minutes;
        match m.kind {
            MoveKind::Rapid => est.rapid_s += s,
            MoveKind::Approach => est.approach_s += s,
            MoveKind::Cut => est.cut_s += s,
            MoveKind::Retract => est.retract_s += s,
        }
    }
    est
}
