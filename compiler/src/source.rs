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
    /// There is something at the path that cannot be read as `.pack`
    /// text: a directory, a file without permission, one too large or
    /// not UTF-8 (the reason, for people).
    Other(String),
}

impl std::fmt::Display for Unreadable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Unreadable::Missing => f.write_str("no such file"),
            Unreadable::Other(reason) => f.write_str(reason),
        }
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
