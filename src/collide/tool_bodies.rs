//! The tool assembly against the part: parry3d shapes for the bodies above the ball, the exact
//! f64 surface distance for the ball.
//!
//! f32 precision: parry runs in f32, so the part is shifted to its bounding-box centre before
//! conversion (a part 200 mm from the origin would otherwise lose a decade of precision), and
//! every f32 test carries a margin of [`F32_SLACK`], far above f32 rounding at these sizes.

use std::sync::Arc;

use glam::{Quat, Vec3};
use parry3d::math::Pose;
use parry3d::query::{self, ClosestPoints};
use parry3d::shape::{ConvexPolyhedron, Cylinder, RoundCylinder, Shape, TriMesh};

use crate::geom::ToolPose;
use crate::geom::{Point3, Vector3};
use crate::mesh::Mesh;
use crate::mesh::{SegmentSearch, SurfaceDistance};
use crate::stock::clearance::MaterialClearance;
use crate::stock::sweep::Frustum;
use crate::tool::{Body, BodyRole, Cutter, ToolAssembly};

/// mm. Larger than f32 rounding of coordinates within ±1000 mm of the part centre (~1e-4 mm).
pub const F32_SLACK: f64 = 1e-3;

/// Why a pose is not acceptable.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Collision {
    /// The ball centre is closer to the part than the ball radius (by `depth` mm), or inside it.
    Gouge { depth: f64 },
    /// A body above the ball comes closer to the part than its margin allows.
    Body { role: BodyRole },
    /// Some part of the tool comes closer to the table than its margin.
    Table,
    /// A body above the flutes comes closer to the stock's material (what the operations
    /// before left, [`PartCollider::with_material`]) than its margin allows.
    Material { role: BodyRole },
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

/// The machine table (or fixture top) the part stands on, in the part frame: everything below
/// the plane `z = top_z` is solid, and the tool must stay `margin` above it. The table turns
/// with the part on a table-table machine, so in the part frame it never moves.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Table {
    pub top_z: f64,
    pub margin: f64,
}

/// Why the collision structures of a part cannot be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ColliderError {
    /// parry3d refused the triangle mesh (its message).
    #[error("collision mesh: {0}")]
    Mesh(String),
}

/// The part (and the table it stands on, and the material standing around it), ready for
/// tool queries. Cloning shares the part's structures.
#[derive(Clone)]
pub struct PartCollider {
    part: Arc<PartStructures>,
    origin: Point3,
    table: Option<Table>,
    material: Option<Arc<MaterialClearance>>,
}

struct PartStructures {
    surface: SurfaceDistance,
    trimesh: TriMesh,
}

impl PartCollider {
    /// Builds the exact f64 structure and the parry3d BVH. Fails only on a mesh parry refuses.
    pub fn new(mesh: &Mesh) -> Result<Self, ColliderError> {
        let origin = mesh.aabb().center();
        let vertices: Vec<Vec3> = mesh
            .positions
            .iter()
            .map(|p| to_f32(&(p - origin)))
            .collect();
        let trimesh = TriMesh::new(vertices, mesh.triangles.clone())
            .map_err(|e| ColliderError::Mesh(format!("{e:?}")))?;
        Ok(Self {
            part: Arc::new(PartStructures {
                surface: SurfaceDistance::new(mesh),
                trimesh,
            }),
            origin,
            table: None,
            material: None,
        })
    }

    /// The same part with the stock's `material` around it: the bodies above the flutes
    /// (shank, neck, holder) must then also keep their margins from it. The flutes and the
    /// cutting end are the tool's cutting part and may be in material. This is how the ball
    /// operations after roughing keep their shank and holder out of the rest.
    pub fn with_material(&self, material: Arc<MaterialClearance>) -> Self {
        Self {
            material: Some(material),
            ..self.clone()
        }
    }

    /// Adds the table the part stands on: every tool check then also keeps the whole tool
    /// `table.margin` above it.
    pub fn with_table(mut self, table: Table) -> Self {
        self.table = Some(table);
        self
    }

    pub fn table(&self) -> Option<&Table> {
        self.table.as_ref()
    }

    /// Height of the tool's lowest point above the table top (∞ without a table).
    pub fn table_clearance(&self, tool: &PreparedTool, pose: &ToolPose, sweep: f64) -> f64 {
        self.table
            .map_or(f64::INFINITY, |t| tool.lowest_z(pose, sweep) - t.top_z)
    }

    fn check_table(
        &self,
        tool: &PreparedTool,
        pose: &ToolPose,
        sweep: f64,
    ) -> Result<(), Collision> {
        match self.table {
            Some(t) if self.table_clearance(tool, pose, sweep) < t.margin => Err(Collision::Table),
            _ => Ok(()),
        }
    }

    pub fn surface(&self) -> &SurfaceDistance {
        &self.part.surface
    }

    fn local(&self, p: &Point3) -> Vec3 {
        to_f32(&(p - self.origin))
    }

    /// Ball-centre test, exact in f64: the centre must be outside the part and at least
    /// `radius - tolerance` from it.
    pub fn check_ball(
        &self,
        centre: &Point3,
        radius: f64,
        tolerance: f64,
    ) -> Result<f64, Collision> {
        let (d, _) = self
            .part
            .surface
            .signed_distance(centre)
            .ok_or(Collision::Gouge { depth: radius })?;
        if d < radius - tolerance {
            Err(Collision::Gouge { depth: radius - d })
        } else {
            Ok(d - radius)
        }
    }

    /// The whole tool at `pose`: ball exact, flutes without touching, shank and holder at least
    /// their margins away.
    pub fn check_pose(&self, tool: &PreparedTool, pose: &ToolPose) -> Result<(), Collision> {
        let r = tool.ball_radius;
        self.check_ball(&(pose.tip + pose.axis.into_inner() * r), r, 0.0)?;
        self.check_bodies(tool, pose)
    }

    /// The tool touching `point` (outward unit `normal`) along unit `axis`, with any cutter:
    /// where its tip goes, or why it cannot stand there. The cutting end may dip into the part
    /// by at most `tolerance` (a ball exactly in f64; flat and bull-nose ends as parry solids
    /// lifted `tolerance` along the normal, so touching is allowed and f32 error is ~1e-4 mm);
    /// the bodies above keep their margins as in [`PartCollider::check_bodies`].
    pub fn check_touching(
        &self,
        tool: &PreparedTool,
        point: &Point3,
        normal: &Vector3,
        axis: &Vector3,
        tolerance: f64,
    ) -> Result<ToolPose, Collision> {
        let tip = tool
            .cutter
            .tip_touching(point, normal, axis)
            .ok_or(Collision::Gouge {
                depth: f64::INFINITY,
            })?;
        let pose = ToolPose {
            tip,
            axis: crate::geom::Direction::new_normalize(*axis),
        };
        if tool.ball_radius > 0.0 {
            let r = tool.ball_radius;
            self.check_ball(&(point + normal * r), r, tolerance)?;
        }
        let lifted = ToolPose {
            tip: tip + normal * tolerance,
            ..pose
        };
        for end in &tool.end {
            if self.intersects(end.shape.as_ref(), &end.geometry.place(&lifted, self)) {
                return Err(Collision::Gouge { depth: tolerance });
            }
        }
        self.check_bodies(tool, &pose)?;
        Ok(pose)
    }

    /// The bodies above the ball at `pose`: flutes must not touch, shank and holder must stay
    /// their margins away.
    pub fn check_bodies(&self, tool: &PreparedTool, pose: &ToolPose) -> Result<(), Collision> {
        self.check_table(tool, pose, 0.0)?;
        for body in &tool.bodies {
            let meets = self
                .capsule_verdict(&body.geometry.grown(body.check_grow), pose)
                .unwrap_or_else(|| self.intersects(body.check.as_ref(), &body.place(pose, self)));
            if meets {
                return Err(Collision::Body { role: body.role });
            }
        }
        self.check_material(tool, pose, 0.0)
    }

    /// Whether `body` at `pose` meets the part, when the exact f64 distance decides it:
    /// `Some(false)` when it surely keeps off, `Some(true)` when it surely meets it, `None`
    /// when parry's test must decide.
    ///
    /// The body is cut along its axis into pieces about its radius long; each lies in the
    /// flat-ended cylinder around its stretch of the axis with its larger radius. When no
    /// triangle comes into any of those cylinders, the body is clear. The points nearest the
    /// stretches of the triangles that do are tested: one inside the body, and they meet;
    /// none, and parry decides. (Flat ends, not a capsule's round ones: the flutes start at
    /// the ball's equator, and a capsule round their first stretch holds the ball's top half,
    /// which touches the part wherever the ball cuts with its side.) Most tested poses are decided here,
    /// without parry's f32 GJK over every triangle under a tilted body's loose box. (Like
    /// parry's, it is a test against the surface: a body wholly inside the part passes both.)
    fn capsule_verdict(&self, body: &Revolved, pose: &ToolPose) -> Option<bool> {
        let k = pose.axis.into_inner();
        let length = body.to - body.from;
        let widest = body.radius_from.max(body.radius_to);
        if !(length > 0.0 && widest > 0.0) {
            return None;
        }
        let radius_at = |h: f64| {
            body.radius_from + (body.radius_to - body.radius_from) * (h - body.from) / length
        };
        let inside = |point: &Point3| {
            let offset = point - pose.tip;
            let h = offset.dot(&k);
            h > body.from
                && h < body.to
                && (offset - h * k).norm() < radius_at(h) * (1.0 - 1e-12) - 1e-9
        };
        let pieces = ((length / widest.max(0.5)).ceil() as usize).clamp(1, 64);
        let mut near = false;
        for i in 0..pieces {
            let h0 = body.from + length * i as f64 / pieces as f64;
            let h1 = body.from + length * (i + 1) as f64 / pieces as f64;
            // Touching is not clear: the radius is taken a hair larger.
            let radius = radius_at(h0).max(radius_at(h1)) * (1.0 + 1e-12) + 1e-9;
            let (a, b) = (pose.tip + h0 * k, pose.tip + h1 * k);
            match self.part.surface.cylinder_search(&a, &b, radius, inside) {
                SegmentSearch::Accepted => return Some(true),
                SegmentSearch::Near => near = true,
                SegmentSearch::Clear => {}
            }
        }
        (!near).then_some(false)
    }

    /// The bodies above the flutes, grown by their margins and extended `sweep` mm up the
    /// axis, against the material (none without it).
    fn check_material(
        &self,
        tool: &PreparedTool,
        pose: &ToolPose,
        sweep: f64,
    ) -> Result<(), Collision> {
        let Some(material) = &self.material else {
            return Ok(());
        };
        for body in tool.bodies.iter().filter(|b| b.role != BodyRole::Flutes) {
            let grown = body.geometry.grown(body.check_grow).swept(sweep);
            let clear = material.frustum_is_clear(&Frustum {
                base: pose.tip,
                axis: pose.axis.into_inner(),
                from: grown.from,
                to: grown.to,
                radius_from: grown.radius_from,
                radius_to: grown.radius_to,
            });
            if !clear {
                return Err(Collision::Material { role: body.role });
            }
        }
        Ok(())
    }

    /// The bodies above the ball, each extended `sweep` mm further along the axis, with their
    /// margins: that covers every position of the tool while it moves `sweep` mm along its own
    /// axis away from `pose` (retract and plunge).
    pub fn check_bodies_swept(
        &self,
        tool: &PreparedTool,
        pose: &ToolPose,
        sweep: f64,
    ) -> Result<(), Collision> {
        self.check_table(tool, pose, sweep)?;
        for body in &tool.bodies {
            let grown = body.geometry.grown(body.check_grow).swept(sweep);
            let meets = self.capsule_verdict(&grown, pose).unwrap_or_else(|| {
                self.intersects(grown.shape(true).as_ref(), &grown.place(pose, self))
            });
            if meets {
                return Err(Collision::Body { role: body.role });
            }
        }
        self.check_material(tool, pose, sweep)
    }

    /// The ball swept `sweep` mm along the axis from `pose` (a capsule), tested without
    /// touching: no triangle within the radius less [`F32_SLACK`] of the centre's sweep, in
    /// f64 (the fences pass by the triangles the ball rests on at once, where parry's f32 GJK
    /// ran over every triangle under the long capsule's box).
    pub fn check_ball_sweep(
        &self,
        tool: &PreparedTool,
        pose: &ToolPose,
        sweep: f64,
    ) -> Result<(), Collision> {
        let r = tool.ball_radius;
        let k = pose.axis.into_inner();
        let c = pose.tip + k * r;
        if self
            .part
            .surface
            .segment_within(&c, &(c + k * sweep.max(0.0)), r - F32_SLACK)
        {
            Err(Collision::Gouge { depth: 0.0 })
        } else {
            Ok(())
        }
    }

    /// How far each kind of body is from the part at `pose`, looking only up to the distances
    /// in `upto` (a body farther than its limit keeps the limit), measured in f32.
    ///
    /// The flutes share the ball's equator, so a ball touching a wall with its side has its
    /// flutes touching too: they are tested shrunk by [`F32_SLACK`] (as during planning), and a
    /// negative flute clearance means they cut into the part. parry's `closest_points` reports
    /// "intersecting" for bodies within its GJK tolerance of the part; where `intersection_test`
    /// says they do not intersect, that counts as touching (0).
    pub fn clearances(
        &self,
        tool: &PreparedTool,
        pose: &ToolPose,
        upto: &BodyClearance,
    ) -> BodyClearance {
        let mut c = *upto;
        for body in &tool.bodies {
            let slot = match body.role {
                BodyRole::Flutes => &mut c.flutes,
                BodyRole::Shank => &mut c.shank,
                BodyRole::Holder => &mut c.holder,
            };
            let limit = *slot;
            if limit <= 0.0 {
                continue;
            }
            let farther = if body.role == BodyRole::Flutes {
                self.flutes_farther_than(&body.geometry, pose, limit)
            } else {
                self.farther_than(&body.geometry, pose, limit)
            };
            if farther {
                continue;
            }
            let at = body.place(pose, self);
            let shrink = if body.role == BodyRole::Flutes {
                F32_SLACK
            } else {
                0.0
            };
            let d = match query::closest_points(
                &at,
                body.exact.as_ref(),
                &Pose::IDENTITY,
                &self.part.trimesh,
                limit as f32,
            ) {
                Ok(ClosestPoints::WithinMargin(a, b)) => (a.distance(b) as f64 + shrink).min(limit),
                Ok(ClosestPoints::Disjoint) => limit,
                Ok(ClosestPoints::Intersecting) | Err(_) => {
                    if !self.intersects(body.exact.as_ref(), &at) {
                        0.0
                    } else if shrink > 0.0 {
                        // Flutes: inside by at least the slack, unless the f64 distance from
                        // their axis says otherwise. Within its f32 tolerance parry calls
                        // intersecting a part 0.9 µm inside the flutes (the sample's finish
                        // after channel roughing), which the planning's f64 test rightly
                        // calls clear of the flutes shrunk by the slack.
                        let g = &body.geometry;
                        let k = pose.axis.into_inner();
                        let inside = self.part.surface.segment_within(
                            &(pose.tip + k * g.from),
                            &(pose.tip + k * g.to),
                            g.radius_from.max(g.radius_to) - shrink,
                        );
                        if inside { -shrink } else { 0.0 }
                    } else {
                        0.0
                    }
                }
            };
            *slot = slot.min(d);
        }
        c
    }

    /// Whether `body` at `pose`, measured as the prism or frustum parry measures, is surely
    /// farther than `limit` from the part, by the f64 search alone.
    ///
    /// The body is cut along its axis into pieces about its narrower radius long; each lies
    /// within its larger radius (the polygon's corners included) of its stretch of the axis,
    /// so every point within `limit` of it lies within that radius and the limit of the
    /// stretch. When no triangle comes that near any stretch, the body is farther: decided far
    /// faster than by parry's f32 GJK over every triangle within the limit of its box, which
    /// is left to the poses this cannot decide (the search stops at the first triangle near).
    fn farther_than(&self, body: &Revolved, pose: &ToolPose, limit: f64) -> bool {
        let length = body.to - body.from;
        let narrow = body.radius_from.min(body.radius_to);
        if !(length > 0.0 && narrow > 0.0 && limit > 0.0) {
            return false;
        }
        let pieces = (length / narrow).ceil().clamp(1.0, 64.0) as usize;
        let k = pose.axis.into_inner();
        let radius_at = |h: f64| {
            body.radius_from + (body.radius_to - body.radius_from) * (h - body.from) / length
        };
        let reach = limit + F32_SLACK;
        (0..pieces).all(|i| {
            let low = body.from + length * i as f64 / pieces as f64;
            let high = body.from + length * (i + 1) as f64 / pieces as f64;
            let radius = radius_at(low).max(radius_at(high)) * circumscribed();
            !self.part.surface.segment_within(
                &(pose.tip + k * low),
                &(pose.tip + k * high),
                radius + reach,
            )
        })
    }

    /// [`Self::farther_than`] for the flutes, which start at the ball's equator: the ball
    /// touches the part, so a round end on their first stretch would always find it. Every
    /// point within `limit` of their flat-ended cylinder lies in the cylinder wider and
    /// longer at both ends by `limit`, which is searched instead; it holds the ball's contact
    /// only where the ball cuts within `limit` of its equator.
    fn flutes_farther_than(&self, body: &Revolved, pose: &ToolPose, limit: f64) -> bool {
        if !(body.to > body.from && limit > 0.0) {
            return false;
        }
        let k = pose.axis.into_inner();
        let radius = body.radius_from.max(body.radius_to);
        let reach = limit + F32_SLACK;
        self.part.surface.cylinder_search(
            &(pose.tip + k * (body.from - reach)),
            &(pose.tip + k * (body.to + reach)),
            radius + reach,
            |_| true,
        ) == SegmentSearch::Clear
    }

    /// Whether a cylinder around the axis of `pose`, from `from` to `to` mm above the tip and of
    /// radius `radius` (a circumscribed 32-gon prism), stays clear of the part.
    pub fn cylinder_clear(&self, pose: &ToolPose, from: f64, to: f64, radius: f64) -> bool {
        let body = Revolved {
            from,
            to,
            radius_from: radius,
            radius_to: radius,
        };
        !self.intersects(body.shape(false).as_ref(), &body.place(pose, self))
    }

    fn intersects(&self, shape: &dyn Shape, at: &Pose) -> bool {
        query::intersection_test(at, shape, &Pose::IDENTITY, &self.part.trimesh)
            .map(|i| i.intersecting)
            .unwrap_or(true)
    }
}

/// Sides of the prism or frustum a body of revolution is measured as.
const SIDES: usize = 32;

/// The ratio of that polygon's corner radius to the body's.
fn circumscribed() -> f64 {
    1.0 / (std::f64::consts::PI / SIDES as f64).cos()
}

/// A body of revolution along the tool axis: heights from the tip, radii at both ends.
#[derive(Clone, Copy, Debug)]
struct Revolved {
    from: f64,
    to: f64,
    radius_from: f64,
    radius_to: f64,
}

impl Revolved {
    fn of(body: &Body) -> Self {
        Self {
            from: body.from,
            to: body.to,
            radius_from: body.radius_from,
            radius_to: body.radius_to,
        }
    }

    /// A body containing every point within `grow` of this one (for `grow > 0`; for
    /// `grow < 0` the body shrunk radially by `-grow`, same length).
    ///
    /// The side of a cone with half-angle α moves out by `grow / cos α` measured radially, not
    /// by `grow`; the grown side is extended `grow` beyond both end discs along the same line,
    /// which is tangent to the rounded rims of the exact offset, so the end caps are covered
    /// too. (Adding `grow` to both radii, as a first version did, let a tapered holder nose
    /// come 0.03 mm inside its margin on a real impeller.)
    fn grown(self, grow: f64) -> Self {
        if grow <= 0.0 {
            return Self {
                radius_from: (self.radius_from + grow).max(1e-3),
                radius_to: (self.radius_to + grow).max(1e-3),
                ..self
            };
        }
        let slope = (self.radius_to - self.radius_from) / (self.to - self.from);
        let side = grow * (1.0 + slope * slope).sqrt();
        Self {
            from: self.from - grow,
            to: self.to + grow,
            radius_from: (self.radius_from + side - slope * grow).max(1e-3),
            radius_to: (self.radius_to + side + slope * grow).max(1e-3),
        }
    }

    /// Extended `sweep` mm toward the spindle; a frustum swept along its axis is covered by its
    /// larger radius all the way.
    fn swept(self, sweep: f64) -> Self {
        if sweep <= 0.0 {
            return self;
        }
        let r = self.radius_from.max(self.radius_to);
        Self {
            to: self.to + sweep,
            radius_from: r,
            radius_to: r,
            ..self
        }
    }

    /// The parry shape, centred on its own origin with its axis along +Y. `exact_cylinder`
    /// asks for parry's true cylinder where the body is one (used for the flutes, whose side
    /// may touch the part); otherwise a circumscribed 32-gon prism or frustum, which contains
    /// the true body and makes parry's queries several times faster (CRATES.md §2).
    fn shape(&self, exact_cylinder: bool) -> Box<dyn Shape> {
        let half = 0.5 * (self.to - self.from);
        if exact_cylinder && self.radius_from == self.radius_to {
            return Box::new(Cylinder::new(
                half as f32,
                self.radius_from.max(self.radius_to) as f32,
            ));
        }
        let scale = circumscribed();
        let mut pts = Vec::with_capacity(2 * SIDES);
        for (y, r) in [(-half, self.radius_from), (half, self.radius_to)] {
            for k in 0..SIDES {
                let a = 2.0 * std::f64::consts::PI * k as f64 / SIDES as f64;
                pts.push(Vec3::new(
                    (r * scale * a.cos()) as f32,
                    y as f32,
                    (r * scale * a.sin()) as f32,
                ));
            }
        }
        match ConvexPolyhedron::from_convex_hull(&pts) {
            Some(hull) => Box::new(hull),
            None => Box::new(Cylinder::new(
                half as f32,
                (scale * self.radius_from.max(self.radius_to)) as f32,
            )),
        }
    }

    /// Where the shape from [`Revolved::shape`] sits for a tool at `pose`.
    fn place(&self, pose: &ToolPose, part: &PartCollider) -> Pose {
        let axis = pose.axis.into_inner();
        let centre = pose.tip + axis * (0.5 * (self.from + self.to));
        let rotation = Quat::from_rotation_arc(Vec3::Y, to_f32(&axis).normalize());
        Pose::from_parts(part.local(&centre), rotation)
    }
}

struct PreparedBody {
    role: BodyRole,
    geometry: Revolved,
    /// Radial growth of the planning test: the margin, or −[`F32_SLACK`] for the flutes.
    check_grow: f64,
    check: Box<dyn Shape>,
    /// The body itself (flutes shrunk by the slack), for clearance measurements.
    exact: Box<dyn Shape>,
}

impl PreparedBody {
    /// Where `check` and `exact` sit at `pose`: growth is symmetric along the axis, so all
    /// variants of the body share its centre.
    fn place(&self, pose: &ToolPose, part: &PartCollider) -> Pose {
        self.geometry.place(pose, part)
    }
}

/// The fluted end of a flat or bull-nose cutter as one parry solid.
struct EndSolid {
    geometry: Revolved,
    shape: Box<dyn Shape>,
}

/// A tool assembly turned into parry shapes once, for many poses.
pub struct PreparedTool {
    /// Radius of the ball of a ball-ended cutter, tested exactly in f64; 0 for flat and
    /// bull-nose cutters, whose ends are `end` solids.
    pub ball_radius: f64,
    /// How far from the tip along the axis anything of the tool can be, plus its widest radius
    /// twice: rays that screen axis candidates run this far.
    pub reach: f64,
    cutter: Cutter,
    end: Vec<EndSolid>,
    bodies: Vec<PreparedBody>,
    /// What it was prepared from, for [`PreparedTool::with_flute_dip`].
    assembly: ToolAssembly,
    margins: Margins,
    /// How far the flutes may dip into the part in the planning test, mm.
    flute_dip: f64,
}

impl PreparedTool {
    pub fn new(tool: &ToolAssembly, margins: &Margins) -> Self {
        Self::prepared(tool, margins, F32_SLACK)
    }

    /// The same tool with its flutes allowed to dip `dip` mm into the part (at least the f32
    /// slack), where they cut with their side as the ball does (swarf milling): the planning
    /// test shrinks them by that much instead of the slack.
    pub fn with_flute_dip(&self, dip: f64) -> Self {
        Self::prepared(&self.assembly, &self.margins, dip.max(F32_SLACK))
    }

    /// How far the flutes may dip into the part in the planning test, mm.
    pub fn flute_dip(&self) -> f64 {
        self.flute_dip
    }

    /// The assembly the tool was prepared from.
    pub fn assembly(&self) -> &ToolAssembly {
        &self.assembly
    }

    /// The cutting length above the ball's centre (flutes from the ball's equator up), and
    /// their radius at the top; `None` for cutters without a ball.
    pub fn flutes_above_ball(&self) -> Option<(f64, f64)> {
        let body = self.bodies.iter().find(|b| b.role == BodyRole::Flutes)?;
        let g = &body.geometry;
        Some((g.to - self.ball_radius, g.radius_from.max(g.radius_to)))
    }

    fn prepared(tool: &ToolAssembly, margins: &Margins, flute_dip: f64) -> Self {
        let bodies = tool
            .bodies()
            .iter()
            .map(|b| {
                let geometry = Revolved::of(b);
                let flutes = b.role == BodyRole::Flutes;
                let check_grow = match b.role {
                    BodyRole::Flutes => -flute_dip,
                    BodyRole::Shank => margins.shank + F32_SLACK,
                    BodyRole::Holder => margins.holder + F32_SLACK,
                };
                let exact_geometry = if flutes {
                    geometry.grown(-F32_SLACK)
                } else {
                    geometry
                };
                // Clearances are measured on the true cylinder where the body is one; frustums
                // use the circumscribed prism (at most 0.5 % of the radius conservative).
                let cylinder = (b.radius_from - b.radius_to).abs() < 1e-12;
                PreparedBody {
                    role: b.role,
                    geometry,
                    check_grow,
                    check: geometry.grown(check_grow).shape(flutes),
                    exact: exact_geometry.shape(flutes || cylinder),
                }
            })
            .collect();
        Self {
            ball_radius: tool.ball_radius().unwrap_or(0.0),
            reach: tool.total_length() + 2.0 * tool.max_radius(),
            cutter: tool.cutter,
            end: end_solids(&tool.cutter),
            bodies,
            assembly: tool.clone(),
            margins: *margins,
            flute_dip,
        }
    }

    pub fn cutter(&self) -> &Cutter {
        &self.cutter
    }

    /// The lowest z of any point of the tool at `pose`, or anywhere along its move of `sweep`
    /// mm up its own axis. Every body is a frustum along the axis, whose lowest point is on the
    /// rim of one of its end discs: z = tip.z + h·a_z − R·√(1 − a_z²); the cutter's rounded end
    /// is lowest on its corner circle, z = tip.z + rc·a_z − R'·√(1 − a_z²) − rc.
    pub fn lowest_z(&self, pose: &ToolPose, sweep: f64) -> f64 {
        let a = pose.axis.into_inner();
        let lateral = (1.0 - a.z * a.z).max(0.0).sqrt();
        let (rc, flat) = (self.cutter.corner_radius(), self.cutter.flat_radius());
        let mut lowest = f64::INFINITY;
        for start in [0.0, sweep.max(0.0)] {
            let tip_z = pose.tip.z + a.z * start;
            // The corner: a circle of radius `flat` at height rc, grown by rc.
            lowest = lowest.min(tip_z + a.z * rc - flat * lateral - rc);
            let top = self.cutter.flute_length();
            lowest = lowest.min(tip_z + a.z * top - self.cutter.flute_top_radius() * lateral);
            for b in &self.bodies {
                let g = &b.geometry;
                for (h, r) in [(g.from, g.radius_from), (g.to, g.radius_to)] {
                    lowest = lowest.min(tip_z + a.z * h - r * lateral);
                }
            }
        }
        lowest
    }
}

/// The fluted end of a flat (a cylinder) or bull-nose cutter (a cylinder rounded by the corner
/// radius, whose rounded top rim is filled by a plain cylinder from the corner up). Ball-ended
/// cutters have none: their ball is exact in f64 and their flank is a flute body.
fn end_solids(cutter: &Cutter) -> Vec<EndSolid> {
    let (length, radius) = (cutter.flute_length(), cutter.diameter() / 2.0);
    let cylinder = |from: f64| {
        let geometry = Revolved {
            from,
            to: length,
            radius_from: radius,
            radius_to: radius,
        };
        EndSolid {
            shape: geometry.shape(true),
            geometry,
        }
    };
    match *cutter {
        Cutter::Flat { .. } => vec![cylinder(0.0)],
        Cutter::BullNose { corner_radius, .. } => {
            // Flutes shorter than two corner radii: the rounded solid reaches a little above them
            // (still inside the tool's reach, never below the tip).
            let inner_half = (0.5 * length - corner_radius).max(1e-3);
            let geometry = Revolved {
                from: 0.0,
                to: 2.0 * (corner_radius + inner_half),
                radius_from: radius,
                radius_to: radius,
            };
            let rounded = RoundCylinder {
                inner_shape: Cylinder::new(inner_half as f32, (radius - corner_radius) as f32),
                border_radius: corner_radius as f32,
            };
            vec![
                EndSolid {
                    geometry,
                    shape: Box::new(rounded),
                },
                cylinder(corner_radius),
            ]
        }
        Cutter::Ball { .. } | Cutter::TaperedBall { .. } => Vec::new(),
    }
}

fn to_f32(v: &Vector3) -> Vec3 {
    Vec3::new(v.x as f32, v.y as f32, v.z as f32)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::geom::Direction;
    use crate::mesh::fixtures::cuboid;
    use crate::tool::{Cutter, Section};

    /// Ball D6, 12 mm flutes, D6 shank sticking out 30 mm, a D30 × 20 holder.
    pub(crate) fn tool() -> ToolAssembly {
        ToolAssembly {
            id: 1,
            name: String::new(),
            cutter: Cutter::Ball {
                diameter: 6.0,
                flute_length: 12.0,
            },
            neck: None,
            shank_diameter: 6.0,
            stickout: 30.0,
            holder: vec![Section::cylinder(30.0, 20.0)],
        }
    }

    fn pose(tip: [f64; 3], axis: [f64; 3]) -> ToolPose {
        ToolPose {
            tip: Point3::from(tip),
            axis: Direction::new_normalize(Vector3::from(axis)),
        }
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

    const M: Margins = Margins {
        shank: 0.5,
        holder: 2.0,
    };

    /// [`tool`] with a 0.5 mm shank and 2 mm holder margin.
    pub(crate) fn prepared() -> PreparedTool {
        PreparedTool::new(&tool(), &M)
    }

    fn far() -> BodyClearance {
        BodyClearance {
            flutes: 50.0,
            shank: 50.0,
            holder: 50.0,
        }
    }

    /// Material left around a plate: a block to z = 40 with a round pocket (radius 8, down to
    /// 0.5 above the plate) about the z axis.
    fn material_around_the_plate() -> Arc<MaterialClearance> {
        let bounds = crate::geom::Aabb::from_points(&[
            Point3::new(-30.0, -30.0, 0.0),
            Point3::new(30.0, 30.0, 40.0),
        ]);
        let mut stock = crate::stock::Stock::block(&bounds, 0.25, 10_000_000).unwrap();
        stock.remove(&Frustum {
            base: Point3::new(0.0, 0.0, 20.5),
            axis: Vector3::z(),
            from: 0.0,
            to: 30.0,
            radius_from: 8.0,
            radius_to: 8.0,
        });
        Arc::new(MaterialClearance::new(&stock))
    }

    /// A tool 1.5 mm above the plate, tilted 20° toward the pocket's wall: where its shank
    /// passes the block's top (19.7 mm up the axis) it reaches 19.7 sin 20° + 3 + 0.5 margin =
    /// 10.2 mm off the pocket's axis, past the wall at 8. The part alone lets it stand, the
    /// material does not. Upright, or tilted 5°, it keeps its margin.
    #[test]
    fn the_shank_keeps_its_margin_from_the_material_left() {
        let part = plate();
        let with_material = part.with_material(material_around_the_plate());
        let tool = prepared();
        let upright = pose([0.0, 0.0, 21.5], [0.0, 0.0, 1.0]);
        let tilted = |degrees: f64| {
            let a = degrees.to_radians();
            pose([0.0, 0.0, 21.5], [a.sin(), 0.0, a.cos()])
        };
        assert!(with_material.check_bodies(&tool, &upright).is_ok());
        assert!(part.check_bodies(&tool, &tilted(20.0)).is_ok());
        assert_eq!(
            with_material.check_bodies(&tool, &tilted(20.0)),
            Err(Collision::Material {
                role: BodyRole::Shank
            })
        );
        assert!(with_material.check_bodies(&tool, &tilted(5.0)).is_ok());
        // Retracting upright 100 mm stays inside the pocket's bore and then above the block;
        // tilted toward the wall, the shank's sweep meets it too.
        assert!(
            with_material
                .check_bodies_swept(&tool, &upright, 100.0)
                .is_ok()
        );
        assert_eq!(
            with_material.check_bodies_swept(&tool, &tilted(20.0), 100.0),
            Err(Collision::Material {
                role: BodyRole::Shank
            })
        );
    }

    #[test]
    fn vertical_tool_touching_the_top_is_clear_and_lower_gouges() {
        let part = plate();
        assert!(
            part.check_pose(&prepared(), &pose([0.0, 0.0, 20.0], [0.0, 0.0, 1.0]))
                .is_ok()
        );
        match part.check_pose(&prepared(), &pose([0.0, 0.0, 19.9], [0.0, 0.0, 1.0])) {
            Err(Collision::Gouge { depth }) => assert!((depth - 0.1).abs() < 1e-9),
            other => panic!("{other:?}"),
        }
        // Deep inside: parry's hollow mesh would see nothing; the signed distance does.
        assert!(matches!(
            part.check_pose(&prepared(), &pose([0.0, 0.0, 5.0], [0.0, 0.0, 1.0])),
            Err(Collision::Gouge { .. })
        ));
    }

    #[test]
    fn holder_hits_a_wall_when_tilted_toward_it() {
        // Ball on the plate near the wall of a tall block: tilt the tool toward the block and
        // the holder (radius 15) reaches it; tilt away and it does not.
        let m = crate::mesh::fixtures::plate_and_wall(20.0, 120.0);
        let part = PartCollider::new(&m).unwrap();
        // The ball (r = 3) rests on the plate at x = 95; the tip moves with the axis.
        let on_ball = |axis: [f64; 3]| {
            let a = Vector3::from(axis).normalize();
            let tip = Point3::new(95.0, 50.0, 23.0) - a * 3.0;
            pose(tip.into(), axis)
        };
        assert!(
            part.check_pose(&prepared(), &on_ball([0.0, 0.0, 1.0]))
                .is_ok()
        );
        assert_eq!(
            part.check_pose(&prepared(), &on_ball([0.6, 0.0, 0.8])),
            Err(Collision::Body {
                role: BodyRole::Holder
            })
        );
        assert!(
            part.check_pose(&prepared(), &on_ball([-0.6, 0.0, 0.8]))
                .is_ok()
        );
    }

    #[test]
    fn clearances_match_closed_form_above_a_plate() {
        let part = plate();
        // Tool hovering 5 mm above the plate, vertical: flutes start at the ball centre, so
        // their lowest point is 5 + 3 above the plate; shank starts at 12 + 5; holder at 30 + 5.
        let c = part.clearances(
            &prepared(),
            &pose([0.0, 0.0, 25.0], [0.0, 0.0, 1.0]),
            &far(),
        );
        // f32 GJK distances: a few µm.
        assert!((c.flutes - 8.0).abs() < 5e-3, "{c:?}");
        assert!((c.shank - 17.0).abs() < 5e-3, "{c:?}");
        assert!((c.holder - 35.0).abs() < 5e-3, "{c:?}");
        // Horizontal tool lying 1 mm above the plate (tip side): every body's lowest line.
        let c = part.clearances(
            &prepared(),
            &pose([-40.0, 0.0, 24.0], [1.0, 0.0, 0.0]),
            &far(),
        );
        assert!((c.flutes - 1.0).abs() < 5e-3, "{c:?}");
        assert!(
            (c.holder - (24.0 - 15.0 - 20.0)).abs() < 1e-3 || c.holder == 0.0,
            "{c:?}"
        );
    }

    #[test]
    fn lowest_point_and_table_match_closed_form() {
        let part = plate().with_table(Table {
            top_z: 0.0,
            margin: 1.0,
        });
        let t = prepared();
        // Vertical tool on the plate top (z = 20): the lowest point is the tip.
        let up = pose([0.0, 0.0, 20.0], [0.0, 0.0, 1.0]);
        assert!((t.lowest_z(&up, 0.0) - 20.0).abs() < 1e-12);
        // Horizontal tool along +X with the ball centre at z = 23 on the plate edge: the holder
        // (radius 15) hangs 15 below the axis.
        let side = pose([45.0, 0.0, 23.0], [1.0, 0.0, 0.0]);
        assert!((t.lowest_z(&side, 0.0) - 8.0).abs() < 1e-12);
        // Tilted 45° down: the holder's far rim is lowest.
        let a = Vector3::new(1.0, 0.0, -1.0).normalize();
        let down = ToolPose {
            tip: Point3::new(60.0, 0.0, 60.0),
            axis: Direction::new_normalize(a),
        };
        let expect =
            60.0 - 50.0 * std::f64::consts::FRAC_1_SQRT_2 - 15.0 * std::f64::consts::FRAC_1_SQRT_2;
        assert!((t.lowest_z(&down, 0.0) - expect).abs() < 1e-9);
        assert_eq!(part.check_bodies(&t, &down), Ok(()));
        // Swept 40 mm further along that axis it would reach below the table.
        assert_eq!(
            part.check_bodies_swept(&t, &down, 40.0),
            Err(Collision::Table)
        );
        let below = pose([60.0, 0.0, 0.5], [1.0, 0.0, 0.0]);
        assert_eq!(part.check_bodies(&t, &below), Err(Collision::Table));
    }

    /// The grown body contains every point within the growth distance of the original: check
    /// points on a fine grid around a steep frustum against the exact distance to it.
    #[test]
    fn grown_frustum_contains_the_offset() {
        let body = Revolved {
            from: 10.0,
            to: 20.0,
            radius_from: 2.0,
            radius_to: 8.0,
        };
        let grow = 1.5;
        let g = body.grown(grow);
        // Distance from a point (h, rho) in the half-plane to the solid frustum profile.
        let inside_profile = |h: f64, rho: f64, b: &Revolved| {
            h >= b.from
                && h <= b.to
                && rho
                    <= b.radius_from
                        + (b.radius_to - b.radius_from) * (h - b.from) / (b.to - b.from)
        };
        let dist_to_segment = |p: (f64, f64), a: (f64, f64), b: (f64, f64)| {
            let (dx, dy) = (b.0 - a.0, b.1 - a.1);
            let t = (((p.0 - a.0) * dx + (p.1 - a.1) * dy) / (dx * dx + dy * dy)).clamp(0.0, 1.0);
            ((p.0 - a.0 - t * dx).powi(2) + (p.1 - a.1 - t * dy).powi(2)).sqrt()
        };
        let corners = [(10.0, 0.0), (10.0, 2.0), (20.0, 8.0), (20.0, 0.0)];
        let mut tested = 0;
        for i in 0..=200 {
            for j in 0..=120 {
                let (h, rho) = (6.0 + i as f64 * 0.09, j as f64 * 0.1);
                let d = if inside_profile(h, rho, &body) {
                    0.0
                } else {
                    (0..4)
                        .map(|k| dist_to_segment((h, rho), corners[k], corners[(k + 1) % 4]))
                        .fold(f64::INFINITY, f64::min)
                };
                if d <= grow {
                    tested += 1;
                    assert!(
                        inside_profile(h, rho, &g),
                        "({h}, {rho}) is {d} from the body but outside the grown one"
                    );
                }
            }
        }
        assert!(tested > 1000);
    }

    #[test]
    fn sweep_along_the_axis_finds_an_overhang() {
        // A roof above the plate: a vertical tool standing on the plate under the roof is fine
        // where it is (the roof is above the holder), but retracting upward hits it.
        let mut m = cuboid(100.0, 100.0, 20.0);
        let roof = cuboid(100.0, 100.0, 5.0);
        let base = m.positions.len() as u32;
        m.positions.extend(
            roof.positions
                .iter()
                .map(|p| Point3::new(p.x, p.y, p.z + 100.0)),
        );
        m.triangles
            .extend(roof.triangles.iter().map(|t| t.map(|i| i + base)));
        let part = PartCollider::new(&m).unwrap();
        let p = pose([50.0, 50.0, 20.0], [0.0, 0.0, 1.0]);
        assert!(part.check_pose(&prepared(), &p).is_ok());
        assert!(part.check_bodies_swept(&prepared(), &p, 10.0).is_ok());
        assert!(part.check_bodies_swept(&prepared(), &p, 60.0).is_err());
        assert!(part.check_ball_sweep(&prepared(), &p, 60.0).is_ok());
        assert!(part.check_ball_sweep(&prepared(), &p, 90.0).is_err());
    }

    /// The inside of a sphere of radius R as the surface (wound inward): a ball of radius r
    /// centred c from the centre clears the wall by R − c − r, less the facets' sagitta.
    #[test]
    fn a_ball_in_a_spherical_cavity_has_its_closed_form_clearance() {
        let big_r = 20.0;
        let mut cavity = crate::mesh::fixtures::uv_sphere(big_r, 90, 180);
        for t in &mut cavity.triangles {
            t.swap(1, 2);
        }
        let collider = PartCollider::new(&cavity).unwrap();
        let sagitta = big_r * (1.0 - (std::f64::consts::PI / 90.0).cos());
        for (c, r) in [(0.0, 5.0), (7.0, 6.0), (12.0, 7.5), (10.0, 9.99)] {
            let centre = Point3::new(c * 0.6, -c * 0.48, c * 0.64);
            let clearance = collider.check_ball(&centre, r, 0.0).unwrap();
            let expected = big_r - centre.coords.norm() - r;
            assert!(
                clearance <= expected + 1e-9 && clearance >= expected - 2.0 * sagitta,
                "c {c} r {r}: {clearance} vs {expected}"
            );
        }
        // A ball reaching past the wall gouges by the overlap.
        match collider.check_ball(&Point3::new(0.0, 12.0, 0.0), 8.5, 0.0) {
            Err(Collision::Gouge { depth }) => {
                assert!((depth - 0.5).abs() <= 2.0 * sagitta, "{depth}")
            }
            other => panic!("{other:?}"),
        }
    }

    /// The truncated cone the sphere tests measure: 4 to 16 mm up the axis, radius 3 to 5.
    fn frustum() -> Revolved {
        Revolved {
            from: 4.0,
            to: 16.0,
            radius_from: 3.0,
            radius_to: 5.0,
        }
    }

    /// Distance from a point at height `h`, `rho` off the axis, to `body`: 0 inside, else to
    /// the nearest side of its half-section (a trapezoid in the meridian half-plane).
    fn to_frustum(body: &Revolved, h: f64, rho: f64) -> f64 {
        let corners = [
            (body.from, 0.0),
            (body.from, body.radius_from),
            (body.to, body.radius_to),
            (body.to, 0.0),
        ];
        let t = (h - body.from) / (body.to - body.from);
        let slant = body.radius_from + (body.radius_to - body.radius_from) * t;
        if (0.0..=1.0).contains(&t) && rho <= slant {
            return 0.0;
        }
        (0..4)
            .map(|i| {
                let (a, b) = (corners[i], corners[(i + 1) % 4]);
                let (dx, dy) = (b.0 - a.0, b.1 - a.1);
                let s = (((h - a.0) * dx + (rho - a.1) * dy) / (dx * dx + dy * dy)).clamp(0.0, 1.0);
                (h - a.0 - s * dx).hypot(rho - a.1 - s * dy)
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// The capsule verdict against a closed form: a truncated cone meets a sphere's surface
    /// when its nearest point lies inside the sphere and its farthest outside. The nearest is
    /// the 2D distance from the centre to the cone's trapezoid in the meridian half-plane, the
    /// farthest lies on a rim. Poses within the mesh's sagitta of either answer are skipped;
    /// every verdict given on the others must be right, and most must be given.
    #[test]
    fn capsule_verdicts_agree_with_a_sphere_in_closed_form() {
        let big_r = 20.0;
        let collider =
            PartCollider::new(&crate::mesh::fixtures::uv_sphere(big_r, 60, 120)).unwrap();
        let sagitta = 2.0 * big_r * (1.0 - (std::f64::consts::PI / 60.0).cos());
        let body = frustum();
        let distance_to_trapezoid = |h: f64, rho: f64| to_frustum(&body, h, rho);
        let (mut decided, mut meets, mut clear, mut judged) = (0, 0, 0, 0);
        for i in 0..40 {
            for j in 0..40 {
                let (u, v) = (i as f64 / 40.0, j as f64 / 40.0);
                let tip = Point3::new(
                    30.0 * u - 15.0,
                    26.0 * v - 13.0,
                    24.0 * (u * 7.3 + v * 3.1).fract() - 4.0,
                );
                let axis = Vector3::new((u * 11.0).sin(), (v * 13.0).cos(), 0.6 + (u + v) * 0.5)
                    .normalize();
                let pose = pose(tip.into(), axis.into());
                let to_centre = Point3::origin() - pose.tip;
                let h = to_centre.dot(&axis);
                let across = (to_centre - h * axis).norm();
                let nearest = distance_to_trapezoid(h, across);
                let farthest = [(body.from, body.radius_from), (body.to, body.radius_to)]
                    .into_iter()
                    .map(|(height, radius)| (height - h).hypot(across + radius))
                    .fold(0.0, f64::max);
                let truth = if nearest < big_r - sagitta - 1e-6 && farthest > big_r + 1e-6 {
                    true
                } else if nearest > big_r + 1e-6 || farthest < big_r - sagitta - 1e-6 {
                    false
                } else {
                    continue;
                };
                judged += 1;
                if let Some(verdict) = collider.capsule_verdict(&body, &pose) {
                    assert_eq!(verdict, truth, "tip {tip:?} axis {axis:?}");
                    decided += 1;
                    if verdict { meets += 1 } else { clear += 1 }
                }
            }
        }
        assert!(meets > 100 && clear > 100, "{meets} meet, {clear} clear");
        assert!(
            decided * 5 >= judged * 4,
            "{decided} of {judged} decided, {meets} meet, {clear} clear"
        );
    }

    /// `farther_than` never says farther where the body comes within the limit (the distance
    /// of a frustum to a sphere's centre, less the radius, in closed form; the facets lie
    /// inside the sphere by at most their sagitta), and it decides most poses it should.
    #[test]
    fn farther_than_agrees_with_a_sphere_in_closed_form() {
        let big_r = 20.0;
        let collider =
            PartCollider::new(&crate::mesh::fixtures::uv_sphere(big_r, 60, 120)).unwrap();
        let body = frustum();
        let (mut should, mut said) = (0, 0);
        for i in 0..30 {
            for j in 0..30 {
                let (u, v) = (i as f64 / 30.0, j as f64 / 30.0);
                let tip = Point3::new(
                    40.0 * u - 20.0,
                    36.0 * v - 18.0,
                    30.0 * (u * 7.3 + v * 3.1).fract() + 10.0,
                );
                let axis = Vector3::new((u * 11.0).sin(), (v * 13.0).cos(), 0.6 + (u + v) * 0.5)
                    .normalize();
                let pose = pose(tip.into(), axis.into());
                let to_centre = Point3::origin() - pose.tip;
                let h = to_centre.dot(&axis);
                let rho = (to_centre - h * axis).norm();
                // Outside the sphere, the frustum's nearest point to the centre is nearest
                // the sphere too.
                let outside = to_frustum(&body, h, rho) - big_r;
                for limit in [0.5, 2.0, 7.0] {
                    let far = collider.farther_than(&body, &pose, limit);
                    if far {
                        said += 1;
                        // Facets lie inside the sphere: the mesh is no nearer than the sphere.
                        assert!(
                            outside >= limit - 1e-9,
                            "{tip:?} {axis:?} {limit}: {outside}"
                        );
                    }
                    // Clear by more than the pieces' capsules reach past the body (a radius
                    // past its ends, the slant over a piece, the prism's corners): it must
                    // say so.
                    if outside > limit + body.radius_to + 0.5 {
                        should += 1;
                        assert!(far, "{tip:?} {axis:?} {limit}: {outside}");
                    }
                }
            }
        }
        assert!(said > 200 && should > 200, "{said} said, {should} should");
    }

    /// A tapered holder (cone 20 → 40 mm over 30 mm) beside the vertical edge of a tall block,
    /// axis parallel to the edge: the clearance is the distance to the edge line less the
    /// largest radius the edge faces, D − 20, within the circumscribed prism's 0.5 %.
    #[test]
    fn a_tapered_holder_beside_an_edge_has_its_closed_form_clearance() {
        let block = cuboid(20.0, 20.0, 100.0);
        let part = PartCollider::new(&block).unwrap();
        let mut t = tool();
        t.holder = vec![Section {
            diameter: 20.0,
            top_diameter: Some(40.0),
            length: 30.0,
        }];
        let prepared = PreparedTool::new(&t, &M);
        // The tool axis vertical, 30 mm from the edge x = 20, y = 20 along the diagonal.
        let d = 30.0;
        let s = d / std::f64::consts::SQRT_2;
        let tip = [20.0 + s, 20.0 + s, 10.0];
        let c = part.clearances(&prepared, &pose(tip, [0.0, 0.0, 1.0]), &far());
        let exact = d - 20.0;
        assert!(
            c.holder <= exact + 5e-3 && c.holder >= exact - 0.005 * 20.0 - 5e-3,
            "{c:?} vs {exact}"
        );
        // Shank (radius 3, up to 30 mm) at 30 mm from the edge: 27.
        assert!((c.shank - (d - 3.0)).abs() < 5e-3, "{c:?}");
    }
}
