//! Per-mapping counters and their `diagnostic_msgs/DiagnosticArray` form (pure).

use crate::dynmsg::Value as Ros;
use parking_lot::Mutex;
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};
use std::time::Duration;

/// Live counters of one mapping, updated lock-free by its bridge task.
#[derive(Debug, Default)]
pub struct Counters {
    messages: AtomicU64,
    drops: AtomicU64,
    latency_ns_total: AtomicU64,
    latency_ns_max: AtomicU64,
    /// Why the last message was not forwarded or applied (until one is again).
    problem: Mutex<Option<String>>,
}

/// A copy of [`Counters`] at one moment.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Snapshot {
    /// Messages forwarded.
    pub messages: u64,
    /// Messages not forwarded (conversion errors, rate limit, write failures).
    pub drops: u64,
    /// Mean time inside the gateway per forwarded message (receive to send).
    pub latency_mean: Duration,
    pub latency_max: Duration,
}

impl Counters {
    /// Counts one forwarded message that spent `latency` inside the gateway.
    pub fn forwarded(&self, latency: Duration) {
        let ns = latency.as_nanos().min(u64::MAX as u128) as u64;
        self.messages.fetch_add(1, Relaxed);
        self.latency_ns_total.fetch_add(ns, Relaxed);
        self.latency_ns_max.fetch_max(ns, Relaxed);
    }

    pub fn dropped(&self) {
        self.drops.fetch_add(1, Relaxed);
    }

    /// Counts a drop and keeps `why` for the diagnostics (e.g. why a command was refused).
    pub fn refused(&self, why: impl Into<String>) {
        self.dropped();
        *self.problem.lock() = Some(why.into());
    }

    /// Counts a success that clears the last problem (the bridge works again).
    pub fn applied(&self, latency: Duration) {
        self.forwarded(latency);
        *self.problem.lock() = None;
    }

    /// The reason kept by the last [`Counters::refused`], if nothing succeeded since.
    pub fn problem(&self) -> Option<String> {
        self.problem.lock().clone()
    }

    pub fn snapshot(&self) -> Snapshot {
        let messages = self.messages.load(Relaxed);
        let total = self.latency_ns_total.load(Relaxed);
        Snapshot {
            messages,
            drops: self.drops.load(Relaxed),
            latency_mean: Duration::from_nanos(total.checked_div(messages).unwrap_or(0)),
            latency_max: Duration::from_nanos(self.latency_ns_max.load(Relaxed)),
        }
    }
}

/// Rate limiting: lets a message through when at least `1/hz` passed since the last one.
#[derive(Debug, Clone)]
pub struct RateLimit {
    min_gap: Duration,
    last: Option<std::time::Instant>,
}

impl RateLimit {
    pub fn new(hz: f64) -> RateLimit {
        RateLimit {
            min_gap: Duration::from_secs_f64(1.0 / hz),
            last: None,
        }
    }

    /// Whether a message arriving `now` may pass (and records it when it does).
    pub fn admit(&mut self, now: std::time::Instant) -> bool {
        match self.last {
            Some(l) if now.duration_since(l) < self.min_gap => false,
            _ => {
                self.last = Some(now);
                true
            }
        }
    }
}

/// One mapping's row in the diagnostics.
#[derive(Debug, Clone)]
pub struct Row {
    pub name: String,
    /// e.g. `yarp->ros /counter:o -> /counter`.
    pub route: String,
    pub snapshot: Snapshot,
    /// Why the last message was not applied, while that is still so.
    pub problem: Option<String>,
}

/// A `diagnostic_msgs/msg/DiagnosticArray` with one OK status per mapping (WARN when it
/// dropped messages), stamped `stamp_ns` nanoseconds after the epoch. A mapping whose last
/// message was not applied says why in its `message` (after the route) and in the value
/// `last_problem`.
pub fn diagnostic_array(stamp_ns: u64, hardware_id: &str, rows: &[Row]) -> Ros {
    let kv = |k: &str, v: String| Ros::Struct(vec![Ros::Str(k.into()), Ros::Str(v)]);
    let statuses = rows
        .iter()
        .map(|r| {
            let s = r.snapshot;
            let level = if s.drops > 0 { 1 } else { 0 };
            let mut values = vec![
                kv("messages", s.messages.to_string()),
                kv("drops", s.drops.to_string()),
                kv(
                    "latency_mean_us",
                    format!("{:.1}", s.latency_mean.as_secs_f64() * 1e6),
                ),
                kv(
                    "latency_max_us",
                    format!("{:.1}", s.latency_max.as_secs_f64() * 1e6),
                ),
            ];
            let mut message = r.route.clone();
            if let Some(p) = &r.problem {
                message = format!("{message}; last message not applied: {p}");
                values.push(kv("last_problem", p.clone()));
            }
            Ros::Struct(vec![
                Ros::U8(level),
                Ros::Str(format!("yarp-ros2-gateway: {}", r.name)),
                Ros::Str(message),
                Ros::Str(hardware_id.into()),
                Ros::List(values),
            ])
        })
        .collect();
    Ros::Struct(vec![header(stamp_ns, ""), Ros::List(statuses)])
}

/// A `std_msgs/msg/Header` value.
pub fn header(stamp_ns: u64, frame_id: &str) -> Ros {
    Ros::Struct(vec![Ros::time(stamp_ns), Ros::Str(frame_id.into())])
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Instant;

    #[test]
    fn counts_and_latency() {
        let c = Counters::default();
        assert_eq!(c.snapshot(), Snapshot::default());
        c.forwarded(Duration::from_micros(10));
        c.forwarded(Duration::from_micros(30));
        c.dropped();
        let s = c.snapshot();
        assert_eq!((s.messages, s.drops), (2, 1));
        assert_eq!(s.latency_mean, Duration::from_micros(20));
        assert_eq!(s.latency_max, Duration::from_micros(30));
        assert_eq!(c.problem(), None);
        c.refused("no board");
        assert_eq!(
            (c.snapshot().drops, c.problem().as_deref()),
            (2, Some("no board"))
        );
        c.applied(Duration::from_micros(20));
        assert_eq!(c.problem(), None);
    }

    #[test]
    fn rate_limit_admits_one_per_period() {
        let mut r = RateLimit::new(10.0);
        let t0 = Instant::now();
        assert!(r.admit(t0));
        assert!(!r.admit(t0 + Duration::from_millis(50)));
        assert!(r.admit(t0 + Duration::from_millis(100)));
        assert!(!r.admit(t0 + Duration::from_millis(150)));
    }

    #[test]
    fn diagnostics_have_the_ros_layout() {
        let rows = [
            Row {
                name: "a".into(),
                route: "yarp->ros /a -> /a".into(),
                snapshot: Snapshot {
                    messages: 3,
                    ..Default::default()
                },
                problem: None,
            },
            Row {
                name: "b".into(),
                route: "ros->yarp /b -> /b".into(),
                snapshot: Snapshot {
                    drops: 1,
                    ..Default::default()
                },
                problem: Some("the board refused it".into()),
            },
        ];
        let m = diagnostic_array(1_500_000_000, "host", &rows);
        assert!(m.conforms_to("diagnostic_msgs/msg/DiagnosticArray"));
        let Some([hdr, Ros::List(st)]) = m.fields() else {
            panic!("layout")
        };
        assert_eq!(
            hdr.fields().unwrap()[0],
            Ros::Struct(vec![Ros::I32(1), Ros::U32(500_000_000)])
        );
        assert_eq!(st[0].fields().unwrap()[0], Ros::U8(0));
        assert_eq!(st[1].fields().unwrap()[0], Ros::U8(1));
        assert_eq!(
            st[1].fields().unwrap()[2],
            Ros::Str("ros->yarp /b -> /b; last message not applied: the board refused it".into())
        );
    }
}
