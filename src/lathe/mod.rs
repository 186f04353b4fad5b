//! Freeform lens turning (DESIGN.md §3.13, seed 003): a lens surface — analytic from a TOML
//! description, or the freeform NURBS face of an IGES file — becomes a polar R × θ grid of
//! nose-centre heights and a spiral slow-tool-servo program for a lathe with a C axis.
//!
//! * [`surface`]: the surfaces behind one parametric interface (point, first and second
//!   derivatives), analytic sags on [`jet`]s;
//! * [`description`]: TOML descriptions and the choice of the freeform face of an IGES file;
//! * [`compensate`]: nose-radius compensation solved exactly per point (seed 003 §3.3: the
//!   programmed point is the nose centre, at ρ from the surface along its normal);
//! * [`grid`]: the seed's polar grid (R vector, θ vector, Z matrix) with what the tool meets
//!   (concave radii, descent against the clearance angle);
//! * [`mod@spiral`]: the spiral program, points spaced by the form tolerance, posted in inverse
//!   time;
//! * [`offset_surface`]: the seed's own route for comparison, an approximate Piegl–Tiller
//!   offset surface onto which the grid is projected;
//! * [`check`]: independent checks of the written grid and program (nearest surface point of
//!   every centre, the program interpolated as the control runs it).

#![warn(missing_docs)]

pub mod check;
pub mod compensate;
pub mod description;
pub mod grid;
pub mod jet;
pub mod offset_surface;
pub mod spiral;
pub mod surface;

pub use compensate::{Contact, ContactError, nose_centre};
pub use description::{FaceChoice, LensDescription, lens_from_iges};
pub use grid::{
    CompensatedGrid, GridError, GridOptions, PolarGrid, RadialSpacing, compensated_grid,
};
pub use spiral::{PostOptions, SpindleSpeed, Spiral, SpiralError, SpiralOptions, post, spiral};
pub use surface::{LensSurface, NurbsLens, SagShape};
