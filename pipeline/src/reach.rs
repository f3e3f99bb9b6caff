//! The robot's answers to the compiler's reach questions
//! ([`packwright_compiler::Workspace`]): the cell's arm (the UR10 or its
//! URDF) and the expert's poses, through [`Reachability`]. Every command
//! that reads `.pack` files for the robot (`check`, `compile`, `execute`,
//! `eval`) compiles with it, so that `check` accepts only what the expert
//! can reach.

use crate::episode::{arm_of, scene_of};
use crate::error::PipelineError;
use packwright_compiler::Workspace;
use packwright_compiler::emit::cell_record;
use packwright_compiler::model::Model;
use packwright_compiler::workspace::{Blocked, Lower, Pose, Released, Standing, Unreached};
use packwright_interface::outcome::{Hit, Stage};
use packwright_interface::world::Body;
use packwright_motion::collision::ProductBody;
use packwright_motion::execute::{self, Reachability};
use std::cell::RefCell;
use std::collections::BTreeMap;

/// The robot's workspace, one [`Reachability`] per cell, built when first
/// asked. A cell whose arm cannot be built (an unreadable URDF, reported
/// by the compiler itself; an unusable one, reported through
/// [`Workspace::robot`]) is not asked about.
#[derive(Default)]
pub struct RobotWorkspace {
    cells: RefCell<BTreeMap<usize, Built>>,
}

/// A cell's reach, or why its arm cannot be built: the robot
/// description's problem, or `None` where the compiler reports it itself
/// (an unreadable file, E012).
type Built = Result<Reachability, Option<String>>;

/// The arm of cell `cell` (its URDF and meshes read once) and its reach.
fn build(m: &Model, cell: usize) -> Built {
    let record = cell_record(m.cells.get(cell).ok_or(None)?);
    match arm_of(&record.robot) {
        Ok(arm) => Ok(Reachability::new(&arm, &scene_of(&record))),
        Err(PipelineError::Urdf { why, .. }) => Err(Some(why.to_string())),
        Err(_) => Err(None),
    }
}

impl RobotWorkspace {
    pub fn new() -> RobotWorkspace {
        RobotWorkspace::default()
    }

    /// `f` of cell `cell`'s [`Built`], built when first asked.
    fn with<T>(&self, m: &Model, cell: usize, f: impl FnOnce(&Built) -> T) -> T {
        let mut cells = self.cells.borrow_mut();
        f(cells.entry(cell).or_insert_with(|| build(m, cell)))
    }

    fn ask<T>(&self, m: &Model, cell: usize, f: impl FnOnce(&Reachability) -> T) -> Option<T> {
        self.with(m, cell, |built| built.as_ref().ok().map(f))
    }

    /// The first pose `unreached` finds out of reach with the `standing`
    /// products where they stand, and the one its nearest arm pose meets;
    /// where no product meets the pose itself (a lift, whose held product
    /// meets one on the way up), the nearest standing product without
    /// which it is reached (`check`'s W003 named no product for a lift
    /// the jitter blocked, and so said nothing).
    fn blocked_among(
        &self,
        m: &Model,
        cell: usize,
        standing: &[Standing],
        unreached: impl Fn(&Reachability) -> Option<execute::Unreached>,
    ) -> Option<Blocked> {
        let among = bodies(m, standing);
        self.ask(m, cell, |empty| {
            let r = empty.among(&among);
            let u = unreached(&r)?;
            let by = r
                .blocked_by(u.tip)
                .and_then(|name| index_of(m, standing, &name))
                .or_else(|| {
                    let away = |j: usize| {
                        let at = among[j].centre;
                        (at[0] - u.tip[0]).hypot(at[1] - u.tip[1])
                    };
                    let mut nearest: Vec<usize> = (0..among.len()).collect();
                    nearest.sort_by(|&a, &b| away(a).total_cmp(&away(b)));
                    let freeing = nearest.into_iter().find(|&j| {
                        let mut fewer = among.clone();
                        fewer.remove(j);
                        unreached(&empty.among(&fewer)).is_none()
                    })?;
                    index_of(m, standing, &among[freeing].name)
                });
            Some(Blocked {
                pose: pose(u).pose,
                by,
            })
        })
        .flatten()
    }
}

/// The standing products as the checker's bodies, named as the model
/// names them (on the table, square).
fn bodies(m: &Model, standing: &[Standing]) -> Vec<ProductBody> {
    standing
        .iter()
        .filter_map(|s| {
            let p = m.products.get(s.product)?;
            let wide = 2.0 * s.margin.max(0.0);
            Some(ProductBody {
                name: p.name.clone(),
                centre: [s.at[0], s.at[1], p.size[2] / 2.0],
                size: [p.size[0] + wide, p.size[1] + wide, p.size[2]],
                yaw: 0.0,
            })
        })
        .collect()
}

/// Which of `standing` is named `name`.
fn index_of(m: &Model, standing: &[Standing], name: &str) -> Option<usize> {
    standing
        .iter()
        .position(|s| m.products.get(s.product).is_some_and(|p| p.name == name))
}

fn pose(u: execute::Unreached) -> Unreached {
    let pose = match (u.stage, u.subgoal) {
        (Stage::Picking, 1) => Pose::Hover,
        (Stage::Picking, 2) => Pose::TopFace,
        (Stage::Picking, _) => Pose::Lift,
        (Stage::Placing, 1) => Pose::Approach,
        (Stage::Placing, 2) => Pose::AboveSlot,
        (Stage::Placing, _) => Pose::Release,
    };
    Unreached {
        pose,
        tip: u.tip,
        meets_itself: u.meets_itself,
    }
}

/// What a raised release meets lower down, in the compiler's terms.
fn lower(hit: Hit) -> Lower {
    match hit {
        Hit::Bodies {
            a: Body::Held(_),
            b: Body::Box(_),
        } => Lower::ProductOnBox,
        Hit::Bodies {
            a: part @ (Body::Link(_) | Body::Cup),
            b: Body::Box(_),
        } => Lower::ArmOnBox(part.to_string()),
        other => Lower::Other(other.to_string()),
    }
}

impl Workspace for RobotWorkspace {
    fn robot(&self, m: &Model, cell: usize) -> Option<String> {
        self.with(m, cell, |built| built.as_ref().err().cloned().flatten())
    }

    fn start(&self, m: &Model, cell: usize) -> Option<Unreached> {
        self.ask(m, cell, |r| {
            r.start().err().map(|tip| Unreached {
                pose: Pose::Start,
                tip,
                meets_itself: false,
            })
        })
        .flatten()
    }

    fn pick(&self, m: &Model, cell: usize, product: usize, at: [f64; 2]) -> Option<Unreached> {
        let size = m.products.get(product)?.size;
        self.ask(m, cell, |r| r.picking(size, at).err().map(pose))
            .flatten()
    }

    fn place(
        &self,
        m: &Model,
        cell: usize,
        product: usize,
        at: [f64; 2],
        slot: usize,
    ) -> Result<Released, Unreached> {
        let Some(size) = m.products.get(product).map(|p| p.size) else {
            return Ok(Released::default());
        };
        self.ask(m, cell, |r| r.placing(size, at, slot))
            .map_or(Ok(Released::default()), |placed| match placed {
                Ok(release) => Ok(Released {
                    drop: Some(release.drop),
                    lower: release.lower.map(lower),
                }),
                Err(u) => Err(pose(u)),
            })
    }

    fn start_among(&self, m: &Model, cell: usize, standing: &[Standing]) -> Option<usize> {
        let among = bodies(m, standing);
        self.ask(m, cell, |r| r.among(&among).start_blocked_by())
            .flatten()
            .and_then(|name| index_of(m, standing, &name))
    }

    fn pick_among(
        &self,
        m: &Model,
        cell: usize,
        product: usize,
        at: [f64; 2],
        standing: &[Standing],
    ) -> Option<Blocked> {
        let size = m.products.get(product)?.size;
        self.blocked_among(m, cell, standing, |r| r.picking(size, at).err())
    }

    fn pick_way_among(
        &self,
        m: &Model,
        cell: usize,
        product: usize,
        at: [f64; 2],
        standing: &[Standing],
    ) -> Option<Blocked> {
        // The way the empty cell has and the standing products take away
        // ([`Reachability::way_to_hover`]), with the product its straight
        // motion meets.
        let size = m.products.get(product)?.size;
        let among = bodies(m, standing);
        self.ask(m, cell, |r| {
            let none = r.way_to_hover(&among, size, at)?;
            Some(Blocked {
                pose: match none.from {
                    None => Pose::HoverFromStart,
                    Some(_) => Pose::HoverFromBox,
                },
                by: none.by.and_then(|name| index_of(m, standing, &name)),
            })
        })
        .flatten()
    }

    fn place_among(
        &self,
        m: &Model,
        cell: usize,
        product: usize,
        at: [f64; 2],
        slot: usize,
        standing: &[Standing],
    ) -> Option<Blocked> {
        let size = m.products.get(product)?.size;
        self.blocked_among(m, cell, standing, |r| r.placing(size, at, slot).err())
    }
}

#[cfg(test)]
mod tests {
    /// `check`'s W002 (products placed too close together) uses its own
    /// copy of the room the planner keeps round a held product, since the
    /// compiler does not depend on the robot crates: the two must agree.
    #[test]
    fn the_compilers_room_round_a_held_product_is_the_planners() {
        assert_eq!(
            packwright_compiler::HELD_ROOM,
            packwright_kinematics::body::HELD_PADDING
        );
    }

    /// A robot description's acceleration and jerk limits are held to the
    /// bounds a cell's `acceleration` and `jerk` statements have (E029).
    #[test]
    fn a_descriptions_dynamics_bounds_are_a_cells() {
        assert_eq!(
            packwright_compiler::model::ACCELERATION_RANGE,
            packwright_kinematics::ACCELERATION_RANGE
        );
        assert_eq!(
            packwright_compiler::model::JERK_RANGE,
            packwright_kinematics::JERK_RANGE
        );
    }

    /// `check` refuses a product side the simulator cannot build (E025).
    #[test]
    fn the_compilers_thinnest_product_is_the_simulators() {
        assert_eq!(
            packwright_compiler::resolve::MIN_PRODUCT_SIZE,
            packwright_sim::MIN_SIZE
        );
    }

    /// `check` refuses a cell the simulator cannot build (E055).
    #[test]
    fn the_compilers_farthest_coordinate_is_the_simulators() {
        assert_eq!(
            packwright_compiler::resolve::MAX_COORDINATE,
            packwright_sim::MAX_COORD
        );
    }

    /// W004's fix names the height the expert lets a product go at
    /// where nothing stops it lower: the compiler's copy must agree.
    #[test]
    fn the_compilers_release_gap_is_the_experts() {
        assert_eq!(
            packwright_compiler::RELEASE_GAP_MM / 1000.0,
            packwright_motion::expert::RELEASE_GAP
        );
    }
}
