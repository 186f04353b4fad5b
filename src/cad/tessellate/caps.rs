//! Caps removed from the welded mesh.
//!
//! Three boundary vertices in a row on a stretch the surface squeezes (a face's side near an
//! axis or a pole of its parameterisation) can form a cap: a triangle whose height is a tiny
//! share of its length. Its normal is noise, and where welding moved a corner across that
//! height it folds over its neighbour, which breaks the inside/outside test of every later
//! stage (pseudo-normals). A cap's middle vertex lies on its long side to within that height,
//! so it is merged into the nearer end of that side: the cap and the triangle across the short
//! side vanish and the mesh moves by less than the cap's height, where the merge keeps the
//! surface manifold and turns no other triangle over.

use nalgebra::Point3;

use super::FaceTriangles;

/// A triangle whose height is below this share of its longest side is a cap.
pub(super) const CAP_THINNESS: f64 = 1e-3;

/// Height over longest side.
pub(super) fn thinness(p: [Point3<f64>; 3]) -> f64 {
    let [a, b, c] = p;
    let longest2 = (b - a)
        .norm_squared()
        .max((c - b).norm_squared())
        .max((a - c).norm_squared());
    if longest2 > 0.0 {
        (b - a).cross(&(c - a)).norm() / longest2
    } else {
        0.0
    }
}

/// Merges caps' middle vertices into their neighbours; returns how many.
pub(super) fn collapse_caps(mesh: &mut FaceTriangles) -> usize {
    let mut collapsed = 0;
    for _ in 0..4 {
        let corners =
            |mesh: &FaceTriangles, t: usize| mesh.triangles[t].map(|i| mesh.positions[i as usize]);
        let caps: Vec<usize> = (0..mesh.triangles.len())
            .filter(|&t| thinness(corners(mesh, t)) < CAP_THINNESS)
            .collect();
        if caps.is_empty() {
            break;
        }
        let mut around: Vec<Vec<u32>> = vec![Vec::new(); mesh.positions.len()];
        for (t, tri) in mesh.triangles.iter().enumerate() {
            for &v in tri {
                around[v as usize].push(t as u32);
            }
        }
        let mut removed = vec![false; mesh.triangles.len()];
        let mut touched = vec![false; mesh.positions.len()];
        let mut merged_this_pass = 0;
        for t in caps {
            let tri = mesh.triangles[t];
            if removed[t] || tri.iter().any(|&v| touched[v as usize]) {
                continue;
            }
            let p = corners(mesh, t);
            // The middle vertex: opposite the longest side; it goes to the nearer end.
            let k = (0..3)
                .max_by(|&x, &y| {
                    let lx = (p[(x + 1) % 3] - p[(x + 2) % 3]).norm_squared();
                    let ly = (p[(y + 1) % 3] - p[(y + 2) % 3]).norm_squared();
                    lx.total_cmp(&ly)
                })
                .unwrap_or(0);
            let c = tri[k];
            let (e1, e2) = (tri[(k + 1) % 3], tri[(k + 2) % 3]);
            let target = if (p[(k + 1) % 3] - p[k]).norm() <= (p[(k + 2) % 3] - p[k]).norm() {
                e1
            } else {
                e2
            };
            if let Some(changes) = plan_merge(mesh, &around, c, target) {
                for (s, new) in changes {
                    match new {
                        None => removed[s] = true,
                        Some((tri, uv)) => {
                            mesh.triangles[s] = tri;
                            mesh.corner_uv[s] = uv;
                        }
                    }
                }
                for &s in &around[c as usize] {
                    for &v in &mesh.triangles[s as usize] {
                        touched[v as usize] = true;
                    }
                }
                touched[c as usize] = true;
                touched[target as usize] = true;
                merged_this_pass += 1;
            }
        }
        if merged_this_pass == 0 {
            break;
        }
        collapsed += merged_this_pass;
        let mut keep = removed.iter().map(|r| !r);
        mesh.triangles.retain(|_| keep.next().unwrap_or(true));
        let mut keep = removed.iter().map(|r| !r);
        mesh.face_of_triangle
            .retain(|_| keep.next().unwrap_or(true));
        let mut keep = removed.iter().map(|r| !r);
        mesh.corner_uv.retain(|_| keep.next().unwrap_or(true));
    }
    collapsed
}

type Change = (usize, Option<([u32; 3], [nalgebra::Point2<f64>; 3])>);

/// What merging vertex `c` into `target` does to the triangles around `c`, or `None` where it
/// would not keep the surface manifold or would turn a triangle over.
fn plan_merge(
    mesh: &FaceTriangles,
    around: &[Vec<u32>],
    c: u32,
    target: u32,
) -> Option<Vec<Change>> {
    let ring = &around[c as usize];
    let neighbours = |v: u32| {
        let mut n: Vec<u32> = around[v as usize]
            .iter()
            .flat_map(|&t| mesh.triangles[t as usize])
            .filter(|&x| x != v)
            .collect();
        n.sort_unstable();
        n.dedup();
        n
    };
    // Link condition: the common neighbours are the triangles' across the merged edge.
    let shared: Vec<usize> = ring
        .iter()
        .map(|&t| t as usize)
        .filter(|&t| mesh.triangles[t].contains(&target))
        .collect();
    let mut opposite: Vec<u32> = shared
        .iter()
        .flat_map(|&t| mesh.triangles[t])
        .filter(|&x| x != c && x != target)
        .collect();
    opposite.sort_unstable();
    opposite.dedup();
    let (nc, nt) = (neighbours(c), neighbours(target));
    let common: Vec<u32> = nc
        .iter()
        .copied()
        .filter(|x| nt.binary_search(x).is_ok())
        .collect();
    if shared.len() != 2 || common != opposite {
        return None;
    }
    let mut changes: Vec<Change> = shared.iter().map(|&t| (t, None)).collect();
    for &t in ring {
        let t = t as usize;
        if shared.contains(&t) {
            continue;
        }
        let old = mesh.triangles[t];
        let new = old.map(|v| if v == c { target } else { v });
        let normal = |tri: [u32; 3]| {
            let [a, b, d] = tri.map(|i| mesh.positions[i as usize]);
            (b - a).cross(&(d - a))
        };
        let (n0, n1) = (normal(old), normal(new));
        if n1.dot(&n0) <= 0.5 * n0.norm() * n1.norm() {
            return None;
        }
        // The target's parameters on this triangle's face, from a triangle of that face that
        // has it.
        let face = mesh.face_of_triangle[t];
        let uv_target = around[target as usize].iter().find_map(|&s| {
            let s = s as usize;
            (mesh.face_of_triangle[s] == face)
                .then(|| mesh.triangles[s].iter().position(|&v| v == target))
                .flatten()
                .map(|k| mesh.corner_uv[s][k])
        })?;
        let mut uv = mesh.corner_uv[t];
        if let Some(k) = old.iter().position(|&v| v == c) {
            uv[k] = uv_target;
        }
        changes.push((t, Some((new, uv))));
    }
    Some(changes)
}
