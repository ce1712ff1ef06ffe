//! CPU time of threads and child processes, for `strata scaling` on shared
//! machines (Linux `/proc`; `None` elsewhere).

/// Nanoseconds the calling thread has run on a CPU: the first field of
/// Linux's `/proc/thread-self/schedstat`. `None` where that file does not
/// exist (other systems, or kernels without scheduler statistics).
pub fn thread_cpu_ns() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    text.split_whitespace().next()?.parse().ok()
}

/// Clock ticks per second of `/proc/*/stat` times: Linux fixes USER_HZ at
/// 100 for user space, whatever the kernel's internal tick rate.
const USER_HZ: f64 = 100.0;

/// CPU seconds (user + system) of this process's children that have been
/// waited for: `cutime` + `cstime` of `/proc/self/stat`, in 10 ms ticks.
pub fn waited_children_cpu_seconds() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/self/stat").ok()?;
    // The command name, field 2, is in parentheses and may hold spaces.
    let rest = &text[text.rfind(')')? + 1..];
    let fields: Vec<&str> = rest.split_whitespace().collect();
    // `rest` starts at field 3 (state); cutime and cstime are fields 16 and 17.
    let cutime: u64 = fields.get(13)?.parse().ok()?;
    let cstime: u64 = fields.get(14)?.parse().ok()?;
    Some((cutime + cstime) as f64 / USER_HZ)
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

    #[test]
    fn waited_children_cpu_is_readable_where_proc_exists() {
        if std::path::Path::new("/proc/self/stat").exists() {
            let t = waited_children_cpu_seconds().expect("parse /proc/self/stat");
            assert!(t >= 0.0);
        }
    }
}
