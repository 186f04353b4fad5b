//! `report.json`: what was planned, how long it takes, and how close the tool comes to the part.

use std::collections::BTreeMap;

use serde::Serialize;

use crate::mesh::{MeshReport, Piece};
use crate::path::LinkReport;
use crate::post::TimeEstimate;
use crate::tool::ToolAssembly;
use crate::verify::Verification;

#[derive(Clone, Debug, Serialize)]
pub struct PlanReport {
    pub wavemill_version: &'static str,
    pub part: PartSummary,
    pub tool: ToolSummary,
    pub machine: MachineSummary,
    pub surface: SurfaceSummary,
    pub strategy: StrategySummary,
    /// The impeller recognised in the part (`[impeller]`), or why it is not one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub impeller: Option<crate::impeller::Impeller>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub not_an_impeller: Option<String>,
    /// What the impeller finishing strategies planned, when they finished the part.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub impeller_finishing: Option<super::impeller_finish::ImpellerFinishSummary>,
    /// The corner finish with a smaller ball along the roots, when the job has one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub corner_finishing: Option<CornerFinishSummary>,
    /// The semi-finishing operations before finishing, in machining order: which shapes were
    /// used as stock to leave, and what the checks measured (issue 4 point 5). Empty: none.
    pub stock_to_leave: Vec<super::semi_finish::SemiFinishSummary>,
    /// The roughing operations before them, in machining order: tool, layers, and the exact
    /// check of each tool's posted moves against its offset shape and the part. Empty: none.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub roughing: Vec<super::plan_roughing::RoughingSummary>,
    /// The channel roughing operations after them: the ball's offset layers, each with what
    /// it cut and the stock it left. Empty: none.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub channel_roughing: Vec<super::channel_rough::ChannelSummary>,
    /// After roughing: the ball operations' rapids that would have passed through the
    /// material roughing leaves, made feed moves at the approach feed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rapids_fed_through_rest: Option<usize>,
    /// After roughing, with `[cutting] feed_control`: what feed control made of each ball
    /// operation's feeds (slowed where it meets the rest, at the limit in air).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub ball_feed_control: Vec<BallFeedControl>,
    /// Poses, lengths, time, clearances and blocks are of the whole program (semi-finishing
    /// and finishing); the strategy and unreachable figures are of the finishing passes.
    pub poses: PoseCounts,
    pub cutting_length_mm: f64,
    pub approach_length_mm: f64,
    pub rapid_length_mm: f64,
    pub estimated_time: TimeSummary,
    pub clearance: Verification,
    /// How the tolerance is split between planner, post, rounding and the check.
    pub tolerance_budget: super::budget::ToleranceBudget,
    /// The back-simulation of `job.nc` as written: least ball clearance along feed moves and
    /// along rapids, interpolated as the control does (absent when the program could not be
    /// read back, which fails the plan).
    pub posted: Option<crate::verify::PostedClearance>,
    pub unreachable: UnreachableSummary,
    /// The scallop the finishing moves leave, measured on the part from the moves alone
    /// ([`crate::verify::measure_scallop`]): heights over the area the passes reach, and the
    /// area they do not reach (the face on the table apart).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub finish_scallop: Option<crate::verify::ScallopReport>,
    /// What the colours of `scallop.glb` and `scallop.png` mean (the part coloured by the
    /// measure above, each triangle by the worst of its samples).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub finish_scallop_colours: Option<Vec<String>>,
    pub linking: LinkReport,
    /// Blocks in `job.nc` after linearisation.
    pub nc_blocks: usize,
    /// The operations run on the job's `[stock]` blank (absent without one).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stock: Option<super::stock_run::PlanStockReport>,
    /// Milliseconds per stage; the only part of the outputs that changes between runs.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub timings_ms: Option<StageTimings>,
}

/// Feed control of one ball operation.
#[derive(Clone, Debug, Serialize)]
pub struct BallFeedControl {
    pub operation: String,
    pub feed_control: crate::feed::FeedReport,
}

#[derive(Clone, Debug, Serialize)]
pub struct PartSummary {
    pub file: String,
    pub units: String,
    /// The file's direction that was turned to +Z, if any.
    pub up: Option<[f64; 3]>,
    pub warnings: Vec<String>,
    pub problems: Vec<String>,
    /// The part as planned: the file's figures without its stray pieces, except the counts of
    /// what reading and cleaning met (see `mesh::prepare_without_stray_pieces`).
    #[serde(flatten)]
    pub mesh: MeshReport,
    /// Stray debris of the file left out of planning, largest first (also a warning).
    pub stray_pieces: Vec<Piece>,
}

/// The surface the passes were driven on (`[surface]` of the job).
#[derive(Clone, Debug, Serialize)]
pub struct SurfaceSummary {
    /// "part (semi-regular)", "part (remeshing off)" or "hierarchy finest level".
    pub source: &'static str,
    /// Times the part un-splits 1-to-4 (0: not semi-regular), up to 8.
    pub part_subdivision_levels: usize,
    /// Levels of the hierarchy built (0 when the part was used as it is).
    pub hierarchy_levels: usize,
    pub base_triangles: usize,
    pub triangles: usize,
    /// Two-sided Hausdorff distance of the drive surface to the part, on dense samples, mm
    /// (0 when the part itself is the drive surface).
    pub hausdorff_to_part_mm: f64,
    pub tolerance_mm: f64,
    /// Whether the fit reached the tolerance within the level and size limits.
    pub tolerance_reached: bool,
}

#[derive(Clone, Debug, Serialize)]
pub struct ToolSummary {
    pub description: String,
    pub ball_radius_mm: f64,
    pub shank_margin_mm: f64,
    pub holder_margin_mm: f64,
    #[serde(flatten)]
    pub assembly: ToolAssembly,
}

#[derive(Clone, Debug, Serialize)]
pub struct MachineSummary {
    pub description: String,
    pub pivot_in_part_frame: [f64; 3],
    pub safe_distance_mm: f64,
    pub table_z_mm: f64,
    pub table_margin_mm: f64,
    /// Where the program unwinds because a rotary limit stops a pass from every branch and
    /// turn (retract along the axis, turn on the safe plane, re-plunge): the pose's move
    /// index (`cl.csv`'s rows from 0).
    pub unwinds: Vec<usize>,
    /// Stops on the safe plane inserted partway along rapids, where a rotary limit needs the
    /// axes to turn in place: their move indices.
    pub rapid_stops: Vec<usize>,
}

#[derive(Clone, Debug, Serialize)]
pub struct StrategySummary {
    pub kind: &'static str,
    pub scallop_height_mm: f64,
    pub stepover_mm: f64,
    pub tolerance_mm: f64,
    pub drive_planes: usize,
    pub drive_points: usize,
    pub refinement_poses: usize,
    pub splits_at_unreachable: usize,
    pub splits_at_refinement: usize,
    /// Poses dropped because they stepped back along their pass (swallowtails of the ball
    /// centre's path in concave corners).
    pub backward_poses_dropped: usize,
    pub lead_deg: f64,
    pub tilt_deg: f64,
    pub axis_smoothing: AxisSmoothingSummary,
}

/// The axis smoothing along the passes, before chord refinement (`orient::smooth_axes`).
#[derive(Clone, Debug, Serialize)]
pub struct AxisSmoothingSummary {
    /// The bound, degrees per mm (0: off) and the averaging window, mm.
    pub max_change_deg_per_mm: f64,
    pub window_mm: f64,
    /// Largest axis change per mm between neighbouring drive points, as chosen and as smoothed
    /// (on the built-in A/C machine with a continuous C, the larger of its rotaries' turns,
    /// `orient::AxisTurn`).
    pub max_rate_before_deg_per_mm: f64,
    pub max_rate_after_deg_per_mm: f64,
    /// Moves over the bound as chosen, and still over it after smoothing (no valid axis
    /// closer to the neighbours' there).
    pub moves_over_bound_before: usize,
    pub moves_over_bound: usize,
}

#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct PoseCounts {
    pub rapid: usize,
    pub approach: usize,
    pub cut: usize,
    pub retract: usize,
    pub total: usize,
}

#[derive(Clone, Debug, Serialize)]
pub struct TimeSummary {
    pub total_s: f64,
    #[serde(flatten)]
    pub by_kind: TimeEstimate,
}

#[derive(Clone, Debug, Serialize)]
pub struct UnreachableSummary {
    /// Drive points that could not be machined.
    pub count: usize,
    pub by_reason: BTreeMap<String, usize>,
    /// Up to 100 of them, in path order, for a first look.
    pub first_points: Vec<[f64; 3]>,
}

#[derive(Clone, Debug, Default, Serialize)]
pub struct StageTimings {
    pub prepare: f64,
    pub drive_surface: f64,
    pub collision_structures: f64,
    /// Roughing and rest-roughing operations planned (offset shapes, layers, planning stock).
    pub roughing: f64,
    /// Channel roughing's offset layers, planned and taken off the planning stock.
    pub channel_roughing: f64,
    pub semi_finishing: f64,
    pub finishing_passes: f64,
    /// Of the finishing of an impeller: its first passage and blade, and the copies.
    pub impeller_first_passage: f64,
    pub impeller_copies: f64,
    pub linking: f64,
    /// The ball operations' poses checked against the part, and (apart) the scallop the
    /// finishing leaves measured from its moves: the two one after the other, beside the
    /// back-simulation of the posted program (their times overlap it; the stages do not add
    /// up to the total).
    pub verification: f64,
    pub scallop: f64,
    pub post: f64,
    pub back_simulation: f64,
    /// Wall time of those independent checks together (pose checks and scallop measure beside
    /// the back-simulation): the rest of `total` is the planning, posting and writing.
    pub checks: f64,
    /// The operations run on the stock (0 without a `[stock]` blank).
    pub stock: f64,
    pub preview: f64,
    pub total: f64,
}

impl PlanReport {
    /// Pretty JSON with a final newline; timings left out when `timings` is false.
    pub fn to_json(&self, timings: bool) -> String {
        let mut r = self.clone();
        if !timings {
            r.timings_ms = None;
        }
        let mut s =
            serde_json::to_string_pretty(&r).unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"));
        s.push('\n');
        s
    }
}

/// What a corner finish (`kind = "corner-finish"`) planned: its ball, the band round the
/// roots it covers, its passes and how they were linked.
#[derive(Clone, Debug, Serialize)]
pub struct CornerFinishSummary {
    pub tool: String,
    pub ball_radius_mm: f64,
    pub scallop_height_mm: f64,
    pub stepover_mm: f64,
    /// From each root out to this far (mm): the finishing ball's radius and a stepover.
    pub band_mm: f64,
    pub drive_points: usize,
    pub cutting_length_mm: f64,
    /// Its drive points the smaller ball could not machine, by reason.
    pub unreachable: usize,
    pub unreachable_by_reason: BTreeMap<String, usize>,
    pub impeller: super::impeller_finish::ImpellerFinishSummary,
    pub linking: LinkReport,
}
