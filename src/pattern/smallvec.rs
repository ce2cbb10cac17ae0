//! A vector that keeps its first `N` elements inline (on the stack when the vector is a local) and
//! moves to the heap only beyond that, so matching an ordinary pattern allocates nothing.

use core::mem::MaybeUninit;

pub(crate) struct SmallVec<T: Copy, const N: usize> {
    /// Elements in `inline[..len]` while `heap` is empty; all of them in `heap` after a spill.
    len: usize,
    inline: [MaybeUninit<T>; N],
    heap: Vec<T>,
}

impl<T: Copy, const N: usize> SmallVec<T, N> {
    pub(crate) fn new() -> Self {
        // Left uninitialised on purpose: only `inline[..len]` is ever read.
        SmallVec {
            len: 0,
            inline: [const { MaybeUninit::uninit() }; N],
            heap: Vec::new(),
        }
    }

    #[inline]
    fn spilled(&self) -> bool {
        self.heap.capacity() != 0
    }

    #[inline]
    pub(crate) fn push(&mut self, value: T) {
        if self.spilled() {
            self.heap.push(value);
        } else if self.len < N {
            self.inline[self.len].write(value);
            self.len += 1;
        } else {
            let mut heap = Vec::with_capacity(2 * N.max(4));
            heap.extend_from_slice(self.as_slice());
            heap.push(value);
            self.heap = heap;
        }
    }

    #[inline]
    pub(crate) fn len(&self) -> usize {
        if self.spilled() {
            self.heap.len()
        } else {
            self.len
        }
    }

    pub(crate) fn truncate(&mut self, len: usize) {
        if self.spilled() {
            self.heap.truncate(len);
        } else {
            self.len = self.len.min(len);
        }
    }

    #[inline]
    pub(crate) fn as_slice(&self) -> &[T] {
        if self.spilled() {
            &self.heap
        } else {
            // SAFETY: `inline[..len]` has been written by `push`; MaybeUninit<T> has T's layout.
            unsafe { core::slice::from_raw_parts(self.inline.as_ptr().cast::<T>(), self.len) }
        }
    }

    #[inline]
    pub(crate) fn as_mut_slice(&mut self) -> &mut [T] {
        if self.spilled() {
            &mut self.heap
        } else {
            // SAFETY: as in `as_slice`, and `self` is borrowed mutably.
            unsafe { core::slice::from_raw_parts_mut(self.inline.as_mut_ptr().cast::<T>(), self.len) }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stays_inline_then_spills_to_the_heap_keeping_order() {
        let mut v = SmallVec::<u32, 4>::new();
        for i in 0..4 {
            v.push(i);
        }
        assert!(!v.spilled());
        assert_eq!(v.as_slice(), &[0, 1, 2, 3]);
        for i in 4..20 {
            v.push(i);
        }
        assert!(v.spilled());
        assert_eq!(v.as_slice(), (0..20).collect::<Vec<_>>().as_slice());
        v.as_mut_slice()[0] = 7;
        v.truncate(3);
        assert_eq!(v.as_slice(), &[7, 1, 2]);
        assert_eq!(v.len(), 3);
    }
}
