//! Encoders for the text carriers (`text`, `text_ack`), byte-exact with C++ YARP.
//!
//! A text connection starts with `CONNECT <sender>\r\n` (`CONNACK` for text_ack); the
//! accepting port answers `Welcome <sender>\r\n`. Each message is the port command line
//! (`D`, `d`, `a`, or a text command such as `q`, `*`, `~/port`) and, for data and admin
//! messages, the Bottle text on the next line. C++ writes `\r\n` line ends. With
//! text_ack the receiver answers `<ACK>\r\n` after every message (after the reply line,
//! if any).

use super::command::PortCommand;
use crate::{Bottle, Stamp};

/// The acknowledgement line of text_ack.
pub const ACK_LINE: &[u8] = b"<ACK>\r\n";
/// The acknowledgement line without its line end (as a line reader returns it).
pub const ACK_TEXT: &[u8] = b"<ACK>";
/// The welcome line starts with this.
pub const WELCOME_PREFIX: &[u8] = b"Welcome ";

/// `CONNECT <sender>\r\n`, or `CONNACK <sender>\r\n` for text_ack.
pub fn connect_line(ack: bool, sender: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(10 + sender.len());
    out.extend_from_slice(if ack { b"CONNACK " } else { b"CONNECT " });
    out.extend_from_slice(sender);
    out.extend_from_slice(b"\r\n");
    out
}

/// The accepting port's answer: `Welcome <sender>\r\n` (C++ `TextCarrier::respondToHeader`).
pub fn welcome_line(sender: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(10 + sender.len());
    out.extend_from_slice(WELCOME_PREFIX);
    out.extend_from_slice(sender);
    out.extend_from_slice(b"\r\n");
    out
}

/// Appends a text-mode message: the command line, then — for data and admin commands —
/// the payload line (Bottle text). Other commands carry no payload line.
pub fn encode_message(command: &PortCommand, payload: &[u8], out: &mut Vec<u8>) {
    command.encode_text(out);
    if matches!(command.key(), b'd' | b'D' | b'a') {
        out.extend_from_slice(payload);
        out.extend_from_slice(b"\r\n");
    }
}

/// A data message as C++ writers send it over text: `D\r\n<bottle text>\r\n`
/// (`d` when a reply is wanted).
pub fn data_message(bottle: &Bottle, reply: bool) -> Vec<u8> {
    let mut out = Vec::new();
    encode_message(&PortCommand::data(reply), &bottle.to_text(), &mut out);
    out
}

/// A data message with an envelope: `D <count> <time>\r\n<bottle text>\r\n`.
pub fn envelope_message(bottle: &Bottle, stamp: &Stamp, reply: bool) -> Vec<u8> {
    let mut out = Vec::new();
    encode_message(
        &PortCommand::with_stamp(stamp, reply),
        &bottle.to_text(),
        &mut out,
    );
    out
}

/// An administrative message: `a\r\n<bottle text>\r\n`.
pub fn admin_message(bottle: &Bottle) -> Vec<u8> {
    let mut out = Vec::new();
    encode_message(&PortCommand::admin(), &bottle.to_text(), &mut out);
    out
}

/// A text command line (`q\r\n`, `*\r\n`, `~/w\r\n`, `r\r\n` ...).
pub fn command_line(text: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(text.len() + 2);
    PortCommand::text(text.to_vec()).encode_text(&mut out);
    out
}

/// A reply over a text carrier: the Bottle text and `\r\n`, then `<ACK>\r\n` for text_ack.
pub fn reply_message(bottle: &Bottle, with_ack: bool) -> Vec<u8> {
    let mut out = bottle.to_text();
    out.extend_from_slice(b"\r\n");
    if with_ack {
        out.extend_from_slice(ACK_LINE);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bottle;

    #[test]
    fn cpp_text_bytes() {
        assert_eq!(connect_line(false, b"/w"), b"CONNECT /w\r\n");
        assert_eq!(connect_line(true, b"/w"), b"CONNACK /w\r\n");
        assert_eq!(welcome_line(b"/w"), b"Welcome /w\r\n");
        assert_eq!(
            data_message(&bottle!["hello", 42], false),
            b"D\r\nhello 42\r\n"
        );
        assert_eq!(command_line(b"q"), b"q\r\n");
        assert_eq!(reply_message(&Bottle::new(), true), b"\r\n<ACK>\r\n");
        assert_eq!(
            envelope_message(&bottle![1], &Stamp::new(3, 1.5), false),
            b"D 3 1.5\r\n1\r\n"
        );
    }
}
