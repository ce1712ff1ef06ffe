//! The crate's one module with `unsafe`: what the walks need of the CPU
//! and of the memory system beyond `wide`'s portable lanes, each part
//! with a safe twin and a test that holds the two to the same answers.
//!
//! - [`prefetch`]: a software prefetch of the next node or leaf block
//!   (`_mm_prefetch`); the twin prefetches nothing.
//! - [`kernel`]: the lone walks compiled a second time for AVX-512, run
//!   where the CPU has it and `STRATA_SIMD=avx512` asks (runtime
//!   dispatch; it measured slower than the build's, so `auto` keeps the
//!   build's); the twin is the build's own code.
//! - [`pages`]: the walk's arrays on huge pages (`madvise`), so that a
//!   tree larger than the caches does not miss the TLB at every node; the
//!   twin is a plain vector. And a large build's freed memory handed back
//!   to the system (`malloc_trim`); the twin keeps it.
//!
//! - [`allocator`]: the `strata` command's allocator, the system's with
//!   every large block advised for huge pages where they are cheap to
//!   write first; the twin is the system's allocator.
//!
//! Each part's doc says why its `unsafe` is sound.

#![allow(unsafe_code)]

pub mod allocator;
pub mod kernel;
pub mod pages;
pub mod prefetch;
