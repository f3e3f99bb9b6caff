//! Damped least squares (Levenberg–Marquardt) inverse kinematics for any
//! 6-axis chain, on the 6-D flange pose error.

use std::f64::consts::TAU;

use nalgebra::{Isometry3, Matrix6, Point3, Unit, UnitQuaternion, Vector3, Vector6};

use crate::{Arm, DOF, Joints};

/// Converged when both errors are below this (m, rad).
const CONVERGED: f64 = 1e-12;
/// Largest joint step per iteration (rad).
const MAX_STEP: f64 = 0.5;

/// The pose error `[position; rotation vector]` of the flange at `q` (base
/// frame) with respect to `target`.
fn error(arm: &Arm, target: &Isometry3<f64>, q: &Joints) -> Vector6<f64> {
    let f = arm.flange_pose(&Isometry3::identity(), q);
    let dp = target.translation.vector - f.translation.vector;
    let dr = (target.rotation * f.rotation.inverse()).scaled_axis();
    Vector6::new(dp.x, dp.y, dp.z, dr.x, dr.y, dr.z)
}

/// The geometric Jacobian of the flange (base frame) at `q`.
fn jacobian(arm: &Arm, q: &Joints) -> Matrix6<f64> {
    let id = Isometry3::identity();
    let poses = arm.link_poses(&id, q);
    let flange = (poses[DOF] * arm.flange).translation.vector;
    let mut j = Matrix6::zeros();
    for (i, ((pose, origin), axis)) in poses.iter().zip(&arm.origins).zip(&arm.axes).enumerate() {
        let frame = pose * origin;
        let axis = frame.rotation * axis.into_inner();
        let linear = axis.cross(&(flange - frame.translation.vector));
        j.fixed_view_mut::<3, 1>(0, i).copy_from(&linear);
        j.fixed_view_mut::<3, 1>(3, i).copy_from(&axis);
    }
    j
}

fn clamp_to_limits(arm: &Arm, q: &mut Joints) {
    for (v, l) in q.iter_mut().zip(&arm.limits) {
        *v = v.max(l.lower).min(l.upper);
    }
}

/// Iterates from `seed` for at most `iterations` steps; the joints reached
/// if they put the flange within 1e-9 (m, rad) of `target` (base frame).
pub(super) fn solve(
    arm: &Arm,
    target: &Isometry3<f64>,
    seed: &Joints,
    iterations: usize,
) -> Option<Joints> {
    let mut q = *seed;
    clamp_to_limits(arm, &mut q);
    let mut e = error(arm, target, &q);
    let mut cost = e.norm_squared();
    let mut lambda = 1e-3;
    for _ in 0..iterations {
        if !cost.is_finite() || cost < CONVERGED * CONVERGED {
            break;
        }
        let j = jacobian(arm, &q);
        let a = j * j.transpose() + Matrix6::identity() * (lambda * lambda);
        let Some(chol) = a.cholesky() else {
            lambda *= 10.0;
            continue;
        };
        let mut dq = j.transpose() * chol.solve(&e);
        let largest = dq.amax();
        if largest > MAX_STEP {
            dq *= MAX_STEP / largest;
        }
        let mut next = q;
        for (v, d) in next.iter_mut().zip(dq.iter()) {
            *v += d;
        }
        clamp_to_limits(arm, &mut next);
        let e_next = error(arm, target, &next);
        let cost_next = e_next.norm_squared();
        if cost_next < cost {
            (q, e, cost) = (next, e_next, cost_next);
            lambda = (lambda * 0.3).max(1e-9);
        } else {
            lambda *= 5.0;
            if lambda > 1e3 {
                break;
            }
        }
    }
    let close = e.fixed_rows::<3>(0).norm() <= 1e-9 && e.fixed_rows::<3>(3).norm() <= 1e-9;
    (close && q.iter().all(|v| v.is_finite())).then_some(q)
}

/// `near` with the base joint turned so that the flange's azimuth about the
/// base axis matches the target's; `None` if either is on the axis.
pub(super) fn aim_base(arm: &Arm, target: &Isometry3<f64>, near: &Joints) -> Option<Joints> {
    let axis = arm.axes[0];
    let joint = arm.origins[0];
    // The target in joint 1's (unturned) frame, the flange in link 1's frame.
    let goal = joint.inverse() * Point3::from(target.translation.vector);
    let link1 = joint * UnitQuaternion::from_axis_angle(&axis, near[0]);
    let here = link1.inverse()
        * Point3::from(
            arm.flange_pose(&Isometry3::identity(), near)
                .translation
                .vector,
        );
    let azimuth = |v: Vector3<f64>| -> Option<f64> {
        let u1 = Unit::try_new(axis.cross(&Vector3::x()), 1e-6)
            .or_else(|| Unit::try_new(axis.cross(&Vector3::y()), 1e-6))?;
        let u2 = axis.cross(&u1);
        let (x, y) = (v.dot(&u1), v.dot(&u2));
        (x.hypot(y) > 1e-6).then(|| y.atan2(x))
    };
    let turn = azimuth(goal.coords)? - azimuth(here.coords)?;
    let mut aimed = *near;
    aimed[0] = turn + ((near[0] - turn) / TAU).round() * TAU;
    Some(aimed)
}
