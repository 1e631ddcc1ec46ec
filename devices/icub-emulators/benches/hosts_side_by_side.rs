//! Our Ethernet host and icub-main's, side by side on the same emulated robots (a bench
//! program, not a timed test): iCubGenova02 and ergoCubSN001 (without its waist MTi and
//! wholebodydynamics, which `../shared/peers` does not build), each brought up by C++
//! `yarprobotinterface` 3.12.3 with icub-main 2.11.1's plugins and then by ours, one after
//! the other, against `icub-eth-emulator` on the robot's own addresses in a network
//! namespace of its own (`tests/hosts_common`).
//!
//!   cargo build --release -p yarp-device-programs -p icub-emulators
//!   ../shared/netns-run cargo bench -p icub-emulators --bench hosts_side_by_side [-- SECONDS [ROBOT [cpp|ours]]]
//!
//! For each robot and host: the time from the host's start to "startup phase finished."
//! (every part calibrated), the host's CPU (user + system, share of one core) over SECONDS
//! (default 300) at rest and over SECONDS while a client streams position commands to the
//! left arm (`set pos` of one joint by RPC at 50 Hz), its threads and resident memory, and
//! the command -> encoder latency (an RPC `set pos` until `state:o` shows the joint moving;
//! min / median / max of 20). The client is this program again (`--client`), run inside
//! the robot's namespace.

#[path = "common/cpu.rs"]
mod cpu;
#[path = "../tests/hosts_common/mod.rs"]
mod hosts_common;

use std::time::{Duration, Instant};

use hosts_common::*;
use yarp_interop_tests::{rss_kib, thread_count, Proc};

/// CPU share of one core of `pid` over `d`.
fn cpu_over(pid: u32, d: Duration) -> f64 {
    let c0 = cpu::cpu_seconds(Some(pid));
    let t0 = Instant::now();
    std::thread::sleep(d);
    100.0 * (cpu::cpu_seconds(Some(pid)) - c0) / t0.elapsed().as_secs_f64()
}

struct Figures {
    startup: Duration,
    rest: f64,
    streaming: f64,
    threads: usize,
    rss_mib: f64,
    latency: String,
}

/// A robot of the bench: its name, directory, top file, port prefix, and the left arm's
/// joint the clients move with the degrees they move it around.
struct Case<'a> {
    name: &'a str,
    dir: &'a std::path::Path,
    xml: &'a str,
    prefix: &'a str,
    joint: usize,
    around: f64,
}

fn measure(case: &Case<'_>, host: Host, secs: u64) -> Figures {
    let (robot, xml, prefix) = (case.dir, case.xml, case.prefix);
    let r = bring_up(BringUp {
        test: "hosts_side_by_side",
        host,
        robot,
        xml,
        record: None,
    })
    .expect("the C++ peer (tests/peers/install-cpp-peers.sh icub)");
    let pid = r.host.pid();
    // let the start-up's tail settle before measuring rest
    std::thread::sleep(Duration::from_secs(5));
    let rest = cpu_over(pid, Duration::from_secs(secs));
    let threads = thread_count(pid);
    let rss_mib = rss_kib(pid) as f64 / 1024.0;
    let client = |mode: &str, extra: &[String]| -> Proc {
        let exe = std::env::current_exe().expect("bench path");
        let mut c = r.net.ns.command(exe);
        c.env("YARP_CONFIG_HOME", r.net.conf.path())
            .args(["--client", mode, prefix, "left_arm"])
            .args([case.joint.to_string(), case.around.to_string()])
            .args(extra);
        Proc::spawn("bench client", c)
    };
    let mut stream = client("stream", &[secs.to_string()]);
    stream.wait_line("streaming", STEP);
    let streaming = cpu_over(pid, Duration::from_secs(secs));
    stream.wait_line("streamed", STEP);
    let mut lat = client("latency", &[]);
    let latency = lat.wait_line("latency", Duration::from_secs(120));
    Figures {
        startup: r.startup,
        rest,
        streaming,
        threads,
        rss_mib,
        latency: latency.trim_start_matches("latency ").to_string(),
    }
}

/// The client: `--client stream PREFIX PART JOINT AROUND SECONDS` or `--client latency
/// PREFIX PART JOINT AROUND`.
fn client(args: &[String]) {
    use yarp_net::blocking::{BufferedPort, Network, Port};
    let (mode, prefix, part) = (&args[0], &args[1], &args[2]);
    let joint: usize = args[3].parse().expect("joint");
    let around: f64 = args[4].parse().expect("degrees");
    let net = Network::from_conf().expect("the robot's name server");
    let rpc = Port::open(&net, &format!("/bench/{part}/rpc")).expect("rpc port");
    rpc.connect(&format!("{prefix}/{part}/rpc:i"), None)
        .expect("connect rpc:i");
    let set = |j: i32, q: f64| {
        let cmd = yarp_proto::Bottle::from_text(format!("set pos {j} {q}"));
        rpc.rpc_timeout(&cmd, Duration::from_secs(5))
    };
    match mode.as_str() {
        "stream" => {
            let secs: u64 = args[5].parse().expect("seconds");
            println!("streaming");
            let t0 = Instant::now();
            while t0.elapsed() < Duration::from_secs(secs) {
                let t = t0.elapsed().as_secs_f64();
                let _ = set(joint as i32, around + 5.0 * (0.5 * t).sin());
                std::thread::sleep(Duration::from_millis(20));
            }
            println!("streamed");
        }
        "latency" => {
            let state = BufferedPort::open(&net, &format!("/bench/{part}/state:i")).unwrap();
            net.connect(
                &format!("{prefix}/{part}/state:o"),
                &format!("/bench/{part}/state:i"),
                None,
            )
            .expect("connect state:o");
            let angle = |d| {
                state
                    .read_timeout(d)
                    .and_then(|m| m.bottle.get(joint).and_then(|v| v.as_f64()))
            };
            let mut samples = Vec::new();
            let mut target = around;
            for _ in 0..20 {
                let Some(q0) = angle(Duration::from_secs(5)) else {
                    break;
                };
                // settle where we are, then ask a 5 degree step and time the first move
                target = if target < around {
                    around + 5.0
                } else {
                    around - 5.0
                };
                while state.try_read().is_some() {}
                let sent = Instant::now();
                let _ = set(joint as i32, target);
                let end = sent + Duration::from_secs(5);
                while Instant::now() < end {
                    match angle(Duration::from_millis(500)) {
                        Some(q) if (q - q0).abs() > 0.01 => {
                            samples.push(sent.elapsed().as_secs_f64() * 1e3);
                            break;
                        }
                        _ => {}
                    }
                }
                std::thread::sleep(Duration::from_millis(1500));
            }
            samples.sort_by(f64::total_cmp);
            if samples.is_empty() {
                println!("latency none");
            } else {
                println!(
                    "latency {:.1} / {:.1} / {:.1} ms ({} moves)",
                    samples[0],
                    samples[samples.len() / 2],
                    samples[samples.len() - 1],
                    samples.len()
                );
            }
        }
        _ => panic!("unknown client mode {mode}"),
    }
}

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| a != "--bench")
        .collect();
    if args.first().map(String::as_str) == Some("--client") {
        return client(&args[1..]);
    }
    let secs: u64 = args.first().and_then(|s| s.parse().ok()).unwrap_or(300);
    let only = args.get(1).cloned();
    let hosts: &[Host] = match args.get(2).map(String::as_str) {
        Some("cpp") => &[Host::Cpp],
        Some("ours") => &[Host::Ours],
        _ => &[Host::Cpp, Host::Ours],
    };
    let (_copy, ergocub) = ergocub_without_xsens_and_wbd();
    let genova = robots().join("iCubGenova02");
    let cases = [
        // l_shoulder_pitch around -30 (limits -95.5..8)
        Case {
            name: "iCubGenova02",
            dir: &genova,
            xml: "icub_all.xml",
            prefix: "/icub",
            joint: 0,
            around: -30.0,
        },
        // l_shoulder_roll around 55 (0..130): the arm's joint 0 ends idle, its file
        // asking a startup position above its upper limit
        Case {
            name: "ergoCubSN001",
            dir: &ergocub,
            xml: "ergocub.xml",
            prefix: "/ergocub",
            joint: 1,
            around: 55.0,
        },
    ];
    let mut rows = Vec::new();
    for case in cases
        .iter()
        .filter(|c| only.as_deref().is_none_or(|o| o == c.name))
    {
        for &host in hosts {
            eprintln!("== {}, {host:?} host, {secs} s per window", case.name);
            let f = measure(case, host, secs);
            let row = format!(
                "| {} | {} | {:.1} s | {:.1} % | {:.1} % | {} | {:.0} MiB | {} |",
                case.name,
                match host {
                    Host::Cpp => "icub-main 2.11.1 (C++)",
                    Host::Ours => "ours",
                },
                f.startup.as_secs_f64(),
                f.rest,
                f.streaming,
                f.threads,
                f.rss_mib,
                f.latency
            );
            eprintln!("{row}");
            rows.push(row);
        }
    }
    println!(
        "| robot | host | start-up to calibrated | CPU at rest | CPU streaming set pos 50 Hz | threads | RSS | command -> encoder min / median / max |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for r in rows {
        println!("{r}");
    }
}
