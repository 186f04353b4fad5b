//! Lifting-scheme wavelets on a Loop subdivision hierarchy (DESIGN.md §3.3–3.4; seed 004
//! §2.3, eqs. 2.18–2.27).
//!
//! One level of a semi-regular hierarchy is split (docs/multires-conventions.md) into *even*
//! vertices `0..V_j` (the coarse vertices) and *odd* vertices `V_j + k` (one per coarse edge
//! k). Seed 004 writes the two-channel filter bank as `V^{j+1} = P^j V^j + Q^j W^j`
//! (synthesis, eq. 2.27) and `V^j = A^j V^{j+1}`, `W^j = B^j V^{j+1}` (analysis, eqs.
//! 2.25–2.26), with `[A; B] = [P Q]^{-1}` (eq. 2.20). We never form the matrices: `[P Q]`
//! is factored into lifting steps, each trivially invertible, so analysis ∘ synthesis is the
//! identity up to rounding, on any connectivity, and costs O(V + E).
//!
//! # The lifting factorisation (synthesis)
//!
//! Coarse positions `c`, details `d_k` (3-vectors in mm, one per coarse edge):
//!
//! 1. **predict** (odd vertices): `odd_k = L_k(c) + d_k`, where `L_k` is Loop's edge rule:
//!    `(3c_a + 3c_b + c_p + c_q)/8` for an interior edge `{a,b}` with opposite vertices
//!    `p, q`; `(c_a + c_b)/2` for a crease or boundary edge.
//! 2. **update** (even vertices): `even_i = α_i c_i + γ_i Σ_{k ∈ K_i} odd_k`, with
//!    * smooth vertex of valence n (all n incident edges interior, `K_i` = all of them):
//!      `α = 1 − 8a(n)/5`, `γ = 8a(n)/(5n)`, `a(n) = 5/8 − (3 + 2cos(2π/n))²/64`;
//!    * crease/boundary vertex (exactly two sharp edges, `K_i` = those two):
//!      `α = 1/2`, `γ = 1/4`;
//!    * corner (one or ≥ 3 sharp edges) or isolated vertex: `α = 1`, `γ = 0`.
//!
//! Optionally (see [`WaveletOptions::kdisk_update`]) a third step, a k-disk lifting update
//! `c = c' − S d` (seed eqs. 2.22–2.24) is applied *before* step 1, so the stored coarse
//! positions `c'` are a least-squares better coarse approximation.
//!
//! **Derivation (d = 0 gives Loop exactly).** Smooth vertex i with neighbours `c_1..c_n`
//! (sum `Σ`): every incident edge is interior and every neighbour is the opposite vertex of
//! exactly two incident edges (its two neighbours in the link, which is a union of cycles
//! because every incident edge has two triangles), so
//! `Σ_k odd_k = (3n c_i + 3Σ + 2Σ)/8 = (3n c_i + 5Σ)/8`. Then
//! `even_i = (α + 3nγ/8) c_i + (5γ/8) Σ`; matching Loop's `(1 − a)c_i + (a/n)Σ` gives
//! `γ = 8a/(5n)` and `α = 1 − a − 3a/5 = 1 − 8a/5` — DESIGN.md §3.3's constants are right.
//! Crease vertex: `odd_± = (c + c_±)/2`, so `c/2 + (odd_− + odd_+)/4 = (c_− + 6c + c_+)/8`,
//! Loop's crease rule. Corner: `even = c`. (Tested against an independent plain-Loop
//! implementation in the tests.)
//!
//! # Analysis (inverse steps, in reverse order)
//!
//! `c_i = (even_i − γ_i Σ_{k ∈ K_i} odd_k) / α_i`, then `d_k = odd_k − L_k(c)`
//! (then `c' = c + S d` with the k-disk update).
//!
//! **Amplification.** `1/α` is large where α is small: α = 0.1 at valence 3 (a = 9/16),
//! 0.225 at valence 4, ≈ 0.327 at valence 5, 0.4 at valence 6, 0.5 on creases. The ∞-norm
//! (per coordinate) of the map fine → `c_i` is `(1 + 8a/5)/(1 − 8a/5)`, and of fine → `d_k`
//! one more. Measured in the tests (one level, all vertices of one valence):
//!
//! | valence | coarse rows | detail rows |
//! |---|---|---|
//! | 3 (tetrahedron) | 19.0 | 20.0 |
//! | 4 (octahedron) | 7.89 | 8.89 |
//! | 5 (icosahedron) | 5.11 | 6.11 |
//!
//! Noise on the fine level near valence-3/4 vertices is therefore amplified in the coarse
//! positions and details there, and compounds over levels (a cube with 0.01 mm noise: plain
//! L∞ deviation of level 1 is 0.14 mm); prefer base meshes without such vertices
//! (DESIGN.md §3.3) or use the k-disk update, which damps it (0.027 mm on the same cube). The
//! transform is still exact: the round-trip error is only rounding, ≤ 1e-12 × diagonal.
//!
//! **k-disk update, measured** (L∞ deviation of the level-j surface from the finest, 4
//! levels, levels 0..3, plain → k-disk): bumpy sphere 0.41→0.089, 0.074→0.047,
//! 0.025→0.012, 0.0088→0.0052; bumpy open grid 0.59→0.15, 0.21→0.043, 0.067→0.018,
//! 0.017→0.0059; noisy creased cube 0.024→0.025, 0.14→0.027, 0.070→0.025, 0.040→0.022. It is
//! off by default so that the stored coarse positions are the plain Loop pre-images.
//!
//! Non-manifold coarse edges (more than two triangles) are rejected
//! ([`WaveletError::NonManifoldEdge`]); all lengths and the split's numbering are checked,
//! and wrong input gives a [`WaveletError`], never a panic. Everything is O(V + E) per level
//! (edge-list accumulation, no per-vertex adjacency needed) and deterministic (fixed
//! summation order). Files: `level.rs` (one level), `hierarchy.rs` (all levels, truncation,
//! deviation), `kdisk.rs` (optional update), `tests.rs`.

mod hierarchy;
mod kdisk;
mod level;
#[cfg(test)]
mod tests;

pub use hierarchy::{Deviation, MultiresWavelets, WaveletHierarchy};
pub use level::{
    DetailStats, LevelTopology, LevelWavelets, VertexClass, WaveletOptions, analyse, detail_stats,
    loop_ring_weight, refine_creases, synthesise,
};

/// Errors of the wavelet transform: inconsistent input, never a numerical failure.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum WaveletError {
    /// The [`Split`](crate::multires::Split) does not follow the 1-to-4 numbering contract.
    #[error("invalid split: {reason}")]
    InvalidSplit {
        /// What is wrong.
        reason: String,
    },
    /// An input slice has the wrong length.
    #[error("{what}: expected {expected} entries, found {found}")]
    LengthMismatch {
        /// Which input.
        what: &'static str,
        /// Required length.
        expected: usize,
        /// Given length.
        found: usize,
    },
    /// A crease edge is not an edge of the coarse level.
    #[error("crease edge {edge:?} is not an edge of the level")]
    UnknownCreaseEdge {
        /// The offending crease edge as given.
        edge: [u32; 2],
    },
    /// A coarse edge has more than two triangles.
    #[error("edge {edge:?} has {triangles} triangles (non-manifold)")]
    NonManifoldEdge {
        /// The edge.
        edge: [u32; 2],
        /// Its number of incident triangles.
        triangles: usize,
    },
    /// A level index beyond the hierarchy.
    #[error("level {level} out of range 0..={levels}")]
    LevelOutOfRange {
        /// Requested level.
        level: usize,
        /// Number of levels (splits) in the hierarchy.
        levels: usize,
    },
}
