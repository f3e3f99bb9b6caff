//! A grip the lift cannot leave, or a contact that collides. The
//! dynamics policy keeps the arm's shape (elbow, wrist) from where a
//! stage starts, so a product close
//! to the base can be gripped with the forearm folded so far that every
//! way up folds it into the base or the upper arm, where the expert,
//! solving the contact by inverse kinematics, grips with another shape.
//! A learned contact that collides (wrist 1 against a 270 mm bottle
//! standing beside the product picked, the forearm folded into the
//! base), or a learned lift that does (every way up from a product close
//! to the base folds the forearm into the base), is made with the first contact shape (nearest the start first)
//! from which the descent and the lift are free (`Station::grip`, which
//! the expert and RRT-Connect use alike), at the learned sub-goals, the
//! arm changing its shape on the way to the hover ([`Learned::grip_learned`]).
//! RRT-Connect from the learned hover would change the arm's shape down
//! among the products and leave the lift in a shape the next stage's
//! steps cannot follow. Where no shape is free that way (and, for a
//! lift, RRT-Connect finds no way up either), the picking stage is
//! planned again from its start by the expert's sub-goals (a fallback).
//!
//! Invariant: every route returned is checked as it will be sent, with
//! the load of its leg; nothing is sent here.

use super::{Learned, StagePlan};
use crate::execute::checked_samples;
use crate::execute::reasoner::f32s;
use crate::execute::station::{Connect, Leg, Load, Route};
use crate::expert::{SubGoal, schedule};
use packwright_interface::outcome::{Failure, Shortfall, Stage};
use packwright_interface::{SubGoalQuery, World};
use packwright_kinematics::Joints;

/// A picking stage's three legs (hover, contact, lift), each with the
/// joints it ends at.
pub(super) type StageLegs = [(Leg, Joints); 3];

/// Whether `why`, the learned motion's shortfall at sub-goal `k + 1` of
/// a picking stage, is a contact that collides: the shape the policy's
/// steps kept from the stage's start meets something there (a wrist or
/// the forearm against a taller product standing beside the one picked,
/// the forearm folded into the base).
pub(super) fn contact_blocked(plan: &StagePlan, k: usize, why: Option<&Shortfall>) -> bool {
    plan.stage == Stage::Picking && k == 1 && matches!(why, Some(Shortfall::Collides { .. }))
}

/// Whether `why`, the learned motion's shortfall at sub-goal `k + 1` of
/// a picking stage, is a lift that collides: from the contact the
/// policy's steps reached in the shape kept from the stage's start, the
/// way up folds the forearm into the base or the upper arm (a product
/// close to the base).
pub(super) fn lift_collides(plan: &StagePlan, k: usize, why: Option<&Shortfall>) -> bool {
    plan.stage == Stage::Picking
        && k + 1 == schedule(Stage::Picking).len()
        && matches!(why, Some(Shortfall::Collides { .. }))
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
    /// A learned contact that collides in the shape the policy's steps
    /// kept, gripped with a free shape at the learned sub-goals instead:
    /// [`Station::grip`](crate::execute::station::Station::grip) at the
    /// hover the steps reached (`hover`, its motion from `from`), the
    /// learned `contact` and the sub-goal planner's lift from there. The
    /// arm changes its shape on the way to the hover (the straight motion
    /// or a swing from `from`), else at the hover (the learned motion
    /// there, then on to the same cup pose in the free shape, checked as
    /// one motion: the wrist turning round there is slow, and tried
    /// first it cost 0.3-0.6 s per product on average on the bakery's and
    /// the display's cells); the descent and
    /// the lift are the straight ones `grip` checked.
    /// Neither RRT-Connect nor an expert's sub-goal: not a fallback. The
    /// three legs with the joints each ends at, and the lift's sub-goal;
    /// `None` when no shape is free that way.
    pub(super) fn grip_learned(
        &self,
        plan: &StagePlan,
        from: Joints,
        hover: &Route,
        contact: [f64; 3],
    ) -> Option<(StageLegs, [f64; 3])> {
        let s = &self.station;
        let reached = *hover.waypoints.last()?;
        let lift = self
            .policy
            .subgoal(&SubGoalQuery {
                stage: Stage::Picking,
                index: 2,
                feature: f32s(plan.feature),
                tool: f32s(contact),
                height: plan.height as f32,
                base: f32s(s.task.cell.base),
            })
            .map(f64::from);
        if lift.iter().any(|v| !v.is_finite()) {
            return None;
        }
        let switches = schedule(Stage::Picking);
        let tips = [s.tip(&reached), contact, lift];
        let goals: [SubGoal; 3] = std::array::from_fn(|i| SubGoal {
            tip: tips[i],
            suction: switches[i],
        });
        let legs = self.gripped_stage(plan, from, &goals, Connect::Straight, Some(hover))?;
        Some((legs, lift))
    }

    /// The picking stage `plan` from `from` by the expert's sub-goals
    /// ([`Station::grip`](crate::execute::station::Station::grip)): the
    /// hover (RRT-Connect from `from`), the guarded descent onto the
    /// product and the lift, each leg with the joints it ends at. `None`
    /// when no contact shape has a free way down and up, or the hover of
    /// that shape is not reached.
    pub(super) fn regrip(&self, plan: &StagePlan, from: Joints) -> Option<StageLegs> {
        let how = Connect::Rrt { seed: self.seed };
        self.gripped_stage(plan, from, &plan.expert, how, None)
    }

    /// The picking stage `plan` from `from` at `goals` (hover, contact,
    /// lift), gripping with the first contact shape `Station::grip` finds
    /// free: the hover of that shape reached from `from` by `how`, else
    /// (with the `hover` motion the learned steps made) along that motion
    /// and on to it, checked as one motion; the descent and the lift by
    /// `how` from the solves `grip` checked.
    fn gripped_stage(
        &self,
        plan: &StagePlan,
        from: Joints,
        goals: &[SubGoal; 3],
        how: Connect,
        hover: Option<&Route>,
    ) -> Option<StageLegs> {
        let s = &self.station;
        let (size, top) = (plan.gripped?, plan.contact?);
        let [over_switch, contact_switch, lift_switch] = schedule(Stage::Picking);
        let free = plan.loads[0];
        let guarded = free.guarded(s.task.cell.descent);
        let held = |at: &Joints| self.gripped_at(at, plan, size, top);
        // The first free shape whose hover is reached from `from`.
        s.grips(goals, &from, 0.0, [free, guarded], &held)
            .find_map(|[over, at, up]| {
                let gripped = held(&at.joints);
                let carrying = Load::holding(&gripped);
                let over = over.joints;
                let to = s.route(how, 1, from, over, free).ok().or_else(|| {
                    let mut waypoints = hover?.waypoints.clone();
                    waypoints.push(over);
                    checked_samples(s.arm, &s.checker, from, &waypoints, free)
                        .ok()
                        .map(|samples| Route { waypoints, samples })
                })?;
                let (at, down) = s.route_solved(how, 2, over, at, 0.0, guarded).ok()?;
                let (raised, up) = s.route_solved(how, 3, at, up, 0.0, carrying).ok()?;
                Some([
                    (Leg::new(to, over_switch, free), over),
                    (Leg::new(down, contact_switch, guarded), at),
                    (Leg::new(up, lift_switch, carrying), raised),
                ])
            })
    }
}
