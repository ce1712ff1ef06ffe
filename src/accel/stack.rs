//! The traversal stack every walk keeps its deferred children on.

/// A traversal stack that keeps its top [`STACK_INLINE`] entries inline
/// and moves older ones to the heap rather than ever dropping a node.
///
/// The heap part holds the *bottom* of the stack, so the hot operations
/// test one length: a push spills the older half when the inline part is
/// full, and a pop refills from the heap only when it is empty.
pub(crate) struct Stack<T> {
    inline: [T; STACK_INLINE],
    len: usize,
    spill: Vec<T>,
}

/// Entries a stack holds inline. A ray needs at most seven per level of an
/// 8-wide tree (about 45 on a 14M-triangle mesh, depth 7 to 8 in practice,
/// and far fewer on average); every ray pays for zeroing these, so 32 is
/// the compromise (64 made the zeroing a `memset` call). A power of two,
/// so indices are masked instead of bounds-checked.
const STACK_INLINE: usize = 32;

impl<T: Copy + Default> Stack<T> {
    #[inline]
    pub(crate) fn new() -> Self {
        Self {
            inline: [T::default(); STACK_INLINE],
            len: 0,
            spill: Vec::new(),
        }
    }

    /// Empties the stack, keeping its memory. Entries are always written
    /// before they are read, so the old ones need no clearing.
    #[inline(always)]
    pub(crate) fn clear(&mut self) {
        self.len = 0;
        self.spill.clear();
    }

    #[inline(always)]
    pub(crate) fn push(&mut self, e: T) {
        if self.len == STACK_INLINE {
            self.spill_bottom();
        }
        self.inline[self.len % STACK_INLINE] = e;
        self.len += 1;
    }

    #[inline(always)]
    pub(crate) fn pop(&mut self) -> Option<T> {
        if self.len == 0 {
            if self.spill.is_empty() {
                return None;
            }
            self.refill();
        }
        self.len -= 1;
        Some(self.inline[self.len % STACK_INLINE])
    }

    /// Makes room for `n` (at most half the inline part) more pushes that
    /// stay inline: the children of one node.
    #[inline(always)]
    pub(super) fn reserve(&mut self, n: usize) {
        debug_assert!(n <= STACK_INLINE / 2);
        if self.len + n > STACK_INLINE {
            self.spill_bottom();
        }
    }

    /// Pushes the first `n - 1` of `entries` (in order, so the last of
    /// them ends on top) and returns entry `n - 1` without pushing it: one
    /// block write for a node's sorted children, the nearest kept back.
    #[inline(always)]
    pub(super) fn push_all_but_nth(&mut self, entries: &[T; 8], n: usize) -> T {
        debug_assert!((1..=8).contains(&n));
        self.reserve(8);
        let top = &mut self.inline[self.len..self.len + 8];
        top.copy_from_slice(entries);
        self.len += n - 1;
        entries[(n - 1) % 8]
    }

    /// Moves the older half of the inline entries to the heap.
    #[cold]
    #[inline(never)]
    fn spill_bottom(&mut self) {
        let half = STACK_INLINE / 2;
        self.spill.extend_from_slice(&self.inline[..half]);
        self.inline.copy_within(half..self.len, 0);
        self.len -= half;
    }

    /// Moves up to half an inline stack back from the (non-empty) heap.
    #[cold]
    #[inline(never)]
    fn refill(&mut self) {
        let k = self.spill.len().min(STACK_INLINE / 2);
        let rest = self.spill.len() - k;
        self.inline[..k].copy_from_slice(&self.spill[rest..]);
        self.spill.truncate(rest);
        self.len = k;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stack_spills_and_refills_in_order() {
        let mut stack: Stack<u64> = Stack::new();
        let mut model: Vec<u64> = Vec::new();
        let mut next = 0u64;
        for round in 0..200u64 {
            if round % 3 == 0 {
                let block: [u64; 8] = std::array::from_fn(|i| next + i as u64);
                let n = (round % 8 + 1) as usize;
                let kept = stack.push_all_but_nth(&block, n);
                assert_eq!(kept, block[n - 1]);
                model.extend_from_slice(&block[..n - 1]);
                next += 8;
            } else {
                stack.push(next);
                model.push(next);
                next += 1;
            }
            if round % 5 == 4 {
                assert_eq!(stack.pop(), model.pop());
            }
        }
        assert!(model.len() > 2 * STACK_INLINE, "the test reaches the heap");
        while let Some(e) = model.pop() {
            assert_eq!(stack.pop(), Some(e));
        }
        assert_eq!(stack.pop(), None);
    }
}
