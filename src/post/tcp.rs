//! Tool-centre-point output: the kinematics a TCP program is written in.
//!
//! With TCP on (`G43.4`, `TRAORI`, `FUNCTION TCPM`, LinuxCNC's TCP kinematics) the control takes
//! X, Y, Z as the tool tip in the part frame and the rotary words as the axes' positions, and
//! between two blocks moves the tip on the straight line while the rotaries move linearly. So a
//! TCP program's "joints" are the tip and the machine's rotary angles, and their forward map is
//! the tip as written with the axis the rotaries give. [`ToolCentrePoint`] wraps a machine's
//! kinematics that way; linearisation on it subdivides a move only as far as the axis's joint
//! interpolation needs, and its limit check converts to the machine's own axes, so the linear
//! travel is checked where the machine really moves.

use nalgebra::{Point3, Vector3};

use super::kinematics::{Joints, KinematicsError, MachineKinematics, RotaryAxis};
use crate::geom::ToolPose;

/// A machine seen through tool-centre-point control.
#[derive(Clone, Copy, Debug)]
pub struct ToolCentrePoint<'a, K: ?Sized>(pub &'a K);

impl<K: MachineKinematics + ?Sized> ToolCentrePoint<'_, K> {
    fn with_tip(tip: &Point3<f64>, j: &Joints) -> Joints {
        Joints {
            x: tip.x,
            y: tip.y,
            z: tip.z,
            a: j.a,
            c: j.c,
        }
    }

    /// The machine's own joints behind TCP joints `j`.
    pub fn machine_joints(&self, j: &Joints) -> Joints {
        self.0.joints_for_tip(&Point3::new(j.x, j.y, j.z), j.a, j.c)
    }
}

impl<K: MachineKinematics + ?Sized> MachineKinematics for ToolCentrePoint<'_, K> {
    fn inverse(
        &self,
        pose: &ToolPose,
        previous: Option<&Joints>,
    ) -> Result<Joints, KinematicsError> {
        let j = self.0.inverse(pose, previous)?;
        Ok(Self::with_tip(&pose.tip, &j))
    }

    fn forward(&self, j: &Joints) -> ToolPose {
        // The axis depends on the rotaries alone.
        let axis = self.0.forward(j).axis;
        ToolPose {
            tip: Point3::from(Vector3::new(j.x, j.y, j.z)),
            axis,
        }
    }

    fn inverse_relaxed(
        &self,
        pose: &ToolPose,
        preferred: &Joints,
        max_axis_error_deg: f64,
    ) -> Result<Joints, KinematicsError> {
        let j = self
            .0
            .inverse_relaxed(pose, preferred, max_axis_error_deg)?;
        Ok(Self::with_tip(&pose.tip, &j))
    }

    fn inverse_all(
        &self,
        pose: &ToolPose,
        previous: Option<&Joints>,
    ) -> Result<Vec<Joints>, KinematicsError> {
        Ok(self
            .0
            .inverse_all(pose, previous)?
            .iter()
            .map(|j| Self::with_tip(&pose.tip, j))
            .collect())
    }

    fn check_limits(&self, j: &Joints) -> Result<(), KinematicsError> {
        if !j.is_finite() {
            return Err(KinematicsError::NonFinite);
        }
        self.0.check_limits(&self.machine_joints(j))
    }

    fn rotary_axes(&self) -> Vec<RotaryAxis> {
        self.0.rotary_axes()
    }

    fn rotary_limits(&self) -> Vec<Option<(f64, f64)>> {
        self.0.rotary_limits()
    }

    fn description(&self) -> String {
        format!("{} (tool centre point)", self.0.description())
    }

    fn work_offset(&self) -> &str {
        "origin at the part origin (the control's TCP kinematics places the rotary axes)"
    }

    fn joints_for_tip(&self, tip: &Point3<f64>, first: f64, second: f64) -> Joints {
        Joints {
            x: tip.x,
            y: tip.y,
            z: tip.z,
            a: first,
            c: second,
        }
    }

    fn has_head_axes(&self) -> bool {
        self.0.has_head_axes()
    }
}
