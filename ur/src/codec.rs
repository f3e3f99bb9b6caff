//! RTDE packets on the wire: big-endian, each packet a `u16` size (the
//! 3-byte header included), a `u8` type and its payload.
//!
//! Requests and replies share type bytes, so decoding needs the
//! [`Direction`]. Guarantees: [`Packet::encode`] and [`Packet::decode`]
//! round-trip; decoding never panics on any bytes (property-tested) and
//! reports a malformed packet as a [`CodecError`]; the [`Framer`] yields
//! the same packets however the bytes were split or coalesced.

use thiserror::Error;

/// Bytes of the header: `u16` size and `u8` type.
pub const HEADER: usize = 3;

/// The RTDE protocol version this crate speaks.
pub const PROTOCOL_VERSION: u16 = 2;

/// Packet type bytes.
pub mod kind {
    pub const PROTOCOL_VERSION: u8 = b'V';
    pub const CONTROLLER_VERSION: u8 = b'v';
    pub const TEXT_MESSAGE: u8 = b'M';
    pub const DATA: u8 = b'U';
    pub const SETUP_OUTPUTS: u8 = b'O';
    pub const SETUP_INPUTS: u8 = b'I';
    pub const START: u8 = b'S';
    pub const PAUSE: u8 = b'P';
}

/// Who sent a packet.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Direction {
    /// The client (this driver) to the controller.
    ToController,
    /// The controller to the client.
    FromController,
}

/// A malformed packet.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum CodecError {
    #[error("a packet's size {size} is smaller than its 3-byte header")]
    ShortSize { size: u16 },
    #[error("a `{kind}` packet's payload is {len} bytes, expected {expected}")]
    PayloadLength {
        kind: char,
        len: usize,
        expected: String,
    },
    #[error("unknown packet type 0x{0:02x}")]
    UnknownType(u8),
    #[error("a `{kind}` packet's text is not UTF-8")]
    NotUtf8 { kind: char },
    #[error("unknown field type `{0}`")]
    UnknownFieldType(String),
    #[error("a packet of {len} bytes does not fit the u16 size field")]
    TooLong { len: usize },
    #[error("a data package holds {got} bytes, its recipe needs {expected}")]
    DataLength { got: usize, expected: usize },
    #[error("a data package's value {index} is {got}, its recipe says {expected}")]
    ValueType {
        index: usize,
        got: FieldType,
        expected: FieldType,
    },
}

/// The controller's version (`v` reply).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ControllerVersion {
    pub major: u32,
    pub minor: u32,
    pub bugfix: u32,
    pub build: u32,
}

impl ControllerVersion {
    /// CB3 controllers (major < 5) stream at 125 Hz, e-Series at 500 Hz.
    pub fn frequency(&self) -> f64 {
        if self.major < 5 { 125.0 } else { 500.0 }
    }
}

impl std::fmt::Display for ControllerVersion {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{}.{}.{}.{}",
            self.major, self.minor, self.bugfix, self.build
        )
    }
}

/// One RTDE packet (protocol version 2).
#[derive(Debug, Clone, PartialEq)]
pub enum Packet {
    /// `V` request: the protocol version the client wants.
    ProtocolVersionRequest {
        version: u16,
    },
    /// `V` reply.
    ProtocolVersionReply {
        accepted: bool,
    },
    /// `v` request (empty).
    ControllerVersionRequest,
    /// `v` reply.
    ControllerVersionReply(ControllerVersion),
    /// `O` request: the output frequency and the field names.
    SetupOutputsRequest {
        frequency: f64,
        names: Vec<String>,
    },
    /// `O` reply: the recipe id and each field's type name (`NOT_FOUND`
    /// for a field the controller does not know).
    SetupOutputsReply {
        recipe: u8,
        types: Vec<String>,
    },
    /// `I` request: the input field names.
    SetupInputsRequest {
        names: Vec<String>,
    },
    /// `I` reply: the recipe id and each field's type name (`NOT_FOUND`,
    /// `IN_USE` for refused fields); recipe 0 when any is refused.
    SetupInputsReply {
        recipe: u8,
        types: Vec<String>,
    },
    StartRequest,
    StartReply {
        accepted: bool,
    },
    PauseRequest,
    PauseReply {
        accepted: bool,
    },
    /// `U`: a recipe id and its fields' bytes, in recipe order.
    Data {
        recipe: u8,
        payload: Vec<u8>,
    },
    /// `M`: a text message (either direction).
    Text(TextMessage),
}

/// An RTDE text message (`M`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TextMessage {
    pub message: String,
    pub source: String,
    /// 0 exception, 1 error, 2 warning, 3 info.
    pub level: u8,
}

impl Packet {
    /// The packet's type byte.
    pub fn kind(&self) -> u8 {
        match self {
            Packet::ProtocolVersionRequest { .. } | Packet::ProtocolVersionReply { .. } => {
                kind::PROTOCOL_VERSION
            }
            Packet::ControllerVersionRequest | Packet::ControllerVersionReply(_) => {
                kind::CONTROLLER_VERSION
            }
            Packet::SetupOutputsRequest { .. } | Packet::SetupOutputsReply { .. } => {
                kind::SETUP_OUTPUTS
            }
            Packet::SetupInputsRequest { .. } | Packet::SetupInputsReply { .. } => {
                kind::SETUP_INPUTS
            }
            Packet::StartRequest | Packet::StartReply { .. } => kind::START,
            Packet::PauseRequest | Packet::PauseReply { .. } => kind::PAUSE,
            Packet::Data { .. } => kind::DATA,
            Packet::Text(_) => kind::TEXT_MESSAGE,
        }
    }

    /// The packet's bytes, header included. Fails only when the packet is
    /// longer than the `u16` size field allows.
    pub fn encode(&self) -> Result<Vec<u8>, CodecError> {
        let mut p = Vec::new();
        match self {
            Packet::ProtocolVersionRequest { version } => p.extend(version.to_be_bytes()),
            Packet::ProtocolVersionReply { accepted }
            | Packet::StartReply { accepted }
            | Packet::PauseReply { accepted } => p.push(u8::from(*accepted)),
            Packet::ControllerVersionRequest | Packet::StartRequest | Packet::PauseRequest => {}
            Packet::ControllerVersionReply(v) => {
                for x in [v.major, v.minor, v.bugfix, v.build] {
                    p.extend(x.to_be_bytes());
                }
            }
            Packet::SetupOutputsRequest { frequency, names } => {
                p.extend(frequency.to_be_bytes());
                p.extend(names.join(",").bytes());
            }
            Packet::SetupInputsRequest { names } => p.extend(names.join(",").bytes()),
            Packet::SetupOutputsReply { recipe, types }
            | Packet::SetupInputsReply { recipe, types } => {
                p.push(*recipe);
                p.extend(types.join(",").bytes());
            }
            Packet::Data { recipe, payload } => {
                p.push(*recipe);
                p.extend(payload);
            }
            Packet::Text(t) => {
                for s in [&t.message, &t.source] {
                    let bytes = s.as_bytes();
                    let bytes = &bytes[..bytes.len().min(255)];
                    p.push(bytes.len() as u8);
                    p.extend(bytes);
                }
                p.push(t.level);
            }
        }
        let len = p.len() + HEADER;
        let size = u16::try_from(len).map_err(|_| CodecError::TooLong { len })?;
        let mut out = Vec::with_capacity(len);
        out.extend(size.to_be_bytes());
        out.push(self.kind());
        out.extend(p);
        Ok(out)
    }

    /// Decodes one packet's payload of type `kind` sent in `direction`.
    pub fn decode(direction: Direction, kind: u8, payload: &[u8]) -> Result<Packet, CodecError> {
        use Direction::*;
        let k = kind as char;
        let exact = |n: usize| -> Result<(), CodecError> {
            if payload.len() == n {
                Ok(())
            } else {
                Err(CodecError::PayloadLength {
                    kind: k,
                    len: payload.len(),
                    expected: n.to_string(),
                })
            }
        };
        let at_least = |n: usize| -> Result<(), CodecError> {
            if payload.len() >= n {
                Ok(())
            } else {
                Err(CodecError::PayloadLength {
                    kind: k,
                    len: payload.len(),
                    expected: format!("at least {n}"),
                })
            }
        };
        let text = |bytes: &[u8]| -> Result<String, CodecError> {
            String::from_utf8(bytes.to_vec()).map_err(|_| CodecError::NotUtf8 { kind: k })
        };
        let list = |bytes: &[u8]| -> Result<Vec<String>, CodecError> {
            let s = text(bytes)?;
            Ok(if s.is_empty() {
                Vec::new()
            } else {
                s.split(',').map(str::to_string).collect()
            })
        };
        Ok(match (kind, direction) {
            (kind::PROTOCOL_VERSION, ToController) => {
                exact(2)?;
                Packet::ProtocolVersionRequest {
                    version: u16::from_be_bytes([payload[0], payload[1]]),
                }
            }
            (kind::PROTOCOL_VERSION, FromController) => {
                exact(1)?;
                Packet::ProtocolVersionReply {
                    accepted: payload[0] != 0,
                }
            }
            (kind::CONTROLLER_VERSION, ToController) => {
                exact(0)?;
                Packet::ControllerVersionRequest
            }
            (kind::CONTROLLER_VERSION, FromController) => {
                exact(16)?;
                let word = |i: usize| {
                    u32::from_be_bytes([
                        payload[4 * i],
                        payload[4 * i + 1],
                        payload[4 * i + 2],
                        payload[4 * i + 3],
                    ])
                };
                Packet::ControllerVersionReply(ControllerVersion {
                    major: word(0),
                    minor: word(1),
                    bugfix: word(2),
                    build: word(3),
                })
            }
            (kind::SETUP_OUTPUTS, ToController) => {
                at_least(8)?;
                let mut f = [0u8; 8];
                f.copy_from_slice(&payload[..8]);
                Packet::SetupOutputsRequest {
                    frequency: f64::from_be_bytes(f),
                    names: list(&payload[8..])?,
                }
            }
            (kind::SETUP_OUTPUTS, FromController) => {
                at_least(1)?;
                Packet::SetupOutputsReply {
                    recipe: payload[0],
                    types: list(&payload[1..])?,
                }
            }
            (kind::SETUP_INPUTS, ToController) => Packet::SetupInputsRequest {
                names: list(payload)?,
            },
            (kind::SETUP_INPUTS, FromController) => {
                at_least(1)?;
                Packet::SetupInputsReply {
                    recipe: payload[0],
                    types: list(&payload[1..])?,
                }
            }
            (kind::START, ToController) => {
                exact(0)?;
                Packet::StartRequest
            }
            (kind::START, FromController) => {
                exact(1)?;
                Packet::StartReply {
                    accepted: payload[0] != 0,
                }
            }
            (kind::PAUSE, ToController) => {
                exact(0)?;
                Packet::PauseRequest
            }
            (kind::PAUSE, FromController) => {
                exact(1)?;
                Packet::PauseReply {
                    accepted: payload[0] != 0,
                }
            }
            (kind::DATA, _) => {
                at_least(1)?;
                Packet::Data {
                    recipe: payload[0],
                    payload: payload[1..].to_vec(),
                }
            }
            (kind::TEXT_MESSAGE, _) => {
                let mut rest = payload;
                let mut field = || -> Result<String, CodecError> {
                    let (&n, tail) = rest.split_first().ok_or(CodecError::PayloadLength {
                        kind: k,
                        len: payload.len(),
                        expected: "a length byte".into(),
                    })?;
                    let n = n as usize;
                    if tail.len() < n {
                        return Err(CodecError::PayloadLength {
                            kind: k,
                            len: payload.len(),
                            expected: "its declared text length".into(),
                        });
                    }
                    // A log line, for people: a byte that is not UTF-8 (a
                    // Latin-1 name in a program's message) is shown as
                    // U+FFFD rather than ending the stream, as the
                    // reference clients take its bytes.
                    let s = String::from_utf8_lossy(&tail[..n]).into_owned();
                    rest = &tail[n..];
                    Ok(s)
                };
                let message = field()?;
                let source = field()?;
                if rest.len() != 1 {
                    return Err(CodecError::PayloadLength {
                        kind: k,
                        len: payload.len(),
                        expected: "texts and a level byte".into(),
                    });
                }
                Packet::Text(TextMessage {
                    message,
                    source,
                    level: rest[0],
                })
            }
            (other, _) => return Err(CodecError::UnknownType(other)),
        })
    }
}

/// Splits a byte stream into packets, whatever the reads' boundaries: feed
/// it every byte read, take the complete packets out.
#[derive(Debug, Default)]
pub struct Framer {
    buf: Vec<u8>,
}

impl Framer {
    pub fn new() -> Framer {
        Framer::default()
    }

    /// Appends bytes as read from the socket.
    pub fn push(&mut self, bytes: &[u8]) {
        self.buf.extend_from_slice(bytes);
    }

    /// The next complete packet's type and payload, `None` if the buffer
    /// holds less than a whole packet. A size smaller than the header is an
    /// error (the stream cannot be re-synchronised after it).
    pub fn next_frame(&mut self) -> Result<Option<(u8, Vec<u8>)>, CodecError> {
        if self.buf.len() < HEADER {
            return Ok(None);
        }
        let size = u16::from_be_bytes([self.buf[0], self.buf[1]]);
        if (size as usize) < HEADER {
            return Err(CodecError::ShortSize { size });
        }
        let size = size as usize;
        if self.buf.len() < size {
            return Ok(None);
        }
        let kind = self.buf[2];
        let payload = self.buf[HEADER..size].to_vec();
        self.buf.drain(..size);
        Ok(Some((kind, payload)))
    }

    /// Bytes waiting for the rest of their packet.
    pub fn pending(&self) -> usize {
        self.buf.len()
    }

    /// The first of the bytes waiting (at most `n`).
    pub fn head(&self, n: usize) -> &[u8] {
        &self.buf[..n.min(self.buf.len())]
    }
}

/// The type of an RTDE field, as the controller names it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FieldType {
    Bool,
    Uint8,
    Uint32,
    Uint64,
    Int32,
    Double,
    Vector3d,
    Vector6d,
    Vector6Int32,
    Vector6Uint32,
}

impl FieldType {
    /// The controller's name of the type.
    pub fn name(self) -> &'static str {
        match self {
            FieldType::Bool => "BOOL",
            FieldType::Uint8 => "UINT8",
            FieldType::Uint32 => "UINT32",
            FieldType::Uint64 => "UINT64",
            FieldType::Int32 => "INT32",
            FieldType::Double => "DOUBLE",
            FieldType::Vector3d => "VECTOR3D",
            FieldType::Vector6d => "VECTOR6D",
            FieldType::Vector6Int32 => "VECTOR6INT32",
            FieldType::Vector6Uint32 => "VECTOR6UINT32",
        }
    }

    /// The type called `name`, if it is one.
    pub fn from_name(name: &str) -> Option<FieldType> {
        use FieldType::*;
        [
            Bool,
            Uint8,
            Uint32,
            Uint64,
            Int32,
            Double,
            Vector3d,
            Vector6d,
            Vector6Int32,
            Vector6Uint32,
        ]
        .into_iter()
        .find(|t| t.name() == name)
    }

    /// Bytes of a value of this type.
    pub fn size(self) -> usize {
        match self {
            FieldType::Bool | FieldType::Uint8 => 1,
            FieldType::Uint32 | FieldType::Int32 => 4,
            FieldType::Uint64 | FieldType::Double => 8,
            FieldType::Vector3d => 24,
            FieldType::Vector6d => 48,
            FieldType::Vector6Int32 | FieldType::Vector6Uint32 => 24,
        }
    }
}

impl std::fmt::Display for FieldType {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A field's value in a data package.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Value {
    Bool(bool),
    Uint8(u8),
    Uint32(u32),
    Uint64(u64),
    Int32(i32),
    Double(f64),
    Vector3d([f64; 3]),
    Vector6d([f64; 6]),
    Vector6Int32([i32; 6]),
    Vector6Uint32([u32; 6]),
}

impl Value {
    /// The value's type.
    pub fn field_type(&self) -> FieldType {
        match self {
            Value::Bool(_) => FieldType::Bool,
            Value::Uint8(_) => FieldType::Uint8,
            Value::Uint32(_) => FieldType::Uint32,
            Value::Uint64(_) => FieldType::Uint64,
            Value::Int32(_) => FieldType::Int32,
            Value::Double(_) => FieldType::Double,
            Value::Vector3d(_) => FieldType::Vector3d,
            Value::Vector6d(_) => FieldType::Vector6d,
            Value::Vector6Int32(_) => FieldType::Vector6Int32,
            Value::Vector6Uint32(_) => FieldType::Vector6Uint32,
        }
    }

    fn write(&self, out: &mut Vec<u8>) {
        match self {
            Value::Bool(b) => out.push(u8::from(*b)),
            Value::Uint8(v) => out.push(*v),
            Value::Uint32(v) => out.extend(v.to_be_bytes()),
            Value::Uint64(v) => out.extend(v.to_be_bytes()),
            Value::Int32(v) => out.extend(v.to_be_bytes()),
            Value::Double(v) => out.extend(v.to_be_bytes()),
            Value::Vector3d(v) => v.iter().for_each(|x| out.extend(x.to_be_bytes())),
            Value::Vector6d(v) => v.iter().for_each(|x| out.extend(x.to_be_bytes())),
            Value::Vector6Int32(v) => v.iter().for_each(|x| out.extend(x.to_be_bytes())),
            Value::Vector6Uint32(v) => v.iter().for_each(|x| out.extend(x.to_be_bytes())),
        }
    }
}

/// The bytes of `values` checked against `types` (same count, same types).
pub fn encode_values(types: &[FieldType], values: &[Value]) -> Result<Vec<u8>, CodecError> {
    if types.len() != values.len() {
        return Err(CodecError::DataLength {
            got: values.len(),
            expected: types.len(),
        });
    }
    let mut out = Vec::new();
    for (index, (t, v)) in types.iter().zip(values).enumerate() {
        if v.field_type() != *t {
            return Err(CodecError::ValueType {
                index,
                got: v.field_type(),
                expected: *t,
            });
        }
        v.write(&mut out);
    }
    Ok(out)
}

/// The values of a data package's `payload` (recipe id removed) read as
/// `types`; the payload must be exactly as long as the types need.
pub fn decode_values(types: &[FieldType], payload: &[u8]) -> Result<Vec<Value>, CodecError> {
    let expected: usize = types.iter().map(|t| t.size()).sum();
    if payload.len() != expected {
        return Err(CodecError::DataLength {
            got: payload.len(),
            expected,
        });
    }
    let mut at = 0;
    let mut take = |n: usize| {
        let s = &payload[at..at + n];
        at += n;
        s
    };
    // `s` holds at least 8 bytes (the sizes were checked above).
    let f64_at = |s: &[u8]| {
        let mut b = [0u8; 8];
        b.copy_from_slice(&s[..8]);
        f64::from_be_bytes(b)
    };
    let u32_at = |s: &[u8]| u32::from_be_bytes([s[0], s[1], s[2], s[3]]);
    let mut values = Vec::with_capacity(types.len());
    for t in types {
        let s = take(t.size());
        values.push(match t {
            FieldType::Bool => Value::Bool(s[0] != 0),
            FieldType::Uint8 => Value::Uint8(s[0]),
            FieldType::Uint32 => Value::Uint32(u32_at(s)),
            FieldType::Uint64 => {
                let mut b = [0u8; 8];
                b.copy_from_slice(s);
                Value::Uint64(u64::from_be_bytes(b))
            }
            FieldType::Int32 => Value::Int32(u32_at(s) as i32),
            FieldType::Double => Value::Double(f64_at(s)),
            FieldType::Vector3d => Value::Vector3d(std::array::from_fn(|i| f64_at(&s[8 * i..]))),
            FieldType::Vector6d => Value::Vector6d(std::array::from_fn(|i| f64_at(&s[8 * i..]))),
            FieldType::Vector6Int32 => {
                Value::Vector6Int32(std::array::from_fn(|i| u32_at(&s[4 * i..]) as i32))
            }
            FieldType::Vector6Uint32 => {
                Value::Vector6Uint32(std::array::from_fn(|i| u32_at(&s[4 * i..])))
            }
        });
    }
    Ok(values)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn frame(bytes: &[u8], direction: Direction) -> Packet {
        let mut f = Framer::new();
        f.push(bytes);
        let (kind, payload) = f.next_frame().unwrap().unwrap();
        assert_eq!(f.pending(), 0);
        Packet::decode(direction, kind, &payload).unwrap()
    }

    #[test]
    fn protocol_version_request_and_reply_bytes() {
        let request = Packet::ProtocolVersionRequest { version: 2 };
        assert_eq!(request.encode().unwrap(), [0x00, 0x05, 0x56, 0x00, 0x02]);
        assert_eq!(
            frame(&[0x00, 0x05, 0x56, 0x00, 0x02], Direction::ToController),
            request
        );
        let reply = frame(&[0x00, 0x04, 0x56, 0x01], Direction::FromController);
        assert_eq!(reply, Packet::ProtocolVersionReply { accepted: true });
        assert_eq!(reply.encode().unwrap(), [0x00, 0x04, 0x56, 0x01]);
    }

    #[test]
    fn output_setup_at_500_hz_bytes() {
        let request = Packet::SetupOutputsRequest {
            frequency: 500.0,
            names: vec!["timestamp".into(), "actual_q".into()],
        };
        let bytes = request.encode().unwrap();
        assert_eq!(
            &bytes[..11],
            [
                0x00, 0x1d, 0x4f, 0x40, 0x7f, 0x40, 0x00, 0x00, 0x00, 0x00, 0x00
            ]
        );
        assert_eq!(&bytes[11..], b"timestamp,actual_q");
        assert_eq!(frame(&bytes, Direction::ToController), request);
    }

    #[test]
    fn controller_version_reply_and_frequency() {
        let mut bytes = vec![0x00, 0x13, b'v'];
        for x in [5u32, 11, 2, 1234] {
            bytes.extend(x.to_be_bytes());
        }
        let Packet::ControllerVersionReply(v) = frame(&bytes, Direction::FromController) else {
            panic!("not a version reply");
        };
        assert_eq!((v.major, v.minor, v.bugfix, v.build), (5, 11, 2, 1234));
        assert_eq!(v.frequency(), 500.0);
        assert_eq!(ControllerVersion { major: 3, ..v }.frequency(), 125.0);
    }

    #[test]
    fn setup_replies_with_refused_fields() {
        let mut bytes = vec![0x00, 0x00, b'I', 0];
        bytes.extend(b"INT32,IN_USE,NOT_FOUND");
        let n = bytes.len() as u16;
        bytes[..2].copy_from_slice(&n.to_be_bytes());
        assert_eq!(
            frame(&bytes, Direction::FromController),
            Packet::SetupInputsReply {
                recipe: 0,
                types: vec!["INT32".into(), "IN_USE".into(), "NOT_FOUND".into()],
            }
        );
    }

    #[test]
    fn text_message_round_trip_and_bytes() {
        let m = Packet::Text(TextMessage {
            message: "hi".into(),
            source: "RTDE".into(),
            level: 2,
        });
        let bytes = m.encode().unwrap();
        assert_eq!(
            bytes,
            [0, 12, b'M', 2, b'h', b'i', 4, b'R', b'T', b'D', b'E', 2]
        );
        assert_eq!(frame(&bytes, Direction::FromController), m);
        assert!(Packet::decode(Direction::FromController, b'M', &[5, b'a']).is_err());
    }

    #[test]
    fn start_pause_and_data() {
        assert_eq!(Packet::StartRequest.encode().unwrap(), [0, 3, b'S']);
        assert_eq!(
            frame(&[0, 4, b'P', 1], Direction::FromController),
            Packet::PauseReply { accepted: true }
        );
        assert!(Packet::decode(Direction::FromController, b'S', &[]).is_err());
        assert!(matches!(
            Packet::decode(Direction::FromController, b'X', &[]),
            Err(CodecError::UnknownType(b'X'))
        ));
    }

    #[test]
    fn values_round_trip_and_are_checked() {
        let types = [
            FieldType::Vector6d,
            FieldType::Int32,
            FieldType::Uint32,
            FieldType::Uint64,
            FieldType::Double,
            FieldType::Uint8,
            FieldType::Bool,
        ];
        let values = [
            Value::Vector6d([1.0, -2.0, 3.5, 0.0, 1e-9, -7.25]),
            Value::Int32(-3),
            Value::Uint32(7),
            Value::Uint64(1 << 40),
            Value::Double(0.125),
            Value::Uint8(9),
            Value::Bool(true),
        ];
        let bytes = encode_values(&types, &values).unwrap();
        assert_eq!(bytes.len(), 48 + 4 + 4 + 8 + 8 + 1 + 1);
        assert_eq!(&bytes[48..52], [0xff, 0xff, 0xff, 0xfd]);
        assert_eq!(decode_values(&types, &bytes).unwrap(), values);
        assert!(decode_values(&types, &bytes[1..]).is_err());
        assert!(encode_values(&types[..2], &values[1..3]).is_err());
    }

    #[test]
    fn framer_rejects_a_size_below_the_header() {
        let mut f = Framer::new();
        f.push(&[0, 2, b'U']);
        assert_eq!(f.next_frame(), Err(CodecError::ShortSize { size: 2 }));
    }

    fn any_packet() -> impl Strategy<Value = Packet> {
        let name = "[a-z_0-9]{1,12}";
        prop_oneof![
            any::<u16>().prop_map(|version| Packet::ProtocolVersionRequest { version }),
            any::<bool>().prop_map(|accepted| Packet::StartReply { accepted }),
            (any::<f64>(), prop::collection::vec(name, 1..5))
                .prop_map(|(frequency, names)| Packet::SetupOutputsRequest { frequency, names }),
            (any::<u8>(), prop::collection::vec(name, 1..5))
                .prop_map(|(recipe, types)| Packet::SetupInputsReply { recipe, types }),
            (any::<u8>(), prop::collection::vec(any::<u8>(), 0..100))
                .prop_map(|(recipe, payload)| Packet::Data { recipe, payload }),
            ("[ -~]{0,40}", "[A-Z]{0,8}", 0u8..4).prop_map(|(message, source, level)| {
                Packet::Text(TextMessage {
                    message,
                    source,
                    level,
                })
            }),
        ]
    }

    fn direction_of(p: &Packet) -> Direction {
        match p {
            Packet::ProtocolVersionRequest { .. } | Packet::SetupOutputsRequest { .. } => {
                Direction::ToController
            }
            _ => Direction::FromController,
        }
    }

    proptest! {
        /// Arbitrary bytes through the framer and the decoder, either
        /// direction: errors, never a panic.
        #[test]
        fn decoding_never_panics(bytes in prop::collection::vec(any::<u8>(), 0..300)) {
            let mut f = Framer::new();
            f.push(&bytes);
            while let Ok(Some((kind, payload))) = f.next_frame() {
                let _ = Packet::decode(Direction::ToController, kind, &payload);
                let _ = Packet::decode(Direction::FromController, kind, &payload);
            }
            for kind in [b'V', b'v', b'O', b'I', b'S', b'P', b'U', b'M'] {
                let _ = Packet::decode(Direction::ToController, kind, &bytes);
                let _ = Packet::decode(Direction::FromController, kind, &bytes);
            }
            let types = [FieldType::Vector6d, FieldType::Int32, FieldType::Uint64];
            let _ = decode_values(&types, &bytes);
        }

        /// Packets split anywhere and coalesced come out whole and in order.
        #[test]
        fn framer_copes_with_split_and_coalesced_reads(
            packets in prop::collection::vec(any_packet(), 1..8),
            cuts in prop::collection::vec(1usize..17, 1..40),
        ) {
            let stream: Vec<u8> = packets.iter().flat_map(|p| p.encode().unwrap()).collect();
            let mut f = Framer::new();
            let mut out = Vec::new();
            let mut at = 0;
            let mut i = 0;
            while at < stream.len() {
                let n = cuts[i % cuts.len()].min(stream.len() - at);
                f.push(&stream[at..at + n]);
                at += n;
                i += 1;
                while let Some((kind, payload)) = f.next_frame().unwrap() {
                    out.push((kind, payload));
                }
            }
            prop_assert_eq!(out.len(), packets.len());
            for ((kind, payload), p) in out.iter().zip(&packets) {
                let back = Packet::decode(direction_of(p), *kind, payload).unwrap();
                // NaN frequencies compare unequal; compare their bytes.
                prop_assert_eq!(back.encode().unwrap(), p.encode().unwrap());
            }
        }
    }
}
