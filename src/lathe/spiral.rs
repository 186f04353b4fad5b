//! The spiral slow-tool-servo program: the nose centre follows an Archimedean spiral from the
//! rim to the centre (`r = R − f θ / 2π`, `f` the feed per revolution) while `Z` follows the
//! compensated surface, on a lathe whose spindle is a C axis.
//!
//! A control interpolates `X` (radius), `Z` and `C` linearly between two blocks; `r` is linear
//! in `θ` on the spiral, so the interpolated path lies exactly on the spiral in plan and only
//! `Z` leaves the compensated surface between points. Points are therefore spaced by the
//! form tolerance: each block is the longest angular step (up to a cap) whose linear `Z`
//! stays, at every quarter of the step, within half the tolerance of the exact nose centre
//! (measured along the surface normal). Every centre is solved exactly, as the grid's are.
//!
//! Feeds are written in inverse time (`G93`): a block's time follows from the spindle speed,
//! constant (rpm) or from a constant surface speed capped by a maximum rpm.

use super::compensate::{Contact, ContactError, nose_centre};
use super::surface::LensSurface;

/// Spindle speed of the turning.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum SpindleSpeed {
    /// Constant revolutions per minute.
    ConstantRpm(f64),
    /// Constant surface speed (m/min) at the nose, the spindle capped at `max_rpm`.
    ConstantSurfaceSpeed {
        /// Surface speed, m/min.
        metres_per_minute: f64,
        /// Highest spindle speed, rpm.
        max_rpm: f64,
    },
}

impl SpindleSpeed {
    /// Spindle speed (rpm) with the nose at radius `r` (mm).
    pub fn rpm_at(&self, r: f64) -> f64 {
        match *self {
            SpindleSpeed::ConstantRpm(rpm) => rpm,
            SpindleSpeed::ConstantSurfaceSpeed {
                metres_per_minute,
                max_rpm,
            } => {
                let circumference_m = std::f64::consts::TAU * r / 1000.0;
                if circumference_m <= 0.0 {
                    max_rpm
                } else {
                    (metres_per_minute / circumference_m).min(max_rpm)
                }
            }
        }
    }
}

/// The spiral's parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpiralOptions {
    /// Nose radius ρ (mm).
    pub nose_radius: f64,
    /// Radius the spiral starts at (mm).
    pub outer_radius: f64,
    /// Radial feed per revolution (mm).
    pub feed_per_rev: f64,
    /// Form tolerance between points (mm).
    pub form_tolerance: f64,
    /// Largest angular step between points (radians).
    pub max_step: f64,
    /// Spindle speed.
    pub speed: SpindleSpeed,
}

/// One programmed point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpiralPoint {
    /// Radius of the nose centre, `X` (mm).
    pub radius: f64,
    /// Angle, continuous from 0 (radians), `C`.
    pub angle: f64,
    /// Nose-centre height, `Z` (mm).
    pub z: f64,
    /// Time of the block ending here (s).
    pub block_seconds: f64,
}

/// The spiral program's points and what making them took.
#[derive(Clone, Debug, PartialEq)]
pub struct Spiral {
    /// Points from the rim to the centre.
    pub points: Vec<SpiralPoint>,
    /// Revolutions.
    pub revolutions: f64,
    /// Exact solves made (points and the checks between them).
    pub solves: usize,
    /// Largest deviation met at the quarter points of accepted blocks (mm, along the normal).
    pub largest_planned_deviation: f64,
    /// Cutting time (s).
    pub seconds: f64,
}

/// Why a spiral cannot be made.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SpiralError {
    /// A parameter out of range.
    #[error("{0}")]
    Parameter(String),
    /// A point of the spiral has no nose centre.
    #[error("spiral point at r = {radius:.4} mm, θ = {angle_degrees:.3}°: {reason}")]
    Point {
        /// Its radius.
        radius: f64,
        /// Its angle modulo 360°.
        angle_degrees: f64,
        /// Why.
        reason: ContactError,
    },
    /// The tolerance cannot be met with steps above the floor.
    #[error(
        "the form tolerance {tolerance} mm needs steps below {min_step_degrees:.2e}° at r = \
         {radius:.4} mm: loosen the tolerance"
    )]
    ToleranceUnreachable {
        /// The tolerance.
        tolerance: f64,
        /// The smallest step tried.
        min_step_degrees: f64,
        /// Where.
        radius: f64,
    },
}

/// Smallest angular step tried before the tolerance is called unreachable.
const MIN_STEP: f64 = 1e-7;

/// The spiral program over `surface`.
pub fn spiral(surface: &LensSurface, options: &SpiralOptions) -> Result<Spiral, SpiralError> {
    let o = options;
    let positive = |v: f64| v.is_finite() && v > 0.0;
    if !positive(o.outer_radius) || !positive(o.feed_per_rev) || !positive(o.form_tolerance) {
        return Err(SpiralError::Parameter(format!(
            "outer radius {}, feed per revolution {}, form tolerance {}: all must be positive",
            o.outer_radius, o.feed_per_rev, o.form_tolerance
        )));
    }
    if !(positive(o.max_step) && o.max_step <= std::f64::consts::PI) {
        return Err(SpiralError::Parameter(format!(
            "largest angular step {}°: must be in (0°, 180°]",
            o.max_step.to_degrees()
        )));
    }
    let rpm_ok = match o.speed {
        SpindleSpeed::ConstantRpm(rpm) => positive(rpm),
        SpindleSpeed::ConstantSurfaceSpeed {
            metres_per_minute,
            max_rpm,
        } => positive(metres_per_minute) && positive(max_rpm),
    };
    if !rpm_ok {
        return Err(SpiralError::Parameter(format!(
            "spindle speed {:?}: must be positive",
            o.speed
        )));
    }
    let revolutions = o.outer_radius / o.feed_per_rev;
    if revolutions > 1e6 {
        return Err(SpiralError::Parameter(format!(
            "{revolutions:.0} revolutions: feed per revolution {} is too fine for radius {}",
            o.feed_per_rev, o.outer_radius
        )));
    }
    // Every step is at most `max_step`, so at least this many points: refuse a program no
    // control would take before computing it.
    let fewest_points = revolutions * std::f64::consts::TAU / o.max_step;
    if fewest_points > 5e7 {
        return Err(SpiralError::Parameter(format!(
            "at least {fewest_points:.0} program points ({revolutions:.0} turns at up to {:.3}° a \
             step): raise the feed per revolution or the largest step",
            o.max_step.to_degrees()
        )));
    }
    let end = std::f64::consts::TAU * revolutions;
    let radius_at =
        |angle: f64| (o.outer_radius - o.feed_per_rev * angle / std::f64::consts::TAU).max(0.0);
    let mut solves = 0usize;
    let mut solve = |angle: f64, guess: (f64, f64)| -> Result<Contact, SpiralError> {
        solves += 1;
        let r = radius_at(angle);
        let line = (r * angle.cos(), r * angle.sin());
        nose_centre(surface, o.nose_radius, line, guess)
            .or_else(|_| {
                let below = surface.parameters_over(line.0, line.1).unwrap_or(guess);
                nose_centre(surface, o.nose_radius, line, below)
            })
            .map_err(|reason| SpiralError::Point {
                radius: r,
                angle_degrees: angle.to_degrees().rem_euclid(360.0),
                reason,
            })
    };
    let start_line = (o.outer_radius, 0.0);
    let guess = surface
        .parameters_over(start_line.0, start_line.1)
        .ok_or(SpiralError::Point {
            radius: o.outer_radius,
            angle_degrees: 0.0,
            reason: ContactError::OffSurface {
                x: start_line.0,
                y: start_line.1,
            },
        })?;
    let mut here = solve(0.0, guess)?;
    let mut angle = 0.0;
    let mut points = vec![SpiralPoint {
        radius: o.outer_radius,
        angle: 0.0,
        z: here.centre.z,
        block_seconds: 0.0,
    }];
    let half = 0.5 * o.form_tolerance;
    let mut step = o.max_step;
    let mut largest = 0.0f64;
    let mut seconds = 0.0;
    while angle < end {
        let (next_angle, next, deviation) = loop {
            let to = (angle + step).min(end);
            let there = solve(to, here.parameters)?;
            let mut worst = 0.0f64;
            let mut guess = here.parameters;
            for q in 1..4 {
                let t = f64::from(q) / 4.0;
                let mid = solve(angle + (to - angle) * t, guess)?;
                guess = mid.parameters;
                let linear = here.centre.z + (there.centre.z - here.centre.z) * t;
                worst = worst.max((mid.centre.z - linear).abs() * mid.normal.z);
                if worst > half {
                    break;
                }
            }
            if worst <= half {
                break (to, there, worst);
            }
            step *= 0.5;
            if step < MIN_STEP {
                return Err(SpiralError::ToleranceUnreachable {
                    tolerance: o.form_tolerance,
                    min_step_degrees: MIN_STEP.to_degrees(),
                    radius: radius_at(angle),
                });
            }
        };
        largest = largest.max(deviation);
        let mid_radius = radius_at(0.5 * (angle + next_angle));
        let block_seconds =
            (next_angle - angle) / std::f64::consts::TAU * 60.0 / o.speed.rpm_at(mid_radius);
        seconds += block_seconds;
        points.push(SpiralPoint {
            radius: radius_at(next_angle),
            angle: next_angle,
            z: next.centre.z,
            block_seconds,
        });
        angle = next_angle;
        here = next;
        step = (step * 1.5).min(o.max_step);
    }
    Ok(Spiral {
        points,
        revolutions,
        solves,
        largest_planned_deviation: largest,
        seconds,
    })
}

/// How a spiral is written as G-code.
#[derive(Clone, Debug, PartialEq)]
pub struct PostOptions {
    /// Height the tool approaches and leaves at (mm, above the lens).
    pub clearance_z: f64,
    /// Feed of the plunge to the first point (mm/min).
    pub plunge_feed: f64,
    /// Comment lines for the header (without parentheses).
    pub header: Vec<String>,
}

/// Decimal places of X and Z (1 nm) and of C (1e-6°).
const LENGTH_DECIMALS: usize = 6;
const ANGLE_DECIMALS: usize = 6;

/// The program text: metric, absolute, radius `X`, continuous `C` in degrees, feed blocks in
/// inverse time.
pub fn post(spiral: &Spiral, options: &PostOptions) -> String {
    use std::fmt::Write;
    let mut out = String::with_capacity(spiral.points.len() * 48 + 512);
    out.push_str("%\n");
    for line in &options.header {
        let clean: String = line.chars().filter(|c| *c != '(' && *c != ')').collect();
        let _ = writeln!(out, "({clean})");
    }
    out.push_str(
        "(X: nose-centre radius, mm; Z: nose-centre height, mm; C: workpiece angle, degrees, continuous)\n",
    );
    out.push_str("G21 G90 G94 G40\n");
    let (l, a) = (LENGTH_DECIMALS, ANGLE_DECIMALS);
    let Some(first) = spiral.points.first() else {
        out.push_str("M30\n%\n");
        return out;
    };
    let _ = writeln!(out, "G0 Z{:.l$}", options.clearance_z);
    let _ = writeln!(
        out,
        "G0 X{:.l$} C{:.a$}",
        first.radius,
        first.angle.to_degrees()
    );
    let _ = writeln!(out, "G1 Z{:.l$} F{:.1}", first.z, options.plunge_feed);
    out.push_str("G93\n");
    for p in &spiral.points[1..] {
        // Inverse time: F = 1 / (block minutes).
        let inverse_minutes = 60.0 / p.block_seconds.max(1e-9);
        let _ = writeln!(
            out,
            "G1 X{:.l$} Z{:.l$} C{:.a$} F{:.3}",
            p.radius,
            p.z,
            p.angle.to_degrees(),
            inverse_minutes
        );
    }
    out.push_str("G94\n");
    let _ = writeln!(out, "G0 Z{:.l$}", options.clearance_z);
    out.push_str("M30\n%\n");
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lathe::check::check_program;
    use crate::lathe::surface::SagShape;

    fn toric() -> LensSurface {
        LensSurface::Sag {
            shape: SagShape::Toric {
                curvature_x: 1.0 / 60.0,
                curvature_y: 1.0 / 45.0,
                conic_y: 0.0,
            },
            aperture: 12.0,
        }
    }

    /// A toric face is not turnable by a circle at constant Z: the spiral's Z swings twice per
    /// turn, and the posted, rounded program stays within the tolerance when interpolated.
    #[test]
    fn toric_spiral_meets_its_form_tolerance_as_posted() {
        let surface = toric();
        let options = SpiralOptions {
            nose_radius: 0.5,
            outer_radius: 5.0,
            feed_per_rev: 0.25,
            form_tolerance: 2e-4,
            max_step: 10f64.to_radians(),
            speed: SpindleSpeed::ConstantRpm(600.0),
        };
        let s = spiral(&surface, &options).unwrap();
        assert!((s.revolutions - 20.0).abs() < 1e-12);
        let last = s.points.last().unwrap();
        assert!(last.radius.abs() < 1e-12);
        assert!((last.angle - std::f64::consts::TAU * 20.0).abs() < 1e-9);
        // Every block at 600 rpm: 20 turns take 2 s.
        assert!((s.seconds - 2.0).abs() < 1e-9, "{}", s.seconds);
        let program = post(
            &s,
            &PostOptions {
                clearance_z: 2.0,
                plunge_feed: 50.0,
                header: vec!["test (toric)".into()],
            },
        );
        let (check, _) = check_program(&surface, 0.5, &program, 8).unwrap();
        assert_eq!(check.blocks, s.points.len());
        let c = check.interpolated;
        assert_eq!(c.no_foot, 0);
        assert_eq!(c.wrong_side, 0);
        assert!(c.max_error <= 2e-4, "{c:?}");
        // The tolerance is used, not wasted: the points are spaced to it.
        assert!(c.max_error > 2e-5, "{c:?}");
        // Halving the tolerance adds points.
        let finer = spiral(
            &surface,
            &SpiralOptions {
                form_tolerance: 1e-4,
                ..options
            },
        )
        .unwrap();
        assert!(finer.points.len() > s.points.len());
    }

    #[test]
    fn a_program_too_long_for_any_control_is_refused_before_it_is_computed() {
        let options = SpiralOptions {
            nose_radius: 0.5,
            outer_radius: 20.0,
            feed_per_rev: 1e-4,
            form_tolerance: 1e-4,
            max_step: 0.1f64.to_radians(),
            speed: SpindleSpeed::ConstantRpm(300.0),
        };
        match spiral(&toric(), &options) {
            Err(SpiralError::Parameter(message)) => {
                assert!(message.contains("program points"), "{message}")
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn constant_surface_speed_caps_at_the_centre() {
        let speed = SpindleSpeed::ConstantSurfaceSpeed {
            metres_per_minute: 100.0,
            max_rpm: 2000.0,
        };
        assert!((speed.rpm_at(10.0) - 100.0 / (std::f64::consts::TAU * 0.01)).abs() < 1e-9);
        assert_eq!(speed.rpm_at(0.0), 2000.0);
        assert_eq!(speed.rpm_at(1e-3), 2000.0);
    }
}
