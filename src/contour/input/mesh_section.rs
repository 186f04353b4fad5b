//! Z-sections of closed triangle meshes as outlines (issue #6, point 1): the part profile of a
//! 2.5D job cut from a 3D part at one height.
//!
//! The plane z = Z is intersected with the mesh by [`crate::mesh::plane_section`]
//! (one segment per crossed triangle, chained by shared edges). The loops become polygons in
//! XY, collinear runs are simplified (Douglas–Peucker on the closed polygon) within the outline
//! tolerance, and the region is built by the outline reader's own region builder under the
//! even-odd rule: the inside of a closed surface is where a ray crosses it an odd number of
//! times, so a loop's orientation comes from its nesting depth and signed area, never from the
//! winding the section happened to produce. Crossing loops (a self-intersecting mesh) are
//! refused exactly like crossing outline paths.
//!
//! Refused, naming the file and Z: a plane that misses the part, open loops (the mesh is not
//! closed there), and a plane running along a horizontal face (the section is not defined
//! there; a slightly different Z is suggested).

use super::fill::{FillRule, build_region};
use super::{OutlineError, RawContour};
use crate::contour::geometry::{Point2, Segment, Shape, Vertex};
use crate::contour::segops::point_distance;
use crate::mesh::Mesh;
use crate::mesh::plane_section;

/// Relative size (of the mesh's bounding-box diagonal) under which a vertex counts as lying on
/// the plane when looking for horizontal faces in it.
const ON_PLANE_REL: f64 = 1e-9;

/// The region of the section of the closed mesh `mesh` by the plane z = `z` (mm, like the
/// mesh), as a [`Shape`]: outer boundaries counter-clockwise, holes clockwise. Straight runs
/// are merged within `tolerance` mm. `name` names the mesh in errors.
pub fn mesh_section(
    mesh: &Mesh,
    z: f64,
    tolerance: f64,
    name: &str,
) -> Result<Shape, OutlineError> {
    let options_error = |message: String| OutlineError::Options {
        file: name.to_string(),
        message,
    };
    if !z.is_finite() {
        return Err(options_error(format!("z must be a finite number, got {z}")));
    }
    if !(tolerance.is_finite() && tolerance > 0.0) {
        return Err(options_error(format!(
            "tolerance must be positive and finite, got {tolerance}"
        )));
    }
    let aabb = mesh.aabb();
    let (zmin, zmax) = (aabb.min.z, aabb.max.z);
    if mesh.triangles.is_empty() || !(zmin..=zmax).contains(&z) {
        return Err(OutlineError::PlaneMisses {
            file: name.to_string(),
            z,
            zmin,
            zmax,
        });
    }
    let eps = ON_PLANE_REL * aabb.diagonal();
    if let Some(t) = mesh.triangles.iter().position(|tri| {
        tri.iter()
            .all(|&v| (mesh.positions[v as usize].z - z).abs() <= eps)
    }) {
        return Err(OutlineError::DegenerateSection {
            file: name.to_string(),
            z,
            triangle: t,
            suggestion: suggest_z(z, zmin, zmax),
        });
    }
    let normals: Vec<_> = (0..mesh.triangles.len())
        .map(|t| mesh.face_normal(t))
        .collect();
    let curves = plane_section(mesh, &normals, &nalgebra::Vector3::z(), z);
    if curves.is_empty() {
        return Err(OutlineError::PlaneMisses {
            file: name.to_string(),
            z,
            zmin,
            zmax,
        });
    }
    let mut raw = Vec::with_capacity(curves.len());
    for (i, c) in curves.iter().enumerate() {
        let points = distinct_points(c.points.iter().map(|d| Point2::new(d.point.x, d.point.y)));
        if !c.closed {
            let (a, b) = (
                points.first().copied().unwrap_or_else(Point2::origin),
                points.last().copied().unwrap_or_else(Point2::origin),
            );
            return Err(OutlineError::OpenSection {
                file: name.to_string(),
                z,
                x: b.x,
                y: b.y,
                gap: (b - a).norm(),
            });
        }
        let kept = simplify_closed(&points, tolerance);
        raw.push(RawContour {
            vertices: kept.iter().map(|p| Vertex::line(p.x, p.y)).collect(),
            label: format!("loop {} of the section at z = {z} mm", i + 1),
            rule: FillRule::EvenOdd,
        });
    }
    build_region(raw, name, tolerance)
}

/// A Z near `z` to try instead, inside the part's height range: a hundredth of a millimetre
/// (or of the part height, if smaller) below, or above at the bottom face.
fn suggest_z(z: f64, zmin: f64, zmax: f64) -> f64 {
    let dz = 0.01_f64.min(0.01 * (zmax - zmin)).max(f64::EPSILON);
    if z - dz > zmin { z - dz } else { z + dz }
}

/// The points without consecutive repeats, the closing repeat included (the section lists
/// every crossing twice, once per triangle).
fn distinct_points(points: impl Iterator<Item = Point2>) -> Vec<Point2> {
    let mut out: Vec<Point2> = Vec::new();
    for p in points {
        if out.last() != Some(&p) {
            out.push(p);
        }
    }
    while out.len() > 1 && out.first() == out.last() {
        out.pop();
    }
    out
}

/// Douglas–Peucker on a closed polygon: the kept vertices are within `tol` of every dropped
/// one's place on the original. The polygon is split at its first vertex and the vertex
/// farthest from it, so the result does not depend on a chord through nowhere.
fn simplify_closed(points: &[Point2], tol: f64) -> Vec<Point2> {
    let n = points.len();
    if n <= 3 {
        return points.to_vec();
    }
    let far = (1..n)
        .max_by(|&a, &b| {
            (points[a] - points[0])
                .norm_squared()
                .total_cmp(&(points[b] - points[0]).norm_squared())
                .then(b.cmp(&a))
        })
        .unwrap_or(n / 2);
    let mut keep = vec![false; n];
    keep[0] = true;
    keep[far] = true;
    // Explicit stack: loops from fine meshes have many thousands of points.
    let mut stack = vec![(0, far), (far, n)];
    while let Some((a, b)) = stack.pop() {
        let (pa, pb) = (points[a], points[b % n]);
        let mut worst = (0.0, a);
        for (i, &p) in points.iter().enumerate().take(b).skip(a + 1) {
            let d = point_segment_distance(p, pa, pb);
            if d > worst.0 {
                worst = (d, i);
            }
        }
        if worst.0 > tol {
            keep[worst.1] = true;
            stack.push((a, worst.1));
            stack.push((worst.1, b));
        }
    }
    points
        .iter()
        .zip(keep)
        .filter_map(|(p, k)| k.then_some(*p))
        .collect()
}

fn point_segment_distance(p: Point2, start: Point2, end: Point2) -> f64 {
    point_distance(p, &Segment::Line { start, end }).0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Point3;
    use crate::mesh::fixtures::{cuboid, torus};
    use std::f64::consts::PI;

    /// A closed cylinder of radius `r` and height `h` around the Z axis, base at z = 0,
    /// outward, `n` sides.
    fn cylinder(r: f64, h: f64, n: u32) -> Mesh {
        let mut positions = vec![Point3::new(0.0, 0.0, 0.0), Point3::new(0.0, 0.0, h)];
        for i in 0..n {
            let a = 2.0 * PI * i as f64 / n as f64;
            positions.push(Point3::new(r * a.cos(), r * a.sin(), 0.0));
            positions.push(Point3::new(r * a.cos(), r * a.sin(), h));
        }
        let (lo, hi) = (|i: u32| 2 + 2 * (i % n), |i: u32| 3 + 2 * (i % n));
        let mut triangles = Vec::new();
        for i in 0..n {
            triangles.push([0, lo(i + 1), lo(i)]);
            triangles.push([1, hi(i), hi(i + 1)]);
            triangles.push([lo(i), lo(i + 1), hi(i + 1)]);
            triangles.push([lo(i), hi(i + 1), hi(i)]);
        }
        Mesh {
            positions,
            triangles,
        }
    }

    fn shape_size(shape: &Shape) -> f64 {
        crate::contour::input::points_size(
            shape
                .contours
                .iter()
                .flat_map(|c| c.vertices.iter().map(|v| &v.point)),
        )
    }

    fn area(shape: &Shape) -> f64 {
        shape.contours.iter().map(|c| c.signed_area()).sum()
    }

    fn perimeter(shape: &Shape) -> f64 {
        shape.contours.iter().map(|c| c.length()).sum()
    }

    #[test]
    fn box_section_is_its_rectangle_counter_clockwise() {
        let s = mesh_section(&cuboid(20.0, 30.0, 10.0), 4.0, 1e-3, "box.stl").expect("section");
        assert_eq!(s.contours.len(), 1);
        // The section of a 12-triangle box has a vertex at every triangle edge it crosses;
        // the collinear ones are merged down to the four corners.
        assert_eq!(s.contours[0].vertices.len(), 4);
        assert!((area(&s) - 600.0).abs() < 1e-9);
        assert!((perimeter(&s) - 100.0).abs() < 1e-9);
        assert!((shape_size(&s) - (20f64.hypot(30.0))).abs() < 1e-9);
    }

    #[test]
    fn inside_out_box_gives_the_same_region() {
        // The region comes from nesting, not from the winding the section produced.
        let mut m = cuboid(20.0, 30.0, 10.0);
        for t in &mut m.triangles {
            t.swap(1, 2);
        }
        let s = mesh_section(&m, 4.0, 1e-3, "box.stl").expect("section");
        assert!((area(&s) - 600.0).abs() < 1e-9);
    }

    #[test]
    fn cylinder_section_is_within_the_chord_error_of_the_circle() {
        let (r, n) = (15.0, 256);
        let s = mesh_section(&cylinder(r, 10.0, n), 3.3, 1e-3, "cyl.stl").expect("section");
        assert_eq!(s.contours.len(), 1);
        // The section is the inscribed n-gon: area and perimeter in closed form, and both
        // within the chord error of the circle's.
        let half = PI / n as f64;
        let (a_poly, p_poly) = (
            n as f64 * r * r * half.sin() * half.cos(),
            2.0 * n as f64 * r * half.sin(),
        );
        assert!((area(&s) - a_poly).abs() < 1e-6, "{}", area(&s));
        assert!((perimeter(&s) - p_poly).abs() < 1e-6);
        let sagitta = r * (1.0 - half.cos());
        assert!((PI * r * r - area(&s)).abs() <= 2.0 * PI * r * sagitta);
        assert!((2.0 * PI * r - perimeter(&s)).abs() <= 2.0 * PI * sagitta + 1e-9);
    }

    #[test]
    fn torus_section_through_its_middle_has_a_hole() {
        let (big, small) = (20.0, 5.0);
        let s = mesh_section(&torus(big, small, 128, 64), 0.5, 1e-3, "torus.obj").expect("section");
        assert_eq!(s.contours.len(), 2);
        let mut areas: Vec<f64> = s.contours.iter().map(|c| c.signed_area()).collect();
        areas.sort_by(f64::total_cmp);
        assert!(
            areas[0] < 0.0 && areas[1] > 0.0,
            "outer CCW, hole CW: {areas:?}"
        );
        // An annulus between radii big ± sqrt(small² − z²), within the facets' chord error.
        let w = (small * small - 0.25f64).sqrt();
        let exact = PI * ((big + w).powi(2) - (big - w).powi(2));
        assert!(
            (area(&s) - exact).abs() < 0.01 * exact,
            "{} vs {exact}",
            area(&s)
        );
    }

    /// Metamorphic: turning the part about the Z axis turns the section, and its area and
    /// perimeter stay.
    #[test]
    fn rotated_torus_gives_the_same_section_figures() {
        let m = torus(20.0, 5.0, 96, 48);
        let a = mesh_section(&m, 1.5, 1e-3, "torus.obj").expect("section");
        let (s, c) = 0.7f64.sin_cos();
        let mut turned = m.clone();
        for p in &mut turned.positions {
            *p = Point3::new(c * p.x - s * p.y, s * p.x + c * p.y, p.z);
        }
        let b = mesh_section(&turned, 1.5, 1e-3, "torus.obj").expect("section");
        assert_eq!(a.contours.len(), b.contours.len());
        assert!((area(&a) - area(&b)).abs() < 1e-9 * area(&a));
        assert!((perimeter(&a) - perimeter(&b)).abs() < 1e-9 * perimeter(&a));
    }

    #[test]
    fn plane_above_the_torus_misses() {
        let e = mesh_section(&torus(20.0, 5.0, 64, 32), 5.5, 1e-3, "torus.obj").unwrap_err();
        let msg = e.to_string();
        assert!(
            msg.starts_with("torus.obj: the plane z = 5.5 mm misses"),
            "{msg}"
        );
    }

    #[test]
    fn plane_outside_the_part_is_refused() {
        let e = mesh_section(&cuboid(1.0, 1.0, 1.0), -2.0, 1e-3, "cube.stl").unwrap_err();
        assert!(matches!(e, OutlineError::PlaneMisses { .. }), "{e}");
        assert!(e.to_string().contains("cube.stl") && e.to_string().contains("-2"));
    }

    #[test]
    fn open_mesh_is_refused() {
        let mut m = cuboid(10.0, 10.0, 10.0);
        // Drop one side face: the section at mid height is open there.
        m.triangles
            .retain(|t| !t.iter().all(|&v| m.positions[v as usize].x.abs() < 1e-12));
        let e = mesh_section(&m, 5.0, 1e-3, "open.stl").unwrap_err();
        assert!(matches!(e, OutlineError::OpenSection { .. }), "{e}");
        let msg = e.to_string();
        assert!(msg.contains("open.stl") && msg.contains("z = 5"), "{msg}");
    }

    #[test]
    fn plane_along_a_horizontal_face_is_refused_with_a_suggestion() {
        let e = mesh_section(&cuboid(10.0, 10.0, 10.0), 10.0, 1e-3, "box.stl").unwrap_err();
        match &e {
            OutlineError::DegenerateSection { suggestion, .. } => {
                assert!(*suggestion < 10.0 && *suggestion > 9.9);
                // The suggested Z works.
                let s = mesh_section(&cuboid(10.0, 10.0, 10.0), *suggestion, 1e-3, "box.stl")
                    .expect("suggested z");
                assert!((area(&s) - 100.0).abs() < 1e-9);
            }
            other => panic!("expected a degenerate section, got {other}"),
        }
        assert!(e.to_string().contains("horizontal face"), "{e}");
    }

    #[test]
    fn simplification_stays_within_tolerance() {
        // A wavy closed polygon: every dropped point is within tol of the kept polygon.
        let n = 2000;
        let pts: Vec<Point2> = (0..n)
            .map(|i| {
                let a = 2.0 * PI * i as f64 / n as f64;
                let rr = 10.0 + 0.05 * (7.0 * a).sin();
                Point2::new(rr * a.cos(), rr * a.sin())
            })
            .collect();
        let tol = 0.01;
        let kept = simplify_closed(&pts, tol);
        assert!(kept.len() < n / 4, "{}", kept.len());
        let m = kept.len();
        for p in &pts {
            let d = (0..m)
                .map(|i| point_segment_distance(*p, kept[i], kept[(i + 1) % m]))
                .fold(f64::INFINITY, f64::min);
            assert!(d <= tol + 1e-12, "{d}");
        }
    }
}
