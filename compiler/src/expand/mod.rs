//! Phase 4: expand `demo`/`demos` blocks into demonstrations and
//! `scenario`/`scenarios` blocks into test cases, deterministically.
//!
//! Every generated block draws from its own ChaCha8 generator seeded with
//! the block's `seed` (`rand_chacha::ChaCha8Rng::seed_from_u64`), in this
//! documented order, so the same file gives the same bytes everywhere:
//! - `demos`: (1) if `keep` < 1, one shuffle of the combination list; then
//!   for each kept configuration and each repeat: (2) human-packed and
//!   missing products, (3) jitter, (4) a random sequence.
//! - `scenarios`, per case: (1) the N-combination, (2) its slots, (3)
//!   human-packed and (4) missing products, (5) jitter.
//! - `scenario`: (1) jitter.
//!
//! Demonstrations are not held in memory: [`expand`] generates each
//! block's once to check it (jitter that cannot place a product) and to
//! count it, and [`Expanded::demonstrations`] generates them again, in
//! the same order and with the same draws, for whoever writes them out
//! (`demonstrations`). Scenario cases are kept: a run needs them by name.

mod demonstrations;

pub use demonstrations::Demonstrations;
use demonstrations::{BlockSource, Kept};

use crate::error::Error;
use crate::model::*;
use crate::source::Loc;
use rand::seq::index;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A block may generate at most this many demonstrations or cases.
pub const MAX_GENERATED: u64 = 1_000_000;
/// The files of one compilation together may generate at most this many
/// demonstrations and cases (the cases are held in memory, the
/// demonstrations streamed: see README, "Reliability").
pub const MAX_GENERATED_TOTAL: u64 = 1_000_000;
/// Redraws of one product's jitter before giving up.
pub const JITTER_TRIES: u32 = 100;

/// The state of one package before the robot starts.
#[derive(Debug, Clone, PartialEq)]
pub struct Setup {
    pub inventory: usize,
    /// (inventory entry, cell slot) for every selected product, in
    /// inventory order.
    pub assignment: Vec<(usize, usize)>,
    /// Entries already in their slots (a worker packed them).
    pub human_packed: Vec<usize>,
    /// Entries absent from the cell.
    pub missing: Vec<usize>,
    /// Per inventory entry, where it stands in the pending area.
    pub positions: Vec<[f64; 2]>,
}

impl Setup {
    pub fn slot_of(&self, entry: usize) -> Option<usize> {
        self.assignment
            .iter()
            .find(|(e, _)| *e == entry)
            .map(|(_, s)| *s)
    }
}

#[derive(Debug, Clone)]
pub struct Demonstration {
    /// Index into [`Expanded::blocks`].
    pub block: usize,
    pub setup: Setup,
    /// Entries the demonstrator handled, in order.
    pub sequence: Vec<usize>,
}

#[derive(Debug, Clone)]
pub struct DemoBlock {
    /// Where its demonstrations come from.
    source: BlockSource,
    pub name: String,
    /// `demo` or `demos`.
    pub kind: &'static str,
    pub inventory: usize,
    pub order: Option<usize>,
    /// Goal configurations the block spans (before `keep`).
    pub configurations: u64,
    /// Kept and held-out combinations (inventory entries), for `demos`.
    pub kept: Vec<Vec<usize>>,
    pub held_out: Vec<Vec<usize>>,
    pub first_demo: usize,
    pub demos: usize,
    /// Products handled, summed over its demonstrations (each is two
    /// graph samples).
    pub handled: usize,
    /// The most products present in one of its demonstrations.
    pub most_present: usize,
    /// A `demos` block with `sequence random`: its demonstrations show
    /// that any order is right, not an order to learn.
    pub any_order: bool,
    /// A `demos` block with `sequence listed`: its `choose` list
    /// (inventory entries), the priority its demonstrations follow, which
    /// also orders the products no demonstration shows together; empty
    /// for every other block.
    pub priority: Vec<usize>,
    /// A `demos` block with `sequence descending`: the direction it
    /// declares, which its demonstrations of one product each cannot show.
    pub descending: bool,
}

#[derive(Debug, Clone)]
pub struct Case {
    pub name: String,
    pub setup: Setup,
}

#[derive(Debug, Clone)]
pub struct Suite {
    pub name: String,
    /// `scenario` or `scenarios`.
    pub kind: &'static str,
    pub inventory: usize,
    pub order: Option<usize>,
    pub seed: u64,
    pub cases: Vec<Case>,
}

#[derive(Debug, Clone, Default)]
pub struct Expanded {
    pub blocks: Vec<DemoBlock>,
    pub suites: Vec<Suite>,
}

impl Expanded {
    /// How many demonstrations the blocks generate.
    pub fn demonstration_count(&self) -> usize {
        self.blocks.iter().map(|b| b.demos).sum()
    }

    /// Every demonstration, block after block, generated as [`expand`]
    /// generated them (same order, same draws). `m` must be the model
    /// this was expanded from.
    pub fn demonstrations<'a>(&'a self, m: &'a Model) -> Demonstrations<'a> {
        Demonstrations::new(m, &self.blocks)
    }
}

pub fn expand(m: &Model) -> Result<Expanded, Vec<Error>> {
    let mut out = Expanded::default();
    let mut errors = Vec::new();
    for (i, d) in m.demos.iter().enumerate() {
        let order = &m.orders[d.order];
        out.blocks.push(DemoBlock {
            source: BlockSource::Observed(i),
            name: d.name.clone(),
            kind: "demo",
            inventory: order.inventory,
            order: Some(d.order),
            configurations: 1,
            kept: Vec::new(),
            held_out: Vec::new(),
            first_demo: out.blocks.len(),
            demos: 1,
            handled: d.sequence.len(),
            most_present: m.inventories[order.inventory].entries.len(),
            any_order: false,
            descending: false,
            priority: Vec::new(),
        });
    }
    // Every block's size is counted before anything is generated: one
    // too large, or one that takes the files over the total, is refused
    // at the statement that sets its size, and nothing is generated.
    let mut generated = out.blocks.len() as u64;
    let sizes = m
        .demo_sets
        .iter()
        .map(|d| demos_count(d).map(|n| (n, d.choose.loc)))
        .chain(
            m.scenario_sets
                .iter()
                .map(|s| scenarios_count(s).map(|n| (n, s.count_loc))),
        );
    for size in sizes {
        match size {
            Ok((count, at)) => {
                let before = generated;
                generated = generated.saturating_add(count);
                if before <= MAX_GENERATED_TOTAL && generated > MAX_GENERATED_TOTAL {
                    errors.push(Error::TooManyInTotal {
                        at,
                        count: generated,
                        limit: MAX_GENERATED_TOTAL,
                    });
                }
            }
            Err(e) => errors.push(e),
        }
    }
    if !errors.is_empty() {
        return Err(errors);
    }
    for (i, d) in m.demo_sets.iter().enumerate() {
        match demo_set(m, i, d, out.demonstration_count()) {
            Ok(block) => out.blocks.push(block),
            Err(e) => errors.push(e),
        }
    }
    for s in &m.scenarios {
        match scenario(m, s) {
            Ok(suite) => out.suites.push(suite),
            Err(e) => errors.push(e),
        }
    }
    for s in &m.scenario_sets {
        match scenario_set(m, s) {
            Ok(suite) => out.suites.push(suite),
            Err(e) => errors.push(e),
        }
    }
    if errors.is_empty() {
        Ok(out)
    } else {
        Err(errors)
    }
}

/// All k-combinations of 0..n in lexicographic order.
pub fn combinations(n: usize, k: usize) -> Vec<Vec<usize>> {
    let mut out = Vec::new();
    if k > n {
        return out;
    }
    let mut c: Vec<usize> = (0..k).collect();
    loop {
        out.push(c.clone());
        let Some(i) = (0..k).rev().find(|&i| c[i] < n - k + i) else {
            return out;
        };
        c[i] += 1;
        for j in i + 1..k {
            c[j] = c[j - 1] + 1;
        }
    }
}

/// All ordered k-tuples of distinct elements of 0..n, in lexicographic order.
pub fn arrangements(n: usize, k: usize) -> Vec<Vec<usize>> {
    fn go(n: usize, k: usize, cur: &mut Vec<usize>, out: &mut Vec<Vec<usize>>) {
        if cur.len() == k {
            out.push(cur.clone());
            return;
        }
        for i in 0..n {
            if !cur.contains(&i) {
                cur.push(i);
                go(n, k, cur, out);
                cur.pop();
            }
        }
    }
    let mut out = Vec::new();
    if k <= n {
        go(n, k, &mut Vec::with_capacity(k), &mut out);
    }
    out
}

/// C(products, n): the product combinations (saturating).
fn combination_count(products: usize, n: usize) -> u128 {
    let mut c: u128 = 1;
    for i in 0..n as u128 {
        c = c.saturating_mul(products as u128 - i) / (i + 1);
    }
    c
}

/// slots!/(slots-n)!: the ways to put n products into the slots
/// (saturating).
fn arrangement_count(slots: usize, n: usize) -> u128 {
    (0..n as u128).fold(1u128, |p, i| p.saturating_mul(slots as u128 - i))
}

/// C(products, n) x slots!/(slots-n)!: every goal configuration
/// (saturating).
fn count_configurations(products: usize, slots: usize, n: usize) -> u128 {
    combination_count(products, n).saturating_mul(arrangement_count(slots, n))
}

/// How many demonstrations a block generates once `keep` has chosen its
/// combinations, counted before anything is generated; an error at the
/// statement that made the count too large: `repeat` when it alone tips
/// the count over the limit, else `choose`. The combinations are listed
/// to choose from, so their number is bounded too.
fn kept_count(d: &DemosDef) -> Result<(usize, usize), Error> {
    let c = &d.choose;
    let too_many = |at: Loc, count: u128| Error::TooManyConfigurations {
        at,
        count: count.to_string(),
        limit: MAX_GENERATED,
    };
    let n_combos = combination_count(c.entries.len(), c.n);
    if n_combos > MAX_GENERATED as u128 {
        let all = count_configurations(c.entries.len(), c.slots.len(), c.n);
        return Err(too_many(c.loc, all.saturating_mul(d.repeat as u128)));
    }
    let n_combos = n_combos as usize;
    let keep = ((d.keep * n_combos as f64).round() as usize).min(n_combos);
    let per_combo = arrangement_count(c.slots.len(), c.n);
    let once = (keep as u128).saturating_mul(per_combo);
    let total = once.saturating_mul(d.repeat as u128);
    if total > MAX_GENERATED as u128 {
        let at = match d.repeat_loc {
            Some(at) if once <= MAX_GENERATED as u128 => at,
            _ => c.loc,
        };
        return Err(too_many(at, total));
    }
    Ok((n_combos, keep))
}

/// How many demonstrations a `demos` block generates (after `keep`, times
/// `repeat`), or why it may not.
fn demos_count(d: &DemosDef) -> Result<u64, Error> {
    let c = &d.choose;
    let (_, keep) = kept_count(d)?;
    let per_combo = arrangement_count(c.slots.len(), c.n);
    // kept_count bounds it by MAX_GENERATED.
    Ok(((keep as u128) * per_combo * d.repeat as u128) as u64)
}

/// The `demos` block `index` of the model, its demonstrations generated
/// once to check and count them (numbered from `first_demo`).
fn demo_set(m: &Model, index: usize, d: &DemosDef, first_demo: usize) -> Result<DemoBlock, Error> {
    let c = &d.choose;
    let total = count_configurations(c.entries.len(), c.slots.len(), c.n);
    let kept = Kept::choose(d)?;
    let mut block = DemoBlock {
        source: BlockSource::Generated(index),
        name: d.name.clone(),
        kind: "demos",
        inventory: d.inventory,
        order: None,
        configurations: u64::try_from(total).unwrap_or(u64::MAX),
        kept: kept.kept_entries(d),
        held_out: kept.held_out_entries(d),
        first_demo,
        demos: 0,
        handled: 0,
        most_present: 0,
        any_order: d.sequence == packwright_grammar::ast::SequenceMode::Random,
        descending: d.sequence == packwright_grammar::ast::SequenceMode::Descending,
        priority: if d.sequence == packwright_grammar::ast::SequenceMode::Listed {
            c.entries.clone()
        } else {
            Vec::new()
        },
    };
    let entries = m.inventories[d.inventory].entries.len();
    for demo in demonstrations::generated(m, d, kept) {
        let demo = demo?;
        block.demos += 1;
        block.handled += demo.sequence.len();
        block.most_present = block.most_present.max(entries - demo.setup.missing.len());
    }
    Ok(block)
}

/// Draws which selected entries a worker packed and which are missing.
fn draw_absent(
    rng: &mut ChaCha8Rng,
    selected: &[usize],
    human: CountRange,
    missing: CountRange,
) -> (Vec<usize>, Vec<usize>) {
    let mut packed = Vec::new();
    if human.loc.is_some() {
        let k = rng.random_range(human.low..=human.high).min(selected.len());
        packed = index::sample(rng, selected.len(), k)
            .into_iter()
            .map(|i| selected[i])
            .collect();
        packed.sort_unstable();
    }
    let mut absent = Vec::new();
    if missing.loc.is_some() {
        let rest: Vec<usize> = selected
            .iter()
            .copied()
            .filter(|e| !packed.contains(e))
            .collect();
        let k = rng.random_range(missing.low..=missing.high).min(rest.len());
        absent = index::sample(rng, rest.len(), k)
            .into_iter()
            .map(|i| rest[i])
            .collect();
        absent.sort_unstable();
    }
    (packed, absent)
}

/// Jittered positions of the products standing in the pending area (not
/// packed, not missing), in inventory order: x and y each offset uniformly
/// in [-j, j], redrawn while the footprint leaves the pending area or
/// overlaps a product placed before it. Returns the entry that could not be
/// placed.
fn jitter(
    m: &Model,
    inv: &Inventory,
    packed: &[usize],
    missing: &[usize],
    j: f64,
    rng: &mut ChaCha8Rng,
) -> Result<Vec<[f64; 2]>, usize> {
    jitter_from(
        m,
        inv,
        inv.entries.iter().map(|e| e.at).collect(),
        packed,
        missing,
        j,
        rng,
    )
}

fn jitter_from(
    m: &Model,
    inv: &Inventory,
    mut positions: Vec<[f64; 2]>,
    packed: &[usize],
    missing: &[usize],
    j: f64,
    rng: &mut ChaCha8Rng,
) -> Result<Vec<[f64; 2]>, usize> {
    if j <= 0.0 {
        return Ok(positions);
    }
    let pending = m.cells[inv.cell].pending;
    let mut placed: Vec<usize> = Vec::new();
    for (i, e) in inv.entries.iter().enumerate() {
        if packed.contains(&i) || missing.contains(&i) {
            continue;
        }
        let product = &m.products[e.product];
        let nominal = positions[i];
        let mut ok = false;
        for _ in 0..JITTER_TRIES {
            let p = [
                nominal[0] + rng.random_range(-j..=j),
                nominal[1] + rng.random_range(-j..=j),
            ];
            let fp = product.footprint(p);
            if pending.excess(&fp) > 0.0 {
                continue;
            }
            if placed
                .iter()
                .any(|&o| fp.overlaps(&m.products[inv.entries[o].product].footprint(positions[o])))
            {
                continue;
            }
            positions[i] = p;
            ok = true;
            break;
        }
        if !ok {
            return Err(i);
        }
        placed.push(i);
    }
    Ok(positions)
}

fn jitter_error(m: &Model, inv: &Inventory, entry: usize, at: Loc) -> Error {
    Error::JitterImpossible {
        at,
        product: m.products[inv.entries[entry].product].name.clone(),
        tries: JITTER_TRIES,
    }
}

fn scenario(m: &Model, s: &ScenarioDef) -> Result<Suite, Error> {
    let order = &m.orders[s.order];
    let inv = &m.inventories[order.inventory];
    let mut positions: Vec<[f64; 2]> = inv.entries.iter().map(|e| e.at).collect();
    for p in &s.at {
        positions[p.entry] = p.at;
    }
    let mut rng = ChaCha8Rng::seed_from_u64(s.seed);
    let mut packed = s.human_packed.clone();
    let mut missing = s.missing.clone();
    packed.sort_unstable();
    missing.sort_unstable();
    let positions = jitter_from(m, inv, positions, &packed, &missing, s.jitter, &mut rng)
        .map_err(|e| jitter_error(m, inv, e, s.jitter_loc.unwrap_or(s.loc)))?;
    Ok(Suite {
        name: s.name.clone(),
        kind: "scenario",
        inventory: order.inventory,
        order: Some(s.order),
        seed: s.seed,
        cases: vec![Case {
            name: s.name.clone(),
            setup: Setup {
                inventory: order.inventory,
                assignment: order.assignment.iter().map(|a| (a.entry, a.slot)).collect(),
                human_packed: packed,
                missing,
                positions,
            },
        }],
    })
}

/// How many cases a `scenarios` block generates, or why it may not.
fn scenarios_count(s: &ScenariosDef) -> Result<u64, Error> {
    if s.count as u64 > MAX_GENERATED {
        return Err(Error::TooManyConfigurations {
            at: s.count_loc,
            count: s.count.to_string(),
            limit: MAX_GENERATED,
        });
    }
    Ok(s.count as u64)
}

/// A `scenarios` block's cases (its size was checked by
/// [`scenarios_count`] before anything was generated).
fn scenario_set(m: &Model, s: &ScenariosDef) -> Result<Suite, Error> {
    let c = &s.choose;
    let inv = &m.inventories[s.inventory];
    let mut rng = ChaCha8Rng::seed_from_u64(s.seed);
    let width = s.count.to_string().len();
    let mut cases = Vec::with_capacity(s.count);
    for i in 0..s.count {
        let mut chosen = index::sample(&mut rng, c.entries.len(), c.n).into_vec();
        chosen.sort_unstable();
        let slots = index::sample(&mut rng, c.slots.len(), c.n).into_vec();
        let mut assignment: Vec<(usize, usize)> = chosen
            .iter()
            .zip(&slots)
            .map(|(&p, &sl)| (c.entries[p], c.slots[sl]))
            .collect();
        assignment.sort_unstable();
        let selected: Vec<usize> = assignment.iter().map(|(e, _)| *e).collect();
        let (human_packed, missing) = draw_absent(&mut rng, &selected, s.human, s.missing);
        let positions = jitter(m, inv, &human_packed, &missing, s.jitter, &mut rng)
            .map_err(|e| jitter_error(m, inv, e, s.jitter_loc.unwrap_or(s.loc)))?;
        cases.push(Case {
            name: format!("{}/{:0width$}", s.name, i + 1),
            setup: Setup {
                inventory: s.inventory,
                assignment,
                human_packed,
                missing,
                positions,
            },
        });
    }
    Ok(Suite {
        name: s.name.clone(),
        kind: "scenarios",
        inventory: s.inventory,
        order: None,
        seed: s.seed,
        cases,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::source::FileId;
    use packwright_grammar::Span;
    use packwright_grammar::ast::SequenceMode;

    #[test]
    fn combinatorics() {
        assert_eq!(combinations(5, 3).len(), 10);
        assert_eq!(combinations(3, 2), vec![vec![0, 1], vec![0, 2], vec![1, 2]]);
        assert_eq!(arrangements(3, 3).len(), 6);
        assert_eq!(arrangements(3, 2).len(), 6);
        assert_eq!(
            arrangements(4, 2)[0..3],
            [vec![0, 1], vec![0, 2], vec![0, 3]]
        );
        assert_eq!(count_configurations(5, 3, 3), 60);
        assert_eq!(count_configurations(5, 4, 4), 120);
        assert_eq!(count_configurations(3, 3, 2), 18);
        assert!(combinations(2, 3).is_empty());
    }

    /// A block of `choose n of products into slots`, with `keep` and
    /// `repeat`; its statements at distinct places.
    fn block(n: usize, products: usize, slots: usize, keep: f64, repeat: usize) -> DemosDef {
        let at = |start: usize| Loc::new(FileId(0), Span::new(start, start + 1));
        DemosDef {
            name: "d".into(),
            loc: at(0),
            inventory: 0,
            choose: Choose {
                n,
                entries: (0..products).collect(),
                slots: (0..slots).collect(),
                loc: at(10),
            },
            keep,
            jitter: 0.0,
            jitter_loc: None,
            sequence: SequenceMode::Ascending,
            repeat,
            repeat_loc: (repeat > 1).then(|| at(20)),
            seed: 0,
            human: CountRange {
                low: 0,
                high: 0,
                loc: None,
            },
            missing: CountRange {
                low: 0,
                high: 0,
                loc: None,
            },
        }
    }

    /// The limit counts what `keep` leaves; the caret goes to `repeat`
    /// when it alone tips the count over, else to `choose`; a number of
    /// combinations too large to list is refused before listing them.
    #[test]
    fn the_limit_counts_what_keep_leaves_and_blames_the_right_statement() {
        let at = |e: Error| e.at().map(|l| l.span.start);
        // 4 of 24 into 5 slots: 10,626 combinations x 120 = 1,275,120.
        assert_eq!(
            at(kept_count(&block(4, 24, 5, 1.0, 1)).unwrap_err()),
            Some(10)
        );
        assert_eq!(
            kept_count(&block(4, 24, 5, 0.5, 1)).ok(),
            Some((10_626, 5_313))
        );
        // 3 of 5 into 5 slots: 600 configurations, 2,000 times each.
        assert_eq!(
            at(kept_count(&block(3, 5, 5, 1.0, 2_000)).unwrap_err()),
            Some(20)
        );
        assert!(kept_count(&block(3, 5, 5, 1.0, 1_000)).is_ok());
        // 10 of 60: 75 billion combinations, never listed.
        assert_eq!(
            at(kept_count(&block(10, 60, 10, 0.000_001, 1)).unwrap_err()),
            Some(10)
        );
    }
}
