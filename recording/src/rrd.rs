//! Runs as Rerun recordings (`.rrd` bytes, Rerun 0.36): one recording per
//! run, on the [`TIMELINE`] timeline, at the entity paths of
//! [`crate::paths`]. The bytes are made in memory (the caller writes the
//! file, atomically); several runs in one file are several recordings the
//! viewer lists side by side.

use crate::error::RecordingError;
use crate::journal::Frame;
use crate::paths::{self, TIMELINE};
use crate::shapes::{ArmBodies, Capsule, arm_bodies, placement};
use crate::timeline::{Run, TimedEvent, fallback_times, tool_path};
use nalgebra::Isometry3;
use packwright_draw::{EventKind, Stage, ToolPath};
use packwright_interface::DOF;
use packwright_interface::outcome::Outcome;
use rerun::components::{FillMode, TextLogLevel};
use rerun::sink::MemorySinkStorage;
use rerun::{
    BarChart, Boxes3D, Capsules3D, Color, LineStrips3D, Points3D, Quaternion, RecordingStream,
    RecordingStreamBuilder, Scalars, TextLog, Transform3D, ViewCoordinates,
};

/// The application the recordings belong to, in the viewer.
pub const APPLICATION: &str = "packwright";

const ARM: [u8; 3] = [140, 150, 165];
const CUP: [u8; 3] = [60, 60, 60];
const SELECTED: [u8; 3] = [255, 127, 14];
const OTHER: [u8; 3] = [170, 170, 170];
const PACKAGE: [u8; 3] = [140, 86, 75];
const SLOT: [u8; 3] = [31, 119, 180];
const REACHED: [u8; 3] = [20, 20, 20];
const PLANNED: [u8; 3] = [227, 119, 194];

fn colour([r, g, b]: [u8; 3]) -> Color {
    Color::from_rgb(r, g, b)
}

/// The `.rrd` bytes of `runs`, one recording each.
pub fn rrd(runs: &[Run]) -> Result<Vec<u8>, RecordingError> {
    let mut storages = Vec::new();
    for run in runs {
        let (rec, storage) = RecordingStreamBuilder::new(APPLICATION)
            .recording_name(run.name)
            .memory()?;
        // Sim time is the only timeline: the wall clock of writing the
        // file means nothing.
        rec.set_log_time_enabled(false);
        rec.set_log_tick_enabled(false);
        record(&rec, run)?;
        storages.push(storage);
    }
    let storages: Vec<&MemorySinkStorage> = storages.iter().collect();
    Ok(MemorySinkStorage::concat_memory_sinks_as_bytes(&storages)?)
}

/// Logs `run` into `rec`.
fn record(rec: &RecordingStream, run: &Run) -> Result<(), RecordingError> {
    let task = run.task;
    let cell = &task.cell;
    rec.log_static(paths::WORLD, &ViewCoordinates::RIGHT_HAND_Z_UP())?;
    let bodies = arm_bodies(run.arm, cell.suction);
    log_arm_bodies(rec, &bodies)?;
    log_cell(rec, run)?;
    let (path, events) = tool_path(run.arm, task, &run.entries.cycles, &run.report.subgoals);
    log_tool_path(rec, &path)?;
    let b = cell.base;
    let base = Isometry3::translation(b[0], b[1], b[2]);
    for frame in &run.entries.frames {
        rec.set_duration_secs(TIMELINE, frame.time);
        log_frame(rec, run, &base, frame)?;
    }
    log_events(rec, run, &events)?;
    log_decisions(rec, run)?;
    log_outcome(rec, run)?;
    Ok(())
}

fn capsules(list: &[Capsule], rgb: [u8; 3]) -> Capsules3D {
    Capsules3D::from_lengths_and_radii(list.iter().map(|c| c.length), list.iter().map(|c| c.radius))
        .with_translations(list.iter().map(|c| c.translation))
        .with_quaternions(list.iter().map(|c| Quaternion::from_xyzw(c.rotation)))
        .with_colors([colour(rgb)])
}

/// The links' and the cup's shapes, static in their links' frames.
fn log_arm_bodies(rec: &RecordingStream, bodies: &ArmBodies) -> Result<(), RecordingError> {
    for (i, link) in bodies.links.iter().enumerate() {
        let path = paths::link(i);
        if !link.capsules.is_empty() {
            rec.log_static(path.as_str(), &capsules(&link.capsules, ARM))?;
        }
        if !link.cuboids.is_empty() {
            rec.log_static(
                format!("{path}/cuboids"),
                &Boxes3D::from_centers_and_half_sizes(
                    link.cuboids.iter().map(|c| c.centre),
                    link.cuboids.iter().map(|c| c.half),
                )
                .with_quaternions(
                    link.cuboids
                        .iter()
                        .map(|c| Quaternion::from_xyzw(c.rotation)),
                )
                .with_colors([colour(ARM)]),
            )?;
        }
    }
    rec.log_static(paths::CUP, &capsules(&bodies.cup, CUP))?;
    Ok(())
}

/// The boxes with their slots, the pending area and the products' shapes
/// (static; the products move every frame).
fn log_cell(rec: &RecordingStream, run: &Run) -> Result<(), RecordingError> {
    let cell = &run.task.cell;
    for (b, package) in cell.boxes.iter().enumerate() {
        let [w, d, h] = package.size.map(|v| v as f32);
        let [x, y] = package.centre.map(|v| v as f32);
        rec.log_static(
            paths::package(&package.name),
            &Boxes3D::from_centers_and_half_sizes([[x, y, h / 2.0]], [[w / 2.0, d / 2.0, h / 2.0]])
                .with_fill_mode(FillMode::MajorWireframe)
                .with_colors([colour(PACKAGE)])
                .with_labels([package.name.as_str()]),
        )?;
        let slots: Vec<_> = cell.slots.iter().filter(|s| s.box_index == b).collect();
        rec.log_static(
            paths::slots(&package.name),
            &Points3D::new(
                slots
                    .iter()
                    .map(|s| [s.position[0] as f32, s.position[1] as f32, 0.002]),
            )
            .with_labels(slots.iter().map(|s| s.name.as_str()))
            .with_colors([colour(SLOT)])
            .with_radii([0.008]),
        )?;
    }
    let ([x0, y0], [x1, y1]) = cell.pending;
    let corners = [[x0, y0], [x1, y0], [x1, y1], [x0, y1], [x0, y0]];
    rec.log_static(
        paths::PENDING,
        &LineStrips3D::new([corners.map(|[x, y]| [x as f32, y as f32, 0.0])])
            .with_colors([colour(OTHER)])
            .with_labels(["pending"]),
    )?;
    // Products never seen (missing from the cell) are not drawn.
    let seen = |name: &str| {
        run.entries
            .frames
            .iter()
            .any(|f| f.products.iter().any(|s| s.name == name))
    };
    for (p, spec) in run.task.products.iter().enumerate() {
        if !seen(&spec.name) {
            continue;
        }
        let rgb = if run.task.slot_of(p).is_some() {
            SELECTED
        } else {
            OTHER
        };
        let [w, d, h] = spec.size.map(|v| v as f32 / 2.0);
        rec.log_static(
            paths::product(&spec.name),
            &Boxes3D::from_half_sizes([[w, d, h]])
                .with_colors([colour(rgb)])
                .with_fill_mode(FillMode::Solid)
                .with_labels([spec.name.as_str()]),
        )?;
    }
    Ok(())
}

fn stage_colour(stage: Stage) -> Color {
    let hex = stage.colour().trim_start_matches('#');
    let channel = |i: usize| {
        hex.get(i..i + 2)
            .and_then(|c| u8::from_str_radix(c, 16).ok())
            .unwrap_or(0)
    };
    Color::from_rgb(channel(0), channel(2), channel(4))
}

/// The whole tool path, static: one strip per run of a stage, joined
/// where the stage changes.
fn log_tool_path(rec: &RecordingStream, path: &ToolPath) -> Result<(), RecordingError> {
    let mut strips: Vec<(Stage, Vec<[f32; 3]>)> = Vec::new();
    for (p, stage) in &path.points {
        let point = p.map(|v| v as f32);
        match strips.last_mut() {
            Some((s, strip)) if s == stage => strip.push(point),
            last => {
                let joint = last.and_then(|(_, strip)| strip.last().copied());
                strips.push((*stage, joint.into_iter().chain([point]).collect()));
            }
        }
    }
    rec.log_static(
        paths::TOOL_PATH,
        &LineStrips3D::new(strips.iter().map(|(_, s)| s.clone()))
            .with_colors(strips.iter().map(|(s, _)| stage_colour(*s)))
            .with_radii([0.002]),
    )?;
    Ok(())
}

/// One frame: the links' and the products' poses, the joint plots.
fn log_frame(
    rec: &RecordingStream,
    run: &Run,
    base: &Isometry3<f64>,
    frame: &Frame,
) -> Result<(), RecordingError> {
    for (i, pose) in run.arm.link_poses(base, &frame.joints).iter().enumerate() {
        let (t, q) = placement(pose);
        rec.log(
            paths::link(i),
            &Transform3D::from_translation(t).with_quaternion(Quaternion::from_xyzw(q)),
        )?;
    }
    for seen in &frame.products {
        let half = seen.yaw / 2.0;
        rec.log(
            paths::product(&seen.name),
            &Transform3D::from_translation(seen.centre.map(|v| v as f32)).with_quaternion(
                Quaternion::from_xyzw([0.0, 0.0, half.sin() as f32, half.cos() as f32]),
            ),
        )?;
    }
    for j in 0..DOF {
        rec.log(paths::joint_position(j), &Scalars::single(frame.joints[j]))?;
        rec.log(
            paths::joint_velocity(j),
            &Scalars::single(frame.velocities[j]),
        )?;
    }
    rec.log(
        paths::SUCTION,
        &Scalars::single(if frame.suction { 1.0 } else { 0.0 }),
    )?;
    Ok(())
}

fn text(
    rec: &RecordingStream,
    path: &str,
    time: f64,
    line: &str,
    level: &str,
) -> Result<(), RecordingError> {
    rec.set_duration_secs(TIMELINE, time);
    rec.log(
        path,
        &TextLog::new(line).with_level(TextLogLevel::from(level)),
    )?;
    Ok(())
}

/// Sub-goals (cumulative, from the time each is reached or planned),
/// picks and releases, collisions and fallbacks.
fn log_events(
    rec: &RecordingStream,
    run: &Run,
    events: &[TimedEvent],
) -> Result<(), RecordingError> {
    let mut reached: Vec<([f32; 3], String)> = Vec::new();
    for e in events {
        match &e.kind {
            EventKind::SubGoal(n) => {
                reached.push((e.at.map(|v| v as f32), n.to_string()));
                rec.set_duration_secs(TIMELINE, e.time);
                rec.log(
                    paths::SUBGOALS_REACHED,
                    &Points3D::new(reached.iter().map(|(p, _)| *p))
                        .with_labels(reached.iter().map(|(_, l)| l.as_str()))
                        .with_colors([colour(REACHED)])
                        .with_radii([0.01]),
                )?;
            }
            EventKind::Pick | EventKind::Release => {
                let what = if e.kind == EventKind::Pick {
                    "pick (suction on)"
                } else {
                    "release (suction off)"
                };
                let [x, y, z] = e.at;
                let line = format!("{what} at ({x:.3}, {y:.3}, {z:.3})");
                text(
                    rec,
                    paths::EVENTS_SUCTION,
                    e.time,
                    &line,
                    TextLogLevel::INFO,
                )?;
            }
            EventKind::Fallback(_) | EventKind::Failure(_) => {}
        }
    }
    let mut planned: Vec<([f32; 3], String)> = Vec::new();
    for p in &run.entries.planned {
        planned.push((
            p.tip.map(|v| v as f32),
            format!("{} {}", p.stage, p.index + 1),
        ));
        rec.set_duration_secs(TIMELINE, p.time);
        rec.log(
            paths::SUBGOALS_PLANNED,
            &Points3D::new(planned.iter().map(|(p, _)| *p))
                .with_labels(planned.iter().map(|(_, l)| l.as_str()))
                .with_colors([colour(PLANNED)])
                .with_radii([0.008]),
        )?;
    }
    for c in &run.entries.contacts {
        let line = format!("collision: {c}");
        text(
            rec,
            paths::EVENTS_COLLISIONS,
            c.time,
            &line,
            TextLogLevel::ERROR,
        )?;
    }
    for (time, f) in fallback_times(run.entries, run.report) {
        let line = format!("fallback to RRT-Connect: {f}");
        text(
            rec,
            paths::EVENTS_FALLBACKS,
            time,
            &line,
            TextLogLevel::WARN,
        )?;
    }
    Ok(())
}

/// Each reasoner decision as text, and its scores as bars.
fn log_decisions(rec: &RecordingStream, run: &Run) -> Result<(), RecordingError> {
    for d in &run.entries.decisions {
        let scores = run.scorer.map(|score| score(&d.graph));
        let line = d.describe(&run.task.cell.slots, scores.as_ref());
        text(rec, paths::DECISIONS, d.time, &line, TextLogLevel::INFO)?;
        if let Some(s) = scores {
            rec.log(paths::SCORES, &BarChart::new(s.nodes.as_slice()))?;
            if d.choice.node.is_none() && !s.slots.is_empty() {
                rec.log(paths::SLOT_SCORES, &BarChart::new(s.slots.as_slice()))?;
            }
        }
    }
    Ok(())
}

/// At the end: each product's outcome, the decisions that broke the
/// order, and the verdict.
fn log_outcome(rec: &RecordingStream, run: &Run) -> Result<(), RecordingError> {
    let report = run.report;
    let end = run.entries.frames.last().map_or(report.time_s, |f| f.time);
    for p in &report.products {
        let level = match p.outcome {
            Outcome::Failed(_) => TextLogLevel::ERROR,
            Outcome::NotAttempted | Outcome::Waiting => TextLogLevel::WARN,
            Outcome::Packed | Outcome::AlreadyPacked => TextLogLevel::INFO,
        };
        let line = format!("{} -> {}: {}", p.product, p.slot, p.outcome);
        text(rec, paths::EVENTS_OUTCOME, end, &line, level)?;
    }
    for v in &report.violations {
        let line = format!("the reasoner {v}: the arm stopped");
        text(rec, paths::EVENTS_OUTCOME, end, &line, TextLogLevel::ERROR)?;
    }
    let verdict = match report.first_problem() {
        None => format!(
            "package complete ({}, {:.2} s)",
            report.planner, report.time_s
        ),
        Some(why) => format!("package NOT complete ({}): {why}", report.planner),
    };
    let level = if report.complete {
        TextLogLevel::INFO
    } else {
        TextLogLevel::ERROR
    };
    text(rec, paths::EVENTS_OUTCOME, end, &verdict, level)
}
