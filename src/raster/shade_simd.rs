//! AVX2 shading of one triangle run into an 8-bit canvas: takes a run of pixels whose
//! centres lie in one triangle (its [`SpanSetup`], the row, the run's 8-bit coverage and
//! canvas pixels) and the source [`Sampler`], and composites the run exactly as the scalar
//! [`shade_span`](super::shade) does — the same bytes, not merely close ones.
//!
//! Why the bytes agree: every value is computed by the same IEEE operations in the same
//! order as the scalar code, lane by lane — the affine maps `m₀ + m_x·dx + m_y·dy` at each
//! pixel centre, the clamped bilinear taps, the lerps `a + (b − a)·t` (separate multiply
//! and add, never fused), `clamp(sample + membrane, 0, 1)` by max then min, and the store
//! `trunc(255·c + ½)` with saturating packs. Only the grouping differs: tap positions for
//! eight pixels at once, then two pixels per 256-bit register for the texel blend and the
//! store. Pixels that need a blend (partial coverage or a translucent source) take the
//! scalar `shade_pixel` with the vector's own sample and membrane.
//!
//! Dispatch: [`Kernel::detect`] once per draw (unless `RasterOptions::simd` is off); without
//! AVX2 (or off x86_64) the scalar path runs. A recording draw (see
//! [`replay`](super::replay)) runs it too and reports every pixel's sample through a
//! [`SampleSink`]; equality is what lets a replay of that record give a fresh draw's bytes on
//! any CPU. Recording this way cut the first draw's shading instructions by 20 % on a
//! 722-vertex photo patch (callgrind, `lapclone clone`); on the boundary-dense spiral, whose
//! runs are 1–3 px, it changed nothing.
//!
//! Measured (callgrind, `bench clone`'s deform frame): the shading instructions fell by 38 %
//! (the whole band draw by 29 %). Not done: replays (their runs on boundary-dense meshes
//! are 2–3 px, where the SIMD kernel measured slower than the scalar loop).

#[cfg(target_arch = "x86_64")]
use super::sampler::{Sampler, SourceTexel};
#[cfg(target_arch = "x86_64")]
use super::setup::SpanSetup;

/// Where the kernel reports each pixel's sample as it shades (a recording draw's
/// [`Recorder`](super::shade::Recorder)): in pixel order, `Some(sample)` for a covered pixel,
/// `None` for one with coverage 0 — what the scalar `shade_span` reports. The samples are the
/// scalar path's, bit for bit, so a record made here replays like one made there.
pub(crate) trait SampleSink {
    /// Whether anything is reported (else the kernel skips the calls).
    const ACTIVE: bool;
    fn pixel(&mut self, sample: Option<glam::Vec4>, coverage: u8);
}

/// Which span kernel a draw uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Kernel {
    Scalar,
    #[cfg(target_arch = "x86_64")]
    Avx2,
}

impl Kernel {
    /// The fastest kernel this CPU runs.
    pub fn detect() -> Kernel {
        #[cfg(target_arch = "x86_64")]
        if is_x86_feature_detected!("avx2") {
            return Kernel::Avx2;
        }
        Kernel::Scalar
    }
}

/// Shades the run starting at canvas column `x0` of row `y` with the kernel's SIMD path.
/// Gives the number of pixels written. `coverage` and `pixels` have the run's length, and
/// the source at most `i32::MAX` texels.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
pub(crate) fn shade_run_rgba8<S: SourceTexel, K: SampleSink>(
    kernel: Kernel,
    setup: &SpanSetup,
    sampler: &Sampler<S>,
    (x0, y): (i32, i32),
    coverage: &[u8],
    pixels: &mut [[u8; 4]],
    sink: &mut K,
) -> usize {
    assert_eq!(coverage.len(), pixels.len(), "one coverage texel per pixel");
    // The kernel's texel indices are i32 lanes (callers route larger sources elsewhere).
    assert!(
        sampler.pixels.len() <= i32::MAX as usize,
        "source too large for i32 indices"
    );
    match kernel {
        // SAFETY: `Kernel::Avx2` is only ever detected on CPUs with AVX2.
        Kernel::Avx2 => unsafe { avx2::shade_run(setup, sampler, (x0, y), coverage, pixels, sink) },
        Kernel::Scalar => unreachable!("the scalar kernel has no SIMD run"),
    }
}

#[cfg(target_arch = "x86_64")]
mod avx2 {
    use std::arch::x86_64::*;

    use glam::Vec4;

    use super::super::sampler::{Sampler, SourceTexel};
    use super::super::setup::SpanSetup;
    use super::super::shade::shade_pixel;
    use super::SampleSink;

    /// The run's constant parts, as vectors.
    struct RunMaps {
        texel_x: [__m256; 2],
        texel_y: [__m256; 2],
        /// The y terms `m_y·dy` of the texel maps, per lane.
        texel_y_terms: [__m256; 2],
        /// Membrane at the origin, its x step and its y term, twice (two pixels).
        membrane: [__m256; 3],
    }

    /// Clamped taps of eight texel-space coordinates: first tap, second tap, fraction
    /// (the scalar `taps_shifted`, lane by lane), and the lanes (bits) whose second tap is
    /// the first plus one.
    #[inline]
    #[target_feature(enable = "avx2")]
    fn taps(shifted: __m256, last: i32, last_f32: f32) -> (__m256i, __m256i, __m256, i32) {
        // max(x, 0) gives 0 for NaN and −0 (second operand), like `x > 0 ? x : 0`.
        let low = _mm256_max_ps(shifted, _mm256_setzero_ps());
        let u = _mm256_min_ps(low, _mm256_set1_ps(last_f32));
        let whole = _mm256_cvttps_epi32(u);
        let fraction = _mm256_sub_ps(u, _mm256_cvtepi32_ps(whole));
        // whole < last: the compare gives −1, so subtracting it adds one.
        let below_last = _mm256_cmpgt_epi32(_mm256_set1_epi32(last), whole);
        let next = _mm256_sub_epi32(whole, below_last);
        let stepped = _mm256_movemask_ps(_mm256_castsi256_ps(below_last));
        (whole, next, fraction, stepped)
    }

    /// Texel indices of the four taps of eight pixels, and their fractions.
    struct Taps {
        index: [[i32; 8]; 4],
        fraction_x: __m256,
        fraction_y: __m256,
        /// Every lane's right taps follow its left ones in memory (no lane is clamped at
        /// the source's last column), so one 32-byte load reads both.
        adjacent: bool,
    }

    #[inline]
    #[target_feature(enable = "avx2")]
    fn taps_of_eight<S: SourceTexel>(sampler: &Sampler<S>, maps: &RunMaps, dx: __m256) -> Taps {
        let u = affine(maps.texel_x, dx, maps.texel_y_terms[0]);
        let v = affine(maps.texel_y, dx, maps.texel_y_terms[1]);
        // The caller keeps sources with more than i32::MAX texels on the scalar path, so
        // every index fits i32.
        let (x0, x1, fraction_x, stepped) = taps(u, sampler.last_x as i32, sampler.last_x_f32);
        let (y0, y1, fraction_y, _) = taps(v, sampler.last_y as i32, sampler.last_y_f32);
        let width = _mm256_set1_epi32(sampler.width as i32);
        let (row0, row1) = (_mm256_mullo_epi32(y0, width), _mm256_mullo_epi32(y1, width));
        let mut index = [[0i32; 8]; 4];
        for (slot, value) in index.iter_mut().zip([
            _mm256_add_epi32(row0, x0),
            _mm256_add_epi32(row0, x1),
            _mm256_add_epi32(row1, x0),
            _mm256_add_epi32(row1, x1),
        ]) {
            // SAFETY: `slot` is eight i32, written unaligned.
            unsafe { _mm256_storeu_si256(slot.as_mut_ptr() as *mut __m256i, value) };
        }
        Taps {
            index,
            fraction_x,
            fraction_y,
            adjacent: stepped == 0xFF,
        }
    }

    /// `(m₀ + m_x·dx) + term`, the scalar `at_pixel`'s order.
    #[inline]
    #[target_feature(enable = "avx2")]
    fn affine([origin, step]: [__m256; 2], dx: __m256, term: __m256) -> __m256 {
        _mm256_add_ps(_mm256_add_ps(origin, _mm256_mul_ps(step, dx)), term)
    }

    /// Lanes `[K ×4, K+1 ×4]` of `v`: a per-pixel scalar spread over a pixel pair.
    #[inline]
    #[target_feature(enable = "avx2")]
    fn pair_of<const K: i32>(v: __m256) -> __m256 {
        let spread = _mm256_setr_epi32(K, K, K, K, K + 1, K + 1, K + 1, K + 1);
        _mm256_permutevar8x32_ps(v, spread)
    }

    /// Texels of tap `tap` of pixels k and k + 1, in blend units (the scalar
    /// `blend_units`).
    ///
    /// # Safety
    /// The indices are taps of `sampler` (clamped into the image).
    #[inline]
    #[target_feature(enable = "avx2")]
    unsafe fn texel_pair<S: SourceTexel>(
        sampler: &Sampler<S>,
        taps: &Taps,
        tap: usize,
        k: usize,
    ) -> __m256 {
        let (a, b) = (taps.index[tap][k] as usize, taps.index[tap][k + 1] as usize);
        if S::EIGHT_BIT {
            let base = sampler.pixels.as_ptr() as *const u8;
            // SAFETY: the caller's contract; a texel is four bytes.
            let (left, right) = unsafe {
                (
                    (base.add(a * 4) as *const i32).read_unaligned(),
                    (base.add(b * 4) as *const i32).read_unaligned(),
                )
            };
            let bytes = _mm_unpacklo_epi32(_mm_cvtsi32_si128(left), _mm_cvtsi32_si128(right));
            _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(bytes))
        } else {
            let base = sampler.pixels.as_ptr() as *const f32;
            // SAFETY: the caller's contract; a texel is four f32.
            unsafe { _mm256_set_m128(_mm_loadu_ps(base.add(b * 4)), _mm_loadu_ps(base.add(a * 4))) }
        }
    }

    /// Texels of taps `tap` and `tap + 1` (left and right) of pixel k, in one load, in
    /// blend units.
    ///
    /// # Safety
    /// As [`texel_pair`], and the right tap is the texel after the left one.
    #[inline]
    #[target_feature(enable = "avx2")]
    unsafe fn adjacent_texels<S: SourceTexel>(
        sampler: &Sampler<S>,
        taps: &Taps,
        tap: usize,
        k: usize,
    ) -> __m256 {
        let at = taps.index[tap][k] as usize;
        if S::EIGHT_BIT {
            let base = sampler.pixels.as_ptr() as *const u8;
            // SAFETY: the caller's contract; two texels are eight bytes.
            let bytes = unsafe { _mm_loadl_epi64(base.add(at * 4) as *const __m128i) };
            _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(bytes))
        } else {
            let base = sampler.pixels.as_ptr() as *const f32;
            // SAFETY: the caller's contract; two texels are eight f32.
            unsafe { _mm256_loadu_ps(base.add(at * 4)) }
        }
    }

    #[inline]
    #[target_feature(enable = "avx2")]
    fn lerp(a: __m256, b: __m256, t: __m256) -> __m256 {
        _mm256_add_ps(a, _mm256_mul_ps(_mm256_sub_ps(b, a), t))
    }

    /// Bilinear samples of pixels k and k + 1 (lanes 0–3 and 4–7).
    ///
    /// # Safety
    /// As [`texel_pair`].
    #[inline]
    #[target_feature(enable = "avx2")]
    unsafe fn sample_pair<S: SourceTexel, const K: i32>(
        sampler: &Sampler<S>,
        taps: &Taps,
    ) -> __m256 {
        let k = K as usize;
        let (tx, ty) = (pair_of::<K>(taps.fraction_x), pair_of::<K>(taps.fraction_y));
        // SAFETY (all loads): the caller's contract; `adjacent` vouches for the right taps.
        let (t00, t01, t10, t11) = if taps.adjacent {
            // Rows 0 and 1 of pixels k and k + 1, left and right taps in each half: the
            // same texels as below, regrouped by tap.
            let (top_k, bottom_k, top_next, bottom_next) = unsafe {
                (
                    adjacent_texels(sampler, taps, 0, k),
                    adjacent_texels(sampler, taps, 2, k),
                    adjacent_texels(sampler, taps, 0, k + 1),
                    adjacent_texels(sampler, taps, 2, k + 1),
                )
            };
            (
                _mm256_permute2f128_ps::<0x20>(top_k, top_next),
                _mm256_permute2f128_ps::<0x31>(top_k, top_next),
                _mm256_permute2f128_ps::<0x20>(bottom_k, bottom_next),
                _mm256_permute2f128_ps::<0x31>(bottom_k, bottom_next),
            )
        } else {
            unsafe {
                (
                    texel_pair(sampler, taps, 0, k),
                    texel_pair(sampler, taps, 1, k),
                    texel_pair(sampler, taps, 2, k),
                    texel_pair(sampler, taps, 3, k),
                )
            }
        };
        let blend = lerp(lerp(t00, t01, tx), lerp(t10, t11, tx), ty);
        // The scalar `finish`.
        if S::EIGHT_BIT {
            _mm256_div_ps(blend, _mm256_set1_ps(255.0))
        } else {
            blend
        }
    }

    /// Stores two clamped colours as 8-bit texels (the scalar `store_unit`, twice).
    ///
    /// # Safety
    /// `out` must have room for two pixels.
    #[inline]
    #[target_feature(enable = "avx2")]
    unsafe fn store_pair(colour: __m256, out: *mut [u8; 4]) {
        let scaled = _mm256_add_ps(
            _mm256_mul_ps(colour, _mm256_set1_ps(255.0)),
            _mm256_set1_ps(0.5),
        );
        let words = _mm256_cvttps_epi32(scaled);
        let halves = _mm_packs_epi32(
            _mm256_castsi256_si128(words),
            _mm256_extracti128_si256::<1>(words),
        );
        // SAFETY: the caller's contract: 8 writable bytes.
        unsafe { _mm_storel_epi64(out as *mut __m128i, _mm_packus_epi16(halves, halves)) };
    }

    #[inline]
    #[target_feature(enable = "avx2")]
    fn low(v: __m256) -> Vec4 {
        Vec4::from(_mm256_castps256_ps128(v))
    }

    #[inline]
    #[target_feature(enable = "avx2")]
    fn high(v: __m256) -> Vec4 {
        Vec4::from(_mm256_extractf128_ps::<1>(v))
    }

    #[inline]
    #[target_feature(enable = "avx2")]
    fn splat_pair(v: Vec4) -> __m256 {
        let v: __m128 = v.into();
        _mm256_set_m128(v, v)
    }

    /// Reports one pixel's sample the way the scalar path does (none when uncovered).
    #[inline]
    fn report<R: SampleSink>(sink: &mut R, sample: Vec4, cover: u8) {
        sink.pixel((cover > 0).then_some(sample), cover);
    }

    /// Shades one pixel the scalar way.
    #[inline]
    fn shade_single(pixel: &mut [u8; 4], cover: u8, sample: Vec4, membrane: Vec4) -> usize {
        if cover > 0 {
            usize::from(shade_pixel(pixel, sample, membrane, cover))
        } else {
            0
        }
    }

    impl RunMaps {
        #[target_feature(enable = "avx2")]
        fn new(maps: &SpanSetup, dy: f32) -> RunMaps {
            let [m_origin, m_x, m_y] = maps.membrane.maps;
            RunMaps {
                texel_x: [
                    _mm256_set1_ps(maps.texel_x[0]),
                    _mm256_set1_ps(maps.texel_x[1]),
                ],
                texel_y: [
                    _mm256_set1_ps(maps.texel_y[0]),
                    _mm256_set1_ps(maps.texel_y[1]),
                ],
                texel_y_terms: [
                    _mm256_set1_ps(maps.texel_x[2] * dy),
                    _mm256_set1_ps(maps.texel_y[2] * dy),
                ],
                membrane: [splat_pair(m_origin), splat_pair(m_x), splat_pair(m_y * dy)],
            }
        }
    }

    /// Eight pixels of a run (the last block may be shorter).
    struct Block {
        taps: Taps,
        dx: __m256,
        len: usize,
        /// Eight pixels, all fully covered (no pair needs its coverage looked at).
        full: bool,
    }

    /// Shades pixels K and K + 1 of `block` (K + 1 only when the block has it); gives the
    /// number written. `OPAQUE`: every sample's alpha is known to be 1.
    ///
    /// # Safety
    /// `block.taps` are taps of `sampler`; `K < block.len` = `coverage.len()` = `pixels.len()`.
    #[inline]
    #[target_feature(enable = "avx2")]
    unsafe fn shade_pair<S: SourceTexel, R: SampleSink, const K: i32, const OPAQUE: bool>(
        sampler: &Sampler<S>,
        maps: &RunMaps,
        block: &Block,
        coverage: &[u8],
        pixels: &mut [[u8; 4]],
        sink: &mut R,
    ) -> usize {
        let at = K as usize;
        // SAFETY: the caller's contract.
        let sample = unsafe { sample_pair::<S, K>(sampler, &block.taps) };
        let both = at + 1 < block.len;
        if R::ACTIVE {
            report(sink, low(sample), coverage[at]);
            if both {
                report(sink, high(sample), coverage[at + 1]);
            }
        }
        let [m_origin, m_x, m_y_term] = maps.membrane;
        let scaled_dx = _mm256_mul_ps(m_x, pair_of::<K>(block.dx));
        let membrane = _mm256_add_ps(_mm256_add_ps(m_origin, scaled_dx), m_y_term);
        // Interior pairs (full coverage, opaque source) are stored directly, the rest take
        // the scalar path out of line (a call per pair would cost as much as the pair).
        let covered = block.full || (both && coverage[at] & coverage[at + 1] == u8::MAX);
        let opaque = || {
            OPAQUE
                || _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_GE_OQ>(sample, _mm256_set1_ps(1.0)))
                    & 0x88
                    == 0x88
        };
        if covered && opaque() {
            let colour = _mm256_min_ps(
                _mm256_max_ps(_mm256_add_ps(sample, membrane), _mm256_setzero_ps()),
                _mm256_set1_ps(1.0),
            );
            let pair = &mut pixels[at..at + 2];
            // SAFETY: `pair` holds two pixels.
            unsafe { store_pair(colour, pair.as_mut_ptr()) };
            2
        } else {
            shade_pair_slowly(sample, membrane, at, both, coverage, pixels)
        }
    }

    /// The pixels of a pair that need the scalar path: partial coverage or a translucent
    /// source (the silhouette's edge, rare inside). Out of line, to keep the pair kernels
    /// small.
    #[cold]
    #[inline(never)]
    #[target_feature(enable = "avx2")]
    fn shade_pair_slowly(
        sample: __m256,
        membrane: __m256,
        at: usize,
        both: bool,
        coverage: &[u8],
        pixels: &mut [[u8; 4]],
    ) -> usize {
        let mut written = shade_single(&mut pixels[at], coverage[at], low(sample), low(membrane));
        if both {
            written += shade_single(
                &mut pixels[at + 1],
                coverage[at + 1],
                high(sample),
                high(membrane),
            );
        }
        written
    }

    /// Shades a run (see [`super::shade_run_rgba8`]).
    ///
    /// # Safety
    /// The CPU must have AVX2; `coverage` and `pixels` have the same length.
    #[inline]
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn shade_run<S: SourceTexel, K: SampleSink>(
        setup: &SpanSetup,
        sampler: &Sampler<S>,
        at: (i32, i32),
        coverage: &[u8],
        pixels: &mut [[u8; 4]],
        sink: &mut K,
    ) -> usize {
        // SAFETY (both): the caller's contract.
        if sampler.opaque {
            unsafe { shade_run_as::<S, K, true>(setup, sampler, at, coverage, pixels, sink) }
        } else {
            unsafe { shade_run_as::<S, K, false>(setup, sampler, at, coverage, pixels, sink) }
        }
    }

    /// [`shade_run`] knowing whether every sample is opaque.
    ///
    /// # Safety
    /// As [`shade_run`].
    #[inline]
    #[target_feature(enable = "avx2")]
    unsafe fn shade_run_as<S: SourceTexel, K: SampleSink, const OPAQUE: bool>(
        setup: &SpanSetup,
        sampler: &Sampler<S>,
        (x0, y): (i32, i32),
        coverage: &[u8],
        pixels: &mut [[u8; 4]],
        sink: &mut K,
    ) -> usize {
        let n = pixels.len();
        let dy = (y - setup.membrane.origin[1]) as f32;
        let maps = RunMaps::new(setup, dy);
        let first_dx = x0 - setup.membrane.origin[0];
        let lanes = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
        let mut written = 0;
        let mut k0 = 0;
        while k0 < n {
            let dx = _mm256_cvtepi32_ps(_mm256_add_epi32(
                _mm256_set1_epi32(first_dx + k0 as i32),
                lanes,
            ));
            let len = (n - k0).min(8);
            let (coverage, pixels) = (&coverage[k0..k0 + len], &mut pixels[k0..k0 + len]);
            let block = Block {
                taps: taps_of_eight(sampler, &maps, dx),
                dx,
                len,
                full: <[u8; 8]>::try_from(coverage)
                    .is_ok_and(|c| u64::from_ne_bytes(c) == u64::MAX),
            };
            // SAFETY (each pair): taps are clamped into the image, lanes past the run included.
            unsafe {
                written +=
                    shade_pair::<S, K, 0, OPAQUE>(sampler, &maps, &block, coverage, pixels, sink);
                if block.len > 2 {
                    written += shade_pair::<S, K, 2, OPAQUE>(
                        sampler, &maps, &block, coverage, pixels, sink,
                    );
                }
                if block.len > 4 {
                    written += shade_pair::<S, K, 4, OPAQUE>(
                        sampler, &maps, &block, coverage, pixels, sink,
                    );
                }
                if block.len > 6 {
                    written += shade_pair::<S, K, 6, OPAQUE>(
                        sampler, &maps, &block, coverage, pixels, sink,
                    );
                }
            }
            k0 += 8;
        }
        written
    }
}
