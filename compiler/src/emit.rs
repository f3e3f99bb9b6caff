//! Phase 6: serialise everything into the artifact files' bytes. Pure and
//! deterministic: the same model gives the same bytes (floats rounded to
//! micrometres in JSON, tensors in a fixed order).

use crate::artifact::*;
use crate::dataset::{Graphs, slot_goal};
use crate::error::Error;
use crate::expand::{Expanded, Setup};
use crate::model::{Cell, Model, RobotModel};
use crate::source::SourceMap;
use safetensors::tensor::{Dtype, TensorView};
use serde::Serialize;
use sha2::{Digest, Sha256};
use std::collections::HashMap;

/// One output file.
#[derive(Debug, Clone, PartialEq)]
pub struct Artifact {
    pub name: &'static str,
    pub bytes: Vec<u8>,
}

/// Round to micrometres so that JSON shows `0.58`, not `0.5800000000000001`.
fn r6(v: f64) -> f64 {
    let r = (v * 1e6).round() / 1e6;
    if r == 0.0 { 0.0 } else { r }
}

fn r6n<const N: usize>(v: [f64; N]) -> [f64; N] {
    v.map(r6)
}

fn json<T: Serialize>(value: &T) -> Result<Vec<u8>, Error> {
    let mut bytes = serde_json::to_vec_pretty(value).map_err(|e| Error::Internal {
        what: e.to_string(),
    })?;
    bytes.push(b'\n');
    Ok(bytes)
}

pub fn emit(
    sources: &SourceMap,
    m: &Model,
    ex: &Expanded,
    g: &Graphs,
) -> Result<Vec<Artifact>, Error> {
    Ok(vec![
        Artifact {
            name: "manifest.json",
            bytes: json(&manifest(sources, m, ex, g))?,
        },
        Artifact {
            name: "labels.json",
            bytes: json(&labels(m))?,
        },
        Artifact {
            name: "orders.json",
            bytes: json(&world(m))?,
        },
        Artifact {
            name: "scenarios.json",
            bytes: json(&scenarios(m, ex))?,
        },
        Artifact {
            name: "graphs.safetensors",
            bytes: tensors(g)?,
        },
    ])
}

fn name_of(m: &Model, inventory: usize, entry: usize) -> String {
    m.products[m.inventories[inventory].entries[entry].product]
        .name
        .clone()
}

fn assignments(m: &Model, setup: &Setup) -> Vec<Assignment> {
    let cell = &m.cells[m.inventories[setup.inventory].cell];
    setup
        .assignment
        .iter()
        .map(|&(e, s)| Assignment {
            product: name_of(m, setup.inventory, e),
            slot: cell.slots[s].name.clone(),
            label: s as u32 + 1,
            goal: r6n(slot_goal(m, setup, e).unwrap_or_default()),
        })
        .collect()
}

/// Present products at the start, packed ones in their slots.
fn start(m: &Model, setup: &Setup) -> Vec<At> {
    let inv = &m.inventories[setup.inventory];
    (0..inv.entries.len())
        .filter(|e| !setup.missing.contains(e))
        .map(|e| {
            let h = m.products[inv.entries[e].product].size[2];
            let at = if setup.human_packed.contains(&e) {
                slot_goal(m, setup, e).unwrap_or_default()
            } else {
                [setup.positions[e][0], setup.positions[e][1], h / 2.0]
            };
            At {
                product: name_of(m, setup.inventory, e),
                at: r6n(at),
            }
        })
        .collect()
}

fn names(m: &Model, inventory: usize, entries: &[usize]) -> Vec<String> {
    entries.iter().map(|&e| name_of(m, inventory, e)).collect()
}

fn manifest(sources: &SourceMap, m: &Model, ex: &Expanded, g: &Graphs) -> Manifest {
    let cell_of = |inv: usize| m.cells[m.inventories[inv].cell].name.clone();
    let demo_blocks = ex
        .blocks
        .iter()
        .map(|b| {
            let range = b.first_demo..b.first_demo + b.demos;
            DemoBlockRecord {
                name: b.name.clone(),
                kind: b.kind.into(),
                cell: cell_of(b.inventory),
                inventory: m.inventories[b.inventory].name.clone(),
                order: b.order.map(|o| m.orders[o].name.clone()),
                configurations: b.configurations,
                kept_combinations: b.kept.iter().map(|c| names(m, b.inventory, c)).collect(),
                held_out_combinations: b
                    .held_out
                    .iter()
                    .map(|c| names(m, b.inventory, c))
                    .collect(),
                first_demonstration: b.first_demo,
                demonstrations: b.demos,
                samples: g.per_demo[range].iter().map(|(_, n)| n).sum(),
            }
        })
        .collect();
    let demonstrations = ex
        .demonstrations
        .iter()
        .zip(&g.per_demo)
        .map(|(d, &(first, n))| {
            let s = &d.setup;
            DemonstrationRecord {
                block: ex.blocks[d.block].name.clone(),
                cell: cell_of(s.inventory),
                inventory: m.inventories[s.inventory].name.clone(),
                assignment: assignments(m, s),
                sequence: names(m, s.inventory, &d.sequence),
                human_packed: names(m, s.inventory, &s.human_packed),
                missing: names(m, s.inventory, &s.missing),
                start: start(m, s),
                first_sample: first,
                samples: n,
            }
        })
        .collect();
    Manifest {
        schema: schema::MANIFEST.into(),
        version: SCHEMA_VERSION,
        sources: sources
            .files()
            .map(|(_, f)| SourceDigest {
                path: f.path.display().to_string(),
                sha256: format!("{:x}", Sha256::digest(f.text.as_bytes())),
            })
            .collect(),
        counts: Counts {
            cells: m.cells.len(),
            products: m.products.len(),
            inventories: m.inventories.len(),
            orders: m.orders.len(),
            demo_blocks: ex.blocks.len(),
            demonstrations: ex.demonstrations.len(),
            samples: g.s,
            suites: ex.suites.len(),
            scenarios: ex.suites.iter().map(|s| s.cases.len()).sum(),
        },
        tensors: TensorShapes {
            samples: g.s,
            nodes: g.m,
            edges: g.edges(),
        },
        demo_blocks,
        demonstrations,
    }
}

fn labels(m: &Model) -> LabelsFile {
    LabelsFile {
        schema: schema::LABELS.into(),
        version: SCHEMA_VERSION,
        cells: m
            .cells
            .iter()
            .map(|c| CellLabels {
                cell: c.name.clone(),
                labels: std::iter::once(Label {
                    label: 0,
                    name: "pick".into(),
                    box_name: None,
                    position: None,
                })
                .chain(c.slots.iter().enumerate().map(|(i, s)| Label {
                    label: i as u32 + 1,
                    name: s.name.clone(),
                    box_name: Some(c.boxes[s.box_index].name.clone()),
                    position: Some(r6n(s.at)),
                }))
                .collect(),
            })
            .collect(),
    }
}

/// A cell as `orders.json` records it (lengths rounded to micrometres).
pub fn cell_record(c: &Cell) -> CellRecord {
    CellRecord {
        name: c.name.clone(),
        robot: match &c.robot {
            RobotModel::Ur10 => RobotRecord::Ur10,
            RobotModel::Urdf(p) => RobotRecord::Urdf(p.clone()),
        },
        base: r6n(c.base),
        suction: r6(c.suction),
        lift: r6(c.lift),
        speed: r6(c.speed),
        pending: RectRecord {
            min: r6n(c.pending.min),
            max: r6n(c.pending.max),
        },
        boxes: c
            .boxes
            .iter()
            .map(|b| BoxRecord {
                name: b.name.clone(),
                centre: r6n(b.centre),
                size: r6n(b.size),
            })
            .collect(),
        slots: c
            .slots
            .iter()
            .enumerate()
            .map(|(i, s)| SlotRecord {
                name: s.name.clone(),
                label: i as u32 + 1,
                box_name: c.boxes[s.box_index].name.clone(),
                position: r6n(s.at),
            })
            .collect(),
    }
}

fn world(m: &Model) -> WorldFile {
    WorldFile {
        schema: schema::ORDERS.into(),
        version: SCHEMA_VERSION,
        cells: m.cells.iter().map(cell_record).collect(),
        products: m
            .products
            .iter()
            .map(|p| ProductRecord {
                name: p.name.clone(),
                size: r6n(p.size),
                mass: p.mass.map(r6),
            })
            .collect(),
        inventories: m
            .inventories
            .iter()
            .map(|inv| InventoryRecord {
                name: inv.name.clone(),
                cell: m.cells[inv.cell].name.clone(),
                products: inv
                    .entries
                    .iter()
                    .map(|e| At {
                        product: m.products[e.product].name.clone(),
                        at: r6n([e.at[0], e.at[1], m.products[e.product].size[2] / 2.0]),
                    })
                    .collect(),
            })
            .collect(),
        orders: m
            .orders
            .iter()
            .map(|o| {
                let inv = &m.inventories[o.inventory];
                let setup = Setup {
                    inventory: o.inventory,
                    assignment: o.assignment.iter().map(|a| (a.entry, a.slot)).collect(),
                    human_packed: Vec::new(),
                    missing: Vec::new(),
                    positions: inv.entries.iter().map(|e| e.at).collect(),
                };
                OrderRecord {
                    name: o.name.clone(),
                    inventory: inv.name.clone(),
                    cell: m.cells[inv.cell].name.clone(),
                    customer: o.customer.clone(),
                    batch: o.batch,
                    assignment: assignments(m, &setup),
                }
            })
            .collect(),
    }
}

fn scenarios(m: &Model, ex: &Expanded) -> ScenariosFile {
    ScenariosFile {
        schema: schema::SCENARIOS.into(),
        version: SCHEMA_VERSION,
        suites: ex
            .suites
            .iter()
            .map(|s| SuiteRecord {
                name: s.name.clone(),
                kind: s.kind.into(),
                cell: m.cells[m.inventories[s.inventory].cell].name.clone(),
                inventory: m.inventories[s.inventory].name.clone(),
                order: s.order.map(|o| m.orders[o].name.clone()),
                seed: s.seed,
                cases: s
                    .cases
                    .iter()
                    .map(|c| CaseRecord {
                        name: c.name.clone(),
                        assignment: assignments(m, &c.setup),
                        human_packed: names(m, s.inventory, &c.setup.human_packed),
                        missing: names(m, s.inventory, &c.setup.missing),
                        start: start(m, &c.setup),
                    })
                    .collect(),
            })
            .collect(),
    }
}

fn le_bytes<T: Copy, const N: usize>(values: &[T], to: impl Fn(T) -> [u8; N]) -> Vec<u8> {
    values.iter().flat_map(|&v| to(v)).collect()
}

/// `graphs.safetensors`; tensor names, dtypes and shapes are documented in
/// the README.
fn tensors(g: &Graphs) -> Result<Vec<u8>, Error> {
    use crate::artifact::tensor;
    let (s, m, e) = (g.s, g.m, g.edges());
    let data: Vec<(&str, Dtype, Vec<usize>, Vec<u8>)> = vec![
        (
            tensor::NODES,
            Dtype::F32,
            vec![s, m, 4],
            le_bytes(&g.nodes, f32::to_le_bytes),
        ),
        (
            tensor::NODE_MASK,
            Dtype::U8,
            vec![s, m],
            g.node_mask.clone(),
        ),
        (
            tensor::GOAL,
            Dtype::F32,
            vec![s, 3],
            le_bytes(&g.goal, f32::to_le_bytes),
        ),
        (
            tensor::TARGET,
            Dtype::I64,
            vec![s],
            le_bytes(&g.target, i64::to_le_bytes),
        ),
        (
            tensor::LABEL,
            Dtype::I64,
            vec![s],
            le_bytes(&g.label, i64::to_le_bytes),
        ),
        (tensor::STAGE, Dtype::U8, vec![s], g.stage.clone()),
        (
            tensor::DEMO,
            Dtype::I64,
            vec![s],
            le_bytes(&g.demo, i64::to_le_bytes),
        ),
        (
            tensor::EDGE_INDEX,
            Dtype::I64,
            vec![2, e],
            le_bytes(&g.edge_index, i64::to_le_bytes),
        ),
    ];
    let internal = |e: safetensors::SafeTensorError| Error::Internal {
        what: e.to_string(),
    };
    let views = data
        .iter()
        .map(|(name, dtype, shape, bytes)| {
            TensorView::new(*dtype, shape.clone(), bytes).map(|v| (*name, v))
        })
        .collect::<Result<Vec<_>, _>>()
        .map_err(internal)?;
    let metadata = HashMap::from([("schema".to_owned(), schema::GRAPHS.to_owned())]);
    safetensors::serialize(views, Some(metadata)).map_err(internal)
}
