//! Freeform lens turning (seed 003) on the bundled 44 mm freeform NURBS lens (`data/lens.igs`,
//! nose radius 0.5 mm, outer diameter 40 mm): the target grid (181 radii × 360 ticks,
//! exact compensation per point), the seed's own grid parameters of its tables 6.3 and 6.5
//! (step 0.5 mm × 180 ticks; step 0.05 mm × 360 ticks), the seed's route on the 181 × 360 grid
//! for comparison (Piegl–Tiller offset to 0.1 mm — the seed's `tol` — then projection), and a
//! spiral program at 0.05 mm/rev.

use criterion::{Criterion, criterion_group, criterion_main};
use wavemill::cad::iges::read_iges;
use wavemill::lathe::offset_surface::piegl_tiller_offset;
use wavemill::lathe::{
    GridOptions, LensSurface, RadialSpacing, SpindleSpeed, SpiralOptions, compensated_grid,
    lens_from_iges, spiral,
};

fn lens() -> LensSurface {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("data/lens.igs");
    let model = read_iges(&std::fs::read_to_string(path).unwrap()).unwrap();
    lens_from_iges(&model, None).unwrap().0
}

fn grids(c: &mut Criterion) {
    let surface = lens();
    let mut g = c.benchmark_group("lens_grid_40mm");
    g.sample_size(10);
    for (name, radial, ticks) in [
        ("181x360", RadialSpacing::Count(181), 360),
        ("seed_step0.5_ticks180", RadialSpacing::Step(0.5), 180),
        ("seed_step0.05_ticks360", RadialSpacing::Step(0.05), 360),
    ] {
        let options = GridOptions {
            nose_radius: 0.5,
            diameter: 40.0,
            radial,
            ticks,
        };
        g.bench_function(format!("exact/{name}"), |b| {
            b.iter(|| compensated_grid(&surface, &options).unwrap())
        });
    }
    // The seed's route: offset surface to its tol = 0.1 mm, then the 181 × 360 projection.
    g.bench_function("piegl_tiller_offset/tol0.1", |b| {
        b.iter(|| piegl_tiller_offset(&surface, 0.5, 0.1).unwrap())
    });
    let offset = piegl_tiller_offset(&surface, 0.5, 0.1)
        .unwrap()
        .as_lens()
        .unwrap();
    g.bench_function("projection_onto_offset/181x360", |b| {
        b.iter(|| {
            let mut sum = 0.0;
            for i in 0..181 {
                let r = 20.0 * i as f64 / 180.0;
                for j in 0..360 {
                    let a = (j as f64).to_radians();
                    let (u, v) = offset.parameters_over(r * a.cos(), r * a.sin()).unwrap();
                    sum += offset.jet(u, v).point.z;
                }
            }
            sum
        })
    });
    g.finish();
}

fn spirals(c: &mut Criterion) {
    let surface = lens();
    let mut g = c.benchmark_group("lens_spiral_40mm");
    g.sample_size(10);
    let options = SpiralOptions {
        nose_radius: 0.5,
        outer_radius: 20.0,
        feed_per_rev: 0.05,
        form_tolerance: 2e-4,
        max_step: 5f64.to_radians(),
        speed: SpindleSpeed::ConstantRpm(300.0),
    };
    g.bench_function("feed0.05_tol0.0002", |b| {
        b.iter(|| spiral(&surface, &options).unwrap())
    });
    g.finish();
}

criterion_group!(benches, grids, spirals);
criterion_main!(benches);
