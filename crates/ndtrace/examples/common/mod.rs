//! What the speed examples share.

/// CPU time of the calling thread in seconds, so that the figures are not distorted by other
/// processes competing for the cores. `clock_gettime(CLOCK_THREAD_CPUTIME_ID)` is exact to the
/// nanosecond; `/proc/thread-self/schedstat`, used before, only advances at scheduler ticks
/// (4 ms here) for a running thread, which made short timings move in steps of several percent.
pub fn thread_seconds() -> Option<f64> {
    #[cfg(unix)]
    {
        let mut ts = libc::timespec {
            tv_sec: 0,
            tv_nsec: 0,
        };
        // SAFETY: `ts` is a valid, writable timespec.
        let rc = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
        (rc == 0).then_some(ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9)
    }
    #[cfg(not(unix))]
    {
        None
    }
}
