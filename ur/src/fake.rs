//! An in-process fake UR controller for tests (feature `fake`): RTDE, the
//! secondary interface and the dashboard server on `127.0.0.1`, each on a
//! port of its own ([`FakeController::url`]).
//!
//! It performs the RTDE handshake from a name-to-type table
//! ([`crate::recipe::type_of`]; names can be made `NOT_FOUND` or
//! `IN_USE`), streams data packages on a test clock (one period per
//! package, lockstep with the client: the next package goes when the
//! client's input arrived, or after [`FakeConfig::pace`] of wall time),
//! runs the streaming program it was sent (the mode register: servoj,
//! followed as a first-order system of [`FakeConfig::time_constant`], 0
//! tracking exactly; stopj; exit), mirrors the digital outputs (and the
//! suction output to a vacuum input if asked), emulates the RTDE watchdog
//! on the test clock, and injects faults ([`Injected`]). Everything it saw
//! is in its [`Record`].
//!
//! Guarantees: it never panics on what a client sends (a malformed packet
//! closes that connection); every socket has a timeout; its threads end
//! when it is dropped.

use crate::codec::{
    ControllerVersion, Direction, FieldType, Framer, Packet, TextMessage, Value, decode_values,
    encode_values,
};
use crate::recipe::{
    MODE_REGISTER, Mode, OUTPUTS, RobotMode, RobotState, RuntimeState, SafetyMode, TARGET_REGISTER,
    type_of,
};
use packwright_interface::Joints;
use std::f64::consts::FRAC_PI_2;
use std::io::{BufRead, BufReader, ErrorKind, Read, Write};
use std::net::{Shutdown, SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// A fault to inject, after the fake has received `after` servo targets.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Injected {
    /// The controller's protective stop: the arm stops, the program
    /// pauses, until the dashboard's `unlock protective stop`.
    ProtectiveStop { after: u64 },
    /// The controller closes the RTDE connection.
    DropSocket { after: u64 },
    /// The link stalls: no data packages go out and what the client sends
    /// is lost (the connection stays open); the controller's clock goes
    /// on, so its watchdog fires.
    Stall { after: u64 },
}

/// How the fake behaves.
#[derive(Debug, Clone, PartialEq)]
pub struct FakeConfig {
    pub version: ControllerVersion,
    /// Where the arm is at the start.
    pub start: Joints,
    /// servoj is followed as `q += (target - q)(1 - exp(-dt/tau))`; 0
    /// tracks exactly.
    pub time_constant: f64,
    /// Whether the robot is in remote control (else programs sent to the
    /// secondary interface are ignored, as a real one does).
    pub remote_control: bool,
    pub robot_mode: RobotMode,
    pub safety_mode: SafetyMode,
    /// Names the controller does not know.
    pub not_found: Vec<String>,
    /// Input names another client already writes.
    pub in_use: Vec<String>,
    pub inject: Option<Injected>,
    /// Write every packet in pieces of 1-7 bytes, and send every seventh
    /// data package together with the next one.
    pub fragment: bool,
    /// Longest wall-clock wait for the client's input before the next
    /// package goes anyway.
    pub pace: Duration,
    /// A vacuum switch: (input bit, output bit) of the digital bits; the
    /// input reads what the output is set to.
    pub vacuum_input: Option<(u32, u32)>,
    /// The digital output bits at the start.
    pub outputs: u64,
    /// The pendant's speed slider (`target_speed_fraction`), 0-1.
    pub speed_fraction: f64,
    /// The program state at the start (a user's program paused on the
    /// pendant: [`RuntimeState::Paused`]).
    pub runtime: RuntimeState,
    /// Every 50th data package is followed by a packet of a type RTDE v2
    /// does not define and a text message whose bytes are not UTF-8 (a
    /// newer controller, a program's Latin-1 message).
    pub stray_packets: bool,
}

impl Default for FakeConfig {
    fn default() -> FakeConfig {
        FakeConfig {
            version: ControllerVersion {
                major: 5,
                minor: 11,
                bugfix: 0,
                build: 0,
            },
            start: [0.0, -FRAC_PI_2, FRAC_PI_2, -FRAC_PI_2, -FRAC_PI_2, 0.0],
            time_constant: 0.0,
            remote_control: true,
            robot_mode: RobotMode::Running,
            safety_mode: SafetyMode::Normal,
            not_found: Vec::new(),
            in_use: Vec::new(),
            inject: None,
            fragment: false,
            pace: Duration::from_millis(50),
            vacuum_input: None,
            outputs: 0,
            speed_fraction: 1.0,
            runtime: RuntimeState::Stopped,
            stray_packets: false,
        }
    }
}

/// What the fake saw and did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Record {
    /// Programs received on the secondary interface (run or ignored).
    pub scripts: Vec<String>,
    /// Servo targets received while the program ran, in order.
    pub targets: Vec<Joints>,
    /// Servo targets received while the arm was stopped (a safety stop, no
    /// program running, after an injected fault): must stay empty.
    pub targets_while_stopped: Vec<Joints>,
    /// Input packages received (any mode).
    pub inputs: u64,
    /// Whether the injected fault happened.
    pub injected: bool,
    /// Whether the watchdog stopped the program.
    pub watchdog_tripped: bool,
    /// The program's exits through the mode register.
    pub exits: u64,
    /// Connections to the RTDE interface.
    pub connections: u64,
    /// Text messages clients sent.
    pub messages: Vec<String>,
    /// Dashboard commands received.
    pub dashboard: Vec<String>,
    /// Programs not in the form the URScript manual gives for a program
    /// sent to the controller (`def` or `sec` in the first column, every
    /// other line indented, `end` last): not run.
    pub malformed_scripts: u64,
    /// Secondary-interface connections the client reset instead of
    /// closing, leaving unread what the controller sent (the manual: read
    /// at least 79 bytes before closing, or the program may be discarded;
    /// the fake discards it).
    pub secondary_resets: u64,
    /// Input packages in mode [`Mode::Hold`].
    pub holds: u64,
    /// Input packages in mode [`Mode::Stop`] while the program played and
    /// the arm moved (a `stopj` in the middle of a motion).
    pub stops_while_moving: u64,
    /// Digital output bits set by clients, in order of change.
    pub outputs: Vec<u64>,
}

/// The emulated robot.
#[derive(Debug, Clone)]
struct Robot {
    time: f64,
    q: Joints,
    qd: Joints,
    target: Joints,
    robot_mode: RobotMode,
    safety_mode: SafetyMode,
    runtime: RuntimeState,
    ints: [i32; 48],
    doubles: [f64; 48],
    outputs: u64,
    /// The watchdog: register, minimum frequency, last value and when it
    /// changed (test clock).
    watchdog: Option<(usize, f64, i32, f64)>,
    /// Servo targets received (for injection).
    servos: u64,
    injected: bool,
    record: Record,
}

impl Robot {
    fn running(&self) -> bool {
        self.runtime == RuntimeState::Playing
            && matches!(self.safety_mode, SafetyMode::Normal | SafetyMode::Reduced)
            && self.robot_mode == RobotMode::Running
    }

    fn state(&self, config: &FakeConfig) -> RobotState {
        let mut inputs = 0u64;
        if let Some((input, output)) = config.vacuum_input
            && input < 64
            && output < 64
            && self.outputs >> output & 1 == 1
        {
            inputs |= 1 << input;
        }
        RobotState {
            timestamp: self.time,
            actual_q: self.q,
            actual_qd: self.qd,
            target_q: self.target,
            robot_mode: self.robot_mode,
            safety_mode: self.safety_mode,
            runtime_state: self.runtime,
            digital_outputs: self.outputs,
            digital_inputs: inputs,
            speed_fraction: config.speed_fraction,
            speed_scaling: 1.0,
        }
    }

    /// One period of the test clock.
    fn tick(&mut self, dt: f64, tau: f64) {
        self.time += dt;
        let before = self.q;
        if self.running() {
            match self.ints[MODE_REGISTER as usize] {
                m if m == Mode::Servo as i32 || m == Mode::Hold as i32 => {
                    let t = TARGET_REGISTER as usize;
                    self.target.copy_from_slice(&self.doubles[t..t + 6]);
                    let k = if tau <= 0.0 {
                        1.0
                    } else {
                        1.0 - (-dt / tau).exp()
                    };
                    for j in 0..6 {
                        self.q[j] += (self.target[j] - self.q[j]) * k;
                    }
                }
                m if m == Mode::Exit as i32 => {
                    self.runtime = RuntimeState::Stopped;
                    self.record.exits += 1;
                    self.target = self.q;
                }
                _ => self.target = self.q,
            }
        } else {
            self.target = self.q;
        }
        for ((v, q), b) in self.qd.iter_mut().zip(&self.q).zip(&before) {
            *v = (q - b) / dt;
        }
        if let Some((reg, hz, last, since)) = self.watchdog
            && self.runtime == RuntimeState::Playing
        {
            let now = self.ints[reg];
            if now != last {
                self.watchdog = Some((reg, hz, now, self.time));
            } else if self.time - since > 1.0 / hz {
                self.runtime = RuntimeState::Stopped;
                self.record.watchdog_tripped = true;
                self.qd = [0.0; 6];
            }
        }
    }

    /// Applies one input package.
    fn input(&mut self, names: &[String], values: &[Value], inject: Option<Injected>) {
        self.record.inputs += 1;
        let mut masks: [(u8, u8); 3] = [(0, 0); 3];
        for (name, v) in names.iter().zip(values) {
            let reg = |prefix: &str| {
                name.strip_prefix(prefix)
                    .and_then(|n| n.parse::<usize>().ok())
                    .filter(|&n| n < 48)
            };
            match (v, name.as_str()) {
                (Value::Int32(x), _) if reg("input_int_register_").is_some() => {
                    if let Some(r) = reg("input_int_register_") {
                        self.ints[r] = *x;
                    }
                }
                (Value::Double(x), _) if reg("input_double_register_").is_some() => {
                    if let Some(r) = reg("input_double_register_") {
                        self.doubles[r] = *x;
                    }
                }
                (Value::Uint8(x), "standard_digital_output_mask") => masks[0].0 = *x,
                (Value::Uint8(x), "standard_digital_output") => masks[0].1 = *x,
                (Value::Uint8(x), "configurable_digital_output_mask") => masks[1].0 = *x,
                (Value::Uint8(x), "configurable_digital_output") => masks[1].1 = *x,
                (Value::Uint8(x), "tool_digital_output_mask") => masks[2].0 = *x,
                (Value::Uint8(x), "tool_digital_output") => masks[2].1 = *x,
                _ => {}
            }
        }
        let before = self.outputs;
        for (i, (mask, value)) in masks.iter().enumerate() {
            let shift = 8 * i;
            let mask = u64::from(*mask) << shift;
            self.outputs = (self.outputs & !mask) | (u64::from(*value) << shift & mask);
        }
        if self.outputs != before {
            self.record.outputs.push(self.outputs);
        }
        let mode = self.ints[MODE_REGISTER as usize];
        if mode == Mode::Hold as i32 {
            self.record.holds += 1;
        }
        if mode == Mode::Stop as i32 && self.running() && self.qd.iter().any(|v| v.abs() > 0.05) {
            self.record.stops_while_moving += 1;
        }
        if mode == Mode::Servo as i32 {
            let t = TARGET_REGISTER as usize;
            let mut q = [0.0; 6];
            q.copy_from_slice(&self.doubles[t..t + 6]);
            if self.running() && !self.injected {
                self.record.targets.push(q);
                self.servos += 1;
            } else {
                self.record.targets_while_stopped.push(q);
            }
        }
        // Injected once; a re-arm clears `injected`, not the record.
        if !self.record.injected
            && let Some(i) = inject
        {
            let after = match i {
                Injected::ProtectiveStop { after }
                | Injected::DropSocket { after }
                | Injected::Stall { after } => after,
            };
            if self.servos >= after {
                self.injected = true;
                self.record.injected = true;
                if let Injected::ProtectiveStop { .. } = i {
                    self.safety_mode = SafetyMode::ProtectiveStop;
                    self.runtime = RuntimeState::Paused;
                    self.qd = [0.0; 6];
                }
            }
        }
    }

    /// Starts a program sent to the secondary interface.
    fn run(&mut self, script: &str, remote: bool) {
        self.record.scripts.push(script.to_string());
        if !crate::script::documented_form(script) {
            self.record.malformed_scripts += 1;
            return;
        }
        if !remote || !script.contains("servoj(") {
            return;
        }
        self.watchdog = watchdog_of(script).map(|(reg, hz)| (reg, hz, self.ints[reg], self.time));
        if matches!(self.safety_mode, SafetyMode::Normal | SafetyMode::Reduced)
            && self.robot_mode == RobotMode::Running
        {
            self.runtime = RuntimeState::Playing;
        }
    }
}

/// The register and frequency of `rtde_set_watchdog("input_int_register_N",
/// HZ, ...)` in a program.
fn watchdog_of(script: &str) -> Option<(usize, f64)> {
    let rest = script
        .split("rtde_set_watchdog(\"input_int_register_")
        .nth(1)?;
    let (reg, rest) = rest.split_once('"')?;
    let hz = rest.trim_start_matches(',').split(',').next()?.trim();
    let reg: usize = reg.parse().ok().filter(|&r| r < 48)?;
    Some((reg, hz.parse().ok().filter(|h: &f64| *h > 0.0)?))
}

struct Inner {
    config: FakeConfig,
    robot: Mutex<Robot>,
    stop: AtomicBool,
}

impl Inner {
    fn robot(&self) -> MutexGuard<'_, Robot> {
        self.robot.lock().unwrap_or_else(|e| e.into_inner())
    }

    fn stopping(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }
}

/// A running fake controller; dropping it ends its threads.
pub struct FakeController {
    inner: Arc<Inner>,
    rtde: SocketAddr,
    secondary: SocketAddr,
    dashboard: SocketAddr,
    threads: Vec<JoinHandle<()>>,
}

impl std::fmt::Debug for FakeController {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "FakeController({})", self.url())
    }
}

impl FakeController {
    /// Starts the fake on three ports of 127.0.0.1.
    pub fn start(config: FakeConfig) -> std::io::Result<FakeController> {
        let robot = Robot {
            time: 1000.0,
            q: config.start,
            qd: [0.0; 6],
            target: config.start,
            robot_mode: config.robot_mode,
            safety_mode: config.safety_mode,
            runtime: config.runtime,
            ints: [0; 48],
            doubles: [0.0; 48],
            outputs: config.outputs,
            watchdog: None,
            servos: 0,
            injected: false,
            record: Record::default(),
        };
        let inner = Arc::new(Inner {
            config,
            robot: Mutex::new(robot),
            stop: AtomicBool::new(false),
        });
        let listen = || -> std::io::Result<TcpListener> {
            let l = TcpListener::bind("127.0.0.1:0")?;
            l.set_nonblocking(true)?;
            Ok(l)
        };
        let (r, s, d) = (listen()?, listen()?, listen()?);
        let (rtde, secondary, dashboard) = (r.local_addr()?, s.local_addr()?, d.local_addr()?);
        // One thread per listener, one more per connection (a controller
        // serves several clients at once); all end when the fake drops.
        let spawn = |l: TcpListener, serve: fn(&Inner, TcpStream)| {
            let inner = Arc::clone(&inner);
            std::thread::spawn(move || {
                let mut connections = Vec::new();
                while !inner.stopping() {
                    match l.accept() {
                        Ok((stream, _)) => {
                            if stream.set_nonblocking(false).is_ok() {
                                let inner = Arc::clone(&inner);
                                connections.push(std::thread::spawn(move || serve(&inner, stream)));
                            }
                        }
                        Err(_) => std::thread::sleep(Duration::from_millis(1)),
                    }
                }
                for c in connections {
                    let _ = c.join();
                }
            })
        };
        let threads = vec![
            spawn(r, serve_rtde),
            spawn(s, serve_secondary),
            spawn(d, serve_dashboard),
        ];
        Ok(FakeController {
            inner,
            rtde,
            secondary,
            dashboard,
            threads,
        })
    }

    /// `ur10://127.0.0.1:RTDE?secondary=PORT&dashboard=PORT`.
    pub fn url(&self) -> String {
        format!(
            "ur10://127.0.0.1:{}?secondary={}&dashboard={}",
            self.rtde.port(),
            self.secondary.port(),
            self.dashboard.port()
        )
    }

    /// The RTDE interface's address.
    pub fn rtde_addr(&self) -> SocketAddr {
        self.rtde
    }

    /// The dashboard server's address.
    pub fn dashboard_addr(&self) -> SocketAddr {
        self.dashboard
    }

    /// What the fake saw so far.
    pub fn record(&self) -> Record {
        self.inner.robot().record.clone()
    }

    /// Where the arm is, its speed, the safety mode and whether the
    /// program plays.
    pub fn arm(&self) -> (Joints, Joints, SafetyMode, RuntimeState) {
        let r = self.inner.robot();
        (r.q, r.qd, r.safety_mode, r.runtime)
    }
}

impl Drop for FakeController {
    fn drop(&mut self) {
        self.inner.stop.store(true, Ordering::Relaxed);
        for t in self.threads.drain(..) {
            let _ = t.join();
        }
    }
}

/// Writes `bytes`, in small pieces when fragmenting.
fn write(stream: &mut TcpStream, bytes: &[u8], fragment: bool) -> std::io::Result<()> {
    if !fragment {
        return stream.write_all(bytes);
    }
    let mut at = 0;
    let mut n = 1;
    while at < bytes.len() {
        let end = (at + n).min(bytes.len());
        stream.write_all(&bytes[at..end])?;
        stream.flush()?;
        at = end;
        n = n % 7 + 1;
        std::thread::sleep(Duration::from_micros(50));
    }
    Ok(())
}

/// An RTDE connection: the handshake, then the stream once started.
fn serve_rtde(inner: &Inner, mut stream: TcpStream) {
    let config = &inner.config;
    inner.robot().record.connections += 1;
    let _ = stream.set_read_timeout(Some(Duration::from_millis(20)));
    let _ = stream.set_write_timeout(Some(Duration::from_secs(2)));
    let _ = stream.set_nodelay(true);
    let mut framer = Framer::new();
    let mut outputs: Option<(f64, Vec<FieldType>)> = None;
    let mut inputs: Option<(Vec<String>, Vec<FieldType>)> = None;
    // Whether this client has sent inputs: only a client that feeds the
    // program moves the test clock (below).
    let mut fed = false;
    let idle = Instant::now();
    while !inner.stopping() && idle.elapsed() < Duration::from_secs(30) {
        let packet = match next_packet(&mut stream, &mut framer) {
            Ok(Some(p)) => p,
            Ok(None) => continue,
            Err(_) => break,
        };
        let reply = match packet {
            Packet::ProtocolVersionRequest { version } => Packet::ProtocolVersionReply {
                accepted: version == 2,
            },
            Packet::ControllerVersionRequest => Packet::ControllerVersionReply(config.version),
            Packet::SetupOutputsRequest { frequency, names } => {
                let types = names.iter().map(|n| {
                    if config.not_found.contains(n) {
                        None
                    } else {
                        type_of(n)
                    }
                });
                let types: Vec<Option<FieldType>> = types.collect();
                if types.iter().all(Option::is_some) {
                    outputs = Some((frequency, types.iter().flatten().copied().collect()));
                }
                Packet::SetupOutputsReply {
                    recipe: 1,
                    types: types
                        .iter()
                        .map(|t| t.map_or("NOT_FOUND".into(), |t| t.name().to_string()))
                        .collect(),
                }
            }
            Packet::SetupInputsRequest { names } => {
                let types: Vec<String> = names
                    .iter()
                    .map(|n| {
                        if config.in_use.contains(n) {
                            "IN_USE".to_string()
                        } else if config.not_found.contains(n)
                            || !n.starts_with("input_") && !n.contains("digital_output")
                        {
                            "NOT_FOUND".to_string()
                        } else {
                            type_of(n).map_or("NOT_FOUND".into(), |t| t.name().to_string())
                        }
                    })
                    .collect();
                let ok = types.iter().all(|t| FieldType::from_name(t).is_some());
                if ok {
                    let parsed = types
                        .iter()
                        .filter_map(|t| FieldType::from_name(t))
                        .collect();
                    inputs = Some((names, parsed));
                }
                Packet::SetupInputsReply {
                    recipe: if ok { 2 } else { 0 },
                    types,
                }
            }
            Packet::StartRequest => {
                let ok = outputs.is_some();
                if send(&mut stream, &Packet::StartReply { accepted: ok }, config).is_err() {
                    break;
                }
                if let (true, Some(out)) = (ok, &outputs) {
                    match stream_data(
                        inner,
                        &mut stream,
                        &mut framer,
                        out,
                        inputs.as_ref(),
                        &mut fed,
                    ) {
                        Streamed::Paused => {
                            let _ =
                                send(&mut stream, &Packet::PauseReply { accepted: true }, config);
                            continue;
                        }
                        Streamed::Closed => break,
                    }
                }
                continue;
            }
            Packet::PauseRequest => Packet::PauseReply { accepted: true },
            Packet::Text(m) => {
                inner.robot().record.messages.push(m.message);
                continue;
            }
            _ => continue,
        };
        if send(&mut stream, &reply, config).is_err() {
            break;
        }
    }
    // The client that fed the program is gone: the robot's clock goes on
    // for a second, so the watchdog stops a program nobody feeds. A client
    // that only read the state (a second driver refused because a program
    // plays) leaves the clock to the one that feeds it, as on a real
    // controller, whose clock does not wait for any client.
    if fed {
        let dt = 1.0 / config.version.frequency();
        let mut r = inner.robot();
        for _ in 0..(config.version.frequency() as usize) {
            r.tick(dt, config.time_constant);
        }
    }
}

fn send(stream: &mut TcpStream, p: &Packet, config: &FakeConfig) -> std::io::Result<()> {
    let bytes = p
        .encode()
        .map_err(|e| std::io::Error::new(ErrorKind::InvalidData, e.to_string()))?;
    write(stream, &bytes, config.fragment)
}

/// The next packet from the client; `None` when nothing came in the read
/// timeout; an error when the connection closed or sent garbage.
fn next_packet(stream: &mut TcpStream, framer: &mut Framer) -> std::io::Result<Option<Packet>> {
    let bad =
        |e: crate::codec::CodecError| std::io::Error::new(ErrorKind::InvalidData, e.to_string());
    if let Some((kind, payload)) = framer.next_frame().map_err(bad)? {
        return Packet::decode(Direction::ToController, kind, &payload)
            .map(Some)
            .map_err(bad);
    }
    let mut buf = [0u8; 4096];
    match stream.read(&mut buf) {
        Ok(0) => Err(ErrorKind::UnexpectedEof.into()),
        Ok(n) => {
            framer.push(&buf[..n]);
            Ok(None)
        }
        Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => Ok(None),
        Err(e) => Err(e),
    }
}

enum Streamed {
    Paused,
    Closed,
}

/// The data stream: a package per tick of the test clock, the client's
/// inputs applied as they come, faults injected. The clock ticks only once
/// the client has fed inputs (`fed`): a client that only reads the state
/// must not run a clock that another client's program is fed by, or the
/// other program's watchdog would see time pass without its feed.
fn stream_data(
    inner: &Inner,
    stream: &mut TcpStream,
    framer: &mut Framer,
    (_, types): &(f64, Vec<FieldType>),
    inputs: Option<&(Vec<String>, Vec<FieldType>)>,
    fed: &mut bool,
) -> Streamed {
    let config = &inner.config;
    let dt = 1.0 / config.version.frequency();
    let _ = stream.set_read_timeout(Some(Duration::from_micros(200)));
    let mut n: u64 = 0;
    let mut held: Vec<u8> = Vec::new();
    while !inner.stopping() {
        n += 1;
        let (bytes, muted, drop_now) = {
            let mut r = inner.robot();
            if *fed {
                r.tick(dt, config.time_constant);
            }
            let injected = r.injected;
            let muted = injected && matches!(config.inject, Some(Injected::Stall { .. }));
            let drop_now = injected && matches!(config.inject, Some(Injected::DropSocket { .. }));
            let values = r.state(config).to_values();
            let bytes = if types.len() == OUTPUTS.len() {
                encode_values(types, &values).ok()
            } else {
                None
            };
            (bytes, muted, drop_now)
        };
        if drop_now {
            let _ = stream.shutdown(Shutdown::Both);
            return Streamed::Closed;
        }
        if !muted && let Some(payload) = bytes {
            let Ok(p) = (Packet::Data { recipe: 1, payload }).encode() else {
                return Streamed::Closed;
            };
            held.extend(p);
            if config.stray_packets && n.is_multiple_of(50) {
                // A packet of a type v2 does not define, then a text
                // message with a Latin-1 byte (size, `M`, message length
                // and bytes, source length and bytes, level).
                held.extend([0, 5, b'Z', 1, 2]);
                held.extend([0, 11, b'M', 4, b'c', b'a', 0xe9, b'!', 1, b'P', 2]);
            }
            // Every seventh package waits to go with the next one.
            if !(config.fragment && n.is_multiple_of(7)) {
                if write(stream, &held, config.fragment).is_err() {
                    return Streamed::Closed;
                }
                held.clear();
            }
        }
        if !held.is_empty() {
            // A package held back: the next tick goes with it at once.
            continue;
        }
        // Wait for the client's answer (lockstep), at most `pace`; a muted
        // controller only lets a period of wall time pass.
        let wait = if muted {
            Duration::from_secs_f64(dt)
        } else {
            config.pace
        };
        let started = Instant::now();
        loop {
            match next_packet(stream, framer) {
                Ok(Some(Packet::Data { recipe: 2, payload })) => {
                    // A stalled link loses what the client sends too.
                    if !muted
                        && let Some((names, t)) = inputs
                        && let Ok(values) = decode_values(t, &payload)
                    {
                        inner.robot().input(names, &values, config.inject);
                        *fed = true;
                    }
                    if !muted {
                        break;
                    }
                }
                Ok(Some(Packet::PauseRequest)) => return Streamed::Paused,
                Ok(Some(Packet::Text(TextMessage { message, .. }))) => {
                    inner.robot().record.messages.push(message);
                }
                Ok(_) => {}
                Err(_) => return Streamed::Closed,
            }
            if started.elapsed() >= wait {
                break;
            }
        }
    }
    Streamed::Closed
}

/// The secondary interface: a program is the text a client sends.
fn serve_secondary(inner: &Inner, mut stream: TcpStream) {
    let _ = stream.set_read_timeout(Some(Duration::from_millis(200)));
    // A controller's primary interface greets every client with its
    // version message (a package of the primary protocol: size, type 20,
    // the version's fields); 96 bytes here.
    let mut greeting = vec![0u8; PRIMARY_GREETING];
    greeting[..4].copy_from_slice(&(PRIMARY_GREETING as u32).to_be_bytes());
    greeting[4] = 20;
    if stream.write_all(&greeting).is_err() {
        return;
    }
    let mut text = Vec::new();
    let mut buf = [0u8; 4096];
    let started = Instant::now();
    let mut reset = false;
    while started.elapsed() < Duration::from_secs(2) && text.len() < 1 << 20 {
        match stream.read(&mut buf) {
            Ok(0) => break,
            Ok(n) => text.extend_from_slice(&buf[..n]),
            Err(e) => {
                reset = e.kind() == ErrorKind::ConnectionReset;
                break;
            }
        }
    }
    let script = String::from_utf8_lossy(&text).into_owned();
    let mut robot = inner.robot();
    if reset {
        // Closed without reading what the controller sent: the manual's
        // warning is that the program may be discarded. This fake does.
        robot.record.secondary_resets += 1;
        robot.record.scripts.push(script);
        return;
    }
    robot.run(&script, inner.config.remote_control);
}

/// The bytes of the fake's greeting on the secondary interface (a
/// client must read at least 79 before closing).
const PRIMARY_GREETING: usize = 96;

/// The dashboard server.
fn serve_dashboard(inner: &Inner, stream: TcpStream) {
    let _ = stream.set_read_timeout(Some(Duration::from_millis(100)));
    let Ok(mut out) = stream.try_clone() else {
        return;
    };
    if out
        .write_all(b"Connected: Universal Robots Dashboard Server\n")
        .is_err()
    {
        return;
    }
    let mut lines = BufReader::new(stream);
    let mut line = String::new();
    let started = Instant::now();
    while !inner.stopping() && started.elapsed() < Duration::from_secs(30) {
        line.clear();
        match (&mut lines).take(4096).read_line(&mut line) {
            Ok(0) => return,
            Ok(_) => {}
            Err(_) => continue,
        }
        let command = line.trim().to_string();
        let remote = inner.config.remote_control;
        let reply = {
            let mut r = inner.robot();
            r.record.dashboard.push(command.clone());
            let refused = "Command is not allowed due to safety reasons. Ensure the robot is in remote control.";
            match command.as_str() {
                "is in remote control" => remote.to_string(),
                "safetystatus" => format!("Safetystatus: {:?}", r.safety_mode).to_uppercase(),
                "robotmode" => format!("Robotmode: {:?}", r.robot_mode).to_uppercase(),
                _ if !remote => refused.to_string(),
                "unlock protective stop" => {
                    if r.safety_mode == SafetyMode::ProtectiveStop {
                        r.safety_mode = SafetyMode::Normal;
                        r.runtime = RuntimeState::Stopped;
                        r.injected = false;
                        "Protective stop releasing".to_string()
                    } else {
                        "Cannot unlock protective stop: the robot is not in protective stop"
                            .to_string()
                    }
                }
                "close safety popup" => "closing safety popup".to_string(),
                "power on" => {
                    r.robot_mode = RobotMode::Idle;
                    "Powering on".to_string()
                }
                "brake release" => {
                    r.robot_mode = RobotMode::Running;
                    "Brake releasing".to_string()
                }
                "stop" => {
                    r.runtime = RuntimeState::Stopped;
                    "Stopped".to_string()
                }
                other => format!("could not understand: '{other}'"),
            }
        };
        if out.write_all(format!("{reply}\n").as_bytes()).is_err() {
            return;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_watchdog_is_read_from_the_program() {
        let p = crate::script::Program::for_period(0.002).render();
        assert_eq!(
            watchdog_of(&p),
            Some((crate::recipe::SEQUENCE_REGISTER as usize, 20.0))
        );
        assert_eq!(watchdog_of("servoj()"), None);
    }
}
