//! `icub-eth-emulator --record DIR` in its own process: what a host sends a board is in
//! `DIR/<board's robot IP>.jsonl`, one line a ROP, even after the emulator is killed.
//! Run under `netns-run`: everything stays on loopback.

use std::io::{BufRead, BufReader};
use std::net::UdpSocket;
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use icub_eth::frame::{Frame, FrameBuilder};
use icub_eth::id::ids;
use icub_eth::rop::{Rop, RopCode};

/// Kills and reaps the emulator however the test ends.
struct Emulator(Child);

impl Drop for Emulator {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn robot_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/robots-configuration/iCubGenova02")
}

#[test]
fn help_names_the_record_flag() {
    let out = Command::new(env!("CARGO_BIN_EXE_icub-eth-emulator"))
        .arg("--help")
        .output()
        .expect("run icub-eth-emulator --help");
    assert!(out.status.success());
    let help = String::from_utf8_lossy(&out.stdout);
    assert!(
        help.contains("--record DIR") && help.contains(".jsonl"),
        "{help}"
    );
}

#[test]
fn the_rops_a_host_sends_are_recorded_per_board() {
    let rec = tempfile::tempdir().unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_icub-eth-emulator"))
        .arg(robot_dir())
        .args(["--address-map", "10.0.1.0/24=127.0.21.0/24", "--record"])
        .arg(rec.path())
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .expect("spawn icub-eth-emulator");
    let stdout = child.stdout.take().unwrap();
    let mut emu = Emulator(child);
    let mut lines = BufReader::new(stdout).lines();
    loop {
        let line = lines.next().expect("the emulator says it serves").unwrap();
        if line.starts_with("icub-eth-emulator: serving") {
            break;
        }
    }

    // a host at the robot's PC104 address (mapped), talking to left_arm-eb1 (10.0.1.1)
    let host = UdpSocket::bind("127.0.21.104:0").unwrap();
    host.set_read_timeout(Some(Duration::from_millis(200)))
        .unwrap();
    let board = "127.0.21.1:12345";
    let mut ask = Rop::ask(ids::COMM_STATUS);
    ask.ctrl.plussign = true;
    ask.signature = Some(0x1234_5678);
    let set = Rop::set(
        ids::APPL_CONFIG,
        vec![
            0xe8, 0x03, 0x90, 0x01, 0x2c, 0x01, 0x2c, 0x01, 0, 0, 5, 0, 0, 0, 0, 0,
        ],
    );
    let datagrams = [vec![ask], vec![set.clone()]];
    for (seq, rops) in datagrams.iter().enumerate() {
        let mut fb = FrameBuilder::new(1400);
        for r in rops {
            fb.push(r).unwrap();
        }
        host.send_to(&fb.finish(seq as u64 + 1, 1000 * seq as u64), board)
            .unwrap();
    }
    // the board answered the ask: both datagrams were read
    let mut buf = [0u8; 2048];
    let end = Instant::now() + Duration::from_secs(10);
    let mut said = false;
    while !said {
        assert!(Instant::now() < end, "no say from the board");
        if let Ok(n) = host.recv(&mut buf) {
            let f = Frame::decode(&buf[..n]).unwrap();
            f.visit_rops(|r| said |= r.code == RopCode::Say && r.id32 == ids::COMM_STATUS);
        }
    }
    // killed: what was recorded is on disk, whole lines (flushed per datagram); the
    // writer may still be on the last datagram, so wait for two lines first
    let file = rec.path().join("10.0.1.1.jsonl");
    let end = Instant::now() + Duration::from_secs(10);
    while std::fs::read_to_string(&file).map_or(0, |t| t.lines().count()) < 2 {
        assert!(Instant::now() < end, "{} has not two lines", file.display());
        std::thread::sleep(Duration::from_millis(20));
    }
    let _ = emu.0.kill();
    let _ = emu.0.wait();
    let text = std::fs::read_to_string(&file).unwrap();
    let got: Vec<&str> = text.lines().collect();
    assert_eq!(got.len(), 2, "{text}");
    assert!(got[0].starts_with("{\"t\":"), "{}", got[0]);
    assert!(got[0].contains("\"from\":\"127.0.21.104:"), "{}", got[0]);
    assert!(got[0].contains("\"seq\":1,"), "{}", got[0]);
    assert!(
        got[0].contains(&format!(
            "\"ropcode\":1,\"rop\":\"ask\",\"id32\":\"{:#010x}\"",
            ids::COMM_STATUS.0
        )),
        "{}",
        got[0]
    );
    assert!(
        got[0].contains("\"signature\":\"0x12345678\""),
        "{}",
        got[0]
    );
    assert!(got[0].ends_with("\"data\":\"\"}"), "{}", got[0]);
    assert!(
        got[1].contains(&format!(
            "\"ropcode\":3,\"rop\":\"set\",\"id32\":\"{:#010x}\"",
            ids::APPL_CONFIG.0
        )),
        "{}",
        got[1]
    );
    assert!(
        got[1].ends_with("\"data\":\"e80390012c012c010000050000000000\"}"),
        "{}",
        got[1]
    );
    let t = |l: &str| -> f64 { l["{\"t\":".len()..l.find(',').unwrap()].parse().unwrap() };
    assert!(0.0 < t(got[0]) && t(got[0]) <= t(got[1]), "{text}");
    // the boards no host talked to have empty files
    assert_eq!(
        std::fs::read_to_string(rec.path().join("10.0.1.2.jsonl")).unwrap(),
        ""
    );
}
