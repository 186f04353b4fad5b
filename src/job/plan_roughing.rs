//! Roughing inside a plan: the job's `rough` and `rest-rough` operations, planned from its
//! `[stock]` blank before the ball operations, each with a library end mill along the
//! machine's vertical axis (A = 0), layer by layer down to the part's offset shape at the
//! operation's stock to leave ([`crate::rough`]).
//!
//! What is written is what is checked: after posting, each roughing tool's moves are read back
//! from the program (as the control interpolates them) and checked exactly against their
//! offset shape and the part ([`crate::rough::check`], sharing no code with the planning); the
//! stock run then runs them on the tri-dexel blank with each tool's whole assembly.

use std::sync::Arc;

use serde::Serialize;

use super::config::{Job, Operation, OperationKind};
use super::offsets::stock_shapes;
use super::rough_stages::{
    ToolLayers, ToolRoughing, first_rougher, layer_blank, next_rougher, rough_with_tool,
    split_at_tool_changes,
};
use super::setup::PlanSetup;
use super::stock_model::{blank_stock, default_resolution};
use crate::error::{Error, JobError, Result};
use crate::feed::{Cutter as FeedCutter, CuttingModel, FeedReport, control_feeds};
use crate::geom::{Move, MoveKind, Point3, Toolpath};
use crate::mesh::Mesh;
use crate::rough::boxes::box_clearance;
use crate::rough::check::{OvercutReport, overcuts};
use crate::rough::{LayerReport, NotReached, RoughingFeeds, RoughingTool};
use crate::stock::clearance::MaterialClearance;
use crate::stock::{DEFAULT_MAX_DEXELS, Stock};
use crate::tool::{ToolAssembly, ToolLibrary};

/// One roughing operation of a plan, for `report.json`.
#[derive(Clone, Debug, Serialize)]
pub struct RoughingSummary {
    pub operation: String,
    pub tool_id: u32,
    pub tool: String,
    /// Why this tool.
    pub chosen: String,
    pub planning: RoughingTool,
    /// `blank` for roughing, `rest` for rest-roughing (only where material stands).
    pub material: &'static str,
    /// What feed control made of the programmed feeds (`[cutting]`); `None` when off.
    pub feed_control: Option<crate::feed::FeedReport>,
    pub stock_to_leave_mm: f64,
    pub shape_triangles: usize,
    pub layers: Vec<LayerReport>,
    pub not_reached: Option<NotReached>,
    pub moves: usize,
    pub cutting_length_mm: f64,
    /// Indexed roughing: the setups proposed from the visibility maps, and what each cut.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub indexed: Option<IndexedSummary>,
    /// The tool's moves as read back from the posted program, against its offset shape and
    /// against the part (filled in after posting).
    pub overcut_vs_shape: Option<OvercutReport>,
    pub overcut_vs_part: Option<OvercutReport>,
}

/// What the indexed setups of an operation did, for `report.json`.
#[derive(Clone, Debug, Serialize)]
pub struct IndexedSummary {
    /// Rest above this much (mm off the part) counted for the proposal.
    pub rest_threshold_mm: f64,
    pub proposal: crate::rough::setups::Proposal,
    pub setups: Vec<SetupSummary>,
}

/// One indexed setup.
#[derive(Clone, Debug, Serialize)]
pub struct SetupSummary {
    /// Tool axis in the part frame, its tilt from the vertical, and the machine's rotary
    /// angles for it, degrees.
    pub axis: [f64; 3],
    pub tilt_deg: f64,
    pub rotary_deg: [f64; 2],
    /// Share of the rest's weight the proposal saw first from this setup.
    pub seen_share: f64,
    pub layers: Vec<LayerReport>,
    pub moves: usize,
    /// Taken off the planning stock, mm³.
    pub removed_mm3: f64,
    pub not_reached: Option<NotReached>,
}

/// A roughing operation, planned: its tool, its moves (from the safe plane back to it) and
/// the offset shape it roughs to, for the check of the posted program.
pub struct PlannedRoughing {
    pub tool: ToolAssembly,
    pub toolpath: Toolpath,
    /// What the layers stopped at: the offset shape, or the convex-hull boxes.
    pub bound: PlannedBound,
    pub summary: RoughingSummary,
}

/// What a roughing operation's layers stopped at, for the check of the posted program.
pub enum PlannedBound {
    Shape(Mesh),
    /// Every box after the splits, grown by the stock to leave (part frame).
    Boxes(Vec<crate::geom::Aabb>),
}

/// What the roughing operations of a plan share: the blank as layers and as a planning
/// stock model, the library and the offset shapes already built.
pub struct RoughingContext {
    pub(super) library: ToolLibrary,
    blank: crate::rough::Blank,
    pub(super) stock: Stock,
    floor: f64,
    shapes: Vec<(f64, Mesh)>,
    /// An IGES part's surfaces, for `hull-boxes` roughing, and their boxes once built.
    surfaces: Option<std::sync::Arc<super::cad_part::PartSurfaces>>,
    hull_boxes: Option<crate::cad::boxes::HullBoxes>,
    previous_diameter: Option<f64>,
    /// The end mill of the last roughing operation (what indexed setups cut with).
    pub(super) previous_tool: Option<ToolAssembly>,
    /// The planning stock as the roughing left it, before the first ball operation came off
    /// it: at least the material any ball move met.
    before_balls: Option<Stock>,
}

impl RoughingContext {
    /// The blank of `job` around `part` (as planned, the table's top at `table_z`), the
    /// planning stock model and the library.
    pub fn new(
        part: &Mesh,
        units: &str,
        job: &Job,
        table_z: f64,
        surfaces: Option<std::sync::Arc<super::cad_part::PartSurfaces>>,
    ) -> Result<Self> {
        let spec = job.stock.blank_spec()?.ok_or_else(|| {
            Error::JobFile(JobError::Operations(
                "roughing clears a blank: name one in [stock] (e.g. blank = \"cylinder\")".into(),
            ))
        })?;
        let spec = spec.resolved(part);
        let blank = layer_blank(&spec, part)?;
        let spacing = job
            .stock
            .resolution
            .unwrap_or_else(|| default_resolution(part));
        let stock = blank_stock(part, &spec, units, spacing, DEFAULT_MAX_DEXELS)?;
        // The tip keeps the table margin above the table, as every ball pose does.
        let floor = (table_z + job.safety.table_margin).max(part.aabb().min.z);
        Ok(RoughingContext {
            library: job.roughing.tool_library()?,
            blank,
            stock,
            floor,
            shapes: Vec::new(),
            surfaces,
            hull_boxes: None,
            previous_diameter: None,
            previous_tool: None,
            before_balls: None,
        })
    }

    /// The convex-hull boxes of the part's surfaces in the plan's frame (the part turned by
    /// `[part] up`), built once; an error naming the operation without surfaces.
    fn hull_boxes(&mut self, job: &Job, operation: &str) -> Result<&crate::cad::boxes::HullBoxes> {
        if self.hull_boxes.is_none() {
            let surfaces = self.surfaces.as_ref().ok_or_else(|| {
                Error::JobFile(JobError::Operations(format!(
                    "operation '{operation}': bound = \"hull-boxes\" boxes the part's surfaces: \
                     plan a part read from IGES (.igs, .iges)"
                )))
            })?;
            let frame = job
                .part
                .up
                .and_then(super::config::unit_direction)
                .map_or_else(nalgebra::Rotation3::identity, |up| {
                    super::setup::upright_rotation(&up)
                });
            let boxes = crate::cad::boxes::HullBoxes::of_faces(&surfaces.faces, frame)
                .map_err(|e| Error::Usage(format!("convex-hull boxes: {e}")))?;
            self.hull_boxes = Some(boxes);
        }
        self.hull_boxes
            .as_ref()
            .ok_or_else(|| Error::Internal("the convex-hull boxes were not built".into()))
    }

    /// The part's verified offset shape at `allowance`, built once per allowance.
    pub(super) fn shape(&mut self, part: &Mesh, allowance: f64) -> Result<Mesh> {
        if let Some((_, shape)) = self.shapes.iter().find(|(a, _)| *a == allowance) {
            return Ok(shape.clone());
        }
        let shapes = stock_shapes(part, &Default::default(), &[allowance])?;
        let shape = shapes
            .into_iter()
            .next()
            .ok_or_else(|| Error::Internal("no offset shape was built".into()))?
            .1
            .mesh;
        self.shapes.push((allowance, shape.clone()));
        Ok(shape)
    }
}

/// Plans `operation` (a `rough` or `rest-rough`; the indexed setups have their own planner)
/// on `part`: chooses its tool, roughs its
/// layers from the blank or from what the roughing before it left, and takes its moves off
/// the planning stock for the next one.
pub fn plan_roughing(
    context: &mut RoughingContext,
    part: &Mesh,
    job: &Job,
    setup: &PlanSetup,
    operation: &Operation,
) -> Result<PlannedRoughing> {
    let depth = context.blank.top - context.floor;
    let margin = job.safety.holder_margin;
    let from_blank = operation.kind == OperationKind::Rough;
    let fail = |reason: String| {
        Error::JobFile(JobError::Operations(format!(
            "operation '{}': {reason}",
            operation.name
        )))
    };
    let (tool, chosen) = match (from_blank, context.previous_diameter) {
        (true, _) | (false, None) => {
            first_rougher(&context.library, operation.library_tool, depth, margin)?
        }
        (false, Some(previous)) => next_rougher(
            &context.library,
            operation.library_tool,
            previous,
            depth,
            margin,
        )?
        .ok_or_else(|| {
            fail(format!(
                "the library has no flat or bull-nose end mill at most 3/4 of the \
                         D{previous} before it to rest-rough with"
            ))
        })?,
    };
    if tool.id == job.tool.id && tool != job.tool.assembly() {
        return Err(fail(format!(
            "library tool T{} ({}) has the number of the job's [tool] ({}): one number, one \
             tool in the magazine",
            tool.id,
            tool.describe(),
            job.tool.assembly().describe()
        )));
    }
    let shape = match operation.boxes {
        Some(_) => None,
        None => Some(context.shape(part, operation.stock_to_leave)?),
    };
    let feeds = RoughingFeeds {
        cut: job.roughing.cut_feed,
        entry: job.roughing.entry_feed,
        rapid: job.machine.rapid_feed,
    };
    let how = ToolRoughing {
        holder_margin: margin,
        floor: context.floor,
        feeds: &feeds,
        tolerance: job.strategy.tolerance,
        feed_control: job
            .cutting
            .model()
            .map(|model| (model, f64::from(job.roughing.spindle_rpm))),
        uniform_layers: false,
        max_depth: None,
        max_engagement: job.roughing.max_engagement,
        paths: job.roughing.layer_paths,
        min_depth: None,
    };
    let planned = match (&shape, operation.boxes) {
        (Some(shape), _) => rough_with_tool(
            crate::rough::Guard::Shape(shape),
            &context.blank,
            &tool,
            &how,
            &mut context.stock,
            from_blank,
        ),
        (None, Some(bound)) => {
            // The boxes are borrowed from the context while its stock is cut: build them
            // first, then take them out for the call and put them back.
            context.hull_boxes(job, &operation.name)?;
            let boxes = context
                .hull_boxes
                .take()
                .ok_or_else(|| Error::Internal("the convex-hull boxes were not built".into()))?;
            let planned = rough_with_tool(
                crate::rough::Guard::HullBoxes {
                    boxes: &boxes,
                    allowance: operation.stock_to_leave,
                    max_box_width: bound.max_box_width,
                    merge: bound.merge,
                },
                &context.blank,
                &tool,
                &how,
                &mut context.stock,
                from_blank,
            );
            context.hull_boxes = Some(boxes);
            planned
        }
        (None, None) => return Err(Error::Internal("roughing has nothing to stop at".into())),
    }
    .map_err(|e| fail(format!("roughing with T{}: {e}", tool.id)))?;
    if from_blank && !planned.cuts() {
        return Err(Error::NothingToCut(format!(
            "operation '{}': the blank holds no material outside the part's offset shape \
             that T{} can reach",
            operation.name, tool.id
        )));
    }
    context.previous_diameter = Some(tool.cutter.diameter());
    context.previous_tool = Some(tool.clone());
    let moves = planned.layers.toolpath.moves.len();
    let cutting_length_mm = planned.cutting_length();
    let ToolLayers {
        tool: planning,
        layers: roughing,
        feed_control,
    } = planned;
    let toolpath = from_safe_plane(roughing.toolpath, setup);
    Ok(PlannedRoughing {
        summary: RoughingSummary {
            operation: operation.name.clone(),
            tool_id: tool.id,
            tool: tool.describe(),
            chosen,
            planning,
            material: if from_blank { "blank" } else { "rest" },
            feed_control,
            stock_to_leave_mm: operation.stock_to_leave,
            shape_triangles: shape.as_ref().map_or(0, |s| s.triangles.len()),
            layers: roughing.layers,
            not_reached: roughing.not_reached,
            moves,
            cutting_length_mm,
            indexed: None,
            overcut_vs_shape: None,
            overcut_vs_part: None,
        },
        tool,
        toolpath,
        bound: match (shape, roughing.hull_boxes) {
            (Some(shape), _) => PlannedBound::Shape(shape),
            (None, Some(planned)) => PlannedBound::Boxes(planned.boxes),
            (None, None) => {
                return Err(Error::Internal("box roughing returned no boxes".into()));
            }
        },
    })
}

impl RoughingContext {
    /// The material standing now — the blank less every operation taken off so far — ready
    /// for the ball operations' shank and holder checks ([`PartCollider::with_material`]).
    ///
    /// [`PartCollider::with_material`]: crate::collide::PartCollider::with_material
    pub fn material(&self) -> Arc<MaterialClearance> {
        Arc::new(MaterialClearance::new(&self.stock))
    }

    /// The volume of the planning stock now, mm³.
    pub fn stock_volume(&self) -> f64 {
        self.stock.volume()
    }

    /// `part` as dexels at the planning stock's spacing (what the rest is measured against).
    pub fn part_model(&self, part: &Mesh) -> Result<Stock> {
        Stock::from_mesh(part, self.stock.spacing(), DEFAULT_MAX_DEXELS)
            .map_err(|e| Error::Internal(format!("the part as dexels: {e}")))
    }

    /// The deepest rest over `part` now, mm: the largest over its faces of how far the
    /// material stands off them along their normals ([`crate::stock::rest`]); `part_model` is
    /// [`Self::part_model`].
    pub fn deepest_rest(&self, part: &Mesh, part_model: &Stock) -> f64 {
        crate::stock::rest::rest_over(
            &self.stock,
            part,
            part_model,
            self.stock.bounds().diagonal(),
        )
        .max_mm
    }

    /// The lowest the tool tip goes, mm (the table's top plus its margin).
    pub fn floor(&self) -> f64 {
        self.floor
    }

    /// The top of the material standing now, mm.
    pub fn material_top(&self) -> f64 {
        self.stock.material_bounds().max.z
    }

    /// Takes a ball operation's moves `path` off the planning stock, from `last` (where the
    /// operation before left the tool), so the next operation is planned against what it
    /// leaves. On the way, from the volume each move removes:
    ///
    /// * rapids that would pass through the material become feed moves at the approach feed.
    ///   The ball's links are planned against the part: the last rapid of a link stops a
    ///   clearance above the entry along the tool axis, which may be inside the rest of a
    ///   terrace or of the floor the table margin leaves. A rapid counts as through material
    ///   when it would remove more than the stock run's allowance (tolerance × dexel spacing²,
    ///   its model's skin). A straight one (the axis fixed) keeps its rapid up to the
    ///   clearance before the ball would first touch the material the operation starts from,
    ///   and is fed from there;
    /// * with feed control, the cutting moves are slowed where they take more than the target
    ///   force allows (the rest a roughing tool could not reach), and passes through air go
    ///   at the machine's limit ([`crate::feed`]; a finishing tool is never sped up in cut).
    pub fn take_off_ball_operation(
        &mut self,
        path: &mut Toolpath,
        last: Option<&Move>,
        how: &BallTakeOff,
    ) -> TakenOff {
        let before = self.stock.clone();
        self.before_balls.get_or_insert_with(|| before.clone());
        let body = crate::stock::cutter::CuttingBody::of(&how.ball.cutter);
        let skin = how.tolerance * before.spacing() * before.spacing();
        let moves: Vec<Move> = last
            .into_iter()
            .copied()
            .chain(path.moves.iter().copied())
            .collect();
        let offset = usize::from(last.is_some());
        let as_toolpath = Toolpath {
            tool_id: how.ball.id,
            moves,
        };
        let removed = self
            .stock
            .remove_cutting(&as_toolpath, &body, how.tolerance);
        let feed_control = how.feed_control.map(|(model, cutter)| {
            let (feeds, report) = control_feeds(&as_toolpath, &removed, &cutter, &model, skin);
            for (m, feed) in path.moves.iter_mut().zip(&feeds[offset..]) {
                m.feed = *feed;
            }
            report
        });
        let moves = &as_toolpath.moves;
        let mut rapids_fed = 0;
        let mut out = Vec::with_capacity(path.moves.len());
        for (k, m) in path.moves.iter().enumerate() {
            let mut m = *m;
            let from = (k + offset).checked_sub(1).map(|j| moves[j]);
            if m.kind == MoveKind::Rapid
                && removed[k + offset] > skin
                && let Some(from) = from
            {
                if let Some(split) =
                    clear_until(&before, &body, &from, &m, how.clearance, how.tolerance)
                {
                    out.push(split);
                }
                m.kind = MoveKind::Approach;
                m.feed = how.approach_feed;
                rapids_fed += 1;
            }
            out.push(m);
        }
        path.moves = out;
        TakenOff {
            rapids_fed,
            feed_control,
        }
    }
}

impl RoughingContext {
    /// Moves added to a ball operation after it came off the stock (an unwind's retract,
    /// turn and re-plunge, from `from`) as the take-off would have left them: a rapid whose
    /// ball would sweep material the roughing left becomes a feed move from `clearance`
    /// before it. Against the stock before the first ball operation, which holds at least
    /// what stood at any later move. Returns how many rapids were fed.
    pub fn feed_rapids_into_rest(
        &self,
        from: &Move,
        moves: &mut Vec<Move>,
        how: &BallTakeOff,
    ) -> usize {
        let stock = self.before_balls.as_ref().unwrap_or(&self.stock);
        feed_rapids_into(stock, from, moves, how)
    }
}

/// [`RoughingContext::feed_rapids_into_rest`] against `stock`.
fn feed_rapids_into(stock: &Stock, from: &Move, moves: &mut Vec<Move>, how: &BallTakeOff) -> usize {
    let body = crate::stock::cutter::CuttingBody::of(&how.ball.cutter);
    let mut fed = 0;
    let mut previous = *from;
    let mut out = Vec::with_capacity(moves.len() + 2);
    for &m in moves.iter() {
        let mut m = m;
        if m.kind == MoveKind::Rapid {
            let meets = body
                .sweep(&previous.pose, &m.pose, how.tolerance)
                .iter()
                .any(|solid| stock.touching(solid, |_| 0.0).is_some());
            if meets {
                if let Some(split) =
                    clear_until(stock, &body, &previous, &m, how.clearance, how.tolerance)
                {
                    out.push(split);
                }
                m.kind = MoveKind::Approach;
                m.feed = how.approach_feed;
                fed += 1;
            }
        }
        out.push(m);
        previous = m;
    }
    *moves = out;
    fed
}

/// How [`RoughingContext::take_off_ball_operation`] treats a ball operation's moves.
#[derive(Clone, Copy, Debug)]
pub struct BallTakeOff<'a> {
    pub ball: &'a ToolAssembly,
    /// The feed of rapids made feed moves, mm/min.
    pub approach_feed: f64,
    /// How far before the material such a rapid stops being one, mm.
    pub clearance: f64,
    pub tolerance: f64,
    /// Feed control (`[cutting]`): the model, and the ball as programmed.
    pub feed_control: Option<(CuttingModel, FeedCutter)>,
}

/// What taking a ball operation off the planning stock changed.
#[derive(Clone, Debug)]
pub struct TakenOff {
    /// Rapids made feed moves.
    pub rapids_fed: usize,
    pub feed_control: Option<FeedReport>,
}

/// The rapid part of a straight rapid `from → to` that the ball would drive into `stock`: the
/// pose `clearance` mm before the first where its sweep from `from` touches material (found by
/// bisection to 1 % of the move), or `None` when that leaves less than `clearance` to go
/// rapid, or the axis turns along the move.
fn clear_until(
    stock: &Stock,
    body: &crate::stock::cutter::CuttingBody,
    from: &Move,
    to: &Move,
    clearance: f64,
    tolerance: f64,
) -> Option<Move> {
    if (from.pose.axis.into_inner() - to.pose.axis.into_inner()).norm() > 1e-12 {
        return None;
    }
    let length = (to.pose.tip - from.pose.tip).norm();
    let at = |t: f64| {
        let mut m = *to;
        m.pose.tip = from.pose.tip + (to.pose.tip - from.pose.tip) * t;
        m
    };
    let clear = |t: f64| {
        body.sweep(&from.pose, &at(t).pose, tolerance)
            .iter()
            .all(|solid| stock.touching(solid, |_| 0.0).is_none())
    };
    // The largest clear fraction: `low` is clear, `high` is not.
    let (mut low, mut high) = (0.0, 1.0);
    if clear(1.0) {
        return None;
    }
    for _ in 0..7 {
        let mid = 0.5 * (low + high);
        if clear(mid) {
            low = mid;
        } else {
            high = mid;
        }
    }
    let t = low - clearance / length.max(f64::MIN_POSITIVE);
    (t * length >= clearance).then(|| at(t))
}

/// `toolpath` (vertical axis, starting and ending on its own safe height above the blank)
/// begun and ended on the plan's safe plane, where tools change and where the ball
/// operations start: machine Z at `safe_distance` from the pivot, whatever C is.
fn from_safe_plane(mut toolpath: Toolpath, setup: &PlanSetup) -> Toolpath {
    let plane_z = setup.pivot.z + setup.safe_distance;
    let lifted = |m: &Move| {
        let mut up = *m;
        up.kind = MoveKind::Rapid;
        up.pose.tip = Point3::new(m.pose.tip.x, m.pose.tip.y, plane_z.max(m.pose.tip.z));
        up
    };
    if let (Some(first), Some(last)) = (toolpath.moves.first(), toolpath.moves.last()) {
        let (start, end) = (lifted(first), lifted(last));
        toolpath.moves.insert(0, start);
        toolpath.moves.push(end);
    }
    toolpath
}

/// Where the roughing moves read back from a program must keep clear of besides the shapes:
/// the machine's safe plane, where the axis may turn, and the table.
pub struct PostedRoughingLimits {
    /// The pivot and the distance of the safe plane from it along the axis, mm.
    pub pivot: Point3,
    pub safe_distance: f64,
    pub table: crate::collide::Table,
}

/// Checks the roughing tools' moves as read back from `gcode` (the first sections of the
/// program, one per roughing operation, in order) against each one's offset shape and the
/// part, exactly; fills in the summaries and returns what is wrong, if anything.
///
/// Each run of moves along one axis (read back from the posted rotary angles) is checked in
/// a frame where that axis is vertical ([`crate::rough::indexed::SetupFrame`]: the vertical
/// layers are one run, each indexed setup another). Where the axis turns between two moves,
/// both must stand on the safe plane. Every move keeps every body of the tool above the
/// table's top by its margin, the bodies' end circles sampled here independently of the
/// planner's closed form.
pub fn check_posted_roughing(
    gcode: &str,
    model: &crate::verify::MachineModel,
    part: &Mesh,
    roughing: &mut [PlannedRoughing],
    tool_changes: usize,
    max_error: f64,
    limits: &PostedRoughingLimits,
) -> Result<Option<String>> {
    if roughing.is_empty() {
        return Ok(None);
    }
    let (posted, lines) = crate::verify::program_toolpath(gcode, model, max_error)
        .map_err(|e| Error::Internal(format!("the posted program does not read back: {e}")))?;
    let sections = split_at_tool_changes(gcode, &posted, &lines, tool_changes)?;
    // Rounding to the posted decimals may bring a move 5e-5 mm nearer; the check allows that.
    let rounding = 1e-4;
    let mut problems = Vec::new();
    for (planned, section) in roughing.iter_mut().zip(sections) {
        let label = format!("'{}' (T{})", planned.summary.operation, planned.tool.id);
        let radius = planned.summary.planning.radius;
        let mut shape = OvercutReport {
            moves_checked: 0,
            overcuts: Vec::new(),
            min_clearance_mm: f64::INFINITY,
        };
        let mut against_part = shape.clone();
        let moves = &section.moves;
        let mut start = 0;
        while start < moves.len() {
            let axis = moves[start].pose.axis;
            let end = moves[start..]
                .iter()
                .position(|m| m.pose.axis != axis)
                .map_or(moves.len(), |n| start + n);
            if end < moves.len() {
                let height = |m: &Move| (m.pose.tip - limits.pivot).dot(&m.pose.axis);
                let (from, to) = (&moves[end - 1], &moves[end]);
                if height(from).min(height(to)) < limits.safe_distance - 1e-3 {
                    problems.push(format!(
                        "{label}: the axis turns between read-back moves {} and {end} off the \
                         safe plane",
                        end - 1
                    ));
                }
            }
            let run = Toolpath {
                tool_id: section.tool_id,
                moves: moves[start..end].to_vec(),
            };
            let Some(frame) = crate::rough::indexed::SetupFrame::new(&axis.into_inner()) else {
                problems.push(format!(
                    "{label}: read-back move {start} points the tool upwards from below"
                ));
                start = end;
                continue;
            };
            let turned = |mesh: &Mesh| frame.mesh_to_setup(mesh);
            let run = Toolpath {
                tool_id: run.tool_id,
                moves: run
                    .moves
                    .iter()
                    .map(|m| {
                        let mut m = *m;
                        m.pose.tip = frame.to_setup(&m.pose.tip);
                        m.pose.axis = nalgebra::Unit::new_normalize(crate::geom::Vector3::z());
                        m
                    })
                    .collect(),
            };
            let mut checks: Vec<(&mut OvercutReport, &Mesh)> = vec![(&mut against_part, part)];
            match &planned.bound {
                PlannedBound::Shape(mesh) => checks.push((&mut shape, mesh)),
                PlannedBound::Boxes(boxes) => {
                    // Boxes are axis-aligned in the part's frame: the layers they bound run
                    // along +Z only.
                    if (axis.into_inner() - crate::geom::Vector3::z()).norm() > 1e-9 {
                        problems.push(format!(
                            "{label}: read-back move {start} tilts the axis of a convex-hull-box \
                             roughing"
                        ));
                    }
                    let found = box_clearance(&run, boxes, radius, rounding, 5.0);
                    shape.moves_checked += found.moves;
                    shape.min_clearance_mm = shape.min_clearance_mm.min(found.min_clearance_mm);
                    shape.overcuts.extend(found.violations.iter().map(|v| {
                        crate::rough::check::Overcut {
                            move_index: v.move_index + start,
                            depth_mm: v.depth_mm,
                        }
                    }));
                }
            }
            for (report, mesh) in checks {
                let found = overcuts(&turned(mesh), &run, radius, rounding);
                report.moves_checked += found.moves_checked;
                report.min_clearance_mm = report.min_clearance_mm.min(found.min_clearance_mm);
                report
                    .overcuts
                    .extend(found.overcuts.into_iter().map(|mut o| {
                        o.move_index += start;
                        o
                    }));
            }
            start = end;
        }
        let bound_name = match planned.bound {
            PlannedBound::Shape(_) => "its offset shape",
            PlannedBound::Boxes(_) => "its convex-hull boxes",
        };
        for (what, report) in [(bound_name, &shape), ("the part", &against_part)] {
            if let Some(o) = report.overcuts.first() {
                problems.push(format!(
                    "{label}: {} posted move(s) into {what}, the first by {:.4} mm",
                    report.overcuts.len(),
                    o.depth_mm
                ));
            }
        }
        let table = limits.table.top_z + limits.table.margin - rounding;
        if let Some((k, low)) = moves
            .iter()
            .enumerate()
            .map(|(k, m)| (k, lowest_point(&planned.tool, &m.pose)))
            .find(|(_, low)| *low < table)
        {
            problems.push(format!(
                "{label}: read-back move {k} brings the tool to z = {low:.4} mm, below the \
                 table's top plus its margin ({table:.4} mm)"
            ));
        }
        planned.summary.overcut_vs_shape = Some(shape);
        planned.summary.overcut_vs_part = Some(against_part);
    }
    Ok((!problems.is_empty()).then(|| problems.join("; ")))
}

/// The lowest z of `tool` at `pose`: its fluted end as the cylinder of its diameter and every
/// body above it, each end circle sampled every 2° (within r·(1 − cos 1°) of the exact low
/// point, 1.5e-4 r).
fn lowest_point(tool: &ToolAssembly, pose: &crate::geom::ToolPose) -> f64 {
    let k = pose.axis.into_inner();
    let u = k.cross(&crate::geom::Vector3::x());
    let u = if u.norm() > 1e-6 {
        u.normalize()
    } else {
        k.cross(&crate::geom::Vector3::y()).normalize()
    };
    let v = k.cross(&u);
    let cutter = 0.5 * tool.cutter.diameter();
    let mut circles = vec![(0.0, cutter), (tool.cutter.flute_length(), cutter)];
    for b in tool.bodies() {
        circles.push((b.from, b.radius_from));
        circles.push((b.to, b.radius_to));
    }
    let mut low = pose.tip.z;
    for (h, r) in circles {
        let centre = pose.tip + k * h;
        for step in 0..180 {
            let t = (step as f64 * 2.0).to_radians();
            low = low.min((centre + r * (t.cos() * u + t.sin() * v)).z);
        }
    }
    low
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::{Aabb, ToolPose, Vector3};

    fn pose_at(z: f64) -> Move {
        Move {
            pose: ToolPose {
                tip: Point3::new(0.0, 0.0, z),
                axis: nalgebra::Unit::new_normalize(Vector3::z()),
            },
            kind: MoveKind::Rapid,
            feed: 15000.0,
        }
    }

    /// A 40 × 40 × 10 block of stock, top at z = 10, its sides at x, y = ±20.
    fn block_stock() -> Stock {
        let bounds = Aabb::from_points(&[
            Point3::new(-20.0, -20.0, 0.0),
            Point3::new(20.0, 20.0, 10.0),
        ]);
        Stock::block(&bounds, 0.5, DEFAULT_MAX_DEXELS).unwrap()
    }

    /// Moves added after the take-off (an unwind's) feed where their rapids would meet the
    /// material: over the block and down beside it by rapid, then across into its side fed
    /// from 3 mm before the ball first touches it (its centre 2 mm off the side at x = 20).
    #[test]
    fn an_unwinds_rapid_into_the_rest_is_fed_from_the_clearance() {
        let stock = block_stock();
        let ball = crate::tool::ToolAssembly {
            id: 1,
            name: String::new(),
            cutter: crate::tool::Cutter::Ball {
                diameter: 4.0,
                flute_length: 10.0,
            },
            neck: None,
            shank_diameter: 4.0,
            stickout: 30.0,
            holder: Vec::new(),
        };
        let how = BallTakeOff {
            ball: &ball,
            approach_feed: 600.0,
            clearance: 3.0,
            tolerance: 0.01,
            feed_control: None,
        };
        let at = |x: f64, z: f64| {
            let mut m = pose_at(z);
            m.pose.tip.x = x;
            m
        };
        let mut moves = vec![at(30.0, 30.0), at(30.0, 5.0), at(0.0, 5.0)];
        let fed = feed_rapids_into(&stock, &at(0.0, 30.0), &mut moves, &how);
        assert_eq!(fed, 1);
        let kinds: Vec<MoveKind> = moves.iter().map(|m| m.kind).collect();
        use MoveKind::{Approach, Rapid};
        assert_eq!(kinds, [Rapid, Rapid, Rapid, Approach]);
        let split = moves[2].pose.tip.x;
        assert!((25.0..=25.25).contains(&split), "{split}");
        assert_eq!((moves[3].feed, moves[3].pose.tip.x), (600.0, 0.0));
        // Nothing there: nothing changes.
        let mut above = vec![at(-30.0, 30.0)];
        assert_eq!(
            feed_rapids_into(&stock, &at(30.0, 30.0), &mut above, &how),
            0
        );
        assert_eq!(above, vec![at(-30.0, 30.0)]);
    }

    /// A ball (r = 2) plunging by rapid from z = 30 to 5 onto a block whose top is z = 10 first
    /// touches it with its tip at 10, 20 mm down the 25 mm move; the rapid part stops 3 mm
    /// before that, at 13 (within the bisection's 25/128 mm), and its sweep is clear.
    #[test]
    fn a_rapid_into_material_keeps_its_rapid_part_up_to_the_clearance() {
        let stock = block_stock();
        let body = crate::stock::cutter::CuttingBody::of(&crate::tool::Cutter::Ball {
            diameter: 4.0,
            flute_length: 10.0,
        });
        let (from, to) = (pose_at(30.0), pose_at(5.0));
        let split = clear_until(&stock, &body, &from, &to, 3.0, 0.01).expect("a rapid part");
        let z = split.pose.tip.z;
        assert!((13.0..=13.0 + 25.0 / 128.0 + 1e-9).contains(&z), "{z}");
        assert_eq!(split.kind, MoveKind::Rapid);
        assert!(
            body.sweep(&from.pose, &split.pose, 0.01)
                .iter()
                .all(|s| stock.touching(s, |_| 0.0).is_none())
        );
        // Too short to be worth a rapid, or turning: fed all the way.
        assert!(clear_until(&stock, &body, &pose_at(14.0), &to, 3.0, 0.01).is_none());
        let mut turned = pose_at(5.0);
        turned.pose.axis = nalgebra::Unit::new_normalize(Vector3::new(0.1, 0.0, 1.0));
        assert!(clear_until(&stock, &body, &from, &turned, 3.0, 0.01).is_none());
    }
}
