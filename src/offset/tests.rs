//! Closed-form offsets (sphere, capped cylinder), tool-centre surfaces, and the verification
//! catching a broken bound.

use super::*;
use crate::geom::closest_point_on_triangle;
use crate::mesh::fixtures::uv_sphere;

/// Distance to the mesh by brute force over all triangles: independent of the BVH.
fn brute_distance(mesh: &Mesh, p: &Point3) -> f64 {
    (0..mesh.triangles.len())
        .map(|t| {
            let [a, b, c] = mesh.corners(t);
            (closest_point_on_triangle(p, &a, &b, &c).0 - p).norm()
        })
        .fold(f64::INFINITY, f64::min)
}

fn specs(surface: &Mesh, allowances: &[f64], bound: f64) -> Vec<ShapeSpec> {
    allowances
        .iter()
        .map(|&allowance| ShapeSpec {
            surface: surface.clone(),
            allowance,
            bound,
            vertex_bounds: None,
        })
        .collect()
}

/// The guarantees of issue 4 point 2, read from the report.
fn assert_guarantees(shapes: &[OffsetShape]) {
    for (j, s) in shapes.iter().enumerate() {
        let r = &s.report;
        assert!(r.verified, "shape {j}: {r:?}");
        assert!(
            r.min_clearance_minus_allowance_mm >= -1e-6,
            "shape {j}: {r:?}"
        );
        assert!(
            r.min_part_depth_minus_allowance_mm >= -1e-6,
            "shape {j}: {r:?}"
        );
        if j + 1 < shapes.len() {
            assert!(
                r.min_inner_depth_mm.is_some_and(|d| d > 0.0),
                "shape {j}: {r:?}"
            );
        }
        let topology = Topology::analyse(&s.mesh.triangles, s.mesh.positions.len());
        assert!(
            topology.is_closed_manifold(),
            "shape {j} is not a closed manifold: {topology:?}"
        );
        assert!(s.mesh.signed_volume() > 0.0, "shape {j} is inside out");
    }
}

/// The offset of a sphere of radius R by t is the sphere of radius R + t. The part is a
/// tessellated sphere (chord error ε), so every vertex of a shape is at R + t within
/// [−ε, chord margin], and at distance ≥ t from the tessellated part to 1e-6 relative.
#[test]
fn sphere_offsets_are_spheres() {
    let (radius, stacks) = (10.0, 48);
    let part = uv_sphere(radius, stacks, 2 * stacks);
    let chord = radius * (1.0 - (std::f64::consts::PI / stacks as f64).cos());
    let allowances = [2.0, 0.5];
    let shapes = nested_offsets(&part, &specs(&part, &allowances, 0.0)).unwrap();
    assert_guarantees(&shapes);
    assert_eq!(shapes[0].report.method.kind(), "distance_grid");
    assert_eq!(shapes[1].report.method.kind(), "normal_offset");
    for (shape, &t) in shapes.iter().zip(&allowances) {
        for v in shape.mesh.positions.iter().step_by(7) {
            let r = v.coords.norm();
            assert!(
                r >= radius + t - chord - 1e-6 * radius,
                "radius {r} for t = {t}"
            );
            assert!(r <= radius + t + t / 20.0, "radius {r} for t = {t}");
            assert!(brute_distance(&part, v) >= t - 1e-6 * radius);
        }
        // Excess is the chord margin only: far below the offset.
        assert!(shape.report.max_excess_mm <= t / 20.0, "{:?}", shape.report);
    }
}

/// A closed cylinder (radius R, height H, flat caps): the offset by t is the rounded cylinder
/// {x : hypot(max(ρ − R, 0), max(|z| − H/2, 0)) = t}.
#[test]
fn capped_cylinder_offsets_are_rounded_cylinders() {
    let (radius, height, n) = (5.0, 20.0, 96u32);
    let mut positions = vec![
        Point3::new(0.0, 0.0, -height / 2.0),
        Point3::new(0.0, 0.0, height / 2.0),
    ];
    for k in 0..n {
        let a = std::f64::consts::TAU * k as f64 / n as f64;
        for z in [-height / 2.0, height / 2.0] {
            positions.push(Point3::new(radius * a.cos(), radius * a.sin(), z));
        }
    }
    let mut triangles = Vec::new();
    for k in 0..n {
        let (b0, t0) = (2 + 2 * k, 3 + 2 * k);
        let (b1, t1) = (2 + 2 * ((k + 1) % n), 3 + 2 * ((k + 1) % n));
        triangles.extend([[0, b1, b0], [1, t0, t1], [b0, b1, t1], [b0, t1, t0]]);
    }
    let part = Mesh {
        positions,
        triangles,
    };
    assert!(part.signed_volume() > 0.0);
    let chord = radius * (1.0 - (std::f64::consts::PI / n as f64).cos());
    let allowances = [1.5, 0.4];
    let shapes = nested_offsets(&part, &specs(&part, &allowances, 0.0)).unwrap();
    assert_guarantees(&shapes);
    let rounded = |p: &Point3| {
        let rho = p.x.hypot(p.y);
        (rho - radius)
            .max(0.0)
            .hypot((p.z.abs() - height / 2.0).max(0.0))
    };
    // The innermost is pushed along vertex directions (capped stretch at the rims), so only
    // the grid shape is held to the closed form.
    let (shape, t) = (&shapes[0], allowances[0]);
    for v in &shape.mesh.positions {
        let d = rounded(v);
        assert!(d >= t - chord - 1e-6 * radius, "{d} at {v:?}");
        assert!(d <= t + t / 20.0, "{d} at {v:?}");
    }
}

/// Ball-centre surfaces: the same shapes offset by the ball radius as well.
#[test]
fn tool_centre_surfaces_keep_the_ball_off_the_part() {
    let part = uv_sphere(10.0, 24, 48);
    let options = OffsetOptions::default().with_tool_radius(3.0);
    let shapes = nested_offsets_opt(&part, &specs(&part, &[1.0, 0.0], 0.0), &options).unwrap();
    assert_guarantees(&shapes);
    for (shape, a) in shapes.iter().zip([1.0, 0.0]) {
        let min = shape
            .mesh
            .positions
            .iter()
            .map(|v| brute_distance(&part, v))
            .fold(f64::INFINITY, f64::min);
        assert!(min >= 3.0 + a - 1e-6, "{min}");
        assert!(min <= 3.0 + a + 0.2, "{min}");
    }
}

/// A bound set to zero while the level surface lies 0.3 mm inside the part: the shapes built
/// from it overcut, the verification must find it and push them out until every guarantee
/// holds.
#[test]
fn a_zeroed_bound_is_caught_and_repaired() {
    let part = uv_sphere(10.0, 24, 48);
    let shrunk = uv_sphere(9.7, 12, 24);
    let shapes = nested_offsets(&part, &specs(&shrunk, &[1.0, 0.2], 0.0)).unwrap();
    assert!(
        shapes.iter().all(|s| s.report.failures_found > 0),
        "{:?}",
        shapes.iter().map(|s| &s.report).collect::<Vec<_>>()
    );
    assert!(shapes.iter().all(|s| s.report.repair_rounds > 0));
    assert_guarantees(&shapes);
}

#[test]
fn bad_inputs_are_refused_by_name() {
    let part = uv_sphere(10.0, 8, 16);
    let err = nested_offsets(&part, &specs(&part, &[0.5, 1.0], 0.0)).unwrap_err();
    assert!(err.to_string().contains("allowance 1"), "{err}");
    let err = nested_offsets(&part, &specs(&part, &[1.0], f64::NAN)).unwrap_err();
    assert!(err.to_string().contains("bound"), "{err}");
    let options = OffsetOptions::default().with_tool_radius(-1.0);
    let err = nested_offsets_opt(&part, &specs(&part, &[1.0], 0.0), &options).unwrap_err();
    assert!(err.to_string().contains("tool_radius"), "{err}");
}

/// Local bounds (DESIGN.md §3.4, "locally per region"): a level surface that lies 0.8 mm inside
/// the part on the upper half and on it below, with the bound 0.8 given only where it is
/// needed. The shape keeps every guarantee, is no thicker than the uniform-bound shape
/// anywhere, and is thinner where the local bound is small.
#[test]
fn local_bounds_tighten_the_shape_where_the_level_is_close() {
    let part = uv_sphere(10.0, 24, 48);
    let mut level = part.clone();
    for p in &mut level.positions {
        if p.z > 0.0 {
            *p = Point3::from(p.coords * (9.2 / 10.0));
        }
    }
    let bound = 0.8 + 1e-9;
    // Vertices on the equator (z = 0) stay where the part is, but their triangles reach up to
    // the shrunk half: their bound must be the large one too.
    let local: Vec<f64> = level
        .positions
        .iter()
        .map(|p| if p.z >= -1e-9 { bound } else { 0.0 })
        .collect();
    // Two shapes: the inner one is pushed along vertex directions, the outer one extracted
    // from the distance field: both ways of building take the local bounds.
    let uniform = specs(&level, &[1.5, 1.0], bound);
    let mut varying = uniform.clone();
    for spec in &mut varying {
        spec.vertex_bounds = Some(local.clone());
    }
    let options = OffsetOptions {
        max_cells_across: 600.0,
        ..Default::default()
    };
    let wide = nested_offsets_opt(&part, &uniform, &options).unwrap();
    let tight = nested_offsets_opt(&part, &varying, &options).unwrap();
    assert_guarantees(&wide);
    assert_guarantees(&tight);
    let thickness = |shapes: &[OffsetShape], j: usize, lower: bool| {
        let below: Vec<f64> = shapes[j]
            .mesh
            .positions
            .iter()
            .filter(|v| (v.z < -3.0) == lower && (v.z > 3.0) != lower)
            .map(|v| brute_distance(&part, v))
            .collect();
        below.iter().sum::<f64>() / below.len() as f64
    };
    for j in 0..2 {
        assert!(matches!(
            (j, tight[j].report.method),
            (0, Method::DistanceGrid { .. }) | (1, Method::NormalOffset)
        ));
        // Below, the local bound is 0: about the allowance instead of allowance + 0.8.
        assert!(
            thickness(&tight, j, true) < thickness(&wide, j, true) - 0.5,
            "shape {j}"
        );
        assert!(tight[j].report.mean_excess_mm < wide[j].report.mean_excess_mm);
        // Above, both need the full bound.
        assert!((thickness(&tight, j, false) - thickness(&wide, j, false)).abs() < 0.2);
    }
}

#[test]
fn local_bounds_must_fit_the_surface_and_the_bound() {
    let part = uv_sphere(10.0, 8, 16);
    let mut spec = specs(&part, &[1.0], 0.5);
    spec[0].vertex_bounds = Some(vec![0.1; part.positions.len() - 1]);
    let err = nested_offsets(&part, &spec).unwrap_err();
    assert!(err.to_string().contains("local bounds"), "{err}");
    spec[0].vertex_bounds = Some(vec![0.6; part.positions.len()]);
    assert!(nested_offsets(&part, &spec).is_err());
}

/// A shell thinner than two grid cells is extracted at two cells and then projected down to
/// its own radius: the excess is the chord margin, not the grid's floor.
#[test]
fn a_thin_shell_is_projected_down_from_the_grid_floor() {
    let part = uv_sphere(10.0, 48, 96);
    let allowance = 0.05;
    // An open level surface (one triangle short) is never offset along its normals.
    let mut level = part.clone();
    level.triangles.pop();
    let shapes = nested_offsets(&part, &specs(&level, &[allowance], 0.0)).unwrap();
    assert_guarantees(&shapes);
    let r = &shapes[0].report;
    let Method::DistanceGrid { spacing_mm } = r.method else {
        panic!("a sphere's own surface is offset on the grid here: {r:?}");
    };
    assert!(
        2.0 * spacing_mm > 2.0 * allowance,
        "the floor is thicker: {r:?}"
    );
    assert!(r.mean_excess_mm < 0.5 * allowance, "{r:?}");
    for p in shapes[0].mesh.positions.iter().step_by(97) {
        assert!(brute_distance(&part, p) >= allowance - 1e-6);
    }
}
