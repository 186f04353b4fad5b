//! Machine definitions: the TOML files of `data/machines/` (shipped inside the binary, so
//! `--machine NAME` works from any directory) or a user's own file (`--machine FILE`).
//!
//! ```toml
//! name = "Trunnion A/C, LinuxCNC"
//! kind = "table-table-ac"          # table-table-ac | table-table-bc | head-table-bc
//!                                  # | head-table-ac | head-head
//! dialect = "linuxcnc"             # linuxcnc | fanuc | siemens | heidenhain
//! output = "joint"                 # joint | tcp   (--output overrides)
//! feed = "inverse-time"            # per-minute | inverse-time   (--feed overrides)
//! pivot_length = 0                 # head machines: head pivot to spindle gauge line, mm
//! rapid_feed = 15000               # mm/min
//! singular_tolerance = 0.05        # half-angle of the cone about the free axis, degrees
//!
//! [[axis]]                         # the first rotary axis: cradle / head / ram-side head
//! letter = "A"
//! side = "table"                   # table | head
//! direction = [1, 0, 0]            # positive rotation right-handed about it, at home
//! point = [0, 0, 0]                # a point on it, mm (table: program frame; head: from
//!                                  # the head's reference point)
//! limits = [-120, 120]             # degrees; leave out for a continuous axis
//! max_speed = 5400                 # degrees/min
//!
//! [[axis]]                         # the second: round table / spindle-side head
//! letter = "C"
//! side = "table"
//! direction = [0, 0, 1]
//! point = [0, 0, 0]
//! max_speed = 7200
//!
//! [travel]                         # linear travel in program coordinates, mm (optional)
//! x = [-300, 300]
//! y = [-250, 250]
//! z = [-200, 400]
//! ```
//!
//! The frames and the kinematics are [`super::chain`]'s; `docs/machines.md` draws each kind.

use std::path::Path;

use nalgebra::{Unit, Vector3};
use serde::Deserialize;

use super::chain::{AxisSide, RotaryChain, RotaryJoint};
use super::dialect::{Dialect, FeedMode, OutputMode};
use super::kinematics::{KinematicsKind, RotaryAxis};

/// The machines shipped in `data/machines/`, by name.
pub const SHIPPED: [(&str, &str); 5] = [
    (
        "trunnion-ac",
        include_str!("../../data/machines/trunnion-ac.toml"),
    ),
    (
        "trunnion-bc",
        include_str!("../../data/machines/trunnion-bc.toml"),
    ),
    (
        "head-table-bc",
        include_str!("../../data/machines/head-table-bc.toml"),
    ),
    (
        "head-table-ac",
        include_str!("../../data/machines/head-table-ac.toml"),
    ),
    (
        "head-head",
        include_str!("../../data/machines/head-head.toml"),
    ),
];

/// `true` when `name` is a shipped machine's.
pub fn is_shipped(name: &str) -> bool {
    SHIPPED.iter().any(|(n, _)| *n == name)
}

/// A machine as a definition file describes it.
#[derive(Clone, Debug, PartialEq)]
pub struct MachineDefinition {
    /// The file's `name`.
    pub name: String,
    /// The kinematics, with the part origin at the table frame's origin and no tool (the job
    /// places the part and mounts its tools: [`RotaryChain::with_part_origin`],
    /// [`RotaryChain::with_tool`]).
    pub chain: RotaryChain,
    /// Head pivot to spindle gauge line, mm (0 without head axes).
    pub pivot_length: f64,
    /// The control's language.
    pub dialect: Dialect,
    /// Joint-space or tool-centre-point output.
    pub output: OutputMode,
    /// Feed per minute or inverse time.
    pub feed: FeedMode,
    /// Rapid traverse, mm/min.
    pub rapid_feed: f64,
    /// The slower rotary axis's top speed, degrees/min.
    pub max_rotary_speed: f64,
}

/// What is wrong with a machine definition.
#[derive(Debug, thiserror::Error)]
#[error("machine {source_name}: {reason}")]
pub struct MachineFileError {
    /// The file, or the shipped name.
    pub source_name: String,
    /// What is wrong.
    pub reason: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileMachine {
    name: String,
    kind: KinematicsKind,
    #[serde(default)]
    dialect: Dialect,
    #[serde(default)]
    output: OutputMode,
    #[serde(default)]
    feed: FeedMode,
    #[serde(default)]
    pivot_length: f64,
    #[serde(default = "default_rapid")]
    rapid_feed: f64,
    #[serde(default = "default_singular")]
    singular_tolerance: f64,
    axis: Vec<FileAxis>,
    travel: Option<FileTravel>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileAxis {
    letter: RotaryAxis,
    side: AxisSide,
    direction: [f64; 3],
    #[serde(default)]
    point: [f64; 3],
    limits: Option<[f64; 2]>,
    #[serde(default = "default_rotary_speed")]
    max_speed: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileTravel {
    x: [f64; 2],
    y: [f64; 2],
    z: [f64; 2],
}

fn default_rapid() -> f64 {
    15000.0
}
fn default_singular() -> f64 {
    0.05
}
fn default_rotary_speed() -> f64 {
    7200.0
}

impl MachineDefinition {
    /// A shipped machine by name, or a definition file.
    pub fn load(name_or_file: &str) -> Result<MachineDefinition, MachineFileError> {
        if let Some((name, text)) = SHIPPED.iter().find(|(n, _)| *n == name_or_file) {
            return Self::parse(text, name);
        }
        let path = Path::new(name_or_file);
        if !path.exists() {
            return Err(MachineFileError {
                source_name: name_or_file.to_string(),
                reason: format!(
                    "neither a shipped machine ({}) nor a file",
                    SHIPPED.map(|(n, _)| n).join(", ")
                ),
            });
        }
        let text = std::fs::read_to_string(path).map_err(|e| MachineFileError {
            source_name: name_or_file.to_string(),
            reason: format!("cannot be read: {e}"),
        })?;
        Self::parse(&text, name_or_file)
    }

    /// Reads a definition from TOML text; `source_name` names it in errors.
    pub fn parse(text: &str, source_name: &str) -> Result<MachineDefinition, MachineFileError> {
        let fail = |reason: String| MachineFileError {
            source_name: source_name.to_string(),
            reason,
        };
        let file: FileMachine =
            toml::from_str(text).map_err(|e| fail(e.to_string().trim_end().to_string()))?;
        let [first, second] = <[FileAxis; 2]>::try_from(file.axis)
            .map_err(|axes| fail(format!("needs two [[axis]] tables, has {}", axes.len())))?;
        let expected: Option<[(AxisSide, RotaryAxis); 2]> = match file.kind {
            KinematicsKind::TableTableAc => Some([
                (AxisSide::Table, RotaryAxis::A),
                (AxisSide::Table, RotaryAxis::C),
            ]),
            KinematicsKind::TableTableBc => Some([
                (AxisSide::Table, RotaryAxis::B),
                (AxisSide::Table, RotaryAxis::C),
            ]),
            KinematicsKind::HeadTableBc => Some([
                (AxisSide::Head, RotaryAxis::B),
                (AxisSide::Table, RotaryAxis::C),
            ]),
            KinematicsKind::HeadTableAc => Some([
                (AxisSide::Head, RotaryAxis::A),
                (AxisSide::Table, RotaryAxis::C),
            ]),
            KinematicsKind::HeadHead => None,
            KinematicsKind::ThreeAxis => {
                return Err(fail("a machine file describes a 5-axis machine".into()));
            }
        };
        let found = [(first.side, first.letter), (second.side, second.letter)];
        match expected {
            Some(e) if e != found => {
                return Err(fail(format!(
                    "kind {} has its axes as {}, the file lists {}",
                    file.kind.name(),
                    describe(&e),
                    describe(&found)
                )));
            }
            None if found.iter().any(|(side, _)| *side != AxisSide::Head) => {
                return Err(fail("kind head-head has both axes on the head".into()));
            }
            _ => {}
        }
        let has_head = found.iter().any(|(side, _)| *side == AxisSide::Head);
        if !(file.pivot_length.is_finite() && file.pivot_length >= 0.0) {
            return Err(fail("pivot_length must be finite and >= 0".into()));
        }
        if !has_head && file.pivot_length != 0.0 {
            return Err(fail("pivot_length is for machines with head axes".into()));
        }
        if !(file.rapid_feed.is_finite() && file.rapid_feed > 0.0) {
            return Err(fail("rapid_feed must be positive".into()));
        }
        let joint = |a: &FileAxis| -> Result<RotaryJoint, MachineFileError> {
            let d = Vector3::from(a.direction);
            if !(d.iter().all(|v| v.is_finite()) && d.norm() > 1e-9) {
                return Err(fail(format!(
                    "axis {}: direction must be a non-zero vector",
                    a.letter
                )));
            }
            if !(a.max_speed.is_finite() && a.max_speed > 0.0) {
                return Err(fail(format!(
                    "axis {}: max_speed must be positive",
                    a.letter
                )));
            }
            Ok(RotaryJoint {
                letter: a.letter,
                side: a.side,
                direction: Unit::new_normalize(d),
                point: Vector3::from(a.point),
                limits_deg: a.limits.map(|[lo, hi]| (lo, hi)),
            })
        };
        let chain = RotaryChain {
            kind: file.kind,
            first: joint(&first)?,
            second: joint(&second)?,
            part_origin_in_table: Vector3::zeros(),
            head_length: 0.0,
            pivot_length: 0.0,
            travel: file
                .travel
                .map(|t| [(t.x[0], t.x[1]), (t.y[0], t.y[1]), (t.z[0], t.z[1])]),
            singular_tolerance_deg: file.singular_tolerance,
            name: file.name.clone(),
        };
        chain.validate().map_err(|e| fail(e.to_string()))?;
        let definition = MachineDefinition {
            name: file.name,
            chain,
            pivot_length: file.pivot_length,
            dialect: file.dialect,
            output: file.output,
            feed: file.feed,
            rapid_feed: file.rapid_feed,
            max_rotary_speed: first.max_speed.min(second.max_speed),
        };
        definition.check_modes().map_err(fail)?;
        Ok(definition)
    }

    /// Refuses the dialect, output and feed combinations no control runs: inverse time in
    /// Heidenhain conversational (it has none), and joint output on a Heidenhain machine with head
    /// axes (`TOOL CALL` applies the tool table's length along machine Z, which a tilted head's
    /// joint program cannot carry).
    pub fn check_modes(&self) -> Result<(), String> {
        if self.dialect != Dialect::Heidenhain {
            return Ok(());
        }
        if self.feed == FeedMode::InverseTime {
            return Err(
                "Heidenhain conversational has no inverse-time feed: use feed = \
                 \"per-minute\" (in TCP output the control keeps the feed at the tool tip, \
                 FUNCTION TCPM F TCP)"
                    .into(),
            );
        }
        let head = [&self.chain.first, &self.chain.second]
            .iter()
            .any(|j| j.side == AxisSide::Head);
        if head && self.output == OutputMode::Joint {
            return Err(
                "joint output on a Heidenhain machine with head axes is not written: \
                 TOOL CALL applies the tool's length along machine Z; use output = \"tcp\" \
                 (FUNCTION TCPM)"
                    .into(),
            );
        }
        Ok(())
    }

    /// The chain with the part clamped at `part_origin_in_table` and a tool of gauge length
    /// `gauge_mm` in the spindle.
    pub fn chain_for(&self, part_origin_in_table: Vector3<f64>, gauge_mm: f64) -> RotaryChain {
        self.chain
            .clone()
            .with_part_origin(part_origin_in_table)
            .with_tool(self.pivot_length, gauge_mm)
    }
}

fn describe(axes: &[(AxisSide, RotaryAxis); 2]) -> String {
    axes.iter()
        .map(|(side, letter)| {
            let side = match side {
                AxisSide::Table => "table",
                AxisSide::Head => "head",
            };
            format!("{letter} on the {side}")
        })
        .collect::<Vec<_>>()
        .join(", then ")
}
