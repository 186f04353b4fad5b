//! The top envelope of a shape seen from the spindle: on a grid of square cells, the highest
//! point of the shape over each cell — seed 002's "z-mapped grid" blocks, each cell a box from
//! the floor up to that height. A vertical tool that stays outside every box stays outside the
//! shape, so the union of the boxes taller than a layer is the region a layer must keep the
//! tool away from.
//!
//! The height of a cell is exact, not sampled: each triangle is clipped to the cell's square
//! and the highest corner of what is left counts. A point sample at cell centres would miss a
//! blade tip between two centres; the clipped maximum cannot, so the boxes enclose the shape.

use crate::geom::{Aabb, Point2, Point3};
use crate::mesh::Mesh;

/// The highest point of a shape over each cell of a grid (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct TopEnvelope {
    /// Lower-left corner of cell (0, 0).
    pub origin: Point2,
    /// Side of a cell, mm.
    pub cell: f64,
    /// Cells along x and y.
    pub width: usize,
    pub height: usize,
    /// Highest point over cell (i, j) at `i + j * width`; `-∞` where the shape has none.
    pub top: Vec<f64>,
}

impl TopEnvelope {
    /// The envelope of `mesh` on cells of `cell` mm covering its footprint (one spare cell on
    /// each side, so the boundary of every non-empty region lies inside the grid).
    pub fn of_mesh(mesh: &Mesh, cell: f64) -> TopEnvelope {
        let mut envelope = TopEnvelope::empty_over(&mesh.aabb(), cell);
        for t in 0..mesh.triangles.len() {
            envelope.add_triangle(&mesh.corners(t));
        }
        envelope
    }

    /// The envelope of axis-aligned boxes (seed 002's convex-hull boxes) on cells of `cell`
    /// mm: every cell the closed footprint of a box meets stands at least at the box's top, so
    /// the union of the cells taller than a layer holds the union of the boxes' footprints
    /// (widened to the cells' sides, by less than a cell).
    pub fn of_boxes<'a>(
        boxes: impl IntoIterator<Item = &'a Aabb> + Clone,
        cell: f64,
    ) -> TopEnvelope {
        let bounds = boxes
            .clone()
            .into_iter()
            .fold(Aabb::empty(), |a, b| a.merge(b));
        let mut envelope = TopEnvelope::empty_over(&bounds, cell);
        let width = envelope.width;
        for b in boxes {
            let (i0, j0) = envelope.index_of(b.min.x, b.min.y);
            let (i1, j1) = envelope.index_of(b.max.x, b.max.y);
            for j in j0..=j1 {
                for k in j * width + i0..=j * width + i1 {
                    envelope.top[k] = envelope.top[k].max(b.max.z);
                }
            }
        }
        envelope
    }

    /// Cells of `cell` mm over the footprint of `bounds` with one spare cell on each side (so
    /// the boundary of every non-empty region lies inside the grid), all empty.
    fn empty_over(bounds: &Aabb, cell: f64) -> TopEnvelope {
        let origin = Point2::new(bounds.min.x - cell, bounds.min.y - cell);
        let width = ((bounds.max.x - origin.x) / cell).ceil().max(0.0) as usize + 2;
        let height = ((bounds.max.y - origin.y) / cell).ceil().max(0.0) as usize + 2;
        TopEnvelope {
            origin,
            cell,
            width,
            height,
            top: vec![f64::NEG_INFINITY; width * height],
        }
    }

    /// Cell column and row of `p` (clamped to the grid).
    fn index_of(&self, x: f64, y: f64) -> (usize, usize) {
        let i = ((x - self.origin.x) / self.cell).floor();
        let j = ((y - self.origin.y) / self.cell).floor();
        (
            i.clamp(0.0, (self.width - 1) as f64) as usize,
            j.clamp(0.0, (self.height - 1) as f64) as usize,
        )
    }

    /// Raises every cell the triangle covers to the triangle's highest point over it.
    fn add_triangle(&mut self, corners: &[Point3; 3]) {
        let min_x = corners.iter().map(|p| p.x).fold(f64::INFINITY, f64::min);
        let max_x = corners
            .iter()
            .map(|p| p.x)
            .fold(f64::NEG_INFINITY, f64::max);
        let min_y = corners.iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
        let max_y = corners
            .iter()
            .map(|p| p.y)
            .fold(f64::NEG_INFINITY, f64::max);
        let (i0, j0) = self.index_of(min_x, min_y);
        let (i1, j1) = self.index_of(max_x, max_y);
        let top_z = corners
            .iter()
            .map(|p| p.z)
            .fold(f64::NEG_INFINITY, f64::max);
        for j in j0..=j1 {
            for i in i0..=i1 {
                let k = i + j * self.width;
                if self.top[k] >= top_z {
                    continue; // nothing of this triangle can raise the cell
                }
                let x0 = self.origin.x + i as f64 * self.cell;
                let y0 = self.origin.y + j as f64 * self.cell;
                if let Some(z) =
                    highest_over_square(corners, x0, y0, x0 + self.cell, y0 + self.cell)
                {
                    self.top[k] = self.top[k].max(z);
                }
            }
        }
    }

    /// Height of the cell holding `p` (`-∞` off the grid).
    pub fn top_at(&self, p: Point2) -> f64 {
        let i = ((p.x - self.origin.x) / self.cell).floor();
        let j = ((p.y - self.origin.y) / self.cell).floor();
        if i < 0.0 || j < 0.0 || i >= self.width as f64 || j >= self.height as f64 {
            return f64::NEG_INFINITY;
        }
        self.at(i as usize, j as usize)
    }

    /// Height of cell (i, j).
    pub fn at(&self, i: usize, j: usize) -> f64 {
        self.top[i + j * self.width]
    }

    /// The highest point of the shape, or `-∞` for an empty one.
    pub fn max_height(&self) -> f64 {
        self.top.iter().copied().fold(f64::NEG_INFINITY, f64::max)
    }

    /// The lowest top of a covered cell, or `+∞` for an empty shape.
    pub fn min_height(&self) -> f64 {
        self.top
            .iter()
            .copied()
            .filter(|z| z.is_finite())
            .fold(f64::INFINITY, f64::min)
    }
}

/// The highest point of the triangle over the closed square [x0, x1] × [y0, y1], if it has
/// one there: the triangle clipped to the square (Sutherland–Hodgman on its four sides, with
/// the points on a side kept) and its highest remaining corner. A linear function's maximum
/// over a convex polygon is at a corner, so this is exact.
fn highest_over_square(corners: &[Point3; 3], x0: f64, y0: f64, x1: f64, y1: f64) -> Option<f64> {
    let mut polygon: Vec<Point3> = corners.to_vec();
    // Each side as (axis, bound, keep the side where the coordinate is ≥ bound).
    for (axis, bound, keep_above) in [(0, x0, true), (0, x1, false), (1, y0, true), (1, y1, false)]
    {
        let inside = |p: &Point3| {
            let c = if axis == 0 { p.x } else { p.y };
            if keep_above { c >= bound } else { c <= bound }
        };
        let mut clipped = Vec::with_capacity(polygon.len() + 2);
        for k in 0..polygon.len() {
            let (a, b) = (polygon[k], polygon[(k + 1) % polygon.len()]);
            let (a_in, b_in) = (inside(&a), inside(&b));
            if a_in {
                clipped.push(a);
            }
            if a_in != b_in {
                let (ca, cb) = if axis == 0 { (a.x, b.x) } else { (a.y, b.y) };
                let t = ((bound - ca) / (cb - ca)).clamp(0.0, 1.0);
                let mut p = a + (b - a) * t;
                // The crossing lies on the side exactly, whatever the round-off of t.
                if axis == 0 {
                    p.x = bound;
                } else {
                    p.y = bound;
                }
                clipped.push(p);
            }
        }
        if clipped.is_empty() {
            return None;
        }
        polygon = clipped;
    }
    polygon.iter().map(|p| p.z).reduce(f64::max)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A box's envelope is its top over the cells its footprint touches and nothing elsewhere.
    #[test]
    fn a_box_stands_at_its_height_over_its_footprint() {
        let mut mesh = crate::mesh::fixtures::cuboid(4.0, 2.0, 3.0);
        for p in &mut mesh.positions {
            p.x += 0.3; // not on cell boundaries
        }
        let b = mesh.aabb();
        let env = TopEnvelope::of_mesh(&mesh, 0.5);
        for j in 0..env.height {
            for i in 0..env.width {
                let (x0, y0) = (env.origin.x + i as f64 * 0.5, env.origin.y + j as f64 * 0.5);
                // Cells meeting the box in more than an edge (an edge is covered by the neighbour).
                let touches =
                    x0 < b.max.x && x0 + 0.5 > b.min.x && y0 < b.max.y && y0 + 0.5 > b.min.y;
                let apart =
                    x0 > b.max.x || x0 + 0.5 < b.min.x || y0 > b.max.y || y0 + 0.5 < b.min.y;
                let got = env.at(i, j);
                if touches {
                    assert_eq!(got, b.max.z, "cell {i},{j}");
                } else if apart {
                    assert_eq!(got, f64::NEG_INFINITY, "cell {i},{j}");
                } else {
                    assert!(got == b.max.z || got == f64::NEG_INFINITY, "cell {i},{j}");
                }
            }
        }
    }

    /// A tilted triangle's highest point over a cell is at the cell's corner nearest its
    /// upper edge, not at the cell centre: the clipped maximum equals the plane's value there.
    #[test]
    fn a_slope_counts_its_highest_point_over_each_cell() {
        // The plane z = x over a big triangle.
        let corners = [
            Point3::new(-10.0, -10.0, -10.0),
            Point3::new(10.0, -10.0, 10.0),
            Point3::new(-10.0, 30.0, -10.0),
        ];
        let z = highest_over_square(&corners, 1.0, 1.0, 1.5, 1.5).expect("covered");
        assert!((z - 1.5).abs() < 1e-12, "{z}");
        // A square the triangle does not reach.
        assert_eq!(highest_over_square(&corners, 20.0, 20.0, 21.0, 21.0), None);
        // A square its hypotenuse cuts: the highest point is where the edge leaves the square.
        // Edge from (10,-10) to (-10,30): x = 10 - (y + 10) / 2; over y ∈ [0, 1] and x ≤ 5.5 …
        let z = highest_over_square(&corners, 4.0, 0.0, 6.0, 1.0).expect("covered");
        assert!((z - 5.0).abs() < 1e-12, "{z}");
    }
}
