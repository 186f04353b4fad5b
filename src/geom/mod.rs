//! Numeric types, small geometric primitives and the toolpath data (poses, moves) shared by
//! every stage.
//!
//! The planner's own geometry is f64 `nalgebra`. Crates that speak `glam` (parry3d, obvhs) are
//! converted to inside `collide` and `access` only, so no glam type appears here or in any other
//! stage's public API.

mod aabb;
mod runs;
#[cfg(test)]
mod seeded_random;
mod toolpath;
mod triangle;

pub use aabb::{Aabb, Aabb2};
pub use runs::{arc_lengths, run_on, runs_of_set};
#[cfg(test)]
pub(crate) use seeded_random::SeededRandom;
pub use toolpath::{Move, MoveKind, ToolPose, Toolpath};
pub use triangle::{
    ClosestFeature, closest_point_on_segment, closest_point_on_triangle,
    closest_points_of_segment_and_triangle, closest_points_of_segments,
    segment_triangle_distance_squared, triangle_area, triangle_normal,
};

/// A point in the XY plane, mm (planar outlines, 2.5D paths).
pub type Point2 = nalgebra::Point2<f64>;
/// A vector in the XY plane, mm.
pub type Vector2 = nalgebra::Vector2<f64>;
/// A point in millimetres.
pub type Point3 = nalgebra::Point3<f64>;
/// A vector in millimetres.
pub type Vector3 = nalgebra::Vector3<f64>;
/// A unit direction.
pub type Direction = nalgebra::Unit<nalgebra::Vector3<f64>>;

/// Two unit vectors perpendicular to `n` and to each other, forming a right-handed frame
/// `(u, v, n)`. Continuous away from `n = -Z` (Duff et al. 2017, "Building an orthonormal basis,
/// revisited"), which is all the callers need: they only want *some* frame.
pub fn orthonormal_frame(n: &Vector3) -> (Vector3, Vector3) {
    let sign = if n.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    let u = Vector3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
    let v = Vector3::new(b, sign + n.y * n.y * a, -n.y);
    (u, v)
}

/// The angle between two unit vectors in radians, accurate also for nearly parallel vectors
/// (`acos` of the dot product loses half the digits there).
pub fn angle_between(a: &Vector3, b: &Vector3) -> f64 {
    a.cross(b).norm().atan2(a.dot(b))
}

/// Spherical linear interpolation between unit vectors `a` and `b` at parameter `t`.
/// Falls back to normalised linear interpolation when they are (anti)parallel.
pub fn slerp(a: &Vector3, b: &Vector3, t: f64) -> Vector3 {
    let angle = angle_between(a, b);
    if angle < 1e-9 || (std::f64::consts::PI - angle) < 1e-9 {
        let v = a * (1.0 - t) + b * t;
        let n = v.norm();
        return if n > 0.0 { v / n } else { *a };
    }
    let s = angle.sin();
    a * (((1.0 - t) * angle).sin() / s) + b * ((t * angle).sin() / s)
}

/// Replaces a negative zero by a positive one. Printing `-0.000` in G-code or CSV is legal but
/// confuses people and diff tools, and obvhs misses every triangle for a `-0.0` ray component
/// (CRATES.md §8.1).
pub fn positive_zero(x: f64) -> f64 {
    if x == 0.0 { 0.0 } else { x }
}

/// Where `holds` starts to hold between `fails` (where it does not) and `holds_at` (where
/// it does), either the larger, by `steps` halvings of the bracket: the end of the last
/// bracket where it holds, within |holds_at − fails| / 2^steps of the change.
pub fn bisect(mut fails: f64, mut holds_at: f64, steps: usize, holds: impl Fn(f64) -> bool) -> f64 {
    for _ in 0..steps {
        let middle = 0.5 * (fails + holds_at);
        if holds(middle) {
            holds_at = middle;
        } else {
            fails = middle;
        }
    }
    holds_at
}

/// The distance between passes of a ball of radius `r` that leaves cusps `h` high on a flat
/// surface: 2·√(h(2r − h)).
pub fn stepover_for_scallop(radius: f64, scallop: f64) -> f64 {
    let h = scallop.clamp(0.0, radius);
    2.0 * (h * (2.0 * radius - h)).sqrt()
}

/// The value below which `share` of the total weight of `(value, weight)` pairs lies (the
/// first value whose running weight, smallest values first, reaches it); `None` when there
/// are none.
pub fn weighted_quantile(mut values: Vec<(f64, f64)>, share: f64) -> Option<f64> {
    values.sort_by(|a, b| a.0.total_cmp(&b.0));
    let total: f64 = values.iter().map(|v| v.1).sum();
    let mut seen = 0.0;
    for (value, weight) in &values {
        seen += weight;
        if seen >= share * total {
            return Some(*value);
        }
    }
    values.last().map(|v| v.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weighted_quantile_walks_the_weight_smallest_first() {
        let values = vec![(3.0, 1.0), (1.0, 1.0), (2.0, 8.0)];
        assert_eq!(weighted_quantile(values.clone(), 0.1), Some(1.0));
        assert_eq!(weighted_quantile(values.clone(), 0.5), Some(2.0));
        assert_eq!(weighted_quantile(values.clone(), 0.95), Some(3.0));
        assert_eq!(weighted_quantile(Vec::new(), 0.5), None);
    }

    #[test]
    fn frame_is_orthonormal_and_right_handed() {
        for n in [
            Vector3::z(),
            -Vector3::z(),
            Vector3::x(),
            Vector3::new(0.3, -0.5, 0.81).normalize(),
            Vector3::new(1e-12, 0.0, -1.0).normalize(),
        ] {
            let (u, v) = orthonormal_frame(&n);
            assert!((u.norm() - 1.0).abs() < 1e-12);
            assert!((v.norm() - 1.0).abs() < 1e-12);
            assert!(u.dot(&v).abs() < 1e-12 && u.dot(&n).abs() < 1e-12 && v.dot(&n).abs() < 1e-12);
            assert!((u.cross(&v) - n).norm() < 1e-12);
        }
    }

    #[test]
    fn slerp_keeps_unit_length_and_angle_proportion() {
        let a = Vector3::x();
        let b = Vector3::new(0.0, 1.0, 1.0).normalize();
        let total = angle_between(&a, &b);
        for k in 0..=10 {
            let t = k as f64 / 10.0;
            let s = slerp(&a, &b, t);
            assert!((s.norm() - 1.0).abs() < 1e-12);
            assert!((angle_between(&a, &s) - t * total).abs() < 1e-12);
        }
    }

    #[test]
    fn angle_between_is_accurate_near_zero() {
        let a = Vector3::x();
        let b = Vector3::new(1.0, 1e-9, 0.0).normalize();
        assert!((angle_between(&a, &b) - 1e-9).abs() < 1e-18);
    }
}
