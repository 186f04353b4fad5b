//! One face's triangles: a constrained Delaunay triangulation of its parameter region, with
//! the trim loops as constraint edges, refined until the linear triangles stay within the
//! tolerance of the surface.
//!
//! The triangulation runs in the parameter plane scaled by the surface's mean speed along u
//! and v, so that a triangle that is well shaped there is roughly well shaped in space. The
//! refinement inserts, for every triangle whose surface leaves it by more than the tolerance,
//! the worst of its centroid and its free edges' midpoints, and repeats. Boundary edges are
//! never split: they are shared with the neighbouring faces (see `seams`).

use std::collections::HashSet;

use nalgebra::{Point2, Point3};
use spade::handles::FixedVertexHandle;
use spade::{
    ConstrainedDelaunayTriangulation, Point2 as SpadePoint, PositionInTriangulation, Triangulation,
};

use super::FaceSurface;
use super::caps::{CAP_THINNESS, thinness};
use super::trim::BoundaryLoop;
use crate::mesh::region::faces_inside;

/// Where a triangle corner's position comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Corner {
    /// A welded boundary vertex (shared with other faces).
    Boundary(u32),
    /// The face's own interior vertex with this index.
    Interior(u32),
}

/// A face's triangulation: its vertices (parameter values and sources) and its triangles.
#[derive(Clone, Debug, Default)]
pub(super) struct FaceMesh {
    /// Parameter values of the triangulation's vertices.
    pub uv: Vec<Point2<f64>>,
    /// Where each vertex's position comes from.
    pub corners: Vec<Corner>,
    /// Positions of the interior vertices (on the surface).
    pub interior: Vec<Point3<f64>>,
    /// Triangles over `uv`/`corners`, counter-clockwise in the parameter plane.
    pub triangles: Vec<[u32; 3]>,
}

/// Why a face could not be triangulated.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct FaceError(pub String);

type Cdt = ConstrainedDelaunayTriangulation<SpadePoint<f64>>;

/// Most vertices one face may need before it is refused: a guard against a surface the
/// tolerance cannot be met on (a singular parameterisation), not a limit real faces meet.
const MAX_FACE_VERTICES: usize = 2_000_000;

/// Triangulates a face bounded by `loops` (welded ids in `ids`), refining until the surface
/// is within `tolerance` of every triangle at its centroid and free edges' midpoints.
/// `boundary_positions` are the welded positions.
pub(super) fn triangulate_face(
    surface: &FaceSurface,
    loops: &[BoundaryLoop],
    ids: &[Vec<u32>],
    boundary_positions: &[Point3<f64>],
    tolerance: f64,
) -> Result<FaceMesh, FaceError> {
    let scale = parameter_scale(surface, loops);
    // spade refuses magnitudes below ~1e-26 other than zero; such a coordinate is zero here.
    let flush = |x: f64| if x.abs() < 1e-20 { 0.0 } else { x };
    let to_plane =
        |uv: &Point2<f64>| SpadePoint::new(flush(uv.x * scale[0]), flush(uv.y * scale[1]));
    let mut cdt = Cdt::new();
    let mut mesh = FaceMesh::default();
    let mut positions: Vec<Point3<f64>> = Vec::new();
    // Each vertex where this face put it, before welding moved it to its neighbours'.
    let mut own: Vec<Point3<f64>> = Vec::new();
    let mut handles: Vec<Vec<FixedVertexHandle>> = Vec::with_capacity(loops.len());
    for (lp, lp_ids) in loops.iter().zip(ids) {
        let mut hs = Vec::with_capacity(lp.len());
        for (v, &id) in lp.iter().zip(lp_ids) {
            let h = cdt.insert(to_plane(&v.uv)).map_err(|e| {
                FaceError(format!(
                    "boundary point (u, v) = ({}, {}): {e:?}",
                    v.uv.x, v.uv.y
                ))
            })?;
            if h.index() == mesh.uv.len() {
                mesh.uv.push(v.uv);
                mesh.corners.push(Corner::Boundary(id));
                positions.push(boundary_positions[id as usize]);
                own.push(v.position);
            }
            hs.push(h);
        }
        handles.push(hs);
    }
    for hs in &handles {
        for (i, &from) in hs.iter().enumerate() {
            let to = hs[(i + 1) % hs.len()];
            if from == to || cdt.exists_constraint(from, to) {
                continue;
            }
            let added = cdt.try_add_constraint(from, to);
            if added.len() != 1 {
                let at = mesh.uv[from.index()];
                return Err(FaceError(format!(
                    "its trim loops cross or touch near (u, v) = ({:.6}, {:.6})",
                    at.x, at.y
                )));
            }
        }
    }

    let boundary_vertices = mesh.uv.len() as u32;
    let mut settled: HashSet<[u32; 3]> = HashSet::new();
    loop {
        let inside = inside_faces(&cdt)?;
        // (error, point, the triangle it came from)
        let mut wanted: Vec<(f64, Point2<f64>, [u32; 3])> = Vec::new();
        for f in cdt.inner_faces() {
            if !inside[f.fix().index()] {
                continue;
            }
            let vs = f.vertices().map(|v| v.fix().index() as u32);
            let mut key = vs;
            key.sort_unstable();
            if settled.contains(&key) {
                continue;
            }
            let uv = vs.map(|i| mesh.uv[i as usize]);
            let p = vs.map(|i| positions[i as usize]);
            let plane = uv.map(|q| to_plane(&q));
            let edges = f.adjacent_edges();
            // A point too near a boundary edge would split it in spade's exact arithmetic; a
            // triangle that thin is left as it is (the deviation measure still sees it).
            let clear_of_boundary = |q: &Point2<f64>| {
                let q = to_plane(q);
                edges.iter().enumerate().all(|(k, e)| {
                    !e.is_constraint_edge()
                        || plane_distance(q, plane[k], plane[(k + 1) % 3])
                            > 1e-9 * plane_length(plane[k], plane[(k + 1) % 3])
                })
            };
            let mut worst: Option<(f64, Point2<f64>)> = None;
            let mut consider = |error: f64, at: Point2<f64>| {
                if worst.is_none_or(|w| error > w.0) && clear_of_boundary(&at) {
                    worst = Some((error, at));
                }
            };
            let centroid_uv = Point2::from((uv[0].coords + uv[1].coords + uv[2].coords) / 3.0);
            let centroid = Point3::from((p[0].coords + p[1].coords + p[2].coords) / 3.0);
            consider(
                (surface.point(centroid_uv.x, centroid_uv.y) - centroid).norm(),
                centroid_uv,
            );
            for (k, e) in edges.iter().enumerate() {
                if e.is_constraint_edge() {
                    continue;
                }
                // Edge k of a spade face runs from vertex k to vertex k + 1.
                let (a, b) = (k, (k + 1) % 3);
                let mid_uv = Point2::from((uv[a].coords + uv[b].coords) * 0.5);
                let mid = Point3::from((p[a].coords + p[b].coords) * 0.5);
                consider((surface.point(mid_uv.x, mid_uv.y) - mid).norm(), mid_uv);
            }
            let worst = worst.unwrap_or((0.0, centroid_uv));
            if worst.0 > tolerance {
                // The circumcentre where it lies inside (Delaunay refinement: the new
                // triangles are well shaped and no smaller than they need be), else the
                // worst test point.
                let at = circumcentre_inside(plane)
                    .map(|c| Point2::new(c.x / scale[0], c.y / scale[1]))
                    .filter(|c| clear_of_boundary(c))
                    .unwrap_or(worst.1);
                wanted.push((worst.0, at, key));
            } else {
                settled.insert(key);
            }
        }
        if wanted.is_empty() {
            break;
        }
        // Worst first, and only into triangles no insertion of this round has changed: a point
        // fixes its neighbours' errors too, and inserting theirs as well would over-refine.
        wanted.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.2.cmp(&b.2)));
        let vertices_before = mesh.uv.len();
        for (_, uv, key) in wanted {
            // A corner of the triangle the point came from: the walks start next to it.
            let hint = FixedVertexHandle::from_index(key[0] as usize);
            let unchanged = match cdt.locate_with_hint(to_plane(&uv), hint) {
                PositionInTriangulation::OnFace(f) => {
                    let mut k = cdt.face(f).vertices().map(|v| v.fix().index() as u32);
                    k.sort_unstable();
                    k == key
                }
                PositionInTriangulation::OnEdge(e) => {
                    // An edge midpoint: either side may be its triangle.
                    let e = cdt.directed_edge(e);
                    [e.face(), e.rev().face()].iter().any(|f| {
                        f.as_inner().is_some_and(|f| {
                            let mut k = f.vertices().map(|v| v.fix().index() as u32);
                            k.sort_unstable();
                            k == key
                        })
                    })
                }
                _ => false,
            };
            if !unchanged {
                continue;
            }
            let constraints = cdt.num_constraints();
            let h = cdt
                .insert_with_hint(to_plane(&uv), hint)
                .map_err(|e| FaceError(format!("refinement point {uv:?}: {e:?}")))?;
            if cdt.num_constraints() != constraints {
                // The point fell on a boundary edge and split it: undo, the boundary is shared.
                return Err(FaceError(format!(
                    "a refinement point fell on a trim edge at (u, v) = ({:.6}, {:.6})",
                    uv.x, uv.y
                )));
            }
            if h.index() == mesh.uv.len() {
                let position = surface.point(uv.x, uv.y);
                mesh.uv.push(uv);
                mesh.corners
                    .push(Corner::Interior(mesh.interior.len() as u32));
                mesh.interior.push(position);
                positions.push(position);
                own.push(position);
            }
        }
        if mesh.uv.len() == vertices_before {
            // Every wanted point fell on an existing vertex: nothing more to gain here.
            break;
        }
        if mesh.uv.len() > MAX_FACE_VERTICES {
            return Err(FaceError(format!(
                "more than {MAX_FACE_VERTICES} vertices would be needed at this tolerance"
            )));
        }
    }
    let inside = inside_faces(&cdt)?;
    mesh.triangles = cdt
        .inner_faces()
        .filter(|f| inside[f.fix().index()])
        .map(|f| f.vertices().map(|v| v.fix().index() as u32))
        .collect();
    untangle(
        surface,
        &mut mesh.triangles,
        &mesh.uv,
        &own,
        &positions,
        boundary_vertices,
    );
    Ok(mesh)
}

/// Flips the longest free edge of caps and of triangles that welding turned over.
///
/// Three trim vertices in a row along a nearly straight stretch make a cap: a triangle whose
/// height is a sliver of its length, so its normal is noise (and welding, moving a corner
/// across that height, can turn it over). A cap's normal spoils the pseudo-normals that tell
/// inside from outside at its edges. Flipping its long edge with the neighbour there gives two
/// sound triangles, where they face as the surface does and are less thin than before.
fn untangle(
    surface: &FaceSurface,
    triangles: &mut [[u32; 3]],
    uv: &[Point2<f64>],
    own: &[Point3<f64>],
    welded: &[Point3<f64>],
    boundary_vertices: u32,
) {
    // The surface's normal at a triangle's parameter centroid (central differences), where
    // the parameterisation is regular; `None` at a pole or a degenerate side.
    let ((u0, u1), (v0, v1)) = surface.domain();
    let h = 1e-6 * ((u1 - u0).abs() + (v1 - v0).abs()).max(f64::MIN_POSITIVE);
    let surface_normal = |t: &[u32; 3]| {
        let c =
            (uv[t[0] as usize].coords + uv[t[1] as usize].coords + uv[t[2] as usize].coords) / 3.0;
        let su = surface.point(c.x + h, c.y) - surface.point(c.x - h, c.y);
        let sv = surface.point(c.x, c.y + h) - surface.point(c.x, c.y - h);
        let n = su.cross(&sv);
        (n.norm() > 1e-12 * su.norm() * sv.norm()).then_some(n)
    };
    let normal = |t: &[u32; 3], at: &[Point3<f64>]| {
        let [a, b, c] = t.map(|i| at[i as usize]);
        (b - a).cross(&(c - a))
    };
    let thinness = |t: &[u32; 3]| thinness(t.map(|i| welded[i as usize]));
    // Turned: against the surface where it has a normal, else against the face's own corners.
    let turned = |t: &[u32; 3]| match surface_normal(t) {
        Some(n) => normal(t, welded).dot(&n) <= 0.0,
        None => normal(t, own).dot(&normal(t, welded)) <= 0.0,
    };
    // Caps and welded folds have at least two corners on the boundary.
    let bad = |t: &[u32; 3]| {
        t.iter().filter(|&&v| v < boundary_vertices).count() >= 2
            && (thinness(t) < CAP_THINNESS || turned(t))
    };
    if !triangles.iter().any(bad) {
        return;
    }
    let mut across: std::collections::HashMap<(u32, u32), usize> = Default::default();
    for (i, t) in triangles.iter().enumerate() {
        for k in 0..3 {
            across.insert((t[k], t[(k + 1) % 3]), i);
        }
    }
    for _ in 0..3 {
        let mut changed = false;
        for i in 0..triangles.len() {
            if !bad(&triangles[i]) {
                continue;
            }
            let t = triangles[i];
            let mut sides: Vec<usize> = (0..3).collect();
            let length = |k: usize| (own[t[k] as usize] - own[t[(k + 1) % 3] as usize]).norm();
            sides.sort_by(|&x, &y| length(y).total_cmp(&length(x)));
            for k in sides {
                let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
                let Some(&j) = across.get(&(b, a)) else {
                    continue;
                };
                let u = triangles[j];
                let Some(d) = u.iter().copied().find(|&x| x != a && x != b) else {
                    continue;
                };
                let (first, second) = ([a, d, c], [d, b, c]);
                let sound = |t: &[u32; 3]| normal(t, own).norm() > 0.0 && !turned(t);
                // Both new triangles must face as the old pair did on the surface.
                let facing = normal(&t, own) + normal(&u, own);
                let before = thinness(&t).min(thinness(&u));
                if sound(&first)
                    && sound(&second)
                    && (turned(&t) || thinness(&first).min(thinness(&second)) > before)
                    && normal(&first, own).dot(&facing) > 0.0
                    && normal(&second, own).dot(&facing) > 0.0
                {
                    for (x, y) in [(a, b), (b, c), (c, a)] {
                        across.remove(&(x, y));
                    }
                    for x in 0..3 {
                        across.remove(&(u[x], u[(x + 1) % 3]));
                    }
                    triangles[i] = first;
                    triangles[j] = second;
                    for (tri, idx) in [(first, i), (second, j)] {
                        for x in 0..3 {
                            across.insert((tri[x], tri[(x + 1) % 3]), idx);
                        }
                    }
                    changed = true;
                    break;
                }
            }
        }
        if !changed {
            break;
        }
    }
}

/// For every face of the triangulation, whether it is inside the loops.
fn inside_faces(cdt: &Cdt) -> Result<Vec<bool>, FaceError> {
    faces_inside(cdt)
        .map_err(|reason| FaceError(format!("its trim loops bound no region: {reason}")))
}

/// Mean speeds `|S_u|`, `|S_v|` over the loops' parameter box (central differences on a 5 × 5
/// grid), floored so that a degenerate side cannot collapse the plane.
fn parameter_scale(surface: &FaceSurface, loops: &[BoundaryLoop]) -> [f64; 2] {
    let (mut lo, mut hi) = (
        Point2::new(f64::INFINITY, f64::INFINITY),
        Point2::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
    );
    for v in loops.iter().flatten() {
        lo = lo.inf(&v.uv);
        hi = hi.sup(&v.uv);
    }
    let size = hi - lo;
    if !(size.x > 0.0 && size.y > 0.0) {
        return [1.0, 1.0];
    }
    let h = size * 1e-4;
    let (mut su, mut sv) = (0.0, 0.0);
    for i in 0..5 {
        for j in 0..5 {
            let u = lo.x + size.x * (i as f64 + 0.5) / 5.0;
            let v = lo.y + size.y * (j as f64 + 0.5) / 5.0;
            su += (surface.point(u + h.x, v) - surface.point(u - h.x, v)).norm() / (2.0 * h.x);
            sv += (surface.point(u, v + h.y) - surface.point(u, v - h.y)).norm() / (2.0 * h.y);
        }
    }
    let floor = 1e-6 * (su + sv).max(f64::MIN_POSITIVE);
    [(su / 25.0).max(floor), (sv / 25.0).max(floor)]
}

fn plane_length(a: SpadePoint<f64>, b: SpadePoint<f64>) -> f64 {
    (b.x - a.x).hypot(b.y - a.y)
}

/// Distance from `q` to the segment `a`–`b` in the (scaled) parameter plane.
fn plane_distance(q: SpadePoint<f64>, a: SpadePoint<f64>, b: SpadePoint<f64>) -> f64 {
    let (dx, dy) = (b.x - a.x, b.y - a.y);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((q.x - a.x) * dx + (q.y - a.y) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (q.x - a.x - t * dx).hypot(q.y - a.y - t * dy)
}

/// The circumcentre of a triangle of the (scaled) parameter plane when it lies inside the
/// triangle (the triangle is acute), else `None`.
fn circumcentre_inside(t: [SpadePoint<f64>; 3]) -> Option<SpadePoint<f64>> {
    let [a, b, c] = t;
    let (bx, by, cx, cy) = (b.x - a.x, b.y - a.y, c.x - a.x, c.y - a.y);
    let d = 2.0 * (bx * cy - by * cx);
    if d.abs() <= f64::EPSILON * (bx * bx + by * by + cx * cx + cy * cy) {
        return None;
    }
    let (b2, c2) = (bx * bx + by * by, cx * cx + cy * cy);
    let ux = (cy * b2 - by * c2) / d;
    let uy = (bx * c2 - cx * b2) / d;
    let p = SpadePoint::new(a.x + ux, a.y + uy);
    // Inside: on the inner side of every edge, by a margin.
    let side = |u: SpadePoint<f64>, v: SpadePoint<f64>| {
        (v.x - u.x) * (p.y - u.y) - (v.y - u.y) * (p.x - u.x)
    };
    let sign = d.signum();
    let margin = 1e-6 * d.abs();
    [(a, b), (b, c), (c, a)]
        .iter()
        .all(|&(u, v)| side(u, v) * sign > margin)
        .then_some(p)
}
