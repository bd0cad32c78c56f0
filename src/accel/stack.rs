//! The traversal stack: a fixed-capacity array on the machine stack that is *not* cleared on creation.
//!
//! A traversal makes a new stack per ray (or packet), and most rays use a few entries of it: zeroing
//! it up front cost more than the packet traversal itself (`profiles/README.md`, tuned constants). The
//! entries are only ever read below `len`, where they were written, so they need no value before that.

use std::mem::MaybeUninit;

/// A stack of at most `N` entries of `T`.
pub struct Stack<T: Copy, const N: usize> {
    items: [MaybeUninit<T>; N],
    len: usize,
}

impl<T: Copy, const N: usize> Stack<T, N> {
    /// An empty stack (nothing written).
    #[inline(always)]
    pub fn new() -> Self {
        Stack {
            items: [const { MaybeUninit::uninit() }; N],
            len: 0,
        }
    }

    /// Entries on the stack.
    #[inline(always)]
    pub fn len(&self) -> usize {
        self.len
    }

    /// True when nothing is on the stack.
    #[inline(always)]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Pushes `item`. Panics past `N` entries, which the traversals' depth bounds rule out.
    #[inline(always)]
    pub fn push(&mut self, item: T) {
        self.items[self.len].write(item);
        self.len += 1;
    }

    /// Pushes `n` entries that `fill` writes, from the first free slot it is given on, at once (a SIMD
    /// store of a sorted run). Panics past `N` entries, as [`Stack::push`] does.
    ///
    /// # Safety
    /// `fill` must write all `n` entries from that pointer on, and nothing past them.
    #[inline(always)]
    pub unsafe fn push_written(&mut self, n: usize, fill: impl FnOnce(*mut T)) {
        assert!(n <= N - self.len, "stack overflow");
        fill(self.items[self.len..].as_mut_ptr().cast());
        self.len += n;
    }

    /// Pops the top entry.
    #[inline(always)]
    pub fn pop(&mut self) -> Option<T> {
        if self.len == 0 {
            return None;
        }
        self.len -= 1;
        // SAFETY: every slot below the old `len` was written by `push` (and `T: Copy` has no drop).
        Some(unsafe { self.items[self.len].assume_init() })
    }

    /// The entries from `start` to the top, for reordering what one node pushed.
    #[inline(always)]
    pub fn above_mut(&mut self, start: usize) -> &mut [T] {
        let init = &mut self.items[start.min(self.len)..self.len];
        // SAFETY: the slots below `len` are initialised, and `MaybeUninit<T>` has `T`'s layout.
        unsafe { &mut *(init as *mut [MaybeUninit<T>] as *mut [T]) }
    }
}

impl<T: Copy, const N: usize> Default for Stack<T, N> {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests {
    use super::Stack;

    #[test]
    fn push_pop_reorder() {
        let mut s: Stack<(u32, f32), 8> = Stack::new();
        assert_eq!(s.pop(), None);
        for i in 0..5 {
            s.push((i, i as f32));
        }
        s.above_mut(2).reverse();
        assert_eq!(s.len(), 5);
        assert_eq!(s.pop(), Some((2, 2.0)));
        assert_eq!(s.pop(), Some((3, 3.0)));
        assert_eq!(s.pop(), Some((4, 4.0)));
        assert_eq!(s.pop(), Some((1, 1.0)));
        assert_eq!(s.pop(), Some((0, 0.0)));
        assert!(s.is_empty());
        assert_eq!(s.pop(), None);
    }

    #[test]
    fn push_written_adds_what_was_written() {
        let mut s: Stack<u32, 8> = Stack::new();
        s.push(7);
        // SAFETY: the closure writes exactly the three entries it was given room for.
        unsafe {
            s.push_written(3, |at| {
                for i in 0..3 {
                    at.add(i).write(10 + i as u32);
                }
            })
        };
        assert_eq!(s.len(), 4);
        let popped: Vec<u32> = std::iter::from_fn(|| s.pop()).collect();
        assert_eq!(popped, [12, 11, 10, 7]);
    }

    #[test]
    #[should_panic]
    fn push_written_past_capacity_panics() {
        let mut s: Stack<u32, 2> = Stack::new();
        s.push(1);
        // SAFETY: never runs the closure: two more do not fit.
        unsafe { s.push_written(2, |_| {}) };
    }

    #[test]
    #[should_panic]
    fn overflow_panics() {
        let mut s: Stack<u8, 2> = Stack::new();
        for i in 0..3 {
            s.push(i);
        }
    }
}
