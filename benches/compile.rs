//! Compiling a large generated file: 5,000 demonstrations and 10,000
//! scenarios (goal: under 1 s for parse + check + expand + emit).
//!
//! `cargo bench --bench compile`

use criterion::{Criterion, criterion_group, criterion_main};
use packwright_compiler::{Anywhere, MemoryLoader, compile};
use std::hint::black_box;
use std::path::PathBuf;

/// A bench with five products and five slots; 4,800 + 200 demonstrations
/// and 10,000 scenarios, all jittered.
pub fn large_file() -> String {
    "cell bench {
  robot ur10
  base (0, 0, 0)
  suction 100 mm
  pending (0.45, -0.50) to (0.85, -0.10)
  box tray (0.00, 0.65) size (0.40, 0.30, 0.08)
  slot g1 (-0.12, 0.58)
  slot g2 ( 0.00, 0.58)
  slot g3 ( 0.12, 0.58)
  slot g4 (-0.06, 0.72)
  slot g5 ( 0.06, 0.72)
}
product A cube 50 mm
product B cube 50 mm
product C cube 50 mm
product D cube 50 mm
product E box (60 mm, 40 mm, 50 mm)
inventory stock5 for bench {
  A (0.50, -0.20)
  B (0.62, -0.20)
  C (0.74, -0.20)
  D (0.56, -0.38)
  E (0.68, -0.38)
}
demos three for stock5 {
  choose 3 of A, B, C, D, E into g1, g2, g3, g4, g5
  jitter 20 mm
  repeat 8
  seed 1
}
demos two for stock5 {
  choose 2 of A, B, C, D, E into g1, g2, g3, g4, g5
  jitter 20 mm
  seed 2
}
scenarios suite for stock5 {
  choose 4 of A, B, C, D, E into g1, g2, g3, g4, g5
  human packs 0 to 2
  missing 0 to 1
  jitter 20 mm
  count 10000
  seed 3
}
"
    .to_owned()
}

fn bench(c: &mut Criterion) {
    let loader = MemoryLoader::new().with("large.pack", large_file());
    let roots = [PathBuf::from("large.pack")];
    let (compiled, artifacts) =
        compile(&loader, &roots, &Anywhere).expect("the generated file compiles");
    assert_eq!(
        compiled.demonstrations().expect("demonstrations").len(),
        5_000
    );
    assert_eq!(compiled.expanded.suites[0].cases.len(), 10_000);
    let bytes: usize = artifacts.iter().map(|a| a.bytes.len()).sum();
    eprintln!(
        "artifacts: {} samples, {:.1} MB",
        compiled.shape.samples,
        bytes as f64 / 1e6
    );
    let mut group = c.benchmark_group("compile");
    group.sample_size(10);
    group.bench_function("5k demos + 10k scenarios", |b| {
        b.iter(|| {
            compile(&loader, black_box(&roots), &Anywhere)
                .map(|(_, a)| a.len())
                .unwrap_or(0)
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
