//! The robot runner on mock devices (no sockets): which devices open with which
//! configuration, and the order of attach / calibrate / park / detach / close calls
//! across the phases, from a fixture robot with includes.

use std::path::PathBuf;
use std::sync::atomic::Ordering;
use std::sync::{Arc, Mutex};
use yarp_devices::robotinterface::{
    read_robot_file, read_robot_str, ActionPhase, DeviceFactory, RobotRunner,
};
use yarp_devices::{
    DevResult, DeviceDriver, DeviceError, ICalibrator, IMultipleWrapper, IWrapper, PolyDriver,
    SharedDevice,
};
use yarp_proto::Property;

type Log = Arc<Mutex<Vec<String>>>;

fn push(log: &Log, s: String) {
    log.lock().unwrap().push(s);
}

fn id_of(d: &SharedDevice) -> String {
    d.lock().name().to_string()
}

/// One mock driver of any kind; `id` is the robot's device name.
struct Mock {
    kind: String,
    id: String,
    log: Log,
    /// `fail_attach` in the configuration: every attach fails.
    fail_attach: bool,
    /// `fail_calibrate` in the configuration: every calibration fails.
    fail_calibrate: bool,
}

impl DeviceDriver for Mock {
    fn open(&mut self, config: &Property) -> DevResult<()> {
        self.id = config
            .find("id")
            .and_then(|v| v.as_str())
            .unwrap_or("")
            .into();
        self.fail_attach = config.check("fail_attach");
        self.fail_calibrate = config.check("fail_calibrate");
        if config.check("fail") {
            return Err(DeviceError::MissingParam {
                device: self.id.clone(),
                param: "fail".into(),
            });
        }
        push(&self.log, format!("open {}", self.id));
        Ok(())
    }
    fn close(&mut self) -> DevResult<()> {
        push(&self.log, format!("close {}", self.id));
        Ok(())
    }
    fn as_wrapper(&mut self) -> Option<&mut dyn IWrapper> {
        (self.kind == "mockWrapper").then_some(self as &mut dyn IWrapper)
    }
    fn as_multiple_wrapper(&mut self) -> Option<&mut dyn IMultipleWrapper> {
        (self.kind == "mockMulti").then_some(self as &mut dyn IMultipleWrapper)
    }
    fn as_calibrator(&mut self) -> Option<&mut dyn ICalibrator> {
        (self.kind == "mockCalibrator").then_some(self as &mut dyn ICalibrator)
    }
}

impl IWrapper for Mock {
    fn attach(&mut self, device: SharedDevice) -> DevResult<()> {
        push(
            &self.log,
            format!("attach {} -> {}", self.id, id_of(&device)),
        );
        Ok(())
    }
    fn detach(&mut self) -> DevResult<()> {
        push(&self.log, format!("detach {}", self.id));
        Ok(())
    }
}

impl IMultipleWrapper for Mock {
    fn attach_all(&mut self, devices: &[(String, SharedDevice)]) -> DevResult<()> {
        if self.fail_attach {
            return Err(DeviceError::Unsupported("no such network"));
        }
        let list: Vec<String> = devices
            .iter()
            .map(|(k, d)| format!("{k}={}", id_of(d)))
            .collect();
        push(
            &self.log,
            format!("attach_all {} [{}]", self.id, list.join(" ")),
        );
        Ok(())
    }
    fn detach_all(&mut self) -> DevResult<()> {
        push(&self.log, format!("detach_all {}", self.id));
        Ok(())
    }
}

impl ICalibrator for Mock {
    fn calibrate(&mut self, target: SharedDevice) -> DevResult<()> {
        push(
            &self.log,
            format!("calibrate {} by {}", id_of(&target), self.id),
        );
        if self.fail_calibrate {
            return Err(DeviceError::Unsupported("joints still moving after 20 s"));
        }
        Ok(())
    }
    fn park(&mut self, target: SharedDevice, wait: bool) -> DevResult<()> {
        push(
            &self.log,
            format!("park {} by {} wait={wait}", id_of(&target), self.id),
        );
        Ok(())
    }
}

/// Makes mocks; records every configuration it opens.
struct MockFactory {
    log: Log,
    configs: Arc<Mutex<Vec<Property>>>,
}

impl DeviceFactory for MockFactory {
    fn knows(&self, kind: &str) -> bool {
        kind.starts_with("mock")
    }
    fn open(&self, config: &Property) -> DevResult<PolyDriver> {
        let kind = config
            .find("device")
            .and_then(|v| v.as_str())
            .unwrap()
            .to_string();
        let mut m = Mock {
            kind: kind.clone(),
            id: String::new(),
            log: self.log.clone(),
            fail_attach: false,
            fail_calibrate: false,
        };
        m.open(config)?;
        self.configs.lock().unwrap().push(config.clone());
        // The PolyDriver name is the robot's device name, so the log reads naturally.
        Ok(PolyDriver::from_driver(&m.id.clone(), Box::new(m)))
    }
}

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/robotinterface")
        .join(name)
}

fn runner_for(
    robot: yarp_devices::robotinterface::Robot,
) -> (RobotRunner, Log, Arc<Mutex<Vec<Property>>>) {
    let log: Log = Arc::default();
    let configs = Arc::default();
    let factory = MockFactory {
        log: log.clone(),
        configs: Arc::clone(&configs),
    };
    (
        RobotRunner::with_factory(robot, Box::new(factory)),
        log,
        configs,
    )
}

fn take(log: &Log) -> Vec<String> {
    std::mem::take(&mut *log.lock().unwrap())
}

#[test]
fn a_device_type_not_in_the_build_stops_the_startup_as_in_cpp() {
    let loaded = read_robot_file(&fixture("mock/robot.xml"), &Property::new()).unwrap();
    let (mut runner, log, _) = runner_for(loaded.robot);
    let err = runner.enter_phase(ActionPhase::Startup).unwrap_err();
    let problems = err.problems.join("; ");
    assert!(
        problems.contains("cannot open device ghost: could not find device <noSuchType>"),
        "{problems}"
    );
    let log = take(&log);
    // every device is tried (C++ opens them all, then gives up), the opened ones closed
    assert!(log.contains(&"open ghost_wrapper".to_string()), "{log:?}");
    assert!(log.contains(&"close board_a".to_string()), "{log:?}");
    assert!(!log.iter().any(|l| l.starts_with("attach")), "{log:?}");
    assert!(runner.failures().is_empty());
}

#[test]
fn phases_run_actions_in_level_order() {
    let loaded = read_robot_file(&fixture("mock/robot.xml"), &Property::new()).unwrap();
    let (mut runner, log, configs) = runner_for(loaded.robot);
    assert_eq!(runner.unavailable_devices(), [("ghost", "noSuchType")]);
    // `ghost`'s type is in no build: only keep-going skips it (C++ stops there)
    runner.set_keep_going(true);
    let seen: Arc<Mutex<Vec<(ActionPhase, u32)>>> = Arc::default();
    let sink = seen.clone();
    runner.set_progress(Box::new(move |phase, level| {
        sink.lock().unwrap().push((phase, level))
    }));

    runner.enter_phase(ActionPhase::Startup).unwrap();
    let startup = ActionPhase::Startup;
    assert_eq!(
        *seen.lock().unwrap(),
        [(startup, 0), (startup, 5), (startup, 10), (startup, 15)]
    );
    assert_eq!(runner.current_level(), 15);
    assert_eq!(
        take(&log),
        [
            "open board_a",
            "open board_b",
            "open remapper",
            "open server",
            "open calib",
            "open ghost_wrapper",
            // level 5
            "attach_all remapper [first=board_a second=board_b]",
            // level 10 (ghost_wrapper's target was skipped, so it stays unattached)
            "attach server -> remapper",
            // level 15
            "calibrate remapper by calib",
        ]
    );
    runner.enter_phase(ActionPhase::Run).unwrap();
    assert!(take(&log).is_empty());
    assert_eq!(runner.current_phase(), Some(ActionPhase::Run));

    runner.enter_phase(ActionPhase::Interrupt1).unwrap();
    assert_eq!(take(&log), ["park remapper by calib wait=true"]);
    runner.enter_phase(ActionPhase::Shutdown).unwrap();
    assert_eq!(
        take(&log),
        [
            "detach server",
            "detach_all remapper",
            "detach ghost_wrapper",
            "close ghost_wrapper",
            "close calib",
            "close server",
            "close remapper",
            "close board_b",
            "close board_a",
        ]
    );
    assert!(
        runner.device("board_a").is_none(),
        "closed devices are released"
    );

    // Configurations as C++ builds them: device, id, robotName, shared <devices> params.
    let configs = configs.lock().unwrap();
    let a = &configs[0];
    assert_eq!(a.find("device").and_then(|v| v.as_str()), Some("mockBoard"));
    assert_eq!(a.find("robotName").and_then(|v| v.as_str()), Some("/mock"));
    assert_eq!(a.find("shared").and_then(|v| v.as_i64()), Some(42));
    let joints = a.find_group("GENERAL").and_then(|g| g.find("Joints"));
    assert_eq!(joints.and_then(|v| v.as_i64()), Some(2));
    let server = &configs[3];
    assert_eq!(
        server.find("name").and_then(|v| v.as_str()),
        Some("/mock/server")
    );
    let remapper = &configs[2];
    assert_eq!(
        remapper.find("networks").unwrap().to_string(),
        "(first second)"
    );
    assert_eq!(remapper.find("second").unwrap().to_string(), "(2 3 0 1)");
}

const HEAD: &str = "<!DOCTYPE robot PUBLIC \"-//YARP//DTD yarprobotinterface 3.0//EN\" \"x\">\n";

fn robot(body: &str) -> yarp_devices::robotinterface::Robot {
    read_robot_str(&format!("{HEAD}{body}"), ".".as_ref(), &Property::new())
        .unwrap()
        .robot
}

#[test]
fn a_device_failing_to_open_fails_startup_and_closes_the_rest() {
    let (mut runner, log, _) = runner_for(robot(
        r#"<robot name="r"><device name="ok" type="mockBoard"/>
           <device name="bad" type="mockBoard"><param name="fail">1</param></device></robot>"#,
    ));
    let err = runner.enter_phase(ActionPhase::Startup).unwrap_err();
    assert_eq!(err.phase, ActionPhase::Startup);
    assert!(err.to_string().contains("bad"), "{err}");
    assert_eq!(take(&log), ["open ok", "close ok"]);
}

#[test]
fn an_unknown_target_is_an_error_naming_it() {
    let (mut runner, _log, _) = runner_for(robot(
        r#"<robot name="r"><device name="w" type="mockWrapper">
             <action phase="startup" level="1" type="attach"><param name="device">nobody</param></action>
           </device></robot>"#,
    ));
    let err = runner
        .enter_phase(ActionPhase::Startup)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("nobody") && err.contains("does not exist"),
        "{err}"
    );
    runner.enter_phase(ActionPhase::Shutdown).unwrap();
}

#[test]
fn attach_needs_a_network_option_and_a_wrapper() {
    let (mut runner, _log, _) = runner_for(robot(
        r#"<robot name="r"><device name="b" type="mockBoard"/>
           <device name="w" type="mockWrapper"><action phase="startup" level="1" type="attach"/></device>
           <device name="c" type="mockBoard"><action phase="startup" level="2" type="attach"><param name="device">b</param></action></device>
           <device name="x" type="mockWrapper"><action phase="startup" level="3" type="attach">
              <param name="device">b</param><param name="all">1</param><param name="networks">(n)</param></action></device>
           </robot>"#,
    ));
    let err = runner.enter_phase(ActionPhase::Startup).unwrap_err();
    assert_eq!(err.problems.len(), 3, "{err}");
    assert!(
        err.problems[0].contains("\"network\" or \"networks\""),
        "{err}"
    );
    assert!(err.problems[1].contains("not a wrapper"), "{err}");
    assert!(err.problems[2].contains("only one option"), "{err}");
    runner.enter_phase(ActionPhase::Shutdown).unwrap();
}

#[test]
fn an_interrupt_stops_startup_between_levels() {
    let (mut runner, log, _) = runner_for(robot(
        r#"<robot name="r"><device name="b" type="mockBoard"/>
           <device name="w" type="mockWrapper"><action phase="startup" level="1" type="attach"><param name="device">b</param></action></device></robot>"#,
    ));
    runner.interrupt_flag().store(true, Ordering::SeqCst);
    let err = runner.enter_phase(ActionPhase::Startup).unwrap_err();
    assert_eq!(err.problems, ["interrupted"]);
    runner.enter_phase(ActionPhase::Shutdown).unwrap();
    assert_eq!(take(&log), ["open b", "open w", "close w", "close b"]);
}

#[test]
fn reverse_shutdown_action_order_reverses_stopping_levels() {
    let (mut runner, log, _) = runner_for(robot(
        r#"<robot name="r" reverse-shutdown-action-order="true">
           <device name="b" type="mockBoard"/>
           <device name="w1" type="mockWrapper"><action phase="shutdown" level="1" type="detach"/></device>
           <device name="w2" type="mockWrapper"><action phase="shutdown" level="2" type="detach"/></device></robot>"#,
    ));
    runner.enter_phase(ActionPhase::Startup).unwrap();
    take(&log);
    runner.enter_phase(ActionPhase::Shutdown).unwrap();
    assert_eq!(
        take(&log),
        ["detach w2", "detach w1", "close w2", "close w1", "close b"]
    );
}

#[test]
fn skipped_targets_propagate_through_wrapper_chains() {
    // (keep-going) missing board -> remapper left unattached -> server aimed at it skipped, no error
    let (mut runner, log, _) = runner_for(robot(
        r#"<robot name="r"><device name="board" type="canmotioncontrol"/>
           <device name="remap" type="mockMulti"><action phase="startup" level="5" type="attach">
              <paramlist name="networks"><elem name="n">board</elem></paramlist></action></device>
           <device name="server" type="mockWrapper"><action phase="startup" level="10" type="attach">
              <param name="device">remap</param></action></device>
           <device name="calib" type="mockCalibrator"><action phase="startup" level="15" type="calibrate">
              <param name="target">remap</param></action></device></robot>"#,
    ));
    runner.set_keep_going(true);
    runner.enter_phase(ActionPhase::Startup).unwrap();
    assert_eq!(take(&log), ["open remap", "open server", "open calib"]);
    runner.enter_phase(ActionPhase::Shutdown).unwrap();
}

#[test]
fn dry_run_opens_nothing() {
    let loaded = read_robot_file(&fixture("mock/robot.xml"), &Property::new()).unwrap();
    let (mut runner, log, _) = runner_for(loaded.robot);
    runner.set_dryrun(true);
    for phase in [
        ActionPhase::Startup,
        ActionPhase::Interrupt1,
        ActionPhase::Shutdown,
    ] {
        runner.enter_phase(phase).unwrap();
    }
    assert!(take(&log).is_empty());
}

#[test]
fn keep_going_skips_failed_devices_and_what_depends_on_them() {
    // `bad` fails to open; `remap2` fails to attach (as a remapper naming a network no
    // board provides): both are reported, their dependants skipped, the rest comes up.
    let body = r#"<robot name="r"><device name="ok" type="mockBoard"/>
           <device name="bad" type="mockBoard"><param name="fail">1</param></device>
           <device name="remap1" type="mockMulti"><action phase="startup" level="5" type="attach">
              <paramlist name="networks"><elem name="n">ok</elem></paramlist></action></device>
           <device name="remap2" type="mockMulti"><param name="fail_attach">1</param>
              <action phase="startup" level="5" type="attach">
              <paramlist name="networks"><elem name="n">ok</elem></paramlist></action></device>
           <device name="remap3" type="mockMulti"><action phase="startup" level="5" type="attach">
              <paramlist name="networks"><elem name="n">bad</elem></paramlist></action></device>
           <device name="server1" type="mockWrapper"><action phase="startup" level="10" type="attach">
              <param name="device">remap1</param></action></device>
           <device name="server2" type="mockWrapper"><action phase="startup" level="10" type="attach">
              <param name="device">remap2</param></action></device>
           <device name="calib" type="mockCalibrator"><action phase="startup" level="15" type="calibrate">
              <param name="target">remap2</param></action></device></robot>"#;

    // without keep-going the startup stops at the failed open, as C++
    let (mut strict, _, _) = runner_for(robot(body));
    assert!(strict.enter_phase(ActionPhase::Startup).is_err());
    strict.enter_phase(ActionPhase::Shutdown).unwrap();

    let (mut runner, log, _) = runner_for(robot(body));
    runner.set_keep_going(true);
    runner.enter_phase(ActionPhase::Startup).unwrap();
    let failures = runner.failures().to_vec();
    assert_eq!(failures.len(), 2, "{failures:?}");
    assert!(
        failures[0].contains("cannot open device bad"),
        "{failures:?}"
    );
    assert!(
        failures[1].contains("remap2") && failures[1].contains("no such network"),
        "{failures:?}"
    );
    assert_eq!(
        take(&log),
        [
            "open ok",
            "open remap1",
            "open remap2",
            "open remap3",
            "open server1",
            "open server2",
            "open calib",
            "attach_all remap1 [n=ok]",
            "attach server1 -> remap1",
        ]
    );
    assert!(runner.device("bad").is_none());
    runner.enter_phase(ActionPhase::Run).unwrap();
    runner.enter_phase(ActionPhase::Shutdown).unwrap();
}

/// As C++ (its CalibratorThread ignores the calibrator's result): a calibration that fails
/// is logged and the robot starts and serves its parts; it is not shut down (its wrappers
/// detached, every command then answered [fail]) right after its startup.
#[test]
fn a_failed_calibration_does_not_stop_the_robot() {
    let (mut runner, log, _) = runner_for(robot(
        r#"<robot name="r"><device name="b" type="mockBoard"/>
           <device name="w" type="mockWrapper"><action phase="startup" level="10" type="attach">
              <param name="device">b</param></action></device>
           <device name="calib" type="mockCalibrator"><param name="fail_calibrate">1</param>
              <action phase="startup" level="15" type="calibrate">
              <param name="target">b</param></action></device></robot>"#,
    ));
    runner.enter_phase(ActionPhase::Startup).unwrap();
    assert!(runner.failures().is_empty(), "{:?}", runner.failures());
    assert_eq!(
        take(&log),
        [
            "open b",
            "open w",
            "open calib",
            "attach w -> b",
            "calibrate b by calib"
        ]
    );
    runner.enter_phase(ActionPhase::Shutdown).unwrap();
}
