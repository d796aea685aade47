//! Reading input files (launch files, worlds, robot descriptions, meshes, maps): only regular
//! files of bounded size, so that `/dev/zero`, a FIFO or a directory given as a world is a
//! clear error at once, not a hang or an exhausted memory.

use std::fs::File;
use std::io::{Error, ErrorKind, Read};
use std::path::Path;

/// The largest input file Caravan reads: 256 MiB.
pub const MAX_INPUT_BYTES: u64 = 256 << 20;

/// Opens `path` if it is a regular file of at most [`MAX_INPUT_BYTES`]; checked before the
/// open, which would block on a FIFO.
pub fn open_regular(path: &Path) -> Result<File, Error> {
    let meta = std::fs::metadata(path)?;
    if !meta.is_file() {
        return Err(Error::new(ErrorKind::InvalidInput, "not a regular file"));
    }
    if meta.len() > MAX_INPUT_BYTES {
        return Err(Error::new(
            ErrorKind::InvalidInput,
            format!(
                "{} bytes, more than the {MAX_INPUT_BYTES} Caravan reads",
                meta.len()
            ),
        ));
    }
    File::open(path)
}

/// The bytes of a regular file of bounded size (see [`open_regular`]).
pub fn read(path: &Path) -> Result<Vec<u8>, Error> {
    let mut bytes = Vec::new();
    // `take` bounds a file that grows after the check.
    open_regular(path)?
        .take(MAX_INPUT_BYTES)
        .read_to_end(&mut bytes)?;
    Ok(bytes)
}

/// A recording (MCAP), mapped into memory rather than read: recordings of long runs are far
/// larger than [`MAX_INPUT_BYTES`], and only the parts a reader touches are loaded. Only
/// regular files are mapped. A file is mapped at its size when opened; one that another
/// process is still appending to is seen up to there.
pub fn map_recording(path: &Path) -> Result<memmap2::Mmap, Error> {
    let meta = std::fs::metadata(path)?;
    if !meta.is_file() {
        return Err(Error::new(ErrorKind::InvalidInput, "not a regular file"));
    }
    let file = File::open(path)?;
    // SAFETY: the map is read-only. Recordings are written by appending; a file truncated
    // while mapped would fault, which Caravan's recorders never do.
    unsafe { memmap2::Mmap::map(&file) }
}

/// The text of a regular file of bounded size (see [`open_regular`]).
pub fn read_to_string(path: &Path) -> Result<String, Error> {
    String::from_utf8(read(path)?).map_err(|e| Error::new(ErrorKind::InvalidData, e))
}

#[cfg(test)]
mod tests {
    #[test]
    fn devices_directories_and_fifos_are_refused_at_once() {
        use std::path::Path;
        for path in ["/dev/zero", "/dev/null", "/"] {
            let e = super::read(Path::new(path)).unwrap_err();
            assert!(e.to_string().contains("not a regular file"), "{path}: {e}");
        }
        let dir = std::env::temp_dir().join(format!("caravan-input-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let fifo = dir.join("fifo");
        let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
        // SAFETY: mkfifo with a valid NUL-terminated path.
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
        assert!(super::read_to_string(&fifo).is_err());
        std::fs::write(dir.join("ok.toml"), "a = 1").unwrap();
        assert_eq!(
            super::read_to_string(&dir.join("ok.toml")).unwrap(),
            "a = 1"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
