//! The edge-collapse loop: a priority queue of edges keyed by quadric error, with lazy deletion
//! through per-vertex version counters, topology and geometry checks at pop time, and the
//! final compaction.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use nalgebra::{Point3, Vector3};

use super::features::InitialQuadrics;
use super::quadric::Quadric;
use super::topology::Topology;
use crate::mesh::Mesh;
use crate::multires::Creases;

/// Triangles whose quality (see [`quality`]) is at or below this are treated as degenerate:
/// their normal is not trusted by the flip test, and no collapse may create one unless the
/// triangle was already that bad.
const QUALITY_FLOOR: f64 = 1e-6;

/// Smallest closed component the collapse may leave (a tetrahedron).
const MIN_CLOSED_COMPONENT_TRIANGLES: usize = 4;

/// Parameters of one run, already validated and converted.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Params {
    pub(crate) target_triangles: usize,
    pub(crate) max_error: Option<f64>,
    pub(crate) min_quality: f64,
    /// Cosine of the largest allowed turn of a surviving triangle's normal.
    pub(crate) cos_max_turn: f64,
    /// Model origin for the quadrics (bounding-box centre).
    pub(crate) origin: Vector3<f64>,
    /// Smallest area (mm²) used to normalise a quadric's error.
    pub(crate) area_floor: f64,
}

/// Result of the collapse loop.
pub(crate) struct Outcome {
    pub(crate) mesh: Mesh,
    pub(crate) creases: Creases,
    pub(crate) origin: Vec<u32>,
    pub(crate) collapses: usize,
    pub(crate) max_error: f64,
}

/// Triangle quality `4√3·area / (l₀² + l₁² + l₂²)`: 1 for equilateral, 0 for degenerate.
/// A needle or cap with smallest angle θ has quality of roughly θ to √3·θ (θ in radians).
pub(crate) fn quality(a: &Point3<f64>, b: &Point3<f64>, c: &Point3<f64>) -> f64 {
    let twice_area = (b - a).cross(&(c - a)).norm();
    let sum_sq = (b - a).norm_squared() + (c - b).norm_squared() + (a - c).norm_squared();
    if sum_sq > 0.0 {
        2.0 * 3f64.sqrt() * twice_area / sum_sq
    } else {
        0.0
    }
}

/// A queued edge. Valid while both endpoint versions match the ones recorded here.
#[derive(Clone, Copy, Debug)]
struct Entry {
    /// Error estimate in mm (square root of the normalised quadric error).
    cost: f64,
    a: u32,
    b: u32,
    version_a: u32,
    version_b: u32,
}

impl Ord for Entry {
    /// Reversed, so that `BinaryHeap` pops the cheapest edge first, then the lowest indices.
    fn cmp(&self, other: &Self) -> Ordering {
        other
            .cost
            .total_cmp(&self.cost)
            .then(other.a.cmp(&self.a))
            .then(other.b.cmp(&self.b))
            .then(other.version_a.cmp(&self.version_a))
            .then(other.version_b.cmp(&self.version_b))
    }
}

impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl PartialEq for Entry {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}

impl Eq for Entry {}

/// One way to collapse an edge: vertex `remove` merges into `keep`, which moves to `position`.
#[derive(Clone, Copy, Debug)]
struct Candidate {
    error: f64,
    keep: u32,
    remove: u32,
    position: Point3<f64>,
}

/// Mutable mesh state during the collapse.
struct State {
    params: Params,
    positions: Vec<Point3<f64>>,
    faces: Vec<[u32; 3]>,
    face_alive: Vec<bool>,
    /// Unit normal of each triangle in the input (`None` if degenerate there).
    original_normal: Vec<Option<Vector3<f64>>>,
    /// Live triangles around each vertex.
    vertex_faces: Vec<Vec<u32>>,
    /// Neighbours across sharp (boundary or crease) edges.
    sharp_neighbours: Vec<Vec<u32>>,
    quadrics: Vec<Quadric>,
    /// Face planes only, summed like `quadrics` (see [`InitialQuadrics::surface`]).
    surface_quadrics: Vec<Quadric>,
    version: Vec<u32>,
    vertex_alive: Vec<bool>,
    component_of_vertex: Vec<u32>,
    component_faces: Vec<usize>,
    component_closed: Vec<bool>,
    live_faces: usize,
    heap: BinaryHeap<Entry>,
    // Scratch buffers.
    ring_a: Vec<u32>,
    ring_b: Vec<u32>,
    candidates: Vec<Candidate>,
}

/// Runs the collapse on a validated mesh. `sharp` lists the sharp edges (`[min, max]`).
pub(crate) fn run(
    mesh: &Mesh,
    topology: &Topology,
    sharp: &[[u32; 2]],
    initial: InitialQuadrics,
    params: Params,
) -> Outcome {
    let n = mesh.positions.len();
    let mut vertex_faces = vec![Vec::new(); n];
    let mut component_of_vertex = vec![u32::MAX; n];
    for (t, tri) in mesh.triangles.iter().enumerate() {
        for &v in tri {
            vertex_faces[v as usize].push(t as u32);
            component_of_vertex[v as usize] = topology.component_of_face[t];
        }
    }
    let mut sharp_neighbours = vec![Vec::new(); n];
    for &[a, b] in sharp {
        sharp_neighbours[a as usize].push(b);
        sharp_neighbours[b as usize].push(a);
    }
    let vertex_alive = vertex_faces.iter().map(|f| !f.is_empty()).collect();
    let mut state = State {
        params,
        positions: mesh.positions.clone(),
        faces: mesh.triangles.clone(),
        face_alive: vec![true; mesh.triangles.len()],
        original_normal: mesh
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
                (quality(&a, &b, &c) > QUALITY_FLOOR).then(|| (b - a).cross(&(c - a)).normalize())
            })
            .collect(),
        vertex_faces,
        sharp_neighbours,
        quadrics: initial.quadrics,
        surface_quadrics: initial.surface,
        version: vec![0; n],
        vertex_alive,
        component_of_vertex,
        component_faces: topology.component_faces.clone(),
        component_closed: topology.component_closed.clone(),
        live_faces: mesh.triangles.len(),
        heap: BinaryHeap::with_capacity(topology.edges.len() * 2),
        ring_a: Vec::new(),
        ring_b: Vec::new(),
        candidates: Vec::new(),
    };
    for e in &topology.edges {
        state.push_edge(e.vertices[0], e.vertices[1]);
    }
    let (collapses, max_error) = state.collapse_loop();
    state.into_outcome(collapses, max_error)
}

impl State {
    /// Normalised error of placing the merged vertex with quadric `q` at `p`, in mm.
    fn error(&self, q: &Quadric, p: &Point3<f64>) -> f64 {
        let rel = p.coords - self.params.origin;
        (q.eval(&rel) / q.area.max(self.params.area_floor)).sqrt()
    }

    fn is_sharp(&self, a: u32, b: u32) -> bool {
        self.sharp_neighbours[a as usize].contains(&b)
    }

    /// Whether `remove` may merge into its neighbour along an edge that is `sharp_edge`:
    /// smooth vertices always may; crease vertices (two sharp edges) only along their crease;
    /// corners (one or three or more sharp edges) never.
    fn may_remove(&self, remove: u32, sharp_edge: bool) -> bool {
        match self.sharp_neighbours[remove as usize].len() {
            0 => true,
            2 => sharp_edge,
            _ => false,
        }
    }

    /// Fills `self.candidates` with the ways to collapse `{a, b}`, cheapest first (ties keep
    /// the fixed order: optimum, `a`, `b`, midpoint).
    fn fill_candidates(&mut self, a: u32, b: u32) {
        let mut out = std::mem::take(&mut self.candidates);
        out.clear();
        let q = self.quadrics[a as usize].sum(&self.quadrics[b as usize]);
        let (pa, pb) = (self.positions[a as usize], self.positions[b as usize]);
        let sharp_edge = self.is_sharp(a, b);
        let smooth_a = self.sharp_neighbours[a as usize].is_empty();
        let smooth_b = self.sharp_neighbours[b as usize].is_empty();
        let mut push = |state: &Self, keep: u32, remove: u32, position: Point3<f64>| {
            out.push(Candidate {
                error: state.error(&q, &position),
                keep,
                remove,
                position,
            });
        };
        if smooth_a && smooth_b {
            // Free placement: the quadric optimum if it stays near the edge, else the best of
            // the endpoints and the midpoint.
            let (keep, remove) = (a.min(b), a.max(b));
            let mid = nalgebra::center(&pa, &pb);
            let length = (pb - pa).norm();
            if let Some(rel) = q.optimum_near(&(mid.coords - self.params.origin)) {
                let p = Point3::from(rel + self.params.origin);
                if (p - mid).norm() <= length {
                    push(self, keep, remove, p);
                }
            }
            push(self, keep, remove, pa);
            push(self, keep, remove, pb);
            push(self, keep, remove, mid);
        } else {
            // A feature vertex never leaves its original position.
            if self.may_remove(b, sharp_edge) {
                push(self, a, b, pa);
            }
            if self.may_remove(a, sharp_edge) {
                push(self, b, a, pb);
            }
        }
        out.sort_by(|x, y| x.error.total_cmp(&y.error));
        self.candidates = out;
    }

    /// Queues edge `{a, b}` with its cheapest candidate's error, if it has any candidate.
    fn push_edge(&mut self, a: u32, b: u32) {
        self.fill_candidates(a, b);
        if let Some(c) = self.candidates.first() {
            let entry = Entry {
                cost: c.error,
                a,
                b,
                version_a: self.version[a as usize],
                version_b: self.version[b as usize],
            };
            self.heap.push(entry);
        }
    }

    /// Sorted, deduplicated neighbours of `v` written into `out`.
    fn ring_into(&self, v: u32, out: &mut Vec<u32>) {
        out.clear();
        for &f in &self.vertex_faces[v as usize] {
            out.extend(self.faces[f as usize].iter().copied().filter(|&w| w != v));
        }
        out.sort_unstable();
        out.dedup();
    }

    /// The best valid collapse of `{a, b}`, or `None` if every candidate is rejected.
    fn evaluate(&mut self, a: u32, b: u32) -> Option<Candidate> {
        // Opposite vertices: third corners of the triangles on the edge.
        let mut opposite = [0u32; 2];
        let mut n_opposite = 0;
        for &f in &self.vertex_faces[a as usize] {
            let tri = self.faces[f as usize];
            if tri.contains(&b) {
                if n_opposite == 2 {
                    return None; // invariant: the mesh stays manifold; never reached.
                }
                // invariant: a triangle holding a and b has a third, distinct corner.
                opposite[n_opposite] = tri.into_iter().find(|&w| w != a && w != b)?;
                n_opposite += 1;
            }
        }
        if n_opposite == 0 {
            return None;
        }
        // Link condition: the common neighbours are exactly the opposite vertices.
        let (mut ring_a, mut ring_b) = (
            std::mem::take(&mut self.ring_a),
            std::mem::take(&mut self.ring_b),
        );
        self.ring_into(a, &mut ring_a);
        self.ring_into(b, &mut ring_b);
        let common = count_common_sorted(&ring_a, &ring_b);
        self.ring_a = ring_a;
        self.ring_b = ring_b;
        if common != n_opposite {
            return None;
        }
        let component = self.component_of_vertex[a as usize] as usize;
        if self.component_closed[component]
            && self.component_faces[component] < MIN_CLOSED_COMPONENT_TRIANGLES + n_opposite
        {
            return None;
        }
        self.fill_candidates(a, b);
        let candidates = std::mem::take(&mut self.candidates);
        // Candidates come cheapest first by their vertex error, which a span error can only
        // raise: stop once no later candidate can beat the best so far.
        let mut best: Option<Candidate> = None;
        for c in &candidates {
            if best.is_some_and(|b| b.error <= c.error) {
                break;
            }
            if !(self.sharp_merge_ok(c) && self.geometry_ok(c)) {
                continue;
            }
            let error = c.error.max(self.span_error(c));
            if best.is_none_or(|b| error < b.error) {
                best = Some(Candidate { error, ..*c });
            }
        }
        self.candidates = candidates;
        best
    }

    /// How far the triangles a collapse leaves around the merged vertex stray from the surface
    /// they replace, in mm: each triangle's summed surface quadric (its corners' regions)
    /// at its centroid and edge midpoints. The vertex quadric alone measures only the merged
    /// vertex, so a long triangle from a flat face across a fillet costs nothing there; this
    /// catches it, and makes the base finer where the part curves.
    fn span_error(&self, c: &Candidate) -> f64 {
        let merged =
            self.surface_quadrics[c.keep as usize].sum(&self.surface_quadrics[c.remove as usize]);
        let mut worst = 0.0_f64;
        // A feature vertex does not move, so its own triangles keep their shape; and they may
        // lie on the other side of its crease, off the planes `remove` brings.
        let keep_moves = self.sharp_neighbours[c.keep as usize].is_empty();
        let keep_faces: &[u32] = if keep_moves {
            &self.vertex_faces[c.keep as usize]
        } else {
            &[]
        };
        let faces = self.vertex_faces[c.remove as usize]
            .iter()
            .chain(keep_faces);
        for &f in faces {
            let tri = self.faces[f as usize];
            if tri.contains(&c.keep) && tri.contains(&c.remove) {
                continue; // dies with the collapse
            }
            let mut q = merged;
            let mut corners = [Point3::origin(); 3];
            for (corner, &v) in corners.iter_mut().zip(&tri) {
                if v == c.keep || v == c.remove {
                    *corner = c.position;
                } else {
                    *corner = self.positions[v as usize];
                    q.add(&self.surface_quadrics[v as usize]);
                }
            }
            let [p0, p1, p2] = corners;
            let points = [
                Point3::from((p0.coords + p1.coords + p2.coords) / 3.0),
                nalgebra::center(&p0, &p1),
                nalgebra::center(&p1, &p2),
                nalgebra::center(&p2, &p0),
            ];
            for p in &points {
                worst = worst.max(self.error(&q, p));
            }
        }
        worst
    }

    /// Moving `remove`'s sharp edges to `keep` must not merge two sharp edges into one (that
    /// would shrink a boundary loop or crease loop of three edges, or fold a crease).
    fn sharp_merge_ok(&self, c: &Candidate) -> bool {
        let keep = &self.sharp_neighbours[c.keep as usize];
        self.sharp_neighbours[c.remove as usize]
            .iter()
            .all(|&x| x == c.keep || !keep.contains(&x))
    }

    /// No surviving triangle around the edge may turn its normal by more than the allowed
    /// angle, in this step or in total since the input, or become worse than the quality
    /// bound (unless it already was).
    fn geometry_ok(&self, c: &Candidate) -> bool {
        let bound = self.params.min_quality.max(QUALITY_FLOOR);
        let faces = self.vertex_faces[c.remove as usize]
            .iter()
            .chain(&self.vertex_faces[c.keep as usize]);
        for &f in faces {
            let tri = self.faces[f as usize];
            if tri.contains(&c.keep) && tri.contains(&c.remove) {
                continue; // dies with the collapse
            }
            let old = tri.map(|v| self.positions[v as usize]);
            let new = tri.map(|v| {
                if v == c.keep || v == c.remove {
                    c.position
                } else {
                    self.positions[v as usize]
                }
            });
            let q_old = quality(&old[0], &old[1], &old[2]);
            let q_new = quality(&new[0], &new[1], &new[2]);
            if q_new < bound && q_new < q_old {
                return false;
            }
            if q_old > QUALITY_FLOOR && q_new > QUALITY_FLOOR {
                let n_old = (old[1] - old[0]).cross(&(old[2] - old[0]));
                let n_new = (new[1] - new[0]).cross(&(new[2] - new[0]));
                if n_old.dot(&n_new) < self.params.cos_max_turn * n_old.norm() * n_new.norm() {
                    return false;
                }
            }
            if let Some(n0) = self.original_normal[f as usize]
                && q_new > QUALITY_FLOOR
            {
                let n_new = (new[1] - new[0]).cross(&(new[2] - new[0]));
                if n0.dot(&n_new) < self.params.cos_max_turn * n_new.norm() {
                    return false;
                }
            }
        }
        true
    }

    /// Performs the collapse; returns the number of triangles removed.
    fn apply(&mut self, c: &Candidate) -> usize {
        let (keep, remove) = (c.keep, c.remove);
        let faces_of_remove = std::mem::take(&mut self.vertex_faces[remove as usize]);
        let mut removed = 0;
        for f in faces_of_remove {
            let tri = self.faces[f as usize];
            if tri.contains(&keep) {
                self.face_alive[f as usize] = false;
                removed += 1;
                for w in tri {
                    if w != remove {
                        self.vertex_faces[w as usize].retain(|&g| g != f);
                    }
                }
            } else {
                self.faces[f as usize] = tri.map(|w| if w == remove { keep } else { w });
                self.vertex_faces[keep as usize].push(f);
            }
        }
        self.positions[keep as usize] = c.position;
        let q_remove = self.quadrics[remove as usize];
        self.quadrics[keep as usize].add(&q_remove);
        // Feature vertices carry no surface quadric (see `InitialQuadrics::surface`).
        if self.sharp_neighbours[keep as usize].is_empty() {
            let s_remove = self.surface_quadrics[remove as usize];
            self.surface_quadrics[keep as usize].add(&s_remove);
        }
        // Sharp edges of `remove` move to `keep` (sharp_merge_ok rules out duplicates).
        self.sharp_neighbours[keep as usize].retain(|&x| x != remove);
        for x in std::mem::take(&mut self.sharp_neighbours[remove as usize]) {
            if x != keep {
                for y in self.sharp_neighbours[x as usize].iter_mut() {
                    if *y == remove {
                        *y = keep;
                    }
                }
                self.sharp_neighbours[keep as usize].push(x);
            }
        }
        self.vertex_alive[remove as usize] = false;
        self.version[remove as usize] += 1;
        self.version[keep as usize] += 1;
        self.component_faces[self.component_of_vertex[keep as usize] as usize] -= removed;
        self.live_faces -= removed;
        removed
    }

    /// After a collapse into `keep`: invalidates and re-queues every edge at `keep` and at its
    /// neighbours (their costs or validity may have changed).
    fn requeue_around(&mut self, keep: u32) {
        let mut ring = std::mem::take(&mut self.ring_a);
        self.ring_into(keep, &mut ring);
        ring.push(keep);
        let mut edges: Vec<[u32; 2]> = Vec::with_capacity(ring.len() * 7);
        let mut ring_w = std::mem::take(&mut self.ring_b);
        for &w in &ring {
            self.version[w as usize] += 1;
            self.ring_into(w, &mut ring_w);
            edges.extend(ring_w.iter().map(|&x| [w.min(x), w.max(x)]));
        }
        self.ring_a = ring;
        self.ring_b = ring_w;
        edges.sort_unstable();
        edges.dedup();
        for [a, b] in edges {
            self.push_edge(a, b);
        }
    }

    /// Collapses until the target, the error limit, or an empty queue. Returns the number of
    /// collapses and the largest error among them.
    fn collapse_loop(&mut self) -> (usize, f64) {
        let mut collapses = 0;
        let mut max_error = 0.0_f64;
        while self.live_faces > self.params.target_triangles {
            let Some(entry) = self.heap.pop() else { break };
            let (a, b) = (entry.a as usize, entry.b as usize);
            if !self.vertex_alive[a]
                || !self.vertex_alive[b]
                || self.version[a] != entry.version_a
                || self.version[b] != entry.version_b
            {
                continue; // stale
            }
            if self.params.max_error.is_some_and(|m| entry.cost > m) {
                break;
            }
            let Some(c) = self.evaluate(entry.a, entry.b) else {
                continue; // re-queued if its neighbourhood changes
            };
            if c.error > entry.cost {
                // The cheapest placement was rejected: queue again at the true cost.
                self.heap.push(Entry {
                    cost: c.error,
                    ..entry
                });
                continue;
            }
            self.apply(&c);
            collapses += 1;
            max_error = max_error.max(c.error);
            self.requeue_around(c.keep);
        }
        (collapses, max_error)
    }

    /// Compacts the live part: vertices renumbered in increasing original index, triangles in
    /// original order; crease edges (interior sharp edges) by the new indices.
    fn into_outcome(self, collapses: usize, max_error: f64) -> Outcome {
        let mut new_index = vec![u32::MAX; self.positions.len()];
        let mut used = vec![false; self.positions.len()];
        for (tri, _) in self.faces.iter().zip(&self.face_alive).filter(|(_, a)| **a) {
            for &v in tri {
                used[v as usize] = true;
            }
        }
        let mut positions = Vec::new();
        let mut origin = Vec::new();
        for (v, _) in used.iter().enumerate().filter(|(_, u)| **u) {
            new_index[v] = positions.len() as u32;
            positions.push(self.positions[v]);
            origin.push(v as u32);
        }
        let triangles = self
            .faces
            .iter()
            .zip(&self.face_alive)
            .filter(|(_, a)| **a)
            .map(|(tri, _)| tri.map(|v| new_index[v as usize]))
            .collect();
        let mut creases = Vec::new();
        for v in (0..self.positions.len() as u32).filter(|&v| used[v as usize]) {
            for &x in self.sharp_neighbours[v as usize].iter().filter(|&&x| x > v) {
                let faces_on_edge = self.vertex_faces[v as usize]
                    .iter()
                    .filter(|&&f| self.faces[f as usize].contains(&x))
                    .count();
                if faces_on_edge == 2 {
                    let (p, q) = (new_index[v as usize], new_index[x as usize]);
                    creases.push([p.min(q), p.max(q)]);
                }
            }
        }
        creases.sort_unstable();
        creases.dedup();
        Outcome {
            mesh: Mesh {
                positions,
                triangles,
            },
            creases: Creases { edges: creases },
            origin,
            collapses,
            max_error,
        }
    }
}

/// Number of values present in both sorted, deduplicated slices.
fn count_common_sorted(a: &[u32], b: &[u32]) -> usize {
    let (mut i, mut j, mut n) = (0, 0, 0);
    while i < a.len() && j < b.len() {
        match a[i].cmp(&b[j]) {
            Ordering::Less => i += 1,
            Ordering::Greater => j += 1,
            Ordering::Equal => {
                n += 1;
                i += 1;
                j += 1;
            }
        }
    }
    n
}
