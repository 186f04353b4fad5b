//! Toolpaths: drive curves, cutter-location points and linking.
//!
//! The finishing strategy here (the walking skeleton's) drives a ball-end mill along plane
//! sections of the part: parallel planes whose spacing comes from the scallop-height target
//! (seed 000 §5: valid coverage within δ). Each drive point becomes a ball centre that is
//! pushed out until it is at least the ball radius from the part (exact f64), then gets a tool
//! axis (`orient`). Between consecutive poses the chord is checked: where the straight move
//! would bring the ball closer to the part than the tolerance, or the axis would turn too much,
//! points are inserted; where that does not converge, the pass is split and linked.

//!
//! The data it produces ([`crate::geom::Toolpath`] of [`crate::geom::Move`]s between
//! [`crate::geom::ToolPose`]s) and the plane sections it drives along
//! ([`crate::mesh::section`]) live below it, where every stage can use them.

mod contact;
mod covered;
mod curves;
mod link;
mod rest;

pub use contact::{place_ball, place_ball_from};
pub use covered::{CONTACT_BAND, CoverOptions, Covered, SweptBalls};
pub use curves::{TurnedCopy, curve_passes, insert_cheapest, nearest_order, turned_copy};
pub use link::{LinkOptions, LinkReport, can_leave, link, relink, safe_midpoint};
pub use rest::{Gap, GapSamples, RestOptions, SweptTool, clusters, gaps, rest_curve, ridges};

use rayon::prelude::*;

use crate::access::RayScene;
use crate::collide::{PartCollider, PreparedTool};
use crate::geom::{Direction, Point3, ToolPose, Vector3, angle_between, slerp};
use crate::mesh::Mesh;
use crate::mesh::{DrivePoint, plane_section};
use crate::orient::{
    AxisChooser, NoAxis, SmoothingOptions, SmoothingStats, axis_is_valid, smooth_axes,
};

/// Options of the plane-section finishing strategy.
#[derive(Clone, Debug, PartialEq)]
pub struct FinishingOptions {
    /// Normal of the drive planes (need not be unit).
    pub drive_normal: Vector3,
    /// Target scallop height, mm; sets the spacing of the planes.
    pub scallop_height: f64,
    /// Chord tolerance, mm: how much closer than the ball radius a straight move between two
    /// poses may bring the ball to the part.
    pub tolerance: f64,
    /// How far the middle of a straight move between two poses on the part may stand off it,
    /// mm: material left, not cut. Where more, the move gets a pose there
    /// ([`FinishingOptions::leaving_at_most`] keeps a share of the scallop target for it).
    pub sag_tolerance: f64,
    /// Longest step between drive points before chord refinement, mm.
    pub max_step: f64,
    /// Largest axis turn between consecutive poses, degrees.
    pub max_axis_turn_deg: f64,
    /// Smoothing of the axes along each pass (bounded turn per mm, never leaving the valid
    /// axes); `None` keeps the point-by-point choice.
    pub axis_smoothing: Option<SmoothingOptions>,
}

impl Default for FinishingOptions {
    fn default() -> Self {
        Self {
            drive_normal: Vector3::x(),
            scallop_height: 0.01,
            tolerance: 0.01,
            sag_tolerance: 0.01,
            max_step: 1.0,
            max_axis_turn_deg: 5.0,
            axis_smoothing: Some(SmoothingOptions::default()),
        }
    }
}

/// The share of a finishing operation's scallop target kept for the moves' sag: the passes
/// are spaced for the rest. A cusp between two passes and a move's middle standing off the
/// part add up where they meet (round the blower's 5 mm bore, cusps spaced for the whole
/// 0.01 mm target rose to 0.016 mm with the 0.005 mm chord tolerance's sag; with a tenth kept
/// for a tenth of the sag, to 0.012 mm).
pub const SAG_SHARE: f64 = 0.1;

/// The scallop passes are spaced for, to leave at most `scallop` with their moves' sag.
fn spaced_for(scallop: f64) -> f64 {
    (1.0 - SAG_SHARE) * scallop
}

impl FinishingOptions {
    /// These options for passes that are to leave at most `scallop` anywhere they reach:
    /// spaced for all but [`SAG_SHARE`] of it, moves sagging off the part by no more than
    /// that share (nor than the chord tolerance).
    pub fn leaving_at_most(&self, scallop: f64) -> FinishingOptions {
        FinishingOptions {
            scallop_height: spaced_for(scallop),
            sag_tolerance: (SAG_SHARE * scallop).min(self.tolerance),
            ..self.clone()
        }
    }
}

/// The stepover a ball of `radius` is planned at to leave at most `scallop`: spaced for all
/// but [`SAG_SHARE`] of it.
pub fn planned_stepover(radius: f64, scallop: f64) -> f64 {
    stepover_for_scallop(radius, spaced_for(scallop))
}

pub use crate::geom::stepover_for_scallop;

/// A run of consecutive cut poses the tool can follow without lifting.
#[derive(Clone, Debug, PartialEq)]
pub struct CutSegment {
    pub poses: Vec<ToolPose>,
    /// At each pose, the unit direction the pass runs in there (the drive curve's tangent):
    /// every step of the ball centre has a positive component along the direction at its end.
    pub pass_directions: Vec<Vector3>,
    /// The first and last poses are leads off the part (a swarf run's ways in and out): the
    /// tool arrives at the first in the air, feeds in to the second (an approach) and out
    /// from the last but one to the last (a retract at the cut feed).
    pub leads: bool,
}

/// Why a drive point could not be machined.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Unreachable {
    /// The ball cannot be placed there without gouging (a slot narrower than the ball).
    BallDoesNotFit,
    /// No axis within the machine's limits.
    MachineLimits,
    /// Every axis ray hits the part.
    Occluded,
    /// Shank or holder would collide for every candidate axis.
    Collision,
    /// The tool would come too close to the machine table for every candidate axis (the
    /// part's underside, which stands on the table).
    Table,
    /// The shank or holder would touch the material the operations before left, for every
    /// candidate axis that clears the part.
    Material,
}

impl From<NoAxis> for Unreachable {
    fn from(n: NoAxis) -> Self {
        match n {
            NoAxis::MachineLimits => Unreachable::MachineLimits,
            NoAxis::Occluded => Unreachable::Occluded,
            NoAxis::Collision => Unreachable::Collision,
            NoAxis::Table => Unreachable::Table,
            NoAxis::Material => Unreachable::Material,
        }
    }
}

/// The result of [`finishing_passes`].
#[derive(Clone, Debug, Default)]
pub struct Finishing {
    pub segments: Vec<CutSegment>,
    /// Drive points that could not be machined, with the reason.
    pub unreachable: Vec<(Point3, Unreachable)>,
    pub drive_points: usize,
    pub planes: usize,
    /// Poses inserted by chord and axis-turn refinement.
    pub inserted_poses: usize,
    /// Passes split because a drive point was unreachable.
    pub splits_at_unreachable: usize,
    /// Passes split because refinement could not make a move safe or smooth enough.
    pub splits_at_refinement: usize,
    /// What the axis smoothing did (before refinement).
    pub smoothing: SmoothingStats,
    /// Poses dropped because they stepped back along the pass (or by less than 0.1 µm).
    pub backward_poses_dropped: usize,
    /// Drive points a roughing layer leaves out because their ball (placed) cuts nothing
    /// there ([`MaterialFilter`]).
    pub points_in_air: usize,
    /// Drive points left to another strategy ([`FinishingContext::region`]).
    pub points_left_to_others: usize,
}

/// A strategy's preferred tool axis at a drive point: (point, normal, feed direction) → axis.
pub type AxisField<'a> = dyn Fn(&Point3, &Vector3, &Vector3) -> Vector3 + Sync + 'a;

/// Everything the per-point work needs, borrowed.
pub struct FinishingContext<'a> {
    pub part: &'a PartCollider,
    pub rays: &'a RayScene,
    pub tool: &'a PreparedTool,
    pub chooser: &'a AxisChooser,
    pub reachable: &'a (dyn Fn(&Vector3) -> bool + Sync),
    /// Material kept on the part, mm: every ball centre (and every chord between two) is held
    /// `ball_radius + allowance` from the part, so the ball stays `allowance` off it. 0 when
    /// finishing; a roughing layer keeps more.
    pub allowance: f64,
    /// Where the ball starts off a drive point before it is pushed out of the part, beyond its
    /// radius along the drive normal, mm: the allowance when the drive surface is the part (the
    /// ball starts where it keeps the allowance), 0 when it is a surface the ball's bottom
    /// follows (a roughing layer between shroud and hub).
    pub lift: f64,
    /// A roughing layer's test of where there is anything to cut; `None` machines every drive
    /// point.
    pub material_filter: Option<&'a MaterialFilter<'a>>,
    /// A strategy's own preferred axis at a drive point (point, normal, feed direction), in
    /// place of the lead and tilt from the normal; the chooser searches around it.
    pub axis_field: Option<&'a AxisField<'a>>,
    /// Which drive points this strategy machines, when others take the rest (the impeller
    /// strategies take the hub and blades, the planes what is left); `None` machines all.
    pub region: Option<&'a (dyn Fn(&Point3) -> bool + Sync)>,
}

impl FinishingContext<'_> {
    /// The chooser's axis for a ball centred at `centre` on `drive`, moving along `feed`:
    /// around the strategy's own preferred axis where it has one, else around the lead and
    /// tilt from the normal.
    pub fn choose_axis(
        &self,
        centre: &Point3,
        drive: &DrivePoint,
        feed: &Vector3,
        previous: Option<&Vector3>,
    ) -> Result<Direction, NoAxis> {
        match self.axis_field {
            Some(field) => self.chooser.choose_around(
                self.part,
                self.rays,
                self.tool,
                centre,
                &field(&drive.point, &drive.normal, feed),
                previous,
                self.reachable,
            ),
            None => self.chooser.choose(
                self.part,
                self.rays,
                self.tool,
                centre,
                &drive.normal,
                feed,
                previous,
                self.reachable,
            ),
        }
    }
}

/// Where a roughing layer has something to cut: `touches(centre, radius)` says
/// whether a ball of `radius` about `centre` may meet material (it must never answer `false`
/// for a ball that does). Drive points whose ball meets none are left out, except within
/// `lead` mm of one that does, along the drive curve: a gap in the air shorter than twice the
/// lead is cut through at feed rather than left and entered again, and each run of cuts starts
/// and ends in the air.
pub struct MaterialFilter<'a> {
    pub touches: &'a (dyn Fn(&Point3, f64) -> bool + Sync),
    pub lead: f64,
}

/// Plans ball-end finishing passes over the whole part along parallel plane sections.
/// Planes run in parallel; each plane's result depends only on the plane, so the output is the
/// same for any number of threads.
pub fn finishing_passes(
    mesh: &Mesh,
    ctx: &FinishingContext,
    options: &FinishingOptions,
    progress: &(dyn Fn() + Sync),
) -> Finishing {
    let normal = options.drive_normal.normalize();
    let face_normals: Vec<Vector3> = (0..mesh.triangles.len())
        .map(|t| mesh.face_normal(t))
        .collect();
    let (lo, hi) = mesh
        .positions
        .iter()
        .map(|p| normal.dot(&p.coords))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(x), b.max(x))
        });
    let spacing = stepover_for_scallop(ctx.tool.ball_radius, options.scallop_height).max(1e-3);
    let count = ((hi - lo) / spacing).ceil().max(1.0) as usize;
    let first = lo + 0.5 * ((hi - lo) - (count as f64 - 1.0) * spacing);
    let planes: Vec<Finishing> = (0..count)
        .into_par_iter()
        .map(|k| {
            let offset = first + k as f64 * spacing;
            let mut result = Finishing {
                planes: 1,
                ..Default::default()
            };
            for curve in plane_section(mesh, &face_normals, &normal, offset) {
                // Ball-centre chords within a quarter of the tolerance: the refinement that
                // follows inserts poses where the chord still strays.
                let mut points = curve
                    .simplified(
                        ctx.tool.ball_radius + ctx.lift,
                        0.25 * options.tolerance,
                        options.max_step,
                    )
                    .resampled(options.max_step);
                if k % 2 == 1 {
                    points.reverse(); // zig-zag: every other plane runs the other way
                }
                drive_curve(&points, ctx, options, &mut result);
            }
            progress();
            result
        })
        .collect();
    let mut out = Finishing::default();
    for p in planes {
        out.merge(p);
    }
    out
}

impl Finishing {
    /// Adds `other`'s segments after this one's, and its counts to these.
    pub fn merge(&mut self, other: Finishing) {
        self.segments.extend(other.segments);
        self.unreachable.extend(other.unreachable);
        self.drive_points += other.drive_points;
        self.planes += other.planes;
        self.inserted_poses += other.inserted_poses;
        self.splits_at_unreachable += other.splits_at_unreachable;
        self.splits_at_refinement += other.splits_at_refinement;
        self.backward_poses_dropped += other.backward_poses_dropped;
        self.points_in_air += other.points_in_air;
        self.points_left_to_others += other.points_left_to_others;
        self.smoothing.merge(&other.smoothing);
    }
}

/// One placed pose with the drive point it came from.
#[derive(Clone, Copy)]
struct Placed {
    drive: DrivePoint,
    centre: Point3,
    axis: Direction,
}

/// The drive curve's direction at point `i`: from the nearest point behind it to the nearest
/// ahead that are elsewhere. A section keeps a crease of the facets as two points in one place
/// (each face's normal), and a short curve clipped round a sharp edge can have all its points
/// in one place: zero only then (the ball rolls round the edge with the drive point still).
fn feed_direction(points: &[DrivePoint], i: usize) -> Vector3 {
    let at = points[i].point;
    let elsewhere = |p: &&DrivePoint| (p.point - at).norm() > 1e-9;
    let prev = points[..i]
        .iter()
        .rev()
        .find(elsewhere)
        .map_or(at, |p| p.point);
    let next = points[i + 1..]
        .iter()
        .find(elsewhere)
        .map_or(at, |p| p.point);
    (next - prev)
        .try_normalize(1e-12)
        .unwrap_or_else(Vector3::zeros)
}

fn drive_curve(
    points: &[DrivePoint],
    ctx: &FinishingContext,
    options: &FinishingOptions,
    out: &mut Finishing,
) {
    let r = ctx.tool.ball_radius;
    // 0. A roughing layer first places every ball and keeps the points near material.
    let (centres, keep) = match ctx.material_filter {
        Some(layer) => {
            let (centres, keep) = points_near_material(points, ctx, layer);
            (Some(centres), keep)
        }
        None => (None, vec![true; points.len()]),
    };
    let ours: Vec<bool> = match ctx.region {
        Some(region) => points.iter().map(|p| region(&p.point)).collect(),
        None => vec![true; points.len()],
    };
    // 1. Place every drive point; unreachable ones (and a roughing layer's points in the air)
    //    split the curve into runs.
    let mut runs: Vec<Vec<(Placed, Vector3)>> = Vec::new();
    let mut run: Vec<(Placed, Vector3)> = Vec::new();
    for i in 0..points.len() {
        out.drive_points += 1;
        let drive = points[i];
        if !ours[i] {
            out.points_left_to_others += 1;
            if !run.is_empty() {
                runs.push(std::mem::take(&mut run));
            }
            continue;
        }
        if !keep[i] {
            // A roughing layer's ball that does not fit there is unreachable, not in the air:
            // whether there is anything to cut cannot be told without a place for it.
            match centres.as_ref().map(|c| c[i]) {
                Some(None) => out
                    .unreachable
                    .push((drive.point, Unreachable::BallDoesNotFit)),
                _ => out.points_in_air += 1,
            }
            if !run.is_empty() {
                runs.push(std::mem::take(&mut run));
            }
            continue;
        }
        let feed = feed_direction(points, i);
        let previous = run
            .last()
            .map(|(l, _): &(Placed, Vector3)| l.axis.into_inner());
        let centre = centres.as_ref().map(|c| c[i]);
        match place(ctx, &drive, &feed, previous.as_ref(), None, centre) {
            Ok(p) => run.push((p, feed)),
            Err(why) => {
                out.unreachable.push((drive.point, why));
                if !run.is_empty() {
                    out.splits_at_unreachable += 1;
                    runs.push(std::mem::take(&mut run));
                }
            }
        }
    }
    if !run.is_empty() {
        runs.push(run);
    }
    for mut run in runs {
        // 2. Smooth the run's axes, each new one checked exactly like the chosen ones.
        if let Some(smoothing) = &options.axis_smoothing {
            let centres: Vec<Point3> = run.iter().map(|(p, _)| p.centre).collect();
            let axes: Vec<Vector3> = run.iter().map(|(p, _)| p.axis.into_inner()).collect();
            let valid = |i: usize, axis: &Vector3| {
                axis_is_valid(
                    ctx.part,
                    ctx.rays,
                    ctx.tool,
                    &centres[i],
                    axis,
                    ctx.reachable,
                )
                .is_ok()
            };
            let (smoothed, stats) = smooth_axes(&centres, &axes, &valid, smoothing);
            out.smoothing.merge(&stats);
            for ((p, _), axis) in run.iter_mut().zip(smoothed) {
                p.axis = Direction::new_normalize(axis);
            }
        }
        // 3. Refine the moves between consecutive poses; split where that fails. Each pose
        //    keeps the pass direction it was driven in (inserted ones: between their ends').
        let mut current: Vec<(ToolPose, Vector3)> = Vec::new();
        for k in 0..run.len() {
            let (placed, feed) = &run[k];
            if k > 0 {
                match refine(ctx, options, &run[k - 1].0, placed, feed, 0) {
                    Some(inner) => {
                        out.inserted_poses += inner.len();
                        let between = (run[k - 1].1 + feed).try_normalize(1e-9).unwrap_or(*feed);
                        current.extend(inner.iter().map(|p| (pose_of(p, r), between)));
                    }
                    None => {
                        out.splits_at_refinement += 1;
                        push_forward_runs(ctx, options, std::mem::take(&mut current), out);
                    }
                }
            }
            current.push((pose_of(placed, r), *feed));
        }
        push_forward_runs(ctx, options, current, out);
    }
}

/// A roughing layer's ball centres for `points` (`None` where the ball does not fit), and which
/// points to machine: those whose ball may touch material, and those within the layer's lead
/// of one, measured along the curve.
fn points_near_material(
    points: &[DrivePoint],
    ctx: &FinishingContext,
    layer: &MaterialFilter,
) -> (Vec<Option<Point3>>, Vec<bool>) {
    let r = ctx.tool.ball_radius;
    let centres: Vec<Option<Point3>> = points
        .iter()
        .map(|p| place_ball_from(ctx.part.surface(), p, r + ctx.lift, r + ctx.allowance))
        .collect();
    let cuts: Vec<bool> = centres
        .iter()
        .map(|c| c.is_some_and(|c| (layer.touches)(&c, r)))
        .collect();
    // Arc length along the curve; a point is kept when a cutting one lies within the lead
    // behind or ahead of it (two sweeps, each carrying the distance to the last cutting one).
    let mut along = Vec::with_capacity(points.len());
    let mut s = 0.0;
    for (i, p) in points.iter().enumerate() {
        if i > 0 {
            s += (p.point - points[i - 1].point).norm();
        }
        along.push(s);
    }
    let mut keep = cuts.clone();
    let mut last = None;
    for i in 0..points.len() {
        if cuts[i] {
            last = Some(along[i]);
        } else if last.is_some_and(|l| along[i] - l <= layer.lead) {
            keep[i] = true;
        }
    }
    last = None;
    for i in (0..points.len()).rev() {
        if cuts[i] {
            last = Some(along[i]);
        } else if last.is_some_and(|l| l - along[i] <= layer.lead) {
            keep[i] = true;
        }
    }
    (centres, keep)
}

/// Steps shorter than this (mm) carry no direction and are dropped.
const MIN_STEP: f64 = 1e-4;

/// Consecutive poses that each turn the travel back before the turn counts as the pass's own
/// (a sharp concave corner) rather than a zig: the pass is split there instead.
const TURN_STREAK: usize = 32;

/// Pushes `poses` (with their pass directions) as cut segments that never step backwards.
///
/// In a concave corner the ball centres of neighbouring drive points overtake each other (the
/// offset of the section has a swallowtail there), neighbouring drive points whose normals
/// differ place their balls a little sideways and back, and refinement can place a midpoint
/// beyond its neighbours: followed in order, the tool would zig back and forth along the
/// pass. So a pose is dropped when its step from the last kept one is shorter than
/// [`MIN_STEP`], goes against its pass direction (the drive curve's tangent), or turns the
/// travel back (negative projection on the step before). The chord that then spans the gap is
/// checked exactly like every other (ball within the chord tolerance, axis turn within its
/// bound); where it fails, or where [`TURN_STREAK`] poses in a row turn back (the centre path
/// itself turns by more than 90°, as in an acute concave corner), the pass is split instead.
fn push_forward_runs(
    ctx: &FinishingContext,
    options: &FinishingOptions,
    poses: Vec<(ToolPose, Vector3)>,
    out: &mut Finishing,
) {
    let r = ctx.tool.ball_radius;
    let centre = |p: &ToolPose| p.tip + p.axis.into_inner() * r;
    let empty = || CutSegment {
        poses: Vec::new(),
        pass_directions: Vec::new(),
        leads: false,
    };
    let emit = |run: CutSegment, out: &mut Finishing| {
        if run.poses.len() >= 2 {
            out.segments.push(run);
        }
    };
    let mut run = empty();
    let mut dropped = false;
    // First pose of the current run of poses that turned the travel back.
    let mut turning: Option<(usize, usize)> = None;
    let mut i = 0;
    while i < poses.len() {
        let (pose, direction) = poses[i];
        i += 1;
        let Some(last) = run.poses.last() else {
            run.poses.push(pose);
            run.pass_directions.push(direction);
            continue;
        };
        let step = centre(&pose) - centre(last);
        let turns_back = run.poses.len() >= 2
            && step.dot(&(centre(last) - centre(&run.poses[run.poses.len() - 2]))) < 0.0;
        if step.norm() < MIN_STEP || step.dot(&direction) < 0.0 || turns_back {
            dropped = true;
            out.backward_poses_dropped += 1;
            if turns_back {
                let (first, count) = turning.unwrap_or((i - 1, 0));
                turning = Some((first, count + 1));
                if count + 1 == TURN_STREAK {
                    // The path turns here: end the run and start the next at the turn.
                    out.backward_poses_dropped -= TURN_STREAK;
                    out.splits_at_refinement += 1;
                    emit(std::mem::replace(&mut run, empty()), out);
                    (i, dropped, turning) = (first, false, None);
                }
            }
            continue;
        }
        turning = None;
        if std::mem::take(&mut dropped) {
            let chord_ok = !ctx.part.surface().segment_within(
                &centre(last),
                &centre(&pose),
                r + ctx.allowance - options.tolerance,
            );
            let turn_ok =
                angle_between(&last.axis, &pose.axis).to_degrees() <= options.max_axis_turn_deg;
            let flutes_ok = flutes_clear_along(
                ctx,
                options,
                (&centre(last), &last.axis),
                (&centre(&pose), &pose.axis),
            );
            if chord_ok && flutes_ok && !turn_ok {
                // Round a concave corner the dropped poses took the axis's turn with them
                // (round a facetted bore, the wall's normal turns by the facets' angle at
                // each crease): the chord is clear, so the axis turns along it instead.
                match turn_along_chord(ctx, options, last, &pose) {
                    Some(between) => {
                        out.inserted_poses += between.len();
                        for p in between {
                            run.poses.push(p);
                            run.pass_directions.push(direction);
                        }
                    }
                    None => {
                        out.splits_at_refinement += 1;
                        emit(std::mem::replace(&mut run, empty()), out);
                    }
                }
            } else if !(chord_ok && turn_ok && flutes_ok) {
                out.splits_at_refinement += 1;
                emit(std::mem::replace(&mut run, empty()), out);
            }
        }
        run.poses.push(pose);
        run.pass_directions.push(direction);
    }
    emit(run, out);
}

/// Poses between `a` and `b` along the straight line of their ball centres (each pushed off
/// the part to touch it where the line comes nearer: the line may cut a concave corner by the
/// tolerance, a pose may not), the axis turning evenly between theirs, each move turning it
/// at most the allowed angle: `None` where an axis between is not valid at its centre, a move
/// comes nearer the part than the tolerance allows, or the flutes do not clear it.
fn turn_along_chord(
    ctx: &FinishingContext,
    options: &FinishingOptions,
    a: &ToolPose,
    b: &ToolPose,
) -> Option<Vec<ToolPose>> {
    let r = ctx.tool.ball_radius;
    let turn = angle_between(&a.axis, &b.axis).to_degrees();
    let pieces = (turn / options.max_axis_turn_deg.max(1e-3)).ceil() as usize;
    if pieces > MAX_TURN_PIECES {
        return None;
    }
    let (from, to) = (
        a.tip + a.axis.into_inner() * r,
        b.tip + b.axis.into_inner() * r,
    );
    let mut poses = Vec::with_capacity(pieces);
    let mut previous = (from, a.axis);
    for k in 1..=pieces {
        let t = k as f64 / pieces as f64;
        let (centre, axis) = if k == pieces {
            (to, b.axis)
        } else {
            let centre = touching(ctx, from + (to - from) * t)?;
            let axis = Direction::new_normalize(slerp(&a.axis, &b.axis, t));
            axis_is_valid(
                ctx.part,
                ctx.rays,
                ctx.tool,
                &centre,
                &axis.into_inner(),
                ctx.reachable,
            )
            .ok()?;
            (centre, axis)
        };
        let held = r + ctx.allowance;
        if ctx
            .part
            .surface()
            .segment_within(&previous.0, &centre, held - options.tolerance)
            || !flutes_clear_along(ctx, options, (&previous.0, &previous.1), (&centre, &axis))
        {
            return None;
        }
        if k < pieces {
            poses.push(ToolPose {
                tip: centre - axis.into_inner() * r,
                axis,
            });
        }
        previous = (centre, axis);
    }
    Some(poses)
}

/// `centre`, or where it comes nearer the part than the ball's radius (and the allowance),
/// moved straight off the nearest point until the ball touches; `None` where a few such moves
/// do not clear it (a corner pushes it back).
fn touching(ctx: &FinishingContext, mut centre: Point3) -> Option<Point3> {
    let held = ctx.tool.ball_radius + ctx.allowance;
    let surface = ctx.part.surface();
    for _ in 0..4 {
        let Some(nearest) = surface.closest(&centre, held) else {
            return Some(centre);
        };
        if nearest.distance >= held - 1e-9 {
            return Some(centre);
        }
        let away = (centre - nearest.point).try_normalize(1e-12)?;
        centre = nearest.point + away * held;
    }
    (!surface.any_within(&centre, held - 1e-9)).then_some(centre)
}

/// Most moves an axis's turn along a chord is spread over ([`turn_along_chord`]): 60° at the
/// 5° default.
const MAX_TURN_PIECES: usize = 12;

fn pose_of(p: &Placed, r: f64) -> ToolPose {
    ToolPose {
        tip: p.centre - p.axis.into_inner() * r,
        axis: p.axis,
    }
}

/// Places the ball for a drive point (or takes the centre `placed` already found for it) and
/// chooses its axis: `try_first` when that axis is valid (used between two placed poses, so
/// the axis turns smoothly where both ends are fine), otherwise the chooser's pick near
/// `previous`.
fn place(
    ctx: &FinishingContext,
    drive: &DrivePoint,
    feed: &Vector3,
    previous: Option<&Vector3>,
    try_first: Option<&Vector3>,
    placed: Option<Option<Point3>>,
) -> Result<Placed, Unreachable> {
    let centre = placed
        .unwrap_or_else(|| {
            place_ball_from(
                ctx.part.surface(),
                drive,
                ctx.tool.ball_radius + ctx.lift,
                ctx.tool.ball_radius + ctx.allowance,
            )
        })
        .ok_or(Unreachable::BallDoesNotFit)?;
    if let Some(axis) = try_first
        && axis_is_valid(ctx.part, ctx.rays, ctx.tool, &centre, axis, ctx.reachable).is_ok()
    {
        return Ok(Placed {
            drive: *drive,
            centre,
            axis: Direction::new_normalize(*axis),
        });
    }
    let axis = ctx.choose_axis(&centre, drive, feed, previous)?;
    Ok(Placed {
        drive: *drive,
        centre,
        axis,
    })
}

/// Poses to insert between `a` and `b` so that every straight move keeps the ball within the
/// tolerance and turns the axis at most the allowed angle; `None` when that needs more than
/// the depth allows (the caller splits the pass there).
///
/// The tolerance holds the other way too: on a concave stretch the chord between two balls
/// touching the part sags off it (round a 5 mm bore, 26° of the ball centres' circle leaves
/// 0.013 mm on the wall). Where the drive points lie on the part, a chord whose middle is
/// more than the sag tolerance off it gets a pose there, its drive point the part's nearest;
/// where that does not help (the part falls away from both balls) the chord stands, and a
/// sag alone never splits a pass.
fn refine(
    ctx: &FinishingContext,
    options: &FinishingOptions,
    a: &Placed,
    b: &Placed,
    feed: &Vector3,
    depth: u32,
) -> Option<Vec<Placed>> {
    let held = ctx.tool.ball_radius + ctx.allowance;
    // The whole chord, exactly: it can cut deepest anywhere along its length.
    let chord_ok =
        !ctx.part
            .surface()
            .segment_within(&a.centre, &b.centre, held - options.tolerance);
    let turn_ok = angle_between(&a.axis, &b.axis).to_degrees() <= options.max_axis_turn_deg;
    let clear = chord_ok
        && turn_ok
        && flutes_clear_along(ctx, options, (&a.centre, &a.axis), (&b.centre, &b.axis));
    let middle = nalgebra::center(&a.centre, &b.centre);
    let drive_on_part = (ctx.lift - ctx.allowance).abs() < 1e-12;
    let sags = clear
        && drive_on_part
        && !ctx
            .part
            .surface()
            .any_within(&middle, held + options.sag_tolerance);
    if clear && !sags {
        return Some(Vec::new());
    }
    // Only a sag to mend: whatever fails to mend it leaves the chord as it is.
    let give_up = || sags.then(Vec::new);
    if depth >= 8
        || (a.drive.point - b.drive.point).norm() + (a.drive.normal - b.drive.normal).norm() < 1e-9
    {
        return give_up();
    }
    let normal = (a.drive.normal + b.drive.normal).try_normalize(1e-12)?;
    let mut point = nalgebra::center(&a.drive.point, &b.drive.point);
    if sags {
        // Between two drive points on a concave part their middle is in the air, and a ball
        // started from it would not come down to the part.
        match ctx.part.surface().closest(&point, held) {
            Some(nearest) => point = nearest.point,
            None => return give_up(),
        }
    }
    let drive = DrivePoint { point, normal };
    let Ok(m) = place(
        ctx,
        &drive,
        feed,
        Some(&a.axis.into_inner()),
        Some(&slerp(&a.axis, &b.axis, 0.5)),
        None,
    ) else {
        return give_up();
    };
    // The right half is not refined when the left fails: the chord is given up either way.
    let Some(mut left) = refine(ctx, options, a, &m, feed, depth + 1) else {
        return give_up();
    };
    let Some(right) = refine(ctx, options, &m, b, feed, depth + 1) else {
        return give_up();
    };
    left.push(m);
    left.extend(right);
    Some(left)
}

/// Longest stretch of a move between two places its flutes are checked, mm.
const FLUTE_CHECK_STEP: f64 = 0.5;

/// Whether the flutes stay clear of the part along the move from `a` to `b` (ball centre and
/// axis at each end; both ends are checked with the tool's bodies): where the axis turns, or
/// the move climbs a wall, the flutes between the two poses can come nearer the part than at
/// either. Each flute's axis, from the ball's centre up its length, must keep the ball's radius
/// less the tolerance at the move's inner points no more than [`FLUTE_CHECK_STEP`] apart
/// along the centres' chord (and at least half-way). On the blower's planes a 3.4 mm move up a
/// blade wall, spanning dropped poses, had its flutes 0.014 mm into the part 3.4 mm above the
/// ball's centre, both ends clear: the back-simulation refused the program.
fn flutes_clear_along(
    ctx: &FinishingContext,
    options: &FinishingOptions,
    a: (&Point3, &Direction),
    b: (&Point3, &Direction),
) -> bool {
    let Some((length, _)) = ctx.tool.flutes_above_ball() else {
        return true;
    };
    let held = ctx.tool.ball_radius + ctx.allowance - options.tolerance;
    let pieces = ((b.0 - a.0).norm() / FLUTE_CHECK_STEP).ceil().max(2.0) as usize;
    (1..pieces).all(|k| {
        let t = k as f64 / pieces as f64;
        let centre = a.0 + (b.0 - a.0) * t;
        let axis = slerp(&a.1.into_inner(), &b.1.into_inner(), t);
        !ctx.part
            .surface()
            .segment_within(&centre, &(centre + axis * length), held)
    })
}

/// Unreachable drive points counted by reason (the reasons' JSON names).
pub fn unreachable_by_reason(
    unreachable: &[(Point3, Unreachable)],
) -> std::collections::BTreeMap<String, usize> {
    let mut by_reason = std::collections::BTreeMap::new();
    for (_, why) in unreachable {
        *by_reason
            .entry(
                serde_json::to_value(why)
                    .ok()
                    .and_then(|v| v.as_str().map(String::from))
                    .unwrap_or_default(),
            )
            .or_insert(0) += 1;
    }
    by_reason
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A crease kept as two points in one place (each face's normal) still has the curve's
    /// direction; only a curve all in one place (a ball rolled round an edge) has none.
    #[test]
    fn a_drive_curve_has_a_direction_through_a_crease() {
        let point = |x: f64, nx: f64| DrivePoint {
            point: Point3::new(x, 0.0, 0.0),
            normal: Vector3::new(nx, 0.0, 1.0).normalize(),
        };
        let creased = [
            point(0.0, 0.0),
            point(1.0, -0.3),
            point(1.0, 0.3),
            point(2.0, 0.0),
        ];
        for i in 0..creased.len() {
            assert_eq!(feed_direction(&creased, i), Vector3::x(), "at {i}");
        }
        let still = [point(1.0, -0.3), point(1.0, 0.0), point(1.0, 0.3)];
        assert_eq!(feed_direction(&still, 1), Vector3::zeros());
    }

    #[test]
    fn stepover_matches_the_flat_surface_formula() {
        // r = 3, h = 0.01: 2·√(0.01·5.99) = 0.48949...
        assert!((stepover_for_scallop(3.0, 0.01) - 2.0 * (0.0599f64).sqrt()).abs() < 1e-12);
        assert_eq!(stepover_for_scallop(3.0, 0.0), 0.0);
        // A cusp as high as the radius: passes one diameter apart.
        assert!((stepover_for_scallop(3.0, 3.0) - 6.0).abs() < 1e-12);
    }

    /// A part with what finishing passes over it need (the box [0,40]×[0,30]×[0,10] unless
    /// made [`Block::of`] another): the ball D6 of the collision tests and the default axis
    /// choice.
    struct Block {
        part: Mesh,
        collider: PartCollider,
        rays: RayScene,
        tool: PreparedTool,
        chooser: AxisChooser,
    }

    /// Reaches every axis.
    fn anywhere(_: &Vector3) -> bool {
        true
    }

    impl Block {
        /// `part` with the ball D6 of the collision tests and the default axis choice.
        fn of(part: Mesh) -> Block {
            Block {
                collider: PartCollider::new(&part).unwrap(),
                rays: RayScene::new(&part),
                tool: crate::collide::tool_bodies::tests::prepared(),
                chooser: AxisChooser::new(crate::orient::AxisOptions::default()),
                part,
            }
        }

        /// The block's finishing context, the ball held `allowance` off the part (and lifted
        /// as much), every axis reachable, no material filter, axis field or region.
        fn context(&self, allowance: f64) -> FinishingContext<'_> {
            FinishingContext {
                part: &self.collider,
                rays: &self.rays,
                tool: &self.tool,
                chooser: &self.chooser,
                reachable: &anywhere,
                allowance,
                lift: allowance,
                material_filter: None,
                axis_field: None,
                region: None,
            }
        }
    }

    fn block() -> Block {
        Block::of(crate::mesh::fixtures::cuboid(40.0, 30.0, 10.0))
    }

    /// Round the block's top edge (x = 40, z = 10) the ball centres circle it; a move between
    /// two of them 24° apart round it cuts the corner, and its axes turn by 24°. The axis turns
    /// along the move in steps within the allowed turn, each pose between pushed off the
    /// corner to touch it; where the machine refuses the axes between, nothing is inserted.
    #[test]
    fn an_axis_turns_along_a_chord_with_every_pose_between_touching() {
        let block = block();
        let ctx = block.context(0.0);
        let r = block.tool.ball_radius;
        let options = FinishingOptions {
            tolerance: 0.5,
            ..FinishingOptions::default()
        };
        let edge = |angle: f64| {
            let (sin, cos) = angle.to_radians().sin_cos();
            let axis = Direction::new_normalize(Vector3::new(sin, 0.0, cos));
            let centre = Point3::new(40.0, 15.0, 10.0) + axis.into_inner() * r;
            ToolPose {
                tip: centre - axis.into_inner() * r,
                axis,
            }
        };
        let (a, b) = (edge(30.0), edge(54.0));
        let between = turn_along_chord(&ctx, &options, &a, &b).expect("poses between");
        assert_eq!(between.len(), 4, "24° in five moves of at most 5°");
        let surface = block.collider.surface();
        let mut previous = a;
        for pose in between.iter().chain(std::iter::once(&b)) {
            assert!(angle_between(&previous.axis, &pose.axis).to_degrees() <= 5.0 + 1e-9);
            let centre = pose.tip + pose.axis.into_inner() * r;
            let nearest = surface.closest(&centre, 2.0 * r).expect("near the corner");
            assert!(
                (nearest.distance - r).abs() < 1e-9,
                "{centre:?} is {} off the part",
                nearest.distance
            );
            previous = *pose;
        }
        // The middle of the chord itself stands nearer than the radius: the poses were moved.
        let middle = nalgebra::center(
            &(a.tip + a.axis.into_inner() * r),
            &(b.tip + b.axis.into_inner() * r),
        );
        assert!(surface.closest(&middle, 2.0 * r).expect("near").distance < r - 0.01);

        let upright_only = |axis: &Vector3| axis.x < 0.6 || axis.x > 0.75;
        let refused = FinishingContext {
            reachable: &upright_only,
            ..ctx
        };
        assert_eq!(turn_along_chord(&refused, &options, &a, &b), None);
    }

    /// The flutes between two poses whose ends are clear: the axis turns a right angle about
    /// a still ball centre, and half-way its flutes pass through a small cube the flutes at
    /// either end miss; turned the other way round the move is clear.
    #[test]
    fn flutes_turning_through_a_post_between_two_clear_poses_are_caught() {
        let tool = crate::collide::tool_bodies::tests::prepared();
        let (length, _) = tool.flutes_above_ball().expect("a ball-end mill");
        let r = tool.ball_radius;
        // A 1 mm cube on the diagonal between +x and +y, a millimetre below the flutes' top.
        let d = (length - 1.0) / 2f64.sqrt();
        let post = crate::mesh::fixtures::box_between(
            Point3::new(d - 0.5, d - 0.5, -0.5),
            Point3::new(d + 0.5, d + 0.5, 0.5),
        );
        let collider = PartCollider::new(&post).unwrap();
        let rays = RayScene::new(&post);
        let chooser = AxisChooser::new(crate::orient::AxisOptions::default());
        let ctx = FinishingContext {
            part: &collider,
            rays: &rays,
            tool: &tool,
            chooser: &chooser,
            reachable: &anywhere,
            allowance: 0.0,
            lift: 0.0,
            material_filter: None,
            axis_field: None,
            region: None,
        };
        let options = FinishingOptions::default();
        let centre = Point3::origin();
        let flutes_clear = |axis: &Vector3| {
            !collider.surface().segment_within(
                &centre,
                &(centre + axis * length),
                r - options.tolerance,
            )
        };
        let (x, y) = (
            Direction::new_normalize(Vector3::x()),
            Direction::new_normalize(Vector3::y()),
        );
        assert!(flutes_clear(&x) && flutes_clear(&y), "both ends clear");
        assert!(!flutes_clear_along(
            &ctx,
            &options,
            (&centre, &x),
            (&centre, &y)
        ));
        let (minus_x, minus_y) = (-x, -y);
        assert!(flutes_clear_along(
            &ctx,
            &options,
            (&centre, &minus_x),
            (&centre, &minus_y)
        ));
    }

    /// A copy steps the way its source stepped: a pass with no pass direction (a ball rolled
    /// round an edge, its drive point still) is copied whole, where the copy once split it at
    /// every pose and kept none.
    #[test]
    fn a_copy_without_pass_directions_keeps_its_passes_whole() {
        let block = block();
        let ctx = block.context(0.0);
        let options = FinishingOptions {
            scallop_height: 0.5,
            tolerance: 0.02,
            drive_normal: Vector3::y(),
            ..FinishingOptions::default()
        };
        let mut source = finishing_passes(&block.part, &ctx, &options, &|| {});
        for segment in &mut source.segments {
            segment.pass_directions.fill(Vector3::zeros());
        }
        let rotation = nalgebra::Rotation3::identity();
        let (copy, stats) = turned_copy(&source, &rotation, &Point3::origin(), &ctx, &options);
        assert_eq!(stats.splits, 0, "{stats:?}");
        let lengths = |f: &Finishing| f.segments.iter().map(|s| s.poses.len()).collect::<Vec<_>>();
        assert_eq!(lengths(&copy), lengths(&source));
    }

    /// Distance from `p` to the box [0,40]×[0,30]×[0,10] (closed form, outside it).
    fn box_distance(p: &Point3) -> f64 {
        let gap = |v: f64, hi: f64| (-v).max(v - hi).max(0.0);
        Vector3::new(gap(p.x, 40.0), gap(p.y, 30.0), gap(p.z, 10.0)).norm()
    }

    /// An offset layer over a block: the ball is held r + a off it (measured here in closed
    /// form, not by the planner's distance queries), and only where the "material" — a slab
    /// over the block's left end, x < 12 — is within the ball shrunk by a quarter of a mm,
    /// plus the lead: no pose's ball centre lies beyond x = 12 + r + lead.
    #[test]
    fn an_offset_layer_holds_its_allowance_and_cuts_only_near_material() {
        let block = block();
        let (part, tool) = (&block.part, &block.tool);
        let r = tool.ball_radius;
        let (allowance, lead, least_cut) = (1.5, 2.0, 0.25);
        // The material: x < 12, up to 5 mm over the top face. A ball meets it when its
        // distance to that slab is below the radius.
        let slab = |c: &Point3| {
            let gap = |v: f64, lo: f64, hi: f64| (lo - v).max(v - hi).max(0.0);
            Vector3::new(
                gap(c.x, -5.0, 12.0),
                gap(c.y, -5.0, 35.0),
                gap(c.z, 10.0, 15.0),
            )
            .norm()
        };
        let touches = |c: &Point3, radius: f64| slab(c) < radius - least_cut;
        let layer = MaterialFilter {
            touches: &touches,
            lead,
        };
        let ctx = FinishingContext {
            material_filter: Some(&layer),
            ..block.context(allowance)
        };
        let options = FinishingOptions {
            scallop_height: 0.2,
            tolerance: 0.02,
            drive_normal: Vector3::y(),
            ..FinishingOptions::default()
        };
        let passes = finishing_passes(part, &ctx, &options, &|| {});
        assert!(passes.points_in_air > 0, "the block's right end is air");
        let poses: Vec<&ToolPose> = passes.segments.iter().flat_map(|s| &s.poses).collect();
        assert!(poses.len() > 50, "{} poses", poses.len());
        let centres: Vec<Point3> = poses
            .iter()
            .map(|p| p.tip + p.axis.into_inner() * r)
            .collect();
        for c in &centres {
            let d = box_distance(c);
            assert!(
                d >= r + allowance - 1e-6,
                "centre {c:?} is {d} from the block"
            );
            assert!(
                c.x <= 12.0 + r + lead + 1e-6,
                "centre {c:?} is beyond the material"
            );
        }
        // Every chord too, sampled: within the chord tolerance of the allowance.
        for s in &passes.segments {
            for w in s.poses.windows(2) {
                let (a, b) = (
                    w[0].tip + w[0].axis.into_inner() * r,
                    w[1].tip + w[1].axis.into_inner() * r,
                );
                for k in 1..16 {
                    let d = box_distance(&(a + (b - a) * (k as f64 / 16.0)));
                    assert!(d >= r + allowance - options.tolerance - 1e-6);
                }
            }
        }
        // The top face is cut where the slab is: some ball sits on it, over x < 12.
        assert!(
            centres
                .iter()
                .any(|c| c.x < 10.0 && (c.z - (10.0 + r + allowance)).abs() < 1e-6)
        );
        // Without the layer's test the whole block is driven.
        let all = finishing_passes(
            part,
            &FinishingContext {
                material_filter: None,
                ..ctx
            },
            &options,
            &|| {},
        );
        assert_eq!(all.points_in_air, 0);
        assert!(
            all.segments
                .iter()
                .any(|s| s.poses.iter().any(|p| p.tip.x > 12.0 + r + lead + 1.0))
        );
    }

    /// Drive planes against −Z are waterlines cut from the top down (what channel roughing
    /// relies on to bound its depth of cut): the passes' heights never rise.
    #[test]
    fn waterlines_against_minus_z_run_from_the_top_down() {
        let block = block();
        let (part, tool) = (&block.part, &block.tool);
        let ctx = block.context(1.0);
        let options = FinishingOptions {
            scallop_height: 0.3,
            tolerance: 0.02,
            drive_normal: -Vector3::z(),
            ..FinishingOptions::default()
        };
        let passes = finishing_passes(part, &ctx, &options, &|| {});
        let heights: Vec<f64> = passes
            .segments
            .iter()
            .map(|s| s.poses[0].tip.z + s.poses[0].axis.z * tool.ball_radius)
            .collect();
        assert!(heights.len() >= 4, "{heights:?}");
        assert!(
            heights.windows(2).all(|w| w[1] <= w[0] + 1e-9),
            "{heights:?}"
        );
        assert!(heights[0] - heights[heights.len() - 1] > 5.0, "{heights:?}");
    }

    /// A block 30 mm long (along y) with a round trough of radius 8 in its top, its axis at
    /// z = 12 and its walls rising to ±60° (z = 8), facetted every degree. The ends are
    /// strips down from the top to the bottom at z = −30 (slivers a fan would make pile up in
    /// the ray tree).
    fn trough() -> Mesh {
        let (radius, axis_z, length, bottom) = (8.0, 12.0, 30.0, -30.0);
        // The top from its right edge to its left, over the trough.
        let mut top = vec![(10.0, 8.0)];
        for k in 0..=120 {
            let angle = (60.0 - f64::from(k)).to_radians();
            top.push((radius * angle.sin(), axis_z - radius * angle.cos()));
        }
        top.push((-10.0, 8.0));
        let n = top.len() as u32;
        let mut positions = Vec::new();
        for y in [0.0, length] {
            positions.extend(top.iter().map(|&(x, z)| Point3::new(x, y, z)));
            positions.extend(top.iter().map(|&(x, _)| Point3::new(x, y, bottom)));
        }
        // Top and bottom of the profile at each end.
        let (top0, bottom0, top1, bottom1) = (|i| i, |i| n + i, |i| 2 * n + i, |i| 3 * n + i);
        let mut triangles = Vec::new();
        for i in 0..n - 1 {
            let j = i + 1;
            triangles.push([top0(i), top1(j), top0(j)]);
            triangles.push([top0(i), top1(i), top1(j)]);
            triangles.push([bottom0(i), bottom0(j), bottom1(j)]);
            triangles.push([bottom0(i), bottom1(j), bottom1(i)]);
            triangles.push([top0(i), top0(j), bottom0(j)]);
            triangles.push([top0(i), bottom0(j), bottom0(i)]);
            triangles.push([top1(i), bottom1(j), top1(j)]);
            triangles.push([top1(i), bottom1(i), bottom1(j)]);
        }
        let last = n - 1;
        triangles.push([bottom0(0), top1(0), top0(0)]);
        triangles.push([bottom0(0), bottom1(0), top1(0)]);
        triangles.push([bottom0(last), top0(last), top1(last)]);
        triangles.push([bottom0(last), top1(last), bottom1(last)]);
        Mesh {
            positions,
            triangles,
        }
    }

    /// Drive points 20° apart round the trough: the ball centres stand on a circle of radius
    /// 5, where a 20° chord sags 0.076 mm off the wall. Every chord of the pass comes within
    /// the sag tolerance of the wall at its middle (closed form) and none cuts into it, in one
    /// pass.
    #[test]
    fn chords_round_a_concave_wall_are_mended_where_they_sag() {
        let trough = Block::of(trough());
        assert!(
            trough.part.signed_volume() > 0.0,
            "the trough is wound outward"
        );
        let ctx = trough.context(0.0);
        let tool = &trough.tool;
        // A finish to 0.01 mm keeps a tenth of it for the sag: 0.001 mm.
        let options = FinishingOptions {
            tolerance: 0.005,
            ..FinishingOptions::default()
        }
        .leaving_at_most(0.01);
        assert!((options.sag_tolerance - SAG_SHARE * 0.01).abs() < 1e-15);
        let (radius, axis_z) = (8.0, 12.0);
        let points: Vec<DrivePoint> = (0..6)
            .map(|k| {
                let angle = (-50.0 + 20.0 * f64::from(k)).to_radians();
                let (sin, cos) = angle.sin_cos();
                DrivePoint {
                    point: Point3::new(radius * sin, 15.0, axis_z - radius * cos),
                    normal: Vector3::new(-sin, 0.0, cos),
                }
            })
            .collect();
        let mut out = Finishing::default();
        drive_curve(&points, &ctx, &options, &mut out);
        assert_eq!(out.segments.len(), 1, "one pass: {:?}", out.unreachable);
        let r = tool.ball_radius;
        let centres: Vec<Point3> = out.segments[0]
            .poses
            .iter()
            .map(|p| p.tip + p.axis.into_inner() * r)
            .collect();
        assert!(centres.len() > 6, "poses inserted: {}", centres.len());
        // From a point inside the trough to its wall: the radius less the distance from the
        // trough's axis.
        let to_wall = |p: &Point3| radius - (p.x.powi(2) + (p.z - axis_z).powi(2)).sqrt();
        for w in centres.windows(2) {
            let middle = nalgebra::center(&w[0], &w[1]);
            let d = to_wall(&middle);
            assert!(
                d <= r + options.sag_tolerance + 1e-6,
                "the chord from {:?} to {:?} stands {} off the wall",
                w[0],
                w[1],
                d - r
            );
            for k in 0..=16 {
                let p = w[0] + (w[1] - w[0]) * (f64::from(k) / 16.0);
                assert!(to_wall(&p) >= r - options.tolerance - 1e-6);
            }
        }
    }
}
