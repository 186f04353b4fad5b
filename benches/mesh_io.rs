//! Mesh input and collision-structure benchmarks on the 65k-triangle blower impeller from the
//! shared test data (skipped with a message when `../shared/testdata` is absent).

use std::path::PathBuf;

use criterion::{Criterion, criterion_group, criterion_main};
use wavemill::access::RayScene;
use wavemill::collide::PartCollider;
use wavemill::mesh::io::{Units, read_mesh};
use wavemill::mesh::{PrepareOptions, prepare};

fn blower() -> Option<PathBuf> {
    let p = std::env::var_os("WAVEMILL_TESTDATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/testdata"))
        .join("meshes/impeller_blower_9blade__necro-nemesis_aero2205.stl");
    if p.is_file() {
        Some(p)
    } else {
        eprintln!(
            "skipped: {} not found (shared test data is beside the clone on CI)",
            p.display()
        );
        None
    }
}

fn load_and_weld(c: &mut Criterion) {
    let Some(path) = blower() else { return };
    let mut g = c.benchmark_group("blower_65k");
    g.sample_size(10);
    g.bench_function("read_stl", |b| {
        b.iter(|| read_mesh(&path, Units::Millimetres).unwrap())
    });
    let raw = read_mesh(&path, Units::Millimetres).unwrap();
    g.bench_function("read_stl+prepare(weld, clean, orient)", |b| {
        b.iter(|| {
            let raw = read_mesh(&path, Units::Millimetres).unwrap();
            prepare(&raw.mesh, &PrepareOptions::default()).unwrap()
        })
    });
    let (mesh, _) = prepare(&raw.mesh, &PrepareOptions::default()).unwrap();
    g.bench_function("bvh_build/exact_f64+parry", |b| {
        b.iter(|| PartCollider::new(&mesh).unwrap())
    });
    g.bench_function("bvh_build/obvhs_rays", |b| b.iter(|| RayScene::new(&mesh)));
    g.finish();
}

criterion_group!(benches, load_and_weld);
criterion_main!(benches);
