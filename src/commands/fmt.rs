//! `packwright fmt`: canonical layout.

use crate::Exit;
use crate::cli::FmtArgs;
use crate::fsio::{read_source, rewrite_source_atomically};
use packwright_compiler::{Error, Loc, SourceMap, diagnostic};

pub fn run(args: &FmtArgs) -> anyhow::Result<Exit> {
    let mut exit = Exit::Success;
    for path in &args.files {
        let text = read_source(path)
            .map_err(|why| anyhow::anyhow!("cannot read {}: {why}", path.display()))?;
        let formatted = match packwright_grammar::format(&text) {
            Ok(f) => f,
            Err(errors) => {
                let mut sources = SourceMap::default();
                let id = sources.add(path.clone(), text);
                for error in errors {
                    let e = Error::Syntax {
                        at: Loc::new(id, error.span()),
                        error,
                    };
                    err!("{}", diagnostic::render(&sources, &e));
                }
                exit = Exit::Diagnostics;
                continue;
            }
        };
        if args.stdout {
            out!("{formatted}");
        } else if formatted != text {
            if args.check {
                outln!("{}", path.display());
                exit = Exit::Diagnostics;
            } else {
                rewrite_source_atomically(path, formatted.as_bytes())?;
                errln!("formatted {}", path.display());
            }
        }
    }
    Ok(exit)
}
