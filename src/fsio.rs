//! File-system edge: the compiler's [`Loader`] on real files (bounded
//! reads), and atomic writes (write a temporary sibling, sync it, rename it
//! into place; siblings left by killed runs are removed by the next one).

use anyhow::{Context, bail};
use packwright_compiler::{Artifact, Loader, Output, OutputFile, Unreadable};
use std::fs;
use std::io::{ErrorKind, Read, Write};
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard};

/// The largest `.pack` source file read, bytes (16 MiB): a bigger one (or
/// an endless one such as `/dev/zero`) is refused after reading this much.
pub const MAX_SOURCE_BYTES: u64 = 16 << 20;

/// Every source file this process read (canonical paths): no output may
/// replace one ([`write_file_atomically`]; `fmt` rewrites its own through
/// [`rewrite_source_atomically`]).
static READ: Mutex<std::collections::BTreeSet<PathBuf>> =
    Mutex::new(std::collections::BTreeSet::new());

/// The sources read so far ([`READ`]; a poisoned lock still holds them).
fn sources_read() -> MutexGuard<'static, std::collections::BTreeSet<PathBuf>> {
    READ.lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// Reads a source file: at most [`MAX_SOURCE_BYTES`], UTF-8 text. The
/// error says why for people ("no such file", "not UTF-8 text", "larger
/// than 16 MiB"). The file is remembered as read ([`READ`]).
pub fn read_source(path: &Path) -> Result<String, Unreadable> {
    let text = read_source_text(path)?;
    if let Ok(canonical) = fs::canonicalize(path) {
        sources_read().insert(canonical);
    }
    Ok(text)
}

/// [`read_source`] without remembering the file.
fn read_source_text(path: &Path) -> Result<String, Unreadable> {
    let describe = |e: std::io::Error| match e.kind() {
        ErrorKind::NotFound => Unreadable::Missing,
        _ => Unreadable::Other(e.to_string()),
    };
    if path.is_dir() {
        return Err(Unreadable::Directory {
            compiled: path.join("manifest.json").is_file(),
        });
    }
    let file = fs::File::open(path).map_err(describe)?;
    let mut bytes = Vec::new();
    file.take(MAX_SOURCE_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(describe)?;
    if bytes.len() as u64 > MAX_SOURCE_BYTES {
        return Err(Unreadable::TooLarge {
            limit_mib: MAX_SOURCE_BYTES >> 20,
        });
    }
    let text = String::from_utf8(bytes).map_err(|e| Unreadable::not_text(e.as_bytes()))?;
    // A byte-order mark (some editors write one) is not part of the text.
    Ok(match text.strip_prefix('\u{feff}') {
        Some(rest) => rest.to_owned(),
        None => text,
    })
}

/// Reads source files from disk (see [`read_source`]).
pub struct FsLoader;

impl Loader for FsLoader {
    fn read(&self, path: &Path) -> Result<String, Unreadable> {
        read_source(path)
    }

    fn identity(&self, path: &Path) -> Option<PathBuf> {
        fs::canonicalize(path).ok()
    }

    fn read_named(&self, path: &Path) -> Result<String, Unreadable> {
        match fs::metadata(path) {
            Ok(m) if !m.is_file() && !m.is_dir() => Err(Unreadable::NotAFile),
            _ => read_source(path),
        }
    }
}

/// The temporary siblings this process is writing: removed when the run
/// is interrupted ([`remove_temporaries_on_interrupt`]), as a failed
/// run's are when its writer is dropped.
static BEING_WRITTEN: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn being_written() -> MutexGuard<'static, Vec<PathBuf>> {
    BEING_WRITTEN.lock().unwrap_or_else(|e| e.into_inner())
}

fn writing(tmp: &Path) {
    being_written().push(tmp.to_owned());
}

fn written(tmp: &Path) {
    being_written().retain(|p| p != tmp);
}

/// On Ctrl-C (SIGINT): the temporary siblings being written are removed,
/// and the run exits 130, as a shell reports an interrupted command.
/// Earlier output is untouched (it is replaced only by a finished
/// write's rename); a run killed outright leaves its siblings to the next
/// run ([`remove_stale_siblings`]).
pub fn remove_temporaries_on_interrupt() {
    // Without a handler (one already set) Ctrl-C keeps its default.
    let _ = ctrlc::set_handler(|| {
        for tmp in being_written().iter() {
            // The writer may still be adding files: tried again.
            for _ in 0..3 {
                let gone = remove(tmp);
                if gone.is_ok() || !tmp.exists() {
                    break;
                }
            }
        }
        std::process::exit(130);
    });
}

/// Removes `path`, a directory with everything in it or a file.
fn remove(path: &Path) -> std::io::Result<()> {
    if path.is_dir() {
        fs::remove_dir_all(path)
    } else {
        fs::remove_file(path)
    }
}

/// Removes temporary siblings of `path` (`.NAME.tmp-PID`, `.NAME.old-PID`)
/// left by runs that were killed: those whose process is gone. Where
/// processes cannot be looked up (no `/proc`), nothing is removed.
fn remove_stale_siblings(path: &Path) {
    let (Some(name), Some(parent)) = (path.file_name(), path.parent()) else {
        return;
    };
    let parent = if parent.as_os_str().is_empty() {
        Path::new(".")
    } else {
        parent
    };
    if !Path::new("/proc/self").exists() {
        return;
    }
    let name = name.to_string_lossy();
    let Ok(entries) = fs::read_dir(parent) else {
        return;
    };
    for entry in entries.flatten() {
        let file = entry.file_name().to_string_lossy().into_owned();
        let pid = ["tmp", "old"]
            .iter()
            .find_map(|tag| sibling_pid(&name, tag, &file));
        if let Some(pid) = pid
            && pid != std::process::id()
            && !Path::new(&format!("/proc/{pid}")).exists()
        {
            let _ = remove(&entry.path());
        }
    }
}

/// The process id of a sibling `.NAME.TAG-PID` of `path` named `file`.
fn sibling_pid(name: &str, tag: &str, file: &str) -> Option<u32> {
    file.strip_prefix(&format!(".{name}.{tag}-"))
        .and_then(|p| p.parse::<u32>().ok())
}

/// Puts back an output directory that a killed run had moved aside: a run
/// replaces `dir` by two renames (`dir` to `.NAME.old-PID`, then the new
/// one into place), and one killed between them leaves no `dir`, only its
/// complete old contents beside it. When `dir` is missing and such a
/// sibling of a process that is gone exists, it is renamed back, so that
/// earlier output is never lost to [`remove_stale_siblings`]. Returns
/// whether it restored one.
pub fn recover_interrupted(dir: &Path) -> bool {
    let (Some(name), Some(parent)) = (dir.file_name(), dir.parent()) else {
        return false;
    };
    let parent = if parent.as_os_str().is_empty() {
        Path::new(".")
    } else {
        parent
    };
    if dir.exists() || !Path::new("/proc/self").exists() {
        return false;
    }
    let name = name.to_string_lossy();
    let Ok(entries) = fs::read_dir(parent) else {
        return false;
    };
    let moved_aside = entries.flatten().find(|e| {
        let file = e.file_name().to_string_lossy().into_owned();
        sibling_pid(&name, "old", &file).is_some_and(|pid| {
            pid != std::process::id() && !Path::new(&format!("/proc/{pid}")).exists()
        }) && e.path().is_dir()
    });
    moved_aside.is_some_and(|e| fs::rename(e.path(), dir).is_ok())
}

fn sibling(path: &Path, tag: &str) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let parent = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    parent.join(format!(".{name}.{tag}-{}", std::process::id()))
}

/// Makes the directory `path` goes in, when missing ([`make_dir`]).
fn make_parent(path: &Path) -> anyhow::Result<()> {
    match path.parent().filter(|p| !p.as_os_str().is_empty()) {
        Some(parent) => {
            make_dir(parent).with_context(|| format!("cannot write {}", path.display()))
        }
        None => Ok(()),
    }
}

/// Makes the directory `dir` (and its parents) when missing. The path or
/// an ancestor that is a file, not a directory, is named (the system says
/// only "File exists").
pub fn make_dir(dir: &Path) -> anyhow::Result<()> {
    if dir.is_dir() {
        return Ok(());
    }
    if let Some(file) = dir
        .ancestors()
        .find(|a| !a.as_os_str().is_empty() && a.exists() && !a.is_dir())
    {
        bail!("{} is a file, not a directory", file.display());
    }
    fs::create_dir_all(dir)
        .with_context(|| format!("cannot create the directory {}", dir.display()))
}

fn write_synced(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    let mut f =
        fs::File::create(path).with_context(|| format!("cannot create {}", path.display()))?;
    f.write_all(bytes)
        .with_context(|| format!("cannot write {}", path.display()))?;
    f.sync_all()
        .with_context(|| format!("cannot sync {}", path.display()))?;
    Ok(())
}

/// Replaces `path` with `bytes` atomically, making its directory when
/// missing. A symbolic link is followed:
/// the file it points to is replaced and the link kept. A path that is
/// not a regular file (a device such as `/dev/null`, a pipe, a terminal)
/// is written to as it is: renaming a file over it would destroy it.
pub fn write_file_atomically(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    // An output named as one of the sources read (`draw order.pack -o
    // order.pack`, or a file it `use`s) would destroy it.
    if let Ok(canonical) = fs::canonicalize(path)
        && sources_read().contains(&canonical)
    {
        bail!(
            "{} is a .pack file this command read: writing the output there would destroy it (nothing was written); choose another path",
            path.display()
        );
    }
    rewrite_source_atomically(path, bytes)
}

/// [`write_file_atomically`] even over a source read: `fmt`'s rewrite of
/// the files it formats.
pub fn rewrite_source_atomically(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    // What the path names in the end, as the kernel follows it: `/dev/stdout`
    // into a pipe is a link to a link (`/proc/self/fd/1`) whose target
    // (`pipe:[…]`) is no path to follow by hand.
    if let Ok(m) = fs::metadata(path)
        && !m.is_file()
        && !m.is_dir()
    {
        return write_in_place(path, bytes);
    }
    let followed;
    let path = match fs::symlink_metadata(path) {
        Ok(m) if m.file_type().is_symlink() => {
            let target = fs::read_link(path)
                .with_context(|| format!("cannot read the link {}", path.display()))?;
            followed = match path.parent() {
                Some(parent) if target.is_relative() => parent.join(target),
                _ => target,
            };
            // A link to a link: followed again (the kernel refuses a loop).
            if fs::symlink_metadata(&followed).is_ok_and(|m| m.file_type().is_symlink()) {
                return rewrite_source_atomically(&followed, bytes);
            }
            followed.as_path()
        }
        _ => path,
    };
    // (Not a device or pipe: the first check above saw where the path
    // leads.) A file replaced keeps its permissions (`fmt` of a 0640
    // file).
    let existing = fs::metadata(path).ok();
    if existing.as_ref().is_some_and(fs::Metadata::is_dir) {
        bail!("{} is a directory, not a file", path.display());
    }
    let kept = existing.map(|m| m.permissions());
    // A missing parent directory is made, as `compile` makes its output
    // directory's.
    make_parent(path)?;
    remove_stale_siblings(path);
    let tmp = sibling(path, "tmp");
    writing(&tmp);
    let replaced = write_synced(&tmp, bytes)
        .with_context(|| {
            format!(
                "cannot write {} (through a temporary file beside it)",
                path.display()
            )
        })
        .and_then(|()| match kept {
            Some(p) => fs::set_permissions(&tmp, p)
                .with_context(|| format!("cannot set the permissions of {}", tmp.display())),
            None => Ok(()),
        })
        .and_then(|()| {
            fs::rename(&tmp, path).with_context(|| format!("cannot replace {}", path.display()))
        });
    if replaced.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    written(&tmp);
    replaced
}

/// Writes `bytes` to what `path` is (a device, a pipe, a terminal).
fn write_in_place(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    let mut f = fs::OpenOptions::new()
        .write(true)
        .open(path)
        .with_context(|| format!("cannot open {}", path.display()))?;
    f.write_all(bytes)
        .with_context(|| format!("cannot write {}", path.display()))
}

/// Refuses to replace `dir` unless it holds nothing, or earlier output of
/// the same command and nothing else: the file `marker` (whose `schema`
/// is one of packwright's) and no entry but regular files named in
/// `names` (what the command writes). Replacing a directory deletes what
/// it holds: a model trained into a compiled directory, or notes beside a
/// model's files, would go with it.
fn ensure_replaceable(dir: &Path, marker: &str, names: &[&str]) -> anyhow::Result<()> {
    let entries: Vec<String> = fs::read_dir(dir)
        .with_context(|| format!("cannot read {}", dir.display()))?
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    if entries.is_empty() {
        return Ok(());
    }
    let refuse = |why: String| {
        anyhow::anyhow!(
            "refusing to replace {}: {why}; move what it holds elsewhere, or choose another output directory",
            dir.display()
        )
    };
    if !ours(&dir.join(marker)) {
        return Err(refuse(format!(
            "it is not empty and holds no {marker} from an earlier run"
        )));
    }
    let mut foreign: Vec<&String> = entries
        .iter()
        .filter(|n| !names.contains(&n.as_str()) || !dir.join(n).is_file())
        .collect();
    foreign.sort();
    if let Some(first) = foreign.first() {
        let more = match foreign.len() {
            1 => String::new(),
            2 => format!(" and `{}`", foreign[1]),
            n => format!(" and {} more", n - 1),
        };
        return Err(refuse(format!(
            "besides an earlier run's output it holds `{first}`{more}, which would be deleted with it"
        )));
    }
    Ok(())
}

/// Whether `marker` is a file that packwright wrote: JSON whose `schema`
/// names one of packwright's formats (read no further than 1 MiB).
fn ours(marker: &Path) -> bool {
    let Ok(file) = fs::File::open(marker) else {
        return false;
    };
    let mut text = String::new();
    if file.take(1 << 20).read_to_string(&mut text).is_err() {
        return false;
    }
    serde_json::from_str::<serde_json::Value>(&text).is_ok_and(|v| {
        v.get("schema")
            .and_then(|s| s.as_str())
            .is_some_and(|s| s.starts_with("packwright."))
    })
}

/// Whether `dir` could be replaced by output whose files are `names`
/// (`marker` among them), checked before a long run (`train`) that
/// would otherwise find out only when it writes.
pub fn check_replaceable(dir: &Path, marker: &str, names: &[&str]) -> anyhow::Result<()> {
    // The output replaces its directory as a whole, through a sibling
    // swapped into place: `.` has no sibling to swap with (helper N: "cannot
    // move . aside").
    if dir.file_name().is_none() {
        bail!(
            "`{}` names no directory of its own (it is `.`, `..` or a root), and the output replaces its directory as a whole: name one, e.g. `-o out`",
            dir.display()
        );
    }
    recover_interrupted(dir);
    match fs::metadata(dir) {
        Ok(m) if !m.is_dir() => bail!("{} exists and is not a directory", dir.display()),
        Ok(_) => ensure_replaceable(dir, marker, names),
        Err(_) => Ok(()),
    }
}

/// A directory being written: files go into a temporary sibling, which
/// [`AtomicDir::commit`] swaps into place, so that `dir` is never
/// half-written. Dropped without a commit, the sibling is removed.
pub struct AtomicDir {
    dir: PathBuf,
    tmp: PathBuf,
    committed: bool,
}

impl AtomicDir {
    /// Starts replacing `dir`. An existing `dir` is replaced only if it is
    /// empty or holds earlier output of the same command alone: `marker`
    /// (the file every such output has) and other files named in `names`
    /// ([`ensure_replaceable`]).
    pub fn begin(dir: &Path, marker: &str, names: &[&str]) -> anyhow::Result<AtomicDir> {
        // A link to a directory: the directory is replaced and the link
        // kept (renamed over, the link itself became a directory and its
        // target kept the old output).
        let followed;
        let dir = match fs::symlink_metadata(dir) {
            Ok(m) if m.file_type().is_symlink() && dir.is_dir() => {
                followed = fs::canonicalize(dir)
                    .with_context(|| format!("cannot follow the link {}", dir.display()))?;
                followed.as_path()
            }
            _ => dir,
        };
        check_replaceable(dir, marker, names)?;
        make_parent(dir)?;
        remove_stale_siblings(dir);
        let tmp = sibling(dir, "tmp");
        let _ = fs::remove_dir_all(&tmp);
        fs::create_dir(&tmp).with_context(|| {
            format!(
                "cannot write {} (through a temporary directory beside it, {})",
                dir.display(),
                tmp.display()
            )
        })?;
        writing(&tmp);
        Ok(AtomicDir {
            dir: dir.to_owned(),
            tmp,
            committed: false,
        })
    }

    /// Where the file `name` is written before the commit.
    pub fn path(&self, name: &str) -> PathBuf {
        self.tmp.join(name)
    }

    /// Swaps the written directory into place.
    pub fn commit(mut self) -> anyhow::Result<()> {
        // From here a Ctrl-C leaves the sibling to the next run, which
        // puts an old directory moved aside back.
        written(&self.tmp);
        let dir = &self.dir;
        if dir.exists() {
            let old = sibling(dir, "old");
            let _ = fs::remove_dir_all(&old);
            fs::rename(dir, &old)
                .with_context(|| format!("cannot move {} aside", dir.display()))?;
            if let Err(e) = fs::rename(&self.tmp, dir) {
                let _ = fs::rename(&old, dir);
                return Err(e)
                    .with_context(|| format!("cannot move the new {} into place", dir.display()));
            }
            let _ = fs::remove_dir_all(&old);
        } else {
            fs::rename(&self.tmp, dir)
                .with_context(|| format!("cannot move the new {} into place", dir.display()))?;
        }
        self.committed = true;
        Ok(())
    }
}

impl Drop for AtomicDir {
    fn drop(&mut self) {
        if !self.committed {
            let _ = fs::remove_dir_all(&self.tmp);
        }
        written(&self.tmp);
    }
}

/// The compiler's files written into an [`AtomicDir`], each synced when
/// finished.
impl Output for AtomicDir {
    fn create(&self, name: &'static str) -> std::io::Result<Box<dyn OutputFile>> {
        Ok(Box::new(SyncedFile(fs::File::create(self.path(name))?)))
    }
}

struct SyncedFile(fs::File);

impl Write for SyncedFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0.write(buf)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.0.flush()
    }
}

impl std::io::Seek for SyncedFile {
    fn seek(&mut self, pos: std::io::SeekFrom) -> std::io::Result<u64> {
        self.0.seek(pos)
    }
}

impl OutputFile for SyncedFile {
    fn finish(self: Box<Self>) -> std::io::Result<u64> {
        self.0.sync_all()?;
        Ok(self.0.metadata()?.len())
    }
}

/// Writes the artifacts into `dir`: first into a temporary sibling
/// directory, then swapped into place, so that `dir` is never half-written.
/// An existing `dir` is replaced only if it holds nothing but an earlier
/// output of the same files ([`AtomicDir::begin`]; `marker` is the file
/// every such output has).
pub fn write_dir_atomically(
    dir: &Path,
    artifacts: &[Artifact],
    marker: &str,
) -> anyhow::Result<()> {
    let names: Vec<&str> = artifacts.iter().map(|a| a.name).collect();
    let out = AtomicDir::begin(dir, marker, &names)?;
    for a in artifacts {
        write_synced(&out.path(a.name), &a.bytes)?;
    }
    out.commit()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `-o .` (or `..`, `./`, `/`) is refused before anything is read or
    /// written, saying why: the output replaces its directory as a whole.
    #[test]
    fn an_output_directory_must_have_a_name() {
        for dir in [".", "..", "./", "/", "a/.."] {
            let refused = check_replaceable(Path::new(dir), "marker.json", &[])
                .expect_err(dir)
                .to_string();
            assert!(refused.contains("names no directory"), "{dir}: {refused}");
        }
        let named = scratch("named").join("out");
        assert!(check_replaceable(&named, "marker.json", &[]).is_ok());
    }

    /// Output to a pipe (as to `/dev/null`, a device) goes through it and
    /// leaves it a pipe: a file renamed over it replaced `/dev/null` for
    /// `draw -o /dev/null`, run as root. Output to a symbolic link replaces
    /// the file it points to and keeps the link; a directory is refused.
    #[test]
    fn output_to_a_pipe_or_a_link_keeps_it_what_it_is() {
        use std::os::unix::fs::FileTypeExt;
        let dir = scratch("special");
        let fifo = dir.join("pipe");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        assert!(made.is_ok_and(|s| s.success()), "mkfifo");
        let reader = {
            let fifo = fifo.clone();
            std::thread::spawn(move || fs::read(&fifo).expect("read the pipe"))
        };
        write_file_atomically(&fifo, b"through").expect("written to the pipe");
        // Before joining the reader, which a replaced pipe would leave
        // waiting for a writer.
        let kind = fs::symlink_metadata(&fifo)
            .expect("still there")
            .file_type();
        assert!(kind.is_fifo(), "{kind:?}");
        assert_eq!(reader.join().expect("reader"), b"through");

        let target = dir.join("target.svg");
        fs::write(&target, "old").expect("target");
        let link = dir.join("link.svg");
        std::os::unix::fs::symlink("target.svg", &link).expect("link");
        write_file_atomically(&link, b"new").expect("written through the link");
        assert!(
            fs::symlink_metadata(&link)
                .expect("link")
                .file_type()
                .is_symlink()
        );
        assert_eq!(fs::read_to_string(&target).expect("target"), "new");

        let dangling = dir.join("dangling.svg");
        std::os::unix::fs::symlink("made.svg", &dangling).expect("link");
        write_file_atomically(&dangling, b"made").expect("written through the link");
        assert_eq!(
            fs::read_to_string(dir.join("made.svg")).expect("made"),
            "made"
        );

        let err = write_file_atomically(&dir, b"x").expect_err("a directory");
        assert!(err.to_string().contains("is a directory"), "{err}");
        let _ = fs::remove_dir_all(&dir);
    }

    /// A file replaced keeps its permissions (`fmt` rewrote a 0640 file
    /// as 0644).
    #[cfg(unix)]
    #[test]
    fn a_replaced_file_keeps_its_permissions() {
        use std::os::unix::fs::PermissionsExt;
        let dir = scratch("mode");
        let file = dir.join("cell.pack");
        fs::write(&file, "old").expect("written");
        fs::set_permissions(&file, fs::Permissions::from_mode(0o640)).expect("mode");
        write_file_atomically(&file, b"new").expect("replaced");
        let mode = fs::metadata(&file).expect("there").permissions().mode();
        assert_eq!(mode & 0o777, 0o640);
        assert_eq!(fs::read_to_string(&file).expect("read"), "new");
        let _ = fs::remove_dir_all(&dir);
    }

    fn scratch(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("packwright-fsio-{}-{name}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).expect("scratch");
        dir
    }

    #[test]
    fn a_source_read_without_its_byte_order_mark_and_a_directory_named() {
        let d = scratch("bom");
        let file = d.join("cell.pack");
        fs::write(&file, "\u{feff}# a comment\nproduct A cube 50 mm\n").expect("written");
        assert_eq!(
            read_source(&file).expect("read"),
            "# a comment\nproduct A cube 50 mm\n"
        );
        assert_eq!(
            read_source(&d).unwrap_err(),
            Unreadable::Directory { compiled: false }
        );
        fs::write(d.join("manifest.json"), "{}").expect("written");
        assert!(
            read_source(&d)
                .unwrap_err()
                .to_string()
                .contains("a compiled directory")
        );
        let _ = fs::remove_dir_all(&d);
    }

    fn artifact(bytes: &str) -> Artifact {
        Artifact {
            name: "manifest.json",
            bytes: bytes.as_bytes().to_vec(),
        }
    }

    /// A manifest as an earlier run wrote it, told apart by `run`.
    fn manifest(run: &str) -> String {
        format!(r#"{{"schema": "packwright.manifest", "run": "{run}"}}"#)
    }

    /// An earlier output is replaced; one that holds anything else too (a
    /// model trained into a compiled directory, a user's notes), or whose
    /// marker packwright did not write, is refused and left as it was.
    #[test]
    fn only_an_earlier_output_alone_is_replaced() {
        let dir = scratch("replace");
        let out = dir.join("out");
        let write =
            |run: &str| write_dir_atomically(&out, &[artifact(&manifest(run))], "manifest.json");
        write("first").expect("a new directory");
        write("second").expect("an earlier output");
        fs::create_dir_all(out.join("model")).expect("created");
        fs::write(out.join("model/config.json"), "{}").expect("written");
        let err = write("third").expect_err("a model inside");
        assert!(err.to_string().contains("`model`"), "{err}");
        assert!(out.join("model/config.json").is_file(), "the model kept");
        fs::remove_dir_all(out.join("model")).expect("removed");
        fs::write(out.join("notes.txt"), "keep").expect("written");
        fs::write(out.join("todo.txt"), "keep").expect("written");
        let err = write("third").expect_err("notes beside it");
        assert!(
            err.to_string().contains("`notes.txt` and `todo.txt`"),
            "{err}"
        );
        fs::remove_file(out.join("notes.txt")).expect("removed");
        fs::remove_file(out.join("todo.txt")).expect("removed");
        fs::write(out.join("manifest.json"), r#"{"name": "a web app"}"#).expect("written");
        let err = write("third").expect_err("someone else's manifest");
        assert!(err.to_string().contains("holds no manifest.json"), "{err}");
        assert_eq!(
            fs::read_to_string(out.join("manifest.json")).expect("kept"),
            r#"{"name": "a web app"}"#
        );
        let _ = fs::remove_dir_all(&dir);
    }

    /// A run killed between its two renames left no `out`, only
    /// `.out.old-PID`: the next run puts it back before anything else, so
    /// the old output is never removed as debris.
    #[test]
    fn output_moved_aside_by_a_killed_run_is_put_back() {
        if !Path::new("/proc/self").exists() {
            return;
        }
        let dir = scratch("moved-aside");
        let out = dir.join("out");
        // Above Linux's largest process id: never alive.
        let aside = dir.join(".out.old-4194400");
        let half_new = dir.join(".out.tmp-4194400");
        for (d, run) in [(&aside, "old"), (&half_new, "new")] {
            fs::create_dir_all(d).expect("created");
            fs::write(d.join("manifest.json"), manifest(run)).expect("written");
        }
        assert!(recover_interrupted(&out));
        assert_eq!(
            fs::read_to_string(out.join("manifest.json"))
                .ok()
                .as_deref(),
            Some(manifest("old").as_str())
        );
        assert!(!aside.exists());
        assert!(!recover_interrupted(&out), "only when `out` is missing");

        // The same through a write: put back, then replaced whole, and the
        // killed run's temporary directory removed.
        fs::rename(&out, &aside).expect("moved aside");
        write_dir_atomically(&out, &[artifact(&manifest("newer"))], "manifest.json")
            .expect("written");
        assert_eq!(
            fs::read_to_string(out.join("manifest.json"))
                .ok()
                .as_deref(),
            Some(manifest("newer").as_str())
        );
        assert!(!aside.exists() && !half_new.exists(), "no debris");
        let _ = fs::remove_dir_all(&dir);
    }

    /// An output named through a link to a directory replaces the
    /// directory and keeps the link (helper W: the link became a
    /// directory, its target kept the old output).
    #[test]
    fn an_output_through_a_link_replaces_its_target_and_keeps_the_link() {
        let dir = scratch("link");
        let (real, link) = (dir.join("real"), dir.join("link"));
        let write =
            |run: &str| write_dir_atomically(&link, &[artifact(&manifest(run))], "manifest.json");
        fs::create_dir_all(&real).expect("created");
        fs::write(real.join("manifest.json"), manifest("old")).expect("written");
        std::os::unix::fs::symlink("real", &link).expect("link");
        write("new").expect("written through the link");
        assert!(
            fs::symlink_metadata(&link)
                .expect("the link")
                .file_type()
                .is_symlink(),
            "the link kept"
        );
        assert_eq!(
            fs::read_to_string(real.join("manifest.json")).expect("read"),
            manifest("new")
        );
        let _ = fs::remove_dir_all(&dir);
    }

    /// A directory asked for under a file names the file (helper W: "cannot
    /// create afile: File exists").
    #[test]
    fn a_directory_under_a_file_names_the_file() {
        let dir = scratch("under-a-file");
        let file = dir.join("afile");
        fs::write(&file, "x").expect("written");
        for asked in [file.clone(), file.join("sub")] {
            let err = make_dir(&asked).expect_err("under a file");
            assert!(
                err.to_string()
                    .contains(&format!("{} is a file, not a directory", file.display())),
                "{err}"
            );
        }
        let err = write_file_atomically(&file.join("sub/x.svg"), b"x").expect_err("under a file");
        assert!(
            format!("{err:#}").contains("is a file, not a directory"),
            "{err:#}"
        );
        let _ = fs::remove_dir_all(&dir);
    }
}
