//! Parsers of command-line values: each refuses a bad value with a message clap shows, and
//! the exit code 2 of a bad command line.

use std::path::PathBuf;

use super::{ball_diameter, flat_diameter};
use crate::job;

/// Parses a direction `x,y,z`: three finite numbers, not all zero (any length: it is
/// normalised).
pub(crate) fn parse_vector(text: &str) -> std::result::Result<[f64; 3], String> {
    let parts: Vec<f64> = text
        .split(',')
        .map(|p| p.trim().parse::<f64>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| format!("`{text}`: expected three numbers x,y,z"))?;
    let v = <[f64; 3]>::try_from(parts)
        .map_err(|_| format!("`{text}`: expected three numbers x,y,z"))?;
    job::unit_direction(v)
        .map(|_| v)
        .ok_or_else(|| format!("`{text}`: expected a direction (finite, not all zero)"))
}

/// A finite number > 0.
pub(crate) fn positive(text: &str) -> std::result::Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("`{text}`: expected a positive number")),
    }
}

/// A share: a number in (0, 1].
pub(crate) fn share(text: &str) -> std::result::Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(v) if v > 0.0 && v <= 1.0 => Ok(v),
        _ => Err(format!("`{text}`: expected a share in (0, 1]")),
    }
}

/// A finite number ≥ 0.
pub(crate) fn non_negative(text: &str) -> std::result::Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
        _ => Err(format!("`{text}`: expected a number >= 0")),
    }
}

/// An angle between two faces, 0 to 180 degrees.
pub(crate) fn face_angle(text: &str) -> std::result::Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(v) if (0.0..=180.0).contains(&v) => Ok(v),
        _ => Err(format!("`{text}`: expected an angle from 0 to 180 degrees")),
    }
}

/// `mm`, `m` or `in` (or their long names).
pub(crate) fn units(text: &str) -> std::result::Result<String, String> {
    text.parse::<crate::mesh::io::Units>()
        .map(|_| text.to_string())
        .map_err(|e| e.to_string())
}

/// Most worker threads accepted: more only costs start-up time (a thread each) and memory.
pub(crate) const MAX_THREADS: usize = 256;

/// A tilt from the normal, 0 to 90 degrees.
pub(crate) fn tilt(text: &str) -> std::result::Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(v) if (0.0..=90.0).contains(&v) => Ok(v),
        _ => Err(format!("`{text}`: expected an angle from 0 to 90 degrees")),
    }
}

/// Grid cells across the part, 4 to 2000.
pub(crate) fn grid_cells(text: &str) -> std::result::Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(v) if (4.0..=2000.0).contains(&v) => Ok(v),
        _ => Err(format!(
            "`{text}`: expected a number of cells from 4 to 2000"
        )),
    }
}

/// A thread count from 1 to [`MAX_THREADS`].
pub(crate) fn threads(text: &str) -> std::result::Result<usize, String> {
    match text.trim().parse::<usize>() {
        Ok(n) if (1..=MAX_THREADS).contains(&n) => Ok(n),
        _ => Err(format!(
            "`{text}`: expected a thread count from 1 to {MAX_THREADS}"
        )),
    }
}

/// A cutter spec `ball:D` for a command that drives a ball-end mill.
pub(crate) fn ball_spec(text: &str) -> std::result::Result<String, String> {
    ball_diameter(text)
        .map(|_| text.to_string())
        .map_err(|e| e.to_string())
}

/// Any cutter spec (`ball:D`, `flat:D`, `bull:D:R`, `taper:D:DEG`), checked.
pub(crate) fn cutter_spec(text: &str) -> std::result::Result<String, String> {
    crate::tool::parse_cutter(text)
        .map(|_| text.to_string())
        .map_err(|e| e.to_string())
}

/// A flat end mill `flat:D`: its diameter, mm.
pub(crate) fn flat_tool(text: &str) -> std::result::Result<f64, String> {
    flat_diameter(text).map_err(|e| e.to_string())
}

/// A stock `margin:M` (M ≥ 0 mm) or `outline:FILE` (an SVG or DXF file).
pub(crate) fn stock(text: &str) -> std::result::Result<job::StockSpec, String> {
    let bad = || {
        format!(
            "`{text}`: expected margin:M with M ≥ 0 mm (e.g. margin:10) or outline:FILE with \
             an .svg or .dxf file"
        )
    };
    let (kind, value) = text.split_once(':').ok_or_else(bad)?;
    match kind.trim() {
        "margin" => match value.trim().parse::<f64>() {
            Ok(m) if m.is_finite() && m >= 0.0 => Ok(job::StockSpec::Margin(m)),
            _ => Err(bad()),
        },
        "outline" if !value.trim().is_empty() => Ok(job::StockSpec::Outline(PathBuf::from(value))),
        _ => Err(bad()),
    }
}

/// A blank: `box:X0,Y0,Z0,X1,Y1,Z1`, `cylinder:R,Z0,Z1`, `offset:M` or `mesh:FILE` (mm).
pub(crate) fn blank(text: &str) -> std::result::Result<job::BlankSpec, String> {
    job::BlankSpec::parse(text)
}
