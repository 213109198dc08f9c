//! Where `preview` and `clone` write their one PNG: takes the `-o` argument and gives a
//! checked destination (a `.png` file, or standard output for `-`, as `render -o -` is),
//! then writes a canvas or encoded PNG bytes to it. Another image extension is a usage
//! error, so `-o x.jpg` never holds PNG bytes under a JPEG name.

use lapclone::util::ShowPath;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use anyhow::Context as _;
use lapclone::pixels::{Canvas, PixelFormat};

use super::UsageError;

/// A PNG's path may have no extension or `.png`: another image extension is refused
/// (`what` says whose path it is), so no file holds PNG bytes under a JPEG name.
pub(crate) fn png_name_only(what: &str, path: &Path) -> Result<(), UsageError> {
    match path.extension() {
        Some(extension) if !extension.eq_ignore_ascii_case("png") => Err(UsageError(format!(
            "{what} writes PNG; name the output .png"
        ))),
        _ => Ok(()),
    }
}

/// A checked `-o` of a one-picture command.
pub(crate) enum PictureOut {
    File(PathBuf),
    Stdout,
}

impl PictureOut {
    /// Checks `output` for `command`: standard output open for `-`; otherwise a `.png` name
    /// (or none) whose folder exists and that names none of `inputs`.
    pub(crate) fn check(command: &str, output: &Path, inputs: &[&Path]) -> anyhow::Result<Self> {
        if output.as_os_str() == "-" {
            super::check_stdout_for_data()?;
            return Ok(PictureOut::Stdout);
        }
        png_name_only(&format!("-o {}: {command}", output.shown()), output)
            .map_err(|e| UsageError(format!("{} (or `-` for standard output)", e.0)))?;
        lapclone::output::check_output_folder(output)?;
        lapclone::output::refuse_input(output, inputs)?;
        Ok(PictureOut::File(output.to_path_buf()))
    }

    /// Writes `canvas` as a PNG in `format`, encoded on `threads` threads.
    pub(crate) fn write_canvas(
        &self,
        canvas: &Canvas,
        format: PixelFormat,
        threads: usize,
    ) -> anyhow::Result<()> {
        match self {
            PictureOut::File(path) => canvas
                .save_png_threaded(path, format, threads)
                .with_context(|| format!("writing {}", path.shown())),
            PictureOut::Stdout => {
                let mut png = Vec::new();
                canvas.write_png(format, threads, &mut png)?;
                self.write_bytes(&png)
            }
        }
    }

    /// Writes an encoded PNG.
    pub(crate) fn write_bytes(&self, png: &[u8]) -> anyhow::Result<()> {
        match self {
            PictureOut::File(path) => lapclone::util::write_atomic(path, png)
                .with_context(|| format!("writing {}", path.shown())),
            PictureOut::Stdout => {
                let mut out = std::io::stdout().lock();
                out.write_all(png)
                    .and_then(|()| out.flush())
                    .context("writing to standard output")
            }
        }
    }
}
