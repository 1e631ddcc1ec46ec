//! YARP 4.0's encoding of the control-board protocol: the thrift service
//! `ControlBoardMsgs` on `<name>/nws/rpc:i`. A call is a list: the method's name as one
//! string (`"positionMoveOneRPC"`), then its arguments; a reply is the method's
//! `ReturnValue` alone, or a list of it and the values asked. Values are written as C++'s
//! generated code writes them (`yarp::os::idl::WireWriter`, 4.0's tags) and read as its
//! `WireReader` reads them (any integer tag for an integer, any number for a double).
//! The methods are those of `methods.rs`, by their thrift name; each value's form is its
//! [`Wire4`] impl.

use super::methods::{Method, Request};
use super::v3::{Done, Flat, Group, Listed, PidType, Wire3, J16};
use crate::driver::DeviceDriver;
use crate::error::DevResult;
use crate::interfaces::{Pid, PidExtraInfo};
use crate::sensors::wire::WireWriter;
use yarp_proto::tags::Generation;
use yarp_proto::{Bottle, Value, Vocab32};

use crate::thrift::{answer4, reply4, take_list};
use crate::thrift::{fail_reply, protocol_version_reply};
pub use crate::thrift::{Cursor4, ReturnValue, Wire4};

/// 4.0's `i16` joints: tag INT16 and two bytes (read from any integer, as C++ does).
impl Wire4 for J16 {
    fn put4(&self, w: &mut WireWriter) {
        w.int16(i16::try_from(self.0).unwrap_or(i16::MAX));
    }
    fn take4(c: &mut Cursor4<'_>) -> Option<Self> {
        usize::take4(c).map(J16)
    }
    fn zero() -> Self {
        J16(0)
    }
}

/// A group's joints: a `list<i32>` (4.0 sends no count before it).
impl Wire4 for Group {
    fn put4(&self, w: &mut WireWriter) {
        w.int32_list(self.0.iter().map(|j| i32::try_from(*j).unwrap_or(i32::MAX)));
    }
    fn take4(c: &mut Cursor4<'_>) -> Option<Self> {
        take_list(c, |v| usize::try_from(v.as_i64()?).ok()).map(Group)
    }
    fn zero() -> Self {
        Group(Vec::new())
    }
}

/// 4.0 numbers the PID types (`pos1`, `pos2`, ...; new ones `pod1`, `ved1`, `mix1`): its
/// first of each of 3.12's four is 3.12's (`pos1` is `pos`).
impl Wire4 for PidType {
    fn put4(&self, w: &mut WireWriter) {
        w.int32(self.to_v4().0);
    }
    fn take4(c: &mut Cursor4<'_>) -> Option<Self> {
        Vocab32::take4(c).map(PidType::from_v4)
    }
    fn zero() -> Self {
        PidType(Vocab32(0))
    }
}

/// `N` doubles, flat (the impedance's stiffness and damping, ...), padded with zeros as
/// C++ reads a short 3.12 list.
impl<const N: usize> Wire4 for Listed<N> {
    const COUNT: usize = N;
    fn put4(&self, w: &mut WireWriter) {
        for i in 0..N {
            w.float64(self.0.get(i).copied().unwrap_or(0.0));
        }
    }
    fn take4(c: &mut Cursor4<'_>) -> Option<Self> {
        (0..N)
            .map(|_| f64::take4(c))
            .collect::<Option<_>>()
            .map(Listed)
    }
    fn zero() -> Self {
        Listed(vec![0.0; N])
    }
}

/// A `yarp::os::Bottle`: nested, in its own encoding.
impl Wire4 for Bottle {
    fn put4(&self, w: &mut WireWriter) {
        w.raw(&self.encode_as(Generation::V4));
    }
    fn take4(c: &mut Cursor4<'_>) -> Option<Self> {
        c.item()?.as_list().cloned()
    }
    fn zero() -> Self {
        Bottle::new()
    }
}

impl Wire4 for Flat {
    fn put4(&self, w: &mut WireWriter) {
        self.0.put4(w);
    }
    fn take4(c: &mut Cursor4<'_>) -> Option<Self> {
        Bottle::take4(c).map(Flat)
    }
    fn zero() -> Self {
        Flat::default()
    }
}

/// The keys of `getRemoteVariablesList`: 3.12's one nested Bottle; 4.0's
/// `list<yBottle>`, of which C++'s server fills the first.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Keys(pub Bottle);

impl Wire3 for Keys {
    fn put(&self, b: &mut Bottle) {
        self.0.put(b);
    }
    fn take(c: &mut super::v3::Cursor<'_>) -> Option<Self> {
        Bottle::take(c).map(Keys)
    }
}

impl Wire4 for Keys {
    fn put4(&self, w: &mut WireWriter) {
        // no keys (a failed call) is C++'s empty vector
        if self.0.is_empty() {
            w.list_header(0);
        } else {
            w.list_header(1);
            self.0.put4(w);
        }
    }
    fn take4(c: &mut Cursor4<'_>) -> Option<Self> {
        let list = c.item()?.as_list()?;
        Some(Keys(
            list.get(0)
                .and_then(Value::as_list)
                .cloned()
                .unwrap_or_default(),
        ))
    }
    fn zero() -> Self {
        Keys::default()
    }
}

/// 4.0 answers "done" with `ok` and "not done" with a failure, and nothing else.
impl Wire4 for Done {
    const COUNT: usize = 0;
    fn put4(&self, _: &mut WireWriter) {}
    fn take4(_: &mut Cursor4<'_>) -> Option<Self> {
        Some(Done(true))
    }
    fn zero() -> Self {
        Done(false)
    }
    fn ret(&self) -> ReturnValue {
        if self.0 {
            ReturnValue::Ok
        } else {
            ReturnValue::MethodFailed
        }
    }
    fn from_failure(_: ReturnValue) -> Option<Self> {
        Some(Done(false))
    }
}

/// `yarp::dev::Pid` (`PidDataGains`): a nested list of ten tagged doubles.
impl Wire4 for Pid {
    fn put4(&self, w: &mut WireWriter) {
        let gains = self.to_array();
        w.list_header(gains.len());
        for g in gains {
            w.float64(g);
        }
    }
    fn take4(c: &mut Cursor4<'_>) -> Option<Self> {
        take_list(c, Value::as_f64).map(|g| Pid::from_slice(&g))
    }
    fn zero() -> Self {
        Pid::default()
    }
}

/// `list<T>` of a thrift struct: a list of the nested structs.
fn put_nested<T: Wire4>(items: &[T], w: &mut WireWriter) {
    w.list_header(items.len());
    for p in items {
        p.put4(w);
    }
}

fn take_nested<T: Wire4>(c: &mut Cursor4<'_>) -> Option<Vec<T>> {
    let list = c.item()?.as_list()?;
    let mut inner = Cursor4::new(list.items());
    (0..list.len()).map(|_| T::take4(&mut inner)).collect()
}

/// `list<yPid>`: a list of nested PIDs.
impl Wire4 for Vec<Pid> {
    fn put4(&self, w: &mut WireWriter) {
        put_nested(self, w);
    }
    fn take4(c: &mut Cursor4<'_>) -> Option<Self> {
        take_nested(c)
    }
    fn zero() -> Self {
        Vec::new()
    }
}

impl PidExtraInfo {
    /// The 13 strings in thrift's order: the three descriptions, then the ten units.
    fn strings(&self) -> impl Iterator<Item = &str> {
        [
            &self.pid_description,
            &self.input_data_description,
            &self.output_data_description,
        ]
        .into_iter()
        .chain(&self.units)
        .map(String::as_str)
    }

    fn from_strings(v: &[Value]) -> Option<PidExtraInfo> {
        let s: Vec<String> = v
            .iter()
            .map(|x| x.as_str().map(str::to_string))
            .collect::<Option<_>>()?;
        let [d, i, o, units @ ..] = <[String; 13]>::try_from(s).ok()?;
        Some(PidExtraInfo {
            pid_description: d,
            input_data_description: i,
            output_data_description: o,
            units,
        })
    }
}

/// `yInfoPid` (`PidDataExtraInfo`): one list of its 13 strings (description and units
/// written flat).
impl Wire4 for PidExtraInfo {
    fn put4(&self, w: &mut WireWriter) {
        w.list_header(13);
        for s in self.strings() {
            w.string(s);
        }
    }
    fn take4(c: &mut Cursor4<'_>) -> Option<Self> {
        PidExtraInfo::from_strings(c.item()?.as_list()?.items())
    }
    fn zero() -> Self {
        PidExtraInfo::default()
    }
}

/// 3.12 has no such call; its form is the same list (for the table's sake).
impl Wire3 for PidExtraInfo {
    fn put(&self, b: &mut Bottle) {
        let mut l = Bottle::with_capacity(13);
        for s in self.strings() {
            l.push(s);
        }
        b.push(Value::List(l));
    }
    fn take(c: &mut super::v3::Cursor<'_>) -> Option<Self> {
        PidExtraInfo::from_strings(Bottle::take(c)?.items())
    }
}

/// `list<yInfoPid>`.
impl Wire4 for Vec<PidExtraInfo> {
    fn put4(&self, w: &mut WireWriter) {
        put_nested(self, w);
    }
    fn take4(c: &mut Cursor4<'_>) -> Option<Self> {
        take_nested(c)
    }
    fn zero() -> Self {
        Vec::new()
    }
}

/// The reply to a call of `M` that gave `result`.
pub fn reply<M: Method>(result: DevResult<M::Reply>) -> Vec<u8> {
    reply4(result, M::V4.unwrap_or("controlBoard_nws_yarp (4.0)"))
}

/// `m`'s arguments from a call's values after its name, if they are all there.
pub fn decode<M: Method>(args: &[Value]) -> Option<M> {
    M::take_args4(&mut Cursor4::new(args))
}

/// The call `m` as 4.0 writes it.
pub fn request<M: Method>(m: &M) -> Vec<u8> {
    let mut w = WireWriter::for_generation(Generation::V4);
    w.list_header(1 + M::ARGS4)
        .string(M::V4.unwrap_or_default());
    m.put_args4(&mut w);
    w.into_bytes()
}

/// What a 4.0 reply to `M` says: its return value, and the value asked when it is `ok`.
pub fn answer<M: Method>(reply: &Bottle) -> Option<(ReturnValue, Option<M::Reply>)> {
    answer4::<M::Reply>(reply)
}

/// The `getDeviceInterfacesRPC` call.
pub fn interfaces_request() -> Vec<u8> {
    let mut w = WireWriter::for_generation(Generation::V4);
    w.list_header(1).string("getDeviceInterfacesRPC");
    w.into_bytes()
}

/// Whether a reply of a `return_*` struct starts with an `ok` return value.
pub fn returned_ok(reply: &Bottle) -> bool {
    reply
        .get(0)
        .and_then(Value::as_list)
        .and_then(|rv| rv.get(0)?.as_vocab())
        == Some(ReturnValue::Ok.vocab())
}

/// The interfaces `getDeviceInterfacesRPC` reports, by C++'s key (sorted, as C++'s
/// `std::map` sends them), and whether `dev` offers each.
fn interfaces(dev: &mut dyn DeviceDriver) -> Vec<(&'static str, bool)> {
    let mut v = vec![
        ("iAmplifierControl", dev.as_amplifier_control().is_some()),
        ("iAxisInfo", dev.as_axis_info().is_some()),
        (
            "iControlCalibration",
            dev.as_control_calibration().is_some(),
        ),
        ("iControlLimits", dev.as_control_limits().is_some()),
        ("iControlMode", dev.as_control_mode().is_some()),
        ("iCurrentControl", dev.as_current_control().is_some()),
        ("iEncodersTimed", dev.as_encoders().is_some()),
        ("iImpedanceControl", dev.as_impedance_control().is_some()),
        ("iInteractionMode", dev.as_interaction_mode().is_some()),
        ("iJointBrake", dev.as_joint_brake().is_some()),
        // 4.0's IJointFault: not in our framework yet
        ("iJointFault", dev.as_joint_fault().is_some()),
        ("iMotor", dev.as_motor().is_some()),
        ("iMotorEncoders", dev.as_motor_encoders().is_some()),
        ("iPidControl", dev.as_pid_control().is_some()),
        ("iPositionControl", dev.as_position_control().is_some()),
        ("iPositionDirect", dev.as_position_direct().is_some()),
        // no IPreciselyTimed view in our framework (C++'s fake has none either)
        ("iPreciselyTimed", false),
        ("iPWMControl", dev.as_pwm_control().is_some()),
        ("iRemoteCalibrator", dev.as_remote_calibrator().is_some()),
        ("iRemoteVariables", dev.as_remote_variables().is_some()),
        ("iTorqueControl", dev.as_torque_control().is_some()),
        ("iVelocityControl", dev.as_velocity_control().is_some()),
        ("iVelocityDirect", dev.as_velocity_direct().is_some()),
    ];
    v.sort_by_key(|(k, _)| *k);
    v
}

/// Serves one 4.0 call (a Bottle decoded from its bytes, or typed at a prompt) on `dev`
/// and returns the reply's bytes.
pub fn handle_rpc(cmd: &Bottle, dev: &mut dyn DeviceDriver) -> Vec<u8> {
    let Some(name) = cmd.get(0).and_then(Value::as_str) else {
        return fail_reply();
    };
    let args = &cmd.items()[1..];
    match name {
        "getRemoteProtocolVersion" => return protocol_version_reply(Generation::V4),
        "getDeviceInterfacesRPC" => {
            let ifaces = interfaces(dev);
            let mut w = WireWriter::for_generation(Generation::V4);
            w.list_header(2);
            ReturnValue::Ok.put(&mut w);
            w.list_header(ifaces.len());
            for (k, has) in ifaces {
                w.list_header(2).string(k).bool(has);
            }
            return w.into_bytes();
        }
        "help" => {
            let mut w = WireWriter::for_generation(Generation::V4);
            let names = Request::V4_NAMES;
            w.list_header(2).vocab(Vocab32::new("many"));
            w.list_header(names.len() + 2)
                .string("*** Available commands:");
            for n in names {
                w.string(n);
            }
            w.string("help");
            return w.into_bytes();
        }
        _ => {}
    }
    match Request::from_v4(name, args) {
        Some(req) => req.serve_v4(dev),
        None => {
            tracing::warn!("controlBoard_nws_yarp (4.0): `{cmd}` is no call of ControlBoardMsgs (unknown, malformed or not served yet): replying [fail]");
            fail_reply()
        }
    }
}
