//! `plan` from a blank: with a `[stock]` box and no listed operations, the job roughs with the
//! bundled library's largest end mill that reaches the floor, rest-roughs with a smaller one,
//! then finishes with the job's ball; one program with a tool change before each tool.
//!
//! The part is a square frustum (40 × 40 at the table, 20 × 20 on top, 15 high), small enough
//! for a debug build and with square horizontal sections narrowing upward, so every roughing
//! pose's distance to it can be measured from those sections: no code of the planner or of its
//! own checks is used to judge it.

use crate::common;
use nalgebra::Point3;
use wavemill::geom::MoveKind;
use wavemill::job::{self, Job, Quiet};
use wavemill::mesh::Mesh;
use wavemill::mesh::io::RawMesh;

const HEIGHT: f64 = 15.0;

fn frustum() -> Mesh {
    let positions = (0..8)
        .map(|i| {
            let top = i & 4 != 0;
            let (lo, hi) = if top { (10.0, 30.0) } else { (0.0, 40.0) };
            Point3::new(
                if i & 1 != 0 { hi } else { lo },
                if i & 2 != 0 { hi } else { lo },
                if top { HEIGHT } else { 0.0 },
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

/// Distance in the plane from `c` to the frustum's square section at height `z` (0 ≤ z ≤ 15):
/// [s, 40 − s]² with s = 2z/3.
fn section_distance(c: &Point3<f64>, z: f64) -> f64 {
    let s = 2.0 * z / 3.0;
    let dx = (s - c.x).max(c.x - (40.0 - s)).max(0.0);
    let dy = (s - c.y).max(c.y - (40.0 - s)).max(0.0);
    dx.hypot(dy)
}

/// The distance between the frustum and a vertical cylinder of `radius` standing on `tip` and
/// reaching up without end, from the frustum's sections: a section at or above the tip is
/// nearest at its widest (the lowest, as the frustum narrows upward); one below the tip is
/// `z₀ − z` down and its distance in the plane beyond the radius across, minimised over the
/// heights in steps of 0.002 mm (the distance changes by less than a step per step).
fn cylinder_clearance(tip: &Point3<f64>, radius: f64) -> f64 {
    let z0 = tip.z;
    let above = if z0 <= HEIGHT {
        (section_distance(tip, z0.max(0.0)) - radius).max(0.0)
    } else {
        f64::INFINITY
    };
    let top = z0.min(HEIGHT);
    let steps = (top / 0.002).ceil().max(0.0) as usize;
    let below = (0..=steps)
        .map(|k| (k as f64 * 0.002).min(top))
        .map(|z| (section_distance(tip, z) - radius).max(0.0).hypot(z0 - z))
        .fold(f64::INFINITY, f64::min);
    above.min(below)
}

fn job_from_box() -> Job {
    let mut job = Job::default();
    job.strategy.scallop_height = 0.3;
    job.strategy.max_step = 2.0;
    job.stock.blank = Some("box:-3,-3,0,43,43,18".into());
    job.stock.resolution = Some(0.4);
    job
}

#[test]
fn a_frustum_is_roughed_rest_roughed_and_finished_from_a_box_in_one_program() {
    let job = job_from_box();
    let raw = RawMesh {
        mesh: frustum(),
        warnings: Vec::new(),
    };
    let out = job::plan(&raw, "frustum", "mm", &job, &Quiet).expect("plan");
    assert_eq!(out.verification_failure, None);
    let r = &out.report;

    // The bundled library: the bull-nose D12 roughs, the flat D6 rest-roughs, then the ball.
    let tools: Vec<u32> = r.roughing.iter().map(|t| t.tool_id).collect();
    assert_eq!(tools, vec![2, 7]);
    assert_eq!(
        common::plan_checks::tool_changes(&out.gcode),
        ["T2 M6", "T7 M6", "T1 M6"]
    );

    // Each roughing tool's posted moves, by the plan's exact check, stay outside its offset
    // shape; and every planned roughing pose, by the closed-form check here, keeps the tool's
    // whole radius at least the allowance (less the chord tolerance) off the part.
    let allowance = job.roughing.allowance;
    for (summary, span) in r.roughing.iter().zip(&out.operations) {
        let shape = summary.overcut_vs_shape.as_ref().expect("checked");
        assert!(shape.overcuts.is_empty(), "T{}", summary.tool_id);
        let radius = summary.planning.radius;
        let moves = &out.toolpath.moves[span.moves.clone()];
        assert!(moves.iter().all(|m| m.pose.axis.z == 1.0));
        assert!(moves.iter().filter(|m| m.kind == MoveKind::Cut).count() > 50);
        let closest = moves
            .iter()
            // Far from the part either way: no need to measure finely.
            .filter(|m| m.pose.tip.z < HEIGHT + allowance + 1.0)
            .filter(|m| section_distance(&m.pose.tip, 0.0) < radius + allowance + 1.0)
            .map(|m| cylinder_clearance(&m.pose.tip, radius))
            .fold(f64::INFINITY, f64::min);
        assert!(
            closest >= allowance - job.strategy.tolerance,
            "T{}: {closest}",
            summary.tool_id
        );
        // Feed control: every cutting move within the machine's limits and at most the target
        // force (none needed the minimum feed here), the whole faster than as programmed.
        let feed = summary
            .feed_control
            .as_ref()
            .expect("feed control is on by default");
        let limits = job.cutting.min_feed..=job.cutting.max_feed;
        assert!(
            moves
                .iter()
                .filter(|m| m.kind != MoveKind::Rapid)
                .all(|m| limits.contains(&m.feed))
        );
        assert_eq!(feed.over_target_at_min_feed, 0);
        assert!(feed.force_after.max <= feed.target_force_n * (1.0 + 1e-9));
        assert!(
            feed.force_after.max <= feed.force_before.max.max(feed.target_force_n) + 1e-9,
            "{feed:?}"
        );
        assert!(feed.time_after_s < feed.time_before_s);
        // The tip never goes below the floor the table margin sets.
        assert!(
            moves
                .iter()
                .all(|m| m.pose.tip.z >= job.safety.table_margin - 1e-9)
        );
    }

    // On the stock: each operation removes material, none touches it with a non-cutting body
    // or rapids through it; the rest tool cuts less than the first; finishing leaves the
    // faces it reaches within a few hundredths.
    let stock = r.stock.as_ref().expect("stock run");
    let names: Vec<&str> = stock.operations.iter().map(|o| o.name.as_str()).collect();
    assert_eq!(
        names,
        vec!["rough to 0.5 mm", "rest-rough to 0.5 mm", "finish"]
    );
    for o in &stock.operations {
        assert_eq!(
            (o.gouge.count, o.collision_count, o.rapids_through_material),
            (0, 0, 0),
            "{}",
            o.name
        );
        assert!(o.removed_volume_mm3 > 0.0, "{}", o.name);
    }
    let (rough, rest, finish) = (
        &stock.operations[0],
        &stock.operations[1],
        &stock.operations[2],
    );
    assert!(rest.removed_volume_mm3 < rough.removed_volume_mm3);
    assert!(rest.rest.mean_mm <= rough.rest.mean_mm);
    assert!(finish.rest.mean_mm < rest.rest.mean_mm);
    // The finishing links that would have rapided into the rest were slowed to feed.
    assert!(r.rapids_fed_through_rest.is_some());

    // The ball's program, as posted, within the tolerance of the part.
    let posted = r.posted.as_ref().expect("posted check");
    assert!(posted.min_feed_clearance_mm >= -job.strategy.tolerance);
    assert!(posted.problems.is_empty(), "{:?}", posted.problems);

    // A real control reads it, tool changes and all.
    let table = "T1 P1 D4 ;ball\nT2 P2 D12 ;bull nose\nT7 P7 D6 ;flat\n";
    if let Some(motions) = common::plan_checks::rs274_motions(&out.gcode, Some(table)) {
        assert!(motions.len() > 1000, "{}", motions.len());
    }
}

/// Roughing needs a blank it can clear in layers, and a library end mill that fits.
#[test]
fn roughing_without_a_layer_blank_or_with_a_ball_is_refused() {
    let raw = RawMesh {
        mesh: frustum(),
        warnings: Vec::new(),
    };
    let mut job = job_from_box();
    job.stock.blank = Some("offset:2".into());
    job.operations = toml::from_str::<Job>(
        "[[operation]]\nkind = \"rough\"\n[[operation]]\nkind = \"finish\"\n",
    )
    .expect("operations")
    .operations;
    let e = job::plan(&raw, "frustum", "mm", &job, &Quiet)
        .err()
        .expect("refused");
    assert!(e.to_string().contains("box or a cylinder blank"), "{e}");

    let mut job = job_from_box();
    job.operations = toml::from_str::<Job>(
        "[[operation]]\nkind = \"rough\"\ntool_id = 4\n[[operation]]\nkind = \"finish\"\n",
    )
    .expect("operations")
    .operations;
    let e = job::plan(&raw, "frustum", "mm", &job, &Quiet)
        .err()
        .expect("refused");
    assert!(e.to_string().contains("T4"), "{e}");
    assert!(e.to_string().contains("not a flat or bull-nose"), "{e}");
}
