//! DXF outline reader (ASCII or binary, via the `dxf` crate).
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

use std::collections::HashMap;
use std::f64::consts::TAU;

use dxf::entities::{Entity, EntityType};
use dxf::enums::Units;
use dxf::{Drawing, Vector};
use nalgebra::Matrix2;

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
    // The dxf crate indexes into its input in places; a malformed file must still not panic
    // out of this library.
    let loaded = std::panic::catch_unwind(|| Drawing::load(&mut std::io::Cursor::new(bytes)))
        .map_err(|_| parse("the DXF reader failed on malformed input".into()))?;
    let drawing = loaded.map_err(|e| parse(format!("not a readable DXF file: {e}")))?;
    let unit =
        unit_mm(drawing.header.default_drawing_units).ok_or_else(|| OutlineError::Unsupported {
            file: file.into(),
            what: "$INSUNITS".into(),
            message: format!("drawing units {:?}", drawing.header.default_drawing_units),
        })?;
    let k = unit * options.scale;
    let tol = options.tolerance;
    let mut pieces = Vec::new();
    for e in drawing.entities() {
        if e.common.is_in_paper_space {
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

/// Millimetres per drawing unit.
fn unit_mm(u: Units) -> Option<f64> {
    Some(match u {
        Units::Unitless | Units::Millimeters => 1.0,
        Units::Inches => 25.4,
        Units::Feet => 304.8,
        Units::Yards => 914.4,
        Units::Mils => 0.0254,
        Units::Microinches => 25.4e-6,
        Units::Centimeters => 10.0,
        Units::Decimeters => 100.0,
        Units::Meters => 1000.0,
        Units::Microns => 1e-3,
        Units::Nanometers => 1e-6,
        _ => return None,
    })
}

/// Whether the object coordinate system of `normal` mirrors x (normal −Z); `None` when the
/// entity does not lie in a plane parallel to XY.
fn ocs_mirror(n: &Vector) -> Option<bool> {
    let len = (n.x * n.x + n.y * n.y + n.z * n.z).sqrt();
    if len == 0.0 {
        return Some(false);
    }
    if !len.is_finite() || n.x.abs() > 1e-9 * len || n.y.abs() > 1e-9 * len {
        return None;
    }
    Some(n.z < 0.0)
}

fn entity_piece(e: &Entity, k: f64, tol: f64, file: &str) -> Result<Option<Piece>, OutlineError> {
    let name = entity_name(&e.specific);
    let label = format!(
        "{name} (handle {}, layer \"{}\")",
        e.common.handle.as_string(),
        e.common.layer
    );
    let invalid = |message: String| OutlineError::Invalid {
        file: file.into(),
        what: label.clone(),
        message,
    };
    let mirror_of = |n: &Vector| {
        ocs_mirror(n).ok_or_else(|| {
            invalid("its extrusion direction is not ±Z (not in the XY plane)".into())
        })
    };
    let pt = |x: f64, y: f64, mirror: bool| Point2::new(if mirror { -x * k } else { x * k }, y * k);
    let piece = match &e.specific {
        EntityType::Line(l) => {
            let (a, b) = (pt(l.p1.x, l.p1.y, false), pt(l.p2.x, l.p2.y, false));
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
        EntityType::Arc(a) => {
            let mirror = mirror_of(&a.normal)?;
            if !(a.radius > 0.0 && a.radius.is_finite()) {
                return Err(invalid(format!("radius {} is not positive", a.radius)));
            }
            let mut sweep = (a.end_angle - a.start_angle).rem_euclid(360.0);
            if sweep == 0.0 {
                sweep = 360.0;
            }
            let arc = ocs_arc(
                pt(a.center.x, a.center.y, mirror),
                a.radius * k,
                mirror,
                a.start_angle.to_radians(),
                sweep.to_radians(),
            );
            let full = sweep >= 360.0;
            arc_piece(&arc, full, tol, label)
        }
        EntityType::Circle(c) => {
            let mirror = mirror_of(&c.normal)?;
            if !(c.radius > 0.0 && c.radius.is_finite()) {
                return Err(invalid(format!("radius {} is not positive", c.radius)));
            }
            let arc = ocs_arc(
                pt(c.center.x, c.center.y, mirror),
                c.radius * k,
                mirror,
                0.0,
                TAU,
            );
            arc_piece(&arc, true, tol, label)
        }
        EntityType::Ellipse(el) => {
            // Centre and major axis are in world coordinates; the parameter runs
            // counter-clockwise about the normal, so the minor axis is ratio · (N × major).
            let n = &el.normal;
            mirror_of(n)?;
            let nz = if n.z < 0.0 { -1.0 } else { 1.0 };
            let (mx, my) = (el.major_axis.x * k, el.major_axis.y * k);
            let r = el.minor_axis_ratio;
            if !(r > 0.0 && r.is_finite()) || (mx == 0.0 && my == 0.0) {
                return Err(invalid("degenerate axes".into()));
            }
            let m = Matrix2::new(mx, -nz * r * my, my, nz * r * mx);
            let (s, mut d) = (el.start_parameter, el.end_parameter - el.start_parameter);
            if !(s.is_finite() && d.is_finite()) {
                return Err(invalid("parameters are not finite".into()));
            }
            d = d.rem_euclid(TAU);
            let full = d <= 1e-12 || d >= TAU - 1e-12;
            if full {
                d = TAU;
            }
            let arc = EllipseArc {
                center: pt(el.center.x, el.center.y, false),
                m,
                theta0: s,
                dtheta: d,
            };
            arc_piece(&arc, full, tol, label)
        }
        EntityType::LwPolyline(p) => {
            let mirror = mirror_of(&p.extrusion_direction)?;
            let sign = if mirror { -1.0 } else { 1.0 };
            let vs: Vec<(Point2, f64)> = p
                .vertices
                .iter()
                .map(|v| (pt(v.x, v.y, mirror), v.bulge * sign))
                .collect();
            poly_piece(&vs, p.is_closed(), label)
        }
        EntityType::Polyline(p) => {
            if p.is_polyface_mesh() || p.is_3d_polygon_mesh() {
                return Ok(None);
            }
            let three_d = p.is_3d_polyline();
            // 3D polylines are in world coordinates and have no bulges.
            let mirror = if three_d {
                false
            } else {
                mirror_of(&p.normal)?
            };
            let sign = if mirror { -1.0 } else { 1.0 };
            let vs: Vec<(Point2, f64)> = p
                .vertices()
                .filter(|v| v.flags & 16 == 0)
                .map(|v| {
                    (
                        pt(v.location.x, v.location.y, mirror),
                        if three_d { 0.0 } else { v.bulge * sign },
                    )
                })
                .collect();
            poly_piece(&vs, p.is_closed(), label)
        }
        EntityType::Spline(sp) => {
            if sp.control_points.is_empty() {
                return Err(OutlineError::Unsupported {
                    file: file.into(),
                    what: label,
                    message: "splines defined only by fit points".into(),
                });
            }
            let pts: Vec<Point2> = sp
                .control_points
                .iter()
                .map(|c| pt(c.x, c.y, false))
                .collect();
            let degree = usize::try_from(sp.degree_of_curve).unwrap_or(0);
            let nurbs = Nurbs::new(degree, sp.knot_values.clone(), &pts, &sp.weight_values)
                .map_err(invalid)?;
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
        EntityType::Insert(_) => {
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

fn entity_name(t: &EntityType) -> &'static str {
    match t {
        EntityType::Line(_) => "LINE",
        EntityType::Arc(_) => "ARC",
        EntityType::Circle(_) => "CIRCLE",
        EntityType::Ellipse(_) => "ELLIPSE",
        EntityType::LwPolyline(_) => "LWPOLYLINE",
        EntityType::Polyline(_) => "POLYLINE",
        EntityType::Spline(_) => "SPLINE",
        EntityType::Insert(_) => "INSERT",
        _ => "entity",
    }
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
mod tests {
    use std::f64::consts::PI;

    use dxf::entities::{
        Arc, Circle, Ellipse, Line, LwPolyline, Polyline, Spline, Vertex as DxfVertex,
    };
    use dxf::enums::AcadVersion;
    use dxf::{LwPolylineVertex, Point};

    use super::*;
    use crate::contour::geometry::Segment;
    use crate::contour::input::curves::{Cubic, Curve};
    use crate::contour::input::read_dxf_bytes;
    use crate::contour::input::segmath::dist_point_segment;
    use crate::contour::input::test_util::total_area;

    fn bytes(units: Units, build: impl FnOnce(&mut Drawing)) -> Vec<u8> {
        let mut d = Drawing::new();
        d.header.version = AcadVersion::R2018;
        d.header.default_drawing_units = units;
        build(&mut d);
        let mut buf = Vec::new();
        d.save(&mut buf).unwrap();
        buf
    }

    fn read(b: &[u8]) -> Result<Shape, OutlineError> {
        read_dxf_bytes(b, "t.dxf", &OutlineOptions::default())
    }

    fn add(d: &mut Drawing, e: EntityType) {
        d.add_entity(Entity::new(e));
    }

    fn p(x: f64, y: f64) -> Point {
        Point::new(x, y, 0.0)
    }

    fn lw(pts: &[(f64, f64, f64)], closed: bool) -> EntityType {
        let mut l = LwPolyline {
            vertices: pts
                .iter()
                .map(|&(x, y, bulge)| LwPolylineVertex {
                    x,
                    y,
                    bulge,
                    ..Default::default()
                })
                .collect(),
            ..Default::default()
        };
        l.set_is_closed(closed);
        EntityType::LwPolyline(l)
    }

    fn max_dist(curve: &dyn Curve, t0: f64, t1: f64, s: &Shape) -> f64 {
        let segs: Vec<Segment> = s
            .contours
            .iter()
            .flat_map(|c| c.segments().collect::<Vec<_>>())
            .collect();
        (0..=20_000)
            .map(|i| {
                let q = curve.eval(t0 + (t1 - t0) * i as f64 / 20_000.0).p;
                segs.iter()
                    .map(|sg| dist_point_segment(q, sg))
                    .fold(f64::INFINITY, f64::min)
            })
            .fold(0.0, f64::max)
    }

    #[test]
    fn lines_and_arcs_chain_into_a_slot() {
        let (l, r) = (30.0, 4.0);
        // Scrambled order and directions.
        let b = bytes(Units::Millimeters, |d| {
            add(d, EntityType::Arc(Arc::new(p(l, 0.0), r, -90.0, 90.0)));
            add(d, EntityType::Line(Line::new(p(0.0, -r), p(l, -r))));
            add(d, EntityType::Line(Line::new(p(0.0, r), p(l, r))));
            add(d, EntityType::Arc(Arc::new(p(0.0, 0.0), r, 90.0, 270.0)));
        });
        let s = read(&b).unwrap();
        assert_eq!(s.contours.len(), 1);
        let c = &s.contours[0];
        assert_eq!(c.vertices.len(), 4);
        assert!(
            (c.signed_area() - (2.0 * r * l + PI * r * r)).abs() < 1e-10,
            "{}",
            c.signed_area()
        );
        assert!((c.length() - (2.0 * l + 2.0 * PI * r)).abs() < 1e-10);
    }

    #[test]
    fn lwpolylines_with_bulges_and_holes() {
        let b = bytes(Units::Unitless, |d| {
            // Square with its right side bulged out by a half circle (bulge 1), closed flag.
            add(
                d,
                lw(
                    &[
                        (0.0, 0.0, 0.0),
                        (10.0, 0.0, 1.0),
                        (10.0, 10.0, 0.0),
                        (0.0, 10.0, 0.0),
                    ],
                    true,
                ),
            );
            // Triangle closed by repeating its first point: a hole under the even-odd rule.
            add(
                d,
                lw(
                    &[
                        (2.0, 2.0, 0.0),
                        (6.0, 2.0, 0.0),
                        (2.0, 8.0, 0.0),
                        (2.0, 2.0, 0.0),
                    ],
                    false,
                ),
            );
        });
        let s = read(&b).unwrap();
        let areas: Vec<f64> = s.contours.iter().map(|c| c.signed_area()).collect();
        assert_eq!(areas.len(), 2);
        assert!((areas[0] - (100.0 + 12.5 * PI)).abs() < 1e-10, "{areas:?}");
        assert!((areas[1] + 12.0).abs() < 1e-10, "{areas:?}");
    }

    #[test]
    fn polyline_with_vertex_bulges() {
        let b = bytes(Units::Millimeters, |d| {
            let mut pl = Polyline::default();
            pl.set_is_closed(true);
            for (x, y, bulge) in [
                (0.0, 0.0, 0.0),
                (20.0, 0.0, 0.0),
                (20.0, 10.0, (PI / 8.0).tan()),
                (10.0, 20.0, 0.0),
                (0.0, 10.0, 0.0),
            ] {
                let mut v = DxfVertex::new(p(x, y));
                v.bulge = bulge;
                pl.add_vertex(d, v);
            }
            add(d, EntityType::Polyline(pl));
        });
        let s = read(&b).unwrap();
        // Polygon (0,0),(20,0),(20,10),(10,20),(0,10) has area 300; the quarter arc of radius 10
        // about (10, 10) from (20, 10) to (10, 20) adds the circular segment 25π − 50.
        assert!(
            (total_area(&s) - (300.0 + 25.0 * PI - 50.0)).abs() < 1e-10,
            "{}",
            total_area(&s)
        );
    }

    #[test]
    fn circle_in_inches_and_scale() {
        let b = bytes(Units::Inches, |d| {
            add(d, EntityType::Circle(Circle::new(p(1.0, 2.0), 1.0)))
        });
        let s = read(&b).unwrap();
        assert!((total_area(&s) - PI * 25.4 * 25.4).abs() < 1e-9);
        let s = read_dxf_bytes(
            &b,
            "t.dxf",
            &OutlineOptions {
                scale: 2.0,
                ..Default::default()
            },
        )
        .unwrap();
        assert!((total_area(&s) - PI * 50.8 * 50.8).abs() < 1e-9);
        let b = bytes(Units::Centimeters, |d| {
            add(d, EntityType::Circle(Circle::new(p(0.0, 0.0), 1.0)))
        });
        assert!((total_area(&read(&b).unwrap()) - PI * 100.0).abs() < 1e-9);
        let b = bytes(Units::Meters, |d| {
            add(d, EntityType::Circle(Circle::new(p(0.0, 0.0), 1.0)))
        });
        assert!((total_area(&read(&b).unwrap()) - PI * 1e6).abs() < 1e-3);
    }

    #[test]
    fn partial_ellipse_closed_by_a_line() {
        let b = bytes(Units::Millimeters, |d| {
            let e = Ellipse {
                center: p(5.0, 5.0),
                major_axis: dxf::Vector::new(20.0, 0.0, 0.0),
                minor_axis_ratio: 0.5,
                start_parameter: 0.0,
                end_parameter: PI,
                ..Default::default()
            };
            add(d, EntityType::Ellipse(e));
            add(d, EntityType::Line(Line::new(p(-15.0, 5.0), p(25.0, 5.0))));
        });
        let s = read(&b).unwrap();
        let c = &s.contours[0];
        assert!(
            (c.signed_area() - PI * 100.0).abs() <= 0.001 * c.length(),
            "{}",
            c.signed_area()
        );
        let truth = EllipseArc {
            center: Point2::new(5.0, 5.0),
            m: Matrix2::new(20.0, 0.0, 0.0, 10.0),
            theta0: 0.0,
            dtheta: PI,
        };
        assert!(max_dist(&truth, 0.0, 1.0, &s) <= 0.001);
        // Upper half: y from 5 to 15.
        // (The parameters went through the DXF text with 12 digits.)
        assert!(
            c.vertices.iter().all(|v| v.point.y >= 5.0 - 1e-9),
            "{:?}",
            c.vertices
        );
    }

    #[test]
    fn splines_bezier_form_and_rational_circle() {
        // A clamped cubic with 4 control points is the Bézier curve of those points.
        let ctrl = [(0.0, 0.0), (10.0, 30.0), (40.0, 30.0), (50.0, 0.0)];
        let b = bytes(Units::Millimeters, |d| {
            let sp = Spline {
                degree_of_curve: 3,
                knot_values: vec![0.0, 0.0, 0.0, 0.0, 2.0, 2.0, 2.0, 2.0],
                control_points: ctrl.iter().map(|&(x, y)| p(x, y)).collect(),
                ..Default::default()
            };
            add(d, EntityType::Spline(sp));
            add(d, EntityType::Line(Line::new(p(50.0, 0.0), p(0.0, 0.0))));
        });
        let s = read(&b).unwrap();
        let bez = Cubic {
            p: ctrl.map(|(x, y)| Point2::new(x, y)),
        };
        assert!(max_dist(&bez, 0.0, 1.0, &s) <= 0.001);
        // Rational quadratic full circle of radius 10 (9 control points), closed spline.
        let w = std::f64::consts::FRAC_1_SQRT_2;
        let pts = [
            (10., 0.),
            (10., 10.),
            (0., 10.),
            (-10., 10.),
            (-10., 0.),
            (-10., -10.),
            (0., -10.),
            (10., -10.),
            (10., 0.),
        ];
        let b = bytes(Units::Millimeters, |d| {
            let mut sp = Spline {
                degree_of_curve: 2,
                knot_values: vec![0., 0., 0., 1., 1., 2., 2., 3., 3., 4., 4., 4.],
                weight_values: vec![1., w, 1., w, 1., w, 1., w, 1.],
                control_points: pts.iter().map(|&(x, y)| p(x, y)).collect(),
                ..Default::default()
            };
            sp.set_is_closed(true);
            sp.set_is_rational(true);
            add(d, EntityType::Spline(sp));
        });
        let s = read(&b).unwrap();
        let c = &s.contours[0];
        for seg in c.segments() {
            for k in 0..=16 {
                let q = crate::contour::input::segmath::point_on_segment(&seg, k as f64 / 16.0);
                assert!((q.coords.norm() - 10.0).abs() <= 0.001, "{q}");
            }
        }
        assert!((c.signed_area() - 100.0 * PI).abs() <= 0.001 * c.length());
        // Few arcs for a circle.
        assert!(c.vertices.len() <= 16, "{}", c.vertices.len());
    }

    #[test]
    fn negative_extrusion_mirrors_x() {
        let neg = dxf::Vector::new(0.0, 0.0, -1.0);
        let b = bytes(Units::Millimeters, |d| {
            let mut c = Circle::new(p(5.0, 0.0), 1.0);
            c.normal = neg.clone();
            add(d, EntityType::Circle(c));
            // Upper half disk: OCS arc 0°→180° is, in world coordinates, from (−10, 0) over the
            // top to (10, 0) clockwise, closed by a world-space line.
            let mut a = Arc::new(p(0.0, 20.0), 10.0, 0.0, 180.0);
            a.normal = neg.clone();
            add(d, EntityType::Arc(a));
            add(
                d,
                EntityType::Line(Line::new(p(-10.0, 20.0), p(10.0, 20.0))),
            );
        });
        let s = read(&b).unwrap();
        assert_eq!(s.contours.len(), 2);
        let circle = &s.contours[0];
        let cx: f64 = circle.vertices.iter().map(|v| v.point.x).sum::<f64>() / 2.0;
        assert!((cx + 5.0).abs() < 1e-12, "{cx}");
        let half = &s.contours[1];
        assert!((half.signed_area() - 50.0 * PI).abs() < 1e-10);
        assert!(half.segments().all(|sg| match sg {
            Segment::Arc { center, .. } => (center - Point2::new(0.0, 20.0)).norm() < 1e-12,
            Segment::Line { .. } => true,
        }));
        let b = bytes(Units::Millimeters, |d| {
            let mut c = Circle::new(p(5.0, 0.0), 1.0);
            c.normal = dxf::Vector::new(1.0, 0.0, 0.0);
            add(d, EntityType::Circle(c));
        });
        assert!(read(&b).unwrap_err().to_string().contains("XY plane"));
    }

    #[test]
    fn errors_are_clear() {
        let b = bytes(Units::Millimeters, |d| {
            add(d, EntityType::Line(Line::new(p(0.0, 0.0), p(10.0, 0.0))))
        });
        let e = read(&b).unwrap_err();
        assert!(
            matches!(e, OutlineError::Open { .. }) && e.to_string().contains("LINE (handle"),
            "{e}"
        );
        let b = bytes(Units::Millimeters, |d| {
            add(d, EntityType::Line(Line::new(p(0.0, 0.0), p(10.0, 0.0))));
            add(d, EntityType::Line(Line::new(p(10.0, 0.0), p(10.0, 10.0))));
        });
        let e = read(&b).unwrap_err().to_string();
        assert!(
            e.contains("the loop of LINE") && e.contains("14.142136"),
            "{e}"
        );
        let b = bytes(Units::Millimeters, |_| {});
        assert!(matches!(read(&b), Err(OutlineError::NoClosedShape { .. })));
        let b = bytes(Units::Millimeters, |d| {
            add(d, EntityType::Insert(Default::default()))
        });
        assert!(matches!(read(&b), Err(OutlineError::Unsupported { .. })));
        assert!(matches!(read(b"  \n"), Err(OutlineError::Empty { .. })));
        assert!(matches!(
            read(b"0\nSECTION\n2\nENTITIES\n0\nLINE\n10\nabc\n"),
            Err(OutlineError::Parse { .. })
        ));
        // Two overlapping circles.
        let b = bytes(Units::Millimeters, |d| {
            add(d, EntityType::Circle(Circle::new(p(0.0, 0.0), 2.0)));
            add(d, EntityType::Circle(Circle::new(p(3.0, 0.0), 2.0)));
        });
        let e = read(&b).unwrap_err().to_string();
        assert!(e.contains("CIRCLE (handle") && e.contains("cross"), "{e}");
    }

    #[test]
    fn many_lines_chain_quickly() {
        // A 20 000-gon as shuffled, partly reversed LINE entities.
        let n = 20_000;
        let pt = |i: usize| {
            let a = 2.0 * PI * (i % n) as f64 / n as f64;
            p(50.0 * a.cos(), 50.0 * a.sin())
        };
        let b = bytes(Units::Millimeters, |d| {
            for k in 0..n {
                let i = (k * 7919) % n;
                let (a, c) = (pt(i), pt(i + 1));
                let line = if k % 3 == 0 {
                    Line::new(c, a)
                } else {
                    Line::new(a, c)
                };
                add(d, EntityType::Line(line));
            }
        });
        let t = std::time::Instant::now();
        let s = read(&b).unwrap();
        assert!(t.elapsed().as_secs_f64() < 20.0);
        assert_eq!(s.contours.len(), 1);
        let expected = 0.5 * n as f64 * 2500.0 * (2.0 * PI / n as f64).sin();
        assert!(
            (total_area(&s) - expected).abs() < 1e-6,
            "{}",
            total_area(&s)
        );
    }

    #[test]
    fn hand_written_minimal_dxf() {
        // Only an ENTITIES section, as many simple exporters write it.
        let text = "0\nSECTION\n2\nENTITIES\n0\nLWPOLYLINE\n8\n0\n90\n4\n70\n1\n10\n0\n20\n0\n10\n4\n20\n0\n10\n4\n20\n3\n10\n0\n20\n3\n0\nENDSEC\n0\nEOF\n";
        let s = read(text.as_bytes()).unwrap();
        assert!((total_area(&s) - 12.0).abs() < 1e-12);
    }
}
