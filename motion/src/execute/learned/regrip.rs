//! A grip the lift cannot leave, or a contact that collides. The
//! dynamics policy keeps the arm's shape (elbow, wrist) from where a
//! stage starts, so a product close
//! to the base can be gripped with the forearm folded so far that every
//! way up folds it into the base or the upper arm, where the expert,
//! solving the contact by inverse kinematics, grips with another shape.
//! When the lift from the learned contact fails, the picking stage is
//! planned again from its start by the expert's sub-goals, with the
//! first contact shape (nearest the start first) from which the descent
//! and the lift are free (`Station::grip`, which the expert and
//! RRT-Connect use alike). So is a learned contact that collides (wrist 1
//! against a 270 mm bottle standing beside the product picked, the
//! forearm folded into the base): RRT-Connect from the learned hover
//! would change the arm's shape down among the products and leave the
//! lift in a shape the next stage's steps cannot follow.
//!
//! Invariant: every route returned is checked as it will be sent, with
//! the load of its leg; nothing is sent here.

use super::{Learned, StagePlan};
use crate::execute::station::{Connect, Leg, Load};
use crate::expert::schedule;
use packwright_interface::World;
use packwright_interface::outcome::{Failure, Shortfall, Stage};
use packwright_kinematics::Joints;

/// Whether `why`, the learned motion's shortfall at sub-goal `k + 1` of
/// a picking stage, is a contact that collides: the shape the policy's
/// steps kept from the stage's start meets something there (a wrist or
/// the forearm against a taller product standing beside the one picked,
/// the forearm folded into the base).
pub(super) fn contact_blocked(plan: &StagePlan, k: usize, why: Option<&Shortfall>) -> bool {
    plan.stage == Stage::Picking && k == 1 && matches!(why, Some(Shortfall::Collides { .. }))
}

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
    /// The picking stage `plan` from `from` by the expert's sub-goals
    /// ([`Station::grip`](crate::execute::station::Station::grip)): the
    /// hover (RRT-Connect from `from`), the guarded descent onto the
    /// product and the lift, each leg with the joints it ends at. `None`
    /// when no contact shape has a free way down and up, or the hover of
    /// that shape is not reached.
    pub(super) fn regrip(&self, plan: &StagePlan, from: Joints) -> Option<[(Leg, Joints); 3]> {
        let s = &self.station;
        let (size, top) = (plan.gripped?, plan.contact?);
        let [over_switch, contact_switch, lift_switch] = schedule(Stage::Picking);
        let free = plan.load;
        let guarded = free.guarded(s.task.cell.descent);
        let held = |at: &Joints| self.gripped_at(at, plan, size, top);
        let [over, at, up] = s.grip(&plan.expert, &from, 0.0, [free, guarded], &held)?;
        let gripped = held(&at.joints);
        let carrying = Load::holding(&gripped);
        let how = Connect::Rrt { seed: self.seed };
        let over = over.joints;
        let to = s.route(how, 1, from, over, free).ok()?;
        let (at, down) = s.route_solved(how, 2, over, at, 0.0, guarded).ok()?;
        let (raised, up) = s.route_solved(how, 3, at, up, 0.0, carrying).ok()?;
        Some([
            (Leg::new(to, over_switch, free), over),
            (Leg::new(down, contact_switch, guarded), at),
            (Leg::new(up, lift_switch, carrying), raised),
        ])
    }
}
