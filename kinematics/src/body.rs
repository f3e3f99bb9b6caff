//! The one collision description of a cell, shared by the planner's
//! checker (`packwright-motion`) and the simulator (`packwright-sim`):
//! the arm's parts (every link's shapes and the suction cup), which part
//! pairs are never checked, and the fixtures (the table, each box's floor
//! and walls). Both build their geometry from these functions, so a motion
//! the planner calls free meets the same bodies in the simulator; the
//! planner only adds [`PADDING`] around the arm as a safety margin.
//!
//! parry works in f32 with glam types; [`pose`] and [`vector`] are the
//! conversion from the robot model's f64 nalgebra types.

use crate::{Arm, DOF, Joints, Shape};
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use packwright_interface::scene::CellScene;
use packwright_interface::world::Body;
use parry3d::math::{Pose, Vector};
use parry3d::query;
use parry3d::shape::{Capsule, Cuboid, Shape as ParryShape, SharedShape};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Radius of the suction cup, metres.
pub const CUP_RADIUS: f64 = 0.02;
/// The cup's body stops this far above the tool tip (metres), so that the
/// tip reaching a product's top face is not a collision.
pub const CUP_SHORT: f64 = 0.005;
/// Thickness of a box's walls and floor, metres.
pub const BOX_WALL: f64 = 0.004;
/// Thickness of the table slab (its top is z = 0), metres.
pub const TABLE_THICKNESS: f64 = 0.1;
/// The planner's margin around the arm's parts, metres.
pub const PADDING: f64 = 0.01;
/// The planner's margin around a held product, metres (it must go down
/// into a slot that fits it with little room).
pub const HELD_PADDING: f64 = 0.003;
/// The cup's index among the arm parts (0..=6 are the links, 0 the base).
pub const CUP: usize = DOF + 1;

/// A robot-model pose as a parry pose.
pub fn pose(iso: &Isometry3<f64>) -> Pose {
    let t = iso.translation.vector;
    let q = iso.rotation.quaternion();
    Pose::from_parts(
        vector(&t),
        parry3d::glamx::Quat::from_xyzw(q.i as f32, q.j as f32, q.k as f32, q.w as f32).normalize(),
    )
}

/// A robot-model vector (or a point's coordinates) as a parry vector.
pub fn vector(v: &Vector3<f64>) -> Vector {
    Vector::new(v.x as f32, v.y as f32, v.z as f32)
}

fn point(p: &Point3<f64>) -> Vector {
    vector(&p.coords)
}

/// One collision primitive of the arm, rigidly attached to a part.
#[derive(Clone)]
pub struct ArmPart {
    /// 0..=6 the links (0 the fixed base link), [`CUP`] the cup (on the
    /// last link).
    pub part: usize,
    /// Pose in the link's frame.
    pub local: Isometry3<f64>,
    pub shape: SharedShape,
}

impl ArmPart {
    /// The link that carries this part (the cup rides on the last link).
    pub fn link(&self) -> usize {
        self.part.min(DOF)
    }
}

/// The arm's parts, each grown by `padding`: every link's capsules and
/// cuboids, and the cup, a capsule of radius [`CUP_RADIUS`] down the
/// flange's z axis whose rounded end stays [`CUP_SHORT`] above the tool
/// tip, grown by `padding` like the rest, downwards too. (Grown only
/// sideways, its end kept no margin below it: a blended back-up from a
/// release swung the cup over a box's wall with its end on the rim, free
/// for the planner and a contact in the simulator. The product the cup
/// comes down onto is not an obstacle for it: a check ignores it.)
pub fn arm_parts(arm: &Arm, suction: f64, padding: f64) -> Vec<ArmPart> {
    let mut parts = Vec::new();
    for (i, link) in arm.links.iter().enumerate() {
        for s in &link.shapes {
            parts.push(match s {
                Shape::Capsule { a, b, radius } => ArmPart {
                    part: i,
                    local: Isometry3::identity(),
                    shape: SharedShape::capsule(point(a), point(b), (radius + padding) as f32),
                },
                Shape::Cuboid { pose, half } => {
                    let h = half.add_scalar(padding);
                    ArmPart {
                        part: i,
                        local: *pose,
                        shape: SharedShape::cuboid(h.x as f32, h.y as f32, h.z as f32),
                    }
                }
                Shape::Cylinder { a, b, radius } => {
                    // parry's cylinders stand along their y axis; grown by
                    // `padding` all round (edges rounded).
                    let axis = b - a;
                    let turn = UnitQuaternion::rotation_between(&Vector3::y(), &axis)
                        .unwrap_or_else(|| {
                            UnitQuaternion::from_euler_angles(std::f64::consts::PI, 0.0, 0.0)
                        });
                    let half = (axis.norm() / 2.0) as f32;
                    ArmPart {
                        part: i,
                        local: Isometry3::from_parts(
                            Translation3::from(a.coords + axis / 2.0),
                            turn,
                        ),
                        shape: if padding > 0.0 {
                            SharedShape::round_cylinder(half, *radius as f32, padding as f32)
                        } else {
                            SharedShape::cylinder(half, *radius as f32)
                        },
                    }
                }
            });
        }
    }
    let radius = CUP_RADIUS + padding;
    let end = (suction - CUP_SHORT - CUP_RADIUS).max(0.0);
    parts.push(ArmPart {
        part: CUP,
        local: arm.flange,
        shape: SharedShape::capsule(
            Vector::ZERO,
            Vector::new(0.0, 0.0, end as f32),
            radius as f32,
        ),
    });
    parts
}

/// The room the last link (the wrist's end, just above the cup) takes
/// round the tool axis: its shapes' farthest reach from the flange's z
/// axis, and how far they reach past the flange face towards the tool
/// (negative: they stop short of it), metres, without padding; `None`
/// for a last link without shapes. With the cup down, the link goes into
/// a box only as far as this radius fits inside the walls.
pub fn wrist_around_tool(arm: &Arm) -> Option<(f64, f64)> {
    let link = arm.links.last()?;
    let to_flange = arm.flange.inverse();
    // Each shape's points (in the flange frame) and the radius round them.
    let points = link.shapes.iter().flat_map(|s| match s {
        Shape::Capsule { a, b, radius } | Shape::Cylinder { a, b, radius } => {
            vec![(to_flange * a, *radius), (to_flange * b, *radius)]
        }
        Shape::Cuboid { pose, half } => (0..8)
            .map(|i| {
                let corner = Point3::new(
                    if i & 1 == 0 { -half.x } else { half.x },
                    if i & 2 == 0 { -half.y } else { half.y },
                    if i & 4 == 0 { -half.z } else { half.z },
                );
                (to_flange * (pose * corner), 0.0)
            })
            .collect(),
    });
    points.fold(None, |room, (p, r)| {
        let (radial, past) = (p.x.hypot(p.y) + r, p.z + r);
        Some(room.map_or((radial, past), |(a, b): (f64, f64)| {
            (a.max(radial), b.max(past))
        }))
    })
}

/// Whether parts `a` and `b` are the same link or neighbours along the
/// chain (the cup's neighbour is the last link): never checked.
pub fn adjacent(a: usize, b: usize) -> bool {
    a.abs_diff(b) <= 1
}

/// What a part is called in contacts.
pub fn part_body(arm: &Arm, part: usize) -> Body {
    match arm.links.get(part) {
        Some(link) if part != CUP => Body::Link(link.name.clone()),
        _ if part == CUP => Body::Cup,
        _ => Body::Link(format!("link{part}")),
    }
}

/// Non-adjacent part pairs that touch by construction, never checked:
/// those in contact at the zero pose, or in at least 90% of 256 seeded
/// random configurations, with the planner's padding (on a real arm they
/// are neighbours whose simplified shapes overlap). Sorted `(low, high)`.
pub fn touching_pairs(arm: &Arm, suction: f64) -> Vec<(usize, usize)> {
    let parts = arm_parts(arm, suction, PADDING);
    let base = Isometry3::identity();
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    let samples = 256usize;
    let n = CUP + 1;
    let mut counts = vec![0usize; n * n];
    let mut allowed = Vec::new();
    for k in 0..=samples {
        let q: Joints = if k == 0 {
            [0.0; DOF]
        } else {
            std::array::from_fn(|j| {
                let l = &arm.limits[j];
                let (lo, hi) = (
                    l.lower.max(-std::f64::consts::PI),
                    l.upper.min(std::f64::consts::PI),
                );
                if lo < hi {
                    rng.random_range(lo..=hi)
                } else {
                    lo
                }
            })
        };
        let links = arm.link_poses(&base, &q);
        let poses: Vec<Pose> = parts
            .iter()
            .map(|p| pose(&(links[p.link()] * p.local)))
            .collect();
        let mut hits = Vec::new();
        for (i, a) in parts.iter().enumerate() {
            for (j, b) in parts.iter().enumerate().skip(i + 1) {
                let (la, lb) = (a.part.min(b.part), a.part.max(b.part));
                if adjacent(la, lb) || hits.contains(&(la, lb)) {
                    continue;
                }
                if intersects(&poses[i], &*a.shape, &poses[j], &*b.shape) {
                    hits.push((la, lb));
                }
            }
        }
        for pair in hits {
            if k == 0 {
                allowed.push(pair);
            } else {
                counts[pair.0 * n + pair.1] += 1;
            }
        }
    }
    for i in 0..n {
        for j in i + 1..n {
            if counts[i * n + j] * 10 >= samples * 9 && !allowed.contains(&(i, j)) {
                allowed.push((i, j));
            }
        }
    }
    allowed.sort_unstable();
    allowed
}

/// Whether two shapes intersect: parry's answer ([`exact_intersects`]).
/// A pair with a cylinder (a collision mesh's bound) is first tried with
/// the capsule round the cylinder, which can only say "apart".
///
/// Two capsules (every arm part of the UR10) are first decided by the
/// distance between their axis segments, computed in closed form (f64,
/// from the same f32 poses and shapes parry is given): farther apart than
/// the sum of their radii by more than [`DECIDED_MARGIN`], they are apart;
/// nearer by more than it, they intersect. Only a pair within the margin
/// of touching goes to parry's GJK. The margin is about a thousand times
/// GJK's own tolerance on these shapes (its termination threshold is
/// 1.2e-6 relative, on shapes of about a metre), so the answer is parry's
/// (property-tested against it in `tests/intersects.rs`).
///
/// A capsule and a cuboid (an arm part or the cup against a product, a
/// box's wall, the table; a held product against a link) are decided in
/// closed form, exactly: the distance from the capsule's segment to the
/// cuboid against its radius ([`segment_box_distance_squared`]). Parry
/// 0.31's GJK says "intersecting" for some such pairs millimetres apart,
/// a capsule pointing straight down beside a box (helper T's probe cell
/// 6302: the cup, 3 and 5 mm clear of a 16 mm cube beside the one it
/// picks, refused the pick with every planner; 60 of 200,000 random
/// cup-down pairs near a box).
pub fn intersects(p1: &Pose, s1: &dyn ParryShape, p2: &Pose, s2: &dyn ParryShape) -> bool {
    if let (Some(c1), Some(c2)) = (s1.as_capsule(), s2.as_capsule())
        && let Some(answer) = capsules_decided(p1, c1, p2, c2)
    {
        return answer;
    }
    if let Some(answer) = capsule_and_cuboid(p1, s1, p2, s2) {
        return answer;
    }
    !cylinder_apart(p1, s1, p2, s2) && parry_intersects(p1, s1, p2, s2)
}

/// Whether a capsule meets a cuboid: the squared distance from its
/// segment to the cuboid (in the cuboid's frame, f64 from parry's f32
/// poses) against its squared radius; touching counts. `None` for
/// anything not finite.
fn capsule_meets_cuboid(pc: &Pose, c: &Capsule, pb: &Pose, b: &Cuboid) -> Option<bool> {
    let local = |v: Vector| {
        let w = pb.inverse_transform_point(pc.transform_point(v));
        [f64::from(w.x), f64::from(w.y), f64::from(w.z)]
    };
    let h = b.half_extents;
    let h = [f64::from(h.x), f64::from(h.y), f64::from(h.z)];
    let d2 = segment_box_distance_squared(local(c.segment.a), local(c.segment.b), h);
    let r = f64::from(c.radius);
    (d2.is_finite() && r.is_finite()).then_some(d2 <= r * r)
}

/// The squared distance from the segment `a`–`e` to the box centred at
/// the origin with half extents `half` (axis-aligned), exactly: along the
/// segment it is convex and, between the parameters where the segment
/// crosses a face's plane, a quadratic of its own; its least value is at
/// one of those parameters or at a quadratic's minimum between them.
pub fn segment_box_distance_squared(a: [f64; 3], e: [f64; 3], half: [f64; 3]) -> f64 {
    let d = [e[0] - a[0], e[1] - a[1], e[2] - a[2]];
    let at = |t: f64| -> f64 {
        (0..3)
            .map(|k| {
                let out = ((a[k] + t * d[k]).abs() - half[k]).max(0.0);
                out * out
            })
            .sum()
    };
    let mut cuts: SmallCuts = [0.0; 8];
    let mut n = 0;
    cuts[n] = 0.0;
    n += 1;
    for k in 0..3 {
        if d[k] != 0.0 {
            for face in [-half[k], half[k]] {
                let t = (face - a[k]) / d[k];
                if t > 0.0 && t < 1.0 {
                    cuts[n] = t;
                    n += 1;
                }
            }
        }
    }
    cuts[n] = 1.0;
    n += 1;
    let cuts = &mut cuts[..n];
    cuts.sort_by(f64::total_cmp);
    let mut best = at(0.0).min(at(1.0));
    for w in cuts.windows(2) {
        let (lo, hi) = (w[0], w[1]);
        let mid = (lo + hi) / 2.0;
        // On (lo, hi) each axis is inside its slab or beyond one face.
        let (mut dd, mut dc) = (0.0, 0.0);
        for k in 0..3 {
            let p = a[k] + mid * d[k];
            let face = if p > half[k] {
                half[k]
            } else if p < -half[k] {
                -half[k]
            } else {
                continue;
            };
            dd += d[k] * d[k];
            dc += d[k] * (a[k] - face);
        }
        if dd > 0.0 {
            best = best.min(at((-dc / dd).clamp(lo, hi)));
        }
    }
    best
}

/// The parameters where a segment may change its quadratic piece: its
/// two ends and up to six face planes.
type SmallCuts = [f64; 8];

/// The capsule round a cylinder (a collision mesh's bound): the same
/// axis segment and radius (and rounded border) hold it. `None` for any
/// other shape.
fn enclosing_capsule(s: &dyn ParryShape) -> Option<Capsule> {
    if let Some(c) = s.as_cylinder() {
        return Some(Capsule::new_y(c.half_height, c.radius));
    }
    let c = s.as_round_cylinder()?;
    Some(Capsule::new_y(
        c.inner_shape.half_height,
        c.inner_shape.radius + c.border_radius,
    ))
}

/// Whether a pair with a cylinder is surely apart, by the capsule round
/// it: capsules decided apart in closed form, or a capsule clear of a
/// cuboid (apart round the cylinder is apart from it; anything else is
/// left to parry).
fn cylinder_apart(p1: &Pose, s1: &dyn ParryShape, p2: &Pose, s2: &dyn ParryShape) -> bool {
    let (e1, e2) = (enclosing_capsule(s1), enclosing_capsule(s2));
    if e1.is_none() && e2.is_none() {
        return false;
    }
    let c1 = e1.as_ref().or(s1.as_capsule());
    let c2 = e2.as_ref().or(s2.as_capsule());
    match (c1, c2) {
        (Some(a), Some(b)) => capsules_decided(p1, a, p2, b) == Some(false),
        (Some(a), None) => s2
            .as_cuboid()
            .is_some_and(|b| capsule_clear_of_cuboid(p1, a, p2, b)),
        (None, Some(b)) => s1
            .as_cuboid()
            .is_some_and(|a| capsule_clear_of_cuboid(p2, b, p1, a)),
        (None, None) => false,
    }
}

/// Whether two shapes intersect, the reference answer without
/// [`intersects`]'s shortcuts: a capsule and a cuboid in closed form
/// (exactly; see [`intersects`]), any other pair by parry's GJK. An
/// unsupported pair cannot happen with capsules and cuboids; it counts as
/// a collision, to stay on the safe side.
pub fn exact_intersects(p1: &Pose, s1: &dyn ParryShape, p2: &Pose, s2: &dyn ParryShape) -> bool {
    capsule_and_cuboid(p1, s1, p2, s2).unwrap_or_else(|| parry_intersects(p1, s1, p2, s2))
}

/// Parry's answer (GJK); an unsupported pair counts as a collision.
fn parry_intersects(p1: &Pose, s1: &dyn ParryShape, p2: &Pose, s2: &dyn ParryShape) -> bool {
    query::intersection_test(p1, s1, p2, s2).map_or(true, |i| i.intersecting)
}

/// A capsule and a cuboid's answer, in either order ([`capsule_meets_cuboid`]);
/// `None` for any other pair.
fn capsule_and_cuboid(
    p1: &Pose,
    s1: &dyn ParryShape,
    p2: &Pose,
    s2: &dyn ParryShape,
) -> Option<bool> {
    match (s1.as_capsule(), s2.as_cuboid()) {
        (Some(c), Some(b)) => capsule_meets_cuboid(p1, c, p2, b),
        _ => match (s1.as_cuboid(), s2.as_capsule()) {
            (Some(b), Some(c)) => capsule_meets_cuboid(p2, c, p1, b),
            _ => None,
        },
    }
}

/// How far from touching (m) two capsules must be, apart or into each
/// other, for [`intersects`] to answer without GJK.
pub const DECIDED_MARGIN: f64 = 1e-3;

/// Two capsules' answer when the distance between their axes is more than
/// [`DECIDED_MARGIN`] from the sum of their radii; `None` otherwise (or
/// for anything not finite).
fn capsules_decided(p1: &Pose, c1: &Capsule, p2: &Pose, c2: &Capsule) -> Option<bool> {
    let world = |p: &Pose, v: Vector| {
        let w = p.transform_point(v);
        [f64::from(w.x), f64::from(w.y), f64::from(w.z)]
    };
    let d2 = segments_distance_squared(
        world(p1, c1.segment.a),
        world(p1, c1.segment.b),
        world(p2, c2.segment.a),
        world(p2, c2.segment.b),
    );
    let reach = f64::from(c1.radius) + f64::from(c2.radius);
    let d = d2.sqrt();
    if !(d.is_finite() && reach.is_finite()) {
        None
    } else if d > reach + DECIDED_MARGIN {
        Some(false)
    } else if d < reach - DECIDED_MARGIN {
        Some(true)
    } else {
        None
    }
}

/// Whether a plane separates a capsule from a cuboid by more than
/// [`DECIDED_MARGIN`]: a separating-axis test on the cuboid's three axes
/// and the three crosses of the capsule's axis with them (the capsule's
/// projection on a unit axis is its segment's, grown by its radius).
/// `false` says nothing: GJK decides.
fn capsule_clear_of_cuboid(pc: &Pose, c: &Capsule, pb: &Pose, b: &Cuboid) -> bool {
    // The segment in the cuboid's frame, in f64.
    let local = |v: Vector| {
        let w = pb.inverse_transform_point(pc.transform_point(v));
        [f64::from(w.x), f64::from(w.y), f64::from(w.z)]
    };
    let (a, e) = (local(c.segment.a), local(c.segment.b));
    let h = [
        f64::from(b.half_extents.x),
        f64::from(b.half_extents.y),
        f64::from(b.half_extents.z),
    ];
    let r = f64::from(c.radius);
    if !(a.iter().chain(&e).chain(&h).all(|x| x.is_finite()) && r.is_finite()) {
        return false;
    }
    let clear = DECIDED_MARGIN + r;
    // The cuboid's axes.
    for k in 0..3 {
        if a[k].min(e[k]) > h[k] + clear || a[k].max(e[k]) < -h[k] - clear {
            return true;
        }
    }
    // The segment's direction crossed with each axis.
    let d = [e[0] - a[0], e[1] - a[1], e[2] - a[2]];
    for k in 0..3 {
        let mut n = [0.0; 3];
        n[(k + 1) % 3] = d[(k + 2) % 3];
        n[(k + 2) % 3] = -d[(k + 1) % 3];
        let norm = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        if norm < 1e-9 {
            continue;
        }
        let s = (a[0] * n[0] + a[1] * n[1] + a[2] * n[2]) / norm;
        let extent = (h[0] * n[0].abs() + h[1] * n[1].abs() + h[2] * n[2].abs()) / norm;
        if s.abs() > extent + clear {
            return true;
        }
    }
    false
}

/// The squared distance between segments `p1`–`q1` and `p2`–`q2`
/// (Ericson, *Real-Time Collision Detection*, 5.1.9; degenerate segments
/// are points).
pub fn segments_distance_squared(p1: [f64; 3], q1: [f64; 3], p2: [f64; 3], q2: [f64; 3]) -> f64 {
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let d1 = sub(q1, p1);
    let d2 = sub(q2, p2);
    let r = sub(p1, p2);
    let a = dot(d1, d1);
    let e = dot(d2, d2);
    let f = dot(d2, r);
    const TINY: f64 = 1e-18;
    let (s, t) = if a <= TINY && e <= TINY {
        (0.0, 0.0)
    } else if a <= TINY {
        (0.0, (f / e).clamp(0.0, 1.0))
    } else {
        let c = dot(d1, r);
        if e <= TINY {
            ((-c / a).clamp(0.0, 1.0), 0.0)
        } else {
            let b = dot(d1, d2);
            let denom = a * e - b * b;
            let mut s = if denom > TINY * a * e {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let mut t = (b * s + f) / e;
            if t < 0.0 {
                t = 0.0;
                s = (-c / a).clamp(0.0, 1.0);
            } else if t > 1.0 {
                t = 1.0;
                s = ((b - c) / a).clamp(0.0, 1.0);
            }
            (s, t)
        }
    };
    let c1 = [p1[0] + d1[0] * s, p1[1] + d1[1] * s, p1[2] + d1[2] * s];
    let c2 = [p2[0] + d2[0] * t, p2[1] + d2[1] * t, p2[2] + d2[2] * t];
    let g = sub(c1, c2);
    dot(g, g)
}

/// Who a fixture belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Owner {
    Table,
    /// Index into [`CellScene::boxes`].
    Box(usize),
}

/// A fixed cuboid of the cell.
#[derive(Debug, Clone, PartialEq)]
pub struct Fixture {
    pub owner: Owner,
    /// World position of the centre.
    pub centre: [f64; 3],
    pub half: [f64; 3],
}

impl Fixture {
    /// What the fixture is called in contacts.
    pub fn body(&self, cell: &CellScene) -> Body {
        match self.owner {
            Owner::Table => Body::Table,
            Owner::Box(k) => Body::Box(
                cell.boxes
                    .get(k)
                    .map_or_else(String::new, |b| b.name.clone()),
            ),
        }
    }
}

/// The cell's fixtures: the table (a [`TABLE_THICKNESS`] slab whose top is
/// z = 0, at least 4 m × 4 m, centred under the base, the pending area and
/// the boxes) and each box's floor (its top at z = 0, the table top: the
/// specification puts the floor at table height) and four walls inside the
/// outside footprint, from z = 0 to the box height, all [`BOX_WALL`] thick.
pub fn fixtures(cell: &CellScene) -> Vec<Fixture> {
    let mut lo = [cell.base[0], cell.base[1]];
    let mut hi = lo;
    let mut grow = |x: f64, y: f64| {
        lo = [lo[0].min(x), lo[1].min(y)];
        hi = [hi[0].max(x), hi[1].max(y)];
    };
    grow(cell.pending.0[0], cell.pending.0[1]);
    grow(cell.pending.1[0], cell.pending.1[1]);
    for b in &cell.boxes {
        grow(b.centre[0] - b.size[0] / 2.0, b.centre[1] - b.size[1] / 2.0);
        grow(b.centre[0] + b.size[0] / 2.0, b.centre[1] + b.size[1] / 2.0);
    }
    let half = |k: usize| ((hi[k] - lo[k]) / 2.0 + 0.5).max(2.0);
    let mut out = vec![Fixture {
        owner: Owner::Table,
        centre: [
            (lo[0] + hi[0]) / 2.0,
            (lo[1] + hi[1]) / 2.0,
            -TABLE_THICKNESS / 2.0,
        ],
        half: [half(0), half(1), TABLE_THICKNESS / 2.0],
    }];
    for (k, b) in cell.boxes.iter().enumerate() {
        let [w, d, h] = b.size;
        let [cx, cy] = b.centre;
        let t = BOX_WALL / 2.0;
        let parts = [
            ([0.0, 0.0, -t], [w / 2.0, d / 2.0, t]),
            ([-w / 2.0 + t, 0.0, h / 2.0], [t, d / 2.0, h / 2.0]),
            ([w / 2.0 - t, 0.0, h / 2.0], [t, d / 2.0, h / 2.0]),
            (
                [0.0, -d / 2.0 + t, h / 2.0],
                [w / 2.0 - BOX_WALL, t, h / 2.0],
            ),
            (
                [0.0, d / 2.0 - t, h / 2.0],
                [w / 2.0 - BOX_WALL, t, h / 2.0],
            ),
        ];
        for (at, half) in parts {
            out.push(Fixture {
                owner: Owner::Box(k),
                centre: [cx + at[0], cy + at[1], at[2]],
                half,
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cup_ends_short_of_the_tip_and_is_grown_downwards_too() {
        let arm = Arm::ur10();
        for padding in [0.0, PADDING] {
            let parts = arm_parts(&arm, 0.1, padding);
            let cup = parts.iter().find(|p| p.part == CUP).expect("a cup");
            let capsule = cup.shape.as_capsule().expect("a capsule");
            let end = f64::from(capsule.segment.b.z + capsule.radius);
            assert!((end - (0.1 - CUP_SHORT + padding)).abs() < 1e-6, "{end}");
            assert!((f64::from(capsule.radius) - (CUP_RADIUS + padding)).abs() < 1e-6);
        }
        assert!(adjacent(CUP, DOF) && !adjacent(CUP, DOF - 1));
        assert_eq!(part_body(&arm, CUP), Body::Cup);
    }

    /// The UR10's wrist 3 housing (ur10.urdf): a cylinder of radius 45
    /// mm round the tool axis from 90 to 10 mm above the flange, its
    /// capsule rounded 45 mm past each end.
    #[test]
    fn the_wrist_round_the_tool_axis_is_read_from_the_last_link() {
        let (radius, past) = wrist_around_tool(&Arm::ur10()).expect("shapes");
        assert!((radius - 0.045).abs() < 1e-9, "{radius}");
        assert!((past - 0.035).abs() < 1e-9, "{past}");
        let mut bare = Arm::ur10();
        if let Some(last) = bare.links.last_mut() {
            last.shapes.clear();
        }
        assert_eq!(wrist_around_tool(&bare), None);
    }
}
