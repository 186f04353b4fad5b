//! Whether a tool body is clear of the stock's material, fast enough to ask for every axis
//! candidate of a finishing pass.
//!
//! The planning of the ball operations chooses each axis so that the shank, neck and holder
//! miss the part; on a raw blank they must also miss the material the operations before left
//! (the stock run fails a plan whose non-cutting bodies touch it). The exact test is the one
//! the stock run makes: the body's interval along every dexel line it crosses against the
//! line's material ([`Stock::is_clear`]). A finishing pass asks it for tens of thousands of
//! poses, several axes each, and a holder 40 mm across crosses thousands of lines, so most
//! answers come from a bound first:
//!
//! * **A distance field.** The stock's box is cut into cubic cells of side `h`; a cell is
//!   *occupied* when a span of material crosses it (the model has material only on its lines,
//!   so an empty cell holds none). A Euclidean distance transform (Felzenszwalb and
//!   Huttenlocher's separable lower envelope of parabolas) gives every cell `D`, its centre's
//!   distance in cells to the nearest occupied cell's centre. A point `p` in cell `c` and a
//!   point `m` of material in cell `o` are each within half a cell diagonal of their centres,
//!   so |p − m| ≥ (D(c) − √3)·h: a lower bound on the distance from `p` to the material.
//!   Outside the box the bound at the nearest point of the box holds (projection onto a convex
//!   set containing the material does not lengthen distances).
//! * **Spheres along the body.** A frustum of revolution is cut into pieces along its axis;
//!   each piece lies inside the sphere about its middle point whose radius is the piece's
//!   largest radius grown by half its length (Pythagoras). A piece whose sphere the field
//!   proves clear is clear; the others get the exact line test, on that piece alone.
//!
//! So the answer is exact with respect to the model (never "clear" for a body that touches its
//! material), and the field only decides how much exact work it takes.

use rayon::prelude::*;

use super::Stock;
use super::sweep::{Frustum, LineInterval};
use crate::geom::Point3;

/// Cells of the distance field at most (16 MB of f32).
const MAX_CELLS: usize = 4_000_000;

/// The stock's material, ready for many "is this body clear of it?" questions.
#[derive(Clone, Debug)]
pub struct MaterialClearance {
    stock: Stock,
    field: DistanceField,
}

impl MaterialClearance {
    /// A copy of `stock` with its distance field (see the module docs).
    pub fn new(stock: &Stock) -> Self {
        MaterialClearance {
            field: DistanceField::of(stock),
            stock: stock.clone(),
        }
    }

    /// The side of the distance field's cells, mm.
    pub fn cell(&self) -> f64 {
        self.field.cell
    }

    /// A lower bound on the distance from `p` to the material, mm (≤ 0 where it cannot tell).
    pub fn distance_bound(&self, p: &Point3) -> f64 {
        self.field.bound(p)
    }

    /// Whether the ball of `radius` about `centre` is clear of the material (the stock run's
    /// test, as [`Self::frustum_is_clear`]); a radius ≤ 0 is clear.
    pub fn ball_is_clear(&self, centre: &Point3, radius: f64) -> bool {
        if radius.is_nan() || radius <= 0.0 || self.field.bound(centre) > radius {
            return true;
        }
        self.stock.is_clear(&super::sweep::Capsule {
            a: *centre,
            b: *centre,
            radius,
        })
    }

    /// Whether `frustum` is clear of the material: no dexel line's material overlaps the
    /// frustum's interval on it by more than 1 nm (the stock run's test).
    pub fn frustum_is_clear(&self, frustum: &Frustum) -> bool {
        let length = frustum.to - frustum.from;
        if length.is_nan() || length <= 0.0 {
            return true;
        }
        // Pieces about two cells long: their spheres are then barely larger than the body.
        let pieces = ((length / (2.0 * self.field.cell)).ceil() as usize).clamp(1, 1024);
        let step = length / pieces as f64;
        let radius_at = |h: f64| {
            frustum.radius_from
                + (h - frustum.from) / length * (frustum.radius_to - frustum.radius_from)
        };
        (0..pieces).all(|k| {
            let (from, to) = (
                frustum.from + k as f64 * step,
                frustum.from + (k + 1) as f64 * step,
            );
            let (r0, r1) = (radius_at(from), radius_at(to));
            let middle = frustum.base + frustum.axis * (0.5 * (from + to));
            let sphere = r0.max(r1).hypot(0.5 * step);
            if self.field.bound(&middle) > sphere {
                return true;
            }
            self.stock.is_clear(&Frustum {
                from,
                to,
                radius_from: r0,
                radius_to: r1,
                ..*frustum
            })
        })
    }
}

impl Stock {
    /// Whether `solid` holds no material: along every dexel line, the solid's interval and the
    /// line's material overlap by at most 1 nm (round-off, as [`Stock::touching`] counts it).
    pub fn is_clear(&self, solid: &dyn LineInterval) -> bool {
        let b = solid.bounds();
        self.grids.iter().all(|grid| {
            let (axis, across, spacing) = (grid.axis, grid.across, grid.spacing);
            let is = grid.index_range(0, b.min[across[0]], b.max[across[0]]);
            grid.index_range(1, b.min[across[1]], b.max[across[1]])
                .all(|j| {
                    is.clone().all(|i| {
                        let line = &grid.lines[i + grid.counts[0] * j];
                        if !line
                            .iter()
                            .any(|s| s.end > b.min[axis] && s.start < b.max[axis])
                        {
                            return true;
                        }
                        let mut p = Point3::origin();
                        p[across[0]] = grid.origin[0] + i as f64 * spacing;
                        p[across[1]] = grid.origin[1] + j as f64 * spacing;
                        let Some((t0, t1)) = solid.line_interval(axis, &p) else {
                            return true;
                        };
                        line.iter().all(|s| s.end.min(t1) - s.start.max(t0) <= 1e-6)
                    })
                })
        })
    }
}

/// Distances in cells from each cell's centre to the nearest occupied cell's centre, over a
/// box holding all the material.
#[derive(Clone, Debug)]
struct DistanceField {
    origin: Point3,
    cell: f64,
    counts: [usize; 3],
    /// Cell `(x, y, z)` at `x + nx·(y + ny·z)`; `f32::INFINITY` when nothing is occupied.
    distance: Vec<f32>,
}

impl DistanceField {
    fn of(stock: &Stock) -> Self {
        let bounds = stock.bounds;
        let e = bounds.extent();
        let volume = e.x.max(1e-9) * e.y.max(1e-9) * e.z.max(1e-9);
        let cell = stock
            .spacing
            .max((volume / MAX_CELLS as f64).cbrt())
            .max(1e-6);
        let counts = [0, 1, 2].map(|a| ((e[a] / cell).ceil() as usize).max(1));
        let [nx, ny, nz] = counts;
        let mut occupied = vec![false; nx * ny * nz];
        let index_of = |a: usize, v: f64| -> usize {
            (((v - bounds.min[a]) / cell).floor().max(0.0) as usize).min(counts[a] - 1)
        };
        for grid in &stock.grids {
            let (axis, across) = (grid.axis, grid.across);
            for j in 0..grid.counts[1] {
                for i in 0..grid.counts[0] {
                    let line = &grid.lines[i + grid.counts[0] * j];
                    if line.is_empty() {
                        continue;
                    }
                    let p = grid.line_point(i, j);
                    let mut at = [0usize; 3];
                    at[across[0]] = index_of(across[0], p[across[0]]);
                    at[across[1]] = index_of(across[1], p[across[1]]);
                    for s in line {
                        for k in index_of(axis, s.start)..=index_of(axis, s.end) {
                            at[axis] = k;
                            occupied[at[0] + nx * (at[1] + ny * at[2])] = true;
                        }
                    }
                }
            }
        }
        let distance = squared_distance_transform(&occupied, counts)
            .into_iter()
            .map(|d2| d2.sqrt() as f32)
            .collect();
        DistanceField {
            origin: bounds.min,
            cell,
            counts,
            distance,
        }
    }

    fn bound(&self, p: &Point3) -> f64 {
        let mut index = [0usize; 3];
        let mut outside = 0.0f64;
        for a in 0..3 {
            let t = (p[a] - self.origin[a]) / self.cell;
            let n = self.counts[a] as f64;
            let clamped = t.clamp(0.0, n);
            outside += ((t - clamped) * self.cell).powi(2);
            index[a] = (clamped.floor() as usize).min(self.counts[a] - 1);
        }
        let d = self.distance[index[0] + self.counts[0] * (index[1] + self.counts[1] * index[2])];
        if d.is_infinite() {
            return f64::INFINITY;
        }
        // The box bound and the field bound hold together; the larger is the better.
        ((d as f64 - 3f64.sqrt()) * self.cell).max(outside.sqrt())
    }
}

impl DistanceField {
    #[cfg(test)]
    fn bounds(&self) -> crate::geom::Aabb {
        let mut b = crate::geom::Aabb::empty();
        b.grow(&self.origin);
        b.grow(
            &(self.origin
                + crate::geom::Vector3::new(
                    self.counts[0] as f64,
                    self.counts[1] as f64,
                    self.counts[2] as f64,
                ) * self.cell),
        );
        b
    }
}

/// Squared Euclidean distance, in cells, from each cell to the nearest `true` one (∞ when
/// there is none): three separable passes of the 1D transform, rows in parallel.
fn squared_distance_transform(occupied: &[bool], counts: [usize; 3]) -> Vec<f64> {
    let [nx, ny, nz] = counts;
    let mut d: Vec<f64> = occupied
        .iter()
        .map(|&o| if o { 0.0 } else { f64::INFINITY })
        .collect();
    // Along x: rows are contiguous.
    d.par_chunks_mut(nx).for_each(transform_1d);
    // Along y and z: gather each line, transform, scatter back (planes in parallel).
    d.par_chunks_mut(nx * ny).for_each(|plane| {
        let mut line = vec![0.0; ny];
        for x in 0..nx {
            for (y, v) in line.iter_mut().enumerate() {
                *v = plane[x + nx * y];
            }
            transform_1d(&mut line);
            for (y, v) in line.iter().enumerate() {
                plane[x + nx * y] = *v;
            }
        }
    });
    let columns: Vec<Vec<f64>> = (0..nx * ny)
        .into_par_iter()
        .map(|xy| {
            let mut line: Vec<f64> = (0..nz).map(|z| d[xy + nx * ny * z]).collect();
            transform_1d(&mut line);
            line
        })
        .collect();
    for (xy, column) in columns.iter().enumerate() {
        for (z, v) in column.iter().enumerate() {
            d[xy + nx * ny * z] = *v;
        }
    }
    d
}

/// The 1D squared distance transform of `f` in place: f'(q) = min_p (q − p)² + f(p), by the
/// lower envelope of the parabolas rooted at the finite samples.
fn transform_1d(f: &mut [f64]) {
    let n = f.len();
    let roots: Vec<usize> = (0..n).filter(|&q| f[q].is_finite()).collect();
    if roots.is_empty() {
        return;
    }
    // Envelope: parabola roots `v` and where each starts to be lowest, `z`.
    let mut v: Vec<usize> = Vec::with_capacity(roots.len());
    let mut z: Vec<f64> = Vec::with_capacity(roots.len() + 1);
    let meet = |p: usize, q: usize, f: &[f64]| {
        ((f[q] + (q * q) as f64) - (f[p] + (p * p) as f64)) / (2.0 * (q as f64 - p as f64))
    };
    for &q in &roots {
        while let Some(&p) = v.last() {
            let s = meet(p, q, f);
            if v.len() > 1 && s <= z[z.len() - 1] {
                v.pop();
                z.pop();
            } else {
                z.push(s);
                v.push(q);
                break;
            }
        }
        if v.is_empty() {
            v.push(q);
        }
    }
    let source: Vec<f64> = f.to_vec();
    let mut k = 0;
    for (q, out) in f.iter_mut().enumerate() {
        while k < z.len() && z[k] < q as f64 {
            k += 1;
        }
        let p = v[k];
        let dq = q as f64 - p as f64;
        *out = dq * dq + source[p];
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::{Aabb, Vector3};

    fn block() -> Stock {
        let bounds = Aabb::from_points(&[Point3::new(0.0, 0.0, 0.0), Point3::new(20.0, 10.0, 8.0)]);
        Stock::block(&bounds, 0.25, 10_000_000).expect("block")
    }

    /// The 1D transform against brute force on a line with gaps and an empty end.
    #[test]
    fn one_dimensional_transform_is_the_brute_force_minimum() {
        let inf = f64::INFINITY;
        let source = [inf, 3.0, inf, inf, 0.0, 7.0, inf, 1.0, inf, inf, inf];
        let mut f = source;
        transform_1d(&mut f);
        for (q, got) in f.iter().enumerate() {
            let want = source
                .iter()
                .enumerate()
                .map(|(p, v)| (q as f64 - p as f64).powi(2) + v)
                .fold(inf, f64::min);
            assert_eq!(*got, want, "at {q}");
        }
    }

    /// The field's bound never exceeds the true distance to a block, at points around it, and
    /// is within two cell diagonals of it.
    #[test]
    fn the_field_bounds_the_distance_to_a_block_from_below() {
        let stock = block();
        let clearance = MaterialClearance::new(&stock);
        let material = stock.material_bounds();
        let cell = clearance.cell();
        let mut checked = 0;
        for k in 0..2000 {
            let t = k as f64;
            let p = Point3::new(
                -15.0 + (t * 7.31) % 50.0,
                -15.0 + (t * 3.77) % 40.0,
                -15.0 + (t * 5.13) % 38.0,
            );
            let truth = material.distance_squared(&p).sqrt();
            let bound = clearance.distance_bound(&p);
            assert!(
                bound <= truth + 1e-9,
                "{p:?}: bound {bound} > distance {truth}"
            );
            if truth > 0.0 {
                assert!(truth - bound < 2.0 * 3f64.sqrt() * cell + 1e-9, "{p:?}");
                checked += 1;
            }
        }
        assert!(checked > 1000);
        assert_eq!(
            clearance
                .field
                .bounds()
                .distance_squared(&material.center()),
            0.0
        );
    }

    /// The answer for shank-like frusta all around a block with a pocket agrees with the
    /// exact line test on the whole frustum, and both agree with the closed form where it is
    /// plain (a vertical cylinder above the top face).
    #[test]
    fn frustum_answers_agree_with_the_exact_line_test() {
        let mut stock = block();
        // A pocket 6 deep from the top, 8 × 4 across.
        let pocket = Frustum {
            base: Point3::new(10.0, 5.0, 2.0),
            axis: Vector3::z(),
            from: 0.0,
            to: 10.0,
            radius_from: 3.0,
            radius_to: 3.0,
        };
        stock.remove(&pocket);
        let clearance = MaterialClearance::new(&stock);
        let (mut clear, mut touching) = (0, 0);
        for k in 0..400 {
            let t = k as f64;
            let axis =
                Vector3::new(((t * 0.37).sin()) * 0.6, ((t * 0.91).cos()) * 0.6, 1.0).normalize();
            let frustum = Frustum {
                base: Point3::new(
                    2.0 + (t * 1.37) % 16.0,
                    1.0 + (t * 0.73) % 8.0,
                    2.0 + (t * 0.53) % 10.0,
                ),
                axis,
                from: 0.0,
                to: 12.0,
                radius_from: 1.0 + (t * 0.11) % 1.5,
                radius_to: 1.0 + (t * 0.17) % 3.0,
            };
            let fast = clearance.frustum_is_clear(&frustum);
            assert_eq!(fast, stock.is_clear(&frustum), "frustum {k}");
            if fast { clear += 1 } else { touching += 1 }
        }
        assert!(
            clear > 20 && touching > 20,
            "{clear} clear, {touching} touching"
        );
        // In the pocket, away from its wall: clear; grazing below the top face: not.
        let in_pocket = |radius: f64, bottom: f64| Frustum {
            base: Point3::new(10.0, 5.0, bottom),
            axis: Vector3::z(),
            from: 0.0,
            to: 20.0,
            radius_from: radius,
            radius_to: radius,
        };
        assert!(clearance.frustum_is_clear(&in_pocket(2.5, 2.5)));
        assert!(!clearance.frustum_is_clear(&in_pocket(3.5, 2.5)));
        assert!(!clearance.frustum_is_clear(&in_pocket(2.5, 1.5)));
        assert!(clearance.frustum_is_clear(&in_pocket(6.0, 8.2)));
    }
}
