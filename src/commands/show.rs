//! `packwright show`: a readable summary of compiled artifacts.

use crate::Exit;
use crate::cli::ShowArgs;
use packwright_compiler::artifact::*;
use packwright_pipeline::artifacts::CompiledDir;
use sha2::{Digest, Sha256};
use std::fmt::Write;

fn p2(p: [f64; 2]) -> String {
    format!("({:.3}, {:.3})", p[0], p[1])
}

fn p3(p: [f64; 3]) -> String {
    format!("({:.3}, {:.3}, {:.3})", p[0], p[1], p[2])
}

pub fn run(args: &ShowArgs) -> anyhow::Result<Exit> {
    // One reader for every command: the artifacts are checked before
    // anything is shown.
    let compiled = CompiledDir::read(&args.dir)?;
    let graphs = compiled.graphs()?;
    let combinations = compiled.combinations()?;
    let held_out = |block: &str| -> Vec<Vec<String>> {
        combinations
            .iter()
            .filter(|c| c.block == block && !c.kept)
            .map(|c| c.products.clone())
            .collect()
    };
    let (manifest, labels, world, scenarios) = (
        compiled.manifest(),
        compiled.labels(),
        compiled.world(),
        compiled.scenarios(),
    );
    let graphs_sha = format!("{:x}", Sha256::digest(&graphs.bytes));
    let tensors: Vec<(&str, String, Vec<usize>)> = graphs
        .tensors()
        .into_iter()
        .map(|(name, dtype, shape)| (name, format!("{dtype:?}"), shape))
        .collect();
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
                "configurations": b.configurations, "kept_combinations": b.kept_combinations,
                "held_out_combinations": held_out(&b.name), "demonstrations": b.demonstrations, "samples": b.samples,
            })).collect::<Vec<_>>(),
            "graphs_sha256": graphs_sha,
            "tensors": tensors.iter().map(|(name, dtype, shape)| serde_json::json!({"name": name, "dtype": dtype, "shape": shape})).collect::<Vec<_>>(),
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
        // Settings other than their defaults.
        let mut settings = String::new();
        if cell.speed < 1.0 {
            settings += &format!(", speed {} %", (cell.speed * 1e4).round() / 1e2);
        }
        if cell.descent < 1.0 {
            settings += &format!(", descent {} %", (cell.descent * 1e4).round() / 1e2);
        }
        let list = |v: &[f64; 6]| {
            let v: Vec<String> = v.iter().map(f64::to_string).collect();
            format!("({})", v.join(", "))
        };
        if let Some(a) = &cell.acceleration {
            settings += &format!(", acceleration {} rad/s²", list(a));
        }
        if let Some(j) = &cell.jerk {
            settings += &format!(", jerk {} rad/s³", list(j));
        }
        let ms = |s: f64| (s * 1e6).round() / 1e3;
        if cell.grip_settle != default_grip_settle() {
            settings += &format!(", settle {} ms after grip", ms(cell.grip_settle));
        }
        if cell.release_settle != default_release_settle() {
            settings += &format!(", settle {} ms after release", ms(cell.release_settle));
        }
        writeln!(
            o,
            "  {}: robot {robot}, base {}, suction {} m, lift {} m, pending {} to {}{settings}",
            cell.name,
            p3(cell.base),
            cell.suction,
            cell.lift,
            p2(cell.pending.min),
            p2(cell.pending.max),
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
                b.kept_combinations,
                b.kept_combinations + b.held_out_combinations
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
        if b.held_out_combinations > 0 {
            /// Held-out combinations listed per block (`--json` lists all).
            const SHOWN: usize = 20;
            let held: Vec<String> = held_out(&b.name)
                .iter()
                .take(SHOWN)
                .map(|h| h.join(" "))
                .collect();
            let more = b.held_out_combinations.saturating_sub(SHOWN);
            let more = if more > 0 {
                format!(" and {more} more (combinations.jsonl)")
            } else {
                String::new()
            };
            writeln!(o, "    held out: {}{more}", held.join(", "))?;
        }
    }
    writeln!(o, "\ngraphs.safetensors  sha256:{}", &graphs_sha[..16])?;
    for (name, dtype, shape) in &tensors {
        writeln!(o, "  {name:<11} {dtype:<4} {shape:?}")?;
    }
    let g = &graphs.graphs;
    let float = |v: &[f32], k: usize| v.get(k).copied().map_or(0.0, f64::from);
    let m = g.m;
    if g.s > 0 {
        writeln!(o, "  first samples (node: x y z I)")?;
    }
    for i in 0..g.s.min(4) {
        let int = |v: &[i64]| v.get(i).copied().unwrap_or_default();
        let byte = |v: &[u8], k: usize| v.get(k).copied().unwrap_or_default();
        writeln!(
            o,
            "    #{i} demo {} stage {} target {} label {} goal ({:.3}, {:.3}, {:.3})",
            int(&g.demo),
            byte(&g.stage, i),
            int(&g.target),
            int(&g.label),
            float(&g.goal, i * 3),
            float(&g.goal, i * 3 + 1),
            float(&g.goal, i * 3 + 2)
        )?;
        let row: Vec<String> = (0..m)
            .filter(|j| byte(&g.node_mask, i * m + j) > 0)
            .map(|j| {
                let v = |f: usize| float(&g.nodes, (i * m + j) * 4 + f);
                format!("{:.3} {:.3} {:.3} {}", v(0), v(1), v(2), v(3))
            })
            .collect();
        writeln!(o, "       nodes [{}]", row.join(" | "))?;
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
