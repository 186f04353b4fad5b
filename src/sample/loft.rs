//! Lofting: joining two vertex loops with a band of triangles.

use super::builder::MeshBuilder;

/// Joins loop `lower` to loop `upper` (same length, vertex `i` of one facing vertex `i` of the
/// other) with a closed band of quads, each split along its shorter diagonal.
///
/// Orientation: the quad (a_i, a_{i+1}, b_{i+1}, b_i) with a = `lower`, b = `upper` is emitted
/// counter-clockwise in that order, so its normal is (a_{i+1} − a_i) × (b_i − a_i). For loops
/// that run counter-clockwise seen from +Z with `upper` above `lower`, the band faces away from
/// the loop's inside; pass the loops reversed for the opposite.
pub(super) fn loft(b: &mut MeshBuilder, lower: &[u32], upper: &[u32]) {
    debug_assert_eq!(lower.len(), upper.len());
    let n = lower.len().min(upper.len());
    let mut tris = Vec::with_capacity(2 * n);
    for i in 0..n {
        let j = (i + 1) % n;
        let (a0, a1, b0, b1) = (lower[i], lower[j], upper[i], upper[j]);
        let d_a0b1 = (b.position(b1) - b.position(a0)).norm_squared();
        let d_a1b0 = (b.position(b0) - b.position(a1)).norm_squared();
        if d_a0b1 <= d_a1b0 {
            tris.push([a0, a1, b1]);
            tris.push([a0, b1, b0]);
        } else {
            tris.push([a0, a1, b0]);
            tris.push([a1, b1, b0]);
        }
    }
    b.triangles(tris);
}
