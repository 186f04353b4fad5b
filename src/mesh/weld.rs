//! Merging vertices closer than a tolerance.
//!
//! STL stores three copies of every vertex, and CAD exporters write coordinates that differ in
//! the last bits. The tolerance is a length in mm, the same wherever the vertex is and however
//! far the rest of the mesh reaches (see [`super::PrepareOptions::weld_tolerance`]).

use std::collections::HashMap;

use super::Mesh;
use crate::geom::Point3;

/// The result of [`weld`]: the mesh on the merged vertices and, for every input vertex, the
/// merged vertex it became.
pub struct Welded {
    pub mesh: Mesh,
    pub vertex_map: Vec<u32>,
}

/// Merges every vertex within `tolerance` (mm) of an earlier kept vertex into it.
///
/// Greedy in input order, so the result is deterministic. A spatial hash with cells of the
/// tolerance size finds candidates in the 27 surrounding cells; among candidates the closest
/// kept vertex wins (ties: the earlier one). Triangles keep their order; they may become
/// degenerate (two equal indices), which [`super::prepare`] removes and counts.
pub fn weld(mesh: &Mesh, tolerance: f64) -> Welded {
    let cell = if tolerance > 0.0 {
        tolerance
    } else {
        f64::MIN_POSITIVE
    };
    let key = |p: &Point3| {
        [
            (p.x / cell).floor() as i64,
            (p.y / cell).floor() as i64,
            (p.z / cell).floor() as i64,
        ]
    };
    let mut grid: HashMap<[i64; 3], Vec<u32>> = HashMap::with_capacity(mesh.positions.len());
    let mut kept: Vec<Point3> = Vec::new();
    let mut vertex_map = Vec::with_capacity(mesh.positions.len());
    let tol2 = tolerance * tolerance;
    for p in &mesh.positions {
        let k = key(p);
        let mut best: Option<(f64, u32)> = None;
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let Some(list) = grid.get(&[k[0] + dx, k[1] + dy, k[2] + dz]) else {
                        continue;
                    };
                    for &i in list {
                        let d2 = (kept[i as usize] - p).norm_squared();
                        if d2 <= tol2 && best.is_none_or(|(bd, bi)| d2 < bd || (d2 == bd && i < bi))
                        {
                            best = Some((d2, i));
                        }
                    }
                }
            }
        }
        let index = match best {
            Some((_, i)) => i,
            None => {
                let i = kept.len() as u32;
                kept.push(*p);
                grid.entry(k).or_default().push(i);
                i
            }
        };
        vertex_map.push(index);
    }
    let triangles = mesh
        .triangles
        .iter()
        .map(|t| t.map(|i| vertex_map[i as usize]))
        .collect();
    Welded {
        mesh: Mesh {
            positions: kept,
            triangles,
        },
        vertex_map,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::fixtures::cuboid;

    /// Explode a mesh into a soup with three copies per triangle (as STL does), jitter the
    /// copies below the tolerance, and weld: the original connectivity must come back.
    #[test]
    fn soup_welds_back_to_the_indexed_mesh() {
        let m = cuboid(10.0, 20.0, 30.0);
        let mut soup = Mesh::default();
        for (t, tri) in m.triangles.iter().enumerate() {
            let base = soup.positions.len() as u32;
            for (k, &i) in tri.iter().enumerate() {
                let jitter = 1e-7 * ((t * 3 + k) % 5) as f64;
                soup.positions
                    .push(m.positions[i as usize] + crate::geom::Vector3::repeat(jitter));
            }
            soup.triangles.push([base, base + 1, base + 2]);
        }
        let w = weld(&soup, 1e-5);
        assert_eq!(w.mesh.positions.len(), 8);
        assert_eq!(w.mesh.triangles.len(), 12);
        assert!((w.mesh.signed_volume() - 6000.0).abs() < 1e-3);
    }

    #[test]
    fn distinct_vertices_stay_apart() {
        let m = cuboid(1e-3, 1e-3, 1e-3);
        assert_eq!(weld(&m, 1e-4).mesh.positions.len(), 8);
        assert_eq!(weld(&m, 1e-2).mesh.positions.len(), 1);
    }
}
