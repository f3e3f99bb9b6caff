//! Compiled artifacts are checked when read, by the one reader every
//! command shares (`packwright_pipeline::artifacts`): a corrupted compiled
//! directory makes `train`, `demonstrate` and `show` exit with 2, write
//! nothing, and name the file and the field on stderr, before any
//! training or replay starts.

mod common;
use common::{packwright, scratch};
use packwright_compiler::artifact::tensor;
use safetensors::SafeTensors;
use safetensors::tensor::TensorView;
use serde_json::Value;
use std::collections::HashMap;
use std::fs;
use std::path::{Path, PathBuf};
use std::process::Output;

fn text(out: &Output) -> String {
    format!(
        "stdout:\n{}\nstderr:\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

fn arg(p: &Path) -> String {
    p.display().to_string()
}

fn read_json(path: &Path) -> Value {
    serde_json::from_slice(&fs::read(path).expect("read")).expect("JSON")
}

fn write_json(path: &Path, value: &Value) {
    fs::write(path, serde_json::to_vec_pretty(value).expect("JSON")).expect("written");
}

/// Edits the JSON file `name` of `dir`.
fn edit(dir: &Path, name: &str, change: impl FnOnce(&mut Value)) {
    let path = dir.join(name);
    let mut value = read_json(&path);
    change(&mut value);
    write_json(&path, &value);
}

/// The first record (line) of the JSON Lines file `name` of `dir`,
/// changed.
fn edit_first_line(dir: &Path, name: &str, change: impl FnOnce(&mut Value)) {
    let path = dir.join(name);
    let text = fs::read_to_string(&path).expect("read");
    let (first, rest) = text.split_once('\n').expect("a line");
    let mut value: Value = serde_json::from_str(first).expect("json");
    change(&mut value);
    fs::write(&path, format!("{value}\n{rest}")).expect("written");
}

/// `graphs.safetensors` of `dir` with `edge_index[0][0]` set to `value`,
/// everything else (and the metadata) as compiled.
fn set_first_edge(dir: &Path, value: i64) {
    let path = dir.join("graphs.safetensors");
    let bytes = fs::read(&path).expect("read");
    let (_, metadata) = SafeTensors::read_metadata(&bytes).expect("metadata");
    let st = SafeTensors::deserialize(&bytes).expect("safetensors");
    let mut data: Vec<(String, safetensors::Dtype, Vec<usize>, Vec<u8>)> = tensor::ALL
        .iter()
        .map(|&name| {
            let view = st.tensor(name).expect("tensor");
            (
                name.to_owned(),
                view.dtype(),
                view.shape().to_vec(),
                view.data().to_vec(),
            )
        })
        .collect();
    let edges = data
        .iter_mut()
        .find(|t| t.0 == tensor::EDGE_INDEX)
        .expect("edge_index");
    assert!(edges.3.len() >= 8, "the chain has edges");
    edges.3[..8].copy_from_slice(&value.to_le_bytes());
    let views: Vec<(String, TensorView)> = data
        .iter()
        .map(|(name, dtype, shape, bytes)| {
            (
                name.clone(),
                TensorView::new(*dtype, shape.clone(), bytes).expect("view"),
            )
        })
        .collect();
    let metadata: Option<HashMap<String, String>> = metadata.metadata().clone();
    fs::write(
        &path,
        safetensors::serialize(views, metadata).expect("serialised"),
    )
    .expect("written");
}

/// One corruption: its name, what it does to a compiled directory, and
/// the file and field the error must name.
struct Corruption {
    name: &'static str,
    apply: fn(&Path),
    file: &'static str,
    field: &'static str,
    /// Only `show` reads `graphs.safetensors`.
    graphs: bool,
}

const CORRUPTIONS: &[Corruption] = &[
    Corruption {
        name: "infinite",
        apply: |dir| {
            // Not JSON a number can be: `1e999` overflows, NaN is no
            // JSON at all. Either way the reader must name the field.
            let path = dir.join("demonstrations.jsonl");
            edit_first_line(dir, "demonstrations.jsonl", |v| {
                v["start"][1]["at"][0] = serde_json::json!(123456.75);
            });
            let text = fs::read_to_string(&path).expect("read");
            fs::write(&path, text.replacen("123456.75", "1e999", 1)).expect("written");
        },
        file: "demonstrations.jsonl",
        field: "[0].start[1].at[0]",
        graphs: false,
    },
    Corruption {
        name: "null",
        apply: |dir| {
            edit(dir, "orders.json", |v| {
                v["cells"][0]["suction"] = Value::Null
            })
        },
        file: "orders.json",
        field: "cells[0].suction",
        graphs: false,
    },
    Corruption {
        name: "version",
        apply: |dir| edit(dir, "manifest.json", |v| v["version"] = 1.into()),
        file: "manifest.json",
        field: "version",
        graphs: false,
    },
    Corruption {
        name: "negative_label",
        apply: |dir| {
            edit_first_line(dir, "demonstrations.jsonl", |v| {
                v["assignment"][0]["label"] = (-1).into();
            });
        },
        file: "demonstrations.jsonl",
        field: "[0].assignment[0].label",
        graphs: false,
    },
    Corruption {
        name: "label_999",
        apply: |dir| {
            edit_first_line(dir, "demonstrations.jsonl", |v| {
                v["assignment"][0]["label"] = 999.into();
            });
        },
        file: "demonstrations.jsonl",
        field: "[0].assignment[0].label",
        graphs: false,
    },
    Corruption {
        name: "count",
        apply: |dir| {
            edit(dir, "manifest.json", |v| {
                v["counts"]["demonstrations"] = 7.into()
            })
        },
        file: "manifest.json",
        field: "counts.demonstrations",
        graphs: false,
    },
    Corruption {
        name: "shuffled_labels",
        apply: |dir| {
            edit(dir, "labels.json", |v| {
                if let Some(table) = v["cells"][0]["labels"].as_array_mut() {
                    table.swap(1, 2);
                }
            });
        },
        file: "labels.json",
        field: "cells[0].labels[1].label",
        graphs: false,
    },
    Corruption {
        name: "short_labels",
        apply: |dir| {
            edit(dir, "labels.json", |v| {
                if let Some(table) = v["cells"][0]["labels"].as_array_mut() {
                    table.pop();
                }
            });
        },
        file: "labels.json",
        field: "cells[0].labels",
        graphs: false,
    },
    Corruption {
        name: "unknown_product",
        apply: |dir| {
            edit_first_line(dir, "demonstrations.jsonl", |v| {
                v["sequence"][1] = "ghost".into();
            });
        },
        file: "demonstrations.jsonl",
        field: "[0].sequence[1]",
        graphs: false,
    },
    Corruption {
        name: "edge_index",
        apply: |dir| set_first_edge(dir, 999),
        file: "graphs.safetensors",
        field: "edge_index[0][0]",
        graphs: true,
    },
];

/// A copy of the clean compiled directory `clean` at `to`.
fn copy_dir(clean: &Path, to: &Path) {
    fs::create_dir_all(to).expect("created");
    for entry in fs::read_dir(clean).expect("listed") {
        let entry = entry.expect("entry");
        fs::copy(entry.path(), to.join(entry.file_name())).expect("copied");
    }
}

/// Runs `args`; it must fail with 2, print nothing on stdout, leave
/// `output` unwritten, and name `file, field` on stderr.
fn refused(args: &[&str], output: &Path, file: &str, field: &str, what: &str) {
    let out = packwright(args);
    assert_eq!(out.status.code(), Some(2), "{what}: {}", text(&out));
    assert!(out.stdout.is_empty(), "{what}: {}", text(&out));
    assert!(!output.exists(), "{what}: {} written", output.display());
    let stderr = String::from_utf8_lossy(&out.stderr);
    let place = format!("{file}, {field}: ");
    assert!(stderr.contains(&place), "{what}: no `{place}` in {stderr}");
}

#[test]
fn corrupted_artifacts_are_refused_by_every_reader() {
    let root = scratch("artifacts", "corrupt");
    let clean: PathBuf = root.join("clean");
    let out = packwright(&[
        "compile",
        "orders/customers/pine_gifts.pack",
        "-o",
        &arg(&clean),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));

    // The clean directory passes the reader: `show` shows it, and `train`
    // gets as far as the sequence rule (the two demonstrations disagree).
    let out = packwright(&["show", &arg(&clean)]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    let model = root.join("clean-model");
    let out = packwright(&[
        "train",
        &arg(&clean),
        "-o",
        &arg(&model),
        "--epochs",
        "1",
        "--quiet",
    ]);
    assert_eq!(out.status.code(), Some(2), "{}", text(&out));
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("follow no one sequence rule"),
        "{}",
        text(&out)
    );

    for c in CORRUPTIONS {
        let dir = root.join(c.name);
        copy_dir(&clean, &dir);
        (c.apply)(&dir);
        let d = arg(&dir);
        let model = root.join(format!("{}-model", c.name));
        let motion = root.join(format!("{}-motion.safetensors", c.name));
        let what = |command: &str| format!("{command} on {}", c.name);
        refused(
            &["show", &d],
            &root.join("none"),
            c.file,
            c.field,
            &what("show"),
        );
        if c.graphs {
            continue;
        }
        refused(
            &["train", &d, "-o", &arg(&model), "--epochs", "1", "--quiet"],
            &model,
            c.file,
            c.field,
            &what("train"),
        );
        refused(
            &["demonstrate", &d, "-o", &arg(&motion)],
            &motion,
            c.file,
            c.field,
            &what("demonstrate"),
        );
    }
}
