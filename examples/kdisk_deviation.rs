//! Does the least-squares k-disk update bring coarse levels closer to the part (issue 3)?
//! Prints the L∞ and RMS deviation of each truncated level from the finest, with plain lifting
//! and with the update, for the parts given (default: the bundled sample impeller).
//!
//! `cargo run --release --example kdisk_deviation [PART [UNITS]]...`, e.g. with
//! `../shared/testdata/meshes/impeller_blower_9blade__necro-nemesis_aero2205.stl mm`.

use wavemill::job;
use wavemill::mesh::{PrepareOptions, prepare};
use wavemill::multires::{Hierarchy, RemeshOptions, WaveletHierarchy, WaveletOptions};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut parts: Vec<(String, String)> = Vec::new();
    let mut i = 0;
    while i < args.len() {
        let units = args
            .get(i + 1)
            .filter(|u| ["mm", "m", "in"].contains(&u.as_str()));
        parts.push((
            args[i].clone(),
            units.cloned().unwrap_or_else(|| "mm".into()),
        ));
        i += if units.is_some() { 2 } else { 1 };
    }
    if parts.is_empty() {
        parts.push((
            concat!(env!("CARGO_MANIFEST_DIR"), "/data/impeller.glb").into(),
            "mm".into(),
        ));
    }
    for (path, units) in parts {
        let raw = job::load_part(path.as_ref(), &units)?;
        let (mesh, _) = prepare(&raw.mesh, &PrepareOptions::default())?;
        let h = Hierarchy::build(
            &mesh,
            &RemeshOptions {
                tolerance: 0.0,
                base_max_error: Some(0.3),
                max_levels: 3,
                ..Default::default()
            },
        )?;
        let base = &h.levels[0];
        for kdisk in [false, true] {
            let wavelets = WaveletHierarchy::new_opt(
                &base.mesh.triangles,
                base.mesh.positions.len(),
                &base.creases,
                h.levels.len() - 1,
                &WaveletOptions::default().with_kdisk_update(kdisk),
            )?;
            let w = wavelets.analyse_all(&h.finest().mesh.positions)?;
            let mut per_level = Vec::new();
            for j in 0..h.levels.len() - 1 {
                let d = wavelets.deviation_to_finest(&w, j)?;
                let rms = (d.per_vertex.iter().map(|v| v.norm_squared()).sum::<f64>()
                    / d.per_vertex.len().max(1) as f64)
                    .sqrt();
                per_level.push(format!("level {j}: max {:.4} rms {:.4}", d.linf, rms));
            }
            println!("{path} (k-disk {kdisk}): {}", per_level.join("; "));
        }
    }
    Ok(())
}
