//! CAD surfaces into the pipeline (DESIGN.md §3.10; seeds 002 and 003): exact NURBS curves and
//! surfaces (`nurbs`) and the faces of IGES files (`iges`); tessellation into the `Mesh` every
//! later stage takes comes next (issue 23).

#![warn(missing_docs)]

pub mod iges;
pub mod nurbs;
