//! [`Isa`] for AVX2 + FMA: 8 lanes per register, 16 x 6 output tiles (12 accumulators of the
//! 16 registers). A 16-lane dot-product group is two registers.

use std::arch::x86_64::*;

use crate::isa::Isa;
use crate::layers::{self, BackwardJob, ForwardJob, InputGradJob};
use crate::team::Part;

#[derive(Clone, Copy)]
pub(crate) struct Avx2;

/// Rows of an output tile in registers: two vectors.
const MV: usize = 2;
/// Rows (in vectors) of a tile of at most 4 columns.
const NMV: usize = 2;
/// Columns of an output tile.
const NR: usize = 6;
/// The tile of a product of at most `WNR` columns, whose column-major `A` is read in place
/// rather than packed: the main tile.
const WMV: usize = 2;
const WNR: usize = 6;

/// All-ones in the first `n` of 8 lanes.
#[inline(always)]
unsafe fn first(n: usize) -> __m256i {
    unsafe {
        _mm256_cmpgt_epi32(
            _mm256_set1_epi32(n as i32),
            _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7),
        )
    }
}

/// The 8 lanes of `s` added in the tree [`Isa::group_sum`] describes: `i + 4`, `i + 2`, `i + 1`.
#[inline(always)]
pub(crate) unsafe fn sum8(s: __m256) -> f32 {
    unsafe {
        let s4 = _mm_add_ps(_mm256_castps256_ps128(s), _mm256_extractf128_ps::<1>(s));
        let s2 = _mm_add_ps(s4, _mm_movehl_ps(s4, s4));
        let s1 = _mm_add_ss(s2, _mm_shuffle_ps::<0b01>(s2, s2));
        _mm_cvtss_f32(s1)
    }
}

impl Isa for Avx2 {
    type V = __m256;
    const LANES: usize = 8;
    type G = [__m256; 2];

    #[inline(always)]
    unsafe fn zero() -> __m256 {
        unsafe { _mm256_setzero_ps() }
    }
    #[inline(always)]
    unsafe fn splat(x: f32) -> __m256 {
        unsafe { _mm256_set1_ps(x) }
    }
    #[inline(always)]
    unsafe fn load(p: *const f32) -> __m256 {
        unsafe { _mm256_loadu_ps(p) }
    }
    #[inline(always)]
    unsafe fn load_first(p: *const f32, n: usize) -> __m256 {
        unsafe { _mm256_maskload_ps(p, first(n)) }
    }
    #[inline(always)]
    unsafe fn transpose(r: &mut [__m256; 16]) {
        unsafe {
            // 32-bit, then 64-bit interleaves: u[4g + c], 128-bit lane l, holds column 4l + c
            // of rows 4g..4g + 4; then the two lanes are exchanged.
            let mut t = [_mm256_setzero_ps(); 8];
            for i in 0..4 {
                t[2 * i] = _mm256_unpacklo_ps(r[2 * i], r[2 * i + 1]);
                t[2 * i + 1] = _mm256_unpackhi_ps(r[2 * i], r[2 * i + 1]);
            }
            let mut u = [_mm256_setzero_ps(); 8];
            for g in 0..2 {
                let pd = |x: __m256| _mm256_castps_pd(x);
                let (t0, t1, t2, t3) = (
                    pd(t[4 * g]),
                    pd(t[4 * g + 1]),
                    pd(t[4 * g + 2]),
                    pd(t[4 * g + 3]),
                );
                u[4 * g] = _mm256_castpd_ps(_mm256_unpacklo_pd(t0, t2));
                u[4 * g + 1] = _mm256_castpd_ps(_mm256_unpackhi_pd(t0, t2));
                u[4 * g + 2] = _mm256_castpd_ps(_mm256_unpacklo_pd(t1, t3));
                u[4 * g + 3] = _mm256_castpd_ps(_mm256_unpackhi_pd(t1, t3));
            }
            for c in 0..4 {
                r[c] = _mm256_permute2f128_ps::<0x20>(u[c], u[4 + c]);
                r[4 + c] = _mm256_permute2f128_ps::<0x31>(u[c], u[4 + c]);
            }
        }
    }
    #[inline(always)]
    unsafe fn store(p: *mut f32, v: __m256) {
        unsafe { _mm256_storeu_ps(p, v) }
    }
    #[inline(always)]
    unsafe fn store_first(p: *mut f32, v: __m256, n: usize) {
        unsafe { _mm256_maskstore_ps(p, first(n), v) }
    }
    #[inline(always)]
    unsafe fn fma(a: __m256, b: __m256, c: __m256) -> __m256 {
        unsafe { _mm256_fmadd_ps(a, b, c) }
    }
    #[inline(always)]
    unsafe fn add(a: __m256, b: __m256) -> __m256 {
        unsafe { _mm256_add_ps(a, b) }
    }
    #[inline(always)]
    unsafe fn relu(v: __m256) -> __m256 {
        unsafe {
            // MAX returns its second operand when they are unordered or both zero.
            _mm256_max_ps(_mm256_setzero_ps(), v)
        }
    }
    #[inline(always)]
    unsafe fn mask_by(g: __m256, h: __m256) -> __m256 {
        unsafe {
            let not_positive = _mm256_cmp_ps::<_CMP_LE_OQ>(h, _mm256_setzero_ps());
            _mm256_andnot_ps(not_positive, g)
        }
    }

    #[inline(always)]
    unsafe fn group_zero() -> [__m256; 2] {
        unsafe { [_mm256_setzero_ps(); 2] }
    }
    #[inline(always)]
    unsafe fn group_load(p: *const f32) -> [__m256; 2] {
        unsafe { [_mm256_loadu_ps(p), _mm256_loadu_ps(p.add(8))] }
    }
    #[inline(always)]
    unsafe fn group_load_first(p: *const f32, n: usize) -> [__m256; 2] {
        unsafe {
            if n > 8 {
                [_mm256_loadu_ps(p), Self::load_first(p.add(8), n - 8)]
            } else if n == 8 {
                [_mm256_loadu_ps(p), _mm256_setzero_ps()]
            } else {
                [Self::load_first(p, n), _mm256_setzero_ps()]
            }
        }
    }
    #[inline(always)]
    unsafe fn group_fma(a: [__m256; 2], b: [__m256; 2], c: [__m256; 2]) -> [__m256; 2] {
        unsafe {
            [
                _mm256_fmadd_ps(a[0], b[0], c[0]),
                _mm256_fmadd_ps(a[1], b[1], c[1]),
            ]
        }
    }
    #[inline(always)]
    unsafe fn group_sum(g: [__m256; 2]) -> f32 {
        unsafe { sum8(_mm256_add_ps(g[0], g[1])) }
    }
}

#[target_feature(enable = "avx2,fma")]
pub(crate) unsafe fn forward_part(part: &Part<'_>, job: &ForwardJob<'_>) {
    unsafe { layers::forward_part::<Avx2, MV, NR, NMV, WMV, WNR>(part, job) }
}

#[target_feature(enable = "avx2,fma")]
pub(crate) unsafe fn weight_grad_part(part: &Part<'_>, job: &BackwardJob<'_>) {
    unsafe { layers::weight_grad_part::<Avx2, MV, NR, NMV, WMV, WNR>(part, job) }
}

#[target_feature(enable = "avx2,fma")]
pub(crate) unsafe fn input_grad_part(part: &Part<'_>, job: &InputGradJob<'_>) {
    unsafe { layers::input_grad_part::<Avx2, MV, NR, NMV, WMV, WNR>(part, job) }
}
