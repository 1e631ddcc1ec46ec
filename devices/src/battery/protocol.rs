//! The wire forms of `battery_nws_yarp` (C++ YARP 3.12 and 4.0), pure:
//!
//! - the stream on `<name>/data:o`, a `yarp::dev::BatteryData` (`BatteryData.thrift`):
//!   `(charge voltage current temperature status)`, four float64 and the
//!   `IBattery::Battery_status` as int32;
//! - the `IBatteryMsgs` thrift service on `<name>/rpc:i`, one method, `getBatteryInfoRPC`,
//!   answered `(return_code info)` (`return_get_BatteryInfo`: a `yarp::dev::ReturnValue`,
//!   then the string), and the `getRemoteProtocolVersion` of every service.
//!
//! 4.0 kept both but renumbered the float tags and re-laid `ReturnValue`
//! (`crate::thrift`): each peer gets its generation's bytes.

use super::{BatteryStatus, IBattery};
use crate::error::DeviceError;
use crate::sensors::wire::WireWriter;
use crate::thrift::{fail_reply, is_protocol_version_request, protocol_version_reply, ReturnValue};
use thiserror::Error;
use yarp_proto::tags::Generation;
use yarp_proto::{Bottle, Value};

/// C++ `yarp::dev::BatteryData`.
#[derive(Debug, Clone, PartialEq)]
pub struct BatteryData {
    /// Percent, 0-100.
    pub charge: f64,
    pub voltage: f64,
    pub current: f64,
    /// Degrees Celsius.
    pub temperature: f64,
    /// An `IBattery::Battery_status` as int32 (the thrift default is 3).
    pub status: i32,
}

/// A stream message that is not a `BatteryData`.
#[derive(Debug, Clone, PartialEq, Error)]
#[error("not a BatteryData: {0}")]
pub struct BatteryDataError(&'static str);

impl BatteryData {
    /// The message bytes as C++'s `BufferedPort<BatteryData>` of `generation` writes them.
    pub fn encode(&self, generation: Generation) -> Vec<u8> {
        let mut w = WireWriter::for_generation(generation);
        w.list_header(5)
            .float64(self.charge)
            .float64(self.voltage)
            .float64(self.current)
            .float64(self.temperature)
            .int32(self.status);
        w.into_bytes()
    }

    /// The same message as a Bottle (the same bytes as [`Self::encode`]).
    pub fn to_bottle(&self) -> Bottle {
        Bottle::new()
            .with(self.charge)
            .with(self.voltage)
            .with(self.current)
            .with(self.temperature)
            .with(self.status)
    }

    pub fn from_bottle(b: &Bottle) -> Result<BatteryData, BatteryDataError> {
        if b.len() != 5 {
            return Err(BatteryDataError("expected 5 elements"));
        }
        let num = |i: usize| {
            b.get(i)
                .filter(|v| v.is_float() || v.is_int())
                .and_then(Value::as_f64)
                .ok_or(BatteryDataError(
                    "charge, voltage, current and temperature must be numbers",
                ))
        };
        let status = b
            .get(4)
            .and_then(Value::as_i32)
            .ok_or(BatteryDataError("status must be an int32"))?;
        Ok(BatteryData {
            charge: num(0)?,
            voltage: num(1)?,
            current: num(2)?,
            temperature: num(3)?,
            status,
        })
    }
}

/// Reads every value of `dev` as C++'s periodic `run` does: a getter that fails keeps
/// the previous value (`last`), and the message goes out only when the status was read.
pub fn read_battery(
    dev: &mut dyn IBattery,
    last: &BatteryData,
) -> Result<BatteryData, DeviceError> {
    let status = dev.get_battery_status()?;
    Ok(BatteryData {
        charge: dev.get_battery_charge().unwrap_or(last.charge),
        voltage: dev.get_battery_voltage().unwrap_or(last.voltage),
        current: dev.get_battery_current().unwrap_or(last.current),
        temperature: dev.get_battery_temperature().unwrap_or(last.temperature),
        status: status as i32,
    })
}

impl Default for BatteryData {
    /// C++'s initial values: NaN everywhere, status `BATTERY_TIMEOUT`.
    fn default() -> Self {
        BatteryData {
            charge: f64::NAN,
            voltage: f64::NAN,
            current: f64::NAN,
            temperature: f64::NAN,
            status: BatteryStatus::Timeout as i32,
        }
    }
}

/// The one method of `IBatteryMsgs`.
const GET_INFO: &str = "getBatteryInfoRPC";

/// Answers one request of a client of `generation` on `dev` (`None`: no device
/// attached, `return_value_error_not_ready`).
pub fn handle_rpc(cmd: &Bottle, dev: Option<&mut dyn IBattery>, generation: Generation) -> Vec<u8> {
    if is_protocol_version_request(cmd) {
        return protocol_version_reply(generation);
    }
    let mut items = cmd.iter().peekable();
    if items.peek().and_then(|v| v.as_str()) == Some("__direct__") {
        items.next();
    }
    let method = items.next().and_then(|v| match v {
        Value::String(_) => v.as_str().map(str::to_string),
        Value::Vocab32(v) => Some(v.as_string()),
        _ => None,
    });
    if method.as_deref() != Some(GET_INFO) || items.next().is_some() {
        return fail_reply();
    }
    let (ret, info) = match dev.map(|d| d.get_battery_info()) {
        None => (ReturnValue::NotReady, String::new()),
        Some(Ok(info)) => (ReturnValue::Ok, info),
        Some(Err(e)) => {
            tracing::error!("battery_nws_yarp: could not retrieve the battery info: {e}");
            (ReturnValue::of(&e), String::new())
        }
    };
    let mut w = WireWriter::for_generation(generation);
    w.list_header(2);
    ret.put(&mut w);
    w.string(&info);
    w.into_bytes()
}

/// C++'s low-charge warnings (`check_battery_status`): each threshold (15, 12, 10 and 5 %)
/// warns once until the charge is above 20 % again. Checked only while the battery is
/// not in standby, as C++ does.
#[derive(Debug)]
pub struct ChargeWarnings {
    armed: [bool; 4],
}

impl Default for ChargeWarnings {
    fn default() -> Self {
        ChargeWarnings { armed: [true; 4] }
    }
}

impl ChargeWarnings {
    /// The warning to give for `charge` (%), if one is due now.
    pub fn check(&mut self, charge: f64) -> Option<&'static str> {
        if charge > 20.0 {
            self.armed = [true; 4];
        }
        let (i, msg) = if charge < 5.0 {
            (
                3,
                "CRITICAL WARNING: battery charge reached critical level 5%, but the emergency shutdown is currently disabled!",
            )
        } else if charge < 10.0 {
            (2, "WARNING: battery charge below 10%")
        } else if charge < 12.0 {
            (1, "WARNING: battery charge below 12%")
        } else if charge < 15.0 {
            (0, "WARNING: battery charge below 15%")
        } else {
            return None;
        };
        std::mem::replace(&mut self.armed[i], false).then_some(msg)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::battery::fake::FakeBattery;
    use crate::DeviceDriver;
    use yarp_proto::Property;

    #[test]
    fn data_bytes_match_the_bottle_and_decode_back() {
        let d = BatteryData {
            charge: 85.0,
            voltage: 48.3,
            current: 2.5,
            temperature: 25.0,
            status: 2,
        };
        let bytes = d.encode(Generation::V3);
        assert_eq!(
            d.encode(Generation::V4),
            d.to_bottle().encode_as(Generation::V4)
        );
        assert_eq!(bytes, d.to_bottle().encode());
        // list tag (BOTTLE_TAG_LIST = 256), 5 elements, then tagged float64 (0x0a = 10)
        assert_eq!(&bytes[..8], &[0, 1, 0, 0, 5, 0, 0, 0]);
        assert_eq!(&bytes[8..12], &[10, 0, 0, 0]);
        assert_eq!(BatteryData::from_bottle(&d.to_bottle()).unwrap(), d);
        assert!(BatteryData::from_bottle(&Bottle::from_text("1 2 3")).is_err());
        assert!(BatteryData::from_bottle(&Bottle::from_text("1 2 3 4 x")).is_err());
    }

    #[test]
    fn info_rpc_with_and_without_a_device() {
        let mut b = FakeBattery::new();
        b.open(&Property::new()).unwrap();
        let ask = |text: &str, dev: Option<&mut dyn IBattery>| {
            Bottle::decode(&handle_rpc(&Bottle::from_text(text), dev, Generation::V3)).unwrap()
        };
        let r = ask("getBatteryInfoRPC", Some(&mut b));
        assert_eq!(r.get(0).and_then(Value::as_i32), Some(0));
        assert_eq!(
            r.get(1).and_then(Value::as_str),
            Some("Fake battery system v2.0")
        );
        let r = ask("getBatteryInfoRPC", None);
        assert_eq!(r.get(0).and_then(Value::as_i32), Some(6));
        for bad in [
            "",
            "getBatteryInfo",
            "getBatteryInfoRPC 1",
            "getRemoteProtocolVersion 1",
            "12",
        ] {
            assert_eq!(ask(bad, Some(&mut b)).to_string(), "[fail]", "{bad}");
        }
        for dev in [Some(&mut b as &mut dyn IBattery), None] {
            assert_eq!(
                handle_rpc(
                    &Bottle::from_text("getRemoteProtocolVersion"),
                    dev,
                    Generation::V4
                ),
                protocol_version_reply(Generation::V4)
            );
        }
    }

    #[test]
    fn each_low_charge_warning_once_until_recharged() {
        let mut w = ChargeWarnings::default();
        assert_eq!(w.check(50.0), None);
        assert_eq!(w.check(14.0), Some("WARNING: battery charge below 15%"));
        assert_eq!(w.check(13.0), None);
        assert_eq!(w.check(11.0), Some("WARNING: battery charge below 12%"));
        assert_eq!(w.check(9.0), Some("WARNING: battery charge below 10%"));
        assert!(w.check(4.0).unwrap().starts_with("CRITICAL"));
        assert_eq!(w.check(3.0), None);
        assert_eq!(w.check(21.0), None);
        assert_eq!(w.check(14.0), Some("WARNING: battery charge below 15%"));
    }
}
