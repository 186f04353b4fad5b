//! G-code: parse the output back and check it against the poses and the modal rules.

use nalgebra::Vector3;
use proptest::prelude::*;

use super::{angle, dir, toolpath};
use crate::geom::{Move, MoveKind::*, Toolpath};
use crate::post::format::fixed;
use crate::post::{
    GcodeOptions, GcodeWriter, Joints, LineariseOptions, MachineKinematics, ProgramHeader,
    TableTableAC, emit, linearise, post_gcode,
};

/// One parsed motion block: the modal state after it.
#[derive(Clone, Debug)]
struct Block {
    joints: Joints,
    mode: u8,
    feed: Option<f64>,
    line: String,
}

/// A small parser for the subset we write: words `<letter><number>`, comments in parentheses,
/// `%` framing. Also checks that modal G0/G1 and F are never repeated needlessly.
fn parse(text: &str) -> Vec<Block> {
    let mut blocks = Vec::new();
    let mut j = [f64::NAN; 5];
    let mut mode: Option<u8> = None;
    let mut feed: Option<f64> = None;
    let mut g43 = false;
    for line in text.lines() {
        let code = match line.find('(') {
            Some(i) => {
                assert!(
                    line.ends_with(')') && line[i + 1..line.len() - 1].find(['(', ')']).is_none()
                );
                &line[..i]
            }
            None => line,
        };
        if code.trim() == "%" || code.trim().is_empty() {
            continue;
        }
        let mut has_axis = false;
        let mut has_f = false;
        for word in code.split_whitespace() {
            let (letter, num) = word.split_at(1);
            let v: f64 = num.parse().unwrap_or_else(|_| panic!("bad word {word}"));
            if num.starts_with('-') {
                assert!(v != 0.0, "negative zero in {line}");
            }
            match letter {
                "G" if v == 0.0 || v == 1.0 => {
                    assert_ne!(mode, Some(v as u8), "redundant G{v} in {line}");
                    mode = Some(v as u8);
                }
                "G" if v == 43.0 => g43 = true,
                "X" | "Y" | "Z" | "A" | "C" => {
                    let i = "XYZAC".find(letter).unwrap();
                    if letter == "Z" {
                        assert!(g43, "Z moves before G43: {line}");
                    }
                    j[i] = v;
                    has_axis = true;
                }
                "F" => {
                    assert_ne!(feed, Some(v), "redundant F in {line}");
                    feed = Some(v);
                    has_f = true;
                }
                _ => {}
            }
        }
        if has_f {
            assert_eq!(mode, Some(1), "F on a non-G1 block: {line}");
        }
        if has_axis {
            if mode == Some(1) {
                assert!(feed.is_some(), "G1 without a feed: {line}");
            }
            blocks.push(Block {
                joints: Joints {
                    x: j[0],
                    y: j[1],
                    z: j[2],
                    a: j[3],
                    c: j[4],
                },
                mode: mode.unwrap(),
                feed,
                line: line.to_string(),
            });
        }
    }
    blocks
}

fn header() -> ProgramHeader {
    ProgramHeader {
        program_name: "blade (op 10)".into(),
        part_name: "impeller".into(),
        tool_description: vec!["ball 6 mm".into(), "holder HSK63 (short)".into()],
        tool_number: 7,
        spindle_rpm: 12000,
        coolant: true,
        comments: vec!["finish pass".into()],
        control_point_mm: None,
    }
}

fn test_path() -> Toolpath {
    toolpath(&[
        (Rapid, 6000.0, [30.0, -10.0, 60.0], dir(20.0, 30.0)),
        (Rapid, 6000.0, [30.0, -10.0, 12.0], dir(20.0, 30.0)),
        (Approach, 500.0, [30.0, -10.0, 2.0], dir(20.0, 30.0)),
        (Cut, 1200.0, [35.0, -5.0, 1.0], dir(25.0, 50.0)),
        (Cut, 1200.0, [40.0, 5.0, 0.5], dir(35.0, 80.0)),
        (Cut, 1200.0, [42.0, 15.0, 0.0], dir(35.0, 120.0)),
        (Cut, 800.0, [40.0, 25.0, 0.0], dir(30.0, 150.0)),
        (Cut, 800.0, [36.0, 30.0, 0.5], dir(10.0, 200.0)),
        (Retract, 3000.0, [36.0, 30.0, 20.0], dir(10.0, 200.0)),
        (Rapid, 6000.0, [0.0, 0.0, 80.0], [0.0, 0.0, 1.0]),
    ])
}

fn kin() -> TableTableAC {
    TableTableAC::new(Vector3::new(5.0, -12.0, 40.0))
}

#[test]
fn parsed_blocks_reproduce_the_poses() {
    let kin = kin();
    let tp = test_path();
    let program = linearise(&kin, &tp, 0.01, 0.1).unwrap();
    assert!(
        program.len() > tp.moves.len(),
        "the path should need inserted points"
    );
    let mut w = GcodeWriter::new(&kin, GcodeOptions::default());
    emit(&program, &header(), &mut w);
    let text = w.into_string();
    let blocks = parse(&text);
    // The first move is posted as two blocks (G43 H Z alone, then X Y A C).
    assert!(
        blocks[0].line.starts_with("G0 G43 H7 Z"),
        "{}",
        blocks[0].line
    );
    for axis in ['X', 'Y', 'A', 'C'] {
        assert!(!blocks[0].line.contains(axis), "{}", blocks[0].line);
    }
    let blocks = &blocks[1..];
    // Every printed change is written: the control is within the rounding of the joints.
    let res_lin = 0.5e-4 + 1e-12;
    let res_ang = 0.5e-4 + 1e-12;
    let mut k = 0;
    for (m, j) in &program {
        let within = |b: &Block| {
            let d = [b.joints.x - j.x, b.joints.y - j.y, b.joints.z - j.z];
            d.iter().all(|v| v.abs() <= res_lin)
                && (b.joints.a - j.a).abs() <= res_ang
                && (b.joints.c - j.c).abs() <= res_ang
        };
        let b = if k < blocks.len() && within(&blocks[k]) {
            k += 1;
            &blocks[k - 1]
        } else {
            // No block: no printed value changed.
            assert!(k > 0 && within(&blocks[k - 1]), "no block for {m:?}");
            &blocks[k - 1]
        };
        assert_eq!(b.mode, u8::from(m.kind != Rapid), "{}", b.line);
        if m.kind != Rapid {
            assert_eq!(b.feed, Some(m.feed), "{}", b.line);
        }
        // Forward kinematics of the posted joints reproduces the pose within the error the
        // resolution allows: linear error + radius × angular error (A and C).
        let q = kin.forward(&b.joints);
        let radius = j.xyz().norm();
        let tol_tip = 3f64.sqrt() * res_lin + 2.0 * radius * res_ang.to_radians() + 1e-9;
        assert!(
            (q.tip - m.pose.tip).norm() <= tol_tip,
            "{} vs {m:?}",
            b.line
        );
        let tol_axis = 2.0 * res_ang.to_radians() + 1e-12;
        assert!(angle(&q.axis, &m.pose.axis) <= tol_axis, "{}", b.line);
    }
    assert_eq!(k, blocks.len(), "every block corresponds to a move");
}

#[test]
fn program_frame_and_header() {
    let kin = kin();
    let text = post_gcode(
        &kin,
        &test_path(),
        &header(),
        &LineariseOptions::default(),
        &GcodeOptions::default(),
    )
    .unwrap();
    assert!(text.starts_with("%\n(PROGRAM: blade [op 10])\n(PART: impeller)\n"));
    assert!(text.contains("(TOOL T7: ball 6 mm)\n(TOOL T7: holder HSK63 [short])\n"));
    assert!(text.contains("(UNITS: MM)\n(MACHINE: table-table A/C"));
    assert!(text.contains("(GENERATED BY: wavemill post)\n(finish pass)\n"));
    let i_safe = text.find("G21 G90 G94 G17 G40 G49 G80\n").unwrap();
    let i_tool = text.find("T7 M6\n").unwrap();
    let i_spindle = text.find("S12000 M3\n").unwrap();
    let i_cool = text.find("M8\n").unwrap();
    let i_g43 = text.find("G43 H7 Z").unwrap();
    assert!(i_safe < i_tool && i_tool < i_spindle && i_spindle < i_cool && i_cool < i_g43);
    assert!(text.ends_with("M5\nM9\nM30\n%\n"));
    assert!(!text.contains("-0.0000"));
    // Deterministic.
    let again = post_gcode(
        &kin,
        &test_path(),
        &header(),
        &LineariseOptions::default(),
        &GcodeOptions::default(),
    )
    .unwrap();
    assert_eq!(text, again);
    // No coolant ⇒ no M8/M9.
    let h = ProgramHeader {
        coolant: false,
        ..header()
    };
    let dry = post_gcode(
        &kin,
        &test_path(),
        &h,
        &LineariseOptions::default(),
        &GcodeOptions::default(),
    )
    .unwrap();
    assert!(!dry.contains("M8") && !dry.contains("M9"));
}

#[test]
fn feed_is_modal() {
    let kin = TableTableAC::default();
    let rows = [
        (Rapid, 5000.0, [0.0, 0.0, 10.0], [0.0, 0.0, 1.0]),
        (Cut, 1000.0, [10.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
        (Cut, 1000.0, [20.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
        (Cut, 500.0, [30.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
        (Cut, 500.0, [40.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
        (Rapid, 5000.0, [40.0, 0.0, 10.0], [0.0, 0.0, 1.0]),
        (Cut, 500.0, [50.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
        (Cut, 1000.0, [60.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
    ];
    let text = post_gcode(
        &kin,
        &toolpath(&rows),
        &header(),
        &LineariseOptions::default(),
        &GcodeOptions::default(),
    )
    .unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let start = lines.iter().position(|l| l.starts_with("G0 G43")).unwrap();
    assert_eq!(
        &lines[start..start + 9],
        &[
            "G0 G43 H7 Z10.0000",
            "X0.0000 Y0.0000 A0.0000 C0.0000",
            "G1 X10.0000 Z0.0000 F1000.0",
            "X20.0000",
            "X30.0000 F500.0",
            "X40.0000",
            "G0 Z10.0000",
            "G1 X50.0000 Z0.0000",
            "X60.0000 F1000.0",
        ]
    );
}

/// Issue 17 item 1c: words whose value changed by less than 0.001 were left out, so poses
/// within ~0.01 mm were merged. Now a word is written whenever its printed value changes, and
/// only then.
#[test]
fn every_printed_change_is_written_and_nothing_else() {
    let kin = TableTableAC::default();
    let mut w = GcodeWriter::new(&kin, GcodeOptions::default());
    let m = |x: f64| Move {
        pose: super::pose([x, 0.0, 0.0], [0.0, 0.0, 1.0]),
        kind: Cut,
        feed: 100.0,
    };
    let j = |x: f64| Joints {
        x,
        ..Joints::default()
    };
    w.begin(&header());
    for x in [0.0, 0.00004, 0.0004, 0.00044, 0.0008, 0.0012] {
        w.motion(&m(x), &j(x));
    }
    w.end();
    let text = w.into_string();
    let written: Vec<&str> = text
        .lines()
        .filter(|l| l.starts_with('X') || l.starts_with("G1 X"))
        .collect();
    // 0.00004 and 0.00044 print as the value before them: no block.
    assert_eq!(
        written,
        [
            "G1 X0.0000 Y0.0000 A0.0000 C0.0000 F100.0",
            "X0.0004",
            "X0.0008",
            "X0.0012"
        ],
        "{text}"
    );
}

#[test]
fn no_negative_zero_near_zero_values() {
    let kin = TableTableAC::default();
    let rows = [
        (Rapid, 5000.0, [-1e-7, -4e-5, 10.0], [-1e-13, 1e-13, 1.0]),
        (Cut, 1000.0, [-3e-5, 1e-9, -2e-5], [1e-13, -1e-13, 1.0]),
        (Cut, 1000.0, [5.0, -0.0, -0.0], [0.0, -0.0, 1.0]),
    ];
    let text = post_gcode(
        &kin,
        &toolpath(&rows),
        &header(),
        &LineariseOptions::default(),
        &GcodeOptions::default(),
    )
    .unwrap();
    assert!(!text.contains("-0.0000"), "{text}");
    parse(&text);
}

use crate::post::ProgramSink;

proptest! {
    #[test]
    fn fixed_never_writes_negative_zero(v in -2e-4f64..2e-4, big in -1e6f64..1e6, d in 0usize..7) {
        for x in [v, big, -v * 1e-300] {
            let s = fixed(x, d);
            let parsed: f64 = s.parse().unwrap();
            prop_assert!((parsed - x).abs() <= 0.5 * 10f64.powi(-(d as i32)) * (1.0 + 1e-9) + 1e-9 * x.abs());
            if parsed == 0.0 {
                prop_assert!(!s.starts_with('-'), "{}", s);
            }
        }
    }
}

/// A tool change that names the new tool's control point times the inverse-time feeds after
/// it there: the same blocks posted before and after it get the F of each tool's own point
/// (a smaller ball's centre moves less when the axis turns).
#[test]
fn a_tool_change_times_inverse_time_feeds_at_the_new_control_point() {
    let kin = kin();
    let program = linearise(&kin, &test_path(), 0.01, 0.1).unwrap();
    let (big, small) = (3.0, 0.5);
    let options = GcodeOptions {
        feed: crate::post::FeedMode::InverseTime,
        control_point_mm: big,
        ..GcodeOptions::default()
    };
    let mut writer = GcodeWriter::new(&kin, options.clone());
    writer.begin(&header());
    for (m, j) in &program {
        writer.motion(m, j);
    }
    writer.tool_change(&ProgramHeader {
        tool_number: 8,
        control_point_mm: Some(small),
        ..header()
    });
    for (m, j) in &program {
        writer.motion(m, j);
    }
    writer.end();
    let text = Box::new(writer).finish();
    let (before, after) = text.split_once("T8 M6").expect("the tool change");
    // The F word of every feed block, in order, and the one the control point gives it.
    let feeds = |section: &str| -> Vec<f64> {
        section
            .lines()
            .filter(|l| l.starts_with("G1") || (l.contains('F') && !l.starts_with('(')))
            .filter_map(|l| {
                l.split_whitespace()
                    .find_map(|w| w.strip_prefix('F'))
                    .map(|f| f.parse::<f64>().unwrap())
            })
            .collect()
    };
    let expected = |control_point: f64| -> Vec<f64> {
        program
            .windows(2)
            .filter(|w| w[1].0.kind != Rapid)
            .map(|w| {
                let minutes = crate::post::inverse_time_minutes(
                    (&w[0].0.pose, &w[0].1),
                    &w[1].0,
                    &w[1].1,
                    control_point,
                    options.max_rotary_speed,
                );
                (1.0 / minutes.max(1e-9)).min(1e6)
            })
            .collect()
    };
    let printed = |f: f64| {
        fixed(f, crate::post::gcode::INVERSE_TIME_DECIMALS)
            .parse::<f64>()
            .unwrap()
    };
    let (wanted_before, wanted_after) = (expected(big), expected(small));
    assert_ne!(wanted_before, wanted_after);
    // F is modal: each printed F is one of the block's, in order.
    for (section, wanted) in [(before, &wanted_before), (after, &wanted_after)] {
        let mut wanted = wanted.iter().map(|&f| printed(f));
        for f in feeds(section) {
            assert!(
                wanted.any(|w| w == f),
                "F{f} is not timed at its control point"
            );
        }
    }
}
