//! Driver framework: registry, PolyDriver, parameter errors, fake dynamics.

use yarp_devices::{DeviceError, PolyDriver, Registry};
use yarp_proto::Property;

#[test]
fn unknown_device_lists_closest() {
    let err = Registry::get("fakeMotionControll").err().unwrap();
    let msg = err.to_string();
    assert!(
        msg.contains("closest known devices: fakeMotionControl"),
        "{msg}"
    );
}

#[test]
fn an_unknown_motor_name_suggests_motor_devices() {
    // the paper's device under another name: a motor was asked for, motors are offered
    let Err(DeviceError::UnknownDevice {
        closest,
        kind: Some(kind),
        ..
    }) = Registry::get("fake_motor")
    else {
        panic!("fake_motor is not a known device");
    };
    assert_eq!(kind.label(), "motor");
    for motor in closest.iter().map(String::as_str) {
        let (_, k) = Registry::interfaces(motor).expect("a known device");
        assert_eq!(k, kind, "{motor} is not a motor device");
    }
    assert!(closest.iter().any(|n| n == "test_motor"), "{closest:?}");
    assert!(
        closest.iter().any(|n| n == "fakeMotionControl"),
        "{closest:?}"
    );
    let msg = Registry::get("fake_motor").err().unwrap().to_string();
    assert!(
        msg.contains("(a motor was asked for)")
            && msg.ends_with("`yarpdev --list` lists every device with its kind and interfaces"),
        "{msg}"
    );
}

#[test]
fn mistyped_parameter_names_param_and_device() {
    let cfg =
        Property::from_config_text("device fakeMotionControl\n[GENERAL]\njoints four\n").unwrap();
    let err = PolyDriver::open(&cfg).err().unwrap();
    assert!(matches!(err, DeviceError::BadParam { .. }), "{err:?}");
    let msg = err.to_string();
    assert!(
        msg.contains("fakeMotionControl") && msg.contains("GENERAL::joints"),
        "{msg}"
    );
    assert_eq!(
        PolyDriver::open(&Property::new()).err().unwrap(),
        DeviceError::NoDeviceName
    );
}

#[test]
fn polydriver_views_and_motion() {
    let cfg = Property::from_config_text("device fakeMotionControl\naxes 3\n").unwrap();
    let mut pd = PolyDriver::open(&cfg).unwrap();
    assert_eq!(pd.name(), "fakeMotionControl");
    assert_eq!(pd.device().as_encoders().unwrap().get_axes().unwrap(), 3);
    let pos = pd.device().as_position_control().unwrap();
    pos.set_ref_speed(1, 1000.0).unwrap();
    pos.position_move(1, 1.0).unwrap();
    std::thread::sleep(std::time::Duration::from_millis(20));
    assert!(pos.check_motion_done(1).unwrap());
    assert_eq!(
        pd.device().as_encoders().unwrap().get_encoder(1).unwrap(),
        1.0
    );
    let v = pd.device().as_velocity_control().unwrap();
    assert!(v.velocity_move(7, 1.0).is_err());
    let info = pd.device().as_axis_info().unwrap();
    assert_eq!(info.get_axis_name(2).unwrap(), "joint2");
}
