//! Handing the heap's free pages back to the system, for programs that run for hours.
//!
//! glibc's malloc keeps the pages freed in its per-thread arenas resident. With clients
//! coming and going for hours (ROS nodes, `yarp read`, rpc clients) and large messages
//! passing through, the soak (`tests/soak/`) saw the gateway's RSS grow ~0.2 MB/min while
//! its live heap (heaptrack) stayed flat, and one `malloc_trim(0)` gave 4 MB back.

use std::time::Duration;

/// How often the long-running programs (yarpserver, yarpdev, yarprobotinterface, the
/// gateway) trim.
pub const TRIM_PERIOD: Duration = Duration::from_secs(10);

/// Starts a thread that calls glibc's `malloc_trim(0)` every `period`, handing the
/// arenas' free pages back (not all of the gateway's growth in the soak: see its
/// reports). A call walks the arenas' free chunks: short at these programs' heaps of a
/// few MB. Does nothing on other C libraries.
pub fn trim_periodically(period: Duration) {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        let spawned = std::thread::Builder::new()
            .name("heap-trim".into())
            .stack_size(64 * 1024)
            .spawn(move || loop {
                std::thread::sleep(period);
                // SAFETY: malloc_trim only returns free memory to the system; it may be
                // called from any thread at any time.
                unsafe {
                    libc::malloc_trim(0);
                }
            });
        if let Err(e) = spawned {
            tracing::debug!("no heap-trim thread: {e}");
        }
    }
    #[cfg(not(all(target_os = "linux", target_env = "gnu")))]
    let _ = period;
}
