//! Closed forms: a sphere of revolution (poles and a seam inside one face), a cylinder in two
//! faces sampled differently along their shared edges (junctions), and a plane in NURBS form
//! (exactly flat: the fewest triangles).

use nalgebra::{Point3, Unit, Vector3};

use super::*;
use crate::cad::iges::{Curve, Surface};
use crate::cad::nurbs::NurbsSurface;
use crate::mesh::topology::Topology;

/// Distance from the origin to the nearest point of a triangle.
fn origin_distance(t: [Point3<f64>; 3]) -> f64 {
    let [a, b, c] = t;
    let n = (b - a).cross(&(c - a));
    let inside = |p: &Point3<f64>| {
        [(a, b), (b, c), (c, a)]
            .iter()
            .all(|(x, y)| (y - x).cross(&(p - x)).dot(&n) >= 0.0)
    };
    let plane_foot = Point3::from(n * (a.coords.dot(&n) / n.norm_squared()));
    if inside(&plane_foot) {
        return plane_foot.coords.norm();
    }
    [(a, b), (b, c), (c, a)]
        .iter()
        .map(|(x, y)| {
            let d = y - x;
            let s = (-x.coords.dot(&d) / d.norm_squared()).clamp(0.0, 1.0);
            (x.coords + d * s).norm()
        })
        .fold(f64::INFINITY, f64::min)
}

fn face(surface: Surface, outer: Option<Curve>) -> Face {
    Face {
        de: 1,
        line: 1,
        surface,
        outer,
        holes: Vec::new(),
        model_boundaries: Vec::new(),
    }
}

/// A sphere of radius `r` about the origin: a semicircle from the south pole over +x to the
/// north pole, turned a full turn about z.
fn sphere(r: f64) -> Face {
    face(
        Surface::Revolution {
            axis: (Point3::origin(), Point3::new(0.0, 0.0, 1.0)),
            generatrix: Box::new(Curve::Arc {
                centre: Point3::origin(),
                start: Point3::new(0.0, 0.0, -r),
                sweep: std::f64::consts::PI,
                normal: Unit::new_normalize(Vector3::new(0.0, -1.0, 0.0)),
            }),
            t: (0.0, std::f64::consts::PI),
            angles: (0.0, std::f64::consts::TAU),
        },
        None,
    )
}

/// One closed surface: Euler characteristic 2, no open or non-manifold edge, outward.
fn assert_closed_sphere_like(t: &Tessellation) {
    let topo = Topology::analyse(&t.mesh.triangles, t.mesh.positions.len());
    assert!(topo.is_closed_manifold(), "{:?}", t.report);
    assert_eq!(t.report.open_seam_edges, 0);
    assert_eq!(t.report.non_manifold_edges, 0);
    let v = t.mesh.positions.len() as i64;
    let f = t.mesh.triangles.len() as i64;
    assert_eq!(v - 3 * f / 2 + f, 2, "Euler characteristic");
    assert!(t.mesh.signed_volume() > 0.0);
}

#[test]
fn a_sphere_of_revolution_closes_at_its_poles_and_seam_within_the_tolerance() {
    let r = 10.0;
    let faces = [sphere(r)];
    for tolerance in [0.1, 0.01] {
        let t = tessellate(&faces, &TessellateOptions { tolerance }).unwrap();
        assert_closed_sphere_like(&t);
        // Closed form: every vertex on the sphere; the mesh's point nearest the centre is at
        // most the tolerance inside it.
        for p in &t.mesh.positions {
            assert!((p.coords.norm() - r).abs() < 1e-9, "{p}");
        }
        let worst = (0..t.mesh.triangles.len())
            .map(|i| r - origin_distance(t.mesh.corners(i)))
            .fold(0.0, f64::max);
        assert!(worst <= tolerance, "{worst} > {tolerance}");
        // The sampled measure agrees with the closed form to within its sampling.
        let d = t.deviation(&faces, 6);
        assert!(
            d.max <= tolerance && d.max > 0.5 * worst,
            "{d:?} vs {worst}"
        );
        // Not wastefully fine either: the chord rule for a sphere, 2πr²/(area of a triangle
        // with edges √(8 r tol)), within a small factor.
        let edge = (8.0 * r * tolerance).sqrt();
        let ideal = 4.0 * std::f64::consts::PI * r * r / (edge * edge * 3f64.sqrt() / 4.0);
        assert!(
            (t.mesh.triangles.len() as f64) < 6.0 * ideal,
            "{} vs {ideal}",
            t.mesh.triangles.len()
        );
    }
}

/// A cylinder r = 5, z ∈ [0, 20], as two half faces; the second's outer loop splits the
/// shared edges at odd places, so the first must take junction vertices to match.
#[test]
fn two_faces_sampled_differently_share_their_edges() {
    let r = 5.0;
    let line = Curve::Line {
        start: Point3::new(r, 0.0, 0.0),
        end: Point3::new(r, 0.0, 20.0),
    };
    let half = |a0: f64, a1: f64, outer: Option<Curve>| {
        face(
            Surface::Revolution {
                axis: (Point3::origin(), Point3::new(0.0, 0.0, 1.0)),
                generatrix: Box::new(line.clone()),
                t: (0.0, 1.0),
                angles: (a0, a1),
            },
            outer,
        )
    };
    let pi = std::f64::consts::PI;
    let seg = |a: (f64, f64), b: (f64, f64)| Curve::Line {
        start: Point3::new(a.0, a.1, 0.0),
        end: Point3::new(b.0, b.1, 0.0),
    };
    // (t, θ) loop of the second half, its straight sides cut at t = 0.37 and 0.71.
    let outer = Curve::Composite(vec![
        seg((0.0, pi), (0.0, 2.0 * pi)),
        seg((0.0, 2.0 * pi), (0.37, 2.0 * pi)),
        seg((0.37, 2.0 * pi), (1.0, 2.0 * pi)),
        seg((1.0, 2.0 * pi), (1.0, pi)),
        seg((1.0, pi), (0.71, pi)),
        seg((0.71, pi), (0.0, pi)),
    ]);
    let faces = [half(0.0, pi, None), half(pi, 2.0 * pi, Some(outer))];
    let t = tessellate(&faces, &TessellateOptions { tolerance: 0.01 }).unwrap();
    assert!(t.report.junction_vertices >= 4, "{:?}", t.report);
    // Open: exactly the two rims (2πr each), nothing along the straight seams.
    assert_eq!(t.report.open_seams.len(), 2, "{:?}", t.report.open_seams);
    let rims = 2.0 * (2.0 * pi * r);
    assert!(
        (t.report.open_seam_length - rims).abs() < 0.01 * rims,
        "{} vs {rims}",
        t.report.open_seam_length
    );
    assert_eq!(t.report.non_manifold_edges, 0);
    assert!(t.deviation(&faces, 6).max <= 0.01);
    // Both halves wound the same way (the cylinder's outside).
    let normals_out = (0..t.mesh.triangles.len()).all(|i| {
        let c = t.mesh.corners(i);
        let centre = (c[0].coords + c[1].coords + c[2].coords) / 3.0;
        let n = t.mesh.face_normal(i);
        n.dot(&Vector3::new(centre.x, centre.y, 0.0)) > 0.0
    }) || (0..t.mesh.triangles.len()).all(|i| {
        let c = t.mesh.corners(i);
        let centre = (c[0].coords + c[1].coords + c[2].coords) / 3.0;
        t.mesh
            .face_normal(i)
            .dot(&Vector3::new(centre.x, centre.y, 0.0))
            < 0.0
    });
    assert!(normals_out);
}

/// The square [0, 10]² in z = 0 as a bilinear NURBS surface on [0, 1]².
fn flat_square() -> NurbsSurface {
    let net = vec![
        vec![Point3::new(0.0, 0.0, 0.0), Point3::new(0.0, 10.0, 0.0)],
        vec![Point3::new(10.0, 0.0, 0.0), Point3::new(10.0, 10.0, 0.0)],
    ];
    NurbsSurface::new(
        [1, 1],
        vec![0.0, 0.0, 1.0, 1.0],
        vec![0.0, 0.0, 1.0, 1.0],
        &net,
        &[vec![1.0; 2], vec![1.0; 2]],
    )
    .expect("a valid net")
}

/// A bilinear NURBS square is flat: its corners' two triangles meet any tolerance, and the
/// sampled deviation is round-off.
#[test]
fn a_flat_nurbs_face_needs_only_its_corners() {
    let surface = flat_square();
    let faces = [face(
        Surface::Nurbs {
            surface,
            u: (0.0, 1.0),
            v: (0.0, 1.0),
        },
        None,
    )];
    let t = tessellate(&faces, &TessellateOptions::default()).unwrap();
    assert!(t.mesh.triangles.len() <= 30, "{}", t.mesh.triangles.len());
    assert!((t.mesh.surface_area() - 100.0).abs() < 1e-9);
    assert!(t.deviation(&faces, 8).max < 1e-12);
}

/// A trim loop that crosses itself cannot bound a region: the face is refused by index and
/// directory line, not triangulated into nonsense.
#[test]
fn a_self_crossing_trim_is_refused_naming_the_face() {
    let surface = flat_square();
    // The diagonals cross at 8/15 of the first: not at any sample point of the sides.
    let corners = [(0.1, 0.1), (0.9, 0.8), (0.9, 0.1), (0.1, 0.9)];
    let bow_tie = Curve::Composite(
        (0..4)
            .map(|i| {
                let (a, b) = (corners[i], corners[(i + 1) % 4]);
                Curve::Line {
                    start: Point3::new(a.0, a.1, 0.0),
                    end: Point3::new(b.0, b.1, 0.0),
                }
            })
            .collect(),
    );
    let mut bad = face(
        Surface::Nurbs {
            surface,
            u: (0.0, 1.0),
            v: (0.0, 1.0),
        },
        Some(bow_tie),
    );
    bad.line = 77;
    let faces = [sphere(5.0), bad];
    let Err(error) = tessellate(&faces, &TessellateOptions::default()) else {
        panic!("a self-crossing trim was triangulated");
    };
    assert_eq!((error.face, error.line), (1, 77), "{error}");
    assert!(error.to_string().contains("cross"), "{error}");
}
