//! The manifest's, the demonstrations', the combinations' and the
//! scenarios' records against `orders.json`: the counts, the blocks'
//! ranges, the demonstrations' products and samples, the suites' cases.

use super::check::Check;
use super::world::{World, assignment, start};
use crate::artifacts::field::Field;
use crate::error::{ArtifactProblem as P, Result};
use packwright_compiler::artifact::*;

/// The manifest (`c`) and `demonstrations.jsonl` (`cd`, `demonstrations`)
/// together.
pub(super) fn manifest(
    c: &Check,
    cd: &Check,
    m: &Manifest,
    demonstrations: &[DemonstrationRecord],
    world: &World,
    scenarios: &ScenariosFile,
) -> Result<()> {
    let root = Field::ROOT;
    let counts = root.key("counts");
    let w = world.file;
    let cases: usize = scenarios.suites.iter().map(|s| s.cases.len()).sum();
    for (key, found, expected) in [
        ("cells", m.counts.cells, w.cells.len()),
        ("products", m.counts.products, w.products.len()),
        ("inventories", m.counts.inventories, w.inventories.len()),
        ("orders", m.counts.orders, w.orders.len()),
        ("demo_blocks", m.counts.demo_blocks, m.demo_blocks.len()),
        (
            "demonstrations",
            m.counts.demonstrations,
            demonstrations.len(),
        ),
        ("suites", m.counts.suites, scenarios.suites.len()),
        ("scenarios", m.counts.scenarios, cases),
    ] {
        c.count(&counts.key(key), found, expected)?;
    }

    let sources = root.key("sources");
    for (i, source) in m.sources.iter().enumerate() {
        let digest = &source.sha256;
        if digest.len() != 64 || !digest.bytes().all(|b| b.is_ascii_hexdigit()) {
            return Err(c.differs(
                &sources.index(i).key("sha256"),
                format!("{digest:?}"),
                "a SHA-256 digest, 64 hexadecimal digits",
            ));
        }
    }

    let blocks = root.key("demo_blocks");
    let demos = Field::ROOT;
    for (d, demo) in demonstrations.iter().enumerate() {
        demonstration(cd, &demos.index(d), demo, world)?;
    }
    c.unique(
        &blocks,
        "name",
        "demonstration block",
        m.demo_blocks.iter().map(|b| b.name.as_str()),
    )?;
    let mut next = 0;
    for (b, block) in m.demo_blocks.iter().enumerate() {
        let at = blocks.index(b);
        if !matches!(block.kind.as_str(), "demo" | "demos") {
            return Err(c.unknown(
                &at.key("kind"),
                "kind of block (`demo`, `demos`)",
                &block.kind,
            ));
        }
        world.setting(c, &at, &block.cell, &block.inventory)?;
        world.order(
            c,
            &at.key("order"),
            block.order.as_deref(),
            &block.inventory,
        )?;
        if block.first_demonstration != next {
            return Err(c.differs(
                &at.key("first_demonstration"),
                block.first_demonstration,
                format!("{next} (the demonstrations follow the blocks' order)"),
            ));
        }
        let left = demonstrations.len().saturating_sub(next);
        if block.demonstrations > left {
            return Err(c.fail(
                &at.key("demonstrations"),
                P::CountMismatch {
                    expected: left,
                    found: block.demonstrations,
                },
            ));
        }
        let range = next..next + block.demonstrations;
        let whose = format!("demonstrations {range:?} are block {b}'s");
        let mut samples = 0usize;
        for (d, demo) in demonstrations[range.clone()].iter().enumerate() {
            let at = demos.index(next + d);
            cd.same_name(&at.key("block"), &demo.block, &block.name, &whose)?;
            cd.same_name(&at.key("cell"), &demo.cell, &block.cell, "its block's cell")?;
            cd.same_name(
                &at.key("inventory"),
                &demo.inventory,
                &block.inventory,
                "its block's inventory",
            )?;
            samples = samples.saturating_add(demo.samples);
        }
        c.count(&at.key("samples"), block.samples, samples)?;
        next = range.end;
    }
    if let Some(demo) = demonstrations.get(next) {
        return Err(cd.differs(
            &demos.index(next).key("block"),
            format!("`{}`", demo.block),
            "a block whose range of demonstrations holds this one",
        ));
    }

    let mut first = 0;
    for (d, demo) in demonstrations.iter().enumerate() {
        let at = demos.index(d);
        if demo.first_sample != first {
            return Err(cd.differs(
                &at.key("first_sample"),
                demo.first_sample,
                format!("{first} (the samples of the demonstrations before)"),
            ));
        }
        cd.count(&at.key("samples"), demo.samples, 2 * demo.sequence.len())?;
        first += demo.samples;
    }
    c.count(&counts.key("samples"), m.counts.samples, first)?;
    let tensors = root.key("tensors");
    c.count(&tensors.key("samples"), m.tensors.samples, first)?;
    let width = demonstrations
        .iter()
        .map(|d| d.start.len())
        .max()
        .unwrap_or(0);
    c.count(&tensors.key("nodes"), m.tensors.nodes, width)?;
    c.count(
        &tensors.key("edges"),
        m.tensors.edges,
        2 * width.saturating_sub(1),
    )
}

/// `combinations.jsonl` (`c`): each line's block is a `demos` block of
/// the manifest and its products are the block inventory's; each block's
/// kept combinations come first, then its held-out ones, as many as the
/// manifest counts.
pub(super) fn combinations(
    c: &Check,
    m: &Manifest,
    list: &[CombinationRecord],
    world: &World,
) -> Result<()> {
    let mut next = 0;
    for block in &m.demo_blocks {
        let (_, inv) = world.setting(c, &Field::ROOT, &block.cell, &block.inventory)?;
        let products: Vec<&str> = inv.products.iter().map(|p| p.product.as_str()).collect();
        for (kept, count) in [
            (true, block.kept_combinations),
            (false, block.held_out_combinations),
        ] {
            for k in next..next + count {
                let at = Field::ROOT.index(k);
                let Some(record) = list.get(k) else {
                    return Err(c.fail(
                        &at,
                        P::CountMismatch {
                            expected: next + count,
                            found: list.len(),
                        },
                    ));
                };
                let whose = format!("the manifest's block `{}`", block.name);
                c.same_name(&at.key("block"), &record.block, &block.name, &whose)?;
                if record.kept != kept {
                    return Err(c.differs(
                        &at.key("kept"),
                        record.kept,
                        format!("{kept} (a block's kept combinations come first)"),
                    ));
                }
                c.names_of(
                    &at.key("products"),
                    &record.products,
                    &products,
                    "product of the inventory",
                    &mut Vec::new(),
                )?;
            }
            next += count;
        }
    }
    if list.len() != next {
        return Err(c.fail(
            &Field::ROOT,
            P::CountMismatch {
                expected: next,
                found: list.len(),
            },
        ));
    }
    Ok(())
}

/// A demonstration: its setting, assignment, and the products it handles
/// (`sequence`), a worker had packed and are missing, which divide the
/// assignment.
fn demonstration(c: &Check, at: &Field, d: &DemonstrationRecord, world: &World) -> Result<()> {
    let (cell, inv) = world.setting(c, at, &d.cell, &d.inventory)?;
    assignment(c, &at.key("assignment"), &d.assignment, cell, inv)?;
    let assigned: Vec<&str> = d.assignment.iter().map(|a| a.product.as_str()).collect();
    let mut seen = Vec::new();
    for (key, names) in [
        ("sequence", &d.sequence),
        ("human_packed", &d.human_packed),
        ("missing", &d.missing),
    ] {
        c.names_of(
            &at.key(key),
            names,
            &assigned,
            "product of the assignment",
            &mut seen,
        )?;
    }
    c.count(
        &at.key("sequence"),
        d.sequence.len(),
        assigned
            .len()
            .saturating_sub(d.human_packed.len() + d.missing.len()),
    )?;
    start(c, &at.key("start"), &d.start, inv, &d.missing)
}

pub(super) fn scenarios(c: &Check, s: &ScenariosFile, world: &World) -> Result<()> {
    let list = Field::ROOT.key("suites");
    c.unique(
        &list,
        "name",
        "suite",
        s.suites.iter().map(|x| x.name.as_str()),
    )?;
    for (i, suite) in s.suites.iter().enumerate() {
        let at = list.index(i);
        if !matches!(suite.kind.as_str(), "scenario" | "scenarios") {
            return Err(c.unknown(
                &at.key("kind"),
                "kind of suite (`scenario`, `scenarios`)",
                &suite.kind,
            ));
        }
        let (cell, inv) = world.setting(c, &at, &suite.cell, &suite.inventory)?;
        world.order(
            c,
            &at.key("order"),
            suite.order.as_deref(),
            &suite.inventory,
        )?;
        let cases = at.key("cases");
        c.unique(
            &cases,
            "name",
            "case of the suite",
            suite.cases.iter().map(|x| x.name.as_str()),
        )?;
        let products: Vec<&str> = inv.products.iter().map(|p| p.product.as_str()).collect();
        for (k, case) in suite.cases.iter().enumerate() {
            let at = cases.index(k);
            assignment(c, &at.key("assignment"), &case.assignment, cell, inv)?;
            let assigned: Vec<&str> = case.assignment.iter().map(|a| a.product.as_str()).collect();
            let mut seen = Vec::new();
            c.names_of(
                &at.key("human_packed"),
                &case.human_packed,
                &assigned,
                "product of the assignment",
                &mut seen,
            )?;
            c.names_of(
                &at.key("missing"),
                &case.missing,
                &products,
                "product of the inventory",
                &mut seen,
            )?;
            start(c, &at.key("start"), &case.start, inv, &case.missing)?;
        }
    }
    Ok(())
}
