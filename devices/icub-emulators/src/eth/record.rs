//! The ROP recorder of `icub-eth-emulator --record DIR`: every datagram a host sends to a
//! board, from the first on, as one JSON object per ROP in `DIR/<board's robot IP>.jsonl`
//! (appended; flushed after each datagram, so a killed emulator leaves whole lines), to
//! compare what two hosts (e.g. icub-main's and ours) say to the same robot.
//!
//! A line:
//!
//! ```json
//! {"t":1.234567,"from":"10.0.1.104:12345","seq":7,"age":1234,"ropcode":3,"rop":"set",
//!  "id32":"0x01000109","ep":1,"entity":0,"index":1,"tag":9,"ctrl":"0x20",
//!  "rqstconf":true,"rqsttime":false,"signature":"0x00000042","data":"0a0b"}
//! ```
//!
//! `t`: seconds since the boards began serving (the datagram's arrival); `from`: the
//! host's socket; `seq` and `age`: the ropframe's sequence number and age (µs, the host's
//! clock); `ropcode` (`eOropcode_t`: 1 ask, 2 say, 3 set, 4 sig, 5 rst) and its name;
//! `id32` and its parts; `ctrl`: the ROP's control byte, with its requests spelled out;
//! `signature` (only with `plussign`) and `time` (only with `plustime`); `data`: the
//! ROP's data, hex (empty for an ask). A datagram that is no ropframe is one line
//! `{"t":..,"from":..,"invalid":"why","datagram":"hex"}`; malformed ROPs after valid ones
//! add a line `{"t":..,"from":..,"bad_rops":"why"}`.
//!
//! The boards' thread only copies the datagram into a channel; a writer thread decodes
//! and writes.

use std::fmt::Write as _;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::net::{Ipv4Addr, SocketAddr};
use std::path::Path;
use std::sync::mpsc;
use std::time::Duration;

use icub_eth::frame::Frame;
use icub_eth::rop::{RopCode, RopRef};

/// A datagram the host sent to board `board`, at `t` since the boards began serving.
struct Received {
    board: usize,
    t: Duration,
    from: SocketAddr,
    bytes: Vec<u8>,
}

/// The boards' thread's end: hands datagrams to the writer.
#[derive(Clone)]
pub struct Recorder {
    tx: mpsc::Sender<Received>,
}

impl Recorder {
    /// Opens (creating `dir` and appending to) one file per board, in the boards' order,
    /// and starts the writer thread; it ends when every [`Recorder`] is dropped, after
    /// writing what it was given.
    pub fn start(
        dir: &Path,
        boards: &[Ipv4Addr],
    ) -> Result<(Recorder, std::thread::JoinHandle<()>), String> {
        std::fs::create_dir_all(dir).map_err(|e| format!("--record {}: {e}", dir.display()))?;
        let mut files = Vec::with_capacity(boards.len());
        for ip in boards {
            let path = dir.join(format!("{ip}.jsonl"));
            let f = std::fs::OpenOptions::new()
                .create(true)
                .append(true)
                .open(&path)
                .map_err(|e| format!("--record {}: {e}", path.display()))?;
            files.push(BufWriter::new(f));
        }
        let (tx, rx) = mpsc::channel();
        let t = std::thread::Builder::new()
            .name("eth-record".into())
            .spawn(move || write_all(rx, files))
            .map_err(|e| e.to_string())?;
        Ok((Recorder { tx }, t))
    }

    /// Queues a datagram board `board` received (a copy; never blocks).
    pub fn record(&self, board: usize, t: Duration, from: SocketAddr, bytes: &[u8]) {
        let _ = self.tx.send(Received {
            board,
            t,
            from,
            bytes: bytes.to_vec(),
        });
    }
}

fn write_all(rx: mpsc::Receiver<Received>, mut files: Vec<BufWriter<File>>) {
    let mut line = String::with_capacity(256);
    let mut failed = vec![false; files.len()];
    for d in rx {
        let Some(f) = files.get_mut(d.board) else {
            continue;
        };
        let mut out = String::new();
        lines_of(&d, &mut line, &mut out);
        let r = f.write_all(out.as_bytes()).and_then(|()| f.flush());
        if let Err(e) = r {
            if !std::mem::replace(&mut failed[d.board], true) {
                tracing::warn!("--record: board {}: {e}", d.board);
            }
        }
    }
}

/// The lines of one datagram (see the module documentation).
fn lines_of(d: &Received, line: &mut String, out: &mut String) {
    let head = format!("{{\"t\":{:.6},\"from\":\"{}\"", d.t.as_secs_f64(), d.from);
    let frame = match Frame::decode(&d.bytes) {
        Ok(f) => f,
        Err(e) => {
            let _ = writeln!(
                out,
                "{head},\"invalid\":\"{}\",\"datagram\":\"{}\"}}",
                json_escape(&e.to_string()),
                hex(&d.bytes)
            );
            return;
        }
    };
    let (seq, age) = (frame.header.sequence, frame.header.age);
    let bad = frame.visit_rops(|r| {
        line.clear();
        rop_line(&head, seq, age, &r, line);
        out.push_str(line);
    });
    if let Some(e) = bad {
        let _ = writeln!(
            out,
            "{head},\"bad_rops\":\"{}\"}}",
            json_escape(&e.to_string())
        );
    }
}

fn rop_line(head: &str, seq: u64, age: u64, r: &RopRef, line: &mut String) {
    let name = match r.code {
        RopCode::Ask => "ask",
        RopCode::Say => "say",
        RopCode::Set => "set",
        RopCode::Sig => "sig",
        RopCode::Rst => "rst",
    };
    let id = r.id32;
    let _ = write!(
        line,
        "{head},\"seq\":{seq},\"age\":{age},\"ropcode\":{},\"rop\":\"{name}\",\"id32\":\"{:#010x}\",\"ep\":{},\"entity\":{},\"index\":{},\"tag\":{},\"ctrl\":\"{:#04x}\",\"rqstconf\":{},\"rqsttime\":{}",
        r.code as u8,
        id.0,
        id.endpoint(),
        id.entity(),
        id.index(),
        id.tag(),
        r.ctrl.to_byte(),
        r.ctrl.rqstconf,
        r.ctrl.rqsttime,
    );
    if let Some(s) = r.signature {
        let _ = write!(line, ",\"signature\":\"{s:#010x}\"");
    }
    if let Some(t) = r.time {
        let _ = write!(line, ",\"time\":{t}");
    }
    let _ = writeln!(line, ",\"data\":\"{}\"}}", hex(r.data));
}

fn hex(b: &[u8]) -> String {
    let mut s = String::with_capacity(2 * b.len());
    for x in b {
        let _ = write!(s, "{x:02x}");
    }
    s
}

fn json_escape(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '"' => o.push_str("\\\""),
            '\\' => o.push_str("\\\\"),
            c if (c as u32) < 0x20 => {
                let _ = write!(o, "\\u{:04x}", c as u32);
            }
            c => o.push(c),
        }
    }
    o
}

#[cfg(test)]
mod tests {
    use super::*;
    use icub_eth::frame::FrameBuilder;
    use icub_eth::id::{ids, Id32};
    use icub_eth::rop::Rop;

    #[test]
    fn a_datagram_becomes_one_line_per_rop() {
        let mut fb = FrameBuilder::new(1400);
        let mut set = Rop::set(ids::APPL_CONFIG, vec![0xe8, 0x03]);
        set.ctrl.rqstconf = true;
        fb.push(&set).unwrap();
        let mut ask = Rop::ask(Id32(0x0100_0105));
        ask.ctrl.plussign = true;
        ask.signature = Some(0x42);
        fb.push(&ask).unwrap();
        let d = Received {
            board: 0,
            t: Duration::from_millis(1500),
            from: "10.0.1.104:12345".parse().unwrap(),
            bytes: fb.finish(7, 99),
        };
        let (mut line, mut out) = (String::new(), String::new());
        lines_of(&d, &mut line, &mut out);
        let lines: Vec<&str> = out.lines().collect();
        assert_eq!(lines.len(), 2, "{out}");
        assert!(lines[0].starts_with("{\"t\":1.500000,\"from\":\"10.0.1.104:12345\",\"seq\":7,\"age\":99,\"ropcode\":3,\"rop\":\"set\""), "{}", lines[0]);
        assert!(lines[0].contains(&format!("\"id32\":\"{:#010x}\"", ids::APPL_CONFIG.0)));
        assert!(lines[0].contains("\"rqstconf\":true"));
        assert!(lines[0].ends_with("\"data\":\"e803\"}"), "{}", lines[0]);
        assert!(lines[1].contains("\"ropcode\":1,\"rop\":\"ask\",\"id32\":\"0x01000105\""));
        assert!(lines[1].contains("\"signature\":\"0x00000042\""));
        assert!(lines[1].ends_with("\"data\":\"\"}"), "{}", lines[1]);

        out.clear();
        let bad = Received {
            bytes: vec![1, 2, 3],
            ..d
        };
        lines_of(&bad, &mut line, &mut out);
        assert!(out.contains("\"invalid\":") && out.contains("\"datagram\":\"010203\""));
    }
}
