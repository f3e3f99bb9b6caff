//! The journal of a run: what a recording shows, collected while the run
//! goes, through a [`World`] wrapper ([`JournalWorld`]: every control
//! cycle's commanded and measured joints, the suction, the products seen
//! and the contacts) and a [`Policy`] wrapper ([`JournalPolicy`]: the
//! reasoner's decisions and the sub-goal planner's answers, at the sim
//! time they were asked). Both pass everything through unchanged, so the
//! run is the same with or without a journal; any planner and any world
//! can be journalled.

use packwright_interface::outcome::Stage;
use packwright_interface::world::Seen;
use packwright_interface::{
    Choice, Contact, DOF, Graph, Joints, Observation, OrderTask, Policy, SequenceRule,
    SubGoalQuery, World, WorldError,
};
use std::sync::{Mutex, MutexGuard, PoisonError};

/// Seconds between two frames of the 3D scene and the joint plots (50
/// frames a second; the world's control cycles in between are summed up
/// by the next frame). Events keep their own cycle's time.
pub const FRAME_PERIOD: f64 = 0.02;

/// One control cycle as it was commanded (what `execute --svg` draws).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cycle {
    /// Sim time at the end of the cycle (s).
    pub time: f64,
    /// The commanded joints (rad).
    pub commanded: Joints,
    /// Whether the suction is on.
    pub suction: bool,
    /// The commanded joints' largest change since the cycle before (rad).
    pub speed: f64,
}

/// The world as measured at one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    /// Sim time (s).
    pub time: f64,
    /// Measured joint positions (rad).
    pub joints: Joints,
    /// Measured joint velocities over the last control cycle (rad/s; 0 at
    /// the start).
    pub velocities: Joints,
    pub suction: bool,
    /// The products seen (centre and yaw), by name.
    pub products: Vec<Seen>,
}

/// A reasoner decision: its graph (nodes in the taught chain order, named
/// in `nodes`) and its choice.
#[derive(Debug, Clone, PartialEq)]
pub struct Decision {
    /// Sim time of the decision (s).
    pub time: f64,
    pub graph: Graph,
    /// The product name of each graph node.
    pub nodes: Vec<String>,
    pub choice: Choice,
}

/// A sub-goal the learned sub-goal planner gave.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Planned {
    /// Sim time of the question (s).
    pub time: f64,
    pub stage: Stage,
    /// 0, 1, 2: which of the stage's sub-goals.
    pub index: usize,
    /// The cup-tip position it gave (m).
    pub tip: [f64; 3],
}

/// Everything journalled, in time order within each list.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Entries {
    /// The control period (s).
    pub period: f64,
    /// One per control cycle.
    pub cycles: Vec<Cycle>,
    /// The start, then one every [`FRAME_PERIOD`], then the last cycle.
    pub frames: Vec<Frame>,
    /// Contacts the world reported, with their time.
    pub contacts: Vec<Contact>,
    /// Learned planner only.
    pub decisions: Vec<Decision>,
    /// Learned planner only.
    pub planned: Vec<Planned>,
}

/// The journal both wrappers write into (shared: the policy is asked from
/// inside the run while the world steps).
#[derive(Debug, Default)]
pub struct Journal {
    state: Mutex<State>,
}

#[derive(Debug, Default)]
struct State {
    entries: Entries,
    /// Cycles per frame.
    every: usize,
    /// The last cycle's frame when it is not kept (the end of the run is
    /// kept by [`Journal::take`]).
    pending: Option<Frame>,
    commanded: Option<Joints>,
    suction: bool,
}

impl State {
    /// The world as last observed: the pending frame, or the last kept.
    fn latest(&self) -> Option<&Frame> {
        self.pending.as_ref().or(self.entries.frames.last())
    }
}

impl Journal {
    pub fn new() -> Journal {
        Journal::default()
    }

    fn lock(&self) -> MutexGuard<'_, State> {
        // A panic elsewhere while holding the lock leaves whole entries.
        self.state.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// What was journalled; the journal is left empty.
    pub fn take(&self) -> Entries {
        let mut s = self.lock();
        if let Some(frame) = s.pending.take() {
            s.entries.frames.push(frame);
        }
        std::mem::take(&mut s.entries)
    }

    fn start(&self, period: f64, observed: Observation) {
        let mut s = self.lock();
        s.every = ((FRAME_PERIOD / period).round() as usize).max(1);
        s.entries.period = period;
        s.commanded = Some(observed.joints);
        s.suction = observed.suction;
        s.entries.frames.push(Frame {
            time: observed.time,
            joints: observed.joints,
            velocities: [0.0; DOF],
            suction: observed.suction,
            products: observed.products,
        });
    }

    fn stepped(&self, observed: Observation) {
        let mut s = self.lock();
        let s = &mut *s;
        let (t0, q0) = s
            .latest()
            .map_or((observed.time, observed.joints), |f| (f.time, f.joints));
        let dt = observed.time - t0;
        let velocities: Joints = std::array::from_fn(|j| {
            if dt > 0.0 {
                (observed.joints[j] - q0[j]) / dt
            } else {
                0.0
            }
        });
        if let Some(q) = s.commanded {
            // The first cycle's change is from the joints at the start.
            let previous = s
                .entries
                .cycles
                .last()
                .map(|c| c.commanded)
                .or(s.entries.frames.first().map(|f| f.joints))
                .unwrap_or(q);
            let speed = q
                .iter()
                .zip(&previous)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            s.entries.cycles.push(Cycle {
                time: observed.time,
                commanded: q,
                suction: s.suction,
                speed,
            });
        }
        let frame = Frame {
            time: observed.time,
            joints: observed.joints,
            velocities,
            suction: observed.suction,
            products: observed.products,
        };
        if s.entries.cycles.len().is_multiple_of(s.every.max(1)) {
            s.entries.frames.push(frame);
            s.pending = None;
        } else {
            s.pending = Some(frame);
        }
    }

    /// The time of the last observation and the names of the products it
    /// saw.
    fn now(&self) -> (f64, Vec<String>) {
        let s = self.lock();
        s.latest().map_or((0.0, Vec::new()), |f| {
            (f.time, f.products.iter().map(|p| p.name.clone()).collect())
        })
    }
}

/// A [`World`] that passes everything to `inner` and journals it.
pub struct JournalWorld<'a, W: World> {
    inner: &'a mut W,
    journal: &'a Journal,
}

impl<'a, W: World> JournalWorld<'a, W> {
    /// Journals `inner` into `journal`, from its state now.
    pub fn new(inner: &'a mut W, journal: &'a Journal) -> JournalWorld<'a, W> {
        journal.start(inner.control_period(), inner.observe());
        JournalWorld { inner, journal }
    }
}

impl<W: World> World for JournalWorld<'_, W> {
    fn control_period(&self) -> f64 {
        self.inner.control_period()
    }
    fn observe(&self) -> Observation {
        self.inner.observe()
    }
    fn command(&mut self, joints: &Joints) -> Result<(), WorldError> {
        self.inner.command(joints)?;
        self.journal.lock().commanded = Some(*joints);
        Ok(())
    }
    fn set_suction(&mut self, on: bool) -> Result<(), WorldError> {
        self.inner.set_suction(on)?;
        self.journal.lock().suction = on;
        Ok(())
    }
    fn step(&mut self) -> Result<(), WorldError> {
        self.inner.step()?;
        self.journal.stepped(self.inner.observe());
        Ok(())
    }
    fn take_collisions(&mut self) -> Vec<Contact> {
        let contacts = self.inner.take_collisions();
        self.journal
            .lock()
            .entries
            .contacts
            .extend(contacts.iter().cloned());
        contacts
    }
}

/// A [`Policy`] that passes everything to `inner` and journals the
/// reasoner's decisions and the sub-goal planner's answers.
pub struct JournalPolicy<'a> {
    inner: &'a dyn Policy,
    journal: &'a Journal,
    /// The task's product names in the taught chain order.
    chain: Vec<String>,
}

impl<'a> JournalPolicy<'a> {
    pub fn new(inner: &'a dyn Policy, journal: &'a Journal, task: &OrderTask) -> JournalPolicy<'a> {
        let names: Vec<&str> = task.products.iter().map(|p| p.name.as_str()).collect();
        let chain = inner
            .sequence()
            .chain(&names)
            .into_iter()
            .filter_map(|p| names.get(p).map(|n| (*n).to_owned()))
            .collect();
        JournalPolicy {
            inner,
            journal,
            chain,
        }
    }
}

impl Policy for JournalPolicy<'_> {
    fn reason(&self, graph: &Graph) -> Choice {
        let choice = self.inner.reason(graph);
        // The graph's nodes are the products seen, in chain order.
        let (time, seen) = self.journal.now();
        let nodes = self
            .chain
            .iter()
            .filter(|n| seen.contains(n))
            .cloned()
            .collect();
        self.journal.lock().entries.decisions.push(Decision {
            time,
            graph: graph.clone(),
            nodes,
            choice,
        });
        choice
    }
    fn subgoal(&self, query: &SubGoalQuery) -> [f32; 3] {
        let tip = self.inner.subgoal(query);
        let (time, _) = self.journal.now();
        self.journal.lock().entries.planned.push(Planned {
            time,
            stage: query.stage,
            index: query.index,
            tip: tip.map(f64::from),
        });
        tip
    }
    fn action(&self, delta: [f32; 3], joints: [f32; 3]) -> [f32; 3] {
        self.inner.action(delta, joints)
    }
    fn sequence(&self) -> SequenceRule {
        self.inner.sequence()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A world whose base joint turns 0.001 rad per 2 ms cycle.
    struct Turning {
        steps: usize,
        commanded: Joints,
    }

    impl World for Turning {
        fn control_period(&self) -> f64 {
            0.002
        }
        fn observe(&self) -> Observation {
            let mut joints = [0.0; DOF];
            joints[0] = self.steps as f64 * 0.001;
            Observation {
                time: self.steps as f64 * 0.002,
                joints,
                suction: false,
                products: vec![Seen {
                    name: "jam".into(),
                    centre: [0.5, 0.0, 0.03],
                    yaw: 0.0,
                }],
            }
        }
        fn command(&mut self, joints: &Joints) -> Result<(), WorldError> {
            self.commanded = *joints;
            Ok(())
        }
        fn set_suction(&mut self, _on: bool) -> Result<(), WorldError> {
            Ok(())
        }
        fn step(&mut self) -> Result<(), WorldError> {
            self.steps += 1;
            Ok(())
        }
        fn take_collisions(&mut self) -> Vec<Contact> {
            Vec::new()
        }
    }

    /// 25 cycles: a frame at the start, every 10 cycles (20 ms) and at
    /// the last cycle; every cycle kept; velocities over one cycle.
    #[test]
    fn frames_every_twenty_milliseconds_and_the_last_cycle() {
        let mut world = Turning {
            steps: 0,
            commanded: [0.0; DOF],
        };
        let journal = Journal::new();
        let mut w = JournalWorld::new(&mut world, &journal);
        for k in 0..25 {
            let mut q = [0.0; DOF];
            q[0] = f64::from(k) * 0.001;
            assert!(w.command(&q).is_ok());
            assert!(w.step().is_ok());
        }
        let entries = journal.take();
        assert_eq!(entries.cycles.len(), 25);
        let times: Vec<f64> = entries.frames.iter().map(|f| f.time).collect();
        assert_eq!(times.len(), 4);
        for (t, expected) in times.iter().zip([0.0, 0.02, 0.04, 0.05]) {
            assert!((t - expected).abs() < 1e-12, "{times:?}");
        }
        assert_eq!(entries.frames[0].velocities[0], 0.0);
        for f in &entries.frames[1..] {
            assert!((f.velocities[0] - 0.5).abs() < 1e-9, "{:?}", f.velocities);
            assert_eq!(f.products.len(), 1);
        }
        assert!(entries.cycles.iter().all(|c| !c.suction));
        assert!(journal.take().frames.is_empty(), "taken");
    }
}
