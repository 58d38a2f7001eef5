//! File helpers shared by every writer: atomic writes (a temporary file, then a rename, so a
//! reader never sees half a file and an interrupted run leaves the old file intact).

use std::io::Write;
use std::path::Path;

use crate::error::{Result, WeftError};

/// Writes `bytes` to `path` through a temporary file and a rename.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let tmp = path.with_extension(format!("{}.tmp", path.extension().and_then(|e| e.to_str()).unwrap_or("")));
    let mut f = std::fs::File::create(&tmp).map_err(|e| WeftError::io(&tmp, e))?;
    f.write_all(bytes).map_err(|e| WeftError::io(&tmp, e))?;
    f.sync_all().map_err(|e| WeftError::io(&tmp, e))?;
    drop(f);
    std::fs::rename(&tmp, path).map_err(|e| WeftError::io(path, e))
}
