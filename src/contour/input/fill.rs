//! Region building: from closed contours and a fill rule to a [`Shape`] (region to the left).
//!
//! 1. Contours are cleaned (zero-length segments removed) and rejected when their area is zero.
//! 2. Crossings are detected exactly for lines and arcs: interior intersections of two segments
//!    are computed in closed form (line–line, line–circle, circle–circle); tangential contacts
//!    are touches, not crossings. Where a vertex lies on another boundary, the four branches
//!    leaving the point are ordered by tangent angle, ties broken by signed curvature (so two
//!    curves touching tangentially, like the leaves of a flower icon, are told apart exactly);
//!    the boundaries cross iff the other contour's branches separate this contour's two.
//!    Crossings and overlaps are errors naming both contours and the point.
//! 3. Containment tree by exact winding numbers (arcs included), parent = smallest container.
//! 4. The winding number (nonzero rule) or depth (even-odd rule) of the face just inside each
//!    contour decides whether it is filled; a contour bounds the region iff the faces on its two
//!    sides differ. Kept contours are oriented counter-clockwise around filled faces.
//!
//! When contours coming from elements with different fill rules nest, each face uses the rule
//! of the innermost contour around it.

use std::f64::consts::TAU;

use super::segmath::{
    arc_param, cross, curvature, dist_point_segment, point_on_segment, seg_bbox, seg_end,
    seg_start, tangent_at, winding_number, wrap_tau,
};
use super::{CrossingKind, OutlineError, RawContour, points_size};
use crate::contour::geometry::{Contour, Point2, Segment, Shape, Vector2, Vertex};

/// SVG's `fill-rule`: which points are inside a set of closed contours.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FillRule {
    /// Inside where the winding number is not zero (SVG default).
    #[default]
    NonZero,
    /// Inside where a ray crosses the boundary an odd number of times.
    EvenOdd,
}

/// Relative size of the matching tolerance used by the region builder.
const REL_EPS: f64 = 1e-9;

struct Prepared {
    label: String,
    rule: FillRule,
    vertices: Vec<Vertex>,
    segs: Vec<Segment>,
    area: f64,
    bbox: [f64; 4],
}

/// Builds the region bounded by `contours` under their fill rules; `tol` (mm) is the curve
/// tolerance, of which 1 % may be spent merging consecutive co-circular arcs.
pub(crate) fn build_region(
    contours: Vec<RawContour>,
    file: &str,
    tol: f64,
) -> Result<Shape, OutlineError> {
    if contours.is_empty() {
        return Err(OutlineError::NoClosedShape {
            file: file.into(),
            detail: String::new(),
        });
    }
    for c in &contours {
        let finite = c
            .vertices
            .iter()
            .all(|v| v.point.x.is_finite() && v.point.y.is_finite() && v.bulge.is_finite());
        if !finite {
            return Err(invalid(
                file,
                &c.label,
                "coordinates are not finite numbers",
            ));
        }
    }
    let size = points_size(
        contours
            .iter()
            .flat_map(|c| c.vertices.iter().map(|v| &v.point)),
    );
    if !size.is_finite() {
        return Err(invalid(file, "drawing", "coordinates are too large"));
    }
    let eps = (REL_EPS * size).max(1e-12);
    let mut prepared = Vec::with_capacity(contours.len());
    for c in contours {
        prepared.push(prepare(c, eps, size, 0.01 * tol, file)?);
    }
    check_crossings(&prepared, eps, size, file)?;
    let parents = containment(&prepared, eps, file)?;

    // Parents have larger areas: visit by decreasing area so a parent is resolved first.
    let mut order: Vec<usize> = (0..prepared.len()).collect();
    order.sort_by(|&a, &b| {
        prepared[b]
            .area
            .abs()
            .total_cmp(&prepared[a].area.abs())
            .then(a.cmp(&b))
    });
    let n = prepared.len();
    let (mut wind, mut depth, mut filled) = (vec![0i64; n], vec![0usize; n], vec![false; n]);
    let mut keep = vec![false; n];
    for &j in &order {
        let orient = if prepared[j].area > 0.0 { 1 } else { -1 };
        let (pw, pd, outside) =
            parents[j].map_or((0, 0, false), |p| (wind[p], depth[p], filled[p]));
        wind[j] = pw + orient;
        depth[j] = pd + 1;
        filled[j] = match prepared[j].rule {
            FillRule::NonZero => wind[j] != 0,
            FillRule::EvenOdd => depth[j] % 2 == 1,
        };
        keep[j] = filled[j] != outside;
    }
    let mut shape = Shape::default();
    for (j, p) in prepared.into_iter().enumerate() {
        if !keep[j] {
            continue;
        }
        let ccw = p.area > 0.0;
        let vertices = if ccw == filled[j] {
            p.vertices
        } else {
            reverse_closed(&p.vertices)
        };
        shape.contours.push(Contour { vertices });
    }
    if shape.contours.is_empty() {
        return Err(OutlineError::NoClosedShape {
            file: file.into(),
            detail: " (nothing is filled)".into(),
        });
    }
    Ok(shape)
}

fn invalid(file: &str, what: &str, message: &str) -> OutlineError {
    OutlineError::Invalid {
        file: file.into(),
        what: what.into(),
        message: message.into(),
    }
}

/// The same closed contour run backwards.
pub(crate) fn reverse_closed(vs: &[Vertex]) -> Vec<Vertex> {
    let n = vs.len();
    (0..n)
        .map(|k| Vertex {
            point: vs[(n - k) % n].point,
            bulge: -vs[(2 * n - k - 1) % n].bulge,
        })
        .collect()
}

fn prepare(
    c: RawContour,
    eps: f64,
    size: f64,
    merge_tol: f64,
    file: &str,
) -> Result<Prepared, OutlineError> {
    let mut vs = c.vertices;
    // Drop the start of every (cyclically) zero-length segment until none is left.
    loop {
        let n = vs.len();
        if n < 2 {
            break;
        }
        let next: Vec<Vertex> = (0..n)
            .filter(|&i| (vs[(i + 1) % n].point - vs[i].point).norm() > eps)
            .map(|i| vs[i])
            .collect();
        if next.len() == n {
            break;
        }
        vs = next;
    }
    let contour = Contour {
        vertices: merge_segments(vs, eps, merge_tol),
    };
    let area = contour.signed_area();
    let degenerate = contour.vertices.len() < 2
        || (contour.vertices.len() == 2 && contour.vertices.iter().all(|v| v.bulge == 0.0));
    let segs: Vec<Segment> = contour.segments().collect();
    if degenerate || area.is_nan() || area.abs() <= 1e-12 * size * size {
        // A contour that crosses itself (a bow-tie) can enclose as much area on the left as
        // on the right: say where it crosses rather than "zero area".
        if !degenerate {
            let alone = Prepared {
                label: c.label.clone(),
                rule: c.rule,
                vertices: contour.vertices.clone(),
                segs: segs.clone(),
                area,
                bbox: [
                    f64::NEG_INFINITY,
                    f64::NEG_INFINITY,
                    f64::INFINITY,
                    f64::INFINITY,
                ],
            };
            check_crossings(std::slice::from_ref(&alone), eps, size, file)?;
        }
        return Err(OutlineError::ZeroArea {
            file: file.into(),
            what: c.label,
            detail: String::new(),
        });
    }
    let mut bbox = [
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    for s in &segs {
        let b = seg_bbox(s);
        bbox = [
            bbox[0].min(b[0]),
            bbox[1].min(b[1]),
            bbox[2].max(b[2]),
            bbox[3].max(b[3]),
        ];
    }
    Ok(Prepared {
        label: c.label,
        rule: c.rule,
        vertices: contour.vertices,
        segs,
        area,
        bbox,
    })
}

/// Merges consecutive collinear lines (middle vertex within `eps` of the joined line) and
/// consecutive arcs of one circle (centres and radii within `merge_tol`, at most a half turn
/// together): fewer NC blocks, geometry moved by at most ~`merge_tol`.
fn merge_segments(mut vs: Vec<Vertex>, eps: f64, merge_tol: f64) -> Vec<Vertex> {
    let mut i = 0;
    let mut since_change = 0;
    while vs.len() > 2 && since_change < vs.len() {
        let n = vs.len();
        let (ia, ib, ic) = ((i + n - 1) % n, i % n, (i + 1) % n);
        let (a, b, c) = (vs[ia], vs[ib], vs[ic]);
        let merged = merged_bulge(a, b, c.point, eps, merge_tol);
        match merged {
            Some(bulge) => {
                vs[ia].bulge = bulge;
                vs.remove(ib);
                since_change = 0;
                // Re-examine the merged segment with its new successor.
                i = if ib == 0 { 0 } else { ib - 1 };
            }
            None => {
                i = (ib + 1) % n;
                since_change += 1;
            }
        }
    }
    vs
}

/// The bulge of one segment from `a` to `c` replacing `a→b` and `b→c`, if it can.
fn merged_bulge(a: Vertex, b: Vertex, c: Point2, eps: f64, merge_tol: f64) -> Option<f64> {
    let (pa, pb) = (a.point, b.point);
    if a.bulge == 0.0 && b.bulge == 0.0 {
        let ac = c - pa;
        let l = ac.norm();
        let between = (pb - pa).dot(&(c - pb)) > 0.0;
        return (l > 0.0 && between && (cross(ac, pb - pa) / l).abs() <= eps).then_some(0.0);
    }
    if a.bulge == 0.0 || b.bulge == 0.0 || a.bulge.signum() != b.bulge.signum() {
        return None;
    }
    let (s1, s2) = (Segment::new(pa, pb, a.bulge), Segment::new(pb, c, b.bulge));
    match (s1, s2) {
        (
            Segment::Arc {
                center: c1,
                radius: r1,
                sweep: w1,
                ..
            },
            Segment::Arc {
                center: c2,
                radius: r2,
                sweep: w2,
                ..
            },
        ) => {
            let close = (c1 - c2).norm() <= merge_tol && (r1 - r2).abs() <= merge_tol;
            let sweep = w1 + w2;
            (close && sweep.abs() <= std::f64::consts::PI + 1e-12).then(|| (sweep / 4.0).tan())
        }
        _ => None,
    }
}

/// A direction leaving a point along a boundary: tangent angle and signed curvature (turning
/// left positive), enough to order curves that leave the point tangentially.
#[derive(Clone, Copy, Debug)]
struct Branch {
    angle: f64,
    kappa: f64,
}

fn branch_forward(s: &Segment, q: Point2) -> Branch {
    let t = tangent_at(s, q);
    Branch {
        angle: t.y.atan2(t.x),
        kappa: curvature(s),
    }
}

fn branch_backward(s: &Segment, q: Point2) -> Branch {
    let t = -tangent_at(s, q);
    Branch {
        angle: t.y.atan2(t.x),
        kappa: -curvature(s),
    }
}

const ANG_EPS: f64 = 1e-9;

/// Counter-clockwise position of `x` around the point, starting just after `base`:
/// (angle from base in [0, 2π], curvature), or `None` when `x` coincides with `base`.
fn ccw_key(x: &Branch, base: &Branch, size: f64) -> Option<(f64, f64)> {
    let r = wrap_tau(x.angle - base.angle);
    if !(ANG_EPS..=TAU - ANG_EPS).contains(&r) {
        return match kappa_cmp(x.kappa, base.kappa, size) {
            std::cmp::Ordering::Greater => Some((0.0, x.kappa)),
            std::cmp::Ordering::Less => Some((TAU, x.kappa)),
            std::cmp::Ordering::Equal => None,
        };
    }
    Some((r, x.kappa))
}

fn kappa_cmp(a: f64, b: f64, size: f64) -> std::cmp::Ordering {
    let tol = 1e-9 * a.abs().max(b.abs()).max(1.0 / size);
    if (a - b).abs() <= tol {
        std::cmp::Ordering::Equal
    } else {
        a.total_cmp(&b)
    }
}

/// Ordering of two keys; `None` when they coincide (overlapping boundaries).
fn key_cmp(x: (f64, f64), y: (f64, f64), size: f64) -> Option<std::cmp::Ordering> {
    if (x.0 - y.0).abs() > ANG_EPS {
        return Some(x.0.total_cmp(&y.0));
    }
    match kappa_cmp(x.1, y.1, size) {
        std::cmp::Ordering::Equal => None,
        o => Some(o),
    }
}

/// Whether boundary B (branches `b`) crosses boundary A (branches `a`) at a common point;
/// `Err` when two branches coincide.
fn branches_cross(a: [Branch; 2], b: [Branch; 2], size: f64) -> Result<bool, ()> {
    let a2 = ccw_key(&a[1], &a[0], size).ok_or(())?;
    let mut inside = [false; 2];
    for (k, bk) in b.iter().enumerate() {
        let key = ccw_key(bk, &a[0], size).ok_or(())?;
        inside[k] = key_cmp(key, a2, size).ok_or(())? == std::cmp::Ordering::Less;
    }
    Ok(inside[0] != inside[1])
}

#[derive(Clone, Copy)]
struct SegRef {
    c: usize,
    i: usize,
    bb: [f64; 4],
}

fn check_crossings(cs: &[Prepared], eps: f64, size: f64, file: &str) -> Result<(), OutlineError> {
    let mut refs: Vec<SegRef> = Vec::new();
    for (c, p) in cs.iter().enumerate() {
        for (i, s) in p.segs.iter().enumerate() {
            let b = seg_bbox(s);
            refs.push(SegRef {
                c,
                i,
                bb: [b[0] - eps, b[1] - eps, b[2] + eps, b[3] + eps],
            });
        }
        // A spike (the boundary folding back on itself) shows at a vertex as equal branches.
        let n = p.segs.len();
        for i in 0..n {
            let q = p.vertices[i].point;
            let out = branch_forward(&p.segs[i], q);
            let back = branch_backward(&p.segs[(i + n - 1) % n], q);
            if ccw_key(&back, &out, size).is_none() {
                return Err(crossing(file, &p.label, &p.label, CrossingKind::Overlap, q));
            }
        }
    }
    refs.sort_by(|a, b| {
        a.bb[0]
            .total_cmp(&b.bb[0])
            .then((a.c, a.i).cmp(&(b.c, b.i)))
    });
    let mut active: Vec<SegRef> = Vec::new();
    for s in refs {
        active.retain(|t| t.bb[2] >= s.bb[0]);
        for t in &active {
            if t.bb[1] > s.bb[3] || s.bb[1] > t.bb[3] {
                continue;
            }
            check_pair(cs, s, *t, eps, size, file)?;
        }
        active.push(s);
    }
    Ok(())
}

fn crossing(file: &str, a: &str, b: &str, kind: CrossingKind, p: Point2) -> OutlineError {
    let second = if a == b {
        "itself".to_string()
    } else {
        b.to_string()
    };
    OutlineError::Crossing {
        file: file.into(),
        first: a.into(),
        second,
        kind,
        x: p.x,
        y: p.y,
    }
}

fn check_pair(
    cs: &[Prepared],
    s: SegRef,
    t: SegRef,
    eps: f64,
    size: f64,
    file: &str,
) -> Result<(), OutlineError> {
    check_vertex(cs, s, t, eps, size, file)?;
    check_vertex(cs, t, s, eps, size, file)?;
    let (ss, ts) = (&cs[s.c].segs[s.i], &cs[t.c].segs[t.i]);
    let ends = [seg_start(ss), seg_end(ss), seg_start(ts), seg_end(ts)];
    for (p, kind) in intersections(ss, ts, eps) {
        let at_end = ends.iter().any(|e| (p - e).norm() <= eps);
        match kind {
            Hit::Cross if !at_end => {
                return Err(crossing(
                    file,
                    &cs[s.c].label,
                    &cs[t.c].label,
                    CrossingKind::Cross,
                    p,
                ));
            }
            Hit::Overlap => {
                return Err(crossing(
                    file,
                    &cs[s.c].label,
                    &cs[t.c].label,
                    CrossingKind::Overlap,
                    p,
                ));
            }
            _ => {}
        }
    }
    Ok(())
}

/// Vertex `s.i` (the start of segment `s`) against segment `t`.
fn check_vertex(
    cs: &[Prepared],
    s: SegRef,
    t: SegRef,
    eps: f64,
    size: f64,
    file: &str,
) -> Result<(), OutlineError> {
    let a = &cs[s.c];
    let na = a.segs.len();
    let prev = (s.i + na - 1) % na;
    if s.c == t.c && (t.i == s.i || t.i == prev) {
        return Ok(());
    }
    let p = a.vertices[s.i].point;
    let tseg = &cs[t.c].segs[t.i];
    if dist_point_segment(p, tseg) > eps {
        return Ok(());
    }
    let b = &cs[t.c];
    let nb = b.segs.len();
    let a_br = [
        branch_forward(&a.segs[s.i], p),
        branch_backward(&a.segs[prev], p),
    ];
    let b_br = if (p - seg_start(tseg)).norm() <= eps {
        [
            branch_forward(tseg, p),
            branch_backward(&b.segs[(t.i + nb - 1) % nb], p),
        ]
    } else if (p - seg_end(tseg)).norm() <= eps {
        // Examined with the segment that starts there.
        return Ok(());
    } else {
        [branch_forward(tseg, p), branch_backward(tseg, p)]
    };
    match branches_cross(a_br, b_br, size) {
        Ok(false) => Ok(()),
        Ok(true) => Err(crossing(file, &a.label, &b.label, CrossingKind::Cross, p)),
        Err(()) => Err(crossing(file, &a.label, &b.label, CrossingKind::Overlap, p)),
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Hit {
    Cross,
    Touch,
    Overlap,
}

fn on_arc(s: &Segment, q: Point2) -> bool {
    match *s {
        Segment::Arc {
            center,
            start,
            sweep,
            ..
        } => arc_param(center, start, sweep, q).0,
        Segment::Line { .. } => true,
    }
}

/// Intersections of two segments, classified; `Overlap` where they share a stretch.
fn intersections(s: &Segment, t: &Segment, eps: f64) -> Vec<(Point2, Hit)> {
    match (*s, *t) {
        (Segment::Line { start: a, end: b }, Segment::Line { start: c, end: d }) => {
            line_line(a, b, c, d, eps)
        }
        (Segment::Line { start, end }, Segment::Arc { center, radius, .. }) => {
            line_circle(start, end, center, radius, eps)
                .into_iter()
                .filter(|(p, _)| on_arc(t, *p))
                .collect()
        }
        (Segment::Arc { center, radius, .. }, Segment::Line { start, end }) => {
            line_circle(start, end, center, radius, eps)
                .into_iter()
                .filter(|(p, _)| on_arc(s, *p))
                .collect()
        }
        (
            Segment::Arc {
                center: c1,
                radius: r1,
                ..
            },
            Segment::Arc {
                center: c2,
                radius: r2,
                ..
            },
        ) => {
            if (c2 - c1).norm() <= eps && (r1 - r2).abs() <= eps {
                return cocircular_overlap(s, t, eps)
                    .map(|p| vec![(p, Hit::Overlap)])
                    .unwrap_or_default();
            }
            circle_circle(c1, r1, c2, r2, eps)
                .into_iter()
                .filter(|(p, _)| on_arc(s, *p) && on_arc(t, *p))
                .collect()
        }
    }
}

fn line_line(a: Point2, b: Point2, c: Point2, d: Point2, eps: f64) -> Vec<(Point2, Hit)> {
    let (r, q) = (b - a, d - c);
    let (lr, lq) = (r.norm(), q.norm());
    if lr == 0.0 || lq == 0.0 {
        return Vec::new();
    }
    let den = cross(r, q);
    if den.abs() <= 1e-12 * lr * lq {
        // Parallel: overlapping when collinear and sharing more than a point.
        if (cross(r, c - a) / lr).abs() > eps {
            return Vec::new();
        }
        let (u0, u1) = ((c - a).dot(&r) / (lr * lr), (d - a).dot(&r) / (lr * lr));
        let lo = u0.min(u1).max(0.0);
        let hi = u0.max(u1).min(1.0);
        if (hi - lo) * lr > eps {
            return vec![(a + r * (0.5 * (lo + hi)), Hit::Overlap)];
        }
        return Vec::new();
    }
    let u = cross(c - a, q) / den;
    let v = cross(c - a, r) / den;
    if (0.0..=1.0).contains(&u) && (0.0..=1.0).contains(&v) {
        vec![(a + r * u, Hit::Cross)]
    } else {
        Vec::new()
    }
}

fn line_circle(a: Point2, b: Point2, c: Point2, r: f64, eps: f64) -> Vec<(Point2, Hit)> {
    let d = b - a;
    let l = d.norm();
    if l == 0.0 {
        return Vec::new();
    }
    let u = d / l;
    let foot_s = (c - a).dot(&u);
    let foot = a + u * foot_s;
    let h = (c - foot).norm();
    let on_line = |s: f64| (0.0..=l).contains(&s);
    if (h - r).abs() <= eps {
        return if on_line(foot_s) {
            vec![(foot, Hit::Touch)]
        } else {
            Vec::new()
        };
    }
    if h > r {
        return Vec::new();
    }
    let k = (r * r - h * h).max(0.0).sqrt();
    [foot_s - k, foot_s + k]
        .into_iter()
        .filter(|&s| on_line(s))
        .map(|s| (a + u * s, Hit::Cross))
        .collect()
}

fn circle_circle(c1: Point2, r1: f64, c2: Point2, r2: f64, eps: f64) -> Vec<(Point2, Hit)> {
    let dv = c2 - c1;
    let d = dv.norm();
    if d == 0.0 {
        return Vec::new();
    }
    let e = dv / d;
    let a = (r1 * r1 - r2 * r2 + d * d) / (2.0 * d);
    if (d - (r1 + r2)).abs() <= eps || (d - (r1 - r2).abs()).abs() <= eps {
        return vec![(c1 + e * a, Hit::Touch)];
    }
    if d > r1 + r2 || d < (r1 - r2).abs() {
        return Vec::new();
    }
    let h = (r1 * r1 - a * a).max(0.0).sqrt();
    let m = c1 + e * a;
    let perp = Vector2::new(-e.y, e.x);
    vec![(m + perp * h, Hit::Cross), (m - perp * h, Hit::Cross)]
}

/// A point interior to both of two arcs on the same circle, if they share a stretch.
fn cocircular_overlap(s: &Segment, t: &Segment, eps: f64) -> Option<Point2> {
    let mid = |x: &Segment| point_on_segment(x, 0.5);
    let interior = |x: &Segment, q: Point2| {
        on_arc(x, q) && (q - seg_start(x)).norm() > eps && (q - seg_end(x)).norm() > eps
    };
    [
        mid(t),
        mid(s),
        seg_start(t),
        seg_end(t),
        seg_start(s),
        seg_end(s),
    ]
    .into_iter()
    .find(|&q| interior(s, q) && interior(t, q))
}

/// Parent (smallest containing contour) of every contour.
fn containment(cs: &[Prepared], eps: f64, file: &str) -> Result<Vec<Option<usize>>, OutlineError> {
    let n = cs.len();
    let mut parents = vec![None; n];
    for j in 0..n {
        let mut best: Option<usize> = None;
        for i in 0..n {
            if i == j {
                continue;
            }
            let (bi, bj) = (cs[i].bbox, cs[j].bbox);
            let inside_bb = bj[0] >= bi[0] - eps
                && bj[1] >= bi[1] - eps
                && bj[2] <= bi[2] + eps
                && bj[3] <= bi[3] + eps;
            if !inside_bb || cs[i].area.abs() < cs[j].area.abs() {
                continue;
            }
            let probe = probe_point(&cs[j], &cs[i], eps).ok_or_else(|| {
                crossing(
                    file,
                    &cs[j].label,
                    &cs[i].label,
                    CrossingKind::Overlap,
                    cs[j].vertices[0].point,
                )
            })?;
            if winding_number(&cs[i].segs, probe) != 0
                && best.is_none_or(|b| cs[i].area.abs() < cs[b].area.abs())
            {
                best = Some(i);
            }
        }
        parents[j] = best;
    }
    Ok(parents)
}

/// A point of contour `c` not on contour `other` (vertices first, then segment midpoints).
fn probe_point(c: &Prepared, other: &Prepared, eps: f64) -> Option<Point2> {
    let off = |q: Point2| other.segs.iter().all(|s| dist_point_segment(q, s) > eps);
    c.vertices
        .iter()
        .map(|v| v.point)
        .chain(c.segs.iter().map(|s| point_on_segment(s, 0.5)))
        .find(|&q| off(q))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn build(cs: Vec<RawContour>, file: &str) -> Result<Shape, OutlineError> {
        build_region(cs, file, 0.001)
    }

    fn raw(vs: Vec<Vertex>, label: &str, rule: FillRule) -> RawContour {
        RawContour {
            vertices: vs,
            label: label.into(),
            rule,
        }
    }

    fn square(x0: f64, y0: f64, s: f64, ccw: bool) -> Vec<Vertex> {
        let mut v = vec![
            Vertex::line(x0, y0),
            Vertex::line(x0 + s, y0),
            Vertex::line(x0 + s, y0 + s),
            Vertex::line(x0, y0 + s),
        ];
        if !ccw {
            v.reverse();
        }
        v
    }

    fn circle(cx: f64, cy: f64, r: f64, ccw: bool) -> Vec<Vertex> {
        let b = if ccw { 1.0 } else { -1.0 };
        vec![
            Vertex {
                point: Point2::new(cx + r, cy),
                bulge: b,
            },
            Vertex {
                point: Point2::new(cx - r, cy),
                bulge: b,
            },
        ]
    }

    fn areas(s: &Shape) -> Vec<f64> {
        s.contours.iter().map(|c| c.signed_area()).collect()
    }

    #[test]
    fn nested_squares_both_rules() {
        // Three nested squares, all counter-clockwise.
        for rule in [FillRule::NonZero, FillRule::EvenOdd] {
            let cs = vec![
                raw(square(0.0, 0.0, 10.0, true), "a", rule),
                raw(square(2.0, 2.0, 6.0, true), "b", rule),
                raw(square(4.0, 4.0, 2.0, true), "c", rule),
            ];
            let s = build(cs, "t").unwrap();
            match rule {
                // Same direction: winding 1, 2, 3 — all filled, only the outer bounds the region.
                FillRule::NonZero => assert_eq!(areas(&s), vec![100.0]),
                // Even-odd: outer, hole, island.
                FillRule::EvenOdd => assert_eq!(areas(&s), vec![100.0, -36.0, 4.0]),
            }
        }
        // Nonzero with alternating directions: outer, hole, island.
        let cs = vec![
            raw(square(0.0, 0.0, 10.0, false), "a", FillRule::NonZero),
            raw(square(2.0, 2.0, 6.0, true), "b", FillRule::NonZero),
            raw(square(4.0, 4.0, 2.0, false), "c", FillRule::NonZero),
        ];
        let s = build(cs, "t").unwrap();
        assert_eq!(areas(&s), vec![100.0, -36.0, 4.0]);
    }

    #[test]
    fn circle_hole_exact_area() {
        let cs = vec![
            raw(square(-5.0, -5.0, 10.0, true), "sq", FillRule::EvenOdd),
            raw(circle(0.0, 0.0, 3.0, true), "c", FillRule::EvenOdd),
        ];
        let s = build(cs, "t").unwrap();
        let a = areas(&s);
        assert_eq!(a[0], 100.0);
        assert!((a[1] + 9.0 * std::f64::consts::PI).abs() < 1e-12);
    }

    #[test]
    fn crossing_squares_are_reported() {
        let cs = vec![
            raw(square(0.0, 0.0, 10.0, true), "first", FillRule::NonZero),
            raw(square(5.0, 5.0, 10.0, true), "second", FillRule::NonZero),
        ];
        let e = build(cs, "x.svg").unwrap_err().to_string();
        assert!(
            e.contains("x.svg")
                && e.contains("first")
                && e.contains("second")
                && e.contains("cross"),
            "{e}"
        );
        // The crossing points are (10, 5) and (5, 10).
        assert!(
            e.contains("(10.000000, 5.000000)") || e.contains("(5.000000, 10.000000)"),
            "{e}"
        );
    }

    #[test]
    fn circles_crossing_and_touching() {
        let cross = vec![
            raw(circle(0.0, 0.0, 2.0, true), "c1", FillRule::NonZero),
            raw(circle(3.0, 0.0, 2.0, true), "c2", FillRule::NonZero),
        ];
        assert!(matches!(
            build(cross, "t"),
            Err(OutlineError::Crossing {
                kind: CrossingKind::Cross,
                ..
            })
        ));
        // Externally tangent at (2, 0), which is a vertex of c1 and interior to c2's arc.
        let touch = vec![
            raw(circle(0.0, 0.0, 2.0, true), "c1", FillRule::NonZero),
            raw(circle(0.0, 5.0, 3.0, true), "c2", FillRule::NonZero),
        ];
        assert_eq!(build(touch, "t").unwrap().contours.len(), 2);
        let touch = vec![
            raw(circle(0.0, 0.0, 2.0, true), "c1", FillRule::NonZero),
            raw(circle(4.0, 0.0, 2.0, true), "c2", FillRule::NonZero),
        ];
        assert_eq!(build(touch, "t").unwrap().contours.len(), 2);
        // Internally tangent circle inside a square touching its side: a hole, no crossing.
        let inner = vec![
            raw(square(0.0, 0.0, 10.0, true), "sq", FillRule::EvenOdd),
            raw(circle(8.0, 5.0, 2.0, true), "c", FillRule::EvenOdd),
        ];
        let s = build(inner, "t").unwrap();
        assert!(s.contours[1].signed_area() < 0.0);
    }

    #[test]
    fn self_crossing_and_overlap() {
        let bowtie = vec![
            Vertex::line(0.0, 0.0),
            Vertex::line(10.0, 10.0),
            Vertex::line(10.0, 0.0),
            Vertex::line(0.0, 20.0),
        ];
        let e = build(vec![raw(bowtie, "bow", FillRule::NonZero)], "t")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("bow and itself cross at (6.666667, 6.666667)"),
            "{e}"
        );
        let shared = vec![
            raw(square(0.0, 0.0, 10.0, true), "l", FillRule::NonZero),
            raw(square(10.0, 0.0, 10.0, true), "r", FillRule::NonZero),
        ];
        let e = build(shared, "t").unwrap_err();
        assert!(
            matches!(
                e,
                OutlineError::Crossing {
                    kind: CrossingKind::Overlap,
                    ..
                }
            ),
            "{e}"
        );
        // Spike: out along a line and back.
        let spike = vec![
            Vertex::line(0.0, 0.0),
            Vertex::line(10.0, 0.0),
            Vertex::line(20.0, 0.0),
            Vertex::line(10.0, 0.0),
            Vertex::line(10.0, 10.0),
        ];
        assert!(build(vec![raw(spike, "s", FillRule::NonZero)], "t").is_err());
    }

    /// Issue 17 item 13: a symmetric bow-tie has zero signed area, and was reported as
    /// "zero area"; it crosses itself, and says where.
    #[test]
    fn symmetric_bowtie_is_reported_as_crossing_itself() {
        let bowtie = vec![
            Vertex::line(0.0, 0.0),
            Vertex::line(10.0, 10.0),
            Vertex::line(10.0, 0.0),
            Vertex::line(0.0, 10.0),
        ];
        let e = build(vec![raw(bowtie, "bow", FillRule::NonZero)], "t")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("bow and itself cross at (5.000000, 5.000000)"),
            "{e}"
        );
    }

    #[test]
    fn vertex_touch_is_not_a_crossing() {
        // Two squares sharing only the corner (10, 10).
        let cs = vec![
            raw(square(0.0, 0.0, 10.0, true), "a", FillRule::NonZero),
            raw(square(10.0, 10.0, 5.0, false), "b", FillRule::NonZero),
        ];
        let s = build(cs, "t").unwrap();
        assert_eq!(areas(&s), vec![100.0, 25.0]);
        // A triangle hole whose vertex touches the outer boundary from inside.
        let tri = vec![
            Vertex::line(5.0, 0.0),
            Vertex::line(7.0, 4.0),
            Vertex::line(3.0, 4.0),
        ];
        let cs = vec![
            raw(square(0.0, 0.0, 10.0, true), "a", FillRule::EvenOdd),
            raw(tri, "t", FillRule::EvenOdd),
        ];
        let s = build(cs, "t").unwrap();
        assert_eq!(areas(&s), vec![100.0, -8.0]);
        // …but a vertex poking through is a crossing.
        let tri = vec![
            Vertex::line(5.0, -1.0),
            Vertex::line(7.0, 4.0),
            Vertex::line(3.0, 4.0),
        ];
        let cs = vec![
            raw(square(0.0, 0.0, 10.0, true), "a", FillRule::EvenOdd),
            raw(tri, "t", FillRule::EvenOdd),
        ];
        assert!(build(cs, "t").is_err());
    }

    #[test]
    fn tangential_touch_told_apart_by_curvature() {
        // Two circles of radii 1 and 2 touching internally at (1, 0): the small one inside the
        // big one, both passing (1, 0) vertically; vertices at the touch point.
        let big = vec![
            Vertex {
                point: Point2::new(1.0, 0.0),
                bulge: 1.0,
            },
            Vertex {
                point: Point2::new(-3.0, 0.0),
                bulge: 1.0,
            },
        ];
        let small = circle(0.0, 0.0, 1.0, true);
        let s = build(
            vec![
                raw(big, "big", FillRule::EvenOdd),
                raw(small, "small", FillRule::EvenOdd),
            ],
            "t",
        )
        .unwrap();
        let a = areas(&s);
        assert!(
            (a[0] - 4.0 * std::f64::consts::PI).abs() < 1e-12
                && (a[1] + std::f64::consts::PI).abs() < 1e-12
        );
        // Same radius at the same point, same direction: overlap.
        let twin = vec![
            raw(circle(0.0, 0.0, 1.0, true), "a", FillRule::EvenOdd),
            raw(circle(0.0, 0.0, 1.0, true), "b", FillRule::EvenOdd),
        ];
        assert!(build(twin, "t").is_err());
    }

    #[test]
    fn zero_area_and_reverse() {
        let flat = vec![
            Vertex::line(0.0, 0.0),
            Vertex::line(10.0, 0.0),
            Vertex::line(5.0, 0.0),
        ];
        let e = build(vec![raw(flat, "flat one", FillRule::NonZero)], "t")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("flat one") && (e.contains("zero area") || e.contains("overlap")),
            "{e}"
        );
        let c = Contour {
            vertices: vec![
                Vertex {
                    point: Point2::new(0.0, 0.0),
                    bulge: 0.3,
                },
                Vertex::line(4.0, 0.0),
                Vertex {
                    point: Point2::new(4.0, 3.0),
                    bulge: -0.2,
                },
            ],
        };
        let r = Contour {
            vertices: reverse_closed(&c.vertices),
        };
        assert!((r.signed_area() + c.signed_area()).abs() < 1e-12);
        assert!((r.length() - c.length()).abs() < 1e-12);
    }
}
