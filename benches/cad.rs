//! IGES read and tessellation of the SolidWorks impeller from the shared test data (277
//! trimmed faces; skipped with a message when `../shared/testdata` is absent), with the
//! reading alone for scale; and seed 002's convex-hull boxes of the same part and their
//! layers (R6, maximum depth 6, minimum 2), the seed's model beside the one split to 6 mm.

use std::path::PathBuf;

use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::{Rotation3, Vector3};
use wavemill::cad::boxes::HullBoxes;
use wavemill::cad::iges::read_iges;
use wavemill::cad::tessellate::{TessellateOptions, tessellate};
use wavemill::rough::LayerOptions;
use wavemill::rough::boxes::{LayerMerge, box_layers};

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

fn hull_boxes_and_layers(c: &mut Criterion) {
    let Some(path) = testdata("cad/impeller_solidworks__pyvista_pyiges.igs") else {
        return;
    };
    let model = read_iges(&std::fs::read_to_string(&path).unwrap()).unwrap();
    // The file stands on its blade tips: turned over, as `--up 0,0,-1` does.
    let frame = Rotation3::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI);
    let options = LayerOptions {
        max_depth: 6.0,
        min_depth: 2.0,
        flat_band: 0.1,
        flat_area: 1.0,
    };
    let mut g = c.benchmark_group("hull_boxes_impeller");
    g.sample_size(10);
    g.bench_function("boxes", |b| {
        b.iter(|| HullBoxes::of_faces(&model.faces, frame).unwrap())
    });
    let boxes = HullBoxes::of_faces(&model.faces, frame).unwrap();
    let bounds = boxes.bounds();
    for (name, width) in [("seed", f64::INFINITY), ("width_6mm", 6.0)] {
        g.bench_function(format!("layers/{name}"), |b| {
            b.iter(|| {
                box_layers(
                    &boxes,
                    0.0,
                    bounds.max.z + 1.0,
                    bounds.min.z,
                    &options,
                    width,
                    LayerMerge::Upward,
                )
            })
        });
    }
    g.finish();
}

criterion_group!(benches, read_and_tessellate, hull_boxes_and_layers);
criterion_main!(benches);
