//! What this machine allows a 1 ms real-time thread, with nothing else of ours running:
//! the baseline for the Ethernet boards' "no silence over 3 periods" figure. A thread
//! under SCHED_FIFO 49 (as the ETH receiver and the emulator's board thread) wakes every
//! 1 ms on absolute deadlines and counts the wake-ups later than 1 and 2 ms (a 1 ms board
//! woken 2 ms late leaves a silence over 3 periods).
//!
//!   cargo bench -p icub-emulators --bench rt_wakeups [-- SECONDS]   (default 60)

use std::time::Duration;

#[cfg(target_os = "linux")]
fn main() {
    let seconds: u64 = std::env::args()
        .skip(1)
        .find_map(|a| a.parse().ok())
        .unwrap_or(60);
    let fifo = yarp_net::realtime::fifo_current_thread(yarp_net::realtime::ETH_RECEIVER_PRIORITY);
    let now = || {
        let mut t = libc::timespec {
            tv_sec: 0,
            tv_nsec: 0,
        };
        // SAFETY: `t` is a valid timespec for the call to fill.
        unsafe { libc::clock_gettime(libc::CLOCK_MONOTONIC, &mut t) };
        Duration::new(t.tv_sec as u64, t.tv_nsec as u32)
    };
    let start = now();
    let mut deadline = start;
    let (mut wakeups, mut late1, mut late2, mut worst) = (0u64, 0u64, 0u64, Duration::ZERO);
    while now() - start < Duration::from_secs(seconds) {
        deadline += Duration::from_millis(1);
        let t = libc::timespec {
            tv_sec: deadline.as_secs() as libc::time_t,
            tv_nsec: deadline.subsec_nanos() as libc::c_long,
        };
        // SAFETY: `t` is a valid absolute deadline; a null remainder is allowed.
        unsafe {
            libc::clock_nanosleep(
                libc::CLOCK_MONOTONIC,
                libc::TIMER_ABSTIME,
                &t,
                std::ptr::null_mut(),
            )
        };
        let late = now().saturating_sub(deadline);
        wakeups += 1;
        worst = worst.max(late);
        if late > Duration::from_millis(1) {
            late1 += 1;
            deadline = now(); // start again from here after a stall
        }
        if late > Duration::from_millis(2) {
            late2 += 1;
        }
    }
    println!(
        "rt_wakeups: {seconds} s, SCHED_FIFO {}: {wakeups} wake-ups every 1 ms, {late1} later than 1 ms, {late2} later than 2 ms, worst {:.2} ms; loadavg {}",
        match fifo {
            Ok(()) => "granted".to_string(),
            Err(e) => format!("refused ({e})"),
        },
        worst.as_secs_f64() * 1e3,
        std::fs::read_to_string("/proc/loadavg").unwrap_or_default().trim()
    );
}

#[cfg(not(target_os = "linux"))]
fn main() {
    eprintln!("rt_wakeups: Linux only");
}
