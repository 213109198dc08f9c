//! Eight pixels of a canvas row at once: takes an 8-bit RGBA source, the triangle of each
//! pixel with its affine maps along the row (source position and membrane) and the column
//! of the first pixel, and gives the eight pixels' 8-bit levels and which of them had an
//! opaque sample. The caller uses it where all eight are inside triangles and fully covered
//! (the interior of a patch, nearly every pixel a clone writes). AVX2, entered only where
//! the CPU has it ([`Wide::detect`]); every other pixel, and every pixel on a CPU without
//! AVX2, goes through the plain per-pixel code.
//!
//! Every lane performs the plain code's IEEE operations in its order: the maps'
//! `(at origin + d/dx·dx) + row term`, the taps' clamp and truncation (`max`/`min` with the
//! operand order of the scalar comparisons), the three lerps `a + (b − a)·t`, the division
//! by 255, the membrane added, the clamp to [0, 1] and the rounding `v·255 + ½` truncated.
//! No product is fused into an add, so each lane's bytes are the plain code's (the raster's
//! proptest compares the two on random triangles, sources and canvases).

use super::Path;

/// The source as eight lanes read it: its 8-bit texels as bytes, its width and last row.
#[derive(Clone, Copy)]
#[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
pub(crate) struct LevelSource<'a> {
    bytes: &'a [u8],
    width: i32,
    last_row: i32,
    last_f32: [f32; 2],
}

impl<'a> LevelSource<'a> {
    /// `texels` row-major, `width` wide; `last_f32` the last column and row as the plain
    /// sampler clamps to them. `None` when an index could overflow the lanes' 32 bits.
    pub fn new(texels: &'a [[u8; 4]], width: usize, last_f32: [f32; 2]) -> Option<Self> {
        if texels.is_empty() || width == 0 || texels.len() > i32::MAX as usize {
            return None;
        }
        let height = texels.len() / width;
        Some(LevelSource {
            bytes: bytemuck::cast_slice(texels),
            width: width as i32,
            last_row: height as i32 - 1,
            last_f32,
        })
    }

    /// The index of texel `(x, y)` when it and the `count − 1` texels right of it lie in the
    /// source's row `y`: there the plain sampler reads those texels unclamped.
    #[inline(always)]
    pub fn run_start(&self, x: i32, y: i32, count: i32) -> Option<usize> {
        let inside = (0..=self.last_row).contains(&y)
            && x >= 0
            && x.checked_add(count).is_some_and(|end| end <= self.width);
        inside.then(|| y as usize * self.width as usize + x as usize)
    }
}

/// A triangle's maps along one row, each `[at origin, d/dx, d/dy · dy]`: the source
/// position in texel space and the membrane (RGB, alpha lane 0).
#[derive(Clone, Copy)]
pub(crate) struct RowAffine {
    pub texel_x: [f32; 3],
    pub texel_y: [f32; 3],
    pub membrane: [[f32; 4]; 3],
}

/// Eight 8-bit pixels and which of them are written: bit `i` set when lane `i`'s sample
/// was opaque.
pub(crate) type Levels8 = ([[u8; 4]; 8], u8);

#[cfg(target_arch = "x86_64")]
pub(crate) use x86::Wide;

/// No eight-lane code off x86_64: [`Wide::detect`] never gives one.
#[cfg(not(target_arch = "x86_64"))]
#[derive(Clone, Copy)]
pub(crate) enum Wide {}

#[cfg(not(target_arch = "x86_64"))]
impl Wide {
    pub fn detect(_: Path) -> Option<Wide> {
        None
    }

    pub fn shade_opaque(
        self,
        _: &LevelSource,
        _: i32,
        _: [u32; 8],
        _: impl Fn(u32) -> (RowAffine, i32),
    ) -> Levels8 {
        match self {}
    }

    pub fn shade_texels(
        self,
        _: &LevelSource,
        _: usize,
        _: i32,
        _: [u32; 8],
        _: impl Fn(u32) -> (RowAffine, i32),
    ) -> Levels8 {
        match self {}
    }
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use core::arch::x86_64::{__m256, __m256i, _CMP_GE_OQ};

    use pulp::x86::V3;

    use super::{LevelSource, Levels8, Path, RowAffine};

    /// The eight-lane shader, present when the CPU has AVX2 and the vector path is chosen.
    #[derive(Clone, Copy)]
    pub(crate) struct Wide(V3);

    /// A texel's four channels, each as eight lanes.
    type Channels = [__m256; 4];

    impl Wide {
        /// The shader, if `path` is the vector one and this CPU has AVX2.
        pub fn detect(path: Path) -> Option<Wide> {
            match path {
                Path::Vector => V3::try_new().map(Wide),
                Path::Portable => None,
            }
        }

        /// Shades the eight pixels from column `x0` on, pixel `i` in triangle `ids[i]`,
        /// whose maps along the row (and the column they are based at) `maps` gives.
        #[inline(always)]
        pub fn shade_opaque(
            self,
            source: &LevelSource,
            x0: i32,
            ids: [u32; 8],
            maps: impl Fn(u32) -> (RowAffine, i32),
        ) -> Levels8 {
            let s = self.0;
            let (avx, avx2) = (s.avx, s.avx2);
            let (position, membrane) = self.maps_per_lane(x0, ids, maps);
            let (x0, tx) = self.taps(position[0], source.last_f32[0]);
            let (y0, ty) = self.taps(position[1], source.last_f32[1]);
            let below = avx2._mm256_cmpgt_epi32(avx._mm256_set1_epi32(source.last_row), y0);
            let width = avx._mm256_set1_epi32(source.width);
            let top_row = avx2._mm256_mullo_epi32(y0, width);
            // The row below is `width` texels on, or the last row again (as the plain code).
            let step = avx2._mm256_and_si256(below, width);
            let [top_left, top_right, low_left, low_right] =
                self.pairs(source.bytes, avx2._mm256_add_epi32(top_row, x0), step);
            let top = self.lerp(self.channels(top_left), self.channels(top_right), tx);
            let bottom = self.lerp(self.channels(low_left), self.channels(low_right), tx);
            self.finish(self.lerp(top, bottom, ty), membrane)
        }

        /// [`shade_opaque`](Self::shade_opaque) where every lane's triangle is moved by the
        /// same whole pixels and the eight samples are the source texels from index `first`
        /// on ([`LevelSource::run_start`]): the plain code's taps then have fraction 0, and
        /// its lerps `a + (b − a) · 0` give the texel `a` itself, so one load gives the
        /// samples.
        #[inline(always)]
        pub fn shade_texels(
            self,
            source: &LevelSource,
            first: usize,
            x0: i32,
            ids: [u32; 8],
            maps: impl Fn(u32) -> (RowAffine, i32),
        ) -> Levels8 {
            let (_, membrane) = self.maps_per_lane(x0, ids, maps);
            let eight = source.bytes.get(4 * first..).and_then(<[u8]>::first_chunk::<32>);
            // invariant: `run_start` gave `first` for eight texels inside the source.
            let words: __m256i = pulp::cast(*eight.expect("eight texels inside the source"));
            self.finish(self.channels(words), membrane)
        }

        /// Samples (0–255 per channel) to levels: divided by 255, the membrane added, each
        /// channel rounded; the pixels and which samples were opaque.
        #[inline(always)]
        fn finish(self, mut sample: Channels, membrane: Channels) -> Levels8 {
            let (avx, avx2) = (self.0.avx, self.0.avx2);
            let mut levels = [avx._mm256_setzero_si256(); 4];
            for c in 0..4 {
                sample[c] = avx._mm256_div_ps(sample[c], avx._mm256_set1_ps(255.0));
                levels[c] = self.level(avx._mm256_add_ps(sample[c], membrane[c]));
            }
            let opaque = avx._mm256_cmp_ps::<_CMP_GE_OQ>(sample[3], avx._mm256_set1_ps(1.0));
            let packed = avx2._mm256_or_si256(
                avx2._mm256_or_si256(levels[0], avx2._mm256_slli_epi32::<8>(levels[1])),
                avx2._mm256_or_si256(
                    avx2._mm256_slli_epi32::<16>(levels[2]),
                    avx2._mm256_slli_epi32::<24>(levels[3]),
                ),
            );
            let words: [u32; 8] = pulp::cast(packed);
            let mut pixels = [[0u8; 4]; 8];
            for (pixel, word) in pixels.iter_mut().zip(words) {
                *pixel = word.to_le_bytes();
            }
            (pixels, avx._mm256_movemask_ps(opaque) as u8)
        }

        /// Each lane's source position (x, y) and membrane channels, from its own
        /// triangle's maps: each triangle of the eight evaluated on all lanes, kept on its
        /// own.
        #[inline(always)]
        fn maps_per_lane(
            self,
            x0: i32,
            ids: [u32; 8],
            maps: impl Fn(u32) -> (RowAffine, i32),
        ) -> ([__m256; 2], Channels) {
            let (avx, avx2) = (self.0.avx, self.0.avx2);
            let lanes = avx._mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
            let id_lanes: __m256i = pulp::cast(ids);
            let zero = avx._mm256_setzero_ps();
            let (mut position, mut membrane) = ([zero; 2], [zero; 4]);
            // A triangle's pixels in a row are one run (two if another triangle is drawn
            // in front of its middle: it is then evaluated twice, to the same values).
            let mut lane = 0;
            while lane < 8 {
                let id = ids[lane];
                while lane < 8 && ids[lane] == id {
                    lane += 1;
                }
                let (affine, origin_x) = maps(id);
                let columns = avx._mm256_set1_epi32(x0.wrapping_sub(origin_x));
                let dx = avx._mm256_cvtepi32_ps(avx2._mm256_add_epi32(columns, lanes));
                let mine = avx2._mm256_cmpeq_epi32(id_lanes, avx._mm256_set1_epi32(id as i32));
                let mine: __m256 = pulp::cast(mine);
                position[0] = self.keep(position[0], affine.texel_x, dx, mine);
                position[1] = self.keep(position[1], affine.texel_y, dx, mine);
                for (c, into) in membrane.iter_mut().enumerate() {
                    let channel = [affine.membrane[0][c], affine.membrane[1][c], affine.membrane[2][c]];
                    *into = self.keep(*into, channel, dx, mine);
                }
            }
            (position, membrane)
        }

        /// `map` evaluated at `dx` where `mine` is set, `kept` elsewhere.
        #[inline(always)]
        fn keep(self, kept: __m256, map: [f32; 3], dx: __m256, mine: __m256) -> __m256 {
            self.0.avx._mm256_blendv_ps(kept, self.affine(map, dx), mine)
        }

        /// `a + (b − a) · t`, channel by channel.
        #[inline(always)]
        fn lerp(self, a: Channels, b: Channels, t: __m256) -> Channels {
            let avx = self.0.avx;
            let mut out = a;
            for c in 0..4 {
                let step = avx._mm256_mul_ps(avx._mm256_sub_ps(b[c], a[c]), t);
                out[c] = avx._mm256_add_ps(a[c], step);
            }
            out
        }

        /// `(at origin + d/dx · dx) + row term` on every lane.
        #[inline(always)]
        fn affine(self, [origin, step, row]: [f32; 3], dx: __m256) -> __m256 {
            let avx = self.0.avx;
            let along = avx._mm256_mul_ps(avx._mm256_set1_ps(step), dx);
            let at = avx._mm256_add_ps(avx._mm256_set1_ps(origin), along);
            avx._mm256_add_ps(at, avx._mm256_set1_ps(row))
        }

        /// The bilinear taps of texel-space positions: the lower index and the fraction, as
        /// `simd::texel_taps` gives them.
        #[inline(always)]
        fn taps(self, p: __m256, last_f32: f32) -> (__m256i, __m256) {
            let avx = self.0.avx;
            // `max(p, 0)` is `p > 0 ? p : 0` and `min(low, last)` is `low < last ? low :
            // last`, lane by lane: the scalar comparisons, NaN going to 0.
            let low = avx._mm256_max_ps(p, avx._mm256_setzero_ps());
            let u = avx._mm256_min_ps(low, avx._mm256_set1_ps(last_f32));
            let whole = avx._mm256_cvttps_epi32(u);
            (whole, avx._mm256_sub_ps(u, avx._mm256_cvtepi32_ps(whole)))
        }

        /// The texels at eight indices `top` and those right of them, then the same at
        /// `top + step`, each as one little-endian word: one 8-byte load per lane and row.
        ///
        /// The plain sampler reads the texel itself again where the tap is the last column;
        /// there the fraction is exactly 0 (the position was clamped to that column), so
        /// `a + (b − a) · 0` is `a` for any 8-bit `b`, and the next texel in memory (or the
        /// texel itself at the end of the image) gives the same bytes.
        #[inline(always)]
        fn pairs(self, bytes: &[u8], top: __m256i, step: __m256i) -> [__m256i; 4] {
            let (top, step): ([i32; 8], [i32; 8]) = (pulp::cast(top), pulp::cast(step));
            // The taps are clamped to the last column and row: every index is in range.
            let pair = |i: usize| match bytes.get(4 * i..).and_then(<[u8]>::first_chunk::<8>) {
                Some(eight) => u64::from_le_bytes(*eight) as i64,
                None => {
                    let last = bytes.get(4 * i..).and_then(<[u8]>::first_chunk::<4>);
                    i64::from(u32::from_le_bytes(last.copied().unwrap_or_default())) * 0x1_0000_0001
                }
            };
            let (mut upper, mut lower) = ([0i64; 8], [0i64; 8]);
            for lane in 0..8 {
                upper[lane] = pair(top[lane] as usize);
                lower[lane] = pair((top[lane] + step[lane]) as usize);
            }
            let (upper, lower) = (self.split(upper), self.split(lower));
            [upper.0, upper.1, lower.0, lower.1]
        }

        /// Eight (left, right) word pairs as the eight lefts and the eight rights.
        #[inline(always)]
        fn split(self, pairs: [i64; 8]) -> (__m256i, __m256i) {
            let (avx, avx2) = (self.0.avx, self.0.avx2);
            // Built in registers: a vector load from eight separate stores would stall.
            let first = avx._mm256_setr_epi64x(pairs[0], pairs[1], pairs[2], pairs[3]);
            let second = avx._mm256_setr_epi64x(pairs[4], pairs[5], pairs[6], pairs[7]);
            // Each half holds four (left, right) pairs: lefts low, rights high.
            let order = avx._mm256_setr_epi32(0, 2, 4, 6, 1, 3, 5, 7);
            let first = avx2._mm256_permutevar8x32_epi32(first, order);
            let second = avx2._mm256_permutevar8x32_epi32(second, order);
            (
                avx2._mm256_permute2x128_si256::<0x20>(first, second),
                avx2._mm256_permute2x128_si256::<0x31>(first, second),
            )
        }

        /// The four 8-bit channels of eight texel words, as floats.
        #[inline(always)]
        fn channels(self, words: __m256i) -> Channels {
            let (avx, avx2) = (self.0.avx, self.0.avx2);
            let byte = avx._mm256_set1_epi32(0xff);
            [
                avx._mm256_cvtepi32_ps(avx2._mm256_and_si256(words, byte)),
                avx._mm256_cvtepi32_ps(avx2._mm256_and_si256(
                    avx2._mm256_srli_epi32::<8>(words),
                    byte,
                )),
                avx._mm256_cvtepi32_ps(avx2._mm256_and_si256(
                    avx2._mm256_srli_epi32::<16>(words),
                    byte,
                )),
                avx._mm256_cvtepi32_ps(avx2._mm256_srli_epi32::<24>(words)),
            ]
        }

        /// A channel clamped to [0, 1] (glam's `clamp`: `max` then `min`, NaN to 0) and
        /// rounded to its level, `(v · 255 + ½)` truncated.
        #[inline(always)]
        fn level(self, value: __m256) -> __m256i {
            let avx = self.0.avx;
            let clamped = avx._mm256_min_ps(
                avx._mm256_max_ps(value, avx._mm256_setzero_ps()),
                avx._mm256_set1_ps(1.0),
            );
            let scaled = avx._mm256_add_ps(
                avx._mm256_mul_ps(clamped, avx._mm256_set1_ps(255.0)),
                avx._mm256_set1_ps(0.5),
            );
            avx._mm256_cvttps_epi32(scaled)
        }
    }
}
