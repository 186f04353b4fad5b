//! Linking cut segments into one toolpath: retract along the tool axis to a safe plane, move
//! there, plunge along the next axis.
//!
//! The safe plane is perpendicular to the tool axis at `safe_distance` from the machine's pivot
//! (where the rotary axes meet). For a machine whose tool points along machine +Z that is the
//! plane machine Z = `safe_distance`, whatever the rotary angles: with `safe_distance` larger
//! than the part's reach from the pivot, the tool is clear of the part there for every rotary
//! position, so the positioning moves between segments are safe however the controller
//! interpolates them. The moves along the axis (retract and plunge) are checked exactly: the
//! tool's bodies extended along the axis up to the safe plane must clear the part; segment ends
//! that fail are trimmed.
//!
//! Rapids keep `rapid_margin` between the ball and the part. Along the axis the ball leaves
//! the surface slowly where the axis is tilted far from the normal (a blade wall cut with a
//! steep lead), so the feed part of the retract and of the approach is lengthened beyond
//! `clearance` until the rest of the way to the safe plane keeps that margin.

use rayon::prelude::*;
use serde::Serialize;

use super::CutSegment;
use crate::collide::{PartCollider, PreparedTool};
use crate::geom::{Direction, Point3, angle_between, slerp};
use crate::geom::{Move, MoveKind, ToolPose, Toolpath};

/// Where and how fast to link.
#[derive(Clone, Debug, PartialEq)]
pub struct LinkOptions {
    /// The pivot of the rotary axes in the part frame.
    pub pivot: Point3,
    /// Distance of the safe plane from the pivot along the tool axis, mm.
    pub safe_distance: f64,
    /// Rapid down to this far above the entry point (along the axis), then feed in, mm.
    pub clearance: f64,
    pub cut_feed: f64,
    pub approach_feed: f64,
    pub retract_feed: f64,
    pub rapid_feed: f64,
    /// Least distance between the ball and the part along rapids, mm.
    pub rapid_margin: f64,
    /// Longest short link, mm between the ball centres: the next segment starting this near
    /// is reached by lifting a little along the axis, moving across at the retract feed and
    /// plunging, where all of that is checked clear, instead of by way of the safe plane.
    /// 0: every segment is left to the safe plane.
    pub max_short_link: f64,
    /// How much closer than its radius the ball may come to the part along a move, mm (the
    /// planner's chord tolerance): a next segment starting within the ball's radius is reached
    /// by cutting straight across where that move keeps it.
    pub chord_tolerance: f64,
}

/// How far up the axis a short link lifts, tried in order, in multiples of the ball radius:
/// low over a flank, high enough to pass over a blade's edge within an impeller's passage.
const SHORT_LINK_LIFTS: [f64; 4] = [0.5, 1.5, 5.0, 12.0];

/// How far up the axis a hop lifts, tried in order, in multiples of the ball radius: over the
/// ridge between neighbouring passes where straight across would cut into it.
const HOP_LIFTS: [f64; 3] = [0.05, 0.15, 0.3];

/// Farthest a hop reaches, in ball radii between the ball centres: the next pass beside this
/// one (further on, the move across would seldom keep the chord tolerance).
const HOP_REACH: f64 = 2.0;

/// Largest axis turn along a short link, degrees. The turn is checked at every degree along
/// the great circle, and the post makes the control follow that circle within its angle
/// tolerance (`post::linearise`); beyond a right angle the axis would swing the holder
/// through a half-space the link was never meant to visit. (At 30° on the sample impeller
/// 191 of 252 safe-plane retracts were for a turn of 33–57° between segments 0.1–2 mm apart,
/// where the chooser had turned the axis round an obstacle.)
const SHORT_LINK_MAX_TURN_DEG: f64 = 90.0;

/// What linking changed.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct LinkReport {
    pub segments: usize,
    /// Cut poses removed from segment ends because the tool could not retract or plunge there.
    pub trimmed_poses: usize,
    /// Segments left with fewer than two poses after trimming.
    pub dropped_segments: usize,
    /// Segments reached from the one before by cutting straight across, by a hop (up a
    /// fraction of the ball's radius, across and down, all at the cut feed), by a short
    /// lifted link, and by way of the safe plane.
    pub links_across: usize,
    pub hops: usize,
    pub short_links: usize,
    pub safe_plane_retracts: usize,
    /// Why the safe plane: the next segment started farther than the longest short link,
    /// its axis turned more than a short link may, or every short link's moves touched the
    /// part (ball within the rapid margin, or shank, holder or table).
    pub safe_plane_far: usize,
    pub safe_plane_turn: usize,
    pub safe_plane_blocked: usize,
}

/// Whether `tool` can leave `pose` straight up its axis to the safe plane, every body of it
/// clear of the part: what linking asks of a segment's end (the end poses that cannot are
/// trimmed off, see [`LinkReport::trimmed_poses`]), for a strategy to ask before it counts on
/// a segment being cut.
pub fn can_leave(
    part: &PartCollider,
    tool: &PreparedTool,
    pose: &ToolPose,
    options: &LinkOptions,
) -> bool {
    SafePlane {
        part,
        tool,
        options,
    }
    .can_leave(pose)
}

/// Links `segments` in order into one toolpath for `tool`.
pub fn link(
    segments: &[CutSegment],
    part: &PartCollider,
    tool: &PreparedTool,
    tool_id: u32,
    options: &LinkOptions,
) -> (Toolpath, LinkReport) {
    let mut path = Toolpath {
        tool_id,
        moves: Vec::new(),
    };
    let mut report = LinkReport::default();
    let safe = SafePlane {
        part,
        tool,
        options,
    };
    let along = SafePlane::along;
    let can_leave = |pose: &ToolPose| safe.can_leave(pose);
    // Trimming is the expensive part (long swept bodies); segments are independent.
    let kept: Vec<(usize, usize)> = segments
        .par_iter()
        .map(|segment| {
            let poses = &segment.poses;
            let start = poses.iter().position(&can_leave).unwrap_or(poses.len());
            let end = poses
                .iter()
                .rposition(&can_leave)
                .map_or(start, |i| (i + 1).max(start));
            (start, end)
        })
        .collect();
    // The segments kept, and for each the lift of the short link into the next one, if any.
    let ends: Vec<(ToolPose, ToolPose)> = segments
        .iter()
        .zip(&kept)
        .filter(|(_, (start, end))| end - start >= 2)
        .map(|(segment, &(start, end))| (segment.poses[start], segment.poses[end - 1]))
        .collect();
    let short: Vec<Result<Link, NoShortLink>> = (0..ends.len())
        .into_par_iter()
        .map(|i| match ends.get(i + 1) {
            Some(next) => short_link(part, tool, &ends[i].1, &next.0, options),
            None => Err(NoShortLink::Last),
        })
        .collect();
    let mut arriving: Option<Link> = None;
    let mut k = 0;
    for (segment, &(start, end)) in segments.iter().zip(&kept) {
        let poses = &segment.poses;
        report.trimmed_poses += poses.len() - (end - start);
        if end - start < 2 {
            report.dropped_segments += 1;
            continue;
        }
        report.segments += 1;
        let (entry, exit) = (poses[start], poses[end - 1]);
        let mv = |pose, kind, feed| Move { pose, kind, feed };
        // A lead off the part kept whole: the arrival ends in the air (an air move at its
        // feed), the move from it to the part is the approach, the last move the retract.
        let (lead_in, lead_out) = (
            segment.leads && start == 0,
            segment.leads && end == poses.len(),
        );
        let arrived = path.moves.len();
        match arriving.take() {
            Some(Link::Across) => {
                // Across at the cut feed, but an approach: the pass it enters starts here
                // (its direction may be the other way round, as in a zig-zag).
                report.links_across += 1;
                path.moves
                    .push(mv(entry, MoveKind::Approach, options.cut_feed));
            }
            Some(Link::Hop(lift)) => {
                // Back down at the cut feed: the ball comes to the part within the chord
                // tolerance of where it left it, as a pass's own moves do.
                report.hops += 1;
                path.moves
                    .push(mv(along(&entry, lift), MoveKind::Retract, options.cut_feed));
                path.moves
                    .push(mv(entry, MoveKind::Approach, options.cut_feed));
            }
            Some(Link::Lifted(lift)) => {
                report.short_links += 1;
                path.moves.push(mv(
                    along(&entry, lift),
                    MoveKind::Retract,
                    options.retract_feed,
                ));
                // Down the checked axis at the retract feed to the clearance above the entry
                // (a move in the air, like the one across), then in at the approach feed, as
                // from the safe plane.
                if lift > options.clearance {
                    path.moves.push(mv(
                        along(&entry, options.clearance),
                        MoveKind::Retract,
                        options.retract_feed,
                    ));
                }
                path.moves
                    .push(mv(entry, MoveKind::Approach, options.approach_feed));
            }
            None => {
                report.safe_plane_retracts += 1;
                path.moves.extend(safe.entry(&entry));
            }
        }
        if lead_in && let Some(last) = path.moves[arrived..].last_mut() {
            last.kind = MoveKind::Retract;
        }
        for (i, pose) in poses[start + 1..end].iter().enumerate() {
            let (kind, feed) = if lead_in && i == 0 {
                (MoveKind::Approach, options.approach_feed)
            } else if lead_out && start + 1 + i == end - 1 {
                (MoveKind::Retract, options.cut_feed)
            } else {
                (MoveKind::Cut, options.cut_feed)
            };
            path.moves.push(mv(*pose, kind, feed));
        }
        match short[k] {
            Ok(Link::Across) => arriving = Some(Link::Across),
            Ok(Link::Hop(lift)) => {
                path.moves
                    .push(mv(along(&exit, lift), MoveKind::Retract, options.cut_feed));
                arriving = Some(Link::Hop(lift));
            }
            Ok(Link::Lifted(lift)) => {
                path.moves.push(mv(
                    along(&exit, lift),
                    MoveKind::Retract,
                    options.retract_feed,
                ));
                arriving = Some(Link::Lifted(lift));
            }
            Err(why) => {
                match why {
                    NoShortLink::Far => report.safe_plane_far += 1,
                    NoShortLink::Turn => report.safe_plane_turn += 1,
                    NoShortLink::Blocked => report.safe_plane_blocked += 1,
                    NoShortLink::Last => {}
                }
                path.moves.extend(safe.exit(&exit))
            }
        }
        k += 1;
    }
    (path, report)
}

/// Leaving a cut pose along its axis for the safe plane, and coming back down to one: the
/// links between segments that are not short, and the unwinds a machine's limits need.
struct SafePlane<'a> {
    part: &'a PartCollider,
    tool: &'a PreparedTool,
    options: &'a LinkOptions,
}

impl SafePlane<'_> {
    fn along(pose: &ToolPose, distance: f64) -> ToolPose {
        ToolPose {
            tip: pose.tip + pose.axis.into_inner() * distance,
            axis: pose.axis,
        }
    }

    /// How far up its axis from `pose` the safe plane is.
    fn to_safe(&self, pose: &ToolPose) -> f64 {
        (self.options.safe_distance - (pose.tip - self.options.pivot).dot(&pose.axis)).max(0.0)
    }

    /// Whether the tool's bodies, swept along the axis from `pose` to the safe plane, clear
    /// the part.
    fn can_leave(&self, pose: &ToolPose) -> bool {
        let sweep = self.to_safe(pose);
        self.part.check_ball_sweep(self.tool, pose, sweep).is_ok()
            && self.part.check_bodies_swept(self.tool, pose, sweep).is_ok()
    }

    /// The fed part of the way up from `pose` (see [`feed_lift`]).
    fn feed_length(&self, pose: &ToolPose) -> f64 {
        feed_lift(
            self.part,
            pose,
            self.tool.ball_radius,
            self.to_safe(pose),
            self.options.rapid_margin,
        )
        .max(self.options.clearance)
        .min(self.to_safe(pose))
    }

    /// Up from `pose`: fed, then rapid to the safe plane.
    fn exit(&self, pose: &ToolPose) -> [Move; 2] {
        [
            Move {
                pose: Self::along(pose, self.feed_length(pose)),
                kind: MoveKind::Retract,
                feed: self.options.retract_feed,
            },
            Move {
                pose: Self::along(pose, self.to_safe(pose)),
                kind: MoveKind::Rapid,
                feed: self.options.rapid_feed,
            },
        ]
    }

    /// Down to `pose` from the safe plane: rapid, then fed.
    fn entry(&self, pose: &ToolPose) -> [Move; 3] {
        [
            Move {
                pose: Self::along(pose, self.to_safe(pose)),
                kind: MoveKind::Rapid,
                feed: self.options.rapid_feed,
            },
            Move {
                pose: Self::along(pose, self.feed_length(pose)),
                kind: MoveKind::Rapid,
                feed: self.options.rapid_feed,
            },
            Move {
                pose: *pose,
                kind: MoveKind::Approach,
                feed: self.options.approach_feed,
            },
        ]
    }
}

/// A link by way of the safe plane from the cut pose `exit` to the cut pose `entry`: up the
/// exit's axis to the safe plane (fed, then rapid), across on it, down the entry's axis (rapid,
/// then fed), the rotary axes free to turn in place on the safe plane; `None` when the tool's
/// bodies swept up either axis would touch the part. With `exit = entry`, an unwind: the tool
/// leaves and comes back to the same pose. The moves are those [`link`] makes between
/// segments.
pub fn relink(
    part: &PartCollider,
    tool: &PreparedTool,
    options: &LinkOptions,
    exit: &ToolPose,
    entry: &ToolPose,
) -> Option<Vec<Move>> {
    let safe = SafePlane {
        part,
        tool,
        options,
    };
    if !safe.can_leave(exit) || (entry != exit && !safe.can_leave(entry)) {
        return None;
    }
    let [retract, up] = safe.exit(exit);
    let [over, down, approach] = safe.entry(entry);
    let mut moves = vec![retract, up];
    if over.pose != up.pose {
        moves.push(over);
    }
    moves.extend([down, approach]);
    Some(moves)
}

/// Least axis turn (degrees) or tip travel (mm) of a rapid that [`safe_midpoint`] still
/// splits: below both, another stop would not give the rotaries any more room.
const SMALLEST_SPLIT: (f64, f64) = (0.01, 0.01);

/// A stop on the safe plane halfway along the rapid `from → to` between two poses on it: the
/// axis halfway round (slerp), the tip halfway along and then out along that axis to the safe
/// plane, where the tool is beyond the part's reach and the rotary axes may turn in place.
/// `None` when either end is not on the safe plane, the axes are opposite, or the rapid is too
/// short to split.
pub fn safe_midpoint(options: &LinkOptions, from: &Move, to: &Move) -> Option<Move> {
    let to_safe =
        |pose: &ToolPose| options.safe_distance - (pose.tip - options.pivot).dot(&pose.axis);
    let on_plane = |pose: &ToolPose| to_safe(pose) <= 1e-6 * options.safe_distance.max(1.0);
    let (a, b) = (&from.pose, &to.pose);
    let turn = angle_between(&a.axis, &b.axis).to_degrees();
    let travel = (b.tip - a.tip).norm();
    if !on_plane(a) || !on_plane(b) || (turn < SMALLEST_SPLIT.0 && travel < SMALLEST_SPLIT.1) {
        return None;
    }
    let axis = Direction::new_normalize(slerp(&a.axis, &b.axis, 0.5));
    if !axis.iter().all(|v| v.is_finite()) || turn > 179.999 {
        return None;
    }
    let tip = a.tip + (b.tip - a.tip) * 0.5;
    let halfway = ToolPose { tip, axis };
    let lift = to_safe(&halfway).max(0.0);
    Some(Move {
        pose: SafePlane::along(&halfway, lift),
        kind: MoveKind::Rapid,
        feed: to.feed,
    })
}

/// How a segment is reached from the one before.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Link {
    /// Straight across, cutting: the next segment starts within the ball's radius, the move
    /// keeps the ball within the chord tolerance and the other bodies clear while the axis
    /// turns (as far as a short link may).
    Across,
    /// Up this far along the axis, across and down, at the cut feed: where straight across
    /// would cut deeper than the chord tolerance, the ball keeps it this little way up.
    Hop(f64),
    /// Up this far along the axis, across, and down.
    Lifted(f64),
}

/// Why a segment is left by way of the safe plane.
#[derive(Clone, Copy, Debug, PartialEq)]
enum NoShortLink {
    /// The next segment starts farther than the longest short link.
    Far,
    /// The axis turns more than a short link may.
    Turn,
    /// Every lift's moves came too near the part.
    Blocked,
    /// No next segment.
    Last,
}

/// How `entry` is reached from `exit`, if by a short link: straight across; else by a hop or a
/// lift, up `lift` along the exit's axis, straight across to `lift` above the entry along its
/// axis (the axis turning evenly), down to the entry. Across and over a hop the ball comes no
/// closer to the part than the chord tolerance lets a cut; across a lift it keeps the rapid
/// margin; it does not touch the part along the lifts. Shank, holder and table are checked
/// along the lifts as swept bodies and across at poses no more than a fifth of the ball radius
/// and one degree apart.
fn short_link(
    part: &PartCollider,
    tool: &PreparedTool,
    exit: &ToolPose,
    entry: &ToolPose,
    options: &LinkOptions,
) -> Result<Link, NoShortLink> {
    let r = tool.ball_radius;
    let centre = |p: &ToolPose, lift: f64| p.tip + p.axis.into_inner() * (r + lift);
    let turn = angle_between(&exit.axis, &entry.axis).to_degrees();
    let distance = (centre(exit, 0.0) - centre(entry, 0.0)).norm();
    if distance > options.max_short_link {
        return Err(NoShortLink::Far);
    }
    if turn > SHORT_LINK_MAX_TURN_DEG {
        return Err(NoShortLink::Turn);
    }
    let bodies_clear = |a: &Point3, b: &Point3| {
        let steps = ((b - a).norm() / (0.2 * r)).max(turn).ceil().max(1.0) as usize;
        (0..=steps).all(|s| {
            let t = s as f64 / steps as f64;
            let axis = Direction::new_normalize(slerp(&exit.axis, &entry.axis, t));
            let c = a + (b - a) * t;
            part.check_bodies(
                tool,
                &ToolPose {
                    tip: c - axis.into_inner() * r,
                    axis,
                },
            )
            .is_ok()
        })
    };
    let (a, b) = (centre(exit, 0.0), centre(entry, 0.0));
    // The axis may turn as far as on a lifted link: the rotaries take the same time either
    // way, and the flutes, shank and holder are checked at every degree of it the same way.
    // (Limited to 5° once, most short links on the real blower were neighbouring segments
    // less than a millimetre apart whose axes differed by more, lifted and fed back in at
    // the approach feed.)
    if distance <= r
        && !part
            .surface()
            .segment_within(&a, &b, r - options.chord_tolerance)
        && bodies_clear(&a, &b)
    {
        return Ok(Link::Across);
    }
    let lift_clear = |lift: f64| {
        part.check_ball_sweep(tool, exit, lift).is_ok()
            && part.check_ball_sweep(tool, entry, lift).is_ok()
            && part.check_bodies_swept(tool, exit, lift).is_ok()
            && part.check_bodies_swept(tool, entry, lift).is_ok()
    };
    // Over the ridge between neighbouring passes the ball need not leave the part by more
    // than a little: held to the chord tolerance like a cut, at the cut feed, it saves a
    // lifted link's feeding back in at the approach feed (on the real blower's fixture most
    // lifted links were between passes a millimetre apart, each fed in 1–3 mm at 600 mm/min).
    if distance <= HOP_REACH * r
        && let Some(lift) = HOP_LIFTS.iter().map(|k| k * r).find(|&lift| {
            let (a, b) = (centre(exit, lift), centre(entry, lift));
            !part
                .surface()
                .segment_within(&a, &b, r - options.chord_tolerance)
                && lift_clear(lift)
                && bodies_clear(&a, &b)
        })
    {
        return Ok(Link::Hop(lift));
    }
    SHORT_LINK_LIFTS
        .iter()
        .map(|k| k * r)
        .find(|&lift| {
            let (a, b) = (centre(exit, lift), centre(entry, lift));
            lift_clear(lift)
                && !part
                    .surface()
                    .segment_within(&a, &b, r + options.rapid_margin)
                && bodies_clear(&a, &b)
        })
        .map(Link::Lifted)
        .ok_or(NoShortLink::Blocked)
}

/// How far up the axis from `pose` the ball must be fed before the rest of the way, up to
/// `to_safe`, keeps `margin` from the part. Sampled every `h` from the safe plane down: the
/// distance to the part changes by at most `h/2` between a sample and the nearer of its
/// neighbours (it is 1-Lipschitz), so samples at `r + 1.25·margin + h/2` or more keep the whole
/// stretch between them at `r + 1.25·margin` (the quarter is room for the back-simulation's own
/// error bound on rapids).
fn feed_lift(part: &PartCollider, pose: &ToolPose, r: f64, to_safe: f64, margin: f64) -> f64 {
    let h = (0.5 * margin).clamp(0.01, 1.0);
    let needed = r + 1.25 * margin + 0.5 * h;
    let samples = (to_safe / h).ceil().max(1.0) as usize;
    let axis = pose.axis.into_inner();
    let centre = |s: f64| pose.tip + axis * (r + s);
    for k in (0..=samples).rev() {
        let s = (k as f64 * h).min(to_safe);
        if part.surface().any_within(&centre(s), needed) {
            return ((k + 1) as f64 * h).min(to_safe);
        }
    }
    0.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collide::{Margins, PartCollider, PreparedTool};
    use crate::geom::{Direction, Vector3};

    fn pose(tip: [f64; 3], axis: [f64; 3]) -> ToolPose {
        ToolPose {
            tip: Point3::from(tip),
            axis: Direction::new_normalize(Vector3::from(axis)),
        }
    }

    /// The plate of these tests (100 × 100 × 20 mm from the origin) and the test tool.
    fn plate_and_tool() -> (PartCollider, PreparedTool) {
        let plate = crate::mesh::fixtures::cuboid(100.0, 100.0, 20.0);
        let part = PartCollider::new(&plate).expect("plate");
        (part, test_tool())
    }

    /// The collide module's test tool (ball radius 3) with these tests' margins.
    fn test_tool() -> PreparedTool {
        let margins = Margins {
            shank: 0.5,
            holder: 2.0,
        };
        PreparedTool::new(&crate::collide::tool_bodies::tests::tool(), &margins)
    }

    /// A pass through `poses` along x, without leads.
    fn segment(poses: Vec<ToolPose>) -> CutSegment {
        CutSegment {
            pass_directions: vec![Vector3::x(); poses.len()],
            poses,
            leads: false,
        }
    }

    /// Linking over the plate of these tests.
    fn plate_options() -> LinkOptions {
        LinkOptions {
            pivot: Point3::new(50.0, 50.0, 0.0),
            safe_distance: 200.0,
            clearance: 1.0,
            cut_feed: 1000.0,
            approach_feed: 300.0,
            retract_feed: 2000.0,
            rapid_feed: 10000.0,
            rapid_margin: 0.5,
            max_short_link: 20.0,
            chord_tolerance: 0.01,
        }
    }

    /// A run with leads: the tool comes down to the lead in the air (no approach there), feeds
    /// in to the part as the approach, cuts, and feeds out to the other lead as the retract
    /// at the cut feed; without leads the same poses are all cut.
    #[test]
    fn a_run_with_leads_approaches_from_one_and_retracts_to_the_other() {
        let (part, tool) = plate_and_tool();
        let up = [0.0, 0.0, 1.0];
        let poses = vec![
            pose([28.0, 50.0, 22.0], up),
            pose([30.0, 50.0, 20.0], up),
            pose([40.0, 50.0, 20.0], up),
            pose([50.0, 50.0, 20.0], up),
            pose([52.0, 50.0, 22.0], up),
        ];
        let options = plate_options();
        let kinds = |leads: bool| {
            let segment = CutSegment {
                pass_directions: vec![Vector3::x(); poses.len()],
                poses: poses.clone(),
                leads,
            };
            let (path, _) = link(&[segment], &part, &tool, 1, &options);
            poses
                .iter()
                .map(|p| {
                    let m = path
                        .moves
                        .iter()
                        .find(|m| m.pose == *p)
                        .expect("every pose");
                    (m.kind, m.feed)
                })
                .collect::<Vec<_>>()
        };
        let (cut, approach, retract) = (
            (MoveKind::Cut, 1000.0),
            (MoveKind::Approach, 300.0),
            (MoveKind::Retract, 1000.0),
        );
        assert_eq!(
            kinds(true),
            vec![(MoveKind::Retract, 300.0), approach, cut, cut, retract]
        );
        assert_eq!(kinds(false)[1..], [cut, cut, cut, cut]);
    }

    /// Two passes on a plate's top whose ends are a millimetre apart, the second with its axis
    /// turned 30°: the ball goes straight across at the cut feed, turning the axis, without
    /// lifting; between axes 100° apart, further than a short link may turn, the tool leaves
    /// by the safe plane.
    #[test]
    fn a_neighbouring_pass_with_a_turned_axis_is_reached_straight_across() {
        let (part, tool) = plate_and_tool();
        let r = 3.0;
        let up = [0.0, 0.0, 1.0];
        let first = segment(vec![
            pose([30.0, 50.0, 20.0], up),
            pose([40.0, 50.0, 20.0], up),
        ]);
        // The ball (centre r above the top) touching the plate under an axis turned `deg`
        // about y, a millimetre on in y.
        let turned = |x: f64, deg: f64| {
            let (s, c) = deg.to_radians().sin_cos();
            pose([x - r * s, 51.0, 23.0 - r * c], [s, 0.0, c])
        };
        let options = plate_options();
        let second = segment(vec![turned(40.0, 30.0), turned(30.0, 30.0)]);
        let (path, report) = link(&[first.clone(), second], &part, &tool, 1, &options);
        assert_eq!(
            (
                report.links_across,
                report.short_links,
                report.safe_plane_retracts
            ),
            (1, 0, 1),
            "{report:?}"
        );
        let across = path
            .moves
            .iter()
            .position(|m| m.pose == turned(40.0, 30.0))
            .expect("the second pass's start");
        assert_eq!(path.moves[across - 1].pose, first.poses[1]);
        assert_eq!(
            (path.moves[across].kind, path.moves[across].feed),
            (MoveKind::Approach, options.cut_feed)
        );
        let first = segment(vec![turned(30.0, -50.0), turned(40.0, -50.0)]);
        let second = segment(vec![turned(40.0, 50.0), turned(30.0, 50.0)]);
        let (_, report) = link(&[first, second], &part, &tool, 1, &options);
        assert_eq!(
            (report.links_across, report.safe_plane_turn),
            (0, 1),
            "{report:?}"
        );
    }

    /// Two passes along a meridian of a sphere (R 20), the ball centres 2.9 mm apart across
    /// the gap: straight across the chord would cut 0.046 mm into the sphere, more than the
    /// 0.01 tolerance, so the ball hops, up its axis a twentieth of its radius, across and
    /// down, all at the cut feed; along the move across it stays off the sphere (closed form)
    /// by the ball's radius less the tolerance.
    #[test]
    fn neighbouring_passes_over_a_convex_ridge_are_joined_by_a_hop() {
        let sphere = crate::mesh::fixtures::uv_sphere(20.0, 90, 180);
        let part = PartCollider::new(&sphere).expect("sphere");
        let tool = test_tool();
        let r = tool.ball_radius;
        let on_meridian = |polar: f64| {
            let u = [polar.sin(), 0.0, polar.cos()];
            pose(u.map(|v| v * 20.0), u)
        };
        let gap = 2.0 * (2.9 / (2.0 * (20.0 + r))).asin();
        let pass = |from: f64, to: f64| segment(vec![on_meridian(from), on_meridian(to)]);
        let options = LinkOptions {
            pivot: Point3::origin(),
            ..plate_options()
        };
        let (first, second) = (pass(0.2, 0.3), pass(0.3 + gap, 0.5));
        let (path, report) = link(&[first, second], &part, &tool, 1, &options);
        assert_eq!(
            (report.links_across, report.hops, report.short_links),
            (0, 1, 0),
            "{report:?}"
        );
        let exit = path
            .moves
            .iter()
            .position(|m| m.pose == on_meridian(0.3))
            .expect("the first pass's end");
        let lift = 0.05 * r;
        let up = |p: ToolPose| SafePlane::along(&p, lift);
        let hop: Vec<_> = path.moves[exit + 1..exit + 4]
            .iter()
            .map(|m| (m.pose, m.kind, m.feed))
            .collect();
        assert_eq!(
            hop,
            vec![
                (up(on_meridian(0.3)), MoveKind::Retract, options.cut_feed),
                (
                    up(on_meridian(0.3 + gap)),
                    MoveKind::Retract,
                    options.cut_feed
                ),
                (on_meridian(0.3 + gap), MoveKind::Approach, options.cut_feed),
            ]
        );
        let centre = |p: &ToolPose| p.tip + p.axis.into_inner() * r;
        let (a, b) = (centre(&hop[0].0), centre(&hop[1].0));
        for k in 0..=100 {
            let c = a + (b - a) * (k as f64 / 100.0);
            assert!(
                c.coords.norm() - 20.0 >= r - options.chord_tolerance,
                "{c:?}"
            );
        }
        // Straight across would have cut deeper than the tolerance.
        let middle = (centre(&on_meridian(0.3)) + centre(&on_meridian(0.3 + gap)).coords) * 0.5;
        assert!(middle.coords.norm() - 20.0 < r - 0.04);
    }

    /// Two passes on a plate's top, 7 mm apart (beyond a hop), the second with its axis turned
    /// 45°: linked by a short lift (not the safe plane), every move of the link keeps the ball
    /// the rapid margin off the plate except the approach's last clearance, and a lift above
    /// the clearance comes down at the retract feed before the approach feed takes over.
    #[test]
    fn a_turned_axis_a_few_millimetres_on_is_reached_by_a_short_link() {
        let (part, tool) = plate_and_tool();
        let (r, tilt) = (3.0, std::f64::consts::FRAC_1_SQRT_2);
        let first = segment(vec![
            pose([30.0, 50.0, 20.0], [0.0, 0.0, 1.0]),
            pose([40.0, 50.0, 20.0], [0.0, 0.0, 1.0]),
        ]);
        // The ball (centre 3 above the top) touching the plate under a tilted axis.
        let tilted = |x: f64| pose([x - r * tilt, 50.0, 23.0 - r * tilt], [tilt, 0.0, tilt]);
        let second = segment(vec![tilted(47.0), tilted(57.0)]);
        let options = plate_options();
        let (path, report) = link(&[first, second], &part, &tool, 1, &options);
        assert_eq!(
            (
                report.short_links,
                report.safe_plane_retracts,
                report.safe_plane_turn
            ),
            (1, 1, 0),
            "{report:?}"
        );
        // The link: the moves between the first pass's last cut and the second's first.
        let from = path
            .moves
            .iter()
            .position(|m| m.pose == pose([40.0, 50.0, 20.0], [0.0, 0.0, 1.0]))
            .expect("first pass's end");
        let to = path.moves[from..]
            .iter()
            .position(|m| m.kind == MoveKind::Approach && m.feed == options.approach_feed)
            .expect("approach")
            + from;
        let lift = (path.moves[from + 1].pose.tip - path.moves[from].pose.tip).norm();
        assert!(lift > options.clearance, "lifted {lift}");
        let centre = |m: &Move| m.pose.tip + m.pose.axis.into_inner() * r;
        for m in &path.moves[from + 1..to] {
            // Top of the plate at z = 20: the ball's lowest point keeps the margin up to the
            // clearance above the entry (along the 45° axis: clearance / √2 higher).
            let least = (options.clearance * tilt).min(options.rapid_margin);
            assert!(centre(m).z - r >= 20.0 + least - 1e-9, "{m:?}");
        }
        let slow_down = &path.moves[to - 1];
        assert_eq!(
            (slow_down.kind, slow_down.feed),
            (MoveKind::Retract, options.retract_feed)
        );
        assert!(
            (slow_down.pose.tip - path.moves[to].pose.tip).norm() - options.clearance < 1e-9,
            "the approach feed takes the last clearance only"
        );
        assert_eq!(path.moves[to].pose, tilted(47.0));
    }
}
