//! Lens surfaces from their sources: a TOML description of an analytic surface, or the
//! freeform face of an IGES file (seed 003: "a square freeform patch closed by five planes" —
//! the largest face that is not a plane, or the one the user names by its DE number).

use super::surface::{LensSurface, NurbsLens, SagShape};
use crate::cad::iges::{IgesModel, Surface};

/// A TOML lens description (see the module docs of [`super::surface`] for the formulas):
///
/// ```toml
/// kind = "zernike"      # sphere | asphere | toric | xy-polynomial | zernike
/// radius = 80.0         # vertex radius, mm; + : centre of curvature toward the tool; inf: flat
/// conic = -0.5          # conic constant (asphere, xy-polynomial, zernike)
/// aperture = 40.0       # clear aperture, diameter, mm
/// normalization = 20.0  # xy-polynomial and zernike: the length x, y, r are divided by
/// coefficients = [0.0, 0.0, 0.0, 0.02, 0.01]   # asphere: r⁴, r⁶, …; zernike: Z1, Z2, …
/// terms = [[2, 1, 0.01]]                       # xy-polynomial: [i, j, c] of c xⁱ yʲ
/// # toric: radius_x, radius_y, conic_y instead of radius and conic
/// ```
#[derive(Clone, Debug, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LensDescription {
    /// Surface kind.
    pub kind: String,
    /// Vertex radius (mm).
    pub radius: Option<f64>,
    /// Conic constant.
    pub conic: Option<f64>,
    /// Clear aperture (diameter, mm).
    pub aperture: f64,
    /// Normalisation length (mm).
    pub normalization: Option<f64>,
    /// Asphere or Zernike coefficients.
    pub coefficients: Option<Vec<f64>>,
    /// XY polynomial terms.
    pub terms: Option<Vec<(u32, u32, f64)>>,
    /// Toric: radius of the sweep in XZ.
    pub radius_x: Option<f64>,
    /// Toric: radius of the profile in YZ.
    pub radius_y: Option<f64>,
    /// Toric: conic constant of the profile.
    pub conic_y: Option<f64>,
}

/// `1/R`, with `inf` for flat; 0 and NaN refused.
fn curvature(name: &str, radius: f64) -> Result<f64, String> {
    if radius.is_nan() || radius == 0.0 {
        return Err(format!(
            "{name} = {radius}: a radius must be non-zero (inf for flat)"
        ));
    }
    Ok(if radius.is_infinite() {
        0.0
    } else {
        1.0 / radius
    })
}

impl LensDescription {
    /// Reads a description from TOML text.
    pub fn from_toml(text: &str) -> Result<LensDescription, String> {
        toml::from_str(text).map_err(|e| e.to_string())
    }

    /// The surface it describes; an error names the key that is missing, extra or out of range.
    pub fn surface(&self) -> Result<LensSurface, String> {
        if !(self.aperture.is_finite() && self.aperture > 0.0) {
            return Err(format!(
                "aperture = {}: must be a positive diameter",
                self.aperture
            ));
        }
        let refuse = |key: &str, present: bool| -> Result<(), String> {
            if present {
                Err(format!(
                    "'{key}' does not apply to kind = \"{}\"",
                    self.kind
                ))
            } else {
                Ok(())
            }
        };
        let radius = || -> Result<f64, String> {
            curvature(
                "radius",
                self.radius
                    .ok_or_else(|| format!("kind = \"{}\" needs 'radius'", self.kind))?,
            )
        };
        let normalization = || -> Result<f64, String> {
            let h = self.normalization.ok_or_else(|| {
                format!(
                    "kind = \"{}\" needs 'normalization' (a length, mm)",
                    self.kind
                )
            })?;
            if h.is_finite() && h > 0.0 {
                Ok(h)
            } else {
                Err(format!("normalization = {h}: must be a positive length"))
            }
        };
        let toric_keys =
            self.radius_x.is_some() || self.radius_y.is_some() || self.conic_y.is_some();
        let shape = match self.kind.as_str() {
            "sphere" => {
                refuse("conic", self.conic.is_some())?;
                refuse("coefficients", self.coefficients.is_some())?;
                refuse("terms", self.terms.is_some())?;
                refuse("normalization", self.normalization.is_some())?;
                refuse("radius_x/radius_y/conic_y", toric_keys)?;
                SagShape::Conic {
                    curvature: radius()?,
                    conic: 0.0,
                    even: Vec::new(),
                }
            }
            "asphere" => {
                refuse("terms", self.terms.is_some())?;
                refuse("normalization", self.normalization.is_some())?;
                refuse("radius_x/radius_y/conic_y", toric_keys)?;
                SagShape::Conic {
                    curvature: radius()?,
                    conic: self.conic.unwrap_or(0.0),
                    even: self.coefficients.clone().unwrap_or_default(),
                }
            }
            "toric" => {
                refuse("radius", self.radius.is_some())?;
                refuse("conic", self.conic.is_some())?;
                refuse("coefficients", self.coefficients.is_some())?;
                refuse("terms", self.terms.is_some())?;
                refuse("normalization", self.normalization.is_some())?;
                let need = |key: &str, v: Option<f64>| {
                    v.ok_or_else(|| format!("kind = \"toric\" needs '{key}'"))
                };
                SagShape::Toric {
                    curvature_x: curvature("radius_x", need("radius_x", self.radius_x)?)?,
                    curvature_y: curvature("radius_y", need("radius_y", self.radius_y)?)?,
                    conic_y: self.conic_y.unwrap_or(0.0),
                }
            }
            "xy-polynomial" => {
                refuse("coefficients", self.coefficients.is_some())?;
                refuse("radius_x/radius_y/conic_y", toric_keys)?;
                SagShape::XyPolynomial {
                    curvature: radius()?,
                    conic: self.conic.unwrap_or(0.0),
                    normalization: normalization()?,
                    terms: self
                        .terms
                        .clone()
                        .ok_or("kind = \"xy-polynomial\" needs 'terms' ([i, j, c], …)")?,
                }
            }
            "zernike" => {
                refuse("terms", self.terms.is_some())?;
                refuse("radius_x/radius_y/conic_y", toric_keys)?;
                let coefficients = self
                    .coefficients
                    .clone()
                    .ok_or("kind = \"zernike\" needs 'coefficients' (Z1, Z2, … in Noll's order)")?;
                if coefficients.len() > 231 {
                    return Err(format!(
                        "{} Zernike coefficients: at most 231 (radial order 20)",
                        coefficients.len()
                    ));
                }
                SagShape::Zernike {
                    curvature: radius()?,
                    conic: self.conic.unwrap_or(0.0),
                    normalization: normalization()?,
                    coefficients,
                }
            }
            other => {
                return Err(format!(
                    "kind = \"{other}\": expected sphere, asphere, toric, xy-polynomial or zernike"
                ));
            }
        };
        let all_finite = match &shape {
            SagShape::Conic { conic, even, .. } => {
                conic.is_finite() && even.iter().all(|c| c.is_finite())
            }
            SagShape::Toric { conic_y, .. } => conic_y.is_finite(),
            SagShape::XyPolynomial { conic, terms, .. } => {
                conic.is_finite()
                    && terms
                        .iter()
                        .all(|t| t.2.is_finite() && u64::from(t.0) + u64::from(t.1) <= 40)
            }
            SagShape::Zernike {
                conic,
                coefficients,
                ..
            } => conic.is_finite() && coefficients.iter().all(|c| c.is_finite()),
        };
        if !all_finite {
            return Err(
                "a coefficient is not a finite number (or an xy term's order exceeds 40)".into(),
            );
        }
        let surface = LensSurface::Sag {
            shape,
            aperture: self.aperture,
        };
        // The formula must be defined over the whole aperture (a conic stops where its
        // square root does).
        let r = self.aperture / 2.0;
        for i in 0..=64 {
            for j in 0..=64 {
                let (x, y) = (
                    -r + 2.0 * r * i as f64 / 64.0,
                    -r + 2.0 * r * j as f64 / 64.0,
                );
                if x.hypot(y) <= r && !surface.jet(x, y).point.z.is_finite() {
                    return Err(format!(
                        "the surface is not defined at ({x:.3}, {y:.3}) within the aperture \
                         (the conic's square root is negative there)"
                    ));
                }
            }
        }
        Ok(surface)
    }
}

/// Which IGES face became the lens.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct FaceChoice {
    /// Its DE number.
    pub de: usize,
    /// Its directory line.
    pub line: usize,
    /// Area (mm², sampled).
    pub area: f64,
    /// Faces in the file, and how many of them are planes.
    pub faces: usize,
    /// Planar faces passed over.
    pub planes: usize,
    /// Whether the face was trimmed in the file (the lens takes the whole surface).
    pub trimmed: bool,
}

/// Area and flatness of a surface by sampling `n × n` cells: `(area, planar)`.
fn area_and_flatness(surface: &Surface, n: usize) -> (f64, bool) {
    let ((u0, u1), (v0, v1)) = surface.domain();
    let at = |i: usize, j: usize| {
        surface.point(
            u0 + (u1 - u0) * i as f64 / n as f64,
            v0 + (v1 - v0) * j as f64 / n as f64,
        )
    };
    let mut area = 0.0;
    let mut normal = nalgebra::Vector3::zeros();
    let mut points = Vec::with_capacity((n + 1) * (n + 1));
    for i in 0..=n {
        for j in 0..=n {
            points.push(at(i, j));
        }
    }
    let p = |i: usize, j: usize| points[i * (n + 1) + j];
    for i in 0..n {
        for j in 0..n {
            // Half the cross product of the diagonals: the cell's vector area.
            let cross = (p(i + 1, j + 1) - p(i, j)).cross(&(p(i, j + 1) - p(i + 1, j))) * 0.5;
            area += cross.norm();
            normal += cross;
        }
    }
    let Some(normal) = normal.try_normalize(1e-300) else {
        return (area, false);
    };
    let base = points[0];
    let size = points
        .iter()
        .map(|q| (q - base).norm())
        .fold(0.0, f64::max)
        .max(1e-300);
    let planar = points
        .iter()
        .all(|q| (q - base).dot(&normal).abs() <= 1e-9 * size);
    (area, planar)
}

/// The lens surface of an IGES model: the face with DE number `de`, or the largest face that
/// is not a plane.
pub fn lens_from_iges(
    model: &IgesModel,
    de: Option<usize>,
) -> Result<(LensSurface, FaceChoice), String> {
    let measured: Vec<(usize, f64, bool)> = model
        .faces
        .iter()
        .enumerate()
        .map(|(k, f)| {
            let (area, planar) = area_and_flatness(&f.surface, 24);
            (k, area, planar)
        })
        .collect();
    let planes = measured.iter().filter(|m| m.2).count();
    let chosen = match de {
        Some(de) => {
            let k = model.faces.iter().position(|f| f.de == de).ok_or_else(|| {
                let list: Vec<String> = model.faces.iter().map(|f| f.de.to_string()).collect();
                format!("no face with DE {de}; the faces are DE {}", list.join(", "))
            })?;
            measured[k]
        }
        None => *measured
            .iter()
            .filter(|m| !m.2)
            .max_by(|a, b| a.1.total_cmp(&b.1).then(b.0.cmp(&a.0)))
            .ok_or_else(|| {
                format!(
                    "no freeform face: the file's {} face(s) are all planes",
                    model.faces.len()
                )
            })?,
    };
    let face = &model.faces[chosen.0];
    let Surface::Nurbs { surface, u, v } = &face.surface else {
        return Err(format!(
            "face DE {} (line {}) is a surface of revolution (120); the lens must be a B-spline \
             surface (128)",
            face.de, face.line
        ));
    };
    if !(u.0 < u.1 && v.0 < v.1) {
        return Err(format!(
            "face DE {} (line {}): empty parameter range u {:?}, v {:?}",
            face.de, face.line, u, v
        ));
    }
    let lens = NurbsLens::new(surface.clone(), (*u, *v)).ok_or_else(|| {
        format!(
            "face DE {} (line {}): too many Bézier patches to evaluate",
            face.de, face.line
        )
    })?;
    Ok((
        LensSurface::Nurbs(Box::new(lens)),
        FaceChoice {
            de: face.de,
            line: face.line,
            area: chosen.1,
            faces: model.faces.len(),
            planes,
            trimmed: face.outer.is_some() || !face.holes.is_empty(),
        },
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn descriptions_name_what_is_wrong() {
        let ok =
            LensDescription::from_toml("kind = \"sphere\"\nradius = 50\naperture = 20\n").unwrap();
        assert!(ok.surface().is_ok());
        let cases = [
            ("kind = \"sphere\"\naperture = 20\n", "needs 'radius'"),
            ("kind = \"sphere\"\nradius = 0\naperture = 20\n", "non-zero"),
            (
                "kind = \"sphere\"\nradius = 5\naperture = 20\n",
                "not defined",
            ),
            (
                "kind = \"sphere\"\nradius = 50\nconic = 1\naperture = 20\n",
                "'conic' does not apply",
            ),
            (
                "kind = \"toric\"\nradius_x = 50\naperture = 20\n",
                "needs 'radius_y'",
            ),
            (
                "kind = \"zernike\"\nradius = inf\naperture = 20\ncoefficients = [1]\n",
                "normalization",
            ),
            (
                "kind = \"lens\"\nradius = 50\naperture = 20\n",
                "expected sphere",
            ),
        ];
        for (text, expected) in cases {
            let e = LensDescription::from_toml(text)
                .and_then(|d| d.surface().map(|_| ()))
                .unwrap_err();
            assert!(e.contains(expected), "{text}: {e}");
        }
        let e = LensDescription::from_toml(
            "kind = \"sphere\"\nradius = 50\naperture = 20\ncolour = 1\n",
        )
        .unwrap_err();
        assert!(e.contains("colour"), "{e}");
    }
}
