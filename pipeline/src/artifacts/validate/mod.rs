//! The JSON artifacts checked together (the invariants of
//! [`CompiledDir`]); the first problem is the error. `orders.json` is
//! checked first, on its own (`world`): the other files are checked
//! against it (`labels` here, `records` for the manifest's and the
//! scenarios' records).

mod check;
mod records;
mod world;

use super::field::Field;
use super::{CompiledDir, file};
use crate::error::{ArtifactProblem as P, Result};
use check::Check;
use packwright_compiler::artifact::LabelsFile;
use world::World;

pub(super) fn all(c: &CompiledDir) -> Result<()> {
    let world = World::check(&Check::of(c, file::ORDERS), &c.world)?;
    labels(&Check::of(c, file::LABELS), &c.labels, &world)?;
    records::manifest(
        &Check::of(c, file::MANIFEST),
        &Check::of(c, file::DEMONSTRATIONS),
        &c.manifest,
        &c.demonstrations,
        &world,
        &c.scenarios,
    )?;
    records::scenarios(&Check::of(c, file::SCENARIOS), &c.scenarios, &world)
}

/// `combinations.jsonl` against the manifest's blocks and the world.
pub(super) fn combinations(
    c: &CompiledDir,
    list: &[packwright_compiler::artifact::CombinationRecord],
) -> Result<()> {
    let world = World::check(&Check::of(c, file::ORDERS), &c.world)?;
    records::combinations(&Check::of(c, file::COMBINATIONS), &c.manifest, list, &world)
}

/// Two positions written from the same value (the compiler rounds them to
/// micrometres) are equal up to this.
const SAME_POSITION: f64 = 1e-9;

fn labels(c: &Check, l: &LabelsFile, world: &World) -> Result<()> {
    let list = Field::ROOT.key("cells");
    c.count(&list, l.cells.len(), world.file.cells.len())?;
    for (i, (table, cell)) in l.cells.iter().zip(&world.file.cells).enumerate() {
        let at = list.index(i);
        c.same_name(
            &at.key("cell"),
            &table.cell,
            &cell.name,
            &format!("cell {i} of orders.json"),
        )?;
        let entries = at.key("labels");
        for (k, label) in table.labels.iter().enumerate() {
            let at = entries.index(k);
            if u64::from(label.label) != k as u64 {
                return Err(c.differs(
                    &at.key("label"),
                    label.label,
                    format!("{k} (a table is numbered in order: 0 `pick`, then the slots)"),
                ));
            }
            let slot = k.checked_sub(1).and_then(|s| cell.slots.get(s));
            let (name, box_name, position) = match slot {
                None if k == 0 => ("pick", None, None),
                None => {
                    return Err(c.fail(
                        &entries,
                        P::CountMismatch {
                            expected: cell.slots.len() + 1,
                            found: table.labels.len(),
                        },
                    ));
                }
                Some(s) => (s.name.as_str(), Some(s.box_name.as_str()), Some(s.position)),
            };
            let whose = || match k {
                0 => "label 0 is always `pick`".to_owned(),
                _ => format!("slot {} of cell `{}` in orders.json", k - 1, cell.name),
            };
            if label.name != name {
                return Err(c.differs(
                    &at.key("name"),
                    format!("`{}`", label.name),
                    format!("`{name}` ({})", whose()),
                ));
            }
            if label.box_name.as_deref() != box_name {
                return Err(c.differs(
                    &at.key("box"),
                    shown(label.box_name.as_deref()),
                    format!("{} ({})", shown(box_name), whose()),
                ));
            }
            let same = match (label.position, position) {
                (None, None) => true,
                (Some(a), Some(b)) => a
                    .iter()
                    .zip(&b)
                    .all(|(x, y)| (x - y).abs() <= SAME_POSITION),
                _ => false,
            };
            if !same {
                return Err(c.differs(
                    &at.key("position"),
                    position_text(label.position),
                    format!("{} ({})", position_text(position), whose()),
                ));
            }
        }
        c.count(&entries, table.labels.len(), cell.slots.len() + 1)?;
    }
    Ok(())
}

fn shown(name: Option<&str>) -> String {
    name.map_or_else(|| "null".to_owned(), |n| format!("`{n}`"))
}

fn position_text(p: Option<[f64; 2]>) -> String {
    p.map_or_else(|| "null".to_owned(), |p| format!("({}, {})", p[0], p[1]))
}
