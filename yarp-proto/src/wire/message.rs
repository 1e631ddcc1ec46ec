//! tcp-family messages: the index, the blocks, and encoders reproducing C++'s bytes.
//!
//! A message on the wire is
//! `YA 10 RP`, `[n_blocks] [n_reply_slots] ff*8`, `n_blocks` int32 LE block lengths,
//! `n_reply_slots` int32 LE reply lengths (C++ always announces one, `0`), then the
//! blocks. The blocks concatenated are the port command followed by the payload. How a
//! sender cuts its message into blocks carries no meaning; C++ (`BufferedConnectionWriter`)
//! puts the port command (with its text) in one block and a Bottle in the next, and
//! Portables writing external data (images, vectors) add more blocks.

use super::command::PortCommand;
use super::number::{YarpNumber, ACK, INDEX_MARKER};
use crate::{Bottle, DecodeError, Stamp};

/// A message index holds at most 255 block lengths (the count is one byte).
pub const MAX_BLOCKS: usize = 255;

/// The fixed part of an index: marker (8) + 10 bytes.
pub const INDEX_FIXED_LEN: usize = 18;

/// A message index.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Index {
    /// Lengths of the data blocks, in order.
    pub block_lens: Vec<u32>,
    /// The reply-length slots (C++ always sends one slot holding 0, and ignores them
    /// when framing).
    pub reply_lens: Vec<u32>,
    /// Bytes 2..10 after the marker (`ff` * 8 from C++; ignored by readers).
    pub reserved: [u8; 8],
}

impl Index {
    /// An index as C++ writes it for these block lengths.
    pub fn new(block_lens: Vec<u32>) -> Index {
        Index {
            block_lens,
            reply_lens: vec![0],
            reserved: [0xff; 8],
        }
    }

    /// Total length of the blocks (the message body).
    pub fn body_len(&self) -> u64 {
        self.block_lens.iter().map(|&l| l as u64).sum()
    }

    pub fn encoded_len(&self) -> usize {
        INDEX_FIXED_LEN + 4 * (self.block_lens.len() + self.reply_lens.len())
    }

    /// Appends the index bytes. Counts above 255 are truncated to one byte as C++ does;
    /// [`encode_message`] never produces such an index.
    pub fn encode(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&INDEX_MARKER);
        out.push(self.block_lens.len() as u8);
        out.push(self.reply_lens.len() as u8);
        out.extend_from_slice(&self.reserved);
        for l in self.block_lens.iter().chain(&self.reply_lens) {
            out.extend_from_slice(&l.to_le_bytes());
        }
    }
}

/// How a received message was framed on a binary connection.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BinaryFrame {
    pub index: Index,
    /// The 8 port-command bytes exactly as received (including the unchecked `n`).
    pub command_header: [u8; 8],
}

/// A received message: port command and payload.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Message {
    pub command: PortCommand,
    /// Binary: the blocks after the port command (and its text), concatenated — a Bottle
    /// or other Portable encoding. Text carriers: the data line(s) of `d`/`D`/`a`
    /// commands, i.e. Bottle text; empty for other commands.
    pub payload: Vec<u8>,
    /// `Some` for binary (tcp-family) messages, `None` for text carriers.
    pub frame: Option<BinaryFrame>,
}

impl Message {
    pub fn is_text(&self) -> bool {
        self.frame.is_none()
    }

    /// The payload as a Bottle (binary decode, or text parse for text carriers).
    pub fn bottle(&self) -> Result<Bottle, DecodeError> {
        if self.is_text() {
            Ok(Bottle::from_text(&self.payload))
        } else {
            Bottle::decode(&self.payload)
        }
    }

    /// The envelope of a data message, as a [`Stamp`].
    pub fn stamp(&self) -> Option<Stamp> {
        self.command.stamp()
    }

    /// The message bytes: for binary messages exactly what was received (index, port
    /// command as received, text, payload); for text messages the canonical CRLF form.
    pub fn to_wire(&self) -> Vec<u8> {
        match &self.frame {
            Some(frame) => {
                let mut out =
                    Vec::with_capacity(frame.index.encoded_len() + frame.index.body_len() as usize);
                frame.index.encode(&mut out);
                out.extend_from_slice(&frame.command_header);
                if frame.command_header[5] == 0 {
                    out.extend_from_slice(&self.command.text);
                    out.push(0);
                }
                out.extend_from_slice(&self.payload);
                out
            }
            None => {
                let mut out = Vec::new();
                super::text_carrier::encode_message(&self.command, &self.payload, &mut out);
                out
            }
        }
    }
}

/// Appends a complete binary message: index, then the blocks `[port command (+text),
/// payload_blocks...]`. Blocks beyond the 255 an index can count are merged into the
/// last one (receivers concatenate blocks, so the bytes mean the same).
pub fn encode_message(command: &PortCommand, payload_blocks: &[&[u8]], out: &mut Vec<u8>) {
    let mut lens = Vec::with_capacity(1 + payload_blocks.len().min(MAX_BLOCKS));
    lens.push(command.binary_len() as u32);
    for (i, b) in payload_blocks.iter().enumerate() {
        if i + 1 < MAX_BLOCKS {
            lens.push(b.len() as u32);
        } else if let Some(last) = lens.last_mut() {
            *last = last.wrapping_add(b.len() as u32);
        }
    }
    let index = Index::new(lens);
    out.reserve(
        index.encoded_len()
            + command.binary_len()
            + payload_blocks.iter().map(|b| b.len()).sum::<usize>(),
    );
    index.encode(out);
    command.encode_binary(out);
    for b in payload_blocks {
        out.extend_from_slice(b);
    }
}

/// A Bottle sent as C++ `yarp write` / `Port::write` sends it: blocks
/// `[port command 'D' (or 'd' when a reply is wanted), Bottle]`.
pub fn data_message(bottle: &Bottle, reply: bool) -> Vec<u8> {
    let payload = bottle.encode();
    let mut out = Vec::new();
    encode_message(&PortCommand::data(reply), &[&payload], &mut out);
    out
}

/// A Bottle with an envelope: blocks `[port command + "D <count> <time>\0", Bottle]`.
pub fn envelope_message(bottle: &Bottle, stamp: &Stamp, reply: bool) -> Vec<u8> {
    let payload = bottle.encode();
    let mut out = Vec::new();
    encode_message(
        &PortCommand::with_stamp(stamp, reply),
        &[&payload],
        &mut out,
    );
    out
}

/// An administrative Bottle: blocks `[port command 'a', Bottle]`.
pub fn admin_message(bottle: &Bottle) -> Vec<u8> {
    let payload = bottle.encode();
    let mut out = Vec::new();
    encode_message(&PortCommand::admin(), &[&payload], &mut out);
    out
}

/// The close message C++ sends when removing an output: one block `[02000000 7e000001 7100]`.
pub fn close_message() -> Vec<u8> {
    let mut out = Vec::new();
    encode_message(&PortCommand::close(), &[], &mut out);
    out
}

/// A text port command (`*`, `help`, `/port` ...) as a one-block message.
pub fn command_message(command: &PortCommand) -> Vec<u8> {
    let mut out = Vec::new();
    encode_message(command, &[], &mut out);
    out
}

/// The acknowledgement (tcp): YARP number 0.
pub fn ack() -> [u8; 8] {
    ACK
}

/// An acknowledgement carrying `n` extra bytes the receiver must discard (C++ accepts
/// these; YARP itself always sends 0).
pub fn ack_with_len(n: i32) -> [u8; 8] {
    YarpNumber(n).to_bytes()
}

/// An RPC reply as C++ writes it: the Bottle bytes with no index, followed by the
/// acknowledgement when the carrier requires one.
pub fn reply_message(bottle: &Bottle, with_ack: bool) -> Vec<u8> {
    let mut out = bottle.encode();
    if with_ack {
        out.extend_from_slice(&ACK);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bottle;

    fn hex(b: &[u8]) -> String {
        b.iter().map(|x| format!("{x:02x}")).collect()
    }

    #[test]
    fn yarp_write_bytes() {
        let b = bottle!["hello", 42];
        assert_eq!(
            hex(&data_message(&b, false)),
            "59410a00000052500201ffffffffffffffff080000001d00000000000000\
             000000007e440001\
             0001000002000000040000000500000068656c6c6f010000002a000000"
        );
        assert_eq!(
            hex(&close_message()),
            "59410a00000052500101ffffffffffffffff0a00000000000000020000007e0000017100"
        );
        assert_eq!(
            hex(&reply_message(&Bottle::new(), true)),
            "00010000000000005941000000005250"
        );
    }

    #[test]
    fn too_many_blocks_are_merged() {
        let blocks: Vec<Vec<u8>> = (0..300).map(|i| vec![i as u8]).collect();
        let refs: Vec<&[u8]> = blocks.iter().map(|b| b.as_slice()).collect();
        let mut out = Vec::new();
        encode_message(&PortCommand::data(false), &refs, &mut out);
        assert_eq!(out[8], 255);
        let total: u64 = (0..255)
            .map(|i| {
                u32::from_le_bytes([
                    out[18 + 4 * i],
                    out[19 + 4 * i],
                    out[20 + 4 * i],
                    out[21 + 4 * i],
                ]) as u64
            })
            .sum();
        assert_eq!(total, 8 + 300);
    }
}
