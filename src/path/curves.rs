//! Finishing passes along drive curves a strategy hands in (the impeller's flow lines and
//! blade loops) rather than plane sections, and copies of planned passes turned about a
//! symmetry axis — each copied pose checked on the part and mended where it does not hold.
//!
//! A symmetric part is symmetric only to its tolerance: the hub's facets differ from passage
//! to passage, and an STL's vertices are rounded. So a copy is never taken on trust: each
//! turned ball centre is pushed out of the part if the turned surface comes closer than the
//! radius (the same placement as the original's), each turned axis goes through the same exact
//! test the chooser's picks do (rays, shank and holder, table, machine limits) and is chosen
//! anew where it fails, and each move between two copied poses is checked like a refined
//! chord (ball within the chord tolerance, axis turn within its bound); where a pose cannot be
//! mended or a move fails, the pass is split there.

use nalgebra::Rotation3;
use rayon::prelude::*;
use serde::Serialize;

use super::{
    CutSegment, Finishing, FinishingContext, FinishingOptions, Unreachable, drive_curve,
    place_ball_from,
};
use crate::geom::{Direction, Point3, ToolPose, angle_between};
use crate::mesh::{DrivePoint, SectionCurve};
use crate::orient::axis_is_valid;

/// Plans finishing passes along `curves` (each simplified and resampled as a plane section
/// is); one result per curve, in order. Curves run in parallel; each result depends only on
/// its curve, so the output is the same for any number of threads.
pub fn curve_passes(
    curves: &[SectionCurve],
    ctx: &FinishingContext,
    options: &FinishingOptions,
    progress: &(dyn Fn() + Sync),
) -> Vec<Finishing> {
    curves
        .par_iter()
        .map(|curve| {
            let points = curve
                .simplified(
                    ctx.tool.ball_radius + ctx.lift,
                    0.25 * options.tolerance,
                    options.max_step,
                )
                .resampled(options.max_step);
            let mut result = Finishing::default();
            drive_curve(&points, ctx, options, &mut result);
            progress();
            result
        })
        .collect()
}

/// What checking a turned copy found.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct TurnedCopy {
    /// Poses copied.
    pub poses: usize,
    /// Poses whose ball the turned part came nearer or farther than the radius: pushed out or
    /// brought down to touch.
    pub centres_moved: usize,
    /// Poses whose turned axis failed its test: given a new one.
    pub axes_chosen_anew: usize,
    /// Poses that could not be mended (left out, the pass split there).
    pub poses_dropped: usize,
    /// Passes split because a move between two copied poses failed its check.
    pub splits: usize,
}

impl TurnedCopy {
    pub fn merge(&mut self, other: &TurnedCopy) {
        self.poses += other.poses;
        self.centres_moved += other.centres_moved;
        self.axes_chosen_anew += other.axes_chosen_anew;
        self.poses_dropped += other.poses_dropped;
        self.splits += other.splits;
    }
}

/// `source`'s passes turned by `rotation` about `centre`, each pose checked on the part and
/// mended (see the module docs). The unreachable points are turned with them: they are the
/// places the source could not reach, reported for the copy, not tried again.
pub fn turned_copy(
    source: &Finishing,
    rotation: &Rotation3<f64>,
    centre: &Point3,
    ctx: &FinishingContext,
    options: &FinishingOptions,
) -> (Finishing, TurnedCopy) {
    let r = ctx.tool.ball_radius;
    let held = r + ctx.allowance;
    let turn_point = |p: &Point3| centre + rotation * (p - centre);
    let pieces: Vec<(Vec<CutSegment>, TurnedCopy)> = source
        .segments
        .par_iter()
        .map(|segment| {
            let mut stats = TurnedCopy::default();
            let mut out = Vec::new();
            let mut run = CutSegment {
                poses: Vec::new(),
                pass_directions: Vec::new(),
                leads: false,
            };
            let flush = |run: &mut CutSegment, out: &mut Vec<CutSegment>| {
                let taken = std::mem::replace(
                    run,
                    CutSegment {
                        poses: Vec::new(),
                        pass_directions: Vec::new(),
                        leads: false,
                    },
                );
                if taken.poses.len() >= 2 {
                    out.push(taken);
                }
            };
            // The turned centre of the source pose the run's last pose was copied from.
            let mut last_source: Option<Point3> = None;
            for (pose, direction) in segment.poses.iter().zip(&segment.pass_directions) {
                stats.poses += 1;
                let axis = rotation * pose.axis.into_inner();
                let feed = rotation * direction;
                let turned_centre = turn_point(&(pose.tip + pose.axis.into_inner() * r));
                let Some(ball) = place_ball_from(
                    ctx.part.surface(),
                    &DrivePoint {
                        point: turned_centre,
                        normal: axis,
                    },
                    0.0,
                    held,
                ) else {
                    stats.poses_dropped += 1;
                    flush(&mut run, &mut out);
                    continue;
                };
                // Where the turned surface lies lower than the original (its facets differ),
                // the ball would float: brought down to touch, and pushed out again if that
                // brings another face nearer than its radius.
                let ball = match ctx.part.surface().signed_distance(&ball) {
                    Some((d, closest)) if d > held + 1e-7 => {
                        let down = closest.point + (ball - closest.point) * (held / d);
                        place_ball_from(
                            ctx.part.surface(),
                            &DrivePoint {
                                point: down,
                                normal: axis,
                            },
                            0.0,
                            held,
                        )
                        .unwrap_or(ball)
                    }
                    _ => ball,
                };
                if (ball - turned_centre).norm() > 0.0 {
                    stats.centres_moved += 1;
                }
                let axis =
                    if axis_is_valid(ctx.part, ctx.rays, ctx.tool, &ball, &axis, ctx.reachable)
                        .is_ok()
                    {
                        Some(Direction::new_normalize(axis))
                    } else {
                        stats.axes_chosen_anew += 1;
                        let normal = ctx
                            .part
                            .surface()
                            .closest(&ball, held + 1.0)
                            .and_then(|c| (ball - c.point).try_normalize(1e-12))
                            .unwrap_or(axis);
                        let previous = run.poses.last().map(|p| p.axis.into_inner());
                        let drive = DrivePoint {
                            point: ball - normal * held,
                            normal,
                        };
                        ctx.choose_axis(&ball, &drive, &feed, previous.as_ref())
                            .ok()
                    };
                let Some(axis) = axis else {
                    stats.poses_dropped += 1;
                    flush(&mut run, &mut out);
                    continue;
                };
                let copied = ToolPose {
                    tip: ball - axis.into_inner() * r,
                    axis,
                };
                if let (Some(last), Some(source)) = (run.poses.last(), last_source) {
                    let centre_of = |p: &ToolPose| p.tip + p.axis.into_inner() * r;
                    let last_centre = centre_of(last);
                    let chord_ok = !ctx.part.surface().segment_within(
                        &last_centre,
                        &ball,
                        held - options.tolerance,
                    );
                    let turn_ok =
                        angle_between(&last.axis, &axis).to_degrees() <= options.max_axis_turn_deg;
                    // The copy steps the way its source stepped (not by the pass direction,
                    // which is zero where a pass rolls the ball round an edge), and never
                    // turns its travel back.
                    let step = ball - last_centre;
                    let forward = step.dot(&(turned_centre - source)) > 0.0
                        && run.poses.len().checked_sub(2).is_none_or(|before| {
                            step.dot(&(last_centre - centre_of(&run.poses[before]))) >= 0.0
                        });
                    if !(chord_ok && turn_ok && forward) {
                        stats.splits += 1;
                        flush(&mut run, &mut out);
                    }
                }
                run.poses.push(copied);
                last_source = Some(turned_centre);
                run.pass_directions.push(feed);
            }
            flush(&mut run, &mut out);
            (out, stats)
        })
        .collect();
    let mut copy = Finishing {
        unreachable: source
            .unreachable
            .iter()
            .map(|(p, why)| (turn_point(p), *why))
            .collect::<Vec<(Point3, Unreachable)>>(),
        drive_points: source.drive_points,
        ..Default::default()
    };
    let mut stats = TurnedCopy::default();
    for (segments, s) in pieces {
        copy.segments.extend(segments);
        stats.merge(&s);
    }
    (copy, stats)
}

/// Puts the run of `chain` into the order `segments` run in where it adds least to the links
/// between them, each costing `link_cost` from the last pose of one segment to the first of
/// the next (before the first, between two, or after the last; the run reversed too when
/// `may_reverse`): passes added to a planned order without reordering the rest.
pub fn insert_cheapest(
    segments: &mut Vec<CutSegment>,
    mut chain: Vec<CutSegment>,
    may_reverse: bool,
    link_cost: &dyn Fn(&ToolPose, &ToolPose) -> f64,
) {
    let start = |s: &CutSegment| s.poses.first().copied();
    let end = |s: &CutSegment| s.poses.last().copied();
    let (Some(first), Some(last)) = (chain.first().and_then(start), chain.last().and_then(end))
    else {
        return;
    };
    let gap = |a: Option<ToolPose>, b: Option<ToolPose>| match (a, b) {
        (Some(a), Some(b)) => link_cost(&a, &b),
        _ => 0.0,
    };
    // (added travel, position, reversed); ties to the earliest, forward first.
    let mut best: Option<(f64, usize, bool)> = None;
    for at in 0..=segments.len() {
        let before = at.checked_sub(1).and_then(|k| end(&segments[k]));
        let after = segments.get(at).and_then(start);
        let kept = gap(before, after);
        for reverse in [false, true] {
            if reverse && !may_reverse {
                continue;
            }
            let (from, to) = if reverse {
                (last, first)
            } else {
                (first, last)
            };
            let added = gap(before, Some(from)) + gap(Some(to), after) - kept;
            if best.is_none_or(|b| added < b.0) {
                best = Some((added, at, reverse));
            }
        }
    }
    let Some((_, at, reverse)) = best else { return };
    if reverse {
        chain.reverse();
        for segment in &mut chain {
            segment.poses.reverse();
            segment.pass_directions.reverse();
            for d in &mut segment.pass_directions {
                *d = -*d;
            }
        }
    }
    segments.splice(at..at, chain);
}

/// `segments` reordered so that each starts near where the one before ended (greedy nearest
/// neighbour from the first by `link_cost`, ties to the lower index), each run backwards
/// when `may_reverse` and its end is the nearer. Fewer and shorter links; the passes
/// themselves are unchanged (a reversed one runs the same poses the other way, its pass
/// directions turned round). The cost is the caller's: the travel, and on a five-axis
/// machine the rotaries' turn (near a rotary's pole a small change of the tool axis is a
/// large turn of the other, which a link's length does not show).
pub fn nearest_order(
    segments: Vec<CutSegment>,
    may_reverse: bool,
    link_cost: &dyn Fn(&ToolPose, &ToolPose) -> f64,
) -> Vec<CutSegment> {
    let n = segments.len();
    let mut slots: Vec<Option<CutSegment>> = segments.into_iter().map(Some).collect();
    let mut out: Vec<CutSegment> = Vec::with_capacity(n);
    let mut here: Option<ToolPose> = None;
    for _ in 0..n {
        let mut best: Option<(f64, usize, bool)> = None;
        for (i, slot) in slots.iter().enumerate() {
            let Some(s) = slot else { continue };
            let (Some(first), Some(last)) = (s.poses.first(), s.poses.last()) else {
                continue;
            };
            let Some(at) = &here else {
                best = Some((0.0, i, false));
                break;
            };
            let forward = link_cost(at, first);
            if best.is_none_or(|b| forward < b.0) {
                best = Some((forward, i, false));
            }
            let backward = link_cost(at, last);
            if may_reverse && backward < best.map_or(f64::INFINITY, |b| b.0) {
                best = Some((backward, i, true));
            }
        }
        let Some((_, i, reverse)) = best else { break };
        let Some(mut s) = slots[i].take() else { break };
        if reverse {
            s.poses.reverse();
            s.pass_directions.reverse();
            for d in &mut s.pass_directions {
                *d = -*d;
            }
        }
        here = s.poses.last().copied();
        out.push(s);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Vector3;

    fn segment(from: Point3, to: Point3) -> CutSegment {
        let axis = Direction::new_normalize(Vector3::z());
        CutSegment {
            poses: vec![ToolPose { tip: from, axis }, ToolPose { tip: to, axis }],
            pass_directions: vec![(to - from).normalize(); 2],
            leads: false,
        }
    }

    fn travel(segments: &[CutSegment]) -> f64 {
        segments
            .windows(2)
            .map(|w| (w[1].poses[0].tip - w[0].poses[w[0].poses.len() - 1].tip).norm())
            .sum()
    }

    /// A run of two passes, against every position and both ways round: the least travel,
    /// and the others' order kept.
    #[test]
    fn cheapest_insertion_is_the_least_travel_of_every_place_and_way() {
        // A fixed scatter of passes (a linear congruential sequence, not `rand`).
        let mut state = 12345u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 33) as f64 / (1u64 << 31) as f64 * 20.0
        };
        for _ in 0..20 {
            let mut point = || Point3::new(next(), next(), 0.0);
            let planned: Vec<CutSegment> = (0..6).map(|_| segment(point(), point())).collect();
            let new = vec![segment(point(), point()), segment(point(), point())];
            for may_reverse in [false, true] {
                let mut best = f64::INFINITY;
                for at in 0..=planned.len() {
                    for reverse in [false, true] {
                        if reverse && !may_reverse {
                            continue;
                        }
                        let mut s = new.clone();
                        if reverse {
                            s.reverse();
                            for x in &mut s {
                                x.poses.reverse();
                            }
                        }
                        let mut order = planned.clone();
                        order.splice(at..at, s);
                        best = best.min(travel(&order));
                    }
                }
                let mut order = planned.clone();
                insert_cheapest(&mut order, new.clone(), may_reverse, &|a, b| {
                    (b.tip - a.tip).norm()
                });
                assert!((travel(&order) - best).abs() < 1e-9);
                let added = |s: &CutSegment| {
                    new.iter()
                        .any(|n| n.poses.iter().any(|p| p.tip == s.poses[0].tip))
                };
                let others: Vec<&CutSegment> = order.iter().filter(|s| !added(s)).collect();
                assert_eq!(others.len(), planned.len());
                assert!(others.iter().zip(&planned).all(|(a, b)| a.poses == b.poses));
            }
        }
    }

    /// Nearest first: by travel from an upright pass the near tilted one comes next; with a
    /// degree of turn costing a millimetre of link, the upright one a little farther does,
    /// and the tilted ones after, together. Either way every pass is there once.
    #[test]
    fn nearest_order_weighs_the_turn_of_the_axis() {
        let tilted = Direction::new_normalize(Vector3::new(1.0, 0.0, 1.0));
        let tilt = |mut s: CutSegment| {
            for p in &mut s.poses {
                p.axis = tilted;
            }
            s
        };
        let passes = vec![
            segment(Point3::new(0.0, 0.0, 0.0), Point3::new(1.0, 0.0, 0.0)),
            tilt(segment(
                Point3::new(1.5, 0.0, 0.0),
                Point3::new(2.5, 0.0, 0.0),
            )),
            segment(Point3::new(3.5, 0.0, 0.0), Point3::new(4.5, 0.0, 0.0)),
            tilt(segment(
                Point3::new(5.0, 0.0, 0.0),
                Point3::new(6.0, 0.0, 0.0),
            )),
        ];
        let starts =
            |order: &[CutSegment]| -> Vec<f64> { order.iter().map(|s| s.poses[0].tip.x).collect() };
        let travel_only = |a: &ToolPose, b: &ToolPose| (b.tip - a.tip).norm();
        let order = nearest_order(passes.clone(), false, &travel_only);
        assert_eq!(starts(&order), [0.0, 1.5, 3.5, 5.0]);
        let with_turn = |a: &ToolPose, b: &ToolPose| {
            (b.tip - a.tip).norm() + angle_between(&a.axis, &b.axis).to_degrees()
        };
        let order = nearest_order(passes, false, &with_turn);
        assert_eq!(starts(&order), [0.0, 3.5, 5.0, 1.5]);
    }

    /// With a link's cost counting the turn of the axis, a pass tilted like the segments at
    /// the far end goes there rather than between the near ones, which stand upright.
    #[test]
    fn cheapest_insertion_weighs_the_turn_of_the_axis() {
        let tilted = Direction::new_normalize(Vector3::new(1.0, 0.0, 1.0));
        let tilt = |mut s: CutSegment| {
            for p in &mut s.poses {
                p.axis = tilted;
            }
            s
        };
        let planned = vec![
            segment(Point3::new(0.0, 0.0, 0.0), Point3::new(1.0, 0.0, 0.0)),
            segment(Point3::new(2.0, 0.0, 0.0), Point3::new(3.0, 0.0, 0.0)),
            tilt(segment(
                Point3::new(10.0, 0.0, 0.0),
                Point3::new(11.0, 0.0, 0.0),
            )),
            tilt(segment(
                Point3::new(12.0, 0.0, 0.0),
                Point3::new(13.0, 0.0, 0.0),
            )),
        ];
        let new = tilt(segment(
            Point3::new(1.5, 1.0, 0.0),
            Point3::new(1.6, 1.0, 0.0),
        ));
        let travel_only = |a: &ToolPose, b: &ToolPose| (b.tip - a.tip).norm();
        let mut order = planned.clone();
        insert_cheapest(&mut order, vec![new.clone()], false, &travel_only);
        assert_eq!(
            order[1].poses, new.poses,
            "by travel, between the near ones"
        );
        // A degree of turn as long as 0.5 mm of link: 45° each way is 45 mm.
        let with_turn = |a: &ToolPose, b: &ToolPose| {
            (b.tip - a.tip).norm() + 0.5 * angle_between(&a.axis, &b.axis).to_degrees()
        };
        let mut order = planned.clone();
        insert_cheapest(&mut order, vec![new.clone()], false, &with_turn);
        assert_eq!(
            order[2].poses, new.poses,
            "with the turn, beside the tilted ones"
        );
    }
}
