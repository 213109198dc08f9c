//! Vector code in one place: takes a kernel written as plain loops (the solve's on `f64`
//! arrays, a [`Row`] of `S` channels with the few operations it needs; the video writer's
//! RGB→YUV conversion on integers) and runs it on a [`Path`]: compiled for
//! the best instruction set this CPU has (pulp's run-time dispatch, e.g. AVX2 on x86_64), or
//! the portable path at the baseline instruction set. Safe throughout: pulp checks the CPU
//! before it enters code compiled for it.
//!
//! Both paths give the same bits. The operations below are separate IEEE multiplies and adds
//! in a fixed order, and Rust never contracts them into fused multiply-adds, so the vector
//! code computes exactly what the portable code computes, lane by lane; only the speed
//! differs. `LAPCLONE_SIMD=portable` in the environment (read once) or [`set_portable`]
//! forces the portable path, so the claim can be tested on any machine.
//!
//! The raster's 8-bit store (`unit_to_levels`) and bilinear taps (`texel_taps`) are here
//! too: four lanes at once with the baseline SSE2 instructions where the target has them (no
//! run-time dispatch needed), the plain per-lane casts and comparisons elsewhere; both give
//! the same bits (tested). The shading's interior pixels go eight at a time with AVX2 where
//! the CPU has it (`Wide`, in `shade8`), each lane giving the plain code's bytes.

use std::sync::atomic::{AtomicU8, Ordering};

mod rgb;
mod shade8;

pub use rgb::{levels_to_rgb8, rgb8_to_levels};

pub(crate) use shade8::{LevelSource, RowAffine, Wide};

/// How a kernel is compiled for this run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Path {
    /// The best instruction set of this CPU (the baseline one if it has nothing better).
    Vector,
    /// The baseline instruction set of the target.
    Portable,
}

/// 0: not decided yet, 1: vector, 2: portable.
static CHOSEN: AtomicU8 = AtomicU8::new(0);

/// Forces the portable path for every later kernel (or lets the vector path back in).
pub fn set_portable(portable: bool) {
    CHOSEN.store(if portable { 2 } else { 1 }, Ordering::Relaxed);
}

impl Path {
    /// The path kernels take: [`Path::Portable`] if `LAPCLONE_SIMD=portable` was set when it
    /// was first asked or [`set_portable`] chose it, [`Path::Vector`] otherwise.
    pub fn current() -> Path {
        let chosen = match CHOSEN.load(Ordering::Relaxed) {
            0 => {
                let portable = std::env::var("LAPCLONE_SIMD").is_ok_and(|v| v == "portable");
                // A concurrent `set_portable` wins over the environment.
                let _ = CHOSEN.compare_exchange(
                    0,
                    if portable { 2 } else { 1 },
                    Ordering::Relaxed,
                    Ordering::Relaxed,
                );
                CHOSEN.load(Ordering::Relaxed)
            }
            chosen => chosen,
        };
        if chosen == 2 {
            Path::Portable
        } else {
            Path::Vector
        }
    }

    /// Runs `kernel` compiled for this path.
    #[inline(always)]
    pub fn run<K: Kernel>(self, kernel: K) -> K::Output {
        match self {
            Path::Vector => pulp::Arch::new().dispatch(Dispatched(kernel)),
            Path::Portable => kernel.call(),
        }
    }
}

/// A kernel for [`Path::run`]. Its `call` and everything that calls should be
/// `#[inline(always)]`, so that they are compiled inside the dispatched function, for the
/// instruction set it was compiled for (a closure's body would not be).
pub trait Kernel {
    type Output;
    fn call(self) -> Self::Output;
}

/// A [`Kernel`] as pulp's dispatch takes it.
struct Dispatched<K>(K);

impl<K: Kernel> pulp::WithSimd for Dispatched<K> {
    type Output = K::Output;

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) -> K::Output {
        self.0.call()
    }
}

/// One row of `S` channels (the channels of one unknown); each channel on its own lane.
pub type Row<const S: usize> = [f64; S];

/// `acc − a·x`, lane by lane (`a·x` rounded first).
#[inline(always)]
pub fn mul_sub<const S: usize>(acc: Row<S>, a: f64, x: Row<S>) -> Row<S> {
    std::array::from_fn(|c| acc[c] - a * x[c])
}

/// `acc + a·x`, lane by lane (`a·x` rounded first).
#[inline(always)]
pub fn mul_add<const S: usize>(acc: Row<S>, a: f64, x: Row<S>) -> Row<S> {
    std::array::from_fn(|c| acc[c] + a * x[c])
}

/// `x·a − y`, lane by lane (`x·a` rounded first).
#[inline(always)]
pub fn scale_sub<const S: usize>(x: Row<S>, a: f64, y: Row<S>) -> Row<S> {
    std::array::from_fn(|c| x[c] * a - y[c])
}

/// `x + y`, lane by lane.
#[inline(always)]
pub fn add<const S: usize>(x: Row<S>, y: Row<S>) -> Row<S> {
    std::array::from_fn(|c| x[c] + y[c])
}

/// `x` (length a multiple of `S`) as rows of `S` channels.
///
/// # Panics
/// If `x.len()` is not a multiple of `S`.
pub fn rows_mut<const S: usize>(x: &mut [f64]) -> &mut [Row<S>]
where
    Row<S>: bytemuck::Pod,
{
    bytemuck::cast_slice_mut(x)
}

/// Quantises four unit values to 8-bit levels, exactly as `(v · 255 + ½) as u8` does lane
/// by lane for every input (the canvas's rounding, [`Texel::from_unit`]).
///
/// The SSE2 path clamps `v · 255 + ½` to [0, 255] the way the saturating cast does (NaN to
/// 0: the first `max` returns its second operand for NaN), truncates to `i32` and packs with
/// saturation that no longer bites: one convert and two packs instead of four saturating
/// scalar casts and the shifts that join their bytes.
///
/// [`Texel::from_unit`]: crate::pixels::Texel::from_unit
#[inline(always)]
pub(crate) fn unit_to_levels(unit: [f32; 4]) -> [u8; 4] {
    #[cfg(all(any(target_arch = "x86", target_arch = "x86_64"), target_feature = "sse2"))]
    {
        unit_to_levels_sse2(unit)
    }
    #[cfg(not(all(any(target_arch = "x86", target_arch = "x86_64"), target_feature = "sse2")))]
    {
        unit_to_levels_portable(unit)
    }
}

/// [`unit_to_levels`] with the per-lane casts (the reference, and the path without SSE2).
#[cfg(any(
    test,
    not(all(any(target_arch = "x86", target_arch = "x86_64"), target_feature = "sse2"))
))]
#[inline(always)]
pub(crate) fn unit_to_levels_portable(unit: [f32; 4]) -> [u8; 4] {
    // `as` saturates (NaN → 0).
    unit.map(|v| (v * 255.0 + 0.5) as u8)
}

#[cfg(all(any(target_arch = "x86", target_arch = "x86_64"), target_feature = "sse2"))]
#[inline(always)]
fn unit_to_levels_sse2(unit: [f32; 4]) -> [u8; 4] {
    use safe_arch::{
        add_m128, get_i32_from_m128i_s, m128, max_m128, min_m128, mul_m128,
        pack_i16_to_u8_m128i, pack_i32_to_i16_m128i, truncate_m128_to_m128i,
    };
    // The same two IEEE operations as the scalar rounding, in the same order.
    let scaled = add_m128(
        mul_m128(m128::from_array(unit), m128::from_array([255.0; 4])),
        m128::from_array([0.5; 4]),
    );
    let clamped = min_m128(
        max_m128(scaled, m128::from_array([0.0; 4])),
        m128::from_array([255.0; 4]),
    );
    let levels = truncate_m128_to_m128i(clamped);
    let words = pack_i32_to_i16_m128i(levels, levels);
    let bytes = pack_i16_to_u8_m128i(words, words);
    get_i32_from_m128i_s(bytes).to_le_bytes()
}

/// The bilinear sampler's taps of a texel-space position `(x, y)` on both axes at once:
/// each coordinate `p` becomes `u = if low < last { low } else { last }` with
/// `low = if p > 0 { p } else { 0 }` (NaN to 0), then `(⌊u⌋, u − ⌊u⌋)`; gives the whole
/// parts and the fractions. `last` must be at most 2^31 − 1 on both axes (whole, or a
/// bound below a whole number), so every `u` truncates exactly.
///
/// With SSE2 that is one `max`, one `min` (whose operand order gives the same results as
/// the comparisons above, NaN included), one truncating convert and one convert back,
/// for both axes: no saturating casts.
#[inline(always)]
pub(crate) fn texel_taps(position: [f32; 2], last: [f32; 2]) -> ([u32; 2], [f32; 2]) {
    debug_assert!(last.iter().all(|&l| (0.0..2_147_483_648.0).contains(&l)));
    #[cfg(all(any(target_arch = "x86", target_arch = "x86_64"), target_feature = "sse2"))]
    {
        texel_taps_sse2(position, last)
    }
    #[cfg(not(all(any(target_arch = "x86", target_arch = "x86_64"), target_feature = "sse2")))]
    {
        texel_taps_portable(position, last)
    }
}

/// [`texel_taps`] one axis at a time (the reference, and the path without SSE2).
#[cfg(any(
    test,
    not(all(any(target_arch = "x86", target_arch = "x86_64"), target_feature = "sse2"))
))]
#[inline(always)]
pub(crate) fn texel_taps_portable(position: [f32; 2], last: [f32; 2]) -> ([u32; 2], [f32; 2]) {
    let tap = |p: f32, last: f32| {
        let low = if p > 0.0 { p } else { 0.0 };
        let u = if low < last { low } else { last };
        // u ∈ [0, last] ⊂ [0, 2^31): the cast truncates exactly.
        let whole = u as u32;
        (whole, u - whole as f32)
    };
    let ((i, fx), (j, fy)) = (tap(position[0], last[0]), tap(position[1], last[1]));
    ([i, j], [fx, fy])
}

#[cfg(all(any(target_arch = "x86", target_arch = "x86_64"), target_feature = "sse2"))]
#[inline(always)]
fn texel_taps_sse2(position: [f32; 2], last: [f32; 2]) -> ([u32; 2], [f32; 2]) {
    use safe_arch::{
        convert_to_m128_from_i32_m128i, m128, max_m128, min_m128, sub_m128,
        truncate_m128_to_m128i,
    };
    // `maxps a, b` is `a > b ? a : b` and `minps a, b` is `a < b ? a : b`, lane by lane:
    // exactly the scalar comparisons (NaN compares false and takes the second operand).
    let p = m128::from_array([position[0], position[1], 0.0, 0.0]);
    let low = max_m128(p, m128::from_array([0.0; 4]));
    let u = min_m128(low, m128::from_array([last[0], last[1], 0.0, 0.0]));
    let whole = truncate_m128_to_m128i(u);
    let fraction = sub_m128(u, convert_to_m128_from_i32_m128i(whole)).to_array();
    let whole = <[i32; 4]>::from(whole);
    (
        [whole[0] as u32, whole[1] as u32],
        [fraction[0], fraction[1]],
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The taps of positions around every whole number up to a few past `last`, negative
    /// ones, NaN, infinities and huge values, against bounds small and large: the SSE2
    /// taps give the portable ones' bits.
    #[test]
    fn texel_taps_match_the_portable_taps() {
        let mut positions = vec![
            0.0f32,
            -0.0,
            f32::NAN,
            -f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::MAX,
            f32::MIN,
            -1e-30,
            1e-30,
            3e9,
        ];
        for k in -3..40 {
            for offset in [-0.5f32, -1e-6, 0.0, 1e-6, 0.25, 0.5, 0.999_999] {
                positions.push(k as f32 + offset);
            }
        }
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        for _ in 0..20_000 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            positions.push(f32::from_bits(state as u32));
            positions.push((state >> 40) as f32 / 1e4 - 200.0);
        }
        let bounds = [0.0f32, 1.0, 6.0, 35.0, 479.0, 16_383.0, 2_147_483_520.0];
        for (n, &x) in positions.iter().enumerate() {
            let y = positions[(n * 7 + 3) % positions.len()];
            for &bx in &bounds {
                let by = bounds[(n + 2) % bounds.len()];
                let (fast, portable) = (
                    texel_taps([x, y], [bx, by]),
                    texel_taps_portable([x, y], [bx, by]),
                );
                assert_eq!(fast.0, portable.0, "{x} {y} / {bx} {by}");
                assert_eq!(
                    fast.1.map(f32::to_bits),
                    portable.1.map(f32::to_bits),
                    "{x} {y} / {bx} {by}"
                );
            }
        }
    }

    /// Every level's rounding boundary (where `v · 255 + ½` crosses an integer) and a few
    /// ulps either side, values outside [0, 1], NaN and infinities, and a fixed-seed sweep
    /// of unit values and of any bits: the fast quantiser gives the per-lane casts' bytes.
    #[test]
    fn levels_match_the_per_lane_casts() {
        let mut values = vec![
            0.0f32,
            -0.0,
            1.0,
            0.5,
            f32::MIN_POSITIVE,
            1.0 - f32::EPSILON,
            -1.0,
            -0.002,
            1.002,
            1.5,
            3e9,
            -3e9,
            f32::MAX,
            f32::MIN,
            f32::NAN,
            -f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
        ];
        for k in 0..=255u32 {
            for centre in [(k as f32 - 0.5) / 255.0, k as f32 / 255.0, (k as f32 + 0.5) / 255.0] {
                let mut v = centre;
                for _ in 0..8 {
                    v = f32::from_bits(v.to_bits().saturating_sub(1));
                }
                for _ in 0..17 {
                    values.push(v);
                    v = f32::from_bits(v.to_bits() + 1);
                }
            }
        }
        let mut state = 0x2545_f491_4f6c_dd1du64;
        for _ in 0..200_000 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            values.push((state >> 40) as f32 / (1u64 << 24) as f32);
            values.push(f32::from_bits((state >> 7) as u32));
        }
        for chunk in values.chunks(4) {
            let mut lanes = [0.0; 4];
            lanes[..chunk.len()].copy_from_slice(chunk);
            // Every rotation, so each value meets every lane.
            for turn in 0..4 {
                lanes.rotate_left(usize::from(turn > 0));
                assert_eq!(
                    unit_to_levels(lanes),
                    unit_to_levels_portable(lanes),
                    "{lanes:?}"
                );
            }
        }
    }
}
