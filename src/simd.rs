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

use std::sync::atomic::{AtomicU8, Ordering};

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
