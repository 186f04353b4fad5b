//! The material between operations: what the runner passes from one operation to the next
//! ([`InProcessStock`]). The operations themselves are read from the job file
//! ([`super::config::Operation`], `[[operation]]` tables) and planned in order by
//! [`super::pipeline::plan`].

use super::config::Operation;

/// What an operation's planner knows of the material the operations before it leave: the
/// stock to leave they were planned to. The material itself, when the job names a `[stock]`
/// blank, is a tri-dexel model the planned operations are run on afterwards, in order
/// ([`crate::job::run_operations`]: what each removes, and whether its shank or holder
/// touches what is left). Planning *from* that material (roughing the blank, rest roughing
/// where it stands) is the roughing work still to come; it will pass the model here.
#[derive(Clone, Debug, PartialEq)]
pub enum InProcessStock {
    /// The blank as clamped: nothing is modelled about it yet.
    Blank,
    /// An earlier operation left at least this much on the whole part, mm (verified by its
    /// own checks against the part).
    AtLeast { stock_to_leave: f64 },
}

impl InProcessStock {
    /// The stock after `operation` has been machined from `self`.
    pub fn after(&self, operation: &Operation) -> InProcessStock {
        InProcessStock::AtLeast {
            stock_to_leave: operation.stock_to_leave,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::job::config::{Job, OperationKind};

    fn job(toml_text: &str) -> Result<Vec<Operation>, String> {
        Job::from_toml(toml_text, "job.toml")
            .and_then(|job| job.operations())
            .map_err(|e| e.to_string())
    }

    /// Today's keys still mean one semi-finishing operation per allowance, then finishing, on
    /// a part taken as roughed.
    #[test]
    fn a_job_without_operation_tables_reads_as_before() {
        let ops = job("[stock]\nblank = \"none\"\n\
             [strategy]\nsemi_finish_allowances = [1.0, 0.3]\nscallop_height = 0.02\n")
        .expect("job");
        let kinds: Vec<(OperationKind, f64, f64)> = ops
            .iter()
            .map(|o| (o.kind, o.stock_to_leave, o.scallop_height))
            .collect();
        assert_eq!(
            kinds,
            vec![
                (OperationKind::SemiFinish, 1.0, 0.05),
                (OperationKind::SemiFinish, 0.3, 0.05),
                (OperationKind::Finish, 0.0, 0.02),
            ]
        );
        assert_eq!(
            job("[stock]\nblank = \"none\"\n").expect("roughed").len(),
            1
        );
        // By default the bar stock is roughed first: rough, one rest tool, finish.
        assert_eq!(job("").expect("defaults").len(), 3);
    }

    /// The same plan written as `[[operation]]` tables resolves to the same operations.
    #[test]
    fn operation_tables_resolve_to_the_same_operations() {
        let listed = job(
            "[stock]\nblank = \"none\"\n[strategy]\nscallop_height = 0.02\n\
             [[operation]]\nkind = \"semi-finish\"\nstock_to_leave = 1.0\n\
             [[operation]]\nkind = \"semi-finish\"\nstock_to_leave = 0.3\n\
             [[operation]]\nkind = \"finish\"\n",
        )
        .expect("job");
        let legacy = job("[stock]\nblank = \"none\"\n\
                 [strategy]\nsemi_finish_allowances = [1.0, 0.3]\nscallop_height = 0.02\n")
        .expect("job");
        assert_eq!(listed, legacy);
    }

    #[test]
    fn broken_lists_are_refused_naming_the_operation() {
        for (text, says) in [
            (
                "[[operation]]\nkind = \"semi-finish\"\n",
                "operation 1 (semi-finish to 0 mm): semi-finish needs stock_to_leave > 0",
            ),
            (
                "[[operation]]\nkind = \"semi-finish\"\nstock_to_leave = 0.5\n[[operation]]\nkind = \"semi-finish\"\nstock_to_leave = 0.5\n[[operation]]\nkind = \"finish\"\n",
                "operation 2 (semi-finish to 0.5 mm): stock_to_leave 0.5 mm is not below",
            ),
            (
                "[[operation]]\nkind = \"finish\"\n[[operation]]\nkind = \"semi-finish\"\nstock_to_leave = 1.0\n",
                "operation 1 (finish): finishing must be the last",
            ),
            (
                "[[operation]]\nkind = \"semi-finish\"\nstock_to_leave = 1.0\n",
                "must end with one finishing operation",
            ),
            (
                "[[operation]]\nkind = \"finish\"\nstock_to_leave = 0.1\n",
                "finishing leaves no stock",
            ),
            (
                "[[operation]]\nkind = \"finish\"\nscallop_height = -1\n",
                "scallop_height must be a positive",
            ),
            (
                "[[operation]]\nkind = \"finish\"\n[operation.tool]\ndiameter = 3.0\n",
                "uses another ball than [tool]",
            ),
            (
                "[strategy]\nsemi_finish_allowances = [1.0]\n[[operation]]\nkind = \"finish\"\n",
                "both list operations",
            ),
            (
                "[[operation]]\nkind = \"finish\"\n[[operation]]\nkind = \"rough\"\n",
                "operation 1 (finish): finishing must be the last",
            ),
            (
                "[[operation]]\nkind = \"semi-finish\"\nstock_to_leave = 1.0\n\
                 [[operation]]\nkind = \"rough\"\nstock_to_leave = 0.5\n[[operation]]\nkind = \"finish\"\n",
                "operation 2 (rough to 0.5 mm): roughing from the blank must be the first",
            ),
            (
                "[[operation]]\nkind = \"rest-rough\"\n[[operation]]\nkind = \"finish\"\n",
                "rest-rough follows a roughing",
            ),
            (
                "[[operation]]\nkind = \"rough\"\nstock_to_leave = 0.5\n\
                 [[operation]]\nkind = \"rest-rough\"\nstock_to_leave = 0.8\n[[operation]]\nkind = \"finish\"\n",
                "stock_to_leave 0.8 mm is not below the 0.5 mm",
            ),
            (
                "[[operation]]\nkind = \"rough\"\n[operation.tool]\ndiameter = 10.0\n[[operation]]\nkind = \"finish\"\n",
                "name it by tool_id",
            ),
            (
                "[[operation]]\nkind = \"finish\"\ntool_id = 3\n",
                "tool_id names a library end mill",
            ),
            ("[[operation]]\nkind = \"face\"\n", "unknown variant `face`"),
            (
                "[[operation]]\nkind = \"finish\"\n[[operation]]\nkind = \"corner-finish\"\n",
                "corner-finish needs its own ball",
            ),
            (
                "[[operation]]\nkind = \"finish\"\n[[operation]]\nkind = \"corner-finish\"\n\
                 [operation.tool]\nid = 2\ndiameter = 6.0\n",
                "its ball (6 mm) must be smaller than the finishing ball (4 mm)",
            ),
            (
                "[[operation]]\nkind = \"finish\"\n[[operation]]\nkind = \"corner-finish\"\n\
                 [operation.tool]\ndiameter = 2.0\n",
                "give it its own id",
            ),
            (
                "[[operation]]\nkind = \"corner-finish\"\n[operation.tool]\nid = 2\ndiameter = 2.0\n\
                 [[operation]]\nkind = \"finish\"\n",
                "operation 1 (corner-finish): corner-finish follows the finishing operation",
            ),
            (
                "[[operation]]\nkind = \"finish\"\n\
                 [[operation]]\nkind = \"corner-finish\"\n[operation.tool]\nid = 2\ndiameter = 2.0\n\
                 [[operation]]\nkind = \"corner-finish\"\n[operation.tool]\nid = 3\ndiameter = 1.0\n",
                "operation 3 (corner-finish): corner-finish follows the finishing operation (and comes once)",
            ),
            (
                "[[operation]]\nkind = \"finish\"\n[[operation]]\nkind = \"corner-finish\"\n\
                 scallop_height = 1.5\n[operation.tool]\nid = 2\ndiameter = 2.0\n",
                "scallop_height 1.5 must be smaller than its ball's radius 1",
            ),
            (
                "[[operation]]\nkind = \"finish\"\n[[operation]]\nkind = \"corner-finish\"\n\
                 [operation.tool]\nid = 2\ndiameter = 2.0\nstickout = -1.0\n",
                "operation 2 (corner-finish): its [operation.tool]:",
            ),
            (
                "[corner_tool]\nid = 2\ndiameter = 2.0\n[[operation]]\nkind = \"finish\"\n",
                "[corner_tool] and [[operation]] tables both list operations",
            ),
        ] {
            let err = job(text).expect_err(text);
            assert!(err.contains(says), "{text}: {err}");
        }
    }

    /// With a blank and no listed operations, the job roughs to `roughing.allowance` with one
    /// tool, rest-roughs with `roughing.rest_tools` more, then semi-finishes and finishes; a
    /// rest-roughing tool may rough to the shape the one before it roughed to.
    #[test]
    fn a_job_with_a_blank_roughs_first() {
        let ops = job(
            "[stock]\nblank = \"cylinder\"\n[roughing]\nallowance = 0.8\nrest_tools = 2\n\
             [strategy]\nsemi_finish_allowances = [0.3]\n",
        )
        .expect("job");
        let kinds: Vec<(OperationKind, f64)> =
            ops.iter().map(|o| (o.kind, o.stock_to_leave)).collect();
        assert_eq!(
            kinds,
            vec![
                (OperationKind::Rough, 0.8),
                (OperationKind::RestRough, 0.8),
                (OperationKind::RestRough, 0.8),
                (OperationKind::SemiFinish, 0.3),
                (OperationKind::Finish, 0.0),
            ]
        );
        assert_eq!(ops[0].name, "rough to 0.8 mm");
        // A near-net blank is taken as roughed.
        let near_net = job("[stock]\nblank = \"offset:3\"\n").expect("job");
        assert_eq!(near_net.len(), 1);
        let listed = job("[[operation]]\nkind = \"rough\"\ntool_id = 3\n\
             [[operation]]\nkind = \"rest-rough\"\nstock_to_leave = 0.2\n[[operation]]\nkind = \"finish\"\n")
        .expect("job");
        assert_eq!(listed[0].library_tool, Some(3));
        assert_eq!(listed[0].stock_to_leave, 0.5);
        assert_eq!(listed[1].library_tool, None);
    }

    /// A `[corner_tool]` puts a corner finish with it after the finishing; listed, it is the
    /// same operation.
    #[test]
    fn a_corner_tool_finishes_the_corners_last() {
        let ops =
            job("[stock]\nblank = \"none\"\n[corner_tool]\nid = 2\ndiameter = 2.0\n").expect("job");
        let kinds: Vec<OperationKind> = ops.iter().map(|o| o.kind).collect();
        assert_eq!(kinds, [OperationKind::Finish, OperationKind::CornerFinish]);
        assert_eq!(ops[1].tool.diameter, 2.0);
        assert_eq!(ops[1].tool.id, 2);
        assert_eq!(ops[1].stock_to_leave, 0.0);
        assert_eq!(ops[0].tool.diameter, 4.0);
        let listed = job(
            "[stock]\nblank = \"none\"\n[[operation]]\nkind = \"finish\"\n\
             [[operation]]\nkind = \"corner-finish\"\n[operation.tool]\nid = 2\ndiameter = 2.0\n",
        )
        .expect("job");
        assert_eq!(listed, ops);
    }

    /// `bound = "hull-boxes"` sets a rough or rest-rough operation's boxes (the seed's model
    /// by default); it and its keys are refused anywhere else.
    #[test]
    fn hull_box_roughing_is_a_bound_of_the_layer_operations() {
        let ops = job("[stock]\nblank = \"cylinder\"\n[[operation]]\nkind = \"rough\"\n\
             bound = \"hull-boxes\"\nbox_layers = \"deepest\"\n[[operation]]\nkind = \"rest-rough\"\n\
             bound = \"hull-boxes\"\nbox_width = 4.0\n[[operation]]\nkind = \"finish\"\n")
        .expect("job");
        let boxes: Vec<Option<crate::job::config::BoxBound>> =
            ops.iter().map(|o| o.boxes).collect();
        use crate::rough::boxes::LayerMerge;
        assert_eq!(
            boxes,
            vec![
                Some(crate::job::config::BoxBound {
                    max_box_width: f64::INFINITY,
                    merge: LayerMerge::Deepest
                }),
                Some(crate::job::config::BoxBound {
                    max_box_width: 4.0,
                    merge: LayerMerge::Upward
                }),
                None,
            ]
        );
        for (text, says) in [
            (
                "[[operation]]\nkind = \"semi-finish\"\nstock_to_leave = 0.3\nbound = \"hull-boxes\"\n",
                "rough and rest-rough",
            ),
            (
                "[[operation]]\nkind = \"rough\"\nbox_width = 3.0\n",
                "box_width and box_layers",
            ),
            (
                "[[operation]]\nkind = \"rough\"\nbound = \"hull-boxes\"\nbox_width = -1.0\n",
                "positive",
            ),
        ] {
            let text =
                format!("[stock]\nblank = \"cylinder\"\n{text}[[operation]]\nkind = \"finish\"\n");
            let err = job(&text).expect_err(&text);
            assert!(err.contains(says), "{text}: {err}");
        }
    }

    /// Channel roughing: after the end mills by `[roughing] channel`, or listed after a
    /// roughing operation, with its layers' step and count; refused anywhere it would have no
    /// stock model to find its material in, and its layer keys refused on other kinds.
    #[test]
    fn channel_roughing_follows_the_end_mills() {
        let ops = job(
            "[stock]\nblank = \"cylinder\"\n[roughing]\nchannel = true\n\
             channel_max_layers = 5\n[tool]\ndiameter = 6.0\n",
        )
        .expect("job");
        let kinds: Vec<OperationKind> = ops.iter().map(|o| o.kind).collect();
        assert_eq!(
            kinds,
            vec![
                OperationKind::Rough,
                OperationKind::RestRough,
                OperationKind::ChannelRough,
                OperationKind::Finish,
            ]
        );
        // The step defaults to the ball's radius.
        assert_eq!(
            ops[2].layers,
            Some(crate::job::ChannelLayers {
                step: 3.0,
                max_layers: 5,
                layering: crate::job::Layering::ShroudToHub,
            })
        );
        assert_eq!(ops[2].stock_to_leave, 0.5);
        assert!(
            ops.iter()
                .filter(|o| o.kind != OperationKind::ChannelRough)
                .all(|o| o.layers.is_none())
        );
        // Without a blank to rough, `channel` adds nothing.
        let none = job("[stock]\nblank = \"none\"\n[roughing]\nchannel = true\n").expect("job");
        assert_eq!(none.len(), 1);
        let listed = job("[[operation]]\nkind = \"rough\"\n\
             [[operation]]\nkind = \"channel-rough\"\nstep = 1.5\nmax_layers = 3\n\
             layering = \"offset\"\n\
             [[operation]]\nkind = \"semi-finish\"\nstock_to_leave = 0.2\n\
             [[operation]]\nkind = \"finish\"\n")
        .expect("job");
        assert_eq!(
            listed[1].layers,
            Some(crate::job::ChannelLayers {
                step: 1.5,
                max_layers: 3,
                layering: crate::job::Layering::Offset,
            })
        );
        for (text, says) in [
            (
                "[[operation]]\nkind = \"channel-rough\"\n[[operation]]\nkind = \"finish\"\n",
                "follows the roughing of a blank",
            ),
            (
                "[[operation]]\nkind = \"rough\"\n[[operation]]\nkind = \"semi-finish\"\n\
                 stock_to_leave = 0.3\n[[operation]]\nkind = \"channel-rough\"\n\
                 stock_to_leave = 0.2\n[[operation]]\nkind = \"finish\"\n",
                "follows the roughing of a blank",
            ),
            (
                "[[operation]]\nkind = \"rough\"\n[[operation]]\nkind = \"channel-rough\"\n\
                 stock_to_leave = 0.8\n[[operation]]\nkind = \"finish\"\n",
                "not below",
            ),
            (
                "[[operation]]\nkind = \"rough\"\n[[operation]]\nkind = \"channel-rough\"\n\
                 step = 0\n[[operation]]\nkind = \"finish\"\n",
                "positive",
            ),
            (
                "[[operation]]\nkind = \"rough\"\nstep = 1\n[[operation]]\nkind = \"finish\"\n",
                "channel-rough alone",
            ),
            ("[roughing]\nchannel_step = -1\n", "roughing.channel_step"),
            (
                "[roughing]\nchannel_max_layers = 0\n",
                "roughing.channel_max_layers",
            ),
        ] {
            let err = Job::from_toml(text, "job.toml")
                .and_then(|job| job.validate())
                .err()
                .unwrap_or_else(|| panic!("accepted: {text}"))
                .to_string();
            assert!(err.contains(says), "{text}: {err}");
        }
    }

    #[test]
    fn the_stock_after_an_operation_is_what_it_leaves() {
        let ops = job("[stock]\nblank = \"none\"\n[strategy]\nsemi_finish_allowances = [0.4]\n")
            .expect("job");
        let mut stock = InProcessStock::Blank;
        let mut seen = Vec::new();
        for op in &ops {
            stock = stock.after(op);
            seen.push(stock.clone());
        }
        assert_eq!(
            seen,
            vec![
                InProcessStock::AtLeast {
                    stock_to_leave: 0.4
                },
                InProcessStock::AtLeast {
                    stock_to_leave: 0.0
                },
            ]
        );
    }
}
