//! The machine a program is posted for, as a job describes it: one variant per
//! [`KinematicsKind`], each holding its typed description (limits, pivot offset), and the
//! [`MachineKinematics`] trait dispatched to it. Planners hold a `Machine` and stay unaware of
//! which kind it is; a new kind is a new variant here.

use super::chain::RotaryChain;
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
    /// Any of the 5-axis kinds as two rotary axes on the table or head side (a machine file's
    /// machine).
    Chain(Box<RotaryChain>),
}

impl Machine {
    /// The kind, as a job file names it.
    pub fn kind(&self) -> KinematicsKind {
        match self {
            Machine::TableTableAc(_) => KinematicsKind::TableTableAc,
            Machine::ThreeAxis(_) => KinematicsKind::ThreeAxis,
            Machine::Chain(m) => m.kind,
        }
    }

    /// Checks the description (finite, ordered limits, …).
    pub fn validate(&self) -> Result<(), KinematicsError> {
        match self {
            Machine::TableTableAc(m) => m.validate(),
            Machine::ThreeAxis(_) => Ok(()),
            Machine::Chain(m) => m.validate(),
        }
    }

    /// The same machine with a tool of gauge length `gauge_mm` (changes only machines with head
    /// axes, whose joint output carries the tool's length).
    pub fn with_gauge_length(&self, gauge_mm: f64) -> Machine {
        match self {
            Machine::Chain(m) => {
                Machine::Chain(Box::new((**m).clone().with_gauge_length(gauge_mm)))
            }
            other => other.clone(),
        }
    }

    /// Head reference point to tool tip, mm (0 without head axes).
    pub fn head_length(&self) -> f64 {
        match self {
            Machine::Chain(m) => m.head_length,
            _ => 0.0,
        }
    }

    fn kinematics(&self) -> &dyn MachineKinematics {
        match self {
            Machine::TableTableAc(m) => m,
            Machine::ThreeAxis(m) => m,
            Machine::Chain(m) => m.as_ref(),
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

    fn reaches_axis(&self, tip: &nalgebra::Point3<f64>, axis: &nalgebra::Vector3<f64>) -> bool {
        self.kinematics().reaches_axis(tip, axis)
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

    fn inverse_all(
        &self,
        pose: &ToolPose,
        previous: Option<&Joints>,
    ) -> Result<Vec<Joints>, KinematicsError> {
        self.kinematics().inverse_all(pose, previous)
    }

    fn rotary_axes(&self) -> Vec<RotaryAxis> {
        self.kinematics().rotary_axes()
    }

    fn rotary_limits(&self) -> Vec<Option<(f64, f64)>> {
        self.kinematics().rotary_limits()
    }

    fn joints_for_tip(&self, tip: &nalgebra::Point3<f64>, first: f64, second: f64) -> Joints {
        self.kinematics().joints_for_tip(tip, first, second)
    }

    fn description(&self) -> String {
        self.kinematics().description()
    }

    fn has_head_axes(&self) -> bool {
        self.kinematics().has_head_axes()
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
