//! The tool assembly against the part: parry3d shapes for the bodies above the ball, the exact
//! f64 surface distance for the ball.
//!
//! f32 precision: parry runs in f32, so the part is shifted to its bounding-box centre before
//! conversion (a part 200 mm from the origin would otherwise lose a decade of precision), and
//! every f32 test carries a margin of [`F32_SLACK`], far above f32 rounding at these sizes.

use glam::{Quat, Vec3};
use parry3d::math::Pose;
use parry3d::query::{self, ClosestPoints};
use parry3d::shape::{Capsule, ConvexPolyhedron, Cylinder, Shape, TriMesh};

use super::distance::SurfaceDistance;
use crate::geom::{Point3, Vector3};
use crate::mesh::Mesh;
use crate::path::ToolPose;
use crate::tool::{Body, BodyRole, ToolAssembly};

/// mm. Larger than f32 rounding of coordinates within ±1000 mm of the part centre (~1e-4 mm).
pub const F32_SLACK: f64 = 1e-3;

/// Why a pose is not acceptable.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Collision {
    /// The ball centre is closer to the part than the ball radius (by `depth` mm), or inside it.
    Gouge { depth: f64 },
    /// A body above the ball comes closer to the part than its margin allows.
    Body { role: BodyRole },
}

/// Distance from each kind of body to the part at one pose, capped at the search distance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyClearance {
    pub flutes: f64,
    pub shank: f64,
    pub holder: f64,
}

/// Safety margins for the bodies above the ball, mm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Margins {
    pub shank: f64,
    pub holder: f64,
}

/// The part, ready for tool queries.
pub struct PartCollider {
    surface: SurfaceDistance,
    trimesh: TriMesh,
    origin: Point3,
}

impl PartCollider {
    /// Builds the exact f64 structure and the parry3d BVH. Fails only on a mesh parry refuses.
    pub fn new(mesh: &Mesh) -> Result<Self, String> {
        let origin = mesh.aabb().center();
        let vertices: Vec<Vec3> = mesh.positions.iter().map(|p| to_f32(&(p - origin))).collect();
        let trimesh = TriMesh::new(vertices, mesh.triangles.clone()).map_err(|e| format!("collision mesh: {e:?}"))?;
        Ok(Self { surface: SurfaceDistance::new(mesh), trimesh, origin })
    }

    pub fn surface(&self) -> &SurfaceDistance {
        &self.surface
    }

    fn local(&self, p: &Point3) -> Vec3 {
        to_f32(&(p - self.origin))
    }

    /// Ball-centre test, exact in f64: the centre must be outside the part and at least
    /// `radius - tolerance` from it.
    pub fn check_ball(&self, centre: &Point3, radius: f64, tolerance: f64) -> Result<f64, Collision> {
        let (d, _) = self.surface.signed_distance(centre).ok_or(Collision::Gouge { depth: radius })?;
        if d < radius - tolerance { Err(Collision::Gouge { depth: radius - d }) } else { Ok(d - radius) }
    }

    /// The whole tool at `pose`: ball exact, flutes without touching, shank and holder at least
    /// their margins away.
    pub fn check_pose(&self, tool: &ToolAssembly, pose: &ToolPose, margins: &Margins, tolerance: f64) -> Result<(), Collision> {
        let r = tool.ball_radius();
        self.check_ball(&(pose.tip + pose.axis.into_inner() * r), r, tolerance)?;
        self.check_bodies(tool, pose, margins, 0.0)
    }

    /// The bodies above the ball, each extended `sweep` mm further along the axis: that covers
    /// every position of the tool while it moves `sweep` mm along its own axis away from `pose`.
    pub fn check_bodies(&self, tool: &ToolAssembly, pose: &ToolPose, margins: &Margins, sweep: f64) -> Result<(), Collision> {
        for body in tool.bodies() {
            let grow = match body.role {
                BodyRole::Flutes => -F32_SLACK,
                BodyRole::Shank => margins.shank + F32_SLACK,
                BodyRole::Holder => margins.holder + F32_SLACK,
            };
            let (shape, at) = self.body_shape(&body, pose, grow, sweep);
            let hit = query::intersection_test(&at, shape.as_ref(), &Pose::IDENTITY, &self.trimesh)
                .map(|i| i.intersecting)
                .unwrap_or(true);
            if hit {
                return Err(Collision::Body { role: body.role });
            }
        }
        Ok(())
    }

    /// The ball swept `sweep` mm along the axis from `pose` (a capsule), tested without touching.
    pub fn check_ball_sweep(&self, tool: &ToolAssembly, pose: &ToolPose, sweep: f64) -> Result<(), Collision> {
        let r = tool.ball_radius();
        let c = pose.tip + pose.axis.into_inner() * r;
        let capsule = Capsule::new(self.local(&c), self.local(&(c + pose.axis.into_inner() * sweep)), (r - F32_SLACK) as f32);
        let hit = query::intersection_test(&Pose::IDENTITY, &capsule, &Pose::IDENTITY, &self.trimesh)
            .map(|i| i.intersecting)
            .unwrap_or(true);
        if hit { Err(Collision::Gouge { depth: 0.0 }) } else { Ok(()) }
    }

    /// How far each kind of body is from the part at `pose`, up to `search` mm (values at or
    /// beyond `search` mean "at least that"). Zero when touching or intersecting.
    pub fn clearances(&self, tool: &ToolAssembly, pose: &ToolPose, search: f64) -> BodyClearance {
        let mut c = BodyClearance { flutes: search, shank: search, holder: search };
        for body in tool.bodies() {
            let (shape, at) = self.body_shape(&body, pose, 0.0, 0.0);
            let d = match query::closest_points(&at, shape.as_ref(), &Pose::IDENTITY, &self.trimesh, search as f32) {
                Ok(ClosestPoints::WithinMargin(a, b)) => (a.distance(b) as f64).min(search),
                Ok(ClosestPoints::Disjoint) => search,
                Ok(ClosestPoints::Intersecting) | Err(_) => 0.0,
            };
            let slot = match body.role {
                BodyRole::Flutes => &mut c.flutes,
                BodyRole::Shank => &mut c.shank,
                BodyRole::Holder => &mut c.holder,
            };
            *slot = slot.min(d);
        }
        c
    }

    /// The parry shape of `body` grown radially by `grow` (and lengthwise by `grow` at both ends
    /// when positive), extended by `sweep` along the axis, placed at `pose`.
    fn body_shape(&self, body: &Body, pose: &ToolPose, grow: f64, sweep: f64) -> (Box<dyn Shape>, Pose) {
        let axis = pose.axis.into_inner();
        let end_grow = grow.max(0.0);
        let (from, to) = (body.from - end_grow, body.to + sweep + end_grow);
        let centre = pose.tip + axis * (0.5 * (from + to));
        let half = (0.5 * (to - from)) as f32;
        let rotation = Quat::from_rotation_arc(Vec3::Y, to_f32(&axis).normalize());
        let at = Pose::from_parts(self.local(&centre), rotation);
        let (r0, r1) = ((body.radius_from + grow).max(1e-3), (body.radius_to + grow).max(1e-3));
        // Swept along the axis, a frustum covers the cylinder of its larger radius above it.
        let r1 = if sweep > 0.0 { r0.max(r1) } else { r1 };
        if (r0 - r1).abs() < 1e-9 {
            return (Box::new(Cylinder::new(half, r0 as f32)), at);
        }
        // A circumscribed 32-gon prism frustum: it contains the true cone frustum.
        const SIDES: usize = 32;
        let scale = 1.0 / (std::f64::consts::PI / SIDES as f64).cos();
        let mut pts = Vec::with_capacity(2 * SIDES);
        for (y, r) in [(-half as f64, r0), (half as f64, r1)] {
            for k in 0..SIDES {
                let a = 2.0 * std::f64::consts::PI * k as f64 / SIDES as f64;
                pts.push(Vec3::new((r * scale * a.cos()) as f32, y as f32, (r * scale * a.sin()) as f32));
            }
        }
        match ConvexPolyhedron::from_convex_hull(&pts) {
            Some(hull) => (Box::new(hull), at),
            None => (Box::new(Cylinder::new(half, r0.max(r1) as f32)), at),
        }
    }
}

fn to_f32(v: &Vector3) -> Vec3 {
    Vec3::new(v.x as f32, v.y as f32, v.z as f32)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Direction;
    use crate::mesh::fixtures::cuboid;
    use crate::tool::{Cutter, Section};

    fn tool() -> ToolAssembly {
        ToolAssembly {
            id: 1,
            cutter: Cutter::Ball { diameter: 6.0, flute_length: 12.0 },
            shank_diameter: 6.0,
            stickout: 30.0,
            holder: vec![Section::cylinder(30.0, 20.0)],
        }
    }

    fn pose(tip: [f64; 3], axis: [f64; 3]) -> ToolPose {
        ToolPose { tip: Point3::from(tip), axis: Direction::new_normalize(Vector3::from(axis)) }
    }

    /// A 100 × 100 × 20 plate, top at z = 20.
    fn plate() -> PartCollider {
        let mut m = cuboid(100.0, 100.0, 20.0);
        for p in &mut m.positions {
            p.x -= 50.0;
            p.y -= 50.0;
        }
        PartCollider::new(&m).unwrap()
    }

    const M: Margins = Margins { shank: 0.5, holder: 2.0 };

    #[test]
    fn vertical_tool_touching_the_top_is_clear_and_lower_gouges() {
        let part = plate();
        assert!(part.check_pose(&tool(), &pose([0.0, 0.0, 20.0], [0.0, 0.0, 1.0]), &M, 1e-6).is_ok());
        match part.check_pose(&tool(), &pose([0.0, 0.0, 19.9], [0.0, 0.0, 1.0]), &M, 1e-6) {
            Err(Collision::Gouge { depth }) => assert!((depth - 0.1).abs() < 1e-9),
            other => panic!("{other:?}"),
        }
        // Deep inside: parry's hollow mesh would see nothing; the signed distance does.
        assert!(matches!(
            part.check_pose(&tool(), &pose([0.0, 0.0, 5.0], [0.0, 0.0, 1.0]), &M, 1e-6),
            Err(Collision::Gouge { .. })
        ));
    }

    #[test]
    fn holder_hits_a_wall_when_tilted_toward_it() {
        // Ball on the plate near the wall of a tall block: tilt the tool toward the block and
        // the holder (radius 15) reaches it; tilt away and it does not.
        let mut m = cuboid(100.0, 100.0, 20.0);
        let wall = cuboid(10.0, 100.0, 60.0);
        let base = m.positions.len() as u32;
        m.positions.extend(wall.positions.iter().map(|p| Point3::new(p.x + 120.0, p.y, p.z)));
        m.triangles.extend(wall.triangles.iter().map(|t| t.map(|i| i + base)));
        let part = PartCollider::new(&m).unwrap();
        // The ball (r = 3) rests on the plate at x = 95; the tip moves with the axis.
        let on_ball = |axis: [f64; 3]| {
            let a = Vector3::from(axis).normalize();
            let tip = Point3::new(95.0, 50.0, 23.0) - a * 3.0;
            pose(tip.into(), axis)
        };
        assert!(part.check_pose(&tool(), &on_ball([0.0, 0.0, 1.0]), &M, 1e-6).is_ok());
        assert_eq!(
            part.check_pose(&tool(), &on_ball([0.6, 0.0, 0.8]), &M, 1e-6),
            Err(Collision::Body { role: BodyRole::Holder })
        );
        assert!(part.check_pose(&tool(), &on_ball([-0.6, 0.0, 0.8]), &M, 1e-6).is_ok());
    }

    #[test]
    fn clearances_match_closed_form_above_a_plate() {
        let part = plate();
        // Tool hovering 5 mm above the plate, vertical: flutes start at the ball centre, so
        // their lowest point is 5 + 3 above the plate; shank starts at 12 + 5; holder at 30 + 5.
        let c = part.clearances(&tool(), &pose([0.0, 0.0, 25.0], [0.0, 0.0, 1.0]), 50.0);
        assert!((c.flutes - 8.0).abs() < 1e-3, "{c:?}");
        assert!((c.shank - 17.0).abs() < 1e-3, "{c:?}");
        assert!((c.holder - 35.0).abs() < 1e-3, "{c:?}");
        // Horizontal tool lying 1 mm above the plate (tip side): every body's lowest line.
        let c = part.clearances(&tool(), &pose([-40.0, 0.0, 24.0], [1.0, 0.0, 0.0]), 50.0);
        assert!((c.flutes - 1.0).abs() < 1e-3, "{c:?}");
        assert!((c.holder - (24.0 - 15.0 - 20.0)).abs() < 1e-3 || c.holder == 0.0, "{c:?}");
    }

    #[test]
    fn sweep_along_the_axis_finds_an_overhang() {
        // A roof above the plate: a vertical tool standing on the plate under the roof is fine
        // where it is (the roof is above the holder), but retracting upward hits it.
        let mut m = cuboid(100.0, 100.0, 20.0);
        let roof = cuboid(100.0, 100.0, 5.0);
        let base = m.positions.len() as u32;
        m.positions.extend(roof.positions.iter().map(|p| Point3::new(p.x, p.y, p.z + 100.0)));
        m.triangles.extend(roof.triangles.iter().map(|t| t.map(|i| i + base)));
        let part = PartCollider::new(&m).unwrap();
        let p = pose([50.0, 50.0, 20.0], [0.0, 0.0, 1.0]);
        assert!(part.check_pose(&tool(), &p, &M, 1e-6).is_ok());
        assert!(part.check_bodies(&tool(), &p, &M, 10.0).is_ok());
        assert!(part.check_bodies(&tool(), &p, &M, 60.0).is_err());
        assert!(part.check_ball_sweep(&tool(), &p, 60.0).is_ok());
        assert!(part.check_ball_sweep(&tool(), &p, 90.0).is_err());
    }
}
