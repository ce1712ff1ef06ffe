//! The one rule for every size a user or a file gives (an image's sides,
//! a texture's or an environment map's, a count of instances or rays, the
//! pixels of a partial file): the bytes it implies, compared with the
//! memory this process may use, before anything is allocated. A size past
//! it is an error naming both figures instead of an allocation that aborts
//! the process (`memory allocation of … bytes failed`, exit 134).
//!
//! The memory is the machine's (`MemTotal` of `/proc/meminfo`), or the
//! limit of the process's cgroup (`memory.max`: a container's, a Slurm
//! job's) where that is lower. Where neither can be read (not Linux), only
//! sizes no process could address are refused, and the large buffers are
//! still allocated through [`try_filled`], whose failure is an error too.

use std::fmt;
use std::sync::OnceLock;

/// The most worker threads a user may ask for (the command line's
/// `--threads`, the Python package's `threads=`): more than any machine
/// has cores, so a larger count is a typo, not a request. Unchecked, a
/// pool of 100,000 threads reserved 32 GB of stacks and never started.
pub const MAX_THREADS: usize = 4096;

/// What one process may allocate, and where that figure comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Budget {
    pub bytes: u64,
    pub source: Source,
}

/// Where a [`Budget`] was read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Source {
    /// `MemTotal` of `/proc/meminfo`.
    Machine,
    /// `memory.max` of the process's cgroup (v2), below the machine's.
    Cgroup,
    /// Given by the caller (tests of the rule itself).
    Given,
}

impl Budget {
    /// A budget of `bytes`, for checking the rule with small figures.
    pub fn given(bytes: u64) -> Self {
        Self {
            bytes,
            source: Source::Given,
        }
    }

    /// This process's budget, read once; `None` where the system does not
    /// say (not Linux).
    pub fn of_this_process() -> Option<Self> {
        static BUDGET: OnceLock<Option<Budget>> = OnceLock::new();
        *BUDGET.get_or_init(|| {
            let machine = meminfo_total()?;
            Some(match cgroup_limit() {
                Some(limit) if limit < machine => Self {
                    bytes: limit,
                    source: Source::Cgroup,
                },
                _ => Self {
                    bytes: machine,
                    source: Source::Machine,
                },
            })
        })
    }

    /// `Ok` if `need` bytes fit; else the message "`what` needs N, more
    /// than this machine's M of memory". `what` says what holds the bytes,
    /// with its figures: "a 32768×32768 image (144 bytes a pixel)".
    pub fn check(&self, need: u128, what: impl fmt::Display) -> Result<(), String> {
        if need <= u128::from(self.bytes) && need <= ADDRESSABLE {
            return Ok(());
        }
        Err(format!("{what} needs {}, {}", bytes_text(need), self))
    }
}

/// "more than this machine's 23.5 GiB of memory", as a message ends.
impl fmt::Display for Budget {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let have = bytes_text(u128::from(self.bytes));
        match self.source {
            Source::Machine => write!(f, "more than this machine's {have} of memory"),
            Source::Cgroup => write!(
                f,
                "more than the {have} this process may use (its cgroup's memory.max)"
            ),
            Source::Given => write!(f, "more than the {have} allowed"),
        }
    }
}

/// The most one allocation can be on any machine (Rust's limit for one
/// object): refused even where the machine's memory is not known.
const ADDRESSABLE: u128 = isize::MAX as u128;

/// Check `need` bytes for `what` against this process's [`Budget`]; see
/// [`Budget::check`].
pub fn check(need: u128, what: impl fmt::Display) -> Result<(), String> {
    check_against(Budget::of_this_process(), need, what)
}

/// [`check`] against `budget`; where it is unknown, only sizes past what
/// a process can address are refused.
pub fn check_against(
    budget: Option<Budget>,
    need: u128,
    what: impl fmt::Display,
) -> Result<(), String> {
    match budget {
        Some(budget) => budget.check(need, what),
        None if need > ADDRESSABLE => Err(format!(
            "{what} needs {}, more than a process can address",
            bytes_text(need)
        )),
        None => Ok(()),
    }
}

/// Check an image of `width` × `height` that will hold `bytes_per_texel`
/// bytes for each texel at once (decoded, converted and kept). `what` names
/// it: "a texture", "an environment map".
pub fn check_image_size(
    what: &str,
    width: u32,
    height: u32,
    bytes_per_texel: u64,
) -> Result<(), String> {
    let need = u128::from(width) * u128::from(height) * u128::from(bytes_per_texel);
    check(
        need,
        format_args!(
            "{what} of {width}×{height} texels ({bytes_per_texel} bytes a texel while decoded)"
        ),
    )
}

/// Check an encoded image (`bytes`, whose format its first bytes tell)
/// before decoding it, from the size its header claims: the decoder's own
/// texels (their colour type's bytes) and `kept_per_texel` bytes that the
/// caller converts them into. A format the header reader does not know,
/// or a header it cannot read, passes: the decoder then says what is wrong.
pub fn check_image(what: &str, bytes: &[u8], kept_per_texel: u64) -> Result<(), String> {
    use image::ImageDecoder;
    let Ok(reader) = image::ImageReader::new(std::io::Cursor::new(bytes)).with_guessed_format()
    else {
        return Ok(());
    };
    let mut reader = reader;
    // The header alone: the decoder's own 512 MiB limit would refuse a
    // large header before it could be named here.
    reader.no_limits();
    let Ok(decoder) = reader.into_decoder() else {
        return Ok(());
    };
    let (width, height) = decoder.dimensions();
    let decoded = u64::from(decoder.color_type().bytes_per_pixel());
    check_image_size(what, width, height, decoded + kept_per_texel)
}

/// The image decoder's limits for an image that [`check_image`] passed:
/// no more than this process's budget, where the decoder's default (512
/// MiB) would refuse images this machine holds easily.
pub fn decoder_limits() -> image::Limits {
    let mut limits = image::Limits::default();
    limits.max_alloc = Budget::of_this_process().map(|b| b.bytes);
    limits
}

/// `n` copies of `value` in a new `Vec`, or an error naming `what` where
/// the allocation fails (instead of the abort of `vec![value; n]`).
pub fn try_filled<T: Clone>(n: usize, value: T, what: &str) -> Result<Vec<T>, String> {
    let mut v = Vec::new();
    v.try_reserve_exact(n).map_err(|_| {
        let need = n as u128 * std::mem::size_of::<T>() as u128;
        format!("cannot allocate {what}: {} not available", bytes_text(need))
    })?;
    v.resize(n, value);
    Ok(v)
}

/// Bytes in words: `812 bytes`, `3.4 MiB`, `150.0 GiB`.
pub fn bytes_text(bytes: u128) -> String {
    const UNITS: [&str; 6] = ["KiB", "MiB", "GiB", "TiB", "PiB", "EiB"];
    if bytes < 1024 {
        return format!("{bytes} bytes");
    }
    let mut value = bytes as f64 / 1024.0;
    let mut unit = 0;
    while value >= 1024.0 && unit + 1 < UNITS.len() {
        value /= 1024.0;
        unit += 1;
    }
    format!("{value:.1} {}", UNITS[unit])
}

/// `MemTotal` of `/proc/meminfo`, in bytes.
fn meminfo_total() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    meminfo_field(&text, "MemTotal:")
}

fn meminfo_field(text: &str, field: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with(field))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kb.checked_mul(1024)
}

/// The `memory.max` of this process's cgroup (v2), where it sets one: the
/// line `0::/PATH` of `/proc/self/cgroup` names the group under
/// `/sys/fs/cgroup`.
fn cgroup_limit() -> Option<u64> {
    let groups = std::fs::read_to_string("/proc/self/cgroup").ok()?;
    let path = groups.lines().find_map(|l| l.strip_prefix("0::"))?;
    let file = format!("/sys/fs/cgroup{}/memory.max", path.trim_end_matches('/'));
    // "max" where there is no limit: not a number, so none.
    std::fs::read_to_string(file).ok()?.trim().parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_need_past_the_budget_names_both_figures() {
        let budget = Budget::given(1 << 30);
        assert!(budget.check(1 << 30, "exactly").is_ok());
        let e = budget.check((1 << 30) + 1, "a 2×2 image").unwrap_err();
        assert_eq!(
            e,
            "a 2×2 image needs 1.0 GiB, more than the 1.0 GiB allowed"
        );
        let e = budget.check(150 << 30, "x").unwrap_err();
        assert!(e.contains("150.0 GiB"), "{e}");
        // Past what any process can address, whatever the machine has.
        assert!(Budget::given(u64::MAX).check(u128::MAX, "x").is_err());
        assert!(check(u128::MAX, "x").is_err());
    }

    #[test]
    fn byte_counts_read_in_binary_units() {
        assert_eq!(bytes_text(812), "812 bytes");
        assert_eq!(bytes_text(1536), "1.5 KiB");
        assert_eq!(bytes_text(51_539_607_552), "48.0 GiB");
        assert_eq!(bytes_text(u128::MAX), "295147905179352825856.0 EiB");
    }

    #[test]
    fn the_machines_memory_is_read_from_meminfo() {
        let text = "MemTotal:       24684096 kB\nMemFree:        11972060 kB\n";
        assert_eq!(meminfo_field(text, "MemTotal:"), Some(24684096 * 1024));
        assert_eq!(meminfo_field(text, "SwapTotal:"), None);
        if cfg!(target_os = "linux") {
            let b = Budget::of_this_process().expect("Linux has /proc/meminfo");
            assert!(b.bytes > 1 << 20);
        }
    }

    #[test]
    fn a_failed_allocation_is_an_error_naming_what() {
        let e = try_filled(usize::MAX / 2, 0u64, "the film").unwrap_err();
        assert!(e.starts_with("cannot allocate the film:"), "{e}");
        assert_eq!(try_filled(3, 7u8, "x").unwrap(), [7, 7, 7]);
    }

    /// PNG's chunk checksum (CRC-32, reflected, polynomial 0xEDB88320).
    fn crc32(bytes: &[u8]) -> u32 {
        let mut crc = !0u32;
        for &b in bytes {
            crc ^= u32::from(b);
            for _ in 0..8 {
                crc = if crc & 1 == 1 {
                    (crc >> 1) ^ 0xEDB8_8320
                } else {
                    crc >> 1
                };
            }
        }
        !crc
    }

    /// An image's header is read for its size, and a claim past the
    /// budget refused before a texel is decoded.
    #[test]
    fn an_image_header_claiming_a_huge_size_is_refused() {
        let mut png = Vec::new();
        image::RgbImage::new(2, 2)
            .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
            .unwrap();
        assert!(check_image("a texture", &png, 6).is_ok());
        // IHDR's width and height, bytes 16..24, and the chunk's CRC.
        png[16..20].copy_from_slice(&1_000_000u32.to_be_bytes());
        png[20..24].copy_from_slice(&1_000_000u32.to_be_bytes());
        let crc = crc32(&png[12..29]);
        png[29..33].copy_from_slice(&crc.to_be_bytes());
        let e = check_image("a texture", &png, 6).unwrap_err();
        assert!(e.starts_with("a texture of 1000000×1000000 texels"), "{e}");
        assert!(check_image("x", b"not an image", 6).is_ok());
    }
}
