//! `plan` with channel roughing: the rest that vertical end mills leave under an overhang,
//! taken down by the ball in 5-axis offset layers before the finish.
//!
//! The part is an I-beam lying along Y (flanges 40 wide and 3 thick, a web 10 wide, 18 high,
//! 30 long): from above, the top flange hides two pockets 12 high and 15 deep that open to the
//! sides and the ends. Its distance is the least of its three boxes' (closed form), so every
//! ball centre is measured without the planner's distance queries.

use crate::common;
use nalgebra::{Point3, Vector3};
use wavemill::geom::MoveKind;
use wavemill::job::{self, Job, Layering, Quiet};
use wavemill::mesh::Mesh;
use wavemill::mesh::io::RawMesh;

const LENGTH: f64 = 30.0;
/// The section in XZ, counter-clockwise.
const SECTION: [(f64, f64); 12] = [
    (0.0, 0.0),
    (40.0, 0.0),
    (40.0, 3.0),
    (25.0, 3.0),
    (25.0, 15.0),
    (40.0, 15.0),
    (40.0, 18.0),
    (0.0, 18.0),
    (0.0, 15.0),
    (15.0, 15.0),
    (15.0, 3.0),
    (0.0, 3.0),
];
/// The section cut into triangles, counter-clockwise in XZ.
const SECTION_TRIANGLES: [[u32; 3]; 10] = [
    [0, 1, 2],
    [0, 2, 3],
    [0, 3, 10],
    [0, 10, 11],
    [10, 3, 4],
    [10, 4, 9],
    [7, 8, 9],
    [7, 9, 4],
    [7, 4, 5],
    [7, 5, 6],
];

fn i_beam() -> Mesh {
    let n = SECTION.len() as u32;
    let positions = [0.0, LENGTH]
        .iter()
        .flat_map(|&y| SECTION.iter().map(move |&(x, z)| Point3::new(x, y, z)))
        .collect();
    // Counter-clockwise in XZ faces −Y: the near cap as listed, the far one turned over.
    let mut triangles: Vec<[u32; 3]> = SECTION_TRIANGLES.to_vec();
    triangles.extend(
        SECTION_TRIANGLES
            .iter()
            .map(|&[a, b, c]| [a + n, c + n, b + n]),
    );
    for i in 0..n {
        let j = (i + 1) % n;
        triangles.push([i, j + n, j]);
        triangles.push([i, i + n, j + n]);
    }
    Mesh {
        positions,
        triangles,
    }
}

/// Distance from `p` (outside the part) to the I-beam: the least over its three boxes.
fn beam_distance(p: &Point3<f64>) -> f64 {
    let boxes = [
        ([0.0, 0.0, 0.0], [40.0, LENGTH, 3.0]),
        ([15.0, 0.0, 3.0], [25.0, LENGTH, 15.0]),
        ([0.0, 0.0, 15.0], [40.0, LENGTH, 18.0]),
    ];
    boxes
        .iter()
        .map(|(lo, hi)| {
            let gap = |k: usize| (lo[k] - p[k]).max(p[k] - hi[k]).max(0.0);
            Vector3::new(gap(0), gap(1), gap(2)).norm()
        })
        .fold(f64::INFINITY, f64::min)
}

fn job(channel: Option<Layering>) -> Job {
    let mut job = Job::default();
    job.strategy.scallop_height = 0.3;
    job.strategy.max_step = 2.0;
    job.stock.blank = Some("box:-3,-3,0,43,33,20".into());
    job.stock.resolution = Some(0.4);
    if let Some(layering) = channel {
        job.roughing.channel = true;
        job.roughing.channel_layering = layering;
    }
    job
}

fn raw_beam() -> RawMesh {
    let part = i_beam();
    let volume: f64 = part
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| part.positions[i as usize].coords);
            a.dot(&b.cross(&c)) / 6.0
        })
        .sum();
    assert!((volume - LENGTH * (2.0 * 40.0 * 3.0 + 10.0 * 12.0)).abs() < 1e-6);
    RawMesh {
        mesh: part,
        warnings: Vec::new(),
    }
}

fn blocked(r: &job::PlanReport) -> usize {
    r.unreachable
        .by_reason
        .get("material")
        .copied()
        .unwrap_or(0)
}

/// What either layering must do on the beam, against the plan without channel roughing.
fn check_channel(with: &job::PlanOutput, without: &job::PlanOutput) {
    assert_eq!(with.verification_failure, None);
    let r = &with.report;

    // One tool change to the ball, which channel-roughs and then finishes.
    assert_eq!(
        common::plan_checks::tool_changes(&with.gcode),
        ["T2 M6", "T7 M6", "T1 M6"]
    );

    // Each layer kept its allowance on the part by the plan's independent verification; most
    // of each is air, left out; together they take a good part of the pockets.
    let channel = &r.channel_roughing[0];
    for layer in &channel.layers {
        assert!(
            layer.min_stock_left_minus_allowance_mm >= -layer.chord_tolerance_mm,
            "{layer:?}"
        );
    }
    assert!(channel.layers.iter().all(|l| l.points_in_air > 0));
    let removed: f64 = channel.layers.iter().map(|l| l.removed_mm3).sum();
    assert!(removed > 1000.0, "{removed} mm³");

    // Every ball centre of the operation, measured here, is at least the last layer's
    // allowance (less its chord tolerance) off the part beyond the radius.
    let span = &with.operations[2];
    let radius = Job::default().tool.diameter / 2.0;
    let least = with.toolpath.moves[span.moves.clone()]
        .iter()
        .filter(|m| m.kind != MoveKind::Rapid)
        .map(|m| beam_distance(&(m.pose.tip + m.pose.axis.into_inner() * radius)) - radius)
        .fold(f64::INFINITY, f64::min);
    let last = channel.layers.last().unwrap();
    assert!(
        least >= last.allowance_mm - last.chord_tolerance_mm,
        "a ball comes {least} mm from the part"
    );
    // Some of it is under the top flange, in the pockets.
    assert!(
        with.toolpath.moves[span.moves.clone()]
            .iter()
            .filter(|m| m.kind == MoveKind::Cut)
            .any(|m| {
                let c = m.pose.tip + m.pose.axis.into_inner() * radius;
                c.z < 15.0 - radius && (c.x < 15.0 - radius || c.x > 25.0 + radius)
            })
    );

    // On the stock: the channel roughing cuts, touches nothing with its shank or holder and
    // leaves less rest than the end mills did; the finish after it is blocked by material at
    // fewer points than without it, and leaves less.
    let stock = r.stock.as_ref().expect("stock run");
    let names: Vec<&str> = stock.operations.iter().map(|o| o.name.as_str()).collect();
    assert_eq!(
        names,
        vec![
            "rough to 0.5 mm",
            "rest-rough to 0.5 mm",
            "channel-rough to 0.5 mm",
            "finish"
        ]
    );
    for o in &stock.operations {
        assert_eq!(
            (o.gouge.count, o.collision_count, o.rapids_through_material),
            (0, 0, 0),
            "{}",
            o.name
        );
    }
    let (rest, channel_run) = (&stock.operations[1], &stock.operations[2]);
    assert!(channel_run.removed_volume_mm3 > 1000.0);
    assert!(channel_run.rest.mean_mm < rest.rest.mean_mm);
    assert!(
        blocked(r) < blocked(&without.report),
        "{} against {}",
        blocked(r),
        blocked(&without.report)
    );
    let finish_rest =
        |r: &job::PlanReport| r.stock.as_ref().unwrap().operations.last().unwrap().rest;
    assert!(finish_rest(r).mean_mm < finish_rest(&without.report).mean_mm);

    // The program, as posted, within the tolerance of the part.
    let posted = r.posted.as_ref().expect("posted check");
    assert!(posted.problems.is_empty(), "{:?}", posted.problems);
}

/// Layers from the shroud (the stock's top) down to the hub (the bottom flange's top under
/// the pockets): evenly spaced between hub and top, from the top down to the hub itself, each
/// within a step of the one above over the part, all at the roughing's allowance.
#[test]
fn shroud_to_hub_layers_take_the_rest_under_an_overhang() {
    let raw = raw_beam();
    let with = job::plan(
        &raw,
        "i-beam",
        "mm",
        &job(Some(Layering::ShroudToHub)),
        &Quiet,
    )
    .expect("plan");
    let without = job::plan(&raw, "i-beam", "mm", &job(None), &Quiet).expect("plan");
    assert_eq!(without.verification_failure, None);
    check_channel(&with, &without);
    let channel = &with.report.channel_roughing[0];
    assert_eq!(channel.layering, Layering::ShroudToHub);
    let heights: Vec<f64> = channel.layers.iter().map(|l| l.height.unwrap()).collect();
    assert_eq!(*heights.last().unwrap(), 0.0);
    let count = (1.0 / heights[heights.len() - 2]).round();
    assert!(
        heights
            .windows(2)
            .all(|w| (w[0] - w[1] - 1.0 / count).abs() < 1e-12),
        "{heights:?}"
    );
    // The hub under the pockets is the bottom flange's top (3 mm) and the material's top after
    // the end mills the top flange's offset (18.5 mm): eight layers, 1.94 mm apart there,
    // within the channel's step of 2 mm (the ball's radius).
    assert_eq!(count, 8.0);
    assert!((18.5 - 3.0) / count <= channel.step_mm, "{count}");
    assert!(
        channel
            .layers
            .iter()
            .all(|l| l.allowance_mm == Job::default().roughing.allowance)
    );
}

/// Offsets of the part, outermost first, a step apart, down to the roughing's allowance.
#[test]
fn offset_layers_take_the_rest_under_an_overhang() {
    let raw = raw_beam();
    let with = job::plan(&raw, "i-beam", "mm", &job(Some(Layering::Offset)), &Quiet).expect("plan");
    let without = job::plan(&raw, "i-beam", "mm", &job(None), &Quiet).expect("plan");
    check_channel(&with, &without);
    let channel = &with.report.channel_roughing[0];
    assert_eq!(channel.layering, Layering::Offset);
    let allowances: Vec<f64> = channel.layers.iter().map(|l| l.allowance_mm).collect();
    assert!(allowances.len() >= 3, "{allowances:?}");
    assert_eq!(
        *allowances.last().unwrap(),
        Job::default().roughing.allowance
    );
    assert!(
        allowances
            .windows(2)
            .all(|w| (w[0] - w[1] - channel.step_mm).abs() < 1e-9)
    );
}
