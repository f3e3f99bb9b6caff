//! The dashboard server (port 29999): line commands and line replies.
//!
//! Re-arming after a protective stop is explicit: the driver never calls
//! [`Dashboard::unlock_protective_stop`] or [`Dashboard::close_safety_popup`]
//! on its own; a person (or a program that decided so) does. Guarantee:
//! every call waits at most the connection's timeout for its reply.

use crate::client::connect;
use crate::error::{Service, UrError};
use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::time::Duration;

/// A connection to the dashboard server.
#[derive(Debug)]
pub struct Dashboard {
    reader: BufReader<TcpStream>,
    writer: TcpStream,
}

impl Dashboard {
    /// Connects to `address` (`host:29999`) and reads the welcome line.
    pub fn connect(address: &str, timeout: Duration) -> Result<Dashboard, UrError> {
        let stream = connect(address, Service::Dashboard, timeout)?;
        let writer = stream.try_clone().map_err(|source| UrError::Io {
            service: Service::Dashboard,
            cause: source,
        })?;
        let mut d = Dashboard {
            reader: BufReader::new(stream),
            writer,
        };
        d.line()?;
        Ok(d)
    }

    fn line(&mut self) -> Result<String, UrError> {
        let mut s = String::new();
        let io = |source| UrError::Io {
            service: Service::Dashboard,
            cause: source,
        };
        let n = (&mut self.reader)
            .take(4096)
            .read_line(&mut s)
            .map_err(io)?;
        if n == 0 {
            return Err(io(std::io::Error::new(
                std::io::ErrorKind::UnexpectedEof,
                "the dashboard server closed the connection",
            )));
        }
        Ok(s.trim_end().to_string())
    }

    /// Sends `command` and returns the reply line.
    pub fn request(&mut self, command: &str) -> Result<String, UrError> {
        self.writer
            .write_all(format!("{command}\n").as_bytes())
            .map_err(|source| UrError::Io {
                service: Service::Dashboard,
                cause: source,
            })?;
        self.line()
    }

    fn expect(&mut self, command: &str, ok: &str) -> Result<(), UrError> {
        let reply = self.request(command)?;
        if reply.to_lowercase().starts_with(&ok.to_lowercase()) {
            Ok(())
        } else {
            Err(UrError::DashboardRefused {
                command: command.into(),
                reply,
            })
        }
    }

    /// Whether the robot is in remote control (e-Series; a CB3 has no
    /// such mode and answers otherwise: `None`).
    pub fn is_in_remote_control(&mut self) -> Result<Option<bool>, UrError> {
        let reply = self.request("is in remote control")?;
        Ok(match reply.trim().to_lowercase().as_str() {
            "true" => Some(true),
            "false" => Some(false),
            _ => None,
        })
    }

    /// `safetystatus` (for example `Safetystatus: PROTECTIVE_STOP`).
    pub fn safety_status(&mut self) -> Result<String, UrError> {
        self.request("safetystatus")
    }

    /// Releases a protective stop. Explicit only: the cause must have been
    /// looked at first.
    pub fn unlock_protective_stop(&mut self) -> Result<(), UrError> {
        self.expect("unlock protective stop", "Protective stop releasing")
    }

    /// Closes the safety pop-up on the pendant.
    pub fn close_safety_popup(&mut self) -> Result<(), UrError> {
        self.expect("close safety popup", "closing safety popup")
    }

    /// Powers the arm on.
    pub fn power_on(&mut self) -> Result<(), UrError> {
        self.expect("power on", "Powering on")
    }

    /// Releases the brakes.
    pub fn brake_release(&mut self) -> Result<(), UrError> {
        self.expect("brake release", "Brake releasing")
    }

    /// Stops the running program.
    pub fn stop(&mut self) -> Result<(), UrError> {
        self.expect("stop", "Stopped")
    }
}

/// Whether the robot at the dashboard server `address` is in remote
/// control, asked within a second: `None` where it cannot be asked (no
/// dashboard, or a CB3, which has no such mode).
pub fn remote_control(address: &str) -> Option<bool> {
    Dashboard::connect(address, Duration::from_secs(1))
        .and_then(|mut d| d.is_in_remote_control())
        .ok()
        .flatten()
}
