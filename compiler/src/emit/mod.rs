//! Phase 6: write everything out as the artifact files. Pure and
//! deterministic: the same model gives the same bytes (floats rounded to
//! micrometres in JSON, tensors in a fixed order); the files are written
//! through an [`Output`] the caller gives.
//!
//! Demonstrations are streamed: generated a chunk at a time
//! ([`CHUNK`]), each chunk written as lines of `demonstrations.jsonl` and
//! as rows of every tensor of `graphs.safetensors` (`tensors`), then
//! dropped, so that memory does not grow with the number of
//! demonstrations. `manifest.json` is written last: a directory with a
//! manifest is complete.

mod tensors;

pub use tensors::serialize as graphs_bytes;

use crate::artifact::*;
use crate::dataset::{Shape, build_chunk, slot_goal};
use crate::error::Error;
use crate::expand::{DemoBlock, Expanded, Setup};
use crate::model::{Cell, Model, RobotModel};
use crate::output::{Output, OutputFile};
use crate::source::SourceMap;
use serde::Serialize;
use sha2::{Digest, Sha256};
use std::io::{BufWriter, Write};
use tensors::TensorsWriter;

pub use crate::output::Artifact;

/// Demonstrations generated, encoded and written at a time.
pub const CHUNK: usize = 1024;

/// The files of a compiled directory.
pub mod file {
    pub const MANIFEST: &str = "manifest.json";
    pub const LABELS: &str = "labels.json";
    pub const ORDERS: &str = "orders.json";
    pub const SCENARIOS: &str = "scenarios.json";
    pub const DEMONSTRATIONS: &str = "demonstrations.jsonl";
    pub const COMBINATIONS: &str = "combinations.jsonl";
    pub const GRAPHS: &str = "graphs.safetensors";
    /// Every file, the manifest first.
    pub const ALL: [&str; 7] = [
        MANIFEST,
        LABELS,
        ORDERS,
        SCENARIOS,
        DEMONSTRATIONS,
        COMBINATIONS,
        GRAPHS,
    ];
}

/// A file written, and its length.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Written {
    pub name: &'static str,
    pub bytes: u64,
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

fn write_error(file: &'static str) -> impl Fn(std::io::Error) -> Error {
    move |e| Error::Write {
        file: file.into(),
        reason: e.to_string(),
    }
}

fn create(out: &dyn Output, name: &'static str) -> Result<Box<dyn OutputFile>, Error> {
    out.create(name).map_err(write_error(name))
}

/// Writes a whole file of `bytes`.
fn whole(out: &dyn Output, name: &'static str, bytes: &[u8]) -> Result<Written, Error> {
    let mut f = create(out, name)?;
    f.write_all(bytes).map_err(write_error(name))?;
    let bytes = f.finish().map_err(write_error(name))?;
    Ok(Written { name, bytes })
}

/// A file of JSON lines, buffered.
struct Lines {
    name: &'static str,
    w: BufWriter<Box<dyn OutputFile>>,
}

impl Lines {
    fn create(out: &dyn Output, name: &'static str) -> Result<Lines, Error> {
        Ok(Lines {
            name,
            w: BufWriter::with_capacity(1 << 20, create(out, name)?),
        })
    }

    fn line<T: Serialize>(&mut self, value: &T) -> Result<(), Error> {
        serde_json::to_writer(&mut self.w, value).map_err(|e| Error::Write {
            file: self.name.into(),
            reason: e.to_string(),
        })?;
        self.w.write_all(b"\n").map_err(write_error(self.name))
    }

    fn finish(self) -> Result<Written, Error> {
        let name = self.name;
        let f = self
            .w
            .into_inner()
            .map_err(|e| write_error(name)(e.into_error()))?;
        let bytes = f.finish().map_err(write_error(name))?;
        Ok(Written { name, bytes })
    }
}

/// Writes every artifact of a clean compilation into `out`, the manifest
/// last; the files written.
pub fn emit(
    sources: &SourceMap,
    m: &Model,
    ex: &Expanded,
    shape: Shape,
    out: &dyn Output,
) -> Result<Vec<Written>, Error> {
    let mut written = vec![
        whole(out, file::LABELS, &json(&labels(m))?)?,
        whole(out, file::ORDERS, &json(&world_file(m))?)?,
        whole(out, file::SCENARIOS, &json(&scenarios(m, ex))?)?,
    ];
    written.extend(demonstrations(m, ex, shape, out)?);
    written.push(combinations(m, ex, out)?);
    written.push(whole(
        out,
        file::MANIFEST,
        &json(&manifest(sources, m, ex, shape))?,
    )?);
    Ok(written)
}

/// Every artifact in memory (for tests and tools).
pub fn emit_to_memory(
    sources: &SourceMap,
    m: &Model,
    ex: &Expanded,
    shape: Shape,
) -> Result<Vec<Artifact>, Error> {
    let out = crate::output::MemoryOutput::new();
    emit(sources, m, ex, shape, &out)?;
    Ok(out.artifacts())
}

/// `demonstrations.jsonl` and `graphs.safetensors`, a chunk at a time.
fn demonstrations(
    m: &Model,
    ex: &Expanded,
    shape: Shape,
    out: &dyn Output,
) -> Result<[Written; 2], Error> {
    let mut lines = Lines::create(out, file::DEMONSTRATIONS)?;
    let mut tensors = TensorsWriter::start(create(out, file::GRAPHS)?, shape)?;
    let mut demos = ex.demonstrations(m);
    let (mut index, mut sample) = (0usize, 0usize);
    loop {
        let chunk = demos.by_ref().take(CHUNK).collect::<Result<Vec<_>, _>>()?;
        if chunk.is_empty() {
            break;
        }
        let g = build_chunk(
            m,
            chunk.iter().enumerate().map(|(i, d)| (index + i, d)),
            shape.width,
            sample,
        );
        for (d, &(first, n)) in chunk.iter().zip(&g.per_demo) {
            lines.line(&demonstration_record(m, &ex.blocks[d.block], d, first, n))?;
        }
        tensors.write(&g)?;
        index += chunk.len();
        sample += g.s;
    }
    if index != ex.demonstration_count() {
        return Err(Error::Internal {
            what: format!(
                "{index} demonstrations generated of {}",
                ex.demonstration_count()
            ),
        });
    }
    Ok([
        lines.finish()?,
        tensors.finish().map(|bytes| Written {
            name: file::GRAPHS,
            bytes,
        })?,
    ])
}

/// The demonstrations of `ex` as `demonstrations.jsonl` records, in
/// memory, without their graph samples (`first_sample` and `samples` are
/// 0): what a tool needs to read the demonstrated sequences without
/// compiling to a directory.
pub fn demonstration_records(m: &Model, ex: &Expanded) -> Result<Vec<DemonstrationRecord>, Error> {
    ex.demonstrations(m)
        .map(|d| d.map(|d| demonstration_record(m, &ex.blocks[d.block], &d, 0, 0)))
        .collect()
}

fn demonstration_record(
    m: &Model,
    block: &DemoBlock,
    d: &crate::expand::Demonstration,
    first_sample: usize,
    samples: usize,
) -> DemonstrationRecord {
    let s = &d.setup;
    DemonstrationRecord {
        block: block.name.clone(),
        cell: m.cells[m.inventories[s.inventory].cell].name.clone(),
        inventory: m.inventories[s.inventory].name.clone(),
        assignment: assignments(m, s),
        sequence: names(m, s.inventory, &d.sequence),
        human_packed: names(m, s.inventory, &s.human_packed),
        missing: names(m, s.inventory, &s.missing),
        start: start(m, s),
        first_sample,
        samples,
    }
}

/// `combinations.jsonl`: every `demos` block's combinations, kept and
/// held out.
fn combinations(m: &Model, ex: &Expanded, out: &dyn Output) -> Result<Written, Error> {
    let mut lines = Lines::create(out, file::COMBINATIONS)?;
    for b in &ex.blocks {
        for (kept, list) in [(true, &b.kept), (false, &b.held_out)] {
            for c in list {
                lines.line(&CombinationRecord {
                    block: b.name.clone(),
                    kept,
                    products: names(m, b.inventory, c),
                })?;
            }
        }
    }
    lines.finish()
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

fn manifest(sources: &SourceMap, m: &Model, ex: &Expanded, shape: Shape) -> Manifest {
    let cell_of = |inv: usize| m.cells[m.inventories[inv].cell].name.clone();
    let demo_blocks = ex
        .blocks
        .iter()
        .map(|b| DemoBlockRecord {
            name: b.name.clone(),
            kind: b.kind.into(),
            cell: cell_of(b.inventory),
            inventory: m.inventories[b.inventory].name.clone(),
            order: b.order.map(|o| m.orders[o].name.clone()),
            configurations: b.configurations,
            kept_combinations: b.kept.len(),
            held_out_combinations: b.held_out.len(),
            first_demonstration: b.first_demo,
            demonstrations: b.demos,
            samples: 2 * b.handled,
            any_order: b.any_order,
            descending: b.descending,
            priority: b
                .priority
                .iter()
                .map(|&e| name_of(m, b.inventory, e))
                .collect(),
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
            demonstrations: ex.demonstration_count(),
            samples: shape.samples,
            suites: ex.suites.len(),
            scenarios: ex.suites.iter().map(|s| s.cases.len()).sum(),
        },
        tensors: TensorShapes {
            samples: shape.samples,
            nodes: shape.width,
            edges: shape.edges(),
        },
        demo_blocks,
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
        grip_settle: r6(c.grip_settle),
        release_settle: r6(c.release_settle),
        descent: r6(c.descent),
        acceleration: c.acceleration.map(|a| a.map(r6)),
        jerk: c.jerk.map(|j| j.map(r6)),
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

/// `orders.json`: the cells, products, inventories and orders.
pub fn world_file(m: &Model) -> WorldFile {
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
