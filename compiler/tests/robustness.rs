//! The compiler never panics, whatever it is given: arbitrary text and
//! mutations of valid files end in diagnostics or a clean compilation.

use packwright_compiler::{Anywhere, MemoryLoader, check, compile};
use proptest::prelude::*;
use std::path::PathBuf;

const VALID: &str = include_str!("../../tests/cases/ok/units.pack");
const SUITE: &str = include_str!("../../orders/suites/teach.pack");
const LINE2: &str = include_str!("../../orders/cells/line2.pack");
const TWIN: &str = include_str!("../../orders/cells/twin_row.pack");

fn run(main: &str) {
    let loader = MemoryLoader::new()
        .with("t/main.pack", main.to_owned())
        .with("cells/line2.pack", LINE2)
        .with("cells/twin_row.pack", TWIN);
    let roots = [PathBuf::from("t/main.pack")];
    match compile(&loader, &roots, &Anywhere) {
        Ok(_) => {}
        Err(f) => {
            assert!(!f.errors.is_empty());
            let _ = f.render();
        }
    }
}

/// Cuts `s` at char boundaries around `at`.
fn boundary(s: &str, at: usize) -> usize {
    let mut i = at.min(s.len());
    while !s.is_char_boundary(i) {
        i -= 1;
    }
    i
}

const TOKENS: &[&str] = &[
    "cell",
    "product",
    "inventory",
    "order",
    "demo",
    "demos",
    "scenario",
    "scenarios",
    "use",
    "for",
    "{",
    "}",
    "(",
    ")",
    ",",
    "->",
    "mm",
    "cm",
    "m",
    "0",
    "-1",
    "1e9",
    "99999999999999999999",
    "0.5",
    "\n",
    "#",
    "\"",
    ";",
    "choose",
    "of",
    "into",
    "keep",
    "jitter",
    "seed",
    "human packs",
    "missing",
    "to",
    "count",
    "A",
    "g1",
    "stock5",
];

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn arbitrary_text_never_panics(s in "\\PC{0,200}") {
        run(&s);
    }

    #[test]
    fn mutated_valid_files_never_panic(
        which in 0usize..2,
        cut in 0usize..4000,
        len in 0usize..60,
        insert in proptest::sample::select(TOKENS),
    ) {
        let base = if which == 0 { VALID } else { SUITE };
        let a = boundary(base, cut);
        let b = boundary(base, a + len);
        run(&format!("{}{}{}", &base[..a], insert, &base[b..]));
        run(&base[..a]);
    }
}

#[test]
fn the_unmutated_bases_compile() {
    let loader = MemoryLoader::new()
        .with("t/main.pack", SUITE)
        .with("cells/line2.pack", LINE2)
        .with("cells/twin_row.pack", TWIN);
    if let Err(f) = check(&loader, &[PathBuf::from("t/main.pack")], &Anywhere) {
        panic!("{}", f.render());
    }
}
