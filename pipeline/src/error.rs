//! The pipeline's error.

use packwright_kinematics::UrdfError;
use packwright_nets::ModelError;
use packwright_sim::SimError;
use std::path::PathBuf;
use thiserror::Error;

#[derive(Debug, Error)]
pub enum PipelineError {
    #[error("cannot read {path}: {reason}")]
    Read { path: PathBuf, reason: String },
    /// A file of a compiled directory that breaks the artifacts' schema or
    /// disagrees with the other files: which file, where in it (a path
    /// such as `demonstrations[3].start[1].at`, empty for the whole file)
    /// and what is wrong (`crate::artifacts` checks it).
    #[error("{}{}: {problem}", file.display(), at_field(field))]
    Invalid {
        file: PathBuf,
        field: String,
        problem: ArtifactProblem,
    },
    /// A path given where a compiled directory is read (`train`, `show`)
    /// that is not one.
    #[error("{}: {what}", path.display())]
    NotCompiled { path: PathBuf, what: NotCompiled },
    #[error("{file} has no {what} `{name}`")]
    Unknown {
        file: &'static str,
        what: &'static str,
        name: String,
    },
    /// A robot description that cannot be used (`why` is not a `source`:
    /// it is said once, in this message).
    #[error("{path}: {why}")]
    Urdf { path: String, why: UrdfError },
    #[error("the arm cannot reach a start pose over the pending area of cell `{cell}`")]
    NoStartPose { cell: String },
    #[error(transparent)]
    Sim(#[from] SimError),
    /// Expanding a clean compilation's demonstrations failed.
    #[error(transparent)]
    Compile(Box<packwright_compiler::Error>),
    /// A model directory that cannot be used (`why` is not a `source`:
    /// it is said once, in this message).
    #[error("{what}: {why}")]
    Model { what: String, why: ModelError },
    /// Demonstrations that follow no one sequence rule.
    #[error(
        "the demonstrations follow no one sequence rule: {0}. A model learns one rule (ascending, descending or a listed priority) from demonstrations that mostly agree: choose blocks that do with --demos (blocks with `sequence random` show that any order is right and are left out of this)"
    )]
    ContradictorySequence(Box<Contradiction>),
    #[error("no {what} `{name}`; {known}")]
    NoSuch {
        what: &'static str,
        name: String,
        known: String,
    },
    #[error("{0}")]
    Selection(String),
    /// The real robot's driver: unreachable, a refused recipe, not ready,
    /// not in remote control (see `packwright_ur::UrError`).
    #[error(transparent)]
    Robot { source: packwright_ur::UrError },
}

/// Why a path is not a compiled directory.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Error)]
pub enum NotCompiled {
    /// A file (a `.pack` source, most likely).
    #[error(
        "a file, not a compiled directory: compile it first (`packwright compile FILE -o DIR`) and give DIR"
    )]
    File,
    #[error("no such directory: give the directory `packwright compile … -o DIR` wrote")]
    Missing,
    #[error(
        "not a compiled directory (no manifest.json): give the directory `packwright compile … -o DIR` wrote"
    )]
    NoManifest,
}

/// `, FIELD` after the file name, or nothing for a whole-file problem.
fn at_field(field: &str) -> String {
    if field.is_empty() {
        String::new()
    } else {
        format!(", {field}")
    }
}

/// What is wrong at one place of a compiled artifact. The values are data
/// for callers; `Display` is for people.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ArtifactProblem {
    /// Not JSON, or not of the schema's shape (a wrong type, a number out
    /// of range for its type, a missing field): the parser's reason.
    #[error("not a packwright artifact ({reason})")]
    Malformed { reason: String },
    /// `graphs.safetensors` is not a safetensors file: the reader's reason.
    #[error("not a safetensors file ({reason})")]
    NotSafetensors { reason: String },
    #[error("schema `{found}`, expected `{expected}`")]
    Schema { found: String, expected: String },
    #[error(
        "schema version {found}; this packwright reads version {expected}: compile the sources again"
    )]
    Version { found: u32, expected: u32 },
    /// A NaN or infinity, or a number beyond what the single-precision
    /// computations downstream (the simulator, the networks) can hold.
    #[error("{value} is not a finite number")]
    NotFinite { value: f64 },
    /// A length or a size that must be greater than `bound`.
    #[error("{value} is not greater than {bound}")]
    NotAbove { value: f64, bound: f64 },
    /// A length in metres outside its checked range.
    #[error("{value} m is outside {min}-{max} m")]
    LengthOutOfRange { value: f64, min: f64, max: f64 },
    /// A share (of the arm's full speed) outside its checked range.
    #[error("{value} is outside {min}-{max}")]
    ShareOutOfRange { value: f64, min: f64, max: f64 },
    /// A joint's acceleration (rad/s²) or jerk (rad/s³) limit outside its
    /// checked range.
    #[error("{value} is outside {min}-{max}")]
    LimitOutOfRange { value: f64, min: f64, max: f64 },
    /// A time in seconds outside its checked range.
    #[error("{value} s is outside {min}-{max} s")]
    TimeOutOfRange { value: f64, min: f64, max: f64 },
    /// An integer (a label, a node, an index, a flag) outside `min..=max`.
    #[error("{value} is outside {min}..={max}")]
    OutOfRange { value: i64, min: i64, max: i64 },
    /// A name that names nothing of its kind where it is used.
    #[error("no {what} is named `{name}`")]
    UnknownName { what: &'static str, name: String },
    /// A name given twice where names are unique.
    #[error("{what} `{name}` is given twice")]
    Duplicate { what: &'static str, name: String },
    /// A count (or a first index) that is not what the files hold.
    #[error("{found}, but the files hold {expected}")]
    CountMismatch { expected: usize, found: usize },
    /// A value that must equal another one in the files (shown as text).
    #[error("{found}, expected {expected}")]
    Differs { expected: String, found: String },
    /// A tensor of the schema that the file does not hold.
    #[error("no such tensor")]
    MissingTensor,
    #[error("dtype {found}, expected {expected}")]
    Dtype { found: String, expected: String },
    #[error("shape {found:?}, expected {expected:?}")]
    Shape {
        found: Vec<usize>,
        expected: Vec<usize>,
    },
}

pub type Result<T, E = PipelineError> = std::result::Result<T, E>;

/// Why demonstrations follow no one sequence rule: the rule that explains
/// the most of them, and the first that breaks it.
#[derive(Debug, Clone, PartialEq)]
pub struct Contradiction {
    pub best: packwright_interface::SequenceRule,
    pub agree: usize,
    pub demonstrations: usize,
    /// The first breaking demonstration: its number within its block
    /// (from 1), its block and its products in the order handled.
    pub first: Option<(usize, String, Vec<String>)>,
}

impl std::fmt::Display for Contradiction {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if let Some((k, block, sequence)) = &self.first {
            write!(
                f,
                "the best rule, {}, explains {} of {} demonstrations (block `{block}`, its demonstration {k}, handles {} in another order)",
                self.best,
                self.agree,
                self.demonstrations,
                sequence.join(", ")
            )?;
        }
        Ok(())
    }
}
