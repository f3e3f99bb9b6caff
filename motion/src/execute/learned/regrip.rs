//! A grip the lift cannot leave. The dynamics policy keeps the arm's
//! shape (elbow, wrist) from where a stage starts, so a product close
//! to the base can be gripped with the forearm folded so far that every
//! way up folds it into the base or the upper arm, where the expert,
//! solving the contact by inverse kinematics, grips with another shape.
//! When the lift from the learned contact fails, the picking stage is
//! planned again from its start by the expert's sub-goals, with the
//! first contact shape (nearest the start first) from which the lift
//! is free.
//!
//! Invariant: every route returned is checked as it will be sent, with
//! the load of its leg; nothing is sent here.

use super::{Learned, StagePlan};
use crate::execute::station::{Connect, Leg, Load, reach, solutions};
use crate::expert::{SubGoal, schedule};
use nalgebra::Point3;
use packwright_interface::World;
use packwright_interface::outcome::{Failure, Stage};
use packwright_kinematics::Joints;

/// Whether `why`, the lift's failure (sub-goal 3 of a picking stage),
/// can come from the shape the arm gripped with: no free way up, rather
/// than an overrun budget or a smoothing error.
pub(super) fn lift_blocked(plan: &StagePlan, k: usize, why: &Failure) -> bool {
    plan.stage == Stage::Picking
        && k + 1 == schedule(Stage::Picking).len()
        && matches!(
            why,
            Failure::Unreachable { .. } | Failure::NoPath { .. } | Failure::WouldCollide { .. }
        )
}

impl<W: World> Learned<'_, W> {
    /// The picking stage `plan` from `from` by the expert's sub-goals: the
    /// hover (RRT-Connect from `from`), the guarded descent onto the
    /// product and the lift, each leg with the joints it ends at; gripping
    /// with the first free contact shape, nearest `from` first, whose
    /// lift is free and whose hover of the same shape is reached. `None`
    /// when no shape does, or the sub-goal's budget runs out.
    pub(super) fn regrip(&self, plan: &StagePlan, from: Joints) -> Option<[(Leg, Joints); 3]> {
        let s = &self.station;
        let (size, top) = (plan.gripped?, plan.contact?);
        let [hover, contact, lift] = &plan.expert;
        let [over_switch, contact_switch, lift_switch] = schedule(Stage::Picking);
        let free = plan.load;
        let guarded = free.guarded(s.task.cell.descent);
        let point = |g: &SubGoal| Point3::new(g.tip[0], g.tip[1], g.tip[2]);
        solutions(&s.checker, point(contact), 0.0, &from)
            .into_iter()
            .filter(|q| {
                s.arm.within_limits(q) && s.checker.check(q, guarded.held, guarded.ignore).is_none()
            })
            .take_while(|_| !s.late())
            .find_map(|at| {
                let held = self.gripped_at(&at, plan, size, top);
                let carrying = Load::holding(&held);
                let solved = s.solve(lift, 3, &at, 0.0, carrying, lift.tip[2]).ok()?;
                let (raised, up) = s
                    .route_solved(Connect::Straight, 3, at, solved, 0.0, carrying)
                    .ok()?;
                let over = reach(&s.checker, point(hover), 0.0, &at, free)?;
                let down = s.checked(2, over, &[at], guarded).ok()?;
                let to = s
                    .route(Connect::Rrt { seed: self.seed }, 1, from, over, free)
                    .ok()?;
                Some([
                    (Leg::new(to, over_switch, free), over),
                    (Leg::new(down, contact_switch, guarded), at),
                    (Leg::new(up, lift_switch, carrying), raised),
                ])
            })
    }
}
