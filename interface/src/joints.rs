//! Joint positions and limits.

/// Degrees of freedom of the arms packwright drives.
pub const DOF: usize = 6;

/// Joint positions in radians, base first.
pub type Joints = [f64; DOF];

/// Limits of one joint (SI units: rad, rad/s, rad/s², rad/s³).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limits {
    pub lower: f64,
    pub upper: f64,
    pub velocity: f64,
    pub acceleration: f64,
    pub jerk: f64,
}

impl Limits {
    /// Whether position `v` is within the range (1e-9 rad of slack for
    /// rounding).
    pub fn contains(&self, v: f64) -> bool {
        v >= self.lower - 1e-9 && v <= self.upper + 1e-9
    }
}

/// Whether `q` is within `limits` (1e-9 rad of slack for rounding).
pub fn within(limits: &[Limits; DOF], q: &Joints) -> bool {
    q.iter().zip(limits).all(|(v, l)| l.contains(*v))
}
