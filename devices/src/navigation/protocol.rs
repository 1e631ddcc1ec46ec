//! The wire of C++ YARP's `odometry2D_nws_yarp`/`odometry2D_nwc_yarp` (3.12 and 4.0 alike):
//! `yarp::dev::OdometryData` (a thrift struct of nine float64) on `<name>/odometry:o`, two
//! Bottles of two float64 on `<name>/odometer:o` and `<name>/velocity:o`, and the one
//! method of `IOdometry2DMsgs` on `<name>/rpc`, `reset_odometry_RPC`, whose reply is its
//! `ReturnValue` alone.

use super::{IOdometry2D, OdometryData};
use crate::thrift::{
    fail_reply, is_protocol_version_request, protocol_version_reply, word, ReturnValue,
};
use yarp_proto::tags::Generation;
use yarp_proto::{Bottle, Value};

/// A stream message that is not an `OdometryData` (nine float64).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("not an OdometryData (nine float64): {0}")]
pub struct OdometryDataError(pub Bottle);

/// The one method of C++ `IOdometry2DMsgs`.
pub const RESET: &str = "reset_odometry_RPC";

impl OdometryData {
    /// The struct's nine fields in thrift order, as a Bottle (C++'s `WireReader` reads
    /// the compact list a Bottle of float64 makes as it reads its own tagged one).
    pub fn to_bottle(&self) -> Bottle {
        Bottle::from(
            self.fields()
                .into_iter()
                .map(Value::Float64)
                .collect::<Vec<_>>(),
        )
    }

    fn fields(&self) -> [f64; 9] {
        [
            self.odom_x,
            self.odom_y,
            self.odom_theta,
            self.base_vel_x,
            self.base_vel_y,
            self.base_vel_theta,
            self.odom_vel_x,
            self.odom_vel_y,
            self.odom_vel_theta,
        ]
    }

    /// Reads the struct from a stream message (nine numbers).
    pub fn from_bottle(b: &Bottle) -> Result<OdometryData, OdometryDataError> {
        let v: Vec<f64> = b.iter().filter_map(Value::as_f64).collect();
        let [odom_x, odom_y, odom_theta, base_vel_x, base_vel_y, base_vel_theta, odom_vel_x, odom_vel_y, odom_vel_theta] =
            <[f64; 9]>::try_from(v.as_slice())
                .ok()
                .filter(|_| b.len() == 9)
                .ok_or_else(|| OdometryDataError(b.clone()))?;
        Ok(OdometryData {
            odom_x,
            odom_y,
            odom_theta,
            base_vel_x,
            base_vel_y,
            base_vel_theta,
            odom_vel_x,
            odom_vel_y,
            odom_vel_theta,
        })
    }
}

/// `<name>/odometer:o` as C++ 3.12 and 4.0 compute it: the distance from the odometry
/// *velocity* to the pose C++ remembers as the old one (which it never updates from its
/// zero start), and the heading from that same zero. Kept as C++ writes it: a reader of
/// a C++ robot reads these numbers.
pub fn odometer(d: &OdometryData) -> Bottle {
    let old = OdometryData::default();
    let distance =
        ((d.odom_vel_x - old.odom_x).powi(2) + (d.odom_vel_y - old.odom_y).powi(2)).sqrt();
    Bottle::new()
        .with(distance)
        .with(d.odom_theta - old.odom_theta)
}

/// `<name>/velocity:o`: the speed in the odometry frame and the base's turn rate.
pub fn velocity(d: &OdometryData) -> Bottle {
    Bottle::new()
        .with(d.odom_vel_x.hypot(d.odom_vel_y))
        .with(d.base_vel_theta)
}

/// Whether `cmd` is `reset_odometry_RPC` (its words joined by `_`, as C++'s reader joins
/// them: `reset odometry RPC` is the same call), optionally behind `__direct__`.
fn is_reset(cmd: &Bottle) -> bool {
    let mut words: Vec<String> = match cmd.iter().map(word).collect::<Option<_>>() {
        Some(w) => w,
        None => return false,
    };
    if words.first().map(String::as_str) == Some("__direct__") {
        words.remove(0);
    }
    words.join("_") == RESET
}

/// Answers one request of a client of `generation` (`None`: nothing attached, C++ fails
/// the read).
pub fn handle_rpc(
    cmd: &Bottle,
    dev: Option<&mut dyn IOdometry2D>,
    generation: Generation,
) -> Vec<u8> {
    if is_protocol_version_request(cmd) {
        return protocol_version_reply(generation);
    }
    let Some(dev) = dev else {
        return fail_reply();
    };
    if !is_reset(cmd) {
        return fail_reply();
    }
    let ret = match dev.reset_odometry() {
        Ok(()) => ReturnValue::Ok,
        Err(e) => {
            tracing::error!("odometry2D_nws_yarp: Unable to resetOdometry: {e}");
            ReturnValue::of(&e)
        }
    };
    ret.bare(generation)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::DevResult;

    struct Odom(OdometryData, u32);
    impl IOdometry2D for Odom {
        fn get_odometry(&mut self) -> DevResult<(OdometryData, f64)> {
            Ok((self.0, 1.0))
        }
        fn reset_odometry(&mut self) -> DevResult<()> {
            self.1 += 1;
            self.0 = OdometryData::default();
            Ok(())
        }
    }

    fn data() -> OdometryData {
        OdometryData {
            odom_x: 1.0,
            odom_y: 2.0,
            odom_theta: 30.0,
            base_vel_x: 0.5,
            base_vel_y: 0.0,
            base_vel_theta: 10.0,
            odom_vel_x: 3.0,
            odom_vel_y: 4.0,
            odom_vel_theta: 10.0,
        }
    }

    #[test]
    fn struct_round_trip_and_streams() {
        let d = data();
        assert_eq!(OdometryData::from_bottle(&d.to_bottle()), Ok(d));
        assert!(OdometryData::from_bottle(&Bottle::from_text("1 2 3")).is_err());
        // C++'s odometer: |odom_vel| from a zero "old" pose, theta from zero
        assert_eq!(odometer(&d).to_string(), "5.0 30.0");
        assert_eq!(velocity(&d).to_string(), "5.0 10.0");
    }

    #[test]
    fn reset_in_words_or_joined_and_bad_calls() {
        let mut o = Odom(data(), 0);
        for text in [
            "reset odometry RPC",
            "reset_odometry_RPC",
            "__direct__ reset odometry RPC",
        ] {
            let reply = handle_rpc(&Bottle::from_text(text), Some(&mut o), Generation::V3);
            assert_eq!(
                ReturnValue::from_bare(&reply),
                Some(ReturnValue::Ok),
                "{text}"
            );
        }
        assert_eq!(o.1, 3);
        let v4 = handle_rpc(
            &Bottle::from_text("reset odometry RPC"),
            Some(&mut o),
            Generation::V4,
        );
        assert_eq!(ReturnValue::from_bare(&v4), Some(ReturnValue::Ok));
        for text in [
            "reset",
            "reset odometry",
            "get odometry RPC",
            "reset odometry RPC 1",
        ] {
            let reply = handle_rpc(&Bottle::from_text(text), Some(&mut o), Generation::V3);
            assert_eq!(reply, fail_reply(), "{text}");
        }
        assert_eq!(
            handle_rpc(
                &Bottle::from_text("reset odometry RPC"),
                None,
                Generation::V3
            ),
            fail_reply()
        );
    }
}
