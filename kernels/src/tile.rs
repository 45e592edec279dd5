//! One output tile of a product: `rows x cols` elements of `C = A B` (at most `MV` vectors by
//! `NR` columns) held in registers over the whole of `k`, then finished by an [`Epilogue`] and
//! stored. Every element is one chain of fused multiply-adds over `k` in order, starting from
//! 0: the same operations whatever the tile's shape, the vector width or the thread.
//!
//! Layouts are column-major with unit row stride: `A[i, kk]` at `a + i + kk * a_ks` (a packed
//! row tile, `MV * LANES` rows of which those past `rows` are padding), `C[i, j]` at
//! `c + i + j * c_js`. `B[kk, j]` is at `b + kk * b_ks + j * b_js`, read one
//! scalar at a time and broadcast, so any strides serve; `B_COLS` says which one is 1 (a
//! column-major `B` read down its columns, or a row-major one along its rows).

use crate::isa::Isa;

/// Where a tile's operands are.
#[derive(Clone, Copy)]
pub(crate) struct TileArgs {
    pub k: usize,
    pub a: *const f32,
    pub a_ks: usize,
    /// Valid rows, `1..=MV * LANES`; rows past them are neither read nor written.
    pub rows: usize,
    pub b: *const f32,
    pub b_ks: usize,
    pub b_js: usize,
    /// Valid columns, `1..=NR`; the others repeat the last valid one and are not stored.
    pub cols: usize,
    pub c: *mut f32,
    pub c_js: usize,
    /// `C`'s row stride: 1, or (a transposed product writing a row-major `C`) anything, with
    /// the [`Epilogue::Accumulate`] or [`Epilogue::Store`] epilogue.
    pub c_is: usize,
}

/// What happens to the accumulated `acc` before it is stored in `C`.
#[derive(Clone, Copy)]
pub(crate) enum Epilogue {
    /// `C = acc + bias[i]` (no bias if null), then ReLU if asked: a layer's forward pass.
    Bias { bias: *const f32, relu: bool },
    /// `C = C + acc`: a gradient that accumulates.
    Accumulate,
    /// `C = acc` where `H[i, j] > 0` (or NaN), else 0, `H` laid out like `C`: an input
    /// gradient through the ReLU that made `H`.
    Mask { h: *const f32 },
    /// `C = acc`.
    Store,
}

impl Epilogue {
    /// This epilogue for a tile whose first row is `row` and first element of `C` is `element`
    /// floats into `C`: the bias moves with the row, the mask (laid out like `C`) with the
    /// element.
    ///
    /// # Safety
    /// The offsets stay inside the bias and the mask.
    #[inline(always)]
    pub(crate) unsafe fn at(self, row: usize, element: usize) -> Self {
        match self {
            Epilogue::Bias { bias, relu } if !bias.is_null() => Epilogue::Bias {
                bias: unsafe { bias.add(row) },
                relu,
            },
            Epilogue::Mask { h } => Epilogue::Mask {
                h: unsafe { h.add(element) },
            },
            other => other,
        }
    }
}

/// Compute and store one tile. `PADDED`: `A` has all `MV * LANES` rows readable (a packed
/// tile); else rows past `rows` are not read (`A` in place, its last tile). `UNROLL`: steps of
/// `k` per turn of the loop.
///
/// # Safety
/// The operands must be valid for the rows, columns and `k` given, `C` writable and aliasing
/// neither `A` nor `B`, and the caller compiled for `I`'s instruction set.
#[inline(always)]
pub(crate) unsafe fn tile<
    I: Isa,
    const MV: usize,
    const NR: usize,
    const B_COLS: bool,
    const PADDED: bool,
    const UNROLL: usize,
>(
    t: &TileArgs,
    epilogue: Epilogue,
) {
    let lanes = I::LANES;
    let acc = [[unsafe { I::zero() }; MV]; NR];
    // Column j's first element; columns past the valid ones read the last valid column.
    let mut b_col = [t.b; NR];
    for (j, p) in b_col.iter_mut().enumerate() {
        *p = unsafe { t.b.add(j.min(t.cols - 1) * t.b_js) };
    }
    // Rows valid in each vector of the tile.
    let mut valid = [lanes; MV];
    for (v, n) in valid.iter_mut().enumerate() {
        *n = t.rows.saturating_sub(v * lanes).min(lanes);
    }
    let acc = unsafe { chains::<I, MV, NR, B_COLS, PADDED, UNROLL>(t, acc, &b_col, &valid) };
    if t.c_is != 1 {
        // By value: a reference would let the accumulators escape, and the compiler would then
        // store every one of them at every step of `k`.
        return unsafe { store_strided::<I, MV, NR>(t, epilogue, acc, valid) };
    }
    // Constant loop bounds, so that the accumulators stay in registers.
    #[allow(clippy::needless_range_loop)]
    for j in 0..NR {
        if j >= t.cols {
            break;
        }
        let c = unsafe { t.c.add(j * t.c_js) };
        for v in 0..MV {
            let n = valid[v];
            if n == 0 {
                break;
            }
            let at = v * lanes;
            unsafe {
                let load = |p: *const f32| {
                    if n == lanes {
                        I::load(p)
                    } else {
                        I::load_first(p, n)
                    }
                };
                let sum = acc[j][v];
                let out = match epilogue {
                    Epilogue::Bias { bias, relu } => {
                        let z = if bias.is_null() {
                            sum
                        } else {
                            I::add(sum, load(bias.add(at)))
                        };
                        if relu { I::relu(z) } else { z }
                    }
                    Epilogue::Accumulate => I::add(load(c.add(at)), sum),
                    Epilogue::Mask { h } => I::mask_by(sum, load(h.add(j * t.c_js + at))),
                    Epilogue::Store => sum,
                };
                if n == lanes {
                    I::store(c.add(at), out);
                } else {
                    I::store_first(c.add(at), out, n);
                }
            }
        }
    }
}

/// All `k` steps of a tile's chains, `U` steps per turn of the loop (fewer branches and
/// pointer updates between the multiply-adds). The steps that do not fill a turn come first,
/// so that there is one loop, in which the compiler keeps every accumulator in a register.
#[inline(always)]
unsafe fn chains<
    I: Isa,
    const MV: usize,
    const NR: usize,
    const B_COLS: bool,
    const PADDED: bool,
    const U: usize,
>(
    t: &TileArgs,
    mut acc: [[I::V; MV]; NR],
    b_col: &[*const f32; NR],
    valid: &[usize; MV],
) -> [[I::V; MV]; NR] {
    let head = t.k % U;
    for u in 0..U - 1 {
        if u < head {
            acc = unsafe { step::<I, MV, NR, B_COLS, PADDED>(t, acc, b_col, valid, u) };
        }
    }
    let mut kk = head;
    while kk < t.k {
        for u in 0..U {
            acc = unsafe { step::<I, MV, NR, B_COLS, PADDED>(t, acc, b_col, valid, kk + u) };
        }
        kk += U;
    }
    acc
}

/// Step `kk` of a tile's chains: one row of `A`'s tile times one row of `B`'s.
#[inline(always)]
unsafe fn step<I: Isa, const MV: usize, const NR: usize, const B_COLS: bool, const PADDED: bool>(
    t: &TileArgs,
    mut acc: [[I::V; MV]; NR],
    b_col: &[*const f32; NR],
    valid: &[usize; MV],
    kk: usize,
) -> [[I::V; MV]; NR] {
    let lanes = I::LANES;
    let a = unsafe { t.a.add(kk * t.a_ks) };
    let mut av = [unsafe { I::zero() }; MV];
    for v in 0..MV {
        av[v] = unsafe {
            if PADDED || valid[v] == lanes {
                I::load(a.add(v * lanes))
            } else if valid[v] > 0 {
                I::load_first(a.add(v * lanes), valid[v])
            } else {
                I::zero()
            }
        };
    }
    for j in 0..NR {
        let x = unsafe {
            if B_COLS {
                *b_col[j].add(kk)
            } else {
                *t.b.add(kk * t.b_ks + j.min(t.cols - 1))
            }
        };
        let bj = unsafe { I::splat(x) };
        for v in 0..MV {
            acc[j][v] = unsafe { I::fma(av[v], bj, acc[j][v]) };
        }
    }
    acc
}

/// The epilogue for a `C` whose rows are not contiguous, element by element through the stack
/// (once per tile, after `k` steps of arithmetic): the same additions as the vector epilogue.
#[inline(never)]
unsafe fn store_strided<I: Isa, const MV: usize, const NR: usize>(
    t: &TileArgs,
    epilogue: Epilogue,
    acc: [[I::V; MV]; NR],
    valid: [usize; MV],
) {
    let lanes = I::LANES;
    let mut lane_values = [0.0f32; 64];
    assert!(MV * lanes <= lane_values.len(), "tile taller than 64 rows");
    for (j, column) in acc.iter().enumerate().take(t.cols) {
        for (v, &sum) in column.iter().enumerate() {
            unsafe { I::store(lane_values.as_mut_ptr().add(v * lanes), sum) };
        }
        for (v, &n) in valid.iter().enumerate() {
            for r in 0..n {
                let i = v * lanes + r;
                let c = unsafe { &mut *t.c.add(i * t.c_is + j * t.c_js) };
                *c = match epilogue {
                    Epilogue::Accumulate => *c + lane_values[i],
                    Epilogue::Store => lane_values[i],
                    Epilogue::Bias { .. } | Epilogue::Mask { .. } => {
                        unreachable!("a transposed product has no bias or mask")
                    }
                };
            }
        }
    }
}
