//! RTDE field names and types, the driver's output and input recipes, the
//! registers it uses, and the robot's state as typed values.
//!
//! Registers: the driver uses input registers from 24 (fieldbus adapters
//! take 0-23): int 24 the sequence number (the controller's watchdog), int
//! 25 the mode, double 24-29 the joint targets. Guarantee: a data package
//! decoded by [`RobotState::from_values`] has every field of
//! [`OUTPUTS`], in order, with its documented type, or is an error.

use crate::codec::{CodecError, FieldType, Value};
use packwright_interface::Joints;

/// The first input register the driver uses (fieldbus adapters use 0-23).
pub const FIRST_REGISTER: u8 = 24;
/// Int register: the sequence number, incremented with every input package
/// (the controller's watchdog watches it).
pub const SEQUENCE_REGISTER: u8 = 24;
/// Int register: what the program does this cycle ([`Mode`]).
pub const MODE_REGISTER: u8 = 25;
/// Double registers 24-29: the joint targets, radians, base first.
pub const TARGET_REGISTER: u8 = 24;

/// What the streaming program does with the registers this cycle.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// `stopj`: decelerate to rest (and hold).
    Stop = 0,
    /// `servoj` to the joint targets.
    Servo = 1,
    /// Leave the loop: the program ends.
    Exit = 2,
    /// `servoj` to the joint targets, which are the last target again:
    /// the planner's next one is late (a cycle the computer missed), or
    /// it thinks between motions. The arm holds its course to the last
    /// target instead of a `stopj` in the middle of a motion; told apart
    /// from [`Mode::Servo`] only so that a log can count them.
    Hold = 3,
}

/// The output fields, in the order of [`RobotState::from_values`].
pub const OUTPUTS: [(&str, FieldType); 11] = [
    ("timestamp", FieldType::Double),
    ("actual_q", FieldType::Vector6d),
    ("actual_qd", FieldType::Vector6d),
    ("target_q", FieldType::Vector6d),
    ("robot_mode", FieldType::Int32),
    ("safety_mode", FieldType::Int32),
    ("runtime_state", FieldType::Uint32),
    ("actual_digital_output_bits", FieldType::Uint64),
    ("actual_digital_input_bits", FieldType::Uint64),
    ("target_speed_fraction", FieldType::Double),
    ("speed_scaling", FieldType::Double),
];

/// A digital output of the controller (the suction valve).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DigitalOutput {
    /// Standard output 0-7.
    Standard(u8),
    /// Configurable output 0-7.
    Configurable(u8),
    /// Tool output 0-1.
    Tool(u8),
}

impl DigitalOutput {
    /// The RTDE mask and value input fields that set it.
    pub fn fields(self) -> (&'static str, &'static str) {
        match self {
            DigitalOutput::Standard(_) => {
                ("standard_digital_output_mask", "standard_digital_output")
            }
            DigitalOutput::Configurable(_) => (
                "configurable_digital_output_mask",
                "configurable_digital_output",
            ),
            DigitalOutput::Tool(_) => ("tool_digital_output_mask", "tool_digital_output"),
        }
    }

    /// Its bit in the mask and value fields.
    pub fn mask(self) -> u8 {
        let (DigitalOutput::Standard(n) | DigitalOutput::Configurable(n) | DigitalOutput::Tool(n)) =
            self;
        1u8 << (n & 7)
    }

    /// Its bit in `actual_digital_output_bits` (standard 0-7, configurable
    /// 8-15, tool 16-17).
    pub fn bit(self) -> u32 {
        match self {
            DigitalOutput::Standard(n) => u32::from(n & 7),
            DigitalOutput::Configurable(n) => 8 + u32::from(n & 7),
            DigitalOutput::Tool(n) => 16 + u32::from(n & 1),
        }
    }
}

/// The input fields of the driver's one input recipe, in the order of
/// [`input_values`].
pub fn input_names(suction: DigitalOutput) -> Vec<String> {
    let mut names = vec![
        format!("input_int_register_{SEQUENCE_REGISTER}"),
        format!("input_int_register_{MODE_REGISTER}"),
    ];
    names.extend((0..6).map(|i| format!("input_double_register_{}", TARGET_REGISTER + i)));
    let (mask, value) = suction.fields();
    names.push(mask.to_string());
    names.push(value.to_string());
    names
}

/// The input recipe's types, in the order of [`input_names`].
pub fn input_types() -> Vec<FieldType> {
    let mut t = vec![FieldType::Int32, FieldType::Int32];
    t.extend([FieldType::Double; 6]);
    t.extend([FieldType::Uint8, FieldType::Uint8]);
    t
}

/// One input package's values: sequence, mode, targets, the suction
/// output's mask and value.
pub fn input_values(
    sequence: i32,
    mode: Mode,
    target: &Joints,
    suction: DigitalOutput,
    on: bool,
) -> Vec<Value> {
    let mut v = vec![Value::Int32(sequence), Value::Int32(mode as i32)];
    v.extend(target.iter().map(|&q| Value::Double(q)));
    v.push(Value::Uint8(suction.mask()));
    v.push(Value::Uint8(if on { suction.mask() } else { 0 }));
    v
}

/// The type the controller gives a field name, for the fields this crate
/// uses (and the registers 0-47): the fake controller's table.
pub fn type_of(name: &str) -> Option<FieldType> {
    if let Some(&(_, t)) = OUTPUTS.iter().find(|(n, _)| *n == name) {
        return Some(t);
    }
    let register = |prefix: &str| {
        name.strip_prefix(prefix)
            .and_then(|n| n.parse::<u8>().ok())
            .is_some_and(|n| n < 48)
    };
    if register("input_int_register_") || register("output_int_register_") {
        return Some(FieldType::Int32);
    }
    if register("input_double_register_") || register("output_double_register_") {
        return Some(FieldType::Double);
    }
    if register("input_bit_register_") || register("output_bit_register_") {
        return Some(FieldType::Bool);
    }
    match name {
        "standard_digital_output_mask"
        | "standard_digital_output"
        | "configurable_digital_output_mask"
        | "configurable_digital_output"
        | "tool_digital_output_mask"
        | "tool_digital_output" => Some(FieldType::Uint8),
        "speed_slider_fraction" => Some(FieldType::Double),
        "actual_TCP_pose" | "target_TCP_pose" | "target_qd" => Some(FieldType::Vector6d),
        "robot_status_bits" | "safety_status_bits" => Some(FieldType::Uint32),
        _ => None,
    }
}

/// `robot_mode`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RobotMode {
    NoController,
    Disconnected,
    ConfirmSafety,
    Booting,
    PowerOff,
    PowerOn,
    Idle,
    Backdrive,
    Running,
    UpdatingFirmware,
    Other(i32),
}

impl RobotMode {
    pub fn from_code(c: i32) -> RobotMode {
        use RobotMode::*;
        match c {
            -1 => NoController,
            0 => Disconnected,
            1 => ConfirmSafety,
            2 => Booting,
            3 => PowerOff,
            4 => PowerOn,
            5 => Idle,
            6 => Backdrive,
            7 => Running,
            8 => UpdatingFirmware,
            c => Other(c),
        }
    }

    pub fn code(self) -> i32 {
        use RobotMode::*;
        match self {
            NoController => -1,
            Disconnected => 0,
            ConfirmSafety => 1,
            Booting => 2,
            PowerOff => 3,
            PowerOn => 4,
            Idle => 5,
            Backdrive => 6,
            Running => 7,
            UpdatingFirmware => 8,
            Other(c) => c,
        }
    }
}

/// `safety_mode`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SafetyMode {
    Normal,
    Reduced,
    ProtectiveStop,
    Recovery,
    SafeguardStop,
    SystemEmergencyStop,
    RobotEmergencyStop,
    Violation,
    Fault,
    ValidateJointId,
    Undefined,
    AutomaticModeSafeguardStop,
    ThreePositionEnablingStop,
    Other(i32),
}

impl SafetyMode {
    pub fn from_code(c: i32) -> SafetyMode {
        use SafetyMode::*;
        match c {
            1 => Normal,
            2 => Reduced,
            3 => ProtectiveStop,
            4 => Recovery,
            5 => SafeguardStop,
            6 => SystemEmergencyStop,
            7 => RobotEmergencyStop,
            8 => Violation,
            9 => Fault,
            10 => ValidateJointId,
            11 => Undefined,
            12 => AutomaticModeSafeguardStop,
            13 => ThreePositionEnablingStop,
            c => Other(c),
        }
    }

    pub fn code(self) -> i32 {
        use SafetyMode::*;
        match self {
            Normal => 1,
            Reduced => 2,
            ProtectiveStop => 3,
            Recovery => 4,
            SafeguardStop => 5,
            SystemEmergencyStop => 6,
            RobotEmergencyStop => 7,
            Violation => 8,
            Fault => 9,
            ValidateJointId => 10,
            Undefined => 11,
            AutomaticModeSafeguardStop => 12,
            ThreePositionEnablingStop => 13,
            Other(c) => c,
        }
    }
}

/// `runtime_state`: the program's state.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RuntimeState {
    Stopping,
    Stopped,
    Playing,
    Pausing,
    Paused,
    Resuming,
    Other(u32),
}

impl RuntimeState {
    pub fn from_code(c: u32) -> RuntimeState {
        use RuntimeState::*;
        match c {
            0 => Stopping,
            1 => Stopped,
            2 => Playing,
            3 => Pausing,
            4 => Paused,
            5 => Resuming,
            c => Other(c),
        }
    }

    pub fn code(self) -> u32 {
        use RuntimeState::*;
        match self {
            Stopping => 0,
            Stopped => 1,
            Playing => 2,
            Pausing => 3,
            Paused => 4,
            Resuming => 5,
            Other(c) => c,
        }
    }
}

/// One data package of the output recipe, typed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RobotState {
    /// Controller time, seconds since it booted.
    pub timestamp: f64,
    pub actual_q: Joints,
    pub actual_qd: Joints,
    pub target_q: Joints,
    pub robot_mode: RobotMode,
    pub safety_mode: SafetyMode,
    pub runtime_state: RuntimeState,
    pub digital_outputs: u64,
    pub digital_inputs: u64,
    /// `target_speed_fraction`: the pendant's speed slider, 0-1.
    pub speed_fraction: f64,
    /// `speed_scaling`: how much the controller's trajectory limiter slows
    /// the motion, 0-1 (Reduced mode's limits, for one).
    pub speed_scaling: f64,
}

impl RobotState {
    /// The fraction of the commanded speed the arm moves at: the slider
    /// times the controller's scaling. packwright streams the speeds it
    /// planned, so below 1 the arm falls behind them.
    pub fn speed(&self) -> f64 {
        self.speed_fraction * self.speed_scaling
    }

    /// The state from values in the order and types of [`OUTPUTS`].
    pub fn from_values(v: &[Value]) -> Result<RobotState, CodecError> {
        let types: Vec<FieldType> = OUTPUTS.iter().map(|(_, t)| *t).collect();
        let wrong = |index: usize| CodecError::ValueType {
            index,
            got: v[index].field_type(),
            expected: types[index],
        };
        if v.len() != OUTPUTS.len() {
            return Err(CodecError::DataLength {
                got: v.len(),
                expected: OUTPUTS.len(),
            });
        }
        let double = |i: usize| match v[i] {
            Value::Double(x) => Ok(x),
            _ => Err(wrong(i)),
        };
        let six = |i: usize| match v[i] {
            Value::Vector6d(x) => Ok(x),
            _ => Err(wrong(i)),
        };
        let int = |i: usize| match v[i] {
            Value::Int32(x) => Ok(x),
            _ => Err(wrong(i)),
        };
        let bits = |i: usize| match v[i] {
            Value::Uint64(x) => Ok(x),
            _ => Err(wrong(i)),
        };
        let runtime = match v[6] {
            Value::Uint32(x) => x,
            _ => return Err(wrong(6)),
        };
        Ok(RobotState {
            timestamp: double(0)?,
            actual_q: six(1)?,
            actual_qd: six(2)?,
            target_q: six(3)?,
            robot_mode: RobotMode::from_code(int(4)?),
            safety_mode: SafetyMode::from_code(int(5)?),
            runtime_state: RuntimeState::from_code(runtime),
            digital_outputs: bits(7)?,
            digital_inputs: bits(8)?,
            speed_fraction: double(9)?,
            speed_scaling: double(10)?,
        })
    }

    /// The values of this state in the order of [`OUTPUTS`] (the fake
    /// controller sends these).
    pub fn to_values(&self) -> Vec<Value> {
        vec![
            Value::Double(self.timestamp),
            Value::Vector6d(self.actual_q),
            Value::Vector6d(self.actual_qd),
            Value::Vector6d(self.target_q),
            Value::Int32(self.robot_mode.code()),
            Value::Int32(self.safety_mode.code()),
            Value::Uint32(self.runtime_state.code()),
            Value::Uint64(self.digital_outputs),
            Value::Uint64(self.digital_inputs),
            Value::Double(self.speed_fraction),
            Value::Double(self.speed_scaling),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::codec::{decode_values, encode_values};

    #[test]
    fn state_round_trips_through_bytes() {
        let s = RobotState {
            timestamp: 12.5,
            actual_q: [0.1, -1.2, 1.3, -1.6, -1.57, 0.0],
            actual_qd: [0.0; 6],
            target_q: [0.1, -1.2, 1.3, -1.6, -1.57, 0.01],
            robot_mode: RobotMode::Running,
            safety_mode: SafetyMode::ProtectiveStop,
            runtime_state: RuntimeState::Playing,
            digital_outputs: 0b100,
            digital_inputs: 1 << 9,
            speed_fraction: 0.3,
            speed_scaling: 1.0,
        };
        let types: Vec<FieldType> = OUTPUTS.iter().map(|(_, t)| *t).collect();
        let bytes = encode_values(&types, &s.to_values()).unwrap();
        let back = RobotState::from_values(&decode_values(&types, &bytes).unwrap()).unwrap();
        assert_eq!(back, s);
    }

    #[test]
    fn input_recipe_uses_registers_from_24() {
        let names = input_names(DigitalOutput::Configurable(2));
        assert_eq!(names[0], "input_int_register_24");
        assert_eq!(names[1], "input_int_register_25");
        assert_eq!(names[2], "input_double_register_24");
        assert_eq!(names[7], "input_double_register_29");
        assert_eq!(names[8], "configurable_digital_output_mask");
        assert_eq!(names.len(), input_types().len());
        let v = input_values(
            7,
            Mode::Servo,
            &[0.0; 6],
            DigitalOutput::Configurable(2),
            true,
        );
        assert_eq!(v[8], Value::Uint8(4));
        assert_eq!(v[9], Value::Uint8(4));
        assert_eq!(DigitalOutput::Configurable(2).bit(), 10);
        for (n, t) in names.iter().zip(input_types()) {
            assert_eq!(type_of(n), Some(t), "{n}");
        }
    }

    #[test]
    fn codes_round_trip() {
        for c in -2..15 {
            assert_eq!(RobotMode::from_code(c).code(), c);
            assert_eq!(SafetyMode::from_code(c).code(), c);
        }
        for c in 0..8 {
            assert_eq!(RuntimeState::from_code(c).code(), c);
        }
        assert_eq!(type_of("input_int_register_48"), None);
        assert_eq!(type_of("no_such_field"), None);
    }
}
