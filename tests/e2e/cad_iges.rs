//! The real SolidWorks impeller IGES (`../shared/testdata/cad/`, 277 trimmed faces): every face
//! reads, and each trim the file gives twice agrees with itself: the parameter-plane curve,
//! carried onto its surface by the surface's own evaluation, lies on the model-space curve
//! (sampled densely) — which checks the 126 and 128 layouts, the net order, the rational
//! evaluation and the surfaces of revolution's parameters at once.

use crate::common;
use nalgebra::Point3;
use wavemill::cad::iges::{Curve, read_iges};

#[test]
fn the_impeller_iges_reads_and_its_trims_agree_in_both_spaces() {
    let Some(dir) = common::testdata() else {
        return;
    };
    let path = dir.join("cad/impeller_solidworks__pyvista_pyiges.igs");
    let text = std::fs::read_to_string(&path).expect("the IGES test part");
    let model = read_iges(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert_eq!(model.millimetres_per_unit, 1.0);
    assert_eq!(model.faces.len(), 277);
    assert!(model.skipped.is_empty(), "{:?}", model.skipped);
    let revolutions = model
        .faces
        .iter()
        .filter(|f| matches!(f.surface, wavemill::cad::iges::Surface::Revolution { .. }))
        .count();
    assert_eq!(revolutions, 30);
    let holes: usize = model.faces.iter().map(|f| f.holes.len()).sum();
    assert_eq!(holes, 2);
    let mut worst: f64 = 0.0;
    let mut checked = 0;
    for face in &model.faces {
        let (Some(outer), Some(model_curve)) = (&face.outer, face.model_boundaries.first()) else {
            continue;
        };
        let polyline = model_curve.sample(48);
        let on_surface: Vec<Point3<f64>> = outer
            .sample(4)
            .iter()
            .map(|uv| face.surface.point(uv.x, uv.y))
            .collect();
        for p in &on_surface {
            let d = polyline
                .windows(2)
                .map(|w| common::segment_distance(p, &w[0], &w[1]))
                .fold(f64::INFINITY, f64::min);
            worst = worst.max(d);
        }
        checked += 1;
        assert!(matches!(outer, Curve::Composite(_)));
    }
    eprintln!(
        "{checked} outer trims: parameter curves on their surfaces within {worst:.2e} mm of the model curves"
    );
    assert_eq!(checked, 277);
    assert!(worst < 0.02, "{worst}");
}
