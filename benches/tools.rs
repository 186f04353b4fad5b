//! Collision queries and tool choice (issue 5 items 4 and 6), on the sample impeller.
//!
//! Throughput in queries/s for the exact f64 ball test (BVH signed distance) and the ball's
//! sweep up its axis to a safe plane (the BVH with the triangles' fences), each against the
//! same test triangle by triangle (the baseline, same run), and for the parry tests of a ball tool's
//! flutes/shank/holder and of flat and bull-nose ends touching the point along its normal; then
//! the whole `choose_tools` over 2000 points with `data/tools.toml`.

use std::path::PathBuf;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use wavemill::collide::{Margins, PartCollider, PreparedTool};
use wavemill::geom::ToolPose;
use wavemill::geom::{
    Point3, Vector3, closest_point_on_triangle, segment_triangle_distance_squared,
};
use wavemill::job;
use wavemill::mesh::{Mesh, PrepareOptions, prepare};
use wavemill::tool::{Cutter, Section, ToolAssembly, ToolLibrary};
use wavemill::tool_choice::{ToolChoiceOptions, choose_tools};

const POINTS: usize = 500;

fn sample_impeller() -> Mesh {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/impeller.glb");
    let raw = job::load_part(&path, "mm").unwrap();
    prepare(&raw.mesh, &PrepareOptions::default()).unwrap().0
}

fn tool(cutter: Cutter) -> ToolAssembly {
    ToolAssembly {
        id: 1,
        name: String::new(),
        cutter,
        neck: None,
        shank_diameter: 6.0,
        stickout: 40.0,
        holder: vec![
            Section {
                diameter: 21.0,
                top_diameter: Some(27.0),
                length: 40.0,
            },
            Section::cylinder(50.0, 40.0),
        ],
    }
}

fn collision_queries(c: &mut Criterion) {
    let part = sample_impeller();
    let collider = PartCollider::new(&part).unwrap();
    let normals = part.vertex_normals();
    let stride = part.positions.len() / POINTS;
    let points: Vec<(Point3, Vector3)> = (0..part.positions.len())
        .step_by(stride.max(1))
        .filter(|&v| normals[v].norm() > 0.5)
        .map(|v| (part.positions[v], normals[v]))
        .collect();
    let margins = Margins {
        shank: 0.5,
        holder: 2.0,
    };
    let r = 3.0;
    let ball = PreparedTool::new(
        &tool(Cutter::Ball {
            diameter: 2.0 * r,
            flute_length: 12.0,
        }),
        &margins,
    );
    let flat = PreparedTool::new(
        &tool(Cutter::Flat {
            diameter: 6.0,
            flute_length: 12.0,
        }),
        &margins,
    );
    let bull = PreparedTool::new(
        &tool(Cutter::BullNose {
            diameter: 6.0,
            corner_radius: 1.0,
            flute_length: 12.0,
        }),
        &margins,
    );
    let triangles: Vec<[Point3; 3]> = (0..part.triangles.len()).map(|t| part.corners(t)).collect();

    let mut g = c.benchmark_group("collision_queries_sample_impeller");
    g.sample_size(10);
    g.throughput(Throughput::Elements(points.len() as u64));
    g.bench_function("ball_exact_bvh", |b| {
        b.iter(|| {
            points
                .iter()
                .filter(|(p, n)| collider.check_ball(&(p + n * r), r, 0.01).is_ok())
                .count()
        })
    });
    g.bench_function("ball_exact_triangle_by_triangle", |b| {
        b.iter(|| {
            points
                .iter()
                .filter(|(p, n)| {
                    let centre = p + n * r;
                    triangles.iter().all(|[a, bb, cc]| {
                        (closest_point_on_triangle(&centre, a, bb, cc).0 - centre).norm()
                            >= r - 0.01
                    })
                })
                .count()
        })
    });
    g.bench_function("ball_tool_bodies_parry", |b| {
        b.iter(|| {
            points
                .iter()
                .filter(|(p, n)| {
                    let pose = ToolPose {
                        tip: p + n * r - n * r,
                        axis: wavemill::geom::Direction::new_normalize(*n),
                    };
                    collider.check_bodies(&ball, &pose).is_ok()
                })
                .count()
        })
    });
    // The ball leaving along its axis for a safe plane 60 mm up (linking's test), decided
    // in f64 with the fences against the same test triangle by triangle.
    let sweep = 60.0;
    g.bench_function("ball_sweep_to_safe_plane_fenced", |b| {
        b.iter(|| {
            points
                .iter()
                .filter(|(p, n)| {
                    let pose = ToolPose {
                        tip: *p,
                        axis: wavemill::geom::Direction::new_normalize(*n),
                    };
                    collider.check_ball_sweep(&ball, &pose, sweep).is_ok()
                })
                .count()
        })
    });
    g.bench_function("ball_sweep_to_safe_plane_triangle_by_triangle", |b| {
        b.iter(|| {
            points
                .iter()
                .filter(|(p, n)| {
                    let (from, to) = (p + n * r, p + n * (r + sweep));
                    let limit = (r - 1e-3) * (r - 1e-3);
                    triangles.iter().all(|[a, bb, cc]| {
                        segment_triangle_distance_squared(&from, &to, a, bb, cc) >= limit
                    })
                })
                .count()
        })
    });
    for (name, prepared) in [
        ("flat_end_touching", &flat),
        ("bull_nose_end_touching", &bull),
    ] {
        g.bench_function(name, |b| {
            b.iter(|| {
                points
                    .iter()
                    .filter(|(p, n)| collider.check_touching(prepared, p, n, n, 0.01).is_ok())
                    .count()
            })
        });
    }
    g.finish();

    let library =
        ToolLibrary::read(&PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/tools.toml"))
            .unwrap();
    let options = ToolChoiceOptions {
        max_points: 2000,
        ..Default::default()
    };
    let mut g = c.benchmark_group("tool_choice_sample_impeller");
    g.sample_size(10);
    g.throughput(Throughput::Elements(2000));
    g.bench_function("choose_tools_2000_points_12_tools", |b| {
        b.iter(|| {
            choose_tools(&part, &library, &options)
                .unwrap()
                .points
                .len()
        })
    });
    g.finish();
}

criterion_group!(benches, collision_queries);
criterion_main!(benches);
