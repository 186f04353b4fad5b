//! Placing a ball against the part: from a drive point to a ball centre that is at least the
//! ball radius from every point of the part (exact f64).

use crate::geom::{Point3, bisect};
use crate::mesh::DrivePoint;
use crate::mesh::SurfaceDistance;

/// How far beyond the radius the centre is placed, mm: keeps the exact check robust against the
/// last bit of rounding without leaving measurable stock.
const PLACEMENT_SLACK: f64 = 1e-9;

/// The ball centre for a drive point: start at `point + r·normal`; while some part of the
/// surface is closer than `r`, move the centre straight away from the closest point to
/// distance `r`. In convex and flat regions the start is already right; in concave ones this
/// converges to where the ball touches two or more faces. Returns `None` when it does not
/// converge (a slot narrower than the ball): such points cannot be machined with this ball.
pub fn place_ball(surface: &SurfaceDistance, drive: &DrivePoint, radius: f64) -> Option<Point3> {
    place_ball_from(surface, drive, radius, radius)
}

/// [`place_ball`] starting `lift` along the drive point's normal instead of `radius`: for a
/// drive surface that is not the part (a roughing layer the ball's bottom follows), the ball
/// starts tangent to it and is pushed out only where the part is nearer than `radius`.
pub fn place_ball_from(
    surface: &SurfaceDistance,
    drive: &DrivePoint,
    lift: f64,
    radius: f64,
) -> Option<Point3> {
    let start = drive.point + drive.normal * lift;
    let (d, first) = surface.signed_distance(&start)?;
    if d >= radius {
        return Some(start);
    }
    let mut centre = start;
    for _ in 0..64 {
        let (d, closest) = surface.signed_distance(&centre)?;
        if d >= radius {
            // Pushed off the face beside the drive point's, the ball may have come off its
            // own: then into the corner instead, touching both.
            let lifted_off = (centre - start).dot(&drive.normal);
            if lifted_off > LIFT_OFF_LIMIT
                && let Some(cornered) =
                    slide_into_corner(surface, drive, &start, &first.point, radius)
            {
                return Some(cornered);
            }
            return Some(centre);
        }
        let away = if d > 1e-12 {
            (centre - closest.point) / d
        } else {
            surface.pseudo_normal(&closest).try_normalize(1e-300)?
        };
        centre = closest.point + away * (radius + PLACEMENT_SLACK);
        // Pushing out of one face can push into another; drifting far from the drive point
        // means the ball is now machining something else entirely.
        if (centre - drive.point).norm() > 3.0 * radius {
            return None;
        }
    }
    None
}

/// A push that lifts the ball this far off the drive point's face (mm) tries the corner
/// instead: between faces turning by less than 1.8° the lift is less, and leaves no scallop
/// any target measures.
const LIFT_OFF_LIMIT: f64 = 1e-3;

/// Bisection steps of the slide into a corner: the ball's radius over 2⁴⁰, far below any
/// tolerance.
const SLIDE_STEPS: usize = 40;

/// The ball in a concave corner, touching the drive point's face and the one beside it: from
/// `start` (the drive face's offset, where the face at `obstacle` comes nearer than the
/// radius), slid along the drive face, away from the obstacle, to where it first clears the
/// part; `None` when the push has no component along the face or the slide a crease allows
/// does not clear. Pushing straight off the obstacle lifts the ball off its own face wherever
/// the faces meet at less than a right angle: on a bore facetted as a 42-gon (8.6° between
/// facets) by 0.023 mm at each edge, ridges over the scallop target down every edge.
fn slide_into_corner(
    surface: &SurfaceDistance,
    drive: &DrivePoint,
    start: &Point3,
    obstacle: &Point3,
    radius: f64,
) -> Option<Point3> {
    let away = (start - obstacle).try_normalize(1e-12)?;
    let along_face = (away - drive.normal * away.dot(&drive.normal)).try_normalize(1e-6)?;
    // Between two planes turning by θ the ball touching both stands r·tan(θ/2) along the
    // drive face from the crease, the farthest a drive point on that face can be from it
    // (twice that searched, a margin for facets not quite planar); more, and the obstacle is
    // no such face (a fillet tighter than the ball): the push's place then.
    let turn = away.dot(&drive.normal).clamp(-1.0, 1.0).acos();
    let farthest = 2.0 * radius * (0.5 * turn).tan() + 1e-6;
    if !(farthest.is_finite() && farthest <= radius) {
        return None;
    }
    // Slid along the face, the ball stays a radius off it up to the last bit: placed the
    // slack off it, as the push places it off the obstacle.
    let lifted = start + drive.normal * PLACEMENT_SLACK;
    let clear = |t: f64| {
        surface
            .signed_distance(&(lifted + along_face * t))
            .is_some_and(|(d, _)| d >= radius)
    };
    if !clear(farthest) {
        return None;
    }
    Some(lifted + along_face * bisect(0.0, farthest, SLIDE_STEPS, clear))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Vector3;
    use crate::mesh::Mesh;
    use crate::mesh::fixtures::cuboid;

    /// An L-shaped inside corner: floor z = 0 for x in [0, 20], wall x = 20 rising to z = 20.
    /// A closed mesh: the union of a 20×10×2 floor slab (top at z = 0) and a wall block.
    fn corner() -> Mesh {
        let mut m = cuboid(30.0, 10.0, 2.0);
        for p in &mut m.positions {
            p.z -= 2.0;
        }
        // Make the wall out of a separate closed box standing on the slab's right end; the
        // two boxes touch on a face, which is enough for distance queries.
        let w = cuboid(10.0, 10.0, 20.0);
        let base = m.positions.len() as u32;
        m.positions.extend(
            w.positions
                .iter()
                .map(|p| Point3::new(p.x + 20.0, p.y, p.z)),
        );
        m.triangles
            .extend(w.triangles.iter().map(|t| t.map(|i| i + base)));
        m
    }

    #[test]
    fn flat_floor_keeps_the_straight_offset() {
        let m = corner();
        let s = SurfaceDistance::new(&m);
        let d = DrivePoint {
            point: Point3::new(5.0, 5.0, 0.0),
            normal: Vector3::z(),
        };
        let c = place_ball(&s, &d, 3.0).unwrap();
        assert!((c - Point3::new(5.0, 5.0, 3.0)).norm() < 1e-8);
    }

    #[test]
    fn inside_corner_converges_to_touching_both_faces() {
        let m = corner();
        let s = SurfaceDistance::new(&m);
        // Drive point on the floor 1 mm from the wall: the ball (r = 3) would dig into the wall.
        let d = DrivePoint {
            point: Point3::new(19.0, 5.0, 0.0),
            normal: Vector3::z(),
        };
        let c = place_ball(&s, &d, 3.0).unwrap();
        let (dist, _) = s.signed_distance(&c).unwrap();
        assert!((3.0..3.0 + 1e-6).contains(&dist), "{dist}");
        assert!(
            (c.x - 17.0).abs() < 1e-6 && (c.z - 3.0).abs() < 1e-6,
            "{c:?}"
        );
    }

    #[test]
    fn a_shallow_inside_corner_holds_the_ball_against_both_faces() {
        // A floor z = 0 for x ≤ 10 and a face rising 10° from x = 10 on: inside, a drive
        // point on the floor 0.1 mm before the crease.
        let rise = 10f64.to_radians();
        let (far_x, far_z) = (10.0 + 20.0 * rise.cos(), 20.0 * rise.sin());
        let positions = vec![
            Point3::new(-10.0, 0.0, 0.0),
            Point3::new(10.0, 0.0, 0.0),
            Point3::new(far_x, 0.0, far_z),
            Point3::new(-10.0, 10.0, 0.0),
            Point3::new(10.0, 10.0, 0.0),
            Point3::new(far_x, 10.0, far_z),
            Point3::new(-10.0, 0.0, -5.0),
            Point3::new(far_x, 0.0, -5.0),
            Point3::new(-10.0, 10.0, -5.0),
            Point3::new(far_x, 10.0, -5.0),
        ];
        let triangles = vec![
            // the floor and the rising face (up), the bottom (down)
            [0, 1, 4],
            [0, 4, 3],
            [1, 2, 5],
            [1, 5, 4],
            [6, 8, 9],
            [6, 9, 7],
            // the ends x = −10 and x = far, the sides y = 0 and y = 10
            [0, 3, 8],
            [0, 8, 6],
            [2, 7, 9],
            [2, 9, 5],
            [0, 6, 7],
            [0, 7, 2],
            [0, 2, 1],
            [3, 4, 5],
            [3, 5, 9],
            [3, 9, 8],
        ];
        let m = Mesh {
            positions,
            triangles,
        };
        let s = SurfaceDistance::new(&m);
        let r = 3.0;
        let d = DrivePoint {
            point: Point3::new(9.9, 5.0, 0.0),
            normal: Vector3::z(),
        };
        let c = place_ball(&s, &d, r).unwrap();
        // The corner's ball: on the floor's offset (z = r) and r from the rising face, whose
        // plane through (10, 0) has the normal (−sin, cos): the centre at x = 10 − r tan(5°).
        let expected_x = 10.0 - r * (0.5 * rise).tan();
        assert!((c.z - r).abs() < 1e-6, "{c:?}");
        assert!(
            (c.x - expected_x).abs() < 1e-6,
            "{c:?} against {expected_x}"
        );
        let (dist, _) = s.signed_distance(&c).unwrap();
        assert!((r..r + 1e-6).contains(&dist), "{dist}");
    }

    #[test]
    fn slot_narrower_than_the_ball_is_refused() {
        // Two walls 4 mm apart on a floor: a 6 mm ball cannot reach the floor of the slot.
        let mut slot = cuboid(40.0, 10.0, 2.0);
        for p in &mut slot.positions {
            p.z -= 2.0;
        }
        for (x0, width) in [(0.0, 18.0), (22.0, 18.0)] {
            let w = cuboid(width, 10.0, 20.0);
            let base = slot.positions.len() as u32;
            slot.positions
                .extend(w.positions.iter().map(|p| Point3::new(p.x + x0, p.y, p.z)));
            slot.triangles
                .extend(w.triangles.iter().map(|t| t.map(|i| i + base)));
        }
        let s = SurfaceDistance::new(&slot);
        let d = DrivePoint {
            point: Point3::new(20.0, 5.0, 0.0),
            normal: Vector3::z(),
        };
        match place_ball(&s, &d, 3.0) {
            None => {}
            Some(c) => {
                // If it converged, the ball sits in the slot's mouth, clear of all walls.
                assert!(s.signed_distance(&c).unwrap().0 >= 3.0);
                assert!(c.z >= 20.0, "{c:?}");
            }
        }
    }
}
