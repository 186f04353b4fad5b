//! Machine definition files, the dialects' program text, inverse-time feed and the pass starts
//! that keep a limited axis inside its travel.

use nalgebra::Vector3;

use super::{dir, pose, toolpath};
use crate::geom::MoveKind;
use crate::post::machine_file::{MachineDefinition, SHIPPED};
use crate::post::{
    Dialect, FeedMode, GcodeOptions, GcodeWriter, HeidenhainWriter, LineariseError,
    LineariseOptions, Machine, MachineKinematics, OutputMode, ProgramHeader, ProgramSink,
    ToolCentrePoint, estimate_time_posted, linearise_opt,
};
use crate::verify::{read_conversational, read_program};

/// Every shipped file reads, as the kind it says, and a wrong file is refused naming itself and
/// what is wrong.
#[test]
fn machine_files_read_and_bad_ones_are_refused_by_name() {
    for (name, text) in SHIPPED {
        let d = MachineDefinition::parse(text, name).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(d.chain.kind.name().replace("table-table", "trunnion"), {
            let n = name.to_string();
            if n.starts_with("trunnion") {
                format!("trunnion-{}", &n[9..])
            } else {
                n
            }
        });
    }
    let ac = SHIPPED[0].1;
    for (edit, expected) in [
        (
            ac.replace("letter = \"A\"", "letter = \"B\""),
            "kind table-table-ac has its axes",
        ),
        (
            ac.replace("direction = [1, 0, 0]", "direction = [0, 0, 1]"),
            "parallel",
        ),
        (
            ac.replace("direction = [1, 0, 0]", "direction = [0, 0, 0]"),
            "non-zero",
        ),
        (
            ac.replace("limits = [-120, 120]", "limits = [120, -120]"),
            "ordered",
        ),
        (
            ac.replace("dialect = \"linuxcnc\"", "dialect = \"heidenhain\""),
            "inverse-time",
        ),
        (
            ac.replace("kind = \"table-table-ac\"", "kind = \"five-axis\""),
            "kind",
        ),
        (ac.replace("[travel]", "[travel]\nw = [0, 1]"), "w"),
        (
            ac.replace("rapid_feed = 15000", "rapid_feed = -1"),
            "rapid_feed",
        ),
    ] {
        let e = MachineDefinition::parse(&edit, "shop.toml")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("shop.toml") && e.contains(expected),
            "{expected}: {e}"
        );
    }
    let head = SHIPPED
        .iter()
        .find(|(n, _)| *n == "head-table-bc")
        .unwrap()
        .1;
    let e = MachineDefinition::parse(
        &head
            .replace("dialect = \"siemens\"", "dialect = \"heidenhain\"")
            .replace("output = \"tcp\"", "output = \"joint\"")
            .replace("feed = \"inverse-time\"", "feed = \"per-minute\""),
        "h.toml",
    )
    .unwrap_err();
    assert!(e.to_string().contains("TCPM"), "{e}");
    let e = MachineDefinition::load("no-such-machine")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("trunnion-ac") && e.contains("no-such-machine"),
        "{e}"
    );
}

fn header() -> ProgramHeader {
    ProgramHeader {
        program_name: "t".into(),
        part_name: "p".into(),
        tool_description: vec!["ball".into()],
        tool_number: 3,
        spindle_rpm: 9000,
        coolant: true,
        comments: vec![],
        control_point_mm: None,
    }
}

/// A short 5-axis path: a rapid down to the safe plane, an approach, cuts that tilt and turn.
fn path() -> crate::geom::Toolpath {
    toolpath(&[
        (MoveKind::Rapid, 0.0, [0.0, 0.0, 80.0], [0.0, 0.0, 1.0]),
        (MoveKind::Approach, 300.0, [5.0, 0.0, 20.0], dir(20.0, 10.0)),
        (MoveKind::Cut, 1200.0, [10.0, 3.0, 19.0], dir(25.0, 40.0)),
        (MoveKind::Cut, 1200.0, [15.0, 8.0, 18.5], dir(30.0, 80.0)),
        (
            MoveKind::Retract,
            2000.0,
            [15.0, 8.0, 60.0],
            dir(30.0, 80.0),
        ),
    ])
}

fn machine(name: &str) -> (MachineDefinition, Machine) {
    let text = SHIPPED.iter().find(|(n, _)| *n == name).unwrap().1;
    let d = MachineDefinition::parse(text, name).unwrap();
    let m = Machine::Chain(Box::new(d.chain_for(Vector3::new(0.0, 0.0, 30.0), 110.0)));
    (d, m)
}

fn post(
    name: &str,
    output: OutputMode,
    feed: FeedMode,
) -> (String, Vec<(crate::geom::Move, crate::post::Joints)>) {
    let (d, m) = machine(name);
    let opts = GcodeOptions {
        dialect: d.dialect,
        output,
        feed,
        max_rotary_speed: d.max_rotary_speed,
        control_point_mm: 3.0,
        ..GcodeOptions::default()
    };
    let lin = LineariseOptions::default().with_control_point_mm(3.0);
    let tcp = ToolCentrePoint(&m);
    let (blocks, kin): (_, &dyn MachineKinematics) = if output == OutputMode::Tcp {
        (linearise_opt(&tcp, &path(), &lin).unwrap(), &tcp)
    } else {
        (linearise_opt(&m, &path(), &lin).unwrap(), &m)
    };
    let mut sink: Box<dyn ProgramSink> = if d.dialect == Dialect::Heidenhain {
        Box::new(HeidenhainWriter::new(kin, opts))
    } else {
        Box::new(GcodeWriter::new(kin, opts))
    };
    sink.begin(&header());
    for (mv, j) in &blocks {
        sink.motion(mv, j);
    }
    sink.end();
    (sink.finish(), blocks)
}

/// Each dialect switches length compensation and TCP the way its control does, and its
/// program reads back (the verifier's own readers) with the state it declares.
#[test]
fn each_dialect_writes_its_own_words() {
    let (fanuc, _) = post("head-table-ac", OutputMode::Tcp, FeedMode::InverseTime);
    assert!(
        fanuc.contains("G0 G43.4 H3 Z") && fanuc.contains("G93") && fanuc.contains("\nG49\n"),
        "{fanuc}"
    );
    let blocks = read_program(&fanuc, ['X', 'Y', 'Z', 'A', 'C']).unwrap();
    assert!(
        blocks
            .iter()
            .all(|b| b.tcp && b.length_compensation && b.inverse_time)
    );

    let (siemens, _) = post("head-table-bc", OutputMode::Tcp, FeedMode::InverseTime);
    assert!(
        siemens.contains("\nD3\nTRAORI\n")
            && siemens.contains("TRAFOOF")
            && siemens.starts_with("; PROGRAM"),
        "{siemens}"
    );
    assert!(!siemens.contains('(') && !siemens.contains('%'));
    let blocks = read_program(&siemens, ['X', 'Y', 'Z', 'B', 'C']).unwrap();
    assert!(blocks.iter().all(|b| b.tcp && b.length_compensation));

    // Joint output on a head machine carries the tool length: compensation stays off.
    let (siemens_joint, _) = post("head-table-bc", OutputMode::Joint, FeedMode::PerMinute);
    assert!(siemens_joint.contains("\nD0\n") && !siemens_joint.contains("TRAORI"));
    let blocks = read_program(&siemens_joint, ['X', 'Y', 'Z', 'B', 'C']).unwrap();
    assert!(
        blocks
            .iter()
            .all(|b| !b.tcp && !b.length_compensation && !b.inverse_time)
    );

    let (linuxcnc, _) = post("head-head", OutputMode::Joint, FeedMode::InverseTime);
    assert!(
        linuxcnc.contains("G0 G49 Z") && linuxcnc.starts_with("%\n"),
        "{linuxcnc}"
    );

    let (heidenhain, _) = post("trunnion-bc", OutputMode::Tcp, FeedMode::PerMinute);
    let lines: Vec<&str> = heidenhain.lines().collect();
    assert!(
        lines[0] == "0 BEGIN PGM WAVEMILL MM"
            && lines.last().unwrap().ends_with("END PGM WAVEMILL MM")
    );
    assert!(
        heidenhain.contains("TOOL CALL 3 Z S9000")
            && heidenhain.contains("FUNCTION TCPM F TCP AXIS POS PATHCTRL AXIS")
    );
    for (n, l) in lines.iter().enumerate() {
        assert!(l.starts_with(&format!("{n} ")), "{l}");
    }
    let blocks = read_conversational(&heidenhain, ['X', 'Y', 'Z', 'B', 'C']).unwrap();
    assert!(blocks.iter().all(|b| b.tcp && b.tool == Some(3)));
    // FMAX holds for its block only: the first feed block after a rapid states F.
    let first_feed = lines
        .iter()
        .position(|l| l.contains(" L ") && l.contains(" R0 F") && !l.contains("FMAX"))
        .unwrap();
    assert!(
        lines[first_feed].contains(" F300.0"),
        "{}",
        lines[first_feed]
    );
}

/// Inverse time: each G1 block's F is 1 / its duration, the duration being the longer of the
/// tip's and the ball centre's part-frame travel at the planned feed (and the rotary time):
/// read back, distance × F never exceeds the planned feed, and equals it on the blocks the
/// linear motion times.
#[test]
fn inverse_time_feeds_give_the_planned_feed_at_the_part() {
    for (name, output) in [
        ("trunnion-ac", OutputMode::Joint),
        ("head-table-ac", OutputMode::Tcp),
    ] {
        let (text, blocks) = post(name, output, FeedMode::InverseTime);
        let read = read_program(&text, ['X', 'Y', 'Z', 'A', 'C']).unwrap();
        let feeds: Vec<f64> = read
            .iter()
            .filter(|b| !b.rapid)
            .map(|b| b.feed.unwrap())
            .collect();
        let moves: Vec<_> = blocks.iter().collect();
        let mut checked = 0;
        for w in moves.windows(2) {
            let ((m0, j0), (m1, j1)) = (w[0], w[1]);
            if m1.kind == MoveKind::Rapid {
                continue;
            }
            let centre = |p: &crate::geom::ToolPose| p.tip + p.axis.into_inner() * 3.0;
            let d = (m1.pose.tip - m0.pose.tip)
                .norm()
                .max((centre(&m1.pose) - centre(&m0.pose)).norm());
            let turn = (j1.a - j0.a).abs().max((j1.c - j0.c).abs());
            let minutes = (d / m1.feed).max(turn / 3600.0f64.min(7200.0).min(5400.0));
            let f = feeds[checked];
            assert!(
                (f * minutes - 1.0).abs() < 1e-3 || d * f <= m1.feed * 1.0001,
                "{name}: F{f} for {d} mm at {}",
                m1.feed
            );
            assert!(
                d * f <= m1.feed * (1.0 + 1e-4),
                "{name}: {} mm/min > {}",
                d * f,
                m1.feed
            );
            checked += 1;
        }
        assert_eq!(checked, feeds.len(), "{name}: every G1 has its F");
    }
}

/// The time estimate of an inverse-time program is what its printed `F` words say: the sum of
/// 1/F over the feed blocks (the rapids timed as per minute), read back from the text. On a
/// table-table machine whose table turns under the pass it is shorter than the per-minute
/// estimate of the same blocks, where F drives the machine's X, Y, Z.
#[test]
fn the_inverse_time_estimate_is_what_the_printed_feeds_say() {
    let (text, blocks) = post("trunnion-ac", OutputMode::Joint, FeedMode::InverseTime);
    let (d, _) = machine("trunnion-ac");
    let read = read_program(&text, ['X', 'Y', 'Z', 'A', 'C']).unwrap();
    let printed_minutes: f64 = read
        .iter()
        .filter(|b| !b.rapid)
        .map(|b| 1.0 / b.feed.unwrap())
        .sum();
    let rapids: Vec<_> = blocks
        .iter()
        .map(|(m, j)| {
            let mut m = *m;
            if m.kind != MoveKind::Rapid {
                m.feed = f64::INFINITY; // only the rapids counted
            }
            (m, *j)
        })
        .collect();
    let rapid_s = crate::post::estimate_time(&rapids, d.max_rotary_speed).rapid_s;
    let posted = estimate_time_posted(&blocks, FeedMode::InverseTime, 3.0, d.max_rotary_speed);
    let feed_s = posted.approach_s + posted.cut_s + posted.retract_s;
    // F is printed to 4 decimals; the first G1 has no block before it in either.
    assert!(
        (feed_s - 60.0 * printed_minutes).abs() <= 1e-3 * feed_s,
        "{feed_s} s estimated, {} s printed",
        60.0 * printed_minutes
    );
    assert!((posted.rapid_s - rapid_s).abs() < 1e-9);
    let per_minute = crate::post::estimate_time(&blocks, d.max_rotary_speed);
    assert!(
        posted.total_s() < per_minute.total_s(),
        "{posted:?} vs {per_minute:?}"
    );
}

/// Two rapids down, then a pass whose axis, tilted 30°, turns its azimuth by 300°.
fn c_turning_pass() -> Vec<(MoveKind, f64, [f64; 3], [f64; 3])> {
    let mut rows = vec![
        (MoveKind::Rapid, 0.0, [0.0, 0.0, 200.0], dir(30.0, -150.0)),
        (MoveKind::Rapid, 0.0, [0.0, 0.0, 150.0], dir(30.0, -150.0)),
    ];
    for k in 0..=30 {
        let az = -150.0 - 10.0 * k as f64;
        rows.push((
            MoveKind::Cut,
            800.0,
            [0.1 * k as f64, 0.0, 20.0],
            dir(30.0, az),
        ));
    }
    rows
}

/// A head-head fork whose C is limited to ±200°: a pass whose axis turns C by 300° cannot
/// start on the nearest turn; another start carries it, and when none can, the error says so.
#[test]
fn a_pass_starts_where_the_limits_let_it_finish() {
    let (d, _) = machine("head-head");
    let mut chain = d.chain_for(Vector3::zeros(), 100.0);
    chain.first.limits_deg = Some((-250.0, 250.0));
    let m = Machine::Chain(Box::new(chain.clone()));
    // C = 180° − azimuth (with A = 30°) or C + 180° (with A = −30°): the pass turns C by
    // 300°, from −30° (the default start, which runs into +250°) or from −210° (which ends at
    // +90°); the turn from +150° would end at 450°.
    let rows = c_turning_pass();
    let lin = LineariseOptions::default();
    let blocks = linearise_opt(&m, &toolpath(&rows), &lin).unwrap();
    for (_, j) in &blocks {
        m.check_limits(j).unwrap();
    }
    // Every block's axis is the planned one at the ends of the moves.
    let last = blocks.last().unwrap();
    let p = m.forward(&last.1);
    assert!((p.axis.into_inner() - nalgebra::Vector3::from(dir(30.0, -450.0))).norm() < 1e-9);

    chain.first.limits_deg = Some((-140.0, 140.0));
    let narrow = Machine::Chain(Box::new(chain));
    let e = linearise_opt(&narrow, &toolpath(&rows), &lin).unwrap_err();
    assert!(matches!(e, LineariseError::NoStart { .. }), "{e}");
    assert!(e.to_string().contains("unwind"), "{e}");
    let _ = pose;
}

/// Where no start carries a pass (C turning 300° on a C limited to ±140°, on a head-head fork
/// and on an A/C trunnion), the hook's unwind lets the program go on: every block inside the
/// limits, every planned pose reached, the rotaries turning only in place at the top of the
/// unwind, and the moves' origins kept.
#[test]
fn an_unwind_carries_a_pass_past_a_limit() {
    use crate::geom::{Move, ToolPose};
    use crate::post::linearise_unwinding;
    let rows = c_turning_pass();
    let path = toolpath(&rows);
    for name in ["head-head", "trunnion-ac"] {
        let (d, _) = machine(name);
        let mut chain = d.chain_for(Vector3::zeros(), 100.0);
        let c = if name == "head-head" {
            &mut chain.first
        } else {
            &mut chain.second
        };
        c.limits_deg = Some((-140.0, 140.0));
        let m = Machine::Chain(Box::new(chain));
        let lin = LineariseOptions::default();
        assert!(linearise_opt(&m, &path, &lin).is_err(), "{name}");
        let mut asked = Vec::new();
        let mut hook = |moves: &[Move], start: usize, stop: usize| {
            asked.push((start, stop));
            let at = stop - 1;
            let p = moves[at].pose;
            let up = |d: f64, kind, feed| Move {
                pose: ToolPose {
                    tip: p.tip + p.axis.into_inner() * d,
                    axis: p.axis,
                },
                kind,
                feed,
            };
            (at > start + 1).then(|| crate::post::Splice {
                after: at,
                replacing: 0,
                moves: vec![
                    up(5.0, MoveKind::Retract, 2000.0),
                    up(150.0, MoveKind::Rapid, 0.0),
                    up(5.0, MoveKind::Rapid, 0.0),
                    up(0.0, MoveKind::Approach, 300.0),
                ],
            })
        };
        let unwound = linearise_unwinding(&m, &path, &lin, &mut hook)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(!unwound.inserted_after.is_empty(), "{name}");
        assert_eq!(
            unwound.inserted_after.len(),
            asked.len(),
            "{name}: {asked:?}"
        );
        assert_eq!(unwound.moves.len(), path.moves.len() + 4 * asked.len());
        // The input's moves keep their order; the unwinds' are the hook's.
        let kept: Vec<usize> = unwound.origin.iter().flatten().copied().collect();
        assert_eq!(kept, (0..path.moves.len()).collect::<Vec<_>>(), "{name}");
        for (n, o) in unwound.origin.iter().enumerate() {
            if let Some(o) = o {
                assert_eq!(unwound.moves[n], path.moves[*o]);
            }
        }
        for &at in &unwound.inserted_after {
            assert!(unwound.origin[at].is_some() && unwound.origin[at + 1].is_none());
            assert_eq!(unwound.moves[at + 4].pose, unwound.moves[at].pose, "{name}");
        }
        for (k, (mv, j)) in unwound.blocks.iter().enumerate() {
            m.check_limits(j)
                .unwrap_or_else(|e| panic!("{name}: block {k}: {e}"));
            let p = m.forward(j);
            assert!(
                (p.tip - mv.pose.tip).norm() < 1e-6
                    && (p.axis.into_inner() - mv.pose.axis.into_inner()).norm() < 1e-6,
                "{name}: block {k} is not at its pose"
            );
        }
        // A big rotary turn between blocks happens only at the top of an unwind, in place.
        for w in unwound.blocks.windows(2) {
            let turn = (w[1].1.a - w[0].1.a).abs() + (w[1].1.c - w[0].1.c).abs();
            if turn > 90.0 {
                assert_eq!(w[0].0.pose, w[1].0.pose, "{name}: a turn that moves");
                assert!(
                    w[0].0.pose.tip.z > 100.0,
                    "{name}: turned at {:?}",
                    w[0].0.pose
                );
            }
        }
    }
}
