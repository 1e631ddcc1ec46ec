//! The `icub-board-emulator` binary in its own process, driven over UDP (cannelloni).
//! Run under `netns-run`: everything stays on loopback.

use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::sync::Arc;
use std::time::{Duration, Instant};

use icub_can::bus::config::BusSpec;
use icub_can::client::{McParams, MotorControlClient, StrainClient, StrainParams};
use icub_can::proto::ControlMode;

/// Kills and reaps the emulator however the test ends.
struct Emulator {
    child: Child,
    lines: mpsc::Receiver<String>,
}

impl Drop for Emulator {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn spawn(args: &[&str]) -> (Emulator, Vec<String>) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_icub-board-emulator"))
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .expect("spawn emulator");
    let stdout = child.stdout.take().unwrap();
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stdout).lines().map_while(Result::ok) {
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    let emu = Emulator { child, lines: rx };
    let mut buses = Vec::new();
    let deadline = Instant::now() + Duration::from_secs(10);
    loop {
        let left = deadline.saturating_duration_since(Instant::now());
        let line = emu
            .lines
            .recv_timeout(left)
            .expect("emulator did not get ready");
        if line == "ready" {
            return (emu, buses);
        }
        // "bus NAME LOCAL boards ..."
        buses.push(
            line.split_whitespace()
                .nth(2)
                .expect("bus line")
                .to_string(),
        );
    }
}

fn free_port_base(count: u16) -> u16 {
    'outer: for base in (30000..60000).step_by(100) {
        let mut held = Vec::new();
        for p in base..base + count {
            match std::net::UdpSocket::bind(("127.0.0.1", p)) {
                Ok(s) => held.push(s),
                Err(_) => continue 'outer,
            }
        }
        return base;
    }
    panic!("no free port range");
}

#[test]
fn emulator_process_serves_motor_and_strain_boards() {
    let (_emu, buses) = spawn(&[
        "--bus",
        "udp-hub://127.0.0.1:0",
        "--board",
        "1:mc",
        "--board",
        "0x0D:strain",
    ]);
    assert_eq!(buses.len(), 1);
    let url = format!("udp://{}", buses[0]);
    let open = || BusSpec::parse(&url, None).unwrap().open().unwrap();

    let mut params = McParams::uniform(&[1], 2, 11.375);
    params.reply_timeout = Duration::from_millis(300);
    let mc = MotorControlClient::open(open(), params).unwrap();
    mc.set_control_mode(1, ControlMode::Position).unwrap();
    mc.set_ref_speed(1, 90.0).unwrap();
    mc.position_move(1, 25.0).unwrap();
    let deadline = Instant::now() + Duration::from_secs(5);
    while !mc.motion_done(1).unwrap() {
        assert!(Instant::now() < deadline, "move did not finish");
        std::thread::sleep(Duration::from_millis(20));
    }
    let deadline = Instant::now() + Duration::from_secs(2);
    let pos = loop {
        if let Ok(p) = mc.encoder(1) {
            if (p - 25.0).abs() < 0.5 {
                break p;
            }
        }
        assert!(
            Instant::now() < deadline,
            "encoder broadcasts did not follow"
        );
        std::thread::sleep(Duration::from_millis(10));
    };
    assert!((pos - 25.0).abs() < 0.5);

    // A second client process-side endpoint on the same bus: the strain.
    // The same reply allowance as the motor client above: a loaded CI machine may keep
    // the emulator process off the CPU for longer than the driver's 100 ms default.
    let mut strain = StrainParams::strain(0x0D);
    strain.reply_timeout = Duration::from_millis(300);
    let ft = StrainClient::open(open(), strain).unwrap();
    let deadline = Instant::now() + Duration::from_secs(2);
    let v = loop {
        if let Ok(v) = ft.read_checked() {
            break v;
        }
        assert!(Instant::now() < deadline, "no F/T data");
        std::thread::sleep(Duration::from_millis(10));
    };
    assert!((4.9..=15.1).contains(&v[2]), "fz {}", v[2]);
    // The motor client still sees its broadcasts while the strain streams (hub relays to both).
    assert!(mc.encoder(1).is_ok());
}

#[test]
fn emulator_process_runs_the_whole_icub() {
    let base = free_port_base(10);
    let bus = format!("udp-hub://127.0.0.1:{base}+n");
    let dir = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/robots-configuration/iCubGenova01"
    );
    let mut args = vec!["--preset", "icub", "--bus", &bus];
    if std::path::Path::new(dir).exists() {
        args.extend(["--robot-dir", dir]);
    }
    let (_emu, buses) = spawn(&args);
    assert_eq!(buses.len(), 10);
    // Left leg on network 3: boards 5 6 7, AxisMap 2 3 0 1 4 5.
    let bus: Arc<dyn icub_can::CanBus> =
        BusSpec::parse(&format!("udp://127.0.0.1:{base}+n"), Some(3))
            .unwrap()
            .open()
            .unwrap();
    let mut params = McParams::uniform(&[5, 6, 7], 6, 11.375);
    params.axis_map = vec![2, 3, 0, 1, 4, 5];
    params.reply_timeout = Duration::from_millis(300);
    let mc = MotorControlClient::open(bus, params).unwrap();
    let deadline = Instant::now() + Duration::from_secs(3);
    while mc.encoders().is_err() {
        assert!(Instant::now() < deadline, "no leg encoders");
        std::thread::sleep(Duration::from_millis(10));
    }
}

#[test]
fn bad_arguments_exit_with_a_message() {
    let out = Command::new(env!("CARGO_BIN_EXE_icub-board-emulator"))
        .args(["--bus", "inproc://x", "--board", "0:mc"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("address must be 1..=14"));
    let out = Command::new(env!("CARGO_BIN_EXE_icub-board-emulator"))
        .args(["--preset", "icub", "--bus", "udp-hub://127.0.0.1:1"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("+n"));
}
