//! APNG frame differencing: records hold only changed rectangles, and compositing them
//! (fcTL offsets, `Source` blend, `None` dispose) gives back every frame exactly.

use std::path::Path;

use lapclone::output::{ApngWriter, Frame, FrameData};

/// A record's rectangle: (x, y, width, height).
type Rect = (u32, u32, u32, u32);

/// Decodes an APNG and composites its records; also gives each record's rectangle.
fn composite(path: &Path) -> (Vec<Vec<u8>>, Vec<Rect>) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let (width, bytes_per_pixel) = {
        let info = reader.info();
        (info.width as usize, info.bytes_per_pixel())
    };
    let count = reader.info().animation_control().unwrap().num_frames;
    let mut canvas = vec![0u8; reader.output_buffer_size().unwrap()];
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let (mut frames, mut rects) = (Vec::new(), Vec::new());
    for _ in 0..count {
        let info = reader.next_frame(&mut buf).unwrap();
        let fc = *reader.info().frame_control().unwrap();
        assert_eq!(fc.blend_op, png::BlendOp::Source);
        assert_eq!(fc.dispose_op, png::DisposeOp::None);
        let row = fc.width as usize * bytes_per_pixel;
        for r in 0..fc.height as usize {
            let to = ((fc.y_offset as usize + r) * width + fc.x_offset as usize) * bytes_per_pixel;
            canvas[to..to + row].copy_from_slice(&buf[r * info.line_size..][..row]);
        }
        frames.push(canvas.clone());
        rects.push((fc.x_offset, fc.y_offset, fc.width, fc.height));
    }
    (frames, rects)
}

fn png_bytes(frame: &Frame) -> Vec<u8> {
    let mut out = Vec::new();
    frame.as_ref().unwrap().write_png_bytes(&mut out);
    out
}

/// A gradient with a square moving across it; transparent left half in odd frames.
fn moving_square(w: u32, h: u32, k: u32, sixteen: bool) -> Frame {
    let mut samples = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let inside = (10 + 4 * k..18 + 4 * k).contains(&x) && (5..13).contains(&y);
            let alpha = if k % 2 == 1 && x < 3 { 0 } else { 255 };
            let pixel = if inside {
                [250, 10, 10, alpha]
            } else {
                [x * 5, y * 7, 99, alpha]
            };
            samples.extend(pixel.map(|v| v as u16 * 257));
        }
    }
    let data = if sixteen {
        FrameData::Rgba16(samples)
    } else {
        FrameData::Rgba8(samples.iter().map(|&v| (v >> 8) as u8).collect())
    };
    Frame {
        width: w,
        height: h,
        data,
    }
}

#[test]
fn apng_records_only_changes_and_round_trips_exactly() {
    let dir = tempfile::tempdir().unwrap();
    for sixteen in [false, true] {
        let path = dir.path().join(format!("a{sixteen}.png"));
        let mut frames: Vec<Frame> = (0..5).map(|k| moving_square(40, 24, k, sixteen)).collect();
        frames.push(frames[4].clone()); // unchanged frame
        let mut writer = ApngWriter::create(&path, 40, 24, sixteen, 6, 10.0).unwrap();
        for f in &frames {
            writer.add(&f.as_ref().unwrap()).unwrap();
        }
        writer.finish().unwrap();
        let (decoded, rects) = composite(&path);
        assert_eq!(decoded.len(), frames.len());
        for (i, (f, d)) in frames.iter().zip(&decoded).enumerate() {
            assert!(png_bytes(f) == *d, "frame {i} ({sixteen}) differs");
        }
        assert_eq!(rects[0], (0, 0, 40, 24));
        assert_eq!(rects[5], (0, 0, 1, 1), "unchanged frame");
        // Frames 1..4 toggle the transparent strip (x < 3) and move the square by 4 px.
        for (k, rect) in rects.iter().enumerate().take(5).skip(1) {
            let right = 18 + 4 * k as u32;
            assert_eq!(*rect, (0, 0, right, 24), "frame {k}");
        }
    }
}
