//! How far the machine turns between two tool axes.
//!
//! The angle between two axes is what the tool sees; a machine turns its rotary axes. On a
//! machine whose outer rotary axis (a table-table machine's C) lies along the *pole*, with
//! the inner one (A) tilting the tool from it, an axis at tilt θ from the pole and azimuth φ
//! about it is reached at (A, C) = (θ, φ) or (−θ, φ + 180°), and a change of azimuth costs C
//! the full Δφ however small θ is: at 15° of tilt C turns four times as far as the tool. The
//! rotaries move together, so a move lasts as long as the larger of the two turns, on the
//! nearer branch:
//!
//! `turn = min( max(|θ₁ − θ₂|, |Δφ|), max(θ₁ + θ₂, |Δφ − 180°|) )` (Δφ wrapped to ±180°).
//!
//! Choosing and smoothing axes by this measure keeps C's rate as bounded as the tool's.

use std::f64::consts::PI;

use crate::geom::{Vector3, angle_between, orthonormal_frame, slerp};

/// How the turn between two unit tool axes is measured, radians.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum AxisTurn {
    /// The angle between them: what a machine without a singular axis turns.
    #[default]
    Angle,
    /// The larger of the two rotary axes' turns of a machine whose outer rotary axis lies
    /// along `pole` (unit, part frame), the inner one tilting the tool from it.
    Rotaries { pole: Vector3 },
}

/// An axis as (tilt from the pole, azimuth about it), radians.
#[derive(Clone, Copy, Debug)]
struct Polar {
    tilt: f64,
    azimuth: f64,
}

/// `a` wrapped into [−π, π].
fn wrap(a: f64) -> f64 {
    a - 2.0 * PI * (a / (2.0 * PI)).round()
}

/// The larger of a (tilt, azimuth) change's two turns.
fn larger((d_tilt, d_azimuth): (f64, f64)) -> f64 {
    d_tilt.abs().max(d_azimuth.abs())
}

impl AxisTurn {
    /// The turn from `a` to `b` (unit), radians.
    pub fn between(&self, a: &Vector3, b: &Vector3) -> f64 {
        match self {
            Self::Angle => angle_between(a, b),
            Self::Rotaries { pole } => {
                let (same, across) = branches(&polar(pole, a), &polar(pole, b));
                larger(same).min(larger(across))
            }
        }
    }

    /// `to` if it is within `max` (radians) of `from`, else the axis `max` of the way there,
    /// along the path the machine takes: the great circle for [`AxisTurn::Angle`], both
    /// rotary axes turning evenly on the nearer branch for [`AxisTurn::Rotaries`].
    pub fn toward(&self, from: &Vector3, to: &Vector3, max: f64) -> Vector3 {
        match self {
            Self::Angle => {
                let total = angle_between(from, to);
                if total <= max {
                    *to
                } else {
                    slerp(from, to, max / total)
                }
            }
            Self::Rotaries { pole } => {
                let p = polar(pole, from);
                let (same, across) = branches(&p, &polar(pole, to));
                let (change, total) = if larger(same) <= larger(across) {
                    (same, larger(same))
                } else {
                    (across, larger(across))
                };
                if total <= max {
                    return *to;
                }
                let t = max / total;
                // A negative tilt is the other branch: the same axis across the pole.
                from_polar(
                    pole,
                    &Polar {
                        tilt: p.tilt + t * change.0,
                        azimuth: p.azimuth + t * change.1,
                    },
                )
            }
        }
    }
}

/// The changes (tilt, azimuth) from `p` to `q` on the same branch, and to `q` reached across
/// the pole (tilt through zero, azimuth half a turn round).
fn branches(p: &Polar, q: &Polar) -> ((f64, f64), (f64, f64)) {
    (
        (q.tilt - p.tilt, wrap(q.azimuth - p.azimuth)),
        (-q.tilt - p.tilt, wrap(q.azimuth + PI - p.azimuth)),
    )
}

fn polar(pole: &Vector3, v: &Vector3) -> Polar {
    let (u, w) = orthonormal_frame(pole);
    Polar {
        tilt: angle_between(pole, v),
        azimuth: v.dot(&w).atan2(v.dot(&u)),
    }
}

fn from_polar(pole: &Vector3, p: &Polar) -> Vector3 {
    let (u, w) = orthonormal_frame(pole);
    let (s, c) = p.tilt.sin_cos();
    let (sa, ca) = p.azimuth.sin_cos();
    (pole * c + (u * ca + w * sa) * s).normalize()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn axis(tilt_deg: f64, azimuth_deg: f64) -> Vector3 {
        let (t, a) = (tilt_deg.to_radians(), azimuth_deg.to_radians());
        Vector3::new(t.sin() * a.cos(), t.sin() * a.sin(), t.cos())
    }

    fn rotaries() -> AxisTurn {
        AxisTurn::Rotaries { pole: Vector3::z() }
    }

    /// The table-table machine's turns, from its joints: A = ±tilt, C = azimuth (+180°).
    #[test]
    fn the_rotary_turn_is_the_larger_joint_turn_on_the_nearer_branch() {
        let deg = |r: f64| r.to_degrees();
        let m = rotaries();
        // 15° tilt, azimuth 0° → 20°: C turns 20° for a 5.2° turn of the tool.
        let (a, b) = (axis(15.0, 0.0), axis(15.0, 20.0));
        assert!((deg(m.between(&a, &b)) - 20.0).abs() < 1e-9);
        assert!(deg(AxisTurn::Angle.between(&a, &b)) < 5.3);
        // Tilt 30° → 40° at one azimuth: A alone.
        assert!((deg(m.between(&axis(30.0, 70.0), &axis(40.0, 70.0))) - 10.0).abs() < 1e-9);
        // Across the pole: 5° at azimuth 0 to 5° at azimuth 180 is A from 5 to −5, C still.
        assert!((deg(m.between(&axis(5.0, 0.0), &axis(5.0, 180.0))) - 10.0).abs() < 1e-9);
        // 5° at 0 to 5° at 100°: C turns 100° or, across the pole, 80° with A 10°.
        assert!((deg(m.between(&axis(5.0, 0.0), &axis(5.0, 100.0))) - 80.0).abs() < 1e-9);
        // Symmetric, zero on itself.
        let (p, q) = (axis(12.0, -40.0), axis(50.0, 130.0));
        assert!((m.between(&p, &q) - m.between(&q, &p)).abs() < 1e-12);
        assert!(m.between(&p, &p) < 1e-12);
        // The angle between the axes never exceeds the rotary turn.
        for (p, q) in [(p, q), (a, b), (axis(80.0, 10.0), axis(20.0, -170.0))] {
            assert!(AxisTurn::Angle.between(&p, &q) <= m.between(&p, &q) + 1e-12);
        }
    }

    #[test]
    fn turning_toward_moves_both_rotaries_evenly_by_at_most_the_step() {
        let m = rotaries();
        let (from, to) = (axis(15.0, 0.0), axis(25.0, 40.0));
        let step = 10f64.to_radians();
        let mid = m.toward(&from, &to, step);
        assert!((m.between(&from, &mid) - step).abs() < 1e-9);
        assert!((m.between(&mid, &to) - 3.0 * step).abs() < 1e-9);
        assert!(angle_between(&mid, &axis(17.5, 10.0)) < 1e-9, "{mid:?}");
        // Across the pole: the tilt runs through zero, the azimuth stays.
        let (from, to) = (axis(4.0, 30.0), axis(4.0, 210.0));
        let mid = m.toward(&from, &to, 4f64.to_radians());
        assert!(angle_between(&mid, &Vector3::z()) < 1e-9, "{mid:?}");
        // Within the step: the target itself.
        assert_eq!(m.toward(&from, &to, 1.0), to);
    }
}
