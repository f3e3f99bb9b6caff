//! Reading compiled artifacts, checked: one reader for every command that
//! reads a compiled directory (`train`, `demonstrate`, `show`).
//!
//! [`CompiledDir::read`] parses `manifest.json`, `labels.json`,
//! `orders.json`, `scenarios.json` and `demonstrations.jsonl` (a record
//! per line) and checks them together
//! (`validate`) before anything uses them; [`CompiledDir::graphs`] reads
//! and checks `graphs.safetensors` against them (`graphs`). A file that
//! breaks the schema is [`PipelineError::Invalid`]: the file, the field
//! (a JSON path such as `suites[0].cases[3].start[1].at`; in a JSON
//! Lines file, the record first: `[3].start[1].at` is line 4; or a tensor
//! element such as `edge_index[0][2]`) and an [`ArtifactProblem`].
//!
//! **The first problem is reported**, in a fixed order: every file's
//! parse, schema and version; then `orders.json` on its own (the world
//! the others refer to); then `labels.json`, `manifest.json` and
//! `scenarios.json` against it; then the tensors. A mistake is therefore
//! reported where it is, not as the disagreements it causes later.
//!
//! (The reasoner's training examples are built from the demonstrations
//! themselves, by the run-time's own graph encoder: `teach`;
//! `graphs.safetensors` is read by `show` and other tools.)

mod field;
mod graphs;
mod json_path;
#[cfg(test)]
mod tests;
mod validate;

pub use graphs::{GraphsFile, layout};

use crate::error::{ArtifactProblem, NotCompiled, PipelineError, Result};
use field::Field;
use packwright_compiler::artifact::{
    CombinationRecord, DemonstrationRecord, LabelsFile, Manifest, SCHEMA_VERSION, ScenariosFile,
    WorldFile, schema,
};
use serde::Deserialize;
use serde::de::DeserializeOwned;
use std::path::{Path, PathBuf};

/// The files of a compiled directory.
pub use packwright_compiler::file;

/// The JSON artifacts of a compiled directory, checked.
///
/// Invariants ([`CompiledDir::read`] checks them, so that users index and
/// look names up without further checks):
/// - every schema string and version is this packwright's;
/// - every number is finite (also in single precision, as the simulator
///   and the networks compute), every size and mass positive, the suction
///   cup and the lift within the compiler's ranges, every pending area has
///   a surface, every source digest is 64 hexadecimal digits;
/// - names are unique: cells, products, inventories, orders, blocks and
///   suites; boxes and slots within a cell, products within an inventory,
///   cases within a suite;
/// - every name a record uses resolves (cells, inventories, orders,
///   blocks; products of the inventory, slots of the cell, a slot's box),
///   and the cells and inventories of related records agree;
/// - slot `i` of a cell has label `i + 1`, and every assignment's label
///   is its slot's; `labels.json` holds one table per cell, in order:
///   `pick` (0), then the cell's slots as `orders.json` lists them;
/// - a demonstration's `sequence`, `human_packed` and `missing` divide its
///   assignment; a case's packed products are its assignment's and its
///   missing ones its inventory's; `start` lists the inventory's present
///   products in listed order;
/// - `counts` are the lengths of what the files hold; the blocks cover the
///   demonstrations in order; each demonstration's samples follow the
///   previous ones' (two per product it handles) and they total
///   `counts.samples` = `tensors.samples`; `tensors.nodes` (M) is the most
///   products present in a demonstration and `tensors.edges` the chain's
///   `2 (M - 1)`.
#[derive(Debug, Clone)]
pub struct CompiledDir {
    dir: PathBuf,
    manifest: Manifest,
    demonstrations: Vec<DemonstrationRecord>,
    labels: LabelsFile,
    world: WorldFile,
    scenarios: ScenariosFile,
}

impl CompiledDir {
    /// [`CompiledDir::read`], then every other file checked too
    /// ([`CompiledDir::graphs`], [`CompiledDir::combinations`]), though
    /// the caller uses only the JSON: a directory with a file missing or
    /// cut short (a copy interrupted) is refused by every command that
    /// reads it, not only by `show`.
    pub fn read_whole(dir: &Path) -> Result<CompiledDir> {
        let compiled = CompiledDir::read(dir)?;
        compiled.graphs()?;
        compiled.combinations()?;
        Ok(compiled)
    }

    /// Reads and checks the JSON artifacts in `dir` (see the type's
    /// invariants); the first problem found is the error. Each file's
    /// schema and version are reported before anything else about it, so
    /// a directory written by another version says so.
    pub fn read(dir: &Path) -> Result<CompiledDir> {
        let not = |what| PipelineError::NotCompiled {
            path: dir.to_path_buf(),
            what,
        };
        if dir.is_file() {
            return Err(not(NotCompiled::File));
        }
        if !dir.is_dir() {
            return Err(not(NotCompiled::Missing));
        }
        if !dir.join(file::MANIFEST).is_file() {
            return Err(not(NotCompiled::NoManifest));
        }
        let manifest = read_artifact(&dir.join(file::MANIFEST), schema::MANIFEST)?;
        let labels = read_artifact(&dir.join(file::LABELS), schema::LABELS)?;
        let world = read_artifact(&dir.join(file::ORDERS), schema::ORDERS)?;
        let scenarios = read_artifact(&dir.join(file::SCENARIOS), schema::SCENARIOS)?;
        let demonstrations = read_lines(&dir.join(file::DEMONSTRATIONS))?;
        CompiledDir::new(dir, manifest, demonstrations, labels, world, scenarios)
    }

    /// The artifacts of `dir` already parsed, checked as [`read`] checks
    /// them.
    ///
    /// [`read`]: CompiledDir::read
    pub fn new(
        dir: &Path,
        manifest: Manifest,
        demonstrations: Vec<DemonstrationRecord>,
        labels: LabelsFile,
        world: WorldFile,
        scenarios: ScenariosFile,
    ) -> Result<CompiledDir> {
        for (name, found, version, expected) in [
            (
                file::MANIFEST,
                &manifest.schema,
                manifest.version,
                schema::MANIFEST,
            ),
            (file::LABELS, &labels.schema, labels.version, schema::LABELS),
            (file::ORDERS, &world.schema, world.version, schema::ORDERS),
            (
                file::SCENARIOS,
                &scenarios.schema,
                scenarios.version,
                schema::SCENARIOS,
            ),
        ] {
            check_schema(&dir.join(name), found, version, expected)?;
        }
        let compiled = CompiledDir {
            dir: dir.to_owned(),
            manifest,
            demonstrations,
            labels,
            world,
            scenarios,
        };
        validate::all(&compiled)?;
        Ok(compiled)
    }

    /// The directory read.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    pub fn manifest(&self) -> &Manifest {
        &self.manifest
    }

    /// `demonstrations.jsonl`: demonstration `i` is line `i + 1`.
    pub fn demonstrations(&self) -> &[DemonstrationRecord] {
        &self.demonstrations
    }

    /// `combinations.jsonl`, read and checked against the manifest's
    /// blocks (each block's kept, then held-out, combinations, of its
    /// inventory's products, as many as the manifest counts).
    pub fn combinations(&self) -> Result<Vec<CombinationRecord>> {
        let combinations = read_lines(&self.dir.join(file::COMBINATIONS))?;
        validate::combinations(self, &combinations)?;
        Ok(combinations)
    }

    pub fn labels(&self) -> &LabelsFile {
        &self.labels
    }

    /// `orders.json`: the compiled world.
    pub fn world(&self) -> &WorldFile {
        &self.world
    }

    pub fn scenarios(&self) -> &ScenariosFile {
        &self.scenarios
    }

    /// Reads and checks `graphs.safetensors` against the JSON artifacts
    /// (see [`GraphsFile`]).
    pub fn graphs(&self) -> Result<GraphsFile> {
        let path = self.dir.join(file::GRAPHS);
        let bytes = read_bytes(&path)?;
        graphs::read(self, &path, bytes)
    }
}

/// The two fields every JSON artifact starts with.
#[derive(Deserialize)]
struct Header {
    schema: String,
    version: u32,
}

/// A JSON artifact's own schema string and version.
trait Versioned {
    fn header(&self) -> (&str, u32);
}

macro_rules! versioned {
    ($($t:ty),*) => {$(
        impl Versioned for $t {
            fn header(&self) -> (&str, u32) {
                (&self.schema, self.version)
            }
        }
    )*};
}

versioned!(Manifest, LabelsFile, WorldFile, ScenariosFile);

/// The artifact at `path` of schema `expected`, parsed once. Its header
/// is checked first: a file of another schema or version says so even
/// when the rest of it does not parse (then the header alone is parsed
/// again, to tell).
fn read_artifact<T: DeserializeOwned + Versioned>(path: &Path, expected: &str) -> Result<T> {
    let bytes = read_bytes(path)?;
    match parse::<T>(path, &bytes) {
        Ok(artifact) => {
            let (found, version) = artifact.header();
            check_schema(path, found, version, expected)?;
            Ok(artifact)
        }
        Err(malformed) => {
            let header: Header = parse(path, &bytes)?;
            check_schema(path, &header.schema, header.version, expected)?;
            Err(malformed)
        }
    }
}

/// The records of the JSON Lines file at `path`, one per line; an error
/// names the record (`[i]`, line `i + 1`) and the field in it.
fn read_lines<T: DeserializeOwned>(path: &Path) -> Result<Vec<T>> {
    use std::io::BufRead;
    let file = crate::regular::open(path).map_err(|e| PipelineError::Read {
        path: path.to_owned(),
        reason: e.to_string(),
    })?;
    let mut records = Vec::new();
    for (i, line) in std::io::BufReader::new(file).split(b'\n').enumerate() {
        let line = line.map_err(|e| PipelineError::Read {
            path: path.to_owned(),
            reason: e.to_string(),
        })?;
        let record = serde_json::from_slice(&line).map_err(|e| {
            let inner = json_path::at(&line, e.line(), e.column());
            PipelineError::Invalid {
                file: path.to_owned(),
                field: if inner.is_empty() {
                    format!("[{i}]")
                } else {
                    format!("[{i}].{inner}")
                },
                problem: ArtifactProblem::Malformed {
                    reason: e.to_string(),
                },
            }
        })?;
        records.push(record);
    }
    Ok(records)
}

fn read_bytes(path: &Path) -> Result<Vec<u8>> {
    crate::regular::read(path).map_err(|e| PipelineError::Read {
        path: path.to_owned(),
        reason: e.to_string(),
    })
}

/// `bytes` of `path` parsed; an error names the field where the parser
/// stopped.
fn parse<T: DeserializeOwned>(path: &Path, bytes: &[u8]) -> Result<T> {
    serde_json::from_slice(bytes).map_err(|e| PipelineError::Invalid {
        file: path.to_owned(),
        field: json_path::at(bytes, e.line(), e.column()),
        problem: ArtifactProblem::Malformed {
            reason: e.to_string(),
        },
    })
}

fn check_schema(path: &Path, found: &str, version: u32, expected: &str) -> Result<()> {
    let fail = |field: &str, problem| PipelineError::Invalid {
        file: path.to_owned(),
        field: field.to_owned(),
        problem,
    };
    if found != expected {
        return Err(fail(
            "schema",
            ArtifactProblem::Schema {
                found: found.to_owned(),
                expected: expected.to_owned(),
            },
        ));
    }
    if version != SCHEMA_VERSION {
        return Err(fail(
            "version",
            ArtifactProblem::Version {
                found: version,
                expected: SCHEMA_VERSION,
            },
        ));
    }
    Ok(())
}

/// The error for `problem` at `field` of `file`.
fn invalid(file: &Path, field: &Field, problem: ArtifactProblem) -> PipelineError {
    PipelineError::Invalid {
        file: file.to_owned(),
        field: field.to_string(),
        problem,
    }
}
