//! Reading footage ahead: takes footage, a frame range and a thread count, and gives the
//! frames in order to a callback while other threads decode the next ones (each with its own
//! `FootageReader`, frame i on thread i mod n). Decoding is most of a track's time, so it
//! runs on every core; the frames and their order are the same for any thread count. A video
//! is one ffmpeg stream and reads on one thread.

use std::ops::RangeInclusive;
use std::sync::mpsc::{sync_channel, Receiver};

use crate::pixels::{FloatImage, Footage, FootageError, FootageReader, FootageSource};

/// Frames a thread decodes before the callback takes them.
const AHEAD: usize = 2;

/// Calls `each(index, frame)` for every frame index in `range` (from 0), in order.
pub fn read_ahead<E: From<FootageError>>(
    footage: &Footage,
    fps: f64,
    range: RangeInclusive<u64>,
    threads: usize,
    mut each: impl FnMut(u64, &FloatImage) -> Result<(), E>,
) -> Result<(), E> {
    let threads = match footage.source {
        FootageSource::Video(_) => 1,
        FootageSource::Sequence { .. } => threads.clamp(1, 16),
    };
    if threads == 1 {
        let mut reader = FootageReader::new(footage.clone(), fps);
        for index in range {
            each(index, reader.frame(index)?)?;
        }
        return Ok(());
    }
    std::thread::scope(|scope| {
        let receivers: Vec<Receiver<Result<FloatImage, FootageError>>> = (0..threads as u64)
            .map(|lane| {
                let (send, receive) = sync_channel(AHEAD);
                let mut reader = FootageReader::new(footage.clone(), fps);
                let lane_range = range.clone();
                scope.spawn(move || {
                    let start = *lane_range.start();
                    for index in lane_range.filter(|i| (i - start) % threads as u64 == lane) {
                        let frame = reader.take_frame(index);
                        let failed = frame.is_err();
                        // A closed channel means the consumer stopped: stop too.
                        if send.send(frame).is_err() || failed {
                            return;
                        }
                    }
                });
                receive
            })
            .collect();
        let start = *range.start();
        for index in range.clone() {
            let lane = ((index - start) % threads as u64) as usize;
            // invariant: each lane sends every frame of its share, or an error, before ending.
            let frame = receivers[lane].recv().expect("a reading thread ended early")?;
            each(index, &frame)?;
        }
        Ok(())
    })
}
