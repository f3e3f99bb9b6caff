//! Closed-form inverse kinematics of a UR arm, from its DH geometry.
//!
//! With `G = Tz(d1) Rz(θ1) Rx(π/2)` (the frame joint 2 turns in) and the
//! link-6 pose `T` in the base frame:
//!
//! * Joints 2, 3 and 4 turn about parallel axes (`z1`, horizontal), so the
//!   wrist point `p5 = p6 - d6 z6` lies `d4` along `z1 = (sin θ1, -cos θ1, 0)`:
//!   `R sin(θ1 - φ) = d4` with `(R, φ)` the polar form of `p5`'s x, y. Two
//!   shoulder branches.
//! * `z1` seen from frame 6 is `(sin θ5 cos θ6, -sin θ5 sin θ6, cos θ5)`,
//!   which gives θ5 = atan2(±|xy|, z) (two wrist branches; atan2 keeps full
//!   precision near the singularity, where acos would not) and θ6
//!   (at the wrist singularity `sin θ5 = 0` it is only bounded by the planar arm's reach: see [`singular_theta6`]).
//! * `M = G⁻¹ T (O5 Rz(θ5) O6 Rz(θ6))⁻¹ = Rz(θ2) Tx(a2) Rz(θ3) Tx(a3) Tz(d4)
//!   Rz(θ4)`: a planar two-link arm (two elbow branches) and
//!   `θ2 + θ3 + θ4` from M's rotation.
//!
//! Arguments of `asin`/`acos` slightly beyond ±1 (by rounding) are clamped;
//! beyond a small slack the branch does not reach and is `None`. Callers
//! check every branch by forward kinematics.

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

use crate::{DOF, Joints, UrGeometry};

/// How far beyond ±1 a sine or cosine may be and still count as ±1.
const SLACK: f64 = 1e-9;
/// Below this `|sin θ5|`, the wrist is singular.
const SINGULAR: f64 = 1e-9;

fn rx(angle: f64) -> UnitQuaternion<f64> {
    UnitQuaternion::from_axis_angle(&Vector3::x_axis(), angle)
}

fn rz(angle: f64) -> UnitQuaternion<f64> {
    UnitQuaternion::from_axis_angle(&Vector3::z_axis(), angle)
}

/// `x` clamped to [-1, 1] if within [`SLACK`] of it, else `None`.
fn unit(x: f64) -> Option<f64> {
    // Not NaN once the test passes, so `clamp` cannot panic.
    (x.abs() <= 1.0 + SLACK).then(|| x.clamp(-1.0, 1.0))
}

/// `O5 Rz(θ5) O6 Rz(θ6)`: link 6 in the wrist-1 frame.
fn wrist_chain(g: &UrGeometry, theta5: f64, theta6: f64) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(0.0, -g.d5, 0.0),
        rx(FRAC_PI_2) * rz(theta5),
    ) * Isometry3::from_parts(
        Translation3::new(0.0, g.d6, 0.0),
        rx(-FRAC_PI_2) * rz(theta6),
    )
}

/// θ6 at the wrist singularity, where joints 4 and 6 are coaxial: any θ6
/// gives the flange orientation, but it swings the wrist-1 point `m(θ6)`
/// (the planar arm's target) around a circle, `m = C + U cos θ6 + V sin θ6`,
/// and the planar arm reaches only radii in `[|a2| - |a3|, |a2| + |a3|]`,
/// i.e. `|m|² = K + A cos(θ6 - β)` within bounds: an arc of θ6. The angle of
/// that arc nearest `near` (which is `near` itself when it fits).
fn singular_theta6(g: &UrGeometry, planar: impl Fn(f64) -> Isometry3<f64>, near: f64) -> f64 {
    let at = |theta6: f64| planar(theta6).translation.vector.xy();
    let (m0, m1, m2) = (at(0.0), at(FRAC_PI_2), at(PI));
    let c = (m0 + m2) / 2.0;
    let (u, v) = (m0 - c, m1 - c);
    let k = c.norm_squared() + (u.norm_squared() + v.norm_squared()) / 2.0;
    let (cu, cv) = (2.0 * c.dot(&u), 2.0 * c.dot(&v));
    let amplitude = cu.hypot(cv);
    if amplitude.is_nan() || amplitude <= 1e-12 {
        return near;
    }
    let beta = cv.atan2(cu);

    let (inner, outer) = (
        (g.a2.abs() - g.a3.abs()).powi(2),
        (g.a2.abs() + g.a3.abs()).powi(2),
    );
    let hi = (outer - k) / amplitude;
    let lo = (inner - k) / amplitude;
    if !(lo <= hi + SLACK && hi >= -1.0 - SLACK && lo <= 1.0 + SLACK) {
        return near;
    }
    let hi = hi.clamp(-1.0, 1.0); // not NaN: the test above failed for NaN
    let lo = lo.max(-1.0).min(hi);
    // |θ6 - β| (wrapped) must lie in [acos hi, acos lo].
    let offset = (near - beta) - ((near - beta) / TAU).round() * TAU;
    let magnitude = offset.abs().max(hi.acos()).min(lo.acos());

    beta + magnitude.copysign(offset)
}

/// The eight branches (index = 4 × shoulder + 2 × wrist + elbow) for the
/// link-6 pose `t` in the base frame; angles are not wrapped.
pub(super) fn solve(g: &UrGeometry, t: &Isometry3<f64>, near: &Joints) -> [Option<Joints>; 8] {
    let mut out = [None; 8];
    let rot = t.rotation.to_rotation_matrix();
    let r = rot.matrix();
    let p = t.translation.vector;
    let z6 = r.column(2).into_owned();
    let p5 = p - z6 * g.d6;

    let radius = p5.x.hypot(p5.y);
    let (phi, sin_offset) = if radius < 1e-12 {
        // The wrist point on the base axis: reachable only if d4 = 0, with
        // the base angle free.
        if g.d4.abs() > 1e-12 {
            return out;
        }
        (near[0], 0.0)
    } else {
        // asin(d4 / R), as an atan2 for precision where R ≈ |d4|.
        let across = radius * radius - g.d4 * g.d4;
        if across.is_nan() || across < -2.0 * SLACK * radius * radius {
            return out;
        }
        (p5.y.atan2(p5.x), g.d4.atan2(across.max(0.0).sqrt()))
    };

    for (shoulder, theta1) in [phi + sin_offset, phi + PI - sin_offset]
        .into_iter()
        .enumerate()
    {
        let (s1, c1) = theta1.sin_cos();
        let z1 = Vector3::new(s1, -c1, 0.0);
        // z1 seen from frame 6: (sin θ5 cos θ6, -sin θ5 sin θ6, cos θ5).
        let w = rot.transpose() * z1;
        let g_frame = Isometry3::from_parts(
            Translation3::new(0.0, 0.0, g.d1),
            rz(theta1) * rx(FRAC_PI_2),
        );
        let g_inv = g_frame.inverse();
        let sin5 = w.x.hypot(w.y);

        for (wrist, theta5) in [sin5.atan2(w.z), (-sin5).atan2(w.z)]
            .into_iter()
            .enumerate()
        {
            let s5 = theta5.sin();
            let planar = |theta6: f64| g_inv * t * wrist_chain(g, theta5, theta6).inverse();
            let theta6 = if sin5 < SINGULAR {
                singular_theta6(g, planar, near[DOF - 1])
            } else {
                let sign = s5.signum();
                (-w.y * sign).atan2(w.x * sign)
            };
            let m = planar(theta6);
            let (mx, my) = (m.translation.x, m.translation.y);
            let mr = m.rotation.to_rotation_matrix();
            let sum = mr[(1, 0)].atan2(mr[(0, 0)]);
            let c3 = (mx * mx + my * my - g.a2 * g.a2 - g.a3 * g.a3) / (2.0 * g.a2 * g.a3);
            let Some(c3) = unit(c3) else { continue };

            for (elbow, theta3) in [c3.acos(), -c3.acos()].into_iter().enumerate() {
                let (s3, c3) = theta3.sin_cos();
                let theta2 = my.atan2(mx) - (g.a3 * s3).atan2(g.a2 + g.a3 * c3);
                let theta4 = sum - theta2 - theta3;
                let q = [theta1, theta2, theta3, theta4, theta5, theta6];
                if q.iter().all(|v| v.is_finite()) {
                    out[4 * shoulder + 2 * wrist + elbow] = Some(q);
                }
            }
        }
    }
    out
}
