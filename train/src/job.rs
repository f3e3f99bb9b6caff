//! A whole training run on a lesson (`packwright_pipeline::teach`): the
//! training set, the expert coach for DAgger, the three networks, and the
//! report saved as `metrics.json`.

use crate::relabel::{ExpertCoach, Recorded};
use crate::training::{Metrics, Network, NetworkMetrics, Progress, TrainError, figures_on, train};
use crate::{RoundMetrics, Trained};
use packwright_nets::TrainConfig;
use packwright_pipeline::PipelineError;
use packwright_pipeline::teach::{Lesson, ReplayProblem, Replayed};
use serde::Serialize;

/// `metrics.json` (schema `packwright.metrics/2`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TrainingReport {
    pub schema: &'static str,
    pub cells: Vec<String>,
    /// The sequence rule the demonstrations follow (the reasoner's chain).
    pub sequence: packwright_interface::SequenceRule,
    /// Taught with several cells: the cells that keep the rule their own
    /// demonstrations follow, and that rule.
    pub cell_rules: std::collections::BTreeMap<String, packwright_interface::SequenceRule>,
    pub demos: Vec<String>,
    pub demonstrations: usize,
    pub replayed: usize,
    /// Indices (among the chosen demonstrations) the expert could not
    /// replay.
    pub replay_failures: Vec<usize>,
    /// Why each failed replay (of a demonstration or a rehearsal) failed.
    pub replay_problems: Vec<ReplayProblem>,
    /// Demonstrations of blocks with `sequence random` (any order right):
    /// taught in the rule's order, and left out of its inference.
    pub any_order: usize,
    /// The expert's rehearsals of the products and slots no demonstration
    /// moved (motion examples only), and how many it completed.
    pub rehearsals: usize,
    pub rehearsed: usize,
    pub replay_s: f64,
    pub samples: Samples,
    pub training_s: f64,
    pub reasoner: NetworkMetrics,
    pub subgoal: NetworkMetrics,
    pub dynamics: NetworkMetrics,
    pub dagger: Vec<RoundMetrics>,
    /// What looks weak: held-out figures below the targets, networks
    /// still improving when training stopped.
    pub warnings: Vec<Weakness>,
}

/// Held-out reasoner accuracy below which `train` warns.
pub const MIN_REASONER_ACCURACY: f64 = 0.99;
/// Held-out mean sub-goal error (m) above which `train` warns.
pub const MAX_SUBGOAL_ERROR: f64 = 0.010;
/// The share of the demonstrated sub-goals the dynamics policy must reach
/// in its last DAgger pass, below which `train` warns.
pub const MIN_POLICY_REACHED: f64 = 0.9;

/// How many products' guessed pairs `train`'s message names (each with
/// the products the list puts after it).
const GROUPS_SHOWN: usize = 3;

/// "a", "a and b", "a, b and c".
fn and_list(items: &[&str]) -> String {
    match items {
        [] => String::new(),
        [one] => (*one).to_owned(),
        [rest @ .., last] => format!("{} and {last}", rest.join(", ")),
    }
}

/// A weakness of a trained model that `train` reports.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Weakness {
    /// Held-out reasoner accuracy below [`MIN_REASONER_ACCURACY`]; the
    /// weakest stage and its accuracy. `held_out` is false when nothing
    /// was held out: the figures are then on the training samples.
    Reasoner {
        held_out: bool,
        accuracy: f64,
        weakest: String,
        weakest_accuracy: f64,
    },
    /// Held-out mean sub-goal error above [`MAX_SUBGOAL_ERROR`]; the
    /// weakest stage and sub-goal and its error (`held_out` as for the
    /// reasoner).
    SubGoal {
        held_out: bool,
        error_m: f64,
        weakest: String,
        weakest_error_m: f64,
    },
    /// Too few samples to hold some out
    /// ([`crate::training::MIN_HELD_OUT`]): the network learned from all
    /// of them, and its figures are on them, not on unseen ones.
    NoneHeldOut { network: String, samples: usize },
    /// Still improving at the most epochs allowed.
    NotConverged { network: String, epochs: usize },
    /// A cell taught with others whose own demonstrations, read alone,
    /// follow another rule than the one the model takes for it: they
    /// share products with the other cells, whose demonstrations order
    /// them too, so the joint rule is kept.
    CellReadsOtherwise {
        cell: String,
        alone: packwright_interface::SequenceRule,
        taught: packwright_interface::SequenceRule,
    },
    /// The taught rule rests on fewer than
    /// [`FEW_PAIRS`](packwright_pipeline::teach::FEW_PAIRS) pairs of
    /// products shown in order: the `rivals` follow the demonstrations as
    /// well and order the products no demonstration shows together
    /// otherwise.
    RuleFromFewPairs {
        /// With several cells taught: the cell that keeps this rule of
        /// its own.
        cell: Option<String>,
        taught: packwright_interface::SequenceRule,
        rivals: Vec<packwright_interface::SequenceRule>,
    },
    /// A priority list read from demonstrations (none declared) that a
    /// direction explains but for a few, and that through those few
    /// orders products no demonstration shows together against it
    /// ([`packwright_pipeline::teach::Leaning`]).
    ListOverDirection {
        taught: packwright_interface::SequenceRule,
        direction: packwright_interface::SequenceRule,
        /// How many demonstrations break the direction, of how many.
        breaking: usize,
        demonstrations: usize,
        /// The first that breaks it: its block and sequence.
        block: String,
        sequence: Vec<String>,
        /// The pairs the list orders against the direction (first before
        /// second).
        against: Vec<(String, String)>,
    },
    /// A priority list read from demonstrations (none declared) that
    /// order only some of its pairs of products, the others standing in
    /// it as the inventory lists them; or a direction read from
    /// demonstrations that order fewer than half of them
    /// ([`packwright_pipeline::teach::Guessed`]).
    PairsGuessed {
        /// With several cells taught: the cell whose products these are.
        cell: Option<String>,
        taught: packwright_interface::SequenceRule,
        /// Pairs the demonstrations order, directly or through others.
        ordered: usize,
        /// Pairs of the list's products in all.
        pairs: usize,
        /// The pairs ordered so (first before second).
        untaught: Vec<(String, String)>,
    },
    /// The dynamics policy reaches fewer than [`MIN_POLICY_REACHED`] of
    /// the demonstrated sub-goals in its last DAgger pass: the learned
    /// planner will hand most motions to RRT-Connect.
    PolicyReachesFew { reached: usize, rollouts: usize },
    /// Demonstrations that break the taught sequence rule (their
    /// decisions were left out of the reasoner's examples).
    SequenceExceptions {
        exceptions: usize,
        demonstrations: usize,
        /// The first one's block and its sequence.
        block: String,
        sequence: Vec<String>,
    },
}

impl std::fmt::Display for Weakness {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Weakness::Reasoner {
                held_out,
                accuracy,
                weakest,
                weakest_accuracy,
            } => write!(
                f,
                "{} reasoner accuracy {accuracy:.3} is below {MIN_REASONER_ACCURACY} (weakest: {weakest} decisions, {weakest_accuracy:.3}); teach more demonstrations of that stage",
                figures_on(*held_out)
            ),
            Weakness::SubGoal {
                held_out,
                error_m,
                weakest,
                weakest_error_m,
            } => write!(
                f,
                "{} sub-goal error {:.1} mm is above {:.0} mm (weakest: {weakest} sub-goal, {:.1} mm)",
                figures_on(*held_out),
                error_m * 1000.0,
                MAX_SUBGOAL_ERROR * 1000.0,
                weakest_error_m * 1000.0
            ),
            Weakness::NoneHeldOut { network, samples } => write!(
                f,
                "the {network} network learned from all of its {samples} samples, too few to hold some out: its figures are on what it was taught; more demonstrations give a held-out measure"
            ),
            Weakness::NotConverged { network, epochs } => write!(
                f,
                "the {network} was still improving after {epochs} epochs; raise --epochs"
            ),
            Weakness::CellReadsOtherwise {
                cell,
                alone,
                taught,
            } => write!(
                f,
                "cell `{cell}`'s demonstrations alone follow the order {alone}; it shares products with the other cells taught, whose demonstrations order them too, so the model follows the order taught over all of them there, {taught}: train the cell on its own (`--demos`) to keep its order"
            ),
            Weakness::RuleFromFewPairs {
                cell,
                taught,
                rivals,
            } => write!(
                f,
                "{} put fewer than {} pairs of products in an order, and other orders follow them as well ({}): the model keeps {taught}. If the line packs otherwise, show it in a demonstration that orders products these disagree on, or declare it in a `demos` block (`sequence ascending`, `descending`, or `listed` with the `choose` list in priority order)",
                cell.as_ref()
                    .map_or("the demonstrations".to_owned(), |c| format!(
                        "cell `{c}` keeps a rule of its own, and its demonstrations"
                    )),
                packwright_pipeline::teach::FEW_PAIRS,
                rivals
                    .iter()
                    .map(ToString::to_string)
                    .collect::<Vec<_>>()
                    .join("; ")
            ),
            Weakness::ListOverDirection {
                taught,
                direction,
                breaking,
                demonstrations,
                block,
                sequence,
                against,
            } => {
                let pairs: Vec<String> = against
                    .iter()
                    .map(|(a, b)| format!("{a} before {b}"))
                    .collect();
                let pairs: Vec<&str> = pairs.iter().map(String::as_str).collect();
                let word = match direction {
                    packwright_interface::SequenceRule::Descending => "descending",
                    _ => "ascending",
                };
                write!(
                    f,
                    "the demonstrations follow {direction} but for {breaking} of {demonstrations} (the first, in block `{block}`, handles {}); the priority list the model keeps, {taught}, fits them all, and so orders {} against {word} order, though no demonstration shows those products together. If {} a slip, leave {} out (`train --demos` with the other blocks), or declare the order in a `demos` block (`sequence {word}`)",
                    sequence.join(", "),
                    and_list(&pairs),
                    if *breaking == 1 {
                        "that was"
                    } else {
                        "those were"
                    },
                    if *breaking == 1 { "it" } else { "them" },
                )
            }
            Weakness::PairsGuessed {
                cell,
                taught,
                ordered,
                pairs,
                untaught,
            } => {
                // Grouped by the product first: "a before b, c and d".
                let mut groups: Vec<(&str, Vec<&str>)> = Vec::new();
                for (a, b) in untaught {
                    match groups.last_mut() {
                        Some((first, seconds)) if first == a => seconds.push(b),
                        _ => groups.push((a, vec![b])),
                    }
                }
                // One group more rather than "and 1 more pair".
                let shown_groups = match groups.get(GROUPS_SHOWN..) {
                    Some([(_, last)]) if last.len() == 1 => GROUPS_SHOWN + 1,
                    _ => GROUPS_SHOWN,
                };
                let shown: Vec<String> = groups
                    .iter()
                    .take(shown_groups)
                    .map(|(a, seconds)| format!("{a} before {}", and_list(seconds)))
                    .collect();
                let more: usize = groups.iter().skip(shown_groups).map(|g| g.1.len()).sum();
                let (kept, how, declare) = match taught {
                    packwright_interface::SequenceRule::Listed(_) => (
                        "in the priority list the model keeps",
                        "as the inventory lists them, where the taught pairs allow,",
                        "the whole list in a `demos` block (`sequence listed`, the `choose` list in priority order)",
                    ),
                    _ => (
                        "in the order the model keeps",
                        "by that order too,",
                        "the order in a `demos` block (`sequence ascending`, `descending`, or `listed` with the `choose` list in priority order)",
                    ),
                };
                write!(
                    f,
                    "{}the demonstrations order {ordered} of the {pairs} pairs of products {kept}, {taught}. The model orders the other {} {how} and no demonstration showed them: {}{}. If the line packs them otherwise, show those products together in a demonstration, or declare {declare}",
                    cell.as_ref()
                        .map_or(String::new(), |c| format!("cell `{c}`: ")),
                    untaught.len(),
                    shown.join("; "),
                    if more > 0 {
                        format!("; and {more} more pair{}", if more == 1 { "" } else { "s" })
                    } else {
                        String::new()
                    }
                )
            }
            Weakness::PolicyReachesFew { reached, rollouts } => write!(
                f,
                "the dynamics policy reaches only {reached} of {rollouts} demonstrated sub-goals in {} steps: the learned planner will hand most motions to RRT-Connect. Its steps turn the base, shoulder and elbow and keep the cup down with wrist 1, as a UR arm's wrist does; on an arm whose wrist cannot (another kind of arm), no model can, and the expert or `--planner rrt` is the planner to use; on a UR arm, teach more demonstrations or raise --dagger-rounds",
                packwright_motion::execute::MAX_POLICY_STEPS
            ),
            Weakness::SequenceExceptions {
                exceptions,
                demonstrations,
                block,
                sequence,
            } => write!(
                f,
                "{exceptions} of {demonstrations} demonstrations break the taught sequence rule (the first, in block `{block}`, handles {}); their decisions were not taught",
                sequence.join(", ")
            ),
        }
    }
}

impl Weakness {
    /// [`Weakness::PairsGuessed`] for the rule `taught` (of `cell`, with
    /// several cells taught) and what it `guessed`.
    fn pairs_guessed(
        cell: Option<&str>,
        taught: &packwright_interface::SequenceRule,
        guessed: &packwright_pipeline::teach::Guessed,
    ) -> Weakness {
        Weakness::PairsGuessed {
            cell: cell.map(str::to_owned),
            taught: taught.clone(),
            ordered: guessed.ordered,
            pairs: guessed.pairs,
            untaught: guessed.untaught.clone(),
        }
    }
}

/// [`Weakness::PolicyReachesFew`] when the last DAgger pass reached fewer
/// than [`MIN_POLICY_REACHED`] of its sub-goals.
pub fn policy_weakness(dagger: &[crate::dagger::RoundMetrics]) -> Option<Weakness> {
    let last = dagger.last()?;
    (last.rollouts > 0 && (last.reached as f64) < MIN_POLICY_REACHED * last.rollouts as f64)
        .then_some(Weakness::PolicyReachesFew {
            reached: last.reached,
            rollouts: last.rollouts,
        })
}

/// The weaknesses of a training run's metrics.
pub fn weaknesses(metrics: &[(Network, &NetworkMetrics)], dagger_rounds: usize) -> Vec<Weakness> {
    let mut out = Vec::new();
    for &(network, m) in metrics {
        let worst = |higher_is_better: bool| {
            m.parts
                .iter()
                .max_by(|a, b| {
                    let o = a.1.total_cmp(b.1);
                    if higher_is_better { o.reverse() } else { o }
                })
                .map(|(k, v)| (k.clone(), *v))
                .unwrap_or_default()
        };
        if !m.held_out() {
            out.push(Weakness::NoneHeldOut {
                network: network.to_string(),
                samples: m.train_samples,
            });
        }
        match network {
            Network::Reasoner if m.valid_metric < MIN_REASONER_ACCURACY => {
                let (weakest, weakest_accuracy) = worst(true);
                out.push(Weakness::Reasoner {
                    held_out: m.held_out(),
                    accuracy: m.valid_metric,
                    weakest,
                    weakest_accuracy,
                });
            }
            Network::SubGoal if m.valid_metric > MAX_SUBGOAL_ERROR => {
                let (weakest, weakest_error_m) = worst(false);
                out.push(Weakness::SubGoal {
                    held_out: m.held_out(),
                    error_m: m.valid_metric,
                    weakest,
                    weakest_error_m,
                });
            }
            _ => {}
        }
        // The dynamics policy's figures are its last DAgger round's, a
        // short fine-tuning on a growing set: not a convergence measure.
        let fine_tuned = network == Network::Dynamics && dagger_rounds > 0;
        // A reasoner right on every held-out decision whose loss still
        // falls is only sharpening its margins: more epochs change no
        // decision, so "raise --epochs" would mislead.
        let perfect = network == Network::Reasoner && m.valid_metric >= 1.0;
        if !m.converged && !fine_tuned && !perfect {
            out.push(Weakness::NotConverged {
                network: network.to_string(),
                epochs: m.epochs_run,
            });
        }
    }
    out
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Samples {
    pub graphs: usize,
    pub subgoals: usize,
    pub actions: usize,
}

#[derive(Debug, thiserror::Error)]
pub enum JobError {
    #[error(transparent)]
    Pipeline(#[from] PipelineError),
    #[error(transparent)]
    Train(#[from] TrainError),
}

/// Trains on `lesson` with its `replayed` demonstrations; DAgger's coach is
/// the expert on the lesson's arm and cell.
pub fn run(
    lesson: &Lesson,
    replayed: &Replayed,
    config: &TrainConfig,
    progress: &(dyn Fn(Progress) + Sync),
) -> Result<(Trained, TrainingReport), JobError> {
    let set = lesson.training_set(replayed)?;
    let episodes = lesson.episodes()?;
    let rehearsals = lesson.rehearsal_episodes()?;
    let recorded: Vec<Recorded> = episodes
        .iter()
        .zip(&replayed.logs)
        .chain(rehearsals.iter().zip(&replayed.rehearsed))
        .filter_map(|(ep, log)| {
            log.as_ref().map(|log| Recorded {
                log,
                arm: &ep.arm,
                base: ep.task.cell.base,
                suction: ep.task.cell.suction,
            })
        })
        .collect();
    // Each demonstration is rolled out with its own cell's arm.
    let coach = ExpertCoach::new(&recorded);
    let (mut trained, metrics) = train(&set, config, Some(&coach), progress)?;
    trained.set_task(lesson.task());
    let Metrics {
        reasoner,
        subgoal,
        dynamics,
        dagger,
        seconds,
    } = metrics;
    let failures = replayed.failures();
    let mut warnings = weaknesses(
        &[
            (Network::Reasoner, &reasoner),
            (Network::SubGoal, &subgoal),
            (Network::Dynamics, &dynamics),
        ],
        config.dagger_rounds,
    );
    warnings.extend(policy_weakness(&dagger));
    for (cell, alone) in &lesson.read_otherwise {
        warnings.push(Weakness::CellReadsOtherwise {
            cell: cell.clone(),
            alone: alone.clone(),
            taught: lesson.sequence.clone(),
        });
    }
    // A list read from few pairs is said once, with its rivals.
    for (cell, rivals) in &lesson.cell_rivals {
        warnings.push(Weakness::RuleFromFewPairs {
            cell: Some(cell.clone()),
            taught: lesson.rule_for(cell).clone(),
            rivals: rivals.clone(),
        });
    }
    if !lesson.rivals.is_empty() {
        warnings.push(Weakness::RuleFromFewPairs {
            cell: None,
            taught: lesson.sequence.clone(),
            rivals: lesson.rivals.clone(),
        });
    } else if !lesson.guessed.untaught.is_empty() {
        warnings.push(Weakness::pairs_guessed(
            None,
            &lesson.sequence,
            &lesson.guessed,
        ));
    }
    if let Some(l) = &lesson.leaning {
        warnings.push(Weakness::ListOverDirection {
            taught: lesson.sequence.clone(),
            direction: l.direction.clone(),
            breaking: l.breaking,
            demonstrations: l.demonstrations,
            block: l.block.clone(),
            sequence: l.sequence.clone(),
            against: l.against.clone(),
        });
    }
    for (cell, g) in &lesson.cell_guessed {
        warnings.push(Weakness::pairs_guessed(
            Some(cell),
            lesson.rule_for(cell),
            g,
        ));
    }
    if let Some(&first) = lesson.exceptions.first() {
        let d = &lesson.chosen[first];
        warnings.insert(
            0,
            Weakness::SequenceExceptions {
                exceptions: lesson.exceptions.len(),
                demonstrations: lesson.chosen.len(),
                block: d.block.clone(),
                sequence: d.sequence.clone(),
            },
        );
    }
    let report = TrainingReport {
        schema: "packwright.metrics/2",
        cells: lesson.cells.clone(),
        sequence: lesson.sequence.clone(),
        cell_rules: lesson.cell_rules.clone(),
        demos: lesson.blocks.clone(),
        demonstrations: lesson.chosen.len(),
        replayed: lesson.chosen.len() - failures.len(),
        replay_failures: failures,
        replay_problems: replayed.problems.clone(),
        any_order: lesson.any_order.len(),
        rehearsals: lesson.rehearsals.len(),
        rehearsed: replayed.rehearsals_completed(),
        replay_s: replayed.seconds,
        samples: Samples {
            graphs: set.graphs.len(),
            subgoals: set.subgoals.len(),
            actions: set.actions.len(),
        },
        training_s: seconds,
        reasoner,
        subgoal,
        dynamics,
        dagger,
        warnings,
    };
    Ok((trained, report))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    /// The policy reaching fewer than nine in ten of its sub-goals in the
    /// last DAgger pass is said (a non-UR arm reached 0 of 18 silently);
    /// the passes before do not count.
    #[test]
    fn a_policy_that_reaches_few_sub_goals_is_said() {
        let round = |round, reached| crate::dagger::RoundMetrics {
            round,
            rollouts: 100,
            reached,
            added: 0,
            seconds: 0.0,
        };
        assert_eq!(
            policy_weakness(&[round(0, 95), round(1, 12)]),
            Some(Weakness::PolicyReachesFew {
                reached: 12,
                rollouts: 100
            })
        );
        assert_eq!(policy_weakness(&[round(0, 10), round(1, 90)]), None);
        assert_eq!(policy_weakness(&[]), None);
        let w = policy_weakness(&[round(0, 0)]).expect("a weakness");
        assert!(w.to_string().contains("reaches only 0 of 100"), "{w}");
    }

    fn metrics(valid_metric: f64, converged: bool) -> NetworkMetrics {
        NetworkMetrics {
            train_samples: 100,
            valid_samples: 20,
            epochs_run: 600,
            best_epoch: 600,
            train_loss: 0.01,
            valid_loss: 0.01,
            valid_metric,
            metric: "held-out".to_owned(),
            parts: BTreeMap::from([("picking".to_owned(), valid_metric)]),
            converged,
            seconds: 1.0,
        }
    }

    /// A reasoner still improving at its epoch limit is reported unless it
    /// is already right on every held-out decision; the sub-goal planner
    /// always is, the dynamics policy only without DAgger.
    #[test]
    fn not_converged_is_reported_where_more_epochs_could_help() {
        let (perfect, weak) = (metrics(1.0, false), metrics(0.995, false));
        let subgoal = metrics(0.002, false);
        let dynamics = metrics(0.05, false);
        let found = weaknesses(
            &[
                (Network::Reasoner, &perfect),
                (Network::SubGoal, &subgoal),
                (Network::Dynamics, &dynamics),
            ],
            2,
        );
        assert_eq!(
            found,
            vec![Weakness::NotConverged {
                network: Network::SubGoal.to_string(),
                epochs: 600,
            }]
        );
        let found = weaknesses(
            &[(Network::Reasoner, &weak), (Network::Dynamics, &dynamics)],
            0,
        );
        let networks: Vec<String> = found
            .iter()
            .filter_map(|w| match w {
                Weakness::NotConverged { network, .. } => Some(network.clone()),
                _ => None,
            })
            .collect();
        assert_eq!(
            networks,
            vec![Network::Reasoner.to_string(), Network::Dynamics.to_string()]
        );
    }

    /// A network that held nothing out says so, with its sample count.
    #[test]
    fn figures_on_the_training_samples_are_reported() {
        let all = NetworkMetrics {
            train_samples: 12,
            valid_samples: 0,
            ..metrics(0.002, true)
        };
        let found = weaknesses(&[(Network::SubGoal, &all)], 2);
        assert_eq!(
            found,
            vec![Weakness::NoneHeldOut {
                network: Network::SubGoal.to_string(),
                samples: 12,
            }]
        );
        assert!(
            found[0]
                .to_string()
                .starts_with("the sub-goal network learned from all of its 12 samples")
        );
        // A weak figure on training samples is not called held-out.
        let weak = NetworkMetrics {
            valid_samples: 0,
            ..metrics(0.5, true)
        };
        let found = weaknesses(&[(Network::Reasoner, &weak)], 2);
        assert!(
            matches!(
                found[1],
                Weakness::Reasoner {
                    held_out: false,
                    ..
                }
            ),
            "{found:?}"
        );
        assert!(
            found[1]
                .to_string()
                .starts_with("training reasoner accuracy 0.500"),
            "{}",
            found[1]
        );
        let found = weaknesses(&[(Network::Reasoner, &metrics(0.5, true))], 2);
        assert!(
            found[0]
                .to_string()
                .starts_with("held-out reasoner accuracy")
        );
    }

    /// A guessed priority list's message groups the pairs by the product
    /// first and names how many it leaves out (a single one it names).
    #[test]
    fn a_guessed_list_says_which_pairs_stand_by_inventory_position() {
        let list = |names: &[&str]| {
            packwright_interface::SequenceRule::Listed(
                names.iter().map(|n| (*n).to_owned()).collect(),
            )
        };
        let pair = |a: &str, b: &str| (a.to_owned(), b.to_owned());
        let w = Weakness::PairsGuessed {
            cell: None,
            taught: list(&["a", "b", "c", "d", "e", "f"]),
            ordered: 9,
            pairs: 15,
            untaught: vec![
                pair("a", "b"),
                pair("a", "c"),
                pair("b", "d"),
                pair("c", "d"),
                pair("c", "e"),
                pair("d", "f"),
            ],
        };
        let text = w.to_string();
        assert!(text.contains("order 9 of the 15 pairs"), "{text}");
        assert!(
            text.contains("in the priority list the model keeps"),
            "{text}"
        );
        assert!(
            text.contains("the other 6 as the inventory lists them"),
            "{text}"
        );
        // The one pair past the groups shown is named (helper AB: "and 1
        // more pair" took as long to read).
        assert!(
            text.contains(": a before b and c; b before d; c before d and e; d before f."),
            "{text}"
        );
        let Weakness::PairsGuessed {
            cell,
            taught,
            ordered,
            pairs,
            mut untaught,
        } = w
        else {
            unreachable!()
        };
        untaught.push(pair("e", "f"));
        let text = Weakness::PairsGuessed {
            cell,
            taught,
            ordered,
            pairs,
            untaught,
        }
        .to_string();
        assert!(
            text.contains(": a before b and c; b before d; c before d and e; and 2 more pairs."),
            "{text}"
        );
    }

    /// A direction read from few pairs says it orders the rest too.
    #[test]
    fn a_guessed_direction_says_the_rest_follow_it() {
        let w = Weakness::PairsGuessed {
            cell: Some("right".to_owned()),
            taught: packwright_interface::SequenceRule::Ascending,
            ordered: 3,
            pairs: 28,
            untaught: vec![("a".to_owned(), "b".to_owned())],
        };
        let text = w.to_string();
        assert!(
            text.contains("in the order the model keeps, ascending"),
            "{text}"
        );
        assert!(text.contains("by that order too"), "{text}");
        assert!(
            text.contains("`sequence ascending`, `descending`"),
            "{text}"
        );
    }
}
