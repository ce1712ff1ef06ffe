//! Huge pages for the arrays a walk reads, and freed pages handed back
//! ([`give_back_freed_memory`]): one of the parts of [`super`], the
//! crate's one module with `unsafe`.
//!
//! A walk through a tree larger than the caches is a chain of loads to
//! scattered addresses, and on 4 KiB pages nearly each of them also
//! misses the TLB: the dragon's 45 MB of nodes and leaf blocks span 11,000
//! pages, where a Zen 4 core's second-level TLB maps 3,072 (12 MB), so a
//! node's load waits for a page walk as well as for its line. Backed by 2
//! MiB pages the same arrays take 23 entries. Linux gives huge pages to
//! the ranges a process asks for with `madvise(MADV_HUGEPAGE)` where
//! transparent huge pages are set to `madvise` (as on the workplace's
//! machines; with `always` it gives them anyway), and Embree asks for them
//! for its trees: on the dragon its process held 61 MB of `AnonHugePages`
//! and strata's none; with its tree on huge pages strata's lone walk went
//! from 0.74–0.82 of Embree's speed to 0.88–0.89 (docs/performance.md,
//! "Huge pages for the tree").
//!
//! Huge pages are not free where they are first written: on the
//! workplace's VMs, whose host takes back the memory a process frees, a
//! fresh huge page cost 1.5 to 5 ms (the dragon subdivided twice built 0.5
//! s slower with its tree on them), and with every large allocation on
//! them (glibc's `glibc.malloc.hugetlb=1`) the build took half as long
//! again. So there only the walk's own arrays (the nodes and the leaf
//! blocks) ask, and only where the render's rays pay for it
//! ([`super::super::choice`] decides: [`Pages`]). Where huge pages are
//! cheap to write first, the `strata` command puts every large block on
//! them ([`super::allocator`]), and the tree with them.
//!
//! The kernel chooses a page's size when it is first written, so
//! [`collect_on`] advises the vector's room before it writes
//! the items into it (`MADV_HUGEPAGE`). Memory the allocator hands out
//! again (glibc's heap below its mmap threshold, up to 32 MB) may have
//! been written before on small pages; those are gathered into huge ones
//! once the items are in (`MADV_COLLAPSE`, Linux 6.1 on: one copy of what
//! is not on huge pages yet, nothing where all is). [`move_to_huge_pages`]
//! does the same for values already written (a tree's nodes, built before
//! the render's choice applies), in place.
//!
//! Why the `unsafe` is sound: `madvise` with either advice changes no
//! byte of memory and no mapping's permissions (a collapse moves pages
//! to new frames, invisibly to the process); the range given is whole
//! pages inside the vector's (or the slice's) own bytes. A failure (a
//! kernel without transparent huge pages, or none free) leaves the values
//! as they were. The safe twin is what every other target gets: a plain
//! `collect`, and values already written left where they are; the tests
//! hold both to the same values and check that the kernel recorded the
//! advice.

use rayon::prelude::*;

/// The smallest array advised: a round size that holds a whole huge page
/// (2 MiB, aligned) wherever it starts.
pub(super) const MIN_BYTES: usize = 4 << 20;

/// The pages a tree's arrays are written to.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Pages {
    /// The system's own (4 KiB on x86-64 Linux).
    #[default]
    Small,
    /// Huge pages (2 MiB), asked of the kernel where it has them.
    Huge,
}

/// `items` collected in order, in parallel, into a vector on `pages`
/// (huge pages on Linux alone, and for [`MIN_BYTES`] and more).
pub fn collect_on<T: Send>(pages: Pages, items: impl IndexedParallelIterator<Item = T>) -> Vec<T> {
    let mut v = Vec::with_capacity(items.len());
    let bytes = v.capacity() * std::mem::size_of::<T>();
    let advised = pages == Pages::Huge && bytes >= MIN_BYTES;
    if advised {
        advise(v.as_ptr() as usize, bytes, Advice::Huge);
    }
    // Written in place: the room is there, so nothing moves.
    v.par_extend(items);
    if advised {
        advise(v.as_ptr() as usize, bytes, Advice::Collapse);
    }
    v
}

/// Moves `values`, already written, onto huge pages where they fill
/// whole ones (Linux 6.1 on, [`MIN_BYTES`] and more): the kernel copies
/// each 2 MiB of them into a huge page and frees the small ones, so no
/// second copy of the values is ever resident, and they stay where they
/// are in the address space. Where the kernel cannot, the range stays
/// advised and its small pages as they were.
pub fn move_to_huge_pages<T>(values: &[T]) {
    let bytes = std::mem::size_of_val(values);
    if bytes >= MIN_BYTES {
        advise(values.as_ptr() as usize, bytes, Advice::Huge);
        advise(values.as_ptr() as usize, bytes, Advice::Collapse);
    }
}

/// Hands the pages of memory the process has freed back to the system
/// (glibc's `malloc_trim(0)`: the whole pages inside each arena's free
/// chunks are released with `MADV_DONTNEED`, the heap's top trimmed).
///
/// A build's temporaries (the binary tree, PLOC's clusters, the collapse's
/// tables) are freed when it ends, but those glibc placed on its heap
/// (arrays under its mmap threshold, which grows to 32 MiB as larger
/// arrays are freed) stay resident, and the leaf blocks written next (a
/// mapping of their own) came on top of them: the dragon's render peaked
/// at 103 B a triangle, 12 to 16 MB of it freed memory (docs/performance.md,
/// "Freed memory handed back"). The call takes about 2 ms there.
///
/// Why the `unsafe` is sound: `malloc_trim` has no precondition, takes
/// each arena's lock as `malloc` does, and touches only memory no live
/// allocation holds. The twin (every other target, or another C
/// library) hands nothing back: the same values, more memory resident.
pub fn give_back_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: see above; the return value (whether anything was
    // released) changes nothing.
    unsafe {
        libc::malloc_trim(0);
    }
}

/// Advises the whole pages inside `bytes` bytes from `start` for huge
/// pages as they are first written (the allocator's large blocks).
pub(super) fn advise_huge(start: usize, bytes: usize) {
    advise(start, bytes, Advice::Huge);
}

#[derive(Clone, Copy)]
enum Advice {
    /// Back the range with huge pages as it is first written.
    Huge,
    /// Move what is already written onto huge pages now.
    Collapse,
}

#[cfg(target_os = "linux")]
fn advise(start: usize, bytes: usize, advice: Advice) {
    /// Linux's `MADV_COLLAPSE` (uapi `asm-generic/mman-common.h`), which
    /// not every C library's headers, nor `libc` for each, carry.
    const MADV_COLLAPSE: libc::c_int = 25;
    // SAFETY: sysconf reads a constant of the system; no memory is touched.
    let page = match unsafe { libc::sysconf(libc::_SC_PAGESIZE) } {
        p if p > 0 => p as usize,
        _ => return,
    };
    // The whole pages inside the allocation: madvise takes page-aligned
    // ranges, and advice past the allocation's end would mark memory that
    // is not the vector's.
    let first = start.next_multiple_of(page);
    let end = (start + bytes) / page * page;
    let advice = match advice {
        Advice::Huge => libc::MADV_HUGEPAGE,
        Advice::Collapse => MADV_COLLAPSE,
    };
    if end > first {
        // SAFETY: [first, end) lies inside the vector's allocation, and
        // neither advice changes its contents, permissions or mapping as
        // the process sees them (the module's doc). The result is
        // ignored: a refused advice leaves the vector as it was.
        unsafe {
            libc::madvise(first as *mut libc::c_void, end - first, advice);
        }
    }
}

#[cfg(not(target_os = "linux"))]
fn advise(_start: usize, _bytes: usize, _advice: Advice) {}

/// Whether the mapping that holds the middle of `values` is marked for
/// huge pages (`hg` in its `VmFlags` in /proc/self/smaps); `None` where
/// that cannot be read: no transparent huge pages in the kernel, no smaps
/// with flags (some sandboxes), or a target other than Linux.
#[cfg(test)]
pub(crate) fn marked_huge<T>(values: &[T]) -> Option<bool> {
    if !cfg!(target_os = "linux")
        || !std::path::Path::new("/sys/kernel/mm/transparent_hugepage").exists()
    {
        return None;
    }
    let addr = values.as_ptr() as usize + std::mem::size_of_val(values) / 2;
    let smaps = std::fs::read_to_string("/proc/self/smaps").ok()?;
    let mut inside = false;
    for line in smaps.lines() {
        let range = line.split_whitespace().next().unwrap_or("");
        if let Some((a, b)) = range.split_once('-') {
            if let (Ok(a), Ok(b)) = (usize::from_str_radix(a, 16), usize::from_str_radix(b, 16)) {
                inside = (a..b).contains(&addr);
                continue;
            }
        }
        if let (true, Some(flags)) = (inside, line.strip_prefix("VmFlags:")) {
            return Some(flags.split_whitespace().any(|f| f == "hg"));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A vector on either pages is the twin's, a plain `collect`: the same
    /// items in the same order, below the threshold and above it.
    #[test]
    fn an_advised_vector_is_a_plain_one() {
        for len in [0, 1, 1000, MIN_BYTES / 8 + 3, 3 * MIN_BYTES / 8] {
            let item = |i: usize| (i as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15);
            let twin: Vec<u64> = (0..len).into_par_iter().map(item).collect();
            for pages in [Pages::Small, Pages::Huge] {
                let v = collect_on(pages, (0..len).into_par_iter().map(item));
                assert_eq!(v, twin, "{len} items on {pages:?} pages");
            }
        }
    }

    /// Where the kernel has transparent huge pages, the mapping that holds
    /// a large vector on huge pages is marked for them, and one on small
    /// pages is left alone. Both are 64 MiB, past the largest threshold
    /// (32 MiB) below which glibc may hand out a range advised before, so
    /// each is a mapping of its own.
    #[test]
    fn the_kernel_records_the_advice() {
        let bytes = || (0..16 * MIN_BYTES).into_par_iter().map(|i| i as u8);
        let big = collect_on(Pages::Huge, bytes());
        let plain = collect_on(Pages::Small, bytes());
        if let (Some(big), Some(plain)) = (marked_huge(&big), marked_huge(&plain)) {
            assert!(big && !plain);
        }
    }

    /// A tree's nodes move onto huge pages unchanged and in place.
    #[test]
    fn a_tree_moves_onto_huge_pages_unchanged() {
        use crate::accel::{BuildQuality, Bvh8};
        use crate::math::Aabb;
        use crate::sampling::stream::{seeded, Draw};
        let mut rng = seeded(3);
        let boxes: Vec<Aabb> = (0..600_000)
            .map(|_| {
                let c = glam::Vec3::new(rng.unit(), rng.unit(), rng.unit()) * 100.0;
                Aabb::new(c, c + glam::Vec3::splat(0.05))
            })
            .collect();
        let built = Bvh8::build(&boxes, BuildQuality::Preview);
        assert!(std::mem::size_of_val(built.nodes.as_slice()) >= MIN_BYTES);
        let mut moved = built.clone();
        let at = moved.nodes.as_ptr();
        moved.set_pages(Pages::Huge);
        assert_eq!((moved.pages, moved.nodes.as_ptr()), (Pages::Huge, at));
        let bits = |t: &Bvh8| -> Vec<u32> {
            t.nodes
                .iter()
                .flat_map(|n| {
                    n.bounds
                        .iter()
                        .flatten()
                        .map(|x| x.to_bits())
                        .chain(n.child)
                })
                .collect()
        };
        assert_eq!(bits(&moved), bits(&built));
        assert_ne!(marked_huge(&moved.nodes), Some(false));
    }
}
