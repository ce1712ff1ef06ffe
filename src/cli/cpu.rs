//! The start-up check that this CPU runs what the binary was built for.
//!
//! `.cargo/config.toml` builds for x86-64-v3 (AVX2 and FMA), so that a
//! `wide::f32x8` is one AVX register. On an older CPU such a binary would die
//! with SIGILL at its first AVX instruction; this check runs first and
//! explains instead. It must not itself contain an AVX (VEX-encoded)
//! instruction, so it is integer code only: CPUID bits, static messages,
//! no formatting. `std::arch::is_x86_feature_detected!` will not do: it
//! answers `true` at compile time for features the build assumes.

/// CPU features, as bits of [`cpu_features`].
pub const AVX2: u32 = 1;
pub const FMA: u32 = 2;

/// The AVX2 and FMA bits this CPU reports through CPUID (and whether the
/// operating system saves AVX state, without which AVX faults too).
#[cfg(target_arch = "x86_64")]
#[inline(never)]
pub fn cpu_features() -> u32 {
    use std::arch::x86_64::__cpuid_count;
    let basic = __cpuid_count(0, 0);
    if basic.eax < 7 {
        return 0;
    }
    let leaf1 = __cpuid_count(1, 0);
    let (osxsave, avx, fma) = (
        leaf1.ecx >> 27 & 1,
        leaf1.ecx >> 28 & 1,
        leaf1.ecx >> 12 & 1,
    );
    if osxsave == 0 || avx == 0 {
        return 0;
    }
    let avx2 = __cpuid_count(7, 0).ebx >> 5 & 1;
    (avx2 * AVX2) | (fma * FMA)
}

#[cfg(not(target_arch = "x86_64"))]
pub fn cpu_features() -> u32 {
    AVX2 | FMA
}

/// The features this binary was compiled to use.
pub fn built_for() -> u32 {
    (if cfg!(target_feature = "avx2") {
        AVX2
    } else {
        0
    }) | (if cfg!(target_feature = "fma") { FMA } else { 0 })
}

/// The one-line error for a CPU that lacks `missing` (bits), or `None`.
/// Whole static strings: formatting would run code built for AVX.
#[inline(never)]
pub fn message(missing: u32) -> Option<&'static str> {
    macro_rules! lacks {
        ($what:literal) => {
            concat!(
                "error: this strata was built for x86-64-v3 CPUs, and this CPU lacks ",
                $what,
                "; rebuild it for this machine with RUSTFLAGS=\"-C target-cpu=native\" cargo install --path . (or RUSTFLAGS=\"\" for a portable build)\n"
            )
        };
    }
    match missing & (AVX2 | FMA) {
        0 => None,
        AVX2 => Some(lacks!("avx2")),
        FMA => Some(lacks!("fma")),
        _ => Some(lacks!("avx2 and fma")),
    }
}

/// Exit with code 1 and the message if this CPU cannot run this binary.
#[inline(never)]
pub fn require_built_for_features() {
    use std::io::Write;
    if let Some(m) = message(built_for() & !cpu_features()) {
        let _ = std::io::stderr().write_all(m.as_bytes());
        std::process::exit(1);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cpu_without_the_built_for_features_gets_a_message_naming_them() {
        assert_eq!(message(0), None);
        assert!(message(AVX2).unwrap().contains("lacks avx2;"));
        assert!(message(FMA).unwrap().contains("lacks fma;"));
        assert!(message(AVX2 | FMA).unwrap().contains("lacks avx2 and fma"));
        assert!(message(AVX2).unwrap().contains("target-cpu=native"));
        // This machine runs the tests, so it has what the build assumes.
        assert_eq!(built_for() & !cpu_features(), 0);
        if cfg!(target_feature = "avx2") {
            assert_eq!(built_for() & AVX2, AVX2);
        }
    }
}
