//! The programs a live test needs beyond this workspace (C++ YARP and its device plugins,
//! rclpy, Chromium), and the one rule for when one is missing: in CI (`CI` set, as every CI
//! service does) the test FAILS naming the peer and its install script, since a test that
//! did not run must not pass; elsewhere it says SKIPPED loudly and returns.

use std::collections::BTreeSet;
use std::ffi::OsString;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// How to install the C++ YARP peer (3.12.3 with its device plugins and icub-main's host).
pub const CPP_YARP_INSTALL: &str = "tests/peers/install-cpp-peers.sh icub (then set \
     YARP_CPP_BIN to the directory it prints)";
/// How to install the C++ YARP 4.0.0 peer.
pub const CPP_YARP4_INSTALL: &str = "tests/peers/install-cpp-peers.sh yarp4 (then set \
     YARP_CPP4_BIN to the directory it prints)";
/// How to install the rclpy peer.
pub const RCLPY_INSTALL: &str =
    "tests/peers/install-ros2.sh (then set ROS_VENV to the directory it prints)";
/// How to install headless Chromium.
pub const CHROMIUM_INSTALL: &str = "launch-configs/launcher/tests/peers/install-chromium.sh";

/// True when the tests run in CI: `CI` is set to anything but `false`/`0`/empty.
pub fn in_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| !matches!(v.trim(), "" | "0" | "false" | "FALSE"))
}

/// Says that `test` cannot run because `peer` is missing (`why`); `install` tells how to
/// get it. In CI this panics; elsewhere it prints a SKIPPED banner straight to stderr
/// (past the harness's capture) and returns, and the caller returns too.
#[track_caller]
pub fn peer_missing(test: &str, peer: &str, why: &str, install: &str) {
    let text = format!("{test}: {peer} is missing ({why}); install it with {install}");
    if in_ci() {
        panic!("CI=true and a live test's peer is missing: {text}");
    }
    let mut e = std::io::stderr().lock();
    let _ = writeln!(e, "\n*** SKIPPED: {text} ***\n");
    let _ = e.flush();
}

/// Where `install-cpp-peers.sh icub` keeps a link to the current build (`<prefix>` of its
/// bin): C++ YARP 3.12.3 with icub-main 2.11.1.
fn cached_cpp_yarp() -> Option<PathBuf> {
    let home = std::env::var_os("HOME")?;
    Some(PathBuf::from(home).join(".cache/yarp-rs/cpp-icub/bin"))
}

/// The directory holding the real C++ YARP programs: `$YARP_CPP_BIN`, else the build of
/// `tests/peers/install-cpp-peers.sh icub` in `~/.cache/yarp-rs/cpp-icub` (C++ YARP
/// 3.12.3, the reference of the live tests). An older peer (the pip-built 3.5 of
/// `<repo>/.venv-yarp`, or the retired CMake build of 3.5) is not looked for: its
/// answers are not the reference any more; point `YARP_CPP_BIN` at it to try one.
pub fn cpp_bin_dir() -> Option<PathBuf> {
    let mut dirs = Vec::new();
    if let Some(d) = std::env::var_os("YARP_CPP_BIN") {
        dirs.push(PathBuf::from(d));
    }
    dirs.extend(cached_cpp_yarp());
    dirs.into_iter().find(|d| d.join("yarp").is_file())
}

/// A C++ YARP program (`yarp`, `yarpdev`, ...), or `None` after [`peer_missing`].
#[track_caller]
pub fn cpp_program(test: &str, name: &str) -> Option<PathBuf> {
    let found = cpp_bin_dir()
        .map(|d| real_cpp_program(&d, name))
        .filter(|p| p.is_file());
    if found.is_none() {
        peer_missing(
            test,
            "C++ YARP",
            &format!("no `{name}` program in $YARP_CPP_BIN or ~/.cache/yarp-rs/cpp-icub/bin"),
            CPP_YARP_INSTALL,
        );
    }
    found
}

/// The `YARP_DATA_DIRS` under which the C++ programs of `bin` find their plugin manifests
/// (`<prefix>/share/yarp/plugins`, and icub-main's in `<prefix>/share/iCub/plugins` where
/// the prefix has them): those directories first, then `$YARP_DATA_DIRS`.
pub fn cpp_data_dirs(bin: &Path) -> Option<OsString> {
    let share = bin.parent()?.join("share/yarp");
    if !share.join("plugins").is_dir() {
        return std::env::var_os("YARP_DATA_DIRS");
    }
    let icub = bin.parent()?.join("share/iCub");
    let mut dirs = share.into_os_string();
    if icub.join("plugins").is_dir() {
        dirs.push(":");
        dirs.push(icub);
    }
    if let Some(more) = std::env::var_os("YARP_DATA_DIRS").filter(|d| !d.is_empty()) {
        dirs.push(":");
        dirs.push(more);
    }
    Some(dirs)
}

/// A command for the C++ program `program` (a path from [`cpp_program`]) with the
/// environment it needs to find its plugins.
pub fn cpp_command(program: &Path) -> Command {
    let mut cmd = Command::new(program);
    if let Some(dirs) = program.parent().and_then(cpp_data_dirs) {
        cmd.env("YARP_DATA_DIRS", dirs);
    }
    cmd
}

/// The directory of C++ YARP 4.0.0's programs: `$YARP_CPP4_BIN`, else the build of
/// `tests/peers/install-cpp-peers.sh yarp4` in `~/.cache/yarp-rs/cpp-yarp4`.
pub fn cpp4_bin_dir() -> Option<PathBuf> {
    let mut dirs: Vec<PathBuf> = std::env::var_os("YARP_CPP4_BIN")
        .map(PathBuf::from)
        .into_iter()
        .collect();
    if let Some(home) = std::env::var_os("HOME") {
        dirs.push(PathBuf::from(home).join(".cache/yarp-rs/cpp-yarp4/bin"));
    }
    dirs.into_iter().find(|d| d.join("yarp").is_file())
}

/// A C++ YARP 4.0.0 program, or `None` after [`peer_missing`].
#[track_caller]
pub fn cpp4_program(test: &str, name: &str) -> Option<PathBuf> {
    let found = cpp4_bin_dir()
        .map(|d| real_cpp_program(&d, name))
        .filter(|p| p.is_file());
    if found.is_none() {
        peer_missing(
            test,
            "C++ YARP 4.0.0",
            &format!("no `{name}` program in $YARP_CPP4_BIN or ~/.cache/yarp-rs/cpp-yarp4/bin"),
            CPP_YARP4_INSTALL,
        );
    }
    found
}

/// The device plugins `yarpdev --list` of the C++ peer in `bin` reports (read once per
/// process and peer).
fn cpp_device_list(bin: &Path) -> BTreeSet<String> {
    static LISTS: std::sync::Mutex<Vec<(PathBuf, BTreeSet<String>)>> =
        std::sync::Mutex::new(Vec::new());
    let mut lists = LISTS.lock().unwrap_or_else(|e| e.into_inner());
    if let Some((_, list)) = lists.iter().find(|(b, _)| b == bin) {
        return list.clone();
    }
    let list = {
        let out = cpp_command(&real_cpp_program(bin, "yarpdev"))
            .arg("--list")
            .stdin(Stdio::null())
            .output();
        let Ok(out) = out else {
            return BTreeSet::new();
        };
        // lines like `[INFO] Device "fakeMotionControl", available on request (found in ...)`
        let text = String::from_utf8_lossy(&out.stdout).into_owned()
            + &String::from_utf8_lossy(&out.stderr);
        text.lines()
            .filter_map(|l| l.split("Device \"").nth(1)?.split('"').next())
            .map(str::to_string)
            .collect::<BTreeSet<String>>()
    };
    lists.push((bin.to_path_buf(), list.clone()));
    list
}

/// The device names the C++ `yarpdev --list` of `bin` reports.
pub fn cpp_device_names(bin: &Path) -> BTreeSet<String> {
    cpp_device_list(bin)
}

/// The C++ bin directory when its `yarpdev --list` has every device of `devices`, or
/// `None` after [`peer_missing`] naming the absent ones.
#[track_caller]
pub fn cpp_devices(test: &str, devices: &[&str]) -> Option<PathBuf> {
    let bin = cpp_program(test, "yarpdev")?.parent()?.to_path_buf();
    devices_in(test, bin, devices)
}

/// [`cpp_devices`] of the C++ YARP 4.0.0 peer.
#[track_caller]
pub fn cpp4_devices(test: &str, devices: &[&str]) -> Option<PathBuf> {
    let bin = cpp4_program(test, "yarpdev")?.parent()?.to_path_buf();
    devices_in(test, bin, devices)
}

#[track_caller]
fn devices_in(test: &str, bin: PathBuf, devices: &[&str]) -> Option<PathBuf> {
    let list = cpp_device_list(&bin);
    let absent: Vec<&str> = devices
        .iter()
        .copied()
        .filter(|d| !list.contains(*d))
        .collect();
    if absent.is_empty() {
        return Some(bin);
    }
    peer_missing(
        test,
        "C++ YARP device plugins",
        &format!(
            "`yarpdev --list` of {} lacks {}",
            bin.display(),
            absent.join(", ")
        ),
        CPP_YARP_INSTALL,
    );
    None
}

/// The program to run for `prog` of the C++ bin directory `bin`. pip's
/// `yarp-middleware` installs Python wrappers in `<venv>/bin` that run the real program of
/// `lib/python*/site-packages/yarp/bin/` as a child and do not pass signals on: killing
/// the wrapper would leave the C++ program (and its port) running. This returns the real
/// program where `bin` holds such a wrapper, else `bin/prog`.
pub fn real_cpp_program(bin: &Path, prog: &str) -> PathBuf {
    let wrapper = bin.join(prog);
    let is_wrapper = std::fs::read(&wrapper)
        .map(|b| b.starts_with(b"#!") && b.windows(17).any(|w| w == b"yarp.bin.__main__"))
        .unwrap_or(false);
    if is_wrapper {
        if let Ok(dirs) = std::fs::read_dir(bin.join("../lib")) {
            for d in dirs.flatten() {
                let real = d.path().join("site-packages/yarp/bin").join(prog);
                if d.file_name().to_string_lossy().starts_with("python") && real.is_file() {
                    return real;
                }
            }
        }
    }
    wrapper
}
