//! What this machine allows a 1 ms real-time thread, with nothing else of ours running:
//! the baseline for the Ethernet boards' "no silence over 3 periods" figure. One thread
//! per CPU, pinned, under SCHED_FIFO 49 (as the ETH receiver and the emulator's board
//! thread) wakes every 1 ms on absolute deadlines; each counts the wake-ups later than 1
//! and 2 ms (a 1 ms board woken 2 ms late leaves a silence over 3 periods), and the
//! stalls over 2 ms seen on every CPU at once are counted apart (see
//! `common/machine_stalls.rs`).
//!
//!   cargo bench -p icub-emulators --bench rt_wakeups [-- SECONDS]   (default 60)

#[path = "common/machine_stalls.rs"]
mod machine_stalls;

fn main() {
    let seconds: u64 = std::env::args()
        .skip(1)
        .find_map(|a| a.parse().ok())
        .unwrap_or(60);
    let stalls = machine_stalls::probe(seconds, yarp_net::realtime::ETH_RECEIVER_PRIORITY);
    println!(
        "rt_wakeups: {}; loadavg {}",
        stalls.summary(),
        std::fs::read_to_string("/proc/loadavg")
            .unwrap_or_default()
            .trim()
    );
}
