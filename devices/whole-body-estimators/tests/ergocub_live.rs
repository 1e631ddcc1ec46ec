//! wholebodydynamics on ergoCubSN001, live from the robot's own files: our
//! `yarprobotinterface` on `ergocub.xml` against `icub-robot-emulator` with the robot's
//! URDF as its body, hanging at its root (as on the crane): the F/T sensors and the
//! waist MTi read the body's statics. After `calib` on `<prefix>/rpc` (offsets: the
//! emulated sensors have none), in three poses, the torques the boards report (which
//! wholebodydynamics sends them as their virtual torque sensors) are the body's joint
//! torques, within 0.05 N·m or 2 %.

use std::collections::HashMap;
use std::path::PathBuf;
use std::process::Command;
use std::time::{Duration, Instant};

use yarp_interop_tests::{robot_addresses, run_fed, workspace_program, NetNs, Proc};

fn shared() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared")
}

/// The robot's network: its namespace, the name server's configuration and every
/// process group started in it (stopped at the end, however the test ends).
struct Robot {
    ns: NetNs,
    conf: tempfile::TempDir,
    groups: Vec<u32>,
}

impl Robot {
    fn cmd(&self, program: &str, package: &str) -> Command {
        use std::os::unix::process::CommandExt;
        let mut c = self.ns.command(workspace_program(program, package));
        c.process_group(0)
            .env("YARP_CONFIG_HOME", self.conf.path())
            .env_remove("YARP_NAMESPACE")
            .env("RUST_LOG", "info");
        c
    }

    fn spawn(&mut self, name: &str, c: Command) -> Proc {
        let p = Proc::spawn(name, c);
        self.groups.push(p.pid());
        p
    }

    fn rpc(&self, port: &str, input: &str) -> String {
        let mut c = self.cmd("yarp", "yarp-cli");
        c.args(["rpc", port]);
        run_fed("yarp rpc", c, input, Duration::from_secs(30))
    }
}

impl Drop for Robot {
    fn drop(&mut self) {
        for signal in ["-TERM", "-KILL"] {
            for pgid in &self.groups {
                let _ = Command::new("kill")
                    .args([signal, "--", &format!("-{pgid}")])
                    .stderr(std::process::Stdio::null())
                    .status();
            }
            std::thread::sleep(Duration::from_millis(300));
        }
    }
}

/// The numbers of the `Response:` lines: those of the list in it when there is one
/// (`[is] [encs] (…) [ok]`), else all of them (`[is] [axes] 6`).
fn numbers(reply: &str) -> Vec<f64> {
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
fn axis_names(robot: &Robot) -> HashMap<&'static str, Vec<String>> {
    let mut out = HashMap::new();
    for part in PARTS {
        let port = format!("/ergocub/{part}/rpc:i");
        let axes = numbers(&robot.rpc(&port, "[get] [axes]\n"))
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
fn board_torques(
    robot: &Robot,
    names: &HashMap<&'static str, Vec<String>>,
) -> HashMap<String, f64> {
    let mut out = HashMap::new();
    for part in PARTS {
        let t = numbers(&robot.rpc(&format!("/ergocub/{part}/rpc:i"), "[get] [torq] [trqs]\n"));
        assert_eq!(t.len(), names[part].len(), "{part}: torques {t:?}");
        out.extend(names[part].iter().cloned().zip(t));
    }
    out
}

/// What the emulated body says its joints bear (`report`).
fn body_torques(emulator: &mut Proc) -> HashMap<String, f64> {
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
fn pose(robot: &Robot, names: &HashMap<&'static str, Vec<String>>, targets: &[(&str, f64)]) {
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
            robot.rpc(&format!("/ergocub/{part}/rpc:i"), &cmds);
        }
    }
    let start = Instant::now();
    let mut last: Vec<f64> = Vec::new();
    loop {
        std::thread::sleep(Duration::from_millis(500));
        let now: Vec<f64> = PARTS
            .iter()
            .flat_map(|p| numbers(&robot.rpc(&format!("/ergocub/{p}/rpc:i"), "[get] [encs]\n")))
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

/// A running ergoCub: its network, the emulator (with the body) and yarprobotinterface.
struct Running {
    robot: Robot,
    emulator: Proc,
    ri: Proc,
    names: HashMap<&'static str, Vec<String>>,
    /// wholebodydynamics' `axesNames`.
    estimated: Vec<String>,
}

/// Brings the robot of `dir` up with ergoCubSN001's URDF as its body held as `stance`
/// says (`icub-robot-emulator --stance`), then calibrates wholebodydynamics' offsets
/// (`calib all 300`: base_link holds the robot) or, standing, zeroes them (`resetOffset`:
/// the emulated sensors have none) once the start-up calibration is over.
fn start(dir: &std::path::Path, stance: &str) -> Running {
    let urdf = shared().join("robot-models/ergoCub/robots/ergoCubSN001/model.urdf");
    let mut robot = Robot {
        ns: NetNs::new().expect("a network namespace (run under netns-run)"),
        conf: tempfile::tempdir().unwrap(),
        groups: Vec::new(),
    };
    robot
        .ns
        .add_addresses(&robot_addresses(dir))
        .expect("the robot's addresses");
    let mut server = {
        let mut c = robot.cmd("yarpserver", "yarp-net");
        c.args(["--ip", "127.0.0.1", "--socket", "10000", "--write"]);
        robot.spawn("yarpserver", c)
    };
    server.wait_line("Ok. Ready!", Duration::from_secs(20));
    std::mem::forget(server); // its process group is stopped with the robot's
    let serial = dir.join(".serial");
    std::fs::create_dir_all(&serial).unwrap();
    let mut emulator = {
        let mut c = robot.cmd("icub-robot-emulator", "icub-emulators");
        c.arg(dir)
            .args(["--address-map", ""])
            .arg("--serial-dir")
            .arg(&serial)
            .arg("--urdf")
            .arg(&urdf);
        robot.spawn("icub-robot-emulator", c)
    };
    emulator.wait_line("ready: ", Duration::from_secs(90));
    let env: Vec<(String, String)> = emulator
        .seen
        .iter()
        .filter_map(|l| l.strip_prefix("env ")?.split_once('='))
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    let mut ri = {
        let mut c = robot.cmd("yarprobotinterface", "yarp-device-programs");
        c.current_dir(dir)
            .envs(env)
            .env("YARP_ROBOT_NAME", "ergoCubSN001")
            .env("YARP_DATA_DIRS", shared().join("robot-models/ergoCub"));
        robot.spawn("yarprobotinterface", c)
    };
    ri.wait_line("running happily", Duration::from_secs(150));
    let names = axis_names(&robot);
    // The offsets against the body held at its root (the emulated sensors have none).
    let reply = robot.rpc("/wholeBodyDynamics/rpc", "calib all 300\n");
    assert!(reply.contains("[ok]"), "calib: {reply}");
    ri.wait_line(
        "F/T offsets calibrated over 300 samples",
        Duration::from_secs(30),
    );
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
        emulator,
        ri,
        names,
        estimated,
    }
}

/// The worst difference between the boards' torques and the body's over `axes`, failing
/// beyond 0.05 N·m or 2 %.
fn check_torques(r: &mut Running, axes: &[String], what: &str) -> (f64, String) {
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
fn copy_dir(from: &std::path::Path, to: &std::path::Path) {
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

/// Three poses: the boards' torques (wholebodydynamics' estimates, through the boards'
/// virtual torque sensors) are the body's; a compliant joint gets its gravity torque as
/// impedance offset.
#[test]
fn ergocub_hanging_torques_are_the_bodys() {
    let work = tempfile::tempdir().unwrap();
    let dir = work.path().join("ergoCubSN001");
    copy_dir(&shared().join("robots-configuration/ergoCubSN001"), &dir);
    let mut r = start(&dir, "fixed-root");
    let poses: [&[(&str, f64)]; 3] = [
        &[],
        &[
            ("l_shoulder_pitch", -40.0),
            ("l_shoulder_roll", 30.0),
            ("l_elbow", 50.0),
            ("r_shoulder_pitch", -20.0),
            ("r_elbow", 70.0),
            ("torso_pitch", 10.0),
            ("l_hip_pitch", 30.0),
            ("l_knee", -40.0),
            ("r_hip_roll", 15.0),
            ("r_knee", -20.0),
            ("neck_pitch", 10.0),
        ],
        &[
            ("l_shoulder_roll", 60.0),
            ("l_shoulder_yaw", 20.0),
            ("l_wrist_yaw", 20.0),
            ("r_shoulder_roll", 45.0),
            ("r_wrist_pitch", 20.0),
            ("torso_roll", 5.0),
            ("torso_yaw", 15.0),
            ("l_hip_pitch", -10.0),
            ("l_ankle_pitch", 20.0),
            ("r_hip_pitch", 45.0),
            ("r_knee", -60.0),
            ("r_ankle_roll", 10.0),
        ],
    ];
    let mut worst = (0.0f64, String::new());
    for (k, targets) in poses.iter().enumerate() {
        pose(&r.robot, &r.names, targets);
        let axes = r.estimated.clone();
        let w = check_torques(&mut r, &axes, &format!("pose {k}"));
        if w.0 > worst.0 {
            worst = w;
        }
    }
    eprintln!("worst difference {:.4} N·m ({})", worst.0, worst.1);
    // Gravity compensation: l_hip_pitch, compliant in position control, gets its gravity
    // torque as impedance offset.
    let j = r.names["left_leg"]
        .iter()
        .position(|n| n == "l_hip_pitch")
        .unwrap();
    let leg = "/ergocub/left_leg/rpc:i";
    let reply = r
        .robot
        .rpc(leg, &format!("[set] [intm] [mode] {j} [comp]\n"));
    assert!(!reply.contains("[fail]"), "{reply}");
    std::thread::sleep(Duration::from_secs(1));
    let offset = numbers(&r.robot.rpc(leg, &format!("[get] [iimp] [iof] {j}\n")));
    let gravity = body_torques(&mut r.emulator)["l_hip_pitch"];
    let got = *offset.last().expect("an impedance offset");
    assert!(
        (got - gravity).abs() <= (0.02 * gravity.abs()).max(0.05),
        "impedance offset {got:.4} N·m, gravity torque {gravity:.4} N·m ({offset:?})"
    );
    eprintln!(
        "l_hip_pitch compliant: impedance offset {got:.4} N·m, gravity torque {gravity:.4} N·m"
    );
}

/// A user's wholebodydynamics.xml for manipulation: the left arm's F/T sensor among the
/// estimation's and a contact at the left palm. The emulator pushes the palm down with
/// 10 N: the palm's wrench port shows it, and the arm's torques follow the body's (its
/// change is the Jacobian-transposed push).
#[test]
fn ergocub_push_on_the_palm_is_estimated() {
    let work = tempfile::tempdir().unwrap();
    let dir = work.path().join("ergoCubSN001");
    copy_dir(&shared().join("robots-configuration/ergoCubSN001"), &dir);
    let file = dir.join("estimators/wholebodydynamics.xml");
    let text = std::fs::read_to_string(&file)
        .unwrap()
        .replace(
            "(l_foot_front_ft, l_foot_rear_ft,",
            "(l_arm_ft, l_foot_front_ft, l_foot_rear_ft,",
        )
        .replace(
            "(root_link,l_foot_front,",
            "(root_link,l_hand_palm,l_foot_front,",
        );
    assert!(text.contains("(l_arm_ft,") && text.contains("l_hand_palm,l_foot_front"));
    std::fs::write(&file, text).unwrap();
    let mut r = start(&dir, "fixed-root");
    pose(
        &r.robot,
        &r.names,
        &[
            ("l_shoulder_pitch", -30.0),
            ("l_shoulder_roll", 40.0),
            ("l_elbow", 60.0),
        ],
    );
    let arm: Vec<String> = [
        "l_shoulder_pitch",
        "l_shoulder_roll",
        "l_shoulder_yaw",
        "l_elbow",
        "l_wrist_yaw",
        "l_wrist_roll",
        "l_wrist_pitch",
    ]
    .map(String::from)
    .to_vec();
    check_torques(&mut r, &arm, "before the push");
    let before = board_torques(&r.robot, &r.names);
    let truth_before = body_torques(&mut r.emulator);
    {
        use std::io::Write;
        writeln!(
            r.emulator.child.stdin.as_mut().unwrap(),
            "push l_hand_palm 0 0 -10"
        )
        .unwrap();
    }
    r.emulator
        .wait_line("pushed: push l_hand_palm", Duration::from_secs(10));
    let worst = check_torques(&mut r, &arm, "pushed");
    let after = board_torques(&r.robot, &r.names);
    let truth_after = body_torques(&mut r.emulator);
    for axis in &arm {
        let (d_est, d_true) = (
            after[axis] - before[axis],
            truth_after[axis] - truth_before[axis],
        );
        eprintln!("{axis}: the push changed the estimate by {d_est:.4} N·m, the body's torque by {d_true:.4} N·m");
    }
    eprintln!("worst difference {:.4} N·m ({})", worst.0, worst.1);
    // The palm's wrench port: (l_hand_palm, l_hand_palm, root_link), the root's axes
    // (the world's: the robot hangs upright), about the palm.
    let mut reader = {
        let mut c = r.robot.cmd("yarp", "yarp-cli");
        c.args([
            "read",
            "/reader",
            "/wholeBodyDynamics/left_arm/cartesianEndEffectorWrench:o",
        ]);
        r.robot.spawn("yarp read", c)
    };
    let line = loop {
        let l = reader.wait_line(".", Duration::from_secs(10));
        let v: Vec<f64> = l
            .split_whitespace()
            .filter_map(|w| w.parse().ok())
            .collect();
        if v.len() == 6 {
            break v;
        }
    };
    let force = (line[0], line[1], line[2]);
    assert!(
        force.0.abs() < 0.5 && force.1.abs() < 0.5 && (force.2 + 10.0).abs() < 0.5,
        "the palm's external wrench {line:?}, pushed with (0, 0, -10) N"
    );
    eprintln!("the palm's wrench port: {line:?}");
}

/// Standing on its four foot plates (the body shares its weight among them): each foot
/// F/T sensor carries its plate's share, and the torques of every estimated joint, legs
/// included, are the body's in two poses.
#[test]
fn ergocub_standing_torques_are_the_bodys() {
    let work = tempfile::tempdir().unwrap();
    let dir = work.path().join("ergoCubSN001");
    copy_dir(&shared().join("robots-configuration/ergoCubSN001"), &dir);
    let mut r = start(
        &dir,
        "standing:l_foot_front,l_foot_rear,r_foot_front,r_foot_rear",
    );
    let axes = r.estimated.clone();
    let mut worst = check_torques(&mut r, &axes, "standing");
    pose(
        &r.robot,
        &r.names,
        &[
            ("l_shoulder_pitch", -30.0),
            ("r_elbow", 60.0),
            ("torso_pitch", 15.0),
            ("l_hip_roll", 5.0),
            ("neck_pitch", -10.0),
        ],
    );
    let w = check_torques(&mut r, &axes, "standing, leaning");
    if w.0 > worst.0 {
        worst = w;
    }
    eprintln!("worst difference {:.4} N·m ({})", worst.0, worst.1);
}
