//! Tests of the isotropic remesher by invariants (topology, features, quality), never by
//! golden vertex lists.
use std::collections::HashMap;
use std::time::Instant;

use nalgebra::Point3;

use super::*;

// ------------------------------------------------------------------ helpers

type P = Point3<f64>;

/// Undirected edges with their triangle counts, sorted.
fn edge_counts(m: &Mesh) -> Vec<([u32; 2], usize)> {
    let mut e: Vec<[u32; 2]> = m
        .triangles
        .iter()
        .flat_map(|t| (0..3).map(move |i| key(t[i], t[(i + 1) % 3])))
        .collect();
    e.sort_unstable();
    let mut out: Vec<([u32; 2], usize)> = Vec::new();
    for k in e {
        match out.last_mut() {
            Some((last, c)) if *last == k => *c += 1,
            _ => out.push((k, 1)),
        }
    }
    out
}

/// Structural invariants every output must satisfy; returns (Euler characteristic, boundary
/// edge count, boundary loop count).
fn sanity_check(m: &Mesh, c: &Creases) -> (i64, usize, usize) {
    // Valid as input again (manifold, oriented, creases are edges, no bow-ties).
    validate(m, c).expect("output must be a valid manifold input");
    let ec = edge_counts(m);
    // Every vertex referenced (compacted).
    let mut used = vec![false; m.positions.len()];
    for t in &m.triangles {
        for &v in t {
            used[v as usize] = true;
        }
    }
    assert!(used.iter().all(|&u| u), "output not compacted");
    assert!(
        c.edges.windows(2).all(|w| w[0] < w[1]),
        "creases sorted, dedup"
    );
    assert!(c.edges.iter().all(|e| e[0] < e[1]));
    let boundary: Vec<[u32; 2]> = ec.iter().filter(|x| x.1 == 1).map(|x| x.0).collect();
    // Boundary loops: connected components of the boundary graph (each vertex degree 2).
    let mut adj: HashMap<u32, Vec<u32>> = HashMap::new();
    for e in &boundary {
        adj.entry(e[0]).or_default().push(e[1]);
        adj.entry(e[1]).or_default().push(e[0]);
    }
    assert!(
        adj.values().all(|v| v.len() == 2),
        "boundary not a set of loops"
    );
    let mut keys: Vec<u32> = adj.keys().copied().collect();
    keys.sort_unstable();
    let mut seen = std::collections::HashSet::new();
    let mut loops = 0;
    for k in keys {
        if seen.insert(k) {
            loops += 1;
            let mut stack = vec![k];
            while let Some(v) = stack.pop() {
                for &n in &adj[&v] {
                    if seen.insert(n) {
                        stack.push(n);
                    }
                }
            }
        }
    }
    let chi = m.positions.len() as i64 - ec.len() as i64 + m.triangles.len() as i64;
    (chi, boundary.len(), loops)
}

fn angles(m: &Mesh) -> Vec<f64> {
    let mut out = Vec::new();
    for t in &m.triangles {
        for i in 0..3 {
            let p = m.positions[t[i] as usize];
            let a = m.positions[t[(i + 1) % 3] as usize] - p;
            let b = m.positions[t[(i + 2) % 3] as usize] - p;
            out.push(a.angle(&b).to_degrees());
        }
    }
    out
}

fn min_angle(m: &Mesh) -> f64 {
    angles(m).into_iter().fold(180.0, f64::min)
}

fn mean_edge(m: &Mesh) -> f64 {
    let ec = edge_counts(m);
    ec.iter()
        .map(|(e, _)| (m.positions[e[0] as usize] - m.positions[e[1] as usize]).norm())
        .sum::<f64>()
        / ec.len() as f64
}

fn volume(m: &Mesh) -> f64 {
    m.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| m.positions[v as usize].coords);
            a.dot(&b.cross(&c)) / 6.0
        })
        .sum()
}

fn valences(m: &Mesh) -> Vec<usize> {
    let mut v = vec![0usize; m.positions.len()];
    for (e, _) in edge_counts(m) {
        v[e[0] as usize] += 1;
        v[e[1] as usize] += 1;
    }
    v
}

// -------------------------------------------------------------------- cube

/// Unit cube, every cube edge cut into `n` pieces, every face a fan of 4n needles from an
/// apex very close to one face corner. Creases: the 12 cube edges.
fn sliver_cube(n: u32) -> (Mesh, Creases) {
    let mut index: HashMap<[u32; 3], u32> = HashMap::new();
    let mut positions: Vec<P> = Vec::new();
    let mut triangles = Vec::new();
    let mut creases = Vec::new();
    // (origin, u, v) with u × v the outward normal.
    let faces: [([u32; 3], usize, usize); 6] = [
        ([0, 0, 0], 1, 0),
        ([0, 0, 1], 0, 1),
        ([0, 0, 0], 2, 1),
        ([1, 0, 0], 1, 2),
        ([0, 0, 0], 0, 2),
        ([0, 1, 0], 2, 0),
    ];
    for (origin, u, v) in faces {
        let at = |i: u32, j: u32| -> [u32; 3] {
            let mut g = origin.map(|o| o * n);
            g[u] += i;
            g[v] += j;
            g
        };
        let mut lp: Vec<[u32; 3]> = Vec::new();
        lp.extend((0..n).map(|i| at(i, 0)));
        lp.extend((0..n).map(|j| at(n, j)));
        lp.extend((0..n).map(|i| at(n - i, n)));
        lp.extend((0..n).map(|j| at(0, n - j)));
        let ids: Vec<u32> = lp
            .iter()
            .map(|g| {
                *index.entry(*g).or_insert_with(|| {
                    positions.push(P::from(g.map(|c| c as f64 / n as f64)));
                    (positions.len() - 1) as u32
                })
            })
            .collect();
        let mut apex = P::from(origin.map(|o| o as f64));
        apex[u] += 1e-3;
        apex[v] += 2e-3;
        positions.push(apex);
        let a = (positions.len() - 1) as u32;
        for k in 0..ids.len() {
            let (p, q) = (ids[k], ids[(k + 1) % ids.len()]);
            triangles.push([a, p, q]);
            creases.push(key(p, q));
        }
    }
    creases.sort_unstable();
    creases.dedup();
    (
        Mesh {
            positions,
            triangles,
        },
        Creases { edges: creases },
    )
}

fn cube_project(p: &P) -> P {
    let mut q = p.map(|c| c.clamp(0.0, 1.0));
    let (mut best, mut axis) = (f64::INFINITY, 0);
    for i in 0..3 {
        let d = q[i].min(1.0 - q[i]);
        if d < best {
            best = d;
            axis = i;
        }
    }
    q[axis] = if q[axis] < 0.5 { 0.0 } else { 1.0 };
    q
}

fn cube_project_to_edge(p: &P) -> P {
    let mut best = (f64::INFINITY, *p);
    for axis in 0..3 {
        for s in 0..4 {
            let mut q = P::origin();
            q[axis] = p[axis].clamp(0.0, 1.0);
            q[(axis + 1) % 3] = (s & 1) as f64;
            q[(axis + 2) % 3] = (s >> 1) as f64;
            let d = (q - p).norm();
            if d < best.0 {
                best = (d, q);
            }
        }
    }
    best.1
}

fn on_cube_surface(p: &P, tol: f64) -> bool {
    p.iter().all(|&c| (-tol..=1.0 + tol).contains(&c))
        && p.iter().any(|&c| c.abs() <= tol || (1.0 - c).abs() <= tol)
}

fn on_cube_edge(p: &P, tol: f64) -> bool {
    p.iter()
        .filter(|&&c| c.abs() <= tol || (1.0 - c).abs() <= tol)
        .count()
        >= 2
}

fn remesh_cube() -> (Mesh, Creases, Mesh) {
    let (mesh, creases) = sliver_cube(5);
    let opts = IsotropicOptions::new(0.2);
    let (out, oc) = isotropic_remesh(&mesh, &creases, &opts, &cube_project, &cube_project_to_edge)
        .expect("valid input");
    (out, oc, mesh)
}

#[test]
fn cad_scale_cube_behaves_like_the_unit_cube() {
    // Same sliver cube at 70 mm (needles of 70 mm next to 0.07 mm edges): tolerances scale.
    let s = 70.0;
    let (mut mesh, creases) = sliver_cube(5);
    for p in &mut mesh.positions {
        *p = P::from(p.coords * s);
    }
    let proj = |p: &P| P::from(cube_project(&P::from(p.coords / s)).coords * s);
    let proj_e = |p: &P| P::from(cube_project_to_edge(&P::from(p.coords / s)).coords * s);
    let opts = IsotropicOptions::new(0.2 * s);
    let (out, oc) = isotropic_remesh(&mesh, &creases, &opts, &proj, &proj_e).expect("valid");
    let (chi, nb, _) = sanity_check(&out, &oc);
    assert_eq!((chi, nb), (2, 0));
    let ma = min_angle(&out);
    let vol = volume(&out);
    eprintln!(
        "cube x70: {} tris, min angle {ma:.2}°, volume {vol}",
        out.triangles.len()
    );
    assert!(ma > 25.0, "min angle {ma}");
    assert!((vol / (s * s * s) - 1.0).abs() < 1e-9, "volume {vol}");
}

#[test]
fn sliver_cube_becomes_well_shaped_and_keeps_features() {
    let (mesh, _) = sliver_cube(5);
    let input_min = min_angle(&mesh);
    let t0 = Instant::now();
    let (out, oc, _) = remesh_cube();
    let dt = t0.elapsed();
    let (chi, nb, _) = sanity_check(&out, &oc);
    assert_eq!(nb, 0, "closed");
    assert_eq!(chi, 2, "genus 0");
    for corner in 0..8u32 {
        let c = P::new(
            (corner & 1) as f64,
            ((corner >> 1) & 1) as f64,
            (corner >> 2) as f64,
        );
        assert!(out.positions.contains(&c), "corner {c} kept exactly");
    }
    for p in &out.positions {
        assert!(on_cube_surface(p, 1e-12), "{p} off the cube");
    }
    let mut crease_len = 0.0;
    for e in &oc.edges {
        let (a, b) = (out.positions[e[0] as usize], out.positions[e[1] as usize]);
        assert!(
            on_cube_edge(&a, 1e-12) && on_cube_edge(&b, 1e-12),
            "crease {a} {b}"
        );
        crease_len += (a - b).norm();
    }
    assert!(
        (crease_len - 12.0).abs() < 1e-9,
        "crease network length {crease_len}"
    );
    let ma = min_angle(&out);
    let me = mean_edge(&out);
    let vol = volume(&out);
    eprintln!(
        "cube: input min angle {input_min:.3}°, {} tris -> {} tris, min angle {ma:.2}°, mean edge {me:.4}, volume {vol:.15}, {dt:?}",
        mesh.triangles.len(),
        out.triangles.len()
    );
    assert!(ma > 25.0, "min angle {ma}");
    assert!((me - 0.2).abs() < 0.2 * 0.2, "mean edge {me}");
    assert!((vol - 1.0).abs() < 1e-9, "volume {vol}");
}

#[test]
fn remeshing_is_deterministic() {
    let (a, ac, _) = remesh_cube();
    let (b, bc, _) = remesh_cube();
    assert_eq!(a, b);
    assert_eq!(ac, bc);
}

// ------------------------------------------------------------------- torus

const R: f64 = 1.0;
const RR: f64 = 0.4;

/// The shared torus fixture with this file's radii.
fn torus(nu: u32, nv: u32) -> Mesh {
    crate::mesh::fixtures::torus(R, RR, nu, nv)
}

fn torus_project(p: &P) -> P {
    let mut radial = nalgebra::Vector3::new(p.x, p.y, 0.0);
    if radial.norm() == 0.0 {
        radial.x = 1.0;
    }
    let c = P::from(radial.normalize() * R);
    let d = p - c;
    if d.norm() == 0.0 {
        return c + nalgebra::Vector3::z() * RR;
    }
    c + d.normalize() * RR
}

fn torus_distance(p: &P) -> f64 {
    let q = (p.x * p.x + p.y * p.y).sqrt() - R;
    ((q * q + p.z * p.z).sqrt() - RR).abs()
}

#[test]
fn slivery_torus_keeps_genus_and_gets_regular() {
    let mesh = torus(60, 3);
    let none = Creases::default();
    let opts = IsotropicOptions::new(0.12);
    let t0 = Instant::now();
    let (out, oc) =
        isotropic_remesh(&mesh, &none, &opts, &torus_project, &torus_project).expect("valid input");
    let dt = t0.elapsed();
    let (chi, nb, _) = sanity_check(&out, &oc);
    assert_eq!((chi, nb), (0, 0), "closed genus 1");
    assert!(oc.edges.is_empty());
    for p in &out.positions {
        assert!(torus_distance(p) < 1e-9, "{p} off the torus");
    }
    let ma = min_angle(&out);
    let val = valences(&out);
    let regular = val.iter().filter(|&&v| (5..=7).contains(&v)).count() as f64 / val.len() as f64;
    eprintln!(
        "torus: input min angle {:.2}°, {} -> {} tris, min angle {ma:.2}°, valence 5-7 {:.1} %, mean edge {:.4}, {dt:?}",
        min_angle(&mesh),
        mesh.triangles.len(),
        out.triangles.len(),
        100.0 * regular,
        mean_edge(&out)
    );
    assert!(ma > 20.0, "min angle {ma}");
    assert!(regular >= 0.9, "valence 5-7 fraction {regular}");
}

// -------------------------------------------------------------------- disc

fn fan_disc(n: u32) -> Mesh {
    let mut positions = vec![P::new(0.03, -0.02, 0.0)];
    for i in 0..n {
        let a = std::f64::consts::TAU * i as f64 / n as f64;
        positions.push(P::new(a.cos(), a.sin(), 0.0));
    }
    let triangles = (0..n).map(|i| [0, 1 + i, 1 + (i + 1) % n]).collect();
    Mesh {
        positions,
        triangles,
    }
}

#[test]
fn open_disc_keeps_its_boundary_on_the_circle() {
    let mesh = fan_disc(96);
    let plane = |p: &P| P::new(p.x, p.y, 0.0);
    let circle = |p: &P| {
        let r = (p.x * p.x + p.y * p.y).sqrt();
        if r == 0.0 {
            P::new(1.0, 0.0, 0.0)
        } else {
            P::new(p.x / r, p.y / r, 0.0)
        }
    };
    let opts = IsotropicOptions::new(0.15);
    let (out, oc) =
        isotropic_remesh(&mesh, &Creases::default(), &opts, &plane, &circle).expect("valid");
    let (chi, nb, loops) = sanity_check(&out, &oc);
    assert_eq!((chi, loops), (1, 1), "still a disc with one boundary loop");
    assert!(
        oc.edges.is_empty(),
        "boundary edges are not reported as creases"
    );
    let ec = edge_counts(&out);
    for (e, c) in &ec {
        if *c == 1 {
            for v in e {
                let p = out.positions[*v as usize];
                assert!(((p.x * p.x + p.y * p.y).sqrt() - 1.0).abs() < 1e-12, "{p}");
            }
        }
    }
    // All triangles still face +z (orientation kept).
    for t in &out.triangles {
        let [a, b, c] = t.map(|v| out.positions[v as usize]);
        assert!((b - a).cross(&(c - a)).z > 0.0);
    }
    let ma = min_angle(&out);
    eprintln!(
        "disc: {} boundary edges, {} tris, min angle {ma:.2}°",
        nb,
        out.triangles.len()
    );
    assert!(ma > 20.0, "min angle {ma}");
}

// --------------------------------------------------------------- bad input

fn id(p: &P) -> P {
    *p
}

fn run(mesh: &Mesh, creases: &Creases, l: f64) -> Result<(Mesh, Creases), IsotropicError> {
    isotropic_remesh(mesh, creases, &IsotropicOptions::new(l), &id, &id)
}

fn quad() -> Mesh {
    Mesh {
        positions: vec![
            P::new(0.0, 0.0, 0.0),
            P::new(1.0, 0.0, 0.0),
            P::new(1.0, 1.0, 0.0),
            P::new(0.0, 1.0, 0.0),
            P::new(0.5, 0.5, 1.0),
        ],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
    }
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    let none = Creases::default();
    let mut m = quad();
    m.triangles.push([0, 2, 4]);
    assert_eq!(
        run(&m, &none, 0.3),
        Err(IsotropicError::NonManifoldEdge(0, 2))
    );

    let mut m = quad();
    m.triangles.push([0, 1, 9]);
    assert!(matches!(
        run(&m, &none, 0.3),
        Err(IsotropicError::IndexOutOfRange { vertex: 9, .. })
    ));

    let mut m = quad();
    m.triangles[1] = [0, 3, 2];
    assert_eq!(
        run(&m, &none, 0.3),
        Err(IsotropicError::InconsistentOrientation(0, 2))
    );

    let mut m = quad();
    m.triangles[1] = [0, 2, 2];
    assert_eq!(
        run(&m, &none, 0.3),
        Err(IsotropicError::DegenerateTriangle(1))
    );

    let mut m = quad();
    m.positions[1].x = f64::NAN;
    assert_eq!(
        run(&m, &none, 0.3),
        Err(IsotropicError::NonFinitePosition(1))
    );

    assert_eq!(
        run(&quad(), &none, 0.0),
        Err(IsotropicError::InvalidTargetEdgeLength(0.0))
    );
    assert!(run(&quad(), &none, f64::NAN).is_err());

    let bad = Creases {
        edges: vec![[1, 3]],
    };
    assert_eq!(
        run(&quad(), &bad, 0.3),
        Err(IsotropicError::CreaseNotAnEdge(1, 3))
    );
    let bad = Creases {
        edges: vec![[0, 99]],
    };
    assert!(run(&quad(), &bad, 0.3).is_err());

    // Bow-tie: two triangles sharing only vertex 0.
    let m = Mesh {
        positions: vec![
            P::new(0.0, 0.0, 0.0),
            P::new(1.0, 0.0, 0.0),
            P::new(0.0, 1.0, 0.0),
            P::new(-1.0, 0.0, 0.0),
            P::new(0.0, -1.0, 0.0),
        ],
        triangles: vec![[0, 1, 2], [0, 3, 4]],
    };
    assert_eq!(
        run(&m, &none, 0.3),
        Err(IsotropicError::NonManifoldVertex(0))
    );

    // A projection returning NaN.
    let nan = |_: &P| P::new(f64::NAN, 0.0, 0.0);
    let r = isotropic_remesh(&quad(), &none, &IsotropicOptions::new(0.3), &nan, &nan);
    assert_eq!(r, Err(IsotropicError::ProjectionNotFinite));

    // The empty mesh is fine.
    let (out, oc) = run(&Mesh::default(), &none, 1.0).expect("empty is valid");
    assert!(out.triangles.is_empty() && oc.edges.is_empty());
}

#[test]
fn a_single_quad_is_refined_and_keeps_its_corners() {
    // A flat square with identity projections: the boundary is refined along the square's
    // sides, the area stays exactly 1 and the result is still one disc.
    let m = quad();
    let (out, oc) = run(&m, &Creases::default(), 0.25).expect("valid");
    let (chi, _, loops) = sanity_check(&out, &oc);
    assert_eq!((chi, loops), (1, 1));
    let area: f64 = out
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| out.positions[v as usize]);
            (b - a).cross(&(c - a)).z / 2.0
        })
        .sum();
    assert!((area - 1.0).abs() < 1e-12, "area {area}");
}

#[test]
fn thin_strip_never_pinches_its_two_boundaries_together() {
    // A 2 × 0.05 strip remeshed with L = 0.2: every rung (0.05) is "short", but collapsing it
    // would merge the two long boundary features into a bow-tie.
    let (w, h, n) = (2.0, 0.05, 8u32);
    let mut positions = Vec::new();
    for i in 0..=n {
        let x = w * i as f64 / n as f64;
        positions.push(P::new(x, 0.0, 0.0));
        positions.push(P::new(x, h, 0.0));
    }
    let mut triangles = Vec::new();
    for i in 0..n {
        let (a, b, c, d) = (2 * i, 2 * i + 2, 2 * i + 3, 2 * i + 1);
        triangles.push([a, b, c]);
        triangles.push([a, c, d]);
    }
    let mesh = Mesh {
        positions,
        triangles,
    };
    let plane = |p: &P| P::new(p.x, p.y, 0.0);
    let rect = move |p: &P| {
        let x = p.x.clamp(0.0, w);
        let y = p.y.clamp(0.0, h);
        // nearest side of the rectangle
        let c = [
            (y, P::new(x, 0.0, 0.0)),
            (h - y, P::new(x, h, 0.0)),
            (x, P::new(0.0, y, 0.0)),
            (w - x, P::new(w, y, 0.0)),
        ];
        c.iter().fold(c[0], |b, q| if q.0 < b.0 { *q } else { b }).1
    };
    let opts = IsotropicOptions::new(0.2);
    let (out, oc) =
        isotropic_remesh(&mesh, &Creases::default(), &opts, &plane, &rect).expect("valid");
    let (chi, _, loops) = sanity_check(&out, &oc);
    assert_eq!((chi, loops), (1, 1));
    let area: f64 = out
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| out.positions[v as usize]);
            (b - a).cross(&(c - a)).z / 2.0
        })
        .sum();
    assert!((area - w * h).abs() < 1e-12, "area {area}");
}

#[test]
fn huge_target_length_coarsens_but_keeps_topology() {
    // With L far beyond the model size every edge wants to collapse: only the link condition,
    // the fold test and the feature rules stand between this and a broken mesh.
    for l in [0.6, 1.0, 3.0] {
        let mesh = torus(60, 3);
        let opts = IsotropicOptions::new(l);
        let (out, oc) = isotropic_remesh(
            &mesh,
            &Creases::default(),
            &opts,
            &torus_project,
            &torus_project,
        )
        .expect("valid");
        let (chi, nb, _) = sanity_check(&out, &oc);
        assert_eq!((chi, nb), (0, 0), "torus genus kept at L = {l}");
        let (mesh, creases) = sliver_cube(5);
        let (out, oc) =
            isotropic_remesh(&mesh, &creases, &opts, &cube_project, &cube_project_to_edge)
                .expect("valid");
        let (chi, nb, _) = sanity_check(&out, &oc);
        assert_eq!((chi, nb), (2, 0), "cube genus kept at L = {l}");
        let vol = volume(&out);
        assert!((vol - 1.0).abs() < 1e-9, "cube volume {vol} at L = {l}");
        // Without creases the cube may be cut down, but stays a closed sphere.
        let (out, oc) = isotropic_remesh(
            &mesh,
            &Creases::default(),
            &opts,
            &cube_project,
            &cube_project_to_edge,
        )
        .expect("valid");
        let (chi, nb, _) = sanity_check(&out, &oc);
        assert_eq!((chi, nb), (2, 0), "crease-free cube genus kept at L = {l}");
        assert!(volume(&out) > 0.0);
    }
}

/// Nearest point on a set of segments.
fn nearest_on_segments(segs: &[(P, P)], p: &P) -> P {
    let mut best = (f64::INFINITY, *p);
    for (a, b) in segs {
        let d = b - a;
        let t = ((p - a).dot(&d) / d.norm_squared()).clamp(0.0, 1.0);
        let q = a + d * t;
        let dist = (q - p).norm();
        if dist < best.0 {
            best = (dist, q);
        }
    }
    best.1
}

#[test]
fn small_crease_triangle_is_not_collapsed_away() {
    // A 0.1-wide crease triangle (a: 136° interior angle, so a plain feature vertex; b and c:
    // corners) inside a 2 × 2 square, L = 0.2: the short crease edge a–b would like to
    // collapse, which must not fold the crease loop onto the single edge b–c.
    let (a, b, c) = (
        P::new(0.0, 0.02, 0.0),
        P::new(-0.05, 0.0, 0.0),
        P::new(0.05, 0.0, 0.0),
    );
    let s = [
        P::new(-1.0, -1.0, 0.0),
        P::new(1.0, -1.0, 0.0),
        P::new(1.0, 1.0, 0.0),
        P::new(-1.0, 1.0, 0.0),
    ];
    let mesh = Mesh {
        positions: vec![a, b, c, s[0], s[1], s[2], s[3]],
        triangles: vec![
            [1, 2, 0],
            [3, 4, 2],
            [3, 2, 1],
            [4, 5, 2],
            [2, 5, 0],
            [0, 5, 6],
            [0, 6, 1],
            [1, 6, 3],
        ],
    };
    let creases = Creases {
        edges: vec![[0, 1], [0, 2], [1, 2]],
    };
    let tri_segs = [(a, b), (b, c), (c, a)];
    let mut all_segs = tri_segs.to_vec();
    all_segs.extend((0..4).map(|i| (s[i], s[(i + 1) % 4])));
    let plane = |p: &P| P::new(p.x, p.y, 0.0);
    let feat = |p: &P| nearest_on_segments(&all_segs, p);
    let opts = IsotropicOptions::new(0.2);
    let (out, oc) = isotropic_remesh(&mesh, &creases, &opts, &plane, &feat).expect("valid");
    let (chi, _, loops) = sanity_check(&out, &oc);
    assert_eq!((chi, loops), (1, 1));
    assert!(oc.edges.len() >= 3, "crease loop kept: {:?}", oc.edges);
    let mut degree: HashMap<u32, usize> = HashMap::new();
    for e in &oc.edges {
        for v in e {
            *degree.entry(*v).or_default() += 1;
            let p = out.positions[*v as usize];
            assert!(
                (nearest_on_segments(&tri_segs, &p) - p).norm() < 1e-12,
                "{p}"
            );
        }
    }
    assert!(degree.values().all(|&d| d == 2), "crease is still a loop");
    assert!(
        out.positions.contains(&b) && out.positions.contains(&c),
        "corners kept"
    );
}

#[test]
fn planar_polygons_never_fold() {
    // Star-shaped 12-gon (alternating radii) fanned from many apexes, many target lengths:
    // every output triangle must still face +z and the area must be exact.
    let n = 12u32;
    let rim: Vec<P> = (0..n)
        .map(|i| {
            let t = std::f64::consts::TAU * i as f64 / n as f64;
            let r = if i % 2 == 0 { 1.0 } else { 0.45 };
            P::new(r * t.cos(), r * t.sin(), 0.0)
        })
        .collect();
    let segs: Vec<(P, P)> = (0..n as usize)
        .map(|i| (rim[i], rim[(i + 1) % n as usize]))
        .collect();
    let area0: f64 = segs
        .iter()
        .map(|(a, b)| (a.x * b.y - a.y * b.x) / 2.0)
        .sum();
    let plane = |p: &P| P::new(p.x, p.y, 0.0);
    let feat = |p: &P| nearest_on_segments(&segs, p);
    for apex in [
        P::new(0.0, 0.0, 0.0),
        P::new(0.3, 0.1, 0.0),
        P::new(-0.15, -0.2, 0.0),
    ] {
        for l in [0.05, 0.13, 0.3, 0.7, 2.0] {
            let mut positions = vec![apex];
            positions.extend(rim.iter().copied());
            let triangles = (0..n).map(|i| [0, 1 + i, 1 + (i + 1) % n]).collect();
            let mesh = Mesh {
                positions,
                triangles,
            };
            assert!(
                mesh.triangles.iter().all(|t| {
                    let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
                    (b - a).cross(&(c - a)).z > 0.0
                }),
                "apex {apex} must see the whole rim (input not folded)"
            );
            let opts = IsotropicOptions::new(l);
            let (out, oc) =
                isotropic_remesh(&mesh, &Creases::default(), &opts, &plane, &feat).expect("valid");
            let (chi, _, loops) = sanity_check(&out, &oc);
            assert_eq!((chi, loops), (1, 1), "apex {apex}, L {l}");
            let mut area = 0.0;
            for t in &out.triangles {
                let [a, b, c] = t.map(|v| out.positions[v as usize]);
                let z = (b - a).cross(&(c - a)).z;
                assert!(
                    z > 0.0,
                    "folded triangle at apex {apex}, L {l}: z {z:e}, {a} {b} {c}"
                );
                area += z / 2.0;
            }
            assert!(
                (area - area0).abs() < 1e-12,
                "area {area} vs {area0}, L {l}"
            );
        }
    }
}
