//! An RTDE client over `std::net`: the handshake (protocol version 2, the
//! controller's version, the output and input recipes), start and pause,
//! reading data packages and sending input packages.
//!
//! Guarantees: every socket operation has a timeout; a recipe field the
//! controller refuses is a [`UrError::FieldNotFound`] or
//! [`UrError::FieldInUse`] naming it; [`Client::receive`] returns the newest
//! of the data packages that have arrived (older ones are dropped); text
//! messages are kept for the caller, never interpreted.

use crate::codec::{
    CodecError, ControllerVersion, Direction, FieldType, Framer, PROTOCOL_VERSION, Packet,
    TextMessage, Value, decode_values, encode_values,
};
use crate::error::{Service, UrError};
use crate::recipe::{OUTPUTS, RobotState};
use std::io::{ErrorKind, Read, Write};
use std::net::{SocketAddr, TcpStream, ToSocketAddrs};
use std::time::{Duration, Instant};

/// How long the handshake waits for each reply.
pub const REPLY_TIMEOUT: Duration = Duration::from_secs(2);

/// A recipe the controller accepted.
#[derive(Debug, Clone, PartialEq)]
pub struct Recipe {
    pub id: u8,
    pub names: Vec<String>,
    pub types: Vec<FieldType>,
}

/// A connected RTDE client.
#[derive(Debug)]
pub struct Client {
    stream: TcpStream,
    framer: Framer,
    controller: ControllerVersion,
    output: Option<Recipe>,
    input: Option<Recipe>,
    messages: Vec<TextMessage>,
}

/// Resolves `address` (`host:port`) to its first socket address.
pub fn resolve(address: &str) -> Result<SocketAddr, UrError> {
    address
        .to_socket_addrs()
        .map_err(|e| UrError::BadAddress {
            address: address.into(),
            reason: e.to_string(),
        })?
        .next()
        .ok_or_else(|| UrError::BadAddress {
            address: address.into(),
            reason: "it resolves to no address".into(),
        })
}

/// A TCP connection to `address` with a connect timeout and `timeout` on
/// reads and writes; `TCP_NODELAY` set.
pub fn connect(address: &str, service: Service, timeout: Duration) -> Result<TcpStream, UrError> {
    let addr = resolve(address)?;
    let stream =
        TcpStream::connect_timeout(&addr, timeout).map_err(|source| UrError::Unreachable {
            service,
            address: address.into(),
            cause: source,
        })?;
    let io = |source| UrError::Io {
        service,
        cause: source,
    };
    stream.set_read_timeout(Some(timeout)).map_err(io)?;
    stream.set_write_timeout(Some(timeout)).map_err(io)?;
    stream.set_nodelay(true).map_err(io)?;
    Ok(stream)
}

fn io(source: std::io::Error) -> UrError {
    UrError::Io {
        service: Service::Rtde,
        cause: source,
    }
}

impl Client {
    /// Connects to the RTDE interface at `address` (`host:30004`),
    /// negotiates protocol version 2 and reads the controller's version.
    pub fn connect(address: &str) -> Result<Client, UrError> {
        let stream = connect(address, Service::Rtde, REPLY_TIMEOUT)?;
        let mut client = Client {
            stream,
            framer: Framer::new(),
            controller: ControllerVersion {
                major: 0,
                minor: 0,
                bugfix: 0,
                build: 0,
            },
            output: None,
            input: None,
            messages: Vec::new(),
        };
        match client.request(&Packet::ProtocolVersionRequest {
            version: PROTOCOL_VERSION,
        })? {
            Packet::ProtocolVersionReply { accepted: true } => {}
            _ => {
                return Err(UrError::ProtocolRefused {
                    version: PROTOCOL_VERSION,
                });
            }
        }
        if let Packet::ControllerVersionReply(v) =
            client.request(&Packet::ControllerVersionRequest)?
        {
            client.controller = v;
        }
        Ok(client)
    }

    /// The controller's version.
    pub fn controller(&self) -> ControllerVersion {
        self.controller
    }

    /// Text messages the controller sent so far (taken).
    pub fn take_messages(&mut self) -> Vec<TextMessage> {
        std::mem::take(&mut self.messages)
    }

    /// Sends `packet` and waits for the reply of the same type; text
    /// messages on the way are kept, data packages dropped.
    fn request(&mut self, packet: &Packet) -> Result<Packet, UrError> {
        self.send_packet(packet)?;
        let deadline = Instant::now() + REPLY_TIMEOUT;
        loop {
            let reply = self.read_packet(deadline, "a handshake reply")?;
            match reply {
                Packet::Text(m) => self.messages.push(m),
                Packet::Data { .. } => {}
                p if p.kind() == packet.kind() => return Ok(p),
                p => {
                    return Err(UrError::UnexpectedReply {
                        expected: packet.kind() as char,
                        got: p.kind() as char,
                    });
                }
            }
        }
    }

    fn send_packet(&mut self, packet: &Packet) -> Result<(), UrError> {
        let bytes = packet.encode()?;
        self.stream.write_all(&bytes).map_err(io)
    }

    /// Reads until one whole packet is framed or `deadline` passes.
    fn read_packet(
        &mut self,
        deadline: Instant,
        expected: &'static str,
    ) -> Result<Packet, UrError> {
        let started = Instant::now();
        loop {
            if let Some((kind, payload)) = self.framer.next_frame()? {
                match decode_known(kind, &payload)? {
                    Some(packet) => return Ok(packet),
                    None => continue,
                }
            }
            let now = Instant::now();
            if now >= deadline {
                let waited = now - started;
                // Something came, never a whole packet: not silence.
                let pending = self.framer.pending();
                if pending > 0 {
                    return Err(UrError::NotRtde {
                        service: Service::Rtde,
                        waited,
                        pending,
                        begins: self
                            .framer
                            .head(8)
                            .iter()
                            .map(|b| format!("{b:02x}"))
                            .collect::<Vec<_>>()
                            .join(" "),
                    });
                }
                return Err(UrError::Timeout {
                    service: Service::Rtde,
                    waited,
                    expected,
                });
            }
            self.fill(deadline - now)?;
        }
    }

    /// One read of at most `wait`; a timeout reads nothing.
    fn fill(&mut self, wait: Duration) -> Result<usize, UrError> {
        self.stream
            .set_read_timeout(Some(wait.max(Duration::from_micros(100))))
            .map_err(io)?;
        let mut buf = [0u8; 4096];
        match self.stream.read(&mut buf) {
            Ok(0) => Err(io(std::io::Error::new(
                ErrorKind::UnexpectedEof,
                "the controller closed the connection",
            ))),
            Ok(n) => {
                self.framer.push(&buf[..n]);
                Ok(n)
            }
            Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => Ok(0),
            Err(e) => Err(io(e)),
        }
    }

    /// Sets up the output recipe of `names` at `frequency` Hz; every field
    /// must be known and of the type `expected` gives (when it gives one).
    pub fn setup_outputs(
        &mut self,
        frequency: f64,
        names: &[String],
        expected: &[FieldType],
    ) -> Result<Recipe, UrError> {
        let reply = self.request(&Packet::SetupOutputsRequest {
            frequency,
            names: names.to_vec(),
        })?;
        let Packet::SetupOutputsReply { recipe, types } = reply else {
            return Err(UrError::UnexpectedReply {
                expected: 'O',
                got: reply.kind() as char,
            });
        };
        let recipe = accept(recipe, names, &types, expected)?;
        self.output = Some(recipe.clone());
        Ok(recipe)
    }

    /// Sets up an input recipe of `names` (checked as [`setup_outputs`]).
    ///
    /// [`setup_outputs`]: Client::setup_outputs
    pub fn setup_inputs(
        &mut self,
        names: &[String],
        expected: &[FieldType],
    ) -> Result<Recipe, UrError> {
        let reply = self.request(&Packet::SetupInputsRequest {
            names: names.to_vec(),
        })?;
        let Packet::SetupInputsReply { recipe, types } = reply else {
            return Err(UrError::UnexpectedReply {
                expected: 'I',
                got: reply.kind() as char,
            });
        };
        let recipe = accept(recipe, names, &types, expected)?;
        self.input = Some(recipe.clone());
        Ok(recipe)
    }

    /// The driver's output recipe ([`OUTPUTS`]) at `frequency`.
    pub fn setup_state(&mut self, frequency: f64) -> Result<Recipe, UrError> {
        let names: Vec<String> = OUTPUTS.iter().map(|(n, _)| n.to_string()).collect();
        let types: Vec<FieldType> = OUTPUTS.iter().map(|(_, t)| *t).collect();
        self.setup_outputs(frequency, &names, &types)
    }

    /// Starts the data stream.
    pub fn start(&mut self) -> Result<(), UrError> {
        match self.request(&Packet::StartRequest)? {
            Packet::StartReply { accepted: true } => Ok(()),
            _ => Err(UrError::Refused { what: "start" }),
        }
    }

    /// Pauses the data stream.
    pub fn pause(&mut self) -> Result<(), UrError> {
        match self.request(&Packet::PauseRequest)? {
            Packet::PauseReply { accepted: true } => Ok(()),
            _ => Err(UrError::Refused { what: "pause" }),
        }
    }

    /// The newest data package of the output recipe, waiting at most
    /// `timeout` for one; packages already queued behind it are read and
    /// dropped.
    pub fn receive(&mut self, timeout: Duration) -> Result<Vec<Value>, UrError> {
        let Some(output) = self.output.clone() else {
            return Err(UrError::Refused {
                what: "stream without an output recipe",
            });
        };
        let started = Instant::now();
        let deadline = started + timeout;
        let mut newest: Option<Vec<u8>> = None;
        loop {
            while let Some((kind, payload)) = self.framer.next_frame()? {
                match decode_known(kind, &payload)? {
                    Some(Packet::Data { recipe, payload }) if recipe == output.id => {
                        newest = Some(payload)
                    }
                    Some(Packet::Text(m)) => self.messages.push(m),
                    _ => {}
                }
            }
            if let Some(payload) = newest.take() {
                // Drain what has already arrived, without waiting. A closed
                // or failed socket is reported by the next call: the
                // package in hand is still the newest state.
                // (A partial packet with nothing more waiting is left for
                // the next call.)
                let more = self.readable().unwrap_or(false);
                if !more || self.fill(Duration::from_micros(100)).is_err() {
                    return Ok(decode_values(&output.types, &payload)?);
                }
                newest = Some(payload);
                continue;
            }
            let now = Instant::now();
            if now >= deadline {
                return Err(UrError::Timeout {
                    service: Service::Rtde,
                    waited: now - started,
                    expected: "a data package",
                });
            }
            self.fill(deadline - now)?;
        }
    }

    /// Whether bytes are waiting on the socket.
    fn readable(&mut self) -> Result<bool, UrError> {
        self.stream.set_nonblocking(true).map_err(io)?;
        let mut b = [0u8; 1];
        let r = self.stream.peek(&mut b);
        self.stream.set_nonblocking(false).map_err(io)?;
        match r {
            Ok(0) => Err(io(std::io::Error::new(
                ErrorKind::UnexpectedEof,
                "the controller closed the connection",
            ))),
            Ok(_) => Ok(true),
            Err(e) if e.kind() == ErrorKind::WouldBlock => Ok(false),
            Err(e) => Err(io(e)),
        }
    }

    /// The newest robot state ([`RobotState`] of [`OUTPUTS`]).
    pub fn receive_state(&mut self, timeout: Duration) -> Result<RobotState, UrError> {
        Ok(RobotState::from_values(&self.receive(timeout)?)?)
    }

    /// Sends one input package of the input recipe.
    pub fn send(&mut self, values: &[Value]) -> Result<(), UrError> {
        let Some(input) = &self.input else {
            return Err(UrError::Refused {
                what: "send without an input recipe",
            });
        };
        let payload = encode_values(&input.types, values)?;
        let packet = Packet::Data {
            recipe: input.id,
            payload,
        };
        self.send_packet(&packet)
    }

    /// Sends a text message to the controller's log.
    pub fn log(&mut self, message: &str) -> Result<(), UrError> {
        self.send_packet(&Packet::Text(TextMessage {
            message: message.into(),
            source: "packwright".into(),
            level: 3,
        }))
    }
}

/// A packet from the controller, `None` for a type this protocol version
/// does not define: skipped, as the reference clients skip it (a newer
/// controller's addition is no reason to stop the arm). A known type that
/// does not decode is an error: the stream cannot be trusted.
fn decode_known(kind: u8, payload: &[u8]) -> Result<Option<Packet>, UrError> {
    match Packet::decode(Direction::FromController, kind, payload) {
        Ok(packet) => Ok(Some(packet)),
        Err(CodecError::UnknownType(_)) => Ok(None),
        Err(e) => Err(e.into()),
    }
}

/// The recipe of a setup reply, or the first refused or mistyped field.
fn accept(
    id: u8,
    names: &[String],
    types: &[String],
    expected: &[FieldType],
) -> Result<Recipe, UrError> {
    let mut parsed = Vec::with_capacity(types.len());
    for (i, t) in types.iter().enumerate() {
        let field = names.get(i).cloned().unwrap_or_else(|| format!("#{i}"));
        match t.as_str() {
            "NOT_FOUND" => return Err(UrError::FieldNotFound { field }),
            "IN_USE" => return Err(UrError::FieldInUse { field }),
            _ => {}
        }
        let Some(ft) = FieldType::from_name(t) else {
            return Err(UrError::UnexpectedType {
                field,
                got: t.clone(),
                expected: expected
                    .get(i)
                    .map_or("a known type".into(), |e| e.to_string()),
            });
        };
        if let Some(&e) = expected.get(i)
            && e != ft
        {
            return Err(UrError::UnexpectedType {
                field,
                got: t.clone(),
                expected: e.to_string(),
            });
        }
        parsed.push(ft);
    }
    if parsed.len() != names.len() {
        return Err(UrError::UnexpectedType {
            field: format!("{} fields", names.len()),
            got: format!("{} types", parsed.len()),
            expected: format!("{} types", names.len()),
        });
    }
    if id == 0 {
        return Err(UrError::Refused {
            what: "accept the recipe of",
        });
    }
    Ok(Recipe {
        id,
        names: names.to_vec(),
        types: parsed,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recipe::{RobotMode, RuntimeState, SafetyMode};
    use std::net::TcpListener;

    fn state_at(timestamp: f64) -> RobotState {
        RobotState {
            timestamp,
            actual_q: [0.0; 6],
            actual_qd: [0.0; 6],
            target_q: [0.0; 6],
            robot_mode: RobotMode::Running,
            safety_mode: SafetyMode::Normal,
            runtime_state: RuntimeState::Stopped,
            digital_outputs: 0,
            digital_inputs: 0,
            speed_fraction: 1.0,
            speed_scaling: 1.0,
        }
    }

    fn package(t: f64) -> Vec<u8> {
        let types: Vec<FieldType> = OUTPUTS.iter().map(|(_, t)| *t).collect();
        let payload = encode_values(&types, &state_at(t).to_values()).unwrap();
        Packet::Data { recipe: 1, payload }.encode().unwrap()
    }

    /// A controller that answers the handshake, writes `after_start` in
    /// one write with the start reply, keeps the connection open for
    /// `hold`, then closes it. Returns its address.
    fn controller(after_start: Vec<u8>, hold: Duration) -> (String, std::thread::JoinHandle<()>) {
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        let address = listener.local_addr().unwrap().to_string();
        let server = std::thread::spawn(move || {
            let (mut s, _) = listener.accept().unwrap();
            s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
            let mut framer = Framer::new();
            let mut buf = [0u8; 1024];
            loop {
                let Some((kind, payload)) = framer.next_frame().unwrap() else {
                    let n = s.read(&mut buf).unwrap();
                    assert!(n > 0, "the client hung up");
                    framer.push(&buf[..n]);
                    continue;
                };
                let reply = match Packet::decode(Direction::ToController, kind, &payload).unwrap() {
                    Packet::ProtocolVersionRequest { .. } => {
                        Packet::ProtocolVersionReply { accepted: true }
                    }
                    Packet::ControllerVersionRequest => {
                        Packet::ControllerVersionReply(ControllerVersion {
                            major: 5,
                            minor: 9,
                            bugfix: 0,
                            build: 0,
                        })
                    }
                    Packet::SetupOutputsRequest { names, .. } => Packet::SetupOutputsReply {
                        recipe: 1,
                        types: names
                            .iter()
                            .map(|n| crate::recipe::type_of(n).unwrap().name().to_string())
                            .collect(),
                    },
                    Packet::StartRequest => {
                        let mut bytes = Packet::StartReply { accepted: true }.encode().unwrap();
                        bytes.extend(&after_start);
                        s.write_all(&bytes).unwrap();
                        std::thread::sleep(hold);
                        return;
                    }
                    other => panic!("unexpected {other:?}"),
                };
                s.write_all(&reply.encode().unwrap()).unwrap();
            }
        });
        (address, server)
    }

    fn started(address: &str) -> Client {
        let mut client = Client::connect(address).unwrap();
        assert_eq!(client.controller().minor, 9);
        client.setup_state(500.0).unwrap();
        client.start().unwrap();
        client
    }

    /// Three packages queued (and the connection closed behind them): the
    /// newest is taken, then the close is reported.
    /// Another service on the port (a web server's reply to the
    /// handshake): said to be no RTDE, not "sent nothing" (helper W).
    #[test]
    fn a_port_that_answers_no_rtde_is_told_apart_from_silence() {
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        let address = listener.local_addr().unwrap().to_string();
        let server = std::thread::spawn(move || {
            let (mut s, _) = listener.accept().unwrap();
            let mut buf = [0u8; 64];
            let _ = s.read(&mut buf);
            s.write_all(b"HTTP/1.1 400 Bad Request\r\n\r\n").unwrap();
            std::thread::sleep(REPLY_TIMEOUT + Duration::from_millis(500));
        });
        let Err(e) = Client::connect(&address) else {
            panic!("no RTDE there")
        };
        assert!(
            matches!(&e, UrError::NotRtde { pending: 28, begins, .. } if begins.starts_with("48 54 54 50")),
            "{e}"
        );
        server.join().unwrap();
    }

    #[test]
    fn the_newest_of_queued_packages_is_taken() {
        let bytes = [package(1.0), package(2.0), package(3.0)].concat();
        let (address, server) = controller(bytes, Duration::ZERO);
        let mut client = started(&address);
        server.join().unwrap();
        let state = client.receive_state(Duration::from_secs(2)).unwrap();
        assert_eq!(state.timestamp, 3.0);
        assert!(matches!(
            client.receive_state(Duration::from_secs(2)),
            Err(UrError::Io { .. })
        ));
    }

    /// A package and half of the next, then silence: the whole one comes
    /// at once, and the next call times out on the half.
    #[test]
    fn a_partial_package_waits_within_the_deadline() {
        let next = package(2.0);
        let bytes = [package(1.0), next[..20].to_vec()].concat();
        let (address, server) = controller(bytes, Duration::from_millis(600));
        let mut client = started(&address);
        let t = Instant::now();
        let state = client.receive_state(Duration::from_secs(2)).unwrap();
        assert_eq!(state.timestamp, 1.0);
        assert!(matches!(
            client.receive_state(Duration::from_millis(100)),
            Err(UrError::Timeout { .. })
        ));
        assert!(t.elapsed() < Duration::from_millis(500));
        server.join().unwrap();
    }

    #[test]
    fn refused_fields_are_named() {
        let names = vec!["a".to_string(), "b".to_string()];
        let e = accept(0, &names, &["INT32".into(), "IN_USE".into()], &[]).unwrap_err();
        assert!(
            matches!(e, UrError::FieldInUse { ref field } if field == "b"),
            "{e}"
        );
        let e = accept(1, &names, &["NOT_FOUND".into(), "INT32".into()], &[]).unwrap_err();
        assert!(matches!(e, UrError::FieldNotFound { ref field } if field == "a"));
        let e = accept(
            1,
            &names,
            &["INT32".into(), "DOUBLE".into()],
            &[FieldType::Int32, FieldType::Int32],
        )
        .unwrap_err();
        assert!(matches!(e, UrError::UnexpectedType { .. }));
        let r = accept(3, &names, &["INT32".into(), "DOUBLE".into()], &[]).unwrap();
        assert_eq!(r.types, [FieldType::Int32, FieldType::Double]);
        assert!(accept(1, &names, &["INT32".into()], &[]).is_err());
    }
}
