//! The `strata` command's allocator: the system's, with every large
//! allocation (4 MiB and more: a mesh's arrays, a build's buffers, the
//! tree) advised for huge pages where they cost no more to write first
//! than small ones ([`HugePages`]). One of the parts of [`super`], the
//! crate's one module with `unsafe`.
//!
//! A huge mesh's first image writes about 3.4 GB of fresh memory on the
//! way (250 bytes a triangle of dragon-sub2), and on 4 KiB pages each page
//! is a fault into the kernel: 840,000 of them, a quarter of the process's
//! time on one thread, and on 16 threads a queue on the kernel's
//! page-table locks. With every large block on huge pages (glibc's
//! `glibc.malloc.hugetlb=1`, measured first) the faults were 74,000, and
//! on the lent 16-core Xeon the medium build of dragon-sub2 gained 10.5×
//! and 9.6× over one thread in two runs, against 8.0× to 8.6× on small
//! pages; with this allocator 10.0× against 9.2× with it off, 0.51 s
//! against 0.59 s on 16 threads (docs/performance.md, "Huge pages for the
//! build").
//!
//! Where a virtual machine hands the memory a process frees back to its
//! host (Linux's free page reporting, as on the workplace's two-core VMs
//! once they have run a while), a fresh huge page waits for the host to
//! back 2 MiB at once, and the same build took half as long again; so
//! [`HugePages::Auto`] asks for them only where the kernel has reported
//! nothing to a host ([`huge_pages_are_cheap`]). Images, hits and trees
//! are the same either way: only where the bytes lie changes.
//!
//! Why the `unsafe` is sound: each method passes its caller's contract on
//! to [`System`] unchanged; the advice is `madvise(MADV_HUGEPAGE)` on
//! whole pages inside the block just returned ([`super::pages`]), which
//! changes no byte, permission or mapping the process sees. The twin is
//! [`System`] itself (`HugePages::Off`, and every process that does not
//! install this allocator, as the Python package does not); the tests
//! hold the two to the same bytes and check the kernel records the
//! advice.

use super::pages::{advise_huge, MIN_BYTES};
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicBool, Ordering::Relaxed};

/// Whether large allocations are advised now (set once, at the start).
static LARGE_ON_HUGE_PAGES: AtomicBool = AtomicBool::new(false);

/// Where large allocations go: `STRATA_HUGE_PAGES` (docs/cli.md).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum HugePages {
    /// On huge pages where they are cheap ([`huge_pages_are_cheap`]).
    #[default]
    Auto,
    /// On huge pages wherever the kernel gives them.
    On,
    /// On the system's own pages.
    Off,
}

impl HugePages {
    /// `auto`, `on` or `off`.
    pub fn parse(name: &str) -> Result<Self, String> {
        match name {
            "auto" => Ok(Self::Auto),
            "on" => Ok(Self::On),
            "off" => Ok(Self::Off),
            other => Err(format!("'{other}': expected auto, on or off")),
        }
    }

    /// Applies the choice to the allocator of this process. In a process
    /// that has not installed [`HugePageAllocator`] only the tree's pages
    /// follow it ([`large_allocations_on_huge_pages`]).
    pub fn apply(self) {
        let on = match self {
            Self::Auto => huge_pages_are_cheap(),
            Self::On => true,
            Self::Off => false,
        };
        LARGE_ON_HUGE_PAGES.store(on, Relaxed);
    }
}

/// Whether large allocations are advised for huge pages in this process.
pub fn large_allocations_on_huge_pages() -> bool {
    LARGE_ON_HUGE_PAGES.load(Relaxed)
}

/// Whether huge pages cost no more to write first than small ones here:
/// Linux with transparent huge pages not set to `never`, whose kernel has
/// reported no freed memory to a host (`reported_kib` of the
/// `page_reporting` module 0, or no such module: bare metal, or a virtual
/// machine that does not report). A fresh virtual machine reports nothing
/// yet, and a fresh huge page cost it less than 512 small ones (0.13
/// against 0.33 s for 600 MB on the lent Xeon); once a VM has handed
/// memory back, its pages come from the host again, 2 MiB at a time.
pub fn huge_pages_are_cheap() -> bool {
    if !cfg!(target_os = "linux") {
        return false;
    }
    let read = |path: &str| std::fs::read_to_string(path).ok();
    match read("/sys/kernel/mm/transparent_hugepage/enabled") {
        Some(modes) if !modes.contains("[never]") => {}
        _ => return false,
    }
    match read("/sys/module/page_reporting/parameters/reported_kib") {
        Some(kib) => kib.trim() == "0",
        None => true,
    }
}

/// The system's allocator, large blocks advised for huge pages while
/// [`large_allocations_on_huge_pages`]. The `strata` binary's global
/// allocator.
pub struct HugePageAllocator;

/// Advises the fresh block `ptr` of `size` bytes if it is large and
/// `asked` (the process's switch; read only for a large block, so that
/// the allocations of every size pay for one comparison alone).
fn advise_large(ptr: *mut u8, size: usize, asked: fn() -> bool) {
    if size >= MIN_BYTES && !ptr.is_null() && asked() {
        advise_huge(ptr as usize, size);
    }
}

// SAFETY: every method is `System`'s with the same arguments (the
// caller's contract passed on unchanged); `advise_large` only advises
// whole pages inside the block `System` returned (see the module's doc).
unsafe impl GlobalAlloc for HugePageAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let ptr = unsafe { System.alloc(layout) };
        advise_large(ptr, layout.size(), large_allocations_on_huge_pages);
        ptr
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        let ptr = unsafe { System.alloc_zeroed(layout) };
        advise_large(ptr, layout.size(), large_allocations_on_huge_pages);
        ptr
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let moved = unsafe { System.realloc(ptr, layout, new_size) };
        if new_size > layout.size() {
            advise_large(moved, new_size, large_allocations_on_huge_pages);
        }
        moved
    }
}

#[cfg(test)]
mod tests {
    use super::super::pages::marked_huge;
    use super::*;

    /// A block from the allocator, advised or not, holds what is written
    /// into it, grown and zeroed as `System`'s would; where the kernel has
    /// transparent huge pages a large advised block's mapping is marked
    /// for them and a plain one's is not. (The process-wide switch is left
    /// alone: other tests run beside this one.)
    #[test]
    fn advised_blocks_hold_what_plain_ones_do() {
        let size = 16 * MIN_BYTES;
        let layout = Layout::from_size_align(size, 64).unwrap();
        for on in [false, true] {
            // SAFETY: a non-zero layout; every access below is inside the
            // block, which is freed once, with its layout.
            unsafe {
                let ptr = System.alloc_zeroed(layout);
                assert!(!ptr.is_null());
                advise_large(ptr, size, if on { || true } else { || false });
                let bytes = std::slice::from_raw_parts_mut(ptr, size);
                assert!(bytes.iter().step_by(4096).all(|&b| b == 0));
                for (i, b) in bytes.iter_mut().enumerate().step_by(1000) {
                    *b = (i % 251) as u8;
                }
                let marked = marked_huge(bytes);
                let grown = HugePageAllocator.realloc(ptr, layout, 2 * size);
                assert!(!grown.is_null());
                let kept = std::slice::from_raw_parts(grown, size);
                assert!(kept
                    .iter()
                    .enumerate()
                    .step_by(1000)
                    .all(|(i, &b)| b == (i % 251) as u8));
                HugePageAllocator.dealloc(grown, Layout::from_size_align(2 * size, 64).unwrap());
                if let Some(marked) = marked {
                    assert_eq!(marked, on, "advised {on}");
                }
            }
        }
        assert_eq!(HugePages::parse("auto"), Ok(HugePages::Auto));
        assert_eq!(HugePages::parse("off"), Ok(HugePages::Off));
        assert!(HugePages::parse("huge")
            .unwrap_err()
            .contains("auto, on or off"));
    }
}
