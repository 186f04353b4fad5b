//! `plan` for every shipped machine (`data/machines/`) in both output modes, on a small dome
//! that a debug build plans in seconds. For each program:
//!
//! * the plan's own back-simulation passes (no gouge, no rapid inside the margin, the
//!   compensation and TCP states the program declares, inverse-time F no faster than planned);
//! * read back through the verifier's forward kinematics (Rodrigues over the file's axes, not the
//!   post's inverse), the program passes through every planned pose, in order, within the
//!   rounding, and between two planned poses the ball centre stays within the tolerance of the
//!   planned straight motion;
//! * LinuxCNC's interpreter (`rs274`, when installed) reads the LinuxCNC and Fanuc joint
//!   programs with the same motions.

use crate::common;
use nalgebra::{Point3, Unit, Vector3};
use wavemill::geom::MoveKind;
use wavemill::job::{self, Job, Quiet};
use wavemill::mesh::Mesh;
use wavemill::mesh::io::RawMesh;
use wavemill::post::machine_file::{MachineDefinition, SHIPPED};
use wavemill::post::{AxisSide, Dialect, OutputMode};
use wavemill::verify::{ChainModel, MachineModel, ModelAxis, program_toolpath};

/// A dome: a spherical cap of radius 20 rising 8 mm over a 35 mm disc, on the table.
fn dome() -> Mesh {
    let (rings, sectors) = (10usize, 36usize);
    let radius: f64 = 20.0;
    let drop = radius - 8.0;
    let rim = (radius * radius - drop * drop).sqrt();
    let mut positions = vec![Point3::new(0.0, 0.0, 8.0)];
    for i in 1..=rings {
        let r = rim * i as f64 / rings as f64;
        let z = (radius * radius - r * r).sqrt() - drop;
        for k in 0..sectors {
            let a = std::f64::consts::TAU * k as f64 / sectors as f64;
            positions.push(Point3::new(r * a.cos(), r * a.sin(), z.max(0.0)));
        }
    }
    let bottom = positions.len() as u32;
    positions.push(Point3::new(0.0, 0.0, 0.0));
    let ring = |i: usize, k: usize| (1 + (i - 1) * sectors + k % sectors) as u32;
    let mut triangles = Vec::new();
    for k in 0..sectors {
        triangles.push([0, ring(1, k), ring(1, k + 1)]);
        for i in 1..rings {
            let (a, b, c, d) = (
                ring(i, k),
                ring(i + 1, k),
                ring(i + 1, k + 1),
                ring(i, k + 1),
            );
            triangles.push([a, b, c]);
            triangles.push([a, c, d]);
        }
        triangles.push([bottom, ring(rings, k + 1), ring(rings, k)]);
    }
    Mesh {
        positions,
        triangles,
    }
}

fn job_for(machine: &str, output: OutputMode) -> Job {
    let mut job = Job::default();
    job.stock.blank = Some("none".into());
    job.strategy.scallop_height = 0.05;
    job.strategy.max_step = 2.0;
    job.strategy.lead_deg = 10.0;
    job.machine.output = Some(output);
    job.use_machine(machine).expect(machine);
    job
}

/// The verifier's model of the machine as planned (the part's origin from the report).
fn model(name: &str, output: OutputMode, pivot: [f64; 3], gauge: f64, tool: u32) -> MachineModel {
    let text = SHIPPED.iter().find(|(n, _)| *n == name).unwrap().1;
    let d = MachineDefinition::parse(text, name).unwrap();
    let axis = |j: &wavemill::post::RotaryJoint| ModelAxis {
        letter: j.letter.to_string().chars().next().unwrap(),
        on_table: j.side == AxisSide::Table,
        direction: j.direction.into_inner(),
        point: j.point,
    };
    let head = [&d.chain.first, &d.chain.second]
        .iter()
        .any(|j| j.side == AxisSide::Head);
    MachineModel::Chain(ChainModel {
        axes: [axis(&d.chain.first), axis(&d.chain.second)],
        part_origin_in_table: -Vector3::from(pivot),
        head_lengths: if head {
            vec![(tool, d.pivot_length + gauge)]
        } else {
            Vec::new()
        },
        tcp: output == OutputMode::Tcp,
        tcp_in_program: d.dialect != Dialect::Linuxcnc,
        conversational: d.dialect == Dialect::Heidenhain,
    })
}

/// How the machine describes itself, as `simulate` reports it.
fn d_description(name: &str) -> String {
    let text = SHIPPED.iter().find(|(n, _)| *n == name).unwrap().1;
    let d = MachineDefinition::parse(text, name).unwrap();
    d.chain.kind.name().to_string()
}

#[test]
fn every_shipped_machine_posts_verified_programs_in_both_modes() {
    let raw = RawMesh {
        mesh: dome(),
        warnings: Vec::new(),
    };
    for (name, _) in SHIPPED {
        for output in [OutputMode::Joint, OutputMode::Tcp] {
            let what = format!("{name} {}", output.name());
            let job = job_for(name, output);
            let out = job::plan(&raw, "dome", "mm", &job, &Quiet).expect(&what);
            assert_eq!(out.verification_failure, None, "{what}");
            let r = &out.report;
            let posted = r.posted.as_ref().expect("back-simulated");
            assert!(posted.problems.is_empty(), "{what}: {:?}", posted.problems);
            let budget = &r.tolerance_budget;

            // Read back with the verifier's kinematics, finely enough for the tolerance.
            let tool = &r.tool.assembly;
            let r_ball = r.tool.ball_radius_mm;
            let model = model(
                name,
                output,
                r.machine.pivot_in_part_frame,
                tool.total_length(),
                tool.id,
            );
            let (read, _) =
                program_toolpath(&out.gcode, &model, 0.1 * budget.total_mm).expect(&what);
            let centre = |p: &wavemill::geom::ToolPose| p.tip + p.axis.into_inner() * r_ball;
            let axis_angle =
                |u: &Unit<Vector3<f64>>, v: &Unit<Vector3<f64>>| u.cross(v).norm().atan2(u.dot(v));

            // Every planned pose, in order, is a block end of the program.
            let mut at = 0;
            let mut matched: Vec<(usize, usize)> = Vec::new();
            let mut worst_pose: f64 = 0.0;
            for (i, m) in out.toolpath.moves.iter().enumerate() {
                let c = centre(&m.pose);
                let found = (at..read.moves.len()).find(|&k| {
                    let p = &read.moves[k].pose;
                    (centre(p) - c).norm() <= budget.rounding_mm + 1e-9
                        && axis_angle(&p.axis, &m.pose.axis) < 1e-5
                });
                let k =
                    found.unwrap_or_else(|| panic!("{what}: planned move {i} not in the program"));
                worst_pose = worst_pose.max((centre(&read.moves[k].pose) - c).norm());
                matched.push((i, k));
                at = k;
            }
            // Between two planned feed poses the control's path stays near the planned line.
            let mut worst_path: f64 = 0.0;
            for w in matched.windows(2) {
                let ((i0, k0), (i1, k1)) = (w[0], w[1]);
                if out.toolpath.moves[i1].kind == MoveKind::Rapid {
                    continue;
                }
                let (a, b) = (
                    centre(&out.toolpath.moves[i0].pose),
                    centre(&out.toolpath.moves[i1].pose),
                );
                for k in k0..=k1 {
                    worst_path = worst_path.max(common::segment_distance(
                        &centre(&read.moves[k].pose),
                        &a,
                        &b,
                    ));
                }
            }
            assert!(
                worst_path <= budget.total_mm - budget.chord_mm,
                "{what}: the program leaves the planned motion by {worst_path} mm"
            );
            eprintln!(
                "{what}: {} planned poses found within {worst_pose:.2e} mm; path within \
                 {worst_path:.2e} mm; {} blocks",
                out.toolpath.moves.len(),
                posted.motion_blocks
            );

            // `simulate` reads the program back for the same machine: the part comes out of an
            // offset blank with no gouge, and the read-back path is the program's.
            if matches!(
                (name, output),
                ("head-head", OutputMode::Joint) | ("head-table-bc", OutputMode::Tcp)
            ) {
                let mut options = job::SimulateOptions::new(
                    job::BlankSpec::parse("offset:0.5").unwrap(),
                    2.0 * r_ball,
                );
                options.assembly = Some(tool.clone());
                options.format = job::ProgramFormat::PostedFor(Box::new(job.clone()));
                let run =
                    job::simulate_program(&raw, "dome", &out.gcode, "job.nc", &options, &Quiet)
                        .expect(&what);
                let sim = &run.report;
                assert_eq!(sim.gouge.count, 0, "{what}: {:?}", sim.gouge);
                assert!(sim.removed_volume_mm3 > 0.0, "{what}");
                assert!(
                    sim.program_format.contains(&d_description(name)),
                    "{what}: {}",
                    sim.program_format
                );
            }

            // LinuxCNC's own interpreter reads the ISO programs it can run.
            let runnable = match name {
                "trunnion-ac" | "head-head" => true,
                "head-table-ac" => output == OutputMode::Joint,
                _ => false,
            };
            if runnable {
                let table = format!("T{0} P{0} D{1}\n", tool.id, 2.0 * r_ball);
                if let Some(motions) = common::plan_checks::rs274_motions(&out.gcode, Some(&table))
                {
                    assert_eq!(motions.len(), posted.motion_blocks, "{what}");
                }
            }
        }
    }
}

/// A machine the part does not fit is refused naming the axis and the move.
#[test]
fn a_part_beyond_the_travel_is_refused() {
    let dir = std::env::temp_dir().join(format!("wavemill-travel-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("small.toml");
    let text = SHIPPED[0].1.replace("z = [-300, 450]", "z = [-300, 20]");
    std::fs::write(&file, text).unwrap();
    let mut job = Job::default();
    job.stock.blank = Some("none".into());
    job.strategy.scallop_height = 0.05;
    job.use_machine(file.to_str().unwrap()).unwrap();
    let raw = RawMesh {
        mesh: dome(),
        warnings: Vec::new(),
    };
    let e = job::plan(&raw, "dome", "mm", &job, &Quiet)
        .err()
        .expect("refused");
    let text = e.to_string();
    assert!(
        text.contains("axis Z") && text.contains("travel") && text.contains("move"),
        "{text}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A head-head fork whose C turns only ±100° (either branch reaches every azimuth, but not
/// along a whole pass): the dome's passes swing the axis round the top further than that, so the plan unwinds (retract along the axis, turn on the safe plane,
/// re-plunge), and the program that results passes every check: C stays inside its limits in
/// the program as read back, each unwind leaves and returns to its pose along the axis, and
/// nothing touches the part.
#[test]
fn a_short_c_fork_is_unwound_on_the_safe_plane() {
    let dir = std::env::temp_dir().join(format!("wavemill-unwind-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("short-c.toml");
    let text = SHIPPED
        .iter()
        .find(|(n, _)| *n == "head-head")
        .unwrap()
        .1
        .replace("limits = [-360, 360]", "limits = [-100, 100]");
    std::fs::write(&file, text).unwrap();
    let mut job = job_for("head-head", OutputMode::Joint);
    job.use_machine(file.to_str().unwrap()).unwrap();
    let raw = RawMesh {
        mesh: dome(),
        warnings: Vec::new(),
    };
    let out = job::plan(&raw, "dome", "mm", &job, &Quiet).expect("planned with unwinds");
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(out.verification_failure, None);
    let r = &out.report;
    let unwinds = &r.machine.unwinds;
    assert!(
        !unwinds.is_empty(),
        "no unwind needed: the test lost its point"
    );
    let moves = &out.toolpath.moves;
    let along = |from: &wavemill::geom::ToolPose, to: &wavemill::geom::ToolPose| {
        let up = to.tip - from.tip;
        to.axis == from.axis && up.cross(&from.axis).norm() < 1e-9 && up.dot(&from.axis) > 0.0
    };
    for &at in unwinds {
        // Up the cut pose's axis (fed, then rapid to the safe plane), down an entry's axis
        // (rapid, then fed): the same pose, or the next segment's entry where a short link
        // was to reach it.
        let entry = (at + 1..moves.len())
            .find(|&i| moves[i].kind == MoveKind::Approach)
            .expect("re-plunged");
        let kinds: Vec<MoveKind> = moves[at + 1..entry].iter().map(|m| m.kind).collect();
        assert!(
            kinds.len() >= 3
                && kinds[0] == MoveKind::Retract
                && kinds[1..].iter().all(|&k| k == MoveKind::Rapid),
            "{kinds:?}"
        );
        // Between, only stops on the safe plane.
        let pivot = Point3::from(r.machine.pivot_in_part_frame);
        for m in &moves[at + 2..entry - 1] {
            let height = (m.pose.tip - pivot).dot(&m.pose.axis);
            assert!(height >= r.machine.safe_distance_mm - 1e-6, "{height}");
        }
        let (cut, down) = (&moves[at].pose, &moves[entry].pose);
        assert!(along(cut, &moves[at + 1].pose) && along(cut, &moves[at + 2].pose));
        assert!(along(down, &moves[entry - 1].pose) && along(down, &moves[entry - 2].pose));
    }
    // Every C word of the program, as the control reads it.
    let c: Vec<f64> = out
        .gcode
        .lines()
        .filter(|l| !l.starts_with('(') && !l.starts_with(';'))
        .flat_map(|l| l.split_whitespace())
        .filter_map(|w| w.strip_prefix('C')?.parse::<f64>().ok())
        .collect();
    assert!(c.len() > unwinds.len());
    assert!(
        c.iter().all(|&c| (-100.0..=100.0).contains(&c)),
        "C leaves its limits: {:?}",
        c.iter()
            .fold((f64::MAX, f64::MIN), |(lo, hi), &v| (lo.min(v), hi.max(v)))
    );
    eprintln!("{} unwinds", unwinds.len());
}
