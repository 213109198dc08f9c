//! Frame writers: file names, PNG sequences identical for any job count and decoding back to
//! the frames, APNG and GIF decoding back, and no leftovers after failures or cancellation.

use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use image::AnimationDecoder;
use lapclone::output::{
    apng_delays, frame_digits, frame_file_name, gif_delays_cs, ApngWriter, Frame, FrameData,
    FrameRef, GifWriter, OutputError, Pixels, PngCompression, PngSequenceWriter,
};

use crate::files;
use files::sorted_names;

/// A deterministic, not-too-compressible test pattern.
fn frame8(w: u32, h: u32, seed: u32) -> Frame {
    let mut state = seed.wrapping_mul(2654435761).wrapping_add(1);
    let data = (0..w * h * 4)
        .map(|i| {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            if i % 4 == 3 {
                255
            } else {
                ((i / 4 % w) * 3 + (state & 15)) as u8
            }
        })
        .collect();
    Frame {
        width: w,
        height: h,
        data: FrameData::Rgba8(data),
    }
}

fn frame16(w: u32, h: u32, seed: u32) -> Frame {
    let data = (0..w * h * 4)
        .map(|i| (i.wrapping_mul(7919).wrapping_add(seed * 104729) % 65536) as u16)
        .collect();
    Frame {
        width: w,
        height: h,
        data: FrameData::Rgba16(data),
    }
}

fn decode_png(path: &Path) -> (u32, u32, png::BitDepth, Vec<u8>) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    buf.truncate(info.buffer_size());
    (info.width, info.height, info.bit_depth, buf)
}

/// The samples a frame file holds: RGB when every pixel is opaque, else RGBA.
fn sequence_png_bytes(frame: &Frame) -> Vec<u8> {
    let frame = frame.as_ref().unwrap();
    let mut out = Vec::new();
    frame.write_png_samples(&mut out, frame.is_opaque());
    out
}

fn png_bytes(frame: &Frame) -> Vec<u8> {
    let mut out = Vec::new();
    frame.as_ref().unwrap().write_png_bytes(&mut out);
    out
}

#[test]
fn frame_names_are_zero_padded_to_the_last_number() {
    assert_eq!(frame_file_name(1, frame_digits(120)), "frame_0001.png");
    assert_eq!(frame_file_name(7, frame_digits(9999)), "frame_0007.png");
    assert_eq!(frame_file_name(42, frame_digits(12345)), "frame_00042.png");
}

#[test]
fn frame_ref_checks_its_size() {
    assert!(matches!(
        FrameRef::new(2, 2, Pixels::Rgba8(&[0; 15])),
        Err(OutputError::BadFrame(_))
    ));
    assert!(FrameRef::new(2, 2, Pixels::Rgba16(&[0; 16])).is_ok());
    assert!(FrameRef::new(0, 2, Pixels::Rgba8(&[])).is_err());
}

fn write_sequence(dir: &Path, frames: &[Frame], jobs: usize) -> Vec<std::path::PathBuf> {
    let mut writer = PngSequenceWriter::new(
        dir,
        frames.len() as u64,
        jobs,
        PngCompression::Fast,
        Arc::default(),
    )
    .unwrap();
    for (i, f) in frames.iter().enumerate() {
        writer.submit(i as u64 + 1, f.clone()).unwrap();
    }
    writer.finish().unwrap()
}

#[test]
fn png_sequence_is_identical_for_any_job_count_and_decodes_back() {
    let frames: Vec<Frame> = (0..6)
        .map(|i| {
            if i % 2 == 0 {
                frame8(37, 23, i)
            } else {
                frame16(37, 23, i)
            }
        })
        .collect();
    let one = tempfile::tempdir().unwrap();
    let two = tempfile::tempdir().unwrap();
    let paths = write_sequence(one.path(), &frames, 1);
    write_sequence(two.path(), &frames, 2);
    let expected: Vec<String> = (1..=6).map(|i| format!("frame_{i:04}.png")).collect();
    assert_eq!(sorted_names(one.path()), expected);
    assert_eq!(sorted_names(two.path()), expected);
    for (i, frame) in frames.iter().enumerate() {
        let name = &expected[i];
        let a = std::fs::read(one.path().join(name)).unwrap();
        let b = std::fs::read(two.path().join(name)).unwrap();
        assert_eq!(a, b, "{name} differs between 1 and 2 jobs");
        let (w, h, depth, data) = decode_png(&paths[i]);
        assert_eq!((w, h), (37, 23));
        let sixteen = matches!(frame.data, FrameData::Rgba16(_));
        assert_eq!(
            depth,
            if sixteen {
                png::BitDepth::Sixteen
            } else {
                png::BitDepth::Eight
            }
        );
        assert_eq!(data, sequence_png_bytes(frame), "{name} pixels");
    }
}

#[test]
fn a_failed_frame_leaves_no_temporary_files() {
    let dir = tempfile::tempdir().unwrap();
    // A folder where frame 2 should go makes its rename fail.
    std::fs::create_dir(dir.path().join("frame_0002.png")).unwrap();
    let mut writer =
        PngSequenceWriter::new(dir.path(), 3, 2, PngCompression::Fast, Arc::default()).unwrap();
    let mut result = Ok(());
    for i in 1..=3 {
        result = result.and(writer.submit(i, frame8(8, 8, i as u32)));
    }
    let finished = writer.finish();
    assert!(
        result.is_err() || finished.is_err(),
        "the failure must be reported"
    );
    let names = sorted_names(dir.path());
    assert!(names.iter().all(|n| !n.ends_with(".tmp")), "{names:?}");
    assert_eq!(
        decode_png(&dir.path().join("frame_0001.png")).3,
        sequence_png_bytes(&frame8(8, 8, 1))
    );
}

#[test]
fn cancel_stops_the_sequence_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    let cancel = Arc::new(AtomicBool::new(false));
    let mut writer =
        PngSequenceWriter::new(dir.path(), 10, 2, PngCompression::Fast, cancel.clone()).unwrap();
    writer.submit(1, frame8(16, 16, 1)).unwrap();
    cancel.store(true, Ordering::Relaxed);
    assert!(matches!(
        writer.submit(2, frame8(16, 16, 2)),
        Err(OutputError::Cancelled)
    ));
    assert!(matches!(writer.finish(), Err(OutputError::Cancelled)));
    let names = sorted_names(dir.path());
    assert!(names.iter().all(|n| n == "frame_0001.png"), "{names:?}");
}

#[test]
fn apng_decodes_back_to_the_same_frames() {
    let dir = tempfile::tempdir().unwrap();
    for sixteen in [false, true] {
        let path = dir.path().join(format!("anim{sixteen}.png"));
        let frames: Vec<Frame> = (0..4)
            .map(|i| {
                if sixteen {
                    frame16(19, 11, i)
                } else {
                    frame8(19, 11, i)
                }
            })
            .collect();
        let mut writer = ApngWriter::create(&path, 19, 11, sixteen, 4, 12.0).unwrap();
        for f in &frames {
            writer.add(&f.as_ref().unwrap()).unwrap();
        }
        writer.finish().unwrap();
        let decoder =
            png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&path).unwrap()));
        let mut reader = decoder.read_info().unwrap();
        let control = reader.info().animation_control().copied().unwrap();
        assert_eq!((control.num_frames, control.num_plays), (4, 0));
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let mut canvas = vec![0; reader.output_buffer_size().unwrap()];
        let pixel = if sixteen { 8 } else { 4 };
        for f in &frames {
            let info = reader.next_frame(&mut buf).unwrap();
            let fc = reader.info().frame_control().copied().unwrap();
            assert_eq!((fc.delay_num, fc.delay_den), (1, 12));
            // Records hold the changed rectangle only: composite them (blend Source).
            let row = fc.width as usize * pixel;
            for r in 0..fc.height as usize {
                let to = ((fc.y_offset as usize + r) * 19 + fc.x_offset as usize) * pixel;
                canvas[to..to + row].copy_from_slice(&buf[r * info.line_size..][..row]);
            }
            assert_eq!(canvas, png_bytes(f));
        }
        assert_eq!(
            sorted_names(dir.path())
                .iter()
                .filter(|n| n.ends_with(".tmp"))
                .count(),
            0
        );
    }
}

#[test]
fn unfinished_apng_leaves_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("a.png");
    let mut writer = ApngWriter::create(&path, 4, 4, false, 3, 24.0).unwrap();
    writer.add(&frame8(4, 4, 0).as_ref().unwrap()).unwrap();
    assert!(
        writer.add(&frame8(5, 4, 0).as_ref().unwrap()).is_err(),
        "size mismatch"
    );
    assert!(writer.finish().is_err());
    assert!(sorted_names(dir.path()).is_empty());
}

#[test]
fn gif_has_every_frame_with_exact_delays() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("a.gif");
    let mut writer = GifWriter::create(&path, 24.0).unwrap();
    for i in 0..5 {
        writer.add(&frame8(20, 10, i).as_ref().unwrap()).unwrap();
    }
    writer.add(&frame16(20, 10, 9).as_ref().unwrap()).unwrap();
    writer.finish().unwrap();
    let decoder = image::codecs::gif::GifDecoder::new(std::io::BufReader::new(
        std::fs::File::open(&path).unwrap(),
    ))
    .unwrap();
    let frames = decoder.into_frames().collect_frames().unwrap();
    assert_eq!(frames.len(), 6);
    let delays: Vec<u64> = frames
        .iter()
        .map(|f| {
            let (n, d) = f.delay().numer_denom_ms();
            (n / d / 10) as u64
        })
        .collect();
    assert_eq!(delays, gif_delays_cs(6, 24.0));
    assert_eq!(
        delays.iter().sum::<u64>(),
        25,
        "6 frames at 24 fps = 0.25 s"
    );
    assert_eq!(sorted_names(dir.path()), vec!["a.gif".to_string()]);
    // Same frames, same bytes.
    let again = dir.path().join("b.gif");
    let mut writer = GifWriter::create(&again, 24.0).unwrap();
    for i in 0..5 {
        writer.add(&frame8(20, 10, i).as_ref().unwrap()).unwrap();
    }
    writer.add(&frame16(20, 10, 9).as_ref().unwrap()).unwrap();
    writer.finish().unwrap();
    assert_eq!(
        std::fs::read(&path).unwrap(),
        std::fs::read(&again).unwrap()
    );
}

#[test]
fn fractional_fps_delays_do_not_drift() {
    // Rates whose fraction fits the 16-bit fields are exact; the slowest rate's 100 s too.
    assert_eq!(apng_delays(3, 23.976), vec![(125, 2997); 3]);
    assert_eq!(apng_delays(2, 1.0 / 3.0), vec![(3, 1); 2]);
    assert_eq!(apng_delays(2, 0.01), vec![(100, 1); 2]);
    assert_eq!(apng_delays(2, 30.0), vec![(1, 30); 2]);
    // Others in rounded milliseconds that never drift from the exact frame times.
    let fps = 999.999;
    let delays = apng_delays(1000, fps);
    let total: u64 = delays
        .iter()
        .map(|&(n, d)| {
            assert_eq!(d, 1000);
            n as u64
        })
        .sum();
    assert_eq!(total, (1000.0 / fps * 1000.0f64).round() as u64);
}
