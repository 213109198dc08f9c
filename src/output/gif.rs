//! An animated GIF from frames: takes frames in order and the fps, gives one `.gif` file
//! (looping forever). Colours are quantised per frame with NeuQuant (deterministic: the
//! same frames give the same bytes). Written through a temporary file and renamed on
//! [`GifWriter::finish`]; a failed or cancelled write leaves nothing behind.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use image::codecs::gif::{GifEncoder, Repeat};
use image::{Delay, RgbaImage};

use super::atomic::TempOutput;
use super::{FrameRef, OutputError};

/// GIF delays are whole centiseconds; frame i lasts from round(100·i/fps) to round(100·(i+1)/fps).
pub fn gif_delays_cs(frames: usize, fps: f64) -> Vec<u64> {
    super::rounded_steps(frames, fps, 100.0)
}

/// The file behind the encoder, shared so `finish` can flush it and see the error.
#[derive(Clone)]
struct Sink(Arc<Mutex<BufWriter<File>>>);

impl Write for Sink {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0.lock().unwrap_or_else(|p| p.into_inner()).write(buf)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.0.lock().unwrap_or_else(|p| p.into_inner()).flush()
    }
}

pub struct GifWriter {
    path: PathBuf,
    temp: TempOutput,
    sink: Sink,
    encoder: GifEncoder<Sink>,
    fps: f64,
    index: u64,
    size: Option<(u32, u32)>,
}

impl GifWriter {
    /// Starts a GIF at `path` shown at `fps`.
    pub fn create(path: &Path, fps: f64) -> Result<Self, OutputError> {
        if !(fps.is_finite() && fps > 0.0) {
            return Err(OutputError::BadFrame(format!("fps {fps} must be > 0")));
        }
        let temp = TempOutput::new(path);
        let file = File::create(temp.temp_path()).map_err(|e| OutputError::io(path, e))?;
        let sink = Sink(Arc::new(Mutex::new(BufWriter::with_capacity(
            1 << 16,
            file,
        ))));
        let mut encoder = GifEncoder::new_with_speed(sink.clone(), 10);
        encoder.set_repeat(Repeat::Infinite)?;
        Ok(GifWriter {
            path: path.to_path_buf(),
            temp,
            sink,
            encoder,
            fps,
            index: 0,
            size: None,
        })
    }

    /// Appends the next frame (16-bit frames are rounded to 8 bits); all frames share a size.
    pub fn add(&mut self, frame: &FrameRef<'_>) -> Result<(), OutputError> {
        let size = (frame.width(), frame.height());
        if *self.size.get_or_insert(size) != size {
            return Err(OutputError::BadFrame(
                "all GIF frames must have the same size".into(),
            ));
        }
        let delay_cs = step_cs(self.index, self.fps);
        let mut rgba = Vec::new();
        frame.write_rgba8(&mut rgba);
        // invariant: FrameRef guarantees width·height·4 samples.
        let image = RgbaImage::from_raw(size.0, size.1, rgba).expect("frame size checked");
        let delay = Delay::from_numer_denom_ms((delay_cs * 10) as u32, 1);
        self.encoder
            .encode_frame(image::Frame::from_parts(image, 0, 0, delay))?;
        self.index += 1;
        Ok(())
    }

    /// Completes the file and moves it into place.
    pub fn finish(self) -> Result<PathBuf, OutputError> {
        if self.index == 0 {
            return Err(OutputError::BadFrame(
                "a GIF needs at least one frame".into(),
            ));
        }
        let GifWriter {
            path,
            temp,
            mut sink,
            encoder,
            ..
        } = self;
        drop(encoder); // writes the trailer into the sink
        sink.flush().map_err(|e| OutputError::io(&path, e))?;
        drop(sink);
        temp.commit().map_err(|e| OutputError::io(&path, e))?;
        Ok(path)
    }
}

fn step_cs(index: u64, fps: f64) -> u64 {
    let at = |i: u64| (i as f64 * 100.0 / fps).round() as u64;
    at(index + 1) - at(index)
}
