//! The one output rule (`TempOutput`, `write_atomic`): whole files or none, unique
//! temporary names, devices written through, folders refused.

use lapclone::util::{write_atomic, write_atomic_with, TempOutput};
use std::io::Write;
use std::path::Path;

#[test]
fn failed_write_leaves_no_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.bin");
    let err = write_atomic_with(&path, |_| Err(std::io::Error::other("boom")));
    assert!(err.is_err());
    assert!(!path.exists());
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

#[test]
fn write_lands_whole() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.bin");
    write_atomic(&path, b"hello").unwrap();
    assert_eq!(std::fs::read(&path).unwrap(), b"hello");
}

#[test]
fn two_writes_of_one_path_never_share_a_temporary_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.bin");
    let first = TempOutput::new(&path).unwrap();
    let second = TempOutput::new(&path).unwrap();
    assert_ne!(first.temp_path(), second.temp_path());
    std::fs::write(first.temp_path(), b"one").unwrap();
    std::fs::write(second.temp_path(), b"two").unwrap();
    first.commit().unwrap();
    assert_eq!(std::fs::read(&path).unwrap(), b"one");
    second.commit().unwrap();
    assert_eq!(std::fs::read(&path).unwrap(), b"two");
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
}

#[cfg(unix)]
#[test]
fn devices_are_written_through_and_folders_refused() {
    let null = TempOutput::new(Path::new("/dev/null")).unwrap();
    assert!(!null.is_temporary());
    assert_eq!(null.temp_path(), Path::new("/dev/null"));
    null.open().unwrap().write_all(b"gone").unwrap();
    null.commit().unwrap();
    let dir = tempfile::tempdir().unwrap();
    let error = TempOutput::new(dir.path()).unwrap_err();
    assert!(error.to_string().contains("it is a folder"), "{error}");
}

#[test]
fn missing_folder_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("nope").join("out.bin");
    assert!(write_atomic(&path, b"x").is_err());
}
