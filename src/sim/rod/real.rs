//! The numbers of the physical model's direct solve: `f64` for one strand,
//! or `f64` lanes for four or eight strands at once. Apart from the solve
//! (direct.rs) and the lanes of the constraint sweep (lanes.rs), which
//! both use them.

use std::ops::{Add, Mul, Neg, Sub};

/// A number of the physical model's direct solve: `f64` for one strand,
/// [`F64x4`] for four strands in lanes. Both do the same IEEE
/// operations in the same order (no fused multiply-add, branches become
/// selects), so a strand's result does not depend on the path.
pub trait Real:
    Copy
    + Default
    + std::fmt::Debug
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + std::ops::Div<Output = Self>
    + Neg<Output = Self>
{
    /// Strands per number.
    const WIDTH: usize;
    fn splat(v: f64) -> Self;
    /// Lane `i` from `f(i)`.
    fn gather(f: impl FnMut(usize) -> f64) -> Self;
    fn lane(self, i: usize) -> f64;
    /// Replaces lane `i` (one store: loading a strand into its lane this
    /// way is much cheaper than gathering the lanes of each number).
    fn set_lane(&mut self, i: usize, v: f64);
    fn sqrt(self) -> Self;
    /// Rounded to the nearest `f32` (the precision a value stored as
    /// `f32` keeps), as `f64`.
    fn to_f32_precision(self) -> Self;
    /// `if a > b { x } else { y }`, per lane.
    fn gt_select(a: Self, b: Self, x: Self, y: Self) -> Self;
    /// `if a < b { x } else { y }`, per lane.
    fn lt_select(a: Self, b: Self, x: Self, y: Self) -> Self;
    /// `if a == b { x } else { y }`, per lane.
    fn eq_select(a: Self, b: Self, x: Self, y: Self) -> Self;
}

impl Real for f64 {
    const WIDTH: usize = 1;
    #[inline(always)]
    fn splat(v: f64) -> f64 {
        v
    }
    #[inline(always)]
    fn gather(mut f: impl FnMut(usize) -> f64) -> f64 {
        f(0)
    }
    #[inline(always)]
    fn lane(self, _: usize) -> f64 {
        self
    }
    #[inline(always)]
    fn set_lane(&mut self, _: usize, v: f64) {
        *self = v;
    }
    #[inline(always)]
    fn sqrt(self) -> f64 {
        f64::sqrt(self)
    }
    #[inline(always)]
    fn to_f32_precision(self) -> f64 {
        self as f32 as f64
    }
    #[inline(always)]
    fn gt_select(a: f64, b: f64, x: f64, y: f64) -> f64 {
        if a > b {
            x
        } else {
            y
        }
    }
    #[inline(always)]
    fn lt_select(a: f64, b: f64, x: f64, y: f64) -> f64 {
        if a < b {
            x
        } else {
            y
        }
    }
    #[inline(always)]
    fn eq_select(a: f64, b: f64, x: f64, y: f64) -> f64 {
        if a == b {
            x
        } else {
            y
        }
    }
}

/// `f64` lanes of the physical model's solve. Plain arrays rather than
/// `wide::f64x4`: wide picks its instructions when the crate is compiled
/// (SSE2 in the portable x86-64 build), while these element-wise operations
/// also compile to AVX2 or AVX-512 inside the solve's copies built with
/// `#[target_feature]` and chosen at run time (`Direct::iterate_lanes`).
/// Either way each lane does the IEEE operation of the scalar code (no
/// FMA), so the results are the same bits at any width. Written out per
/// lane (not with `array::map`, which was not inlined in the hot loop).
macro_rules! f64_lanes {
    ($(#[$doc:meta])* $name:ident, $width:literal, $align:literal, [$($i:literal)*]) => {
        $(#[$doc])*
        #[derive(Debug, Clone, Copy, PartialEq, Default)]
        #[repr(align($align))]
        pub struct $name(pub [f64; $width]);

        impl $name {
            #[inline(always)]
            fn zip(self, o: $name, f: impl Fn(f64, f64) -> f64) -> $name {
                let (a, b) = (self.0, o.0);
                $name([$(f(a[$i], b[$i])),*])
            }
            #[inline(always)]
            fn each(self, f: impl Fn(f64) -> f64) -> $name {
                let a = self.0;
                $name([$(f(a[$i])),*])
            }
            #[inline(always)]
            fn select(
                a: $name,
                b: $name,
                x: $name,
                y: $name,
                test: impl Fn(f64, f64) -> bool,
            ) -> $name {
                let pick = |i: usize| if test(a.0[i], b.0[i]) { x.0[i] } else { y.0[i] };
                $name([$(pick($i)),*])
            }
        }

        impl Add for $name {
            type Output = $name;
            #[inline(always)]
            fn add(self, o: $name) -> $name {
                self.zip(o, |a, b| a + b)
            }
        }
        impl Sub for $name {
            type Output = $name;
            #[inline(always)]
            fn sub(self, o: $name) -> $name {
                self.zip(o, |a, b| a - b)
            }
        }
        impl Mul for $name {
            type Output = $name;
            #[inline(always)]
            fn mul(self, o: $name) -> $name {
                self.zip(o, |a, b| a * b)
            }
        }
        impl std::ops::Div for $name {
            type Output = $name;
            #[inline(always)]
            fn div(self, o: $name) -> $name {
                self.zip(o, |a, b| a / b)
            }
        }
        impl Neg for $name {
            type Output = $name;
            #[inline(always)]
            fn neg(self) -> $name {
                self.each(|a| -a)
            }
        }

        impl Real for $name {
            const WIDTH: usize = $width;
            #[inline(always)]
            fn splat(v: f64) -> Self {
                $name([v; $width])
            }
            #[inline(always)]
            fn gather(mut f: impl FnMut(usize) -> f64) -> Self {
                $name([$(f($i)),*])
            }
            #[inline(always)]
            fn lane(self, i: usize) -> f64 {
                self.0[i]
            }
            #[inline(always)]
            fn set_lane(&mut self, i: usize, v: f64) {
                self.0[i] = v;
            }
            #[inline(always)]
            fn sqrt(self) -> Self {
                self.each(f64::sqrt)
            }
            #[inline(always)]
            fn to_f32_precision(self) -> Self {
                self.each(|a| a as f32 as f64)
            }
            #[inline(always)]
            fn gt_select(a: Self, b: Self, x: Self, y: Self) -> Self {
                $name::select(a, b, x, y, |a, b| a > b)
            }
            #[inline(always)]
            fn lt_select(a: Self, b: Self, x: Self, y: Self) -> Self {
                $name::select(a, b, x, y, |a, b| a < b)
            }
            #[inline(always)]
            fn eq_select(a: Self, b: Self, x: Self, y: Self) -> Self {
                $name::select(a, b, x, y, |a, b| a == b)
            }
        }
    };
}

f64_lanes!(
    /// Four `f64` lanes (AVX2: one register).
    F64x4, 4, 32, [0 1 2 3]
);
f64_lanes!(
    /// Eight `f64` lanes (AVX-512: one register), for eight strands.
    F64x8, 8, 64, [0 1 2 3 4 5 6 7]
);

/// Strands per group of the physical model's wide solve.
pub const WIDE: usize = 8;
