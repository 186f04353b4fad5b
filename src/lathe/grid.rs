//! The polar point grid of seed 003 (ch. 4, its "HDF" file): radii `0, s, 2s, … ≤ D/2`,
//! `ticks` angles `2πj/ticks`, and the nose-centre height `Z[i][j]` over every `(rᵢ, θⱼ)`,
//! each compensated exactly ([`super::compensate`]).
//!
//! Every angle is its own radial march, outward from the centre, each point's solve starting
//! from the one before (two or three Newton steps); the angles run in parallel and the result
//! does not depend on the thread count (each value comes from the same sequence of operations).
//!
//! The grid also measures what the tool will meet: the largest concave curvature (against
//! the nose) and the steepest descent along the cutting direction (against the tool's clearance
//! angle: a turning tool moving downhill faster than its clearance rubs its flank on the
//! surface just cut).

use rayon::prelude::*;

use super::compensate::{Contact, ContactError, nose_centre};
use super::surface::LensSurface;

/// How the radii are spaced.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RadialSpacing {
    /// A radial step (the seed's `step`): radii `0, s, 2s, …` up to the outer radius.
    Step(f64),
    /// This many radii from the centre to the outer radius, both included.
    Count(usize),
}

/// The grid's parameters (the seed's `outerD`, `step`, `ticks`) and the tool.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridOptions {
    /// Nose radius ρ (mm).
    pub nose_radius: f64,
    /// Outer diameter of the grid (mm).
    pub diameter: f64,
    /// Radial spacing.
    pub radial: RadialSpacing,
    /// Angles per turn.
    pub ticks: usize,
}

/// Why a grid cannot be made.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum GridError {
    /// A parameter out of range.
    #[error("{0}")]
    Parameter(String),
    /// A point of the grid has no nose centre.
    #[error("grid point r = {radius:.4} mm, θ = {angle_degrees:.3}°: {reason}")]
    Point {
        /// Its radius.
        radius: f64,
        /// Its angle.
        angle_degrees: f64,
        /// Why.
        reason: ContactError,
    },
}

/// Radii and angles of a polar grid.
#[derive(Clone, Debug, PartialEq)]
pub struct PolarGrid {
    /// Radii (mm), ascending from 0.
    pub radii: Vec<f64>,
    /// Angles (radians), ascending from 0.
    pub angles: Vec<f64>,
}

impl PolarGrid {
    /// The grid of `options`.
    pub fn new(options: &GridOptions) -> Result<PolarGrid, GridError> {
        let outer = options.diameter / 2.0;
        if !(outer.is_finite() && outer > 0.0) {
            return Err(GridError::Parameter(format!(
                "outer diameter {}: must be a positive length",
                options.diameter
            )));
        }
        // The count first, in floating point: a tiny step or a huge count must be refused
        // before a vector of that length is asked for.
        let count = match options.radial {
            RadialSpacing::Step(step) => {
                if !(step.is_finite() && step > 0.0 && step <= outer) {
                    return Err(GridError::Parameter(format!(
                        "radial step {step}: must be positive and at most the outer radius {outer}"
                    )));
                }
                (outer / step + 1e-9).floor() + 1.0
            }
            RadialSpacing::Count(n) => {
                if n < 2 {
                    return Err(GridError::Parameter(format!(
                        "{n} radii: at least 2 (the centre and the rim)"
                    )));
                }
                n as f64
            }
        };
        if options.ticks == 0 {
            return Err(GridError::Parameter("0 ticks: at least 1 angle".into()));
        }
        if count * options.ticks as f64 > 200_000_000.0 {
            return Err(GridError::Parameter(format!(
                "{count} × {} points: more than 200 million",
                options.ticks
            )));
        }
        let count = count as usize;
        let radii: Vec<f64> = match options.radial {
            RadialSpacing::Step(step) => (0..count).map(|i| i as f64 * step).collect(),
            RadialSpacing::Count(_) => (0..count)
                .map(|i| outer * i as f64 / (count - 1) as f64)
                .collect(),
        };
        let angles = (0..options.ticks)
            .map(|j| std::f64::consts::TAU * j as f64 / options.ticks as f64)
            .collect();
        Ok(PolarGrid { radii, angles })
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.radii.len() * self.angles.len()
    }

    /// Whether the grid has no points.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Where on the surface a measure is worst.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Extreme {
    /// The value.
    pub value: f64,
    /// Grid radius (mm).
    pub radius: f64,
    /// Grid angle (degrees).
    pub angle_degrees: f64,
}

/// What the solve met on the way.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct GridStatistics {
    /// Newton iterations, mean per point.
    pub mean_iterations: f64,
    /// Newton iterations, most at one point.
    pub max_iterations: u32,
    /// Smallest concave radius of curvature met (mm), where; `None`: nowhere concave.
    pub smallest_concave_radius: Option<Extreme>,
    /// Steepest descent along the cutting direction (degrees), where.
    pub steepest_descent: Extreme,
    /// Largest distance between a grid line and its contact point, in plan (mm): how far
    /// the compensation moves the contact.
    pub largest_contact_shift: Extreme,
}

/// The compensated grid: the seed's R vector, θ vector and Z matrix.
#[derive(Clone, Debug, PartialEq)]
pub struct CompensatedGrid {
    /// Radii and angles.
    pub grid: PolarGrid,
    /// Nose-centre heights, row-major by radius: `z[i · ticks + j]` over `(rᵢ, θⱼ)`.
    pub z: Vec<f64>,
    /// What the solve met.
    pub statistics: GridStatistics,
}

/// Magic bytes of the binary grid file.
pub const BINARY_MAGIC: &[u8; 8] = b"WMLGRID1";

impl CompensatedGrid {
    /// The grid as CSV, the seed's HDF layout: the first row `r\θ` and the angles (degrees),
    /// then one row per radius, the radius and its nose-centre heights (mm, 9 decimals:
    /// picometres, far below any machine's resolution and the 1e-6 mm check).
    pub fn csv(&self) -> String {
        use std::fmt::Write;
        let ticks = self.grid.angles.len();
        let mut out = String::with_capacity(self.z.len() * 14 + 64);
        out.push_str("r\\theta");
        for a in &self.grid.angles {
            let _ = write!(out, ",{:.12}", a.to_degrees());
        }
        out.push('\n');
        for (i, r) in self.grid.radii.iter().enumerate() {
            let _ = write!(out, "{r:.9}");
            for z in &self.z[i * ticks..(i + 1) * ticks] {
                let _ = write!(out, ",{z:.9}");
            }
            out.push('\n');
        }
        out
    }

    /// The grid as a little-endian binary file: the 8 bytes `WMLGRID1`, the number of radii
    /// and of angles (u32 each), the radii (f64, mm), the angles (f64, radians), then the
    /// heights (f64, mm) row-major by radius — every value exactly as computed.
    pub fn binary(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(
            16 + 8 * (self.grid.radii.len() + self.grid.angles.len() + self.z.len()),
        );
        out.extend_from_slice(BINARY_MAGIC);
        out.extend_from_slice(&(self.grid.radii.len() as u32).to_le_bytes());
        out.extend_from_slice(&(self.grid.angles.len() as u32).to_le_bytes());
        for v in self
            .grid
            .radii
            .iter()
            .chain(&self.grid.angles)
            .chain(&self.z)
        {
            out.extend_from_slice(&v.to_le_bytes());
        }
        out
    }
}

/// Per-angle accumulators of [`GridStatistics`].
#[derive(Clone, Copy)]
struct Tally {
    iterations: u64,
    max_iterations: u32,
    concave: Option<(f64, usize)>,
    descent: (f64, usize),
    shift: (f64, usize),
}

/// The descent angle (degrees) along the cutting direction `+θ` at a contact.
pub fn descent_degrees(contact: &Contact) -> f64 {
    let (x, y) = (contact.point.x, contact.point.y);
    let r = x.hypot(y);
    if r < 1e-12 {
        return 0.0;
    }
    let tangent = nalgebra::Vector3::new(-y / r, x / r, 0.0);
    // Slope dz/ds of the surface along the tangent, from its normal.
    let slope = -contact.normal.dot(&tangent) / contact.normal.z;
    (-slope).atan().to_degrees()
}

/// One angle's march from the centre outward.
fn march(
    surface: &LensSurface,
    nose_radius: f64,
    radii: &[f64],
    angle: f64,
    centre: &Contact,
) -> Result<(Vec<f64>, Tally), (usize, ContactError)> {
    let (sin, cos) = angle.sin_cos();
    let mut z = Vec::with_capacity(radii.len());
    let mut tally = Tally {
        iterations: 0,
        max_iterations: 0,
        concave: None,
        descent: (f64::NEG_INFINITY, 0),
        shift: (0.0, 0),
    };
    let mut previous = *centre;
    let mut before: Option<Contact> = None;
    for (i, &r) in radii.iter().enumerate() {
        let contact = if i == 0 {
            *centre
        } else {
            // Predict linearly from the last two contacts along this angle.
            let (pu, pv) = previous.parameters;
            let guess = match before {
                Some(b) => (2.0 * pu - b.parameters.0, 2.0 * pv - b.parameters.1),
                None => (pu, pv),
            };
            let line = (r * cos, r * sin);
            let solved = nose_centre(surface, nose_radius, line, guess).or_else(|_| {
                // The prediction overshot (an edge, a kink in the parametrisation): restart
                // from the point below.
                let guess = surface
                    .parameters_over(line.0, line.1)
                    .unwrap_or(previous.parameters);
                nose_centre(surface, nose_radius, line, guess)
            });
            solved.map_err(|e| (i, e))?
        };
        tally.iterations += u64::from(contact.iterations);
        tally.max_iterations = tally.max_iterations.max(contact.iterations);
        if contact.curvatures[0] > 0.0
            && tally.concave.is_none_or(|(k, _)| contact.curvatures[0] > k)
        {
            tally.concave = Some((contact.curvatures[0], i));
        }
        let descent = descent_degrees(&contact);
        if descent > tally.descent.0 {
            tally.descent = (descent, i);
        }
        let shift = (contact.point.x - r * cos).hypot(contact.point.y - r * sin);
        if shift > tally.shift.0 {
            tally.shift = (shift, i);
        }
        z.push(contact.centre.z);
        before = (i > 0).then_some(previous);
        previous = contact;
    }
    Ok((z, tally))
}

/// The compensated polar grid over `surface` (the seed's `projPt` on an exact offset).
pub fn compensated_grid(
    surface: &LensSurface,
    options: &GridOptions,
) -> Result<CompensatedGrid, GridError> {
    let rho = options.nose_radius;
    if !(rho.is_finite() && rho >= 0.0) {
        return Err(GridError::Parameter(format!(
            "nose radius {rho}: must be zero or a positive length"
        )));
    }
    let grid = PolarGrid::new(options)?;
    let centre_error = |reason| GridError::Point {
        radius: 0.0,
        angle_degrees: 0.0,
        reason,
    };
    let guess = surface
        .parameters_over(0.0, 0.0)
        .ok_or_else(|| centre_error(ContactError::OffSurface { x: 0.0, y: 0.0 }))?;
    let centre = nose_centre(surface, rho, (0.0, 0.0), guess).map_err(centre_error)?;
    let columns: Vec<_> = grid
        .angles
        .par_iter()
        .map(|&angle| march(surface, rho, &grid.radii, angle, &centre))
        .collect();
    let ticks = grid.angles.len();
    let mut z = vec![0.0; grid.len()];
    let mut iterations = 0u64;
    let mut max_iterations = 0;
    let mut concave: Option<Extreme> = None;
    let mut descent: Option<Extreme> = None;
    let mut shift: Option<Extreme> = None;
    for (j, column) in columns.into_iter().enumerate() {
        let angle_degrees = grid.angles[j].to_degrees();
        let (values, tally) = column.map_err(|(i, reason)| GridError::Point {
            radius: grid.radii[i],
            angle_degrees,
            reason,
        })?;
        for (i, value) in values.into_iter().enumerate() {
            z[i * ticks + j] = value;
        }
        iterations += tally.iterations;
        max_iterations = max_iterations.max(tally.max_iterations);
        let at = |value: f64, i: usize| Extreme {
            value,
            radius: grid.radii[i],
            angle_degrees,
        };
        if let Some((k, i)) = tally.concave
            && concave.is_none_or(|c| 1.0 / k < c.value)
        {
            concave = Some(at(1.0 / k, i));
        }
        if descent.is_none_or(|d| tally.descent.0 > d.value) {
            descent = Some(at(tally.descent.0, tally.descent.1));
        }
        if shift.is_none_or(|s| tally.shift.0 > s.value) {
            shift = Some(at(tally.shift.0, tally.shift.1));
        }
    }
    let zero = Extreme {
        value: 0.0,
        radius: 0.0,
        angle_degrees: 0.0,
    };
    Ok(CompensatedGrid {
        statistics: GridStatistics {
            mean_iterations: iterations as f64 / grid.len().max(1) as f64,
            max_iterations,
            smallest_concave_radius: concave,
            steepest_descent: descent.unwrap_or(zero),
            largest_contact_shift: shift.unwrap_or(zero),
        },
        grid,
        z,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lathe::surface::SagShape;

    #[test]
    fn radii_follow_the_step_or_the_count() {
        let options = |radial| GridOptions {
            nose_radius: 0.5,
            diameter: 40.0,
            radial,
            ticks: 360,
        };
        let g = PolarGrid::new(&options(RadialSpacing::Step(0.05))).unwrap();
        assert_eq!(g.radii.len(), 401);
        assert!((g.radii[400] - 20.0).abs() < 1e-12);
        assert_eq!(g.angles.len(), 360);
        let g = PolarGrid::new(&options(RadialSpacing::Count(181))).unwrap();
        assert_eq!(g.len(), 181 * 360);
        assert!((g.radii[180] - 20.0).abs() < 1e-12);
        assert!(PolarGrid::new(&options(RadialSpacing::Step(0.0))).is_err());
        assert!(PolarGrid::new(&options(RadialSpacing::Count(1))).is_err());
        // Refused by their count before any vector of that length is asked for.
        assert!(PolarGrid::new(&options(RadialSpacing::Step(1e-300))).is_err());
        assert!(PolarGrid::new(&options(RadialSpacing::Count(1 << 62))).is_err());
    }

    /// A paraboloid `z = r²/(2R)` (conic −1): the nose centre over radius `r_c` comes from the
    /// contact at `x` with `r_c = x (1 − ρ/(R s))`, `z_c = x²/(2R) + ρ/s`, `s = √(1 + x²/R²)`;
    /// solved here for `x` by bisection, independently of the grid's Newton.
    #[test]
    fn paraboloid_grid_matches_the_closed_form_offset() {
        let (radius, rho) = (25.0, 0.8);
        let surface = LensSurface::Sag {
            shape: SagShape::Conic {
                curvature: 1.0 / radius,
                conic: -1.0,
                even: vec![],
            },
            aperture: 30.0,
        };
        let options = GridOptions {
            nose_radius: rho,
            diameter: 26.0,
            radial: RadialSpacing::Count(27),
            ticks: 7,
        };
        let g = compensated_grid(&surface, &options).unwrap();
        for (i, &rc) in g.grid.radii.iter().enumerate() {
            let offset_radius =
                |x: f64| x * (1.0 - rho / (radius * (1.0 + x * x / (radius * radius)).sqrt()));
            let (mut lo, mut hi) = (0.0, 15.0);
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if offset_radius(mid) < rc {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            let x = 0.5 * (lo + hi);
            let s = (1.0 + x * x / (radius * radius)).sqrt();
            let expected = x * x / (2.0 * radius) + rho / s;
            for j in 0..7 {
                let z = g.z[i * 7 + j];
                assert!((z - expected).abs() < 1e-10, "r {rc}: {z} vs {expected}");
            }
        }
        // Rotationally symmetric: nothing descends along the cut, concave everywhere.
        assert!(g.statistics.steepest_descent.value.abs() < 1e-9);
        let concave = g.statistics.smallest_concave_radius.unwrap();
        // The paraboloid's curvature is largest (radius smallest, R) at the vertex.
        assert!((concave.value - radius).abs() < 1e-9, "{concave:?}");
    }

    #[test]
    fn a_grid_wider_than_the_aperture_names_the_point() {
        let surface = LensSurface::Sag {
            shape: SagShape::Conic {
                curvature: -1.0 / 60.0,
                conic: 0.0,
                even: vec![],
            },
            aperture: 20.0,
        };
        let options = GridOptions {
            nose_radius: 0.5,
            diameter: 24.0,
            radial: RadialSpacing::Step(0.5),
            ticks: 12,
        };
        match compensated_grid(&surface, &options) {
            Err(GridError::Point { radius, reason, .. }) => {
                assert!(radius > 10.0 && radius <= 12.0, "{radius}");
                assert!(matches!(reason, ContactError::OffSurface { .. }));
            }
            other => panic!("{other:?}"),
        }
    }
}
