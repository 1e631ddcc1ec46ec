//! The incremental connection decoder: feed bytes as they arrive, poll for events.
//!
//! One [`Decoder`] reads one direction of one connection:
//!
//! * [`Decoder::accepting`]: the bytes the *connecting* side sends, as the accepting port
//!   reads them: the 8-byte header (classified through the [`CarrierRegistry`]), the
//!   sender name, then messages (binary indexed messages, text command lines, or
//!   name-server lines).
//! * [`Decoder::connecting`]: the bytes the *accepting* side sends back: the header reply
//!   (or welcome line), then acknowledgements and RPC replies. Tell it about every
//!   message you send with [`Decoder::expect_response`], so that it knows when an
//!   index-less reply Bottle is due and when a reversed connection (`r`) starts carrying
//!   messages the other way.
//!
//! The decoder never blocks and never panics on input. Any frame announcing more than
//! [`DecoderConfig::max_message_size`] bytes is an error at once; below that limit,
//! [`Decoder::feed`] buffers bytes only as they arrive, while [`Decoder::read_buf`] (the
//! zero-copy path for socket reads) reserves room for the rest of the frame being read,
//! which is known to fit the limit, once.
//!
//! Large frames are handed out without copying: a frame that fills the buffer becomes the
//! event's `Vec` and the decoder starts a new buffer for the bytes after it.

use std::collections::VecDeque;

use bytes::buf::UninitSlice;
use bytes::BufMut;

use super::carrier::{CarrierRegistry, CarrierSpec, ConnectionHeader, Framing, MAX_SENDER_NAME};
use super::command::PortCommand;
use super::error::WireError;
use super::line::{CompletenessCheck, LineReader, LineStep};
use super::message::{BinaryFrame, Index, Message, INDEX_FIXED_LEN};
use super::number::{YarpNumber, INDEX_VALUE};
use super::scan::{BottleScanner, Scan};
use super::text_carrier::{ACK_TEXT, WELCOME_PREFIX};

/// The longest reply that is no Bottle (its end found by the acknowledgement after it).
const RAW_REPLY_MAX: usize = 4096;

/// Default limit for one message, reply or text payload: 256 MiB.
pub const DEFAULT_MAX_MESSAGE_SIZE: usize = 256 * 1024 * 1024;
/// Default limit for one text line: 16 MiB.
pub const DEFAULT_MAX_LINE_LEN: usize = 16 * 1024 * 1024;

/// Frames (binary message payloads, reply Bottles, raw bytes) at least this long are
/// handed out by moving the decoder's buffer into the event rather than copying them.
const SPLIT_MIN: usize = 64 * 1024;

/// Limits and the carrier table.
#[derive(Debug, Clone)]
pub struct DecoderConfig {
    /// Largest message body (sum of block lengths), reply Bottle, multi-line text
    /// payload or acknowledgement payload accepted.
    pub max_message_size: usize,
    /// Longest text line accepted.
    pub max_line_len: usize,
    /// Carriers recognised in connection headers.
    pub registry: CarrierRegistry,
}

impl Default for DecoderConfig {
    fn default() -> Self {
        DecoderConfig {
            max_message_size: DEFAULT_MAX_MESSAGE_SIZE,
            max_line_len: DEFAULT_MAX_LINE_LEN,
            registry: CarrierRegistry::builtin(),
        }
    }
}

/// Something decoded from the byte stream.
#[derive(Debug, Clone, PartialEq)]
pub enum Event {
    /// The connection header (first 8 bytes of a connection).
    Header(ConnectionHeader),
    /// The sender's port name (tcp family: length-prefixed; text: rest of the
    /// `CONNECT` line).
    SenderName(Vec<u8>),
    /// The accepting side's header reply (tcp family): its TCP port (UDP port for udp).
    HeaderReply(i32),
    /// The accepting side's welcome line (text carriers), without `Welcome `.
    Welcome(Vec<u8>),
    /// A message.
    Message(Message),
    /// A well-framed binary message whose port command is unusable (C++ skips such a
    /// message without acknowledging it). The stream stays in sync.
    InvalidMessage {
        index: Index,
        body: Vec<u8>,
        error: WireError,
    },
    /// An index-less RPC reply: the bytes of one Bottle.
    Reply(Vec<u8>),
    /// An acknowledgement: YARP number (tcp; a positive value is followed by that many
    /// bytes, which are skipped) or an `<ACK>` line (text_ack, value 0).
    Ack(i32),
    /// A text line from the accepting side (reply Bottle text, port help, name-server
    /// output ...).
    Line(Vec<u8>),
    /// Bytes this decoder does not interpret (after a udp/mcast/shmem/local handshake,
    /// http, custom carriers).
    Raw(Vec<u8>),
}

#[derive(Debug, Clone, Copy)]
struct Expect {
    reply: bool,
    ack: bool,
    reverse: bool,
    /// The reply may be no Bottle (a thrift server's protocol version): it then ends
    /// where its acknowledgement starts.
    raw: bool,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Join {
    First,
    Concat,
    Newline,
}

#[derive(Debug, Clone)]
enum State {
    Header,
    SenderName,
    TextSenderName,
    Messages,
    TextMessages,
    TextPayload {
        command: PortCommand,
        text: Vec<u8>,
        join: Join,
        check: CompletenessCheck,
    },
    NameServer {
        swallow: usize,
    },
    /// A large binary message whose index and port command have been read; its payload
    /// (`len` bytes) starts at `pos`.
    MessagePayload {
        index: Index,
        command: PortCommand,
        command_header: [u8; 8],
        len: usize,
    },
    HeaderReply,
    Welcome,
    Responses,
    TextResponses,
    Raw,
    Failed(WireError),
}

enum Step {
    Event(Event),
    NeedMore,
    Continue,
}

/// Incremental decoder for one direction of a YARP connection. See the module docs.
#[derive(Debug, Clone)]
pub struct Decoder {
    config: DecoderConfig,
    pub(super) buf: Vec<u8>,
    pos: usize,
    state: State,
    spec: Option<CarrierSpec>,
    line: LineReader,
    scanner: Option<BottleScanner>,
    need: u64,
    /// Bytes (from `pos`) the frame being read needs in all, when known (always within
    /// `max_message_size`): sizes [`Decoder::read_buf`]'s reservation.
    hint: usize,
    discard: u64,
    expect: VecDeque<Expect>,
}

/// Room for one read straight into a [`Decoder`]'s buffer, from [`Decoder::read_buf`].
///
/// It is a [`BufMut`] over the buffer's spare capacity (not zeroed, never grown past what
/// `read_buf` reserved), so `tokio::io::AsyncReadExt::read_buf` can fill it; the bytes
/// written become input of the decoder, as if fed.
#[derive(Debug)]
pub struct ReadSpace<'a> {
    buf: &'a mut Vec<u8>,
}

impl ReadSpace<'_> {
    /// Bytes that can be written.
    pub fn len(&self) -> usize {
        self.buf.capacity() - self.buf.len()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

// SAFETY: every method forwards to `Vec<u8>`'s implementation; `remaining_mut` is the
// spare capacity, so the buffer is never asked to grow.
unsafe impl BufMut for ReadSpace<'_> {
    fn remaining_mut(&self) -> usize {
        self.len()
    }

    unsafe fn advance_mut(&mut self, cnt: usize) {
        // SAFETY: the caller initialised `cnt` bytes of `chunk_mut`, which is the
        // vector's spare capacity; `Vec::advance_mut` checks `cnt` against it.
        unsafe { self.buf.advance_mut(cnt) }
    }

    fn chunk_mut(&mut self) -> &mut UninitSlice {
        UninitSlice::uninit(self.buf.spare_capacity_mut())
    }
}

impl Decoder {
    fn with_state(config: DecoderConfig, state: State, spec: Option<CarrierSpec>) -> Decoder {
        let line = LineReader::new(config.max_line_len);
        Decoder {
            config,
            buf: Vec::new(),
            pos: 0,
            state,
            spec,
            line,
            scanner: None,
            need: 0,
            hint: 0,
            discard: 0,
            expect: VecDeque::new(),
        }
    }

    /// Reads a connection from its first byte, as the accepting port does.
    pub fn accepting(config: DecoderConfig) -> Decoder {
        Decoder::with_state(config, State::Header, None)
    }

    /// Reads what the accepting port sends back on a connection we opened with `spec`
    /// (e.g. `Carrier::Tcp.spec()`).
    pub fn connecting(spec: CarrierSpec, config: DecoderConfig) -> Decoder {
        let state = match spec.framing {
            Framing::Stream | Framing::Handshake => State::HeaderReply,
            Framing::Text => State::Welcome,
            Framing::NameServer => State::TextResponses,
            Framing::Local | Framing::Raw => State::Raw,
        };
        Decoder::with_state(config, state, Some(spec))
    }

    /// Reads messages on an established connection (handshake already done).
    pub fn messages(spec: CarrierSpec, config: DecoderConfig) -> Decoder {
        let state = match spec.framing {
            Framing::Stream => State::Messages,
            Framing::Text => State::TextMessages,
            Framing::NameServer => State::NameServer { swallow: 0 },
            _ => State::Raw,
        };
        Decoder::with_state(config, state, Some(spec))
    }

    /// Reads acknowledgements and replies on an established connection.
    pub fn responses(spec: CarrierSpec, config: DecoderConfig) -> Decoder {
        let state = match spec.framing {
            Framing::Stream => State::Responses,
            Framing::Text | Framing::NameServer => State::TextResponses,
            _ => State::Raw,
        };
        Decoder::with_state(config, state, Some(spec))
    }

    /// The carrier, once known.
    pub fn carrier_spec(&self) -> Option<&CarrierSpec> {
        self.spec.as_ref()
    }

    /// Registers a message we sent on this connection, so that the responses to it are
    /// read correctly: an index-less reply Bottle for `d` / `a` when the carrier supports
    /// replies, an acknowledgement when it requires them, and after `r` the switch to
    /// reading messages (after its acknowledgement, if any).
    ///
    /// Acknowledgements that arrive with nothing registered are accepted too, and an
    /// acknowledgement where a reply was due means the peer did not reply.
    pub fn expect_response(&mut self, command: &PortCommand) {
        let Some(spec) = self.spec else { return };
        let e = Expect {
            reply: command.expects_reply() && spec.supports_reply,
            ack: spec.requires_ack,
            reverse: command.key() == b'r',
            raw: false,
        };
        if e.reply || e.ack || e.reverse {
            self.expect.push_back(e);
        }
    }

    /// As [`Decoder::expect_response`], for a call whose reply may be no Bottle (a
    /// thrift call): such a reply ends where its acknowledgement starts, so it is only
    /// read on carriers that acknowledge.
    pub fn expect_raw_response(&mut self, command: &PortCommand) {
        self.expect_response(command);
        if let Some(e) = self.expect.back_mut().filter(|e| e.ack) {
            e.raw = true;
        }
    }

    /// Switches to reading messages now (a reversed connection, managed by the caller).
    pub fn start_messages(&mut self) {
        if matches!(self.state, State::Failed(_) | State::MessagePayload { .. }) {
            return;
        }
        self.state = match self.spec.map(|s| s.framing) {
            Some(Framing::Stream) => State::Messages,
            Some(Framing::Text) => State::TextMessages,
            _ => State::Raw,
        };
    }

    /// Appends received bytes.
    pub fn feed(&mut self, data: &[u8]) {
        if self.pos > 0 && self.pos * 2 >= self.buf.len() {
            self.buf.drain(..self.pos);
            self.pos = 0;
        }
        self.buf.extend_from_slice(data);
    }

    /// Room for reading at least `min` (at least 1) bytes straight into the decoder's
    /// buffer, without the copy of [`Decoder::feed`]: read into it, e.g. with
    /// `stream.read_buf(&mut decoder.read_buf(n))`, then [`Decoder::poll`].
    ///
    /// When the frame being read has announced its size (a message index, or a reply
    /// Bottle's strings and blobs as scanned so far), the room covers the rest of that
    /// frame too, so that it arrives into one allocation that then becomes the event's
    /// bytes. Such sizes have been checked against [`DecoderConfig::max_message_size`].
    pub fn read_buf(&mut self, min: usize) -> ReadSpace<'_> {
        let min = min.max(1);
        let pos = self.pos.min(self.buf.len());
        let have = self.buf.len() - pos;
        let frame = self.hint.min(self.config.max_message_size);
        let want = frame.saturating_sub(have).saturating_add(min);
        let spare = self.buf.capacity() - self.buf.len();
        // drop consumed bytes (a large frame then starts the buffer and can be handed
        // out without a copy); `have` is at most what earlier reads brought
        if pos > 0 && (pos == self.buf.len() || spare < want || frame >= SPLIT_MIN) {
            self.buf.drain(..pos);
            self.pos = 0;
        }
        let spare = self.buf.capacity() - self.buf.len();
        if spare < want {
            self.buf.reserve(want);
        }
        ReadSpace { buf: &mut self.buf }
    }

    /// Hands back a buffer the decoder gave out (an event's bytes, once used), to read into
    /// again: the next large frame then arrives in memory already mapped, not in a fresh
    /// allocation the kernel has to fault in page by page. Kept only if it is larger than
    /// the current buffer (and within `max_message_size`, plus room for one read).
    pub fn recycle(&mut self, mut buf: Vec<u8>) {
        let limit = self.config.max_message_size.saturating_add(SPLIT_MIN);
        if buf.capacity() <= self.buf.capacity() || buf.capacity() > limit {
            return;
        }
        buf.clear();
        buf.extend_from_slice(self.avail());
        self.buf = buf;
        self.pos = 0;
    }

    /// Bytes received but not yet turned into events (including a partial line).
    pub fn pending(&self) -> usize {
        self.buf.len().saturating_sub(self.pos)
            + usize::from(self.line.has_partial())
            + usize::from(matches!(
                self.state,
                State::TextPayload { .. } | State::MessagePayload { .. }
            ))
    }

    /// Whether the stream stopped at an event boundary (check this at end of stream).
    pub fn is_idle(&self) -> bool {
        self.pending() == 0 && self.discard == 0
    }

    /// Feeds `data` and returns every event that became complete.
    pub fn decode(&mut self, data: &[u8]) -> Result<Vec<Event>, WireError> {
        self.feed(data);
        let mut out = Vec::new();
        while let Some(ev) = self.poll()? {
            out.push(ev);
        }
        Ok(out)
    }

    /// The next event, `Ok(None)` when more bytes are needed. An error is fatal and is
    /// returned again by every later call.
    pub fn poll(&mut self) -> Result<Option<Event>, WireError> {
        if let State::Failed(e) = &self.state {
            return Err(e.clone());
        }
        loop {
            match self.step() {
                Ok(Step::Event(ev)) => return Ok(Some(ev)),
                Ok(Step::NeedMore) => return Ok(None),
                Ok(Step::Continue) => {}
                Err(e) => {
                    self.state = State::Failed(e.clone());
                    return Err(e);
                }
            }
        }
    }

    fn avail(&self) -> &[u8] {
        self.buf.get(self.pos..).unwrap_or_default()
    }

    /// Takes the frame at `buf[start..end]` out of the buffer and consumes it. A large
    /// frame that starts the buffer and fills most of it is moved out whole, the fewer
    /// bytes after it going to a new buffer; anything else is copied.
    fn take_frame(&mut self, start: usize, end: usize) -> Vec<u8> {
        let len = self.buf.len();
        let end = end.min(len);
        let start = start.min(end);
        let tail = len - end;
        let unused = self.buf.capacity() - end;
        if start == 0 && end >= SPLIT_MIN && tail <= end && unused <= end + SPLIT_MIN {
            let rest = self.buf[end..].to_vec();
            let mut frame = std::mem::replace(&mut self.buf, rest);
            frame.truncate(end);
            self.pos = 0;
            return frame;
        }
        let frame = self.buf[start..end].to_vec();
        self.pos = end;
        frame
    }

    fn framing(&self) -> Framing {
        self.spec.map(|s| s.framing).unwrap_or(Framing::Raw)
    }

    fn too_large(&self, what: &'static str, size: u64) -> Result<(), WireError> {
        if size > self.config.max_message_size as u64 {
            Err(WireError::TooLarge {
                what,
                size,
                max: self.config.max_message_size,
            })
        } else {
            Ok(())
        }
    }

    fn next_line(&mut self) -> Result<Option<Vec<u8>>, WireError> {
        let start = self.pos.min(self.buf.len());
        match self.line.push(&self.buf[start..]) {
            LineStep::Partial => {
                self.pos = self.buf.len();
                Ok(None)
            }
            LineStep::Line { line, used } => {
                self.pos = start + used;
                Ok(Some(line))
            }
            LineStep::TooLong => Err(WireError::TooLarge {
                what: "text line",
                size: self.config.max_line_len as u64 + 1,
                max: self.config.max_line_len,
            }),
        }
    }

    fn step(&mut self) -> Result<Step, WireError> {
        self.hint = 0;
        if self.discard > 0 {
            let n = (self.avail().len() as u64).min(self.discard);
            self.pos += n as usize;
            self.discard -= n;
            if self.discard > 0 {
                return Ok(Step::NeedMore);
            }
        }
        match &self.state {
            State::Failed(e) => Err(e.clone()),
            State::Header => self.step_header(),
            State::SenderName => self.step_sender_name(),
            State::TextSenderName => {
                let Some(line) = self.next_line()? else {
                    return Ok(Step::NeedMore);
                };
                self.state = State::TextMessages;
                Ok(Step::Event(Event::SenderName(line)))
            }
            State::Messages => self.step_message(),
            State::MessagePayload { len, .. } => {
                let len = *len;
                if self.avail().len() < len {
                    self.hint = len;
                    return Ok(Step::NeedMore);
                }
                let State::MessagePayload {
                    index,
                    command,
                    command_header,
                    ..
                } = std::mem::replace(&mut self.state, State::Messages)
                else {
                    return Ok(Step::Continue);
                };
                if command.key() == b'r' {
                    // the accepting port now writes on this connection; the peer acks
                    self.state = State::Responses;
                }
                let payload = self.take_frame(self.pos, self.pos + len);
                Ok(Step::Event(Event::Message(Message {
                    command,
                    payload,
                    frame: Some(BinaryFrame {
                        index,
                        command_header,
                    }),
                })))
            }
            State::TextMessages => self.step_text_message(),
            State::TextPayload { .. } => self.step_text_payload(),
            State::NameServer { swallow } => {
                let swallow = *swallow;
                if swallow > 0 {
                    let n = self.avail().len().min(swallow);
                    self.pos += n;
                    self.state = State::NameServer {
                        swallow: swallow - n,
                    };
                    return Ok(if n == swallow {
                        Step::Continue
                    } else {
                        Step::NeedMore
                    });
                }
                let Some(line) = self.next_line()? else {
                    return Ok(Step::NeedMore);
                };
                // C++ swallows "NAME_SERVER " (12 bytes) after every line end
                self.state = State::NameServer { swallow: 12 };
                Ok(Step::Event(Event::Message(Message {
                    command: PortCommand::new(b'd', Vec::new()),
                    payload: line,
                    frame: None,
                })))
            }
            State::HeaderReply => {
                let avail = self.avail();
                if avail.len() < 8 {
                    return Ok(Step::NeedMore);
                }
                let Some(n) = YarpNumber::decode(avail) else {
                    return Err(WireError::BadHeaderReply {
                        found: first8(avail),
                    });
                };
                self.pos += 8;
                self.state = if self.framing() == Framing::Stream {
                    State::Responses
                } else {
                    State::Raw
                };
                Ok(Step::Event(Event::HeaderReply(n.0)))
            }
            State::Welcome => {
                let Some(line) = self.next_line()? else {
                    return Ok(Step::NeedMore);
                };
                self.state = State::TextResponses;
                let name = line
                    .strip_prefix(WELCOME_PREFIX)
                    .map(<[u8]>::to_vec)
                    .unwrap_or(line);
                Ok(Step::Event(Event::Welcome(name)))
            }
            State::Responses => self.step_response(),
            State::TextResponses => self.step_text_response(),
            State::Raw => {
                let avail = self.avail();
                if avail.is_empty() {
                    return Ok(Step::NeedMore);
                }
                let bytes = self.take_frame(self.pos, self.buf.len());
                Ok(Step::Event(Event::Raw(bytes)))
            }
        }
    }

    fn step_header(&mut self) -> Result<Step, WireError> {
        let avail = self.avail();
        if avail.len() < 8 {
            return Ok(Step::NeedMore);
        }
        let header = self.config.registry.classify(&first8(avail))?;
        self.pos += 8;
        self.spec = Some(header.spec);
        self.state = match header.spec.framing {
            Framing::Stream | Framing::Handshake | Framing::Local => State::SenderName,
            Framing::Text => State::TextSenderName,
            Framing::NameServer => State::NameServer { swallow: 4 },
            Framing::Raw => State::Raw,
        };
        Ok(Step::Event(Event::Header(header)))
    }

    fn step_sender_name(&mut self) -> Result<Step, WireError> {
        let avail = self.avail();
        let Some(len) = read_i32(avail, 0) else {
            return Ok(Step::NeedMore);
        };
        // C++ clamps the length to 1..=1000 and reads that many bytes
        let n = len.clamp(1, MAX_SENDER_NAME as i32) as usize;
        let Some(raw) = avail.get(4..4 + n) else {
            return Ok(Step::NeedMore);
        };
        let name = match raw.iter().position(|&b| b == 0) {
            Some(nul) => raw[..nul].to_vec(),
            None => raw.to_vec(),
        };
        self.pos += 4 + n;
        self.state = if self.framing() == Framing::Stream {
            State::Messages
        } else {
            State::Raw
        };
        Ok(Step::Event(Event::SenderName(name)))
    }

    fn step_message(&mut self) -> Result<Step, WireError> {
        let max = self.config.max_message_size;
        let avail = self.buf.get(self.pos..).unwrap_or_default();
        if avail.len() < 8 {
            return Ok(Step::NeedMore);
        }
        if YarpNumber::decode(avail) != Some(YarpNumber(INDEX_VALUE)) {
            return Err(WireError::BadIndex {
                found: first8(avail),
            });
        }
        let Some(fixed) = avail.get(8..INDEX_FIXED_LEN) else {
            return Ok(Step::NeedMore);
        };
        let n_blocks = fixed[0] as usize;
        let n_replies = fixed[1] as usize;
        let mut reserved = [0u8; 8];
        reserved.copy_from_slice(&fixed[2..10]);
        let index_len = INDEX_FIXED_LEN + 4 * (n_blocks + n_replies);
        if avail.len() < index_len {
            return Ok(Step::NeedMore);
        }
        let mut block_lens = Vec::with_capacity(n_blocks);
        for i in 0..n_blocks {
            let len = read_i32(avail, INDEX_FIXED_LEN + 4 * i).unwrap_or(0);
            if len < 0 {
                return Err(WireError::NegativeBlockLength { block: i, len });
            }
            block_lens.push(len as u32);
        }
        let reply_lens: Vec<u32> = (0..n_replies)
            .map(|i| read_i32(avail, INDEX_FIXED_LEN + 4 * (n_blocks + i)).unwrap_or(0) as u32)
            .collect();
        let index = Index {
            block_lens,
            reply_lens,
            reserved,
        };
        let body_len = index.body_len();
        if body_len > max as u64 {
            return Err(WireError::TooLarge {
                what: "message",
                size: body_len,
                max,
            });
        }
        let end = index_len + body_len as usize;
        let Some(body) = avail.get(index_len..end) else {
            // a large body: once its port command is in, read the payload on its own so
            // that it can be handed out without a copy
            if body_len as usize >= SPLIT_MIN {
                let have = avail.get(index_len..).unwrap_or_default();
                // (a command that cannot be decoded yet waits for the whole body)
                if let Ok((command, used)) = PortCommand::decode_binary(have) {
                    let mut command_header = [0u8; 8];
                    command_header.copy_from_slice(&have[..8]);
                    self.pos += index_len + used;
                    self.state = State::MessagePayload {
                        index,
                        command,
                        command_header,
                        len: body_len as usize - used,
                    };
                    return Ok(Step::Continue);
                }
            }
            self.hint = end;
            return Ok(Step::NeedMore);
        };
        let (body_at, body_end) = (self.pos + index_len, self.pos + end);
        let event = match PortCommand::decode_binary(body) {
            Ok((command, used)) => {
                let mut command_header = [0u8; 8];
                command_header.copy_from_slice(&body[..8]);
                if command.key() == b'r' {
                    // the accepting port now writes on this connection; the peer acks
                    self.state = State::Responses;
                }
                Event::Message(Message {
                    command,
                    payload: self.take_frame(body_at + used, body_end),
                    frame: Some(BinaryFrame {
                        index,
                        command_header,
                    }),
                })
            }
            Err(error) => Event::InvalidMessage {
                index,
                body: self.take_frame(body_at, body_end),
                error,
            },
        };
        Ok(Step::Event(event))
    }

    fn step_text_message(&mut self) -> Result<Step, WireError> {
        let Some(line) = self.next_line()? else {
            return Ok(Step::NeedMore);
        };
        if line == ACK_TEXT {
            return Ok(Step::Event(Event::Ack(0)));
        }
        let command = PortCommand::from_line(line);
        if matches!(command.key(), b'd' | b'D' | b'a') {
            self.state = State::TextPayload {
                command,
                text: Vec::new(),
                join: Join::First,
                check: CompletenessCheck::default(),
            };
            return Ok(Step::Continue);
        }
        Ok(Step::Event(Event::Message(Message {
            command,
            payload: Vec::new(),
            frame: None,
        })))
    }

    /// The Bottle text after `d`/`D`/`a`, read as C++ `BottleImpl::read` in text mode: a
    /// trailing backslash joins the next line; an incomplete text (open parenthesis or
    /// quote) continues on the next line after a `\n`.
    fn step_text_payload(&mut self) -> Result<Step, WireError> {
        let Some(line) = self.next_line()? else {
            return Ok(Step::NeedMore);
        };
        let State::TextPayload {
            command,
            mut text,
            join,
            mut check,
        } = std::mem::replace(&mut self.state, State::TextMessages)
        else {
            return Ok(Step::Continue);
        };
        let start = text.len();
        if join == Join::Newline {
            text.push(b'\n');
        }
        text.extend_from_slice(&line);
        self.too_large("text message", text.len() as u64)?;
        let done = if join == Join::First && text.is_empty() {
            true
        } else if text.last() == Some(&b'\\') {
            text.pop();
            // the backslash may have come from an earlier line (an empty line joined)
            check.feed(&text[start.min(text.len())..]);
            self.state = State::TextPayload {
                command,
                text,
                join: Join::Concat,
                check,
            };
            return Ok(Step::Continue);
        } else {
            check.feed(&text[start..]);
            check.is_complete() || text.is_empty()
        };
        if done {
            return Ok(Step::Event(Event::Message(Message {
                command,
                payload: text,
                frame: None,
            })));
        }
        self.state = State::TextPayload {
            command,
            text,
            join: Join::Newline,
            check,
        };
        Ok(Step::Continue)
    }

    /// Pops leading expectations that need nothing more; true when that switched the
    /// connection to reading messages.
    fn settle_expectations(&mut self) -> bool {
        while let Some(f) = self.expect.front().copied() {
            if f.reply || f.ack {
                break;
            }
            self.expect.pop_front();
            if f.reverse {
                self.start_messages();
                return true;
            }
        }
        false
    }

    fn step_response(&mut self) -> Result<Step, WireError> {
        if self.settle_expectations() {
            return Ok(Step::Continue);
        }
        let avail = self.avail();
        if avail.len() < 8 {
            return Ok(Step::NeedMore);
        }
        let reply_due = self.expect.front().is_some_and(|f| f.reply);
        if reply_due && !YarpNumber::is_at(avail) {
            return self.step_reply();
        }
        let Some(YarpNumber(value)) = YarpNumber::decode(avail) else {
            return Err(WireError::BadAck {
                found: first8(avail),
            });
        };
        if value < 0 {
            return Err(WireError::BadAck {
                found: first8(avail),
            });
        }
        self.too_large("acknowledgement payload", value as u64)?;
        self.pos += 8;
        self.discard = value as u64;
        if let Some(f) = self.expect.pop_front() {
            if f.reverse {
                self.start_messages();
            }
        }
        Ok(Step::Event(Event::Ack(value)))
    }

    fn step_reply(&mut self) -> Result<Step, WireError> {
        let start = self.pos;
        let avail_len = self.avail().len() as u64;
        if avail_len < self.need {
            self.hint = self.need as usize;
            return Ok(Step::NeedMore);
        }
        let scanner = self.scanner.get_or_insert_with(BottleScanner::new);
        let scan = match scanner.scan(self.buf.get(start..).unwrap_or_default()) {
            Ok(scan) => scan,
            Err(e) if self.expect.front().is_some_and(|f| f.raw) => {
                // A reply that is no Bottle (a thrift server's protocol version: a list
                // header, then raw int16s) ends where the acknowledgement starts, as the
                // C++ reader that knows its form would stop there.
                self.scanner = None;
                let avail = self.avail();
                match (1..avail.len()).find(|&i| YarpNumber::is_at(&avail[i..])) {
                    Some(end) => Scan::Complete(end),
                    None if avail.len() < RAW_REPLY_MAX => {
                        self.need = avail_len + 8;
                        self.hint = self.need as usize;
                        return Ok(Step::NeedMore);
                    }
                    None => return Err(WireError::BadReply(e)),
                }
            }
            Err(e) => return Err(WireError::BadReply(e)),
        };
        match scan {
            Scan::NeedAtLeast(n) => {
                self.too_large("reply", n)?;
                self.need = n;
                self.hint = n as usize;
                Ok(Step::NeedMore)
            }
            Scan::Complete(end) => {
                // the scanner applies the rules of `Bottle::decode`: these bytes decode
                let bytes = self.take_frame(start, start + end);
                self.scanner = None;
                self.need = 0;
                if let Some(f) = self.expect.front_mut() {
                    f.reply = false;
                }
                Ok(Step::Event(Event::Reply(bytes)))
            }
        }
    }

    fn step_text_response(&mut self) -> Result<Step, WireError> {
        if self.settle_expectations() {
            return Ok(Step::Continue);
        }
        let Some(line) = self.next_line()? else {
            return Ok(Step::NeedMore);
        };
        if line == ACK_TEXT {
            if let Some(f) = self.expect.pop_front() {
                if f.reverse {
                    self.start_messages();
                }
            }
            return Ok(Step::Event(Event::Ack(0)));
        }
        Ok(Step::Event(Event::Line(line)))
    }
}

fn first8(bytes: &[u8]) -> [u8; 8] {
    let mut a = [0u8; 8];
    let n = bytes.len().min(8);
    a[..n].copy_from_slice(&bytes[..n]);
    a
}

fn read_i32(buf: &[u8], at: usize) -> Option<i32> {
    let b = buf.get(at..at.checked_add(4)?)?;
    Some(i32::from_le_bytes([b[0], b[1], b[2], b[3]]))
}
