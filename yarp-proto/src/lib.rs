//! The YARP core, free of sockets: values and Bottles with their binary and text codecs,
//! vocabs, envelopes (stamps) and Property/Searchable configuration.
//!
//! Everything here is pure encode/decode and data structures; network I/O lives in the
//! crates layered above (as `quinn-proto` sits under `quinn`). Byte layouts follow
//! C++ YARP 3.12 exactly and are checked against recordings of the real thing.
//!
//! ```
//! use yarp_proto::{Bottle, Value};
//! let b = Bottle::from_text("set pos 0 100.0");
//! assert_eq!(b.get(2), Some(&Value::Int32(0)));
//! let bytes = b.encode();
//! assert_eq!(Bottle::decode(&bytes).unwrap(), b);
//! assert_eq!(b.to_string(), "set pos 0 100.0");
//! ```
//!
//! The README's example (the docs test checks the two stay the same):
//!
//! ```
//! use yarp_proto::{bottle, Bottle, Value, Vocab32};
//!
//! let cmd = bottle![Vocab32::new("set"), Vocab32::new("pos"), 0, 100.0];
//! assert_eq!(cmd.to_string(), "[set] [pos] 0 100.0");
//! let wire = cmd.encode();                      // bytes exactly as C++ YARP writes them
//! let back = Bottle::decode(&wire).unwrap();    // typed error (with byte offset) on bad input
//! assert_eq!(back, cmd);
//!
//! let reply = Bottle::from_text("[is] [axes] 4 [ok]");   // C++ Bottle::fromString rules
//! assert_eq!(reply.get(2), Some(&Value::Int32(4)));
//! ```

pub mod auth;
pub mod binary;
pub mod contact;
pub mod error;
pub mod image;
pub mod nameserver;
pub mod number;
pub mod port_admin;
pub mod portmonitor;
pub mod property;
pub mod stamp;
pub mod tags;
pub mod text;
pub mod value;
pub mod vocab;
pub mod wire;

pub use contact::{Contact, PortRef};
pub use error::{DecodeError, ParseError};
pub use property::Property;
pub use stamp::Stamp;
pub use value::{Bottle, Value};
pub use vocab::Vocab32;
