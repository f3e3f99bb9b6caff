//! From the compiler's model to the runtime's terms: a cell scene, the
//! inventory's product specs, an order's assignment and the products'
//! start placements. (The runtime does not depend on the compiler.)

use anyhow::{Context, bail};
use packwright_compiler::Compiled;
use packwright_compiler::artifact::{CellRecord, DemonstrationRecord, RobotRecord, WorldFile};
use packwright_compiler::emit::cell_record;
use packwright_compiler::expand::Setup;
use packwright_compiler::model::Model;
use packwright_runtime::execute::OrderTask;
use packwright_runtime::robot::{Arm, from_urdf};
use packwright_runtime::scene::{
    BoxSpec, CellScene, DEFAULT_MASS, Placement, ProductSpec, SlotSpec,
};

/// What `execute` needs: the arm, the task and where products start.
pub struct Episode {
    pub arm: Arm,
    pub task: OrderTask,
    pub placements: Vec<Placement>,
}

/// The runtime's scene of a cell, from its compiled record (the same for
/// `execute`, which compiles in memory, and `demonstrate`, which reads
/// `orders.json`).
pub fn scene_of(cell: &CellRecord) -> CellScene {
    CellScene {
        base: cell.base,
        suction: cell.suction,
        lift: cell.lift,
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
pub fn arm_of(robot: &RobotRecord) -> anyhow::Result<Arm> {
    match robot {
        RobotRecord::Ur10 => Ok(Arm::ur10()),
        RobotRecord::Urdf(path) => {
            let text =
                std::fs::read_to_string(path).with_context(|| format!("cannot read {path}"))?;
            from_urdf(&text).with_context(|| format!("robot description {path}"))
        }
    }
}

/// The episode of a setup (an order's, or a scenario case's).
pub fn episode(m: &Model, setup: &Setup) -> anyhow::Result<Episode> {
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
        arm: arm_of(&cell.robot)?,
        task,
        placements,
    })
}

/// The setup named by `--order` or `--scenario`.
pub fn find_setup(
    c: &Compiled,
    order: Option<&str>,
    scenario: Option<&str>,
) -> anyhow::Result<(String, Setup)> {
    let m = &c.model;
    if let Some(name) = scenario {
        for suite in &c.expanded.suites {
            if let Some(case) = suite.cases.iter().find(|k| k.name == name) {
                return Ok((case.name.clone(), case.setup.clone()));
            }
        }
        let known: Vec<&str> = c
            .expanded
            .suites
            .iter()
            .flat_map(|s| s.cases.first().map(|k| k.name.as_str()))
            .collect();
        bail!(
            "no scenario `{name}`; scenarios are named like: {}",
            known.join(", ")
        );
    }
    let Some(name) = order else {
        bail!("give --order NAME or --scenario NAME");
    };
    let Some(o) = m.orders.iter().find(|o| o.name == name) else {
        let known: Vec<&str> = m.orders.iter().map(|o| o.name.as_str()).collect();
        bail!("no order `{name}`; known orders: {}", known.join(", "));
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
pub fn demonstration_episode(
    world: &WorldFile,
    demo: &DemonstrationRecord,
) -> anyhow::Result<Episode> {
    let Some(cell) = world.cells.iter().find(|c| c.name == demo.cell) else {
        bail!("orders.json has no cell `{}`", demo.cell);
    };
    let Some(inv) = world.inventories.iter().find(|i| i.name == demo.inventory) else {
        bail!("orders.json has no inventory `{}`", demo.inventory);
    };
    let scene = scene_of(cell);
    let products = inv
        .products
        .iter()
        .map(|at| {
            let p = world
                .products
                .iter()
                .find(|p| p.name == at.product)
                .with_context(|| format!("orders.json has no product `{}`", at.product))?;
            Ok(ProductSpec {
                name: p.name.clone(),
                size: p.size,
                mass: p.mass.unwrap_or(DEFAULT_MASS),
            })
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
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
            _ => bail!(
                "demonstration of `{}` names an unknown product `{name}`",
                demo.block
            ),
        }
    }
    let placements = demo
        .start
        .iter()
        .map(|at| {
            let p =
                index(&at.product).with_context(|| format!("unknown product `{}`", at.product))?;
            Ok(Placement {
                product: products[p].clone(),
                centre: at.at,
            })
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    let arm = arm_of(&cell.robot)?;
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
