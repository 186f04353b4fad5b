//! `wavemill rough-boxes`: seed 002's convex-hull-box roughing of an IGES part with one end
//! mill; posted, read back and checked; with --compare the uniform route beside it.

use std::path::PathBuf;
use std::sync::Arc;

use clap::Args;

use crate::cad::tessellate::TessellateOptions;
use crate::cli::values::*;
use crate::error::{Error, Result};
use crate::job;

#[derive(Args, Debug)]
pub struct RoughBoxesArgs {
    /// IGES part (.igs, .iges): its B-spline surfaces and surfaces of revolution are boxed;
    /// it stands on its lowest point with its axis along +Z unless --up says otherwise.
    pub part: PathBuf,
    /// The end mill: `flat:D`, or `bull:D:R` (corner radius R), mm; flutes 3·D long, in a
    /// shrink-fit holder (nose cone D + 12 → D + 20 mm over 40 mm, then Ø50 × 40 mm).
    #[arg(long, value_name = "SPEC")]
    pub tool: String,
    /// Length the tool sticks out of its holder, mm [default: the longer of the blank's height
    /// and the flutes, plus 7, rounded up to 5 mm].
    #[arg(long, value_parser = positive)]
    pub stickout: Option<f64>,
    /// Largest depth of cut, mm: thicker layers are split at the tops of de Casteljau halves
    /// of the patches in them [default: the tool's radius].
    #[arg(long, value_parser = positive)]
    pub max_depth: Option<f64>,
    /// Smallest depth of cut, mm: thinner layers are merged with the layer above [default: a
    /// third of the largest].
    #[arg(long)]
    pub min_depth: Option<f64>,
    /// Split every patch whose box is wider than this (in X or Y), mm, before the layers: a
    /// tighter model that leaves less material [default: none, the seed's model, split only
    /// where a layer is thicker than --max-depth].
    #[arg(long, value_parser = positive)]
    pub box_width: Option<f64>,
    /// Take, from the top down, the deepest box top within --max-depth of the layer above
    /// for each layer, instead of the seed's rule (a layer thinner than --min-depth merged
    /// upward until it is not, which with thousands of box tops leaves layers of about the
    /// minimum depth).
    #[arg(long)]
    pub deepest_layers: bool,
    /// Material left outside the boxes: every box is grown by this much, mm.
    #[arg(long, default_value_t = 0.0)]
    pub allowance: f64,
    /// The blank (stock): `box:X0,Y0,Z0,X1,Y1,Z1` or `cylinder:R,Z0,Z1` (about the vertical
    /// line through the part's box centre), mm [default: a cylinder 2 mm wider than the part
    /// and 1 mm above it].
    #[arg(long, value_name = "SPEC", value_parser = blank)]
    pub stock: Option<job::BlankSpec>,
    /// Direction in the part file that should point up the spindle, e.g. `0,0,-1` for an
    /// impeller modelled upside down; the program is in the part's frame turned so.
    #[arg(long, value_parser = parse_vector)]
    pub up: Option<[f64; 3]>,
    /// Cutting feed, mm/min.
    #[arg(long, default_value_t = 2000.0, value_parser = positive)]
    pub feed: f64,
    /// Feed of ramped entries, mm/min.
    #[arg(long, default_value_t = 800.0, value_parser = positive)]
    pub entry_feed: f64,
    /// Spindle speed, rev/min.
    #[arg(long, default_value_t = 8000)]
    pub spindle_rpm: u32,
    /// Also plan the uniform route — equal layers at the largest depth, each pocket bounded by
    /// the part's own section — with the same tool, and set both side by side in rough.json.
    #[arg(long)]
    pub compare: bool,
    /// Chord tolerance of the part's mesh (the checks and the stock model run on it), mm.
    #[arg(long, default_value_t = 0.01, value_parser = positive)]
    pub tolerance: f64,
    /// Distance between dexel lines of the stock model the program is run on, mm [default: the
    /// part's box diagonal / 400, within 0.05 to 1 mm].
    #[arg(long, value_parser = positive)]
    pub resolution: Option<f64>,
    /// Leave the run-dependent timings out of rough.json (byte-identical reports).
    #[arg(long)]
    pub no_timings: bool,
    /// Output folder: rough.nc, cl.csv, rough.json, stock.glb (only rough.json when a check
    /// fails; exit 3).
    #[arg(long)]
    pub out: PathBuf,
}

/// Runs the command.
pub fn run(args: &RoughBoxesArgs) -> Result<()> {
    let name = args.part.display().to_string();
    if !job::is_iges(&args.part) {
        return Err(Error::Usage(format!(
            "{name}: convex-hull boxes need the part's surfaces: give an IGES file (.igs, .iges)"
        )));
    }
    let cutter =
        crate::tool::parse_cutter(&args.tool).map_err(|e| Error::Usage(format!("--tool: {e}")))?;
    if !matches!(
        cutter,
        crate::tool::Cutter::Flat { .. } | crate::tool::Cutter::BullNose { .. }
    ) {
        return Err(Error::Usage(format!(
            "--tool {}: convex-hull-box roughing cuts with a flat or bull-nose end mill (flat:D \
             or bull:D:R)",
            args.tool
        )));
    }
    if !(args.allowance.is_finite() && args.allowance >= 0.0) {
        return Err(Error::Usage(format!(
            "--allowance {}: must be a length ≥ 0",
            args.allowance
        )));
    }
    let max_depth = args.max_depth.unwrap_or(cutter.diameter() / 2.0);
    let min_depth = args.min_depth.unwrap_or(max_depth / 3.0);
    if !(min_depth.is_finite() && (0.0..=max_depth).contains(&min_depth)) {
        return Err(Error::Usage(format!(
            "--min-depth {min_depth}: must lie in [0, {max_depth}] (the largest depth)"
        )));
    }
    job::check_output_dir(&args.out, &job::OutputKind::ROUGH)?;
    let options = TessellateOptions {
        tolerance: args.tolerance,
    };
    let part = job::tessellate_iges(&args.part, &options)?;
    let warnings = job::tessellation_warnings(&part, &options);
    for w in &warnings {
        eprintln!("warning: {name}: {w}");
    }
    let surfaces = Arc::new(job::PartSurfaces {
        faces: part.model.faces,
        face_of_triangle: part.tessellation.face_of_triangle,
        tolerance: args.tolerance,
    });
    let raw = crate::mesh::io::RawMesh {
        mesh: part.tessellation.mesh,
        warnings,
    };
    let defaults = job::RoughOptions::default();
    let options = job::RoughBoxesOptions {
        rough: job::RoughOptions {
            allowance: args.allowance,
            up: args.up,
            blank: args.stock.clone(),
            spindle_rpm: args.spindle_rpm,
            feeds: crate::rough::RoughingFeeds {
                cut: args.feed,
                entry: args.entry_feed,
                ..defaults.feeds.clone()
            },
            resolution: args.resolution,
            max_depth: Some(max_depth),
            min_depth: Some(min_depth),
            // The seed's comparison is of layers and pockets: straight passes at the
            // programmed feeds on both routes.
            max_engagement: 1.0,
            feed_control: None,
            ..defaults
        },
        cutter,
        stickout: args.stickout,
        max_box_width: args.box_width.unwrap_or(f64::INFINITY),
        merge: if args.deepest_layers {
            crate::rough::boxes::LayerMerge::Deepest
        } else {
            crate::rough::boxes::LayerMerge::Upward
        },
        compare_uniform: args.compare,
    };
    let output = job::rough_boxes(&raw, surfaces, &name, "mm", &options)?;
    job::write_rough_outputs(&args.out, &output, !args.no_timings)?;
    let r = &output.report;
    if let Some(boxes) = &r.hull_boxes {
        say!(
            "{name}: {} faces, {} Bézier patches boxed ({} left out, outside their trims); {} \
             points of the surfaces and their mesh checked, all inside their face's boxes",
            boxes.faces,
            boxes.patches,
            boxes.trimmed_away,
            boxes.enclosure.samples + boxes.mesh_enclosure.samples
        );
    }
    for t in &r.tools {
        if let Some(b) = &t.box_layers {
            say!(
                "  T{} {}: {} planes at box tops, {} patches split → {} boxes, {} layers \
                 ({} even slab(s) above or beside the boxes)",
                t.tool.id,
                t.tool.description,
                b.planes_at_box_tops,
                b.splits,
                b.patches_after_splits,
                b.layers,
                b.even_slabs
            );
        }
        if let Some(c) = &t.overcut_vs_boxes {
            say!(
                "  checks: the posted moves keep {:.4} mm off every box above the tip, {:.3} mm \
                 off the part; no gouge, rapid through material, or shank or holder touch",
                c.min_clearance_mm,
                t.overcut_vs_part.min_clearance_mm
            );
        }
    }
    if let Some(rows) = &r.comparison {
        say!(
            "  {:<11} {:>6} {:>11} {:>11} {:>9} {:>12} {:>10}",
            "route",
            "layers",
            "cut m",
            "path m",
            "time min",
            "left mm³",
            "rest mean"
        );
        for row in rows {
            say!(
                "  {:<11} {:>6} {:>11.2} {:>11.2} {:>9.1} {:>12.0} {:>10.2}",
                row.route,
                row.layers,
                row.cutting_length_mm / 1000.0,
                row.path_length_mm / 1000.0,
                row.estimated_time_s / 60.0,
                row.material_left_mm3,
                row.rest_mean_mm
            );
        }
    }
    say!("  wrote {}", args.out.display());
    Ok(())
}
