//! [`Ur10World`]: the real UR10 as a [`World`].
//!
//! Connecting sets up RTDE (the state at the controller's frequency, one
//! input recipe), checks the robot can move, sends the streaming program
//! ([`crate::script`]) over the secondary interface and waits for it to
//! play. A streaming thread then answers every data package with one
//! input package (robot-paced), with a new sequence number: the command
//! [`World::step`] handed over (mode servo) or, when none came within half
//! a period, a hold: the last target again (mode hold: a late cycle in
//! the middle of a motion delays it by a cycle rather than putting a
//! `stopj` into it), or mode stop before the first target. So the
//! controller's watchdog sees the computer alive while it plans, and
//! stops the arm when the process dies.
//!
//! Guarantees: every target is checked ([`CommandCheck`]) before it is
//! sent; the first fault ([`Fault`]: the safety mode not normal or
//! reduced, the robot not running, the program not playing, the socket
//! closed, no data for [`Settings::stall_periods`] periods, a refused
//! target) is latched, the thread sends the program's exit (stopj) and
//! stops, and every later call returns [`WorldError::Stopped`]: no further
//! command is sent. Nothing re-arms the robot; that is
//! [`crate::dashboard`], called by a person's decision.

use crate::address::RobotAddress;
use crate::client::{Client, connect};
use crate::codec::ControllerVersion;
use crate::dashboard::remote_control;
use crate::error::{Service, UrError};
use crate::products::ProductSource;
use crate::recipe::{
    DigitalOutput, Mode, RobotState, RuntimeState, input_names, input_types, input_values,
};
use crate::safety::{CommandCheck, CommandProblem, Fault, Latch, check_state};
use crate::script::Program;
use packwright_interface::world::{Contact, Observation, World, WorldError};
use packwright_interface::{DOF, Joints, Limits};
use std::io::Read;
use std::io::Write;
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Where the suction's state is read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SuctionSensor {
    /// The suction output itself, as the controller reports it.
    Output,
    /// A digital input (a vacuum switch): its bit in
    /// `actual_digital_input_bits` (standard 0-7, configurable 8-15, tool
    /// 16-17).
    Input(u32),
}

/// How to drive the robot.
#[derive(Debug, Clone, PartialEq)]
pub struct Settings {
    pub address: RobotAddress,
    /// The arm's joint limits (the commands are checked against them).
    pub limits: [Limits; DOF],
    /// The digital output that switches the suction.
    pub suction: DigitalOutput,
    pub sensor: SuctionSensor,
    /// Largest distance (rad) of a target from the measured joints.
    pub tracking: f64,
    /// Periods without a data package before the driver stops.
    pub stall_periods: u32,
    /// How long to wait for the program to play after sending it.
    pub start_timeout: Duration,
    /// The controller's watchdog: below this frequency of sequence
    /// changes it stops the program (Hz).
    pub watchdog_hz: f64,
    /// servoj's lookahead time (s); the period comes from the controller's
    /// version.
    pub lookahead: f64,
    /// servoj's gain.
    pub gain: f64,
}

impl Settings {
    /// The defaults: suction on standard output 0 read back from the
    /// output, a tracking bound of 0.3 rad, 25 periods of silence (50 ms
    /// at 500 Hz), 3 s for the program to start, watchdog 20 Hz,
    /// lookahead 0.1 s, gain 300.
    pub fn new(address: RobotAddress, limits: [Limits; DOF]) -> Settings {
        Settings {
            address,
            limits,
            suction: DigitalOutput::Standard(0),
            sensor: SuctionSensor::Output,
            tracking: 0.3,
            stall_periods: 25,
            start_timeout: Duration::from_secs(3),
            watchdog_hz: 20.0,
            lookahead: 0.1,
            gain: 300.0,
        }
    }
}

/// What the main thread and the streaming thread share.
struct Shared {
    state: RobotState,
    /// Data packages received.
    cycle: u64,
    /// The step waiting to be sent: its id and target (`None`: hold).
    command: Option<(u64, Option<Joints>)>,
    /// The last step sent: its id and the cycle it answered.
    sent: (u64, u64),
    suction: bool,
    latch: Latch,
    /// Targets sent (servo packages).
    targets: u64,
    /// The thread is to send the program's exit and end.
    finish: bool,
    /// The thread has ended.
    ended: bool,
}

type Sync = Arc<(Mutex<Shared>, Condvar)>;

fn lock(sync: &Sync) -> MutexGuard<'_, Shared> {
    // A poisoned lock means the other thread panicked; its data is still
    // the best there is.
    sync.0.lock().unwrap_or_else(|e| e.into_inner())
}

/// The real UR10 (or a controller that speaks like it).
pub struct Ur10World {
    sync: Sync,
    thread: Option<JoinHandle<()>>,
    period: f64,
    controller: ControllerVersion,
    sensor: SuctionSensor,
    output: DigitalOutput,
    products: Box<dyn ProductSource>,
    pending: Option<Joints>,
    next_id: u64,
    t0: f64,
    stall: Duration,
    /// Planner cycles per controller cycle: 1 on an e-Series (2 ms), 4 on
    /// a CB3 (8 ms).
    substeps: u32,
    /// Planner cycles since the last controller cycle.
    substep: u32,
}

/// The planner's control period (s): its Ruckig commands are 2 ms apart
/// whatever the controller. On a slower controller (a CB3's 8 ms) the
/// world takes several of them per controller cycle and streams the last:
/// the same trajectory, sampled at the controller's rate, at full speed.
pub const PLANNER_PERIOD: f64 = 0.002;

impl std::fmt::Debug for Ur10World {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Ur10World")
            .field("period", &self.period)
            .field("controller", &self.controller)
            .finish_non_exhaustive()
    }
}

impl Ur10World {
    /// Connects, checks the robot can move, starts the streaming program.
    /// Errors: an unreachable host, a refused recipe, a robot not ready
    /// (protective stop, not running), a program already playing, a
    /// program that does not play (not in remote control).
    pub fn connect(
        settings: &Settings,
        products: Box<dyn ProductSource>,
    ) -> Result<Ur10World, UrError> {
        let mut client = Client::connect(&settings.address.rtde_addr())?;
        let controller = client.controller();
        let frequency = controller.frequency();
        let period = 1.0 / frequency;
        client.setup_state(frequency)?;
        client.setup_inputs(&input_names(settings.suction), &input_types())?;
        client.start()?;
        let stall = Duration::from_secs_f64(period * f64::from(settings.stall_periods.max(1)));
        let mut state = client.receive_state(stall.max(Duration::from_millis(500)))?;
        // The robot must be powered, running and safe before the program
        // goes.
        if let Err(f @ (Fault::Safety(_) | Fault::Robot(_))) = check_state(&state) {
            let _ = client.pause();
            return Err(UrError::NotReady(f));
        }
        // Only a program that starts after ours was sent is ours; the
        // arm must move at the speeds planned.
        if let Err(e) = ready_to_stream(&state) {
            let _ = client.pause();
            return Err(e);
        }
        // The suction stays as it is (a product held at connection is not
        // dropped) until the caller switches it.
        let suction_on = state.digital_outputs >> settings.suction.bit() & 1 == 1;
        let mut sequence = 1;
        let hold = |client: &mut Client, sequence: &mut i32, q: &Joints| {
            *sequence = sequence.wrapping_add(1);
            client.send(&input_values(
                *sequence,
                Mode::Stop,
                q,
                settings.suction,
                suction_on,
            ))
        };
        hold(&mut client, &mut sequence, &state.actual_q)?;
        let program = Program {
            watchdog_hz: settings.watchdog_hz,
            lookahead: settings.lookahead,
            gain: settings.gain,
            ..Program::for_period(period)
        };
        send_program(&settings.address, &program.render())?;
        let started = Instant::now();
        while state.runtime_state != RuntimeState::Playing {
            if started.elapsed() > settings.start_timeout {
                let _ = client.pause();
                let remote = remote_control(&settings.address.dashboard_addr());
                return Err(UrError::ProgramNotStarted { remote });
            }
            state = client.receive_state(stall.max(Duration::from_millis(500)))?;
            if let Err(f @ (Fault::Safety(_) | Fault::Robot(_))) = check_state(&state) {
                let _ = client.pause();
                return Err(UrError::NotReady(f));
            }
            hold(&mut client, &mut sequence, &state.actual_q)?;
        }
        let sync: Sync = Arc::new((
            Mutex::new(Shared {
                state,
                cycle: 0,
                command: None,
                sent: (0, 0),
                suction: suction_on,
                latch: Latch::default(),
                targets: 0,
                finish: false,
                ended: false,
            }),
            Condvar::new(),
        ));
        let check = CommandCheck {
            limits: settings.limits,
            period,
            tracking: settings.tracking,
        };
        let streamer = Streamer {
            client,
            sync: Arc::clone(&sync),
            check,
            suction: settings.suction,
            sequence,
            previous: state.actual_q,
            servoing: false,
            stall,
            period,
        };
        let thread = std::thread::Builder::new()
            .name("ur-stream".into())
            .spawn(move || streamer.run())
            .map_err(|source| UrError::Io {
                service: Service::Rtde,
                cause: source,
            })?;
        Ok(Ur10World {
            sync,
            thread: Some(thread),
            period,
            controller,
            sensor: settings.sensor,
            output: settings.suction,
            products,
            pending: None,
            next_id: 1,
            t0: state.timestamp,
            stall,
            substeps: ((period / PLANNER_PERIOD).round() as u32).max(1),
            substep: 0,
        })
    }

    /// The controller's version.
    pub fn controller(&self) -> ControllerVersion {
        self.controller
    }

    /// The latched fault, if the driver stopped.
    pub fn fault(&self) -> Option<Fault> {
        lock(&self.sync).latch.fault()
    }

    /// The newest robot state.
    pub fn state(&self) -> RobotState {
        lock(&self.sync).state
    }

    /// Targets sent to the controller so far.
    pub fn targets_sent(&self) -> u64 {
        lock(&self.sync).targets
    }

    /// Ends the program (exit: stopj) and the stream; the latched fault, if
    /// any. Dropping the world does the same.
    pub fn close(mut self) -> Option<Fault> {
        self.shutdown();
        self.fault()
    }

    fn shutdown(&mut self) {
        {
            let mut s = lock(&self.sync);
            s.finish = true;
        }
        self.sync.1.notify_all();
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }

    fn stopped(&self, fault: Fault) -> WorldError {
        WorldError::Stopped {
            reason: fault.reason(),
        }
    }
}

impl Drop for Ur10World {
    fn drop(&mut self) {
        self.shutdown();
    }
}

/// The arm's speed (the slider times the controller's scaling) below
/// which a run is refused: packwright streams the speeds it planned.
pub const FULL_SPEED: f64 = 0.99;

/// Whether a robot in `state` may be given the streaming program: no
/// program of someone else's loaded and not stopped (playing, paused: the
/// driver would abort it), and the arm moving at the speeds planned (the
/// pendant's speed slider at 100%). Asked at connection and by dry runs.
pub fn ready_to_stream(state: &RobotState) -> Result<(), UrError> {
    if !matches!(
        state.runtime_state,
        RuntimeState::Stopped | RuntimeState::Stopping
    ) {
        return Err(UrError::ProgramRunning {
            state: state.runtime_state,
        });
    }
    if state.speed() < FULL_SPEED {
        return Err(UrError::SlowedDown {
            percent: state.speed() * 100.0,
        });
    }
    Ok(())
}

/// The controller's version and one state of the robot, read without
/// taking control: an output recipe only, no input recipe, no program
/// (for dry runs). The robot is not checked; see [`check_state`].
pub fn read_state(address: &RobotAddress) -> Result<(ControllerVersion, RobotState), UrError> {
    let mut client = Client::connect(&address.rtde_addr())?;
    let controller = client.controller();
    client.setup_state(controller.frequency())?;
    client.start()?;
    let state = client.receive_state(Duration::from_millis(500))?;
    let _ = client.pause();
    Ok((controller, state))
}

/// What the URScript manual asks a client to read from the secondary
/// interface before closing it ("Connecting to URControl": at least 79
/// bytes, or the program sent may be discarded before it runs).
const READ_BEFORE_CLOSING: usize = 79;

/// Sends the program text to the secondary interface, then reads what the
/// controller greets a client with (its version message, then robot
/// state), [`READ_BEFORE_CLOSING`] bytes at least, for at most a second,
/// before closing.
fn send_program(address: &RobotAddress, text: &str) -> Result<(), UrError> {
    let mut s = connect(
        &address.secondary_addr(),
        Service::Secondary,
        Duration::from_secs(2),
    )?;
    let io = |source| UrError::Io {
        service: Service::Secondary,
        cause: source,
    };
    s.write_all(text.as_bytes())
        .and_then(|_| s.flush())
        .map_err(io)?;
    let deadline = Instant::now() + Duration::from_secs(1);
    let mut read = 0;
    let mut buf = [0u8; 4096];
    while read < READ_BEFORE_CLOSING {
        let left = deadline.saturating_duration_since(Instant::now());
        if left.is_zero() || s.set_read_timeout(Some(left)).is_err() {
            break;
        }
        match s.read(&mut buf) {
            Ok(0) => break,
            Ok(n) => read += n,
            Err(_) => break,
        }
    }
    Ok(())
}

fn read_suction(sensor: SuctionSensor, output: DigitalOutput, s: &RobotState) -> bool {
    match sensor {
        SuctionSensor::Output => s.digital_outputs >> output.bit() & 1 == 1,
        SuctionSensor::Input(bit) => bit < 64 && s.digital_inputs >> bit & 1 == 1,
    }
}

impl World for Ur10World {
    /// The planner's period: the controller's divided by the planner
    /// cycles it takes ([`PLANNER_PERIOD`] on a UR10 of either series).
    fn control_period(&self) -> f64 {
        self.period / f64::from(self.substeps)
    }

    fn observe(&self) -> Observation {
        let state = self.state();
        Observation {
            time: state.timestamp - self.t0,
            joints: state.actual_q,
            suction: read_suction(self.sensor, self.output, &state),
            products: self.products.products(),
        }
    }

    /// Keeps the target for the next [`World::step`]; it is checked there,
    /// before it is sent.
    fn command(&mut self, joints: &Joints) -> Result<(), WorldError> {
        if let Some(f) = self.fault() {
            return Err(self.stopped(f));
        }
        self.pending = Some(*joints);
        Ok(())
    }

    fn set_suction(&mut self, on: bool) -> Result<(), WorldError> {
        let mut s = lock(&self.sync);
        if let Some(f) = s.latch.fault() {
            return Err(self.stopped(f));
        }
        s.suction = on;
        Ok(())
    }

    /// Hands the target (or a hold) to the streaming thread and waits until
    /// it was sent and the next state arrived: one controller cycle. On a
    /// controller slower than the planner (a CB3), only every
    /// `substeps`-th planner cycle does so, with the latest target; the
    /// others only keep it.
    fn step(&mut self) -> Result<(), WorldError> {
        self.substep += 1;
        if self.substep < self.substeps {
            return match self.fault() {
                Some(f) => Err(self.stopped(f)),
                None => Ok(()),
            };
        }
        self.substep = 0;
        let id = self.next_id;
        self.next_id += 1;
        let target = self.pending.take();
        let sync = Arc::clone(&self.sync);
        let mut s = lock(&sync);
        if let Some(f) = s.latch.fault() {
            return Err(self.stopped(f));
        }
        s.command = Some((id, target));
        sync.1.notify_all();
        let deadline = Instant::now() + self.stall * 4 + Duration::from_millis(200);
        loop {
            if let Some(f) = s.latch.fault() {
                return Err(self.stopped(f));
            }
            if s.sent.0 >= id && s.cycle > s.sent.1 {
                break;
            }
            if s.ended {
                let f = s.latch.trip(Fault::ConnectionLost);
                return Err(self.stopped(f));
            }
            let now = Instant::now();
            if now >= deadline {
                let f = s.latch.trip(Fault::Stalled {
                    waited_s: (self.stall * 4).as_secs_f64(),
                });
                sync.1.notify_all();
                return Err(self.stopped(f));
            }
            s = sync
                .1
                .wait_timeout(s, deadline - now)
                .map(|(g, _)| g)
                .unwrap_or_else(|e| e.into_inner().0);
        }
        let state = s.state;
        drop(s);
        let suction = read_suction(self.sensor, self.output, &state);
        self.products.update(&state.actual_q, suction);
        Ok(())
    }

    /// The driver cannot tell contacts; a collision stops the robot
    /// (protective stop), which [`World::step`] reports.
    fn take_collisions(&mut self) -> Vec<Contact> {
        Vec::new()
    }
}

/// The fault of a target that failed its check with the robot in
/// `state`: a target too far from the measured joints while the
/// controller slows the arm (the slider moved during the run, Reduced
/// mode's limits) says so.
fn fell_behind(problem: CommandProblem, state: &RobotState) -> Fault {
    match problem {
        CommandProblem::FarFromMeasured { .. } if state.speed() < FULL_SPEED => Fault::FellBehind {
            problem,
            percent: state.speed() * 100.0,
        },
        _ => Fault::Rejected(problem),
    }
}

/// The streaming thread's state.
struct Streamer {
    client: Client,
    sync: Sync,
    check: CommandCheck,
    suction: DigitalOutput,
    sequence: i32,
    /// The last target sent (the measured joints before the first).
    previous: Joints,
    /// Whether a target was sent: holds are then the last target again.
    servoing: bool,
    stall: Duration,
    period: f64,
}

impl Streamer {
    fn run(mut self) {
        let fault = self.stream();
        {
            let mut s = lock(&self.sync);
            if let Some(f) = fault {
                s.latch.trip(f);
            }
        }
        self.sync.1.notify_all();
        // Stop: the program's exit (stopj, end), best effort; then the
        // stream pauses and the socket closes.
        let q = lock(&self.sync).state.actual_q;
        let on = lock(&self.sync).suction;
        self.sequence = self.sequence.wrapping_add(1);
        let _ = self.client.send(&input_values(
            self.sequence,
            Mode::Exit,
            &q,
            self.suction,
            on,
        ));
        let _ = self.client.pause();
        lock(&self.sync).ended = true;
        self.sync.1.notify_all();
    }

    /// Streams until a fault (returned) or the world finishes (`None`).
    fn stream(&mut self) -> Option<Fault> {
        let wait = Duration::from_secs_f64(self.period / 2.0);
        loop {
            let state = match self.client.receive_state(self.stall) {
                Ok(s) => s,
                Err(UrError::Timeout { waited, .. }) => {
                    return Some(Fault::Stalled {
                        waited_s: waited.as_secs_f64(),
                    });
                }
                Err(UrError::Io { .. }) => return Some(Fault::ConnectionLost),
                // A malformed package: the stream cannot be trusted.
                Err(_) => return Some(Fault::ConnectionLost),
            };
            let mut s = lock(&self.sync);
            s.state = state;
            // Latched before the cycle counts, so that no step sees this
            // state as a cycle that went well.
            if let Err(f) = check_state(&state) {
                s.latch.trip(f);
            }
            s.cycle += 1;
            let cycle = s.cycle;
            self.sync.1.notify_all();
            if s.latch.fault().is_some() || s.finish {
                return None;
            }
            // Wait (briefly) for the next step.
            let deadline = Instant::now() + wait;
            while s.command.is_none() && !s.finish && s.latch.fault().is_none() {
                let now = Instant::now();
                if now >= deadline {
                    break;
                }
                s = self
                    .sync
                    .1
                    .wait_timeout(s, deadline - now)
                    .map(|(g, _)| g)
                    .unwrap_or_else(|e| e.into_inner().0);
            }
            if s.finish || s.latch.fault().is_some() {
                return None;
            }
            let command = s.command.take();
            let on = s.suction;
            drop(s);
            let (mode, target) = match command {
                Some((_, Some(q))) => (Mode::Servo, q),
                // Once servoing, a hold is the last target again.
                _ if self.servoing => (Mode::Hold, self.previous),
                _ => (Mode::Stop, self.previous),
            };
            if mode != Mode::Stop
                && let Err(p) = self.check.check(&target, &self.previous, &state.actual_q)
            {
                return Some(fell_behind(p, &state));
            }
            self.sequence = self.sequence.wrapping_add(1);
            let values = input_values(self.sequence, mode, &target, self.suction, on);
            if self.client.send(&values).is_err() {
                return Some(Fault::ConnectionLost);
            }
            if mode == Mode::Servo {
                self.previous = target;
                self.servoing = true;
            }
            let mut s = lock(&self.sync);
            if mode == Mode::Servo {
                s.targets += 1;
            }
            if let Some((id, _)) = command {
                s.sent = (id, cycle);
            }
            drop(s);
            self.sync.1.notify_all();
        }
    }
}
