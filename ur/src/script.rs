//! The URScript program the driver sends over the secondary interface: it
//! arms the RTDE watchdog on the sequence register and, every cycle,
//! `servoj`s to the joint targets in the double registers while the mode
//! register says servo or hold, else `stopj`s; mode exit ends it.
//!
//! Guarantees: the text depends only on [`Program`]'s fields and the
//! register constants of [`crate::recipe`] (a golden file pins it); it
//! has the form the URScript manual ("Connecting to URControl") gives a
//! program sent to the controller: one `def` in the first column, every
//! other line indented, `end` last (the controller runs it as sent; no
//! call of it follows, as the reference clients send none).

use crate::recipe::{MODE_REGISTER, Mode, SEQUENCE_REGISTER, TARGET_REGISTER};

/// The program's parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Program {
    /// The control period, seconds (servoj's blocking time).
    pub period: f64,
    /// The watchdog's minimum frequency of sequence changes, Hz: below it
    /// the controller stops the program and the arm.
    pub watchdog_hz: f64,
    /// servoj's lookahead time, seconds (0.03-0.2).
    pub lookahead: f64,
    /// servoj's gain (100-2000).
    pub gain: f64,
    /// stopj's deceleration, rad/s².
    pub stop_deceleration: f64,
}

impl Program {
    /// The defaults for a control period: a 20 Hz watchdog (50 ms of
    /// silence stops the arm), lookahead 0.1 s, gain 300, stop at 3 rad/s².
    pub fn for_period(period: f64) -> Program {
        Program {
            period,
            watchdog_hz: 20.0,
            lookahead: 0.1,
            gain: 300.0,
            stop_deceleration: 3.0,
        }
    }

    /// The program's text.
    pub fn render(&self) -> String {
        let q = (0..6)
            .map(|i| format!("read_input_float_register({})", TARGET_REGISTER + i))
            .collect::<Vec<_>>()
            .join(", ");
        format!(
            "def packwright_stream():
  # packwright: streams joint targets from RTDE input registers.
  # int {seq}: sequence number (watched), int {mode}: mode ({servo} servoj, {hold} servoj to the same targets, {exit} exit, else stopj),
  # double {t0}-{t5}: joint targets (rad).
  textmsg(\"packwright: streaming started\")
  rtde_set_watchdog(\"input_int_register_{seq}\", {hz:.1}, \"stop\")
  while True:
    mode = read_input_integer_register({mode})
    if mode == {servo} or mode == {hold}:
      q = [{q}]
      servoj(q, 0, 0, {period:.4}, {lookahead:.3}, {gain:.0})
    elif mode == {exit}:
      break
    else:
      stopj({decel:.2})
      sync()
    end
  end
  stopj({decel:.2})
  textmsg(\"packwright: streaming ended\")
end
",
            seq = SEQUENCE_REGISTER,
            mode = MODE_REGISTER,
            servo = Mode::Servo as i32,
            hold = Mode::Hold as i32,
            exit = Mode::Exit as i32,
            t0 = TARGET_REGISTER,
            t5 = TARGET_REGISTER + 5,
            hz = self.watchdog_hz,
            q = q,
            period = self.period,
            lookahead = self.lookahead,
            gain = self.gain,
            decel = self.stop_deceleration,
        )
    }
}

/// Whether `script` has the form the URScript manual ("Connecting to
/// URControl") gives a program sent to the controller: its first line
/// starts with `def ` or `sec ` in the first column, its last line is
/// `end`, and every line between is indented (or empty). The fake
/// controller runs only such programs.
#[cfg(any(test, feature = "fake"))]
pub(crate) fn documented_form(script: &str) -> bool {
    let lines: Vec<&str> = script.trim_end().lines().collect();
    let (Some(first), Some(last)) = (lines.first(), lines.last()) else {
        return false;
    };
    let inner = &lines[1..lines.len() - 1];
    (first.starts_with("def ") || first.starts_with("sec "))
        && *last == "end"
        && inner
            .iter()
            .all(|l| l.trim().is_empty() || l.starts_with([' ', '\t']))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_program_sent_to_an_e_series() {
        insta::assert_snapshot!(Program::for_period(0.002).render());
    }

    /// The manual's form: the last line is `end`, every line but the
    /// first and the last is indented (a trailing call of the function,
    /// as once sent, is not a program a controller is documented to run).
    #[test]
    fn the_program_has_the_documented_form() {
        let text = Program::for_period(0.002).render();
        assert!(documented_form(&text));
        let lines: Vec<&str> = text.trim_end().lines().collect();
        assert!(lines[0].starts_with("def "));
        assert_eq!(lines.last(), Some(&"end"));
        assert!(
            lines[1..lines.len() - 1]
                .iter()
                .all(|l| l.starts_with("  "))
        );
    }

    #[test]
    fn the_period_and_watchdog_are_in_the_program() {
        let cb3 = Program::for_period(0.008).render();
        assert!(cb3.contains("servoj(q, 0, 0, 0.0080, 0.100, 300)"));
        assert!(cb3.contains("rtde_set_watchdog(\"input_int_register_24\", 20.0, \"stop\")"));
    }
}
