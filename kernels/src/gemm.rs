//! One team member's share of a product `C (m x n) = A (m x k) B (k x n)` around [`tile`]:
//!
//! 1. `A` is packed into row tiles of `MR` rows, one `MR`-float row per `kk`, 64-byte
//!    aligned (each member packs a share, then they meet at the barrier): the tile loop then
//!    streams it in order, whatever `A`'s layout was;
//! 2. the member's tiles are visited in blocks of row tiles that stay in L2, each `k x NR`
//!    slice of `B` staying in L1 while the block's tiles use it. A `B` read along its rows
//!    (`k`-stride above `NR`) is first copied into a contiguous slice, or its rows would
//!    scatter over more cache lines than L1 holds.

use crate::cache::l2_bytes;
use crate::isa::Isa;
use crate::scratch::b_scratch;
use crate::team::Part;
use crate::tile::{Epilogue, TileArgs, tile};

/// Where `A[i, kk]` is.
#[derive(Clone, Copy)]
pub(crate) enum ASource {
    /// At `ptr + i + kk * ld` (column-major).
    Columns { ptr: *const f32, ld: usize },
    /// At `ptr + i * ld + kk` (row-major: a weight read as `W`).
    Rows { ptr: *const f32, ld: usize },
}

/// A product's operands. `B[kk, j]` is at `b + kk * b_ks + j * b_js` with one of the strides
/// 1 (`b_cols`: `b_ks == 1`); `C[i, j]` at `c + i + j * c_js`.
#[derive(Clone, Copy)]
pub(crate) struct Product {
    pub m: usize,
    pub n: usize,
    pub k: usize,
    pub a: ASource,
    /// Room for `A` packed: [`packed_len`] floats, shared by the team.
    pub a_pack: *mut f32,
    pub b: *const f32,
    pub b_ks: usize,
    pub b_js: usize,
    pub b_cols: bool,
    pub c: *mut f32,
    pub c_js: usize,
    /// 1, or `C` row-major (a transposed product): see [`TileArgs::c_is`].
    pub c_is: usize,
    pub epilogue: Epilogue,
}

/// Steps of `k` per turn of a packed tile's loop. Four ran Lunar Lander's 400:300 products
/// 2-7 % faster than one on an Intel Xeon with AVX-512 (`docs/results/speed`); two made the
/// compiler store every accumulator at every step. A tile read in place keeps one: its
/// twelve-column tile (a first layer's weight gradient) ran slower unrolled.
const UNROLL: usize = 4;

/// The widest row tile of any instruction set: 4 x 16 rows.
pub(crate) const MAX_MR: usize = 64;

/// Floats a packed `A` of `m x k` may take: `m` rounded up to any tile height.
pub(crate) fn packed_len(m: usize, k: usize) -> usize {
    (m + MAX_MR) * k
}

/// Pack `A`, then compute this member's tiles: whole columns of `C` in `NR`-wide chunks when
/// there are at least as many column tiles as row tiles, else whole rows. A `C` of at most
/// `WNR` columns uses each row of `A` once, so a column-major `A` is read in place instead, by
/// tiles of `WMV` vectors by `WNR` columns (a first layer's weight gradient), or of `NMV`
/// vectors by 4 columns when `C` has at most 4 (a head's weight gradient).
///
/// # Safety
/// The operands hold their shapes, `C` is writable and aliases neither `A` nor `B`, and the
/// caller is compiled for `I`'s instruction set.
#[inline(always)]
pub(crate) unsafe fn product<
    I: Isa,
    const MV: usize,
    const NR: usize,
    const NMV: usize,
    const WMV: usize,
    const WNR: usize,
>(
    part: &Part<'_>,
    p: &Product,
) {
    if let ASource::Columns { .. } = p.a {
        // One column (a critic output's weight gradient): 4 columns would compute it 4 times.
        if p.n == 1 {
            return unsafe { in_place::<I, NMV, 1>(part, p) };
        }
        if p.n <= 4 {
            return unsafe { in_place::<I, NMV, 4>(part, p) };
        }
        if p.n <= WNR {
            return unsafe { in_place::<I, WMV, WNR>(part, p) };
        }
    }
    let mr = MV * I::LANES;
    let row_tiles = p.m.div_ceil(mr);
    for t in part.share(row_tiles, 1) {
        unsafe { pack_a::<I, MV>(p, t) };
    }
    part.barrier();
    let (rows, cols) = if p.n.div_ceil(NR) >= row_tiles {
        (0..p.m, part.share(p.n, NR))
    } else {
        (part.share(p.m, mr), 0..p.n)
    };
    // Row tiles whose packed A takes half of L2 at most.
    let block = (l2_bytes() / 2 / (4 * mr * p.k.max(1))).max(1) * mr;
    let b_panel = if p.b_cols {
        std::ptr::null_mut()
    } else {
        // Each row is written as one full vector: room for the last one's overhang.
        b_scratch(p.k * NR + I::LANES)
    };
    let mut i_block = rows.start;
    while i_block < rows.end {
        let i_end = (i_block + block).min(rows.end);
        let mut j = cols.start;
        while j < cols.end {
            let width = NR.min(cols.end - j);
            let (b, b_ks, b_js) = if p.b_cols {
                (unsafe { p.b.add(j * p.b_js) }, p.b_ks, p.b_js)
            } else {
                unsafe { pack_b_rows::<I, NR>(p, j, width, b_panel) };
                (b_panel as *const f32, NR, 1)
            };
            let mut i = i_block;
            while i < i_end {
                let height = mr.min(i_end - i);
                let args = TileArgs {
                    k: p.k,
                    a: unsafe { p.a_pack.add(i * p.k) },
                    a_ks: mr,
                    rows: height,
                    b,
                    b_ks,
                    b_js,
                    cols: width,
                    c: unsafe { p.c.add(i * p.c_is + j * p.c_js) },
                    c_js: p.c_js,
                    c_is: p.c_is,
                };
                let epilogue = unsafe { p.epilogue.at(i, i + j * p.c_js) };
                // Chains of fewer than 16 steps (a first layer's forward, `k` = 10) step by step:
                // the leftover steps of an unrolled loop would cost more than the loop saves.
                unsafe {
                    if p.k >= 16 {
                        packed_tile::<I, MV, NR, UNROLL>(p.b_cols, &args, epilogue)
                    } else {
                        packed_tile::<I, MV, NR, 1>(p.b_cols, &args, epilogue)
                    }
                }
                i += mr;
            }
            j += NR;
        }
        i_block = i_end;
    }
}

/// One tile of a packed row tile of `A`, `U` steps of `k` per turn. The last row tile may be
/// short: as few vectors as its rows need (a 300-row layer is six 48-row tiles and one of 12
/// rows on AVX-512).
#[inline(always)]
unsafe fn packed_tile<I: Isa, const MV: usize, const NR: usize, const U: usize>(
    b_cols: bool,
    args: &TileArgs,
    epilogue: Epilogue,
) {
    let height = args.rows;
    let two = MV > 2 && height > I::LANES && height <= 2 * I::LANES;
    unsafe {
        match (b_cols, height <= I::LANES) {
            (true, _) if two => tile::<I, 2, NR, true, true, U>(args, epilogue),
            (false, _) if two => tile::<I, 2, NR, false, true, U>(args, epilogue),
            (true, false) => tile::<I, MV, NR, true, true, U>(args, epilogue),
            (false, false) => tile::<I, MV, NR, false, true, U>(args, epilogue),
            (true, true) => tile::<I, 1, NR, true, true, U>(args, epilogue),
            (false, true) => tile::<I, 1, NR, false, true, U>(args, epilogue),
        }
    }
}

/// [`product`] for `n <= NR` (here the in-place tile's width): members share out rows; `A` (column-major) is read in place.
#[inline(always)]
unsafe fn in_place<I: Isa, const MV: usize, const NR: usize>(part: &Part<'_>, p: &Product) {
    let ASource::Columns { ptr: a, ld } = p.a else {
        unreachable!("only a column-major A is read in place")
    };
    let mr = MV * I::LANES;
    let rows = part.share(p.m, mr);
    let mut i = rows.start;
    while i < rows.end {
        let height = mr.min(rows.end - i);
        let args = TileArgs {
            k: p.k,
            a: unsafe { a.add(i) },
            a_ks: ld,
            rows: height,
            b: p.b,
            b_ks: p.b_ks,
            b_js: p.b_js,
            cols: p.n,
            c: unsafe { p.c.add(i * p.c_is) },
            c_js: p.c_js,
            c_is: p.c_is,
        };
        let epilogue = unsafe { p.epilogue.at(i, i) };
        unsafe {
            match (p.b_cols, height == mr) {
                (true, true) => tile::<I, MV, NR, true, true, 1>(&args, epilogue),
                (false, true) => tile::<I, MV, NR, false, true, 1>(&args, epilogue),
                (true, false) => tile::<I, MV, NR, true, false, 1>(&args, epilogue),
                (false, false) => tile::<I, MV, NR, false, false, 1>(&args, epilogue),
            }
        }
        i += mr;
    }
}

/// Row tile `t` of `A` into `a_pack + t * MR * k`: for each `kk`, the tile's `MR` rows, those
/// past `m` as zeros.
#[inline(always)]
unsafe fn pack_a<I: Isa, const MV: usize>(p: &Product, t: usize) {
    let lanes = I::LANES;
    let mr = MV * lanes;
    let first_row = t * mr;
    let panel = unsafe { p.a_pack.add(first_row * p.k) };
    let mut valid = [lanes; MV];
    for (v, n) in valid.iter_mut().enumerate() {
        *n = p.m.saturating_sub(first_row + v * lanes).min(lanes);
    }
    match p.a {
        ASource::Columns { ptr, ld } => {
            for kk in 0..p.k {
                let out = unsafe { panel.add(kk * mr) };
                for (v, &n) in valid.iter().enumerate() {
                    let src = unsafe { ptr.add(first_row + v * lanes + kk * ld) };
                    let x = unsafe {
                        match n {
                            0 => I::zero(),
                            n if n == lanes => I::load(src),
                            n => I::load_first(src, n),
                        }
                    };
                    unsafe { I::store(out.add(v * lanes), x) };
                }
            }
        }
        // Rows of A are contiguous: read blocks of LANES rows x LANES columns along the rows
        // (in order, as the prefetchers like) and transpose them in registers.
        ASource::Rows { ptr, ld } => {
            let mut kk = 0;
            while kk < p.k {
                let width = lanes.min(p.k - kk);
                for (v, &n) in valid.iter().enumerate() {
                    let mut block = [unsafe { I::zero() }; 16];
                    for (r, row) in block.iter_mut().enumerate().take(n) {
                        let src = unsafe { ptr.add((first_row + v * lanes + r) * ld + kk) };
                        *row = unsafe {
                            if width == lanes {
                                I::load(src)
                            } else {
                                I::load_first(src, width)
                            }
                        };
                    }
                    unsafe { I::transpose(&mut block) };
                    for (c, column) in block.iter().enumerate().take(width) {
                        unsafe { I::store(panel.add((kk + c) * mr + v * lanes), *column) };
                    }
                }
                kk += lanes;
            }
        }
    }
}

/// Columns `j..j + width` of a `B` read along its rows into `panel`, `NR` floats per `kk`
/// (columns past `width` hold zeros or the next row's start; their results are not stored).
#[inline(always)]
unsafe fn pack_b_rows<I: Isa, const NR: usize>(
    p: &Product,
    j: usize,
    width: usize,
    panel: *mut f32,
) {
    let lanes = I::LANES;
    for kk in 0..p.k {
        let src = unsafe { p.b.add(kk * p.b_ks + j) };
        let dst = unsafe { panel.add(kk * NR) };
        let mut done = 0;
        while done < NR {
            let n = (width.saturating_sub(done)).min(lanes);
            unsafe {
                let x = match n {
                    0 => I::zero(),
                    n if n == lanes => I::load(src.add(done)),
                    n => I::load_first(src.add(done), n),
                };
                I::store(dst.add(done), x);
            }
            done += lanes;
        }
    }
}
