//! Connectivity of a triangle mesh: edges, boundaries, non-manifold places, components,
//! orientation and genus. Works on indices only.

/// One undirected edge and the faces that use it, with the direction each face walks it.
#[derive(Clone, Debug)]
pub struct Edge {
    /// Smaller vertex index first.
    pub vertices: [u32; 2],
    /// `(face, walks it from vertices[0] to vertices[1])`.
    pub faces: Vec<(u32, bool)>,
}

/// All undirected edges of `triangles`, sorted by vertex pair (deterministic).
pub fn edges(triangles: &[[u32; 3]]) -> Vec<Edge> {
    let mut half: Vec<(u32, u32, u32, bool)> = Vec::with_capacity(triangles.len() * 3);
    for (f, t) in triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            half.push((a.min(b), a.max(b), f as u32, a < b));
        }
    }
    half.sort_unstable();
    let mut out: Vec<Edge> = Vec::new();
    for (a, b, f, fwd) in half {
        match out.last_mut() {
            Some(e) if e.vertices == [a, b] => e.faces.push((f, fwd)),
            _ => out.push(Edge {
                vertices: [a, b],
                faces: vec![(f, fwd)],
            }),
        }
    }
    out
}

/// Union–find over `n` items, with path halving.
pub(crate) struct DisjointSets {
    parent: Vec<u32>,
}

impl DisjointSets {
    pub fn new(n: usize) -> Self {
        Self {
            parent: (0..n as u32).collect(),
        }
    }
    pub fn find(&mut self, mut x: u32) -> u32 {
        while self.parent[x as usize] != x {
            let grand = self.parent[self.parent[x as usize] as usize];
            self.parent[x as usize] = grand;
            x = grand;
        }
        x
    }
    pub fn union(&mut self, a: u32, b: u32) {
        let (ra, rb) = (self.find(a), self.find(b));
        // The smaller root wins, so labels do not depend on the order of unions.
        if ra < rb {
            self.parent[rb as usize] = ra;
        } else if rb < ra {
            self.parent[ra as usize] = rb;
        }
    }
}

/// What the connectivity says about a mesh.
#[derive(Clone, Debug, Default)]
pub struct Topology {
    /// Component label per face, `0..component_count`, numbered by their lowest face.
    pub face_component: Vec<u32>,
    pub component_count: usize,
    pub edge_count: usize,
    /// Edges used by one face.
    pub boundary_edges: usize,
    /// Connected chains of boundary edges (holes).
    pub boundary_loops: usize,
    /// Edges used by more than two faces.
    pub non_manifold_edges: usize,
    /// Vertices whose faces form more than one fan (e.g. two cones touching at their tips).
    pub non_manifold_vertices: usize,
    /// Interior edges walked in the same direction by both faces: the winding disagrees there.
    pub inconsistent_edges: usize,
    /// Vertices referenced by at least one face.
    pub used_vertices: usize,
}

impl Topology {
    /// Analyses `triangles` on `vertex_count` vertices.
    pub fn analyse(triangles: &[[u32; 3]], vertex_count: usize) -> Topology {
        let edges = edges(triangles);
        let mut faces = DisjointSets::new(triangles.len());
        let mut boundary_vertices = DisjointSets::new(vertex_count);
        let mut is_boundary_vertex = vec![false; vertex_count];
        let mut topo = Topology {
            edge_count: edges.len(),
            ..Default::default()
        };
        for e in &edges {
            for w in e.faces.windows(2) {
                faces.union(w[0].0, w[1].0);
            }
            match e.faces.len() {
                1 => {
                    topo.boundary_edges += 1;
                    boundary_vertices.union(e.vertices[0], e.vertices[1]);
                    is_boundary_vertex[e.vertices[0] as usize] = true;
                    is_boundary_vertex[e.vertices[1] as usize] = true;
                }
                2 if e.faces[0].1 == e.faces[1].1 => topo.inconsistent_edges += 1,
                2 => {}
                _ => topo.non_manifold_edges += 1,
            }
        }
        topo.boundary_loops = (0..vertex_count as u32)
            .filter(|&v| is_boundary_vertex[v as usize] && boundary_vertices.find(v) == v)
            .count();
        let (labels, count) = relabel(&mut faces, triangles.len());
        topo.face_component = labels;
        topo.component_count = count;
        let (used, non_manifold) = vertex_fans(triangles, &edges, vertex_count);
        topo.used_vertices = used;
        topo.non_manifold_vertices = non_manifold;
        topo
    }

    pub fn is_closed_manifold(&self) -> bool {
        self.boundary_edges == 0 && self.non_manifold_edges == 0 && self.non_manifold_vertices == 0
    }
}

fn relabel(sets: &mut DisjointSets, n: usize) -> (Vec<u32>, usize) {
    let mut label_of_root = vec![u32::MAX; n];
    let mut labels = Vec::with_capacity(n);
    let mut count = 0;
    for f in 0..n as u32 {
        let r = sets.find(f) as usize;
        if label_of_root[r] == u32::MAX {
            label_of_root[r] = count;
            count += 1;
        }
        labels.push(label_of_root[r]);
    }
    (labels, count as usize)
}

/// Counts used vertices and vertices whose incident faces do not form a single fan when joined
/// across manifold edges.
fn vertex_fans(triangles: &[[u32; 3]], edges: &[Edge], vertex_count: usize) -> (usize, usize) {
    // Faces around each vertex, in CSR form.
    let mut start = vec![0u32; vertex_count + 1];
    for t in triangles {
        for &v in t {
            start[v as usize + 1] += 1;
        }
    }
    for i in 0..vertex_count {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut around = vec![0u32; start[vertex_count] as usize];
    for (f, t) in triangles.iter().enumerate() {
        for &v in t {
            around[fill[v as usize] as usize] = f as u32;
            fill[v as usize] += 1;
        }
    }
    // Manifold edges link the two faces around both of their end vertices.
    let mut links: Vec<(u32, u32, u32)> = Vec::new(); // (vertex, face, face)
    for e in edges.iter().filter(|e| e.faces.len() == 2) {
        for &v in &e.vertices {
            links.push((v, e.faces[0].0, e.faces[1].0));
        }
    }
    links.sort_unstable();
    let mut used = 0;
    let mut non_manifold = 0;
    let mut li = 0;
    for v in 0..vertex_count {
        let fs = &around[start[v] as usize..start[v + 1] as usize];
        if fs.is_empty() {
            while li < links.len() && links[li].0 as usize == v {
                li += 1;
            }
            continue;
        }
        used += 1;
        let mut local = DisjointSets::new(fs.len());
        let pos = |f: u32| fs.iter().position(|&g| g == f).unwrap_or(0) as u32;
        while li < links.len() && links[li].0 as usize == v {
            local.union(pos(links[li].1), pos(links[li].2));
            li += 1;
        }
        let fans = (0..fs.len() as u32).filter(|&i| local.find(i) == i).count();
        if fans > 1 {
            non_manifold += 1;
        }
    }
    (used, non_manifold)
}

/// The outcome of [`orient`].
#[derive(Clone, Debug, Default)]
pub struct Orientation {
    /// Faces whose winding was reversed.
    pub flipped_faces: usize,
    /// Components that cannot be oriented consistently (Möbius-like); left as they were.
    pub non_orientable_components: usize,
}

/// Makes the winding consistent within every orientable component by walking across
/// manifold edges, keeping for each component whichever orientation most input faces already
/// had. Closed components are then turned outward by `outward(component) -> bool`, which the
/// caller answers from geometry (signed volume) because connectivity cannot.
pub fn orient(
    triangles: &mut [[u32; 3]],
    topo: &Topology,
    mut is_outward: impl FnMut(&[[u32; 3]], &[u32]) -> bool,
) -> Orientation {
    let edges = edges(triangles);
    // Neighbours across manifold edges, with "same direction" flags.
    let mut neighbours: Vec<Vec<(u32, bool)>> = vec![Vec::new(); triangles.len()];
    for e in edges.iter().filter(|e| e.faces.len() == 2) {
        let [(f, df), (g, dg)] = [e.faces[0], e.faces[1]];
        neighbours[f as usize].push((g, df == dg));
        neighbours[g as usize].push((f, df == dg));
    }
    let mut flip: Vec<Option<bool>> = vec![None; triangles.len()];
    let mut result = Orientation::default();
    let mut component_faces: Vec<Vec<u32>> = vec![Vec::new(); topo.component_count];
    for (f, &c) in topo.face_component.iter().enumerate() {
        component_faces[c as usize].push(f as u32);
    }
    for faces in &component_faces {
        let mut orientable = true;
        // A component may be several edge-connected pieces joined only at non-manifold
        // edges; each piece is oriented on its own.
        for &seed in faces {
            if flip[seed as usize].is_some() {
                continue;
            }
            flip[seed as usize] = Some(false);
            let mut stack = vec![seed];
            let mut piece = vec![seed];
            while let Some(f) = stack.pop() {
                let ff = flip[f as usize].unwrap_or(false);
                for &(g, same) in &neighbours[f as usize] {
                    let want = ff ^ same;
                    match flip[g as usize] {
                        None => {
                            flip[g as usize] = Some(want);
                            stack.push(g);
                            piece.push(g);
                        }
                        Some(have) if have != want => orientable = false,
                        Some(_) => {}
                    }
                }
            }
            // Keep the majority's orientation.
            let flipped = piece
                .iter()
                .filter(|&&f| flip[f as usize] == Some(true))
                .count();
            if 2 * flipped > piece.len() {
                for &f in &piece {
                    flip[f as usize] = flip[f as usize].map(|x| !x);
                }
            }
        }
        if !orientable {
            result.non_orientable_components += 1;
            for &f in faces {
                flip[f as usize] = Some(false);
            }
        }
    }
    for (t, f) in triangles.iter_mut().zip(&flip) {
        if *f == Some(true) {
            t.swap(1, 2);
            result.flipped_faces += 1;
        }
    }
    // Closed, consistent components must face outward.
    let closed = closed_components(triangles, topo);
    for (c, faces) in component_faces.iter().enumerate() {
        if closed[c] && !is_outward(triangles, faces) {
            for &f in faces {
                triangles[f as usize].swap(1, 2);
            }
            result.flipped_faces += faces.len();
        }
    }
    result
}

/// For each component: no boundary edge, no non-manifold edge, winding consistent.
pub fn closed_components(triangles: &[[u32; 3]], topo: &Topology) -> Vec<bool> {
    let mut closed = vec![true; topo.component_count];
    for e in edges(triangles) {
        let c = topo.face_component[e.faces[0].0 as usize] as usize;
        if e.faces.len() != 2 || e.faces[0].1 == e.faces[1].1 {
            closed[c] = false;
        }
    }
    closed
}

/// Genus of each component that is a manifold orientable surface, from its Euler
/// characteristic χ = V − E + F = 2 − 2g − b (b = boundary loops). `None` for components where
/// the formula does not apply.
pub fn component_genus(
    triangles: &[[u32; 3]],
    topo: &Topology,
    vertex_count: usize,
) -> Vec<Option<i64>> {
    let n = topo.component_count;
    let mut v = vec![0i64; n];
    let mut e = vec![0i64; n];
    let mut f = vec![0i64; n];
    let mut b = vec![0i64; n];
    let mut bad = vec![false; n];
    let mut vertex_component = vec![u32::MAX; vertex_count];
    for (t, tri) in triangles.iter().enumerate() {
        let c = topo.face_component[t];
        f[c as usize] += 1;
        for &i in tri {
            if vertex_component[i as usize] == u32::MAX {
                vertex_component[i as usize] = c;
                v[c as usize] += 1;
            }
        }
    }
    let all_edges = edges(triangles);
    let mut boundary = DisjointSets::new(vertex_count);
    let mut on_boundary = vec![false; vertex_count];
    for ed in &all_edges {
        let c = topo.face_component[ed.faces[0].0 as usize] as usize;
        e[c] += 1;
        match ed.faces.len() {
            1 => {
                boundary.union(ed.vertices[0], ed.vertices[1]);
                on_boundary[ed.vertices[0] as usize] = true;
                on_boundary[ed.vertices[1] as usize] = true;
            }
            2 if ed.faces[0].1 != ed.faces[1].1 => {}
            _ => bad[c] = true,
        }
    }
    for vi in 0..vertex_count as u32 {
        if on_boundary[vi as usize] && boundary.find(vi) == vi {
            b[vertex_component[vi as usize] as usize] += 1;
        }
    }
    (0..n)
        .map(|c| {
            let twice = 2 - (v[c] - e[c] + f[c]) - b[c];
            (!bad[c] && twice >= 0 && twice % 2 == 0).then_some(twice / 2)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::fixtures::{cuboid, torus, uv_sphere};

    #[test]
    fn closed_shapes_have_the_right_genus() {
        for (m, g) in [
            (cuboid(1.0, 1.0, 1.0), 0),
            (uv_sphere(1.0, 8, 12), 0),
            (torus(5.0, 1.0, 24, 12), 1),
        ] {
            let t = Topology::analyse(&m.triangles, m.positions.len());
            assert!(t.is_closed_manifold());
            assert_eq!(t.component_count, 1);
            assert_eq!(t.inconsistent_edges, 0);
            assert_eq!(
                component_genus(&m.triangles, &t, m.positions.len()),
                vec![Some(g)]
            );
        }
    }

    #[test]
    fn open_box_has_one_boundary_loop() {
        let mut m = cuboid(1.0, 1.0, 1.0);
        m.triangles.truncate(10); // drop the last quad (two triangles)
        let t = Topology::analyse(&m.triangles, m.positions.len());
        assert_eq!(t.boundary_edges, 4);
        assert_eq!(t.boundary_loops, 1);
        // A disc: χ = 1 = 2 − 2g − 1 ⇒ g = 0.
        assert_eq!(component_genus(&m.triangles, &t, 8), vec![Some(0)]);
    }

    #[test]
    fn scrambled_winding_is_repaired_and_turned_outward() {
        let reference = uv_sphere(3.0, 10, 16);
        let mut m = reference.clone();
        for (i, t) in m.triangles.iter_mut().enumerate() {
            if i % 3 == 0 || i % 7 == 0 {
                t.swap(0, 1);
            }
        }
        let topo = Topology::analyse(&m.triangles, m.positions.len());
        assert!(topo.inconsistent_edges > 0);
        let positions = m.positions.clone();
        let outward = |tris: &[[u32; 3]], faces: &[u32]| {
            let mesh = crate::mesh::Mesh {
                positions: positions.clone(),
                triangles: faces.iter().map(|&f| tris[f as usize]).collect(),
            };
            mesh.signed_volume() > 0.0
        };
        let o = orient(&mut m.triangles, &topo, outward);
        assert_eq!(o.non_orientable_components, 0);
        assert!(m.signed_volume() > 0.0);
        let after = Topology::analyse(&m.triangles, m.positions.len());
        assert_eq!(after.inconsistent_edges, 0);
        // Same triangles as the reference up to rotation of corners.
        let canon = |t: &[u32; 3]| {
            let k = (0..3).min_by_key(|&k| t[k]).unwrap_or(0);
            [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]
        };
        for (a, b) in m.triangles.iter().zip(&reference.triangles) {
            assert_eq!(canon(a), canon(b));
        }
    }

    #[test]
    fn bowtie_vertex_and_fin_edge_are_non_manifold() {
        // Two tetrahedra sharing one vertex: a non-manifold vertex, manifold edges.
        let tet = |o: u32| {
            vec![
                [o, o + 2, o + 1],
                [o, o + 1, 3],
                [o + 1, o + 2, 3],
                [o + 2, o, 3],
            ]
        };
        let mut tris = tet(0);
        tris.extend(
            tet(4)
                .into_iter()
                .map(|t| t.map(|i| if i == 7 { 3 } else { i })),
        );
        let t = Topology::analyse(&tris, 8);
        assert_eq!(t.non_manifold_vertices, 1);
        assert_eq!(t.non_manifold_edges, 0);
        // A third face on one edge: a non-manifold edge.
        let mut fin = tet(0);
        fin.push([0, 1, 9]);
        let t = Topology::analyse(&fin, 10);
        assert_eq!(t.non_manifold_edges, 1);
    }
}
