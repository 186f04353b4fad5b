//! Tests of the public entry points: the shared test outlines, file handling, and fuzz-style
//! robustness (random bytes and random path data must never panic).

use std::f64::consts::PI;
use std::path::Path;

use proptest::prelude::*;

use super::segmath::winding_number;
use super::test_util::{outlines_dir, total_area};
use super::*;
use crate::contour::geometry::{Contour, Segment};

fn read_file(name: &str) -> Option<Result<Shape, OutlineError>> {
    let dir = outlines_dir()?;
    Some(read_outline(&dir.join(name), &OutlineOptions::default()))
}

fn shoelace(pts: &[(f64, f64)]) -> f64 {
    let n = pts.len();
    (0..n)
        .map(|i| pts[i].0 * pts[(i + 1) % n].1 - pts[(i + 1) % n].0 * pts[i].1)
        .sum::<f64>()
        / 2.0
}

fn inside(outer: &Contour, inner: &Contour) -> bool {
    let segs: Vec<Segment> = outer.segments().collect();
    winding_number(&segs, inner.vertices[0].point) != 0
}

#[test]
fn every_shared_outline_reads_or_fails_clearly() {
    let Some(dir) = outlines_dir() else { return };
    let mut names: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    names.sort();
    let mut seen = 0;
    for path in names {
        let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
        if ext != "svg" && ext != "dxf" {
            continue;
        }
        seen += 1;
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        match read_outline(&path, &OutlineOptions::default()) {
            Ok(shape) => {
                assert!(!shape.contours.is_empty(), "{name}");
                // Region to the left: the total signed area is the region's area, positive.
                assert!(total_area(&shape) > 0.0, "{name}");
                for c in &shape.contours {
                    assert!(c.vertices.len() >= 2 && c.signed_area() != 0.0, "{name}");
                }
            }
            Err(e) => {
                // Only the drawing of overlapping profiles may fail, with a crossing that names
                // the file, both paths and the place.
                let msg = e.to_string();
                assert!(name.starts_with("compfan"), "{name}: {msg}");
                assert!(matches!(e, OutlineError::Crossing { .. }), "{msg}");
                assert!(
                    msg.starts_with(&name)
                        && msg.matches("<path id=").count() == 2
                        && msg.contains(" mm"),
                    "{msg}"
                );
            }
        }
    }
    assert!(seen >= 7);
}

#[test]
fn pycam_polygons_blob_star_and_ellipse() {
    let Some(r) = read_file("pycam_polygons.svg") else {
        return;
    };
    let s = r.unwrap();
    assert_eq!(s.contours.len(), 3);
    let a: Vec<f64> = s.contours.iter().map(|c| c.signed_area()).collect();
    // The star, exactly (its outline is straight lines; y flipped): independent shoelace.
    let star = [
        (129.3125, 158.5625),
        (111.53125, 370.9375),
        (-25.1875, 373.5),
        (171.28125, 456.0625),
        (131.5, 586.875),
        (270.71875, 425.53125),
        (382.84375, 503.78125),
        (249.5625, 350.09375),
        (318.65625, 393.34375),
        (336.875, 284.9375),
    ];
    let star_area = -shoelace(&star);
    assert!(
        (a[1].abs() - star_area.abs()).abs() < 1e-6,
        "{a:?} {star_area}"
    );
    // The blob is a "C" that curls around the star without enclosing it (checked against its
    // own winding): both are outer boundaries (counter-clockwise) and the ellipse is a hole
    // (clockwise) in the star.
    assert!(a[0] > 0.0 && a[1] > 0.0 && a[2] < 0.0, "{a:?}");
    assert!(!inside(&s.contours[0], &s.contours[1]));
    assert!(inside(&s.contours[1], &s.contours[2]));
    assert!((total_area(&s) - (a[0].abs() + star_area.abs() - a[2].abs())).abs() < 1e-6);
    // Same region under the even-odd rule (no same-direction nesting here).
    let text = std::fs::read_to_string(outlines_dir().unwrap().join("pycam_polygons.svg")).unwrap();
    let eo = read_svg_str(
        &text.replace("<path", "<path fill-rule=\"evenodd\""),
        "eo.svg",
        &OutlineOptions::default(),
    )
    .unwrap();
    assert_eq!(eo, s);
}

#[test]
fn mdi_phone_has_a_hole_with_an_island() {
    let Some(r) = read_file("mdi_phone-classic.svg") else {
        return;
    };
    let s = r.unwrap();
    let holes: Vec<&Contour> = s
        .contours
        .iter()
        .filter(|c| c.signed_area() < 0.0)
        .collect();
    assert_eq!(holes.len(), 1);
    let hole = holes[0];
    // The dial: a circle of radius 4 drawn with cubics, and the island of radius 2.5.
    assert!(
        (hole.signed_area() + 16.0 * PI).abs() < 0.05,
        "{}",
        hole.signed_area()
    );
    let islands: Vec<&Contour> = s
        .contours
        .iter()
        .filter(|c| c.signed_area() > 0.0 && inside(hole, c))
        .collect();
    assert_eq!(islands.len(), 1);
    assert!((islands[0].signed_area() - 6.25 * PI).abs() < 0.01);
    // The hole lies inside one of the two outer shapes (the phone body).
    assert_eq!(
        s.contours
            .iter()
            .filter(|c| c.signed_area() > 0.0 && inside(c, hole))
            .count(),
        1
    );
}

#[test]
fn mdi_flower_three_shapes_and_a_hole() {
    let Some(r) = read_file("mdi_flower.svg") else {
        return;
    };
    let s = r.unwrap();
    assert_eq!(s.contours.len(), 4);
    let neg: Vec<f64> = s
        .contours
        .iter()
        .map(|c| c.signed_area())
        .filter(|a| *a < 0.0)
        .collect();
    assert_eq!(neg.len(), 1);
    assert!((neg[0] + 6.25 * PI).abs() < 0.01, "{neg:?}");
}

#[test]
fn rabbit_ignores_viewport_scaling() {
    let Some(r) = read_file("clipper2_rabbit.svg") else {
        return;
    };
    let s = r.unwrap();
    assert_eq!(s.contours.len(), 1);
    let c = &s.contours[0];
    assert!(c.vertices.iter().all(|v| v.bulge == 0.0));
    // viewBox 0 0 300 400 with height 480: user units kept, so y ∈ [−400, 0].
    let (ymin, ymax) = c
        .vertices
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v.point.y), b.max(v.point.y))
        });
    assert!(
        (ymin + 400.0).abs() < 1e-9 && ymax.abs() < 1e-9,
        "{ymin} {ymax}"
    );
    let pts: Vec<(f64, f64)> = c.vertices.iter().map(|v| (v.point.x, v.point.y)).collect();
    assert!((c.signed_area() - shoelace(&pts)).abs() < 1e-9 && c.signed_area() > 0.0);
}

#[test]
fn pycam_dxf_ellipse_and_three_polylines() {
    let Some(r) = read_file("pycam_simple-shapes.dxf") else {
        return;
    };
    let s = r.unwrap();
    assert_eq!(s.contours.len(), 4);
    assert!(s.contours.iter().all(|c| c.signed_area() > 0.0));
    let arcs: Vec<&Contour> = s
        .contours
        .iter()
        .filter(|c| c.vertices.iter().any(|v| v.bulge != 0.0))
        .collect();
    assert_eq!(arcs.len(), 1);
    // Ellipse with major axis (50, −30) and ratio 15/34: area π · 3400 · 15/34 = 1500 π.
    let e = arcs[0];
    assert!(
        (e.signed_area() - 1500.0 * PI).abs() <= 0.001 * e.length(),
        "{}",
        e.signed_area()
    );
    let mut polys: Vec<f64> = s
        .contours
        .iter()
        .filter(|c| c.vertices.iter().all(|v| v.bulge == 0.0))
        .map(|c| c.signed_area())
        .collect();
    polys.sort_by(f64::total_cmp);
    let expected = [
        shoelace(&[(110., 70.), (100., 0.), (160., -10.)]).abs(),
        shoelace(&[(130., 110.), (200., 80.), (200., 50.), (160., 30.)]).abs(),
        4000.0,
    ];
    for (a, b) in polys.iter().zip(expected) {
        assert!((a - b).abs() < 1e-9, "{polys:?} {expected:?}");
    }
}

#[test]
fn file_handling() {
    let dir = std::env::temp_dir().join(format!("outline-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let svg = dir.join("UPPER.SVG");
    std::fs::write(
        &svg,
        r#"<svg xmlns="http://www.w3.org/2000/svg"><circle r="2"/></svg>"#,
    )
    .unwrap();
    let s = read_outline(&svg, &OutlineOptions::default()).unwrap();
    assert!((total_area(&s) - 4.0 * PI).abs() < 1e-12);
    let dxf = dir.join("part.Dxf");
    std::fs::write(
        &dxf,
        "0\nSECTION\n2\nENTITIES\n0\nCIRCLE\n8\n0\n10\n0\n20\n0\n40\n3\n0\nENDSEC\n0\nEOF\n",
    )
    .unwrap();
    let s = read_outline(&dxf, &OutlineOptions::default()).unwrap();
    assert!((total_area(&s) - 9.0 * PI).abs() < 1e-12);
    let txt = dir.join("a.txt");
    std::fs::write(&txt, "x").unwrap();
    assert!(matches!(
        read_outline(&txt, &OutlineOptions::default()),
        Err(OutlineError::UnknownFormat { .. })
    ));
    let empty = dir.join("empty.svg");
    std::fs::write(&empty, "").unwrap();
    let e = read_outline(&empty, &OutlineOptions::default()).unwrap_err();
    assert!(
        matches!(e, OutlineError::Empty { .. }) && e.to_string().starts_with("empty.svg"),
        "{e}"
    );
    let missing = dir.join("missing.dxf");
    assert!(matches!(
        read_outline(&missing, &OutlineOptions::default()),
        Err(OutlineError::Io { .. })
    ));
    // Over the size limit: a sparse file, refused before reading.
    let big = dir.join("big.svg");
    let f = std::fs::File::create(&big).unwrap();
    f.set_len(MAX_FILE_BYTES + 1).unwrap();
    assert!(matches!(
        read_outline(&big, &OutlineOptions::default()),
        Err(OutlineError::TooLarge { .. })
    ));
    let bad = OutlineOptions {
        tolerance: -1.0,
        ..Default::default()
    };
    assert!(matches!(
        read_outline(&svg, &bad),
        Err(OutlineError::Options { .. })
    ));
    std::fs::remove_dir_all(&dir).unwrap();
    let _ = Path::new("");
}

/// Random path data from the SVG grammar's alphabet.
fn path_data() -> impl Strategy<Value = String> {
    let token = prop_oneof![
        proptest::sample::select(vec![
            "M", "m", "L", "l", "H", "h", "V", "v", "C", "c", "S", "s", "Q", "q", "T", "t", "A",
            "a", "Z", "z", ",", " "
        ])
        .prop_map(str::to_string),
        (-1000.0f64..1000.0).prop_map(|v| format!("{v:.3}")),
        proptest::sample::select(vec![
            "0",
            "1",
            "1e308",
            "-1e308",
            "1e-320",
            "NaN",
            "inf",
            ".",
            "-",
            "0 0 0 1 1",
            "1 0 0 0 0"
        ])
        .prop_map(str::to_string),
    ];
    proptest::collection::vec(token, 0..60).prop_map(|t| t.join(" "))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..2000)) {
        let _ = read_dxf_bytes(&bytes, "r.dxf", &OutlineOptions::default());
        let _ = read_svg_str(&String::from_utf8_lossy(&bytes), "r.svg", &OutlineOptions::default());
    }

    #[test]
    fn random_dxf_like_text_never_panics(lines in proptest::collection::vec(
        prop_oneof![
            proptest::sample::select(vec!["0", "SECTION", "2", "ENTITIES", "LINE", "ARC", "CIRCLE", "LWPOLYLINE", "SPLINE", "ELLIPSE",
                "POLYLINE", "VERTEX", "SEQEND", "ENDSEC", "EOF", "10", "20", "11", "21", "40", "42", "70", "71", "72", "73", "90", "8"]).prop_map(str::to_string),
            (-100.0f64..100.0).prop_map(|v| format!("{v}")),
        ], 0..120)) {
        let text = lines.join("\n");
        let _ = read_dxf_bytes(text.as_bytes(), "r.dxf", &OutlineOptions::default());
    }

    #[test]
    fn random_dxf_entities_never_panic(entities in proptest::collection::vec(
        (
            proptest::sample::select(vec!["LINE", "ARC", "CIRCLE", "ELLIPSE", "LWPOLYLINE", "POLYLINE", "SPLINE", "INSERT"]),
            proptest::collection::vec(
                (
                    proptest::sample::select(vec![10, 20, 11, 21, 40, 41, 42, 50, 51, 70, 71, 72, 73, 74, 90, 210, 220, 230]),
                    prop_oneof![
                        (-50.0f64..50.0).prop_map(|v| format!("{v}")),
                        (0i32..12).prop_map(|v| v.to_string()),
                        proptest::sample::select(vec!["0", "1", "-1", "1e308", "NaN", "inf", "6.283185307179586"]).prop_map(str::to_string),
                    ],
                ),
                0..40,
            ),
        ),
        0..6,
    )) {
        let mut text = String::from("0\nSECTION\n2\nENTITIES\n");
        for (kind, pairs) in &entities {
            text += &format!("0\n{kind}\n8\n0\n");
            for (code, value) in pairs {
                text += &format!("{code}\n{value}\n");
            }
            if *kind == "POLYLINE" {
                text += "0\nVERTEX\n10\n1\n20\n2\n42\n0.5\n0\nVERTEX\n10\n3\n20\n-2\n0\nSEQEND\n";
            }
        }
        text += "0\nENDSEC\n0\nEOF\n";
        let r = read_dxf_bytes(text.as_bytes(), "e.dxf", &OutlineOptions::default());
        if std::env::var_os("OUTLINE_FUZZ_TRACE").is_some() {
            eprintln!("dxf-fuzz {}", r.as_ref().map_or_else(|e| format!("{e}"), |s| format!("ok {}", s.contours.len())));
        }
    }

    #[test]
    fn random_svg_shapes_never_panic(shapes in proptest::collection::vec(
        (
            proptest::sample::select(vec!["rect", "circle", "ellipse", "polygon", "polyline", "path", "g", "line"]),
            proptest::collection::vec(
                (
                    proptest::sample::select(vec!["x", "y", "width", "height", "rx", "ry", "cx", "cy", "r", "points", "d", "transform", "fill-rule", "style"]),
                    proptest::sample::select(vec![
                        "0", "5", "-3", "1e308", "50%", "2mm", "auto", "nonsense", "1 2 3 4 5 6", "0,0 10,0 10,10",
                        "M0 0 A 5 5 0 1 1 10 0 Z", "M 0 0 C 10 10 -10 10 0 0 Z", "rotate(45 5 5) skewX(89.9999)", "scale(0)",
                        "matrix(1 2 3 4 5 6)", "evenodd", "display:none", "fill-rule:evenodd",
                    ]),
                ),
                0..8,
            ),
        ),
        0..6,
    )) {
        let mut body = String::new();
        for (kind, attrs) in &shapes {
            // XML forbids repeated attributes: keep the first value of each.
            let mut seen = std::collections::BTreeMap::new();
            for (k, v) in attrs {
                seen.entry(*k).or_insert(*v);
            }
            let a: String = seen.iter().map(|(k, v)| format!(" {k}=\"{v}\"")).collect();
            body += &format!("<{kind}{a}/>");
        }
        let text = format!(r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 100">{body}</svg>"#);
        let r = read_svg_str(&text, "s.svg", &OutlineOptions::default());
        if std::env::var_os("OUTLINE_FUZZ_TRACE").is_some() {
            eprintln!("svg-fuzz {}", r.as_ref().map_or_else(|e| format!("{e}"), |s| format!("ok {}", s.contours.len())));
        }
    }

    #[test]
    fn random_path_data_never_panics(d in path_data(), evenodd in any::<bool>()) {
        let rule = if evenodd { "evenodd" } else { "nonzero" };
        let text = format!(r#"<svg xmlns="http://www.w3.org/2000/svg"><path fill-rule="{rule}" d="{d}"/></svg>"#);
        let _ = read_svg_str(&text, "p.svg", &OutlineOptions::default());
    }

    #[test]
    fn similarity_transforms_keep_rounded_rect_area_exact(
        w in 1.0f64..100.0, h in 1.0f64..100.0, rf in 0.0f64..0.5, angle in -360.0f64..360.0,
        s in 0.1f64..10.0, tx in -100.0f64..100.0, ty in -100.0f64..100.0, flip in any::<bool>(),
    ) {
        let r = rf * w.min(h);
        let sx = if flip { -s } else { s };
        let text = format!(
            r#"<svg xmlns="http://www.w3.org/2000/svg"><g transform="translate({tx} {ty}) rotate({angle})"><rect width="{w}" height="{h}" rx="{r}" transform="scale({sx} {s})"/></g></svg>"#
        );
        let shape = read_svg_str(&text, "r.svg", &OutlineOptions::default()).unwrap();
        let expected = s * s * (w * h - (4.0 - PI) * r * r);
        prop_assert_eq!(shape.contours.len(), 1);
        prop_assert!((total_area(&shape) - expected).abs() <= 1e-9 * expected.max(1.0), "{} vs {}", total_area(&shape), expected);
        // Circular corners stay exact arcs: at most 4 lines and 4 arcs.
        prop_assert!(shape.contours[0].vertices.len() <= 8);
    }

    #[test]
    fn winding_number_matches_a_dense_polygon(
        bulges in proptest::collection::vec(-0.9f64..0.9, 4), px in -12.0f64..12.0, py in -12.0f64..12.0,
    ) {
        // A square with bulged sides; compare with a finely sampled polygon (skip points very
        // close to the boundary, where sampling could disagree).
        let pts = [(-5.0, -5.0), (5.0, -5.0), (5.0, 5.0), (-5.0, 5.0)];
        let c = Contour { vertices: pts.iter().zip(&bulges).map(|(&(x, y), &b)| crate::contour::geometry::Vertex { point: crate::contour::geometry::Point2::new(x, y), bulge: b }).collect() };
        let segs: Vec<Segment> = c.segments().collect();
        let p = crate::contour::geometry::Point2::new(px, py);
        let dist = segs.iter().map(|s| super::segmath::dist_point_segment(p, s)).fold(f64::INFINITY, f64::min);
        prop_assume!(dist > 1e-3);
        let mut poly = Vec::new();
        for s in &segs {
            for k in 0..2000 {
                let q = super::segmath::point_on_segment(s, k as f64 / 2000.0);
                poly.push((q.x - px, q.y - py));
            }
        }
        let mut total = 0.0;
        for i in 0..poly.len() {
            let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
            total += (a.0 * b.1 - a.1 * b.0).atan2(a.0 * b.0 + a.1 * b.1);
        }
        let reference = (total / (2.0 * PI)).round() as i64;
        prop_assert_eq!(winding_number(&segs, p), reference);
        // Points exactly on a chord line through the square's corners are handled too.
        let on_chord = crate::contour::geometry::Point2::new(0.0, -5.0);
        let d0 = segs.iter().map(|s| super::segmath::dist_point_segment(on_chord, s)).fold(f64::INFINITY, f64::min);
        if d0 > 1e-9 {
            let expected = i64::from(bulges[0] > 0.0);
            prop_assert_eq!(winding_number(&segs, on_chord), expected);
        }
    }
}
