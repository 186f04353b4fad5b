//! Visibility maps, 10242 directions: coarse-to-fine over the direction hierarchy against brute
//! force on the same points (issue 5 item 2: hierarchical ≥ 5× faster at ≥ 99.9 % agreement).
//! Throughput is in points/s; rays/s, ray counts and the agreement are printed once per part
//! before the timings. The shared impellers are skipped when ../shared/testdata is absent.

use std::path::{Path, PathBuf};
use std::time::Instant;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use wavemill::access::{
    DirectionSet, RayScene, Refine, SurfacePoint, VisibilityOptions, vertex_points,
    visibility_brute_force, visibility_hierarchical,
};
use wavemill::job;
use wavemill::mesh::{PrepareOptions, prepare};

const POINTS: usize = 500;

fn points(path: &Path) -> (RayScene, Vec<SurfacePoint>) {
    let raw = job::load_part(path, "mm").unwrap();
    let (mesh, _) = prepare(&raw.mesh, &PrepareOptions::default()).unwrap();
    let (_, all) = vertex_points(&mesh);
    let stride = (all.len() / POINTS).max(1);
    let points = all.into_iter().step_by(stride).collect();
    (RayScene::new(&mesh), points)
}

fn parts() -> Vec<(String, PathBuf)> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let mut parts = vec![(
        "sample_impeller".to_string(),
        root.join("data/impeller.glb"),
    )];
    let shared = std::env::var_os("WAVEMILL_TESTDATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join("../shared/testdata"))
        .join("meshes");
    for (short, file) in [
        (
            "compressor",
            "impeller_compressor_splitter__omorellAUS_Impellor-V3.stl",
        ),
        (
            "blower",
            "impeller_blower_9blade__necro-nemesis_aero2205.stl",
        ),
        (
            "blower_tall",
            "impeller_blower_9blade_tall__necro-nemesis_aero2205_aggressive.stl",
        ),
    ] {
        if shared.join(file).is_file() {
            parts.push((short.to_string(), shared.join(file)));
        }
    }
    parts
}

fn visibility(c: &mut Criterion) {
    let set = DirectionSet::new(5);
    let options = VisibilityOptions::default().with_level(5);
    let mut g = c.benchmark_group("visibility_10242");
    g.sample_size(10);
    for (name, path) in parts() {
        let (scene, points) = points(&path);
        // One measured run each for the printed figures.
        let t = Instant::now();
        let brute = visibility_brute_force(&scene, &set, &points, &options).unwrap();
        let brute_s = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let hier = visibility_hierarchical(&scene, &set, &points, &options).unwrap();
        let hier_s = t.elapsed().as_secs_f64();
        println!(
            "{name}: {} points, agreement {:.4} %, rays {} hierarchical / {} brute ({:.1}x fewer), \
             time {:.3} / {:.3} s ({:.2}x faster), {:.2} / {:.2} Mrays/s",
            points.len(),
            100.0 * hier.agreement(&brute),
            hier.rays_cast,
            brute.rays_cast,
            brute.rays_cast as f64 / hier.rays_cast.max(1) as f64,
            hier_s,
            brute_s,
            brute_s / hier_s,
            hier.rays_cast as f64 / hier_s / 1e6,
            brute.rays_cast as f64 / brute_s / 1e6,
        );
        // Other refinement choices, for comparison: a coarser start (42 directions) and the
        // more cautious parent-ring rule.
        for (label, other) in [
            ("start at 42", options.clone().with_start_level(1)),
            ("triangles", options.clone().with_refine(Refine::Triangles)),
            (
                "parent rings",
                options.clone().with_refine(Refine::ParentRings),
            ),
        ] {
            let t = Instant::now();
            let maps = visibility_hierarchical(&scene, &set, &points, &other).unwrap();
            let seconds = t.elapsed().as_secs_f64();
            println!(
                "{name}: {label}: agreement {:.4} %, rays {}, {:.2}x faster than brute force",
                100.0 * maps.agreement(&brute),
                maps.rays_cast,
                brute_s / seconds
            );
        }
        g.throughput(Throughput::Elements(points.len() as u64));
        g.bench_function(format!("{name}_hierarchical"), |b| {
            b.iter(|| visibility_hierarchical(&scene, &set, &points, &options).unwrap())
        });
        g.bench_function(format!("{name}_brute_force"), |b| {
            b.iter(|| visibility_brute_force(&scene, &set, &points, &options).unwrap())
        });
    }
    g.finish();
}

criterion_group!(benches, visibility);
criterion_main!(benches);
