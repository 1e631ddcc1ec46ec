//! Rates of ergoCubSN001's ROS 2 wrappers (a bench program, not a timed test): the
//! whole-body JointState (`alljoints-mc_nws_ros2.xml`, 0.02 s) and the four WrenchStamped
//! (`*-FT_nws_ros2.xml`, 0.002 s), as one rclpy subscriber receives them, and the CPU of
//! the publishing robot process.
//!
//!   ../shared/netns-run cargo bench -p yarp-devices-ros2 --bench ergocub_rates [-- SECONDS]
//!
//! Three processes, as on the robot: the emulated Ethernet boards (this program in its
//! emulator role: `icub-eth-emulator`'s boards), the robot (this program in its robot
//! role: the robot-interface runner with every driver `yarprobotinterface` registers, on
//! the test's top file of `tests/ergocub/mod.rs`, without the command device) and rclpy
//! (`tests/peers/robot_watch.py --rates SECONDS`, default 20). The robot's CPU (user +
//! system, share of one core) is measured twice over SECONDS: with no ROS subscriber (the
//! wrappers publish only to matched subscribers, as C++) and while rclpy receives every
//! topic. Per topic: messages, rate, and the gaps between arrivals at rclpy (mean,
//! standard deviation, p99, max).

#[path = "../../tests/common/mod.rs"]
mod common;
#[path = "../tests/ergocub/mod.rs"]
mod ergocub;

use ergocub::*;
use serde_json::Value as Json;
use std::process::Command;
use std::time::{Duration, Instant};

const MAP: &str = "10.0.1.0/24=127.0.6.0/24";

/// User + system CPU seconds of process `pid`.
fn cpu_seconds(pid: u32) -> f64 {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).unwrap_or_default();
    let after = stat.rsplit(')').next().unwrap_or("");
    let f: Vec<&str> = after.split_whitespace().collect();
    let ut: f64 = f.get(11).and_then(|v| v.parse().ok()).unwrap_or(0.0);
    let st: f64 = f.get(12).and_then(|v| v.parse().ok()).unwrap_or(0.0);
    (ut + st) / 100.0 // USER_HZ
}

fn emulator_role(top: &str) {
    let dir = robot_dir();
    let specs = icub_emulators::eth::robot_boards(&dir, Some(std::path::Path::new(top)))
        .expect("robot boards");
    let n = specs.len();
    let map = icubmod::eth::params::AddressMap::parse(MAP).unwrap();
    let (_served, _threads) = icub_emulators::eth::serve(
        specs,
        &map,
        std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false)),
    )
    .expect("the emulator binds its addresses");
    println!("serving {n} boards");
    loop {
        std::thread::sleep(Duration::from_secs(3600));
    }
}

fn robot_role(top: &str) {
    yarp_devices::Registry::install(icubmod::register);
    yarp_devices::Registry::install(yarp_devices_ros2::register);
    let robot = yarp_devices::robotinterface::read_robot_file(
        std::path::Path::new(top),
        &yarp_proto::Property::from_text("(enable_tags (enable_ros2))"),
    )
    .unwrap_or_else(|e| panic!("{e}"))
    .robot;
    let mut runner = yarp_devices::robotinterface::RobotRunner::new(robot);
    runner.set_keep_going(true);
    let t0 = Instant::now();
    runner
        .enter_phase(yarp_devices::robotinterface::ActionPhase::Startup)
        .unwrap_or_else(|e| panic!("{e}"));
    runner
        .enter_phase(yarp_devices::robotinterface::ActionPhase::Run)
        .unwrap();
    eprintln!("robot: given up at start-up: {:?}", runner.failures());
    println!("READY {:.1}", t0.elapsed().as_secs_f64());
    loop {
        std::thread::sleep(Duration::from_secs(3600));
    }
}

fn role(role: &str, top: &std::path::Path) -> Child2 {
    let mut cmd = Command::new(std::env::current_exe().unwrap());
    cmd.arg(role).arg(top);
    Child2::spawn(cmd, role)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    match args.get(1).map(String::as_str) {
        Some("--role-emulator") => return emulator_role(&args[2]),
        Some("--role-robot") => return robot_role(&args[2]),
        _ => {}
    }
    let seconds: f64 = args
        .iter()
        .skip(1)
        .find_map(|a| a.parse().ok())
        .unwrap_or(20.0);
    let Some(venv) = ros_venv("ergocub_rates") else {
        return;
    };
    // a domain of the gateway's test harness, index 23 (unused by the tests)
    let domain = common::domain_id(23);
    let conf = tempfile::tempdir().unwrap();
    std::env::set_var("YARP_CONFIG_HOME", conf.path());
    std::env::set_var(icubmod::eth::params::ADDRESS_MAP_ENV, MAP);
    std::env::set_var("ROS_DOMAIN_ID", domain.to_string());
    std::env::set_var("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST");
    let addr = yarp_devices::runtime::block_on(async {
        let ns = yarp_interop_tests::bind_name_server().await;
        let addr = ns.local_addr();
        tokio::spawn(ns.serve());
        addr
    })
    .expect("the device runtime");
    yarp_net::network::write_conf("127.0.0.1", addr.port()).unwrap();
    let dir = robot_dir();
    let top = top_file(&dir, conf.path(), false);

    let emulator = role("--role-emulator", &top);
    eprintln!(
        "emulator: {}",
        emulator.expect("serving", Duration::from_secs(60))
    );
    let robot = role("--role-robot", &top);
    let startup = robot.expect("READY", Duration::from_secs(300));
    eprintln!("robot up in {startup} s");
    std::thread::sleep(Duration::from_secs(2));

    let (c0, t0) = (cpu_seconds(robot.id()), Instant::now());
    std::thread::sleep(Duration::from_secs_f64(seconds));
    let idle = (cpu_seconds(robot.id()) - c0) / t0.elapsed().as_secs_f64();

    let mut wargs = watched(false);
    wargs.extend([
        "--rates".into(),
        seconds.to_string(),
        "--timeout".into(),
        "120".into(),
    ]);
    let topics = wargs.iter().filter(|a| a.contains('=')).count();
    let watch = watch(&venv, domain, &wargs);
    watch.expect("READY", Duration::from_secs(30));
    let (mut firsts, mut hashes) = (0, 0);
    while firsts < topics || hashes < topics {
        let l = watch.expect("", Duration::from_secs(120));
        firsts += l.starts_with("FIRST") as usize;
        hashes += l.starts_with("HASH") as usize;
    }
    let (c1, t1) = (cpu_seconds(robot.id()), Instant::now());
    let rates = watch.collect("RATE", "DONE", Duration::from_secs_f64(seconds + 60.0));
    let busy = (cpu_seconds(robot.id()) - c1) / t1.elapsed().as_secs_f64();

    let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    println!(
        "\nergoCubSN001 ROS 2 wrappers, {seconds} s windows, load average {}",
        load.trim()
    );
    println!(
        "| topic | type | configured | messages | rate | gap mean | gap std | gap p99 | gap max |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for r in &rates {
        let (topic, j) = r.split_once(' ').unwrap();
        let j: Json = serde_json::from_str(j).unwrap();
        let (ty, hz) = if topic == JOINT_STATES {
            ("JointState (45 joints)", 50.0)
        } else {
            ("WrenchStamped", 500.0)
        };
        let ms = |k: &str| j[k].as_f64().map_or("-".into(), |v| format!("{v:.2} ms"));
        println!(
            "| `{topic}` | {ty} | {hz} Hz | {} | {:.1} Hz | {} | {} | {} | {} |",
            j["n"],
            j["hz"].as_f64().unwrap_or(0.0),
            ms("gap_mean_ms"),
            ms("gap_std_ms"),
            ms("gap_p99_ms"),
            ms("gap_max_ms"),
        );
    }
    println!(
        "\nrobot process CPU (share of one core): {:.1} % with no ROS subscriber, {:.1} % while rclpy receives all {topics} topics",
        idle * 100.0,
        busy * 100.0
    );
    drop(watch);
    drop(robot);
    drop(emulator);
}
