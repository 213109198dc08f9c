//! Rows of 8-bit RGB samples to and from RGBA levels: takes a row of three-sample pixels (RGB
//! or BGR order) and gives canvas texels with alpha 255, or takes texels and gives the three
//! samples back. Plain loops compiled for this CPU's best instruction set through
//! [`Path::run`](super::Path::run): at the baseline (SSE2) a three-byte pixel has no byte
//! shuffle to move it, so the loop goes a sample at a time; with AVX2 it goes by whole
//! registers. The bytes are the same on both paths.

use super::{Kernel, Path};

/// Writes `out[i] = [r, g, b, 255]` from pixel `i` of `samples` (three bytes per pixel, blue
/// first when `bgr`), for as many pixels as both hold.
pub fn rgb8_to_levels(samples: &[u8], bgr: bool, out: &mut [[u8; 4]]) {
    let path = Path::current();
    if bgr {
        path.run(ToLevels::<true> { samples, out });
    } else {
        path.run(ToLevels::<false> { samples, out });
    }
}

/// Writes pixel `i` of `out` (three bytes, blue first when `bgr`) from `levels[i]`, dropping
/// alpha, for as many pixels as both hold.
pub fn levels_to_rgb8(levels: &[[u8; 4]], bgr: bool, out: &mut [u8]) {
    let path = Path::current();
    if bgr {
        path.run(FromLevels::<true> { levels, out });
    } else {
        path.run(FromLevels::<false> { levels, out });
    }
}

/// The channel a pixel's first sample is, and its third's: red and blue, or swapped.
#[inline(always)]
const fn red_blue(bgr: bool) -> (usize, usize) {
    if bgr {
        (2, 0)
    } else {
        (0, 2)
    }
}

struct ToLevels<'a, const BGR: bool> {
    samples: &'a [u8],
    out: &'a mut [[u8; 4]],
}

impl<const BGR: bool> Kernel for ToLevels<'_, BGR> {
    type Output = ();

    #[inline(always)]
    fn call(self) {
        let (red, blue) = red_blue(BGR);
        for (texel, px) in self.out.iter_mut().zip(self.samples.chunks_exact(3)) {
            let px: [u8; 3] = std::array::from_fn(|k| px[k]);
            *texel = [px[red], px[1], px[blue], u8::MAX];
        }
    }
}

struct FromLevels<'a, const BGR: bool> {
    levels: &'a [[u8; 4]],
    out: &'a mut [u8],
}

impl<const BGR: bool> Kernel for FromLevels<'_, BGR> {
    type Output = ();

    #[inline(always)]
    fn call(self) {
        let (red, blue) = red_blue(BGR);
        for (px, texel) in self.out.chunks_exact_mut(3).zip(self.levels) {
            px.copy_from_slice(&[texel[red], texel[1], texel[blue]]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_convert_both_ways_in_both_orders() {
        for len in [0usize, 1, 7, 31, 32, 33, 100] {
            let samples: Vec<u8> = (0..len * 3).map(|i| (i * 37 % 251) as u8).collect();
            for bgr in [false, true] {
                let mut levels = vec![[0u8; 4]; len];
                rgb8_to_levels(&samples, bgr, &mut levels);
                for (i, texel) in levels.iter().enumerate() {
                    let p = &samples[i * 3..i * 3 + 3];
                    let expected = if bgr { [p[2], p[1], p[0], 255] } else { [p[0], p[1], p[2], 255] };
                    assert_eq!(*texel, expected, "{len} {bgr} {i}");
                }
                let mut back = vec![0u8; len * 3];
                levels_to_rgb8(&levels, bgr, &mut back);
                assert_eq!(back, samples, "{len} {bgr}");
            }
        }
    }
}
