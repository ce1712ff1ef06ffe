//! Software prefetch, one of the two parts of [`super`], the crate's one
//! module with `unsafe` (the other is the runtime AVX-512 dispatch).
//!
//! A single ray's walk is a chain of dependent loads: the next node's
//! address is known only once the current node's boxes are tested. On a
//! mesh that outgrows the L2 cache (the dragon's 45 MB of nodes and leaf
//! blocks against 2 MB of L2 here) each link waits for the next cache
//! level, so a random dragon ray took twice a bunny ray's time for the
//! same instructions. The children a node defers onto the stack are known
//! long before they are visited; asking for their lines then overlaps
//! those waits with the walk of the nearest child's subtree (the
//! software-pipelined prefetch of Mowry, Lam and Gupta 1992, applied to
//! the stack of a tree walk).
//!
//! On a mesh that fits the caches the hints are pure cost, so
//! [`Prefetch::Auto`] turns them on only for
//! scenes whose nodes and leaf blocks outgrow [`AUTO_MIN_BYTES`].
//!
//! A prefetch is a hint: it never faults and changes no result. Where the
//! target has no stable prefetch instruction (anything but x86-64) the
//! safe fallback does nothing; traversal with prefetching switched off
//! ([`super::Bvh8::prefetch`]) is the same fallback on x86-64, and a test
//! checks that both return the same hits.

crate::mode::mode_enum! {
    /// Whether traversal prefetches: `auto` decides by the scene's size.
    #[derive(Default)]
    pub enum Prefetch("prefetch mode") {
        #[default]
        Auto = "auto",
        On = "on",
        Off = "off",
    }
}

/// The size of a tree's nodes and leaf blocks from which [`Prefetch::Auto`]
/// prefetches: four times the 2 MiB of L2 per core it was measured on,
/// between the sizes where prefetching lost and won (docs/embree.md,
/// "Prefetch").
pub const AUTO_MIN_BYTES: usize = 8 << 20;

impl Prefetch {
    /// Whether to prefetch for a tree whose nodes and leaf blocks take `bytes`.
    pub fn enabled(self, bytes: usize) -> bool {
        match self {
            Self::Auto => bytes >= AUTO_MIN_BYTES,
            Self::On => true,
            Self::Off => false,
        }
    }
}

/// Cache line size of every x86-64 CPU this targets.
const LINE: usize = 64;

/// Asks the CPU to bring every cache line of `value` into the L1 cache,
/// without waiting for them.
#[inline(always)]
pub fn prefetch<T>(value: &T) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        let first = value as *const T as *const i8;
        for offset in line_offsets::<T>() {
            // SAFETY: PREFETCHT0 reads no architectural state and never
            // faults, whatever the address; the addresses lie inside
            // `value` anyway (`wrapping_add`: no pointer arithmetic rules
            // to uphold either). SSE, which the intrinsic is gated on, is
            // part of the x86-64 baseline.
            unsafe { _mm_prefetch::<_MM_HINT_T0>(first.wrapping_add(offset)) };
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = value;
}

/// Offsets into a `T` that touch every cache line it may span: one per
/// 64 bytes, and its last byte too where its alignment lets it start far
/// enough into a line to spill into one more (a 224-byte node at 32-byte
/// alignment never spans more than four lines; a 320-byte triangle block,
/// aligned to a line, exactly five).
///
/// A range of a count constant per type, each offset a multiply and a
/// `min`, so that the loop unrolls into straight prefetches: as a range
/// chained with an optional last offset it compiled to a loop with the
/// chain's state in flags, and walks in flight on the dragon ran about 5%
/// slower (docs/performance.md, "Prefetches in a straight line").
#[inline(always)]
fn line_offsets<T>() -> impl Iterator<Item = usize> {
    let size = std::mem::size_of::<T>();
    let align = std::mem::align_of::<T>();
    let lines = size.div_ceil(LINE);
    let spills = size > 0 && align < LINE && (size - 1) % LINE >= align;
    // The spilled line's offset is the last byte's: past it, `min` holds
    // every offset inside the value.
    (0..lines + usize::from(spills)).map(move |i| (i * LINE).min(size.saturating_sub(1)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Prefetching any value, at any alignment and of any size, reads and
    /// changes nothing.
    #[test]
    fn prefetch_leaves_values_unchanged() {
        let bytes: Vec<u8> = (0..=255).collect();
        for byte in &bytes[..64] {
            prefetch(byte);
        }
        let blocks = [[1.5f32; 80]; 3];
        for block in &blocks {
            prefetch(block);
        }
        prefetch(&());
        assert_eq!(bytes, (0..=255).collect::<Vec<u8>>());
        assert!(blocks.iter().flatten().all(|&x| x == 1.5));
    }

    /// The offsets reach every line a value can span at any address its
    /// alignment allows, and no more than one spare.
    #[test]
    fn line_offsets_cover_every_line_a_value_may_span() {
        fn check<T>() {
            let (size, align) = (std::mem::size_of::<T>(), std::mem::align_of::<T>());
            let offsets: Vec<usize> = line_offsets::<T>().collect();
            for start in (0..2 * LINE).step_by(align) {
                let lines = |range: std::ops::Range<usize>| {
                    range
                        .map(|b| (start + b) / LINE)
                        .collect::<std::collections::BTreeSet<_>>()
                };
                let spanned = lines(0..size);
                let fetched = offsets.iter().map(|&o| (start + o) / LINE).collect();
                assert_eq!(spanned, fetched, "size {size} align {align} at {start}");
            }
            assert!(offsets.len() <= size.div_ceil(LINE) + 1);
        }
        check::<crate::accel::node::Node8>();
        check::<crate::shape::triangle_lanes::TriangleBlock>();
        check::<[u8; 64]>();
        check::<[u32; 17]>();
        check::<u8>();
        check::<()>();
    }

    #[test]
    fn auto_prefetches_only_trees_that_outgrow_the_caches() {
        assert!(!Prefetch::Auto.enabled(AUTO_MIN_BYTES - 1));
        assert!(Prefetch::Auto.enabled(AUTO_MIN_BYTES));
        assert!(Prefetch::On.enabled(0) && !Prefetch::Off.enabled(usize::MAX));
        assert_eq!("off".parse(), Ok(Prefetch::Off));
        assert!("yes"
            .parse::<Prefetch>()
            .unwrap_err()
            .contains("auto, on or off"));
    }
}
