//! The crate's one module with `unsafe`: what the walks need of the CPU
//! beyond `wide`'s portable lanes, each part with a safe twin and a test
//! that holds the two to the same answers.
//!
//! - [`prefetch`]: a software prefetch of the next node or leaf block
//!   (`_mm_prefetch`); the twin prefetches nothing.
//! - [`kernel`]: the lone walks compiled a second time for AVX-512, run
//!   where the CPU has it and `STRATA_SIMD=avx512` asks (runtime
//!   dispatch; it measured slower than the build's, so `auto` keeps the
//!   build's); the twin is the build's own code.
//!
//! Each part's doc says why its `unsafe` is sound.

#![allow(unsafe_code)]

pub mod kernel;
pub mod prefetch;
