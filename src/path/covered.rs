//! Passes that cut nothing new: the stretches of a pass whose ball touches the part only where
//! passes kept before it already came as near (seed 000/001's coverage rule, every point
//! within δ of a pass and passes only where needed, applied to the balls as placed).
//!
//! Strategies space their passes on the drive surface, but the ball is placed against the
//! part: in a concave corner tighter than the ball every drive point within about a radius of
//! the wall lands on nearly the same ball centre. At a blade's root the flow lines beside the
//! wall and the loops less than a radius above the hub all become the one pass that touches
//! both blade and hub (the pencil line), cut over and over; on the sample impeller 5 m of its
//! 53 m of cutting ran within 0.1 mm of an earlier pass, on the blower 4 of 24 m.
//!
//! A pose is *covered* when a ball swept along a kept pass comes, within a slack, as near as
//! its own ball to every point of the part it touches (each triangle's nearest point within
//! [`CONTACT_BAND`] of the ball) and to six points round each, half a stepover away in the
//! plane square to the contact: what it finishes toward its neighbouring passes. There,
//! dropping the pose leaves at most the slack more. A pose
//! that touches nothing (a pass bridging a gap) is not covered: dropping it would only split
//! the pass. A covered stretch is dropped when it is at least `min_gap` long (at a pass's
//! ends, any length): a gap in the middle of a pass costs a link. What stays runs on by
//! `overlap` into the dropped stretch, as partial passes do.

use std::collections::HashMap;

use rayon::prelude::*;

use crate::geom::{Point3, Vector3, arc_lengths, closest_point_on_segment, run_on, runs_of_set};
use crate::mesh::SurfaceDistance;

use super::CutSegment;

/// How far beyond the radius a point of the part counts as touched by a ball, mm: the placed
/// balls sit a nanometre off the part, refined and smoothed poses within a micrometre.
pub const CONTACT_BAND: f64 = 1e-3;

/// How the covered stretches are found and dropped.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CoverOptions {
    pub ball_radius: f64,
    /// A touched point counts as covered within the ball's radius and this, mm (what dropping
    /// a pose may leave there).
    pub slack: f64,
    /// Shortest covered stretch dropped from the middle of a pass, mm of the ball centre's path.
    pub min_gap: f64,
    /// How far a kept stretch runs on into a dropped one, mm.
    pub overlap: f64,
    /// How far round each point a ball touches the kept balls must come as near as it, mm:
    /// half the stepover (what a pass finishes toward its neighbours).
    pub around: f64,
}

/// What [`SweptBalls::keep_needed`] dropped.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Covered {
    /// Passes looked at, and how many were dropped whole or split.
    pub passes: usize,
    pub passes_dropped: usize,
    pub passes_split: usize,
    pub poses_dropped: usize,
    /// Length of the ball centres' path dropped, mm.
    pub length_dropped_mm: f64,
}

impl Covered {
    pub fn merge(&mut self, other: &Covered) {
        self.passes += other.passes;
        self.passes_dropped += other.passes_dropped;
        self.passes_split += other.passes_split;
        self.poses_dropped += other.poses_dropped;
        self.length_dropped_mm += other.length_dropped_mm;
    }
}

/// The balls swept along the passes kept so far: capsules of the ball's radius around the
/// centres' moves, hashed by the cells their reach overlaps.
pub struct SweptBalls {
    options: CoverOptions,
    cell: f64,
    moves: Vec<[Point3; 2]>,
    cells: HashMap<[i64; 3], Vec<u32>>,
}

impl SweptBalls {
    pub fn new(options: CoverOptions) -> Self {
        Self {
            options,
            cell: options.ball_radius.max(1e-3),
            moves: Vec::new(),
            cells: HashMap::new(),
        }
    }

    fn key(&self, p: &Point3) -> [i64; 3] {
        [0, 1, 2].map(|k| (p[k] / self.cell).floor() as i64)
    }

    /// Adds the ball swept along `segment`'s centres.
    pub fn insert(&mut self, segment: &CutSegment) {
        let centres = centres(segment, self.options.ball_radius);
        for pair in centres.windows(2) {
            self.insert_move(pair[0], pair[1]);
        }
        if let [only] = centres.as_slice() {
            self.insert_move(*only, *only);
        }
    }

    /// Adds the ball swept along `toolpath`'s cut moves (another operation's, already linked).
    pub fn insert_cuts(&mut self, toolpath: &crate::geom::Toolpath) {
        let radius = self.options.ball_radius;
        let centre = |m: &crate::geom::Move| m.pose.tip + m.pose.axis.into_inner() * radius;
        for w in toolpath.moves.windows(2) {
            if w[1].kind == crate::geom::MoveKind::Cut {
                self.insert_move(centre(&w[0]), centre(&w[1]));
            }
        }
    }

    fn insert_move(&mut self, a: Point3, b: Point3) {
        let index = self.moves.len() as u32;
        self.moves.push([a, b]);
        let reach = self.reach();
        let lo = self.key(&a.inf(&b).map(|v| v - reach));
        let hi = self.key(&a.sup(&b).map(|v| v + reach));
        for x in lo[0]..=hi[0] {
            for y in lo[1]..=hi[1] {
                for z in lo[2]..=hi[2] {
                    self.cells.entry([x, y, z]).or_default().push(index);
                }
            }
        }
    }

    /// The farthest a point [`SweptBalls::covers`] asks of lies from the centres: the radius,
    /// the slack and the points round a contact.
    fn reach(&self) -> f64 {
        self.options.ball_radius + self.options.slack + self.options.around
    }

    /// Whether a swept ball's centre comes within `reach` of `p` (at most
    /// the radius, the slack and `around`: the cells hold no more).
    pub fn covers(&self, p: &Point3, reach: f64) -> bool {
        let reach = reach.min(self.reach());
        self.cells.get(&self.key(p)).is_some_and(|moves| {
            moves.iter().any(|&m| {
                let [a, b] = self.moves[m as usize];
                (closest_point_on_segment(p, &a, &b) - p).norm_squared() <= reach * reach
            })
        })
    }

    /// The stretches of `segments` (in order of precedence) that cut something the passes
    /// kept before them have not, each kept stretch added to the swept balls as it is kept.
    /// A segment with leads (a swarf run) is kept whole.
    pub fn keep_needed(
        &mut self,
        segments: Vec<CutSegment>,
        surface: &SurfaceDistance,
    ) -> (Vec<CutSegment>, Covered) {
        let radius = self.options.ball_radius;
        // What each pose's ball touches does not depend on the order: found in parallel.
        let touched: Vec<Vec<Vec<(Point3, f64)>>> = segments
            .par_iter()
            .map(|segment| {
                centres(segment, radius)
                    .iter()
                    .map(|c| touched_points(surface, c, radius, self.options.around))
                    .collect()
            })
            .collect();
        let mut stats = Covered::default();
        let mut kept = Vec::with_capacity(segments.len());
        for (segment, touched) in segments.into_iter().zip(touched) {
            stats.passes += 1;
            if segment.leads {
                self.insert(&segment);
                kept.push(segment);
                continue;
            }
            let slack = self.options.slack;
            let needed: Vec<bool> = touched
                .iter()
                .map(|points| {
                    points.is_empty()
                        || points
                            .iter()
                            .any(|(p, from_centre)| !self.covers(p, from_centre + slack))
                })
                .collect();
            let pieces = self.needed_pieces(&segment, &needed);
            let kept_poses: usize = pieces.iter().map(|r| r.len()).sum();
            if kept_poses < segment.poses.len() {
                let centres = centres(&segment, radius);
                let mut inside = vec![false; centres.len()];
                for range in &pieces {
                    inside[range.clone()].iter_mut().for_each(|k| *k = true);
                }
                stats.poses_dropped += segment.poses.len() - kept_poses;
                stats.length_dropped_mm += centres
                    .windows(2)
                    .zip(inside.windows(2))
                    .filter(|(_, k)| !(k[0] && k[1]))
                    .map(|(c, _)| (c[1] - c[0]).norm())
                    .sum::<f64>();
                match pieces.len() {
                    0 => stats.passes_dropped += 1,
                    _ => stats.passes_split += 1,
                }
            }
            for range in pieces {
                let piece = CutSegment {
                    poses: segment.poses[range.clone()].to_vec(),
                    pass_directions: segment.pass_directions[range].to_vec(),
                    leads: false,
                };
                self.insert(&piece);
                kept.push(piece);
            }
        }
        (kept, stats)
    }

    /// The index ranges of `segment` to keep: every needed pose, run on by the overlap, and
    /// the covered stretches too short to drop from the middle.
    fn needed_pieces(&self, segment: &CutSegment, needed: &[bool]) -> Vec<std::ops::Range<usize>> {
        let n = needed.len();
        if n < 2 || needed.iter().all(|&k| k) {
            return std::iter::once(0..n).collect();
        }
        let along = arc_lengths(&centres(segment, self.options.ball_radius));
        let mut keep = run_on(needed, &along, self.options.overlap);
        // Gaps between kept stretches shorter than `min_gap` are kept too.
        let dropped: Vec<bool> = keep.iter().map(|k| !k).collect();
        for gap in runs_of_set(&dropped) {
            let inner = gap.start > 0 && gap.end < n;
            if inner && along[gap.end] - along[gap.start - 1] < self.options.min_gap {
                keep[gap].iter_mut().for_each(|k| *k = true);
            }
        }
        // A lone needed pose (its neighbours farther than the overlap) keeps a move.
        runs_of_set(&keep)
            .into_iter()
            .map(|run| match run.len() {
                1 if run.start > 0 => run.start - 1..run.end,
                1 => run.start..(run.end + 1).min(n),
                _ => run,
            })
            .collect()
    }
}

/// The ball centres along `segment`.
fn centres(segment: &CutSegment, radius: f64) -> Vec<Point3> {
    segment
        .poses
        .iter()
        .map(|p| p.tip + p.axis.into_inner() * radius)
        .collect()
}

/// The points a ball at `centre` must leave no worse, with their distance from the centre:
/// where it touches the part (each triangle's nearest point within the radius and
/// [`CONTACT_BAND`], those within a micrometre of another dropped) and round each, six points
/// `around` away in the plane square to the ball's normal there. A ball that comes as near
/// to those finishes what the dropped one did between it and the next pass, on any curvature.
fn touched_points(
    surface: &SurfaceDistance,
    centre: &Point3,
    radius: f64,
    around: f64,
) -> Vec<(Point3, f64)> {
    let mut contacts: Vec<Point3> = Vec::new();
    surface.segment_search(centre, centre, radius + CONTACT_BAND, |p| {
        if contacts.iter().all(|c| (c - p).norm_squared() > 1e-6) {
            contacts.push(*p);
        }
        false
    });
    let mut points = Vec::with_capacity(7 * contacts.len());
    for c in contacts {
        points.push((c, (c - centre).norm()));
        let Some(normal) = (centre - c).try_normalize(1e-12) else {
            continue;
        };
        let u = normal
            .cross(&Vector3::x())
            .try_normalize(0.1)
            .unwrap_or_else(|| normal.cross(&Vector3::y()).normalize());
        let v = normal.cross(&u);
        for k in 0..6 {
            let angle = f64::from(k) * std::f64::consts::FRAC_PI_3;
            let q = c + (u * angle.cos() + v * angle.sin()) * around;
            points.push((q, (q - centre).norm()));
        }
    }
    points
}

#[cfg(test)]
mod tests;
