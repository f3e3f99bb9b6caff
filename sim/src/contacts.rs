//! Which contacts are collisions, and their names.

use super::{ARM_TOUCH, CUP, HELD_PENETRATION, Part, RELEASE_GRACE, Simulator};
use packwright_interface::world::{Body, Contact};
use packwright_kinematics::DOF;
use packwright_kinematics::body::{self, adjacent};

impl Simulator {
    fn name(&self, part: Part) -> Body {
        match part {
            Part::Arm(i) => body::part_body(&self.arm, i),
            Part::Table => Body::Table,
            Part::Box(k) => Body::Box(
                self.cell
                    .boxes
                    .get(k)
                    .map_or_else(String::new, |b| b.name.clone()),
            ),
            Part::Product(k) => {
                let name = self
                    .products
                    .get(k)
                    .map_or_else(String::new, |p| p.name.clone());
                if self.held.as_ref().is_some_and(|h| h.product == k) {
                    Body::Held(name)
                } else {
                    Body::Product(name)
                }
            }
        }
    }

    /// Whether `part` can collide: an arm part or the held product; its
    /// rank orders the two sides of a contact.
    fn rank(&self, part: Part) -> Option<usize> {
        match part {
            Part::Arm(i) => Some(i),
            Part::Product(k) if self.held.as_ref().is_some_and(|h| h.product == k) => Some(CUP + 1),
            _ => None,
        }
    }

    /// For a contact between `p1` and `p2`: the colliding side first, the
    /// other, and the distance under which it counts; `None` when the pair
    /// never counts.
    fn rule(&self, p1: Part, p2: Part) -> Option<(Part, Part, f64)> {
        let (a, b) = match (self.rank(p1), self.rank(p2)) {
            (None, None) => return None,
            (Some(r1), Some(r2)) if r2 < r1 => (p2, p1),
            (None, Some(_)) => (p2, p1),
            _ => (p1, p2),
        };
        let holds = |k: usize| {
            self.held.as_ref().is_some_and(|h| h.product == k)
                || self.released.is_some_and(|(r, _)| r == k)
        };
        match (a, b) {
            (Part::Arm(i), Part::Arm(j)) => {
                let pair = (i.min(j), i.max(j));
                (!adjacent(i, j) && !self.neighbours.contains(&pair)).then_some((a, b, ARM_TOUCH))
            }
            (Part::Arm(i), Part::Table) if i <= 1 => None,
            (Part::Arm(i), Part::Product(k)) if i >= DOF && holds(k) => None,
            (Part::Arm(_), _) => Some((a, b, ARM_TOUCH)),
            (Part::Product(_), _) => Some((a, b, -HELD_PENETRATION)),
            _ => None,
        }
    }

    /// Records the contacts of the last step.
    pub(super) fn collect_contacts(&mut self) {
        let mut now: Vec<(Body, Body)> = Vec::new();
        let mut released_near = false;
        let released = self.released.map(|(r, _)| r);
        for pair in self.world.narrow_phase.contact_pairs() {
            let (Some(c1), Some(c2)) = (
                self.world.colliders.get(pair.collider1),
                self.world.colliders.get(pair.collider2),
            ) else {
                continue;
            };
            let (Some(p1), Some(p2)) = (Part::decode(c1.user_data), Part::decode(c2.user_data))
            else {
                continue;
            };
            let depth = pair
                .manifolds()
                .iter()
                .flat_map(|m| m.points.iter())
                .map(|p| f64::from(p.dist))
                .fold(f64::INFINITY, f64::min);
            if let Some(r) = released
                && depth < ARM_TOUCH
                && matches!((p1, p2), (Part::Arm(i), Part::Product(k)) | (Part::Product(k), Part::Arm(i)) if i >= DOF && k == r)
            {
                released_near = true;
            }
            if let Some((a, b, limit)) = self.rule(p1, p2)
                && depth < limit
            {
                now.push((self.name(a), self.name(b)));
            }
        }
        now.sort();
        now.dedup();
        let time = self.time();
        for (a, b) in &now {
            if !self.touching.iter().any(|(x, y)| x == a && y == b) {
                self.collisions.push(Contact {
                    time,
                    a: a.clone(),
                    b: b.clone(),
                });
            }
        }
        self.touching = now;
        self.released = match self.released {
            Some((r, _)) if released_near => Some((r, 0)),
            Some((_, n)) if n + 1 >= RELEASE_GRACE => None,
            Some((r, n)) => Some((r, n + 1)),
            None => None,
        };
    }
}
