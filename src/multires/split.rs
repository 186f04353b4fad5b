//! The 1-to-4 split: the connectivity of level j+1 as a pure function of level j, and the
//! sharp-feature bookkeeping (creases, vertex classes) that goes with it.
//!
//! Topology only: nothing in this file reads a position.
//!
//! ```text
//!            c                 numbering (docs/multires-conventions.md):
//!           / \                  t = [a, b, c] -> 4t+0 [a, ab, ca]
//!         ca---bc                                 4t+1 [ab, b, bc]
//!         / \ / \                                 4t+2 [ca, bc, c]
//!        a---ab--b                                4t+3 [ab, bc, ca]
//! ```
//! Even vertices keep their index; the odd vertex of coarse edge k (edges sorted `[min, max]`)
//! is `coarse_vertices + k`.

/// "No half-edge" marker in [`EdgeTable::halfedges`].
pub(crate) const NO_HALFEDGE: u32 = u32::MAX;

/// The connectivity produced by one 1-to-4 split.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Split {
    /// Vertices of the coarse level.
    pub coarse_vertices: usize,
    /// Coarse edges [min, max], sorted; edge k's odd vertex is coarse_vertices + k.
    pub edges: Vec<[u32; 2]>,
    /// Fine triangles (4 per coarse triangle, in the order above).
    pub triangles: Vec<[u32; 3]>,
}

impl Split {
    /// Number of vertices of the fine level: `coarse_vertices + edges.len()`.
    pub fn fine_vertices(&self) -> usize {
        self.coarse_vertices + self.edges.len()
    }

    /// Index of the odd vertex on coarse edge `k` (no range check).
    pub fn odd_vertex(&self, k: usize) -> u32 {
        (self.coarse_vertices + k) as u32
    }

    /// Index of coarse edge `[min(a, b), max(a, b)]` in [`Split::edges`], if it is an edge.
    pub fn edge_index(&self, a: u32, b: u32) -> Option<usize> {
        self.edges.binary_search(&[a.min(b), a.max(b)]).ok()
    }

    /// The fine level's creases: coarse crease `{a, b}` with odd vertex `m` becomes `{a, m}`
    /// and `{b, m}` (`m` is above both). Listed creases that are not edges are dropped.
    pub fn fine_creases(&self, coarse: &Creases) -> Creases {
        let mut edges = Vec::with_capacity(2 * coarse.edges.len());
        for &[a, b] in &coarse.edges {
            if let Some(k) = self.edge_index(a, b) {
                let m = self.odd_vertex(k);
                edges.push([a.min(b), m]);
                edges.push([a.max(b), m]);
            }
        }
        edges.sort_unstable();
        edges.dedup();
        Creases { edges }
    }
}

/// The 1-to-4 split of `coarse_triangles` (a level with `coarse_vertices` vertices).
///
/// Preconditions (checked by [`crate::multires::loop_subdivide`], not here): every index is
/// `< coarse_vertices`, no triangle repeats a vertex, and `coarse_vertices + |edges|` fits in
/// `u32`. Violations give a meaningless but well-formed result; this function never panics.
/// Runs in O(V + T) (bucket sort of the edges by their smaller vertex).
pub fn split(coarse_triangles: &[[u32; 3]], coarse_vertices: usize) -> Split {
    let table = EdgeTable::build(coarse_triangles, coarse_vertices);
    let triangles = split_triangles(coarse_triangles, &table.tri_edges, coarse_vertices);
    Split {
        coarse_vertices,
        edges: table.edges,
        triangles,
    }
}

/// Fine triangles from the coarse ones and their edge indices (see [`EdgeTable::tri_edges`]).
pub(crate) fn split_triangles(
    triangles: &[[u32; 3]],
    tri_edges: &[[u32; 3]],
    coarse_vertices: usize,
) -> Vec<[u32; 3]> {
    let base = coarse_vertices as u32;
    let mut out = Vec::with_capacity(4 * triangles.len());
    for (&[a, b, c], e) in triangles.iter().zip(tri_edges) {
        let ab = base.wrapping_add(e[0]);
        let bc = base.wrapping_add(e[1]);
        let ca = base.wrapping_add(e[2]);
        out.extend_from_slice(&[[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
    }
    out
}

/// Undirected edges of a triangle list with their incidences. Half-edge `3t + s` is side
/// `(t[s], t[(s + 1) % 3])` of triangle `t`.
#[derive(Clone, Debug, Default)]
pub(crate) struct EdgeTable {
    /// Edges `[min, max]`, sorted, unique.
    pub edges: Vec<[u32; 2]>,
    /// Per triangle, the edge index of its sides `(t0,t1)`, `(t1,t2)`, `(t2,t0)`.
    pub tri_edges: Vec<[u32; 3]>,
    /// Per edge, its first two half-edges (ascending), [`NO_HALFEDGE`] where absent.
    pub halfedges: Vec<[u32; 2]>,
    /// Per edge, the number of triangle sides on it (saturating at 255).
    pub face_count: Vec<u8>,
}

impl EdgeTable {
    /// Builds the table in O(V + T): bucket sort by the smaller vertex, then a sort of each
    /// (small) bucket. Falls back to one global sort if an index is `>= vertex_count`.
    /// Needs `3 * triangles.len() <= u32::MAX` for the half-edge ids (else they wrap).
    pub fn build(triangles: &[[u32; 3]], vertex_count: usize) -> Self {
        let in_range = triangles
            .iter()
            .all(|t| t.iter().all(|&i| (i as usize) < vertex_count));
        let mut walk = Walk::new(triangles.len());
        if in_range {
            // start[v]..start[v + 1] is the bucket of edges whose smaller vertex is v.
            let mut start = vec![0usize; vertex_count + 1];
            for t in triangles {
                for s in 0..3 {
                    start[t[s].min(t[(s + 1) % 3]) as usize + 1] += 1;
                }
            }
            for v in 0..vertex_count {
                start[v + 1] += start[v];
            }
            let mut keys = vec![0u64; 3 * triangles.len()];
            let mut cursor = start.clone();
            for (t, tri) in triangles.iter().enumerate() {
                for s in 0..3 {
                    let (a, b) = (tri[s], tri[(s + 1) % 3]);
                    let lo = a.min(b) as usize;
                    let he = (3 * t + s) as u32;
                    keys[cursor[lo]] = (u64::from(a.max(b)) << 32) | u64::from(he);
                    cursor[lo] += 1;
                }
            }
            for v in 0..vertex_count {
                let bucket = &mut keys[start[v]..start[v + 1]];
                bucket.sort_unstable();
                for &key in bucket.iter() {
                    walk.push(v as u32, (key >> 32) as u32, key as u32);
                }
            }
        } else {
            let mut keys: Vec<(u32, u32, u32)> = Vec::with_capacity(3 * triangles.len());
            for (t, tri) in triangles.iter().enumerate() {
                for s in 0..3 {
                    let (a, b) = (tri[s], tri[(s + 1) % 3]);
                    keys.push((a.min(b), a.max(b), (3 * t + s) as u32));
                }
            }
            keys.sort_unstable();
            for (lo, hi, he) in keys {
                walk.push(lo, hi, he);
            }
        }
        walk.table
    }

    /// The vertex opposite half-edge `he` in its triangle.
    pub fn opposite(triangles: &[[u32; 3]], he: u32) -> u32 {
        let (t, s) = (he as usize / 3, he as usize % 3);
        triangles[t][(s + 2) % 3]
    }
}

/// Accumulates the edge table from half-edges sorted by (min, max, half-edge).
struct Walk {
    table: EdgeTable,
    last: Option<(u32, u32)>,
}

impl Walk {
    fn new(triangles: usize) -> Self {
        let edges = 3 * triangles / 2 + 3;
        Walk {
            table: EdgeTable {
                edges: Vec::with_capacity(edges),
                tri_edges: vec![[0; 3]; triangles],
                halfedges: Vec::with_capacity(edges),
                face_count: Vec::with_capacity(edges),
            },
            last: None,
        }
    }

    #[inline]
    fn push(&mut self, lo: u32, hi: u32, he: u32) {
        let t = &mut self.table;
        if self.last != Some((lo, hi)) {
            self.last = Some((lo, hi));
            t.edges.push([lo, hi]);
            t.halfedges.push([NO_HALFEDGE; 2]);
            t.face_count.push(0);
        }
        let k = t.edges.len() - 1;
        let count = t.face_count[k];
        if count < 2 {
            t.halfedges[k][count as usize] = he;
        }
        t.face_count[k] = count.saturating_add(1);
        t.tri_edges[he as usize / 3][he as usize % 3] = k as u32;
    }
}

/// Which edges of a level are creases (sharp): sorted, deduplicated `[min, max]` pairs.
/// Boundary edges are always treated as creases and need not be listed.
///
/// Creases carry over to the next level: a crease edge `{a, b}` with odd vertex `m` becomes the
/// two crease edges `{a, m}` and `{m, b}` (done by [`crate::multires::loop_step`]).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Creases {
    /// Crease edges `[min, max]`, sorted, deduplicated.
    pub edges: Vec<[u32; 2]>,
}

impl Creases {
    /// No creases (boundaries are still sharp).
    pub fn none() -> Self {
        Creases::default()
    }

    /// Creases from edges in any order and orientation; sorts and deduplicates them.
    pub fn from_edges(edges: impl IntoIterator<Item = [u32; 2]>) -> Self {
        let mut edges: Vec<[u32; 2]> = edges
            .into_iter()
            .map(|[a, b]| [a.min(b), a.max(b)])
            .collect();
        edges.sort_unstable();
        edges.dedup();
        Creases { edges }
    }

    /// Whether `edges` holds the invariant (each `[min, max]`, strictly increasing).
    pub fn is_normalized(&self) -> bool {
        self.edges.iter().all(|e| e[0] <= e[1]) && self.edges.windows(2).all(|w| w[0] < w[1])
    }

    /// Number of crease edges.
    pub fn len(&self) -> usize {
        self.edges.len()
    }

    /// Whether there are no crease edges.
    pub fn is_empty(&self) -> bool {
        self.edges.is_empty()
    }

    /// Whether `{a, b}` is listed as a crease (binary search; needs [`Creases::is_normalized`]).
    pub fn contains(&self, a: u32, b: u32) -> bool {
        self.edges.binary_search(&[a.min(b), a.max(b)]).is_ok()
    }
}

/// The class of a vertex on one level, from its sharp (crease + boundary) edges; it selects
/// the Loop vertex rule.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VertexClass {
    /// No sharp edge: smooth rule `(1 − nβ)v + βΣ neighbours` (an isolated vertex stays).
    Smooth,
    /// Exactly two sharp edges, to these neighbours (ascending): rule `(v₋ + 6v + v₊)/8`.
    Crease([u32; 2]),
    /// One or at least three sharp edges: the vertex stays.
    Corner,
}

/// Classifies the vertices of a level (`vertex_count` vertices, `triangles`) from its boundary
/// edges and `creases`. Listed creases that are not edges of the mesh are ignored (the
/// subdivision entry points reject them instead). Never panics.
pub fn classify_vertices(
    triangles: &[[u32; 3]],
    vertex_count: usize,
    creases: &Creases,
) -> Vec<VertexClass> {
    let table = EdgeTable::build(triangles, vertex_count);
    let creases = normalized(creases);
    let (sharp, _) = mark_sharp(&table, &creases.edges);
    classify(vertex_count, &table.edges, &sharp)
}

/// `creases` itself if normalized, else a normalized copy.
pub(crate) fn normalized(creases: &Creases) -> std::borrow::Cow<'_, Creases> {
    if creases.is_normalized() {
        std::borrow::Cow::Borrowed(creases)
    } else {
        std::borrow::Cow::Owned(Creases::from_edges(creases.edges.iter().copied()))
    }
}

/// Sharp flags per edge (boundary, non-manifold or listed crease) and the listed creases
/// that are not edges of the table. `creases` must be normalized. O(E + C) merge.
pub(crate) fn mark_sharp(table: &EdgeTable, creases: &[[u32; 2]]) -> (Vec<bool>, Vec<[u32; 2]>) {
    let mut sharp: Vec<bool> = table.face_count.iter().map(|&c| c != 2).collect();
    let mut unknown = Vec::new();
    let mut k = 0;
    for &c in creases {
        while k < table.edges.len() && table.edges[k] < c {
            k += 1;
        }
        if k < table.edges.len() && table.edges[k] == c {
            sharp[k] = true;
        } else {
            unknown.push(c);
        }
    }
    (sharp, unknown)
}

/// Vertex classes from the edge list and per-edge sharp flags. Endpoints `>= vertex_count`
/// are ignored.
pub(crate) fn classify(
    vertex_count: usize,
    edges: &[[u32; 2]],
    sharp: &[bool],
) -> Vec<VertexClass> {
    let mut count = vec![0u32; vertex_count];
    let mut first = vec![[0u32; 2]; vertex_count];
    for (&[a, b], _) in edges.iter().zip(sharp).filter(|(_, s)| **s) {
        for (v, w) in [(a, b), (b, a)] {
            if let Some(c) = count.get_mut(v as usize) {
                if *c < 2 {
                    first[v as usize][*c as usize] = w;
                }
                *c += 1;
            }
        }
    }
    count
        .iter()
        .zip(&first)
        .map(|(&c, &nb)| match c {
            0 => VertexClass::Smooth,
            2 => VertexClass::Crease([nb[0].min(nb[1]), nb[0].max(nb[1])]),
            _ => VertexClass::Corner,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::multires::test_meshes;

    #[test]
    fn single_triangle_split_follows_numbering() {
        let s = split(&[[0, 1, 2]], 3);
        // edges sorted: [0,1] -> 3, [0,2] -> 4, [1,2] -> 5
        assert_eq!(s.edges, vec![[0, 1], [0, 2], [1, 2]]);
        assert_eq!(
            s.triangles,
            vec![[0, 3, 4], [3, 1, 5], [4, 5, 2], [3, 5, 4]]
        );
        assert_eq!(s.fine_vertices(), 6);
        assert_eq!(s.edge_index(2, 1), Some(2));
        assert_eq!(s.odd_vertex(2), 5);
    }

    #[test]
    fn split_counts_match_euler_on_closed_mesh() {
        let m = test_meshes::octahedron();
        let s = split(&m.triangles, m.positions.len());
        assert_eq!(s.edges.len(), 12);
        assert_eq!(s.triangles.len(), 32);
        assert!(s.edges.windows(2).all(|w| w[0] < w[1]));
    }

    #[test]
    fn split_does_not_depend_on_bucket_or_fallback_path() {
        // Declaring fewer vertices than used forces the global-sort path: same edges.
        let m = test_meshes::irregular_closed();
        let a = EdgeTable::build(&m.triangles, m.positions.len());
        let b = EdgeTable::build(&m.triangles, 0);
        assert_eq!(a.edges, b.edges);
        assert_eq!(a.tri_edges, b.tri_edges);
        assert_eq!(a.halfedges, b.halfedges);
    }

    #[test]
    fn split_with_bad_indices_does_not_panic() {
        let s = split(&[[0, 1, u32::MAX], [5, 5, 5]], 3);
        assert_eq!(s.triangles.len(), 8);
        let t = EdgeTable::build(&[[0, 1, 2], [1, 0, 3], [0, 1, 4]], 5);
        let k = t.edges.binary_search(&[0, 1]).unwrap();
        assert_eq!(t.face_count[k], 3);
    }

    #[test]
    fn creases_normalize() {
        let c = Creases::from_edges([[3, 1], [1, 3], [0, 2]]);
        assert_eq!(c.edges, vec![[0, 2], [1, 3]]);
        assert!(c.is_normalized() && c.contains(3, 1) && !c.contains(0, 1));
        assert!(
            !Creases {
                edges: vec![[2, 1]]
            }
            .is_normalized()
        );
    }

    #[test]
    fn classification_of_grid_and_cube() {
        // Open grid: corners and sides have 2 boundary edges, interior none.
        let g = test_meshes::grid(3, 3, false);
        let classes = classify_vertices(&g.triangles, g.positions.len(), &Creases::none());
        let boundary = |i: usize| {
            let (x, y) = (i % 4, i / 4);
            x == 0 || y == 0 || x == 3 || y == 3
        };
        for (i, c) in classes.iter().enumerate() {
            assert_eq!(
                matches!(c, VertexClass::Crease(_)),
                boundary(i),
                "vertex {i}"
            );
            assert_eq!(matches!(c, VertexClass::Smooth), !boundary(i), "vertex {i}");
        }
        assert_eq!(classes[1], VertexClass::Crease([0, 2]));
        // A crease from the corner 0 into the interior makes vertex 0 a corner (3 sharp
        // edges) and the interior end a corner (1 sharp edge).
        let c = Creases::from_edges([[0, 5]]);
        let classes = classify_vertices(&g.triangles, g.positions.len(), &c);
        assert_eq!(classes[0], VertexClass::Corner);
        assert_eq!(classes[5], VertexClass::Corner);
        // Cube with its 12 edges creased: all 8 vertices are corners.
        let cube = test_meshes::cube();
        let creases = test_meshes::cube_edges();
        let classes = classify_vertices(&cube.triangles, 8, &creases);
        assert!(classes.iter().all(|c| *c == VertexClass::Corner));
    }
}
