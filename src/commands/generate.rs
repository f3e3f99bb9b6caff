//! `packwright generate`: random valid cells for tests and benchmarks (the
//! generator is `packwright_pipeline::generate`; this is the file edge).

use crate::Exit;
use crate::cli::{CellFamily, GenerateArgs, TaughtOrder};
use crate::fsio::write_file_atomically;
use anyhow::{Context, bail};
use packwright_pipeline::generate::{Family, Sequence, Variant, generated_variant};
use std::fs;

pub fn run(args: &GenerateArgs) -> anyhow::Result<Exit> {
    let last = args
        .count
        .checked_sub(1)
        .and_then(|k| args.seed.checked_add(k));
    let Some(last) = last else {
        bail!(
            "--count must be at least 1, and SEED + COUNT - 1 at most {}",
            u64::MAX
        );
    };
    if args.output.exists() && !args.output.is_dir() {
        bail!("{} exists and is not a directory", args.output.display());
    }
    fs::create_dir_all(&args.output)
        .with_context(|| format!("cannot create {}", args.output.display()))?;
    let rule = args.sequence.map(|r| match r {
        TaughtOrder::Ascending => Sequence::Ascending,
        TaughtOrder::Descending => Sequence::Descending,
        TaughtOrder::Listed => Sequence::Listed,
    });
    let family = match args.family {
        CellFamily::Standard => Family::Standard,
        CellFamily::Wide => Family::Wide,
        CellFamily::Compact => Family::Compact,
    };
    let variant = Variant {
        hand: args.hand.map(usize::from),
        reversed_stock: args.reversed_stock,
    };
    let generated: Vec<_> = (args.seed..=last)
        .map(|seed| {
            let g = generated_variant(family, seed, rule, variant);
            (args.output.join(g.file_name()), g.text)
        })
        .collect();
    // A file of the same name that is not what its seed generates was
    // edited (or written by something else): nothing is replaced, so no
    // edit is lost. One that is the same is written again.
    let edited: Vec<String> = generated
        .iter()
        .filter(|(path, text)| match fs::read(path) {
            Ok(old) => old != text.as_bytes(),
            // Missing: written. Unreadable (a directory of that name):
            // not replaced either.
            Err(e) => e.kind() != std::io::ErrorKind::NotFound,
        })
        .map(|(path, _)| path.display().to_string())
        .collect();
    if !edited.is_empty() {
        let one = edited.len() == 1;
        bail!(
            "{}: not what {} seed generates (edited since?); nothing was written, so no edit is lost: move {} or choose another -o",
            edited.join(", "),
            if one { "its" } else { "their" },
            if one { "it" } else { "them" },
        );
    }
    for (path, text) in &generated {
        write_file_atomically(path, text.as_bytes())?;
        outln!("{}", path.display());
    }
    Ok(Exit::Success)
}
