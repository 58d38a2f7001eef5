//! Files: bounded reading and atomic writing. Every file weft reads goes through
//! [`read_limited`], so no input can make it read (and allocate) without bound; every file it
//! writes goes through [`write_atomic`] (a temporary file, then a rename), so a reader never
//! sees half a file.
//!
//! A path that is not a regular file (a directory, `/dev/zero`, a FIFO, a socket) is refused
//! before anything is read, because its size says nothing about how much it yields. A regular
//! file larger than its format's limit is refused from its metadata, and the read itself stops
//! one byte past the limit, so a file that grows while being read cannot slip through.
//!
//! The limits, one per format:
//!
//! | format | limit | why |
//! |---|---|---|
//! | scene (TOML) | [`SCENE_LIMIT`] = 4 MiB | hand-written text; the shipped scenes are under 4 KiB |
//! | OBJ mesh | [`OBJ_LIMIT`] = 256 MiB | about 4 million triangles of text; `tobj` holds the parsed mesh in a few times the text's size |
//! | checkpoint | [`CHECKPOINT_LIMIT`] = 4 GiB | 24 bytes a particle plus the scene text: about 178 million particles; the memory budget ([`crate::model::budget`]) refuses what would not fit anyway |
//! | cached accuracy reference | its exact expected size | the size follows from the steps and the particle count |
//!
//! ```
//! let dir = std::env::temp_dir();
//! let e = weft::files::read_limited(&dir, 1024, "scene").unwrap_err();
//! assert!(e.to_string().contains("not a regular file"), "{e}");
//! ```

use crate::{Result, WeftError};
use std::io::{Read, Write};
use std::path::Path;

/// Largest scene file read, in bytes.
pub const SCENE_LIMIT: u64 = 4 << 20;
/// Largest OBJ file read, in bytes.
pub const OBJ_LIMIT: u64 = 256 << 20;
/// Largest checkpoint file read, in bytes.
pub const CHECKPOINT_LIMIT: u64 = 4 << 30;

/// Reads the whole of `path`, refusing a path that is not a regular file or holds more than
/// `limit` bytes. `what` names the format in the error ("scene", "OBJ mesh", ...).
pub fn read_limited(path: &Path, limit: u64, what: &str) -> Result<Vec<u8>> {
    let refuse = |message: String| WeftError::Io {
        path: path.display().to_string(),
        message,
    };
    let file = std::fs::File::open(path).map_err(|e| WeftError::io(path, e))?;
    let meta = file.metadata().map_err(|e| WeftError::io(path, e))?;
    if !meta.is_file() {
        return Err(refuse(format!(
            "not a regular file (the {what} must be a regular file, not a directory, device or pipe)"
        )));
    }
    if meta.len() > limit {
        return Err(too_big(what, &meta.len().to_string(), limit, &path.display().to_string()));
    }
    // Capacity from the validated metadata.
    read_to_limit(file, limit, what, &path.display().to_string(), meta.len() as usize)
}

/// Reads `reader` to its end, refusing more than `limit` bytes: the read stops one byte past
/// the limit. `what` names the format and `name` the source in errors; `capacity` is the
/// expected size (0 when unknown).
pub fn read_to_limit(reader: impl Read, limit: u64, what: &str, name: &str, capacity: usize) -> Result<Vec<u8>> {
    let mut bytes = Vec::with_capacity(capacity.min(limit as usize));
    reader
        .take(limit.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(|e| WeftError::Io {
            path: name.to_string(),
            message: e.to_string(),
        })?;
    if bytes.len() as u64 > limit {
        return Err(too_big(what, &format!("more than {limit}"), limit, name));
    }
    Ok(bytes)
}

/// The error of a `what` of `size` bytes over `limit`.
fn too_big(what: &str, size: &str, limit: u64, name: &str) -> WeftError {
    WeftError::Io {
        path: name.to_string(),
        message: format!("{what} file is {size} bytes, more than the limit of {limit} bytes"),
    }
}

/// [`read_limited`] for text: the bytes must be UTF-8.
pub fn read_text_limited(path: &Path, limit: u64, what: &str) -> Result<String> {
    let bytes = read_limited(path, limit, what)?;
    String::from_utf8(bytes).map_err(|_| WeftError::Io {
        path: path.display().to_string(),
        message: format!("{what} file is not valid UTF-8 text"),
    })
}

/// Writes `bytes` to `path` through a temporary file and a rename.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let tmp = path.with_extension(format!("{}.tmp", path.extension().and_then(|e| e.to_str()).unwrap_or("")));
    let mut f = std::fs::File::create(&tmp).map_err(|e| WeftError::io(&tmp, e))?;
    f.write_all(bytes).map_err(|e| WeftError::io(&tmp, e))?;
    f.sync_all().map_err(|e| WeftError::io(&tmp, e))?;
    drop(f);
    std::fs::rename(&tmp, path).map_err(|e| WeftError::io(path, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limits_and_non_regular_files_are_refused() {
        let dir = std::env::temp_dir().join(format!("weft_input_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("ten.txt");
        std::fs::write(&p, "0123456789").unwrap();
        assert_eq!(read_limited(&p, 10, "scene").unwrap(), b"0123456789");
        let e = read_limited(&p, 9, "scene").unwrap_err().to_string();
        assert!(e.contains("more than the limit of 9 bytes"), "{e}");
        let e = read_limited(&dir, 1 << 20, "scene").unwrap_err().to_string();
        assert!(e.contains("not a regular file"), "{e}");
        std::fs::write(&p, [0xff, 0xfe]).unwrap();
        let e = read_text_limited(&p, 10, "scene").unwrap_err().to_string();
        assert!(e.contains("UTF-8"), "{e}");
        assert!(matches!(read_limited(&dir.join("missing"), 10, "scene"), Err(WeftError::Io { .. })));
        std::fs::remove_dir_all(&dir).ok();
        #[cfg(unix)]
        {
            let e = read_limited(Path::new("/dev/zero"), 1 << 20, "checkpoint").unwrap_err().to_string();
            assert!(e.contains("not a regular file"), "{e}");
        }
    }
}
