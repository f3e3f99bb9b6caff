//! What the networks read: the training examples (plain numbers) and the
//! input encodings shared by training and run time.

/// Scale of the dynamics policy's outputs: actions are learnt as fractions
/// of the largest joint step (5 degrees).
pub const ACTION_SCALE: f32 = packwright_interface::record::MAX_ACTION as f32;

/// Inputs per node: (x, y, z, I) and the node's place along the chain,
/// 0 for the first present product to 1 for the last.
pub const NODE_FEATURES: usize = 5;

/// One reasoner decision: the graph of the present products at the start of
/// a stage and what the demonstrator did.
#[derive(Debug, Clone, PartialEq)]
pub struct GraphExample {
    /// (x, y, z, I) of each present product, in inventory order.
    pub nodes: Vec<[f32; 4]>,
    /// The handled product's goal position.
    pub goal: [f32; 3],
    /// The chosen node, or `nodes.len()` for the box.
    pub target: usize,
    /// 0 = pick, k = the k-th slot of the cell.
    pub label: usize,
}

/// One sub-goal issued by the demonstrator.
#[derive(Debug, Clone, PartialEq)]
pub struct SubGoalExample {
    /// The selected feature: product centre (picking) or box top centre
    /// (placing).
    pub feature: [f32; 3],
    /// The tool tip when the sub-goal was issued.
    pub tool: [f32; 3],
    pub label: usize,
    /// 0, 1, 2: which of the stage's three sub-goals.
    pub index: usize,
    /// The tool tip reached.
    pub target: [f32; 3],
}

/// One joint action of the demonstrator.
#[derive(Debug, Clone, PartialEq)]
pub struct ActionExample {
    /// Sub-goal minus tool tip.
    pub delta: [f32; 3],
    /// Base, shoulder and elbow positions when the action was taken.
    pub joints: [f32; 3],
    /// Base, shoulder and elbow steps (radians, at most 5 degrees each).
    pub action: [f32; 3],
}

/// Everything the three networks learn from.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TrainingSet {
    pub graphs: Vec<GraphExample>,
    pub subgoals: Vec<SubGoalExample>,
    pub actions: Vec<ActionExample>,
    /// Number of labels: `pick` plus the cell's slots.
    pub labels: usize,
}

/// The sub-goal planner's input row: feature, tool − feature, one-hot
/// label, one-hot sub-goal index.
pub fn subgoal_input(
    out: &mut Vec<f32>,
    feature: [f32; 3],
    tool: [f32; 3],
    label: usize,
    index: usize,
    labels: usize,
) {
    out.extend(feature);
    out.extend((0..3).map(|j| tool[j] - feature[j]));
    one_hot(out, label, labels);
    one_hot(out, index, 3);
}

pub fn subgoal_width(labels: usize) -> usize {
    6 + labels + 3
}

/// Appends a one-hot row of `n` with a 1 at `k` (none when `k >= n`).
pub fn one_hot(out: &mut Vec<f32>, k: usize, n: usize) {
    out.extend((0..n).map(|i| if i == k { 1.0 } else { 0.0 }));
}
