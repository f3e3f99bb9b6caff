//! The demonstrations of expanded blocks, generated on demand.
//!
//! Invariants:
//! - one generator per block, seeded as the module documents
//!   ([`super`]): the same model gives the same demonstrations, in the
//!   same order, every time it is iterated, so that what [`super::expand`]
//!   checked and counted is what a writer gets;
//! - nothing is held but the block being generated (its kept
//!   combinations and slot arrangements), so memory does not grow with
//!   the number of demonstrations.

use super::{
    DemoBlock, Demonstration, Setup, arrangements, combinations, draw_absent, jitter, jitter_error,
    kept_count,
};
use crate::error::Error;
use crate::model::{DemosDef, Model};
use packwright_grammar::ast::SequenceMode;
use rand::SeedableRng;
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;

/// Where a block's demonstrations come from: index into the model's
/// `demos` (one observed demonstration) or `demo_sets`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum BlockSource {
    Observed(usize),
    Generated(usize),
}

/// The combinations a `demos` block keeps, and its generator as it stands
/// after choosing them.
pub(super) struct Kept {
    rng: ChaCha8Rng,
    /// Indices into the block's combinations, ascending.
    kept: Vec<usize>,
    held_out: Vec<usize>,
    combinations: Vec<Vec<usize>>,
}

impl Kept {
    /// Draw (1) of the block: which combinations `keep` keeps.
    pub(super) fn choose(d: &DemosDef) -> Result<Kept, Error> {
        let c = &d.choose;
        let (n_combos, keep) = kept_count(d)?;
        if keep == 0 {
            return Err(Error::KeepsNothing {
                at: c.loc,
                fraction: d.keep,
                combinations: n_combos as u64,
            });
        }
        let mut rng = ChaCha8Rng::seed_from_u64(d.seed);
        let combinations = combinations(c.entries.len(), c.n);
        let mut order: Vec<usize> = (0..combinations.len()).collect();
        if keep < combinations.len() {
            order.shuffle(&mut rng);
        }
        let mut kept = order[..keep].to_vec();
        let mut held_out = order[keep..].to_vec();
        kept.sort_unstable();
        held_out.sort_unstable();
        Ok(Kept {
            rng,
            kept,
            held_out,
            combinations,
        })
    }

    fn entries(&self, d: &DemosDef, which: &[usize]) -> Vec<Vec<usize>> {
        which
            .iter()
            .map(|&i| {
                self.combinations[i]
                    .iter()
                    .map(|&j| d.choose.entries[j])
                    .collect()
            })
            .collect()
    }

    /// The kept combinations as inventory entries.
    pub(super) fn kept_entries(&self, d: &DemosDef) -> Vec<Vec<usize>> {
        self.entries(d, &self.kept)
    }

    /// The held-out combinations as inventory entries.
    pub(super) fn held_out_entries(&self, d: &DemosDef) -> Vec<Vec<usize>> {
        self.entries(d, &self.held_out)
    }
}

/// Every demonstration of the expanded blocks, in order.
pub struct Demonstrations<'a> {
    m: &'a Model,
    blocks: &'a [DemoBlock],
    next_block: usize,
    current: Option<BlockDemos<'a>>,
}

impl<'a> Demonstrations<'a> {
    pub(super) fn new(m: &'a Model, blocks: &'a [DemoBlock]) -> Demonstrations<'a> {
        Demonstrations {
            m,
            blocks,
            next_block: 0,
            current: None,
        }
    }
}

impl Iterator for Demonstrations<'_> {
    type Item = Result<Demonstration, Error>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            if let Some(demo) = self.current.as_mut().and_then(Iterator::next) {
                return Some(demo);
            }
            let index = self.next_block;
            let block = self.blocks.get(index)?;
            self.next_block += 1;
            self.current = Some(match block.source {
                BlockSource::Observed(i) => BlockDemos::Observed(Some(observed(self.m, i, index))),
                BlockSource::Generated(i) => {
                    let d = &self.m.demo_sets[i];
                    match Kept::choose(d) {
                        Ok(kept) => {
                            BlockDemos::Generated(Box::new(Generator::new(self.m, d, index, kept)))
                        }
                        Err(e) => BlockDemos::Failed(Some(e)),
                    }
                }
            });
        }
    }
}

enum BlockDemos<'a> {
    Observed(Option<Demonstration>),
    Generated(Box<Generator<'a>>),
    Failed(Option<Error>),
}

impl Iterator for BlockDemos<'_> {
    type Item = Result<Demonstration, Error>;

    fn next(&mut self) -> Option<Self::Item> {
        match self {
            BlockDemos::Observed(d) => d.take().map(Ok),
            BlockDemos::Generated(g) => g.next(),
            BlockDemos::Failed(e) => e.take().map(Err),
        }
    }
}

/// The one demonstration of the model's `demo` block `i` (block `block`).
fn observed(m: &Model, i: usize, block: usize) -> Demonstration {
    let d = &m.demos[i];
    let order = &m.orders[d.order];
    let mut positions: Vec<[f64; 2]> = m.inventories[order.inventory]
        .entries
        .iter()
        .map(|e| e.at)
        .collect();
    for p in &d.at {
        positions[p.entry] = p.at;
    }
    Demonstration {
        block,
        setup: Setup {
            inventory: order.inventory,
            assignment: order.assignment.iter().map(|a| (a.entry, a.slot)).collect(),
            human_packed: Vec::new(),
            missing: Vec::new(),
            positions,
        },
        sequence: d.sequence.clone(),
    }
}

/// The demonstrations of a `demos` block, generated to check and count it
/// (numbered as block 0: the caller keeps only the counts).
pub(super) fn generated<'a>(
    m: &'a Model,
    d: &'a DemosDef,
    kept: Kept,
) -> impl Iterator<Item = Result<Demonstration, Error>> + 'a {
    Generator::new(m, d, 0, kept)
}

/// A `demos` block's demonstrations: for each kept combination, each
/// arrangement of it in the slots, each repeat, draws (2) to (4).
struct Generator<'a> {
    m: &'a Model,
    d: &'a DemosDef,
    block: usize,
    rng: ChaCha8Rng,
    kept: Vec<Vec<usize>>,
    tuples: Vec<Vec<usize>>,
    /// The next demonstration: (kept combination, arrangement, repeat).
    at: (usize, usize, usize),
    /// A draw failed: nothing follows.
    stopped: bool,
}

impl<'a> Generator<'a> {
    fn new(m: &'a Model, d: &'a DemosDef, block: usize, kept: Kept) -> Generator<'a> {
        Generator {
            m,
            d,
            block,
            kept: kept.kept_entries(d),
            rng: kept.rng,
            tuples: arrangements(d.choose.slots.len(), d.choose.n),
            at: (0, 0, 0),
            stopped: false,
        }
    }

    fn advance(&mut self) {
        let (combo, tuple, repeat) = &mut self.at;
        *repeat += 1;
        if *repeat == self.d.repeat {
            *repeat = 0;
            *tuple += 1;
            if *tuple == self.tuples.len() {
                *tuple = 0;
                *combo += 1;
            }
        }
    }
}

impl Iterator for Generator<'_> {
    type Item = Result<Demonstration, Error>;

    fn next(&mut self) -> Option<Self::Item> {
        let (combo, tuple, _) = self.at;
        if self.stopped || self.d.repeat == 0 || self.tuples.is_empty() {
            return None;
        }
        let products = self.kept.get(combo)?;
        let (d, m) = (self.d, self.m);
        let c = &d.choose;
        let inv = &m.inventories[d.inventory];
        let mut assignment: Vec<(usize, usize)> = products
            .iter()
            .zip(&self.tuples[tuple])
            .map(|(&e, &s)| (e, c.slots[s]))
            .collect();
        assignment.sort_unstable();
        self.advance();
        let selected: Vec<usize> = assignment.iter().map(|(e, _)| *e).collect();
        let (human_packed, missing) = draw_absent(&mut self.rng, &selected, d.human, d.missing);
        let positions = match jitter(m, inv, &human_packed, &missing, d.jitter, &mut self.rng) {
            Ok(p) => p,
            Err(product) => {
                self.stopped = true;
                return Some(Err(jitter_error(
                    m,
                    inv,
                    product,
                    d.jitter_loc.unwrap_or(d.loc),
                )));
            }
        };
        let mut sequence: Vec<usize> = selected
            .iter()
            .copied()
            .filter(|e| !human_packed.contains(e) && !missing.contains(e))
            .collect();
        match d.sequence {
            SequenceMode::Ascending => {}
            SequenceMode::Descending => sequence.reverse(),
            SequenceMode::Listed => {
                sequence.sort_by_key(|e| c.entries.iter().position(|x| x == e));
            }
            SequenceMode::Random => sequence.shuffle(&mut self.rng),
        }
        Some(Ok(Demonstration {
            block: self.block,
            setup: Setup {
                inventory: d.inventory,
                assignment,
                human_packed,
                missing,
                positions,
            },
            sequence,
        }))
    }
}
