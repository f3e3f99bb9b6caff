//! The driver's safety rules: which robot states allow commanding, the
//! fault latch, and the check of every joint target before it is sent.
//!
//! Guarantees: once a [`Latch`] holds a fault it keeps the first one for
//! good (re-arming is a new connection after the dashboard's explicit
//! unlock); [`CommandCheck::check`] passes a target only when it is finite,
//! within the limits, at most one cycle's travel (the velocity limit times
//! the period, plus 5%) from the previous target, and within the tracking
//! bound of the measured joints.

use crate::recipe::{RobotMode, RobotState, RuntimeState, SafetyMode};
use packwright_interface::world::StopReason;
use packwright_interface::{DOF, Joints, Limits};

/// Why the driver stopped commanding the robot.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Fault {
    /// The safety mode is not normal or reduced.
    Safety(SafetyMode),
    /// The robot mode is not running.
    Robot(RobotMode),
    /// The streaming program is not playing.
    Program(RuntimeState),
    /// The RTDE connection closed or failed.
    ConnectionLost,
    /// No data package for this long (seconds).
    Stalled { waited_s: f64 },
    /// A target failed the check; it was not sent.
    Rejected(CommandProblem),
    /// A target was too far from the measured joints while the
    /// controller moved the arm at `percent` of the speed commanded (the
    /// pendant's speed slider, or Reduced mode's limits): it fell behind
    /// the plan. Not sent.
    FellBehind {
        problem: CommandProblem,
        percent: f64,
    },
}

impl Fault {
    /// The interface's summary of the fault.
    pub fn reason(&self) -> StopReason {
        match self {
            Fault::Safety(SafetyMode::ProtectiveStop) => StopReason::ProtectiveStop,
            Fault::Safety(SafetyMode::SystemEmergencyStop | SafetyMode::RobotEmergencyStop) => {
                StopReason::EmergencyStop
            }
            Fault::Safety(
                SafetyMode::SafeguardStop
                | SafetyMode::AutomaticModeSafeguardStop
                | SafetyMode::ThreePositionEnablingStop,
            ) => StopReason::SafeguardStop,
            Fault::Safety(_) => StopReason::SafetyFault,
            Fault::Robot(_) => StopReason::NotRunning,
            Fault::Program(_) => StopReason::ProgramNotPlaying,
            Fault::ConnectionLost => StopReason::ConnectionLost,
            Fault::Stalled { .. } => StopReason::StalledStream,
            Fault::Rejected(_) | Fault::FellBehind { .. } => StopReason::CommandRejected,
        }
    }

    /// Whether the dashboard's explicit re-arm (`unlock protective stop`,
    /// `close safety popup`) is what it takes to go on.
    pub fn needs_rearm(&self) -> bool {
        matches!(
            self,
            Fault::Safety(SafetyMode::ProtectiveStop | SafetyMode::SafeguardStop)
        )
    }
}

impl std::fmt::Display for Fault {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Fault::Safety(SafetyMode::ProtectiveStop) => write!(
                f,
                "protective stop: the arm stopped; check the cell, then re-arm explicitly (dashboard `unlock protective stop`, or the pendant)"
            ),
            Fault::Safety(m) => write!(f, "safety mode {m:?}: the arm stopped"),
            Fault::Robot(m) => write!(
                f,
                "robot mode {m:?}, not running (power on and release the brakes)"
            ),
            Fault::Program(s) => write!(f, "the streaming program is {s:?}, not playing"),
            Fault::ConnectionLost => write!(f, "the connection to the controller was lost"),
            Fault::Stalled { waited_s } => write!(
                f,
                "no data from the controller for {:.0} ms",
                waited_s * 1000.0
            ),
            Fault::Rejected(p) => write!(f, "command not sent: {p}"),
            Fault::FellBehind { problem, percent } => write!(
                f,
                "command not sent: {problem}: the controller moves the arm at {percent:.0}% of the commanded speed (the pendant's speed slider, or Reduced mode's limits), so it fell behind the plan; set the slider to 100% (a cell's `speed` statement slows the plan itself)"
            ),
        }
    }
}

/// Why a joint target was refused.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CommandProblem {
    NonFinite {
        joint: usize,
    },
    OutsideLimits {
        joint: usize,
        value: f64,
        lower: f64,
        upper: f64,
    },
    /// Further from the previous target than one cycle's travel.
    TooFast {
        joint: usize,
        step: f64,
        max: f64,
    },
    /// Further from the measured joints than the tracking bound.
    FarFromMeasured {
        joint: usize,
        error: f64,
        max: f64,
    },
}

impl std::fmt::Display for CommandProblem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CommandProblem::NonFinite { joint } => write!(f, "joint {joint} is not finite"),
            CommandProblem::OutsideLimits {
                joint,
                value,
                lower,
                upper,
            } => write!(
                f,
                "joint {joint} at {value:.4} rad is outside [{lower:.4}, {upper:.4}]"
            ),
            CommandProblem::TooFast { joint, step, max } => write!(
                f,
                "joint {joint} jumps {step:.4} rad in one cycle (at most {max:.4})"
            ),
            CommandProblem::FarFromMeasured { joint, error, max } => write!(
                f,
                "joint {joint} is {error:.4} rad from where it is measured (at most {max:.4})"
            ),
        }
    }
}

/// Whether the robot's state allows commanding it.
pub fn check_state(s: &RobotState) -> Result<(), Fault> {
    if !matches!(s.safety_mode, SafetyMode::Normal | SafetyMode::Reduced) {
        return Err(Fault::Safety(s.safety_mode));
    }
    if s.robot_mode != RobotMode::Running {
        return Err(Fault::Robot(s.robot_mode));
    }
    if s.runtime_state != RuntimeState::Playing {
        return Err(Fault::Program(s.runtime_state));
    }
    Ok(())
}

/// The first fault, kept.
#[derive(Debug, Clone, Default)]
pub struct Latch {
    fault: Option<Fault>,
}

impl Latch {
    /// Latches `fault` unless one is latched already; returns the latched
    /// fault.
    pub fn trip(&mut self, fault: Fault) -> Fault {
        *self.fault.get_or_insert(fault)
    }

    pub fn fault(&self) -> Option<Fault> {
        self.fault
    }
}

/// The check of every joint target before it is sent.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CommandCheck {
    pub limits: [Limits; DOF],
    /// The control period, seconds.
    pub period: f64,
    /// Largest distance (rad) of a target from the measured joints; the
    /// arm lags a moving target by servoj's lookahead.
    pub tracking: f64,
}

/// Slack on one cycle's travel for rounding and the smoother's sampling.
pub const TRAVEL_SLACK: f64 = 1.05;

impl CommandCheck {
    /// Most travel of joint `j` in one cycle.
    pub fn max_step(&self, j: usize) -> f64 {
        self.limits[j].velocity * self.period * TRAVEL_SLACK + 1e-9
    }

    /// Whether `target` may be sent after `previous` (the last target sent,
    /// or the measured joints when the stream starts) with the arm
    /// measured at `measured`.
    pub fn check(
        &self,
        target: &Joints,
        previous: &Joints,
        measured: &Joints,
    ) -> Result<(), CommandProblem> {
        for j in 0..DOF {
            let v = target[j];
            if !v.is_finite() {
                return Err(CommandProblem::NonFinite { joint: j });
            }
            let l = self.limits[j];
            if !l.contains(v) {
                return Err(CommandProblem::OutsideLimits {
                    joint: j,
                    value: v,
                    lower: l.lower,
                    upper: l.upper,
                });
            }
            let step = (v - previous[j]).abs();
            let max = self.max_step(j);
            if step > max {
                return Err(CommandProblem::TooFast {
                    joint: j,
                    step,
                    max,
                });
            }
            let error = (v - measured[j]).abs();
            if error > self.tracking {
                return Err(CommandProblem::FarFromMeasured {
                    joint: j,
                    error,
                    max: self.tracking,
                });
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check() -> CommandCheck {
        let l = Limits {
            lower: -3.0,
            upper: 3.0,
            velocity: 2.0,
            acceleration: 10.0,
            jerk: 100.0,
        };
        CommandCheck {
            limits: [l; DOF],
            period: 0.002,
            tracking: 0.1,
        }
    }

    fn state() -> RobotState {
        RobotState {
            timestamp: 0.0,
            actual_q: [0.0; 6],
            actual_qd: [0.0; 6],
            target_q: [0.0; 6],
            robot_mode: RobotMode::Running,
            safety_mode: SafetyMode::Normal,
            runtime_state: RuntimeState::Playing,
            digital_outputs: 0,
            digital_inputs: 0,
            speed_fraction: 1.0,
            speed_scaling: 1.0,
        }
    }

    #[test]
    fn states_that_allow_commanding() {
        assert_eq!(check_state(&state()), Ok(()));
        let reduced = RobotState {
            safety_mode: SafetyMode::Reduced,
            ..state()
        };
        assert_eq!(check_state(&reduced), Ok(()));
        let stop = RobotState {
            safety_mode: SafetyMode::ProtectiveStop,
            ..state()
        };
        let f = check_state(&stop).unwrap_err();
        assert_eq!(f.reason(), StopReason::ProtectiveStop);
        assert!(f.needs_rearm());
        let idle = RobotState {
            robot_mode: RobotMode::Idle,
            ..state()
        };
        assert_eq!(check_state(&idle), Err(Fault::Robot(RobotMode::Idle)));
        let paused = RobotState {
            runtime_state: RuntimeState::Paused,
            ..state()
        };
        assert_eq!(
            check_state(&paused).map_err(|f| f.reason()),
            Err(StopReason::ProgramNotPlaying)
        );
        let estop = RobotState {
            safety_mode: SafetyMode::RobotEmergencyStop,
            ..state()
        };
        assert_eq!(
            check_state(&estop).map_err(|f| f.reason()),
            Err(StopReason::EmergencyStop)
        );
    }

    #[test]
    fn the_latch_keeps_the_first_fault() {
        let mut l = Latch::default();
        assert_eq!(l.fault(), None);
        l.trip(Fault::ConnectionLost);
        assert_eq!(
            l.trip(Fault::Stalled { waited_s: 1.0 }),
            Fault::ConnectionLost
        );
        assert_eq!(l.fault(), Some(Fault::ConnectionLost));
    }

    #[test]
    fn targets_are_checked() {
        let c = check();
        let z = [0.0; 6];
        // One cycle at 2 rad/s: 4 mrad.
        let mut ok = z;
        ok[2] = 0.004;
        assert_eq!(c.check(&ok, &z, &z), Ok(()));
        let mut fast = z;
        fast[2] = 0.005;
        assert!(matches!(
            c.check(&fast, &z, &z),
            Err(CommandProblem::TooFast { joint: 2, .. })
        ));
        let mut out = [2.999; 6];
        out[4] = 3.01;
        assert!(matches!(
            c.check(&out, &out, &out),
            Err(CommandProblem::OutsideLimits { joint: 4, .. })
        ));
        let mut nan = z;
        nan[0] = f64::NAN;
        assert_eq!(
            c.check(&nan, &z, &z),
            Err(CommandProblem::NonFinite { joint: 0 })
        );
        // Small step from the previous target, but far from the arm.
        let far = [0.5; 6];
        assert!(matches!(
            c.check(&far, &far, &z),
            Err(CommandProblem::FarFromMeasured { joint: 0, .. })
        ));
    }
}
