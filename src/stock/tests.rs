//! The stock model against closed forms: blank volumes, swept capsules, convergence with the
//! spacing, point queries, and the same model whatever the thread count.

use std::f64::consts::PI;

use super::sweep::SphereSweptHull;
use super::*;
use crate::mesh::fixtures::{cuboid, uv_sphere};

const LIMIT: usize = DEFAULT_MAX_DEXELS;

fn block(spacing: f64) -> Stock {
    let bounds = Aabb::from_points(&[
        Point3::new(-20.0, -15.0, -10.0),
        Point3::new(20.0, 15.0, 10.0),
    ]);
    Stock::block(&bounds, spacing, LIMIT).unwrap()
}

#[test]
fn a_block_holds_its_volume_exactly() {
    let s = block(0.5);
    assert!((s.volume() - 40.0 * 30.0 * 20.0).abs() < 1e-9);
    assert!(s.is_material(&Point3::new(0.0, 0.0, 0.0)));
    assert!(s.is_material(&Point3::new(19.9, -14.9, 9.9)));
    assert!(!s.is_material(&Point3::new(20.5, 0.0, 0.0)));
    assert_eq!(s.line_count(), 60 * 40 + 40 * 80 + 80 * 60);
}

#[test]
fn a_cylinder_converges_to_its_volume() {
    let exact = PI * 25.0 * 30.0;
    let mut errors = Vec::new();
    for spacing in [0.8, 0.4, 0.2] {
        let axis = Vector3::new(1.0, 2.0, 2.0).normalize();
        let s = Stock::cylinder(
            &Point3::new(1.0, -2.0, 3.0),
            &axis,
            5.0,
            30.0,
            spacing,
            LIMIT,
        )
        .unwrap();
        errors.push((s.volume() - exact).abs() / exact);
        let centre = Point3::new(1.0, -2.0, 3.0) + 15.0 * axis;
        assert!(s.is_material(&centre));
        assert!(!s.is_material(&(centre + 5.5 * axis.cross(&Vector3::z()).normalize())));
    }
    assert!(errors[2] < 0.005, "{errors:?}");
    assert!(errors[2] < errors[0], "no convergence: {errors:?}");
}

#[test]
fn a_closed_mesh_gives_its_own_volume() {
    // The box mesh's faces lie between lines: exact. The sphere's error shrinks with the
    // spacing toward the mesh's own volume (not the sphere's).
    let b = Stock::from_mesh(&cuboid(4.0, 6.0, 10.0), 0.5, LIMIT).unwrap();
    assert!((b.volume() - 240.0).abs() < 1e-9, "{}", b.volume());
    let sphere = uv_sphere(10.0, 24, 48);
    let exact = sphere.signed_volume();
    let coarse = (Stock::from_mesh(&sphere, 1.0, LIMIT).unwrap().volume() - exact).abs();
    let fine = Stock::from_mesh(&sphere, 0.25, LIMIT).unwrap();
    let fine_error = (fine.volume() - exact).abs();
    assert!(
        fine_error / exact < 0.002 && fine_error < coarse,
        "{coarse} {fine_error}"
    );
    assert!(fine.is_material(&Point3::new(0.0, 0.0, 9.0)));
    assert!(!fine.is_material(&Point3::new(7.5, 7.5, 0.0)));
    // A mesh facing inward (a cavity) is not a solid: nothing is material.
    let mut inverted = sphere.clone();
    for t in &mut inverted.triangles {
        t.swap(1, 2);
    }
    assert_eq!(
        Stock::from_mesh(&inverted, 1.0, LIMIT).unwrap().volume(),
        0.0
    );
}

#[test]
fn the_sample_impeller_blank_has_the_meshs_volume() {
    let part = crate::sample::impeller(&Default::default()).unwrap();
    let exact = part.signed_volume();
    let s = Stock::from_mesh(&part, 0.25, LIMIT).unwrap();
    assert!(
        (s.volume() - exact).abs() / exact < 0.01,
        "{} vs {exact}",
        s.volume()
    );
}

/// Capsule volume: a cylinder of length L and the two half balls.
fn capsule_volume(r: f64, length: f64) -> f64 {
    PI * r * r * length + 4.0 / 3.0 * PI * r.powi(3)
}

#[test]
fn a_ball_along_a_line_inside_the_block_removes_a_capsule() {
    // Straight, diagonal and a plunge along the axis: each within a few tenths of a percent at
    // 0.1 mm, the error shrinking with the spacing.
    let moves = [
        (Point3::new(-10.0, 0.0, 0.0), Point3::new(10.0, 0.0, 0.0)),
        (Point3::new(-8.0, -6.0, -3.0), Point3::new(7.0, 5.0, 4.0)),
        (Point3::new(0.0, 0.0, 5.0), Point3::new(0.0, 0.0, -5.0)),
    ];
    let r = 3.0;
    for (a, b) in moves {
        let exact = capsule_volume(r, (b - a).norm());
        let mut errors = Vec::new();
        for spacing in [0.4, 0.2, 0.1] {
            let mut s = block(spacing);
            let before = s.volume();
            let removed = s.remove(&SphereSweptHull::new(&[a, b], r));
            assert!((before - s.volume() - removed).abs() < 1e-6 * exact);
            errors.push((removed - exact).abs() / exact);
            assert!(!s.is_material(&nalgebra::center(&a, &b)));
            assert!(s.is_material(
                &(nalgebra::center(&a, &b)
                    + Vector3::new(0.0, 0.0, 0.0)
                    + (b - a).cross(&Vector3::new(0.3, 0.1, 1.0)).normalize() * (r + 0.5))
            ));
        }
        assert!(errors[2] < 0.004, "{errors:?}");
        assert!(errors[2] < errors[0], "no convergence: {errors:?}");
    }
}

#[test]
fn a_tilted_capsule_sweep_removes_the_swept_prism_and_its_ends() {
    // A ball-end's capsule (segment a→a+h·k) translated by d, k ⟂ d: the swept solid is a
    // rectangle h × |d| thickened by r — a box 2r thick, four half cylinders round its edges and
    // four quarter balls at its corners: h|d|·2r + πr²(h + |d|) + 4/3 πr³.
    let r = 2.0;
    let k = Vector3::new(0.0, 1.0, 1.0).normalize();
    let d = Vector3::new(12.0, 0.0, 0.0);
    let h = 6.0;
    let a0 = Point3::new(-6.0, -3.0, -3.0);
    let pts = [a0, a0 + h * k, a0 + d, a0 + h * k + d];
    let exact = h * d.norm() * 2.0 * r + PI * r * r * (h + d.norm()) + 4.0 / 3.0 * PI * r.powi(3);
    let mut s = block(0.1);
    let removed = s.remove(&SphereSweptHull::new(&pts, r));
    assert!(
        (removed - exact).abs() / exact < 0.003,
        "{removed} vs {exact}"
    );
}

#[test]
fn removal_is_the_same_on_one_thread_and_two() {
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                let mut s = block(0.2);
                let mut total = 0.0;
                for k in 0..20 {
                    let t = k as f64 * 0.3;
                    let a = Point3::new(-12.0 + t * 3.0, 4.0 * t.sin(), 2.0 * t.cos());
                    let b = Point3::new(
                        -11.0 + t * 3.0,
                        4.0 * (t + 0.3).sin(),
                        2.0 * (t + 0.3).cos(),
                    );
                    total += s.remove(&SphereSweptHull::new(
                        &[
                            a,
                            b,
                            a + Vector3::z() * 5.0,
                            b + Vector3::new(0.1, 0.0, 5.0),
                        ],
                        1.5,
                    ));
                }
                (s, total)
            })
    };
    let (one, total_one) = run(1);
    let (two, total_two) = run(2);
    assert!(one == two);
    assert_eq!(total_one.to_bits(), total_two.to_bits());
}

#[test]
fn bad_blanks_are_refused_before_any_allocation() {
    let bounds = Aabb::from_points(&[Point3::origin(), Point3::new(1000.0, 1000.0, 1000.0)]);
    assert!(matches!(
        Stock::block(&bounds, 0.01, LIMIT),
        Err(StockError::TooLarge { .. })
    ));
    assert!(matches!(
        Stock::block(&bounds, 0.0, LIMIT),
        Err(StockError::Spacing(_))
    ));
    assert!(matches!(
        Stock::block(&Aabb::empty(), 1.0, LIMIT),
        Err(StockError::Blank(_))
    ));
    assert!(Stock::cylinder(&Point3::origin(), &Vector3::z(), -1.0, 5.0, 1.0, LIMIT).is_err());
}

#[test]
fn a_saved_stock_reads_back_the_same_and_bad_bytes_are_refused() {
    let mut s = block(0.5);
    s.remove(&SphereSweptHull::new(
        &[Point3::new(-5.0, 0.0, 0.0), Point3::new(5.0, 2.0, 1.0)],
        3.0,
    ));
    let bytes = s.to_bytes();
    assert!(Stock::from_bytes(&bytes, LIMIT).unwrap() == s);
    for cut in [0, 7, 8, 30, bytes.len() / 2, bytes.len() - 1] {
        assert!(
            matches!(
                Stock::from_bytes(&bytes[..cut], LIMIT),
                Err(StockError::Format(_))
            ),
            "truncated at {cut}"
        );
    }
    let mut extra = bytes.clone();
    extra.push(0);
    assert!(Stock::from_bytes(&extra, LIMIT).is_err());
    // A header asking for an absurd grid is refused by the same limit as a new stock.
    let mut huge = bytes.clone();
    huge[8..16].copy_from_slice(&1e-6f64.to_le_bytes());
    assert!(matches!(
        Stock::from_bytes(&huge, LIMIT),
        Err(StockError::TooLarge { .. })
    ));
}

#[test]
fn a_path_cut_in_pieces_removes_what_it_removes_in_one_move_and_moves_rigidly() {
    use crate::geom::{Move, MoveKind, ToolPose, Toolpath};
    use crate::stock::cutter::BallEndBody;
    let body = BallEndBody::new(6.0, 18.0);
    let axis = nalgebra::Unit::new_normalize(Vector3::new(0.2, -0.1, 1.0));
    let path = |offset: Vector3, pieces: usize| Toolpath {
        tool_id: 1,
        moves: (0..=pieces)
            .map(|k| Move {
                pose: ToolPose {
                    tip: Point3::new(-10.0 + 20.0 * k as f64 / pieces as f64, 2.0, -4.0) + offset,
                    axis,
                },
                kind: if k == 0 {
                    MoveKind::Rapid
                } else {
                    MoveKind::Cut
                },
                feed: 1000.0,
            })
            .collect(),
    };
    let bounds = |offset: Vector3| {
        Aabb::from_points(&[
            Point3::new(-20.0, -15.0, -10.0) + offset,
            Point3::new(20.0, 15.0, 10.0) + offset,
        ])
    };
    let run = |offset: Vector3, pieces: usize| {
        let mut s = Stock::block(&bounds(offset), 0.2, LIMIT).unwrap();
        let removed = s.remove_toolpath(&path(offset, pieces), &body, 0.001);
        (s.volume(), removed)
    };
    let (one_volume, one) = run(Vector3::zeros(), 1);
    let (ten_volume, ten) = run(Vector3::zeros(), 10);
    assert_eq!(one[0], 0.0);
    assert!((one_volume - ten_volume).abs() < 1e-6 * one_volume);
    // Later pieces cut less than the first (the ball's front half-sphere is already gone).
    assert!(ten[2] < ten[1]);
    // The whole job moved by a whole number of lines: the same volumes.
    let (moved_volume, moved) = run(Vector3::new(0.4, -1.2, 2.0), 10);
    assert!((moved_volume - ten_volume).abs() < 1e-6 * ten_volume);
    for (a, b) in moved.iter().zip(&ten) {
        assert!((a - b).abs() < 1e-6 * ten_volume, "{a} vs {b}");
    }
}
