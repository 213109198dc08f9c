//! Temporary output files that become real only on success: takes a destination path and
//! gives a sibling temporary path; [`TempOutput::commit`] renames it onto the destination,
//! dropping it uncommitted removes it. So no reader ever sees a half-written output, even
//! when writing fails or is cancelled.

use std::path::{Path, PathBuf};

/// A temporary sibling of `dest`, removed on drop unless committed.
#[derive(Debug)]
pub struct TempOutput {
    temp: PathBuf,
    dest: PathBuf,
    committed: bool,
}

impl TempOutput {
    pub fn new(dest: &Path) -> Self {
        let name = dest
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let temp_name = format!(".{name}.{}.tmp", std::process::id());
        let temp = match dest.parent() {
            Some(dir) if !dir.as_os_str().is_empty() => dir.join(temp_name),
            _ => PathBuf::from(temp_name),
        };
        TempOutput {
            temp,
            dest: dest.to_path_buf(),
            committed: false,
        }
    }

    pub fn temp_path(&self) -> &Path {
        &self.temp
    }

    /// Renames the temporary file onto the destination.
    pub fn commit(mut self) -> std::io::Result<()> {
        std::fs::rename(&self.temp, &self.dest)?;
        self.committed = true;
        Ok(())
    }
}

impl Drop for TempOutput {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_file(&self.temp);
        }
    }
}
