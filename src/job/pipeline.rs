//! The plan pipeline: prepare the part, build the collision structures, drive the finishing
//! passes, link, verify, post, preview. Each stage is a plain function of the stage before;
//! this file only wires them and times them.

use std::borrow::Cow;
use std::path::Path;
use std::time::Instant;

use super::budget::ToleranceBudget;
use super::config::{Job, SurfaceSection};
use super::preview::preview;
use super::report::*;
use super::semi_finish::{SemiFinishContext, semi_finishing};
use crate::access::RayScene;
use crate::collide::{Margins, PartCollider, PreparedTool, Table};
use crate::error::{Error, Result};
use crate::geom::{Move, MoveKind, Point3, ToolPose, Toolpath, Vector3, positive_zero};
use crate::mesh::io::{RawMesh, Units, read_mesh};
use crate::mesh::{Mesh, PrepareOptions, prepare_without_stray_pieces, set_aside_warning};
use crate::multires::Hierarchy;
use crate::orient::{AxisChooser, AxisOptions, SmoothingOptions};
use crate::path::{self, FinishingContext, FinishingOptions, LinkOptions};
use crate::post::{
    self, GcodeOptions, LineariseOptions, MachineKinematics, ProgramHeader, TableTableAC,
};
use crate::verify::{MachineModel, PostedClearance, PostedOptions, check_posted, verify};

/// Hears about progress; the CLI shows it as progress bars, libraries can ignore it.
pub trait Observer: Sync {
    /// A stage starts; `work` units of [`Observer::advance`] will follow (0 if unknown).
    fn stage(&self, name: &str, work: u64);
    fn advance(&self);
    fn finish(&self);
}

/// An observer that ignores everything.
pub struct Quiet;

impl Observer for Quiet {
    fn stage(&self, _: &str, _: u64) {}
    fn advance(&self) {}
    fn finish(&self) {}
}

/// Everything a plan produces, in memory.
pub struct PlanOutput {
    /// The part as planned (welded, oriented).
    pub part: Mesh,
    pub toolpath: Toolpath,
    /// The operations of `toolpath`, in order: semi-finishing to each stock-to-leave shape,
    /// then finishing (stock to leave 0).
    pub operations: Vec<Operation>,
    pub gcode: String,
    pub cl_csv: String,
    pub report: PlanReport,
    pub preview_glb: Vec<u8>,
    /// What the independent re-check of the finished path found wrong, if anything. A path
    /// that fails must not be run; [`super::write_outputs`] then writes only the report.
    pub verification_failure: Option<String>,
}

/// One operation of a plan: the stock it leaves on the part and its moves in the toolpath.
#[derive(Clone, Debug, PartialEq)]
pub struct Operation {
    pub stock_to_leave_mm: f64,
    pub moves: std::ops::Range<usize>,
}

/// The surface the passes are driven on: the part when it already has subdivision
/// connectivity (or remeshing is off), else its hierarchy's finest level (DESIGN.md §3.2).
fn drive_surface<'a>(
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
pub fn load_part(path: &Path, units: &str) -> Result<RawMesh> {
    let units: Units = units
        .parse()
        .map_err(|e| Error::Usage(format!("units of {}: {e}", path.display())))?;
    let mut raw = read_mesh(path, units)?;
    if let Some(warning) = units_warning(&raw.mesh, units) {
        raw.warnings.push(warning);
    }
    Ok(raw)
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

fn ms(since: Instant) -> f64 {
    (since.elapsed().as_secs_f64() * 1e3 * 10.0).round() / 10.0
}

/// Plans 5-axis ball-end finishing of `raw` (already in mm) for `job`. `part_name` names the
/// part in errors, the report and the G-code header.
pub fn plan(
    raw: &RawMesh,
    part_name: &str,
    units: &str,
    job: &Job,
    observer: &dyn Observer,
) -> Result<PlanOutput> {
    job.validate().map_err(Error::Job)?;
    let started = Instant::now();
    let mut timings = StageTimings::default();
    let mesh_error = |reason: String| Error::Mesh {
        file: part_name.to_string(),
        reason,
    };

    let t = Instant::now();
    observer.stage("prepare part", 0);
    let upright = match job.part.up {
        Some(up) => turned_upright(
            &raw.mesh,
            &super::config::unit_direction(up).ok_or_else(|| {
                Error::Job(format!("part.up must be a non-zero vector, got {up:?}"))
            })?,
        ),
        None => raw.mesh.clone(),
    };
    // Debris (a lone far triangle, a sliver shell) is set aside and reported, not planned:
    // it would make the part open or stretch every size taken from its box (issue 17 item 8).
    let (part, mesh_report, stray_pieces) =
        prepare_without_stray_pieces(&upright, &PrepareOptions::default()).map_err(mesh_error)?;
    if !mesh_report.watertight {
        return Err(mesh_error(format!(
            "the part must be a closed, consistently oriented surface to tell inside from outside; found: {}",
            mesh_report.problems().join("; ")
        )));
    }
    timings.prepare = ms(t);
    check_drive_points(&mesh_report, job)?;
    let lowest = part.aabb().min.z;
    let table_z = job.machine.table_z.unwrap_or(lowest);
    if table_z > lowest + job.strategy.tolerance {
        return Err(Error::Job(format!(
            "machine.table_z {table_z} mm is above the part's lowest point (z = {lowest:.4} mm \
             after turning the part up): the part would stand inside the table"
        )));
    }

    let t = Instant::now();
    observer.stage("drive surface", 0);
    let (drive, surface) = drive_surface(&part, &job.surface).map_err(mesh_error)?;
    timings.drive_surface = ms(t);

    let t = Instant::now();
    observer.stage("collision structures", 0);
    let table = Table {
        top_z: table_z,
        margin: job.safety.table_margin,
    };
    let collider = PartCollider::new(&part)
        .map_err(mesh_error)?
        .with_table(table);
    let rays = RayScene::new(&part);
    timings.collision_structures = ms(t);

    let tool = job.tool.assembly();
    let margins = Margins {
        shank: job.safety.shank_margin,
        holder: job.safety.holder_margin,
    };
    let prepared = PreparedTool::new(&tool, &margins);
    // Unless told otherwise, the part is clamped centred on the C axis, standing on the table
    // at the pivot height: its footprint's centre and lowest point are the pivot.
    let part_box = part.aabb();
    let part_origin_in_table = job
        .machine
        .part_origin_in_table
        .map(Vector3::from)
        .unwrap_or_else(|| -Vector3::new(part_box.center().x, part_box.center().y, part_box.min.z))
        .map(positive_zero);
    let kinematics = machine(job, part_origin_in_table)?;
    let pivot = Point3::from(-part_origin_in_table);
    let reach = part
        .positions
        .iter()
        .map(|p| (p - pivot).norm())
        .fold(0.0, f64::max);
    let safe_distance = job
        .machine
        .safe_distance
        .unwrap_or(reach + job.machine.safe_margin);
    if safe_distance <= reach {
        return Err(Error::Job(format!(
            "machine.safe_distance {safe_distance} mm is inside the part's reach from the pivot ({reach:.3} mm)"
        )));
    }
    // Rounding is charged where the ball centre is farthest from the pivot: on the safe plane.
    let gcode_options = GcodeOptions::default();
    let budget = ToleranceBudget::split(
        job.strategy.tolerance,
        &gcode_options,
        safe_distance + prepared.ball_radius,
    )
    .map_err(Error::Job)?;

    let t = Instant::now();
    let chooser = AxisChooser::new(AxisOptions {
        lead_deg: job.strategy.lead_deg,
        tilt_deg: job.strategy.tilt_deg,
        max_deviation_deg: job.strategy.max_axis_deviation_deg,
        ..AxisOptions::default()
    });
    let reachable = |axis: &Vector3| {
        let pose = ToolPose {
            tip: pivot,
            axis: crate::geom::Direction::new_normalize(*axis),
        };
        kinematics.inverse(&pose, None).is_ok()
    };
    let ctx = FinishingContext {
        part: &collider,
        rays: &rays,
        tool: &prepared,
        chooser: &chooser,
        reachable: &reachable,
    };
    let options = FinishingOptions {
        drive_normal: Vector3::from(job.strategy.drive_normal),
        scallop_height: job.strategy.scallop_height,
        tolerance: budget.chord_mm,
        max_step: job.strategy.max_step,
        max_axis_turn_deg: job.strategy.max_axis_turn_deg,
        axis_smoothing: (job.strategy.max_axis_change_deg_per_mm > 0.0).then_some(
            SmoothingOptions {
                max_turn_deg_per_mm: job.strategy.max_axis_change_deg_per_mm,
                window_mm: job.strategy.axis_smoothing_window_mm,
            },
        ),
    };
    let link_options = LinkOptions {
        pivot,
        safe_distance,
        clearance: job.feeds.clearance,
        cut_feed: job.feeds.cut,
        approach_feed: job.feeds.approach,
        retract_feed: job.feeds.retract,
        rapid_feed: job.machine.rapid_feed,
        rapid_margin: job.safety.shank_margin,
    };
    let search = job.safety.holder_margin.max(job.safety.shank_margin) + 5.0;
    timings.finishing_passes = ms(t);

    let t = Instant::now();
    let allowances = &job.strategy.semi_finish_allowances;
    let semi = if allowances.is_empty() {
        None
    } else {
        observer.stage("stock-to-leave shapes and semi-finishing", 0);
        let semi_ctx = SemiFinishContext {
            part: &part,
            part_collider: &collider,
            table,
            tool: &prepared,
            tool_id: tool.id,
            chooser: &chooser,
            reachable: &reachable,
            finishing: &options,
            link: &link_options,
            shank_margin: margins.shank,
            holder_margin: margins.holder,
            search,
        };
        // As `wavemill offsets` does: shape j offsets level j of a hierarchy with one level
        // above the base per allowance, so the finest allowance is not on the coarsest level.
        let remesh = crate::multires::RemeshOptions {
            tolerance: 0.0,
            base_triangles: job.surface.base_triangles,
            base_max_error: None,
            max_levels: allowances.len() as u32,
            crease_angle_deg: job.surface.crease_angle_deg,
            ..Default::default()
        };
        Some(semi_finishing(
            &semi_ctx,
            &remesh,
            allowances,
            job.strategy.semi_finish_scallop_height,
            &|| observer.advance(),
        )?)
    };
    timings.semi_finishing = ms(t);

    let t = Instant::now();
    let stepover = path::stepover_for_scallop(job.tool.diameter / 2.0, options.scallop_height);
    let extent = part
        .aabb()
        .extent()
        .dot(&options.drive_normal.normalize())
        .abs();
    observer.stage(
        "finishing passes",
        (extent / stepover.max(1e-3)).ceil() as u64,
    );
    // Sections follow the drive surface; every pose is placed and checked against the part.
    let finishing = path::finishing_passes(&drive, &ctx, &options, &|| observer.advance());
    timings.finishing_passes += ms(t);

    let t = Instant::now();
    observer.stage("linking", 0);
    let (finishing_path, link_report) = path::link(
        &finishing.segments,
        &collider,
        &prepared,
        tool.id,
        &link_options,
    );
    // One program: the semi-finishing operations, coarsest first, then finishing. Each
    // operation starts and ends on the safe plane, as its segments do.
    let mut toolpath = Toolpath {
        tool_id: finishing_path.tool_id,
        moves: Vec::new(),
    };
    let mut operations = Vec::new();
    let mut append = |moves: &[Move], stock_to_leave_mm: f64| {
        let start = toolpath.moves.len();
        toolpath.moves.extend_from_slice(moves);
        operations.push(Operation {
            stock_to_leave_mm,
            moves: start..toolpath.moves.len(),
        });
    };
    for (operation, allowance) in semi.iter().flat_map(|s| &s.toolpaths).zip(allowances) {
        append(&operation.moves, *allowance);
    }
    append(&finishing_path.moves, 0.0);
    timings.linking = ms(t);

    let t = Instant::now();
    observer.stage("verification", 0);
    let verification = verify(&toolpath, &collider, &prepared, search);
    timings.verification = ms(t);
    let pose_failure = verification
        .passes(
            budget.chord_mm,
            job.safety.shank_margin,
            job.safety.holder_margin,
            job.safety.table_margin,
        )
        .err();

    let t = Instant::now();
    observer.stage("post-processing", 0);
    let mut header = ProgramHeader {
        program_name: format!("wavemill finishing of {part_name}"),
        part_name: part_name.to_string(),
        tool_description: vec![tool.describe()],
        tool_number: tool.id,
        spindle_rpm: job.tool.spindle_rpm,
        coolant: true,
        comments: vec![
            format!(
                "ball-end finishing along parallel planes, scallop {} mm, tolerance {} mm",
                job.strategy.scallop_height, job.strategy.tolerance
            ),
            format!("safe plane {safe_distance:.3} mm from the pivot along the tool axis"),
        ],
    };
    if !allowances.is_empty() {
        header.comments.insert(
            0,
            format!(
                "first semi-finishing to stock-to-leave shapes of {} mm, scallop {} mm",
                allowances
                    .iter()
                    .map(|a| a.to_string())
                    .collect::<Vec<_>>()
                    .join(", "),
                job.strategy.semi_finish_scallop_height
            ),
        );
    }
    header.comments.push(format!(
        "tolerance {} mm = chord {:.4} + linearisation {:.4} + rounding {:.4} + verification 2 x {:.4}",
        budget.total_mm,
        budget.chord_mm,
        budget.linearisation_mm,
        budget.rounding_mm,
        budget.verification_mm
    ));
    let linearise = LineariseOptions::default()
        .with_tolerance_mm(budget.linearisation_mm)
        .with_control_point_mm(prepared.ball_radius);
    let program = post::linearise_opt(&kinematics, &toolpath, &linearise)?;
    let mut writer = post::GcodeWriter::new(&kinematics, gcode_options);
    post::emit(&program, &header, &mut writer);
    let gcode = writer.into_string();
    let cl_csv = post::write_cl_csv(&toolpath);
    let time = post::estimate_time(&program, job.machine.max_rotary_speed);
    timings.post = ms(t);

    let t = Instant::now();
    observer.stage("back-simulation of the program", 0);
    let rapid_margin = job.safety.shank_margin;
    let posted = check_posted(
        &gcode,
        &MachineModel::TableTableAc {
            part_origin_in_table,
        },
        &part,
        &PostedOptions {
            ball_radius: prepared.ball_radius,
            feed_error_mm: budget.verification_mm,
            rapid_error_mm: (0.1 * rapid_margin).max(budget.verification_mm),
            search_mm: search,
        },
    );
    timings.back_simulation = ms(t);
    let verification_failure = pose_failure
        .or_else(|| posted_failure(&posted, &budget, rapid_margin))
        .or_else(|| semi.as_ref().and_then(|s| s.failure.clone()));
    let posted = posted.ok();

    let t = Instant::now();
    observer.stage("preview", 0);
    let preview_glb = preview(&part, &toolpath, 5.0, 2.0 * job.tool.diameter / 2.0 + 8.0)?;
    timings.preview = ms(t);
    timings.total = ms(started);
    observer.finish();

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
                .chain(set_aside_warning(&stray_pieces))
                .collect(),
            problems: mesh_report.problems(),
            mesh: mesh_report,
            stray_pieces,
        },
        tool: ToolSummary {
            description: tool.describe(),
            ball_radius_mm: job.tool.diameter / 2.0,
            shank_margin_mm: margins.shank,
            holder_margin_mm: margins.holder,
            assembly: tool.clone(),
        },
        machine: MachineSummary {
            description: kinematics.description(),
            pivot_in_part_frame: pivot.coords.into(),
            safe_distance_mm: safe_distance,
            table_z_mm: table_z,
            table_margin_mm: job.safety.table_margin,
        },
        surface,
        strategy: StrategySummary {
            kind: "parallel-plane ball-end finishing",
            scallop_height_mm: options.scallop_height,
            stepover_mm: stepover,
            tolerance_mm: options.tolerance,
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
        stock_to_leave: semi.map(|s| s.summaries).unwrap_or_default(),
        poses: pose_counts(&toolpath),
        cutting_length_mm: length(MoveKind::Cut),
        approach_length_mm: length(MoveKind::Approach),
        rapid_length_mm: length(MoveKind::Rapid),
        estimated_time: TimeSummary {
            total_s: time.total_s(),
            by_kind: time,
        },
        clearance: verification,
        tolerance_budget: budget,
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
        linking: link_report,
        nc_blocks: program.len(),
        timings_ms: Some(timings),
    };
    Ok(PlanOutput {
        part,
        toolpath,
        operations,
        gcode,
        cl_csv,
        report,
        preview_glb,
        verification_failure,
    })
}

/// What the back-simulation of the posted program found wrong, if anything: a feed move
/// deeper into the part than the tolerance, a rapid closer than `rapid_margin`, a program
/// structure problem, or a program the reader could not take.
fn posted_failure(
    posted: &std::result::Result<PostedClearance, crate::verify::ProgramError>,
    budget: &ToleranceBudget,
    rapid_margin: f64,
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
    if posted.min_rapid_clearance_mm < rapid_margin {
        problems.push(format!(
            "a rapid passes {:.6} mm from the part at line {} of job.nc (it must keep the shank \
             margin {rapid_margin} mm)",
            posted.min_rapid_clearance_mm, posted.min_rapid_line
        ));
    }
    (!problems.is_empty()).then(|| problems.join("; "))
}

/// Refuses a job whose finishing passes are estimated to have more drive points than
/// `limits.max_drive_points`, before any of the work. The planes are a stepover apart and each
/// section is sampled at most `max_step` apart, so a surface of area A has at least about
/// A / (stepover · max_step) drive points; the points where sections cross the drive surface's
/// edges come on top (measured: 2.8× the estimate on the sample impeller, 4.4× on the real
/// blower), so the estimate is a lower one and the limit is set with that in mind.
fn check_drive_points(mesh: &crate::mesh::MeshReport, job: &Job) -> Result<()> {
    let stepover = path::stepover_for_scallop(job.tool.diameter / 2.0, job.strategy.scallop_height);
    let estimate = mesh.surface_area / (stepover * job.strategy.max_step);
    let limit = job.limits.max_drive_points;
    if estimate > limit as f64 {
        return Err(Error::TooLarge {
            what: format!(
                "finishing {:.0} mm² at a {stepover:.4} mm stepover and {} mm steps",
                mesh.surface_area, job.strategy.max_step
            ),
            estimate: format!("{:.3e} drive points", estimate),
            limit: format!("{limit}"),
            how_to_raise: "check the part's units and the scallop height, or raise \
                           limits.max_drive_points"
                .into(),
        });
    }
    Ok(())
}

/// `mesh` turned so that the unit vector `up` points along +Z (the shortest rotation; 180° about X when `up`
/// points down).
fn turned_upright(mesh: &Mesh, up: &Vector3) -> Mesh {
    let rotation = nalgebra::Rotation3::rotation_between(up, &Vector3::z()).unwrap_or_else(|| {
        nalgebra::Rotation3::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI)
    });
    Mesh {
        positions: mesh.positions.iter().map(|p| rotation * p).collect(),
        triangles: mesh.triangles.clone(),
    }
}

/// The machine the job describes, with the part clamped at `part_origin_in_table`.
pub fn machine(job: &Job, part_origin_in_table: Vector3) -> Result<TableTableAC> {
    let m = &job.machine;
    let kin = TableTableAC::new(part_origin_in_table)
        .with_a_limits(m.a_limits[0], m.a_limits[1])
        .with_c_limits(m.c_limits.map(|[lo, hi]| (lo, hi)));
    kin.validate()?;
    Ok(kin)
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
    use crate::mesh::fixtures::cuboid;

    fn plan_block() -> PlanOutput {
        // A 30 x 30 x 10 block: the top is reachable straight down, the sides with the axis
        // tilted, the bottom stands on the table.
        let mut job = Job::default();
        job.strategy.scallop_height = 0.5;
        job.strategy.max_step = 3.0;
        let raw = RawMesh {
            mesh: cuboid(30.0, 30.0, 10.0),
            warnings: Vec::new(),
        };
        plan(&raw, "block", "mm", &job, &Quiet).unwrap()
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
            r.clearance.min_cutter_clearance >= -1e-9 && r.clearance.min_table_clearance >= 2.0
        );
    }

    /// Semi-finishing to two stock-to-leave shapes, then finishing: the report names the
    /// shapes, and every semi-finishing ball centre is, by an independent brute-force distance
    /// to the part's triangles, at least r + aⱼ − tolerance from it.
    #[test]
    fn semi_finishing_leaves_the_stock_of_each_shape() {
        let mut job = Job::default();
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
