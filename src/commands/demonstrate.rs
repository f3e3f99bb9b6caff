//! `packwright demonstrate`: record the expert's motion demonstrations.

use crate::Exit;
use crate::cli::DemonstrateArgs;
use crate::fsio::write_file_atomically;
use anyhow::bail;
use packwright_compiler::artifact::{Manifest, WorldFile};
use packwright_interface::outcome::Stage;
use packwright_interface::record::MotionLog;
use packwright_pipeline::artifacts::read_json;
use packwright_pipeline::replay::replay_all;
use safetensors::tensor::{Dtype, TensorView};
use std::collections::HashMap;
use std::sync::atomic::{AtomicUsize, Ordering};

fn f32s<const N: usize>(rows: impl Iterator<Item = [f64; N]>) -> Vec<u8> {
    rows.flat_map(|r| r.map(|v| v as f32))
        .flat_map(f32::to_le_bytes)
        .collect()
}

/// The motion-demonstration tensors (names documented in the README).
fn tensors(log: &MotionLog, demo_of: &[i64]) -> anyhow::Result<Vec<u8>> {
    let (n, k) = (log.subgoals.len(), log.actions.len());
    let s = &log.subgoals;
    let a = &log.actions;
    let data: Vec<(&str, Dtype, Vec<usize>, Vec<u8>)> = vec![
        (
            "subgoal_feature",
            Dtype::F32,
            vec![n, 3],
            f32s(s.iter().map(|x| x.feature)),
        ),
        (
            "subgoal_tool",
            Dtype::F32,
            vec![n, 3],
            f32s(s.iter().map(|x| x.tool)),
        ),
        (
            "subgoal_target",
            Dtype::F32,
            vec![n, 3],
            f32s(s.iter().map(|x| x.target)),
        ),
        (
            "subgoal_label",
            Dtype::I64,
            vec![n],
            s.iter()
                .flat_map(|x| i64::from(x.label).to_le_bytes())
                .collect(),
        ),
        (
            "subgoal_stage",
            Dtype::U8,
            vec![n],
            s.iter()
                .map(|x| match x.stage {
                    Stage::Picking => 0,
                    Stage::Placing => 1,
                })
                .collect(),
        ),
        (
            "subgoal_index",
            Dtype::U8,
            vec![n],
            s.iter().map(|x| x.index).collect(),
        ),
        (
            "subgoal_start_joints",
            Dtype::F32,
            vec![n, 6],
            f32s(s.iter().map(|x| x.start)),
        ),
        (
            "subgoal_goal_joints",
            Dtype::F32,
            vec![n, 6],
            f32s(s.iter().map(|x| x.goal)),
        ),
        (
            "subgoal_demo",
            Dtype::I64,
            vec![n],
            demo_of.iter().flat_map(|d| d.to_le_bytes()).collect(),
        ),
        (
            "action_delta",
            Dtype::F32,
            vec![k, 3],
            f32s(a.iter().map(|x| x.delta)),
        ),
        (
            "action_joints",
            Dtype::F32,
            vec![k, 3],
            f32s(a.iter().map(|x| x.action)),
        ),
        (
            "action_state",
            Dtype::F32,
            vec![k, 3],
            f32s(a.iter().map(|x| x.joints)),
        ),
        (
            "action_subgoal",
            Dtype::I64,
            vec![k],
            a.iter()
                .flat_map(|x| (x.subgoal as i64).to_le_bytes())
                .collect(),
        ),
    ];
    let views = data
        .iter()
        .map(|(name, dtype, shape, bytes)| {
            TensorView::new(*dtype, shape.clone(), bytes).map(|v| (*name, v))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let metadata = HashMap::from([("schema".to_owned(), "packwright.motion/1".to_owned())]);
    Ok(safetensors::serialize(views, Some(metadata))?)
}

pub fn run(args: &DemonstrateArgs) -> anyhow::Result<Exit> {
    let manifest: Manifest = read_json(&args.dir.join("manifest.json"))?;
    let world: WorldFile = read_json(&args.dir.join("orders.json"))?;
    if manifest.demonstrations.is_empty() {
        bail!(
            "{} holds no demonstrations: compile files with `demo` or `demos` blocks",
            args.dir.display()
        );
    }
    let total = manifest.demonstrations.len();
    let done = AtomicUsize::new(0);
    let demos: Vec<_> = manifest.demonstrations.iter().collect();
    let logs = replay_all(&world, &demos, &|| {
        let n = done.fetch_add(1, Ordering::Relaxed) + 1;
        if !args.json && (n.is_multiple_of(10) || n == total) {
            err!("\rrecorded {n}/{total} demonstrations");
        }
    })?;
    if !args.json {
        errln!();
    }
    let mut log = MotionLog::default();
    let mut demo_of: Vec<i64> = Vec::new();
    let mut failed = Vec::new();
    for (i, one) in logs.into_iter().enumerate() {
        let Some(one) = one else {
            failed.push(i);
            continue;
        };
        let offset = log.subgoals.len();
        demo_of.extend(std::iter::repeat_n(i as i64, one.subgoals.len()));
        log.subgoals.extend(one.subgoals);
        log.actions.extend(one.actions.into_iter().map(|mut a| {
            a.subgoal += offset;
            a
        }));
    }
    write_file_atomically(&args.output, &tensors(&log, &demo_of)?)?;
    if args.json {
        outln!(
            "{}",
            serde_json::json!({
                "output": args.output.display().to_string(),
                "demonstrations": total,
                "failed": failed,
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
            outln!("could not replay demonstrations {failed:?} (indices into manifest.json)");
        }
    }
    Ok(if failed.is_empty() {
        Exit::Success
    } else {
        Exit::Diagnostics
    })
}
