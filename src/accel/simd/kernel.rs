//! Which instruction set the hot walks run in: the build's own (AVX2 and
//! FMA under the default x86-64-v3 target, SSE2 in the portable build), or
//! a copy of the same code compiled for AVX-512 where the CPU has it and
//! `STRATA_SIMD=avx512` asks for it (it measured slower than the build's
//! on the CPUs tried), chosen once per process (runtime dispatch). One of the two parts of [`super`], the crate's one
//! module with `unsafe`; the other is `prefetch`.
//!
//! A [`Kernel`] runs a closure inside a function of its own: the build's
//! kernel in one compiled for the build's target, the AVX-512 kernel in
//! one compiled with
//! `#[target_feature(enable = "avx512f,avx512vl,avx512bw,avx512dq")]`.
//! Everything the closure inlines (the walks, node tests and leaf tests
//! are `#[inline(always)]`, so the whole lone walk) is then compiled a
//! second time for AVX-512: `wide`'s 8-lane types keep their AVX2
//! intrinsics, which LLVM re-encodes as EVEX with 32 vector registers and
//! mask registers for compares (docs/performance.md, "AVX-512 by runtime
//! dispatch", says what that changes). The arithmetic is the same IEEE
//! operations in the same order (Rust never contracts a multiply and an
//! add into an FMA on its own), so both kernels give the same hits bit
//! for bit, which `tests/suite/kernels.rs` checks.
//!
//! Safety: calling a `#[target_feature]` function on a CPU without those
//! features is undefined behaviour (an illegal instruction at best). A
//! [`Kernel`] that names AVX-512 can only be made by [`Kernel::avx512`],
//! which returns it only where `is_x86_feature_detected!` reports all
//! four features at run time (that macro also checks that the operating
//! system saves the AVX-512 state); so [`Kernel::run`] calls the AVX-512
//! copy only on a CPU that runs it. The safe twin is the same closure
//! called directly ([`Kernel::build`]).

use std::sync::atomic::{AtomicU8, Ordering};

/// An instruction set the hot walks can run in, proven available: a value
/// naming AVX-512 exists only on a CPU that has it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Kernel(Isa);

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
enum Isa {
    /// What the build targets: AVX2 and FMA by default, SSE2 portable.
    Build,
    /// The same code compiled for AVX-512 (F, VL, BW, DQ).
    Avx512,
}

/// The name of the build's own kernel.
const BUILD_NAME: &str = if cfg!(target_feature = "avx2") {
    "avx2"
} else {
    "sse2"
};

/// The kernel in use: 0 while undecided, else 1 + the [`Isa`] index.
static SELECTED: AtomicU8 = AtomicU8::new(0);

impl Kernel {
    /// The build's own kernel, which every CPU that runs the binary runs.
    pub const fn build() -> Self {
        Self(Isa::Build)
    }

    /// The AVX-512 kernel, where this CPU (and its operating system) runs
    /// AVX-512 F, VL, BW and DQ.
    pub fn avx512() -> Option<Self> {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx512f")
            && std::arch::is_x86_feature_detected!("avx512vl")
            && std::arch::is_x86_feature_detected!("avx512bw")
            && std::arch::is_x86_feature_detected!("avx512dq")
        {
            return Some(Self(Isa::Avx512));
        }
        None
    }

    /// The kernel `auto` picks: the build's. The AVX-512 copy measured
    /// slower on both CPUs it ran on, an AMD Zen 4 and an Intel Xeon (0.96×
    /// the build's over the dragon's ray kinds on each, docs/performance.md,
    /// "AVX-512 by runtime dispatch"): the walks' 8-wide lanes gain only
    /// the extra registers, so it stays for `STRATA_SIMD=avx512` to measure.
    pub fn detect() -> Self {
        Self::build()
    }

    /// Every kernel this CPU runs, the build's first.
    pub fn available() -> Vec<Self> {
        std::iter::once(Self::build())
            .chain(Self::avx512())
            .collect()
    }

    /// Its name: `avx2` (or `sse2` in a portable build) or `avx512`.
    pub fn name(self) -> &'static str {
        match self.0 {
            Isa::Build => BUILD_NAME,
            Isa::Avx512 => "avx512",
        }
    }

    /// The kernel a name asks for (`auto`: [`Kernel::detect`]'s); an error
    /// names the accepted ones, or says that this CPU lacks AVX-512.
    pub fn parse(name: &str) -> Result<Self, String> {
        match name {
            "auto" => Ok(Self::detect()),
            "avx512" => Self::avx512().ok_or_else(|| {
                "avx512: this CPU lacks AVX-512 (F, VL, BW and DQ); use auto or ".to_string()
                    + BUILD_NAME
            }),
            _ if name == BUILD_NAME => Ok(Self::build()),
            _ => Err(format!(
                "'{name}' is not a kernel: expected auto, {BUILD_NAME} or avx512"
            )),
        }
    }

    /// The kernel the hot walks of this process use: the one [`Kernel::set`]
    /// chose, else [`Kernel::detect`]'s, decided at the first call.
    #[inline(always)]
    pub fn selected() -> Self {
        match SELECTED.load(Ordering::Relaxed) {
            1 => Self(Isa::Build),
            2 => Self(Isa::Avx512),
            _ => Self::decide(),
        }
    }

    #[cold]
    #[inline(never)]
    fn decide() -> Self {
        let k = Self::detect();
        // A `set` that came first wins.
        let _ = SELECTED.compare_exchange(0, k.code(), Ordering::Relaxed, Ordering::Relaxed);
        Self::selected()
    }

    /// Makes `self` the kernel of every later walk in this process (the
    /// command line's `STRATA_SIMD`). Both kernels give the same hits, so
    /// a walk under way when it changes answers the same.
    pub fn set(self) {
        SELECTED.store(self.code(), Ordering::Relaxed);
    }

    fn code(self) -> u8 {
        match self.0 {
            Isa::Build => 1,
            Isa::Avx512 => 2,
        }
    }

    /// Runs `f` compiled for this kernel: inside a function of its own
    /// compiled for the build's target or for AVX-512, into which `f`
    /// (marked `#[inline(always)]`) is inlined. Whatever `f` calls without
    /// inlining runs the build's code.
    ///
    /// Both copies are functions of their own, so the build's copy is
    /// compiled as it was before there was a choice: with the AVX-512
    /// call beside it in one function, the register allocation of the
    /// build's walk changed and a random bunny ray took 30 more
    /// instructions (docs/performance.md, "AVX-512 by runtime dispatch").
    #[inline(always)]
    pub fn run<R>(self, f: impl FnOnce() -> R) -> R {
        #[cfg(target_arch = "x86_64")]
        if self.0 == Isa::Avx512 {
            // SAFETY: a Kernel naming AVX-512 is made only by
            // `Kernel::avx512`, after `is_x86_feature_detected!` found
            // every feature `in_avx512` is compiled for (module docs).
            return unsafe { in_avx512(f) };
        }
        in_build(f)
    }
}

/// `f`, compiled for the build's target, in a function of its own.
#[inline(never)]
fn in_build<R>(f: impl FnOnce() -> R) -> R {
    f()
}

/// `f`, compiled for AVX-512, in a function of its own: LLVM inlines a callee whose features are a
/// subset of its caller's, so `f` and its `#[inline(always)]` callees are
/// generated here with EVEX encodings available.
///
/// # Safety
/// Only on a CPU with AVX-512 F, VL, BW and DQ.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512vl,avx512bw,avx512dq")]
unsafe fn in_avx512<R>(f: impl FnOnce() -> R) -> R {
    f()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_parse_back_and_unknown_ones_say_what_is_accepted() {
        for k in Kernel::available() {
            assert_eq!(Kernel::parse(k.name()), Ok(k));
        }
        assert_eq!(Kernel::parse("auto"), Ok(Kernel::detect()));
        let e = Kernel::parse("avx9").unwrap_err();
        assert!(e.contains("'avx9'") && e.contains("avx512"), "{e}");
        assert_eq!(Kernel::detect(), Kernel::build());
        match Kernel::avx512() {
            Some(k) => assert_eq!(Kernel::parse("avx512"), Ok(k)),
            None => assert!(Kernel::parse("avx512").unwrap_err().contains("lacks")),
        }
    }

    /// The AVX-512 copy computes what the build's does, float for float
    /// (skipped where the CPU lacks AVX-512).
    #[test]
    fn every_kernel_runs_the_same_arithmetic() {
        let work = || {
            let x = wide::f32x8::new([1.0, -2.5, 3.0e-39, 7.0, 1e30, -0.0, 0.1, 3.3]);
            let y = x.mul_add(x, wide::f32x8::splat(0.3)) / (x + wide::f32x8::splat(2.0));
            (y.to_array(), x.simd_lt(y).to_bitmask())
        };
        let expected = Kernel::build().run(work);
        for k in Kernel::available() {
            let got = k.run(work);
            assert_eq!(got.0.map(f32::to_bits), expected.0.map(f32::to_bits));
            assert_eq!(got.1, expected.1, "{}", k.name());
        }
    }
}
