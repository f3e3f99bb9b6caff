//! What the learned loop asks of a trained model: the [`Policy`] trait.
//! `packwright-nets`'s `Networks` is the implementation; tests drive the
//! loop with their own (a scripted reasoner, a policy that never moves, to
//! exercise the fallbacks).

/// The reasoner's decision at the start of a stage.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Choice {
    /// The node to pick, or `None` for the box.
    pub node: Option<usize>,
    /// 0 = pick, k = the k-th slot.
    pub label: usize,
}

/// The three learned decisions, on plain numbers.
pub trait Policy: Sync {
    /// The reasoner: which of `nodes` (x, y, z, I of the present products,
    /// inventory order) to pick, or the box (`node: None`), and the label
    /// (0 = pick, k = the k-th slot). `goal_of(node)` gives the handled
    /// product's goal for the chosen node (`None`: the held product's).
    fn reason(&self, nodes: &[[f32; 4]], goal_of: &dyn Fn(Option<usize>) -> [f32; 3]) -> Choice;
    /// The sub-goal planner: the next cup-tip position for the stage's
    /// sub-goal `index` (0, 1, 2), from the selected feature, the cup tip
    /// and the label.
    fn subgoal(&self, feature: [f32; 3], tool: [f32; 3], label: usize, index: usize) -> [f32; 3];
    /// The dynamics policy: base, shoulder and elbow steps (radians) for
    /// `delta` = sub-goal − cup tip at those joints.
    fn action(&self, delta: [f32; 3], joints: [f32; 3]) -> [f32; 3];
}
