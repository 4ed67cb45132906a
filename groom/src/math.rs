//! The 3-vector helpers of the whole engine (groom, importers, simulation,
//! preview, generator), on plain `[T; 3]` arrays: the layout of a groom's
//! points and of every file format, so no conversion at the boundaries.
//! Written once by a macro for `f32` ([`single`]) and `f64` ([`double`]);
//! the solver's quaternions build on [`single`] in `groombake::sim`.
//!
//! Not glam: the solver's SIMD lanes must reproduce these operations bit
//! for bit in a fixed order, which glam's SIMD-backed types do not promise.

macro_rules! vector_helpers {
    ($module:ident, $t:ty) => {
        /// 3-vector helpers in this precision.
        pub mod $module {
            pub type V3 = [$t; 3];

            #[inline(always)]
            pub fn add(a: V3, b: V3) -> V3 {
                [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
            }
            #[inline(always)]
            pub fn sub(a: V3, b: V3) -> V3 {
                [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
            }
            #[inline(always)]
            pub fn scale(a: V3, s: $t) -> V3 {
                [a[0] * s, a[1] * s, a[2] * s]
            }
            #[inline(always)]
            pub fn dot(a: V3, b: V3) -> $t {
                a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
            }
            #[inline(always)]
            pub fn cross(a: V3, b: V3) -> V3 {
                [
                    a[1] * b[2] - a[2] * b[1],
                    a[2] * b[0] - a[0] * b[2],
                    a[0] * b[1] - a[1] * b[0],
                ]
            }
            #[inline(always)]
            pub fn length(a: V3) -> $t {
                dot(a, a).sqrt()
            }
            #[inline(always)]
            pub fn is_finite3(a: V3) -> bool {
                a[0].is_finite() && a[1].is_finite() && a[2].is_finite()
            }
            /// `a` scaled to unit length; `None` when it has no direction
            /// (zero) or its length is not finite.
            #[inline(always)]
            pub fn try_normalize(a: V3) -> Option<V3> {
                let n = length(a);
                (n > 0.0 && n.is_finite()).then(|| scale(a, 1.0 / n))
            }
        }
    };
}

vector_helpers!(single, f32);
vector_helpers!(double, f64);

#[cfg(test)]
mod tests {
    use super::{double, single};

    #[test]
    fn cross_follows_the_right_hand_rule_in_both_precisions() {
        assert_eq!(
            single::cross([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
            [0.0, 0.0, 1.0]
        );
        assert_eq!(
            double::cross([0.0, 1.0, 0.0], [0.0, 0.0, 1.0]),
            [1.0, 0.0, 0.0]
        );
    }

    #[test]
    fn a_vector_without_direction_has_no_unit_vector() {
        assert_eq!(single::try_normalize([0.0; 3]), None);
        assert_eq!(single::try_normalize([f32::INFINITY, 0.0, 0.0]), None);
        let unit = double::try_normalize([0.0, 3.0, 4.0]).unwrap_or_default();
        assert!((unit[1] - 0.6).abs() < 1e-15 && (unit[2] - 0.8).abs() < 1e-15);
    }
}
