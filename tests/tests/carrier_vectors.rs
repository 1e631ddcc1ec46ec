//! Connection framing against the recorded C++ YARP 3.12 transcripts.
//!
//! Every record of `carriers.jsonl` is replayed through `yarp_proto::wire::Decoder` (whole,
//! one byte at a time, and in uneven chunks); the decoded units must match the recorded
//! `c2s_units` / `s2c_units`, and everything our side would send is re-encoded and
//! compared byte for byte. The parsed `units` of the device recordings (controlboard,
//! framegrabber, imu: C++ clients, `yarp rpc`, streams) are checked the same way.
//!
//! The vectors are at `$YARP_VECTORS_DIR`, else `../../shared/yarp-vectors` from this
//! crate. A missing directory fails the tests: they are never skipped.

use std::collections::BTreeMap;
use std::io::Write;

use serde_json::Value as Json;
use yarp_proto::wire::{
    self, classify_header, text_carrier, Carrier, CommandKind, Decoder, DecoderConfig, Event,
    Framing, Message, PortCommand,
};
use yarp_proto::{Bottle, Stamp, Value};

// ---------------------------------------------------------------- loading

/// The shared loader (fails loudly when the vectors are missing).
fn load(file: &str) -> Vec<Json> {
    yarp_interop_tests::load_records(file)
}

fn unhex(s: &str) -> Vec<u8> {
    hex::decode(s).unwrap_or_else(|e| panic!("bad hex {s:?}: {e}"))
}

fn field_hex(rec: &Json, key: &str) -> Vec<u8> {
    unhex(
        rec[key]
            .as_str()
            .unwrap_or_else(|| panic!("field {key} missing in {rec}")),
    )
}

fn id(rec: &Json) -> String {
    rec["id"].as_str().unwrap_or("?").to_string()
}

/// The two directions of a transcript (`events`), concatenated.
fn directions(events: &Json) -> (Vec<u8>, Vec<u8>) {
    let mut c2s = Vec::new();
    let mut s2c = Vec::new();
    for e in events.as_array().map(Vec::as_slice).unwrap_or_default() {
        let bytes = unhex(e["hex"].as_str().unwrap_or(""));
        match e["dir"].as_str() {
            Some("c2s") => c2s.extend(bytes),
            Some("s2c") => s2c.extend(bytes),
            _ => {}
        }
    }
    (c2s, s2c)
}

fn strings(v: &Json) -> Option<Vec<String>> {
    v.as_array().map(|a| {
        a.iter()
            .map(|s| s.as_str().unwrap_or("").to_string())
            .collect()
    })
}

// ---------------------------------------------------------------- counters

#[derive(Default, Debug)]
struct Stats {
    records: usize,
    connections: usize,
    text_connections: usize,
    units: usize,
    messages: usize,
    canonical_messages: usize,
    replies: usize,
    canonical_replies: usize,
    acks: usize,
    printed_lines: usize,
}

fn report(what: &str, s: &Stats) {
    // straight to stderr so that the line shows even when cargo captures test output
    let _ = writeln!(
        std::io::stderr().lock(),
        "carrier_vectors: {what}: {} records, {} connections ({} text), {} units \
         ({} messages, {} re-encoded through the high-level encoders, {} replies \
         ({} re-encoded as Bottles), {} acks), {} printed lines matched",
        s.records,
        s.connections,
        s.text_connections,
        s.units,
        s.messages,
        s.canonical_messages,
        s.replies,
        s.canonical_replies,
        s.acks,
        s.printed_lines
    );
}

// ---------------------------------------------------------------- decoding

fn cfg() -> DecoderConfig {
    DecoderConfig::default()
}

/// Decodes `bytes` whole, byte by byte and in uneven chunks; all three must agree, succeed
/// and end on an event boundary.
fn decode_all_ways(ctx: &str, make: impl Fn() -> Decoder, bytes: &[u8]) -> Vec<Event> {
    let mut d = make();
    let whole = d
        .decode(bytes)
        .unwrap_or_else(|e| panic!("{ctx}: decode failed: {e}"));
    assert!(d.is_idle(), "{ctx}: {} byte(s) left undecoded", d.pending());

    let mut d = make();
    let mut bytewise = Vec::new();
    for b in bytes {
        bytewise.extend(
            d.decode(std::slice::from_ref(b))
                .unwrap_or_else(|e| panic!("{ctx}: bytewise decode failed: {e}")),
        );
    }
    assert_eq!(whole, bytewise, "{ctx}: byte-by-byte decoding differs");

    let mut d = make();
    let mut chunked = Vec::new();
    let mut rest = bytes;
    let mut k = 0usize;
    while !rest.is_empty() {
        let n = [1usize, 7, 2, 13, 3, 64, 5, 1000][k % 8].min(rest.len());
        chunked.extend(
            d.decode(&rest[..n])
                .unwrap_or_else(|e| panic!("{ctx}: chunked decode failed: {e}")),
        );
        rest = &rest[n..];
        k += 1;
    }
    assert_eq!(whole, chunked, "{ctx}: chunked decoding differs");
    whole
}

fn messages(events: &[Event]) -> Vec<&Message> {
    events
        .iter()
        .filter_map(|e| match e {
            Event::Message(m) => Some(m),
            _ => None,
        })
        .collect()
}

/// A decoder for the accepting side's answers, told about every message we sent.
fn responder(spec: wire::CarrierSpec, sent: &[&Message], from_start: bool) -> Decoder {
    let mut d = if from_start {
        Decoder::connecting(spec, cfg())
    } else {
        Decoder::responses(spec, cfg())
    };
    for m in sent {
        d.expect_response(&m.command);
    }
    d
}

// ---------------------------------------------------------------- recorder rendering

/// Python `repr` of a float (the recorder's `decoded` uses it).
fn py_repr(x: f64) -> String {
    if x.is_nan() {
        return "nan".into();
    }
    if x.is_infinite() {
        return if x < 0.0 { "-inf" } else { "inf" }.into();
    }
    let sci = format!("{:e}", x.abs());
    let (mant, exp) = sci.split_once('e').unwrap_or((&sci, "0"));
    let exp: i32 = exp.parse().unwrap_or(0);
    let digits: String = mant.chars().filter(|c| c.is_ascii_digit()).collect();
    let sign = if x.is_sign_negative() { "-" } else { "" };
    if (-4..16).contains(&exp) {
        if exp >= 0 {
            let e = exp as usize;
            let mut int = digits.clone();
            while int.len() < e + 1 {
                int.push('0');
            }
            let frac = &int[e + 1..];
            let frac = if frac.is_empty() { "0" } else { frac };
            format!("{sign}{}.{frac}", &int[..e + 1])
        } else {
            format!("{sign}0.{}{digits}", "0".repeat((-exp - 1) as usize))
        }
    } else {
        let m = if digits.len() > 1 {
            format!("{}.{}", &digits[..1], &digits[1..])
        } else {
            digits.clone()
        };
        format!(
            "{sign}{m}e{}{:02}",
            if exp < 0 { '-' } else { '+' },
            exp.abs()
        )
    }
}

/// The recorder's `decoded` rendering: strings always quoted, floats as Python repr,
/// vocabs as `[abc]` (vocab 0 as `[]`), blobs as `{1 2 3}`.
fn render(b: &Bottle) -> String {
    b.iter().map(render_value).collect::<Vec<_>>().join(" ")
}

fn render_value(v: &Value) -> String {
    match v {
        Value::Int8(x) => x.to_string(),
        Value::Int16(x) => x.to_string(),
        Value::Int32(x) => x.to_string(),
        Value::Int64(x) => x.to_string(),
        Value::Float32(x) => py_repr(*x as f64),
        Value::Float64(x) => py_repr(*x),
        Value::Vocab32(x) => format!("[{}]", String::from_utf8_lossy(&x.decode())),
        Value::Vocab64(x) => format!(
            "[{}]",
            String::from_utf8_lossy(&yarp_proto::value::vocab64_decode(*x))
        ),
        Value::String(s) => format!("\"{}\"", String::from_utf8_lossy(s)),
        Value::Blob(b) => format!(
            "{{{}}}",
            b.iter().map(u8::to_string).collect::<Vec<_>>().join(" ")
        ),
        Value::List(l) | Value::Dict(l) => format!("({})", render(l)),
    }
}

// ---------------------------------------------------------------- unit checks

/// Checks decoded events against recorded units, one to one, and re-encodes them.
fn check_units(ctx: &str, events: &[Event], units: &[Json], stats: &mut Stats) {
    assert_eq!(
        events.len(),
        units.len(),
        "{ctx}: {} events decoded, {} units recorded\nevents: {events:#?}\nunits: {units:#?}",
        events.len(),
        units.len()
    );
    for (i, (ev, u)) in events.iter().zip(units).enumerate() {
        let ctx = format!("{ctx} unit {i} ({})", u["unit"]);
        stats.units += 1;
        match (u["unit"].as_str(), ev) {
            (Some("header"), Event::Header(h)) => {
                let hex = field_hex(u, "hex");
                assert_eq!(h.raw.as_slice(), hex, "{ctx}");
                assert_eq!(h.value(), u["value"].as_i64().map(|v| v as i32), "{ctx}");
                assert_eq!(
                    h.carrier().header().as_slice(),
                    hex,
                    "{ctx}: re-encoded header"
                );
            }
            (Some("sender"), Event::SenderName(name)) => {
                assert_eq!(
                    Some(name.as_slice()),
                    u["name"].as_str().map(str::as_bytes),
                    "{ctx}"
                );
                let mut enc = Vec::new();
                wire::encode_sender_name(name, &mut enc);
                assert_eq!(enc, field_hex(u, "hex"), "{ctx}: re-encoded sender name");
            }
            (Some("header_reply"), Event::HeaderReply(v)) => {
                assert_eq!(Some(*v as i64), u["value"].as_i64(), "{ctx}");
                assert_eq!(
                    wire::encode_header_reply(*v).as_slice(),
                    field_hex(u, "hex"),
                    "{ctx}: re-encoded header reply"
                );
            }
            (Some("ack"), Event::Ack(v)) => {
                stats.acks += 1;
                assert_eq!(Some(*v as i64), u["value"].as_i64(), "{ctx}");
                assert_eq!(
                    wire::ack().as_slice(),
                    field_hex(u, "hex"),
                    "{ctx}: re-encoded ack"
                );
            }
            (Some("reply"), Event::Reply(bytes)) => {
                stats.replies += 1;
                assert_eq!(*bytes, field_hex(u, "payload_hex"), "{ctx}");
                let b = Bottle::decode(bytes).unwrap_or_else(|e| panic!("{ctx}: {e}"));
                if let Some(d) = u["decoded"].as_str() {
                    assert_eq!(render(&b), d, "{ctx}: decoded");
                }
                // Bottle replies re-encode exactly; thrift-style replies (`WireWriter`,
                // e.g. the IMU metadata) tag every element of mixed lists and so differ
                // from what a Bottle writes for the same values
                if b.encode() == *bytes {
                    assert_eq!(wire::reply_message(&b, true)[..bytes.len()], bytes[..]);
                    stats.canonical_replies += 1;
                }
            }
            (Some("message"), Event::Message(m)) => check_message(&ctx, m, u, stats),
            (unit, ev) => panic!("{ctx}: recorded {unit:?}, decoded {ev:?}"),
        }
    }
}

fn check_message(ctx: &str, m: &Message, u: &Json, stats: &mut Stats) {
    stats.messages += 1;
    let frame = m
        .frame
        .as_ref()
        .unwrap_or_else(|| panic!("{ctx}: not a binary message"));
    let index_hex = field_hex(u, "index_hex");
    let mut idx = Vec::new();
    frame.index.encode(&mut idx);
    assert_eq!(idx, index_hex, "{ctx}: index");
    let lens: Vec<u32> = u["block_lens"]
        .as_array()
        .map(|a| {
            a.iter()
                .filter_map(|v| v.as_u64())
                .map(|v| v as u32)
                .collect()
        })
        .unwrap_or_default();
    assert_eq!(frame.index.block_lens, lens, "{ctx}: block_lens");
    if let Some(r) = u["reply_lens"].as_array() {
        let r: Vec<u32> = r
            .iter()
            .filter_map(|v| v.as_u64())
            .map(|v| v as u32)
            .collect();
        assert_eq!(frame.index.reply_lens, r, "{ctx}: reply_lens");
    }
    let cmd_hex = field_hex(u, "port_command_hex");
    assert_eq!(
        frame.command_header.as_slice(),
        cmd_hex,
        "{ctx}: port command"
    );
    assert_eq!(
        m.command.header().as_slice(),
        cmd_hex,
        "{ctx}: re-encoded port command"
    );
    match u["port_command_text"].as_str() {
        Some(t) => {
            assert_eq!(m.command.text, t.as_bytes(), "{ctx}: port command text");
            let mut t0 = m.command.text.clone();
            t0.push(0);
            assert_eq!(t0, field_hex(u, "port_command_text_hex"), "{ctx}");
        }
        None => assert!(m.command.text.is_empty(), "{ctx}: unexpected command text"),
    }
    let payload = field_hex(u, "payload_hex");
    assert_eq!(m.payload, payload, "{ctx}: payload");

    // the exact bytes, and our canonical encoding with the recorded block split
    let blocks: Vec<Vec<u8>> = u["blocks_hex"]
        .as_array()
        .map(|a| a.iter().map(|b| unhex(b.as_str().unwrap_or(""))).collect())
        .unwrap_or_default();
    let mut wire_bytes = index_hex.clone();
    blocks.iter().for_each(|b| wire_bytes.extend(b));
    assert_eq!(m.to_wire(), wire_bytes, "{ctx}: to_wire");
    assert_eq!(
        lens.first().copied(),
        Some(m.command.binary_len() as u32),
        "{ctx}: C++ puts the port command (and its text) in the first block"
    );
    let mut split = Vec::new();
    let mut at = 0usize;
    for &l in lens.iter().skip(1) {
        split.push(&payload[at..at + l as usize]);
        at += l as usize;
    }
    let mut enc = Vec::new();
    wire::encode_message(&m.command, &split, &mut enc);
    assert_eq!(
        enc, wire_bytes,
        "{ctx}: encode_message with the recorded blocks"
    );

    // envelopes re-print identically from the parsed Stamp
    if let Some(stamp) = m.stamp() {
        let again = PortCommand::with_stamp(&stamp, m.command.key() == b'd');
        assert_eq!(again, m.command, "{ctx}: envelope text from Stamp");
    }

    let bottle = Bottle::decode(&m.payload).ok();
    if let Some(d) = u["decoded"].as_str() {
        let b = bottle
            .as_ref()
            .unwrap_or_else(|| panic!("{ctx}: payload does not decode"));
        assert_eq!(render(b), d, "{ctx}: decoded");
    }

    // the high-level encoders reproduce C++ exactly for Bottle messages
    let canonical: Option<Vec<u8>> = match (&bottle, m.command.kind()) {
        (_, CommandKind::Close) if m.payload.is_empty() => Some(wire::close_message()),
        _ if m.payload.is_empty() => Some(wire::command_message(&m.command)),
        (Some(b), _) if lens.len() == 2 && b.encode() == m.payload => {
            match (m.command.ch, m.command.kind(), m.stamp()) {
                (0, CommandKind::Data { reply }, Some(s)) => {
                    Some(wire::envelope_message(b, &s, reply))
                }
                (b'D' | b'd', CommandKind::Data { reply }, None) => {
                    Some(wire::data_message(b, reply))
                }
                (b'a', CommandKind::Admin, None) => Some(wire::admin_message(b)),
                _ => None,
            }
        }
        _ => None,
    };
    if let Some(c) = canonical {
        assert_eq!(c, wire_bytes, "{ctx}: high-level encoder");
        stats.canonical_messages += 1;
    }
}

// ---------------------------------------------------------------- connections

/// One TCP connection: c2s and s2c bytes, optionally with recorded units.
fn check_connection(
    ctx: &str,
    c2s: &[u8],
    s2c: &[u8],
    c2s_units: Option<&[Json]>,
    s2c_units: Option<&[Json]>,
    printed: Option<&[String]>,
    stats: &mut Stats,
) {
    stats.connections += 1;
    let mut h8 = [0u8; 8];
    h8.copy_from_slice(&c2s[..8]);
    let header = classify_header(&h8).unwrap_or_else(|e| panic!("{ctx}: {e}"));
    if header.framing() == Framing::Text {
        return check_text_connection(ctx, c2s, s2c, printed, stats);
    }
    let cevs = decode_all_ways(&format!("{ctx} c2s"), || Decoder::accepting(cfg()), c2s);
    let Some(Event::SenderName(name)) = cevs.get(1) else {
        panic!("{ctx}: no sender name in {cevs:?}")
    };
    assert_eq!(
        wire::encode_connection_start(&header.spec, name),
        c2s[..12 + name.len() + 1],
        "{ctx}: re-encoded connection start"
    );
    match c2s_units {
        Some(units) => check_units(&format!("{ctx} c2s"), &cevs, units, stats),
        None => assert_eq!(cevs.len(), 2, "{ctx}: {cevs:?}"),
    }
    let sent = messages(&cevs);
    if let Some(p) = printed {
        if !sent
            .iter()
            .any(|m| m.command.kind() == CommandKind::Describe)
        {
            let data: Vec<String> = sent
                .iter()
                .filter(|m| matches!(m.command.kind(), CommandKind::Data { .. }))
                .map(|m| m.bottle().map(|b| b.to_string()).unwrap_or_default())
                .collect();
            assert_eq!(data, p, "{ctx}: what yarp read printed");
            stats.printed_lines += data.len();
        }
    }
    let sevs = decode_all_ways(
        &format!("{ctx} s2c"),
        || responder(header.spec, &sent, true),
        s2c,
    );
    match s2c_units {
        Some(units) => check_units(&format!("{ctx} s2c"), &sevs, units, stats),
        None => {
            let Some(Event::HeaderReply(port)) = sevs.first() else {
                panic!("{ctx}: no header reply in {sevs:?}")
            };
            assert_eq!(wire::encode_header_reply(*port).as_slice(), s2c, "{ctx}");
        }
    }
}

/// A text / text_ack connection: decode both directions, re-encode them, and check what
/// the C++ reader printed and answered.
fn check_text_connection(
    ctx: &str,
    c2s: &[u8],
    s2c: &[u8],
    printed: Option<&[String]>,
    stats: &mut Stats,
) {
    stats.text_connections += 1;
    let cevs = decode_all_ways(&format!("{ctx} c2s"), || Decoder::accepting(cfg()), c2s);
    let Some(Event::Header(header)) = cevs.first() else {
        panic!("{ctx}: {cevs:?}")
    };
    let with_ack = header.carrier() == Carrier::TextAck;
    let Some(Event::SenderName(name)) = cevs.get(1) else {
        panic!("{ctx}: {cevs:?}")
    };
    let mut again = text_carrier::connect_line(with_ack, name);
    for ev in &cevs[2..] {
        match ev {
            Event::Message(m) => again.extend(m.to_wire()),
            Event::Ack(0) => again.extend_from_slice(text_carrier::ACK_LINE),
            other => panic!("{ctx}: unexpected c2s event {other:?}"),
        }
    }
    let no_cr = |b: &[u8]| {
        b.iter()
            .copied()
            .filter(|&c| c != b'\r')
            .collect::<Vec<u8>>()
    };
    let all_crlf = c2s
        .iter()
        .enumerate()
        .all(|(i, &b)| b != b'\n' || (i > 0 && c2s[i - 1] == b'\r'));
    if all_crlf {
        assert_eq!(again, c2s, "{ctx}: C++ text bytes re-encoded");
    } else {
        assert_eq!(
            no_cr(&again),
            no_cr(c2s),
            "{ctx}: raw client text re-encoded"
        );
    }
    let sent = messages(&cevs);
    for m in &sent {
        stats.units += 1;
        stats.messages += 1;
        if matches!(
            m.command.kind(),
            CommandKind::Data { .. } | CommandKind::Admin
        ) {
            assert!(m.bottle().is_ok(), "{ctx}");
        }
    }
    if let Some(p) = printed {
        let data: Vec<String> = sent
            .iter()
            .filter(|m| matches!(m.command.kind(), CommandKind::Data { .. }))
            .map(|m| m.bottle().map(|b| b.to_string()).unwrap_or_default())
            .collect();
        assert_eq!(data, p, "{ctx}: what yarp read printed");
        stats.printed_lines += data.len();
    }

    let sevs = decode_all_ways(
        &format!("{ctx} s2c"),
        || responder(header.spec, &sent, true),
        s2c,
    );
    let Some(Event::Welcome(w)) = sevs.first() else {
        panic!("{ctx}: no welcome in {sevs:?}")
    };
    assert_eq!(w, name, "{ctx}: the welcome echoes the sender name");
    let mut again = text_carrier::welcome_line(w);
    let mut acks = 0;
    for ev in &sevs[1..] {
        stats.units += 1;
        match ev {
            Event::Line(l) => {
                again.extend_from_slice(l);
                again.extend_from_slice(b"\r\n");
            }
            Event::Ack(0) => {
                acks += 1;
                stats.acks += 1;
                again.extend_from_slice(text_carrier::ACK_LINE);
            }
            Event::Message(m) => {
                stats.messages += 1;
                again.extend(m.to_wire())
            }
            other => panic!("{ctx}: unexpected s2c event {other:?}"),
        }
    }
    assert_eq!(again, s2c, "{ctx}: s2c re-encoded");
    if with_ack && !s2c.is_empty() {
        assert_eq!(acks, sent.len(), "{ctx}: one <ACK> per message");
    }
    let s2c_text = String::from_utf8_lossy(s2c);
    for m in &sent {
        if m.command.kind() == CommandKind::Help {
            assert!(s2c_text.contains(wire::PORT_HELP), "{ctx}: port help text");
        }
    }
}

// ---------------------------------------------------------------- carriers.jsonl

#[test]
fn carriers_jsonl() {
    let recs = load("carriers.jsonl");
    assert_eq!(recs.len(), 24, "carriers.jsonl should hold 24 records");
    let mut stats = Stats::default();
    for rec in &recs {
        let rid = id(rec);
        let printed = strings(&rec["reader_printed"]);
        match rec["kind"].as_str() {
            Some("writer_to_reader") => {
                let conns = rec["connections"].as_array().cloned().unwrap_or_default();
                assert!(!conns.is_empty(), "{rid}");
                for (i, c) in conns.iter().enumerate() {
                    let (c2s, s2c) = directions(&c["events"]);
                    // only the data connection carries what yarp read printed
                    let p = if i == 0 { printed.as_deref() } else { None };
                    check_connection(
                        &format!("{rid} conn {i}"),
                        &c2s,
                        &s2c,
                        c["c2s_units"].as_array().map(Vec::as_slice),
                        c["s2c_units"].as_array().map(Vec::as_slice),
                        p.filter(|_| rec["carrier"] != "udp"),
                        &mut stats,
                    );
                }
            }
            Some("raw_text_client") | Some("raw_tcp_client") | Some("reverse") => {
                let (c2s, s2c) = directions(&rec["events"]);
                check_connection(
                    &rid,
                    &c2s,
                    &s2c,
                    rec["c2s_units"].as_array().map(Vec::as_slice),
                    rec["s2c_units"].as_array().map(Vec::as_slice),
                    printed.as_deref(),
                    &mut stats,
                );
                if rec["kind"] == "reverse" {
                    check_reverse(&rid, &s2c);
                }
            }
            other => panic!("{rid}: unknown kind {other:?}"),
        }
        stats.records += 1;
    }
    report("carriers.jsonl", &stats);
    assert_eq!(stats.records, 24);
}

/// After `r`, the writer port sends its output over the connection in text mode.
fn check_reverse(rid: &str, s2c: &[u8]) {
    let ack = s2c.windows(7).any(|w| w == b"<ACK>\r\n");
    let spec = if ack { Carrier::TextAck } else { Carrier::Text }.spec();
    let mut d = Decoder::connecting(spec, cfg());
    d.expect_response(&PortCommand::from_line("r"));
    let evs = d.decode(s2c).unwrap_or_else(|e| panic!("{rid}: {e}"));
    let data: Vec<String> = messages(&evs)
        .iter()
        .map(|m| m.bottle().map(|b| b.to_string()).unwrap_or_default())
        .collect();
    assert_eq!(data, ["reversed 1 2.5", "second [ok]"], "{rid}");
    // what yarp write sends over a reversed text connection
    let expect: Vec<u8> = [
        text_carrier::data_message(&Bottle::from_text("reversed 1 2.5"), false),
        text_carrier::data_message(&Bottle::from_text("second [ok]"), false),
    ]
    .concat();
    let without_acks: Vec<u8> = String::from_utf8_lossy(s2c)
        .split_once("\r\n")
        .map(|(_, rest)| rest.replace("<ACK>\r\n", "").into_bytes())
        .unwrap_or_default();
    assert_eq!(without_acks, expect, "{rid}");
}

// ---------------------------------------------------------------- device recordings

fn unit_bytes(u: &Json) -> Vec<u8> {
    match u["unit"].as_str() {
        Some("message") => {
            let mut b = field_hex(u, "index_hex");
            for blk in u["blocks_hex"]
                .as_array()
                .map(Vec::as_slice)
                .unwrap_or_default()
            {
                b.extend(unhex(blk.as_str().unwrap_or("")));
            }
            b
        }
        Some("reply") => field_hex(u, "payload_hex"),
        _ => field_hex(u, "hex"),
    }
}

fn arr(v: &Json) -> &[Json] {
    v.as_array().map(Vec::as_slice).unwrap_or_default()
}

fn check_device_file(file: &str, stats: &mut Stats) {
    let recs = load(file);
    // C++ client transcripts, grouped per (kind, port, connection), units in order
    type Key = (String, String, i64);
    let mut groups: BTreeMap<Key, (Vec<Json>, Vec<Json>)> = BTreeMap::new();
    for rec in &recs {
        let rid = id(rec);
        match rec["kind"].as_str() {
            Some("cpp_client") | Some("cpp_client_tcp") => {
                for u in arr(&rec["units"]) {
                    let key = (
                        rec["kind"].as_str().unwrap_or("").to_string(),
                        u["port"].as_str().unwrap_or("").to_string(),
                        u["conn"].as_i64().unwrap_or(-1),
                    );
                    let g = groups.entry(key).or_default();
                    match u["dir"].as_str() {
                        Some("c2s") => g.0.push(u.clone()),
                        Some("s2c") => g.1.push(u.clone()),
                        d => panic!("{rid}: unit without direction {d:?}"),
                    }
                }
            }
            Some("yarp_rpc") => {
                let req = arr(&rec["request"]);
                let rep = arr(&rec["reply"]);
                let req_bytes = field_hex(rec, "request_hex");
                let rep_bytes = field_hex(rec, "reply_hex");
                assert_eq!(
                    req_bytes,
                    req.iter().flat_map(unit_bytes).collect::<Vec<_>>()
                );
                assert_eq!(
                    rep_bytes,
                    rep.iter().flat_map(unit_bytes).collect::<Vec<_>>()
                );
                let spec = Carrier::Tcp.spec();
                let evs = decode_all_ways(&rid, || Decoder::messages(spec, cfg()), &req_bytes);
                check_units(&format!("{rid} request"), &evs, req, stats);
                let sent = messages(&evs);
                let revs = decode_all_ways(&rid, || responder(spec, &sent, false), &rep_bytes);
                check_units(&format!("{rid} reply"), &revs, rep, stats);
            }
            Some("yarp_rpc_connection") => {
                let c2s = field_hex(rec, "c2s_hex");
                let s2c = field_hex(rec, "s2c_hex");
                check_connection(
                    &rid,
                    &c2s,
                    &s2c,
                    rec["c2s_units"].as_array().map(Vec::as_slice),
                    rec["s2c_units"].as_array().map(Vec::as_slice),
                    None,
                    stats,
                );
            }
            Some("stream_connection") => {
                let (c2s, s2c) = directions(&rec["events"]);
                check_connection(&rid, &c2s, &s2c, None, None, None, stats);
            }
            Some("stream") => {
                let mut unit = rec.clone();
                unit["unit"] = Json::from("message");
                let bytes = unit_bytes(&unit);
                let evs = decode_all_ways(
                    &rid,
                    || Decoder::messages(Carrier::Tcp.spec(), cfg()),
                    &bytes,
                );
                check_units(&rid, &evs, std::slice::from_ref(&unit), stats);
                let stamp = messages(&evs).first().and_then(|m| m.stamp());
                assert!(stamp.is_some(), "{rid}: streams carry an envelope");
            }
            Some("stream_text") => {}
            other => panic!("{rid}: unknown kind {other:?}"),
        }
        stats.records += 1;
    }
    for ((kind, port, conn), (c2s_u, s2c_u)) in &groups {
        let ctx = format!("{file} {kind} {port} conn {conn}");
        let c2s: Vec<u8> = c2s_u.iter().flat_map(unit_bytes).collect();
        let s2c: Vec<u8> = s2c_u.iter().flat_map(unit_bytes).collect();
        let raw = c2s_u.iter().chain(s2c_u).all(|u| u["unit"] == "raw");
        if raw {
            check_connection(&ctx, &c2s, &s2c, None, None, None, stats);
        } else {
            check_connection(&ctx, &c2s, &s2c, Some(c2s_u), Some(s2c_u), None, stats);
        }
    }
}

#[test]
fn device_units() {
    let mut total = Stats::default();
    for file in ["controlboard.jsonl", "framegrabber.jsonl", "imu.jsonl"] {
        let mut stats = Stats::default();
        check_device_file(file, &mut stats);
        report(file, &stats);
        assert!(
            stats.records > 0 && stats.messages > 0,
            "{file}: nothing checked"
        );
        total.records += stats.records;
        total.messages += stats.messages;
    }
    assert!(
        total.records >= 150,
        "only {} device records",
        total.records
    );
}

#[test]
fn python_repr_matches_recorder() {
    assert_eq!(py_repr(2.5), "2.5");
    assert_eq!(py_repr(1.0), "1.0");
    assert_eq!(py_repr(1795298219.8398943), "1795298219.8398943");
    assert_eq!(py_repr(6.901573306687e-310), "6.901573306687e-310");
    assert_eq!(py_repr(1e16), "1e+16");
    assert_eq!(py_repr(0.0001), "0.0001");
    assert_eq!(py_repr(0.00001), "1e-05");
    assert_eq!(py_repr(-90.0), "-90.0");
    assert_eq!(py_repr(123456789012345.6), "123456789012345.6");
}

#[test]
fn stamp_envelopes_from_vectors() {
    // the envelope text of recorded streams parses as a Stamp and prints back identically
    let mut n = 0;
    for file in ["controlboard.jsonl", "framegrabber.jsonl", "imu.jsonl"] {
        for rec in load(file) {
            if let Some(t) = rec["port_command_text"].as_str() {
                let cmd = PortCommand::text(t.as_bytes().to_vec());
                let s: Stamp = cmd.stamp().unwrap_or_else(|| panic!("{}: {t}", id(&rec)));
                assert_eq!(PortCommand::with_stamp(&s, false), cmd);
                n += 1;
            }
        }
    }
    assert!(n >= 6, "only {n} envelopes");
}

// ---------------------------------------------------------------- name server

/// A C++ client's `NAME_SERVER <command>` connection (no CONNECT header).
fn check_name_server_connection(ctx: &str, c2s: &[u8], s2c: &[u8], stats: &mut Stats) {
    stats.connections += 1;
    let cevs = decode_all_ways(&format!("{ctx} c2s"), || Decoder::accepting(cfg()), c2s);
    let Some(Event::Header(h)) = cevs.first() else {
        panic!("{ctx}: {cevs:?}")
    };
    assert_eq!(h.carrier(), Carrier::NameSer, "{ctx}");
    let mut again = Vec::new();
    for m in messages(&cevs) {
        stats.messages += 1;
        let line = String::from_utf8_lossy(&m.payload).into_owned();
        again.extend(wire::name_server_request(&line, "\n"));
    }
    let no_cr = |b: &[u8]| {
        b.iter()
            .copied()
            .filter(|&c| c != b'\r')
            .collect::<Vec<u8>>()
    };
    assert_eq!(again, no_cr(c2s), "{ctx}: re-encoded request");
    let sevs = decode_all_ways(
        &format!("{ctx} s2c"),
        || Decoder::connecting(Carrier::NameSer.spec(), cfg()),
        s2c,
    );
    let mut again = Vec::new();
    for ev in &sevs {
        stats.units += 1;
        let Event::Line(l) = ev else {
            panic!("{ctx}: unexpected {ev:?}")
        };
        again.extend_from_slice(l);
        again.extend_from_slice(b"\r\n");
    }
    assert_eq!(again, s2c, "{ctx}: re-encoded answer");
}

#[test]
fn nameserver_transcripts() {
    let mut stats = Stats::default();
    for rec in load("nameserver.jsonl") {
        let rid = id(&rec);
        match rec["kind"].as_str() {
            Some("text_session") => {
                let (c2s, s2c) = directions(&rec["events"]);
                check_connection(&rid, &c2s, &s2c, None, None, None, &mut stats);
            }
            Some("client_capture") => {
                for (i, conn) in arr(&rec["connections"]).iter().enumerate() {
                    let (c2s, s2c) = directions(conn);
                    if c2s.len() < 8 {
                        // `yarp detect` pings with 5 bytes, `yarp where` sends nothing
                        continue;
                    }
                    check_name_server_connection(
                        &format!("{rid} conn {i}"),
                        &c2s,
                        &s2c,
                        &mut stats,
                    );
                }
            }
            other => panic!("{rid}: unknown kind {other:?}"),
        }
        stats.records += 1;
    }
    report("nameserver.jsonl", &stats);
    assert!(stats.connections > 30, "{stats:?}");
}
