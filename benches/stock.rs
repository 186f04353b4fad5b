//! Tri-dexel stock removal (issue 19): a ball-end mill (6 mm, 18 mm flutes) along a zig-zag of
//! 0.5 mm moves 1 mm apart, its axis leaning 15° and turning slowly about Z, at 0.1 and 0.05 mm
//! spacing, through two 40 mm square blocks: a "skin" whose top is 0.5 mm above the tip (a
//! finishing pass: the body above is in air) and a "buried" one reaching past the flutes (the
//! worst case: every line the body crosses holds material); each move split to a tenth of the
//! spacing. Read the figures as moves per
//! second, and the two spacings as a ratio. "one solid at a time" is the same skin at 0.1 mm
//! with each solid removed by `Stock::remove` (parallel over one solid's rows), the baseline
//! the batched replay of `remove_toolpath` is measured against.

use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::Unit;
use wavemill::geom::{Aabb, Move, MoveKind, Point3, ToolPose, Toolpath, Vector3};
use wavemill::stock::cutter::BallEndBody;
use wavemill::stock::{DEFAULT_MAX_DEXELS, Stock};

/// 400 moves of 0.5 mm: ten 20 mm rows, 1 mm apart.
fn zig_zag() -> Toolpath {
    let mut moves = Vec::new();
    for row in 0..10 {
        for step in 0..=40 {
            let along = if row % 2 == 0 { step } else { 40 - step } as f64 * 0.5;
            let (x, y) = (-10.0 + along, -5.0 + row as f64);
            let turn = (moves.len() as f64 * 0.2).to_radians();
            let lean = 15f64.to_radians();
            let axis = Vector3::new(lean.sin() * turn.cos(), lean.sin() * turn.sin(), lean.cos());
            moves.push(Move {
                pose: ToolPose {
                    tip: Point3::new(x, y, 9.5),
                    axis: Unit::new_normalize(axis),
                },
                kind: if moves.is_empty() {
                    MoveKind::Rapid
                } else {
                    MoveKind::Cut
                },
                feed: 2000.0,
            });
        }
    }
    Toolpath { tool_id: 1, moves }
}

fn removal(c: &mut Criterion) {
    let path = zig_zag();
    let body = BallEndBody::new(6.0, 18.0);
    let mut group = c.benchmark_group("stock");
    group.sample_size(10);
    // A skin: material only 0.5 mm above the tip, as on a finishing pass; the shank is in air.
    let skin = Aabb::from_points(&[
        Point3::new(-20.0, -20.0, -10.0),
        Point3::new(20.0, 20.0, 10.0),
    ]);
    {
        let spacing = 0.1;
        let blank = Stock::block(&skin, spacing, DEFAULT_MAX_DEXELS).unwrap();
        group.bench_function("skin, 400 moves at 0.1 mm, one solid at a time", |b| {
            b.iter_batched(
                || blank.clone(),
                |mut stock| {
                    path.moves
                        .windows(2)
                        .map(|pair| {
                            body.sweep(&pair[0].pose, &pair[1].pose, spacing / 10.0)
                                .iter()
                                .map(|solid| stock.remove(solid))
                                .sum::<f64>()
                        })
                        .sum::<f64>()
                },
                criterion::BatchSize::LargeInput,
            )
        });
    }
    for spacing in [0.1, 0.05] {
        let blank = Stock::block(&skin, spacing, DEFAULT_MAX_DEXELS).unwrap();
        group.bench_function(format!("skin, 400 moves at {spacing} mm"), |b| {
            b.iter_batched(
                || blank.clone(),
                |mut stock| stock.remove_toolpath(&path, &body, spacing / 10.0),
                criterion::BatchSize::LargeInput,
            )
        });
    }
    let bounds = Aabb::from_points(&[
        Point3::new(-20.0, -20.0, -10.0),
        Point3::new(20.0, 20.0, 30.0),
    ]);
    for spacing in [0.1, 0.05] {
        let blank = Stock::block(&bounds, spacing, DEFAULT_MAX_DEXELS).unwrap();
        group.bench_function(format!("buried, 400 moves at {spacing} mm"), |b| {
            b.iter_batched(
                || blank.clone(),
                |mut stock| stock.remove_toolpath(&path, &body, spacing / 10.0),
                criterion::BatchSize::LargeInput,
            )
        });
    }
    group.finish();
}

criterion_group!(benches, removal);
criterion_main!(benches);
