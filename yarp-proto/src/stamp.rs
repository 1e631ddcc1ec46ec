//! Envelopes: the `Stamp` (sequence count + time) that streaming ports attach to messages.
//!
//! On tcp-family carriers C++ YARP sends the envelope as port-command text `D <count> <time>`
//! (the text form of a Bottle `count time`, time with 15 significant digits).

use crate::number;
use crate::value::{Bottle, Value};

/// Seconds since the Unix epoch on the system clock: C++ `yarp::os::Time::now()`, the time
/// envelopes carry (0 on a clock set before 1970).
pub fn now() -> f64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0.0, |d| d.as_secs_f64())
}

/// A YARP `Stamp`: sequence number and timestamp in seconds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stamp {
    pub count: i32,
    pub time: f64,
}

impl Stamp {
    pub fn new(count: i32, time: f64) -> Stamp {
        Stamp { count, time }
    }

    /// The envelope's text as it travels (`3092 1795297706.58327`).
    pub fn to_text(&self) -> String {
        format!("{} {}", self.count, format_stamp_time(self.time))
    }

    /// Reads `count time` text (also accepts the Bottle form `count time` with extra spaces).
    pub fn from_text(text: &str) -> Option<Stamp> {
        Stamp::from_bottle(&Bottle::from_text(text))
    }

    /// The Stamp as a Bottle `(int32 count, float64 time)`, its Portable form.
    pub fn to_bottle(&self) -> Bottle {
        let mut b = Bottle::new();
        b.push(self.count).push(self.time);
        b
    }

    pub fn from_bottle(b: &Bottle) -> Option<Stamp> {
        let count = b.get(0).filter(|v| v.is_int())?.as_i32()?;
        let time = b.get(1).and_then(Value::as_f64)?;
        Some(Stamp { count, time })
    }
}

/// Time as C++ prints it in envelopes (`%.15g`, no forced `.0`).
fn format_stamp_time(t: f64) -> String {
    number::format_g(t, 15)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn envelope_text() {
        let s = Stamp::new(3092, 1795297706.58327);
        assert_eq!(s.to_text(), "3092 1795297706.58327");
        assert_eq!(Stamp::from_text("3092 1795297706.58327"), Some(s));
    }
}
