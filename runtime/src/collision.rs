//! Collision checking for planning (parry3d): the arm's links and cup as
//! padded capsules, the held product and every obstacle as cuboids, with an
//! axis-aligned bounding-box prefilter.
//!
//! What is checked: every arm part against the table (except the base and
//! shoulder links, which stand on it), the box walls and the products (except
//! the one being picked); non-adjacent arm parts against each other (except
//! pairs that touch in nearly every configuration: their capsules overlap by
//! construction, see [`Checker::new`]); a held product against everything
//! but the cup and the last link, which hold it. A motion between two
//! configurations is checked at joint steps of at most 1 degree.
//!
//! parry works in f32 with glam types; the conversion from the robot
//! model's f64 nalgebra types happens here and only here.

use crate::robot::{Arm, DOF, Joints, Shape};
use crate::scene::{BOX_WALL, CellScene};
use nalgebra::{Isometry3, Point3, Vector3};
use parry3d::bounding_volume::{Aabb, BoundingVolume};
use parry3d::math::{Pose, Vector};
use parry3d::query;
use parry3d::shape::{Capsule, Cuboid, Shape as ParryShape};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Padding around the arm's parts and obstacles' contact, metres.
pub const PADDING: f64 = 0.01;
/// Padding around a held product (it must go down into a slot that fits it
/// with little room).
pub const HELD_PADDING: f64 = 0.003;
/// Radius of the suction cup.
pub const CUP_RADIUS: f64 = 0.02;
/// Largest joint step when checking a motion, radians (1 degree).
pub const MAX_STEP: f64 = std::f64::consts::PI / 180.0;

fn pose(iso: &Isometry3<f64>) -> Pose {
    let t = iso.translation.vector;
    let q = iso.rotation.quaternion();
    Pose::from_parts(
        Vector::new(t.x as f32, t.y as f32, t.z as f32),
        parry3d::glamx::Quat::from_xyzw(q.i as f32, q.j as f32, q.k as f32, q.w as f32),
    )
}

fn vector(v: &Vector3<f64>) -> Vector {
    Vector::new(v.x as f32, v.y as f32, v.z as f32)
}

fn point(p: &Point3<f64>) -> Vector {
    Vector::new(p.x as f32, p.y as f32, p.z as f32)
}

#[derive(Debug, Clone)]
enum Geom {
    Capsule(Capsule),
    Cuboid(Cuboid),
}

impl Geom {
    fn shape(&self) -> &dyn ParryShape {
        match self {
            Geom::Capsule(c) => c,
            Geom::Cuboid(c) => c,
        }
    }
}

/// One collision primitive of the arm, rigidly attached to a link.
#[derive(Debug, Clone)]
struct Part {
    /// 0 = base link, 1..=6 = moving links, 7 = the cup (on the last link).
    link: usize,
    /// Pose in the link's frame.
    local: Isometry3<f64>,
    geom: Geom,
}

/// Index of the cup among the arm's "links".
const CUP: usize = DOF + 1;

/// A fixed or free-standing obstacle.
#[derive(Debug, Clone)]
pub struct Obstacle {
    pub name: String,
    pose: Pose,
    cuboid: Cuboid,
    aabb: Aabb,
    /// The table: the base and shoulder links stand on it.
    is_table: bool,
}

impl Obstacle {
    fn new(name: String, centre: [f64; 3], half: [f64; 3], yaw: f64, is_table: bool) -> Obstacle {
        let iso = Isometry3::new(
            Vector3::new(centre[0], centre[1], centre[2]),
            Vector3::z() * yaw,
        );
        let cuboid = Cuboid::new(Vector::new(half[0] as f32, half[1] as f32, half[2] as f32));
        let pose = pose(&iso);
        let aabb = cuboid.compute_aabb(&pose);
        Obstacle {
            name,
            pose,
            cuboid,
            aabb,
            is_table,
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
}

/// What collided with what.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Hit {
    pub a: String,
    pub b: String,
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
#[derive(Debug, Clone)]
pub struct Checker {
    arm: Arm,
    base: Isometry3<f64>,
    parts: Vec<Part>,
    names: Vec<String>,
    statics: Vec<Obstacle>,
    products: Vec<Obstacle>,
    /// Link pairs never checked against each other.
    allowed: Vec<(usize, usize)>,
}

impl Checker {
    /// A checker for `arm` in `cell`, with no products yet.
    ///
    /// Self-collision pairs that touch at the zero pose or in at least 90%
    /// of 256 seeded random configurations are disabled: on a real arm they
    /// are neighbours whose simplified capsules overlap, not collisions.
    pub fn new(arm: &Arm, cell: &CellScene) -> Checker {
        let base = Isometry3::translation(cell.base[0], cell.base[1], cell.base[2]);
        let mut parts = Vec::new();
        for (i, link) in arm.links.iter().enumerate() {
            for s in &link.shapes {
                parts.push(match s {
                    Shape::Capsule { a, b, radius } => Part {
                        link: i,
                        local: Isometry3::identity(),
                        geom: Geom::Capsule(Capsule::new(
                            point(a),
                            point(b),
                            (radius + PADDING) as f32,
                        )),
                    },
                    Shape::Cuboid { pose, half } => Part {
                        link: i,
                        local: *pose,
                        geom: Geom::Cuboid(Cuboid::new(vector(&half.add_scalar(PADDING)))),
                    },
                });
            }
        }
        // The cup: from the flange down its z axis; the capsule's rounded end
        // stops 5 mm short of the tip, so that touching a product's top is
        // not a collision (nor the table beside a thin product).
        let cup_radius = CUP_RADIUS + PADDING;
        let tip = (cell.suction - 0.005 - cup_radius).max(0.0);
        parts.push(Part {
            link: CUP,
            local: arm.flange,
            geom: Geom::Capsule(Capsule::new(
                Vector::ZERO,
                Vector::new(0.0, 0.0, tip as f32),
                cup_radius as f32,
            )),
        });
        let mut names: Vec<String> = arm.links.iter().map(|l| l.name.clone()).collect();
        names.push("cup".into());
        let mut statics = vec![Obstacle::new(
            "table".into(),
            [0.0, 0.0, -0.05],
            [3.0, 3.0, 0.05],
            0.0,
            true,
        )];
        for b in &cell.boxes {
            let [w, d, h] = b.size;
            let [cx, cy] = b.centre;
            let t = BOX_WALL / 2.0;
            let walls = [
                ([cx - w / 2.0 + t, cy, h / 2.0], [t, d / 2.0, h / 2.0]),
                ([cx + w / 2.0 - t, cy, h / 2.0], [t, d / 2.0, h / 2.0]),
                ([cx, cy - d / 2.0 + t, h / 2.0], [w / 2.0, t, h / 2.0]),
                ([cx, cy + d / 2.0 - t, h / 2.0], [w / 2.0, t, h / 2.0]),
            ];
            for (centre, half) in walls {
                statics.push(Obstacle::new(
                    format!("box:{}", b.name),
                    centre,
                    half,
                    0.0,
                    false,
                ));
            }
        }
        let mut checker = Checker {
            arm: arm.clone(),
            base,
            parts,
            names,
            statics,
            products: Vec::new(),
            allowed: Vec::new(),
        };
        checker.allowed = checker.always_touching();
        checker
    }

    fn always_touching(&self) -> Vec<(usize, usize)> {
        let mut rng = ChaCha8Rng::seed_from_u64(0);
        let samples = 256;
        let mut counts = vec![0usize; (CUP + 1) * (CUP + 1)];
        let mut at_zero = Vec::new();
        for k in 0..=samples {
            let q: Joints = if k == 0 {
                [0.0; DOF]
            } else {
                std::array::from_fn(|j| {
                    let l = &self.arm.limits[j];
                    rng.random_range(
                        l.lower.max(-std::f64::consts::PI)..=l.upper.min(std::f64::consts::PI),
                    )
                })
            };
            let poses = self.part_poses(&q);
            for (pair, _) in self.self_pairs(&poses, &[]) {
                if k == 0 {
                    at_zero.push(pair);
                } else {
                    counts[pair.0 * (CUP + 1) + pair.1] += 1;
                }
            }
        }
        let mut allowed = at_zero;
        for i in 0..=CUP {
            for j in i + 1..=CUP {
                if counts[i * (CUP + 1) + j] * 10 >= samples * 9 && !allowed.contains(&(i, j)) {
                    allowed.push((i, j));
                }
            }
        }
        allowed
    }

    /// Replaces the free-standing products.
    pub fn set_products(&mut self, products: &[ProductBody]) {
        self.products = products
            .iter()
            .map(|p| {
                Obstacle::new(
                    format!("product:{}", p.name),
                    p.centre,
                    [p.size[0] / 2.0, p.size[1] / 2.0, p.size[2] / 2.0],
                    p.yaw,
                    false,
                )
            })
            .collect();
    }

    /// World poses of every part for joints `q`.
    fn part_poses(&self, q: &Joints) -> Vec<Pose> {
        let links = self.arm.link_poses(&self.base, q);
        self.parts
            .iter()
            .map(|p| {
                let link = if p.link == CUP { DOF } else { p.link };
                pose(&(links[link] * p.local))
            })
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
            .map(|(part, p)| part.geom.shape().compute_aabb(p))
            .collect();
        for (i, a) in self.parts.iter().enumerate() {
            for (j, b) in self.parts.iter().enumerate().skip(i + 1) {
                let (la, lb) = (a.link.min(b.link), a.link.max(b.link));
                if lb <= la + 1 || allowed.contains(&(la, lb)) || !boxes[i].intersects(&boxes[j]) {
                    continue;
                }
                if intersects(&poses[i], a.geom.shape(), &poses[j], b.geom.shape()) {
                    out.push(((la, lb), (i, j)));
                }
            }
        }
        out
    }

    /// The first collision of the arm (and `held`) at joints `q`, ignoring
    /// the product named `ignore` (the one being picked).
    pub fn check(&self, q: &Joints, held: Option<&Held>, ignore: Option<&str>) -> Option<Hit> {
        if q.iter().any(|v| !v.is_finite()) {
            return Some(Hit {
                a: "arm".into(),
                b: "invalid joints".into(),
            });
        }
        let poses = self.part_poses(q);
        let ignored = ignore.map(|n| format!("product:{n}"));
        let held_name = held.map(|h| format!("product:{}", h.name));
        let obstacles = || {
            self.statics.iter().chain(self.products.iter().filter(|o| {
                Some(&o.name) != ignored.as_ref() && Some(&o.name) != held_name.as_ref()
            }))
        };
        for (part, p) in self.parts.iter().zip(&poses) {
            let aabb = part.geom.shape().compute_aabb(p);
            for o in obstacles() {
                if o.is_table && part.link <= 1 {
                    continue;
                }
                if aabb.intersects(&o.aabb) && intersects(p, part.geom.shape(), &o.pose, &o.cuboid)
                {
                    return Some(Hit {
                        a: self.names[part.link].clone(),
                        b: o.name.clone(),
                    });
                }
            }
        }
        if let Some(((la, lb), _)) = self.self_pairs(&poses, &self.allowed).first() {
            return Some(Hit {
                a: self.names[*la].clone(),
                b: self.names[*lb].clone(),
            });
        }
        if let Some(h) = held {
            let flange = self.arm.flange_pose(&self.base, q);
            let hp = pose(&(flange * h.in_flange));
            let cuboid = Cuboid::new(Vector::new(
                (h.size[0] / 2.0 + HELD_PADDING) as f32,
                (h.size[1] / 2.0 + HELD_PADDING) as f32,
                (h.size[2] / 2.0 + HELD_PADDING) as f32,
            ));
            let aabb = cuboid.compute_aabb(&hp);
            let name = format!("held:{}", h.name);
            for o in obstacles() {
                if aabb.intersects(&o.aabb) && intersects(&hp, &cuboid, &o.pose, &o.cuboid) {
                    return Some(Hit {
                        a: name,
                        b: o.name.clone(),
                    });
                }
            }
            for (part, p) in self.parts.iter().zip(&poses) {
                if part.link < DOF && intersects(&hp, &cuboid, p, part.geom.shape()) {
                    return Some(Hit {
                        a: name,
                        b: self.names[part.link].clone(),
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

fn intersects(p1: &Pose, s1: &dyn ParryShape, p2: &Pose, s2: &dyn ParryShape) -> bool {
    // An unsupported pair cannot happen with capsules and cuboids; treat it
    // as a collision to stay on the safe side.
    query::intersection_test(p1, s1, p2, s2).map_or(true, |i| i.intersecting)
}
