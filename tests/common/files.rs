//! Shared file helpers of the CLI and output tests: takes a bundled asset's name or a folder
//! and gives the asset's absolute path as scene text, or the folder's file names in order.
//! Included with `#[path = "common/files.rs"] mod files;`.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

/// Absolute path of a bundled asset, as text for a scene file.
pub fn asset(name: &str) -> String {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("assets")
        .join(name)
        .display()
        .to_string()
}

/// The names of the entries of `dir`, sorted.
pub fn sorted_names(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// Makes a FIFO at `path` (with `mkfifo`, as a user would).
#[cfg(unix)]
pub fn make_fifo(path: &Path) {
    let made = std::process::Command::new("mkfifo").arg(path).status();
    assert!(made.unwrap().success(), "mkfifo {}", path.display());
}
