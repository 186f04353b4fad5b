//! Invariant checker for the subdivision hierarchy: is a fine level exactly the 1-to-4 split
//! of a coarse one, with the numbering of docs/multires-conventions.md? Called by tests (and meant
//! for fuzzers and debug assertions in the later stages). Written independently of
//! [`crate::multires::split()`]: it reads the numbering back out of the fine triangles.

/// Checks that `fine_triangles` is exactly the 1-to-4 split of `coarse_triangles` (a level with
/// `coarse_vertices` vertices):
/// * 4 fine triangles per coarse one, in the order `[a, ab, ca]`, `[ab, b, bc]`, `[ca, bc, c]`,
///   `[ab, bc, ca]`;
/// * every odd vertex lies on exactly one coarse edge, every coarse edge has exactly one odd
///   vertex, and the odd vertex of sorted coarse edge k is `coarse_vertices + k`;
/// * neighbours in the fine mesh: an odd vertex on coarse edge `{a, b}` is adjacent to exactly
///   the evens `a, b` and to 2 odd vertices per coarse triangle on the edge; an even vertex is
///   adjacent only to odd vertices, as many as its coarse valence.
///
/// Returns a message naming the first violation. O(T log T); never panics.
pub fn check_split(
    coarse_triangles: &[[u32; 3]],
    coarse_vertices: usize,
    fine_triangles: &[[u32; 3]],
) -> Result<(), String> {
    let nc = coarse_vertices;
    if fine_triangles.len() != 4 * coarse_triangles.len() {
        return Err(format!(
            "{} fine triangles for {} coarse ones (expected {})",
            fine_triangles.len(),
            coarse_triangles.len(),
            4 * coarse_triangles.len()
        ));
    }

    // 1. The 4-triangle pattern; collect (coarse edge, odd vertex) pairs.
    let mut pairs: Vec<([u32; 2], u32)> = Vec::with_capacity(3 * coarse_triangles.len());
    for (t, (&[a, b, c], fine)) in coarse_triangles
        .iter()
        .zip(fine_triangles.chunks_exact(4))
        .enumerate()
    {
        if let Some(i) = [a, b, c].into_iter().find(|&i| i as usize >= nc) {
            return Err(format!(
                "coarse triangle {t} refers to vertex {i} >= {nc} coarse vertices"
            ));
        }
        if a == b || b == c || c == a {
            return Err(format!(
                "coarse triangle {t} {:?} repeats a vertex",
                [a, b, c]
            ));
        }
        let [ab, bc, ca] = fine[3];
        let expected = [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]];
        for (i, (got, want)) in fine.iter().zip(&expected).enumerate() {
            if got != want {
                return Err(format!(
                    "fine triangle {} is {got:?}, expected {want:?} (child {i} of coarse \
                     triangle {t} {:?}, odd vertices read from child 3)",
                    4 * t + i,
                    [a, b, c]
                ));
            }
        }
        for (m, x, y) in [(ab, a, b), (bc, b, c), (ca, c, a)] {
            if (m as usize) < nc {
                return Err(format!(
                    "odd vertex of coarse edge {:?} (triangle {t}) is {m}, an even index",
                    [x.min(y), x.max(y)]
                ));
            }
            pairs.push(([x.min(y), x.max(y)], m));
        }
    }

    // 2. Each odd vertex on exactly one coarse edge.
    let mut by_odd: Vec<(u32, [u32; 2])> = pairs.iter().map(|&(e, m)| (m, e)).collect();
    by_odd.sort_unstable();
    by_odd.dedup();
    if let Some(w) = by_odd.windows(2).find(|w| w[0].0 == w[1].0) {
        return Err(format!(
            "odd vertex {} lies on two coarse edges {:?} and {:?}",
            w[0].0, w[0].1, w[1].1
        ));
    }

    // 3. Each coarse edge has one odd vertex, numbered coarse_vertices + rank.
    pairs.sort_unstable();
    pairs.dedup();
    if let Some(w) = pairs.windows(2).find(|w| w[0].0 == w[1].0) {
        return Err(format!(
            "coarse edge {:?} has two odd vertices {} and {}",
            w[0].0, w[0].1, w[1].1
        ));
    }
    for (k, &(e, m)) in pairs.iter().enumerate() {
        if m as usize != nc + k {
            return Err(format!(
                "odd vertex of coarse edge #{k} {e:?} is {m}, expected {}",
                nc + k
            ));
        }
    }

    // 4. Neighbours in the fine mesh (from the fine triangles alone).
    let edge_count = pairs.len();
    let mut faces_on_edge = vec![0usize; edge_count];
    let mut coarse_valence = vec![0usize; nc];
    {
        let mut sides: Vec<[u32; 2]> = coarse_triangles
            .iter()
            .flat_map(|&[a, b, c]| [[a, b], [b, c], [c, a]])
            .map(|[x, y]| [x.min(y), x.max(y)])
            .collect();
        sides.sort_unstable();
        let mut k = 0;
        for (i, s) in sides.iter().enumerate() {
            if i > 0 && sides[i - 1] != *s {
                k += 1;
            }
            if i == 0 || sides[i - 1] != *s {
                coarse_valence[s[0] as usize] += 1;
                coarse_valence[s[1] as usize] += 1;
            }
            faces_on_edge[k] += 1;
        }
    }
    let mut fine_edges: Vec<[u32; 2]> = fine_triangles
        .iter()
        .flat_map(|&[a, b, c]| [[a, b], [b, c], [c, a]])
        .map(|[x, y]| [x.min(y), x.max(y)])
        .collect();
    fine_edges.sort_unstable();
    fine_edges.dedup();
    let fine_count = nc + edge_count;
    let mut even_nbrs: Vec<Vec<u32>> = vec![Vec::new(); edge_count];
    let mut odd_nbrs = vec![0usize; fine_count];
    for &[x, y] in &fine_edges {
        if y as usize >= fine_count {
            return Err(format!(
                "fine edge {:?} refers to vertex {y} >= {fine_count} fine vertices",
                [x, y]
            ));
        }
        // x <= y, so y even means both are even.
        if (y as usize) < nc {
            return Err(format!("fine edge {:?} joins two even vertices", [x, y]));
        }
        if (x as usize) < nc {
            even_nbrs[y as usize - nc].push(x);
        }
        odd_nbrs[x as usize] += 1;
        if (x as usize) >= nc {
            odd_nbrs[y as usize] += 1;
        }
    }
    for (k, &(e, m)) in pairs.iter().enumerate() {
        let mut evens = even_nbrs[k].clone();
        evens.sort_unstable();
        if evens != e {
            return Err(format!(
                "odd vertex {m} of coarse edge {e:?} has even neighbours {evens:?}"
            ));
        }
        let want = 2 * faces_on_edge[k];
        if odd_nbrs[m as usize] != want {
            return Err(format!(
                "odd vertex {m} of coarse edge {e:?} has {} odd neighbours, expected {want}",
                odd_nbrs[m as usize]
            ));
        }
    }
    for v in 0..nc {
        if odd_nbrs[v] != coarse_valence[v] {
            return Err(format!(
                "even vertex {v} has {} fine neighbours, coarse valence {}",
                odd_nbrs[v], coarse_valence[v]
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::multires::{Creases, loop_step, split, test_meshes};

    fn levels() -> Vec<(crate::mesh::Mesh, &'static str)> {
        vec![
            (test_meshes::octahedron(), "octahedron"),
            (test_meshes::irregular_closed(), "irregular"),
            (test_meshes::grid(4, 3, false), "grid"),
            (test_meshes::grid(3, 3, true), "regular grid"),
            (test_meshes::cube(), "cube"),
            (test_meshes::fan(7), "fan"),
        ]
    }

    #[test]
    fn accepts_every_level_produced() {
        for (mut mesh, name) in levels() {
            let mut creases = Creases::none();
            for level in 0..4 {
                let (fine, fc) = loop_step(&mesh, &creases).unwrap();
                check_split(&mesh.triangles, mesh.positions.len(), &fine.triangles)
                    .unwrap_or_else(|e| panic!("{name} level {level}: {e}"));
                assert_eq!(
                    split(&mesh.triangles, mesh.positions.len()).fine_vertices(),
                    fine.positions.len()
                );
                (mesh, creases) = (fine, fc);
            }
        }
    }

    fn one_level() -> (crate::mesh::Mesh, Vec<[u32; 3]>) {
        let m = test_meshes::irregular_closed();
        let s = split(&m.triangles, m.positions.len());
        (m, s.triangles)
    }

    #[test]
    fn rejects_swapped_triangles() {
        let (m, mut fine) = one_level();
        fine.swap(4, 9);
        let err = check_split(&m.triangles, m.positions.len(), &fine).unwrap_err();
        assert!(err.contains("fine triangle"), "{err}");
        // Swapping the last two children of one coarse triangle is also caught.
        let (m, mut fine) = one_level();
        fine.swap(6, 7);
        assert!(check_split(&m.triangles, m.positions.len(), &fine).is_err());
        // So is a rotated (same orientation) or flipped child.
        let (m, mut fine) = one_level();
        fine[0] = [fine[0][1], fine[0][2], fine[0][0]];
        assert!(check_split(&m.triangles, m.positions.len(), &fine).is_err());
        let (m, mut fine) = one_level();
        fine[1].swap(0, 1);
        assert!(check_split(&m.triangles, m.positions.len(), &fine).is_err());
    }

    #[test]
    fn rejects_wrong_odd_index() {
        let nv = test_meshes::irregular_closed().positions.len() as u32;
        // Renumber one odd vertex everywhere it occurs (consistently): bad numbering.
        let (m, mut fine) = one_level();
        for t in fine.iter_mut() {
            for i in t.iter_mut() {
                if *i == nv + 3 {
                    *i = nv + 1000;
                }
            }
        }
        let err = check_split(&m.triangles, m.positions.len(), &fine).unwrap_err();
        assert!(err.contains("expected"), "{err}");
        // Replace one odd vertex in one coarse triangle's 4 children: the edge then has two.
        let (m, mut fine) = one_level();
        let [ab, _, _] = fine[3];
        let other = if ab == nv + 5 { nv + 6 } else { nv + 5 };
        for t in fine[0..4].iter_mut() {
            for i in t.iter_mut() {
                if *i == ab {
                    *i = other;
                }
            }
        }
        let err = check_split(&m.triangles, m.positions.len(), &fine).unwrap_err();
        assert!(err.contains("two"), "{err}");
        // An even index where an odd one belongs.
        let (m, mut fine) = one_level();
        let [ab, _, _] = fine[3];
        for t in fine[0..4].iter_mut() {
            for i in t.iter_mut() {
                if *i == ab {
                    *i = 0;
                }
            }
        }
        assert!(check_split(&m.triangles, m.positions.len(), &fine).is_err());
    }

    #[test]
    fn rejects_missing_triangle() {
        let (m, mut fine) = one_level();
        fine.remove(17);
        let err = check_split(&m.triangles, m.positions.len(), &fine).unwrap_err();
        assert!(err.contains("fine triangles for"), "{err}");
        // Missing group of four: counts no longer match either.
        let (m, mut fine) = one_level();
        fine.drain(8..12);
        assert!(check_split(&m.triangles, m.positions.len(), &fine).is_err());
    }

    #[test]
    fn rejects_bad_coarse_data_without_panicking() {
        let (m, fine) = one_level();
        assert!(check_split(&m.triangles, 3, &fine).is_err());
        assert!(check_split(&[[0, 0, 1]], 2, &[[0; 3]; 4]).is_err());
        assert!(
            check_split(
                &[[0, 1, 2]],
                3,
                &[[0, 3, 4], [3, 1, 5], [4, 5, 2], [3, 5, 4]]
            )
            .is_ok()
        );
        assert!(
            check_split(
                &[[0, 1, 2]],
                3,
                &[[0, 3, 9], [3, 1, 5], [9, 5, 2], [3, 5, 9]]
            )
            .is_err()
        );
    }
}
