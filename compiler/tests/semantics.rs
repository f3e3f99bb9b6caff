//! The compiler's documented semantics, on in-memory files.

use packwright_compiler::model::Model;
use packwright_compiler::workspace::{Blocked, Lower, Pose, Released, Standing, Unreached};
use packwright_compiler::{Anywhere, Compiled, Draws, Error, MemoryLoader, Warning, check};
use std::path::PathBuf;

const CELL: &str = "
cell bench {
  robot ur10
  base (0, 0, 0)
  suction 100 mm
  pending (0.45, -0.50) to (0.85, -0.10)
  box tray (0.00, 0.65) size (0.40, 0.30, 0.08)
  slot g1 (-0.12, 0.58)
  slot g2 ( 0.00, 0.58)
  slot g3 ( 0.12, 0.58)
  slot g4 (-0.06, 0.72)
  lift 200 mm
}
product A cube 50 mm
product B cube 50 mm
product C cube 40 mm
product D cube 50 mm
product E box (60 mm, 40 mm, 30 mm)
inventory stock5 for bench {
  A (0.50, -0.20)
  B (0.62, -0.20)
  C (0.74, -0.20)
  D (0.56, -0.38)
  E (0.68, -0.38)
}
";

fn compile(extra: &str) -> Result<Compiled, Vec<Error>> {
    let loader = MemoryLoader::new().with("main.pack", format!("{CELL}\n{extra}"));
    check(&loader, &[PathBuf::from("main.pack")], &Anywhere).map_err(|f| f.errors)
}

fn ok(extra: &str) -> Compiled {
    match compile(extra) {
        Ok(c) => c,
        Err(errors) => panic!("unexpected errors: {errors:#?}"),
    }
}

fn codes(extra: &str) -> Vec<&'static str> {
    compile(extra)
        .err()
        .unwrap_or_default()
        .iter()
        .map(Error::code)
        .collect()
}

#[test]
fn sample_count_is_configurations_times_repeat_times_n_times_two() {
    let c = ok("demos t for stock5 {\n choose 3 of A, B, C, D, E into g1, g2, g3\n repeat 2\n}\n");
    // C(5,3) = 10 combinations x 3! slot assignments = 60 configurations.
    assert_eq!(c.demonstrations().expect("demonstrations").len(), 60 * 2);
    assert_eq!(c.shape.samples, 60 * 2 * 3 * 2);
    assert_eq!(c.shape.width, 5);
    assert_eq!(c.shape.edges(), 8);
}

#[test]
fn slot_lists_longer_than_n_give_injective_assignments() {
    let c = ok("demos t for stock5 {\n choose 2 of A, B, C into g1, g2, g3\n}\n");
    // C(3,2) x 3x2 ordered slot pairs.
    assert_eq!(c.demonstrations().expect("demonstrations").len(), 18);
}

#[test]
fn keep_holds_out_combinations_deterministically() {
    let src =
        "demos t for stock5 {\n choose 3 of A, B, C, D, E into g1, g2, g3\n keep 0.6\n seed 7\n}\n";
    let a = ok(src);
    let block = &a.expanded.blocks[0];
    assert_eq!(block.kept.len(), 6);
    assert_eq!(block.held_out.len(), 4);
    assert_eq!(a.demonstrations().expect("demonstrations").len(), 6 * 6);
    for h in &block.held_out {
        assert!(!block.kept.contains(h));
    }
    let b = ok(src);
    assert_eq!(b.expanded.blocks[0].kept, block.kept);
    let other_seed = ok(&src.replace("seed 7", "seed 8"));
    let kept_sets: Vec<_> = (0..20)
        .map(|s| {
            ok(&src.replace("seed 7", &format!("seed {s}")))
                .expanded
                .blocks[0]
                .kept
                .clone()
        })
        .collect();
    assert!(
        kept_sets.iter().any(|k| *k != block.kept),
        "the seed changes what is kept"
    );
    assert_eq!(other_seed.expanded.blocks[0].kept.len(), 6);
}

#[test]
fn picking_and_placing_samples_follow_the_definition() {
    let c = ok("order o for stock5 {\n C -> g1\n A -> g3\n}\ndemo d for o {\n sequence A, C\n}\n");
    let g = &c.graphs().expect("graphs");
    assert_eq!(g.s, 4);
    let node = |s: usize, n: usize| &g.nodes[(s * g.m + n) * 4..(s * g.m + n) * 4 + 4];
    // Picking A: A at rest, target A's node, label pick.
    assert_eq!((g.stage[0], g.target[0], g.label[0]), (0, 0, 0));
    assert_eq!(node(0, 0), &[0.50, -0.20, 0.025, 1.0]);
    assert_eq!(node(0, 1)[3], 0.0, "B is not selected");
    assert_eq!(&g.goal[0..3], &[0.12, 0.58, 0.025]);
    // Placing A: raised by the lift (200 mm), target M = the box, label of g3.
    assert_eq!((g.stage[1], g.target[1], g.label[1]), (1, 5, 3));
    assert!((node(1, 0)[2] - 0.225).abs() < 1e-6);
    // Picking C: A now rests in g3.
    assert_eq!(node(2, 0), &[0.12, 0.58, 0.025, 1.0]);
    assert_eq!((g.target[2], g.label[2]), (2, 0));
    assert_eq!(&g.goal[6..9], &[-0.12, 0.58, 0.02]);
    assert_eq!(g.label[3], 1);
    assert!(g.node_mask.iter().all(|&m| m == 1));
}

#[test]
fn missing_products_have_no_node_and_are_padded() {
    let c = ok(
        "demos t for stock5 {\n choose 3 of A, B, C, D, E into g1, g2, g3\n missing 1 to 1\n seed 4\n}\n\
         demos full for stock5 {\n choose 1 of A into g1\n}\n",
    );
    let g = &c.graphs().expect("graphs");
    assert_eq!(g.m, 5);
    for (i, d) in c
        .demonstrations()
        .expect("demonstrations")
        .iter()
        .enumerate()
    {
        let (first, n) = g.per_demo[i];
        let present = 5 - d.setup.missing.len();
        assert_eq!(n, d.sequence.len() * 2);
        for s in first..first + n {
            let mask = &g.node_mask[s * g.m..(s + 1) * g.m];
            assert_eq!(mask.iter().filter(|&&m| m == 1).count(), present);
            assert!(
                mask[..present].iter().all(|&m| m == 1),
                "present nodes come first"
            );
        }
        assert!(d.sequence.iter().all(|e| !d.setup.missing.contains(e)));
    }
    assert!(
        c.demonstrations()
            .expect("demonstrations")
            .iter()
            .any(|d| d.setup.missing.len() == 1)
    );
}

#[test]
fn sequence_modes() {
    let c = ok(
        "demos asc for stock5 {\n choose 3 of E, A, C into g1, g2, g3\n sequence ascending\n}\n\
         demos desc for stock5 {\n choose 3 of E, A, C into g1, g2, g3\n sequence descending\n}\n\
         demos lst for stock5 {\n choose 3 of E, A, C into g1, g2, g3\n sequence listed\n}\n\
         demos rnd for stock5 {\n choose 3 of E, A, C into g1, g2, g3\n sequence random\n seed 1\n}\n",
    );
    let seq = |block: usize| {
        let b = &c.expanded.blocks[block];
        c.demonstrations().expect("demonstrations")[b.first_demo..b.first_demo + b.demos]
            .iter()
            .map(|d| d.sequence.clone())
            .collect::<Vec<_>>()
    };
    // Entries: A=0, C=2, E=4.
    assert!(seq(0).iter().all(|s| *s == [0, 2, 4]));
    assert!(seq(1).iter().all(|s| *s == [4, 2, 0]));
    assert!(seq(2).iter().all(|s| *s == [4, 0, 2]));
    let random = seq(3);
    assert!(
        random.iter().any(|s| *s != random[0]),
        "a random order varies"
    );
}

#[test]
fn jitter_stays_in_bounds_and_apart() {
    let c = ok(
        "scenarios s for stock5 {\n choose 3 of A, B, C, D, E into g1, g2, g3\n jitter 20 mm\n count 200\n seed 5\n}\n",
    );
    let m = &c.model;
    let inv = &m.inventories[0];
    let pending = m.cells[0].pending;
    let suite = &c.expanded.suites[0];
    assert_eq!(suite.cases.len(), 200);
    let mut moved = false;
    for case in &suite.cases {
        let fps: Vec<_> = inv
            .entries
            .iter()
            .enumerate()
            .map(|(i, e)| {
                let p = case.setup.positions[i];
                assert!(
                    (p[0] - e.at[0]).abs() <= 0.020 + 1e-12
                        && (p[1] - e.at[1]).abs() <= 0.020 + 1e-12
                );
                moved |= p != e.at;
                m.products[e.product].footprint(p)
            })
            .collect();
        for (i, a) in fps.iter().enumerate() {
            assert_eq!(pending.excess(a), 0.0);
            for b in &fps[..i] {
                assert!(!a.overlaps(b));
            }
        }
        assert_eq!(case.setup.assignment.len(), 3);
    }
    assert!(moved);
}

#[test]
fn scenario_ranges_are_respected() {
    let c = ok(
        "scenarios s for stock5 {\n choose 4 of A, B, C, D, E into g1, g2, g3, g4\n human packs 1 to 2\n missing 0 to 1\n count 300\n seed 12\n}\n",
    );
    let cases = &c.expanded.suites[0].cases;
    let mut seen = std::collections::BTreeSet::new();
    for case in cases {
        let s = &case.setup;
        assert!((1..=2).contains(&s.human_packed.len()));
        assert!(s.missing.len() <= 1);
        for e in s.human_packed.iter().chain(&s.missing) {
            assert!(
                s.slot_of(*e).is_some(),
                "only selected products are packed or missing"
            );
        }
        assert!(s.human_packed.iter().all(|e| !s.missing.contains(e)));
        seen.insert((s.human_packed.len(), s.missing.len()));
    }
    assert_eq!(
        seen.len(),
        4,
        "every combination of counts occurs in 300 draws"
    );
}

#[test]
fn every_independent_error_is_reported() {
    let got = codes(
        "order o for stock5 {\n A -> g1\n B -> g1\n F -> g2\n}\n\
         demos t for stock5 {\n choose 6 of A, B into g1\n keep 1.5\n}\n\
         scenarios s for stok5 {\n count 3\n}\n",
    );
    for code in ["E032", "E021", "E040", "E042"] {
        assert!(got.contains(&code), "{code} missing from {got:?}");
    }
    assert!(got.len() >= 5, "{got:?}");
}

#[test]
fn unknown_names_suggest_close_ones() {
    let errors = compile("order o for stok5 {\n A -> g1\n}\n")
        .err()
        .unwrap_or_default();
    match errors.first() {
        Some(Error::Unknown { suggestion, .. }) => {
            assert_eq!(suggestion.as_deref(), Some("stock5"))
        }
        other => panic!("expected an unknown-name error, got {other:?}"),
    }
}

#[test]
fn a_use_is_relative_to_the_using_file_and_loaded_once() {
    let loader = MemoryLoader::new()
        .with("cells/bench.pack", CELL)
        .with(
            "orders/a.pack",
            "use \"../cells/bench.pack\"\norder a for stock5 {\n A -> g1\n}\n",
        )
        .with(
            "orders/b.pack",
            "use \"../cells/./bench.pack\"\norder b for stock5 {\n B -> g1\n}\n",
        );
    let c = check(
        &loader,
        &[
            PathBuf::from("orders/a.pack"),
            PathBuf::from("orders/b.pack"),
        ],
        &Anywhere,
    )
    .expect("compiles");
    assert_eq!(c.sources.files().count(), 3);
    assert_eq!(c.model.cells.len(), 1);
}

#[test]
fn geometry_checks() {
    assert_eq!(
        codes("product Z cube 50 mm\ninventory i for bench {\n Z (0.46, -0.20)\n}\n"),
        ["E034"]
    );
    assert_eq!(
        codes(
            "product Z cube 50 mm\nproduct Y cube 50 mm\ninventory i for bench {\n Z (0.60, -0.20)\n Y (0.63, -0.20)\n}\n"
        ),
        ["E035"]
    );
    assert_eq!(
        codes(
            "product Z box (300 mm, 40 mm, 30 mm)\ninventory i for bench {\n Z (0.65, -0.20)\n}\norder o for i {\n Z -> g1\n}\n"
        ),
        ["E037"]
    );
}

/// The streamed artifacts say what the demonstrations held in memory say:
/// `graphs.safetensors` written a chunk at a time (here more than one
/// chunk, with missing products so rows differ in width) equals the
/// `safetensors` crate's serialisation of every sample built at once, and
/// `demonstrations.jsonl` has one line per demonstration with its samples.
#[test]
fn streamed_artifacts_equal_the_dataset_built_in_memory() {
    use packwright_compiler::artifact::DemonstrationRecord;
    use packwright_compiler::{MemoryOutput, emit, file};
    let c = ok(
        "demos t for stock5 {\n choose 3 of A, B, C, D, E into g1, g2, g3, g4\n missing 0 to 1\n repeat 5\n seed 9\n}\n",
    );
    let demos = c.demonstrations().expect("demonstrations");
    assert_eq!(demos.len(), 10 * 24 * 5);
    assert!(demos.len() > emit::CHUNK);
    let out = MemoryOutput::new();
    emit::emit(&c.sources, &c.model, &c.expanded, c.shape, &out).expect("emitted");
    let artifacts = out.artifacts();
    let bytes = |name: &str| {
        artifacts
            .iter()
            .find(|a| a.name == name)
            .map(|a| a.bytes.clone())
            .expect(name)
    };
    let g = c.graphs().expect("graphs");
    assert_eq!(g.s, c.shape.samples);
    assert_eq!(
        bytes(file::GRAPHS),
        emit::graphs_bytes(&g).expect("serialised")
    );
    let lines = bytes(file::DEMONSTRATIONS);
    let records: Vec<DemonstrationRecord> = lines
        .split(|&b| b == b'\n')
        .filter(|l| !l.is_empty())
        .map(|l| serde_json::from_slice(l).expect("a record"))
        .collect();
    assert_eq!(records.len(), demos.len());
    for (i, (r, d)) in records.iter().zip(&demos).enumerate() {
        assert_eq!((r.first_sample, r.samples), g.per_demo[i]);
        assert_eq!(r.missing.len(), d.setup.missing.len());
        assert_eq!(r.sequence.len(), d.sequence.len());
    }
}

/// A workspace where the standing products block: the start meets `D`;
/// picking `A` meets `B` while it stands. Records each pick asked among
/// standing products, with the margins it was given.
struct Crowded {
    asked: std::cell::RefCell<Vec<(String, Vec<f64>)>>,
}

impl packwright_compiler::Workspace for Crowded {
    fn start(&self, _: &Model, _: usize) -> Option<Unreached> {
        None
    }
    fn pick(&self, _: &Model, _: usize, _: usize, _: [f64; 2]) -> Option<Unreached> {
        None
    }
    fn place(
        &self,
        _: &Model,
        _: usize,
        _: usize,
        _: [f64; 2],
        _: usize,
    ) -> Result<Released, Unreached> {
        Ok(Released::default())
    }
    fn start_among(&self, m: &Model, _: usize, standing: &[Standing]) -> Option<usize> {
        standing
            .iter()
            .position(|s| m.products[s.product].name == "D")
    }
    fn pick_among(
        &self,
        m: &Model,
        _: usize,
        product: usize,
        _: [f64; 2],
        standing: &[Standing],
    ) -> Option<Blocked> {
        let name = &m.products[product].name;
        self.asked
            .borrow_mut()
            .push((name.clone(), standing.iter().map(|s| s.margin).collect()));
        let b = standing
            .iter()
            .position(|s| m.products[s.product].name == "B")?;
        (name == "A").then_some(Blocked {
            pose: Pose::TopFace,
            by: Some(b),
        })
    }
}

fn crowded(extra: &str) -> Result<Compiled, Vec<Error>> {
    let loader = MemoryLoader::new().with("main.pack", format!("{CELL}\n{extra}"));
    let ws = Crowded {
        asked: Default::default(),
    };
    check(&loader, &[PathBuf::from("main.pack")], &ws).map_err(|f| f.errors)
}

/// What standing products block: a start every branch of which meets one
/// is an error at that product's entry; a pick they block is a warning at
/// the picked product's entry naming the one met; only picks something
/// asks for are asked about, each among the others of its inventory,
/// widened by the largest `jitter` of the blocks on that inventory.
#[test]
fn standing_products_block_the_start_as_an_error_and_a_pick_as_a_warning() {
    let errors = crowded("order o for stock5 {\n A -> g1\n}\n").expect_err("the start is blocked");
    assert_eq!(errors.len(), 1, "{errors:#?}");
    let Error::StartBlocked { by, at, .. } = &errors[0] else {
        panic!("{errors:#?}")
    };
    assert_eq!(by, "D");
    // D's entry: the fourth line of the inventory.
    let d = CELL.find("  D (0.56").expect("D's entry") + 2;
    assert_eq!(at.span.start as usize, d);

    let no_d = CELL.replace("  D (0.56, -0.38)\n", "");
    let loader = MemoryLoader::new().with(
        "main.pack",
        format!(
            "{no_d}\norder o for stock5 {{\n A -> g1\n B -> g2\n}}\n\
             scenarios s for stock5 {{\n choose 1 of A, B into g1, g2\n jitter 5 mm\n count 4\n}}\n\
             demos t for stock5 {{\n choose 1 of A, B into g1, g2\n jitter 8 mm\n}}\n"
        ),
    );
    let ws = Crowded {
        asked: Default::default(),
    };
    let c = match check(&loader, &[PathBuf::from("main.pack")], &ws) {
        Ok(c) => c,
        Err(f) => panic!("{:#?}", f.errors),
    };
    assert_eq!(c.warnings.len(), 1, "{:#?}", c.warnings);
    let Warning::PickBlocked {
        product, by, pose, ..
    } = &c.warnings[0]
    else {
        panic!("a blocked pick: {:#?}", c.warnings);
    };
    assert_eq!((product.as_str(), *pose), ("A", Pose::TopFace));
    assert_eq!(by.as_ref().map(|b| b.0.as_str()), Some("B"));
    // The message says B was asked about anywhere the jitter may put it;
    // A is blocked with B where written too.
    let message = c.warnings[0].to_string();
    assert!(
        message.ends_with("or up to 8 mm from there (the jitter of its inventory's blocks)"),
        "{message}"
    );
    assert!(matches!(
        c.warnings[0],
        Warning::PickBlocked {
            where_written: true,
            ..
        }
    ));
    let asked = ws.asked.into_inner();
    // W001's questions come first (A's pick asked again with the others
    // where written, once it is blocked within the jitter); then W003's,
    // about the suite's picks (at the written places with the others
    // widened by its 5 mm jitter and by twice that: B is blocked by
    // neither, A already by W001, so no scenario is asked about), and the
    // same about the `demos` block's, at its 8 mm.
    let (w001, draws) = asked.split_at(asked.len().min(3));
    let names: Vec<&str> = w001.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["A", "A", "B"], "C and E are packed by nothing");
    assert!(
        w001[1].1.iter().all(|&m| m == 0.0),
        "A asked again where written: {:?}",
        w001[1].1
    );
    let w001 = [&w001[0], &w001[2]];
    let draws: Vec<(&str, f64)> = draws
        .iter()
        .map(|(n, m)| (n.as_str(), m.first().copied().unwrap_or(f64::NAN)))
        .collect();
    assert_eq!(
        draws,
        [
            ("A", 0.005),
            ("B", 0.005),
            ("B", 0.01),
            ("A", 0.008),
            ("B", 0.008),
            ("B", 0.016)
        ]
    );
    for (_, margins) in w001 {
        assert_eq!(margins.len(), 3, "the other three of the four entries");
        assert!(
            margins.iter().all(|m| (m - 0.008).abs() < 1e-12),
            "{margins:?}"
        );
    }
}

/// A workspace where picking `A` is blocked by `B` standing nearer than
/// 114.9 mm along x (B's footprint widened by its margin); everything else
/// is free.
struct Near;

/// How near (m, along x) `B` blocks the pick of `A` in [`Near`].
const NEAR: f64 = 0.1149;

impl packwright_compiler::Workspace for Near {
    fn start(&self, _: &Model, _: usize) -> Option<Unreached> {
        None
    }
    fn pick(&self, _: &Model, _: usize, _: usize, _: [f64; 2]) -> Option<Unreached> {
        None
    }
    fn place(
        &self,
        _: &Model,
        _: usize,
        _: usize,
        _: [f64; 2],
        _: usize,
    ) -> Result<Released, Unreached> {
        Ok(Released::default())
    }
    fn pick_among(
        &self,
        m: &Model,
        _: usize,
        product: usize,
        at: [f64; 2],
        standing: &[Standing],
    ) -> Option<Blocked> {
        if m.products[product].name != "A" {
            return None;
        }
        let b = standing.iter().position(|s| {
            m.products[s.product].name == "B" && (s.at[0] - at[0]).abs() - s.margin < NEAR
        })?;
        Some(Blocked {
            pose: Pose::TopFace,
            by: Some(b),
        })
    }
}

/// W003: A and B stand 120 mm apart, and the suite jitters them by 5 mm:
/// W001 (B widened by 5 mm, A where it is written) passes, but a draw can
/// bring the two up to 10 mm nearer. The warning names exactly the
/// scenarios where A is picked while B stands nearer than the workspace
/// allows: B packed after A (the blocks declare ascending). Declaring
/// descending, B is packed first and gone: no warning.
#[test]
fn a_pick_the_suites_draws_block_is_a_warning_naming_those_scenarios() {
    let demos = |mode: &str| {
        format!("demos t for stock5 {{\n choose 2 of A, B, C into g1, g2\n sequence {mode}\n}}\n")
    };
    // Nothing demonstrating the inventory: packed in inventory order.
    for (demos, b_packed_first) in [
        (demos("ascending"), false),
        (demos("descending"), true),
        (String::new(), false),
    ] {
        let mode = demos.lines().nth(2).unwrap_or("no demonstrations");
        let loader = MemoryLoader::new().with(
            "main.pack",
            format!(
                "{CELL}\n{demos}\
                 scenarios s for stock5 {{\n choose 2 of A, B, C into g1, g2, g3\n jitter 5 mm\n count 60\n seed 3\n}}\n"
            ),
        );
        let c = match check(&loader, &[PathBuf::from("main.pack")], &Near) {
            Ok(c) => c,
            Err(f) => panic!("{:#?}", f.errors),
        };
        // The scenarios that should be named, from the expanded draws.
        let suite = &c.expanded.suites[0];
        let (a, b) = (0, 1);
        let expected: Vec<String> = suite
            .cases
            .iter()
            .filter(|case| {
                let s = &case.setup;
                let b_gone = s.slot_of(b).is_some() && b_packed_first;
                s.slot_of(a).is_some()
                    && !b_gone
                    && (s.positions[b][0] - s.positions[a][0]).abs() < NEAR
            })
            .map(|case| case.name.rsplit('/').next().unwrap_or("").to_owned())
            .collect();
        // Only the products a scenario packs are drawn off their places:
        // A is blocked only where B is packed too, after A (ascending).
        assert_eq!(expected.is_empty(), b_packed_first, "{mode}: {expected:?}");
        let named: Vec<&Vec<String>> = c
            .warnings
            .iter()
            .filter_map(|w| match w {
                Warning::DrawnPickBlocked {
                    product, by, cases, ..
                } if product == "A" && by == "B" => Some(cases),
                _ => None,
            })
            .collect();
        let want: Vec<&Vec<String>> = Some(&expected)
            .filter(|e| !e.is_empty())
            .into_iter()
            .collect();
        assert_eq!(named, want, "{mode}: {:#?}", c.warnings);
        assert!(
            c.warnings.iter().all(|w| w.code() == "W003"),
            "{mode}: W001 passes: {:#?}",
            c.warnings
        );
    }
}

/// W003 for single `scenario` blocks, whose order hand-written `demo`s
/// teach (helper U's cell 6407: a flat product picked while a heavy cube
/// drawn 19 mm from it still stood, every planner failed, and `check` was
/// silent). Each scenario is one draw of the order `o` (A and B); a demo
/// packing A first leaves B standing at A's pick: the warning names each
/// scenario where the draw brings them nearer than the workspace allows,
/// one warning per scenario. A demo packing B first: no warning; two
/// demos that disagree do not say, and a product that may be gone is not
/// asked about: no warning either.
#[test]
fn a_single_scenario_the_draw_blocks_is_a_warning_with_the_order_hand_written_demos_teach() {
    let scenarios: String = (1..=30)
        .map(|i| format!("scenario s{i:02} for o {{\n jitter 5 mm\n seed {i}\n}}\n"))
        .collect();
    let demo = |name: &str, first: &str, then: &str| {
        format!("demo {name} for o {{\n sequence {first}, {then}\n}}\n")
    };
    for (demos, b_stands) in [
        (demo("d", "A", "B"), true),
        (demo("d", "B", "A"), false),
        (demo("d", "A", "B") + &demo("e", "B", "A"), false),
    ] {
        let loader = MemoryLoader::new().with(
            "main.pack",
            format!("{CELL}\norder o for stock5 {{\n A -> g1\n B -> g2\n}}\n{demos}{scenarios}"),
        );
        let c = match check(&loader, &[PathBuf::from("main.pack")], &Near) {
            Ok(c) => c,
            Err(f) => panic!("{:#?}", f.errors),
        };
        let (a, b) = (0, 1);
        let expected: Vec<String> = c
            .expanded
            .suites
            .iter()
            .filter(|suite| suite.kind == "scenario")
            .filter(|suite| {
                let s = &suite.cases[0].setup;
                b_stands && (s.positions[b][0] - s.positions[a][0]).abs() < NEAR
            })
            .map(|suite| suite.name.clone())
            .collect();
        // Some draws, not all: the 120 mm between them shrinks by up to 10.
        assert_eq!(expected.is_empty(), !b_stands, "{demos}: {expected:?}");
        assert!(expected.len() < 30, "{expected:?}");
        let named: Vec<String> = c
            .warnings
            .iter()
            .filter_map(|w| match w {
                Warning::DrawnPickBlocked {
                    product,
                    by,
                    suite,
                    draws: Draws::Scenario,
                    ..
                } if product == "A" && by == "B" => Some(suite.clone()),
                _ => None,
            })
            .collect();
        assert_eq!(named, expected, "{demos}: {:#?}", c.warnings);
        let first = c.warnings.iter().find(|w| w.code() == "W003");
        if let Some(w) = first {
            assert!(w.to_string().starts_with("in scenario `s"), "{w}");
        }
    }
}

/// W003 for a `demos` block's draws (the repository's sauce row: `train`
/// could not replay demonstrations 12 and 46, the mustard picked while
/// the chili drawn beside it stood, and `check` was silent). Each
/// demonstration's own sequence says what stands: A picked first leaves
/// B standing. The warning names, by the numbers `train` gives them
/// (among all the file's demonstrations, from 1: the hand-written one
/// first), exactly the demonstrations where the draw brings B nearer
/// than the workspace allows while A is picked.
#[test]
fn a_demonstration_the_draw_blocks_is_a_warning_numbered_as_train_numbers_it() {
    let loader = MemoryLoader::new().with(
        "main.pack",
        format!(
            "{CELL}\norder o for stock5 {{\n A -> g1\n C -> g2\n}}\ndemo seen for o {{\n sequence A, C\n}}\n\
             demos t for stock5 {{\n choose 2 of A, B into g1, g2, g3\n sequence ascending\n jitter 5 mm\n repeat 5\n seed 4\n}}\n"
        ),
    );
    let c = match check(&loader, &[PathBuf::from("main.pack")], &Near) {
        Ok(c) => c,
        Err(f) => panic!("{:#?}", f.errors),
    };
    let demos = c.demonstrations().expect("demonstrations");
    assert_eq!(demos.len(), 1 + 6 * 5);
    let (a, b) = (0, 1);
    let expected: Vec<String> = demos
        .iter()
        .enumerate()
        .filter(|(_, d)| {
            let place = |e: usize| d.sequence.iter().position(|&x| x == e);
            let b_stands = match (place(a), place(b)) {
                (Some(pa), Some(pb)) => pa < pb,
                _ => false,
            };
            b_stands && (d.setup.positions[b][0] - d.setup.positions[a][0]).abs() < NEAR
        })
        .map(|(i, _)| (i + 1).to_string())
        .collect();
    assert!(!expected.is_empty() && expected.len() < 30, "{expected:?}");
    let named: Vec<&Vec<String>> = c
        .warnings
        .iter()
        .filter_map(|w| match w {
            Warning::DrawnPickBlocked {
                product,
                by,
                cases,
                draws: Draws::Demonstrations,
                ..
            } if product == "A" && by == "B" => Some(cases),
            _ => None,
        })
        .collect();
    assert_eq!(named, vec![&expected], "{:#?}", c.warnings);
    let w = c
        .warnings
        .iter()
        .find(|w| w.code() == "W003")
        .expect("W003");
    assert!(
        w.to_string().starts_with(&format!(
            "in {} of 30 demonstrations of `t` (",
            expected.len()
        )),
        "{w}"
    );
}

/// A workspace that lets every product go `DEEP` above the floor in slot
/// `g4` and at the usual 5 mm elsewhere.
struct Deep;

const DEEP: f64 = 0.09;

impl packwright_compiler::Workspace for Deep {
    fn start(&self, _: &Model, _: usize) -> Option<Unreached> {
        None
    }
    fn pick(&self, _: &Model, _: usize, _: usize, _: [f64; 2]) -> Option<Unreached> {
        None
    }
    fn place(
        &self,
        m: &Model,
        cell: usize,
        _: usize,
        _: [f64; 2],
        slot: usize,
    ) -> Result<Released, Unreached> {
        let deep = m.cells[cell].slots[slot].name == "g4";
        Ok(Released {
            drop: Some(if deep { DEEP } else { 0.005 }),
            lower: deep.then(|| Lower::ArmOnBox("wrist_3_link".into())),
        })
    }
}

/// A workspace where `B`, standing, blocks the approach of `A` to slots
/// `g1` and `g2`, and `A`, standing, that of `B` to `g2`; everything else
/// is free. Records the placings asked about.
struct InTheWay {
    asked: std::cell::RefCell<Vec<(String, String)>>,
}

impl packwright_compiler::Workspace for InTheWay {
    fn start(&self, _: &Model, _: usize) -> Option<Unreached> {
        None
    }
    fn pick(&self, _: &Model, _: usize, _: usize, _: [f64; 2]) -> Option<Unreached> {
        None
    }
    fn place(
        &self,
        _: &Model,
        _: usize,
        _: usize,
        _: [f64; 2],
        _: usize,
    ) -> Result<Released, Unreached> {
        Ok(Released::default())
    }
    fn place_among(
        &self,
        m: &Model,
        _: usize,
        product: usize,
        _: [f64; 2],
        slot: usize,
        standing: &[Standing],
    ) -> Option<Blocked> {
        let name = m.products[product].name.as_str();
        let slot = m.cells[0].slots[slot].name.as_str();
        self.asked
            .borrow_mut()
            .push((name.to_owned(), slot.to_owned()));
        let met = match (name, slot) {
            ("A", "g1" | "g2") => "B",
            ("B", "g2") => "A",
            _ => return None,
        };
        let by = standing
            .iter()
            .position(|s| m.products[s.product].name == met)?;
        Some(Blocked {
            pose: Pose::Approach,
            by: Some(by),
        })
    }
}

/// W007: a placing the empty cell allows that a product standing blocks
/// is a warning at what asked for it, naming the product met and every
/// slot blocked alike (one warning per product, pose and product met);
/// two products each in the other's way say so, since packing either
/// first can stop the other. Only placings something asks for are asked
/// about, each among the others of its inventory.
#[test]
fn a_placing_a_standing_product_blocks_is_a_warning_naming_its_slots() {
    let loader = MemoryLoader::new().with(
        "main.pack",
        format!(
            "{CELL}\norder o for stock5 {{\n A -> g1\n C -> g3\n}}\n\
             scenarios s for stock5 {{\n choose 2 of A, B into g1, g2\n count 4\n}}\n"
        ),
    );
    let ws = InTheWay {
        asked: Default::default(),
    };
    let c = match check(&loader, &[PathBuf::from("main.pack")], &ws) {
        Ok(c) => c,
        Err(f) => panic!("{:#?}", f.errors),
    };
    let mut asked = ws.asked.into_inner();
    asked.sort();
    asked.dedup();
    let asked: Vec<(&str, &str)> = asked
        .iter()
        .map(|(p, s)| (p.as_str(), s.as_str()))
        .collect();
    assert_eq!(
        asked,
        [
            ("A", "g1"),
            ("A", "g2"),
            ("B", "g1"),
            ("B", "g2"),
            ("C", "g3")
        ]
    );
    let blocked: Vec<_> = c
        .warnings
        .iter()
        .filter_map(|w| match w {
            Warning::PlaceBlocked {
                product,
                slots,
                pose: Pose::Approach,
                by,
                by_packed,
                mutual,
                ..
            } => Some((
                product.as_str(),
                slots.as_slice(),
                by.as_ref().map(|b| b.0.as_str()),
                *by_packed,
                *mutual,
            )),
            _ => None,
        })
        .collect();
    let (g1_g2, g2) = (["g1".to_owned(), "g2".to_owned()], ["g2".to_owned()]);
    assert_eq!(
        blocked,
        [
            ("A", &g1_g2[..], Some("B"), true, true),
            ("B", &g2[..], Some("A"), true, true)
        ],
        "{:#?}",
        c.warnings
    );
    assert!(c.warnings.iter().all(|w| w.code() == "W007"));
    // At what asked first: the order's assignment `A -> g1`.
    let a = c.warnings[0].at();
    let text = format!("{CELL}\n");
    assert_eq!(
        a.span.start as usize,
        text.len() + "order o for stock5 {\n ".len()
    );
    let message = c.warnings[0].to_string();
    assert!(
        message.contains("puts product `A` (picked at (0.500, -0.200)) in slots `g1` and `g2` while `B` stands at (0.620, -0.200)"),
        "{message}"
    );
    assert!(
        c.warnings[0]
            .help()
            .contains("packing either first can stop the other")
    );
}

/// W004: a product over twice as tall as its narrow side, dropped more
/// than twice that side, is warned about once per box, at its highest
/// drop, with the cup that would let it down; a cube dropped as far, or
/// a tall product let go low, is not.
#[test]
fn a_tall_narrow_product_dropped_high_is_warned_about_once() {
    let cell = CELL.replace(
        "product E box (60 mm, 40 mm, 30 mm)",
        "product E box (60 mm, 40 mm, 30 mm)\nproduct T box (30 mm, 40 mm, 100 mm)",
    );
    let cell = cell.replace(
        "  E (0.68, -0.38)\n",
        "  E (0.68, -0.38)\n  T (0.80, -0.38)\n",
    );
    let warned = |extra: &str| {
        let loader = MemoryLoader::new().with("main.pack", format!("{cell}\n{extra}"));
        match check(&loader, &[PathBuf::from("main.pack")], &Deep) {
            Ok(c) => c.warnings,
            Err(f) => panic!("{:#?}", f.errors),
        }
    };
    let w = warned(
        "scenarios s for stock5 {\n choose 2 of A, T into g1, g2, g4\n count 2\n}\n\
         order o for stock5 {\n T -> g4\n A -> g1\n}\n",
    );
    assert_eq!(w.len(), 1, "{w:#?}");
    let Warning::DroppedHigh {
        product,
        slot,
        drop_mm,
        ..
    } = &w[0]
    else {
        panic!("a drop: {w:#?}");
    };
    assert_eq!((product.as_str(), slot.as_str()), ("T", "g4"));
    assert!((drop_mm - 90.0).abs() < 1e-9);
    assert_eq!(w[0].code(), "W004");
    assert!(
        w[0].help()
            .contains("`wrist_3_link` meets box `tray`: a longer suction cup"),
        "{}",
        w[0].help()
    );
    // Let go at 5 mm, or a cube: nothing to say.
    assert!(warned("order o for stock5 {\n T -> g1\n A -> g4\n}\n").is_empty());
}
