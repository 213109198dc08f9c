//! Output formats and how an output path names one: takes the `-o` path and gives the
//! [`OutputKind`] its extension stands for (`.gif`, `.apng`, `.mp4`, `.webm`, `.mov`,
//! `.y4m`; `-` is a Y4M stream on standard output; a name without an extension is a folder
//! of PNG frames).
//!
//! `.png` names a folder of PNG frames too (`out/shot.png/frame_0001.png …`), as it always
//! has: a render is a sequence, and one animated file is asked for with `.apng`.

use std::path::Path;

use super::OutputError;

/// What `lapclone render` writes (also its `--format` values: png, gif, apng, mp4, webm, mov,
/// y4m).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub enum OutputKind {
    /// A folder of `frame_NNNN.png`.
    #[cfg_attr(feature = "cli", value(name = "png"))]
    PngFolder,
    /// An animated GIF.
    Gif,
    /// An animated PNG.
    Apng,
    /// H.264 through ffmpeg.
    Mp4,
    /// VP9 through ffmpeg.
    Webm,
    /// H.264, or ProRes 4444 for a transparent canvas, through ffmpeg.
    Mov,
    /// YUV4MPEG2 4:4:4, written without ffmpeg (`-`: standard output).
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
        // An extension is a format's name (`.png` names the frame folder, as `png` does).
        OutputKind::from_name(extension).map_err(|_| extension.to_string())
    }

    /// The format a name stands for: `png` (a folder of frames), `gif`, `apng`, `mp4`,
    /// `webm`, `mov`, `y4m` (the names `lapclone render --format` takes).
    pub fn from_name(name: &str) -> Result<OutputKind, OutputError> {
        Ok(match name.to_ascii_lowercase().as_str() {
            "png" => OutputKind::PngFolder,
            "gif" => OutputKind::Gif,
            "apng" => OutputKind::Apng,
            "mp4" => OutputKind::Mp4,
            "webm" => OutputKind::Webm,
            "mov" => OutputKind::Mov,
            "y4m" => OutputKind::Y4m,
            _ => return Err(OutputError::UnknownFormat(name.to_string())),
        })
    }

    /// The output's format: `format` when given (the path is then just a name), else the
    /// one `path` names. `-` (standard output) must be Y4M.
    pub fn resolve(path: &Path, format: Option<OutputKind>) -> Result<OutputKind, OutputError> {
        let kind = match (format, OutputKind::from_path(path)) {
            (Some(format), _) => format,
            (None, Ok(named)) => named,
            (None, Err(extension)) => {
                return Err(OutputError::UnknownExtension {
                    path: path.to_path_buf(),
                    extension,
                })
            }
        };
        if path.as_os_str() == "-" && kind != OutputKind::Y4m {
            return Err(OutputError::StdoutNeedsY4m);
        }
        Ok(kind)
    }

    /// Whether it is written through ffmpeg.
    pub fn needs_ffmpeg(self) -> bool {
        matches!(self, OutputKind::Mp4 | OutputKind::Webm | OutputKind::Mov)
    }

    /// Its name in a message: `PNG frame folder`, `GIF`, `APNG`, `MP4`, `WebM`, `MOV`, `Y4M`.
    pub fn label(self) -> &'static str {
        match self {
            OutputKind::PngFolder => "PNG frame folder",
            OutputKind::Gif => "GIF",
            OutputKind::Apng => "APNG",
            OutputKind::Mp4 => "MP4",
            OutputKind::Webm => "WebM",
            OutputKind::Mov => "MOV",
            OutputKind::Y4m => "Y4M",
        }
    }
}
