//! Indexed (3+2) layer roughing: the layer planner of [`super::rough_layers`] run along a fixed
//! tilted tool axis, to reach the material the vertical layers cannot (under a blade's
//! overhang, in an undercut), in the setups [`super::setups`] proposes from the visibility maps.
//!
//! A setup is a frame whose +Z is the tool axis ([`SetupFrame`]). The shape roughed to and the
//! in-process stock are turned into it (the stock resampled along the frame's axes,
//! [`crate::stock::Stock::resampled`]), the layers are planned there exactly as vertical ones,
//! and the moves are turned back, the axis fixed for the whole setup. The planner's guarantees
//! carry over as they are: outside the turned shape by the tool's widest radius below the
//! holder, the holder above all the material standing (in the setup's vertical), the shank off
//! what stands above the flutes.
//!
//! What a vertical axis never meets and a tilted one does is the machine table: a tool tilted
//! by θ reaches below its tip by its radius × sin θ, and a holder further out. The table's
//! top, less the table margin and that reach, is a plane the tip must stay above
//! ([`lowest_tip_z`]); in the setup frame it is a tilted plane, and the region below it over
//! the material's footprint is added to the shape as a solid the layers keep off.

use nalgebra::Rotation3;

use super::{Blank, Material, RoughError, Roughing, RoughingOptions, RoughingTool, region};
use crate::contour::geometry::{Point2, Shape};
use crate::geom::{Direction, Point3, Toolpath, Vector3};
use crate::mesh::Mesh;
use crate::stock::cutter::CuttingBody;
use crate::stock::{DEFAULT_MAX_DEXELS, Stock};
use crate::tool::ToolAssembly;

/// A setup's frame: the part turned so that the tool axis is +Z.
#[derive(Clone, Debug, PartialEq)]
pub struct SetupFrame {
    axis: Direction,
    to_setup: Rotation3<f64>,
}

impl SetupFrame {
    /// The frame for tool axis `axis` (part frame); `None` for a zero axis or one pointing
    /// down (no setup cuts from below the table).
    pub fn new(axis: &Vector3) -> Option<SetupFrame> {
        let axis = Direction::try_new(*axis, 1e-12)?;
        if axis.z <= 0.0 {
            return None;
        }
        // The shortest turn taking the axis to +Z: a pure tilt about a horizontal line, as a
        // table-table machine's tilting axis makes it.
        let to_setup = Rotation3::rotation_between(&axis.into_inner(), &Vector3::z())?;
        Some(SetupFrame { axis, to_setup })
    }

    /// The tool axis in the part frame.
    pub fn axis(&self) -> Direction {
        self.axis
    }

    /// The angle between the tool axis and the part's +Z, degrees.
    pub fn tilt_deg(&self) -> f64 {
        self.axis.z.clamp(-1.0, 1.0).acos().to_degrees()
    }

    /// The rotation from the part frame into the setup frame.
    pub fn rotation(&self) -> &Rotation3<f64> {
        &self.to_setup
    }

    pub fn to_setup(&self, p: &Point3) -> Point3 {
        self.to_setup * p
    }

    pub fn to_part(&self, p: &Point3) -> Point3 {
        self.to_setup.inverse_transform_point(p)
    }

    /// `mesh` in the setup frame.
    pub fn mesh_to_setup(&self, mesh: &Mesh) -> Mesh {
        Mesh {
            positions: mesh.positions.iter().map(|p| self.to_setup(p)).collect(),
            triangles: mesh.triangles.clone(),
        }
    }
}

/// The lowest the tip of `tool` may go (part-frame z) along `axis` so that no body of the
/// tool comes below `table_top + margin`: the lowest point of each body (a frustum from
/// `from` to `to` along the axis; the fluted end taken as the cylinder of its diameter, which
/// holds it) is on one of its end circles.
pub fn lowest_tip_z(tool: &ToolAssembly, axis: &Direction, table_top: f64, margin: f64) -> f64 {
    let sideways = (1.0 - axis.z * axis.z).max(0.0).sqrt();
    let cutter = 0.5 * tool.cutter.diameter();
    let below_tip = tool
        .bodies()
        .iter()
        .flat_map(|b| [(b.from, b.radius_from), (b.to, b.radius_to)])
        .chain([(0.0, cutter), (tool.flute_length(), cutter)])
        .map(|(h, r)| h * axis.z - r * sideways)
        .fold(0.0, f64::min);
    table_top + margin - below_tip
}

/// How a setup roughs, beyond the tool and the shape.
pub struct SetupRoughing<'a> {
    /// The lowest part-frame z the tip may go ([`lowest_tip_z`]).
    pub lowest_tip_z: f64,
    /// The rest this setup is for, part frame, in zones: each from a point of the part out to
    /// where its material ends. Each zone's layers clear material only within the convex hull
    /// of its rest seen along the axis, grown by the tool's radius and a dexel spacing; empty:
    /// wherever material stands.
    pub zones: &'a [Vec<(Point3, Point3)>],
    /// The widest radius of the tool's holder, mm: the holder must clear the material it can
    /// pass over (the zone grown by the tool's and the holder's radii), not all of it.
    pub holder_radius: f64,
    /// The body taken off the setup's copy of the stock as layers are planned.
    pub body: &'a CuttingBody,
    pub options: &'a RoughingOptions,
}

/// The layers of one setup: `shape` (part frame) roughed from what `stock` (part frame) still
/// holds, with the tool along `frame`'s axis. The moves come back in the part frame, the axis
/// fixed, starting and ending at the setup's safe height above the material; `removed_mm3`
/// is what each took off the setup's resampled copy of the stock (the caller takes them off
/// `stock` itself). `None` when the stock holds no material.
pub fn rough_setup(
    shape: &Mesh,
    stock: &Stock,
    frame: &SetupFrame,
    tool: &RoughingTool,
    tool_id: u32,
    how: &SetupRoughing,
) -> Result<Option<Roughing>, RoughError> {
    let spacing = stock.spacing();
    // Not grown: what the planner keeps off is checked on the original model by the stock run
    // with the whole tool, and a grown copy shows a skin of rest over every surface.
    let mut turned = match stock.resampled(frame.rotation(), spacing, 0.0, DEFAULT_MAX_DEXELS) {
        Ok(turned) => turned,
        Err(crate::stock::StockError::Blank(_)) => return Ok(None),
        Err(e) => {
            return Err(RoughError::Blank(format!(
                "the stock in the setup's frame: {e}"
            )));
        }
    };
    let material = turned.material_bounds();
    if material.is_empty() {
        return Ok(None);
    }
    let mut shape = frame.mesh_to_setup(shape);
    let footprint = (
        Point2::new(material.min.x, material.min.y),
        Point2::new(material.max.x, material.max.y),
    );
    if let Some(keep_out) = below_plane(frame, how.lowest_tip_z, footprint, tool.radius + 1.0)
        && keep_out.aabb().max.z > material.min.z
    {
        append(&mut shape, &keep_out);
    }
    let blank = Blank {
        outline: Shape {
            contours: vec![region::rectangle(
                footprint.0 - Vector2::new(1.0, 1.0),
                footprint.1 + Vector2::new(1.0, 1.0),
            )],
        },
        bottom: material.min.z,
        top: material.max.z,
    };
    let mut options = how.options.clone();
    options.floor = Some(material.min.z);
    let whole = [Vec::new()];
    let zones = if how.zones.is_empty() {
        &whole[..]
    } else {
        how.zones
    };
    let mut roughing: Option<Roughing> = None;
    for rest in zones {
        if !rest.is_empty() {
            let seen: Vec<Point2> = rest
                .iter()
                .flat_map(|(a, b)| [frame.to_setup(a), frame.to_setup(b)])
                .map(|p| Point2::new(p.x, p.y))
                .collect();
            let zone = grown_hull(&seen, tool.radius + spacing);
            options.holder_top = Some(highest_within(
                &turned,
                &grown_hull(&zone, how.holder_radius + spacing),
            ));
            options.zone = Some(zone);
            options.skin = 2.0 * spacing;
        }
        let zone = super::rough_layers(
            &shape,
            &blank,
            tool,
            tool_id,
            Material::Stock {
                stock: &mut turned,
                body: how.body,
            },
            &options,
        )?;
        roughing = Some(match roughing {
            None => zone,
            Some(mut so_far) => {
                // Both start and end on the setup's safe height, above all the material.
                so_far.toolpath.moves.extend(zone.toolpath.moves);
                so_far.layers.extend(zone.layers);
                so_far.removed_mm3.extend(zone.removed_mm3);
                so_far.safe_z = so_far.safe_z.max(zone.safe_z);
                so_far.not_reached = so_far.not_reached.or(zone.not_reached);
                so_far
            }
        });
    }
    let Some(mut roughing) = roughing else {
        return Ok(None);
    };
    for m in &mut roughing.toolpath.moves {
        m.pose.tip = frame.to_part(&m.pose.tip);
        m.pose.axis = frame.axis();
    }
    Ok(Some(roughing))
}

type Vector2 = nalgebra::Vector2<f64>;

/// The convex hull of `points` grown by `by`: each point replaced by the 16-gon circumscribing
/// its disc of radius `by`, so the hull holds every point within `by` of the points' hull.
fn grown_hull(points: &[Point2], by: f64) -> Vec<Point2> {
    let corner = by / (std::f64::consts::PI / 16.0).cos();
    let ring: Vec<Vector2> = (0..16)
        .map(|k| {
            let t = k as f64 * std::f64::consts::PI / 8.0;
            Vector2::new(t.cos(), t.sin()) * corner
        })
        .collect();
    let grown: Vec<Point2> = points
        .iter()
        .flat_map(|p| ring.iter().map(move |v| p + v))
        .collect();
    crate::contour::multires::hull::convex_hull(&grown)
}

/// Whether the segment from `a` to `b` meets the convex counter-clockwise polygon `hull`
/// (Cyrus–Beck: the segment clipped by each edge's inner half-plane).
fn segment_meets_convex(hull: &[Point2], a: Point2, b: Point2) -> bool {
    if hull.len() < 3 {
        return false;
    }
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    let d = b - a;
    for k in 0..hull.len() {
        let (p, q) = (hull[k], hull[(k + 1) % hull.len()]);
        let edge = q - p;
        // Inside: edge.perp(x − p) ≥ 0, linear in t: f0 + t·df.
        let f0 = edge.perp(&(a - p));
        let df = edge.perp(&d);
        if df.abs() < 1e-15 {
            if f0 < 0.0 {
                return false;
            }
        } else {
            let t = -f0 / df;
            if df > 0.0 {
                t0 = t0.max(t);
            } else {
                t1 = t1.min(t);
            }
        }
        if t0 > t1 {
            return false;
        }
    }
    true
}

/// The top of the material of `stock` over the convex polygon `zone`: the highest end of a
/// span on its vertical lines there, or of a horizontal line's span crossing it, mm.
fn highest_within(stock: &Stock, zone: &[Point2]) -> f64 {
    let inside = |p: &Point3| super::rest::in_convex(zone, Point2::new(p.x, p.y));
    let mut top = f64::NEG_INFINITY;
    let vertical = stock.grid(2);
    let [w, h] = vertical.counts();
    for j in 0..h {
        for i in 0..w {
            if let Some(last) = vertical.spans(i, j).last()
                && inside(&vertical.line_point(i, j))
            {
                top = top.max(last.end);
            }
        }
    }
    for axis in [0, 1] {
        let grid = stock.grid(axis);
        let [n0, n1] = grid.counts();
        for b in 0..n1 {
            for a in 0..n0 {
                let p = grid.line_point(a, b);
                if p.z <= top {
                    continue;
                }
                let crosses = grid.spans(a, b).iter().any(|span| {
                    let (mut from, mut to) = (p, p);
                    from[axis] = span.start;
                    to[axis] = span.end;
                    segment_meets_convex(zone, Point2::new(from.x, from.y), Point2::new(to.x, to.y))
                });
                if crosses {
                    top = p.z;
                }
            }
        }
    }
    top
}

/// The solid below the plane `z = lowest` of the part frame, seen in the setup frame over the
/// rectangle `footprint` grown by `margin`: a prism whose top is the plane's patch over it.
/// `None` when the axis lies in the plane (no setup is that steep).
fn below_plane(
    frame: &SetupFrame,
    lowest: f64,
    footprint: (Point2, Point2),
    margin: f64,
) -> Option<Mesh> {
    // The part's +Z in the setup frame; the plane is n · q = lowest.
    let n = frame.rotation() * Vector3::z();
    if n.z < 1e-6 {
        return None;
    }
    let (lo, hi) = (
        footprint.0 - Vector2::new(margin, margin),
        footprint.1 + Vector2::new(margin, margin),
    );
    let height = |x: f64, y: f64| (lowest - n.x * x - n.y * y) / n.z;
    let corners = [(lo.x, lo.y), (hi.x, lo.y), (hi.x, hi.y), (lo.x, hi.y)];
    let tops: Vec<Point3> = corners
        .iter()
        .map(|&(x, y)| Point3::new(x, y, height(x, y)))
        .collect();
    let bottom = tops.iter().map(|p| p.z).fold(f64::INFINITY, f64::min) - 1.0;
    let mut positions = tops.clone();
    positions.extend(tops.iter().map(|p| Point3::new(p.x, p.y, bottom)));
    // Top 0-1-2-3 counter-clockwise seen from above, bottom 4-5-6-7, sides outward.
    let triangles = vec![
        [0, 1, 2],
        [0, 2, 3],
        [4, 6, 5],
        [4, 7, 6],
        [0, 4, 5],
        [0, 5, 1],
        [1, 5, 6],
        [1, 6, 2],
        [2, 6, 7],
        [2, 7, 3],
        [3, 7, 4],
        [3, 4, 0],
    ];
    Some(Mesh {
        positions,
        triangles,
    })
}

fn append(mesh: &mut Mesh, other: &Mesh) {
    let offset = mesh.positions.len() as u32;
    mesh.positions.extend_from_slice(&other.positions);
    mesh.triangles
        .extend(other.triangles.iter().map(|t| t.map(|v| v + offset)));
}

/// The moves of `roughing` lifted along their axis to `to_safe(pose)` before the first and
/// after the last, so a setup starts and ends where the tool may turn.
pub fn lifted_to(
    toolpath: &mut Toolpath,
    to_safe: impl Fn(&crate::geom::ToolPose) -> f64,
    rapid: f64,
) {
    let lift = |m: &crate::geom::Move| {
        let mut up = *m;
        up.kind = crate::geom::MoveKind::Rapid;
        up.feed = rapid;
        up.pose.tip += up.pose.axis.into_inner() * to_safe(&m.pose);
        up
    };
    if let (Some(first), Some(last)) = (toolpath.moves.first(), toolpath.moves.last()) {
        let (start, end) = (lift(first), lift(last));
        toolpath.moves.insert(0, start);
        toolpath.moves.push(end);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_frame_turns_its_axis_up_and_back() {
        let frame = SetupFrame::new(&Vector3::new(0.5, -0.3, 0.8)).unwrap();
        let up = frame.rotation() * frame.axis().into_inner();
        assert!((up - Vector3::z()).norm() < 1e-12);
        let p = Point3::new(3.0, -7.0, 11.0);
        assert!((frame.to_part(&frame.to_setup(&p)) - p).norm() < 1e-12);
        assert!(SetupFrame::new(&Vector3::new(1.0, 0.0, -0.1)).is_none());
        let straight = SetupFrame::new(&Vector3::z()).unwrap();
        assert!(straight.tilt_deg().abs() < 1e-9);
    }

    /// A flat D6 (flutes 13, shank D6 to 35, holder D21 above) tilted 60°: the flutes' bottom
    /// edge reaches 3 sin 60° below the tip and the holder's near edge at 35 cos 60° − 10.5 sin
    /// 60° = 8.4 above it, so the disc is the lowest; tilted 80°, the holder reaches lower.
    #[test]
    fn the_lowest_tip_keeps_the_whole_tool_off_the_table() {
        let tool = ToolAssembly {
            id: 7,
            name: String::new(),
            cutter: crate::tool::Cutter::Flat {
                diameter: 6.0,
                flute_length: 13.0,
            },
            neck: None,
            shank_diameter: 6.0,
            stickout: 35.0,
            holder: vec![crate::tool::Section {
                diameter: 21.0,
                top_diameter: None,
                length: 40.0,
            }],
        };
        let tilt = |deg: f64| {
            let t = deg.to_radians();
            Direction::new_normalize(Vector3::new(t.sin(), 0.0, t.cos()))
        };
        let z60 = lowest_tip_z(&tool, &tilt(60.0), 0.0, 1.0);
        assert!(
            (z60 - (1.0 + 3.0 * 60f64.to_radians().sin())).abs() < 1e-9,
            "{z60}"
        );
        let z80 = lowest_tip_z(&tool, &tilt(80.0), 0.0, 1.0);
        let (s, c) = (80f64.to_radians().sin(), 80f64.to_radians().cos());
        assert!((z80 - (1.0 + 10.5 * s - 35.0 * c)).abs() < 1e-9, "{z80}");
        assert_eq!(lowest_tip_z(&tool, &tilt(0.0), 0.0, 1.0), 1.0);
    }

    /// The prism below the table's plane: its top face lies on the plane (every top corner is
    /// at `lowest` in the part frame) and it stands below it.
    #[test]
    fn the_keep_out_prism_stands_below_the_table_plane() {
        let frame = SetupFrame::new(&Vector3::new(0.6, 0.2, 0.7)).unwrap();
        let prism = below_plane(
            &frame,
            4.0,
            (Point2::new(-10.0, -5.0), Point2::new(12.0, 8.0)),
            2.0,
        )
        .unwrap();
        for (k, p) in prism.positions.iter().enumerate() {
            let z = frame.to_part(p).z;
            if k < 4 {
                assert!((z - 4.0).abs() < 1e-9, "{z}");
            } else {
                assert!(z < 4.0, "{z}");
            }
        }
    }
}
