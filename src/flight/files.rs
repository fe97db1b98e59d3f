//! Writing the files a run leaves behind so that a crash or a full disk never leaves a torn one.

use std::path::Path;

/// Write `text` beside `path`, then rename it over `path`: a process killed mid-write, or a full disk, leaves the
/// previous file whole (or none), never a torn one; the error names the file.
pub fn write_atomically(path: &Path, text: &str) -> std::io::Result<()> {
    let tmp = path.with_extension("tmp");
    std::fs::write(&tmp, text).and_then(|()| std::fs::rename(&tmp, path)).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        std::io::Error::new(e.kind(), format!("writing {}: {e}", path.display()))
    })
}
