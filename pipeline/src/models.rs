//! Model directories on disk, the bundled model (`models/default/`,
//! compiled into the binary), and which planner packs a cell.

use crate::error::{PipelineError, Result};
use packwright_compiler::Compiled;
use packwright_interface::{PlannerKind, SequenceRule};
use packwright_nets::{FILES, Networks};
use std::path::Path;

/// The bundled model (`models/default/`), trained by `packwright train`
/// on `orders/` (`scripts/train-default.sh`).
const DEFAULT: [&[u8]; 4] = [
    include_bytes!("../../models/default/config.json"),
    include_bytes!("../../models/default/reasoner.safetensors"),
    include_bytes!("../../models/default/subgoal.safetensors"),
    include_bytes!("../../models/default/dynamics.safetensors"),
];

pub fn default_model() -> Result<Networks> {
    Networks::from_files(DEFAULT[0], DEFAULT[1], DEFAULT[2], DEFAULT[3]).map_err(|why| {
        PipelineError::Model {
            what: "the bundled default model".into(),
            why,
        }
    })
}

/// A model directory written by `packwright train`.
pub fn load_model(dir: &Path) -> Result<Networks> {
    let read = |name: &str| {
        let path = dir.join(name);
        crate::regular::read(&path).map_err(|e| PipelineError::Read {
            reason: format!("{e} (a model directory holds the files `packwright train` writes)"),
            path,
        })
    };
    Networks::from_files(
        &read(FILES[0])?,
        &read(FILES[1])?,
        &read(FILES[2])?,
        &read(FILES[3])?,
    )
    .map_err(|why| PipelineError::Model {
        what: format!("{} is not a usable model", dir.display()),
        why,
    })
}

/// The planner to use and, for the learned one, its networks: `model`
/// when given, else the bundled model, unless `asked` for another planner.
/// A model answers about any cell (its inputs are relative to the cell's
/// geometry; the bundled model was taught 17 cells and measured on 20
/// others); whether it was taught the order's cell is for the caller to
/// say ([`taught`]). Without a usable bundled model, the expert.
pub fn choose_planner(
    asked: Option<PlannerKind>,
    model: Option<&Path>,
) -> Result<(PlannerKind, Option<Networks>)> {
    let nets = match (asked, model) {
        (Some(PlannerKind::Expert | PlannerKind::Rrt), _) => None,
        (_, Some(dir)) => Some(load_model(dir)?),
        (Some(PlannerKind::Learned), None) => Some(default_model()?),
        (None, None) => default_model().ok(),
    };
    let planner = match (asked, &nets) {
        (Some(p), _) => p,
        (None, Some(_)) => PlannerKind::Learned,
        (None, None) => PlannerKind::Expert,
    };
    Ok((planner, nets))
}

/// What [`follow_cell_rule`] did.
#[derive(Debug, Clone, PartialEq)]
pub enum CellRule {
    /// The model was taught the cell: it follows the rule it was taught
    /// there (the cell's own where it kept one, [`Task::rule_for`]).
    ///
    /// [`Task::rule_for`]: packwright_nets::Task::rule_for
    Taught(SequenceRule),
    /// The compilation holds no demonstration of the cell that orders
    /// it (none, or only `sequence random` ones): the model's rule is
    /// kept.
    Undemonstrated,
    /// The cell's demonstrations follow the model's own rule.
    Same(SequenceRule),
    /// The model now follows the rule the cell's demonstrations show.
    Followed(SequenceRule),
    /// The cell's demonstrations follow no one rule (as `sequence random`
    /// teaches): the model's rule is kept.
    NoRule,
}

/// Makes `nets`, on `cell` of `compiled` which it was not taught, follow
/// the sequence rule that the compilation's demonstrations of that cell
/// show ([`crate::teach::cell_rule`]), so that a model serving many cells
/// packs each in the order its own file teaches; on a cell it was taught,
/// the rule it was taught there.
pub fn follow_cell_rule(nets: &mut Networks, compiled: &Compiled, cell: &str) -> CellRule {
    if taught(nets, cell) {
        nets.task.sequence = nets.task.rule_for(cell).clone();
        return CellRule::Taught(nets.task.sequence.clone());
    }
    match crate::teach::cell_rule(compiled, cell) {
        Ok(Some(inferred)) if inferred.rule != nets.task.sequence => {
            nets.task.sequence = inferred.rule.clone();
            CellRule::Followed(inferred.rule)
        }
        Ok(Some(inferred)) => CellRule::Same(inferred.rule),
        Ok(None) => CellRule::Undemonstrated,
        Err(_) => CellRule::NoRule,
    }
}

/// The order the expert and RRT-Connect handle `cell`'s products in: the
/// learned planner's when one runs beside them (`nets`, after
/// [`follow_cell_rule`]), so that the planners pack the same sequence;
/// else the one rule the compilation's demonstrations of the cell show;
/// else inventory order.
pub fn baseline_rule(nets: Option<&Networks>, compiled: &Compiled, cell: &str) -> SequenceRule {
    match nets {
        Some(n) => n.task.sequence.clone(),
        None => crate::teach::cell_rule(compiled, cell)
            .ok()
            .flatten()
            .map_or(SequenceRule::Ascending, |inferred| inferred.rule),
    }
}

/// Whether `nets` was taught demonstrations in `cell`.
pub fn taught(nets: &Networks, cell: &str) -> bool {
    nets.task.cells.iter().any(|c| c == cell)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On a cell it was taught, a model follows the rule it was taught
    /// there: the cell's own where it kept one, else the one for every
    /// cell; and the expert and RRT-Connect beside it follow the same.
    #[test]
    fn a_taught_cell_is_packed_in_the_rule_taught_there() {
        let compiled = crate::teach::tests::rule_cell("");
        let Ok(mut nets) = default_model() else {
            panic!("the bundled model loads");
        };
        nets.task.cells = vec!["c".into(), "d".into()];
        nets.task.sequence = SequenceRule::Ascending;
        nets.task.cell_rules = [("c".to_owned(), SequenceRule::Descending)].into();
        let mut own = nets.clone();
        assert_eq!(
            follow_cell_rule(&mut own, &compiled, "c"),
            CellRule::Taught(SequenceRule::Descending)
        );
        assert_eq!(own.task.sequence, SequenceRule::Descending);
        assert_eq!(
            baseline_rule(Some(&own), &compiled, "c"),
            SequenceRule::Descending
        );
        let mut joint = nets.clone();
        assert_eq!(
            follow_cell_rule(&mut joint, &compiled, "d"),
            CellRule::Taught(SequenceRule::Ascending)
        );
        assert_eq!(joint.task.sequence, SequenceRule::Ascending);
    }
}
