//! Swarf (flank) milling of ruled blades (issue 21 item 2): passes round the blade's root
//! with the tool standing along the blade's rulings, so the flutes finish the flank from the
//! root up in one go where point milling needs a loop per stepover of height.
//!
//! A flank is ruled within the tolerance where, through a root point, some straight line runs
//! up it without leaving the surface by more than the tolerance. The tool there is placed as
//! point milling places it — the ball pushed out to touch at the root point — and stands along
//! that line; its flutes, a cylinder of the ball's radius round the axis, then lie along the
//! flank. Nothing is assumed of the surface's form: the axis is searched by its angle off the
//! rising direction in the tangent plane at the ball's contact, each candidate brought onto
//! the surface the ball's centre keeps at its far end (a drafted flank leans its rulings toward
//! the normal), and what decides is the flutes' distance to the part, exact nearest-point
//! queries every 0.2 mm (`SAMPLE_STEP`) up the axis. The flank is the unbroken stretch from
//! the ball's centre up where that distance stays within the tolerance of the radius both ways (closer is
//! a gouge, farther leaves material) on this blade; above it (the tip's rounding) the flutes
//! only must not gouge. Where many lines keep within the tolerance (a nearly flat flank) the
//! one nearest the rising direction is taken, so neighbouring rulings agree; a direction to
//! snap to (the machine's pole) is taken where it does as well.
//!
//! The root is the loop a ball's radius above the hub (the ball sits on the hub, its equator
//! on the flank). Root points whose ruling holds and whose tool the job accepts (shank,
//! holder, table, machine) form runs; between neighbours rulings are inserted where the axis
//! turns more than allowed or the ball's chord or the flutes half-way would gouge. The
//! single-point offset of the swarf literature: a developable flank is cut exactly, a twisted
//! one leaves what its deviation says. [`SwarfPlan::sweeps`] tells the loops what is left to
//! them.

use rayon::prelude::*;
use serde::Serialize;

use crate::geom::{Aabb, Point3, Vector3, angle_between, closest_point_on_segment};
use crate::mesh::distance::SurfaceDistance;
use crate::mesh::{DrivePoint, SectionCurve};

/// Distance between the flutes' samples up the axis, mm.
const SAMPLE_STEP: f64 = 0.2;

/// Widest angle the axis is searched off the flank's rising direction, degrees.
const SEARCH_DEG: f64 = 45.0;

/// How near a ruling must be to [`SwarfOptions::snap_to`] to be snapped to it, degrees.
const SNAP_DEG: f64 = 2.0;

/// Steps of the walk out from the rising direction, each way, over [`SEARCH_DEG`].
const WALK_STEPS: i32 = 45;

/// Coarse scan step of the angle before the golden-section refinement, degrees.
const SCAN_STEP_DEG: f64 = 5.0;

/// Deepest halving between two rulings (an axis turn or a gouge in between).
const MAX_REFINE_DEPTH: u32 = 6;

/// Fewest rulings in a run: shorter stretches are left to the loops.
const MIN_RUN_RULINGS: usize = 3;

/// Shortest flank above the ball's centre worth a swarf pass, mm.
const MIN_FLANK: f64 = 1.0;

/// Shortest step between the ball centres of two rulings kept in a run, mm.
const MIN_STEP: f64 = 1e-4;

/// Rulings in a row whose centres turn the travel back, after which the run is split rather
/// than the rulings dropped (the centres' path turns round, as in an acute concave corner).
const TURN_STREAK: usize = 8;

/// How the swarf pass is asked to run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SwarfOptions {
    pub ball_radius: f64,
    /// The flutes' length above the ball's centre, mm (their radius is the ball's).
    pub flutes_above_ball: f64,
    /// Deviation allowed both ways between the flutes and the flank, mm.
    pub tolerance: f64,
    /// Longest step between rulings along the root, mm.
    pub max_step: f64,
    /// Largest turn of the axis between two neighbouring rulings, degrees.
    pub max_axis_turn_deg: f64,
    /// A direction taken instead of a ruling within 2° (`SNAP_DEG`) of it wherever the flutes
    /// along it keep within half the tolerance of the same flank: the machine's pole, where a
    /// tilt of hundredths of a degree swings the rotary table half a turn.
    pub snap_to: Option<Vector3>,
}

/// The tool standing along one ruling.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ruling {
    /// The root point and its normal.
    pub contact: DrivePoint,
    /// The ball's centre.
    pub centre: Point3,
    /// Unit tool axis, up the flank.
    pub axis: Vector3,
    /// Largest distance between the flutes and the flank off the ball's radius, either way, mm.
    pub deviation: f64,
    /// How far up the axis from the ball's centre the flank reaches, mm.
    pub flank_length: f64,
}

/// A stretch of the root the tool sweeps with its flutes along the flank: the whole loop
/// (`closed`) or part of it.
#[derive(Clone, Debug, PartialEq)]
pub struct SwarfRun {
    pub rulings: Vec<Ruling>,
    pub closed: bool,
}

/// What the search round a blade's root found.
#[derive(Clone, Debug, PartialEq)]
pub struct SwarfPlan {
    pub runs: Vec<SwarfRun>,
    /// Root points tried, and the ones refused with the reason.
    pub root_points: usize,
    pub refused: Vec<NotSwarf>,
    /// Rulings dropped from runs because their ball centre stepped back along the run.
    pub stepping_back: usize,
}

impl SwarfPlan {
    /// The largest deviation of any ruling kept, mm.
    pub fn deviation(&self) -> f64 {
        self.rulings().map(|r| r.deviation).fold(0.0, f64::max)
    }

    pub fn rulings(&self) -> impl Iterator<Item = &Ruling> {
        self.runs.iter().flat_map(|run| &run.rulings)
    }

    /// Whether the flutes of a run pass within `radius` of `p`, anywhere between two
    /// neighbouring rulings, their axis extended down `below` mm past the ball's centre (the
    /// corner under the ball's equator, which no ball of this radius reaches, counts as theirs).
    pub fn sweeps(&self, p: &Point3, radius: f64, below: f64) -> bool {
        // A point half-way between two interpolated axes is (Δ/16)²/2r off them: nothing.
        const SUBDIVISIONS: usize = 8;
        self.runs.iter().any(|run| {
            let n = run.rulings.len();
            let pairs = if run.closed { n } else { n.saturating_sub(1) };
            (0..pairs).any(|i| {
                let (a, b) = (&run.rulings[i], &run.rulings[(i + 1) % n]);
                // The interpolated axes stay within the box of the two rulings' ends, grown by
                // how far a renormalised axis can stray from the chord of theirs: a point
                // farther from that box than the stray and the radius is not swept by them.
                let reach = below.max(a.flank_length).max(b.flank_length);
                let grow = radius + reach * (a.axis - b.axis).norm();
                let ends = [
                    a.centre - a.axis * below,
                    a.centre + a.axis * a.flank_length,
                    b.centre - b.axis * below,
                    b.centre + b.axis * b.flank_length,
                ];
                let outside = Aabb::from_points(&ends).distance_squared(p) > grow * grow;
                if outside {
                    return false;
                }
                (0..=SUBDIVISIONS).any(|k| {
                    let t = k as f64 / SUBDIVISIONS as f64;
                    let centre = a.centre + (b.centre - a.centre) * t;
                    let axis = (a.axis * (1.0 - t) + b.axis * t).normalize();
                    let length = a.flank_length + (b.flank_length - a.flank_length) * t;
                    let (from, to) = (centre - axis * below, centre + axis * length);
                    (p - closest_point_on_segment(p, &from, &to)).norm() <= radius
                })
            })
        })
    }
}

/// Why a root point (or the whole blade) is not swarfed.
#[derive(Clone, Debug, PartialEq, Serialize, thiserror::Error)]
#[serde(rename_all = "snake_case", tag = "reason")]
pub enum NotSwarf {
    /// No closed loop round the blade a ball's radius above the hub (or no flutes above a
    /// ball to swarf with).
    #[error("no loop round the blade's root a ball's radius above the hub")]
    NoRoot,
    /// The flank leaves the best line through a root point by more than the tolerance within
    /// 1 mm (`MIN_FLANK`) of the ball's centre (a rounded or leaning blade end, a twisted flank).
    #[error("not ruled within the tolerance: {deviation_mm:.4} mm off the best line at {at:?}")]
    NotRuled { deviation_mm: f64, at: [f64; 3] },
    /// The flank goes on above the top of the flutes.
    #[error("the flank at {at:?} is taller than the flutes")]
    TallerThanFlutes { at: [f64; 3] },
    /// The surface at the root faces up or down the blade, not across it.
    #[error("the root at {at:?} is not on a flank")]
    NotAFlank { at: [f64; 3] },
    /// The tool standing along the ruling at `at` is refused (`why`: the ball does not fit,
    /// the ball or flutes gouge elsewhere, shank, holder or table, the machine's limits, or
    /// the axis turns too fast between two rulings).
    #[error("the tool along the ruling at {at:?} is refused: {why}")]
    Refused { at: [f64; 3], why: String },
}

/// The swarf runs round `root` (a closed loop on the blade a ball's radius above the hub), on
/// the part `surface`, whose triangles `on_blade` says are this blade's; `rising` gives the
/// direction a point's height above the hub grows in, `place` the ball's centre for a root
/// point (the finishing's placement: pushed out of every face nearer than the radius, `None`
/// where the ball does not fit), and `accept` says whether the tool may
/// stand along a ruling (the job's checks of shank, holder, table and machine; `Err` says
/// why not). Runs are the stretches where every ruling is within the tolerance and accepted,
/// and so is every one inserted between two of them.
pub fn swarf_runs(
    surface: &SurfaceDistance,
    on_blade: &(dyn Fn(u32) -> bool + Sync),
    rising: &(dyn Fn(&Point3) -> Vector3 + Sync),
    place: &(dyn Fn(&DrivePoint) -> Option<Point3> + Sync),
    accept: &(dyn Fn(&Ruling) -> Result<(), String> + Sync),
    root: &SectionCurve,
    options: &SwarfOptions,
) -> Result<SwarfPlan, NotSwarf> {
    if !root.closed || root.points.len() < 3 {
        return Err(NotSwarf::NoRoot);
    }
    let points = root
        .simplified(
            options.ball_radius,
            0.25 * options.tolerance,
            options.max_step,
        )
        .resampled(options.max_step);
    let find = |p: &DrivePoint| {
        let found = ruling(surface, on_blade, rising, place, p, options)?;
        accept(&found).map_err(|why| NotSwarf::Refused {
            at: [p.point.x, p.point.y, p.point.z],
            why,
        })?;
        Ok(found)
    };
    let found: Vec<Result<Ruling, NotSwarf>> = points.par_iter().map(find).collect();
    let n = found.len();
    let mut refused: Vec<NotSwarf> = found.iter().filter_map(|f| f.clone().err()).collect();
    // Walk the loop from a refused point (if any), so no run wraps round the start.
    let start = found.iter().position(|f| f.is_err());
    let order: Vec<usize> = (0..n).map(|i| (start.unwrap_or(0) + i) % n).collect();
    let mut runs = Vec::new();
    let mut current: Vec<Ruling> = Vec::new();
    // Whether a move between two held rulings failed: then no run goes all the way round.
    let mut broken = false;
    let close = |current: &mut Vec<Ruling>, runs: &mut Vec<SwarfRun>| {
        if current.len() >= MIN_RUN_RULINGS {
            runs.push(SwarfRun {
                rulings: std::mem::take(current),
                closed: false,
            });
        }
        current.clear();
    };
    for (k, &i) in order.iter().enumerate() {
        let Ok(ruling) = &found[i] else {
            close(&mut current, &mut runs);
            continue;
        };
        if let Some(last) = current.last().copied() {
            match between(&find, surface, &last, ruling, options, 0) {
                Ok(inserted) => current.extend(inserted),
                Err(why) => {
                    refused.push(why);
                    broken = true;
                    close(&mut current, &mut runs);
                }
            }
        }
        current.push(*ruling);
        if k + 1 == n && start.is_none() && !broken {
            // Every root point holds, and every move between: the run closes round the loop.
            match between(&find, surface, ruling, &current[0], options, 0) {
                Ok(inserted) => {
                    current.extend(inserted);
                    runs.push(SwarfRun {
                        rulings: std::mem::take(&mut current),
                        closed: true,
                    });
                }
                Err(why) => {
                    refused.push(why);
                    close(&mut current, &mut runs);
                }
            }
        }
    }
    close(&mut current, &mut runs);
    let mut forward = Vec::with_capacity(runs.len());
    let mut stepping_back = 0;
    for run in runs {
        let (kept, dropped) = forward_runs(surface, run, options);
        forward.extend(kept);
        stepping_back += dropped;
    }
    Ok(SwarfPlan {
        runs: forward,
        root_points: n,
        refused,
        stepping_back,
    })
}

/// Rulings to insert between `a` and `b`, in order: halved where the axis turns too far, or
/// the ball's chord or the flutes half-way between the two would gouge.
fn between(
    find: &(dyn Fn(&DrivePoint) -> Result<Ruling, NotSwarf> + Sync),
    surface: &SurfaceDistance,
    a: &Ruling,
    b: &Ruling,
    options: &SwarfOptions,
    depth: u32,
) -> Result<Vec<Ruling>, NotSwarf> {
    if move_holds(surface, a, b, options) {
        return Ok(Vec::new());
    }
    let turn = angle_between(&a.axis, &b.axis).to_degrees();
    let centre = nalgebra::center(&a.centre, &b.centre);
    let at = [centre.x, centre.y, centre.z];
    let Some(normal) = (a.contact.normal + b.contact.normal).try_normalize(1e-9) else {
        return Err(NotSwarf::Refused {
            at,
            why: "the flank turns back between two rulings".into(),
        });
    };
    if depth >= MAX_REFINE_DEPTH {
        return Err(NotSwarf::Refused {
            at,
            why: format!("between two rulings the axis turns {turn:.1}° or the tool gouges"),
        });
    }
    let mid = find(&DrivePoint {
        point: nalgebra::center(&a.contact.point, &b.contact.point),
        normal,
    })?;
    let mut out = between(find, surface, a, &mid, options, depth + 1)?;
    out.push(mid);
    out.extend(between(find, surface, &mid, b, options, depth + 1)?);
    Ok(out)
}

/// Whether the tool may move straight from ruling `a` to ruling `b`: the axis turns no more
/// than allowed, and neither the ball's chord nor the flutes half-way come nearer the part
/// than the tolerance allows.
fn move_holds(surface: &SurfaceDistance, a: &Ruling, b: &Ruling, options: &SwarfOptions) -> bool {
    let held = options.ball_radius - options.tolerance;
    let centre = nalgebra::center(&a.centre, &b.centre);
    let axis = (a.axis + b.axis).try_normalize(1e-12).unwrap_or(a.axis);
    angle_between(&a.axis, &b.axis).to_degrees() <= options.max_axis_turn_deg
        && !surface.segment_within(&a.centre, &b.centre, held)
        && !surface.segment_within(&centre, &(centre + axis * options.flutes_above_ball), held)
}

/// `run` (rulings in order round the root) as runs whose ball centre never steps back.
///
/// Each root point's ball is pushed out of the faces near it, and a midpoint inserted between
/// two rulings is placed the same way: on a facetted flank, or where the root bends concave,
/// a ball centre can land behind the one before it, and the tool would zig back along the
/// flank. As the loops do (`path::push_forward_runs`), a ruling is dropped when its centre's
/// step from the last one kept is shorter than [`MIN_STEP`], goes against the root's
/// direction, or turns the travel back; the move that then spans the gap is checked as every
/// other ([`move_holds`]), and the run is split where it fails, or where [`TURN_STREAK`]
/// rulings in a row turn back (the centres' path itself turns round). A closed run whose last
/// move back to its start fails the same tests is left open. Runs shorter than
/// [`MIN_RUN_RULINGS`] are left to the loops; returns the runs and how many rulings were
/// dropped.
fn forward_runs(
    surface: &SurfaceDistance,
    run: SwarfRun,
    options: &SwarfOptions,
) -> (Vec<SwarfRun>, usize) {
    let rulings = run.rulings;
    let n = rulings.len();
    // The root's direction at each ruling: from the nearest root point behind it to the
    // nearest ahead that are elsewhere (neighbouring rulings can share a root point: a crease
    // of the facets is kept with each face's normal, and each gives its own ball).
    let elsewhere = |i: usize, ahead: bool| {
        let at = rulings[i].contact.point;
        let mut j = i;
        for _ in 1..n {
            j = match (ahead, run.closed) {
                (true, _) if j + 1 < n => j + 1,
                (true, true) => 0,
                (false, _) if j > 0 => j - 1,
                (false, true) => n - 1,
                _ => break,
            };
            let p = rulings[j].contact.point;
            if (p - at).norm() > MIN_STEP {
                return p;
            }
        }
        at
    };
    let tangents: Vec<Vector3> = (0..n)
        .map(|i| elsewhere(i, true) - elsewhere(i, false))
        .collect();
    let steps_back = |kept: &[Ruling], next: usize| {
        let last = &kept[kept.len() - 1];
        let step = rulings[next].centre - last.centre;
        let turns_back =
            kept.len() >= 2 && step.dot(&(last.centre - kept[kept.len() - 2].centre)) < 0.0;
        step.norm() < MIN_STEP || step.dot(&tangents[next]) < 0.0 || turns_back
    };
    let mut runs = Vec::new();
    let mut dropped = 0;
    let emit = |kept: Vec<Ruling>, runs: &mut Vec<SwarfRun>| {
        if kept.len() >= MIN_RUN_RULINGS {
            runs.push(SwarfRun {
                rulings: kept,
                closed: false,
            });
        }
    };
    let mut kept: Vec<Ruling> = Vec::with_capacity(rulings.len());
    let mut split = false;
    // Whether rulings were dropped since the last one kept, and where the streak began.
    let mut streak: Option<(usize, usize)> = None;
    let mut i = 0;
    while i < rulings.len() {
        let next = rulings[i];
        i += 1;
        if kept.is_empty() {
            kept.push(next);
            continue;
        }
        if steps_back(&kept, i - 1) {
            dropped += 1;
            let (first, count) = streak.unwrap_or((i - 1, 0));
            streak = Some((first, count + 1));
            if count + 1 == TURN_STREAK {
                // The path turns round here: end the run, start the next at the turn.
                dropped -= TURN_STREAK;
                split = true;
                emit(std::mem::take(&mut kept), &mut runs);
                (i, streak) = (first, None);
            }
            continue;
        }
        if streak.take().is_some() && !move_holds(surface, &kept[kept.len() - 1], &next, options) {
            split = true;
            emit(std::mem::take(&mut kept), &mut runs);
        }
        kept.push(next);
    }
    // A closed run's last ruling may be its first again (the loop's end point): not a step.
    if run.closed && !split {
        while kept.len() > 1 && (kept[0].centre - kept[kept.len() - 1].centre).norm() < MIN_STEP {
            kept.pop();
        }
    }
    // Round the loop only when nothing was split off and the move back to the start holds.
    let closes = run.closed
        && !split
        && kept.len() >= MIN_RUN_RULINGS
        && !steps_back(&kept, 0)
        && (streak.is_none() || move_holds(surface, &kept[kept.len() - 1], &kept[0], options));
    if closes {
        runs.push(SwarfRun {
            rulings: kept,
            closed: true,
        });
    } else {
        emit(kept, &mut runs);
    }
    (runs, dropped)
}

/// The flutes' distance to the part off the ball's radius at the samples up the axis from
/// `centre` (0 at the centre), and whether each sample's nearest point is on this blade (or
/// the blade is as near as the nearest).
fn deviations(
    surface: &SurfaceDistance,
    on_blade: &(dyn Fn(u32) -> bool + Sync),
    centre: &Point3,
    axis: &Vector3,
    length: f64,
    radius: f64,
) -> Vec<(f64, f64, bool)> {
    let steps = (length / SAMPLE_STEP).ceil().max(1.0) as usize;
    (0..=steps)
        .map(|k| {
            let s = length * k as f64 / steps as f64;
            let q = centre + axis * s;
            // Farther than this from everything, a sample neither gouges nor is on the flank.
            match surface.closest(&q, radius + 1.0) {
                Some(near) => {
                    // Where another face is as near (the hub under the ball), the blade's own
                    // distance says whether the flank is there too.
                    let on = on_blade(near.triangle)
                        || surface
                            .closest_where(&q, near.distance + 1e-9, on_blade)
                            .is_some();
                    (s, near.distance - radius, on)
                }
                None => (s, 1.0, false),
            }
        })
        .collect()
}

/// How far up the axis the flank follows the flutes within `tolerance`, from the ball's
/// centre on: the last sample of the unbroken run of samples on the blade within it.
fn flank_length(samples: &[(f64, f64, bool)], tolerance: f64) -> f64 {
    samples
        .iter()
        .take_while(|(_, d, blade)| *blade && d.abs() <= tolerance)
        .last()
        .map_or(0.0, |(s, _, _)| *s)
}

/// The best ruling through root point `p`.
///
/// The axis is searched in the tangent plane at the ball's contact, by its angle off the
/// rising direction. What is minimised is the largest deviation over a stretch of the axis
/// that lies beside the flank, which is smooth in the angle (the flank's normal curvature
/// along it): first over the shortest flank worth swarfing, then over the flank that axis
/// finds, around the first answer. The flank is where the flutes follow the surface within
/// the tolerance without a break; above it (a rounded tip) they only must not gouge.
fn ruling(
    surface: &SurfaceDistance,
    on_blade: &(dyn Fn(u32) -> bool + Sync),
    rising: &(dyn Fn(&Point3) -> Vector3 + Sync),
    place: &(dyn Fn(&DrivePoint) -> Option<Point3> + Sync),
    p: &DrivePoint,
    options: &SwarfOptions,
) -> Result<Ruling, NotSwarf> {
    let at = [p.point.x, p.point.y, p.point.z];
    let r = options.ball_radius;
    // The ball as point milling places it: pushed out of every face nearer than its radius
    // (a facetted flank's neighbouring facets lean a few degrees off the root point's).
    let centre = place(p).ok_or(NotSwarf::Refused {
        at,
        why: "the ball does not fit".into(),
    })?;
    // The flank's normal at the ball's contact with this blade (in the corner the ball
    // touches the hub as well, as near).
    let n = surface
        .closest_where(&centre, 2.0 * r, on_blade)
        .and_then(|c| (centre - c.point).try_normalize(1e-12))
        .unwrap_or(p.normal);
    let up = rising(&p.point);
    let across = up - n * n.dot(&up);
    if across.norm() < 0.3 {
        return Err(NotSwarf::NotAFlank { at });
    }
    let u = across.normalize();
    let w = n.cross(&u);
    // The axis toward the point `length` up the line at angle `phi` in the tangent plane,
    // brought onto the surface the ball's centre keeps (a radius off the part): the line
    // then meets the flank's offset at both ends, whatever the tangent plane's error (a
    // drafted flank leans its rulings toward the normal).
    let axis_at = |phi: f64, length: f64| {
        let mut axis = u * phi.cos() + w * phi.sin();
        for _ in 0..2 {
            let q = centre + axis * length;
            let Some(near) = surface.closest(&q, 2.0 * r) else {
                break;
            };
            let Some(out) = (q - near.point).try_normalize(1e-12) else {
                break;
            };
            match (near.point + out * r - centre).try_normalize(1e-12) {
                Some(a) => axis = a,
                None => break,
            }
        }
        axis
    };
    let worst = |phi: f64, length: f64| {
        deviations(surface, on_blade, &centre, &axis_at(phi, length), length, r)
            .iter()
            .map(|(_, d, _)| d.abs())
            .fold(0.0, f64::max)
    };
    // Over the shortest flank first, then over the flank that axis finds, while it grows.
    // Where the flank is nearly flat many lines keep within the tolerance: the one nearest
    // the rising direction is taken (the first within half the tolerance, walking out from
    // it a degree at a time), so neighbouring rulings agree; where none is, the least
    // deviation (a coarse scan, then golden section in the best cell).
    let reach = options.flutes_above_ball;
    let (mut best, mut baseline) = (0.0, MIN_FLANK);
    let mut length = MIN_FLANK;
    for _ in 0..4 {
        let admissible = (0..=WALK_STEPS)
            .flat_map(|k| [k, -k])
            .map(|k| f64::from(k) * (SEARCH_DEG / f64::from(WALK_STEPS)).to_radians())
            .find(|&phi| worst(phi, length) <= 0.5 * options.tolerance);
        let found = admissible.unwrap_or_else(|| {
            let step = SCAN_STEP_DEG.to_radians();
            let cells = (2.0 * SEARCH_DEG / SCAN_STEP_DEG).round() as i32;
            let mut scan = (0.0, f64::INFINITY);
            for k in 0..=cells {
                let phi = -SEARCH_DEG.to_radians() + step * f64::from(k);
                let c = worst(phi, length);
                if c < scan.1 {
                    scan = (phi, c);
                }
            }
            golden_section(&|phi| worst(phi, length), scan.0 - step, scan.0 + step)
        });
        let found_length = flank_length(
            &deviations(
                surface,
                on_blade,
                &centre,
                &axis_at(found, length),
                reach,
                r,
            ),
            options.tolerance,
        );
        if found_length < length && length > MIN_FLANK {
            break;
        }
        (best, baseline) = (found, length);
        if found_length <= length {
            break;
        }
        length = found_length;
    }
    let mut axis = axis_at(best, baseline);
    let mut samples = deviations(surface, on_blade, &centre, &axis, reach, r);
    let mut length = flank_length(&samples, options.tolerance);
    if let Some(snap) = options.snap_to
        && angle_between(&axis, &snap).to_degrees() <= SNAP_DEG
    {
        let snapped = deviations(surface, on_blade, &centre, &snap, reach, r);
        let snapped_length = flank_length(&snapped, 0.5 * options.tolerance);
        if snapped_length + SAMPLE_STEP >= length {
            (axis, samples, length) = (snap, snapped, snapped_length);
        }
    }
    if samples.last().is_some_and(|(s, _, _)| *s <= length) {
        return Err(NotSwarf::TallerThanFlutes { at });
    }
    if length < MIN_FLANK {
        let deviation_mm = samples
            .iter()
            .take_while(|(s, _, _)| *s <= MIN_FLANK)
            .map(|(_, d, _)| d.abs())
            .fold(0.0, f64::max);
        return Err(NotSwarf::NotRuled { deviation_mm, at });
    }
    // Above the flank the flutes may leave material but not gouge.
    if let Some((s, d, _)) = samples.iter().find(|(_, d, _)| *d < -options.tolerance) {
        return Err(NotSwarf::Refused {
            at,
            why: format!("the flutes gouge {:.4} mm at {s:.2} mm up the axis", -d),
        });
    }
    let deviation = samples
        .iter()
        .take_while(|(s, _, _)| *s <= length)
        .map(|(_, d, _)| d.abs())
        .fold(0.0, f64::max);
    Ok(Ruling {
        contact: *p,
        centre,
        axis,
        deviation,
        flank_length: length,
    })
}

/// The least of `f` in `[lo, hi]` (taken single-troughed there), to 0.618¹⁶ of the width.
fn golden_section(f: &dyn Fn(f64) -> f64, mut lo: f64, mut hi: f64) -> f64 {
    let ratio = 0.5 * (5f64.sqrt() - 1.0);
    let (mut x1, mut x2) = (hi - ratio * (hi - lo), lo + ratio * (hi - lo));
    let (mut f1, mut f2) = (f(x1), f(x2));
    for _ in 0..16 {
        if f1 <= f2 {
            (hi, x2, f2) = (x2, x1, f1);
            x1 = hi - ratio * (hi - lo);
            f1 = f(x1);
        } else {
            (lo, x1, f1) = (x1, x2, f2);
            x2 = lo + ratio * (hi - lo);
            f2 = f(x2);
        }
    }
    if f1 <= f2 { x1 } else { x2 }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::fixtures::{box_between, joined};
    use crate::mesh::{Mesh, plane_section};

    const R: f64 = 2.0;
    const TOLERANCE: f64 = 0.01;

    fn options() -> SwarfOptions {
        SwarfOptions {
            ball_radius: R,
            flutes_above_ball: 8.0,
            tolerance: TOLERANCE,
            max_step: 1.0,
            max_axis_turn_deg: 5.0,
            snap_to: None,
        }
    }

    /// A plate (top at z = 0) with a blade standing on it, 20 × 2 × 8 mm, its x ends leaned
    /// by `lean` (x grows with z by tan(lean)): the long flanks are planes, the ends ruled
    /// along the leaning direction. The blade's triangles come after the plate's 12.
    fn plate_and_blade(lean: f64) -> Mesh {
        let mut blade = box_between(Point3::new(-10.0, -1.0, -1.0), Point3::new(10.0, 1.0, 8.0));
        for p in &mut blade.positions {
            p.x += p.z * lean.tan();
        }
        joined([
            box_between(
                Point3::new(-30.0, -30.0, -5.0),
                Point3::new(30.0, 30.0, 0.0),
            ),
            blade,
        ])
    }

    /// The root loop: the blade's section a ball's radius (and a hair) above the plate.
    fn root(mesh: &Mesh) -> SectionCurve {
        let blade = Mesh::compacted(&mesh.positions, mesh.triangles[12..].iter().copied());
        let normals: Vec<Vector3> = (0..blade.triangles.len())
            .map(|t| blade.face_normal(t))
            .collect();
        plane_section(&blade, &normals, &Vector3::z(), R + 0.5 * TOLERANCE)
            .into_iter()
            .next()
            .expect("one loop round the blade")
    }

    /// Brute force over every triangle: the least distance from the flute axis of `ruling`
    /// (sampled every 0.02 mm from the ball's centre up `length`) to the part.
    fn flute_distance(mesh: &Mesh, ruling: &Ruling, length: f64) -> f64 {
        let steps = (length / 0.02).ceil() as usize;
        (0..=steps)
            .map(|k| ruling.centre + ruling.axis * (length * k as f64 / steps as f64))
            .map(|q| {
                (0..mesh.triangles.len())
                    .map(|t| {
                        let [a, b, c] = mesh.corners(t);
                        (q - crate::geom::closest_point_on_triangle(&q, &a, &b, &c).0).norm()
                    })
                    .fold(f64::INFINITY, f64::min)
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// The ball a radius out along the normal, pushed away from whatever is nearer than
    /// that (the plate, under a leaning end's root).
    fn push_out(surface: &SurfaceDistance, p: &DrivePoint) -> Option<Point3> {
        let mut centre = p.point + p.normal * R;
        for _ in 0..32 {
            let Some(near) = surface.closest(&centre, R - 1e-12) else {
                break;
            };
            centre = near.point + (centre - near.point).try_normalize(1e-12)? * R;
        }
        Some(centre)
    }

    fn run(mesh: &Mesh, options: &SwarfOptions) -> SwarfPlan {
        let surface = SurfaceDistance::new(mesh);
        swarf_runs(
            &surface,
            &|t| t >= 12,
            &|_| Vector3::z(),
            &|p| push_out(&surface, p),
            &|_| Ok(()),
            &root(mesh),
            options,
        )
        .expect("a root loop")
    }

    /// Every run's ball centres step on along the root and never turn the travel back.
    fn assert_forward(plan: &SwarfPlan) {
        for run in &plan.runs {
            let mut centres: Vec<Point3> = run.rulings.iter().map(|g| g.centre).collect();
            if run.closed {
                centres.push(centres[0]);
            }
            for w in centres.windows(3) {
                let (before, step) = (w[1] - w[0], w[2] - w[1]);
                assert!(before.norm() >= MIN_STEP && step.norm() >= MIN_STEP);
                assert!(
                    step.dot(&before) >= 0.0,
                    "{step:?} turns back after {before:?}"
                );
            }
        }
    }

    /// A ruling standing on the −y flank of `plate_and_blade(0.0)`, the ball's centre at `x`
    /// along it, the root point at `root_x`.
    fn flank_ruling(x: f64, root_x: f64, axis: Vector3) -> Ruling {
        let z = R + 0.5 * TOLERANCE;
        Ruling {
            contact: DrivePoint {
                point: Point3::new(root_x, -1.0, z),
                normal: -Vector3::y(),
            },
            centre: Point3::new(x, -1.0 - R, z),
            axis,
            deviation: 0.0,
            flank_length: 6.0,
        }
    }

    #[test]
    fn a_ruling_whose_centre_steps_back_is_dropped_and_the_move_over_it_checked() {
        let mesh = plate_and_blade(0.0);
        let surface = SurfaceDistance::new(&mesh);
        let up = Vector3::z();
        // The fourth ball sits 0.03 mm behind the third on the same root point (a facets'
        // crease, each face's normal giving its own ball), the fifth 0.05 mm behind although
        // its root point is ahead.
        let at = [
            (0.0, 0.0),
            (0.5, 0.5),
            (1.0, 1.0),
            (0.97, 1.0),
            (0.95, 1.25),
            (1.5, 1.5),
            (2.0, 2.0),
        ];
        let rulings: Vec<Ruling> = at
            .iter()
            .map(|&(x, root)| flank_ruling(x, root, up))
            .collect();
        let run = SwarfRun {
            rulings: rulings.clone(),
            closed: false,
        };
        let (runs, dropped) = forward_runs(&surface, run, &options());
        assert_eq!(dropped, 2);
        assert_eq!(runs.len(), 1);
        let xs: Vec<f64> = runs[0].rulings.iter().map(|g| g.centre.x).collect();
        assert_eq!(xs, [0.0, 0.5, 1.0, 1.5, 2.0]);

        // At a run's start, where there is no step before to judge by, the root's direction
        // (its points ahead and behind, not the shared one) says the second ball is behind.
        let starting: Vec<Ruling> = [(0.0, 0.0), (-0.02, 0.0), (0.5, 0.5), (1.0, 1.0)]
            .iter()
            .map(|&(x, root)| flank_ruling(x, root, up))
            .collect();
        let (runs, dropped) = forward_runs(
            &surface,
            SwarfRun {
                rulings: starting,
                closed: false,
            },
            &options(),
        );
        assert_eq!(dropped, 1);
        let xs: Vec<f64> = runs[0].rulings.iter().map(|g| g.centre.x).collect();
        assert_eq!(xs, [0.0, 0.5, 1.0]);

        // Where the axis turns more than allowed across the gap, the run is split there.
        let tilted = Vector3::new(0.0, -(10f64.to_radians().sin()), 10f64.to_radians().cos());
        let mut turning = rulings;
        turning.push(flank_ruling(2.5, 2.5, up));
        for g in &mut turning[5..] {
            g.axis = tilted;
        }
        let (runs, dropped) = forward_runs(
            &surface,
            SwarfRun {
                rulings: turning,
                closed: false,
            },
            &options(),
        );
        assert_eq!(dropped, 2);
        let xs: Vec<Vec<f64>> = runs
            .iter()
            .map(|run| run.rulings.iter().map(|g| g.centre.x).collect())
            .collect();
        assert_eq!(xs, [vec![0.0, 0.5, 1.0], vec![1.5, 2.0, 2.5]]);
    }

    #[test]
    fn an_upright_blade_is_swarfed_in_one_closed_run_along_its_height() {
        let mesh = plate_and_blade(0.0);
        let plan = run(&mesh, &options());
        assert_forward(&plan);
        assert_eq!(plan.runs.len(), 1, "refused: {:?}", plan.refused);
        assert!(plan.runs[0].closed);
        assert!(plan.refused.is_empty(), "{:?}", plan.refused);
        for ruling in plan.rulings() {
            assert!(ruling.axis.z > 1.0 - 1e-6, "axis {:?}", ruling.axis);
            // The flank reaches from the ball's centre (z = 2) to the top (z = 8).
            assert!(
                (ruling.flank_length - 6.0).abs() <= SAMPLE_STEP + TOLERANCE,
                "flank {}",
                ruling.flank_length
            );
            let d = flute_distance(&mesh, ruling, ruling.flank_length);
            assert!((d - R).abs() <= TOLERANCE, "flutes {d} from the part");
        }
        // Every point of the long flanks between the ball's equator and the top is swept.
        for x in [-9.5, -3.3, 0.0, 4.1, 9.5] {
            for z in [2.1, 4.0, 6.5, 7.9] {
                for y in [-1.0, 1.0] {
                    let p = Point3::new(x, y, z);
                    assert!(plan.sweeps(&p, R + TOLERANCE, 0.0), "{p:?} not swept");
                }
            }
        }
    }

    #[test]
    fn leaning_ends_get_leaning_rulings_and_the_flutes_keep_the_tolerance() {
        let lean = 12f64.to_radians();
        let mesh = plate_and_blade(lean);
        let plan = run(&mesh, &options());
        assert!(!plan.runs.is_empty(), "refused: {:?}", plan.refused);
        assert_forward(&plan);
        let leaning = Vector3::new(lean.sin(), 0.0, lean.cos());
        let mut on_ends = 0;
        for ruling in plan.rulings() {
            // Nothing gouges, by an independent brute-force distance up the whole flutes.
            let d = flute_distance(&mesh, ruling, options().flutes_above_ball);
            assert!(d >= R - TOLERANCE - 1e-9, "flutes {d} from the part");
            assert!(ruling.deviation <= TOLERANCE);
            // On the +x end, square to the plate's rise the wall leans: the ruling with it.
            if ruling.contact.normal.x > 0.9 {
                on_ends += 1;
                let off = angle_between(&ruling.axis, &leaning).to_degrees();
                assert!(off < 0.5, "ruling {off}° off the leaning end");
            }
        }
        assert!(
            on_ends > 0,
            "no ruling on the leaning end: {:?}",
            plan.refused
        );
    }

    /// `SwarfPlan::sweeps` without its box test: every interpolated axis measured.
    fn sweeps_by_every_axis(plan: &SwarfPlan, p: &Point3, radius: f64, below: f64) -> bool {
        plan.runs.iter().any(|run| {
            let n = run.rulings.len();
            let pairs = if run.closed { n } else { n - 1 };
            (0..pairs).any(|i| {
                let (a, b) = (&run.rulings[i], &run.rulings[(i + 1) % n]);
                (0..=8).any(|k| {
                    let t = k as f64 / 8.0;
                    let centre = a.centre + (b.centre - a.centre) * t;
                    let axis = (a.axis * (1.0 - t) + b.axis * t).normalize();
                    let length = a.flank_length + (b.flank_length - a.flank_length) * t;
                    let (from, to) = (centre - axis * below, centre + axis * length);
                    (p - closest_point_on_segment(p, &from, &to)).norm() <= radius
                })
            })
        })
    }

    #[test]
    fn the_box_test_of_sweeps_leaves_out_only_axes_too_far_to_sweep() {
        // Leaning ends: the rulings' axes turn between neighbours there.
        let mesh = plate_and_blade(20f64.to_radians());
        let plan = run(&mesh, &options());
        assert!(!plan.runs.is_empty(), "refused: {:?}", plan.refused);
        let mut random = crate::geom::SeededRandom::new(7);
        let (mut swept, mut not) = (0, 0);
        for _ in 0..4000 {
            let p = Point3::new(
                random.range(-16.0, 16.0),
                random.range(-5.0, 5.0),
                random.range(-1.0, 10.0),
            );
            let radius = random.range(0.5, 2.5);
            let below = random.range(0.0, 2.5);
            let expected = sweeps_by_every_axis(&plan, &p, radius, below);
            assert_eq!(
                plan.sweeps(&p, radius, below),
                expected,
                "{p:?} r {radius} below {below}"
            );
            if expected { swept += 1 } else { not += 1 }
        }
        // Both answers came up often enough to mean something.
        assert!(swept > 400 && not > 400, "swept {swept}, not {not}");
    }

    #[test]
    fn a_blade_taller_than_the_flutes_is_refused() {
        let mesh = plate_and_blade(0.0);
        let short = SwarfOptions {
            flutes_above_ball: 4.0,
            ..options()
        };
        let plan = run(&mesh, &short);
        assert!(plan.runs.is_empty());
        assert!(
            plan.refused
                .iter()
                .all(|why| matches!(why, NotSwarf::TallerThanFlutes { .. })),
            "{:?}",
            plan.refused
        );
    }
}
