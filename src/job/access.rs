//! `wavemill access`: visibility maps of a part, as outputs people can look at (issue 5 item 7;
//! DESIGN.md §3.5).
//!
//! * `access.glb`: the part with a per-vertex heat map, the fraction of the front-facing
//!   directions (d·n > 0) whose ray escapes the part, red (none) → yellow → green (all).
//!   Computed coarse-to-fine over the direction hierarchy for every vertex.
//! * `access.json`: statistics — points, directions, rays cast by the hierarchy against what
//!   brute force would cast, the agreement of the two measured on a subsample of vertices, and
//!   (unless switched off) timings.
//! * `query.csv` for given points: `visible` counts the escaping front-facing directions by
//!   brute force (ray visibility only, no tool); the axis is what the tool-axis choice
//!   (`orient::AxisChooser`, as `plan` uses it) picks for a ball of the job's tool touching the
//!   point, with the part's collision structures and no machine limits or table. The feed
//!   direction is +X projected into the tangent plane (a fixed frame's first axis when the
//!   normal is along X), so lead leans toward +X.

use std::path::Path;
use std::time::Instant;

use serde::Serialize;

use super::config::Job;
use super::output::{OutputKind, json_bytes, write_output_set};
use crate::access::{
    DirectionSet, RayScene, SurfacePoint, VisibilityOptions, level_for_count, vertex_points,
    visibility_brute_force, visibility_hierarchical,
};
use crate::collide::{Margins, PartCollider, PreparedTool};
use crate::error::{Error, JobError, Result};
use crate::geom::{Vector3, positive_zero};
use crate::mesh::io::{GlbBuilder, RawMesh};
use crate::mesh::{Piece, PrepareOptions, prepare_without_stray_pieces};
use crate::orient::{AxisChooser, AxisOptions};

/// What `access` computes.
#[derive(Clone, Debug, PartialEq)]
pub struct AccessOptions {
    /// Size K of the direction set: 12, 42, 162, 642, 2562 or 10242.
    pub directions: usize,
    /// Vertices (evenly spread) whose hierarchical maps are checked against brute force.
    pub check_points: usize,
    /// Record timings in the report (the only run-dependent figures).
    pub timings: bool,
}

impl Default for AccessOptions {
    fn default() -> Self {
        Self {
            directions: 642,
            check_points: 200,
            timings: true,
        }
    }
}

/// `access.json`.
#[derive(Clone, Debug, Serialize)]
pub struct AccessReport {
    pub wavemill_version: &'static str,
    pub part: String,
    pub triangles: usize,
    /// Stray debris of the file left out of the maps, largest first.
    pub stray_pieces: Vec<Piece>,
    /// Vertices with a map (all but those whose normal is undefined).
    pub points: usize,
    pub skipped_vertices: usize,
    pub directions: usize,
    /// Directions of the coarse set the hierarchy casts in full.
    pub start_directions: usize,
    pub lift_mm: f64,
    pub rays: RayCounts,
    pub agreement: Agreement,
    /// Fraction of front-facing directions visible, over the points.
    pub visible_fraction: Spread,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub query: Option<QuerySummary>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub timings_ms: Option<AccessTimings>,
}

#[derive(Clone, Debug, Serialize)]
pub struct RayCounts {
    pub hierarchical: u64,
    /// Rays a brute-force computation of the same maps casts (every front-facing direction).
    pub brute_force: u64,
    /// brute_force / hierarchical.
    pub saving: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct Agreement {
    pub points_checked: usize,
    pub pairs_checked: usize,
    /// Share of (point, direction) pairs where the hierarchical and brute-force maps agree, %.
    pub percent: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct Spread {
    pub min: f64,
    pub mean: f64,
    pub max: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct QuerySummary {
    pub points: usize,
    pub tool: String,
    pub feed_direction: &'static str,
    /// Query points where no axis was found (zeros in query.csv).
    pub without_axis: usize,
}

#[derive(Clone, Debug, Serialize)]
pub struct AccessTimings {
    pub prepare: f64,
    pub ray_scene: f64,
    pub hierarchical: f64,
    pub brute_force_check: f64,
    pub query: f64,
    pub total: f64,
    /// Rays per second of the hierarchical maps.
    pub hierarchical_rays_per_s: f64,
}

/// Everything `access` produces, in memory.
pub struct AccessOutput {
    pub glb: Vec<u8>,
    pub report: AccessReport,
    pub query_csv: Option<String>,
}

const FEED: &str = "+X projected into the tangent plane";

/// Computes the maps of `raw` (already in mm) and, for `query` points, their visible counts and
/// tool axes with the tool of `job`.
pub fn access(
    raw: &RawMesh,
    part_name: &str,
    job: &Job,
    options: &AccessOptions,
    query: Option<&[SurfacePoint]>,
) -> Result<AccessOutput> {
    let started = Instant::now();
    let ms = |t: Instant| (t.elapsed().as_secs_f64() * 1e4).round() / 10.0;
    let level = level_for_count(options.directions).map_err(|e| {
        Error::JobFile(JobError::Invalid {
            key: "directions".into(),
            reason: e.to_string(),
        })
    })?;
    let mesh_error = |reason: String| Error::Mesh {
        file: part_name.to_string(),
        reason,
    };
    let t = Instant::now();
    // As `plan` does: stray debris is left out of the maps and reported.
    let (part, _, stray_pieces) =
        prepare_without_stray_pieces(&raw.mesh, &PrepareOptions::default())
            .map_err(|e| mesh_error(e.to_string()))?;
    let prepare_ms = ms(t);
    let t = Instant::now();
    let scene = RayScene::new(&part);
    let ray_scene_ms = ms(t);

    let set = DirectionSet::new(level);
    let visibility = VisibilityOptions::default()
        .with_level(level)
        // The default coarse set (162), or one level below K when K is that small.
        .with_start_level(
            level
                .saturating_sub(1)
                .min(VisibilityOptions::default().start_level),
        );
    let visibility_error = Error::Visibility;
    let (vertices, points) = vertex_points(&part);
    let t = Instant::now();
    let maps =
        visibility_hierarchical(&scene, &set, &points, &visibility).map_err(visibility_error)?;
    let hierarchical_ms = ms(t);

    let t = Instant::now();
    let stride = (points.len() / options.check_points.max(1)).max(1);
    let checked: Vec<usize> = (0..points.len()).step_by(stride).collect();
    let subset: Vec<SurfacePoint> = checked.iter().map(|&i| points[i]).collect();
    let brute =
        visibility_brute_force(&scene, &set, &subset, &visibility).map_err(visibility_error)?;
    let (mut same, mut pairs) = (0, 0);
    for (k, &i) in checked.iter().enumerate() {
        same += maps.maps[i].agreement(&brute.maps[k]);
        pairs += maps.maps[i].len();
    }
    let check_ms = ms(t);

    let fractions: Vec<f64> = maps
        .maps
        .iter()
        .zip(&maps.front_facing)
        .map(|(m, &f)| {
            if f == 0 {
                0.0
            } else {
                m.count() as f64 / f as f64
            }
        })
        .collect();
    let mut colours = vec![heat(0.0); part.positions.len()];
    for (&v, &f) in vertices.iter().zip(&fractions) {
        colours[v] = heat(f);
    }
    let mut glb = GlbBuilder::new();
    glb.add_triangles("access", &part, [1.0, 1.0, 1.0, 1.0], Some(&colours))
        .map_err(|error| Error::Glb {
            file: "access.glb".into(),
            error,
        })?;

    let t = Instant::now();
    let (query_csv, query_summary) = match query {
        Some(q) => {
            let (csv, summary) = query_points(&part, &scene, &set, &visibility, job, q)?;
            (Some(csv), Some(summary))
        }
        None => (None, None),
    };
    let query_ms = ms(t);

    let brute_force_rays = maps.brute_force_rays();
    let report = AccessReport {
        wavemill_version: env!("CARGO_PKG_VERSION"),
        part: part_name.to_string(),
        triangles: part.triangles.len(),
        stray_pieces,
        points: points.len(),
        skipped_vertices: part.positions.len() - points.len(),
        directions: options.directions,
        start_directions: set.count(visibility.start_level),
        lift_mm: visibility.lift_for(&scene),
        rays: RayCounts {
            hierarchical: maps.rays_cast,
            brute_force: brute_force_rays,
            saving: brute_force_rays as f64 / maps.rays_cast.max(1) as f64,
        },
        agreement: Agreement {
            points_checked: checked.len(),
            pairs_checked: pairs,
            percent: if pairs == 0 {
                100.0
            } else {
                100.0 * same as f64 / pairs as f64
            },
        },
        visible_fraction: Spread {
            min: fractions
                .iter()
                .copied()
                .fold(f64::INFINITY, f64::min)
                .min(1.0),
            mean: fractions.iter().sum::<f64>() / fractions.len().max(1) as f64,
            max: fractions.iter().copied().fold(0.0, f64::max),
        },
        query: query_summary,
        timings_ms: options.timings.then(|| AccessTimings {
            prepare: prepare_ms,
            ray_scene: ray_scene_ms,
            hierarchical: hierarchical_ms,
            brute_force_check: check_ms,
            query: query_ms,
            total: ms(started),
            hierarchical_rays_per_s: (maps.rays_cast as f64 / (hierarchical_ms.max(0.1) / 1e3))
                .round(),
        }),
    };
    Ok(AccessOutput {
        glb: glb.build(),
        report,
        query_csv,
    })
}

/// `query.csv` rows and the summary for the query points.
fn query_points(
    part: &crate::mesh::Mesh,
    scene: &RayScene,
    set: &DirectionSet,
    visibility: &VisibilityOptions,
    job: &Job,
    query: &[SurfacePoint],
) -> Result<(String, QuerySummary)> {
    let visible =
        visibility_brute_force(scene, set, query, visibility).map_err(Error::Visibility)?;
    let collider = PartCollider::new(part).map_err(|error| Error::Collider {
        what: "the part".into(),
        error,
    })?;
    let tool = job.tool.assembly();
    let prepared = PreparedTool::new(
        &tool,
        &Margins {
            shank: job.safety.shank_margin,
            holder: job.safety.holder_margin,
        },
    );
    let chooser = AxisChooser::new(AxisOptions {
        lead_deg: job.strategy.lead_deg,
        tilt_deg: job.strategy.tilt_deg,
        max_deviation_deg: job.strategy.max_axis_deviation_deg,
        ..AxisOptions::default()
    });
    let r = job.tool.diameter / 2.0;
    let anywhere = |_: &Vector3| true;
    let total = set.count(visibility.level);
    let mut csv = String::from("x,y,z,visible,total,axis_i,axis_j,axis_k\n");
    let mut without_axis = 0;
    for (k, q) in query.iter().enumerate() {
        // Normals were checked by the brute-force pass above.
        let n = q.normal.normalize();
        let axis = chooser
            .choose(
                &collider,
                scene,
                &prepared,
                &(q.point + n * r),
                &n,
                &Vector3::x(),
                None,
                &anywhere,
            )
            .map(|a| a.into_inner())
            .unwrap_or_else(|_| {
                without_axis += 1;
                Vector3::zeros()
            })
            .map(positive_zero);
        csv.push_str(&format!(
            "{},{},{},{},{},{:.6},{:.6},{:.6}\n",
            q.point.x,
            q.point.y,
            q.point.z,
            visible.maps[k].count(),
            total,
            axis.x,
            axis.y,
            axis.z
        ));
    }
    let summary = QuerySummary {
        points: query.len(),
        tool: tool.describe(),
        feed_direction: FEED,
        without_axis,
    };
    Ok((csv, summary))
}

/// Red (0) → yellow (0.5) → green (1), linear RGBA.
fn heat(f: f64) -> [f32; 4] {
    let f = f.clamp(0.0, 1.0) as f32;
    let (red, yellow, green) = ([0.8, 0.08, 0.06], [0.95, 0.85, 0.1], [0.1, 0.7, 0.2]);
    let (a, b, t) = if f < 0.5 {
        (red, yellow, 2.0 * f)
    } else {
        (yellow, green, 2.0 * f - 1.0)
    };
    [
        a[0] + (b[0] - a[0]) * t,
        a[1] + (b[1] - a[1]) * t,
        a[2] + (b[2] - a[2]) * t,
        1.0,
    ]
}

/// Reads query points: CSV with a header naming the columns `x,y,z,nx,ny,nz` (any order, other
/// columns ignored). `file` names the source in errors.
pub fn parse_query_csv(text: &str, file: &str) -> Result<Vec<SurfacePoint>> {
    let bad = |line: usize, reason: String| Error::DataFile {
        file: file.to_string(),
        line,
        reason,
    };
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty());
    let (header_line, header) = lines.next().ok_or_else(|| {
        bad(
            1,
            "the file is empty; expected a header x,y,z,nx,ny,nz".into(),
        )
    })?;
    let names: Vec<String> = header
        .split(',')
        .map(|c| c.trim().to_ascii_lowercase())
        .collect();
    let wanted = ["x", "y", "z", "nx", "ny", "nz"];
    let missing: Vec<&str> = wanted
        .iter()
        .copied()
        .filter(|w| !names.iter().any(|n| n == w))
        .collect();
    if !missing.is_empty() {
        return Err(bad(
            header_line,
            format!(
                "header `{header}` lacks column(s) {}; expected x,y,z,nx,ny,nz",
                missing.join(",")
            ),
        ));
    }
    let columns: Vec<usize> = wanted
        .iter()
        .filter_map(|w| names.iter().position(|n| n == w))
        .collect();
    let mut points = Vec::new();
    for (line, row) in lines {
        let fields: Vec<&str> = row.split(',').map(str::trim).collect();
        let mut v = [0.0; 6];
        for (slot, (&c, name)) in v.iter_mut().zip(columns.iter().zip(wanted)) {
            let field = fields
                .get(c)
                .ok_or_else(|| bad(line, format!("no value for column {name}")))?;
            *slot = field
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| bad(line, format!("{name} = `{field}` is not a finite number")))?;
        }
        let normal = Vector3::new(v[3], v[4], v[5]);
        if normal.norm() < 1e-12 {
            return Err(bad(line, "the normal (nx,ny,nz) is zero".into()));
        }
        points.push(SurfacePoint {
            point: crate::geom::Point3::new(v[0], v[1], v[2]),
            normal,
        });
    }
    Ok(points)
}

/// Writes `access.glb`, `access.json` and, with queries, `query.csv` into `dir` (created if
/// missing), each atomically.
pub fn write_access_outputs(dir: &Path, output: &AccessOutput) -> Result<()> {
    let mut files = vec![
        ("access.glb".to_string(), output.glb.clone()),
        (
            "access.json".to_string(),
            json_bytes("access.json", &output.report)?,
        ),
    ];
    if let Some(csv) = &output.query_csv {
        files.push(("query.csv".to_string(), csv.clone().into_bytes()));
    }
    write_output_set(dir, &OutputKind::ACCESS, &files)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn query_csv_is_read_by_column_name_and_bad_rows_are_named() {
        let p = parse_query_csv("nx,ny,nz,x,y,z\n0,0,2,1,2,3\n\n0,1,0,4,5,6\n", "q.csv").unwrap();
        assert_eq!(p.len(), 2);
        assert_eq!(p[0].point, crate::geom::Point3::new(1.0, 2.0, 3.0));
        assert_eq!(p[1].normal, Vector3::y());
        let err = |text: &str| parse_query_csv(text, "q.csv").unwrap_err().to_string();
        assert!(err("x,y,z,nx,ny\n").contains("lacks column(s) nz"));
        assert!(err("").contains("q.csv: line 1: the file is empty"));
        let e = err("x,y,z,nx,ny,nz\n1,2,3,0,0,1\n1,2,three,0,0,1\n");
        assert!(e.contains("line 3") && e.contains("three"), "{e}");
        assert!(err("x,y,z,nx,ny,nz\n1,2,3,0,0\n").contains("no value for column nz"));
        assert!(err("x,y,z,nx,ny,nz\n1,2,3,0,0,0\n").contains("line 2: the normal"));
        assert!(err("x,y,z,nx,ny,nz\n1,2,inf,0,0,1\n").contains("not a finite"));
    }

    #[test]
    fn heat_map_runs_red_to_green() {
        let close = |a: [f32; 4], b: [f32; 3]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-6);
        assert!(close(heat(0.0), [0.8, 0.08, 0.06]));
        assert!(close(heat(0.5), [0.95, 0.85, 0.1]));
        assert!(close(heat(1.0), [0.1, 0.7, 0.2]));
        // Green rises and red falls monotonically along the ramp.
        let ramp: Vec<[f32; 4]> = (0..=10).map(|k| heat(k as f64 / 10.0)).collect();
        assert!(ramp.windows(2).skip(5).all(|w| w[1][0] <= w[0][0]));
        assert!(ramp.windows(2).take(5).all(|w| w[1][1] >= w[0][1]));
        assert!(heat(2.0) == heat(1.0) && heat(-1.0) == heat(0.0));
    }
}
