//! Decoder tests: round trips, segmentation independence, hostile input.

use super::*;
use crate::{bottle, Bottle, Stamp, Value};

fn cfg() -> DecoderConfig {
    DecoderConfig::default()
}

/// Decodes `bytes` whole and one byte at a time; both must give the same events.
fn both_ways(mut make: impl FnMut() -> Decoder, bytes: &[u8]) -> Result<Vec<Event>, WireError> {
    let whole = make().decode(bytes);
    let mut d = make();
    let mut split = Vec::new();
    let mut err = None;
    for b in bytes {
        match d.decode(std::slice::from_ref(b)) {
            Ok(evs) => split.extend(evs),
            Err(e) => {
                err = Some(e);
                break;
            }
        }
    }
    match (whole, err) {
        (Ok(w), None) => {
            assert_eq!(w, split);
            Ok(w)
        }
        (Err(a), Some(b)) => {
            assert_eq!(a, b);
            Err(a)
        }
        (w, e) => panic!("whole {w:?} vs split error {e:?}"),
    }
}

#[test]
fn tcp_session_round_trip() {
    let mut c2s = encode_connection_start(&Carrier::Tcp.spec(), b"/w");
    c2s.extend(data_message(&bottle!["hello", 42], false));
    c2s.extend(envelope_message(
        &bottle![1.5],
        &Stamp::new(7, 1795297706.58327),
        false,
    ));
    c2s.extend(admin_message(&bottle![crate::Vocab32::new("help")]));
    c2s.extend(close_message());
    let evs = both_ways(|| Decoder::accepting(cfg()), &c2s).unwrap();
    assert_eq!(evs.len(), 6);
    assert!(
        matches!(&evs[0], Event::Header(h) if h.carrier() == Carrier::Tcp && h.value() == Some(7908))
    );
    let msgs: Vec<&Message> = evs
        .iter()
        .filter_map(|e| match e {
            Event::Message(m) => Some(m),
            _ => None,
        })
        .collect();
    assert_eq!(msgs[0].command.kind(), CommandKind::Data { reply: false });
    assert_eq!(msgs[1].stamp(), Some(Stamp::new(7, 1795297706.58327)));
    assert_eq!(msgs[1].bottle().unwrap(), bottle![1.5]);
    assert_eq!(msgs[2].command.kind(), CommandKind::Admin);
    assert_eq!(msgs[3].command.kind(), CommandKind::Close);
    let rewired: Vec<u8> = msgs.iter().flat_map(|m| m.to_wire()).collect();
    assert_eq!(rewired, c2s[15..]);

    // the other direction: header reply, ack, ack, reply+ack, ack
    let mut s2c = encode_header_reply(10002).to_vec();
    s2c.extend(ack());
    s2c.extend(ack());
    s2c.extend(reply_message(&bottle!["/w"], true));
    s2c.extend(ack());
    let make = || {
        let mut d = Decoder::connecting(Carrier::Tcp.spec(), cfg());
        for m in &msgs {
            d.expect_response(&m.command);
        }
        d
    };
    let evs = both_ways(make, &s2c).unwrap();
    assert_eq!(
        evs,
        [
            Event::HeaderReply(10002),
            Event::Ack(0),
            Event::Ack(0),
            Event::Reply(bottle!["/w"].encode()),
            Event::Ack(0),
            Event::Ack(0),
        ]
    );
}

#[test]
fn missing_reply_is_an_ack() {
    let mut d = Decoder::responses(Carrier::Tcp.spec(), cfg());
    d.expect_response(&PortCommand::data(true));
    d.expect_response(&PortCommand::data(true));
    let mut s2c = ack().to_vec();
    s2c.extend(reply_message(&bottle![1], true));
    let evs = d.decode(&s2c).unwrap();
    assert_eq!(
        evs,
        [
            Event::Ack(0),
            Event::Reply(bottle![1].encode()),
            Event::Ack(0)
        ]
    );
}

#[test]
fn fast_tcp_reply_without_ack_and_ack_payload_skip() {
    let mut d = Decoder::responses(Carrier::FastTcp.spec(), cfg());
    d.expect_response(&PortCommand::data(true));
    d.expect_response(&PortCommand::data(false));
    let evs = d.decode(&reply_message(&bottle![2], false)).unwrap();
    assert_eq!(evs, [Event::Reply(bottle![2].encode())]);
    // an ack announcing 3 bytes: they are skipped
    let mut bytes = message::ack_with_len(3).to_vec();
    bytes.extend_from_slice(b"xyz");
    bytes.extend(ack());
    let mut d = Decoder::responses(Carrier::Tcp.spec(), cfg());
    assert_eq!(d.decode(&bytes).unwrap(), [Event::Ack(3), Event::Ack(0)]);
    assert!(d.is_idle());
}

#[test]
fn binary_reverse() {
    // we send 'r' on tcp: after its ack the peer writes messages to us
    let mut d = Decoder::connecting(Carrier::Tcp.spec(), cfg());
    d.expect_response(&PortCommand::text("r"));
    let mut s2c = encode_header_reply(5).to_vec();
    s2c.extend(ack());
    s2c.extend(data_message(&bottle![1, 2], false));
    let evs = d.decode(&s2c).unwrap();
    assert_eq!(evs.len(), 3);
    assert!(matches!(&evs[2], Event::Message(m) if m.bottle() == Ok(bottle![1, 2])));
    // and the accepting side, after reading 'r', reads acks
    let mut c2s = encode_connection_start(&Carrier::Tcp.spec(), b"/x");
    c2s.extend(command_message(&PortCommand::text("r")));
    c2s.extend(ack());
    let evs = Decoder::accepting(cfg()).decode(&c2s).unwrap();
    assert_eq!(evs.last(), Some(&Event::Ack(0)));
}

#[test]
fn text_sessions() {
    let c2s = b"CONNACK /raw\na\n[list] [in]\nd\n(1 2\n3)\nD 3 1.5\nhello\\\n world\nq\n<ACK>\r\n";
    let evs = both_ways(|| Decoder::accepting(cfg()), c2s).unwrap();
    assert!(matches!(&evs[0], Event::Header(h) if h.carrier() == Carrier::TextAck));
    assert_eq!(evs[1], Event::SenderName(b"/raw".to_vec()));
    let Event::Message(m) = &evs[2] else { panic!() };
    assert_eq!(
        (m.command.kind(), m.payload.as_slice()),
        (CommandKind::Admin, &b"[list] [in]"[..])
    );
    let Event::Message(m) = &evs[3] else { panic!() };
    assert_eq!(m.payload, b"(1 2\n3)");
    assert_eq!(m.bottle().unwrap().to_string(), "(1 2 3)");
    let Event::Message(m) = &evs[4] else { panic!() };
    assert_eq!(m.payload, b"hello world");
    assert_eq!(m.stamp(), Some(Stamp::new(3, 1.5)));
    let Event::Message(m) = &evs[5] else { panic!() };
    assert_eq!(m.command.kind(), CommandKind::Close);
    assert_eq!(evs[6], Event::Ack(0));

    let s2c = b"Welcome /raw\r\n\"/w\"\r\n<ACK>\r\n";
    let make = || {
        let mut d = Decoder::connecting(Carrier::TextAck.spec(), cfg());
        d.expect_response(&PortCommand::from_line("a"));
        d
    };
    assert_eq!(
        both_ways(make, s2c).unwrap(),
        [
            Event::Welcome(b"/raw".to_vec()),
            Event::Line(b"\"/w\"".to_vec()),
            Event::Ack(0)
        ]
    );
}

#[test]
fn name_server_lines() {
    let c2s = b"NAME_SERVER query /r\nNAME_SERVER register /x\r\n";
    let evs = both_ways(|| Decoder::accepting(cfg()), c2s).unwrap();
    assert!(matches!(&evs[0], Event::Header(h) if h.carrier() == Carrier::NameSer));
    let lines: Vec<Vec<u8>> = evs
        .iter()
        .filter_map(|e| match e {
            Event::Message(m) => Some(m.payload.clone()),
            _ => None,
        })
        .collect();
    assert_eq!(lines, [b"query /r".to_vec(), b"register /x".to_vec()]);
    assert_eq!(
        name_server_request("query /r", "\n"),
        b"NAME_SERVER query /r\n"
    );
}

#[test]
fn handshake_only_carriers_pass_bytes_through() {
    let mut c2s = encode_connection_start(&Carrier::Udp.spec(), b"/w");
    c2s.extend_from_slice(b"anything");
    let evs = Decoder::accepting(cfg()).decode(&c2s).unwrap();
    assert_eq!(evs.len(), 3);
    assert_eq!(evs[2], Event::Raw(b"anything".to_vec()));
    let mut d = Decoder::connecting(Carrier::Udp.spec(), cfg());
    assert_eq!(
        d.decode(&encode_header_reply(50071)).unwrap(),
        [Event::HeaderReply(50071)]
    );
    let evs = Decoder::accepting(cfg())
        .decode(b"GET /data=list HTTP/1.0\r\n")
        .unwrap();
    assert!(matches!(&evs[0], Event::Header(h) if h.carrier() == Carrier::Http));
}

// ---- hostile input ----

#[test]
fn garbage_header_is_unknown_protocol() {
    let err = Decoder::accepting(cfg())
        .decode(b"\x16\x03\x01\x02\x00\x01\x00\x01")
        .unwrap_err();
    assert!(matches!(err, WireError::UnknownProtocol { .. }));
    // short garbage just waits
    let mut d = Decoder::accepting(cfg());
    assert_eq!(d.decode(b"ping\n").unwrap(), []);
    assert!(!d.is_idle());
    // errors are sticky
    let mut d = Decoder::accepting(cfg());
    assert!(d.decode(b"xxxxxxxx").is_err());
    assert!(d.poll().is_err());
}

fn tcp_after_handshake() -> Vec<u8> {
    encode_connection_start(&Carrier::Tcp.spec(), b"/evil")
}

#[test]
fn huge_lengths_error_without_allocating() {
    // index announcing one block of i32::MAX and another: 4 GiB total
    let mut bytes = tcp_after_handshake();
    bytes.extend_from_slice(&number::INDEX_MARKER);
    bytes.extend_from_slice(&[2, 1, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff]);
    bytes.extend_from_slice(&i32::MAX.to_le_bytes());
    bytes.extend_from_slice(&i32::MAX.to_le_bytes());
    bytes.extend_from_slice(&0i32.to_le_bytes());
    let err = both_ways(|| Decoder::accepting(cfg()), &bytes).unwrap_err();
    assert!(matches!(
        err,
        WireError::TooLarge {
            size: 4294967294,
            ..
        }
    ));

    // within the limit: waits for the data, nothing reserved up front
    let small = DecoderConfig {
        max_message_size: 1 << 20,
        ..DecoderConfig::default()
    };
    let mut bytes = tcp_after_handshake();
    bytes.extend_from_slice(&number::INDEX_MARKER);
    bytes.extend_from_slice(&[1, 1, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff]);
    bytes.extend_from_slice(&(1_000_000i32).to_le_bytes());
    bytes.extend_from_slice(&0i32.to_le_bytes());
    bytes.extend_from_slice(b"short");
    let mut d = Decoder::accepting(small.clone());
    assert_eq!(d.decode(&bytes).unwrap().len(), 2);
    assert!(!d.is_idle());
    assert!(d.buf.capacity() < 4096);

    // negative block length
    let mut bytes = tcp_after_handshake();
    bytes.extend_from_slice(&number::INDEX_MARKER);
    bytes.extend_from_slice(&[1, 1, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff]);
    bytes.extend_from_slice(&(-8i32).to_le_bytes());
    bytes.extend_from_slice(&0i32.to_le_bytes());
    assert!(matches!(
        Decoder::accepting(cfg()).decode(&bytes),
        Err(WireError::NegativeBlockLength { block: 0, len: -8 })
    ));

    // a reply claiming a 2 GiB string with a 1 MiB limit
    let mut d = Decoder::responses(Carrier::Tcp.spec(), small.clone());
    d.expect_response(&PortCommand::data(true));
    let evil = [0, 1, 0, 0, 1, 0, 0, 0, 4, 0, 0, 0, 0xff, 0xff, 0xff, 0x7f];
    assert!(matches!(
        d.decode(&evil),
        Err(WireError::TooLarge { what: "reply", .. })
    ));
    // an ack announcing a huge payload
    let mut d = Decoder::responses(Carrier::Tcp.spec(), small.clone());
    assert!(d.decode(&message::ack_with_len(i32::MAX)).is_err());
    // a text line without end
    let tiny = DecoderConfig {
        max_line_len: 64,
        ..DecoderConfig::default()
    };
    let mut d = Decoder::accepting(tiny);
    let mut line = b"CONNECT ".to_vec();
    line.extend(vec![b'a'; 100]);
    assert!(matches!(
        d.decode(&line),
        Err(WireError::TooLarge {
            what: "text line",
            ..
        })
    ));
    // an endless multi-line bottle text
    let mut d = Decoder::accepting(small);
    d.feed(b"CONNECT /x\nd\n(");
    let chunk = vec![b'x'; 1000];
    let mut failed = false;
    for _ in 0..2000 {
        d.feed(&chunk);
        d.feed(b"\n");
        if let Err(e) = d.decode(b"") {
            assert!(matches!(
                e,
                WireError::TooLarge {
                    what: "text message",
                    ..
                }
            ));
            failed = true;
            break;
        }
    }
    assert!(failed);
}

#[test]
fn truncated_and_malformed_frames() {
    let full = {
        let mut b = tcp_after_handshake();
        b.extend(data_message(&bottle![1, 2, 3], false));
        b
    };
    // every truncation waits (never errors, never panics)
    for n in 0..full.len() {
        let mut d = Decoder::accepting(cfg());
        let evs = d.decode(&full[..n]).unwrap();
        assert!(evs.len() <= 2);
        assert_eq!(d.is_idle(), [0, 8, 18].contains(&n), "{n}");
    }
    // not an index after the handshake
    let mut bytes = tcp_after_handshake();
    bytes.extend_from_slice(b"YA\x0b\0\0\0RP");
    assert!(matches!(
        Decoder::accepting(cfg()).decode(&bytes),
        Err(WireError::BadIndex { .. })
    ));
    // well-framed message with a bad port command: reported, stream continues
    let mut bytes = tcp_after_handshake();
    let mut idx = Vec::new();
    Index::new(vec![4]).encode(&mut idx);
    bytes.extend(idx);
    bytes.extend_from_slice(b"abcd");
    bytes.extend(data_message(&bottle![7], false));
    let evs = both_ways(|| Decoder::accepting(cfg()), &bytes).unwrap();
    assert!(matches!(
        &evs[2],
        Event::InvalidMessage {
            error: WireError::ShortPortCommand { len: 4 },
            ..
        }
    ));
    assert!(matches!(&evs[3], Event::Message(m) if m.bottle() == Ok(bottle![7])));
    // a reply that is not a Bottle
    let mut d = Decoder::responses(Carrier::Tcp.spec(), cfg());
    d.expect_response(&PortCommand::data(true));
    assert!(matches!(
        d.decode(&[0, 1, 0, 0, 1, 0, 0, 0, 0x33, 0, 0, 0]),
        Err(WireError::BadReply(_))
    ));
    // garbage where an ack belongs
    let mut d = Decoder::responses(Carrier::Tcp.spec(), cfg());
    assert!(matches!(
        d.decode(b"garbage!"),
        Err(WireError::BadAck { .. })
    ));
    // sender name length is clamped like C++ (no 2 GiB read)
    let mut bytes = Carrier::Tcp.header().to_vec();
    bytes.extend_from_slice(&i32::MAX.to_le_bytes());
    bytes.extend(vec![b'n'; 1000]);
    let evs = Decoder::accepting(cfg()).decode(&bytes).unwrap();
    assert!(matches!(&evs[1], Event::SenderName(n) if n.len() == 1000));
}

#[test]
fn random_bytes_never_panic() {
    // a tiny xorshift generator: deterministic pseudo-random streams
    let mut x: u64 = 0x9e3779b97f4a7c15;
    let mut next = move || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        x
    };
    let prefixes: [&[u8]; 4] = [&Carrier::Tcp.header(), b"CONNECT ", b"NAME_SER", &[]];
    for round in 0..400 {
        let mut bytes = prefixes[round % 4].to_vec();
        let len = (next() % 300) as usize;
        for _ in 0..len {
            // bias towards small numbers and framing bytes
            let r = next();
            bytes.push(match r % 5 {
                0 => 0,
                1 => 0xff,
                2 => b"YARP~\n\\(\"D"[(r >> 8) as usize % 10],
                _ => (r >> 16) as u8,
            });
        }
        let small = DecoderConfig {
            max_message_size: 4096,
            max_line_len: 4096,
            ..DecoderConfig::default()
        };
        let _ = both_ways(|| Decoder::accepting(small.clone()), &bytes);
        let _ = both_ways(
            || {
                let mut d = Decoder::connecting(Carrier::Tcp.spec(), small.clone());
                d.expect_response(&PortCommand::data(true));
                d
            },
            &bytes,
        );
    }
}

#[test]
fn encoders_match_recorded_cpp_bytes() {
    fn hex(b: &[u8]) -> String {
        b.iter().map(|x| format!("{x:02x}")).collect()
    }
    assert_eq!(
        hex(&encode_connection_start(&Carrier::Tcp.spec(), b"/w")),
        "5941e41e00005250030000002f7700"
    );
    assert_eq!(
        hex(&encode_connection_start(&Carrier::FastTcp.spec(), b"/w")),
        "5941641e00005250030000002f7700"
    );
    assert_eq!(
        hex(&encode_connection_start(&Carrier::Udp.spec(), b"/w")),
        "5941611e00005250030000002f7700"
    );
    assert_eq!(hex(&encode_header_reply(10002)), "5941122700005250");
    assert_eq!(hex(&ack()), "5941000000005250");
    let b = Bottle::from_text("1 2.5 [ok] \"two words\" (3 4)");
    assert_eq!(
        hex(&data_message(&b, false)),
        "59410a00000052500201ffffffffffffffff080000004500000000000000000000007e440001\
         000100000500000001000000010000000a0000000000000000000440090000006f6b0000040000\
         000900000074776f20776f72647301010000020000000300000004000000"
    );
    assert_eq!(
        text_carrier::data_message(&b, false),
        b"D\r\n1 2.5 [ok] \"two words\" (3 4)\r\n"
    );
}

/// Reads `bytes` through [`Decoder::read_buf`] as a socket would, `chunk` bytes at most
/// per read; returns the events and the buffers read into (to check for copies).
fn read_through(
    d: &mut Decoder,
    mut bytes: &[u8],
    chunk: usize,
) -> Result<(Vec<Event>, Vec<*const u8>), WireError> {
    use bytes::BufMut;
    let mut events = Vec::new();
    let mut bufs = Vec::new();
    while !bytes.is_empty() {
        let mut space = d.read_buf(chunk);
        assert!(space.remaining_mut() >= chunk);
        let n = chunk.min(bytes.len());
        space.put_slice(&bytes[..n]);
        bytes = &bytes[n..];
        bufs.push(d.buf.as_ptr());
        while let Some(ev) = d.poll()? {
            events.push(ev);
        }
    }
    Ok((events, bufs))
}

fn big_blob(len: usize) -> Vec<u8> {
    (0..len).map(|i| (i * 7 + i / 251) as u8).collect()
}

#[test]
fn read_buf_hands_out_large_messages_without_copying() {
    let mut big = bottle![1, "x"];
    big.push(Value::Blob(big_blob(300_000)));
    let mut bytes = encode_connection_start(&Carrier::Tcp.spec(), b"/w");
    bytes.extend(data_message(&big, false));
    bytes.extend(data_message(&bottle!["small"], false));
    bytes.extend(envelope_message(&big, &Stamp::new(3, 1.25), true));
    // a 'd' with command text (NUL-terminated) and a large payload
    encode_message(
        &PortCommand::new(0, b"d".to_vec()),
        &[&big.encode()],
        &mut bytes,
    );
    // a well-framed large body with an unusable command
    Index::new(vec![70_000]).encode(&mut bytes);
    bytes.extend(vec![b'z'; 70_000]);
    bytes.extend(data_message(&big, false));
    let whole = Decoder::accepting(cfg()).decode(&bytes).unwrap();
    assert_eq!(whole.len(), 8);
    for chunk in [1000, 4096, 65_536, 1 << 20] {
        let mut d = Decoder::accepting(cfg());
        let (evs, bufs) = read_through(&mut d, &bytes, chunk).unwrap();
        assert_eq!(evs, whole, "chunk {chunk}");
        assert!(d.is_idle());
        for ev in &evs {
            if let Event::Message(m) = ev {
                if m.payload.len() > 100_000 && chunk < 300_000 {
                    assert!(bufs.contains(&m.payload.as_ptr()), "chunk {chunk}: copied");
                }
            }
        }
    }
    // also the same one byte at a time through `feed`
    assert_eq!(
        both_ways(|| Decoder::accepting(cfg()), &bytes[..bytes.len() / 3]).unwrap(),
        Decoder::accepting(cfg())
            .decode(&bytes[..bytes.len() / 3])
            .unwrap()
    );
}

#[test]
fn read_buf_hands_out_large_replies_without_copying() {
    let mut big = bottle![7, 8];
    big.push(Value::Blob(big_blob(500_000)));
    big.push(2.5);
    let mut bytes = reply_message(&big, true);
    bytes.extend(reply_message(&bottle![1], true));
    bytes.extend(reply_message(&big, false));
    let make = || {
        let mut d = Decoder::responses(Carrier::Tcp.spec(), cfg());
        d.expect_response(&PortCommand::data(true));
        d.expect_response(&PortCommand::data(true));
        d.expect_response(&PortCommand::data(true));
        d
    };
    let whole = make().decode(&bytes).unwrap();
    assert_eq!(whole.len(), 5);
    for chunk in [1000, 65_536, 1 << 20] {
        let mut d = make();
        let (evs, bufs) = read_through(&mut d, &bytes, chunk).unwrap();
        assert_eq!(evs, whole, "chunk {chunk}");
        let Event::Reply(r) = &evs[0] else { panic!() };
        if chunk < 500_000 {
            assert!(bufs.contains(&r.as_ptr()), "chunk {chunk}: copied");
        }
        assert_eq!(Bottle::decode_owned(r.clone()).unwrap(), big);
    }
}

#[test]
fn reversed_connection_after_a_large_message() {
    let mut bytes = encode_connection_start(&Carrier::Tcp.spec(), b"/w");
    encode_message(
        &PortCommand::new(b'r', Vec::new()),
        &[&[9u8; 100_000]],
        &mut bytes,
    );
    bytes.extend(ack());
    let whole = Decoder::accepting(cfg()).decode(&bytes).unwrap();
    assert_eq!(whole.last(), Some(&Event::Ack(0)));
    let (evs, _) = read_through(&mut Decoder::accepting(cfg()), &bytes, 5000).unwrap();
    assert_eq!(evs, whole);
}

#[test]
fn read_buf_reserves_only_verified_sizes() {
    let small = DecoderConfig {
        max_message_size: 1 << 20,
        ..DecoderConfig::default()
    };
    // a body within the limit: room for it once its index is in
    let mut bytes = tcp_after_handshake();
    bytes.extend_from_slice(&number::INDEX_MARKER);
    bytes.extend_from_slice(&[1, 1, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff]);
    bytes.extend_from_slice(&(1_000_000i32).to_le_bytes());
    bytes.extend_from_slice(&0i32.to_le_bytes());
    bytes.extend_from_slice(b"0000~d\0\x01short");
    let mut d = Decoder::accepting(small.clone());
    let (evs, _) = read_through(&mut d, &bytes, 512).unwrap();
    assert_eq!(evs.len(), 2);
    assert!(!d.is_idle());
    let cap = d.read_buf(512).len();
    assert!((1_000_000 - 13..=1_000_000 + 1024).contains(&cap), "{cap}");
    // a body over the limit: an error, nothing reserved
    let mut bytes = tcp_after_handshake();
    bytes.extend_from_slice(&number::INDEX_MARKER);
    bytes.extend_from_slice(&[1, 1, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff]);
    bytes.extend_from_slice(&(2_000_000i32).to_le_bytes());
    bytes.extend_from_slice(&0i32.to_le_bytes());
    let mut d = Decoder::accepting(small.clone());
    assert!(matches!(
        read_through(&mut d, &bytes, 512),
        Err(WireError::TooLarge { .. })
    ));
    assert!(d.read_buf(512).len() < 4096);
    // a reply claiming a 2 GiB string
    let mut d = Decoder::responses(Carrier::Tcp.spec(), small.clone());
    d.expect_response(&PortCommand::data(true));
    let evil = [0, 1, 0, 0, 1, 0, 0, 0, 4, 0, 0, 0, 0xff, 0xff, 0xff, 0x7f];
    assert!(read_through(&mut d, &evil, 512).is_err());
    assert!(d.read_buf(512).len() < 4096);
    // a reply claiming 900 kB: room for that, not more
    let mut d = Decoder::responses(Carrier::Tcp.spec(), small);
    d.expect_response(&PortCommand::data(true));
    let claim = [0, 1, 0, 0, 1, 0, 0, 0, 4, 0, 0, 0, 0xa0, 0xbb, 0x0d, 0];
    read_through(&mut d, &claim, 512).unwrap();
    let cap = d.read_buf(512).len();
    assert!((900_000..=900_000 + 1024).contains(&cap), "{cap}");
}

#[test]
fn random_large_frames_never_panic() {
    let mut x: u64 = 0x2545f4914f6cdd1d;
    let mut next = move || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        x
    };
    let mut big = bottle!["a", 1];
    big.push(Value::Blob(big_blob(70_000)));
    let mut base = tcp_after_handshake();
    base.extend(data_message(&big, true));
    base.extend(envelope_message(&big, &Stamp::new(1, 2.0), false));
    let reply = reply_message(&big, true);
    for round in 0..300 {
        for bytes in [&base, &reply] {
            let mut bytes = bytes.clone();
            for _ in 0..(next() % 4) {
                let at = (next() as usize) % bytes.len().min(200);
                bytes[at] = next() as u8;
            }
            bytes.truncate(bytes.len() - (next() as usize) % 100_000.min(bytes.len()));
            let small = DecoderConfig {
                max_message_size: 100_000 + (next() % 100_000) as usize,
                ..DecoderConfig::default()
            };
            let chunk = 1 + (next() % 70_000) as usize;
            let make: Box<dyn Fn() -> Decoder> = if round % 2 == 1 {
                Box::new(|| Decoder::accepting(small.clone()))
            } else {
                Box::new(|| {
                    let mut d = Decoder::responses(Carrier::Tcp.spec(), small.clone());
                    d.expect_response(&PortCommand::data(true));
                    d
                })
            };
            let whole = make().decode(&bytes);
            let read = read_through(&mut make(), &bytes, chunk).map(|(e, _)| e);
            match (&whole, &read) {
                (Ok(a), Ok(b)) => assert_eq!(a, b),
                (Err(a), Err(b)) => assert_eq!(a, b),
                // events before the error are not returned by `decode`
                (Err(_), Ok(_)) | (Ok(_), Err(_)) => panic!("{whole:?} vs {read:?}"),
            }
        }
    }
}

/// Found by the `wire_decode` fuzz target: a text payload ending in an escaped backslash
/// followed by an empty line used to index past the end of the joined text.
#[test]
fn text_payload_backslash_then_empty_line_does_not_panic() {
    let input = b"CONNACK /ra;;;;;\nD\r\nHeLlo\\\\\\\n\n\n\n\n\n\n\n\n\n\xf4\xf5\xdd\xf5\n\nr]\n";
    let mut d = Decoder::accepting(DecoderConfig::default());
    let _ = d.decode(input);
    let mut d = Decoder::accepting(DecoderConfig::default());
    for b in input.iter() {
        let _ = d.decode(std::slice::from_ref(b));
    }
}
