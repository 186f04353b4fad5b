//! A closed mesh onto a dexel grid: every triangle is rasterised onto the lines it covers
//! (seen along the grid's axis), each crossing records where and which way the surface faces,
//! and along each line the winding number says where the solid is.
//!
//! A line through an edge shared by two triangles must cross the surface once, not twice or
//! never. The edge test is computed with the edge's end points in one canonical order, so the
//! two triangles see exactly opposite values, and a point exactly on an edge belongs to the
//! triangle for which the edge runs "down" (or "right" when level) — the top-left rule of
//! rasterisers, which gives every point of a planar partition to exactly one triangle.

use super::DexelGrid;
use super::spans::{Span, Spans};
use crate::mesh::Mesh;
use rayon::prelude::*;

/// Twice the signed area of (a, b, p), with the edge's ends in canonical order so that the
/// reversed edge gives exactly the negated value.
fn edge_function(a: [f64; 2], b: [f64; 2], p: [f64; 2]) -> f64 {
    let swap = (b[0], b[1]) < (a[0], a[1]);
    let (s, e) = if swap { (b, a) } else { (a, b) };
    let v = (e[0] - s[0]) * (p[1] - s[1]) - (e[1] - s[1]) * (p[0] - s[0]);
    if swap { -v } else { v }
}

/// Whether a point exactly on edge a→b of a counter-clockwise triangle belongs to it.
fn owns_edge(a: [f64; 2], b: [f64; 2]) -> bool {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    dy < 0.0 || (dy == 0.0 && dx > 0.0)
}

/// Fills `grid`'s lines with the solid bounded by `mesh`.
pub(super) fn fill_grid(grid: &mut DexelGrid, mesh: &Mesh) {
    let (axis, [u, v]) = (grid.axis, grid.across);
    let mut crossings: Vec<Vec<(f64, i32)>> = vec![Vec::new(); grid.lines.len()];
    for t in &mesh.triangles {
        let p = t.map(|i| mesh.positions[i as usize]);
        let mut q = p.map(|x| [x[u], x[v]]);
        let mut depth = p.map(|x| x[axis]);
        let area = edge_function(q[0], q[1], q[2]);
        if area == 0.0 || !area.is_finite() {
            continue; // seen edge-on: no line crosses its interior
        }
        // Facing: +1 where the surface's outward normal has a positive `axis` component
        // (the line leaves the solid there), −1 where it enters.
        let facing = if area > 0.0 { 1 } else { -1 };
        if area < 0.0 {
            q.swap(1, 2);
            depth.swap(1, 2);
        }
        let (lo_u, hi_u) = (
            q.iter().map(|x| x[0]).fold(f64::INFINITY, f64::min),
            q.iter().map(|x| x[0]).fold(f64::NEG_INFINITY, f64::max),
        );
        let (lo_v, hi_v) = (
            q.iter().map(|x| x[1]).fold(f64::INFINITY, f64::min),
            q.iter().map(|x| x[1]).fold(f64::NEG_INFINITY, f64::max),
        );
        let area = area.abs();
        for j in grid.index_range(1, lo_v, hi_v) {
            for i in grid.index_range(0, lo_u, hi_u) {
                let point = grid.line_point(i, j);
                let c = [point[u], point[v]];
                let w = [
                    edge_function(q[1], q[2], c),
                    edge_function(q[2], q[0], c),
                    edge_function(q[0], q[1], c),
                ];
                let edges = [(q[1], q[2]), (q[2], q[0]), (q[0], q[1])];
                let inside = w
                    .iter()
                    .zip(edges)
                    .all(|(&e, (a, b))| e > 0.0 || (e == 0.0 && owns_edge(a, b)));
                if inside {
                    let t = (w[0] * depth[0] + w[1] * depth[1] + w[2] * depth[2]) / area;
                    crossings[i + grid.counts[0] * j].push((t, facing));
                }
            }
        }
    }
    grid.lines = crossings
        .into_par_iter()
        .map(|mut hits| {
            hits.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            let mut spans = Spans::new();
            let mut winding = 0i32;
            let mut start = 0.0;
            for (t, facing) in hits {
                let before = winding;
                winding -= facing;
                if before <= 0 && winding > 0 {
                    start = t;
                } else if before > 0 && winding <= 0 && t > start {
                    spans.push(Span { start, end: t });
                }
            }
            spans
        })
        .collect();
}
