//! The driver against the in-process fake controller: the handshake, the
//! stream, the suction, refused recipes, and every injected fault ending
//! in a stopped arm, a clear typed error and no further target sent.

use packwright_interface::world::{StopReason, World, WorldError};
use packwright_interface::{DOF, Joints, Limits};
use packwright_ur::codec::ControllerVersion;
use packwright_ur::dashboard::Dashboard;
use packwright_ur::fake::{FakeConfig, FakeController, Injected};
use packwright_ur::products::NoProducts;
use packwright_ur::recipe::{RuntimeState, SafetyMode};
use packwright_ur::safety::{CommandProblem, Fault};
use packwright_ur::{RobotAddress, Settings, SuctionSensor, Ur10World, UrError};
use std::time::{Duration, Instant};

fn limits() -> [Limits; DOF] {
    [Limits {
        lower: -2.0 * std::f64::consts::PI,
        upper: 2.0 * std::f64::consts::PI,
        velocity: 2.0,
        acceleration: 8.0,
        jerk: 80.0,
    }; DOF]
}

fn settings(fake: &FakeController) -> Settings {
    let mut s = Settings::new(RobotAddress::parse(&fake.url()).unwrap(), limits());
    s.start_timeout = Duration::from_secs(2);
    // Half a second of silence before a stall (50 ms on a robot), so that
    // a loaded test machine does not look like a stalled link.
    s.stall_periods = 250;
    // For the same reason the controller's watchdog allows half a second
    // without a fed register (50 ms by default): the fake's clock keeps
    // ticking at its pace while a starved driver thread sends nothing. The
    // watchdog tests still see it trip (they wait up to 5 s).
    s.watchdog_hz = 2.0;
    s
}

fn connect(fake: &FakeController) -> Ur10World {
    Ur10World::connect(&settings(fake), Box::new(NoProducts)).expect("connects to the fake")
}

/// `n` targets moving joint 0 by 1 mrad per cycle (0.5 rad/s) from `from`.
fn ramp(from: Joints, n: usize) -> Vec<Joints> {
    (1..=n)
        .map(|i| {
            let mut q = from;
            q[0] += 0.001 * i as f64;
            q
        })
        .collect()
}

/// Sends `targets` one per cycle; the first error and how many went.
fn send(world: &mut Ur10World, targets: &[Joints]) -> (usize, Option<WorldError>) {
    for (i, q) in targets.iter().enumerate() {
        if let Err(e) = world.command(q).and_then(|_| world.step()) {
            return (i, Some(e));
        }
    }
    (targets.len(), None)
}

/// Waits (bounded) until the fake's arm is at rest with its program not
/// playing.
fn wait_stopped(fake: &FakeController) -> (Joints, Joints, SafetyMode, RuntimeState) {
    let started = Instant::now();
    loop {
        let arm = fake.arm();
        if arm.3 != RuntimeState::Playing && arm.1.iter().all(|v| *v == 0.0) {
            return arm;
        }
        assert!(
            started.elapsed() < Duration::from_secs(5),
            "the arm did not stop: {arm:?}"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
}

#[test]
fn streams_targets_one_per_cycle_and_mirrors_the_suction() {
    let fake = FakeController::start(FakeConfig::default()).unwrap();
    let mut world = connect(&fake);
    assert_eq!(world.control_period(), 0.002);
    let start = world.observe().joints;
    assert_eq!(start, FakeConfig::default().start);
    let targets = ramp(start, 200);
    assert_eq!(send(&mut world, &targets[..100]).1, None);
    world.set_suction(true).unwrap();
    assert_eq!(send(&mut world, &targets[100..]).1, None);
    // The fake tracks exactly: the arm is where it was last sent.
    assert_eq!(world.observe().joints, targets[199]);
    assert!(world.observe().suction, "the output reads back as on");
    assert!(world.observe().time > 0.39);
    // Holds (steps without a target) are not targets.
    world.step().unwrap();
    world.set_suction(false).unwrap();
    world.step().unwrap();
    world.step().unwrap();
    assert!(!world.observe().suction);
    assert_eq!(world.targets_sent(), 200);
    assert_eq!(world.close(), None);
    let record = fake.record();
    assert_eq!(record.targets, targets);
    assert!(record.targets_while_stopped.is_empty());
    assert_eq!(record.outputs, [1, 0]);
    assert_eq!(record.exits, 1, "closing ends the program");
    assert_eq!(record.scripts.len(), 1);
    assert!(record.scripts[0].contains("servoj(q, 0, 0, 0.0020"));
    assert!(!record.watchdog_tripped);
    // The program in the manual's form, sent and the greeting read
    // before the connection closed.
    assert_eq!(record.malformed_scripts, 0);
    assert_eq!(record.secondary_resets, 0);
}

/// A planner cycle that comes late in the middle of a motion (the
/// computer busy for 10 ms) holds the arm's course to the last target
/// (mode hold), never a `stopj` into the motion; the targets are the
/// ones sent, in order.
#[test]
fn a_late_cycle_mid_motion_holds_the_course() {
    let fake = FakeController::start(FakeConfig::default()).unwrap();
    let mut world = connect(&fake);
    let start = world.observe().joints;
    let targets = ramp(start, 200);
    assert_eq!(send(&mut world, &targets[..100]).1, None);
    std::thread::sleep(Duration::from_millis(10));
    assert_eq!(send(&mut world, &targets[100..]).1, None);
    assert_eq!(world.close(), None);
    let record = fake.record();
    assert_eq!(record.targets, targets);
    assert!(record.holds > 0, "the late cycles were holds");
    assert_eq!(record.stops_while_moving, 0, "no stopj mid-motion");
}

/// A packet of a type this protocol version does not define, and a text
/// message that is not UTF-8, are skipped: the motion goes on.
#[test]
fn stray_packets_do_not_end_the_stream() {
    let fake = FakeController::start(FakeConfig {
        stray_packets: true,
        ..FakeConfig::default()
    })
    .unwrap();
    let mut world = connect(&fake);
    let start = world.observe().joints;
    let targets = ramp(start, 300);
    assert_eq!(send(&mut world, &targets).1, None);
    assert_eq!(world.close(), None);
    assert_eq!(fake.record().targets, targets);
}

/// A user's program paused on the pendant is not replaced (the driver's
/// program would abort it), and a speed slider below 100% is refused at
/// connection (the arm would fall behind the planned speeds): both named,
/// no program sent.
#[test]
fn a_paused_program_or_a_slowed_arm_is_refused_at_connection() {
    let fake = FakeController::start(FakeConfig {
        runtime: RuntimeState::Paused,
        ..FakeConfig::default()
    })
    .unwrap();
    let e = Ur10World::connect(&settings(&fake), Box::new(NoProducts)).unwrap_err();
    assert!(
        matches!(
            e,
            UrError::ProgramRunning {
                state: RuntimeState::Paused
            }
        ),
        "{e}"
    );
    assert!(e.to_string().contains("a program is paused"), "{e}");
    assert!(fake.record().scripts.is_empty());
    let fake = FakeController::start(FakeConfig {
        speed_fraction: 0.5,
        ..FakeConfig::default()
    })
    .unwrap();
    let e = Ur10World::connect(&settings(&fake), Box::new(NoProducts)).unwrap_err();
    let UrError::SlowedDown { percent } = e else {
        panic!("{e}");
    };
    assert!((percent - 50.0).abs() < 1e-9);
    assert!(fake.record().scripts.is_empty());
}

#[test]
fn a_first_order_arm_lags_and_the_vacuum_input_is_read() {
    let fake = FakeController::start(FakeConfig {
        time_constant: 0.02,
        vacuum_input: Some((9, 0)),
        ..FakeConfig::default()
    })
    .unwrap();
    let mut s = settings(&fake);
    s.sensor = SuctionSensor::Input(9);
    let mut world = Ur10World::connect(&s, Box::new(NoProducts)).unwrap();
    let start = world.observe().joints;
    let targets = ramp(start, 100);
    assert_eq!(send(&mut world, &targets).1, None);
    let lag = targets[99][0] - world.observe().joints[0];
    // At 0.5 rad/s through a 20 ms first-order lag: about 10 mrad behind.
    assert!(lag > 0.005 && lag < 0.012, "lag {lag}");
    world.set_suction(true).unwrap();
    world.step().unwrap();
    world.step().unwrap();
    assert!(world.observe().suction);
}

#[test]
fn fragmented_and_coalesced_writes_stream_the_same() {
    let fake = FakeController::start(FakeConfig {
        fragment: true,
        ..FakeConfig::default()
    })
    .unwrap();
    let mut world = connect(&fake);
    let targets = ramp(world.observe().joints, 60);
    assert_eq!(send(&mut world, &targets).1, None);
    assert_eq!(world.close(), None);
    assert_eq!(fake.record().targets, targets);
}

#[test]
fn a_cb3_streams_at_125_hz() {
    let fake = FakeController::start(FakeConfig {
        version: ControllerVersion {
            major: 3,
            minor: 15,
            bugfix: 0,
            build: 0,
        },
        ..FakeConfig::default()
    })
    .unwrap();
    let mut world = connect(&fake);
    // The planner's 2 ms commands, four per 8 ms controller cycle: the
    // last of each four is streamed, so the motion keeps its speed.
    assert_eq!(world.control_period(), 0.002);
    let commands = ramp(world.observe().joints, 80);
    assert_eq!(send(&mut world, &commands).1, None);
    drop(world);
    let record = fake.record();
    let streamed: Vec<Joints> = commands.iter().skip(3).step_by(4).copied().collect();
    assert_eq!(streamed.len(), 20);
    assert_eq!(record.targets, streamed);
    assert!(record.scripts[0].contains("servoj(q, 0, 0, 0.0080"));
}

#[test]
fn an_unknown_field_is_named() {
    let fake = FakeController::start(FakeConfig {
        not_found: vec!["actual_digital_input_bits".into()],
        ..FakeConfig::default()
    })
    .unwrap();
    let e = Ur10World::connect(&settings(&fake), Box::new(NoProducts)).unwrap_err();
    assert!(
        matches!(&e, UrError::FieldNotFound { field } if field == "actual_digital_input_bits"),
        "{e}"
    );
    assert!(e.to_string().contains("NOT_FOUND"));
    assert!(fake.record().scripts.is_empty(), "no program sent");
}

#[test]
fn a_register_in_use_is_named() {
    let fake = FakeController::start(FakeConfig {
        in_use: vec!["input_int_register_24".into()],
        ..FakeConfig::default()
    })
    .unwrap();
    let e = Ur10World::connect(&settings(&fake), Box::new(NoProducts)).unwrap_err();
    assert!(
        matches!(&e, UrError::FieldInUse { field } if field == "input_int_register_24"),
        "{e}"
    );
    assert!(e.to_string().contains("in use"));
}

#[test]
fn a_robot_not_in_remote_control_is_said_so() {
    let fake = FakeController::start(FakeConfig {
        remote_control: false,
        ..FakeConfig::default()
    })
    .unwrap();
    let mut s = settings(&fake);
    s.start_timeout = Duration::from_millis(300);
    let e = Ur10World::connect(&s, Box::new(NoProducts)).unwrap_err();
    assert!(
        matches!(
            e,
            UrError::ProgramNotStarted {
                remote: Some(false)
            }
        ),
        "{e}"
    );
    assert!(e.to_string().contains("not in remote control"));
    let record = fake.record();
    assert_eq!(record.scripts.len(), 1, "sent, and ignored");
    assert!(record.targets.is_empty() && record.targets_while_stopped.is_empty());
}

#[test]
fn a_robot_in_protective_stop_is_not_started() {
    let fake = FakeController::start(FakeConfig {
        safety_mode: SafetyMode::ProtectiveStop,
        ..FakeConfig::default()
    })
    .unwrap();
    let e = Ur10World::connect(&settings(&fake), Box::new(NoProducts)).unwrap_err();
    assert!(
        matches!(
            e,
            UrError::NotReady(Fault::Safety(SafetyMode::ProtectiveStop))
        ),
        "{e}"
    );
    assert!(e.to_string().contains("protective stop"));
    assert!(fake.record().scripts.is_empty());
}

#[test]
fn an_unreachable_host_is_said_so() {
    // A port nothing listens on.
    let port = {
        let l = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
        l.local_addr().unwrap().port()
    };
    let address = RobotAddress::parse(&format!("ur10://127.0.0.1:{port}")).unwrap();
    let started = Instant::now();
    let e =
        Ur10World::connect(&Settings::new(address, limits()), Box::new(NoProducts)).unwrap_err();
    assert!(matches!(e, UrError::Unreachable { .. }), "{e}");
    assert!(e.to_string().contains("cannot reach"));
    assert!(started.elapsed() < Duration::from_secs(5));
}

/// After a fault: every call fails with the same reason and nothing more
/// is sent.
fn assert_latched(world: &mut Ur10World, reason: StopReason) {
    let stopped = Some(WorldError::Stopped { reason });
    assert_eq!(world.command(&world.observe().joints).err(), stopped);
    assert_eq!(world.step().err(), stopped);
    assert_eq!(world.set_suction(false).err(), stopped);
}

#[test]
fn a_protective_stop_mid_motion_stops_and_needs_an_explicit_rearm() {
    let fake = FakeController::start(FakeConfig {
        inject: Some(Injected::ProtectiveStop { after: 50 }),
        ..FakeConfig::default()
    })
    .unwrap();
    let mut world = connect(&fake);
    let targets = ramp(world.observe().joints, 200);
    let (sent, error) = send(&mut world, &targets);
    assert_eq!(
        error,
        Some(WorldError::Stopped {
            reason: StopReason::ProtectiveStop
        })
    );
    assert_eq!(sent, 49, "the 50th target's cycle reports the stop");
    let fault = world.fault().unwrap();
    assert_eq!(fault, Fault::Safety(SafetyMode::ProtectiveStop));
    assert!(fault.needs_rearm());
    assert!(fault.to_string().contains("re-arm explicitly"));
    assert_latched(&mut world, StopReason::ProtectiveStop);
    let (q, _, safety, _) = wait_stopped(&fake);
    assert_eq!(safety, SafetyMode::ProtectiveStop, "nothing re-armed it");
    // The 50th target arrived as the stop came: the arm stopped at the
    // 49th.
    assert_eq!(q, targets[48]);
    drop(world);
    let record = fake.record();
    assert_eq!(record.targets, targets[..50]);
    assert!(record.targets_while_stopped.is_empty());
    assert!(record.dashboard.is_empty(), "the driver never re-arms");
    // A new connection refuses to start until re-armed...
    let e = Ur10World::connect(&settings(&fake), Box::new(NoProducts)).unwrap_err();
    assert!(matches!(e, UrError::NotReady(_)), "{e}");
    // ...explicitly, through the dashboard.
    let mut dashboard =
        Dashboard::connect(&fake.dashboard_addr().to_string(), Duration::from_secs(2)).unwrap();
    dashboard.close_safety_popup().unwrap();
    dashboard.unlock_protective_stop().unwrap();
    let mut world = connect(&fake);
    let more = ramp(world.observe().joints, 20);
    assert_eq!(send(&mut world, &more).1, None);
}

#[test]
fn a_dropped_socket_stops_and_the_watchdog_stops_the_arm() {
    let fake = FakeController::start(FakeConfig {
        inject: Some(Injected::DropSocket { after: 30 }),
        ..FakeConfig::default()
    })
    .unwrap();
    let mut world = connect(&fake);
    let targets = ramp(world.observe().joints, 200);
    let (sent, error) = send(&mut world, &targets);
    assert_eq!(
        error,
        Some(WorldError::Stopped {
            reason: StopReason::ConnectionLost
        })
    );
    assert_eq!(sent, 29, "the 30th target's cycle reports the loss");
    assert_eq!(world.fault(), Some(Fault::ConnectionLost));
    assert!(
        world
            .fault()
            .unwrap()
            .to_string()
            .contains("connection to the controller was lost")
    );
    assert_latched(&mut world, StopReason::ConnectionLost);
    wait_stopped(&fake);
    let record = fake.record();
    assert!(
        record.watchdog_tripped,
        "the controller's watchdog stopped it"
    );
    assert_eq!(record.targets, targets[..30]);
    assert!(record.targets_while_stopped.is_empty());
}

#[test]
fn a_stalled_stream_stops_and_the_watchdog_stops_the_arm() {
    let fake = FakeController::start(FakeConfig {
        inject: Some(Injected::Stall { after: 40 }),
        ..FakeConfig::default()
    })
    .unwrap();
    let mut s = settings(&fake);
    s.stall_periods = 25;
    let mut world = Ur10World::connect(&s, Box::new(NoProducts)).unwrap();
    let targets = ramp(world.observe().joints, 200);
    let started = Instant::now();
    let (sent, error) = send(&mut world, &targets);
    assert_eq!(
        error,
        Some(WorldError::Stopped {
            reason: StopReason::StalledStream
        })
    );
    assert_eq!(sent, 39, "the 40th target's cycle reports the stall");
    assert!(started.elapsed() < Duration::from_secs(3));
    assert!(matches!(world.fault(), Some(Fault::Stalled { waited_s }) if waited_s >= 0.04));
    assert_latched(&mut world, StopReason::StalledStream);
    wait_stopped(&fake);
    let record = fake.record();
    assert!(record.watchdog_tripped);
    assert_eq!(
        record.exits, 0,
        "the link is down: only the watchdog stops it"
    );
    assert_eq!(record.targets, targets[..40]);
    assert!(record.targets_while_stopped.is_empty());
}

#[test]
fn a_jump_is_refused_before_it_is_sent() {
    let fake = FakeController::start(FakeConfig::default()).unwrap();
    let mut world = connect(&fake);
    let mut targets = ramp(world.observe().joints, 20);
    // 0.1 rad in one 2 ms cycle: 50 rad/s.
    targets[10][3] += 0.1;
    let (sent, error) = send(&mut world, &targets);
    assert_eq!(
        error,
        Some(WorldError::Stopped {
            reason: StopReason::CommandRejected
        })
    );
    assert_eq!(sent, 10);
    assert!(matches!(
        world.fault(),
        Some(Fault::Rejected(CommandProblem::TooFast { joint: 3, .. }))
    ));
    assert_latched(&mut world, StopReason::CommandRejected);
    let (q, ..) = wait_stopped(&fake);
    assert_eq!(q, targets[9]);
    let record = fake.record();
    assert_eq!(record.targets, targets[..10]);
    assert_eq!(record.exits, 1, "the program was ended");
}

#[test]
fn a_target_outside_the_limits_is_refused() {
    let fake = FakeController::start(FakeConfig::default()).unwrap();
    let mut s = settings(&fake);
    s.limits[5].upper = 0.0005;
    let mut world = Ur10World::connect(&s, Box::new(NoProducts)).unwrap();
    let mut q = world.observe().joints;
    q[5] += 0.001;
    world.command(&q).unwrap();
    assert_eq!(
        world.step().err(),
        Some(WorldError::Stopped {
            reason: StopReason::CommandRejected
        })
    );
    assert!(matches!(
        world.fault(),
        Some(Fault::Rejected(CommandProblem::OutsideLimits {
            joint: 5,
            ..
        }))
    ));
    assert!(fake.record().targets.is_empty());
}

/// Against a real controller or URSim: connect, read the joints, hold for
/// a few cycles, end the program. It moves nothing. Runs only when
/// `UR_ROBOT_HOST` is set.
#[test]
fn a_real_controller_when_ur_robot_host_is_set() {
    let Ok(host) = std::env::var("UR_ROBOT_HOST") else {
        eprintln!("UR_ROBOT_HOST not set: skipped");
        return;
    };
    let address = RobotAddress::parse(&format!("ur10://{host}")).unwrap();
    let mut world = Ur10World::connect(&Settings::new(address, limits()), Box::new(NoProducts))
        .unwrap_or_else(|e| panic!("{e}"));
    let q = world.observe().joints;
    assert!(q.iter().all(|v| v.is_finite()));
    for _ in 0..50 {
        world.step().unwrap();
    }
    assert_eq!(world.close(), None);
}

#[test]
fn the_state_is_read_without_taking_control() {
    let fake = FakeController::start(FakeConfig::default()).unwrap();
    let address = RobotAddress::parse(&fake.url()).unwrap();
    let (controller, state) = packwright_ur::read_state(&address).unwrap();
    assert_eq!(controller.major, 5);
    assert_eq!(state.actual_q, FakeConfig::default().start);
    assert_eq!(state.runtime_state, RuntimeState::Stopped);
    let record = fake.record();
    assert!(record.scripts.is_empty() && record.inputs == 0);
}

#[test]
fn a_program_already_playing_is_not_replaced() {
    let fake = FakeController::start(FakeConfig::default()).unwrap();
    let world = connect(&fake);
    // A second driver while the first one's program plays.
    let e = Ur10World::connect(&settings(&fake), Box::new(NoProducts)).unwrap_err();
    assert!(
        matches!(
            e,
            UrError::ProgramRunning {
                state: RuntimeState::Playing
            }
        ),
        "{e}"
    );
    assert_eq!(fake.record().scripts.len(), 1);
    // The refused driver has gone; the first one's program still plays,
    // fed by it (the fake's clock once ran on for the one that left, and
    // the watchdog stopped the program that was still fed).
    std::thread::sleep(Duration::from_millis(300));
    assert_eq!(world.close(), None);
}

#[test]
fn products_come_from_a_vision_feed() {
    use packwright_ur::products::JsonFeed;
    use std::io::Write;
    let vision = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let at = vision.local_addr().unwrap().to_string();
    let sender = std::thread::spawn(move || {
        let (mut s, _) = vision.accept().unwrap();
        s.write_all(b"{\"products\": [{\"name\": \"jam\", \"centre\": [0.6, -0.2, 0.04]}]}\n")
            .unwrap();
        // Keep the feed open while the world runs.
        std::thread::sleep(Duration::from_millis(500));
    });
    let fake = FakeController::start(FakeConfig::default()).unwrap();
    let feed = JsonFeed::connect(&at, Duration::from_secs(2)).unwrap();
    let mut world = Ur10World::connect(&settings(&fake), Box::new(feed)).unwrap();
    let started = Instant::now();
    while world.observe().products.is_empty() {
        assert!(started.elapsed() < Duration::from_secs(5), "no products");
        world.step().unwrap();
    }
    let seen = world.observe().products;
    assert_eq!(seen.len(), 1);
    assert_eq!(seen[0].name, "jam");
    assert_eq!(seen[0].centre, [0.6, -0.2, 0.04]);
    assert_eq!(world.close(), None);
    sender.join().unwrap();
}

#[test]
fn a_product_held_at_connection_is_not_dropped() {
    let fake = FakeController::start(FakeConfig {
        outputs: 1,
        ..FakeConfig::default()
    })
    .unwrap();
    let mut world = connect(&fake);
    world.step().unwrap();
    assert!(world.observe().suction, "still on");
    world.set_suction(false).unwrap();
    world.step().unwrap();
    world.step().unwrap();
    assert!(!world.observe().suction);
    assert_eq!(world.close(), None);
    assert_eq!(fake.record().outputs, [0], "switched only by the caller");
}
