//! IGES read and tessellation of the SolidWorks impeller from the shared test data (277
//! trimmed faces; skipped with a message when `../shared/testdata` is absent). Beside it, the
//! same part's reading alone and the blower STL's read + prepare, for scale.

use std::path::PathBuf;

use criterion::{Criterion, criterion_group, criterion_main};
use wavemill::cad::iges::read_iges;
use wavemill::cad::tessellate::{TessellateOptions, tessellate};

fn testdata(rel: &str) -> Option<PathBuf> {
    let p = std::env::var_os("WAVEMILL_TESTDATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/testdata"))
        .join(rel);
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

fn read_and_tessellate(c: &mut Criterion) {
    let Some(path) = testdata("cad/impeller_solidworks__pyvista_pyiges.igs") else {
        return;
    };
    let mut g = c.benchmark_group("iges_impeller_277_faces");
    g.sample_size(10);
    g.bench_function("read", |b| {
        b.iter(|| {
            let text = std::fs::read_to_string(&path).unwrap();
            read_iges(&text).unwrap()
        })
    });
    for tolerance in [0.01, 0.05] {
        g.bench_function(format!("read+tessellate/{tolerance}mm"), |b| {
            b.iter(|| {
                let text = std::fs::read_to_string(&path).unwrap();
                let model = read_iges(&text).unwrap();
                tessellate(&model.faces, &TessellateOptions { tolerance }).unwrap()
            })
        });
    }
    g.finish();
}

criterion_group!(benches, read_and_tessellate);
criterion_main!(benches);
