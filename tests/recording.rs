//! Rerun recordings (`execute --record`, `eval --record`). With the
//! `rerun` feature: the written `.rrd` files are read back with Rerun's
//! own decoder (`re_log_encoding`, chunks from `re_chunk`) and their
//! entity paths and time steps checked. Without it: `--record` is refused
//! with exit 2 and the way to rebuild.

mod common;

use common::{packwright, scratch};

#[cfg(feature = "rerun")]
mod with_rerun {
    use super::{packwright, scratch};
    use packwright_recording::rerun::external::re_log_encoding::DecoderApp;
    use packwright_recording::rerun::log::{Chunk, LogMsg};
    use packwright_recording::rerun::{StoreKind, TimelineName};
    use packwright_recording::{FRAME_PERIOD, paths};
    use std::collections::{BTreeMap, BTreeSet};
    use std::io::BufReader;
    use std::path::Path;

    /// What one recording of a file holds, per entity path (without the
    /// leading `/`).
    #[derive(Default)]
    struct Recording {
        /// Entities with static data.
        statics: BTreeSet<String>,
        /// The distinct `sim_time` steps of each entity with temporal data
        /// (nanoseconds).
        steps: BTreeMap<String, BTreeSet<i64>>,
        /// Rows logged on the timeline, per entity.
        rows: BTreeMap<String, usize>,
        /// Every timeline of the temporal data.
        timelines: BTreeSet<String>,
    }

    impl Recording {
        fn has(&self, path: &str) -> bool {
            self.statics.contains(path) || self.steps.contains_key(path)
        }

        fn steps(&self, path: &str) -> usize {
            self.steps.get(path).map_or(0, BTreeSet::len)
        }

        fn rows(&self, path: &str) -> usize {
            self.rows.get(path).copied().unwrap_or(0)
        }
    }

    /// Decodes `file` with Rerun's decoder: its recordings (blueprints
    /// aside), by recording id.
    fn decode(file: &Path) -> BTreeMap<String, Recording> {
        let reader = BufReader::new(std::fs::File::open(file).expect("the .rrd file"));
        let timeline = TimelineName::from_static_str(paths::TIMELINE);
        let mut recordings: BTreeMap<String, Recording> = BTreeMap::new();
        for msg in DecoderApp::decode_lazy(reader) {
            let msg = msg.expect("a valid .rrd message");
            let LogMsg::ArrowMsg(store, arrow) = msg else {
                continue;
            };
            if store.kind() != StoreKind::Recording {
                continue;
            }
            let chunk = Chunk::from_arrow_msg(&arrow).expect("a valid chunk");
            let path = chunk
                .entity_path()
                .to_string()
                .trim_start_matches('/')
                .to_owned();
            let r = recordings
                .entry(store.recording_id().to_string())
                .or_default();
            r.timelines
                .extend(chunk.timelines().keys().map(|t| t.to_string()));
            if chunk.is_static() {
                r.statics.insert(path);
            } else if let Some(times) = chunk.timelines().get(&timeline) {
                r.steps
                    .entry(path.clone())
                    .or_default()
                    .extend(times.times_raw());
                *r.rows.entry(path).or_default() += chunk.num_rows();
            }
        }
        recordings
    }

    /// The frames a run of `time_s` simulated seconds is recorded at: the
    /// start, every [`FRAME_PERIOD`], and the last control cycle.
    fn frames(time_s: f64) -> usize {
        let cycles = (time_s / 0.002).round() as usize;
        let every = (FRAME_PERIOD / 0.002).round() as usize;
        1 + cycles.div_ceil(every)
    }

    /// The learned planner packs deli_crate (4 products of 5, on line2,
    /// which the bundled model was taught): every entity is in the file,
    /// the arm and the joint plots have one step per frame up to the end
    /// of the run, and the events and decisions are all there.
    #[test]
    fn execute_records_a_run_that_rerun_reads_back() {
        let dir = scratch("recording", "execute");
        let file = dir.join("deli.rrd");
        let o = packwright(&[
            "execute",
            "orders/customers/hampton_deli.pack",
            "--order",
            "deli_crate",
            "--json",
            "--record",
            file.to_str().expect("UTF-8 path"),
        ]);
        assert_eq!(
            o.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
        let report: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON report");
        assert_eq!(report["planner"], "learned");
        assert_eq!(report["complete"], true);
        let time_s = report["time_s"].as_f64().expect("time_s");

        let recordings = decode(&file);
        assert_eq!(recordings.len(), 1, "one recording");
        let r = recordings.values().next().expect("a recording");

        let mut expected: Vec<String> = vec![
            paths::WORLD.into(),
            paths::CUP.into(),
            paths::PENDING.into(),
            paths::TOOL_PATH.into(),
            paths::SUBGOALS_REACHED.into(),
            paths::SUBGOALS_PLANNED.into(),
            paths::SUCTION.into(),
            paths::DECISIONS.into(),
            paths::SCORES.into(),
            paths::SLOT_SCORES.into(),
            paths::EVENTS_SUCTION.into(),
            paths::EVENTS_OUTCOME.into(),
            paths::package("crate"),
            paths::slots("crate"),
        ];
        expected.extend((0..=6).map(paths::link));
        expected.extend((0..6).map(paths::joint_position));
        expected.extend((0..6).map(paths::joint_velocity));
        let products = ["jam", "honey", "tea", "soap", "candle"];
        expected.extend(products.iter().map(|p| paths::product(p)));
        for path in &expected {
            assert!(
                r.has(path),
                "{path} missing; the file has {:?} and {:?}",
                r.statics,
                r.steps.keys()
            );
        }
        // No collision, no fallback: nothing logged there.
        assert!(!r.has(paths::EVENTS_COLLISIONS));
        assert!(!r.has(paths::EVENTS_FALLBACKS));

        // Sim time is the only timeline, with one step per frame, from 0
        // to the end of the run.
        assert_eq!(r.timelines, BTreeSet::from([paths::TIMELINE.to_owned()]));
        let n = frames(time_s);
        assert!(n > 100, "{n} frames");
        for path in [
            paths::link(1),
            paths::joint_position(0),
            paths::product("jam"),
        ] {
            assert_eq!(r.steps(&path), n, "{path}");
        }
        let steps = &r.steps[&paths::link(1)];
        assert_eq!(steps.first(), Some(&0));
        let end = (time_s * 1e9).round() as i64;
        assert!(
            steps.last().is_some_and(|t| (t - end).abs() < 1_000),
            "last step {:?}, run ended at {end} ns",
            steps.last()
        );

        // Four products packed: a picking and a placing decision each,
        // with their scores; four picks and four releases; every product
        // of the order has its outcome, then the verdict.
        assert_eq!(r.rows(paths::DECISIONS), 8);
        assert_eq!(r.rows(paths::SCORES), 8);
        assert_eq!(r.rows(paths::SLOT_SCORES), 4);
        assert_eq!(r.rows(paths::EVENTS_SUCTION), 8);
        assert_eq!(r.rows(paths::EVENTS_OUTCOME), 4 + 1);
        assert_eq!(r.rows(paths::SUBGOALS_PLANNED), 4 * 6);
        assert!(r.rows(paths::SUBGOALS_REACHED) >= 4 * 4);
    }

    /// `eval --record DIR` writes DIR/SUITE/NN.rrd per scenario (numbered
    /// as the suite names its scenarios), one recording per planner in it.
    #[test]
    fn eval_records_every_scenario_with_one_recording_per_planner() {
        let dir = scratch("recording", "eval");
        let out = dir.join("runs");
        let o = packwright(&[
            "eval",
            "orders/suites/teach.pack",
            "--suite",
            "case1_2of3",
            "--limit",
            "2",
            "--baselines",
            "--quiet",
            "--record",
            out.to_str().expect("UTF-8 path"),
        ]);
        assert_eq!(
            o.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
        for case in ["01", "02"] {
            let file = out.join("case1_2of3").join(format!("{case}.rrd"));
            let recordings = decode(&file);
            assert_eq!(recordings.len(), 3, "{case}: learned, rrt and expert");
            for r in recordings.values() {
                assert!(r.steps(&paths::link(1)) > 10, "{case}");
                assert_eq!(
                    r.steps(&paths::link(1)),
                    r.steps(&paths::joint_velocity(5)),
                    "{case}"
                );
                assert_eq!(r.rows(paths::EVENTS_SUCTION), 2 * 2, "{case}");
            }
            // Only the learned planner has a reasoner.
            let reasoned = recordings
                .values()
                .filter(|r| r.has(paths::DECISIONS))
                .count();
            assert_eq!(reasoned, 1, "{case}");
        }
    }
}

/// Without the feature, `--record` is refused before anything runs: exit
/// 2, the way to rebuild, no file.
#[cfg(not(feature = "rerun"))]
#[test]
fn record_needs_the_rerun_feature() {
    let dir = scratch("recording", "refused");
    let file = dir.join("run.rrd");
    let file = file.to_str().expect("UTF-8 path");
    for args in [
        &[
            "execute",
            "orders/customers/hampton_deli.pack",
            "--order",
            "deli_crate",
            "--record",
            file,
        ][..],
        &["eval", "orders/suites/teach.pack", "--record", file][..],
    ] {
        let o = packwright(args);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(stderr.contains("--features rerun"), "{stderr}");
        assert!(o.stdout.is_empty(), "nothing ran");
    }
    assert!(!std::path::Path::new(file).exists());
}
