//! Real-time scheduling of the tracker thread.

/// Asks for `SCHED_FIFO` at `priority` for the calling thread.
#[cfg(target_os = "linux")]
pub(super) fn set_fifo_priority(priority: u8) -> Result<(), String> {
    let param = libc::sched_param {
        sched_priority: i32::from(priority),
    };
    // SAFETY: pthread_self() is the calling thread; `param` is a valid, initialised sched_param.
    let rc = unsafe { libc::pthread_setschedparam(libc::pthread_self(), libc::SCHED_FIFO, &param) };
    if rc == 0 {
        Ok(())
    } else {
        Err(format!(
            "SCHED_FIFO priority {priority} refused for the tracker thread ({}); running with normal scheduling",
            std::io::Error::from_raw_os_error(rc)
        ))
    }
}

/// Real-time scheduling is only implemented on Linux.
#[cfg(not(target_os = "linux"))]
pub(super) fn set_fifo_priority(priority: u8) -> Result<(), String> {
    Err(format!(
        "SCHED_FIFO priority {priority}: real-time scheduling is only supported on Linux; running with normal scheduling"
    ))
}
