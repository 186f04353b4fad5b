//! Multiresolution benchmarks: Loop subdivision throughput (output triangles/s; compare with
//! `scripts/time_trimesh_loop.py` on the same mesh), the 1-to-4 split's connectivity alone,
//! quadric simplification to a base mesh, and lifting-wavelet analysis + synthesis at three
//! sizes (linear scaling expected).

mod common;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use wavemill::job;
use wavemill::mesh::{PrepareOptions, prepare};
use wavemill::multires::{
    Creases, Hierarchy, RemeshOptions, SimplifyOptions, WaveletHierarchy, loop_subdivide, simplify,
    split,
};

fn sample_blade() -> wavemill::mesh::Mesh {
    let root = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let raw = job::load_part(&root.join("data/blade.glb"), "mm").unwrap();
    prepare(&raw.mesh, &PrepareOptions::default()).unwrap().0
}

fn subdivision(c: &mut Criterion) {
    // The 18.7k-triangle sample blade, two levels: 300k output triangles.
    let blade = sample_blade();
    let mut g = c.benchmark_group("loop_subdivision");
    g.sample_size(10);
    let out = 16 * blade.triangles.len() as u64;
    g.throughput(Throughput::Elements(out));
    g.bench_function("blade_2_levels_output_triangles", |b| {
        b.iter(|| loop_subdivide(&blade, &Creases::none(), 2).unwrap())
    });
    g.finish();
}

/// The connectivity of one 1-to-4 split (numbering, DESIGN.md §3.1) of the sample blade after
/// two levels (300k triangles), without positions: the part of a subdivision step that the
/// wavelet transform reuses.
fn split_connectivity(c: &mut Criterion) {
    let (fine, _) = loop_subdivide(&sample_blade(), &Creases::none(), 2).unwrap();
    let mut g = c.benchmark_group("split");
    g.sample_size(10);
    g.throughput(Throughput::Elements(4 * fine.triangles.len() as u64));
    g.bench_function("blade_300k_to_1.2M_triangles", |b| {
        b.iter(|| split(&fine.triangles, fine.positions.len()))
    });
    g.finish();
}

/// Quadric simplification of the sample impeller (38.5k triangles) to the base sizes the
/// remesher asks for.
fn simplification(c: &mut Criterion) {
    let root = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let raw = job::load_part(&root.join("data/impeller.glb"), "mm").unwrap();
    let impeller = prepare(&raw.mesh, &PrepareOptions::default()).unwrap().0;
    let mut g = c.benchmark_group("simplify");
    g.sample_size(10);
    for target in [2000usize, 8000] {
        g.bench_with_input(
            BenchmarkId::from_parameter(format!("impeller_to_{target}")),
            &target,
            |b, &target| {
                b.iter(|| simplify(&impeller, &SimplifyOptions::with_target(target)).unwrap())
            },
        );
    }
    g.finish();
}

fn wavelets(c: &mut Criterion) {
    let blade = sample_blade();
    let mut g = c.benchmark_group("wavelet_analysis_synthesis");
    g.sample_size(10);
    for levels in [1u32, 2, 3] {
        let hierarchy = WaveletHierarchy::new(
            &blade.triangles,
            blade.positions.len(),
            &Creases::none(),
            levels as usize,
        )
        .unwrap();
        let (fine, _) = loop_subdivide(&blade, &Creases::none(), levels).unwrap();
        g.throughput(Throughput::Elements(fine.positions.len() as u64));
        g.bench_with_input(
            BenchmarkId::from_parameter(format!("{}_vertices", fine.positions.len())),
            &fine,
            |b, fine| {
                b.iter(|| {
                    let w = hierarchy.analyse_all(&fine.positions).unwrap();
                    hierarchy.synthesise_all(&w).unwrap()
                })
            },
        );
    }
    g.finish();
}

/// Remeshing the 65k-triangle blower impeller with the default options until the finest level
/// is within 0.01 mm (base ~17k triangles + 3 levels, 1.1 M triangles, Hausdorff measured per
/// level); skipped when the shared test data is absent.
fn remeshing(c: &mut Criterion) {
    let Some(mesh) =
        common::shared_mesh("impeller_blower_9blade__necro-nemesis_aero2205.stl", "mm")
    else {
        return;
    };
    let options = RemeshOptions::default();
    let mut g = c.benchmark_group("remesh");
    g.sample_size(10);
    g.bench_function("blower_65k_to_0.01mm", |b| {
        b.iter(|| {
            let h = Hierarchy::build(&mesh, &options).unwrap();
            assert!(h.finest().hausdorff <= options.tolerance);
            h
        })
    });
    g.finish();
}

criterion_group!(
    benches,
    subdivision,
    split_connectivity,
    simplification,
    wavelets,
    remeshing
);
criterion_main!(benches);
