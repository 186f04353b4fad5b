//! The checks of the sample impeller's finishing (scallop 0.05 mm, `data/impeller.toml`
//! without its blank and corner tool), each against its cheaper variant in the same run:
//! * the pose checks (`verify::verify`) of its parallel-plane finishing with each set of
//!   bodies `PoseChecks` names: every body, the bodies but the flutes (what `plan` asks: the
//!   back-simulation measures the flutes), the ball alone;
//! * the back-simulation (`verify::check_posted`) of the program `plan` posts (the impeller
//!   strategies) with the ball and its flutes' sheets, as `plan` runs it, and with the ball
//!   alone.

use std::path::PathBuf;

use criterion::{Criterion, criterion_group, criterion_main};
use wavemill::job::Quiet;
use wavemill::job::{self, InProcessStock, Job, OperationKind, OperationTarget, PlanSetup};
use wavemill::verify::{PoseChecks, PostedOptions, check_posted, verify};

fn pose_checks(c: &mut Criterion) {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let mut job = Job::load(&root.join("data/impeller.toml")).unwrap();
    job.stock.blank = None;
    job.corner_tool = None;
    job.strategy.scallop_height = 0.05;
    job.validate().unwrap();
    let part_file = root.join("data/impeller.glb");
    let raw = job::load_part(&part_file, "mm").unwrap();
    let prepared = job::prepare_part(&raw, &part_file.display().to_string(), &job).unwrap();
    let (drive, _) = job::drive_surface(&prepared.part, &job.surface).unwrap();
    let setup = PlanSetup::new(&prepared, &job).unwrap();
    let finish = job
        .operations()
        .unwrap()
        .into_iter()
        .find(|op| op.kind == OperationKind::Finish)
        .unwrap();
    let planned = job::plan_operation(
        &setup,
        &finish,
        OperationTarget::DriveSurface(&drive),
        &InProcessStock::Blank,
        None,
        &|| (),
    )
    .unwrap();
    let mut g = c.benchmark_group("pose_checks_sample_impeller_finish");
    g.sample_size(10);
    for (name, checks) in [
        ("everything", PoseChecks::Everything),
        (
            "leave_flutes_to_back_simulation",
            PoseChecks::LeaveFlutesToBackSimulation,
        ),
        ("ball_only", PoseChecks::BallOnly),
    ] {
        g.bench_function(name, |b| {
            b.iter(|| {
                verify(
                    &planned.toolpath,
                    &setup.collider,
                    &setup.prepared_tool,
                    setup.search,
                    checks,
                )
            })
        });
    }
    g.finish();

    // The program as `plan` posts it, read back with the ball and its flutes, and with the
    // ball alone.
    let output = job::plan(&raw, "impeller", "mm", &job, &Quiet).unwrap();
    let model = setup.verifier_model(&[(setup.tool.id, setup.tool.total_length())]);
    let radius = setup.prepared_tool.ball_radius;
    let flutes = setup
        .prepared_tool
        .flutes_above_ball()
        .map_or(0.0, |(length, _)| length);
    assert!(flutes > 0.0);
    let mut g = c.benchmark_group("back_simulation_sample_impeller_finish");
    g.sample_size(10);
    for (name, flutes_above_ball) in [("ball_and_flutes", flutes), ("ball_only", 0.0)] {
        let options = PostedOptions {
            ball_radius: radius,
            feed_error_mm: setup.budget.verification_mm,
            rapid_error_mm: (0.1 * job.safety.shank_margin).max(setup.budget.verification_mm),
            search_mm: setup.search,
            tool: Some(setup.tool.id),
            rounding_mm: setup.budget.rounding_mm,
            flutes_above_ball,
        };
        g.bench_function(name, |b| {
            b.iter(|| check_posted(&output.gcode, &model, &prepared.part, &options).unwrap())
        });
    }
    g.finish();
}

criterion_group!(benches, pose_checks);
criterion_main!(benches);
