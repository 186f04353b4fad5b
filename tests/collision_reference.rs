//! The tool-body collision tests (`collide`, parry3d in f32) against references that share no
//! code with them (issue 5 item 4): random poses near the sample impeller decided by brute
//! force over dense samples of the part's surface and closed-form point-to-frustum distances,
//! and a ball in a spherical cavity against its closed-form clearance.

mod common;

use common::{repo_file, surface_samples};
use nalgebra::{Point3, Unit, Vector3};
use wavemill::collide::{Collision, F32_SLACK, Margins, PartCollider, PreparedTool};
use wavemill::geom::orthonormal_frame;
use wavemill::job;
use wavemill::mesh::{Mesh, PrepareOptions, prepare};
use wavemill::path::ToolPose;
use wavemill::tool::{Body, BodyRole, Cutter, Neck, Section, ToolAssembly};

/// Distance from the point at axial height `h` and radius `rho` to a solid frustum in the
/// (h, ρ) half-plane (0 inside).
fn frustum_distance(h: f64, rho: f64, b: &Body) -> f64 {
    let radius_at =
        |x: f64| b.radius_from + (b.radius_to - b.radius_from) * (x - b.from) / (b.to - b.from);
    if h >= b.from && h <= b.to && rho <= radius_at(h) {
        return 0.0;
    }
    let segment = |a: (f64, f64), c: (f64, f64)| {
        let (dx, dy) = (c.0 - a.0, c.1 - a.1);
        let t = (((h - a.0) * dx + (rho - a.1) * dy) / (dx * dx + dy * dy)).clamp(0.0, 1.0);
        ((h - a.0 - t * dx).powi(2) + (rho - a.1 - t * dy).powi(2)).sqrt()
    };
    segment((b.from, 0.0), (b.from, b.radius_from))
        .min(segment((b.from, b.radius_from), (b.to, b.radius_to)))
        .min(segment((b.to, 0.0), (b.to, b.radius_to)))
}

/// A deterministic generator (64-bit LCG), so the poses are the same on every run.
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

#[test]
fn body_tests_agree_with_brute_force_on_random_poses_near_the_sample_impeller() {
    let raw = job::load_part(&repo_file("data/impeller.glb"), "mm").unwrap();
    let (part, _) = prepare(&raw.mesh, &PrepareOptions::default()).unwrap();
    let collider = PartCollider::new(&part).unwrap();
    let triangles: Vec<[Point3<f64>; 3]> =
        (0..part.triangles.len()).map(|t| part.corners(t)).collect();
    let spacing = 0.4;
    let samples = surface_samples(&triangles, spacing);
    let margins = Margins {
        shank: 0.5,
        holder: 2.0,
    };
    let tool = ToolAssembly {
        id: 1,
        name: String::new(),
        cutter: Cutter::TaperedBall {
            diameter: 3.0,
            taper_deg: 4.0,
            flute_length: 10.0,
        },
        neck: Some(Neck {
            diameter: 3.0,
            length: 6.0,
        }),
        shank_diameter: 6.0,
        stickout: 30.0,
        holder: vec![
            Section {
                diameter: 16.0,
                top_diameter: Some(24.0),
                length: 25.0,
            },
            Section::cylinder(40.0, 20.0),
        ],
    };
    let prepared = PreparedTool::new(&tool, &margins);
    let bodies = tool.bodies();
    let normals = part.vertex_normals();
    let mut rng = Lcg(2026);
    let (mut clear, mut colliding) = (0, 0);
    for _ in 0..250 {
        let v = (rng.next() * part.positions.len() as f64) as usize;
        let n = normals[v];
        if n.norm() < 0.5 {
            continue;
        }
        // A tip up to 6 mm off the surface, the axis within 60° of the normal.
        let (s1, s2) = orthonormal_frame(&n);
        let (tilt, turn) = (
            rng.next() * 60f64.to_radians(),
            rng.next() * std::f64::consts::TAU,
        );
        let axis = n * tilt.cos() + (s1 * turn.cos() + s2 * turn.sin()) * tilt.sin();
        let tip = part.positions[v] + n * (0.3 + 6.0 * rng.next());
        let pose = ToolPose {
            tip,
            axis: Unit::new_normalize(axis),
        };
        // Brute force: the smallest (distance − margin) of any body over the samples; the
        // flutes' margin is 0 (they may touch, not enter).
        let margin = |role: BodyRole| match role {
            BodyRole::Flutes => 0.0,
            BodyRole::Shank => margins.shank,
            BodyRole::Holder => margins.holder,
        };
        let mut worst = f64::INFINITY;
        for q in &samples {
            let d: Vector3<f64> = q - tip;
            let h = d.dot(&axis);
            let rho = (d - axis * h).norm();
            for b in &bodies {
                worst = worst.min(frustum_distance(h, rho, b) - margin(b.role));
            }
        }
        match collider.check_bodies(&prepared, &pose) {
            Ok(()) => {
                // Clear for parry: no sample of the part comes inside any margin.
                assert!(
                    worst >= -F32_SLACK,
                    "pose {pose:?}: brute force finds {worst}"
                );
                clear += 1;
            }
            Err(Collision::Body { .. }) => {
                // A collision for parry: some part point is within the margin plus what the
                // circumscribed 32-gon adds (0.5 % of the widest radius), the f32 slack and the
                // sampling's reach.
                assert!(
                    worst <= 0.005 * 20.0 + F32_SLACK + spacing,
                    "pose {pose:?}: brute force finds {worst}"
                );
                colliding += 1;
            }
            Err(other) => panic!("{other:?} without a table"),
        }
    }
    assert!(
        clear > 30 && colliding > 30,
        "{clear} clear, {colliding} colliding"
    );
}

#[test]
fn a_ball_in_a_spherical_cavity_has_its_closed_form_clearance() {
    // The inside of a sphere of radius R as the part's surface (normals inward): a ball of
    // radius r centred c from the cavity's centre clears the wall by R − c − r, less the
    // facets' sagitta.
    let big_r = 20.0;
    let (stacks, slices) = (90u32, 180u32);
    let mut positions = vec![Point3::new(0.0, 0.0, big_r)];
    for i in 1..stacks {
        let phi = std::f64::consts::PI * i as f64 / stacks as f64;
        for j in 0..slices {
            let th = std::f64::consts::TAU * j as f64 / slices as f64;
            positions.push(Point3::new(
                big_r * phi.sin() * th.cos(),
                big_r * phi.sin() * th.sin(),
                big_r * phi.cos(),
            ));
        }
    }
    positions.push(Point3::new(0.0, 0.0, -big_r));
    let south = positions.len() as u32 - 1;
    let ring = |i: u32, j: u32| 1 + (i - 1) * slices + (j % slices);
    let mut triangles = Vec::new();
    for j in 0..slices {
        // Wound inward: the cavity's wall faces its centre.
        triangles.push([0, ring(1, j + 1), ring(1, j)]);
        triangles.push([south, ring(stacks - 1, j), ring(stacks - 1, j + 1)]);
    }
    for i in 1..stacks - 1 {
        for j in 0..slices {
            let (a, b, c, d) = (
                ring(i, j),
                ring(i, j + 1),
                ring(i + 1, j),
                ring(i + 1, j + 1),
            );
            triangles.push([a, d, c]);
            triangles.push([a, b, d]);
        }
    }
    let cavity = Mesh {
        positions,
        triangles,
    };
    let collider = PartCollider::new(&cavity).unwrap();
    let sagitta = big_r * (1.0 - (std::f64::consts::PI / stacks as f64).cos());
    for (c, r) in [(0.0, 5.0), (7.0, 6.0), (12.0, 7.5), (10.0, 9.99)] {
        let centre = Point3::new(c * 0.6, -c * 0.48, c * 0.64);
        let clearance = collider.check_ball(&centre, r, 0.0).unwrap();
        let expected = big_r - centre.coords.norm() - r;
        assert!(
            clearance <= expected + 1e-9 && clearance >= expected - 2.0 * sagitta,
            "c {c} r {r}: {clearance} vs {expected}"
        );
    }
    // A ball that reaches past the wall gouges by about the overlap.
    let centre = Point3::new(0.0, 12.0, 0.0);
    match collider.check_ball(&centre, 8.5, 0.0) {
        Err(Collision::Gouge { depth }) => {
            assert!((depth - 0.5).abs() <= 2.0 * sagitta, "{depth}")
        }
        other => panic!("{other:?}"),
    }
}
