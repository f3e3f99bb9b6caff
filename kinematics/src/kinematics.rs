//! Forward and inverse kinematics of an [`Arm`].
//!
//! Frames: `base` is the world pose of the arm's base link; link `i + 1` is
//! joint `i`'s origin turned by `q[i]` about its axis; the flange is
//! [`Arm::flange`] in the last link. The suction cup points along the flange
//! z axis and its tip is `suction` metres from the flange.
//!
//! "Tool down" means the flange z axis is world -z; `yaw` is then the angle
//! of the flange x axis from world x about world z ([`tool_down_pose`]).
//!
//! Inverse kinematics returns, among the solutions within the joint limits,
//! the one nearest to `near` (least sum of squared joint differences), each
//! joint taken at the 2π turn nearest `near` that its limits allow. UR arms
//! ([`Arm::ur`]) are solved in closed form (`closed_form.rs`, eight
//! branches); other arms by damped least squares (`numeric.rs`). Every
//! function is total: non-finite or unreachable input gives `None`.

mod closed_form;
mod cup_down;
mod numeric;

pub use cup_down::CupDownTip;

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};

use super::{Arm, DOF, Joints, Limits};

/// A solution must put the flange within this distance (m) and angle (rad)
/// of the target.
pub const IK_TOLERANCE: f64 = 1e-9;

/// How close (sum of squared joint differences, rad²) a branch's solution
/// must be to joints for them to be on that branch ([`Arm::ur_branch`]):
/// the solutions are exact to about 1e-9 rad, and two branches are this
/// close only at a singular pose, where either is right.
const BRANCH_TOLERANCE: f64 = 1e-12;
/// [`BRANCH_TOLERANCE`] for a calibrated UR arm, whose closed-form
/// solutions are polished by damped least squares to [`IK_TOLERANCE`].
const POLISHED_BRANCH_TOLERANCE: f64 = 1e-6;

/// The world flange pose that puts the cup tip at `tip`, pointing straight
/// down, with the flange x axis at `yaw` from world x.
pub fn tool_down_pose(tip: Point3<f64>, yaw: f64, suction: f64) -> Isometry3<f64> {
    let rotation = UnitQuaternion::from_euler_angles(PI, 0.0, yaw);
    Isometry3::from_parts(
        Translation3::from(tip.coords + Vector3::z() * suction),
        rotation,
    )
}

/// The sum of squared joint differences.
pub fn joint_distance(a: &Joints, b: &Joints) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum()
}

impl Arm {
    /// World poses of the base link and the six moving links.
    pub fn link_poses(&self, base: &Isometry3<f64>, q: &Joints) -> [Isometry3<f64>; DOF + 1] {
        let mut poses = [*base; DOF + 1];
        for i in 0..DOF {
            poses[i + 1] =
                poses[i] * self.origins[i] * UnitQuaternion::from_axis_angle(&self.axes[i], q[i]);
        }
        poses
    }

    /// World pose of the flange.
    pub fn flange_pose(&self, base: &Isometry3<f64>, q: &Joints) -> Isometry3<f64> {
        let mut pose = *base;
        for ((origin, axis), angle) in self.origins.iter().zip(&self.axes).zip(q) {
            pose = pose * origin * UnitQuaternion::from_axis_angle(axis, *angle);
        }
        pose * self.flange
    }

    /// Per joint, an upper bound (m) on how far the cup tip, `suction`
    /// metres along the flange z axis, is from that joint's axis, in any
    /// configuration: the lengths of the chain after the joint (each later
    /// joint origin's offset, the flange's, the cup). So turning joint `j`
    /// by `dq` moves the tip at most `radii[j] * |dq|`, and along any joint
    /// path the tip moves at most `Σ radii[j] * |Δq[j]|` (the straight
    /// joint segment from `a` to `b`: `radii · |b − a|`).
    pub fn tip_radii(&self, suction: f64) -> [f64; DOF] {
        let mut radii = [0.0; DOF];
        let mut after = self.flange.translation.vector.norm() + suction.abs();
        for j in (0..DOF).rev() {
            radii[j] = after;
            after += self.origins[j].translation.vector.norm();
        }
        radii
    }

    /// World position of the cup tip, `suction` metres along the flange z axis.
    pub fn tool_tip(&self, base: &Isometry3<f64>, q: &Joints, suction: f64) -> Point3<f64> {
        Arm::tip_of(&self.flange_pose(base, q), suction)
    }

    /// The cup tip of a flange at `flange`, `suction` metres along its z
    /// axis: [`Arm::tool_tip`] for a caller that has the flange pose.
    pub fn tip_of(flange: &Isometry3<f64>, suction: f64) -> Point3<f64> {
        flange * Point3::new(0.0, 0.0, suction)
    }

    /// Joints that put the cup tip at `tip`, pointing straight down, with the
    /// given yaw; the solution nearest `near`, or `None`.
    pub fn tool_down_ik(
        &self,
        base: &Isometry3<f64>,
        tip: Point3<f64>,
        yaw: f64,
        suction: f64,
        near: &Joints,
    ) -> Option<Joints> {
        if !(finite(&tip.coords) && yaw.is_finite() && suction.is_finite()) {
            return None;
        }
        self.pose_ik(base, &tool_down_pose(tip, yaw, suction), near)
    }

    /// Like [`Arm::tool_down_ik`], with the yaw left free: the solution moves
    /// the joints least from `near`.
    ///
    /// When the cup axis is the last joint's axis (as on the UR10), any yaw
    /// is joint 6 alone, so this solves every branch at yaw 0, sets joint 6
    /// as near `near[5]` as its limits allow and keeps the nearest branch:
    /// the exact optimum. Otherwise it tries the flange yaw at `near` and
    /// the three quarter turns from it, and keeps the nearest solution.
    pub fn yaw_free_tool_down_ik(
        &self,
        base: &Isometry3<f64>,
        tip: Point3<f64>,
        suction: f64,
        near: &Joints,
    ) -> Option<Joints> {
        if !(finite(&tip.coords)
            && suction.is_finite()
            && finite_iso(base)
            && near.iter().all(|v| v.is_finite()))
        {
            return None;
        }
        if self.tool_on_last_axis() {
            let target = tool_down_pose(tip, 0.0, suction);
            let l = &self.limits[DOF - 1];
            let spun = |mut q: Joints| {
                q[DOF - 1] = near[DOF - 1].max(l.lower).min(l.upper);
                q
            };
            let ok = |q: &Joints| {
                let f = self.flange_pose(base, q);
                let tip_error = (f * Point3::new(0.0, 0.0, suction) - tip).norm();
                let axis_error = (f.rotation * Vector3::z() + Vector3::z()).norm();
                tip_error <= IK_TOLERANCE && axis_error <= IK_TOLERANCE
            };
            let candidates: Vec<Joints> = if self.ur.is_some() {
                // Joint 6 is set afterwards: leave it free here.
                let mut free = self.limits;
                free[DOF - 1].lower = f64::NEG_INFINITY;
                free[DOF - 1].upper = f64::INFINITY;
                self.ur_branches(base, &target, near, &free)
                    .into_iter()
                    .flatten()
                    .collect()
            } else {
                self.numeric_ik(
                    base,
                    &tool_down_pose(tip, self.flange_yaw(base, near), suction),
                    near,
                )
                .into_iter()
                .collect()
            };
            return nearest(candidates.into_iter().map(spun).filter(ok), near);
        }
        let yaw0 = self.flange_yaw(base, near);
        let candidates = (0..4).filter_map(|k| {
            self.tool_down_ik(base, tip, yaw0 + k as f64 * FRAC_PI_2, suction, near)
        });
        nearest(candidates, near)
    }

    /// Joints that put the flange at the world pose `flange`, nearest `near`:
    /// closed form for UR arms, damped least squares otherwise.
    pub fn pose_ik(
        &self,
        base: &Isometry3<f64>,
        flange: &Isometry3<f64>,
        near: &Joints,
    ) -> Option<Joints> {
        match &self.ur {
            Some(g) => nearest(
                self.ur_ik_branches(base, flange, near)
                    .into_iter()
                    .flatten(),
                near,
            )
            // A calibrated arm's closed form is its nominal arm's: at the
            // edge of the reach (the elbow nearly straight) the nominal
            // arm may fall short where the real one reaches.
            .or_else(|| {
                (!g.exact)
                    .then(|| self.numeric_ik(base, flange, near))
                    .flatten()
            }),
            None => self.numeric_ik(base, flange, near),
        }
    }

    /// The closed-form solutions for a UR arm, one per branch (index =
    /// 4 × shoulder + 2 × wrist + elbow), each joint at the 2π turn nearest
    /// `near` within its limits, checked by forward kinematics; `None` for a
    /// branch that does not reach, is outside the limits, or on a non-UR arm.
    pub fn ur_ik_branches(
        &self,
        base: &Isometry3<f64>,
        flange: &Isometry3<f64>,
        near: &Joints,
    ) -> [Option<Joints>; 8] {
        self.ur_branches(base, flange, near, &self.limits)
    }

    /// Which closed-form branch (the index of [`Arm::ur_ik_branches`]:
    /// shoulder, wrist, elbow) joints `q` are on: the branch whose
    /// solution for `q`'s own flange pose is `q`. `None` on a non-UR arm,
    /// or where no branch's solution is `q` (outside the limits).
    pub fn ur_branch(&self, base: &Isometry3<f64>, q: &Joints) -> Option<usize> {
        let flange = self.flange_pose(base, q);
        // A calibrated arm's solutions are polished to the pose: `q` to
        // within what the polishing leaves.
        let tolerance = match &self.ur {
            Some(g) if !g.exact => POLISHED_BRANCH_TOLERANCE,
            _ => BRANCH_TOLERANCE,
        };
        self.ur_ik_branches(base, &flange, q)
            .iter()
            .position(|s| s.is_some_and(|s| joint_distance(&s, q) < tolerance))
    }

    /// How far (rad) one of the learned loop's steps, which turn wrist 1
    /// against the shoulder and the elbow to keep the cup down, may turn
    /// the flange: 1e-6 on an exact UR arm (a step on another arm's wrist
    /// turns it far more); a milliradian on a calibrated one, whose
    /// shoulder, elbow and wrist 1 axes are parallel only to about that.
    pub fn cup_down_tolerance(&self) -> f64 {
        match &self.ur {
            Some(g) if !g.exact => 1e-3,
            _ => 1e-6,
        }
    }

    /// [`Arm::ur_ik_branches`] within the given limits.
    fn ur_branches(
        &self,
        base: &Isometry3<f64>,
        flange: &Isometry3<f64>,
        near: &Joints,
        limits: &[Limits; DOF],
    ) -> [Option<Joints>; 8] {
        let mut out = [None; 8];
        let Some(g) = &self.ur else { return out };
        if !(finite_iso(base) && finite_iso(flange) && near.iter().all(|v| v.is_finite())) {
            return out;
        }
        // The last link's pose in the base frame, then in the DH base frame.
        let target = base.inverse() * flange;
        let last = g.mount.inverse() * target * self.flange.inverse();
        for (slot, raw) in out.iter_mut().zip(closed_form::solve(g, &last, near)) {
            *slot = raw
                .and_then(|q| wrap_all(&q, near, limits))
                .and_then(|q| self.verified(&target, q, near, limits));
        }
        out
    }

    /// Damped least squares on the flange pose error (position in metres,
    /// orientation in radians), at most 200 steps from each of `near` with
    /// the base joint first aimed at the target and `near` itself; the
    /// converged solution nearest `near`, else `None`. Being local, it finds
    /// the solution whose branch `near` is in (it does not cross the
    /// stretched or folded elbow).
    pub fn numeric_ik(
        &self,
        base: &Isometry3<f64>,
        flange: &Isometry3<f64>,
        near: &Joints,
    ) -> Option<Joints> {
        if !(finite_iso(base) && finite_iso(flange) && near.iter().all(|v| v.is_finite())) {
            return None;
        }
        let target = base.inverse() * flange;
        let mut seeds = vec![*near];
        if let Some(aimed) = numeric::aim_base(self, &target, near) {
            seeds.insert(0, aimed);
        }
        let solve = |seeds: &[Joints]| {
            let solutions = seeds.iter().filter_map(|seed| {
                let q = numeric::solve(self, &target, seed, 200)?;
                wrap_all(&q, near, &self.limits)
                    .and_then(|q| self.verified(&target, q, near, &self.limits))
            });
            nearest(solutions, near)
        };
        // Being local, the descent fails from a seed far from any solution
        // (an arm whose joints `near` names poses of another convention,
        // such as the UR "ready" pose): then from spread seeds, each aimed.
        solve(&seeds).or_else(|| solve(&self.spread_seeds(&target)))
    }

    /// Seeds across the joint ranges for [`Arm::numeric_ik`]'s second try:
    /// the middle of every range (within ±π), with the shoulder and the
    /// elbow (joints 2 and 3) on a 5 × 5 grid over theirs and the wrist's
    /// middle joint (5) at a quarter and three quarters of its range, the
    /// base aimed at `target`; tried only where the first seeds failed.
    fn spread_seeds(&self, target: &Isometry3<f64>) -> Vec<Joints> {
        let at = |i: usize, share: f64| {
            let l = &self.limits[i];
            let (lo, hi) = (l.lower.max(-PI), l.upper.min(PI));
            lo + share * (hi - lo)
        };
        let middle: Joints = std::array::from_fn(|i| at(i, 0.5));
        let shares = [0.1, 0.3, 0.5, 0.7, 0.9];
        let mut seeds = Vec::with_capacity(50);
        for wrist in [0.25, 0.75] {
            for a in shares {
                for b in shares {
                    let mut q = middle;
                    q[1] = at(1, a);
                    q[2] = at(2, b);
                    q[4] = at(4, wrist);
                    seeds.push(numeric::aim_base(self, target, &q).unwrap_or(q));
                }
            }
        }
        seeds
    }

    /// `q` if it puts the flange at `target` (base frame) within
    /// [`IK_TOLERANCE`], after a few polishing steps if needed.
    fn verified(
        &self,
        target: &Isometry3<f64>,
        q: Joints,
        near: &Joints,
        limits: &[Limits; DOF],
    ) -> Option<Joints> {
        let id = Isometry3::identity();
        if pose_error(&self.flange_pose(&id, &q), target) <= IK_TOLERANCE {
            return Some(q);
        }
        let q = numeric::solve(self, target, &q, 20)?;
        let q = wrap_all(&q, near, limits)?;
        (pose_error(&self.flange_pose(&id, &q), target) <= IK_TOLERANCE).then_some(q)
    }

    /// Whether the cup axis (flange z) is the last joint's axis, so that
    /// turning joint 6 only changes the cup's yaw.
    fn tool_on_last_axis(&self) -> bool {
        let axis = self.axes[DOF - 1].into_inner();
        let z = self.flange.rotation * Vector3::z();
        let offset = self.flange.translation.vector;
        z.cross(&axis).norm() < 1e-9 && offset.cross(&axis).norm() < 1e-9
    }

    /// The world yaw of the flange x axis at `q` (0 when it is vertical).
    fn flange_yaw(&self, base: &Isometry3<f64>, q: &Joints) -> f64 {
        let x = self.flange_pose(base, q).rotation * Vector3::x();
        if x.x.hypot(x.y) > 1e-6 {
            x.y.atan2(x.x)
        } else {
            0.0
        }
    }
}

/// The larger of the position and orientation errors between two poses.
fn pose_error(a: &Isometry3<f64>, b: &Isometry3<f64>) -> f64 {
    let d = (a.translation.vector - b.translation.vector).norm();
    let r = a.rotation.angle_to(&b.rotation);
    if d.is_nan() || r.is_nan() {
        f64::INFINITY
    } else {
        d.max(r)
    }
}

/// The candidate nearest `near`, if any.
fn nearest(candidates: impl IntoIterator<Item = Joints>, near: &Joints) -> Option<Joints> {
    candidates
        .into_iter()
        .map(|q| (joint_distance(&q, near), q))
        .filter(|(d, _)| d.is_finite())
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, q)| q)
}

impl Arm {
    /// The same pose as `q` within the joint limits: each joint already
    /// within its limits is kept, each other one is turned by the multiple
    /// of 2π (every joint is revolute) that brings it within its limits
    /// nearest `near`; `None` when no turn fits.
    pub fn into_limits(&self, q: &Joints, near: &Joints) -> Option<Joints> {
        let mut out = *q;
        for (i, l) in self.limits.iter().enumerate() {
            if !l.contains(q[i]) {
                out[i] = wrap_near(q[i], near[i], l)?;
            }
        }
        Some(out)
    }
}

/// Each joint at the 2π turn nearest `near` within its limits.
fn wrap_all(q: &Joints, near: &Joints, limits: &[Limits; DOF]) -> Option<Joints> {
    let mut out = [0.0; DOF];
    for i in 0..DOF {
        out[i] = wrap_near(q[i], near[i], &limits[i])?;
    }
    Some(out)
}

/// `theta + 2πk` nearest `near` within `[lower, upper]` (with a 1e-9 rad
/// allowance, then clamped), or `None` if no turn fits.
fn wrap_near(theta: f64, near: f64, l: &Limits) -> Option<f64> {
    const SLACK: f64 = 1e-9;
    let k_min = ((l.lower - SLACK - theta) / TAU).ceil();
    let k_max = ((l.upper + SLACK - theta) / TAU).floor();
    if k_min.is_nan() || k_max.is_nan() || k_min > k_max {
        return None;
    }
    let k = ((near - theta) / TAU).round().max(k_min).min(k_max);
    let v = (theta + k * TAU).max(l.lower).min(l.upper);
    v.is_finite().then_some(v)
}

fn finite(v: &Vector3<f64>) -> bool {
    v.iter().all(|x| x.is_finite())
}

fn finite_iso(p: &Isometry3<f64>) -> bool {
    finite(&p.translation.vector) && p.rotation.coords.iter().all(|x| x.is_finite())
}
