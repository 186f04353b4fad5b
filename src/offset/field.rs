//! The offset region as a distance field: f(x) = minₖ (sdₖ(x) − levelₖ), the union of the
//! offset of the level surface and of the next shape (module docs). f is 1-Lipschitz (a min of
//! distance functions), which is what lets [`super::extract`] skip whole blocks of the grid
//! from one query at their centre.

use rayon::prelude::*;

use crate::geom::{Point3, Vector3};
use crate::mesh::Mesh;
use crate::mesh::{Closest, SurfaceDistance};

/// Alternating projections onto the terms' level sets at a crease of the union (where two
/// terms are both near zero) settle in one or two rounds; more buys nothing.
const PROJECTION_ROUNDS: usize = 4;

/// Rounds of shortening the moves of vertices that would turn a triangle over.
const REVERT_ROUNDS: usize = 4;

/// One term: the region within `level` of a surface, and its inside when it is closed
/// (signed distance by pseudo-normals). Without the inside, the tube around a closed surface
/// would also have an inner sheet: a cavity that splits the shape in two.
pub(super) struct Term<'a> {
    pub surface: &'a SurfaceDistance,
    pub closed: bool,
    pub level: f64,
}

/// A term's value at a point and the closest point it came from.
struct Sample {
    value: f64,
    closest: Closest,
    inside: bool,
}

impl Term<'_> {
    /// The term at `p` if the surface is within `reach` of it. A closed term is always
    /// evaluated: deep inside, its very negative value decides the sign, which an unlimited
    /// search is the only way to know.
    fn sample(&self, p: &Point3, reach: f64) -> Option<Sample> {
        let reach = if self.closed { f64::INFINITY } else { reach };
        let closest = self.surface.closest(p, reach)?;
        let inside =
            self.closed && (p - closest.point).dot(&self.surface.pseudo_normal(&closest)) < 0.0;
        let signed = if inside {
            -closest.distance
        } else {
            closest.distance
        };
        Some(Sample {
            value: signed - self.level,
            closest,
            inside,
        })
    }

    /// The point at distance `level + margin` from the surface along the line from the
    /// closest point through `p` (along the pseudo-normal when `p` is on the surface).
    fn project(&self, p: &Point3, s: &Sample, margin: f64) -> Point3 {
        let away = p - s.closest.point;
        let direction = if s.closest.distance > 1e-12 {
            away / s.closest.distance * if s.inside { -1.0 } else { 1.0 }
        } else {
            let n = self.surface.pseudo_normal(&s.closest);
            n / n.norm().max(f64::MIN_POSITIVE)
        };
        s.closest.point + direction * (self.level + margin)
    }
}

/// The union of the terms' regions.
pub(super) struct Field<'a> {
    pub terms: Vec<Term<'a>>,
}

impl Field<'_> {
    /// f(p), searching each open (tube) surface only within `reach` of its level: terms with
    /// nothing that near count as +∞, which they are not below (a tube's value is ≥ −level).
    pub fn value(&self, p: &Point3, reach: f64) -> f64 {
        self.terms
            .iter()
            .filter_map(|t| t.sample(p, t.level + reach).map(|s| s.value))
            .fold(f64::INFINITY, f64::min)
    }

    /// min over terms of unsigned distance − level: how far `p` is from the tube of any
    /// term, inside or out (the zero set lies in the tubes).
    pub fn tube_value(&self, p: &Point3, reach: f64) -> f64 {
        self.terms
            .iter()
            .filter_map(|t| {
                t.surface
                    .closest(p, t.level + reach)
                    .map(|c| c.distance - t.level)
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// Moves `p` onto the level set f = `margin`: project onto the smallest term's level set,
    /// and again if that leaves another term below it (a crease of the union).
    fn project(&self, p: &Point3, margin: f64) -> Point3 {
        let mut x = *p;
        for _ in 0..PROJECTION_ROUNDS {
            let Some((term, sample)) = self
                .terms
                .iter()
                .filter_map(|t| t.sample(&x, f64::INFINITY).map(|s| (t, s)))
                .min_by(|a, b| a.1.value.total_cmp(&b.1.value))
            else {
                return x;
            };
            if (sample.value - margin).abs() <= 1e-12 * (1.0 + term.level) {
                break;
            }
            x = term.project(&x, &sample, margin);
        }
        x
    }

    /// Puts every vertex of an extracted surface on the level set, lifted by a chord margin
    /// ℓ²/(6·offset) (ℓ its longest edge: the sag of a triangle of that size inscribed in a
    /// sphere of radius `offset`, the smallest radius of a convex part of the offset), so that
    /// edges and faces, not just vertices, keep their distance. A vertex whose move would flip
    /// an incident triangle goes only part of the way, or stays where the grid put it; the
    /// verification judges it.
    pub fn project_vertices(&self, mut mesh: Mesh, offset: f64) -> Mesh {
        let mut longest = vec![0.0f64; mesh.positions.len()];
        for t in &mesh.triangles {
            for k in 0..3 {
                let (a, b) = (t[k] as usize, t[(k + 1) % 3] as usize);
                let l = (mesh.positions[a] - mesh.positions[b]).norm();
                longest[a] = longest[a].max(l);
                longest[b] = longest[b].max(l);
            }
        }
        let before: Vec<Vector3> = (0..mesh.triangles.len())
            .map(|t| mesh.face_normal(t))
            .collect();
        let original = mesh.positions.clone();
        let projected: Vec<Point3> = original
            .par_iter()
            .zip(&longest)
            .map(|(p, l)| self.project(p, l * l / (6.0 * offset.max(f64::MIN_POSITIVE))))
            .collect();
        // A vertex whose move turns an incident triangle over goes only part of the way
        // (halved each round); after the last round it stays where the grid put it.
        let mut share = vec![1.0f64; original.len()];
        for round in 0..=REVERT_ROUNDS {
            for v in 0..original.len() {
                mesh.positions[v] = original[v] + (projected[v] - original[v]) * share[v];
            }
            if round == REVERT_ROUNDS {
                break;
            }
            let mut turned = false;
            for (t, tri) in mesh.triangles.iter().enumerate() {
                if mesh.face_normal(t).dot(&before[t]) <= 0.0 {
                    turned = true;
                    for &v in tri {
                        share[v as usize] = if round + 1 == REVERT_ROUNDS {
                            0.0
                        } else {
                            share[v as usize] * 0.5
                        };
                    }
                }
            }
            if !turned {
                break;
            }
        }
        mesh
    }
}
