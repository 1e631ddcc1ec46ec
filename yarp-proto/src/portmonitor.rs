//! Port monitors: the `portmonitor` carrier modifier that transforms every message of a
//! connection, on the sending side (`+send.portmonitor`) or the receiving one
//! (`+recv.portmonitor`). C++ loads the monitor named by `+file.NAME` as a plug-in
//! (`+type.dll`) or a Lua script (`+type.lua`, the default); here the dll monitors
//! robots' files name are built in:
//!
//! - `depthimage_compression_zlib` (YARP's `src/portmonitors/depthimage_compression_zlib`):
//!   a float depth image travels as the Bottle `width height compressed_size raw_size
//!   {zlib of the raw rows}`;
//! - `bottle_compression_zlib` (YARP 3.12's `src/portmonitors/bottle_compression_zlib`):
//!   any message travels as `raw_size {zlib of its Bottle encoding}`.
//!
//! ergoCub's `sensors/ros2_repeaters/*.xml` name both. Sans-I/O: Bottles in, Bottles out.

use crate::image::{Image, PixelCode};
use crate::wire::modifiers::CarrierName;
use crate::Bottle;
use std::io::{Read, Write};

/// Which end of the connection a monitor runs at.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// The output port: the monitor changes what is sent (`sender_side`).
    Sender,
    /// The input port: the monitor changes what is received (`receiver_side`).
    Receiver,
}

/// The monitors built into this crate.
pub const BUILT_IN: &[&str] = &["depthimage_compression_zlib", "bottle_compression_zlib"];

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
}

/// A configured monitor of one connection end.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Monitor {
    kind: Kind,
    side: Side,
}

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
        // C++ PortMonitor::configureFromProperty: type defaults to lua, file to "modifier"
        let kind = carrier.find("type").unwrap_or("lua");
        if kind != "dll" {
            return Err(MonitorError::UnsupportedType(kind.to_string()));
        }
        let file = carrier.find("file").unwrap_or("modifier");
        let kind = match file {
            "depthimage_compression_zlib" => Kind::DepthImageZlib,
            "bottle_compression_zlib" => Kind::BottleZlib,
            other => return Err(MonitorError::UnknownMonitor(other.to_string())),
        };
        Ok(Some(Monitor { kind, side }))
    }

    pub fn name(&self) -> &'static str {
        match self.kind {
            Kind::DepthImageZlib => "depthimage_compression_zlib",
            Kind::BottleZlib => "bottle_compression_zlib",
        }
    }

    pub fn side(&self) -> Side {
        self.side
    }

    /// The message as the monitor passes it on; an error when it does not accept it
    /// (C++ then drops the message).
    pub fn update(&self, msg: &Bottle) -> Result<Bottle, MonitorError> {
        match (self.kind, self.side) {
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
