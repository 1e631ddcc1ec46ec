//! `controlboardremapper`: boards joined by axis names or by networks, driven directly and,
//! wrapped by `controlBoard_nws_yarp`, through `remote_controlboard` (run under netns-run).

mod controlboard_common;

use controlboard_common::{name_client, wait_for};
use yarp_devices::vocabs::CM_VELOCITY;
use yarp_devices::{shared, DeviceError, PolyDriver, Registry, SharedDevice};
use yarp_proto::Property;

fn open(text: &str) -> PolyDriver {
    PolyDriver::open(&Property::from_config_text(text).unwrap()).expect("open")
}

fn fake(names: &[&str]) -> SharedDevice {
    let quoted: Vec<String> = names.iter().map(|n| format!("\"{n}\"")).collect();
    shared(open(&format!(
        "device fakeMotionControl\n[GENERAL]\njoints {}\nAxisName {}\n",
        names.len(),
        quoted.join(" ")
    )))
}

fn target(d: &SharedDevice, j: usize) -> f64 {
    let mut pd = d.lock();
    pd.device()
        .as_position_control()
        .unwrap()
        .get_target_position(j)
        .unwrap()
}

#[test]
fn registered_under_the_cpp_name() {
    assert!(Registry::names().contains(&"controlboardremapper"));
}

#[test]
fn axes_names_join_two_boards() {
    let arm = fake(&["a0", "a1"]);
    let hand = fake(&["h0", "h1", "h2"]);
    let mut part = open("device controlboardremapper\naxesNames (h2 a1 a0)\n");
    let d = part.device();
    assert!(
        d.as_encoders().unwrap().get_axes().is_err(),
        "not attached yet"
    );
    d.as_multiple_wrapper()
        .unwrap()
        .attach_all(&[("arm".into(), arm.clone()), ("hand".into(), hand.clone())])
        .unwrap();
    assert_eq!(d.as_encoders().unwrap().get_axes().unwrap(), 3);
    let names: Vec<String> = (0..3)
        .map(|j| d.as_axis_info().unwrap().get_axis_name(j).unwrap())
        .collect();
    assert_eq!(names, ["h2", "a1", "a0"]);
    d.as_position_control()
        .unwrap()
        .position_moves(&[7.0, 8.0, 9.0])
        .unwrap();
    assert_eq!(
        (target(&hand, 2), target(&arm, 1), target(&arm, 0)),
        (7.0, 8.0, 9.0)
    );
    assert_eq!(
        d.as_encoders().unwrap().get_encoders().unwrap(),
        [7.0, 8.0, 9.0]
    );
    d.as_control_mode()
        .unwrap()
        .set_control_mode(0, CM_VELOCITY)
        .unwrap();
    let mut h = hand.lock();
    assert_eq!(
        h.device()
            .as_control_mode()
            .unwrap()
            .get_control_mode(2)
            .unwrap(),
        CM_VELOCITY
    );
    drop(h);
    assert!(matches!(
        d.as_encoders().unwrap().get_encoder(3),
        Err(DeviceError::InvalidJoint { joint: 3, axes: 3 })
    ));
    // an axis no board has
    let mut bad = open("device controlboardremapper\naxesNames (a0 zz)\n");
    let err = bad
        .device()
        .as_multiple_wrapper()
        .unwrap()
        .attach_all(&[("arm".into(), arm)])
        .unwrap_err();
    assert!(err.to_string().contains("`zz`"), "{err}");
}

#[test]
fn networks_joined_part_served_and_driven_remotely() {
    name_client();
    let arm = fake(&["a0", "a1", "a2"]);
    let hand = fake(&["h0", "h1"]);
    let part = shared(open(
        "device controlboardremapper\nnetworks (net_arm net_hand)\njoints 4\n\
         net_arm (0 1 1 2)\nnet_hand 2 3 0 1\n",
    ));
    {
        let mut p = part.lock();
        let w = p.device().as_multiple_wrapper().unwrap();
        let missing = w
            .attach_all(&[("net_arm".into(), arm.clone())])
            .unwrap_err();
        assert!(missing.to_string().contains("net_hand"), "{missing}");
        w.attach_all(&[
            ("net_hand".into(), hand.clone()),
            ("net_arm".into(), arm.clone()),
        ])
        .unwrap();
    }
    let mut nws = open("device controlBoard_nws_yarp\nname /part\nperiod 0.01\n");
    nws.device()
        .as_multiple_wrapper()
        .unwrap()
        .attach_all(&[("part".into(), part)])
        .unwrap();
    let mut remote = open("device remote_controlboard\nremote /part\nlocal /partcli\n");
    let d = remote.device();
    assert_eq!(d.as_encoders().unwrap().get_axes().unwrap(), 4);
    d.as_position_control()
        .unwrap()
        .position_move(0, 5.0)
        .unwrap();
    d.as_position_control()
        .unwrap()
        .position_move(3, 6.0)
        .unwrap();
    assert_eq!((target(&arm, 1), target(&hand, 1)), (5.0, 6.0));
    let q = wait_for("the part's encoders", || {
        let q = d.as_encoders().unwrap().get_encoders().ok()?;
        (q[0] == 5.0 && q[3] == 6.0).then_some(q)
    });
    assert_eq!(q.len(), 4);
    assert_eq!(d.as_axis_info().unwrap().get_axis_name(2).unwrap(), "h0");
}

/// The interfaces added for the C++ 3.12 vectors (position direct, PID error/output/reset,
/// torque and current ranges, motors, duty cycles, motor encoder speeds) reach the
/// owning board with its own joint index.
#[test]
fn remapper_forwards_position_direct_pid_motor_and_pwm_calls() {
    use yarp_devices::vocabs::PIDTYPE_POSITION;
    let arm = fake(&["a0", "a1"]);
    let hand = fake(&["h0", "h1", "h2"]);
    let mut part = open("device controlboardremapper\naxesNames (h2 a1)\n");
    let d = part.device();
    d.as_multiple_wrapper()
        .unwrap()
        .attach_all(&[("arm".into(), arm.clone()), ("hand".into(), hand.clone())])
        .unwrap();
    let pdir = d.as_position_direct().unwrap();
    pdir.set_positions(&[4.0, 5.0]).unwrap();
    assert_eq!(pdir.get_ref_positions().unwrap(), [4.0, 5.0]);
    let board_ref = |b: &SharedDevice, j: usize| {
        let mut pd = b.lock();
        pd.device()
            .as_position_direct()
            .unwrap()
            .get_ref_position(j)
            .unwrap()
    };
    assert_eq!((board_ref(&hand, 2), board_ref(&arm, 1)), (4.0, 5.0));
    let pid = d.as_pid_control().unwrap();
    // the fake's PID output depends on the board joint: 1.1 + 10 j
    assert_eq!(pid.get_pid_output(PIDTYPE_POSITION, 0).unwrap(), 21.1);
    assert_eq!(pid.get_pid_error(PIDTYPE_POSITION, 1).unwrap(), 0.1);
    pid.reset_pid(PIDTYPE_POSITION, 1).unwrap();
    assert!(pid.reset_pid(PIDTYPE_POSITION, 2).is_err());
    let m = d.as_motor().unwrap();
    assert_eq!(m.get_number_of_motors().unwrap(), 2);
    assert_eq!(m.get_temperature(0).unwrap(), 39.5);
    assert_eq!(m.get_gearbox_ratio(1).unwrap(), 0.0);
    assert_eq!(
        d.as_torque_control().unwrap().get_torque_range(0).unwrap(),
        (0.0, 0.0)
    );
    let pwm = d.as_pwm_control().unwrap();
    assert_eq!(pwm.get_duty_cycle(0).unwrap(), 35.0);
    pwm.set_ref_duty_cycle(1, 12.0).unwrap();
    assert_eq!(pwm.get_duty_cycle(1).unwrap(), 12.0);
    let cur = d.as_current_control().unwrap();
    cur.set_ref_current(0, 2.0).unwrap();
    assert_eq!(cur.get_current_range(0).unwrap(), (0.02, 200.0));
    assert_eq!(
        d.as_amplifier_control().unwrap().get_current(0).unwrap(),
        1.0
    );
    let me = d.as_motor_encoders().unwrap();
    assert_eq!(me.get_motor_encoder_speeds().unwrap(), [0.0, 0.0]);
    assert_eq!(me.get_motor_encoder_accelerations().unwrap(), [0.0, 0.0]);
}

/// A board with joints and remote variables only: `gain` holds one value per joint.
struct VariableBoard {
    gains: Vec<f64>,
}

impl yarp_devices::DeviceDriver for VariableBoard {
    fn open(&mut self, _: &Property) -> yarp_devices::DevResult<()> {
        Ok(())
    }
    yarp_devices::views!(as_encoders, as_remote_variables);
}

impl yarp_devices::interfaces::IEncoders for VariableBoard {
    fn get_axes(&mut self) -> yarp_devices::DevResult<usize> {
        Ok(self.gains.len())
    }
    fn get_encoder(&mut self, _: usize) -> yarp_devices::DevResult<f64> {
        Ok(0.0)
    }
    fn get_encoder_speed(&mut self, _: usize) -> yarp_devices::DevResult<f64> {
        Ok(0.0)
    }
    fn get_encoder_acceleration(&mut self, _: usize) -> yarp_devices::DevResult<f64> {
        Ok(0.0)
    }
    fn get_encoder_timed(&mut self, _: usize) -> yarp_devices::DevResult<(f64, f64)> {
        Ok((0.0, 0.0))
    }
    fn set_encoder(&mut self, _: usize, _: f64) -> yarp_devices::DevResult<()> {
        Ok(())
    }
}

impl yarp_devices::interfaces::IRemoteVariables for VariableBoard {
    fn get_remote_variable(&mut self, key: &str) -> yarp_devices::DevResult<yarp_proto::Bottle> {
        match key {
            "gain" => Ok(self.gains.iter().copied().collect()),
            _ => Err(DeviceError::Unsupported("no such variable")),
        }
    }
    fn set_remote_variable(
        &mut self,
        key: &str,
        value: &yarp_proto::Bottle,
    ) -> yarp_devices::DevResult<()> {
        match key {
            "gain" => {
                self.gains = value.iter().filter_map(|v| v.as_f64()).collect();
                Ok(())
            }
            _ => Err(DeviceError::Unsupported("no such variable")),
        }
    }
    fn get_remote_variables_list(&mut self) -> yarp_devices::DevResult<yarp_proto::Bottle> {
        Ok(yarp_proto::Bottle::from_text(format!(
            "gain n{}",
            self.gains.len()
        )))
    }
}

/// IRemoteVariables through the remapper, as C++'s (3.12 and 4.0): a variable is every
/// board's values one after the other; it is set with one list per board; the keys are
/// those of the board owning joint 0; a board without the interface fails the call.
#[test]
fn remote_variables_join_the_boards_as_cpp_joins_them() {
    let board = |gains: &[f64]| {
        shared(PolyDriver::from_driver(
            "variableBoard",
            Box::new(VariableBoard {
                gains: gains.to_vec(),
            }),
        ))
    };
    let (a, b) = (board(&[1.0, 2.0]), board(&[3.0]));
    let mut part =
        open("device controlboardremapper\nnetworks (A B)\njoints 3\nA 0 1 0 1\nB 2 2 0 0\n");
    let d = part.device();
    d.as_multiple_wrapper()
        .unwrap()
        .attach_all(&[("A".into(), a.clone()), ("B".into(), b.clone())])
        .unwrap();
    let v = d.as_remote_variables().unwrap();
    assert_eq!(
        v.get_remote_variable("gain").unwrap().to_string(),
        "1.0 2.0 3.0"
    );
    assert_eq!(
        v.get_remote_variables_list().unwrap().to_string(),
        "gain n2"
    );
    v.set_remote_variable("gain", &yarp_proto::Bottle::from_text("(5.0 6.0) (7.0)"))
        .unwrap();
    assert_eq!(
        v.get_remote_variable("gain").unwrap().to_string(),
        "5.0 6.0 7.0"
    );
    // one list per board, or the call fails and nothing is set
    assert!(v
        .set_remote_variable("gain", &yarp_proto::Bottle::from_text("1.0 2.0 3.0"))
        .is_err());
    assert!(v.get_remote_variable("other").is_err());
    // a board without the interface fails the call
    let plain = fake(&["p0"]);
    let mut part =
        open("device controlboardremapper\nnetworks (A P)\njoints 3\nA 0 1 0 1\nP 2 2 0 0\n");
    let d = part.device();
    d.as_multiple_wrapper()
        .unwrap()
        .attach_all(&[("A".into(), a), ("P".into(), plain)])
        .unwrap();
    assert!(d
        .as_remote_variables()
        .unwrap()
        .get_remote_variable("gain")
        .is_err());
}
