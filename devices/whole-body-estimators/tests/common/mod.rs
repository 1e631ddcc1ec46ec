//! What the live tests of wholebodydynamics share: a robot brought up in a network
//! namespace of its own from its files against `icub-robot-emulator` with its URDF as
//! its body, and the boards' and the body's torques compared.
#![allow(dead_code)]

use std::collections::HashMap;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use yarp_interop_tests::{Proc, RobotNet};

pub fn shared() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared")
}

/// The robot's network (stopped, with every program in it, when dropped) and its
/// boards' port prefix (`/ergocub`, `/icub`).
pub struct Robot {
    pub prefix: String,
    pub net: RobotNet,
}

impl Robot {
    pub fn rpc(&self, port: &str, input: &str) -> String {
        self.net.rpc(port, input)
    }
}

/// The numbers of the `Response:` lines: those of the list in it when there is one
/// (`[is] [encs] (…) [ok]`), else all of them (`[is] [axes] 6`).
pub fn numbers(reply: &str) -> Vec<f64> {
    reply
        .lines()
        .filter_map(|l| l.strip_prefix("Response:"))
        .flat_map(|l| {
            let list = match (l.find('('), l.find(')')) {
                (Some(a), Some(b)) if a < b => &l[a + 1..b],
                _ => l,
            };
            list.split_whitespace()
                .filter_map(|w| w.parse().ok())
                .collect::<Vec<f64>>()
        })
        .collect()
}

const PARTS: &[&str] = &[
    "head",
    "torso",
    "left_arm",
    "right_arm",
    "left_leg",
    "right_leg",
];

/// Each part's axis names, by asking its board (`[get] [name] j`).
pub fn axis_names(robot: &Robot) -> HashMap<&'static str, Vec<String>> {
    let mut out = HashMap::new();
    for part in PARTS {
        let port = format!("{}/{part}/rpc:i", robot.prefix);
        let axes = numbers(&robot.net.rpc(&port, "[get] [axes]\n"))
            .first()
            .copied()
            .unwrap_or(0.0) as usize;
        let input: String = (0..axes).map(|j| format!("[get] [name] {j}\n")).collect();
        let names: Vec<String> = robot
            .rpc(&port, &input)
            .lines()
            .filter_map(|l| l.strip_prefix("Response:"))
            // `[is] [name] 0 torso_roll [ok]`: the word that is neither a vocab nor a number
            .map(|l| {
                l.split_whitespace()
                    .map(|w| w.trim_matches('"'))
                    .rfind(|w| !w.starts_with('[') && w.parse::<f64>().is_err())
                    .unwrap_or_default()
                    .to_string()
            })
            .collect();
        assert_eq!(names.len(), axes, "{part}: names {names:?}");
        out.insert(*part, names);
    }
    out
}

/// The torques every part's board reports, by axis name.
pub fn board_torques(
    robot: &Robot,
    names: &HashMap<&'static str, Vec<String>>,
) -> HashMap<String, f64> {
    let mut out = HashMap::new();
    for part in PARTS {
        let t = numbers(&robot.net.rpc(
            &format!("{}/{part}/rpc:i", robot.prefix),
            "[get] [torq] [trqs]\n",
        ));
        assert_eq!(t.len(), names[part].len(), "{part}: torques {t:?}");
        out.extend(names[part].iter().cloned().zip(t));
    }
    out
}

/// What the emulated body says its joints bear (`report`).
pub fn body_torques(emulator: &mut Proc) -> HashMap<String, f64> {
    use std::io::Write;
    writeln!(
        emulator.child.stdin.as_mut().expect("the emulator's stdin"),
        "report"
    )
    .unwrap();
    let line = emulator.wait_line("body torques", Duration::from_secs(10));
    let at = line.find("body torques").unwrap() + "body torques".len();
    line[at..]
        .split_whitespace()
        .filter_map(|kv| {
            let (k, v) = kv.split_once('=')?;
            Some((k.to_string(), v.parse().ok()?))
        })
        .collect()
}

/// Moves the named joints (degrees) and waits until every part's encoders stand still.
pub fn pose(robot: &Robot, names: &HashMap<&'static str, Vec<String>>, targets: &[(&str, f64)]) {
    for part in PARTS {
        let cmds: String = targets
            .iter()
            .filter_map(|(name, deg)| {
                names[part]
                    .iter()
                    .position(|n| n == name)
                    .map(|j| format!("[set] [pos] {j} {deg}\n"))
            })
            .collect();
        if !cmds.is_empty() {
            robot
                .net
                .rpc(&format!("{}/{part}/rpc:i", robot.prefix), &cmds);
        }
    }
    let start = Instant::now();
    let mut last: Vec<f64> = Vec::new();
    loop {
        std::thread::sleep(Duration::from_millis(500));
        let now: Vec<f64> = PARTS
            .iter()
            .flat_map(|p| {
                numbers(
                    &robot
                        .net
                        .rpc(&format!("{}/{p}/rpc:i", robot.prefix), "[get] [encs]\n"),
                )
            })
            .collect();
        if !last.is_empty()
            && now.len() == last.len()
            && now.iter().zip(&last).all(|(a, b)| (a - b).abs() < 0.01)
        {
            break;
        }
        let moving: Vec<(usize, f64, f64)> = now
            .iter()
            .zip(&last)
            .enumerate()
            .filter(|(_, (a, b))| (*a - *b).abs() >= 0.01)
            .map(|(i, (a, b))| (i, *a, *b))
            .collect();
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "the joints did not settle: {moving:?} ({} vs {} values)",
            now.len(),
            last.len()
        );
        last = now;
    }
}

/// A running robot: its network, the emulator (with the body) and yarprobotinterface.
pub struct Running {
    pub robot: Robot,
    /// The name server (stopped when dropped).
    pub server: Proc,
    pub emulator: Proc,
    pub ri: Proc,
    pub names: HashMap<&'static str, Vec<String>>,
    /// wholebodydynamics' `axesNames`.
    pub estimated: Vec<String>,
}

/// Which robot, as installed: its name, URDF, the data directory holding the URDF, the
/// top-level file (`None`: yarprobotinterface.ini's), its boards' port prefix and
/// wholebodydynamics' RPC port.
pub struct RobotSpec {
    pub name: &'static str,
    pub urdf: PathBuf,
    pub data_dir: PathBuf,
    pub config: Option<&'static str>,
    pub prefix: &'static str,
    pub wbd_rpc: &'static str,
}

/// Brings the robot of `dir` up with its URDF as its body held as `stance`
/// says (`icub-robot-emulator --stance`), then calibrates wholebodydynamics' offsets
/// (`calib all 300`: base_link holds the robot) or, standing, zeroes them (`resetOffset`:
/// the emulated sensors have none) once the start-up calibration is over.
pub fn start(spec: &RobotSpec, dir: &std::path::Path, stance: &str) -> Running {
    let urdf = &spec.urdf;
    let robot = Robot {
        prefix: spec.prefix.to_string(),
        net: RobotNet::new(dir),
    };
    let server = robot.net.server();
    let serial = dir.join(".serial");
    std::fs::create_dir_all(&serial).unwrap();
    let mut emulator = {
        let mut c = robot.net.cmd("icub-robot-emulator", "icub-emulators");
        c.arg(dir)
            .args(["--address-map", "", "--stance", stance])
            .arg("--serial-dir")
            .arg(&serial)
            .arg("--urdf")
            .arg(urdf);
        if let Some(config) = spec.config {
            c.args(["--config", config]);
        }
        robot.net.spawn("icub-robot-emulator", c)
    };
    emulator.wait_line("ready: ", Duration::from_secs(90));
    let env: Vec<(String, String)> = emulator
        .seen
        .iter()
        .filter_map(|l| l.strip_prefix("env ")?.split_once('='))
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    let mut ri = {
        let mut c = robot.net.cmd("yarprobotinterface", "yarp-device-programs");
        c.current_dir(dir)
            .envs(env)
            .env("YARP_ROBOT_NAME", spec.name)
            .env("YARP_DATA_DIRS", &spec.data_dir);
        if let Some(config) = spec.config {
            c.args(["--config", config]);
        }
        robot.net.spawn("yarprobotinterface", c)
    };
    ri.wait_line("running happily", Duration::from_secs(150));
    let names = axis_names(&robot);
    if stance == "fixed-root" {
        // The offsets against the body held at its root (the emulated sensors have none).
        let reply = robot.net.rpc(spec.wbd_rpc, "calib all 300\n");
        assert!(reply.contains("[ok]"), "calib: {reply}");
        ri.wait_line(
            "F/T offsets calibrated over 300 samples",
            Duration::from_secs(30),
        );
    } else {
        // Standing, no calibration holds: the emulated sensors have no offset.
        let done = "F/T offsets calibrated over 100 samples";
        if !ri.seen.iter().any(|l| l.contains(done)) {
            ri.wait_line(done, Duration::from_secs(30));
        }
        let reply = robot.net.rpc(spec.wbd_rpc, "resetOffset all\n");
        assert!(reply.contains("[ok]"), "resetOffset: {reply}");
    }
    let text = std::fs::read_to_string(dir.join("estimators/wholebodydynamics.xml")).unwrap();
    let key = "name=\"axesNames\">(";
    let at = text.find(key).unwrap() + key.len();
    let estimated = text[at..]
        .split(')')
        .next()
        .unwrap()
        .split(',')
        .map(|s| s.trim().to_string())
        .collect();
    Running {
        robot,
        server,
        emulator,
        ri,
        names,
        estimated,
    }
}

/// The worst difference between the boards' torques and the body's over `axes`, failing
/// beyond 0.05 N·m or 2 %.
pub fn check_torques(r: &mut Running, axes: &[String], what: &str) -> (f64, String) {
    // the estimate's filters (3 Hz) settle
    std::thread::sleep(Duration::from_secs(1));
    r.ri.drain();
    let truth = body_torques(&mut r.emulator);
    let boards = board_torques(&r.robot, &r.names);
    let mut worst = (0.0f64, String::new());
    for axis in axes {
        let t = *truth
            .get(axis)
            .unwrap_or_else(|| panic!("the body reports no {axis}: {truth:?}"));
        let e = *boards
            .get(axis)
            .unwrap_or_else(|| panic!("no board reports {axis}: {boards:?}"));
        let tolerance = (0.02 * t.abs()).max(0.05);
        assert!(
            (t - e).abs() <= tolerance,
            "{what}: {axis}: estimated {e:.4} N·m, the body bears {t:.4} N·m"
        );
        if (t - e).abs() > worst.0 {
            worst = ((t - e).abs(), format!("{what} {axis}: {e:.4} vs {t:.4}"));
        }
    }
    worst
}

/// The robot's files copied as they are (the user then edits one).
pub fn copy_dir(from: &std::path::Path, to: &std::path::Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap().map(Result::unwrap) {
        let target = to.join(e.file_name());
        if e.file_type().unwrap().is_dir() {
            copy_dir(&e.path(), &target);
        } else {
            std::fs::copy(e.path(), target).unwrap();
        }
    }
}

/// Pushes `link` down with 10 N through the emulator's standard input, once it says so.
pub fn push_down(r: &mut Running, link: &str) {
    use std::io::Write;
    writeln!(
        r.emulator
            .child
            .stdin
            .as_mut()
            .expect("the emulator's stdin"),
        "push {link} 0 0 -10"
    )
    .unwrap();
    r.emulator
        .wait_line(&format!("pushed: push {link}"), Duration::from_secs(10));
}

/// The first six numbers a wrench port sends (`yarp read`).
pub fn read_wrench(r: &Running, port: &str) -> Vec<f64> {
    let mut c = r.robot.net.cmd("yarp", "yarp-cli");
    c.args(["read", "/reader", port]);
    let mut reader = r.robot.net.spawn("yarp read", c);
    loop {
        let l = reader.wait_line(".", Duration::from_secs(10));
        let v: Vec<f64> = l
            .split_whitespace()
            .filter_map(|w| w.parse().ok())
            .collect();
        if v.len() == 6 {
            return v;
        }
    }
}
