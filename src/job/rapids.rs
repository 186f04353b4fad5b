//! Rapids that turn the tool axis, as the control moves them.
//!
//! A rapid is posted as `G0`, and the control interpolates its joints linearly; when the axis
//! turns, the tip then follows a curve in the part frame (on a table-table machine, an arc
//! about the rotary axes), not the chord between the rapid's ends. Everything that reads the
//! CL data as straight moves — the planning stock's removal, the stock run's test for rapids
//! through material, the split of rapids that enter the rest into fed moves — would see the
//! chord, which can cut through the part: on a large impeller from its bar stock, a rapid
//! between two safe-plane poses whose chord crossed the rest was fed along that chord, and
//! the posted move went through the part. So each turning rapid is split into rapids of at
//! most `max_turn_deg` of rotary motion each, at poses on the joint path (forward kinematics
//! of the interpolated joints). A step's chord then stays within the sagitta
//! R·(1 − cos(θ/2)) of the real path, R the tip's distance from the rotary axes.

use crate::geom::{Move, MoveKind, Toolpath, angle_between};
use crate::post::{Joints, MachineKinematics};

/// Motion of each rotary axis in one step of a split rapid in a plan, degrees: the axis turns
/// at most twice that, and at 300 mm from the rotary axes a step's chord keeps within 0.2 mm
/// of the path the control takes (rapids run at the safe distance, 20 mm beyond the part's
/// reach).
pub const MAX_RAPID_TURN_DEG: f64 = 2.0;

/// Splits every rapid of `path` that turns the axis into steps of at most `max_turn_deg` of
/// rotary motion along the joint path, with the joints chosen as the post chooses them (the
/// nearest branch to the move before); returns how many rapids were split. `from` is the move
/// the tool makes before the path's first (where the operation or layer before left it), so
/// the rapid from there is split too: the first move of an operation is a rapid on the safe
/// plane from the last one's axis to its own. A pose the kinematics cannot reach is left as it
/// is (the post refuses it with its own error).
pub fn split_turning_rapids(
    path: &mut Toolpath,
    from: Option<&Move>,
    kinematics: &dyn MachineKinematics,
    max_turn_deg: f64,
) -> usize {
    let step = max_turn_deg.max(1e-3);
    if kinematics.has_head_axes() {
        return split_along_plan(path, from, step);
    }
    let mut out = Vec::with_capacity(path.moves.len());
    let mut previous: Option<(Move, Joints)> = from.and_then(|m| {
        kinematics
            .inverse(&m.pose, None)
            .ok()
            .map(|joints| (*m, joints))
    });
    let mut split = 0;
    for m in &path.moves {
        let joints = kinematics
            .inverse(&m.pose, previous.as_ref().map(|(_, j)| j))
            .ok();
        if let (Some((from, j0)), Some(j1)) = (&previous, joints)
            && m.kind == MoveKind::Rapid
            && angle_between(&from.pose.axis.into_inner(), &m.pose.axis.into_inner()) > 1e-9
        {
            let turn = (j1.a - j0.a).abs().max((j1.c - j0.c).abs());
            let steps = (turn / step).ceil().max(1.0) as usize;
            for s in 1..steps {
                let pose = kinematics.forward(&j0.lerp(&j1, s as f64 / steps as f64));
                out.push(Move { pose, ..*m });
            }
            split += usize::from(steps > 1);
        }
        out.push(*m);
        previous = joints.map(|j| (*m, j));
    }
    path.moves = out;
    split
}

/// [`split_turning_rapids`] on a machine with head axes, whose post drives every rapid along
/// its planned motion (a head would swing the tool about its pivot): the turning rapids are
/// split along that motion (control point straight, axis by slerp) into steps of at most `step`
/// degrees of axis turn.
fn split_along_plan(path: &mut Toolpath, from: Option<&Move>, step: f64) -> usize {
    let mut out = Vec::with_capacity(path.moves.len());
    let mut previous = from.copied();
    let mut split = 0;
    for m in &path.moves {
        if let Some(p) = previous
            && m.kind == MoveKind::Rapid
        {
            let turn =
                angle_between(&p.pose.axis.into_inner(), &m.pose.axis.into_inner()).to_degrees();
            let steps = (turn / step).ceil().max(1.0) as usize;
            for s in 1..steps {
                if let Some(pose) = crate::post::linearise::interpolate_pose(
                    &p.pose,
                    &m.pose,
                    s as f64 / steps as f64,
                ) {
                    out.push(Move { pose, ..*m });
                }
            }
            split += usize::from(steps > 1);
        }
        out.push(*m);
        previous = Some(*m);
    }
    path.moves = out;
    split
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::{Direction, Point3, ToolPose, Vector3};
    use crate::post::TableTableAC;

    fn pose(tip: Point3, axis: Vector3) -> ToolPose {
        ToolPose {
            tip,
            axis: Direction::new_normalize(axis),
        }
    }

    /// A rapid from 100 mm above the pivot along +Z to 100 mm from it along +X, the tool turning
    /// with it: the table turns the part under a fixed tip, so every split pose stays 100 mm
    /// from the pivot (the chord's middle is only 70.7 mm away); each step moves each rotary
    /// axis at most 5°, so the axis turns at most 10° and the step's chord keeps within the
    /// sagitta 100·(1 − cos 5°).
    #[test]
    fn a_turning_rapid_follows_the_joint_path() {
        let machine = TableTableAC::new(Vector3::zeros());
        let pivot = machine.forward(&Joints::default()).tip;
        let turned = machine.forward(&Joints {
            a: 30.0,
            c: 40.0,
            ..Default::default()
        });
        assert!((turned.tip - pivot).norm() < 1e-9, "the pivot is fixed");
        let start = pose(pivot + Vector3::z() * 100.0, Vector3::z());
        let end = pose(pivot + Vector3::x() * 100.0, Vector3::x());
        let mut path = Toolpath {
            tool_id: 1,
            moves: [
                (start, MoveKind::Retract),
                (end, MoveKind::Rapid),
                (
                    pose(end.tip - Vector3::x() * 20.0, Vector3::x()),
                    MoveKind::Rapid,
                ),
            ]
            .map(|(pose, kind)| Move {
                pose,
                kind,
                feed: 0.0,
            })
            .to_vec(),
        };
        let whole = path.clone();
        assert_eq!(split_turning_rapids(&mut path, None, &machine, 5.0), 1);
        let moves = &path.moves;
        assert!(moves.len() >= 2 + 90 / 5, "{}", moves.len());
        assert_eq!(moves.first().map(|m| m.pose), Some(start));
        // The straight plunge along the axis that follows is left alone.
        assert_eq!(moves[moves.len() - 2].pose, end);
        let sagitta = 100.0 * (1.0 - 5.0f64.to_radians().cos());
        for w in moves[..moves.len() - 1].windows(2) {
            assert!(((w[1].pose.tip - pivot).norm() - 100.0).abs() < 1e-9);
            assert!(
                angle_between(&w[0].pose.axis.into_inner(), &w[1].pose.axis.into_inner())
                    <= 10.0f64.to_radians() + 1e-9
            );
            let middle = Point3::from((w[0].pose.tip.coords + w[1].pose.tip.coords) * 0.5);
            assert!((middle - pivot).norm() >= 100.0 - sagitta - 1e-9);
            assert_eq!(w[1].kind, MoveKind::Rapid);
        }
        // The same rapid as the first move of a path that starts where another left the tool
        // (an operation or a layer after the one before): split the same way from `from`.
        let mut rest = Toolpath {
            tool_id: 1,
            moves: whole.moves[1..].to_vec(),
        };
        assert_eq!(
            split_turning_rapids(&mut rest, Some(&whole.moves[0]), &machine, 5.0),
            1
        );
        assert_eq!(rest.moves, path.moves[1..].to_vec());
        // Without it the first move is left as its chord.
        let mut alone = Toolpath {
            tool_id: 1,
            moves: whole.moves[1..].to_vec(),
        };
        assert_eq!(split_turning_rapids(&mut alone, None, &machine, 5.0), 0);
    }
}
