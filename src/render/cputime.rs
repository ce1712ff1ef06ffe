//! CPU time of the calling thread, for `strata scaling` on shared machines.

/// Nanoseconds the calling thread has run on a CPU: the first field of
/// Linux's `/proc/thread-self/schedstat`. `None` where that file does not
/// exist (other systems, or kernels without scheduler statistics).
pub fn thread_cpu_ns() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    text.split_whitespace().next()?.parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cpu_time_grows_with_work_where_available() {
        let Some(before) = thread_cpu_ns() else {
            return;
        };
        let mut x = 0u64;
        for i in 0..20_000_000u64 {
            x = std::hint::black_box(x.wrapping_mul(31).wrapping_add(i));
        }
        let after = thread_cpu_ns().unwrap();
        assert!(after > before, "{x}");
    }
}
