//! Leading and trailing edges (issue 21 item 1): where a main blade meets the flow coming in
//! and lets it go.
//!
//! The flow runs along the hub's meridian, inlet to outlet ([`HubPassage::along`]). Each loop
//! of constant height above the hub round the first main blade ([`super::blade_loop_at`])
//! has a most upstream and a most downstream point; they are on the leading and trailing
//! edges where the surface there faces the inlet or the outlet (its normal at least
//! [`FACING`] against or along the flow: a level above a centrifugal wheel's low outlet ends
//! where the tip cuts it, not at an edge). The edges' triangles are the blades' triangles
//! within [`EDGE_BAND`] of the meridian's length of those points (every blade turned onto the
//! first by the symmetry): the rounded nose and the start of the flanks behind it, where a
//! loop turns round the blade.

use serde::Serialize;

use crate::geom::{Point3, closest_point_on_segment};
use crate::mesh::Mesh;

use super::passage::HubPassage;
use super::recognise::{Impeller, Region};

/// The share of a unit normal along the flow that makes a loop's end an edge.
pub const FACING: f64 = 0.5;

/// How far from an edge's curve a blade's triangle belongs to the edge, as a share of the
/// meridian's length.
pub const EDGE_BAND: f64 = 0.02;

/// Levels the edge curves are sampled at, evenly up the blade's height above the hub.
const LEVELS: usize = 24;

/// Which edge a blade's triangle is on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum EdgeSide {
    Leading,
    Trailing,
}

/// The leading and trailing edges of an impeller's main blades.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BladeEdges {
    /// Area of the edges' triangles, mm², over every main blade.
    pub leading_area_mm2: f64,
    pub trailing_area_mm2: f64,
    /// The first blade's edges from hub to tip, as (height above the hub, distance along the
    /// meridian from the inlet, radius), mm.
    pub leading: Vec<[f64; 3]>,
    pub trailing: Vec<[f64; 3]>,
    /// Per triangle of the mesh: the edge it is on, if any.
    #[serde(skip)]
    pub sides: Vec<Option<EdgeSide>>,
}

/// The edges of `impeller`'s main blades (recognised in `mesh`) along `passage`'s meridian.
pub fn blade_edges(mesh: &Mesh, impeller: &Impeller, passage: &HubPassage) -> BladeEdges {
    let piece = passage.first_blade;
    let top = mesh
        .triangles
        .iter()
        .zip(&impeller.regions)
        .filter(|(_, r)| **r == Region::Blade(piece as u32))
        .flat_map(|(t, _)| t.map(|v| passage.above_hub(&mesh.positions[v as usize]).0))
        .fold(0.0, f64::max);
    let placed = |p: &Point3| {
        let (m, _) = passage.along(p);
        let (radius, _, _) = passage.frame.cylindrical(p);
        [passage.above_hub(p).0, m, radius]
    };
    let (mut leading, mut trailing) = (Vec::new(), Vec::new());
    let (mut lead_points, mut trail_points) = (Vec::new(), Vec::new());
    for k in 0..LEVELS {
        let level = (k as f64 + 0.5) / LEVELS as f64 * top;
        let Some(curve) = super::blade_loop_at(mesh, impeller, passage, piece, level) else {
            continue;
        };
        let along: Vec<(f64, f64, Point3)> = curve
            .points
            .iter()
            .map(|d| {
                let (m, downstream) = passage.along(&d.point);
                (m, d.normal.dot(&downstream), d.point)
            })
            .collect();
        let first = along.iter().min_by(|a, b| a.0.total_cmp(&b.0));
        let last = along.iter().max_by(|a, b| a.0.total_cmp(&b.0));
        if let Some(&(_, _, p)) = first.filter(|a| a.1 <= -FACING) {
            leading.push(placed(&p));
            lead_points.push(p);
        }
        if let Some(&(_, _, p)) = last.filter(|a| a.1 >= FACING) {
            trailing.push(placed(&p));
            trail_points.push(p);
        }
    }

    // Every blade's triangles turned onto the first blade, within the band of its curves.
    let band = EDGE_BAND * passage.meridian_length();
    let near = |curve: &[Point3], p: &Point3| match curve {
        [] => false,
        [only] => (only - p).norm() <= band,
        _ => curve
            .windows(2)
            .any(|w| (closest_point_on_segment(p, &w[0], &w[1]) - p).norm() <= band),
    };
    let first_angle = impeller.pieces[piece].angle_deg.to_radians();
    let mut areas = [0.0; 2];
    let sides: Vec<Option<EdgeSide>> = (0..mesh.triangles.len())
        .map(|t| {
            let Region::Blade(k) = impeller.regions[t] else {
                return None;
            };
            let [a, b, c] = mesh.corners(t);
            let apart = impeller.pieces[k as usize].angle_deg.to_radians() - first_angle;
            let turns = (apart / passage.pitch).round();
            let rotation = passage.frame.turn(-turns * passage.pitch);
            let centre = passage.frame.turned(
                &Point3::from((a.coords + b.coords + c.coords) / 3.0),
                &rotation,
            );
            let side = if near(&lead_points, &centre) {
                EdgeSide::Leading
            } else if near(&trail_points, &centre) {
                EdgeSide::Trailing
            } else {
                return None;
            };
            areas[(side == EdgeSide::Trailing) as usize] += 0.5 * (b - a).cross(&(c - a)).norm();
            Some(side)
        })
        .collect();
    BladeEdges {
        leading_area_mm2: areas[0],
        trailing_area_mm2: areas[1],
        leading,
        trailing,
        sides,
    }
}
