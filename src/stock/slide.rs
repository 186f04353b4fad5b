//! A cutter sliding across its own axis, in closed form.
//!
//! Every layer move of fixed-axis roughing keeps the axis and travels square to it, and flat
//! and bull-nose mills have a cylindrical core: a solid cylinder of radius `a` between heights
//! `h₀` and `h₁`, thickened by the corner radius `ρ` (0 for a flat end). The general hull of
//! [`super::convex`] is exact for such a step but costs two GJK ray casts a line; for the lines
//! of a grid along or across the axis the swept solid has closed forms:
//!
//! * A line **along the axis** at distance `r` from the axis meets the body over heights
//!   `[h₀ − Δ(r), h₁ + Δ(r)]` with `Δ = ρ` for `r ≤ a` and `√(ρ² − (r − a)²)` up to `a + ρ`.
//!   `Δ` never grows with `r`, so over the slide the intervals are nested and their union is
//!   the one at the least distance: the distance from the line to the tip's segment.
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

/// A revolved body with a cylindrical core, moved from one tip to another square to its axis.
#[derive(Clone, Debug, PartialEq)]
pub struct Slide {
    /// The same solid for lines at other angles to the axis (and its box).
    hull: HullOfTwo,
    from: Point3,
    to: Point3,
    axis: Vector3,
    h0: f64,
    h1: f64,
    core: f64,
    round: f64,
}

impl Slide {
    /// The slide of a body from `from` to `to`, when it is one: the same axis (to round-off),
    /// a cylindrical core, and no travel along the axis (to 1 nm).
    pub fn of(from: &RevolvedBody, to: &RevolvedBody) -> Option<Slide> {
        let k = from.axis;
        let same_axis = (to.axis - k).norm() <= ALIGNED;
        let cylinder = from.r0 == from.r1 && from.h0 <= from.h1;
        let same_body = (from.h0, from.r0, from.h1, from.r1, from.round)
            == (to.h0, to.r0, to.h1, to.r1, to.round);
        let square = (to.tip - from.tip).dot(&k).abs() <= 1e-9;
        (same_axis && cylinder && same_body && square).then(|| Slide {
            hull: HullOfTwo::new(*from, *to),
            from: from.tip,
            to: to.tip,
            axis: k,
            h0: from.h0,
            h1: from.h1,
            core: from.r0,
            round: from.round,
        })
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

    /// The radius of the body's section at height `h` above the tip.
    fn section_radius(&self, h: f64) -> Option<f64> {
        let beyond = if h < self.h0 {
            self.h0 - h
        } else if h > self.h1 {
            h - self.h1
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
        let mut w = self.to - self.from;
        w[axis] = 0.0;
        let ww = w.norm_squared();
        let s = if ww > 0.0 {
            (v.dot(&w) / ww).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let r = (v - s * w).norm();
        let reach = self.reach_beyond_ends(r)?;
        let (low, high) = (self.h0 - reach, self.h1 + reach);
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
        let radius = self.section_radius(h)?;
        line_capsule(
            axis,
            p,
            &(self.from + h * self.axis),
            &(self.to + h * self.axis),
            radius,
        )
    }
}

impl LineInterval for Slide {
    fn bounds(&self) -> Aabb {
        self.hull.bounds()
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
            // The ray cast stops short of the surface by up to tens of nm (seen: 30 nm on a
            // cylinder where the closed form is exact to round-off).
            (Some(a), Some(b)) => {
                assert!(
                    (a.0 - b.0).abs() < 1e-4 && (a.1 - b.1).abs() < 1e-4,
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

        /// On lines along, across and (through the fallback) oblique to a grid-aligned axis,
        /// and for an axis along each grid direction, the closed forms give the GJK ray cast's
        /// interval of the same hull, for flat ends (ρ = 0) and bull-noses.
        #[test]
        fn closed_forms_agree_with_the_ray_cast_hull(
            axis_index in 0usize..3, flip in any::<bool>(),
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
            let to = body(tip + length * across, k, core, round, top.max(round));
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
