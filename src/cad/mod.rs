//! CAD surfaces into the pipeline (DESIGN.md §3.10; seeds 002 and 003): exact NURBS curves and
//! surfaces (`nurbs`), read from IGES files and tessellated into the `Mesh` every later stage
//! takes.

pub mod nurbs;
