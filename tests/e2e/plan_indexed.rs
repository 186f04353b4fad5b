//! Indexed (3+2) roughing in a plan: a part whose sides overhang (a square frustum standing
//! on its small end) keeps, after the vertical end mills, the material under its overhang;
//! `indexed-rough` proposes tilted axes from the visibility of that rest and roughs it in
//! layers along each, in one program with the vertical roughing and the ball's finishing.
//!
//! The clearance of every indexed move's tool axis is measured here by the exact distance to
//! the part's twelve triangles, sharing nothing with the planner or its checks.

use crate::common;
use nalgebra::Point3;
use wavemill::geom::MoveKind;
use wavemill::job::{self, Job, Quiet};
use wavemill::mesh::Mesh;
use wavemill::mesh::io::RawMesh;

const HEIGHT: f64 = 15.0;

/// A square frustum 20 × 20 on the table, 40 × 40 on top, 15 high: every side overhangs by
/// atan(10/15) = 33.7° from the vertical.
fn overhanging_frustum() -> Mesh {
    let positions = (0..8)
        .map(|i| {
            let top = i & 4 != 0;
            let (lo, hi) = if top { (0.0, 40.0) } else { (10.0, 30.0) };
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

/// The closest point of triangle `abc` to `p` (Ericson, Real-Time Collision Detection 5.1.5).
fn closest_on_triangle(
    p: &Point3<f64>,
    a: &Point3<f64>,
    b: &Point3<f64>,
    c: &Point3<f64>,
) -> Point3<f64> {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(&ap), ac.dot(&ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return *a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(&bp), ac.dot(&bp));
    if d3 >= 0.0 && d4 <= d3 {
        return *b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(&cp), ac.dot(&cp));
    if d6 >= 0.0 && d5 <= d6 {
        return *c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

/// The distance from `p` to the part's surface, negative inside (the part is convex: inside
/// when behind every face plane).
fn signed_distance(mesh: &Mesh, p: &Point3<f64>) -> f64 {
    let mut nearest = f64::INFINITY;
    let mut inside = true;
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
        nearest = nearest.min((p - closest_on_triangle(p, &a, &b, &c)).norm());
        let n = (b - a).cross(&(c - a));
        inside &= n.dot(&(p - a)) < 0.0;
    }
    if inside { -nearest } else { nearest }
}

#[test]
fn the_rest_under_an_overhang_is_roughed_in_tilted_setups() {
    let mut job = Job::default();
    job.strategy.scallop_height = 0.3;
    job.strategy.max_step = 2.0;
    job.stock.blank = Some("box:-3,-3,0,43,43,18".into());
    job.stock.resolution = Some(0.4);
    job.roughing.indexed_setups = 4;
    let part = overhanging_frustum();
    let raw = RawMesh {
        mesh: part.clone(),
        warnings: Vec::new(),
    };
    let out = job::plan(&raw, "overhanging frustum", "mm", &job, &Quiet).expect("plan");
    assert_eq!(out.verification_failure, None);
    let r = &out.report;
    assert_eq!(
        common::plan_checks::tool_changes(&out.gcode),
        ["T2 M6", "T7 M6", "T7 M6", "T1 M6"]
    );

    // The setups lean out over the sides, steeper than the overhang.
    let indexed = r.roughing[2].indexed.as_ref().expect("indexed summary");
    assert!(indexed.setups.len() >= 2, "{indexed:?}");
    for setup in &indexed.setups {
        assert!(setup.tilt_deg >= 30.0, "{setup:?}");
        assert!(setup.removed_mm3 > 0.0, "{setup:?}");
    }

    // Every indexed move keeps its tool off the part by half the allowance (the posted check
    // holds it to the offset shape exactly): the flat end mill's rim circles from the tip up
    // the flutes, and its end face, sampled at each end and the middle of every move, and
    // measured against the part's triangles. The axis stays fixed along every feed move.
    let span = &out.operations[2];
    let moves = &out.toolpath.moves[span.moves.clone()];
    let radius = r.roughing[2].planning.radius;
    let flutes = 13.0;
    let mut nearest = f64::INFINITY;
    let mut poses = 0;
    for w in moves.windows(2) {
        if w[1].kind == MoveKind::Rapid {
            continue;
        }
        assert_eq!(w[0].pose.axis, w[1].pose.axis, "{:?}", w[1]);
        let k = w[1].pose.axis.into_inner();
        assert!(k.z < 0.9, "a tilted axis: {k:?}");
        let u = k.cross(&nalgebra::Vector3::x()).normalize();
        let v = k.cross(&u);
        for t in [0.0, 0.5, 1.0] {
            let tip = w[0].pose.tip + (w[1].pose.tip - w[0].pose.tip) * t;
            if signed_distance(&part, &tip) > radius + flutes + 1.0 {
                continue;
            }
            poses += 1;
            let mut samples = vec![tip];
            for step in 0..32 {
                let a = step as f64 * std::f64::consts::PI / 16.0;
                let out = u * a.cos() + v * a.sin();
                samples.push(tip + out * (0.5 * radius));
                for h in 0..=26 {
                    samples.push(tip + out * radius + k * (0.5 * h as f64));
                }
            }
            for q in &samples {
                nearest = nearest.min(signed_distance(&part, q));
            }
        }
    }
    assert!(poses > 100, "{poses}");
    let allowance = job.roughing.allowance;
    assert!(
        nearest >= 0.5 * allowance,
        "{nearest} off the part, against an allowance of {allowance}"
    );
    let checked = r.roughing[2].overcut_vs_part.as_ref().expect("checked");
    assert!(checked.overcuts.is_empty() && checked.moves_checked > 100);

    // On the stock: the indexed setups take material the vertical tools left, touching it
    // with nothing but the flutes, and leave less rest on the part.
    let stock = r.stock.as_ref().expect("stock run");
    let names: Vec<&str> = stock.operations.iter().map(|o| o.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "rough to 0.5 mm",
            "rest-rough to 0.5 mm",
            "indexed-rough to 0.5 mm",
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
    let (rest, tilted) = (&stock.operations[1], &stock.operations[2]);
    assert!(
        tilted.removed_volume_mm3 > 0.07 * (rest.volume_after_mm3 - part_volume()),
        "{} of {}",
        tilted.removed_volume_mm3,
        rest.volume_after_mm3 - part_volume()
    );
    assert!(
        tilted.rest.mean_mm < 0.9 * rest.rest.mean_mm,
        "{:?} {:?}",
        tilted.rest,
        rest.rest
    );

    let table = "T1 P1 D4 ;ball\nT2 P2 D12 ;bull nose\nT7 P7 D6 ;flat\n";
    if let Some(motions) = common::plan_checks::rs274_motions(&out.gcode, Some(table)) {
        assert!(motions.len() > 1000, "{}", motions.len());
    }
}

/// The frustum's volume: h/3 (A₁ + A₂ + √(A₁A₂)).
fn part_volume() -> f64 {
    HEIGHT / 3.0 * (400.0 + 1600.0 + 800.0)
}
