//! [`Isa`] for AVX-512F: 16 lanes per register, 48 x 8 output tiles (24 accumulators of
//! the 32 registers). Three vectors by eight columns take 11 loads per 24 FMAs where 32 x 12
//! took 14. On an Intel Xeon (Sapphire Rapids class) they ran Lunar Lander's 400:300 products
//! 3-10 % faster than 32 x 12 in interleaved runs, though the whole update moved by less than
//! that machine's noise (`docs/results/speed`). The tile's shape changes no bit (`tile.rs`).

use std::arch::x86_64::*;

use crate::isa::Isa;
use crate::layers::{self, BackwardJob, ForwardJob, InputGradJob};
use crate::team::Part;

#[derive(Clone, Copy)]
pub(crate) struct Avx512;

/// Rows of an output tile in registers: three vectors.
const MV: usize = 3;
/// Rows (in vectors) of a tile of at most 4 columns.
const NMV: usize = 4;
/// Columns of an output tile.
const NR: usize = 8;
/// The tile of a product of at most `WNR` columns, whose column-major `A` is read in place
/// rather than packed: `WMV` vectors by `WNR` columns. Two vectors by twelve columns keep
/// a first layer's weight gradient (ten columns) in one tile, where eight columns took two
/// and a packed copy of `A`.
const WMV: usize = 2;
const WNR: usize = 12;

#[inline(always)]
fn first(n: usize) -> __mmask16 {
    ((1u32 << n) - 1) as __mmask16
}

impl Isa for Avx512 {
    type V = __m512;
    const LANES: usize = 16;
    type G = __m512;

    #[inline(always)]
    unsafe fn zero() -> __m512 {
        unsafe { _mm512_setzero_ps() }
    }
    #[inline(always)]
    unsafe fn splat(x: f32) -> __m512 {
        unsafe { _mm512_set1_ps(x) }
    }
    #[inline(always)]
    unsafe fn load(p: *const f32) -> __m512 {
        unsafe { _mm512_loadu_ps(p) }
    }
    #[inline(always)]
    unsafe fn load_first(p: *const f32, n: usize) -> __m512 {
        unsafe { _mm512_maskz_loadu_ps(first(n), p) }
    }
    #[inline(always)]
    unsafe fn transpose(r: &mut [__m512; 16]) {
        unsafe {
            // 32-bit, then 64-bit interleaves: u[4g + c], 128-bit lane l, holds column 4l + c
            // of rows 4g..4g + 4.
            let mut t = [_mm512_setzero_ps(); 16];
            for i in 0..8 {
                t[2 * i] = _mm512_unpacklo_ps(r[2 * i], r[2 * i + 1]);
                t[2 * i + 1] = _mm512_unpackhi_ps(r[2 * i], r[2 * i + 1]);
            }
            let mut u = [_mm512_setzero_ps(); 16];
            for g in 0..4 {
                let pd = |x: __m512| _mm512_castps_pd(x);
                let (t0, t1, t2, t3) = (
                    pd(t[4 * g]),
                    pd(t[4 * g + 1]),
                    pd(t[4 * g + 2]),
                    pd(t[4 * g + 3]),
                );
                u[4 * g] = _mm512_castpd_ps(_mm512_unpacklo_pd(t0, t2));
                u[4 * g + 1] = _mm512_castpd_ps(_mm512_unpackhi_pd(t0, t2));
                u[4 * g + 2] = _mm512_castpd_ps(_mm512_unpacklo_pd(t1, t3));
                u[4 * g + 3] = _mm512_castpd_ps(_mm512_unpackhi_pd(t1, t3));
            }
            // Then a 4 x 4 transpose of 128-bit lanes for each c.
            for c in 0..4 {
                let v0 = _mm512_shuffle_f32x4::<0x44>(u[c], u[4 + c]);
                let v1 = _mm512_shuffle_f32x4::<0xee>(u[c], u[4 + c]);
                let v2 = _mm512_shuffle_f32x4::<0x44>(u[8 + c], u[12 + c]);
                let v3 = _mm512_shuffle_f32x4::<0xee>(u[8 + c], u[12 + c]);
                r[c] = _mm512_shuffle_f32x4::<0x88>(v0, v2);
                r[4 + c] = _mm512_shuffle_f32x4::<0xdd>(v0, v2);
                r[8 + c] = _mm512_shuffle_f32x4::<0x88>(v1, v3);
                r[12 + c] = _mm512_shuffle_f32x4::<0xdd>(v1, v3);
            }
        }
    }
    #[inline(always)]
    unsafe fn store(p: *mut f32, v: __m512) {
        unsafe { _mm512_storeu_ps(p, v) }
    }
    #[inline(always)]
    unsafe fn store_first(p: *mut f32, v: __m512, n: usize) {
        unsafe { _mm512_mask_storeu_ps(p, first(n), v) }
    }
    #[inline(always)]
    unsafe fn fma(a: __m512, b: __m512, c: __m512) -> __m512 {
        unsafe { _mm512_fmadd_ps(a, b, c) }
    }
    #[inline(always)]
    unsafe fn add(a: __m512, b: __m512) -> __m512 {
        unsafe { _mm512_add_ps(a, b) }
    }
    #[inline(always)]
    unsafe fn relu(v: __m512) -> __m512 {
        unsafe {
            // MAX returns its second operand when they are unordered or both zero.
            _mm512_max_ps(_mm512_setzero_ps(), v)
        }
    }
    #[inline(always)]
    unsafe fn mask_by(g: __m512, h: __m512) -> __m512 {
        unsafe {
            let not_positive = _mm512_cmp_ps_mask::<_CMP_LE_OQ>(h, _mm512_setzero_ps());
            _mm512_mask_blend_ps(not_positive, g, _mm512_setzero_ps())
        }
    }

    #[inline(always)]
    unsafe fn group_zero() -> __m512 {
        unsafe { _mm512_setzero_ps() }
    }
    #[inline(always)]
    unsafe fn group_load(p: *const f32) -> __m512 {
        unsafe { _mm512_loadu_ps(p) }
    }
    #[inline(always)]
    unsafe fn group_load_first(p: *const f32, n: usize) -> __m512 {
        unsafe { _mm512_maskz_loadu_ps(first(n), p) }
    }
    #[inline(always)]
    unsafe fn group_fma(a: __m512, b: __m512, c: __m512) -> __m512 {
        unsafe { _mm512_fmadd_ps(a, b, c) }
    }
    #[inline(always)]
    unsafe fn group_sum(g: __m512) -> f32 {
        unsafe {
            let lo = _mm512_castps512_ps256(g);
            let hi = _mm256_castpd_ps(_mm512_extractf64x4_pd::<1>(_mm512_castps_pd(g)));
            crate::avx2::sum8(_mm256_add_ps(lo, hi))
        }
    }
}

#[target_feature(enable = "avx512f,avx2,fma")]
pub(crate) unsafe fn forward_part(part: &Part<'_>, job: &ForwardJob<'_>) {
    unsafe { layers::forward_part::<Avx512, MV, NR, NMV, WMV, WNR>(part, job) }
}

#[target_feature(enable = "avx512f,avx2,fma")]
pub(crate) unsafe fn weight_grad_part(part: &Part<'_>, job: &BackwardJob<'_>) {
    unsafe { layers::weight_grad_part::<Avx512, MV, NR, NMV, WMV, WNR>(part, job) }
}

#[target_feature(enable = "avx512f,avx2,fma")]
pub(crate) unsafe fn input_grad_part(part: &Part<'_>, job: &InputGradJob<'_>) {
    unsafe { layers::input_grad_part::<Avx512, MV, NR, NMV, WMV, WNR>(part, job) }
}
