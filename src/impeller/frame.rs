//! Cylindrical coordinates about an impeller's axis: radius, angle and height, and the
//! turns about the axis that map one passage onto the next.

use nalgebra::{Rotation3, Unit};

use crate::geom::{Point3, Vector3};

/// A frame about the axis: radial, tangential and axial components.
#[derive(Clone, Debug, PartialEq)]
pub struct AxisFrame {
    pub centre: Point3,
    /// Unit.
    pub axis: Vector3,
    /// The first radial direction (angle 0) and the second (angle 90°).
    pub u: Vector3,
    pub v: Vector3,
}

impl AxisFrame {
    pub fn new(centre: Point3, axis: &Vector3) -> AxisFrame {
        let axis = axis.normalize();
        let helper = if axis.x.abs() < 0.9 {
            Vector3::x()
        } else {
            Vector3::y()
        };
        let u = (helper - axis * axis.dot(&helper)).normalize();
        let v = axis.cross(&u);
        AxisFrame { centre, axis, u, v }
    }

    /// Radius, angle (radians) and height of `p`.
    pub fn cylindrical(&self, p: &Point3) -> (f64, f64, f64) {
        let d = p - self.centre;
        let (x, y) = (d.dot(&self.u), d.dot(&self.v));
        (x.hypot(y), y.atan2(x), d.dot(&self.axis))
    }

    /// The unit tangential direction at `p` (zero on the axis).
    pub fn tangent(&self, p: &Point3) -> Vector3 {
        let d = p - self.centre;
        let radial = d - self.axis * d.dot(&self.axis);
        self.axis
            .cross(&radial)
            .try_normalize(1e-12)
            .unwrap_or_else(Vector3::zeros)
    }

    pub fn turn(&self, angle: f64) -> Rotation3<f64> {
        Rotation3::from_axis_angle(&Unit::new_unchecked(self.axis), angle)
    }

    pub fn turned(&self, p: &Point3, rotation: &Rotation3<f64>) -> Point3 {
        self.centre + rotation * (p - self.centre)
    }

    /// The point at `radius`, `angle` (radians) and `height`.
    pub fn point(&self, radius: f64, angle: f64, height: f64) -> Point3 {
        self.centre + self.axis * height + (self.u * angle.cos() + self.v * angle.sin()) * radius
    }

    /// The unit radial direction at `angle`.
    pub fn radial(&self, angle: f64) -> Vector3 {
        self.u * angle.cos() + self.v * angle.sin()
    }
}
