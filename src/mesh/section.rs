//! Plane sections of a triangle mesh: the drive curves of a pass family.
//!
//! Each triangle crossing the plane contributes one segment between the crossings of two of
//! its edges. Segments are oriented consistently (the crossing where the sign goes − to + along
//! the triangle's winding is the start), so on an oriented manifold every segment's end edge is
//! the next segment's start edge and chaining is a lookup. Vertices exactly on the plane are
//! treated as above it (symbolic perturbation), so no crossing is ever counted twice.

use std::collections::HashMap;

use crate::geom::{Point3, Vector3};
use crate::mesh::Mesh;

/// A point on a drive curve with the unit normal of the triangle it lies in.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DrivePoint {
    pub point: Point3,
    pub normal: Vector3,
}

/// One connected piece of a section: a closed loop or an open chain (on open meshes).
#[derive(Clone, Debug, PartialEq)]
pub struct SectionCurve {
    /// Segment end points in order; a point where the curve crosses into another triangle
    /// appears twice, once with each triangle's normal (the ball rolls over the edge there).
    pub points: Vec<DrivePoint>,
    pub closed: bool,
}

struct Segment {
    start_edge: (u32, u32),
    end_edge: (u32, u32),
    start: Point3,
    end: Point3,
    normal: Vector3,
}

/// The curves where the plane `{x : normal·x = offset}` cuts `mesh`, in a deterministic order.
pub fn plane_section(
    mesh: &Mesh,
    face_normals: &[Vector3],
    normal: &Vector3,
    offset: f64,
) -> Vec<SectionCurve> {
    let side: Vec<f64> = mesh
        .positions
        .iter()
        .map(|p| normal.dot(&p.coords) - offset)
        .collect();
    level_section(mesh, face_normals, &side)
}

/// The curves where the function given by its value at each vertex (linear on each triangle)
/// crosses zero, oriented and chained as plane sections are: a plane section is the level
/// set of the signed distance to the plane; the impeller's blade loops are level sets of the
/// height above the hub.
pub fn level_section(mesh: &Mesh, face_normals: &[Vector3], side: &[f64]) -> Vec<SectionCurve> {
    let above = |i: u32| side[i as usize] >= 0.0;
    let crossing = |a: u32, b: u32| {
        let (da, db) = (side[a as usize], side[b as usize]);
        let t = da / (da - db);
        let (pa, pb) = (mesh.positions[a as usize], mesh.positions[b as usize]);
        // Interpolate from the lower index so both triangles sharing the edge get the same bits.
        if a < b {
            pa + (pb - pa) * t
        } else {
            pb + (pa - pb) * (1.0 - t)
        }
    };
    let key = |a: u32, b: u32| (a.min(b), a.max(b));
    let mut segments = Vec::new();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let mut rising = None;
        let mut falling = None;
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            match (above(a), above(b)) {
                (false, true) => rising = Some((a, b)),
                (true, false) => falling = Some((a, b)),
                _ => {}
            }
        }
        if let (Some((ra, rb)), Some((fa, fb))) = (rising, falling) {
            segments.push(Segment {
                start_edge: key(fa, fb),
                end_edge: key(ra, rb),
                start: crossing(fa, fb),
                end: crossing(ra, rb),
                normal: face_normals[t],
            });
        }
    }
    chain(segments)
}

fn chain(segments: Vec<Segment>) -> Vec<SectionCurve> {
    let by_start: HashMap<(u32, u32), usize> = segments
        .iter()
        .enumerate()
        .map(|(i, s)| (s.start_edge, i))
        .collect();
    let has_predecessor: std::collections::HashSet<(u32, u32)> =
        segments.iter().map(|s| s.end_edge).collect();
    let mut used = vec![false; segments.len()];
    let mut curves = Vec::new();
    let follow = |first: usize, used: &mut Vec<bool>| {
        let mut points = Vec::new();
        let mut i = first;
        let closed = loop {
            used[i] = true;
            let s = &segments[i];
            points.push(DrivePoint {
                point: s.start,
                normal: s.normal,
            });
            points.push(DrivePoint {
                point: s.end,
                normal: s.normal,
            });
            match by_start.get(&s.end_edge) {
                Some(&next) if next == first => break true,
                Some(&next) if !used[next] => i = next,
                _ => break false,
            }
        };
        SectionCurve { points, closed }
    };
    // Open chains first from their true starts, then the loops, each from its lowest segment.
    for first in 0..segments.len() {
        if !used[first] && !has_predecessor.contains(&segments[first].start_edge) {
            curves.push(follow(first, &mut used));
        }
    }
    for first in 0..segments.len() {
        if !used[first] {
            curves.push(follow(first, &mut used));
        }
    }
    curves
}

impl SectionCurve {
    /// Total length along the points.
    pub fn length(&self) -> f64 {
        self.points
            .windows(2)
            .map(|w| (w[1].point - w[0].point).norm())
            .sum()
    }

    /// The curve with the points a ball of `radius` does not need dropped: Douglas–Peucker on
    /// the ball-centre polyline (point + radius·normal), keeping every point whose removal
    /// would move that polyline more than `tolerance`, and never leaving a span longer than
    /// `max_step` that had points inside. A finely remeshed surface crosses many small
    /// triangles; their crossings add poses, not accuracy.
    pub fn simplified(&self, radius: f64, tolerance: f64, max_step: f64) -> SectionCurve {
        let n = self.points.len();
        if n <= 2 {
            return self.clone();
        }
        let centre: Vec<Point3> = self
            .points
            .iter()
            .map(|p| p.point + p.normal * radius)
            .collect();
        let mut keep = vec![false; n];
        keep[0] = true;
        keep[n - 1] = true;
        let mut spans = vec![(0usize, n - 1)];
        while let Some((a, b)) = spans.pop() {
            if b <= a + 1 {
                continue;
            }
            let (ca, cb) = (centre[a], centre[b]);
            let ab = cb - ca;
            let len2 = ab.norm_squared();
            let mut worst = (0.0, a + (b - a) / 2);
            for (i, c) in centre.iter().enumerate().take(b).skip(a + 1) {
                let t = if len2 > 0.0 {
                    ((c - ca).dot(&ab) / len2).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                let d = (c - (ca + ab * t)).norm();
                if d > worst.0 {
                    worst = (d, i);
                }
            }
            // Splitting a too-long span at its farthest point (or its middle) keeps both rules.
            let too_long = (self.points[b].point - self.points[a].point).norm() > max_step;
            if worst.0 > tolerance || too_long {
                keep[worst.1] = true;
                spans.push((a, worst.1));
                spans.push((worst.1, b));
            }
        }
        SectionCurve {
            points: self
                .points
                .iter()
                .zip(&keep)
                .filter(|(_, k)| **k)
                .map(|(p, _)| *p)
                .collect(),
            closed: self.closed,
        }
    }

    /// Inserts points so that no two consecutive points are more than `step` apart, drops
    /// repeated points whose normals agree, and, for a closed curve, repeats the first point at
    /// the end so the pass returns to its start.
    pub fn resampled(&self, step: f64) -> Vec<DrivePoint> {
        let mut out: Vec<DrivePoint> = Vec::with_capacity(self.points.len());
        let push = |p: DrivePoint, out: &mut Vec<DrivePoint>| {
            if let Some(last) = out.last()
                && (last.point - p.point).norm() < 1e-9
                && (last.normal - p.normal).norm() < 1e-9
            {
                return;
            }
            out.push(p);
        };
        for w in self.points.windows(2) {
            let (a, b) = (w[0], w[1]);
            push(a, &mut out);
            if (a.normal - b.normal).norm() < 1e-12 {
                let len = (b.point - a.point).norm();
                let pieces = (len / step).ceil().max(1.0) as usize;
                for k in 1..pieces {
                    let t = k as f64 / pieces as f64;
                    push(
                        DrivePoint {
                            point: a.point + (b.point - a.point) * t,
                            normal: a.normal,
                        },
                        &mut out,
                    );
                }
            }
        }
        if let Some(&last) = self.points.last() {
            push(last, &mut out);
        }
        if self.closed
            && let Some(&first) = out.first()
        {
            push(first, &mut out);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::fixtures::{cuboid, torus, uv_sphere};

    fn normals(m: &Mesh) -> Vec<Vector3> {
        (0..m.triangles.len()).map(|t| m.face_normal(t)).collect()
    }

    #[test]
    fn box_section_is_one_rectangle() {
        let m = cuboid(10.0, 20.0, 30.0);
        let c = plane_section(&m, &normals(&m), &Vector3::x(), 4.0);
        assert_eq!(c.len(), 1);
        assert!(c[0].closed);
        assert!((c[0].length() - 2.0 * (20.0 + 30.0)).abs() < 1e-9);
        assert!(c[0].points.iter().all(|p| (p.point.x - 4.0).abs() < 1e-12));
    }

    #[test]
    fn torus_sections_have_the_right_loop_count() {
        let m = torus(20.0, 5.0, 64, 32);
        let n = normals(&m);
        // Through the hole: two loops; through the tube only: one; outside: none.
        assert_eq!(plane_section(&m, &n, &Vector3::x(), 0.0).len(), 2);
        assert_eq!(plane_section(&m, &n, &Vector3::x(), 23.0).len(), 1);
        assert_eq!(plane_section(&m, &n, &Vector3::x(), 26.0).len(), 0);
        // Horizontal section at the equator: two circles (inner and outer).
        let eq = plane_section(&m, &n, &Vector3::z(), 0.0);
        assert_eq!(eq.len(), 2);
        assert!(eq.iter().all(|c| c.closed));
    }

    #[test]
    fn plane_through_vertices_still_gives_closed_loops() {
        // The UV sphere has a ring of vertices exactly on z = 0 (equator when stacks is even).
        let m = uv_sphere(10.0, 16, 24);
        let c = plane_section(&m, &normals(&m), &Vector3::z(), 0.0);
        assert_eq!(c.len(), 1);
        assert!(c[0].closed);
        let circumference = 2.0 * std::f64::consts::PI * 10.0;
        assert!((c[0].length() - circumference).abs() / circumference < 0.02);
    }

    #[test]
    fn resampling_respects_the_step_and_keeps_the_shape() {
        let m = cuboid(10.0, 20.0, 30.0);
        let c = &plane_section(&m, &normals(&m), &Vector3::x(), 4.0)[0];
        let r = c.resampled(0.7);
        assert!(
            r.windows(2)
                .all(|w| (w[1].point - w[0].point).norm() <= 0.7 + 1e-12)
        );
        assert_eq!(r.first().unwrap().point, r.last().unwrap().point);
        let len: f64 = r.windows(2).map(|w| (w[1].point - w[0].point).norm()).sum();
        assert!((len - c.length()).abs() < 1e-9);
    }

    /// Simplifying keeps every dropped ball centre within the tolerance of the kept chords
    /// (brute force over all original points), keeps the ends, honours the step, and on a
    /// fine sphere section drops a good part of them.
    #[test]
    fn simplified_section_keeps_ball_centres_within_tolerance() {
        let m = uv_sphere(10.0, 96, 192);
        let c = &plane_section(&m, &normals(&m), &Vector3::x(), 3.0)[0];
        let (radius, tolerance, step) = (2.0, 0.002, 1.5);
        let s = c.simplified(radius, tolerance, step);
        assert!(
            s.points.len() * 4 < c.points.len() * 3,
            "{} of {}",
            s.points.len(),
            c.points.len()
        );
        assert_eq!(s.points.first(), c.points.first());
        assert_eq!(s.points.last(), c.points.last());
        assert!(
            s.points
                .windows(2)
                .all(|w| (w[1].point - w[0].point).norm() <= step)
        );
        let centre = |p: &DrivePoint| p.point + p.normal * radius;
        let chords: Vec<(Point3, Point3)> = s
            .points
            .windows(2)
            .map(|w| (centre(&w[0]), centre(&w[1])))
            .collect();
        for p in &c.points {
            let q = centre(p);
            let d = chords
                .iter()
                .map(|(a, b)| (q - crate::geom::closest_point_on_segment(&q, a, b)).norm())
                .fold(f64::INFINITY, f64::min);
            assert!(
                d <= tolerance + 1e-12,
                "centre {q} is {d} from the kept path"
            );
        }
    }
}
