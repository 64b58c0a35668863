//! Files built into a front end — its bundled robots, tables and fixtures — read in place of a missing
//! file of the same relative path, straight from the program's memory: nothing is unpacked, so no copy on
//! disk can be edited or planted. A file that exists on disk always wins.

use std::borrow::Cow;
use std::path::Path;
use std::sync::OnceLock;

use crate::IoError;

/// The bundled files, `(relative path, content)`, set once by the front end.
static BUNDLED: OnceLock<&'static [(&'static str, &'static [u8])]> = OnceLock::new();

/// Makes `files` (`configs/irb140.toml`, …) readable by every reader of this crate where no file of that
/// relative path exists on disk. The first call wins.
pub fn bundle(files: &'static [(&'static str, &'static [u8])]) {
    let _ = BUNDLED.set(files);
}

/// The bundled content of `path`, when it is a relative path of a bundled file (`./` and `\` allowed).
pub fn bundled(path: &Path) -> Option<&'static [u8]> {
    if path.is_absolute() {
        return None;
    }
    let key = path.to_string_lossy().replace('\\', "/");
    let key = key.trim_start_matches("./");
    BUNDLED.get()?.iter().find(|(name, _)| *name == key).map(|(_, bytes)| *bytes)
}

/// The names of the bundled files.
pub fn bundled_names() -> Vec<&'static str> {
    BUNDLED.get().map_or_else(Vec::new, |files| files.iter().map(|(n, _)| *n).collect())
}

/// Whether `path` can be read: a file on disk, or a bundled one.
pub fn file_exists(path: &Path) -> bool {
    path.is_file() || (!path.exists() && bundled(path).is_some())
}

/// The bytes of `path`: the file on disk, or the bundled copy when there is none.
pub fn read_bytes(path: &Path) -> Result<Cow<'static, [u8]>, IoError> {
    match std::fs::read(path) {
        Ok(bytes) => Ok(Cow::Owned(bytes)),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            bundled(path).map(Cow::Borrowed).ok_or_else(|| IoError::file(path, e))
        }
        Err(e) => Err(IoError::file(path, e)),
    }
}

/// `path` opened for buffered reading: the file on disk, or the bundled copy when there is none.
pub fn open(path: &Path) -> Result<Box<dyn std::io::BufRead + Send>, IoError> {
    match std::fs::File::open(path) {
        Ok(file) => Ok(Box::new(std::io::BufReader::new(file))),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => match bundled(path) {
            Some(bytes) => Ok(Box::new(bytes)),
            None => Err(IoError::file(path, e)),
        },
        Err(e) => Err(IoError::file(path, e)),
    }
}
