//! The whole `plan` on the bundled sample impeller, at a coarse and at the default scallop.

use std::path::PathBuf;

use criterion::{Criterion, criterion_group, criterion_main};
use wavemill::job::{self, Job, Quiet};

fn plan(c: &mut Criterion) {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let job_file = Job::load(&root.join("data/impeller.toml")).unwrap();
    let raw = job::load_part(&root.join("data/impeller.glb"), "mm").unwrap();
    let mut g = c.benchmark_group("plan_sample_impeller");
    g.sample_size(10);
    for scallop in [0.2, 0.05] {
        let mut job = job_file.clone();
        job.strategy.scallop_height = scallop;
        // Finishing only, as this benchmark has always measured (the part taken as roughed).
        job.stock.blank = None;
        g.bench_function(format!("scallop_{scallop}mm"), |b| {
            b.iter(|| job::plan(&raw, "impeller", "mm", &job, &Quiet).unwrap())
        });
    }
    g.finish();
}

criterion_group!(benches, plan);
criterion_main!(benches);
