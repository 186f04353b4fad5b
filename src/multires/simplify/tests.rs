//! Tests of [`simplify`] by invariants: topology kept, features kept, geometry close.

use std::time::Instant;

use nalgebra::{Point3, Vector3};

use super::test_support::*;
use super::*;

/// The result must be a valid oriented manifold with the same components, Euler
/// characteristic and number of boundary loops as the input.
fn assert_topology_kept(input: &Mesh, output: &Mesh) {
    let (ti, to) = (manifold(input), manifold(output));
    assert_eq!(
        ti.component_count(),
        to.component_count(),
        "components changed"
    );
    assert_eq!(
        ti.euler_characteristic(&input.triangles),
        to.euler_characteristic(&output.triangles),
        "Euler characteristic changed"
    );
    assert_eq!(
        boundary_loops(input).len(),
        boundary_loops(output).len(),
        "boundary loop count changed"
    );
}

fn max_deviation(input: &Mesh, output: &Mesh, stride: usize) -> f64 {
    input
        .positions
        .iter()
        .step_by(stride)
        .map(|p| nearest_triangle(output, p).1)
        .fold(0.0, f64::max)
}

#[test]
fn cube_grid_simplifies_to_12_triangles_with_exact_corners() {
    let cube = cube_grid(10, 10.0);
    assert_eq!(cube.triangles.len(), 1200);
    let out = simplify(&cube, &SimplifyOptions::with_target(12)).unwrap();
    assert_eq!(out.mesh.triangles.len(), 12);
    assert_eq!(out.mesh.positions.len(), 8);
    for p in &out.mesh.positions {
        for c in p.coords.iter() {
            assert!(*c == 0.0 || *c == 10.0, "corner moved: {p}");
        }
    }
    assert_topology_kept(&cube, &out.mesh);
    assert!((signed_volume(&out.mesh) - 1000.0).abs() < 1e-9);
    // The 12 cube edges stay creases.
    assert_eq!(out.creases.edges.len(), 12);
    assert!(
        out.max_error < 1e-9,
        "flat collapses cost {}",
        out.max_error
    );
}

#[test]
fn torus_keeps_genus_one_at_200_triangles() {
    let torus = torus(10.0, 3.0, 60, 24);
    assert_eq!(genus(&torus), 1);
    let out = simplify(&torus, &SimplifyOptions::with_target(200)).unwrap();
    assert_eq!(out.mesh.triangles.len(), 200);
    assert_eq!(genus(&out.mesh), 1);
    assert!(signed_volume(&out.mesh) > 0.0);
    assert!(out.creases.edges.is_empty());
    assert!(inverted_triangles(&torus, &out.mesh, 1e-3).is_empty());
    let deviation = max_deviation(&torus, &out.mesh, 1);
    assert!(deviation < 1.0, "deviation {deviation}");
}

#[test]
fn torus_reduced_hard_stays_a_torus() {
    // Far below what a torus can reasonably take: the checks stop it, genus never changes.
    let torus = torus(10.0, 3.0, 40, 16);
    let out = simplify(&torus, &SimplifyOptions::with_target(0)).unwrap();
    assert_eq!(genus(&out.mesh), 1);
    assert!(
        out.mesh.triangles.len() >= 14,
        "{}",
        out.mesh.triangles.len()
    );
}

#[test]
fn open_disc_keeps_its_boundary_loop_on_the_original_polyline() {
    let sectors = 48;
    let cap = spherical_cap(20.0, 0.8, 12, sectors);
    let n = cap.positions.len();
    let original_loop: Vec<Point3<f64>> = cap.positions[n - sectors..].to_vec();
    let out = simplify(&cap, &SimplifyOptions::with_target(60)).unwrap();
    assert!(out.mesh.triangles.len() <= 60);
    assert_topology_kept(&cap, &out.mesh);
    let loops = boundary_loops(&out.mesh);
    assert_eq!(loops.len(), 1);
    // Every boundary vertex is an original boundary vertex, and the loop visits them in the
    // original cyclic order.
    let mut last: Option<usize> = None;
    let mut wraps = 0;
    for &v in &loops[0] {
        let p = out.mesh.positions[v as usize];
        let k = original_loop
            .iter()
            .position(|q| *q == p)
            .unwrap_or_else(|| panic!("boundary vertex {p} left the original boundary"));
        if last.is_some_and(|l| k < l) {
            wraps += 1;
        }
        last = Some(k);
    }
    assert!(wraps <= 1, "boundary order scrambled");
    assert!(loops[0].len() >= 3);
}

#[test]
fn flat_grid_simplifies_to_two_triangles_and_stays_planar() {
    // A tilted plane through (1, 2, 3) with normal (1, 2, 2)/3.
    let normal = Vector3::new(1.0, 2.0, 2.0) / 3.0;
    let u = Vector3::new(2.0, -1.0, 0.0).normalize();
    let v = normal.cross(&u);
    let origin = Point3::new(1.0, 2.0, 3.0);
    let plane = grid(20, |x, y| origin + u * (30.0 * x) + v * (20.0 * y));
    let out = simplify(&plane, &SimplifyOptions::with_target(2)).unwrap();
    assert_eq!(out.mesh.triangles.len(), 2);
    assert_topology_kept(&plane, &out.mesh);
    for p in &out.mesh.positions {
        assert!(
            normal.dot(&(p - origin)).abs() < 1e-9,
            "left the plane: {p}"
        );
    }
    // The four corners are what is left.
    let corners = [0usize, 20, 20 * 21, 21 * 21 - 1].map(|k| plane.positions[k]);
    for c in corners {
        assert!(out.mesh.positions.contains(&c), "corner {c} lost");
    }
    for t in 0..2 {
        assert!((triangle_normal(&out.mesh, t) - normal).norm() < 1e-9);
    }
}

#[test]
fn runs_are_bit_identical() {
    let mut bumpy = torus(10.0, 3.0, 50, 20);
    for (k, p) in bumpy.positions.iter_mut().enumerate() {
        p.z += 0.05 * ((k * 7919) % 13) as f64 / 13.0;
    }
    let options = SimplifyOptions::with_target(150);
    let a = simplify(&bumpy, &options).unwrap();
    let b = simplify(&bumpy, &options).unwrap();
    assert_eq!(a, b);
    let bits = |s: &Simplified| -> Vec<u64> {
        s.mesh
            .positions
            .iter()
            .flat_map(|p| p.coords.iter().map(|c| c.to_bits()).collect::<Vec<_>>())
            .collect()
    };
    assert_eq!(bits(&a), bits(&b));
}

#[test]
fn non_manifold_edge_is_named() {
    // Three triangles on edge {0, 1}.
    let mesh = Mesh {
        positions: vec![
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(0.0, 1.0, 0.0),
            Point3::new(0.0, -1.0, 0.0),
            Point3::new(0.0, 0.0, 1.0),
        ],
        triangles: vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]],
    };
    let err = simplify(&mesh, &SimplifyOptions::default()).unwrap_err();
    assert_eq!(
        err,
        SimplifyError::NonManifoldEdge {
            edge: [0, 1],
            triangles: 3
        }
    );
}

#[test]
fn non_manifold_vertex_is_named() {
    // Two triangles touching only at vertex 0 (a bow tie).
    let mesh = Mesh {
        positions: vec![
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(1.0, 1.0, 0.0),
            Point3::new(-1.0, 0.0, 0.0),
            Point3::new(-1.0, -1.0, 0.0),
        ],
        triangles: vec![[0, 1, 2], [0, 3, 4]],
    };
    let err = simplify(&mesh, &SimplifyOptions::default()).unwrap_err();
    assert_eq!(err, SimplifyError::NonManifoldVertex { vertex: 0 });
}

#[test]
fn inconsistent_orientation_and_bad_input_are_errors() {
    let positions = vec![
        Point3::new(0.0, 0.0, 0.0),
        Point3::new(1.0, 0.0, 0.0),
        Point3::new(0.0, 1.0, 0.0),
        Point3::new(1.0, 1.0, 0.0),
    ];
    let flipped = Mesh {
        positions: positions.clone(),
        triangles: vec![[0, 1, 2], [1, 2, 3]],
    };
    assert_eq!(
        simplify(&flipped, &SimplifyOptions::default()).unwrap_err(),
        SimplifyError::InconsistentOrientation { edge: [1, 2] }
    );
    let out_of_range = Mesh {
        positions: positions.clone(),
        triangles: vec![[0, 1, 7]],
    };
    assert!(matches!(
        simplify(&out_of_range, &SimplifyOptions::default()),
        Err(SimplifyError::IndexOutOfRange { vertex: 7, .. })
    ));
    let mut nan = Mesh {
        positions,
        triangles: vec![[0, 1, 2]],
    };
    nan.positions[2].y = f64::NAN;
    assert_eq!(
        simplify(&nan, &SimplifyOptions::default()).unwrap_err(),
        SimplifyError::NonFinitePosition { vertex: 2 }
    );
    let bad = SimplifyOptions::default().with_min_triangle_quality(2.0);
    assert!(matches!(
        simplify(&nan, &bad),
        Err(SimplifyError::InvalidOption {
            name: "min_triangle_quality",
            ..
        })
    ));
}

#[test]
fn components_and_tetrahedra_survive() {
    // A tetrahedron next to a fine cube: the tetrahedron is never collapsed, the cube goes
    // down to 12 triangles, the component count stays 2.
    let mut mesh = cube_grid(6, 5.0);
    let base = mesh.positions.len() as u32;
    mesh.positions.extend([
        Point3::new(20.0, 0.0, 0.0),
        Point3::new(21.0, 0.0, 0.0),
        Point3::new(20.0, 1.0, 0.0),
        Point3::new(20.0, 0.0, 1.0),
    ]);
    mesh.triangles.extend(
        [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]].map(|t: [u32; 3]| t.map(|v| v + base)),
    );
    let out = simplify(&mesh, &SimplifyOptions::with_target(0)).unwrap();
    assert_topology_kept(&mesh, &out.mesh);
    assert_eq!(out.mesh.triangles.len(), 16);
}

#[test]
fn max_error_stops_early() {
    let torus = torus(10.0, 3.0, 60, 24);
    let limit = 0.2;
    let out = simplify(
        &torus,
        &SimplifyOptions::with_target(0).with_max_error(Some(limit)),
    )
    .unwrap();
    assert!(out.max_error <= limit);
    assert!(
        out.mesh.triangles.len() > 200,
        "{}",
        out.mesh.triangles.len()
    );
    assert!(out.mesh.triangles.len() < torus.triangles.len());
    assert_eq!(genus(&out.mesh), 1);
}

#[test]
fn creases_of_a_folded_sheet_are_kept() {
    // A sheet folded by 90° along x = 0.5: the fold is a crease, kept straight and reported.
    let sheet = grid(10, |x, y| {
        if x <= 0.5 {
            Point3::new(x, y, 0.0)
        } else {
            Point3::new(0.5, y, 0.5 - x)
        }
    });
    let out = simplify(&sheet, &SimplifyOptions::with_target(4)).unwrap();
    assert_topology_kept(&sheet, &out.mesh);
    assert_eq!(out.mesh.triangles.len(), 4);
    assert_eq!(out.creases.edges.len(), 1);
    let [a, b] = out.creases.edges[0];
    for v in [a, b] {
        assert_eq!(out.mesh.positions[v as usize].x, 0.5);
        assert_eq!(out.mesh.positions[v as usize].z, 0.0);
    }
}

/// The shared compressor impeller, beside the clone on CI (`../shared/testdata`).
const IMPELLER: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../shared/testdata/meshes/impeller_compressor_splitter__omorellAUS_Impellor-V3.stl"
);

#[test]
fn shared_impeller_simplifies_keeping_genus_and_orientation() {
    let Ok(bytes) = std::fs::read(IMPELLER) else {
        println!("skipped: {IMPELLER} not found");
        return;
    };
    let input = read_binary_stl(&bytes).expect("binary STL");
    let t_in = manifold(&input);
    let genus_in = genus(&input);
    println!(
        "impeller input: {} triangles, {} vertices, genus {genus_in}, closed {}",
        input.triangles.len(),
        input.positions.len(),
        t_in.boundary_edge_count() == 0
    );
    let options = SimplifyOptions::with_target(1500);
    let start = Instant::now();
    let out = simplify(&input, &options).unwrap();
    let elapsed = start.elapsed();
    assert_eq!(genus(&out.mesh), genus_in);
    assert_topology_kept(&input, &out.mesh);
    assert!(signed_volume(&out.mesh) > 0.0);

    // Flips: output triangles facing against the input surface near them.
    let flipped = inverted_triangles(&input, &out.mesh, 0.01).len();
    let worst_quality = out
        .mesh
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| out.mesh.positions[v as usize]);
            collapse::quality(&a, &b, &c)
        })
        .fold(f64::INFINITY, f64::min);
    let deviation = max_deviation(&input, &out.mesh, 3);
    println!(
        "impeller: {} -> {} triangles ({} collapses) in {:.1} ms; genus {}; {} creases; \
         max collapse error {:.4} mm; max deviation (1/3 of input vertices) {:.4} mm; \
         flipped vs input {}; worst quality {:.4}",
        input.triangles.len(),
        out.mesh.triangles.len(),
        out.collapses,
        elapsed.as_secs_f64() * 1e3,
        genus(&out.mesh),
        out.creases.edges.len(),
        out.max_error,
        deviation,
        flipped,
        worst_quality
    );
    assert!(
        out.mesh.triangles.len() <= 2000,
        "{}",
        out.mesh.triangles.len()
    );
    assert_eq!(flipped, 0);
}

#[test]
fn tetrahedron_is_never_collapsed_even_without_geometric_checks() {
    let tetra = Mesh {
        positions: vec![
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(0.0, 1.0, 0.0),
            Point3::new(0.0, 0.0, 1.0),
        ],
        triangles: vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
    };
    let permissive = SimplifyOptions::with_target(0)
        .with_crease_angle_deg(180.0)
        .with_max_normal_turn_deg(180.0)
        .with_min_triangle_quality(0.0);
    let out = simplify(&tetra, &permissive).unwrap();
    assert_eq!(out.mesh, tetra);
    assert_eq!(out.collapses, 0);
}
