//! Layer roughing (`wavemill::rough`) of four 20 × 20 × 10 blocks on a 2 × 2 grid, 14 mm
//! apart, in an 80 × 80 × 12 box blank, with a D12 end mill at 0.8 r stepover: every pass
//! straight (the first pass into each channel between blocks is a slot) against the default
//! engagement bound of half the diameter, where those slots become trochoidal loops. Read the
//! loops as a ratio to the straight plan measured in the same run.

use criterion::{Criterion, criterion_group, criterion_main};
use wavemill::geom::Point3;
use wavemill::mesh::Mesh;
use wavemill::rough::{Blank, Material, RoughingOptions, RoughingTool, rough_layers};

/// An axis-aligned box from `min` to `max`, outward.
fn cuboid(min: [f64; 3], max: [f64; 3]) -> Mesh {
    let positions = (0..8)
        .map(|i| {
            Point3::new(
                if i & 1 != 0 { max[0] } else { min[0] },
                if i & 2 != 0 { max[1] } else { min[1] },
                if i & 4 != 0 { max[2] } else { min[2] },
            )
        })
        .collect();
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    Mesh {
        positions,
        triangles: quads
            .iter()
            .flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]])
            .collect(),
    }
}

fn four_blocks() -> Mesh {
    let mut mesh = Mesh {
        positions: Vec::new(),
        triangles: Vec::new(),
    };
    for (x, y) in [(-27.0, -27.0), (7.0, -27.0), (-27.0, 7.0), (7.0, 7.0)] {
        let block = cuboid([x, y, 0.0], [x + 20.0, y + 20.0, 10.0]);
        let base = mesh.positions.len() as u32;
        mesh.positions.extend(block.positions);
        mesh.triangles.extend(
            block
                .triangles
                .iter()
                .map(|t| [t[0] + base, t[1] + base, t[2] + base]),
        );
    }
    mesh
}

fn layers(c: &mut Criterion) {
    let shape = four_blocks();
    let blank = Blank::cuboid(
        Point3::new(-40.0, -40.0, 0.0),
        Point3::new(40.0, 40.0, 12.0),
    );
    let tool = RoughingTool {
        radius: 6.0,
        flute_length: 26.0,
        reach: 60.0,
    };
    let mut looped = RoughingOptions::for_radius(6.0);
    looped.floor = Some(0.0);
    let straight = RoughingOptions {
        max_engagement: None,
        ..looped.clone()
    };
    let mut group = c.benchmark_group("rough_four_blocks");
    group.sample_size(10);
    for (name, options) in [("straight", &straight), ("loops", &looped)] {
        group.bench_function(name, |b| {
            b.iter(|| rough_layers(&shape, &blank, &tool, 1, Material::Blank, options).unwrap())
        });
    }
    group.finish();
}

criterion_group!(benches, layers);
criterion_main!(benches);
