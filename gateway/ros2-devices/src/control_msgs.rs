//! yarp-devices-ros2's `yarp_control_msgs` services as typed requests and responses (the
//! CDR layout of the catalog types `yarp_control_msgs/srv/*` of
//! `yarp_ros2_gateway::types`, checked by the tests below), and the control-mode names
//! `controlBoard_nws_ros2` speaks.

use serde::{Deserialize, Serialize};
use yarp_proto::Vocab32;

/// `GetJointsNames` request.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct JointIndexes {
    pub joint_indexes: Vec<i32>,
}

/// `GetControlModes`, `GetPosition` and `GetVelocity` requests.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct JointNames {
    pub names: Vec<String>,
}

/// `SetControlModes` request.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct SetModes {
    pub names: Vec<String>,
    pub modes: Vec<String>,
}

/// `GetAvailableControlModes` request.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct OnlyImplemented {
    pub only_implemented: bool,
}

/// `GetJointsNames` (names), `GetControlModes` and `GetAvailableControlModes` (modes)
/// responses: strings, then the outcome.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StringsOutcome {
    pub values: Vec<String>,
    pub response: String,
    pub opt_descr: String,
}

/// `GetPosition` and `GetVelocity` responses.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ValuesOutcome {
    pub values: Vec<f64>,
    pub response: String,
    pub opt_descr: String,
}

/// `SetControlModes` response.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Outcome {
    pub response: String,
    pub opt_descr: String,
}

impl ros2_client::Message for JointIndexes {}
impl ros2_client::Message for JointNames {}
impl ros2_client::Message for SetModes {}
impl ros2_client::Message for OnlyImplemented {}
impl ros2_client::Message for StringsOutcome {}
impl ros2_client::Message for ValuesOutcome {}
impl ros2_client::Message for Outcome {}

/// The `.srv` default of `response` (`string response "NOT_SPECIFIED"`).
pub const NOT_SPECIFIED: &str = "NOT_SPECIFIED";

impl Outcome {
    pub fn new(response: &str) -> Outcome {
        Outcome {
            response: response.into(),
            opt_descr: String::new(),
        }
    }
}

impl StringsOutcome {
    pub fn new(values: Vec<String>, response: &str) -> StringsOutcome {
        StringsOutcome {
            values,
            response: response.into(),
            opt_descr: String::new(),
        }
    }
}

impl ValuesOutcome {
    pub fn new(values: Vec<f64>, response: &str) -> ValuesOutcome {
        ValuesOutcome {
            values,
            response: response.into(),
            opt_descr: String::new(),
        }
    }
}

const fn vocab(s: &str) -> Vocab32 {
    Vocab32::new(s)
}

/// The control modes by their yarp-devices-ros2 names, with C++ YARP's vocabs
/// (`IControlMode.h`); the first ten can be set (`fromStringToCtrlMode`), the rest are
/// only reported (`fromCtrlModeToString`).
pub const MODES: &[(&str, Vocab32)] = &[
    ("IDLE", vocab("idl")),
    ("TORQUE", vocab("torq")),
    ("POSITION", vocab("pos")),
    ("POSITION_DIRECT", vocab("posd")),
    ("VELOCITY", vocab("vel")),
    ("CURRENT", vocab("icur")),
    ("PWM", vocab("ipwm")),
    ("IMPEDANCE_POS", vocab("impo")),
    ("IMPEDANCE_VEL", vocab("imve")),
    ("MIXED", vocab("mix")),
    ("HW_FAULT", vocab("hwfa")),
    ("CALIBRATING", vocab("cal")),
    ("CALIB_DONE", vocab("cald")),
    ("NOT_CONFIGURED", vocab("cfgn")),
    ("CONFIGURED", vocab("cfgy")),
];
const SETTABLE: usize = 10;

/// What `GetAvailableControlModes` answers with `only_implemented`
/// (`implementedCtrlModes`: what the command topics serve).
pub const IMPLEMENTED: &[&str] = &["POSITION", "POSITION_DIRECT", "VELOCITY"];

/// The name of a mode a board reports; `None` for a vocab C++ has no name for.
pub fn mode_name(m: Vocab32) -> Option<&'static str> {
    MODES.iter().find(|(_, v)| *v == m).map(|(n, _)| *n)
}

/// The vocab of a mode a client may set.
pub fn settable_mode(name: &str) -> Option<Vocab32> {
    MODES[..SETTABLE]
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, v)| *v)
}

/// Every settable mode, in the order C++ lists them (its `std::map`'s, by name).
pub fn settable_modes() -> Vec<String> {
    let mut all: Vec<String> = MODES[..SETTABLE]
        .iter()
        .map(|(n, _)| n.to_string())
        .collect();
    all.sort();
    all
}

#[cfg(test)]
mod tests {
    use super::*;
    use byteorder::LittleEndian;
    use serde::de::DeserializeSeed;
    use yarp_ros2_gateway::dynmsg::MsgSeed;

    /// The typed value's CDR bytes decode as the catalog type and encode back identically.
    fn same_layout<T: Serialize>(v: &T, catalog: &str) {
        let bytes = cdr_encoding::to_vec::<_, LittleEndian>(v).unwrap();
        let mut d = cdr_encoding::CdrDeserializer::<LittleEndian>::new(&bytes);
        let dynamic = MsgSeed::new(catalog)
            .unwrap()
            .deserialize(&mut d)
            .unwrap_or_else(|e| panic!("{catalog}: {e}"));
        assert_eq!(d.bytes_consumed(), bytes.len(), "{catalog}");
        assert!(dynamic.conforms_to(catalog), "{catalog}");
        assert_eq!(
            cdr_encoding::to_vec::<_, LittleEndian>(&dynamic).unwrap(),
            bytes,
            "{catalog}"
        );
    }

    #[test]
    fn typed_services_have_the_catalog_layout() {
        let srv = |s: &str| format!("yarp_control_msgs/srv/{s}");
        let names = JointNames {
            names: vec!["neck_pitch".into(), "l_elbow".into()],
        };
        same_layout(
            &JointIndexes {
                joint_indexes: vec![0, 3],
            },
            &srv("GetJointsNames_Request"),
        );
        let strings = StringsOutcome::new(vec!["a".into(), "bc".into()], "OK");
        same_layout(&strings, &srv("GetJointsNames_Response"));
        same_layout(&names, &srv("GetControlModes_Request"));
        same_layout(&strings, &srv("GetControlModes_Response"));
        same_layout(
            &SetModes {
                names: names.names.clone(),
                modes: vec!["POSITION".into(), "IDLE".into()],
            },
            &srv("SetControlModes_Request"),
        );
        same_layout(&Outcome::new("OK"), &srv("SetControlModes_Response"));
        same_layout(
            &OnlyImplemented {
                only_implemented: true,
            },
            &srv("GetAvailableControlModes_Request"),
        );
        same_layout(&strings, &srv("GetAvailableControlModes_Response"));
        let values = ValuesOutcome::new(vec![0.5, -1.0], "OK");
        same_layout(&names, &srv("GetPosition_Request"));
        same_layout(&values, &srv("GetPosition_Response"));
        same_layout(&names, &srv("GetVelocity_Request"));
        same_layout(&values, &srv("GetVelocity_Response"));
    }

    #[test]
    fn mode_names() {
        assert_eq!(mode_name(vocab("pos")), Some("POSITION"));
        assert_eq!(mode_name(vocab("mix")), Some("MIXED"));
        assert_eq!(mode_name(vocab("zzz")), None);
        assert_eq!(settable_mode("VELOCITY"), Some(vocab("vel")));
        assert_eq!(settable_mode("HW_FAULT"), None);
        assert_eq!(settable_modes()[0], "CURRENT");
        assert_eq!(settable_modes().len(), 10);
    }
}
