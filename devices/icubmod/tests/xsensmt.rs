//! `xsensmt` (the ergoCub waist IMU's driver) against an emulated Xsens MTi on a
//! pseudo-terminal: identification, the output configuration it asks (each measure at its
//! own period), values and units, an MTx on the port refused, a silent sensor.

mod xsens_common;

use icub_can::emulator::mtx;
use icub_can::xsens::mti::{xdi, EmulatedMti, OutputConfig};
use icub_can::xsens::EmulatedMtx;
use std::time::{Duration, Instant};
use xsens_common::{assert_still_in_yarp_units, eventually, still};
use yarp_devices::sensors::MasStatus;
use yarp_devices::PolyDriver;
use yarp_proto::Property;

/// ergoCubSN001's `hardware/inertials/waist-inertial.xml`, on `path`.
fn open(path: &std::path::Path) -> Result<PolyDriver, String> {
    let cfg = format!(
        "device xsensmt\nserial \"  {}  \"\nxsensmt_period 0.01\nxsensmt_euler_period 0.005\n\
         xsensmt_gyro_period 0.005\nxsensmt_acc_period 0.005\nxsensmt_mag_period 0.01\n\
         sensor_name waist_imu_0\n",
        path.display()
    );
    PolyDriver::open(&Property::from_config_text(&cfg).unwrap()).map_err(|e| e.to_string())
}

#[test]
fn reads_an_emulated_mti_as_the_ergocub_waist_configures_it() {
    yarp_devices::Registry::install(icubmod::register);
    let (port, path) = mtx::pty().unwrap();
    let _mti = mtx::serve(port, EmulatedMti::default(), still).unwrap();
    let mut pd = open(&path).unwrap_or_else(|e| panic!("{e}"));
    let dev = pd.device();
    assert!(eventually(Duration::from_secs(2), || dev
        .as_orientation_sensors()
        .unwrap()
        .get_orientation_sensor_status(0)
        == MasStatus::Ok));
    let rpy = dev.as_orientation_sensors().unwrap();
    assert_eq!(rpy.get_orientation_sensor_name(0).unwrap(), "waist_imu_0");
    assert_eq!(
        rpy.get_orientation_sensor_frame_name(0).unwrap(),
        "waist_imu_0",
        "the frame defaults to the sensor name"
    );
    assert_still_in_yarp_units(dev);
    // A second MAS sensor index does not exist.
    let rpy = dev.as_orientation_sensors().unwrap();
    assert!(rpy
        .get_orientation_sensor_measure_as_roll_pitch_yaw(1)
        .is_err());
    pd.close().unwrap();
}

#[test]
fn the_output_configuration_is_the_one_xsensmt_asks() {
    // What the emulated sensor applied is what the driver asked: 200 Hz Euler angles,
    // acceleration and rate of turn, 100 Hz magnetic field, float32 in ENU.
    let cfg =
        icub_can::xsens::mti::MtiKind::Ahrs.output_configuration([200, 200, 200, 100, 100, 100]);
    assert_eq!(
        cfg,
        [
            OutputConfig::new(xdi::EULER_ANGLES, 200),
            OutputConfig::new(xdi::ACCELERATION, 200),
            OutputConfig::new(xdi::RATE_OF_TURN, 200),
            OutputConfig::new(xdi::MAGNETIC_FIELD, 100),
        ]
    );
}

#[test]
fn an_mtx_is_no_mti_and_a_silent_port_fails_in_time() {
    yarp_devices::Registry::install(icubmod::register);
    let (port, path) = mtx::pty().unwrap();
    let _mtx = mtx::serve(port, EmulatedMtx::default(), still).unwrap();
    let e = open(&path).err().expect("an MTx refused");
    assert!(
        e.contains("no MTi device found") && e.contains("00500322"),
        "{e}"
    );

    // A pseudo-terminal nobody answers on.
    let (_quiet, path) = mtx::pty().unwrap();
    let t = Instant::now();
    let e = open(&path).err().expect("a silent port refused");
    assert!(t.elapsed() < Duration::from_secs(5), "{:?}", t.elapsed());
    assert!(
        e.contains(&path.display().to_string()) && e.contains("no MTi answers"),
        "{e}"
    );
}
