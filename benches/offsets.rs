//! Intermediate shapes (issue 4 point 7): building and verifying every shape of the 65k-triangle
//! blower impeller for allowances 1.0, 0.5, 0.2, 0 mm (base 2000 + 3 levels). The hierarchy is
//! made once, outside the measurement; the build/verify split of one run is printed. Skipped
//! when the shared test data is absent.

mod common;

use criterion::{Criterion, criterion_group, criterion_main};
use wavemill::job;
use wavemill::multires::RemeshOptions;
use wavemill::offset::nested_offsets;

const ALLOWANCES: [f64; 4] = [1.0, 0.5, 0.2, 0.0];

fn blower_offsets(c: &mut Criterion) {
    let Some(part) =
        common::shared_mesh("impeller_blower_9blade__necro-nemesis_aero2205.stl", "mm")
    else {
        return;
    };
    let remesh = RemeshOptions {
        tolerance: 0.0,
        base_max_error: None,
        max_levels: ALLOWANCES.len() as u32 - 1,
        ..Default::default()
    };
    let specs = job::offset_specs(&part, &remesh, &ALLOWANCES).unwrap();
    let shapes = nested_offsets(&part, &specs).unwrap();
    for (j, s) in shapes.iter().enumerate() {
        let r = &s.report;
        eprintln!(
            "blower shape {j}: allowance {} mm, {} triangles ({}), build {:.2} s, verify {:.2} s, verified {}",
            r.allowance_mm,
            r.triangles,
            r.method.kind(),
            r.build_s,
            r.verify_s,
            r.verified
        );
    }
    let mut g = c.benchmark_group("offsets");
    g.sample_size(10);
    g.bench_function("blower_4_shapes_build_and_verify", |b| {
        b.iter(|| nested_offsets(&part, &specs).unwrap())
    });
    g.finish();
}

criterion_group!(benches, blower_offsets);
criterion_main!(benches);
