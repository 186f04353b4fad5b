//! Tool assemblies: the cutter, the shank above it and the holder, as plain geometry along the
//! tool axis. Heights are measured from the tool tip toward the spindle, in millimetres.
//!
//! This module knows nothing about the part or about collision queries; `collide` turns these
//! bodies into shapes.

use serde::{Deserialize, Serialize};

/// The cutting end. Only ball-end mills so far (flat, bull-nose and tapered ball come with the
/// accessibility work).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Cutter {
    Ball {
        /// Cutting diameter, mm.
        diameter: f64,
        /// Fluted length from the tip, mm (the cutting part; must be ≥ the radius).
        flute_length: f64,
    },
}

/// A round section of the shank or holder: a cylinder, or a cone frustum when the diameters
/// differ. Sections stack along the axis in the order given.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Section {
    /// Diameter at the end nearer the tip, mm.
    pub diameter: f64,
    /// Diameter at the end nearer the spindle, mm (defaults to `diameter`).
    #[serde(default)]
    pub top_diameter: Option<f64>,
    pub length: f64,
}

impl Section {
    pub fn cylinder(diameter: f64, length: f64) -> Self {
        Self {
            diameter,
            top_diameter: None,
            length,
        }
    }
    pub fn top(&self) -> f64 {
        self.top_diameter.unwrap_or(self.diameter)
    }
}

/// A cutter in its holder.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ToolAssembly {
    /// Tool number on the machine (T word).
    pub id: u32,
    pub cutter: Cutter,
    /// Shank diameter above the flutes, mm.
    pub shank_diameter: f64,
    /// Length the tool sticks out of the holder, from the tip, mm.
    pub stickout: f64,
    /// Holder sections from the holder nose upward.
    pub holder: Vec<Section>,
}

/// What a body is, for error messages and for which margin applies to it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Hash, PartialOrd, Ord)]
#[serde(rename_all = "snake_case")]
pub enum BodyRole {
    /// The fluted part above the ball: touching the part with it is a gouge.
    Flutes,
    Shank,
    Holder,
}

/// One solid of revolution of the assembly, from `from` to `to` along the axis, with radius
/// `radius_from` at `from` and `radius_to` at `to`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Body {
    pub role: BodyRole,
    pub from: f64,
    pub to: f64,
    pub radius_from: f64,
    pub radius_to: f64,
}

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ToolError {
    #[error("tool spec `{0}`: expected `ball:DIAMETER` (e.g. ball:6)")]
    BadSpec(String),
    #[error("tool: {0}")]
    Invalid(String),
}

impl ToolAssembly {
    /// Radius of the ball.
    pub fn ball_radius(&self) -> f64 {
        match self.cutter {
            Cutter::Ball { diameter, .. } => diameter / 2.0,
        }
    }

    pub fn flute_length(&self) -> f64 {
        match self.cutter {
            Cutter::Ball { flute_length, .. } => flute_length,
        }
    }

    /// Distance from the tip to the end of the holder.
    pub fn total_length(&self) -> f64 {
        self.stickout + self.holder.iter().map(|s| s.length).sum::<f64>()
    }

    /// The largest radius of any body: how far from the axis anything of the tool reaches.
    pub fn max_radius(&self) -> f64 {
        self.bodies()
            .iter()
            .map(|b| b.radius_from.max(b.radius_to))
            .fold(self.ball_radius(), f64::max)
    }

    /// The bodies above the ball, tip to spindle. The ball itself is handled exactly by
    /// `collide::distance` (its centre's distance to the part).
    pub fn bodies(&self) -> Vec<Body> {
        let r = self.ball_radius();
        let mut out = vec![Body {
            role: BodyRole::Flutes,
            from: r,
            to: self.flute_length(),
            radius_from: r,
            radius_to: r,
        }];
        if self.stickout > self.flute_length() {
            let rs = self.shank_diameter / 2.0;
            out.push(Body {
                role: BodyRole::Shank,
                from: self.flute_length(),
                to: self.stickout,
                radius_from: rs,
                radius_to: rs,
            });
        }
        let mut h = self.stickout;
        for s in &self.holder {
            out.push(Body {
                role: BodyRole::Holder,
                from: h,
                to: h + s.length,
                radius_from: s.diameter / 2.0,
                radius_to: s.top() / 2.0,
            });
            h += s.length;
        }
        out.retain(|b| b.to > b.from);
        out
    }

    /// Checks the dimensions make a physical tool.
    pub fn validate(&self) -> Result<(), ToolError> {
        let r = self.ball_radius();
        let positive = |name: &str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(ToolError::Invalid(format!(
                    "{name} must be positive, got {v}"
                )))
            }
        };
        positive("cutter diameter", 2.0 * r)?;
        positive("flute length", self.flute_length())?;
        positive("shank diameter", self.shank_diameter)?;
        positive("stickout", self.stickout)?;
        if self.flute_length() < r {
            return Err(ToolError::Invalid(format!(
                "flute length {} is shorter than the ball radius {r}",
                self.flute_length()
            )));
        }
        if self.stickout < self.flute_length() {
            return Err(ToolError::Invalid(format!(
                "stickout {} is shorter than the flute length {}",
                self.stickout,
                self.flute_length()
            )));
        }
        for (i, s) in self.holder.iter().enumerate() {
            positive(
                &format!("holder section {i} diameter"),
                s.diameter.min(s.top()),
            )?;
            positive(&format!("holder section {i} length"), s.length)?;
        }
        Ok(())
    }

    /// A one-line description for reports and G-code comments.
    pub fn describe(&self) -> String {
        let Cutter::Ball {
            diameter,
            flute_length,
        } = self.cutter;
        let holder: Vec<String> = self
            .holder
            .iter()
            .map(|s| match s.top_diameter {
                Some(t) if t != s.diameter => format!("D{}-{}x{}", s.diameter, t, s.length),
                _ => format!("D{}x{}", s.diameter, s.length),
            })
            .collect();
        format!(
            "T{} ball D{diameter} flutes {flute_length} shank D{} stickout {} holder [{}]",
            self.id,
            self.shank_diameter,
            self.stickout,
            holder.join(", ")
        )
    }
}

/// Parses `ball:D` (D in mm) into a cutter.
pub fn parse_cutter(spec: &str) -> Result<Cutter, ToolError> {
    let bad = || ToolError::BadSpec(spec.to_string());
    let (kind, diameter) = spec.split_once(':').ok_or_else(bad)?;
    let diameter: f64 = diameter.trim().parse().map_err(|_| bad())?;
    if !(diameter.is_finite() && diameter > 0.0) {
        return Err(bad());
    }
    match kind.trim() {
        "ball" => Ok(Cutter::Ball {
            diameter,
            flute_length: 3.0 * diameter,
        }),
        _ => Err(bad()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> ToolAssembly {
        ToolAssembly {
            id: 1,
            cutter: Cutter::Ball {
                diameter: 6.0,
                flute_length: 18.0,
            },
            shank_diameter: 6.0,
            stickout: 40.0,
            holder: vec![
                Section {
                    diameter: 20.0,
                    top_diameter: Some(30.0),
                    length: 20.0,
                },
                Section::cylinder(40.0, 40.0),
            ],
        }
    }

    #[test]
    fn bodies_stack_without_gaps() {
        let t = sample();
        let b = t.bodies();
        assert_eq!(b.len(), 4);
        assert_eq!(b[0].from, 3.0);
        for w in b.windows(2) {
            assert_eq!(w[0].to, w[1].from);
        }
        assert_eq!(b.last().unwrap().to, t.total_length());
        assert_eq!(t.max_radius(), 20.0);
        t.validate().unwrap();
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
        for bad in ["ball", "ball:x", "ball:-1", "flat:6", "ball:inf", ""] {
            assert!(parse_cutter(bad).is_err(), "{bad}");
        }
        let mut t = sample();
        t.stickout = 10.0;
        assert!(t.validate().is_err());
    }
}
