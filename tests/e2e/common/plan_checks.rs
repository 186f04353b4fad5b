//! Checks of a whole plan's outputs shared by the end-to-end plan tests: written against the
//! CL data and the G-code text, with the tests' own reader, kinematics and distance oracle.

use nalgebra::Vector3;
use wavemill::job::{self, Job};

use super::{ClRow, Oracle, ac_ball_centre, read_ac_program};

/// Issue 17 item 2: inside a run of cut poses the ball centre never steps back along the
/// direction it was travelling: the projection of each step on the step before is never below
/// −1e-6 mm (the planner's passes zig-zagged along themselves by up to 0.8 mm).
pub fn passes_never_step_backwards(rows: &[ClRow], r: f64) {
    let centre = |row: &ClRow| row.tip + row.axis * r;
    let mut steps = 0;
    for run in rows.split(|row| row.kind != "cut") {
        for w in run.windows(3) {
            let before = centre(&w[1]) - centre(&w[0]);
            let step = centre(&w[2]) - centre(&w[1]);
            if before.norm() == 0.0 {
                continue;
            }
            steps += 1;
            let along = step.dot(&before.normalize());
            assert!(
                along >= -1e-6,
                "a cut step goes {along} mm back along its pass at {:?}",
                w[2]
            );
        }
    }
    assert!(steps > 1000, "{steps} steps checked");
}

/// Issue 17 items 1, 3, 4: the program as posted and rounded, read back by the tests' own
/// reader, interpolated in machine axes as the control does and turned into ball centres by
/// the tests' own forward kinematics: along every feed block the ball stays within the
/// tolerance of the part, along every rapid it keeps the shank margin. The samples are
/// 0.02 mm apart along feed blocks (0.2 mm along rapids); the report's certified minimum, a
/// lower bound for the whole curve, must not exceed what the samples find. Each block is
/// measured with the ball of the tool the program last called (a corner finish's smaller one
/// after its tool change).
pub fn posted_program_keeps_the_ball_within_the_tolerance(
    out: &job::PlanOutput,
    job: &Job,
    oracle: &Oracle,
) {
    let balls: Vec<(u32, f64)> = job
        .operations()
        .expect("the job's operations")
        .iter()
        .filter(|op| !op.kind.is_roughing())
        .map(|op| (op.tool.id, op.tool.diameter / 2.0))
        .collect();
    let radius_of = |tool: u32| {
        balls
            .iter()
            .find(|(id, _)| *id == tool)
            .map_or(job.tool.diameter / 2.0, |(_, r)| *r)
    };
    let origin = -Vector3::from(out.report.machine.pivot_in_part_frame);
    // Issue 17 item 4: the first block moved X, Y, A and C before G43 set Z. Now the first
    // block with an axis word switches length compensation on and moves Z alone.
    let first = out
        .gcode
        .lines()
        .map(|l| l.split('(').next().unwrap_or(""))
        .find(|l| l.chars().any(|c| "XYZAC".contains(c)))
        .expect("a motion block");
    assert!(
        first.contains("G43") && first.contains('Z') && !first.contains(['X', 'Y', 'A', 'C']),
        "first motion block: {first}"
    );
    let blocks = read_ac_program(&out.gcode);
    assert!(blocks.len() > 1000, "{} blocks", blocks.len());
    let (mut feed_min, mut rapid_min) = (f64::INFINITY, f64::INFINITY);
    let mut samples = 0usize;
    for w in blocks.windows(2) {
        let (from, to) = (&w[0].axes, &w[1].axes);
        let r = radius_of(w[1].tool);
        let at = |t: f64| {
            let joints: [f64; 5] = std::array::from_fn(|i| from[i] + (to[i] - from[i]) * t);
            ac_ball_centre(&joints, r, &origin)
        };
        let length: f64 = (0..16)
            .map(|k| (at((k + 1) as f64 / 16.0) - at(k as f64 / 16.0)).norm())
            .sum();
        let spacing = if w[1].rapid { 0.2 } else { 0.02 };
        let n = (length / spacing).ceil().max(1.0) as usize;
        for k in 1..=n {
            let centre = at(k as f64 / n as f64);
            let d = oracle.distance_below(&centre, r + 1.0) - r;
            samples += 1;
            if w[1].rapid {
                rapid_min = rapid_min.min(d);
            } else {
                feed_min = feed_min.min(d);
            }
        }
    }
    let posted = out
        .report
        .posted
        .as_ref()
        .expect("back-simulation in the report");
    let tolerance = job.strategy.tolerance;
    assert!(
        feed_min >= -tolerance,
        "a posted feed move cuts {} mm into the part (tolerance {tolerance}, {samples} samples)",
        -feed_min
    );
    assert!(
        posted.min_feed_clearance_mm >= -tolerance
            && posted.min_feed_clearance_mm <= feed_min + 1e-9,
        "certified {} mm vs sampled {feed_min} mm",
        posted.min_feed_clearance_mm
    );
    assert!(
        rapid_min - 0.1 >= job.safety.shank_margin,
        "a rapid passes {rapid_min} mm from the part (shank margin {})",
        job.safety.shank_margin
    );
    assert!(posted.min_rapid_clearance_mm >= job.safety.shank_margin);
    assert!(posted.problems.is_empty(), "{:?}", posted.problems);
}

/// LinuxCNC's interpreter (`rs274 -g`, Debian's `linuxcnc-uspace`) reads `gcode` into the
/// canonical motions a control would execute; those must be the blocks the tests' reader (and
/// so the back-simulation above) saw: the same kind of move to the same position in every
/// axis. Skipped, saying so, where `rs274` is not installed.
pub fn a_real_control_reads_the_program_as_the_tests_do(gcode: &str) {
    // The control's tool table holds every tool the program calls (its default one only the
    // first few numbers).
    let table: String = tool_changes(gcode)
        .iter()
        .map(|change| {
            let number = change.trim_start_matches('T').trim_end_matches(" M6");
            format!("T{number} P{number} D1 Z0\n")
        })
        .collect();
    let Some(motions) = rs274_motions(gcode, Some(&table)) else {
        return;
    };
    let motions: Vec<(bool, [f64; 5])> = motions
        .into_iter()
        .map(|(rapid, v)| (rapid, [v[0], v[1], v[2], v[3], v[5]]))
        .collect();
    let blocks = read_ac_program(gcode);
    assert!(
        motions.len() >= blocks.len() && blocks.len() > 100,
        "{} canonical motions, {} blocks",
        motions.len(),
        blocks.len()
    );
    for (block, (rapid, axes)) in blocks.iter().zip(&motions[motions.len() - blocks.len()..]) {
        assert_eq!(block.rapid, *rapid, "line {}", block.line);
        for k in 0..5 {
            assert!(
                (block.axes[k] - axes[k]).abs() < 1e-9,
                "line {}: {:?} vs the control's {axes:?}",
                block.line,
                block.axes
            );
        }
    }
}

/// The straight motions LinuxCNC's interpreter (`rs274 -g`, with `tool_table` as its tool
/// table when given) reads from `gcode`: rapid or not, and X, Y, Z, A, B, C in program
/// coordinates. `None`, saying so, where `rs274` is not installed.
#[allow(dead_code)] // each test crate uses its own part of this module
pub fn rs274_motions(gcode: &str, tool_table: Option<&str>) -> Option<Vec<(bool, [f64; 6])>> {
    let Ok(rs274) = which("rs274") else {
        eprintln!("skipped: rs274 not found (apt-get install linuxcnc-uspace)");
        return None;
    };
    // A directory of its own per call: tests run side by side in one process, and two
    // programs of one length once shared a directory, the first to finish removing the
    // other's tool table under it ("Requested tool 1 not found in the tool table").
    static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let call = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("wavemill-rs274-{}-{call}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (program, canon, table) = (
        dir.join("job.nc"),
        dir.join("job.canon"),
        dir.join("tools.tbl"),
    );
    std::fs::write(&program, gcode).unwrap();
    let mut command = std::process::Command::new(rs274);
    if let Some(text) = tool_table {
        std::fs::write(&table, text).unwrap();
        command.arg("-t").arg(&table);
    }
    let run = command
        .arg("-g")
        .arg(&program)
        .arg(&canon)
        .stdin(std::process::Stdio::null())
        .output()
        .expect("run rs274");
    assert!(
        run.status.success(),
        "rs274: {}",
        String::from_utf8_lossy(&run.stderr)
    );
    let text = std::fs::read_to_string(&canon).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    // STRAIGHT_TRAVERSE(x, y, z, a, b, c) / STRAIGHT_FEED(...), in program coordinates.
    Some(
        text.lines()
            .filter_map(|l| {
                let (rapid, rest) = if let Some(i) = l.find("STRAIGHT_TRAVERSE(") {
                    (true, &l[i + 18..])
                } else if let Some(i) = l.find("STRAIGHT_FEED(") {
                    (false, &l[i + 14..])
                } else {
                    return None;
                };
                let v: Vec<f64> = rest
                    .trim_end_matches(')')
                    .split(',')
                    .map(|x| x.trim().parse().unwrap())
                    .collect();
                Some((rapid, [v[0], v[1], v[2], v[3], v[4], v[5]]))
            })
            .collect(),
    )
}

/// `name` on the PATH.
/// The program's tool changes (`T… M6` lines), in order.
pub fn tool_changes(gcode: &str) -> Vec<&str> {
    gcode
        .lines()
        .filter(|l| l.starts_with('T') && l.ends_with(" M6"))
        .collect()
}

pub fn which(name: &str) -> Result<std::path::PathBuf, ()> {
    std::env::var_os("PATH")
        .and_then(|paths| {
            std::env::split_paths(&paths)
                .map(|p| p.join(name))
                .find(|p| p.is_file())
        })
        .ok_or(())
}
