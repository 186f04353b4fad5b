//! wavemill plans 5-axis CNC toolpaths for impellers, blisks and turbine blades.
//!
//! The pipeline, one module per stage (DESIGN.md §2), data flowing one way:
//!
//! ```text
//! mesh ─► collide / access ─► orient ─► path ─► verify ─► post
//!   ▲                                                       │
//! sample (generated parts)              job (job file + the pipeline that wires the stages)
//!
//! stock: the in-process material (tri-dexel), removed by swept cutters
//! rough: layer roughing of the blank down to an offset shape (through the contour engine)
//! ```
//!
//! Every stage takes plain data and returns plain data; the CLI (`wavemill`) is a thin shell
//! over [`job::plan`] and friends.

#![forbid(unsafe_code)]

pub use error::{Error, Result};

pub mod access;
pub mod cad;
pub mod cli;
pub mod collide;
pub mod contour;
pub mod error;
pub mod feed;
pub mod geom;
pub mod impeller;
pub mod job;
pub mod lathe;
pub mod mesh;
pub mod multires;
pub mod offset;
pub mod orient;
pub mod path;
pub mod post;
pub mod rough;
pub mod sample;
pub mod stock;
pub mod tool;
pub mod tool_choice;
pub mod verify;
