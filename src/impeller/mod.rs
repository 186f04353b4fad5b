//! Impellers and blisks (issue 21): the typed geometry the impeller strategies plan from.
//!
//! [`recognise()`] finds the rotation axis, the order of rotational symmetry (checked on the
//! surface), the hub and the blades (main and splitters) in a closed mesh, or says why the
//! mesh is not an impeller; [`impeller_glb`] pictures what it found.

pub mod blade;
pub mod edges;
pub mod frame;
pub mod hub_wall;
pub mod passage;
pub mod picture;
pub mod recognise;
pub mod root;
pub mod swarf;

pub use blade::{
    BladeLoops, BladeTip, blade_loop_at, blade_loops, blade_section_at, blade_tip_passes,
};
pub use edges::{BladeEdges, EdgeSide, blade_edges};
pub use frame::AxisFrame;
pub use passage::{FlowLine, HubPassage, PassageOptions, stepover_on_convex};
pub use picture::impeller_glb;
pub use root::{RootCorner, corner_ball};
pub use swarf::{NotSwarf, Ruling, SwarfOptions, SwarfPlan, SwarfRun, swarf_runs};

pub use recognise::{
    Impeller, NotAnImpeller, Piece, PieceKind, RecogniseOptions, Region, recognise,
};
