//! The wire forms of `rangefinder2D_nws_yarp` (C++ YARP 3.12 and 4.0), pure:
//!
//! - the stream, a `yarp::sig::LaserScan2D` (`LaserScan2D.thrift`): `(angle_min angle_max
//!   range_min range_max (scans...) status)`, four tagged float64, the scans as a
//!   `yarp::sig::Vector` (compact float64 list) and the status as int32;
//! - the `IRangefinder2DMsgs` thrift service on `<name>/rpc:i`: commands are the method
//!   name split at `_` (`getDistanceRange RPC`), replies a list whose first element is the
//!   `yarp::dev::ReturnValue` followed by the `return_*` struct's fields, or a setter's
//!   `ReturnValue` alone; and the `getRemoteProtocolVersion` of every service.
//!
//! YARP 4.0 kept the service and the scan but renumbered the float tags and re-laid
//! `ReturnValue` (see `crate::thrift`): each is written in the peer's generation.

use super::{IRangefinder2D, LaserStatus};
use crate::sensors::wire::WireWriter;
use crate::thrift::{
    is_protocol_version_request, protocol_version_reply, split_method, ReturnValue,
};
use thiserror::Error;
use yarp_proto::tags::Generation;
use yarp_proto::{Bottle, Value, Vocab32};

/// C++ `yarp::sig::LaserScan2D`.
#[derive(Debug, Clone, PartialEq)]
pub struct LaserScan2D {
    pub angle_min: f64,
    pub angle_max: f64,
    pub range_min: f64,
    pub range_max: f64,
    pub scans: Vec<f64>,
    /// An `IRangefinder2D::Device_status` (C++ default: 3, timeout).
    pub status: i32,
}

/// A stream message that is not a `LaserScan2D`.
#[derive(Debug, Clone, PartialEq, Error)]
#[error("not a LaserScan2D: {0}")]
pub struct ScanError(&'static str);

impl LaserScan2D {
    /// The message bytes as C++'s `BufferedPort<LaserScan2D>` of `generation` writes them.
    pub fn encode(&self, generation: Generation) -> Vec<u8> {
        let mut w = WireWriter::for_generation(generation);
        w.list_header(6)
            .float64(self.angle_min)
            .float64(self.angle_max)
            .float64(self.range_min)
            .float64(self.range_max)
            .float_vector(&self.scans)
            .int32(self.status);
        w.into_bytes()
    }

    /// The same message as a Bottle (what our ports write; a Bottle of these elements has
    /// the same bytes as [`Self::encode`] unless the scan is empty).
    pub fn to_bottle(&self) -> Bottle {
        let scans = Bottle::from(
            self.scans
                .iter()
                .map(|&d| Value::Float64(d))
                .collect::<Vec<_>>(),
        );
        Bottle::new()
            .with(self.angle_min)
            .with(self.angle_max)
            .with(self.range_min)
            .with(self.range_max)
            .with(Value::List(scans))
            .with(self.status)
    }

    pub fn from_bottle(b: &Bottle) -> Result<LaserScan2D, ScanError> {
        if b.len() != 6 {
            return Err(ScanError("expected 6 elements"));
        }
        let num = |i: usize| {
            b.get(i)
                .filter(|v| v.is_float() || v.is_int())
                .and_then(Value::as_f64)
                .ok_or(ScanError("angles and ranges must be numbers"))
        };
        let scans = b
            .get(4)
            .and_then(Value::as_list)
            .ok_or(ScanError("scans must be a list"))?
            .iter()
            .map(|v| v.as_f64().ok_or(ScanError("scans must be numbers")))
            .collect::<Result<Vec<_>, _>>()?;
        let status = b
            .get(5)
            .and_then(Value::as_i32)
            .ok_or(ScanError("status must be an int32"))?;
        Ok(LaserScan2D {
            angle_min: num(0)?,
            angle_max: num(1)?,
            range_min: num(2)?,
            range_max: num(3)?,
            scans,
            status,
        })
    }
}

/// The methods of `IRangefinder2DMsgs`, by thrift name.
const METHODS: &[&str] = &[
    "getDeviceStatus_RPC",
    "getDistanceRange_RPC",
    "getScanLimits_RPC",
    "getHorizontalResolution_RPC",
    "getScanRate_RPC",
    "getDeviceInfo_RPC",
    "setDistanceRange_RPC",
    "setScanLimits_RPC",
    "setHorizontalResolution_RPC",
    "setScanRate_RPC",
];

/// Splits a request into its method and arguments (see [`split_method`]).
pub fn parse_request(cmd: &Bottle) -> Option<(&'static str, Vec<f64>)> {
    let (m, rest) = split_method(cmd, METHODS)?;
    let args = rest.iter().map(Value::as_f64).collect::<Option<Vec<_>>>()?;
    let wanted = if m.starts_with("set") {
        if m.contains("Range") || m.contains("Limits") {
            2
        } else {
            1
        }
    } else {
        0
    };
    (args.len() == wanted).then_some((m, args))
}

/// Answers one request of a client of `generation` on `dev` (`None`: no device
/// attached, every method answers `return_value_error_not_ready`).
pub fn handle_rpc(
    cmd: &Bottle,
    dev: Option<&mut dyn IRangefinder2D>,
    generation: Generation,
) -> Vec<u8> {
    if is_protocol_version_request(cmd) {
        return protocol_version_reply(generation);
    }
    let Some((method, args)) = parse_request(cmd) else {
        return crate::thrift::fail_reply();
    };
    let head = |ret: ReturnValue| {
        let mut w = WireWriter::for_generation(generation);
        w.list_header(reply_len(method));
        ret.put(&mut w);
        w
    };
    let Some(dev) = dev else {
        if reply_len(method) == 1 {
            return ReturnValue::NotReady.bare(generation);
        }
        let mut w = head(ReturnValue::NotReady);
        default_fields(&mut w, method);
        return w.into_bytes();
    };
    let w = match method {
        "getDeviceStatus_RPC" => {
            let r = dev.get_device_status();
            let mut w = head(ReturnValue::of_result(&r));
            w.vocab(Vocab32(r.map_or(0, |s| s as i32)));
            w
        }
        "getDistanceRange_RPC" | "getScanLimits_RPC" => {
            let r = if method == "getDistanceRange_RPC" {
                dev.get_distance_range()
            } else {
                dev.get_scan_limits()
            };
            let mut w = head(ReturnValue::of_result(&r));
            let (min, max) = r.unwrap_or((0.0, 0.0));
            w.float64(min).float64(max);
            w
        }
        "getHorizontalResolution_RPC" | "getScanRate_RPC" => {
            let r = if method == "getScanRate_RPC" {
                dev.get_scan_rate()
            } else {
                dev.get_horizontal_resolution()
            };
            let mut w = head(ReturnValue::of_result(&r));
            w.float64(r.unwrap_or(0.0));
            w
        }
        "getDeviceInfo_RPC" => {
            let r = dev.get_device_info();
            let mut w = head(ReturnValue::of_result(&r));
            w.string(r.as_deref().unwrap_or(""));
            w
        }
        set => {
            let r = match set {
                "setDistanceRange_RPC" => dev.set_distance_range(args[0], args[1]),
                "setScanLimits_RPC" => dev.set_scan_limits(args[0], args[1]),
                "setHorizontalResolution_RPC" => dev.set_horizontal_resolution(args[0]),
                _ => dev.set_scan_rate(args[0]),
            };
            // a setter's reply is its ReturnValue alone, no list around it
            return ReturnValue::of_result(&r).bare(generation);
        }
    };
    w.into_bytes()
}

/// Elements of a method's reply (C++ `s_reply_len`).
fn reply_len(method: &str) -> usize {
    match method {
        "getDistanceRange_RPC" | "getScanLimits_RPC" => 3,
        m if m.starts_with("get") => 2,
        _ => 1,
    }
}

/// The default-valued fields of a `return_*` struct after its return code.
fn default_fields(w: &mut WireWriter, method: &str) {
    match method {
        "getDeviceStatus_RPC" => {
            w.vocab(Vocab32(0));
        }
        "getDistanceRange_RPC" | "getScanLimits_RPC" => {
            w.float64(0.0).float64(0.0);
        }
        "getHorizontalResolution_RPC" | "getScanRate_RPC" => {
            w.float64(0.0);
        }
        "getDeviceInfo_RPC" => {
            w.string("");
        }
        _ => {}
    }
}

/// The status a `getDeviceStatus_RPC` reply or a scan carries.
pub fn status_of(code: i32) -> Option<LaserStatus> {
    Some(match code {
        0 => LaserStatus::OkStandby,
        1 => LaserStatus::OkInUse,
        2 => LaserStatus::GeneralError,
        3 => LaserStatus::Timeout,
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rangefinder::fake::FakeLaser;
    use crate::DeviceDriver;
    use yarp_proto::Property;

    fn laser() -> FakeLaser {
        let mut l = FakeLaser::new();
        let cfg = "test use_constant\n[SENSOR]\nmin_distance 0.1\nmax_distance 30\nresolution 0.5\n[CONSTANT_MODE]\nconst_distance 2";
        l.open(&Property::from_config_text(cfg).unwrap()).unwrap();
        l
    }

    fn ask(text: &str, dev: Option<&mut dyn IRangefinder2D>) -> Bottle {
        Bottle::decode(&handle_rpc(&Bottle::from_text(text), dev, Generation::V3)).unwrap()
    }

    fn nums(b: &Bottle) -> Vec<f64> {
        b.iter().filter_map(Value::as_f64).collect()
    }

    #[test]
    fn scan_bytes_match_the_bottle() {
        let s = LaserScan2D {
            angle_min: 0.0,
            angle_max: 360.0,
            range_min: 0.1,
            range_max: 30.0,
            scans: vec![1.0, 2.5, f64::INFINITY],
            status: 1,
        };
        assert_eq!(s.encode(Generation::V3), s.to_bottle().encode());
        assert_eq!(
            s.encode(Generation::V4),
            s.to_bottle().encode_as(Generation::V4)
        );
        assert_eq!(LaserScan2D::from_bottle(&s.to_bottle()).unwrap(), s);
        assert!(LaserScan2D::from_bottle(&Bottle::from_text("1 2 3")).is_err());
    }

    #[test]
    fn getters_and_setters() {
        let mut l = laser();
        let r = ask("getDistanceRange RPC", Some(&mut l));
        assert_eq!(nums(&r), [0.0, 0.1, 30.0]);
        let r = ask("getScanLimits_RPC", Some(&mut l));
        assert_eq!(nums(&r), [0.0, 0.0, 360.0]);
        let r = ask("getHorizontalResolution RPC", Some(&mut l));
        assert_eq!(r.get(1).and_then(Value::as_f64), Some(0.5));
        let r = ask("getDeviceStatus RPC", Some(&mut l));
        assert_eq!(r.get(1).and_then(Value::as_vocab), Some(Vocab32(1)));
        let r = ask("getDeviceInfo RPC", Some(&mut l));
        assert_eq!(
            r.get(1).and_then(Value::as_str),
            Some("Fake Laser device for test/debugging")
        );
        let set =
            |l: &mut FakeLaser, g| handle_rpc(&Bottle::from_text("setScanRate RPC 25"), Some(l), g);
        // a setter's reply is its ReturnValue alone: 3.12's tag and code, no Bottle
        assert_eq!(set(&mut l, Generation::V3), [1, 0, 0, 0, 0, 0, 0, 0]);
        // 4.0's: a list of one vocab
        assert_eq!(
            set(&mut l, Generation::V4),
            ReturnValue::Ok.bare(Generation::V4)
        );
        let r = ask("getScanRate RPC", Some(&mut l));
        assert_eq!(r.get(1).and_then(Value::as_f64), Some(25.0));
        // 4.0's getter: its ReturnValue nested, its floats tagged 20
        let r = handle_rpc(
            &Bottle::from_text("getScanRate RPC"),
            Some(&mut l),
            Generation::V4,
        );
        let b = Bottle::decode(&r).unwrap();
        assert_eq!(b.to_string(), "([ok]) 25.0");
        // the ReturnValue is a mixed list of one tagged vocab (a Bottle would compact it)
        assert_eq!(
            r[..20],
            [0, 1, 0, 0, 2, 0, 0, 0, 0, 1, 0, 0, 1, 0, 0, 0, 9, 0, 0, 0]
        );
    }

    #[test]
    fn bad_requests_and_no_device() {
        let mut l = laser();
        for bad in [
            "",
            "getScanRate",
            "getScanRate RPC 1",
            "setScanRate RPC",
            "fly RPC",
            "12",
        ] {
            assert_eq!(ask(bad, Some(&mut l)).to_string(), "[fail]", "{bad}");
        }
        assert_eq!(nums(&ask("getDistanceRange RPC", None)), [6.0, 0.0, 0.0]);
        let set = handle_rpc(
            &Bottle::from_text("setScanRate RPC 2"),
            None,
            Generation::V3,
        );
        assert_eq!(ReturnValue::from_bare(&set), Some(ReturnValue::NotReady));
    }

    #[test]
    fn protocol_version_with_and_without_a_device() {
        let mut l = laser();
        let want = protocol_version_reply(Generation::V3);
        let ask = |text: &str, dev: Option<&mut dyn IRangefinder2D>| {
            handle_rpc(&Bottle::from_text(text), dev, Generation::V3)
        };
        assert_eq!(ask("getRemoteProtocolVersion", Some(&mut l)), want);
        assert_eq!(ask("__direct__ getRemoteProtocolVersion", None), want);
        assert_eq!(
            ask("getRemoteProtocolVersion 1", None),
            crate::thrift::fail_reply()
        );
    }
}
