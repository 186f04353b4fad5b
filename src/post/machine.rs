//! The machine a program is posted for, as a job describes it: one variant per
//! [`KinematicsKind`], each holding its typed description (limits, pivot offset), and the
//! [`MachineKinematics`] trait dispatched to it. Planners hold a `Machine` and stay unaware of
//! which kind it is; a new kind is a new variant here.

use super::kinematics::{
    Joints, KinematicsError, KinematicsKind, MachineKinematics, RotaryAxis, TableTableAC, ThreeAxis,
};
use crate::geom::ToolPose;

/// A machine the post can drive.
#[derive(Clone, Debug, PartialEq)]
pub enum Machine {
    /// Table-table A/C 5-axis machine.
    TableTableAc(TableTableAC),
    /// 3-axis machine, tool along +Z.
    ThreeAxis(ThreeAxis),
}

impl Machine {
    /// The kind, as a job file names it.
    pub fn kind(&self) -> KinematicsKind {
        match self {
            Machine::TableTableAc(_) => KinematicsKind::TableTableAc,
            Machine::ThreeAxis(_) => KinematicsKind::ThreeAxis,
        }
    }

    /// Checks the description (finite, ordered limits, …).
    pub fn validate(&self) -> Result<(), KinematicsError> {
        match self {
            Machine::TableTableAc(m) => m.validate(),
            Machine::ThreeAxis(_) => Ok(()),
        }
    }

    fn kinematics(&self) -> &dyn MachineKinematics {
        match self {
            Machine::TableTableAc(m) => m,
            Machine::ThreeAxis(m) => m,
        }
    }
}

impl MachineKinematics for Machine {
    fn inverse(
        &self,
        pose: &ToolPose,
        previous: Option<&Joints>,
    ) -> Result<Joints, KinematicsError> {
        self.kinematics().inverse(pose, previous)
    }

    fn forward(&self, joints: &Joints) -> ToolPose {
        self.kinematics().forward(joints)
    }

    fn inverse_relaxed(
        &self,
        pose: &ToolPose,
        preferred: &Joints,
        max_axis_error_deg: f64,
    ) -> Result<Joints, KinematicsError> {
        self.kinematics()
            .inverse_relaxed(pose, preferred, max_axis_error_deg)
    }

    fn check_limits(&self, joints: &Joints) -> Result<(), KinematicsError> {
        self.kinematics().check_limits(joints)
    }

    fn rotary_axes(&self) -> &[RotaryAxis] {
        self.kinematics().rotary_axes()
    }

    fn description(&self) -> String {
        self.kinematics().description()
    }

    fn work_offset(&self) -> &str {
        self.kinematics().work_offset()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::post::tests::{dir, pose};

    /// The enum answers as the machine it holds, including the relaxed inverse that only the
    /// table-table machine overrides.
    #[test]
    fn a_machine_dispatches_to_its_kind() {
        let ac = TableTableAC::new(nalgebra::Vector3::new(1.0, 2.0, 3.0));
        let machine = Machine::TableTableAc(ac.clone());
        assert_eq!(machine.kind(), KinematicsKind::TableTableAc);
        let near_pole = pose([5.0, 6.0, 7.0], dir(0.01, 40.0));
        let preferred = Joints {
            c: 123.0,
            ..Joints::default()
        };
        assert_eq!(
            machine.inverse_relaxed(&near_pole, &preferred, 0.05),
            ac.inverse_relaxed(&near_pole, &preferred, 0.05)
        );
        let p = pose([5.0, 6.0, 7.0], dir(30.0, 40.0));
        let j = machine.inverse(&p, None).unwrap();
        assert_eq!(j, ac.inverse(&p, None).unwrap());
        assert_eq!(machine.forward(&j), ac.forward(&j));
        assert_eq!(machine.rotary_axes(), [RotaryAxis::A, RotaryAxis::C]);
        let three = Machine::ThreeAxis(ThreeAxis);
        assert_eq!(three.kind(), KinematicsKind::ThreeAxis);
        assert!(three.rotary_axes().is_empty());
        assert!(three.inverse(&p, None).is_err());
        let bad = Machine::TableTableAc(ac.with_a_limits(10.0, -10.0));
        assert!(bad.validate().is_err());
    }
}
