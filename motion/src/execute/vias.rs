//! Via points a motion passes through, and which of them it needs.

use packwright_kinematics::Joints;

/// `steps` from `start` with the steps a straight joint motion can skip
/// left out: from each point kept, the farthest later step that `free`
/// joins it to (the next step where none is), the last step always kept.
/// Through every one of a policy's 10-15 steps, the blend has short legs
/// to speed up on and the arm moves slowly (a development cell: a hover
/// through 13 steps took 5.5 s).
pub(crate) fn fewer_vias(
    start: Joints,
    steps: &[Joints],
    free: impl Fn(&Joints, &Joints) -> bool,
) -> Vec<Joints> {
    let mut kept = Vec::new();
    let mut from = start;
    let mut next = 0;
    while let Some(last) = steps.len().checked_sub(1)
        && next <= last
    {
        let j = (next + 1..=last)
            .rev()
            .find(|&j| free(&from, &steps[j]))
            .unwrap_or(next);
        kept.push(steps[j]);
        from = steps[j];
        next = j + 1;
    }
    kept
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points on joint 0 only, at `x`.
    fn at(x: f64) -> Joints {
        [x, 0.0, 0.0, 0.0, 0.0, 0.0]
    }

    #[test]
    fn fewer_vias_skips_what_a_straight_motion_joins_and_keeps_the_last_step() {
        let steps: Vec<Joints> = (1..=6).map(|i| at(i as f64)).collect();
        // Everything joins: the last step alone.
        assert_eq!(fewer_vias(at(0.0), &steps, |_, _| true), vec![at(6.0)]);
        // Nothing joins: every step, in order.
        assert_eq!(fewer_vias(at(0.0), &steps, |_, _| false), steps);
        // A wall between 2.5 and 3.5 that only a motion starting or ending
        // inside [2, 4] passes: from the start to 4 (the farthest it
        // joins), from there to the last step.
        let crosses = |a: &Joints, b: &Joints| a[0].min(b[0]) < 2.5 && a[0].max(b[0]) > 3.5;
        let inside = |q: &Joints| (2.0..=4.0).contains(&q[0]);
        let free = |a: &Joints, b: &Joints| !crosses(a, b) || inside(a) || inside(b);
        assert_eq!(fewer_vias(at(0.0), &steps, free), vec![at(4.0), at(6.0)]);
        // No steps: nothing.
        assert!(fewer_vias(at(0.0), &[], |_, _| true).is_empty());
    }
}
