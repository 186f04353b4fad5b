//! Convex-hull boxes of a part's surfaces (seed 002 §3–4, after Chuang & Pan): every face's
//! surface split into Bézier patches, each patch wrapped in the axis-aligned box of its
//! control points. A Bézier patch with positive weights lies in the convex hull of its
//! control points, and the hull in its box, so a tool that enters no box cannot overcut any
//! surface — with no surface–plane intersection solved anywhere.
//!
//! * B-spline surfaces (128) become patches by knot insertion (seed 002 eq. 1–2,
//!   [`super::nurbs::NurbsSurface::bezier_patches`]).
//! * Surfaces of revolution (120) become patches exactly: each Bézier piece of the generatrix
//!   swept by rational quadratic arcs of at most 90° (the standard NURBS circle), so a hub
//!   turned by 360° is four patches per generatrix piece, not an approximation.
//! * [`split_patch`] is de Casteljau's subdivision at the middle in both directions (seed 002
//!   fig. 11–12): four patches whose boxes are tighter, which is how a layer thicker than the
//!   maximum depth of cut gets its intermediate slicing planes.
//!
//! A trimmed face keeps the patches whose parameter rectangles meet its trimmed region (the
//! trim loops sampled in the parameter plane, each rectangle grown by the longest chord of
//! the samples so that a loop bulging between two samples cannot slip past): CAD surfaces
//! reach well beyond their faces (a blade's surface past the hub and the tip), and boxes of
//! what was trimmed away would keep the tool off material it may cut. The enclosure is
//! checked independently of the construction: [`HullBoxes::enclosure`] evaluates untrimmed
//! faces' surfaces (de Boor on the original entity) on a grid, [`HullBoxes::mesh_enclosure`]
//! takes every vertex of the tessellation (the tessellator trims on its own); each point must
//! lie in a box of its face.

use nalgebra::{Point2, Rotation3, Unit, Vector3, Vector4};
use rayon::prelude::*;

use super::iges::{Curve, Face, Surface};
use super::nurbs::BezierPatch;
use crate::geom::{Aabb, Point3};

/// Relative margin of a box around its control points, for the round-off of evaluation.
pub const ROUND_OFF: f64 = 1e-12;

/// One Bézier patch of a face, in the boxes' frame, and its box.
#[derive(Clone, Debug, PartialEq)]
pub struct HullPatch {
    /// Index of the face (in the model's face order) the patch belongs to.
    pub face: usize,
    /// The patch's homogeneous control net, in the boxes' frame.
    pub patch: BezierPatch,
    /// The box of its control points (widened by [`ROUND_OFF`] of their size).
    pub bounds: Aabb,
    /// How many times it was split from a patch of the surface's own decomposition.
    pub splits: u8,
}

impl HullPatch {
    fn new(face: usize, patch: BezierPatch, splits: u8) -> HullPatch {
        let hull = Aabb::from_points(patch.control_points().collect::<Vec<_>>().iter());
        // The patch's points are computed in floating point too: a point on the box's face
        // may come out an ulp or two outside it. A relative 1e-12 keeps them in.
        let size = hull.min.coords.amax().max(hull.max.coords.amax()).max(1.0);
        let bounds = hull.inflated(ROUND_OFF * size);
        HullPatch {
            face,
            patch,
            bounds,
            splits,
        }
    }

    /// The four patches of de Casteljau's split at the middle, with their boxes.
    pub fn split(&self) -> [HullPatch; 4] {
        split_patch(&self.patch).map(|p| HullPatch::new(self.face, p, self.splits + 1))
    }
}

/// Why a face cannot be boxed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("face at directory line {line}: {reason}")]
pub struct BoxError {
    /// The face's directory line in the IGES file.
    pub line: usize,
    /// What is wrong.
    pub reason: String,
}

/// The convex-hull boxes of a part (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct HullBoxes {
    /// The patches, face by face, each face's in its surface's patch order.
    pub patches: Vec<HullPatch>,
    /// The rotation from the file's frame into the boxes' frame.
    pub frame: Rotation3<f64>,
    /// Patches left out because their parameter rectangles lie outside their face's trim.
    pub trimmed_away: usize,
}

/// What [`HullBoxes::enclosure`] found.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Enclosure {
    /// Surface points checked.
    pub samples: usize,
    /// Points in no box of their face.
    pub outside: usize,
    /// The farthest such point from its face's boxes, mm (0 when none is outside).
    pub worst_mm: f64,
}

impl HullBoxes {
    /// The boxes of `faces`' surfaces with every control point turned by `frame` (the
    /// rotation that stands the part up for machining; the boxes are axis-aligned in that
    /// frame, not the file's).
    pub fn of_faces(faces: &[Face], frame: Rotation3<f64>) -> Result<HullBoxes, BoxError> {
        type FacePatches = (Vec<HullPatch>, usize);
        let per_face: Vec<Result<FacePatches, BoxError>> = faces
            .par_iter()
            .enumerate()
            .map(|(index, face)| {
                let patches = surface_patches(&face.surface).map_err(|reason| BoxError {
                    line: face.line,
                    reason,
                })?;
                let trim = TrimRegion::of(face);
                let all = patches.len();
                let kept: Vec<HullPatch> = patches
                    .into_iter()
                    .filter(|p| trim.as_ref().is_none_or(|t| t.meets(p.u, p.v)))
                    .map(|mut p| {
                        for q in &mut p.points {
                            let turned = frame * q.xyz();
                            *q = Vector4::new(turned.x, turned.y, turned.z, q.w);
                        }
                        HullPatch::new(index, p, 0)
                    })
                    .collect();
                let away = all - kept.len();
                Ok((kept, away))
            })
            .collect();
        let mut patches = Vec::new();
        let mut trimmed_away = 0;
        for face in per_face {
            let (kept, away) = face?;
            patches.extend(kept);
            trimmed_away += away;
        }
        Ok(HullBoxes {
            patches,
            frame,
            trimmed_away,
        })
    }

    /// Checks that the boxes enclose a tessellation of the faces (`mesh` in the file's frame,
    /// `face_of_triangle` naming each triangle's face): every corner of every triangle, turned
    /// into the boxes' frame, within `slack` mm (the tessellation's tolerance: seam vertices
    /// are welded between faces) of a box of the triangle's face.
    pub fn mesh_enclosure(
        &self,
        mesh: &crate::mesh::Mesh,
        face_of_triangle: &[u32],
        slack: f64,
    ) -> Enclosure {
        let by_face = self.boxes_by_face(
            face_of_triangle
                .iter()
                .map(|&f| f as usize)
                .max()
                .map_or(0, |m| m + 1),
        );
        let per_triangle: Vec<(usize, f64)> = mesh
            .triangles
            .par_iter()
            .zip(face_of_triangle)
            .map(|(t, &face)| {
                let boxes = by_face.get(face as usize).map_or(&[][..], |b| &b[..]);
                let (mut outside, mut worst) = (0, 0.0f64);
                for &v in t {
                    let nearest = nearest_box(boxes, &(self.frame * mesh.positions[v as usize]));
                    if nearest > slack {
                        outside += 1;
                        worst = worst.max(nearest);
                    }
                }
                (outside, worst)
            })
            .collect();
        Enclosure {
            samples: 3 * mesh.triangles.len(),
            outside: per_triangle.iter().map(|t| t.0).sum(),
            worst_mm: per_triangle.iter().map(|t| t.1).fold(0.0, f64::max),
        }
    }

    /// The boxes of each of `faces` faces.
    fn boxes_by_face(&self, faces: usize) -> Vec<Vec<&Aabb>> {
        let mut by_face: Vec<Vec<&Aabb>> = vec![Vec::new(); faces];
        for p in &self.patches {
            if let Some(list) = by_face.get_mut(p.face) {
                list.push(&p.bounds);
            }
        }
        by_face
    }

    /// The boxes, in patch order.
    pub fn boxes(&self) -> impl Iterator<Item = &Aabb> + '_ {
        self.patches.iter().map(|p| &p.bounds)
    }

    /// The box around every box.
    pub fn bounds(&self) -> Aabb {
        self.boxes().fold(Aabb::empty(), |a, b| a.merge(b))
    }

    /// Checks that the boxes enclose the untrimmed faces' surfaces: each evaluated on its own
    /// (de Boor, or the generatrix turned about its axis) at a grid of parameters, about
    /// `density` points per patch side, every point turned into the boxes' frame and looked
    /// for in the boxes of its face (with a round-off slack of 1e-9 of the part's size).
    /// Trimmed faces are left to [`HullBoxes::mesh_enclosure`].
    pub fn enclosure(&self, faces: &[Face], density: usize) -> Enclosure {
        let by_face = self.boxes_by_face(faces.len());
        let slack = 1e-9 * self.bounds().diagonal().max(1.0);
        let per_face: Vec<(usize, usize, f64)> = faces
            .par_iter()
            .zip(&by_face)
            .filter(|(face, _)| face.outer.is_none() && face.holes.is_empty())
            .map(|(face, boxes)| {
                let ((u0, u1), (v0, v1)) = face.surface.domain();
                let side = density.max(1) * (boxes.len() as f64).sqrt().ceil().max(1.0) as usize;
                let n = side.clamp(8, 400);
                let (mut outside, mut worst) = (0, 0.0f64);
                for i in 0..=n {
                    for j in 0..=n {
                        let u = u0 + (u1 - u0) * i as f64 / n as f64;
                        let v = v0 + (v1 - v0) * j as f64 / n as f64;
                        let nearest = nearest_box(boxes, &(self.frame * face.surface.point(u, v)));
                        if nearest > slack {
                            outside += 1;
                            worst = worst.max(nearest);
                        }
                    }
                }
                ((n + 1) * (n + 1), outside, worst)
            })
            .collect();
        Enclosure {
            samples: per_face.iter().map(|f| f.0).sum(),
            outside: per_face.iter().map(|f| f.1).sum(),
            worst_mm: per_face.iter().map(|f| f.2).fold(0.0, f64::max),
        }
    }
}

/// The distance from `p` to the nearest of `boxes` (0 inside one, ∞ for none).
fn nearest_box(boxes: &[&Aabb], p: &Point3) -> f64 {
    boxes
        .iter()
        .map(|b| b.distance_squared(p))
        .fold(f64::INFINITY, f64::min)
        .sqrt()
}

/// A face's trimmed region in its parameter plane, as sampled loops, and how far a loop may
/// stand off its samples.
struct TrimRegion {
    outer: Option<Vec<Point2<f64>>>,
    holes: Vec<Vec<Point2<f64>>>,
    /// The longest chord between two samples: a rectangle grown by it cannot miss a loop
    /// that bends between samples by less than that.
    margin: f64,
}

/// Samples per curve piece of a trim loop.
const TRIM_SAMPLES: usize = 16;

impl TrimRegion {
    /// `None` for a face that is its whole surface.
    fn of(face: &Face) -> Option<TrimRegion> {
        if face.outer.is_none() && face.holes.is_empty() {
            return None;
        }
        let polygon = |c: &Curve| -> Vec<Point2<f64>> {
            c.sample(TRIM_SAMPLES)
                .into_iter()
                .map(|p| Point2::new(p.x, p.y))
                .collect()
        };
        let outer = face.outer.as_ref().map(polygon);
        let holes: Vec<Vec<Point2<f64>>> = face.holes.iter().map(polygon).collect();
        let margin = outer
            .iter()
            .chain(&holes)
            .flat_map(|l| l.windows(2).map(|w| (w[1] - w[0]).norm()))
            .fold(0.0, f64::max);
        Some(TrimRegion {
            outer,
            holes,
            margin,
        })
    }

    /// Whether the rectangle `u × v`, grown by the margin, may hold a point of the region:
    /// it meets the outer loop or lies inside it, and is not wholly inside a hole.
    fn meets(&self, u: (f64, f64), v: (f64, f64)) -> bool {
        let lo = Point2::new(u.0.min(u.1) - self.margin, v.0.min(v.1) - self.margin);
        let hi = Point2::new(u.0.max(u.1) + self.margin, v.0.max(v.1) + self.margin);
        let centre = nalgebra::center(&lo, &hi);
        let square = crate::geom::Aabb2 { min: lo, max: hi };
        let crosses = |l: &[Point2<f64>]| {
            l.windows(2).any(|w| square.meets_segment(w[0], w[1]))
                || l.first()
                    .is_some_and(|p| p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y)
        };
        let in_outer = match &self.outer {
            Some(l) => crosses(l) || inside_polygon(l, centre),
            None => true,
        };
        in_outer
            && !self
                .holes
                .iter()
                .any(|h| !crosses(h) && inside_polygon(h, centre))
    }
}

/// Even–odd test of `p` against the closed polyline `loop_` (its last point may repeat the
/// first).
fn inside_polygon(loop_: &[Point2<f64>], p: Point2<f64>) -> bool {
    let n = loop_.len();
    let mut inside = false;
    for k in 0..n {
        let (a, b) = (loop_[k], loop_[(k + 1) % n]);
        if (a.y > p.y) != (b.y > p.y) {
            let x = a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x);
            if p.x < x {
                inside = !inside;
            }
        }
    }
    inside
}

/// The Bézier patches of a surface in the file's frame.
fn surface_patches(surface: &Surface) -> Result<Vec<BezierPatch>, String> {
    match surface {
        Surface::Nurbs { surface, .. } => Ok(surface.bezier_patches()),
        Surface::Revolution {
            axis,
            generatrix,
            t,
            angles,
        } => {
            let direction = Unit::try_new(axis.1 - axis.0, 1e-12)
                .ok_or("the surface of revolution's axis has no length")?;
            let pieces = curve_pieces(generatrix, *t)?;
            Ok(revolve(axis.0, direction, &pieces, *angles))
        }
    }
}

/// A Bézier piece of a curve: its parameter interval and homogeneous control points.
type Piece = ((f64, f64), Vec<Vector4<f64>>);

/// The Bézier pieces of a generatrix meeting the parameter range `range` (a segment on
/// [0, 1], an arc as rational quadratics of at most 90° on its angle, a NURBS by knot
/// insertion, a composite member k on [k, k + 1]).
fn curve_pieces(curve: &Curve, range: (f64, f64)) -> Result<Vec<Piece>, String> {
    let (lo, hi) = (range.0.min(range.1), range.0.max(range.1));
    Ok(match curve {
        Curve::Line { start, end } => vec![(
            (0.0, 1.0),
            vec![start.coords.push(1.0), end.coords.push(1.0)],
        )],
        Curve::Arc {
            centre,
            start,
            sweep,
            normal,
        } => {
            let arcs = (sweep.abs() / std::f64::consts::FRAC_PI_2).ceil().max(1.0) as usize;
            let step = sweep / arcs as f64;
            (0..arcs)
                .map(|k| {
                    let a = step * k as f64;
                    let at = |angle: f64, scale: f64| {
                        centre
                            + Rotation3::from_axis_angle(normal, angle) * (start - centre) * scale
                    };
                    let c = (step / 2.0).cos();
                    let middle = at(a + step / 2.0, 1.0 / c);
                    (
                        (a, a + step),
                        vec![
                            at(a, 1.0).coords.push(1.0),
                            (middle.coords * c).push(c),
                            at(a + step, 1.0).coords.push(1.0),
                        ],
                    )
                })
                .collect()
        }
        Curve::Nurbs { curve, .. } => curve
            .bezier_pieces()
            .into_iter()
            .filter(|(a, b, _)| *b >= lo && *a <= hi)
            .map(|(a, b, points)| ((a, b), points))
            .collect(),
        Curve::Composite(members) => {
            let mut out = Vec::new();
            for (k, member) in members.iter().enumerate() {
                let offset = k as f64;
                if offset + 1.0 < lo || offset > hi {
                    continue;
                }
                for ((a, b), points) in curve_pieces(member, (lo - offset, hi - offset))? {
                    out.push(((a + offset, b + offset), points));
                }
            }
            if out.is_empty() {
                return Err("the generatrix has no piece in the surface's range".into());
            }
            out
        }
    })
}

/// Each piece turned about the axis through `origin` along `direction` by `angles` (radians,
/// right-handed), as rational Bézier patches of degree (piece's, 2): per arc of at most 90°,
/// a control point's circle is the rational quadratic with its middle point at 1/cos(φ/2)
/// of the radius on the bisector and weight cos(φ/2) (times the piece's weight).
fn revolve(
    origin: Point3,
    direction: Unit<Vector3<f64>>,
    pieces: &[Piece],
    angles: (f64, f64),
) -> Vec<BezierPatch> {
    let sweep = angles.1 - angles.0;
    let arcs = (sweep.abs() / std::f64::consts::FRAC_PI_2).ceil().max(1.0) as usize;
    let step = sweep / arcs as f64;
    let half = (step / 2.0).cos();
    let mut patches = Vec::with_capacity(pieces.len() * arcs);
    for (range, points) in pieces {
        for k in 0..arcs {
            let a = angles.0 + step * k as f64;
            let turned = |q: &Vector4<f64>, angle: f64, scale: f64, weight: f64| {
                let p = Point3::from(q.xyz() / q.w);
                let height = (p - origin).dot(&direction);
                let radial = (p - origin) - direction.into_inner() * height;
                let at = origin
                    + direction.into_inner() * height
                    + Rotation3::from_axis_angle(&direction, angle) * radial * scale;
                (at.coords * (q.w * weight)).push(q.w * weight)
            };
            let net = points
                .iter()
                .flat_map(|q| {
                    [
                        turned(q, a, 1.0, 1.0),
                        turned(q, a + step / 2.0, 1.0 / half, half),
                        turned(q, a + step, 1.0, 1.0),
                    ]
                })
                .collect();
            patches.push(BezierPatch {
                u: *range,
                v: (a, a + step),
                degree: [points.len() - 1, 2],
                points: net,
            });
        }
    }
    patches
}

/// de Casteljau's split of a Bézier patch at the middle of both parameters (seed 002 fig.
/// 11–12), homogeneous throughout so a rational patch stays exact: the four quarters, in the
/// order (low u, low v), (low u, high v), (high u, low v), (high u, high v).
pub fn split_patch(patch: &BezierPatch) -> [BezierPatch; 4] {
    let [p, q] = patch.degree;
    let columns = q + 1;
    // Along u: each column of the net (a curve in u) halved.
    let mut low_u = patch.points.clone();
    let mut high_u = patch.points.clone();
    for j in 0..columns {
        let column: Vec<Vector4<f64>> = (0..=p).map(|i| patch.points[i * columns + j]).collect();
        let (a, b) = halve(&column);
        for i in 0..=p {
            low_u[i * columns + j] = a[i];
            high_u[i * columns + j] = b[i];
        }
    }
    let split_v = |net: &[Vector4<f64>]| {
        let mut low = net.to_vec();
        let mut high = net.to_vec();
        for i in 0..=p {
            let (a, b) = halve(&net[i * columns..(i + 1) * columns]);
            low[i * columns..(i + 1) * columns].copy_from_slice(&a);
            high[i * columns..(i + 1) * columns].copy_from_slice(&b);
        }
        (low, high)
    };
    let (um, vm) = (0.5 * (patch.u.0 + patch.u.1), 0.5 * (patch.v.0 + patch.v.1));
    let (a, b) = split_v(&low_u);
    let (c, d) = split_v(&high_u);
    let make = |u, v, points| BezierPatch {
        u,
        v,
        degree: patch.degree,
        points,
    };
    [
        make((patch.u.0, um), (patch.v.0, vm), a),
        make((patch.u.0, um), (vm, patch.v.1), b),
        make((um, patch.u.1), (patch.v.0, vm), c),
        make((um, patch.u.1), (vm, patch.v.1), d),
    ]
}

/// A Bézier curve's control points halved at t = ½ by de Casteljau: the left half's points
/// are the first of each level, the right half's the last, reversed.
fn halve(points: &[Vector4<f64>]) -> (Vec<Vector4<f64>>, Vec<Vector4<f64>>) {
    let n = points.len();
    let mut level = points.to_vec();
    let mut left = Vec::with_capacity(n);
    let mut right = Vec::with_capacity(n);
    left.push(level[0]);
    right.push(level[n - 1]);
    for _ in 1..n {
        for i in 0..level.len() - 1 {
            level[i] = (level[i] + level[i + 1]) * 0.5;
        }
        level.pop();
        left.push(level[0]);
        right.push(level[level.len() - 1]);
    }
    right.reverse();
    (left, right)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cad::iges::Face;
    use crate::cad::nurbs::NurbsSurface;

    fn face(surface: Surface) -> Face {
        Face {
            de: 1,
            line: 1,
            surface,
            outer: None,
            holes: Vec::new(),
            model_boundaries: Vec::new(),
        }
    }

    /// A sphere of radius 10 as a surface of revolution: a half circle turned by 360°. Its
    /// patches evaluate on the sphere (closed form), and its boxes' union spans exactly the
    /// sphere's box (the rational quadratic's middle control points stand out, but the box of
    /// the whole is the sphere's: every extreme of the sphere is a patch corner).
    #[test]
    fn a_sphere_of_revolution_is_boxed_exactly() {
        let sphere = Surface::Revolution {
            axis: (Point3::origin(), Point3::new(0.0, 0.0, 1.0)),
            generatrix: Box::new(Curve::Arc {
                centre: Point3::origin(),
                start: Point3::new(0.0, 0.0, -10.0),
                sweep: std::f64::consts::PI,
                normal: Unit::new_normalize(Vector3::new(0.0, -1.0, 0.0)),
            }),
            t: (0.0, std::f64::consts::PI),
            angles: (0.0, 2.0 * std::f64::consts::PI),
        };
        let faces = [face(sphere)];
        let boxes = HullBoxes::of_faces(&faces, Rotation3::identity()).unwrap();
        // Two 90° generatrix arcs × four 90° turns.
        assert_eq!(boxes.patches.len(), 8);
        for p in &boxes.patches {
            for k in 0..=8 {
                for l in 0..=8 {
                    let q = p.patch.point(k as f64 / 8.0, l as f64 / 8.0);
                    assert!(((q - Point3::origin()).norm() - 10.0).abs() < 1e-9);
                    assert!(p.bounds.distance_squared(&q) == 0.0);
                }
            }
        }
        let all = boxes.bounds();
        assert!((all.min - Point3::new(-10.0, -10.0, -10.0)).norm() < 1e-9);
        assert!((all.max - Point3::new(10.0, 10.0, 10.0)).norm() < 1e-9);
        // The middle control points of the arcs stand outside the sphere, at 10/cos 45°.
        assert!(
            boxes
                .patches
                .iter()
                .all(|p| p.bounds.extent().max() <= 10.0 + 1e-9)
        );
        let enclosure = boxes.enclosure(&faces, 4);
        assert_eq!(enclosure.outside, 0);
        assert!(enclosure.samples > 100);
    }

    /// de Casteljau's quarters reproduce the patch: each quarter at (s, t) is the whole at
    /// the corresponding point, and the quarters' boxes lie inside the whole's box.
    #[test]
    fn split_quarters_reproduce_the_patch() {
        // A rational bicubic-by-quadratic patch with uneven weights.
        let points = (0..4)
            .flat_map(|i| {
                (0..3).map(move |j| {
                    let w = 1.0 + 0.3 * ((i * 3 + j) % 4) as f64;
                    let p = Vector3::new(i as f64 * 2.0, j as f64 * 3.0, ((i * j) % 3) as f64);
                    (p * w).push(w)
                })
            })
            .collect();
        let patch = BezierPatch {
            u: (1.0, 3.0),
            v: (0.0, 1.0),
            degree: [3, 2],
            points,
        };
        let whole = HullPatch::new(0, patch.clone(), 0);
        let quarters = whole.split();
        let corners = [(0.0, 0.0), (0.0, 0.5), (0.5, 0.0), (0.5, 0.5)];
        for (quarter, (s0, t0)) in quarters.iter().zip(corners) {
            assert_eq!(quarter.splits, 1);
            let inside = whole.bounds.inflated(1e-9).merge(&quarter.bounds);
            assert_eq!(inside, whole.bounds.inflated(1e-9));
            for k in 0..=5 {
                for l in 0..=5 {
                    let (s, t) = (k as f64 / 5.0, l as f64 / 5.0);
                    let got = quarter.patch.point(s, t);
                    let want = patch.point(s0 + 0.5 * s, t0 + 0.5 * t);
                    assert!((got - want).norm() < 1e-12, "{got} vs {want}");
                }
            }
        }
        // A split box is no larger than its parent, and here strictly smaller.
        let volume = |b: &Aabb| b.extent().x * b.extent().y * b.extent().z;
        let sum: f64 = quarters.iter().map(|q| volume(&q.bounds)).sum();
        assert!(sum < volume(&whole.bounds));
    }

    /// A B-spline surface's boxes enclose it, and a turned frame turns the boxes: boxes of
    /// the part stood upside down are the mirror of the upright ones in z.
    #[test]
    fn a_bspline_surface_is_enclosed_in_either_frame() {
        let net: Vec<Vec<Point3>> = (0..5)
            .map(|i| {
                (0..4)
                    .map(|j| {
                        Point3::new(
                            i as f64 * 5.0,
                            j as f64 * 4.0,
                            ((i + 2 * j) % 3) as f64 * 2.0,
                        )
                    })
                    .collect()
            })
            .collect();
        let weights = vec![vec![1.0; 4]; 5];
        let surface = NurbsSurface::new(
            [3, 2],
            vec![0.0, 0.0, 0.0, 0.0, 0.5, 1.0, 1.0, 1.0, 1.0],
            vec![0.0, 0.0, 0.0, 0.4, 1.0, 1.0, 1.0],
            &net,
            &weights,
        )
        .unwrap();
        let faces = [face(Surface::Nurbs {
            surface: surface.clone(),
            u: (0.0, 1.0),
            v: (0.0, 1.0),
        })];
        let upright = HullBoxes::of_faces(&faces, Rotation3::identity()).unwrap();
        assert_eq!(upright.patches.len(), 4);
        assert_eq!(upright.enclosure(&faces, 6).outside, 0);
        let flipped_frame = Rotation3::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI);
        let flipped = HullBoxes::of_faces(&faces, flipped_frame).unwrap();
        assert_eq!(flipped.enclosure(&faces, 6).outside, 0);
        for (a, b) in upright.boxes().zip(flipped.boxes()) {
            assert!((a.max.z + b.min.z).abs() < 1e-9 && (a.min.z + b.max.z).abs() < 1e-9);
        }
        // Boxes flattened to their lower halves no longer hold the surface's top: the
        // check finds it out.
        let mut broken = upright.clone();
        for p in &mut broken.patches {
            p.bounds.max.z = 0.5 * (p.bounds.min.z + p.bounds.max.z);
        }
        let enclosure = broken.enclosure(&faces, 6);
        assert!(enclosure.outside > 0 && enclosure.worst_mm > 0.1);
    }
}
