//! What the learned loop asks of a trained model: the [`Policy`] trait,
//! and the inputs it is given. Every input is in terms that mean the same
//! in any cell (positions, goals, slots, the base axis), so one model can
//! be asked about cells it was not taught. `packwright-nets`'s `Networks`
//! is the implementation; tests drive the loop with their own (a scripted
//! reasoner, a policy that never moves, to exercise the fallbacks).

use crate::outcome::Stage;
use serde::{Deserialize, Serialize};

/// One product the reasoner sees.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Node {
    /// Its sensed centre.
    pub centre: [f32; 3],
    /// Its height (from the inventory).
    pub height: f32,
    /// Whether the order selects it.
    pub selected: bool,
    /// Where the order wants it (its own centre when it is not selected).
    pub goal: [f32; 3],
}

/// The reasoner's input at the start of a stage: the products seen, as a
/// chain in the taught sequence order ([`SequenceRule::chain`]), the
/// cell's slots, and the goal of the product in the cup (if any).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Graph {
    pub nodes: Vec<Node>,
    /// Each slot's centre on the box floor, in the cell's slot order.
    pub slots: Vec<[f32; 3]>,
    /// The held product's goal (zeros when nothing is held): the placing
    /// decision points at the slot that fits it.
    pub held_goal: [f32; 3],
}

/// The reasoner's decision at the start of a stage.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Choice {
    /// The node to pick, or `None` for the box.
    pub node: Option<usize>,
    /// 0 = pick, k = the k-th slot of the cell (from 1).
    pub label: usize,
}

/// The sub-goal planner's question.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SubGoalQuery {
    pub stage: Stage,
    /// 0, 1, 2: which of the stage's sub-goals.
    pub index: usize,
    /// The selected feature: the product's centre (picking), or the
    /// slot's centre at the height of its box's rim (placing).
    pub feature: [f32; 3],
    /// The cup tip now.
    pub tool: [f32; 3],
    /// The handled product's height.
    pub height: f32,
    /// The robot base's position (the arm turns about its vertical axis).
    pub base: [f32; 3],
}

/// The order in which the demonstrations handled products: what a model
/// was taught and what `eval` judges its decisions against. Products are
/// named as in the inventory.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SequenceRule {
    /// Inventory (listed) order.
    #[default]
    Ascending,
    /// Reverse inventory order.
    Descending,
    /// A priority list of product names; products it does not name come
    /// after, in inventory order.
    Listed(Vec<String>),
}

impl SequenceRule {
    /// The inventory indices of `names` (an inventory's products, in
    /// listed order) in the rule's order: the reasoner's chain.
    pub fn chain(&self, names: &[&str]) -> Vec<usize> {
        let mut order: Vec<usize> = (0..names.len()).collect();
        match self {
            SequenceRule::Ascending => {}
            SequenceRule::Descending => order.reverse(),
            SequenceRule::Listed(list) => {
                order.sort_by_key(|&i| {
                    list.iter()
                        .position(|n| n == names[i])
                        .unwrap_or(usize::MAX)
                });
            }
        }
        order
    }
}

impl std::fmt::Display for SequenceRule {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SequenceRule::Ascending => f.write_str("ascending (inventory order)"),
            SequenceRule::Descending => f.write_str("descending (reverse inventory order)"),
            SequenceRule::Listed(list) => write!(f, "listed: {}", list.join(", ")),
        }
    }
}

/// The three learned decisions, on plain numbers.
pub trait Policy: Sync {
    /// The reasoner: which node to pick, or the box (`node: None`) with
    /// the slot for the held product.
    fn reason(&self, graph: &Graph) -> Choice;
    /// The sub-goal planner: the next cup-tip position.
    fn subgoal(&self, query: &SubGoalQuery) -> [f32; 3];
    /// The dynamics policy: base, shoulder and elbow steps (radians) for
    /// `delta` = sub-goal − cup tip at those joints.
    fn action(&self, delta: [f32; 3], joints: [f32; 3]) -> [f32; 3];
    /// The sequence rule the reasoner was taught: its chain order.
    fn sequence(&self) -> SequenceRule;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chains_follow_the_rule() {
        let names = ["a", "b", "c", "d"];
        assert_eq!(SequenceRule::Ascending.chain(&names), [0, 1, 2, 3]);
        assert_eq!(SequenceRule::Descending.chain(&names), [3, 2, 1, 0]);
        let listed = SequenceRule::Listed(vec!["c".into(), "a".into()]);
        assert_eq!(listed.chain(&names), [2, 0, 1, 3]);
        let json = serde_json::to_string(&listed).unwrap_or_default();
        assert_eq!(json, r#"{"listed":["c","a"]}"#);
    }
}
