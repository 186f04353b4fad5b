//! `paths.glb`: the part and the toolpath for any glTF viewer. Cut moves green, approach and
//! retract orange, rapids red, and every few millimetres of cutting a short blue line along the
//! tool axis.

use crate::error::{Error, Result};
use crate::geom::Point3;
use crate::geom::{MoveKind, Toolpath};
use crate::mesh::Mesh;
use crate::mesh::io::GlbBuilder;

const PART: [f32; 4] = [0.72, 0.74, 0.78, 1.0];
const CUT: [f32; 4] = [0.1, 0.75, 0.2, 1.0];
const LINK: [f32; 4] = [1.0, 0.55, 0.0, 1.0];
const RAPID: [f32; 4] = [0.9, 0.1, 0.1, 1.0];
const AXIS: [f32; 4] = [0.15, 0.35, 1.0, 1.0];

/// Builds the preview; `axis_spacing` is the cut length between drawn axes, `axis_length` their
/// length (mm).
pub fn preview(
    part: &Mesh,
    path: &Toolpath,
    axis_spacing: f64,
    axis_length: f64,
) -> Result<Vec<u8>> {
    let mut cut = Vec::new();
    let mut link = Vec::new();
    let mut rapid = Vec::new();
    let mut axes = Vec::new();
    let mut since_axis = f64::INFINITY;
    for w in path.moves.windows(2) {
        let (a, b) = (w[0].pose, w[1].pose);
        let segment: [Point3; 2] = [a.tip, b.tip];
        match w[1].kind {
            MoveKind::Cut => {
                cut.push(segment);
                since_axis += (b.tip - a.tip).norm();
                if since_axis >= axis_spacing {
                    axes.push([b.tip, b.tip + b.axis.into_inner() * axis_length]);
                    since_axis = 0.0;
                }
            }
            MoveKind::Approach | MoveKind::Retract => link.push(segment),
            MoveKind::Rapid => rapid.push(segment),
        }
    }
    let glb = |error| Error::Glb {
        file: "paths.glb".into(),
        error,
    };
    let mut b = GlbBuilder::new();
    b.add_triangles("part", part, PART, None).map_err(glb)?;
    b.add_lines("cut", &cut, CUT).map_err(glb)?;
    b.add_lines("approach_retract", &link, LINK).map_err(glb)?;
    b.add_lines("rapid", &rapid, RAPID).map_err(glb)?;
    b.add_lines("tool_axes", &axes, AXIS).map_err(glb)?;
    Ok(b.build())
}
