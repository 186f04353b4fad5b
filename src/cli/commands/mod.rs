//! One file per subcommand: its arguments and a thin runner over the library.

pub mod access;
pub mod contour;
pub mod info;
pub mod lens;
pub mod levels;
pub mod offsets;
pub mod plan;
pub mod rough;
pub mod rough_boxes;
pub mod sample;
pub mod simulate;
pub mod subdivide;
pub mod tessellate;
pub mod tools;
