//! Helpers shared by the end-to-end tests: where the shared test data lives, and an
//! independent distance oracle (uniform grid + brute-force point–triangle distance, ray
//! parity for inside/outside) that shares no code with the library's own queries.

#![allow(dead_code)]

pub mod plan_checks;

use std::path::PathBuf;

use nalgebra::{Point3, Vector3};

/// `../shared/testdata` beside the clone (CI has it), or `WAVEMILL_TESTDATA`.
pub fn testdata() -> Option<PathBuf> {
    let dir = std::env::var_os("WAVEMILL_TESTDATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/testdata"));
    if dir.is_dir() {
        Some(dir)
    } else {
        eprintln!(
            "skipped: shared test data not found at {} (set WAVEMILL_TESTDATA or clone beside ../shared)",
            dir.display()
        );
        None
    }
}

/// The manifold meshes of the shared test data (paths under `meshes/`) and their units: the
/// set every multiresolution and offset test runs over.
pub const MANIFOLD_MESHES: [(&str, &str); 10] = [
    (
        "impeller_compressor_splitter__omorellAUS_Impellor-V3.stl",
        "mm",
    ),
    ("impeller_blower_9blade__necro-nemesis_aero2205.stl", "mm"),
    (
        "impeller_blower_9blade_tall__necro-nemesis_aero2205_aggressive.stl",
        "mm",
    ),
    ("turbine_blade_with_root__dengwirda_jigsaw-models.stl", "m"),
    ("blade_airfoil__LostSunset_pyturbo-aero.stl", "m"),
    ("blade_coarse196tri__pittance_compressorFan.stl", "mm"),
    ("ocl/sphere_on_plate.stl", "mm"),
    ("ocl/wheel_in_box.stl", "mm"),
    ("ocl/ktoolcav.stl", "mm"),
    ("ocl/demo.stl", "mm"),
];

/// Distance from `p` to the segment `a b`.
pub fn segment_distance(p: &Point3<f64>, a: &Point3<f64>, b: &Point3<f64>) -> f64 {
    let ab = b - a;
    let t = if ab.norm_squared() > 0.0 {
        ((p - a).dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + ab * t)).norm()
}

pub fn repo_file(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// Closest point on triangle by projecting onto the plane and, if outside, onto the three
/// edges (a different formulation from the library's Voronoi-region walk).
pub fn point_triangle_distance(p: &Point3<f64>, t: &[Point3<f64>; 3]) -> f64 {
    let n = (t[1] - t[0]).cross(&(t[2] - t[0]));
    let nn = n.norm_squared();
    if nn > 0.0 {
        let q = p - n * ((p - t[0]).dot(&n) / nn);
        let inside = (0..3).all(|k| (t[(k + 1) % 3] - t[k]).cross(&(q - t[k])).dot(&n) >= 0.0);
        if inside {
            return (p - q).norm();
        }
    }
    (0..3)
        .map(|k| {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            let ab = b - a;
            let s = if ab.norm_squared() > 0.0 {
                ((p - a).dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0)
            } else {
                0.0
            };
            (p - (a + ab * s)).norm()
        })
        .fold(f64::INFINITY, f64::min)
}

/// Triangles bucketed in a uniform grid for "everything within d of p" queries.
pub struct Oracle {
    pub triangles: Vec<[Point3<f64>; 3]>,
    min: Point3<f64>,
    cell: f64,
    dims: [usize; 3],
    buckets: Vec<Vec<u32>>,
    /// Each triangle's bounding box, to skip the exact distance to triangles that cannot be
    /// nearer than the nearest found so far.
    boxes: Vec<(Point3<f64>, Point3<f64>)>,
    /// Per ray axis, triangles by the 2D cell of their projected box.
    columns: [std::collections::HashMap<(i64, i64), Vec<u32>>; 3],
}

impl Oracle {
    pub fn new(positions: &[Point3<f64>], indices: &[[u32; 3]], cell: f64) -> Self {
        let triangles: Vec<[Point3<f64>; 3]> = indices
            .iter()
            .map(|t| t.map(|i| positions[i as usize]))
            .collect();
        let mut min = Point3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY);
        let mut max = Point3::new(f64::NEG_INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY);
        for p in positions {
            min = min.inf(p);
            max = max.sup(p);
        }
        let dims = [0, 1, 2].map(|i| (((max[i] - min[i]) / cell).floor() as usize) + 1);
        let mut buckets = vec![Vec::new(); dims[0] * dims[1] * dims[2]];
        for (ti, t) in triangles.iter().enumerate() {
            let lo = [0, 1, 2].map(|i| {
                (((t[0][i].min(t[1][i]).min(t[2][i]) - min[i]) / cell).floor() as usize)
                    .min(dims[i] - 1)
            });
            let hi = [0, 1, 2].map(|i| {
                (((t[0][i].max(t[1][i]).max(t[2][i]) - min[i]) / cell).floor() as usize)
                    .min(dims[i] - 1)
            });
            for x in lo[0]..=hi[0] {
                for y in lo[1]..=hi[1] {
                    for z in lo[2]..=hi[2] {
                        buckets[(x * dims[1] + y) * dims[2] + z].push(ti as u32);
                    }
                }
            }
        }
        let mut columns: [std::collections::HashMap<(i64, i64), Vec<u32>>; 3] = Default::default();
        for (axis, map) in columns.iter_mut().enumerate() {
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            for (ti, t) in triangles.iter().enumerate() {
                let cell_of = |c: usize, x: f64| ((x - min[c]) / cell).floor() as i64;
                let (u0, u1) = (
                    cell_of(u, t[0][u].min(t[1][u]).min(t[2][u])),
                    cell_of(u, t[0][u].max(t[1][u]).max(t[2][u])),
                );
                let (v0, v1) = (
                    cell_of(v, t[0][v].min(t[1][v]).min(t[2][v])),
                    cell_of(v, t[0][v].max(t[1][v]).max(t[2][v])),
                );
                for a in u0..=u1 {
                    for b in v0..=v1 {
                        map.entry((a, b)).or_default().push(ti as u32);
                    }
                }
            }
        }
        let boxes = triangles
            .iter()
            .map(|t| (t[0].inf(&t[1]).inf(&t[2]), t[0].sup(&t[1]).sup(&t[2])))
            .collect();
        Self {
            triangles,
            min,
            cell,
            dims,
            buckets,
            boxes,
            columns,
        }
    }

    /// Distance from `p` to the surface if it is below `limit`, else `limit`.
    pub fn distance_below(&self, p: &Point3<f64>, limit: f64) -> f64 {
        let r = (limit / self.cell).ceil() as i64;
        let c = [0, 1, 2].map(|i| ((p[i] - self.min[i]) / self.cell).floor() as i64);
        let mut best = limit;
        // The cells around p, nearest first, so that the nearest triangle found early lets
        // the farther cells and triangles be skipped by their boxes.
        let mut cells = Vec::with_capacity(((2 * r + 1) as usize).pow(3));
        for x in c[0] - r..=c[0] + r {
            for y in c[1] - r..=c[1] + r {
                for z in c[2] - r..=c[2] + r {
                    if x < 0
                        || y < 0
                        || z < 0
                        || x >= self.dims[0] as i64
                        || y >= self.dims[1] as i64
                        || z >= self.dims[2] as i64
                    {
                        continue;
                    }
                    let lo = Point3::new(
                        self.min.x + x as f64 * self.cell,
                        self.min.y + y as f64 * self.cell,
                        self.min.z + z as f64 * self.cell,
                    );
                    let hi = lo + Vector3::repeat(self.cell);
                    let gap = (lo - p)
                        .sup(&(p - hi))
                        .sup(&Vector3::zeros())
                        .norm_squared();
                    cells.push((
                        gap,
                        ((x as usize) * self.dims[1] + y as usize) * self.dims[2] + z as usize,
                    ));
                }
            }
        }
        cells.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        for (gap, cell) in cells {
            if gap >= best * best {
                break;
            }
            for &t in &self.buckets[cell] {
                // A triangle in several cells is measured again: harmless for a minimum, and
                // cheaper than remembering it.
                let (lo, hi) = &self.boxes[t as usize];
                let outside = (lo - p).sup(&(p - hi)).sup(&Vector3::zeros());
                if outside.norm_squared() < best * best {
                    best = best.min(point_triangle_distance(p, &self.triangles[t as usize]));
                }
            }
        }
        best
    }

    /// Inside test by ray parity along +X, +Y and +Z, majority vote (a ray through an edge
    /// can miscount; three rarely all do). Each axis has a 2D grid of the triangles' projected
    /// boxes, so a query only looks at the triangles its ray can meet.
    pub fn inside(&self, p: &Point3<f64>) -> bool {
        let votes = (0..3)
            .filter(|&axis| self.crossings_along(p, axis) % 2 == 1)
            .count();
        votes >= 2
    }

    fn crossings_along(&self, p: &Point3<f64>, axis: usize) -> usize {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        // Shift the ray sideways by an irrational hair (far below any distance the tests care
        // about) so that it does not pass exactly through edges of meshes built on round
        // coordinates, where both neighbouring triangles would reject it.
        let mut p = *p;
        p[u] += 1.234_567e-7 * std::f64::consts::SQRT_2;
        p[v] += 0.987_654e-7 * 3f64.sqrt();
        let p = &p;
        let columns = self.columns[axis].get(&(
            ((p[u] - self.min[u]) / self.cell).floor() as i64,
            ((p[v] - self.min[v]) / self.cell).floor() as i64,
        ));
        let Some(columns) = columns else { return 0 };
        columns
            .iter()
            .filter(|&&t| {
                let t = &self.triangles[t as usize];
                // 2D point-in-triangle in the (u, v) plane, half-open on edges.
                let mut sign = 0i32;
                for k in 0..3 {
                    let (a, b) = (t[k], t[(k + 1) % 3]);
                    let cross = (b[u] - a[u]) * (p[v] - a[v]) - (b[v] - a[v]) * (p[u] - a[u]);
                    let s = if cross > 0.0 {
                        1
                    } else if cross < 0.0 {
                        -1
                    } else {
                        0
                    };
                    if s == 0 {
                        return false;
                    }
                    if sign == 0 {
                        sign = s;
                    } else if s != sign {
                        return false;
                    }
                }
                // Height of the triangle's plane above p along the axis.
                let n = (t[1] - t[0]).cross(&(t[2] - t[0]));
                if n[axis].abs() < 1e-300 {
                    return false;
                }
                let along =
                    t[0][axis] - ((p[u] - t[0][u]) * n[u] + (p[v] - t[0][v]) * n[v]) / n[axis];
                along > p[axis]
            })
            .count()
    }
}

/// Points on every triangle at most `spacing` apart (vertices, edge points, interior grid).
pub fn surface_samples(triangles: &[[Point3<f64>; 3]], spacing: f64) -> Vec<Point3<f64>> {
    let mut out = Vec::new();
    for t in triangles {
        let longest = (0..3)
            .map(|k| (t[(k + 1) % 3] - t[k]).norm())
            .fold(0.0, f64::max);
        let n = ((longest / spacing).ceil() as usize).max(1);
        for i in 0..=n {
            for j in 0..=(n - i) {
                let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                out.push(t[0] + (t[1] - t[0]) * u + (t[2] - t[0]) * v);
            }
        }
    }
    out
}

/// A CL row of `cl.csv`.
#[derive(Clone, Debug)]
pub struct ClRow {
    pub tip: Point3<f64>,
    pub axis: Vector3<f64>,
    pub kind: String,
    pub feed: f64,
    pub tool: u32,
}

pub fn parse_cl(text: &str) -> Vec<ClRow> {
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("x,y,z,i,j,k,kind,feed,tool"));
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            assert_eq!(f.len(), 9, "bad row {l}");
            let n = |i: usize| {
                f[i].parse::<f64>()
                    .unwrap_or_else(|_| panic!("bad number in {l}"))
            };
            ClRow {
                tip: Point3::new(n(0), n(1), n(2)),
                axis: Vector3::new(n(3), n(4), n(5)),
                kind: f[6].to_string(),
                feed: n(7),
                tool: f[8].parse().unwrap_or_else(|_| panic!("bad tool in {l}")),
            }
        })
        .collect()
}

/// One motion block of a posted program, read the way a control reads it: modal G0/G1, every
/// axis keeps its last commanded value.
#[derive(Clone, Debug)]
pub struct PostedBlock {
    pub line: usize,
    pub rapid: bool,
    /// X, Y, Z (mm), A, C (degrees) after the block.
    pub axes: [f64; 5],
    /// The tool in the spindle (the last `T` word; 0 before any).
    pub tool: u32,
}

/// The motion blocks of a table-table A/C program once every axis has a value (the earlier
/// ones only position single axes). Written for the tests alone: comments in parentheses,
/// words as letter + number, nothing shared with the post or the library's reader.
pub fn read_ac_program(text: &str) -> Vec<PostedBlock> {
    let mut axes: [Option<f64>; 5] = [None; 5];
    let mut rapid = true;
    let mut tool = 0;
    let mut out = Vec::new();
    for (index, raw) in text.lines().enumerate() {
        let code: String = {
            let mut depth = 0;
            raw.chars()
                .filter(|&c| {
                    match c {
                        '(' => depth += 1,
                        ')' => {
                            depth -= 1;
                            return false;
                        }
                        _ => {}
                    }
                    depth == 0
                })
                .collect()
        };
        let mut moved = false;
        let mut chars = code.trim().chars().peekable();
        while let Some(letter) = chars.next() {
            if letter.is_whitespace() || letter == '%' {
                continue;
            }
            let mut number = String::new();
            while let Some(&c) = chars.peek() {
                if c.is_ascii_digit() || c == '.' || c == '-' {
                    number.push(c);
                    chars.next();
                } else {
                    break;
                }
            }
            let value: f64 = number
                .parse()
                .unwrap_or_else(|_| panic!("line {}: word {letter}{number}", index + 1));
            let slot = match letter {
                'G' if value == 0.0 => {
                    rapid = true;
                    None
                }
                'G' if value == 1.0 => {
                    rapid = false;
                    None
                }
                'T' => {
                    tool = value as u32;
                    None
                }
                'X' => Some(0),
                'Y' => Some(1),
                'Z' => Some(2),
                'A' => Some(3),
                'C' => Some(4),
                _ => None,
            };
            if let Some(i) = slot {
                axes[i] = Some(value);
                moved = true;
            }
        }
        if moved && let [Some(x), Some(y), Some(z), Some(a), Some(c)] = axes {
            out.push(PostedBlock {
                line: index + 1,
                rapid,
                axes: [x, y, z, a, c],
                tool,
            });
        }
    }
    out
}

/// The ball centre in the part frame for table-table A/C joints: the tool points along
/// machine +Z with its tip at X Y Z; the table turns a part point `p` to
/// `R_x(A) · R_z(C) · (p + origin)`, so the centre is that map inverted.
pub fn ac_ball_centre(joints: &[f64; 5], radius: f64, origin: &Vector3<f64>) -> Point3<f64> {
    let machine = Vector3::new(joints[0], joints[1], joints[2] + radius);
    let table = nalgebra::Rotation3::from_axis_angle(&Vector3::x_axis(), joints[3].to_radians())
        * nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), joints[4].to_radians());
    Point3::from(table.inverse() * machine - origin)
}
