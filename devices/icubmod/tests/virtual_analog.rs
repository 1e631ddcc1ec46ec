//! The virtual F/T path of a real iCub and its gyro-bias filter, in process with a name
//! server (run under netns-run):
//! - a YARP port writes wholeBodyDynamics-style torque Bottles to `virtualAnalogServer`,
//!   which hands them to `canBusVirtualAnalogSensor`; the frames it puts on an in-process
//!   CAN bus decode (with the `icub_can::proto` codec) to those torques; bad Bottles are
//!   counted and ignored; silence resets the torques to zero once;
//! - the same with iCubGenova01's own VFT files through the robotinterface runner;
//! - `imuFilter` over `fakeIMU` (a constant gyro = a constant bias) drives the gyro to
//!   zero, passes the other families through, streams the bias on `<name>/bias:o`, and
//!   is served by `multipleanalogsensorsserver` as in `head-imuFilter_wrapper.xml`.
//!
//! Every wait is bounded.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use icub_can::bus::inproc::{VirtualBus, VirtualEndpoint};
use icub_can::proto::{AsPeriodic, Message};
use icub_can::{CanBus, CanFrame};
use yarp_devices::sensors::{FakeImu, MasStatus, VirtualAnalogServer};
use yarp_devices::{shared, DeviceDriver, IMultipleWrapper, PolyDriver};
use yarp_interop_tests::{name_client, wait_for, T};
use yarp_net::blocking::{BufferedPort, Network, Port};
use yarp_proto::{Bottle, Property, Value};

fn genova_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/robots-configuration/iCubGenova01")
}

/// The next two frames on `tap` (one 0xA, one 0xB), decoded to (board, six torques).
fn next_torques(tap: &VirtualEndpoint, full_scale: f64) -> (u8, [f64; 6]) {
    let mut out = [f64::NAN; 6];
    let mut board = None;
    for _ in 0..2 {
        let frame: CanFrame = tap.recv(T).expect("a torque frame");
        let Ok(Message::AsPeriodic {
            board: b,
            msg: AsPeriodic::Vector { kind, raw, .. },
        }) = Message::decode(&frame)
        else {
            panic!("not a strain vector: {frame:?}");
        };
        assert!(board.is_none_or(|x| x == b));
        board = Some(b);
        for (k, v) in AsPeriodic::signed(raw).into_iter().enumerate() {
            // what a motor board does with a calibrated strain reading
            out[kind.first_channel() + k] = f64::from(v) * full_scale / 32768.0;
        }
    }
    (board.unwrap(), out)
}

/// Like [`next_torques`], skipping the all-zero pairs the server sends when it saw no
/// message for 80 ms (a slow test machine may pause that long between two writes).
fn next_nonzero_torques(tap: &VirtualEndpoint, full_scale: f64) -> (u8, [f64; 6]) {
    loop {
        let (board, t) = next_torques(tap, full_scale);
        if t.iter().any(|v| *v != 0.0) {
            return (board, t);
        }
    }
}

fn assert_torques(got: [f64; 6], want: [f64; 6], full_scale: f64) {
    for (g, w) in got.iter().zip(want) {
        // one count of 16 bits, plus the 0x7fff/0x8000 asymmetry of the C++ scaling
        assert!(
            (g - w).abs() <= full_scale / 32767.0 * 2.0,
            "{got:?} != {want:?}"
        );
    }
}

/// Nothing on `tap` for `d`.
fn quiet(tap: &VirtualEndpoint, d: Duration) -> bool {
    matches!(tap.recv(d), Err(icub_can::BusError::Timeout(_)))
}

#[test]
fn torques_written_to_the_port_reach_the_can_bus() {
    yarp_devices::Registry::install(icubmod::register);
    name_client();
    let bus = format!("vas-it-{}", std::process::id());
    let tap = VirtualBus::named(&bus).endpoint();
    // hardware/VFT/left_arm_virtual_strain.xml, with the bus given by canBackend
    let sensor_cfg = format!(
        "(device canBusVirtualAnalogSensor) (id left_arm_virtual_strain) (canBackend inproc://{bus}) (canbusDevice \"sharedcan\") (physDevice \"cfw2can\") (canDeviceNum 1) (canAddress 0x0C) (format 16) (channels 6) (period 1) (useCalibration 1) (fullScale 8 8 8 8 8 8)"
    );
    let sensor = shared(PolyDriver::open(&Property::from_text(&sensor_cfg)).unwrap());
    // wrappers/VFT/left_arm_VFT_wrapper.xml as yarprobotinterface passes it
    let server_cfg = Property::from_text(
        "(device virtualAnalogServer) (robotName /icub) (period 10) (networks (net_VFT_LA)) (net_VFT_LA (0 5 0 5)) (name /vasit/joint_vsens/left_arm:i)",
    );
    let mut server = VirtualAnalogServer::new();
    server.open(&server_cfg).unwrap();
    assert_eq!(
        server.port_name().as_deref(),
        Some("/vasit/joint_vsens/left_arm:i")
    );
    // attaching with a key naming no network leaves that network unattached: an error
    let err = server
        .attach_all(&[("other".into(), sensor.clone())])
        .unwrap_err();
    assert!(err.to_string().contains("net_VFT_LA"), "{err}");
    // a device without IVirtualAnalogSensor is refused
    let imu = shared(PolyDriver::from_driver("fakeIMU", Box::new(FakeImu::new())));
    assert!(server.attach_all(&[("net_VFT_LA".into(), imu)]).is_err());
    server
        .attach_all(&[("net_VFT_LA".into(), sensor.clone())])
        .unwrap();

    let net = Network::from_conf().expect("network");
    let out = Port::open(&net, "/vasit/wbd:o").unwrap();
    out.connect("/vasit/joint_vsens/left_arm:i", None).unwrap();

    // an arm message: channels 0..5 from the values, channel 5 zero
    out.write(&Bottle::from_text("1 1.5 -2.25 0.5 7.0 -3.0 9.9 9.9"));
    let (board, torques) = next_nonzero_torques(&tap, 8.0);
    assert_eq!(board, 0x0C);
    assert_torques(torques, [1.5, -2.25, 0.5, 7.0, -3.0, 0.0], 8.0);

    // a leg message, one value past the full scale: clamped, and the status says so
    out.write(&Bottle::from_text("2 0.1 0.2 0.3 0.4 0.5 -20.0"));
    let (_, torques) = next_nonzero_torques(&tap, 8.0);
    assert_torques(torques, [0.1, 0.2, 0.3, 0.4, 0.5, -8.0], 8.0);
    {
        let mut pd = sensor.lock();
        let vas = pd.device().as_virtual_analog_sensor().unwrap();
        assert_eq!(vas.get_virtual_analog_sensor_channels(), 6);
        assert_eq!(
            vas.get_virtual_analog_sensor_status(5),
            yarp_devices::sensors::VasStatus::Overflow
        );
        assert_eq!(
            vas.get_virtual_analog_sensor_status(0),
            yarp_devices::sensors::VasStatus::Ok
        );
    }

    // silence: after 80 ms the torques are sent as zeros, once
    let (_, torques) = next_torques(&tap, 8.0);
    assert_torques(torques, [0.0; 6], 8.0);
    assert!(quiet(&tap, Duration::from_millis(300)));
    assert_eq!(server.counts(), (2, 0));

    // bad Bottles: logged and ignored, nothing reaches the bus
    for bad in [
        "hello world",
        "1 2.0",
        "9 1 2 3 4 5 6",
        "2 1 2 three 4 5 6",
        "(1 2 3)",
        "",
    ] {
        out.write(&Bottle::from_text(bad));
    }
    // a strange but decodable binary message too
    out.write(&Bottle::new().with(Value::Blob(vec![0, 1, 2])));
    wait_for("the bad Bottles to be counted", || {
        (server.counts().1 == 7).then_some(())
    });
    assert!(quiet(&tap, Duration::from_millis(200)));

    // and the server still works: a torso message
    out.write(&Bottle::from_text("4 -1.0 2.0 -3.0"));
    let (_, torques) = next_nonzero_torques(&tap, 8.0);
    assert_torques(torques, [-1.0, 2.0, -3.0, 0.0, 0.0, 0.0], 8.0);
    assert_eq!(server.counts(), (3, 7));

    // detached: messages are dropped; closing unregisters the port
    server.detach_all().unwrap();
    while tap.try_recv().unwrap().is_some() {}
    out.write(&Bottle::from_text("4 1 1 1"));
    assert!(quiet(&tap, Duration::from_millis(200)));
    out.close();
    server.close().unwrap();
    let ns = name_client();
    let gone = yarp_devices::runtime::block_on(async move {
        ns.query("/vasit/joint_vsens/left_arm:i").await.unwrap()
    })
    .expect("the device runtime");
    assert!(gone.is_none());
    // closing the CAN device stops the "board" (SET_TXMODE 1 to 0x0C)
    sensor.lock().close().unwrap();
    let stop = tap.recv(T).unwrap();
    assert_eq!((stop.std_id(), stop.data()), (Some(0x20C), &[7u8, 1][..]));
}

/// iCubGenova01's own left-arm and torso VFT files, unmodified, through the
/// robotinterface runner (the bus from `YARP_ICUB_CAN_BACKEND`, as the Genova01 tests do).
#[test]
fn genova01_vft_files_run_unmodified() {
    yarp_devices::Registry::install(icubmod::register);
    let dir = genova_dir();
    if !dir.exists() {
        eprintln!("SKIPPED: {} not found", dir.display());
        return;
    }
    name_client();
    let tag = format!("vas-g-{}", std::process::id());
    std::env::set_var(
        icubmod::common::BACKEND_ENV,
        format!("inproc://{tag}-{{n}}"),
    );
    let arm_tap = VirtualBus::named(&format!("{tag}-1")).endpoint();
    let torso_tap = VirtualBus::named(&format!("{tag}-0")).endpoint();
    let tmp = tempfile::tempdir().unwrap();
    let file = tmp.path().join("vft.xml");
    let inc = |p: &str| {
        let href = yarp_interop_tests::include_href(tmp.path(), &dir.join(p));
        format!("    <xi:include href=\"{href}\" />\n")
    };
    let xml = format!(
        "<?xml version=\"1.0\" encoding=\"UTF-8\" ?>\n<!DOCTYPE robot PUBLIC \"-//YARP//DTD yarprobotinterface 3.0//EN\" \"http://www.yarp.it/DTD/yarprobotinterfaceV3.0.dtd\">\n<robot name=\"iCubGenova01\" portprefix=\"/icub\" build=\"0\" xmlns:xi=\"http://www.w3.org/2001/XInclude\">\n<devices>\n{}{}{}{}</devices>\n</robot>\n",
        inc("wrappers/VFT/left_arm_VFT_wrapper.xml"),
        inc("wrappers/VFT/torso_VFT_wrapper.xml"),
        inc("hardware/VFT/left_arm_virtual_strain.xml"),
        inc("hardware/VFT/torso_virtual_strain.xml"),
    );
    std::fs::write(&file, xml).unwrap();
    let robot = yarp_devices::robotinterface::read_robot_file(&file, &Property::new())
        .unwrap_or_else(|e| panic!("{e}"))
        .robot;
    let mut runner = yarp_devices::robotinterface::RobotRunner::new(robot);
    assert!(
        runner.unavailable_devices().is_empty(),
        "{:?}",
        runner.unavailable_devices()
    );
    runner
        .enter_phase(yarp_devices::robotinterface::ActionPhase::Startup)
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(runner.failures().is_empty(), "{:?}", runner.failures());

    let net = Network::from_conf().expect("network");
    let out = Port::open(&net, "/vasg/wbd:o").unwrap();
    out.connect("/icub/joint_vsens/left_arm:i", None).unwrap();
    out.write(&Bottle::from_text("1 1 2 3 4 5 6 7"));
    let (board, torques) = next_nonzero_torques(&arm_tap, 8.0);
    assert_eq!(board, 0x0C);
    assert_torques(torques, [1.0, 2.0, 3.0, 4.0, 5.0, 0.0], 8.0);
    out.disconnect("/icub/joint_vsens/left_arm:i");
    out.connect("/icub/joint_vsens/torso:i", None).unwrap();
    out.write(&Bottle::from_text("4 -10 11 -12.5"));
    // the torso's full scale is 12
    let (board, torques) = next_nonzero_torques(&torso_tap, 12.0);
    assert_eq!(board, 0x0C);
    assert_torques(torques, [-10.0, 11.0, -12.0, 0.0, 0.0, 0.0], 12.0);
    out.close();
    runner
        .enter_phase(yarp_devices::robotinterface::ActionPhase::Interrupt1)
        .unwrap_or_else(|e| panic!("{e}"));
    runner
        .enter_phase(yarp_devices::robotinterface::ActionPhase::Shutdown)
        .unwrap_or_else(|e| panic!("{e}"));
}

/// `imuFilter` with `fakeIMU` as its subdevice: the constant gyro of `constantValue` is a
/// pure bias, which the filter estimates and removes.
#[test]
fn imu_filter_removes_a_constant_gyro_bias() {
    yarp_devices::Registry::install(icubmod::register);
    name_client();
    let cfg = Property::from_config_text(
        "device imuFilter\nsubdevice fakeIMU\nname /imufit\nperiod 5\nbias-gain 0.2\nconstantValue true\nsensorName head_imu\nframeName head_frame\n",
    )
    .unwrap();
    let filter = shared(PolyDriver::open(&cfg).unwrap_or_else(|e| panic!("{e}")));
    {
        let mut pd = filter.lock();
        let dev = pd.device();
        let gyro = dev.as_three_axis_gyroscopes().unwrap();
        assert_eq!(gyro.get_nr_of_three_axis_gyroscopes(), 1);
        assert_eq!(gyro.get_three_axis_gyroscope_name(0).unwrap(), "head_imu");
        assert!(gyro.get_three_axis_gyroscope_measure(1).is_err());
    }
    // the raw gyro reads 10 deg/s on every axis; the filtered one goes to zero
    let start = Instant::now();
    let m = wait_for("the bias to be removed", || {
        let mut pd = filter.lock();
        let g = pd.device().as_three_axis_gyroscopes().unwrap();
        let m = g.get_three_axis_gyroscope_measure(0).ok()?;
        (g.get_three_axis_gyroscope_status(0) == MasStatus::Ok
            && m.values.iter().all(|v| v.abs() < 0.05))
        .then_some(m)
    });
    assert_eq!(m.values.len(), 3);
    assert!(start.elapsed() < T);
    {
        let mut pd = filter.lock();
        let dev = pd.device();
        // the other families pass through
        let acc = dev
            .as_three_axis_linear_accelerometers()
            .unwrap()
            .get_three_axis_linear_accelerometer_measure(0)
            .unwrap();
        assert_eq!(acc.values, FakeImu::acceleration(10.0));
        let mag = dev
            .as_three_axis_magnetometers()
            .unwrap()
            .get_three_axis_magnetometer_measure(0)
            .unwrap();
        assert_eq!(mag.values, [10.0; 3]);
        let rpy = dev.as_orientation_sensors().unwrap();
        assert_eq!(
            rpy.get_orientation_sensor_frame_name(0).unwrap(),
            "head_frame"
        );
    }

    // the bias estimate streams on /imufit/bias:o
    let net = Network::from_conf().expect("network");
    let bias_in = BufferedPort::open(&net, "/imufit/bias:i").unwrap();
    net.connect("/imufit/bias:o", "/imufit/bias:i", None)
        .unwrap();
    let msg = bias_in.read_timeout(T).expect("a bias");
    let bias: Vec<f64> = msg.bottle.iter().map(|v| v.as_f64().unwrap()).collect();
    assert_eq!(bias.len(), 3);
    assert!(bias.iter().all(|b| (b - 10.0).abs() < 0.1), "{bias:?}");
    assert!(msg.stamp.is_some());
    bias_in.close();

    // served as head-imuFilter_wrapper.xml does, and read back by a client
    let mut wrapper = PolyDriver::open(
        &Property::from_config_text(
            "device multipleanalogsensorsserver\nname /imufitw\nperiod 10\n",
        )
        .unwrap(),
    )
    .unwrap();
    wrapper
        .device()
        .as_multiple_wrapper()
        .unwrap()
        .attach_all(&[("SetOfIMUs".into(), filter.clone())])
        .unwrap();
    let mut client = PolyDriver::open(
        &Property::from_config_text(
            "device multipleanalogsensorsclient\nremote /imufitw\nlocal /imufitcl\ntimeout 1.0\n",
        )
        .unwrap(),
    )
    .unwrap();
    let gyro = client.device().as_three_axis_gyroscopes().unwrap();
    let m = wait_for("a filtered gyro from the wrapper", || {
        (gyro.get_three_axis_gyroscope_status(0) == MasStatus::Ok)
            .then(|| gyro.get_three_axis_gyroscope_measure(0).ok())
            .flatten()
    });
    assert!(m.values.iter().all(|v| v.abs() < 0.05), "{m:?}");
    client.close().unwrap();
    wrapper.close().unwrap();
    filter.lock().close().unwrap();
}

/// A bad `imuFilter` configuration or attachment is an error naming the problem.
#[test]
fn imu_filter_refuses_what_it_cannot_filter() {
    yarp_devices::Registry::install(icubmod::register);
    name_client();
    let bad =
        Property::from_config_text("device imuFilter\nname /imufbad\nbias-gain -1\n").unwrap();
    let e = PolyDriver::open(&bad).err().unwrap().to_string();
    assert!(e.contains("bias-gain"), "{e}");
    let proxy = Property::from_config_text(
        "device imuFilter\nname /imufbad\nproxy_remote /x\nproxy_local /y\n",
    )
    .unwrap();
    let e = PolyDriver::open(&proxy).err().unwrap().to_string();
    assert!(e.contains("proxy_remote"), "{e}");
    let mut f =
        PolyDriver::open(&Property::from_config_text("device imuFilter\nname /imufok\n").unwrap())
            .unwrap();
    // not attached: no sensors, errors rather than hangs
    let g = f.device().as_three_axis_gyroscopes().unwrap();
    assert_eq!(g.get_nr_of_three_axis_gyroscopes(), 0);
    assert!(g.get_three_axis_gyroscope_measure(0).is_err());
    // an F/T sensor is not an IMU
    let fts = shared(
        PolyDriver::open(
            &Property::from_config_text("device fakeFTs\nsensorNames (ft)\n").unwrap(),
        )
        .unwrap(),
    );
    let e = f
        .device()
        .as_multiple_wrapper()
        .unwrap()
        .attach_all(&[("x".into(), fts)])
        .unwrap_err();
    assert!(e.to_string().contains("gyroscopes"), "{e}");
    f.close().unwrap();
}
