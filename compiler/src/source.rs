//! Source files and the one door to the file system: the [`Loader`] trait.
//! The compiler reads through it and never touches the disk itself, so tests
//! run on in-memory files ([`MemoryLoader`]) and the CLI passes a real one.

use packwright_grammar::{LineIndex, Span};
use std::collections::BTreeMap;
use std::path::{Component, Path, PathBuf};

/// Reads source files for the compiler.
pub trait Loader {
    /// The text of the file at `path`, or why not.
    fn read(&self, path: &Path) -> Result<String, Unreadable>;

    /// What makes two paths the same file (on disk: the path with every
    /// link and `..` resolved), so that a file named on the command line
    /// by its absolute path and `use`d by a relative one is loaded once;
    /// `None` where the loader cannot tell (the path itself is used).
    fn identity(&self, _path: &Path) -> Option<PathBuf> {
        None
    }

    /// Reads a file another one names (a `use`, a `robot urdf`): as
    /// [`Loader::read`], but a loader on real files refuses what is not
    /// a file on disk (a named pipe nobody writes to would be waited on
    /// for ever). Files named on the command line may be pipes (`<(...)`).
    fn read_named(&self, path: &Path) -> Result<String, Unreadable> {
        self.read(path)
    }
}

/// Why a source file could not be read.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Unreadable {
    /// There is no file at the path.
    Missing,
    /// A directory; `compiled`: one `compile` wrote.
    Directory { compiled: bool },
    /// Not UTF-8 text: the first byte that is not, by line and column
    /// (from 1; the column counts bytes).
    NotText { line: usize, column: usize },
    /// Larger than the limit for a source file, in MiB.
    TooLarge { limit_mib: u64 },
    /// Not a file on disk (a named pipe, a socket or a device), where a
    /// file another one names must be a regular file.
    NotAFile,
    /// Anything else the system said (no permission, an I/O error), for
    /// people.
    Other(String),
}

impl std::fmt::Display for Unreadable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Unreadable::Missing => f.write_str("no such file"),
            Unreadable::Directory { compiled: true } => f.write_str(
                "a compiled directory, not a .pack file: give the .pack files it was compiled from (`train` and `show` read compiled directories)",
            ),
            Unreadable::Directory { compiled: false } => {
                f.write_str("a directory, not a .pack file")
            }
            Unreadable::NotText { line, column } => write!(
                f,
                "not UTF-8 text (the first byte that is not: line {line}, column {column})"
            ),
            Unreadable::TooLarge { limit_mib } => {
                write!(f, "larger than {limit_mib} MiB, the limit for a .pack file")
            }
            Unreadable::NotAFile => f.write_str(
                "not a file on disk (a named pipe, a socket or a device): a file another one names must be a regular file",
            ),
            Unreadable::Other(reason) => f.write_str(reason),
        }
    }
}

impl Unreadable {
    /// Not UTF-8 text: where in `bytes` the first byte that is not
    /// stands ([`Unreadable::NotText`]).
    pub fn not_text(bytes: &[u8]) -> Unreadable {
        let valid = std::str::from_utf8(bytes).map_or_else(|e| e.valid_up_to(), str::len);
        let before = &bytes[..valid.min(bytes.len())];
        let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
        let column = valid
            - before
                .iter()
                .rposition(|&b| b == b'\n')
                .map_or(0, |i| i + 1)
            + 1;
        Unreadable::NotText { line, column }
    }

    /// How to fix it, where it is the file's own problem.
    pub fn help(&self) -> String {
        let help: &str = match self {
            Unreadable::Missing => "check the path",
            Unreadable::Directory { compiled: true } => {
                "name the .pack files; compiled directories are for `train` and `show`"
            }
            Unreadable::Directory { compiled: false } => "name a .pack file, not a directory",
            Unreadable::NotText { .. } => {
                "save the file as UTF-8 text (in most editors: save with encoding UTF-8); a name or comment in another encoding is the usual cause"
            }
            Unreadable::TooLarge { limit_mib } => {
                return format!(
                    "a .pack file is at most {limit_mib} MiB: split it into files joined with `use`"
                );
            }
            Unreadable::NotAFile => "name a regular file",
            Unreadable::Other(_) => "check the path and the file's permissions",
        };
        help.into()
    }
}

/// Files held in memory, by normalised path.
#[derive(Debug, Default, Clone)]
pub struct MemoryLoader {
    files: BTreeMap<PathBuf, String>,
}

impl MemoryLoader {
    pub fn new() -> MemoryLoader {
        MemoryLoader::default()
    }

    pub fn with(mut self, path: impl AsRef<Path>, text: impl Into<String>) -> MemoryLoader {
        self.files.insert(normalize(path.as_ref()), text.into());
        self
    }
}

impl Loader for MemoryLoader {
    fn read(&self, path: &Path) -> Result<String, Unreadable> {
        self.files
            .get(&normalize(path))
            .cloned()
            .ok_or(Unreadable::Missing)
    }
}

/// Lexical normalisation: drops `.` and folds `dir/..`, so that one file
/// reached by two relative paths is loaded once. Does not follow links.
pub fn normalize(path: &Path) -> PathBuf {
    let mut out: Vec<Component> = Vec::new();
    for c in path.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => match out.last() {
                Some(Component::Normal(_)) => {
                    out.pop();
                }
                Some(Component::RootDir | Component::Prefix(_)) => {}
                _ => out.push(c),
            },
            _ => out.push(c),
        }
    }
    if out.is_empty() {
        return PathBuf::from(".");
    }
    out.iter().collect()
}

/// Index of a file in a [`SourceMap`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct FileId(pub u32);

/// A place in a source file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct Loc {
    pub file: FileId,
    pub span: Span,
}

impl Loc {
    pub fn new(file: FileId, span: Span) -> Loc {
        Loc { file, span }
    }
}

#[derive(Debug, Clone)]
pub struct SourceFile {
    /// The normalised path, as the user (or a `use`) named it.
    pub path: PathBuf,
    pub text: String,
    pub lines: LineIndex,
}

/// Every file the compilation read, in the order it read them.
#[derive(Debug, Clone, Default)]
pub struct SourceMap {
    files: Vec<SourceFile>,
}

impl SourceMap {
    pub fn add(&mut self, path: PathBuf, text: String) -> FileId {
        let id = FileId(u32::try_from(self.files.len()).unwrap_or(u32::MAX));
        let lines = LineIndex::new(&text);
        self.files.push(SourceFile { path, text, lines });
        id
    }

    pub fn get(&self, id: FileId) -> Option<&SourceFile> {
        self.files.get(id.0 as usize)
    }

    pub fn find(&self, path: &Path) -> Option<FileId> {
        self.files
            .iter()
            .position(|f| f.path == path)
            .and_then(|i| u32::try_from(i).ok())
            .map(FileId)
    }

    pub fn files(&self) -> impl Iterator<Item = (FileId, &SourceFile)> {
        self.files
            .iter()
            .enumerate()
            .map(|(i, f)| (FileId(i as u32), f))
    }

    /// `path:line:col` of a place.
    pub fn position(&self, loc: Loc) -> (String, usize, usize) {
        match self.get(loc.file) {
            Some(f) => {
                let (line, col) = f.lines.line_col(&f.text, loc.span.start as usize);
                (f.path.display().to_string(), line, col)
            }
            None => ("<unknown>".into(), 0, 0),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A file in Latin-1 (a name with an accent) is told where its first
    /// byte that is not UTF-8 stands, and to save it as UTF-8 (helper W:
    /// the help said to check the path and the permissions).
    #[test]
    fn a_file_not_in_utf8_is_told_where_and_how_to_save_it() {
        let bytes = b"product tea cube 50 mm\nproduct caf\xe9 cube 50 mm\n";
        let why = Unreadable::not_text(bytes);
        assert_eq!(
            why,
            Unreadable::NotText {
                line: 2,
                column: 12
            }
        );
        assert!(why.to_string().contains("line 2, column 12"), "{why}");
        assert!(why.help().contains("UTF-8"));
        let first = Unreadable::not_text(b"\xff\xfe");
        assert_eq!(first, Unreadable::NotText { line: 1, column: 1 });
    }

    #[test]
    fn normalises_paths() {
        assert_eq!(
            normalize(Path::new("a/./b/../c.pack")),
            PathBuf::from("a/c.pack")
        );
        assert_eq!(normalize(Path::new("../x/../y")), PathBuf::from("../y"));
        assert_eq!(normalize(Path::new("/a/../../b")), PathBuf::from("/b"));
        assert_eq!(normalize(Path::new("./")), PathBuf::from("."));
    }
}
