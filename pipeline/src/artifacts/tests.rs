//! Each kind of problem, on the artifacts of a small file compiled in
//! memory: a clean directory is read, and one corruption at a time is
//! refused with its file, field and problem.

use super::*;
use packwright_compiler::artifact::{CellRecord, tensor};
use packwright_compiler::{Anywhere, Compiled, MemoryLoader, compile, emit};

const LINE2: &str = include_str!("../../../orders/cells/line2.pack");

/// Pine Gifts' order and demonstration, a generated block with products
/// packed by a worker and missing, and scenarios.
const FILE: &str = r#"use "line2.pack"

order trio for pantry3 {
  honey -> k1
  jam   -> k2
  tea   -> k4
}

demo seen for trio {
  sequence jam, tea, honey
  at jam (0.46, -0.38)
}

demos mixed for pantry5 {
  choose 3 of jam, tea, honey, soap, candle into k1, k2, k3
  human packs 1 to 1
  missing 0 to 1
  keep 0.2
  seed 3
}

scenario worker for trio {
  human packed jam, honey
  seed 5
}

scenarios short for pantry5 {
  choose 3 of jam, tea, honey, soap, candle into k1, k2, k3
  missing 1 to 2
  count 4
  seed 6
}
"#;

struct Fixture {
    compiled: Compiled,
    manifest: Manifest,
    demonstrations: Vec<DemonstrationRecord>,
    labels: LabelsFile,
    world: WorldFile,
    scenarios: ScenariosFile,
}

fn fixture() -> Fixture {
    let loader = MemoryLoader::new()
        .with("line2.pack", LINE2.to_owned())
        .with("pine.pack", FILE.to_owned());
    let (compiled, artifacts) = match compile(&loader, &[PathBuf::from("pine.pack")], &Anywhere) {
        Ok(done) => done,
        Err(failed) => panic!("{}", failed.render()),
    };
    let bytes = |name: &str| {
        artifacts
            .iter()
            .find(|a| a.name == name)
            .map(|a| a.bytes.clone())
            .unwrap_or_else(|| panic!("no {name}"))
    };
    Fixture {
        manifest: serde_json::from_slice(&bytes(file::MANIFEST)).expect("manifest"),
        demonstrations: bytes(file::DEMONSTRATIONS)
            .split(|&b| b == b'\n')
            .filter(|l| !l.is_empty())
            .map(|l| serde_json::from_slice(l).expect("demonstration"))
            .collect(),
        labels: serde_json::from_slice(&bytes(file::LABELS)).expect("labels"),
        world: serde_json::from_slice(&bytes(file::ORDERS)).expect("orders"),
        scenarios: serde_json::from_slice(&bytes(file::SCENARIOS)).expect("scenarios"),
        compiled,
    }
}

const DIR: &str = "compiled";

impl Fixture {
    fn check(self) -> Result<CompiledDir> {
        CompiledDir::new(
            Path::new(DIR),
            self.manifest,
            self.demonstrations,
            self.labels,
            self.world,
            self.scenarios,
        )
    }

    /// `graphs.safetensors` of the fixture's graphs changed by `change`,
    /// read against the fixture's JSON artifacts.
    fn graphs(self, change: impl FnOnce(&mut packwright_compiler::dataset::Graphs)) -> Result<()> {
        let mut g = self.compiled.graphs().expect("graphs");
        change(&mut g);
        let bytes = emit::graphs_bytes(&g).expect("serialised");
        let dir = CompiledDir::new(
            Path::new(DIR),
            self.manifest,
            self.demonstrations,
            self.labels,
            self.world,
            self.scenarios,
        )?;
        graphs::read(&dir, &dir.dir.join(file::GRAPHS), bytes).map(|_| ())
    }
}

/// The file name, field and problem of an error.
fn problem<T: std::fmt::Debug>(r: Result<T>) -> (String, String, ArtifactProblem) {
    match r {
        Err(PipelineError::Invalid {
            file,
            field,
            problem,
        }) => (
            file.file_name()
                .map(|f| f.to_string_lossy().into_owned())
                .unwrap_or_default(),
            field,
            problem,
        ),
        other => panic!("not an invalid artifact: {other:?}"),
    }
}

fn expect(
    r: Result<impl std::fmt::Debug>,
    file: &str,
    field: &str,
    is: impl Fn(&ArtifactProblem) -> bool,
) {
    let (f, at, p) = problem(r);
    assert_eq!((f.as_str(), at.as_str()), (file, field), "{p:?}");
    assert!(is(&p), "{file} {field}: {p:?}");
}

#[test]
fn a_clean_directory_is_read_from_disk_with_its_graphs() {
    let f = fixture();
    assert!(f.demonstrations.len() > 2);
    assert!(f.demonstrations.iter().any(|d| !d.missing.is_empty()));
    let dir =
        std::env::temp_dir().join(format!("packwright-artifacts-unit-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("dir");
    let loader = MemoryLoader::new()
        .with("line2.pack", LINE2.to_owned())
        .with("pine.pack", FILE.to_owned());
    let (_, artifacts) =
        compile(&loader, &[PathBuf::from("pine.pack")], &Anywhere).expect("compiled");
    for a in &artifacts {
        std::fs::write(dir.join(a.name), &a.bytes).expect("written");
    }
    let read = CompiledDir::read(&dir).expect("read");
    assert_eq!(read.manifest(), &f.manifest);
    assert_eq!(read.demonstrations(), &f.demonstrations[..]);
    let combinations = read.combinations().expect("combinations");
    let mixed = &f.manifest.demo_blocks[1];
    assert_eq!(
        combinations.len(),
        mixed.kept_combinations + mixed.held_out_combinations
    );
    assert!(
        combinations
            .iter()
            .all(|c| c.block == "mixed" && c.products.len() == 3)
    );
    let graphs = read.graphs().expect("graphs");
    assert_eq!(graphs.graphs.s, f.compiled.shape.samples);
    assert_eq!(
        graphs.graphs.per_demo,
        f.compiled.graphs().expect("graphs").per_demo
    );
    let names: Vec<&str> = graphs.tensors().iter().map(|t| t.0).collect();
    assert_eq!(names, tensor::ALL);
    std::fs::write(
        dir.join(file::LABELS),
        b"{\"schema\": \"packwright.labels\", \"version\": 1}",
    )
    .expect("written");
    expect(CompiledDir::read(&dir), "labels.json", "version", |p| {
        matches!(
            p,
            ArtifactProblem::Version {
                found: 1,
                expected: 2
            }
        )
    });
    std::fs::remove_file(dir.join(file::LABELS)).expect("removed");
    assert!(matches!(
        CompiledDir::read(&dir),
        Err(PipelineError::Read { .. })
    ));
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(
        schema::GRAPHS,
        format!("packwright.graphs/{SCHEMA_VERSION}")
    );
}

#[test]
fn schemas_and_versions_are_this_packwrights() {
    let mut f = fixture();
    f.manifest.schema = "packwright.orders".into();
    expect(
        f.check(),
        "manifest.json",
        "schema",
        |p| matches!(p, ArtifactProblem::Schema { found, .. } if found == "packwright.orders"),
    );
    let mut f = fixture();
    f.scenarios.version = 3;
    expect(f.check(), "scenarios.json", "version", |p| {
        matches!(
            p,
            ArtifactProblem::Version {
                found: 3,
                expected: 2
            }
        )
    });
}

#[test]
fn parse_errors_name_the_field() {
    let path = Path::new("labels.json");
    let text = br#"{"schema": "packwright.labels", "version": 1, "cells": [{"cell": "c", "labels": [{"label": -1, "name": "pick", "box": null, "position": null}]}]}"#;
    expect(
        parse::<LabelsFile>(path, text),
        "labels.json",
        "cells[0].labels[0].label",
        |p| matches!(p, ArtifactProblem::Malformed { .. }),
    );
    let text = br#"{"min": [0.1, 1e999], "max": [1, 2]}"#;
    expect(
        parse::<packwright_compiler::artifact::RectRecord>(path, text),
        "labels.json",
        "min[1]",
        |p| matches!(p, ArtifactProblem::Malformed { .. }),
    );
}

#[test]
fn numbers_are_finite_and_sizes_positive() {
    let mut f = fixture();
    f.world.cells[0].base[1] = f64::NAN;
    expect(
        f.check(),
        "orders.json",
        "cells[0].base[1]",
        |p| matches!(p, ArtifactProblem::NotFinite { value } if value.is_nan()),
    );
    let mut f = fixture();
    f.demonstrations[1].start[2].at[0] = 1e300;
    expect(
        f.check(),
        "demonstrations.jsonl",
        "[1].start[2].at[0]",
        |p| matches!(p, ArtifactProblem::NotFinite { .. }),
    );
    let mut f = fixture();
    f.scenarios.suites[0].cases[0].assignment[0].goal[2] = f64::INFINITY;
    expect(
        f.check(),
        "scenarios.json",
        "suites[0].cases[0].assignment[0].goal[2]",
        |p| matches!(p, ArtifactProblem::NotFinite { .. }),
    );
    let mut f = fixture();
    f.world.products[1].size[2] = 0.0;
    expect(f.check(), "orders.json", "products[1].size[2]", |p| {
        matches!(p, ArtifactProblem::NotAbove { bound: 0.0, .. })
    });
    let mut f = fixture();
    f.world.products[0].mass = Some(-1.0);
    expect(f.check(), "orders.json", "products[0].mass", |p| {
        matches!(p, ArtifactProblem::NotAbove { .. })
    });
    let mut f = fixture();
    f.world.cells[0].pending.max[1] = f.world.cells[0].pending.min[1];
    expect(f.check(), "orders.json", "cells[0].pending.max[1]", |p| {
        matches!(p, ArtifactProblem::NotAbove { .. })
    });
    let mut f = fixture();
    f.world.cells[0].suction = 10.0;
    expect(f.check(), "orders.json", "cells[0].suction", |p| {
        matches!(p, ArtifactProblem::LengthOutOfRange { value: 10.0, .. })
    });
    let mut f = fixture();
    f.world.cells[0].release_settle = 60.0;
    expect(f.check(), "orders.json", "cells[0].release_settle", |p| {
        matches!(p, ArtifactProblem::TimeOutOfRange { value: 60.0, .. })
    });
    let mut f = fixture();
    f.world.cells[0].descent = 0.0;
    expect(f.check(), "orders.json", "cells[0].descent", |p| {
        matches!(p, ArtifactProblem::ShareOutOfRange { value: 0.0, .. })
    });
    let mut f = fixture();
    f.world.cells[0].jerk = Some([10.0, 10.0, 10.0, 20.0, -20.0, 20.0]);
    expect(f.check(), "orders.json", "cells[0].jerk[4]", |p| {
        matches!(p, ArtifactProblem::LimitOutOfRange { value: -20.0, .. })
    });
    let mut f = fixture();
    f.world.cells[0].grip_settle = -0.1;
    expect(f.check(), "orders.json", "cells[0].grip_settle", |p| {
        matches!(p, ArtifactProblem::TimeOutOfRange { .. })
    });
    let mut f = fixture();
    f.world.cells[0].boxes[0].size[0] = -0.5;
    expect(f.check(), "orders.json", "cells[0].boxes[0].size[0]", |p| {
        matches!(p, ArtifactProblem::NotAbove { .. })
    });
}

#[test]
fn names_resolve_and_are_unique() {
    let mut f = fixture();
    f.demonstrations[0].sequence[1] = "ghost".into();
    expect(
        f.check(),
        "demonstrations.jsonl",
        "[0].sequence[1]",
        |p| matches!(p, ArtifactProblem::UnknownName { name, .. } if name == "ghost"),
    );
    let mut f = fixture();
    f.demonstrations[0].assignment[0].slot = "k9".into();
    expect(
        f.check(),
        "demonstrations.jsonl",
        "[0].assignment[0].slot",
        |p| {
            matches!(
                p,
                ArtifactProblem::UnknownName {
                    what: "slot of the cell",
                    ..
                }
            )
        },
    );
    let mut f = fixture();
    f.demonstrations[0].cell = "line3".into();
    expect(f.check(), "demonstrations.jsonl", "[0].cell", |p| {
        matches!(p, ArtifactProblem::UnknownName { .. })
    });
    let mut f = fixture();
    f.scenarios.suites[1].cases[0].start[0].product = "soup".into();
    expect(
        f.check(),
        "scenarios.json",
        "suites[1].cases[0].start[0].product",
        |p| matches!(p, ArtifactProblem::UnknownName { .. }),
    );
    let mut f = fixture();
    f.world.inventories[1].cell = "nowhere".into();
    expect(f.check(), "orders.json", "inventories[1].cell", |p| {
        matches!(p, ArtifactProblem::UnknownName { .. })
    });
    let mut f = fixture();
    f.world.products[2].name = f.world.products[0].name.clone();
    expect(f.check(), "orders.json", "products[2].name", |p| {
        matches!(p, ArtifactProblem::Duplicate { .. })
    });
    let mut f = fixture();
    let first = f.demonstrations[0].sequence[0].clone();
    f.demonstrations[0].sequence[2] = first;
    expect(f.check(), "demonstrations.jsonl", "[0].sequence[2]", |p| {
        matches!(p, ArtifactProblem::Duplicate { .. })
    });
    let mut f = fixture();
    f.world.cells[0].slots[1].box_name = "bin".into();
    expect(f.check(), "orders.json", "cells[0].slots[1].box", |p| {
        matches!(p, ArtifactProblem::UnknownName { .. })
    });
}

#[test]
fn labels_are_the_slots_labels_in_both_files() {
    let mut f = fixture();
    f.demonstrations[0].assignment[0].label = 999;
    expect(
        f.check(),
        "demonstrations.jsonl",
        "[0].assignment[0].label",
        |p| matches!(p, ArtifactProblem::Differs { found, .. } if found == "999"),
    );
    let mut f = fixture();
    f.world.cells[0].slots[2].label = 1;
    expect(f.check(), "orders.json", "cells[0].slots[2].label", |p| {
        matches!(p, ArtifactProblem::Differs { .. })
    });
    // A shuffled table: labels 1 and 2 swapped, numbers and all.
    let mut f = fixture();
    f.labels.cells[0].labels.swap(1, 2);
    expect(
        f.check(),
        "labels.json",
        "cells[0].labels[1].label",
        |p| matches!(p, ArtifactProblem::Differs { found, .. } if found == "2"),
    );
    // Names shuffled, numbers kept.
    let mut f = fixture();
    let table = &mut f.labels.cells[0].labels;
    let (a, b) = (table[1].name.clone(), table[3].name.clone());
    table[1].name = b;
    table[3].name = a;
    expect(f.check(), "labels.json", "cells[0].labels[1].name", |p| {
        matches!(p, ArtifactProblem::Differs { .. })
    });
    let mut f = fixture();
    f.labels.cells[0].labels.pop();
    expect(f.check(), "labels.json", "cells[0].labels", |p| {
        matches!(
            p,
            ArtifactProblem::CountMismatch {
                expected: 6,
                found: 5
            }
        )
    });
    let mut f = fixture();
    f.labels.cells[0].labels[4].position = Some([0.0, 0.0]);
    expect(
        f.check(),
        "labels.json",
        "cells[0].labels[4].position",
        |p| matches!(p, ArtifactProblem::Differs { .. }),
    );
    let mut f = fixture();
    f.labels.cells.clear();
    expect(f.check(), "labels.json", "cells", |p| {
        matches!(
            p,
            ArtifactProblem::CountMismatch {
                expected: 1,
                found: 0
            }
        )
    });
}

#[test]
fn counts_and_sample_ranges_match_what_the_files_hold() {
    let mut f = fixture();
    f.manifest.counts.demonstrations = 7;
    expect(f.check(), "manifest.json", "counts.demonstrations", |p| {
        matches!(p, ArtifactProblem::CountMismatch { found: 7, .. })
    });
    let mut f = fixture();
    f.manifest.counts.scenarios += 1;
    expect(f.check(), "manifest.json", "counts.scenarios", |p| {
        matches!(p, ArtifactProblem::CountMismatch { .. })
    });
    let mut f = fixture();
    f.manifest.demo_blocks[1].first_demonstration = 0;
    expect(
        f.check(),
        "manifest.json",
        "demo_blocks[1].first_demonstration",
        |p| matches!(p, ArtifactProblem::Differs { .. }),
    );
    let mut f = fixture();
    f.manifest.demo_blocks[0].demonstrations = 2;
    expect(f.check(), "demonstrations.jsonl", "[1].block", |p| {
        matches!(p, ArtifactProblem::Differs { .. })
    });
    let mut f = fixture();
    f.manifest.demo_blocks[1].demonstrations = 1000;
    expect(
        f.check(),
        "manifest.json",
        "demo_blocks[1].demonstrations",
        |p| matches!(p, ArtifactProblem::CountMismatch { found: 1000, .. }),
    );
    let mut f = fixture();
    f.demonstrations[1].first_sample += 1;
    expect(f.check(), "demonstrations.jsonl", "[1].first_sample", |p| {
        matches!(p, ArtifactProblem::Differs { .. })
    });
    let mut f = fixture();
    f.demonstrations[0].samples = 4;
    f.manifest.demo_blocks[0].samples = 4;
    expect(f.check(), "demonstrations.jsonl", "[0].samples", |p| {
        matches!(
            p,
            ArtifactProblem::CountMismatch {
                expected: 6,
                found: 4
            }
        )
    });
    let mut f = fixture();
    f.manifest.tensors.nodes += 1;
    expect(f.check(), "manifest.json", "tensors.nodes", |p| {
        matches!(p, ArtifactProblem::CountMismatch { .. })
    });
    let mut f = fixture();
    f.demonstrations[0].start.pop();
    expect(f.check(), "demonstrations.jsonl", "[0].start", |p| {
        matches!(p, ArtifactProblem::CountMismatch { .. })
    });
    let mut f = fixture();
    f.demonstrations[0].start.swap(0, 1);
    expect(
        f.check(),
        "demonstrations.jsonl",
        "[0].start[0].product",
        |p| matches!(p, ArtifactProblem::Differs { .. }),
    );
}

#[test]
fn tensors_hold_what_the_manifest_says() {
    fn is_range(value: i64) -> impl Fn(&ArtifactProblem) -> bool {
        move |p| matches!(p, ArtifactProblem::OutOfRange { value: v, .. } if *v == value)
    }
    assert!(fixture().graphs(|_| {}).is_ok());
    expect(
        fixture().graphs(|g| g.edge_index[0] = 999),
        "graphs.safetensors",
        "edge_index[0][0]",
        is_range(999),
    );
    expect(
        fixture().graphs(|g| g.edge_index[1] = 0),
        "graphs.safetensors",
        "edge_index[0][1]",
        |p| matches!(p, ArtifactProblem::Differs { .. }),
    );
    expect(
        fixture().graphs(|g| g.target[1] = 999),
        "graphs.safetensors",
        "target[1]",
        is_range(999),
    );
    expect(
        fixture().graphs(|g| g.target[0] = g.target[1]),
        "graphs.safetensors",
        "target[0]",
        |p| matches!(p, ArtifactProblem::OutOfRange { min: 0, .. }),
    );
    expect(
        fixture().graphs(|g| g.label[1] = 999),
        "graphs.safetensors",
        "label[1]",
        is_range(999),
    );
    expect(
        fixture().graphs(|g| g.label[1] = -1),
        "graphs.safetensors",
        "label[1]",
        is_range(-1),
    );
    expect(
        fixture().graphs(|g| g.label[0] = 1),
        "graphs.safetensors",
        "label[0]",
        is_range(1),
    );
    expect(
        fixture().graphs(|g| g.stage[2] = 2),
        "graphs.safetensors",
        "stage[2]",
        is_range(2),
    );
    expect(
        fixture().graphs(|g| g.stage[2] = 1),
        "graphs.safetensors",
        "stage[2]",
        |p| matches!(p, ArtifactProblem::Differs { .. }),
    );
    expect(
        fixture().graphs(|g| g.demo[0] = 99),
        "graphs.safetensors",
        "demo[0]",
        is_range(99),
    );
    expect(
        fixture().graphs(|g| g.node_mask[1] = 7),
        "graphs.safetensors",
        "node_mask[0][1]",
        is_range(7),
    );
    expect(
        fixture().graphs(|g| g.nodes[5] = f32::NAN),
        "graphs.safetensors",
        "nodes[0][1][1]",
        |p| matches!(p, ArtifactProblem::NotFinite { .. }),
    );
    expect(
        fixture().graphs(|g| g.goal[4] = f32::INFINITY),
        "graphs.safetensors",
        "goal[1][1]",
        |p| matches!(p, ArtifactProblem::NotFinite { .. }),
    );
    // Two samples fewer than the manifest says.
    expect(
        fixture().graphs(|g| {
            g.s -= 2;
            g.nodes.truncate(g.s * g.m * 4);
            g.node_mask.truncate(g.s * g.m);
            g.goal.truncate(g.s * 3);
            for v in [&mut g.target, &mut g.label, &mut g.demo] {
                v.truncate(g.s);
            }
            g.stage.truncate(g.s);
        }),
        "graphs.safetensors",
        "nodes",
        |p| matches!(p, ArtifactProblem::Shape { .. }),
    );
}

#[test]
fn graphs_files_of_another_layout_are_refused() {
    let f = fixture();
    let dir = f.check().expect("clean");
    let path = Path::new("graphs.safetensors");
    let data = [0u8; 8];
    let view = |dtype: safetensors::Dtype| {
        let shape = vec![64 / dtype.bitsize()];
        safetensors::tensor::TensorView::new(dtype, shape, &data).expect("view")
    };
    let with = |metadata: Option<&str>, dtype| {
        let metadata = metadata
            .map(|m| std::collections::HashMap::from([("schema".to_owned(), m.to_owned())]));
        safetensors::serialize([(tensor::NODES, view(dtype))], metadata).expect("serialised")
    };
    expect(
        graphs::read(&dir, path, b"not a file".to_vec()),
        "graphs.safetensors",
        "",
        |p| matches!(p, ArtifactProblem::NotSafetensors { .. }),
    );
    expect(
        graphs::read(&dir, path, with(None, safetensors::Dtype::I64)),
        "graphs.safetensors",
        "__metadata__.schema",
        |p| matches!(p, ArtifactProblem::Schema { .. }),
    );
    expect(
        graphs::read(
            &dir,
            path,
            with(Some(schema::GRAPHS), safetensors::Dtype::I64),
        ),
        "graphs.safetensors",
        "nodes",
        |p| matches!(p, ArtifactProblem::Dtype { .. }),
    );
    expect(
        graphs::read(
            &dir,
            path,
            with(Some(schema::GRAPHS), safetensors::Dtype::F32),
        ),
        "graphs.safetensors",
        "nodes",
        |p| matches!(p, ArtifactProblem::Shape { .. }),
    );
}

#[test]
fn messages_name_the_file_and_the_field() {
    let mut f = fixture();
    f.demonstrations[0].sequence[1] = "ghost".into();
    let message = f
        .check()
        .map(|_| ())
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert_eq!(
        message,
        "compiled/demonstrations.jsonl, [0].sequence[1]: no product of the assignment is named `ghost`"
    );
    let mut f = fixture();
    f.manifest.version = 1;
    let message = f
        .check()
        .map(|_| ())
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert!(
        message.starts_with("compiled/manifest.json, version: schema version 1"),
        "{message}"
    );
    assert!(message.contains("compile"), "{message}");
}

#[test]
fn settle_times_are_written_only_when_not_the_defaults() {
    // An `orders.json` cell without settle times or descent (as written
    // before they existed, or with the defaults) reads as the defaults,
    // and a cell with others keeps them through a write and a read.
    let f = fixture();
    let mut cell = f.world.cells[0].clone();
    let json = serde_json::to_value(&cell).expect("serialises");
    for key in ["grip_settle", "release_settle", "descent"] {
        assert!(json.get(key).is_none(), "{key}");
    }
    let back: CellRecord = serde_json::from_value(json).expect("reads");
    assert_eq!(
        (back.grip_settle, back.release_settle, back.descent),
        (0.1, 0.5, 1.0)
    );
    cell.grip_settle = 0.25;
    cell.release_settle = 0.0;
    cell.descent = 0.3;
    let json = serde_json::to_value(&cell).expect("serialises");
    assert_eq!(json["grip_settle"], 0.25);
    assert_eq!(json["release_settle"], 0.0);
    assert_eq!(json["descent"], 0.3);
    let back: CellRecord = serde_json::from_value(json).expect("reads");
    assert_eq!(
        (back.grip_settle, back.release_settle, back.descent),
        (0.25, 0.0, 0.3)
    );
}

#[test]
fn a_cells_joint_limits_replace_the_arms_then_its_speed_scales_them() {
    let f = fixture();
    let mut cell = f.world.cells[0].clone();
    let own = crate::episode::cell_arm(&cell).expect("an arm").limits;
    let json = serde_json::to_value(&cell).expect("serialises");
    assert!(json.get("acceleration").is_none() && json.get("jerk").is_none());
    cell.acceleration = Some([1.0, 1.5, 2.0, 2.5, 3.0, 3.5]);
    cell.jerk = Some([5.0; 6]);
    cell.speed = 0.5;
    let json = serde_json::to_value(&cell).expect("serialises");
    let back: CellRecord = serde_json::from_value(json).expect("reads");
    assert_eq!(
        (back.acceleration, back.jerk),
        (cell.acceleration, cell.jerk)
    );
    let arm = crate::episode::cell_arm(&back).expect("an arm");
    for (j, (l, o)) in arm.limits.iter().zip(&own).enumerate() {
        assert_eq!(l.acceleration, [1.0, 1.5, 2.0, 2.5, 3.0, 3.5][j] * 0.25);
        assert_eq!(l.jerk, 5.0 * 0.125);
        assert_eq!(l.velocity, o.velocity * 0.5);
        assert_eq!((l.lower, l.upper), (o.lower, o.upper));
    }
}
