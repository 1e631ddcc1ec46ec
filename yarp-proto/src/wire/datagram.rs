//! Sans-I/O framing of the udp and mcast carriers: C++ `DgramTwoWayStream`, byte-exact
//! with C++ YARP 3.12.
//!
//! # The connection
//!
//! Both carriers open with the tcp-family handshake on a TCP connection to the receiving
//! port, then move the data to UDP and close the TCP connection:
//!
//! ```text
//! udp    c2s  59 41 61 1e 00 00 52 50     header: YARP number 7777 (udp, specifier 0)
//!        c2s  03 00 00 00 2f 77 00        sender name "/w" (int32 LE length incl. NUL)
//!        s2c  59 41 xx xx 00 00 52 50     header reply: the receiver's *UDP* port
//!        (both sides close the TCP connection; the sender sends its datagrams to the
//!         TCP peer's host at that port)
//!
//! mcast  c2s  59 41 62 1e 00 00 52 50     header: YARP number 7778 (mcast, specifier 1)
//!        c2s  03 00 00 00 2f 77 00        sender name "/w"
//!        c2s  e0 01 01 03 27 13           the group: 4 IPv4 bytes, port big-endian
//!                                         (224.1.1.3:10003) — see [`McastGroup`]
//!        (no reply at all; the receiver joins the group, the sender sends to it)
//! ```
//!
//! # The datagrams
//!
//! A message is encoded exactly as on tcp (index, port command, blocks; see
//! [`encode_message`](super::encode_message)), without acknowledgements or replies, and
//! its bytes are cut into datagrams of at most [`DEFAULT_DATAGRAM_SIZE`] bytes (65 499,
//! C++ `UDP_MAX_DATAGRAM_SIZE`), each
//!
//! ```text
//! [crc: int32 LE] [counter: int32 LE] [payload ...]      (CRC_SIZE = 8 header bytes)
//! ```
//!
//! * `crc` is [`get_crc`] (C++ `NetType::getCrc`, the standard CRC-32 of zlib/IEEE
//!   802.3) of the payload only, stored as a little-endian int32;
//! * `counter` counts the datagrams of *one message*: C++ calls `beginPacket()` (counter
//!   := 0) before writing every message and flushes the last, partial datagram when the
//!   message ends, so a message is the datagrams `0, 1, 2, ...` and never shares a
//!   datagram with the next one. An empty datagram (no payload) is never sent.
//! * counter `-1` marks the "interrupt" datagram C++ sends to its own socket to wake a
//!   blocked reader (10 zero bytes of payload); readers ignore it whatever its CRC.
//!
//! C++ readers expect counter 0 at the start of every message (`Protocol::expectIndex`
//! calls `beginPacket()`) and `expected + 1` afterwards; any CRC or counter mismatch makes
//! the read fail, resets the expectation to 0, and the reader drops datagrams until a
//! counter-0 datagram starts a new message. [`DatagramReader`] does the same, except that
//! a counter-0 datagram arriving in the middle of a message is taken as the start of the
//! next message (C++ loses that message too), a datagram with a bad CRC does not abandon
//! the message in progress (a lost or corrupted datagram of the message is caught by the
//! counter of the next one, while stray garbage then does no harm), and an exact duplicate
//! of an already-accepted datagram of the current message is ignored.

use super::carrier::{Carrier, CarrierSpec, Framing};
use super::decoder::{Decoder, DecoderConfig, Event};
use super::error::WireError;
use super::message::{Index, Message};
use thiserror::Error;

/// Bytes before the payload of every datagram: CRC (4) and counter (4).
pub const CRC_SIZE: usize = 8;
/// The largest UDP payload over IPv4.
pub const MAX_UDP_PAYLOAD: usize = 65507;
/// The size (header included) of the datagrams C++ writes: its write buffer,
/// `UDP_MAX_DATAGRAM_SIZE = 65507 - CRC_SIZE`. (`YARP_UDP_SIZE` / `YARP_MCAST_SIZE` /
/// `YARP_DGRAM_SIZE` can make it smaller, never larger.)
pub const DEFAULT_DATAGRAM_SIZE: usize = MAX_UDP_PAYLOAD - CRC_SIZE;
/// Message bytes carried by a full datagram of [`DEFAULT_DATAGRAM_SIZE`].
pub const DEFAULT_PAYLOAD_SIZE: usize = DEFAULT_DATAGRAM_SIZE - CRC_SIZE;
/// The counter of C++'s interrupt datagram, which readers skip.
pub const INTERRUPT_COUNTER: i32 = -1;
/// Datagrams longer than this are refused by [`DatagramReader`] by default (C++ reads
/// into a buffer the size of the socket's receive buffer; UDP cannot carry more).
pub const DEFAULT_MAX_DATAGRAM: usize = 65535;

const fn make_crc_table() -> [u32; 256] {
    let mut table = [0u32; 256];
    let mut n = 0;
    while n < 256 {
        let mut c = n as u32;
        let mut k = 0;
        while k < 8 {
            c = if c & 1 != 0 {
                0xedb8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
            k += 1;
        }
        table[n] = c;
        n += 1;
    }
    table
}

static CRC_TABLE: [u32; 256] = make_crc_table();

/// C++ `NetType::getCrc(buf, len)`: the CRC-32 of zlib / PNG / IEEE 802.3 (reflected
/// polynomial `0xedb88320`, initial value and final xor `0xffffffff`). C++ computes it
/// in an `unsigned long`, but every intermediate value fits 32 bits, so this is exact.
/// On the wire it is stored as `(NetInt32)crc`, i.e. these 4 bytes little-endian.
pub fn get_crc(data: &[u8]) -> u32 {
    let mut c = 0xffff_ffffu32;
    for &b in data {
        c = CRC_TABLE[((c ^ b as u32) & 0xff) as usize] ^ (c >> 8);
    }
    c ^ 0xffff_ffff
}

/// One datagram: the 8-byte header then `payload` (C++ `addCrc`).
pub fn encode_datagram(counter: i32, payload: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(CRC_SIZE + payload.len());
    out.extend_from_slice(&get_crc(payload).to_le_bytes());
    out.extend_from_slice(&counter.to_le_bytes());
    out.extend_from_slice(payload);
    out
}

/// The datagram C++ sends to wake a reader blocked on its own socket
/// (`DgramTwoWayStream::interrupt`): counter -1, 10 zero bytes.
pub fn interrupt_datagram() -> Vec<u8> {
    encode_datagram(INTERRUPT_COUNTER, &[0u8; 10])
}

/// A datagram's header, read without checking anything.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DatagramHeader {
    /// The CRC the sender stored.
    pub crc: u32,
    /// The packet counter within the message.
    pub counter: i32,
}

impl DatagramHeader {
    /// The header of `datagram`, `None` when it is shorter than [`CRC_SIZE`].
    pub fn read(datagram: &[u8]) -> Option<DatagramHeader> {
        let h = datagram.get(..CRC_SIZE)?;
        Some(DatagramHeader {
            crc: u32::from_le_bytes([h[0], h[1], h[2], h[3]]),
            counter: i32::from_le_bytes([h[4], h[5], h[6], h[7]]),
        })
    }
}

/// Checks a datagram's length and CRC; returns its counter and payload.
pub fn parse_datagram(datagram: &[u8]) -> Result<(i32, &[u8]), DatagramError> {
    let header = DatagramHeader::read(datagram).ok_or(DatagramError::Short {
        len: datagram.len(),
    })?;
    let payload = &datagram[CRC_SIZE..];
    let computed = get_crc(payload);
    if computed != header.crc {
        return Err(DatagramError::BadCrc {
            counter: header.counter,
            found: header.crc,
            computed,
        });
    }
    Ok((header.counter, payload))
}

/// Why a datagram was dropped.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum DatagramError {
    /// Shorter than the 8-byte header.
    #[error("datagram of {len} byte(s) is shorter than its 8-byte header")]
    Short { len: usize },
    /// Longer than the reader accepts.
    #[error("datagram of {len} bytes exceeds the limit of {max} bytes")]
    Oversized { len: usize, max: usize },
    /// The stored CRC does not match the payload.
    #[error("datagram {counter}: crc {found:08x} does not match the payload's {computed:08x}")]
    BadCrc {
        counter: i32,
        found: u32,
        computed: u32,
    },
    /// A valid datagram that does not continue the message in progress (a datagram was
    /// lost) or, between messages, does not start one (counter not 0).
    #[error("datagram counter {found} where {expected} was expected")]
    OutOfSequence { expected: i32, found: i32 },
    /// A repeat of a datagram already taken for the message in progress.
    #[error("datagram counter {found} repeated (expected {expected})")]
    Duplicate { expected: i32, found: i32 },
}

/// Cuts messages into datagrams as C++ `DgramTwoWayStream::write` + `flush` do.
#[derive(Debug, Clone)]
pub struct DatagramWriter {
    datagram_size: usize,
    messages: u64,
    datagrams: u64,
}

impl Default for DatagramWriter {
    fn default() -> Self {
        DatagramWriter::new()
    }
}

impl DatagramWriter {
    /// Datagrams of [`DEFAULT_DATAGRAM_SIZE`] bytes, as C++ writes by default.
    pub fn new() -> DatagramWriter {
        DatagramWriter::with_datagram_size(DEFAULT_DATAGRAM_SIZE)
    }

    /// Datagrams of at most `size` bytes, header included (C++ `YARP_UDP_SIZE`); clamped
    /// to `CRC_SIZE + 1 ..= DEFAULT_DATAGRAM_SIZE`.
    pub fn with_datagram_size(size: usize) -> DatagramWriter {
        DatagramWriter {
            datagram_size: size.clamp(CRC_SIZE + 1, DEFAULT_DATAGRAM_SIZE),
            messages: 0,
            datagrams: 0,
        }
    }

    /// The largest datagram this writer produces, header included.
    pub fn datagram_size(&self) -> usize {
        self.datagram_size
    }

    /// Message bytes per full datagram.
    pub fn payload_size(&self) -> usize {
        self.datagram_size - CRC_SIZE
    }

    /// How many datagrams a message of `len` bytes takes.
    pub fn datagram_count(&self, len: usize) -> usize {
        len.div_ceil(self.payload_size())
    }

    /// The datagrams of one message (its complete tcp-family bytes, e.g. from
    /// [`data_message`](super::data_message)), counters `0, 1, ...`. An empty message
    /// gives no datagram, as in C++.
    pub fn split<'a>(&mut self, message: &'a [u8]) -> Datagrams<'a> {
        let n = self.datagram_count(message.len());
        self.messages += 1;
        self.datagrams += n as u64;
        Datagrams {
            chunks: message.chunks(self.payload_size()),
            counter: 0,
        }
    }

    /// Messages split so far.
    pub fn messages(&self) -> u64 {
        self.messages
    }

    /// Datagrams produced so far.
    pub fn datagrams(&self) -> u64 {
        self.datagrams
    }
}

/// The datagrams of one message; see [`DatagramWriter::split`].
#[derive(Debug, Clone)]
pub struct Datagrams<'a> {
    chunks: std::slice::Chunks<'a, u8>,
    counter: i32,
}

impl Iterator for Datagrams<'_> {
    type Item = Vec<u8>;

    fn next(&mut self) -> Option<Vec<u8>> {
        let chunk = self.chunks.next()?;
        let d = encode_datagram(self.counter, chunk);
        self.counter = self.counter.wrapping_add(1);
        Some(d)
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        self.chunks.size_hint()
    }
}

impl ExactSizeIterator for Datagrams<'_> {}

/// Something the [`DatagramReader`] made of a datagram.
#[derive(Debug, Clone, PartialEq)]
pub enum DatagramEvent {
    /// A complete message.
    Message(Message),
    /// A well-framed message whose port command is unusable (skipped by C++).
    InvalidMessage {
        index: Index,
        body: Vec<u8>,
        error: WireError,
    },
    /// A datagram was dropped (its bytes are not part of any message).
    Dropped(DatagramError),
    /// A message in progress was abandoned after `received` of its bytes: a datagram of
    /// it went missing, a new message started, or its bytes do not frame (`framing`).
    Lost {
        received: usize,
        framing: Option<WireError>,
    },
    /// C++'s interrupt datagram (counter -1), ignored.
    Interrupt,
}

/// Counters kept by a [`DatagramReader`].
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct DatagramStats {
    /// Datagrams pushed.
    pub datagrams: u64,
    /// Datagrams whose payload went into a message.
    pub accepted: u64,
    /// Datagrams dropped ([`DatagramEvent::Dropped`]).
    pub dropped: u64,
    /// Complete messages (valid or not).
    pub messages: u64,
    /// Messages abandoned ([`DatagramEvent::Lost`]).
    pub lost: u64,
    /// Interrupt datagrams.
    pub interrupts: u64,
}

/// The carrier description the reassembled byte stream is decoded with: udp's row, with
/// tcp-family message framing (no acks, no replies).
pub fn stream_spec(carrier: Carrier) -> CarrierSpec {
    CarrierSpec {
        framing: Framing::Stream,
        requires_ack: false,
        supports_reply: false,
        ..carrier.spec()
    }
}

/// Validates datagrams, reassembles the messages they carry and decodes them. One reader
/// per incoming connection (C++ opens one socket per connection). Never panics, and holds
/// at most one partial message (bounded by [`DecoderConfig::max_message_size`]).
#[derive(Debug, Clone)]
pub struct DatagramReader {
    config: DecoderConfig,
    spec: CarrierSpec,
    decoder: Decoder,
    max_datagram: usize,
    /// Counter of the next datagram of the message in progress; `None` between messages
    /// or after a loss (waiting for counter 0).
    expected: Option<i32>,
    /// Bytes of the message in progress taken so far.
    received: usize,
    stats: DatagramStats,
}

impl Default for DatagramReader {
    fn default() -> Self {
        DatagramReader::new(DecoderConfig::default())
    }
}

impl DatagramReader {
    /// A reader for udp (mcast frames messages the same way).
    pub fn new(config: DecoderConfig) -> DatagramReader {
        DatagramReader::for_carrier(Carrier::Udp, config)
    }

    /// A reader whose messages report `carrier` (udp or mcast).
    pub fn for_carrier(carrier: Carrier, config: DecoderConfig) -> DatagramReader {
        let spec = stream_spec(carrier);
        DatagramReader {
            decoder: Decoder::messages(spec, config.clone()),
            config,
            spec,
            max_datagram: DEFAULT_MAX_DATAGRAM,
            expected: None,
            received: 0,
            stats: DatagramStats::default(),
        }
    }

    /// Refuses datagrams longer than `max` bytes (default [`DEFAULT_MAX_DATAGRAM`]).
    pub fn with_max_datagram(mut self, max: usize) -> DatagramReader {
        self.max_datagram = max;
        self
    }

    pub fn stats(&self) -> DatagramStats {
        self.stats
    }

    /// Whether a message is partly received.
    pub fn in_message(&self) -> bool {
        self.expected.is_some()
    }

    fn reset_decoder(&mut self) {
        self.decoder = Decoder::messages(self.spec, self.config.clone());
        self.received = 0;
    }

    /// Abandons the message in progress, if any.
    fn abandon(&mut self, framing: Option<WireError>, out: &mut Vec<DatagramEvent>) {
        if self.received > 0 || framing.is_some() || self.expected.is_some() {
            self.stats.lost += 1;
            out.push(DatagramEvent::Lost {
                received: self.received,
                framing,
            });
        }
        self.expected = None;
        self.reset_decoder();
    }

    fn drop_datagram(&mut self, error: DatagramError, out: &mut Vec<DatagramEvent>) {
        self.stats.dropped += 1;
        out.push(DatagramEvent::Dropped(error));
    }

    /// Takes one received datagram; returns what it completed or broke.
    pub fn push(&mut self, datagram: &[u8]) -> Vec<DatagramEvent> {
        let mut out = Vec::new();
        self.push_into(datagram, &mut out);
        out
    }

    /// As [`push`](Self::push), appending to `out`.
    pub fn push_into(&mut self, datagram: &[u8], out: &mut Vec<DatagramEvent>) {
        self.stats.datagrams += 1;
        if datagram.len() > self.max_datagram {
            let e = DatagramError::Oversized {
                len: datagram.len(),
                max: self.max_datagram,
            };
            return self.drop_datagram(e, out);
        }
        // C++ skips the interrupt datagram before looking at its CRC
        if DatagramHeader::read(datagram).map(|h| h.counter) == Some(INTERRUPT_COUNTER) {
            self.stats.interrupts += 1;
            out.push(DatagramEvent::Interrupt);
            return;
        }
        let (counter, payload) = match parse_datagram(datagram) {
            Ok(p) => p,
            Err(e) => return self.drop_datagram(e, out),
        };
        match self.expected {
            _ if counter == 0 => {
                // a new message; whatever was in progress is incomplete
                if self.expected.is_some() {
                    self.abandon(None, out);
                }
            }
            Some(expected) if counter == expected => {}
            Some(expected) if counter > 0 && counter < expected => {
                let e = DatagramError::Duplicate {
                    expected,
                    found: counter,
                };
                return self.drop_datagram(e, out);
            }
            Some(expected) => {
                self.abandon(None, out);
                let e = DatagramError::OutOfSequence {
                    expected,
                    found: counter,
                };
                return self.drop_datagram(e, out);
            }
            None => {
                let e = DatagramError::OutOfSequence {
                    expected: 0,
                    found: counter,
                };
                return self.drop_datagram(e, out);
            }
        }
        self.stats.accepted += 1;
        self.expected = Some(counter.wrapping_add(1));
        self.received = self.received.saturating_add(payload.len());
        self.decoder.feed(payload);
        loop {
            match self.decoder.poll() {
                Ok(Some(Event::Message(m))) => {
                    self.stats.messages += 1;
                    let reverse = m.command.key() == b'r';
                    out.push(DatagramEvent::Message(m));
                    if reverse {
                        // meaningless on a datagram connection; keep reading messages
                        self.decoder.start_messages();
                    }
                }
                Ok(Some(Event::InvalidMessage { index, body, error })) => {
                    self.stats.messages += 1;
                    out.push(DatagramEvent::InvalidMessage { index, body, error });
                }
                Ok(Some(_)) => {}
                Ok(None) => break,
                Err(e) => {
                    self.abandon(Some(e), out);
                    return;
                }
            }
        }
        if self.decoder.is_idle() {
            // the message ended with this datagram: the next one must start a new message
            self.expected = None;
            self.received = 0;
        }
    }
}

/// The 6 bytes a mcast sender adds after its sender name (C++
/// `McastCarrier::sendHeader` / `expectExtraHeader`): the group's IPv4 address, then its
/// port big-endian.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct McastGroup {
    pub ip: [u8; 4],
    pub port: u16,
}

impl McastGroup {
    /// What C++ falls back to when the name server allocates no group.
    pub const FALLBACK: McastGroup = McastGroup {
        ip: [224, 3, 1, 1],
        port: 11000,
    };

    pub fn encode(&self) -> [u8; 6] {
        let p = self.port.to_be_bytes();
        [self.ip[0], self.ip[1], self.ip[2], self.ip[3], p[0], p[1]]
    }

    pub fn decode(b: &[u8; 6]) -> McastGroup {
        McastGroup {
            ip: [b[0], b[1], b[2], b[3]],
            port: u16::from_be_bytes([b[4], b[5]]),
        }
    }

    pub fn addr(&self) -> std::net::SocketAddrV4 {
        std::net::SocketAddrV4::new(self.ip.into(), self.port)
    }
}

impl From<std::net::SocketAddrV4> for McastGroup {
    fn from(a: std::net::SocketAddrV4) -> Self {
        McastGroup {
            ip: a.ip().octets(),
            port: a.port(),
        }
    }
}

/// Everything a mcast sender writes on the TCP connection: header 7778, sender name, the
/// group. No reply follows.
pub fn encode_mcast_connection_start(sender: &[u8], group: McastGroup) -> Vec<u8> {
    let mut out = super::carrier::encode_connection_start(&Carrier::Mcast.spec(), sender);
    out.extend_from_slice(&group.encode());
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bottle;
    use crate::wire::{data_message, encode_connection_start, encode_header_reply};

    fn hex(b: &[u8]) -> String {
        b.iter().map(|x| format!("{x:02x}")).collect()
    }

    #[test]
    fn crc_test_vectors() {
        // the table C++ make_crc_table builds: entry 1 and 255 of the zlib table
        assert_eq!(CRC_TABLE[1], 0x7707_3096);
        assert_eq!(CRC_TABLE[255], 0x2d02_ef8d);
        assert_eq!(get_crc(b""), 0);
        assert_eq!(get_crc(b"123456789"), 0xcbf4_3926);
        assert_eq!(get_crc(b"a"), 0xe8b7_be43);
        assert_eq!(
            get_crc(b"The quick brown fox jumps over the lazy dog"),
            0x414f_a339
        );
        assert_eq!(get_crc(&[0u8; 10]), 0xe38a_6876);
    }

    #[test]
    fn datagram_bytes() {
        // header little-endian: (NetInt32)crc, then the counter
        assert_eq!(
            hex(&encode_datagram(0, b"123456789")),
            "2639f4cb00000000313233343536373839"
        );
        assert_eq!(
            hex(&interrupt_datagram()),
            "76688ae3ffffffff00000000000000000000"
        );
        // a whole `yarp write` message fits one datagram
        let msg = data_message(&bottle!["hello", 42], false);
        let mut w = DatagramWriter::new();
        let d: Vec<_> = w.split(&msg).collect();
        assert_eq!(d.len(), 1);
        assert_eq!(&d[0][8..], &msg[..]);
        assert_eq!(&d[0][..4], &get_crc(&msg).to_le_bytes());
        assert_eq!(&d[0][4..8], &[0, 0, 0, 0]);
        assert_eq!(parse_datagram(&d[0]), Ok((0, &msg[..])));
    }

    #[test]
    fn handshake_bytes() {
        assert_eq!(
            hex(&encode_connection_start(&Carrier::Udp.spec(), b"/w")),
            "5941611e00005250030000002f7700"
        );
        assert_eq!(hex(&encode_header_reply(10002)), "5941122700005250");
        let g = McastGroup {
            ip: [224, 1, 1, 3],
            port: 10003,
        };
        assert_eq!(
            hex(&encode_mcast_connection_start(b"/w", g)),
            "5941621e00005250030000002f7700e00101032713"
        );
        assert_eq!(McastGroup::decode(&g.encode()), g);
        assert_eq!(g.addr().to_string(), "224.1.1.3:10003");
    }

    #[test]
    fn split_sizes_and_counters() {
        let mut w = DatagramWriter::new();
        assert_eq!(w.split(b"").count(), 0);
        let big = vec![7u8; DEFAULT_PAYLOAD_SIZE * 2 + 1];
        let d: Vec<_> = w.split(&big).collect();
        assert_eq!(d.len(), 3);
        assert_eq!(d[0].len(), DEFAULT_DATAGRAM_SIZE);
        assert_eq!(d[2].len(), CRC_SIZE + 1);
        for (i, x) in d.iter().enumerate() {
            assert_eq!(DatagramHeader::read(x).unwrap().counter, i as i32);
        }
        // exactly full: no trailing empty datagram
        assert_eq!(w.split(&big[..DEFAULT_PAYLOAD_SIZE]).count(), 1);
        assert_eq!(w.messages(), 3);
        assert_eq!(w.datagrams(), 4);
        let w = DatagramWriter::with_datagram_size(0);
        assert_eq!(w.payload_size(), 1);
        let w = DatagramWriter::with_datagram_size(1 << 20);
        assert_eq!(w.datagram_size(), DEFAULT_DATAGRAM_SIZE);
    }

    fn messages(events: &[DatagramEvent]) -> Vec<String> {
        events
            .iter()
            .filter_map(|e| match e {
                DatagramEvent::Message(m) => {
                    let b = m.bottle().unwrap();
                    Some(match b.get(1) {
                        Some(crate::Value::Blob(x)) => format!("{} blob{}", b.get(0)?, x.len()),
                        _ => b.to_string(),
                    })
                }
                _ => None,
            })
            .collect()
    }

    fn big_message(n: usize, tag: &str) -> Vec<u8> {
        let blob = crate::Value::Blob(vec![0xab; n]);
        let mut b = bottle![tag];
        b.push(blob);
        data_message(&b, false)
    }

    #[test]
    fn reassembles_small_and_large() {
        let mut w = DatagramWriter::with_datagram_size(100);
        let mut r = DatagramReader::default();
        let mut ev = Vec::new();
        for text in ["one", "two"] {
            let msg = data_message(&bottle![text, 1], false);
            for d in w.split(&msg) {
                ev.extend(r.push(&d));
            }
        }
        let big = big_message(1000, "big");
        for d in w.split(&big) {
            ev.extend(r.push(&d));
        }
        assert_eq!(messages(&ev)[..2], ["one 1", "two 1"]);
        assert_eq!(ev.len(), 3);
        let DatagramEvent::Message(m) = &ev[2] else {
            panic!()
        };
        assert_eq!(m.command.key(), b'D');
        assert!(m.to_wire() == big);
        assert!(!r.in_message());
        let s = r.stats();
        assert_eq!((s.messages, s.dropped, s.lost), (3, 0, 0));
    }

    #[test]
    fn loss_and_resync() {
        let mut w = DatagramWriter::with_datagram_size(64);
        let mut r = DatagramReader::default();
        let a: Vec<_> = w.split(&big_message(200, "a")).collect();
        let b: Vec<_> = w.split(&big_message(200, "b")).collect();
        let c: Vec<_> = w.split(&big_message(200, "c")).collect();
        assert!(a.len() > 3);
        // lose a middle datagram of `a`: a is lost, the rest of it dropped, b arrives
        let mut ev = Vec::new();
        for (i, d) in a.iter().enumerate() {
            if i != 1 {
                ev.extend(r.push(d));
            }
        }
        assert!(matches!(
            ev[0],
            DatagramEvent::Lost {
                received: 56,
                framing: None
            }
        ));
        assert!(matches!(
            ev[1],
            DatagramEvent::Dropped(DatagramError::OutOfSequence {
                expected: 1,
                found: 2
            })
        ));
        assert!(ev[2..].iter().all(|e| matches!(
            e,
            DatagramEvent::Dropped(DatagramError::OutOfSequence { expected: 0, .. })
        )));
        // lose the tail of `b`: c's first datagram starts the next message
        let mut ev = Vec::new();
        for d in &b[..b.len() - 1] {
            ev.extend(r.push(d));
        }
        for d in &c {
            ev.extend(r.push(d));
        }
        assert!(matches!(ev[0], DatagramEvent::Lost { framing: None, .. }));
        assert_eq!(messages(&ev), ["c blob200"]);
    }

    #[test]
    fn garbage_and_duplicates_do_not_break_a_message() {
        let mut w = DatagramWriter::with_datagram_size(64);
        let mut r = DatagramReader::default();
        let a: Vec<_> = w.split(&big_message(200, "a")).collect();
        let mut ev = Vec::new();
        ev.extend(r.push(&a[0]));
        ev.extend(r.push(b""));
        ev.extend(r.push(b"short"));
        ev.extend(r.push(&[0x5au8; 100]));
        let mut corrupt = a[1].clone();
        corrupt[20] ^= 1;
        ev.extend(r.push(&corrupt));
        ev.extend(r.push(&interrupt_datagram()));
        ev.extend(
            r.push(&a[0][..])
                .into_iter()
                .filter(|e| !matches!(e, DatagramEvent::Lost { .. })),
        );
        // (a repeated counter 0 restarts the message, by design)
        for d in &a[1..] {
            ev.extend(r.push(d));
            ev.extend(r.push(&a[1]));
        }
        assert_eq!(messages(&ev), ["a blob200"]);
        assert!(ev
            .iter()
            .any(|e| matches!(e, DatagramEvent::Dropped(DatagramError::Short { len: 0 }))));
        assert!(ev.iter().any(|e| matches!(
            e,
            DatagramEvent::Dropped(DatagramError::BadCrc { counter: 1, .. })
        )));
        assert!(ev.iter().any(|e| matches!(e, DatagramEvent::Interrupt)));
        assert!(ev
            .iter()
            .any(|e| matches!(e, DatagramEvent::Dropped(DatagramError::Duplicate { .. }))));
    }

    #[test]
    fn hostile_datagrams() {
        let mut r = DatagramReader::default();
        // huge: refused before any work
        let huge = vec![0u8; 1 << 20];
        assert_eq!(
            r.push(&huge),
            [DatagramEvent::Dropped(DatagramError::Oversized {
                len: 1 << 20,
                max: DEFAULT_MAX_DATAGRAM
            })]
        );
        // valid CRC, not a message: framing error, message lost, reader still works
        let ev = r.push(&encode_datagram(0, b"not a yarp message at all"));
        assert!(matches!(
            ev[..],
            [DatagramEvent::Lost {
                framing: Some(WireError::BadIndex { .. }),
                ..
            }]
        ));
        // an index announcing 2 GB: refused by the decoder limit at once
        let mut idx = Vec::new();
        Index::new(vec![i32::MAX as u32, i32::MAX as u32]).encode(&mut idx);
        let mut small = DatagramReader::new(DecoderConfig {
            max_message_size: 1 << 20,
            ..DecoderConfig::default()
        });
        let ev = small.push(&encode_datagram(0, &idx));
        assert!(matches!(
            ev[..],
            [DatagramEvent::Lost {
                framing: Some(WireError::TooLarge { .. }),
                ..
            }]
        ));
        // a bad port command is reported, the stream stays usable
        let mut bad = data_message(&bottle!["x"], false);
        bad[30 + 4] = b'!';
        let ev = r.push(&encode_datagram(0, &bad));
        assert!(matches!(ev[..], [DatagramEvent::InvalidMessage { .. }]));
        let ok = data_message(&bottle!["fine"], false);
        assert_eq!(messages(&r.push(&encode_datagram(0, &ok))), ["fine"]);
        // counters at the extremes
        r.push(&encode_datagram(i32::MAX, b"x"));
        r.push(&encode_datagram(i32::MIN, b"x"));
        // every truncation and single-bit flip of a valid datagram: no panic
        let d = encode_datagram(0, &ok);
        for n in 0..d.len() {
            r.push(&d[..n]);
        }
        for i in 0..d.len() * 8 {
            let mut x = d.clone();
            x[i / 8] ^= 1 << (i % 8);
            r.push(&x);
        }
        assert_eq!(messages(&r.push(&d)), ["fine"]);
    }

    #[test]
    fn mcast_reader_reports_mcast() {
        let r = DatagramReader::for_carrier(Carrier::Mcast, DecoderConfig::default());
        assert_eq!(r.spec.carrier, Carrier::Mcast);
        assert_eq!(r.spec.framing, Framing::Stream);
    }
}
