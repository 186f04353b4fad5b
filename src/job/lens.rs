//! `wavemill lens`: a lens surface into its compensated polar grid and spiral program, both
//! checked as written (seed 003; the stages are in [`crate::lathe`]).
//!
//! Read the surface (TOML or IGES) ► grid (exact compensation per point) ► refuse what the
//! tool cannot cut (concave radius below the nose, descent beyond the clearance angle) ►
//! spiral ► post ► read the grid CSV and the program text back and check every centre's
//! distance from the surface (1e-6 mm) and the program's form error as interpolated ► picture
//! ► `grid.csv`, `grid.bin`, `lens.nc`, `lens.json`, `lens.png` (and with the seed's route
//! for comparison, `offset.igs`), all or nothing.

use std::path::Path;
use std::time::Instant;

use serde::Serialize;

use super::cad_part::read_iges_file;
use super::output::{OutputKind, write_output_set};
use super::render::{Canvas, encode_rgb};
use rayon::prelude::*;

use crate::cad::iges::write_surfaces;
use crate::error::{Error, JobError, Result};
use crate::lathe::check::{
    DistanceCheck, ProgramCheck, ProgramSample, centre_errors, check_program, read_grid_csv,
    summarise,
};
use crate::lathe::grid::GridStatistics;
use crate::lathe::offset_surface::piegl_tiller_offset;
use crate::lathe::{
    CompensatedGrid, FaceChoice, GridOptions, LensDescription, LensSurface, PostOptions,
    SpindleSpeed, Spiral, SpiralOptions, compensated_grid, lens_from_iges, post, spiral,
};

/// How far a grid's nose centres may be from ρ off the surface (the 1e-6 mm).
pub const GRID_DISTANCE_TOLERANCE: f64 = 1e-6;

/// What `wavemill lens` is asked for.
#[derive(Clone, Debug, PartialEq)]
pub struct LensOptions {
    /// The IGES face (DE number); `None`: the largest face that is not a plane.
    pub face: Option<usize>,
    /// Grid and nose radius.
    pub grid: GridOptions,
    /// Radial feed per revolution of the spiral (mm).
    pub feed_per_rev: f64,
    /// Form tolerance of the spiral program (mm).
    pub form_tolerance: f64,
    /// Largest angular step between program points (degrees).
    pub max_step_degrees: f64,
    /// Spindle speed.
    pub speed: SpindleSpeed,
    /// The tool's clearance angle (degrees).
    pub clearance_angle_degrees: f64,
    /// Height above the lens's highest centre for the approach and retract (mm).
    pub clearance_height: f64,
    /// Plunge feed to the first point (mm/min).
    pub plunge_feed: f64,
    /// Also build the seed's Piegl–Tiller offset surface to this tolerance (mm) and project
    /// the grid onto it, to compare with the exact compensation (IGES lenses only).
    pub offset_tolerance: Option<f64>,
    /// Whether the report carries timings (without them, repeated runs give identical bytes).
    pub timings: bool,
}

/// A lens surface as loaded.
#[derive(Clone, Debug)]
pub struct LoadedLens {
    /// The surface.
    pub surface: LensSurface,
    /// What it is: `nurbs` or the TOML kind.
    pub kind: String,
    /// For an IGES file, which face.
    pub face: Option<FaceChoice>,
}

/// Reads a lens surface: `.toml` (an analytic description) or `.igs`/`.iges` (the freeform
/// face).
pub fn load_lens(path: &Path, face: Option<usize>) -> Result<LoadedLens> {
    let file = path.display().to_string();
    let bad = |reason: String| Error::Mesh {
        file: file.clone(),
        reason,
    };
    if super::is_iges(path) {
        let model = read_iges_file(path)?;
        let (surface, choice) = lens_from_iges(&model, face).map_err(bad)?;
        return Ok(LoadedLens {
            surface,
            kind: "nurbs".into(),
            face: Some(choice),
        });
    }
    let is_toml = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("toml"));
    if !is_toml {
        return Err(Error::Usage(format!(
            "{file}: a lens surface is a .toml description or an .igs/.iges file"
        )));
    }
    if face.is_some() {
        return Err(Error::Usage(format!(
            "{file}: a face (DE number) can only be chosen in an IGES file"
        )));
    }
    let text = std::fs::read_to_string(path).map_err(|source| Error::Io {
        path: file.clone(),
        source,
    })?;
    let description = LensDescription::from_toml(&text).map_err(bad)?;
    let surface = description.surface().map_err(bad)?;
    Ok(LoadedLens {
        surface,
        kind: description.kind,
        face: None,
    })
}

/// The report, `lens.json`.
#[derive(Clone, Debug, Serialize)]
pub struct LensReport {
    /// The surface file.
    pub surface_file: String,
    /// What the surface is.
    pub kind: String,
    /// The IGES face used.
    pub face: Option<FaceChoice>,
    /// Nose radius (mm).
    pub nose_radius: f64,
    /// The tool's clearance angle (degrees).
    pub clearance_angle_degrees: f64,
    /// The grid.
    pub grid: GridReport,
    /// The spiral program.
    pub spiral: SpiralReport,
    /// The seed's route beside the exact one, when asked for.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub piegl_tiller: Option<PieglTillerReport>,
    /// Stage times in seconds (left out with `--no-timings`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub timings_s: Option<LensTimings>,
}

/// The grid part of the report.
#[derive(Clone, Debug, Serialize)]
pub struct GridReport {
    /// Outer diameter (mm).
    pub diameter: f64,
    /// Radii.
    pub radii: usize,
    /// Angles.
    pub ticks: usize,
    /// Points.
    pub points: usize,
    /// What the solve met.
    pub statistics: GridStatistics,
    /// The written CSV read back: every centre's distance from the surface against ρ.
    pub check: DistanceCheck,
}

/// The spiral part of the report.
#[derive(Clone, Debug, Serialize)]
pub struct SpiralReport {
    /// Feed per revolution (mm).
    pub feed_per_rev: f64,
    /// Radial scallop height `f² / 8ρ` of the nose between turns (mm).
    pub radial_scallop: f64,
    /// Form tolerance (mm).
    pub form_tolerance: f64,
    /// Spindle speed.
    pub speed: SpindleSpeed,
    /// Program points.
    pub points: usize,
    /// Revolutions.
    pub revolutions: f64,
    /// Exact solves made.
    pub solves: usize,
    /// Cutting time (min).
    pub minutes: f64,
    /// The posted program read back and interpolated as the control runs it.
    pub check: ProgramCheck,
}

/// The seed's route: an approximate offset surface, the grid projected onto it.
#[derive(Clone, Debug, Serialize)]
pub struct PieglTillerReport {
    /// The tolerance ε of eq. 3.20 (mm).
    pub tolerance: f64,
    /// Offset samples along u and v.
    pub samples: [usize; 2],
    /// Control points of the interpolating bicubic.
    pub interpolated_control_points: usize,
    /// Knots removed within ε.
    pub knots_removed: usize,
    /// Control points left.
    pub control_points: usize,
    /// Largest distance of the final surface from an offset sample (mm).
    pub sample_error: f64,
    /// Largest second-derivative bounds `M₁, M₂, M₃` over the Bézier patches.
    pub bounds: [f64; 3],
    /// Largest |z − z_exact| over the grid (mm).
    pub max_error: f64,
    /// Root mean square of the same (mm).
    pub rms_error: f64,
    /// Building the offset surface (s; left out with `--no-timings`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub offset_seconds: Option<f64>,
    /// Projecting the grid onto it (s).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub projection_seconds: Option<f64>,
}

/// Stage times (s).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct LensTimings {
    /// Reading the surface.
    pub read: f64,
    /// The compensated grid.
    pub grid: f64,
    /// The spiral's points.
    pub spiral: f64,
    /// Both checks.
    pub check: f64,
    /// Everything.
    pub total: f64,
}

/// Everything `wavemill lens` writes.
#[derive(Clone, Debug)]
pub struct LensOutput {
    /// The report.
    pub report: LensReport,
    /// The grid.
    pub grid: CompensatedGrid,
    /// The spiral.
    pub spiral: Spiral,
    /// The program text.
    pub program: String,
    /// The picture (PNG).
    pub picture: Vec<u8>,
    /// The Piegl–Tiller offset surface as IGES, when asked for.
    pub offset_iges: Option<String>,
}

fn lens_error(file: &str, reason: impl std::fmt::Display) -> Error {
    Error::Mesh {
        file: file.to_string(),
        reason: reason.to_string(),
    }
}

/// Plans, posts and checks a lens from the surface file at `path`.
pub fn lens(path: &Path, options: &LensOptions) -> Result<LensOutput> {
    let file = path.display().to_string();
    let o = options;
    // Option errors name the option (the CLI names its flag in their place).
    let invalid = |key: &str, reason: String| {
        Error::JobFile(JobError::Invalid {
            key: key.to_string(),
            reason,
        })
    };
    for (key, value) in [
        ("feed_per_rev", o.feed_per_rev),
        ("form_tolerance", o.form_tolerance),
        ("max_step_degrees", o.max_step_degrees),
        ("clearance_height", o.clearance_height),
        ("plunge_feed", o.plunge_feed),
    ] {
        if !(value.is_finite() && value > 0.0) {
            return Err(invalid(key, format!("{value}: must be positive")));
        }
    }
    if !(o.clearance_angle_degrees > 0.0 && o.clearance_angle_degrees < 90.0) {
        return Err(invalid(
            "clearance_angle_degrees",
            format!("{}: must be between 0° and 90°", o.clearance_angle_degrees),
        ));
    }
    let start = Instant::now();
    let loaded = load_lens(path, o.face)?;
    let read = start.elapsed().as_secs_f64();
    let t = Instant::now();
    let grid = compensated_grid(&loaded.surface, &o.grid).map_err(|e| match e {
        crate::lathe::GridError::Parameter(p) => Error::Usage(p),
        e => lens_error(&file, e),
    })?;
    let grid_seconds = t.elapsed().as_secs_f64();
    let descent = grid.statistics.steepest_descent;
    if descent.value > o.clearance_angle_degrees {
        return Err(lens_error(
            &file,
            format!(
                "the surface falls {:.3}° along the cut at r = {:.4} mm, θ = {:.3}°: {:.3}° more \
                 than the tool's clearance angle of {}° (its flank would rub the surface just cut)",
                descent.value,
                descent.radius,
                descent.angle_degrees,
                descent.value - o.clearance_angle_degrees,
                o.clearance_angle_degrees
            ),
        ));
    }
    let t = Instant::now();
    let spiral_options = SpiralOptions {
        nose_radius: o.grid.nose_radius,
        outer_radius: o.grid.diameter / 2.0,
        feed_per_rev: o.feed_per_rev,
        form_tolerance: o.form_tolerance,
        max_step: o.max_step_degrees.to_radians(),
        speed: o.speed,
    };
    let turned = spiral(&loaded.surface, &spiral_options).map_err(|e| match e {
        crate::lathe::SpiralError::Parameter(p) => Error::Usage(p),
        e => lens_error(&file, e),
    })?;
    let spiral_seconds = t.elapsed().as_secs_f64();
    let top = grid.z.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let program = post(
        &turned,
        &PostOptions {
            clearance_z: top + o.clearance_height,
            plunge_feed: o.plunge_feed,
            header: vec![
                format!(
                    "wavemill lens: {}",
                    path.file_name()
                        .map_or(file.clone(), |n| n.to_string_lossy().into_owned())
                ),
                format!(
                    "nose radius {} mm, outer diameter {} mm, feed {} mm/rev, form tolerance {} mm",
                    o.grid.nose_radius, o.grid.diameter, o.feed_per_rev, o.form_tolerance
                ),
            ],
        },
    );
    // The checks read what is written.
    let t = Instant::now();
    let csv = grid.csv();
    let centres = read_grid_csv(&csv).map_err(|e| Error::Internal(format!("grid.csv: {e}")))?;
    let errors = centre_errors(&loaded.surface, o.grid.nose_radius, &centres);
    let grid_check = summarise(&centres, &errors);
    const SAMPLES_PER_BLOCK: usize = 4;
    let (program_check, samples) = check_program(
        &loaded.surface,
        o.grid.nose_radius,
        &program,
        SAMPLES_PER_BLOCK,
    )
    .map_err(|e| Error::Internal(format!("lens.nc: {e}")))?;
    let check_seconds = t.elapsed().as_secs_f64();
    let mut report = LensReport {
        surface_file: file.clone(),
        kind: loaded.kind.clone(),
        face: loaded.face.clone(),
        nose_radius: o.grid.nose_radius,
        clearance_angle_degrees: o.clearance_angle_degrees,
        grid: GridReport {
            diameter: o.grid.diameter,
            radii: grid.grid.radii.len(),
            ticks: grid.grid.angles.len(),
            points: grid.grid.len(),
            statistics: grid.statistics,
            check: grid_check,
        },
        spiral: SpiralReport {
            feed_per_rev: o.feed_per_rev,
            radial_scallop: o.feed_per_rev * o.feed_per_rev
                / (8.0 * o.grid.nose_radius.max(1e-300)),
            form_tolerance: o.form_tolerance,
            speed: o.speed,
            points: turned.points.len(),
            revolutions: turned.revolutions,
            solves: turned.solves,
            minutes: turned.seconds / 60.0,
            check: program_check,
        },
        piegl_tiller: None,
        timings_s: o.timings.then_some(LensTimings {
            read,
            grid: grid_seconds,
            spiral: spiral_seconds,
            check: check_seconds,
            total: start.elapsed().as_secs_f64(),
        }),
    };
    let (piegl_tiller, offset_iges) = match o.offset_tolerance {
        None => (None, None),
        Some(tolerance) => {
            let (report, iges) = seed_route(&loaded.surface, &grid, o, tolerance, &file)?;
            (Some(report), Some(iges))
        }
    };
    report.piegl_tiller = piegl_tiller;
    let picture = picture(&grid, &samples, o.form_tolerance)
        .map_err(|e| Error::Internal(format!("lens.png: {e}")))?;
    Ok(LensOutput {
        report,
        grid,
        spiral: turned,
        program,
        picture,
        offset_iges,
    })
}

/// The seed's route on the same grid: the Piegl–Tiller offset, then every grid line projected
/// onto it, compared with the exact heights.
fn seed_route(
    surface: &LensSurface,
    grid: &CompensatedGrid,
    o: &LensOptions,
    tolerance: f64,
    file: &str,
) -> Result<(PieglTillerReport, String)> {
    let t = Instant::now();
    let offset = piegl_tiller_offset(surface, o.grid.nose_radius, tolerance)
        .map_err(|e| lens_error(file, format!("Piegl–Tiller offset: {e}")))?;
    let offset_seconds = t.elapsed().as_secs_f64();
    let projected = offset
        .as_lens()
        .ok_or_else(|| lens_error(file, "Piegl–Tiller offset: too many patches to evaluate"))?;
    let t = Instant::now();
    let ticks = grid.grid.angles.len();
    let heights: Vec<Option<f64>> = (0..grid.z.len())
        .into_par_iter()
        .map(|k| {
            let (r, a) = (grid.grid.radii[k / ticks], grid.grid.angles[k % ticks]);
            let (x, y) = (r * a.cos(), r * a.sin());
            projected
                .parameters_over(x, y)
                .map(|(u, v)| projected.jet(u, v).point.z)
        })
        .collect();
    let projection_seconds = t.elapsed().as_secs_f64();
    let mut max_error = 0.0f64;
    let mut sum = 0.0;
    for (k, h) in heights.iter().enumerate() {
        let Some(h) = h else {
            return Err(lens_error(
                file,
                format!(
                    "Piegl–Tiller offset: grid point r = {:.4}, θ = {:.3}° lies beyond the offset surface",
                    grid.grid.radii[k / ticks],
                    grid.grid.angles[k % ticks].to_degrees()
                ),
            ));
        };
        let e = h - grid.z[k];
        max_error = max_error.max(e.abs());
        sum += e * e;
    }
    let iges = write_surfaces(&[(offset.surface.clone(), offset.domain)], "offset.igs");
    Ok((
        PieglTillerReport {
            tolerance,
            samples: [offset.samples.0, offset.samples.1],
            interpolated_control_points: offset.interpolated_control_points,
            knots_removed: offset.knots_removed,
            control_points: offset.control_points(),
            sample_error: offset.sample_error,
            bounds: offset.bounds,
            max_error,
            rms_error: (sum / heights.len().max(1) as f64).sqrt(),
            offset_seconds: o.timings.then_some(offset_seconds),
            projection_seconds: o.timings.then_some(projection_seconds),
        },
        iges,
    ))
}

/// What failed in the checks of a lens output, if anything.
pub fn lens_failure(report: &LensReport) -> Option<String> {
    let g = &report.grid.check;
    let p = &report.spiral.check.interpolated;
    if g.no_foot > 0 || g.wrong_side > 0 || g.max_error > GRID_DISTANCE_TOLERANCE {
        return Some(format!(
            "grid: {} centre(s) without a foot, {} on the wrong side, largest distance error \
             {:.3e} mm (allowed {GRID_DISTANCE_TOLERANCE:e})",
            g.no_foot, g.wrong_side, g.max_error
        ));
    }
    if p.no_foot > 0 || p.wrong_side > 0 || p.max_error > report.spiral.form_tolerance {
        return Some(format!(
            "program: {} interpolated centre(s) without a foot, {} on the wrong side, largest \
             form error {:.3e} mm (tolerance {})",
            p.no_foot, p.wrong_side, p.max_error, report.spiral.form_tolerance
        ));
    }
    None
}

/// Writes the outputs into `dir`, all or nothing; when a check failed, only `lens.json`, and
/// returns the failure (exit 3).
pub fn write_lens_outputs(dir: &Path, output: &LensOutput) -> Result<()> {
    let json = serde_json::to_vec_pretty(&output.report)
        .map_err(|e| Error::Internal(format!("lens.json: {e}")))?;
    let mut files = vec![("lens.json".to_string(), json)];
    if let Some(problem) = lens_failure(&output.report) {
        write_output_set(dir, &OutputKind::LENS, &files)?;
        return Err(Error::Verification(format!(
            "{problem} (see {})",
            dir.join("lens.json").display()
        )));
    }
    files.push(("grid.csv".into(), output.grid.csv().into_bytes()));
    files.push(("grid.bin".into(), output.grid.binary()));
    files.push(("lens.nc".into(), output.program.clone().into_bytes()));
    files.push(("lens.png".into(), output.picture.clone()));
    if let Some(iges) = &output.offset_iges {
        files.push(("offset.igs".into(), iges.clone().into_bytes()));
    }
    write_output_set(dir, &OutputKind::LENS, &files)
}

/// A colour of the ramp dark blue → teal → yellow for `t ∈ [0, 1]`.
fn ramp(t: f64) -> [u8; 3] {
    const STOPS: [[f64; 3]; 4] = [
        [40.0, 30.0, 110.0],
        [30.0, 120.0, 160.0],
        [90.0, 190.0, 90.0],
        [250.0, 230.0, 40.0],
    ];
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        1.0
    };
    let x = t * (STOPS.len() - 1) as f64;
    let k = (x.floor() as usize).min(STOPS.len() - 2);
    let f = x - k as f64;
    let mut c = [0u8; 3];
    for (i, v) in c.iter_mut().enumerate() {
        *v = (STOPS[k][i] + (STOPS[k + 1][i] - STOPS[k][i]) * f).round() as u8;
    }
    c
}

/// Two discs side by side: the nose-centre heights of the grid (nearest grid point per pixel)
/// and the program's form error as interpolated (largest per pixel, full scale = the
/// tolerance; red beyond it), each with its range written below.
fn picture(
    grid: &CompensatedGrid,
    samples: &[ProgramSample],
    tolerance: f64,
) -> std::result::Result<Vec<u8>, png::EncodingError> {
    const SIDE: usize = 360;
    const MARGIN: usize = 20;
    const LEGEND: usize = 40;
    let mut canvas = Canvas::new(2 * SIDE + 3 * MARGIN, SIDE + 2 * MARGIN + LEGEND);
    let outer = grid.grid.radii.last().copied().unwrap_or(1.0).max(1e-9);
    let half = SIDE as f64 / 2.0;
    let to_plane = |px: usize, py: usize| {
        (
            (px as f64 + 0.5 - half) / half * outer,
            (half - py as f64 - 0.5) / half * outer,
        )
    };
    let (lo, hi) = grid
        .z
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &z| {
            (a.min(z), b.max(z))
        });
    let ticks = grid.grid.angles.len();
    let radial_step = outer / (grid.grid.radii.len().max(2) - 1) as f64;
    for py in 0..SIDE {
        for px in 0..SIDE {
            let (x, y) = to_plane(px, py);
            let r = x.hypot(y);
            if r > outer {
                continue;
            }
            let i = ((r / radial_step).round() as usize).min(grid.grid.radii.len() - 1);
            let a = y.atan2(x).rem_euclid(std::f64::consts::TAU);
            let j = ((a / std::f64::consts::TAU * ticks as f64).round() as usize) % ticks;
            let z = grid.z[i * ticks + j];
            let t = if hi > lo { (z - lo) / (hi - lo) } else { 0.5 };
            canvas.put(MARGIN + px, MARGIN + py, ramp(t));
        }
    }
    // Form error: largest per pixel.
    let mut worst = vec![f64::NAN; SIDE * SIDE];
    for s in samples {
        let (p, e) = (s.centre, s.error);
        let px = ((p.x / outer * half) + half).floor();
        let py = (half - (p.y / outer * half)).floor();
        if !(0.0..SIDE as f64).contains(&px) || !(0.0..SIDE as f64).contains(&py) {
            continue;
        }
        let k = py as usize * SIDE + px as usize;
        let e = e.map_or(f64::INFINITY, f64::abs);
        if worst[k].is_nan() || e > worst[k] {
            worst[k] = e;
        }
    }
    // Samples lie along the passes, a few pixels apart near the rim of a step: fill the gaps
    // between them from their neighbours (largest), inside the disc only.
    for _ in 0..4 {
        let before = worst.clone();
        for py in 0..SIDE {
            for px in 0..SIDE {
                let k = py * SIDE + px;
                let (x, y) = to_plane(px, py);
                if !before[k].is_nan() || x.hypot(y) > outer {
                    continue;
                }
                let mut fill = f64::NAN;
                for (dx, dy) in [(-1i64, 0i64), (1, 0), (0, -1), (0, 1)] {
                    let (qx, qy) = (px as i64 + dx, py as i64 + dy);
                    if (0..SIDE as i64).contains(&qx) && (0..SIDE as i64).contains(&qy) {
                        let v = before[qy as usize * SIDE + qx as usize];
                        if !v.is_nan() && (fill.is_nan() || v > fill) {
                            fill = v;
                        }
                    }
                }
                worst[k] = fill;
            }
        }
    }
    for py in 0..SIDE {
        for px in 0..SIDE {
            let e = worst[py * SIDE + px];
            if e.is_nan() {
                continue;
            }
            let colour = if e > tolerance {
                [220, 30, 30]
            } else {
                ramp(e / tolerance)
            };
            canvas.put(2 * MARGIN + SIDE + px, MARGIN + py, colour);
        }
    }
    let dark = [40, 40, 40];
    let legend_y = SIDE + MARGIN + 12;
    for (k, x0) in [MARGIN, 2 * MARGIN + SIDE].into_iter().enumerate() {
        for s in 0..SIDE {
            let colour = ramp(s as f64 / (SIDE - 1) as f64);
            canvas.fill(x0 + s, legend_y, 1, 8, colour);
        }
        let (left, right) = if k == 0 {
            (format!("{lo:.4}mm"), format!("{hi:.4}mm"))
        } else {
            ("0".to_string(), format!("{tolerance}mm"))
        };
        canvas.text(x0, legend_y + 12, &left, 2, dark);
        let width = right.len() * 8;
        canvas.text(
            x0 + SIDE.saturating_sub(width),
            legend_y + 12,
            &right,
            2,
            dark,
        );
    }
    encode_rgb(canvas.w, canvas.h, &canvas.px)
}
