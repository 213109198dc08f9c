//! An animated GIF from frames: takes frames in order and the fps, gives one `.gif` file
//! (looping forever, delays in whole centiseconds that never drift).
//!
//! Once per animation: one global palette, quantised from the first
//! [`PALETTE_FRAMES`] frames (see [`Palette::from_samples`]). Per frame: every pixel is
//! mapped onto that palette (cached exact nearest colour, optional ordered dithering) and
//! only the rectangle of changed indices is stored, unchanged pixels in it transparent
//! (see `gif_frame`). Mapping and LZW compression run on `jobs` threads; each record depends
//! only on its frame and the one before, so the bytes are identical for any job count.
//! Written through a temporary file and renamed on [`GifWriter::finish`]; a failed or
//! cancelled (dropped) write leaves nothing behind.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::mpsc::{channel, Receiver};
use std::sync::Arc;

use crate::util::TempOutput;
use super::gif_frame::{EncodedFrame, FrameEncoder};
use super::gif_palette::{Palette, PaletteMap};
use super::pool::WorkerPool;
use super::{FrameRef, OutputError};

/// Frames sampled for the palette (fewer if the animation is shorter).
pub const PALETTE_FRAMES: usize = 4;

/// A note when `fps` is past what GIF players keep: delays are whole centiseconds, and
/// browsers show one under 2 cs for 10 cs, so above 50 fps the GIF plays slower.
pub(crate) fn slow_in_players(fps: f64) -> Option<String> {
    (fps > 50.0).then(|| {
        format!(
            "{} fps is past what GIF players keep (delays are whole centiseconds, and a \
             delay under 2 cs plays as 10 cs): this GIF plays slower than the scene; APNG or \
             a video keeps the rate",
            crate::util::number_text(fps)
        )
    })
}

/// GIF delays are whole centiseconds; frame i lasts from round(100·i/fps) to round(100·(i+1)/fps).
pub fn gif_delays_cs(frames: usize, fps: f64) -> Vec<u64> {
    super::rounded_steps(frames, fps, 100.0)
}

/// How a GIF is encoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GifOptions {
    /// Threads mapping and compressing frames (1 = on the caller's thread).
    pub jobs: usize,
    /// Ordered (8×8 Bayer) dithering: smoother gradients, larger files.
    pub dither: bool,
}

impl Default for GifOptions {
    fn default() -> Self {
        GifOptions {
            jobs: 1,
            dither: false,
        }
    }
}

type Rgba = Arc<Vec<u8>>;

struct Job {
    index: u64,
    current: Rgba,
    previous: Option<Rgba>,
}

struct Done {
    job: Job,
    encoded: EncodedFrame,
}

/// Where frames are encoded: inline, or on worker threads.
enum Pipeline {
    Inline(FrameEncoder),
    Threads {
        pool: WorkerPool<Job, ()>,
        results: Receiver<Done>,
    },
}

pub struct GifWriter {
    path: PathBuf,
    temp: Option<TempOutput>,
    file: Option<BufWriter<File>>,
    encoder: Option<gif::Encoder<BufWriter<File>>>,
    fps: f64,
    options: GifOptions,
    size: Option<(u32, u32)>,
    warmup: Vec<Rgba>,
    pipeline: Option<Pipeline>,
    last: Option<Rgba>,
    pool: Vec<Vec<u8>>,
    dispatched: u64,
    ready: BTreeMap<u64, EncodedFrame>,
    written: u64,
    held: Option<gif::Frame<'static>>,
}

impl GifWriter {
    /// Starts a GIF at `path` shown at `fps`, encoded on the caller's thread, no dithering.
    pub fn create(path: &Path, fps: f64) -> Result<Self, OutputError> {
        Self::create_with(path, fps, GifOptions::default())
    }

    /// Starts a GIF at `path` shown at `fps`, encoded as `options` say.
    pub fn create_with(path: &Path, fps: f64, options: GifOptions) -> Result<Self, OutputError> {
        if !(fps.is_finite() && fps > 0.0) {
            return Err(OutputError::BadFrame(format!("fps {fps} must be > 0")));
        }
        let io = |e| OutputError::io(path, e);
        let temp = TempOutput::new(path).map_err(io)?;
        let file = temp.open().map_err(io)?;
        Ok(GifWriter {
            path: path.to_path_buf(),
            temp: Some(temp),
            file: Some(BufWriter::with_capacity(1 << 16, file)),
            encoder: None,
            fps,
            options: GifOptions {
                jobs: options.jobs.max(1),
                ..options
            },
            size: None,
            warmup: Vec::new(),
            pipeline: None,
            last: None,
            pool: Vec::new(),
            dispatched: 0,
            ready: BTreeMap::new(),
            written: 0,
            held: None,
        })
    }

    /// Appends the next frame (16-bit frames are rounded to 8 bits); all frames share a size.
    pub fn add(&mut self, frame: &FrameRef<'_>) -> Result<(), OutputError> {
        let size = (frame.width(), frame.height());
        if size.0 > u16::MAX as u32 || size.1 > u16::MAX as u32 {
            return Err(OutputError::BadFrame(format!(
                "a GIF is at most {0}×{0}, the frame is {1}×{2}",
                u16::MAX,
                size.0,
                size.1
            )));
        }
        if *self.size.get_or_insert(size) != size {
            return Err(OutputError::BadFrame(
                "all GIF frames must have the same size".into(),
            ));
        }
        let mut rgba = self.pool.pop().unwrap_or_default();
        frame.write_rgba8(&mut rgba);
        let rgba = Arc::new(rgba);
        if self.pipeline.is_some() {
            return self.dispatch(rgba);
        }
        self.warmup.push(rgba);
        if self.warmup.len() == PALETTE_FRAMES {
            self.start()?;
        }
        Ok(())
    }

    /// Completes the file and moves it into place.
    pub fn finish(mut self) -> Result<PathBuf, OutputError> {
        if self.size.is_none() {
            return Err(OutputError::BadFrame(
                "a GIF needs at least one frame".into(),
            ));
        }
        if self.pipeline.is_none() {
            self.start()?;
        }
        self.drain()?;
        if let Some(last) = self.held.take() {
            self.write_record(&last)?;
        }
        let path = self.path.clone();
        let io = |e| OutputError::io(&path, e);
        // invariant: `start` created the encoder.
        let encoder = self.encoder.take().expect("encoder started");
        let mut file = encoder.into_inner()?;
        file.flush().map_err(io)?;
        drop(file);
        // invariant: only `finish` (which consumes self) takes the temporary file.
        let temp = self.temp.take().expect("temporary file present");
        temp.commit().map_err(io)?;
        Ok(path)
    }

    /// Builds the palette from the frames so far, writes the header and starts encoding.
    fn start(&mut self) -> Result<(), OutputError> {
        let samples: Vec<&[u8]> = self.warmup.iter().map(|f| f.as_slice()).collect();
        let palette = Palette::from_samples(&samples);
        // invariant: `add` recorded the size before any frame reached the warm-up list.
        let (width, height) = self.size.expect("size known");
        // invariant: `create_with` opened the file and only `start` (run once) takes it.
        let file = self.file.take().expect("file open");
        let mut encoder =
            gif::Encoder::new(file, width as u16, height as u16, &palette.gif_table())?;
        encoder.set_repeat(gif::Repeat::Infinite)?;
        self.encoder = Some(encoder);
        self.pipeline = Some(self.spawn(palette, width, height));
        for frame in std::mem::take(&mut self.warmup) {
            self.dispatch(frame)?;
        }
        Ok(())
    }

    fn spawn(&self, palette: Palette, width: u32, height: u32) -> Pipeline {
        let (fps, dither, jobs) = (self.fps, self.options.dither, self.options.jobs);
        if jobs == 1 {
            return Pipeline::Inline(FrameEncoder::new(
                PaletteMap::new(palette, dither),
                width,
                height,
            ));
        }
        let (done, results) = channel::<Done>();
        let pool = WorkerPool::new(jobs, move || {
            let map = PaletteMap::new(palette.clone(), dither);
            let mut encoder = FrameEncoder::new(map, width, height);
            let done = done.clone();
            // A closed result channel means the writer is gone: skip what is left.
            move |job| done.send(run(&mut encoder, job, fps)).map_err(|_| ())
        });
        Pipeline::Threads { pool, results }
    }

    fn dispatch(&mut self, current: Rgba) -> Result<(), OutputError> {
        let job = Job {
            index: self.dispatched,
            previous: self.last.replace(current.clone()),
            current,
        };
        self.dispatched += 1;
        let fps = self.fps;
        // invariant: dispatch runs after `start`
        let pipeline = self.pipeline.as_mut().expect("started");
        match pipeline {
            Pipeline::Inline(encoder) => {
                let done = run(encoder, job, fps);
                self.accept(done)
            }
            Pipeline::Threads { pool, results } => {
                pool.send(job)
                    .map_err(|_| OutputError::Worker("a GIF encoder thread stopped".into()))?;
                let finished: Vec<Done> = results.try_iter().collect();
                finished.into_iter().try_for_each(|done| self.accept(done))
            }
        }
    }

    /// Waits for every dispatched frame and stops the workers.
    fn drain(&mut self) -> Result<(), OutputError> {
        let Some(Pipeline::Threads { pool, results }) = self.pipeline.as_mut() else {
            return Ok(());
        };
        // The result channel is unbounded, so the workers finish the queue without waiting;
        // once they have ended, every result there will be is in the channel.
        pool.stop(|| ());
        let finished: Vec<Done> = results.try_iter().collect();
        finished.into_iter().try_for_each(|done| self.accept(done))?;
        if self.written < self.dispatched {
            return Err(OutputError::Worker("a GIF encoder thread panicked".into()));
        }
        Ok(())
    }

    /// Takes an encoded frame; writes every frame now complete in order, holding the last
    /// back one step because the next one may replace it.
    fn accept(&mut self, done: Done) -> Result<(), OutputError> {
        self.recycle(done.job.current);
        if let Some(previous) = done.job.previous {
            self.recycle(previous);
        }
        self.ready.insert(done.job.index, done.encoded);
        while let Some(encoded) = self.ready.remove(&self.written) {
            if let Some(replacement) = encoded.replace_previous {
                self.held = Some(replacement);
            }
            if let Some(previous) = self.held.replace(encoded.frame) {
                self.write_record(&previous)?;
            }
            self.written += 1;
        }
        Ok(())
    }

    fn write_record(&mut self, frame: &gif::Frame<'_>) -> Result<(), OutputError> {
        // invariant: records exist only after `start` created the encoder.
        let encoder = self.encoder.as_mut().expect("encoder started");
        Ok(encoder.write_lzw_pre_encoded_frame(frame)?)
    }

    /// Keeps a frame buffer for reuse once no job refers to it.
    fn recycle(&mut self, frame: Rgba) {
        if let Ok(buffer) = Arc::try_unwrap(frame) {
            if self.pool.len() < 2 * self.options.jobs + 2 {
                self.pool.push(buffer);
            }
        }
    }
}

fn run(encoder: &mut FrameEncoder, job: Job, fps: f64) -> Done {
    let delay = step_cs(job.index, fps);
    let previous = job
        .previous
        .as_deref()
        .map(|p| (p.as_slice(), step_cs(job.index - 1, fps)));
    let encoded = encoder.encode(&job.current, previous, delay);
    Done { job, encoded }
}

fn step_cs(index: u64, fps: f64) -> u16 {
    let at = |i: u64| (i as f64 * 100.0 / fps).round() as u64;
    (at(index + 1) - at(index)).min(u16::MAX as u64) as u16
}
