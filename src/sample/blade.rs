//! The sample turbine blade on its root block (see [`super::blade()`] and [`BladeParams`]).
//!
//! Geometry: the root block is the box [−x/2, x/2] × [−y/2, y/2] × [0, z]. The airfoil is a
//! NACA-4-like section of unit chord with half thickness
//! y_t(x) = 5τ(0.2969√x − 0.1260x − 0.3516x² + 0.2843x³ − 0.1036x⁴)
//! (the closed-trailing-edge variant) and the NACA 4-digit mean line y_c(x) with maximum
//! camber m at 40 % chord. The thickness is applied vertically (y = y_c ± y_t), so the section
//! area is exactly c² τ ∫₀¹ 2y_t/τ dx. At span fraction σ the section is scaled to the chord
//! c(σ) (linear from root to tip), centred on mid-chord, rotated about +Z by σ · twist, and
//! placed at z = z_block + σ · span.
//!
//! Perimeter points are placed once on the unit airfoil, by arc length with a spacing that
//! follows the curvature near the leading edge (down to resolution/4) and is graded smoothly;
//! every section reuses them, so the blade is a loft of equal-length loops. The sharp trailing
//! edge is always a vertex.
//!
//! Mesh: the block's sides are a loft of its rectangular outline; its bottom is a CDT of the
//! rectangle with a staggered Steiner grid; its top is a CDT of the rectangle with the blade's
//! root section as a hole (the same vertices as the blade loft's first loop) and the grid
//! thinned around it; the tip is a CDT of the tip section. One closed 2-manifold of genus 0.

use std::f64::consts::PI;

use nalgebra::Point3;

use super::builder::MeshBuilder;
use super::cdt::triangulate_region;
use super::loft::loft;
use super::poly::{self, ArcTable, Obstacles, P2};
use super::{BladeParams, MAX_TRIANGLES, SampleError, bounded, invalid, positive};
use crate::mesh::Mesh;

/// Chordwise position of maximum camber (NACA `p`).
const CAMBER_POSITION: f64 = 0.4;
/// Top-face Steiner points keep at least this many `resolution`s from the blade.
const STEINER_CLEARANCE: f64 = 0.6;
/// Perimeter spacing near the leading edge: `CURVATURE_SPACING` × radius of curvature, but
/// never below resolution × `MIN_SPACING`.
const CURVATURE_SPACING: f64 = 0.8;
const MIN_SPACING: f64 = 0.25;
/// How fast the perimeter spacing may grow per unit length.
const GRADING: f64 = 0.4;
/// Samples of the dense unit-airfoil table.
const FINE: usize = 4000;

/// The unit-chord NACA-4-like airfoil.
#[derive(Debug)]
pub(super) struct Airfoil {
    /// Thickness ratio τ.
    pub(super) tau: f64,
    /// Maximum camber m.
    pub(super) camber: f64,
}

impl Airfoil {
    /// ∫₀¹ 2 y_t(x)/τ dx: the unit section's area per unit thickness ratio.
    #[cfg(test)]
    pub(super) const AREA_FACTOR: f64 =
        10.0 * (0.2969 * 2.0 / 3.0 - 0.1260 / 2.0 - 0.3516 / 3.0 + 0.2843 / 4.0 - 0.1036 / 5.0);

    fn half_thickness(&self, x: f64) -> f64 {
        let x = x.clamp(0.0, 1.0);
        5.0 * self.tau
            * (0.2969 * x.sqrt() + x * (-0.1260 + x * (-0.3516 + x * (0.2843 - 0.1036 * x))))
    }

    fn mean_line(&self, x: f64) -> f64 {
        let (m, p) = (self.camber, CAMBER_POSITION);
        if x < p {
            m / (p * p) * (2.0 * p * x - x * x)
        } else {
            m / ((1.0 - p) * (1.0 - p)) * (1.0 - 2.0 * p + 2.0 * p * x - x * x)
        }
    }

    /// Perimeter point for λ ∈ [0, 2]: trailing edge at 0, upper surface to the leading edge
    /// at 1, lower surface back to the trailing edge at 2 (counter-clockwise).
    fn point(&self, lam: f64) -> P2 {
        if lam <= 1.0 {
            let x = 0.5 * (1.0 + (PI * lam).cos());
            [x, self.mean_line(x) + self.half_thickness(x)]
        } else {
            let x = 0.5 * (1.0 - (PI * (lam - 1.0)).cos());
            [x, self.mean_line(x) - self.half_thickness(x)]
        }
    }

    /// Perimeter parameters λ of the section vertices for a chord of `chord` mm at
    /// `resolution`: spacing ≈ resolution, finer where the curvature is high. λ = 0 first.
    fn perimeter(&self, chord: f64, res: f64) -> Vec<f64> {
        let lam = |i: usize| 2.0 * i as f64 / FINE as f64;
        let pts: Vec<P2> = (0..=FINE)
            .map(|i| {
                let q = self.point(lam(i));
                [q[0] * chord, q[1] * chord]
            })
            .collect();
        let dist = |a: P2, b: P2| ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt();
        let seg: Vec<f64> = pts.windows(2).map(|w| dist(w[0], w[1])).collect();
        // Desired spacing from the circumradius of consecutive samples (not at the corner).
        let mut size = vec![res; FINE + 1];
        for i in 1..FINE {
            let (a, b, c) = (pts[i - 1], pts[i], pts[i + 1]);
            let area2 = ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])).abs();
            if area2 > 0.0 {
                let rho = dist(a, b) * dist(b, c) * dist(a, c) / (2.0 * area2);
                size[i] = (CURVATURE_SPACING * rho).clamp(MIN_SPACING * res, res);
            }
        }
        for _ in 0..2 {
            for i in 1..=FINE {
                size[i] = size[i].min(size[i - 1] + GRADING * seg[i - 1]);
            }
            for i in (0..FINE).rev() {
                size[i] = size[i].min(size[i + 1] + GRADING * seg[i]);
            }
            size[0] = size[0].min(size[FINE]);
            size[FINE] = size[0];
        }
        // Cumulative ∫ ds / size, then equal steps of it.
        let mut acc = vec![0.0; FINE + 1];
        for i in 0..FINE {
            acc[i + 1] = acc[i] + seg[i] * 0.5 * (1.0 / size[i] + 1.0 / size[i + 1]);
        }
        let total = acc[FINE];
        let n = (total.ceil() as usize).max(8);
        (0..n)
            .map(|k| {
                let target = total * k as f64 / n as f64;
                let i = acc.partition_point(|&a| a < target).clamp(1, FINE);
                let f = (target - acc[i - 1]) / (acc[i] - acc[i - 1]);
                lam(i - 1) + f.clamp(0.0, 1.0) * (lam(i) - lam(i - 1))
            })
            .collect()
    }
}

/// Validated blade geometry plus its discretisation.
#[derive(Debug)]
pub(super) struct Blade {
    span: f64,
    chords: [f64; 2],
    twist: f64,
    block: [f64; 3],
    res: f64,
    /// Unit-airfoil section points (counter-clockwise, trailing edge first).
    unit: Vec<P2>,
    levels: usize,
}

impl Blade {
    /// Validates `p` and computes the section discretisation.
    pub(super) fn new(p: &BladeParams) -> Result<Self, SampleError> {
        let span = positive("span", p.span)?;
        let c0 = positive("root_chord", p.root_chord)?;
        let c1 = positive("tip_chord", p.tip_chord)?;
        let tau = positive("thickness_ratio", p.thickness_ratio)?;
        if tau > 0.3 {
            return Err(invalid(
                "thickness_ratio",
                format!("must be at most 0.3, got {tau}"),
            ));
        }
        let camber = bounded("camber_ratio", p.camber_ratio, 0.1)?;
        let twist = bounded("twist_deg", p.twist_deg, 180.0)?.to_radians();
        let mut block = [0.0; 3];
        for (k, &s) in p.root_block.iter().enumerate() {
            block[k] = positive("root_block", s)?;
        }
        let res = positive("resolution", p.resolution)?;
        let limit = c0.min(c1) / 4.0;
        if res > limit {
            return Err(invalid(
                "resolution",
                format!("must be at most min(root_chord, tip_chord)/4 = {limit}, got {res}"),
            ));
        }
        if !(0.25..=4.0).contains(&(c1 / c0)) {
            return Err(invalid(
                "tip_chord",
                format!("must be within 0.25…4 × root_chord ({c0}), got {c1}"),
            ));
        }
        // The loft joins section points straight up; keep its surface slope from twist ≤ 45°.
        let twist_slope = twist.abs() * 0.5 * c0.max(c1) / span;
        if twist_slope > 1.0 {
            return Err(invalid(
                "twist_deg",
                format!(
                    "{} degrees over a span of {span} mm shears the blade's edges by more than \
                     45° (limit {:.1} degrees)",
                    p.twist_deg,
                    (span / (0.5 * c0.max(c1))).to_degrees()
                ),
            ));
        }
        let airfoil = Airfoil { tau, camber };
        let c_max = c0.max(c1);
        let perimeter = ArcTable::new(0.0, 2.0, FINE, |l| {
            let q = airfoil.point(l);
            [q[0] * c_max, q[1] * c_max]
        })
        .length();
        let levels = (span / res).ceil().max(1.0);
        let face = block[0] * block[1] / (0.433 * res * res);
        let sides = 4.0 * (block[0] + block[1]) * block[2] / (res * res);
        let blade = 2.0 * 2.0 * perimeter / res * (levels + 1.0);
        if 2.0 * face + sides + blade > MAX_TRIANGLES {
            return Err(invalid(
                "resolution",
                format!(
                    "{res} mm would give about {:.0} triangles (limit {MAX_TRIANGLES:.0})",
                    2.0 * face + sides + blade
                ),
            ));
        }
        let unit: Vec<P2> = airfoil
            .perimeter(c_max, res)
            .into_iter()
            .map(|l| airfoil.point(l))
            .collect();
        let me = Self {
            span,
            chords: [c0, c1],
            twist,
            block,
            res,
            unit,
            levels: levels as usize,
        };
        for sigma in [0.0, 1.0] {
            if !poly::polygon_is_simple(&me.section(sigma)) {
                return Err(invalid(
                    "thickness_ratio",
                    "the airfoil section folds over itself",
                ));
            }
        }
        let (hx, hy, margin) = (block[0] / 2.0, block[1] / 2.0, 0.5 * res);
        if me
            .section(0.0)
            .iter()
            .any(|q| q[0].abs() > hx - margin || q[1].abs() > hy - margin)
        {
            return Err(invalid(
                "root_block",
                format!(
                    "the root section (chord {c0}) must fit on the block's top face with a \
                     margin of resolution/2 = {margin}"
                ),
            ));
        }
        Ok(me)
    }

    /// The section at span fraction `sigma`, in (x, y).
    fn section(&self, sigma: f64) -> Vec<P2> {
        let c = self.chords[0] + (self.chords[1] - self.chords[0]) * sigma;
        let (s, co) = (self.twist * sigma).sin_cos();
        self.unit
            .iter()
            .map(|q| {
                let (x, y) = (c * (q[0] - 0.5), c * q[1]);
                [co * x - s * y, s * x + co * y]
            })
            .collect()
    }

    /// Builds the mesh.
    pub(super) fn build(&self) -> Result<Mesh, SampleError> {
        let res = self.res;
        let [bx, by, bz] = self.block;
        let (hx, hy) = (bx / 2.0, by / 2.0);
        let mut b = MeshBuilder::default();

        // Block outline, counter-clockwise from (−x, −y); edges split evenly.
        let (nx, ny) = (
            (bx / res).ceil().max(1.0) as usize,
            (by / res).ceil().max(1.0) as usize,
        );
        let corners = [[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy]];
        let mut outline: Vec<P2> = Vec::with_capacity(2 * (nx + ny));
        for (k, &a) in corners.iter().enumerate() {
            let e = corners[(k + 1) % 4];
            let n = if k % 2 == 0 { nx } else { ny };
            for i in 0..n {
                let f = i as f64 / n as f64;
                outline.push([a[0] + f * (e[0] - a[0]), a[1] + f * (e[1] - a[1])]);
            }
        }
        let nz = (bz / res).ceil().max(1.0) as usize;
        let rings = (0..=nz)
            .map(|l| {
                let z = if l == nz {
                    bz
                } else {
                    bz * l as f64 / nz as f64
                };
                b.vertex_loop(outline.iter().map(|q| Point3::new(q[0], q[1], z)))
            })
            .collect::<Result<Vec<_>, _>>()?;
        for pair in rings.windows(2) {
            loft(&mut b, &pair[0], &pair[1]);
        }

        // Staggered grid of Steiner points over the rectangle.
        let rows = (by / (res * 0.75f64.sqrt())).ceil().max(2.0) as usize;
        let grid = |keep: &dyn Fn(P2) -> bool| -> Vec<P2> {
            let mut out = Vec::new();
            for j in 1..rows {
                let y = -hy + by * j as f64 / rows as f64;
                let (shift, count) = if j % 2 == 0 { (0.0, nx - 1) } else { (0.5, nx) };
                for i in 0..count {
                    let x = -hx + bx * (i as f64 + 1.0 - shift) / nx as f64;
                    if keep([x, y]) {
                        out.push([x, y]);
                    }
                }
            }
            out
        };
        let bottom_pts = grid(&|_| true);
        let steiner = bottom_pts
            .iter()
            .map(|q| b.vertex(Point3::new(q[0], q[1], 0.0)))
            .collect::<Result<Vec<_>, _>>()?;
        let tris = triangulate_region(&b, &[&rings[0]], &steiner, "blade root block bottom")?;
        b.triangles_flipped(tris);

        // Blade: lofted sections, tip capped.
        let loops = (0..=self.levels)
            .map(|k| {
                let sigma = k as f64 / self.levels as f64;
                let z = bz + self.span * sigma;
                b.vertex_loop(
                    self.section(sigma)
                        .into_iter()
                        .map(|q| Point3::new(q[0], q[1], z)),
                )
            })
            .collect::<Result<Vec<_>, _>>()?;
        for pair in loops.windows(2) {
            loft(&mut b, &pair[0], &pair[1]);
        }
        let tris = triangulate_region(&b, &[&loops[self.levels]], &[], "blade tip")?;
        b.triangles(tris);

        // Block top: rectangle minus the root section.
        let mut obstacles = Obstacles::default();
        obstacles.add(self.section(0.0));
        let top_pts = grid(&|q| obstacles.is_clear(q, STEINER_CLEARANCE * res));
        let steiner = top_pts
            .iter()
            .map(|q| b.vertex(Point3::new(q[0], q[1], bz)))
            .collect::<Result<Vec<_>, _>>()?;
        let tris = triangulate_region(
            &b,
            &[&rings[nz], &loops[0]],
            &steiner,
            "blade root block top",
        )?;
        b.triangles(tris);
        Ok(b.finish())
    }
}

#[cfg(test)]
mod tests {
    use super::super::check;
    use super::*;

    /// Root block volume plus ∫ section area d(span), the area being c(σ)² τ · AREA_FACTOR
    /// (exact for vertically applied thickness): independent of the mesh.
    fn volume_estimate(p: &BladeParams) -> f64 {
        let [bx, by, bz] = p.root_block;
        let (c0, c1) = (p.root_chord, p.tip_chord);
        bx * by * bz
            + p.thickness_ratio * Airfoil::AREA_FACTOR * p.span * (c0 * c0 + c0 * c1 + c1 * c1)
                / 3.0
    }

    fn other() -> BladeParams {
        BladeParams {
            span: 60.0,
            root_chord: 25.0,
            tip_chord: 12.0,
            thickness_ratio: 0.15,
            camber_ratio: 0.06,
            twist_deg: -50.0,
            root_block: [36.0, 28.0, 12.0],
            resolution: 1.2,
        }
    }

    fn blade(p: &BladeParams) -> Result<Mesh, SampleError> {
        super::super::blade(p)
    }

    /// Generates the part and runs every check: closed manifold, Euler characteristic, outward
    /// volume near the independent estimate, minimum angle, no self-intersections.
    fn check_part(p: &BladeParams, vol_tol: f64, min_angle: f64) -> check::Report {
        let mesh = blade(p).unwrap_or_else(|e| panic!("{e}"));
        let rep = check::closed_manifold(&mesh).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(rep.euler, 2, "genus 0 expected: {rep:?}");
        let est = volume_estimate(p);
        let rel = (rep.volume - est) / est;
        println!(
            "blade res {}: {}; estimate {est:.1} mm³ ({:+.3} %)",
            p.resolution,
            rep.summary(),
            100.0 * rel
        );
        assert!(rep.min_edge > 1e-3, "{}", rep.summary());
        assert!(rep.volume > 0.0);
        assert!(rel.abs() < vol_tol, "volume {} vs {est}", rep.volume);
        assert!(rep.min_angle_deg > min_angle, "{rep:?}");
        // Cheap enough (sweep over x, then exact tests) to run at every resolution.
        let bad = check::self_intersections(&mesh, 10);
        assert!(bad.is_empty(), "self-intersecting pairs: {bad:?}");
        rep
    }

    #[test]
    fn area_factor_matches_numeric_integral() {
        let a = Airfoil {
            tau: 1.0,
            camber: 0.0,
        };
        let n = 200_000;
        let s: f64 = (0..n)
            .map(|i| 2.0 * a.half_thickness((i as f64 + 0.5) / n as f64) / n as f64)
            .sum();
        assert!((s - Airfoil::AREA_FACTOR).abs() < 1e-6, "{s}");
    }

    #[test]
    fn default_is_closed_genus0() {
        check_part(&BladeParams::default(), 0.01, 5.0);
    }

    #[test]
    fn other_params_are_closed_genus0() {
        check_part(&other(), 0.01, 5.0);
    }

    /// Coarse versions (a few thousand triangles), as the planner's fast tests will use them.
    #[test]
    fn coarse_versions_are_valid() {
        for p in [
            BladeParams {
                resolution: 3.0,
                ..BladeParams::default()
            },
            BladeParams {
                resolution: 2.5,
                ..other()
            },
        ] {
            let rep = check_part(&p, 0.03, 5.0);
            assert!(rep.triangles < 12_000, "{rep:?}");
        }
    }

    /// The checks can fail on this part: pushing one tip vertex down into the root block keeps
    /// the topology valid but must be reported as self-intersecting.
    #[test]
    fn pushed_vertex_is_caught() {
        let mut m = blade(&BladeParams {
            resolution: 3.0,
            ..BladeParams::default()
        })
        .unwrap();
        let top = (0..m.positions.len())
            .max_by(|&a, &b| m.positions[a].z.total_cmp(&m.positions[b].z))
            .unwrap();
        m.positions[top].z = 8.0;
        assert!(check::closed_manifold(&m).is_ok());
        assert!(!check::self_intersections(&m, 1).is_empty());
    }

    #[test]
    fn deterministic() {
        let p = BladeParams::default();
        assert!(check::bitwise_equal(
            &blade(&p).unwrap(),
            &blade(&p).unwrap()
        ));
    }

    #[test]
    fn invalid_parameters_are_errors() {
        let with = |f: &dyn Fn(&mut BladeParams)| {
            let mut p = BladeParams::default();
            f(&mut p);
            p
        };
        let cases = [
            (with(&|p| p.span = 0.0), "span"),
            (with(&|p| p.root_chord = -3.0), "root_chord"),
            (with(&|p| p.tip_chord = f64::NAN), "tip_chord"),
            (with(&|p| p.tip_chord = 5.0), "tip_chord"),
            (with(&|p| p.thickness_ratio = 0.0), "thickness_ratio"),
            (with(&|p| p.thickness_ratio = 0.5), "thickness_ratio"),
            (with(&|p| p.camber_ratio = 0.3), "camber_ratio"),
            (with(&|p| p.twist_deg = f64::INFINITY), "twist_deg"),
            (
                with(&|p| {
                    p.span = 10.0;
                    p.twist_deg = 170.0;
                }),
                "twist_deg",
            ),
            (with(&|p| p.root_block = [40.0, -1.0, 16.0]), "root_block"),
            (with(&|p| p.root_block = [20.0, 24.0, 16.0]), "root_block"),
            (with(&|p| p.resolution = f64::NAN), "resolution"),
            (with(&|p| p.resolution = 10.0), "resolution"),
            (with(&|p| p.resolution = 0.005), "resolution"),
        ];
        for (p, name) in cases {
            match blade(&p) {
                Err(SampleError::InvalidParameter { name: n, reason }) => {
                    assert_eq!(n, name, "{reason}");
                    println!("{name}: {reason}");
                }
                other => panic!(
                    "{name}: expected an error, got {:?}",
                    other.map(|m| m.triangles.len())
                ),
            }
        }
    }

    /// Robustness sweep over 2187 parameter combinations (run with `--ignored`, ~15 s): each
    /// is either rejected with `InvalidParameter` or gives a closed genus-0 manifold, free of
    /// self-intersections at the coarse resolution.
    #[test]
    #[ignore]
    fn sweep() {
        let mut ok = 0;
        let mut errs = std::collections::BTreeMap::new();
        let mut worst: f64 = 90.0;
        for span in [10.0, 80.0, 200.0] {
            for (c0, c1) in [(30.0, 20.0), (10.0, 30.0), (50.0, 5.0)] {
                for tau in [0.04, 0.12, 0.3] {
                    for m in [-0.1, 0.0, 0.06] {
                        for twist in [-170.0, 35.0, 180.0] {
                            for block in [[40.0, 24.0, 16.0], [60.0, 60.0, 2.0], [12.0, 8.0, 30.0]]
                            {
                                for res in [0.7, 1.5, 3.0] {
                                    let p = BladeParams {
                                        span,
                                        root_chord: c0,
                                        tip_chord: c1,
                                        thickness_ratio: tau,
                                        camber_ratio: m,
                                        twist_deg: twist,
                                        root_block: block,
                                        resolution: res,
                                    };
                                    match blade(&p) {
                                        Ok(mesh) => {
                                            let r = check::closed_manifold(&mesh)
                                                .unwrap_or_else(|e| panic!("{p:?}: {e}"));
                                            assert_eq!(r.euler, 2, "{p:?}");
                                            assert!(r.volume > 0.0);
                                            if p.resolution >= 2.5 {
                                                let bad = check::self_intersections(&mesh, 5);
                                                assert!(bad.is_empty(), "{p:?}: {bad:?}");
                                            }
                                            worst = worst.min(r.min_angle_deg);
                                            ok += 1;
                                        }
                                        Err(SampleError::InvalidParameter { name, .. }) => {
                                            *errs.entry(name).or_insert(0) += 1
                                        }
                                        Err(e) => panic!("{p:?}: {e}"),
                                    }
                                }
                            }
                        }
                    }
                }
            }
        }
        println!("valid {ok}, rejected {errs:?}, worst angle {worst:.2}°");
    }
}
