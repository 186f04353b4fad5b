//! The pose checks (`verify::verify`) of the sample impeller's parallel-plane finishing, each set of bodies
//! `PoseChecks` names in the same run: every body, the bodies but the flutes (what `plan`
//! asks: the back-simulation measures the flutes), the ball alone.

use std::path::PathBuf;

use criterion::{Criterion, criterion_group, criterion_main};
use wavemill::job::{self, InProcessStock, Job, OperationKind, OperationTarget, PlanSetup};
use wavemill::verify::{PoseChecks, verify};

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
}

criterion_group!(benches, pose_checks);
criterion_main!(benches);
