//! Index-less binary framing, as the `unix_stream` carriers use it after their handshake.
//!
//! C++'s `UnixSocketCarrier` sends no message index: each message is the binary port
//! command (8 bytes, then its NUL-terminated text when `ch = 0`) followed by the payload,
//! a Bottle that delimits itself. The `unix_stream_ack` flavour answers every message
//! with the 4 bytes `ACK\0`.

use super::command::{CommandKind, PortCommand, HEADER_LEN};
use super::error::WireError;
use super::message::{BinaryFrame, Index, Message};
use super::scan::{BottleScanner, Scan};

/// What `unix_stream_ack` receivers answer to every message.
pub const UNIX_ACK: &[u8; 4] = b"ACK\0";

/// Appends one index-less message: the binary port command, then `payload`.
pub fn encode_indexless(cmd: &PortCommand, payload: &[u8], out: &mut Vec<u8>) {
    cmd.encode_binary(out);
    out.extend_from_slice(payload);
}

/// Splits an index-less byte stream into messages (sans-I/O: feed bytes, poll messages).
#[derive(Debug, Default)]
pub struct IndexlessDecoder {
    buf: Vec<u8>,
    /// The command of the message being read, and where its payload starts.
    command: Option<(PortCommand, [u8; 8], usize)>,
    scanner: BottleScanner,
    max_message: usize,
}

impl IndexlessDecoder {
    /// A decoder refusing messages larger than `max_message` bytes.
    pub fn new(max_message: usize) -> IndexlessDecoder {
        IndexlessDecoder {
            max_message,
            ..IndexlessDecoder::default()
        }
    }

    /// Appends received bytes.
    pub fn feed(&mut self, bytes: &[u8]) {
        self.buf.extend_from_slice(bytes);
    }

    /// The next complete message, if the bytes fed so far hold one.
    pub fn poll(&mut self) -> Result<Option<Message>, WireError> {
        if self.command.is_none() {
            if self.buf.len() < HEADER_LEN {
                return Ok(None);
            }
            let (command, used) = match PortCommand::decode_binary(&self.buf) {
                Ok(c) => c,
                // the text may still be arriving
                Err(WireError::UnterminatedCommandText) if self.buf.len() <= self.max_message => {
                    return Ok(None)
                }
                Err(e) => return Err(e),
            };
            let mut header = [0u8; 8];
            header.copy_from_slice(&self.buf[..HEADER_LEN]);
            self.command = Some((command, header, used));
            self.scanner = BottleScanner::new();
        }
        let Some((command, header, start)) = self.command.clone() else {
            return Ok(None);
        };
        // only data and admin messages carry a payload
        let payload_len = if matches!(
            command.kind(),
            CommandKind::Data { .. } | CommandKind::Admin
        ) {
            match self
                .scanner
                .scan(&self.buf[start..])
                .map_err(WireError::BadReply)?
            {
                Scan::Complete(n) => n,
                Scan::NeedAtLeast(n) => {
                    if n > self.max_message as u64 {
                        return Err(WireError::TooLarge {
                            what: "message",
                            size: n,
                            max: self.max_message,
                        });
                    }
                    return Ok(None);
                }
            }
        } else {
            0
        };
        let end = start + payload_len;
        let payload = self.buf[start..end].to_vec();
        self.buf.drain(..end);
        self.command = None;
        Ok(Some(Message {
            command,
            payload,
            frame: Some(BinaryFrame {
                index: Index::new(vec![start as u32, payload_len as u32]),
                command_header: header,
            }),
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{bottle, Bottle, Stamp};

    #[test]
    fn messages_split_at_any_byte() {
        let mut bytes = Vec::new();
        let a = bottle!["hello", 42, 1.5];
        let b = Bottle::from_text("(1 2 3) x {1.5 2.5}");
        encode_indexless(&PortCommand::data(false), &a.encode(), &mut bytes);
        encode_indexless(
            &PortCommand::with_stamp(&Stamp::new(7, 2.5), false),
            &b.encode(),
            &mut bytes,
        );
        encode_indexless(&PortCommand::close(), &[], &mut bytes);
        for chunk in [1, 3, 7, 1000] {
            let mut d = IndexlessDecoder::new(1 << 20);
            let mut got = Vec::new();
            for piece in bytes.chunks(chunk) {
                d.feed(piece);
                while let Some(m) = d.poll().unwrap() {
                    got.push(m);
                }
            }
            assert_eq!(got.len(), 3, "chunk {chunk}");
            assert_eq!(got[0].bottle().unwrap(), a);
            assert_eq!(got[1].bottle().unwrap(), b);
            assert_eq!(got[1].stamp(), Some(Stamp::new(7, 2.5)));
            assert_eq!(got[2].command.kind(), CommandKind::Close);
        }
    }

    #[test]
    fn garbage_and_oversize_are_errors() {
        let mut d = IndexlessDecoder::new(1 << 20);
        d.feed(b"garbage!garbage!");
        assert!(d.poll().is_err());
        let mut d = IndexlessDecoder::new(64);
        let big = Bottle::from_text(format!("{{{}}}", "1 ".repeat(100)));
        let mut bytes = Vec::new();
        encode_indexless(&PortCommand::data(false), &big.encode(), &mut bytes);
        d.feed(&bytes[..40]);
        assert!(matches!(d.poll(), Err(WireError::TooLarge { .. })));
    }
}
