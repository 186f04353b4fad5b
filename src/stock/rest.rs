//! Rest material: how much stock a program left over the part's surface.
//!
//! From the centre of each triangle of the part, outwards along its normal, the stock is
//! walked in quarter-spacing steps while it is material ([`Stock::is_material`]) and not the
//! part's (a dexel model of the part at the same spacing: at a concave corner the normal of one
//! face runs into the part under the next, which is not rest); the rest there is the last
//! distance still in material. The walk starts half a spacing out, where a surface cut exactly
//! to size has no material left in the model (the model knows a surface to within its spacing
//! across the lines), so the figures are good to about a spacing.
//! Summaries are weighted by the triangles' areas, so a finely meshed corner does not count
//! more than a broad face.

use rayon::prelude::*;

use super::Stock;
use crate::mesh::Mesh;

/// Material left over the part's surface, mm (area-weighted over the part's triangles).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Rest {
    pub max_mm: f64,
    pub mean_mm: f64,
    pub p99_mm: f64,
    /// Share of the part's surface with more than half a spacing of material on it.
    pub covered_fraction: f64,
}

/// The rest of `stock` over each triangle of `part` (walked up to `reach` mm, stopping where
/// `part_model`, the part as dexels, is material), in triangle order.
pub fn rest_per_triangle(stock: &Stock, part: &Mesh, part_model: &Stock, reach: f64) -> Vec<f64> {
    let spacing = stock.spacing();
    let (start, step) = (0.5 * spacing, 0.25 * spacing);
    (0..part.triangles.len())
        .into_par_iter()
        .map(|t| {
            let [a, b, c] = part.corners(t);
            let normal = (b - a).cross(&(c - a));
            let Some(n) = normal.try_normalize(1e-300) else {
                return 0.0;
            };
            let centre = a + ((b - a) + (c - a)) / 3.0;
            let mut rest = 0.0;
            let mut d = start;
            while d <= reach
                && stock.is_material(&(centre + d * n))
                && !part_model.is_material(&(centre + d * n))
            {
                rest = d;
                d += step;
            }
            rest
        })
        .collect()
}

/// Summarises [`rest_per_triangle`].
pub fn rest_over(stock: &Stock, part: &Mesh, part_model: &Stock, reach: f64) -> Rest {
    let rest = rest_per_triangle(stock, part, part_model, reach);
    let mut weighted: Vec<(f64, f64)> = rest
        .iter()
        .enumerate()
        .map(|(t, r)| {
            let [a, b, c] = part.corners(t);
            (*r, 0.5 * (b - a).cross(&(c - a)).norm())
        })
        .collect();
    let area: f64 = weighted.iter().map(|w| w.1).sum();
    if area.is_nan() || area <= 0.0 {
        return Rest::default();
    }
    weighted.sort_by(|x, y| x.0.total_cmp(&y.0));
    let mut below = 0.0;
    let mut p99 = 0.0;
    for (r, a) in &weighted {
        below += a;
        p99 = *r;
        if below >= 0.99 * area {
            break;
        }
    }
    Rest {
        max_mm: weighted.last().map_or(0.0, |w| w.0),
        mean_mm: weighted.iter().map(|(r, a)| r * a).sum::<f64>() / area,
        p99_mm: p99,
        covered_fraction: weighted
            .iter()
            .filter(|(r, _)| *r > 0.0)
            .map(|w| w.1)
            .sum::<f64>()
            / area,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::{Aabb, Point3};
    use crate::mesh::fixtures::cuboid;
    use crate::stock::DEFAULT_MAX_DEXELS;

    /// A 10 mm cube part in a block 1 mm larger on top and 0.4 mm larger on the sides: the
    /// top carries 1 mm, the sides 0.4, the bottom none, each within a spacing. The same cube
    /// as its own stock carries none: the walks into the part at its edges do not count.
    #[test]
    fn rest_over_a_cube_in_a_larger_block_is_the_margins() {
        let part = cuboid(10.0, 10.0, 10.0);
        let b = part.aabb();
        let blank = Aabb::from_points(&[
            Point3::new(b.min.x - 0.4, b.min.y - 0.4, b.min.z),
            Point3::new(b.max.x + 0.4, b.max.y + 0.4, b.max.z + 1.0),
        ]);
        let spacing = 0.05;
        let stock = Stock::block(&blank, spacing, DEFAULT_MAX_DEXELS).unwrap();
        let model = Stock::from_mesh(&part, spacing, DEFAULT_MAX_DEXELS).unwrap();
        let per = rest_per_triangle(&stock, &part, &model, 5.0);
        for (t, r) in per.iter().enumerate() {
            let n = part.face_normal(t);
            let expected = if n.z > 0.9 {
                1.0
            } else if n.z < -0.9 {
                0.0
            } else {
                0.4
            };
            assert!(
                (r - expected).abs() <= 0.5 * spacing + 1e-9,
                "{t}: {r} vs {expected}"
            );
        }
        let rest = rest_over(&stock, &part, &model, 5.0);
        assert!((rest.max_mm - 1.0).abs() <= spacing + 1e-9);
        // Area shares: top 1/6, sides 4/6, bottom 1/6 bare.
        assert!((rest.covered_fraction - 5.0 / 6.0).abs() < 1e-9);
        let mean = (1.0 + 4.0 * 0.4) / 6.0;
        assert!(
            (rest.mean_mm - mean).abs() < 0.5 * spacing,
            "{}",
            rest.mean_mm
        );
    }
}
