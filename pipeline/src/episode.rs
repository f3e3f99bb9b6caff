//! From the compiler's model (or its compiled artifacts) to the robot
//! half's terms: a cell scene, the inventory's product specs, an order's
//! assignment and the products' start placements. (The robot crates do
//! not depend on the compiler.)

use crate::error::{PipelineError, Result};
use packwright_compiler::Compiled;
use packwright_compiler::artifact::{CellRecord, DemonstrationRecord, RobotRecord, WorldFile};
use packwright_compiler::emit::cell_record;
use packwright_compiler::expand::{Expanded, Setup};
use packwright_compiler::model::Model;
use packwright_interface::OrderTask;
use packwright_interface::scene::{
    BoxSpec, CellScene, DEFAULT_MASS, Placement, ProductSpec, SlotSpec,
};
use packwright_kinematics::{Arm, Joints, from_urdf_with};
use packwright_motion::collision::ProductBody;
use packwright_motion::execute;
use packwright_sim::Simulator;
use std::path::{Path, PathBuf};

/// What `execute` needs: the arm, the task and where products start.
pub struct Episode {
    pub arm: Arm,
    pub task: OrderTask,
    pub placements: Vec<Placement>,
}

impl Episode {
    /// The arm's start pose (over the pending area), clear of the products
    /// standing in the cell where a branch is.
    pub fn home(&self) -> Result<Joints> {
        let standing: Vec<ProductBody> =
            self.placements.iter().map(ProductBody::at_start).collect();
        execute::home_among(&self.arm, &self.task.cell, &standing).ok_or_else(|| {
            PipelineError::NoStartPose {
                cell: self.task.cell.name.clone(),
            }
        })
    }

    /// A fresh simulation of the episode with the arm at `start`.
    pub fn simulator(&self, start: Joints) -> Result<Simulator> {
        Ok(Simulator::new(
            self.arm.clone(),
            &self.task.cell,
            &self.placements,
            start,
        )?)
    }
}

/// The runtime's scene of a cell, from its compiled record (the same for
/// `execute`, which compiles in memory, and `demonstrate`, which reads
/// `orders.json`).
pub fn scene_of(cell: &CellRecord) -> CellScene {
    CellScene {
        name: cell.name.clone(),
        base: cell.base,
        suction: cell.suction,
        lift: cell.lift,
        speed: cell.speed,
        grip_settle: cell.grip_settle,
        release_settle: cell.release_settle,
        descent: cell.descent,
        pending: (cell.pending.min, cell.pending.max),
        boxes: cell
            .boxes
            .iter()
            .map(|b| BoxSpec {
                name: b.name.clone(),
                centre: b.centre,
                size: b.size,
            })
            .collect(),
        slots: cell
            .slots
            .iter()
            .map(|s| SlotSpec {
                name: s.name.clone(),
                position: s.position,
                box_index: cell
                    .boxes
                    .iter()
                    .position(|b| b.name == s.box_name)
                    .unwrap_or(0),
            })
            .collect(),
    }
}

/// The arm a cell names: the built-in UR10, or a URDF file.
pub fn arm_of(robot: &RobotRecord) -> Result<Arm> {
    match robot {
        RobotRecord::Ur10 => Ok(Arm::ur10()),
        RobotRecord::Urdf(path) => {
            let text =
                crate::regular::read_to_string(path.as_ref()).map_err(|e| PipelineError::Read {
                    path: path.into(),
                    reason: e.to_string(),
                })?;
            let meshes = |filename: &str| read_mesh(Path::new(path), filename);
            from_urdf_with(&text, &meshes).map_err(|why| PipelineError::Urdf {
                path: path.clone(),
                why,
            })
        }
    }
}

/// The bytes of a collision mesh that the description at `urdf` names:
/// `package://NAME/REST` from a folder NAME on `ROS_PACKAGE_PATH`, the
/// description's folders or a folder NAME beside one of them; `file://`
/// absolute; anything else relative to the description.
fn read_mesh(urdf: &Path, filename: &str) -> Result<Vec<u8>, String> {
    let dir = urdf.parent().unwrap_or(Path::new(""));
    let file = if let Some(rest) = filename.strip_prefix("package://") {
        let (package, inside) = rest.split_once('/').unwrap_or((rest, ""));
        let roots = std::env::var_os("ROS_PACKAGE_PATH")
            .map(|p| std::env::split_paths(&p).collect::<Vec<_>>())
            .unwrap_or_default();
        let mut candidates: Vec<PathBuf> =
            roots.iter().map(|r| r.join(package).join(inside)).collect();
        for up in dir.ancestors() {
            if up.file_name().is_some_and(|n| n == package) {
                candidates.push(up.join(inside));
            }
            candidates.push(up.join(package).join(inside));
        }
        candidates
            .into_iter()
            .find(|c| c.is_file())
            .ok_or_else(|| {
                format!(
                    "package `{package}` not found on ROS_PACKAGE_PATH or beside the description"
                )
            })?
    } else if let Some(absolute) = filename.strip_prefix("file://") {
        PathBuf::from(absolute)
    } else {
        dir.join(filename)
    };
    crate::regular::read(&file).map_err(|e| format!("cannot read {}: {e}", file.display()))
}

/// The arm a cell packs with: its robot, with the cell's acceleration and
/// jerk limits where it gives them, then slowed to the cell's speed.
pub fn cell_arm(cell: &CellRecord) -> Result<Arm> {
    Ok(arm_of(&cell.robot)?
        .with_dynamics(cell.acceleration, cell.jerk)
        .at_speed(cell.speed))
}

/// The name of the cell a setup packs in.
pub fn cell_of(compiled: &Compiled, setup: &Setup) -> String {
    let m = &compiled.model;
    m.inventories
        .get(setup.inventory)
        .and_then(|inv| m.cells.get(inv.cell))
        .map(|c| c.name.clone())
        .unwrap_or_default()
}

/// The episode of a setup (an order's, or a scenario case's).
pub fn episode(m: &Model, setup: &Setup) -> Result<Episode> {
    let inv = &m.inventories[setup.inventory];
    let products: Vec<ProductSpec> = inv
        .entries
        .iter()
        .map(|e| {
            let p = &m.products[e.product];
            ProductSpec {
                name: p.name.clone(),
                size: p.size,
                mass: p.mass.unwrap_or(DEFAULT_MASS),
            }
        })
        .collect();
    let cell = cell_record(&m.cells[inv.cell]);
    let task = OrderTask {
        cell: scene_of(&cell),
        products,
        assignment: setup.assignment.clone(),
    };
    let placements = (0..inv.entries.len())
        .filter(|e| !setup.missing.contains(e))
        .map(|e| {
            let spec = task.products[e].clone();
            let centre = match setup.slot_of(e) {
                Some(s) if setup.human_packed.contains(&e) => task.goal(e, s),
                _ => [
                    setup.positions[e][0],
                    setup.positions[e][1],
                    spec.size[2] / 2.0,
                ],
            };
            Placement {
                product: spec,
                centre,
            }
        })
        .collect();
    Ok(Episode {
        arm: cell_arm(&cell)?,
        task,
        placements,
    })
}

/// What to say of a scenario `name` that `x` does not hold: the suite's
/// name for that number (`SUITE/7` for `SUITE/07`: numbers are padded to
/// the count's digits), the suite's range (a number past its count), or
/// how scenarios are named.
pub fn scenario_hint(x: &Expanded, name: &str) -> String {
    let named = name.rsplit_once('/').and_then(|(suite, number)| {
        let suite = x.suites.iter().find(|s| s.name == suite)?;
        Some((suite, number.parse::<usize>().ok()?))
    });
    match named {
        Some((suite, n)) if (1..=suite.cases.len()).contains(&n) => format!(
            "did you mean `{}`? (a suite's numbers are padded to its count's digits)",
            suite.cases[n - 1].name
        ),
        Some((suite, _)) => match (suite.cases.first(), suite.cases.last()) {
            (Some(first), Some(last)) => format!(
                "suite `{}` has {} scenarios, `{}` to `{}`",
                suite.name,
                suite.cases.len(),
                first.name,
                last.name
            ),
            _ => format!("suite `{}` has no scenarios", suite.name),
        },
        None => {
            let known: Vec<&str> = x
                .suites
                .iter()
                .flat_map(|s| s.cases.first().map(|k| k.name.as_str()))
                .collect();
            format!("scenarios are named like: {}", known.join(", "))
        }
    }
}

/// The setup named by `--order` or `--scenario`.
pub fn find_setup(
    c: &Compiled,
    order: Option<&str>,
    scenario: Option<&str>,
) -> Result<(String, Setup)> {
    let m = &c.model;
    if let Some(name) = scenario {
        for suite in &c.expanded.suites {
            if let Some(case) = suite.cases.iter().find(|k| k.name == name) {
                return Ok((case.name.clone(), case.setup.clone()));
            }
        }
        return Err(PipelineError::NoSuch {
            what: "scenario",
            name: name.to_owned(),
            known: scenario_hint(&c.expanded, name),
        });
    }
    let Some(name) = order else {
        return Err(PipelineError::Selection(
            "give --order NAME or --scenario NAME".into(),
        ));
    };
    let Some(o) = m.orders.iter().find(|o| o.name == name) else {
        let known: Vec<&str> = m.orders.iter().map(|o| o.name.as_str()).collect();
        return Err(PipelineError::NoSuch {
            what: "order",
            name: name.to_owned(),
            known: format!("known orders: {}", known.join(", ")),
        });
    };
    let inv = &m.inventories[o.inventory];
    Ok((
        o.name.clone(),
        Setup {
            inventory: o.inventory,
            assignment: o.assignment.iter().map(|a| (a.entry, a.slot)).collect(),
            human_packed: Vec::new(),
            missing: Vec::new(),
            positions: inv.entries.iter().map(|e| e.at).collect(),
        },
    ))
}

/// The episode of a compiled demonstration (from the artifacts): the
/// assignment in the demonstrated sequence, then the products a worker had
/// packed.
pub fn demonstration_episode(world: &WorldFile, demo: &DemonstrationRecord) -> Result<Episode> {
    let unknown = |what, name: &str| PipelineError::Unknown {
        file: "orders.json",
        what,
        name: name.to_owned(),
    };
    let cell = world
        .cells
        .iter()
        .find(|c| c.name == demo.cell)
        .ok_or_else(|| unknown("cell", &demo.cell))?;
    let inv = world
        .inventories
        .iter()
        .find(|i| i.name == demo.inventory)
        .ok_or_else(|| unknown("inventory", &demo.inventory))?;
    let scene = scene_of(cell);
    let products = inv
        .products
        .iter()
        .map(|at| {
            let p = world
                .products
                .iter()
                .find(|p| p.name == at.product)
                .ok_or_else(|| unknown("product", &at.product))?;
            Ok(ProductSpec {
                name: p.name.clone(),
                size: p.size,
                mass: p.mass.unwrap_or(DEFAULT_MASS),
            })
        })
        .collect::<Result<Vec<_>>>()?;
    let index = |name: &str| products.iter().position(|p| p.name == name);
    let slot_of = |name: &str| {
        demo.assignment
            .iter()
            .find(|a| a.product == name)
            .and_then(|a| scene.slots.iter().position(|s| s.name == a.slot))
    };
    let mut assignment = Vec::new();
    for name in demo.sequence.iter().chain(&demo.human_packed) {
        match (index(name), slot_of(name)) {
            (Some(p), Some(s)) => assignment.push((p, s)),
            _ => return Err(unknown("product of a demonstration", name)),
        }
    }
    let placements = demo
        .start
        .iter()
        .map(|at| {
            let p = index(&at.product).ok_or_else(|| unknown("product", &at.product))?;
            Ok(Placement {
                product: products[p].clone(),
                centre: at.at,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    let arm = cell_arm(cell)?;
    Ok(Episode {
        arm,
        task: OrderTask {
            cell: scene,
            products,
            assignment,
        },
        placements,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use packwright_compiler::{Anywhere, MemoryLoader, check};

    /// A scenario name a user mistyped gets the suite's name for that
    /// number, or the suite's range; any other, how scenarios are named.
    #[test]
    fn a_mistyped_scenario_gets_its_padded_name_or_the_suites_range() {
        let text = "cell c {
  robot ur10
  base (0, 0, 0)
  suction 100 mm
  pending (0.45, -0.50) to (0.85, -0.10)
  box b (0.00, 0.65) size (0.40, 0.30, 0.08)
  slot s1 (-0.12, 0.58)
  slot s2 ( 0.00, 0.58)
}
product p1 cube 50 mm
product p2 cube 50 mm
inventory inv for c {
  p1 (0.50, -0.20)
  p2 (0.62, -0.20)
}
scenarios many for inv {
  choose 1 of p1, p2 into s1, s2
  count 12
}";
        let loader = MemoryLoader::new().with("hint.pack", text);
        let compiled = check(&loader, &["hint.pack".into()], &Anywhere)
            .unwrap_or_else(|f| panic!("{}", f.render()));
        let hint = |name| scenario_hint(&compiled.expanded, name);
        assert_eq!(
            hint("many/7"),
            "did you mean `many/07`? (a suite's numbers are padded to its count's digits)"
        );
        assert_eq!(
            hint("many/13"),
            "suite `many` has 12 scenarios, `many/01` to `many/12`"
        );
        assert_eq!(hint("few/1"), "scenarios are named like: many/01");
    }
}
