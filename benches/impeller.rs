//! Impeller recognition (`wavemill::impeller::recognise`) on the sample impeller and, when
//! ../shared/testdata is present, the real blower: axis, symmetry check, hub and blades; and
//! the geometry of the impeller finishing from it (the hub's passage, its flow lines and one
//! blade's loops), measured in the same run against the recognition. Read both against the
//! whole plan's time (`benches/plan.rs`): they are meant to be a small part of it.

use std::path::PathBuf;

use criterion::{Criterion, criterion_group, criterion_main};
use wavemill::impeller::{HubPassage, PassageOptions, RecogniseOptions, blade_loops, recognise};
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

    let mut group = c.benchmark_group("impeller_passage_lines_and_loops");
    group.sample_size(10);
    let options = PassageOptions {
        station_step: 0.25,
        ball_radius: 2.0,
        scallop_height: 0.01,
        overlap: 1.6,
    };
    for (name, path) in parts() {
        let raw = job::load_part(&path, "mm").expect("part");
        let (mesh, _) = prepare(&raw.mesh, &PrepareOptions::default()).expect("prepared");
        let impeller = recognise(&mesh, &RecogniseOptions::default()).expect("an impeller");
        group.bench_function(&name, |b| {
            b.iter(|| {
                let passage = HubPassage::new(&mesh, &impeller, &options).expect("a passage");
                let lines = passage.flow_lines(&options);
                let loops = blade_loops(&mesh, &impeller, &passage, passage.first_blade, 0.4, 0.4);
                (lines.len(), loops.curves.len())
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
