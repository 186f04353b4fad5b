//! 2.5D contour machining of planar profiles (DESIGN.md §3.9; seed 004 ch. 3–4).
//!
//! Shapes are closed curves of lines and arcs ([`geometry`]: bulge vertices, the region to the
//! left of every contour). So far:
//!
//! * [`input`] — SVG (paths incl. arcs, basic shapes, nested transforms, fill rules) and DXF
//!   (LINE, ARC, CIRCLE, ELLIPSE, LWPOLYLINE, POLYLINE, SPLINE) outlines read into a
//!   [`geometry::Shape`]; curves that are not circles become biarcs within a tolerance;
//!   crossing paths are refused, naming both and where they cross; Z-sections of closed
//!   meshes ([`input::mesh_section`]: region by nesting, straight runs merged within the
//!   tolerance, a missed plane / open mesh / horizontal face in the plane refused);
//! * [`wavelet`] — the endpoint-interpolating cubic B-spline wavelet filters P^j and Q^j
//!   (seed 004 §2.2, figs. 2.5–2.6), decomposition (eq. 2.16), reconstruction (eq. 2.17),
//!   fractional levels (eq. 3.2), least-squares fitting and the eq. 3.1 deviation bound;
//! * [`multires`] — the multiresolution method of seed 004 ch. 3–4: corners by multi-scale
//!   curvature (§3.1), ν = l/m segmentation (§3.2), wavelet-approximated offsets checked
//!   exactly against the part (§3.3–3.4), adaptive curves where measured pass deviations open
//!   gaps (§3.5, eq. 3.3), the loose convex hull and its offsets (§4.1), the part levels
//!   clipped to it (§4.2);
//! * [`parallel`] — the contour-parallel baseline the seed compares against (tables 3.1,
//!   4.1): exact line/arc offsets of the part at r, r + s, …, clipped to the stock
//!   (cavalier_contours), ordered from the far side toward the part and linked;
//! * [`toolpath`] — tool-centre paths: [`Pass`], [`Link`], [`CenterPath`];
//! * [`verify`] — exact overcut (closed-form line/arc distances), uncut area (exact
//!   x-intervals per scanline), path statistics;
//! * posting (G-code with G2/G3 arcs and the seed's machining-time model) is the post's:
//!   `crate::post::contour`;
//! * helpers: [`segops`] (exact segment geometry), [`bvh`] (segment BVH), [`region`]
//!   (point-in-shape, scanline crossings, part-inside-stock check), [`cavc`] (the
//!   cavalier_contours bridge).
//!
//! Not done (issue #6): biarc fitting of mesh sections (they are polygons simplified within
//! the tolerance); eq. 3.2's control-point interpolation for the adaptive curves (see
//! [`multires`] for why the fractional level is interpolated instead).

pub mod bvh;
pub mod cavc;
pub mod error;
pub mod geometry;
pub mod input;
pub mod material;
pub mod multires;
pub mod parallel;
pub mod region;
pub mod segops;
pub mod simplify;
pub mod toolpath;
pub mod verify;
pub mod wavelet;

pub use error::ContourError;
pub use input::{OutlineError, OutlineOptions, mesh_section, read_outline};
pub use multires::{MultiresOptions, MultiresPlan, MultiresReport, multires_paths};
pub use parallel::{ParallelOptions, contour_parallel};
pub use toolpath::{CenterPath, CutDirection, Link, Pass};
pub use verify::{
    Clearance, PassSpacing, PathStats, UncutArea, clearance, pass_spacing, path_stats, uncut_area,
};
