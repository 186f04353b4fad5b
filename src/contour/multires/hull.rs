//! The loose convex hull of seed 004 §4.1 and its offsets (Fig. 4.4).
//!
//! * [`enclosing_points`] — points whose convex hull contains the part exactly: line end points,
//!   and for each arc piece of at most 90° its end points and the intersection of its end
//!   tangents (the arc lies in that triangle);
//! * [`convex_hull`] — Andrew's monotone chain, counter-clockwise, no collinear vertices;
//! * [`loose_hull`] — algorithm *LooseConvexHull*: legs shorter than `min_leg` are deleted
//!   (the neighbouring legs extended to meet, Fig. 4.2a) or, when adjacent short legs form a
//!   run, combined into one leg perpendicular to the run's mean normal through its extreme
//!   vertex (Fig. 4.2b–d), repeatedly until nothing changes; a run that cannot be replaced
//!   as a whole is tried by pairs and single legs. Every new line is a supporting
//!   line of the polygon, so the loose hull still encloses the part. Unlike the seed, each
//!   change must keep the loose hull within `max_growth` of the true hull (a bound on how much
//!   air the roughing passes cut), and convex;
//! * [`hull_offset`] — the legs moved out by δ, joined by arcs of radius δ centred on the hull
//!   vertices: exactly the hull grown by δ.

use crate::contour::geometry::{Contour, Point2, Segment, Shape, Vector2, Vertex};
use crate::contour::segops::{cross, split_arc};
use std::f64::consts::FRAC_PI_2;

/// Points whose convex hull encloses every contour of `shape` exactly.
pub fn enclosing_points(shape: &Shape) -> Vec<Point2> {
    let mut pts = Vec::new();
    for c in &shape.contours {
        for seg in c.segments() {
            for piece in split_arc(&seg, FRAC_PI_2) {
                match piece {
                    Segment::Line { start, end } => pts.extend([start, end]),
                    Segment::Arc {
                        start,
                        end,
                        center,
                        radius,
                        sweep,
                    } => {
                        let mid = nalgebra::center(&start, &end) - center;
                        let apex = if mid.norm() > 0.0 {
                            center + mid.normalize() * (radius / (0.5 * sweep).cos())
                        } else {
                            start
                        };
                        pts.extend([start, apex, end]);
                    }
                }
            }
        }
    }
    pts
}

/// Convex hull, counter-clockwise, without collinear or repeated vertices.
pub fn convex_hull(points: &[Point2]) -> Vec<Point2> {
    let mut p: Vec<Point2> = points
        .iter()
        .copied()
        .filter(|q| q.x.is_finite() && q.y.is_finite())
        .collect();
    p.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    let mut hull: Vec<Point2> = Vec::with_capacity(2 * p.len());
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &Point2>> = if pass == 0 {
            Box::new(p.iter())
        } else {
            Box::new(p.iter().rev())
        };
        for &q in iter {
            while hull.len() >= start + 2
                && cross(
                    hull[hull.len() - 1] - hull[hull.len() - 2],
                    q - hull[hull.len() - 1],
                ) <= 0.0
            {
                hull.pop();
            }
            hull.push(q);
        }
        hull.pop();
    }
    hull
}

/// Outward normal of the leg a → b of a counter-clockwise polygon.
fn normal(a: Point2, b: Point2) -> Vector2 {
    let d = (b - a).normalize();
    Vector2::new(d.y, -d.x)
}

/// Intersection of the line through `p` with direction `u` and the line through `q` with
/// direction `v`; `None` when (nearly) parallel.
fn meet(p: Point2, u: Vector2, q: Point2, v: Vector2) -> Option<Point2> {
    let den = cross(u, v);
    if den.abs() <= 1e-12 * u.norm() * v.norm() {
        return None;
    }
    Some(p + u * (cross(q - p, v) / den))
}

fn is_convex(poly: &[Point2]) -> bool {
    let n = poly.len();
    n >= 3
        && (0..n).all(|i| {
            let (a, b, c) = (poly[i], poly[(i + 1) % n], poly[(i + 2) % n]);
            cross(b - a, c - b) > 0.0
        })
}

/// Largest distance from any vertex of `poly` to the convex polygon `hull` (0 inside).
fn growth(poly: &[Point2], hull: &[Point2]) -> f64 {
    let n = hull.len();
    poly.iter()
        .map(|&p| {
            (0..n)
                .map(|i| normal(hull[i], hull[(i + 1) % n]).dot(&(p - hull[i])))
                .fold(0.0, f64::max)
        })
        .fold(0.0, f64::max)
}

/// The loose convex hull of the counter-clockwise convex polygon `hull` (see the module docs).
pub fn loose_hull(hull: &[Point2], min_leg: f64, max_growth: f64) -> Vec<Point2> {
    let mut poly = hull.to_vec();
    'outer: loop {
        let n = poly.len();
        if n <= 3 {
            break;
        }
        let short: Vec<bool> = (0..n)
            .map(|i| (poly[(i + 1) % n] - poly[i]).norm() < min_leg)
            .collect();
        // Runs of consecutive short legs, each given by its first leg and its length. When
        // every leg is short, adjacent pairs are candidates.
        let mut runs: Vec<(usize, usize)> = Vec::new();
        let long = short.iter().position(|s| !s).unwrap_or(0);
        let all_short = short.iter().all(|&s| s);
        if all_short {
            runs.extend((0..n).map(|i| (i, 2)));
        }
        let mut k = 1;
        while !all_short && k <= n {
            let i = (long + k) % n;
            if short[i] {
                let mut len = 0;
                while len < n && short[(i + len) % n] {
                    len += 1;
                }
                runs.push((i, len));
                k += len;
            } else {
                k += 1;
            }
        }
        // Shortest total run first: the smallest change of the outline.
        runs.sort_by(|a, b| {
            let la: f64 = (0..a.1).map(|t| leg(&poly, a.0 + t)).sum();
            let lb: f64 = (0..b.1).map(|t| leg(&poly, b.0 + t)).sum();
            la.total_cmp(&lb).then(a.0.cmp(&b.0))
        });
        // When a whole run cannot go (too much growth), try its pairs and single legs.
        let mut candidates = runs.clone();
        for width in [2, 1] {
            for &(first, len) in &runs {
                if len > width {
                    candidates.extend((0..=len - width).map(|t| ((first + t) % n, width)));
                }
            }
        }
        for &(first, len) in &candidates {
            if len + 2 >= n {
                continue;
            }
            if let Some(candidate) = replace_run(&poly, first, len)
                && is_convex(&candidate)
                && growth(&candidate, hull) <= max_growth
            {
                poly = candidate;
                continue 'outer;
            }
        }
        break;
    }
    poly
}

fn leg(poly: &[Point2], i: usize) -> f64 {
    let n = poly.len();
    (poly[(i + 1) % n] - poly[i % n]).norm()
}

/// The polygon with the `len` legs from leg `first` replaced: one leg deleted (neighbours
/// extended), or a run combined into one leg along the run's mean normal.
fn replace_run(poly: &[Point2], first: usize, len: usize) -> Option<Vec<Point2>> {
    let n = poly.len();
    let at = |i: usize| poly[i % n];
    let prev_dir = at(first) - at(first + n - 1);
    let next_dir = at(first + len + 1) - at(first + len);
    let mut inserted = Vec::new();
    if len == 1 {
        inserted.push(meet(at(first), prev_dir, at(first + 1), next_dir)?);
    } else {
        let mut nsum = Vector2::zeros();
        for t in 0..len {
            let (a, b) = (at(first + t), at(first + t + 1));
            nsum += normal(a, b) * (b - a).norm();
        }
        let nrm = nsum.try_normalize(1e-15)?;
        let apex = (0..=len)
            .map(|t| at(first + t))
            .max_by(|a, b| nrm.dot(&a.coords).total_cmp(&nrm.dot(&b.coords)))?;
        let dir = Vector2::new(-nrm.y, nrm.x);
        inserted.push(meet(at(first), prev_dir, apex, dir)?);
        inserted.push(meet(apex, dir, at(first + len), next_dir)?);
    }
    // Keep the vertices outside the run, in order, starting after it.
    let mut out: Vec<Point2> = (first + len + 1..first + n).map(at).collect();
    out.extend(inserted);
    Some(out)
}

/// The convex polygon grown by `delta` > 0: legs moved out, arcs of radius `delta` around the
/// vertices (Fig. 4.4). Counter-clockwise.
pub fn hull_offset(poly: &[Point2], delta: f64) -> Contour {
    let n = poly.len();
    let mut vertices = Vec::with_capacity(2 * n);
    for i in 0..n {
        let (prev, here, next) = (poly[(i + n - 1) % n], poly[i], poly[(i + 1) % n]);
        let (n0, n1) = (normal(prev, here), normal(here, next));
        let turn = cross(n0, n1).atan2(n0.dot(&n1));
        vertices.push(Vertex {
            point: here + n0 * delta,
            bulge: (turn / 4.0).tan(),
        });
        vertices.push(Vertex {
            point: here + n1 * delta,
            bulge: 0.0,
        });
    }
    Contour { vertices }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contour::parallel::tests::{circle, rect};
    use std::f64::consts::PI;

    fn inside(poly: &[Point2], p: Point2) -> bool {
        let n = poly.len();
        (0..n).all(|i| cross(poly[(i + 1) % n] - poly[i], p - poly[i]) >= -1e-9)
    }

    #[test]
    fn hull_of_arcs_encloses_them() {
        let shape = Shape {
            contours: vec![circle(1.0, 2.0, 5.0, true)],
        };
        let hull = convex_hull(&enclosing_points(&shape));
        assert!(is_convex(&hull));
        for k in 0..360 {
            let a = k as f64 * PI / 180.0;
            let p = Point2::new(1.0 + 5.0 * a.cos(), 2.0 + 5.0 * a.sin());
            assert!(inside(&hull, p), "circle point {k}° outside the hull");
        }
    }

    #[test]
    fn loose_hull_encloses_the_hull_with_fewer_legs_within_its_growth() {
        // A 24-gon: short legs everywhere.
        let poly: Vec<Point2> = (0..24)
            .map(|k| {
                let a = k as f64 * PI / 12.0;
                Point2::new(20.0 * a.cos(), 20.0 * a.sin())
            })
            .collect();
        let hull = convex_hull(&poly);
        assert_eq!(hull.len(), 24);
        let loose = loose_hull(&hull, 8.0, 2.0);
        assert!(loose.len() < hull.len(), "{} legs", loose.len());
        assert!(is_convex(&loose));
        for p in &hull {
            assert!(inside(&loose, *p));
        }
        assert!(growth(&loose, &hull) <= 2.0);
        // No growth allowed: nothing changes.
        assert_eq!(loose_hull(&hull, 8.0, 0.0), hull);
        // A rectangle with one chamfer-like short leg loses it.
        let chamfered = vec![
            Point2::new(0.0, 0.0),
            Point2::new(10.0, 0.0),
            Point2::new(10.0, 9.0),
            Point2::new(9.0, 10.0),
            Point2::new(0.0, 10.0),
        ];
        let l = loose_hull(&chamfered, 2.0, 1.0);
        assert_eq!(l.len(), 4);
        assert!(
            l.iter()
                .any(|p| (p - Point2::new(10.0, 10.0)).norm() < 1e-12)
        );
    }

    #[test]
    fn hull_offset_is_the_grown_polygon() {
        let sq = rect(0.0, 0.0, 10.0, 4.0, true);
        let poly: Vec<Point2> = sq.vertices.iter().map(|v| v.point).collect();
        let off = hull_offset(&poly, 2.0);
        // Perimeter + 2π δ, area + perimeter δ + π δ².
        assert!((off.length() - (28.0 + 4.0 * PI)).abs() < 1e-9);
        assert!((off.signed_area() - (40.0 + 28.0 * 2.0 + PI * 4.0)).abs() < 1e-9);
    }
}
