//! The real SolidWorks impeller IGES tessellated: every face, within the tolerance.

mod common;

use wavemill::cad::iges::read_iges;
use wavemill::cad::tessellate::{TessellateOptions, tessellate};

#[test]
fn probe() {
    let Some(dir) = common::testdata() else {
        return;
    };
    let path = dir.join("cad/impeller_solidworks__pyvista_pyiges.igs");
    let text = std::fs::read_to_string(&path).expect("the IGES test part");
    let t0 = std::time::Instant::now();
    let model = read_iges(&text).unwrap();
    let t1 = std::time::Instant::now();
    let t = tessellate(&model.faces, &TessellateOptions::default()).unwrap();
    let t2 = std::time::Instant::now();
    let r = &t.report;
    eprintln!("read {:?} tess {:?}", t1 - t0, t2 - t1);
    eprintln!("{:?}", TessellateOptions::default());
    eprintln!("{r:?}");
    for s in r.open_seams.iter().take(10) { eprintln!("  seam {:.3} mm {} edges at {:?}", s.length, s.edges, s.at); }
    {
        let es = wavemill::mesh::topology::edges(&t.mesh.triangles);
        let open: Vec<[u32;2]> = es.iter().filter(|e| e.faces.len()==1).map(|e| e.vertices).collect();
        let pos = &t.mesh.positions;
        let seg = |e: [u32;2]| (pos[e[0] as usize], pos[e[1] as usize]);
        let mut hist = [0usize; 8];
        let bounds = [1e-4, 1e-3, 0.0025, 0.005, 0.01, 0.02, 0.05, f64::INFINITY];
        let mut total_len = [0.0f64; 8];
        for (i, &e) in open.iter().enumerate() {
            let (a, b) = seg(e);
            let m = nalgebra::Point3::from((a.coords + b.coords) / 2.0);
            let mut best = f64::INFINITY;
            for (j, &g) in open.iter().enumerate() {
                if i == j { continue; }
                let (c, d) = seg(g);
                if (c - m).norm() > (d - c).norm() + 1.0 && (d - m).norm() > (d-c).norm() + 1.0 { continue; }
                let cd = d - c; let tt = ((m - c).dot(&cd) / cd.norm_squared()).clamp(0.0, 1.0);
                best = best.min((m - (c + cd * tt)).norm());
            }
            let k = bounds.iter().position(|&x| best <= x).unwrap();
            hist[k] += 1; total_len[k] += (b - a).norm();
        }
        eprintln!("open edge nearest-open-edge hist (<=1e-4,1e-3,2.5e-3,5e-3,1e-2,2e-2,5e-2,inf): {:?} len {:?}", hist, total_len);
    }
    let d = t.deviation(&model.faces, 6);
    eprintln!("deviation {:?}", d);
    eprintln!("area {}", t.mesh.surface_area());
    // worst triangles
    let mut worst: Vec<(f64, usize)> = (0..t.mesh.triangles.len()).map(|i| {
        let f = t.face_of_triangle[i] as usize;
        let uv = t.corner_parameters(i);
        let p = t.mesh.corners(i);
        let mut m: f64 = 0.0;
        for a in 0..=6 { for b in 0..=6-a { let (x,y)=(a as f64/6.0,b as f64/6.0); let z=1.0-x-y;
            let q = uv[0].coords*x+uv[1].coords*y+uv[2].coords*z;
            let mm = p[0].coords*x+p[1].coords*y+p[2].coords*z;
            m = m.max((model.faces[f].surface.point(q.x,q.y).coords-mm).norm()); }}
        (m, i)}).collect();
    worst.sort_by(|a,b| b.0.total_cmp(&a.0));
    let mut per_face = std::collections::BTreeMap::new();
    for &(m,i) in &worst { if m > 0.01 { *per_face.entry(t.face_of_triangle[i]).or_insert(0) += 1; } }
    eprintln!("faces over: {:?}", per_face);
    for &(m, i) in worst.iter().take(8) {
        let f = t.face_of_triangle[i] as usize;
        let uv = t.corner_parameters(i);
        let p = t.mesh.corners(i);
        let s: Vec<_> = uv.iter().map(|q| (model.faces[f].surface.point(q.x,q.y) - p[0]).norm()).collect();
        eprintln!("  dev {m:.4} face {f} surf {} uv {:?} p {:?} ", matches!(model.faces[f].surface, wavemill::cad::iges::Surface::Revolution{..}), uv.map(|q| (q.x,q.y)), p.map(|q|(q.x,q.y,q.z)));
        let _ = s;
        eprintln!("   corner offsets {:?}", (0..3).map(|k| (model.faces[f].surface.point(uv[k].x,uv[k].y)-p[k]).norm()).collect::<Vec<_>>());
    }
}

#[test]
fn probe_face() {
    let Some(dir) = common::testdata() else { return; };
    let path = dir.join("cad/impeller_solidworks__pyvista_pyiges.igs");
    let text = std::fs::read_to_string(&path).unwrap();
    let model = read_iges(&text).unwrap();
    let f = &model.faces[132];
    eprintln!("domain {:?}", f.surface.domain());
    if let wavemill::cad::iges::Surface::Nurbs { surface, .. } = &f.surface {
        eprintln!("deg {:?} knots {:?} net {:?}", surface.degree(), surface.knots(), surface.net_size());
    }
    fn show(c: &wavemill::cad::iges::Curve, d: usize) {
        match c {
            wavemill::cad::iges::Curve::Composite(m) => { for x in m { show(x, d+1); } }
            wavemill::cad::iges::Curve::Nurbs{curve, range} => { let a = curve.point(range.0); let b = curve.point(range.1); eprintln!("{:d$}nurbs deg {} {:?} -> {:?} range {:?}", "", curve.degree(), (a.x,a.y), (b.x,b.y), range, d=d); }
            other => { let s = other.sample(1); eprintln!("{:d$}{:?} -> {:?}", "", s.first().map(|p|(p.x,p.y)), s.last().map(|p|(p.x,p.y)), d=d); }
        }
    }
    if let Some(o) = &f.outer { show(o, 0); }
    for u in [0.057, 0.1185, 0.18, 0.303] { for v in [0.0, 1.45e-9, 1e-6, 1e-3] { let p = f.surface.point(u, v); eprintln!("S({u},{v}) = {:?}", (p.x,p.y,p.z)); } }
}

#[test]
fn probe_sign() {
    let Some(dir) = common::testdata() else { return; };
    let path = dir.join("cad/impeller_solidworks__pyvista_pyiges.igs");
    let text = std::fs::read_to_string(&path).unwrap();
    let model = read_iges(&text).unwrap();
    let t = tessellate(&model.faces, &TessellateOptions::default()).unwrap();
    let (mesh, rep) = wavemill::mesh::prepare(&t.mesh, &Default::default()).unwrap();
    eprintln!("{:?}", rep.problems());
    let sd = wavemill::mesh::SurfaceDistance::new(&mesh);
    let bb = mesh.aabb();
    let mut bad = 0;
    let mut state = 12345u64;
    let mut rnd = || { state ^= state << 13; state ^= state >> 7; state ^= state << 17; (state >> 11) as f64 / (1u64 << 53) as f64 };
    for _ in 0..20000 {
        let p = nalgebra::Point3::new(bb.min.x + rnd() * (bb.max.x - bb.min.x), bb.min.y + rnd() * (bb.max.y - bb.min.y), bb.min.z + rnd() * (bb.max.z - bb.min.z));
        let (d, c) = sd.signed_distance(&p).unwrap();
        let par = sd.contains_by_parity(&p);
        if (d < 0.0) != par && d.abs() > 0.05 {
            bad += 1;
            if bad < 10 { eprintln!("disagree at {p} d {d:.4} parity {par} closest {:?}", c); }
        }
    }
    eprintln!("bad {bad}");
}

#[test]
fn probe_flips() {
    let Some(dir) = common::testdata() else { return; };
    let path = dir.join("cad/impeller_solidworks__pyvista_pyiges.igs");
    let text = std::fs::read_to_string(&path).unwrap();
    let model = read_iges(&text).unwrap();
    let t = tessellate(&model.faces, &TessellateOptions::default()).unwrap();
    let mut signs: std::collections::BTreeMap<u32, (usize, usize, Vec<usize>)> = Default::default();
    for i in 0..t.mesh.triangles.len() {
        let f = t.face_of_triangle[i];
        let s = &model.faces[f as usize].surface;
        let uv = t.corner_parameters(i);
        let c = (uv[0].coords + uv[1].coords + uv[2].coords) / 3.0;
        let h = 1e-6;
        let su = s.point(c.x + h, c.y) - s.point(c.x - h, c.y);
        let sv = s.point(c.x, c.y + h) - s.point(c.x, c.y - h);
        let n = su.cross(&sv);
        let tn = t.mesh.face_normal(i);
        let e = signs.entry(f).or_default();
        if n.dot(&tn) > 0.0 { e.0 += 1 } else { e.1 += 1; e.2.push(i) }
    }
    let q = nalgebra::Point3::new(-20.37847364463208, 35.718767728431395, -0.9448355360245393);
    for i in 0..t.mesh.triangles.len() {
        let c = t.mesh.corners(i);
        if c.iter().any(|p| (p - q).norm() < 0.05) {
            let f = t.face_of_triangle[i];
            let s = &model.faces[f as usize].surface;
            let uv = t.corner_parameters(i);
            eprintln!("near: tri {i} face {f} corners {:?} uv {:?} normal {:?} rev {}", c.map(|p| (p.x, p.y, p.z)), uv.map(|q| (q.x, q.y)), t.mesh.face_normal(i), matches!(s, wavemill::cad::iges::Surface::Revolution{..}));
        }
    }
    for (f, (a, b, list)) in &signs {
        let minority = if a < b { *a } else { *b };
        if minority > 0 {
            let bad: Vec<_> = if a < b { vec![] } else { list.iter().take(3).map(|&i| { let c = t.mesh.corners(i); (i, c[0], t.mesh.triangles[i]) }).collect() };
            eprintln!("face {f}: {a} vs {b} {:?}", bad);
        }
    }
}
