//! The rotary-chain kinematics of every shipped machine: round trips to 1e-9 everywhere
//! (including inside and around the singular cone and on the limits), agreement with the closed
//! forms, the limits and travel refused by name.

use nalgebra::{Point3, Rotation3, Unit, Vector3};

use super::{angle, dir, forward_ref, pose};
use crate::post::machine_file::{MachineDefinition, SHIPPED};
use crate::post::{
    AxisSide, Joints, KinematicsError, KinematicsKind, MachineKinematics, RotaryAxis, RotaryChain,
    RotaryJoint, TableTableAC, ToolCentrePoint,
};

/// Every shipped machine with a part placed off the pivot and a 100 mm tool mounted.
fn shipped() -> Vec<(&'static str, RotaryChain)> {
    SHIPPED
        .iter()
        .map(|(name, text)| {
            let d = MachineDefinition::parse(text, name).expect(name);
            (*name, d.chain_for(Vector3::new(3.0, -2.0, 40.0), 100.0))
        })
        .collect()
}

/// Axes over the whole sphere the machines reach, and tips around the part.
fn sample_poses() -> Vec<crate::geom::ToolPose> {
    let mut poses = Vec::new();
    for (i, tilt) in [
        0.0, 1e-7, 1e-4, 0.01, 0.05, 0.08, 0.12, 3.0, 30.0, 60.0, 89.0, 100.0,
    ]
    .iter()
    .enumerate()
    {
        for k in 0..7 {
            let azimuth = -170.0 + 53.0 * k as f64 + i as f64;
            let tip = [
                10.0 * (k as f64).cos(),
                -7.0 + i as f64,
                5.0 + 3.0 * k as f64,
            ];
            poses.push(pose(tip, dir(*tilt, azimuth)));
        }
    }
    poses
}

/// Asserts the round trip within 1e-9; returns the larger of the tip (mm) and axis (rad)
/// errors.
fn close(kin: &dyn MachineKinematics, p: &crate::geom::ToolPose, j: &Joints, what: &str) -> f64 {
    let back = kin.forward(j);
    let tip = (back.tip - p.tip).norm();
    let axis = angle(&back.axis, &p.axis);
    assert!(
        tip < 1e-9 && axis < 1e-9,
        "{what}: tip {tip:e}, axis {axis:e} at {j:?}"
    );
    tip.max(axis)
}

/// forward(inverse(pose)) = pose to 1e-9 on every kind, in joint and TCP output, with and
/// without previous joints (the continuity branch), and the relaxed inverse keeps the tip
/// exact and the axis within its allowance near the singular cone.
#[test]
fn every_kind_round_trips_its_poses() {
    for (name, chain) in shipped() {
        let tcp = ToolCentrePoint(&chain);
        let mut worst: f64 = 0.0;
        for kin in [&chain as &dyn MachineKinematics, &tcp] {
            let mut previous: Option<Joints> = None;
            for p in sample_poses() {
                // The head-table machines tilt their head only so far.
                let Ok(j) = kin.inverse(&p, previous.as_ref()) else {
                    assert!(name.starts_with("head"), "{name}: {p:?} refused");
                    continue;
                };
                worst = worst.max(close(kin, &p, &j, name));
                kin.check_limits(&j)
                    .unwrap_or_else(|e| panic!("{name}: {e}"));
                for alternative in kin.inverse_all(&p, previous.as_ref()).unwrap() {
                    worst = worst.max(close(kin, &p, &alternative, name));
                    kin.check_limits(&alternative).unwrap();
                }
                let preferred = Joints {
                    a: j.a + 0.3,
                    c: j.c - 40.0,
                    ..j
                };
                let relaxed = kin.inverse_relaxed(&p, &preferred, 0.05).unwrap();
                let back = kin.forward(&relaxed);
                assert!(
                    (back.tip - p.tip).norm() < 1e-9,
                    "{name}: relaxed tip moved"
                );
                assert!(
                    angle(&back.axis, &p.axis).to_degrees() <= 0.05 + 1e-9,
                    "{name}: relaxed axis off by {}",
                    angle(&back.axis, &p.axis).to_degrees()
                );
                previous = Some(j);
            }
        }
        eprintln!("{name}: worst round trip {worst:.1e} (mm or rad)");
    }
}

/// Close to the free axis the relaxed inverse holds the free angle where it was (inside the
/// cone), instead of the exact inverse's half-turn.
#[test]
fn the_free_axis_is_held_inside_the_singular_cone() {
    for (name, chain) in shipped() {
        let free_is_second = chain.kind != KinematicsKind::HeadHead;
        let near = pose([1.0, 2.0, 3.0], dir(0.02, 77.0));
        let exact = chain.inverse(&near, None).unwrap();
        let held = if free_is_second {
            Joints {
                c: exact.c + 120.0,
                ..exact
            }
        } else {
            Joints {
                a: exact.a + 120.0,
                ..exact
            }
        };
        let j = chain.inverse_relaxed(&near, &held, 0.05).unwrap();
        let (free, wanted) = if free_is_second {
            (j.c, held.c)
        } else {
            (j.a, held.a)
        };
        assert!(
            (free - wanted).abs() < 1e-9,
            "{name}: free axis moved to {free}"
        );
    }
}

/// The table-table A/C machine file is the closed-form A/C machine: the same joints.
#[test]
fn the_ac_trunnion_agrees_with_the_closed_form() {
    let o = Vector3::new(3.0, -2.0, 40.0);
    let (_, text) = SHIPPED[0];
    let chain = MachineDefinition::parse(text, "trunnion-ac")
        .unwrap()
        .chain_for(o, 100.0);
    let closed = TableTableAC::new(o);
    let mut prev_chain = None;
    let mut prev_closed = None;
    for p in sample_poses() {
        let a = chain.inverse(&p, prev_chain.as_ref()).unwrap();
        let b = closed.inverse(&p, prev_closed.as_ref()).unwrap();
        for (u, v) in [(a.x, b.x), (a.y, b.y), (a.z, b.z), (a.a, b.a), (a.c, b.c)] {
            assert!((u - v).abs() < 1e-9, "{a:?} vs {b:?}");
        }
        let (tip, axis) = forward_ref(&o, &a);
        assert!((tip - p.tip).norm() < 1e-9 && angle(&axis, &p.axis) < 1e-9);
        (prev_chain, prev_closed) = (Some(a), Some(b));
    }
}

/// Closed forms of the head kinematics: the tip `head_length` below the pivot, turned by the
/// head; with B = 90° on the B head the tool lies along +X and the pivot sits `L` beyond the
/// tip along it; the C/A fork at C = 90°, A = 90° points the tool along +X too.
#[test]
fn head_machines_carry_the_tool_length_in_their_linear_axes() {
    let chains = shipped();
    let get = |name: &str| chains.iter().find(|(n, _)| *n == name).unwrap().1.clone();
    let b_head = get("head-table-bc");
    let l = b_head.head_length;
    assert_eq!(l, 250.0);
    let tip = Point3::new(1.0, 2.0, 3.0);
    let j = b_head
        .inverse(&pose([1.0, 2.0, 3.0], [1.0, 0.0, 0.0]), None)
        .unwrap();
    assert!((j.a - 90.0).abs() < 1e-9 && j.c.abs() < 1e-9, "{j:?}");
    let o = b_head.part_origin_in_table;
    let expected = tip.coords + o + Vector3::new(l, 0.0, 0.0);
    assert!((j.xyz() - expected).norm() < 1e-9, "{j:?} vs {expected}");

    let fork = get("head-head");
    let j = Joints {
        x: 0.0,
        y: 0.0,
        z: 0.0,
        a: 90.0,
        c: 90.0,
    };
    // R_z(90°) R_x(90°) ẑ = R_z(90°) (0, −1, 0) = (1, 0, 0).
    let p = fork.forward(&j);
    assert!(angle(&p.axis, &Vector3::x()) < 1e-12, "{:?}", p.axis);
    let expected = -Vector3::x() * fork.head_length - fork.part_origin_in_table;
    assert!((p.tip.coords - expected).norm() < 1e-9, "{:?}", p.tip);
}

/// The B/C trunnion's axes do not meet (0.8 mm apart): a part point is turned about the real
/// lines, checked against rotations written out with nalgebra.
#[test]
fn offset_axes_turn_about_their_own_lines() {
    let chains = shipped();
    let chain = chains
        .iter()
        .find(|(n, _)| *n == "trunnion-bc")
        .unwrap()
        .1
        .clone();
    let j = Joints {
        x: 12.0,
        y: -4.0,
        z: 30.0,
        a: 35.0,
        c: -70.0,
    };
    let q_b = Vector3::new(0.8, 0.0, -60.0);
    let rb = Rotation3::from_axis_angle(&Vector3::y_axis(), 35f64.to_radians());
    let rc = Rotation3::from_axis_angle(&Vector3::z_axis(), -70f64.to_radians());
    // machine = q_b + R_b(R_c(p + o) − q_b)  ⇒  p = R_c⁻¹(q_b + R_b⁻¹(m − q_b)) − o.
    let m = j.xyz();
    let p = rc.inverse() * (q_b + rb.inverse() * (m - q_b)) - chain.part_origin_in_table;
    let back = chain.forward(&j);
    assert!((back.tip.coords - p).norm() < 1e-9);
    assert!(angle(&back.axis, &(rc.inverse() * (rb.inverse() * Vector3::z()))) < 1e-12);
}

/// A pose beyond a tilt limit is refused naming the axis; beyond the travel naming X, Y or Z.
#[test]
fn limits_and_travel_are_refused_by_name() {
    let chains = shipped();
    let b_head = chains
        .iter()
        .find(|(n, _)| *n == "head-table-bc")
        .unwrap()
        .1
        .clone();
    let e = b_head
        .inverse(&pose([0.0, 0.0, 0.0], dir(120.0, 0.0)), None)
        .unwrap_err();
    assert!(
        matches!(
            e,
            KinematicsError::OutOfLimits {
                axis: RotaryAxis::B,
                ..
            }
        ),
        "{e}"
    );
    // Exactly on the limit is inside.
    let on = b_head
        .inverse(&pose([0.0, 0.0, 0.0], dir(110.0, 90.0)), None)
        .unwrap();
    assert!((on.a.abs() - 110.0).abs() < 1e-9, "{on:?}");
    let far = b_head
        .inverse(&pose([2000.0, 0.0, 0.0], [0.0, 0.0, 1.0]), None)
        .unwrap();
    let e = b_head.check_limits(&far).unwrap_err();
    assert!(
        matches!(e, KinematicsError::OutOfTravel { axis: 'X', .. }),
        "{e}"
    );
}

/// A nutating head (B at 45° between Y and Z over a C table) reaches only a cone of axes: one
/// outside it is refused as unreachable, one inside round-trips.
#[test]
fn a_nutating_head_refuses_what_it_cannot_reach() {
    let head = RotaryChain {
        kind: KinematicsKind::HeadTableBc,
        first: RotaryJoint {
            letter: RotaryAxis::B,
            side: AxisSide::Head,
            direction: Unit::new_normalize(Vector3::new(0.0, 1.0, 1.0)),
            point: Vector3::zeros(),
            limits_deg: None,
        },
        second: RotaryJoint {
            letter: RotaryAxis::C,
            side: AxisSide::Table,
            direction: Vector3::z_axis(),
            point: Vector3::zeros(),
            limits_deg: None,
        },
        part_origin_in_table: Vector3::zeros(),
        head_length: 200.0,
        pivot_length: 100.0,
        travel: None,
        singular_tolerance_deg: 0.05,
        name: "nutating".into(),
    };
    head.validate().unwrap();
    // The spindle turned about (0, 1, 1)/√2 sweeps a cone of half-angle 45° about it, so
    // the tool reaches at most 90° from +Z.
    let e = head
        .inverse(&pose([0.0; 3], dir(120.0, 10.0)), None)
        .unwrap_err();
    assert!(matches!(e, KinematicsError::Unreachable { .. }), "{e}");
    let p = pose([1.0, 2.0, 3.0], dir(70.0, 10.0));
    let j = head.inverse(&p, None).unwrap();
    let _ = close(&head, &p, &j, "nutating");
}

/// The verifier's own forward kinematics of every shipped machine (Rodrigues' formula over
/// the file's axes) and the post's (nalgebra rotations in `post::chain`) agree on joints
/// all over the travel, in joint and in TCP programs: two implementations, one answer.
#[test]
fn the_verifier_and_the_post_agree_on_every_shipped_machine() {
    use crate::verify::{ChainModel, MachineModel, ModelAxis};
    for (name, text) in SHIPPED {
        let d = MachineDefinition::parse(text, name).unwrap();
        let chain = d.chain_for(Vector3::new(-4.0, 6.0, 35.0), 90.0);
        for tcp in [false, true] {
            let axis = |j: &RotaryJoint| ModelAxis {
                letter: j.letter.to_string().chars().next().unwrap(),
                on_table: j.side == AxisSide::Table,
                direction: j.direction.into_inner(),
                point: j.point,
            };
            let model = MachineModel::Chain(ChainModel {
                axes: [axis(&chain.first), axis(&chain.second)],
                part_origin_in_table: chain.part_origin_in_table,
                head_lengths: vec![(5, chain.head_length)],
                tcp,
                tcp_in_program: true,
                conversational: false,
            });
            for k in 0..40 {
                let t = k as f64;
                let j = Joints {
                    x: 30.0 * (0.7 * t).sin(),
                    y: -20.0 + t,
                    z: 50.0 * (0.3 * t).cos(),
                    a: -100.0 + 5.0 * t,
                    c: 400.0 - 19.0 * t,
                };
                let ours = model.program_pose(&[j.x, j.y, j.z, j.a, j.c], Some(5));
                let theirs = if tcp {
                    ToolCentrePoint(&chain).forward(&j)
                } else {
                    chain.forward(&j)
                };
                assert!(
                    (ours.tip - theirs.tip).norm() < 1e-9,
                    "{name} tcp {tcp}: {:?} vs {:?}",
                    ours.tip,
                    theirs.tip
                );
                assert!((ours.axis.into_inner() - theirs.axis.into_inner()).norm() < 1e-12);
            }
        }
    }
}
