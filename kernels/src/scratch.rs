//! Per-thread scratch memory for packed operands, 64-byte aligned, grown on first use and kept
//! for the thread's life: after the first update nothing more is allocated, and the same
//! memory stays warm in cache from one product to the next.

use std::cell::RefCell;

/// Aligned scratch of at least `len` floats, uninitialised contents.
pub(crate) struct Scratch {
    buf: Vec<f32>,
}

/// Floats of alignment slack: 64 bytes.
const ALIGN: usize = 16;

impl Scratch {
    const fn new() -> Self {
        Scratch { buf: Vec::new() }
    }

    /// A 64-byte aligned pointer to at least `len` floats.
    fn get(&mut self, len: usize) -> *mut f32 {
        if self.buf.len() < len + ALIGN {
            self.buf = vec![0.0; len + ALIGN];
        }
        let p = self.buf.as_mut_ptr();
        let skip = p.align_offset(64).min(ALIGN);
        // SAFETY: `skip < ALIGN`, and the buffer holds `len + ALIGN` floats.
        unsafe { p.add(skip) }
    }
}

thread_local! {
    /// The packed left operand: the caller's, shared with its team for one product.
    static A: RefCell<Scratch> = const { RefCell::new(Scratch::new()) };
    /// Each thread's own packed slice of the right operand.
    static B: RefCell<Scratch> = const { RefCell::new(Scratch::new()) };
}

/// This thread's scratch for a packed `A` (valid until the next call on this thread).
pub(crate) fn a_scratch(len: usize) -> *mut f32 {
    A.with(|s| s.borrow_mut().get(len))
}

/// This thread's scratch for a packed slice of `B` (valid until the next call on this thread).
pub(crate) fn b_scratch(len: usize) -> *mut f32 {
    B.with(|s| s.borrow_mut().get(len))
}
