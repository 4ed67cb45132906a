//! The widest instructions the solver's lanes may run in: found once per
//! [`Solver`](super::Solver) from the CPU, then passed down with the step's
//! context, so every phase of a step takes the same choice and a test can
//! lower it for one solver (to check the AVX2 path's bits on a CPU with
//! AVX-512) without touching any other solver in the process.
//!
//! Every path does the same IEEE operations in the same order (no FMA), so
//! the choice changes the speed, never a bit of a result.
//!
//! [`in_widest!`] is the one dispatch: a body written once, compiled for
//! each set, run in the widest the choice allows.

/// An instruction set of the lanes, narrowest first (so `min` lowers a
/// choice). The phases' dispatch runs code compiled for the set it is given
/// (`unsafe`), so a set must come from [`Instructions::of_this_cpu`],
/// perhaps lowered: never wider than the CPU's.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Instructions {
    /// What every x86-64 (or other) CPU runs: SSE2 on x86-64.
    Baseline,
    /// AVX2: the groups of four's f64 lanes, the blower's and the
    /// volumetric grid's eight-float lanes, the per-strand phases.
    /// (Groups of eight as two AVX2 registers a lane took fewer
    /// instructions but four times the L2 misses on a CPU with 512 KB of
    /// L2: not faster.)
    Avx2,
    /// AVX-512F: also the groups of eight and the rest shape in lanes.
    Avx512,
}

impl Instructions {
    /// The widest this CPU has.
    pub fn of_this_cpu() -> Instructions {
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx512f") {
                return Instructions::Avx512;
            }
            if std::arch::is_x86_feature_detected!("avx2") {
                return Instructions::Avx2;
            }
        }
        Instructions::Baseline
    }

    /// AVX-512F may be used (and with it AVX2).
    #[inline]
    pub fn avx512(self) -> bool {
        self == Instructions::Avx512
    }

    /// AVX2 may be used.
    #[inline]
    pub fn avx2(self) -> bool {
        self >= Instructions::Avx2
    }

    /// The name `bench` reports.
    pub fn name(self) -> &'static str {
        match self {
            Instructions::Baseline => "baseline",
            Instructions::Avx2 => "AVX2",
            Instructions::Avx512 => "AVX-512",
        }
    }
}

/// Runs a body compiled for the widest instructions of a set: AVX-512F,
/// AVX2, else the baseline. The body is written once as a function of the
/// named locals (a function, not a closure: only a function can be
/// compiled for other instructions), and compiled once per set; every
/// path does the same operations in the same order (no FMA), so the set
/// changes the speed, never a bit. The body should be, or call, code that
/// is `#[inline(always)]`, so that it is compiled in the wider
/// instructions too.
///
/// `in_widest!(set, fn<T: Bound>(a: A, b: B) -> R { ... })`: the generic
/// parameters are optional. `in_widest!(set, fn<const WIDE; T: Bound>(...)
/// ...)` also gives the body a `const WIDE: bool`, true in AVX2 or wider,
/// for code written in intrinsics that no baseline CPU has.
///
/// The set must come from [`Instructions::of_this_cpu`], perhaps lowered:
/// the dispatch is `unsafe`, sound only on a CPU that has the set.
macro_rules! in_widest {
    (
        $set:expr,
        fn $(<$($g:ident: $bound:path),* $(,)?>)?
        ($($arg:ident: $ty:ty),* $(,)?) $(-> $ret:ty)? $body:block
    ) => {
        $crate::sim::instructions::in_widest!(
            $set,
            fn<const _WIDE; $($($g: $bound),*)?>($($arg: $ty),*) $(-> $ret)? $body
        )
    };
    (
        $set:expr,
        fn<const $wide:ident; $($g:ident: $bound:path),* $(,)?>
        ($($arg:ident: $ty:ty),* $(,)?) $(-> $ret:ty)? $body:block
    ) => {{
        #[inline(always)]
        fn body<const $wide: bool, $($g: $bound),*>($($arg: $ty),*) $(-> $ret)? $body
        #[inline(always)]
        fn baseline<$($g: $bound),*>($($arg: $ty),*) $(-> $ret)? {
            body::<false, $($g),*>($($arg),*)
        }
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2")]
        fn avx2<$($g: $bound),*>($($arg: $ty),*) $(-> $ret)? {
            body::<true, $($g),*>($($arg),*)
        }
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx512f")]
        fn avx512<$($g: $bound),*>($($arg: $ty),*) $(-> $ret)? {
            body::<true, $($g),*>($($arg),*)
        }
        match $set {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: the set comes from `Instructions::of_this_cpu`: the CPU
            // has AVX-512F.
            $crate::sim::Instructions::Avx512 => unsafe { avx512($($arg),*) },
            #[cfg(target_arch = "x86_64")]
            // SAFETY: as above, the CPU has AVX2.
            $crate::sim::Instructions::Avx2 => unsafe { avx2($($arg),*) },
            _ => baseline($($arg),*),
        }
    }};
}
pub(crate) use in_widest;

/// Asks the cache for the line holding `item`, where the code knows what it
/// will read next and the hardware cannot (a grid of megabytes read at
/// scattered places). Only a hint: no value read or computed changes.
#[inline(always)]
pub(crate) fn prefetch<T>(item: &T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch of a valid reference's address (SSE, part of
    // x86-64) reads nothing the program sees.
    unsafe {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        _mm_prefetch::<_MM_HINT_T0>(std::ptr::from_ref(item).cast());
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = item;
}
