//! The regions of one roughing layer as planar shapes for the contour engine: what the tool
//! must stay away from (the envelope's boxes taller than the layer, traced as exact
//! rectilinear outlines), and the blank's section, the material the layer clears.

use std::collections::BTreeMap;

use super::envelope::TopEnvelope;
use crate::contour::geometry::{Contour, Point2, Shape, Vertex};

/// The union of the envelope's cells standing higher than `z` (by more than `slack`) as a
/// shape: counter-clockwise outer boundaries, clockwise holes, on cell edges. Two cells that
/// meet only at a corner are joined by filling a neighbour (the region only grows, and the
/// outline never touches itself). `None` when no cell stands that high.
pub fn cells_above(envelope: &TopEnvelope, z: f64, slack: f64) -> Option<Shape> {
    let filled: Vec<bool> = envelope.top.iter().map(|&t| t > z + slack).collect();
    trace_cells(
        filled,
        envelope.width,
        envelope.height,
        envelope.origin,
        envelope.cell,
    )
}

/// The union of the `filled` cells of a `w` × `h` grid (cell (0, 0)'s lower-left corner at
/// `origin`, sides `cell`) as a shape, corner contacts joined as in [`cells_above`]; `None`
/// when no cell is filled.
pub fn trace_cells(
    mut filled: Vec<bool>,
    w: usize,
    h: usize,
    origin: Point2,
    cell: f64,
) -> Option<Shape> {
    if !filled.iter().any(|&f| f) {
        return None;
    }
    fill_saddles(&mut filled, w, h);
    Some(trace(&filled, w, h, origin, cell))
}

/// Fills one empty cell of every diagonal pair (two filled cells meeting only at a corner)
/// until there is none, so that each grid vertex has at most one outgoing boundary edge.
fn fill_saddles(filled: &mut [bool], w: usize, h: usize) {
    let at = |f: &[bool], i: usize, j: usize| f[i + j * w];
    loop {
        let mut changed = false;
        for j in 1..h {
            for i in 1..w {
                let (a, b) = (at(filled, i - 1, j - 1), at(filled, i, j - 1));
                let (c, d) = (at(filled, i - 1, j), at(filled, i, j));
                if a && d && !b && !c {
                    filled[i + (j - 1) * w] = true;
                    changed = true;
                } else if b && c && !a && !d {
                    filled[i - 1 + (j - 1) * w] = true;
                    changed = true;
                }
            }
        }
        if !changed {
            return;
        }
    }
}

/// The boundary of the filled cells, each edge directed with its filled cell on the left,
/// chained into loops from the lowest-index start (deterministic) and with the vertices inside
/// straight runs dropped.
fn trace(filled: &[bool], w: usize, h: usize, origin: Point2, cell: f64) -> Shape {
    let is = |i: isize, j: isize| {
        i >= 0
            && j >= 0
            && (i as usize) < w
            && (j as usize) < h
            && filled[i as usize + j as usize * w]
    };
    // Grid vertex (i, j) → the vertex its one outgoing edge reaches.
    let mut next: BTreeMap<(isize, isize), (isize, isize)> = BTreeMap::new();
    for j in 0..h as isize {
        for i in 0..w as isize {
            if !is(i, j) {
                continue;
            }
            if !is(i, j - 1) {
                next.insert((i, j), (i + 1, j));
            }
            if !is(i + 1, j) {
                next.insert((i + 1, j), (i + 1, j + 1));
            }
            if !is(i, j + 1) {
                next.insert((i + 1, j + 1), (i, j + 1));
            }
            if !is(i - 1, j) {
                next.insert((i, j + 1), (i, j));
            }
        }
    }
    let mut contours = Vec::new();
    while let Some((&start, _)) = next.iter().next() {
        let mut corners: Vec<(isize, isize)> = Vec::new();
        let mut at = start;
        while let Some(to) = next.remove(&at) {
            corners.push(at);
            at = to;
        }
        // Keep only the corners where the direction turns.
        let n = corners.len();
        let kept: Vec<(isize, isize)> = (0..n)
            .filter(|&k| {
                let (p, c, q) = (corners[(k + n - 1) % n], corners[k], corners[(k + 1) % n]);
                (c.0 - p.0, c.1 - p.1) != (q.0 - c.0, q.1 - c.1)
            })
            .map(|k| corners[k])
            .collect();
        contours.push(Contour {
            vertices: kept
                .into_iter()
                .map(|(i, j)| Vertex::line(origin.x + i as f64 * cell, origin.y + j as f64 * cell))
                .collect(),
        });
    }
    Shape { contours }
}

/// A circle as a contour: two half arcs, counter-clockwise.
pub fn circle(center: Point2, radius: f64) -> Contour {
    Contour {
        vertices: vec![
            Vertex {
                point: Point2::new(center.x + radius, center.y),
                bulge: 1.0,
            },
            Vertex {
                point: Point2::new(center.x - radius, center.y),
                bulge: 1.0,
            },
        ],
    }
}

/// An axis-aligned rectangle as a contour, counter-clockwise.
pub fn rectangle(min: Point2, max: Point2) -> Contour {
    Contour {
        vertices: vec![
            Vertex::line(min.x, min.y),
            Vertex::line(max.x, min.y),
            Vertex::line(max.x, max.y),
            Vertex::line(min.x, max.y),
        ],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn envelope(rows: &[&str]) -> TopEnvelope {
        // Rows from the top of the picture down; '#' is a cell at height 1.
        let height = rows.len();
        let width = rows[0].len();
        let mut top = vec![f64::NEG_INFINITY; width * height];
        for (r, row) in rows.iter().enumerate() {
            for (i, ch) in row.chars().enumerate() {
                if ch == '#' {
                    top[i + (height - 1 - r) * width] = 1.0;
                }
            }
        }
        TopEnvelope {
            origin: Point2::new(0.0, 0.0),
            cell: 1.0,
            width,
            height,
            top,
        }
    }

    fn area(shape: &Shape) -> f64 {
        shape.contours.iter().map(|c| c.signed_area()).sum()
    }

    #[test]
    fn a_ring_is_one_outer_boundary_and_one_hole() {
        let env = envelope(&[".....", ".###.", ".#.#.", ".###.", "....."]);
        let shape = cells_above(&env, 0.5, 0.0).expect("cells");
        assert_eq!(shape.contours.len(), 2);
        let mut areas: Vec<f64> = shape.contours.iter().map(|c| c.signed_area()).collect();
        areas.sort_by(f64::total_cmp);
        assert_eq!(areas, vec![-1.0, 9.0]);
        assert_eq!(area(&shape), 8.0);
        assert!(shape.contours.iter().all(|c| c.vertices.len() == 4));
    }

    #[test]
    fn cells_meeting_at_a_corner_are_joined_and_lower_cells_ignored() {
        let env = envelope(&["....", ".#..", "..#.", "...."]);
        let shape = cells_above(&env, 0.5, 0.0).expect("cells");
        assert_eq!(shape.contours.len(), 1);
        assert_eq!(area(&shape), 3.0, "one cell filled to join the diagonal");
        assert!(
            cells_above(&env, 1.0, 0.0).is_none(),
            "nothing stands above 1"
        );
    }

    #[test]
    fn shapes_on_the_grid_boundary_close() {
        let env = envelope(&["##", "##"]);
        let shape = cells_above(&env, 0.0, 0.0).expect("cells");
        assert_eq!(shape.contours.len(), 1);
        assert_eq!(area(&shape), 4.0);
    }

    #[test]
    fn circle_and_rectangle_enclose_their_areas() {
        let c = circle(Point2::new(1.0, 2.0), 3.0);
        assert!((c.signed_area() - std::f64::consts::PI * 9.0).abs() < 1e-9);
        let r = rectangle(Point2::new(0.0, 0.0), Point2::new(2.0, 3.0));
        assert_eq!(r.signed_area(), 6.0);
    }
}
