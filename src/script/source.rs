//! Scene and module source files: takes a path and gives the file's text, refusing what is
//! not a regular file (a FIFO or a device would be read until it ends, which may be never)
//! and anything past the scene file limit. The one reader the scene, its modules and its
//! errors' source lines go through. A leading UTF-8 byte-order mark is dropped.

use std::path::Path;

/// The UTF-8 byte-order mark.
const BOM: &[u8] = b"\xEF\xBB\xBF";

/// The text of a scene or module file: a regular file of at most
/// [`MAX_SCENE_BYTES`](crate::limits::MAX_SCENE_BYTES), read no further than that even if it
/// grows meanwhile.
pub(super) fn read_source(path: &Path) -> std::io::Result<String> {
    let limit = crate::limits::MAX_SCENE_BYTES;
    let Some(mut bytes) = crate::util::read_input_file(path, limit)? else {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("it is larger than {} MiB, the limit for scene files", limit >> 20),
        ));
    };
    // Editors on Windows may start a UTF-8 file with a byte-order mark; it is not text.
    if bytes.starts_with(BOM) {
        bytes.drain(..BOM.len());
    }
    String::from_utf8(bytes).map_err(|_| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            "stream did not contain valid UTF-8",
        )
    })
}

#[cfg(test)]
mod tests {
    use super::read_source;

    /// A byte-order mark is not part of the text (it was a syntax error at 1:1); one inside
    /// the text is kept.
    #[test]
    fn a_leading_byte_order_mark_is_dropped() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bom.rhai");
        std::fs::write(&path, b"\xEF\xBB\xBFcanvas(64, 48);\n// \xEF\xBB\xBF\n").unwrap();
        assert_eq!(read_source(&path).unwrap(), "canvas(64, 48);\n// \u{feff}\n");
    }
}
