//! Planar (3-axis) programs: the 3-axis kinematics, arcs through the writer, arc and helix
//! lengths in the time model, and arcs fitted to the output grid.

use proptest::prelude::*;

use super::{dir, pose};
use crate::geom::{Move, MoveKind, Point2};
use crate::post::estimate::{TimeModel, block_length, block_seconds};
use crate::post::{
    ArcXY, GcodeOptions, Joints, KinematicsError, MachineKinematics, PlanarError, PlanarProgram,
    ProgramHeader, ThreeAxis,
};

fn joints(x: f64, y: f64, z: f64) -> Joints {
    Joints {
        x,
        y,
        z,
        a: 0.0,
        c: 0.0,
    }
}

#[test]
fn three_axis_maps_the_tip_and_refuses_a_tilted_tool() {
    let p = pose([3.0, -4.0, 5.5], [0.0, 0.0, 1.0]);
    let j = ThreeAxis.inverse(&p, None).unwrap();
    assert_eq!(j, joints(3.0, -4.0, 5.5));
    assert_eq!(ThreeAxis.forward(&j), p);
    assert!(ThreeAxis.rotary_axes().is_empty());
    match ThreeAxis.inverse(&pose([0.0; 3], dir(0.5, 30.0)), None) {
        Err(KinematicsError::FixedAxis { angle_deg }) => assert!((angle_deg - 0.5).abs() < 1e-9),
        other => panic!("a tilted tool on three axes: {other:?}"),
    }
    assert_eq!(
        ThreeAxis.inverse(&pose([f64::NAN, 0.0, 0.0], [0.0, 0.0, 1.0]), None),
        Err(KinematicsError::NonFinite)
    );
}

#[test]
fn arc_and_helix_lengths_and_times_have_their_closed_forms() {
    let r = 10.0;
    let (from, to) = (joints(r, 0.0, 0.0), joints(0.0, r, 0.0));
    let ccw = ArcXY {
        center: [0.0, 0.0],
        ccw: true,
    };
    let cw = ArcXY { ccw: false, ..ccw };
    let quarter = 0.5 * std::f64::consts::PI * r;
    assert!((block_length(&from, &to, Some(&ccw)) - quarter).abs() < 1e-12);
    assert!((block_length(&from, &to, Some(&cw)) - 3.0 * quarter).abs() < 1e-12);
    // A helix: the quarter turn climbing 4 mm.
    let up = joints(0.0, r, 4.0);
    let helix = block_length(&from, &up, Some(&ccw));
    assert!((helix - quarter.hypot(4.0)).abs() < 1e-12);
    let cut = Move {
        pose: pose([0.0, r, 4.0], [0.0, 0.0, 1.0]),
        kind: MoveKind::Cut,
        feed: 600.0,
    };
    let s = block_seconds(&from, &cut, &up, Some(&ccw), 0.0).unwrap();
    assert!((s - 60.0 * helix / 600.0).abs() < 1e-12);
    // A straight block of the same ends is the chord.
    assert!((block_length(&from, &to, None) - r * 2f64.sqrt()).abs() < 1e-12);
}

#[test]
fn the_writer_posts_arcs_and_no_rotary_words_on_three_axes() {
    let opts = GcodeOptions::default();
    let mut p = PlanarProgram::new(&opts).unwrap();
    assert_eq!(
        p.straight(MoveKind::Cut, 100.0, [None, None, Some(1.0)]),
        Err(PlanarError::NoStart)
    );
    p.straight(MoveKind::Rapid, 5000.0, [Some(10.0), Some(0.0), Some(5.0)])
        .unwrap();
    p.straight(MoveKind::Approach, 200.0, [None, None, Some(-1.0)])
        .unwrap();
    let center = Point2::new(0.0, 0.0);
    let half = std::f64::consts::FRAC_PI_2;
    p.arc(
        MoveKind::Cut,
        600.0,
        center,
        10.0,
        half,
        Point2::new(0.0, 10.0),
        None,
    )
    .unwrap();
    p.arc(
        MoveKind::Cut,
        600.0,
        center,
        10.0,
        -half,
        Point2::new(10.0, 0.0),
        None,
    )
    .unwrap();
    let header = ProgramHeader {
        program_name: "arcs".into(),
        tool_number: 2,
        ..ProgramHeader::default()
    };
    let text = p.to_gcode(&header, &opts);
    let motion: Vec<&str> = text
        .lines()
        .skip_while(|l| !l.starts_with("G0 G43"))
        .collect();
    assert_eq!(
        motion,
        [
            "G0 G43 H2 Z5.0000",
            "X10.0000 Y0.0000",
            "G1 Z-1.0000 F200.0",
            "G3 X0.0000 Y10.0000 I-10.0000 J0.0000 F600.0",
            "G2 X10.0000 Y0.0000 I0.0000 J-10.0000",
            "M30",
            "%"
        ]
    );
    // Spindle speed 0 leaves the spindle alone; a 3-axis machine's header says where the
    // work offset goes.
    let codes: Vec<&str> = text
        .lines()
        .filter(|l| !l.starts_with('('))
        .flat_map(|l| l.split_whitespace())
        .collect();
    assert!(
        codes
            .iter()
            .all(|w| !["M3", "M5"].contains(w) && !w.starts_with(['S', 'A', 'C'])),
        "{text}"
    );
    assert!(text.contains("(WORK OFFSET: origin at the part origin)"));
    // Time: two quarter circles at 600 mm/min and the 6 mm plunge at 200; the rapid to
    // the start has no known start.
    let model = TimeModel {
        max_rotary_deg_per_min: 0.0,
        dwell_per_block_s: 0.5,
    };
    let t = p.estimate(&model);
    let quarter = 0.5 * std::f64::consts::PI * 10.0;
    assert!(
        (t.cut_s - 60.0 * 2.0 * quarter / 600.0).abs() < 1e-9,
        "{t:?}"
    );
    assert!((t.approach_s - 60.0 * 6.0 / 200.0).abs() < 1e-12, "{t:?}");
    assert_eq!(t.rapid_s, 0.0);
    assert_eq!(p.motion_lines(), 5);
    assert!((t.dwell_s - 5.0 * 0.5).abs() < 1e-12);
}

proptest! {
    /// Every arc fitted to the grid has start and end radii within half a grid unit of each
    /// other (LinuxCNC refuses 0.002 mm), its end within a unit of the exact end, and its
    /// centre within three units of the exact centre.
    #[test]
    fn arcs_on_the_grid_keep_their_radius(
        cx in -500.0..500.0f64,
        cy in -500.0..500.0f64,
        radius in 0.01..300.0f64,
        start in 0.0..std::f64::consts::TAU,
        sweep in prop_oneof![-3.1..-0.001f64, 0.001..3.1f64],
    ) {
        let opts = GcodeOptions::default();
        let mut p = PlanarProgram::new(&opts).unwrap();
        let q = p.quantum();
        let at = |a: f64| Point2::new(cx + radius * a.cos(), cy + radius * a.sin());
        let s = at(start);
        p.straight(MoveKind::Rapid, 5000.0, [Some(s.x), Some(s.y), Some(0.0)]).unwrap();
        let e = at(start + sweep);
        p.arc(MoveKind::Cut, 600.0, Point2::new(cx, cy), radius, sweep, e, None).unwrap();
        let blocks = p.blocks();
        let (b0, b1) = (blocks[0], blocks[blocks.len() - 1]);
        let mm = |v: i64| v as f64 * q;
        prop_assert!((mm(b1.end[0]) - e.x).abs() <= 1.5 * q && (mm(b1.end[1]) - e.y).abs() <= 1.5 * q);
        if let Some(arc) = b1.arc {
            let c = [mm(arc.center[0]), mm(arc.center[1])];
            let r0 = (mm(b0.end[0]) - c[0]).hypot(mm(b0.end[1]) - c[1]);
            let r1 = (mm(b1.end[0]) - c[0]).hypot(mm(b1.end[1]) - c[1]);
            prop_assert!((r0 - r1).abs() <= 0.5 * q, "radii {r0} vs {r1}");
            prop_assert!((c[0] - cx).abs() <= 3.0 * q && (c[1] - cy).abs() <= 3.0 * q);
            prop_assert_eq!(arc.ccw, sweep > 0.0);
        } else {
            // Only an arc flat to within the grid is posted straight.
            prop_assert!(radius * (1.0 - (0.5 * sweep).cos()) < q);
        }
    }
}
