//! Placing a ball against the part: from a drive point to a ball centre that is at least the
//! ball radius from every point of the part (exact f64).

use crate::geom::Point3;
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
    let mut centre = drive.point + drive.normal * lift;
    for _ in 0..64 {
        let (d, closest) = surface.signed_distance(&centre)?;
        if d >= radius {
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
