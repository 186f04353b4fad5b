//! Impeller recognition (`wavemill::impeller::recognise`) on the sample impeller and, when
//! ../shared/testdata is present, the real blower: axis, symmetry check, hub and blades. Read
//! it against the whole plan's time (`benches/plan.rs`): the recognition is meant to be a
//! small part of it.

use std::path::PathBuf;

use criterion::{Criterion, criterion_group, criterion_main};
use wavemill::impeller::{RecogniseOptions, recognise};
use wavemill::job;
use wavemill::mesh::{PrepareOptions, prepare};

fn parts() -> Vec<(String, PathBuf)> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let mut parts = vec![("sample".to_string(), root.join("data/impeller.glb"))];
    let blower =
        root.join("../shared/testdata/meshes/impeller_blower_9blade__necro-nemesis_aero2205.stl");
    if blower.exists() {
        parts.push(("blower".to_string(), blower));
    } else {
        eprintln!("skipped the blower: ../shared/testdata is absent");
    }
    parts
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("impeller_recognise");
    group.sample_size(10);
    for (name, path) in parts() {
        let raw = job::load_part(&path, "mm").expect("part");
        let (mesh, _) = prepare(&raw.mesh, &PrepareOptions::default()).expect("prepared");
        group.bench_function(&name, |b| {
            b.iter(|| recognise(&mesh, &RecogniseOptions::default()).expect("an impeller"))
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
