//! Whether any posture of the tool reaches a point of the part at all: for the scallop
//! measure, what stands over the target where none does (a bore narrower than the shank and
//! its margin, a wall's foot below the table's margin) is the tool's and the machine's, not
//! the passes'.
//!
//! A ball touching the part at p with outward normal n is centred at c = p + r·n, its lower
//! half toward p: the axis a has a·n ≥ 0. For the normal itself, the vertical (a deep slot's
//! floor or a bore's wall may leave no room to tilt off them) and each of a fixed set of
//! directions (a Fibonacci sphere) that the machine allows and that holds the ball so, the
//! tool's bodies above the ball are tested at points up the axis: a point of a body within
//! the body's radius and its margin of the part (the flutes: within their radius less the
//! scallop target, a cut beyond it) or any body below the table's margin rules the axis out.
//! Each such test is certain (the body holds a ball of that radius round the point); between
//! the points and between the directions nothing is claimed, so *blocked* means: none of
//! these directions reaches.
//! Nothing of how the moves were planned is used; the machine's limits are the caller's.

use crate::geom::{Point3, Vector3};
use crate::mesh::SurfaceDistance;
use crate::tool::{Body, BodyRole};

/// Distance between the points a body is tested at, up its axis, mm.
const STEP: f64 = 0.25;

/// The tool and machine a point must be reachable with.
pub struct ToolReach<'a> {
    /// The bodies above the tip (flutes, neck and shank, holder), as
    /// [`crate::tool::ToolAssembly::bodies`] gives them.
    pub bodies: Vec<Body>,
    pub shank_margin: f64,
    pub holder_margin: f64,
    /// The table's top (z in the part frame) and how far above it the tool must stay.
    pub table: Option<(f64, f64)>,
    /// Whether the machine can hold the tool along an axis (part frame).
    pub reachable: &'a (dyn Fn(&Vector3) -> bool + Sync),
    directions: Vec<Vector3>,
}

impl<'a> ToolReach<'a> {
    /// Tests `count` directions spread evenly over the sphere.
    pub fn new(
        bodies: Vec<Body>,
        shank_margin: f64,
        holder_margin: f64,
        table: Option<(f64, f64)>,
        reachable: &'a (dyn Fn(&Vector3) -> bool + Sync),
        count: usize,
    ) -> Self {
        Self {
            bodies,
            shank_margin,
            holder_margin,
            table,
            reachable,
            directions: fibonacci_sphere(count),
        }
    }

    /// Whether no direction of the set holds a ball of `radius` touching the part at `p`
    /// (outward normal `n`) with every body clear of the part by its margin and of the table.
    pub fn blocked(
        &self,
        distance: &SurfaceDistance,
        p: &Point3,
        n: &Vector3,
        radius: f64,
        target: f64,
    ) -> bool {
        let centre = p + n * radius;
        if let Some((top, margin)) = self.table
            && centre.z - radius < top + margin
        {
            // The ball itself comes within the table's margin, whatever the axis.
            return true;
        }
        let mut hint = None;
        // The normal and the vertical first (a floor's and a bore's own axes, which a
        // deep slot or bore leaves no room to tilt off), then the set.
        [*n, Vector3::z()]
            .iter()
            .chain(&self.directions)
            .all(|axis| {
                axis.dot(n) < 0.0
                    || !(self.reachable)(axis)
                    || !self.clear(distance, &centre, axis, radius, target, &mut hint)
            })
    }

    /// Whether no test rules out the tool along `axis` with its ball centred at `centre`.
    fn clear(
        &self,
        distance: &SurfaceDistance,
        centre: &Point3,
        axis: &Vector3,
        radius: f64,
        target: f64,
        hint: &mut Option<u32>,
    ) -> bool {
        let tip = centre - axis * radius;
        let sideways = (1.0 - axis.z * axis.z).max(0.0).sqrt();
        for body in &self.bodies {
            let margin = match body.role {
                BodyRole::Flutes => -target,
                BodyRole::Shank => self.shank_margin,
                BodyRole::Holder => self.holder_margin,
            };
            // Below the ball's centre is the ball, which touches the part by construction.
            let from = body.from.max(radius);
            if body.to <= from {
                continue;
            }
            let radius_at = |h: f64| {
                let t = if body.to > body.from {
                    (h - body.from) / (body.to - body.from)
                } else {
                    0.0
                };
                body.radius_from + (body.radius_to - body.radius_from) * t
            };
            if let Some((top, table_margin)) = self.table {
                let lowest = (tip + axis * from).z.min((tip + axis * body.to).z)
                    - radius_at(from).max(radius_at(body.to)) * sideways;
                if lowest < top + table_margin {
                    return false;
                }
            }
            let steps = ((body.to - from) / STEP).ceil().max(1.0) as usize;
            for k in 0..=steps {
                let h = from + (body.to - from) * k as f64 / steps as f64;
                let reach = radius_at(h) + margin;
                if reach > 0.0 && distance.any_within_from(&(tip + axis * h), reach, hint) {
                    return false;
                }
            }
        }
        true
    }
}

/// `count` unit vectors spread evenly over the sphere (golden-angle spiral).
fn fibonacci_sphere(count: usize) -> Vec<Vector3> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..count)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / count as f64;
            let ring = (1.0 - z * z).max(0.0).sqrt();
            let angle = golden * i as f64;
            Vector3::new(ring * angle.cos(), ring * angle.sin(), z)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::fixtures::{box_between, joined};

    const RADIUS: f64 = 2.0;

    /// A D4 ball on a D4 shank with a D12 holder 30 mm up.
    fn bodies() -> Vec<Body> {
        vec![
            Body {
                role: BodyRole::Flutes,
                from: RADIUS,
                to: 10.0,
                radius_from: RADIUS,
                radius_to: RADIUS,
            },
            Body {
                role: BodyRole::Shank,
                from: 10.0,
                to: 30.0,
                radius_from: 2.0,
                radius_to: 2.0,
            },
            Body {
                role: BodyRole::Holder,
                from: 30.0,
                to: 60.0,
                radius_from: 6.0,
                radius_to: 6.0,
            },
        ]
    }

    /// Two blocks on a floor (z ≤ 0) leaving a slot `width` wide and 20 deep between them.
    fn slot(width: f64) -> crate::mesh::Mesh {
        joined([
            box_between(
                Point3::new(-40.0, -40.0, -20.0),
                Point3::new(40.0, 40.0, 0.0),
            ),
            box_between(Point3::new(-40.0, -40.0, 0.0), Point3::new(0.0, 40.0, 20.0)),
            box_between(
                Point3::new(width, -40.0, 0.0),
                Point3::new(40.0 + width, 40.0, 20.0),
            ),
        ])
    }

    #[test]
    fn a_slot_the_shank_and_its_margin_do_not_fit_is_blocked_and_one_they_fit_is_not() {
        let any = |_: &Vector3| true;
        let reach = ToolReach::new(bodies(), 0.5, 2.0, None, &any, 600);
        // The floor of the slot in the middle, 20 mm down: the shank (radius 2 and 0.5 of
        // margin) must go down the slot to reach it.
        let floor = |width: f64| Point3::new(0.5 * width, 0.0, 0.0);
        let narrow = slot(4.6);
        let distance = SurfaceDistance::new(&narrow);
        assert!(reach.blocked(&distance, &floor(4.6), &Vector3::z(), RADIUS, 0.01));
        let wide = slot(5.4);
        let distance = SurfaceDistance::new(&wide);
        assert!(!reach.blocked(&distance, &floor(5.4), &Vector3::z(), RADIUS, 0.01));
        // Without the margin the narrow one's floor is reached straight down.
        let no_margin = ToolReach::new(bodies(), 0.0, 0.0, None, &any, 600);
        let distance = SurfaceDistance::new(&narrow);
        assert!(!no_margin.blocked(&distance, &floor(4.6), &Vector3::z(), RADIUS, 0.01));
    }

    #[test]
    fn the_machine_limits_and_the_table_block_what_the_part_does_not() {
        // A block's side 1 mm above the table: the ball must come from the side, its
        // underside within the table's margin of 2 mm.
        let part = box_between(Point3::new(0.0, 0.0, 0.0), Point3::new(20.0, 20.0, 20.0));
        let distance = SurfaceDistance::new(&part);
        let side = Point3::new(20.0, 10.0, 1.0);
        let any = |_: &Vector3| true;
        let free = ToolReach::new(bodies(), 0.5, 2.0, None, &any, 600);
        assert!(!free.blocked(&distance, &side, &Vector3::x(), RADIUS, 0.01));
        let tabled = ToolReach::new(bodies(), 0.5, 2.0, Some((0.0, 2.0)), &any, 600);
        assert!(tabled.blocked(&distance, &side, &Vector3::x(), RADIUS, 0.01));
        // High up the side the table is far: reached, even upright (the ball's equator on
        // the side), unless the machine holds the tool only leaning away from the side's
        // normal, where the ball would touch with its upper half.
        let high = Point3::new(20.0, 10.0, 15.0);
        assert!(!tabled.blocked(&distance, &high, &Vector3::x(), RADIUS, 0.01));
        let upright = |a: &Vector3| a.z >= 0.99;
        let limited = ToolReach::new(bodies(), 0.5, 2.0, Some((0.0, 2.0)), &upright, 600);
        assert!(!limited.blocked(&distance, &high, &Vector3::x(), RADIUS, 0.01));
        let away = |a: &Vector3| a.x <= -0.1;
        let limited = ToolReach::new(bodies(), 0.5, 2.0, Some((0.0, 2.0)), &away, 600);
        assert!(limited.blocked(&distance, &high, &Vector3::x(), RADIUS, 0.01));
    }
}
