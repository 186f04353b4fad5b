//! Tools: cutters (ball, flat, bull-nose, tapered ball), assemblies (neck, shank, holder
//! sections) and tool libraries, as plain geometry along the tool axis. Heights are measured
//! from the tool tip toward the spindle, in millimetres.
//!
//! * `cutter`: the cutting end's profile and where its tip sits when it touches a point;
//! * `assembly`: the cutter in its holder, as bodies of revolution for `collide`;
//! * `library`: a shop's tools in a TOML file (`data/tools.toml` is an example).
//!
//! This module knows nothing about the part or about collision queries; `collide` turns these
//! bodies into shapes.

mod assembly;
mod cutter;
mod library;

pub use assembly::{Body, BodyRole, Neck, Section, ToolAssembly};
pub use cutter::{Cutter, parse_cutter};
pub use library::ToolLibrary;

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ToolError {
    #[error(
        "tool spec `{0}`: expected `ball:D`, `flat:D`, `bull:D:R` or `taper:D:DEG` (mm; e.g. ball:6)"
    )]
    BadSpec(String),
    #[error("tool: {0}")]
    Invalid(String),
    /// A tool library file cannot be read or breaks a rule.
    #[error("{file}: {reason}")]
    Library { file: String, reason: String },
}
