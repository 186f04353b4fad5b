//! Where the layers go: seed 002 §4's non-uniform layers on the envelope's boxes.
//!
//! Seed 002 slices the stock at the top faces of its boxes, so a flat of the shape is cut at
//! its own height instead of leaving the step of an even layer on it; then a layer thicker
//! than the maximum depth of cut is subdivided and one thinner than the minimum is merged with
//! the layer above ("the top face of this layer will be elevated to the height of its next top
//! layer"). Our boxes are grid cells, so nearly every cell has a height of its own; a top face
//! becomes a slicing plane when it is a flat — when cells of about one height together cover
//! at least a given area (a tool's footprint by default).

/// How deep a layer may be, and what counts as a flat.
#[derive(Clone, Debug, PartialEq)]
pub struct LayerOptions {
    /// Largest depth of cut, mm (> 0).
    pub max_depth: f64,
    /// Smallest depth of cut, mm (0 ≤ min ≤ max): thinner layers are merged upward.
    pub min_depth: f64,
    /// Cells whose tops lie within this band, mm, are one flat.
    pub flat_band: f64,
    /// Least area of a flat that gets its own slicing plane, mm².
    pub flat_area: f64,
}

/// A slicing plane and why it is there.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Layer {
    /// Height of the tool tip, mm.
    pub z: f64,
    /// Depth below the layer above (or the stock top), mm.
    pub depth: f64,
    /// At the top of a flat of the shape, or of a convex-hull box (else an even subdivision
    /// of a thick layer).
    pub at_flat: bool,
}

/// Layers from `stock_top` down to `bottom` over the cell `tops` (each cell `cell_area` mm²),
/// top first. The lowest layer is `bottom` itself.
pub fn layer_heights(
    tops: &[f64],
    cell_area: f64,
    stock_top: f64,
    bottom: f64,
    options: &LayerOptions,
) -> Vec<Layer> {
    if stock_top <= bottom {
        return Vec::new();
    }
    // Flats: cell tops binned by the band, each bin weighed by its area; the plane of a flat
    // is the highest top in its bin, so the layer clears down to just above the whole flat.
    let mut bins: std::collections::BTreeMap<i64, (f64, f64)> = std::collections::BTreeMap::new();
    for &t in tops
        .iter()
        .filter(|t| t.is_finite() && **t > bottom && **t < stock_top)
    {
        let key = (t / options.flat_band).floor() as i64;
        let entry = bins.entry(key).or_insert((0.0, f64::NEG_INFINITY));
        entry.0 += cell_area;
        entry.1 = entry.1.max(t);
    }
    let mut planes: Vec<(f64, bool)> = bins
        .values()
        .filter(|(area, _)| *area >= options.flat_area)
        .map(|&(_, top)| (top, true))
        .collect();
    planes.push((bottom, false));
    merge_and_split(planes, stock_top, options)
}

/// Seed 002's rules on slicing planes `(z, at a flat)` below `stock_top` (the lowest of them
/// the bottom, which always stays): a plane closer than the minimum depth below the one kept
/// above it is dropped (its layer joins the next one down — "elevated to the height of its
/// next top layer"), except the bottom, which then lifts nothing: the plane above it is
/// dropped instead; then a layer deeper than the maximum is split evenly. Top first.
pub fn merge_and_split(
    mut planes: Vec<(f64, bool)>,
    stock_top: f64,
    options: &LayerOptions,
) -> Vec<Layer> {
    planes.retain(|(z, _)| *z < stock_top);
    planes.sort_by(|a, b| b.0.total_cmp(&a.0));
    planes.dedup_by(|a, b| a.0 == b.0);
    if planes.is_empty() {
        return Vec::new();
    }

    let mut merged: Vec<(f64, bool)> = Vec::new();
    let mut above = stock_top;
    let last = planes.len() - 1;
    for (k, &(z, flat)) in planes.iter().enumerate() {
        if k == last {
            while let Some(&(previous, _)) = merged.last() {
                if previous - z < options.min_depth {
                    merged.pop();
                } else {
                    break;
                }
            }
            merged.push((z, flat));
        } else if above - z >= options.min_depth {
            merged.push((z, flat));
            above = z;
        }
    }

    // Subdivide: a layer deeper than the maximum is split evenly.
    let mut layers = Vec::new();
    let mut above = stock_top;
    for (z, flat) in merged {
        let depth = above - z;
        let parts = (depth / options.max_depth - 1e-9).ceil().max(1.0) as usize;
        for p in 1..=parts {
            let zp = if p == parts {
                z
            } else {
                above - depth * p as f64 / parts as f64
            };
            layers.push(Layer {
                z: zp,
                depth: depth / parts as f64,
                at_flat: flat && p == parts,
            });
        }
        above = z;
    }
    layers
}

#[cfg(test)]
mod tests {
    use super::*;

    fn options() -> LayerOptions {
        LayerOptions {
            max_depth: 2.0,
            min_depth: 0.5,
            flat_band: 0.05,
            flat_area: 4.0,
        }
    }

    #[test]
    fn without_flats_layers_are_even_and_no_deeper_than_the_maximum() {
        let layers = layer_heights(&[], 1.0, 10.0, 0.0, &options());
        assert_eq!(layers.len(), 5);
        for (k, l) in layers.iter().enumerate() {
            assert!((l.z - (8.0 - 2.0 * k as f64)).abs() < 1e-12);
            assert!((l.depth - 2.0).abs() < 1e-12);
        }
        assert_eq!(layers.last().map(|l| l.z), Some(0.0));
    }

    /// A flat at 6.3 gets a plane at its height: the layers above and below it are split
    /// evenly within the maximum depth.
    #[test]
    fn a_flat_is_cut_at_its_own_height() {
        let tops = vec![6.3; 10];
        let layers = layer_heights(&tops, 1.0, 10.0, 0.0, &options());
        let zs: Vec<f64> = layers.iter().map(|l| l.z).collect();
        assert!(zs.contains(&6.3), "{zs:?}");
        assert!(layers.iter().all(|l| l.depth <= 2.0 + 1e-12));
        let flat = layers.iter().find(|l| l.z == 6.3).expect("flat layer");
        assert!(flat.at_flat);
        // A flat too small is not a plane.
        let layers = layer_heights(&tops[..3], 1.0, 10.0, 0.0, &options());
        assert!(layers.iter().all(|l| l.z != 6.3));
    }

    /// Flats closer than the minimum depth to the plane above are merged into the next layer.
    #[test]
    fn thin_layers_are_merged_upward() {
        let mut tops = vec![9.8; 10]; // 0.2 below the stock top
        tops.extend(vec![5.0; 10]);
        tops.extend(vec![4.8; 10]); // 0.2 below the flat at 5
        let layers = layer_heights(&tops, 1.0, 10.0, 0.0, &options());
        let zs: Vec<f64> = layers.iter().map(|l| l.z).collect();
        assert!(!zs.contains(&9.8), "{zs:?}");
        assert!(zs.contains(&5.0) && !zs.contains(&4.8), "{zs:?}");
        let mut above = 10.0;
        for l in &layers {
            assert!(
                above - l.z >= 0.5 - 1e-12 && above - l.z <= 2.0 + 1e-12,
                "{zs:?}"
            );
            above = l.z;
        }
    }
}
