//! What this machine allows a 1 ms real-time thread: one thread per CPU, each pinned to
//! its CPU under SCHED_FIFO, waking every 1 ms on absolute deadlines. A wake-up more than
//! 2 ms late is a stall (a 1 ms board's stream then shows a silence over 3 periods, and
//! no thread of ours on that CPU could have done better); a stall that overlaps a stall
//! on every other CPU by more than 1 ms is machine-wide: no placement of the work on
//! any CPU could have avoided it.

use std::time::Duration;

/// The probe's findings.
#[derive(Debug, Default)]
pub struct Stalls {
    pub seconds: u64,
    pub fifo: Option<String>,
    /// Per CPU: wake-ups, later than 1 ms, later than 2 ms (stalls), the worst.
    pub per_cpu: Vec<(usize, u64, u64, u64, Duration)>,
    /// Stalls of the first CPU that overlap a stall on every other CPU by over 1 ms.
    pub machine_wide: u64,
}

impl Stalls {
    pub fn summary(&self) -> String {
        let cpus: Vec<String> = self
            .per_cpu
            .iter()
            .map(|(cpu, w, l1, l2, worst)| {
                format!(
                    "cpu{cpu}: {w} wake-ups, {l1} later than 1 ms, {l2} later than 2 ms, worst {:.2} ms",
                    worst.as_secs_f64() * 1e3
                )
            })
            .collect();
        format!(
            "{} s, SCHED_FIFO {}: {}; {} stalls over 2 ms on every CPU at once",
            self.seconds,
            self.fifo.as_deref().unwrap_or("granted"),
            cpus.join("; "),
            self.machine_wide
        )
    }
}

#[cfg(target_os = "linux")]
fn now() -> Duration {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `t` is a valid timespec for the call to fill.
    unsafe { libc::clock_gettime(libc::CLOCK_MONOTONIC, &mut t) };
    Duration::new(t.tv_sec as u64, t.tv_nsec as u32)
}

/// One pinned thread: its counts and its stalls as (start, end) on CLOCK_MONOTONIC.
#[cfg(target_os = "linux")]
#[allow(clippy::type_complexity)]
fn probe_cpu(
    cpu: usize,
    priority: i32,
    until: Duration,
) -> (
    Result<(), String>,
    (u64, u64, u64, Duration),
    Vec<(Duration, Duration)>,
) {
    // SAFETY: a zeroed cpu_set_t is a valid empty set; CPU_SET and the affinity call get
    // valid pointers to it, for the calling thread (pid 0).
    unsafe {
        let mut set: libc::cpu_set_t = std::mem::zeroed();
        libc::CPU_SET(cpu, &mut set);
        libc::sched_setaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &set);
    }
    let fifo = yarp_net::realtime::fifo_current_thread(priority).map_err(|e| e.to_string());
    let mut deadline = now();
    let (mut wakeups, mut late1, mut late2, mut worst) = (0u64, 0u64, 0u64, Duration::ZERO);
    let mut stalls = Vec::new();
    while now() < until {
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
        let woke = now();
        let late = woke.saturating_sub(deadline);
        wakeups += 1;
        worst = worst.max(late);
        if late > Duration::from_millis(2) {
            late2 += 1;
            stalls.push((deadline, woke));
        }
        if late > Duration::from_millis(1) {
            late1 += 1;
            deadline = woke; // start again from here after a stall
        }
    }
    (fifo, (wakeups, late1, late2, worst), stalls)
}

/// Runs the probe for `seconds` on every online CPU at SCHED_FIFO `priority`.
#[cfg(target_os = "linux")]
pub fn probe(seconds: u64, priority: i32) -> Stalls {
    let cpus = std::thread::available_parallelism().map_or(1, |n| n.get());
    let until = now() + Duration::from_secs(seconds);
    let threads: Vec<_> = (0..cpus)
        .map(|cpu| std::thread::spawn(move || probe_cpu(cpu, priority, until)))
        .collect();
    let results: Vec<_> = threads.into_iter().filter_map(|t| t.join().ok()).collect();
    let mut out = Stalls {
        seconds,
        ..Default::default()
    };
    for (cpu, (fifo, (w, l1, l2, worst), _)) in results.iter().enumerate() {
        if let Err(e) = fifo {
            out.fifo = Some(format!("refused ({e})"));
        }
        out.per_cpu.push((cpu, *w, *l1, *l2, *worst));
    }
    let overlaps = |a: &(Duration, Duration), b: &(Duration, Duration)| {
        let start = a.0.max(b.0);
        let end = a.1.min(b.1);
        end > start + Duration::from_millis(1)
    };
    if let Some((first, rest)) = results.split_first() {
        out.machine_wide = first
            .2
            .iter()
            .filter(|s| rest.iter().all(|r| r.2.iter().any(|o| overlaps(s, o))))
            .count() as u64;
    }
    out
}

#[cfg(not(target_os = "linux"))]
pub fn probe(seconds: u64, _priority: i32) -> Stalls {
    Stalls {
        seconds,
        fifo: Some("unsupported: Linux only".into()),
        ..Default::default()
    }
}
