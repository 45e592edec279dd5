//! The vector operations the fast kernels are written in, once for AVX-512 and once for AVX2.
//!
//! Every function is `#[inline(always)]` and `unsafe`: it may only run inside a function
//! compiled for its instruction set (`#[target_feature]`), where it inlines into plain
//! instructions. Pointers must be valid for the lanes read or written.
//!
//! Besides the native vector `V`, each set has a 16-lane group `G` (one AVX-512 register, two
//! AVX2 registers) for dot products: lane `l` of a group sums the elements `l, l + 16, ...`, and
//! [`Isa::group_sum`] adds the 16 lanes in one fixed tree, so that both sets give the same bits.

pub(crate) trait Isa: Copy + 'static {
    /// A native vector of `LANES` f32.
    type V: Copy;
    const LANES: usize;
    /// 16 f32 partial sums of a dot product.
    type G: Copy;

    unsafe fn zero() -> Self::V;
    unsafe fn splat(x: f32) -> Self::V;
    unsafe fn load(p: *const f32) -> Self::V;
    /// The first `n < LANES` lanes from `p`, the others 0 (nothing past them is read).
    unsafe fn load_first(p: *const f32, n: usize) -> Self::V;
    /// Transpose the `LANES x LANES` block in `rows[..LANES]`: afterwards `rows[c]` holds what
    /// was column `c`.
    unsafe fn transpose(rows: &mut [Self::V; 16]);
    unsafe fn store(p: *mut f32, v: Self::V);
    /// The first `n < LANES` lanes to `p` (nothing past them is written).
    unsafe fn store_first(p: *mut f32, v: Self::V, n: usize);
    /// `a * b + c`, rounded once.
    unsafe fn fma(a: Self::V, b: Self::V, c: Self::V) -> Self::V;
    unsafe fn add(a: Self::V, b: Self::V) -> Self::V;
    /// `max(0, v)` as `torch.relu` computes it: NaN and -0.0 pass through.
    unsafe fn relu(v: Self::V) -> Self::V;
    /// `g` where `h > 0` or `h` is NaN, else 0: the ReLU's derivative applied to a gradient,
    /// as `if h <= 0 { 0 } else { g }`.
    unsafe fn mask_by(g: Self::V, h: Self::V) -> Self::V;

    unsafe fn group_zero() -> Self::G;
    unsafe fn group_load(p: *const f32) -> Self::G;
    /// The first `n < 16` values, the other lanes 0.
    unsafe fn group_load_first(p: *const f32, n: usize) -> Self::G;
    unsafe fn group_fma(a: Self::G, b: Self::G, c: Self::G) -> Self::G;
    /// `((s[i] + s[i + 8]) + (s[i + 4] + ...))`: lanes `i` and `i + 8` first, then `i` and
    /// `i + 4` of those 8, then `i` and `i + 2`, then the last two.
    unsafe fn group_sum(g: Self::G) -> f32;
}
