//! Whole-robot figures of the Ethernet robots (a bench program, not a timed test):
//! iCubGenova02 and ergoCubSN001, unmodified, brought up by the robot-interface runner
//! against `icub-eth-emulator`'s boards in the same process (so the process's CPU time is
//! the robot's and the emulator's together), at the rates of their files.
//!
//!   ../shared/netns-run cargo bench -p icub-emulators --bench eth_robots [-- SECONDS]
//!
//! For each robot (one child process each, since the host socket is per process): the
//! start-up time (open, attach, calibrate every part), the CPU over SECONDS (default 20)
//! of running, as a share of one core, the command-to-encoder latency (position command
//! on the left arm's remapper until its encoder moves, median of 20), and the boards'
//! status streams as they reach the host's socket (kernel receive timestamps):
//! datagrams, the longest gap between two, the gaps longer than three periods, sequence
//! gaps (in all and per board); how long datagrams waited there for the host's reader;
//! how late the emulator's board thread woke; and, over the same window, the machine's
//! own stalls (`common/machine_stalls.rs`, in a child process) to compare them with.

#[path = "common/cpu.rs"]
mod cpu;
#[path = "common/machine_stalls.rs"]
mod machine_stalls;

use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::{Duration, Instant};

use icub_emulators::eth::{robot_boards, serve};
use icub_emulators::eth::{AddressMap, ADDRESS_MAP_ENV};
use icubmod::eth::manager::EthManager;
use yarp_devices::robotinterface::{read_robot_file, ActionPhase, RobotRunner};
use yarp_devices::vocabs::CM_POSITION;
use yarp_proto::Property;

fn run(robot: &str, xml: &str, part: &str, joint: usize, seconds: u64) {
    let map = "10.0.1.0/24=127.0.5.0/24";
    std::env::set_var(ADDRESS_MAP_ENV, map);
    let conf = tempfile::tempdir().unwrap();
    std::env::set_var("YARP_CONFIG_HOME", conf.path());
    let addr = yarp_devices::runtime::block_on(async {
        let ns = yarp_interop_tests::bind_name_server().await;
        let addr = ns.local_addr();
        tokio::spawn(ns.serve());
        addr
    })
    .expect("the device runtime");
    yarp_net::network::write_conf("127.0.0.1", addr.port()).unwrap();
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/robots-configuration")
        .join(robot);
    let top = dir.join(xml);
    let specs = robot_boards(&dir, Some(&top)).unwrap();
    let boards = specs.len();
    let (_s, _t) = serve(
        specs,
        &AddressMap::parse(map).unwrap(),
        Arc::new(AtomicBool::new(false)),
    )
    .unwrap();
    // ergoCub's waist IMU is an Xsens MTi on a serial line: emulated on a pseudo-terminal,
    // as `icub-eth-emulator --xsens` does, so that the whole robot comes up.
    let xsens_link = conf.path().join("ttyXSENS");
    let (_mti, _pts) = icub_can::emulator::mtx::pty_link_with(
        &xsens_link,
        icub_can::xsens::mti::EmulatedMti::default(),
    )
    .expect("emulate the Xsens MTi on a pseudo-terminal");
    std::env::set_var(icubmod::xsens::SERIAL_ENV, &xsens_link);
    let r = read_robot_file(&top, &Property::default()).unwrap().robot;
    yarp_devices::Registry::install(icubmod::register);
    let mut runner = RobotRunner::new(r);
    runner.set_keep_going(true);
    let t0 = Instant::now();
    runner.enter_phase(ActionPhase::Startup).unwrap();
    let startup = t0.elapsed();
    runner.enter_phase(ActionPhase::Run).unwrap();
    for f in runner.failures() {
        eprintln!("start-up failure: {f}");
    }

    let mgr = EthManager::current().expect("the embObj devices made the manager");
    for b in mgr.all_boards() {
        b.reset_rx_stats();
    }
    // The machine's own stalls over the same window, measured apart (its CPU is not
    // ours) one priority above our real-time threads, so that it sees the machine only.
    let probe = std::process::Command::new(std::env::current_exe().unwrap())
        .args(["--machine-probe", &seconds.to_string()])
        .stdout(std::process::Stdio::piped())
        .spawn()
        .expect("start the machine probe");
    let c0 = cpu::cpu_seconds(None);
    let wake0 = icub_emulators::eth::wake_stats();
    let w0 = Instant::now();
    std::thread::sleep(Duration::from_secs(seconds));
    let cpu = (cpu::cpu_seconds(None) - c0) / w0.elapsed().as_secs_f64();
    let wake1 = icub_emulators::eth::wake_stats();
    let machine = probe
        .wait_with_output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_else(|e| format!("the probe failed: {e}"));
    let mut worst = (Duration::ZERO, String::new());
    let (mut frames, mut seq_gaps, mut late) = (0u64, 0u64, 0u64);
    let mut reader = icubmod::eth::manager::ReaderDelays::default();
    let mut per_board = Vec::new();
    for b in mgr.all_boards() {
        let st = b.rx_stats();
        let period = b.params().regulars_period();
        frames += st.datagrams;
        seq_gaps += st.counters.sequence_gaps;
        late += st.late_gaps;
        reader.longest = reader.longest.max(st.reader_delays.longest);
        reader.over_1ms += st.reader_delays.over_1ms;
        per_board.push(format!(
            "  {}: period {:?}, {} datagrams ({:.0}/s), longest gap {:.1} ms, {} gaps over 3 periods",
            b.who(),
            period,
            st.datagrams,
            st.datagrams as f64 / seconds as f64,
            st.longest_gap.as_secs_f64() * 1e3,
            st.late_gaps
        ));
        if st.longest_gap > worst.0 {
            worst = (st.longest_gap, format!("{} (period {period:?})", b.who()));
        }
    }

    let dev = runner.device(part).expect(part);
    let mut lat = Vec::new();
    let mut missed = 0;
    for k in 0..20 {
        let mut pd = dev.lock();
        let d = pd.device();
        let step = |d: &mut dyn yarp_devices::DeviceDriver| -> yarp_devices::DevResult<Duration> {
            d.as_control_mode()
                .unwrap()
                .set_control_mode(joint, CM_POSITION)?;
            let q = d.as_encoders().unwrap().get_encoder(joint)?;
            let target = q + if k % 2 == 0 { 5.0 } else { -5.0 };
            d.as_position_control()
                .unwrap()
                .set_ref_speed(joint, 100.0)?;
            let t = Instant::now();
            d.as_position_control()
                .unwrap()
                .position_move(joint, target)?;
            while (d.as_encoders().unwrap().get_encoder(joint)? - q).abs() < 0.01 {
                if t.elapsed() > Duration::from_secs(5) {
                    return Err(yarp_devices::DeviceError::Unsupported(
                        "the joint does not move",
                    ));
                }
                std::thread::sleep(Duration::from_micros(200));
            }
            Ok(t.elapsed())
        };
        match step(d) {
            Ok(l) => lat.push(l),
            Err(e) => {
                eprintln!("move {k}: {e}");
                missed += 1;
            }
        }
        drop(pd);
        std::thread::sleep(Duration::from_millis(200));
    }
    assert!(!lat.is_empty(), "no move succeeded");
    lat.sort();
    let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    println!(
        "{robot}: {boards} boards; startup {:.1} s; CPU {:.1} % of one core over {seconds} s (robot + emulator); \
         command-to-encoder median {:.1} ms (min {:.1}, max {:.1}); {frames} status datagrams, \
         longest gap {:.1} ms at {}, {late} gaps over 3 periods, {seq_gaps} sequence gaps; failures at start-up: {}; moves that failed: {missed}; loadavg {}",
        startup.as_secs_f64(),
        cpu * 100.0,
        lat[lat.len() / 2].as_secs_f64() * 1e3,
        lat[0].as_secs_f64() * 1e3,
        lat[lat.len() - 1].as_secs_f64() * 1e3,
        worst.0.as_secs_f64() * 1e3,
        worst.1,
        runner.failures().len(),
        load.trim()
    );
    println!(
        "  the host's reader: datagrams waited in its socket (kernel timestamp to the reader) more than 1 ms {} times, longest {:.1} ms",
        reader.over_1ms,
        reader.longest.as_secs_f64() * 1e3
    );
    println!(
        "  the boards' thread: {} wake-ups for due work, {} of them more than 2 ms late (latest since start {:.1} ms); {} rounds of work over 1 ms (longest since start {:.1} ms)",
        wake1.0 - wake0.0,
        wake1.1 - wake0.1,
        wake1.2 as f64 / 1e3,
        wake1.3 - wake0.3,
        wake1.4 as f64 / 1e3
    );
    println!("  the machine over the same window (a probe thread per CPU at SCHED_FIFO 50, another process): {machine}");
    for line in per_board {
        println!("{line}");
    }
    let _ = runner.enter_phase(ActionPhase::Interrupt1);
    let _ = runner.enter_phase(ActionPhase::Shutdown);
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if let Some(i) = args.iter().position(|a| a == "--machine-probe") {
        let seconds = args.get(i + 1).and_then(|s| s.parse().ok()).unwrap_or(20);
        let prio = yarp_net::realtime::ETH_RECEIVER_PRIORITY + 1;
        println!("{}", machine_stalls::probe(seconds, prio).summary());
        return;
    }
    if let Some(i) = args.iter().position(|a| a == "--robot") {
        let seconds = args.get(i + 2).and_then(|s| s.parse().ok()).unwrap_or(20);
        match args[i + 1].as_str() {
            "iCubGenova02" => run(
                "iCubGenova02",
                "icub_all.xml",
                "left_arm-mc_remapper",
                3,
                seconds,
            ),
            _ => run(
                "ergoCubSN001",
                "ergocub.xml",
                "left_arm-mc_remapper",
                1,
                seconds,
            ),
        }
        return;
    }
    let seconds = args
        .iter()
        .skip(1)
        .find_map(|a| a.parse::<u64>().ok())
        .unwrap_or(20);
    for robot in ["iCubGenova02", "ergoCubSN001"] {
        let status = std::process::Command::new(std::env::current_exe().unwrap())
            .args(["--robot", robot, &seconds.to_string()])
            .env("RUST_LOG", "error")
            .status()
            .expect("run the bench child");
        assert!(status.success(), "{robot}: {status}");
    }
}
