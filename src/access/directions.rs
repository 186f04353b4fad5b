//! Near-uniform direction sets on the unit sphere and visibility maps over them (DESIGN.md §3.5;
//! Chen & Woo's visibility maps, discretised as in seed 004 ch. 5 step 4).
//!
//! The sets are the vertices of a subdivided icosahedron: each step splits every triangle 1-to-4
//! and pushes the edge midpoints onto the sphere, giving 12, 42, 162, 642, 2562, 10242
//! directions (10·4ᵏ + 2). The levels are nested by index: level k's directions are the first
//! `count(k)` directions of every finer level, and each direction added at level k records the
//! two level-(k − 1) directions whose edge it split (its parents). That nesting is what lets a
//! map be computed coarse-to-fine (`super::visibility`): a new direction whose parents agree,
//! away from the coarse map's border, inherits their answer.

use std::collections::HashMap;

use crate::geom::Vector3;

/// Direction counts of the icosphere levels 0..=[`MAX_LEVEL`].
pub const LEVEL_COUNTS: [usize; 6] = [12, 42, 162, 642, 2562, 10242];
/// The finest level built.
pub const MAX_LEVEL: usize = LEVEL_COUNTS.len() - 1;

/// A direction count that is not one of [`LEVEL_COUNTS`].
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{count} directions: the direction sets have 12, 42, 162, 642, 2562 or 10242")]
pub struct BadDirectionCount {
    pub count: usize,
}

/// The level with `count` directions.
pub fn level_for_count(count: usize) -> Result<usize, BadDirectionCount> {
    LEVEL_COUNTS
        .iter()
        .position(|&c| c == count)
        .ok_or(BadDirectionCount { count })
}

/// Subdivided-icosahedron directions, levels 0..=`levels()-1`, nested by index.
#[derive(Clone, Debug)]
pub struct DirectionSet {
    directions: Vec<Vector3>,
    /// For direction `i ≥ 12`: the two directions of the level below whose edge it splits.
    parents: Vec<[u32; 2]>,
    /// For direction `i ≥ 12`: the two directions of the level below opposite that edge (the
    /// third corners of the two triangles the edge bounds).
    opposite: Vec<[u32; 2]>,
    /// Per level, per direction of that level: its neighbours on that level's sphere mesh,
    /// sorted by index.
    neighbours: Vec<Vec<Vec<u32>>>,
}

impl DirectionSet {
    /// The sets up to and including `level` (0..=[`MAX_LEVEL`]; larger values are clamped).
    pub fn new(level: usize) -> Self {
        let level = level.min(MAX_LEVEL);
        let phi = (1.0 + 5.0_f64.sqrt()) / 2.0;
        let mut directions: Vec<Vector3> = [
            (-1.0, phi, 0.0),
            (1.0, phi, 0.0),
            (-1.0, -phi, 0.0),
            (1.0, -phi, 0.0),
            (0.0, -1.0, phi),
            (0.0, 1.0, phi),
            (0.0, -1.0, -phi),
            (0.0, 1.0, -phi),
            (phi, 0.0, -1.0),
            (phi, 0.0, 1.0),
            (-phi, 0.0, -1.0),
            (-phi, 0.0, 1.0),
        ]
        .iter()
        .map(|&(x, y, z)| Vector3::new(x, y, z).normalize())
        .collect();
        let mut faces: Vec<[u32; 3]> = vec![
            [0, 11, 5],
            [0, 5, 1],
            [0, 1, 7],
            [0, 7, 10],
            [0, 10, 11],
            [1, 5, 9],
            [5, 11, 4],
            [11, 10, 2],
            [10, 7, 6],
            [7, 1, 8],
            [3, 9, 4],
            [3, 4, 2],
            [3, 2, 6],
            [3, 6, 8],
            [3, 8, 9],
            [4, 9, 5],
            [2, 4, 11],
            [6, 2, 10],
            [8, 6, 7],
            [9, 8, 1],
        ];
        let mut parents = Vec::new();
        let mut opposite: Vec<[u32; 2]> = Vec::new();
        let mut neighbours = vec![neighbours_of(&faces, directions.len())];
        for _ in 0..level {
            let mut midpoint: HashMap<(u32, u32), u32> = HashMap::new();
            let mut split = |a: u32, b: u32, directions: &mut Vec<Vector3>| -> u32 {
                let key = (a.min(b), a.max(b));
                *midpoint.entry(key).or_insert_with(|| {
                    let m = (directions[a as usize] + directions[b as usize]).normalize();
                    directions.push(m);
                    parents.push([key.0, key.1]);
                    (directions.len() - 1) as u32
                })
            };
            let mut finer = Vec::with_capacity(faces.len() * 4);
            let mut across = Vec::with_capacity(faces.len() * 3);
            for &[a, b, c] in &faces {
                let ab = split(a, b, &mut directions);
                let bc = split(b, c, &mut directions);
                let ca = split(c, a, &mut directions);
                finer.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
                across.extend([(ab, c), (bc, a), (ca, b)]);
            }
            // Each edge bounds two triangles: its midpoint has one opposite corner in each.
            let first = LEVEL_COUNTS[0] + opposite.len();
            opposite.resize(directions.len() - LEVEL_COUNTS[0], [u32::MAX; 2]);
            for (mid, corner) in across {
                let slot = &mut opposite[mid as usize - LEVEL_COUNTS[0]];
                if slot[0] == u32::MAX {
                    slot[0] = corner;
                } else {
                    slot[1] = corner;
                }
            }
            debug_assert!(
                opposite[first - LEVEL_COUNTS[0]..]
                    .iter()
                    .all(|o| o[1] != u32::MAX)
            );
            faces = finer;
            neighbours.push(neighbours_of(&faces, directions.len()));
        }
        Self {
            directions,
            parents,
            opposite,
            neighbours,
        }
    }

    /// The sets up to the level with `count` directions.
    pub fn with_count(count: usize) -> Result<Self, BadDirectionCount> {
        Ok(Self::new(level_for_count(count)?))
    }

    /// Number of levels built (the finest is `levels() - 1`).
    pub fn levels(&self) -> usize {
        self.neighbours.len()
    }

    /// Number of directions of `level` (the first that many of [`Self::directions`]).
    pub fn count(&self, level: usize) -> usize {
        LEVEL_COUNTS[level.min(self.levels() - 1)]
    }

    /// All directions of the finest level; level k's are the first `count(k)`.
    pub fn directions(&self) -> &[Vector3] {
        &self.directions
    }

    /// The two parents (directions of level k − 1) of direction `i`, added at level k ≥ 1;
    /// `None` for the 12 icosahedron vertices.
    pub fn parents(&self, i: usize) -> Option<[u32; 2]> {
        i.checked_sub(LEVEL_COUNTS[0])
            .and_then(|k| self.parents.get(k).copied())
    }

    /// The two directions of level k − 1 opposite the edge direction `i` (added at level
    /// k ≥ 1) splits: with its parents, the corners of the two coarse triangles it lies in.
    /// `None` for the 12 icosahedron vertices.
    pub fn opposite(&self, i: usize) -> Option<[u32; 2]> {
        i.checked_sub(LEVEL_COUNTS[0])
            .and_then(|k| self.opposite.get(k).copied())
    }

    /// Neighbours of direction `i` on the sphere mesh of `level` (`i < count(level)`).
    pub fn neighbours(&self, level: usize, i: usize) -> &[u32] {
        self.neighbours
            .get(level)
            .and_then(|n| n.get(i))
            .map_or(&[], Vec::as_slice)
    }

    /// The direction of `level` nearest to `d` (any non-zero vector), by a greedy walk down the
    /// levels: the icosphere meshes are Delaunay on the sphere, so a walk that always moves to a
    /// nearer neighbour ends at the nearest direction.
    pub fn nearest(&self, level: usize, d: &Vector3) -> usize {
        let level = level.min(self.levels() - 1);
        let closeness = |i: usize| self.directions[i].dot(d);
        let mut best = (0..LEVEL_COUNTS[0])
            .max_by(|&a, &b| closeness(a).total_cmp(&closeness(b)))
            .unwrap_or(0);
        for l in 0..=level {
            // Coming from level l − 1, the nearest of level l is near the walk's current point.
            loop {
                let next = self
                    .neighbours(l, best)
                    .iter()
                    .map(|&j| j as usize)
                    .max_by(|&a, &b| closeness(a).total_cmp(&closeness(b)));
                match next {
                    Some(j) if closeness(j) > closeness(best) => best = j,
                    _ => break,
                }
            }
        }
        best
    }
}

/// Sorted, de-duplicated vertex neighbours of a closed triangle mesh with `n` vertices.
fn neighbours_of(faces: &[[u32; 3]], n: usize) -> Vec<Vec<u32>> {
    let mut out = vec![Vec::with_capacity(6); n];
    for f in faces {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            out[a as usize].push(b);
            out[b as usize].push(a);
        }
    }
    for list in &mut out {
        list.sort_unstable();
        list.dedup();
    }
    out
}

/// A set of directions (indices into a [`DirectionSet`] level) as a bitset: a Chen & Woo
/// visibility map.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct VisibilityMap {
    len: usize,
    words: Vec<u64>,
}

impl VisibilityMap {
    /// The empty map over `len` directions.
    pub fn empty(len: usize) -> Self {
        Self {
            len,
            words: vec![0; len.div_ceil(64)],
        }
    }

    /// The map holding every one of `len` directions.
    pub fn full(len: usize) -> Self {
        let mut m = Self {
            len,
            words: vec![u64::MAX; len.div_ceil(64)],
        };
        m.clear_tail();
        m
    }

    /// Number of directions the map is over.
    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Whether direction `i` is in the map (false beyond `len`).
    pub fn contains(&self, i: usize) -> bool {
        i < self.len && self.words[i / 64] & (1 << (i % 64)) != 0
    }

    /// Puts direction `i` in the map or takes it out; indices beyond `len` are ignored.
    pub fn set(&mut self, i: usize, value: bool) {
        if i >= self.len {
            return;
        }
        let bit = 1u64 << (i % 64);
        if value {
            self.words[i / 64] |= bit;
        } else {
            self.words[i / 64] &= !bit;
        }
    }

    /// Number of directions in the map.
    pub fn count(&self) -> usize {
        self.words.iter().map(|w| w.count_ones() as usize).sum()
    }

    /// Indices of the directions in the map, ascending.
    pub fn iter(&self) -> impl Iterator<Item = usize> + '_ {
        (0..self.len).filter(|&i| self.contains(i))
    }

    /// Directions in both maps: the map of a region is the intersection of its points' maps.
    /// Maps over different numbers of directions intersect over the shorter one's.
    pub fn intersection(&self, other: &Self) -> Self {
        self.combine(other, |a, b| a & b)
    }

    /// Directions in either map.
    pub fn union(&self, other: &Self) -> Self {
        self.combine(other, |a, b| a | b)
    }

    /// Number of directions (of the first `min(len)`) on which the two maps agree.
    pub fn agreement(&self, other: &Self) -> usize {
        let len = self.len.min(other.len);
        let differ: usize = self
            .combine(other, |a, b| a ^ b)
            .words
            .iter()
            .map(|w| w.count_ones() as usize)
            .sum();
        len - differ
    }

    /// The intersection of every map in `maps` (`None` when there are none).
    pub fn region<'a>(maps: impl IntoIterator<Item = &'a VisibilityMap>) -> Option<Self> {
        maps.into_iter()
            .fold(None, |acc: Option<Self>, m| match acc {
                None => Some(m.clone()),
                Some(a) => Some(a.intersection(m)),
            })
    }

    fn combine(&self, other: &Self, op: impl Fn(u64, u64) -> u64) -> Self {
        let len = self.len.min(other.len);
        let mut m = Self {
            len,
            words: self
                .words
                .iter()
                .zip(&other.words)
                .take(len.div_ceil(64))
                .map(|(&a, &b)| op(a, b))
                .collect(),
        };
        m.clear_tail();
        m
    }

    fn clear_tail(&mut self) {
        let used = self.len % 64;
        if used != 0
            && let Some(last) = self.words.last_mut()
        {
            *last &= (1u64 << used) - 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::angle_between;

    #[test]
    fn counts_unit_length_and_nesting() {
        let set = DirectionSet::new(MAX_LEVEL);
        assert_eq!(set.levels(), 6);
        assert_eq!(set.directions().len(), 10242);
        for (level, &count) in LEVEL_COUNTS.iter().enumerate() {
            assert_eq!(set.count(level), count);
            assert_eq!(level_for_count(count), Ok(level));
            // A coarser set built alone is the prefix of the finer one.
            let alone = DirectionSet::new(level);
            assert_eq!(alone.directions(), &set.directions()[..count]);
        }
        assert!(level_for_count(100).is_err());
        for d in set.directions() {
            assert!((d.norm() - 1.0).abs() < 1e-12);
        }
        // Every direction is distinct.
        let mut keys: Vec<_> = set
            .directions()
            .iter()
            .map(|d| [d.x, d.y, d.z].map(|c| (c * 1e9).round() as i64))
            .collect();
        keys.sort_unstable();
        keys.dedup();
        assert_eq!(keys.len(), 10242);
    }

    #[test]
    fn children_are_midpoints_of_neighbouring_parents() {
        let set = DirectionSet::new(4);
        for level in 1..set.levels() {
            for i in set.count(level - 1)..set.count(level) {
                let [a, b] = set.parents(i).unwrap();
                assert!((a as usize) < set.count(level - 1) && (b as usize) < set.count(level - 1));
                assert!(set.neighbours(level - 1, a as usize).contains(&b));
                let mid = (set.directions()[a as usize] + set.directions()[b as usize]).normalize();
                assert!((mid - set.directions()[i]).norm() < 1e-12);
                // The opposite corners are the parents' two common neighbours.
                let [c, d] = set.opposite(i).unwrap();
                for o in [c, d] {
                    assert!(set.neighbours(level - 1, a as usize).contains(&o));
                    assert!(set.neighbours(level - 1, b as usize).contains(&o));
                }
                assert_ne!(c, d);
                // On its own level, the child neighbours both parents.
                assert!(set.neighbours(level, i).contains(&a));
                assert!(set.neighbours(level, i).contains(&b));
            }
            // Valence 5 at the 12 icosahedron vertices, 6 elsewhere; symmetric.
            for i in 0..set.count(level) {
                let n = set.neighbours(level, i);
                assert_eq!(n.len(), if i < 12 { 5 } else { 6 }, "level {level} dir {i}");
                for &j in n {
                    assert!(set.neighbours(level, j as usize).contains(&(i as u32)));
                }
            }
        }
        assert_eq!(set.parents(5), None);
        assert_eq!(set.opposite(11), None);
    }

    #[test]
    fn near_uniform_nearest_neighbour_angles() {
        let set = DirectionSet::new(MAX_LEVEL);
        for level in 0..set.levels() {
            let n = set.count(level);
            let nearest: Vec<f64> = (0..n)
                .map(|i| {
                    set.neighbours(level, i)
                        .iter()
                        .map(|&j| {
                            angle_between(&set.directions()[i], &set.directions()[j as usize])
                        })
                        .fold(f64::INFINITY, f64::min)
                })
                .collect();
            let max = nearest.iter().copied().fold(0.0, f64::max);
            let min = nearest.iter().copied().fold(f64::INFINITY, f64::min);
            assert!(max / min < 1.3, "level {level}: ratio {}", max / min);
            // Spacing halves with each level (sphere area / count).
            let expected = (4.0 * std::f64::consts::PI / n as f64).sqrt();
            assert!(
                min > 0.8 * expected && max < 1.4 * expected,
                "level {level}"
            );
        }
    }

    #[test]
    fn nearest_lookup_matches_brute_force() {
        let set = DirectionSet::new(4);
        let mut random = crate::geom::SeededRandom::new(12345);
        let mut next = || random.range(-1.0, 1.0);
        for _ in 0..500 {
            let d = Vector3::new(next(), next(), next());
            if d.norm() < 1e-3 {
                continue;
            }
            for level in 0..set.levels() {
                let got = set.nearest(level, &d);
                let want = (0..set.count(level))
                    .max_by(|&a, &b| {
                        set.directions()[a]
                            .dot(&d)
                            .total_cmp(&set.directions()[b].dot(&d))
                    })
                    .unwrap();
                let (g, w) = (
                    set.directions()[got].dot(&d),
                    set.directions()[want].dot(&d),
                );
                assert!(got < set.count(level));
                assert!((g - w).abs() < 1e-12, "level {level}: {got} vs {want}");
            }
        }
        // Exactly on a direction: that direction.
        assert_eq!(set.nearest(4, &set.directions()[777]), 777);
    }

    #[test]
    fn bitset_algebra() {
        let n = 162;
        let mut a = VisibilityMap::empty(n);
        let mut b = VisibilityMap::empty(n);
        for i in 0..n {
            a.set(i, i % 2 == 0);
            b.set(i, i % 3 == 0);
        }
        assert_eq!(a.count(), 81);
        assert_eq!(b.count(), 54);
        let both = a.intersection(&b);
        assert_eq!(both.count(), 27);
        assert!(both.iter().all(|i| i % 6 == 0));
        assert_eq!(a.union(&b).count(), 81 + 54 - 27);
        // Agreement: equal where both hold or both lack.
        let agree = (0..n).filter(|&i| (i % 2 == 0) == (i % 3 == 0)).count();
        assert_eq!(a.agreement(&b), agree);
        assert_eq!(a.agreement(&a), n);
        let full = VisibilityMap::full(n);
        assert_eq!(full.count(), n);
        assert_eq!(full.intersection(&a), a);
        assert!(!full.contains(n) && !full.contains(n + 100));
        let mut c = full.clone();
        c.set(n + 3, true);
        assert_eq!(c, full);
        c.set(5, false);
        assert_eq!(c.count(), n - 1);
        let region = VisibilityMap::region([&a, &b, &full]).unwrap();
        assert_eq!(region, both);
        assert!(VisibilityMap::region(std::iter::empty()).is_none());
    }
}
