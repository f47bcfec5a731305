//! The CPU time of the whole process: what the benchmarks that count every thread (the tracker's, the render-ahead
//! thread, the renderer's helpers) read before and after their work.

/// CPU time of the whole process (every thread, user and system), nanoseconds.
pub fn process_cpu_ns() -> u64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid, writable timespec; CLOCK_PROCESS_CPUTIME_ID is supported on Linux.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut ts) };
    assert_eq!(rc, 0, "clock_gettime(CLOCK_PROCESS_CPUTIME_ID) failed");
    u64::try_from(ts.tv_sec).unwrap_or(0) * 1_000_000_000 + u64::try_from(ts.tv_nsec).unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cpu_time_counts_the_work_done_and_no_more() {
        let wall = std::time::Instant::now();
        let start = process_cpu_ns();
        let mut x = 0u64;
        while wall.elapsed() < std::time::Duration::from_millis(50) {
            x = std::hint::black_box(x.wrapping_mul(6364136223846793005).wrapping_add(1));
        }
        let spent = process_cpu_ns() - start;
        let elapsed = u64::try_from(wall.elapsed().as_nanos()).unwrap_or(u64::MAX);
        // Busy for 50 ms of wall time: at least a fifth of it on the CPU even on a loaded machine, and no more
        // than the wall time on every core this process may have run on.
        assert!(spent >= 10_000_000, "{spent} ns of CPU in {elapsed} ns");
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get() as u64);
        assert!(
            spent <= elapsed * cores + 5_000_000,
            "{spent} ns of CPU in {elapsed} ns"
        );
    }
}
