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
