//! `wavemill tools`: which tool of a library finishes which region of a part, largest first
//! (issue 5 item 6; `tool_choice` does the work).
//!
//! * `tools.json`: the shape classes (area shares of convex / concave / saddle / flat), the
//!   smallest concave radius and the smallest safe ball and where they are, then the proposal:
//!   per tool, the area it finishes that no larger tool could, its regions (the largest with
//!   their smallest concave radius and largest safe ball) and why the next larger tool was
//!   refused there; the tools left out and why; what no tool reaches; timings.
//! * `tools.glb`: the part coloured by the proposed tool (the legend is the proposal's order in
//!   `tools.json`: blue, green, yellow, orange, purple, cyan, …), unreachable points red.

use std::path::Path;
use std::time::Instant;

use serde::Serialize;

use super::output::{OutputKind, json_bytes, write_output_set};
use crate::error::{Error, Result};
use crate::mesh::io::{GlbBuilder, RawMesh};
use crate::mesh::{Piece, PrepareOptions, prepare_without_stray_pieces};
use crate::tool::ToolLibrary;
use crate::tool_choice::{ToolChoiceOptions, ToolChoiceReport, choose_tools};

/// `tools.json`.
#[derive(Clone, Debug, Serialize)]
pub struct ToolsReport {
    pub wavemill_version: &'static str,
    pub part: String,
    pub library: String,
    pub library_tools: usize,
    pub triangles: usize,
    /// Stray debris of the file left out of the choice, largest first.
    pub stray_pieces: Vec<Piece>,
    pub max_tilt_deg: f64,
    pub table: bool,
    /// Colour of each proposed tool in tools.glb, in the proposal's order (linear RGB).
    pub colours: Vec<[f32; 3]>,
    #[serde(flatten)]
    pub choice: ToolChoiceReport,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub timings_ms: Option<ToolsTimings>,
}

#[derive(Clone, Debug, Serialize)]
pub struct ToolsTimings {
    pub prepare: f64,
    pub choose: f64,
    pub total: f64,
}

pub struct ToolsOutput {
    pub glb: Vec<u8>,
    pub report: ToolsReport,
}

const PALETTE: [[f32; 3]; 12] = [
    [0.12, 0.35, 0.85],
    [0.15, 0.65, 0.25],
    [0.95, 0.8, 0.1],
    [0.95, 0.5, 0.1],
    [0.55, 0.25, 0.75],
    [0.1, 0.75, 0.8],
    [0.6, 0.45, 0.25],
    [0.85, 0.45, 0.7],
    [0.4, 0.4, 0.4],
    [0.5, 0.8, 0.4],
    [0.3, 0.2, 0.6],
    [0.9, 0.9, 0.6],
];
const UNREACHABLE: [f32; 3] = [0.85, 0.08, 0.06];

/// Chooses tools for `raw` (already in mm) from `library`; `part_name` and `library_name` name
/// the sources in errors and the report.
pub fn tools(
    raw: &RawMesh,
    part_name: &str,
    library: &ToolLibrary,
    library_name: &str,
    options: &ToolChoiceOptions,
    timings: bool,
) -> Result<ToolsOutput> {
    let started = Instant::now();
    let ms = |t: Instant| (t.elapsed().as_secs_f64() * 1e4).round() / 10.0;
    let mesh_error = |reason: String| Error::Mesh {
        file: part_name.to_string(),
        reason,
    };
    // As `plan` does: stray debris is left out of the choice and reported.
    let (part, report, stray_pieces) =
        prepare_without_stray_pieces(&raw.mesh, &PrepareOptions::default())
            .map_err(|e| mesh_error(e.to_string()))?;
    if report.non_manifold_edges > 0 || report.boundary_edges > 0 {
        return Err(mesh_error(format!(
            "tool choice needs a closed manifold part (inside and outside must be defined): {}",
            report.problems().join("; ")
        )));
    }
    let prepare_ms = ms(started);
    let t = Instant::now();
    let choice = choose_tools(&part, library, options)?;
    let choose_ms = ms(t);

    // Colours follow the proposal's order (largest first), so the legend reads like the list.
    let proposal_index = |tool: usize| {
        choice
            .report
            .proposal
            .iter()
            .position(|p| p.id == library.tools[tool].id)
    };
    let colour = |slot: Option<usize>| {
        let [r, g, b] = slot.map_or(UNREACHABLE, |k| PALETTE[k % PALETTE.len()]);
        [r, g, b, 1.0]
    };
    let colours: Vec<[f32; 4]> = choice
        .vertex_tool
        .iter()
        .map(|t| colour(t.and_then(proposal_index)))
        .collect();
    let mut glb = GlbBuilder::new();
    glb.add_triangles("tools", &part, [1.0, 1.0, 1.0, 1.0], Some(&colours))
        .map_err(|error| Error::Glb {
            file: "tools.glb".into(),
            error,
        })?;
    let legend = (0..choice.report.proposal.len())
        .map(|k| PALETTE[k % PALETTE.len()])
        .collect();
    Ok(ToolsOutput {
        glb: glb.build(),
        report: ToolsReport {
            wavemill_version: env!("CARGO_PKG_VERSION"),
            part: part_name.to_string(),
            library: library_name.to_string(),
            library_tools: library.tools.len(),
            triangles: part.triangles.len(),
            stray_pieces,
            max_tilt_deg: options.max_tilt_deg,
            table: options.table_margin.is_some(),
            colours: legend,
            choice: choice.report,
            timings_ms: timings.then(|| ToolsTimings {
                prepare: prepare_ms,
                choose: choose_ms,
                total: ms(started),
            }),
        },
    })
}

/// Writes `tools.glb` and `tools.json` into `dir` (created if missing), each atomically.
pub fn write_tools_outputs(dir: &Path, output: &ToolsOutput) -> Result<()> {
    write_output_set(
        dir,
        &OutputKind::TOOLS,
        &[
            ("tools.glb".to_string(), output.glb.clone()),
            (
                "tools.json".to_string(),
                json_bytes("tools.json", &output.report)?,
            ),
        ],
    )
}
