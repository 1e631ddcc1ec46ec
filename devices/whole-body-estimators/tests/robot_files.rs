//! Every wholebodydynamics file of robots-configuration, read as yarprobotinterface
//! reads it and checked as the device's open checks it (no network): the ergoCubs' are
//! complete; the iCubs' predate the groups whole-body-estimators requires and are
//! refused at the first one C++'s open reads (`multipleAnalogSensorsNames`), as C++
//! refuses them; once a user adds
//! them, an iCub's `FT_SECONDARY_CALIBRATION` matrices (comma-separated) are read.

use std::path::{Path, PathBuf};

use whole_body_estimators::wholebodydynamics::config::Config;
use yarp_devices::robotinterface::read_robot_str;
use yarp_proto::Property;

fn robots() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/robots-configuration")
}

/// Every `estimators/wholebodydynamics*.xml` of every robot directory.
fn files() -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(robots())
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    if let Ok(icebox) = std::fs::read_dir(robots().join("robots-icebox")) {
        dirs.extend(icebox.map(|e| e.unwrap().path()));
    }
    for d in dirs {
        let Ok(entries) = std::fs::read_dir(d.join("estimators")) else {
            continue;
        };
        out.extend(entries.map(|e| e.unwrap().path()).filter(|p| {
            p.file_name()
                .is_some_and(|n| n.to_string_lossy().starts_with("wholebodydynamics"))
        }));
    }
    out.sort();
    out
}

/// The device's configuration, as yarprobotinterface gives it to `open`.
fn device_config(file: &Path, text: &str) -> Property {
    // the file is a <device>: wrap it in a robot, as an include in the robot's file
    let body = text.split_once("?>").map_or(text, |(_, rest)| rest);
    let body = body
        .split_once("<device")
        .map(|(_, rest)| format!("<device{rest}"))
        .expect("a <device>");
    let xml = format!(
        "<?xml version=\"1.0\"?>\n<robot name=\"r\" build=\"0\" portprefix=\"/r\" xmlns:xi=\"http://www.w3.org/2001/XInclude\"><devices>{body}</devices></robot>"
    );
    let loaded = read_robot_str(&xml, file.parent().unwrap(), &Property::default())
        .unwrap_or_else(|e| panic!("{}: {e}", file.display()));
    loaded.robot.devices[0].to_property().unwrap()
}

#[test]
fn every_robots_file_reads_as_cpp_reads_it() {
    let files = files();
    assert!(files.len() >= 13, "{files:?}");
    let mut read = 0;
    for file in &files {
        let text = std::fs::read_to_string(file).unwrap();
        let result = Config::read(&device_config(file, &text));
        // the ergoCubs' and retired iCubGenova09's are of today's whole-body-estimators
        if text.contains("HW_USE_MAS_IMU") {
            let c = result.unwrap_or_else(|e| panic!("{}: {e}", file.display()));
            assert_eq!(c.params.axes_names.len(), 32, "{}", file.display());
            assert!(c.params.ft_names.len() >= 4);
            assert!(c.wrench_ports.len() >= 8);
            assert!(c.gravity_compensation.is_some());
            read += 1;
        } else {
            let e = result.expect_err(&file.display().to_string()).to_string();
            assert!(
                e.contains("multipleAnalogSensorsNames"),
                "{}: {e}",
                file.display()
            );
        }
    }
    eprintln!(
        "{} wholebodydynamics files, {read} read, the others refused as C++ refuses them",
        files.len()
    );
    assert!(read >= 4);
}

#[test]
fn an_icubs_secondary_calibration_reads_once_the_file_is_complete() {
    let file = robots().join("iCubLisboa01/estimators/wholebodydynamics.xml");
    // (the user also writes the cut-offs this older file lacks)
    let text = std::fs::read_to_string(&file).unwrap().replacen(
        "<param name=\"modelFile\">",
        "<group name=\"HW_USE_MAS_IMU\"><param name=\"accelerometer\">a</param><param name=\"gyroscope\">g</param></group>\n\
         <group name=\"multipleAnalogSensorsNames\"><param name=\"SixAxisForceTorqueSensorsNames\">(l_leg_ft, r_leg_ft)</param></group>\n\
         <param name=\"imuFilterCutoffInHz\">3.0</param><param name=\"forceTorqueFilterCutoffInHz\">3.0</param>\n\
         <param name=\"jointVelFilterCutoffInHz\">3.0</param><param name=\"jointAccFilterCutoffInHz\">3.0</param>\n\
         <param name=\"modelFile\">",
        1,
    );
    let c = Config::read(&device_config(&file, &text)).unwrap();
    let names: Vec<&str> = c
        .secondary_calibration
        .iter()
        .map(|(n, _)| n.as_str())
        .collect();
    assert!(names.contains(&"l_leg_ft"), "{names:?}");
    let (_, m) = c
        .secondary_calibration
        .iter()
        .find(|(n, _)| n == "l_leg_ft")
        .unwrap();
    assert!(
        (m[0] - 0.5969361).abs() < 1e-9 && (m[35] - 1.0).abs() < 1e-9,
        "{m:?}"
    );
}
