//! Board emulators killed and restarted under a running `yarprobotinterface` (all real
//! processes on loopback; run under netns-run): the CAN robot (iCubGenova01's left arm,
//! `canmotioncontrol`, against `icub-board-emulator` over a cannelloni hub) and the
//! Ethernet robot (iCubGenova02's left arm board `left_arm-eb1-j0_3`, `embObjMotionControl`,
//! against `icub-eth-emulator`), each behind `controlBoard_nws_yarp`.
//!
//! What icub-main does, we do: a CAN board that falls silent is reported ("have not heard
//! from board N", `CanBusMotionControl`), its reads fail instead of hanging, and when it
//! broadcasts again its encoders flow again (a reset board lost its configuration: the log
//! says to restart yarprobotinterface). An Ethernet board that falls silent is reported by
//! `eth::EthMonitorPresence`; a restarted one waits in its configuration state for a host
//! start-up sequence that (as in C++) only a new open sends, so the report names what to
//! do: restart yarprobotinterface. A board that reboots under a running host restarts its
//! sequence numbers, which the host reports as icub-main's does.
//!
//! Needs the workspace programs in the same target directory (`cargo build --workspace
//! --bins`; `tests/run.sh` does) and `../shared/robots-configuration`.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};
use yarp_interop_tests::{Proc, YarpNet, STEP};

fn robots_configuration() -> Option<PathBuf> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/robots-configuration")
        .canonicalize()
        .ok()?;
    if dir.join("iCubGenova01").is_dir() && dir.join("iCubGenova02").is_dir() {
        Some(dir)
    } else {
        None
    }
}

/// A robot file with `included` (device files, absolute paths) and one
/// `controlBoard_nws_yarp` as `/fault/left_arm` attached to `attach`.
fn robot_xml(
    dir: &Path,
    name: &str,
    params: Option<&Path>,
    included: &[PathBuf],
    attach: &str,
) -> PathBuf {
    let href = |p: &Path| yarp_interop_tests::include_href(dir, p);
    let params = params.map_or(String::new(), |p| {
        format!("<params><xi:include href=\"{}\" /></params>", href(p))
    });
    let devices: String = included
        .iter()
        .map(|f| format!("<xi:include href=\"{}\" />\n", href(f)))
        .collect();
    let xml = format!(
        r#"<?xml version="1.0" encoding="UTF-8" ?>
<!DOCTYPE robot PUBLIC "-//YARP//DTD yarprobotinterface 3.0//EN" "http://www.yarp.it/DTD/yarprobotinterfaceV3.0.dtd">
<robot name="{name}" build="1" portprefix="/icub" xmlns:xi="http://www.w3.org/2001/XInclude">
{params}
<devices>
{devices}
<device name="fault_nws" type="controlBoard_nws_yarp">
  <param name="name">/fault/left_arm</param>
  <param name="period">0.01</param>
  <action phase="startup" level="5" type="attach"><param name="device">{attach}</param></action>
  <action phase="shutdown" level="5" type="detach" />
</device>
</devices>
</robot>
"#
    );
    let path = dir.join(format!("{name}-fault.xml"));
    std::fs::write(&path, xml).expect("robot file");
    path
}

/// `get encs` over `yarp rpc`: the values when the device answers.
fn encoders(net: &YarpNet) -> Option<Vec<f64>> {
    let out = net.rpc("/fault/left_arm/rpc:i", "get encs\n");
    let line = out.lines().find(|l| l.contains("Response: [is] encs"))?;
    let inside = line.split('(').nth(1)?.split(')').next()?;
    inside.split_whitespace().map(|v| v.parse().ok()).collect()
}

/// Polls `get encs` until it gives values (or not, per `want`), at most `limit`.
fn encoders_become(net: &YarpNet, want: bool, limit: Duration) -> bool {
    let start = Instant::now();
    while start.elapsed() < limit {
        if encoders(net).is_some() == want {
            return true;
        }
        std::thread::sleep(Duration::from_millis(200));
    }
    false
}

/// `yarprobotinterface --config FILE` on `net`; returns once its wrapper port is up.
fn robot_interface(net: &YarpNet, file: &Path, env: &[(&str, String)]) -> Proc {
    let mut c = net.cmd("yarprobotinterface", "yarp-device-programs");
    c.args(["--config", file.to_str().expect("utf-8 path")]);
    for (k, v) in env {
        c.env(k, v);
    }
    let mut p = Proc::spawn("yarprobotinterface", c);
    p.wait_line(
        "yarprobotinterface running happily",
        Duration::from_secs(60),
    );
    net.wait_registered("/fault/left_arm/rpc:i");
    p
}

#[test]
fn can_board_emulator_killed_and_restarted() {
    let Some(rc) = robots_configuration() else {
        eprintln!("SKIPPED: ../shared/robots-configuration not found");
        return;
    };
    let net = YarpNet::new();
    let _server = net.server();
    // one cannelloni hub for the left arm's network (CanDeviceNum 1): base + 1
    let base = free_udp_pair();
    let emulator = || {
        let mut c = net.cmd("icub-board-emulator", "icub-emulators");
        c.args(["--bus", &format!("udp-hub://127.0.0.1:{}", base + 1)]);
        for b in 1..=4 {
            c.args(["--board", &format!("{b}:mc")]);
        }
        let mut p = Proc::spawn("icub-board-emulator", c);
        p.wait_line("ready", STEP);
        p
    };
    let mut emu = emulator();
    let file = robot_xml(
        net.dir.path(),
        "iCubGenova01",
        None,
        &[rc.join("iCubGenova01/hardware/motorControl/icub_left_arm.xml")],
        "left_arm_mc",
    );
    let backend = format!("udp://127.0.0.1:{base}+n");
    let mut robot = robot_interface(&net, &file, &[("YARP_ICUB_CAN_BACKEND", backend)]);
    let before = encoders(&net).expect("encoders before the fault");
    assert_eq!(before.len(), 8);

    emu.kill();
    let t0 = Instant::now();
    // reads fail after the broadcast timeout (500 ms), never hang
    assert!(encoders_become(&net, false, STEP), "encoders still read");
    let report = robot.wait_line("have not heard from board", STEP);
    let took = t0.elapsed();
    println!("CAN fault reported after {took:?}: {report}");
    assert!(took < Duration::from_secs(5), "reported after {took:?}");
    assert!(report.contains("left_arm_mc"), "{report}");

    let _emu = emulator();
    let t1 = Instant::now();
    assert!(
        encoders_become(&net, true, STEP),
        "encoders never came back; yarprobotinterface printed:\n{}",
        robot.seen.join("\n")
    );
    println!("CAN encoders back {:?} after the restart", t1.elapsed());
    let back = robot.wait_line("talks again after", STEP);
    assert!(back.contains("restart yarprobotinterface"), "{back}");
    assert_eq!(encoders(&net).map(|e| e.len()), Some(8));
}

/// iCubGenova02's left arm board (`left_arm-eb1-j0_3`) behind `/fault/left_arm`, with a
/// name server; the robot's 10.0.1.x boards and host on a 127.x net of their own (per test
/// process and `salt`, so that concurrent tests do not share addresses).
struct EthArm {
    net: YarpNet,
    _server: Proc,
    robot_dir: PathBuf,
    file: PathBuf,
    net_byte: u32,
    map: String,
}

impl EthArm {
    fn new(name: &str, salt: u32) -> Option<EthArm> {
        let Some(rc) = robots_configuration() else {
            eprintln!("SKIPPED: ../shared/robots-configuration not found");
            return None;
        };
        let net = YarpNet::new();
        let server = net.server();
        let robot_dir = rc.join("iCubGenova02");
        let file = robot_xml(
            net.dir.path(),
            name,
            Some(&robot_dir.join("hardware/electronics/pc104.xml")),
            &[robot_dir.join("hardware/motorControl/left_arm-eb1-j0_3-mc.xml")],
            "left_arm-eb1-j0_3-mc",
        );
        let net_byte = 2 + (std::process::id() + salt) % 200;
        let map = format!("10.0.1.0/24=127.{net_byte}.1.0/24");
        Some(EthArm {
            net,
            _server: server,
            robot_dir,
            file,
            net_byte,
            map,
        })
    }

    /// The board's emulator, once it serves the board.
    fn emulator(&self) -> Proc {
        let mut c = self.net.cmd("icub-eth-emulator", "icub-emulators");
        c.arg(&self.robot_dir)
            .args(["--config", self.file.to_str().expect("utf-8 path")])
            .args(["--address-map", &self.map]);
        let mut p = Proc::spawn("icub-eth-emulator", c);
        p.wait_line("left_arm-eb1-j0_3", STEP);
        p
    }

    /// `yarprobotinterface` on the board, once `/fault/left_arm` is up.
    fn robot(&self) -> Proc {
        robot_interface(
            &self.net,
            &self.file,
            &[("YARP_ICUB_ETH_ADDRESS_MAP", self.map.clone())],
        )
    }
}

#[test]
fn eth_board_emulator_killed_and_restarted() {
    let Some(arm) = EthArm::new("iCubGenova02", 0) else {
        return;
    };
    let net = &arm.net;
    let mut emu = arm.emulator();
    let mut robot = arm.robot();
    let before = encoders(net).expect("encoders before the fault");
    assert_eq!(before.len(), 4);

    emu.kill();
    let t0 = Instant::now();
    assert!(encoders_become(net, false, STEP), "encoders still read");
    let report = robot.wait_line("refused until it talks again", STEP);
    let took = t0.elapsed();
    println!("Ethernet fault reported after {took:?}: {report}");
    assert!(took < Duration::from_secs(5), "reported after {took:?}");
    assert!(
        report.contains("left_arm-eb1-j0_3") && report.contains("restart yarprobotinterface"),
        "{report}"
    );

    // a restarted board waits to be configured: reads keep failing (no hang), the report
    // stays the same, and a new yarprobotinterface brings the part back
    let _emu = arm.emulator();
    std::thread::sleep(Duration::from_secs(2));
    assert_eq!(encoders(net), None, "a reset board is not running");
    robot.kill();
    let _robot = arm.robot();
    assert!(
        encoders_become(net, true, STEP),
        "the restarted robot reads encoders"
    );
}

/// A board that reboots mid-run (its emulator killed and started again at once): its
/// sequence numbers restart, which the host reports as icub-main's `hostTransceiver`
/// does (`detected an ERROR in sequence number from IP = ... Expected: N - Received: 1`)
/// when the board next talks, here its answer to an ask (`get llim 0`). The rebooted board
/// lost its configuration and sends no regulars, so the part's reads stay refused with the
/// presence report naming the cure; as in C++, a new yarprobotinterface brings it back.
#[test]
fn eth_board_rebooted_mid_run() {
    let Some(arm) = EthArm::new("iCubGenova02-reboot", 202) else {
        return;
    };
    let net = &arm.net;
    let mut emu = arm.emulator();
    let mut robot = arm.robot();
    assert!(encoders(net).is_some(), "encoders before the reboot");

    emu.kill();
    let _emu = arm.emulator();
    let asked = net.rpc("/fault/left_arm/rpc:i", "get llim 0\n");
    let report = robot.wait_line("detected an ERROR in sequence number", STEP);
    println!("after the reboot, `get llim 0`: {asked}\nhost: {report}");
    let number = |key: &str| -> u64 {
        let rest = report.split(key).nth(1).unwrap_or("");
        let digits: String = rest
            .trim_start()
            .chars()
            .take_while(char::is_ascii_digit)
            .collect();
        digits
            .parse()
            .unwrap_or_else(|_| panic!("no `{key}` number in: {report}"))
    };
    let (expected, received) = (number("Expected:"), number("Received:"));
    assert!(
        report.contains("IP = 10.0.1.1") && received < expected && received <= 2,
        "a restarted sequence from the board: {report}"
    );
    // Its answer was heard, but no regulars follow: the part's reads are refused again.
    assert!(
        encoders_become(net, false, STEP),
        "a rebooted board's part still reads"
    );
    assert!(
        robot.child.try_wait().ok().flatten().is_none(),
        "yarprobotinterface died:\n{}",
        robot.seen.join("\n")
    );

    robot.kill();
    let _robot = arm.robot();
    assert!(
        encoders_become(net, true, STEP),
        "a new yarprobotinterface reads the rebooted board"
    );
}

/// A storm of garbage at the host's UDP port (random lengths and bytes, a truncated
/// ropframe header, from an address that is no board and from a board's own address)
/// while the left arm runs: the host drops what is no board's, counts what does not parse,
/// stays up, and the part's encoders read again once the storm ends.
#[test]
fn eth_host_survives_a_datagram_storm() {
    let Some(arm) = EthArm::new("iCubGenova02-storm", 101) else {
        return;
    };
    let (net, net_byte) = (&arm.net, arm.net_byte);
    let _emu = arm.emulator();
    let mut robot = arm.robot();
    assert!(encoders(net).is_some(), "encoders before the storm");

    // pc104.xml: the host is 10.0.1.104, port 12345; the board 10.0.1.1
    let host = format!("127.{net_byte}.1.104:12345");
    let strangers = std::net::UdpSocket::bind("127.0.0.1:0").expect("socket");
    let impostor =
        std::net::UdpSocket::bind(format!("127.{net_byte}.1.1:0")).expect("a board's address");
    let mut x: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut next = || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        x
    };
    let start = Instant::now();
    let mut sent = 0u64;
    while start.elapsed() < Duration::from_secs(2) {
        let len = (next() % 1500) as usize;
        let mut d: Vec<u8> = (0..len).map(|_| next() as u8).collect();
        if sent.is_multiple_of(3) && d.len() >= 24 {
            // a ropframe's start marker, then nonsense
            d[..4].copy_from_slice(&0x1234_5678u32.to_le_bytes());
        }
        let from = if sent.is_multiple_of(2) {
            &strangers
        } else {
            &impostor
        };
        let _ = from.send_to(&d, &host);
        sent += 1;
    }
    println!("sent {sent} garbage datagrams in 2 s");
    assert!(
        robot.child.try_wait().ok().flatten().is_none(),
        "yarprobotinterface died in the storm:\n{}",
        robot.seen.join("\n")
    );
    assert!(
        encoders_become(net, true, STEP),
        "the left arm's encoders after the storm"
    );
    let _ = robot.drain();
    assert!(
        !robot.seen.iter().any(|l| l.contains("panicked")),
        "{}",
        robot.seen.join("\n")
    );
}

/// A UDP port `p` with `p + 1` free too (the hub of network 1 is `base + 1`).
fn free_udp_pair() -> u16 {
    for base in (30_000..60_000).step_by(97) {
        let a = std::net::UdpSocket::bind(("127.0.0.1", base));
        let b = std::net::UdpSocket::bind(("127.0.0.1", base + 1));
        if a.is_ok() && b.is_ok() {
            return base;
        }
    }
    panic!("no free UDP ports (run under netns-run)");
}
