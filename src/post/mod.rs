//! Post-processing (DESIGN §3.8): machine kinematics, linearisation and output.
//!
//! ```text
//! Toolpath (part-frame poses) ──► linearise (inverse kinematics, C continuity, subdivision)
//!      │                               │
//!      │                               ▼  Vec<(Move, Joints)>
//!      │                        emit ──► ProgramSink ──► GcodeWriter (G-code text)
//!      └──► write_cl_csv (CL data, original moves)       estimate_time (seconds per kind)
//! ```
//!
//! * [`kinematics`]: the [`MachineKinematics`] trait and the table-table A/C machine
//!   [`TableTableAC`]; the convention `m = R_x(a) · R_z(c) · (p + o)`,
//!   `k = (sin a · sin c, sin a · cos c, cos a)` is documented there.
//! * [`linearise`](mod@linearise): inserts part-frame points until the controller's joint-space
//!   interpolation stays within the tip and axis tolerances.
//! * [`chain`]: the other 5-axis kinds (table-table B/C, head-table, head-head, offset axes) as
//!   two rotary axes on the table or head side, from the machine files of [`machine_file`];
//!   [`tcp`]: tool-centre-point output as kinematics.
//! * [`gcode`]: the [`GcodeWriter`] sink (LinuxCNC, Fanuc, Siemens; joint or TCP output; feed
//!   per minute or inverse time, [`dialect`]); [`heidenhain`]: conversational; [`cl`]: CL CSV;
//!   [`apt`]: APT CL data; [`estimate`]: time estimate. `docs/machines.md` has the pictures.
#![warn(missing_docs)]

pub mod apt;
pub mod chain;
pub mod cl;
pub mod contour;
pub mod dialect;
pub mod estimate;
mod format;
pub mod gcode;
pub mod heidenhain;
pub mod kinematics;
pub mod linearise;
pub mod machine;
pub mod machine_file;
pub mod planar;
pub mod tcp;

#[cfg(test)]
mod tests;

use serde::{Deserialize, Serialize};

pub use apt::{AptTool, write_apt};
pub use chain::{AxisSide, RotaryChain, RotaryJoint};
pub use cl::{CL_CSV_HEADER, ClError, read_cl_csv, write_cl_csv};
pub use contour::{BlockRole, ContourPostError, ContourProgram, PlanarParams, ProgramStats};
pub use dialect::{Dialect, FeedMode, OutputMode};
pub use estimate::{
    TimeEstimate, TimeModel, estimate_blocks, estimate_time, estimate_time_posted,
    inverse_time_minutes,
};
pub use gcode::{GcodeOptions, GcodeWriter};
pub use heidenhain::HeidenhainWriter;
pub use kinematics::{
    Joints, KinematicsError, KinematicsKind, MachineKinematics, RotaryAxis, TableTableAC, ThreeAxis,
};
pub use linearise::{
    LineariseError, LineariseOptions, Splice, UnwindHook, Unwound, linearise, linearise_opt,
    linearise_unwinding,
};
pub use machine::Machine;
pub use machine_file::{MachineDefinition, MachineFileError};
pub use planar::{PlanarBlock, PlanarError, PlanarProgram};
pub use tcp::ToolCentrePoint;

use crate::geom::{Move, Toolpath};

/// A circular block in the machine's XY plane (G17): the centre in machine coordinates and the
/// sense seen from +Z. It starts where the previous block ended and ends at the block's joints.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ArcXY {
    /// Centre (machine X, Y), mm.
    pub center: [f64; 2],
    /// Counter-clockwise seen from +Z (`G3`); else clockwise (`G2`).
    pub ccw: bool,
}

/// What goes at the top of a program.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ProgramHeader {
    /// Program name (comment).
    pub program_name: String,
    /// Part name (comment).
    pub part_name: String,
    /// Tool description, one comment line each.
    pub tool_description: Vec<String>,
    /// Tool number: `T` word and `H` length-offset register.
    pub tool_number: u32,
    /// Spindle speed (rev/min), clockwise; 0 leaves the spindle alone.
    pub spindle_rpm: u32,
    /// Flood coolant on (M8) during the program.
    pub coolant: bool,
    /// Free comments, one line each.
    pub comments: Vec<String>,
    /// At a tool change, the new tool's control point (mm up its axis from the tip: a ball's
    /// centre), where its inverse-time feeds are timed; `None` keeps the writer's.
    pub control_point_mm: Option<f64>,
}

/// Receives a posted program: one `begin`, one `motion` per block, one `end`. Implemented by
/// output formats ([`GcodeWriter`]; previews and other dialects can follow).
pub trait ProgramSink {
    /// Starts the program.
    fn begin(&mut self, header: &ProgramHeader);
    /// One block: the move (part-frame pose, kind, feed) and the joints that realise it.
    fn motion(&mut self, m: &Move, j: &Joints);
    /// One circular block in the machine's XY plane, from the previous block's end to `end`
    /// (planar programs: [`planar`]).
    fn arc(&mut self, m: &Move, end: &Joints, arc: &ArcXY);
    /// Changes to the tool of `header` (its number, description and spindle speed) between two
    /// motions: the next motion starts as a program's first does, length compensation and Z
    /// first. The tool is on its safe height when this is called.
    fn tool_change(&mut self, header: &ProgramHeader);
    /// Ends the program.
    fn end(&mut self);

    /// The program text, once ended.
    fn finish(self: Box<Self>) -> String;
}

/// Feeds a linearised program through a sink.
pub fn emit<S: ProgramSink + ?Sized>(
    program: &[(Move, Joints)],
    header: &ProgramHeader,
    sink: &mut S,
) {
    sink.begin(header);
    for (m, j) in program {
        sink.motion(m, j);
    }
    sink.end();
}

/// Convenience: linearise `toolpath` on `kin` and write G-code.
pub fn post_gcode<K: MachineKinematics + ?Sized>(
    kin: &K,
    toolpath: &Toolpath,
    header: &ProgramHeader,
    lin: &LineariseOptions,
    gcode: &GcodeOptions,
) -> Result<String, LineariseError> {
    let program = linearise_opt(kin, toolpath, lin)?;
    let mut w = GcodeWriter::new(kin, gcode.clone());
    emit(&program, header, &mut w);
    Ok(w.into_string())
}
