//! The cup tip of a UR arm in closed form while its wrist keeps the cup
//! down: the learned loop's inner loop ([`CupDownTip`]).
//!
//! With the DH frames of `closed_form.rs`, the link-6 pose is
//! `Tz(d1) Rz(θ1) Rx(π/2) M W` where `M = Rz(θ2) Tx(a2) Rz(θ3) Tx(a3)
//! Tz(d4) Rz(θ4)` is a planar two-link arm and `W` the wrist. A step that
//! keeps the cup down (`θ4` against `θ2 + θ3`, `θ6` with `θ1`) keeps
//! `φ = θ2 + θ3 + θ4` and `θ5`; when the cup tip is on joint 6's axis, `θ6`
//! does not move it, so in the frame joint 2 turns in the tip is
//!
//! `P(θ2, θ3) + w`, `P = (a2 cos θ2 + a3 cos(θ2 + θ3), a2 sin θ2 + a3 sin(θ2 + θ3), 0)`
//!
//! with `w` (`d4` out of the plane, and the wrist) the same at every step:
//! three sines and cosines per pose instead of six joint rotations
//! composed.

use nalgebra::{Isometry3, Point3, Vector3};

use crate::{Arm, Joints};

/// The cup tip of a UR arm at joints reached from `from` by steps that keep
/// the cup down ([`Arm::cup_down_tip`]).
#[derive(Debug, Clone, Copy)]
pub struct CupDownTip {
    base: Isometry3<f64>,
    d1: f64,
    a2: f64,
    a3: f64,
    /// The tip minus the planar arm's reach, in the frame joint 2 turns in.
    w: Vector3<f64>,
    /// `θ2 + θ3 + θ4` and `θ5` of the joints it was made at.
    phi: f64,
    theta5: f64,
}

impl Arm {
    /// The cup tip for joints moved from `from`, where it is at `tip`
    /// (world), keeping `θ2 + θ3 + θ4` and `θ5` (the learned loop's
    /// cup-down steps); `None` unless the arm has the exact UR geometry
    /// ([`UrGeometry::exact`](crate::UrGeometry::exact): a calibrated
    /// arm's tip is not the planar arm's to the micrometre) and the cup
    /// axis is joint 6's.
    pub fn cup_down_tip(
        &self,
        base: &Isometry3<f64>,
        from: &Joints,
        tip: &Point3<f64>,
    ) -> Option<CupDownTip> {
        let g = self.ur.as_ref().filter(|g| g.exact)?;
        if !self.tool_on_last_axis() {
            return None;
        }
        // The tip in the frame joint 2 turns in, then w = tip − P.
        let base = base * g.mount;
        let tip = base.inverse() * tip;
        let v = tip.coords - Vector3::new(0.0, 0.0, g.d1);
        let (s1, c1) = from[0].sin_cos();
        let u = Vector3::new(c1 * v.x + s1 * v.y, -s1 * v.x + c1 * v.y, v.z);
        let in_plane = Vector3::new(u.x, u.z, -u.y);
        let w = in_plane - planar(g.a2, g.a3, from);
        Some(CupDownTip {
            base,
            d1: g.d1,
            a2: g.a2,
            a3: g.a3,
            w,
            phi: from[1] + from[2] + from[3],
            theta5: from[4],
        })
    }
}

/// The planar arm's reach `P(θ2, θ3)` in its plane (`d4` out of the
/// plane, the same at every pose, is left in `w`).
fn planar(a2: f64, a3: f64, q: &Joints) -> Vector3<f64> {
    let (s2, c2) = q[1].sin_cos();
    let (s23, c23) = (q[1] + q[2]).sin_cos();
    Vector3::new(a2 * c2 + a3 * c23, a2 * s2 + a3 * s23, 0.0)
}

impl CupDownTip {
    /// The world position of the cup tip at `q`; `None` when `q` does not
    /// keep `θ2 + θ3 + θ4` and `θ5` (within 1e-9 rad) of the joints it was
    /// made at.
    pub fn at(&self, q: &Joints) -> Option<Point3<f64>> {
        let kept = (q[1] + q[2] + q[3] - self.phi).abs() <= 1e-9 && q[4] == self.theta5;
        if !kept {
            return None;
        }
        let p = planar(self.a2, self.a3, q) + self.w;
        // Out of the plane (Rx(π/2)), round the base (Rz(θ1)), up by d1.
        let (s1, c1) = q[0].sin_cos();
        let (x, y, z) = (p.x, -p.z, p.y);
        let tip = Point3::new(c1 * x - s1 * y, s1 * x + c1 * y, z + self.d1);
        Some(self.base * tip)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::f64::consts::FRAC_PI_2;

    proptest! {
        /// Along cup-down steps from a cup-down pose, the closed form is
        /// the forward kinematics' tip to within 1e-9 m.
        #[test]
        fn the_closed_form_tip_is_the_forward_kinematics_tip(
            q0 in -3.0..3.0f64, q1 in -2.5..-0.5f64, q2 in 0.3..2.5f64, q5 in -3.0..3.0f64,
            steps in proptest::collection::vec((-0.26..0.26f64, -0.26..0.26f64, -0.26..0.26f64), 1..12),
            yaw in -3.0..3.0f64, x in -1.0..1.0f64, suction in 0.05..0.3f64,
        ) {
            let arm = Arm::ur10();
            let base = Isometry3::new(Vector3::new(x, 0.3, 0.7), Vector3::z() * yaw);
            // Cup down: wrist 1 against shoulder and elbow, wrist 2 at −π/2.
            let start = [q0, q1, q2, -FRAC_PI_2 - q1 - q2, -FRAC_PI_2, q5];
            let tip = arm.tool_tip(&base, &start, suction);
            let fast = arm.cup_down_tip(&base, &start, &tip).expect("a UR10");
            let mut q = start;
            for (a, b, c) in steps {
                q[0] += a;
                q[1] += b;
                q[2] += c;
                q[3] -= b + c;
                q[5] += a;
                let exact = arm.tool_tip(&base, &q, suction);
                let tip = fast.at(&q).expect("the wrist kept");
                prop_assert!((tip - exact).norm() < 1e-9, "{tip} vs {exact}");
            }
        }
    }

    /// Joints that moved wrist 2, or wrist 1 against the others, are refused.
    #[test]
    fn joints_off_the_cup_down_steps_are_refused() {
        let arm = Arm::ur10();
        let base = Isometry3::identity();
        let start = [0.2, -1.2, 1.4, -FRAC_PI_2 - 0.2, -FRAC_PI_2, 0.0];
        let tip = arm.tool_tip(&base, &start, 0.12);
        let fast = arm.cup_down_tip(&base, &start, &tip).expect("a UR10");
        let mut wrist2 = start;
        wrist2[4] += 0.1;
        let mut wrist1 = start;
        wrist1[3] += 0.1;
        assert!(fast.at(&start).is_some());
        assert!(fast.at(&wrist2).is_none());
        assert!(fast.at(&wrist1).is_none());
    }
}
