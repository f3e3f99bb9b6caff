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
/// The largest joint step of an action, radians (15 degrees). Each step is
/// one call of the dynamics policy in the learned planner's inner loop: at
/// 5 degrees the swing to the next product took some 22 calls, most of a
/// sub-goal's planning time beside its collision check; at 15 degrees
/// about 8. The steps' end is joined straight when that motion is free,
/// so the step size does not change the path the arm takes there.
pub const MAX_ACTION: f64 = 15.0 * std::f64::consts::PI / 180.0;

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

/// Largest change (rad) of a cup-down invariant that still counts as the
/// same wrist shape in [`keeps_cup_down`].
pub const SHAPE_TOLERANCE: f64 = 0.02;

/// Whether the straight joint motion from `start` to `goal` is one the
/// dynamics policy's steps can make: they move the base, shoulder and
/// elbow and turn the wrist so that the cup keeps pointing down with its
/// yaw (`execute::cup_down`), which keeps q1 + q2 + q3, q4 and q5 − q0
/// (modulo 2π) unchanged. A motion that changes them (the expert going to
/// another shape of the arm, where the nearest one collides) cannot be
/// imitated step by step, and its action labels would contradict the
/// others': such sub-goals are not taught to the dynamics policy (the
/// sub-goal planner still learns them; at run time RRT-Connect finishes
/// what the policy cannot).
pub fn keeps_cup_down(start: &Joints, goal: &Joints) -> bool {
    let wrap = |v: f64| short_way(v).abs();
    let pitch = |q: &Joints| q[1] + q[2] + q[3];
    let twist = |q: &Joints| q[5] - q[0];
    (pitch(goal) - pitch(start)).abs() <= SHAPE_TOLERANCE
        && (goal[4] - start[4]).abs() <= SHAPE_TOLERANCE
        && wrap(twist(goal) - twist(start)) <= SHAPE_TOLERANCE
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

    /// Cup-down poses of one UR10 cup tip (found on a probe cell): the
    /// arm's shape at the contact, the same shape 15 cm higher, another
    /// elbow shape, and a flipped wrist with the base turned round.
    #[test]
    fn a_change_of_wrist_shape_is_not_a_cup_down_motion() {
        let contact = [0.638, -2.132, -1.72, -4.002, -1.571, -4.074];
        let lifted = [0.638, -1.994, -1.625, -4.235, -1.571, -4.074];
        let elbow = [0.638, -3.549, 1.625, -5.931, -1.571, -4.074];
        let flipped = [3.281, 0.407, -1.625, -3.494, -4.712, -4.573];
        assert!(keeps_cup_down(&contact, &lifted));
        assert!(
            keeps_cup_down(&contact, &elbow),
            "the policy moves q0-q2 freely"
        );
        assert!(!keeps_cup_down(&contact, &flipped));
        // The base and wrist 3 turned together a whole turn: the same.
        let mut round = lifted;
        round[0] += std::f64::consts::TAU;
        assert!(keeps_cup_down(&contact, &round));
        let mut twisted = lifted;
        twisted[5] += 0.5;
        assert!(!keeps_cup_down(&contact, &twisted));
    }

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
