//! The dynamics policy's steps: from a start towards a cup-tip position,
//! at most [`MAX_POLICY_STEPS`] steps of at most 15 degrees (base,
//! shoulder, elbow), the wrist turned with them so that the cup keeps
//! pointing down with its yaw ([`cup_down`]), until the tip is within a
//! [`tolerance`]. The learned loop and DAgger's rollouts step through
//! [`policy_steps`] alike.
//!
//! Invariants: every returned joint vector keeps the start's cup-down
//! wrist shape and has joints 2 to 5 within their limits (the base and
//! wrist 3 turn freely; whoever moves the arm along the steps brings them
//! into the limits); the steps are the same, bit for bit, as forward
//! kinematics at every step would give (the tip in closed form after the
//! first step, tested against it).

use crate::expert::{Suction, schedule};
use nalgebra::Isometry3;
use packwright_interface::outcome::{Shortfall, Stage};
use packwright_interface::record;
use packwright_kinematics::{Arm, CupDownTip, Joints};

/// full steps, and near 180 degrees, where both ways round are as short,
/// the policy takes a few steps to commit to one; the last steps, near the
/// sub-goal, are short.
pub const MAX_POLICY_STEPS: usize = 30;
/// A sub-goal where the suction switches (the cup on a product's top
/// face, a release in a slot), or the one just before it (the hover, above
/// the slot), is reached when the cup tip is this close (m): the motion
/// between them is then the straight descent the expert showed.
pub const REACHED: f64 = 0.002;
/// Any other via point (the lift, the approach) is reached when the cup tip
/// is this close (m).
pub const REACHED_VIA: f64 = 0.01;
/// The policy's steps end the back-up from a release this close (m) to
/// straight above it: within [`REACHED`], the end's millimetre or two
/// changed the blend into the next hover (one product of the golden
/// `pine_trio` took 0.15 s longer); this close, the executed motion is the
/// inverse kinematics' to the millisecond.
pub(super) const BACK_UP_REACHED: f64 = 0.0005;

/// How close the cup tip must come to sub-goal `index` (from 0) of `stage`:
/// [`REACHED`] where the suction switches and just before, else
/// [`REACHED_VIA`]. The learned loop and DAgger's coach both use it.
pub fn tolerance(stage: Stage, index: usize) -> f64 {
    let switches = |k: usize| schedule(stage).get(k).is_some_and(|&s| s != Suction::Keep);
    if switches(index) || switches(index + 1) {
        REACHED
    } else {
        REACHED_VIA
    }
}

/// `q` moved by `step` (base, shoulder, elbow), the wrist turned so that the
/// cup keeps pointing down with the same yaw (UR-type wrists); why not when
/// that does not hold for this arm or leaves the joint limits. The base and
/// wrist 3 turn freely here (`q` and `q` ± 2π are the same pose): whoever
/// moves the arm along the steps brings them into the limits
/// ([`Arm::into_limits`]).
pub fn cup_down(
    arm: &Arm,
    base: &Isometry3<f64>,
    q: &Joints,
    step: [f64; 3],
) -> Result<Joints, Shortfall> {
    cup_down_from(arm, base, q, &arm.flange_pose(base, q), step).map(|(next, _)| next)
}

/// [`cup_down`] from `q` whose flange pose `flange` is known, with the
/// flange pose of the joints it returns: stepping along, each pose is
/// computed once (forward kinematics is most of a policy step's own work).
fn cup_down_from(
    arm: &Arm,
    base: &Isometry3<f64>,
    q: &Joints,
    flange: &Isometry3<f64>,
    step: [f64; 3],
) -> Result<(Joints, Isometry3<f64>), Shortfall> {
    let next = stepped(q, step);
    let after = arm.flange_pose(base, &next);
    if flange.rotation.angle_to(&after.rotation) >= arm.cup_down_tolerance() {
        return Err(Shortfall::Limits {
            joint: None,
            value: f64::NAN,
        });
    }
    within_limits(arm, next).map(|next| (next, after))
}

/// `q` moved by `step` (base, shoulder, elbow), wrist 1 against shoulder
/// and elbow, wrist 3 with the base.
fn stepped(q: &Joints, step: [f64; 3]) -> Joints {
    let mut next = *q;
    next[0] += step[0];
    next[1] += step[1];
    next[2] += step[2];
    next[3] -= step[1] + step[2];
    next[5] += step[0];
    next
}

/// `q`, or which of joints 2-5 left its limits (the base and wrist 3 turn
/// freely here: [`cup_down`]).
fn within_limits(arm: &Arm, q: Joints) -> Result<Joints, Shortfall> {
    match (1..5).find(|&j| !arm.limits[j].contains(q[j])) {
        Some(j) => Err(Shortfall::Limits {
            joint: Some(j),
            value: q[j],
        }),
        None => Ok(q),
    }
}

/// The dynamics policy's steps from `start` towards the cup-tip position
/// `goal`, with forward kinematics (after the first step the tip in
/// closed form, [`CupDownTip`], where the arm has one), as the learned
/// loop takes them: at
/// most [`MAX_POLICY_STEPS`], each `action(q, delta)` (base, shoulder,
/// elbow, radians; delta = goal − cup tip) scaled down to 15 degrees, the
/// wrist keeping the cup down; until the tip is within `tolerance`. The
/// joints after each step, or why the goal was not reached. DAgger's
/// rollouts step through this too.
pub fn policy_steps(
    arm: &Arm,
    base: &Isometry3<f64>,
    suction: f64,
    start: Joints,
    goal: [f64; 3],
    tolerance: f64,
    action: &mut dyn FnMut(&Joints, [f64; 3]) -> [f32; 3],
) -> Result<Vec<Joints>, Shortfall> {
    policy_steps_near(
        0,
        Hold::Nothing,
        arm,
        base,
        suction,
        start,
        goal,
        tolerance,
        action,
    )
}

/// How close (m) the policy's [`MAX_POLICY_STEPS`] steps must have come
/// to a goal for the learned loop to let it take [`MORE_STEPS`] more: a
/// policy that spirals in (near the base its steps turn the tip's way a
/// few degrees off: 2.3 mm from a point above a slot 0.35 m from the
/// base axis after 30 steps, coming nearer by a few tenths of a
/// millimetre a step) rather than one that stalls or wanders off.
pub const NEAR_MISS: f64 = 0.01;

/// The steps the learned loop allows a policy that ended within
/// [`NEAR_MISS`] of its goal, beyond [`MAX_POLICY_STEPS`].
pub const MORE_STEPS: usize = 15;

/// How far inside its limits (rad) [`Hold::ShoulderElbow`] holds the
/// shoulder and the elbow.
pub(super) const HOLD_MARGIN: f64 = 0.01;

/// Whether the policy's steps are held inside the joints' limits.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Hold {
    /// A step that leaves the limits ends the steps
    /// ([`Shortfall::Limits`]): the policy as taught, and DAgger's
    /// rollouts.
    Nothing,
    /// A step that would take the shoulder or the elbow past its limit
    /// is cut short [`HOLD_MARGIN`] inside it (the wrist turned with the
    /// step as cut, so the cup stays down), and the other joints' steps
    /// go on; steps that stay within the limits are
    /// [`Hold::Nothing`]'s, bit for bit. Near the base, an elbow folded
    /// to reach a product a few tenths of a metre out is close to its
    /// limit, and the policy's steps overshoot it on the way before they
    /// come back (probe cell 6003 reversed: the elbow to 3.209 rad for a
    /// hover the expert reaches at 2.754). For the learned loop only.
    ShoulderElbow,
}

/// [`policy_steps`], holding the joints as `hold` says, going on for up
/// to `more` steps where the first [`MAX_POLICY_STEPS`] end within
/// [`NEAR_MISS`] of the goal; where those fall short too (or leave the
/// limits), the shortfall after [`MAX_POLICY_STEPS`] is the one returned.
#[allow(clippy::too_many_arguments)]
pub fn policy_steps_near(
    more: usize,
    hold: Hold,
    arm: &Arm,
    base: &Isometry3<f64>,
    suction: f64,
    start: Joints,
    goal: [f64; 3],
    tolerance: f64,
    action: &mut dyn FnMut(&Joints, [f64; 3]) -> [f32; 3],
) -> Result<Vec<Joints>, Shortfall> {
    let mut q = start;
    let mut flange = arm.flange_pose(base, &q);
    let mut tip = Arm::tip_of(&flange, suction);
    // After the first step, which checks that the wrist keeps the cup
    // down, the tip in closed form where the arm has one (forward
    // kinematics was most of a step's own work).
    let mut closed: Option<CupDownTip> = None;
    let mut steps = Vec::with_capacity(MAX_POLICY_STEPS);
    // The shortfall after MAX_POLICY_STEPS, once the steps go on.
    let mut short = None;
    loop {
        let delta: [f64; 3] = std::array::from_fn(|j| goal[j] - tip[j]);
        let away = delta.iter().map(|d| d * d).sum::<f64>().sqrt();
        if away <= tolerance {
            return Ok(steps);
        }
        if steps.len() == MAX_POLICY_STEPS {
            let why = Shortfall::Short {
                steps: MAX_POLICY_STEPS,
                distance_m: away,
            };
            if more == 0 || away > NEAR_MISS {
                return Err(why);
            }
            short = Some(why);
        }
        if steps.len() == MAX_POLICY_STEPS + more {
            return Err(short.unwrap_or(Shortfall::Short {
                steps: steps.len(),
                distance_m: away,
            }));
        }
        let mut step = record::clip(action(&q, delta).map(f64::from));
        if hold == Hold::ShoulderElbow {
            for j in [1, 2] {
                let l = &arm.limits[j];
                let to = q[j] + step[j];
                let (lower, upper) = (l.lower + HOLD_MARGIN, l.upper - HOLD_MARGIN);
                if !l.contains(to) && lower < upper {
                    step[j] = to.clamp(lower, upper) - q[j];
                }
            }
        }
        let stepped = match &closed {
            Some(c) => within_limits(arm, stepped(&q, step)).map(|next| {
                q = next;
                tip = c.at(&q).unwrap_or_else(|| arm.tool_tip(base, &q, suction));
            }),
            None => cup_down_from(arm, base, &q, &flange, step).map(|(next, after)| {
                (q, flange) = (next, after);
                tip = Arm::tip_of(&flange, suction);
                closed = arm.cup_down_tip(base, &q, &tip);
            }),
        };
        if let Err(why) = stepped {
            return Err(short.unwrap_or(why));
        }
        steps.push(q);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point3;
    /// A way of stepping the policy, with the signature of [`policy_steps`].
    type Stepper = fn(
        &Arm,
        &Isometry3<f64>,
        f64,
        Joints,
        [f64; 3],
        f64,
        &mut dyn FnMut(&Joints, [f64; 3]) -> [f32; 3],
    ) -> Result<Vec<Joints>, Shortfall>;

    /// The policy's steps as they were taken before each flange pose was
    /// computed once and the tip in closed form: the tip and both sides of
    /// the wrist check each by forward kinematics of their own.
    fn steps_by_separate_poses(
        arm: &Arm,
        base: &Isometry3<f64>,
        suction: f64,
        start: Joints,
        goal: [f64; 3],
        tolerance: f64,
        action: &mut dyn FnMut(&Joints, [f64; 3]) -> [f32; 3],
    ) -> Result<Vec<Joints>, Shortfall> {
        let mut q = start;
        let mut steps = Vec::new();
        loop {
            let tip: [f64; 3] = arm.tool_tip(base, &q, suction).coords.into();
            let delta: [f64; 3] = std::array::from_fn(|j| goal[j] - tip[j]);
            let away = delta.iter().map(|d| d * d).sum::<f64>().sqrt();
            if away <= tolerance {
                return Ok(steps);
            }
            if steps.len() == MAX_POLICY_STEPS {
                return Err(Shortfall::Short {
                    steps: MAX_POLICY_STEPS,
                    distance_m: away,
                });
            }
            let step = record::clip(action(&q, delta).map(f64::from));
            q = cup_down(arm, base, &q, step)?;
            steps.push(q);
        }
    }

    /// Numbers in [-1, 1), the same for a seed on every machine.
    fn numbers(seed: u64) -> impl FnMut() -> f64 {
        let mut x = seed;
        move || {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((x >> 40) as f64 / (1u64 << 24) as f64) * 2.0 - 1.0
        }
    }

    /// The arm with the cup down over a random point in front of it, or
    /// `None` where that is out of reach.
    fn cup_down_start(
        arm: &Arm,
        base: &Isometry3<f64>,
        suction: f64,
        next: &mut impl FnMut() -> f64,
    ) -> Option<Joints> {
        let tip = Point3::new(0.5 + 0.3 * next(), 0.4 * next(), 0.3 + 0.1 * next());
        arm.tool_down_ik(
            base,
            tip,
            next(),
            suction,
            &[0.0, -1.5, 1.5, -1.6, -1.6, 0.0],
        )
    }

    /// `n` small random actions.
    fn wandering(next: &mut impl FnMut() -> f64, n: usize) -> Vec<[f32; 3]> {
        (0..n)
            .map(|_| {
                [
                    0.1 * next() as f32,
                    0.1 * next() as f32,
                    0.1 * next() as f32,
                ]
            })
            .collect()
    }

    /// Random actions from cup-down starts give the very same steps and
    /// shortfalls as forward kinematics at every use (the distance left
    /// to within 1e-9 m: the tip is in closed form after the first step):
    /// short of a goal out of reach, at a goal some steps away (within
    /// 1e-9 m), or off the joint limits.
    #[test]
    fn policy_steps_match_separate_forward_kinematics() {
        let arm = Arm::ur10();
        let base = Isometry3::translation(0.1, -0.2, 0.05);
        let suction = 0.12;
        let mut next = numbers(17);
        let mut outcomes = Vec::new();
        for _ in 0..40 {
            let Some(start) = cup_down_start(&arm, &base, suction, &mut next) else {
                continue;
            };
            let wander = wandering(&mut next, MAX_POLICY_STEPS);
            // The elbow bends on until it leaves its limits.
            let bend: Vec<[f32; 3]> = wander.iter().map(|a| [a[0], a[1], 0.1]).collect();
            // A goal out of reach, and the tip after a few of the actions.
            let mut after = start;
            for a in &wander[..5] {
                after =
                    cup_down(&arm, &base, &after, record::clip(a.map(f64::from))).unwrap_or(after);
            }
            let near: [f64; 3] = arm.tool_tip(&base, &after, suction).coords.into();
            let far = [3.0, 0.0, 0.5];
            for (actions, goal, tolerance) in [
                (&wander, far, 0.01),
                (&wander, near, 1e-9),
                (&bend, far, 0.01),
            ] {
                let run = |stepper: Stepper| {
                    let mut k = 0;
                    stepper(&arm, &base, suction, start, goal, tolerance, &mut |_, _| {
                        k += 1;
                        actions[k - 1]
                    })
                };
                let (new, old) = (run(policy_steps), run(steps_by_separate_poses));
                // The distance left within 1e-9 m, all else exactly.
                let rounded = |r: &Result<Vec<Joints>, Shortfall>| match r {
                    Err(Shortfall::Short { steps, distance_m }) => Err(Shortfall::Short {
                        steps: *steps,
                        distance_m: (distance_m * 1e9).round(),
                    }),
                    other => other.clone(),
                };
                // Debug prints each value exactly (NaN included).
                let (new, old) = (
                    format!("{:?}", rounded(&new)),
                    format!("{:?}", rounded(&old)),
                );
                assert_eq!(new, old);
                outcomes.push(new.chars().take(8).collect::<String>());
            }
        }
        // Each way of ending was met.
        for ending in ["Ok(", "Err(Shor", "Err(Limi"] {
            assert!(
                outcomes.iter().any(|o| o.starts_with(ending)),
                "no {ending} among {outcomes:?}"
            );
        }
    }

    /// Held steps go on where a step would take the shoulder or the elbow
    /// past its limit, each held [`HOLD_MARGIN`] inside it, the cup still
    /// down; where no step leaves the limits, they are the policy's own
    /// steps bit for bit (random actions from random cup-down starts).
    #[test]
    fn held_steps_stay_inside_the_limits_and_are_the_policys_where_it_does() {
        let arm = Arm::ur10();
        let base = Isometry3::translation(0.0, 0.0, 0.0);
        let suction = 0.12;
        let mut next = numbers(29);
        let (mut same, mut held) = (0, 0);
        for _ in 0..60 {
            let Some(start) = cup_down_start(&arm, &base, suction, &mut next) else {
                continue;
            };
            let down = arm.flange_pose(&base, &start).rotation;
            // Wandering steps, and steps folding the elbow (or lowering
            // the shoulder) until it would leave its limit.
            let wander = wandering(&mut next, MAX_POLICY_STEPS + MORE_STEPS);
            let fold: Vec<[f32; 3]> = wander.iter().map(|a| [a[0], a[1], 1.0]).collect();
            let lower: Vec<[f32; 3]> = wander.iter().map(|a| [a[0], -1.0, a[2]]).collect();
            let far = [3.0, 0.0, 0.5];
            for actions in [&wander, &fold, &lower] {
                // The joints each step left the arm in (the policy is
                // asked from each).
                let mut seen: Vec<Joints> = Vec::new();
                let mut run = |hold: Hold| {
                    seen.clear();
                    let action = &mut |q: &Joints, _: [f64; 3]| {
                        seen.push(*q);
                        actions[seen.len() - 1]
                    };
                    policy_steps_near(
                        MORE_STEPS, hold, &arm, &base, suction, start, far, 0.01, action,
                    )
                };
                let own = run(Hold::Nothing);
                let kept = run(Hold::ShoulderElbow);
                match &own {
                    Err(Shortfall::Limits {
                        joint: Some(1 | 2), ..
                    }) => {
                        held += 1;
                        // Held, the steps go on, short of a goal out of
                        // reach, every joint inside its limits and the
                        // cup down.
                        assert!(
                            matches!(kept, Err(Shortfall::Short { steps, .. }) if steps >= MAX_POLICY_STEPS),
                            "{kept:?}"
                        );
                        assert_eq!(seen.len(), MAX_POLICY_STEPS);
                        for q in &seen {
                            assert!((1..5).all(|j| arm.limits[j].contains(q[j])), "{q:?}");
                            let turned = arm.flange_pose(&base, q).rotation.angle_to(&down);
                            assert!(turned < 1e-6, "{turned}");
                        }
                    }
                    _ => {
                        same += 1;
                        assert_eq!(format!("{own:?}"), format!("{kept:?}"));
                    }
                }
            }
        }
        assert!(held >= 10 && same >= 10, "held {held}, same {same}");
    }
}
