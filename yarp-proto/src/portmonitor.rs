//! Port monitors: the `portmonitor` carrier modifier that transforms every message of a
//! connection, on the sending side (`+send.portmonitor`) or the receiving one
//! (`+recv.portmonitor`). C++ loads the monitor named by `+file.NAME` as a plug-in
//! (`+type.dll`) or a Lua script (`+type.lua`, 3.12's default); here the dll monitors
//! robots' files name are built in:
//!
//! - `depthimage_compression_zlib` (YARP's `src/portmonitors/depthimage_compression_zlib`):
//!   a float depth image travels as the Bottle `width height compressed_size raw_size
//!   {zlib of the raw rows}`;
//! - `bottle_compression_zlib` (YARP 3.12's `src/portmonitors/bottle_compression_zlib`):
//!   any message travels as `raw_size {zlib of its Bottle encoding}`;
//! - `throttleDown` (YARP 4.0): lets a message through only when more than `period_ms`
//!   (default 1000) have passed since the last one it let through (or since the
//!   connection was made); on the sender the others are not sent, on the receiver they
//!   are read and dropped;
//! - `stats_monitor` (YARP 4.0, sender side only): counts what the connection sends; the
//!   port layer publishes it every second as `yarp::stats::ConnectionStats` on
//!   `/stats_monitor<source><destination>/stats:o` (and the reverse name for replies),
//!   where 4.0's `yarpconnectionsstats` finds it. [`with_stats_monitor`] is what
//!   `YARP_CONNECTIONS_STATS_ENABLE=1` does to a connection's carrier.
//!
//! Monitors chain as in YARP 4.0: `file`/`type`, then `file1`/`type1`, `file2`/`type2`...,
//! each passing its output to the next; only the first may drop a message (4.0 asks the
//! first monitor's `accept` only). Each side reads its own qualifiers, as 4.0 does (the
//! sender's follow `+send.portmonitor`, up to `+recv.portmonitor`; the receiver's follow
//! `+recv.portmonitor`), and what its part lacks from the whole name, as 3.12 does (3.12
//! mixed both sides: robots' files such as ergoCub's name `type.dll` once, at the end).
//! Sans-I/O: Bottles in, Bottles out.

use crate::image::{Image, PixelCode};
use crate::wire::modifiers::CarrierName;
use crate::Bottle;
use std::io::{Read, Write};
use std::time::{Duration, Instant};

/// Which end of the connection a monitor runs at.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// The output port: the monitor changes what is sent (`sender_side`).
    Sender,
    /// The input port: the monitor changes what is received (`receiver_side`).
    Receiver,
}

/// The monitors built into this crate.
pub const BUILT_IN: &[&str] = &[
    "depthimage_compression_zlib",
    "bottle_compression_zlib",
    "throttleDown",
    "stats_monitor",
];

/// Why a monitor cannot be set up, or refused a message.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum MonitorError {
    #[error("carrier modifier `{0}` is not available (only `portmonitor` is)")]
    UnknownModifier(String),
    #[error(
        "portmonitor of type `{0}`: only `dll` monitors are supported here (Lua scripts are not)"
    )]
    UnsupportedType(String),
    #[error("portmonitor `{0}` is not built in (built in: {list})", list = BUILT_IN.join(", "))]
    UnknownMonitor(String),
    #[error("{monitor}: {reason}")]
    Refused {
        monitor: &'static str,
        reason: String,
    },
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    DepthImageZlib,
    BottleZlib,
    ThrottleDown,
    Stats,
}

impl Kind {
    fn name(self) -> &'static str {
        match self {
            Kind::DepthImageZlib => "depthimage_compression_zlib",
            Kind::BottleZlib => "bottle_compression_zlib",
            Kind::ThrottleDown => "throttleDown",
            Kind::Stats => "stats_monitor",
        }
    }
}

/// What a `stats_monitor` counted since it was last read (messages and their bytes).
#[derive(Debug, Default)]
pub struct StatsCounter {
    count: std::sync::atomic::AtomicU64,
    bytes: std::sync::atomic::AtomicU64,
}

impl StatsCounter {
    fn add(&self, bytes: usize) {
        use std::sync::atomic::Ordering::Relaxed;
        self.count.fetch_add(1, Relaxed);
        self.bytes.fetch_add(bytes as u64, Relaxed);
    }

    /// The messages and bytes counted since the last call.
    pub fn take(&self) -> (u64, u64) {
        use std::sync::atomic::Ordering::Relaxed;
        (self.count.swap(0, Relaxed), self.bytes.swap(0, Relaxed))
    }
}

/// `yarp::stats::ConnectionStats` (YARP 4.0's `YarpStatsMsgs.thrift`) as the monitor
/// writes it each `period` seconds: `timestamp source destination carrier [ok|fail]
/// bytes_per_second frequency` (`[ok]`: the forward direction).
pub fn connection_stats(
    timestamp: f64,
    (source, destination, carrier): (&str, &str, &str),
    forward: bool,
    (count, bytes): (u64, u64),
    period: f64,
) -> Bottle {
    let mut b = Bottle::with_capacity(7);
    b.push(timestamp)
        .push(source)
        .push(destination)
        .push(carrier)
        .push(crate::Vocab32::new(if forward { "ok" } else { "fail" }))
        .push(bytes as f64 / period)
        .push(count as f64 / period);
    b
}

/// The carrier YARP 4.0's `YARP_CONNECTIONS_STATS_ENABLE=1` gives a connection `source`
/// -> `destination` (C++ `addStatsMonitorIfNeeded`): a `stats_monitor` on the sender,
/// chained after an existing monitor (`+fileN.stats_monitor+typeN.dll`) or as the first
/// (`+send.portmonitor+file.stats_monitor+type.dll`); logger and stats connections are
/// left as they are.
pub fn with_stats_monitor(source: &str, destination: &str, carrier: &str) -> String {
    let both = |a: &str, b: &str| {
        [source, destination]
            .iter()
            .all(|p| p.contains(a) && p.contains(b))
    };
    if carrier.is_empty()
        || both("/log", "/logger")
        || both("/stats_monitor", "/yarpConnectionsStats")
    {
        return carrier.to_string();
    }
    if carrier.contains("portmonitor") {
        let n = (1..)
            .find(|i| !carrier.contains(&format!("file{i}.")))
            .unwrap_or(1);
        format!("{carrier}+file{n}.stats_monitor+type{n}.dll")
    } else {
        format!("{carrier}+send.portmonitor+file.stats_monitor+type.dll")
    }
}

/// A configured monitor chain of one connection end.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Monitor {
    /// In order: `file`, `file1`, `file2`...
    chain: Vec<Kind>,
    side: Side,
    /// throttleDown's period (when it is first in the chain) and the time it last let a
    /// message through (the connection's start at first).
    period: Duration,
    last: Instant,
    /// A `stats_monitor`'s counts (what is sent, and the replies), for the port layer to
    /// publish.
    stats: Option<std::sync::Arc<StatsCounter>>,
    replies: Option<std::sync::Arc<StatsCounter>>,
}

impl PartialEq for StatsCounter {
    fn eq(&self, other: &Self) -> bool {
        std::ptr::eq(self, other)
    }
}

impl Eq for StatsCounter {}

impl Monitor {
    /// The monitor a carrier's qualifiers ask for at `side` (`send.X` for the sender,
    /// `recv.X` for the receiver): `None` when they ask for none, an error (as C++ refuses
    /// the connection) when it cannot be had.
    pub fn for_side(carrier: &CarrierName, side: Side) -> Result<Option<Monitor>, MonitorError> {
        let key = match side {
            Side::Sender => "send",
            Side::Receiver => "recv",
        };
        let Some(modifier) = carrier.find(key) else {
            return Ok(None);
        };
        if modifier != "portmonitor" {
            return Err(MonitorError::UnknownModifier(modifier.to_string()));
        }
        let part = side_part(carrier, side);
        // this side's own qualifier (4.0), else the first in the whole name (3.12); chains
        // are 4.0's: their keys only from this side's part
        let own = |k: &str| part.iter().find(|(q, _)| q == k).map(|(_, v)| v.as_str());
        let find = |k: &str| own(k).or_else(|| carrier.find(k));
        let mut chain = Vec::new();
        for i in 0.. {
            let (ty, file) = if i == 0 {
                (find("type"), find("file"))
            } else {
                (own(&format!("type{i}")), own(&format!("file{i}")))
            };
            if i > 0 && ty.is_none() {
                break;
            }
            // 3.12's defaults for the first: a Lua script called `modifier`
            let ty = ty.unwrap_or("lua");
            if ty != "dll" {
                return Err(MonitorError::UnsupportedType(ty.to_string()));
            }
            chain.push(match file.unwrap_or("modifier") {
                "depthimage_compression_zlib" => Kind::DepthImageZlib,
                "bottle_compression_zlib" => Kind::BottleZlib,
                "throttleDown" => Kind::ThrottleDown,
                // as C++ 4.0: "Attaching on receiver side is not supported yet."
                "stats_monitor" if side == Side::Receiver => {
                    return Err(MonitorError::Refused {
                        monitor: "stats_monitor",
                        reason: "attaching on the receiver side is not supported".into(),
                    })
                }
                "stats_monitor" => Kind::Stats,
                other => return Err(MonitorError::UnknownMonitor(other.to_string())),
            });
        }
        // every monitor sees every parameter (C++ copies them all into each one's info)
        let period = find("period_ms")
            .and_then(|v| v.parse::<f64>().ok())
            .filter(|ms| ms.is_finite() && *ms >= 0.0)
            .map_or(Duration::from_secs(1), |ms| {
                Duration::from_secs_f64(ms.trunc() / 1000.0)
            });
        let counter = || {
            chain
                .contains(&Kind::Stats)
                .then(|| std::sync::Arc::new(StatsCounter::default()))
        };
        let (stats, replies) = (counter(), counter());
        Ok(Some(Monitor {
            chain,
            side,
            period,
            last: Instant::now(),
            stats,
            replies,
        }))
    }

    /// The counts of the chain's `stats_monitor`, if it has one: what is sent, and the
    /// replies.
    pub fn stats(&self) -> Option<(std::sync::Arc<StatsCounter>, std::sync::Arc<StatsCounter>)> {
        Some((self.stats.clone()?, self.replies.clone()?))
    }

    /// A reply came back on the connection: counted (with no bytes, as C++ 4.0's
    /// `updateReply` counts it: the reply it is given serialises to nothing).
    pub fn reply_seen(&self) {
        if let Some(r) = &self.replies {
            r.add(0);
        }
    }

    /// The first monitor's name (the one that may drop messages).
    pub fn name(&self) -> &'static str {
        self.chain.first().map_or("", |k| k.name())
    }

    /// Whether the message arriving (or leaving) `now` goes on: only the first monitor is
    /// asked, as YARP 4.0 asks; throttleDown lets one through when more than its period
    /// has passed since the last it let through.
    pub fn accept(&mut self, now: Instant) -> bool {
        match self.chain.first() {
            Some(Kind::ThrottleDown) => {
                if now.saturating_duration_since(self.last) > self.period {
                    self.last = now;
                    true
                } else {
                    false
                }
            }
            _ => true,
        }
    }

    pub fn side(&self) -> Side {
        self.side
    }

    /// The message as the chain passes it on; an error when a monitor cannot take it
    /// (C++ then drops the message).
    pub fn update(&self, msg: &Bottle) -> Result<Bottle, MonitorError> {
        let mut out = msg.clone();
        for &k in &self.chain {
            out = self.update_one(k, &out).map_err(|e| match e {
                MonitorError::Refused { reason, .. } => MonitorError::Refused {
                    monitor: k.name(),
                    reason,
                },
                e => e,
            })?;
        }
        Ok(out)
    }

    fn update_one(&self, kind: Kind, msg: &Bottle) -> Result<Bottle, MonitorError> {
        match (kind, self.side) {
            (Kind::ThrottleDown, _) => Ok(msg.clone()),
            (Kind::Stats, _) => {
                if let Some(s) = &self.stats {
                    s.add(msg.encode().len());
                }
                Ok(msg.clone())
            }
            (Kind::DepthImageZlib, Side::Sender) => self.compress_depth(msg),
            (Kind::DepthImageZlib, Side::Receiver) => self.decompress_depth(msg),
            (Kind::BottleZlib, Side::Sender) => {
                let raw = msg.encode();
                let mut b = Bottle::with_capacity(2);
                b.push(len_i32(raw.len(), self)?)
                    .push(crate::Value::Blob(self.deflate(&raw)?));
                Ok(b)
            }
            (Kind::BottleZlib, Side::Receiver) => {
                let raw_size = msg.get(0).and_then(|v| v.as_i64());
                let blob = msg.get(1).and_then(blob);
                let (Some(raw_size), Some(blob), 2) = (raw_size, blob, msg.len()) else {
                    return Err(self.refused("expected `raw_size {compressed}`"));
                };
                let raw = self.inflate(blob, raw_size)?;
                Bottle::decode(&raw).map_err(|e| self.refused(format!("the inflated bytes: {e}")))
            }
        }
    }

    fn compress_depth(&self, msg: &Bottle) -> Result<Bottle, MonitorError> {
        let img = Image::from_bottle(msg).map_err(|e| self.refused(e.to_string()))?;
        if img.pixel_code() != PixelCode::MONO_FLOAT {
            return Err(self.refused(format!(
                "expected a float image (ImageOf<PixelFloat>), got pixel code {}",
                img.pixel_code().vocab().as_string()
            )));
        }
        let raw = img.data();
        let packed = self.deflate(raw)?;
        let mut b = Bottle::with_capacity(5);
        b.push(len_i32(img.width(), self)?)
            .push(len_i32(img.height(), self)?)
            .push(len_i32(packed.len(), self)?)
            .push(len_i32(raw.len(), self)?)
            .push(crate::Value::Blob(packed));
        Ok(b)
    }

    fn decompress_depth(&self, msg: &Bottle) -> Result<Bottle, MonitorError> {
        let int = |i: usize| msg.get(i).and_then(|v| v.as_i64());
        let blob = msg.get(4).and_then(blob);
        let (Some(w), Some(h), Some(packed_size), Some(raw_size), Some(blob)) =
            (int(0), int(1), int(2), int(3), blob)
        else {
            return Err(self.refused("expected `width height compressed_size raw_size {data}`"));
        };
        // the checks of the C++ receiver: the sizes must agree with the data
        let expected = w.checked_mul(h).and_then(|n| n.checked_mul(4));
        if w < 0 || h < 0 || expected != Some(raw_size) || packed_size != blob.len() as i64 {
            return Err(self.refused("invalid data received: wrong blob size"));
        }
        let raw = self.inflate(blob, raw_size)?;
        let mut img = Image::new(PixelCode::MONO_FLOAT, w as usize, h as usize)
            .map_err(|e| self.refused(e.to_string()))?;
        // rows of width * 4 bytes, placed in the image's (possibly padded) rows
        let row = w as usize * 4;
        for (y, src) in raw.chunks_exact(row.max(1)).take(h as usize).enumerate() {
            img.row_mut(y)[..row].copy_from_slice(src);
        }
        Ok(img.to_bottle())
    }

    fn deflate(&self, raw: &[u8]) -> Result<Vec<u8>, MonitorError> {
        // zlib's `compress()`: the zlib format at the default level
        let mut z = flate2::write::ZlibEncoder::new(
            Vec::with_capacity(raw.len() / 2 + 64),
            flate2::Compression::default(),
        );
        z.write_all(raw)
            .and_then(|_| z.finish())
            .map_err(|e| self.refused(format!("compression failed: {e}")))
    }

    /// Inflates exactly `raw_size` bytes (as zlib's `uncompress()` into a buffer of that
    /// size): more or fewer is corrupt data, and a lying size cannot make us allocate
    /// more than the data inflates to.
    fn inflate(&self, packed: &[u8], raw_size: i64) -> Result<Vec<u8>, MonitorError> {
        let want = usize::try_from(raw_size).map_err(|_| self.refused("negative size"))?;
        let mut out = Vec::with_capacity(want.min(packed.len().saturating_mul(64)));
        flate2::read::ZlibDecoder::new(packed)
            .take(want as u64 + 1)
            .read_to_end(&mut out)
            .map_err(|e| self.refused(format!("corrupted data: {e}")))?;
        if out.len() != want {
            return Err(self.refused(format!(
                "the data inflates to {} bytes, not the {want} announced",
                out.len()
            )));
        }
        Ok(out)
    }

    fn refused(&self, reason: impl Into<String>) -> MonitorError {
        MonitorError::Refused {
            monitor: self.name(),
            reason: reason.into(),
        }
    }
}

/// The qualifiers of one side's part of the carrier name, as YARP 4.0 splits it
/// (`PortMonitor::parseBlocks`): the sender's follow `send.portmonitor` up to a later
/// `recv.portmonitor`; the receiver's, everything after `recv.portmonitor`.
fn side_part(carrier: &CarrierName, side: Side) -> &[(String, String)] {
    let q = &carrier.qualifiers;
    let at = |key: &str| q.iter().position(|(k, v)| k == key && v == "portmonitor");
    match (side, at("send"), at("recv")) {
        (Side::Sender, Some(s), Some(r)) if r > s => &q[s + 1..r],
        (Side::Sender, Some(s), _) => &q[s + 1..],
        (Side::Receiver, _, Some(r)) => &q[r + 1..],
        _ => &[],
    }
}

fn blob(v: &crate::Value) -> Option<&[u8]> {
    match v {
        crate::Value::Blob(b) => Some(b),
        _ => None,
    }
}

fn len_i32(n: usize, m: &Monitor) -> Result<i32, MonitorError> {
    i32::try_from(n).map_err(|_| m.refused(format!("{n} does not fit an int32")))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{bottle, Value};

    fn monitors(carrier: &str) -> (Monitor, Monitor) {
        let c = CarrierName::parse(carrier);
        (
            Monitor::for_side(&c, Side::Sender).unwrap().unwrap(),
            Monitor::for_side(&c, Side::Receiver).unwrap().unwrap(),
        )
    }

    #[test]
    fn a_depth_image_round_trips_through_the_ergocub_carrier() {
        let (tx, rx) = monitors("fast_tcp+send.portmonitor+file.depthimage_compression_zlib+recv.portmonitor+file.depthimage_compression_zlib+type.dll");
        let mut img = Image::new(PixelCode::MONO_FLOAT, 64, 48).unwrap();
        for y in 0..48 {
            for x in 0..64 {
                let d = 0.5 + (x + y) as f32 * 0.01;
                img.pixel_mut(x, y).copy_from_slice(&d.to_le_bytes());
            }
        }
        let sent = tx.update(&img.to_bottle()).unwrap();
        assert_eq!(sent.len(), 5);
        assert_eq!(sent.get(0), Some(&Value::Int32(64)));
        assert_eq!(sent.get(1), Some(&Value::Int32(48)));
        assert_eq!(sent.get(3), Some(&Value::Int32(64 * 48 * 4)));
        let packed = sent.get(4).and_then(blob).unwrap();
        assert_eq!(sent.get(2), Some(&Value::Int32(packed.len() as i32)));
        assert!(packed.len() < 64 * 48 * 4 / 2, "{} bytes", packed.len());
        // the zlib stream header (CMF 0x78: deflate, 32 KiB window)
        assert_eq!(packed[0], 0x78);
        let back = Image::from_bottle(&rx.update(&sent).unwrap()).unwrap();
        assert_eq!(back, img);
    }

    #[test]
    fn a_bottle_round_trips_through_bottle_compression() {
        let (tx, rx) = monitors(
            "fast_tcp+send.portmonitor+file.bottle_compression_zlib+recv.portmonitor+file.bottle_compression_zlib+type.dll",
        );
        let scan = bottle![1.5, "laser", 720, bottle![0.1, 0.2, 0.3]];
        let sent = tx.update(&scan).unwrap();
        assert_eq!(sent.get(0), Some(&Value::Int32(scan.encode().len() as i32)));
        assert_eq!(rx.update(&sent).unwrap(), scan);
    }

    #[test]
    fn what_cannot_be_had_is_named() {
        let err = |c: &str, side| Monitor::for_side(&CarrierName::parse(c), side).unwrap_err();
        assert_eq!(
            err("tcp+recv.portmonitor+file.my_filter", Side::Receiver),
            MonitorError::UnsupportedType("lua".into())
        );
        let e = err(
            "tcp+recv.portmonitor+file.segmentationimage_to_rgb+type.dll",
            Side::Receiver,
        );
        assert!(e.to_string().contains("segmentationimage_to_rgb"), "{e}");
        assert!(e.to_string().contains("depthimage_compression_zlib"), "{e}");
        assert_eq!(
            err("tcp+send.bayer", Side::Sender),
            MonitorError::UnknownModifier("bayer".into())
        );
        // no modifier for this side: no monitor
        let c = CarrierName::parse("tcp+recv.portmonitor+file.bottle_compression_zlib+type.dll");
        assert_eq!(Monitor::for_side(&c, Side::Sender), Ok(None));
    }

    #[test]
    fn throttle_down_lets_one_message_through_per_period() {
        let c = CarrierName::parse("tcp+send.portmonitor+type.dll+file.throttleDown+period_ms.500");
        let mut m = Monitor::for_side(&c, Side::Sender).unwrap().unwrap();
        assert_eq!(m.name(), "throttleDown");
        let t0 = m.last;
        let at = |ms: u64| t0 + Duration::from_millis(ms);
        // not before a period has passed since the connection; strictly more than it
        assert!(!m.accept(at(100)));
        assert!(!m.accept(at(500)));
        assert!(m.accept(at(501)));
        // drops do not move the reference
        assert!(!m.accept(at(900)));
        assert!(m.accept(at(1002)));
        assert_eq!(m.update(&bottle![1, "a"]).unwrap(), bottle![1, "a"]);
        // default period: 1 s
        let c = CarrierName::parse("tcp+recv.portmonitor+type.dll+file.throttleDown");
        let m = Monitor::for_side(&c, Side::Receiver).unwrap().unwrap();
        assert_eq!(m.period, Duration::from_secs(1));
    }

    #[test]
    fn monitors_chain_as_in_yarp_4() {
        // throttle, then compress: the first decides what goes, each passes to the next
        let (mut tx, rx) = monitors(
            "tcp+send.portmonitor+type.dll+file.throttleDown+type1.dll+file1.bottle_compression_zlib+period_ms.0+recv.portmonitor+type.dll+file.bottle_compression_zlib",
        );
        assert_eq!(tx.chain, [Kind::ThrottleDown, Kind::BottleZlib]);
        assert_eq!(
            rx.chain,
            [Kind::BottleZlib],
            "the receiver reads its own part"
        );
        assert!(tx.accept(tx.last + Duration::from_millis(1)));
        let msg = bottle![7, "seven"];
        let sent = tx.update(&msg).unwrap();
        assert_ne!(sent, msg);
        assert_eq!(rx.update(&sent).unwrap(), msg);
        // a later monitor that cannot be had, or a type1 that is not a dll, refuses
        let c = CarrierName::parse(
            "tcp+send.portmonitor+type.dll+file.throttleDown+type1.dll+file1.nope",
        );
        assert!(Monitor::for_side(&c, Side::Sender).is_err());
        let c =
            CarrierName::parse("tcp+send.portmonitor+type.dll+file.throttleDown+type1.lua+file1.x");
        assert!(Monitor::for_side(&c, Side::Sender).is_err());
        // a failure names the monitor that failed
        let (tx, _) = monitors(
            "tcp+send.portmonitor+type.dll+file.throttleDown+type1.dll+file1.depthimage_compression_zlib+recv.portmonitor+type.dll+file.throttleDown",
        );
        let e = tx.update(&bottle!["not an image"]).unwrap_err();
        assert!(
            e.to_string().starts_with("depthimage_compression_zlib"),
            "{e}"
        );
    }

    #[test]
    fn stats_monitor_counts_and_is_added_as_4_0_adds_it() {
        assert_eq!(
            with_stats_monitor("/a", "/b", "tcp"),
            "tcp+send.portmonitor+file.stats_monitor+type.dll"
        );
        assert_eq!(
            with_stats_monitor("/a", "/b", "tcp+send.portmonitor+type.dll+file.throttleDown+file1.x+type1.dll"),
            "tcp+send.portmonitor+type.dll+file.throttleDown+file1.x+type1.dll+file2.stats_monitor+type2.dll"
        );
        assert_eq!(with_stats_monitor("/a", "/b", ""), "");
        let log = "/logger/log/x";
        assert_eq!(with_stats_monitor(log, log, "tcp"), "tcp");
        let c = CarrierName::parse(&with_stats_monitor("/a", "/b", "tcp"));
        let m = Monitor::for_side(&c, Side::Sender).unwrap().unwrap();
        let (counts, replies) = m.stats().unwrap();
        m.reply_seen();
        assert_eq!(replies.take(), (1, 0));
        let msg = bottle![1, "two"];
        assert_eq!(m.update(&msg).unwrap(), msg);
        m.update(&msg).unwrap();
        assert_eq!(counts.take(), (2, 2 * msg.encode().len() as u64));
        assert_eq!(counts.take(), (0, 0));
        // as C++ 4.0, not on the receiver
        assert!(Monitor::for_side(&c.clone(), Side::Receiver)
            .unwrap_or(None)
            .is_none());
        let c = CarrierName::parse("tcp+recv.portmonitor+file.stats_monitor+type.dll");
        assert!(Monitor::for_side(&c, Side::Receiver).is_err());
        let s = connection_stats(5.0, ("/a", "/b", "tcp"), true, (10, 400), 1.0);
        assert_eq!(s.to_string(), "5.0 \"/a\" \"/b\" tcp [ok] 400.0 10.0");
    }

    #[test]
    fn bad_messages_are_refused_never_a_panic() {
        let (tx, rx) = monitors(
            "tcp+send.portmonitor+recv.portmonitor+file.depthimage_compression_zlib+type.dll",
        );
        // not a float image
        let rgb = Image::new(PixelCode::RGB, 4, 4).unwrap().to_bottle();
        assert!(tx.update(&rgb).is_err());
        assert!(tx.update(&bottle!["hello"]).is_err());
        // sizes that disagree with the data, a lying raw size, garbage
        let mut ok = Image::new(PixelCode::MONO_FLOAT, 8, 8).unwrap();
        ok.pixel_mut(1, 1).copy_from_slice(&1.0f32.to_le_bytes());
        let good = tx.update(&ok.to_bottle()).unwrap();
        let mut wrong = good.clone();
        *wrong.get_mut(3).unwrap() = Value::Int32(1 << 30);
        assert!(rx.update(&wrong).is_err());
        let mut wrong = good.clone();
        *wrong.get_mut(0).unwrap() = Value::Int32(-8);
        assert!(rx.update(&wrong).is_err());
        let garbage = bottle![8, 8, 4, 256, Value::Blob(vec![1, 2, 3, 4])];
        assert!(rx.update(&garbage).is_err());
        assert!(rx.update(&bottle![]).is_err());
        let (_, brx) =
            monitors("tcp+recv.portmonitor+send.portmonitor+file.bottle_compression_zlib+type.dll");
        assert!(brx
            .update(&bottle![1 << 30, Value::Blob(vec![0x78, 0x9c])])
            .is_err());
        assert!(brx.update(&bottle![-1, Value::Blob(vec![])]).is_err());
    }
}
