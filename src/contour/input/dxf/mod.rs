//! DXF outline reader (ASCII or binary).
//!
//! Model-space LINE, ARC, CIRCLE, ELLIPSE (full and partial), LWPOLYLINE and POLYLINE (bulges,
//! closed flag; spline-frame vertices skipped) and SPLINE (NURBS from degree, knots, control
//! points and weights; fit-point-only splines are unsupported) become chains of lines and arcs.
//! Open chains are joined into loops by matching endpoints within 1e-6 × the drawing size (at
//! least 1e-9 mm); a polyline closed by repeating its first point counts as closed.
//!
//! Units: `$INSUNITS` (inches, feet, mm, cm, m, µm, …) converted to mm; unitless → mm; then
//! times [`OutlineOptions::scale`]. Not y-flipped. Entities with extrusion direction (0, 0, −1)
//! are mirrored as their object coordinate system requires; other extrusion directions are
//! errors. Z is ignored. INSERT (block references) is an error; text, dimensions, hatches,
//! points, meshes and other entities without an outline are ignored. Loops are combined with
//! the even-odd rule (DXF records no fill rule and its loop directions are arbitrary).
//!
//! The file is read by our own group-code reader (`groups`, `drawing`): an outline needs seven
//! entity types and one header variable, and the general-purpose `dxf` crate, with its image
//! library for thumbnails, was a quarter of the dependencies' build time on 2-core CI and
//! panicked on some malformed files.

mod drawing;
mod groups;

use std::collections::HashMap;
use std::f64::consts::TAU;

use nalgebra::Matrix2;

use self::drawing::Entity;
use super::curves::{EllipseArc, Nurbs, fit_curve};
use super::fill::{FillRule, build_region};
use super::{Chain, OutlineError, OutlineOptions, RawContour, points_size};
use crate::contour::geometry::{Point2, Shape};

struct Piece {
    chain: Chain,
    closed: bool,
    label: String,
}

/// Reads DXF bytes into a region.
pub(crate) fn read(
    bytes: &[u8],
    file: &str,
    options: &OutlineOptions,
) -> Result<Shape, OutlineError> {
    let parse = |message: String| OutlineError::Parse {
        file: file.into(),
        message,
    };
    let groups = groups::read_groups(bytes).map_err(parse)?;
    let drawing = drawing::drawing(groups).map_err(parse)?;
    let unit = unit_mm(drawing.units).ok_or_else(|| OutlineError::Unsupported {
        file: file.into(),
        what: "$INSUNITS".into(),
        message: format!("drawing units code {}", drawing.units),
    })?;
    let k = unit * options.scale;
    let tol = options.tolerance;
    let mut pieces = Vec::new();
    for e in &drawing.entities {
        if e.in_paper_space() {
            continue;
        }
        if let Some(p) = entity_piece(e, k, tol, file)? {
            pieces.push(p);
        }
    }
    for p in &pieces {
        let finite = p
            .chain
            .vertices
            .iter()
            .all(|v| v.point.x.is_finite() && v.point.y.is_finite() && v.bulge.is_finite())
            && p.chain.end.x.is_finite()
            && p.chain.end.y.is_finite();
        if !finite {
            return Err(OutlineError::Invalid {
                file: file.into(),
                what: p.label.clone(),
                message: "coordinates are not finite".into(),
            });
        }
    }
    if pieces.is_empty() {
        return Err(OutlineError::NoClosedShape {
            file: file.into(),
            detail: " (no LINE, ARC, CIRCLE, ELLIPSE, POLYLINE or SPLINE in model space)".into(),
        });
    }
    let size = points_size(pieces.iter().flat_map(|p| {
        p.chain
            .vertices
            .iter()
            .map(|v| &v.point)
            .chain([&p.chain.end])
    }));
    let eps = (1e-6 * size).max(1e-9);
    let contours = chain_pieces(pieces, eps, file)?;
    build_region(contours, file, tol)
}

/// Millimetres per drawing unit, from the `$INSUNITS` code (DXF reference, HEADER section).
/// `None` for the astronomical units and codes the reference does not define.
fn unit_mm(code: i64) -> Option<f64> {
    Some(match code {
        0 | 4 => 1.0,               // unitless, millimetres
        1 => 25.4,                  // inches
        2 => 304.8,                 // feet
        3 => 1_609_344.0,           // miles
        5 => 10.0,                  // centimetres
        6 => 1000.0,                // metres
        7 => 1.0e6,                 // kilometres
        8 => 25.4e-6,               // microinches
        9 => 0.0254,                // mils
        10 => 914.4,                // yards
        11 => 1.0e-7,               // ångströms
        12 => 1.0e-6,               // nanometres
        13 => 1.0e-3,               // microns
        14 => 100.0,                // decimetres
        15 => 1.0e4,                // decametres
        16 => 1.0e5,                // hectometres
        21 => 1_200_000.0 / 3937.0, // US survey feet
        _ => return None,
    })
}

/// Whether the object coordinate system of `normal` mirrors x (normal −Z); `None` when the
/// entity does not lie in a plane parallel to XY.
fn ocs_mirror(n: [f64; 3]) -> Option<bool> {
    let [x, y, z] = n;
    let len = (x * x + y * y + z * z).sqrt();
    if len == 0.0 {
        return Some(false);
    }
    if !len.is_finite() || x.abs() > 1e-9 * len || y.abs() > 1e-9 * len {
        return None;
    }
    Some(z < 0.0)
}

/// The default extrusion direction of every planar entity.
const Z_AXIS: [f64; 3] = [0.0, 0.0, 1.0];

fn entity_piece(e: &Entity, k: f64, tol: f64, file: &str) -> Result<Option<Piece>, OutlineError> {
    let name = e.kind.as_str();
    let label = match e.handle() {
        Some(handle) => format!("{name} (handle {handle}, layer \"{}\")", e.layer()),
        None => format!("{name} ({}, layer \"{}\")", e.place, e.layer()),
    };
    let invalid = |message: String| OutlineError::Invalid {
        file: file.into(),
        what: label.clone(),
        message,
    };
    let mirror_of = |n: [f64; 3]| {
        ocs_mirror(n).ok_or_else(|| {
            invalid("its extrusion direction is not ±Z (not in the XY plane)".into())
        })
    };
    let pt = |x: f64, y: f64, mirror: bool| Point2::new(if mirror { -x * k } else { x * k }, y * k);
    let piece = match name {
        "LINE" => {
            let (p1, p2) = (
                e.point(10, [0.0; 3]).map_err(invalid)?,
                e.point(11, [0.0; 3]).map_err(invalid)?,
            );
            let (a, b) = (pt(p1[0], p1[1], false), pt(p2[0], p2[1], false));
            if a == b {
                return Ok(None);
            }
            let mut chain = Chain::new(a);
            chain.push(b, 0.0);
            Piece {
                chain,
                closed: false,
                label,
            }
        }
        "ARC" | "CIRCLE" => {
            let mirror = mirror_of(e.point(210, Z_AXIS).map_err(invalid)?)?;
            let center = e.point(10, [0.0; 3]).map_err(invalid)?;
            let radius = e.real(40, 0.0).map_err(invalid)?;
            if !(radius > 0.0 && radius.is_finite()) {
                return Err(invalid(format!("radius {radius} is not positive")));
            }
            let (start, sweep) = if name == "CIRCLE" {
                (0.0, 360.0)
            } else {
                let start = e.real(50, 0.0).map_err(invalid)?;
                let end = e.real(51, 360.0).map_err(invalid)?;
                if !(start.is_finite() && end.is_finite()) {
                    return Err(invalid("angles are not finite".into()));
                }
                let sweep = (end - start).rem_euclid(360.0);
                (start, if sweep == 0.0 { 360.0 } else { sweep })
            };
            let arc = ocs_arc(
                pt(center[0], center[1], mirror),
                radius * k,
                mirror,
                start.to_radians(),
                sweep.to_radians(),
            );
            arc_piece(&arc, sweep >= 360.0, tol, label)
        }
        "ELLIPSE" => {
            // Centre and major axis are in world coordinates; the parameter runs
            // counter-clockwise about the normal, so the minor axis is ratio · (N × major).
            let n = e.point(210, Z_AXIS).map_err(invalid)?;
            mirror_of(n)?;
            let nz = if n[2] < 0.0 { -1.0 } else { 1.0 };
            let center = e.point(10, [0.0; 3]).map_err(invalid)?;
            let major = e.point(11, [1.0, 0.0, 0.0]).map_err(invalid)?;
            let (mx, my) = (major[0] * k, major[1] * k);
            let r = e.real(40, 1.0).map_err(invalid)?;
            if !(r > 0.0 && r.is_finite()) || (mx == 0.0 && my == 0.0) {
                return Err(invalid("degenerate axes".into()));
            }
            let m = Matrix2::new(mx, -nz * r * my, my, nz * r * mx);
            let s = e.real(41, 0.0).map_err(invalid)?;
            let mut d = e.real(42, TAU).map_err(invalid)? - s;
            if !(s.is_finite() && d.is_finite()) {
                return Err(invalid("parameters are not finite".into()));
            }
            d = d.rem_euclid(TAU);
            let full = d <= 1e-12 || d >= TAU - 1e-12;
            if full {
                d = TAU;
            }
            let arc = EllipseArc {
                center: pt(center[0], center[1], false),
                m,
                theta0: s,
                dtheta: d,
            };
            arc_piece(&arc, full, tol, label)
        }
        "LWPOLYLINE" => {
            let mirror = mirror_of(e.point(210, Z_AXIS).map_err(invalid)?)?;
            let sign = if mirror { -1.0 } else { 1.0 };
            // Each 10 starts a vertex; the 20 and 42 after it are its y and bulge.
            let mut vs: Vec<(f64, f64, f64)> = Vec::new();
            for g in &e.groups {
                let number = || g.number().map_err(invalid);
                match (g.code, vs.last_mut()) {
                    (10, _) => vs.push((number()?, 0.0, 0.0)),
                    (20, Some(v)) => v.1 = number()?,
                    (42, Some(v)) => v.2 = number()?,
                    _ => {}
                }
            }
            let vs: Vec<(Point2, f64)> = vs
                .into_iter()
                .map(|(x, y, bulge)| (pt(x, y, mirror), bulge * sign))
                .collect();
            let closed = e.integer(70, 0).map_err(invalid)? & 1 != 0;
            poly_piece(&vs, closed, label)
        }
        "POLYLINE" => {
            let flags = e.integer(70, 0).map_err(invalid)?;
            // Polyface meshes (64) and polygon meshes (16) are surfaces, not outlines.
            if flags & (16 | 64) != 0 {
                return Ok(None);
            }
            let three_d = flags & 8 != 0;
            // 3D polylines are in world coordinates and have no bulges.
            let mirror = if three_d {
                false
            } else {
                mirror_of(e.point(210, Z_AXIS).map_err(invalid)?)?
            };
            let sign = if mirror { -1.0 } else { 1.0 };
            let mut vs: Vec<(Point2, f64)> = Vec::new();
            for v in &e.vertices {
                // Spline-frame control points (16) are not on the curve.
                if v.integer(70, 0).map_err(invalid)? & 16 != 0 {
                    continue;
                }
                let at = v.point(10, [0.0; 3]).map_err(invalid)?;
                let bulge = if three_d {
                    0.0
                } else {
                    v.real(42, 0.0).map_err(invalid)? * sign
                };
                vs.push((pt(at[0], at[1], mirror), bulge));
            }
            poly_piece(&vs, flags & 1 != 0, label)
        }
        "SPLINE" => {
            // Control points, knots and weights repeat their codes, in order.
            let mut control: Vec<Point2> = Vec::new();
            let (mut knots, mut weights) = (Vec::new(), Vec::new());
            for g in &e.groups {
                let number = || g.number().map_err(invalid);
                match g.code {
                    10 => control.push(Point2::new(number()?, 0.0)),
                    20 => {
                        if let Some(c) = control.last_mut() {
                            c.y = number()?;
                        }
                    }
                    40 => knots.push(number()?),
                    41 => weights.push(number()?),
                    _ => {}
                }
            }
            if control.is_empty() {
                return Err(OutlineError::Unsupported {
                    file: file.into(),
                    what: label,
                    message: "splines defined only by fit points".into(),
                });
            }
            let pts: Vec<Point2> = control.iter().map(|c| pt(c.x, c.y, false)).collect();
            let degree = usize::try_from(e.integer(71, 1).map_err(invalid)?).unwrap_or(0);
            let nurbs = Nurbs::new(degree, knots, &pts, &weights).map_err(invalid)?;
            let spans = nurbs.spans();
            let Some(&s0) = spans.first() else {
                return Ok(None);
            };
            let (first, a0, _) = nurbs.span(s0);
            let start = super::curves::Curve::eval(&first, a0).p;
            let mut chain = Chain::new(start);
            for &s in &spans {
                let (c, a, b) = nurbs.span(s);
                let end = super::curves::Curve::eval(&c, b).p;
                let vs = fit_curve(&c, a, b, tol);
                if vs.is_empty() {
                    if end != chain.end {
                        chain.push(end, 0.0);
                    }
                } else {
                    chain.extend(&vs, end);
                }
            }
            if chain.is_empty() {
                return Ok(None);
            }
            Piece {
                chain,
                closed: false,
                label,
            }
        }
        "INSERT" => {
            return Err(OutlineError::Unsupported {
                file: file.into(),
                what: label,
                message: "block references (INSERT); explode the blocks first".into(),
            });
        }
        _ => return Ok(None),
    };
    Ok(Some(piece))
}

/// A circular arc in an object coordinate system that may mirror x: angles are measured in the
/// OCS, so mirroring turns counter-clockwise arcs clockwise.
fn ocs_arc(center: Point2, r: f64, mirror: bool, start: f64, sweep: f64) -> EllipseArc {
    let sx = if mirror { -r } else { r };
    EllipseArc {
        center,
        m: Matrix2::new(sx, 0.0, 0.0, r),
        theta0: start,
        dtheta: sweep,
    }
}

fn arc_piece(arc: &EllipseArc, full: bool, tol: f64, label: String) -> Piece {
    let start = arc.start();
    let end = if full { start } else { arc.end() };
    let mut chain = Chain::new(start);
    arc.emit(tol, end, &mut chain);
    Piece {
        chain,
        closed: full,
        label,
    }
}

fn poly_piece(vs: &[(Point2, f64)], closed_flag: bool, label: String) -> Piece {
    let mut chain = Chain::new(vs.first().map_or(Point2::origin(), |v| v.0));
    for w in vs.windows(2) {
        chain.push(w[1].0, w[0].1);
    }
    if closed_flag && vs.len() > 1 {
        let (first, last) = (vs[0], vs[vs.len() - 1]);
        chain.push(first.0, last.1);
    }
    Piece {
        chain,
        closed: closed_flag,
        label,
    }
}

/// Joins pieces into closed contours by their endpoints.
fn chain_pieces(pieces: Vec<Piece>, eps: f64, file: &str) -> Result<Vec<RawContour>, OutlineError> {
    let mut out = Vec::new();
    let mut open: Vec<Piece> = Vec::new();
    for p in pieces {
        if p.chain.is_empty() {
            continue;
        }
        if p.closed || (p.chain.end - p.chain.start()).norm() <= eps {
            out.push(RawContour {
                vertices: p.chain.into_closed_vertices(),
                label: p.label,
                rule: FillRule::EvenOdd,
            });
        } else {
            open.push(p);
        }
    }
    // Endpoints hashed on a grid of cell 2·eps: a match within eps lies in one of the 3 × 3
    // cells around a point, so joining n pieces costs O(n) instead of O(n²).
    let cell = 2.0 * eps;
    let key = |p: Point2| ((p.x / cell).floor() as i64, (p.y / cell).floor() as i64);
    let mut grid: HashMap<(i64, i64), Vec<(usize, bool)>> = HashMap::new();
    for (j, p) in open.iter().enumerate() {
        grid.entry(key(p.chain.start()))
            .or_default()
            .push((j, false));
        grid.entry(key(p.chain.end)).or_default().push((j, true));
    }
    let mut used = vec![false; open.len()];
    for i in 0..open.len() {
        if used[i] {
            continue;
        }
        used[i] = true;
        let mut chain = open[i].chain.clone();
        let mut labels = vec![open[i].label.clone()];
        loop {
            if (chain.end - chain.start()).norm() <= eps {
                break;
            }
            // The nearest free endpoint within tolerance (lowest index on ties).
            let (kx, ky) = key(chain.end);
            let mut best: Option<(f64, usize, bool)> = None;
            for dx in -1..=1 {
                for dy in -1..=1 {
                    let Some(cands) = grid.get(&(kx.saturating_add(dx), ky.saturating_add(dy)))
                    else {
                        continue;
                    };
                    for &(j, rev) in cands {
                        if used[j] {
                            continue;
                        }
                        let q = if rev {
                            open[j].chain.end
                        } else {
                            open[j].chain.start()
                        };
                        let d = (q - chain.end).norm();
                        let better =
                            best.is_none_or(|b| d < b.0 || (d == b.0 && (j, rev) < (b.1, b.2)));
                        if d <= eps && better {
                            best = Some((d, j, rev));
                        }
                    }
                }
            }
            let Some((_, j, rev)) = best else {
                let gap = (chain.end - chain.start()).norm();
                let what = chain_label(&labels);
                return Err(OutlineError::Open {
                    file: file.into(),
                    what,
                    gap,
                    x: chain.end.x,
                    y: chain.end.y,
                });
            };
            used[j] = true;
            let next = if rev {
                open[j].chain.reversed()
            } else {
                open[j].chain.clone()
            };
            chain.extend(&next.vertices, next.end);
            labels.push(open[j].label.clone());
        }
        out.push(RawContour {
            vertices: chain.into_closed_vertices(),
            label: chain_label(&labels),
            rule: FillRule::EvenOdd,
        });
    }
    Ok(out)
}

fn chain_label(labels: &[String]) -> String {
    match labels.len() {
        0 => "empty chain".into(),
        1 => labels[0].clone(),
        n if n <= 4 => format!("the loop of {}", labels.join(", ")),
        n => format!(
            "the loop of {}, {} and {} more",
            labels[0],
            labels[1],
            n - 2
        ),
    }
}

#[cfg(test)]
mod tests;
