//! A cutter in its holder: neck, shank and holder sections stacked along the tool axis.

use serde::{Deserialize, Serialize};

use super::ToolError;
use super::cutter::{Cutter, positive};

/// A round section of the shank or holder: a cylinder, or a cone frustum when the diameters
/// differ. Sections stack along the axis in the order given.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
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

/// A relieved neck between the flutes and the shank: narrower than the cut, so the tool reaches
/// past walls deeper than its flute length alone would let it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Neck {
    pub diameter: f64,
    /// Length from the top of the flutes, mm.
    pub length: f64,
}

/// A cutter in its holder.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ToolAssembly {
    /// Tool number on the machine (T word).
    pub id: u32,
    /// What the shop calls it (catalogue name); may be empty.
    #[serde(default)]
    pub name: String,
    pub cutter: Cutter,
    #[serde(default)]
    pub neck: Option<Neck>,
    /// Shank diameter above the flutes (and neck), mm.
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
    /// Neck and shank: must keep the shank margin.
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

impl ToolAssembly {
    /// Radius of the ball of a ball-ended cutter (ball or tapered ball); `None` for flat and
    /// bull-nose end mills.
    pub fn ball_radius(&self) -> Option<f64> {
        self.cutter.ball_radius()
    }

    pub fn flute_length(&self) -> f64 {
        self.cutter.flute_length()
    }

    /// Height above the tip where the shank starts (the top of the neck, if there is one).
    fn shank_from(&self) -> f64 {
        self.flute_length() + self.neck.map_or(0.0, |n| n.length)
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
            .fold(self.cutter.diameter() / 2.0, f64::max)
    }

    /// The bodies above the cutter's rounded end, tip to spindle: the flank of the flutes of a
    /// ball-ended cutter (its ball is handled exactly by `collide::distance`, the centre's
    /// distance to the part; flat and bull-nose cutters have no body here, their whole fluted
    /// end is one solid in `collide`), then neck and shank (role `Shank`), then the holder.
    pub fn bodies(&self) -> Vec<Body> {
        let mut out = Vec::new();
        if self.cutter.ball_radius().is_some() {
            let from = self.cutter.end_height();
            out.push(Body {
                role: BodyRole::Flutes,
                from,
                to: self.flute_length(),
                radius_from: self.cutter.radius_at(from),
                radius_to: self.cutter.flute_top_radius(),
            });
        }
        if let Some(neck) = self.neck {
            out.push(Body {
                role: BodyRole::Shank,
                from: self.flute_length(),
                to: self.shank_from().min(self.stickout),
                radius_from: neck.diameter / 2.0,
                radius_to: neck.diameter / 2.0,
            });
        }
        if self.stickout > self.shank_from() {
            let rs = self.shank_diameter / 2.0;
            out.push(Body {
                role: BodyRole::Shank,
                from: self.shank_from(),
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
        self.cutter.validate()?;
        positive("shank diameter", self.shank_diameter)?;
        positive("stickout", self.stickout)?;
        if let Some(neck) = self.neck {
            positive("neck diameter", neck.diameter)?;
            positive("neck length", neck.length)?;
            if neck.diameter > self.shank_diameter {
                return Err(ToolError::Invalid(format!(
                    "neck diameter {} is wider than the shank {}",
                    neck.diameter, self.shank_diameter
                )));
            }
        }
        if self.stickout < self.shank_from() {
            return Err(ToolError::Invalid(format!(
                "stickout {} is shorter than the flutes and neck ({} mm)",
                self.stickout,
                self.shank_from()
            )));
        }
        for (i, s) in self.holder.iter().enumerate() {
            // Each on its own: `min` would pass a NaN beside a good value.
            positive(&format!("holder section {i} diameter"), s.diameter)?;
            positive(&format!("holder section {i} top diameter"), s.top())?;
            positive(&format!("holder section {i} length"), s.length)?;
        }
        Ok(())
    }

    /// A one-line description for reports and G-code comments.
    pub fn describe(&self) -> String {
        let holder: Vec<String> = self
            .holder
            .iter()
            .map(|s| match s.top_diameter {
                Some(t) if t != s.diameter => format!("D{}-{}x{}", s.diameter, t, s.length),
                _ => format!("D{}x{}", s.diameter, s.length),
            })
            .collect();
        let name = if self.name.is_empty() {
            String::new()
        } else {
            format!(" \"{}\"", self.name)
        };
        let neck = self.neck.map_or(String::new(), |n| {
            format!(" neck D{}x{}", n.diameter, n.length)
        });
        format!(
            "T{}{name} {} flutes {}{neck} shank D{} stickout {} holder [{}]",
            self.id,
            self.cutter.describe(),
            self.cutter.flute_length(),
            self.shank_diameter,
            self.stickout,
            holder.join(", ")
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> ToolAssembly {
        ToolAssembly {
            id: 1,
            name: String::new(),
            cutter: Cutter::Ball {
                diameter: 6.0,
                flute_length: 18.0,
            },
            neck: None,
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

        // A necked tapered ball: flank frustum, neck, shank, holder, still gapless.
        let mut necked = sample();
        necked.cutter = Cutter::TaperedBall {
            diameter: 2.0,
            taper_deg: 2.0,
            flute_length: 12.0,
        };
        necked.neck = Some(Neck {
            diameter: 1.5,
            length: 10.0,
        });
        necked.validate().unwrap();
        let b = necked.bodies();
        let roles: Vec<BodyRole> = b.iter().map(|b| b.role).collect();
        use BodyRole::*;
        assert_eq!(roles, [Flutes, Shank, Shank, Holder, Holder]);
        assert_eq!(b[0].from, necked.cutter.end_height());
        assert!(b[0].radius_to > b[0].radius_from);
        assert_eq!((b[1].from, b[1].to, b[1].radius_to), (12.0, 22.0, 0.75));
        for w in b.windows(2) {
            assert_eq!(w[0].to, w[1].from);
        }

        // Flat and bull-nose ends have no flute body: `collide` tests their end as one solid.
        necked.cutter = Cutter::BullNose {
            diameter: 6.0,
            corner_radius: 1.0,
            flute_length: 12.0,
        };
        assert_eq!(necked.bodies()[0].from, 12.0);
    }

    #[test]
    fn bad_assemblies_are_refused() {
        let mut t = sample();
        t.stickout = 10.0;
        assert!(t.validate().unwrap_err().to_string().contains("stickout"));
        let mut t = sample();
        t.neck = Some(Neck {
            diameter: 8.0,
            length: 5.0,
        });
        assert!(t.validate().unwrap_err().to_string().contains("wider"));
        t.neck = Some(Neck {
            diameter: 4.0,
            length: 30.0,
        });
        assert!(
            t.validate()
                .unwrap_err()
                .to_string()
                .contains("flutes and neck")
        );
    }
}
