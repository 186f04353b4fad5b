//! CAD surfaces into the pipeline (DESIGN.md §3.10; seeds 002 and 003): exact NURBS curves and
//! surfaces (`nurbs`), the faces of IGES files (`iges`), and their tessellation into the one
//! welded `Mesh` every later stage takes (`tessellate`).

#![warn(missing_docs)]

pub mod boxes;
pub mod iges;
pub mod nurbs;
pub mod tessellate;
