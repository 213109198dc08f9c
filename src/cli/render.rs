//! `lapclone render`, `preview` and `check`: scene files to frames. `check` parses, evaluates
//! and validates a scene and prints positioned errors with a caret; `render` and `preview`
//! take their final flags here and are wired to the renderer by the pipeline integration.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

use anyhow::Context;
use clap::ValueEnum;
use indicatif::{ProgressBar, ProgressStyle};
use lapclone::output::{
    foreign_frames, frame_digits, frame_file_name, ApngWriter, FfmpegWriter, Frame, FrameData,
    FrameRef, GifWriter, OutputKind, PendingVideo, Pixels, PngCompression, PngSequenceWriter,
    VideoFrames, VideoKind, Y4mWriter,
};
use lapclone::pixels::{Canvas, CanvasPixels, Depth};
use lapclone::render::{RenderError, Renderer};
use lapclone::script::{load_scene_and_imports, LoadedScene};

use crate::cli::UsageError;

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum OutputFormat {
    /// A folder of frame_NNNN.png.
    Png,
    Gif,
    Apng,
    /// H.264 (through ffmpeg).
    Mp4,
    /// VP9 (through ffmpeg).
    Webm,
    /// H.264, or ProRes 4444 with alpha for a transparent canvas (through ffmpeg).
    Mov,
    /// YUV4MPEG2, 4:4:4 (written without ffmpeg; `-o -` for standard output).
    Y4m,
}

impl OutputFormat {
    pub(crate) fn kind(self) -> OutputKind {
        match self {
            OutputFormat::Png => OutputKind::PngFolder,
            OutputFormat::Gif => OutputKind::Gif,
            OutputFormat::Apng => OutputKind::Apng,
            OutputFormat::Mp4 => OutputKind::Mp4,
            OutputFormat::Webm => OutputKind::Webm,
            OutputFormat::Mov => OutputKind::Mov,
            OutputFormat::Y4m => OutputKind::Y4m,
        }
    }
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum)]
pub enum CompressionArg {
    #[default]
    Fast,
    Default,
    Best,
}

/// Output settings beyond the format and path.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct SinkSettings {
    /// Remove frame files of another render from a PNG folder instead of refusing.
    pub force: bool,
    pub png_compression: PngCompression,
    pub crf: Option<u32>,
}

/// An inclusive frame range `A..B` (frame numbers as in the file names, from 1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameRange {
    pub first: u64,
    pub last: u64,
}

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
    /// PNG deflate effort for frame folders: fast (default; unchanged rows reuse the frame before's bands), default, or best (smaller files).
    #[arg(long, value_enum, default_value = "fast")]
    pub png_compression: CompressionArg,
    /// Constant quality for MP4/WebM/MOV (lower is better; H.264 default 20, VP9 default 32).
    #[arg(long, visible_alias = "quality", value_parser = clap::value_parser!(u32).range(0..=63))]
    pub crf: Option<u32>,
}

/// The output format: `--format`, else the one `-o`'s extension names.
fn output_kind(args: &RenderArgs) -> anyhow::Result<OutputKind> {
    let kind = match (args.format, OutputKind::from_path(&args.output)) {
        // An explicit format wins: the name is then just a name.
        (Some(format), _) => format.kind(),
        (None, Ok(named)) => named,
        (None, Err(extension)) => {
            return Err(UsageError(format!(
                "-o {}: unknown output extension `.{extension}` (use .gif, .apng, .mp4, .webm, .mov, .y4m, a folder name without an extension, or --format)",
                args.output.display()
            ))
            .into())
        }
    };
    if args.output.as_os_str() == "-" && kind != OutputKind::Y4m {
        return Err(UsageError("-o - (standard output) needs --format y4m".into()).into());
    }
    if args.output.as_os_str() == "-" && !super::stdout_is_open() {
        anyhow::bail!("-o -: standard output is closed");
    }
    if kind.needs_ffmpeg() && lapclone::util::find_program("ffmpeg").is_none() {
        anyhow::bail!("{}", lapclone::util::FFMPEG_MISSING);
    }
    Ok(kind)
}

#[derive(clap::Args, Debug)]
#[command(group(clap::ArgGroup::new("when").args(["t", "frame"]).multiple(false)))]
pub struct PreviewArgs {
    pub scene: PathBuf,
    /// Time in seconds.
    #[arg(long = "t", value_parser = crate::cli::finite_f64, allow_hyphen_values = true)]
    pub t: Option<f64>,
    /// Frame number (from 1).
    #[arg(long, allow_hyphen_values = true)]
    pub frame: Option<u64>,
    #[arg(short = 'o', long = "output")]
    pub output: PathBuf,
}

#[derive(clap::Args, Debug)]
pub struct CheckArgs {
    /// Scene file (.rhai).
    pub scene: PathBuf,
}

pub fn run_render(args: RenderArgs) -> anyhow::Result<()> {
    let jobs = super::jobs(args.jobs, default_jobs())?;
    // Before any output exists, so that Ctrl-C always goes through the clean-up below.
    let cancel = install_cancel_handler();
    let kind = output_kind(&args)?;
    let settings = SinkSettings {
        force: args.force,
        png_compression: match args.png_compression {
            CompressionArg::Fast => PngCompression::Fast,
            CompressionArg::Default => PngCompression::Default,
            CompressionArg::Best => PngCompression::Best,
        },
        crf: args.crf,
    };
    // Before the scene: a video's ffmpeg starts up while the scene loads.
    let plan = SinkPlan::new(kind, &args.output, settings)?;
    let (loaded, imports, mut renderer) = load_renderer(&args.scene)?;
    for warning in renderer.point_warnings() {
        eprintln!("warning: {warning}");
    }
    super::inputs::refuse_render_input(kind, &args.output, &loaded, &imports)?;
    let total = renderer.frame_count();
    let range = match args.frames {
        None => FrameRange {
            first: 1,
            last: total,
        },
        Some(r) if r.last > total => {
            return Err(UsageError(format!(
                "--frames {}..{}: the scene has {total} frames",
                r.first, r.last
            ))
            .into())
        }
        Some(r) => r,
    };
    let started = Instant::now();
    let mut sink = plan.open(&renderer, range, jobs, cancel.clone())?;
    let progress = progress_bar(range.last - range.first + 1);
    let mut compute_ms = 0.0;
    for number in range.first..=range.last {
        if cancel.load(Ordering::Relaxed) {
            sink.abandon();
            anyhow::bail!("interrupted: stopped after frame {}", number - 1);
        }
        if let Err(e) = renderer.render_frame(number - 1) {
            sink.abandon();
            return Err(positioned(&loaded, e));
        }
        compute_ms += renderer.last_stats().total_ms;
        if let Err(error) = sink.push(number, renderer.frame()) {
            // The writers see Ctrl-C too: report the interruption, not their refusal.
            if cancel.load(Ordering::Relaxed) {
                sink.abandon();
                anyhow::bail!("interrupted: stopped after frame {}", number - 1);
            }
            sink.abandon();
            return Err(error);
        }
        progress.inc(1);
    }
    progress.finish_and_clear();
    let written = match sink.finish() {
        Err(_) if cancel.load(Ordering::Relaxed) => {
            anyhow::bail!("interrupted: stopped while writing the last frames")
        }
        result => result?,
    };
    let frames = range.last - range.first + 1;
    let seconds = started.elapsed().as_secs_f64();
    let factorisations = renderer.factorisations();
    let summary = format!(
        "rendered {frames} frames to {} in {seconds:.2} s ({:.1} fps; {:.2} ms/frame compute; {factorisations} factorisation{})",
        written.display(),
        frames as f64 / seconds,
        compute_ms / frames as f64,
        if factorisations == 1 { "" } else { "s" }
    );
    // Standard output may be the video stream itself.
    if args.output.as_os_str() == "-" {
        eprintln!("{summary}");
    } else {
        super::say(summary)?;
    }
    Ok(())
}

pub fn run_preview(args: PreviewArgs) -> anyhow::Result<()> {
    if args.t.is_some_and(|t| t < 0.0) || args.frame == Some(0) {
        return Err(UsageError("--t must be ≥ 0 and --frame ≥ 1".into()).into());
    }
    super::clone::check_output_folder(&args.output)?;
    let (loaded, imports, mut renderer) = load_renderer(&args.scene)?;
    super::inputs::refuse_scene_input(&args.output, &loaded, &imports)?;
    let format = renderer.output_format();
    let canvas = match (args.t, args.frame) {
        (Some(t), _) => renderer.render_time(t),
        (None, Some(frame)) => renderer.render_frame(frame - 1),
        (None, None) => renderer.render_frame(0),
    }
    .map_err(|e| positioned(&loaded, e))?;
    canvas
        .save_png_threaded(&args.output, format, default_jobs())
        .with_context(|| format!("writing {}", args.output.display()))?;
    Ok(())
}

pub fn run_check(args: CheckArgs) -> anyhow::Result<()> {
    let (loaded, _, renderer) = load_renderer(&args.scene)?;
    let c = &loaded.scene.canvas;
    let handles: usize = loaded.scene.patches.iter().map(|p| p.handles.len()).sum();
    let pins: usize = loaded.scene.patches.iter().map(|p| p.pins.len()).sum();
    let vertices: usize = renderer.vertex_counts().iter().sum();
    super::say(format_args!(
        "{}: ok — {}×{}, {} fps, {} s ({} frames), {} patches ({vertices} mesh vertices), {handles} handles, {pins} pins",
        args.scene.display(),
        c.width,
        c.height,
        c.fps,
        c.duration,
        c.frame_count(),
        loaded.scene.patches.len(),
    ))?;
    for warning in loaded
        .warnings()
        .into_iter()
        .chain(renderer.point_warnings())
    {
        eprintln!("warning: {warning}");
    }
    Ok(())
}

/// Parses, validates and builds the renderer (meshes and factors every patch); every error
/// comes back positioned at the scene call it is about.
fn load_renderer(scene: &Path) -> anyhow::Result<(LoadedScene, Vec<PathBuf>, Renderer)> {
    let (loaded, imports) = load_scene_and_imports(scene).map_err(|e| anyhow::anyhow!("{e}"))?;
    let renderer = lapclone::build_renderer(&loaded).map_err(|e| anyhow::anyhow!("{e}"))?;
    Ok((loaded, imports, renderer))
}

pub(crate) fn positioned(loaded: &LoadedScene, error: RenderError) -> anyhow::Error {
    let scene_error = loaded.error_at_patch(error.patch_name(), error.to_string());
    anyhow::anyhow!("{scene_error}")
}

fn install_cancel_handler() -> Arc<AtomicBool> {
    let cancel = Arc::new(AtomicBool::new(false));
    let flag = cancel.clone();
    // A second handler cannot be installed (e.g. in tests running several renders in one
    // process); rendering then simply is not interruptible, which is harmless.
    let _ = ctrlc::set_handler(move || flag.store(true, Ordering::Relaxed));
    cancel
}

pub(crate) fn default_jobs() -> usize {
    lapclone::util::available_cores()
}

/// A frame counter on stderr when it is a terminal (hidden otherwise).
pub(crate) fn progress_bar(frames: u64) -> ProgressBar {
    if !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(frames);
    if let Ok(style) =
        ProgressStyle::with_template("{bar:40} {pos}/{len} frames  {per_sec}  eta {eta}")
    {
        bar.set_style(style);
    }
    bar
}

/// Where rendered frames go: a PNG folder (encoded in parallel), a GIF, an APNG, a Y4M
/// stream or a video through ffmpeg.
pub(crate) enum FrameSink {
    Png(PngSequenceWriter, Box<PngStaging>),
    Gif(Box<GifWriter>),
    Apng(Box<ApngWriter>),
    Y4m(Box<Y4mWriter>),
    Video(Box<FfmpegWriter>),
}

/// An output chosen before the scene is loaded; a video's ffmpeg is already starting.
pub(crate) struct SinkPlan {
    kind: OutputKind,
    output: PathBuf,
    settings: SinkSettings,
    video: Option<PendingVideo>,
}

impl SinkPlan {
    /// Checks the output path and, for a video, starts ffmpeg.
    pub(crate) fn new(
        kind: OutputKind,
        output: &Path,
        settings: SinkSettings,
    ) -> anyhow::Result<Self> {
        if kind != OutputKind::PngFolder && output.is_dir() {
            anyhow::bail!(
                "{} is a folder; name a file for {kind:?} output",
                output.display()
            );
        }
        let video_kind = match kind {
            OutputKind::Mp4 => Some(VideoKind::Mp4),
            OutputKind::Webm => Some(VideoKind::Webm),
            OutputKind::Mov => Some(VideoKind::Mov),
            _ => None,
        };
        let video = match video_kind {
            Some(video_kind) => {
                super::clone::check_output_folder(output)?;
                Some(FfmpegWriter::start(output, video_kind, settings.crf)?)
            }
            None => None,
        };
        Ok(SinkPlan {
            kind,
            output: output.to_path_buf(),
            settings,
            video,
        })
    }

    /// Opens the sink for `renderer`'s frames in `range`, encoding on `jobs` threads.
    pub(crate) fn open(
        self,
        renderer: &Renderer,
        range: FrameRange,
        jobs: usize,
        cancel: Arc<AtomicBool>,
    ) -> anyhow::Result<FrameSink> {
        let canvas = &renderer.scene().canvas;
        let output = self.output.as_path();
        Ok(match self.kind {
            OutputKind::PngFolder => {
                let (writer, staging) =
                    open_png_folder(output, renderer, range, jobs, cancel, self.settings)?;
                FrameSink::Png(writer, Box::new(staging))
            }
            OutputKind::Gif => {
                super::clone::check_output_folder(output)?;
                FrameSink::Gif(Box::new(GifWriter::create(output, canvas.fps)?))
            }
            OutputKind::Y4m => {
                let path = (output.as_os_str() != "-").then_some(output);
                if let Some(path) = path {
                    super::clone::check_output_folder(path)?;
                }
                let writer = Y4mWriter::create(path, canvas.width, canvas.height, canvas.fps)?;
                FrameSink::Y4m(Box::new(writer))
            }
            OutputKind::Mp4 | OutputKind::Webm | OutputKind::Mov => {
                // invariant: `new` starts a video for exactly these kinds.
                let pending = self.video.expect("a started video");
                let frames = VideoFrames {
                    width: canvas.width,
                    height: canvas.height,
                    fps: canvas.fps,
                    alpha: !renderer.frame().pixels_opaque(),
                };
                let writer = pending.begin(frames, jobs)?.with_cancel(cancel);
                if let Some((w, h)) = writer.padded() {
                    eprintln!(
                        "note: {}×{} has an odd side; the video is padded to {w}×{h} (4:2:0 needs even sides; the edge pixels repeat)",
                        canvas.width, canvas.height
                    );
                }
                FrameSink::Video(Box::new(writer))
            }
            OutputKind::Apng => {
                super::clone::check_output_folder(output)?;
                let frames = u32::try_from(range.last - range.first + 1)
                    .context("too many frames for an APNG")?;
                let sixteen = renderer.output_format().depth == Depth::Sixteen;
                FrameSink::Apng(Box::new(ApngWriter::create(
                    output,
                    canvas.width,
                    canvas.height,
                    sixteen,
                    frames,
                    canvas.fps,
                )?))
            }
        })
    }
}

impl FrameSink {
    pub(crate) fn push(&mut self, number: u64, canvas: &Canvas) -> anyhow::Result<()> {
        match self {
            FrameSink::Png(writer, _) => {
                let mut frame = writer.spare_frame().unwrap_or_else(|| empty_frame(canvas));
                fill_frame(&mut frame, canvas);
                writer.submit(number, frame)?;
            }
            FrameSink::Gif(writer) => writer.add(&frame_ref(canvas)?)?,
            FrameSink::Apng(writer) => writer.add(&frame_ref(canvas)?)?,
            FrameSink::Y4m(writer) => writer.add(&frame_ref(canvas)?)?,
            FrameSink::Video(writer) => writer.add(&frame_ref(canvas)?)?,
        }
        Ok(())
    }

    pub(crate) fn finish(self) -> anyhow::Result<PathBuf> {
        Ok(match self {
            FrameSink::Png(writer, staging) => {
                let written = writer.finish()?;
                staging.commit(&written)?
            }
            FrameSink::Gif(writer) => writer.finish()?,
            FrameSink::Apng(writer) => writer.finish()?,
            FrameSink::Y4m(writer) => writer.finish()?,
            FrameSink::Video(writer) => writer.finish()?,
        })
    }

    /// Drops the sink after a failure or an interruption: writers remove their temporary
    /// files (a PNG sequence its temporary folder).
    pub(crate) fn abandon(self) {
        if let FrameSink::Png(writer, _) = self {
            let _ = writer.finish();
        }
    }
}

/// A PNG sequence's frames, written into a temporary folder beside the destination and
/// moved into place only once every frame is written: a failed or interrupted render
/// leaves no new folder, and an existing folder exactly as it was.
pub(crate) struct PngStaging {
    dest: PathBuf,
    temp: tempfile::TempDir,
    /// Frame files of an earlier render to remove at the end (`--force`).
    foreign: Vec<PathBuf>,
}

impl PngStaging {
    /// Moves the written frames into the destination (or the whole folder, if it is new).
    fn commit(self, written: &[PathBuf]) -> anyhow::Result<PathBuf> {
        let dest = self.dest;
        if !dest.exists() {
            let temp = self.temp.keep();
            if let Err(e) = std::fs::rename(&temp, &dest) {
                let _ = std::fs::remove_dir_all(&temp);
                return Err(e).with_context(|| format!("moving the frames to {}", dest.display()));
            }
            return Ok(dest);
        }
        for path in &self.foreign {
            std::fs::remove_file(path).with_context(|| format!("removing {}", path.display()))?;
        }
        for path in written {
            // invariant: the writer names every frame `temp/frame_N.png`.
            let name = path.file_name().expect("a frame file name");
            let target = dest.join(name);
            std::fs::rename(path, &target)
                .with_context(|| format!("moving the frames to {}", dest.display()))?;
        }
        Ok(dest)
    }
}

/// The PNG frame folder (created at the end if missing, its parent never); frame files of
/// another render in it are refused, or removed at the end with `--force`, so the folder
/// never holds a mixed set.
fn open_png_folder(
    output: &Path,
    renderer: &Renderer,
    range: FrameRange,
    jobs: usize,
    cancel: Arc<AtomicBool>,
    settings: SinkSettings,
) -> anyhow::Result<(PngSequenceWriter, PngStaging)> {
    let foreign = if output.is_dir() {
        existing_frames(output, renderer, range, settings)?
    } else if output.exists() || output.symlink_metadata().is_ok() {
        anyhow::bail!(
            "{} exists and is not a folder; name a folder for PNG frames",
            output.display()
        );
    } else {
        super::clone::check_output_folder(output)?;
        Vec::new()
    };
    let parent = match output.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir,
        _ => Path::new("."),
    };
    let name = output.file_name().unwrap_or_default().to_string_lossy();
    let temp = tempfile::Builder::new()
        .prefix(&format!(".{name}."))
        .suffix(".tmp")
        .tempdir_in(parent)
        .with_context(|| format!("creating a folder beside {}", output.display()))?;
    let writer = PngSequenceWriter::new(
        temp.path(),
        renderer.frame_count(),
        jobs,
        settings.png_compression,
        cancel,
    )?;
    let staging = PngStaging {
        dest: output.to_path_buf(),
        temp,
        foreign,
    };
    Ok((writer, staging))
}

/// The frame files of another render in the existing folder `output`: an error without
/// `--force`, else the files to remove once the new frames are in.
fn existing_frames(
    output: &Path,
    renderer: &Renderer,
    range: FrameRange,
    settings: SinkSettings,
) -> anyhow::Result<Vec<PathBuf>> {
    let digits = frame_digits(renderer.frame_count());
    let ours: std::collections::HashSet<String> = (range.first..=range.last)
        .map(|n| frame_file_name(n, digits))
        .collect();
    let foreign = foreign_frames(output, |name| ours.contains(name))
        .with_context(|| format!("reading {}", output.display()))?;
    if let Some(first) = foreign.first() {
        if !settings.force {
            anyhow::bail!(
                "{} holds {} frame files of another render (e.g. {}); use --force to remove them, or another folder",
                output.display(),
                foreign.len(),
                first.file_name().unwrap_or_default().to_string_lossy()
            );
        }
    }
    Ok(foreign)
}

fn frame_ref(canvas: &Canvas) -> anyhow::Result<FrameRef<'_>> {
    let pixels = match canvas.pixels() {
        CanvasPixels::Eight(p) => Pixels::Rgba8(p.as_flattened()),
        CanvasPixels::Sixteen(p) => Pixels::Rgba16(p.as_flattened()),
    };
    Ok(FrameRef::new(canvas.width(), canvas.height(), pixels)?)
}

fn empty_frame(canvas: &Canvas) -> Frame {
    Frame {
        width: canvas.width(),
        height: canvas.height(),
        data: FrameData::Rgba8(Vec::new()),
    }
}

/// Copies the canvas into a (recycled) frame buffer without reallocating when sizes match.
fn fill_frame(frame: &mut Frame, canvas: &Canvas) {
    frame.width = canvas.width();
    frame.height = canvas.height();
    match (canvas.pixels(), &mut frame.data) {
        (CanvasPixels::Eight(p), FrameData::Rgba8(out)) => {
            out.clear();
            out.extend_from_slice(p.as_flattened());
        }
        (CanvasPixels::Sixteen(p), FrameData::Rgba16(out)) => {
            out.clear();
            out.extend_from_slice(p.as_flattened());
        }
        (CanvasPixels::Eight(p), data) => *data = FrameData::Rgba8(p.as_flattened().to_vec()),
        (CanvasPixels::Sixteen(p), data) => *data = FrameData::Rgba16(p.as_flattened().to_vec()),
    }
}
