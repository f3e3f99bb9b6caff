//! What the sub-goal planner was taught to answer: for each sub-goal kind
//! (stage and index), the range of each of its continuous inputs
//! ([`subgoal_input`]'s radius offset, height and turn) over the training
//! queries. Saved in `config.json` (`taught_queries`).
//!
//! A query beyond that range is answered as at its edge. Over a range no
//! demonstration covered, a network's answer is an extrapolation: the
//! bundled model, taught cells whose products stand within 0.95 m of the
//! base, put "above the slot" 2-3 cm off (and the release 1-2 cm) when
//! the products stood 1.0-1.2 m out, so that a product let go over a
//! narrow box's wall rested on it (docs/measurements.md, "Queries beyond what was
//! taught"). The expert's sub-goals over a product or a slot do not
//! depend on where the cup comes from, and its approach point is a via
//! point, so the nearest taught query answers them as well as the
//! network can.
//!
//! Invariant: a query inside every taught range is not changed (the
//! clamp is the identity there), so a model answers the queries it was
//! taught exactly as it was trained to.

use crate::error::ModelError;
use crate::features::{SUBGOAL_INPUTS, subgoal_input};
use packwright_interface::{Stage, SubGoalQuery};
use serde::{Deserialize, Serialize};

/// The continuous inputs at the head of a sub-goal input row (the rest
/// is the stage and index one-hot).
pub const CONTINUOUS: usize = 3;

/// Sub-goal indices per stage.
const INDICES: usize = 3;

/// The lowest and highest value of each continuous input.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Bounds {
    pub low: [f32; CONTINUOUS],
    pub high: [f32; CONTINUOUS],
}

impl Bounds {
    fn of(x: &[f32; SUBGOAL_INPUTS]) -> Bounds {
        let mut low = [0.0; CONTINUOUS];
        low.copy_from_slice(&x[..CONTINUOUS]);
        Bounds { low, high: low }
    }

    fn widen(&mut self, x: &[f32; SUBGOAL_INPUTS]) {
        for (i, &v) in x.iter().take(CONTINUOUS).enumerate() {
            self.low[i] = self.low[i].min(v);
            self.high[i] = self.high[i].max(v);
        }
    }

    fn valid(&self) -> bool {
        self.low
            .iter()
            .zip(&self.high)
            .all(|(l, h)| l.is_finite() && h.is_finite() && l <= h)
    }
}

/// Per stage, per sub-goal index (0 to 2): the bounds of the queries
/// taught, `None` for a kind no demonstration issued (its queries are
/// not clamped).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct TaughtQueries {
    pub picking: [Option<Bounds>; INDICES],
    pub placing: [Option<Bounds>; INDICES],
}

impl TaughtQueries {
    /// The bounds of `queries`' inputs, per kind.
    pub fn of<'q>(queries: impl IntoIterator<Item = &'q SubGoalQuery>) -> TaughtQueries {
        let mut taught = TaughtQueries::default();
        for q in queries {
            let x = subgoal_input(q);
            match taught.kind_mut(q) {
                Some(b) => b.widen(&x),
                kind @ None => *kind = Some(Bounds::of(&x)),
            }
        }
        taught
    }

    fn kind(&self, q: &SubGoalQuery) -> Option<&Bounds> {
        let index = q.index.min(INDICES - 1);
        match q.stage {
            Stage::Picking => self.picking[index].as_ref(),
            Stage::Placing => self.placing[index].as_ref(),
        }
    }

    fn kind_mut(&mut self, q: &SubGoalQuery) -> &mut Option<Bounds> {
        let index = q.index.min(INDICES - 1);
        match q.stage {
            Stage::Picking => &mut self.picking[index],
            Stage::Placing => &mut self.placing[index],
        }
    }

    /// `x`, the input row of `q`, with its continuous inputs brought
    /// within the bounds taught for `q`'s kind (unchanged inside them,
    /// and for a kind not taught).
    pub fn clamp(&self, q: &SubGoalQuery, x: &mut [f32; SUBGOAL_INPUTS]) {
        if let Some(b) = self.kind(q) {
            for (i, v) in x.iter_mut().take(CONTINUOUS).enumerate() {
                *v = v.clamp(b.low[i], b.high[i]);
            }
        }
    }

    /// Whether every bound is finite and no lower than its low end
    /// (`clamp` would panic on a low end above the high one).
    pub fn check(&self) -> Result<(), ModelError> {
        let mut kinds = self.picking.iter().chain(&self.placing).flatten();
        match kinds.all(Bounds::valid) {
            true => Ok(()),
            false => Err(ModelError::TaughtQueries),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn query(stage: Stage, index: usize, tool: [f32; 3]) -> SubGoalQuery {
        SubGoalQuery {
            stage,
            index,
            feature: [0.5, 0.0, 0.06],
            tool,
            height: 0.05,
            base: [0.0; 3],
        }
    }

    #[test]
    fn queries_inside_the_taught_bounds_are_unchanged_and_beyond_them_held_at_the_edge() {
        // "Above the slot" taught from tips 0.4-0.6 m from the base.
        let taught = TaughtQueries::of(&[
            query(Stage::Placing, 1, [0.4, -0.1, 0.25]),
            query(Stage::Placing, 1, [0.6, 0.0, 0.20]),
        ]);
        let edge = subgoal_input(&query(Stage::Placing, 1, [0.6, 0.0, 0.25]))[0];
        let inside = query(Stage::Placing, 1, [0.55, -0.05, 0.22]);
        let mut x = subgoal_input(&inside);
        let before = x;
        taught.clamp(&inside, &mut x);
        assert_eq!(x, before);
        // A tip 1.1 m out reads as one at the farthest taught radius; its
        // height and turn, inside, are kept; the one-hot is untouched.
        let far = query(Stage::Placing, 1, [1.1, 0.0, 0.22]);
        let mut x = subgoal_input(&far);
        let before = x;
        taught.clamp(&far, &mut x);
        assert!(before[0] > edge + 0.4);
        assert!((x[0] - edge).abs() < 1e-6, "{} vs {edge}", x[0]);
        assert_eq!(x[1..], before[1..]);
        // A kind not taught is not clamped.
        let other = query(Stage::Picking, 1, [1.1, 0.0, 0.22]);
        let mut x = subgoal_input(&other);
        let before = x;
        taught.clamp(&other, &mut x);
        assert_eq!(x, before);
    }

    #[test]
    fn bounds_that_are_not_finite_or_inverted_are_refused() {
        let taught = TaughtQueries::of(&[query(Stage::Picking, 0, [0.4, 0.0, 0.25])]);
        assert_eq!(taught.check(), Ok(()));
        let mut inverted = taught.clone();
        if let Some(b) = inverted.picking[0].as_mut() {
            b.low[1] = b.high[1] + 0.1;
        }
        assert_eq!(inverted.check(), Err(ModelError::TaughtQueries));
        let mut nan = taught;
        if let Some(b) = nan.picking[0].as_mut() {
            b.high[2] = f32::NAN;
        }
        assert_eq!(nan.check(), Err(ModelError::TaughtQueries));
    }

    #[test]
    fn the_bounds_round_trip_through_json() {
        let taught = TaughtQueries::of(&[
            query(Stage::Picking, 2, [0.5, 0.0, 0.1]),
            query(Stage::Placing, 0, [0.3, 0.3, 0.3]),
        ]);
        let text = serde_json::to_string(&taught).unwrap_or_default();
        let back: TaughtQueries = serde_json::from_str(&text).unwrap_or_default();
        assert_eq!(back, taught);
        assert!(back.picking[2].is_some() && back.picking[0].is_none());
    }
}
