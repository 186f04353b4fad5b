//! Where a layer still holds material after earlier tools: the in-process stock (tri-dexel)
//! read as a planar region per layer, for rest roughing with a smaller tool.
//!
//! A cell of the stock's vertical lattice (one per vertical dexel, of the stock's spacing) is
//! material when any of the three grids shows material in the layer's slab there: its own
//! vertical dexel, or a stretch of a horizontal dexel at a height inside the slab crossing it.
//! The horizontal dexels see walls thinner than the spacing that fall between vertical lines.
//! The region is grown by one cell, so material between lines is inside it. Cells under the
//! shape's envelope (where no vertical tool may go at this layer) are left out: their material
//! is the shape's own or out of reach.

use super::envelope::TopEnvelope;
use super::region::trace_cells;
use crate::contour::geometry::{Point2, Shape};
use crate::stock::Stock;

/// The cells of the stock's vertical lattice holding more than `min_thickness` mm of material
/// between `z_low` and `z_high` and outside the shape's envelope above `z_low`, grown by one
/// cell, as a shape; `None` when there is none.
pub fn material_in_slab(
    stock: &Stock,
    envelope: &TopEnvelope,
    z_low: f64,
    z_high: f64,
    min_thickness: f64,
) -> Option<Shape> {
    material_cells(stock, envelope, z_low, z_high, min_thickness, true, None)
}

/// [`material_in_slab`] inside the convex counter-clockwise polygon `zone` only (cells whose
/// centre lies in it), and without the cells within `skin` mm of the envelope above `z_low`:
/// an indexed setup clears the rest it was proposed for, not the skin every surface keeps.
pub fn material_in_slab_within(
    stock: &Stock,
    envelope: &TopEnvelope,
    z_low: f64,
    z_high: f64,
    min_thickness: f64,
    zone: Option<(&[Point2], f64)>,
) -> Option<Shape> {
    material_cells(stock, envelope, z_low, z_high, min_thickness, true, zone)
}

/// Whether a cell of `envelope` taller than `z` lies within `distance` of `c` (its centre, on
/// the envelope's lattice about `c`).
fn near_envelope(envelope: &TopEnvelope, c: Point2, distance: f64, z: f64) -> bool {
    let k = (distance / envelope.cell).ceil() as i64;
    (-k..=k).any(|a| {
        (-k..=k).any(|b| {
            let d = crate::geom::Vector2::new(a as f64, b as f64) * envelope.cell;
            d.norm() <= distance && envelope.top_at(c + d) > z
        })
    })
}

/// Whether `p` lies in the convex counter-clockwise polygon `hull` (on its boundary counts).
pub fn in_convex(hull: &[Point2], p: Point2) -> bool {
    hull.len() >= 3
        && (0..hull.len()).all(|k| {
            let (a, b) = (hull[k], hull[(k + 1) % hull.len()]);
            (b - a).perp(&(p - a)) >= 0.0
        })
}

/// [`material_in_slab`] without the growth: the cells whose own vertical dexel, or a
/// horizontal dexel crossing them, shows material. What stands between lines is missed by
/// less than a cell; a tool kept off this region by a margin of a cell or more keeps off it.
pub fn material_on_lines(
    stock: &Stock,
    envelope: &TopEnvelope,
    z_low: f64,
    z_high: f64,
) -> Option<Shape> {
    material_cells(stock, envelope, z_low, z_high, 0.0, false, None)
}

fn material_cells(
    stock: &Stock,
    envelope: &TopEnvelope,
    z_low: f64,
    z_high: f64,
    min_thickness: f64,
    grow: bool,
    zone: Option<(&[Point2], f64)>,
) -> Option<Shape> {
    let vertical = stock.grid(2);
    let [w, h] = vertical.counts();
    let s = stock.spacing();
    let corner = vertical.line_point(0, 0);
    // Cell (i, j) is centred on vertical line (i, j).
    let origin = Point2::new(corner.x - 0.5 * s, corner.y - 0.5 * s);
    let mut material = vec![false; w * h];
    for j in 0..h {
        for i in 0..w {
            let inside: f64 = vertical
                .spans(i, j)
                .iter()
                .map(|span| (span.end.min(z_high) - span.start.max(z_low)).max(0.0))
                .sum();
            material[i + j * w] = inside > min_thickness;
        }
    }
    // Horizontal dexels at heights inside the slab mark the cells their material crosses.
    let mut mark = |x0: f64, x1: f64, y0: f64, y1: f64| {
        let column = |x: f64| ((x - origin.x) / s).floor().clamp(0.0, (w - 1) as f64) as usize;
        let row = |y: f64| ((y - origin.y) / s).floor().clamp(0.0, (h - 1) as f64) as usize;
        for j in row(y0)..=row(y1) {
            for i in column(x0)..=column(x1) {
                material[i + j * w] = true;
            }
        }
    };
    for axis in [0usize, 1] {
        let grid = stock.grid(axis);
        let [n0, n1] = grid.counts();
        for b in 0..n1 {
            for a in 0..n0 {
                let p = grid.line_point(a, b);
                if p.z <= z_low || p.z > z_high {
                    continue;
                }
                for span in grid.spans(a, b) {
                    if span.length() <= min_thickness {
                        continue;
                    }
                    if axis == 0 {
                        mark(span.start, span.end, p.y, p.y);
                    } else {
                        mark(p.x, p.x, span.start, span.end);
                    }
                }
            }
        }
    }
    // Out of reach under the envelope: the cell's centre is over a box taller than z_low.
    for j in 0..h {
        for i in 0..w {
            let c = Point2::new(
                origin.x + (i as f64 + 0.5) * s,
                origin.y + (j as f64 + 0.5) * s,
            );
            if envelope.top_at(c) > z_low {
                material[i + j * w] = false;
            } else if let Some((hull, skin)) = zone
                && material[i + j * w]
                && (!in_convex(hull, c) || near_envelope(envelope, c, skin, z_low))
            {
                material[i + j * w] = false;
            }
        }
    }
    if !grow {
        return trace_cells(material, w, h, origin, s);
    }
    let mut grown = material.clone();
    for j in 0..h {
        for i in 0..w {
            if material[i + j * w] {
                for (di, dj) in [
                    (-1i64, 0i64),
                    (1, 0),
                    (0, -1),
                    (0, 1),
                    (-1, -1),
                    (1, 1),
                    (-1, 1),
                    (1, -1),
                ] {
                    let (a, b) = (i as i64 + di, j as i64 + dj);
                    if a >= 0 && b >= 0 && (a as usize) < w && (b as usize) < h {
                        grown[a as usize + b as usize * w] = true;
                    }
                }
            }
        }
    }
    trace_cells(grown, w, h, origin, s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::{Aabb, Point3};
    use crate::mesh::fixtures::cuboid;

    fn area(shape: &Shape) -> f64 {
        shape.contours.iter().map(|c| c.signed_area()).sum()
    }

    /// A 10 mm cube of stock: its slabs hold material over its footprint (the lattice ends at
    /// the stock's box, so there is no cell to grow into), none above it; what stands under a
    /// taller shape is left out.
    #[test]
    fn the_material_of_a_slab_is_the_stocks_footprint_where_a_tool_may_go() {
        let bounds =
            Aabb::from_points(&[Point3::new(0.0, 0.0, 0.0), Point3::new(10.0, 10.0, 10.0)]);
        let stock = Stock::block(&bounds, 0.5, 1 << 20).expect("stock");
        let nothing = TopEnvelope::of_mesh(&cuboid(1.0, 1.0, 1.0), 0.5);
        let region = material_in_slab(&stock, &nothing, 5.0, 10.0, 0.05).expect("material");
        assert!((area(&region) - 100.0).abs() < 1e-9, "{}", area(&region));
        assert!(material_in_slab(&stock, &nothing, 12.0, 15.0, 0.05).is_none());
        // A wall over the left half, 20 mm tall: its side of the stock is out of reach.
        let wall = TopEnvelope::of_mesh(&cuboid(5.0, 10.0, 20.0), 0.5);
        let region = material_in_slab(&stock, &wall, 5.0, 10.0, 0.05).expect("material");
        // The cells from x = 5.5 stand clear of the wall's envelope (whose cells reach 5.5, the
        // wall's face lying on a cell edge), grown back by one cell to x = 5: 5 × 10.
        let a = area(&region);
        assert!((a - 50.0).abs() < 1e-9, "{a}");
    }
}
