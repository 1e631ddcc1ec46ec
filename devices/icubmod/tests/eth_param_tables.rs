//! Each `embObj*` device's declared parameter table (`yarpdev --device X --help`) is what
//! its readers read: opened on every robot of robots-configuration that has it, every
//! parameter a device looks up is a row of its table, and every row of the device's own
//! table is looked up by some robot.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use icubmod::eth::config::lookups;
use yarp_devices::params::ParamSpec;
use yarp_proto::Property;

/// The robots of robots-configuration (in service and retired) whose top-level file our
/// reader reads, with the devices of each.
fn robots() -> Vec<(String, Vec<yarp_devices::robotinterface::Device>)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/robots-configuration");
    let mut dirs: Vec<_> = std::fs::read_dir(&root)
        .unwrap()
        .chain(std::fs::read_dir(root.join("robots-icebox")).unwrap())
        .filter_map(Result::ok)
        .map(|e| e.path())
        .collect();
    dirs.sort();
    let mut out = Vec::new();
    for dir in dirs {
        let Ok(ini) = std::fs::read_to_string(dir.join("yarprobotinterface.ini")) else {
            continue;
        };
        let Some(top) = ini
            .lines()
            .find_map(|l| l.trim().strip_prefix("config"))
            .map(|t| t.trim().trim_matches('"').to_string())
        else {
            continue;
        };
        match yarp_devices::robotinterface::read_robot_file(&dir.join(&top), &Property::new()) {
            Ok(r) => out.push((dir.display().to_string(), r.robot.devices)),
            Err(e) => eprintln!("{}: not read ({e})", dir.display()),
        }
    }
    out
}

#[test]
fn every_lookup_is_a_row() {
    let mut seen: BTreeMap<&str, BTreeSet<String>> = BTreeMap::new();
    let (robots, mut opened) = (robots(), 0);
    assert!(robots.len() >= 50, "{} robots read", robots.len());
    for (robot, devices) in robots {
        for d in devices.iter().filter(|d| d.kind.starts_with("embObj")) {
            let Some((name, factory)) = icubmod::eth::DRIVERS.iter().find(|(n, _)| *n == d.kind)
            else {
                continue;
            };
            let Ok(mut config) = d.to_property() else {
                continue;
            };
            // an address no machine has: the device stops at binding the host's socket
            config.put_group(
                "PC104",
                &Property::from_text("(PC104IpAddress \"192.0.2.1\") (PC104IpPort 12345)"),
            );
            let mut dev = factory();
            let (r, keys) = lookups::record(&config, || dev.open(&config));
            assert!(r.is_err(), "{robot} {}: opened", d.name);
            seen.entry(name).or_default().extend(keys);
            opened += 1;
        }
    }
    assert!(
        seen.len() >= 8,
        "embObj devices of the robots: {:?}",
        seen.keys()
    );
    assert!(opened >= 500, "{opened} devices opened");
    let mut problems = Vec::new();
    for (name, keys) in &seen {
        let table = icubmod::eth::tables::of(name);
        for key in keys {
            if !table.iter().any(|row| covers(row, key)) {
                problems.push(format!("{name}: `{key}` is looked up but not in the table"));
            }
        }
        // the device's own rows (the Ethernet groups are read through their declaration)
        let common = icubmod::eth::tables::of("");
        for row in table.iter().filter(|r| !common.contains(r)) {
            let reached = keys.iter().any(|k| matches(row.name, k));
            if !reached && !NOT_IN_ANY_ROBOT.contains(&row.name) {
                problems.push(format!(
                    "{name}: row `{}` is looked up by no robot",
                    row.name
                ));
            }
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// Rows whose group no robot of robots-configuration v2.15.0 has (C++ reads them all the
/// same when a file has the group).
const NOT_IN_ANY_ROBOT: &[&str] = &[
    "LUGRE::Km",
    "LUGRE::Kw",
    "LUGRE::S0",
    "LUGRE::S1",
    "LUGRE::Vth",
    "LUGRE::Fc_pos",
    "LUGRE::Fc_neg",
    "LUGRE::Fs_pos",
    "LUGRE::Fs_neg",
    "MAINTENANCE::skipRecalibration",
];

/// One segment of a row's key: `<...>` stands for a name the file chooses, after a fixed
/// start (`JOINTSET_<n>`).
fn segment_matches(pattern: &str, segment: &str) -> bool {
    match pattern.find('<') {
        Some(i) => segment.len() > i && segment.starts_with(&pattern[..i]),
        None => pattern == segment,
    }
}

/// `path` is the row `row` (`A::B::name`).
fn matches(row: &str, path: &str) -> bool {
    let (r, p): (Vec<&str>, Vec<&str>) = (row.split("::").collect(), path.split("::").collect());
    r.len() == p.len() && r.iter().zip(&p).all(|(r, p)| segment_matches(r, p))
}

/// `path` is the row or one of the groups on its way.
fn covers(row: &ParamSpec, path: &str) -> bool {
    let r: Vec<&str> = row.name.split("::").collect();
    let p: Vec<&str> = path.split("::").collect();
    p.len() <= r.len() && r.iter().zip(&p).all(|(r, p)| segment_matches(r, p))
}
