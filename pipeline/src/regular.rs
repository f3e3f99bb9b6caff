//! Reading the files the pipeline is given (compiled artifacts, model
//! files, robot descriptions and their meshes): regular files only. A
//! link to `/dev/zero`, a pipe or a terminal never ends; read whole it
//! took every byte of memory and aborted the process.

use std::fs::File;
use std::io::{Error, ErrorKind, Read};
use std::path::Path;

/// `path` opened for reading, when it is a regular file (links followed).
pub fn open(path: &Path) -> std::io::Result<File> {
    let file = File::open(path)?;
    let meta = file.metadata()?;
    if meta.is_file() {
        Ok(file)
    } else if meta.is_dir() {
        Err(Error::new(
            ErrorKind::InvalidInput,
            "a directory, not a file",
        ))
    } else {
        Err(Error::new(
            ErrorKind::InvalidInput,
            "not a regular file (a device, a pipe or a socket), which could be read without end",
        ))
    }
}

/// The bytes of the regular file `path`.
pub fn read(path: &Path) -> std::io::Result<Vec<u8>> {
    let mut file = open(path)?;
    let mut bytes = Vec::new();
    file.read_to_end(&mut bytes)?;
    Ok(bytes)
}

/// The text of the regular file `path`.
pub fn read_to_string(path: &Path) -> std::io::Result<String> {
    let mut file = open(path)?;
    let mut text = String::new();
    file.read_to_string(&mut text)?;
    Ok(text)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_device_or_a_directory_is_refused_and_a_file_read() {
        if Path::new("/dev/zero").exists() {
            let e = read(Path::new("/dev/zero")).expect_err("a device");
            assert_eq!(e.kind(), ErrorKind::InvalidInput);
            assert!(e.to_string().contains("not a regular file"), "{e}");
        }
        let dir = std::env::temp_dir();
        assert!(read(&dir).is_err());
        let file = dir.join(format!("packwright-regular-{}", std::process::id()));
        std::fs::write(&file, "text").expect("written");
        assert_eq!(read_to_string(&file).expect("read"), "text");
        let _ = std::fs::remove_file(&file);
    }
}
