//! Properties of the multiresolution planner on small shapes with known geometry.

use super::*;
use crate::contour::geometry::Vertex;
use crate::contour::parallel::tests::rect;
use crate::contour::parallel::{ParallelOptions, contour_parallel};
use crate::contour::verify::{clearance, path_stats, uncut_area};

/// A "mountain" range: a base with five peaks of different heights, some rounded.
pub(crate) fn mountain() -> Shape {
    let mut v = vec![Vertex::line(0.0, 0.0), Vertex::line(100.0, 0.0)];
    let peaks = [
        (90.0, 30.0),
        (80.0, 14.0),
        (70.0, 40.0),
        (58.0, 20.0),
        (45.0, 48.0),
        (30.0, 18.0),
        (18.0, 35.0),
        (8.0, 12.0),
    ];
    v.push(Vertex::line(100.0, 10.0));
    for (i, (x, y)) in peaks.iter().enumerate() {
        // Every other vertex starts a slightly curved segment.
        let bulge = if i % 2 == 0 { 0.15 } else { 0.0 };
        v.push(Vertex {
            point: Point2::new(*x, *y),
            bulge,
        });
    }
    v.push(Vertex::line(0.0, 8.0));
    Shape {
        contours: vec![Contour { vertices: v }],
    }
}

fn stock_around(part: &Shape, margin: f64) -> Shape {
    let pts: Vec<Point2> = hull::enclosing_points(part);
    let (mut lo, mut hi) = (pts[0], pts[0]);
    for p in &pts {
        lo = Point2::new(lo.x.min(p.x), lo.y.min(p.y));
        hi = Point2::new(hi.x.max(p.x), hi.y.max(p.y));
    }
    Shape {
        contours: vec![rect(
            lo.x - margin,
            lo.y - margin,
            hi.x + margin,
            hi.y + margin,
            true,
        )],
    }
}

fn transformed(shape: &Shape, angle: f64, mirror: bool) -> Shape {
    let (s, c) = angle.sin_cos();
    let contours = shape
        .contours
        .iter()
        .map(|ct| {
            let mut vs: Vec<Vertex> = ct
                .vertices
                .iter()
                .map(|v| {
                    let x = if mirror { -v.point.x } else { v.point.x };
                    Vertex {
                        point: Point2::new(c * x - s * v.point.y, s * x + c * v.point.y),
                        bulge: if mirror { -v.bulge } else { v.bulge },
                    }
                })
                .collect();
            if mirror {
                // Mirroring flips the orientation: reverse, moving each bulge to its segment's
                // new start vertex.
                let n = vs.len();
                let bulges: Vec<f64> = vs.iter().map(|v| v.bulge).collect();
                vs.reverse();
                for (i, v) in vs.iter_mut().enumerate() {
                    // New segment i runs from old vertex n−1−i to old vertex n−2−i: the old
                    // segment n−2−i reversed.
                    v.bulge = -bulges[(2 * n - 2 - i) % n];
                }
            }
            Contour { vertices: vs }
        })
        .collect();
    Shape { contours }
}

struct Measured {
    clearance: f64,
    uncut: f64,
    length: f64,
    segments: usize,
}

fn measure(path: &CenterPath, part: &Shape, stock: &Shape) -> Measured {
    let c = clearance(path, part).expect("clearance");
    let u = uncut_area(path, part, stock, Some(0.05)).expect("uncut");
    let st = path_stats(path);
    Measured {
        clearance: c.clearance,
        uncut: u.uncut,
        length: st.cut_length,
        segments: st.segments,
    }
}

/// No overcut, and no more uncut area than the baseline `b` up to one 0.05 mm scanline row
/// across a stock `width` mm wide.
fn assert_covered_as_well(m: &Measured, b: &Measured, width: f64) {
    assert!(m.clearance >= -1e-6, "overcut {}", m.clearance);
    assert!(
        m.uncut <= b.uncut + 0.05 * width,
        "uncut {} vs {}",
        m.uncut,
        b.uncut
    );
}

#[test]
fn mountain_no_overcut_no_more_uncut() {
    let part = mountain();
    let stock = stock_around(&part, 10.0);
    let (r, s) = (3.0, 2.4);
    let plan = multires_paths(&part, &stock, &MultiresOptions::new(r, s)).expect("plan");
    let base = contour_parallel(&part, &stock, &ParallelOptions::new(r, s)).expect("baseline");
    let (m, b) = (
        measure(&plan.path, &part, &stock),
        measure(&base, &part, &stock),
    );
    eprintln!(
        "mountain: length {:.1} vs {:.1}, segments {} vs {}, uncut {:.2} vs {:.2}, {:?}",
        m.length, b.length, m.segments, b.segments, m.uncut, b.uncut, plan.report
    );
    assert!(m.clearance >= -1e-6, "overcut {}", m.clearance);
    assert!(b.clearance >= -1e-6);
    // One row of the scanline is 0.05 mm: allow that much area per mm of stock width.
    assert!(
        m.uncut <= b.uncut + 0.05 * 130.0,
        "uncut {} vs {}",
        m.uncut,
        b.uncut
    );
    assert!(plan.report.hull_levels > 0 && plan.report.part_levels > 0);
    // The finishing pass is the exact offset at r: the path touches r somewhere.
    assert!(m.clearance <= 1e-6);
    eprintln!(
        "mountain: length {:.1} vs {:.1}, segments {} vs {}, uncut {:.2} vs {:.2}, {:?}",
        m.length, b.length, m.segments, b.segments, m.uncut, b.uncut, plan.report
    );
}

/// Far side first across the hull: a part level cut off at the loose hull waits for the hull
/// passes outside it, so it is entered next to cleared stock — no plunge goes straight down
/// into uncut material (more than half the tool's disc), and the passes remove what the
/// exact measure says they do.
#[test]
fn part_levels_wait_for_the_hull_passes() {
    let part = mountain();
    let stock = stock_around(&part, 10.0);
    let (r, s) = (3.0, 2.4);
    let plan = multires_paths(&part, &stock, &MultiresOptions::new(r, s)).expect("plan");
    let e = crate::contour::material::engagement(&plan.path, &part, &stock, 0.05, r)
        .expect("engagement");
    let half_disc = 0.5 * std::f64::consts::PI * r * r;
    assert!(
        e.entry_max <= 1.05 * half_disc,
        "a plunge into {} mm² of stock at {:?}",
        e.entry_max,
        e.entry_max_at
    );
    let u = uncut_area(&plan.path, &part, &stock, Some(0.05)).expect("uncut");
    let exact = u.region - u.uncut;
    assert!(
        (e.removed_area() - exact).abs() < 0.005 * exact,
        "{e:?} vs {exact}"
    );
}

#[test]
fn loose_hull_encloses_the_part_with_no_more_legs() {
    let part = mountain();
    let plan = multires_paths(
        &part,
        &stock_around(&part, 8.0),
        &MultiresOptions::new(3.0, 2.4),
    )
    .expect("plan");
    assert!(plan.report.loose_hull_legs <= plan.report.hull_legs);
    let hull = &plan.loose_hull;
    let n = hull.len();
    for p in hull::enclosing_points(&part) {
        for i in 0..n {
            let (a, b) = (hull[i], hull[(i + 1) % n]);
            assert!(
                crate::contour::segops::cross(b - a, p - a) >= -1e-9,
                "{p:?} outside"
            );
        }
    }
}

#[test]
fn rotation_and_mirroring_keep_the_figures() {
    let part = mountain();
    let (r, s) = (3.0, 2.4);
    let opts = MultiresOptions::new(r, s);
    let stock = stock_around(&part, 10.0);
    let plan = multires_paths(&part, &stock, &opts).expect("plan");
    let m0 = measure(&plan.path, &part, &stock);
    for (angle, mirror) in [
        (37f64.to_radians(), false),
        (0.0, true),
        (37f64.to_radians(), true),
    ] {
        let p = transformed(&part, angle, mirror);
        // The stock turns with the part (a rectangle around the turned part would be another
        // problem).
        let st = transformed(&stock, angle, mirror);
        assert!(p.contours[0].signed_area() > 0.0);
        let plan = multires_paths(&p, &st, &opts).expect("plan");
        let m = measure(&plan.path, &p, &st);
        assert!(
            m.clearance >= -1e-6,
            "{angle} {mirror}: overcut {}",
            m.clearance
        );
        assert!(
            (m.length - m0.length).abs() <= 0.03 * m0.length,
            "{angle} {mirror}: length {} vs {}",
            m.length,
            m0.length
        );
        let ds = m.segments.abs_diff(m0.segments) as f64;
        assert!(
            ds <= 0.1 * m0.segments as f64,
            "{angle} {mirror}: segments {} vs {}",
            m.segments,
            m0.segments
        );
        assert!(
            (m.uncut - m0.uncut).abs() <= 0.02 * 130.0 * 80.0 * 0.01 + 0.1 * m0.uncut,
            "{angle} {mirror}: uncut {} vs {}",
            m.uncut,
            m0.uncut
        );
    }
}

#[test]
fn same_input_same_path() {
    let part = mountain();
    let stock = stock_around(&part, 6.0);
    let opts = MultiresOptions::new(2.0, 1.5);
    let a = multires_paths(&part, &stock, &opts).expect("plan");
    let b = multires_paths(&part, &stock, &opts).expect("plan");
    assert_eq!(a, b);
}

#[test]
fn options_are_validated() {
    let part = mountain();
    let stock = stock_around(&part, 6.0);
    let mut o = MultiresOptions::new(2.0, 1.5);
    o.tolerance = Some(f64::NAN);
    let e = multires_paths(&part, &stock, &o).unwrap_err();
    assert!(e.to_string().contains("tolerance"), "{e}");
    let e = multires_paths(&part, &stock, &MultiresOptions::new(2.0, 5.0)).unwrap_err();
    assert!(e.to_string().contains("stepover"), "{e}");
}

/// A part outlined by many short lines (as from a scanned or finely tessellated drawing): its
/// offsets have hundreds of segments, the wavelet approximation replaces them by a few arcs
/// within the band, and the path still never cuts the part nor leaves more material.
#[test]
fn many_segment_part_gets_wavelet_passes() {
    let part = lobed_part();
    let stock = stock_around(&part, 8.0);
    let (r, s) = (3.0, 2.0);
    let plan = multires_paths(&part, &stock, &MultiresOptions::new(r, s)).expect("plan");
    let rep = &plan.report;
    // Deep bays between the lobes: several part levels inside the hull, simplified.
    assert!(rep.part_levels >= 3 && rep.wavelet_loops >= 2, "{rep:?}");
    assert!(rep.used_segments < rep.exact_segments, "{rep:?}");
    assert!((rep.tolerance - 0.5).abs() < 1e-12);
    let base = contour_parallel(&part, &stock, &ParallelOptions::new(r, s)).expect("baseline");
    let (m, b) = (
        measure(&plan.path, &part, &stock),
        measure(&base, &part, &stock),
    );
    assert_covered_as_well(&m, &b, 100.0);
    assert!(m.segments < b.segments, "{} vs {}", m.segments, b.segments);
}

/// The wavy many-segment part of [`many_segment_part_gets_wavelet_passes`].
fn lobed_part() -> Shape {
    let vertices: Vec<Vertex> = (0..360)
        .map(|k| {
            let a = k as f64 * std::f64::consts::TAU / 360.0;
            let rho = 30.0 + 10.0 * (5.0 * a).sin();
            Vertex::line(rho * a.cos(), rho * a.sin())
        })
        .collect();
    Shape {
        contours: vec![Contour { vertices }],
    }
}

#[test]
fn adaptive_levels_close_every_gap_to_the_limit() {
    // No gap beyond the limit: no curve (the default band gives s + 2τ = r exactly).
    assert!(adaptive_levels(3.0, 3.0 + 3.0, 3.0, 0.3).is_empty());
    assert!(adaptive_levels(3.0, 5.9, 3.0, 0.0).is_empty());
    for (from, to, limit, band) in [
        (3.0, 7.5, 3.0, 0.0),
        (3.0, 7.5, 3.0, 0.3),
        (5.0, 19.0, 3.0, 0.9),
        (2.0, 2.0 + 6.01, 3.0, 0.1),
    ] {
        let u = adaptive_levels(from, to, limit, band);
        assert!(!u.is_empty());
        // Each step from the farthest-in crossing of one curve to the farthest-out crossing
        // of the next stays within the limit, and the levels increase.
        let mut lows = vec![from];
        let mut highs = Vec::new();
        for &x in &u {
            lows.push(x - band);
            highs.push(x + band);
        }
        highs.push(to);
        for (lo, hi) in lows.iter().zip(&highs) {
            assert!(
                hi - lo <= limit * (1.0 + 1e-12),
                "{from} {to} {band}: {u:?}"
            );
            assert!(hi > lo);
        }
        // No more curves than needed: one fewer would leave a step beyond the limit.
        let n = u.len() as f64;
        assert!(
            (n - 1.0) * (limit - 2.0 * band) < to - from - limit,
            "{u:?}"
        );
        // Eq. 3.3 for exact curves and s = r: n = ⌈(e₁ + e₂)/r⌉.
        if band == 0.0 {
            let (r, e_sum) = (limit, (to - from) - limit);
            assert_eq!(u.len(), (e_sum / r).ceil() as usize);
        }
    }
}

#[test]
fn default_band_needs_no_adaptive_curve() {
    let part = lobed_part();
    let stock = stock_around(&part, 8.0);
    let plan = multires_paths(&part, &stock, &MultiresOptions::new(3.0, 2.0)).expect("plan");
    let rep = &plan.report;
    assert_eq!(rep.adaptive_curves, 0, "{rep:?}");
    assert!(
        rep.max_deviation > 0.0 && rep.max_deviation <= rep.tolerance,
        "{rep:?}"
    );
}

/// With a band wider than (r − s)/2 the passes drift apart by more than r: the adaptive curves
/// of eq. 3.3 fill the gaps, exactly checked like every pass — no overcut, no more uncut area
/// than the baseline.
#[test]
fn wide_band_inserts_adaptive_curves_without_losing_coverage() {
    let part = lobed_part();
    let stock = stock_around(&part, 8.0);
    let (r, s) = (3.0, 2.6);
    let mut opts = MultiresOptions::new(r, s);
    opts.tolerance = Some(1.5);
    let plan = multires_paths(&part, &stock, &opts).expect("plan");
    let rep = &plan.report;
    assert!(rep.adaptive_curves > 0 && rep.adaptive_loops > 0, "{rep:?}");
    // Beyond the default band (r − s)/2 = 0.2 mm.
    assert!(rep.max_deviation > 0.2, "{rep:?}");
    let base = contour_parallel(&part, &stock, &ParallelOptions::new(r, s)).expect("baseline");
    let (m, b) = (
        measure(&plan.path, &part, &stock),
        measure(&base, &part, &stock),
    );
    eprintln!(
        "wide band: length {:.1} vs {:.1}, segments {} vs {}, uncut {:.3} vs {:.3}, {rep:?}",
        m.length, b.length, m.segments, b.segments, m.uncut, b.uncut
    );
    assert_covered_as_well(&m, &b, 100.0);
}
