//! Linearisation: inserted points keep joint-space motion within tolerance, checked with an
//! independent forward map.

use nalgebra::Vector3;
use proptest::prelude::*;

use super::{angle, dir, forward_ref, slerp_ref, toolpath};
use crate::geom::{Move, MoveKind::*, Toolpath};
use crate::post::{
    Joints, LineariseError, LineariseOptions, MachineKinematics, TableTableAC, linearise,
    linearise_opt,
};

/// Independent check: every feed block of `out` stays within tolerance of the planned motion
/// at t = ¼, ½, ¾ (and within `slack`× tolerance at t = k/16), every block pose lies on its
/// original segment, and the original moves appear in order. Returns the largest tip deviation.
fn check(
    kin: &TableTableAC,
    tp: &Toolpath,
    out: &[(Move, Joints)],
    tol: f64,
    ang_deg: f64,
    slack: f64,
) -> f64 {
    let o = kin.part_origin_in_table;
    // Original moves appear, in order, with their poses and kinds.
    let mut idx = Vec::new();
    let mut next = 0;
    for (i, (m, _)) in out.iter().enumerate() {
        if next < tp.moves.len() && *m == tp.moves[next] {
            idx.push(i);
            next += 1;
        }
    }
    assert_eq!(
        next,
        tp.moves.len(),
        "original moves missing from the output"
    );
    assert_eq!(idx[0], 0);
    assert_eq!(*idx.last().unwrap(), out.len() - 1);
    let mut worst: f64 = 0.0;
    for seg in 1..tp.moves.len() {
        let (a, b) = (&tp.moves[seg - 1].pose, &tp.moves[seg].pose);
        let blocks = &out[idx[seg - 1]..=idx[seg]];
        if tp.moves[seg].kind == Rapid {
            assert_eq!(blocks.len(), 2, "rapids are not subdivided");
            continue;
        }
        // Inserted poses lie on the planned segment (tip on the line, axis on the arc).
        let dir_ab = b.tip - a.tip;
        for (m, _) in &blocks[1..] {
            assert_eq!(m.kind, tp.moves[seg].kind);
            assert_eq!(m.feed, tp.moves[seg].feed);
        }
        for (m, j) in blocks {
            let t = if dir_ab.norm() > 1e-12 {
                (m.pose.tip - a.tip).dot(&dir_ab) / dir_ab.norm_squared()
            } else {
                let total = angle(&a.axis, &b.axis);
                angle(&a.axis, &m.pose.axis) / total.max(1e-300)
            };
            assert!((-1e-12..=1.0 + 1e-12).contains(&t));
            assert!((a.tip + dir_ab * t - m.pose.tip).norm() < 1e-9);
            let k = slerp_ref(&a.axis, &b.axis, t);
            assert!(angle(&k, &m.pose.axis) < 1e-9);
            // The block's joints realise its pose (tip exact; axis within half the tolerance).
            let (tip, axis) = forward_ref(&o, j);
            assert!((tip - m.pose.tip).norm() < 1e-9);
            assert!(angle(&axis, &m.pose.axis).to_degrees() <= 0.5 * ang_deg + 1e-12);
        }
        for w in blocks.windows(2) {
            let ((m0, j0), (m1, j1)) = (&w[0], &w[1]);
            for s in 1..16 {
                let t = f64::from(s) / 16.0;
                let planned_tip = m0.pose.tip + (m1.pose.tip - m0.pose.tip) * t;
                let planned_axis = slerp_ref(&m0.pose.axis, &m1.pose.axis, t);
                let (tip, axis) = forward_ref(&o, &j0.lerp(j1, t));
                let dt = (tip - planned_tip).norm();
                let da = angle(&axis, &planned_axis).to_degrees();
                let f = if s % 4 == 0 { 1.0 } else { slack };
                assert!(dt <= f * tol + 1e-12, "tip deviation {dt} at t={t}");
                assert!(da <= f * ang_deg + 1e-12, "axis deviation {da} at t={t}");
                worst = worst.max(dt);
            }
        }
    }
    worst
}

fn machine() -> TableTableAC {
    TableTableAC::new(Vector3::new(0.0, 0.0, 20.0))
}

#[test]
fn large_c_swing_at_moderate_a_gets_points_inserted() {
    let kin = machine();
    // Tip fixed 50 mm off the C axis; the axis turns 90° in azimuth at tilt 30° ⇒ C swings
    // 90° at A = 30°: the part turns under the tool, the raw joint interpolation would miss
    // the tip by ~14 mm.
    let tp = toolpath(&[
        (Rapid, 5000.0, [50.0, 0.0, 30.0], dir(30.0, 0.0)),
        (Approach, 800.0, [50.0, 0.0, 5.0], dir(30.0, 0.0)),
        (Cut, 1000.0, [50.0, 0.0, 5.0], dir(30.0, 90.0)),
        (Cut, 1000.0, [40.0, 30.0, 5.0], dir(25.0, 120.0)),
    ]);
    let raw = [
        kin.inverse(&tp.moves[1].pose, None).unwrap(),
        kin.inverse(&tp.moves[2].pose, None).unwrap(),
    ];
    let (mid, _) = forward_ref(&kin.part_origin_in_table, &raw[0].lerp(&raw[1], 0.5));
    assert!(
        (mid - tp.moves[2].pose.tip).norm() > 5.0,
        "the test move must deviate"
    );
    let out = linearise(&kin, &tp, 0.01, 0.1).unwrap();
    assert!(out.len() > tp.moves.len() + 10, "only {} blocks", out.len());
    let worst = check(&kin, &tp, &out, 0.01, 0.1, 1.5);
    assert!(worst > 0.001, "tolerance is used, not wasted: {worst}");
}

#[test]
fn tighter_tolerance_gives_more_points() {
    let kin = machine();
    let tp = toolpath(&[
        (Rapid, 5000.0, [30.0, 10.0, 10.0], dir(40.0, -20.0)),
        (Cut, 1000.0, [35.0, -20.0, 0.0], dir(50.0, 60.0)),
    ]);
    let coarse = linearise(&kin, &tp, 0.05, 0.5).unwrap();
    let fine = linearise(&kin, &tp, 0.005, 0.05).unwrap();
    assert!(fine.len() > coarse.len());
    check(&kin, &tp, &coarse, 0.05, 0.5, 1.5);
    check(&kin, &tp, &fine, 0.005, 0.05, 1.5);
}

#[test]
fn rapids_are_not_subdivided() {
    let kin = machine();
    let tp = toolpath(&[
        (Rapid, 5000.0, [50.0, 0.0, 50.0], dir(30.0, 0.0)),
        (Rapid, 5000.0, [50.0, 0.0, 50.0], dir(30.0, 170.0)),
    ]);
    let out = linearise(&kin, &tp, 0.01, 0.1).unwrap();
    assert_eq!(out.len(), 2);
}

/// A move passing 1e-4° from the pole with the tip 80 mm off the C axis. The exact C turns by
/// ~180° within the move; the relaxed inverse keeps C calm.
fn near_pole_path() -> Toolpath {
    let eps = 1e-4f64.to_radians();
    let s5 = 5f64.to_radians().sin();
    toolpath(&[
        (Rapid, 5000.0, [80.0, 0.0, 20.0], [-s5, eps, 1.0]),
        (Cut, 1000.0, [80.0, 1.0, 0.0], [-s5, eps, 1.0]),
        (Cut, 1000.0, [80.0, 2.0, 0.0], [s5, eps, 1.0]),
        (Cut, 1000.0, [80.0, 3.0, 0.0], [s5, -eps, 1.0]),
    ])
}

#[test]
fn near_singular_pass_keeps_c_calm() {
    let kin = machine().with_singular_tolerance(0.05);
    let tp = near_pole_path();
    let out = linearise(&kin, &tp, 0.01, 0.1).unwrap();
    check(&kin, &tp, &out, 0.01, 0.1, 1.5);
    let cs: Vec<f64> = out.iter().map(|(_, j)| j.c).collect();
    let span =
        cs.iter().cloned().fold(f64::MIN, f64::max) - cs.iter().cloned().fold(f64::MAX, f64::min);
    assert!(span < 1.0, "C span {span}");
    assert!(out.iter().all(|(_, j)| j.is_finite()));
    // Without the relaxation the result is still within tolerance (the exact C swings or A
    // flips, whichever the walk verifies).
    let exact = machine().with_singular_tolerance(0.0);
    let out2 = linearise_opt(&exact, &tp, &LineariseOptions::default().with_max_depth(30)).unwrap();
    check(&exact, &tp, &out2, 0.01, 0.1, 1.5);
}

/// A move in the air whose axis passes the pole at 1.35 × the relaxed inverse's budget, where
/// it lets C stray from its exact value by only 39° (the bundled job's lifted link between
/// two blade passes): C turns half a turn while the axis moves by hundredths of a degree, the tip
/// 29 mm off the C axis. The walk needs steps of ~2⁻¹⁷ of the move there; it follows them,
/// and the table turns without the tip leaving its tolerance.
#[test]
fn an_axis_passing_the_pole_where_c_barely_strays_turns_c_half_a_turn_within_tolerance() {
    let kin = machine().with_singular_tolerance(0.05);
    let (tolerance, angle_tolerance): (f64, f64) = (0.0046, 0.033);
    let budget = 0.5 * angle_tolerance;
    // The great circle's point nearest the pole, `miss` from it, and its tangent there.
    let miss = (1.35 * budget).to_radians();
    let nearest = Vector3::new(0.0, miss.sin(), miss.cos());
    let on_circle = |deg: f64| {
        let a = nearest * deg.to_radians().cos() + Vector3::x() * deg.to_radians().sin();
        [a.x, a.y, a.z]
    };
    let tp = toolpath(&[
        (Rapid, 5000.0, [29.7, -25.0, 60.0], on_circle(-12.0)),
        (Retract, 6000.0, [29.7, -25.0, 36.3], on_circle(-12.0)),
        (Retract, 6000.0, [-2.1, -4.9, 35.0], on_circle(41.0)),
    ]);
    let options = LineariseOptions::default()
        .with_tolerance_mm(tolerance)
        .with_angle_tolerance_deg(angle_tolerance);
    let out = linearise_opt(&kin, &tp, &options).unwrap();
    check(&kin, &tp, &out, tolerance, angle_tolerance, 1.5);
    let cs: Vec<f64> = out.iter().map(|(_, j)| j.c).collect();
    let span =
        cs.iter().cloned().fold(f64::MIN, f64::max) - cs.iter().cloned().fold(f64::MAX, f64::min);
    assert!(span > 150.0, "C span {span}");
    // The walk's old bound, 2¹⁶ steps a move, stopped it at the pole.
    let Err(LineariseError::NoStart { source, .. }) =
        linearise_opt(&kin, &tp, &options.with_max_depth(16))
    else {
        panic!("the pass was followed in 2^16 steps a move");
    };
    assert!(matches!(
        *source,
        LineariseError::DepthLimit { move_index: 2, .. }
    ));
}

#[test]
fn c_is_unwrapped_across_the_program() {
    let kin = machine();
    let mut rows = vec![(Rapid, 5000.0, [10.0, 0.0, 30.0], dir(20.0, 0.0))];
    for i in 1..=40 {
        let az = f64::from(i) * 20.0;
        rows.push((Cut, 2000.0, [10.0, 0.0, 0.0], dir(20.0, az)));
    }
    let tp = toolpath(&rows);
    let out = linearise(&kin, &tp, 0.01, 0.1).unwrap();
    check(&kin, &tp, &out, 0.01, 0.1, 1.5);
    assert!((out.last().unwrap().1.c - 800.0).abs() < 1e-9);
    for w in out.windows(2) {
        assert!((w[1].1.c - w[0].1.c).abs() <= 20.0 + 1e-9);
    }
}

#[test]
fn depth_bound_is_an_error() {
    let kin = machine();
    let tp = toolpath(&[
        (Rapid, 5000.0, [50.0, 0.0, 5.0], dir(30.0, 0.0)),
        (Cut, 1000.0, [50.0, 0.0, 5.0], dir(30.0, 90.0)),
    ]);
    // Every start of the pass (both branches) is tried; the nearest one's failure is kept.
    let err = linearise_opt(&kin, &tp, &LineariseOptions::default().with_max_depth(2)).unwrap_err();
    let LineariseError::NoStart { source, tried, .. } = err else {
        panic!("{err}");
    };
    assert_eq!(tried, 2, "both branches");
    assert_eq!(
        *source,
        LineariseError::DepthLimit {
            move_index: 1,
            depth: 2
        }
    );
}

#[test]
fn bad_inputs_are_errors() {
    let kin = machine();
    let tp = toolpath(&[
        (Rapid, 5000.0, [0.0, 0.0, 5.0], [0.0, 0.3, 1.0]),
        (Cut, 1000.0, [0.0, 0.0, 5.0], [0.0, -0.3, -1.0]),
    ]);
    assert!(matches!(
        linearise(&kin, &tp, 0.0, 0.1),
        Err(LineariseError::InvalidOptions(_))
    ));
    // Axis reverses within the move.
    let kin = machine().with_a_limits(-180.0, 180.0);
    assert_eq!(
        linearise(&kin, &tp, 0.01, 0.1).unwrap_err(),
        LineariseError::AntipodalAxes { move_index: 1 }
    );
    // Out of limits reports the move.
    let tp = toolpath(&[
        (Rapid, 5000.0, [0.0, 0.0, 5.0], [0.0, 0.0, 1.0]),
        (Cut, 1000.0, [0.0, 0.0, 5.0], dir(125.0, 0.0)),
    ]);
    let e = linearise(&machine(), &tp, 0.01, 0.1).unwrap_err();
    let LineariseError::NoStart { source, .. } = e else {
        panic!("{e}");
    };
    assert!(
        matches!(*source, LineariseError::Kinematics { move_index: 1, .. }),
        "{source}"
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Random short paths: every block stays within tolerance of the plan (metamorphic:
    /// whatever the path, the same properties hold).
    #[test]
    fn random_paths_stay_within_tolerance(
        pts in prop::collection::vec(
            (prop::array::uniform3(-60.0f64..60.0), 0.0f64..60.0, -180.0f64..180.0),
            2..6,
        ),
    ) {
        let kin = machine();
        let mut rows = vec![(Rapid, 5000.0, [0.0, 0.0, 80.0], [0.0, 0.0, 1.0])];
        for (tip, tilt, az) in pts {
            rows.push((Cut, 1000.0, tip, dir(tilt, az)));
        }
        let tp = toolpath(&rows);
        let out = linearise_opt(&kin, &tp, &LineariseOptions::default().with_max_depth(20));
        let out = out.unwrap();
        check(&kin, &tp, &out, 0.01, 0.1, 3.0);
    }
}

#[test]
fn linearised_joints_respect_limits() {
    let kin = machine();
    let tp = near_pole_path();
    for (_, j) in linearise(&kin, &tp, 0.01, 0.1).unwrap() {
        kin.check_limits(&j).unwrap();
    }
}

#[test]
fn circling_inside_the_singular_cone_holds_c() {
    // The axis circles the pole at 0.02° tilt (inside the 0.05° cone) while the tip, 80 mm off
    // the C axis, moves slowly: the exact C must turn a full 360°, the relaxed C stays put.
    let mut rows = vec![(Rapid, 5000.0, [80.0, 0.0, 20.0], dir(0.02, 0.0))];
    for i in 1..=8 {
        rows.push((
            Cut,
            1000.0,
            [80.0, f64::from(i), 0.0],
            dir(0.02, f64::from(i) * 45.0),
        ));
    }
    let tp = toolpath(&rows);
    let c_span = |out: &[(Move, Joints)]| {
        let cs = out.iter().map(|(_, j)| j.c);
        cs.clone().fold(f64::MIN, f64::max) - cs.fold(f64::MAX, f64::min)
    };
    let relaxed = machine().with_singular_tolerance(0.05);
    let out = linearise(&relaxed, &tp, 0.01, 0.1).unwrap();
    check(&relaxed, &tp, &out, 0.01, 0.1, 1.5);
    assert!(c_span(&out) < 1e-9, "C span {}", c_span(&out));
    assert_eq!(out.len(), tp.moves.len());
    let exact = machine().with_singular_tolerance(0.0);
    let out2 = linearise(&exact, &tp, 0.01, 0.1).unwrap();
    check(&exact, &tp, &out2, 0.01, 0.1, 1.5);
    assert!(c_span(&out2) > 359.0, "C span {}", c_span(&out2));
    assert!(
        out2.len() > 10 * out.len(),
        "{} vs {}",
        out2.len(),
        out.len()
    );
}
