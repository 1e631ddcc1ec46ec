//! Heap settings for programs that run for hours (yarpserver, yarpdev, yarprobotinterface,
//! the gateway).
//!
//! glibc's malloc keeps the pages freed in its per-thread arenas resident. With clients
//! coming and going for hours (ROS nodes, `yarp read`, rpc clients) and large messages
//! passing through, the soak (`tests/soak/`) saw the gateway's RSS grow ~0.2 MB/min while
//! its live heap (heaptrack) stayed flat, and one `malloc_trim(0)` gave 4 MB back.

use std::time::Duration;

/// How often the long-running programs trim.
pub const TRIM_PERIOD: Duration = Duration::from_secs(10);

/// Blocks of this size or more get a mapping of their own, for the whole run.
pub const MMAP_THRESHOLD: usize = 128 * 1024;

/// Sets up the heap of a program that runs for hours: [`keep_large_blocks_mapped`] at
/// [`MMAP_THRESHOLD`] and [`trim_periodically`] every [`TRIM_PERIOD`]. Call it early,
/// before the program's threads start allocating.
pub fn for_long_runs() {
    keep_large_blocks_mapped(MMAP_THRESHOLD);
    trim_periodically(TRIM_PERIOD);
}

/// Allocates every block of `threshold` bytes or more in a mapping of its own, which
/// goes back to the system when the block is freed.
///
/// glibc starts at 128 KiB but raises the threshold to the size of every mapped block
/// freed (up to 32 MiB). RustDDS receives datagrams into 256 KiB buffers and hands out
/// slices of them, so after the first such buffer was freed the next ones came from the
/// arenas, where a slice kept alive by a sample pinned its buffer among short-lived
/// blocks: in the fast-churn soak the gateway grew +5.5 % in 6 minutes (25.4 -> 26.8 MB),
/// and +2.7 % (21.8 -> 22.4 MB) with the threshold fixed at 128 KiB. Setting it also
/// stops glibc moving its trim threshold. Does nothing on other C libraries.
pub fn keep_large_blocks_mapped(threshold: usize) {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        let value = libc::c_int::try_from(threshold).unwrap_or(libc::c_int::MAX);
        // SAFETY: mallopt only changes malloc's parameters; it is thread-safe.
        if unsafe { libc::mallopt(libc::M_MMAP_THRESHOLD, value) } != 1 {
            tracing::debug!("mallopt(M_MMAP_THRESHOLD, {threshold}) refused");
        }
    }
    #[cfg(not(all(target_os = "linux", target_env = "gnu")))]
    let _ = threshold;
}

/// Starts a thread that calls glibc's `malloc_trim(0)` every `period`, handing the
/// arenas' free pages back. A call walks the arenas' free chunks: short at these
/// programs' heaps of a few MB. Does nothing on other C libraries.
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
