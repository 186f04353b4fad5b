//! The region closed loops bound in a constrained Delaunay triangulation (spade): the faces an
//! odd number of constraint edges away from the outside, found by one flood fill.

use std::collections::VecDeque;

use spade::{ConstrainedDelaunayTriangulation, Point2, Triangulation};

/// For every face of the triangulation (outer face included, by spade's face index), whether
/// it is inside the loops. An error when the parity is inconsistent: loops that are not
/// closed or that cross each other.
pub fn faces_inside(
    cdt: &ConstrainedDelaunayTriangulation<Point2<f64>>,
) -> Result<Vec<bool>, &'static str> {
    const UNKNOWN: u8 = u8::MAX;
    let mut parity = vec![UNKNOWN; cdt.num_all_faces()];
    let mut queue = VecDeque::new();
    for f in cdt.inner_faces() {
        for e in f.adjacent_edges() {
            if e.rev().face().is_outer() {
                let p = u8::from(e.is_constraint_edge());
                let slot = &mut parity[f.fix().index()];
                if *slot == UNKNOWN {
                    *slot = p;
                    queue.push_back(f.fix());
                } else if *slot != p {
                    return Err("inconsistent region parity on the hull");
                }
            }
        }
    }
    while let Some(fh) = queue.pop_front() {
        let pf = parity[fh.index()];
        for e in cdt.face(fh).adjacent_edges() {
            if let Some(g) = e.rev().face().as_inner() {
                let p = pf ^ u8::from(e.is_constraint_edge());
                let slot = &mut parity[g.fix().index()];
                if *slot == UNKNOWN {
                    *slot = p;
                    queue.push_back(g.fix());
                } else if *slot != p {
                    return Err("loops are not closed or cross each other");
                }
            }
        }
    }
    if cdt
        .inner_faces()
        .any(|f| parity[f.fix().index()] == UNKNOWN)
    {
        return Err("a face was not reached by the flood fill");
    }
    Ok(parity.into_iter().map(|p| p == 1).collect())
}
