//! Multiresolution view of a part: Loop subdivision hierarchy (DESIGN.md §3.1–3.3).
//!
//! Level j+1 of the hierarchy is the 1-to-4 split of level j ([`split()`]) with Loop's rules
//! for the positions (seed 004, §5 eq. 5.1; DESIGN.md §3.1), extended with creases, corners
//! and boundaries ([`loop_subdivide`]). The numbering contract every multires file relies on
//! (docs/multires-conventions.md):
//! * vertices `0..V_j` of level j+1 are level j's vertices ("even", same index);
//! * vertex `V_j + k` is the "odd" vertex on edge k of level j, edges `[min, max]` sorted;
//! * coarse triangle t = `[a, b, c]` becomes fine triangles `4t..4t+4`:
//!   `[a, ab, ca]`, `[ab, b, bc]`, `[ca, bc, c]`, `[ab, bc, ca]`.
//!
//! Sharp features ([`Creases`]) are listed per level; boundary edges are always sharp. A vertex
//! is smooth (no sharp edge), crease/boundary (two) or corner (one or three and more)
//! ([`VertexClass`]). [`check_split`] verifies the numbering contract between two levels.
//!
//! Files: `split.rs` (topology only: [`Split`], [`Creases`], [`VertexClass`]),
//! `subdivision.rs` (positions: [`loop_step`], [`loop_subdivide`], [`detect_creases`]),
//! `check.rs` (the hierarchy invariant checker), `simplify/` (the base mesh: topology-preserving
//! quadric edge collapse, Garland & Heckbert 1997), `wavelet.rs` (the lifting scheme: analysis and
//! synthesis, exactly invertible, per-level details and deviation bounds; DESIGN.md §3.3–3.4).
#![warn(missing_docs)]

pub mod check;
pub mod isotropic;
pub mod remesh;
pub mod simplify;
pub mod split;
pub mod subdivision;
pub mod unsplit;
pub mod wavelet;

#[cfg(test)]
pub(crate) mod test_meshes;

pub use check::check_split;
pub use isotropic::{IsotropicError, IsotropicOptions, isotropic_remesh};
pub use remesh::{Fit, FittedLevel, Hierarchy, RemeshError, RemeshOptions};
pub use simplify::{Simplified, SimplifyError, SimplifyOptions, simplify};
pub use split::{Creases, Split, VertexClass, classify_vertices, split};
pub use subdivision::{SubdivisionError, detect_creases, loop_step, loop_subdivide};
pub use unsplit::{Unsplit, subdivision_depth, unsplit};
pub use wavelet::{
    DetailStats, Deviation, LevelTopology, LevelWavelets, MultiresWavelets, WaveletError,
    WaveletHierarchy, WaveletOptions, analyse, detail_stats, synthesise,
};
