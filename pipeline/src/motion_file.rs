//! `motion.safetensors`, the motion demonstrations `packwright demonstrate`
//! writes: every replayed demonstration's sub-goals and actions in one log.

use packwright_interface::outcome::Stage;
use packwright_interface::record::MotionLog;
use safetensors::SafeTensorError;
use safetensors::tensor::{Dtype, TensorView};
use std::collections::HashMap;

/// One log of all `logs` (per demonstration, `None` if it could not be
/// replayed): the merged log, each sub-goal's demonstration index, and the
/// indices of the failed ones.
pub fn merge(logs: Vec<Option<MotionLog>>) -> (MotionLog, Vec<i64>, Vec<usize>) {
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
    (log, demo_of, failed)
}

fn f32s<const N: usize>(rows: impl Iterator<Item = [f64; N]>) -> Vec<u8> {
    rows.flat_map(|r| r.map(|v| v as f32))
        .flat_map(f32::to_le_bytes)
        .collect()
}

/// `motion.safetensors`: the motion-demonstration tensors (names, dtypes
/// and shapes documented in the README), `demo_of` giving each sub-goal's
/// demonstration.
pub fn motion_file(log: &MotionLog, demo_of: &[i64]) -> Result<Vec<u8>, SafeTensorError> {
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
    safetensors::serialize(views, Some(metadata))
}
