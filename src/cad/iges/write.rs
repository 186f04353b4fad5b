//! Writing B-spline surfaces (entity 128) as an IGES 5.3 file: the Start, Global, Directory,
//! Parameter and Terminate sections in their fixed 80-column form, millimetres, reals written
//! to round-trip exactly (17 significant digits). Used for the lens surfaces a user can open
//! in CAD (the Piegl–Tiller offset of seed 003) and for test parts.

use std::fmt::Write;

use crate::cad::nurbs::NurbsSurface;

/// A surface's parameter rectangle `((u₀, u₁), (v₀, v₁))`.
pub type ParameterRectangle = ((f64, f64), (f64, f64));

/// A real with a decimal point and 17 significant digits (exact round trip).
fn real(x: f64) -> String {
    if x == 0.0 {
        "0.0".into()
    } else {
        format!("{x:.16E}")
    }
}

/// A Hollerith string.
fn hollerith(s: &str) -> String {
    format!("{}H{s}", s.len())
}

/// Packs tokens into lines of at most `width` characters, each token followed by its delimiter
/// (`,`, the last by `;`); a token never splits across lines.
fn pack(tokens: &[String], width: usize) -> Vec<String> {
    let mut lines = vec![String::new()];
    for (k, t) in tokens.iter().enumerate() {
        let piece = format!("{t}{}", if k + 1 == tokens.len() { ';' } else { ',' });
        let last = lines.last_mut().expect("one line at least");
        if !last.is_empty() && last.len() + piece.len() > width {
            lines.push(piece);
        } else {
            last.push_str(&piece);
        }
    }
    lines
}

/// The 128 entity's parameters of `surface`, on the parameter rectangle `domain`.
fn surface_parameters(surface: &NurbsSurface, domain: ParameterRectangle) -> Vec<String> {
    let [p, q] = surface.degree();
    let (rows, columns) = surface.net_size();
    let (knots_u, knots_v) = surface.knots();
    let points = surface.homogeneous_points();
    let rational = points.iter().any(|h| (h.w - points[0].w).abs() > 0.0);
    let mut t = vec![
        "128".to_string(),
        (rows - 1).to_string(),
        (columns - 1).to_string(),
        p.to_string(),
        q.to_string(),
        "0".into(),
        "0".into(),
        if rational { "0" } else { "1" }.into(),
        "0".into(),
        "0".into(),
    ];
    t.extend(knots_u.iter().map(|&k| real(k)));
    t.extend(knots_v.iter().map(|&k| real(k)));
    // The file's first index (along u) varies fastest.
    for j in 0..columns {
        for i in 0..rows {
            t.push(real(points[i * columns + j].w));
        }
    }
    for j in 0..columns {
        for i in 0..rows {
            let h = points[i * columns + j];
            let c = h.xyz() / h.w;
            t.extend([real(c.x), real(c.y), real(c.z)]);
        }
    }
    let ((u0, u1), (v0, v1)) = domain;
    t.extend([real(u0), real(u1), real(v0), real(v1)]);
    t
}

/// An IGES file holding `surfaces` (each on its parameter rectangle) as independent 128
/// entities, in millimetres. `name` goes into the Start section and the Global file name.
pub fn write_surfaces(surfaces: &[(NurbsSurface, ParameterRectangle)], name: &str) -> String {
    let mut out = String::new();
    let card = |out: &mut String, text: &str, section: char, seq: usize| {
        let _ = writeln!(out, "{text:<72}{section}{seq:>7}");
    };
    // Start.
    let start = format!("{name} (wavemill)");
    let start_lines: Vec<String> = start
        .chars()
        .collect::<Vec<_>>()
        .chunks(72)
        .map(|c| c.iter().collect())
        .collect();
    for (k, line) in start_lines.iter().enumerate() {
        card(&mut out, line, 'S', k + 1);
    }
    // Global.
    let max_coordinate = surfaces
        .iter()
        .flat_map(|(s, _)| {
            s.homogeneous_points()
                .iter()
                .map(|h| (h.xyz() / h.w).amax())
        })
        .fold(1.0, f64::max);
    let file_name: String = name.chars().filter(|c| c.is_ascii_graphic()).collect();
    let file_name = if file_name.is_empty() {
        "lens".to_string()
    } else {
        file_name
    };
    let global = [
        hollerith(","),
        hollerith(";"),
        hollerith("wavemill"),
        hollerith(&file_name),
        hollerith("wavemill"),
        hollerith(env!("CARGO_PKG_VERSION")),
        "32".into(),
        "38".into(),
        "6".into(),
        "308".into(),
        "15".into(),
        hollerith("wavemill"),
        "1.0".into(),
        "2".into(),
        hollerith("MM"),
        "1".into(),
        "0.0".into(),
        // A fixed stamp: the same surfaces give the same bytes.
        hollerith("20000101.000000"),
        "1.0E-9".into(),
        real(max_coordinate),
        hollerith("wavemill"),
        hollerith("wavemill"),
        "11".into(),
        "0".into(),
        hollerith("20000101.000000"),
    ];
    let global_lines = pack(&global, 72);
    for (k, line) in global_lines.iter().enumerate() {
        card(&mut out, line, 'G', k + 1);
    }
    // Parameter lines first (the directory points into them).
    let mut directory = String::new();
    let mut parameter = String::new();
    let mut p_seq = 1;
    for (k, (surface, domain)) in surfaces.iter().enumerate() {
        let de = 2 * k + 1;
        let lines = pack(&surface_parameters(surface, *domain), 64);
        let _ = writeln!(
            directory,
            "{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}D{:>7}",
            128, p_seq, 0, 0, 0, 0, 0, 0, "00000000", de
        );
        let _ = writeln!(
            directory,
            "{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}D{:>7}",
            128,
            0,
            0,
            lines.len(),
            0,
            "",
            "",
            format!("LENS{}", k + 1),
            0,
            de + 1
        );
        for line in &lines {
            let _ = writeln!(parameter, "{line:<64} {de:>7}P{p_seq:>7}");
            p_seq += 1;
        }
    }
    out.push_str(&directory);
    out.push_str(&parameter);
    let _ = writeln!(
        out,
        "{:<72}T{:>7}",
        format!(
            "S{:>7}G{:>7}D{:>7}P{:>7}",
            start_lines.len(),
            global_lines.len(),
            2 * surfaces.len(),
            p_seq - 1
        ),
        1
    );
    out
}

#[cfg(test)]
mod tests {
    use nalgebra::Point3;

    use super::*;
    use crate::cad::iges::{Surface, read_iges};

    /// A rational bicubic written and read back is the same surface (knots and weights to the
    /// last bit).
    #[test]
    fn surfaces_round_trip_exactly() {
        let net: Vec<Vec<Point3<f64>>> = (0..5)
            .map(|i| {
                (0..4)
                    .map(|j| {
                        let (x, y) = (i as f64 * 2.5 - 5.0, j as f64 * 3.0 - 4.5);
                        Point3::new(x, y, 0.1 * x * y + 1.0 / 3.0)
                    })
                    .collect()
            })
            .collect();
        let weights: Vec<Vec<f64>> = (0..5)
            .map(|i| {
                (0..4)
                    .map(|j| 1.0 + 0.1 * ((i + 2 * j) % 3) as f64)
                    .collect()
            })
            .collect();
        let surface = NurbsSurface::new(
            [3, 2],
            vec![0.0, 0.0, 0.0, 0.0, 0.4, 1.0, 1.0, 1.0, 1.0],
            vec![0.0, 0.0, 0.0, 0.7, 1.0, 1.0, 1.0],
            &net,
            &weights,
        )
        .unwrap();
        let plane = NurbsSurface::new(
            [1, 1],
            vec![0.0, 0.0, 1.0, 1.0],
            vec![0.0, 0.0, 1.0, 1.0],
            &[
                vec![Point3::new(0.0, 0.0, -1.0), Point3::new(0.0, 1.0, -1.0)],
                vec![Point3::new(1.0, 0.0, -1.0), Point3::new(1.0, 1.0, -1.0)],
            ],
            &[vec![1.0, 1.0], vec![1.0, 1.0]],
        )
        .unwrap();
        let text = write_surfaces(
            &[
                (surface.clone(), ((0.0, 1.0), (0.0, 1.0))),
                (plane.clone(), ((0.0, 1.0), (0.0, 1.0))),
            ],
            "test lens",
        );
        assert!(
            text.lines().all(|l| l.len() == 80),
            "every card is 80 columns"
        );
        let model = read_iges(&text).unwrap();
        assert_eq!(model.faces.len(), 2);
        assert_eq!(model.millimetres_per_unit, 1.0);
        match &model.faces[0].surface {
            Surface::Nurbs { surface: s, u, v } => {
                // Knots and weights exactly; points to the rounding of w·(h/w).
                assert_eq!(s.degree(), surface.degree());
                assert_eq!(s.knots(), surface.knots());
                for (a, b) in s
                    .homogeneous_points()
                    .iter()
                    .zip(surface.homogeneous_points())
                {
                    assert_eq!(a.w, b.w);
                    assert!((a - b).amax() <= 1e-15 * b.amax());
                }
                assert_eq!((*u, *v), ((0.0, 1.0), (0.0, 1.0)));
            }
            other => panic!("{other:?}"),
        }
        match &model.faces[1].surface {
            Surface::Nurbs { surface: s, .. } => assert_eq!(s, &plane),
            other => panic!("{other:?}"),
        }
    }
}
