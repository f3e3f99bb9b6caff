//! Collision checking for planning (parry3d), on the cell's one collision
//! description (`packwright_kinematics::body`, which the simulator builds
//! from too): the arm's parts grown by [`PADDING`], the held product
//! grown by [`HELD_PADDING`], the fixtures and products as they are, with
//! an axis-aligned bounding-box prefilter.
//!
//! What is checked: every arm part against the table (except the base and
//! shoulder links, which stand on it), the boxes and the products (except
//! the one being picked); non-adjacent arm parts against each other (except
//! the pairs that touch by construction, `body::touching_pairs`); a held
//! product against everything but the cup and the last link, which hold
//! it. A motion between two configurations is checked at joint steps of at
//! most 1 degree.

use nalgebra::{Isometry3, UnitQuaternion, Vector3};
use packwright_interface::outcome::Hit;
use packwright_interface::scene::CellScene;
use packwright_interface::world::Body;
use packwright_kinematics::body::{self, ArmPart, CUP, HELD_PADDING, PADDING, intersects, pose};
use packwright_kinematics::{Arm, DOF, Joints};
use parry3d::bounding_volume::{Aabb, BoundingVolume};
use parry3d::math::{Pose, Vector};
use parry3d::shape::{Cuboid, SharedShape};

/// Largest joint step when checking a motion, radians (1 degree).
pub const MAX_STEP: f64 = std::f64::consts::PI / 180.0;

/// A fixed or free-standing obstacle.
#[derive(Debug, Clone)]
struct Obstacle {
    body: Body,
    pose: Pose,
    shape: SharedShape,
    aabb: Aabb,
    /// The table: the base and shoulder links stand on it.
    is_table: bool,
}

impl Obstacle {
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
}

/// How far above its bottom a product leaving its support is checked from
/// (m): the check box stops this short of the product's bottom, so that
/// resting on the surface is no collision. Below the simulator's 1 mm
/// tolerance for a held product's penetration.
pub const LIFT_CLEARANCE: f64 = 0.0005;

impl Held {
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

/// Checks arm configurations and motions against a cell.
#[derive(Clone)]
pub struct Checker {
    arm: Arm,
    base: Isometry3<f64>,
    parts: Vec<ArmPart>,
    names: Vec<Body>,
    statics: Vec<Obstacle>,
    products: Vec<Obstacle>,
    /// Part pairs never checked against each other.
    allowed: Vec<(usize, usize)>,
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
        Checker {
            arm: arm.clone(),
            base,
            parts,
            names,
            statics,
            products: Vec::new(),
            allowed: body::touching_pairs(arm, cell.suction),
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

    /// World poses of every part for joints `q`.
    fn part_poses(&self, q: &Joints) -> Vec<Pose> {
        let links = self.arm.link_poses(&self.base, q);
        self.parts
            .iter()
            .map(|p| pose(&(links[p.link()] * p.local)))
            .collect()
    }

    /// Colliding non-adjacent part pairs (by link index), skipping `allowed`.
    fn self_pairs(
        &self,
        poses: &[Pose],
        allowed: &[(usize, usize)],
    ) -> Vec<((usize, usize), (usize, usize))> {
        let mut out = Vec::new();
        let boxes: Vec<Aabb> = self
            .parts
            .iter()
            .zip(poses)
            .map(|(part, p)| part.shape.compute_aabb(p))
            .collect();
        for (i, a) in self.parts.iter().enumerate() {
            for (j, b) in self.parts.iter().enumerate().skip(i + 1) {
                let (la, lb) = (a.part.min(b.part), a.part.max(b.part));
                if body::adjacent(la, lb)
                    || allowed.contains(&(la, lb))
                    || !boxes[i].intersects(&boxes[j])
                {
                    continue;
                }
                if intersects(&poses[i], &a.shape, &poses[j], &b.shape) {
                    out.push(((la, lb), (i, j)));
                }
            }
        }
        out
    }

    /// The first collision of the arm (and `held`) at joints `q`. The
    /// product named `ignore` (the one being picked, or just released) is
    /// ignored by the cup alone, which touches its top face: a link that
    /// reaches it still collides.
    pub fn check(&self, q: &Joints, held: Option<&Held>, ignore: Option<&str>) -> Option<Hit> {
        if q.iter().any(|v| !v.is_finite()) {
            return Some(Hit::InvalidJoints);
        }
        let poses = self.part_poses(q);
        let skipped = |o: &Obstacle, by_cup: bool| match &o.body {
            Body::Product(n) => {
                (by_cup && Some(n.as_str()) == ignore) || held.is_some_and(|h| &h.name == n)
            }
            _ => false,
        };
        let obstacles = move |by_cup: bool| {
            self.statics
                .iter()
                .chain(self.products.iter().filter(move |o| !skipped(o, by_cup)))
        };
        for (part, p) in self.parts.iter().zip(&poses) {
            let aabb = part.shape.compute_aabb(p);
            for o in obstacles(part.part == CUP) {
                if o.is_table && part.part <= 1 {
                    continue;
                }
                if aabb.intersects(&o.aabb) && intersects(p, &part.shape, &o.pose, &o.shape) {
                    return Some(Hit::Bodies {
                        a: self.names[part.part].clone(),
                        b: o.body.clone(),
                    });
                }
            }
        }
        if let Some(((la, lb), _)) = self.self_pairs(&poses, &self.allowed).first() {
            return Some(Hit::Bodies {
                a: self.names[*la].clone(),
                b: self.names[*lb].clone(),
            });
        }
        if let Some(h) = held {
            let flange = self.arm.flange_pose(&self.base, q);
            let pad = self.held_padding;
            // Leaving its support, the box keeps its margin above but ends
            // LIFT_CLEARANCE short of the bottom (the product's +z is the
            // flange's, pointing down).
            let (half_z, shift) = if h.leaving_support {
                let cut = pad + LIFT_CLEARANCE;
                (h.size[2] / 2.0 + pad - cut / 2.0, -cut / 2.0)
            } else {
                (h.size[2] / 2.0 + pad, 0.0)
            };
            let hp = pose(&(flange * h.in_flange * Isometry3::translation(0.0, 0.0, shift)));
            let cuboid = SharedShape::new(Cuboid::new(Vector::new(
                (h.size[0] / 2.0 + pad) as f32,
                (h.size[1] / 2.0 + pad) as f32,
                half_z as f32,
            )));
            let aabb = cuboid.compute_aabb(&hp);
            let name = Body::Held(h.name.clone());
            for o in obstacles(true) {
                if aabb.intersects(&o.aabb) && intersects(&hp, &cuboid, &o.pose, &o.shape) {
                    return Some(Hit::Bodies {
                        a: name,
                        b: o.body.clone(),
                    });
                }
            }
            for (part, p) in self.parts.iter().zip(&poses) {
                if part.part < DOF && intersects(&hp, &cuboid, p, &part.shape) {
                    return Some(Hit::Bodies {
                        a: name,
                        b: self.names[part.part].clone(),
                    });
                }
            }
        }
        None
    }

    /// The first collision along the straight joint-space motion from `q0`
    /// to `q1`, checked at steps of at most [`MAX_STEP`] (both ends
    /// included).
    pub fn check_motion(
        &self,
        q0: &Joints,
        q1: &Joints,
        held: Option<&Held>,
        ignore: Option<&str>,
    ) -> Option<Hit> {
        let span = q0
            .iter()
            .zip(q1)
            .map(|(a, b)| (b - a).abs())
            .fold(0.0, f64::max);
        if !span.is_finite() {
            return self.check(q1, held, ignore);
        }
        let steps = (span / MAX_STEP).ceil().max(1.0) as usize;
        (0..=steps).find_map(|k| {
            let t = k as f64 / steps as f64;
            let q: Joints = std::array::from_fn(|j| q0[j] + (q1[j] - q0[j]) * t);
            self.check(&q, held, ignore)
        })
    }
}
