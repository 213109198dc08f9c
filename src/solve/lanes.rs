//! One row of right-hand sides as a small SIMD vector, for the supernodal solve
//! ([`solve_supernodal`](super::solve_supernodal)): takes `S` ∈ {1, 2, 4} consecutive `f64`
//! (the channels of one unknown, padded) and gives the few operations the kernel needs —
//! load, store, and multiply-add by a broadcast factor entry. Each channel is computed on
//! its own lane, so channels never mix.
//!
//! Two families: [`Portable`] (plain arrays, separate multiply and add, any target) and, on
//! x86_64, fused multiply-add types ([`Fma1`], [`Fma2`], [`Avx4`]) that are only ever
//! instantiated inside functions compiled with `#[target_feature(enable = "avx2,fma")]`
//! and called after run-time detection. Their methods are `#[inline(always)]` so that they
//! are compiled inside those functions; outside them they must not be used.

/// A row of `S` channels.
pub(super) trait Lanes: Copy {
    /// Channels per row (the stride of the interleaved right-hand sides).
    const S: usize;

    /// # Safety
    /// `p..p + S` must be readable.
    unsafe fn load(p: *const f64) -> Self;

    /// # Safety
    /// `p..p + S` must be writable.
    unsafe fn store(self, p: *mut f64);

    fn zero() -> Self;

    /// `self − a·x`, channel by channel.
    fn mul_sub(self, a: f64, x: Self) -> Self;

    /// `self + a·x`, channel by channel.
    fn mul_add(self, a: f64, x: Self) -> Self;

    /// `self · a − y`, channel by channel (`a·self` rounded first).
    fn scale_sub(self, a: f64, y: Self) -> Self;

    fn add(self, y: Self) -> Self;
}

/// Plain arrays: separate multiply and add; LLVM vectorises with the baseline ISA.
#[derive(Clone, Copy)]
pub(super) struct Portable<const S: usize>([f64; S]);

impl<const S: usize> Lanes for Portable<S> {
    const S: usize = S;

    #[inline(always)]
    unsafe fn load(p: *const f64) -> Self {
        // SAFETY: the caller's contract.
        Self(unsafe { (p as *const [f64; S]).read_unaligned() })
    }

    #[inline(always)]
    unsafe fn store(self, p: *mut f64) {
        // SAFETY: the caller's contract.
        unsafe { (p as *mut [f64; S]).write_unaligned(self.0) }
    }

    #[inline(always)]
    fn zero() -> Self {
        Self([0.0; S])
    }

    #[inline(always)]
    fn mul_sub(self, a: f64, x: Self) -> Self {
        Self(std::array::from_fn(|c| self.0[c] - a * x.0[c]))
    }

    #[inline(always)]
    fn mul_add(self, a: f64, x: Self) -> Self {
        Self(std::array::from_fn(|c| self.0[c] + a * x.0[c]))
    }

    #[inline(always)]
    fn scale_sub(self, a: f64, y: Self) -> Self {
        Self(std::array::from_fn(|c| self.0[c] * a - y.0[c]))
    }

    #[inline(always)]
    fn add(self, y: Self) -> Self {
        Self(std::array::from_fn(|c| self.0[c] + y.0[c]))
    }
}

#[cfg(target_arch = "x86_64")]
pub(super) use fma::{Avx4, Fma1, Fma2};

/// Fused multiply-add rows. SAFETY (every intrinsic call in this module): these types are
/// only constructed inside `#[target_feature(enable = "avx2,fma")]` functions that run after
/// run-time detection of both features (see the module doc).
#[cfg(target_arch = "x86_64")]
mod fma {
    use super::Lanes;
    use std::arch::x86_64::*;

    /// One channel, scalar FMA.
    #[derive(Clone, Copy)]
    pub(in crate::solve) struct Fma1(f64);

    impl Lanes for Fma1 {
        const S: usize = 1;

        #[inline(always)]
        unsafe fn load(p: *const f64) -> Self {
            // SAFETY: the caller's contract.
            Self(unsafe { *p })
        }

        #[inline(always)]
        unsafe fn store(self, p: *mut f64) {
            // SAFETY: the caller's contract.
            unsafe { *p = self.0 }
        }

        #[inline(always)]
        fn zero() -> Self {
            Self(0.0)
        }

        #[inline(always)]
        fn mul_sub(self, a: f64, x: Self) -> Self {
            Self((-a).mul_add(x.0, self.0))
        }

        #[inline(always)]
        fn mul_add(self, a: f64, x: Self) -> Self {
            Self(a.mul_add(x.0, self.0))
        }

        #[inline(always)]
        fn scale_sub(self, a: f64, y: Self) -> Self {
            Self(self.0 * a - y.0)
        }

        #[inline(always)]
        fn add(self, y: Self) -> Self {
            Self(self.0 + y.0)
        }
    }

    /// Two channels in an SSE register, FMA.
    #[derive(Clone, Copy)]
    pub(in crate::solve) struct Fma2(__m128d);

    impl Lanes for Fma2 {
        const S: usize = 2;

        #[inline(always)]
        unsafe fn load(p: *const f64) -> Self {
            // SAFETY: the caller's contract.
            Self(unsafe { _mm_loadu_pd(p) })
        }

        #[inline(always)]
        unsafe fn store(self, p: *mut f64) {
            // SAFETY: the caller's contract.
            unsafe { _mm_storeu_pd(p, self.0) }
        }

        #[inline(always)]
        fn zero() -> Self {
            // SAFETY: see the module doc.
            Self(unsafe { _mm_setzero_pd() })
        }

        #[inline(always)]
        fn mul_sub(self, a: f64, x: Self) -> Self {
            // SAFETY: see the module doc.
            Self(unsafe { _mm_fnmadd_pd(_mm_set1_pd(a), x.0, self.0) })
        }

        #[inline(always)]
        fn mul_add(self, a: f64, x: Self) -> Self {
            // SAFETY: see the module doc.
            Self(unsafe { _mm_fmadd_pd(_mm_set1_pd(a), x.0, self.0) })
        }

        #[inline(always)]
        fn scale_sub(self, a: f64, y: Self) -> Self {
            // SAFETY: see the module doc.
            Self(unsafe { _mm_sub_pd(_mm_mul_pd(self.0, _mm_set1_pd(a)), y.0) })
        }

        #[inline(always)]
        fn add(self, y: Self) -> Self {
            // SAFETY: see the module doc.
            Self(unsafe { _mm_add_pd(self.0, y.0) })
        }
    }

    /// Four channels in an AVX register, FMA.
    #[derive(Clone, Copy)]
    pub(in crate::solve) struct Avx4(__m256d);

    impl Lanes for Avx4 {
        const S: usize = 4;

        #[inline(always)]
        unsafe fn load(p: *const f64) -> Self {
            // SAFETY: the caller's contract.
            Self(unsafe { _mm256_loadu_pd(p) })
        }

        #[inline(always)]
        unsafe fn store(self, p: *mut f64) {
            // SAFETY: the caller's contract.
            unsafe { _mm256_storeu_pd(p, self.0) }
        }

        #[inline(always)]
        fn zero() -> Self {
            // SAFETY: see the module doc.
            Self(unsafe { _mm256_setzero_pd() })
        }

        #[inline(always)]
        fn mul_sub(self, a: f64, x: Self) -> Self {
            // SAFETY: see the module doc.
            Self(unsafe { _mm256_fnmadd_pd(_mm256_set1_pd(a), x.0, self.0) })
        }

        #[inline(always)]
        fn mul_add(self, a: f64, x: Self) -> Self {
            // SAFETY: see the module doc.
            Self(unsafe { _mm256_fmadd_pd(_mm256_set1_pd(a), x.0, self.0) })
        }

        #[inline(always)]
        fn scale_sub(self, a: f64, y: Self) -> Self {
            // SAFETY: see the module doc.
            Self(unsafe { _mm256_sub_pd(_mm256_mul_pd(self.0, _mm256_set1_pd(a)), y.0) })
        }

        #[inline(always)]
        fn add(self, y: Self) -> Self {
            // SAFETY: see the module doc.
            Self(unsafe { _mm256_add_pd(self.0, y.0) })
        }
    }
}
