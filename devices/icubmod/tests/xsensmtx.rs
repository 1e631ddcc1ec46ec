//! `xsensmtx` against an emulated Xsens MTx on a pseudo-terminal: the configuration
//! sequence, values and units, an unplugged sensor, and a sensor that never answers.

mod xsens_common;

use icub_can::emulator::mtx;
use icub_can::xsens::EmulatedMtx;
use std::time::{Duration, Instant};
use xsens_common::{assert_still_in_yarp_units, eventually, still};
use yarp_devices::sensors::{AnalogStatus, MasStatus};
use yarp_devices::PolyDriver;
use yarp_proto::Property;

fn open(path: &std::path::Path) -> Result<PolyDriver, String> {
    let cfg = format!(
        "device xsensmtx\nserial {}\nsensor_name head_imu\nframe_name head_imu_frame\n",
        path.display()
    );
    PolyDriver::open(&Property::from_config_text(&cfg).unwrap()).map_err(|e| e.to_string())
}

#[test]
fn reads_an_emulated_mtx_in_yarp_units() {
    yarp_devices::Registry::install(icubmod::register);
    let (port, path) = mtx::pty().unwrap();
    // The sensor powers up measuring in another mode: open must reconfigure it.
    let emulated = EmulatedMtx {
        output_settings: 0,
        ..EmulatedMtx::default()
    };
    let _mtx = mtx::serve(port, emulated, still).unwrap();
    let mut pd = open(&path).unwrap_or_else(|e| panic!("{e}"));
    let dev = pd.device();
    assert!(eventually(Duration::from_secs(2), || dev
        .as_three_axis_gyroscopes()
        .unwrap()
        .get_three_axis_gyroscope_status(0)
        == MasStatus::Ok));
    assert_still_in_yarp_units(dev);
    let mag = dev.as_three_axis_magnetometers().unwrap();
    assert_eq!(mag.get_three_axis_magnetometer_name(0).unwrap(), "head_imu");
    assert_eq!(
        mag.get_three_axis_magnetometer_frame_name(0).unwrap(),
        "head_imu_frame"
    );
    assert!(mag.get_three_axis_magnetometer_measure(1).is_err());
    pd.close().unwrap();
}

#[test]
fn an_unplugged_mtx_reads_as_timeout_and_recovers() {
    yarp_devices::Registry::install(icubmod::register);
    let (port, path) = mtx::pty().unwrap();
    let emulated = mtx::serve(port, EmulatedMtx::default(), still).unwrap();
    let mut pd = open(&path).unwrap_or_else(|e| panic!("{e}"));
    let dev = pd.device();
    let status = |dev: &mut dyn yarp_devices::DeviceDriver| {
        dev.as_orientation_sensors()
            .unwrap()
            .get_orientation_sensor_status(0)
    };
    assert!(eventually(Duration::from_secs(2), || status(dev) == MasStatus::Ok));
    emulated.set_silent(true);
    let t = Instant::now();
    assert!(eventually(Duration::from_secs(2), || status(dev) == MasStatus::Timeout));
    assert!(t.elapsed() < Duration::from_secs(1), "{:?}", t.elapsed());
    let err = dev
        .as_orientation_sensors()
        .unwrap()
        .get_orientation_sensor_measure_as_roll_pitch_yaw(0)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("xsensmtx") && err.contains("no sample"),
        "{err}"
    );
    let mut v = Vec::new();
    assert_eq!(
        dev.as_analog_sensor().unwrap().read(&mut v),
        AnalogStatus::Timeout
    );
    emulated.set_silent(false);
    assert!(eventually(Duration::from_secs(2), || status(dev) == MasStatus::Ok));
}

#[test]
fn a_silent_or_missing_sensor_fails_open_naming_the_port() {
    yarp_devices::Registry::install(icubmod::register);
    // A pseudo-terminal nobody answers on.
    let (_quiet, path) = mtx::pty().unwrap();
    let t = Instant::now();
    let err = open(&path).err().expect("open must fail");
    assert!(t.elapsed() < Duration::from_secs(4), "{:?}", t.elapsed());
    assert!(err.contains(&path.display().to_string()), "{err}");
    assert!(err.contains("no MTx answers"), "{err}");

    let err = open(std::path::Path::new("/nonexistent/ttyXSENS"))
        .err()
        .expect("open must fail");
    assert!(err.contains("/nonexistent/ttyXSENS"), "{err}");
}

#[test]
fn pty_link_gives_the_path_a_robot_file_names() {
    yarp_devices::Registry::install(icubmod::register);
    let dir = tempfile::tempdir().unwrap();
    let link = dir.path().join("ttyS0");
    std::fs::write(&link, b"stale").unwrap(); // replaced, not an error
    let (emulated, _pts) = mtx::pty_link(&link).unwrap();
    let mut pd = open(&link).unwrap_or_else(|e| panic!("{e}"));
    let dev = pd.device();
    assert!(eventually(Duration::from_secs(2), || {
        let mut v = Vec::new();
        dev.as_analog_sensor().unwrap().read(&mut v) == AnalogStatus::Ok && v.len() == 12
    }));
    pd.close().unwrap();
    drop(emulated);
    assert!(
        link.symlink_metadata().is_err(),
        "the link goes with the emulator"
    );
}

/// The terminal's exclusive-use flag (TIOCEXCL), read through a new descriptor.
fn exclusive(path: &std::path::Path) -> bool {
    use std::os::fd::AsRawFd;
    let f = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .open(path)
        .unwrap();
    let mut on: libc::c_int = 0;
    // SAFETY: TIOCGEXCL writes one int through the pointer we pass.
    let r = unsafe { libc::ioctl(f.as_raw_fd(), libc::TIOCGEXCL, &mut on) };
    assert_eq!(r, 0, "TIOCGEXCL: {}", std::io::Error::last_os_error());
    on != 0
}

#[test]
fn the_port_is_exclusive_while_open_and_released_on_close() {
    yarp_devices::Registry::install(icubmod::register);
    // Root may open an exclusive terminal anyway, so the flag itself is checked: were it
    // left set (it outlives the descriptor while the emulator holds the terminal open), a
    // non-root user could not open the emulator's terminal a second time. serialport
    // clears it when it closes a port.
    let (port, path) = mtx::pty().unwrap();
    let _mtx = mtx::serve(port, EmulatedMtx::default(), still).unwrap();
    let mut pd = open(&path).unwrap_or_else(|e| panic!("{e}"));
    assert!(
        exclusive(&path),
        "no second reader while the device is open"
    );
    pd.close().unwrap();
    assert!(!exclusive(&path), "released on close");
    // and after an open that failed (nobody answers on this one)
    let (_quiet, quiet_path) = mtx::pty().unwrap();
    assert!(open(&quiet_path).is_err());
    assert!(!exclusive(&quiet_path));
}

/// The emulator killed and started again on the same link (a new terminal behind it, as
/// `icub-board-emulator --xsens PATH` does; or a sensor's USB cable pulled and plugged
/// back): the device reads `Timeout` meanwhile and measures again without being reopened.
#[test]
fn a_restarted_emulator_on_the_same_link_is_measured_again() {
    yarp_devices::Registry::install(icubmod::register);
    let dir = tempfile::tempdir().unwrap();
    let link = dir.path().join("ttyXSENS");
    let (first, _pts) = mtx::pty_link(&link).unwrap();
    let mut pd = open(&link).unwrap_or_else(|e| panic!("{e}"));
    let dev = pd.device();
    let status = |dev: &mut dyn yarp_devices::DeviceDriver| {
        dev.as_three_axis_gyroscopes()
            .unwrap()
            .get_three_axis_gyroscope_status(0)
    };
    assert!(eventually(Duration::from_secs(2), || status(dev) == MasStatus::Ok));
    drop(first);
    assert!(eventually(Duration::from_secs(2), || status(dev) == MasStatus::Timeout));
    let (_second, _pts) = mtx::pty_link(&link).unwrap();
    assert!(
        eventually(Duration::from_secs(5), || status(dev) == MasStatus::Ok),
        "not measuring again"
    );
    pd.close().unwrap();
}
