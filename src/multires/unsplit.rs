//! Recognising subdivision connectivity: the inverse of the 1-to-4 split ([`super::split()`]).
//!
//! A mesh made by splitting a coarser one has a telltale structure. The coarse ("even")
//! vertices are pairwise non-adjacent; every other ("odd") vertex sits on one coarse edge, so
//! an interior odd vertex has valence 6 with its two even neighbours opposite each other in its
//! ring, a boundary one valence 4 with the evens at the two ends of its fan. Every fine
//! triangle holds at most one even vertex. [`unsplit`] finds such a colouring by propagation
//! from one vertex per connected piece, rebuilds the coarse triangles from the corner
//! triangles and accepts only if splitting them gives back exactly the input: the answer is
//! proved, not guessed.
//!
//! The planner uses [`subdivision_depth`] to tell a part that is already semi-regular (it can
//! be its own hierarchy) from one that must be remeshed first.

use std::collections::VecDeque;

use super::split::split;

/// A coarse level whose 1-to-4 split is the given mesh.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Unsplit {
    /// The coarse triangles, by coarse vertex index.
    pub triangles: Vec<[u32; 3]>,
    /// For each coarse vertex, the fine vertex it is (increasing).
    pub fine_vertex: Vec<u32>,
}

/// How many times in a row `triangles` (a manifold mesh of `vertex_count` vertices, every
/// vertex used) can be un-split: 0 for a mesh without subdivision connectivity. Stops at
/// `max_depth`.
pub fn subdivision_depth(triangles: &[[u32; 3]], vertex_count: usize, max_depth: usize) -> usize {
    let mut depth = 0;
    let mut current = triangles.to_vec();
    let mut vertices = vertex_count;
    while depth < max_depth {
        let Some(coarse) = unsplit(&current, vertices) else {
            break;
        };
        depth += 1;
        vertices = coarse.fine_vertex.len();
        current = coarse.triangles;
    }
    depth
}

const UNKNOWN: u8 = 0;
const EVEN: u8 = 1;
const ODD: u8 = 2;

/// The coarse level of `triangles` if they are exactly the 1-to-4 split of some mesh (up to
/// vertex numbering and the order of triangles), else `None`.
pub fn unsplit(triangles: &[[u32; 3]], vertex_count: usize) -> Option<Unsplit> {
    if triangles.is_empty()
        || !triangles.len().is_multiple_of(4)
        || triangles
            .iter()
            .flatten()
            .any(|&v| v as usize >= vertex_count)
    {
        return None;
    }
    let rings = Rings::new(triangles, vertex_count)?;
    let mut colour = vec![UNKNOWN; vertex_count];
    for start in 0..vertex_count {
        if colour[start] != UNKNOWN || rings.ring(start).is_empty() {
            continue;
        }
        // A vertex whose valence no odd vertex can have is even; in a piece without one (a
        // torus of valence-6 vertices) the evens are one of four cosets: `start` itself or the
        // far end of one of its first three ring directions.
        let piece_start = (start..vertex_count)
            .find(|&v| colour[v] == UNKNOWN && rings.same_piece(start, v) && rings.must_be_even(v));
        let seeds: Vec<u32> = match piece_start {
            Some(v) => vec![v as u32],
            None => std::iter::once(start as u32)
                .chain(rings.ring(start).iter().take(3).copied())
                .collect(),
        };
        let mut coloured = None;
        for seed in seeds {
            let mut trial = colour.clone();
            if propagate(&rings, &mut trial, seed) {
                coloured = Some(trial);
                break;
            }
        }
        colour = coloured?;
    }
    coarse_level(triangles, &rings, &colour)
}

/// Colours the piece of `seed` from `seed` being even; false on a contradiction.
fn propagate(rings: &Rings, colour: &mut [u8], seed: u32) -> bool {
    let mut queue = VecDeque::from([seed]);
    if colour[seed as usize] == ODD {
        return false;
    }
    colour[seed as usize] = EVEN;
    while let Some(even) = queue.pop_front() {
        for &odd in rings.ring(even as usize) {
            match colour[odd as usize] {
                EVEN => return false,
                ODD => {}
                _ => colour[odd as usize] = ODD,
            }
            let Some(other) = rings.across(odd as usize, even) else {
                return false;
            };
            match colour[other as usize] {
                ODD => return false,
                EVEN => {}
                _ => {
                    colour[other as usize] = EVEN;
                    queue.push_back(other);
                }
            }
        }
    }
    true
}

/// Coarse triangles from the corner triangles, checked by splitting them again.
fn coarse_level(triangles: &[[u32; 3]], rings: &Rings, colour: &[u8]) -> Option<Unsplit> {
    let fine_vertex: Vec<u32> = (0..colour.len() as u32)
        .filter(|&v| colour[v as usize] == EVEN)
        .collect();
    let mut coarse_index = vec![u32::MAX; colour.len()];
    for (i, &v) in fine_vertex.iter().enumerate() {
        coarse_index[v as usize] = i as u32;
    }
    let mut coarse = Vec::with_capacity(triangles.len() / 4);
    for tri in triangles {
        let evens = tri.iter().filter(|&&v| colour[v as usize] == EVEN).count();
        match evens {
            0 => continue,
            1 => {}
            _ => return None,
        }
        let r = tri.iter().position(|&v| colour[v as usize] == EVEN)?;
        let [e, o1, o2] = [tri[r], tri[(r + 1) % 3], tri[(r + 2) % 3]];
        let b = rings.across(o1 as usize, e)?;
        let c = rings.across(o2 as usize, e)?;
        coarse.push(canonical([e, b, c].map(|v| coarse_index[v as usize])));
    }
    coarse.sort_unstable();
    coarse.dedup();
    if coarse.iter().flatten().any(|&v| v == u32::MAX) {
        return None;
    }
    // Splitting the candidate must give back the input exactly.
    let s = split(&coarse, fine_vertex.len());
    if s.fine_vertices() != colour.len() {
        return None;
    }
    let mut fine_of_split = vec![u32::MAX; s.fine_vertices()];
    for (i, &v) in fine_vertex.iter().enumerate() {
        fine_of_split[i] = v;
    }
    for v in 0..colour.len() {
        if colour[v] == ODD {
            let ring = rings.ring(v);
            let ends: Vec<u32> = ring
                .iter()
                .filter(|&&w| colour[w as usize] == EVEN)
                .map(|&w| coarse_index[w as usize])
                .collect();
            let [a, b] = ends[..] else { return None };
            let k = s.edge_index(a, b)?;
            let slot = &mut fine_of_split[s.odd_vertex(k) as usize];
            if *slot != u32::MAX {
                return None;
            }
            *slot = v as u32;
        }
    }
    let mut rebuilt: Vec<[u32; 3]> = s
        .triangles
        .iter()
        .map(|t| canonical(t.map(|v| fine_of_split[v as usize])))
        .collect();
    let mut given: Vec<[u32; 3]> = triangles.iter().map(|&t| canonical(t)).collect();
    rebuilt.sort_unstable();
    given.sort_unstable();
    (rebuilt == given).then_some(Unsplit {
        triangles: coarse,
        fine_vertex,
    })
}

/// The rotation of `t` that starts at its smallest index (orientation kept).
fn canonical(t: [u32; 3]) -> [u32; 3] {
    let r = (0..3).min_by_key(|&i| t[i]).unwrap_or(0);
    [t[r], t[(r + 1) % 3], t[(r + 2) % 3]]
}

/// Ordered one-rings: for an interior vertex its neighbours around it, for a boundary vertex
/// its fan from one boundary neighbour to the other.
struct Rings {
    start: Vec<usize>,
    ring: Vec<u32>,
    /// Whether the ring closes (interior vertex).
    closed: Vec<bool>,
    /// Connected piece of each vertex.
    piece: Vec<u32>,
}

impl Rings {
    /// `None` when a ring is not a single fan or cycle (non-manifold).
    fn new(triangles: &[[u32; 3]], vertex_count: usize) -> Option<Self> {
        // Per vertex, the (next, previous) pairs of its triangles.
        let mut count = vec![0usize; vertex_count + 1];
        for t in triangles {
            for &v in t {
                count[v as usize + 1] += 1;
            }
        }
        for v in 0..vertex_count {
            count[v + 1] += count[v];
        }
        let mut pairs = vec![(0u32, 0u32); count[vertex_count]];
        let mut cursor = count.clone();
        for t in triangles {
            for k in 0..3 {
                let v = t[k] as usize;
                pairs[cursor[v]] = (t[(k + 1) % 3], t[(k + 2) % 3]);
                cursor[v] += 1;
            }
        }
        let mut start = vec![0usize; vertex_count + 1];
        let mut ring = Vec::with_capacity(pairs.len() + vertex_count);
        let mut closed = vec![false; vertex_count];
        for v in 0..vertex_count {
            let fan = &mut pairs[count[v]..count[v + 1]];
            fan.sort_unstable();
            start[v] = ring.len();
            if !fan.is_empty() {
                let (cycle, order) = chain(fan)?;
                closed[v] = cycle;
                ring.extend(order);
            }
            start[v + 1] = ring.len();
        }
        // Pieces by flood fill over the rings.
        let mut piece = vec![u32::MAX; vertex_count];
        let mut next_piece = 0;
        for v in 0..vertex_count {
            if piece[v] != u32::MAX {
                continue;
            }
            let mut stack = vec![v as u32];
            piece[v] = next_piece;
            while let Some(w) = stack.pop() {
                for &x in &ring[start[w as usize]..start[w as usize + 1]] {
                    if piece[x as usize] == u32::MAX {
                        piece[x as usize] = next_piece;
                        stack.push(x);
                    }
                }
            }
            next_piece += 1;
        }
        Some(Self {
            start,
            ring,
            closed,
            piece,
        })
    }

    fn ring(&self, v: usize) -> &[u32] {
        &self.ring[self.start[v]..self.start[v + 1]]
    }

    fn same_piece(&self, a: usize, b: usize) -> bool {
        self.piece[a] == self.piece[b]
    }

    /// An odd vertex has valence 6 inside and 4 on the boundary; any other vertex is even.
    fn must_be_even(&self, v: usize) -> bool {
        let n = self.ring(v).len();
        if self.closed[v] { n != 6 } else { n != 4 }
    }

    /// For an odd vertex `odd` with even neighbour `even`, the coarse edge's other end: the
    /// ring vertex opposite `even` (interior), or the other end of the fan (boundary).
    fn across(&self, odd: usize, even: u32) -> Option<u32> {
        let ring = self.ring(odd);
        let i = ring.iter().position(|&w| w == even)?;
        if self.closed[odd] {
            (ring.len() == 6).then(|| ring[(i + 3) % 6])
        } else {
            // The fan of a boundary odd vertex is [even, odd, odd, even].
            (ring.len() == 4 && (i == 0 || i == 3)).then(|| ring[3 - i])
        }
    }
}

/// Orders a vertex's (next, previous) pairs into one fan or cycle of neighbours; `None` if
/// they do not form exactly one.
fn chain(fan: &[(u32, u32)]) -> Option<(bool, Vec<u32>)> {
    let find = |x: u32| fan.binary_search_by(|p| p.0.cmp(&x)).ok().map(|i| fan[i].1);
    // The fan starts where a `next` is no triangle's `previous`.
    let open_start = fan
        .iter()
        .map(|p| p.0)
        .find(|&x| !fan.iter().any(|p| p.1 == x));
    let first = open_start.unwrap_or(fan[0].0);
    let mut order = vec![first];
    let mut at = first;
    for _ in 0..fan.len() {
        let Some(next) = find(at) else { break };
        if next == first {
            break;
        }
        order.push(next);
        at = next;
    }
    let cycle = open_start.is_none();
    let expected = if cycle { fan.len() } else { fan.len() + 1 };
    (order.len() == expected).then_some((cycle, order))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::multires::test_meshes::{fan, grid, irregular_closed, octahedron};

    fn sorted_canonical(t: &[[u32; 3]]) -> Vec<[u32; 3]> {
        let mut v: Vec<[u32; 3]> = t.iter().map(|&t| canonical(t)).collect();
        v.sort_unstable();
        v
    }

    /// Closed torus grid (every vertex valence 6): no vertex marks the evens.
    fn torus_grid(nu: u32, nv: u32) -> Vec<[u32; 3]> {
        let id = |i: u32, j: u32| (i % nu) + nu * (j % nv);
        let mut t = Vec::new();
        for j in 0..nv {
            for i in 0..nu {
                let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
                t.extend([[a, b, c], [a, c, d]]);
            }
        }
        t
    }

    fn assert_recovers(coarse: &[[u32; 3]], vertices: usize) {
        let s = split(coarse, vertices);
        let found = unsplit(&s.triangles, s.fine_vertices()).expect("a split mesh un-splits");
        // Even vertices keep their indices in a split, so the coarse level comes back as is.
        assert_eq!(found.fine_vertex, (0..vertices as u32).collect::<Vec<_>>());
        assert_eq!(sorted_canonical(&found.triangles), sorted_canonical(coarse));
    }

    #[test]
    fn split_meshes_come_back_exactly() {
        let m = irregular_closed();
        assert_recovers(&m.triangles, m.positions.len());
        let m = octahedron();
        assert_recovers(&m.triangles, m.positions.len());
        // Open, with boundary odd vertices of valence 4.
        let m = grid(4, 3, false);
        assert_recovers(&m.triangles, m.positions.len());
        let m = fan(7);
        assert_recovers(&m.triangles, m.positions.len());
    }

    #[test]
    fn all_valence_six_torus_finds_its_coset() {
        let coarse = torus_grid(6, 5);
        let s = split(&coarse, 30);
        let found = unsplit(&s.triangles, s.fine_vertices()).expect("torus un-splits");
        assert_eq!(found.fine_vertex.len(), 30);
        // Whichever coset was found, splitting it again rebuilds the input (checked inside);
        // and it has the coarse counts.
        assert_eq!(found.triangles.len(), coarse.len());
    }

    #[test]
    fn renumbered_and_shuffled_split_is_still_recognised() {
        let m = irregular_closed();
        let s = split(&m.triangles, m.positions.len());
        let n = s.fine_vertices() as u32;
        // A fixed permutation of the vertices and a rotation of the triangle list.
        let perm = |v: u32| (v * 7919 + 13) % n;
        assert_eq!(
            (0..n)
                .map(perm)
                .collect::<std::collections::BTreeSet<_>>()
                .len(),
            n as usize,
            "7919 must be coprime with the vertex count"
        );
        let mut fine: Vec<[u32; 3]> = s.triangles.iter().map(|t| t.map(perm)).collect();
        fine.rotate_left(17);
        let found = unsplit(&fine, n as usize).expect("renumbered split");
        assert_eq!(found.triangles.len(), m.triangles.len());
        let evens: Vec<u32> = (0..m.positions.len() as u32).map(perm).collect();
        let mut sorted = evens.clone();
        sorted.sort_unstable();
        assert_eq!(found.fine_vertex, sorted);
    }

    #[test]
    fn depth_counts_levels_and_irregular_meshes_have_none() {
        let m = irregular_closed();
        assert_eq!(subdivision_depth(&m.triangles, m.positions.len(), 8), 0);
        let s1 = split(&m.triangles, m.positions.len());
        let s2 = split(&s1.triangles, s1.fine_vertices());
        assert_eq!(subdivision_depth(&s2.triangles, s2.fine_vertices(), 8), 2);
        assert_eq!(subdivision_depth(&s2.triangles, s2.fine_vertices(), 1), 1);
    }

    #[test]
    fn one_flipped_edge_breaks_subdivision_connectivity() {
        let m = irregular_closed();
        let s = split(&m.triangles, m.positions.len());
        // Flip the shared edge of a corner triangle and the centre triangle of coarse
        // triangle 0: [a, ab, ca] and [ab, bc, ca] share ab–ca.
        let mut t = s.triangles.clone();
        let [a, ab, ca] = t[0];
        let [_, bc, _] = t[3];
        t[0] = [a, ab, bc];
        t[3] = [a, bc, ca];
        assert!(unsplit(&t, s.fine_vertices()).is_none());
        assert!(unsplit(&[], 0).is_none());
        assert!(unsplit(&[[0, 1, 2]], 2).is_none());
    }
}
