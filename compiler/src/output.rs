//! Where [`emit`](crate::emit) writes: through the [`Output`] trait, so
//! that the compiler does no IO of its own. The command line gives it a
//! directory (written atomically); tests and tools give it a
//! [`MemoryOutput`].
//!
//! Invariant: `emit` creates each file once, writes it (sequentially, or
//! at offsets it computed in advance: `graphs.safetensors` is written a
//! chunk of samples at a time into each tensor's place) and calls
//! [`OutputFile::finish`]; a file not finished is not part of the output.

use std::collections::BTreeMap;
use std::io::{self, Cursor, Seek, SeekFrom, Write};
use std::sync::{Arc, Mutex};

/// A destination for a compilation's files.
pub trait Output {
    /// A new, empty file called `name`.
    fn create(&self, name: &'static str) -> io::Result<Box<dyn OutputFile>>;
}

/// One file being written.
pub trait OutputFile: Write + Seek {
    /// Everything written is complete (flushed; on disk, synced): returns
    /// the file's length in bytes.
    fn finish(self: Box<Self>) -> io::Result<u64>;
}

/// One output file, in memory.
#[derive(Debug, Clone, PartialEq)]
pub struct Artifact {
    pub name: &'static str,
    pub bytes: Vec<u8>,
}

/// An [`Output`] that keeps every finished file in memory.
#[derive(Debug, Clone, Default)]
pub struct MemoryOutput {
    files: Arc<Mutex<BTreeMap<&'static str, Vec<u8>>>>,
}

impl MemoryOutput {
    pub fn new() -> MemoryOutput {
        MemoryOutput::default()
    }

    /// The finished files, by name.
    pub fn artifacts(&self) -> Vec<Artifact> {
        self.files
            .lock()
            .map(|files| {
                files
                    .iter()
                    .map(|(&name, bytes)| Artifact {
                        name,
                        bytes: bytes.clone(),
                    })
                    .collect()
            })
            .unwrap_or_default()
    }
}

impl Output for MemoryOutput {
    fn create(&self, name: &'static str) -> io::Result<Box<dyn OutputFile>> {
        Ok(Box::new(MemoryFile {
            name,
            bytes: Cursor::new(Vec::new()),
            files: Arc::clone(&self.files),
        }))
    }
}

struct MemoryFile {
    name: &'static str,
    bytes: Cursor<Vec<u8>>,
    files: Arc<Mutex<BTreeMap<&'static str, Vec<u8>>>>,
}

impl Write for MemoryFile {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.bytes.write(buf)
    }

    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}

impl Seek for MemoryFile {
    fn seek(&mut self, pos: SeekFrom) -> io::Result<u64> {
        self.bytes.seek(pos)
    }
}

impl OutputFile for MemoryFile {
    fn finish(self: Box<Self>) -> io::Result<u64> {
        let bytes = self.bytes.into_inner();
        let len = bytes.len() as u64;
        self.files
            .lock()
            .map_err(|_| io::Error::other("the memory output was poisoned"))?
            .insert(self.name, bytes);
        Ok(len)
    }
}
