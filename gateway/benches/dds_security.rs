//! What SROS2 costs: round trips of `std_msgs/String` between two DDS participants of this
//! process (ros2-client over RustDDS, as the gateway and the `*_nws_ros2` devices use it),
//! reliable, on loopback, ping -> echo -> ping, one message in flight; plain and secured
//! (the governance `ros2 security create_keystore` writes: discovery, liveliness, RTPS
//! messages and data all encrypted, AES-GCM) in the same run, for three payload sizes.
//! Reports the round-trip time (p50, p99) and the process's CPU time per round trip
//! (both participants: two encryptions and two decryptions of the sample, plus the
//! ACKNACKs and HEARTBEATs of the reliable protocol, each protected).
//!
//! Run under `netns-run` (ROS domain 231):
//! `../shared/netns-run cargo bench -p yarp-ros2-gateway --bench dds_security`
//! (`-- --quick`: fewer round trips).

use futures::{pin_mut, StreamExt};
use std::path::Path;
use std::time::{Duration, Instant};
use yarp_ros2_gateway::dynmsg::{MsgSeed, Value as Ros};
use yarp_ros2_gateway::mapping::Qos;
use yarp_ros2_gateway::ros;
use yarp_ros2_gateway::security::Security;

const DOMAIN: u16 = 231;
const STRING: &str = "std_msgs/msg/String";
const SIZES: [usize; 3] = [16, 1024, 60 * 1024];

/// Process CPU time (user + system), from `/proc/self/stat` (clock ticks of 10 ms: a
/// run of several seconds keeps the error near 1 %).
fn cpu_time() -> Duration {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    // Fields after the command (which may hold spaces) start after the last ')'.
    let rest = stat.rsplit_once(')').map(|(_, r)| r).unwrap_or("");
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: u64 = f.get(11).and_then(|u| u.parse().ok()).unwrap_or(0)
        + f.get(12).and_then(|s| s.parse().ok()).unwrap_or(0);
    Duration::from_millis(ticks * 10)
}

fn pct(v: &mut [Duration], p: usize) -> Duration {
    v.sort();
    v[(v.len() * p / 100).min(v.len() - 1)]
}

/// An SROS2 keystore with enclaves `/ping` and `/echo` (the project's script).
fn keystore(dir: &Path) -> (Security, Security) {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/peers/sros2-keystore.sh");
    let ks = dir.join("keystore");
    for args in [
        vec!["create_keystore", ks.to_str().unwrap()],
        vec!["create_enclave", ks.to_str().unwrap(), "/ping"],
        vec!["create_enclave", ks.to_str().unwrap(), "/echo"],
    ] {
        let ok = std::process::Command::new("bash")
            .arg(&script)
            .args(&args)
            .env("ROS_DOMAIN_ID", DOMAIN.to_string())
            .status()
            .expect("run sros2-keystore.sh")
            .success();
        assert!(ok, "sros2-keystore.sh {args:?} failed");
    }
    let enclave = |e: &str| Security::Enclave(ks.join("enclaves").join(e));
    (enclave("ping"), enclave("echo"))
}

fn string(len: usize, i: usize) -> Ros {
    let mut s = format!("{i:08}");
    s.extend(std::iter::repeat_n('x', len.saturating_sub(s.len())));
    Ros::Struct(vec![Ros::Str(s)])
}

struct Result {
    size: usize,
    p50: Duration,
    p99: Duration,
    cpu: Duration,
}

async fn run(mode: &str, ping_sec: Security, echo_sec: Security, n: usize) -> Vec<Result> {
    let lo = ["127.0.0.1".parse().unwrap()];
    let ctx_p = ros::start_context_with(DOMAIN, &lo, ping_sec).expect("ping participant");
    let ctx_e = ros::start_context_with(DOMAIN, &lo, echo_sec).expect("echo participant");
    let mut node_p = ros::new_node(&ctx_p, "/", &format!("ping_{mode}")).unwrap();
    let mut node_e = ros::new_node(&ctx_e, "/", &format!("echo_{mode}")).unwrap();
    let qos = Qos::default();
    let ping_pub = ros::publisher(&mut node_p, "/ping", STRING, &qos).unwrap();
    let pong_sub = ros::subscription(&mut node_p, "/pong", STRING, &qos).unwrap();
    let ping_sub = ros::subscription(&mut node_e, "/ping", STRING, &qos).unwrap();
    let pong_pub = ros::publisher(&mut node_e, "/pong", STRING, &qos).unwrap();
    let spinners: Vec<_> = [&mut node_p, &mut node_e]
        .into_iter()
        .map(|n| {
            let s = n.spinner().expect("spinner");
            tokio::spawn(async move {
                let _ = s.spin().await;
            })
        })
        .collect();
    let echo = tokio::spawn(async move {
        let stream = ping_sub.async_stream_seed(MsgSeed::new(STRING).unwrap());
        pin_mut!(stream);
        while let Some(Ok((m, _))) = stream.next().await {
            let _ = pong_pub.async_publish(m).await;
        }
    });
    let stream = pong_sub.async_stream_seed(MsgSeed::new(STRING).unwrap());
    pin_mut!(stream);
    // Matched (and, secured, authenticated) once a message comes back.
    let end = Instant::now() + Duration::from_secs(30);
    loop {
        let _ = ping_pub.async_publish(string(16, 0)).await;
        if let Ok(Some(Ok(_))) =
            tokio::time::timeout(Duration::from_millis(200), stream.next()).await
        {
            break;
        }
        assert!(Instant::now() < end, "{mode}: the echo never answered");
    }
    let mut out = Vec::new();
    for size in SIZES {
        let mut rtts = Vec::with_capacity(n);
        let cpu0 = cpu_time();
        for i in 1..=n {
            let t0 = Instant::now();
            let _ = ping_pub.async_publish(string(size, i)).await;
            // Only this round's answer counts (a late one of the warm-up is skipped).
            loop {
                let m = tokio::time::timeout(Duration::from_secs(10), stream.next())
                    .await
                    .unwrap_or_else(|_| panic!("{mode}: no echo of round {i} ({size} B)"));
                if let Some(Ok((Ros::Struct(f), _))) = m {
                    if matches!(f.first(), Some(Ros::Str(s)) if s.starts_with(&format!("{i:08}"))) {
                        break;
                    }
                }
            }
            rtts.push(t0.elapsed());
        }
        let cpu = (cpu_time() - cpu0) / n as u32;
        out.push(Result {
            size,
            p50: pct(&mut rtts, 50),
            p99: pct(&mut rtts, 99),
            cpu,
        });
    }
    echo.abort();
    drop((ping_pub, node_p, node_e));
    for s in spinners {
        let _ = tokio::time::timeout(Duration::from_secs(2), s).await;
    }
    out
}

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    // `cargo bench` passes `--bench`; nothing else is read.
    let n = if quick { 200 } else { 2000 };
    std::env::set_var("ROS_DISTRO", "kilted");
    let dir = tempfile::tempdir().unwrap();
    let (ping_sec, echo_sec) = keystore(dir.path());
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .unwrap();
    let plain = rt.block_on(run("plain", Security::Off, Security::Off, n));
    let secured = rt.block_on(run("secured", ping_sec, echo_sec, n));
    println!("DDS round trips, String, reliable, loopback, {n} per size (ping -> echo -> ping):");
    println!(
        "{:>8}  {:>10} {:>10} {:>12}   {:>10} {:>10} {:>12}",
        "bytes", "plain p50", "p99", "CPU/trip", "SROS2 p50", "p99", "CPU/trip"
    );
    let us = |d: Duration| format!("{:.0} us", d.as_secs_f64() * 1e6);
    for (p, s) in plain.iter().zip(&secured) {
        println!(
            "{:>8}  {:>10} {:>10} {:>12}   {:>10} {:>10} {:>12}",
            p.size,
            us(p.p50),
            us(p.p99),
            us(p.cpu),
            us(s.p50),
            us(s.p99),
            us(s.cpu)
        );
    }
}
