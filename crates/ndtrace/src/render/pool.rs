//! Retina output buffers kept for reuse between traces.
//!
//! A retina's outputs would otherwise be fresh memory on every trace, and the first write to
//! each 4 KiB page of fresh memory is a page fault in which the kernel zeroes the page: for the
//! hundred megabytes of a large 4D retina, a good part of the trace. Buffers handed back with
//! [`recycle`] (the Python bindings do so when numpy frees a retina's arrays) are reused by the
//! next trace instead, so a loop that traces, reads and drops its results only touches fresh
//! memory on the first trace. They come back as they were, not cleared: the tracer writes
//! every element of its outputs, and clearing them would cost another pass over the memory.
//!
//! At most [`KEEP_BUFFERS`] buffers per element type and [`KEEP_BYTES`] in all are kept;
//! [`release`] frees them.

use std::sync::{Mutex, MutexGuard};

/// The most bytes kept, over all element types.
pub const KEEP_BYTES: usize = 256 << 20;
/// The most buffers kept per element type (a retina has three `f32` arrays).
pub const KEEP_BUFFERS: usize = 6;

/// The buffers kept, per element type, and their total size in bytes (opaque: reached only
/// through a [`Pool`]).
#[doc(hidden)]
pub struct Kept {
    f32: Vec<Vec<f32>>,
    i32: Vec<Vec<i32>>,
    i64: Vec<Vec<i64>>,
    bytes: usize,
}

/// An element type whose buffers are kept: the retina's `f32`, `i32` and `i64`.
pub trait Pooled: Copy + Default + Send + 'static {
    #[doc(hidden)]
    fn list(k: &mut Kept) -> &mut Vec<Vec<Self>>;
}

macro_rules! pooled {
    ($($t:ident),*) => {$(
        impl Pooled for $t {
            fn list(k: &mut Kept) -> &mut Vec<Vec<Self>> {
                &mut k.$t
            }
        }
    )*};
}
pooled!(f32, i32, i64);

fn bytes<T>(v: &Vec<T>) -> usize {
    v.capacity() * size_of::<T>()
}

/// A set of kept buffers; the tracer uses the process-wide one ([`take`], [`recycle`],
/// [`release`]).
pub struct Pool(Mutex<Kept>);

impl Default for Pool {
    fn default() -> Self {
        Self::new()
    }
}

impl Pool {
    /// An empty pool.
    pub const fn new() -> Self {
        Pool(Mutex::new(Kept {
            f32: Vec::new(),
            i32: Vec::new(),
            i64: Vec::new(),
            bytes: 0,
        }))
    }

    fn kept(&self) -> MutexGuard<'_, Kept> {
        // The lists stay consistent even if a holder panicked (each update is one push or
        // remove).
        self.0.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// A buffer of `len` elements for a caller that overwrites every one: a kept one whose
    /// capacity is at least `len` and at most twice it (the smallest such), holding its old
    /// values (zeros past its old length), else a new zeroed allocation.
    pub fn take<T: Pooled>(&self, len: usize) -> Vec<T> {
        let reused = {
            let mut k = self.kept();
            let list = T::list(&mut k);
            let fit = list
                .iter()
                .enumerate()
                .filter(|(_, v)| v.capacity() >= len && v.capacity() / 2 <= len)
                .min_by_key(|(_, v)| v.capacity())
                .map(|(i, _)| i);
            let v = fit.map(|i| list.swap_remove(i));
            if let Some(v) = &v {
                k.bytes -= bytes(v);
            }
            v
        };
        match reused {
            Some(mut v) => {
                v.truncate(len);
                v.resize(len, T::default());
                v
            }
            None => vec![T::default(); len],
        }
    }

    /// Keeps `v`'s allocation for a later [`Pool::take`], unless that would pass
    /// [`KEEP_BUFFERS`] or [`KEEP_BYTES`] (then it is freed).
    pub fn recycle<T: Pooled>(&self, v: Vec<T>) {
        let b = bytes(&v);
        if b == 0 {
            return;
        }
        let mut k = self.kept();
        if k.bytes + b <= KEEP_BYTES && T::list(&mut k).len() < KEEP_BUFFERS {
            k.bytes += b;
            T::list(&mut k).push(v);
        } else {
            drop(k);
            drop(v);
        }
    }

    /// Frees every kept buffer; returns the bytes freed.
    pub fn release(&self) -> usize {
        let mut k = self.kept();
        let freed = k.bytes;
        k.f32 = Vec::new();
        k.i32 = Vec::new();
        k.i64 = Vec::new();
        k.bytes = 0;
        freed
    }
}

static GLOBAL: Pool = Pool::new();

/// [`Pool::take`] from the process-wide pool (the tracer's outputs).
pub fn take<T: Pooled>(len: usize) -> Vec<T> {
    GLOBAL.take(len)
}

/// [`Pool::recycle`] into the process-wide pool.
pub fn recycle<T: Pooled>(v: Vec<T>) {
    GLOBAL.recycle(v)
}

/// [`Pool::release`] of the process-wide pool.
pub fn release() -> usize {
    GLOBAL.release()
}

#[cfg(test)]
mod tests;
