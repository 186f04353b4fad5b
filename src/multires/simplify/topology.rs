//! Connectivity checks and facts for the input: manifold edges and vertices, consistent
//! orientation, boundary edges, connected components. Works on indices only, never positions.

use super::SimplifyError;

/// One undirected edge of the input and the (one or two) triangles using it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct EdgeFaces {
    /// `[min, max]` vertex indices.
    pub(crate) vertices: [u32; 2],
    /// Triangle indices; `faces[1]` is meaningful only when `count == 2`.
    pub(crate) faces: [u32; 2],
    /// 1 for a boundary edge, 2 for an interior edge.
    pub(crate) count: u8,
}

impl EdgeFaces {
    /// True for a boundary edge (one incident triangle).
    pub(crate) fn is_boundary(&self) -> bool {
        self.count == 1
    }
}

/// Connectivity facts of a validated manifold mesh.
#[derive(Clone, Debug)]
pub(crate) struct Topology {
    /// Undirected edges, sorted by `vertices`.
    pub(crate) edges: Vec<EdgeFaces>,
    /// Component id of each triangle (components numbered by their lowest triangle).
    pub(crate) component_of_face: Vec<u32>,
    /// Per component: true when it has no boundary edge.
    pub(crate) component_closed: Vec<bool>,
    /// Per component: its number of triangles.
    pub(crate) component_faces: Vec<usize>,
}

impl Topology {
    /// Number of connected components (triangles connected through shared edges).
    #[cfg(test)]
    pub(crate) fn component_count(&self) -> usize {
        self.component_closed.len()
    }

    /// Euler characteristic `V − E + F` counting only referenced vertices.
    #[cfg(test)]
    pub(crate) fn euler_characteristic(&self, triangles: &[[u32; 3]]) -> i64 {
        let mut used: Vec<u32> = triangles.iter().flatten().copied().collect();
        used.sort_unstable();
        used.dedup();
        used.len() as i64 - self.edges.len() as i64 + triangles.len() as i64
    }

    /// Number of boundary edges.
    #[cfg(test)]
    pub(crate) fn boundary_edge_count(&self) -> usize {
        self.edges.iter().filter(|e| e.is_boundary()).count()
    }
}

/// Union–find with path halving; roots are the smallest member (deterministic numbering).
struct UnionFind {
    parent: Vec<u32>,
}

impl UnionFind {
    fn new(n: usize) -> Self {
        Self {
            parent: (0..n as u32).collect(),
        }
    }

    fn find(&mut self, mut x: u32) -> u32 {
        while self.parent[x as usize] != x {
            let grand = self.parent[self.parent[x as usize] as usize];
            self.parent[x as usize] = grand;
            x = grand;
        }
        x
    }

    fn union(&mut self, a: u32, b: u32) {
        let (ra, rb) = (self.find(a), self.find(b));
        let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
        self.parent[hi as usize] = lo;
    }
}

/// Validates that `triangles` over `vertex_count` vertices form an oriented 2-manifold (with
/// or without boundary) and returns its edges and components.
///
/// Errors: an index out of range, a triangle repeating a vertex, an edge with more than two
/// triangles, two triangles traversing an edge in the same direction, or a vertex whose
/// triangles form more than one fan.
pub(crate) fn analyse(
    triangles: &[[u32; 3]],
    vertex_count: usize,
) -> Result<Topology, SimplifyError> {
    // Directed half-edges keyed by their undirected edge.
    let mut half: Vec<([u32; 2], bool, u32)> = Vec::with_capacity(triangles.len() * 3);
    for (t, tri) in triangles.iter().enumerate() {
        for &v in tri {
            if v as usize >= vertex_count {
                return Err(SimplifyError::IndexOutOfRange {
                    triangle: t,
                    vertex: v,
                });
            }
        }
        if tri[0] == tri[1] || tri[1] == tri[2] || tri[2] == tri[0] {
            return Err(SimplifyError::DegenerateTriangle { triangle: t });
        }
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            half.push(([a.min(b), a.max(b)], a < b, t as u32));
        }
    }
    half.sort_unstable();

    let mut edges = Vec::with_capacity(half.len() / 2 + 1);
    let mut i = 0;
    while i < half.len() {
        let key = half[i].0;
        let mut j = i;
        while j < half.len() && half[j].0 == key {
            j += 1;
        }
        match j - i {
            1 => edges.push(EdgeFaces {
                vertices: key,
                faces: [half[i].2, half[i].2],
                count: 1,
            }),
            2 => {
                if half[i].1 == half[i + 1].1 {
                    return Err(SimplifyError::InconsistentOrientation { edge: key });
                }
                edges.push(EdgeFaces {
                    vertices: key,
                    faces: [half[i].2, half[i + 1].2],
                    count: 2,
                });
            }
            n => {
                return Err(SimplifyError::NonManifoldEdge {
                    edge: key,
                    triangles: n,
                });
            }
        }
        i = j;
    }

    check_vertex_fans(triangles, vertex_count, &edges)?;

    // Components through interior edges.
    let mut uf = UnionFind::new(triangles.len());
    for e in edges.iter().filter(|e| e.count == 2) {
        uf.union(e.faces[0], e.faces[1]);
    }
    let mut component_of_root = vec![u32::MAX; triangles.len()];
    let mut component_of_face = Vec::with_capacity(triangles.len());
    let mut component_faces = Vec::new();
    for t in 0..triangles.len() as u32 {
        let r = uf.find(t) as usize;
        if component_of_root[r] == u32::MAX {
            component_of_root[r] = component_faces.len() as u32;
            component_faces.push(0);
        }
        let c = component_of_root[r];
        component_faces[c as usize] += 1;
        component_of_face.push(c);
    }
    let mut component_closed = vec![true; component_faces.len()];
    for e in edges.iter().filter(|e| e.is_boundary()) {
        component_closed[component_of_face[e.faces[0] as usize] as usize] = false;
    }
    Ok(Topology {
        edges,
        component_of_face,
        component_closed,
        component_faces,
    })
}

/// Every vertex's triangles must form one fan: connected through the edges at that vertex.
fn check_vertex_fans(
    triangles: &[[u32; 3]],
    vertex_count: usize,
    edges: &[EdgeFaces],
) -> Result<(), SimplifyError> {
    // Triangles per vertex (CSR layout).
    let mut start = vec![0usize; vertex_count + 1];
    for tri in triangles {
        for &v in tri {
            start[v as usize + 1] += 1;
        }
    }
    for v in 0..vertex_count {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    let mut faces_of = vec![0u32; start[vertex_count]];
    for (t, tri) in triangles.iter().enumerate() {
        for &v in tri {
            faces_of[fill[v as usize]] = t as u32;
            fill[v as usize] += 1;
        }
    }
    // Union, per vertex, the two triangles of each interior edge at it. Union–find over
    // triangle *slots* (a triangle has one slot per corner) keeps the fans of different
    // vertices apart.
    let slot = |v: u32, t: u32| -> usize {
        let range = &faces_of[start[v as usize]..start[v as usize + 1]];
        // invariant: t is incident to v (it came from an edge at v), so the search succeeds.
        start[v as usize] + range.iter().position(|&f| f == t).unwrap_or(0)
    };
    let mut uf = UnionFind::new(faces_of.len());
    for e in edges.iter().filter(|e| e.count == 2) {
        for &v in &e.vertices {
            uf.union(slot(v, e.faces[0]) as u32, slot(v, e.faces[1]) as u32);
        }
    }
    for v in 0..vertex_count {
        let (s, t) = (start[v], start[v + 1]);
        if t > s {
            let root = uf.find(s as u32);
            if (s + 1..t).any(|k| uf.find(k as u32) != root) {
                return Err(SimplifyError::NonManifoldVertex { vertex: v as u32 });
            }
        }
    }
    Ok(())
}
