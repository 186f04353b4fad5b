//! How the job's tolerance is spent between the stages that each move the ball centre off the
//! path the part allows.
//!
//! The promise of a plan is that the ball centre, along every block of the posted program as
//! the control interpolates it, stays at least `r − tolerance` from the part. Four things eat
//! into that tolerance, one after the other, so each gets its own share and the shares add up
//! to the whole:
//!
//! * **chord**: the planner joins poses by straight ball-centre moves and checks each whole
//!   chord against the part with this share;
//! * **linearisation**: the post inserts blocks until the control's joint-space interpolation
//!   keeps the ball centre this close to those chords;
//! * **rounding**: the printed decimals move the commanded joints by up to half a unit of the
//!   last decimal; at the ball centre's largest distance from the pivot that is
//!   `√3·δ_lin + 2·δ_rot·R` (computed, not chosen);
//! * **verification**: the back-simulation's own error bound, twice (a chord of a piece of
//!   the path may lie that far from it, and the bound is subtracted from what it measures).
//!
//! Linearisation gets what the other three leave.

use serde::Serialize;

use crate::error::JobError;
use crate::post::GcodeOptions;

/// The tolerance split (mm); `chord + linearisation + rounding + 2·verification = total`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ToleranceBudget {
    pub total_mm: f64,
    pub chord_mm: f64,
    pub linearisation_mm: f64,
    pub rounding_mm: f64,
    pub verification_mm: f64,
}

/// The planner's share of the tolerance.
const CHORD_SHARE: f64 = 0.5;
/// The back-simulation's error bound, as a share of the tolerance.
const VERIFICATION_SHARE: f64 = 0.01;
/// Linearisation needs at least this share to converge in a sensible number of blocks.
const MIN_LINEARISATION_SHARE: f64 = 0.1;

impl ToleranceBudget {
    /// Splits `total` for a program printed with `gcode`'s decimals, whose ball centre stays
    /// within `reach` mm of the rotary pivot. Refuses a tolerance the printed resolution
    /// cannot hold.
    pub fn split(total: f64, gcode: &GcodeOptions, reach: f64) -> Result<Self, JobError> {
        let (linear, angular_deg) = gcode.rounding();
        let rounding = 3f64.sqrt() * linear + 2.0 * angular_deg.to_radians() * reach;
        let chord = CHORD_SHARE * total;
        let verification = VERIFICATION_SHARE * total;
        let linearisation = total - chord - rounding - 2.0 * verification;
        if linearisation.is_nan() || linearisation < MIN_LINEARISATION_SHARE * total {
            return Err(JobError::Invalid {
                key: "strategy.tolerance".into(),
                reason: format!(
                    "= {total} mm is too small for the program's resolution: rounding {} linear \
                     / {} angular decimals alone moves the ball centre by up to {rounding:.6} mm \
                     at {reach:.1} mm from the pivot",
                    gcode.linear_decimals, gcode.angular_decimals
                ),
            });
        }
        Ok(ToleranceBudget {
            total_mm: total,
            chord_mm: chord,
            linearisation_mm: linearisation,
            rounding_mm: rounding,
            verification_mm: verification,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shares_add_up_to_the_tolerance_and_rounding_is_computed() {
        let b = ToleranceBudget::split(0.01, &GcodeOptions::default(), 100.0).unwrap();
        let sum = b.chord_mm + b.linearisation_mm + b.rounding_mm + 2.0 * b.verification_mm;
        assert!((sum - 0.01).abs() < 1e-15, "{b:?}");
        // 4 decimals: √3·0.00005 + 2·0.00005°·100 mm.
        let expected = 3f64.sqrt() * 5e-5 + 2.0 * 5e-5f64.to_radians() * 100.0;
        assert!((b.rounding_mm - expected).abs() < 1e-15);
    }

    #[test]
    fn a_tolerance_below_the_printed_resolution_is_refused() {
        let e = ToleranceBudget::split(0.0005, &GcodeOptions::default(), 100.0).unwrap_err();
        assert_eq!(e.key(), Some("strategy.tolerance"));
        assert!(e.to_string().contains("too small"), "{e}");
        assert!(ToleranceBudget::split(f64::NAN, &GcodeOptions::default(), 100.0).is_err());
    }
}
