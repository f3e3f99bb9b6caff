//! `Station::send_legs` against the simulator.

use super::*;
use packwright_interface::world::WorldError;
use packwright_sim::Simulator;

// The bench cell the crate's integration tests use.
#[path = "../../tests/common/mod.rs"]
mod common;

/// The simulator, remembering each command and where each suction
/// switch happened.
struct Recording {
    sim: Simulator,
    commands: Vec<Joints>,
    switches: Vec<(bool, Option<Joints>)>,
}

impl World for Recording {
    fn control_period(&self) -> f64 {
        self.sim.control_period()
    }
    fn observe(&self) -> Observation {
        self.sim.observe()
    }
    fn command(&mut self, joints: &Joints) -> Result<(), WorldError> {
        self.commands.push(*joints);
        self.sim.command(joints)
    }
    fn set_suction(&mut self, on: bool) -> Result<(), WorldError> {
        self.switches.push((on, self.commands.last().copied()));
        self.sim.set_suction(on)
    }
    fn step(&mut self) -> Result<(), WorldError> {
        self.sim.step()
    }
    fn take_collisions(&mut self) -> Vec<Contact> {
        self.sim.take_collisions()
    }
}

/// A leg that does not move but switches the suction (its sub-goal
/// already reached) switches where the leg before it ends, at rest:
/// the blend must stop there, not pass through it.
#[test]
fn a_switch_on_a_leg_that_does_not_move_happens_at_rest() {
    let arm = Arm::ur10();
    let task = OrderTask {
        cell: common::bench_cell(),
        products: Vec::new(),
        assignment: Vec::new(),
    };
    let start = home(&arm, &task.cell).expect("a start pose");
    let sim = Simulator::new(arm.clone(), &task.cell, &[], start).expect("a simulation");
    let mut world = Recording {
        sim,
        commands: Vec::new(),
        switches: Vec::new(),
    };
    let mut station = Station::new(&mut world, &arm, &task);
    let at = |x: f64, y: f64, z: f64| {
        reach(
            &station.checker,
            Point3::new(x, y, z),
            0.0,
            &start,
            Load::FREE,
        )
        .expect("reachable")
    };
    // Out and back: the joints turn round at `a`, where two legs can
    // overlap.
    let (a, b) = (at(0.45, -0.15, 0.2), at(0.75, -0.4, 0.35));
    let route = |station: &Station<Recording>, from: Joints, to: Joints| {
        station.checked(1, from, &[to], Load::FREE).expect("free")
    };
    let legs = vec![
        Leg::new(route(&station, start, a), Suction::Keep, Load::FREE),
        Leg::new(
            Route {
                waypoints: Vec::new(),
                samples: Vec::new(),
            },
            Suction::On,
            Load::FREE,
        ),
        Leg::new(route(&station, a, b), Suction::Keep, Load::FREE),
    ];
    let tail = station.send_legs(legs, false).expect("sent");
    assert!(tail.is_empty());
    assert_eq!(world.switches, [(true, Some(a))]);
    assert_eq!(world.commands.last(), Some(&b));
}

#[test]
fn settle_times_are_whole_control_cycles() {
    assert_eq!(settle_cycles(0.1, 0.002), 50);
    assert_eq!(settle_cycles(0.5, 0.002), 250);
    assert_eq!(settle_cycles(0.0, 0.002), 0);
    assert_eq!(settle_cycles(0.0031, 0.002), 2);
    assert_eq!(settle_cycles(-1.0, 0.002), 0);
    assert_eq!(settle_cycles(f64::NAN, 0.002), 0);
    assert_eq!(settle_cycles(0.1, 0.0), 0);
}
