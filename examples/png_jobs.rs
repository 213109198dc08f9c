//! PNG sequence encoding speed with 1 and 2 jobs on 1920×1080 frames (release build):
//! `cargo run --release --example png_jobs`.

use std::sync::Arc;
use std::time::Instant;

use lapclone::output::{Frame, FrameData, PngCompression, PngSequenceWriter};

fn main() {
    let (w, h, n) = (1920u32, 1080u32, 24u64);
    let frames: Vec<Frame> = (0..n)
        .map(|k| Frame {
            width: w,
            height: h,
            data: FrameData::Rgba8(
                (0..w * h * 4)
                    .map(|i| {
                        let (x, y) = ((i / 4) % w, (i / 4) / w);
                        ((x * 3 + y * 5 + k as u32 * 7 + (x * y) % 11) % 256) as u8
                    })
                    .collect(),
            ),
        })
        .collect();
    let mut seconds = Vec::new();
    for jobs in [1usize, 2] {
        let dir = tempfile::tempdir().unwrap();
        let start = Instant::now();
        let mut writer =
            PngSequenceWriter::new(dir.path(), n, jobs, PngCompression::Fast, Arc::default())
                .unwrap();
        for (i, f) in frames.iter().enumerate() {
            writer.submit(i as u64 + 1, f.clone()).unwrap();
        }
        writer.finish().unwrap();
        let s = start.elapsed().as_secs_f64();
        println!(
            "jobs={jobs}: {n} frames in {s:.3} s ({:.1} ms/frame)",
            s * 1000.0 / n as f64
        );
        seconds.push(s);
    }
    println!("speed-up 2 jobs vs 1: {:.2}×", seconds[0] / seconds[1]);
}
