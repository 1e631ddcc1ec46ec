//! Control-board wrapper benchmarks on loopback with an in-process name server:
//!
//! * CPU cost of `state:o` / `stateExt:o` for a 50-axis board published at 1 kHz:
//!   process CPU time (sum of every thread's run time, /proc/self/task/*/schedstat)
//!   over a few seconds, for the wrapper alone and with in-process tcp readers;
//! * round trip of a remote `getEncoders`: `[get] [encs]` over RPC through
//!   `remote_controlboard` -> `controlBoard_nws_yarp`, and the streamed (cached) read;
//! * the per-tick work of the publisher (read the board, build and encode `jointData`).
//!
//! Run (a private loopback-only network namespace):
//!
//! ```text
//! /work/shared/netns-run cargo bench -p yarp-devices --bench controlboard [-- <filter>]
//! ```

use criterion::{criterion_group, Criterion};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};
use yarp_devices::controlboard::{ControlBoardNws, JointData};
use yarp_devices::remote_controlboard::RemoteControlBoard;
use yarp_devices::{
    runtime, shared, DevResult, DeviceDriver, FakeMotionControl, IEncoders, PolyDriver,
    SharedDevice,
};
use yarp_net::nameserver::{NameClient, NameServer};
use yarp_net::port::Port;
use yarp_proto::{bottle, Property, Vocab32};

const AXES: usize = 50;
const PERIOD: Duration = Duration::from_millis(1);
/// How long each CPU measurement runs.
const CPU_WINDOW: Duration = Duration::from_secs(3);

/// Starts a name server and points yarp.conf at it; returns a client.
fn start_name_server(dir: &std::path::Path) -> NameClient {
    std::env::set_var("YARP_CONFIG_HOME", dir);
    let addr = runtime::block_on(async {
        let ns = NameServer::bind("127.0.0.1:0", "127.0.0.1")
            .await
            .expect("bind name server");
        let addr = ns.local_addr();
        tokio::spawn(ns.serve());
        addr
    })
    .expect("the device runtime");
    yarp_net::network::write_conf("127.0.0.1", addr.port()).expect("yarp.conf");
    NameClient::new(addr)
}

/// Nanoseconds of CPU used so far by every thread of this process.
fn process_cpu_ns() -> u64 {
    let Ok(tasks) = std::fs::read_dir("/proc/self/task") else {
        return 0;
    };
    tasks
        .flatten()
        .filter_map(|t| std::fs::read_to_string(t.path().join("schedstat")).ok())
        .filter_map(|s| s.split_whitespace().next()?.parse::<u64>().ok())
        .sum()
}

/// A board that only has encoders and does no simulation work: isolates the wrapper.
struct StaticBoard;

impl DeviceDriver for StaticBoard {
    fn open(&mut self, _: &Property) -> DevResult<()> {
        Ok(())
    }
    yarp_devices::views!(as_encoders);
}

impl IEncoders for StaticBoard {
    fn get_axes(&mut self) -> DevResult<usize> {
        Ok(AXES)
    }
    fn get_encoder(&mut self, j: usize) -> DevResult<f64> {
        Ok(j as f64)
    }
    fn get_encoder_speed(&mut self, _: usize) -> DevResult<f64> {
        Ok(0.0)
    }
    fn get_encoder_acceleration(&mut self, _: usize) -> DevResult<f64> {
        Ok(0.0)
    }
    fn get_encoder_timed(&mut self, j: usize) -> DevResult<(f64, f64)> {
        let t = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map_or(0.0, |d| d.as_secs_f64());
        Ok((j as f64, t))
    }
    fn set_encoder(&mut self, _: usize, _: f64) -> DevResult<()> {
        Ok(())
    }
}

fn fake_board(n: usize) -> SharedDevice {
    let cfg = Property::from_config_text(format!("device fakeMotionControl\naxes {n}\n"));
    shared(PolyDriver::open(&cfg.unwrap()).unwrap())
}

/// One CPU measurement: a wrapper on `board` at 1 kHz with tcp readers on `streams`.
fn cpu_case(ns: &NameClient, label: &str, board: SharedDevice, streams: &[&str]) {
    let prefix = format!("/bench/{}", label.replace(' ', "_"));
    let (ns1, p1) = (ns.clone(), prefix.clone());
    let nws = runtime::block_on(async move {
        let mut nws = ControlBoardNws::open_ports(&p1, ns1, PERIOD).await.unwrap();
        nws.attach(board).unwrap();
        nws
    })
    .expect("the device runtime");
    let received = Arc::new(AtomicU64::new(0));
    let mut readers = Vec::new();
    for s in streams {
        let (ns1, from, to, got) = (
            ns.clone(),
            format!("{prefix}/{s}"),
            format!("{prefix}/reader/{s}"),
            received.clone(),
        );
        let port = runtime::block_on(async move {
            let port = Port::open(&to, ns1.clone()).await.unwrap();
            let (ok, msg) = yarp_net::network::connect(&ns1, &from, &to, None)
                .await
                .unwrap();
            assert!(ok, "{msg}");
            port
        })
        .expect("the device runtime");
        readers.push(runtime::handle().spawn(async move {
            while port.read().await.is_some() {
                got.fetch_add(1, Ordering::Relaxed);
            }
        }));
    }
    std::thread::sleep(Duration::from_millis(300));
    let (cpu0, t0, n0) = (
        process_cpu_ns(),
        Instant::now(),
        received.load(Ordering::Relaxed),
    );
    std::thread::sleep(CPU_WINDOW);
    let (cpu1, t1, n1) = (
        process_cpu_ns(),
        Instant::now(),
        received.load(Ordering::Relaxed),
    );
    let wall = (t1 - t0).as_secs_f64();
    let cpu = (cpu1 - cpu0) as f64 / 1e9;
    let rate = (n1 - n0) as f64 / wall / streams.len().max(1) as f64;
    println!(
        "cpu/{label:<40} {:>6.1}% of one core, {:>6.1} us per tick; received {:>6.0} msg/s per stream",
        100.0 * cpu / wall,
        1e6 * cpu / (wall / PERIOD.as_secs_f64()),
        rate
    );
    for r in readers {
        r.abort();
    }
    runtime::block_on(nws.close()).expect("the device runtime");
}

/// The CPU figures (printed; criterion has no CPU-time measurement).
fn cpu_per_stream(ns: &NameClient) {
    let baseline = {
        let (c0, t0) = (process_cpu_ns(), Instant::now());
        std::thread::sleep(Duration::from_secs(1));
        (process_cpu_ns() - c0) as f64 / t0.elapsed().as_secs_f64() / 1e9
    };
    println!(
        "cpu/idle process baseline                       {:>6.1}% of one core",
        100.0 * baseline
    );
    let static_board = || shared(PolyDriver::from_driver("static", Box::new(StaticBoard)));
    cpu_case(ns, "static50 no reader", static_board(), &[]);
    cpu_case(ns, "static50 state:o", static_board(), &["state:o"]);
    cpu_case(ns, "static50 stateExt:o", static_board(), &["stateExt:o"]);
    cpu_case(
        ns,
        "static50 both",
        static_board(),
        &["state:o", "stateExt:o"],
    );
    cpu_case(
        ns,
        "fake50 both",
        fake_board(AXES),
        &["state:o", "stateExt:o"],
    );
}

fn publisher_tick(c: &mut Criterion) {
    let mut g = c.benchmark_group("tick");
    let mut fake = FakeMotionControl::with_joints(AXES);
    g.bench_function("fake50 read+encode jointData", |b| {
        b.iter(|| {
            let (d, _) = JointData::read(&mut fake, AXES);
            d.to_bottle().encode()
        })
    });
    let mut board = StaticBoard;
    g.bench_function("static50 read+encode jointData", |b| {
        b.iter(|| {
            let (d, _) = JointData::read(&mut board, AXES);
            d.to_bottle().encode()
        })
    });
    g.finish();
}

fn remote_get_encoders(c: &mut Criterion) {
    let ns = yarp_net::network::name_client().expect("name server");
    let nws = runtime::block_on(async move {
        let mut nws = ControlBoardNws::open_ports("/bench/rt", ns, Duration::from_millis(10))
            .await
            .unwrap();
        nws.attach(fake_board(AXES)).unwrap();
        nws
    })
    .expect("the device runtime");
    let mut remote = RemoteControlBoard::new();
    remote
        .open(&Property::from_config_text("remote /bench/rt\nlocal /bench/rtcli\n").unwrap())
        .expect("remote opens");
    let deadline = Instant::now() + Duration::from_secs(10);
    while remote.get_encoders().is_err() {
        assert!(Instant::now() < deadline, "no state streamed");
        std::thread::sleep(Duration::from_millis(10));
    }
    let encs = bottle![Vocab32::new("get"), Vocab32::new("encs")];
    let mut g = c.benchmark_group("remote");
    g.bench_function("getEncoders RPC [get] [encs] 50 axes round trip", |b| {
        b.iter(|| remote.call(&encs).unwrap())
    });
    g.bench_function("getEncoders from the streamed state (udp)", |b| {
        b.iter(|| remote.get_encoders().unwrap())
    });
    g.finish();
    drop(remote);
    runtime::block_on(nws.close()).expect("the device runtime");
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3));
    targets = publisher_tick, remote_get_encoders
}

fn main() {
    let dir = tempfile::tempdir().expect("temp dir");
    let ns = start_name_server(dir.path());
    let filter: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .collect();
    if filter.is_empty() || filter.iter().any(|f| "cpu".contains(f.as_str())) {
        cpu_per_stream(&ns);
    }
    benches();
    Criterion::default().configure_from_args().final_summary();
}
