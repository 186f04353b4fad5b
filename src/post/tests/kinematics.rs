//! Kinematics: closed forms, round trips, branches, singularity, limits.

use nalgebra::{Rotation3, Vector3};
use proptest::prelude::*;

use super::{dir, forward_ref, pose};
use crate::geom::ToolPose;
use crate::post::{Joints, KinematicsError, MachineKinematics, RotaryAxis, TableTableAC};

const EPS: f64 = 1e-9;

fn machine() -> TableTableAC {
    TableTableAC::new(Vector3::new(12.5, -30.0, 45.0))
}

/// forward(inverse(p)) == p to `EPS`, also checked with the independent forward map, and the
/// rotation really takes the axis to +Z.
fn assert_round_trip(kin: &TableTableAC, p: &ToolPose, prev: Option<&Joints>) -> Joints {
    let j = kin.inverse(p, prev).unwrap();
    kin.check_limits(&j).unwrap();
    let q = kin.forward(&j);
    assert!(
        (q.tip - p.tip).norm() <= EPS,
        "tip {:?} vs {:?}",
        q.tip,
        p.tip
    );
    assert!(
        (q.axis.into_inner() - p.axis.into_inner()).amax() <= EPS,
        "axis {q:?} vs {p:?}"
    );
    let (tip_ref, axis_ref) = forward_ref(&kin.part_origin_in_table, &j);
    assert!((tip_ref - p.tip).norm() <= EPS);
    assert!((axis_ref - p.axis.into_inner()).amax() <= EPS);
    let r = Rotation3::from_axis_angle(&Vector3::x_axis(), j.a.to_radians())
        * Rotation3::from_axis_angle(&Vector3::z_axis(), j.c.to_radians());
    assert!((r * p.axis.into_inner() - Vector3::z()).amax() <= EPS);
    j
}

fn close(u: f64, v: f64) -> bool {
    (u - v).abs() <= 1e-9
}

#[test]
fn closed_form_cases() {
    let kin = TableTableAC::default();
    let s30 = 30f64.to_radians().sin();
    let c30 = 30f64.to_radians().cos();
    let h = 0.5f64.sqrt();
    let cases: [([f64; 3], f64, f64); 7] = [
        ([0.0, s30, c30], 30.0, 0.0),
        ([1.0, 0.0, 0.0], 90.0, 90.0),
        ([-1.0, 0.0, 0.0], 90.0, -90.0),
        ([0.0, -1.0, 0.0], 90.0, 180.0),
        ([0.5, 0.5, h], 45.0, 45.0),
        ([c30, 0.0, -s30], 120.0, 90.0),
        ([0.0, 0.0, 1.0], 0.0, 0.0),
    ];
    for (k, a, c) in cases {
        let j = kin.inverse(&pose([0.0; 3], k), None).unwrap();
        assert!(
            close(j.a, a) && close(j.c, c),
            "{k:?}: got a={} c={}",
            j.a,
            j.c
        );
    }
}

#[test]
fn closed_form_machine_position() {
    // Part origin 10 mm along table +X; axis (1,0,0) ⇒ A = 90, C = 90. C turns +X to +Y, then
    // A turns +Y to +Z: the tip (part origin) sits at machine (0, 0, 10).
    let kin = TableTableAC::new(Vector3::new(10.0, 0.0, 0.0));
    let j = kin.inverse(&pose([0.0; 3], [1.0, 0.0, 0.0]), None).unwrap();
    assert!(close(j.a, 90.0) && close(j.c, 90.0));
    assert!((j.xyz() - Vector3::new(0.0, 0.0, 10.0)).amax() <= 1e-12);
    // Axis +Z: no rotation, machine = part + o.
    let j = kin
        .inverse(&pose([1.0, 2.0, 3.0], [0.0, 0.0, 1.0]), None)
        .unwrap();
    assert_eq!((j.a, j.c), (0.0, 0.0));
    assert!((j.xyz() - Vector3::new(11.0, 2.0, 3.0)).amax() <= 1e-12);
}

#[test]
fn second_branch_is_the_same_pose() {
    let kin = machine();
    let p = pose([3.0, -4.0, 5.0], dir(40.0, 70.0));
    let j = kin.inverse(&p, None).unwrap();
    assert!(j.a > 0.0);
    // A previous joint state near the other branch selects it.
    let prev = Joints {
        a: -35.0,
        c: 245.0,
        ..j
    };
    let j2 = assert_round_trip(&kin, &p, Some(&prev));
    assert!(close(j2.a, -j.a) && close(j2.c, j.c + 180.0), "{j2:?}");
}

#[test]
fn hand_picked_round_trips() {
    let kin = machine();
    let tip = [17.0, -8.0, 33.0];
    let mut axes: Vec<[f64; 3]> = vec![
        [0.0, 0.0, 1.0],
        [1e-7, 0.0, 1.0],
        [0.0, -1e-7, 1.0],
        dir(1e-9, 33.0),
        dir(1e-9, -147.0),
        dir(1e-7f64.to_degrees(), 200.0),
        dir(120.0, 0.0),
        dir(120.0, -90.0),
        dir(120.0, 123.0),
        dir(119.999_999_999, 45.0),
    ];
    for sx in [-1.0, 1.0] {
        for sy in [-1.0, 1.0] {
            for sz in [-1.0, 1.0] {
                axes.push([sx * 0.5, sy * 0.6, sz * 0.3]);
            }
        }
    }
    let prevs = [
        None,
        Some(Joints {
            a: 10.0,
            c: 725.0,
            ..Joints::default()
        }),
        Some(Joints {
            a: -90.0,
            c: -400.0,
            ..Joints::default()
        }),
    ];
    for k in axes {
        for prev in &prevs {
            assert_round_trip(&kin, &pose(tip, k), prev.as_ref());
        }
    }
}

#[test]
fn singular_pose_keeps_previous_c() {
    let kin = machine();
    let p = pose([1.0, 2.0, 3.0], [0.0, 0.0, 1.0]);
    let prev = Joints {
        a: -3.0,
        c: 417.25,
        ..Joints::default()
    };
    let j = assert_round_trip(&kin, &p, Some(&prev));
    assert_eq!(j.c, 417.25);
    assert_eq!(j.a, 0.0);
    assert!(j.a.is_sign_positive());
    // Without previous: a = 0, c = 0, no negative zero, no NaN.
    let j = kin
        .inverse(&pose([0.0; 3], [-0.0, -0.0, 1.0]), None)
        .unwrap();
    assert!(j.is_finite());
    assert!(j.a.is_sign_positive() && j.c.is_sign_positive());
}

#[test]
fn sweep_through_the_pole_is_continuous() {
    // Axis sweeps in the YZ plane from tilt −20° through +Z (exactly) to +20°.
    let kin = machine();
    let mut prev: Option<Joints> = None;
    let mut seen_pole = false;
    for i in -40..=40 {
        let t = f64::from(i) * 0.5;
        seen_pole |= i == 0;
        let p = pose(
            [5.0, 6.0, 7.0],
            [0.0, t.to_radians().sin(), t.to_radians().cos()],
        );
        let j = assert_round_trip(&kin, &p, prev.as_ref());
        if let Some(q) = prev {
            assert!((j.c - q.c).abs() < 1e-9, "C jumped {} -> {}", q.c, j.c);
            assert!(
                (j.a - q.a).abs() <= 0.5 + 1e-9,
                "A jumped {} -> {}",
                q.a,
                j.a
            );
        }
        prev = Some(j);
    }
    assert!(seen_pole);
    // Started at (a = 20, c = 180), ends at (a = −20, c = 180): tilt changed sign, C stayed.
    let j = prev.unwrap();
    assert!(close(j.a, -20.0) && close(j.c, 180.0), "{j:?}");
}

#[test]
fn a_out_of_limits_names_axis_a() {
    let kin = machine().with_a_limits(-120.0, 120.0);
    let err = kin
        .inverse(&pose([0.0; 3], dir(130.0, 20.0)), None)
        .unwrap_err();
    match err {
        KinematicsError::OutOfLimits {
            axis, value_deg, ..
        } => {
            assert_eq!(axis, RotaryAxis::A);
            assert!((value_deg - 130.0).abs() < 1e-9);
        }
        e => panic!("unexpected {e:?}"),
    }
    assert!(err.to_string().contains("axis A"));
}

#[test]
fn c_out_of_limits_names_axis_c() {
    // Needs c = −90 (or the flipped branch c = 90): both outside [10, 80].
    let kin = machine().with_c_limits(Some((10.0, 80.0)));
    let err = kin
        .inverse(&pose([0.0; 3], dir(30.0, -90.0)), None)
        .unwrap_err();
    assert!(
        matches!(
            err,
            KinematicsError::OutOfLimits {
                axis: RotaryAxis::C,
                ..
            }
        ),
        "{err:?}"
    );
    // A wrap inside the limits is found: c = −300 ≡ 60.
    let j = kin
        .inverse(&pose([0.0; 3], dir(30.0, -300.0)), None)
        .unwrap();
    assert!(close(j.c, 60.0));
}

#[test]
fn limited_c_picks_a_wrap_inside_the_limits() {
    let kin = machine().with_c_limits(Some((-360.0, 360.0)));
    let prev = Joints {
        a: 45.0,
        c: 350.0,
        ..Joints::default()
    };
    let j = assert_round_trip(&kin, &pose([1.0; 3], dir(45.0, 370.0)), Some(&prev));
    assert!((-360.0..=360.0).contains(&j.c), "{j:?}");
}

#[test]
fn continuous_c_unwraps_past_360() {
    let kin = machine();
    let mut prev: Option<Joints> = None;
    for i in 0..=72 {
        let az = f64::from(i) * 10.0;
        let j = assert_round_trip(&kin, &pose([20.0, 0.0, 5.0], dir(45.0, az)), prev.as_ref());
        if let Some(q) = prev {
            assert!((j.c - q.c - 10.0).abs() < 1e-9, "{} -> {}", q.c, j.c);
        }
        prev = Some(j);
    }
    assert!(close(prev.unwrap().c, 720.0));
}

#[test]
fn on_the_a_limit_is_reachable() {
    let kin = machine().with_a_limits(-120.0, 120.0);
    for az in [0.0, 90.0, -135.0] {
        let j = assert_round_trip(&kin, &pose([0.0; 3], dir(120.0, az)), None);
        assert!(j.a <= 120.0);
    }
}

#[test]
fn relaxed_inverse_is_calm_and_bounded_near_the_pole() {
    let kin = machine().with_singular_tolerance(0.05);
    let prev = Joints {
        a: 0.01,
        c: 33.0,
        ..Joints::default()
    };
    for (tilt, az) in [
        (0.0, 0.0),
        (0.01, 150.0),
        (0.04, -100.0),
        (0.07, 80.0),
        (0.2, 200.0),
    ] {
        let p = pose([40.0, -10.0, 3.0], dir(tilt, az));
        let j = kin.inverse_relaxed(&p, &prev, 0.05).unwrap();
        let q = kin.forward(&j);
        assert!((q.tip - p.tip).norm() <= EPS, "tip must stay exact");
        let err = super::angle(&q.axis, &p.axis).to_degrees();
        assert!(err <= 0.05 + 1e-12, "tilt {tilt}: axis error {err}");
        if tilt <= 0.025 {
            assert_eq!(j.c, 33.0, "C is held inside half the cone");
        }
        if tilt >= 0.1 {
            assert!(err <= 1e-9, "exact outside 2× the cone");
        }
    }
}

/// Leaving the pole square to where C is held, the relaxed C turns to the exact one at no more
/// than 60°/s per degree of tilt (s the cone), within the axis error all the way: what lets
/// linearisation follow it in blocks of bounded length.
#[test]
fn relaxed_c_turns_at_a_bounded_rate_leaving_the_pole() {
    let s = 0.0165;
    let kin = machine().with_singular_tolerance(0.05);
    // The axis tilts toward azimuth 176°; C held at the value square to it.
    let mut prev = Joints {
        a: 0.0,
        c: -179.82 + 90.0,
        ..Joints::default()
    };
    let steps = 20_000;
    let step = 3.0 * s / steps as f64;
    for i in 1..=steps {
        let tilt = i as f64 * step;
        let p = pose([13.0, -4.0, 3.0], dir(tilt, 176.0));
        let j = kin.inverse_relaxed(&p, &prev, s).unwrap();
        let err = super::angle(&kin.forward(&j).axis, &p.axis).to_degrees();
        assert!(err <= s + 1e-12, "tilt {tilt}: axis error {err}");
        let turn = (j.c - prev.c).abs();
        assert!(
            turn <= 60.0 / s * step * (1.0 + 1e-6) + 1e-9,
            "tilt {tilt}: C turned {turn}° in a step of {step}°"
        );
        prev = j;
    }
    assert!(prev.a.abs() > 0.0);
}

#[test]
fn invalid_machine_and_pose_are_errors() {
    let kin = machine().with_a_limits(10.0, -10.0);
    assert!(matches!(
        kin.inverse(&pose([0.0; 3], [0.0, 0.0, 1.0]), None),
        Err(KinematicsError::InvalidMachine(_))
    ));
    let mut p = pose([0.0; 3], [0.0, 0.0, 1.0]);
    p.tip.x = f64::NAN;
    assert_eq!(machine().inverse(&p, None), Err(KinematicsError::NonFinite));
}

fn axis_strategy() -> impl Strategy<Value = [f64; 3]> {
    // Uniform on the spherical cap tilt ≤ 120°: z uniform in [cos 120°, 1].
    (-0.5f64..=1.0, -180.0f64..180.0).prop_map(|(z, az)| {
        let r = (1.0 - z * z).max(0.0).sqrt();
        let (s, c) = az.to_radians().sin_cos();
        [r * s, r * c, z]
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn round_trip_random(
        axis in axis_strategy(),
        tip in prop::array::uniform3(-200.0f64..200.0),
        o in prop::array::uniform3(-100.0f64..100.0),
        prev in prop::option::of((-120.0f64..120.0, -1000.0f64..1000.0)),
    ) {
        let kin = TableTableAC::new(Vector3::from(o));
        let prev = prev.map(|(a, c)| Joints { a, c, ..Joints::default() });
        let p = pose(tip, axis);
        let j = assert_round_trip(&kin, &p, prev.as_ref());
        if let Some(q) = prev {
            // The chosen branch/wrap is the closest one: compare with the other branch.
            let other = Joints { a: -j.a, c: j.c + 180.0, ..j };
            let cost = |w: &Joints| (w.a - q.a).powi(2) + (w.c - q.c).powi(2);
            for k in -4..=4 {
                let alt = Joints { c: other.c + 360.0 * f64::from(k), ..other };
                let same = Joints { c: j.c + 360.0 * f64::from(k), ..j };
                prop_assert!(cost(&j) <= cost(&alt) + 1e-6);
                prop_assert!(cost(&j) <= cost(&same) + 1e-6);
            }
        } else {
            prop_assert!(j.a >= 0.0 && j.c > -180.0 && j.c <= 180.0);
        }
    }

    #[test]
    fn relaxed_round_trip_random(
        tilt in 0.0f64..0.3,
        az in -180.0f64..180.0,
        tip in prop::array::uniform3(-200.0f64..200.0),
        prev_c in -500.0f64..500.0,
        budget in 0.001f64..0.2,
    ) {
        let kin = machine().with_singular_tolerance(0.1);
        let prev = Joints { a: 0.0, c: prev_c, ..Joints::default() };
        let p = pose(tip, dir(tilt, az));
        let j = kin.inverse_relaxed(&p, &prev, budget).unwrap();
        let q = kin.forward(&j);
        prop_assert!((q.tip - p.tip).norm() <= EPS);
        let err = super::angle(&q.axis, &p.axis).to_degrees();
        prop_assert!(err <= budget.min(0.1) + 1e-12);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    /// The quick reach test says yes exactly when the inverse finds joints, with limited and
    /// continuous C, narrow and wide A.
    #[test]
    fn reaching_an_axis_agrees_with_the_inverse(
        axis in axis_strategy(),
        tip in prop::array::uniform3(-200.0f64..200.0),
        a_limits in (-150.0f64..0.0, 0.0f64..150.0),
        c_limits in prop::option::of((-400.0f64..0.0, 0.0f64..400.0)),
    ) {
        let kin = machine()
            .with_a_limits(a_limits.0, a_limits.1)
            .with_c_limits(c_limits);
        let p = pose(tip, axis);
        prop_assert_eq!(
            kin.reaches_axis(&p.tip, &p.axis.into_inner()),
            kin.inverse(&p, None).is_ok()
        );
    }
}
