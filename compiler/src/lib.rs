//! The packwright compiler: `.pack` files in, checked model and artifacts
//! out. Pure: files are read through a [`Loader`], artifacts are returned
//! as bytes; the caller does the IO.
//!
//! Phases: [`load`] (read + parse, following `use`) -> [`resolve`] (names,
//! statements) -> [`validate`] (geometry) -> [`workspace`] (every pose the
//! robot needs, asked of a [`Workspace`] the caller gives: the compiler
//! knows no kinematics) -> [`expand`] (generators; [`draws`] then asks
//! about the picks the suites' draws block) ->
//! [`dataset`] (graph samples) -> [`emit`] (artifact bytes). Each phase
//! reports every error it finds; a phase runs only if those before it were
//! clean, so that one mistake is not reported again as its consequences.

pub mod artifact;
pub mod dataset;
pub mod diagnostic;
pub mod draws;
pub mod emit;
mod error;
pub mod expand;
pub mod load;
pub mod model;
pub mod output;
pub mod resolve;
pub mod source;
pub mod validate;
mod warning;
pub mod workspace;

pub use emit::{Written, file};
pub use error::Error;
pub use output::{Artifact, MemoryOutput, Output, OutputFile};
pub use source::{FileId, Loader, Loc, MemoryLoader, SourceMap, Unreadable};
pub use warning::{Draws, HELD_ROOM, RELEASE_GAP_MM, Warning};
pub use workspace::{Anywhere, Workspace};

use std::path::PathBuf;

/// A clean compilation.
#[derive(Debug)]
pub struct Compiled {
    pub sources: SourceMap,
    pub model: model::Model,
    pub expanded: expand::Expanded,
    /// The dataset's size (its samples are built only when emitted).
    pub shape: dataset::Shape,
    /// What compiles but may fail on the robot.
    pub warnings: Vec<Warning>,
}

impl Compiled {
    /// Every demonstration, generated again and held in memory: for tests
    /// and small files (writers stream them: [`expand::Expanded::demonstrations`]).
    pub fn demonstrations(&self) -> Result<Vec<expand::Demonstration>, Error> {
        self.expanded.demonstrations(&self.model).collect()
    }

    /// Every graph sample, in memory: for tests and small files.
    pub fn graphs(&self) -> Result<dataset::Graphs, Error> {
        dataset::build(&self.model, &self.expanded)
    }
}

/// A failed compilation: every error found, sorted by place.
#[derive(Debug)]
pub struct Failed {
    pub sources: SourceMap,
    pub errors: Vec<Error>,
}

impl Failed {
    /// True when a file could not be read at all, or an output file
    /// written (not a diagnostic in the input).
    pub fn is_io(&self) -> bool {
        self.errors
            .iter()
            .any(|e| matches!(e, Error::Read { .. } | Error::Write { .. }))
    }

    /// The errors shown: the first [`SHOWN_ERRORS`] by position.
    pub fn shown(&self) -> &[Error] {
        &self.errors[..self.errors.len().min(SHOWN_ERRORS)]
    }

    /// How many errors are not shown ([`Failed::shown`]).
    pub fn not_shown(&self) -> usize {
        self.errors.len() - self.shown().len()
    }

    /// The errors shown, rendered for people, and a line saying how many
    /// more there are.
    pub fn render(&self) -> String {
        let mut text = self
            .shown()
            .iter()
            .map(|e| diagnostic::render(&self.sources, e))
            .collect::<Vec<_>>()
            .join("\n");
        let more = self.not_shown();
        if more > 0 {
            text.push_str(&format!(
                "\n... and {more} more error{} not shown: the first {SHOWN_ERRORS} are; fix them and check again\n",
                if more == 1 { "" } else { "s" }
            ));
        }
        text
    }
}

/// The most errors a failed compilation shows ([`Failed::render`], and
/// `--json`): a file of a million stray lines has a million, and echoing
/// each took gigabytes.
pub const SHOWN_ERRORS: usize = 100;

fn fail(sources: SourceMap, mut errors: Vec<Error>) -> Failed {
    errors.sort_by_key(|e| e.at());
    errors.dedup();
    Failed { sources, errors }
}

/// Checks the files and everything they use (the robot's reach through
/// `workspace`; [`Anywhere`] skips it), and expands their generators.
pub fn check(
    loader: &dyn Loader,
    roots: &[PathBuf],
    workspace: &dyn Workspace,
) -> Result<Compiled, Failed> {
    let loaded = load::load(loader, roots);
    if !loaded.errors.is_empty() {
        return Err(fail(loaded.sources, loaded.errors));
    }
    let (model, mut errors) = resolve::resolve(loader, &loaded.sources, &loaded.files);
    errors.extend(validate::validate(&model));
    if !errors.is_empty() {
        return Err(fail(loaded.sources, errors));
    }
    let (errors, mut warnings) = workspace::check(&model, workspace);
    if !errors.is_empty() {
        return Err(fail(loaded.sources, errors));
    }
    warnings.extend(validate::warnings(&model));
    warnings.sort_by_key(Warning::at);
    warnings.dedup();
    let expanded = match expand::expand(&model) {
        Ok(x) => x,
        Err(errors) => return Err(fail(loaded.sources, errors)),
    };
    warnings.extend(draws::check(&model, &expanded, workspace));
    warnings.sort_by_key(Warning::at);
    let shape = dataset::Shape::of(&expanded);
    Ok(Compiled {
        sources: loaded.sources,
        model,
        expanded,
        shape,
        warnings,
    })
}

/// Checks, then writes the artifacts into `out` (the manifest last).
pub fn compile_into(
    loader: &dyn Loader,
    roots: &[PathBuf],
    workspace: &dyn Workspace,
    out: &dyn Output,
) -> Result<(Compiled, Vec<Written>), Failed> {
    let compiled = check(loader, roots, workspace)?;
    match emit::emit(
        &compiled.sources,
        &compiled.model,
        &compiled.expanded,
        compiled.shape,
        out,
    ) {
        Ok(written) => Ok((compiled, written)),
        Err(e) => Err(fail(compiled.sources, vec![e])),
    }
}

/// Checks, then serialises the artifacts in memory.
pub fn compile(
    loader: &dyn Loader,
    roots: &[PathBuf],
    workspace: &dyn Workspace,
) -> Result<(Compiled, Vec<Artifact>), Failed> {
    let out = MemoryOutput::new();
    let (compiled, _) = compile_into(loader, roots, workspace, &out)?;
    Ok((compiled, out.artifacts()))
}
