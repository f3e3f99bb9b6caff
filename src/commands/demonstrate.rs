//! `packwright demonstrate`: record the expert's motion demonstrations.

use crate::Exit;
use crate::cli::DemonstrateArgs;
use crate::fsio::write_file_atomically;
use anyhow::bail;
use packwright_pipeline::artifacts::CompiledDir;
use packwright_pipeline::motion_file::{merge, motion_file};
use packwright_pipeline::replay::replay_all;
use std::sync::atomic::{AtomicUsize, Ordering};

pub fn run(args: &DemonstrateArgs) -> anyhow::Result<Exit> {
    let compiled = CompiledDir::read_whole(&args.dir)?;
    let (demonstrations, world) = (compiled.demonstrations(), compiled.world());
    if demonstrations.is_empty() {
        bail!(
            "{} holds no demonstrations: compile files with `demo` or `demos` blocks",
            args.dir.display()
        );
    }
    let total = demonstrations.len();
    let terminal = std::io::IsTerminal::is_terminal(&std::io::stderr());
    let done = AtomicUsize::new(0);
    let demos: Vec<_> = demonstrations.iter().collect();
    let logs = replay_all(world, &demos, &|| {
        let n = done.fetch_add(1, Ordering::Relaxed) + 1;
        if !args.json && (n.is_multiple_of(10) || n == total) {
            // One line rewritten on a terminal; a line each in a file.
            if terminal {
                err!("\rrecorded {n}/{total} demonstrations");
            } else {
                errln!("recorded {n}/{total} demonstrations");
            }
        }
    })?;
    if !args.json && terminal {
        errln!();
    }
    let mut problems = Vec::new();
    let logs = logs
        .into_iter()
        .enumerate()
        .map(|(i, replay)| {
            replay
                .map_err(|why| {
                    // Numbered from 1, as `train` numbers them: the line
                    // of demonstrations.jsonl.
                    problems.push(format!(
                        "demonstration {} ({}; line {} of demonstrations.jsonl): {why}",
                        i + 1,
                        demos[i].block,
                        i + 1
                    ))
                })
                .ok()
        })
        .collect();
    let (log, demo_of, failed) = merge(logs);
    if !args.json {
        for p in &problems {
            errln!("error: the expert could not replay {p}");
        }
    }
    write_file_atomically(&args.output, &motion_file(&log, &demo_of)?)?;
    if args.json {
        outln!(
            "{}",
            serde_json::json!({
                "output": args.output.display().to_string(),
                "demonstrations": total,
                "failed": failed,
                "problems": problems,
                "subgoals": log.subgoals.len(),
                "actions": log.actions.len(),
            })
        );
    } else {
        outln!(
            "wrote {}: {} of {total} demonstrations, {} sub-goals, {} action samples",
            args.output.display(),
            total - failed.len(),
            log.subgoals.len(),
            log.actions.len()
        );
        if !failed.is_empty() {
            let lines: Vec<usize> = failed.iter().map(|i| i + 1).collect();
            outln!("could not replay demonstrations {lines:?} (lines of demonstrations.jsonl)");
        }
    }
    Ok(if failed.is_empty() {
        Exit::Success
    } else {
        Exit::Diagnostics
    })
}
