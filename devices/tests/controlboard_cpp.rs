//! Interoperability with a real C++ YARP (run under netns-run): C++ `yarp rpc` drives our
//! `controlBoard_nws_yarp`; a C++ `remote_controlboard` drives it and our
//! `remote_controlboard` drives a C++ `fakeMotionControl` when the C++ build has those
//! devices (`yarpdev --list`). The C++ programs come from `YARP_CPP_BIN`, else
//! `<repo>/.venv-yarp/bin`; without them every test prints `SKIPPED: C++ YARP not
//! found` and passes.

mod controlboard_common;

use controlboard_common::{name_client, T};
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::Instant;
use yarp_devices::PolyDriver;
use yarp_proto::Property;

/// The real C++ program `prog` (see `yarp_interop_tests::cpp_bin_dir`).
fn cpp_program(prog: &str) -> Option<PathBuf> {
    yarp_interop_tests::cpp_bin_dir()
        .map(|d| yarp_interop_tests::real_cpp_program(&d, prog))
        .filter(|p| p.is_file())
}

fn skip(what: &str) {
    let mut e = std::io::stderr().lock();
    let _ = writeln!(e, "SKIPPED: {what}");
}

/// Waits for `child` at most `T`, killing it if it is still running; returns its stdout.
fn finish(mut child: Child) -> String {
    let start = Instant::now();
    while child.try_wait().expect("try_wait").is_none() {
        if start.elapsed() > T {
            let _ = child.kill();
            let _ = child.wait();
            panic!("C++ program did not finish within {T:?}");
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let mut out = String::new();
    if let Some(mut s) = child.stdout.take() {
        let _ = s.read_to_string(&mut out);
    }
    out
}

/// C++ `yarp rpc <name>/rpc:i` against our controlBoard_nws_yarp over a 4-joint
/// fakeMotionControl: types `input`, returns the `Response` lines (or `None`, after a
/// SKIPPED notice, without the C++ peer).
fn cpp_rpc_session(name: &str, input: &[u8]) -> Option<Vec<String>> {
    let Some(yarp) = cpp_program("yarp") else {
        skip("C++ YARP not found (set YARP_CPP_BIN or install .venv-yarp)");
        return None;
    };
    name_client();
    let _nws = PolyDriver::open(
        &Property::from_config_text(format!(
            "device controlBoard_nws_yarp\nsubdevice fakeMotionControl\nname {name}\n\
             [GENERAL]\njoints 4\n"
        ))
        .unwrap(),
    )
    .expect("open wrapper");
    let mut child = Command::new(&yarp)
        .args(["rpc", &format!("{name}/rpc:i")])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("spawn C++ yarp rpc");
    child.stdin.take().unwrap().write_all(input).unwrap();
    let out = finish(child);
    Some(
        out.lines()
            .filter(|l| l.starts_with("Response"))
            .map(str::to_string)
            .collect(),
    )
}

#[test]
fn cpp_yarp_rpc_drives_our_wrapper() {
    let Some(lines) = cpp_rpc_session(
        "/cpp",
        b"get axes\n[get] [axes]\n[set] [pos] 0 10.0\n[get] [pos] 0\n[get] [prot]\nfoo bar\n[set] [poss] 5\n",
    ) else {
        return;
    };
    let out = lines.join("\n");
    assert_eq!(lines.len(), 7, "{out}");
    assert!(
        lines[0].starts_with("Response: [is] axes 4 [tsta] 0 "),
        "{out}"
    );
    assert!(
        lines[1].starts_with("Response: [is] [axes] 4 [tsta] 1 "),
        "{out}"
    );
    assert_eq!(lines[2], "Response: [ok]");
    assert!(
        lines[3].starts_with("Response: [is] [pos] 10.0 [tsta] 2 "),
        "{out}"
    );
    assert_eq!(lines[4], "Response: [prot] 1 9 0 [ok]");
    assert_eq!(lines[5], "Response: [fail]");
    assert_eq!(lines[6], "Response: [fail]");
}

/// C++ `yarp rpc` text commands for impedance and calibration get the replies C++ 3.12's
/// parser gives (plain words are packed into vocabs and echoed as typed).
#[test]
fn cpp_yarp_rpc_impedance_and_calibration() {
    let Some(lines) = cpp_rpc_session(
        "/cppimp",
        b"set iimp ipr 0 (1.0 0.5)\nget iimp ipr 0\n[get] [iimp] [llim] 0\n\
          [set] [iimp] [iof] 0 (2.5)\n[get] [iimp] [iof] 0\ncalj 0 3 1.0 2.0 3.0\n\
          cald 0\nget reca isca\nset imp ipr 0 (1.0 0.5)\n",
    ) else {
        return;
    };
    let out = lines.join("\n");
    assert_eq!(lines.len(), 9, "{out}");
    let stamped = |line: &str, head: &str| {
        assert!(
            line.starts_with(head) && line.ends_with(" [ok]") && line.contains(" [tsta] "),
            "{line} (want {head} [tsta] n t [ok])"
        );
    };
    assert_eq!(lines[0], "Response: [ok]");
    stamped(&lines[1], "Response: [is] iimp (1.0 0.5) [tsta] ");
    stamped(
        &lines[2],
        "Response: [is] [iimp] (1.0 10.0 2.0 20.0) [tsta] ",
    );
    assert_eq!(lines[3], "Response: [ok]");
    stamped(&lines[4], "Response: [is] [iimp] (2.5) [tsta] ");
    assert_eq!(lines[5], "Response: [ok]");
    assert_eq!(lines[6], "Response: [ok]");
    // the fake has no remote calibrator; `imp` is not the impedance vocab (`iimp` is)
    assert_eq!(lines[7], "Response: [fail]");
    assert_eq!(lines[8], "Response: [fail]");
}

/// The C++ devices this test needs, if the C++ build has them.
fn cpp_devices() -> Option<String> {
    let yarpdev = cpp_program("yarpdev")?;
    let child = Command::new(yarpdev)
        .arg("--list")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .ok()?;
    let out = child.wait_with_output().ok()?;
    Some(format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    ))
}

fn registered(port: &str) -> bool {
    let ns = name_client();
    let port = port.to_string();
    controlboard_common::run(async move { ns.query(&port).await.unwrap().is_some() })
}

/// Stops a child on every exit path.
struct Reap(Child);

impl Drop for Reap {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

#[test]
fn our_remote_drives_cpp_fake_motion_control() {
    let Some(list) = cpp_devices() else {
        skip("C++ YARP not found (set YARP_CPP_BIN or install .venv-yarp)");
        return;
    };
    if !(list.contains("fakeMotionControl") && list.contains("controlBoard_nws_yarp")) {
        skip("the C++ YARP build has no fakeMotionControl / controlBoard_nws_yarp (`yarpdev --list`)");
        return;
    }
    name_client();
    let child = Command::new(cpp_program("yarpdev").unwrap())
        .args([
            "--device",
            "controlBoard_nws_yarp",
            "--subdevice",
            "fakeMotionControl",
            "--name",
            "/cppfake",
            "--period",
            "0.01",
            "--GENERAL::Joints",
            "4",
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("spawn yarpdev");
    let _reap = Reap(child);
    controlboard_common::wait_for("C++ /cppfake/stateExt:o", || {
        registered("/cppfake/stateExt:o").then_some(())
    });
    let mut remote = PolyDriver::open(
        &Property::from_config_text("device remote_controlboard\nremote /cppfake\nlocal /ours\n")
            .unwrap(),
    )
    .expect("our remote_controlboard opens against C++");
    let d = remote.device();
    let axes = d.as_encoders().unwrap().get_axes().unwrap();
    assert!(axes > 0);
    let q = controlboard_common::wait_for("encoders streamed by C++", || {
        d.as_encoders().unwrap().get_encoders().ok()
    });
    assert_eq!(q.len(), axes);
    d.as_position_control()
        .unwrap()
        .position_move(0, 10.0)
        .unwrap();
    assert_eq!(
        d.as_position_control()
            .unwrap()
            .get_target_position(0)
            .unwrap(),
        10.0
    );
}

#[test]
fn cpp_remote_controlboard_drives_our_wrapper() {
    let Some(list) = cpp_devices() else {
        skip("C++ YARP not found (set YARP_CPP_BIN or install .venv-yarp)");
        return;
    };
    // the venv the C++ peer was installed into (CI: YARP_CPP_VENV)
    let python = std::env::var_os("YARP_CPP_VENV")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../.venv-yarp"))
        .join("bin/python3");
    if !list.contains("remote_controlboard") {
        skip("the C++ YARP build has no remote_controlboard device (`yarpdev --list`)");
        return;
    }
    if !python.is_file() {
        skip("no python3 with the C++ YARP bindings next to the C++ programs");
        return;
    }
    name_client();
    let _nws = PolyDriver::open(
        &Property::from_config_text(
            "device controlBoard_nws_yarp\nsubdevice fakeMotionControl\nname /ourcb\nperiod 0.01\n\
             [GENERAL]\njoints 4\n",
        )
        .unwrap(),
    )
    .expect("open wrapper");
    let script = r#"
import time, yarp
yarp.Network.init()
p = yarp.Property()
p.put("device", "remote_controlboard"); p.put("remote", "/ourcb"); p.put("local", "/pycli")
d = yarp.PolyDriver(p)
assert d.isValid(), "open"
enc = d.viewIEncoders(); pos = d.viewIPositionControl()
print("axes", enc.getAxes())
assert pos.positionMove(1, 30.0)
v = yarp.Vector(4)
deadline = time.time() + 5
while time.time() < deadline:
    if enc.getEncoders(v.data()) and abs(v[1] - 30.0) < 1e-6:
        break
    time.sleep(0.05)
print("enc1", v[1])
d.close()
"#;
    let mut child = Command::new(python)
        .arg("-c")
        .arg(script)
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("spawn python");
    let _ = child.stdin.take();
    let out = finish(child);
    assert!(out.contains("axes 4"), "{out}");
    assert!(out.contains("enc1 30.0"), "{out}");
}
