//! Output formats and how an output path names one: takes the `-o` path and gives the
//! [`OutputKind`] its extension stands for (`.gif`, `.apng`, `.mp4`, `.webm`, `.mov`,
//! `.y4m`; `-` is a Y4M stream on standard output; a name without an extension is a folder
//! of PNG frames).
//!
//! `.png` names a folder of PNG frames too (`out/shot.png/frame_0001.png …`), as it always
//! has: a render is a sequence, and one animated file is asked for with `.apng`.

use std::path::Path;

/// What `lapclone render` writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OutputKind {
    /// A folder of `frame_NNNN.png`.
    PngFolder,
    Gif,
    Apng,
    Mp4,
    Webm,
    Mov,
    Y4m,
}

impl OutputKind {
    /// The format `path` names; `Err` with the extension when it names none.
    pub fn from_path(path: &Path) -> Result<OutputKind, String> {
        if path.as_os_str() == "-" {
            return Ok(OutputKind::Y4m);
        }
        let Some(extension) = path.extension().and_then(|e| e.to_str()) else {
            return Ok(OutputKind::PngFolder);
        };
        Ok(match extension.to_ascii_lowercase().as_str() {
            "gif" => OutputKind::Gif,
            "apng" => OutputKind::Apng,
            "png" => OutputKind::PngFolder,
            "mp4" => OutputKind::Mp4,
            "webm" => OutputKind::Webm,
            "mov" => OutputKind::Mov,
            "y4m" => OutputKind::Y4m,
            _ => return Err(extension.to_string()),
        })
    }

    /// Whether it is written through ffmpeg.
    pub fn needs_ffmpeg(self) -> bool {
        matches!(self, OutputKind::Mp4 | OutputKind::Webm | OutputKind::Mov)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn extensions_name_their_formats() {
        let kind = |p: &str| OutputKind::from_path(Path::new(p));
        assert_eq!(kind("out/cat.gif"), Ok(OutputKind::Gif));
        assert_eq!(kind("cat.MP4"), Ok(OutputKind::Mp4));
        assert_eq!(kind("cat.png"), Ok(OutputKind::PngFolder));
        assert_eq!(kind("cat.apng"), Ok(OutputKind::Apng));
        assert_eq!(kind("frames"), Ok(OutputKind::PngFolder));
        assert_eq!(kind("-"), Ok(OutputKind::Y4m));
        assert_eq!(kind("cat.jpg"), Err("jpg".to_string()));
    }
}
