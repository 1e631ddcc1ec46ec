//! Sans-I/O framing of YARP connections: the tcp-family carriers (tcp, fast_tcp, and the
//! TCP handshake of udp/mcast/shmem) and the text carriers (text, text_ack), byte-exact
//! with C++ YARP 3.12.
//!
//! Nothing here touches a socket: encoders return bytes to send, and the [`Decoder`]
//! turns received bytes (in whatever pieces TCP delivers them) into [`Event`]s.
//!
//! A tcp connection, as `yarp write /w` opens it to a reader:
//!
//! ```text
//! c2s  59 41 e4 1e 00 00 52 50         header: YARP number 7777 + 3 + 128 (tcp, acks)
//! c2s  03 00 00 00 2f 77 00            sender name "/w"
//! s2c  59 41 12 27 00 00 52 50         header reply: the reader's port (10002)
//! c2s  59 41 0a 00 00 00 52 50 02 01 ff*8 08000000 1d000000 00000000
//!                                      index: 2 blocks of 8 and 29 bytes, 1 reply slot
//! c2s  00 00 00 00 7e 44 00 01         port command 'D' (data, no reply)
//! c2s  00 01 00 00 02 00 00 00 ...     the Bottle
//! s2c  59 41 00 00 00 00 52 50         ack
//! ```
//!
//! ```
//! use yarp_proto::bottle;
//! use yarp_proto::wire::{self, Carrier, Decoder, DecoderConfig, Event};
//!
//! // what we send when connecting and writing
//! let mut bytes = wire::encode_connection_start(&Carrier::Tcp.spec(), b"/w");
//! bytes.extend(wire::data_message(&bottle!["hello", 42], false));
//!
//! // what the accepting side reads, even one byte at a time
//! let mut rx = Decoder::accepting(DecoderConfig::default());
//! let mut events = Vec::new();
//! for b in &bytes {
//!     events.extend(rx.decode(std::slice::from_ref(b)).unwrap());
//! }
//! assert!(matches!(&events[0], Event::Header(h) if h.carrier() == Carrier::Tcp));
//! assert_eq!(events[1], Event::SenderName(b"/w".to_vec()));
//! let Event::Message(m) = &events[2] else { panic!() };
//! assert_eq!(m.bottle().unwrap().to_string(), "hello 42");
//! ```

pub mod carrier;
pub mod command;
pub mod datagram;
pub mod decoder;
pub mod error;
pub mod indexless;
pub mod line;
pub mod message;
pub mod mjpeg;
pub mod modifiers;
pub mod number;
pub mod scan;
pub mod shmem;
pub mod text_carrier;

pub use carrier::{
    classify_header, encode_connection_start, encode_header_reply, encode_sender_name,
    name_server_request, specifier, Carrier, CarrierRegistry, CarrierSpec, ConnectionHeader,
    Framing, HeaderPattern, ACK_FLAG, PROTOCOL_NOT_FOUND, SPECIFIER_BASE,
};
pub use command::{CommandKind, PortCommand, NOT_UNDERSTOOD, PORT_HELP};
pub use decoder::{
    Decoder, DecoderConfig, Event, ReadSpace, DEFAULT_MAX_LINE_LEN, DEFAULT_MAX_MESSAGE_SIZE,
};
pub use error::WireError;
pub use indexless::{encode_indexless, IndexlessDecoder, UNIX_ACK};
pub use message::{
    ack, admin_message, close_message, command_message, data_message, encode_message,
    envelope_message, reply_message, BinaryFrame, Index, Message,
};
pub use number::YarpNumber;

#[cfg(test)]
mod tests;
