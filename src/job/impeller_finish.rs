//! Finishing an impeller with its own strategies (issue 21): flow-line passes over the hub
//! between two blades ([`crate::impeller::passage`]; they run past a splitter on either side
//! of it) and loops around the blade and each splitter in the passage
//! ([`crate::impeller::blade`]; partial loops where the flank leans), planned for one passage
//! and copied to the others by the symmetry, each copy checked on the part
//! ([`crate::path::turned_copy`]); the parallel planes finish what the impeller strategies
//! leave (nose, bore, rim), their drive points on the hub, blades and splitters left out.
//!
//! Axes. On the hub the preferred axis is either one axis per passage (the mean of the walls'
//! span directions down its middle: the rotary axes stand still along the passes) or the
//! walls' span directions interpolated across the passage, leaning toward the feed. Around a
//! blade it is either the same axis turned to the blade (the rotary axes stand still round
//! the loop) or the blade's rising direction leaned off the surface by `blade_lean_deg`, so
//! the tool stands along the blade and the ball cuts with its side. Both are kept off the
//! machine's pole; the chooser searches around them with the exact checks as everywhere.

use std::time::Instant;

use serde::Serialize;

use super::config::{BladeAxes, HubAxes};
use super::impeller_rest::{
    COPIES_REACH, COPIES_ROUNDS, COPIES_SAMPLE_SPACING, LeftPlaces, PASSAGE_REACH, PASSAGE_ROUNDS,
    PASSAGE_SAMPLE_SPACING, PLANES_ROUNDS, RestScope, RestSummary, RestTarget,
    angle_past_first_blade, passage_turn, passage_views, rest_passes,
};
use crate::access::{
    DirectionSet, RayScene, SurfacePoint, VisibilityOptions, region_axis, visibility_hierarchical,
};
use crate::geom::{Direction, ToolPose};
use crate::geom::{Point3, Vector3};
use crate::impeller::blade::needed_stretches;
use crate::impeller::hub_wall::{HubWall, wall_loops};
use crate::impeller::{
    HubPassage, Impeller, NotSwarf, PassageOptions, Region, Ruling, SwarfOptions, SwarfPlan,
    blade_loop_at, blade_loops, blade_section_at, blade_tip_passes, swarf_runs,
};
use crate::mesh::Mesh;
use crate::orient::{AxisTurn, away_from_pole, preferred_axis};
use crate::path::{
    self, CoverOptions, Covered, CutSegment, Finishing, FinishingContext, FinishingOptions,
    LinkOptions, SweptBalls, TurnedCopy,
};

/// Distance between the stations along the hub's meridian, mm.
const STATION_STEP: f64 = 0.25;

/// Least tilt of the tool from the machine's pole (its C axis), degrees: nearer, C swings
/// fast for small changes of the tool axis.
const MIN_TILT_FROM_POLE_DEG: f64 = 15.0;

/// How far a partial flow line runs on past where it is needed, in stepovers.
const OVERLAP_STEPOVERS: f64 = 4.0;

/// How far a partial loop round a blade runs on past where it is needed, in stepovers: the
/// ball's end covers its radius beyond the last centre, and every piece costs a link.
const PARTIAL_LOOP_OVERLAP_STEPOVERS: f64 = 1.0;

/// Height of the root pass's drive section above the hub, in the loops' level steps (the
/// lowest loop stands at half a step): every ball of it comes to rest in the corner.
const ROOT_LEVEL_STEPS: f64 = 0.25;

/// The root pass round blade or splitter `piece` (its region) of `passage`, every ball in the
/// corner: the section a quarter of the loops' `level_step` above the hub, a loop round the
/// piece or stretches where the hub rises off its meridian's fit and the level runs into it,
/// planned like a loop. With what it planned, or why there is none.
pub fn root_pass(
    part: &Mesh,
    impeller: &Impeller,
    passage: &HubPassage,
    piece: Region,
    level_step: f64,
    ctx: &FinishingContext,
    options: &FinishingOptions,
) -> (Finishing, Result<RootPass, String>) {
    let (Region::Blade(index) | Region::Splitter(index)) = piece else {
        return (
            Finishing::default(),
            Err(format!("{piece:?} is neither a blade nor a splitter")),
        );
    };
    let level = ROOT_LEVEL_STEPS * level_step;
    let curves = blade_section_at(part, impeller, passage, index as usize, level);
    let mut root = Finishing::default();
    // A pass of a few hundred poses: no progress of its own.
    for result in path::curve_passes(&curves, ctx, options, &|| {}) {
        root.merge(result);
    }
    if root.segments.is_empty() {
        let why = format!("no pass on the piece {level:.3} mm above the hub");
        return (root, Err(why));
    }
    let summary = root_pass_summary(
        &root,
        level,
        ctx.tool.ball_radius,
        ctx.part.surface(),
        &impeller.regions,
        piece,
    );
    (root, Ok(summary))
}

/// What the root pass planned: its length, and how many of its balls touch hub and blade.
fn root_pass_summary(
    root: &Finishing,
    level: f64,
    radius: f64,
    surface: &crate::mesh::SurfaceDistance,
    regions: &[Region],
    piece: Region,
) -> RootPass {
    let reach = radius + path::CONTACT_BAND;
    let mut both = 0;
    let mut poses = 0;
    let mut length = 0.0;
    for segment in &root.segments {
        let centres: Vec<Point3> = segment
            .poses
            .iter()
            .map(|p| p.tip + p.axis.into_inner() * radius)
            .collect();
        length += centres
            .windows(2)
            .map(|w| (w[1] - w[0]).norm())
            .sum::<f64>();
        for c in &centres {
            poses += 1;
            let hub = surface.closest_where(c, reach, |t| regions[t as usize] == Region::Hub);
            let blade = surface.closest_where(c, reach, |t| regions[t as usize] == piece);
            if hub.is_some() && blade.is_some() {
                both += 1;
            }
        }
    }
    RootPass {
        level_mm: level,
        length_mm: length,
        poses,
        touching_both: both as f64 / poses.max(1) as f64,
    }
}

/// How the impeller strategies are asked to run.
#[derive(Clone, Debug, PartialEq)]
pub struct ImpellerFinishOptions {
    pub hub_axes: HubAxes,
    pub blade_axes: BladeAxes,
    /// How far the tool leans off a blade's surface, degrees.
    pub blade_lean_deg: f64,
    /// Swarf a blade where it is ruled within the tolerance (the loops for the rest).
    pub swarf: bool,
    /// Passes along the blade's tip where the loops leave its land.
    pub tip: bool,
    /// Rest passes where the first passage's passes, then the planes, leave the scallop over
    /// the target.
    pub rest: bool,
    /// The tool axis at which the machine's rotary axes are singular (part frame).
    pub pole: Vector3,
    /// How the segments will be linked: a swarf run counts as cut only where the tool can
    /// leave its ends to the safe plane.
    pub link: LinkOptions,
    /// The machine's fastest rotary motion, degrees per minute: a link that turns the
    /// rotaries lasts at least the turn over this.
    pub max_rotary_speed: f64,
    /// Corner finishing with a smaller ball: only the band this far (mm) from each blade's and
    /// splitter's root, on the hub beside it and up its sides (the loops, the flow lines
    /// beside it and the root pass), no swarf, tip passes or planes. `None`: the whole part.
    pub corner_band: Option<f64>,
}

/// What the hub finishing planned.
#[derive(Clone, Debug, Serialize)]
pub struct HubSummary {
    pub flow_triangles: usize,
    pub flow_area_mm2: f64,
    /// Largest distance of a hub vertex from the meridian found, mm.
    pub profile_fit_mm: f64,
    pub stations: usize,
    /// Flow lines across one passage, and how many of them are partial (inserted only where
    /// the passage is wide, alg. 5.1).
    pub flow_lines: usize,
    pub partial_lines: usize,
    pub axes: HubAxes,
    /// How the passage's axis came from the visibility maps (`hub_axes = "visibility"`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub visibility: Option<PassageVisibility>,
}

/// The passage's axis from its points' visibility maps.
#[derive(Clone, Debug, Serialize)]
pub struct PassageVisibility {
    /// Points of the passage whose maps were computed, and how many of them see the axis.
    pub points: usize,
    pub seen_by: usize,
    /// Directions (of 2,562, ≈ 4° apart) every point sees.
    pub common_directions: usize,
    /// Angle from the axis to the nearest direction not every point sees (or not as many),
    /// degrees, to the set's spacing.
    pub room_deg: f64,
    /// Angle between the axis and the walls' mean span direction, degrees.
    pub from_walls_deg: f64,
    pub rays_cast: u64,
    /// Time of the maps and the choice, ms (part of the report's `impeller_first_passage`
    /// timing; left out of the report's figures, which must not change from run to run).
    #[serde(skip)]
    pub ms: f64,
}

/// What the blade finishing planned (for one blade; the others are its copies).
#[derive(Clone, Debug, Serialize)]
pub struct BladeSummary {
    pub levels: usize,
    pub loops: usize,
    /// Stretches of loops between the levels, where the flank leans so that the levels stand
    /// farther apart than the stepover (alg. 5.1).
    pub partial_loops: usize,
    /// Height between levels, mm.
    pub level_step_mm: f64,
    /// The blade's height above the hub, mm.
    pub height_mm: f64,
    pub axes: BladeAxes,
    pub lean_deg: f64,
    /// With `blade_axes = "visibility"`: the maps of points round the blade and the axis
    /// chosen from them (`from_walls_deg`: from the passages' axis turned to the blade).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub visibility: Option<PassageVisibility>,
    /// The pass round the blade's root (its fillet, or the ball touching hub and blade where
    /// the root is sharper than the ball), or why there is none.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub root_pass: Option<RootPass>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub no_root_pass: Option<String>,
    /// The passes along the tip's land (where the loops leave it), if it has one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tip: Option<TipPasses>,
    /// The swarf runs that finish the blade's ruled stretches (the loops take the rest).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub swarf: Option<SwarfSummary>,
    /// Why no stretch of the blade is swarfed (swarf asked for): the loops finish it all.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub not_swarfed: Option<NotSwarf>,
}

/// The pass round a blade's root: the loop just above the hub, where the ball placed against
/// the part comes to rest in the corner (on the fillet where the fillet is as large as the
/// ball, else touching hub and blade both: the pencil line).
#[derive(Clone, Debug, Serialize)]
pub struct RootPass {
    /// Height of the drive loop above the hub, mm.
    pub level_mm: f64,
    /// Length of the ball centres' path and poses, as planned.
    pub length_mm: f64,
    pub poses: usize,
    /// Share of the poses whose ball touches both hub and blade (within a micrometre).
    pub touching_both: f64,
}

/// The passes along a blade's tip: the curves across its land, the land's area and width,
/// and the segments kept where the loops leave it.
#[derive(Clone, Debug, Serialize)]
pub struct TipPasses {
    pub curves: usize,
    pub land_area_mm2: f64,
    pub width_mm: f64,
    pub segments_kept: usize,
}

/// The root pass and tip passes of one splitter (by its index in the impeller's pieces).
#[derive(Clone, Debug, Serialize)]
pub struct SplitterPasses {
    pub piece: usize,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub root_pass: Option<RootPass>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub no_root_pass: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tip: Option<TipPasses>,
}

/// A splitter of the first passage as planned: its loops, the passes along its tip and its
/// root pass (before the coverage rule), and the context they were planned in.
/// A passage's passes, turned from the first passage's.
struct CopiedPassage {
    hub: Finishing,
    blade: Finishing,
    swarf: Option<Finishing>,
    splitters: Vec<Finishing>,
}

struct PlannedSplitter<'a> {
    loops: Finishing,
    tip: crate::impeller::BladeTip,
    tip_passes: Finishing,
    root: Finishing,
    ctx: FinishingContext<'a>,
}

/// What the tip passes planned, when the piece has a land.
fn tip_summary_of(tip: &crate::impeller::BladeTip, kept: &Finishing) -> Option<TipPasses> {
    (!tip.curves.is_empty()).then_some(TipPasses {
        curves: tip.curves.len(),
        land_area_mm2: tip.land_area_mm2,
        width_mm: tip.width_mm,
        segments_kept: kept.segments.len(),
    })
}

/// The swarf runs round one blade.
#[derive(Clone, Debug, Serialize)]
pub struct SwarfSummary {
    /// Stretches of the root swarfed, and the rulings the tool stands along in them.
    pub runs: usize,
    pub rulings: usize,
    /// Rulings dropped because their ball centre stepped back along the run.
    pub rulings_stepping_back: usize,
    /// Points of the root tried, and the ones refused by reason (the loops finish there).
    pub root_points: usize,
    pub refused: std::collections::BTreeMap<String, usize>,
    /// Largest deviation between the flutes and the flank, either way, mm.
    pub deviation_mm: f64,
    /// Longest stretch of flank along a ruling above the ball's centre, mm.
    pub flank_length_mm: f64,
    /// Height of the root loop above the hub, mm.
    pub root_height_mm: f64,
    /// Runs in the other passages (copied by the symmetry) with no clear way in or out: the
    /// link trims them back to where the tool can leave.
    pub copied_runs_without_leads: usize,
}

/// What the impeller finishing planned, by strategy.
#[derive(Clone, Debug, Serialize)]
pub struct ImpellerFinishSummary {
    pub hub: Option<HubSummary>,
    pub blade: Option<BladeSummary>,
    /// Splitters in each passage finished by their own loops, and the loops (full and partial)
    /// round them in one passage.
    pub splitters: usize,
    pub splitter_loops: usize,
    /// The pass round each splitter's root in the first passage (copied with it), or why
    /// there is none, and the passes along its tip.
    pub splitter_passes: Vec<SplitterPasses>,
    /// Why the hub and blades are finished by the planes instead, when they are.
    pub not_planned: Option<String>,
    /// Passages (each with its blade) planned, and copied from the first.
    pub passages: usize,
    /// Planning the first passage and its blade, and copying them to the others, ms (in the
    /// report's timings, which a byte-identical report leaves out).
    #[serde(skip)]
    pub first_passage_ms: f64,
    #[serde(skip)]
    pub copies_ms: f64,
    pub copies: TurnedCopy,
    /// Stretches of the first passage's passes dropped because what their ball touches the
    /// passes before them already came as near (the copies follow).
    pub covered: Covered,
    /// Drive points of the planes over the regions the impeller strategies finish.
    pub plane_points_left_to_impeller: usize,
    /// Passes along the places the first passage's passes left over the scallop target.
    pub rest: Option<RestSummary>,
    /// Passes along the places the copies, as the part has them, left over the target
    /// (every passage measured among the passes as copied).
    pub copies_rest: Option<RestSummary>,
    /// Passes along the places the planes left over the scallop target (the part outside
    /// the impeller strategies' surface, measured against every pass).
    pub plane_rest: Option<RestSummary>,
    /// Loops round the bore and the rim, when the hub has them.
    pub bore: Option<HubWallSummary>,
    pub rim: Option<HubWallSummary>,
}

/// What the loops round a hub wall (the bore, the rim) planned.
#[derive(Clone, Debug, Serialize)]
pub struct HubWallSummary {
    /// Area of the wall, mm², its height along the axis and the step between loops, mm.
    pub wall_area_mm2: f64,
    pub height_mm: f64,
    pub level_step_mm: f64,
    /// How far the ball stands off the deepest crease between the wall's facets (the step
    /// leaves the rest of the scallop target between the loops), mm.
    pub crease_standoff_mm: f64,
    /// Curves at the levels, the segments planned along them, and their drive points no
    /// tool axis reached.
    pub loops: usize,
    pub segments: usize,
    pub unreachable_points: usize,
}

/// Plans the finishing of `part` (recognised as `impeller`): hub flow lines and blade loops
/// for every passage, then the parallel planes over `drive` for the rest. A corner finish
/// (`impeller_options.corner_band`) plans only the band round the roots, and of it only the
/// stretches of its passes over points an operation before it has not `finished` (within
/// the scallop target): rest finishing.
#[allow(clippy::too_many_arguments)]
pub fn finish_impeller(
    part: &Mesh,
    drive: &Mesh,
    impeller: &Impeller,
    ctx: &FinishingContext,
    options: &FinishingOptions,
    impeller_options: &ImpellerFinishOptions,
    finished: Option<&(dyn Fn(&Point3) -> bool + Sync)>,
    advance: &(dyn Fn() + Sync),
) -> (Finishing, ImpellerFinishSummary) {
    let radius = ctx.tool.ball_radius;
    let stepover = path::stepover_for_scallop(radius, options.scallop_height);
    let passage_options = PassageOptions {
        station_step: STATION_STEP,
        ball_radius: radius,
        scallop_height: options.scallop_height,
        overlap: OVERLAP_STEPOVERS * stepover,
    };
    let mut finishing = Finishing::default();
    let mut summary = ImpellerFinishSummary {
        hub: None,
        blade: None,
        splitters: 0,
        splitter_loops: 0,
        splitter_passes: Vec::new(),
        not_planned: None,
        passages: 0,
        first_passage_ms: 0.0,
        copies_ms: 0.0,
        copies: TurnedCopy::default(),
        covered: Covered::default(),
        plane_points_left_to_impeller: 0,
        rest: None,
        copies_rest: None,
        plane_rest: None,
        bore: None,
        rim: None,
    };
    let mut handled = vec![false; part.triangles.len()];
    let mut summary_visibility = None;
    // A rest pass goes where it adds the least to the links, their travel and the turn of the
    // rotaries (as the machine turns them: near C's pole a small change of the tool's axis is
    // a large turn of C), a degree of which lasts as long as a link's approach feed covers
    // this many millimetres.
    let turn = options
        .axis_smoothing
        .as_ref()
        .map_or(AxisTurn::Angle, |s| s.turn);
    let mm_per_degree = impeller_options.link.approach_feed / impeller_options.max_rotary_speed;
    let link_cost = |a: &ToolPose, b: &ToolPose| {
        (b.tip - a.tip).norm()
            + mm_per_degree
                * turn
                    .between(&a.axis.into_inner(), &b.axis.into_inner())
                    .to_degrees()
    };
    match HubPassage::new(part, impeller, &passage_options) {
        Ok(passage) => {
            let t = Instant::now();
            let pole = impeller_options.pole;
            // Leans `axis` off the pole toward the outside of the wheel at `p`.
            let off_pole = |p: &Point3, axis: &Vector3| {
                let (_, angle, _) = passage.frame.cylindrical(p);
                let radial = passage.frame.radial(angle);
                let outward = (radial - pole * pole.dot(&radial))
                    .try_normalize(1e-9)
                    .unwrap_or(radial);
                away_from_pole(axis, &pole, &outward, MIN_TILT_FROM_POLE_DEG)
            };

            // The hub: flow lines across passage 0.
            let lines = passage.flow_lines(&passage_options);
            let mut curves = passage.drive_curves(&lines, ctx.part.surface());
            let corner_band = impeller_options.corner_band;
            if let Some(band) = corner_band {
                // The stretches of the flow lines beside a blade or splitter.
                let surface = ctx.part.surface();
                let beside_wall = |p: &Point3| {
                    !finished.is_some_and(|f| f(p))
                        && surface
                            .closest_where(p, band, |t| {
                                matches!(
                                    impeller.regions[t as usize],
                                    Region::Blade(_) | Region::Splitter(_)
                                )
                            })
                            .is_some()
                };
                curves = curves
                    .iter()
                    .flat_map(|curve| {
                        let needed: Vec<bool> =
                            curve.points.iter().map(|p| beside_wall(&p.point)).collect();
                        needed_stretches(curve, &needed, PARTIAL_LOOP_OVERLAP_STEPOVERS * stepover)
                    })
                    .collect();
            }
            let lead = ctx.chooser.options().lead_deg;
            let (mean, middle) = passage.mean_wall_axis();
            let hub_axes = impeller_options.hub_axes;
            let hub_mean = if hub_axes == HubAxes::Visibility {
                let (axis, figures, _) = visible_passage_axis(
                    &passage,
                    mean,
                    middle,
                    ctx.rays,
                    ctx.tool.ball_radius,
                    ctx.tool.reach,
                );
                summary_visibility = Some(figures);
                axis
            } else {
                mean
            };
            let hub_field = |p: &Point3, _normal: &Vector3, feed: &Vector3| {
                let axis = match hub_axes {
                    HubAxes::Passage | HubAxes::Visibility => {
                        // The passage's own axis, turned to the passage `p` is in.
                        let (_, angle, _) = passage.frame.cylindrical(p);
                        let k = ((angle - middle) / passage.pitch).round();
                        let radial = passage.frame.radial(middle + k * passage.pitch);
                        passage.frame.axis * hub_mean[0]
                            + radial * hub_mean[1]
                            + passage.frame.axis.cross(&radial) * hub_mean[2]
                    }
                    HubAxes::Walls => preferred_axis(&passage.wall_axis(p), feed, lead, 0.0),
                };
                off_pole(p, &axis)
            };
            let hub_ctx = FinishingContext {
                axis_field: Some(&hub_field),
                ..*ctx
            };
            let mut hub = Finishing::default();
            for result in path::curve_passes(&curves, &hub_ctx, options, advance) {
                hub.merge(result);
            }
            // One fixed axis leaves the passes free to run either way; leaning toward the
            // feed does not.
            hub.segments = path::nearest_order(
                std::mem::take(&mut hub.segments),
                hub_axes != HubAxes::Walls,
                &link_cost,
            );

            // The blade passage 0 starts at: loops from the tip down.
            let loops = blade_loops(
                part,
                impeller,
                &passage,
                passage.first_blade,
                stepover,
                PARTIAL_LOOP_OVERLAP_STEPOVERS * stepover,
            );
            let lean = impeller_options.blade_lean_deg.to_radians();
            let blade_axes = impeller_options.blade_axes;
            // The blade stands half a pitch before the middle of its passage.
            let blade_angle = middle - 0.5 * passage.pitch;
            // The blade's one axis as (axial, radial, tangential) at its own angle: the
            // passages' axis turned to it, or from the maps of points round it.
            let mut blade_visibility = None;
            let blade_mean = if blade_axes == BladeAxes::Visibility {
                let t = Instant::now();
                let radial = passage.frame.radial(blade_angle);
                let tangent = passage.frame.axis.cross(&radial);
                let default = passage.frame.axis * mean[0] + radial * mean[1] + tangent * mean[2];
                let (direction, figures) = visible_axis(
                    &blade_visibility_points(&loops),
                    &default,
                    ctx.rays,
                    ctx.tool.ball_radius,
                    ctx.tool.reach,
                    t,
                );
                blade_visibility = Some(figures);
                [
                    direction.dot(&passage.frame.axis),
                    direction.dot(&radial),
                    direction.dot(&tangent),
                ]
            } else {
                mean
            };
            let (passage_ref, off_pole_ref) = (&passage, &off_pole);
            // The preferred axis round the blade or splitter standing at angle `reference`
            // (and its copies a pitch apart).
            let field_for = |reference: f64| {
                move |p: &Point3, normal: &Vector3, _feed: &Vector3| {
                    let axis = match blade_axes {
                        BladeAxes::Blade | BladeAxes::Visibility => {
                            // The blade's axis, turned to the piece `p` is on.
                            let (_, angle, _) = passage_ref.frame.cylindrical(p);
                            let k = ((angle - reference) / passage_ref.pitch).round();
                            let radial =
                                passage_ref.frame.radial(reference + k * passage_ref.pitch);
                            passage_ref.frame.axis * blade_mean[0]
                                + radial * blade_mean[1]
                                + passage_ref.frame.axis.cross(&radial) * blade_mean[2]
                        }
                        BladeAxes::Lean => {
                            let (_, up) = passage_ref.above_hub(p);
                            let across = up - normal * normal.dot(&up);
                            // On the tip the rising direction is the normal itself.
                            let rising = if across.norm() > 0.3 {
                                across.normalize()
                            } else {
                                up
                            };
                            rising * lean.cos() + normal * lean.sin()
                        }
                    };
                    off_pole_ref(p, &axis)
                }
            };
            let blade_field = field_for(blade_angle);
            let blade_ctx = FinishingContext {
                axis_field: Some(&blade_field),
                ..*ctx
            };
            // The loops' curves, less what `covered` says another strategy sweeps (each
            // stretch left run on by the partial loops' overlap).
            let plan_loops =
                |loops: &crate::impeller::BladeLoops,
                 piece_ctx: &FinishingContext,
                 covered: Option<&(dyn Fn(&Point3) -> bool + Sync)>| {
                    let mut finishing = Finishing::default();
                    let all = loops.curves.iter().chain(&loops.partial);
                    let curves: Vec<_> = match covered {
                        None => all.cloned().collect(),
                        Some(covered) => all
                            .flat_map(|curve| {
                                let needed: Vec<bool> =
                                    curve.points.iter().map(|p| !covered(&p.point)).collect();
                                needed_stretches(
                                    curve,
                                    &needed,
                                    PARTIAL_LOOP_OVERLAP_STEPOVERS * stepover,
                                )
                            })
                            .collect(),
                    };
                    for result in path::curve_passes(&curves, piece_ctx, options, advance) {
                        finishing.merge(result);
                    }
                    finishing.segments = path::nearest_order(
                        std::mem::take(&mut finishing.segments),
                        blade_axes != BladeAxes::Lean,
                        &link_cost,
                    );
                    finishing
                };
            // Swarf where the blade is ruled: the tool along the rulings, its flutes dipping
            // no more than the tolerance into the flank (the loops keep them off it); the
            // loops finish what the swarf runs do not sweep (the tip's rounding, unruled ends).
            let swarf_tool = ctx.tool.with_flute_dip(options.tolerance);
            let swarf_ctx = FinishingContext {
                tool: &swarf_tool,
                ..blade_ctx
            };
            // Into and out of a run off the flank, checked with the tool linking uses.
            let leads = |segment: &CutSegment| {
                swarf_leads(
                    segment,
                    &blade_ctx,
                    options.tolerance,
                    &impeller_options.link,
                )
            };
            // In a corner finish the loops are wanted only up the band.
            let above_band = |p: &Point3| {
                corner_band.is_some_and(|band| passage.above_hub(p).0 > band)
                    || finished.is_some_and(|f| f(p))
            };
            let band_covered: Option<&(dyn Fn(&Point3) -> bool + Sync)> =
                corner_band.map(|_| &above_band as &(dyn Fn(&Point3) -> bool + Sync));
            let swarfed = if impeller_options.swarf && corner_band.is_none() {
                Some(swarf_blade(
                    part, impeller, &passage, &swarf_ctx, options, pole, &leads,
                ))
            } else {
                None
            };
            let (swarf, mut blade, mut swarf_summary, not_swarfed) = match swarfed {
                Some(Ok((finishing, plan, summary))) => {
                    // Swept where the flutes pass within the scallop target of the flank.
                    let reach = radius + options.scallop_height;
                    let below = summary.root_height_mm;
                    let covered = |p: &Point3| plan.sweeps(p, reach, below);
                    let loops = plan_loops(&loops, &blade_ctx, Some(&covered));
                    (Some(finishing), loops, Some(summary), None)
                }
                Some(Err(why)) => (
                    None,
                    plan_loops(&loops, &blade_ctx, band_covered),
                    None,
                    Some(why),
                ),
                None => (
                    None,
                    plan_loops(&loops, &blade_ctx, band_covered),
                    None,
                    None,
                ),
            };

            // Passes along the tip's land, where the level loops cross it far apart.
            let tip = if impeller_options.tip && corner_band.is_none() {
                blade_tip_passes(part, impeller, &passage, passage.first_blade, stepover)
            } else {
                crate::impeller::BladeTip::default()
            };
            let mut tip_passes = Finishing::default();
            for result in path::curve_passes(&tip.curves, &blade_ctx, options, advance) {
                tip_passes.merge(result);
            }

            let (mut root, root_summary) = root_pass(
                part,
                impeller,
                &passage,
                Region::Blade(passage.first_blade as u32),
                loops.level_step,
                &blade_ctx,
                options,
            );
            let (blade_root_pass, no_root_pass) = match root_summary {
                Ok(summary) => (Some(summary), None),
                Err(why) => (None, Some(why)),
            };

            // The splitters in the passage: loops round each, both its sides, like the blade.
            let splitter_pieces = passage.splitters(impeller);
            let splitter_fields: Vec<_> = splitter_pieces
                .iter()
                .map(|&s| field_for(impeller.pieces[s].angle_deg.to_radians()))
                .collect();
            let mut splitters = Vec::new();
            let mut splitter_loops = 0;
            for (&piece, field) in splitter_pieces.iter().zip(&splitter_fields) {
                let piece_loops = blade_loops(
                    part,
                    impeller,
                    &passage,
                    piece,
                    stepover,
                    PARTIAL_LOOP_OVERLAP_STEPOVERS * stepover,
                );
                splitter_loops += piece_loops.curves.len() + piece_loops.partial.len();
                let piece_ctx = FinishingContext {
                    axis_field: Some(field),
                    ..*ctx
                };
                let (root, root_summary) = root_pass(
                    part,
                    impeller,
                    &passage,
                    Region::Splitter(piece as u32),
                    piece_loops.level_step,
                    &piece_ctx,
                    options,
                );
                summary.splitter_passes.push(SplitterPasses {
                    piece,
                    root_pass: root_summary.as_ref().ok().cloned(),
                    no_root_pass: root_summary.err(),
                    tip: None,
                });
                let tip = if impeller_options.tip && corner_band.is_none() {
                    blade_tip_passes(part, impeller, &passage, piece, stepover)
                } else {
                    crate::impeller::BladeTip::default()
                };
                let mut tip_passes = Finishing::default();
                for result in path::curve_passes(&tip.curves, &piece_ctx, options, advance) {
                    tip_passes.merge(result);
                }
                splitters.push(PlannedSplitter {
                    loops: plan_loops(&piece_loops, &piece_ctx, band_covered),
                    tip,
                    tip_passes,
                    root,
                    ctx: piece_ctx,
                });
            }

            // Passes are spaced on the drive surface, but in a corner tighter than the ball
            // the balls placed against the part collapse onto one pass: at the blade's root
            // the loops less than a radius above the hub and the flow lines beside the wall
            // all become the pass touching both. What a pass's ball touches that the passes
            // before it (swarf, loops, splitters, then the hub) came within half the scallop
            // target of is dropped.
            let mut swept = SweptBalls::new(CoverOptions {
                ball_radius: radius,
                slack: 0.5 * options.scallop_height,
                min_gap: 2.0 * radius,
                overlap: stepover,
                around: 0.5 * stepover,
            });
            if let Some(swarf) = &swarf {
                swarf.segments.iter().for_each(|s| swept.insert(s));
            }
            let surface = ctx.part.surface();
            let mut keep_needed = |finishing: &mut Finishing, may_reverse: bool| {
                let (kept, covered) =
                    swept.keep_needed(std::mem::take(&mut finishing.segments), surface);
                finishing.segments = path::nearest_order(kept, may_reverse, &link_cost);
                summary.covered.merge(&covered);
            };
            keep_needed(&mut blade, blade_axes != BladeAxes::Lean);
            // The tip's passes where the loops leave its land.
            keep_needed(&mut tip_passes, blade_axes != BladeAxes::Lean);
            let tip_summary = tip_summary_of(&tip, &tip_passes);
            blade.merge(tip_passes);
            keep_needed(&mut root, blade_axes != BladeAxes::Lean);
            // Copied with the blade's loops, after them: they end at the root.
            blade.merge(root);
            let mut splitter_tips = Vec::new();
            for splitter in &mut splitters {
                let may_reverse = blade_axes != BladeAxes::Lean;
                keep_needed(&mut splitter.loops, may_reverse);
                // Copied with the splitter's loops, after them, as the blade's.
                keep_needed(&mut splitter.tip_passes, may_reverse);
                splitter_tips.push(tip_summary_of(&splitter.tip, &splitter.tip_passes));
                splitter
                    .loops
                    .merge(std::mem::take(&mut splitter.tip_passes));
                keep_needed(&mut splitter.root, may_reverse);
                splitter.loops.merge(std::mem::take(&mut splitter.root));
            }
            keep_needed(&mut hub, hub_axes != HubAxes::Walls);
            for (passes, tip) in summary.splitter_passes.iter_mut().zip(splitter_tips) {
                passes.tip = tip;
            }
            // Where the passes as planned leave more than the target between them.
            if impeller_options.rest && corner_band.is_none() {
                let in_first_passage =
                    |t: usize| angle_past_first_blade(part, impeller, &passage, t) < passage.pitch;
                let target_of = |t: usize| match impeller.regions[t] {
                    Region::Blade(b) if b as usize == passage.first_blade => Some(1),
                    Region::Splitter(p) => splitter_pieces
                        .iter()
                        .position(|&s| s == p as usize)
                        .map(|k| 2 + k),
                    _ if passage.flow[t] && in_first_passage(t) => Some(0),
                    _ => None,
                };
                let may_reverse = blade_axes != BladeAxes::Lean;
                let mut targets = vec![
                    RestTarget {
                        ctx: &hub_ctx,
                        finishing: &mut hub,
                        may_reverse: hub_axes != HubAxes::Walls,
                    },
                    RestTarget {
                        ctx: &blade_ctx,
                        finishing: &mut blade,
                        may_reverse,
                    },
                ];
                for splitter in &mut splitters {
                    targets.push(RestTarget {
                        ctx: &splitter.ctx,
                        finishing: &mut splitter.loops,
                        may_reverse,
                    });
                }
                let flutes_above_ball = ctx.tool.flutes_above_ball().map_or(0.0, |(l, _)| l);
                let others: Vec<(&Finishing, f64)> =
                    swarf.iter().map(|s| (s, flutes_above_ball)).collect();
                let scope = RestScope {
                    target_of: &target_of,
                    link_cost: &link_cost,
                    views: &passage_views(&passage),
                    others: &others,
                    reach: PASSAGE_REACH,
                    sample_spacing: PASSAGE_SAMPLE_SPACING,
                    // Along their length, the passage's places at the ends of its passes
                    // (on the blower) left 0.47 mm² over the target for the planner's
                    // measure where along the passes left 0.07.
                    run_thin_places_along: false,
                    rounds: PASSAGE_ROUNDS,
                    skip: None,
                };
                summary.rest = Some(rest_passes(part, &mut targets, &scope, options));
            }
            summary.first_passage_ms = round_ms(t);

            let t = Instant::now();
            let mut copies = Vec::new();
            for k in 1..impeller.order {
                let rotation = passage.frame.turn(k as f64 * passage.pitch);
                let centre = passage.frame.centre;
                let (hub_copy, hub_stats) =
                    path::turned_copy(&hub, &rotation, &centre, &hub_ctx, options);
                let (blade_copy, blade_stats) =
                    path::turned_copy(&blade, &rotation, &centre, &blade_ctx, options);
                summary.copies.merge(&hub_stats);
                summary.copies.merge(&blade_stats);
                let mut copy = CopiedPassage {
                    hub: hub_copy,
                    blade: blade_copy,
                    swarf: None,
                    splitters: Vec::new(),
                };
                if let Some(swarf) = &swarf {
                    // Copied without its leads (a copy brings a pose in the air down onto
                    // the part), which the copy's runs get anew.
                    let runs = Finishing {
                        segments: swarf.segments.iter().map(without_leads).collect(),
                        ..Finishing::default()
                    };
                    let (mut runs_copy, stats) =
                        path::turned_copy(&runs, &rotation, &centre, &swarf_ctx, options);
                    summary.copies.merge(&stats);
                    for segment in &mut runs_copy.segments {
                        match leads(segment) {
                            Some(led) => *segment = led,
                            None => {
                                if let Some(s) = swarf_summary.as_mut() {
                                    s.copied_runs_without_leads += 1;
                                }
                            }
                        }
                    }
                    copy.swarf = Some(runs_copy);
                }
                for splitter in &splitters {
                    let (loops, stats) = path::turned_copy(
                        &splitter.loops,
                        &rotation,
                        &centre,
                        &splitter.ctx,
                        options,
                    );
                    summary.copies.merge(&stats);
                    copy.splitters.push(loops);
                }
                copies.push(copy);
            }
            // The part is symmetric only within its symmetry tolerance, and each copy's balls
            // were brought back onto it: what the first passage's passes left within the
            // target, a copy's may not (on the blower, 0.5 mm² at 0.018 mm by a blade's top in
            // 7 of its 9 passages). Every passage is measured among the passes as copied, and
            // mended where it needs it.
            if impeller_options.rest && corner_band.is_none() && !copies.is_empty() {
                let order = impeller.order;
                let pitch = passage.pitch;
                // Pitches from the piece `from` to the piece `to`, when `to` stands there
                // (within a quarter pitch).
                let turns_between = |from: usize, to: usize| -> Option<usize> {
                    let turn = (impeller.pieces[to].angle_deg - impeller.pieces[from].angle_deg)
                        .to_radians()
                        .rem_euclid(std::f64::consts::TAU);
                    let k = (turn / pitch).round();
                    ((turn - k * pitch).abs() < 0.25 * pitch).then_some(k as usize % order)
                };
                let slots = 2 + splitter_pieces.len();
                let target_of = |t: usize| match impeller.regions[t] {
                    Region::Blade(b) => {
                        turns_between(passage.first_blade, b as usize).map(|k| k * slots + 1)
                    }
                    Region::Splitter(p) => {
                        splitter_pieces.iter().enumerate().find_map(|(j, &s)| {
                            turns_between(s, p as usize).map(|k| k * slots + 2 + j)
                        })
                    }
                    _ if passage.flow[t] => {
                        let k =
                            (angle_past_first_blade(part, impeller, &passage, t) / pitch) as usize;
                        Some(k.min(order - 1) * slots)
                    }
                    _ => None,
                };
                let splitter_ctxs: Vec<FinishingContext> = splitters
                    .iter()
                    .map(|s| FinishingContext { ..s.ctx })
                    .collect();
                let may_reverse = blade_axes != BladeAxes::Lean;
                let hub_reverses = hub_axes != HubAxes::Walls;
                let flutes_above_ball = ctx.tool.flutes_above_ball().map_or(0.0, |(l, _)| l);
                let mut targets = vec![
                    RestTarget {
                        ctx: &hub_ctx,
                        finishing: &mut hub,
                        may_reverse: hub_reverses,
                    },
                    RestTarget {
                        ctx: &blade_ctx,
                        finishing: &mut blade,
                        may_reverse,
                    },
                ];
                for (splitter, ctx) in splitters.iter_mut().zip(&splitter_ctxs) {
                    targets.push(RestTarget {
                        ctx,
                        finishing: &mut splitter.loops,
                        may_reverse,
                    });
                }
                let mut others: Vec<(&Finishing, f64)> =
                    swarf.iter().map(|s| (s, flutes_above_ball)).collect();
                for copy in &mut copies {
                    targets.push(RestTarget {
                        ctx: &hub_ctx,
                        finishing: &mut copy.hub,
                        may_reverse: hub_reverses,
                    });
                    targets.push(RestTarget {
                        ctx: &blade_ctx,
                        finishing: &mut copy.blade,
                        may_reverse,
                    });
                    for (loops, ctx) in copy.splitters.iter_mut().zip(&splitter_ctxs) {
                        targets.push(RestTarget {
                            ctx,
                            finishing: loops,
                            may_reverse,
                        });
                    }
                    if let Some(swarf) = &copy.swarf {
                        others.push((swarf, flutes_above_ball));
                    }
                }
                // Each passage k is the first turned by k pitches.
                let turns: Vec<_> = (0..order as i32)
                    .map(|k| passage_turn(&passage, k))
                    .collect();
                let left = LeftPlaces::new(
                    summary.rest.as_ref().map_or(&[], |r| r.left.as_slice()),
                    &turns,
                );
                let left_in_first = |p: &Point3| left.near(p);
                let scope = RestScope {
                    target_of: &target_of,
                    link_cost: &link_cost,
                    views: &[nalgebra::Isometry3::identity()],
                    others: &others,
                    reach: COPIES_REACH,
                    skip: Some(&left_in_first),
                    sample_spacing: COPIES_SAMPLE_SPACING,
                    run_thin_places_along: false,
                    rounds: COPIES_ROUNDS,
                };
                summary.copies_rest = Some(rest_passes(part, &mut targets, &scope, options));
            }
            summary.copies_ms = round_ms(t);
            summary.passages = impeller.order;
            summary.splitters = splitter_pieces.len();
            summary.splitter_loops = splitter_loops;
            finishing.merge(hub);
            if let Some(swarf) = swarf {
                finishing.merge(swarf);
            }
            finishing.merge(blade);
            for splitter in splitters {
                finishing.merge(splitter.loops);
            }
            for copy in copies {
                finishing.merge(copy.hub);
                finishing.merge(copy.blade);
                if let Some(swarf) = copy.swarf {
                    finishing.merge(swarf);
                }
                for loops in copy.splitters {
                    finishing.merge(loops);
                }
            }
            for (t, h) in handled.iter_mut().enumerate() {
                *h = passage.flow[t]
                    || match impeller.regions[t] {
                        crate::impeller::Region::Blade(_) => true,
                        crate::impeller::Region::Splitter(_) => !splitter_pieces.is_empty(),
                        _ => false,
                    };
            }
            summary.hub = Some(HubSummary {
                flow_triangles: passage.flow_triangles,
                flow_area_mm2: passage.flow_area_mm2,
                profile_fit_mm: passage.profile_fit_mm,
                stations: passage.stations.len(),
                flow_lines: lines.len(),
                partial_lines: lines.iter().filter(|l| l.runs != lines[0].runs).count(),
                axes: hub_axes,
                visibility: summary_visibility.take(),
            });
            summary.blade = Some(BladeSummary {
                levels: loops.levels,
                loops: loops.curves.len(),
                partial_loops: loops.partial.len(),
                level_step_mm: loops.level_step,
                height_mm: loops.top,
                axes: blade_axes,
                root_pass: blade_root_pass,
                no_root_pass,
                tip: tip_summary,
                visibility: blade_visibility,
                lean_deg: impeller_options.blade_lean_deg,
                swarf: swarf_summary,
                not_swarfed,
            });

            // The bore and the rim: loops round each wall with the tool along the axis,
            // leaning off the machine's pole away from the wall it cuts.
            if corner_band.is_none() {
                for hub_wall in [HubWall::Bore, HubWall::Rim] {
                    let loops = wall_loops(
                        part,
                        impeller,
                        &passage.frame,
                        hub_wall,
                        radius,
                        options.scallop_height,
                    );
                    if loops.curves.is_empty() {
                        continue;
                    }
                    let frame = &passage.frame;
                    let wall_field = |_: &Point3, normal: &Vector3, _: &Vector3| {
                        let off_wall = (normal - frame.axis * normal.dot(&frame.axis))
                            .try_normalize(1e-9)
                            .unwrap_or(*normal);
                        away_from_pole(&frame.axis, &pole, &off_wall, MIN_TILT_FROM_POLE_DEG)
                    };
                    let wall_ctx = FinishingContext {
                        axis_field: Some(&wall_field),
                        ..*ctx
                    };
                    let mut passes = Finishing::default();
                    for result in path::curve_passes(&loops.curves, &wall_ctx, options, advance) {
                        passes.merge(result);
                    }
                    passes.segments =
                        path::nearest_order(std::mem::take(&mut passes.segments), true, &link_cost);
                    let wall_summary = Some(HubWallSummary {
                        wall_area_mm2: loops.area_mm2,
                        height_mm: loops.height_mm,
                        level_step_mm: loops.level_step,
                        crease_standoff_mm: loops.crease_standoff_mm,
                        loops: loops.curves.len(),
                        segments: passes.segments.len(),
                        unreachable_points: passes.unreachable.len(),
                    });
                    match hub_wall {
                        HubWall::Bore => summary.bore = wall_summary,
                        HubWall::Rim => summary.rim = wall_summary,
                    }
                    finishing.merge(passes);
                    for (h, on_wall) in handled.iter_mut().zip(&loops.wall) {
                        *h |= *on_wall;
                    }
                }
            }
        }
        Err(reason) => summary.not_planned = Some(reason),
    }
    if impeller_options.corner_band.is_some() {
        return (finishing, summary);
    }
    // The planes take every drive point whose nearest part triangle no strategy above took.
    let surface = ctx.part.surface();
    let region = |p: &Point3| {
        surface
            .closest(p, 1.0)
            .is_none_or(|c| !handled[c.triangle as usize])
    };
    let planes_ctx = FinishingContext {
        region: Some(&region),
        ..*ctx
    };
    let mut planes = path::finishing_passes(drive, &planes_ctx, options, advance);
    // Where the planes leave more than the target between them: a wall they cross at a
    // slant (the blower's rim, 0.3 mm tall, where the planes run nearly along it, passes
    // mm apart on it), the ends of their pieces.
    if impeller_options.rest {
        let target_of = |t: usize| (!handled[t]).then_some(0);
        // Every other pass as its ball alone: the swarf runs' flutes cut blade flanks, which
        // are not the planes'.
        let others = [(&finishing, 0.0)];
        let scope = RestScope {
            target_of: &target_of,
            link_cost: &link_cost,
            views: &[nalgebra::Isometry3::identity()],
            others: &others,
            reach: PLANES_REST_REACH,
            sample_spacing: PLANES_REST_SAMPLE_SPACING,
            run_thin_places_along: true,
            rounds: PLANES_ROUNDS,
            skip: None,
        };
        let mut targets = [RestTarget {
            ctx: &planes_ctx,
            finishing: &mut planes,
            may_reverse: true,
        }];
        summary.plane_rest = Some(rest_passes(part, &mut targets, &scope, options));
    }
    // What the planes take here is pieces round the rim, the bore and the blade tips, not
    // whole planes: in plane order, one piece's end is seldom near the next one's start (on
    // the blower on a fixture, 356 of 357 safe-plane retracts were links too long for a short
    // one). Nearest first, either way round (the planes zig-zag already), links them short.
    planes.segments = path::nearest_order(std::mem::take(&mut planes.segments), true, &link_cost);
    summary.plane_points_left_to_impeller = planes.points_left_to_others;
    finishing.merge(planes);
    (finishing, summary)
}

/// Deepest gap the rest passes over the planes' region measure, mm: on the blower's rim the
/// planes stand up to 7 mm apart where they run nearly along its wall, and a place seen
/// within this of the passes on either side is joined along the wall. (With a radius's
/// reach and 0.1 mm samples, each measure of the blower's region took 2.3 s, 0.24 s so.)
const PLANES_REST_REACH: f64 = 0.5;

/// Distance between the samples of the planes' region, mm: still two across the blower's
/// 0.3 mm rim wall, and the region is six times the passage's area there (4,824 mm²).
const PLANES_REST_SAMPLE_SPACING: f64 = 0.2;

/// Level of the direction set the passage's maps are over: 2,562 directions, ≈ 4° apart.
const VISIBILITY_LEVEL: usize = 4;

/// Stations between the points the passage's maps are computed at, and fractions of the
/// passage's width across: enough to catch every wall and the shroud's overhang, few enough
/// that the maps cost milliseconds.
const VISIBILITY_STATION_STRIDE: usize = 4;
const VISIBILITY_FRACTIONS: [f64; 7] = [0.05, 0.2, 0.35, 0.5, 0.65, 0.8, 0.95];

/// The passage's one axis from the visibility maps of points across it (seed 004 ch. 5 step
/// 4): the ball centres over the hub's surface of revolution, rays up to the tool's reach;
/// the direction with the most room among those all of them see, ties to the walls' mean.
/// Returned in the passage frame at `middle` (along the axis, radial, tangential), like
/// [`HubPassage::mean_wall_axis`] (the walls' mean where nothing is seen), with the figures
/// and the surface points the maps were computed at.
pub fn visible_passage_axis(
    passage: &HubPassage,
    walls: [f64; 3],
    middle: f64,
    rays: &RayScene,
    ball_radius: f64,
    reach: f64,
) -> ([f64; 3], PassageVisibility, Vec<SurfacePoint>) {
    let t = Instant::now();
    let radial = passage.frame.radial(middle);
    let tangent = passage.frame.axis.cross(&radial);
    let from_frame = |c: [f64; 3]| passage.frame.axis * c[0] + radial * c[1] + tangent * c[2];
    let to_frame = |v: &Vector3| [v.dot(&passage.frame.axis), v.dot(&radial), v.dot(&tangent)];
    let walls_axis = from_frame(walls);
    let points: Vec<SurfacePoint> = passage
        .stations
        .iter()
        .enumerate()
        .step_by(VISIBILITY_STATION_STRIDE)
        .flat_map(|(j, station)| {
            VISIBILITY_FRACTIONS.iter().filter_map(move |&f| {
                let angle = station.angle_at(f)?;
                let drive = passage.point(j, angle);
                Some(SurfacePoint {
                    point: drive.point,
                    normal: drive.normal,
                })
            })
        })
        .collect();
    let (direction, figures) = visible_axis(&points, &walls_axis, rays, ball_radius, reach, t);
    (to_frame(&direction), figures, points)
}

/// The one axis for `points` from their visibility maps (seed 004 ch. 5 step 4): of the
/// directions all of them see (or, where none is, the most), the one with the most room,
/// ties to `default` (in the part frame); `default` where no point sees anything. `started`:
/// when the caller began, for the figures' time.
fn visible_axis(
    points: &[SurfacePoint],
    default: &Vector3,
    rays: &RayScene,
    ball_radius: f64,
    reach: f64,
    started: Instant,
) -> (Vector3, PassageVisibility) {
    let set = DirectionSet::new(VISIBILITY_LEVEL);
    let options = VisibilityOptions {
        level: VISIBILITY_LEVEL,
        lift: Some(ball_radius),
        max_distance: reach,
        ..VisibilityOptions::default()
    };
    let (maps, rays_cast) = match visibility_hierarchical(rays, &set, points, &options) {
        Ok(maps) => (maps.maps, maps.rays_cast),
        Err(_) => (Vec::new(), 0),
    };
    let chosen = region_axis(&set, VISIBILITY_LEVEL, &maps, default);
    let spacing_deg = set.directions()[set.neighbours(VISIBILITY_LEVEL, 0)[0] as usize]
        .angle(&set.directions()[0])
        .to_degrees();
    let direction = chosen.map_or(*default, |c| c.direction);
    let figures = PassageVisibility {
        points: points.len(),
        seen_by: chosen.map_or(0, |c| c.seen_by),
        common_directions: chosen.map_or(0, |c| c.region_directions),
        room_deg: chosen.map_or(0.0, |c| c.room_steps as f64 * spacing_deg),
        from_walls_deg: direction.angle(default).to_degrees(),
        rays_cast,
        ms: round_ms(started),
    };
    (direction, figures)
}

/// Levels between the loops whose points the blade's maps are computed at, and the least
/// distance between two points of a loop, mm: a few hundred points round the blade.
const VISIBILITY_LEVEL_STRIDE: usize = 4;
const VISIBILITY_LOOP_SPACING_MM: f64 = 2.0;

/// The points round a blade its maps are computed at: on every fourth of its full loops, at
/// least 2 mm apart along each.
fn blade_visibility_points(loops: &crate::impeller::BladeLoops) -> Vec<SurfacePoint> {
    let mut points = Vec::new();
    for curve in loops.curves.iter().step_by(VISIBILITY_LEVEL_STRIDE) {
        let mut last: Option<Point3> = None;
        for p in &curve.points {
            if last.is_none_or(|q| (p.point - q).norm() >= VISIBILITY_LOOP_SPACING_MM) {
                points.push(SurfacePoint {
                    point: p.point,
                    normal: p.normal,
                });
                last = Some(p.point);
            }
        }
    }
    points
}

fn round_ms(since: Instant) -> f64 {
    (since.elapsed().as_secs_f64() * 1e4).round() / 10.0
}

/// The swarf runs round the blade `passage` starts at (of the part as recognised), every pose
/// checked exactly on the part: the ball and the flutes within the tolerance of it, shank,
/// holder and table by `ctx`'s tool (whose flutes may dip the tolerance), the machine's
/// limits; only runs `leads` finds a way into and out of.
fn swarf_blade(
    part: &Mesh,
    impeller: &Impeller,
    passage: &HubPassage,
    ctx: &FinishingContext,
    options: &FinishingOptions,
    pole: Vector3,
    leads: &dyn Fn(&CutSegment) -> Option<CutSegment>,
) -> Result<(Finishing, SwarfPlan, SwarfSummary), NotSwarf> {
    let r = ctx.tool.ball_radius;
    let piece = passage.first_blade;
    let Some((flutes_above_ball, _)) = ctx.tool.flutes_above_ball() else {
        return Err(NotSwarf::NoRoot);
    };
    // The ball sits on the hub with its equator on the flank; the hub's fitted meridian is off
    // the facets by up to its fit, so the root is lifted by that and half the tolerance.
    let root_height = r + passage.profile_fit_mm + 0.5 * options.tolerance;
    let root =
        blade_loop_at(part, impeller, passage, piece, root_height).ok_or(NotSwarf::NoRoot)?;
    let on_blade = |t: u32| {
        matches!(impeller.regions[t as usize], Region::Blade(k) | Region::Splitter(k)
            if k as usize == piece)
    };
    let rising = |p: &Point3| passage.above_hub(p).1;
    let accept = |ruling: &Ruling| -> Result<(), String> {
        let centre = ruling.centre;
        ctx.part
            .check_ball(&centre, r, options.tolerance)
            .map_err(|c| format!("{c:?}"))?;
        let top = centre + ruling.axis * flutes_above_ball;
        if ctx
            .part
            .surface()
            .segment_within(&centre, &top, r - options.tolerance)
        {
            return Err("the flutes gouge".into());
        }
        if !(ctx.reachable)(&ruling.axis) {
            return Err("beyond the machine's limits".into());
        }
        ctx.part
            .check_bodies(ctx.tool, &swarf_pose(ruling, r))
            .map_err(|c| format!("{c:?}"))
    };
    // The ball placed as the loops place it, pushed out of every face nearer than its radius
    // (a facetted flank's neighbouring facets lean a few degrees off the root point's).
    let place = |p: &crate::mesh::DrivePoint| path::place_ball(ctx.part.surface(), p, r);
    let mut plan = swarf_runs(
        ctx.part.surface(),
        &on_blade,
        &rising,
        &place,
        &accept,
        &root,
        &SwarfOptions {
            ball_radius: r,
            flutes_above_ball,
            tolerance: options.tolerance,
            max_step: options.max_step,
            max_axis_turn_deg: options.max_axis_turn_deg,
            snap_to: Some(pole),
        },
    )?;
    let mut finishing = Finishing {
        drive_points: plan.root_points,
        ..Finishing::default()
    };
    let mut kept = Vec::new();
    for run in std::mem::take(&mut plan.runs) {
        let n = run.rulings.len();
        let mut poses: Vec<ToolPose> = run.rulings.iter().map(|g| swarf_pose(g, r)).collect();
        let mut directions: Vec<Vector3> = (0..n)
            .map(|i| {
                let (before, after) = if run.closed {
                    (&run.rulings[(i + n - 1) % n], &run.rulings[(i + 1) % n])
                } else {
                    (
                        &run.rulings[i.saturating_sub(1)],
                        &run.rulings[(i + 1).min(n - 1)],
                    )
                };
                (after.centre - before.centre)
                    .try_normalize(1e-12)
                    .unwrap_or_else(Vector3::zeros)
            })
            .collect();
        if run.closed {
            poses.push(poses[0]);
            directions.push(directions[0]);
        }
        let segment = CutSegment {
            poses,
            pass_directions: directions,
            leads: false,
        };
        // A run the tool cannot get into or out of would be trimmed away by the link, and
        // the loops would have been dropped along it: refused here, the loops finish it.
        match leads(&segment) {
            Some(led) => {
                finishing.segments.push(led);
                kept.push(run);
            }
            None => plan.refused.push(NotSwarf::Refused {
                at: run.rulings[0].contact.point.into(),
                why: "no way in or out of the run clear to the safe plane".into(),
            }),
        }
    }
    plan.runs = kept;
    if plan.runs.is_empty() {
        return Err(plan.refused.first().cloned().unwrap_or(NotSwarf::NoRoot));
    }
    let mut by_reason = std::collections::BTreeMap::new();
    for why in &plan.refused {
        let name = serde_json::to_value(why)
            .ok()
            .and_then(|v| v.get("reason").and_then(|r| r.as_str().map(String::from)))
            .unwrap_or_default();
        *by_reason.entry(name).or_insert(0) += 1;
    }
    let summary = SwarfSummary {
        runs: plan.runs.len(),
        rulings: plan.rulings().count(),
        rulings_stepping_back: plan.stepping_back,
        root_points: plan.root_points,
        refused: by_reason,
        deviation_mm: plan.deviation(),
        flank_length_mm: plan.rulings().map(|g| g.flank_length).fold(0.0, f64::max),
        root_height_mm: root_height,
        copied_runs_without_leads: 0,
    };
    Ok((finishing, plan, summary))
}

/// Ways into and out of a swarf run: directions off the run's end, by their angle up from
/// square off the flank toward the tool axis and their angle back or on along the run,
/// degrees, tried with the most room first; and how far the ball's centre goes, in radii.
const SWARF_LEAD_UP_DEG: [f64; 4] = [0.0, 30.0, 60.0, 80.0];
const SWARF_LEAD_ALONG_DEG: [f64; 3] = [-45.0, 0.0, 45.0];
const SWARF_LEAD_LENGTHS: [f64; 3] = [0.5, 1.0, 2.0];

/// `segment` (a swarf run) with a way in and out. Its tool stands along the flank, so
/// straight up its axis the ball would slide along the flank within the tolerance: a touch to
/// the check the link makes before leaving a segment, which trimmed the runs away pose by pose
/// (on the blower 97 of 356 rulings). At each end the tool first moves off the flank to a pose
/// `ctx`'s tool can leave to the safe plane (`link`'s check) with its ball and bodies clear:
/// the directions off the flank (square, up the axis, back or on along the run) are tried in
/// the order of the room the ball has half a radius along them (square off was not always
/// best: a hub rising across the passage), each at growing distances. `None` where no such
/// pose is found at one end.
fn swarf_leads(
    segment: &CutSegment,
    ctx: &FinishingContext,
    tolerance: f64,
    link: &LinkOptions,
) -> Option<CutSegment> {
    let r = ctx.tool.ball_radius;
    let n = segment.poses.len();
    if n < 2 {
        return None;
    }
    let surface = ctx.part.surface();
    let centre = |pose: &ToolPose| pose.tip + pose.axis.into_inner() * r;
    let room = |p: &Point3| {
        surface
            .signed_distance(p)
            .map_or(f64::NEG_INFINITY, |(d, _)| d)
    };
    let lead = |pose: &ToolPose, along: Vector3| -> Option<ToolPose> {
        let axis = pose.axis.into_inner();
        let at = centre(pose);
        let along = (along - axis * axis.dot(&along)).try_normalize(1e-9)?;
        let across = axis.cross(&along);
        // Off the flank: the side with more room.
        let out = if room(&(at + across * r)) >= room(&(at - across * r)) {
            across
        } else {
            -across
        };
        let mut directions: Vec<(f64, Vector3)> = Vec::new();
        for up in SWARF_LEAD_UP_DEG {
            for on in SWARF_LEAD_ALONG_DEG {
                let (up_sin, up_cos) = up.to_radians().sin_cos();
                let (on_sin, on_cos) = on.to_radians().sin_cos();
                let d = (out * on_cos + along * on_sin) * up_cos + axis * up_sin;
                directions.push((room(&(at + d * (0.5 * r))), d));
            }
        }
        // Most room first; ties in the order listed.
        directions.sort_by(|a, b| b.0.total_cmp(&a.0));
        directions.iter().find_map(|(_, d)| {
            SWARF_LEAD_LENGTHS.iter().find_map(|&length| {
                let from = at + d * (length * r);
                let led = ToolPose {
                    tip: from - axis * r,
                    axis: pose.axis,
                };
                let clear = ctx.part.check_ball(&from, r, tolerance).is_ok()
                    && !surface.segment_within(&from, &at, r - tolerance)
                    && ctx.part.check_bodies(ctx.tool, &led).is_ok()
                    && path::can_leave(ctx.part, ctx.tool, &led, link);
                clear.then_some(led)
            })
        })
    };
    let (first, last) = (&segment.poses[0], &segment.poses[n - 1]);
    let entry = lead(first, centre(&segment.poses[1]) - centre(first))?;
    let exit = lead(last, centre(last) - centre(&segment.poses[n - 2]))?;
    let mut poses = Vec::with_capacity(n + 2);
    let mut directions = Vec::with_capacity(n + 2);
    poses.push(entry);
    directions.push(segment.pass_directions[0]);
    poses.extend_from_slice(&segment.poses);
    directions.extend_from_slice(&segment.pass_directions);
    poses.push(exit);
    directions.push(segment.pass_directions[n - 1]);
    Some(CutSegment {
        poses,
        pass_directions: directions,
        leads: true,
    })
}

/// A swarf run without the leads [`swarf_leads`] gave it.
fn without_leads(segment: &CutSegment) -> CutSegment {
    let n = segment.poses.len();
    CutSegment {
        poses: segment.poses[1..n - 1].to_vec(),
        pass_directions: segment.pass_directions[1..n - 1].to_vec(),
        leads: false,
    }
}

/// The tool standing along `ruling`, ball of radius `r`.
fn swarf_pose(ruling: &Ruling, r: f64) -> ToolPose {
    ToolPose {
        tip: ruling.centre - ruling.axis * r,
        axis: Direction::new_normalize(ruling.axis),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collide::PartCollider;
    use crate::mesh::fixtures::{box_between, joined};
    use crate::mesh::{DrivePoint, SectionCurve};
    use crate::orient::{AxisChooser, AxisOptions};

    /// Distance from `p` to the box `[lo, hi]` (closed form, outside it).
    fn box_distance(p: &Point3, lo: [f64; 3], hi: [f64; 3]) -> f64 {
        let gap = |k: usize| (lo[k] - p[k]).max(p[k] - hi[k]).max(0.0);
        Vector3::new(gap(0), gap(1), gap(2)).norm()
    }

    /// A swarf run along a wall standing on a plate, the tool upright with its flutes half
    /// the tolerance into the wall (as swarf allows) and its ball that far above the plate:
    /// straight up from its ends the tool cannot leave, which had linking trim the run away.
    /// Each end gets a lead off the wall from which it can, its ball clear of both boxes (in
    /// closed form) and the run itself untouched between the leads.
    #[test]
    fn a_swarf_run_gets_a_way_in_and_out_off_the_flank() {
        let (plate, wall) = (
            ([-30.0, -30.0, -5.0], [30.0, 30.0, 0.0]),
            ([-10.0, -1.0, 0.0], [10.0, 1.0, 8.0]),
        );
        let part = joined([plate, wall].map(|(lo, hi)| box_between(lo.into(), hi.into())));
        let collider = PartCollider::new(&part).unwrap();
        let rays = RayScene::new(&part);
        let tool = crate::collide::tool_bodies::tests::prepared();
        let chooser = AxisChooser::new(AxisOptions::default());
        let anywhere = |_: &Vector3| true;
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
        let tolerance = 0.01;
        let link = LinkOptions {
            pivot: Point3::origin(),
            safe_distance: 80.0,
            clearance: 2.0,
            cut_feed: 1000.0,
            approach_feed: 500.0,
            retract_feed: 2000.0,
            rapid_feed: 10000.0,
            rapid_margin: 0.5,
            max_short_link: 20.0,
            chord_tolerance: tolerance,
        };
        let r = tool.ball_radius;
        let axis = Direction::new_normalize(Vector3::z());
        let y = wall.1[1] + r - 0.5 * tolerance;
        let poses: Vec<ToolPose> = (-8..=8)
            .map(|x| ToolPose {
                tip: Point3::new(x as f64, y, 0.5 * tolerance),
                axis,
            })
            .collect();
        let n = poses.len();
        let run = CutSegment {
            poses: poses.clone(),
            pass_directions: vec![Vector3::x(); n],
            leads: false,
        };
        assert!(!path::can_leave(&collider, &tool, &poses[0], &link));
        assert!(!path::can_leave(&collider, &tool, &poses[n - 1], &link));

        let led = swarf_leads(&run, &ctx, tolerance, &link).expect("a way in and out");
        assert_eq!(led.poses.len(), n + 2);
        assert_eq!(led.poses[1..=n], poses[..]);
        assert_eq!(led.pass_directions.len(), n + 2);
        for (lead, end) in [(led.poses[0], poses[0]), (led.poses[n + 1], poses[n - 1])] {
            assert!(path::can_leave(&collider, &tool, &lead, &link), "{lead:?}");
            let centre = lead.tip + lead.axis.into_inner() * r;
            for (lo, hi) in [plate, wall] {
                assert!(box_distance(&centre, lo, hi) >= r, "{centre:?}");
            }
            // Off the wall, not into it, and no farther than the longest lead.
            let from = end.tip + end.axis.into_inner() * r;
            assert!(centre.y > from.y, "{centre:?}");
            assert!((centre - from).norm() <= 2.0 * r + 1e-9, "{centre:?}");
        }

        // Under a roof there is no way out: the run is not led (the job refuses it, and the
        // loops finish there).
        let roof = ([-30.0, -30.0, 20.0], [30.0, 30.0, 22.0]);
        let roofed = joined([plate, wall, roof].map(|(lo, hi)| box_between(lo.into(), hi.into())));
        let collider = PartCollider::new(&roofed).unwrap();
        let rays = RayScene::new(&roofed);
        let ctx = FinishingContext {
            part: &collider,
            rays: &rays,
            ..ctx
        };
        assert_eq!(swarf_leads(&run, &ctx, tolerance, &link), None);
    }

    /// Points on the floor of a slot 10 mm wide and 10 deep (its ends open): every point sees
    /// the directions within the slot's opening across it, so the one with the most room is
    /// straight up, whatever the default leans toward; a default that every point sees is
    /// kept where it has as much room. The blade's points: every fourth loop, 2 mm apart.
    #[test]
    fn the_visible_axis_of_a_slot_floor_is_straight_up() {
        let part = joined(
            [
                ([-40.0, -20.0, -5.0], [40.0, 20.0, 0.0]),
                ([-40.0, -20.0, 0.0], [40.0, -5.0, 10.0]),
                ([-40.0, 5.0, 0.0], [40.0, 20.0, 10.0]),
            ]
            .map(|(lo, hi)| box_between(lo.into(), hi.into())),
        );
        let rays = RayScene::new(&part);
        let points: Vec<SurfacePoint> = (-10..=10)
            .map(|x| SurfacePoint {
                point: Point3::new(x as f64, 0.0, 0.0),
                normal: Vector3::z(),
            })
            .collect();
        let leaning = Vector3::new(0.0, 0.4, 1.0).normalize();
        let (axis, figures) = visible_axis(&points, &leaning, &rays, 1.0, 60.0, Instant::now());
        assert_eq!(figures.seen_by, points.len(), "{figures:?}");
        // Within the direction set's spacing (about 4°) of up, across the slot: its opening
        // from a ball centre 1 mm up is ±29° across.
        assert!(axis.y.abs() < 0.08 && axis.z > 0.99, "{axis:?} {figures:?}");
        assert!(figures.room_deg > 20.0, "{figures:?}");
        assert!((figures.from_walls_deg - axis.angle(&leaning).to_degrees()).abs() < 1e-9);

        let loops = crate::impeller::BladeLoops {
            curves: (0..9)
                .map(|level| SectionCurve {
                    points: (0..=40)
                        .map(|k| DrivePoint {
                            point: Point3::new(0.5 * k as f64, 0.0, level as f64),
                            normal: Vector3::y(),
                        })
                        .collect(),
                    closed: false,
                })
                .collect(),
            partial: Vec::new(),
            levels: 9,
            level_step: 1.0,
            top: 9.0,
        };
        let chosen = blade_visibility_points(&loops);
        // Levels 0, 4 and 8; x = 0, 2, …, 20 on each.
        assert_eq!(chosen.len(), 3 * 11);
        assert!(
            chosen
                .iter()
                .all(|p| p.point.z % 4.0 == 0.0 && p.point.x % 2.0 == 0.0)
        );
    }
}
