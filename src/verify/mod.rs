//! Verification of a finished toolpath against the part, independent of how it was planned.
//!
//! Every cut and approach pose is checked again: the ball centre's exact f64 signed distance to
//! the part (gouge), and the distance of flutes, shank and holder to the part (parry3d
//! `closest_points` with a search radius; full `distance` is milliseconds per query on big
//! meshes, CRATES.md §2). Straight moves between consecutive cut poses are checked at their
//! midpoints too, which is where a chord cuts deepest into a convex surface. [`PoseChecks`]
//! says which bodies: a plan leaves the flutes to [`check_posted`], which measures them
//! between the poses too.
//!
//! [`check_posted`] goes further and checks what a machine would run: it reads the posted
//! G-code back, interpolates every block in machine axes as the control does and measures the
//! ball centre along it against the part (its own G-code reader, forward kinematics and
//! segment–mesh distance; nothing shared with the post or the planner's queries).

mod posted;
mod program;
mod reach;
mod scallop;
mod segment_distance;

pub use posted::{
    ChainModel, FluteClearance, MachineModel, ModelAxis, PostedClearance, PostedOptions,
    check_posted, program_toolpath,
};
pub use program::{MotionBlock, ProgramError, read_conversational, read_program};
pub use reach::ToolReach;
pub use scallop::{
    AreaSplit, Ball, SampleScallop, ScallopOptions, ScallopPatch, ScallopReport, measure_scallop,
    measure_scallop_map, measure_scallop_map_of, ray_capsule_entry,
};
pub use segment_distance::SegmentDistance;

use rayon::prelude::*;
use serde::Serialize;

use crate::collide::{BodyClearance, PartCollider, PreparedTool};
use crate::geom::Point3;
use crate::geom::{MoveKind, ToolPose, Toolpath};

/// Which bodies [`verify`] measures at every pose besides the ball (which it always does).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PoseChecks {
    /// Flutes, shank, holder and table.
    Everything,
    /// Shank, holder and table. For a program whose back-simulation ([`check_posted`] with
    /// [`PostedOptions::flutes_above_ball`]) measures the sheet the flutes sweep along every
    /// posted block: a certified bound between the poses as well as at them, so measuring
    /// them again pose by pose adds nothing (and was half this check's time on the blower).
    LeaveFlutesToBackSimulation,
    /// None: the stock a path leaves on the part, its bodies checked elsewhere.
    BallOnly,
}

/// Clearances over all checked poses, mm. Body clearances are capped at `search`; a body
/// [`PoseChecks`] left out is `None`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Verification {
    pub checked_poses: usize,
    pub checked_midpoints: usize,
    /// min over poses of (ball centre distance − ball radius): 0 means touching, < 0 a gouge.
    pub min_cutter_clearance: f64,
    /// The same at the midpoints of cut moves (the chord error, negative = inside by that much).
    pub min_chord_clearance: f64,
    /// Flutes (the cylinder above the ball): ≈0 where the ball touches with its side or they
    /// cut along a flank (swarf), < 0 where they are inside the part. parry's distance where
    /// they keep off the part; where it finds them touching or inside, for a ball-end tool,
    /// the distance from their axis (the ball's centre up, flat-ended) to the part less their
    /// radius, exact in f64.
    pub min_flutes_clearance: Option<f64>,
    pub min_shank_clearance: Option<f64>,
    pub min_holder_clearance: Option<f64>,
    /// Lowest point of the tool above the table top (∞ without a table).
    pub min_table_clearance: Option<f64>,
    /// The body clearances above were searched up to this distance.
    pub search_distance: f64,
}

impl Verification {
    /// The verification of two paths checked apart (each with its own tool) as one: counts
    /// added, every clearance the least of the two.
    pub fn merge(&self, other: &Verification) -> Verification {
        Verification {
            checked_poses: self.checked_poses + other.checked_poses,
            checked_midpoints: self.checked_midpoints + other.checked_midpoints,
            min_cutter_clearance: self.min_cutter_clearance.min(other.min_cutter_clearance),
            min_chord_clearance: self.min_chord_clearance.min(other.min_chord_clearance),
            min_flutes_clearance: least(self.min_flutes_clearance, other.min_flutes_clearance),
            min_shank_clearance: least(self.min_shank_clearance, other.min_shank_clearance),
            min_holder_clearance: least(self.min_holder_clearance, other.min_holder_clearance),
            min_table_clearance: least(self.min_table_clearance, other.min_table_clearance),
            search_distance: self.search_distance.min(other.search_distance),
        }
    }

    /// Whether the path respects the tolerances and margins it was planned with; else every
    /// check it fails.
    pub fn passes(
        &self,
        tolerance: f64,
        shank_margin: f64,
        holder_margin: f64,
        table_margin: f64,
    ) -> Result<(), VerificationFailure> {
        let mut problems = Vec::new();
        if self.min_cutter_clearance < -1e-6 {
            problems.push(Problem::Gouge {
                depth: -self.min_cutter_clearance,
            });
        }
        if self.min_chord_clearance < -tolerance - 1e-6 {
            problems.push(Problem::Chord {
                depth: -self.min_chord_clearance,
                tolerance,
            });
        }
        // The flutes cut with their side like the ball: within the tolerance of the part.
        if let Some(flutes) = self.min_flutes_clearance
            && flutes < -tolerance - 1e-6
        {
            problems.push(Problem::Flutes { depth: -flutes });
        }
        if let Some(shank) = self.min_shank_clearance
            && shank < shank_margin
        {
            problems.push(Problem::Shank {
                clearance: shank,
                margin: shank_margin,
            });
        }
        if let Some(holder) = self.min_holder_clearance
            && holder < holder_margin
        {
            problems.push(Problem::Holder {
                clearance: holder,
                margin: holder_margin,
            });
        }
        if let Some(table) = self.min_table_clearance
            && table < table_margin - 1e-9
        {
            problems.push(Problem::Table {
                clearance: table,
                margin: table_margin,
            });
        }
        if problems.is_empty() {
            Ok(())
        } else {
            Err(VerificationFailure { problems })
        }
    }
}

/// A check of [`Verification::passes`] that a path fails, with its figures (mm).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Problem {
    #[error("ball gouges the part by {depth:.6} mm")]
    Gouge { depth: f64 },
    #[error("a straight move cuts {depth:.6} mm into the part (tolerance {tolerance})")]
    Chord { depth: f64, tolerance: f64 },
    #[error("the flutes cut {depth:.6} mm into the part above the ball, beyond the tolerance")]
    Flutes { depth: f64 },
    #[error("shank clearance {clearance:.4} mm is below its margin {margin}")]
    Shank { clearance: f64, margin: f64 },
    #[error("holder clearance {clearance:.4} mm is below its margin {margin}")]
    Holder { clearance: f64, margin: f64 },
    #[error("the tool comes {clearance:.4} mm from the table, below its margin {margin}")]
    Table { clearance: f64, margin: f64 },
}

/// Every check a path fails (at least one).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{}", .problems.iter().map(|p| p.to_string()).collect::<Vec<_>>().join("; "))]
pub struct VerificationFailure {
    pub problems: Vec<Problem>,
}

/// The clearance of the flutes round the segment `from to` (their axis, from the ball's
/// centre up) of `radius` when it is below `upto`, else `upto`: one "anything nearer?" query,
/// and bisection on the distance only when there is (branch and bound over a chunk's running
/// minimum). Only the part between the planes square to the axis through its ends counts
/// (a flat-ended cylinder): below the ball's equator is the ball's. With the axis wholly
/// inside the part the clearance is `-radius`.
fn flutes_below(part: &PartCollider, from: &Point3, to: &Point3, radius: f64, upto: f64) -> f64 {
    let surface = part.surface();
    let within = |distance: f64| {
        surface.cylinder_search(from, to, distance, |_| true) != crate::mesh::SegmentSearch::Clear
    };
    let limit = radius + upto;
    if limit <= 0.0 || !within(limit) {
        return upto;
    }
    let (mut near, mut far) = (0.0, limit);
    for _ in 0..40 {
        let mid = 0.5 * (near + far);
        if within(mid) {
            far = mid;
        } else {
            near = mid;
        }
    }
    near - radius
}

/// The lesser of two minima, either of which may not have been measured.
fn least(a: Option<f64>, b: Option<f64>) -> Option<f64> {
    match (a, b) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    }
}

/// Every how many poses the first pass of [`verify`] measures one.
const CEILING_SAMPLE: usize = 16;

/// Checks every cut and approach pose of `path`, the bodies `checks` names. Body clearances
/// are searched up to `search` mm.
///
/// Exact clearance queries cost far more than "is it farther than d" queries, and only the
/// minimum is reported, so each chunk of poses keeps its running minimum and asks each pose
/// only whether it comes closer than that (branch and bound). The bound starts at what a first
/// pass over every 16th pose found: a clearance some pose has, so at least the minimum, and
/// far below the search distance where a body comes near anywhere (the shank beside the
/// blower's blades: most poses are then settled by the quick test, where a chunk starting from
/// the search distance measured them exactly until it came near). Chunks are fixed, and the
/// minimum of exact per-pose values does not depend on the order they were found in, so the
/// result is the same for any number of threads.
pub fn verify(
    path: &Toolpath,
    part: &PartCollider,
    tool: &PreparedTool,
    search: f64,
    checks: PoseChecks,
) -> Verification {
    let r = tool.ball_radius;
    let centre = |pose: &ToolPose| pose.tip + pose.axis.into_inner() * r;
    let ball_clearance = |c: &Point3| {
        part.surface()
            .signed_distance(c)
            .map_or(f64::NEG_INFINITY, |(d, _)| d - r)
    };
    let flutes_axis = tool.flutes_above_ball();
    let measure_flutes = checks == PoseChecks::Everything;
    let measure_bodies = checks != PoseChecks::BallOnly;
    // A body whose bound is not above 0 is not measured by `clearances`: that is how the
    // bodies left out are skipped.
    let start = BodyClearance {
        flutes: if measure_flutes {
            search
        } else {
            f64::NEG_INFINITY
        },
        shank: if measure_bodies {
            search
        } else {
            f64::NEG_INFINITY
        },
        holder: if measure_bodies {
            search
        } else {
            f64::NEG_INFINITY
        },
    };
    // The least body clearances of the poses in `chunk` below `bound`, and, with `ball`, the
    // least ball and table clearances.
    let measure = |chunk: &[usize], bound: &BodyClearance, ball_too: bool| {
        let mut ball = f64::INFINITY;
        let mut bodies = *bound;
        let mut table = f64::INFINITY;
        for &i in chunk {
            let pose = &path.moves[i].pose;
            if ball_too {
                ball = ball.min(ball_clearance(&centre(pose)));
                if measure_bodies {
                    table = table.min(part.table_clearance(tool, pose, 0.0));
                }
            }
            if !measure_bodies {
                continue;
            }
            let before = bodies.flutes;
            bodies = part.clearances(tool, pose, &bodies);
            // parry floors flutes it finds intersecting at 0 or −slack, however deep:
            // those (flutes touching a wall, cutting a flank) are measured exactly.
            if let Some((length, radius)) = flutes_axis
                && measure_flutes
                && bodies.flutes <= 0.0
            {
                let from = centre(pose);
                let to = from + pose.axis.into_inner() * length;
                bodies.flutes = flutes_below(part, &from, &to, radius, before);
            }
        }
        (ball, bodies, table)
    };
    let cutting: Vec<usize> = (0..path.moves.len())
        .filter(|&i| matches!(path.moves[i].kind, MoveKind::Cut | MoveKind::Approach))
        .collect();
    let sample: Vec<usize> = cutting.iter().copied().step_by(CEILING_SAMPLE).collect();
    let ceilings = if measure_bodies {
        sample
            .par_chunks(256)
            .map(|chunk| measure(chunk, &start, false).1)
            .collect::<Vec<_>>()
            .iter()
            .fold(start, |a, b| BodyClearance {
                flutes: a.flutes.min(b.flutes),
                shank: a.shank.min(b.shank),
                holder: a.holder.min(b.holder),
            })
    } else {
        start
    };
    let per_chunk: Vec<(f64, BodyClearance, f64)> = cutting
        .par_chunks(256)
        .map(|chunk| measure(chunk, &ceilings, true))
        .collect();
    let midpoints: Vec<f64> = (1..path.moves.len())
        .filter(|&i| path.moves[i].kind == MoveKind::Cut)
        .collect::<Vec<_>>()
        .par_iter()
        .map(|&i| {
            ball_clearance(&nalgebra::center(
                &centre(&path.moves[i - 1].pose),
                &centre(&path.moves[i].pose),
            ))
        })
        .collect();
    let min = |f: &dyn Fn(&(f64, BodyClearance, f64)) -> f64| {
        per_chunk.iter().map(f).fold(f64::INFINITY, f64::min)
    };
    // Bounded by the ceilings, a chunk finds nothing below them where its poses keep farther.
    let least_body = |measured: bool, ceiling: f64, f: &dyn Fn(&BodyClearance) -> f64| {
        measured.then(|| min(&|c| f(&c.1)).min(ceiling))
    };
    Verification {
        checked_poses: cutting.len(),
        checked_midpoints: midpoints.len(),
        min_cutter_clearance: min(&|c| c.0),
        min_chord_clearance: midpoints.iter().copied().fold(f64::INFINITY, f64::min),
        min_flutes_clearance: least_body(measure_flutes, ceilings.flutes, &|b| b.flutes),
        min_shank_clearance: least_body(measure_bodies, ceilings.shank, &|b| b.shank),
        min_holder_clearance: least_body(measure_bodies, ceilings.holder, &|b| b.holder),
        min_table_clearance: measure_bodies.then(|| min(&|c| c.2)),
        search_distance: search,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn clear() -> Verification {
        Verification {
            checked_poses: 10,
            checked_midpoints: 9,
            min_cutter_clearance: 0.0,
            min_chord_clearance: -0.004,
            min_flutes_clearance: Some(0.1),
            min_shank_clearance: Some(0.6),
            min_holder_clearance: Some(2.5),
            min_table_clearance: Some(3.0),
            search_distance: 7.0,
        }
    }

    /// One path per check, each made to fail exactly that check (tolerance 0.005, margins
    /// 0.5 / 2 / 2): the message names what failed. Issue 17 item 5: the table clearance was
    /// computed and never checked, so a path into the table passed.
    #[test]
    fn each_check_fails_the_path_made_to_fail_it() {
        let check = |v: &Verification| v.passes(0.005, 0.5, 2.0, 2.0);
        assert!(check(&clear()).is_ok());
        type Breaker = fn(&mut Verification);
        let cases: [(Breaker, Problem, &str); 6] = [
            (
                |v| v.min_cutter_clearance = -0.001,
                Problem::Gouge { depth: 0.001 },
                "gouges",
            ),
            (
                |v| v.min_chord_clearance = -0.006,
                Problem::Chord {
                    depth: 0.006,
                    tolerance: 0.005,
                },
                "straight move",
            ),
            (
                |v| v.min_flutes_clearance = Some(-0.01),
                Problem::Flutes { depth: 0.01 },
                "flutes",
            ),
            (
                |v| v.min_shank_clearance = Some(0.49),
                Problem::Shank {
                    clearance: 0.49,
                    margin: 0.5,
                },
                "shank",
            ),
            (
                |v| v.min_holder_clearance = Some(1.9),
                Problem::Holder {
                    clearance: 1.9,
                    margin: 2.0,
                },
                "holder",
            ),
            (
                |v| v.min_table_clearance = Some(1.5),
                Problem::Table {
                    clearance: 1.5,
                    margin: 2.0,
                },
                "table",
            ),
        ];
        for (break_it, problem, needle) in cases {
            let mut v = clear();
            break_it(&mut v);
            let e = check(&v).unwrap_err();
            assert_eq!(e.problems, vec![problem]);
            assert!(e.to_string().contains(needle), "{needle}: {e}");
        }
    }

    /// `verify` itself, on a 30 × 30 × 40 block standing on a table (top z = 0) with a D6 ball
    /// mill (shank D6 from 12 mm, holder D30 from 30 mm), one path made to fail each check:
    /// the clearance it reports is the closed-form one, and `passes` names that check.
    #[test]
    fn verify_measures_each_clearance_on_a_path_made_to_fail_it() {
        use crate::collide::{Margins, Table};
        use crate::geom::{Direction, Move, Vector3};
        let part = PartCollider::new(&crate::mesh::fixtures::cuboid(30.0, 30.0, 40.0))
            .expect("block")
            .with_table(Table {
                top_z: 0.0,
                margin: 2.0,
            });
        let margins = Margins {
            shank: 0.5,
            holder: 2.0,
        };
        let tool = PreparedTool::new(&crate::collide::tool_bodies::tests::tool(), &margins);
        let path = |poses: &[([f64; 3], [f64; 3])]| Toolpath {
            tool_id: 1,
            moves: poses
                .iter()
                .map(|&(tip, axis)| Move {
                    pose: ToolPose {
                        tip: Point3::from(tip),
                        axis: Direction::new_normalize(Vector3::from(axis)),
                    },
                    kind: MoveKind::Cut,
                    feed: 1000.0,
                })
                .collect(),
        };
        let check = |v: &Verification| v.passes(0.005, 0.5, 2.0, 2.0);
        let up = [0.0, 0.0, 1.0];
        let verify_poses = |poses: &[([f64; 3], [f64; 3])]| {
            verify(&path(poses), &part, &tool, 7.0, PoseChecks::Everything)
        };

        // The ball 0.1 mm into the top face.
        let v = verify_poses(&[([15.0, 15.0, 39.9], up)]);
        assert!((v.min_cutter_clearance + 0.1).abs() < 1e-9, "{v:?}");
        assert!(matches!(
            check(&v).unwrap_err().problems[..],
            [Problem::Gouge { .. }]
        ));

        // Two poses touching the top and the side face; the chord between the ball centres
        // runs through the edge at its midpoint: clearance −r there.
        let v = verify_poses(&[
            ([27.0, 15.0, 40.0], up),
            ([30.0, 15.0, 37.0], [1.0, 0.0, 0.0]),
        ]);
        assert!(v.min_cutter_clearance.abs() < 1e-9, "{v:?}");
        assert!((v.min_chord_clearance + 3.0).abs() < 1e-9, "{v:?}");
        assert!(
            check(&v)
                .unwrap_err()
                .problems
                .iter()
                .any(|p| matches!(p, Problem::Chord { .. }))
        );

        // Beside the block, the tip 0.5 mm above the table.
        let v = verify_poses(&[([60.0, 15.0, 0.5], up)]);
        assert!((v.min_table_clearance.unwrap() - 0.5).abs() < 1e-9, "{v:?}");
        assert!(matches!(
            check(&v).unwrap_err().problems[..],
            [Problem::Table { .. }]
        ));

        // Upright beside the wall, 0.2 mm off it: the ball and the flutes keep 0.2 mm, the
        // shank 0.2 mm (below its 0.5 margin), the D30 holder reaches into the block.
        let v = verify_poses(&[([33.2, 15.0, 5.0], up)]);
        assert!((v.min_cutter_clearance - 0.2).abs() < 1e-9, "{v:?}");
        assert!((v.min_shank_clearance.unwrap() - 0.2).abs() < 1e-3, "{v:?}");
        assert!(v.min_holder_clearance.unwrap() <= 0.0, "{v:?}");
        let e = check(&v).unwrap_err();
        assert!(
            matches!(
                e.problems[..],
                [Problem::Shank { .. }, Problem::Holder { .. }]
            ),
            "{e}"
        );
    }

    /// The bound a chunk starts from (the first pass's minima) and its running minimum only
    /// skip poses that cannot lower the answer: over 700 poses round the block (beside its
    /// walls at 0.1–6 mm, tilted up to 40°, above its top), every minimum equals the least of
    /// the poses verified one by one. The checks left out are `None`; the rest do not change.
    #[test]
    fn bounded_verification_equals_the_poses_measured_one_by_one() {
        use crate::collide::{Margins, Table};
        use crate::geom::{Direction, Move, Vector3};
        let part = PartCollider::new(&crate::mesh::fixtures::cuboid(30.0, 30.0, 40.0))
            .expect("block")
            .with_table(Table {
                top_z: 0.0,
                margin: 2.0,
            });
        let tool = PreparedTool::new(
            &crate::collide::tool_bodies::tests::tool(),
            &Margins {
                shank: 0.5,
                holder: 2.0,
            },
        );
        let r = tool.ball_radius;
        let moves: Vec<Move> = (0..720)
            .map(|i| {
                let f = i as f64;
                // Round the block's x = 30 wall and over its top, the gap and tilt varying.
                let gap = 0.1 + 5.9 * (0.5 + 0.5 * (f * 0.37).sin());
                let tilt = (40.0 * (f * 0.23).cos()).to_radians();
                let (tip, axis) = if i % 3 == 0 {
                    (
                        [5.0 + f * 0.03, 5.0 + (f * 0.7) % 20.0, 40.0 + gap],
                        Vector3::new(tilt.sin(), 0.0, tilt.cos()),
                    )
                } else {
                    (
                        [30.0 + r + gap, (f * 0.041) % 30.0, 4.0 + (f * 0.05) % 30.0],
                        Vector3::new(tilt.sin().abs(), 0.0, tilt.cos()),
                    )
                };
                Move {
                    pose: ToolPose {
                        tip: Point3::from(tip),
                        axis: Direction::new_normalize(axis),
                    },
                    kind: MoveKind::Cut,
                    feed: 1000.0,
                }
            })
            .collect();
        let path = Toolpath { tool_id: 1, moves };
        let whole = verify(&path, &part, &tool, 7.0, PoseChecks::Everything);
        let one_by_one = path
            .moves
            .iter()
            .map(|m| {
                let single = Toolpath {
                    tool_id: 1,
                    moves: vec![*m],
                };
                verify(&single, &part, &tool, 7.0, PoseChecks::Everything)
            })
            .reduce(|a, b| a.merge(&b))
            .expect("poses");
        assert_eq!(whole.checked_poses, 720);
        assert_eq!(whole.min_cutter_clearance, one_by_one.min_cutter_clearance);
        assert_eq!(whole.min_flutes_clearance, one_by_one.min_flutes_clearance);
        assert_eq!(whole.min_shank_clearance, one_by_one.min_shank_clearance);
        assert_eq!(whole.min_holder_clearance, one_by_one.min_holder_clearance);
        assert_eq!(whole.min_table_clearance, one_by_one.min_table_clearance);
        // Something came near: the bounds had work to do.
        let shank = whole.min_shank_clearance.expect("measured");
        assert!(shank > 0.0 && shank < 1.0, "{whole:?}");

        let without_flutes = verify(
            &path,
            &part,
            &tool,
            7.0,
            PoseChecks::LeaveFlutesToBackSimulation,
        );
        assert_eq!(without_flutes.min_flutes_clearance, None);
        assert_eq!(
            Verification {
                min_flutes_clearance: whole.min_flutes_clearance,
                ..without_flutes.clone()
            },
            whole
        );
        let ball = verify(&path, &part, &tool, 7.0, PoseChecks::BallOnly);
        assert_eq!(
            (
                ball.min_cutter_clearance,
                ball.min_chord_clearance,
                ball.min_shank_clearance,
                ball.min_table_clearance
            ),
            (
                whole.min_cutter_clearance,
                whole.min_chord_clearance,
                None,
                None
            )
        );
    }
}
