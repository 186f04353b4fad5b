//! The cutting end of a tool as a profile of revolution: ball, flat, bull-nose (torus) and
//! tapered ball end mills. Heights are measured from the tip along the axis, radii from the
//! axis, both in millimetres.
//!
//! Every cutter here is "a disc of radius `flat_radius` at height `corner_radius`, grown by a
//! ball of radius `corner_radius`", capped below its flutes' top (APT's generalised cutter with
//! the cone only on the tapered ball): a ball has no flat part, a flat end mill no corner, a
//! bull-nose both. That one description gives the contact geometry of all four (where the tip
//! sits when the cutter touches a point with a given normal along a given axis) and the lowest
//! point of a tilted tool.

use serde::{Deserialize, Serialize};

use super::ToolError;
use crate::geom::{Point3, Vector3};

/// The cutting end of an end mill.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Cutter {
    /// Ball-end mill: a hemisphere of radius diameter/2 on a cylinder.
    Ball {
        /// Cutting diameter, mm.
        diameter: f64,
        /// Fluted length from the tip, mm (the cutting part; must be ≥ the radius).
        flute_length: f64,
    },
    /// Flat (square) end mill: a cylinder with a sharp bottom rim.
    Flat { diameter: f64, flute_length: f64 },
    /// Bull-nose (torus, corner-radius) end mill: a flat bottom of diameter
    /// `diameter − 2·corner_radius` rounded into the side by a quarter circle.
    BullNose {
        diameter: f64,
        /// Radius of the rounded corner, mm: 0 < corner_radius < diameter/2.
        corner_radius: f64,
        flute_length: f64,
    },
    /// Tapered ball-end mill: a ball of diameter `diameter` at the tip and a conical flank of
    /// half-angle `taper_deg` tangent to it, widening toward the shank (the impeller finisher:
    /// a small tip with a stiff body).
    TaperedBall {
        /// Diameter of the ball at the tip, mm.
        diameter: f64,
        /// Half-angle of the cone, degrees: 0 < taper_deg < 45.
        taper_deg: f64,
        flute_length: f64,
    },
}

impl Cutter {
    /// Diameter at the cutting end, mm: what "a D6 tool" means (for a tapered ball, the tip ball).
    pub fn diameter(&self) -> f64 {
        match *self {
            Cutter::Ball { diameter, .. }
            | Cutter::Flat { diameter, .. }
            | Cutter::BullNose { diameter, .. }
            | Cutter::TaperedBall { diameter, .. } => diameter,
        }
    }

    pub fn flute_length(&self) -> f64 {
        match *self {
            Cutter::Ball { flute_length, .. }
            | Cutter::Flat { flute_length, .. }
            | Cutter::BullNose { flute_length, .. }
            | Cutter::TaperedBall { flute_length, .. } => flute_length,
        }
    }

    /// Radius of the rounded corner that does the cutting near the tip: the ball radius for ball
    /// and tapered ball, the corner radius of a bull-nose, 0 for a flat end mill.
    pub fn corner_radius(&self) -> f64 {
        match *self {
            Cutter::Ball { diameter, .. } | Cutter::TaperedBall { diameter, .. } => diameter / 2.0,
            Cutter::Flat { .. } => 0.0,
            Cutter::BullNose { corner_radius, .. } => corner_radius,
        }
    }

    /// Radius of the flat bottom disc: diameter/2 − corner radius (0 for ball-ended cutters).
    pub fn flat_radius(&self) -> f64 {
        self.diameter() / 2.0 - self.corner_radius()
    }

    /// The ball radius of a ball-ended cutter (ball or tapered ball), `None` for flat and
    /// bull-nose end mills.
    pub fn ball_radius(&self) -> Option<f64> {
        match *self {
            Cutter::Ball { diameter, .. } | Cutter::TaperedBall { diameter, .. } => {
                Some(diameter / 2.0)
            }
            Cutter::Flat { .. } | Cutter::BullNose { .. } => None,
        }
    }

    /// Short name of the kind, as in tool specs and reports.
    pub fn kind(&self) -> &'static str {
        match self {
            Cutter::Ball { .. } => "ball",
            Cutter::Flat { .. } => "flat",
            Cutter::BullNose { .. } => "bull",
            Cutter::TaperedBall { .. } => "taper",
        }
    }

    /// Height above the tip where the rounded end meets the straight flank: the corner radius,
    /// or for a tapered ball the circle where the cone touches the ball, r·(1 − sin α).
    pub fn end_height(&self) -> f64 {
        match *self {
            Cutter::TaperedBall { taper_deg, .. } => {
                self.corner_radius() * (1.0 - taper_deg.to_radians().sin())
            }
            _ => self.corner_radius(),
        }
    }

    /// Radius of the cutter at height `h` above the tip (0 ≤ h ≤ flute length; the flank's
    /// radius continues above).
    pub fn radius_at(&self, h: f64) -> f64 {
        let rc = self.corner_radius();
        let below_corner = |h: f64| {
            let dz = rc - h.clamp(0.0, rc);
            self.flat_radius() + (rc * rc - dz * dz).max(0.0).sqrt()
        };
        match *self {
            Cutter::TaperedBall { taper_deg, .. } => {
                let a = taper_deg.to_radians();
                let ht = self.end_height();
                if h < ht {
                    below_corner(h)
                } else {
                    rc * a.cos() + (h - ht) * a.tan()
                }
            }
            _ if h < rc => below_corner(h),
            _ => self.diameter() / 2.0,
        }
    }

    /// Radius at the top of the flutes.
    pub fn flute_top_radius(&self) -> f64 {
        self.radius_at(self.flute_length())
    }

    /// Where the tip (the lowest point of the axis) sits when the cutter touches `point`, whose
    /// outward unit normal is `normal`, with its unit `axis`; `None` when the axis points into
    /// the surface (axis·normal < 0), where the end cannot be the part touching. An axis along
    /// the surface (axis·normal = 0) touches with the side: a ball or a flat end mill's flank
    /// on a wall.
    ///
    /// The touching point of the corner (a circle of radius `flat_radius` at height
    /// `corner_radius`, grown by the corner radius) is where the corner's normal is `normal`:
    /// its circle point lies on the side the normal leans away from, u = −(n − (n·a)a)/|…|, so
    /// tip = point + rc·n − rc·a − (R − rc)·u. On a ball this is the familiar
    /// centre = point + r·n; with the axis along the normal the flat bottom sits on the point.
    /// The tapered ball's cone is never the contact here: its ball touches every normal with
    /// n·a ≥ sin α, and a steeper wall is touched by the flank only when the ball clears it,
    /// which the collision test of the flank decides.
    pub fn tip_touching(&self, point: &Point3, normal: &Vector3, axis: &Vector3) -> Option<Point3> {
        let along = normal.dot(axis);
        if along < 0.0 {
            return None;
        }
        let rc = self.corner_radius();
        let sideways = -(normal - axis * along);
        let u = sideways.try_normalize(1e-9).unwrap_or_else(Vector3::zeros);
        Some(point + normal * rc - axis * rc - u * self.flat_radius())
    }

    /// Checks the dimensions make a physical cutter.
    pub fn validate(&self) -> Result<(), ToolError> {
        let d = self.diameter();
        positive("cutter diameter", d)?;
        positive("flute length", self.flute_length())?;
        match *self {
            Cutter::BullNose { corner_radius, .. } => {
                positive("corner radius", corner_radius)?;
                if corner_radius >= d / 2.0 {
                    return Err(ToolError::Invalid(format!(
                        "corner radius {corner_radius} must be less than half the diameter {d} \
                         (a corner radius of D/2 is a ball-end mill: use kind = \"ball\")"
                    )));
                }
            }
            Cutter::TaperedBall { taper_deg, .. } => {
                if !(taper_deg.is_finite() && taper_deg > 0.0 && taper_deg < 45.0) {
                    return Err(ToolError::Invalid(format!(
                        "taper half-angle {taper_deg}° must be between 0 and 45 degrees"
                    )));
                }
            }
            Cutter::Ball { .. } | Cutter::Flat { .. } => {}
        }
        if self.flute_length() < self.end_height() {
            return Err(ToolError::Invalid(format!(
                "flute length {} is shorter than the rounded end ({} mm)",
                self.flute_length(),
                self.end_height()
            )));
        }
        Ok(())
    }

    /// "ball D6", "bull D10 R1", "taper D2 3°", "flat D8".
    pub fn describe(&self) -> String {
        let d = self.diameter();
        match *self {
            Cutter::Ball { .. } | Cutter::Flat { .. } => format!("{} D{d}", self.kind()),
            Cutter::BullNose { corner_radius, .. } => format!("bull D{d} R{corner_radius}"),
            Cutter::TaperedBall { taper_deg, .. } => format!("taper D{d} {taper_deg}°"),
        }
    }
}

pub(super) fn positive(name: &str, v: f64) -> Result<(), ToolError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(ToolError::Invalid(format!(
            "{name} must be positive, got {v}"
        )))
    }
}

/// Parses a cutter spec: `ball:D`, `flat:D`, `bull:D:R` (corner radius R) or `taper:D:DEG`
/// (tapered ball, tip diameter D, half-angle DEG), all in mm. The flutes are 3·D long.
pub fn parse_cutter(spec: &str) -> Result<Cutter, ToolError> {
    let bad = || ToolError::BadSpec(spec.to_string());
    let mut fields = spec.split(':').map(str::trim);
    let kind = fields.next().ok_or_else(bad)?;
    let numbers: Vec<f64> = fields
        .map(|f| f.parse::<f64>().ok().filter(|x| x.is_finite() && *x > 0.0))
        .collect::<Option<_>>()
        .ok_or_else(bad)?;
    let cutter = match (kind, numbers.as_slice()) {
        ("ball", &[diameter]) => Cutter::Ball {
            diameter,
            flute_length: 3.0 * diameter,
        },
        ("flat", &[diameter]) => Cutter::Flat {
            diameter,
            flute_length: 3.0 * diameter,
        },
        ("bull", &[diameter, corner_radius]) => Cutter::BullNose {
            diameter,
            corner_radius,
            flute_length: 3.0 * diameter,
        },
        ("taper", &[diameter, taper_deg]) => Cutter::TaperedBall {
            diameter,
            taper_deg,
            flute_length: 3.0 * diameter,
        },
        _ => return Err(bad()),
    };
    cutter.validate().map_err(|e| match e {
        ToolError::Invalid(why) => ToolError::Invalid(format!("`{spec}`: {why}")),
        other => other,
    })?;
    Ok(cutter)
}

#[cfg(test)]
mod tests {
    use super::*;

    const KINDS: [Cutter; 4] = [
        Cutter::Ball {
            diameter: 6.0,
            flute_length: 18.0,
        },
        Cutter::Flat {
            diameter: 6.0,
            flute_length: 18.0,
        },
        Cutter::BullNose {
            diameter: 10.0,
            corner_radius: 1.5,
            flute_length: 20.0,
        },
        Cutter::TaperedBall {
            diameter: 2.0,
            taper_deg: 3.0,
            flute_length: 20.0,
        },
    ];

    #[test]
    fn profiles_are_continuous_and_match_their_closed_forms() {
        for c in KINDS {
            c.validate().unwrap();
            // Continuous and non-decreasing from tip to flute top.
            let steps = 4000;
            let mut last = c.radius_at(0.0);
            for k in 1..=steps {
                let h = c.flute_length() * k as f64 / steps as f64;
                let r = c.radius_at(h);
                assert!(r >= last - 1e-12, "{c:?} at {h}");
                assert!(r - last < 0.2, "{c:?} jumps at {h}: {last} -> {r}");
                last = r;
            }
        }
        let [ball, flat, bull, taper] = KINDS;
        assert!((ball.radius_at(3.0 - 3.0 * 0.6) - 3.0 * 0.8).abs() < 1e-12); // 3-4-5
        assert_eq!(ball.radius_at(10.0), 3.0);
        assert_eq!(flat.radius_at(0.0), 3.0);
        assert_eq!(bull.radius_at(0.0), 3.5);
        assert!((bull.radius_at(1.5) - 5.0).abs() < 1e-12);
        // Tapered ball: the cone is tangent to the ball where r·cos α meets r·(1 − sin α), and
        // at the flute top the radius is r·cos α + (L − h_t)·tan α.
        let a = 3f64.to_radians();
        let ht = 1.0 - a.sin();
        assert!((taper.end_height() - ht).abs() < 1e-15);
        assert!((taper.radius_at(ht) - a.cos()).abs() < 1e-12);
        assert!((taper.flute_top_radius() - (a.cos() + (20.0 - ht) * a.tan())).abs() < 1e-12);
        let slope = (taper.radius_at(ht + 1.0) - taper.radius_at(ht)) / 1.0;
        assert!((slope - a.tan()).abs() < 1e-12);
    }

    #[test]
    fn the_tip_touching_a_point_puts_the_cutter_surface_there() {
        // For every kind, tilt and normal: the touched point is at the corner-ring distance
        // from the tip's corner circle (on the cutter's surface), and the cutter's surface normal
        // there is the given normal.
        let normal = Vector3::new(0.2, -0.3, 0.9).normalize();
        let point = Point3::new(1.0, 2.0, 3.0);
        for c in KINDS {
            for tilt in [0.0f64, 10.0, 35.0, 60.0] {
                let t = tilt.to_radians();
                let axis = (normal * t.cos()
                    + Vector3::new(1.0, 0.0, 0.0).cross(&normal).normalize() * t.sin())
                .normalize();
                let tip = c.tip_touching(&point, &normal, &axis).unwrap();
                let rc = c.corner_radius();
                // Corner centre: on the ring of radius flat_radius at height rc.
                let centre = point + normal * rc;
                let rel = centre - tip;
                let h = rel.dot(&axis);
                let radial = (rel - axis * h).norm();
                assert!((h - rc).abs() < 1e-12, "{c:?} {tilt}");
                if tilt == 0.0 {
                    // Along the normal the flat bottom (or the ball's lowest point) sits on it.
                    assert!(radial <= c.flat_radius() + 1e-12, "{c:?}");
                } else {
                    assert!((radial - c.flat_radius()).abs() < 1e-12, "{c:?} {tilt}");
                }
                // The touched point is the lowest in direction −normal among the corner's points
                // near it: moving along −normal from the contact leaves the cutter.
                let below = point - normal * 1e-6;
                let rel = below - tip;
                let h = rel.dot(&axis);
                let radial = (rel - axis * h).norm();
                assert!(h < 0.0 || radial > c.radius_at(h) - 1e-12, "{c:?} {tilt}");
            }
            assert!(c.tip_touching(&point, &normal, &-normal).is_none());
        }
    }

    #[test]
    fn specs_parse_and_reject() {
        assert_eq!(
            parse_cutter("ball:6").unwrap(),
            Cutter::Ball {
                diameter: 6.0,
                flute_length: 18.0
            }
        );
        assert_eq!(parse_cutter("bull:10:1").unwrap().corner_radius(), 1.0);
        assert_eq!(parse_cutter(" taper : 2 : 3 ").unwrap().kind(), "taper");
        assert_eq!(parse_cutter("flat:8").unwrap().flat_radius(), 4.0);
        for bad in [
            "ball",
            "ball:x",
            "ball:-1",
            "ball:inf",
            "",
            "drill:6",
            "bull:10",
            "bull:10:5",
            "bull:10:6",
            "taper:2:50",
            "flat:6:1",
        ] {
            assert!(parse_cutter(bad).is_err(), "{bad}");
        }
        let e = parse_cutter("bull:10:5").unwrap_err().to_string();
        assert!(e.contains("bull:10:5") && e.contains("ball"), "{e}");
    }
}
