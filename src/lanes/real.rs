//! One kernel for one value and for `LANES` values: [`Real`] and [`Vector`] are implemented by
//! `f32` and glam's `Vec3` (masks are `bool`) and by [`F32x16`] and [`Vec3x16`] (masks are
//! [`Mask16`]), so a kernel written over them is a single implementation that scalar callers run
//! at one value and lane kernels at sixteen, with the same operations in the same order and so
//! the same bits. Branches become masks: a kernel computes every step and selects, and says with
//! a mask where its result holds.

use std::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Not, Sub};

use glam::Vec3;

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
    /// A comparison's result: `bool`, or [`Mask16`].
    type Mask: Copy + BitAnd<Output = Self::Mask> + BitOr<Output = Self::Mask> + Not<Output = Self::Mask>;
    /// Vectors of these numbers.
    type Vector: Vector<Real = Self>;
    fn splat(v: f32) -> Self;
    fn sqrt(self) -> Self;
    fn abs(self) -> Self;
    fn min(self, o: Self) -> Self;
    fn max(self, o: Self) -> Self;
    fn lt(self, o: Self) -> Self::Mask;
    fn le(self, o: Self) -> Self::Mask;
    fn gt(self, o: Self) -> Self::Mask;
    fn ge(self, o: Self) -> Self::Mask;
    fn is_finite(self) -> Self::Mask;
    /// `yes` where `mask` holds, else `no`.
    fn select(mask: Self::Mask, yes: Self, no: Self) -> Self;
    /// A mask of one value everywhere.
    fn mask(v: bool) -> Self::Mask;
}

/// Vectors of three [`Real`]s: glam's `Vec3`, or [`Vec3x16`].
pub trait Vector:
    Copy + Add<Output = Self> + Sub<Output = Self> + Neg<Output = Self> + Mul<Self::Real, Output = Self>
{
    type Real: Real<Vector = Self>;
    fn zero() -> Self;
    fn dot(self, o: Self) -> Self::Real;
    fn cross(self, o: Self) -> Self;
    fn length(self) -> Self::Real;
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
    type Vector = Vec3;
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
        f32::min(self, o)
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        f32::max(self, o)
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
    fn mask(v: bool) -> bool {
        v
    }
}

impl Vector for Vec3 {
    type Real = f32;
    #[inline(always)]
    fn zero() -> Self {
        Vec3::ZERO
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
    type Vector = Vec3x16;
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
    fn mask(v: bool) -> Mask16 {
        Mask16::splat(v)
    }
}

impl Vector for Vec3x16 {
    type Real = F32x16;
    #[inline(always)]
    fn zero() -> Self {
        Vec3x16::ZERO
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
    fn is_finite(self) -> Mask16 {
        Vec3x16::is_finite(self)
    }
    #[inline(always)]
    fn select(mask: Mask16, yes: Self, no: Self) -> Self {
        Vec3x16::select(mask, yes, no)
    }
}
