//! Port commands: the first thing in every message (C++ `PortCommand`).
//!
//! Binary form (8 bytes): int32 LE `n`, `'~'`, `ch`, `0`, `1`. With `ch = 0` a
//! NUL-terminated text of `n` bytes (NUL included) follows; C++ then uses the text's first
//! character as the command key. Text form: one line whose first character is the key.

use super::error::WireError;
use crate::Stamp;

/// Length of the binary port-command header.
pub const HEADER_LEN: usize = 8;

/// A port command as it travels: `ch` (0 when the command is carried as text) and the
/// text (without its NUL terminator; empty when `ch != 0`).
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct PortCommand {
    pub ch: u8,
    pub text: Vec<u8>,
}

/// What a port command asks for, as C++ `PortCoreInputUnit` dispatches on the key.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum CommandKind {
    /// `D` (no reply wanted) or `d` (reply wanted): user data follows. The text after
    /// `"D "` / `"d "`, if any, is the envelope.
    Data { reply: bool },
    /// `a`: an administrative Bottle follows; a reply comes back.
    Admin,
    /// `q`: disconnect.
    Close,
    /// `*`: describe the port.
    Describe,
    /// `?` or `h` (so also `help` and any word starting with `h`): print the help.
    Help,
    /// `r`: reverse the connection (the accepting port starts writing on it).
    Reverse,
    /// `/port`: add an output to that port.
    AddOutput(Vec<u8>),
    /// `!/port`: remove that output.
    RemoveOutput(Vec<u8>),
    /// `~/port`: remove that input.
    RemoveInput(Vec<u8>),
    /// `i`: interrupt (debug builds of C++ only).
    Interrupt,
    /// Anything else (C++ answers "Port command not understood." in text mode).
    Unknown(u8),
}

impl PortCommand {
    pub fn new(ch: u8, text: impl Into<Vec<u8>>) -> PortCommand {
        PortCommand {
            ch,
            text: text.into(),
        }
    }

    /// `D` (no reply) or `d` (reply wanted), as a `yarp write` / RPC client sends it.
    pub fn data(reply: bool) -> PortCommand {
        PortCommand::new(if reply { b'd' } else { b'D' }, Vec::new())
    }

    /// `a`: administrative message.
    pub fn admin() -> PortCommand {
        PortCommand::new(b'a', Vec::new())
    }

    /// A command carried as text (`ch = 0`), e.g. `q`, `*`, `help`, `/port`.
    pub fn text(text: impl Into<Vec<u8>>) -> PortCommand {
        PortCommand::new(0, text)
    }

    /// `q` as C++ sends it when closing an output (`PortCommand('\0', "q")`).
    pub fn close() -> PortCommand {
        PortCommand::text(b"q".to_vec())
    }

    /// Data with an envelope: text `"D <envelope>"` (or `"d ..."` when a reply is wanted).
    pub fn with_envelope(envelope: &[u8], reply: bool) -> PortCommand {
        let mut t = Vec::with_capacity(2 + envelope.len());
        t.extend_from_slice(if reply { b"d " } else { b"D " });
        t.extend_from_slice(envelope);
        PortCommand::text(t)
    }

    /// Data with a [`Stamp`] envelope (`D 3092 1795297706.58327`).
    pub fn with_stamp(stamp: &Stamp, reply: bool) -> PortCommand {
        PortCommand::with_envelope(stamp.to_text().as_bytes(), reply)
    }

    /// A text-mode command line (text carriers): the whole line is the text.
    pub fn from_line(line: impl Into<Vec<u8>>) -> PortCommand {
        PortCommand::text(line)
    }

    /// The key C++ dispatches on: `ch`, or the first text byte when `ch = 0`
    /// (0 for an empty text).
    pub fn key(&self) -> u8 {
        if self.ch != 0 {
            self.ch
        } else {
            self.text.first().copied().unwrap_or(0)
        }
    }

    /// The argument of `/`, `!` and `~` commands as C++ takes it.
    fn arg(&self, skip: usize) -> Vec<u8> {
        self.text.get(skip..).unwrap_or_default().to_vec()
    }

    pub fn kind(&self) -> CommandKind {
        match self.key() {
            b'D' => CommandKind::Data { reply: false },
            b'd' => CommandKind::Data { reply: true },
            b'a' => CommandKind::Admin,
            b'q' => CommandKind::Close,
            b'*' => CommandKind::Describe,
            b'?' | b'h' => CommandKind::Help,
            b'r' => CommandKind::Reverse,
            b'/' => CommandKind::AddOutput(self.arg(0)),
            b'!' => CommandKind::RemoveOutput(self.arg(1)),
            b'~' => CommandKind::RemoveInput(self.arg(1)),
            b'i' => CommandKind::Interrupt,
            k => CommandKind::Unknown(k),
        }
    }

    /// Whether the receiving port answers with a reply (data with `d`, and admin).
    pub fn expects_reply(&self) -> bool {
        matches!(self.key(), b'd' | b'a')
    }

    /// The envelope text of a data command (`"3092 1795297706.58327"` from
    /// `"D 3092 1795297706.58327"`): C++ takes everything after the first two characters
    /// when the text is longer than 2.
    pub fn envelope_text(&self) -> Option<&[u8]> {
        match self.key() {
            b'D' | b'd' if self.text.len() > 2 => self.text.get(2..),
            _ => None,
        }
    }

    /// The envelope read as a [`Stamp`] (`count time`).
    pub fn stamp(&self) -> Option<Stamp> {
        let env = self.envelope_text()?;
        Stamp::from_text(std::str::from_utf8(env).ok()?)
    }

    /// The 8-byte binary header as C++ writes it (`n` = text length + 1 when `ch = 0`,
    /// else 0).
    pub fn header(&self) -> [u8; 8] {
        let n: i32 = if self.ch == 0 {
            (self.text.len() as i32).wrapping_add(1)
        } else {
            0
        };
        let n = n.to_le_bytes();
        [n[0], n[1], n[2], n[3], b'~', self.ch, 0, 1]
    }

    /// Length of the binary form (header, plus text and NUL when `ch = 0`).
    pub fn binary_len(&self) -> usize {
        if self.ch == 0 {
            HEADER_LEN + self.text.len() + 1
        } else {
            HEADER_LEN
        }
    }

    /// Appends the binary form: C++ writes header and text into one block.
    pub fn encode_binary(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.header());
        if self.ch == 0 {
            out.extend_from_slice(&self.text);
            out.push(0);
        }
    }

    /// Appends the text-mode form: the key character (or the text) and `\r\n`.
    pub fn encode_text(&self, out: &mut Vec<u8>) {
        if self.ch != 0 {
            out.push(self.ch);
        } else {
            out.extend_from_slice(&self.text);
        }
        out.extend_from_slice(b"\r\n");
    }

    /// Reads a binary port command at the start of a message body. Returns the command
    /// and the number of body bytes it used. The `n` field is not trusted (C++ reads the
    /// text up to its NUL regardless of `n`).
    pub fn decode_binary(body: &[u8]) -> Result<(PortCommand, usize), WireError> {
        let header: [u8; 8] = match body.get(..HEADER_LEN) {
            Some(h) => {
                let mut a = [0u8; 8];
                a.copy_from_slice(h);
                a
            }
            None => return Err(WireError::ShortPortCommand { len: body.len() }),
        };
        if header[4] != b'~' {
            return Err(WireError::BadPortCommand { header });
        }
        let ch = header[5];
        if ch != 0 {
            return Ok((PortCommand::new(ch, Vec::new()), HEADER_LEN));
        }
        let rest = body.get(HEADER_LEN..).unwrap_or_default();
        match rest.iter().position(|&b| b == 0) {
            Some(nul) => Ok((
                PortCommand::text(rest[..nul].to_vec()),
                HEADER_LEN + nul + 1,
            )),
            None => Err(WireError::UnterminatedCommandText),
        }
    }
}

/// The port help C++ YARP (release build) sends back over text connections for `?`,
/// `h`, `help`, or any line starting with `h`.
pub const PORT_HELP: &str = "This is a YARP port.  Here are the commands it responds to:\r\n\
*       Gives a description of this port\r\n\
d       Signals the beginning of input for the port's owner\r\n\
do      The same as \"d\" except replies should be suppressed (\"data-only\")\r\n\
q       Disconnects\r\n\
r       Reverse connection type to be a reader\r\n\
/port   Requests to send output to /port\r\n\
!/port  Requests to stop sending output to /port\r\n\
~/port  Requests to stop receiving input from /port\r\n\
a       Signals the beginning of an administrative message\r\n\
?       Gives this help\r\n";

/// What C++ sends back over text connections for an unknown command key.
pub const NOT_UNDERSTOOD: &str = "Port command not understood.\r\n\
Type d to send data to the port's owner.\r\n\
Type ? for help.\r\n";

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn binary_forms() {
        let mut out = Vec::new();
        PortCommand::data(false).encode_binary(&mut out);
        assert_eq!(out, [0, 0, 0, 0, b'~', b'D', 0, 1]);
        out.clear();
        PortCommand::close().encode_binary(&mut out);
        assert_eq!(out, [2, 0, 0, 0, b'~', 0, 0, 1, b'q', 0]);
        let (c, used) = PortCommand::decode_binary(&out).unwrap();
        assert_eq!((c.key(), c.kind(), used), (b'q', CommandKind::Close, 10));
    }

    #[test]
    fn envelope() {
        let s = Stamp::new(3092, 1795297706.58327);
        let c = PortCommand::with_stamp(&s, false);
        assert_eq!(c.text, b"D 3092 1795297706.58327");
        assert_eq!(c.kind(), CommandKind::Data { reply: false });
        assert_eq!(c.stamp(), Some(s));
        assert_eq!(c.header()[..4], [24, 0, 0, 0]);
    }

    #[test]
    fn text_keys() {
        assert_eq!(PortCommand::from_line("help").kind(), CommandKind::Help);
        assert_eq!(
            PortCommand::from_line("hello without d").kind(),
            CommandKind::Help
        );
        assert_eq!(
            PortCommand::from_line("~/w").kind(),
            CommandKind::RemoveInput(b"/w".to_vec())
        );
        assert_eq!(
            PortCommand::from_line("/x").kind(),
            CommandKind::AddOutput(b"/x".to_vec())
        );
        assert_eq!(PortCommand::from_line("").kind(), CommandKind::Unknown(0));
        assert!(PortCommand::admin().expects_reply());
        assert!(!PortCommand::data(false).expects_reply());
    }

    #[test]
    fn hostile_commands() {
        assert_eq!(
            PortCommand::decode_binary(&[1, 2, 3]),
            Err(WireError::ShortPortCommand { len: 3 })
        );
        assert!(matches!(
            PortCommand::decode_binary(&[0, 0, 0, 0, b'x', b'D', 0, 1]),
            Err(WireError::BadPortCommand { .. })
        ));
        assert_eq!(
            PortCommand::decode_binary(&[0xff, 0xff, 0xff, 0x7f, b'~', 0, 0, 1, b'q']),
            Err(WireError::UnterminatedCommandText)
        );
    }
}
