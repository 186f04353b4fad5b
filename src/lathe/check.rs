//! Independent checks of what was written: every programmed nose centre must be at distance
//! ρ from the design surface, on the tool's side, and between two programmed points — as the
//! control interpolates them — within the form tolerance.
//!
//! The planner solved "the surface point whose offset lands on this line"; the check solves
//! the other problem, "the surface point nearest this centre" (Newton on `|S(u, v) − C|²` from
//! the point vertically below `C`), and shares only the surface's own evaluation with it. It
//! reads the grid and the program back from their files' text, so rounding in the writing
//! is part of what is checked.

use nalgebra::{Matrix2, Point3, Vector2};
use rayon::prelude::*;

use super::surface::LensSurface;

/// The nearest surface point to a centre.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Foot {
    /// Its parameters.
    pub parameters: (f64, f64),
    /// The point.
    pub point: Point3<f64>,
    /// Distance from the centre.
    pub distance: f64,
    /// Whether the centre is on the tool's side (along the normal toward `+z`).
    pub tool_side: bool,
}

/// The foot of the perpendicular from `centre` to the surface: the local minimum of the
/// squared distance reached by Newton from the point below `centre`; `None` when nothing of
/// the surface lies below or Newton leaves the surface.
pub fn foot_point(surface: &LensSurface, centre: &Point3<f64>) -> Option<Foot> {
    let (mut u, mut v) = surface.parameters_over(centre.x, centre.y)?;
    let ((u0, u1), (v0, v1)) = surface.domain();
    let clamp = |u: f64, v: f64| match surface {
        LensSurface::Sag { .. } => (u, v),
        LensSurface::Nurbs(_) => (u.clamp(u0, u1), v.clamp(v0, v1)),
    };
    for _ in 0..100 {
        let s = surface.jet(u, v);
        let d = s.point - centre;
        let gradient = Vector2::new(d.dot(&s.du), d.dot(&s.dv));
        let hessian = Matrix2::new(
            s.du.dot(&s.du) + d.dot(&s.duu),
            s.du.dot(&s.dv) + d.dot(&s.duv),
            s.du.dot(&s.dv) + d.dot(&s.duv),
            s.dv.dot(&s.dv) + d.dot(&s.dvv),
        );
        let step = hessian.lu().solve(&gradient)?;
        (u, v) = clamp(u - step.x, v - step.y);
        if step.norm() < 1e-15 * (1.0 + u.abs() + v.abs()) {
            break;
        }
    }
    let s = surface.jet(u, v);
    let normal = surface.normal(&s)?;
    let d = centre - s.point;
    // A true foot: the offset is along the normal (the gradient vanished).
    let along = d.dot(&normal);
    let across = (d - normal * along).norm();
    if across > 1e-7 || !surface.contains(u, v, 1e-9) {
        return None;
    }
    Some(Foot {
        parameters: (u, v),
        point: s.point,
        distance: d.norm(),
        tool_side: along > 0.0,
    })
}

/// Distances of a set of centres from the surface against the nose radius.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct DistanceCheck {
    /// Centres checked.
    pub points: usize,
    /// Largest `| |C − foot| − ρ |` (mm).
    pub max_error: f64,
    /// Root mean square of the same (mm).
    pub rms_error: f64,
    /// Centres on the wrong side of the surface.
    pub wrong_side: usize,
    /// Centres with no foot on the surface (beyond its edge).
    pub no_foot: usize,
    /// The worst centre `(x, y, z)`.
    pub worst: [f64; 3],
}

/// Every centre's distance from the surface minus ρ (signed, mm) and whether it is on the
/// tool's side; `None` where the centre has no foot on the surface.
pub fn centre_errors(
    surface: &LensSurface,
    nose_radius: f64,
    centres: &[Point3<f64>],
) -> Vec<Option<(f64, bool)>> {
    centres
        .par_iter()
        .map(|c| foot_point(surface, c).map(|f| (f.distance - nose_radius, f.tool_side)))
        .collect()
}

/// Sums up [`centre_errors`].
pub fn summarise(centres: &[Point3<f64>], errors: &[Option<(f64, bool)>]) -> DistanceCheck {
    let mut check = DistanceCheck {
        points: centres.len(),
        max_error: 0.0,
        rms_error: 0.0,
        wrong_side: 0,
        no_foot: 0,
        worst: [0.0; 3],
    };
    let mut sum = 0.0;
    for (c, r) in centres.iter().zip(errors) {
        match r {
            None => check.no_foot += 1,
            Some((error, side)) => {
                if !side {
                    check.wrong_side += 1;
                }
                sum += error * error;
                if error.abs() > check.max_error {
                    check.max_error = error.abs();
                    check.worst = [c.x, c.y, c.z];
                }
            }
        }
    }
    let found = check.points - check.no_foot;
    check.rms_error = if found > 0 {
        (sum / found as f64).sqrt()
    } else {
        0.0
    };
    check
}

/// Checks every centre against the surface.
pub fn check_centres(
    surface: &LensSurface,
    nose_radius: f64,
    centres: &[Point3<f64>],
) -> DistanceCheck {
    summarise(centres, &centre_errors(surface, nose_radius, centres))
}

/// Reads a grid written as CSV by [`super::grid::CompensatedGrid::csv`]: the first row `r\θ` then the
/// angles in degrees, every further row a radius then its heights. Returns the centres.
pub fn read_grid_csv(text: &str) -> Result<Vec<Point3<f64>>, String> {
    let mut lines = text
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty());
    let header = lines.next().ok_or("empty grid file")?;
    let angles: Vec<f64> = header
        .split(',')
        .skip(1)
        .map(|t| t.trim().parse::<f64>().map(f64::to_radians))
        .collect::<Result<_, _>>()
        .map_err(|e| format!("header: {e}"))?;
    let mut centres = Vec::new();
    for (k, line) in lines.enumerate() {
        let values: Vec<f64> = line
            .split(',')
            .map(|t| t.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|e| format!("row {}: {e}", k + 2))?;
        if values.len() != angles.len() + 1 {
            return Err(format!(
                "row {}: {} values for {} angles",
                k + 2,
                values.len() - 1,
                angles.len()
            ));
        }
        let r = values[0];
        for (a, z) in angles.iter().zip(&values[1..]) {
            centres.push(Point3::new(r * a.cos(), r * a.sin(), *z));
        }
    }
    Ok(centres)
}

/// One programmed position of a lathe program.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Position {
    x: f64,
    z: f64,
    c_degrees: f64,
}

/// The form error of a spiral program, as the control runs it.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ProgramCheck {
    /// Feed blocks read.
    pub blocks: usize,
    /// Distance check of the interpolated centres (every block at `samples` points).
    pub interpolated: DistanceCheck,
    /// Samples per block.
    pub samples_per_block: usize,
}

/// One interpolated centre of a program and its distance error (`None`: no foot).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProgramSample {
    /// The centre.
    pub centre: Point3<f64>,
    /// Its distance from the surface minus ρ (mm).
    pub error: Option<f64>,
}

/// Reads a program's `G0`/`G1` blocks in `X` (radius), `Z`, `C` (degrees), interpolates each
/// feed block linearly in all three axes as the control does, and measures every sample's
/// distance from the surface; also returns every sample with its error (for a picture).
/// Words other than G0/G1/X/Z/C/F/N and comments are ignored; an unreadable number is an
/// error naming its line.
pub fn check_program(
    surface: &LensSurface,
    nose_radius: f64,
    program: &str,
    samples_per_block: usize,
) -> Result<(ProgramCheck, Vec<ProgramSample>), String> {
    let mut position: Option<Position> = None;
    let mut current = Position {
        x: 0.0,
        z: 0.0,
        c_degrees: 0.0,
    };
    let mut feed_moves: Vec<(Position, Position)> = Vec::new();
    let mut motion = 0;
    for (n, raw) in program.lines().enumerate() {
        let line = strip_comments(raw);
        let mut moved = false;
        let mut next = current;
        let mut chars = line.char_indices().peekable();
        while let Some((i, c)) = chars.next() {
            if !c.is_ascii_alphabetic() {
                continue;
            }
            let start = i + 1;
            let mut end = start;
            while let Some(&(j, d)) = chars.peek() {
                if d.is_ascii_digit() || d == '.' || d == '-' || d == '+' {
                    end = j + d.len_utf8();
                    chars.next();
                } else {
                    break;
                }
            }
            let word = &line[start..end];
            let value = || {
                word.parse::<f64>()
                    .map_err(|_| format!("line {}: '{}{}' is not a number", n + 1, c, word))
            };
            match c.to_ascii_uppercase() {
                'G' => match value()? as i64 {
                    0 => motion = 0,
                    1 => motion = 1,
                    _ => {}
                },
                'X' => {
                    next.x = value()?;
                    moved = true;
                }
                'Z' => {
                    next.z = value()?;
                    moved = true;
                }
                'C' => {
                    next.c_degrees = value()?;
                    moved = true;
                }
                _ => {}
            }
        }
        if moved {
            if motion == 1
                && let Some(from) = position
            {
                feed_moves.push((from, next));
            }
            position = Some(next);
            current = next;
        }
    }
    let k = samples_per_block.max(1);
    let centres: Vec<Point3<f64>> = feed_moves
        .iter()
        // The plunge and other moves at a fixed angle and radius are not on the surface.
        .filter(|(a, b)| a.c_degrees != b.c_degrees)
        .flat_map(|(a, b)| {
            (1..=k).map(move |s| {
                let t = s as f64 / k as f64;
                let x = a.x + (b.x - a.x) * t;
                let z = a.z + (b.z - a.z) * t;
                let c = (a.c_degrees + (b.c_degrees - a.c_degrees) * t).to_radians();
                Point3::new(x * c.cos(), x * c.sin(), z)
            })
        })
        .collect();
    let errors = centre_errors(surface, nose_radius, &centres);
    let check = ProgramCheck {
        blocks: feed_moves.len(),
        interpolated: summarise(&centres, &errors),
        samples_per_block: k,
    };
    let samples = centres
        .into_iter()
        .zip(errors)
        .map(|(centre, e)| ProgramSample {
            centre,
            error: e.map(|(error, _)| error),
        })
        .collect();
    Ok((check, samples))
}

/// A line without its `( … )` and `; …` comments.
fn strip_comments(line: &str) -> String {
    let mut out = String::with_capacity(line.len());
    let mut depth = 0;
    for c in line.chars() {
        match c {
            '(' => depth += 1,
            ')' if depth > 0 => depth -= 1,
            ';' if depth == 0 => break,
            _ if depth == 0 => out.push(c),
            _ => {}
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lathe::surface::SagShape;

    #[test]
    fn feet_on_a_sphere_are_radial() {
        let surface = LensSurface::Sag {
            shape: SagShape::Conic {
                curvature: 1.0 / 20.0,
                conic: 0.0,
                even: vec![],
            },
            aperture: 20.0,
        };
        // Points inside the concave sphere (toward its centre (0, 0, 20)) at distance 1.
        for &(x, y) in &[(0.0, 0.0), (3.0, -4.0), (6.0, 5.0)] {
            let r2: f64 = x * x + y * y;
            let on = Point3::new(x, y, 20.0 - (400.0 - r2).sqrt());
            let centre = on + (Point3::new(0.0, 0.0, 20.0) - on).normalize();
            let foot = foot_point(&surface, &centre).unwrap();
            assert!((foot.distance - 1.0).abs() < 1e-12);
            assert!(foot.tool_side);
            assert!((foot.point - on).norm() < 1e-9);
            // The mirror point below the surface is on the wrong side.
            let below = on - (centre - on);
            let foot = foot_point(&surface, &below).unwrap();
            assert!(!foot.tool_side && (foot.distance - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn programs_are_read_with_their_comments_and_modes() {
        let surface = LensSurface::Sag {
            shape: SagShape::Conic {
                curvature: 0.0,
                conic: 0.0,
                even: vec![],
            },
            aperture: 20.0,
        };
        // A flat face: centres at z = ρ are exact, one at 0.6 is 0.1 off.
        let program = "(a flat)\nG0 X5 Z2 C0\nG1 Z0.5 F100 (plunge)\nG93 G1 X4 C90 Z0.5 F600 ; note\nG1 X3 C180 Z0.6 F600\n";
        let (check, samples) = check_program(&surface, 0.5, program, 4).unwrap();
        assert_eq!(samples.len(), 8);
        assert_eq!(check.blocks, 3);
        assert_eq!(check.interpolated.points, 8);
        assert!((check.interpolated.max_error - 0.1).abs() < 1e-12);
        assert!(check_program(&surface, 0.5, "G1 X1.2.3", 4).is_err());
    }
}
