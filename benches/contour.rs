//! 2.5D contour paths (issue 6) on the project's sample outline `data/mountain.svg`, flat 6 mm,
//! stepover 2.4 mm, a 10 mm margin: the contour-parallel baseline, the multiresolution
//! (wavelet + loose hull) planner, and the engagement replay `compare.json` runs on a path —
//! read them as ratios to the baseline, measured in the same run.

use std::path::PathBuf;

use criterion::{Criterion, criterion_group, criterion_main};
use wavemill::contour::geometry::{Contour, Shape, Vertex};
use wavemill::contour::material::{engagement, report_cell};
use wavemill::contour::{
    MultiresOptions, OutlineOptions, ParallelOptions, contour_parallel, multires_paths,
    read_outline,
};

fn mountain() -> (Shape, Shape) {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/mountain.svg");
    let part = read_outline(&path, &OutlineOptions::default()).unwrap();
    let points = part
        .contours
        .iter()
        .flat_map(|c| c.vertices.iter().map(|v| v.point));
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in points {
        lo = [lo[0].min(p.x), lo[1].min(p.y)];
        hi = [hi[0].max(p.x), hi[1].max(p.y)];
    }
    // The bounding box of the vertices (the arcs bulge past it by little) grown by 10 mm.
    let m = 10.0;
    let stock = Shape {
        contours: vec![Contour {
            vertices: vec![
                Vertex::line(lo[0] - m, lo[1] - m),
                Vertex::line(hi[0] + m, lo[1] - m),
                Vertex::line(hi[0] + m, hi[1] + m),
                Vertex::line(lo[0] - m, hi[1] + m),
            ],
        }],
    };
    (part, stock)
}

fn planners(c: &mut Criterion) {
    let (part, stock) = mountain();
    let (r, s) = (3.0, 2.4);
    let mut group = c.benchmark_group("contour_mountain");
    group.sample_size(10);
    group.bench_function("contour_parallel", |b| {
        b.iter(|| contour_parallel(&part, &stock, &ParallelOptions::new(r, s)).unwrap())
    });
    group.bench_function("multires_wavelet_hull", |b| {
        b.iter(|| multires_paths(&part, &stock, &MultiresOptions::new(r, s)).unwrap())
    });
    let path = contour_parallel(&part, &stock, &ParallelOptions::new(r, s)).unwrap();
    group.bench_function("engagement_replay", |b| {
        b.iter(|| engagement(&path, &part, &stock, report_cell(r, s), r).unwrap())
    });
    group.finish();
}

criterion_group!(benches, planners);
criterion_main!(benches);
