//! Simulating the sample impeller's finishing program (issue 19): `plan data/impeller.glb` with
//! the default job, its finishing operation's first 4,000 moves run on an `offset:0.5` blank
//! with the job's ball-end mill, at 0.1 and 0.05 mm. Three ways in one run:
//!
//! * "one solid at a time": each move's swept solids removed from the stock by
//!   `Stock::remove`, each parallel over its own rows (the path before the batched replay; the
//!   baseline);
//! * "batched, stock only": `Stock::remove_toolpath`, the batched replay on the stock alone;
//! * "simulate": `stock::simulate::simulate`, the stock and the part's gouge model together,
//!   with the shank and holder checked against the material (what `wavemill simulate --job`
//!   runs).
//!
//! Planning and the blank are set up once, outside the timings (about a minute). Read the
//! figures as moves per second (4,000 / time).

use std::path::PathBuf;

use criterion::{Criterion, criterion_group, criterion_main};
use wavemill::geom::Toolpath;
use wavemill::job::{self, Job, Quiet};
use wavemill::stock::cutter::{BallEndBody, CuttingBody};
use wavemill::stock::simulate::{SimulationOptions, simulate};
use wavemill::stock::{DEFAULT_MAX_DEXELS, Stock};
use wavemill::tool::{BodyRole, Cutter};

const MOVES: usize = 4000;

fn finishing_program(c: &mut Criterion) {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let raw = job::load_part(&root.join("data/impeller.glb"), "mm").unwrap();
    let mut job = Job::default();
    // The finishing program alone (the part taken as roughed).
    job.stock.blank = None;
    let plan = job::plan(&raw, "impeller", "mm", &job, &Quiet).unwrap();
    let finishing = plan.operations.last().unwrap().moves.clone();
    let program = Toolpath {
        tool_id: plan.toolpath.tool_id,
        moves: plan.toolpath.moves[finishing.start..(finishing.start + MOVES).min(finishing.end)]
            .to_vec(),
    };
    let assembly = job.tool.assembly();
    let Cutter::Ball {
        diameter,
        flute_length,
    } = assembly.cutter
    else {
        panic!("the default job's cutter is a ball-end mill");
    };
    let ball = BallEndBody::new(diameter, flute_length);
    let body = CuttingBody::Ball(ball);
    let options = SimulationOptions {
        tolerance: 0.01,
        non_cutting: assembly
            .bodies()
            .into_iter()
            .filter(|b| b.role != BodyRole::Flutes)
            .collect(),
        ..Default::default()
    };
    let shapes = job::stock_shapes(&plan.part, &Default::default(), &[0.5]).unwrap();
    let blank_mesh = &shapes.last().unwrap().1.mesh;

    let mut group = c.benchmark_group("simulate_sample_finishing");
    group.sample_size(10);
    for spacing in [0.1, 0.05] {
        let blank = Stock::from_mesh(blank_mesh, spacing, DEFAULT_MAX_DEXELS).unwrap();
        let split = options.tolerance.max(0.1 * spacing);
        group.bench_function(
            format!("{MOVES} moves at {spacing} mm, one solid at a time"),
            |b| {
                b.iter_batched(
                    || blank.clone(),
                    |mut stock| {
                        program
                            .moves
                            .windows(2)
                            .map(|pair| {
                                ball.sweep(&pair[0].pose, &pair[1].pose, split)
                                    .iter()
                                    .map(|solid| stock.remove(solid))
                                    .sum::<f64>()
                            })
                            .sum::<f64>()
                    },
                    criterion::BatchSize::LargeInput,
                )
            },
        );
        group.bench_function(
            format!("{MOVES} moves at {spacing} mm, batched, stock only"),
            |b| {
                b.iter_batched(
                    || blank.clone(),
                    |mut stock| stock.remove_toolpath(&program, &ball, split),
                    criterion::BatchSize::LargeInput,
                )
            },
        );
        group.bench_function(format!("{MOVES} moves at {spacing} mm, simulate"), |b| {
            b.iter_batched(
                || blank.clone(),
                |mut stock| simulate(&mut stock, &plan.part, &program, &body, &options).unwrap(),
                criterion::BatchSize::LargeInput,
            )
        });
    }
    group.finish();
}

criterion_group!(benches, finishing_program);
criterion_main!(benches);
