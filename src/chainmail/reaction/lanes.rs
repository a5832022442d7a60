//! Sixteen lanes of `u32` or `f32` as the vector chunk paths see them: one register with AVX-512
//! (comparisons give mask registers, read as bits directly), two with AVX2 (comparisons give lane
//! masks, read as bits by `movemask`). Both do the same comparisons and selects, which are exact, so
//! the chunk paths give the same results at either width.

use pulp::Simd;
use pulp::x86::{V3, V4};
use pulp::{f32x8, f32x16, m32x8, u32x8, u32x16};

/// The operations the chunk paths use on sixteen lanes. The vector types are plain bits
/// (`bytemuck::Pod`), so arrays of sixteen cast to and from them.
pub(super) trait Lanes: Copy {
    /// Sixteen `u32`.
    type U: bytemuck::Pod;
    /// Sixteen `f32`.
    type F: bytemuck::Pod;
    /// A mask of sixteen lanes.
    type M: Copy;

    fn splat(self, x: u32) -> Self::U;
    fn add(self, a: Self::U, b: Self::U) -> Self::U;
    fn sub(self, a: Self::U, b: Self::U) -> Self::U;
    /// Bit `i` set where lane `i` of `a` equals that of `b`.
    fn equal_bits(self, a: Self::U, b: Self::U) -> u16;
    fn sub_f(self, a: Self::F, b: Self::F) -> Self::F;
    fn less(self, a: Self::F, b: Self::F) -> Self::M;
    fn greater(self, a: Self::F, b: Self::F) -> Self::M;
    /// Bit `i` set where lane `i` of `a` equals that of `b`.
    fn equal_f_bits(self, a: Self::F, b: Self::F) -> u16;
    /// The mask of the lanes whose bits are set.
    fn mask(self, bits: u16) -> Self::M;
    fn select(self, m: Self::M, a: Self::F, b: Self::F) -> Self::F;
    fn select_u(self, m: Self::M, a: Self::U, b: Self::U) -> Self::U;
}

impl Lanes for V4 {
    type U = u32x16;
    type F = f32x16;
    type M = pulp::b16;

    #[inline(always)]
    fn splat(self, x: u32) -> u32x16 {
        self.splat_u32s(x)
    }
    #[inline(always)]
    fn add(self, a: u32x16, b: u32x16) -> u32x16 {
        self.add_u32s(a, b)
    }
    #[inline(always)]
    fn sub(self, a: u32x16, b: u32x16) -> u32x16 {
        self.sub_u32s(a, b)
    }
    #[inline(always)]
    fn equal_bits(self, a: u32x16, b: u32x16) -> u16 {
        self.equal_u32s(a, b).0
    }
    #[inline(always)]
    fn sub_f(self, a: f32x16, b: f32x16) -> f32x16 {
        self.sub_f32s(a, b)
    }
    #[inline(always)]
    fn less(self, a: f32x16, b: f32x16) -> pulp::b16 {
        self.cmp_lt_f32x16(a, b)
    }
    #[inline(always)]
    fn greater(self, a: f32x16, b: f32x16) -> pulp::b16 {
        self.cmp_gt_f32x16(a, b)
    }
    #[inline(always)]
    fn equal_f_bits(self, a: f32x16, b: f32x16) -> u16 {
        self.cmp_eq_f32x16(a, b).0
    }
    #[inline(always)]
    fn mask(self, bits: u16) -> pulp::b16 {
        pulp::b16(bits)
    }
    #[inline(always)]
    fn select(self, m: pulp::b16, a: f32x16, b: f32x16) -> f32x16 {
        self.select_f32x16(m, a, b)
    }
    #[inline(always)]
    fn select_u(self, m: pulp::b16, a: u32x16, b: u32x16) -> u32x16 {
        self.select_u32s(m, a, b)
    }
}

/// The bit of each lane of a half, for turning bits into lane masks.
const BITS: u32x8 = u32x8(1, 2, 4, 8, 16, 32, 64, 128);

/// Eight lane masks as eight bits.
#[inline(always)]
fn bits8(v: V3, m: m32x8) -> u16 {
    (v.avx._mm256_movemask_ps(pulp::cast(m)) as u32 & 0xff) as u16
}

impl Lanes for V3 {
    type U = [u32x8; 2];
    type F = [f32x8; 2];
    type M = [m32x8; 2];

    #[inline(always)]
    fn splat(self, x: u32) -> [u32x8; 2] {
        [self.splat_u32s(x); 2]
    }
    #[inline(always)]
    fn add(self, a: [u32x8; 2], b: [u32x8; 2]) -> [u32x8; 2] {
        [self.add_u32s(a[0], b[0]), self.add_u32s(a[1], b[1])]
    }
    #[inline(always)]
    fn sub(self, a: [u32x8; 2], b: [u32x8; 2]) -> [u32x8; 2] {
        [self.sub_u32s(a[0], b[0]), self.sub_u32s(a[1], b[1])]
    }
    #[inline(always)]
    fn equal_bits(self, a: [u32x8; 2], b: [u32x8; 2]) -> u16 {
        bits8(self, self.equal_u32s(a[0], b[0])) | bits8(self, self.equal_u32s(a[1], b[1])) << 8
    }
    #[inline(always)]
    fn sub_f(self, a: [f32x8; 2], b: [f32x8; 2]) -> [f32x8; 2] {
        [self.sub_f32s(a[0], b[0]), self.sub_f32s(a[1], b[1])]
    }
    #[inline(always)]
    fn less(self, a: [f32x8; 2], b: [f32x8; 2]) -> [m32x8; 2] {
        [self.less_than_f32s(a[0], b[0]), self.less_than_f32s(a[1], b[1])]
    }
    #[inline(always)]
    fn greater(self, a: [f32x8; 2], b: [f32x8; 2]) -> [m32x8; 2] {
        [self.greater_than_f32s(a[0], b[0]), self.greater_than_f32s(a[1], b[1])]
    }
    #[inline(always)]
    fn equal_f_bits(self, a: [f32x8; 2], b: [f32x8; 2]) -> u16 {
        bits8(self, self.equal_f32s(a[0], b[0])) | bits8(self, self.equal_f32s(a[1], b[1])) << 8
    }
    #[inline(always)]
    fn mask(self, bits: u16) -> [m32x8; 2] {
        let half = |b: u16| self.equal_u32s(self.and_u32s(self.splat_u32s(u32::from(b)), BITS), BITS);
        [half(bits & 0xff), half(bits >> 8)]
    }
    #[inline(always)]
    fn select(self, m: [m32x8; 2], a: [f32x8; 2], b: [f32x8; 2]) -> [f32x8; 2] {
        [self.select_f32s(m[0], a[0], b[0]), self.select_f32s(m[1], a[1], b[1])]
    }
    #[inline(always)]
    fn select_u(self, m: [m32x8; 2], a: [u32x8; 2], b: [u32x8; 2]) -> [u32x8; 2] {
        [self.select_u32s(m[0], a[0], b[0]), self.select_u32s(m[1], a[1], b[1])]
    }
}
