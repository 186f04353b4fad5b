//! The plan pipeline run stage by stage through the public API, on the bundled sample
//! impeller: what `wavemill plan` does, with each stage's plain-data result in hand.
//!
//! `cargo run --release --example plan_stages [PART]` (default `data/impeller.glb`). A
//! coarse scallop keeps it quick; one semi-finishing operation shows the operation chain.

use wavemill::geom::MoveKind;
use wavemill::job::{self, InProcessStock, Job, OperationKind, OperationTarget, PlanSetup, Quiet};
use wavemill::verify::{PoseChecks, PostedOptions, check_posted, verify};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let part_file = std::env::args()
        .nth(1)
        .unwrap_or_else(|| concat!(env!("CARGO_MANIFEST_DIR"), "/data/impeller.glb").into());
    let mut job = Job::default();
    // The stages of the ball operations; `job::plan` runs roughing from a blank.
    job.stock.blank = None;
    job.strategy.scallop_height = 0.1;
    job.strategy.semi_finish_allowances = vec![0.5];
    job.validate()?;
    let operations = job.operations()?;

    // 1. The part, welded, repaired and upright.
    let raw = job::load_part(part_file.as_ref(), "mm")?;
    let prepared = job::prepare_part(&raw, &part_file, &job)?;
    println!(
        "part: {} triangles, {} stray pieces set aside",
        prepared.part.triangles.len(),
        prepared.stray_pieces.len()
    );

    // 2. The drive surface: the finest level of the part's hierarchy.
    let (drive, surface) = job::drive_surface(&prepared.part, &job.surface)?;
    println!(
        "drive surface: {} ({} triangles, {:.4} mm from the part)",
        surface.source, surface.triangles, surface.hausdorff_to_part_mm
    );

    // 3. The cell: collision structures, tool, machine, tolerance budget.
    let setup = PlanSetup::new(&prepared, &job)?;
    println!(
        "tolerance {} mm: chord {:.4} + linearisation {:.4} + rounding {:.4}",
        setup.budget.total_mm,
        setup.budget.chord_mm,
        setup.budget.linearisation_mm,
        setup.budget.rounding_mm
    );

    // 4. The stock-to-leave shapes the semi-finishing operations machine to.
    let shapes = job::stock_to_leave_shapes(&prepared.part, &job, &operations)?;
    let mut shapes_left = shapes.iter();

    // 5. Each operation from the stock the ones before it leave.
    let mut stock = InProcessStock::Blank;
    let mut planned = Vec::new();
    for operation in &operations {
        let target = match operation.kind {
            OperationKind::SemiFinish => {
                let (level, shape) = shapes_left.next().ok_or("a shape per semi-finish")?;
                OperationTarget::Shape {
                    level: *level,
                    shape,
                }
            }
            OperationKind::Finish => OperationTarget::DriveSurface(&drive),
            // Roughing has its own stage (`job::plan_roughing`, from a `[stock]` blank; channel
            // roughing `job::channel_rough` on the stock it leaves) and a program with tool
            // changes (`job::post_program_with_tool_changes`): `job::plan` wires it in.
            OperationKind::Rough
            | OperationKind::RestRough
            | OperationKind::IndexedRough
            | OperationKind::ChannelRough => {
                return Err(format!(
                    "{}: this example runs the ball operations only; job::plan runs roughing",
                    operation.name
                )
                .into());
            }
            // A smaller ball along an impeller's roots (`OperationTarget::Impeller` with a
            // band, on `PlanSetup::with_ball`'s cell): `job::plan` wires it in.
            OperationKind::CornerFinish => {
                return Err(format!(
                    "{}: this example finishes with one ball; job::plan runs corner finishing",
                    operation.name
                )
                .into());
            }
        };
        let p = job::plan_operation(&setup, operation, target, &stock, None, &|| ())?;
        let cuts = p
            .toolpath
            .moves
            .iter()
            .filter(|m| m.kind == MoveKind::Cut)
            .count();
        println!("{}: {cuts} cut poses", operation.name);
        stock = stock.after(operation);
        planned.push(p);
    }

    // 6. One program; 7. every pose and chord verified, posted, and read back.
    let (toolpath, _) = job::join_operations(&planned);
    let poses = verify(
        &toolpath,
        &setup.collider,
        &setup.prepared_tool,
        setup.search,
        PoseChecks::Everything,
    );
    println!(
        "least ball clearance over poses and chords: {:+.5} mm",
        poses.min_cutter_clearance.min(poses.min_chord_clearance)
    );
    let as_impeller = planned
        .iter()
        .any(job::PlannedOperation::finished_as_impeller);
    let header = job::program_header(&prepared, &job, &setup, &operations, as_impeller);
    let (blocks, gcode) = job::post_program(&setup, &toolpath, &header)?;
    let posted = check_posted(
        &gcode,
        &setup.verifier_model(&[(setup.tool.id, setup.tool.total_length())]),
        &prepared.part,
        &PostedOptions {
            ball_radius: setup.prepared_tool.ball_radius,
            feed_error_mm: setup.budget.verification_mm,
            rapid_error_mm: setup
                .budget
                .verification_mm
                .max(0.1 * job.safety.shank_margin),
            search_mm: setup.search,
            tool: None,
            rounding_mm: setup.budget.rounding_mm,
            flutes_above_ball: setup
                .prepared_tool
                .flutes_above_ball()
                .map_or(0.0, |(length, _)| length),
        },
    )?;
    println!(
        "{} blocks; as posted, least ball clearance along feed moves {:+.5} mm, rapids {:.4} mm",
        blocks.len(),
        posted.min_feed_clearance_mm,
        posted.min_rapid_clearance_mm
    );
    if let Some(flutes) = &posted.flutes {
        println!(
            "  ball and flutes together: {:+.5} mm along feed moves",
            flutes.min_feed_clearance_mm
        );
    }

    // The same chain in one call.
    let whole = job::plan(&raw, &part_file, "mm", &job, &Quiet)?;
    assert_eq!(
        whole.gcode, gcode,
        "the stages give the program plan() posts"
    );
    println!("job::plan posts the same program");
    Ok(())
}
