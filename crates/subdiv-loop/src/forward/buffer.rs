//! Output arrays of a refinement step: written once, in parallel, without being
//! initialised first, and backed by transparent huge pages, mapped up front, on Linux.
//!
//! A step writes every element of its outputs exactly once, so filling them with
//! placeholders first would only add a pass over hundreds of megabytes. [`Output`] hands
//! out the uninitialised slots as disjoint [`Slots`] pieces that are written front to
//! back; a piece counts as filled once its last slot is written, and
//! [`Output::into_vec`] checks that the filled pieces cover the whole array before it
//! exposes the elements. That check is what makes the `unsafe` call of
//! [`Vec::set_len`] sound whatever the callers do: slots are only reachable
//! through [`Slots::push`], each piece is a distinct sub-slice, so "filled lengths add up
//! to the length" means every slot was written. A piece dropped half-written (a panic
//! in a task, or a bug) never counts, `into_vec` then panics, and the written values
//! leak instead of being read uninitialised.
//!
//! Large outputs are fresh memory that nothing has touched yet. With 4 KiB pages the
//! kernel takes one page fault per 4 KiB on first touch, which costs about as much as
//! the subdivision itself at a few million triangles. [`advise_huge_pages`] asks Linux
//! to back the buffer with transparent huge pages (2 MiB on x86-64): one fault per huge
//! page, fewer TLB misses, and a cheaper release; [`map_pages`] then maps all of a large
//! buffer's pages up front (in one call, or in pieces on every thread of the pool)
//! instead of a fault per page as the writes reach them.
//! Both only change how the kernel backs the pages, never their contents; on other
//! systems they do nothing.
//!
//! [`prefetch`] is the other memory hint kept here: a cache prefetch for the passes that
//! read large arrays at random (the renumbered reversal), which never changes memory.

#![allow(unsafe_code)]

use std::mem::MaybeUninit;
use std::sync::atomic::{AtomicUsize, Ordering};

use mesh_topo::memory::{self, advise_huge_pages, huge_page_size};
use rayon::prelude::*;

/// An array of `len` elements under construction.
pub(crate) struct Output<T> {
    vec: Vec<T>,
    len: usize,
    /// Elements in pieces that were written completely.
    filled: AtomicUsize,
    /// Whether [`Output::slots`] was called: slots are handed out once, so no slot can
    /// be counted twice through two sets of pieces.
    handed_out: bool,
}

impl<T> Output<T> {
    /// Allocates room for `len` elements (uninitialised; huge pages where possible).
    pub(crate) fn new(len: usize) -> Self {
        let vec: Vec<T> = Vec::with_capacity(len);
        advise_huge_pages(vec.as_ptr().cast(), len * size_of::<T>());
        map_pages(vec.as_ptr().cast(), len * size_of::<T>());
        Self { vec, len, filled: AtomicUsize::new(0), handed_out: false }
    }

    /// Room for `len` elements in the memory of `vec` (its elements are dropped) when
    /// its capacity suffices: memory that was written before is already mapped, so
    /// writing it again takes no page fault. A vector that is too small is released
    /// before a new one is allocated, as by [`Output::new`].
    ///
    /// Room beyond what `vec` holds (its length, the elements a previous use wrote) is
    /// mapped as [`Output::new`] maps it: a vector made larger than its first use (the
    /// base level's triangles in `forward::refine`) is written there for the first time.
    pub(crate) fn reuse(mut vec: Vec<T>, len: usize) -> Self {
        let written = vec.len();
        vec.clear();
        if vec.capacity() < len {
            drop(vec);
            return Self::new(len);
        }
        if written < len {
            let (start, bytes) = (vec.as_ptr().wrapping_add(written).cast(), (len - written) * size_of::<T>());
            advise_huge_pages(start, bytes);
            map_pages(start, bytes);
        }
        Self { vec, len, filled: AtomicUsize::new(0), handed_out: false }
    }

    /// All slots, to be split into the pieces that the tasks write.
    ///
    /// # Panics
    /// If called a second time (an internal error).
    pub(crate) fn slots(&mut self) -> Slots<'_, T> {
        let Self { vec, len, filled, handed_out } = self;
        assert!(!*handed_out, "internal: output slots handed out twice");
        *handed_out = true;
        Slots { slots: &mut vec.spare_capacity_mut()[..*len], written: 0, filled }
    }

    /// The finished array.
    ///
    /// # Panics
    /// If some slot was not written (an internal error).
    pub(crate) fn into_vec(self) -> Vec<T> {
        let Self { mut vec, len, filled, .. } = self;
        assert_eq!(filled.into_inner(), len, "internal: an output slot was not written");
        // SAFETY: `len <= capacity` (allocated with `Vec::with_capacity(len)`), and the
        // first `len` slots are initialised: the only way to reach them is
        // `Slots::push`, which writes them in order; the slots are handed out once and
        // split into pieces that are disjoint sub-slices, which
        // add their length to `filled` only once all of their slots are written, so
        // `filled == len` means that every slot was written exactly once.
        unsafe { vec.set_len(len) };
        vec
    }
}

/// A piece of an [`Output`]'s slots, written front to back by one task.
pub(crate) struct Slots<'a, T> {
    slots: &'a mut [MaybeUninit<T>],
    written: usize,
    filled: &'a AtomicUsize,
}

impl<'a, T> Slots<'a, T> {
    /// Splits the first `n` slots off into their own piece (nothing written yet).
    ///
    /// # Panics
    /// If `n` exceeds the slots left or if slots were already written.
    pub(crate) fn take_front(&mut self, n: usize) -> Slots<'a, T> {
        assert_eq!(self.written, 0, "internal: split a piece that is being written");
        let (front, back) = std::mem::take(&mut self.slots).split_at_mut(n);
        self.slots = back;
        Slots { slots: front, written: 0, filled: self.filled }
    }

    /// Writes the next slot.
    ///
    /// # Panics
    /// If the piece is full.
    #[inline(always)]
    pub(crate) fn push(&mut self, value: T) {
        self.slots[self.written].write(value);
        self.written += 1;
    }

    /// Number of slots written so far: the index of the next one within the piece.
    #[inline(always)]
    pub(crate) fn written(&self) -> usize {
        self.written
    }

    /// Number of slots of the piece.
    #[inline(always)]
    pub(crate) fn len(&self) -> usize {
        self.slots.len()
    }
}

impl<T> Drop for Slots<'_, T> {
    fn drop(&mut self) {
        if self.written == self.slots.len() {
            self.filled.fetch_add(self.written, Ordering::Relaxed);
        }
    }
}

/// The vector `[value(0), value(1), ..., value(len - 1)]`, computed in parallel when
/// large (see [`splits`](super::kernel::splits)).
pub(crate) fn par_fill<T: Send>(len: usize, value: impl Fn(usize) -> T + Sync) -> Vec<T> {
    const CHUNK: usize = 1 << 16;
    let mut output = Output::new(len);
    {
        let mut slots = output.slots();
        let pieces: Vec<(usize, Slots<'_, T>)> =
            (0..len).step_by(CHUNK).map(|start| (start, slots.take_front(CHUNK.min(len - start)))).collect();
        let run = |(start, mut piece): (usize, Slots<'_, T>)| {
            for i in start..start + piece.len() {
                piece.push(value(i));
            }
        };
        if super::kernel::splits(len, CHUNK) {
            pieces.into_par_iter().for_each(run);
        } else {
            pieces.into_iter().for_each(run);
        }
    }
    output.into_vec()
}

/// Buffers of at least this many bytes are mapped by [`map_pages`] when allocated.
const MAP_PAGES_MIN_BYTES: usize = 1 << 18;

/// Maps every page of a fresh buffer of `bytes` bytes at `start` in one system call
/// (`MADV_POPULATE_WRITE`, Linux 5.14 and later), instead of one page fault per page as
/// the writes first touch it. The kernel still clears each page, but without a trap per
/// page. Measured on the 2-core test machine (`forward::subdivide`, median of 30 calls,
/// with and without the call interleaved): one thread, the bunny to level 3 / 4 in 3.2 /
/// 14.5 ms instead of 3.8 / 17.2 ms, `bunny00.off` to level 2 / 3 in 34 / 145 ms instead
/// of 39 / 169 ms (and to level 4 in 576 ms instead of 1067 ms, criterion means); two
/// threads 3-10% faster at the same sizes, or the same.
///
/// On a pool of several threads a buffer of [`PARALLEL_MAP_MIN_HUGE_PAGES`] huge pages
/// or more is mapped in pieces by all of them: the kernel clears each thread's pages on
/// that thread. An earlier measurement found this slower; a later one, on the same kind
/// of machine, found clearing 512 MiB of huge pages 2x as fast on two threads, and
/// `bunny00.off` to level 3 / 4 on two threads in 74-78 / 305-309 ms instead of 86-88 /
/// 343-350 ms (best of 15 / 6 calls, three interleaved rounds; one thread unchanged).
///
/// Only whole pages inside the buffer are mapped. Errors (an older kernel) are ignored:
/// the writes then fault the pages in as before.
fn map_pages(start: *const u8, bytes: usize) {
    if bytes < MAP_PAGES_MIN_BYTES {
        return;
    }
    let threads = rayon::current_num_threads();
    let huge = huge_page_size();
    if threads == 1 || bytes < PARALLEL_MAP_MIN_HUGE_PAGES * huge {
        memory::map_pages(start, bytes);
        return;
    }
    // Pieces of whole huge pages, a few per thread so that a slow one is made up for;
    // the unaligned ends go with the first and the last piece.
    let (begin, end) = (start as usize, start as usize + bytes);
    let pages = bytes / huge;
    let pages_per_piece = pages.div_ceil(4 * threads);
    let pieces = pages.div_ceil(pages_per_piece);
    let cut = |k: usize| match k {
        0 => begin,
        _ if k == pieces => end,
        _ => (begin.next_multiple_of(huge) + k * pages_per_piece * huge).min(end),
    };
    (0..pieces).into_par_iter().for_each(|k| {
        let (from, to) = (cut(k), cut(k + 1));
        memory::map_pages(from as *const u8, to - from);
    });
}

/// Buffers of at least this many huge pages are mapped by all threads of the pool (a
/// smaller one is mapped faster than the threads can be woken).
const PARALLEL_MAP_MIN_HUGE_PAGES: usize = 4;

/// True if an array of `bytes` read at random is worth prefetching: larger than a
/// core's share of the caches. Below that the reads hit the cache anyway, and the
/// hints and the look-ahead only add work.
#[inline]
pub(crate) fn worth_prefetching(bytes: usize) -> bool {
    bytes >= 1 << 21
}

/// Asks the processor to bring the cache line of `slice[i]` into its caches (nothing
/// if `i` is out of range, or on targets without a prefetch instruction). A hint only:
/// it never changes memory, so results never depend on it. Searches that hop through
/// arrays larger than the caches issue it for elements they will read a few steps
/// later, so that the misses overlap instead of following one another.
#[inline(always)]
pub(crate) fn prefetch<T>(slice: &[T], i: usize) {
    #[cfg(target_arch = "x86_64")]
    if let Some(element) = slice.get(i) {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        // SAFETY: `_mm_prefetch` needs SSE, part of every x86-64 target; a prefetch
        // never faults and never changes memory (here the address is even that of a
        // live element).
        unsafe { _mm_prefetch::<_MM_HINT_T0>(std::ptr::from_ref(element).cast()) };
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (slice, i);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Mapping pages never changes memory: written values stay, on every page of a
    /// buffer and at its unaligned ends.
    #[test]
    fn mapping_pages_keeps_what_they_hold() {
        let values: Vec<u64> = (0..(3 * MAP_PAGES_MIN_BYTES / 8) as u64).map(|i| i.wrapping_mul(0x9e37_79b9)).collect();
        map_pages(values.as_ptr().cast(), values.len() * 8);
        advise_huge_pages(values.as_ptr().cast(), values.len() * 8);
        assert!(values.iter().enumerate().all(|(i, &v)| v == (i as u64).wrapping_mul(0x9e37_79b9)));
        // A large output, every slot written once after its pages were mapped.
        let len = MAP_PAGES_MIN_BYTES;
        let mut output = Output::<u32>::new(len);
        {
            let mut all = output.slots();
            for i in 0..len {
                all.push(i as u32);
            }
        }
        assert!(output.into_vec().iter().enumerate().all(|(i, &v)| v == i as u32));
    }

    /// On a pool of two threads a large buffer is mapped in pieces: what it holds
    /// stays, including at the unaligned ends and at the cuts between pieces.
    #[test]
    fn mapping_pages_on_several_threads_keeps_what_they_hold() {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().expect("thread pool");
        for words in [PARALLEL_MAP_MIN_HUGE_PAGES * huge_page_size() / 8 + 3, (9 * huge_page_size() + 4096) / 8 + 1] {
            let values: Vec<u64> = (0..words as u64).map(|i| i.wrapping_mul(0x9e37_79b9)).collect();
            pool.install(|| map_pages(values.as_ptr().cast(), values.len() * 8));
            assert!(values.iter().enumerate().all(|(i, &v)| v == (i as u64).wrapping_mul(0x9e37_79b9)));
            let mut output = pool.install(|| Output::<u64>::new(words));
            {
                let mut all = output.slots();
                for i in 0..words as u64 {
                    all.push(i);
                }
            }
            assert!(output.into_vec().iter().copied().eq(0..words as u64));
        }
    }

    #[test]
    fn pieces_written_in_full_make_the_array() {
        let mut output = Output::new(5);
        {
            let mut all = output.slots();
            let mut front = all.take_front(2);
            let mut back = all.take_front(3);
            assert_eq!((front.len(), back.len()), (2, 3));
            for i in 0..3 {
                back.push(format!("b{i}"));
            }
            front.push("a0".to_string());
            assert_eq!(front.written(), 1);
            front.push("a1".to_string());
        }
        assert_eq!(output.into_vec(), ["a0", "a1", "b0", "b1", "b2"]);
    }

    #[test]
    #[should_panic(expected = "internal: an output slot was not written")]
    fn a_piece_left_half_written_is_caught() {
        let mut output = Output::new(3);
        {
            let mut all = output.slots();
            all.push(vec![1u8]);
            all.push(vec![2u8]);
        }
        output.into_vec();
    }

    #[test]
    #[should_panic(expected = "internal: output slots handed out twice")]
    fn slots_are_handed_out_once() {
        // Otherwise the same half written through two sets of pieces would count as
        // the whole array.
        let mut output = Output::<u32>::new(2);
        {
            let mut front = output.slots().take_front(1);
            front.push(1);
        }
        let mut again = output.slots().take_front(1);
        again.push(1);
    }

    #[test]
    #[should_panic]
    fn writing_past_a_piece_panics() {
        let mut output = Output::<u32>::new(4);
        let mut all = output.slots();
        let mut front = all.take_front(1);
        front.push(1);
        front.push(2);
    }

    #[test]
    fn large_buffers_get_huge_pages_and_small_ones_are_left_alone() {
        // Large, untouched buffers go through the hint; it must not disturb anything.
        let len = (16 << 20) / 8;
        let mut output = Output::<u64>::new(len);
        {
            let mut all = output.slots();
            for i in 0..len as u64 {
                all.push(i);
            }
        }
        let values = output.into_vec();
        assert!(values.iter().enumerate().all(|(i, &v)| v == i as u64));
        assert!(Output::<u8>::new(0).into_vec().is_empty());
    }

    #[test]
    fn reused_vectors_keep_their_memory_and_grow_when_too_small() {
        let mut output = Output::reuse(vec![7u64; 10], 4);
        {
            let mut all = output.slots();
            for i in 0..4 {
                all.push(i);
            }
        }
        let values = output.into_vec();
        assert_eq!(values, [0, 1, 2, 3]);
        assert!(values.capacity() >= 10);
        let address = values.as_ptr();
        let mut again = Output::reuse(values, 10);
        {
            let mut all = again.slots();
            for i in 0..10 {
                all.push(i);
            }
        }
        let values = again.into_vec();
        assert_eq!(values.as_ptr(), address, "the memory is reused");
        assert_eq!(values.len(), 10);
        let mut grown = Output::reuse(values, 100);
        {
            let mut all = grown.slots();
            for i in 0..100 {
                all.push(i);
            }
        }
        assert!(grown.into_vec().iter().copied().eq(0..100));
    }

    #[test]
    fn parallel_fill_covers_every_index() {
        let len = 3 * (1 << 16) + 5;
        let filled = par_fill(len, |i| 3 * i as u64);
        assert_eq!(filled.len(), len);
        assert!(filled.iter().enumerate().all(|(i, &v)| v == 3 * i as u64));
        assert!(par_fill(0, |i| i).is_empty());
    }
}
