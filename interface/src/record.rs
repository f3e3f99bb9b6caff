//! Motion demonstrations recorded from the scripted expert, for training
//! the sub-goal planner and the dynamics policy.
//!
//! For every sub-goal: what the sub-goal planner will observe (the feature
//! the reasoner selects: the product's centre when picking, the slot's
//! centre at its box's rim when placing; the product's height; the tool tip; the label, 0 = pick or the slot's)
//! and the sub-goal reached. Along the way to it, [`SAMPLES_PER_SUBGOAL`]
//! (delta, action) pairs: delta = sub-goal − tool tip, action = the
//! expert's next joint step of base, shoulder and elbow towards the
//! sub-goal's joints, each clipped to ±[`MAX_ACTION`].

use crate::joints::Joints;
use crate::outcome::Stage;

/// (delta, action) samples recorded per sub-goal.
pub const SAMPLES_PER_SUBGOAL: usize = 20;
/// The largest joint step of an action, radians (5 degrees).
pub const MAX_ACTION: f64 = 5.0 * std::f64::consts::PI / 180.0;

#[derive(Debug, Clone, PartialEq)]
pub struct SubGoalSample {
    /// The selected feature: product centre (picking) or the slot's
    /// centre at its box's rim (placing).
    pub feature: [f64; 3],
    /// The handled product's height.
    pub height: f64,
    /// The tool tip when the sub-goal is issued.
    pub tool: [f64; 3],
    /// 0 = pick, else the slot's label.
    pub label: u32,
    pub stage: Stage,
    /// 0, 1, 2: which of the stage's sub-goals.
    pub index: u8,
    /// The tool tip the expert reached.
    pub target: [f64; 3],
    /// The arm's joints when the sub-goal is issued.
    pub start: Joints,
    /// The joints the expert reached it with.
    pub goal: Joints,
}

#[derive(Debug, Clone, PartialEq)]
pub struct ActionSample {
    /// Index into [`MotionLog::subgoals`].
    pub subgoal: usize,
    pub delta: [f64; 3],
    /// Base, shoulder and elbow positions when the action is taken.
    pub joints: [f64; 3],
    /// Joint steps of base, shoulder, elbow (radians).
    pub action: [f64; 3],
}

/// Everything recorded while the expert packs.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MotionLog {
    pub subgoals: Vec<SubGoalSample>,
    pub actions: Vec<ActionSample>,
}

/// Indices of `n` samples spread evenly over `len` (all of them if fewer).
pub fn spread(len: usize, n: usize) -> Vec<usize> {
    if len <= n {
        return (0..len).collect();
    }
    (0..n).map(|i| i * (len - 1) / (n - 1).max(1)).collect()
}

/// The expert's action at `q` towards `goal`: the base, shoulder and elbow
/// differences, scaled down together so that none exceeds
/// ±[`MAX_ACTION`] (the step stays on the straight joint-space line the
/// expert moves along). The base turns the short way (its difference
/// within ±π): the policy's rollouts turn the base freely and bring the
/// end into the limits after (the same pose), so the long way round a
/// limit is the same motion, and one state never has two labels.
pub fn action(q: &Joints, goal: &Joints) -> [f64; 3] {
    clip([short_way(goal[0] - q[0]), goal[1] - q[1], goal[2] - q[2]])
}

/// `turn` plus the multiple of 2π that puts it within (−π, π].
pub fn short_way(turn: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    let wrapped = turn - TAU * (turn / TAU).round();
    if wrapped <= -PI {
        wrapped + TAU
    } else {
        wrapped
    }
}

/// `step` scaled down, direction kept, so that no joint moves more than
/// [`MAX_ACTION`].
pub fn clip(step: [f64; 3]) -> [f64; 3] {
    let largest = step.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    if largest > MAX_ACTION {
        step.map(|v| v * MAX_ACTION / largest)
    } else {
        step
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_and_clip() {
        assert_eq!(spread(5, 20), vec![0, 1, 2, 3, 4]);
        let s = spread(1000, 20);
        assert_eq!(s.len(), 20);
        assert_eq!((s[0], s[19]), (0, 999));
        let a = action(&[0.0; 6], &[1.0, -0.01, -1.0, 0.0, 0.0, 0.0]);
        assert_eq!(a, [MAX_ACTION, -0.01 * MAX_ACTION, -MAX_ACTION]);
        let small = action(&[0.0; 6], &[0.01, -0.02, 0.03, 1.0, 1.0, 1.0]);
        assert_eq!(small, [0.01, -0.02, 0.03]);
    }

    #[test]
    fn the_base_turns_the_short_way() {
        use std::f64::consts::{PI, TAU};
        for (turn, short) in [
            (0.3, 0.3),
            (-0.3, -0.3),
            (PI, PI),
            (-PI, PI),
            (3.5, 3.5 - TAU),
            (-3.5, TAU - 3.5),
            (10.0, 10.0 - 2.0 * TAU),
        ] {
            assert!((short_way(turn) - short).abs() < 1e-12, "{turn}");
        }
        // A turn of 200 degrees to the goal is a step back towards it the
        // other way (the same pose, 160 degrees away).
        let a = action(&[0.0; 6], &[200f64.to_radians(), 0.0, 0.0, 0.0, 0.0, 0.0]);
        assert_eq!(a, [-MAX_ACTION, 0.0, 0.0]);
    }
}
