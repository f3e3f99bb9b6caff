//! Collision checking for planning (parry3d), on the cell's one collision
//! description (`packwright_kinematics::body`, which the simulator builds
//! from too): the arm's parts grown by [`PADDING`], the held product
//! grown by [`HELD_PADDING`], the fixtures and products as they are, with
//! an axis-aligned bounding-box prefilter.
//!
//! What is checked: every arm part against the table (except the base and
//! shoulder links, which stand on it), the boxes and the products (the cup
//! may touch the one being picked from above only, and the one just
//! released anywhere: [`Touch`]); non-adjacent arm parts against each other (except
//! the pairs that touch by construction, `body::touching_pairs`); a held
//! product against everything but the cup and the last link, which hold
//! it. A motion between two configurations is checked at joint steps of at
//! most 1 degree; between two checked configurations the held product is
//! checked swept: the convex hull of its padded boxes at both
//! ([`Checker::sweep`]), which holds every point of the product on the
//! way to within [`Checker::sweep_slack`] (the bound checked, else the way
//! is split).
//!
//! Cost (issue 11): forward kinematics runs once per configuration, each
//! part's pose and box once; obstacles whose box misses the whole arm's are
//! skipped; narrow tests go through `body::intersects`, which decides
//! capsule pairs in closed form and goes to GJK only within 1 mm of
//! touching. The answers (which bodies included) are those of the plain
//! check, kept as the reference in this module's tests.

use nalgebra::{Isometry3, UnitQuaternion, Vector3};
use packwright_interface::outcome::Hit;
use packwright_interface::scene::{CellScene, Placement};
use packwright_interface::world::Body;
use packwright_kinematics::body::{self, ArmPart, CUP, HELD_PADDING, PADDING, intersects, pose};
use packwright_kinematics::{Arm, DOF, Joints};
use parry3d::bounding_volume::{Aabb, BoundingVolume};
use parry3d::math::{Pose, Vector};
use parry3d::query::details::intersection_test_support_map_support_map;
use parry3d::shape::{Cuboid, Shape as _, SharedShape, SupportMap};
use smallvec::SmallVec;

/// Arm parts whose poses a check keeps on the stack (the UR10 has 10);
/// an arm of more goes to the heap.
const STACK_PARTS: usize = 16;

/// Obstacles near the arm a check lists on the stack; more go to the
/// heap.
const STACK_NEAR: usize = 32;

/// Largest joint step when checking a motion, radians (1 degree).
pub const MAX_STEP: f64 = std::f64::consts::PI / 180.0;

/// How far a held product's points may stray from the convex hull of its
/// boxes at two checked configurations, on the way between them, for that
/// hull to stand for the way ([`Checker::sweep`]), as a share of its
/// padding: the product then keeps two thirds of its padding clear of
/// whatever the padded hull misses. Checking the boxes at the two
/// configurations alone is not enough: a 70 mm vase carried 0.9 m from the
/// base moved 16 mm between configurations a degree apart and grazed a
/// neighbouring product's corner, which a check of the commands in
/// between would have seen (found by a probe of hand-written cells;
/// `tests::a_held_product_is_checked_between_the_checked_configurations`).
pub const SWEEP_SLACK_SHARE: f64 = 1.0 / 3.0;

/// The slack allowed when the padding is less than this (m): a checker
/// without padding cannot keep the promise above, and is not asked to
/// split the way ever finer.
const MIN_SWEEP_SLACK: f64 = 0.0003;

/// How many times a sweep halves its way at most; a way that still
/// strays too far (not finite) is a collision ([`Hit::InvalidJoints`]).
const MAX_SWEEP_SPLITS: usize = 32;

/// How far, per radian of each joint, the points of a held product move
/// at a configuration (m/rad), at most: the distance from each joint's
/// axis to the centre of its padded box plus half the box's diagonal
/// ([`HeldPose::levers`]).
pub type LeverArms = [f64; DOF];

/// A bound on how far the held product moves from `a` to `b` along the
/// straight joint motion, with `levers` bounding its lever arms there.
pub fn held_move(levers: &LeverArms, a: &Joints, b: &Joints) -> f64 {
    levers
        .iter()
        .zip(a.iter().zip(b))
        .map(|(r, (x, y))| r * (y - x).abs())
        .sum()
}

/// A bound on how far the held product's points bow away from the chords
/// of their ways along the straight joint motion from `a` to `b` (m), with
/// `levers` bounding its lever arms there. A point's acceleration along the
/// motion (per unit of its parameter) is at most `3 Θ M`, with `Θ` the sum
/// of the joints' turns and `M` the [`held_move`] bound (each joint's turn
/// swings the axes after it and the point: two terms of at most `Θ r_j
/// |Δq_j|`, and the point's own `Θ r_j |Δq_j|`); a curve strays from its
/// chord by at most an eighth of its largest acceleration.
pub fn held_bow(levers: &LeverArms, a: &Joints, b: &Joints) -> f64 {
    let turned: f64 = a.iter().zip(b).map(|(x, y)| (y - x).abs()).sum();
    3.0 * turned * held_move(levers, a, b) / 8.0
}

/// The held product's padded box at a checked configuration, with its
/// lever arms there: what a swept check between two checked
/// configurations ([`Checker::sweep`]) needs.
#[derive(Debug, Clone, Copy)]
pub struct HeldPose {
    pose: Pose,
    cuboid: Cuboid,
    aabb: Aabb,
    /// How far its points move per radian of each joint.
    pub levers: LeverArms,
}

/// The convex hull of two boxes, `a` at the origin and `b` at `b_in_a`
/// (the support of either, whichever reaches farther).
struct TwoBoxes {
    a: Cuboid,
    b: Cuboid,
    b_in_a: Pose,
}

impl SupportMap for TwoBoxes {
    fn local_support_point(&self, dir: Vector) -> Vector {
        let on_a = self.a.local_support_point(dir);
        let on_b = self.b_in_a.transform_point(
            self.b
                .local_support_point(self.b_in_a.inverse_transform_vector(dir)),
        );
        if on_a.dot(dir) >= on_b.dot(dir) {
            on_a
        } else {
            on_b
        }
    }
}

/// A fixed or free-standing obstacle.
#[derive(Debug, Clone)]
struct Obstacle {
    body: Body,
    pose: Pose,
    shape: SharedShape,
    aabb: Aabb,
    /// The table: the base and shoulder links stand on it.
    is_table: bool,
    /// The height of its top face (it stands upright).
    top: f64,
}

/// How far (m) above the top face of the product it picks the cup's
/// unpadded body stays while it meets the product ([`Touch::Picking`]):
/// the simulator counts a contact within half a millimetre, and a checked
/// motion moves up to a degree between checked configurations. Cup down,
/// the tip may still go 2 mm under the face (the body ends 5 mm above it).
pub const TOUCH_CLEARANCE: f64 = 0.003;

/// A product the cup may touch ([`Checker::check`]), by name.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Touch<'a> {
    /// Being picked: the cup meets its top face from above. The cup
    /// (its body as the simulator has it, without the planner's padding,
    /// [`CUP_SHORT`](body::CUP_SHORT) short of the tip) may meet it
    /// while no point of that body is below the top face: then it cannot
    /// be inside the product (cup down, the tip up to `CUP_SHORT` under
    /// the face). Lower, or tilted into it, the cup may not meet it: a
    /// fallback's RRT-Connect path to the pick that swept the cup into
    /// the product's side passed the check, and the simulator saw the
    /// collision.
    Picking(&'a str),
    /// Just released: the cup may touch it anywhere (it lies where it
    /// landed, perhaps tilted against the cup), as the simulator allows.
    Released(&'a str),
}

impl<'a> Touch<'a> {
    /// The product touched.
    pub fn product(self) -> &'a str {
        match self {
            Touch::Picking(name) | Touch::Released(name) => name,
        }
    }

    /// Whether the cup, the lowest point of its unpadded body at height
    /// `bottom`, may meet the product whose top face is at `top`.
    fn allows(self, bottom: f64, top: f64) -> bool {
        match self {
            Touch::Picking(_) => bottom >= top + TOUCH_CLEARANCE,
            Touch::Released(_) => true,
        }
    }
}

/// The height of the lowest point of the cup's unpadded body (a capsule
/// of radius [`CUP_RADIUS`](body::CUP_RADIUS) along the flange's z axis,
/// ending [`CUP_SHORT`](body::CUP_SHORT) above the tip of a cup
/// `suction` long) with the flange at `flange`.
fn cup_bottom(flange: &Isometry3<f64>, suction: f64) -> f64 {
    let end = (suction - body::CUP_SHORT - body::CUP_RADIUS).max(0.0);
    let far = flange.transform_point(&nalgebra::Point3::new(0.0, 0.0, end));
    flange.translation.z.min(far.z) - body::CUP_RADIUS
}

impl Obstacle {
    /// Whether this is the product `name` names (none when `None`).
    fn is_product(&self, name: Option<&str>) -> bool {
        matches!(&self.body, Body::Product(n) if Some(n.as_str()) == name)
    }

    fn new(body: Body, centre: [f64; 3], half: [f64; 3], yaw: f64) -> Obstacle {
        let iso = Isometry3::new(
            Vector3::new(centre[0], centre[1], centre[2]),
            Vector3::z() * yaw,
        );
        let shape = SharedShape::cuboid(half[0] as f32, half[1] as f32, half[2] as f32);
        let pose = pose(&iso);
        let aabb = shape.compute_aabb(&pose);
        Obstacle {
            is_table: body == Body::Table,
            body,
            pose,
            shape,
            aabb,
            top: centre[2] + half[2],
        }
    }
}

/// A product carried by the cup.
#[derive(Debug, Clone, PartialEq)]
pub struct Held {
    pub name: String,
    /// Width, depth, height.
    pub size: [f64; 3],
    /// The product's centre pose in the flange frame.
    pub in_flange: Isometry3<f64>,
    /// Just gripped where it stood: it is checked with no margin below its
    /// bottom (but [`LIFT_CLEARANCE`]), so the surface it leaves is no
    /// obstacle while it rises, and going into that surface, or dragging
    /// down through it, still is.
    pub leaving_support: bool,
    /// The most its sides are padded (m; infinite: the checker's held
    /// padding): set by [`Checker::lifting`] for a product standing
    /// closer to a neighbour than that padding. A sweep's slack is a share
    /// of it too ([`Checker::sweep`]).
    pub side_pad: f64,
}

/// The room kept at the start of a lift between a product's padded sides
/// and its nearest neighbour (m), when the neighbour stands closer than
/// the padding ([`Checker::lifting`]).
pub const LIFT_ROOM: f64 = 0.0005;

/// The room kept between a lowered product's padded sides and the nearest
/// wall or product beside its slot ([`Checker::lowering`]): the release
/// is reached within half a millimetre, and as much again is left for
/// rounding and the flange's small tilt.
pub const LOWER_ROOM: f64 = 0.001;

/// How near (m) a standing product's footprint must come to a carried
/// product's for [`Checker::above_neighbours`] to ask that the carried one
/// hang above it.
pub const ABOVE_NEIGHBOURS: f64 = 0.02;

/// The least a lifted product's sides are padded ([`Checker::lifting`],
/// m): a neighbour closer than this and [`LIFT_ROOM`] together leaves the
/// product where it stands.
pub const MIN_SIDE_PAD: f64 = 0.0005;

/// How far above its bottom a product leaving its support is checked from
/// (m): the check box stops this short of the product's bottom, so that
/// resting on the surface is no collision. Below the simulator's 1 mm
/// tolerance for a held product's penetration.
pub const LIFT_CLEARANCE: f64 = 0.0005;

impl Held {
    /// The box the checker tests for this product hanging from `flange`
    /// (its pose and shape), grown by `pad` (its sides by no more than
    /// [`Held::side_pad`]). Leaving its support, the box
    /// keeps its margin above but ends [`LIFT_CLEARANCE`] short of the
    /// bottom (the product's +z is the flange's, pointing down).
    fn padded_box(&self, flange: &Isometry3<f64>, pad: f64) -> (Pose, Cuboid) {
        let (half_z, shift) = if self.leaving_support {
            let cut = pad + LIFT_CLEARANCE;
            (self.size[2] / 2.0 + pad - cut / 2.0, -cut / 2.0)
        } else {
            (self.size[2] / 2.0 + pad, 0.0)
        };
        let at = pose(&(flange * self.in_flange * Isometry3::translation(0.0, 0.0, shift)));
        let side = pad.min(self.side_pad);
        let cuboid = Cuboid::new(Vector::new(
            (self.size[0] / 2.0 + side) as f32,
            (self.size[1] / 2.0 + side) as f32,
            half_z as f32,
        ));
        (at, cuboid)
    }

    /// A product of `size` held by its top face under a cup `suction` long,
    /// its centre `beside` the cup's axis (flange frame, m; zero when the
    /// cup met the face at its centre), half its height below the tip.
    pub fn under_cup(name: &str, size: [f64; 3], suction: f64, beside: Vector3<f64>) -> Held {
        Held {
            name: name.to_owned(),
            size,
            in_flange: Isometry3::from_parts(
                (beside + Vector3::new(0.0, 0.0, suction + size[2] / 2.0)).into(),
                UnitQuaternion::identity(),
            ),
            leaving_support: false,
            side_pad: f64::INFINITY,
        }
    }

    /// The same product carried, no longer leaving its support: padded
    /// all round.
    pub fn carried(&self) -> Held {
        Held {
            leaving_support: false,
            side_pad: f64::INFINITY,
            ..self.clone()
        }
    }

    /// The same product while it is lifted off where it stood (the lift
    /// right after the grip).
    pub fn leaving_support(self) -> Held {
        Held {
            leaving_support: true,
            ..self
        }
    }
}

/// A product standing in the cell, for [`Checker::set_products`].
#[derive(Debug, Clone, PartialEq)]
pub struct ProductBody {
    pub name: String,
    pub centre: [f64; 3],
    pub size: [f64; 3],
    pub yaw: f64,
}

impl ProductBody {
    /// A product where it stands when a package starts (square: placements
    /// carry no yaw).
    pub fn at_start(p: &Placement) -> ProductBody {
        ProductBody {
            name: p.product.name.clone(),
            centre: p.centre,
            size: p.product.size,
            yaw: 0.0,
        }
    }
}

/// The part pairs a checker tests against each other: indices into
/// `parts`, `i < j` in order, whose links (the cup counted as its own
/// part) are not adjacent and not `allowed`.
fn checked_pairs(parts: &[ArmPart], allowed: &[(usize, usize)]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    for (i, a) in parts.iter().enumerate() {
        for (j, b) in parts.iter().enumerate().skip(i + 1) {
            let (la, lb) = (a.part.min(b.part), a.part.max(b.part));
            if !body::adjacent(la, lb) && !allowed.contains(&(la, lb)) {
                out.push((i, j));
            }
        }
    }
    out
}

/// Checks arm configurations and motions against a cell.
#[derive(Clone)]
pub struct Checker {
    arm: Arm,
    base: Isometry3<f64>,
    parts: Vec<ArmPart>,
    names: Vec<Body>,
    statics: Vec<Obstacle>,
    products: Vec<Obstacle>,
    /// Per part, whether its pose in its link is the identity.
    at_origin: Vec<bool>,
    /// The part pairs checked against each other (indices into `parts`,
    /// `i < j`, in that order): non-adjacent, and not among
    /// `body::touching_pairs`.
    pairs: Vec<(usize, usize)>,
    held_padding: f64,
    /// Length of the cup below the flange.
    suction: f64,
}

impl Checker {
    /// A checker for `arm` in `cell`, with no products yet, with the
    /// planner's margins ([`PADDING`], [`HELD_PADDING`]).
    pub fn new(arm: &Arm, cell: &CellScene) -> Checker {
        Checker::with_padding(arm, cell, PADDING, HELD_PADDING)
    }

    /// A checker whose arm parts are grown by `padding` and held products
    /// by `held_padding` (0 and 0: the simulator's bodies exactly).
    pub fn with_padding(arm: &Arm, cell: &CellScene, padding: f64, held_padding: f64) -> Checker {
        let base = Isometry3::translation(cell.base[0], cell.base[1], cell.base[2]);
        let parts = body::arm_parts(arm, cell.suction, padding);
        let names = (0..=CUP).map(|i| body::part_body(arm, i)).collect();
        let statics = body::fixtures(cell)
            .iter()
            .map(|f| Obstacle::new(f.body(cell), f.centre, f.half, 0.0))
            .collect();
        let allowed = body::touching_pairs(arm, cell.suction);
        let pairs = checked_pairs(&parts, &allowed);
        let at_origin = parts
            .iter()
            .map(|p| p.local == Isometry3::identity())
            .collect();
        Checker {
            arm: arm.clone(),
            base,
            parts,
            names,
            statics,
            products: Vec::new(),
            at_origin,
            pairs,
            held_padding,
            suction: cell.suction,
        }
    }

    /// The arm checked.
    pub fn arm(&self) -> &Arm {
        &self.arm
    }

    /// The robot base's pose in the world.
    pub fn base(&self) -> &Isometry3<f64> {
        &self.base
    }

    /// The length of the cup below the flange.
    pub fn suction(&self) -> f64 {
        self.suction
    }

    /// Replaces the free-standing products.
    pub fn set_products(&mut self, products: &[ProductBody]) {
        self.products = products
            .iter()
            .map(|p| {
                Obstacle::new(
                    Body::Product(p.name.clone()),
                    p.centre,
                    [p.size[0] / 2.0, p.size[1] / 2.0, p.size[2] / 2.0],
                    p.yaw,
                )
            })
            .collect();
    }

    /// This checker with the product `p` standing too.
    pub fn with_product(&self, p: &ProductBody) -> Checker {
        let mut checker = self.clone();
        checker.products.push(Obstacle::new(
            Body::Product(p.name.clone()),
            p.centre,
            p.size.map(|v| v / 2.0),
            p.yaw,
        ));
        checker
    }

    /// `held`, just gripped where it stands, lifted off
    /// ([`Held::leaving_support`]) with its sides padded no more than the
    /// room to its nearest neighbour leaves, less [`LIFT_ROOM`], and no
    /// less than [`MIN_SIDE_PAD`] (a sweep keeps its slack to a share of
    /// that, [`Checker::sweep`]). Products
    /// wait on a line a few millimetres apart, jittered closer; the lift
    /// takes one straight up from between them, where the full padding
    /// would meet a neighbour before it moves. Where it stands: the
    /// standing product of its name, else `standing` (none: the full
    /// padding).
    pub fn lifting(&self, held: Held, standing: Option<&ProductBody>) -> Held {
        let named = self
            .products
            .iter()
            .find(|o| o.is_product(Some(held.name.as_str())));
        let own;
        let at = match (named, standing) {
            (Some(o), _) => o,
            (None, Some(p)) => {
                own = Obstacle::new(
                    Body::Product(held.name.clone()),
                    p.centre,
                    p.size.map(|v| v / 2.0),
                    p.yaw,
                );
                &own
            }
            (None, None) => return held.leaving_support(),
        };
        let room = self.room_round(at, &held.name);
        let side_pad =
            (room - LIFT_ROOM).clamp(MIN_SIDE_PAD.min(self.held_padding), self.held_padding);
        Held {
            side_pad,
            ..held.leaving_support()
        }
    }

    /// Whether the carry of `held` (padded all round, no longer leaving
    /// its support) may start with the arm at `q`: it is free there, but
    /// the product `touch` names, and hangs above its neighbours
    /// ([`Checker::above_neighbours`]). What a lowered lift must leave.
    pub fn clear_to_carry(&self, q: &Joints, held: &Held, touch: Option<Touch>) -> bool {
        self.check(q, Some(&held.carried()), touch).is_none() && self.above_neighbours(q, held)
    }

    /// Whether `held`, carried with the arm at `q`, hangs above every
    /// standing product whose footprint comes within [`ABOVE_NEIGHBOURS`]
    /// of its own (the held product's padded bottom over their tops): a
    /// lift lowered until the product hangs beside a neighbour leaves the
    /// carry that follows, which moves it sideways, to meet it.
    pub fn above_neighbours(&self, q: &Joints, held: &Held) -> bool {
        let at = self.held_pose(q, &held.carried());
        let near = ABOVE_NEIGHBOURS as f32;
        let (lo, hi) = (at.aabb.mins, at.aabb.maxs);
        self.products
            .iter()
            .filter(|o| !o.is_product(Some(held.name.as_str())))
            .filter(|o| {
                o.aabb.maxs.x > lo.x - near
                    && o.aabb.mins.x < hi.x + near
                    && o.aabb.maxs.y > lo.y - near
                    && o.aabb.mins.y < hi.y + near
            })
            .all(|o| o.top < f64::from(lo.z))
    }

    /// `held`, carried down into its slot (the release): its sides padded
    /// no more than the room between it, standing at `centre` turned by
    /// `yaw`, and the nearest wall or product beside it leaves, less
    /// [`LOWER_ROOM`], and no less than [`MIN_SIDE_PAD`]. A snug slot
    /// (a tray 86 mm deep in a crate 90 mm inside) has less room than the
    /// full padding, which then kept every planner's release above the
    /// rim: the product dropped the box's depth and landed tilted.
    pub fn lowering(&self, held: Held, centre: [f64; 3], yaw: f64) -> Held {
        let at = Obstacle::new(
            Body::Product(held.name.clone()),
            centre,
            held.size.map(|v| v / 2.0),
            yaw,
        );
        let room = self.room_round(&at, &held.name);
        let side_pad =
            (room - LOWER_ROOM).clamp(MIN_SIDE_PAD.min(self.held_padding), self.held_padding);
        Held {
            side_pad,
            ..held.carried()
        }
    }

    /// The distance from a standing product's box `at` to the nearest
    /// other product or fixture beside it (reaching above its bottom:
    /// not what it stands on), but the product `name`.
    fn room_round(&self, at: &Obstacle, name: &str) -> f64 {
        let bottom = f64::from(at.aabb.mins.z);
        self.statics
            .iter()
            .chain(&self.products)
            .filter(|o| !o.is_product(Some(name)) && o.top > bottom + LIFT_CLEARANCE)
            .map(|o| {
                parry3d::query::distance(&at.pose, &*at.shape, &o.pose, &*o.shape)
                    .map_or(0.0, |d| f64::from(d.distance))
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// The first collision of the arm (and `held`) at joints `q`. The
    /// product `touch` names (the one being picked, or just released) may
    /// be touched by the cup alone, as [`Touch`] says: a link that reaches
    /// it still collides.
    ///
    /// In order (the first found is the answer): each part against the
    /// obstacles (the fixed ones, then the products), the checked part
    /// pairs, the held product against the obstacles, then against the
    /// links. Forward kinematics runs once: each part's pose and bounding
    /// box are computed once and shared by every test; an obstacle whose
    /// box misses the whole arm's is skipped for every part (it misses
    /// each part's).
    pub fn check(&self, q: &Joints, held: Option<&Held>, touch: Option<Touch>) -> Option<Hit> {
        if q.iter().any(|v| !v.is_finite()) {
            return Some(Hit::InvalidJoints);
        }
        let links = self.arm.link_poses(&self.base, q);
        self.check_links(&links, held, touch).err()
    }

    /// [`Checker::check`], with the held product's box and lever arms at
    /// `q` when it passes (`None` when nothing is held): forward kinematics
    /// runs once for both.
    pub fn check_posed(
        &self,
        q: &Joints,
        held: Option<&Held>,
        touch: Option<Touch>,
    ) -> Result<Option<HeldPose>, Hit> {
        if q.iter().any(|v| !v.is_finite()) {
            return Err(Hit::InvalidJoints);
        }
        let links = self.arm.link_poses(&self.base, q);
        let boxed = self.check_links(&links, held, touch)?;
        Ok(held.zip(boxed).map(|(h, (pose, cuboid, aabb))| HeldPose {
            pose,
            cuboid,
            aabb,
            levers: self.levers_at(&links, h),
        }))
    }

    /// [`Checker::check`] at the link poses `links`: the held product's
    /// padded box (its pose, shape and bounding box) when it passes.
    fn check_links(
        &self,
        links: &[Isometry3<f64>; DOF + 1],
        held: Option<&Held>,
        touch: Option<Touch>,
    ) -> Result<Option<(Pose, Cuboid, Aabb)>, Hit> {
        // Each part's pose and box, on the stack for an arm of up to
        // STACK_PARTS parts (no allocation per check).
        let mut placed: SmallVec<[(Pose, Aabb); STACK_PARTS]> = SmallVec::new();
        // A part placed at its link's origin has its link's pose (times
        // the identity, which changes no value): converted once per link.
        let mut last: Option<(usize, Pose)> = None;
        for (part, &at_origin) in self.parts.iter().zip(&self.at_origin) {
            let link = part.link();
            let p = match last {
                Some((l, p)) if at_origin && l == link => p,
                _ if at_origin => {
                    let p = pose(&links[link]);
                    last = Some((link, p));
                    p
                }
                _ => pose(&(links[link] * part.local)),
            };
            placed.push((p, part.shape.compute_aabb(&p)));
        }
        let placed = &placed[..];
        let whole = placed
            .iter()
            .map(|(_, b)| *b)
            .reduce(|a, b| a.merged(&b))
            .unwrap_or_else(Aabb::new_invalid);
        let held_name = held.map(|h| h.name.as_str());
        // The obstacles near the arm, the held product never one of them
        // (on the stack up to STACK_NEAR of them).
        let near: SmallVec<[&Obstacle; STACK_NEAR]> = self
            .statics
            .iter()
            .chain(&self.products)
            .filter(|o| o.aabb.intersects(&whole) && !o.is_product(held_name))
            .collect();
        let ignore = touch.map(Touch::product);
        // Where the cup meets the touched product: its lowest point.
        let bottom = || cup_bottom(&(links[DOF] * self.arm.flange), self.suction);
        for (part, (p, aabb)) in self.parts.iter().zip(placed) {
            let by_cup = part.part == CUP;
            for &o in &near {
                let touched = || {
                    by_cup
                        && o.is_product(ignore)
                        && touch.is_some_and(|t| t.allows(bottom(), o.top))
                };
                if (o.is_table && part.part <= 1) || touched() {
                    continue;
                }
                if aabb.intersects(&o.aabb) && intersects(p, &*part.shape, &o.pose, &*o.shape) {
                    return Err(Hit::Bodies {
                        a: self.names[part.part].clone(),
                        b: o.body.clone(),
                    });
                }
            }
        }
        for &(i, j) in &self.pairs {
            let ((pi, bi), (pj, bj)) = (&placed[i], &placed[j]);
            if bi.intersects(bj) && intersects(pi, &*self.parts[i].shape, pj, &*self.parts[j].shape)
            {
                let (a, b) = (self.parts[i].part, self.parts[j].part);
                return Err(Hit::Bodies {
                    a: self.names[a.min(b)].clone(),
                    b: self.names[a.max(b)].clone(),
                });
            }
        }
        let Some(h) = held else {
            return Ok(None);
        };
        let (hp, cuboid, aabb) = self.held_box(links, h);
        if let Some(hit) = self.held_meets_obstacles(h, (&hp, &cuboid, &aabb), ignore) {
            return Err(hit);
        }
        let name = || Body::Held(h.name.clone());
        for (part, (p, part_aabb)) in self.parts.iter().zip(placed) {
            if part.part < DOF
                && aabb.intersects(part_aabb)
                && intersects(&hp, &cuboid, p, &*part.shape)
            {
                return Err(Hit::Bodies {
                    a: name(),
                    b: self.names[part.part].clone(),
                });
            }
        }
        Ok(Some((hp, cuboid, aabb)))
    }

    /// The obstacles a held product may meet: all but itself and the one
    /// `ignore` names, those whose bounding box meets `aabb`.
    fn obstacles_near<'s>(
        &'s self,
        h: &'s Held,
        aabb: &'s Aabb,
        ignore: Option<&'s str>,
    ) -> impl Iterator<Item = &'s Obstacle> + 's {
        self.statics.iter().chain(&self.products).filter(move |o| {
            aabb.intersects(&o.aabb)
                && !o.is_product(Some(h.name.as_str()))
                && !o.is_product(ignore)
        })
    }

    /// The first obstacle the held product's padded box (`at` its pose,
    /// its bounding box `aabb`) meets, but the product itself and the one
    /// `ignore` names.
    fn held_meets_obstacles(
        &self,
        h: &Held,
        (at, cuboid, aabb): (&Pose, &Cuboid, &Aabb),
        ignore: Option<&str>,
    ) -> Option<Hit> {
        self.obstacles_near(h, aabb, ignore)
            .find(|o| intersects(at, cuboid, &o.pose, &*o.shape))
            .map(|o| Hit::Bodies {
                a: Body::Held(h.name.clone()),
                b: o.body.clone(),
            })
    }

    /// The held product's padded box at the link poses `links`: its pose,
    /// shape and bounding box.
    fn held_box(&self, links: &[Isometry3<f64>; DOF + 1], held: &Held) -> (Pose, Cuboid, Aabb) {
        // The flange from the same links (the same arithmetic as
        // `Arm::flange_pose`).
        let flange = links[DOF] * self.arm.flange;
        let (pose, cuboid) = held.padded_box(&flange, self.held_padding);
        (pose, cuboid, cuboid.compute_aabb(&pose))
    }

    /// The held product's box and lever arms at `q`, unchecked.
    pub fn held_pose(&self, q: &Joints, held: &Held) -> HeldPose {
        let links = self.arm.link_poses(&self.base, q);
        let (pose, cuboid, aabb) = self.held_box(&links, held);
        HeldPose {
            pose,
            cuboid,
            aabb,
            levers: self.levers_at(&links, held),
        }
    }

    /// The held product's box and lever arms at `q` when the box meets no
    /// obstacle (the arm is not checked), else the first it meets.
    fn held_posed(&self, q: &Joints, held: &Held, ignore: Option<&str>) -> Result<HeldPose, Hit> {
        if q.iter().any(|v| !v.is_finite()) {
            return Err(Hit::InvalidJoints);
        }
        let at = self.held_pose(q, held);
        match self.held_meets_obstacles(held, (&at.pose, &at.cuboid, &at.aabb), ignore) {
            Some(hit) => Err(hit),
            None => Ok(at),
        }
    }

    /// How far a held product's points may stray from the convex hull of
    /// its unpadded boxes at the two ends of a sweep (m):
    /// [`SWEEP_SLACK_SHARE`] of its padding.
    pub fn sweep_slack(&self) -> f64 {
        (self.held_padding * SWEEP_SLACK_SHARE).max(MIN_SWEEP_SLACK)
    }

    /// [`Checker::sweep_slack`] for `held`, whose sides may be padded less
    /// ([`Held::side_pad`]): the same share of its least padding.
    fn slack_for(&self, held: &Held) -> f64 {
        (self.held_padding.min(held.side_pad) * SWEEP_SLACK_SHARE).max(MIN_SWEEP_SLACK)
    }

    /// The first obstacle the held product meets on its way from `qa`
    /// (where its box is `a`, checked) to `qb` (`b`, checked), through the
    /// configurations `between` in order (commands between two checked
    /// ones; with none, the straight joint motion), but the product itself
    /// and the one `touch` names.
    ///
    /// The convex hull of its padded boxes at both ends is tested, when
    /// every point of the product stays within [`Checker::sweep_slack`] of
    /// the hull of its unpadded boxes on the way: along the straight
    /// motion from `qa` to `qb` by its [`held_bow`], plus how far each
    /// configuration between moves it from the nearest point of that motion
    /// ([`held_move`]), plus the bow between consecutive ones. The padded
    /// hull holds the unpadded one grown by the padding, so the product
    /// then keeps the rest of its padding clear of anything the hull
    /// misses. Where the bound is larger, the way is split at its middle
    /// configuration (at the middle of the straight motion when there are
    /// none between), the product's box checked there, and each half swept.
    #[allow(clippy::too_many_arguments)]
    pub fn sweep(
        &self,
        qa: &Joints,
        a: &HeldPose,
        qb: &Joints,
        b: &HeldPose,
        between: &[Joints],
        held: &Held,
        touch: Option<Touch>,
    ) -> Option<Hit> {
        self.sweep_split(
            (qa, a),
            (qb, b),
            between,
            held,
            touch.map(Touch::product),
            0,
        )
        .err()
    }

    fn sweep_split(
        &self,
        (qa, a): (&Joints, &HeldPose),
        (qb, b): (&Joints, &HeldPose),
        between: &[Joints],
        held: &Held,
        ignore: Option<&str>,
        depth: usize,
    ) -> Result<(), Hit> {
        if self.strays(qa, a, qb, b, between) <= self.slack_for(held) {
            return match self.hull_meets_obstacles(a, b, held, ignore) {
                Some(hit) => Err(hit),
                None => Ok(()),
            };
        }
        if depth >= MAX_SWEEP_SPLITS {
            return Err(Hit::InvalidJoints);
        }
        let (before, mid, after) = match between.len() {
            0 => (&[][..], lerp(qa, qb, 0.5), &[][..]),
            n => (&between[..n / 2], between[n / 2], &between[n / 2 + 1..]),
        };
        let m = self.held_posed(&mid, held, ignore)?;
        self.sweep_split((qa, a), (&mid, &m), before, held, ignore, depth + 1)?;
        self.sweep_split((&mid, &m), (qb, b), after, held, ignore, depth + 1)
    }

    /// A bound on how far the held product's points stray from the convex
    /// hull of its unpadded boxes at `qa` and `qb` on the way through
    /// `between` ([`Checker::sweep`]); infinite when some configuration is
    /// not finite.
    fn strays(
        &self,
        qa: &Joints,
        a: &HeldPose,
        qb: &Joints,
        b: &HeldPose,
        between: &[Joints],
    ) -> f64 {
        // The lever arms at either end, the larger, grown by how far the
        // product moves: a lever arm changes by no more than that.
        let ends: LeverArms = std::array::from_fn(|j| a.levers[j].max(b.levers[j]));
        let moved = held_move(&ends, qa, qb);
        let levers: LeverArms = ends.map(|r| r + moved);
        let d: Joints = std::array::from_fn(|j| qb[j] - qa[j]);
        let dd: f64 = d.iter().map(|v| v * v).sum();
        // Each configuration between from the nearest point of the straight
        // motion (nearest by the joints' squared differences; any point
        // gives a bound).
        let off = |q: &Joints| {
            let t = if dd > 0.0 {
                (q.iter()
                    .zip(qa)
                    .zip(&d)
                    .map(|((x, y), e)| (x - y) * e)
                    .sum::<f64>()
                    / dd)
                    .clamp(0.0, 1.0)
            } else {
                0.0
            };
            held_move(&levers, q, &lerp(qa, qb, t))
        };
        let off = between.iter().map(off).fold(0.0, f64::max);
        // The bow between consecutive configurations of the way.
        let way = std::iter::once(qa)
            .chain(between)
            .chain(std::iter::once(qb));
        let bows = way
            .clone()
            .zip(way.skip(1))
            .map(|(x, y)| held_bow(&levers, x, y))
            .fold(0.0, f64::max);
        let total = held_bow(&levers, qa, qb) + off + bows;
        if total.is_finite() {
            total
        } else {
            f64::INFINITY
        }
    }

    /// The first obstacle the convex hull of the held product's padded
    /// boxes `a` and `b` meets, but the product itself and the one `ignore`
    /// names.
    fn hull_meets_obstacles(
        &self,
        a: &HeldPose,
        b: &HeldPose,
        held: &Held,
        ignore: Option<&str>,
    ) -> Option<Hit> {
        let aabb = a.aabb.merged(&b.aabb);
        let hull = TwoBoxes {
            a: a.cuboid,
            b: b.cuboid,
            b_in_a: a.pose.inv_mul(&b.pose),
        };
        self.obstacles_near(held, &aabb, ignore)
            .find(|o| match o.shape.as_support_map() {
                Some(shape) => intersection_test_support_map_support_map(
                    &a.pose.inv_mul(&o.pose),
                    &hull,
                    shape,
                ),
                // Every obstacle is a box: anything else counts as met.
                None => true,
            })
            .map(|o| Hit::Bodies {
                a: Body::Held(held.name.clone()),
                b: o.body.clone(),
            })
    }

    /// The lever arms ([`LeverArms`]) of `held` at the link poses `links`.
    fn levers_at(&self, links: &[Isometry3<f64>; DOF + 1], held: &Held) -> LeverArms {
        let centre = (links[DOF] * self.arm.flange * held.in_flange)
            .translation
            .vector;
        let reach = held
            .size
            .iter()
            .map(|v| (v / 2.0 + self.held_padding).powi(2))
            .sum::<f64>()
            .sqrt();
        std::array::from_fn(|i| {
            // Joint `i` turns link `i + 1` about its own origin and axis:
            // both are where that link's pose puts them.
            let joint = &links[i + 1];
            let axis = joint.rotation * self.arm.axes[i].into_inner();
            let d = centre - joint.translation.vector;
            (d - axis * d.dot(&axis)).norm() + reach
        })
    }

    /// The first collision along the straight joint-space motion from `q0`
    /// to `q1`, checked at steps of at most [`MAX_STEP`] (both ends
    /// included), a held product swept between them ([`Checker::sweep`]).
    pub fn check_motion(
        &self,
        q0: &Joints,
        q1: &Joints,
        held: Option<&Held>,
        touch: Option<Touch>,
    ) -> Option<Hit> {
        self.check_motion_posed(q0, q1, held, touch).err()
    }

    /// [`Checker::check_motion`], with the held product's box and lever
    /// arms at `q1` when it passes.
    pub fn check_motion_posed(
        &self,
        q0: &Joints,
        q1: &Joints,
        held: Option<&Held>,
        touch: Option<Touch>,
    ) -> Result<Option<HeldPose>, Hit> {
        let span = q0
            .iter()
            .zip(q1)
            .map(|(a, b)| (b - a).abs())
            .fold(0.0, f64::max);
        if !span.is_finite() {
            return self.check_posed(q1, held, touch);
        }
        let steps = (span / MAX_STEP).ceil().max(1.0) as usize;
        let mut last = (*q0, self.check_posed(q0, held, touch)?);
        for k in 1..=steps {
            let q = lerp(q0, q1, k as f64 / steps as f64);
            let at = self.check_posed(&q, held, touch)?;
            if let (Some(h), (before, Some(from)), Some(to)) = (held, &last, &at)
                && let Some(hit) = self.sweep(before, from, &q, to, &[], h, touch)
            {
                return Err(hit);
            }
            last = (q, at);
        }
        Ok(last.1)
    }
}

/// The configuration a share `t` of the way from `a` to `b`, joint by
/// joint.
fn lerp(a: &Joints, b: &Joints, t: f64) -> Joints {
    std::array::from_fn(|j| a[j] + (b[j] - a[j]) * t)
}

/// The motion an independent probe found, for tests: a UR10 on a 400 mm
/// riser carrying a 70 x 70 x 150 mm vase 80 mm above the table past a
/// 140 mm lamp waiting beside it, whose corner the vase grazes between
/// configurations a degree apart.
#[cfg(test)]
pub(crate) mod graze {
    use super::{Held, ProductBody};
    use nalgebra::Vector3;
    use packwright_interface::scene::{BoxSpec, CellScene};
    use packwright_kinematics::Joints;
    use std::f64::consts::FRAC_PI_2;

    pub fn cell() -> CellScene {
        CellScene {
            name: "edge".into(),
            base: [0.0, 0.0, 0.4],
            suction: 0.06,
            lift: 0.08,
            speed: 1.0,
            grip_settle: 0.1,
            release_settle: 0.5,
            descent: 1.0,
            pending: ([0.55, -0.9], [0.85, -0.55]),
            boxes: vec![BoxSpec {
                name: "carton".into(),
                centre: [0.55, 0.85],
                size: [0.32, 0.26, 0.3],
            }],
            slots: vec![],
        }
    }

    pub fn lamp() -> ProductBody {
        ProductBody {
            name: "lamp".into(),
            centre: [0.7844, -0.6469, 0.07],
            size: [0.08, 0.06, 0.14],
            yaw: 0.0,
        }
    }

    pub fn vase() -> Held {
        Held::under_cup("vase", [0.07, 0.07, 0.15], 0.06, Vector3::zeros())
    }

    /// `s` radians of the joint that moves most along the way, from one of
    /// two commands the simulator sent on it, 2 ms apart or so.
    pub fn along(s: f64) -> Joints {
        let a: Joints = [
            2.2699418, -0.6469222, 1.6674664, -2.5912656, -FRAC_PI_2, -2.4379699,
        ];
        let b: Joints = [
            2.2738583, -0.6477525, 1.6655460, -2.5885238, -FRAC_PI_2, -2.4339118,
        ];
        let most = a
            .iter()
            .zip(&b)
            .map(|(x, y)| (y - x).abs())
            .fold(0.0, f64::max);
        std::array::from_fn(|j| a[j] + (b[j] - a[j]) * s / most)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use packwright_interface::scene::{BoxSpec, CellScene};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The checker as it was before its fast path (issue 11): every part's
    /// pose and box computed apart, every obstacle tested against every
    /// part, every pair's adjacency looked up, the reference narrow test
    /// for every pair (`body::exact_intersects`: a capsule and a cuboid in
    /// closed form, anything else by parry's GJK). [`Checker::check`] must
    /// give its answers.
    fn reference_check(
        c: &Checker,
        allowed: &[(usize, usize)],
        q: &Joints,
        held: Option<&Held>,
        touch: Option<Touch>,
    ) -> Option<Hit> {
        use body::exact_intersects as intersects;
        if q.iter().any(|v| !v.is_finite()) {
            return Some(Hit::InvalidJoints);
        }
        let links = c.arm.link_poses(&c.base, q);
        let poses: Vec<Pose> = c
            .parts
            .iter()
            .map(|p| pose(&(links[p.link()] * p.local)))
            .collect();
        let bottom = cup_bottom(&c.arm.flange_pose(&c.base, q), c.suction);
        let skipped = |o: &Obstacle, by_cup: bool| match &o.body {
            Body::Product(n) => {
                let touched = touch.filter(|t| t.product() == n && t.allows(bottom, o.top));
                (by_cup && touched.is_some()) || held.is_some_and(|h| &h.name == n)
            }
            _ => false,
        };
        let obstacles = move |by_cup: bool| {
            c.statics
                .iter()
                .chain(c.products.iter().filter(move |o| !skipped(o, by_cup)))
        };
        for (part, p) in c.parts.iter().zip(&poses) {
            let aabb = part.shape.compute_aabb(p);
            for o in obstacles(part.part == CUP) {
                if o.is_table && part.part <= 1 {
                    continue;
                }
                if aabb.intersects(&o.aabb) && intersects(p, &*part.shape, &o.pose, &*o.shape) {
                    return Some(Hit::Bodies {
                        a: c.names[part.part].clone(),
                        b: o.body.clone(),
                    });
                }
            }
        }
        let boxes: Vec<Aabb> = c
            .parts
            .iter()
            .zip(&poses)
            .map(|(part, p)| part.shape.compute_aabb(p))
            .collect();
        for (i, a) in c.parts.iter().enumerate() {
            for (j, b) in c.parts.iter().enumerate().skip(i + 1) {
                let (la, lb) = (a.part.min(b.part), a.part.max(b.part));
                if body::adjacent(la, lb)
                    || allowed.contains(&(la, lb))
                    || !boxes[i].intersects(&boxes[j])
                {
                    continue;
                }
                if intersects(&poses[i], &*a.shape, &poses[j], &*b.shape) {
                    return Some(Hit::Bodies {
                        a: c.names[la].clone(),
                        b: c.names[lb].clone(),
                    });
                }
            }
        }
        if let Some(h) = held {
            let flange = c.arm.flange_pose(&c.base, q);
            let (hp, cuboid) = h.padded_box(&flange, c.held_padding);
            let aabb = cuboid.compute_aabb(&hp);
            let name = Body::Held(h.name.clone());
            // The held product is kept off everything but itself and the
            // touched product, wherever the cup is.
            let named = |o: &Obstacle, n: Option<&str>| matches!(&o.body, Body::Product(p) if Some(p.as_str()) == n);
            let others = c.statics.iter().chain(c.products.iter().filter(|o| {
                !named(o, Some(h.name.as_str())) && !named(o, touch.map(Touch::product))
            }));
            for o in others {
                if aabb.intersects(&o.aabb) && intersects(&hp, &cuboid, &o.pose, &*o.shape) {
                    return Some(Hit::Bodies {
                        a: name,
                        b: o.body.clone(),
                    });
                }
            }
            for (part, p) in c.parts.iter().zip(&poses) {
                if part.part < DOF && intersects(&hp, &cuboid, p, &*part.shape) {
                    return Some(Hit::Bodies {
                        a: name,
                        b: c.names[part.part].clone(),
                    });
                }
            }
        }
        None
    }

    fn cell() -> CellScene {
        CellScene {
            name: "c".into(),
            base: [0.05, -0.02, 0.0],
            suction: 0.1,
            lift: 0.15,
            speed: 1.0,
            grip_settle: 0.1,
            release_settle: 0.5,
            descent: 1.0,
            pending: ([0.45, -0.5], [0.85, -0.1]),
            boxes: vec![BoxSpec {
                name: "tray".into(),
                centre: [0.0, 0.65],
                size: [0.4, 0.3, 0.08],
            }],
            slots: vec![],
        }
    }

    /// A product standing 2 mm from its neighbour (products waiting on a
    /// line, jittered closer): padded all round, the lift collides before
    /// it moves; lifted ([`Checker::lifting`]), its sides are padded by
    /// the room less [`LIFT_ROOM`], and the arm gripping it is free. The
    /// padding stays whole with room for it, and no less than
    /// [`MIN_SIDE_PAD`] when a neighbour is closer still (then the lift
    /// collides).
    #[test]
    fn a_product_close_to_its_neighbour_is_lifted_with_the_room_it_has() {
        use crate::execute::{Load, reach};
        use nalgebra::Point3;
        use std::f64::consts::FRAC_PI_2;
        let arm = Arm::ur10();
        let size = [0.05, 0.05, 0.06];
        let stand = |gap: f64| {
            let mut checker = Checker::new(&arm, &cell());
            let product = |name: &str, x: f64| ProductBody {
                name: name.into(),
                centre: [x, -0.3, 0.03],
                size,
                yaw: 0.0,
            };
            checker.set_products(&[product("A", 0.6), product("B", 0.65 + gap)]);
            checker
        };
        let held = Held::under_cup("A", size, 0.1, Vector3::zeros());
        let checker = stand(0.002);
        let lifted = checker.lifting(held.clone(), None);
        assert!(
            (lifted.side_pad - (0.002 - LIFT_ROOM)).abs() < 1e-6,
            "{}",
            lifted.side_pad
        );
        assert!(lifted.leaving_support);
        // The UR "ready" pose, for the inverse kinematics to start near.
        let ready =
            arm.from_ur_convention(&[0.0, -FRAC_PI_2, FRAC_PI_2, -FRAC_PI_2, -FRAC_PI_2, 0.0]);
        let top = Point3::new(0.6, -0.3, 0.06);
        let grip =
            reach(&checker, top, 0.0, &ready, Load::picking("A")).expect("the gripping pose");
        assert_eq!(checker.check(&grip, Some(&lifted), None), None);
        let whole = held.clone().leaving_support();
        assert!(
            checker.check(&grip, Some(&whole), None).is_some(),
            "padded all round, the lift starts free: a weak test"
        );
        assert_eq!(
            stand(0.01).lifting(held.clone(), None).side_pad,
            HELD_PADDING
        );
        assert_eq!(
            stand(0.0003).lifting(held.clone(), None).side_pad,
            MIN_SIDE_PAD
        );
        // Not standing among the checker's products: given where it stands.
        let elsewhere = Held::under_cup("C", size, 0.1, Vector3::zeros());
        let at = ProductBody {
            name: "C".into(),
            centre: [0.6, -0.3 - 0.05 - 0.0015, 0.03],
            size,
            yaw: 0.0,
        };
        let mut only_a = Checker::new(&arm, &cell());
        only_a.set_products(&[ProductBody {
            name: "A".into(),
            centre: [0.6, -0.3, 0.03],
            size,
            yaw: 0.0,
        }]);
        let side = only_a.lifting(elsewhere, Some(&at)).side_pad;
        assert!((side - (0.0015 - LIFT_ROOM)).abs() < 1e-6, "{side}");
    }

    /// A tray 287 mm deep let go in a box 292 mm deep inside (2.5 mm each
    /// side): padded all round, the release collides, and every planner
    /// let it go above the rim; lowered ([`Checker::lowering`]), its
    /// sides are padded by the room less [`LOWER_ROOM`], and the release
    /// and the last 3 cm down to it are free. With room to spare the
    /// padding stays whole; a product already packed beside the slot
    /// counts as a wall does.
    #[test]
    fn a_product_lowered_into_a_snug_slot_is_padded_with_the_room_it_has() {
        use crate::execute::{Load, reach};
        use crate::expert::released_centre;
        use nalgebra::Point3;
        use packwright_kinematics::body::BOX_WALL;
        use std::f64::consts::FRAC_PI_2;
        let arm = Arm::ur10();
        let size = [0.05, 0.287, 0.03];
        let slot = [0.0, 0.65];
        let mut checker = Checker::new(&arm, &cell());
        let held = Held::under_cup("T", size, 0.1, Vector3::zeros());
        let lowered = checker.lowering(held.clone(), released_centre(slot, size[2]), 0.0);
        let room = (0.3 - 2.0 * BOX_WALL - size[1]) / 2.0;
        assert!(
            (lowered.side_pad - (room - LOWER_ROOM)).abs() < 1e-6,
            "{}",
            lowered.side_pad
        );
        assert!(!lowered.leaving_support);
        let ready =
            arm.from_ur_convention(&[0.0, -FRAC_PI_2, FRAC_PI_2, -FRAC_PI_2, -FRAC_PI_2, 0.0]);
        let tip = |z: f64| Point3::new(slot[0], slot[1], z);
        let release = released_centre(slot, size[2])[2] + size[2] / 2.0;
        let down = Load::holding(&lowered);
        let above = reach(&checker, tip(release + 0.03), 0.0, &ready, down).expect("in the box");
        let at = reach(&checker, tip(release), 0.0, &above, down).expect("the release, lowered");
        assert_eq!(
            checker.check_motion(&above, &at, Some(&lowered), None),
            None
        );
        assert!(
            checker.check(&at, Some(&held), None).is_some(),
            "padded all round, the release is free: a weak test"
        );
        // A narrow product: the whole padding.
        let narrow = Held::under_cup("N", [0.05, 0.2, 0.03], 0.1, Vector3::zeros());
        let side = checker
            .lowering(narrow, released_centre(slot, 0.03), 0.0)
            .side_pad;
        assert_eq!(side, HELD_PADDING);
        // A product packed 2 mm beside the slot: the room to it counts.
        checker.set_products(&[ProductBody {
            name: "P".into(),
            centre: [0.05 + 0.002, 0.65, 0.02],
            size: [0.05, 0.05, 0.04],
            yaw: 0.0,
        }]);
        let narrow = Held::under_cup("N", [0.05, 0.2, 0.03], 0.1, Vector3::zeros());
        let side = checker
            .lowering(narrow, released_centre(slot, 0.03), 0.0)
            .side_pad;
        assert!((side - (0.002 - LOWER_ROOM)).abs() < 1e-6, "{side}");
    }

    /// A product carried up from beside a taller neighbour 4 mm away hangs
    /// above it only once its padded bottom is over the neighbour's top;
    /// a taller product 10 cm away does not count.
    #[test]
    fn a_carried_product_hangs_above_its_neighbours_only_over_their_tops() {
        use crate::execute::{Load, reach};
        use nalgebra::Point3;
        use std::f64::consts::FRAC_PI_2;
        let arm = Arm::ur10();
        let mut checker = Checker::new(&arm, &cell());
        let product = |name: &str, x: f64, size: [f64; 3]| ProductBody {
            name: name.into(),
            centre: [x, -0.3, size[2] / 2.0],
            size,
            yaw: 0.0,
        };
        checker.set_products(&[
            product("A", 0.6, [0.05, 0.05, 0.06]),
            product("B", 0.654, [0.05, 0.05, 0.08]),
            product("far", 0.75, [0.05, 0.05, 0.2]),
        ]);
        let held = Held::under_cup("A", [0.05, 0.05, 0.06], 0.1, Vector3::zeros());
        let ready =
            arm.from_ur_convention(&[0.0, -FRAC_PI_2, FRAC_PI_2, -FRAC_PI_2, -FRAC_PI_2, 0.0]);
        let at = |tip_z: f64| {
            reach(
                &checker,
                Point3::new(0.6, -0.3, tip_z),
                0.0,
                &ready,
                Load::FREE,
            )
            .expect("a pose")
        };
        // Bottom 40 mm up, beside B's 80 mm: not above it.
        assert!(!checker.above_neighbours(&at(0.10), &held));
        // Bottom 90 mm up: over B's top by more than the padding.
        assert!(checker.above_neighbours(&at(0.15), &held));
    }

    /// Over thousands of configurations, free and colliding, near the
    /// products and the box and anywhere, with and without a held product
    /// and an ignored one, the checker's answer (which bodies included) is
    /// the reference's.
    #[test]
    fn the_fast_check_answers_as_the_reference() {
        let products: Vec<ProductBody> = (0..6)
            .map(|i| ProductBody {
                name: format!("P{i}"),
                centre: [0.45 + 0.07 * i as f64, -0.2 - 0.03 * i as f64, 0.03],
                size: [0.05, 0.06, 0.06],
                yaw: 0.3 * i as f64,
            })
            .collect();
        let (free, hit) = answers_as_the_reference(&products, 11);
        assert!(free > 500 && hit > 500, "{free} free, {hit} colliding");
    }

    /// More obstacles near the arm than a check lists on the stack
    /// (`STACK_NEAR`): the same answers.
    #[test]
    fn the_fast_check_answers_as_the_reference_among_many_products() {
        let products: Vec<ProductBody> = (0..60)
            .map(|i| ProductBody {
                name: format!("P{i}"),
                centre: [
                    0.4 + 0.06 * (i % 10) as f64,
                    -0.15 - 0.07 * (i / 10) as f64,
                    0.02,
                ],
                size: [0.04, 0.04, 0.04],
                yaw: 0.1 * i as f64,
            })
            .collect();
        let (free, hit) = answers_as_the_reference(&products, 12);
        assert!(free > 300 && hit > 500, "{free} free, {hit} colliding");
    }

    /// The motion an independent probe found (a hand-written cell: a UR10
    /// on a 400 mm riser carrying a 70 x 70 x 150 mm vase 80 mm above the
    /// table, past a 140 mm lamp waiting beside it): the vase's corner
    /// grazes the lamp's between configurations a degree apart, each of
    /// which the padded check passes. Over every such pair along that way,
    /// [`Checker::check_motion`] finds the collision that a check of 200
    /// steps without padding sees; a degree per step (the rule before)
    /// missed some, which the test also requires, so that it tests
    /// something.
    #[test]
    fn a_held_product_is_checked_between_the_checked_configurations() {
        use super::graze::{self, along};
        let arm = Arm::ur10();
        let cell = graze::cell();
        let mut padded = Checker::new(&arm, &cell);
        padded.set_products(&[graze::lamp()]);
        let mut exact = Checker::with_padding(&arm, &cell, 0.0, 0.0);
        exact.set_products(&[graze::lamp()]);
        let vase = graze::vase();
        let (mut grazes, mut missed_by_degrees) = (0, 0);
        for i in 0..=40 {
            let s0 = -MAX_STEP + MAX_STEP * i as f64 / 40.0;
            // Checked configurations lie just under a degree apart.
            let (q0, q1) = (along(s0), along(s0 + 0.999 * MAX_STEP));
            let at = |t: f64| -> Joints { std::array::from_fn(|j| q0[j] + (q1[j] - q0[j]) * t) };
            let collides = (0..=200).any(|k| {
                exact
                    .check(&at(k as f64 / 200.0), Some(&vase), None)
                    .is_some()
            });
            if !collides {
                continue;
            }
            grazes += 1;
            assert!(
                padded.check_motion(&q0, &q1, Some(&vase), None).is_some(),
                "a graze from {s0} rad on passed"
            );
            let ends_pass = [q0, q1]
                .iter()
                .all(|q| padded.check(q, Some(&vase), None).is_none());
            if ends_pass {
                missed_by_degrees += 1;
            }
        }
        assert!(grazes > 0, "the way grazes the lamp nowhere");
        assert!(
            missed_by_degrees > 0,
            "degree steps alone missed none: a weak test"
        );
    }

    /// The sweep's promise, over 10,000 random ways of a held product of a
    /// random size (from configurations near the graze's, joint steps of
    /// up to 3 degrees, half of them through commands strayed up to 0.1
    /// degree from the straight motion), each past a 40 mm cube put at
    /// random beside the product half way: wherever [`Checker::sweep`]
    /// finds the way free, a check of the product at 60 points along every
    /// straight piece of it, padded by what the sweep leaves of the
    /// padding, finds nothing. Among the ways are some whose ends pass the
    /// padded check while that check finds the product meeting the cube
    /// between them: a check of the ends alone would pass them.
    #[test]
    fn a_swept_held_product_keeps_clear_of_what_its_hull_misses() {
        use super::graze::{self, along};
        let arm = Arm::ur10();
        let cell = graze::cell();
        let mut padded = Checker::new(&arm, &cell);
        let kept = HELD_PADDING - padded.sweep_slack();
        let mut inner = Checker::with_padding(&arm, &cell, 0.0, kept);
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let (mut free, mut met, mut between_only) = (0, 0, 0);
        for k in 0..10_000 {
            let size = [
                rng.random_range(0.03..0.12),
                rng.random_range(0.03..0.12),
                rng.random_range(0.05..0.15),
            ];
            let held = Held::under_cup("vase", size, 0.06, Vector3::zeros());
            let held = if k % 3 == 0 {
                held.leaving_support()
            } else {
                held
            };
            let q0: Joints = {
                let q = along(rng.random_range(-0.3..0.3));
                std::array::from_fn(|j| q[j] + rng.random_range(-0.02..0.02))
            };
            let step = 3.0 * MAX_STEP;
            let q1: Joints = std::array::from_fn(|j| q0[j] + rng.random_range(-step..step));
            let between: Vec<Joints> = if k % 2 == 0 {
                Vec::new()
            } else {
                (1..6)
                    .map(|i| {
                        let q = lerp(&q0, &q1, f64::from(i) / 6.0);
                        std::array::from_fn(|j| q[j] + rng.random_range(-0.1..0.1) * MAX_STEP)
                    })
                    .collect()
            };
            // The cube beside the product half way, in a random direction
            // across, from touching its side to a centimetre off its
            // corner.
            let mid = centre_of(&padded, &lerp(&q0, &q1, 0.5), &held);
            let heading = rng.random_range(-std::f64::consts::PI..std::f64::consts::PI);
            let (near, far) = (
                size[0].max(size[1]) / 2.0 + 0.015,
                size[0].hypot(size[1]) / 2.0 + 0.045,
            );
            let off = rng.random_range(near..far);
            let centre = mid
                + Vector3::new(
                    heading.cos() * off,
                    heading.sin() * off,
                    rng.random_range(-0.05..0.05),
                );
            let cube = [ProductBody {
                name: "cube".into(),
                centre: centre.into(),
                size: [0.04; 3],
                yaw: rng.random_range(0.0..1.0),
            }];
            padded.set_products(&cube);
            inner.set_products(&cube);
            let (Ok(a), Ok(b)) = (
                padded.held_posed(&q0, &held, None),
                padded.held_posed(&q1, &held, None),
            ) else {
                continue;
            };
            let way: Vec<Joints> = std::iter::once(q0)
                .chain(between.iter().copied())
                .chain(std::iter::once(q1))
                .collect();
            let meets = way.windows(2).any(|w| {
                (0..=60).any(|i| {
                    inner
                        .held_posed(&lerp(&w[0], &w[1], f64::from(i) / 60.0), &held, None)
                        .is_err()
                })
            });
            match padded.sweep(&q0, &a, &q1, &b, &between, &held, None) {
                None => {
                    assert!(
                        !meets,
                        "a way found free meets the cube within {kept} m: {q0:?} to {q1:?} through {between:?}, {held:?}, {cube:?}"
                    );
                    free += 1;
                }
                Some(_) => {
                    met += 1;
                    if meets {
                        between_only += 1;
                    }
                }
            }
        }
        assert!(free > 3_000, "{free} free, {met} met");
        assert!(
            between_only >= 20,
            "{between_only} met between the ends only"
        );
    }

    /// The centre of `held` at `q` (world, m).
    fn centre_of(checker: &Checker, q: &Joints, held: &Held) -> Vector3<f64> {
        (checker.arm.link_poses(&checker.base, q)[DOF] * checker.arm.flange * held.in_flange)
            .translation
            .vector
    }

    /// `held`'s boxes at `q0` and `q1`, each free, and the hull of the two
    /// missing everything too: a sweep that finds something between them
    /// finds what a check of the ends alone would miss.
    fn free_ends(checker: &Checker, q0: &Joints, q1: &Joints, held: &Held) -> (HeldPose, HeldPose) {
        let (a, b) = (
            checker
                .held_posed(q0, held, None)
                .expect("the start is free"),
            checker.held_posed(q1, held, None).expect("the end is free"),
        );
        assert!(
            checker.hull_meets_obstacles(&a, &b, held, None).is_none(),
            "the ends' hull meets something: a weak test"
        );
        (a, b)
    }

    /// A 40 degree turn of the base carries the vase along an arc that
    /// bows 5 cm out of the chord between its ends; a cube on the arc's
    /// outside, 3.5 cm out, meets the vase half way while the hull of the
    /// vase's boxes at the two ends passes inside it. The sweep splits the
    /// way until the hull follows the arc, with no commands between and
    /// with commands along it, and finds the cube.
    #[test]
    fn a_sweep_follows_an_arc_that_its_ends_hull_cuts_across() {
        use super::graze::{self, along};
        let arm = Arm::ur10();
        let cell = graze::cell();
        let mut checker = Checker::new(&arm, &cell);
        let vase = graze::vase();
        let q0 = along(0.0);
        let turned = |t: f64| -> Joints {
            let mut q = q0;
            q[0] += 0.7 * t;
            q
        };
        let mid = centre_of(&checker, &turned(0.5), &vase);
        let base = Vector3::new(cell.base[0], cell.base[1], mid.z);
        let out = (mid - base).normalize() * 0.035;
        checker.set_products(&[ProductBody {
            name: "cube".into(),
            centre: (mid + out).into(),
            size: [0.04; 3],
            yaw: 0.0,
        }]);
        let q1 = turned(1.0);
        let (a, b) = free_ends(&checker, &q0, &q1, &vase);
        assert!(checker.held_posed(&turned(0.5), &vase, None).is_err());
        assert!(checker.sweep(&q0, &a, &q1, &b, &[], &vase, None).is_some());
        let commands: Vec<Joints> = (1..40).map(|i| turned(f64::from(i) / 40.0)).collect();
        assert!(
            checker
                .sweep(&q0, &a, &q1, &b, &commands, &vase, None)
                .is_some()
        );
    }

    /// Commands between two checked configurations a little apart that
    /// stray from the straight motion, a little at a time (the shoulder
    /// bulging out to 8 degrees off half way) carry the vase into a cube
    /// that the hull of its boxes at the two ends misses: the sweep counts
    /// how far they stray, splits the way at them and finds the cube.
    #[test]
    fn a_sweep_follows_commands_that_stray_from_the_straight_motion() {
        use super::graze::{self, along};
        let arm = Arm::ur10();
        let cell = graze::cell();
        let mut checker = Checker::new(&arm, &cell);
        let vase = graze::vase();
        let (q0, q1) = (along(0.0), along(0.2 * MAX_STEP));
        let mut strayed = along(0.1 * MAX_STEP);
        strayed[1] -= 8.0 * MAX_STEP;
        let at = centre_of(&checker, &strayed, &vase);
        checker.set_products(&[ProductBody {
            name: "cube".into(),
            centre: at.into(),
            size: [0.01; 3],
            yaw: 0.0,
        }]);
        let (a, b) = free_ends(&checker, &q0, &q1, &vase);
        assert!(checker.sweep(&q0, &a, &q1, &b, &[], &vase, None).is_none());
        // Commands 2 ms apart bulging out to the strayed one and back.
        let commands: Vec<Joints> = (1..40)
            .map(|i| {
                let t = f64::from(i) / 40.0;
                let mut q = along(0.2 * MAX_STEP * t);
                q[1] -= 8.0 * MAX_STEP * (std::f64::consts::PI * t).sin();
                q
            })
            .collect();
        assert!(commands.contains(&strayed));
        assert!(
            checker
                .sweep(&q0, &a, &q1, &b, &commands, &vase, None)
                .is_some()
        );
    }

    /// [`Checker::check`] against [`reference_check`] at 6,000 random
    /// configurations (tool down over the pending area or the box, or
    /// anywhere), holding or not, ignoring P1 or not, among `products`:
    /// how many were free and how many collided.
    fn answers_as_the_reference(products: &[ProductBody], seed: u64) -> (usize, usize) {
        let arm = Arm::ur10();
        let cell = cell();
        let mut checker = Checker::new(&arm, &cell);
        let allowed = body::touching_pairs(&arm, cell.suction);
        checker.set_products(products);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let held = Held::under_cup("P2", [0.05, 0.06, 0.06], 0.1, Vector3::new(0.004, 0.0, 0.0));
        let (mut free, mut hit) = (0, 0);
        for k in 0..6_000 {
            // Tool down over the pending area or the box, give or take,
            // or anywhere in the joint ranges.
            let q: Joints = if k % 3 == 2 {
                std::array::from_fn(|j| {
                    let l = &arm.limits[j];
                    rng.random_range(l.lower.max(-3.3)..=l.upper.min(3.3))
                })
            } else {
                let (x, y) = if k % 2 == 0 {
                    (rng.random_range(0.4..0.9), rng.random_range(-0.5..-0.1))
                } else {
                    (rng.random_range(-0.25..0.25), rng.random_range(0.45..0.85))
                };
                let tip = nalgebra::Point3::new(x, y, rng.random_range(0.0..0.3));
                let near = [0.0, -1.57, 1.57, -1.57, -1.57, 0.0];
                let Some(q) =
                    arm.tool_down_ik(checker.base(), tip, rng.random_range(-1.0..1.0), 0.1, &near)
                else {
                    continue;
                };
                q
            };
            let h = match k % 4 {
                0 => None,
                1 => Some(held.clone()),
                2 => Some(held.clone().leaving_support()),
                _ => None,
            };
            let ignore = match k % 5 {
                0 => Some(Touch::Picking("P1")),
                1 => Some(Touch::Released("P1")),
                _ => None,
            };
            let got = checker.check(&q, h.as_ref(), ignore);
            assert_eq!(
                got,
                reference_check(&checker, &allowed, &q, h.as_ref(), ignore),
                "at {q:?}, held {h:?}, ignoring {ignore:?}"
            );
            if got.is_some() {
                hit += 1;
            } else {
                free += 1;
            }
        }
        (free, hit)
    }
}
