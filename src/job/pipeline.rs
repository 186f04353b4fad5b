//! The plan runner: a job is a list of operations ([`super::operation`]) planned in order by
//! [`plan`] through public stages, each a function from plain data to plain data, so a
//! library user can run them one by one or replace one (`examples/plan_stages.rs`):
//!
//! 1. [`prepare_part`] — the part welded, repaired, upright, stray pieces set aside;
//! 2. [`drive_surface`] — the finest level of its multiresolution hierarchy (DESIGN.md §3.2);
//! 3. [`PlanSetup::new`] — collision structures, tool, machine, safe plane, tolerance budget;
//! 4. [`stock_to_leave_shapes`] — the offset shapes semi-finishing machines to (§3.4);
//! 5. [`plan_operation`] per operation, from the [`InProcessStock`] the ones before leave;
//! 6. [`join_operations`] — one program;
//! 7. [`crate::verify::verify`] of every pose and chord, [`post_program`] (linearised and
//!    written for the machine), and [`crate::verify::check_posted`] of the program as
//!    written; then the preview.
//!
//! This file wires and times them, and gathers the report.

use std::borrow::Cow;
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use super::budget::ToleranceBudget;
use super::channel_rough::channel_rough;
use super::config::{Job, Operation, OperationKind, SurfaceSection, ToolSection};
use super::impeller_finish::{ImpellerFinishOptions, ImpellerFinishSummary, finish_impeller};
use super::offsets::stock_shapes;
use super::operation::InProcessStock;
use super::plan_roughing::{BallTakeOff, RoughingContext, check_posted_roughing, plan_roughing};
use super::preview::preview;
use super::rapids::{MAX_RAPID_TURN_DEG, split_turning_rapids};
use super::report::*;
use super::semi_finish::{SemiFinishSummary, semi_finish_operation};
use super::setup::{PlanSetup, PreparedPart, prepare_part};
use crate::collide::PreparedTool;
use crate::error::{Error, JobError, Result};
use crate::geom::{Direction, Move, MoveKind, Point3, ToolPose, Toolpath, Vector3, slerp};
use crate::impeller::Impeller;
use crate::impeller::Region;
use crate::mesh::io::{RawMesh, Units, read_mesh};
use crate::mesh::{Mesh, set_aside_warning};
use crate::multires::Hierarchy;
use crate::offset::OffsetShape;
use crate::path::{self, Finishing, LinkReport};
use crate::post::{self, Joints, LineariseOptions, MachineKinematics, ProgramHeader};
use crate::stock::clearance::MaterialClearance;
use crate::verify::{Ball, ScallopOptions, ToolReach, measure_scallop_map_of};
use crate::verify::{PoseChecks, PostedClearance, PostedOptions, check_posted, verify};

pub use super::observer::{Observer, Quiet};

/// Everything a plan produces, in memory.
pub struct PlanOutput {
    /// The part as planned (welded, oriented).
    pub part: Mesh,
    pub toolpath: Toolpath,
    /// Where each operation's moves are in `toolpath`, in order: semi-finishing to each
    /// stock-to-leave shape, then finishing (stock to leave 0).
    pub operations: Vec<OperationSpan>,
    pub gcode: String,
    pub cl_csv: String,
    /// The same poses as APT CL data (`cl.apt`).
    pub cl_apt: String,
    pub report: PlanReport,
    pub preview_glb: Vec<u8>,
    /// `scallop.glb` and `scallop.png`: the part coloured by what the finishing leaves
    /// (`job::scallop_picture`); none without a finishing operation.
    pub scallop_pictures: Vec<(String, Vec<u8>)>,
    /// `stock-N.glb`: the stock after each operation, with a `[stock]` blank.
    pub stock_models: Vec<(String, Vec<u8>)>,
    /// What the independent re-check of the finished path found wrong, if anything. A path
    /// that fails must not be run; [`super::write_outputs`] then writes only the report.
    pub verification_failure: Option<String>,
}

/// One operation of a plan: the stock it leaves on the part and its moves in the toolpath.
#[derive(Clone, Debug, PartialEq)]
pub struct OperationSpan {
    pub stock_to_leave_mm: f64,
    pub moves: std::ops::Range<usize>,
}

/// The surface the passes are driven on: the part when it already has subdivision
/// connectivity (or remeshing is off), else its hierarchy's finest level (DESIGN.md §3.2).
pub fn drive_surface<'a>(
    part: &'a Mesh,
    settings: &SurfaceSection,
) -> std::result::Result<(Cow<'a, Mesh>, SurfaceSummary), String> {
    let depth = crate::multires::subdivision_depth(&part.triangles, part.positions.len(), 8);
    let as_is = |source| SurfaceSummary {
        source,
        part_subdivision_levels: depth,
        hierarchy_levels: 0,
        base_triangles: part.triangles.len(),
        triangles: part.triangles.len(),
        hausdorff_to_part_mm: 0.0,
        tolerance_mm: settings.tolerance,
        tolerance_reached: true,
    };
    if depth > 0 {
        return Ok((Cow::Borrowed(part), as_is("part (semi-regular)")));
    }
    if !settings.remesh {
        return Ok((Cow::Borrowed(part), as_is("part (remeshing off)")));
    }
    let hierarchy = Hierarchy::build(part, &settings.remesh_options())
        .map_err(|e| format!("remeshing for the drive surface: {e}"))?;
    let finest = hierarchy.finest();
    let summary = SurfaceSummary {
        source: "hierarchy finest level",
        part_subdivision_levels: 0,
        hierarchy_levels: hierarchy.levels.len(),
        base_triangles: hierarchy
            .levels
            .first()
            .map_or(0, |l| l.mesh.triangles.len()),
        triangles: finest.mesh.triangles.len(),
        hausdorff_to_part_mm: finest.hausdorff,
        tolerance_mm: settings.tolerance,
        tolerance_reached: finest.hausdorff <= settings.tolerance,
    };
    Ok((Cow::Owned(finest.mesh.clone()), summary))
}

/// Reads a part file in the given units.
///
/// When the part's size in the file's own numbers suggests other units than `units` by orders
/// of magnitude (a 185-unit impeller read as inches is 4.7 m across), a warning saying so is
/// added to the mesh's warnings.
///
/// An IGES file (`.igs`, `.iges`) is tessellated at 0.01 mm into one welded mesh; its units
/// are the file's own (its Global section), so `units` is not asked.
pub fn load_part(path: &Path, units: &str) -> Result<RawMesh> {
    load_part_with_surfaces(path, units).map(|(raw, _)| raw)
}

/// [`load_part`], and for an IGES file its surfaces beside the mesh (for `hull-boxes`
/// roughing, [`plan_with_surfaces`]).
pub fn load_part_with_surfaces(
    path: &Path,
    units: &str,
) -> Result<(
    RawMesh,
    Option<std::sync::Arc<super::cad_part::PartSurfaces>>,
)> {
    let units: Units = units
        .parse()
        .map_err(|e| Error::Usage(format!("units of {}: {e}", path.display())))?;
    if super::is_iges(path) {
        let options = crate::cad::tessellate::TessellateOptions::default();
        let part = super::tessellate_iges(path, &options)?;
        let mut warnings = super::tessellation_warnings(&part, &options);
        if units != Units::Millimetres {
            warnings.push(format!(
                "units {units} not applied: an IGES file's Global section gives its own unit"
            ));
        }
        let surfaces = super::cad_part::PartSurfaces {
            faces: part.model.faces,
            face_of_triangle: part.tessellation.face_of_triangle,
            tolerance: options.tolerance,
        };
        let raw = RawMesh {
            mesh: part.tessellation.mesh,
            warnings,
        };
        return Ok((raw, Some(std::sync::Arc::new(surfaces))));
    }
    let mut raw = read_mesh(path, units)?;
    if let Some(warning) = units_warning(&raw.mesh, units) {
        raw.warnings.push(warning);
    }
    Ok((raw, None))
}

/// A warning when the part read in `units` has a size those units make implausible while
/// another unit makes it plausible (the guess of `wavemill info`, from the size in the file's
/// numbers).
fn units_warning(mesh: &crate::mesh::Mesh, units: Units) -> Option<String> {
    use crate::mesh::UnitsGuess;
    if mesh.positions.is_empty() {
        return None;
    }
    let diagonal_mm = mesh.aabb().diagonal();
    let in_file_units = diagonal_mm / units.scale_to_mm();
    if !in_file_units.is_finite() || in_file_units <= 0.0 {
        return None;
    }
    let suggested = match (UnitsGuess::from_diagonal(in_file_units), units) {
        (UnitsGuess::Millimetres, Units::Inches | Units::Metres) => Units::Millimetres,
        (UnitsGuess::Metres, Units::Millimetres | Units::Inches) => Units::Metres,
        (UnitsGuess::MillimetresOrInches, Units::Metres) => Units::Millimetres,
        _ => return None,
    };
    let name = |u: Units| match u {
        Units::Millimetres => "millimetres",
        Units::Metres => "metres",
        Units::Inches => "inches",
    };
    Some(format!(
        "read in {} the part is {} mm across ({} {units} in the file); its size suggests {} \
         ({} mm): check the units",
        name(units),
        significant(diagonal_mm),
        significant(in_file_units),
        name(suggested),
        significant(in_file_units * suggested.scale_to_mm())
    ))
}

/// `v` with four significant digits, in plain notation where that stays short.
fn significant(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        format!("{v}")
    } else if !(1e-3..1e6).contains(&v.abs()) {
        format!("{v:.3e}")
    } else {
        format!(
            "{:.*}",
            (3 - v.abs().log10().floor() as i64).max(0) as usize,
            v
        )
    }
}

/// Distance between the points the finishing scallop is measured at, mm: near the stepover of
/// a 4 mm ball at 0.01 mm but not a multiple of it, so the points fall at every phase between
/// neighbouring passes.
const SCALLOP_SAMPLE_SPACING: f64 = 0.5;

/// Tool axes tried at a sample over the target before it is called blocked (no axis reaches):
/// a Fibonacci sphere, neighbours about 7° apart.
const REACH_DIRECTIONS: usize = 800;

fn ms(since: Instant) -> f64 {
    (since.elapsed().as_secs_f64() * 1e3 * 10.0).round() / 10.0
}

/// One operation, planned: its moves and what planning it measured.
pub struct PlannedOperation {
    pub operation: Operation,
    pub toolpath: Toolpath,
    pub details: OperationDetails,
    /// What the operation's own checks found wrong, if anything (the plan must not be run).
    pub failure: Option<String>,
}

impl PlannedOperation {
    /// Whether the operation finished the part as an impeller, with its own strategies.
    pub fn finished_as_impeller(&self) -> bool {
        matches!(
            &self.details,
            OperationDetails::Finish {
                impeller: Some(_),
                ..
            }
        )
    }
}

/// What planning an operation measured, by kind.
pub enum OperationDetails {
    /// Layers with a library end mill ([`super::plan_roughing`]); the summary as planned,
    /// before the posted program is checked.
    Rough(Box<super::plan_roughing::RoughingSummary>),
    /// Offset layers of the ball ([`super::channel_rough`]).
    ChannelRough(Box<super::channel_rough::ChannelSummary>),
    SemiFinish(SemiFinishSummary),
    Finish {
        passes: Finishing,
        linking: LinkReport,
        /// What the impeller strategies planned, when the part was finished as an impeller.
        impeller: Option<Box<ImpellerFinishSummary>>,
    },
}

/// What an operation machines: the stock-to-leave shape of a semi-finishing operation (with
/// its hierarchy level), the drive surface of finishing.
pub enum OperationTarget<'a> {
    Shape {
        level: usize,
        shape: &'a OffsetShape,
    },
    DriveSurface(&'a Mesh),
    /// Finishing an impeller: its strategies on the part, the planes on the drive surface for
    /// what they leave.
    Impeller {
        drive: &'a Mesh,
        part: &'a Mesh,
        impeller: &'a Impeller,
        /// A corner finish: how far from each root (mm) its passes run.
        corner_band: Option<f64>,
        /// A corner finish: the finishing before it, and its ball's radius (what it already
        /// finished is left out).
        finished: Option<(&'a Toolpath, f64)>,
    },
}

/// Plans one operation on `target` from the material `stock` the operations before it leave;
/// refuses an operation that would leave as much as is already there (it would cut nothing).
/// With `material` (the stock roughing and the operations since left, as a model), the shank
/// and holder keep their margins from it as well as from the part.
pub fn plan_operation(
    setup: &PlanSetup,
    operation: &Operation,
    target: OperationTarget,
    stock: &InProcessStock,
    material: Option<Arc<MaterialClearance>>,
    advance: &(dyn Fn() + Sync),
) -> Result<PlannedOperation> {
    // A corner finish leaves the finish's 0 mm, taking what the finishing ball could not reach.
    if let InProcessStock::AtLeast { stock_to_leave } = *stock
        && operation.stock_to_leave >= stock_to_leave
        && operation.kind != OperationKind::CornerFinish
    {
        return Err(Error::JobFile(JobError::Operations(format!(
            "operation '{}' leaves {} mm where the operations before it already leave \
             {stock_to_leave} mm: it would cut nothing",
            operation.name, operation.stock_to_leave
        ))));
    }
    let planned = |toolpath, details, failure| PlannedOperation {
        operation: operation.clone(),
        toolpath,
        details,
        failure,
    };
    match (operation.kind, target) {
        (OperationKind::SemiFinish, OperationTarget::Shape { level, shape }) => {
            let semi = semi_finish_operation(
                setup,
                level,
                shape,
                operation.scallop_height,
                material,
                advance,
            )?;
            Ok(planned(
                semi.toolpath,
                OperationDetails::SemiFinish(semi.summary),
                semi.failure,
            ))
        }
        (
            OperationKind::Finish,
            target @ (OperationTarget::DriveSurface(_) | OperationTarget::Impeller { .. }),
        )
        | (OperationKind::CornerFinish, target @ OperationTarget::Impeller { .. }) => {
            let reachable = |axis: &Vector3| setup.reachable(axis);
            let with_material = material.map(|m| setup.collider.with_material(m));
            let collider = with_material.as_ref().unwrap_or(&setup.collider);
            let ctx = setup.finishing_context(collider, &setup.rays, &reachable);
            // What is verified is the whole target: the passes keep a share of it for
            // their moves' sag.
            let options = setup.finishing.leaving_at_most(operation.scallop_height);
            // Sections follow the drive surface; every pose is placed and checked against
            // the part (and the material).
            let (passes, impeller) = match target {
                OperationTarget::Impeller {
                    drive,
                    part,
                    impeller,
                    corner_band,
                    finished,
                } => {
                    // A point is finished where the ball before came within the target of it.
                    let swept = finished.map(|(toolpath, radius)| {
                        let mut swept = path::SweptBalls::new(path::CoverOptions {
                            ball_radius: radius,
                            slack: operation.scallop_height,
                            min_gap: 0.0,
                            overlap: 0.0,
                            around: 0.0,
                        });
                        swept.insert_cuts(toolpath);
                        (swept, radius)
                    });
                    let is_finished = |p: &Point3| {
                        swept.as_ref().is_some_and(|(swept, radius)| {
                            swept.covers(p, radius + operation.scallop_height)
                        })
                    };
                    let finished: Option<&(dyn Fn(&Point3) -> bool + Sync)> =
                        swept.as_ref().map(|_| &is_finished as _);
                    let (passes, summary) = finish_impeller(
                        part,
                        drive,
                        impeller,
                        &ctx,
                        &options,
                        &ImpellerFinishOptions {
                            hub_axes: setup.impeller.hub_axes,
                            blade_axes: setup.impeller.blade_axes,
                            blade_lean_deg: setup.impeller.blade_lean_deg,
                            swarf: setup.impeller.swarf,
                            tip: setup.impeller.tip,
                            rest: setup.impeller.rest,
                            pole: setup.pole(),
                            link: setup.link.clone(),
                            max_rotary_speed: setup.gcode_options.max_rotary_speed,
                            corner_band,
                        },
                        finished,
                        advance,
                    );
                    (passes, Some(Box::new(summary)))
                }
                OperationTarget::DriveSurface(drive) => {
                    (path::finishing_passes(drive, &ctx, &options, advance), None)
                }
                OperationTarget::Shape { .. } => unreachable!("matched above"),
            };
            let (toolpath, linking) = path::link(
                &passes.segments,
                collider,
                &setup.prepared_tool,
                setup.tool.id,
                &setup.link,
            );
            Ok(planned(
                toolpath,
                OperationDetails::Finish {
                    passes,
                    linking,
                    impeller,
                },
                None,
            ))
        }
        (kind, _) => Err(Error::Internal(format!(
            "operation '{}' ({}) was given the wrong surface to machine",
            operation.name,
            kind.name()
        ))),
    }
}

/// The stock-to-leave shapes of the semi-finishing `operations`, in their order, each with
/// the hierarchy level it offsets. As `wavemill offsets` does: shape j offsets level j of a
/// hierarchy with one level above the base per shape, so the finest allowance is not on the
/// coarsest level.
pub fn stock_to_leave_shapes(
    part: &Mesh,
    job: &Job,
    operations: &[Operation],
) -> Result<Vec<(usize, OffsetShape)>> {
    let allowances: Vec<f64> = operations
        .iter()
        .filter(|op| op.kind == OperationKind::SemiFinish)
        .map(|op| op.stock_to_leave)
        .collect();
    if allowances.is_empty() {
        return Ok(Vec::new());
    }
    let remesh = crate::multires::RemeshOptions {
        tolerance: 0.0,
        base_triangles: job.surface.base_triangles,
        base_max_error: None,
        max_levels: allowances.len() as u32,
        crease_angle_deg: job.surface.crease_angle_deg,
        ..Default::default()
    };
    stock_shapes(part, &remesh, &allowances)
}

/// Where the operations planned so far leave the tool: their last move.
fn last_move(planned: &[PlannedOperation]) -> Option<Move> {
    planned
        .last()
        .and_then(|p| p.toolpath.moves.last().copied())
}

/// The operations' moves as one program, in order, and where each operation's moves are.
/// Each operation starts and ends on the safe plane, as its segments do.
pub fn join_operations(planned: &[PlannedOperation]) -> (Toolpath, Vec<OperationSpan>) {
    let mut toolpath = Toolpath {
        tool_id: planned.first().map_or(0, |p| p.toolpath.tool_id),
        moves: Vec::new(),
    };
    let mut spans = Vec::with_capacity(planned.len());
    for p in planned {
        let start = toolpath.moves.len();
        toolpath.moves.extend_from_slice(&p.toolpath.moves);
        spans.push(OperationSpan {
            stock_to_leave_mm: p.operation.stock_to_leave,
            moves: start..toolpath.moves.len(),
        });
    }
    (toolpath, spans)
}

/// Plans `job` on `raw` (already in mm): the stages in order — prepare the part, its drive
/// surface, the cell ([`PlanSetup`]), the stock-to-leave shapes, each operation from the
/// stock the ones before it leave, then the joined program verified, posted, read back and
/// previewed. `part_name` names the part in errors, the report and the G-code header.
pub fn plan(
    raw: &RawMesh,
    part_name: &str,
    units: &str,
    job: &Job,
    observer: &dyn Observer,
) -> Result<PlanOutput> {
    plan_with_surfaces(raw, None, part_name, units, job, observer)
}

/// [`plan`] of a part read from IGES, with its surfaces beside its mesh: what `hull-boxes`
/// roughing operations box (`raw` is their tessellation, in the file's frame).
pub fn plan_with_surfaces(
    raw: &RawMesh,
    surfaces: Option<std::sync::Arc<super::cad_part::PartSurfaces>>,
    part_name: &str,
    units: &str,
    job: &Job,
    observer: &dyn Observer,
) -> Result<PlanOutput> {
    job.validate()?;
    let operations = job.operations()?;
    if surfaces.is_none()
        && let Some(boxed) = operations.iter().find(|op| op.boxes.is_some())
    {
        return Err(Error::JobFile(JobError::Operations(format!(
            "operation '{}': bound = \"hull-boxes\" boxes the part's surfaces, and {part_name} \
             is a mesh: plan a part read from IGES (.igs, .iges)",
            boxed.name
        ))));
    }
    let started = Instant::now();
    let mut timings = StageTimings::default();

    let t = Instant::now();
    observer.stage("prepare part", 0);
    let prepared = prepare_part(raw, part_name, job)?;
    let part = &prepared.part;
    let impeller = recognise_impeller(part, part_name, job)?;
    if let Some(e) = operations
        .iter()
        .find_map(|op| corner_refusal(op, part_name, job, &impeller))
    {
        return Err(e);
    }
    timings.prepare = ms(t);

    let t = Instant::now();
    observer.stage("drive surface", 0);
    // An impeller finished by its own strategies leaves the planes only the nose, bore and rim
    // (surfaces of revolution): they are driven on the part itself, and the hierarchy, a third
    // of the blower's plan, is not built.
    let impeller_finishes = job.impeller.finishing
        && matches!(impeller, Some(Ok(_)))
        && operations.iter().any(|op| op.kind == OperationKind::Finish);
    let settings = SurfaceSection {
        remesh: job.surface.remesh && !impeller_finishes,
        ..job.surface.clone()
    };
    let (drive, surface) = drive_surface(part, &settings).map_err(|reason| Error::Mesh {
        file: part_name.to_string(),
        reason,
    })?;
    timings.drive_surface = ms(t);

    let t = Instant::now();
    observer.stage("collision structures", 0);
    let setup = PlanSetup::new(&prepared, job)?;
    timings.collision_structures = ms(t);

    let t = Instant::now();
    let semi_count = operations
        .iter()
        .filter(|op| op.kind == OperationKind::SemiFinish)
        .count();
    if semi_count > 0 {
        observer.stage("stock-to-leave shapes and semi-finishing", 0);
    }
    let shapes = stock_to_leave_shapes(part, job, &operations)?;
    let mut shapes_left = shapes.iter();
    let mut stock = InProcessStock::Blank;
    let mut planned = Vec::with_capacity(operations.len());
    let mut roughing = Vec::new();
    let mut roughing_context = None;
    // The tool each operation cuts with, in order: a library end mill or the job's ball.
    let mut tools = Vec::with_capacity(operations.len());
    let advance = || observer.advance();
    // Ball rapids made feed moves through the rest (with a raw blank), and where the ball's
    // last operation left it.
    let mut rapids_fed: Option<usize> = None;
    let mut last_ball_move: Option<Move> = None;
    let mut ball_feed_control = Vec::new();
    let has_blank = job.stock.blank_spec()?.is_some();
    // How every ball operation comes off the planning stock after roughing.
    fn take_off_with<'a>(
        job: &Job,
        ball: &'a crate::tool::ToolAssembly,
        tool: &ToolSection,
    ) -> BallTakeOff<'a> {
        BallTakeOff {
            ball,
            approach_feed: job.feeds.approach,
            clearance: job.feeds.clearance,
            tolerance: job.strategy.tolerance,
            feed_control: job.cutting.model().map(|model| {
                let cutter = crate::feed::Cutter {
                    diameter: tool.diameter,
                    spindle_rpm: f64::from(tool.spindle_rpm),
                    pass_feed: job.feeds.cut,
                    rapid_feed: job.machine.rapid_feed,
                    speed_up: false,
                };
                (model, cutter)
            }),
        }
    }
    let ball_take_off = take_off_with(job, &setup.tool, &job.tool);
    // The corner finish's smaller ball, in the same cell.
    let corner_setup = operations
        .iter()
        .find(|op| op.kind == OperationKind::CornerFinish)
        .map(|op| setup.with_ball(&op.tool));
    for operation in &operations {
        if operation.kind.is_roughing() {
            let t = Instant::now();
            observer.stage(&format!("roughing: {}", operation.name), 0);
            let context = match &mut roughing_context {
                Some(context) => context,
                None => roughing_context.insert(RoughingContext::new(
                    part,
                    units,
                    job,
                    prepared.table_z,
                    surfaces.clone(),
                )?),
            };
            let mut rough = if operation.kind == OperationKind::IndexedRough {
                super::indexed_rough::plan_indexed_roughing(context, part, job, &setup, operation)?
            } else {
                plan_roughing(context, part, job, &setup, operation)?
            };
            if operation.kind == OperationKind::IndexedRough {
                // Between setups the table turns: the stock run sweeps those rapids as the
                // control moves them.
                let before = last_move(&planned);
                split_turning_rapids(
                    &mut rough.toolpath,
                    before.as_ref(),
                    setup.program_kinematics().as_ref(),
                    MAX_RAPID_TURN_DEG,
                );
            }
            planned.push(PlannedOperation {
                operation: operation.clone(),
                toolpath: rough.toolpath.clone(),
                details: OperationDetails::Rough(Box::new(rough.summary.clone())),
                failure: None,
            });
            tools.push(rough.tool.clone());
            roughing.push(rough);
            stock = stock.after(operation);
            timings.roughing += ms(t);
            continue;
        }
        if operation.kind == OperationKind::ChannelRough {
            let t = Instant::now();
            observer.stage(&format!("channel roughing: {}", operation.name), 0);
            let context = roughing_context.as_mut().ok_or_else(|| {
                Error::JobFile(JobError::Operations(format!(
                    "operation '{}' roughs what a blank's roughing left: it needs a [stock] \
                     blank roughed before it",
                    operation.name
                )))
            })?;
            // From where the operation before left the tool (a roughing tool's last move, on the
            // safe plane, when this is the first ball operation).
            let before = last_move(&planned).or(last_ball_move);
            let channel = channel_rough(
                &setup,
                part,
                operation,
                context,
                &ball_take_off,
                before.as_ref(),
                has_blank,
                &advance,
            )?;
            *rapids_fed.get_or_insert(0) += channel.rapids_fed;
            ball_feed_control.extend(channel.feed_control.into_iter().map(
                |(operation, feed_control)| BallFeedControl {
                    operation,
                    feed_control,
                },
            ));
            if let Some(m) = channel.toolpath.moves.last() {
                last_ball_move = Some(*m);
            }
            planned.push(PlannedOperation {
                operation: operation.clone(),
                toolpath: channel.toolpath,
                details: OperationDetails::ChannelRough(Box::new(channel.summary)),
                failure: channel.failure,
            });
            tools.push(setup.tool.clone());
            stock = stock.after(operation);
            timings.channel_roughing += ms(t);
            continue;
        }
        let target = match operation.kind {
            OperationKind::SemiFinish => {
                let (level, shape) = shapes_left.next().ok_or_else(|| {
                    Error::Internal(format!("no stock-to-leave shape for '{}'", operation.name))
                })?;
                OperationTarget::Shape {
                    level: *level,
                    shape,
                }
            }
            OperationKind::Finish => {
                // Each roughing time is rounded on its own: clamp the rounding's -0.1 ms away.
                timings.semi_finishing =
                    (ms(t) - timings.roughing - timings.channel_roughing).max(0.0);
                let stepover = path::stepover_for_scallop(
                    operation.tool.diameter / 2.0,
                    operation.scallop_height,
                );
                let extent = part
                    .aabb()
                    .extent()
                    .dot(&setup.finishing.drive_normal.normalize())
                    .abs();
                observer.stage(
                    "finishing passes",
                    (extent / stepover.max(1e-3)).ceil() as u64,
                );
                match impeller.as_ref() {
                    Some(Ok(impeller)) if job.impeller.finishing => OperationTarget::Impeller {
                        drive: &drive,
                        part,
                        impeller,
                        corner_band: None,
                        finished: None,
                    },
                    _ => OperationTarget::DriveSurface(&drive),
                }
            }
            OperationKind::CornerFinish => {
                observer.stage(&format!("corner finishing: {}", operation.name), 0);
                let finish_before = planned
                    .iter()
                    .rfind(|p| p.operation.kind == OperationKind::Finish);
                let band = corner_band(job, operation);
                match impeller.as_ref() {
                    Some(Ok(impeller)) if job.impeller.finishing => OperationTarget::Impeller {
                        drive: &drive,
                        part,
                        impeller,
                        corner_band: Some(band),
                        finished: finish_before.map(|p: &PlannedOperation| {
                            (&p.toolpath, p.operation.tool.diameter / 2.0)
                        }),
                    },
                    _ => {
                        return Err(corner_refusal(operation, part_name, job, &impeller)
                            .unwrap_or_else(|| {
                                Error::Internal("a corner finish without an impeller".into())
                            }));
                    }
                }
            }
            OperationKind::Rough
            | OperationKind::RestRough
            | OperationKind::IndexedRough
            | OperationKind::ChannelRough => {
                return Err(Error::Internal("roughing is planned above".into()));
            }
        };
        let t = Instant::now();
        let material = roughing_context.as_ref().map(RoughingContext::material);
        let op_setup = match (&corner_setup, operation.kind) {
            (Some(corner), OperationKind::CornerFinish) => corner,
            _ => &setup,
        };
        let mut operation_planned =
            plan_operation(op_setup, operation, target, &stock, material, &advance)?;
        if matches!(
            operation.kind,
            OperationKind::Finish | OperationKind::CornerFinish
        ) {
            timings.finishing_passes += ms(t);
        }
        // With a blank, every move is also read as a straight sweep through the stock: rapids
        // that turn the axis go there as the control moves them (super::rapids).
        // The first is the rapid from where the operation before left the tool.
        if has_blank {
            let before = last_move(&planned);
            split_turning_rapids(
                &mut operation_planned.toolpath,
                before.as_ref(),
                op_setup.program_kinematics().as_ref(),
                MAX_RAPID_TURN_DEG,
            );
        }
        // After roughing, each ball operation comes off the planning stock before the next is
        // planned against it; rapids its links drive into the rest become feed moves.
        if let Some(context) = roughing_context.as_mut() {
            let t = Instant::now();
            let taken = context.take_off_ball_operation(
                &mut operation_planned.toolpath,
                last_ball_move.as_ref(),
                &take_off_with(job, &op_setup.tool, &operation.tool),
            );
            *rapids_fed.get_or_insert(0) += taken.rapids_fed;
            if let Some(feed_control) = taken.feed_control {
                ball_feed_control.push(BallFeedControl {
                    operation: operation.name.clone(),
                    feed_control,
                });
            }
            timings.linking += ms(t);
        }
        last_ball_move = operation_planned.toolpath.moves.last().copied();
        planned.push(operation_planned);
        tools.push(op_setup.tool.clone());
        stock = stock.after(operation);
    }

    // One number, one tool: the program's T words and the control's offsets go by it.
    for (k, tool) in tools.iter().enumerate() {
        if let Some(other) = tools[..k]
            .iter()
            .find(|t| t.id == tool.id && t.describe() != tool.describe())
        {
            return Err(Error::JobFile(JobError::Operations(format!(
                "tool number T{} names two tools, {} and {}: give them their own numbers",
                tool.id,
                other.describe(),
                tool.describe()
            ))));
        }
    }

    let t = Instant::now();
    observer.stage("linking", 0);
    let (toolpath, spans) = join_operations(&planned);
    timings.linking += ms(t);

    // The machine's limits: the program linearised as the post writes it, unwinding in the
    // ball's sections where a limit stops a pass, so that every check below sees those moves.
    let t = Instant::now();
    observer.stage("machine motion", 0);
    let impeller_finished = planned.iter().any(PlannedOperation::finished_as_impeller);
    let mut header = program_header(&prepared, job, &setup, &operations, impeller_finished);
    if let Some(first) = roughing.first() {
        header.program_name = format!("wavemill roughing and finishing of {}", prepared.name);
        header.tool_description = vec![first.tool.describe()];
        header.tool_number = first.tool.id;
        header.spindle_rpm = job.roughing.spindle_rpm;
        header.comments.insert(
            0,
            format!(
                "layer roughing from {} with {}, 3-axis (A0){}, to the part + {} mm",
                job.stock.blank.as_deref().unwrap_or("the blank"),
                roughing
                    .iter()
                    .map(|r| format!("T{}", r.tool.id))
                    .collect::<Vec<_>>()
                    .join(", then "),
                if roughing.iter().any(|r| r.summary.indexed.is_some()) {
                    " and in indexed 3+2 setups"
                } else {
                    ""
                },
                first.summary.stock_to_leave_mm
            ),
        );
    }
    let changes = tool_changes(job, &spans, &operations, &tools);
    let section_starts: Vec<usize> = std::iter::once(0)
        .chain(changes.iter().map(|c| c.at))
        .collect();
    // The ball each operation cuts with, prepared (`None` for the roughing end mills).
    let ball_of = |op: &Operation| -> Option<&PreparedTool> {
        match (op.kind, &corner_setup) {
            (kind, _) if kind.is_roughing() => None,
            (OperationKind::CornerFinish, Some(corner)) => Some(&corner.prepared_tool),
            _ => Some(&setup.prepared_tool),
        }
    };
    let unwind_sections: Vec<Option<&PreparedTool>> = section_starts
        .iter()
        .map(|&at| {
            spans
                .iter()
                .zip(&operations)
                .find(|(span, _)| span.moves.contains(&at))
                .and_then(|(_, op)| ball_of(op))
        })
        .collect();
    // An unwind's rapids the ball would drive into the rest the roughing left are fed, as
    // the take-off feeds the operations' own.
    let unwind_rapids_fed = std::cell::Cell::new(0);
    let feed_into_rest = |from: &Move, moves: &mut Vec<Move>, ball: &PreparedTool| {
        if let Some(context) = roughing_context.as_ref() {
            let how = BallTakeOff {
                ball: ball.assembly(),
                approach_feed: job.feeds.approach,
                clearance: job.feeds.clearance,
                tolerance: job.strategy.tolerance,
                feed_control: None,
            };
            let fed = context.feed_rapids_into_rest(from, moves, &how);
            unwind_rapids_fed.set(unwind_rapids_fed.get() + fed);
        }
    };
    let linearised = linearise_program(
        &setup,
        &toolpath,
        &changes,
        tools
            .first()
            .map_or(setup.tool.total_length(), |t| t.total_length()),
        &unwind_sections,
        Some(&feed_into_rest),
    )?;
    if unwind_rapids_fed.get() > 0 {
        *rapids_fed.get_or_insert(0) += unwind_rapids_fed.get();
    }
    let new_index = linearised.new_index();
    let spans: Vec<OperationSpan> = spans
        .into_iter()
        .map(|span| OperationSpan {
            moves: new_index[span.moves.start]..new_index[span.moves.end],
            ..span
        })
        .collect();
    let changes: Vec<ToolChange> = changes
        .into_iter()
        .map(|change| ToolChange {
            at: new_index[change.at],
            ..change
        })
        .collect();
    let toolpath = linearised.toolpath.clone();
    timings.post += ms(t);

    let t = Instant::now();
    observer.stage("post-processing", 0);
    let (program, gcode) = write_program(&setup, &linearised, &changes, &header);
    let cl_csv = if tools.iter().all(|t| t.id == setup.tool.id) {
        post::write_cl_csv(&toolpath)
    } else {
        let rows: Vec<(u32, Move)> = spans
            .iter()
            .zip(&tools)
            .flat_map(|(span, tool)| {
                toolpath.moves[span.moves.clone()]
                    .iter()
                    .map(|m| (tool.id, *m))
            })
            .collect();
        super::rough_stages::cl_csv_of(&rows)
    };
    let apt_rows: Vec<(post::AptTool, Move)> = spans
        .iter()
        .zip(&tools)
        .flat_map(|(span, tool)| {
            let apt = post::AptTool {
                number: tool.id,
                diameter: tool.cutter.diameter(),
                corner_radius: tool.cutter.corner_radius(),
            };
            toolpath.moves[span.moves.clone()]
                .iter()
                .map(move |m| (apt, *m))
        })
        .collect();
    let cl_apt = post::write_apt(&prepared.name, &apt_rows);
    // Each section between tool changes timed at the control point its F words were written
    // for (the ball's centre; a corner finish's smaller ball turns about its own), the block
    // into a section with it.
    let mut time = post::TimeEstimate::default();
    let mut control_point = setup.prepared_tool.ball_radius;
    let mut start = 0;
    for (k, section) in linearised.sections.iter().enumerate() {
        if let Some(c) = k
            .checked_sub(1)
            .and_then(|k| changes[k].header.control_point_mm)
        {
            control_point = c;
        }
        let end = start + section.len();
        time.merge(&post::estimate_time_posted(
            &program[start.saturating_sub(1)..end],
            setup.gcode_options.feed,
            control_point,
            setup.gcode_options.max_rotary_speed,
        ));
        start = end;
    }
    timings.post += ms(t);

    // The pose verification and the scallop measure need only the moves; the back-simulation
    // reads the posted program. Each runs its queries in parallel, but not every stage
    // keeps both cores busy (one thread: 7.4, 4.7 and 9.6 s on the blower, two: 4.8, 2.8
    // and 5.1 s), so they run side by side.
    let budget = &setup.budget;
    let t_checks = Instant::now();
    let (checks, back_simulation) = rayon::join(
        || {
            let t = Instant::now();
            observer.stage("verification", 0);
            // Every pose of the ball operations against the part and the machine, each ball's
            // moves with its bodies; the roughing tools' moves are checked exactly as posted
            // below.
            let ball_start = spans
                .iter()
                .zip(&operations)
                .find(|(_, op)| !op.kind.is_roughing())
                .map_or(toolpath.moves.len(), |(span, _)| span.moves.start);
            let corner_start = spans
                .iter()
                .zip(&operations)
                .find(|(_, op)| op.kind == OperationKind::CornerFinish)
                .map_or(toolpath.moves.len(), |(span, _)| span.moves.start);
            let moves_of = |range: std::ops::Range<usize>, tool_id: u32| Toolpath {
                tool_id,
                moves: toolpath.moves[range].to_vec(),
            };
            let mut verification = verify(
                &moves_of(ball_start..corner_start, setup.tool.id),
                &setup.collider,
                &setup.prepared_tool,
                setup.search,
                PoseChecks::LeaveFlutesToBackSimulation,
            );
            if let Some(corner) = &corner_setup {
                verification = verification.merge(&verify(
                    &moves_of(corner_start..toolpath.moves.len(), corner.tool.id),
                    &corner.collider,
                    &corner.prepared_tool,
                    corner.search,
                    PoseChecks::LeaveFlutesToBackSimulation,
                ));
            }
            let verification_ms = ms(t);
            let t = Instant::now();
            // The scallop the finishing moves leave on the part, measured from the moves alone.
            let ball_of = |p: &PlannedOperation| {
                let radius = p.operation.tool.diameter / 2.0;
                Ball {
                    radius,
                    flutes_above_ball: (p.operation.tool.flute_length - radius).max(0.0),
                }
            };
            let corner = planned
                .iter()
                .find(|p| p.operation.kind == OperationKind::CornerFinish);
            let finish_scallop = planned
                .iter()
                .rfind(|p| p.operation.kind == OperationKind::Finish)
                .map(|p| {
                    let radius = p.operation.tool.diameter / 2.0;
                    let labels: Option<Vec<&str>> =
                        impeller.as_ref().and_then(|i| i.as_ref().ok()).map(|i| {
                            i.regions
                                .iter()
                                .map(|r| match r {
                                    Region::Hub => "hub",
                                    Region::Blade(_) => "blade",
                                    Region::Splitter(_) => "splitter",
                                    Region::Other(_) => "other",
                                })
                                .collect()
                        });
                    let target = p.operation.scallop_height;
                    let passes: Vec<(&Toolpath, Ball)> = std::iter::once(p)
                        .chain(corner)
                        .map(|p| (&p.toolpath, ball_of(p)))
                        .collect();
                    // Where no axis of the finishing tool reaches; with a corner tool as
                    // well (another ball, shank and holder) nothing is told apart.
                    let reachable = |axis: &Vector3| setup.reachable(axis);
                    let reach = corner.is_none().then(|| {
                        ToolReach::new(
                            setup.prepared_tool.assembly().bodies(),
                            job.safety.shank_margin,
                            job.safety.holder_margin,
                            Some((prepared.table_z, job.safety.table_margin)),
                            &reachable,
                            REACH_DIRECTIONS,
                        )
                    });
                    let (report, found) = measure_scallop_map_of(
                        part,
                        &passes,
                        &ScallopOptions {
                            radius,
                            target: p.operation.scallop_height,
                            spacing: SCALLOP_SAMPLE_SPACING,
                            reach: radius,
                            table_z: prepared.table_z,
                            flutes_above_ball: (p.operation.tool.flute_length - radius).max(0.0),
                        },
                        labels.as_deref(),
                        reach.as_ref(),
                    );
                    (report, found, target)
                });
            let scallop_ms = ms(t);
            (verification, verification_ms, finish_scallop, scallop_ms)
        },
        || {
            let t = Instant::now();
            observer.stage("back-simulation of the program", 0);
            let rapid_margin = job.safety.shank_margin;
            let gauges: Vec<(u32, f64)> = tools
                .iter()
                .map(|t| (t.id, t.total_length()))
                .chain(std::iter::once((setup.tool.id, setup.tool.total_length())))
                .collect();
            let model = setup.verifier_model(&gauges);
            // Each ball's blocks with that ball.
            let posted_for = |ball: &PlanSetup| {
                check_posted(
                    &gcode,
                    &model,
                    part,
                    &PostedOptions {
                        ball_radius: ball.prepared_tool.ball_radius,
                        feed_error_mm: budget.verification_mm,
                        rapid_error_mm: (0.1 * rapid_margin).max(budget.verification_mm),
                        search_mm: ball.search,
                        tool: Some(ball.tool.id),
                        rounding_mm: budget.rounding_mm,
                        flutes_above_ball: ball
                            .prepared_tool
                            .flutes_above_ball()
                            .map_or(0.0, |(length, _)| length),
                    },
                )
            };
            let posted = match &corner_setup {
                None => posted_for(&setup),
                Some(corner) => {
                    posted_for(&setup).and_then(|finish| Ok(finish.merge(posted_for(corner)?)))
                }
            };
            let roughing_failure = check_posted_roughing(
                &gcode,
                &model,
                part,
                &mut roughing,
                1 + changes.len(),
                budget.verification_mm,
                &super::plan_roughing::PostedRoughingLimits {
                    pivot: setup.pivot,
                    safe_distance: setup.safe_distance,
                    table: setup.table,
                },
            );
            let back_simulation_ms = ms(t);
            (rapid_margin, posted, roughing_failure, back_simulation_ms)
        },
    );
    timings.checks = ms(t_checks);
    let (verification, verification_ms, finish_scallop, scallop_ms) = checks;
    let (finish_scallop, scallop_map) = match finish_scallop {
        Some((report, found, target)) => (Some(report), Some((found, target))),
        None => (None, None),
    };
    let (rapid_margin, posted, roughing_failure, back_simulation_ms) = back_simulation;
    let roughing_failure = roughing_failure?;
    timings.verification = verification_ms;
    timings.scallop = scallop_ms;
    timings.back_simulation = back_simulation_ms;
    let pose_failure = verification
        .passes(
            budget.chord_mm,
            job.safety.shank_margin,
            job.safety.holder_margin,
            job.safety.table_margin,
        )
        .err()
        .map(|failure| failure.to_string());
    let t = Instant::now();
    let runs: Vec<super::stock_run::OperationMoves> = operations
        .iter()
        .zip(&spans)
        .zip(&tools)
        .map(
            |((operation, span), tool)| super::stock_run::OperationMoves {
                operation,
                moves: &span.moves,
                tool,
            },
        )
        .collect();
    let stock_run = super::stock_run::run_operations(part, units, job, &toolpath, &runs, observer)?;
    timings.stock = ms(t);
    let verification_failure = pose_failure
        .or_else(|| {
            let fastest = toolpath
                .moves
                .iter()
                .filter(|m| m.kind != MoveKind::Rapid)
                .map(|m| m.feed)
                .fold(0.0, f64::max);
            posted_failure(&posted, budget, rapid_margin, fastest)
        })
        .or(roughing_failure)
        .or_else(|| planned.iter().find_map(|p| p.failure.clone()))
        .or_else(|| stock_run.as_ref().and_then(|run| run.failure.clone()));
    let posted = posted.ok();

    let t = Instant::now();
    observer.stage("preview", 0);
    let preview_glb = preview(part, &toolpath, 5.0, 2.0 * job.tool.diameter / 2.0 + 8.0)?;
    let scallop_pictures = match &scallop_map {
        Some((patches, target)) => super::scallop_picture::scallop_pictures(patches, *target)?,
        None => Vec::new(),
    };
    timings.preview = ms(t);
    timings.total = ms(started);
    observer.finish();

    let mut semi_summaries = Vec::new();
    let mut channel_summaries = Vec::new();
    let mut finishing = None;
    let mut corner_finishing = None;
    for p in planned {
        match p.details {
            OperationDetails::Finish {
                passes,
                linking,
                impeller: Some(impeller),
            } if p.operation.kind == OperationKind::CornerFinish => {
                let radius = p.operation.tool.diameter / 2.0;
                let stepover = path::planned_stepover(radius, p.operation.scallop_height);
                let cutting_length_mm = p
                    .toolpath
                    .moves
                    .windows(2)
                    .filter(|w| w[1].kind == MoveKind::Cut)
                    .map(|w| (w[1].pose.tip - w[0].pose.tip).norm())
                    .sum();
                corner_finishing = Some(CornerFinishSummary {
                    tool: p.operation.tool.assembly().describe(),
                    ball_radius_mm: radius,
                    scallop_height_mm: p.operation.scallop_height,
                    stepover_mm: stepover,
                    band_mm: corner_band(job, &p.operation),
                    drive_points: passes.drive_points,
                    cutting_length_mm,
                    unreachable: passes.unreachable.len(),
                    unreachable_by_reason: path::unreachable_by_reason(&passes.unreachable),
                    impeller: *impeller,
                    linking,
                });
            }
            OperationDetails::Rough(_) => {}
            OperationDetails::ChannelRough(summary) => channel_summaries.push(*summary),
            OperationDetails::SemiFinish(summary) => semi_summaries.push(summary),
            OperationDetails::Finish {
                passes,
                linking,
                impeller,
            } => {
                if let Some(summary) = &impeller {
                    timings.impeller_first_passage = summary.first_passage_ms;
                    timings.impeller_copies = summary.copies_ms;
                }
                finishing = Some((passes, linking, impeller.map(|s| *s)))
            }
        }
    }
    let (finishing, link_report, impeller_finishing) = finishing.ok_or_else(|| {
        Error::JobFile(JobError::Operations(
            "the operations must end with finishing".into(),
        ))
    })?;
    let length = |kind: MoveKind| -> f64 {
        toolpath
            .moves
            .windows(2)
            .filter(|w| w[1].kind == kind)
            .map(|w| (w[1].pose.tip - w[0].pose.tip).norm())
            .sum()
    };
    let by_reason = path::unreachable_by_reason(&finishing.unreachable);
    if !toolpath.moves.iter().any(|m| m.kind == MoveKind::Cut) {
        let reasons: Vec<String> = by_reason.iter().map(|(r, n)| format!("{r}: {n}")).collect();
        return Err(Error::NothingToCut(format!(
            "{part_name}: none of the {} drive points can be machined{}",
            finishing.drive_points,
            if reasons.is_empty() {
                " (the part is smaller than the stepover, or the sections miss it)".to_string()
            } else {
                format!(" (unreachable: {})", reasons.join(", "))
            }
        )));
    }
    let finish = operations
        .iter()
        .rfind(|op| op.kind == OperationKind::Finish)
        .ok_or_else(|| {
            Error::JobFile(JobError::Operations(
                "a job needs a finishing operation".into(),
            ))
        })?;
    let stepover = path::planned_stepover(finish.tool.diameter / 2.0, finish.scallop_height);
    let report = PlanReport {
        wavemill_version: env!("CARGO_PKG_VERSION"),
        part: PartSummary {
            file: part_name.to_string(),
            units: units.to_string(),
            up: job.part.up,
            warnings: raw
                .warnings
                .iter()
                .cloned()
                .chain(set_aside_warning(&prepared.stray_pieces))
                .collect(),
            problems: prepared.mesh_report.problems(),
            mesh: prepared.mesh_report.clone(),
            stray_pieces: prepared.stray_pieces.clone(),
        },
        tool: ToolSummary {
            description: setup.tool.describe(),
            ball_radius_mm: job.tool.diameter / 2.0,
            shank_margin_mm: setup.margins.shank,
            holder_margin_mm: setup.margins.holder,
            assembly: setup.tool.clone(),
        },
        machine: MachineSummary {
            description: setup.kinematics.description(),
            pivot_in_part_frame: setup.pivot.coords.into(),
            safe_distance_mm: setup.safe_distance,
            table_z_mm: prepared.table_z,
            table_margin_mm: job.safety.table_margin,
            unwinds: linearised.unwinds.clone(),
            rapid_stops: linearised.rapid_stops.clone(),
        },
        surface,
        strategy: StrategySummary {
            kind: finishing_strategy(impeller_finishing.is_some()),
            scallop_height_mm: finish.scallop_height,
            stepover_mm: stepover,
            tolerance_mm: setup.finishing.tolerance,
            drive_planes: finishing.planes,
            drive_points: finishing.drive_points,
            refinement_poses: finishing.inserted_poses,
            splits_at_unreachable: finishing.splits_at_unreachable,
            splits_at_refinement: finishing.splits_at_refinement,
            backward_poses_dropped: finishing.backward_poses_dropped,
            lead_deg: job.strategy.lead_deg,
            tilt_deg: job.strategy.tilt_deg,
            axis_smoothing: AxisSmoothingSummary {
                max_change_deg_per_mm: job.strategy.max_axis_change_deg_per_mm,
                window_mm: job.strategy.axis_smoothing_window_mm,
                max_rate_before_deg_per_mm: finishing.smoothing.max_rate_before,
                max_rate_after_deg_per_mm: finishing.smoothing.max_rate_after,
                moves_over_bound_before: finishing.smoothing.moves_over_bound_before,
                moves_over_bound: finishing.smoothing.moves_over_bound,
            },
        },
        impeller_finishing,
        corner_finishing,
        not_an_impeller: impeller.as_ref().and_then(|r| r.as_ref().err().cloned()),
        impeller: impeller.and_then(|r| r.ok()),
        stock_to_leave: semi_summaries,
        roughing: roughing.into_iter().map(|r| r.summary).collect(),
        channel_roughing: channel_summaries,
        rapids_fed_through_rest: rapids_fed,
        ball_feed_control,
        poses: pose_counts(&toolpath),
        cutting_length_mm: length(MoveKind::Cut),
        approach_length_mm: length(MoveKind::Approach),
        rapid_length_mm: length(MoveKind::Rapid),
        estimated_time: TimeSummary {
            total_s: time.total_s(),
            by_kind: time,
        },
        clearance: verification,
        tolerance_budget: *budget,
        posted,
        unreachable: UnreachableSummary {
            count: finishing.unreachable.len(),
            by_reason,
            first_points: finishing
                .unreachable
                .iter()
                .take(100)
                .map(|(p, _)| p.coords.into())
                .collect(),
        },
        finish_scallop_colours: scallop_map
            .as_ref()
            .map(|(_, target)| super::scallop_picture::scallop_legend(*target)),
        finish_scallop,
        linking: link_report,
        nc_blocks: program.len(),
        stock: stock_run.as_ref().map(|run| run.report.clone()),
        timings_ms: Some(timings),
    };
    Ok(PlanOutput {
        part: prepared.part,
        toolpath,
        operations: spans,
        gcode,
        cl_csv,
        cl_apt,
        report,
        preview_glb,
        scallop_pictures,
        stock_models: stock_run.map(|run| run.models).unwrap_or_default(),
        verification_failure,
    })
}

/// The impeller in `part`, or why it is not one (`None` when the job does not look). With
/// `[impeller]` keys given, a part that does not match them is an error naming them.
fn recognise_impeller(
    part: &crate::mesh::Mesh,
    part_name: &str,
    job: &Job,
) -> Result<Option<std::result::Result<crate::impeller::Impeller, String>>> {
    if !job.impeller.recognise {
        return Ok(None);
    }
    let options = crate::impeller::RecogniseOptions {
        axis: job.impeller.axis,
        order: job.impeller.blades,
        ..Default::default()
    };
    match crate::impeller::recognise(part, &options) {
        Ok(found) => Ok(Some(Ok(found))),
        Err(reason) if job.impeller.is_given() => Err(Error::JobFile(JobError::Invalid {
            key: "impeller".into(),
            reason: format!("{part_name} does not match the [impeller] given: {reason}"),
        })),
        Err(reason) => Ok(Some(Err(reason.to_string()))),
    }
}

/// The post stage: `toolpath` linearised for `setup`'s machine within the budget's
/// linearisation share (bounding the ball centre, not the tip), and the program written with
/// `header` in the machine's dialect and output mode. Returns the machine blocks and the
/// program text.
pub fn post_program(
    setup: &PlanSetup,
    toolpath: &Toolpath,
    header: &ProgramHeader,
) -> Result<(Vec<(Move, Joints)>, String)> {
    post_program_with_tool_changes(setup, toolpath, &[], header, setup.tool.total_length())
}

/// A tool change within a program: at move `at` of the toolpath, to the tool of `header`.
#[derive(Clone, Debug, PartialEq)]
pub struct ToolChange {
    pub at: usize,
    pub header: ProgramHeader,
    /// The new tool's gauge length (tip to the holder's top), mm: machines with head axes carry
    /// it in joint output.
    pub gauge_length: f64,
}

/// Where the plan's program changes tools: at the start of every roughing operation after
/// the first (each roughing tool's moves stand apart in the program, for its check), at the
/// first ball operation after roughing, and where a ball operation's ball is another (a
/// corner finish's); a ball's change sets its centre as the control point.
fn tool_changes(
    job: &Job,
    spans: &[OperationSpan],
    operations: &[Operation],
    tools: &[crate::tool::ToolAssembly],
) -> Vec<ToolChange> {
    let mut changes = Vec::new();
    for k in 1..operations.len() {
        let (before, now) = (&operations[k - 1], &operations[k]);
        if now.kind.is_roughing() || before.kind.is_roughing() || tools[k].id != tools[k - 1].id {
            let tool = &tools[k];
            changes.push(ToolChange {
                at: spans[k].moves.start,
                header: ProgramHeader {
                    tool_description: vec![tool.describe()],
                    tool_number: tool.id,
                    spindle_rpm: if now.kind.is_roughing() {
                        job.roughing.spindle_rpm
                    } else {
                        now.tool.spindle_rpm
                    },
                    control_point_mm: (!now.kind.is_roughing()).then(|| now.tool.diameter / 2.0),
                    ..Default::default()
                },
                gauge_length: tool.total_length(),
            });
        }
    }
    changes
}

/// [`post_program`] for a program with tool changes: each tool's moves linearised on their
/// own and written after a tool change ([`post::ProgramSink::tool_change`]) at the safe plane,
/// where every operation starts and ends.
pub fn post_program_with_tool_changes(
    setup: &PlanSetup,
    toolpath: &Toolpath,
    changes: &[ToolChange],
    header: &ProgramHeader,
    first_gauge_length: f64,
) -> Result<(Vec<(Move, Joints)>, String)> {
    let linearised = linearise_program(setup, toolpath, changes, first_gauge_length, &[], None)?;
    Ok(write_program(setup, &linearised, changes, header))
}

/// A program's moves as the machine runs them: the toolpath (with the unwinds the machine's
/// limits needed) and its machine blocks, section by section between tool changes.
#[derive(Clone, Debug)]
pub struct LinearisedProgram {
    /// The toolpath with the unwinds inserted; the input's where there were none.
    pub toolpath: Toolpath,
    /// For each move of `toolpath`, its index in the input; `None` for an unwind's moves.
    pub origin: Vec<Option<usize>>,
    /// The poses the program unwinds at (retract, turn on the safe plane, re-plunge), as
    /// indices in `toolpath`.
    pub unwinds: Vec<usize>,
    /// Stops on the safe plane inserted partway along rapids for the rotaries to turn in
    /// place, as indices in `toolpath`.
    pub rapid_stops: Vec<usize>,
    /// How many moves the input had.
    inputs: usize,
    /// The machine blocks of each section (the moves before the first tool change, then
    /// after each).
    sections: Vec<Vec<(Move, Joints)>>,
}

impl LinearisedProgram {
    /// Where each move of the input toolpath went (and, last, the input's length: the new
    /// length). A move an unwind replaced maps to the next that is still there.
    pub fn new_index(&self) -> Vec<usize> {
        let mut new = vec![None; self.inputs + 1];
        new[self.inputs] = Some(self.toolpath.moves.len());
        for (n, o) in self.origin.iter().enumerate() {
            if let Some(o) = o {
                new[*o] = Some(n);
            }
        }
        let mut next = self.toolpath.moves.len();
        let mut out = vec![0; self.inputs + 1];
        for (o, n) in new.iter().enumerate().rev() {
            next = n.unwrap_or(next);
            out[o] = next;
        }
        out
    }
}

/// What [`linearise_program`] does to an unwind's moves (from the exit move, with the
/// section's ball) before they go in: feeds the rapids that would drive into the rest.
pub type IntoRest<'a> = dyn Fn(&Move, &mut Vec<Move>, &PreparedTool) + 'a;

/// Most cut poses walked back from where a limit stopped a pass, looking for one the tool can
/// leave along its axis (each a swept-body check).
const UNWIND_SEARCH_POSES: usize = 400;

/// A first cut shorter than this (between ball centres, mm) is not halved for an unwind.
const MIN_UNWIND_SPLIT_MM: f64 = 0.01;

/// The post's first half: `toolpath` linearised for `setup`'s machine, each section between
/// tool changes on its own with its tool's gauge length, in the output mode's kinematics.
/// In the sections `unwind[k]` names a ball for (the job's, or a corner finish's: its centre
/// the control point, its bodies checked on the way out), where no branch or turn of the
/// rotary axes carries a pass within the machine's limits, the program unwinds: the tool
/// leaves along its axis from the last cut pose before the limit that it can leave without
/// touching the part (the link's exact swept-body check, [`path::relink`]), the rotaries
/// turn in place on the safe plane, and the tool comes back down to that pose (or to the next
/// segment's entry, where a short link was to take it there); a rapid on the safe plane that a
/// limit stops gets a stop halfway ([`path::safe_midpoint`]).
pub fn linearise_program(
    setup: &PlanSetup,
    toolpath: &Toolpath,
    changes: &[ToolChange],
    first_gauge_length: f64,
    unwind: &[Option<&PreparedTool>],
    into_rest: Option<&IntoRest<'_>>,
) -> Result<LinearisedProgram> {
    // The flutes' top too: they may touch the part (and dip the tolerance on a swarf run),
    // and 0.1° of axis is 0.014 mm at the top of 8 mm of flutes.
    let linearise_for = |tool: &PreparedTool| {
        LineariseOptions::default()
            .with_tolerance_mm(setup.budget.linearisation_mm)
            .with_control_point_mm(tool.ball_radius)
            .with_flutes_above_control_mm(
                tool.flutes_above_ball().map_or(0.0, |(length, _)| length),
            )
    };
    let tcp = setup.gcode_options.output == post::OutputMode::Tcp;
    let mut starts: Vec<usize> = std::iter::once(0)
        .chain(changes.iter().map(|c| c.at))
        .collect();
    starts.push(toolpath.moves.len());
    let mut out = LinearisedProgram {
        toolpath: Toolpath {
            tool_id: toolpath.tool_id,
            moves: Vec::with_capacity(toolpath.moves.len()),
        },
        origin: Vec::with_capacity(toolpath.moves.len()),
        unwinds: Vec::new(),
        rapid_stops: Vec::new(),
        inputs: 0,
        sections: Vec::with_capacity(starts.len() - 1),
    };
    for (k, window) in starts.windows(2).enumerate() {
        let section = Toolpath {
            tool_id: toolpath.tool_id,
            moves: toolpath.moves[window[0]..window[1]].to_vec(),
        };
        let gauge = match k {
            0 => first_gauge_length,
            k => changes[k - 1].gauge_length,
        };
        let kinematics = setup.kinematics.with_gauge_length(gauge);
        let ball = unwind.get(k).copied().flatten();
        let linearise = linearise_for(ball.unwrap_or(&setup.prepared_tool));
        let mut hook = |moves: &[Move], start: usize, stop: usize| {
            let ball = ball?;
            // A rapid between two poses on the safe plane: a stop halfway, where the rotaries
            // turn in place (halved again while the limit still stops one of the halves).
            if stop >= 1
                && moves[stop].kind == MoveKind::Rapid
                && moves[stop - 1].kind == MoveKind::Rapid
            {
                return path::safe_midpoint(&setup.link, &moves[stop - 1], &moves[stop]).map(
                    |stop_move| post::Splice {
                        after: stop - 1,
                        replacing: 0,
                        moves: vec![stop_move],
                    },
                );
            }
            // An unwind from the last cut pose before the stop that the tool can leave along
            // its axis: back down to the same pose when the cut goes on from there, or to the
            // next segment's entry when a short link (lifted or across) was to take it there.
            let splice = |at: usize| {
                let next = (at + 1..moves.len()).find(|&i| {
                    matches!(
                        moves[i].kind,
                        MoveKind::Cut | MoveKind::Approach | MoveKind::Rapid
                    )
                })?;
                let entry = match moves[next].kind {
                    MoveKind::Cut if next == at + 1 => &moves[at].pose,
                    MoveKind::Approach => &moves[next].pose,
                    _ => return None,
                };
                let replacing = if entry == &moves[at].pose {
                    0
                } else {
                    next - at
                };
                path::relink(&setup.collider, ball, &setup.link, &moves[at].pose, entry).map(
                    |mut unwind| {
                        // Back down through what the roughing left, it feeds.
                        if let Some(into_rest) = into_rest {
                            into_rest(&moves[at], &mut unwind, ball);
                        }
                        post::Splice {
                            after: at,
                            replacing,
                            moves: unwind,
                        }
                    },
                )
            };
            let unwound = (start + 1..stop)
                .rev()
                .filter(|&at| moves[at].kind == MoveKind::Cut)
                .take(UNWIND_SEARCH_POSES)
                .find_map(splice);
            if unwound.is_some() {
                return unwound;
            }
            // The pass stopped in its first cut (near the pole a move turning the axis a few
            // degrees can turn a rotary by tens, from a start where no other branch is
            // within the limits): an unwind half-way along it, where the rotaries may have
            // come within reach of another branch. The pose there is on the move, as the
            // control would pass it; the linearisation asks again, halving, while it stops.
            let (from, to) = (moves.get(stop.checked_sub(1)?)?, &moves[stop]);
            let centre = |m: &Move| m.pose.tip + m.pose.axis.into_inner() * ball.ball_radius;
            if to.kind != MoveKind::Cut
                || !matches!(from.kind, MoveKind::Cut | MoveKind::Approach)
                || (centre(to) - centre(from)).norm() < MIN_UNWIND_SPLIT_MM
            {
                return None;
            }
            let axis = Direction::new_normalize(slerp(&from.pose.axis, &to.pose.axis, 0.5));
            let middle = Move {
                pose: ToolPose {
                    tip: nalgebra::center(&centre(from), &centre(to))
                        - axis.into_inner() * ball.ball_radius,
                    axis,
                },
                kind: MoveKind::Cut,
                feed: to.feed,
            };
            let mut unwind = path::relink(
                &setup.collider,
                ball,
                &setup.link,
                &middle.pose,
                &middle.pose,
            )?;
            if let Some(into_rest) = into_rest {
                into_rest(&middle, &mut unwind, ball);
            }
            unwind.insert(0, middle);
            Some(post::Splice {
                after: stop - 1,
                replacing: 0,
                moves: unwind,
            })
        };
        let unwound = if tcp {
            post::linearise_unwinding(
                &post::ToolCentrePoint(&kinematics),
                &section,
                &linearise,
                &mut hook,
            )?
        } else {
            post::linearise_unwinding(&kinematics, &section, &linearise, &mut hook)?
        };
        let offset = out.toolpath.moves.len();
        for &at in &unwound.inserted_after {
            match unwound.moves.get(at + 1).map(|m| m.kind) {
                Some(MoveKind::Retract) => out.unwinds.push(offset + at),
                _ => out.rapid_stops.push(offset + at + 1),
            }
        }
        out.inputs += section.moves.len();
        out.origin
            .extend(unwound.origin.iter().map(|o| o.map(|o| window[0] + o)));
        out.toolpath.moves.extend(unwound.moves);
        out.sections.push(unwound.blocks);
    }
    Ok(out)
}

/// The post's second half: the blocks of `linearised` written with `header` in the machine's
/// dialect and output mode, a tool change before each section after the first. Returns the
/// machine blocks and the program text.
pub fn write_program(
    setup: &PlanSetup,
    linearised: &LinearisedProgram,
    changes: &[ToolChange],
    header: &ProgramHeader,
) -> (Vec<(Move, Joints)>, String) {
    let mut options = setup.gcode_options.clone();
    options.control_point_mm = setup.prepared_tool.ball_radius;
    let tcp = options.output == post::OutputMode::Tcp;
    let mut writer: Box<dyn post::ProgramSink> = match options.dialect {
        post::Dialect::Heidenhain => {
            Box::new(post::HeidenhainWriter::new(&setup.kinematics, options))
        }
        _ if tcp => Box::new(post::GcodeWriter::new(
            &post::ToolCentrePoint(&setup.kinematics),
            options,
        )),
        _ => Box::new(post::GcodeWriter::new(&setup.kinematics, options)),
    };
    let mut program = Vec::new();
    for (k, blocks) in linearised.sections.iter().enumerate() {
        match k {
            0 => writer.begin(header),
            k => writer.tool_change(&changes[k - 1].header),
        }
        for (m, j) in blocks {
            writer.motion(m, j);
        }
        program.extend_from_slice(blocks);
    }
    writer.end();
    (program, writer.finish())
}

/// What the finishing ran: the impeller's own strategies (`impeller`) or the parallel planes.
fn finishing_strategy(impeller: bool) -> &'static str {
    if impeller {
        "impeller: hub flow lines, blade and splitter loops, swarf where ruled, parallel planes for the rest"
    } else {
        "parallel-plane ball-end finishing"
    }
}

/// Why `operation`, a corner finish, cannot run on the part (`impeller`: what recognising it
/// found), if it cannot: it runs along the roots the impeller strategies finish.
fn corner_refusal(
    operation: &Operation,
    part_name: &str,
    job: &Job,
    impeller: &Option<std::result::Result<Impeller, String>>,
) -> Option<Error> {
    if operation.kind != OperationKind::CornerFinish {
        return None;
    }
    let why = match impeller {
        Some(Ok(_)) if job.impeller.finishing => return None,
        Some(Ok(_)) => "the impeller strategies are off ([impeller] finishing = false)".to_string(),
        Some(Err(why)) => format!("{part_name} was not recognised as an impeller ({why})"),
        None => {
            format!("{part_name} was not looked at as an impeller ([impeller] recognise = false)")
        }
    };
    Some(Error::JobFile(JobError::Operations(format!(
        "operation '{}': corner finishing runs along an impeller's blade and splitter roots, \
         and {why}",
        operation.name
    ))))
}

/// How far from each root a corner finish runs: a stepover of its ball past where the
/// finishing ball's passes touch, which is the finishing ball's radius from a square root's
/// corner.
fn corner_band(job: &Job, corner: &Operation) -> f64 {
    job.tool.diameter / 2.0
        + path::planned_stepover(corner.tool.diameter / 2.0, corner.scallop_height)
}

/// The program header: what was planned (`impeller`: the finishing ran the impeller's own
/// strategies), with which tool, and the tolerance budget.
pub fn program_header(
    prepared: &PreparedPart,
    job: &Job,
    setup: &PlanSetup,
    operations: &[Operation],
    impeller: bool,
) -> ProgramHeader {
    let budget = &setup.budget;
    let mut header = ProgramHeader {
        program_name: format!("wavemill finishing of {}", prepared.name),
        part_name: prepared.name.clone(),
        tool_description: vec![setup.tool.describe()],
        tool_number: setup.tool.id,
        spindle_rpm: job.tool.spindle_rpm,
        coolant: true,
        control_point_mm: None,
        comments: vec![
            format!(
                "{}, scallop {} mm, tolerance {} mm",
                finishing_strategy(impeller),
                operations
                    .iter()
                    .rfind(|op| op.kind == OperationKind::Finish)
                    .map_or(job.strategy.scallop_height, |op| op.scallop_height),
                job.strategy.tolerance
            ),
            format!(
                "safe plane {:.3} mm from the pivot along the tool axis",
                setup.safe_distance
            ),
        ],
    };
    let semi: Vec<&Operation> = operations
        .iter()
        .filter(|op| op.kind == OperationKind::SemiFinish)
        .collect();
    if let Some(first) = semi.first() {
        header.comments.insert(
            0,
            format!(
                "first semi-finishing to stock-to-leave shapes of {} mm, scallop {} mm",
                semi.iter()
                    .map(|op| op.stock_to_leave.to_string())
                    .collect::<Vec<_>>()
                    .join(", "),
                first.scallop_height
            ),
        );
    }
    if let Some(corner) = operations
        .iter()
        .find(|op| op.kind == OperationKind::CornerFinish)
    {
        header.comments.push(format!(
            "then corner finishing with T{} (ball D{}) within {:.3} mm of the roots, where the \
             finishing left more than {} mm",
            corner.tool.id,
            corner.tool.diameter,
            corner_band(job, corner),
            corner.scallop_height
        ));
    }
    header.comments.push(format!(
        "tolerance {} mm = chord {:.4} + linearisation {:.4} + rounding {:.4} + verification 2 x {:.4}",
        budget.total_mm,
        budget.chord_mm,
        budget.linearisation_mm,
        budget.rounding_mm,
        budget.verification_mm
    ));
    header
}

/// What the back-simulation of the posted program found wrong, if anything: a feed move
/// deeper into the part than the tolerance, a rapid closer than `rapid_margin`, a program
/// structure problem, or a program the reader could not take.
fn posted_failure(
    posted: &std::result::Result<PostedClearance, crate::verify::ProgramError>,
    budget: &ToleranceBudget,
    rapid_margin: f64,
    fastest_planned_feed: f64,
) -> Option<String> {
    let posted = match posted {
        Ok(p) => p,
        Err(e) => return Some(format!("the posted program cannot be read back: {e}")),
    };
    let mut problems = posted.problems.clone();
    if posted.min_feed_clearance_mm < -budget.total_mm {
        problems.push(format!(
            "a posted move cuts {:.6} mm into the part at line {} of job.nc (tolerance {})",
            -posted.min_feed_clearance_mm, posted.min_feed_line, budget.total_mm
        ));
    }
    if let Some(flutes) = &posted.flutes {
        if flutes.min_feed_clearance_mm < -budget.total_mm {
            problems.push(format!(
                "a posted move's flutes cut {:.6} mm into the part at line {} of job.nc \
                 (tolerance {})",
                -flutes.min_feed_clearance_mm, flutes.min_feed_line, budget.total_mm
            ));
        }
        if flutes.min_rapid_clearance_mm < rapid_margin {
            problems.push(format!(
                "a rapid's flutes pass {:.6} mm from the part at line {} of job.nc (they must \
                 keep the shank margin {rapid_margin} mm)",
                flutes.min_rapid_clearance_mm, flutes.min_rapid_line
            ));
        }
    }
    if posted.min_rapid_clearance_mm < rapid_margin {
        problems.push(format!(
            "a rapid passes {:.6} mm from the part at line {} of job.nc (it must keep the shank \
             margin {rapid_margin} mm)",
            posted.min_rapid_clearance_mm, posted.min_rapid_line
        ));
    }
    // Inverse time: the F words, read back, must not drive the ball faster than planned (0.1 %
    // for the F word's rounding).
    if let Some((feed, line)) = posted.fastest_part_feed
        && feed > 1.001 * fastest_planned_feed
    {
        problems.push(format!(
            "an inverse-time block moves the ball at {feed:.1} mm/min relative to the part at \
             line {line} of job.nc, faster than the fastest planned feed {fastest_planned_feed} \
             mm/min"
        ));
    }
    (!problems.is_empty()).then(|| problems.join("; "))
}

fn pose_counts(path: &Toolpath) -> PoseCounts {
    let mut c = PoseCounts {
        total: path.moves.len(),
        ..Default::default()
    };
    for m in &path.moves {
        match m.kind {
            MoveKind::Rapid => c.rapid += 1,
            MoveKind::Approach => c.approach += 1,
            MoveKind::Cut => c.cut += 1,
            MoveKind::Retract => c.retract += 1,
        }
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::{Move, Point3};
    use crate::mesh::fixtures::cuboid;

    fn plan_block() -> PlanOutput {
        // A 30 x 30 x 10 block: the top is reachable straight down, the sides with the axis
        // tilted, the bottom stands on the table. Finishing only: the block is taken as roughed.
        let mut job = Job::default();
        job.stock.blank = None;
        job.strategy.scallop_height = 0.5;
        job.strategy.max_step = 3.0;
        let raw = RawMesh {
            mesh: cuboid(30.0, 30.0, 10.0),
            warnings: Vec::new(),
        };
        plan(&raw, "block", "mm", &job, &Quiet).unwrap()
    }

    /// A corner finish runs along an impeller's roots: on a part that is none it is refused,
    /// saying why, before anything is planned; so it is with the impeller strategies off.
    #[test]
    fn a_corner_finish_of_a_part_that_is_no_impeller_is_refused() {
        let mut job = Job::default();
        job.stock.blank = None;
        job.strategy.scallop_height = 0.5;
        job.corner_tool = Some(super::super::config::ToolSection {
            id: 20,
            diameter: 2.0,
            ..Default::default()
        });
        let raw = RawMesh {
            mesh: cuboid(30.0, 30.0, 10.0),
            warnings: Vec::new(),
        };
        let e = plan(&raw, "block", "mm", &job, &Quiet)
            .err()
            .expect("refused")
            .to_string();
        assert!(
            e.contains("operation 'corner-finish'")
                && e.contains("block was not recognised as an impeller"),
            "{e}"
        );
        job.impeller.recognise = false;
        let e = plan(&raw, "block", "mm", &job, &Quiet)
            .err()
            .expect("refused")
            .to_string();
        assert!(e.contains("block was not looked at as an impeller"), "{e}");
    }

    /// A part with subdivision connectivity drives as it is; any other is remeshed to its
    /// hierarchy's finest level within the tolerance, unless remeshing is off.
    #[test]
    fn drive_surface_is_the_part_when_semi_regular_else_its_finest_level() {
        let sphere = crate::mesh::fixtures::uv_sphere(10.0, 24, 48);
        let settings = SurfaceSection {
            tolerance: 0.02,
            base_triangles: 300,
            // Coarse enough that the tolerance needs levels above the base.
            base_max_error: Some(1.0),
            ..SurfaceSection::default()
        };
        let (drive, summary) = drive_surface(&sphere, &settings).unwrap();
        assert!(matches!(drive, Cow::Owned(_)));
        assert_eq!(summary.source, "hierarchy finest level");
        assert_eq!(summary.triangles, drive.triangles.len());
        assert!(summary.tolerance_reached && summary.hausdorff_to_part_mm <= 0.02);
        assert!(summary.hierarchy_levels >= 2, "{summary:?}");

        // The finest level is semi-regular itself: it drives as it is.
        let finest = drive.into_owned();
        let (again, summary) = drive_surface(&finest, &settings).unwrap();
        assert!(matches!(again, Cow::Borrowed(_)));
        assert_eq!(summary.source, "part (semi-regular)");
        assert!(summary.part_subdivision_levels >= 1);
        let off = SurfaceSection {
            remesh: false,
            ..settings
        };
        let (same, summary) = drive_surface(&sphere, &off).unwrap();
        assert!(matches!(same, Cow::Borrowed(_)));
        assert_eq!(summary.source, "part (remeshing off)");
    }

    #[test]
    fn a_block_is_machined_on_top_and_sides_and_refused_underneath() {
        let out = plan_block();
        let r = &out.report;
        assert!(
            out.verification_failure.is_none(),
            "{:?}",
            out.verification_failure
        );
        assert!(r.poses.cut > 100);
        // Cut poses on the top face: the ball (r = 2) centred 2 mm above it.
        let radius = Job::default().tool.diameter / 2.0;
        let top = out
            .toolpath
            .moves
            .iter()
            .filter(|m| {
                m.kind == MoveKind::Cut
                    && ((m.pose.tip + m.pose.axis.into_inner() * radius).z - 12.0).abs() < 1e-6
            })
            .count();
        assert!(top > 20, "{top}");
        // Everything unreachable is underneath (table) or hugging it.
        assert!(
            r.unreachable.by_reason.keys().all(|k| k == "table"),
            "{:?}",
            r.unreachable.by_reason
        );
        assert!(
            r.clearance.min_cutter_clearance >= -1e-9
                && r.clearance.min_table_clearance.is_some_and(|c| c >= 2.0)
        );
    }

    /// Semi-finishing to two stock-to-leave shapes, then finishing: the report names the
    /// shapes, and every semi-finishing ball centre is, by an independent brute-force distance
    /// to the part's triangles, at least r + aⱼ − tolerance from it.
    #[test]
    fn semi_finishing_leaves_the_stock_of_each_shape() {
        let mut job = Job::default();
        job.stock.blank = None;
        job.strategy.scallop_height = 0.5;
        job.strategy.max_step = 3.0;
        job.strategy.semi_finish_allowances = vec![1.0, 0.3];
        job.strategy.semi_finish_scallop_height = 0.5;
        let part = cuboid(30.0, 30.0, 10.0);
        let raw = RawMesh {
            mesh: part.clone(),
            warnings: Vec::new(),
        };
        let out = plan(&raw, "block", "mm", &job, &Quiet).unwrap();
        assert!(
            out.verification_failure.is_none(),
            "{:?}",
            out.verification_failure
        );
        let stock = &out.report.stock_to_leave;
        assert_eq!(stock.len(), 2);
        for (j, s) in stock.iter().enumerate() {
            // Shape j offsets level j, or the finest when the hierarchy is shallower (a block
            // is exact on its base).
            assert!(s.level <= j);
            assert!(s.shape_verified && s.segments > 0, "{s:?}");
            assert!(s.min_stock_left_minus_allowance_mm >= -job.strategy.tolerance);
        }
        let allowances: Vec<f64> = out.operations.iter().map(|o| o.stock_to_leave_mm).collect();
        assert_eq!(allowances, [1.0, 0.3, 0.0]);
        assert_eq!(
            out.operations.last().unwrap().moves.end,
            out.toolpath.moves.len()
        );
        let radius = job.tool.diameter / 2.0;
        let distance = |p: &Point3| {
            (0..part.triangles.len())
                .map(|t| {
                    let [a, b, c] = part.corners(t);
                    (crate::geom::closest_point_on_triangle(p, &a, &b, &c).0 - p).norm()
                })
                .fold(f64::INFINITY, f64::min)
        };
        for operation in &out.operations[..2] {
            let cuts: Vec<&Move> = out.toolpath.moves[operation.moves.clone()]
                .iter()
                .filter(|m| m.kind == MoveKind::Cut)
                .collect();
            assert!(cuts.len() > 20);
            let closest = cuts
                .iter()
                .map(|m| distance(&(m.pose.tip + m.pose.axis.into_inner() * radius)))
                .fold(f64::INFINITY, f64::min);
            assert!(
                closest >= radius + operation.stock_to_leave_mm - job.strategy.tolerance,
                "{closest}"
            );
        }
    }

    #[test]
    fn a_path_that_fails_verification_writes_only_its_report() {
        let mut out = plan_block();
        out.verification_failure = Some("ball gouges the part by 0.1 mm".into());
        let dir = std::env::temp_dir().join(format!("wavemill-verify-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let err = super::super::write_outputs(&dir, &out, false).unwrap_err();
        assert_eq!(err.exit_code(), 3);
        assert!(err.to_string().contains("gouges"));
        assert!(dir.join("report.json").is_file());
        for f in ["job.nc", "cl.csv", "paths.glb"] {
            assert!(!dir.join(f).exists(), "{f} written for a failed path");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
