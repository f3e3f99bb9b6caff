//! Where products are on a real cell, for [`World::observe`]: a real cell
//! has no simulator to ask.
//!
//! Two sources: [`Nominal`] (the positions the caller gives, for example
//! the `.pack` file's inventory on a jig or fixture; a gripped product
//! follows the tool tip through a caller-supplied function, since this
//! crate has no kinematics) and [`JsonFeed`] (a vision system's
//! line-delimited JSON on a local socket).
//!
//! [`World::observe`]: packwright_interface::World::observe

use crate::client::connect;
use crate::error::{Service, UrError};
use packwright_interface::{Joints, Seen};
use serde::Deserialize;
use std::io::{BufRead, BufReader, Read};
use std::net::{Shutdown, TcpStream};
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// A source of product positions.
pub trait ProductSource: Send {
    /// Called once per control cycle (after each [`World::step`], not
    /// before the first) with the measured joints and whether the suction
    /// holds.
    ///
    /// [`World::step`]: packwright_interface::World::step
    fn update(&mut self, joints: &Joints, suction: bool);
    /// The products as seen now.
    fn products(&self) -> Vec<Seen>;
}

/// No products (a cell the driver only moves the arm in).
#[derive(Debug, Default, Clone, Copy)]
pub struct NoProducts;

impl ProductSource for NoProducts {
    fn update(&mut self, _: &Joints, _: bool) {}
    fn products(&self) -> Vec<Seen> {
        Vec::new()
    }
}

/// A product at a known position, with its size (width, depth, height).
#[derive(Debug, Clone, PartialEq)]
pub struct Known {
    pub seen: Seen,
    pub size: [f64; 3],
}

/// The tool tip's position and its rotation about the vertical (radians)
/// for measured joints: the caller's forward kinematics.
pub type ToolTip = Box<dyn Fn(&Joints) -> ([f64; 3], f64) + Send>;

/// How far (m) the tip may be above or below a product's top face when the
/// suction switches on for the product to count as gripped.
pub const GRIP_GAP: f64 = 0.01;

/// Products where the caller says they are (a jig or fixture). When the
/// suction switches on with the tool tip on a product's top face (within
/// [`GRIP_GAP`] of its height, horizontally inside its footprint), that
/// product follows the tip at the offset where it was gripped, turning
/// with the tool; when the suction switches off, it stays where it was
/// carried, lowered to the height it stood at (products stand on the
/// table plane; the boxes' floors are at the table).
pub struct Nominal {
    products: Vec<Known>,
    tool: ToolTip,
    /// Held product: index, offset from the tip in the tool's frame, yaw
    /// relative to the tool, the height it stood at.
    held: Option<(usize, [f64; 3], f64, f64)>,
    suction: bool,
}

impl Nominal {
    pub fn new(products: Vec<Known>, tool: ToolTip) -> Nominal {
        Nominal {
            products,
            tool,
            held: None,
            suction: false,
        }
    }

    /// The held product's name, if one is held.
    pub fn held(&self) -> Option<&str> {
        self.held.map(|(i, ..)| self.products[i].seen.name.as_str())
    }
}

fn rotate(v: [f64; 3], angle: f64) -> [f64; 3] {
    let (s, c) = angle.sin_cos();
    [c * v[0] - s * v[1], s * v[0] + c * v[1], v[2]]
}

impl ProductSource for Nominal {
    fn update(&mut self, joints: &Joints, suction: bool) {
        let (tip, yaw) = (self.tool)(joints);
        if suction && !self.suction {
            self.held = self
                .products
                .iter()
                .enumerate()
                .filter(|(_, p)| {
                    let c = p.seen.centre;
                    let top = c[2] + p.size[2] / 2.0;
                    let local = rotate([tip[0] - c[0], tip[1] - c[1], 0.0], -p.seen.yaw);
                    (tip[2] - top).abs() <= GRIP_GAP
                        && local[0].abs() <= p.size[0] / 2.0
                        && local[1].abs() <= p.size[1] / 2.0
                })
                .min_by(|(_, a), (_, b)| {
                    let d =
                        |p: &Known| (p.seen.centre[0] - tip[0]).hypot(p.seen.centre[1] - tip[1]);
                    d(a).total_cmp(&d(b))
                })
                .map(|(i, p)| {
                    let c = p.seen.centre;
                    let offset = rotate([c[0] - tip[0], c[1] - tip[1], c[2] - tip[2]], -yaw);
                    (i, offset, p.seen.yaw - yaw, c[2])
                });
        }
        if let Some((i, offset, rel_yaw, rest_z)) = self.held {
            let o = rotate(offset, yaw);
            let p = &mut self.products[i].seen;
            p.centre = [tip[0] + o[0], tip[1] + o[1], tip[2] + o[2]];
            p.yaw = yaw + rel_yaw;
            if !suction {
                p.centre[2] = rest_z;
                self.held = None;
            }
        }
        self.suction = suction;
    }

    fn products(&self) -> Vec<Seen> {
        self.products.iter().map(|p| p.seen.clone()).collect()
    }
}

/// One line of a product feed: `{"products": [{"name": "cup_a", "centre":
/// [x, y, z], "yaw": 0.0}]}` (world frame, metres, radians; `yaw`
/// optional).
#[derive(Debug, Deserialize)]
struct FeedLine {
    products: Vec<FeedProduct>,
}

#[derive(Debug, Deserialize)]
struct FeedProduct {
    name: String,
    centre: [f64; 3],
    #[serde(default)]
    yaw: f64,
}

#[derive(Debug, Default)]
struct FeedState {
    latest: Vec<Seen>,
    lines: u64,
    error: Option<(u64, String)>,
    closed: bool,
}

/// Products from a vision system: line-delimited JSON on a local socket
/// (one line per observation, see the line format above); the newest valid
/// line is what [`ProductSource::products`] returns. A malformed line
/// (not JSON, a non-finite number) is skipped and remembered
/// ([`JsonFeed::last_error`]); it never replaces a valid observation.
pub struct JsonFeed {
    state: Arc<Mutex<FeedState>>,
    stream: TcpStream,
    reader: Option<std::thread::JoinHandle<()>>,
}

impl JsonFeed {
    /// Connects to the feed at `address` and reads it on a thread.
    pub fn connect(address: &str, timeout: Duration) -> Result<JsonFeed, UrError> {
        let stream = connect(address, Service::Feed, timeout)?;
        stream
            .set_read_timeout(None)
            .map_err(|source| UrError::Io {
                service: Service::Feed,
                cause: source,
            })?;
        let read = stream.try_clone().map_err(|source| UrError::Io {
            service: Service::Feed,
            cause: source,
        })?;
        let state = Arc::new(Mutex::new(FeedState::default()));
        let shared = Arc::clone(&state);
        let reader = std::thread::spawn(move || {
            let mut lines = BufReader::new(read);
            let mut line = String::new();
            loop {
                line.clear();
                // Lines longer than 1 MiB end the feed (a broken sender).
                match (&mut lines).take(1 << 20).read_line(&mut line) {
                    Ok(0) | Err(_) => break,
                    Ok(_) => {}
                }
                let parsed = parse_line(&line);
                let Ok(mut s) = shared.lock() else { break };
                s.lines += 1;
                let n = s.lines;
                match parsed {
                    Ok(products) => s.latest = products,
                    Err(e) => s.error = Some((n, e)),
                }
            }
            if let Ok(mut s) = shared.lock() {
                s.closed = true;
            }
        });
        Ok(JsonFeed {
            state,
            stream,
            reader: Some(reader),
        })
    }

    /// The last malformed line's number and why, if any.
    pub fn last_error(&self) -> Option<UrError> {
        let s = self.state.lock().ok()?;
        s.error
            .clone()
            .map(|(line, reason)| UrError::BadFeed { line, reason })
    }

    /// Lines read so far.
    pub fn lines(&self) -> u64 {
        self.state.lock().map_or(0, |s| s.lines)
    }

    /// Whether the feed closed.
    pub fn closed(&self) -> bool {
        self.state.lock().map_or(true, |s| s.closed)
    }
}

fn parse_line(line: &str) -> Result<Vec<Seen>, String> {
    let l: FeedLine = serde_json::from_str(line.trim()).map_err(|e| e.to_string())?;
    l.products
        .into_iter()
        .map(|p| {
            if p.centre.iter().chain([&p.yaw]).all(|v| v.is_finite()) {
                Ok(Seen {
                    name: p.name,
                    centre: p.centre,
                    yaw: p.yaw,
                })
            } else {
                Err(format!("product `{}` has a non-finite number", p.name))
            }
        })
        .collect()
}

impl ProductSource for JsonFeed {
    fn update(&mut self, _: &Joints, _: bool) {}
    fn products(&self) -> Vec<Seen> {
        self.state
            .lock()
            .map(|s| s.latest.clone())
            .unwrap_or_default()
    }
}

impl Drop for JsonFeed {
    fn drop(&mut self) {
        let _ = self.stream.shutdown(Shutdown::Both);
        if let Some(r) = self.reader.take() {
            let _ = r.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;
    use std::net::TcpListener;
    use std::time::Instant;

    fn box_at(name: &str, x: f64, y: f64) -> Known {
        Known {
            seen: Seen {
                name: name.into(),
                centre: [x, y, 0.05],
                yaw: 0.0,
            },
            size: [0.06, 0.06, 0.1],
        }
    }

    /// A "tool" whose tip is at (q0, q1, q2) with yaw q5.
    fn tool() -> ToolTip {
        Box::new(|q: &Joints| ([q[0], q[1], q[2]], q[5]))
    }

    #[test]
    fn a_gripped_product_follows_the_tip_and_stays_where_released() {
        let mut n = Nominal::new(vec![box_at("a", 0.5, 0.0), box_at("b", 0.7, 0.0)], tool());
        // Suction on above `b`'s top but too high: nothing gripped.
        n.update(&[0.7, 0.0, 0.2, 0.0, 0.0, 0.0], true);
        assert_eq!(n.held(), None);
        n.update(&[0.7, 0.0, 0.2, 0.0, 0.0, 0.0], false);
        // On `a`'s top face, 5 mm off its centre.
        n.update(&[0.505, 0.0, 0.1, 0.0, 0.0, 0.0], true);
        assert_eq!(n.held(), Some("a"));
        n.update(&[0.305, 0.2, 0.3, 0.0, 0.0, 0.0], true);
        let a = &n.products()[0];
        assert!((a.centre[0] - 0.3).abs() < 1e-12 && (a.centre[2] - 0.25).abs() < 1e-12);
        // Turning the tool a quarter turn turns the offset with it.
        n.update(
            &[0.305, 0.2, 0.3, 0.0, 0.0, std::f64::consts::FRAC_PI_2],
            true,
        );
        let a = &n.products()[0];
        assert!((a.centre[0] - 0.305).abs() < 1e-12 && (a.centre[1] - 0.195).abs() < 1e-12);
        assert!((a.yaw - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        n.update(
            &[0.305, 0.2, 0.3, 0.0, 0.0, std::f64::consts::FRAC_PI_2],
            false,
        );
        assert_eq!(n.held(), None);
        let a = &n.products()[0];
        assert!(
            (a.centre[2] - 0.05).abs() < 1e-12,
            "lowered to where it stood"
        );
        assert_eq!(n.products()[1], box_at("b", 0.7, 0.0).seen);
    }

    #[test]
    fn the_feed_keeps_the_newest_valid_line() {
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        let addr = listener.local_addr().unwrap().to_string();
        let sender = std::thread::spawn(move || {
            let (mut s, _) = listener.accept().unwrap();
            s.write_all(b"{\"products\":[{\"name\":\"a\",\"centre\":[1,2,3]}]}\n")
                .unwrap();
            s.write_all(b"not json\n").unwrap();
            s.write_all(b"{\"products\":[{\"name\":\"b\",\"centre\":[0.5,0,0.1],\"yaw\":0.2}]}\n")
                .unwrap();
        });
        let feed = JsonFeed::connect(&addr, Duration::from_secs(2)).unwrap();
        sender.join().unwrap();
        let started = Instant::now();
        while !feed.closed() && started.elapsed() < Duration::from_secs(5) {
            std::thread::sleep(Duration::from_millis(5));
        }
        assert_eq!(feed.lines(), 3);
        let seen = feed.products();
        assert_eq!(seen.len(), 1);
        assert_eq!(seen[0].name, "b");
        assert_eq!(seen[0].yaw, 0.2);
        assert!(matches!(
            feed.last_error(),
            Some(UrError::BadFeed { line: 2, .. })
        ));
        assert!(parse_line("{\"products\":[{\"name\":\"x\",\"centre\":[1e999,0,0]}]}").is_err());
    }
}
