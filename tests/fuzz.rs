//! In-process fuzzing of the parser, the compiler, `draw` and the artifact
//! reader (issue 14): seeded mutations of every `.pack` file in `orders/`
//! and `tests/cases/` go through `parse`, `format` (idempotent on its own
//! output), `check` and `compile`; every one that resolves has each of its
//! cells, inventories and orders drawn as `packwright draw` draws them
//! (diagnostics and all: `draw` shows invalid geometry rather than refuse
//! it); a share of those that compile have one artifact file mutated and
//! read back by `CompiledDir::read` and `graphs()`. Every input must end in a result or an error, never a panic,
//! within a time bound. A failing input is written to
//! `target/fuzz-failures/` with its seed.
//!
//! A watchdog thread sees every input in flight: one still running after
//! [`HANG`] (a real hang would never return to be timed) is saved and the
//! process ends with its description, instead of the test blocking.
//!
//! `fuzz_short` runs in every `cargo test`; the long run is
//! `cargo test --release --test fuzz -- --ignored --nocapture`
//! (`FUZZ_INPUTS`, default 1,000,000, and `FUZZ_SEED`).
//!
//! The compiler is asked with `Anywhere` (no robot reach questions): the
//! reach check is the robot half's and is property-tested in
//! `tests/reach.rs`.

#[allow(dead_code)] // only `root` is used here
mod common;

use packwright::commands::draw::{Subject, picture_of};
use packwright_compiler::{Anywhere, MemoryLoader, load, resolve, validate};
use packwright_pipeline::artifacts::CompiledDir;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use std::fs;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// The longest one input may take (debug builds included), beyond the
/// time its generated data takes ([`PER_SAMPLE`], [`PER_CASE`]).
const BOUND: Duration = Duration::from_secs(5);

/// Time allowed per dataset sample a compiled input generates: a valid
/// file may ask for up to a million demonstrations and scenarios (E048),
/// whose compile takes seconds (release: 1.6 µs per sample and 12 µs per
/// scenario case measured on the two such inputs seed 25 found).
const PER_SAMPLE: Duration = Duration::from_micros(5);

/// Time allowed per scenario case a compiled input generates.
const PER_CASE: Duration = Duration::from_micros(40);

/// An input still running after this long is taken for a hang: the
/// watchdog saves it and ends the process.
const HANG: Duration = Duration::from_secs(60);

/// One compiled input in this many has an artifact mutated and read back.
const READ_BACK_EVERY: u64 = 4;

/// Words and punctuation of the language, for insertions.
const TOKENS: &[&str] = &[
    "cell",
    "robot",
    "ur10",
    "urdf",
    "base",
    "suction",
    "lift",
    "pending",
    "box",
    "slot",
    "size",
    "product",
    "cube",
    "mass",
    "inventory",
    "for",
    "order",
    "customer",
    "batch",
    "demo",
    "demos",
    "sequence",
    "at",
    "scenario",
    "scenarios",
    "human",
    "packed",
    "packs",
    "missing",
    "jitter",
    "seed",
    "choose",
    "of",
    "into",
    "keep",
    "repeat",
    "count",
    "use",
    "ascending",
    "descending",
    "random",
    "to",
    "->",
    "{",
    "}",
    "(",
    ")",
    ",",
    "\"",
    "#",
    "mm",
    "cm",
    "m",
    "kg",
    "%",
    "\n",
];

/// Numbers that stress the checks; the large counts are above the
/// generation limit (E047), so that they are refused, not generated.
const NUMBERS: &[&str] = &[
    "1e308",
    "-0",
    "NaN",
    "inf",
    "999999999999",
    "0.0000001",
    "-1",
    "0",
    "18446744073709551616",
    "1e-320",
    "3.",
    ".5",
    "1_000",
];

/// Every `.pack` file below `dirs`, repo-relative path and text.
fn corpus() -> Vec<(PathBuf, String)> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        for e in fs::read_dir(dir).into_iter().flatten().flatten() {
            let p = e.path();
            if p.is_dir() {
                walk(&p, out);
            } else if p.extension().is_some_and(|x| x == "pack") {
                out.push(p);
            }
        }
    }
    let root = common::root();
    let mut paths = Vec::new();
    for dir in ["orders", "tests/cases"] {
        walk(&root.join(dir), &mut paths);
    }
    paths.sort();
    paths
        .into_iter()
        .filter_map(|p| {
            let text = fs::read_to_string(&p).ok()?;
            Some((p.strip_prefix(root).ok()?.to_path_buf(), text))
        })
        .collect()
}

fn boundary(s: &str, at: usize) -> usize {
    let mut i = at.min(s.len());
    while !s.is_char_boundary(i) {
        i -= 1;
    }
    i
}

fn pick<'a>(rng: &mut ChaCha8Rng, items: &[&'a str]) -> &'a str {
    items[rng.random_range(0..items.len())]
}

/// One mutation of `text` (another corpus file `other` for splices). Text
/// that is not UTF-8 cannot reach the compiler (`Loader` returns text; the
/// file-system loader refuses it as "not UTF-8 text", `tests/reliability.rs`),
/// so byte-level damage is made of characters: NUL, replacement
/// characters, wide characters.
fn mutate(rng: &mut ChaCha8Rng, text: &str, other: &str) -> String {
    let mut s = text.to_owned();
    for _ in 0..rng.random_range(1..=3) {
        let at = boundary(&s, rng.random_range(0..=s.len()));
        match rng.random_range(0..10) {
            0 => {
                let end = boundary(&s, at + rng.random_range(1..8));
                s.replace_range(at..end, "");
            }
            1 => s.insert_str(at, &format!(" {} ", pick(rng, TOKENS))),
            2 => {
                let cut = boundary(other, rng.random_range(0..=other.len()));
                s = format!("{}{}", &s[..at], &other[cut..]);
            }
            3 => {
                let lines: Vec<&str> = s.lines().collect();
                if !lines.is_empty() {
                    let (a, b) = (
                        rng.random_range(0..lines.len()),
                        rng.random_range(0..lines.len()),
                    );
                    let mut out: Vec<&str> = lines.clone();
                    match rng.random_range(0..3) {
                        0 => out.swap(a, b),
                        1 => out.insert(a, lines[b]),
                        _ => {
                            out.remove(a);
                        }
                    }
                    s = out.join("\n");
                }
            }
            4 => {
                // A number replaced by an extreme one.
                let digits: Vec<usize> = s
                    .char_indices()
                    .filter(|(_, c)| c.is_ascii_digit())
                    .map(|(i, _)| i)
                    .collect();
                if let Some(&i) = digits.get(rng.random_range(0..digits.len().max(1))) {
                    let end = s[i..]
                        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
                        .map_or(s.len(), |n| i + n);
                    s.replace_range(i..end, pick(rng, NUMBERS));
                }
            }
            5 => s.insert_str(at, pick(rng, &["\0", "\u{FFFD}", "漢字", "\u{200B}", "\r"])),
            6 => s = s.replace('\n', "\r\n"),
            7 => {
                let depth = rng.random_range(1..300);
                s.insert_str(at, &"{".repeat(depth));
            }
            8 => {
                let b = s.as_bytes().get(at).copied().unwrap_or(b' ');
                if b.is_ascii() && at < s.len() {
                    let flipped = (b ^ (1 << rng.random_range(0..7))) & 0x7f;
                    s.replace_range(at..at + 1, &char::from(flipped).to_string());
                }
            }
            _ => s.insert_str(
                at,
                pick(
                    rng,
                    &[
                        " repeat 99999999 ",
                        " count 10000000 ",
                        " choose 99 of ",
                        " keep 0.0000001 ",
                        " jitter 1e300 mm ",
                    ],
                ),
            ),
        }
    }
    s
}

/// One artifact file's bytes damaged: a JSON value changed, dropped or
/// retyped (in a JSON Lines file, in one record), or raw bytes flipped.
fn damage(rng: &mut ChaCha8Rng, bytes: &[u8]) -> Vec<u8> {
    let lines: Vec<&[u8]> = bytes.split(|&b| b == b'\n').collect();
    if lines.len() > 2 && serde_json::from_slice::<serde_json::Value>(bytes).is_err() {
        let k = rng.random_range(0..lines.len());
        let mut out = Vec::with_capacity(bytes.len());
        for (i, line) in lines.iter().enumerate() {
            if i > 0 {
                out.push(b'\n');
            }
            if i == k {
                out.extend(damage(rng, line));
            } else {
                out.extend_from_slice(line);
            }
        }
        return out;
    }
    if let Ok(mut v) = serde_json::from_slice::<serde_json::Value>(bytes)
        && rng.random_bool(0.8)
    {
        // A random path down the document, as a JSON pointer.
        let mut pointer = String::new();
        let mut node = &v;
        for _ in 0..rng.random_range(0..8) {
            let next = match node {
                serde_json::Value::Object(m) if !m.is_empty() => {
                    let k = rng.random_range(0..m.len());
                    m.iter()
                        .nth(k)
                        .map(|(key, n)| (key.replace('~', "~0").replace('/', "~1"), n))
                }
                serde_json::Value::Array(a) if !a.is_empty() => {
                    let k = rng.random_range(0..a.len());
                    a.get(k).map(|n| (k.to_string(), n))
                }
                _ => None,
            };
            match next {
                Some((key, n)) => {
                    pointer.push('/');
                    pointer.push_str(&key);
                    node = n;
                }
                None => break,
            }
        }
        let Some(node) = v.pointer_mut(&pointer) else {
            return bytes.to_vec();
        };
        *node = match rng.random_range(0..6) {
            0 => serde_json::json!(null),
            1 => serde_json::json!(-1),
            2 => serde_json::json!(1e300),
            3 => serde_json::json!("ghost"),
            4 => serde_json::json!([]),
            _ => serde_json::json!(u64::MAX),
        };
        return serde_json::to_vec(&v).unwrap_or_default();
    }
    let mut out = bytes.to_vec();
    for _ in 0..rng.random_range(1..16) {
        if out.is_empty() {
            break;
        }
        let i = rng.random_range(0..out.len());
        out[i] ^= 1 << rng.random_range(0..8);
    }
    if rng.random_bool(0.2) {
        out.truncate(rng.random_range(0..=out.len()));
    }
    out
}

/// What happened to one input.
#[derive(Default, Clone, Copy)]
struct Tally {
    inputs: u64,
    drawn: u64,
    compiled: u64,
    read_back: u64,
    /// The time its generated data may take beyond [`BOUND`].
    allowance: Duration,
}

/// The input each worker is running: its number, when it started and its
/// text, for the watchdog.
type InFlight = Mutex<Vec<Option<(u64, Instant, String)>>>;

/// Writes a failing input where the README says, and says where.
fn save(seed: u64, i: u64, input: &str) -> PathBuf {
    let saved = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("fuzz-failures")
        .join(format!("seed{seed}-input{i}.pack"));
    if let Some(parent) = saved.parent() {
        let _ = fs::create_dir_all(parent);
    }
    let _ = fs::write(&saved, input);
    saved
}

/// Watches the inputs in flight until `done`: one running longer than
/// [`HANG`] is saved and the process exits (a hung thread cannot be
/// stopped otherwise).
fn watchdog(seed: u64, in_flight: &InFlight, done: &AtomicBool) {
    while !done.load(Ordering::Relaxed) {
        std::thread::sleep(Duration::from_millis(200));
        let Ok(slots) = in_flight.lock() else {
            return;
        };
        for (i, started, input) in slots.iter().flatten() {
            if started.elapsed() > HANG {
                let saved = save(seed, *i, input);
                eprintln!(
                    "fuzz: input {i} of seed {seed} has run for over {HANG:?} (a hang); saved as {}",
                    saved.display()
                );
                std::process::exit(101);
            }
        }
    }
}

/// Draws every cell, inventory and order of `roots` as `packwright draw`
/// does, if they resolve; the number of pictures asked for (each one an
/// SVG or a `DrawError`, never a panic or a hang).
fn draw_all(loader: &MemoryLoader, roots: &[PathBuf]) -> u64 {
    let loaded = load::load(loader, roots);
    if !loaded.errors.is_empty() {
        return 0;
    }
    let (model, errors) = resolve::resolve(loader, &loaded.sources, &loaded.files);
    if !errors.is_empty() {
        return 0;
    }
    let diagnostics = validate::validate(&model);
    let subjects: Vec<Subject> = (0..model.cells.len())
        .map(Subject::Cell)
        .chain((0..model.inventories.len()).map(Subject::Inventory))
        .chain((0..model.orders.len()).map(|o| Subject::order(&model, o)))
        .collect();
    for subject in &subjects {
        let _ = packwright_draw::picture(&picture_of(&model, subject, &diagnostics));
    }
    subjects.len() as u64
}

/// Runs input number `i` of the stream seeded `seed` as worker `worker`;
/// `Err` with a description (the input saved) if it panicked or took too
/// long.
fn one(
    corpus: &[(PathBuf, String)],
    seed: u64,
    i: u64,
    scratch: &Path,
    (worker, in_flight): (usize, &InFlight),
) -> Result<Tally, String> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ i.wrapping_mul(0x9e37_79b9_7f4a_7c15));
    let (path, text) = &corpus[rng.random_range(0..corpus.len())];
    let other = &corpus[rng.random_range(0..corpus.len())].1;
    let input = mutate(&mut rng, text, other);
    let started = Instant::now();
    let track = |now: Option<(u64, Instant, String)>| {
        if let Ok(mut slots) = in_flight.lock()
            && let Some(slot) = slots.get_mut(worker)
        {
            *slot = now;
        }
    };
    track(Some((i, started, input.clone())));
    let run = catch_unwind(AssertUnwindSafe(|| {
        let mut tally = Tally {
            inputs: 1,
            ..Tally::default()
        };
        if let Ok(formatted) = packwright_grammar::format(&input) {
            let again = packwright_grammar::format(&formatted);
            assert_eq!(
                again.as_ref().ok(),
                Some(&formatted),
                "format is idempotent"
            );
        }
        let _ = packwright_grammar::parse(&input);
        let loader = corpus
            .iter()
            .fold(MemoryLoader::new(), |l, (p, t)| l.with(p, t.clone()))
            .with(path, input.clone());
        let roots = [path.clone()];
        tally.drawn = draw_all(&loader, &roots);
        let Ok((compiled, artifacts)) = packwright_compiler::compile(&loader, &roots, &Anywhere)
        else {
            if let Err(failed) = packwright_compiler::check(&loader, &roots, &Anywhere) {
                let _ = failed.render();
            }
            return tally;
        };
        tally.compiled = 1;
        let cases: usize = compiled.expanded.suites.iter().map(|s| s.cases.len()).sum();
        tally.allowance = PER_SAMPLE * u32::try_from(compiled.shape.samples).unwrap_or(u32::MAX)
            + PER_CASE * u32::try_from(cases).unwrap_or(u32::MAX);
        if i.is_multiple_of(READ_BACK_EVERY) && !artifacts.is_empty() {
            let _ = fs::remove_dir_all(scratch);
            let damaged = rng.random_range(0..artifacts.len());
            let written = fs::create_dir_all(scratch).is_ok()
                && artifacts.iter().enumerate().all(|(k, a)| {
                    let bytes = if k == damaged {
                        damage(&mut rng, &a.bytes)
                    } else {
                        a.bytes.clone()
                    };
                    fs::write(scratch.join(a.name), bytes).is_ok()
                });
            if written {
                tally.read_back = 1;
                if let Ok(dir) = CompiledDir::read(scratch) {
                    let _ = dir.graphs();
                }
            }
        }
        tally
    }));
    let took = started.elapsed();
    track(None);
    let allowed = BOUND + run.as_ref().map_or(Duration::ZERO, |t| t.allowance);
    let failure = match (&run, took > allowed) {
        (Err(_), _) => "panicked".to_owned(),
        (Ok(_), true) => format!("took {took:?}"),
        (Ok(t), false) => return Ok(*t),
    };
    let saved = save(seed, i, &input);
    Err(format!(
        "input {i} of seed {seed} (a mutation of {}) {failure}; saved as {}",
        path.display(),
        saved.display()
    ))
}

/// Runs inputs `0..n` of seed `seed` on every core; the totals.
fn fuzz(n: u64, seed: u64) -> Tally {
    let corpus = corpus();
    assert!(corpus.len() >= 30, "the corpus: {} files", corpus.len());
    let threads = rayon::current_num_threads().max(1) as u64;
    let in_flight: InFlight = Mutex::new(vec![None; threads as usize]);
    let done = AtomicBool::new(false);
    /// Stops the watchdog when the workers end, panicking or not.
    struct Done<'a>(&'a AtomicBool);
    impl Drop for Done<'_> {
        fn drop(&mut self) {
            self.0.store(true, Ordering::Relaxed);
        }
    }
    std::thread::scope(|scope| {
        scope.spawn(|| watchdog(seed, &in_flight, &done));
        let _done = Done(&done);
        work(&corpus, n, seed, threads, &in_flight)
    })
}

/// The workers of [`fuzz`]: inputs `t, t + threads, …` each.
fn work(
    corpus: &[(PathBuf, String)],
    n: u64,
    seed: u64,
    threads: u64,
    in_flight: &InFlight,
) -> Tally {
    let tallies: Vec<Tally> = (0..threads)
        .into_par_iter()
        .map(|t| {
            let scratch = std::env::temp_dir()
                .join(format!("packwright-fuzz-{}-{seed}-{t}", std::process::id()));
            let mut total = Tally::default();
            for i in (t..n).step_by(threads as usize) {
                match one(corpus, seed, i, &scratch, (t as usize, in_flight)) {
                    Ok(x) => {
                        total.inputs += x.inputs;
                        total.drawn += x.drawn;
                        total.compiled += x.compiled;
                        total.read_back += x.read_back;
                    }
                    Err(why) => panic!("{why}"),
                }
            }
            let _ = fs::remove_dir_all(&scratch);
            total
        })
        .collect();
    tallies.iter().fold(Tally::default(), |a, b| Tally {
        inputs: a.inputs + b.inputs,
        drawn: a.drawn + b.drawn,
        compiled: a.compiled + b.compiled,
        read_back: a.read_back + b.read_back,
        allowance: Duration::ZERO,
    })
}

fn report(t: Tally, started: Instant) {
    let s = started.elapsed().as_secs_f64();
    eprintln!(
        "fuzz: {} inputs, {} pictures drawn, {} compiled, {} artifact sets damaged and read back; {s:.1} s, {:.0} inputs/s",
        t.inputs,
        t.drawn,
        t.compiled,
        t.read_back,
        t.inputs as f64 / s
    );
}

#[test]
fn fuzz_short() {
    let started = Instant::now();
    let t = fuzz(5_000, 1);
    report(t, started);
    assert_eq!(t.inputs, 5_000);
    // The mutations leave some inputs valid, so the reader and `draw` are
    // exercised.
    assert!(t.compiled > 0 && t.read_back > 0, "compiled {}", t.compiled);
    assert!(t.drawn > t.compiled, "drawn {}", t.drawn);
}

#[test]
#[ignore = "the long run: cargo test --release --test fuzz -- --ignored --nocapture"]
fn fuzz_million() {
    let env = |k: &str, d: u64| {
        std::env::var(k)
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(d)
    };
    let (n, seed) = (env("FUZZ_INPUTS", 1_000_000), env("FUZZ_SEED", 2));
    let started = Instant::now();
    let t = fuzz(n, seed);
    report(t, started);
    assert_eq!(t.inputs, n);
}
