//! The typed layer: the entities that carry a part's faces, read from their parameter records
//! into exact geometry in millimetres (IGES 5.3 §4: 100 arc, 102 composite curve, 110 line, 120
//! surface of revolution, 124 transformation, 126 B-spline curve, 128 B-spline surface, 142
//! curve on surface, 144 trimmed surface; parameter layouts as in the module docs).

use nalgebra::{Matrix3, Point3, Rotation3, Unit, Vector3, Vector4};

use super::IgesError;
use super::cards::{RawEntity, RawFile, parse_real};
use crate::cad::nurbs::{NurbsCurve, NurbsSurface};

/// Deepest chain of transformation matrices or composite curves followed.
const MAX_DEPTH: usize = 16;

/// Most simple curves one composite curve (102) may expand to, nested members counted.
const MAX_COMPOSITE_LEAVES: usize = 1_000_000;

/// A rigid (or reflecting) map `x ↦ R·x + t` (entity 124).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    /// R.
    pub rotation: Matrix3<f64>,
    /// t, mm.
    pub translation: Vector3<f64>,
}

impl Transform {
    fn identity() -> Transform {
        Transform {
            rotation: Matrix3::identity(),
            translation: Vector3::zeros(),
        }
    }
    fn apply(&self, p: &Point3<f64>) -> Point3<f64> {
        Point3::from(self.rotation * p.coords + self.translation)
    }
    /// `self` after `inner`.
    fn after(&self, inner: &Transform) -> Transform {
        Transform {
            rotation: self.rotation * inner.rotation,
            translation: self.rotation * inner.translation + self.translation,
        }
    }
    fn scaled(&self, s: f64) -> Transform {
        Transform {
            rotation: self.rotation,
            translation: self.translation * s,
        }
    }
}

/// A curve in model space (mm) or in a surface's parameter plane (z = 0).
#[derive(Clone, Debug, PartialEq)]
pub enum Curve {
    /// A segment (110), parameter `t ∈ [0, 1]`.
    Line {
        /// Where it starts.
        start: Point3<f64>,
        /// Where it ends.
        end: Point3<f64>,
    },
    /// A circular arc (100), counter-clockwise about the transformed +Z from `start` to `end`,
    /// a full circle when they coincide; parameter the angle from `start`.
    Arc {
        /// The circle's centre.
        centre: Point3<f64>,
        /// Where it starts.
        start: Point3<f64>,
        /// The sweep, radians, in (0, 2π].
        sweep: f64,
        /// The arc plane's normal (the transformed +Z).
        normal: Unit<Vector3<f64>>,
    },
    /// A B-spline curve (126) on the parameter range `range`.
    Nurbs {
        /// The curve.
        curve: NurbsCurve,
        /// The parameter range used (126's V(0), V(1)).
        range: (f64, f64),
    },
    /// A chain of curves (102), each ending where the next starts.
    Composite(Vec<Curve>),
}

impl Curve {
    /// The number of simple curves (lines, arcs, NURBS) this curve is made of.
    fn leaves(&self) -> usize {
        match self {
            Curve::Composite(members) => members.iter().map(Curve::leaves).sum(),
            _ => 1,
        }
    }

    /// Points along the curve, ends included, at least `per_piece` intervals per member (more
    /// for a NURBS of many spans).
    pub fn sample(&self, per_piece: usize) -> Vec<Point3<f64>> {
        let n = per_piece.max(1);
        match self {
            Curve::Line { start, end } => vec![*start, *end],
            Curve::Arc {
                centre,
                start,
                sweep,
                normal,
            } => {
                let steps = ((sweep.abs() / (std::f64::consts::PI / 36.0)).ceil() as usize).max(n);
                (0..=steps)
                    .map(|k| {
                        let r = Rotation3::from_axis_angle(normal, sweep * k as f64 / steps as f64);
                        centre + r * (start - centre)
                    })
                    .collect()
            }
            Curve::Nurbs { curve, range } => {
                let spans = curve.knots().windows(2).filter(|w| w[1] > w[0]).count();
                let steps = n * spans.max(1) * curve.degree().max(1);
                (0..=steps)
                    .map(|k| curve.point(range.0 + (range.1 - range.0) * k as f64 / steps as f64))
                    .collect()
            }
            Curve::Composite(members) => {
                let mut out: Vec<Point3<f64>> = Vec::new();
                for m in members {
                    let pts = m.sample(per_piece);
                    let skip = usize::from(!out.is_empty());
                    out.extend(pts.into_iter().skip(skip));
                }
                out
            }
        }
    }
}

/// A surface a face lies on.
#[derive(Clone, Debug, PartialEq)]
pub enum Surface {
    /// A B-spline surface (128) on the parameter rectangle `u × v`.
    Nurbs {
        /// The surface.
        surface: NurbsSurface,
        /// Parameter range in u (128's U(0), U(1)).
        u: (f64, f64),
        /// Parameter range in v.
        v: (f64, f64),
    },
    /// A surface of revolution (120): the generatrix `C(t)` turned by `θ ∈ angles` (radians,
    /// right-handed) about the line from `axis.0` to `axis.1`; parameters `(t, θ)`.
    Revolution {
        /// Start and end of the axis (a 110).
        axis: (Point3<f64>, Point3<f64>),
        /// The generatrix.
        generatrix: Box<Curve>,
        /// The generatrix's parameter range.
        t: (f64, f64),
        /// Start and end angle, radians.
        angles: (f64, f64),
    },
}

impl Surface {
    /// The parameter rectangle `((u₀, u₁), (v₀, v₁))`.
    pub fn domain(&self) -> ((f64, f64), (f64, f64)) {
        match self {
            Surface::Nurbs { u, v, .. } => (*u, *v),
            Surface::Revolution { t, angles, .. } => (*t, *angles),
        }
    }

    /// The point at `(u, v)`.
    pub fn point(&self, u: f64, v: f64) -> Point3<f64> {
        match self {
            Surface::Nurbs { surface, .. } => surface.point(u, v),
            Surface::Revolution {
                axis, generatrix, ..
            } => {
                let c = curve_point(generatrix, u);
                let direction = Unit::new_normalize(axis.1 - axis.0);
                let r = Rotation3::from_axis_angle(&direction, v);
                axis.0 + r * (c - axis.0)
            }
        }
    }
}

/// The point of a generatrix at its own parameter `t` (a segment on [0, 1], a NURBS on its
/// range, a composite on the concatenation of its members' ranges).
fn curve_point(curve: &Curve, t: f64) -> Point3<f64> {
    match curve {
        Curve::Line { start, end } => start + (end - start) * t,
        Curve::Arc {
            centre,
            start,
            normal,
            ..
        } => centre + Rotation3::from_axis_angle(normal, t) * (start - centre),
        Curve::Nurbs { curve, .. } => curve.point(t),
        Curve::Composite(members) => {
            // Member k spans [k, k + 1) of the composite's parameter.
            let k = (t.floor().max(0.0) as usize).min(members.len().saturating_sub(1));
            members
                .get(k)
                .map_or(Point3::origin(), |m| curve_point(m, t - k as f64))
        }
    }
}

/// A face: a surface and the loops that trim it (144), or a whole surface.
#[derive(Clone, Debug, PartialEq)]
pub struct Face {
    /// The DE of the entity the face comes from (144, or an untrimmed surface's).
    pub de: usize,
    /// Its directory line.
    pub line: usize,
    /// The surface it lies on.
    pub surface: Surface,
    /// The outer boundary in the surface's parameter plane; `None`: the domain's boundary.
    pub outer: Option<Curve>,
    /// Holes, in the parameter plane.
    pub holes: Vec<Curve>,
    /// The same boundaries in model space, where the file gives them (outer first).
    pub model_boundaries: Vec<Curve>,
}

/// Typed access to one entity's parameters with errors naming the line, entity and index.
struct Params<'a> {
    e: &'a RawEntity,
}

impl<'a> Params<'a> {
    fn error(&self, i: usize, what: impl std::fmt::Display) -> IgesError {
        let line = self
            .e
            .parameters
            .get(i)
            .or(self.e.parameters.last())
            .map_or(self.e.line, |t| t.line);
        IgesError::at(
            line,
            format!(
                "entity {} at DE {}, parameter {i}: {what}",
                self.e.entity_type, self.e.de
            ),
        )
    }
    fn text(&self, i: usize) -> Result<&'a str, IgesError> {
        self.e
            .parameters
            .get(i)
            .map(|t| t.text.as_str())
            .ok_or_else(|| {
                self.error(
                    i,
                    format!("missing (the record has {})", self.e.parameters.len() - 1),
                )
            })
    }
    fn real(&self, i: usize) -> Result<f64, IgesError> {
        let t = self.text(i)?;
        if t.is_empty() {
            return Ok(0.0);
        }
        parse_real(t).ok_or_else(|| self.error(i, format!("'{t}' is not a finite number")))
    }
    fn int(&self, i: usize) -> Result<i64, IgesError> {
        let t = self.text(i)?;
        if t.is_empty() {
            return Ok(0);
        }
        t.parse()
            .map_err(|_| self.error(i, format!("'{t}' is not an integer")))
    }
    fn count(&self, i: usize, most: usize) -> Result<usize, IgesError> {
        let v = self.int(i)?;
        usize::try_from(v)
            .ok()
            .filter(|&v| v <= most)
            .ok_or_else(|| self.error(i, format!("count {v} is negative or beyond the record")))
    }
    fn point(&self, i: usize) -> Result<Point3<f64>, IgesError> {
        Ok(Point3::new(
            self.real(i)?,
            self.real(i + 1)?,
            self.real(i + 2)?,
        ))
    }
    /// `q`, read from parameter `i` on, placed by `place`: finite in the file may still be
    /// infinite once transformed and scaled to millimetres.
    fn placed(
        &self,
        place: &Transform,
        q: Point3<f64>,
        i: usize,
    ) -> Result<Point3<f64>, IgesError> {
        let q = place.apply(&q);
        if q.iter().all(|c| c.is_finite()) {
            Ok(q)
        } else {
            Err(self.error(i, "the point is not finite once placed in mm"))
        }
    }
    fn len(&self) -> usize {
        self.e.parameters.len().saturating_sub(1)
    }
}

/// Reads geometry out of a raw file, in millimetres.
pub struct Reader<'a> {
    file: &'a RawFile,
    /// Millimetres per model unit.
    scale: f64,
}

impl<'a> Reader<'a> {
    /// A reader of `file`, its coordinates scaled to mm by the Global section's units.
    pub fn new(file: &'a RawFile) -> Result<Reader<'a>, IgesError> {
        let scale = file
            .global
            .millimetres_per_unit()
            .map_err(|reason| IgesError::at(1, reason))?;
        Ok(Reader { file, scale })
    }

    fn entity(&self, de: usize, from: &RawEntity, what: &str) -> Result<&'a RawEntity, IgesError> {
        self.file.entity(de).ok_or_else(|| {
            IgesError::at(
                from.line,
                format!(
                    "entity {} at DE {}: its {what} points to DE {de}, which is not an entity",
                    from.entity_type, from.de
                ),
            )
        })
    }

    /// The model-space map of entity `e`: its 124 chain, then units to mm.
    fn placement(&self, e: &RawEntity) -> Result<Transform, IgesError> {
        let mut total = Transform::identity();
        let mut de = e.transform;
        let mut depth = 0;
        while de != 0 {
            depth += 1;
            let t = self.entity(de, e, "transformation matrix")?;
            if t.entity_type != 124 || depth > MAX_DEPTH {
                return Err(IgesError::at(
                    e.line,
                    format!(
                        "entity {} at DE {}: its transformation matrix DE {de} is entity {} \
                         (124 expected) or the chain is deeper than {MAX_DEPTH}",
                        e.entity_type, e.de, t.entity_type
                    ),
                ));
            }
            let p = Params { e: t };
            let mut rotation = Matrix3::zeros();
            let mut translation = Vector3::zeros();
            for row in 0..3 {
                for col in 0..3 {
                    rotation[(row, col)] = p.real(1 + 4 * row + col)?;
                }
                translation[row] = p.real(4 + 4 * row)?;
            }
            // The matrix of a 124 applies first, then the one its own DE points to.
            total = Transform {
                rotation,
                translation,
            }
            .after(&total);
            de = t.transform;
        }
        Ok(Transform {
            rotation: total.rotation,
            translation: total.translation,
        }
        .scaled(self.scale))
    }

    /// A curve; `model`: in model space (placed and in mm), else a parameter-plane curve.
    pub fn curve(
        &self,
        de: usize,
        from: &RawEntity,
        model: bool,
        depth: usize,
    ) -> Result<Curve, IgesError> {
        let e = self.entity(de, from, "curve")?;
        let p = Params { e };
        let place = if model {
            let t = self.placement(e)?;
            Transform {
                rotation: t.rotation * self.scale,
                translation: t.translation,
            }
        } else {
            Transform::identity()
        };
        match e.entity_type {
            110 => Ok(Curve::Line {
                start: p.placed(&place, p.point(1)?, 1)?,
                end: p.placed(&place, p.point(4)?, 4)?,
            }),
            100 => {
                let z = p.real(1)?;
                let centre = Point3::new(p.real(2)?, p.real(3)?, z);
                let start = Point3::new(p.real(4)?, p.real(5)?, z);
                let end = Point3::new(p.real(6)?, p.real(7)?, z);
                let a0 = (start.y - centre.y).atan2(start.x - centre.x);
                let a1 = (end.y - centre.y).atan2(end.x - centre.x);
                let mut sweep = (a1 - a0).rem_euclid(std::f64::consts::TAU);
                if sweep < 1e-12 {
                    sweep = std::f64::consts::TAU;
                }
                let normal = place.rotation * Vector3::z();
                Ok(Curve::Arc {
                    centre: p.placed(&place, centre, 2)?,
                    start: p.placed(&place, start, 4)?,
                    sweep,
                    normal: Unit::try_new(normal, 1e-12)
                        .ok_or_else(|| p.error(0, "a degenerate transformation"))?,
                })
            }
            126 => {
                let k = p.count(1, p.len())?;
                let m = p.count(2, p.len())?;
                let n_knots = k + m + 2;
                let need = 5 * k + m + 17;
                if p.len() < need - 2 {
                    return Err(p.error(
                        p.len(),
                        format!(
                            "{} parameters for K = {k}, M = {m}: {need} expected",
                            p.len()
                        ),
                    ));
                }
                let knots = (0..n_knots)
                    .map(|i| p.real(7 + i))
                    .collect::<Result<Vec<_>, _>>()?;
                let wbase = 7 + n_knots;
                let pbase = wbase + k + 1;
                let points = (0..=k)
                    .map(|i| {
                        let w = p.real(wbase + i)?;
                        let q = place.apply(&p.point(pbase + 3 * i)?);
                        Ok(Vector4::new(q.x * w, q.y * w, q.z * w, w))
                    })
                    .collect::<Result<Vec<_>, IgesError>>()?;
                let curve = NurbsCurve::from_homogeneous(m, knots, points)
                    .map_err(|err| p.error(1, err))?;
                let range_at = pbase + 3 * (k + 1);
                let (a, b) = curve.domain();
                let range = match (p.real(range_at), p.real(range_at + 1)) {
                    (Ok(v0), Ok(v1)) if v1 > v0 => (v0.max(a), v1.min(b)),
                    _ => (a, b),
                };
                Ok(Curve::Nurbs { curve, range })
            }
            102 => {
                if depth > MAX_DEPTH {
                    return Err(p.error(1, "composite curves nested too deep"));
                }
                let n = p.count(1, p.len())?;
                // A member may be referenced many times over, and nested: counted as it is
                // read, so a small file cannot expand into billions of curves.
                let mut members = Vec::with_capacity(n);
                let mut leaves = 0;
                for i in 0..n {
                    let member = self.curve(p.count(2 + i, usize::MAX)?, e, model, depth + 1)?;
                    leaves += member.leaves();
                    if leaves > MAX_COMPOSITE_LEAVES {
                        return Err(p.error(
                            2 + i,
                            format!(
                                "the composite curve expands to more than \
                                 {MAX_COMPOSITE_LEAVES} simple curves"
                            ),
                        ));
                    }
                    members.push(member);
                }
                Ok(Curve::Composite(members))
            }
            other => Err(p.error(
                0,
                format!("curve entity {other} is not read (100, 102, 110 and 126 are)"),
            )),
        }
    }

    /// The surface entity at `de` (128 or 120), in model space.
    pub fn surface(&self, de: usize, from: &RawEntity) -> Result<Surface, IgesError> {
        let e = self.entity(de, from, "surface")?;
        let p = Params { e };
        match e.entity_type {
            128 => {
                let k1 = p.count(1, p.len())?;
                let k2 = p.count(2, p.len())?;
                let m1 = p.count(3, p.len())?;
                let m2 = p.count(4, p.len())?;
                let a = k1 + m1 + 2;
                let b = k2 + m2 + 2;
                let c = (k1 + 1)
                    .checked_mul(k2 + 1)
                    .filter(|&c| c <= p.len())
                    .ok_or_else(|| p.error(1, "a control net larger than the record"))?;
                let need = 9 + a + b + 4 * c + 4;
                if p.len() < need - 4 {
                    return Err(p.error(
                        p.len(),
                        format!(
                            "{} parameters for a {}×{} net of degree {m1}×{m2}: {need} expected",
                            p.len(),
                            k1 + 1,
                            k2 + 1
                        ),
                    ));
                }
                let knots_u = (0..a)
                    .map(|i| p.real(10 + i))
                    .collect::<Result<Vec<_>, _>>()?;
                let knots_v = (0..b)
                    .map(|i| p.real(10 + a + i))
                    .collect::<Result<Vec<_>, _>>()?;
                let wbase = 10 + a + b;
                let pbase = wbase + c;
                let place = self.placement(e)?;
                let place = Transform {
                    rotation: place.rotation * self.scale,
                    translation: place.translation,
                };
                // The file's index (i, j) = (u, v) has i varying fastest; the net is row-major
                // in u.
                let mut points = vec![Vector4::zeros(); c];
                for j in 0..=k2 {
                    for i in 0..=k1 {
                        let f = i + j * (k1 + 1);
                        let w = p.real(wbase + f)?;
                        let q = place.apply(&p.point(pbase + 3 * f)?);
                        points[i * (k2 + 1) + j] = Vector4::new(q.x * w, q.y * w, q.z * w, w);
                    }
                }
                let surface = NurbsSurface::from_homogeneous(
                    [m1, m2],
                    knots_u,
                    knots_v,
                    k1 + 1,
                    k2 + 1,
                    points,
                )
                .map_err(|err| p.error(1, err))?;
                let ((u0, u1), (v0, v1)) = surface.domain();
                let r = pbase + 3 * c;
                let range =
                    |lo: Result<f64, IgesError>, hi: Result<f64, IgesError>, a: f64, b: f64| {
                        // A stated range outside the knot domain (or crossing it) says nothing
                        // usable: the whole domain is the surface then.
                        match (lo, hi) {
                            (Ok(lo), Ok(hi)) if lo.max(a) < hi.min(b) => (lo.max(a), hi.min(b)),
                            _ => (a, b),
                        }
                    };
                Ok(Surface::Nurbs {
                    u: range(p.real(r), p.real(r + 1), u0, u1),
                    v: range(p.real(r + 2), p.real(r + 3), v0, v1),
                    surface,
                })
            }
            120 => {
                let axis = match self.curve(p.count(1, usize::MAX)?, e, true, 0)? {
                    Curve::Line { start, end } if (end - start).norm() > 0.0 => (start, end),
                    _ => {
                        return Err(p.error(
                            1,
                            "the axis of revolution must be a line (110) of some length",
                        ));
                    }
                };
                let generatrix = self.curve(p.count(2, usize::MAX)?, e, true, 0)?;
                let t = match &generatrix {
                    Curve::Nurbs { range, .. } => *range,
                    Curve::Composite(members) => (0.0, members.len() as f64),
                    Curve::Arc { sweep, .. } => (0.0, *sweep),
                    Curve::Line { .. } => (0.0, 1.0),
                };
                let angles = (p.real(3)?, p.real(4)?);
                if angles.1 <= angles.0 || angles.1.is_nan() {
                    return Err(p.error(
                        3,
                        format!(
                            "angles {} to {}: the end must follow the start",
                            angles.0, angles.1
                        ),
                    ));
                }
                Ok(Surface::Revolution {
                    axis,
                    generatrix: Box::new(generatrix),
                    t,
                    angles,
                })
            }
            other => Err(p.error(
                0,
                format!("surface entity {other} is not read (120 and 128 are)"),
            )),
        }
    }

    /// A curve on a surface (142): its parameter-plane curve and its model-space curve, where
    /// given.
    fn curve_on_surface(
        &self,
        de: usize,
        face: &RawEntity,
    ) -> Result<(Option<Curve>, Option<Curve>), IgesError> {
        let e = self.entity(de, face, "boundary")?;
        let p = Params { e };
        if e.entity_type != 142 {
            return Err(p.error(
                0,
                "a trimmed surface's boundary must be a curve on surface (142)",
            ));
        }
        let parameter = match p.count(3, usize::MAX)? {
            0 => None,
            b => Some(self.curve(b, e, false, 0)?),
        };
        let model = match p.count(4, usize::MAX)? {
            0 => None,
            c => Some(self.curve(c, e, true, 0)?),
        };
        Ok((parameter, model))
    }

    /// A trimmed surface (144).
    pub fn trimmed_face(&self, e: &RawEntity) -> Result<Face, IgesError> {
        let p = Params { e };
        let surface = self.surface(p.count(1, usize::MAX)?, e)?;
        let n1 = p.int(2)?;
        let n2 = p.count(3, p.len())?;
        let mut model_boundaries = Vec::new();
        let outer = if n1 == 0 {
            None
        } else {
            let (parameter, model) = self.curve_on_surface(p.count(4, usize::MAX)?, e)?;
            model_boundaries.extend(model);
            Some(parameter.ok_or_else(|| {
                p.error(
                    4,
                    "the outer boundary has no parameter-plane curve (only those are read)",
                )
            })?)
        };
        let holes = (0..n2)
            .map(|i| {
                let (parameter, model) = self.curve_on_surface(p.count(5 + i, usize::MAX)?, e)?;
                model_boundaries.extend(model);
                parameter.ok_or_else(|| {
                    p.error(
                        5 + i,
                        "a hole has no parameter-plane curve (only those are read)",
                    )
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Face {
            de: e.de,
            line: e.line,
            surface,
            outer,
            holes,
            model_boundaries,
        })
    }
}
