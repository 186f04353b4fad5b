//! A cutter sliding across its own axis, in closed form.
//!
//! Every layer move of fixed-axis roughing keeps the axis and travels square to it, its
//! descents and retracts travel along it, and flat and bull-nose mills have a cylindrical core: a solid cylinder of radius `a` between heights
//! `h₀` and `h₁`, thickened by the corner radius `ρ` (0 for a flat end). The general hull of
//! [`super::convex`] is exact for such a step but costs two GJK ray casts a line; for the lines
//! of a grid along or across the axis the swept solid has closed forms:
//!
//! * A line **along the axis** at distance `r` from the axis meets the body over heights
//!   `[h₀ − Δ(r), h₁ + Δ(r)]` with `Δ = ρ` for `r ≤ a` and `√(ρ² − (r − a)²)` up to `a + ρ`.
//!   `Δ` never grows with `r`, so over the slide the intervals are nested and their union is
//!   the one at the least distance: the distance from the line to the tip's segment. A move
//!   along the axis by `δ` stretches that interval by `δ`.
//! * A line **across the axis** stays at one height `h` of the body, whose section there is a
//!   disc of radius `a + ρ` (or `a + √(ρ² − (h₀ − h)²)` on the corner, likewise at the top).
//!   The slide sweeps that disc along the tip's segment lifted to `h`: a stadium, the section of
//!   the capsule around that segment, whose line interval is closed form
//!   ([`super::sweep::line_capsule`]).
//!
//! Lines at other angles to the axis fall back to the hull.

use super::convex::{HullOfTwo, RevolvedBody};
use super::sweep::{LineInterval, line_capsule};
use crate::geom::{Aabb, Point3, Vector3};

/// Below this, a line's direction counts as along (or across) the axis: the intervals then
/// move by at most this times the body's size, far below a µm.
const ALIGNED: f64 = 1e-12;

/// A revolved body with a cylindrical core, moved from one tip to another without turning:
/// square to its axis, along it, or (as a step of a ramp) across by `across` and then along
/// by `lift`.
#[derive(Clone, Debug, PartialEq)]
pub struct Slide {
    /// The body swept along the step's chord, for lines at other angles to the axis.
    hull: HullOfTwo,
    /// A box holding the body at the four corners of the travel's rectangle.
    bounds: Aabb,
    from: Point3,
    /// The tip's travel square to the axis.
    across: Vector3,
    /// The tip's travel along the axis.
    lift: f64,
    axis: Vector3,
    h0: f64,
    h1: f64,
    core: f64,
    round: f64,
}

impl Slide {
    /// The slide of a body from `from` to `to`, when it is an exact one: the same axis (to
    /// round-off), a cylindrical core, and travel either square to the axis or along it (to
    /// 1 nm).
    pub fn of(from: &RevolvedBody, to: &RevolvedBody) -> Option<Slide> {
        let travel = to.tip - from.tip;
        let lift = travel.dot(&from.axis);
        let across = travel - lift * from.axis;
        if lift.abs() > 1e-9 && across.norm() > 1e-9 {
            return None;
        }
        Slide::steps(from, to, f64::INFINITY).and_then(|mut steps| steps.pop())
    }

    /// A move of a body from `from` to `to` without turning its axis, as slides: one when it
    /// travels square to the axis or along it; a ramp in steps, each sweeping the body over
    /// the rectangle of its travel across and along the axis rather than the chord, which
    /// holds the chord's sweep and exceeds it by at most the rectangle's far corner's distance
    /// from the chord, `|across|·|lift| / |travel|`, kept within `tolerance`. `None` when the
    /// body is not a cylindrical core or the axis turns.
    pub fn steps(from: &RevolvedBody, to: &RevolvedBody, tolerance: f64) -> Option<Vec<Slide>> {
        let k = from.axis;
        let same_axis = (to.axis - k).norm() <= ALIGNED;
        let cylinder = from.r0 == from.r1 && from.h0 <= from.h1;
        let same_body = (from.h0, from.r0, from.h1, from.r1, from.round)
            == (to.h0, to.r0, to.h1, to.r1, to.round);
        if !(same_axis && cylinder && same_body) {
            return None;
        }
        let travel = to.tip - from.tip;
        let mut lift = travel.dot(&k);
        let mut across = travel - lift * k;
        if lift.abs() <= 1e-9 {
            (across, lift) = (travel, 0.0);
        } else if across.norm() <= 1e-9 {
            across = Vector3::zeros();
        }
        let excess = across.norm() * lift.abs() / travel.norm().max(1e-300);
        let count = if excess <= tolerance.max(0.0) {
            1
        } else {
            ((excess / tolerance).ceil() as usize).clamp(1, 100_000)
        };
        let at = |tip: Point3| RevolvedBody { tip, ..*from };
        Some(
            (0..count)
                .map(|i| {
                    let (t0, t1) = (i as f64 / count as f64, (i + 1) as f64 / count as f64);
                    let (start, end) = (from.tip + t0 * travel, from.tip + t1 * travel);
                    let (across, lift) = (across / count as f64, lift / count as f64);
                    let mut bounds = at(start).bounds();
                    for corner in [start + across, start + lift * k, end] {
                        let b = at(corner).bounds();
                        bounds.grow(&b.min);
                        bounds.grow(&b.max);
                    }
                    Slide {
                        hull: HullOfTwo::new(at(start), at(end)),
                        bounds,
                        from: start,
                        across,
                        lift,
                        axis: k,
                        h0: from.h0,
                        h1: from.h1,
                        core: from.r0,
                        round: from.round,
                    }
                })
                .collect(),
        )
    }

    /// How far past the core's ends the body reaches at distance `r` from the axis.
    fn reach_beyond_ends(&self, r: f64) -> Option<f64> {
        if r <= self.core {
            Some(self.round)
        } else {
            let off = r - self.core;
            (off <= self.round).then(|| (self.round * self.round - off * off).max(0.0).sqrt())
        }
    }

    /// The widest section of the body at heights `low..=high` above the tip: its radius.
    fn section_radius(&self, low: f64, high: f64) -> Option<f64> {
        let beyond = if high < self.h0 {
            self.h0 - high
        } else if low > self.h1 {
            low - self.h1
        } else {
            0.0
        };
        (beyond <= self.round)
            .then(|| self.core + (self.round * self.round - beyond * beyond).max(0.0).sqrt())
    }

    fn along_axis(&self, axis: usize, p: &Point3) -> Option<(f64, f64)> {
        // The line's and the segment's points with the line's own coordinate dropped: the
        // plane square to the axis, where the distance is taken.
        let mut v = p - self.from;
        v[axis] = 0.0;
        let mut w = self.across;
        w[axis] = 0.0;
        let ww = w.norm_squared();
        let s = if ww > 0.0 {
            (v.dot(&w) / ww).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let r = (v - s * w).norm();
        let reach = self.reach_beyond_ends(r)?;
        let (low, high) = (
            self.h0 - reach + self.lift.min(0.0),
            self.h1 + reach + self.lift.max(0.0),
        );
        let (a, b) = (
            self.from[axis] + low * self.axis[axis],
            self.from[axis] + high * self.axis[axis],
        );
        Some((a.min(b), a.max(b)))
    }

    fn across_axis(&self, axis: usize, p: &Point3) -> Option<(f64, f64)> {
        let mut on_line = *p;
        on_line[axis] = self.from[axis];
        let h = (on_line - self.from).dot(&self.axis);
        let radius = self.section_radius(h - self.lift.max(0.0), h - self.lift.min(0.0))?;
        let centre = self.from + h * self.axis;
        line_capsule(axis, p, &centre, &(centre + self.across), radius)
    }
}

impl LineInterval for Slide {
    fn bounds(&self) -> Aabb {
        self.bounds
    }

    fn line_interval(&self, axis: usize, p: &Point3) -> Option<(f64, f64)> {
        let along = self.axis[axis].abs();
        if along >= 1.0 - ALIGNED {
            self.along_axis(axis, p)
        } else if along <= ALIGNED {
            self.across_axis(axis, p)
        } else {
            self.hull.line_interval(axis, p)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn body(tip: Point3, axis: Vector3, core: f64, round: f64, top: f64) -> RevolvedBody {
        RevolvedBody {
            tip,
            axis,
            h0: round,
            r0: core,
            h1: top,
            r1: core,
            round,
        }
    }

    /// Two unit vectors square to each other, from two angles.
    fn frame(theta: f64, phi: f64, twist: f64) -> (Vector3, Vector3) {
        let k = Vector3::new(
            theta.sin() * phi.cos(),
            theta.sin() * phi.sin(),
            theta.cos(),
        );
        let helper = if k.x.abs() < 0.9 {
            Vector3::x()
        } else {
            Vector3::y()
        };
        let u = k.cross(&helper).normalize();
        let v = k.cross(&u);
        (k, twist.cos() * u + twist.sin() * v)
    }

    fn compare(slide: &Slide, hull: &HullOfTwo, axis: usize, p: &Point3) {
        let closed = slide.line_interval(axis, p);
        let cast = hull.line_interval(axis, p);
        match (closed, cast) {
            // The ray cast stops short of the surface by up to 0.1 µm (seen: 104 nm on the end
            // disc of a stadium, checked by hand; the closed form is exact to round-off).
            (Some(a), Some(b)) => {
                assert!(
                    (a.0 - b.0).abs() < 5e-4 && (a.1 - b.1).abs() < 5e-4,
                    "axis {axis} line {p:?}: closed {a:?}, hull {b:?}"
                );
            }
            // A line grazing the solid may go either way by round-off: the chord one of them
            // finds must then be tiny.
            (Some((t0, t1)), None) | (None, Some((t0, t1))) => {
                assert!(
                    t1 - t0 < 1e-3,
                    "axis {axis} line {p:?}: only one finds {t0}..{t1}"
                );
            }
            (None, None) => {}
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]

        /// On lines along and across an axis along each grid direction, for moves square to
        /// the axis and along it (up or down), the closed forms give the GJK ray cast's
        /// interval of the same hull, for flat ends (ρ = 0) and bull-noses.
        #[test]
        fn closed_forms_agree_with_the_ray_cast_hull(
            axis_index in 0usize..3, flip in any::<bool>(), plunge in any::<bool>(),
            core in 0.0..6.0f64, round in prop_oneof![Just(0.0), 0.2..3.0f64],
            top in 4.0..25.0f64, length in 0.0..20.0f64, twist in 0.0..6.3f64,
            x in -12.0..12.0f64, y in -12.0..12.0f64, z in -8.0..30.0f64,
        ) {
            prop_assume!(core + round > 0.1);
            let mut k = Vector3::zeros();
            k[axis_index] = if flip { -1.0 } else { 1.0 };
            let (mut u, mut v) = (Vector3::zeros(), Vector3::zeros());
            u[(axis_index + 1) % 3] = 1.0;
            v[(axis_index + 2) % 3] = 1.0;
            let across = twist.cos() * u + twist.sin() * v;
            let tip = Point3::new(0.3, -0.7, 1.1);
            let from = body(tip, k, core, round, top.max(round));
            let travel = if plunge { (length - 10.0) * k } else { length * across };
            let to = body(tip + travel, k, core, round, top.max(round));
            let slide = Slide::of(&from, &to).expect("a slide");
            let hull = HullOfTwo::new(from, to);
            let p = Point3::new(x, y, z);
            for axis in 0..3 {
                compare(&slide, &hull, axis, &p);
            }
        }

        /// An axis oblique to every grid direction goes to the hull on every line, and a move
        /// with travel along the axis, or a turning axis, is not a slide.
        #[test]
        fn oblique_axes_fall_back_and_other_moves_are_not_slides(
            theta in 0.2..1.3f64, phi in 0.2..1.3f64, twist in 0.0..6.3f64,
            x in -12.0..12.0f64, y in -12.0..12.0f64, z in -8.0..30.0f64,
        ) {
            let (k, across) = frame(theta, phi, twist);
            let tip = Point3::new(1.0, 2.0, 3.0);
            let from = body(tip, k, 4.0, 1.0, 20.0);
            let to = body(tip + 7.0 * across, k, 4.0, 1.0, 20.0);
            let slide = Slide::of(&from, &to).expect("a slide");
            let hull = HullOfTwo::new(from, to);
            for axis in 0..3 {
                compare(&slide, &hull, axis, &Point3::new(x, y, z));
            }
            let lifted = body(tip + 7.0 * across + 0.5 * k, k, 4.0, 1.0, 20.0);
            prop_assert!(Slide::of(&from, &lifted).is_none());
            let turned = RevolvedBody { axis: (k + 0.01 * across).normalize(), ..to };
            prop_assert!(Slide::of(&from, &turned).is_none());
        }
    }

    /// Distance from `q` to the solid cylinder of `body` (before its rounding).
    fn distance_to_core(body: &RevolvedBody, q: &Point3) -> f64 {
        let y = q - body.tip;
        let h = y.dot(&body.axis);
        let r = (y - h * body.axis).norm();
        let dr = (r - body.r0).max(0.0);
        let dh = (body.h0 - h).max(h - body.h1).max(0.0);
        dr.hypot(dh)
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]

        /// A ramp's steps hold the body swept along the chord (their intervals cover the hull's
        /// on every grid line) and exceed it by no more than the tolerance: every end of every
        /// step's interval lies within the tolerance of the body at some point of the chord,
        /// found by brute force over the chord.
        #[test]
        fn ramp_steps_hold_the_chord_sweep_within_the_tolerance(
            axis_index in 0usize..3, round in prop_oneof![Just(0.0), 0.5..2.0f64],
            run in 0.5..15.0f64, rise in -4.0..4.0f64, twist in 0.0..6.3f64,
            tolerance in 0.005..0.05f64,
            x in -10.0..10.0f64, y in -10.0..10.0f64, z in -6.0..20.0f64,
        ) {
            prop_assume!(rise.abs() > 0.01);
            let mut k = Vector3::zeros();
            k[axis_index] = 1.0;
            let (mut u, mut v) = (Vector3::zeros(), Vector3::zeros());
            u[(axis_index + 1) % 3] = 1.0;
            v[(axis_index + 2) % 3] = 1.0;
            let travel = run * (twist.cos() * u + twist.sin() * v) + rise * k;
            let tip = Point3::new(0.4, -0.3, 0.9);
            let from = body(tip, k, 3.0, round, 14.0);
            let to = body(tip + travel, k, 3.0, round, 14.0);
            let steps = Slide::steps(&from, &to, tolerance).expect("slides");
            let hull = HullOfTwo::new(from, to);
            let p = Point3::new(x, y, z);
            for axis in 0..3 {
                let mut covered: Option<(f64, f64)> = None;
                for step in &steps {
                    let Some((t0, t1)) = step.line_interval(axis, &p) else { continue };
                    covered = Some(covered.map_or((t0, t1), |(a, b)| (a.min(t0), b.max(t1))));
                    for t in [t0, t1] {
                        let mut q = p;
                        q[axis] = t;
                        let samples = 4000;
                        let nearest = (0..=samples)
                            .map(|i| {
                                let at = RevolvedBody {
                                    tip: tip + (i as f64 / samples as f64) * travel,
                                    ..from
                                };
                                distance_to_core(&at, &q)
                            })
                            .fold(f64::INFINITY, f64::min);
                        let slack = travel.norm() / samples as f64 + 1e-9;
                        prop_assert!(
                            nearest <= round + tolerance + slack,
                            "axis {axis}: end {t} of a step is {} off the chord's sweep",
                            nearest - round
                        );
                    }
                }
                if let Some((t0, t1)) = hull.line_interval(axis, &p) {
                    let (a, b) = covered.unwrap_or((f64::INFINITY, f64::NEG_INFINITY));
                    prop_assert!(a <= t0 + 5e-4 && b >= t1 - 5e-4, "axis {axis}: {a}..{b} misses {t0}..{t1}");
                }
            }
        }
    }

    /// A flat end mill of radius 3 sliding 10 mm along x with its axis up: a vertical line
    /// 4 mm off the path misses, one 2 mm off meets the whole flute length; a horizontal line
    /// across the path at mid-height meets the stadium over its width 2·3, and a line along
    /// the path over the path plus both radii.
    #[test]
    fn a_flat_end_slot_in_closed_form() {
        let from = body(Point3::origin(), Vector3::z(), 3.0, 0.0, 12.0);
        let to = RevolvedBody {
            tip: Point3::new(10.0, 0.0, 0.0),
            ..from
        };
        let slide = Slide::of(&from, &to).expect("a slide");
        assert_eq!(slide.line_interval(2, &Point3::new(5.0, 4.0, 0.0)), None);
        assert_eq!(
            slide.line_interval(2, &Point3::new(5.0, 2.0, 0.0)),
            Some((0.0, 12.0))
        );
        let (a, b) = slide.line_interval(1, &Point3::new(5.0, 0.0, 6.0)).unwrap();
        assert!((a + 3.0).abs() < 1e-12 && (b - 3.0).abs() < 1e-12);
        let (a, b) = slide.line_interval(0, &Point3::new(0.0, 0.0, 6.0)).unwrap();
        assert!((a + 3.0).abs() < 1e-12 && (b - 13.0).abs() < 1e-12);
        assert_eq!(slide.line_interval(0, &Point3::new(0.0, 0.0, 12.5)), None);
    }
}
