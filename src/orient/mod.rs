//! Tool-axis choice at a contact point (DESIGN.md §3.6; seed 004 fig. 1.4 for lead and tilt).
//!
//! The preferred axis is the surface normal turned by the lead angle toward the feed direction
//! and by the tilt angle across it. Candidates are cones of directions around it, ordered by
//! how far they turn from the preferred axis and from the previous point's axis (smoothness).
//! The first candidate that the machine can reach, whose axis ray escapes the part, and whose
//! shank and holder clear the part exactly, wins. Visibility maps (issue 5) will replace the
//! ray screening; the exact body test stays the last word. `smooth` then evens the chosen
//! axes along each pass (bounded turn per mm), keeping every axis valid.

mod smooth;
mod turn;

pub use smooth::{SmoothingOptions, SmoothingStats, smooth_axes};
pub use turn::AxisTurn;

use crate::access::RayScene;
use crate::collide::{Collision, PartCollider, PreparedTool};
use crate::geom::ToolPose;
use crate::geom::{Direction, Point3, Vector3, angle_between, orthonormal_frame};

/// How axes are searched.
#[derive(Clone, Debug, PartialEq)]
pub struct AxisOptions {
    /// Lead angle, degrees: the axis leans toward the feed direction (positive) or away.
    pub lead_deg: f64,
    /// Tilt angle, degrees: the axis leans to the left of the feed direction.
    pub tilt_deg: f64,
    /// Largest angle, degrees, the axis may turn away from the preferred one.
    pub max_deviation_deg: f64,
    /// Angular spacing of the candidate cones, degrees.
    pub step_deg: f64,
    /// Weight of turning away from the previous point's axis, against turning away from the
    /// preferred one.
    pub smoothness_weight: f64,
    /// At most this many candidates get the exact (expensive) body test per point.
    pub max_exact_tests: usize,
    /// Angular clearance, degrees: an axis is preferred when the four axes this far from it
    /// (across and along its turn from the preferred axis) are valid too, so that small changes
    /// (smoothing, interpolation between poses, the real holder's tolerances) keep it valid.
    /// Candidates are taken in order of cost as before; the first valid one with that clearance
    /// wins, and if none of the first `clearance_tries` valid ones has it, the first valid one
    /// (on the border of the valid set). 0 takes the first valid candidate.
    pub clearance_deg: f64,
    /// Valid candidates checked for clearance per point before falling back. Default 4.
    pub clearance_tries: usize,
}

impl Default for AxisOptions {
    fn default() -> Self {
        Self {
            lead_deg: 10.0,
            tilt_deg: 0.0,
            max_deviation_deg: 70.0,
            step_deg: 5.0,
            smoothness_weight: 1.0,
            max_exact_tests: 48,
            clearance_deg: 3.0,
            clearance_tries: 4,
        }
    }
}

/// Candidate offsets around a preferred axis: `(angle from it, unit vector in a frame whose
/// z is the preferred axis)`, cone by cone.
pub struct AxisChooser {
    cones: Vec<(f64, Vector3)>,
    options: AxisOptions,
    /// A finer search where this one finds no axis ([`Self::with_fine_fallback`]).
    fallback: Option<Box<AxisChooser>>,
}

/// Why no axis was found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NoAxis {
    /// Every candidate was outside the machine's reach.
    MachineLimits,
    /// Every reachable candidate's axis ray hits the part.
    Occluded,
    /// Candidates passed the ray test but the shank or holder collides.
    Collision,
    /// Every candidate brings the tool too close to the machine table.
    Table,
    /// Candidates cleared the part, but the shank or holder would touch the material the
    /// operations before left.
    Material,
}

/// The preferred axis at a contact point (unit normal `normal`, feed direction `feed`).
pub fn preferred_axis(normal: &Vector3, feed: &Vector3, lead_deg: f64, tilt_deg: f64) -> Vector3 {
    let f = feed - normal * normal.dot(feed);
    let f = if f.norm() > 1e-12 {
        f.normalize()
    } else {
        orthonormal_frame(normal).0
    };
    let side = normal.cross(&f);
    let (l, t) = (lead_deg.to_radians(), tilt_deg.to_radians());
    (normal * (l.cos() * t.cos()) + f * l.sin() + side * (l.cos() * t.sin())).normalize()
}

/// `axis` leaned away from the machine's `pole` (the rotary axis the tool must not stand
/// near: there the other rotary axis swings half a turn for a small change of the tool axis)
/// to at least `min_tilt_deg`, toward `outward` (unit, square to the pole): fully within the
/// tilt, not at all beyond twice it, blended between so the change is continuous.
pub fn away_from_pole(
    axis: &Vector3,
    pole: &Vector3,
    outward: &Vector3,
    min_tilt_deg: f64,
) -> Vector3 {
    let s0 = min_tilt_deg.to_radians().sin();
    let along = pole * pole.dot(axis);
    let across = axis - along;
    let tilt = across.norm();
    let weight = ((2.0 * s0 - tilt) / s0).clamp(0.0, 1.0);
    let missing = (s0 - across.dot(outward)).max(0.0);
    (along + across + outward * (weight * missing))
        .try_normalize(1e-12)
        .unwrap_or(*axis)
}

/// Whether a ball-end tool with its ball centred at `centre` can stand along unit `axis`: the
/// machine reaches the axis, the axis ray escapes the part (cheap, screens most candidates),
/// and the flutes, shank and holder clear the part (exact test, the last word).
pub fn axis_is_valid(
    part: &PartCollider,
    rays: &RayScene,
    tool: &PreparedTool,
    centre: &Point3,
    axis: &Vector3,
    reachable: &dyn Fn(&Vector3) -> bool,
) -> Result<(), NoAxis> {
    if !reachable(axis) {
        return Err(NoAxis::MachineLimits);
    }
    let r = tool.ball_radius;
    // The ray starts inside the ball, half a radius up the axis, so it does not see the face
    // the ball touches; it runs as far as the tool reaches.
    if !rays.escapes(&(centre + axis * (0.5 * r)), axis, tool.reach) {
        return Err(NoAxis::Occluded);
    }
    let pose = ToolPose {
        tip: centre - axis * r,
        axis: Direction::new_unchecked(*axis),
    };
    part.check_bodies(tool, &pose).map_err(|c| match c {
        Collision::Table => NoAxis::Table,
        Collision::Material { .. } => NoAxis::Material,
        _ => NoAxis::Collision,
    })
}

impl AxisChooser {
    pub fn new(options: AxisOptions) -> Self {
        let mut cones = vec![(0.0, Vector3::z())];
        let step = options.step_deg.max(0.5);
        let mut angle = step;
        while angle <= options.max_deviation_deg + 1e-9 {
            let a = angle.to_radians();
            let count = ((2.0 * std::f64::consts::PI * a.sin()) / step.to_radians())
                .round()
                .max(6.0) as usize;
            for k in 0..count {
                let phi = 2.0 * std::f64::consts::PI * k as f64 / count as f64;
                cones.push((
                    a,
                    Vector3::new(a.sin() * phi.cos(), a.sin() * phi.sin(), a.cos()),
                ));
            }
            angle += step;
        }
        Self {
            cones,
            options,
            fallback: None,
        }
    }

    /// This chooser, searching again with cones `step_deg` apart and up to `max_exact_tests`
    /// exact tests where its own search finds no axis. An axis may stand in a window narrower
    /// than the cones' spacing, or farther out than the exact tests' cap reaches (the sample
    /// impeller's leading edge by the hub's nose: 5° cones and 48 tests find nothing, 2°
    /// cones and 600 tests find it, 200 do not). Where the coarse search succeeds the axis is
    /// the same, so a strategy's passes keep their axes; only points it gives up on cost more.
    pub fn with_fine_fallback(self, step_deg: f64, max_exact_tests: usize) -> Self {
        let fine = AxisChooser::new(AxisOptions {
            step_deg,
            max_exact_tests,
            ..self.options.clone()
        });
        Self {
            fallback: Some(Box::new(fine)),
            ..self
        }
    }

    pub fn options(&self) -> &AxisOptions {
        &self.options
    }

    /// Chooses the axis for a ball centred at `centre` touching the part at a point with unit
    /// normal `normal`, moving along `feed`.
    #[allow(clippy::too_many_arguments)]
    pub fn choose(
        &self,
        part: &PartCollider,
        rays: &RayScene,
        tool: &PreparedTool,
        centre: &Point3,
        normal: &Vector3,
        feed: &Vector3,
        previous: Option<&Vector3>,
        reachable: &dyn Fn(&Vector3) -> bool,
    ) -> Result<Direction, NoAxis> {
        let preferred = preferred_axis(normal, feed, self.options.lead_deg, self.options.tilt_deg);
        self.choose_around(part, rays, tool, centre, &preferred, previous, reachable)
    }

    /// Chooses the axis nearest `preferred` (a strategy's own, rather than the lead and tilt
    /// from the normal) for a ball centred at `centre`, as [`Self::choose`] does.
    #[allow(clippy::too_many_arguments)]
    pub fn choose_around(
        &self,
        part: &PartCollider,
        rays: &RayScene,
        tool: &PreparedTool,
        centre: &Point3,
        preferred: &Vector3,
        previous: Option<&Vector3>,
        reachable: &dyn Fn(&Vector3) -> bool,
    ) -> Result<Direction, NoAxis> {
        // The ball's lowest point is the same for every axis: below the table's margin no
        // axis can help, and trying them all (the part's underside) costs the most.
        if let Some(table) = part.table()
            && centre.z - tool.ball_radius < table.top_z + table.margin
        {
            return Err(NoAxis::Table);
        }
        let preferred = preferred.normalize();
        let (u, v) = orthonormal_frame(&preferred);
        let mut candidates: Vec<(f64, usize, Vector3)> = self
            .cones
            .iter()
            .enumerate()
            .map(|(i, (angle, local))| {
                let axis = (u * local.x + v * local.y + preferred * local.z).normalize();
                let turn = previous.map_or(0.0, |p| angle_between(p, &axis));
                (angle + self.options.smoothness_weight * turn, i, axis)
            })
            .collect();
        candidates.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let mut why = NoAxis::MachineLimits;
        let mut exact_tests = 0;
        let mut first_valid: Option<(f64, Vector3)> = None;
        let mut tried = 0;
        let delta = self.options.clearance_deg.to_radians();
        for (_, i, axis) in candidates {
            let angle = self.cones[i].0;
            // Past a valid axis without clearance, only candidates at least the clearance
            // angle further out can have it (the border runs between).
            if first_valid.is_some_and(|(a0, _)| angle < a0 + delta) {
                continue;
            }
            match axis_is_valid(part, rays, tool, centre, &axis, reachable) {
                Ok(()) => {
                    let clear = self.options.clearance_deg <= 0.0
                        || self
                            .has_clearance(part, rays, tool, centre, &preferred, &axis, reachable);
                    if clear {
                        return Ok(Direction::new_unchecked(axis));
                    }
                    if first_valid.is_none() {
                        // The border is most likely between this axis and the preferred one:
                        // first try the axis turned the clearance angle further out.
                        if let Some(further) = turned_away(&preferred, &axis, delta)
                            && angle + delta <= self.options.max_deviation_deg.to_radians()
                            && axis_is_valid(part, rays, tool, centre, &further, reachable).is_ok()
                            && self.has_clearance(
                                part, rays, tool, centre, &preferred, &further, reachable,
                            )
                        {
                            return Ok(Direction::new_normalize(further));
                        }
                    }
                    first_valid.get_or_insert((angle, axis));
                    tried += 1;
                    if tried >= self.options.clearance_tries {
                        break;
                    }
                }
                Err(NoAxis::MachineLimits) => {}
                Err(cheap @ (NoAxis::Occluded | NoAxis::Table)) => {
                    if why == NoAxis::MachineLimits
                        || (why == NoAxis::Occluded && cheap == NoAxis::Table)
                    {
                        why = cheap;
                    }
                }
                Err(exact @ (NoAxis::Collision | NoAxis::Material)) => {
                    // An axis that only the material blocks says more: the point opens up
                    // once that material comes off.
                    if why != NoAxis::Material {
                        why = exact;
                    }
                    exact_tests += 1;
                    if exact_tests >= self.options.max_exact_tests {
                        break;
                    }
                }
            }
        }
        match (first_valid, &self.fallback) {
            (Some((_, axis)), _) => Ok(Direction::new_unchecked(axis)),
            (None, Some(fine)) => {
                fine.choose_around(part, rays, tool, centre, &preferred, previous, reachable)
            }
            (None, None) => Err(why),
        }
    }
}

/// `axis` turned by `angle` (radians) further from `preferred`, along their great circle; `None`
/// when the two coincide.
fn turned_away(preferred: &Vector3, axis: &Vector3, angle: f64) -> Option<Vector3> {
    let about = preferred.cross(axis).try_normalize(1e-12)?;
    Some(nalgebra::Rotation3::from_axis_angle(&nalgebra::Unit::new_unchecked(about), angle) * axis)
}

impl AxisChooser {
    /// Whether the four axes `clearance_deg` from `axis` — toward and away from `preferred`,
    /// and to either side — are valid too (see [`AxisOptions::clearance_deg`]).
    #[allow(clippy::too_many_arguments)]
    fn has_clearance(
        &self,
        part: &PartCollider,
        rays: &RayScene,
        tool: &PreparedTool,
        centre: &Point3,
        preferred: &Vector3,
        axis: &Vector3,
        reachable: &dyn Fn(&Vector3) -> bool,
    ) -> bool {
        let delta = self.options.clearance_deg.to_radians();
        // Along the turn from the preferred axis, and across it; any frame at the preferred
        // axis itself.
        let along = (axis - preferred * preferred.dot(axis))
            .try_normalize(1e-9)
            .map(|w| {
                // The tangent at `axis` of the great circle from `preferred`.
                (w * axis.dot(preferred) - preferred * w.dot(axis))
                    .try_normalize(1e-12)
                    .unwrap_or(w)
            })
            .unwrap_or_else(|| orthonormal_frame(axis).0);
        let along = (along - axis * axis.dot(&along)).normalize();
        let across = axis.cross(&along);
        [along, -along, across, -across].iter().all(|w| {
            let probe = axis * delta.cos() + w * delta.sin();
            axis_is_valid(part, rays, tool, centre, &probe, reachable).is_ok()
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn preferred_axis_leans_by_the_lead_angle_toward_the_feed() {
        let n = Vector3::z();
        let f = Vector3::x();
        let a = preferred_axis(&n, &f, 10.0, 0.0);
        assert!((angle_between(&a, &n).to_degrees() - 10.0).abs() < 1e-9);
        assert!(a.x > 0.0 && a.y.abs() < 1e-12);
        let b = preferred_axis(&n, &f, 0.0, 15.0);
        assert!((angle_between(&b, &n).to_degrees() - 15.0).abs() < 1e-9);
        assert!(
            b.y > 0.0 && b.x.abs() < 1e-12,
            "tilt leans to the left of the feed"
        );
        // A feed direction not in the tangent plane is projected into it first.
        let c = preferred_axis(&n, &Vector3::new(1.0, 0.0, 5.0), 10.0, 0.0);
        assert!((c - a).norm() < 1e-12);
    }

    #[test]
    fn cones_cover_the_deviation_evenly() {
        let ch = AxisChooser::new(AxisOptions {
            step_deg: 5.0,
            max_deviation_deg: 30.0,
            ..Default::default()
        });
        // Every direction within 30° has a candidate within about one step.
        let mut worst: f64 = 0.0;
        for i in 0..200 {
            let th = (i as f64 / 200.0 * 30.0).to_radians();
            let ph = i as f64 * 2.399963;
            let d = Vector3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos());
            let best = ch
                .cones
                .iter()
                .map(|(_, c)| angle_between(c, &d))
                .fold(f64::INFINITY, f64::min);
            worst = worst.max(best.to_degrees());
        }
        assert!(worst < 5.0, "worst gap {worst}°");
    }

    /// A machine that holds the tool only within 2.2° of a direction between the 5° cones:
    /// the coarse search finds nothing, its finer fallback finds the window.
    #[test]
    fn the_fine_fallback_finds_a_window_between_the_coarse_cones() {
        let part = crate::mesh::fixtures::plate_and_wall(10.0, 90.0);
        let collider = PartCollider::new(&part).unwrap();
        let rays = RayScene::new(&part);
        let tool = crate::collide::tool_bodies::tests::prepared();
        let centre = Point3::new(30.0, 50.0, 13.0);
        let coarse = AxisChooser::new(AxisOptions {
            clearance_deg: 0.0,
            ..AxisOptions::default()
        });
        // Around the vertical the cones' frame is the vertical's; the direction at 7.5° off
        // it farthest from every cone.
        let (u, v) = orthonormal_frame(&Vector3::z());
        let cone_axes: Vec<Vector3> = coarse
            .cones
            .iter()
            .map(|(_, c)| u * c.x + v * c.y + Vector3::z() * c.z)
            .collect();
        let gap = |d: &Vector3| {
            cone_axes
                .iter()
                .map(|c| angle_between(c, d).to_degrees())
                .fold(f64::INFINITY, f64::min)
        };
        let window = (0..360)
            .map(|k| {
                let (tilt, turn) = (7.5_f64.to_radians(), (k as f64).to_radians());
                u * (tilt.sin() * turn.cos())
                    + v * (tilt.sin() * turn.sin())
                    + Vector3::z() * tilt.cos()
            })
            .max_by(|a, b| gap(a).total_cmp(&gap(b)))
            .unwrap();
        assert!(gap(&window) > 2.2, "{}", gap(&window));
        let machine = |a: &Vector3| angle_between(a, &window).to_degrees() < 2.2;
        let choose = |chooser: &AxisChooser| {
            chooser.choose_around(
                &collider,
                &rays,
                &tool,
                &centre,
                &Vector3::z(),
                None,
                &machine,
            )
        };
        assert_eq!(choose(&coarse), Err(NoAxis::MachineLimits));
        let fine = AxisChooser::new(coarse.options().clone()).with_fine_fallback(2.0, 1000);
        let axis = choose(&fine).unwrap().into_inner();
        assert!(machine(&axis));
    }

    /// A plate with a tall wall beside the point: the preferred axis (10° lead toward the wall)
    /// puts the holder into the wall, so the chosen axis turns away; with a clearance angle it
    /// turns that much further, and can then turn back part of the way and still be valid.
    #[test]
    fn a_clearance_angle_keeps_the_axis_off_the_border_of_the_valid_set() {
        let part = crate::mesh::fixtures::plate_and_wall(10.0, 60.0);
        let collider = PartCollider::new(&part).unwrap();
        let rays = RayScene::new(&part);
        let tool = crate::collide::tool_bodies::tests::prepared();
        let centre = Point3::new(50.0, 50.0, 13.0);
        let (normal, feed) = (Vector3::z(), Vector3::x());
        let anywhere = |_: &Vector3| true;
        let choose = |clearance_deg: f64| {
            // 1° cones: the first valid candidate is within 1° of the border.
            AxisChooser::new(AxisOptions {
                clearance_deg,
                step_deg: 1.0,
                max_exact_tests: 10_000,
                ..AxisOptions::default()
            })
            .choose(
                &collider, &rays, &tool, &centre, &normal, &feed, None, &anywhere,
            )
            .unwrap()
            .into_inner()
        };
        let preferred = preferred_axis(&normal, &feed, 10.0, 0.0);
        let valid =
            |a: &Vector3| axis_is_valid(&collider, &rays, &tool, &centre, a, &anywhere).is_ok();
        assert!(!valid(&preferred));
        let (border, clear) = (choose(0.0), choose(3.0));
        assert!(valid(&border) && valid(&clear));
        let turn = |a: &Vector3| angle_between(&preferred, a).to_degrees();
        assert!(
            turn(&clear) > turn(&border),
            "{} {}",
            turn(&clear),
            turn(&border)
        );
        // The border axis has an invalid axis within 3° toward the preferred one; the chosen
        // one does not: turned back by 3° it is still valid.
        assert!(!valid(&slerp_toward(&border, &preferred, 3.0)));
        assert!(valid(&slerp_toward(&clear, &preferred, 3.0)));
    }

    /// `from` turned toward `to` by `deg` degrees.
    fn slerp_toward(from: &Vector3, to: &Vector3, deg: f64) -> Vector3 {
        crate::geom::slerp(from, to, deg / angle_between(from, to).to_degrees())
    }
}
