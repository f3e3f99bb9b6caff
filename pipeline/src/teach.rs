//! What a training run learns from: the demonstrations chosen from a
//! compiled directory (in one cell or several), the sequence rule they
//! follow, the reasoner's decisions they imply, and the expert's replays
//! of them and rehearsals of what they did not move (motion
//! demonstrations).

use crate::artifacts::CompiledDir;
use crate::episode::{Episode, demonstration_episode};
use crate::error::{Contradiction, PipelineError, Result};
use crate::rehearse::rehearsals;
use crate::replay::{motion_examples, replay_all};
use packwright_compiler::artifact::{DemonstrationRecord, WorldFile};
use packwright_compiler::{Compiled, Warning, emit};
use packwright_interface::record::MotionLog;
use packwright_interface::{Graph, SequenceRule, world::Seen};
use packwright_motion::execute::demonstrated_decisions;
use packwright_nets::{GraphExample, Task, TrainingSet};
use serde::Serialize;
use std::collections::{BTreeMap, BTreeSet};
use std::fmt;
use std::path::Path;
use std::time::Instant;

/// The chosen demonstrations of one compiled directory.
pub struct Lesson {
    world: WorldFile,
    /// The chosen demonstrations, in manifest order.
    pub chosen: Vec<DemonstrationRecord>,
    /// The cells they are in, sorted.
    pub cells: Vec<String>,
    /// The demonstration blocks chosen, sorted.
    pub blocks: Vec<String>,
    /// The sequence rule they follow.
    pub sequence: SequenceRule,
    /// The chosen demonstrations (indices) that break it: their decisions
    /// are not taught.
    pub exceptions: Vec<usize>,
    /// The chosen demonstrations (indices) of blocks with `sequence
    /// random`: they show that any order is right, so they are taught in
    /// the rule's order and the rule is inferred from the others (the
    /// inventory's order when there are none).
    pub any_order: Vec<usize>,
    /// The expert's rehearsals of the products and slots no chosen
    /// demonstration moved ([`rehearsals`]): motion examples only.
    pub rehearsals: Vec<DemonstrationRecord>,
    /// With several cells: the cells that keep the rule their own
    /// demonstrations follow, read alone, where it orders one of their
    /// inventories otherwise than [`Lesson::sequence`] (see `own_rule`).
    pub cell_rules: BTreeMap<String, SequenceRule>,
    /// The cells whose own demonstrations, read alone, follow another
    /// rule than the one they are taught ([`Lesson::rule_for`]): they
    /// share products with other cells, whose demonstrations order them
    /// too, and their own break no rule taught with those; with that rule.
    pub read_otherwise: Vec<(String, SequenceRule)>,
    /// Other rules the demonstrations follow as well, when they show few
    /// pairs of products in order ([`Inferred::rivals`]).
    pub rivals: Vec<SequenceRule>,
    /// With several cells: each cell on the one rule, read from
    /// demonstrations, with the pairs of its own products that rule
    /// orders and no demonstration does ([`guessed_in`]).
    pub cell_guessed: Vec<(String, Guessed)>,
    /// With several cells: each cell that keeps its own rule
    /// ([`Lesson::cell_rules`]) read from few pairs, with the other rules
    /// its demonstrations follow as well ([`Inferred::rivals`]).
    pub cell_rivals: Vec<(String, Vec<SequenceRule>)>,
    /// The pairs of products a priority list read from the
    /// demonstrations orders as the inventory lists them
    /// ([`Inferred::guessed`]).
    pub guessed: Guessed,
    /// One cell taught: a priority list read from the demonstrations
    /// that a direction explains but for a few ([`Inferred::leaning`]).
    pub leaning: Option<Leaning>,
}

/// The expert's replays of a lesson's demonstrations.
pub struct Replayed {
    /// Per chosen demonstration: its motion log, `None` if the expert
    /// could not complete it.
    pub logs: Vec<Option<MotionLog>>,
    /// Per rehearsal, the same.
    pub rehearsed: Vec<Option<MotionLog>>,
    /// Why the expert could not complete a chosen demonstration (its
    /// index) or a rehearsal, for people.
    pub problems: Vec<ReplayProblem>,
    pub seconds: f64,
}

/// A replay the expert could not complete.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReplayProblem {
    /// A rehearsal (an index into the lesson's rehearsals), or a chosen
    /// demonstration (an index into the chosen ones).
    pub rehearsal: bool,
    pub index: usize,
    /// The block it comes from.
    pub block: String,
    /// Its products in the order packed.
    pub sequence: Vec<String>,
    /// The run's first problem, for people.
    pub why: String,
}

impl fmt::Display for ReplayProblem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let n = self.index + 1;
        let products = self.sequence.join(", ");
        if self.rehearsal {
            write!(
                f,
                "the expert could not complete rehearsal {n} ({products})"
            )?;
        } else {
            write!(
                f,
                "the expert could not replay demonstration {n} (`{}`: {products})",
                self.block
            )?;
        }
        write!(f, ": {}", self.why)
    }
}

impl Replayed {
    /// Indices (into the chosen demonstrations) of the failed replays.
    pub fn failures(&self) -> Vec<usize> {
        self.logs
            .iter()
            .enumerate()
            .filter(|(_, l)| l.is_none())
            .map(|(i, _)| i)
            .collect()
    }

    pub fn complete(&self) -> Vec<&MotionLog> {
        self.logs.iter().flatten().collect()
    }

    /// How many rehearsals the expert completed.
    pub fn rehearsals_completed(&self) -> usize {
        self.rehearsed.iter().flatten().count()
    }
}

impl Lesson {
    /// The demonstrations of the blocks `demos` (all when empty) in the
    /// compiled directory `dir`, whose artifacts are checked first
    /// ([`CompiledDir::read_whole`]).
    pub fn read(dir: &Path, demos: &[String]) -> Result<Lesson> {
        let compiled = CompiledDir::read_whole(dir)?;
        let manifest = compiled.manifest();
        let world = compiled.world().clone();
        let known: BTreeSet<&str> = manifest
            .demo_blocks
            .iter()
            .map(|b| b.name.as_str())
            .collect();
        if let Some(unknown) = demos.iter().find(|d| !known.contains(d.as_str())) {
            return Err(PipelineError::NoSuch {
                what: "demonstration block",
                name: unknown.clone(),
                known: format!(
                    "{} has: {}",
                    dir.display(),
                    known.iter().copied().collect::<Vec<_>>().join(", ")
                ),
            });
        }
        let chosen: Vec<DemonstrationRecord> = compiled
            .demonstrations()
            .iter()
            .filter(|d| demos.is_empty() || demos.contains(&d.block))
            .cloned()
            .collect();
        if chosen.is_empty() {
            return Err(PipelineError::Selection(format!(
                "{} holds no demonstrations to learn from: compile files with `demo` or `demos` blocks",
                dir.display()
            )));
        }
        let cells: Vec<String> = chosen
            .iter()
            .map(|d| d.cell.clone())
            .collect::<BTreeSet<_>>()
            .into_iter()
            .collect();
        let blocks: Vec<String> = chosen
            .iter()
            .map(|d| d.block.clone())
            .collect::<BTreeSet<_>>()
            .into_iter()
            .collect();
        let any_order: BTreeSet<&str> = manifest
            .demo_blocks
            .iter()
            .filter(|b| b.any_order)
            .map(|b| b.name.as_str())
            .collect();
        let mut chosen = chosen;
        let any_order: Vec<usize> = chosen
            .iter()
            .enumerate()
            .filter(|(_, d)| any_order.contains(d.block.as_str()))
            .map(|(k, _)| k)
            .collect();
        // The rule comes from the demonstrations that show an order; with
        // none, the inventory's.
        let ordered: Vec<usize> = (0..chosen.len())
            .filter(|k| !any_order.contains(k))
            .collect();
        let mut read_otherwise = Vec::new();
        let mut cell_rules = BTreeMap::new();
        let mut cell_rivals = Vec::new();
        let mut cell_guessed = Vec::new();
        let Inferred {
            rule: sequence,
            exceptions,
            rivals,
            guessed,
            leaning,
        } = if ordered.is_empty() {
            Inferred {
                rule: SequenceRule::Ascending,
                exceptions: Vec::new(),
                rivals: Vec::new(),
                guessed: Guessed::default(),
                leaning: None,
            }
        } else {
            let shown: Vec<DemonstrationRecord> =
                ordered.iter().map(|&k| chosen[k].clone()).collect();
            // The priorities `sequence listed` blocks wrote, of the blocks
            // taught.
            // Those of the cells `keep` keeps.
            let declared_in = |keep: &dyn Fn(&str) -> bool| -> Vec<Vec<String>> {
                manifest
                    .demo_blocks
                    .iter()
                    .filter(|b| !b.priority.is_empty() && blocks.contains(&b.name))
                    .filter(|b| keep(&b.cell))
                    .map(|b| b.priority.clone())
                    .collect()
            };
            let declared = declared_in(&|_| true);
            // The blocks that declared `sequence ascending` (or nothing:
            // the default) or `descending`, with the direction.
            let directed: BTreeMap<&str, SequenceRule> = manifest
                .demo_blocks
                .iter()
                .filter(|b| b.kind == "demos" && b.priority.is_empty() && !b.any_order)
                .map(|b| (b.name.as_str(), direction(b.descending)))
                .collect();
            // Each cell's own demonstrations, read alone (indices into
            // `shown`, and the rule they follow).
            let alone: Vec<(&String, Vec<usize>, Result<Inferred>)> = cells
                .iter()
                .filter(|_| cells.len() > 1)
                .map(|cell| {
                    let mine: Vec<usize> = (0..shown.len())
                        .filter(|&i| &shown[i].cell == cell)
                        .collect();
                    let own: Vec<DemonstrationRecord> =
                        mine.iter().map(|&i| shown[i].clone()).collect();
                    // Read alone: with its own blocks' declared lists
                    // only (another cell's `sequence listed` made a cell's
                    // two hand-written pairs read as that list, and the
                    // cell was packed in it without a word).
                    let own_declared = declared_in(&|c| c == cell.as_str());
                    let rule = sequence_rule(&world, &own, &own_declared, &directed);
                    (cell, mine, rule)
                })
                .filter(|(_, mine, _)| !mine.is_empty())
                .collect();
            // Cells taught in orders that no one rule explains together
            // (two lines stocking the same products, one packed
            // ascending, the other descending), each of which follows
            // one: each keeps its own, and the rule for every other cell
            // is the one that explains the most.
            let (mut inferred, each_own) = match sequence_rule(&world, &shown, &declared, &directed)
            {
                Ok(inferred) => (inferred, false),
                Err(PipelineError::ContradictorySequence(why))
                    if !alone.is_empty() && alone.iter().all(|(_, _, r)| r.is_ok()) =>
                {
                    let rule = why.best.clone();
                    (
                        Inferred {
                            rule,
                            exceptions: Vec::new(),
                            rivals: Vec::new(),
                            guessed: Guessed::default(),
                            leaning: None,
                        },
                        true,
                    )
                }
                Err(e) => return Err(e),
            };
            let mut exceptions: BTreeSet<usize> = inferred.exceptions.iter().copied().collect();
            for (cell, mine, own) in alone {
                let Ok(own) = own else {
                    continue;
                };
                let otherwise = orders_otherwise(&world, cell, &own.rule, &inferred.rule);
                if each_own {
                    exceptions.extend(own.exceptions.iter().map(|&e| mine[e]));
                    if otherwise {
                        if !own.rivals.is_empty() {
                            cell_rivals.push((cell.clone(), own.rivals));
                        }
                        cell_rules.insert(cell.clone(), own.rule);
                    }
                    continue;
                }
                if !otherwise {
                    continue;
                }
                let broken = mine.iter().any(|i| exceptions.contains(i));
                if own_rule(&world, &cells, cell, broken) {
                    exceptions.retain(|i| !mine.contains(i));
                    exceptions.extend(own.exceptions.iter().map(|&e| mine[e]));
                    // Kept from few pairs: said for this cell, as for a
                    // cell taught alone.
                    if !own.rivals.is_empty() {
                        cell_rivals.push((cell.clone(), own.rivals));
                    }
                    cell_rules.insert(cell.clone(), own.rule);
                } else {
                    read_otherwise.push((cell.clone(), own.rule));
                }
            }
            // The rule for the other cells, read again without the cells
            // that keep their own: their demonstrations no longer order
            // the others' products (a cell kept descending put D and E
            // first in the list another cell, taught ascending, was then
            // packed in).
            if !each_own && !cell_rules.is_empty() {
                let rest: Vec<usize> = (0..shown.len())
                    .filter(|&i| !cell_rules.contains_key(&shown[i].cell))
                    .collect();
                let rest_demos: Vec<DemonstrationRecord> =
                    rest.iter().map(|&i| shown[i].clone()).collect();
                let rest_declared = declared_in(&|c| !cell_rules.contains_key(c));
                if !rest.is_empty()
                    && let Ok(again) = sequence_rule(&world, &rest_demos, &rest_declared, &directed)
                {
                    exceptions.retain(|&i| cell_rules.contains_key(&shown[i].cell));
                    exceptions.extend(again.exceptions.iter().map(|&e| rest[e]));
                    read_otherwise
                        .retain(|(cell, own)| orders_otherwise(&world, cell, own, &again.rule));
                    inferred.rule = again.rule;
                    inferred.guessed = again.guessed;
                }
            }
            // Each cell on the one rule read from demonstrations (not
            // declared): the pairs of its own products the rule orders
            // that no demonstration of the cells on it orders (the rule's
            // pairs over all cells would name products no inventory holds
            // together).
            if cells.len() > 1 && inferred.guessed != Guessed::default() {
                let on_rule: Vec<&DemonstrationRecord> = shown
                    .iter()
                    .filter(|d| !cell_rules.contains_key(&d.cell))
                    .collect();
                cell_guessed = cells
                    .iter()
                    .filter(|c| !cell_rules.contains_key(*c))
                    .filter_map(|cell| {
                        let g = guessed_in(&world, cell, &inferred.rule, &on_rule);
                        (!g.untaught.is_empty()).then(|| (cell.clone(), g))
                    })
                    .collect();
            }
            Inferred {
                exceptions: exceptions.iter().map(|&e| ordered[e]).collect(),
                rule: inferred.rule,
                // One rule over several cells: said for one cell's alone.
                rivals: if cells.len() == 1 {
                    inferred.rivals
                } else {
                    Vec::new()
                },
                guessed: if cells.len() == 1 {
                    inferred.guessed
                } else {
                    Guessed::default()
                },
                leaning: inferred.leaning.filter(|_| cells.len() == 1),
            }
        };
        for &k in &any_order {
            let rule = cell_rules.get(&chosen[k].cell).unwrap_or(&sequence);
            follow_rule(&world, rule, &mut chosen[k]);
        }
        let rehearsals = rehearsals(&world, &chosen);
        Ok(Lesson {
            world,
            chosen,
            cells,
            blocks,
            sequence,
            exceptions,
            any_order,
            rehearsals,
            cell_rules,
            read_otherwise,
            rivals,
            cell_rivals,
            guessed,
            cell_guessed,
            leaning,
        })
    }

    /// The rule the demonstrations of `cell` are taught in: its own
    /// ([`Lesson::cell_rules`]), else the one for every cell.
    pub fn rule_for(&self, cell: &str) -> &SequenceRule {
        self.cell_rules.get(cell).unwrap_or(&self.sequence)
    }

    /// Replays the chosen demonstrations and the rehearsals with the
    /// expert in the simulator (in parallel); `tick` after each.
    pub fn replay(&self, tick: &(dyn Fn() + Sync)) -> Result<Replayed> {
        let started = Instant::now();
        let demos: Vec<&DemonstrationRecord> = self.chosen.iter().chain(&self.rehearsals).collect();
        let mut problems = Vec::new();
        let mut logs = Vec::with_capacity(demos.len());
        for (i, (replay, demo)) in replay_all(&self.world, &demos, tick)?
            .into_iter()
            .zip(&demos)
            .enumerate()
        {
            let rehearsal = i >= self.chosen.len();
            match replay {
                Ok(log) => logs.push(Some(log)),
                Err(why) => {
                    logs.push(None);
                    problems.push(ReplayProblem {
                        rehearsal,
                        index: if rehearsal { i - self.chosen.len() } else { i },
                        block: demo.block.clone(),
                        sequence: demo.sequence.clone(),
                        why,
                    });
                }
            }
        }
        let rehearsed = logs.split_off(self.chosen.len());
        Ok(Replayed {
            logs,
            rehearsed,
            problems,
            seconds: started.elapsed().as_secs_f64(),
        })
    }

    /// The three networks' examples: the reasoner's decisions each
    /// demonstration implies (under the lesson's sequence rule), and the
    /// sub-goals and actions of the completed replays.
    pub fn training_set(&self, replayed: &Replayed) -> Result<TrainingSet> {
        let mut set = TrainingSet::default();
        for (k, (demo, log)) in self.chosen.iter().zip(&replayed.logs).enumerate() {
            let ep = demonstration_episode(&self.world, demo)?;
            let taught = !self.exceptions.contains(&k);
            let seen: Vec<Seen> = ep
                .placements
                .iter()
                .map(|p| Seen {
                    name: p.product.name.clone(),
                    centre: p.centre,
                    yaw: 0.0,
                })
                .collect();
            let sequence: Vec<usize> = ep
                .task
                .assignment
                .iter()
                .take(demo.sequence.len())
                .map(|&(p, _)| p)
                .collect();
            let rule = self.rule_for(&demo.cell);
            let decisions = demonstrated_decisions(&ep.task, &seen, &sequence, rule);
            for (graph, choice) in decisions.into_iter().filter(|_| taught) {
                let example = |graph: Graph| GraphExample {
                    target: choice.node.unwrap_or(graph.nodes.len()),
                    slot: choice.label.checked_sub(1),
                    graph,
                };
                if let Some(more) = with_more_selected(&graph, choice.node) {
                    set.graphs.push(example(more));
                }
                if let Some(fewer) = without_later(&graph, choice.node) {
                    if let Some(swapped) = with_skipped_swapped(&fewer, choice.node) {
                        set.graphs.push(example(swapped));
                    }
                    set.graphs.push(example(fewer));
                }
                set.graphs.push(example(graph));
            }
            if let Some(log) = log {
                let (s, a) = motion_examples(log, ep.task.cell.base);
                set.subgoals.extend(s);
                set.actions.extend(a);
            }
        }
        for (ep, log) in self.rehearsal_episodes()?.iter().zip(&replayed.rehearsed) {
            if let Some(log) = log {
                let (s, a) = motion_examples(log, ep.task.cell.base);
                set.subgoals.extend(s);
                set.actions.extend(a);
            }
        }
        Ok(set)
    }

    /// The episodes of the chosen demonstrations (their arms and cells).
    pub fn episodes(&self) -> Result<Vec<Episode>> {
        self.chosen
            .iter()
            .map(|d| demonstration_episode(&self.world, d))
            .collect()
    }

    /// The episodes of the rehearsals.
    pub fn rehearsal_episodes(&self) -> Result<Vec<Episode>> {
        self.rehearsals
            .iter()
            .map(|d| demonstration_episode(&self.world, d))
            .collect()
    }

    /// What a model trained on this lesson was taught.
    pub fn task(&self) -> Task {
        Task {
            cells: self.cells.clone(),
            sequence: self.sequence.clone(),
            cell_rules: self.cell_rules.clone(),
            demos: self.blocks.clone(),
        }
    }
}

/// Whether `cell`, whose own demonstrations read alone follow another
/// rule than the one inferred over every taught cell, keeps its own: when
/// some of them break that rule (`broken`), or when none of its products
/// stands in another taught cell's inventory, so that the other cells'
/// demonstrations say nothing of their order. Where they share products,
/// the joint rule orders them from more demonstrations than the cell's
/// own and is kept.
fn own_rule(world: &WorldFile, cells: &[String], cell: &str, broken: bool) -> bool {
    let products_of = |c: &str| -> BTreeSet<&str> {
        world
            .inventories
            .iter()
            .filter(|i| i.cell == c)
            .flat_map(|i| i.products.iter().map(|p| p.product.as_str()))
            .collect()
    };
    let mine = products_of(cell);
    broken
        || cells
            .iter()
            .filter(|c| c.as_str() != cell)
            .all(|c| products_of(c).is_disjoint(&mine))
}

/// Whether rules `a` and `b` order some inventory of `cell` differently
/// (a listed order taught over several cells can chain one cell's
/// products as its own rule does).
fn orders_otherwise(world: &WorldFile, cell: &str, a: &SequenceRule, b: &SequenceRule) -> bool {
    world
        .inventories
        .iter()
        .filter(|i| i.cell == cell)
        .any(|i| {
            let names: Vec<&str> = i.products.iter().map(|p| p.product.as_str()).collect();
            a.chain(&names) != b.chain(&names)
        })
}

/// A decision's graph with more products selected than its demonstration
/// had, and the same answer under the rule: every unselected product that
/// the rule reaches later (picking: after the chosen node in the chain;
/// placing, `chosen` `None`: any) becomes a selected product still waiting
/// (its goal the first slot). Demonstrations of n products never show a
/// larger order; a reasoner taught only them chose a waiting product over
/// the box while holding one, in orders of n + 1. `None` when no product
/// is left to select.
fn with_more_selected(graph: &Graph, chosen: Option<usize>) -> Option<Graph> {
    let first = chosen.map_or(0, |c| c + 1);
    let slot = *graph.slots.first()?;
    let mut more = graph.clone();
    let mut changed = false;
    for node in more.nodes.iter_mut().skip(first) {
        if !node.selected {
            node.selected = true;
            node.goal = [slot[0], slot[1], node.height / 2.0];
            changed = true;
        }
    }
    changed.then_some(more)
}

/// A picking decision's graph without the products after the chosen one
/// along the chain (missing stock), and the same answer under the rule:
/// the chosen product is still the first selected one not in its slot,
/// now last along the chain. A node's place is its index over the chain's
/// length, so the products before it that the rule skips (packed, or not
/// in the order) now stand a whole chain before it. A reasoner taught
/// only the demonstrations' places chose a packed product at the chain's
/// head over a waiting one at its tail, a pair of places no demonstration
/// of 2 of 6 products showed (per-cell models of generated cells, e.g.
/// development cell 2903). `None` for a placing decision or when the
/// chosen product is already last.
fn without_later(graph: &Graph, chosen: Option<usize>) -> Option<Graph> {
    let keep = chosen? + 1;
    (keep < graph.nodes.len()).then(|| Graph {
        nodes: graph.nodes[..keep].to_vec(),
        ..graph.clone()
    })
}

/// A picking decision's graph with the two kinds of product the rule
/// skips before the chosen one swapped, and the same answer under the
/// rule: each product outside the order becomes a selected one already in
/// its slot, each packed one a product outside the order. Applied to
/// [`without_later`]'s graph, it puts the kind the demonstrations did not
/// show at the chain's head, with the chosen product at its tail. Orders
/// whose products all come late in the chain show only products outside
/// the order there: a model taught three hand-written demonstrations
/// (`tests/cells/handful.pack`) chose a product packed at the chain's head
/// again in 19 of 30 packages of five; an order whose first product
/// heads the chain shows only packed products there: a model taught one
/// such demonstration chose a product outside the order at the head.
/// `None` for a placing decision or the chain's first product.
fn with_skipped_swapped(graph: &Graph, chosen: Option<usize>) -> Option<Graph> {
    let chosen = chosen.filter(|&c| c > 0)?;
    let mut swapped = graph.clone();
    for node in swapped.nodes.iter_mut().take(chosen) {
        node.selected = !node.selected;
        node.goal = node.centre;
    }
    Some(swapped)
}

/// `demo`'s products handled in `rule`'s order (a demonstration that
/// shows any order is right, taught as the rule's). Products its
/// inventory does not list keep their places at the end.
fn follow_rule(world: &WorldFile, rule: &SequenceRule, demo: &mut DemonstrationRecord) {
    let Some(inventory) = world.inventories.iter().find(|i| i.name == demo.inventory) else {
        return;
    };
    let names: Vec<&str> = inventory
        .products
        .iter()
        .map(|p| p.product.as_str())
        .collect();
    let chain = rule.chain(&names);
    let place = |name: &str| {
        chain
            .iter()
            .position(|&i| names[i] == name)
            .unwrap_or(usize::MAX)
    };
    demo.sequence.sort_by_key(|n| place(n));
}

/// Share of the demonstrations a rule must explain to be taught.
pub const RULE_MAJORITY: f64 = 0.8;

/// Whether a rule that `agree` of `total` demonstrations follow explains
/// at least [`RULE_MAJORITY`] of them.
fn explains_majority(agree: usize, total: usize) -> bool {
    agree as f64 >= RULE_MAJORITY * total as f64
}

/// The sequence rule a lesson's demonstrations follow, and the ones that
/// do not follow it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Inferred {
    pub rule: SequenceRule,
    /// Indices (into the demonstrations) of those that break the rule:
    /// reported by `train`, and their decisions left out of the reasoner's
    /// examples.
    pub exceptions: Vec<usize>,
    /// Rules the demonstrations follow as well, where they show fewer
    /// than [`FEW_PAIRS`] pairs of products and neither a direction nor
    /// a priority was declared: each orders some of the products no
    /// demonstration shows together otherwise than `rule` (one
    /// hand-written demonstration of two products taught `descending`
    /// where the line packs by a priority list that put those two so).
    pub rivals: Vec<SequenceRule>,
    /// A priority list read from the demonstrations (none declared), or a
    /// direction read from demonstrations that order fewer than half of
    /// the pairs of products: the pairs it orders that no demonstration
    /// orders, directly or through others. A list orders them as the
    /// inventory lists them where the taught pairs allow, a direction as
    /// it orders the rest: a guess, not something taught.
    pub guessed: Guessed,
    /// A priority list read from demonstrations (none declared) where a
    /// direction explains all but a few of them, at least
    /// [`RULE_MAJORITY`]: what the few make the list order against it.
    pub leaning: Option<Leaning>,
}

/// A priority list read from demonstrations that a direction explains
/// all but a few of: the list fits those few too, and through them orders
/// products no demonstration shows together against the direction (one
/// hand-written demonstration of five out of inventory order made the
/// list order two untaught pairs against it, and nothing was said).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Leaning {
    /// The direction: ascending or descending.
    pub direction: SequenceRule,
    /// How many demonstrations break it, of how many.
    pub breaking: usize,
    pub demonstrations: usize,
    /// The first that breaks it: its block and sequence.
    pub block: String,
    pub sequence: Vec<String>,
    /// The pairs the list orders against the direction (first before
    /// second) that no demonstration shows together.
    pub against: Vec<(String, String)>,
}

/// What a priority list read from demonstrations leaves to the inventory.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Guessed {
    /// Pairs of the list's products the demonstrations order, directly or
    /// through others.
    pub ordered: usize,
    /// Pairs of the list's products in all.
    pub pairs: usize,
    /// The pairs they do not order, each as the list has it (first
    /// before second), in the list's order.
    pub untaught: Vec<(String, String)>,
}

/// Fewer pairs of products shown in order than this, and a rule read
/// from them is said to rest on them ([`Inferred::rivals`]).
pub const FEW_PAIRS: usize = 3;

/// The sequence rule the demonstrations of `cell` in a compilation
/// follow, or `None` when it holds none of that cell: the order a model
/// that was not taught the cell packs it in (`execute`, `eval`). Its
/// reasoner learned "the first selected product along the chain not yet
/// in its slot", which is the same function for any rule, so the rule can
/// come from the cell's own file without training. Blocks with `sequence
/// random` show no order and are left out (`None` when only they teach
/// the cell). An error when the others follow no one rule.
pub fn cell_rule(compiled: &Compiled, cell: &str) -> Result<Option<Inferred>> {
    let records = demonstration_records(compiled)?;
    cell_rule_among(compiled, &records, &emit::world_file(&compiled.model), cell)
}

/// Every demonstration record of a compilation.
fn demonstration_records(compiled: &Compiled) -> Result<Vec<DemonstrationRecord>> {
    emit::demonstration_records(&compiled.model, &compiled.expanded)
        .map_err(|e| PipelineError::Compile(Box::new(e)))
}

/// [`cell_rule`] from the compilation's demonstration `records` and
/// `world`, made once for all its cells.
fn cell_rule_among(
    compiled: &Compiled,
    records: &[DemonstrationRecord],
    world: &WorldFile,
    cell: &str,
) -> Result<Option<Inferred>> {
    let any_order: BTreeSet<&str> = compiled
        .expanded
        .blocks
        .iter()
        .filter(|b| b.any_order)
        .map(|b| b.name.as_str())
        .collect();
    let demos: Vec<DemonstrationRecord> = records
        .iter()
        .filter(|d| d.cell == cell && !any_order.contains(d.block.as_str()))
        .cloned()
        .collect();
    if demos.is_empty() {
        return Ok(None);
    }
    let model = &compiled.model;
    let declared: Vec<Vec<String>> = compiled
        .expanded
        .blocks
        .iter()
        .filter(|b| model.cells[model.inventories[b.inventory].cell].name == cell)
        .filter(|b| !b.priority.is_empty())
        .map(|b| {
            let inventory = &model.inventories[b.inventory];
            b.priority
                .iter()
                .map(|&e| model.products[inventory.entries[e].product].name.clone())
                .collect()
        })
        .collect();
    let directed: BTreeMap<&str, SequenceRule> = compiled
        .expanded
        .blocks
        .iter()
        .filter(|b| b.kind == "demos" && b.priority.is_empty() && !b.any_order)
        .map(|b| (b.name.as_str(), direction(b.descending)))
        .collect();
    // Demonstrations of one product each order nothing, unless a block
    // declares an order for them (a list, or `sequence descending`:
    // ascending is also what one that wrote nothing gets): as none (a
    // model not taught the cell said they followed ascending, where a
    // `sequence random` file was said to order nothing).
    let shows_order = demos.iter().any(|d| d.sequence.len() > 1)
        || !declared.is_empty()
        || demos
            .iter()
            .any(|d| directed.get(d.block.as_str()) == Some(&SequenceRule::Descending));
    if !shows_order {
        return Ok(None);
    }
    sequence_rule(world, &demos, &declared, &directed).map(Some)
}

/// The direction a `demos` block declares.
fn direction(descending: bool) -> SequenceRule {
    if descending {
        SequenceRule::Descending
    } else {
        SequenceRule::Ascending
    }
}

/// W005 for every cell of a clean compilation whose demonstrations (but
/// `sequence random` ones) follow no one sequence rule, at the first block
/// that breaks the best one ([`cell_rule`]): `check` and `compile` report
/// them with the compiler's warnings, so that a file `train` would refuse
/// is named before anything is trained.
pub fn rule_warnings(compiled: &Compiled) -> Vec<Warning> {
    let model = &compiled.model;
    // A compilation whose records cannot be made has no rules to warn
    // about (`train` reports that itself).
    let Ok(records) = demonstration_records(compiled) else {
        return Vec::new();
    };
    let world = emit::world_file(model);
    model
        .cells
        .iter()
        .filter_map(|cell| {
            let Err(PipelineError::ContradictorySequence(why)) =
                cell_rule_among(compiled, &records, &world, &cell.name)
            else {
                return None;
            };
            let (block, sequence) = why
                .first
                .as_ref()
                .map(|(_, b, s)| (b.clone(), s.clone()))
                .unwrap_or_default();
            let at = model
                .demo_sets
                .iter()
                .find(|d| d.name == block)
                .map(|d| d.loc)
                .or_else(|| model.demos.iter().find(|d| d.name == block).map(|d| d.loc))
                .unwrap_or(cell.loc);
            Some(Warning::NoSequenceRule {
                at,
                cell: cell.name.clone(),
                best: why.best.to_string(),
                agree: why.agree,
                demonstrations: why.demonstrations,
                block,
                sequence,
            })
        })
        .collect()
}

/// The pairs of `list` that `before` (a pair shown in that order by the
/// demonstrations' majority) orders neither way, directly or through
/// other products.
fn guessed(list: &[String], before: impl Fn(&str, &str) -> bool) -> Guessed {
    let n = list.len();
    let mut reach: Vec<Vec<bool>> = (0..n)
        .map(|i| (0..n).map(|j| before(&list[i], &list[j])).collect())
        .collect();
    for k in 0..n {
        let through = reach[k].clone();
        for row in reach.iter_mut().filter(|row| row[k]) {
            for (r, &t) in row.iter_mut().zip(&through) {
                *r |= t;
            }
        }
    }
    let mut out = Guessed::default();
    for i in 0..n {
        for j in i + 1..n {
            out.pairs += 1;
            if reach[i][j] || reach[j][i] {
                out.ordered += 1;
            } else {
                out.untaught.push((list[i].clone(), list[j].clone()));
            }
        }
    }
    out
}

/// How many of `sequences` put each pair of products in that order.
fn pair_votes<'a>(
    sequences: impl Iterator<Item = &'a [String]>,
) -> BTreeMap<(&'a str, &'a str), usize> {
    let mut votes = BTreeMap::new();
    for sequence in sequences {
        for (i, a) in sequence.iter().enumerate() {
            for b in &sequence[i + 1..] {
                *votes.entry((a.as_str(), b.as_str())).or_default() += 1;
            }
        }
    }
    votes
}

/// Whether more of the `votes` put `a` before `b` than after it.
fn before_by(votes: &BTreeMap<(&str, &str), usize>, a: &str, b: &str) -> bool {
    votes.get(&(a, b)).copied().unwrap_or(0) > votes.get(&(b, a)).copied().unwrap_or(0)
}

/// The pairs of `cell`'s first inventory that `rule` orders and `demos`
/// do not, directly or through others ([`guessed`]); a direction's only
/// when they order fewer than half of them.
fn guessed_in(
    world: &WorldFile,
    cell: &str,
    rule: &SequenceRule,
    demos: &[&DemonstrationRecord],
) -> Guessed {
    let Some(inventory) = world.inventories.iter().find(|i| i.cell == cell) else {
        return Guessed::default();
    };
    let names: Vec<&str> = inventory
        .products
        .iter()
        .map(|p| p.product.as_str())
        .collect();
    let votes = pair_votes(demos.iter().map(|d| d.sequence.as_slice()));
    let before = |a: &str, b: &str| before_by(&votes, a, b);
    let order: Vec<String> = rule
        .chain(&names)
        .into_iter()
        .map(|i| names[i].to_owned())
        .collect();
    let g = guessed(&order, before);
    let listed = matches!(rule, SequenceRule::Listed(_));
    if listed || 2 * g.ordered < g.pairs {
        g
    } else {
        Guessed::default()
    }
}

/// The direction among `scored` (rules with the demonstrations that
/// break them) that the fewest break, when some do and it still explains
/// [`RULE_MAJORITY`] of `demos`, with the pairs the priority list `order`
/// (of `names`) orders against it that no demonstration shows together
/// (by `votes`); `None` when there are none.
fn leaning(
    demos: &[DemonstrationRecord],
    names: &[&str],
    order: &[String],
    votes: &BTreeMap<(&str, &str), usize>,
    scored: &[(SequenceRule, Vec<usize>)],
) -> Option<Leaning> {
    let (direction, breaking) = scored
        .iter()
        .filter(|(rule, broken)| {
            !matches!(rule, SequenceRule::Listed(_))
                && !broken.is_empty()
                && explains_majority(demos.len() - broken.len(), demos.len())
        })
        .min_by_key(|(_, broken)| broken.len())?;
    let along: Vec<&str> = direction
        .chain(names)
        .into_iter()
        .map(|i| names[i])
        .collect();
    let place = |n: &str| along.iter().position(|&m| m == n);
    let shown = |a: &str, b: &str| votes.contains_key(&(a, b)) || votes.contains_key(&(b, a));
    let against: Vec<(String, String)> = order
        .iter()
        .enumerate()
        .flat_map(|(i, a)| order[i + 1..].iter().map(move |b| (a, b)))
        .filter(|(a, b)| place(b) < place(a) && !shown(a, b))
        .map(|(a, b)| (a.clone(), b.clone()))
        .collect();
    let first = &demos[*breaking.first()?];
    (!against.is_empty()).then(|| Leaning {
        direction: direction.clone(),
        breaking: breaking.len(),
        demonstrations: demos.len(),
        block: first.block.clone(),
        sequence: first.sequence.clone(),
        against,
    })
}

/// Whether `sequence` (product names) follows `rule` in `inventory`
/// (product names in listed order).
fn follows(rule: &SequenceRule, inventory: &[&str], sequence: &[String]) -> bool {
    let chain = rule.chain(inventory);
    let place = |name: &str| {
        chain
            .iter()
            .position(|&i| inventory[i] == name)
            .unwrap_or(usize::MAX)
    };
    sequence.windows(2).all(|w| place(&w[0]) < place(&w[1]))
}

/// The sequence rule `demos` follow: ascending or descending inventory
/// order, or a priority list of product names (the order the most
/// demonstrations agree on pairwise; products never ordered against each
/// other keep the order a `declared` priority gives them, a `sequence
/// listed` block's `choose` list, else their first inventory's). The rule
/// that explains the most demonstrations wins (on a tie: the listed one
/// when a priority was declared, else ascending, then descending); it
/// must explain at least [`RULE_MAJORITY`] of them, else the
/// demonstrations teach no rule and this is an error. A direction the
/// `directed` blocks (`sequence ascending` or `descending`) declared comes
/// first: it is the rule when it explains that many, even where a
/// priority list fitted to every demonstration explains more (one
/// hand-written demonstration against a generated block's direction
/// would otherwise turn the rule into a list that orders the products no
/// demonstration showed together by the inventory, against the declared
/// direction); the others are its exceptions.
pub fn sequence_rule(
    world: &WorldFile,
    demos: &[DemonstrationRecord],
    declared: &[Vec<String>],
    directed: &BTreeMap<&str, SequenceRule>,
) -> Result<Inferred> {
    let mut inventories: Vec<Vec<&str>> = Vec::new();
    let mut names: Vec<&str> = Vec::new();
    for d in demos {
        let inventory = world
            .inventories
            .iter()
            .find(|i| i.name == d.inventory)
            .ok_or_else(|| PipelineError::Unknown {
                file: "orders.json",
                what: "inventory",
                name: d.inventory.clone(),
            })?;
        let listed: Vec<&str> = inventory
            .products
            .iter()
            .map(|p| p.product.as_str())
            .collect();
        for &n in &listed {
            if !names.contains(&n) {
                names.push(n);
            }
        }
        inventories.push(listed);
    }
    let votes = pair_votes(demos.iter().map(|d| d.sequence.as_slice()));
    // Declared priorities first: the order a tie below keeps.
    let mut names: Vec<&str> = declared
        .iter()
        .flatten()
        .map(String::as_str)
        .chain(names)
        .fold(Vec::new(), |mut out, n| {
            if !out.contains(&n) {
                out.push(n);
            }
            out
        });
    names.retain(|n| inventories.iter().any(|inv| inv.contains(n)));
    // The priority list: the majority's pairwise order, one product at a
    // time (the first not after any remaining one; in a cycle, the one
    // after the fewest).
    let after = |m: &str, n: &str| before_by(&votes, m, n);
    // Ties (products no demonstration puts in an order) go in the order
    // of `names`.
    let priority = |names: Vec<&str>| {
        let mut left = names;
        let mut list = Vec::new();
        while !left.is_empty() {
            let behind = |n: &str| left.iter().filter(|&&m| m != n && after(m, n)).count();
            let i = (0..left.len())
                .min_by_key(|&i| behind(left[i]))
                .unwrap_or(0);
            list.push(left.remove(i).to_owned());
        }
        SequenceRule::Listed(list)
    };
    let listed = priority(names.clone());
    let candidates = if declared.is_empty() {
        [SequenceRule::Ascending, SequenceRule::Descending, listed]
    } else {
        [listed, SequenceRule::Ascending, SequenceRule::Descending]
    };
    let breaking = |rule: &SequenceRule| -> Vec<usize> {
        demos
            .iter()
            .zip(&inventories)
            .enumerate()
            .filter(|(_, (d, inv))| !follows(rule, inv, &d.sequence))
            .map(|(k, _)| k)
            .collect()
    };
    // The direction the directed blocks declared, when they agree on one:
    // each demonstration of two products or more follows its block's by
    // construction; one of a single product follows both, so only a
    // block that wrote `sequence descending` says which (a line taught
    // one product at a time, `sequence descending`, was packed
    // ascending); ascending is also what a block that wrote nothing gets,
    // so one product of such a block says nothing.
    let mut directions: Vec<&SequenceRule> = Vec::new();
    for (k, d) in demos.iter().enumerate() {
        let Some(rule) = directed.get(d.block.as_str()) else {
            continue;
        };
        let shown = d.sequence.len() > 1 && follows(rule, &inventories[k], &d.sequence);
        if (shown || *rule == SequenceRule::Descending) && !directions.contains(&rule) {
            directions.push(rule);
        }
    }
    if let [rule] = directions[..] {
        let rule = rule.clone();
        let exceptions = breaking(&rule);
        if explains_majority(demos.len() - exceptions.len(), demos.len()) {
            return Ok(Inferred {
                rule,
                exceptions,
                rivals: Vec::new(),
                guessed: Guessed::default(),
                leaning: None,
            });
        }
    }
    // Each candidate with the demonstrations that break it; the first
    // that fewest break is the rule.
    let scored: Vec<(SequenceRule, Vec<usize>)> = candidates
        .into_iter()
        .map(|rule| {
            let exceptions = breaking(&rule);
            (rule, exceptions)
        })
        .collect();
    let mut best = scored
        .iter()
        .min_by_key(|(_, exceptions)| exceptions.len())
        .map_or(
            Inferred {
                rule: SequenceRule::Ascending,
                exceptions: Vec::new(),
                rivals: Vec::new(),
                guessed: Guessed::default(),
                leaning: None,
            },
            |(rule, exceptions)| Inferred {
                rule: rule.clone(),
                exceptions: exceptions.clone(),
                rivals: Vec::new(),
                guessed: Guessed::default(),
                leaning: None,
            },
        );
    // The pairs of products the demonstrations put in an order.
    let pairs: BTreeSet<(&str, &str)> = votes
        .keys()
        .map(|&(a, b)| if a < b { (a, b) } else { (b, a) })
        .collect();
    if declared.is_empty() && pairs.len() < FEW_PAIRS {
        // The same votes with the ties the other way round, a rival only:
        // without it, two pairs in inventory order made the list the same
        // as `ascending`, and nothing was said, where the same two pairs
        // reversed were warned about.
        let mut reversed = names.clone();
        reversed.reverse();
        let listed_other = priority(reversed);
        let other = breaking(&listed_other);
        best.rivals = scored
            .iter()
            .cloned()
            .chain(std::iter::once((listed_other, other)))
            .filter(|(r, exceptions)| {
                *r != best.rule
                    && exceptions.len() == best.exceptions.len()
                    && inventories
                        .iter()
                        .any(|inv| r.chain(inv) != best.rule.chain(inv))
            })
            .map(|(r, _)| r)
            .fold(Vec::new(), |mut kept: Vec<SequenceRule>, r| {
                // One order under two names (descending, and the list
                // that reverses every inventory) is said once.
                let same =
                    |k: &SequenceRule| inventories.iter().all(|inv| k.chain(inv) == r.chain(inv));
                if !kept.iter().any(same) {
                    kept.push(r);
                }
                kept
            });
    }
    // What the rule orders that no demonstration does: every such pair
    // of a list read from them; of a direction, when they order fewer
    // than half of the pairs and nothing else fits as well (that is said
    // with the rivals).
    if declared.is_empty() {
        let listed = matches!(best.rule, SequenceRule::Listed(_));
        let order: Vec<String> = best
            .rule
            .chain(&names)
            .into_iter()
            .map(|i| names[i].to_owned())
            .collect();
        let g = guessed(&order, after);
        if listed || (best.rivals.is_empty() && 2 * g.ordered < g.pairs) {
            best.guessed = g;
        }
        if listed {
            best.leaning = leaning(demos, &names, &order, &votes, &scored);
        }
    }
    let agree = demos.len() - best.exceptions.len();
    if !explains_majority(agree, demos.len()) {
        // Numbered within its block, from 1 (a block's demonstrations
        // are numbered so in `train`'s other messages).
        let first = best.exceptions.first().map(|&k| {
            let within = demos[..k]
                .iter()
                .filter(|d| d.block == demos[k].block)
                .count()
                + 1;
            (within, demos[k].block.clone(), demos[k].sequence.clone())
        });
        return Err(PipelineError::ContradictorySequence(Box::new(
            Contradiction {
                best: best.rule,
                agree,
                demonstrations: demos.len(),
                first,
            },
        )));
    }
    Ok(best)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use packwright_interface::Node;

    fn graph(n: usize) -> Graph {
        Graph {
            nodes: (0..n)
                .map(|i| Node {
                    centre: [0.1 * i as f32, 0.5, 0.02],
                    height: 0.04,
                    selected: i % 2 == 0,
                    goal: [0.0, -0.5, 0.02],
                })
                .collect(),
            slots: vec![[0.0, -0.5, 0.0]],
            held_goal: [0.0; 3],
        }
    }

    /// A world of one inventory `inv` of cell `c` stocking `products`.
    fn one_inventory(products: &[&str]) -> WorldFile {
        use packwright_compiler::artifact::{At, InventoryRecord};
        WorldFile {
            schema: "test".into(),
            version: 0,
            cells: Vec::new(),
            products: Vec::new(),
            inventories: vec![InventoryRecord {
                name: "inv".into(),
                cell: "c".into(),
                products: products
                    .iter()
                    .map(|p| At {
                        product: p.to_string(),
                        at: [0.0; 3],
                    })
                    .collect(),
            }],
            orders: Vec::new(),
        }
    }

    /// A demonstration of a `sequence random` block is taught in the
    /// rule's order: ascending, descending or a priority list.
    #[test]
    fn a_demonstration_that_shows_any_order_is_taught_in_the_rules() {
        let world = one_inventory(&["a", "b", "c", "d"]);
        let demo = DemonstrationRecord {
            block: "shuffled".into(),
            cell: "c".into(),
            inventory: "inv".into(),
            assignment: Vec::new(),
            sequence: ["c", "a", "d"].map(String::from).to_vec(),
            human_packed: Vec::new(),
            missing: Vec::new(),
            start: Vec::new(),
            first_sample: 0,
            samples: 0,
        };
        let taught = |rule: SequenceRule| {
            let mut d = demo.clone();
            follow_rule(&world, &rule, &mut d);
            d.sequence
        };
        assert_eq!(taught(SequenceRule::Ascending), ["a", "c", "d"]);
        assert_eq!(taught(SequenceRule::Descending), ["d", "c", "a"]);
        let listed = SequenceRule::Listed(["d", "a"].map(String::from).to_vec());
        assert_eq!(taught(listed), ["d", "a", "c"]);
    }

    /// A `demos` block that moves one product per demonstration shows no
    /// order: `sequence descending` written on it is the rule (it was
    /// read as ascending, the inventory's order); one that wrote nothing
    /// (ascending by default) says nothing, and a hand-written
    /// demonstration of two products decides.
    #[test]
    fn a_direction_declared_on_single_product_demonstrations_is_the_rule() {
        let world = one_inventory(&["a", "b", "c"]);
        let demo = |block: &str, sequence: &[&str]| DemonstrationRecord {
            block: block.into(),
            cell: "c".into(),
            inventory: "inv".into(),
            assignment: Vec::new(),
            sequence: sequence.iter().map(|s| s.to_string()).collect(),
            human_packed: Vec::new(),
            missing: Vec::new(),
            start: Vec::new(),
            first_sample: 0,
            samples: 0,
        };
        let singles: Vec<DemonstrationRecord> =
            ["a", "b", "c"].iter().map(|p| demo("one", &[p])).collect();
        let rule = |demos: &[DemonstrationRecord], declared: SequenceRule| {
            let directed = BTreeMap::from([("one", declared)]);
            sequence_rule(&world, demos, &[], &directed)
                .map(|i| i.rule)
                .ok()
        };
        assert_eq!(
            rule(&singles, SequenceRule::Descending),
            Some(SequenceRule::Descending)
        );
        assert_eq!(
            rule(&singles, SequenceRule::Ascending),
            Some(SequenceRule::Ascending)
        );
        // With nothing written, a hand-written demonstration's order decides.
        let mut shown = singles.clone();
        shown.push(demo("by_hand", &["c", "a"]));
        shown.push(demo("by_hand", &["b", "a"]));
        assert_eq!(
            rule(&shown, SequenceRule::Ascending),
            Some(SequenceRule::Descending)
        );
    }

    /// A cell keeps its own rule where its demonstrations break the joint
    /// one, or where no other taught cell stocks its products; where
    /// cells share products the joint rule, taught from more
    /// demonstrations of them, is kept.
    #[test]
    fn a_cell_keeps_its_own_rule_unless_it_shares_products() {
        use packwright_compiler::artifact::{At, InventoryRecord};
        let inventory = |name: &str, cell: &str, products: &[&str]| InventoryRecord {
            name: name.into(),
            cell: cell.into(),
            products: products
                .iter()
                .map(|&p| At {
                    product: p.into(),
                    at: [0.0; 3],
                })
                .collect(),
        };
        let world = |right: &[&str]| WorldFile {
            schema: "test".into(),
            version: 0,
            cells: Vec::new(),
            products: Vec::new(),
            inventories: vec![
                inventory("la", "left", &["a1", "a2", "a3"]),
                inventory("rb", "right", right),
            ],
            orders: Vec::new(),
        };
        let cells = ["left", "right"].map(String::from);
        let apart = world(&["b1", "b2", "b3"]);
        assert!(own_rule(&apart, &cells, "right", false));
        assert!(own_rule(&apart, &cells, "left", false));
        let shared = world(&["b1", "a2", "b3"]);
        assert!(!own_rule(&shared, &cells, "right", false));
        assert!(own_rule(&shared, &cells, "right", true));
        // A cell taught alone has no other cell to share with.
        assert!(own_rule(&shared, &cells[..1], "left", false));
    }

    /// The products after the chosen one are left out, so that it is last
    /// along the chain; nothing for the box or a chosen last product.
    #[test]
    fn a_picking_decision_is_also_taught_without_the_later_products() {
        let g = graph(5);
        let Some(fewer) = without_later(&g, Some(2)) else {
            panic!("products after the chosen one");
        };
        assert_eq!(fewer.nodes, g.nodes[..3].to_vec());
        assert_eq!(
            (fewer.slots, fewer.held_goal),
            (g.slots.clone(), g.held_goal)
        );
        assert_eq!(without_later(&g, Some(4)), None);
        assert_eq!(without_later(&g, None), None);
    }

    /// Before the chosen product, the products outside the order become
    /// packed ones (selected, at their goal) and the packed ones products
    /// outside the order; the chosen one and those after it are as they
    /// were, and so is the rule's answer.
    #[test]
    fn a_picking_decision_is_also_taught_with_the_skipped_products_swapped() {
        let mut g = graph(5);
        // Node 0 packed: selected, at its goal.
        g.nodes[0].centre = g.nodes[0].goal;
        let Some(swapped) = with_skipped_swapped(&g, Some(2)) else {
            panic!("nodes before the chosen one");
        };
        assert_eq!(swapped.nodes[2..], g.nodes[2..]);
        let rows = packwright_nets::features::node_rows(&swapped);
        // (selected, place, out of its slot, held)
        assert_eq!((rows[0][0], rows[0][2]), (0.0, 0.0), "outside the order");
        assert_eq!(
            (rows[1][0], rows[1][2]),
            (1.0, 0.0),
            "selected, in its slot"
        );
        let before = packwright_nets::features::node_rows(&g);
        assert_eq!(rows[2..], before[2..]);
        assert_eq!(with_skipped_swapped(&g, Some(0)), None);
        assert_eq!(with_skipped_swapped(&g, None), None);
    }

    /// Hand-written demonstrations of [`rule_cell`], one per sequence
    /// (an order `oK` of its products into s1, s2, ... and the demo
    /// `oK_seen` in that sequence).
    fn by_hand(sequences: &[&[&str]]) -> String {
        sequences
            .iter()
            .enumerate()
            .map(|(k, sequence)| {
                let lines: Vec<String> = sequence
                    .iter()
                    .enumerate()
                    .map(|(i, p)| format!("{p} -> s{}", i + 1))
                    .collect();
                format!(
                    "order o{k} for inv {{ {} }}\ndemo o{k}_seen for o{k} {{ sequence {} }}\n",
                    lines.join("\n  "),
                    sequence.join(", ")
                )
            })
            .collect()
    }

    /// A generated block `d` of [`rule_cell`]: two of `choose` into s1
    /// and s2, in `sequence`.
    fn demos_block(choose: &str, sequence: &str) -> String {
        format!(
            "demos d for inv {{\n  choose 2 of {choose} into s1, s2\n  sequence {sequence}\n  seed 1\n}}"
        )
    }

    /// The rule of cell `c` in [`rule_cell`] with `tail`.
    fn rule_of(tail: &str) -> Result<Option<Inferred>> {
        cell_rule(&rule_cell(tail), "c")
    }

    /// The cell `c`, products and inventory of the rule tests below (six
    /// products listed p1..p6) and `tail` (blocks) after them, compiled.
    pub(crate) fn rule_cell(tail: &str) -> Compiled {
        use packwright_compiler::{Anywhere, MemoryLoader, check};
        let text = format!(
            "cell c {{
  robot ur10
  base (0, 0, 0)
  suction 100 mm
  pending (0.40, -0.40) to (0.80, 0.00)
  box b (0.00, 0.65) size (0.40, 0.30, 0.08)
  slot s1 (-0.12, 0.58)
  slot s2 ( 0.00, 0.58)
  slot s3 ( 0.12, 0.58)
}}
product p1 cube 50 mm
product p2 cube 50 mm
product p3 cube 50 mm
product p4 cube 50 mm
product p5 cube 50 mm
product p6 cube 50 mm
inventory inv for c {{
  p1 (0.45, -0.10)
  p2 (0.55, -0.10)
  p3 (0.65, -0.10)
  p4 (0.45, -0.25)
  p5 (0.55, -0.25)
  p6 (0.65, -0.25)
}}
{tail}"
        );
        let loader = MemoryLoader::new().with("rule.pack", text);
        check(&loader, &["rule.pack".into()], &Anywhere)
            .unwrap_or_else(|f| panic!("{}", f.render()))
    }

    /// One hand-written demonstration of two products, against the
    /// inventory's order: `descending` follows it, and so does the
    /// inventory order with those two swapped, which orders the products
    /// it does not show otherwise; both are said. Three pairs shown, or a
    /// declared direction, and the rule stands alone.
    #[test]
    fn a_rule_read_from_few_pairs_names_the_others_that_fit() {
        let list = |names: [&str; 6]| SequenceRule::Listed(names.map(String::from).to_vec());
        // One demonstration handling `a` then `b`.
        let pair = |a: &str, b: &str| {
            rule_of(&by_hand(&[&[a, b]]))
                .ok()
                .flatten()
                .expect("a rule")
        };
        let inferred = pair("p3", "p2");
        assert_eq!(inferred.rule, SequenceRule::Descending);
        assert_eq!(
            inferred.rivals,
            [list(["p1", "p3", "p2", "p4", "p5", "p6"])]
        );
        // The same pair in the inventory's order (helper P: said for
        // `descending`, not for `ascending`): the list with the products
        // it does not show the other way round fits as well.
        let inferred = pair("p2", "p3");
        assert_eq!(inferred.rule, SequenceRule::Ascending);
        assert_eq!(
            inferred.rivals,
            [list(["p6", "p5", "p4", "p2", "p3", "p1"])]
        );
        // A priority list read from two pairs (p2 before p1 and p3, which
        // neither direction follows): so does the list with the other
        // products the other way round.
        let first = by_hand(&[&["p2", "p1"], &["p2", "p3"]]);
        let inferred = rule_of(&first).ok().flatten().expect("a rule");
        assert_eq!(inferred.rule, list(["p2", "p1", "p3", "p4", "p5", "p6"]));
        assert_eq!(
            inferred.rivals,
            [list(["p6", "p5", "p4", "p2", "p3", "p1"])]
        );
        let three = by_hand(&[&["p3", "p2", "p1"]]);
        let inferred = rule_of(&three).ok().flatten().expect("a rule");
        assert_eq!(inferred.rule, SequenceRule::Descending);
        assert!(inferred.rivals.is_empty(), "{:?}", inferred.rivals);
        // A direction from 3 of 15 pairs (helper V: one demonstration of
        // three products, silent): the other 12 are said to be guessed.
        assert_eq!((inferred.guessed.ordered, inferred.guessed.pairs), (3, 15));
        assert_eq!(inferred.guessed.untaught.len(), 12);
        // Demonstrations that chain every product: nothing guessed.
        let chained = by_hand(&[&["p1", "p2", "p3"], &["p3", "p4", "p5"], &["p5", "p6"]]);
        let inferred = rule_of(&chained).ok().flatten().expect("a rule");
        assert_eq!(inferred.rule, SequenceRule::Ascending);
        assert_eq!(inferred.guessed, Guessed::default());
        let inferred = rule_of(&demos_block("p2, p3", "descending"))
            .ok()
            .flatten()
            .expect("a rule");
        assert_eq!(inferred.rule, SequenceRule::Descending);
        assert!(inferred.rivals.is_empty(), "{:?}", inferred.rivals);
    }

    /// Demonstrations of one product each order nothing for a model not
    /// taught the cell, as `sequence random` ones do (helper AB: they
    /// were said to follow ascending); `sequence descending` written on
    /// them is an order.
    #[test]
    fn single_product_demonstrations_order_a_cell_only_where_declared() {
        assert_eq!(rule_of(&by_hand(&[&["p1"], &["p3"]])).ok(), Some(None));
        let declared = "demos d for inv {\n  choose 1 of p1, p2, p3 into s1, s2\n  sequence descending\n  seed 1\n}";
        let inferred = rule_of(declared).ok().flatten().expect("a rule");
        assert_eq!(inferred.rule, SequenceRule::Descending);
        // Taught so (`train`): any order fits, and descending is said
        // once, not again as the list that reverses the inventory.
        let world = one_inventory(&["a", "b", "c"]);
        let singles: Vec<DemonstrationRecord> = ["a", "b", "c"]
            .iter()
            .map(|p| DemonstrationRecord {
                block: "one".into(),
                cell: "c".into(),
                inventory: "inv".into(),
                assignment: Vec::new(),
                sequence: vec![p.to_string()],
                human_packed: Vec::new(),
                missing: Vec::new(),
                start: Vec::new(),
                first_sample: 0,
                samples: 0,
            })
            .collect();
        let inferred = sequence_rule(&world, &singles, &[], &BTreeMap::new()).expect("a rule");
        assert_eq!(inferred.rule, SequenceRule::Ascending);
        assert_eq!(inferred.rivals, [SequenceRule::Descending]);
    }

    /// Five hand-written demonstrations, four in inventory order and one
    /// not (helper AA's: e before b): the priority list fits all five and
    /// is the rule, and through the fifth it orders two pairs no
    /// demonstration shows together against the inventory's order (c
    /// before b through c, e and e, b; e before d). Those are named with
    /// the demonstration they rest on; four demonstrations alone teach
    /// ascending, and nothing leans.
    #[test]
    fn a_list_that_one_demonstration_turns_from_a_direction_names_what_it_reorders() {
        let slip = by_hand(&[
            &["p1", "p3", "p5"],
            &["p2", "p4"],
            &["p3", "p6"],
            &["p1", "p4", "p6"],
            &["p5", "p2"],
        ]);
        let inferred = rule_of(&slip).ok().flatten().expect("a rule");
        let SequenceRule::Listed(list) = &inferred.rule else {
            panic!("{:?}", inferred.rule)
        };
        assert_eq!(list, &["p1", "p3", "p5", "p2", "p4", "p6"]);
        let leaning = inferred.leaning.expect("leans on one demonstration");
        assert_eq!(leaning.direction, SequenceRule::Ascending);
        assert_eq!((leaning.breaking, leaning.demonstrations), (1, 5));
        assert_eq!(
            (leaning.block.as_str(), &leaning.sequence[..]),
            ("o4_seen", &["p5".to_owned(), "p2".to_owned()][..])
        );
        assert_eq!(
            leaning.against,
            [("p3", "p2"), ("p5", "p4")].map(|(a, b)| (a.to_owned(), b.to_owned()))
        );
        let four = by_hand(&[
            &["p1", "p3", "p5"],
            &["p2", "p4"],
            &["p3", "p6"],
            &["p1", "p4", "p6"],
        ]);
        let inferred = rule_of(&four).ok().flatten().expect("a rule");
        assert_eq!(inferred.rule, SequenceRule::Ascending);
        assert_eq!(inferred.leaning, None);
    }

    /// A priority list read from hand-written demonstrations (helper V:
    /// one demonstration of p3, p1, p6 where the line packs by another
    /// list) orders the products no demonstration shows together by
    /// the inventory's order: those pairs are named, not passed off as
    /// taught. A pair ordered through a third product is taught.
    #[test]
    fn a_priority_list_read_from_demonstrations_names_the_pairs_it_guesses() {
        let pairs = |list: &[(&str, &str)]| -> Vec<(String, String)> {
            list.iter()
                .map(|&(a, b)| (a.to_owned(), b.to_owned()))
                .collect()
        };
        let one = by_hand(&[&["p3", "p1", "p6"]]);
        let inferred = rule_of(&one).ok().flatten().expect("a rule");
        let SequenceRule::Listed(list) = &inferred.rule else {
            panic!("{:?}", inferred.rule)
        };
        assert_eq!(list, &["p2", "p3", "p1", "p4", "p5", "p6"]);
        assert_eq!((inferred.guessed.ordered, inferred.guessed.pairs), (3, 15));
        assert_eq!(inferred.guessed.untaught.len(), 12);
        assert_eq!(
            inferred.guessed.untaught[..6],
            pairs(&[
                ("p2", "p3"),
                ("p2", "p1"),
                ("p2", "p4"),
                ("p2", "p5"),
                ("p2", "p6"),
                ("p3", "p4")
            ])
        );
        for taught in [("p3", "p1"), ("p1", "p6"), ("p3", "p6")] {
            assert!(!inferred.guessed.untaught.contains(&pairs(&[taught])[0]));
        }
        // p2 before p1 and p1 before p3 in two demonstrations: p2 before
        // p3 is taught through p1.
        let chained = by_hand(&[&["p2", "p1"], &["p1", "p3"]]);
        let inferred = rule_of(&chained).ok().flatten().expect("a rule");
        assert_eq!(inferred.guessed.ordered, 3);
        assert!(
            inferred
                .guessed
                .untaught
                .iter()
                .all(|(a, b)| ![a.as_str(), b.as_str()]
                    .iter()
                    .all(|n| ["p1", "p2", "p3"].contains(n))),
            "{:?}",
            inferred.guessed
        );
        // A declared list guesses nothing.
        let inferred = rule_of(&demos_block("p4, p2", "listed"))
            .ok()
            .flatten()
            .expect("a rule");
        assert!(
            matches!(inferred.rule, SequenceRule::Listed(_)),
            "{:?}",
            inferred.rule
        );
        assert_eq!(inferred.guessed, Guessed::default());
    }

    /// A generated block declares `sequence descending`, and one
    /// hand-written demonstration goes the other way. A priority list
    /// fits all seven (p3, p2, p1 from the block, then p4 before p6):
    /// it would order p5 and p6, which no demonstration shows against
    /// p1-p3, by the inventory, against the declared direction. The
    /// declared direction is the rule; the hand-written one breaks it.
    #[test]
    fn a_declared_direction_is_the_rule_where_most_demonstrations_follow_it() {
        let tail = "demos d for inv {
  choose 2 of p1, p2, p3 into s1, s2
  sequence descending
  seed 1
}
order o for inv {
  p4 -> s1
  p6 -> s2
}
demo o_seen for o { sequence p4, p6 }";
        let inferred = rule_of(tail).ok().flatten();
        let inferred = inferred.as_ref();
        assert_eq!(inferred.map(|i| &i.rule), Some(&SequenceRule::Descending));
        assert_eq!(inferred.map(|i| i.exceptions.len()), Some(1));
        // Without the declaration (the same demonstrations written by
        // hand), the list that explains every one is the rule.
        let by_hand = "order o1 for inv { p3 -> s1
  p2 -> s2 }
demo o1_seen for o1 { sequence p3, p2 }
order o2 for inv { p3 -> s1
  p1 -> s2 }
demo o2_seen for o2 { sequence p3, p1 }
order o3 for inv { p2 -> s1
  p1 -> s2 }
demo o3_seen for o3 { sequence p2, p1 }
order o4 for inv { p4 -> s1
  p6 -> s2 }
demo o4_seen for o4 { sequence p4, p6 }";
        let inferred = rule_of(by_hand).ok().flatten();
        assert!(
            matches!(
                inferred.as_ref().map(|i| &i.rule),
                Some(SequenceRule::Listed(_))
            ),
            "{:?}",
            inferred.map(|i| i.rule)
        );
    }
}
