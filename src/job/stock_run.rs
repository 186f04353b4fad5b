//! The in-process stock through a plan. With a `[stock]` blank, the plan's operations run on a
//! tri-dexel model of it in machining order ([`crate::stock::simulate`]): each removes its
//! material from what the operations before it left, and is checked against that material —
//! gouges into the part, rapids through material, and the shank, neck and holder of its own
//! tool touching it. Each operation's summary goes into the plan's report and the stock it
//! leaves into `stock-N.glb`, coloured by the distance to the part. A gouge, a rapid through
//! material or a touch fails the plan (exit 3), as the pose checks do.

use serde::Serialize;

use super::config::{Job, Operation};
use super::observer::Observer;
use super::stock_model::{
    CollisionReport, DepthOfCutReport, GougeReport, Spread, blank_stock, cutting_spreads,
    default_resolution, enclosure_warning, stock_error, stock_model_glb,
};
use crate::error::{Error, JobError, Result};
use crate::geom::Toolpath;
use crate::mesh::Mesh;
use crate::stock::cutter::CuttingBody;
use crate::stock::rest::{Rest, rest_over};
use crate::stock::simulate::{SimulationOptions, simulate_with_progress};
use crate::stock::{DEFAULT_MAX_DEXELS, Stock};

/// Collisions listed per operation in the report (all are counted).
const LISTED_COLLISIONS: usize = 100;

/// `stock` in `report.json`.
#[derive(Clone, Debug, Serialize)]
pub struct PlanStockReport {
    /// The blank, as the job names it.
    pub blank: String,
    pub resolution_mm: f64,
    pub dexel_lines: usize,
    pub blank_volume_mm3: f64,
    /// One per operation, in machining order.
    pub operations: Vec<OperationStockReport>,
    pub warnings: Vec<String>,
}

/// What one operation did to the stock.
#[derive(Clone, Debug, Serialize)]
pub struct OperationStockReport {
    pub name: String,
    /// The coloured model of the stock it leaves.
    pub model: String,
    pub moves: usize,
    pub removed_volume_mm3: f64,
    pub volume_after_mm3: f64,
    /// Share of its feed moves' length that removed nothing.
    pub air_cut_fraction: f64,
    /// Removed volume per mm of cut, mm³/mm.
    pub engagement: Spread,
    pub depth_of_cut: DepthOfCutReport,
    /// Move indices are the plan's (`cl.csv`'s rows from 0).
    pub gouge: GougeReport,
    pub rapids_through_material: usize,
    pub first_rapid_through_material: Option<usize>,
    /// Moves whose shank, neck or holder touched material (the deepest body each).
    pub collision_count: usize,
    /// The first of them, at most 100.
    pub collisions: Vec<CollisionReport>,
    /// Material left over the part after the operation.
    pub rest: Rest,
}

/// The stock run through a plan's operations.
#[derive(Clone, Debug)]
pub struct StockRun {
    pub report: PlanStockReport,
    /// `stock-N.glb` for the N-th operation, from 1.
    pub models: Vec<(String, Vec<u8>)>,
    /// What makes the plan unfit to run, if anything: the first operation that gouges,
    /// rapids through material or touches it with a non-cutting body.
    pub failure: Option<String>,
    /// The stock after the last operation.
    pub stock: Stock,
}

/// One operation of a plan as the stock run takes it: its moves (indices into the plan's
/// toolpath) and the tool that cuts them.
#[derive(Clone, Copy, Debug)]
pub struct OperationMoves<'a> {
    pub operation: &'a Operation,
    pub moves: &'a std::ops::Range<usize>,
    pub tool: &'a crate::tool::ToolAssembly,
}

/// Runs each of `operations` (its moves in `toolpath`, with its tool) on the job's `[stock]`
/// blank of `part` (as planned; a mesh blank is read in `units`), in order; `None` when the
/// job names no blank.
pub fn run_operations(
    part: &Mesh,
    units: &str,
    job: &Job,
    toolpath: &Toolpath,
    operations: &[OperationMoves],
    observer: &dyn Observer,
) -> Result<Option<StockRun>> {
    let Some(spec) = job.stock.blank_spec()? else {
        return Ok(None);
    };
    let spacing = job
        .stock
        .resolution
        .unwrap_or_else(|| default_resolution(part));
    let tolerance = job.strategy.tolerance;
    observer.stage("stock: blank", 0);
    let mut stock = blank_stock(part, &spec, units, spacing, DEFAULT_MAX_DEXELS)?;
    let part_model = Stock::from_mesh(part, spacing, DEFAULT_MAX_DEXELS).map_err(stock_error)?;
    let mut report = PlanStockReport {
        blank: spec.describe(),
        resolution_mm: spacing,
        dexel_lines: stock.line_count(),
        blank_volume_mm3: stock.volume(),
        operations: Vec::with_capacity(operations.len()),
        warnings: enclosure_warning(&stock, part).into_iter().collect(),
    };
    let mut models = Vec::with_capacity(operations.len());
    let mut failure = None;
    for (k, run) in operations.iter().enumerate() {
        let (operation, span, assembly) = (run.operation, run.moves, run.tool);
        // From the pose the operation starts at (the last of the one before).
        let first = span.start.saturating_sub(1);
        let moves = Toolpath {
            tool_id: assembly.id,
            moves: toolpath.moves[first..span.end].to_vec(),
        };
        let options = SimulationOptions::for_tool(assembly, tolerance);
        observer.stage(
            &format!("stock: {}", operation.name),
            moves.moves.len() as u64,
        );
        let reported = std::sync::atomic::AtomicUsize::new(0);
        let sim = simulate_with_progress(
            &mut stock,
            part,
            &moves,
            &CuttingBody::of(&assembly.cutter),
            &options,
            &|done| {
                let before = reported.swap(done, std::sync::atomic::Ordering::Relaxed);
                for _ in before..done {
                    observer.advance();
                }
            },
        )
        .map_err(|e| match e {
            crate::stock::StockError::Blank(reason) => Error::JobFile(JobError::Invalid {
                key: format!("stock (operation '{}')", operation.name),
                reason,
            }),
            e => stock_error(e),
        })?;
        let global = |index: usize| first + index;
        let (engagement, depth_of_cut) = cutting_spreads(&sim, &moves);
        let rest = rest_over(&stock, part, &part_model, stock.bounds().diagonal());
        let name = format!("stock-{}.glb", k + 1);
        models.push((name.clone(), stock_model_glb(&stock, part, tolerance)?));
        let summary = OperationStockReport {
            name: operation.name.clone(),
            model: name,
            moves: moves.moves.len(),
            removed_volume_mm3: sim.removed_volume_mm3,
            volume_after_mm3: stock.volume(),
            air_cut_fraction: sim.air_cut_fraction,
            engagement,
            depth_of_cut,
            gouge: GougeReport {
                count: sim.gouge.count,
                max_depth_mm: sim.gouge.max_depth_mm,
                volume_mm3: sim.gouge.volume_mm3,
                first_move: sim.gouge.first_move.map(global),
            },
            rapids_through_material: sim.rapids_through_material.len(),
            first_rapid_through_material: sim.rapids_through_material.first().map(|&m| global(m)),
            collision_count: sim.collisions.len(),
            collisions: sim
                .collisions
                .iter()
                .take(LISTED_COLLISIONS)
                .map(|c| CollisionReport {
                    move_index: global(c.move_index),
                    body: c.role,
                    depth_mm: c.depth_mm,
                    at: [c.at.x, c.at.y, c.at.z],
                })
                .collect(),
            rest,
        };
        if failure.is_none() {
            failure = operation_failure(&summary);
        }
        report.operations.push(summary);
    }
    Ok(Some(StockRun {
        report,
        models,
        failure,
        stock,
    }))
}

/// Why an operation must not run on the stock, if it must not.
fn operation_failure(summary: &OperationStockReport) -> Option<String> {
    let mut problems = Vec::new();
    if let Some(first) = summary.gouge.first_move {
        problems.push(format!(
            "{} gouging move(s) up to {:.4} mm deep, the first move {first}",
            summary.gouge.count, summary.gouge.max_depth_mm
        ));
    }
    if let Some(first) = summary.collisions.first() {
        let deepest = summary
            .collisions
            .iter()
            .map(|c| c.depth_mm)
            .fold(0.0, f64::max);
        problems.push(format!(
            "{} move(s) with the shank, neck or holder in material (the first move {}, the {:?}; up to {deepest:.3} mm deep among the first {})",
            summary.collision_count,
            first.move_index,
            first.body,
            summary.collisions.len()
        ));
    }
    if let Some(first) = summary.first_rapid_through_material {
        problems.push(format!(
            "{} rapid(s) through material, the first move {first}",
            summary.rapids_through_material
        ));
    }
    (!problems.is_empty()).then(|| {
        format!(
            "operation '{}' on the stock: {}",
            summary.name,
            problems.join("; ")
        )
    })
}
