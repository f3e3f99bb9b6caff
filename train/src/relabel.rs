//! DAgger's expert for the dynamics policy (Ross et al., 2011).
//!
//! The demonstrations show the policy only the states on the expert's own
//! paths; a learnt policy drifts off them, and near a sub-goal it then
//! meets deltas it never saw and stalls short of it (ARCHITECTURE.md,
//! "Decisions"). [`ExpertCoach`] rolls the policy out with forward
//! kinematics from every demonstrated sub-goal start towards the
//! demonstrated sub-goal through the learned loop's own stepping
//! (`packwright_motion::execute::policy_steps`: clipped to 15 degrees, the
//! wrist keeping the cup down), and labels each state it visits with the
//! expert's action there: the straight joint-space step towards the joints
//! the expert reached the sub-goal with.

use crate::dagger::{Coach, Relabelled};
use nalgebra::Isometry3;
use packwright_interface::record::{self, MotionLog};
use packwright_kinematics::{Arm, Joints};
use packwright_motion::execute::{policy_steps, tolerance};
use packwright_nets::features::ActionExample;
use rayon::prelude::*;

/// One demonstrated sub-goal motion.
#[derive(Debug, Clone, PartialEq)]
pub struct Motion<'a> {
    /// The arm of its cell.
    pub arm: &'a Arm,
    pub start: Joints,
    /// The joints the expert reached the sub-goal with.
    pub goal: Joints,
    /// The tool tip there.
    pub target: [f64; 3],
    /// Reached within this distance (m), as the runtime loop judges it.
    pub tolerance: f64,
    /// The robot base of its cell.
    pub base: Isometry3<f64>,
    /// Its cell's cup length.
    pub suction: f64,
}

/// Where a log was recorded: its cell's arm, robot base and cup length.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Recorded<'l> {
    pub log: &'l MotionLog,
    pub arm: &'l Arm,
    pub base: [f64; 3],
    pub suction: f64,
}

/// The expert's labels for the states a policy visits, each motion with
/// its own cell's arm (a lesson of a UR3e's and a UR20's cells was once
/// rolled out with the first arm alone: none of the UR20's sub-goals was
/// reached, and nothing said why).
pub struct ExpertCoach<'a> {
    motions: Vec<Motion<'a>>,
}

impl<'a> ExpertCoach<'a> {
    /// The sub-goal motions of `logs` (expert replays, each by its arm).
    pub fn new(logs: &[Recorded<'a>]) -> Self {
        let motions = logs
            .iter()
            .flat_map(|r| r.log.subgoals.iter().map(move |s| (r, s)))
            // Only the motions the policy's cup-down steps can make
            // (`record::keeps_cup_down`), as in its training set.
            .filter(|(_, s)| record::keeps_cup_down(&s.start, &s.goal))
            .map(|(r, s)| Motion {
                arm: r.arm,
                start: s.start,
                goal: s.goal,
                target: s.target,
                tolerance: tolerance(s.stage, usize::from(s.index)),
                base: Isometry3::translation(r.base[0], r.base[1], r.base[2]),
                suction: r.suction,
            })
            .collect();
        ExpertCoach { motions }
    }

    pub fn motions(&self) -> &[Motion<'a>] {
        &self.motions
    }

    /// One rollout: the labelled states visited, and whether it reached the
    /// sub-goal within [`MAX_POLICY_STEPS`].
    fn rollout(
        &self,
        m: &Motion,
        policy: &(dyn Fn([f32; 3], [f32; 3]) -> [f32; 3] + Sync),
    ) -> (Vec<ActionExample>, bool) {
        let f = |v: [f64; 3]| v.map(|x| x as f32);
        let mut visited = Vec::new();
        let reached = policy_steps(
            m.arm,
            &m.base,
            m.suction,
            m.start,
            m.target,
            m.tolerance,
            &mut |q, delta| {
                let joints = f(m.arm.policy_joints(q));
                visited.push(ActionExample {
                    delta: f(delta),
                    joints,
                    action: f(record::action(q, &m.goal)),
                });
                policy(f(delta), joints)
            },
        )
        .is_ok();
        (visited, reached)
    }
}

impl Coach for ExpertCoach<'_> {
    fn relabel(&self, policy: &(dyn Fn([f32; 3], [f32; 3]) -> [f32; 3] + Sync)) -> Relabelled {
        let runs: Vec<(Vec<ActionExample>, bool)> = self
            .motions
            .par_iter()
            .map(|m| self.rollout(m, policy))
            .collect();
        Relabelled {
            rollouts: runs.len(),
            reached: runs.iter().filter(|(_, r)| *r).count(),
            actions: runs.into_iter().flat_map(|(a, _)| a).collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::train;
    use nalgebra::Point3;
    use packwright_interface::outcome::Stage;
    use packwright_interface::record::SubGoalSample;
    use packwright_interface::{Graph, Node, SubGoalQuery};
    use packwright_nets::TrainConfig;
    use packwright_nets::features::{GraphExample, SubGoalExample, TrainingSet};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use std::f64::consts::FRAC_PI_2;

    /// Via-point motions of the UR10 between random cup-down poses over a
    /// table, recorded as the expert records them: 20 (delta, action)
    /// samples along the straight joint-space line.
    fn demonstrations(arm: &Arm, n: usize, seed: u64) -> (MotionLog, Vec<ActionExample>) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let base = Isometry3::identity();
        let suction = 0.1;
        let near = [0.0, -FRAC_PI_2, FRAC_PI_2, -FRAC_PI_2, -FRAC_PI_2, 0.0];
        let pose = |rng: &mut ChaCha8Rng| loop {
            let r = rng.random_range(0.45..0.9);
            let a = rng.random_range(-1.2..1.2);
            let tip = Point3::new(
                r * f64::cos(a),
                r * f64::sin(a),
                rng.random_range(0.05..0.4),
            );
            if let Some(q) = arm.tool_down_ik(&base, tip, 0.0, suction, &near) {
                return q;
            }
        };
        let mut log = MotionLog::default();
        let mut actions = Vec::new();
        for _ in 0..n {
            let (start, goal) = (pose(&mut rng), pose(&mut rng));
            let target: [f64; 3] = arm.tool_tip(&base, &goal, suction).coords.into();
            log.subgoals.push(SubGoalSample {
                feature: target,
                height: 0.05,
                tool: arm.tool_tip(&base, &start, suction).coords.into(),
                label: 0,
                stage: Stage::Picking,
                index: 0,
                target,
                start,
                goal,
            });
            for i in 0..20 {
                let t = f64::from(i) / 19.0;
                let q: Joints = std::array::from_fn(|j| start[j] + t * (goal[j] - start[j]));
                let tip: [f64; 3] = arm.tool_tip(&base, &q, suction).coords.into();
                let f = |v: [f64; 3]| v.map(|x| x as f32);
                actions.push(ActionExample {
                    delta: f(std::array::from_fn(|j| target[j] - tip[j])),
                    joints: f(arm.policy_joints(&q)),
                    action: f(record::action(&q, &goal)),
                });
            }
        }
        (log, actions)
    }

    /// DAgger's rollouts label states off the demonstrated paths, and the
    /// policy trained on them reaches more of the demonstrated sub-goals.
    #[test]
    fn dagger_reaches_more_sub_goals() {
        let arm = Arm::ur10();
        let (log, actions) = demonstrations(&arm, 150, 3);
        let coach = ExpertCoach::new(&[Recorded {
            log: &log,
            arm: &arm,
            base: [0.0; 3],
            suction: 0.1,
        }]);
        assert_eq!(coach.motions().len(), 150);
        let set = TrainingSet {
            graphs: vec![GraphExample {
                graph: Graph {
                    nodes: vec![Node {
                        centre: [0.5, -0.4, 0.03],
                        height: 0.06,
                        selected: true,
                        goal: [0.0, 0.6, 0.03],
                    }],
                    slots: vec![[0.0, 0.6, 0.0]],
                    held_goal: [0.0; 3],
                },
                target: 0,
                slot: None,
            }],
            subgoals: vec![SubGoalExample {
                query: SubGoalQuery {
                    stage: Stage::Picking,
                    index: 0,
                    feature: [0.5, -0.4, 0.03],
                    tool: [0.5, -0.4, 0.3],
                    height: 0.06,
                    base: [0.0; 3],
                },
                target: [0.5, -0.4, 0.2],
            }],
            actions,
        };
        let config = TrainConfig {
            epochs: 20,
            dagger_rounds: 1,
            dagger_epochs: 20,
            ..TrainConfig::default()
        };
        let (_, metrics) = train(&set, &config, Some(&coach), &|_| {}).expect("trains");
        let [before, after] = &metrics.dagger[..] else {
            panic!("one DAgger round gives two passes: {:?}", metrics.dagger);
        };
        assert_eq!((before.rollouts, after.rollouts), (150, 150));
        assert!(before.added > 0 && after.added == 0);
        // Measured: 64 before, 86 after (20 + 20 epochs, seed 0). With 60
        // + 60 epochs the policy reaches about 100 before and after: the
        // inputs in the base joint's frame (`features::action_input`)
        // generalise off the demonstrated paths by themselves, and DAgger
        // matters where training is short.
        assert!(
            after.reached >= before.reached + 15,
            "reached {} of 150 before DAgger, {} after",
            before.reached,
            after.reached
        );
    }
}
