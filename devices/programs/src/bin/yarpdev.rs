//! `yarpdev`: opens one device from the command line (C++ YARP 3.12 `Drivers::yarpdev`)
//! and keeps it open until Ctrl-C, SIGTERM or a message on `<name>/quit`.
//!
//! ```text
//! yarpdev --device fakeMotionControl --name /robot/part --GENERAL::Joints 4
//! yarpdev --device deviceBundler --wrapper_device controlBoard_nws_yarp \
//!         --attached_device fakeMotionControl --name /robot/part
//! yarpdev --from board.ini [--context C] [--key value ...]  # command line overrides
//!                       # the file, found as C++ ResourceFinder would (see `resource`)
//! yarpdev --list
//! yarpdev --device test_motor --axes 2 --single_port --name /motors   # YARP's design paper
//! ```
//!
//! As C++, a device that has a network wrapper of another name (`--list`: "wrapped by")
//! is opened through `deviceBundler` with that wrapper (`test_motor` and
//! `fakeMotionControl` come up served by `controlBoard_nws_yarp`).
//!
//! Exit status: 0 after a clean close (and for `--list` / help, as C++), 1 when the
//! device cannot be opened or the configuration cannot be read, 255 without a name server.
#![forbid(unsafe_code)]

use std::io::IsTerminal;
use std::sync::mpsc;
use std::time::Duration;
use yarp_devices::robotinterface::resource;
use yarp_devices::{runtime, PolyDriver, Registry};
use yarp_proto::{Property, Value};

const COMPONENT: &str = "yarp.dev.Drivers";

fn info(msg: &str) {
    println!("[INFO] |{COMPONENT}| {msg}");
}

fn warning(msg: &str) {
    eprintln!("[WARNING] |{COMPONENT}| {msg}");
}

fn error(msg: &str) {
    eprintln!("[ERROR] |{COMPONENT}| {msg}");
}

/// Why the program should stop waiting.
enum Stop {
    Signal(&'static str),
    QuitPort,
}

/// Installs SIGINT/SIGTERM handlers now (so that an early signal is not lost) and
/// reports each signal on `tx`; the fourth one exits at once.
fn watch_signals(tx: mpsc::Sender<Stop>) -> std::io::Result<()> {
    let mut count = 0;
    yarp_net::signals::on_signals(move |which| {
        count += 1;
        // As C++: a device that does not let go is abandoned after three tries.
        if count > 3 {
            info("Aborting...");
            std::process::exit(1);
        }
        let _ = tx.send(Stop::Signal(which));
    })
}

/// C++ class and network wrapper of the devices C++ YARP also has, for `--list`.
fn cxx_info(name: &str) -> (&'static str, Option<&'static str>) {
    match name {
        "fakeMotionControl" => ("FakeMotionControl", Some("controlBoard_nws_yarp")),
        "test_motor" => ("TestMotor", Some("controlBoard_nws_yarp")),
        "controlBoard_nws_yarp" => ("ControlBoard_nws_yarp", Some("controlBoard_nws_yarp")),
        "remote_controlboard" => ("RemoteControlBoard", None),
        "controlboardremapper" => ("ControlBoardRemapper", Some("controlBoard_nws_yarp")),
        "fakeFrameGrabber" => ("FakeFrameGrabber", Some("frameGrabber_nws_yarp")),
        "frameGrabber_nws_yarp" => ("FrameGrabber_nws_yarp", Some("frameGrabber_nws_yarp")),
        "frameGrabber_nwc_yarp" => ("FrameGrabber_nwc_yarp", None),
        "fakeIMU" => ("FakeIMU", Some("multipleanalogsensorsserver")),
        "fakeAnalogSensor" => ("FakeAnalogSensor", Some("analogServer")),
        "multipleanalogsensorsserver" => (
            "MultipleAnalogSensorsServer",
            Some("multipleanalogsensorsserver"),
        ),
        "multipleanalogsensorsclient" => ("MultipleAnalogSensorsClient", None),
        "deviceBundler" => ("DeviceBundler", None),
        "fakeLaser" => ("FakeLaser", Some("rangefinder2D_nws_yarp")),
        "fakeDepthCamera" => ("FakeDepthCameraDriver", Some("rgbdSensor_nws_yarp")),
        "fakeBattery" => ("FakeBattery", Some("battery_nws_yarp")),
        "fakeOdometry2D" => ("FakeOdometry2D", Some("odometry2D_nws_yarp")),
        "odometry2D_nws_yarp" => ("Odometry2D_nws_yarp", Some("odometry2D_nws_yarp")),
        "odometry2D_nwc_yarp" => ("Odometry2D_nwc_yarp", None),
        "fakeNavigation" => ("FakeNavigation", Some("navigation2D_nws_yarp")),
        // yarp-devices-ros2's plugins (their manifests name each its own wrapper)
        "controlBoard_nws_ros2" => ("ControlBoard_nws_ros2", Some("controlBoard_nws_ros2")),
        "imu_nws_ros2" => ("Imu_nws_ros2", Some("imu_nws_ros2")),
        "wrenchStamped_nws_ros2" => ("WrenchStamped_nws_ros2", Some("wrenchStamped_nws_ros2")),
        "rangefinder2D_nws_ros2" => ("Rangefinder2D_nws_ros2", Some("rangefinder2D_nws_ros2")),
        "rangefinder2D_nwc_ros2" => ("Rangefinder2D_nwc_ros2", None),
        "imu_nwc_ros2" => ("Imu_nwc_ros2", None),
        "rgbdSensor_nwc_ros2" => ("RgbdSensor_nwc_ros2", None),
        "frameTransformGet_nwc_ros2" => ("FrameTransformGet_nwc_ros2", None),
        "frameTransformSet_nwc_ros2" => ("FrameTransformSet_nwc_ros2", None),
        "frameGrabber_nws_ros2" => ("FrameGrabber_nws_ros2", Some("frameGrabber_nws_ros2")),
        "rgbdSensor_nws_ros2" => ("RgbdSensor_nws_ros2", Some("rgbdSensor_nws_ros2")),
        "rgbdToPointCloudSensor_nws_ros2" => (
            "RgbdToPointCloudSensor_nws_ros2",
            Some("rgbdToPointCloudSensor_nws_ros2"),
        ),
        "battery_nws_ros2" => ("Battery_nws_ros2", Some("battery_nws_ros2")),
        "odometry2D_nws_ros2" => ("Odometry2D_nws_ros2", Some("odometry2D_nws_ros2")),
        "mobileBaseVelocityControl_nws_ros2" => (
            "MobileBaseVelocityControl_nws_ros2",
            Some("mobileBaseVelocityControl_nws_ros2"),
        ),
        _ => ("unknown", None),
    }
}

/// C++ `PolyDriver` with `wrapping_enabled` (which yarpdev sets): a device whose network
/// wrapper is another device is opened by `deviceBundler` with that wrapper.
fn wrap_in_network_wrapper(options: &mut Property) {
    let Some(device) = options.find("device").map(Value::to_string_bare) else {
        return;
    };
    let Some(wrapper) = cxx_info(&device).1 else {
        return;
    };
    if wrapper == device || !Registry::knows(wrapper) {
        return;
    }
    options.put("attached_device", Value::from(device.as_str()));
    options.put("wrapper_device", Value::from(wrapper));
    options.put("device", Value::from("deviceBundler"));
}

/// One `--list` line, in the form C++ `Drivers::toString` gives built-in devices, with
/// the crate that provides the device where C++ names a plugin's library.
fn list_line(name: &str, provider: &str) -> String {
    let (class, wrapper) = cxx_info(name);
    let wrapped = match wrapper {
        None => "has no network wrapper".to_string(),
        Some(w) if w == name => "is a network wrapper.".to_string(),
        Some(w) => format!("wrapped by \"{w}\""),
    };
    format!("Device \"{name}\", C++ class {class}, {wrapped} (found in crate {provider})")
}

fn print_help() {
    for line in [
        "Welcome to yarpdev, a program to create YARP devices",
        "To see the devices available, try:",
        "   yarpdev --list",
        "To create a device whose name you know, call yarpdev like this:",
        "   yarpdev --device DEVICENAME --OPTION VALUE ...",
        "   For example:",
        "   yarpdev --device fakeFrameGrabber --width 32 --height 16 --name /grabber",
        "If the device supports it, you can check its configuration parameters using the --help option",
        "You can always move options to a configuration file:",
        "   yarpdev [--device DEVICENAME] --from CONFIG_FILENAME",
    ] {
        info(line);
    }
    error("Device name not specified");
}

/// The options: `single_threaded 1`, then the `--from` file, then the command line.
fn options(args: &[String]) -> Result<Property, String> {
    let cli = Property::from_args(args);
    let mut options = Property::new();
    options.put("single_threaded", 1);
    if let Some(from) = cli.find("from").map(Value::to_string_bare) {
        let context = cli.find("context").map(Value::to_string_bare);
        let path = resource::find_file(&from, context.as_deref())
            .unwrap_or_else(|| std::path::PathBuf::from(&from));
        let file = Property::from_config_file(&path)
            .map_err(|e| format!("cannot read --from {}: {e}", path.display()))?;
        options.merge_bottle(&file.to_bottle());
    }
    options.merge_args(args);
    Ok(options)
}

/// Waits until the name server in `yarp.conf` answers.
fn check_network() -> Result<yarp_net::nameserver::NameClient, String> {
    let client = yarp_net::network::name_client()
        .map_err(|e| e.to_string())?
        .with_timeout(Duration::from_secs(5));
    let probe = client.clone();
    runtime::block_on_result(
        async move { probe.query("/yarpdev").await.map_err(|e| e.to_string()) },
    )?;
    Ok(client)
}

fn run() -> i32 {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (tx, rx) = mpsc::channel();
    if let Err(e) = watch_signals(tx.clone()) {
        error(&format!("cannot install signal handlers: {e}"));
        return 1;
    }
    let mut options = match options(&args) {
        Ok(o) => o,
        Err(e) => {
            error(&e);
            return 1;
        }
    };
    let verbose = options.check("verbose");
    let filter = if verbose { "debug" } else { "info" };
    let _ = tracing_subscriber::fmt()
        .with_writer(std::io::stderr)
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new(filter)),
        )
        .with_ansi(std::io::stderr().is_terminal())
        .without_time()
        .try_init();

    if options.check("file") {
        error("*** yarpdev --file is deprecated, please use --from");
        return 0;
    }
    if options.check("list") {
        info("Here are devices listed for your system:");
        for entry in Registry::entries() {
            info(&list_line(entry.name, entry.provider));
            // then what the device is: its kind and interfaces
            if let Some((ifaces, kind)) = Registry::interfaces(entry.name) {
                info(&format!("    {}: {}", kind.label(), ifaces.join(", ")));
            }
        }
        return 0;
    }
    if let Some(lispy) = options.find("nested").or_else(|| options.find("lispy")) {
        options = Property::from_text(lispy.to_string_bare());
    }
    // As C++: with `--from` but no `device`, the open below reports the missing name.
    if !options.check("device") && !options.check("from") {
        print_help();
        return 0;
    }
    if let (Some(dev), Some(sub)) = (options.find("device"), options.find("subdevice")) {
        // C++ 3.12 refuses this form; we still honour it, pointing at the new one.
        warning(&format!(
            "yarpdev --device {0} --subdevice {1} is deprecated in C++ YARP 3.12; use: yarpdev --device deviceBundler --wrapper_device {0} --attached_device {1}",
            dev.to_string_bare(),
            sub.to_string_bare()
        ));
    }
    options.put("wrapping_enabled", Value::from("1"));
    wrap_in_network_wrapper(&mut options);

    let ns = match check_network() {
        Ok(ns) => ns,
        Err(e) => {
            error(&format!(
                "YARP network not available, check if yarp server is reachable ({e})"
            ));
            return 255;
        }
    };

    let mut dd = match PolyDriver::open(&options) {
        Ok(dd) => dd,
        Err(e) => {
            error("yarpdev: ***ERROR*** device not available.");
            error(&e.to_string());
            if let yarp_devices::DeviceError::UnknownDevice { closest, .. } = &e {
                info("+ Suggestions:");
                for name in closest {
                    info(name);
                }
            }
            info("+ Do \"yarpdev --list\" to see list of supported devices.");
            return 1;
        }
    };

    // The terminator port C++ opens: any message on it stops the program.
    let name = options
        .find("name")
        .map(Value::to_string_bare)
        .filter(|n| !n.is_empty())
        .unwrap_or_else(|| "/yarpdev".to_string());
    let quit_name = format!("{name}/quit");
    let quit_port = if quit_name.contains(['=', '@']) {
        None
    } else {
        let tx = tx.clone();
        let ns = ns.clone();
        let (stop, stopped) = tokio::sync::oneshot::channel::<()>();
        runtime::block_on(async move {
            let port = yarp_net::port::Port::open(&quit_name, ns).await.ok()?;
            let task = tokio::spawn(async move {
                tokio::select! {
                    _ = stopped => {}
                    msg = port.read() => if msg.is_some() {
                        let _ = tx.send(Stop::QuitPort);
                    },
                }
                port.close().await;
            });
            Some((stop, task))
        })
        .ok()
        .flatten()
    };

    info("device active in background...");
    match rx.recv() {
        Ok(Stop::Signal(sig)) => info(&format!("{sig} received: shutting down {name}")),
        Ok(Stop::QuitPort) => info(&format!("quit requested on {name}/quit")),
        Err(_) => {}
    }
    if let Some((stop, task)) = quit_port {
        let _ = stop.send(());
        runtime::block_on_logged("yarpdev: closing the quit port", async move {
            let _ = tokio::time::timeout(Duration::from_secs(2), task).await;
        });
    }
    if let Err(e) = dd.close() {
        warning(&format!("error while closing the device: {e}"));
    }
    info("yarpdev is finished.");
    0
}

fn main() {
    yarp_device_programs::register_all();
    // Runs for hours: keep glibc's freed pages from piling up in the RSS.
    yarp_net::heap::for_long_runs();
    let code = run();
    use std::io::Write;
    let _ = std::io::stdout().flush();
    // Device tasks may still be winding down on the runtime; they must not hold the
    // process open.
    std::process::exit(code);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn text(v: &Value) -> String {
        v.to_string_bare()
    }

    #[test]
    fn a_device_with_a_network_wrapper_is_bundled_with_it() {
        let mut o = Property::from_args(["--device", "test_motor", "--single_port"]);
        wrap_in_network_wrapper(&mut o);
        assert_eq!(text(o.find("device").unwrap()), "deviceBundler");
        assert_eq!(text(o.find("attached_device").unwrap()), "test_motor");
        assert_eq!(
            text(o.find("wrapper_device").unwrap()),
            "controlBoard_nws_yarp"
        );
        for own in [
            "controlBoard_nws_yarp",
            "remote_controlboard",
            "deviceBundler",
        ] {
            let mut o = Property::from_args(["--device", own]);
            wrap_in_network_wrapper(&mut o);
            assert_eq!(text(o.find("device").unwrap()), own);
            assert!(o.find("attached_device").is_none());
        }
    }

    #[test]
    fn list_lines_in_cpp_form() {
        assert_eq!(
            list_line("fakeMotionControl", "yarp-devices"),
            "Device \"fakeMotionControl\", C++ class FakeMotionControl, wrapped by \"controlBoard_nws_yarp\" (found in crate yarp-devices)"
        );
        assert_eq!(
            list_line("controlBoard_nws_yarp", "yarp-devices"),
            "Device \"controlBoard_nws_yarp\", C++ class ControlBoard_nws_yarp, is a network wrapper. (found in crate yarp-devices)"
        );
        assert_eq!(
            list_line("remote_controlboard", "yarp-devices"),
            "Device \"remote_controlboard\", C++ class RemoteControlBoard, has no network wrapper (found in crate yarp-devices)"
        );
    }
}
