//! Linearisation: make the controller's joint-space interpolation follow the planned motion.
//!
//! Between two blocks the controller interpolates X, Y, Z, A, C linearly. In the part frame the
//! tool tip then follows a curve, not the straight segment the planner meant, and the tool
//! axis does not follow the great-circle (slerp) interpolation.
//!
//! Each feed move (Approach, Cut, Retract) `p0 → p1` is walked from the previous block in
//! adaptive steps `t → t + dt` along its planned motion: the control point (the point
//! `control_point_mm` up the axis from the tip; the ball centre for a ball-end mill, the tip
//! with 0) moves on the straight segment the planner checked, the axis by `slerp`. A step's
//! joints come from [`MachineKinematics::inverse_relaxed`] relative to the current joints, and
//! the step is accepted when the forward kinematics of the joint-space interpolation, at the
//! seven [`CHECK_PARAMETERS`] of the step, is within `tolerance_mm` of the planned control
//! point (and of the flutes' top, `flutes_above_control_mm` above it, where a tool cuts with
//! its flutes) and within `angle_tolerance_deg` of the planned axis; otherwise `dt` is halved (down
//! to `2^−max_depth`, error beyond), and after each accepted step doubled. Every accepted
//! interior step end becomes an inserted block, lying exactly on the planned segment. The
//! samples do not bound the deviation between them by themselves; the back-simulation of the
//! posted program (`verify::check_posted`) does, and the plan fails when it finds more.
//!
//! Why a forward walk rather than splitting the move at its midpoint: the end joints must be on
//! the branch and C wrap the planned motion actually reaches. Picking them by joint distance
//! alone can choose a branch that is near in joint space but not connected along the motion
//! (the axis sweeping around the pole at 1°, where the exact C turns by ~165° while the other
//! branch looks like a 20° move); no midpoint subdivision converges then. Walking forward, the
//! nearest branch of each short step is one whose joint motion verifiably follows the plan.
//!
//! Joints use half the angle tolerance as the relaxed inverse's axis-error budget (or half the
//! axis error that moves the flutes' top by the tolerance, where that is less): near the C
//! singularity C stays calm (tip exact, axis within the budget), leaving the other half for
//! interpolation. Rapid moves are positioning moves above the safe height: on a
//! machine that turns only the table they get the nearest joints (C continuity kept) and are
//! not subdivided, the table turning under a tool that stays on its safe plane; on a machine
//! with head axes, whose rapids swing the tool about the head's pivot, they follow their
//! planned motion like feed moves. C is unwrapped continuously across the whole program.
//!
//! # Limits
//!
//! The program is linearised pass by pass (a rapid and the feed moves up to the next). Where a
//! pass starts, the rotaries may take either branch and any turn inside the limits; the one
//! nearest the previous joints is tried first, and when the pass then cannot stay within the
//! limits (a limited C running out of travel, a tilt limit on one branch) the others are tried
//! in turn ([`MachineKinematics::inverse_all`]). The turn to another start is made in place on
//! the safe plane: at the end of the move before the pass when that is a rapid (or always, on
//! a machine with head axes), the rapid then leaving from the turned joints. When none carries
//! the pass, [`linearise_unwinding`] asks its hook for an unwind where the furthest start was
//! stopped (retract, turn on the safe plane, re-plunge; the planner builds and checks those
//! moves), and [`linearise_opt`] reports [`LineariseError::NoStart`]: the post itself never
//! inserts a move the planner has not checked.

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use super::kinematics::{Joints, KinematicsError, MachineKinematics};
use crate::geom::{Move, MoveKind, ToolPose, Toolpath};

/// A rotary jump (degrees) within the shortest step that only another branch or turn explains.
const LIMIT_JUMP_DEG: f64 = 90.0;

/// Interpolation parameters at which joint-space and part-frame motion are compared.
pub const CHECK_PARAMETERS: [f64; 7] = [0.125, 0.25, 0.375, 0.5, 0.625, 0.75, 0.875];

/// Options of [`linearise_opt`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LineariseOptions {
    /// Largest allowed deviation (mm) of the control point between joint-space and planned
    /// motion. Default 0.01.
    pub tolerance_mm: f64,
    /// The point whose deviation is bounded, this far up the axis from the tip (mm): the ball
    /// radius for a ball-end mill, whose cutting surface is the sphere around that point.
    /// Default 0 (the tip).
    #[serde(default)]
    pub control_point_mm: f64,
    /// Largest allowed tool-axis deviation (degrees). Default 0.1.
    pub angle_tolerance_deg: f64,
    /// The flutes reach this far above the control point (mm); their top is held within
    /// `tolerance_mm` too, and so is every point between (a point's deviation is affine in
    /// its height). Default 0: the control point alone, with the angle tolerance.
    #[serde(default)]
    pub flutes_above_control_mm: f64,
    /// Largest subdivision depth per move (the shortest step is `2^-max_depth` of the move).
    /// Default 24: where the axis passes the pole just where the relaxed inverse stops
    /// letting C stray, C turns half a turn while the axis moves by a few hundredths of a
    /// degree, and a move turning the axis by 50° needs steps of about 2⁻¹⁷ of it there (the
    /// bundled job's lifted links between blade passes); the walk doubles its step after each
    /// accepted one, so the depth costs only where it is needed.
    pub max_depth: u32,
}

impl Default for LineariseOptions {
    fn default() -> Self {
        LineariseOptions {
            tolerance_mm: 0.01,
            control_point_mm: 0.0,
            angle_tolerance_deg: 0.1,
            flutes_above_control_mm: 0.0,
            max_depth: 24,
        }
    }
}

impl LineariseOptions {
    /// Sets the tip tolerance (mm).
    pub fn with_tolerance_mm(mut self, v: f64) -> Self {
        self.tolerance_mm = v;
        self
    }
    /// Sets the control point's distance up the axis from the tip (mm).
    pub fn with_control_point_mm(mut self, v: f64) -> Self {
        self.control_point_mm = v;
        self
    }
    /// Sets the axis tolerance (degrees).
    pub fn with_angle_tolerance_deg(mut self, v: f64) -> Self {
        self.angle_tolerance_deg = v;
        self
    }
    /// Sets how far the flutes reach above the control point (mm).
    pub fn with_flutes_above_control_mm(mut self, v: f64) -> Self {
        self.flutes_above_control_mm = v;
        self
    }
    /// Sets the subdivision depth bound.
    pub fn with_max_depth(mut self, v: u32) -> Self {
        self.max_depth = v;
        self
    }
}

/// Errors of [`linearise`].
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum LineariseError {
    /// Inverse kinematics failed for move `move_index` (or a point inserted before it).
    #[error("move {move_index}: {source}")]
    Kinematics {
        /// Index of the move in the original toolpath.
        move_index: usize,
        /// The kinematic failure.
        #[source]
        source: KinematicsError,
    },
    /// The subdivision bound was hit before the deviation fell below tolerance.
    #[error("move {move_index}: deviation still above tolerance at subdivision depth {depth}")]
    DepthLimit {
        /// Index of the move in the original toolpath.
        move_index: usize,
        /// The depth bound.
        depth: u32,
    },
    /// The motion needs a limited rotary axis to go on past its limit (the inverse can only
    /// stay inside by jumping to another branch or turn).
    #[error(
        "move {move_index}: axis {axis} reaches {at_deg:.4}° and the motion needs it to go on, \
         but its limits are [{min_deg}°, {max_deg}°]"
    )]
    LimitReached {
        /// Index of the move in the original toolpath.
        move_index: usize,
        /// The limited axis nearest its limit.
        axis: super::kinematics::RotaryAxis,
        /// Where it stands at the last step that kept the tolerance, degrees.
        at_deg: f64,
        /// Its lower limit, degrees.
        min_deg: f64,
        /// Its upper limit, degrees.
        max_deg: f64,
    },
    /// The tool axis turns by 180° within one move: the planned interpolation is undefined.
    #[error("move {move_index}: tool axis reverses within the move")]
    AntipodalAxes {
        /// Index of the move in the original toolpath.
        move_index: usize,
    },
    /// No branch or turn of the rotary axes at a pass's start carries the whole pass within the
    /// limits, and no unwind (retract, turn, re-plunge) partway was made.
    #[error(
        "moves {first_move}..={last_move}: from none of the {tried} branches and turns of the \
         rotary axes at the pass's start can the pass be followed within the machine's limits and \
         the tolerance, and no unwind partway (retract along the axis, turn on the safe plane, \
         re-plunge) could be made before the stop: no cut pose there that the tool leaves clear \
         of the part, or this tool's moves are not unwound. From the nearest: {source}"
    )]
    NoStart {
        /// The pass's first move (a rapid, or the program's first).
        first_move: usize,
        /// The pass's last move.
        last_move: usize,
        /// How many starts were tried.
        tried: usize,
        /// What went wrong from the nearest start.
        #[source]
        source: Box<LineariseError>,
    },
    /// A pose or feed is not finite.
    #[error("move {move_index}: non-finite pose or feed")]
    NonFinite {
        /// Index of the move in the original toolpath.
        move_index: usize,
    },
    /// Tolerances must be finite and positive.
    #[error("invalid tolerance: {0}")]
    InvalidOptions(String),
}

/// Angle (radians) between two unit vectors, accurate for small and large angles.
pub fn angle_between(u: &Vector3<f64>, v: &Vector3<f64>) -> f64 {
    u.cross(v).norm().atan2(u.dot(v))
}

/// Angle (radians) above which two axes count as antipodal for [`slerp`].
const ANTIPODAL_SLACK: f64 = 1e-9;

/// Spherical linear interpolation of unit vectors; `None` when they are (nearly) antipodal.
pub fn slerp(u: &Vector3<f64>, v: &Vector3<f64>, t: f64) -> Option<Vector3<f64>> {
    let theta = angle_between(u, v);
    if std::f64::consts::PI - theta < ANTIPODAL_SLACK {
        return None;
    }
    let w = if theta < 1e-12 {
        u * (1.0 - t) + v * t
    } else {
        let s = theta.sin();
        u * (((1.0 - t) * theta).sin() / s) + v * ((t * theta).sin() / s)
    };
    Some(w.normalize())
}

/// The planned (part-frame) pose at parameter `t` of the segment `p0 → p1`: tip linear, axis
/// slerp.
pub fn interpolate_pose(p0: &ToolPose, p1: &ToolPose, t: f64) -> Option<ToolPose> {
    interpolate_pose_about(p0, p1, t, 0.0)
}

/// The planned pose at parameter `t` of `p0 → p1` when the point `control` up the axis from
/// the tip moves on a straight line: that point linear, axis slerp.
pub fn interpolate_pose_about(
    p0: &ToolPose,
    p1: &ToolPose,
    t: f64,
    control: f64,
) -> Option<ToolPose> {
    let axis = slerp(&p0.axis, &p1.axis, t)?;
    let point = |p: &ToolPose| p.tip + p.axis.into_inner() * control;
    let moving = point(p0) + (point(p1) - point(p0)) * t;
    Some(ToolPose {
        tip: moving - axis * control,
        axis: nalgebra::Unit::new_unchecked(axis),
    })
}

/// Largest deviation (tip mm, axis degrees) between joint-space interpolation `j0 → j1` and the
/// planned interpolation `p0 → p1`, over [`CHECK_PARAMETERS`].
pub fn segment_deviation<K: MachineKinematics + ?Sized>(
    kin: &K,
    p0: &ToolPose,
    j0: &Joints,
    p1: &ToolPose,
    j1: &Joints,
) -> Option<(f64, f64)> {
    segment_deviation_about(kin, p0, j0, p1, j1, 0.0)
}

/// [`segment_deviation`] of the point `control` up the axis from the tip, against the planned
/// motion that moves that point on a straight line.
pub fn segment_deviation_about<K: MachineKinematics + ?Sized>(
    kin: &K,
    p0: &ToolPose,
    j0: &Joints,
    p1: &ToolPose,
    j1: &Joints,
    control: f64,
) -> Option<(f64, f64)> {
    segment_deviation_over(kin, p0, j0, p1, j1, control, 0.0)
}

/// [`segment_deviation_about`] with the point deviation the larger of the control point's and
/// that of the point `above` it up the axis (the flutes' top).
fn segment_deviation_over<K: MachineKinematics + ?Sized>(
    kin: &K,
    p0: &ToolPose,
    j0: &Joints,
    p1: &ToolPose,
    j1: &Joints,
    control: f64,
    above: f64,
) -> Option<(f64, f64)> {
    let mut point_dev: f64 = 0.0;
    let mut ang_dev: f64 = 0.0;
    for &t in &CHECK_PARAMETERS {
        let planned = interpolate_pose_about(p0, p1, t, control)?;
        let actual = kin.forward(&j0.lerp(j1, t));
        for height in [control, control + above] {
            let point = |p: &ToolPose| p.tip + p.axis.into_inner() * height;
            point_dev = point_dev.max((point(&actual) - point(&planned)).norm());
            if above <= 0.0 {
                break;
            }
        }
        ang_dev = ang_dev.max(angle_between(&actual.axis, &planned.axis).to_degrees());
    }
    Some((point_dev, ang_dev))
}

/// [`linearise_opt`] with the given tolerances and the default depth bound.
pub fn linearise<K: MachineKinematics + ?Sized>(
    kin: &K,
    toolpath: &Toolpath,
    tolerance_mm: f64,
    angle_tolerance_deg: f64,
) -> Result<Vec<(Move, Joints)>, LineariseError> {
    let opts = LineariseOptions::default()
        .with_tolerance_mm(tolerance_mm)
        .with_angle_tolerance_deg(angle_tolerance_deg);
    linearise_opt(kin, toolpath, &opts)
}

/// Converts a toolpath into machine blocks: every original move with its joints, plus the
/// part-frame points inserted so that joint-space interpolation stays within tolerance (see
/// the module docs). Inserted moves carry the kind and feed of the move they subdivide.
pub fn linearise_opt<K: MachineKinematics + ?Sized>(
    kin: &K,
    toolpath: &Toolpath,
    opts: &LineariseOptions,
) -> Result<Vec<(Move, Joints)>, LineariseError> {
    Ok(linearise_unwinding(kin, toolpath, opts, &mut |_: &[Move], _, _| None)?.blocks)
}

/// Where a pass cannot be followed within the limits from any start, a hook may splice in
/// moves that give the rotaries a place to turn: given the moves, the pass's first move and
/// the furthest move any start reached before a limit stopped it, it returns a [`Splice`].
/// `None` leaves the pass to fail.
pub type UnwindHook<'a> = dyn FnMut(&[Move], usize, usize) -> Option<Splice> + 'a;

/// Moves an [`UnwindHook`] puts in: after move `after` (`pass start − 1 ≤ after < stopped`),
/// in place of the `replacing` moves that follow it (all inside the pass), with a rapid among
/// them (where a pass starts, so where the rotaries may turn in place). An unwind from a cut
/// (a retract to the safe plane, the rapids there and the re-plunge), a short link made a link
/// by way of the safe plane, or a stop on the safe plane partway along a rapid.
#[derive(Clone, Debug, PartialEq)]
pub struct Splice {
    /// The move the new ones follow.
    pub after: usize,
    /// How many of the moves after it they take the place of.
    pub replacing: usize,
    /// The new moves.
    pub moves: Vec<Move>,
}

/// What [`linearise_unwinding`] made of a toolpath.
#[derive(Clone, Debug, PartialEq)]
pub struct Unwound {
    /// The machine blocks, as [`linearise_opt`] returns them.
    pub blocks: Vec<(Move, Joints)>,
    /// The toolpath with the hook's moves inserted.
    pub moves: Vec<Move>,
    /// For each of `moves`, its index in the input toolpath; `None` for the hook's moves (the
    /// input's moves they replaced are not there).
    pub origin: Vec<Option<usize>>,
    /// Where the hook's moves went: after these moves (indices in `moves`), in order.
    pub inserted_after: Vec<usize>,
}

/// [`linearise_opt`] that asks `unwind` for moves to insert where a limit stops a pass from
/// every start, inserts them and goes on (see [`UnwindHook`]). An unwind from a cut starts a
/// new pass after the last; moves inserted before a pass split a rapid, and the hook bounds
/// how often it splits one.
pub fn linearise_unwinding<K: MachineKinematics + ?Sized>(
    kin: &K,
    toolpath: &Toolpath,
    opts: &LineariseOptions,
    unwind: &mut UnwindHook<'_>,
) -> Result<Unwound, LineariseError> {
    if !(opts.tolerance_mm.is_finite() && opts.tolerance_mm > 0.0) {
        return Err(LineariseError::InvalidOptions(
            "tolerance_mm must be finite and > 0".into(),
        ));
    }
    if !(opts.control_point_mm.is_finite() && opts.control_point_mm >= 0.0) {
        return Err(LineariseError::InvalidOptions(
            "control_point_mm must be finite and >= 0".into(),
        ));
    }
    if !(opts.flutes_above_control_mm.is_finite() && opts.flutes_above_control_mm >= 0.0) {
        return Err(LineariseError::InvalidOptions(
            "flutes_above_control_mm must be finite and >= 0".into(),
        ));
    }
    if !(opts.angle_tolerance_deg.is_finite() && opts.angle_tolerance_deg > 0.0) {
        return Err(LineariseError::InvalidOptions(
            "angle_tolerance_deg must be finite and > 0".into(),
        ));
    }
    // The flutes' top swings by the axis error times their length: half the tolerance there
    // is the axis's share too.
    let flute_axis_deg = if opts.flutes_above_control_mm > 0.0 {
        (opts.tolerance_mm / opts.flutes_above_control_mm).to_degrees()
    } else {
        f64::INFINITY
    };
    let budget = 0.5 * opts.angle_tolerance_deg.min(flute_axis_deg);
    for (i, mv) in toolpath.moves.iter().enumerate() {
        let finite = mv.feed.is_finite()
            && mv
                .pose
                .tip
                .iter()
                .chain(mv.pose.axis.iter())
                .all(|v| v.is_finite());
        if !finite {
            return Err(LineariseError::NonFinite { move_index: i });
        }
    }
    let mut moves = toolpath.moves.clone();
    let mut origin: Vec<Option<usize>> = (0..moves.len()).map(Some).collect();
    let mut inserted_after = Vec::new();
    let mut out: Vec<(Move, Joints)> = Vec::with_capacity(moves.len());
    let mut start = 0;
    'passes: while start < moves.len() {
        // A pass: a rapid (or the program's first move) and the feed moves up to the next
        // rapid. Where it starts the rotaries may take any branch or turn; the nearest is
        // tried first, the others when the pass cannot be held within the limits from it.
        let end = (start + 1..moves.len())
            .find(|&k| moves[k].kind == MoveKind::Rapid)
            .unwrap_or(moves.len());
        let kin_err = |source| LineariseError::Kinematics {
            move_index: start,
            source,
        };
        let previous = out.last().copied();
        // The alternatives are taken where the rotaries may turn freely. With head axes that
        // is the end of the move before the pass (on the safe plane, where turning in place
        // keeps the tip outside the part's reach), so that the rapid itself has room to
        // follow its motion; on a table machine the same where that move was a rapid (on the
        // safe plane too), else the pass's start.
        let turn_before =
            previous.is_some_and(|(m, _)| kin.has_head_axes() || m.kind == MoveKind::Rapid);
        let free_pose = match previous {
            Some((m, _)) if turn_before => m.pose,
            _ => moves[start].pose,
        };
        // `None`: where the nearest joints (or, with head axes, the planned motion) lead.
        let mut candidates: Vec<Option<Joints>> = vec![None];
        let mut first_error = None;
        // The furthest move any start reached before a limit stopped it, and that start's
        // blocks with where each move's blocks end (relative to the pass's first block): an
        // unwind before the stop keeps them up to its pose.
        let mut limit_stop: Option<usize> = None;
        let mut furthest: (Vec<(Move, Joints)>, Vec<usize>) = (Vec::new(), Vec::new());
        let mut ends = Vec::new();
        let kept = out.len();
        let mut tried = 0;
        while tried < candidates.len() {
            let candidate = candidates[tried];
            tried += 1;
            out.truncate(kept);
            let result = run_pass(
                kin,
                &moves,
                start,
                end,
                candidate.as_ref(),
                turn_before,
                opts,
                budget,
                &mut out,
                &mut ends,
            );
            let error = match result {
                Ok(()) => {
                    start = end;
                    continue 'passes;
                }
                // Not a matter of where the rotaries start: no other start can help.
                Err(
                    e @ (LineariseError::AntipodalAxes { .. } | LineariseError::NonFinite { .. }),
                ) => {
                    return Err(e);
                }
                Err(e) => e,
            };
            if let LineariseError::Kinematics {
                move_index,
                source: KinematicsError::OutOfLimits { .. } | KinematicsError::OutOfTravel { .. },
            }
            | LineariseError::LimitReached { move_index, .. } = error
                && limit_stop.is_none_or(|stop| move_index > stop)
            {
                limit_stop = Some(move_index);
                furthest = (
                    out[kept..].to_vec(),
                    ends.iter().map(|e| e - kept).collect(),
                );
            }
            if first_error.is_none() {
                first_error = Some(error);
                // Only now are the alternatives worth computing; the one the nearest start
                // already stood on is left out.
                let tried_joints = if turn_before {
                    previous.map(|(_, j)| j)
                } else {
                    out.get(kept).map(|&(_, j)| j)
                };
                let near = previous.map(|(_, j)| j);
                for j in kin
                    .inverse_all(&free_pose, near.as_ref())
                    .map_err(kin_err)?
                {
                    let same = tried_joints
                        .is_some_and(|t| (t.a - j.a).abs() < 1e-9 && (t.c - j.c).abs() < 1e-9);
                    if !same {
                        candidates.push(Some(j));
                    }
                }
            }
        }
        out.truncate(kept);
        if let Some(Splice {
            after: at,
            replacing,
            moves: inserted,
        }) = limit_stop.and_then(|stop| unwind(&moves, start, stop))
        {
            let valid = at + 1 >= start
                && limit_stop.is_some_and(|stop| at < stop)
                && at + replacing < end
                && inserted.iter().any(|m| m.kind == MoveKind::Rapid);
            if !valid {
                return Err(LineariseError::InvalidOptions(format!(
                    "moves inserted after move {at} do not lie inside the pass of moves \
                     {start}..{end} or have no rapid to turn on"
                )));
            }
            let count = inserted.len();
            moves.splice(at + 1..at + 1 + replacing, inserted);
            origin.splice(at + 1..at + 1 + replacing, std::iter::repeat_n(None, count));
            for u in &mut inserted_after {
                if *u > at {
                    *u = *u + count - replacing;
                }
            }
            inserted_after.push(at);
            if at <= start {
                // Before the pass or at its first move: the pass runs again from its start.
                continue 'passes;
            }
            // The furthest start's blocks up to the unwind's pose, then the retract; the
            // rapids on the safe plane start the next passes. (Should the retract itself not
            // go, the shortened pass is run again from its start.)
            let (blocks, block_ends) = furthest;
            out.extend_from_slice(&blocks[..block_ends[at - start]]);
            let retract = at + 1;
            let resumable = moves[retract].kind != MoveKind::Rapid;
            let resumed =
                out.last()
                    .copied()
                    .filter(|_| resumable)
                    .and_then(|(prev_move, prev_j)| {
                        let placed = out.len();
                        let j = march(
                            kin,
                            &prev_move.pose,
                            &prev_j,
                            &moves[retract],
                            retract,
                            opts,
                            budget,
                            &mut out,
                        )
                        .ok()?;
                        out.push((moves[retract], j));
                        let inside = out[placed..]
                            .iter()
                            .all(|(_, j)| kin.check_limits(j).is_ok());
                        inside.then_some(())
                    });
            let next_is_rapid = moves
                .get(retract + 1)
                .is_some_and(|m| m.kind == MoveKind::Rapid);
            match resumed {
                Some(()) if next_is_rapid => {
                    start = retract + 1;
                }
                _ => out.truncate(kept),
            }
            continue 'passes;
        }
        let source = first_error
            .map(Box::new)
            .ok_or(LineariseError::NonFinite { move_index: start })?;
        return Err(LineariseError::NoStart {
            first_move: start,
            last_move: end - 1,
            tried: candidates.len(),
            source,
        });
    }
    inserted_after.sort_unstable();
    Ok(Unwound {
        blocks: out,
        moves,
        origin,
        inserted_after,
    })
}

/// Linearises the pass `moves[start..end]` into `out`: the pass's first move placed, then each
/// feed move walked ([`march`]). With `turn_before` the machine first turns in place at the
/// end of the move before, to `first`, another branch or turn of that pose, if given; with
/// head axes the rapid then follows its planned motion, on a table machine it goes straight to
/// the nearest joints. Without, the rapid goes straight to `first` (`None`: the nearest). Every
/// block is checked against the limits and travel as it is made, so that an error names the
/// move where a limit stops the pass.
#[allow(clippy::too_many_arguments)]
fn run_pass<K: MachineKinematics + ?Sized>(
    kin: &K,
    moves: &[Move],
    start: usize,
    end: usize,
    first: Option<&Joints>,
    turn_before: bool,
    opts: &LineariseOptions,
    budget: f64,
    out: &mut Vec<(Move, Joints)>,
    ends: &mut Vec<usize>,
) -> Result<(), LineariseError> {
    ends.clear();
    let mv = &moves[start];
    let kin_err = |source| LineariseError::Kinematics {
        move_index: start,
        source,
    };
    let checked = |out: &[(Move, Joints)], from: usize, move_index: usize| {
        out[from..].iter().try_for_each(|(_, j)| {
            kin.check_limits(j)
                .map_err(|source| LineariseError::Kinematics { move_index, source })
        })
    };
    let placed = out.len();
    match out.last().copied() {
        Some((prev_move, prev_j)) if turn_before => {
            let from = match first {
                Some(j) => {
                    out.push((prev_move, *j));
                    *j
                }
                None => prev_j,
            };
            if kin.has_head_axes() {
                // A head swings the tool about its pivot: the joint path of a rapid is not
                // safe by itself, so the rapid follows its planned motion like a feed move.
                let arrived = march(kin, &prev_move.pose, &from, mv, start, opts, budget, out)?;
                out.push((*mv, arrived));
            } else {
                out.push((
                    *mv,
                    kin.inverse_relaxed(&mv.pose, &from, budget)
                        .map_err(kin_err)?,
                ));
            }
        }
        previous => {
            let joints = match (previous, first) {
                (_, Some(first)) => *first,
                (None, None) => kin.inverse(&mv.pose, None).map_err(kin_err)?,
                (Some((_, prev_j)), None) => kin
                    .inverse_relaxed(&mv.pose, &prev_j, budget)
                    .map_err(kin_err)?,
            };
            out.push((*mv, joints));
        }
    }
    checked(out, placed, start)?;
    ends.push(out.len());
    for (i, mv) in moves.iter().enumerate().take(end).skip(start + 1) {
        let &(prev_move, prev_j) = out
            .last()
            .ok_or(LineariseError::NonFinite { move_index: i })?;
        let placed = out.len();
        let j = march(kin, &prev_move.pose, &prev_j, mv, i, opts, budget, out)?;
        out.push((*mv, j));
        checked(out, placed, i)?;
        ends.push(out.len());
    }
    Ok(())
}

/// Walks the feed move `p0 → mv.pose` from joints `j0` in adaptive steps (see the module
/// docs), pushing the inserted blocks into `out`; returns the joints at `mv.pose`.
#[allow(clippy::too_many_arguments)]
fn march<K: MachineKinematics + ?Sized>(
    kin: &K,
    p0: &ToolPose,
    j0: &Joints,
    mv: &Move,
    move_index: usize,
    opts: &LineariseOptions,
    budget: f64,
    out: &mut Vec<(Move, Joints)>,
) -> Result<Joints, LineariseError> {
    let p1 = &mv.pose;
    let antipodal = LineariseError::AntipodalAxes { move_index };
    let min_dt = 0.5f64.powi(opts.max_depth.min(1000) as i32);
    let (mut t, mut dt) = (0.0f64, 1.0f64);
    let (mut cur_p, mut cur_j) = (*p0, *j0);
    loop {
        // Snap onto the move's end when the remaining piece is negligible.
        let t_next = if t + dt >= 1.0 - 1e-12 { 1.0 } else { t + dt };
        let p_next = if t_next == 1.0 {
            *p1
        } else {
            interpolate_pose_about(p0, p1, t_next, opts.control_point_mm)
                .ok_or(antipodal.clone())?
        };
        let j_next = kin
            .inverse_relaxed(&p_next, &cur_j, budget)
            .map_err(|source| LineariseError::Kinematics { move_index, source })?;
        let (point_dev, ang_dev) = segment_deviation_over(
            kin,
            &cur_p,
            &cur_j,
            &p_next,
            &j_next,
            opts.control_point_mm,
            opts.flutes_above_control_mm,
        )
        .ok_or(antipodal.clone())?;
        if point_dev <= opts.tolerance_mm && ang_dev <= opts.angle_tolerance_deg {
            if t_next == 1.0 {
                return Ok(j_next);
            }
            out.push((
                Move {
                    pose: p_next,
                    ..*mv
                },
                j_next,
            ));
            (t, cur_p, cur_j) = (t_next, p_next, j_next);
            dt *= 2.0;
        } else if dt <= min_dt {
            // A step that cannot be made short enough while a rotary axis jumps is the
            // inverse keeping a limited axis inside its travel by another branch or turn (the
            // motion itself turns the axes steadily, and the relaxed inverse holds them near
            // the singular cone): the limit is what stops the pass, and saying so lets an
            // unwind help.
            let jumps = [(j_next.a - cur_j.a).abs(), (j_next.c - cur_j.c).abs()];
            if jumps.iter().any(|&d| d > LIMIT_JUMP_DEG) {
                let values = [cur_j.a, cur_j.c];
                let nearest = kin
                    .rotary_axes()
                    .into_iter()
                    .zip(kin.rotary_limits())
                    .zip(values)
                    .filter_map(|((axis, limits), value)| {
                        let (lo, hi) = limits?;
                        Some(((value - lo).min(hi - value), axis, value, lo, hi))
                    })
                    .min_by(|u, v| u.0.total_cmp(&v.0));
                if let Some((_, axis, at_deg, min_deg, max_deg)) = nearest {
                    return Err(LineariseError::LimitReached {
                        move_index,
                        axis,
                        at_deg,
                        min_deg,
                        max_deg,
                    });
                }
            }
            return Err(LineariseError::DepthLimit {
                move_index,
                depth: opts.max_depth,
            });
        } else {
            dt *= 0.5;
        }
    }
}
