//! One kernel for one value and for `LANES` values: [`Real`] and [`Vector`] are implemented by
//! `f32` and glam's `Vec3` (masks are `bool`) and by [`F32x16`] and [`Vec3x16`] (masks are
//! [`Mask16`]), and `Real` by glam's `Vec4` too (four values, `BVec4A`), so a kernel written over
//! them is a single implementation that scalar callers run at one value and lane kernels at four
//! or sixteen, with the same operations in the same order and so the same bits. `max` and `min`
//! are SSE's (`a > b ? a : b`, `a < b ? a : b`) for every type, NaN operands included. Branches
//! become masks: a kernel computes every step and selects, and says with a mask where its result
//! holds.

use std::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Not, Sub};

use glam::{BVec4A, Vec3, Vec4};

use super::{F32x16, Mask16, Vec3x16};

/// Numbers a kernel computes with: `f32`, or [`F32x16`].
pub trait Real:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + Add<f32, Output = Self>
    + Sub<f32, Output = Self>
    + Mul<f32, Output = Self>
    + Div<f32, Output = Self>
{
    /// A comparison's result: `bool`, `BVec4A` or [`Mask16`].
    type Mask: Copy + BitAnd<Output = Self::Mask> + BitOr<Output = Self::Mask> + Not<Output = Self::Mask>;
    fn splat(v: f32) -> Self;
    fn sqrt(self) -> Self;
    fn abs(self) -> Self;
    /// `self < o ? self : o` per value (SSE `minps`).
    fn min(self, o: Self) -> Self;
    /// `self > o ? self : o` per value (SSE `maxps`).
    fn max(self, o: Self) -> Self;
    fn lt(self, o: Self) -> Self::Mask;
    fn le(self, o: Self) -> Self::Mask;
    fn gt(self, o: Self) -> Self::Mask;
    fn ge(self, o: Self) -> Self::Mask;
    fn is_finite(self) -> Self::Mask;
    /// `yes` where `mask` holds, else `no`.
    fn select(mask: Self::Mask, yes: Self, no: Self) -> Self;
    /// Whether `mask` holds everywhere.
    fn all(mask: Self::Mask) -> bool;
    /// Whether `mask` holds somewhere.
    fn any(mask: Self::Mask) -> bool;
}

/// A [`Real`] with 3-vectors of its own: `f32` (`Vec3`) and [`F32x16`] ([`Vec3x16`]).
pub trait Real3: Real {
    type Vector: Vector<Real = Self>;
}

impl Real3 for f32 {
    type Vector = Vec3;
}

impl Real3 for F32x16 {
    type Vector = Vec3x16;
}

/// Vectors of three [`Real`]s: glam's `Vec3`, or [`Vec3x16`].
pub trait Vector:
    Copy + Add<Output = Self> + Sub<Output = Self> + Neg<Output = Self> + Mul<Self::Real, Output = Self>
{
    type Real: Real;
    fn zero() -> Self;
    /// `v` in every value.
    fn splat(v: Vec3) -> Self;
    fn new(x: Self::Real, y: Self::Real, z: Self::Real) -> Self;
    fn xyz(self) -> [Self::Real; 3];
    fn dot(self, o: Self) -> Self::Real;
    fn cross(self, o: Self) -> Self;
    fn length(self) -> Self::Real;
    /// Each component's magnitude.
    fn abs(self) -> Self;
    fn is_finite(self) -> <Self::Real as Real>::Mask;
    /// `yes` where `mask` holds, else `no`.
    fn select(mask: <Self::Real as Real>::Mask, yes: Self, no: Self) -> Self;

    /// Unit vector along `self`, zero where it has no direction (as glam's `normalize_or_zero`).
    #[inline(always)]
    fn normalize_or_zero(self) -> Self {
        let rcp = Self::Real::splat(1.0) / self.length();
        let ok = rcp.is_finite() & rcp.gt(Self::Real::splat(0.0));
        Self::select(ok, self * rcp, Self::zero())
    }

    /// Unit vector along `self` (as glam's `normalize`, without its debug check).
    #[inline(always)]
    fn normalize(self) -> Self {
        self * (Self::Real::splat(1.0) / self.length())
    }
}

impl Real for f32 {
    type Mask = bool;
    #[inline(always)]
    fn splat(v: f32) -> Self {
        v
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f32::sqrt(self)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        f32::abs(self)
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        if self < o { self } else { o }
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        if self > o { self } else { o }
    }
    #[inline(always)]
    fn lt(self, o: Self) -> bool {
        self < o
    }
    #[inline(always)]
    fn le(self, o: Self) -> bool {
        self <= o
    }
    #[inline(always)]
    fn gt(self, o: Self) -> bool {
        self > o
    }
    #[inline(always)]
    fn ge(self, o: Self) -> bool {
        self >= o
    }
    #[inline(always)]
    fn is_finite(self) -> bool {
        f32::is_finite(self)
    }
    #[inline(always)]
    fn select(mask: bool, yes: Self, no: Self) -> Self {
        if mask { yes } else { no }
    }
    #[inline(always)]
    fn all(mask: bool) -> bool {
        mask
    }
    #[inline(always)]
    fn any(mask: bool) -> bool {
        mask
    }
}

impl Vector for Vec3 {
    type Real = f32;
    #[inline(always)]
    fn zero() -> Self {
        Vec3::ZERO
    }
    #[inline(always)]
    fn splat(v: Vec3) -> Self {
        v
    }
    #[inline(always)]
    fn new(x: f32, y: f32, z: f32) -> Self {
        Vec3::new(x, y, z)
    }
    #[inline(always)]
    fn xyz(self) -> [f32; 3] {
        self.to_array()
    }
    #[inline(always)]
    fn dot(self, o: Self) -> f32 {
        Vec3::dot(self, o)
    }
    #[inline(always)]
    fn cross(self, o: Self) -> Self {
        Vec3::cross(self, o)
    }
    #[inline(always)]
    fn length(self) -> f32 {
        Vec3::length(self)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        Vec3::abs(self)
    }
    #[inline(always)]
    fn is_finite(self) -> bool {
        Vec3::is_finite(self)
    }
    #[inline(always)]
    fn select(mask: bool, yes: Self, no: Self) -> Self {
        if mask { yes } else { no }
    }
}

impl Real for F32x16 {
    type Mask = Mask16;
    #[inline(always)]
    fn splat(v: f32) -> Self {
        F32x16::splat(v)
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        F32x16::sqrt(self)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        F32x16::abs(self)
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        F32x16::min(self, o)
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        F32x16::max(self, o)
    }
    #[inline(always)]
    fn lt(self, o: Self) -> Mask16 {
        F32x16::lt(self, o)
    }
    #[inline(always)]
    fn le(self, o: Self) -> Mask16 {
        F32x16::le(self, o)
    }
    #[inline(always)]
    fn gt(self, o: Self) -> Mask16 {
        F32x16::gt(self, o)
    }
    #[inline(always)]
    fn ge(self, o: Self) -> Mask16 {
        F32x16::ge(self, o)
    }
    #[inline(always)]
    fn is_finite(self) -> Mask16 {
        F32x16::is_finite(self)
    }
    #[inline(always)]
    fn select(mask: Mask16, yes: Self, no: Self) -> Self {
        F32x16::select(mask, yes, no)
    }
    #[inline(always)]
    fn all(mask: Mask16) -> bool {
        mask.all()
    }
    #[inline(always)]
    fn any(mask: Mask16) -> bool {
        mask.any()
    }
}

/// A wide light-BVH node's four clusters (see `light_sampler::importance_lanes`).
impl Real for Vec4 {
    type Mask = BVec4A;
    #[inline(always)]
    fn splat(v: f32) -> Self {
        Vec4::splat(v)
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        Vec4::sqrt(self)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        Vec4::abs(self)
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        Vec4::min(self, o)
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        Vec4::max(self, o)
    }
    #[inline(always)]
    fn lt(self, o: Self) -> BVec4A {
        self.cmplt(o)
    }
    #[inline(always)]
    fn le(self, o: Self) -> BVec4A {
        self.cmple(o)
    }
    #[inline(always)]
    fn gt(self, o: Self) -> BVec4A {
        self.cmpgt(o)
    }
    #[inline(always)]
    fn ge(self, o: Self) -> BVec4A {
        self.cmpge(o)
    }
    #[inline(always)]
    fn is_finite(self) -> BVec4A {
        self.is_finite_mask()
    }
    #[inline(always)]
    fn select(mask: BVec4A, yes: Self, no: Self) -> Self {
        Vec4::select(mask, yes, no)
    }
    #[inline(always)]
    fn all(mask: BVec4A) -> bool {
        mask.all()
    }
    #[inline(always)]
    fn any(mask: BVec4A) -> bool {
        mask.any()
    }
}

impl Vector for Vec3x16 {
    type Real = F32x16;
    #[inline(always)]
    fn zero() -> Self {
        Vec3x16::ZERO
    }
    #[inline(always)]
    fn splat(v: Vec3) -> Self {
        Vec3x16::splat(v)
    }
    #[inline(always)]
    fn new(x: F32x16, y: F32x16, z: F32x16) -> Self {
        Vec3x16 { x, y, z }
    }
    #[inline(always)]
    fn xyz(self) -> [F32x16; 3] {
        [self.x, self.y, self.z]
    }
    #[inline(always)]
    fn dot(self, o: Self) -> F32x16 {
        Vec3x16::dot(self, o)
    }
    #[inline(always)]
    fn cross(self, o: Self) -> Self {
        Vec3x16::cross(self, o)
    }
    #[inline(always)]
    fn length(self) -> F32x16 {
        Vec3x16::length(self)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        self.map(F32x16::abs)
    }
    #[inline(always)]
    fn is_finite(self) -> Mask16 {
        Vec3x16::is_finite(self)
    }
    #[inline(always)]
    fn select(mask: Mask16, yes: Self, no: Self) -> Self {
        Vec3x16::select(mask, yes, no)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_value_four_and_sixteen_agree_on_min_max_and_comparisons_with_nan_and_signed_zeros() {
        let values = [f32::NAN, -0.0, 0.0, 1.0, -1.0, f32::INFINITY, f32::NEG_INFINITY, f32::MIN_POSITIVE / 2.0];
        let pairs: Vec<(f32, f32)> = values.iter().flat_map(|&a| values.iter().map(move |&b| (a, b))).collect();
        for chunk in pairs.chunks(16) {
            let (mut a, mut b) = (F32x16::ZERO, F32x16::ZERO);
            for (l, &(x, y)) in chunk.iter().enumerate() {
                (a[l], b[l]) = (x, y);
            }
            let (max16, min16, lt16) = (Real::max(a, b), Real::min(a, b), Real::lt(a, b));
            for (l, &(x, y)) in chunk.iter().enumerate() {
                let (x4, y4) = (Vec4::splat(x), Vec4::splat(y));
                let max = [Real::max(x, y), max16[l], Real::max(x4, y4).x].map(f32::to_bits);
                let min = [Real::min(x, y), min16[l], Real::min(x4, y4).x].map(f32::to_bits);
                assert!(max.iter().all(|&m| m == max[0]), "max({x}, {y}): {max:x?}");
                assert!(min.iter().all(|&m| m == min[0]), "min({x}, {y}): {min:x?}");
                assert_eq!(Real::lt(x, y), lt16.test(l), "{x} < {y}");
                assert_eq!(Real::lt(x, y), <Vec4 as Real>::all(Real::lt(x4, y4)), "{x} < {y}");
            }
        }
    }
}
