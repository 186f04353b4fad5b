//! Issue 17 item 8 end to end: a part with a small stray piece is still planned, and the plan
//! report says what was left out. Before, the stray triangle made the part "open" and `plan`
//! refused it (or, far enough away, the box-relative tolerances wrecked the part).

use nalgebra::Point3;
use wavemill::job::{self, Job, Quiet};
use wavemill::mesh::Mesh;
use wavemill::mesh::io::RawMesh;

/// The 30 × 30 × 10 mm block, outward, 12 triangles.
fn block() -> Mesh {
    let positions = (0..8)
        .map(|i| {
            Point3::new(
                30.0 * f64::from(i & 1),
                30.0 * f64::from((i >> 1) & 1),
                10.0 * f64::from((i >> 2) & 1),
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
    let triangles = quads
        .iter()
        .flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]])
        .collect();
    Mesh {
        positions,
        triangles,
    }
}

#[test]
fn a_block_with_a_far_stray_triangle_is_planned_and_the_triangle_reported() {
    let mut mesh = block();
    let base = mesh.positions.len() as u32;
    // 0.5 mm², 0.017 % of the block's 3000 mm², 100 m away.
    mesh.positions.extend([
        Point3::new(1e5, 0.0, 0.0),
        Point3::new(1e5 + 1.0, 0.0, 0.0),
        Point3::new(1e5, 1.0, 0.0),
    ]);
    mesh.triangles.push([base, base + 1, base + 2]);
    let raw = RawMesh {
        mesh,
        warnings: Vec::new(),
    };
    let mut job = Job::default();
    // Finishing only: the part is taken as roughed.
    job.stock.blank = None;
    job.strategy.scallop_height = 0.5;
    job.strategy.max_step = 3.0;
    let out = job::plan(&raw, "block+stray", "mm", &job, &Quiet).unwrap();
    assert!(
        out.verification_failure.is_none(),
        "{:?}",
        out.verification_failure
    );
    // The part planned is the block alone.
    assert_eq!(out.part.triangles.len(), 12);
    assert!((out.part.signed_volume() - 9000.0).abs() < 1e-9);
    let part = &out.report.part;
    assert_eq!(part.mesh.input_triangles, 13);
    assert_eq!(part.mesh.triangles, 12);
    assert!(part.mesh.watertight);
    assert_eq!(part.mesh.bounding_box_max, [30.0, 30.0, 10.0]);
    assert_eq!(part.stray_pieces.len(), 1);
    assert_eq!(part.stray_pieces[0].triangles, 1);
    assert_eq!(part.stray_pieces[0].bounding_box_min, [1e5, 0.0, 0.0]);
    assert!(
        part.warnings
            .iter()
            .any(|w| w.contains("1 stray piece set aside")),
        "{:?}",
        part.warnings
    );
    let json = out.report.to_json(false);
    assert!(json.contains("\"stray_pieces\": ["), "{json}");
}
