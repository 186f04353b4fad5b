//! What a control understands: its language ([`Dialect`]), whether programs drive the joints or
//! the tool tip ([`OutputMode`]), and how feed is given ([`FeedMode`]).

use serde::{Deserialize, Serialize};

/// The control's language.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Dialect {
    /// LinuxCNC's RS274/NGC: ISO G-code, `( )` comments. Tool-centre-point motion is a
    /// kinematics mode of the machine configuration (e.g. `xyzac-trt-kins` switched to TCP),
    /// not a G-code, so a TCP program only says so in its header.
    #[default]
    Linuxcnc,
    /// Fanuc ISO G-code: as LinuxCNC, with `G43.4 H…` for tool-centre-point control.
    Fanuc,
    /// Siemens SINUMERIK 840D: ISO G-code with `;` comments, `TRAORI` / `TRAFOOF` for
    /// tool-centre-point control, `G93` for inverse time.
    Siemens,
    /// Heidenhain TNC conversational (Klartext): numbered `L` blocks, `FUNCTION TCPM F TCP AXIS
    /// POS PATHCTRL AXIS` for tool-centre-point control. It has no inverse-time feed.
    Heidenhain,
}

impl Dialect {
    /// The name machine files use.
    pub fn name(self) -> &'static str {
        match self {
            Dialect::Linuxcnc => "linuxcnc",
            Dialect::Fanuc => "fanuc",
            Dialect::Siemens => "siemens",
            Dialect::Heidenhain => "heidenhain",
        }
    }

    /// The program file's usual extension.
    pub fn extension(self) -> &'static str {
        match self {
            Dialect::Linuxcnc => "ngc",
            Dialect::Fanuc => "nc",
            Dialect::Siemens => "mpf",
            Dialect::Heidenhain => "h",
        }
    }
}

/// What the linear and rotary words of a program mean.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum OutputMode {
    /// Joint space: X, Y, Z, and the rotaries are the machine's axes (the post has solved the
    /// kinematics and subdivided moves until the control's linear joint interpolation stays
    /// within tolerance).
    #[default]
    Joint,
    /// Tool centre point: X, Y, Z are the tool tip in the part frame and the rotaries set the
    /// orientation; the control keeps the tip on the straight line while the rotaries move. Moves
    /// are subdivided only as far as the axis interpolation needs.
    Tcp,
}

impl OutputMode {
    /// The name machine files and `--output` use.
    pub fn name(self) -> &'static str {
        match self {
            OutputMode::Joint => "joint",
            OutputMode::Tcp => "tcp",
        }
    }
}

/// How feed blocks give their speed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FeedMode {
    /// `G94`: mm/min, which a control applies to the linear axes' motion (wrong at the tip when
    /// the rotaries move in joint mode).
    #[default]
    PerMinute,
    /// `G93`: each feed block carries `F` = 1 / (its duration in minutes), computed from the
    /// tool's motion relative to the part, so the feed at the part is what was planned whatever
    /// the rotaries do.
    InverseTime,
}

impl FeedMode {
    /// The name machine files and `--feed` use.
    pub fn name(self) -> &'static str {
        match self {
            FeedMode::PerMinute => "per-minute",
            FeedMode::InverseTime => "inverse-time",
        }
    }
}
