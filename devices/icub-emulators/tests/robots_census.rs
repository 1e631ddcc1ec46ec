//! Census of the robots of robots-configuration (in service, and retired under
//! `robots-icebox/`), each brought up live from its own files, unmodified: in a network
//! namespace of its own holding the robot's addresses (the host's and every board's), our
//! `yarpserver`, `icub-robot-emulator` serving what the files call for (Ethernet boards,
//! CAN buses, serial IMUs) and our `yarprobotinterface` with `--keep-going`, so that every
//! gap is named, not only the first.
//!
//! For each robot: start-up reaches "running happily"; what does not open or attach is
//! exactly the robot's entries in [`KNOWN`] (each with its reason: a device type this build
//! lacks yet, or a file C++ refuses too); every control board (a port `…/rpc:i` beside a
//! `…/state:o` and a `…/stateExt:o`) answers `get axes`, and one part's `state:o` streams; Ctrl-C parks and
//! closes (exit 0) within 60 s. Start-up times are printed (`census ROBOT up S s`), for
//! BENCHMARKS.md. Directories without a yarprobotinterface file predate it: C++ cannot
//! run them either.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use yarp_interop_tests::RobotNet;

/// What a robot's start-up is known to leave out, and why: (robot directory, a fragment of
/// the log line naming it, the reason). A robot whose start-up C++ refuses as a whole has
/// one entry, matched against what our programs print when they refuse it.
const KNOWN: &[(&str, &str, &str)] = &[
    ("iCubPrague01", "OrientationSensorsNames", ORIENTATION),
    ("iCubShanghai01", "OrientationSensorsNames", ORIENTATION),
    ("iCubTokyo01", "right_leg_oints", OINTS),
    ("iCubTokyo01", "l_foot_ft (found", L_FOOT_FT),
    ("iCubValparaiso01", "OrientationSensorsNames", ORIENTATION),
    ("iCubWaterloo01", "OrientationSensorsNames", ORIENTATION),
    ("robots-icebox/iCubAberystwyth01", "right_leg_oints", OINTS),
    (
        "robots-icebox/iCubAberystwyth01",
        "l_foot_ft (found",
        L_FOOT_FT,
    ),
    ("robots-icebox/iCubAnkara01", "right_leg_oints", OINTS),
    ("robots-icebox/iCubAnkara01", "l_foot_ft (found", L_FOOT_FT),
    ("robots-icebox/iCubBarcelona01", "right_leg_oints", OINTS),
    ("robots-icebox/iCubDijon01", "l_foot_ft (found", L_FOOT_FT),
    (
        "robots-icebox/iCubGenova04",
        "multipleAnalogSensorsNames",
        WBD_OLD,
    ),
    (
        "robots-icebox/iCubGenova09",
        "impossible to find modelFile",
        NO_MODEL,
    ),
    (
        "robots-icebox/iCubGenova04",
        "cbw_ros (controlBoard_nws_ros)",
        ROS1,
    ),
    (
        "robots-icebox/iCubHertfordshire01",
        "right_leg_oints",
        OINTS,
    ),
    ("robots-icebox/iCubLausanne01", "right_leg_oints", OINTS),
    (
        "robots-icebox/iCubLausanne01",
        "l_foot_ft (found",
        L_FOOT_FT,
    ),
    ("robots-icebox/iCubManchester01", "right_leg_oints", OINTS),
    (
        "robots-icebox/iCubManchester01",
        "l_foot_ft (found",
        L_FOOT_FT,
    ),
    ("robots-icebox/iCubMunich01", "right_leg_oints", OINTS),
    ("robots-icebox/iCubParis01", "right_leg_oints", OINTS),
    ("robots-icebox/iCubParis01", "l_foot_ft (found", L_FOOT_FT),
    ("robots-icebox/iCubPlymouth01", "right_leg_oints", OINTS),
    (
        "robots-icebox/vizzy",
        "left_arm_mc_wrapper (controlboardwrapper2)",
        CBW2,
    ),
    (
        "robots-icebox/vizzy",
        "right_arm_mc_wrapper (controlboardwrapper2)",
        CBW2,
    ),
    (
        "robots-icebox/vizzy",
        "torso_mc_wrapper (controlboardwrapper2)",
        CBW2,
    ),
    (
        "robots-icebox/vizzy",
        "head_mc_wrapper (controlboardwrapper2)",
        CBW2,
    ),
    (
        "robots-icebox/iCubFrankfurt01",
        "robot file /icub_all.xml",
        FRANKFURT,
    ),
];

/// Device types C++ YARP 3.12 lacks too: its yarprobotinterface stops at them ("Could not find
/// device"), ours with --keep-going goes on without them.
const WBD_OLD: &str =
    "its wholebodydynamics file predates the groups whole-body-estimators requires \
     (multipleAnalogSensorsNames, HW_USE_MAS_IMU): C++'s open fails too (\"Impossible to find \
     required group multipleAnalogSensorsNames\")";
const NO_MODEL: &str =
    "no URDF of this retired iCub is installed (PyPI's icub-models 3.2.0 has none): C++'s \
     wholebodydynamics does not find its modelFile either";
const ROS1: &str = "controlBoard_nws_ros (ROS 1) is not in C++ YARP 3.12 either";
const CBW2: &str = "controlboardwrapper2 was removed from C++ YARP before 3.12";
/// Robots' files that C++ refuses at the same point (icub-main's host run here stops there).
const OINTS: &str =
    "the right leg's remapper names the network `right_leg_oints`, which no device \
     has (a typo upstream): C++'s controlboardremapper refuses the attach too";
const L_FOOT_FT: &str =
    "the left leg's F/T remapper asks for `l_foot_ft` where the board's sensor is \
     `l_foot_sensor`: C++'s multipleanalogsensorsremapper refuses the attach too";
const ORIENTATION: &str =
    "the inertials remapper names an orientation sensor the head's board does not \
     have: C++'s multipleanalogsensorsremapper refuses the attach too";
/// Appends the robot's start-up time to `census.txt` in the tests' temporary directory,
/// for BENCHMARKS.md.
fn record(robot: &str, up: Duration, gaps: usize) {
    use std::io::Write;
    let path = Path::new(env!("CARGO_TARGET_TMPDIR")).join("census.txt");
    if let Ok(mut f) = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(path)
    {
        let _ = writeln!(f, "{robot}\t{:.1}\t{gaps}", up.as_secs_f64());
    }
}

/// The part left without a board by each refused attach.
const UNSERVED: &[(&str, &str)] = &[(OINTS, "/right_leg")];
const FRANKFURT: &str =
    "yarprobotinterface.ini says `config /icub_all.xml`, an absolute path where \
     there is no file: C++'s ResourceFinder finds none either";

/// The data directories holding the robots' URDFs: `../shared/robot-models/ergoCub`
/// and, from the ROS venv (tests/peers/install-ros2.sh installs icub-models there),
/// `share/iCub`.
fn model_dirs() -> String {
    let mut dirs = vec![
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/robot-models/ergoCub")
    ];
    if let Some(venv) = std::env::var_os("ROS_VENV") {
        dirs.push(PathBuf::from(venv).join("share/iCub"));
    }
    std::env::join_paths(dirs)
        .expect("paths without ':'")
        .to_string_lossy()
        .into_owned()
}

fn robots_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/robots-configuration")
}

/// The lines of the start-up log that name what did not come up.
fn gaps(log: &[String]) -> Vec<String> {
    let mut out = Vec::new();
    for l in log {
        if let Some((_, list)) = l.split_once("skipped with their actions: ") {
            out.extend(list.split(", ").map(|d| format!("not available: {d}")));
        }
        if let Some((_, list)) = l.split_once("failed device(s)/action(s): ") {
            out.extend(failures(list));
        }
    }
    out
}

/// The failures of `--keep-going`'s summary, one per device or action (its messages may
/// hold `; ` too).
fn failures(list: &str) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for part in list.split("; ") {
        let starts = [
            "cannot ",
            "attach ",
            "detach ",
            "calibrate ",
            "park ",
            "configure ",
        ];
        match out.last_mut() {
            Some(last) if !starts.iter().any(|s| part.starts_with(s)) => {
                last.push_str("; ");
                last.push_str(part);
            }
            _ => out.push(part.to_string()),
        }
    }
    out
}

fn census(robot: &str) {
    let dir = robots_dir().join(robot);
    if !dir.join("yarprobotinterface.ini").exists() {
        // retired robots older than yarprobotinterface: no file to run, in C++ either
        assert!(
            robot.starts_with("robots-icebox/"),
            "{robot}: a robot in service without yarprobotinterface.ini"
        );
        eprintln!("census {robot}: no yarprobotinterface file (predates it)");
        return;
    }
    // every program of the robot's network stops with it, however the census ends
    let net = RobotNet::new(&dir);
    let _server = net.server();
    let serial = tempfile::tempdir().unwrap();
    let mut emulator = {
        let mut c = net.cmd("icub-robot-emulator", "icub-emulators");
        c.arg(&dir)
            .args(["--address-map", ""])
            .arg("--serial-dir")
            .arg(serial.path());
        net.spawn("icub-robot-emulator", c)
    };
    // its own `ready: ...` (after its `env` lines), not a child's `ready`
    let refused: Vec<&(&str, &str, &str)> = KNOWN
        .iter()
        .filter(|k| k.0 == robot && [FRANKFURT].contains(&k.2))
        .collect();
    if let Some(k) = refused.first() {
        // C++ refuses the whole robot: so must the emulator and yarprobotinterface, naming why
        let status = emulator.child.wait().expect("the emulator's exit");
        let _ = emulator.drain();
        assert!(
            !status.success() && emulator.seen.iter().any(|l| l.contains(k.1)),
            "{robot}: {:?}",
            emulator.seen
        );
        let mut c = net.cmd("yarprobotinterface", "yarp-device-programs");
        c.current_dir(&dir);
        let out = c.output().expect("yarprobotinterface");
        let text = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && text.contains(k.1),
            "{robot}: {text}"
        );
        eprintln!("census {robot}: refused as C++ refuses it: {}", k.2);
        return;
    }
    emulator.wait_line("ready: ", Duration::from_secs(90));
    let env: Vec<(String, String)> = emulator
        .seen
        .iter()
        .filter_map(|l| l.strip_prefix("env ")?.split_once('='))
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    let start = Instant::now();
    let mut ri = {
        let mut c = net.cmd("yarprobotinterface", "yarp-device-programs");
        c.current_dir(&dir).arg("--keep-going").envs(env);
        // As installed on the robot's computer: the robot's name, and the models
        // (ergocub-software's share/ergoCub, icub-models' share/iCub) among the data
        // directories, where wholebodydynamics finds its `modelFile`.
        let name = robot.rsplit('/').next().unwrap_or(robot);
        c.env("YARP_ROBOT_NAME", name)
            .env("YARP_DATA_DIRS", model_dirs());
        net.spawn("yarprobotinterface", c)
    };
    let happy = ri.try_wait_line("running happily", Duration::from_secs(150));
    let up = start.elapsed();
    assert!(
        happy.is_some(),
        "{robot}: no start-up within 150 s; yarprobotinterface printed:\n{}",
        ri.seen.join("\n")
    );
    eprintln!("census {robot} up {:.1} s", up.as_secs_f64());

    // what did not come up: exactly the known gaps
    let found = gaps(&ri.seen);
    let known: Vec<&(&str, &str, &str)> = KNOWN.iter().filter(|k| k.0 == robot).collect();
    let unexplained: Vec<&String> = found
        .iter()
        .filter(|g| !known.iter().any(|k| g.contains(k.1)))
        .collect();
    let unseen: Vec<&str> = known
        .iter()
        .filter(|k| !found.iter().any(|g| g.contains(k.1)))
        .map(|k| k.1)
        .collect();
    assert!(
        unexplained.is_empty() && unseen.is_empty(),
        "{robot}: not up and not known: {unexplained:#?}\nknown but up now: {unseen:#?}"
    );

    // every control board answers, one streams
    let list = net.yarp(&["name", "list"], "");
    let names: Vec<&str> = list
        .lines()
        .filter_map(|l| {
            l.strip_prefix("registration name ")?
                .split_whitespace()
                .next()
        })
        .collect();
    let boards: Vec<&str> = names
        .iter()
        .filter_map(|n| n.strip_suffix("/rpc:i"))
        // a board's wrapper streams stateExt:o too (a Cartesian controller has only state:o)
        .filter(|p| names.contains(&format!("{p}/state:o").as_str()))
        .filter(|p| names.contains(&format!("{p}/stateExt:o").as_str()))
        .collect();
    // a part whose remapper C++ refuses too has its wrapper but no board behind it
    let unserved: Vec<&str> = UNSERVED
        .iter()
        .filter(|(reason, _)| known.iter().any(|k| k.2 == *reason))
        .map(|(_, part)| *part)
        .collect();
    for part in boards
        .iter()
        .filter(|p| !unserved.iter().any(|u| p.contains(u)))
    {
        let reply = net.yarp(&["rpc", &format!("{part}/rpc:i")], "get axes\n");
        assert!(
            reply.contains("] axes "),
            "{robot}: {part}/rpc:i answered {reply:?}"
        );
    }
    if let Some(part) = boards
        .iter()
        .find(|p| !unserved.iter().any(|u| p.contains(u)))
    {
        let mut reader = {
            let mut c = net.cmd("yarp", "yarp-cli");
            c.args(["read", "/census/reader", &format!("{part}/state:o")]);
            net.spawn("yarp read", c)
        };
        // a line of numbers: the part's encoders
        let line = reader.try_wait_line(".", Duration::from_secs(20));
        assert!(line.is_some(), "{robot}: {part}/state:o sent nothing");
    }

    // Ctrl-C parks and closes
    let _ = Command::new("kill")
        .args(["-INT", &ri.pid().to_string()])
        .status();
    let deadline = Instant::now() + Duration::from_secs(60);
    let status = loop {
        if let Ok(Some(s)) = ri.child.try_wait() {
            break Some(s);
        }
        if Instant::now() > deadline {
            break None;
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    let _ = ri.drain();
    assert!(
        status.is_some_and(|s| s.success()),
        "{robot}: Ctrl-C: {status:?}; yarprobotinterface printed:\n{}",
        ri.seen.join("\n")
    );
    record(robot, up, found.len());
}

/// One test per robot directory.
macro_rules! census {
    ($($name:ident => $dir:literal,)*) => {
        $(
            #[test]
            fn $name() {
                census($dir);
            }
        )*

        /// The list above is every directory of robots-configuration.
        #[test]
        fn every_robot_directory_has_its_census() {
            let listed = [$($dir),*];
            let mut dirs = Vec::new();
            for sub in ["", "robots-icebox/"] {
                for e in std::fs::read_dir(robots_dir().join(sub)).unwrap().flatten() {
                    let name = e.file_name().to_string_lossy().into_owned();
                    if e.path().is_dir() && is_robot(&e.path()) {
                        dirs.push(format!("{sub}{name}"));
                    }
                }
            }
            dirs.sort();
            let mut listed: Vec<String> = listed.iter().map(|s| s.to_string()).collect();
            listed.sort();
            assert_eq!(listed, dirs);
        }
    };
}

/// A robot's directory: one with a yarprobotinterface file, or hardware or robot files.
fn is_robot(dir: &Path) -> bool {
    dir.join("yarprobotinterface.ini").exists()
        || dir.join("hardware").is_dir()
        || std::fs::read_dir(dir).is_ok_and(|d| {
            d.flatten().any(|e| {
                e.path()
                    .extension()
                    .is_some_and(|x| x == "xml" || x == "ini")
            })
        })
}

census! {
    r1sn001 => "R1SN001",
    r1sn002 => "R1SN002",
    skinfingertipdemo => "SkinFingertipDemo",
    skintabletop => "SkinTableTop",
    ergocubsn001 => "ergoCubSN001",
    ergocubsn002 => "ergoCubSN002",
    ergocubsn003 => "ergoCubSN003",
    icubedinburgh01 => "iCubEdinburgh01",
    icuberzelli01 => "iCubErzelli01",
    icuberzelli02 => "iCubErzelli02",
    icuberzelli03 => "iCubErzelli03",
    icubgenova01 => "iCubGenova01",
    icubgenova02 => "iCubGenova02",
    icubgenova06 => "iCubGenova06",
    icubgenova07 => "iCubGenova07",
    icubgenova08 => "iCubGenova08",
    icubgenova10 => "iCubGenova10",
    icubgrenoble01 => "iCubGrenoble01",
    icublisboa01 => "iCubLisboa01",
    icubnancy01 => "iCubNancy01",
    icubprague01 => "iCubPrague01",
    icubshanghai01 => "iCubShanghai01",
    icubsingapore01 => "iCubSingapore01",
    icubstanford01 => "iCubStanford01",
    icubtokyo01 => "iCubTokyo01",
    icubvalparaiso01 => "iCubValparaiso01",
    icubwaterloo01 => "iCubWaterloo01",
    icebox_icubaberystwyth01 => "robots-icebox/iCubAberystwyth01",
    icebox_icubankara01 => "robots-icebox/iCubAnkara01",
    icebox_icubbarcelona01 => "robots-icebox/iCubBarcelona01",
    icebox_icubbielefeld01 => "robots-icebox/iCubBielefeld01",
    icebox_icubbielefeld02 => "robots-icebox/iCubBielefeld02",
    icebox_icubbielefeld03 => "robots-icebox/iCubBielefeld03",
    icebox_icubbremen01 => "robots-icebox/iCubBremen01",
    icebox_icubchemnitz01 => "robots-icebox/iCubChemnitz01",
    icebox_icubdarmstadt01 => "robots-icebox/iCubDarmstadt01",
    icebox_icubdijon01 => "robots-icebox/iCubDijon01",
    icebox_icubfrankfurt01 => "robots-icebox/iCubFrankfurt01",
    icebox_icubgenova03 => "robots-icebox/iCubGenova03",
    icebox_icubgenova04 => "robots-icebox/iCubGenova04",
    icebox_icubgenova09 => "robots-icebox/iCubGenova09",
    icebox_icubhalfie01 => "robots-icebox/iCubHalfie01",
    icebox_icubhamburg01 => "robots-icebox/iCubHamburg01",
    icebox_icubheidelberg01 => "robots-icebox/iCubHeidelberg01",
    icebox_icubhertfordshire01 => "robots-icebox/iCubHertfordshire01",
    icebox_icubhertfordshire02 => "robots-icebox/iCubHertfordshire02",
    icebox_icubhongkong01 => "robots-icebox/iCubHongKong01",
    icebox_icubkarlsruhe01 => "robots-icebox/iCubKarlsruhe01",
    icebox_icublausanne01 => "robots-icebox/iCubLausanne01",
    icebox_icublausanne02 => "robots-icebox/iCubLausanne02",
    icebox_icublisboa02 => "robots-icebox/iCubLisboa02",
    icebox_icublondon01 => "robots-icebox/iCubLondon01",
    icebox_icublugano01 => "robots-icebox/iCubLugano01",
    icebox_icubmanchester01 => "robots-icebox/iCubManchester01",
    icebox_icubmoscow01 => "robots-icebox/iCubMoscow01",
    icebox_icubmunich01 => "robots-icebox/iCubMunich01",
    icebox_icubnottingham01 => "robots-icebox/iCubNottingham01",
    icebox_icuboffenbach01 => "robots-icebox/iCubOffenbach01",
    icebox_icuboffenbach02 => "robots-icebox/iCubOffenbach02",
    icebox_icubparis01 => "robots-icebox/iCubParis01",
    icebox_icubpisa01 => "robots-icebox/iCubPisa01",
    icebox_icubplymouth01 => "robots-icebox/iCubPlymouth01",
    icebox_icubplymouth02 => "robots-icebox/iCubPlymouth02",
    icebox_icubrome02 => "robots-icebox/iCubRome02",
    icebox_icubseoul01 => "robots-icebox/iCubSeoul01",
    icebox_icubsheffield01 => "robots-icebox/iCubSheffield01",
    icebox_icubtwente01 => "robots-icebox/iCubTwente01",
    icebox_icuburbana01 => "robots-icebox/iCubUrbana01",
    icebox_icubzurich01 => "robots-icebox/iCubZurich01",
    icebox_iiwaboston01 => "robots-icebox/iiwaBoston01",
    icebox_naoprague01 => "robots-icebox/naoPrague01",
    icebox_vizzy => "robots-icebox/vizzy",
}
