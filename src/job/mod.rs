//! Jobs: the job file, and the pipeline that wires the stages together into a plan.
//!
//! [`access`] computes the visibility maps `wavemill access` writes; [`tools`] proposes tools
//! from a library for `wavemill tools`; [`simulate_program`] runs CL data on a blank for
//! `wavemill simulate`.
//!
//! [`plan`] is what `wavemill plan` runs and what other planners call: it takes a raw part mesh
//! and a [`Job`] and returns every output in memory; [`write_outputs`] writes them atomically.
//! With a `[stock]` blank, [`run_operations`] runs the plan's operations on it in order.

mod access;
mod blank;
mod budget;
mod cad_part;
mod channel_rough;
mod config;
mod contour;
mod contour_picture;
mod impeller_finish;
mod impeller_rest;
mod indexed_rough;
mod lens;
mod levels;
mod observer;
mod offsets;
mod operation;
mod output;
mod pipeline;
mod plan_roughing;
mod preview;
mod rapids;
mod render;
mod report;
mod rough;
mod rough_boxes;
mod rough_stages;
mod samples;
mod scallop_picture;
mod semi_finish;
mod setup;
mod simulate;
mod stock_model;
mod stock_run;
mod tools;

pub use access::{
    AccessOptions, AccessOutput, AccessReport, access, parse_query_csv, write_access_outputs,
};
pub use blank::BlankSpec;
pub use budget::ToleranceBudget;
pub use cad_part::{
    PartSurfaces, TessellateSummary, TessellatedPart, is_iges, load_iges_part, read_iges_file,
    tessellate_iges, tessellate_summary, tessellation_warnings,
};
pub use channel_rough::{
    ChannelLayerSummary, ChannelPlan, ChannelSummary, channel_rough, layer_allowances,
};
pub use config::{
    BoxBound, ChannelLayers, CuttingSection, FeedSection, ImpellerSection, Job, JobError, Layering,
    LimitsSection, MachineSection, NO_BLANK, Operation, OperationKind, OperationSection,
    PartSection, RoughingBound, RoughingSection, SafetySection, StockSection, StrategySection,
    ToolSection, unit_direction,
};
pub use contour::{
    CompareReport, ContourComparison, ContourJobOptions, DEFAULT_MAX_LEVELS,
    DEFAULT_MAX_OUTLINE_VERTICES, MethodFigures, StockSpec, contour_compare, contour_wavelet,
    write_contour_outputs,
};
pub use impeller_finish::{PassageVisibility, RootPass, root_pass, visible_passage_axis};
pub use lens::{
    GRID_DISTANCE_TOLERANCE, LensOptions, LensOutput, LensReport, LoadedLens, lens, lens_failure,
    load_lens, write_lens_outputs,
};
pub use levels::{AnalysedHierarchy, LevelSummary, LevelsReport, analyse_hierarchy, levels};
pub use offsets::{
    MAX_SHAPE_LEVELS, OffsetsOutput, OffsetsReport, ShapeSummary, level_specs,
    levels_for_allowances, offset_specs, offsets, shape_glb, stock_shapes,
};
pub use operation::InProcessStock;
pub use output::{OutputKind, check_output_dir, write_atomically, write_output_set, write_outputs};
pub use pipeline::{
    Observer, OperationDetails, OperationSpan, OperationTarget, PlanOutput, PlannedOperation,
    Quiet, ToolChange, drive_surface, join_operations, load_part, load_part_with_surfaces, plan,
    plan_operation, plan_with_surfaces, post_program, post_program_with_tool_changes,
    program_header, stock_to_leave_shapes,
};
pub use plan_roughing::{
    PlannedRoughing, RoughingContext, RoughingSummary, check_posted_roughing, plan_roughing,
};
pub use report::{CornerFinishSummary, PlanReport, PoseCounts, StageTimings};
pub use rough::{
    HullBoxesReport, LayerBound, RoughOptions, RoughOutput, RoughReport, RoughToolRun, SlicingRow,
    rough, write_rough_outputs,
};
pub use rough_boxes::{RoughBoxesOptions, rough_boxes, rougher_assembly};
pub use samples::{SamplePart, sample_files};
pub use semi_finish::{SemiFinishPlan, SemiFinishSummary, semi_finish_operation};
pub use setup::{PlanSetup, PreparedPart, machine, posted_program_model, prepare_part};
pub use simulate::{
    ProgramFormat, SimulateOptions, SimulationReport, SimulationRun, StockReport, simulate_program,
    write_simulation,
};
pub use stock_model::{
    CollisionReport, DepthOfCutReport, EngagementReport, GougeReport, Spread, blank_stock,
    cutting_spreads, default_resolution, enclosure_warning, stock_model_glb,
};
pub use stock_run::{
    OperationMoves, OperationStockReport, PlanStockReport, StockRun, run_operations,
};
pub use tools::{ToolsOutput, ToolsReport, tools, write_tools_outputs};
