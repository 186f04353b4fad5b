//! Triangulating a region bounded by vertex loops with a constrained Delaunay triangulation.

use spade::handles::FixedVertexHandle;
use spade::{ConstrainedDelaunayTriangulation, Point2, Triangulation};

use super::SampleError;
use super::builder::MeshBuilder;
use crate::mesh::region::faces_inside;

/// Triangulates, in the (x, y) projection, the region bounded by `loops` (an outer boundary and
/// any number of holes, in any orientation; they must be simple and must not cross), using the
/// mesh vertices `steiner` as interior points. Returns triangles of mesh indices,
/// counter-clockwise seen from +Z; positions (including z) are the mesh's own.
///
/// No vertex is added: every loop edge is a triangle edge (the loops are seams shared with
/// neighbouring faces), and every Steiner vertex is used. Either failing returns
/// [`SampleError::Triangulation`] naming `surface`. The region is the set of faces an odd
/// number of constraint edges away from the outside.
pub(super) fn triangulate_region(
    b: &MeshBuilder,
    loops: &[&[u32]],
    steiner: &[u32],
    surface: &'static str,
) -> Result<Vec<[u32; 3]>, SampleError> {
    let fail = |reason: String| SampleError::Triangulation { surface, reason };
    let mut cdt = ConstrainedDelaunayTriangulation::<Point2<f64>>::new();
    // Mesh index of each spade vertex (spade numbers vertices in insertion order).
    let mut ids: Vec<u32> = Vec::new();
    let mut insert = |cdt: &mut ConstrainedDelaunayTriangulation<Point2<f64>>,
                      id: u32|
     -> Result<FixedVertexHandle, SampleError> {
        let p = b.position(id);
        let h = cdt
            .insert(Point2::new(p.x, p.y))
            .map_err(|e| fail(format!("inserting vertex {id}: {e:?}")))?;
        if h.index() != ids.len() {
            return Err(fail(format!(
                "vertex {id} duplicates another vertex in (x, y)"
            )));
        }
        ids.push(id);
        Ok(h)
    };
    let mut loop_handles = Vec::with_capacity(loops.len());
    for lp in loops {
        let hs = lp
            .iter()
            .map(|&id| insert(&mut cdt, id))
            .collect::<Result<Vec<_>, _>>()?;
        loop_handles.push(hs);
    }
    for &id in steiner {
        insert(&mut cdt, id)?;
    }
    for hs in &loop_handles {
        for (i, &from) in hs.iter().enumerate() {
            let to = hs[(i + 1) % hs.len()];
            let added = cdt.try_add_constraint(from, to);
            if added.len() != 1 || !cdt.exists_constraint(from, to) {
                return Err(fail(format!(
                    "loop edge {}–{} is crossed or touched by other geometry",
                    ids[from.index()],
                    ids[to.index()]
                )));
            }
        }
    }

    let inside = faces_inside(&cdt).map_err(|reason| fail(reason.into()))?;

    let mut used = vec![false; ids.len()];
    let mut tris = Vec::new();
    for f in cdt.inner_faces() {
        if inside[f.fix().index()] {
            let [a, c, d] = f.vertices().map(|v| v.fix().index());
            used[a] = true;
            used[c] = true;
            used[d] = true;
            tris.push([ids[a], ids[c], ids[d]]);
        }
    }
    if let Some(i) = used.iter().position(|u| !u) {
        return Err(fail(format!("vertex {} lies outside the region", ids[i])));
    }
    Ok(tris)
}

#[cfg(test)]
mod tests {
    use nalgebra::Point3;

    use super::*;

    /// A square with a square hole: 8 loop vertices + 0 Steiner points → 8 triangles with
    /// total area 16 − 4.
    #[test]
    fn square_with_hole() {
        let mut b = MeshBuilder::default();
        let sq = |s: f64| [[-s, -s], [s, -s], [s, s], [-s, s]].map(|[x, y]| Point3::new(x, y, 0.0));
        let outer = b.vertex_loop(sq(2.0)).unwrap();
        let hole = b.vertex_loop(sq(1.0).into_iter().rev()).unwrap();
        let tris = triangulate_region(&b, &[&outer, &hole], &[], "test").unwrap();
        assert_eq!(tris.len(), 8);
        let area: f64 = tris
            .iter()
            .map(|t| {
                let [p, q, r] = t.map(|i| b.position(i));
                (q - p).cross(&(r - p)).z / 2.0
            })
            .sum();
        assert!((area - 12.0).abs() < 1e-12, "{area}");
    }

    /// A Steiner point inside the hole is reported, not silently dropped.
    #[test]
    fn steiner_in_hole_is_an_error() {
        let mut b = MeshBuilder::default();
        let sq = |s: f64| [[-s, -s], [s, -s], [s, s], [-s, s]].map(|[x, y]| Point3::new(x, y, 0.0));
        let outer = b.vertex_loop(sq(2.0)).unwrap();
        let hole = b.vertex_loop(sq(1.0)).unwrap();
        let s = b.vertex(Point3::new(0.1, 0.2, 0.0)).unwrap();
        assert!(triangulate_region(&b, &[&outer, &hole], &[s], "test").is_err());
    }
}
