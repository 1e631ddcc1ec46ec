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
