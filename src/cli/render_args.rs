//! `lapclone render`'s arguments: takes the command line and gives [`RenderArgs`] (scene,
//! output, frames, format, jobs, force, PNG compression, quality), the `A..B` frame range
//! parser the REPL and `track` share, and the output format those arguments name.

use lapclone::util::ShowPath;
use std::path::PathBuf;

use lapclone::output::{OutputError, OutputKind, PngCompression, SinkSettings};
use lapclone::FrameRange;

use crate::cli::UsageError;

/// `--format`'s values are the library's output kinds.
pub use crate::output::OutputKind as OutputFormat;

pub fn frame_range(text: &str) -> Result<FrameRange, String> {
    let (a, b) = text
        .split_once("..")
        .ok_or_else(|| format!("`{text}` is not a frame range A..B"))?;
    let parse = |s: &str| {
        s.trim()
            .parse::<u64>()
            .map_err(|_| format!("`{s}` is not a frame number"))
    };
    let (first, last) = (parse(a)?, parse(b)?);
    if first == 0 || last < first {
        return Err(format!("frame range `{text}` must have 1 ≤ A ≤ B"));
    }
    Ok(FrameRange { first, last })
}

#[derive(clap::Args, Debug)]
pub struct RenderArgs {
    /// Scene file (.rhai).
    pub scene: PathBuf,
    /// Output: a folder for frame_NNNN.png (a name without an extension, or ending in .png),
    /// or a file whose extension names the format (.gif, .apng, .mp4, .webm, .mov, .y4m);
    /// `-` writes Y4M to standard output.
    #[arg(
        short = 'o',
        long = "output",
        default_value = "frames",
        allow_hyphen_values = true
    )]
    pub output: PathBuf,
    /// Inclusive frame numbers to render, e.g. 1..24 (default: all).
    #[arg(long, value_parser = frame_range, allow_hyphen_values = true)]
    pub frames: Option<FrameRange>,
    /// Output format (default: the one the output's extension names).
    #[arg(long, value_enum)]
    pub format: Option<OutputFormat>,
    /// Encoder threads: PNG frames, and the conversion of video frames (default: available
    /// cores).
    #[arg(long, allow_hyphen_values = true)]
    pub jobs: Option<usize>,
    /// Remove frame files of an earlier render from the PNG output folder (without it,
    /// such a folder is refused).
    #[arg(long)]
    pub force: bool,
    /// PNG deflate effort for frame folders (default: fast).
    #[arg(long, value_enum)]
    pub png_compression: Option<PngCompression>,
    /// Constant quality for MP4/WebM/MOV (lower is better; H.264 default 20, VP9 default 32).
    #[arg(long, visible_alias = "quality", value_parser = clap::value_parser!(u32).range(0..=63), allow_hyphen_values = true)]
    pub crf: Option<u32>,
}

impl RenderArgs {
    /// The output format: `--format`, else the one `-o`'s extension names.
    pub(crate) fn output_kind(&self) -> anyhow::Result<OutputKind> {
        let kind = match OutputKind::resolve(&self.output, self.format) {
            Ok(kind) => kind,
            Err(OutputError::UnknownExtension { extension, .. }) => {
                return Err(UsageError(format!(
                    "-o {}: unknown output extension `.{extension}` (use .gif, .apng, .mp4, .webm, .mov, .y4m, a folder name without an extension, or --format)",
                    self.output.shown()
                ))
                .into())
            }
            Err(OutputError::StdoutNeedsY4m) => {
                return Err(UsageError("-o - (standard output) needs --format y4m".into()).into())
            }
            Err(other) => return Err(other.into()),
        };
        if self.output.as_os_str() == "-" {
            super::check_stdout_for_data()?;
        }
        if kind.needs_ffmpeg() && lapclone::util::find_program("ffmpeg").is_none() {
            anyhow::bail!("{}", lapclone::util::FFMPEG_MISSING);
        }
        Ok(kind)
    }

    /// Force, PNG compression and quality.
    pub(crate) fn sink_settings(&self) -> SinkSettings {
        SinkSettings {
            force: self.force,
            png_compression: self.png_compression.unwrap_or(PngCompression::Fast),
            crf: self.crf,
        }
    }

    /// A warning per flag given that the output `kind` does not use: it changes nothing,
    /// and a user who gave it expects it to.
    pub(crate) fn unused_flags(&self, kind: OutputKind) -> Vec<String> {
        let folder = kind == OutputKind::PngFolder;
        let unused = [
            (
                self.crf.is_some() && !kind.needs_ffmpeg(),
                "--crf",
                "MP4, WebM and MOV videos",
            ),
            (self.force && !folder, "--force", "PNG frame folders"),
            (
                self.png_compression.is_some() && !folder,
                "--png-compression",
                "PNG frame folders",
            ),
        ];
        unused
            .into_iter()
            .filter(|(given, ..)| *given)
            .map(|(_, flag, used_by)| {
                format!(
                    "{flag} applies to {used_by} only; this {} output ignores it",
                    kind.label()
                )
            })
            .collect()
    }

    /// The frames to render of a scene with `total` frames; beyond its end is a usage error.
    pub(crate) fn range(&self, total: u64) -> anyhow::Result<FrameRange> {
        match self.frames {
            None => Ok(FrameRange::all(total)),
            Some(r) if r.last > total => Err(UsageError(format!(
                "--frames {}..{}: the scene has {total} frames",
                r.first, r.last
            ))
            .into()),
            Some(r) => Ok(r),
        }
    }
}
