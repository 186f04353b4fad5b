//! The end-to-end tests, one module per capability, built as one test binary: one link
//! instead of one per file, and the test harness runs them all on both cores together (a
//! binary of one long test left the second core idle while it ran).

mod common;

mod access_testdata;
mod cad_iges;
mod cad_plan;
mod cad_rough_boxes;
mod cad_tessellate;
mod cli;
mod collision_reference;
mod contour_compare;
mod impeller_recognition;
mod layering;
mod lens;
mod machines;
mod multires_testdata;
mod offsets_testdata;
mod plan_channel;
mod plan_indexed;
mod plan_rough;
mod plan_sample_impeller;
mod plan_semi_finish;
mod plan_stock;
mod plan_testdata;
mod rough;
mod simulate;
mod stray_pieces;
mod testdata_meshes;
mod tool_choice;
