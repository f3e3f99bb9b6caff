//! Robot addresses: `ur10://HOST[:PORT][?secondary=PORT&dashboard=PORT]`
//! (`ur://` is accepted for `ur10://`, the specification's spelling).
//!
//! `PORT` is the RTDE port (30004 by default); the secondary interface and
//! the dashboard server default to 30002 and 29999 on the same host (a
//! fake controller listens on other ports and says so in the query).
//! Guarantee: [`RobotAddress::parse`] accepts only that form, with ports
//! 1-65535, and never panics.

use crate::error::UrError;

/// The controller's default ports.
pub const RTDE_PORT: u16 = 30004;
pub const SECONDARY_PORT: u16 = 30002;
pub const DASHBOARD_PORT: u16 = 29999;

/// Where a controller's services listen.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RobotAddress {
    pub host: String,
    pub rtde: u16,
    pub secondary: u16,
    pub dashboard: u16,
}

impl RobotAddress {
    /// The services of the controller at `host` on their default ports.
    pub fn host(host: &str) -> RobotAddress {
        RobotAddress {
            host: host.into(),
            rtde: RTDE_PORT,
            secondary: SECONDARY_PORT,
            dashboard: DASHBOARD_PORT,
        }
    }

    /// Parses `ur10://HOST[:PORT][?secondary=PORT&dashboard=PORT]`.
    pub fn parse(url: &str) -> Result<RobotAddress, UrError> {
        let bad = |reason: &str| UrError::BadAddress {
            address: url.into(),
            reason: reason.into(),
        };
        let rest = url
            .strip_prefix("ur10://")
            .or_else(|| url.strip_prefix("ur://"))
            .ok_or_else(|| bad("expected ur10://HOST[:PORT]"))?;
        let (authority, query) = rest.split_once('?').unwrap_or((rest, ""));
        let authority = authority.strip_suffix('/').unwrap_or(authority);
        let port = |s: &str| -> Result<u16, UrError> {
            s.parse::<u16>()
                .ok()
                .filter(|&p| p > 0)
                .ok_or_else(|| bad(&format!("`{s}` is not a port (1-65535)")))
        };
        let (host, rtde) = if let Some(v6) = authority.strip_prefix('[') {
            let (h, tail) = v6
                .split_once(']')
                .ok_or_else(|| bad("an IPv6 host needs its closing `]`"))?;
            match tail.strip_prefix(':') {
                Some(p) => (h.to_string(), port(p)?),
                None if tail.is_empty() => (h.to_string(), RTDE_PORT),
                None => return Err(bad("unexpected text after the host")),
            }
        } else {
            match authority.rsplit_once(':') {
                Some((h, p)) => (h.to_string(), port(p)?),
                None => (authority.to_string(), RTDE_PORT),
            }
        };
        if host.is_empty() || host.contains(['/', '@', ' ', '[', ']']) {
            return Err(bad("expected a host name or address"));
        }
        let mut a = RobotAddress {
            rtde,
            ..RobotAddress::host(&host)
        };
        for pair in query.split('&').filter(|p| !p.is_empty()) {
            match pair.split_once('=') {
                Some(("secondary", p)) => a.secondary = port(p)?,
                Some(("dashboard", p)) => a.dashboard = port(p)?,
                _ => return Err(bad(&format!("unknown option `{pair}`"))),
            }
        }
        Ok(a)
    }

    fn join(&self, port: u16) -> String {
        if self.host.contains(':') {
            format!("[{}]:{port}", self.host)
        } else {
            format!("{}:{port}", self.host)
        }
    }

    /// `host:port` of the RTDE interface.
    pub fn rtde_addr(&self) -> String {
        self.join(self.rtde)
    }

    /// `host:port` of the secondary interface.
    pub fn secondary_addr(&self) -> String {
        self.join(self.secondary)
    }

    /// `host:port` of the dashboard server.
    pub fn dashboard_addr(&self) -> String {
        self.join(self.dashboard)
    }
}

impl std::fmt::Display for RobotAddress {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "ur10://{}", self.join(self.rtde))?;
        if (self.secondary, self.dashboard) != (SECONDARY_PORT, DASHBOARD_PORT) {
            write!(
                f,
                "?secondary={}&dashboard={}",
                self.secondary, self.dashboard
            )?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn addresses() {
        let a = RobotAddress::parse("ur10://192.168.1.10").unwrap();
        assert_eq!(a, RobotAddress::host("192.168.1.10"));
        assert_eq!(a.rtde_addr(), "192.168.1.10:30004");
        assert_eq!(a.dashboard_addr(), "192.168.1.10:29999");
        let b = RobotAddress::parse("ur10://127.0.0.1:4000?secondary=4001&dashboard=4002").unwrap();
        assert_eq!((b.rtde, b.secondary, b.dashboard), (4000, 4001, 4002));
        assert_eq!(RobotAddress::parse(&b.to_string()).unwrap(), b);
        assert_eq!(RobotAddress::parse("ur://192.168.1.10").unwrap(), a);
        let c = RobotAddress::parse("ur10://[::1]:5").unwrap();
        assert_eq!(c.rtde_addr(), "[::1]:5");
        for bad in [
            "ur5://host",
            "ur10://",
            "ur10://host:0",
            "ur10://host:99999",
            "ur10://host:x",
            "ur10://host?foo=1",
            "ur10://[::1",
            "ur10://[[]",
            "ur10://a]:5",
        ] {
            assert!(RobotAddress::parse(bad).is_err(), "{bad}");
        }
    }
}

#[cfg(test)]
mod properties {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// Any text: an address or an error, never a panic; a parsed
        /// address prints as one that parses to itself.
        #[test]
        fn parsing_never_panics(text in "(ur10://)?[\\[\\]:?&=a-z0-9./@ ]{0,30}") {
            if let Ok(a) = RobotAddress::parse(&text) {
                prop_assert_eq!(RobotAddress::parse(&a.to_string()).unwrap(), a);
            }
        }
    }
}
