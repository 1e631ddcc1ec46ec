//! Errors of the connection framing. Every error names what was wrong; none of them
//! is produced by a panic path, and network data never reaches an `unwrap`.

use crate::DecodeError;
use thiserror::Error;

/// Lowercase hex of a short byte string, for error messages.
pub(crate) fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// A framing error on a YARP connection.
///
/// Errors returned by [`Decoder::poll`](super::Decoder::poll) are fatal for the
/// connection (the byte stream cannot be re-synchronised). The only non-fatal case, a
/// well-framed message with an unusable port command, is reported as
/// [`Event::InvalidMessage`](super::Event::InvalidMessage) instead.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum WireError {
    /// The first 8 bytes of a connection match no known carrier (C++ answers with
    /// [`PROTOCOL_NOT_FOUND`](super::PROTOCOL_NOT_FOUND) and closes).
    #[error("unknown protocol: the first 8 bytes ({}) match no carrier", hex(.header))]
    UnknownProtocol { header: [u8; 8] },
    /// A message did not start with the index marker (YARP number 10).
    #[error("expected a message index (YARP number 10), found {}", hex(.found))]
    BadIndex { found: [u8; 8] },
    /// A block length in a message index does not fit a non-negative int32.
    #[error("block {block} of a message index has the negative length {len}")]
    NegativeBlockLength { block: usize, len: i32 },
    /// A message, reply, line or acknowledgement payload is larger than the configured limit.
    #[error("{what} of {size} bytes exceeds the limit of {max} bytes")]
    TooLarge {
        what: &'static str,
        size: u64,
        max: usize,
    },
    /// Something other than a YARP number where an acknowledgement was expected.
    #[error("expected an acknowledgement (YARP number), found {}", hex(.found))]
    BadAck { found: [u8; 8] },
    /// Something other than a YARP number where the header reply was expected.
    #[error("expected a header reply (YARP number), found {}", hex(.found))]
    BadHeaderReply { found: [u8; 8] },
    /// An index-less RPC reply that is not a valid Bottle.
    #[error("malformed reply: {0}")]
    BadReply(DecodeError),
    /// A message body shorter than the 8-byte port command.
    #[error("message body of {len} byte(s) is shorter than the 8-byte port command")]
    ShortPortCommand { len: usize },
    /// A port command without the `'~'` marker at byte 4.
    #[error("port command {} lacks the '~' marker at byte 4", hex(.header))]
    BadPortCommand { header: [u8; 8] },
    /// A port command with `ch = 0` whose text has no NUL terminator inside the message.
    #[error("port command text is not NUL-terminated inside its message")]
    UnterminatedCommandText,
}
