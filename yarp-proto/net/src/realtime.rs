//! Real-time scheduling for threads that keep a hardware period. icub-main's Ethernet
//! receiver thread asks for SCHED_FIFO at half the maximum priority (49) and its sender
//! one below, and goes on at the normal priority when refused (no CAP_SYS_NICE, e.g. a
//! user on a laptop): so do we.

/// icub-main's `EthReceiver` priority: `sched_get_priority_max(SCHED_FIFO) / 2`.
pub const ETH_RECEIVER_PRIORITY: i32 = 49;

/// Puts the calling thread under SCHED_FIFO at `priority` (1..=99 on Linux). The error
/// says why not (EPERM without the capability); elsewhere than Linux it is Unsupported.
pub fn fifo_current_thread(priority: i32) -> std::io::Result<()> {
    #[cfg(target_os = "linux")]
    {
        let param = libc::sched_param {
            sched_priority: priority,
        };
        // SAFETY: pthread_self() is the calling thread; `param` is a valid sched_param
        // that outlives the call.
        let rc =
            unsafe { libc::pthread_setschedparam(libc::pthread_self(), libc::SCHED_FIFO, &param) };
        if rc == 0 {
            Ok(())
        } else {
            Err(std::io::Error::from_raw_os_error(rc))
        }
    }
    #[cfg(not(target_os = "linux"))]
    {
        let _ = priority;
        Err(std::io::ErrorKind::Unsupported.into())
    }
}

/// [`fifo_current_thread`] as icub-main does it: best effort, the refusal logged at
/// debug level under the thread's `role`.
pub fn try_fifo_current_thread(role: &str, priority: i32) {
    match fifo_current_thread(priority) {
        Ok(()) => tracing::debug!("{role}: SCHED_FIFO priority {priority}"),
        Err(e) => tracing::debug!("{role}: normal priority (SCHED_FIFO {priority} refused: {e})"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_refused_or_granted_request_never_panics() {
        // Root in CI is granted, a user is refused: either way the thread goes on.
        let r = std::thread::spawn(|| {
            let r = fifo_current_thread(ETH_RECEIVER_PRIORITY);
            r.map_err(|e| e.kind())
        })
        .join()
        .unwrap();
        if let Err(kind) = r {
            assert!(matches!(
                kind,
                std::io::ErrorKind::PermissionDenied | std::io::ErrorKind::Unsupported
            ));
        }
    }

    #[test]
    fn an_impossible_priority_is_an_error() {
        assert!(std::thread::spawn(|| fifo_current_thread(1000).is_err())
            .join()
            .unwrap());
    }
}
