//! RGB → Y′CbCr for the video outputs: takes 8-bit straight-alpha RGBA pixels (or a whole
//! [`FrameRef`]) and gives 8-bit BT.709 limited-range levels — one pixel at a time for the
//! Y4M writer's 4:4:4, or the three planes of 4:2:0 (`yuv420p`) that the ffmpeg pipe feeds
//! its encoders. Both use the same integer coefficients, so the two outputs agree.
//!
//! Each pixel is first composited over black (rounded to 8 bits: neither format has alpha),
//! then Y = 16 + 219·E′y, Cb = 128 + 224·(E′b − E′y)/1.8556, Cr = 128 + 224·(E′r − E′y)/1.5748
//! with E′y = 0.2126 E′r + 0.7152 E′g + 0.0722 E′b and E′ = value / 255. The weights are
//! fixed point, scaled by 2¹⁶ (each within 0.5/2¹⁶ of the exact value; the chroma rows sum to
//! 0, so greys have Cb = Cr = 128 exactly), and every level is rounded once, at the end. A
//! 4:2:0 chroma sample is the rounded mean of its 2×2 block's unrounded values (centre
//! siting); a frame with an odd side is padded to even by repeating its last column or row.
//! Integer maths, row bands independent of each other: the same frame gives the same bytes on
//! any number of threads.

use super::{FrameRef, Pixels};

/// Fixed-point fraction bits of the weights.
const SHIFT: u32 = 16;
/// Luma weights: 219/255 · (0.2126, 0.7152, 0.0722) · 2¹⁶.
const Y_W: [i32; 3] = [11966, 40254, 4064];
/// Blue-difference weights: 224/255 · (−0.2126, −0.7152, 0.9278)/1.8556 · 2¹⁶.
const CB_W: [i32; 3] = [-6596, -22188, 28784];
/// Red-difference weights: 224/255 · (0.7874, −0.7152, −0.0722)/1.5748 · 2¹⁶.
const CR_W: [i32; 3] = [28784, -26145, -2639];

/// An 8-bit straight-alpha pixel composited over black: each of R, G, B times alpha / 255,
/// rounded to the nearest level (exactly, without a division or a branch, so rows
/// vectorise).
#[inline(always)]
fn over_black(px: [u8; 4]) -> [i32; 3] {
    let [r, g, b, a] = px.map(i32::from);
    [r, g, b].map(|v| {
        let x = v * a + 128;
        (x + (x >> 8)) >> 8
    })
}

#[inline(always)]
fn dot(w: [i32; 3], rgb: [i32; 3]) -> i32 {
    w[0] * rgb[0] + w[1] * rgb[1] + w[2] * rgb[2]
}

/// A fixed-point sum of `2^extra` weighted pixels plus `offset` levels, rounded to a level.
#[inline]
fn level(sum: i32, offset: i32, extra: u32) -> u8 {
    let shift = SHIFT + extra;
    ((sum + (offset << shift) + (1 << (shift - 1))) >> shift).clamp(0, 255) as u8
}

/// One 8-bit straight-alpha RGBA pixel as limited-range BT.709 `[Y, Cb, Cr]`.
pub fn rgb_to_ycbcr(rgba: [u8; 4]) -> [u8; 3] {
    let rgb = over_black(rgba);
    [
        level(dot(Y_W, rgb), 16, 0),
        level(dot(CB_W, rgb), 128, 0),
        level(dot(CR_W, rgb), 128, 0),
    ]
}

/// The size of a frame's 4:2:0 picture: each side rounded up to even.
pub fn yuv420_size(width: u32, height: u32) -> (u32, u32) {
    (width.next_multiple_of(2), height.next_multiple_of(2))
}

/// Bytes of a `width`×`height` frame as 4:2:0 planes (the padded size's Y, then Cb, then Cr).
pub fn yuv420_len(width: u32, height: u32) -> usize {
    let (w, h) = yuv420_size(width, height);
    let (w, h) = (w as usize, h as usize);
    w * h + 2 * (w / 2) * (h / 2)
}

/// Converts `frame` into `out` as 4:2:0 planes ([`yuv420_len`] bytes) on up to `threads`
/// threads (row bands; the bytes do not depend on the count).
pub fn frame_to_yuv420(frame: &FrameRef<'_>, out: &mut Vec<u8>, threads: usize) {
    convert_frame(frame, out, threads, crate::simd::Path::current());
}

/// [`frame_to_yuv420`] with the rows compiled for `path`.
fn convert_frame(frame: &FrameRef<'_>, out: &mut Vec<u8>, threads: usize, path: crate::simd::Path) {
    let (w, h) = (frame.width() as usize, frame.height() as usize);
    let (pw, ph) = yuv420_size(frame.width(), frame.height());
    let (pw, ph) = (pw as usize, ph as usize);
    out.resize(yuv420_len(frame.width(), frame.height()), 0);
    let (y_plane, chroma) = out.split_at_mut(pw * ph);
    let (cb_plane, cr_plane) = chroma.split_at_mut(pw / 2 * (ph / 2));
    let pairs = ph / 2;
    // Bands of whole row pairs; small frames are not worth a thread.
    let bands = threads.clamp(1, ((w * h) >> 14).max(1)).min(pairs);
    let per_band = pairs.div_ceil(bands);
    let bands = pairs.div_ceil(per_band);
    let source = RgbaRows::new(frame);
    let y_bands = y_plane.chunks_mut(per_band * 2 * pw);
    let cb_bands = cb_plane.chunks_mut(per_band * (pw / 2));
    let cr_bands = cr_plane.chunks_mut(per_band * (pw / 2));
    let jobs = y_bands.zip(cb_bands).zip(cr_bands).enumerate();
    std::thread::scope(|scope| {
        for (band, ((y, cb), cr)) in jobs {
            let source = &source;
            // Compiled for the best instruction set this CPU has (integer maths: the same
            // bytes on every path).
            let mut work = move || {
                path.run(Band {
                    source,
                    first_pair: band * per_band,
                    planes: [y, cb, cr],
                })
            };
            if band + 1 == bands {
                work();
            } else {
                scope.spawn(work);
            }
        }
    });
}

/// A frame's rows as 8-bit RGBA, rows and columns past the edge repeating the last one.
struct RgbaRows<'a> {
    pixels: Pixels<'a>,
    width: usize,
    height: usize,
}

impl<'a> RgbaRows<'a> {
    fn new(frame: &FrameRef<'a>) -> Self {
        RgbaRows {
            pixels: frame.pixels(),
            width: frame.width() as usize,
            height: frame.height() as usize,
        }
    }

    /// Row `y` (clamped to the frame) as 8-bit RGBA: borrowed, or rounded into `scratch`.
    fn row<'s>(&'s self, y: usize, scratch: &'s mut Vec<u8>) -> &'s [u8] {
        let y = y.min(self.height - 1);
        let range = y * self.width * 4..(y + 1) * self.width * 4;
        match self.pixels {
            Pixels::Rgba8(p) => &p[range],
            Pixels::Rgba16(p) => {
                scratch.clear();
                scratch.extend(
                    p[range]
                        .iter()
                        .map(|&v| ((u32::from(v) * 255 + 32767) / 65535) as u8),
                );
                scratch
            }
        }
    }
}

/// One band's work, as a kernel for [`crate::simd`].
struct Band<'a, 'f> {
    source: &'a RgbaRows<'f>,
    first_pair: usize,
    planes: [&'a mut [u8]; 3],
}

impl crate::simd::Kernel for Band<'_, '_> {
    type Output = ();

    #[inline(always)]
    fn call(self) {
        convert_band(self.source, self.first_pair, self.planes);
    }
}

/// Per-band rows: the chroma sums of two luma rows, and 16-bit rows rounded to 8 bits.
#[derive(Default)]
struct Scratch {
    cb: [Vec<i32>; 2],
    cr: [Vec<i32>; 2],
    rows: [Vec<u8>; 2],
}

/// Converts the row pairs from `first_pair` on into the band's slices of the three planes.
#[inline(always)]
fn convert_band(source: &RgbaRows<'_>, first_pair: usize, [y, cb, cr]: [&mut [u8]; 3]) {
    let pw = source.width.next_multiple_of(2);
    let mut scratch = Scratch::default();
    for row in scratch.cb.iter_mut().chain(scratch.cr.iter_mut()) {
        row.resize(pw, 0);
    }
    let rows = y.chunks_exact_mut(2 * pw);
    let chroma = cb.chunks_exact_mut(pw / 2).zip(cr.chunks_exact_mut(pw / 2));
    for (k, (luma, (cb_row, cr_row))) in rows.zip(chroma).enumerate() {
        let (y_top, y_bottom) = luma.split_at_mut(pw);
        for (half, luma_row) in [y_top, y_bottom].into_iter().enumerate() {
            let rgba = source.row(2 * (first_pair + k) + half, &mut scratch.rows[half]);
            convert_row(rgba, luma_row, &mut scratch.cb[half], &mut scratch.cr[half]);
        }
        subsample(&scratch.cb, cb_row);
        subsample(&scratch.cr, cr_row);
    }
}

/// One row of RGBA pixels (of the frame's width) into luma levels and unrounded chroma
/// values (of the padded width: an odd row's last pixel is repeated).
#[inline(always)]
fn convert_row(rgba: &[u8], luma: &mut [u8], cb: &mut [i32], cr: &mut [i32]) {
    let pixels = rgba.chunks_exact(4).zip(luma.iter_mut());
    for ((p, y), (u, v)) in pixels.zip(cb.iter_mut().zip(cr.iter_mut())) {
        // One 32-bit load split by shifts: vectorises without byte shuffles.
        let word = u32::from_le_bytes([p[0], p[1], p[2], p[3]]);
        let rgb = over_black([0, 8, 16, 24].map(|shift| (word >> shift) as u8));
        // Within 16..=235 for any RGB: no clamp needed.
        *y = ((dot(Y_W, rgb) + (16 << SHIFT) + (1 << (SHIFT - 1))) >> SHIFT) as u8;
        *u = dot(CB_W, rgb);
        *v = dot(CR_W, rgb);
    }
    let width = rgba.len() / 4;
    if width < luma.len() {
        luma[width] = luma[width - 1];
        cb[width] = cb[width - 1];
        cr[width] = cr[width - 1];
    }
}

/// Each 2×2 block's four unrounded chroma values as one rounded level.
#[inline(always)]
fn subsample(rows: &[Vec<i32>; 2], out: &mut [u8]) {
    let blocks = rows[0].chunks_exact(2).zip(rows[1].chunks_exact(2));
    for ((top, bottom), level) in blocks.zip(out.iter_mut()) {
        let sum = top[0] + top[1] + bottom[0] + bottom[1];
        // Within 16..=240 for any RGB: no clamp needed.
        *level = ((sum + (128 << (SHIFT + 2)) + (1 << (SHIFT + 1))) >> (SHIFT + 2)) as u8;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The exact formula in f64, for checking the fixed-point weights.
    fn exact(rgb: [f64; 3]) -> [f64; 3] {
        let [r, g, b] = rgb.map(|v| v / 255.0);
        let y = 0.2126 * r + 0.7152 * g + 0.0722 * b;
        [
            16.0 + 219.0 * y,
            128.0 + 224.0 * (b - y) / 1.8556,
            128.0 + 224.0 * (r - y) / 1.5748,
        ]
    }

    #[test]
    fn reference_colours_convert_to_their_bt709_levels() {
        assert_eq!(rgb_to_ycbcr([0, 0, 0, 255]), [16, 128, 128]);
        assert_eq!(rgb_to_ycbcr([255, 255, 255, 255]), [235, 128, 128]);
        // BT.709 100% colours (ITU-R BT.709 colour bars).
        assert_eq!(rgb_to_ycbcr([255, 0, 0, 255]), [63, 102, 240]);
        assert_eq!(rgb_to_ycbcr([0, 255, 0, 255]), [173, 42, 26]);
        assert_eq!(rgb_to_ycbcr([0, 0, 255, 255]), [32, 240, 118]);
        assert_eq!(rgb_to_ycbcr([255, 255, 255, 0]), [16, 128, 128]);
        for v in 0..=255u8 {
            let [_, cb, cr] = rgb_to_ycbcr([v, v, v, 255]);
            assert_eq!((cb, cr), (128, 128), "grey {v}");
        }
    }

    #[test]
    fn compositing_over_black_rounds_exactly() {
        for v in 0..=255u8 {
            for a in 0..=255u8 {
                let want = (u32::from(v) * u32::from(a) + 127) / 255;
                assert_eq!(over_black([v, v, v, a])[0], want as i32, "{v} at alpha {a}");
            }
        }
    }

    #[test]
    fn every_level_is_the_exact_formula_rounded_within_a_hair() {
        // A lattice over the cube: the fixed point is off by far less than half a level.
        for r in (0..=255).step_by(5) {
            for g in (0..=255).step_by(3) {
                for b in (0..=255).step_by(7) {
                    let got = rgb_to_ycbcr([r as u8, g as u8, b as u8, 255]);
                    let want = exact([r as f64, g as f64, b as f64]);
                    for c in 0..3 {
                        let error = (f64::from(got[c]) - want[c]).abs();
                        assert!(error <= 0.51, "{r},{g},{b} channel {c}: {error}");
                    }
                }
            }
        }
    }

    fn frame_bytes(width: u32, height: u32) -> Vec<u8> {
        (0..width * height)
            .flat_map(|i| {
                let v = i.wrapping_mul(2_654_435_761);
                [v as u8, (v >> 8) as u8, (v >> 16) as u8, 255]
            })
            .collect()
    }

    #[test]
    fn planes_hold_each_pixel_and_the_mean_of_each_block() {
        let (w, h) = (5u32, 3u32);
        let bytes = frame_bytes(w, h);
        let frame = FrameRef::new(w, h, Pixels::Rgba8(&bytes)).unwrap();
        let mut out = Vec::new();
        frame_to_yuv420(&frame, &mut out, 1);
        assert_eq!(out.len(), 6 * 4 + 2 * 3 * 2);
        let px = |x: u32, y: u32| {
            let i = 4 * (y.min(h - 1) * w + x.min(w - 1)) as usize;
            [bytes[i], bytes[i + 1], bytes[i + 2], bytes[i + 3]]
        };
        for y in 0..4 {
            for x in 0..6 {
                assert_eq!(out[(y * 6 + x) as usize], rgb_to_ycbcr(px(x, y))[0]);
            }
        }
        for by in 0..2 {
            for bx in 0..3 {
                let mut mean = [0.0; 3];
                for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    let p = px(2 * bx + dx, 2 * by + dy);
                    let e = exact([p[0], p[1], p[2]].map(f64::from));
                    mean.iter_mut().zip(e).for_each(|(m, v)| *m += v / 4.0);
                }
                let i = (by * 3 + bx) as usize;
                let (cb, cr) = (f64::from(out[24 + i]), f64::from(out[30 + i]));
                assert!((cb - mean[1]).abs() <= 0.5 + 1e-3, "block {bx},{by}");
                assert!((cr - mean[2]).abs() <= 0.5 + 1e-3, "block {bx},{by}");
            }
        }
    }

    /// The vector and portable builds of the rows give the same bytes (integer maths).
    #[test]
    fn both_simd_paths_give_the_same_bytes() {
        use crate::simd::Path;
        let (w, h) = (333u32, 190u32);
        let bytes = frame_bytes(w, h);
        let frame = FrameRef::new(w, h, Pixels::Rgba8(&bytes)).unwrap();
        let (mut vector, mut portable) = (Vec::new(), Vec::new());
        convert_frame(&frame, &mut vector, 2, Path::Vector);
        convert_frame(&frame, &mut portable, 2, Path::Portable);
        assert_eq!(vector, portable);
    }

    /// A frame with translucent pixels gives the planes of the same frame composited over
    /// black beforehand: the compositing is each pixel's, before any averaging.
    #[test]
    fn translucent_rows_give_the_planes_of_the_frame_over_black() {
        let (w, h) = (97u32, 64u32);
        let mut bytes = frame_bytes(w, h);
        // Translucent pixels in every fourth row pair, mixed with opaque ones.
        for (i, px) in bytes.chunks_exact_mut(4).enumerate() {
            let (x, y) = (i % w as usize, i / w as usize);
            if (y / 2) % 4 == 1 && x % 3 != 0 {
                px[3] = (x * 37 + y * 11) as u8;
            }
        }
        let flattened: Vec<u8> = bytes
            .chunks_exact(4)
            .flat_map(|px| {
                let [r, g, b] = over_black([px[0], px[1], px[2], px[3]]).map(|v| v as u8);
                [r, g, b, 255]
            })
            .collect();
        let (mut got, mut want) = (Vec::new(), Vec::new());
        frame_to_yuv420(&FrameRef::new(w, h, Pixels::Rgba8(&bytes)).unwrap(), &mut got, 2);
        let opaque = FrameRef::new(w, h, Pixels::Rgba8(&flattened)).unwrap();
        frame_to_yuv420(&opaque, &mut want, 2);
        assert_eq!(got, want);
        assert!(bytes.chunks_exact(4).any(|px| px[3] != 255));
    }

    #[test]
    fn threads_and_sample_depth_do_not_change_the_bytes() {
        let (w, h) = (301u32, 257u32);
        let bytes = frame_bytes(w, h);
        let frame = FrameRef::new(w, h, Pixels::Rgba8(&bytes)).unwrap();
        let mut one = Vec::new();
        frame_to_yuv420(&frame, &mut one, 1);
        let wide: Vec<u16> = bytes.iter().map(|&v| u16::from(v) * 257).collect();
        let frame16 = FrameRef::new(w, h, Pixels::Rgba16(&wide)).unwrap();
        for threads in [2, 3, 8] {
            let mut many = Vec::new();
            frame_to_yuv420(&frame, &mut many, threads);
            assert_eq!(one, many, "{threads} threads");
            frame_to_yuv420(&frame16, &mut many, threads);
            assert_eq!(one, many, "16-bit, {threads} threads");
        }
    }
}
