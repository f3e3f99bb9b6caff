//! RRT-Connect in joint space: the baseline planner (the paper's
//! "RM + RRT-Connect"). Written here rather than taken from the `rrt` crate
//! because every motion between tree nodes must be checked (at 1 degree)
//! and plans must be reproducible from a seed.
//!
//! Two trees grow from the start and the goal towards seeded random
//! samples, each extension a straight joint-space step of at most `step`
//! radians that is collision-checked along its length; when the trees meet,
//! the path is shortcut (random pairs joined directly when the motion is
//! free) and checked once more as a whole.

use crate::collision::{Checker, Held, Touch};
use packwright_kinematics::{DOF, Joints, Limits};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::time::Instant;

#[derive(Debug, Clone, PartialEq)]
pub struct RrtConfig {
    /// Largest extension, radians (max over joints).
    pub step: f64,
    /// Samples before giving up.
    pub max_samples: usize,
    /// Shortcut attempts on the found path.
    pub shortcuts: usize,
    pub seed: u64,
    /// Give up (no path) once this wall-clock time has passed, whatever
    /// samples are left.
    pub deadline: Option<Instant>,
}

impl Default for RrtConfig {
    fn default() -> RrtConfig {
        RrtConfig {
            step: 0.15,
            max_samples: 4000,
            shortcuts: 100,
            seed: 0,
            deadline: None,
        }
    }
}

/// What the planner avoids and ignores.
pub struct Query<'a> {
    pub checker: &'a Checker,
    pub limits: &'a [Limits; DOF],
    pub held: Option<&'a Held>,
    /// The product being picked or just released, which the cup may touch
    /// ([`Touch`]).
    pub ignore: Option<Touch<'a>>,
}

impl Query<'_> {
    fn free(&self, a: &Joints, b: &Joints) -> bool {
        self.checker
            .check_motion(a, b, self.held, self.ignore)
            .is_none()
    }
}

fn distance(a: &Joints, b: &Joints) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).powi(2))
        .sum::<f64>()
        .sqrt()
}

/// A point at most `step` (max-norm) from `from` towards `to`.
fn towards(from: &Joints, to: &Joints, step: f64) -> Joints {
    let span = from
        .iter()
        .zip(to)
        .map(|(a, b)| (b - a).abs())
        .fold(0.0, f64::max);
    if span <= step {
        return *to;
    }
    let t = step / span;
    std::array::from_fn(|j| from[j] + (to[j] - from[j]) * t)
}

struct Tree {
    nodes: Vec<Joints>,
    parents: Vec<usize>,
}

impl Tree {
    fn new(root: Joints) -> Tree {
        Tree {
            nodes: vec![root],
            parents: vec![0],
        }
    }

    fn nearest(&self, q: &Joints) -> usize {
        let mut best = (0, f64::INFINITY);
        for (i, n) in self.nodes.iter().enumerate() {
            let d = distance(n, q);
            if d < best.1 {
                best = (i, d);
            }
        }
        best.0
    }

    /// The path from the root to node `i`.
    fn path_to(&self, mut i: usize) -> Vec<Joints> {
        let mut out = vec![self.nodes[i]];
        while i != 0 {
            i = self.parents[i];
            out.push(self.nodes[i]);
        }
        out.reverse();
        out
    }
}

enum Extend {
    Reached(usize),
    Advanced(usize),
    Trapped,
}

fn extend(tree: &mut Tree, target: &Joints, step: f64, query: &Query) -> Extend {
    let near = tree.nearest(target);
    let from = tree.nodes[near];
    let new = towards(&from, target, step);
    if !query.free(&from, &new) {
        return Extend::Trapped;
    }
    tree.nodes.push(new);
    tree.parents.push(near);
    let i = tree.nodes.len() - 1;
    if new == *target {
        Extend::Reached(i)
    } else {
        Extend::Advanced(i)
    }
}

fn connect(tree: &mut Tree, target: &Joints, step: f64, query: &Query) -> Option<usize> {
    loop {
        match extend(tree, target, step, query) {
            Extend::Reached(i) => return Some(i),
            Extend::Advanced(_) => {}
            Extend::Trapped => return None,
        }
    }
}

/// A collision-free joint path from `start` to `goal` (both included), or
/// `None` if none was found within the sample budget. The same inputs and
/// seed always give the same path.
pub fn plan(query: &Query, start: Joints, goal: Joints, config: &RrtConfig) -> Option<Vec<Joints>> {
    if query
        .checker
        .check(&start, query.held, query.ignore)
        .is_some()
        || query
            .checker
            .check(&goal, query.held, query.ignore)
            .is_some()
    {
        return None;
    }
    if query.free(&start, &goal) {
        return Some(vec![start, goal]);
    }
    search(query, start, goal, config)
}

/// RRT-Connect between two free configurations whose direct motion is
/// already known to collide (no direct check, no end-point check).
pub fn search(
    query: &Query,
    start: Joints,
    goal: Joints,
    config: &RrtConfig,
) -> Option<Vec<Joints>> {
    let mut rng = ChaCha8Rng::seed_from_u64(config.seed);
    // Sample within the limits, around the span of the query.
    let bounds: [(f64, f64); DOF] = std::array::from_fn(|j| {
        let l = &query.limits[j];
        let lo = (start[j].min(goal[j]) - std::f64::consts::PI).max(l.lower);
        let hi = (start[j].max(goal[j]) + std::f64::consts::PI).min(l.upper);
        (lo.min(hi), hi.max(lo))
    });
    let mut a = Tree::new(start);
    let mut b = Tree::new(goal);
    let mut a_is_start = true;
    for _ in 0..config.max_samples {
        if config.deadline.is_some_and(|d| Instant::now() >= d) {
            return None;
        }
        let sample: Joints = std::array::from_fn(|j| rng.random_range(bounds[j].0..=bounds[j].1));
        if let Extend::Advanced(i) | Extend::Reached(i) =
            extend(&mut a, &sample, config.step, query)
        {
            let new = a.nodes[i];
            if let Some(k) = connect(&mut b, &new, config.step, query) {
                let (from_start, from_goal) = if a_is_start {
                    (a.path_to(i), b.path_to(k))
                } else {
                    (b.path_to(k), a.path_to(i))
                };
                let mut path = from_start;
                path.extend(from_goal.into_iter().rev().skip(1));
                let path = shortcut(path, query, config, &mut rng);
                return path
                    .windows(2)
                    .all(|w| query.free(&w[0], &w[1]))
                    .then_some(path);
            }
        }
        std::mem::swap(&mut a, &mut b);
        a_is_start = !a_is_start;
    }
    None
}

/// Joins random pairs of waypoints directly when the motion is free.
fn shortcut(
    mut path: Vec<Joints>,
    query: &Query,
    config: &RrtConfig,
    rng: &mut ChaCha8Rng,
) -> Vec<Joints> {
    for _ in 0..config.shortcuts {
        if path.len() < 3 {
            break;
        }
        let i = rng.random_range(0..path.len() - 2);
        let j = rng.random_range(i + 2..path.len());
        if query.free(&path[i], &path[j]) {
            path.drain(i + 1..j);
        }
    }
    path
}
