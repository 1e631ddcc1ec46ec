//! `yarpdev --device X --help`, ours beside C++ YARP 3.12.3's (under netns-run): for every
//! device both have and C++ declares with its parameter generator, our table lists the
//! parameters C++ lists, by the same names; and every device we register declares its
//! parameters. Without a C++ YARP the comparison says SKIPPED loudly (in CI: fails).

#[path = "../../tests/fixtures/robotinterface/live_support.rs"]
mod support;

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::time::Duration;
use support::*;
use yarp_devices::Registry;

const BIN: &str = env!("CARGO_BIN_EXE_yarpdev");

/// Our devices that read C++ parameters they do not declare, and why.
const NOT_DECLARED: &[(&str, &[&str], &str)] = &[(
    "fakeLaser",
    &[
        "localization_port",
        "localization_server",
        "localization_client",
        "localization_device",
        "MAP_MODE::map_file",
        "MAP_MODE::map_context",
        "clip_max",
        "clip_min",
    ],
    "no maps or localization here: use_mapfile is refused",
)];

/// `name` as the help's header names a device: C++ uses the class name
/// (`RemoteControlBoard` for `remote_controlboard`, `FakeDepthCameraDriver`).
fn same_device(header: &str, device: &str) -> bool {
    let norm = |s: &str| s.to_lowercase().replace('_', "");
    let (h, d) = (norm(header), norm(device));
    h == d || h == format!("{d}driver")
}

/// The help sections of `out`: each header's device and the parameter names listed,
/// C++'s lines `'name': description` or the rows of our table (`GROUP::name` in a group).
fn sections(out: &str) -> Vec<(String, BTreeSet<String>)> {
    let mut found = Vec::new();
    let mut current: Option<(String, BTreeSet<String>)> = None;
    for line in out.lines() {
        let line = line.trim_start();
        if let Some(name) = line.strip_prefix("This is the help for device: ") {
            current = Some((name.trim().to_string(), BTreeSet::new()));
        } else if line.starts_with("=====") {
            found.extend(current.take());
        } else if let Some((_, names)) = &mut current {
            if let Some((name, _)) = line.strip_prefix('\'').and_then(|l| l.split_once("':")) {
                names.insert(name.to_string());
            } else if line.starts_with("| ") && !line.starts_with("| Group ") {
                let cells: Vec<&str> = line.split('|').map(str::trim).collect();
                let rule = |c: &&str| c.len() > 1 && c.chars().all(|c| c == '-');
                if let (Some(group), Some(name)) = (cells.get(1), cells.get(2).filter(|c| !rule(c)))
                {
                    names.insert(match *group {
                        "-" => name.to_string(),
                        g => format!("{g}::{name}"),
                    });
                }
            }
        }
    }
    found
}

/// Runs `yarpdev --device DEVICE --help ARGS` until it has printed the device's help, or
/// exited, or opened (its terminator port `quit` is registered: a device without a table
/// prints nothing more), or the time is up; what it printed.
async fn help_output(
    bin: &Path,
    device: &str,
    args: &[&str],
    net: &Network,
    quit: Option<&str>,
    env: &[(&str, &Path)],
) -> String {
    let conf_home = net.conf_home.path();
    let cwd = std::env::temp_dir();
    let bin = bin.to_str().expect("utf-8 path");
    let mut all = vec!["--device", device, "--help"];
    all.extend_from_slice(args);
    let mut child = Child::spawn_env(bin, &all, &cwd, Some(conf_home), env);
    let deadline = std::time::Instant::now() + T;
    loop {
        let out = child.output();
        let done = sections(&out).iter().any(|(h, _)| same_device(h, device));
        let opened = match quit {
            Some(port) => matches!(net.client.query(port).await, Ok(Some(_))),
            None => false,
        };
        if done || opened || child.is_gone() || std::time::Instant::now() > deadline {
            return child.output();
        }
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
}

#[tokio::test]
async fn every_registered_device_declares_its_parameters() {
    yarp_device_programs::register_all();
    let mut undeclared = Vec::new();
    for entry in Registry::entries() {
        let device = (entry.factory)();
        let params = device.parameters();
        if params.is_empty() {
            undeclared.push(entry.name);
            continue;
        }
        let names: BTreeSet<&str> = params.iter().map(|p| p.name).collect();
        assert_eq!(
            names.len(),
            params.len(),
            "{}: a parameter declared twice",
            entry.name
        );
    }
    assert!(
        undeclared.is_empty(),
        "devices without declared parameters: {undeclared:?}"
    );
}

#[tokio::test]
async fn help_lists_the_parameters_cpp_lists() {
    let Some(bin) = yarp_interop_tests::cpp_devices("device_help_cpp", &["remote_controlboard"])
    else {
        return;
    };
    let cpp_yarpdev = yarp_interop_tests::real_cpp_program(&bin, "yarpdev");
    let data_dirs: Option<PathBuf> = yarp_interop_tests::cpp_data_dirs(&bin).map(PathBuf::from);
    let cpp_env: Vec<(&str, &Path)> = data_dirs
        .as_deref()
        .map(|d| vec![("YARP_DATA_DIRS", d)])
        .unwrap_or_default();
    let cpp_list = yarp_interop_tests::cpp_device_names(&bin);
    yarp_device_programs::register_all();
    let net = start_network().await;

    // ours prints the declared table, by the device's name
    let out = help_output(Path::new(BIN), "remote_controlboard", &[], &net, None, &[]).await;
    let printed = sections(&out);
    let declared: BTreeSet<String> =
        yarp_devices::remote_controlboard::RemoteControlBoardParams::PARAMS
            .iter()
            .map(|p| p.name.to_string())
            .collect();
    assert!(
        printed
            .iter()
            .any(|(h, names)| h == "remote_controlboard" && *names == declared),
        "{out}"
    );

    // C++ prints what its generated parsers declare: the wrappers it opens first get a
    // name, so that the device behind them is reached and prints its own
    let mut cpp: Vec<(String, BTreeSet<String>)> = Vec::new();
    for (i, entry) in Registry::entries().iter().enumerate() {
        if cpp_list.contains(entry.name) {
            let name = format!("/help{i}");
            let quit = format!("{name}/quit");
            let args = ["--name", name.as_str()];
            let out =
                help_output(&cpp_yarpdev, entry.name, &args, &net, Some(&quit), &cpp_env).await;
            cpp.extend(sections(&out));
        }
    }
    let mut compared = BTreeSet::new();
    for entry in Registry::entries() {
        let Some((_, cpp_names)) = cpp.iter().find(|(h, _)| same_device(h, entry.name)) else {
            continue; // C++ reads this device's parameters by hand: no table
        };
        let ours: BTreeSet<String> = (entry.factory)()
            .parameters()
            .iter()
            .map(|p| p.name.to_string())
            .collect();
        let excused: BTreeSet<String> = NOT_DECLARED
            .iter()
            .filter(|(d, _, _)| *d == entry.name)
            .flat_map(|(_, names, _)| names.iter().map(|n| n.to_string()))
            .collect();
        let missing: Vec<&String> = cpp_names
            .difference(&ours)
            .filter(|n| !excused.contains(*n))
            .collect();
        assert!(
            missing.is_empty(),
            "{}: we do not declare C++'s {missing:?}",
            entry.name
        );
        compared.insert(entry.name);
    }
    eprintln!(
        "parameters compared with C++'s --help for {} devices: {compared:?}",
        compared.len()
    );
    assert!(
        compared.len() >= 15,
        "too few devices compared: {compared:?}"
    );
}
