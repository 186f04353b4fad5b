//! Swept solids a dexel line can be cut by, with their exact line intervals.
//!
//! Removal asks one question of a swept solid: which interval of an axis-parallel line lies
//! inside it. Every solid here is convex, so the answer is one interval, and it is computed in
//! closed form, not by sampling poses:
//!
//! * [`SphereSweptHull`]: the points within `radius` of the convex hull of up to four points.
//!   A ball-end cutter's body is a capsule (its axis segment thickened by the ball radius); a
//!   move sweeps the segment over the quadrilateral its two end positions span, so the move's
//!   swept body is the sphere-swept hull of those four points. For a pure translation the four
//!   points are coplanar and the hull is exactly the swept parallelogram; when the axis turns,
//!   the segment sweeps a bilinear (twisted) patch, which its hull encloses with an excess of at
//!   most a quarter of the twist `|a₀ − b₀ − a₁ + b₁|` ([`SphereSweptHull::twist`]): the caller
//!   splits the move until that is below its tolerance.
//!
//! The hull thickened by `r` is covered exactly by: the hull itself, each face's prism (points
//! whose projection falls inside the face, within `r` of its plane), and each edge's capsule
//! (which holds the vertex balls). The line interval is the union of the pieces' intervals,
//! which for a convex solid is their smallest start to their largest end.

use crate::geom::{Aabb, Point3, Vector3};

/// A solid a dexel line can be intersected with.
pub trait LineInterval: Sync {
    /// A box containing the solid.
    fn bounds(&self) -> Aabb;
    /// The interval `[t₀, t₁]` of the line `{p + t·e_axis}` (p's own `axis` coordinate is
    /// ignored) inside the solid, or `None` when the line misses it.
    fn line_interval(&self, axis: usize, p: &Point3) -> Option<(f64, f64)>;
}

/// Grows `acc` to hold `(t0, t1)`.
fn merge(acc: &mut Option<(f64, f64)>, hit: Option<(f64, f64)>) {
    if let Some((t0, t1)) = hit {
        *acc = Some(match *acc {
            None => (t0, t1),
            Some((a, b)) => (a.min(t0), b.max(t1)),
        });
    }
}

/// The line `p + t·e_axis` inside the ball of `center`, `radius`.
pub fn line_ball(axis: usize, p: &Point3, center: &Point3, radius: f64) -> Option<(f64, f64)> {
    let mut d2 = 0.0;
    for i in 0..3 {
        if i != axis {
            d2 += (p[i] - center[i]).powi(2);
        }
    }
    let h = radius * radius - d2;
    if h < 0.0 {
        return None;
    }
    let h = h.sqrt();
    Some((center[axis] - h, center[axis] + h))
}

/// The line `p + t·e_axis` inside the capsule of segment `a`→`b` and `radius`.
pub fn line_capsule(
    axis: usize,
    p: &Point3,
    a: &Point3,
    b: &Point3,
    radius: f64,
) -> Option<(f64, f64)> {
    let mut hit = None;
    merge(&mut hit, line_ball(axis, p, a, radius));
    merge(&mut hit, line_ball(axis, p, b, radius));
    let ba = b - a;
    let baba = ba.norm_squared();
    if baba == 0.0 {
        return hit;
    }
    // Work on the line with its axis coordinate at 0: o = p with o[axis] = 0, u = e_axis.
    let mut o = *p;
    o[axis] = 0.0;
    let oa = o - a;
    let (bard, baoa, rdoa, oaoa) = (ba[axis], ba.dot(&oa), oa[axis], oa.norm_squared());
    // The infinite cylinder around the segment: quadratic α t² + 2β t + γ ≤ 0.
    let alpha = baba - bard * bard;
    let beta = baba * rdoa - baoa * bard;
    let gamma = baba * oaoa - baoa * baoa - radius * radius * baba;
    let body = if alpha <= 1e-12 * baba {
        // The line runs along the segment: inside the cylinder everywhere or nowhere.
        (gamma <= 0.0).then_some((f64::NEG_INFINITY, f64::INFINITY))
    } else {
        let disc = beta * beta - alpha * gamma;
        (disc >= 0.0).then(|| {
            let s = disc.sqrt();
            ((-beta - s) / alpha, (-beta + s) / alpha)
        })
    };
    if let Some((t0, t1)) = body {
        // Keep the part whose projection falls on the segment: 0 ≤ baoa + t·bard ≤ baba.
        let (mut lo, mut hi) = (t0, t1);
        if bard.abs() > 0.0 {
            let (u0, u1) = ((0.0 - baoa) / bard, (baba - baoa) / bard);
            let (u0, u1) = if u0 <= u1 { (u0, u1) } else { (u1, u0) };
            lo = lo.max(u0);
            hi = hi.min(u1);
        } else if !(0.0..=baba).contains(&baoa) {
            lo = f64::INFINITY;
        }
        if lo <= hi {
            merge(&mut hit, Some((lo, hi)));
        }
    }
    hit
}

/// Clips the line `o + t·e_axis` (o with its axis coordinate 0) by the half-space
/// `g·x + h ≥ 0`, narrowing `[lo, hi]`; `false` when nothing is left.
fn clip(axis: usize, o: &Point3, g: &Vector3, h: f64, lo: &mut f64, hi: &mut f64) -> bool {
    let value = g.dot(&o.coords) + h;
    let slope = g[axis];
    if slope.abs() < 1e-300 {
        return value >= 0.0;
    }
    let t = -value / slope;
    if slope > 0.0 {
        *lo = lo.max(t);
    } else {
        *hi = hi.min(t);
    }
    *lo <= *hi
}

/// The points within `radius` of the convex hull of two to four points (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct SphereSweptHull {
    points: Vec<Point3>,
    radius: f64,
    bounds: Aabb,
    /// Faces of the hull as triangles with unit normals (degenerate ones left out).
    triangles: Vec<([Point3; 3], Vector3)>,
    /// The tetrahedron's outward face planes `(g, h)` with inside `g·x + h ≥ 0`; empty when
    /// the points are (nearly) coplanar and the hull has no interior.
    solid: Vec<(Vector3, f64)>,
}

impl SphereSweptHull {
    /// The solid of `points` (1 to 4) thickened by `radius`.
    pub fn new(points: &[Point3], radius: f64) -> Self {
        assert!(
            (1..=4).contains(&points.len()),
            "a sphere-swept hull takes 1 to 4 points"
        );
        let mut bounds = Aabb::empty();
        for p in points {
            bounds.grow(p);
        }
        let bounds = bounds.inflated(radius);
        let scale = points
            .iter()
            .flat_map(|p| points.iter().map(move |q| (p - q).norm()))
            .fold(0.0, f64::max);
        let mut triangles = Vec::new();
        let n = points.len();
        for i in 0..n {
            for j in i + 1..n {
                for k in j + 1..n {
                    let (a, b, c) = (points[i], points[j], points[k]);
                    let normal = (b - a).cross(&(c - a));
                    if normal.norm() > 1e-12 * scale * scale {
                        triangles.push(([a, b, c], normal.normalize()));
                    }
                }
            }
        }
        let mut solid = Vec::new();
        if n == 4 {
            let [a, b, c, d] = [points[0], points[1], points[2], points[3]];
            let volume6 = (b - a).cross(&(c - a)).dot(&(d - a));
            if volume6.abs() > 1e-9 * scale * scale * scale {
                for (p, q, r, opposite) in [(a, b, c, d), (a, b, d, c), (a, c, d, b), (b, c, d, a)]
                {
                    let mut g = (q - p).cross(&(r - p));
                    if g.dot(&(opposite - p)) < 0.0 {
                        g = -g;
                    }
                    solid.push((g, -g.dot(&p.coords)));
                }
            }
        }
        SphereSweptHull {
            points: points.to_vec(),
            radius,
            bounds,
            triangles,
            solid,
        }
    }

    /// The twist of a segment moving from `a0`→`b0` to `a1`→`b1`: its hull exceeds the swept
    /// bilinear patch by at most a quarter of this.
    pub fn twist(a0: &Point3, b0: &Point3, a1: &Point3, b1: &Point3) -> f64 {
        ((a0 - b0) - (a1 - b1)).norm()
    }

    /// The points whose hull is thickened.
    pub fn points(&self) -> &[Point3] {
        &self.points
    }

    /// The thickening radius.
    pub fn radius(&self) -> f64 {
        self.radius
    }
}

impl LineInterval for SphereSweptHull {
    fn bounds(&self) -> Aabb {
        self.bounds
    }

    fn line_interval(&self, axis: usize, p: &Point3) -> Option<(f64, f64)> {
        // Quick reject on the box, across the line.
        for i in 0..3 {
            if i != axis && (p[i] < self.bounds.min[i] || p[i] > self.bounds.max[i]) {
                return None;
            }
        }
        let r = self.radius;
        let mut hit = None;
        let pts = &self.points;
        if pts.len() == 1 {
            return line_ball(axis, p, &pts[0], r);
        }
        for i in 0..pts.len() {
            for j in i + 1..pts.len() {
                merge(&mut hit, line_capsule(axis, p, &pts[i], &pts[j], r));
            }
        }
        let mut o = *p;
        o[axis] = 0.0;
        for ([a, b, c], n) in &self.triangles {
            let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
            // Within r of the plane: n·(x − a) + r ≥ 0 and −n·(x − a) + r ≥ 0.
            let d = n.dot(&a.coords);
            let mut inside = clip(axis, &o, n, r - d, &mut lo, &mut hi)
                && clip(axis, &o, &-n, r + d, &mut lo, &mut hi);
            // Projection inside the triangle: on the inner side of each edge's plane.
            for (s, e) in [(a, b), (b, c), (c, a)] {
                if !inside {
                    break;
                }
                let g = n.cross(&(e - s));
                inside = clip(axis, &o, &g, -g.dot(&s.coords), &mut lo, &mut hi);
            }
            if inside {
                merge(&mut hit, Some((lo, hi)));
            }
        }
        if !self.solid.is_empty() {
            let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
            if self
                .solid
                .iter()
                .all(|(g, h)| clip(axis, &o, g, *h, &mut lo, &mut hi))
            {
                merge(&mut hit, Some((lo, hi)));
            }
        }
        hit
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::closest_point_on_triangle;
    use proptest::prelude::*;

    /// Distance from `x` to the hull of the points, by brute force: 0 inside the tetrahedron
    /// (barycentric test), else the nearest point on any triangle or segment of the points.
    fn hull_distance(points: &[Point3], x: &Point3) -> f64 {
        let mut best = f64::INFINITY;
        let n = points.len();
        for i in 0..n {
            best = best.min((x - points[i]).norm());
            for j in i + 1..n {
                let (a, b) = (points[i], points[j]);
                let ab = b - a;
                let t = if ab.norm_squared() > 0.0 {
                    ((x - a).dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                best = best.min((x - (a + t * ab)).norm());
                for c in &points[j + 1..n] {
                    let q = closest_point_on_triangle(x, &a, &b, c);
                    best = best.min((x - q.0).norm());
                }
            }
        }
        if n == 4 {
            let m = nalgebra::Matrix3::from_columns(&[
                points[1] - points[0],
                points[2] - points[0],
                points[3] - points[0],
            ]);
            if let Some(inv) = m.try_inverse() {
                let l = inv * (x - points[0]);
                if l.iter().all(|&v| v >= 0.0) && l.sum() <= 1.0 {
                    return 0.0;
                }
            }
        }
        best
    }

    fn point() -> impl Strategy<Value = Point3> {
        (-5.0..5.0f64, -5.0..5.0f64, -5.0..5.0f64).prop_map(|(x, y, z)| Point3::new(x, y, z))
    }

    proptest! {
        /// The interval's ends are on the surface (distance = r, to 1e-7) and a point between
        /// them is inside, a point just beyond each end is outside.
        #[test]
        fn line_intervals_agree_with_the_distance_to_the_hull(
            pts in proptest::collection::vec(point(), 1..=4),
            radius in 0.05..2.0f64,
            axis in 0usize..3,
            across in (-6.0..6.0f64, -6.0..6.0f64),
            flat in any::<bool>(),
        ) {
            let mut pts = pts;
            if flat && pts.len() == 4 {
                // A translation: a parallelogram.
                pts[3] = pts[1] + (pts[2] - pts[0]);
            }
            let solid = SphereSweptHull::new(&pts, radius);
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let mut p = Point3::origin();
            p[u] = across.0;
            p[v] = across.1;
            let at = |t: f64| { let mut q = p; q[axis] = t; q };
            match solid.line_interval(axis, &p) {
                Some((t0, t1)) => {
                    prop_assert!(t0 <= t1);
                    for t in [t0, t1] {
                        let d = hull_distance(&pts, &at(t));
                        prop_assert!((d - radius).abs() < 1e-7 || (t0 == t1), "end at distance {} vs r {}", d, radius);
                    }
                    prop_assert!(hull_distance(&pts, &at(0.5 * (t0 + t1))) <= radius + 1e-9);
                    prop_assert!(hull_distance(&pts, &at(t0 - 1e-6)) > radius - 1e-9);
                    prop_assert!(hull_distance(&pts, &at(t1 + 1e-6)) > radius - 1e-9);
                }
                None => {
                    // The line stays out: its closest approach is beyond r (checked on a fine
                    // sweep of t over the solid's box).
                    let b = solid.bounds();
                    for k in 0..=400 {
                        let t = b.min[axis] + (b.max[axis] - b.min[axis]) * k as f64 / 400.0;
                        prop_assert!(hull_distance(&pts, &at(t)) > radius - 1e-6);
                    }
                }
            }
        }
    }
}
