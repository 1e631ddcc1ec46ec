//! Census of the robots' own files: every robot of robots-configuration (in service and
//! retired, under `robots-icebox/`) read by our reader, dry (no device opened, no socket).
//!
//! The files read are, for each robot directory, the one its `yarprobotinterface.ini`
//! names (`config ...`, found as C++ `ResourceFinder::findFile` finds it: a name starting
//! with `/` is absolute) and every `.xml` directly in the directory whose root element is
//! `<robot`. Every one must read, except those C++ YARP 3.12 (TinyXML and
//! `XMLReaderFileV3`) refuses too, listed in [`BROKEN_UPSTREAM`] with the reason; those
//! must still fail, with our message naming the same cause.
//!
//! `cargo test -p yarp-devices --test robotinterface_census -- --nocapture` prints the
//! census: how many files read, and each failure with its message.

use std::path::{Path, PathBuf};
use yarp_devices::robotinterface::read_robot_file;
use yarp_proto::Property;

/// Files C++ refuses too: (path under robots-configuration, a fragment of our error
/// message, why C++ fails).
const BROKEN_UPSTREAM: &[(&str, &str, &str)] = &[
    // firmware-updater board lists (`<robot>` of `<board>`s), not yarprobotinterface files
    (
        "ergoCubSN001/network.ergoCubSN001-2foc.xml",
        "\"robot\" element should contain the \"name\" attribute",
        NOT_A_ROBOT,
    ),
    (
        "ergoCubSN002/network.ergoCubSN002-2foc.xml",
        "\"robot\" element should contain the \"name\" attribute",
        NOT_A_ROBOT,
    ),
    (
        "ergoCubSN003/network.ergoCubSN003-2foc.xml",
        "\"robot\" element should contain the \"name\" attribute",
        NOT_A_ROBOT,
    ),
    (
        "/icub_all.xml",
        "cannot read /icub_all.xml",
        "robots-icebox/iCubFrankfurt01/yarprobotinterface.ini has `config /icub_all.xml`: \
         ResourceFinder::findFile takes a name starting with `/` as an absolute path, \
         where there is no file (the robot's icub_all.xml is read on its own below)",
    ),
    // files that include a file robots-configuration does not have
    (
        "iCubEdinburgh01/icub_all_inertials.xml",
        "hardware/motorControl/face-j0_1-mc.xml",
        MISSING,
    ),
    (
        "iCubGenova10/calib_upperbody1.xml",
        "wrappers/motorControl/left_shoulder-mc_wrapper.xml",
        MISSING,
    ),
    (
        "iCubGenova10/calib_upperbody2.xml",
        "wrappers/motorControl/left_shoulder-mc_wrapper.xml",
        MISSING,
    ),
    (
        "iCubGenova10/rs.xml",
        "wrappers/motorControl/right_shoulder-mc_wrapper.xml",
        MISSING,
    ),
    (
        "iCubSingapore01/icub_all_inertials.xml",
        "hardware/motorControl/head-cfw2_can0-mc.xml",
        MISSING,
    ),
    (
        "robots-icebox/iCubGenova04/iRonCub-noLegs_wbd.xml",
        "wrappers/motorControl/left_arm-mc_wrapper_iRonCub.xml",
        MISSING,
    ),
    (
        "robots-icebox/iCubGenova04/iRonCub_wbd.xml",
        "wrappers/motorControl/left_arm-mc_wrapper_iRonCub.xml",
        MISSING,
    ),
    (
        "robots-icebox/iCubGenova04/icub_standup.xml",
        "wrappers/motorControl/icub_ros_wrapper.xml",
        MISSING,
    ),
    (
        "robots-icebox/iCubGenova04/icub_wbd_inertials.xml",
        "wrappers/motorControl/icub_ros_wrapper.xml",
        MISSING,
    ),
    (
        "robots-icebox/iCubGenova04/icub_wbd_noFTfeet.xml",
        "wrappers/motorControl/icub_ros_wrapper.xml",
        MISSING,
    ),
    (
        "robots-icebox/iCubGenova04/icub_wbd_nofingers.xml",
        "wrappers/motorControl/left_arm-mc_wrapper_nofingers.xml",
        MISSING,
    ),
    (
        "robots-icebox/iCubGenova04/icub_wbd_nohands.xml",
        "wrappers/motorControl/left_arm-mc_wrapper_nohands.xml",
        MISSING,
    ),
    (
        "robots-icebox/iCubGenova04/icub_wbd_noskin.xml",
        "wrappers/motorControl/icub_ros_wrapper.xml",
        MISSING,
    ),
    (
        "robots-icebox/iCubGenova04/icub_wbd_noskin_noxsens.xml",
        "wrappers/motorControl/icub_ros_wrapper.xml",
        MISSING,
    ),
    (
        "robots-icebox/iCubGenova04/icub_wbd_noskin_noxsens_wfeetimu_strain2.xml",
        "wrappers/motorControl/icub_ros_wrapper.xml",
        MISSING,
    ),
    (
        "robots-icebox/iCubGenova04/icub_wbd_noskin_wfeetimu.xml",
        "wrappers/motorControl/icub_ros_wrapper.xml",
        MISSING,
    ),
    (
        "robots-icebox/iCubGenova09/icub_FT_feet.xml",
        "hardware/FT/left_leg-eb8-j4_5-strain.xml",
        MISSING,
    ),
    (
        "robots-icebox/iCubGenova09/icub_FT_right_hip.xml",
        "hardware/FT/torso-eb5-j0_2-strain.xml",
        MISSING,
    ),
    (
        "robots-icebox/iCubGenova09/icub_all.xml",
        "hardware/skin/left_upperarm-eb1-skin.xml",
        MISSING,
    ),
    (
        "robots-icebox/iCubGenova09/icub_all_inertials.xml",
        "hardware/motorControl/icub_left_arm.xml",
        MISSING,
    ),
    (
        "robots-icebox/iCubGenova09/icub_legs_mcOnly.xml",
        "hardware/motorControl/left_leg-eb6-j0_1-mc.xml",
        MISSING,
    ),
    (
        "robots-icebox/iCubGenova09/icub_legs_rarm.xml",
        "hardware/motorControl/left_leg-eb6-j0_1-mc.xml",
        MISSING,
    ),
    (
        "robots-icebox/iCubGenova09/legs-wbd.xml",
        "hardware/FT/left_leg-eb8-j4_5-strain.xml",
        MISSING,
    ),
    (
        "robots-icebox/iCubNottingham01/icub_all_inertials.xml",
        "hardware/inertials/left_arm-eb24-j4_7-inertials.xml",
        MISSING,
    ),
    (
        "robots-icebox/iCubPisa01/head.xml",
        "wrappers/motorControl/head_mc_wrapper.xml",
        MISSING,
    ),
];

const NOT_A_ROBOT: &str = "a firmware-updater board list whose <robot> has no name: \
     XMLReaderFileV3::readRobotTag fails with '\"robot\" element should contain the \"name\" \
     attribute'";

const MISSING: &str = "it includes (unconditionally) a file that is not in robots-configuration: \
     PerformInclusions' LoadFile fails and C++ stops with 'In file: ... included by: ... at \
     line: ...'";

fn robots_configuration() -> PathBuf {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/robots-configuration");
    std::fs::canonicalize(&root).unwrap_or(root)
}

/// Whether robots-configuration is beside the repository (a failure under CI).
fn robot_files_present() -> bool {
    let root = robots_configuration();
    if root.exists() {
        return true;
    }
    let why = format!("no robots-configuration at {}", root.display());
    assert!(std::env::var("CI").as_deref() != Ok("true"), "{why}");
    eprintln!("\n*** SKIPPED: {why} ***\n");
    false
}

/// The robot directories: those of robots-configuration and of its robots-icebox.
fn robot_dirs(root: &Path) -> Vec<PathBuf> {
    let mut dirs = Vec::new();
    for base in [root.to_path_buf(), root.join("robots-icebox")] {
        let Ok(entries) = std::fs::read_dir(&base) else {
            continue;
        };
        for e in entries.flatten() {
            let p = e.path();
            if p.is_dir() && p.file_name().is_some_and(|n| n != "robots-icebox") {
                dirs.push(p);
            }
        }
    }
    dirs.sort();
    dirs
}

/// The `config` of a `yarprobotinterface.ini`, resolved as C++ `ResourceFinder` does.
fn ini_config(dir: &Path) -> Option<PathBuf> {
    let ini = std::fs::read_to_string(dir.join("yarprobotinterface.ini")).ok()?;
    let name = ini.lines().find_map(|l| {
        let mut words = l.split_whitespace();
        (words.next() == Some("config")).then(|| words.next().map(str::to_owned))?
    })?;
    let name = name.trim_matches('"');
    Some(if name.starts_with('/') {
        PathBuf::from(name)
    } else {
        dir.join(name.trim_start_matches("./"))
    })
}

/// Whether the first element of `text` (after declarations, DOCTYPE and comments) is
/// `<robot`.
fn robot_rooted(text: &str) -> bool {
    let mut rest = text;
    loop {
        let Some(at) = rest.find('<') else {
            return false;
        };
        rest = &rest[at..];
        let end = if rest.starts_with("<!--") {
            rest.find("-->").map(|e| e + 3)
        } else if rest.starts_with("<?") || rest.starts_with("<!") {
            rest.find('>').map(|e| e + 1)
        } else {
            let name: String = rest[1..]
                .chars()
                .take_while(|c| c.is_alphanumeric() || "_-.:".contains(*c))
                .collect();
            return name == "robot";
        };
        let Some(end) = end else {
            return false;
        };
        rest = &rest[end..];
    }
}

/// Every file of the census, as (path, named by the ini), without repeats.
fn census_files(root: &Path) -> Vec<(PathBuf, bool)> {
    let mut files: Vec<(PathBuf, bool)> = Vec::new();
    for dir in robot_dirs(root) {
        let config = ini_config(&dir);
        if let Some(c) = &config {
            files.push((c.clone(), true));
        }
        let mut xmls: Vec<PathBuf> = std::fs::read_dir(&dir)
            .unwrap()
            .flatten()
            .map(|e| e.path())
            .filter(|p| p.extension().is_some_and(|x| x == "xml") && p.is_file())
            .filter(|p| config.as_ref() != Some(p))
            .filter(|p| std::fs::read_to_string(p).is_ok_and(|t| robot_rooted(&t)))
            .collect();
        xmls.sort();
        files.extend(xmls.into_iter().map(|p| (p, false)));
    }
    files
}

fn relative(root: &Path, p: &Path) -> String {
    p.strip_prefix(root).unwrap_or(p).display().to_string()
}

#[test]
fn every_robot_file_that_cpp_reads_reads() {
    if !robot_files_present() {
        return;
    }
    let root = robots_configuration();
    let files = census_files(&root);
    let (mut read, mut read_ini, mut ini) = (0, 0, 0);
    let mut failures = Vec::new();
    let mut unexpected = Vec::new();
    for (path, named_by_ini) in &files {
        let rel = relative(&root, path);
        ini += usize::from(*named_by_ini);
        let result = read_robot_file(path, &Property::new());
        let broken = BROKEN_UPSTREAM.iter().find(|(f, _, _)| *f == rel);
        match (&result, broken) {
            (Ok(_), None) => {
                read += 1;
                read_ini += usize::from(*named_by_ini);
            }
            (Ok(_), Some((_, _, why))) => {
                read += 1;
                read_ini += usize::from(*named_by_ini);
                unexpected.push(format!(
                    "{rel}: listed as broken upstream ({why}) but reads"
                ));
            }
            (Err(e), Some((_, fragment, _))) if e.to_string().contains(fragment) => {
                failures.push(format!("{rel}: (broken upstream) {e}"));
            }
            (Err(e), _) => {
                let e = e.to_string();
                failures.push(format!("{rel}: {e}"));
                unexpected.push(format!("{rel}: {e}"));
            }
        }
    }
    println!(
        "census: {read} of {} files read ({read_ini} of {ini} named by a yarprobotinterface.ini)",
        files.len()
    );
    for f in &failures {
        println!("  {f}");
    }
    assert!(files.len() > 200, "only {} files found", files.len());
    assert!(unexpected.is_empty(), "{}", unexpected.join("\n"));
}
