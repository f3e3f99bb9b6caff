//! `packwright show`: a readable summary of compiled artifacts.

use crate::Exit;
use crate::cli::ShowArgs;
use anyhow::{Context, bail};
use packwright_compiler::artifact::*;
use safetensors::SafeTensors;
use serde::de::DeserializeOwned;
use sha2::{Digest, Sha256};
use std::fmt::Write;
use std::path::Path;

/// The tensors of `graphs.safetensors`, in documented order.
pub const TENSORS: [&str; 8] = tensor::ALL;

fn read_json<T: DeserializeOwned>(dir: &Path, name: &str) -> anyhow::Result<T> {
    let path = dir.join(name);
    let bytes = std::fs::read(&path).with_context(|| format!("cannot read {}", path.display()))?;
    serde_json::from_slice(&bytes)
        .with_context(|| format!("{} is not a packwright artifact", path.display()))
}

struct Tensor {
    name: &'static str,
    dtype: String,
    shape: Vec<usize>,
    /// Values as f64, row-major.
    values: Vec<f64>,
}

fn read_tensors(bytes: &[u8]) -> anyhow::Result<Vec<Tensor>> {
    let st =
        SafeTensors::deserialize(bytes).context("graphs.safetensors is not a safetensors file")?;
    let mut out = Vec::new();
    for name in TENSORS {
        let view = st
            .tensor(name)
            .with_context(|| format!("graphs.safetensors has no tensor `{name}`"))?;
        let data = view.data();
        let values: Vec<f64> = match view.dtype() {
            safetensors::Dtype::F32 => data
                .chunks_exact(4)
                .map(|c| f64::from(f32::from_le_bytes([c[0], c[1], c[2], c[3]])))
                .collect(),
            safetensors::Dtype::I64 => data
                .chunks_exact(8)
                .map(|c| {
                    i64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]]) as f64
                })
                .collect(),
            safetensors::Dtype::U8 => data.iter().map(|&b| f64::from(b)).collect(),
            other => bail!("tensor `{name}` has an unexpected dtype {other:?}"),
        };
        out.push(Tensor {
            name,
            dtype: format!("{:?}", view.dtype()),
            shape: view.shape().to_vec(),
            values,
        });
    }
    Ok(out)
}

fn p2(p: [f64; 2]) -> String {
    format!("({:.3}, {:.3})", p[0], p[1])
}

fn p3(p: [f64; 3]) -> String {
    format!("({:.3}, {:.3}, {:.3})", p[0], p[1], p[2])
}

pub fn run(args: &ShowArgs) -> anyhow::Result<Exit> {
    let dir = &args.dir;
    let manifest: Manifest = read_json(dir, "manifest.json")?;
    let labels: LabelsFile = read_json(dir, "labels.json")?;
    let world: WorldFile = read_json(dir, "orders.json")?;
    let scenarios: ScenariosFile = read_json(dir, "scenarios.json")?;
    if manifest.version != SCHEMA_VERSION {
        bail!(
            "{} was written with schema version {}; this packwright reads version {SCHEMA_VERSION}: compile again",
            dir.display(),
            manifest.version
        );
    }
    let graphs_path = dir.join("graphs.safetensors");
    let graph_bytes = std::fs::read(&graphs_path)
        .with_context(|| format!("cannot read {}", graphs_path.display()))?;
    let tensors = read_tensors(&graph_bytes)?;
    let graphs_sha = format!("{:x}", Sha256::digest(&graph_bytes));
    let suite_stats = |s: &SuiteRecord| {
        (
            s.cases
                .iter()
                .filter(|c| !c.human_packed.is_empty())
                .count(),
            s.cases.iter().filter(|c| !c.missing.is_empty()).count(),
        )
    };
    if args.json {
        let value = serde_json::json!({
            "schema_version": manifest.version,
            "sources": manifest.sources,
            "counts": manifest.counts,
            "labels": labels.cells,
            "orders": world.orders,
            "demo_blocks": manifest.demo_blocks.iter().map(|b| serde_json::json!({
                "name": b.name, "kind": b.kind, "cell": b.cell, "inventory": b.inventory, "order": b.order,
                "configurations": b.configurations, "kept_combinations": b.kept_combinations.len(),
                "held_out_combinations": b.held_out_combinations, "demonstrations": b.demonstrations, "samples": b.samples,
            })).collect::<Vec<_>>(),
            "graphs_sha256": graphs_sha,
            "tensors": tensors.iter().map(|t| serde_json::json!({"name": t.name, "dtype": t.dtype, "shape": t.shape})).collect::<Vec<_>>(),
            "suites": scenarios.suites.iter().map(|s| {
                let (human, missing) = suite_stats(s);
                serde_json::json!({"name": s.name, "kind": s.kind, "cell": s.cell, "inventory": s.inventory, "order": s.order,
                    "seed": s.seed, "cases": s.cases.len(), "cases_with_human_packed": human, "cases_with_missing": missing})
            }).collect::<Vec<_>>(),
        });
        outln!("{}", serde_json::to_string_pretty(&value)?);
        return Ok(Exit::Success);
    }

    let mut o = String::new();
    let c = &manifest.counts;
    writeln!(
        o,
        "compiled artifacts (schema version {})",
        manifest.version
    )?;
    writeln!(o, "\nsources")?;
    for s in &manifest.sources {
        writeln!(
            o,
            "  {}  sha256:{}",
            s.path,
            &s.sha256[..s.sha256.len().min(16)]
        )?;
    }
    writeln!(o, "\ncells")?;
    for (cell, table) in world.cells.iter().zip(&labels.cells) {
        let robot = match &cell.robot {
            RobotRecord::Ur10 => "ur10".to_owned(),
            RobotRecord::Urdf(p) => format!("urdf {p}"),
        };
        writeln!(
            o,
            "  {}: robot {robot}, base {}, suction {} m, lift {} m, pending {} to {}",
            cell.name,
            p3(cell.base),
            cell.suction,
            cell.lift,
            p2(cell.pending.min),
            p2(cell.pending.max)
        )?;
        writeln!(
            o,
            "    {:>5}  {:<10} {:<10} position",
            "label", "name", "box"
        )?;
        for l in &table.labels {
            let bx = l.box_name.as_deref().unwrap_or("");
            let pos = l.position.map(p2).unwrap_or_default();
            writeln!(o, "    {:>5}  {:<10} {:<10} {pos}", l.label, l.name, bx)?;
        }
    }
    writeln!(o, "\norders")?;
    if world.orders.is_empty() {
        writeln!(o, "  (none)")?;
    }
    for ord in &world.orders {
        let mut extra = String::new();
        if let Some(cust) = &ord.customer {
            write!(extra, ", customer {cust:?}")?;
        }
        if let Some(b) = ord.batch {
            write!(extra, ", batch {b}")?;
        }
        writeln!(
            o,
            "  {} for {} (cell {}){extra}",
            ord.name, ord.inventory, ord.cell
        )?;
        for a in &ord.assignment {
            writeln!(
                o,
                "    {} -> {} (label {}), goal {}",
                a.product,
                a.slot,
                a.label,
                p3(a.goal)
            )?;
        }
    }
    writeln!(
        o,
        "\ndemonstrations: {} blocks, {} demonstrations, {} samples",
        c.demo_blocks, c.demonstrations, c.samples
    )?;
    for b in &manifest.demo_blocks {
        let kept = if b.kind == "demos" {
            format!(
                ", combinations kept {}/{}",
                b.kept_combinations.len(),
                b.kept_combinations.len() + b.held_out_combinations.len()
            )
        } else {
            String::new()
        };
        writeln!(
            o,
            "  {} ({} for {}): {} configurations{kept}, {} demonstrations, {} samples",
            b.name,
            b.kind,
            b.order.as_deref().unwrap_or(&b.inventory),
            b.configurations,
            b.demonstrations,
            b.samples
        )?;
        if !b.held_out_combinations.is_empty() {
            let held: Vec<String> = b
                .held_out_combinations
                .iter()
                .map(|h| h.join(" "))
                .collect();
            writeln!(o, "    held out: {}", held.join(", "))?;
        }
    }
    writeln!(o, "\ngraphs.safetensors  sha256:{}", &graphs_sha[..16])?;
    for t in &tensors {
        writeln!(o, "  {:<11} {:<4} {:?}", t.name, t.dtype, t.shape)?;
    }
    let find = |n: &str| tensors.iter().find(|t| t.name == n);
    if let (
        Some(nodes),
        Some(mask),
        Some(goal),
        Some(target),
        Some(label),
        Some(stage),
        Some(demo),
    ) = (
        find("nodes"),
        find("node_mask"),
        find("goal"),
        find("target"),
        find("label"),
        find("stage"),
        find("demo"),
    ) {
        let m = nodes.shape.get(1).copied().unwrap_or(0);
        let s = target.values.len();
        if s > 0 {
            writeln!(o, "  first samples (node: x y z I)")?;
        }
        for i in 0..s.min(4) {
            let g = &goal.values[i * 3..i * 3 + 3];
            writeln!(
                o,
                "    #{i} demo {} stage {} target {} label {} goal ({:.3}, {:.3}, {:.3})",
                demo.values[i],
                stage.values[i],
                target.values[i],
                label.values[i],
                g[0],
                g[1],
                g[2]
            )?;
            let row: Vec<String> = (0..m)
                .filter(|j| mask.values[i * m + j] > 0.0)
                .map(|j| {
                    let v = &nodes.values[(i * m + j) * 4..(i * m + j) * 4 + 4];
                    format!("{:.3} {:.3} {:.3} {}", v[0], v[1], v[2], v[3])
                })
                .collect();
            writeln!(o, "       nodes [{}]", row.join(" | "))?;
        }
    }
    writeln!(o, "\nscenarios: {} suites, {} cases", c.suites, c.scenarios)?;
    for s in &scenarios.suites {
        let (human, missing) = suite_stats(s);
        writeln!(
            o,
            "  {} ({} for {}, seed {}): {} cases, {} with products packed by a worker, {} with missing products",
            s.name,
            s.kind,
            s.order.as_deref().unwrap_or(&s.inventory),
            s.seed,
            s.cases.len(),
            human,
            missing
        )?;
        if let Some(first) = s.cases.first() {
            let assign: Vec<String> = first
                .assignment
                .iter()
                .map(|a| format!("{}->{}", a.product, a.slot))
                .collect();
            let mut line = format!("    {}: {}", first.name, assign.join(" "));
            if !first.human_packed.is_empty() {
                write!(line, "; packed {}", first.human_packed.join(" "))?;
            }
            if !first.missing.is_empty() {
                write!(line, "; missing {}", first.missing.join(" "))?;
            }
            writeln!(o, "{line}")?;
        }
    }
    out!("{o}");
    Ok(Exit::Success)
}
