use super::{Point3, Vector3};

/// Which feature of a triangle a closest point lies on. Needed for the sign of a distance:
/// the angle-weighted pseudo-normal of that feature decides inside or outside
/// (Bærentzen & Aanæs 2005).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ClosestFeature {
    /// Corner `0..3` of the triangle.
    Vertex(u8),
    /// Edge from corner `i` to corner `(i + 1) % 3`.
    Edge(u8),
    Face,
}

/// The point of segment `ab` closest to `p` (`a` if the segment is a point).
pub fn closest_point_on_segment(p: &Point3, a: &Point3, b: &Point3) -> Point3 {
    let d = b - a;
    let len2 = d.norm_squared();
    if len2 == 0.0 {
        return *a;
    }
    a + d * ((p - a).dot(&d) / len2).clamp(0.0, 1.0)
}

/// The point of triangle `abc` closest to `p`, and the feature it lies on.
/// Ericson, *Real-Time Collision Detection* §5.1.5, in f64; exact up to rounding.
pub fn closest_point_on_triangle(
    p: &Point3,
    a: &Point3,
    b: &Point3,
    c: &Point3,
) -> (Point3, ClosestFeature) {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(&ap);
    let d2 = ac.dot(&ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return (*a, ClosestFeature::Vertex(0));
    }
    let bp = p - b;
    let d3 = ab.dot(&bp);
    let d4 = ac.dot(&bp);
    if d3 >= 0.0 && d4 <= d3 {
        return (*b, ClosestFeature::Vertex(1));
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (a + ab * v, ClosestFeature::Edge(0));
    }
    let cp = p - c;
    let d5 = ab.dot(&cp);
    let d6 = ac.dot(&cp);
    if d6 >= 0.0 && d5 <= d6 {
        return (*c, ClosestFeature::Vertex(2));
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (a + ac * w, ClosestFeature::Edge(2));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (b + (c - b) * w, ClosestFeature::Edge(1));
    }
    let denom = 1.0 / (va + vb + vc);
    let v = vb * denom;
    let w = vc * denom;
    (a + ab * v + ac * w, ClosestFeature::Face)
}

/// The closest points `(on pq, on ab)` of two segments. Ericson, *Real-Time Collision
/// Detection* §5.1.9 (clamped parameters), in f64; degenerate segments are points.
pub fn closest_points_of_segments(
    p: &Point3,
    q: &Point3,
    a: &Point3,
    b: &Point3,
) -> (Point3, Point3) {
    let d1 = q - p;
    let d2 = b - a;
    let r = p - a;
    let (len1, len2) = (d1.norm_squared(), d2.norm_squared());
    let f = d2.dot(&r);
    let (s, t) = if len1 == 0.0 && len2 == 0.0 {
        (0.0, 0.0)
    } else if len1 == 0.0 {
        (0.0, (f / len2).clamp(0.0, 1.0))
    } else {
        let c = d1.dot(&r);
        if len2 == 0.0 {
            ((-c / len1).clamp(0.0, 1.0), 0.0)
        } else {
            let b_ = d1.dot(&d2);
            let denom = len1 * len2 - b_ * b_;
            let mut s = if denom > 0.0 {
                ((b_ * f - c * len2) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let mut t = (b_ * s + f) / len2;
            if t < 0.0 {
                t = 0.0;
                s = (-c / len1).clamp(0.0, 1.0);
            } else if t > 1.0 {
                t = 1.0;
                s = ((b_ - c) / len1).clamp(0.0, 1.0);
            }
            (s, t)
        }
    };
    (p + d1 * s, a + d2 * t)
}

/// Squared distance from segment `pq` to triangle `abc`: 0 where the segment crosses the
/// triangle, else the least over the segment's ends against the triangle and the triangle's
/// edges against the segment (the closest pair of two disjoint convex sets has a point on the
/// boundary of one of them).
pub fn segment_triangle_distance_squared(
    p: &Point3,
    q: &Point3,
    a: &Point3,
    b: &Point3,
    c: &Point3,
) -> f64 {
    let (x, y) = closest_points_of_segment_and_triangle(p, q, a, b, c);
    (x - y).norm_squared()
}

/// The closest points `(on pq, on abc)` of a segment and a triangle (the crossing point twice
/// where the segment crosses the triangle); see [`segment_triangle_distance_squared`].
pub fn closest_points_of_segment_and_triangle(
    p: &Point3,
    q: &Point3,
    a: &Point3,
    b: &Point3,
    c: &Point3,
) -> (Point3, Point3) {
    // Crossing: Möller–Trumbore with the segment as a ray of parameter range [0, 1].
    let (e1, e2) = (b - a, c - a);
    let direction = q - p;
    let h = direction.cross(&e2);
    let det = e1.dot(&h);
    if det != 0.0 {
        let s = p - a;
        let u = s.dot(&h) / det;
        let k = s.cross(&e1);
        let v = direction.dot(&k) / det;
        let t = e2.dot(&k) / det;
        if u >= 0.0 && v >= 0.0 && u + v <= 1.0 && (0.0..=1.0).contains(&t) {
            let crossing = p + t * direction;
            return (crossing, crossing);
        }
    }
    let mut best = (*p, closest_point_on_triangle(p, a, b, c).0);
    let mut consider = |x: Point3, y: Point3| {
        if (x - y).norm_squared() < (best.0 - best.1).norm_squared() {
            best = (x, y);
        }
    };
    consider(*q, closest_point_on_triangle(q, a, b, c).0);
    for (u, v) in [(a, b), (b, c), (c, a)] {
        let (x, y) = closest_points_of_segments(p, q, u, v);
        consider(x, y);
    }
    best
}

/// Unnormalised normal (twice the area, right-hand rule).
pub fn triangle_normal(a: &Point3, b: &Point3, c: &Point3) -> Vector3 {
    (b - a).cross(&(c - a))
}

pub fn triangle_area(a: &Point3, b: &Point3, c: &Point3) -> f64 {
    0.5 * triangle_normal(a, b, c).norm()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brute force: the closest point over a fine barycentric grid can never be closer than the
    /// exact answer, and comes within the grid's resolution of it.
    #[test]
    fn closest_point_agrees_with_dense_sampling() {
        let a = Point3::new(0.0, 0.0, 0.0);
        let b = Point3::new(4.0, 0.5, 0.0);
        let c = Point3::new(1.0, 3.0, 1.0);
        let queries = [
            Point3::new(1.0, 1.0, 2.0),
            Point3::new(-1.0, -1.0, 0.0),
            Point3::new(6.0, 0.0, 0.0),
            Point3::new(1.0, 5.0, 1.0),
            Point3::new(2.0, -2.0, 0.5),
            Point3::new(3.0, 3.0, 0.0),
            Point3::new(-2.0, 2.0, 1.0),
        ];
        let n = 300;
        for q in queries {
            let (exact, _) = closest_point_on_triangle(&q, &a, &b, &c);
            let exact_d = (q - exact).norm();
            let mut best = f64::INFINITY;
            for i in 0..=n {
                for j in 0..=(n - i) {
                    let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                    let s = a + (b - a) * u + (c - a) * v;
                    best = best.min((q - s).norm());
                }
            }
            assert!(
                best >= exact_d - 1e-12,
                "sampling beat the exact answer at {q:?}"
            );
            assert!(
                best - exact_d < 0.02,
                "exact answer too far at {q:?}: {exact_d} vs {best}"
            );
        }
    }

    #[test]
    fn features_are_reported() {
        let a = Point3::new(0.0, 0.0, 0.0);
        let b = Point3::new(1.0, 0.0, 0.0);
        let c = Point3::new(0.0, 1.0, 0.0);
        let f = |p| closest_point_on_triangle(&p, &a, &b, &c).1;
        assert_eq!(f(Point3::new(-1.0, -1.0, 0.0)), ClosestFeature::Vertex(0));
        assert_eq!(f(Point3::new(2.0, -0.5, 0.0)), ClosestFeature::Vertex(1));
        assert_eq!(f(Point3::new(-0.5, 2.0, 0.0)), ClosestFeature::Vertex(2));
        assert_eq!(f(Point3::new(0.5, -1.0, 0.0)), ClosestFeature::Edge(0));
        assert_eq!(f(Point3::new(1.0, 1.0, 0.0)), ClosestFeature::Edge(1));
        assert_eq!(f(Point3::new(-1.0, 0.5, 0.0)), ClosestFeature::Edge(2));
        assert_eq!(f(Point3::new(0.2, 0.2, 5.0)), ClosestFeature::Face);
    }
}
