//! The lane types kernels are written over: [`F32x16`], [`U32x16`], [`Mask16`] and [`Vec3x16`],
//! `LANES` values each, whose every operation is one loop over the lanes with one step in it (the
//! form LLVM vectorises, see the parent module). Inside [`super::widest`] each operation compiles
//! to one or two AVX-512 or AVX2 instructions; outside it to SSE2. Arithmetic rounds exactly as
//! the scalar operation does, lane by lane, so a kernel over these types gives the bits of the
//! scalar code it stands for when it performs the same operations in the same order.
//!
//! Masks are bit masks (all ones or zero per lane), not bools: selects on arrays of bools stayed
//! scalar where bit masks vectorised.

use std::ops::{Add, AddAssign, BitAnd, BitOr, Div, DivAssign, Mul, MulAssign, Neg, Not, Sub, SubAssign};

use glam::Vec3;

use super::{LANES, block, block_mut};

/// `LANES` f32.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(transparent)]
pub struct F32x16(pub [f32; LANES]);

/// `LANES` u32 (wrapping arithmetic).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(transparent)]
pub struct U32x16(pub [u32; LANES]);

/// A comparison's result per lane: all ones where true, zero where false.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(transparent)]
pub struct Mask16(pub [u32; LANES]);

/// `LANES` vectors as lane columns x, y, z.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct Vec3x16 {
    pub x: F32x16,
    pub y: F32x16,
    pub z: F32x16,
}

/// One loop over the lanes computing `$e` from lane `$l` into a new array.
macro_rules! each {
    ($zero:expr, |$l:ident| $e:expr) => {{
        let mut r = [$zero; LANES];
        for $l in 0..LANES {
            r[$l] = $e;
        }
        r
    }};
}

impl F32x16 {
    pub const ZERO: Self = Self([0.0; LANES]);
    pub const ONE: Self = Self([1.0; LANES]);

    #[inline(always)]
    pub const fn splat(v: f32) -> Self {
        Self([v; LANES])
    }

    /// Lanes `first..first + LANES` of `column`. Panics if fewer remain.
    #[inline(always)]
    pub fn load(column: &[f32], first: usize) -> Self {
        Self(*block(column, first))
    }

    /// Writes the lanes to `column[first..first + LANES]`. Panics if fewer remain.
    #[inline(always)]
    pub fn store(self, column: &mut [f32], first: usize) {
        *block_mut(column, first) = self.0;
    }

    /// Lane `l` is `column[index[l]]`. Panics on an index out of range.
    #[inline(always)]
    pub fn gather(column: &[f32], index: U32x16) -> Self {
        Self(each!(0.0, |l| column[index.0[l] as usize]))
    }

    #[inline(always)]
    pub fn map(self, f: impl Fn(f32) -> f32) -> Self {
        Self(each!(0.0, |l| f(self.0[l])))
    }

    #[inline(always)]
    pub fn zip(self, o: Self, f: impl Fn(f32, f32) -> f32) -> Self {
        Self(each!(0.0, |l| f(self.0[l], o.0[l])))
    }

    #[inline(always)]
    fn test(self, o: Self, f: impl Fn(f32, f32) -> bool) -> Mask16 {
        Mask16(each!(0, |l| 0u32.wrapping_sub(f(self.0[l], o.0[l]) as u32)))
    }

    #[inline(always)]
    pub fn sqrt(self) -> Self {
        self.map(f32::sqrt)
    }

    #[inline(always)]
    pub fn abs(self) -> Self {
        self.map(f32::abs)
    }

    /// `self > o ? self : o` per lane (SSE `maxps`: `o` where either is NaN).
    #[inline(always)]
    pub fn max(self, o: Self) -> Self {
        self.zip(o, |a, b| if a > b { a } else { b })
    }

    /// `self < o ? self : o` per lane (SSE `minps`: `o` where either is NaN).
    #[inline(always)]
    pub fn min(self, o: Self) -> Self {
        self.zip(o, |a, b| if a < b { a } else { b })
    }

    #[inline(always)]
    pub fn lt(self, o: Self) -> Mask16 {
        self.test(o, |a, b| a < b)
    }

    #[inline(always)]
    pub fn le(self, o: Self) -> Mask16 {
        self.test(o, |a, b| a <= b)
    }

    #[inline(always)]
    pub fn gt(self, o: Self) -> Mask16 {
        self.test(o, |a, b| a > b)
    }

    #[inline(always)]
    pub fn ge(self, o: Self) -> Mask16 {
        self.test(o, |a, b| a >= b)
    }

    #[inline(always)]
    pub fn eq(self, o: Self) -> Mask16 {
        self.test(o, |a, b| a == b)
    }

    #[inline(always)]
    pub fn ne(self, o: Self) -> Mask16 {
        self.test(o, |a, b| a != b)
    }

    /// Lanes neither infinite nor NaN.
    #[inline(always)]
    pub fn is_finite(self) -> Mask16 {
        Mask16(each!(0, |l| 0u32.wrapping_sub(self.0[l].is_finite() as u32)))
    }

    #[inline(always)]
    pub fn is_nan(self) -> Mask16 {
        self.ne(self)
    }

    #[inline(always)]
    pub fn to_bits(self) -> U32x16 {
        U32x16(each!(0, |l| self.0[l].to_bits()))
    }

    #[inline(always)]
    pub fn from_bits(bits: U32x16) -> Self {
        Self(each!(0.0, |l| f32::from_bits(bits.0[l])))
    }

    /// `yes` where `mask` is set, `no` elsewhere, as bits.
    #[inline(always)]
    pub fn select(mask: Mask16, yes: Self, no: Self) -> Self {
        Self::from_bits(U32x16::select(mask, yes.to_bits(), no.to_bits()))
    }

    /// The lanes' sum, added from lane 0 up.
    #[inline(always)]
    pub fn sum(self) -> f32 {
        self.0.iter().fold(0.0, |a, &b| a + b)
    }
}

impl U32x16 {
    #[inline(always)]
    pub const fn splat(v: u32) -> Self {
        Self([v; LANES])
    }

    /// Lanes `first..first + LANES` of `column`. Panics if fewer remain.
    #[inline(always)]
    pub fn load(column: &[u32], first: usize) -> Self {
        Self(*block(column, first))
    }

    /// 0, 1, .. `LANES` - 1.
    #[inline(always)]
    pub fn lane_indices() -> Self {
        Self(each!(0, |l| l as u32))
    }

    #[inline(always)]
    pub fn eq(self, o: Self) -> Mask16 {
        Mask16(each!(0, |l| 0u32.wrapping_sub((self.0[l] == o.0[l]) as u32)))
    }

    /// Whether every lane holds lane 0's value.
    #[inline(always)]
    pub fn is_uniform(self) -> bool {
        self.0.iter().all(|&v| v == self.0[0])
    }

    #[inline(always)]
    pub fn to_f32(self) -> F32x16 {
        F32x16(each!(0.0, |l| self.0[l] as f32))
    }

    /// `yes` where `mask` is set, `no` elsewhere.
    #[inline(always)]
    pub fn select(mask: Mask16, yes: Self, no: Self) -> Self {
        Self(each!(0, |l| (yes.0[l] & mask.0[l]) | (no.0[l] & !mask.0[l])))
    }
}

impl Mask16 {
    #[inline(always)]
    pub const fn splat(v: bool) -> Self {
        Self([0u32.wrapping_sub(v as u32); LANES])
    }

    #[inline(always)]
    pub fn from_bools(b: [bool; LANES]) -> Self {
        Self(each!(0, |l| 0u32.wrapping_sub(b[l] as u32)))
    }

    #[inline(always)]
    pub fn to_bools(self) -> [bool; LANES] {
        each!(false, |l| self.0[l] != 0)
    }

    /// Whether lane `l` is set.
    #[inline(always)]
    pub fn test(self, l: usize) -> bool {
        self.0[l] != 0
    }

    #[inline(always)]
    pub fn all(self) -> bool {
        self.0.iter().fold(u32::MAX, |a, &b| a & b) != 0
    }

    #[inline(always)]
    pub fn any(self) -> bool {
        self.0.iter().fold(0, |a, &b| a | b) != 0
    }

    /// Bit `l` set where lane `l` is: `movmskps` per 4 lanes (LLVM does not find it in a loop of
    /// shifts), SSE being in x86-64's baseline.
    #[inline(always)]
    pub fn bits(self) -> u32 {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::x86_64::{_mm_loadu_ps, _mm_movemask_ps};
            let mut bits = 0;
            for q in 0..LANES / 4 {
                // SAFETY: SSE is baseline on x86-64; the load reads lanes 4q..4q + 4 of 16.
                let m = unsafe { _mm_movemask_ps(_mm_loadu_ps(self.0.as_ptr().add(4 * q).cast())) };
                bits |= (m as u32) << (4 * q);
            }
            bits
        }
        #[cfg(not(target_arch = "x86_64"))]
        (0..LANES).fold(0, |bits, l| bits | (self.0[l] >> 31) << l)
    }

    /// The mask with lane `l` set where bit `l` of `bits` is.
    #[inline(always)]
    pub fn from_bits(bits: u32) -> Self {
        Self(each!(0, |l| 0u32.wrapping_sub((bits >> l) & 1)))
    }
}

impl Vec3x16 {
    pub const ZERO: Self = Self::splat(Vec3::ZERO);

    #[inline(always)]
    pub const fn splat(v: Vec3) -> Self {
        Self { x: F32x16::splat(v.x), y: F32x16::splat(v.y), z: F32x16::splat(v.z) }
    }

    /// The lane columns of `LANES` vectors, read from the block as one run of floats, which LLVM
    /// loads as whole registers and shuffles (reading `v[l].x` lane by lane made scalar loads and
    /// stores that stalled the vector loads after them).
    #[inline(always)]
    pub fn from_vec3s(v: &[Vec3; LANES]) -> Self {
        // SAFETY: `Vec3` is `#[repr(C)]` of three f32 (no padding), so the block is 3 * LANES f32.
        let flat: &[f32; 3 * LANES] = unsafe { &*(v as *const [Vec3; LANES]).cast() };
        let axis = |a: usize| F32x16(each!(0.0, |l| flat[3 * l + a]));
        Self { x: axis(0), y: axis(1), z: axis(2) }
    }

    /// The inverse of [`Self::from_vec3s`]: writes the lanes through the block as one run of floats
    /// (an interleaving store LLVM can shuffle), not vector by vector.
    #[inline(always)]
    pub fn store_vec3s(self, v: &mut [Vec3; LANES]) {
        // SAFETY: as in `from_vec3s`.
        let flat: &mut [f32; 3 * LANES] = unsafe { &mut *(v as *mut [Vec3; LANES]).cast() };
        for l in 0..LANES {
            flat[3 * l] = self.x.0[l];
            flat[3 * l + 1] = self.y.0[l];
            flat[3 * l + 2] = self.z.0[l];
        }
    }

    /// Vectors `first..first + LANES` of `column`. Panics if fewer remain.
    #[inline(always)]
    pub fn load(column: &[Vec3], first: usize) -> Self {
        Self::from_vec3s(block(column, first))
    }

    /// Lane `l` is `column[index[l]]`. Panics on an index out of range.
    #[inline(always)]
    pub fn gather(column: &[Vec3], index: U32x16) -> Self {
        let mut r = Self::ZERO;
        for l in 0..LANES {
            r.set_lane(l, column[index.0[l] as usize]);
        }
        r
    }

    /// The columns x, y, z as an array.
    #[inline(always)]
    pub fn as_array(&self) -> &[F32x16; 3] {
        // SAFETY: `#[repr(C)]` of three fields of one type: laid out as an array of three.
        unsafe { &*(self as *const Self).cast() }
    }

    #[inline(always)]
    pub fn as_array_mut(&mut self) -> &mut [F32x16; 3] {
        // SAFETY: as in `as_array`.
        unsafe { &mut *(self as *mut Self).cast() }
    }

    #[inline(always)]
    pub fn lane(&self, l: usize) -> Vec3 {
        Vec3::new(self.x.0[l], self.y.0[l], self.z.0[l])
    }

    #[inline(always)]
    pub fn set_lane(&mut self, l: usize, v: Vec3) {
        (self.x.0[l], self.y.0[l], self.z.0[l]) = (v.x, v.y, v.z);
    }

    /// `x x' + y y' + z z'`, added in that order (as glam's scalar `Vec3::dot`).
    #[inline(always)]
    pub fn dot(self, o: Self) -> F32x16 {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    /// As glam's scalar `Vec3::cross`.
    #[inline(always)]
    pub fn cross(self, o: Self) -> Self {
        Self { x: self.y * o.z - o.y * self.z, y: self.z * o.x - o.z * self.x, z: self.x * o.y - o.x * self.y }
    }

    #[inline(always)]
    pub fn length_squared(self) -> F32x16 {
        self.dot(self)
    }

    #[inline(always)]
    pub fn length(self) -> F32x16 {
        self.dot(self).sqrt()
    }

    /// Every component finite.
    #[inline(always)]
    pub fn is_finite(self) -> Mask16 {
        self.x.is_finite() & self.y.is_finite() & self.z.is_finite()
    }

    #[inline(always)]
    pub fn select(mask: Mask16, yes: Self, no: Self) -> Self {
        Self {
            x: F32x16::select(mask, yes.x, no.x),
            y: F32x16::select(mask, yes.y, no.y),
            z: F32x16::select(mask, yes.z, no.z),
        }
    }

    #[inline(always)]
    pub fn map(self, f: impl Fn(F32x16) -> F32x16) -> Self {
        Self { x: f(self.x), y: f(self.y), z: f(self.z) }
    }
}

macro_rules! f32_op {
    ($trait:ident, $f:ident, $assign:ident, $fa:ident, $op:tt) => {
        impl $trait for F32x16 {
            type Output = Self;
            #[inline(always)]
            fn $f(self, o: Self) -> Self {
                Self(each!(0.0, |l| self.0[l] $op o.0[l]))
            }
        }
        impl $trait<f32> for F32x16 {
            type Output = Self;
            #[inline(always)]
            fn $f(self, o: f32) -> Self {
                Self(each!(0.0, |l| self.0[l] $op o))
            }
        }
        impl $trait<F32x16> for f32 {
            type Output = F32x16;
            #[inline(always)]
            fn $f(self, o: F32x16) -> F32x16 {
                F32x16(each!(0.0, |l| self $op o.0[l]))
            }
        }
        impl $assign for F32x16 {
            #[inline(always)]
            fn $fa(&mut self, o: Self) {
                *self = *self $op o;
            }
        }
        impl $trait for Vec3x16 {
            type Output = Self;
            #[inline(always)]
            fn $f(self, o: Self) -> Self {
                Self { x: self.x $op o.x, y: self.y $op o.y, z: self.z $op o.z }
            }
        }
        impl $trait<F32x16> for Vec3x16 {
            type Output = Self;
            #[inline(always)]
            fn $f(self, o: F32x16) -> Self {
                Self { x: self.x $op o, y: self.y $op o, z: self.z $op o }
            }
        }
        impl $trait<f32> for Vec3x16 {
            type Output = Self;
            #[inline(always)]
            fn $f(self, o: f32) -> Self {
                Self { x: self.x $op o, y: self.y $op o, z: self.z $op o }
            }
        }
        impl $assign for Vec3x16 {
            #[inline(always)]
            fn $fa(&mut self, o: Self) {
                *self = *self $op o;
            }
        }
    };
}
f32_op!(Add, add, AddAssign, add_assign, +);
f32_op!(Sub, sub, SubAssign, sub_assign, -);
f32_op!(Mul, mul, MulAssign, mul_assign, *);
f32_op!(Div, div, DivAssign, div_assign, /);

impl Neg for F32x16 {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        self.map(|v| -v)
    }
}

impl Neg for Vec3x16 {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Self { x: -self.x, y: -self.y, z: -self.z }
    }
}

impl Add for U32x16 {
    type Output = Self;
    /// Wrapping.
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Self(each!(0, |l| self.0[l].wrapping_add(o.0[l])))
    }
}

macro_rules! bit_op {
    ($t:ident, $trait:ident, $f:ident, $op:tt) => {
        impl $trait for $t {
            type Output = Self;
            #[inline(always)]
            fn $f(self, o: Self) -> Self {
                Self(each!(0, |l| self.0[l] $op o.0[l]))
            }
        }
    };
}
bit_op!(U32x16, BitAnd, bitand, &);
bit_op!(U32x16, BitOr, bitor, |);
bit_op!(Mask16, BitAnd, bitand, &);
bit_op!(Mask16, BitOr, bitor, |);

impl Not for Mask16 {
    type Output = Self;
    #[inline(always)]
    fn not(self) -> Self {
        Self(each!(0, |l| !self.0[l]))
    }
}

impl std::ops::BitAndAssign for Mask16 {
    #[inline(always)]
    fn bitand_assign(&mut self, o: Self) {
        *self = *self & o;
    }
}

/// Lane `l`, for code that steps through lanes one at a time.
impl std::ops::Index<usize> for F32x16 {
    type Output = f32;
    #[inline(always)]
    fn index(&self, l: usize) -> &f32 {
        &self.0[l]
    }
}

impl std::ops::IndexMut<usize> for F32x16 {
    #[inline(always)]
    fn index_mut(&mut self, l: usize) -> &mut f32 {
        &mut self.0[l]
    }
}

/// Axis `a` (0, 1, 2 for x, y, z): `v[a][l]` is lane `l`'s component `a`.
impl std::ops::Index<usize> for Vec3x16 {
    type Output = F32x16;
    #[inline(always)]
    fn index(&self, a: usize) -> &F32x16 {
        &self.as_array()[a]
    }
}

impl std::ops::IndexMut<usize> for Vec3x16 {
    #[inline(always)]
    fn index_mut(&mut self, a: usize) -> &mut F32x16 {
        &mut self.as_array_mut()[a]
    }
}

impl From<[[f32; LANES]; 3]> for Vec3x16 {
    #[inline(always)]
    fn from([x, y, z]: [[f32; LANES]; 3]) -> Self {
        Self { x: F32x16(x), y: F32x16(y), z: F32x16(z) }
    }
}

#[cfg(test)]
mod tests;
