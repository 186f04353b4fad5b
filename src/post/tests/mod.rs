//! Tests of the post-processor: kinematics, linearisation, G-code, CL data, time estimate.

mod chain;
mod cl;
mod estimate;
mod gcode;
mod kinematics;
mod linearise;
mod machines;
mod planar;

use nalgebra::{Point3, Rotation3, Unit, Vector3};

use crate::geom::{Move, MoveKind, ToolPose, Toolpath};
use crate::post::Joints;

/// A pose from a tip and a (not necessarily unit) axis.
pub fn pose(tip: [f64; 3], axis: [f64; 3]) -> ToolPose {
    ToolPose {
        tip: Point3::new(tip[0], tip[1], tip[2]),
        axis: Unit::new_normalize(Vector3::new(axis[0], axis[1], axis[2])),
    }
}

/// Unit axis with the given tilt from +Z and azimuth measured from +Y toward +X (degrees),
/// built from spherical coordinates (independent of the kinematics code).
pub fn dir(tilt_deg: f64, azimuth_deg: f64) -> [f64; 3] {
    let (st, ct) = tilt_deg.to_radians().sin_cos();
    let (sa, ca) = azimuth_deg.to_radians().sin_cos();
    [st * sa, st * ca, ct]
}

/// Independent forward kinematics of the A/C table-table machine with nalgebra rotations:
/// machine = R_x(a) R_z(c) (part + o).
pub fn forward_ref(o: &Vector3<f64>, j: &Joints) -> (Point3<f64>, Vector3<f64>) {
    let r = Rotation3::from_axis_angle(&Vector3::x_axis(), j.a.to_radians())
        * Rotation3::from_axis_angle(&Vector3::z_axis(), j.c.to_radians());
    let tip = r.inverse() * Vector3::new(j.x, j.y, j.z) - o;
    let axis = r.inverse() * Vector3::z();
    (Point3::from(tip), axis)
}

/// Angle between two vectors, radians.
pub fn angle(u: &Vector3<f64>, v: &Vector3<f64>) -> f64 {
    u.cross(v).norm().atan2(u.dot(v))
}

/// Independent slerp for tests.
pub fn slerp_ref(u: &Vector3<f64>, v: &Vector3<f64>, t: f64) -> Vector3<f64> {
    let th = angle(u, v);
    if th < 1e-15 {
        return *u;
    }
    (u * ((1.0 - t) * th).sin() + v * (t * th).sin()) / th.sin()
}

/// A toolpath from (kind, feed, tip, axis) rows.
pub fn toolpath(rows: &[(MoveKind, f64, [f64; 3], [f64; 3])]) -> Toolpath {
    Toolpath {
        tool_id: 7,
        moves: rows
            .iter()
            .map(|&(kind, feed, tip, axis)| Move {
                pose: pose(tip, axis),
                kind,
                feed,
            })
            .collect(),
    }
}
