//! IImpedanceControl, IControlCalibration and IRemoteCalibrator through the control-board
//! stack: the RPC shapes C++ 3.12's `RPCMessagesParser` serves (pure `handle_rpc`), and
//! `remote_controlboard` -> `controlBoard_nws_yarp` -> `fakeMotionControl` (and the
//! remapper) over real loopback sockets (run under netns-run).

mod controlboard_common;

use controlboard_common::name_client;
use std::sync::{Arc, Mutex};
use yarp_devices::controlboard::{handle_rpc, RpcStamp};
use yarp_devices::remapper::ControlBoardRemapper;
use yarp_devices::{
    shared, CalibrationParameters, DevResult, DeviceDriver, DeviceError, FakeMotionControl,
    IRemoteCalibrator, ImpedanceLimits, PolyDriver,
};
use yarp_proto::{Bottle, Property, Value};

fn rpc(dev: &mut dyn DeviceDriver, stamp: &mut RpcStamp, text: &str) -> Bottle {
    handle_rpc(&Bottle::from_text(text), dev, stamp)
}

/// `reply` without its `[tsta] count time` (checked for shape), as text.
fn unstamped(reply: &Bottle) -> String {
    let items: Vec<Value> = reply.iter().cloned().collect();
    let at = items
        .iter()
        .position(|v| v.to_string() == "[tsta]")
        .unwrap_or_else(|| panic!("no timestamp in `{reply}`"));
    assert!(matches!(items[at + 1], Value::Int32(_)), "{reply}");
    assert!(matches!(items[at + 2], Value::Float64(_)), "{reply}");
    let mut rest: Vec<Value> = items[..at].to_vec();
    rest.extend_from_slice(&items[at + 3..]);
    rest.into_iter().collect::<Bottle>().to_string()
}

#[test]
fn impedance_rpc_shapes_are_cpp_3_12() {
    let mut dev = FakeMotionControl::with_joints(4);
    let mut st = RpcStamp::new();
    let d = &mut dev;
    // set: the values travel in a list; the reply is [ok] alone
    assert_eq!(
        rpc(d, &mut st, "[set] [iimp] [ipr] 1 (1.5 0.25)").to_string(),
        "[ok]"
    );
    assert_eq!(
        rpc(d, &mut st, "[set] [iimp] [iof] 1 (0.5)").to_string(),
        "[ok]"
    );
    // get: [is] <echo> (values) [tsta] count time [ok]
    let r = rpc(d, &mut st, "[get] [iimp] [ipr] 1");
    assert_eq!(unstamped(&r), "[is] [iimp] (1.5 0.25) [ok]");
    let stamped = Bottle::from_text(format!(
        "[is] [iimp] (1.5 0.25) [tsta] {} {} [ok]",
        r.get(4).unwrap(),
        r.get(5).unwrap()
    ));
    assert_eq!(r.encode(), stamped.encode(), "reply bytes");
    assert_eq!(
        unstamped(&rpc(d, &mut st, "[get] [iimp] [iof] 1")),
        "[is] [iimp] (0.5) [ok]"
    );
    // 3.12 asks the limits with the generic [llim]; the fake's constants
    assert_eq!(
        unstamped(&rpc(d, &mut st, "[get] [iimp] [llim] 0")),
        "[is] [iimp] (1.0 10.0 2.0 20.0) [ok]"
    );
    // plain words, as `yarp rpc` users type them, are packed into vocabs and echoed
    assert_eq!(
        rpc(d, &mut st, "set iimp ipr 0 (1.0 0.5)").to_string(),
        "[ok]"
    );
    assert_eq!(
        unstamped(&rpc(d, &mut st, "get iimp ipr 0")),
        "[is] iimp (1.0 0.5) [ok]"
    );
    // a missing list item reads as 0 (C++ Bottle::get out of range)
    assert_eq!(
        rpc(d, &mut st, "[set] [iimp] [ipr] 2 (7.0)").to_string(),
        "[ok]"
    );
    assert_eq!(
        unstamped(&rpc(d, &mut st, "[get] [iimp] [ipr] 2")),
        "[is] [iimp] (7.0 0.0) [ok]"
    );
    // what C++ 3.12 refuses
    for bad in [
        "[set] [iimp] [ipr] 0 1.0 2.0", // values not in a list
        "[set] [iimp] [llim] 0 (1.0)",
        "[get] [iimp] [ilim] 0", // the later releases' vocab
        "[get] [iimp] [ipr] 9",  // no such joint
        "[set] [imp] [ipr] 0 (1.0 0.1)",
        "[rst] [iimp] [ipr] 0",
    ] {
        assert_eq!(rpc(d, &mut st, bad).to_string(), "[fail]", "{bad}");
    }
}

#[test]
fn calibration_rpc_shapes_are_cpp_3_12() {
    let mut dev = FakeMotionControl::with_joints(4);
    let mut st = RpcStamp::new();
    let d = &mut dev;
    // the fake (as C++'s) calibrates at once and reports every joint done
    for (cmd, want) in [
        ("[calj] 0 3 1.0 2.0 3.0", "[ok]"),
        ("[cljp] 1 3 1.0 2.0 3.0 4.0", "[ok]"),
        ("[cald] 1", "[ok]"),
        ("[cald] 7", "[fail]"),
        ("[calj] 9 3 1.0 2.0 3.0", "[fail]"),
        // no calibrator set on the device: calibrateRobot fails, park answers ok anyway
        ("[cal] 0", "[fail]"),
        ("[park] 1", "[ok]"),
        // shorter than two elements (what the C++ client sends for these): [nak]
        ("[cal]", "[nak]"),
        ("[park]", "[nak]"),
        // not served by the 3.12 parser
        ("[abca] 0", "[fail]"),
    ] {
        assert_eq!(rpc(d, &mut st, cmd).to_string(), want, "{cmd}");
    }
    // the fake lacks IRemoteCalibrator (as in C++): [reca] fails
    assert_eq!(rpc(d, &mut st, "[get] [reca] [isca]").to_string(), "[fail]");
    assert_eq!(
        rpc(d, &mut st, "[set] [reca] [cal] 0").to_string(),
        "[fail]"
    );
}

/// What a calibrator device was asked to do.
#[derive(Default)]
struct SpyCalibrator {
    calls: Arc<Mutex<Vec<String>>>,
}

impl SpyCalibrator {
    fn log(&self, s: String) -> DevResult<()> {
        self.calls.lock().unwrap().push(s);
        Ok(())
    }
}

impl DeviceDriver for SpyCalibrator {
    fn open(&mut self, _: &Property) -> DevResult<()> {
        Ok(())
    }
    yarp_devices::views!(as_remote_calibrator);
}

impl IRemoteCalibrator for SpyCalibrator {
    fn is_calibrator_device_present(&mut self) -> DevResult<bool> {
        Ok(true)
    }
    fn calibrate_single_joint(&mut self, j: usize) -> DevResult<()> {
        self.log(format!("cal {j}"))
    }
    fn calibrate_whole_part(&mut self) -> DevResult<()> {
        self.log("cals".into())
    }
    fn homing_single_joint(&mut self, j: usize) -> DevResult<()> {
        self.log(format!("hom {j}"))
    }
    fn homing_whole_part(&mut self) -> DevResult<()> {
        self.log("homs".into())
    }
    fn park_single_joint(&mut self, j: usize, wait: bool) -> DevResult<()> {
        self.log(format!("par {j} {wait}"))
    }
    fn park_whole_part(&mut self) -> DevResult<()> {
        self.log("pars".into())
    }
    fn quit_calibrate(&mut self) -> DevResult<()> {
        Err(DeviceError::Unsupported("refused by the spy"))
    }
    fn quit_park(&mut self) -> DevResult<()> {
        self.log("qupa".into())
    }
}

/// A remapper over one 4-joint fake, optionally with `spy` as its calibrator device.
fn remapper(spy: Option<&Arc<Mutex<Vec<String>>>>) -> PolyDriver {
    let fake = shared(PolyDriver::from_driver(
        "fakeMotionControl",
        Box::new(FakeMotionControl::with_joints(4)),
    ));
    let mut r = ControlBoardRemapper::new();
    r.open(&Property::from_config_text("networks (a)\njoints 4\na (0 3 0 3)\n").unwrap())
        .expect("open remapper");
    r.as_multiple_wrapper()
        .unwrap()
        .attach_all(&[("a".into(), fake)])
        .expect("attach");
    if let Some(calls) = spy {
        let s = SpyCalibrator {
            calls: calls.clone(),
        };
        r.set_calibrator_device(Some(shared(PolyDriver::from_driver(
            "spyCalibrator",
            Box::new(s),
        ))));
    }
    PolyDriver::from_driver("controlboardremapper", Box::new(r))
}

#[test]
fn remote_calibrator_rpc_through_the_remapper() {
    let mut st = RpcStamp::new();
    // no calibrator device: present is 0 (no timestamp in this reply); calls go to the
    // boards, and the fake has no remote calibrator
    let mut plain = remapper(None);
    let d = plain.device();
    assert_eq!(
        rpc(d, &mut st, "[get] [reca] [isca]").to_string(),
        "[is] [reca] 0 [ok]"
    );
    assert_eq!(
        rpc(d, &mut st, "[set] [reca] [cal] 0").to_string(),
        "[fail]"
    );
    let calls = Arc::new(Mutex::new(Vec::new()));
    let mut with = remapper(Some(&calls));
    let d = with.device();
    assert_eq!(
        rpc(d, &mut st, "[get] [reca] [isca]").encode(),
        Bottle::from_text("[is] [reca] 1 [ok]").encode()
    );
    for (cmd, want) in [
        ("[set] [reca] [cal] 2", "[ok]"),
        ("[set] [reca] [cals]", "[ok]"),
        ("[set] [reca] [hom] 1", "[ok]"),
        ("[set] [reca] [homs]", "[ok]"),
        ("[set] [reca] [par] 3", "[ok]"),
        ("[set] [reca] [pars]", "[ok]"),
        ("[set] [reca] [quca]", "[fail]"),
        ("[set] [reca] [qupa]", "[ok]"),
        ("[set] [reca] [zzz]", "[fail]"),
        ("[get] [reca] [cal]", "[fail]"),
    ] {
        assert_eq!(rpc(d, &mut st, cmd).to_string(), want, "{cmd}");
    }
    assert_eq!(
        *calls.lock().unwrap(),
        [
            "cal 2",
            "cals",
            "hom 1",
            "homs",
            "par 3 true",
            "pars",
            "qupa"
        ]
    );
}

fn open(text: &str) -> PolyDriver {
    PolyDriver::open(&Property::from_config_text(text).unwrap()).expect("open device")
}

#[test]
fn remote_round_trip_impedance_and_calibration() {
    name_client();
    let _server = open(
        "device controlBoard_nws_yarp\nsubdevice fakeMotionControl\nname /imp\nperiod 0.01\n\
         [GENERAL]\njoints 4\n",
    );
    let mut remote = open("device remote_controlboard\nremote /imp\nlocal /impcli\n");
    let d = remote.device();
    let imp = d.as_impedance_control().expect("IImpedanceControl");
    assert_eq!(imp.get_axes().unwrap(), 4);
    assert_eq!(imp.get_impedance(2).unwrap(), (0.0, 0.0));
    imp.set_impedance(2, 1.5, 0.25).unwrap();
    assert_eq!(imp.get_impedance(2).unwrap(), (1.5, 0.25));
    imp.set_impedance_offset(3, -0.5).unwrap();
    assert_eq!(imp.get_impedance_offset(3).unwrap(), -0.5);
    assert_eq!(
        imp.get_current_impedance_limit(0).unwrap(),
        ImpedanceLimits {
            min_stiffness: 1.0,
            max_stiffness: 10.0,
            min_damping: 2.0,
            max_damping: 20.0,
        }
    );
    assert!(imp.set_impedance(9, 1.0, 1.0).is_err());
    assert!(imp.get_impedance(9).is_err());

    let cal = d.as_control_calibration().expect("IControlCalibration");
    cal.calibrate_axis_with_params(0, 3, 1.0, 2.0, 3.0).unwrap();
    let params = CalibrationParameters {
        kind: 3,
        param1: 1.0,
        param4: 4.0,
        ..Default::default()
    };
    cal.set_calibration_parameters(1, &params).unwrap();
    assert!(cal.calibration_done(1).unwrap());
    // [fail] means "not done" (here: no such joint)
    assert!(!cal.calibration_done(9).unwrap());
    assert!(cal.calibrate_axis_with_params(9, 3, 1.0, 2.0, 3.0).is_err());
    // a lone vocab, as C++ sends: refused by a 3.12 server
    assert!(cal.calibrate_robot().is_err());
    assert!(cal.park(true).is_err());
    assert!(cal.abort_calibration().is_err());
    assert!(cal.abort_park().is_err());

    // the fake has no remote calibrator: the server fails these
    let rc = d.as_remote_calibrator().expect("IRemoteCalibrator");
    assert!(rc.is_calibrator_device_present().is_err());
    assert!(rc.calibrate_single_joint(0).is_err());
}

#[test]
fn remote_round_trip_remote_calibrator_and_remapper() {
    name_client();
    let calls = Arc::new(Mutex::new(Vec::new()));
    let mut nws = open("device controlBoard_nws_yarp\nname /rcal\nperiod 0.01\n");
    nws.device()
        .as_wrapper()
        .unwrap()
        .attach(shared(remapper(Some(&calls))))
        .expect("attach remapper");
    let mut remote = open("device remote_controlboard\nremote /rcal\nlocal /rcalcli\n");
    let d = remote.device();
    let rc = d.as_remote_calibrator().unwrap();
    assert!(rc.is_calibrator_device_present().unwrap());
    rc.calibrate_single_joint(1).unwrap();
    rc.calibrate_whole_part().unwrap();
    rc.homing_single_joint(2).unwrap();
    rc.homing_whole_part().unwrap();
    rc.park_single_joint(3, true).unwrap();
    rc.park_whole_part().unwrap();
    assert!(rc.quit_calibrate().is_err());
    rc.quit_park().unwrap();
    assert_eq!(
        *calls.lock().unwrap(),
        [
            "cal 1",
            "cals",
            "hom 2",
            "homs",
            "par 3 true",
            "pars",
            "qupa"
        ]
    );
    // impedance and calibration are forwarded by the remapper to the fake
    let imp = d.as_impedance_control().unwrap();
    imp.set_impedance(3, 4.0, 0.5).unwrap();
    assert_eq!(imp.get_impedance(3).unwrap(), (4.0, 0.5));
    assert_eq!(
        imp.get_current_impedance_limit(3).unwrap().max_damping,
        20.0
    );
    let cal = d.as_control_calibration().unwrap();
    cal.calibrate_axis_with_params(2, 0, 0.0, 0.0, 0.0).unwrap();
    assert!(cal.calibration_done(2).unwrap());
}

/// As C++ `attachAll`: a device keyed `calibrator` becomes the remapper's calibrator
/// device; while that calibrator is busy (held by its own calibrate or park, which may
/// wait for the remapper) remote calls fail at once instead of deadlocking.
#[test]
fn remapper_takes_its_calibrator_from_the_attach_list_and_never_waits_for_a_busy_one() {
    let calls = Arc::new(Mutex::new(Vec::new()));
    let fake = shared(PolyDriver::from_driver(
        "fakeMotionControl",
        Box::new(FakeMotionControl::with_joints(4)),
    ));
    let spy = shared(PolyDriver::from_driver(
        "spyCalibrator",
        Box::new(SpyCalibrator {
            calls: calls.clone(),
        }),
    ));
    let mut r = ControlBoardRemapper::new();
    r.open(&Property::from_config_text("networks (a)\njoints 4\na (0 3 0 3)\n").unwrap())
        .expect("open remapper");
    r.as_multiple_wrapper()
        .unwrap()
        .attach_all(&[("a".into(), fake), ("Calibrator".into(), spy.clone())])
        .expect("attach");
    let rc = r.as_remote_calibrator().unwrap();
    assert!(rc.is_calibrator_device_present().unwrap());
    rc.homing_single_joint(2).unwrap();
    {
        let _busy = spy.lock();
        let err = rc.homing_whole_part().unwrap_err();
        assert!(err.to_string().contains("busy"), "{err}");
    }
    rc.park_whole_part().unwrap();
    assert_eq!(*calls.lock().unwrap(), ["hom 2", "pars"]);
    rc.set_calibrator_device(None).unwrap();
    assert!(!rc.is_calibrator_device_present().unwrap());
}

/// A calibrator whose homing runs until quit (at most 10 s), like parametricCalibrator's
/// bounded waits.
#[derive(Default)]
struct SlowCalibrator {
    quit: Arc<std::sync::atomic::AtomicBool>,
}

impl DeviceDriver for SlowCalibrator {
    fn open(&mut self, _: &Property) -> DevResult<()> {
        Ok(())
    }
    yarp_devices::views!(as_remote_calibrator);
}

impl IRemoteCalibrator for SlowCalibrator {
    fn is_calibrator_device_present(&mut self) -> DevResult<bool> {
        Ok(true)
    }
    fn calibrate_single_joint(&mut self, _: usize) -> DevResult<()> {
        Ok(())
    }
    fn calibrate_whole_part(&mut self) -> DevResult<()> {
        Ok(())
    }
    fn homing_single_joint(&mut self, _: usize) -> DevResult<()> {
        Ok(())
    }
    fn homing_whole_part(&mut self) -> DevResult<()> {
        use std::sync::atomic::Ordering;
        // (the flag is not cleared here, so a quit that comes first is not lost)
        let end = std::time::Instant::now() + std::time::Duration::from_secs(10);
        while std::time::Instant::now() < end {
            if self.quit.load(Ordering::SeqCst) {
                return Err(DeviceError::Unsupported("stopped by quitPark"));
            }
            std::thread::sleep(std::time::Duration::from_millis(10));
        }
        Ok(())
    }
    fn park_single_joint(&mut self, _: usize, _: bool) -> DevResult<()> {
        Ok(())
    }
    fn park_whole_part(&mut self) -> DevResult<()> {
        Ok(())
    }
    fn quit_calibrate(&mut self) -> DevResult<()> {
        self.quit.store(true, std::sync::atomic::Ordering::SeqCst);
        Ok(())
    }
    fn quit_park(&mut self) -> DevResult<()> {
        self.quit_calibrate()
    }
    fn quit_signal(&self) -> Option<Arc<std::sync::atomic::AtomicBool>> {
        Some(self.quit.clone())
    }
}

/// A calibrator busy with a procedure started in-process (as yarprobotinterface's
/// calibrate or park holds it) still gets a client's `quitCalibrate`/`quitPark` over the
/// part's `rpc:i`, as C++'s flag-based abort: the running procedure stops at once. Other
/// remote-calibrator requests meanwhile are refused, not queued behind it.
#[test]
fn a_quit_over_rpc_stops_a_procedure_that_holds_the_calibrator() {
    name_client();
    let fake = shared(PolyDriver::from_driver(
        "fakeMotionControl",
        Box::new(FakeMotionControl::with_joints(4)),
    ));
    let slow = shared(PolyDriver::from_driver(
        "slowCalibrator",
        Box::new(SlowCalibrator::default()),
    ));
    let mut r = ControlBoardRemapper::new();
    r.open(&Property::from_config_text("networks (a)\njoints 4\na (0 3 0 3)\n").unwrap())
        .expect("open remapper");
    r.as_multiple_wrapper()
        .unwrap()
        .attach_all(&[("a".into(), fake), ("calibrator".into(), slow.clone())])
        .expect("attach");
    let mut nws = open("device controlBoard_nws_yarp\nname /qcal\nperiod 0.01\n");
    nws.device()
        .as_wrapper()
        .unwrap()
        .attach(shared(PolyDriver::from_driver(
            "controlboardremapper",
            Box::new(r),
        )))
        .expect("attach remapper");
    let mut client = open("device remote_controlboard\nremote /qcal\nlocal /qcal/cli\n");
    let (started_tx, started) = std::sync::mpsc::channel();
    let procedure = std::thread::spawn(move || {
        let mut c = slow.lock();
        started_tx.send(()).unwrap();
        let t = std::time::Instant::now();
        let r = c
            .device()
            .as_remote_calibrator()
            .unwrap()
            .homing_whole_part();
        (r, t.elapsed())
    });
    started.recv().unwrap();
    let rc = client.device().as_remote_calibrator().unwrap();
    assert!(rc.homing_single_joint(1).is_err(), "busy: refused");
    rc.quit_park().unwrap();
    let (r, took) = procedure.join().unwrap();
    assert!(r.is_err(), "a quit procedure fails");
    assert!(
        took < std::time::Duration::from_secs(3),
        "the quit stopped it: {took:?}"
    );
}
