//! CPU of the Cartesian controller at rest and while it moves the arm, ours beside
//! icub-main's C++ server in one run, for BENCHMARKS.md. Each side is a process holding
//! two fake boards, their wrappers and the server (C++: yarprobotinterface; ours: this
//! bench, which also holds the name server), with our solver in its own process; the
//! C++ client moves each arm through three poses (trajectory time 1 s).
//!
//! Run under netns-run: `../shared/netns-run cargo bench -p icub-cartesian --bench controllers_cpu`.

#[path = "../tests/common/mod.rs"]
mod common;

use common::*;
use std::time::{Duration, Instant};

/// CPU seconds used so far by process `pid` (utime + stime of /proc/PID/stat).
fn cpu_seconds(pid: u32) -> f64 {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).unwrap_or_default();
    // fields after the command's closing parenthesis: state is field 3, utime 14, stime 15
    let rest = stat.rsplit_once(')').map_or("", |(_, r)| r);
    let f: Vec<f64> = rest
        .split_whitespace()
        .map(|v| v.parse().unwrap_or(0.0))
        .collect();
    let ticks = 100.0; // sysconf(_SC_CLK_TCK) on Linux
    (f.get(11).copied().unwrap_or(0.0) + f.get(12).copied().unwrap_or(0.0)) / ticks
}

/// CPU share (percent of one core) of `pid` at rest over `secs`, then while the C++
/// client moves the arm on `ctrl`.
fn measure(pid: u32, ctrl: &str, program: &std::path::Path) -> (f64, f64, f64) {
    let secs = 10.0;
    let c0 = cpu_seconds(pid);
    std::thread::sleep(Duration::from_secs_f64(secs));
    let rest = (cpu_seconds(pid) - c0) / secs * 100.0;
    let (c0, t0) = (cpu_seconds(pid), Instant::now());
    let times = run_cpp_client("controllers_cpu", program, ctrl, 1.0);
    let moving = (cpu_seconds(pid) - c0) / t0.elapsed().as_secs_f64() * 100.0;
    (rest, moving, times.iter().sum::<f64>() / times.len() as f64)
}

fn main() {
    if std::env::args().any(|a| a == "--list") {
        return; // `cargo test --benches` lists benches: nothing to list here
    }
    let test = "controllers_cpu";
    let Some(program) = cpp_client(test) else {
        return;
    };
    yarp_interop_tests::name_server();
    let Some(cpp) = cpp_stack(test) else {
        return;
    };
    wait_solver(test, "/cpp/cartesianController/left_arm");
    let theirs = measure(cpp.0 .0.id(), "/cpp/cartesianController/left_arm", &program);
    drop(cpp);
    let _robot = up(test);
    wait_solver(test, CTRL);
    let ours = measure(std::process::id(), CTRL, &program);
    println!("cartesiancontrollerserver, left arm, period 10 ms (CPU % of one core)");
    println!("| | at rest | moving | time per pose (T = 1 s, tol 1 mm) |");
    println!("|---|---|---|---|");
    for (who, (rest, moving, t)) in [("C++ icub-main 2.11.1", theirs), ("ours", ours)] {
        println!("| {who} | {rest:.1} % | {moving:.1} % | {t:.2} s |");
    }
}
