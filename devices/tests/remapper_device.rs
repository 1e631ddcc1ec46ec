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
    let mut pd = d.lock().unwrap();
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
    let mut h = hand.lock().unwrap();
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
        let mut p = part.lock().unwrap();
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
