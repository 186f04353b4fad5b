//! Rest passes over an impeller's first passage (issue 21 item 4: scallop within the target
//! everywhere the ball reaches). The flow lines, the loops and the passes along a blade's tip
//! and root are spaced by models of the surface (the hub's surface of revolution, height above
//! it, a land between two crests); where the part is not the model — a tip rounding over, a
//! land that narrows at the leading edge, the blade's top falling to the rim — neighbouring
//! balls leave more than the target between them. After the first passage is planned, its
//! surface is measured against the balls as placed ([`crate::path::gaps`], the neighbouring
//! passages' balls by the symmetry), and a pass is planned along the ridge of each place left
//! over the target, with the axes of the strategy whose surface it is on, put into that
//! strategy's order where it adds the least to the links (travel and the rotaries' turn) and
//! copied to the other passages with it. Further rounds measure again with them. Where the
//! strategy's axis search finds nothing along a rest pass, a finer one searches again.
//!
//! The same runs over what the parallel planes finish round the impeller strategies (the rim,
//! the bore's top, the tips' ends), against every pass, with the planes' axes: a wall the
//! planes run nearly along gets its passes millimetres apart.

use serde::Serialize;

use crate::geom::{Point3, ToolPose};
use crate::impeller::{HubPassage, Impeller};
use crate::mesh::{Mesh, SectionCurve};
use crate::orient::AxisChooser;
use crate::path::{
    self, Finishing, FinishingContext, FinishingOptions, GapSamples, RestOptions, SweptTool,
    clusters, rest_curve, ridges,
};

/// Rounds of measuring and mending over the first passage: a round mends what the one
/// before left, less each time (the sample's fourth and fifth took its planner's measure from
/// 0.025 to 0.019 mm at no cost a report shows).
pub(super) const PASSAGE_ROUNDS: usize = 5;

/// A round whose measure finds more than this share of the area the round before found over
/// the target stalls the rounds.
const STALLED: f64 = 0.5;

/// Rounds over the copies and the planes' region.
pub(super) const COPIES_ROUNDS: usize = 3;
pub(super) const PLANES_ROUNDS: usize = 3;

/// Gaps up to this deep are the copies' rest passes' to close, mm: a copy's gaps differ from
/// the first passage's by what the asymmetry moves its balls, hundredths of a millimetre
/// (blower: symmetry p99 0.032 mm, its copies' places 0.044 mm at most). Deeper ones are the
/// first passage's too, which its rest passes mended or could not.
pub(super) const COPIES_REACH: f64 = 0.05;

/// A copy's sample this near (mm) a place the first passage's rest passes left, turned by
/// the symmetry, is left to that place: the copies' rest passes would plan again what the
/// first passage's could not mend (in the bundled job, by the roots the corner finish
/// takes: 520 mm² over all passages, which 245 passes planned again in vain).
pub(super) const LEFT_IN_FIRST_PASSAGE: f64 = 1.0;

/// The places the first passage's rest passes left (`left`), turned into every passage
/// (`views`): whether a point stands within [`LEFT_IN_FIRST_PASSAGE`] of one.
pub(super) struct LeftPlaces {
    cells: std::collections::HashMap<[i64; 3], Vec<Point3>>,
}

impl LeftPlaces {
    pub fn new(left: &[Point3], views: &[nalgebra::Isometry3<f64>]) -> Self {
        let mut cells: std::collections::HashMap<[i64; 3], Vec<Point3>> = Default::default();
        for view in views {
            for p in left {
                let turned = view.transform_point(p);
                cells.entry(Self::key(&turned)).or_default().push(turned);
            }
        }
        Self { cells }
    }

    fn key(p: &Point3) -> [i64; 3] {
        [0, 1, 2].map(|k| (p[k] / LEFT_IN_FIRST_PASSAGE).floor() as i64)
    }

    pub fn near(&self, p: &Point3) -> bool {
        let [x, y, z] = Self::key(p);
        (x - 1..=x + 1).any(|i| {
            (y - 1..=y + 1).any(|j| {
                (z - 1..=z + 1).any(|k| {
                    self.cells.get(&[i, j, k]).is_some_and(|points| {
                        points
                            .iter()
                            .any(|r| (r - p).norm() <= LEFT_IN_FIRST_PASSAGE)
                    })
                })
            })
        })
    }
}

/// Distance between the samples of the copies, mm: coarser than the first passage's (the
/// copies' places are what the asymmetry opens, specks a few tenths of a mm² across), at a
/// fraction of the cost over every passage.
pub(super) const COPIES_SAMPLE_SPACING: f64 = 0.2;

/// Distance between the samples of the passage, mm: several per stepover.
pub(super) const PASSAGE_SAMPLE_SPACING: f64 = 0.1;

/// Places on one ridge this far apart are run as one pass, mm: cutting the stretch between
/// (at 2000 mm/min, 0.1 s) costs less than linking to a pass of its own.
const JOIN_ALONG: f64 = 4.0;

/// Where a strategy's axis search finds nothing along a rest pass, the cones of the second,
/// finer search, degrees, and its exact tests: a place the passes leave is often one their
/// axes could not reach, and the claim is the target wherever any axis reaches (the sample's
/// leading edge by the nose, 0.19 mm deep: reached through a window that 5° cones miss, after
/// 200–600 exact tests at 2°).
const FINE_AXIS_STEP_DEG: f64 = 2.0;
const FINE_AXIS_EXACT_TESTS: usize = 1000;

/// Neighbouring passages measured on either side: a swept blade wraps more than a pitch.
const NEIGHBOURS: i32 = 2;

/// Gaps up to this deep are the passage's passes' to close, mm; a sample farther from every
/// ball is out of their reach (the tool cannot get there, or another strategy finishes it).
pub(super) const PASSAGE_REACH: f64 = 0.2;

/// The samples of passage 0 among the passes of the passages up to [`NEIGHBOURS`] on either
/// side: a sample of passage 0 among the passes of passage k is the sample turned back by k
/// pitches among passage 0's.
pub(super) fn passage_views(passage: &HubPassage) -> Vec<nalgebra::Isometry3<f64>> {
    (-NEIGHBOURS..=NEIGHBOURS)
        .map(|k| passage_turn(passage, k))
        .collect()
}

/// The turn by `k` pitches about the impeller's axis: passage 0 to passage k.
pub(super) fn passage_turn(passage: &HubPassage, k: i32) -> nalgebra::Isometry3<f64> {
    let turn = nalgebra::UnitQuaternion::from_rotation_matrix(
        &passage.frame.turn(k as f64 * passage.pitch),
    );
    nalgebra::Isometry3::rotation_wrt_point(turn, passage.frame.centre)
}

/// How far round the axis from the first blade's angle triangle `t`'s centroid stands,
/// radians in [0, 2π): passage k spans k to k + 1 pitches.
pub(super) fn angle_past_first_blade(
    part: &Mesh,
    impeller: &Impeller,
    passage: &HubPassage,
    t: usize,
) -> f64 {
    let blade_angle = impeller.pieces[passage.first_blade].angle_deg.to_radians();
    let [a, b, c] = part.corners(t);
    let centroid = Point3::from((a.coords + b.coords + c.coords) / 3.0);
    let (_, angle, _) = passage.frame.cylindrical(&centroid);
    (angle - blade_angle).rem_euclid(std::f64::consts::TAU)
}

/// What the rest passes over a region (the first passage, or the planes') found and planned.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct RestSummary {
    /// Area measured (the passage's blade, splitters and hub; the planes' region), mm².
    pub measured_mm2: f64,
    pub rounds: Vec<RestRound>,
    /// What the planner's measure still finds over the target after the last round.
    pub left_over_target_mm2: f64,
    pub left_max_mm: f64,
    /// Where: the samples still over the target.
    #[serde(skip)]
    pub left: Vec<Point3>,
}

/// One round of measuring and mending.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct RestRound {
    /// Area over the target where the ball fits, mm², and the deepest gap, mm.
    pub over_target_mm2: f64,
    pub max_mm: f64,
    /// Places (clusters of samples over the target), and the passes planned along them.
    pub places: usize,
    pub passes: usize,
    /// Length of the passes' ball centres' paths, mm.
    pub length_mm: f64,
}

/// A strategy the rest passes may join: its context (the axes it plans with) and its passes.
pub(super) struct RestTarget<'a> {
    pub ctx: &'a FinishingContext<'a>,
    pub finishing: &'a mut Finishing,
    pub may_reverse: bool,
}

/// Where rest passes look and what else cuts there.
pub(super) struct RestScope<'a> {
    /// Which target's surface a triangle of the part is (`None`: not measured).
    pub target_of: &'a (dyn Fn(usize) -> Option<usize> + Sync),
    /// What linking from the one pose to the other costs, in millimetres of link: where a
    /// rest pass goes into its strategy's order.
    pub link_cost: &'a dyn Fn(&ToolPose, &ToolPose) -> f64,
    /// Where a sample stands among the passes: the identity, and for passes that will be
    /// copied, the sample turned back by each copy's turn.
    pub views: &'a [nalgebra::Isometry3<f64>],
    /// Other passes that cut there, each with how far above the ball its flutes cut (0: the
    /// ball alone).
    pub others: &'a [(&'a Finishing, f64)],
    /// Deepest gap measured, mm (farther from every ball: not reached).
    pub reach: f64,
    /// Distance between the samples, mm.
    pub sample_spacing: f64,
    /// Run a place no wider than a stepover along its own length when it runs across its
    /// passes (see [`crate::path::RestOptions::thin`]).
    pub run_thin_places_along: bool,
    /// Rounds of measuring and mending.
    pub rounds: usize,
    /// Samples left out of the measure (places another rest run measured already).
    pub skip: Option<&'a (dyn Fn(&Point3) -> bool + Sync)>,
}

/// Plans rest passes into `targets` where the passes leave more than the target over the
/// surface `scope` measures.
pub(super) fn rest_passes(
    part: &Mesh,
    targets: &mut [RestTarget],
    scope: &RestScope,
    options: &FinishingOptions,
) -> RestSummary {
    let Some(ctx) = targets.first().map(|t| t.ctx) else {
        return RestSummary::default();
    };
    let radius = ctx.tool.ball_radius;
    let stepover = path::stepover_for_scallop(radius, options.scallop_height);
    let rest_options = RestOptions {
        ball_radius: radius,
        scallop_height: options.scallop_height,
        sample_spacing: scope.sample_spacing,
        reach: scope.reach,
        overlap: 0.5 * stepover,
        step: 0.25,
        thin: scope.run_thin_places_along.then_some(stepover),
    };
    let target_of = scope.target_of;
    let surface = ctx.part.surface();
    let mut swept = SweptTool::new(radius, scope.reach);
    for target in targets.iter() {
        for segment in &target.finishing.segments {
            swept.insert(segment, 0.0, options.scallop_height);
        }
    }
    for (other, flutes_above_ball) in scope.others {
        for segment in &other.segments {
            swept.insert(segment, *flutes_above_ball, options.scallop_height);
        }
    }
    let sampled: Vec<bool> = (0..part.triangles.len())
        .map(|t| target_of(t).is_some())
        .collect();
    let mut summary = RestSummary {
        measured_mm2: (0..part.triangles.len())
            .filter(|&t| sampled[t])
            .map(|t| {
                let [a, b, c] = part.corners(t);
                0.5 * (b - a).cross(&(c - a)).norm()
            })
            .sum(),
        ..RestSummary::default()
    };
    let mut samples = GapSamples::new(part, &sampled, &rest_options);
    if let Some(skip) = scope.skip {
        samples.retain(|p| !skip(p));
    }
    for round in 0..=scope.rounds {
        let found = samples.measure(surface, &swept, scope.views, &rest_options);
        let over_target_mm2: f64 = found.iter().map(|g| g.area).sum();
        let max_mm = found.iter().map(|g| g.height).fold(0.0, f64::max);
        // Rounds that do not halve what is over the target are mostly planning passes along
        // places they cannot reach (in the bundled job, drive points the stock blocks: after
        // the first, four rounds planned 380 mm of passes for 72 -> 59 mm²); the round after
        // one is not planned. (The sample's and the blower's rounds fall to a quarter or
        // less each, to the last.)
        let stuck = summary
            .rounds
            .last()
            .is_some_and(|last| over_target_mm2 > STALLED * last.over_target_mm2);
        if round == scope.rounds || found.is_empty() || stuck {
            summary.left_over_target_mm2 = over_target_mm2;
            summary.left_max_mm = max_mm;
            summary.left = found.iter().map(|g| g.point).collect();
            break;
        }
        let places = ridges(
            &found,
            &clusters(&found, 1.5 * scope.sample_spacing),
            JOIN_ALONG,
            0.5 * stepover,
            rest_options.thin,
        );
        // Each place's curve, to the target most of its samples are on.
        let mut curves: Vec<Vec<SectionCurve>> = vec![Vec::new(); targets.len()];
        for members in &places {
            let mut votes = vec![0usize; targets.len()];
            for &i in members {
                if let Some(k) = target_of(found[i].triangle as usize) {
                    votes[k] += 1;
                }
            }
            let Some(k) = (0..votes.len()).max_by_key(|&k| (votes[k], std::cmp::Reverse(k))) else {
                continue;
            };
            if let Some(curve) = rest_curve(&found, members, part, surface, &rest_options) {
                curves[k].push(curve);
            }
        }
        let mut this_round = RestRound {
            over_target_mm2,
            max_mm,
            places: places.len(),
            ..RestRound::default()
        };
        for (target, curves) in targets.iter_mut().zip(&curves) {
            // With the strategy's own axes: round a blade one axis, so the links to the
            // passes beside stay still in the rotary axes (the axes of the nearest pass
            // beside instead, tried: the hub's or a swarf run's near a root, 5 minutes more
            // on the blower).
            let chooser = AxisChooser::new(target.ctx.chooser.options().clone())
                .with_fine_fallback(FINE_AXIS_STEP_DEG, FINE_AXIS_EXACT_TESTS);
            let ctx = FinishingContext {
                chooser: &chooser,
                ..*target.ctx
            };
            let mut planned = Vec::new();
            for result in path::curve_passes(curves, &ctx, options, &|| {}) {
                planned.extend(result.segments);
            }
            for segment in &planned {
                this_round.passes += 1;
                this_round.length_mm += centre_path_length(segment, radius);
                swept.insert(segment, 0.0, options.scallop_height);
            }
            // Each into the strategy's order where it adds the least travel.
            for segment in planned {
                path::insert_cheapest(
                    &mut target.finishing.segments,
                    vec![segment],
                    target.may_reverse,
                    scope.link_cost,
                );
            }
        }
        summary.rounds.push(this_round);
    }
    summary
}

/// Length of the path `segment`'s ball centres run, mm.
fn centre_path_length(segment: &path::CutSegment, radius: f64) -> f64 {
    let centre = |k: usize| -> Point3 {
        let pose = &segment.poses[k];
        pose.tip + pose.axis.into_inner() * radius
    };
    (1..segment.poses.len())
        .map(|k| (centre(k) - centre(k - 1)).norm())
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A place left in the first passage stands for its turned copies: a point by the copy a
    /// third of a turn on is near it, one by the place turned a sixth of a turn (no copy
    /// there) is not, nor one farther than the distance from the copy.
    #[test]
    fn a_place_left_in_the_first_passage_is_near_its_copies_only() {
        let turn = |angle: f64| nalgebra::Isometry3::rotation(nalgebra::Vector3::z() * angle);
        let thirds: Vec<_> = (0..3)
            .map(|k| turn(k as f64 * std::f64::consts::TAU / 3.0))
            .collect();
        let place = Point3::new(20.0, 0.0, 5.0);
        let left = LeftPlaces::new(&[place], &thirds);
        let copy = thirds[1].transform_point(&place);
        assert!(left.near(&place));
        assert!(left.near(&(copy + nalgebra::Vector3::new(0.0, 0.0, 0.9))));
        assert!(!left.near(&(copy + nalgebra::Vector3::new(0.0, 0.0, 1.1))));
        let between = turn(std::f64::consts::TAU / 6.0).transform_point(&place);
        assert!(!left.near(&between));
    }
}
