//! `plan` with channel roughing: the rest that vertical end mills leave under an overhang,
//! taken down by the ball in 5-axis offset layers before the finish.
//!
//! The part is an I-beam lying along Y (flanges 40 wide and 3 thick, a web 10 wide, 18 high,
//! 30 long): from above, the top flange hides two pockets 12 high and 15 deep that open to the
//! sides and the ends. Its distance is the least of its three boxes' (closed form), so every
//! ball centre is measured without the planner's distance queries.

mod common;

use nalgebra::{Point3, Vector3};
use wavemill::geom::MoveKind;
use wavemill::job::{self, Job, Quiet};
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

fn job(channel: bool) -> Job {
    let mut job = Job::default();
    job.strategy.scallop_height = 0.3;
    job.strategy.max_step = 2.0;
    job.stock.blank = Some("box:-3,-3,0,43,33,20".into());
    job.stock.resolution = Some(0.4);
    job.roughing.channel = channel;
    job
}

#[test]
fn channel_roughing_takes_the_rest_under_an_overhang_in_offset_layers() {
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
    let raw = RawMesh {
        mesh: part,
        warnings: Vec::new(),
    };
    let with = job::plan(&raw, "i-beam", "mm", &job(true), &Quiet).expect("plan");
    let without = job::plan(&raw, "i-beam", "mm", &job(false), &Quiet).expect("plan");
    assert_eq!(with.verification_failure, None);
    assert_eq!(without.verification_failure, None);
    let r = &with.report;

    // One tool change to the ball, which channel-roughs and then finishes.
    let changes: Vec<&str> = with
        .gcode
        .lines()
        .filter(|l| l.starts_with('T') && l.ends_with(" M6"))
        .collect();
    assert_eq!(changes, vec!["T2 M6", "T7 M6", "T1 M6"]);

    // The layers, outermost first, a step apart, down to the roughing's allowance; each kept
    // its own allowance on the part by the plan's independent verification.
    let channel = &r.channel_roughing[0];
    let allowances: Vec<f64> = channel.layers.iter().map(|l| l.allowance_mm).collect();
    assert!(allowances.len() >= 3, "{allowances:?}");
    assert_eq!(*allowances.last().unwrap(), job(true).roughing.allowance);
    assert!(
        allowances
            .windows(2)
            .all(|w| (w[0] - w[1] - channel.step_mm).abs() < 1e-9)
    );
    for layer in &channel.layers {
        assert!(
            layer.min_stock_left_minus_allowance_mm >= -layer.chord_tolerance_mm,
            "{layer:?}"
        );
    }
    // Most of each layer is air, and left out.
    assert!(channel.layers.iter().all(|l| l.points_in_air > 0));
    let removed: f64 = channel.layers.iter().map(|l| l.removed_mm3).sum();
    assert!(removed > 1000.0, "{removed} mm³");

    // Every ball centre of the operation, measured here, is at least the last layer's
    // allowance (less its chord tolerance) off the part beyond the radius.
    let span = &with.operations[2];
    let radius = job(true).tool.diameter / 2.0;
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
    let blocked = |r: &job::PlanReport| {
        r.unreachable
            .by_reason
            .get("material")
            .copied()
            .unwrap_or(0)
    };
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
