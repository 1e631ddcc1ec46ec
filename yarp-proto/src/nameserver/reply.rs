//! Reply bytes, as C++ `NameServerConnectionHandler` writes them.
//!
//! A reply Bottle whose first element prints as `old` is the old multi-line form: every
//! following list is printed as Bottle text with all `"` removed (skipped when that
//! leaves nothing), every string as it is, each as one `\r\n`-terminated line, then
//! `*** end of message\r\n`. Any other reply is the Bottle itself: its text plus `\r\n`
//! on text connections, its binary encoding on binary ones.

use crate::value::{Bottle, Value};

const CRLF: &[u8] = b"\r\n";

/// Removes every `"` (C++ does this to old-style reply lines and to client requests).
pub fn strip_quotes(text: &[u8]) -> Vec<u8> {
    text.iter().copied().filter(|&c| c != b'"').collect()
}

/// Whether a reply goes out in the old multi-line text form.
pub fn is_old_reply(reply: &Bottle) -> bool {
    reply.get(0).is_some_and(|v| v.to_text_bare() == b"old")
}

fn old_form(reply: &Bottle, binary: bool) -> Vec<u8> {
    let mut out = Vec::new();
    for v in reply.iter().skip(1) {
        match v {
            Value::List(b) => {
                let line = strip_quotes(&b.to_text());
                if !line.is_empty() {
                    out.extend_from_slice(&line);
                    out.extend_from_slice(CRLF);
                }
            }
            Value::String(s) => {
                out.extend_from_slice(s);
                out.extend_from_slice(CRLF);
            }
            other => {
                let single: Bottle = vec![other.clone()].into();
                if binary {
                    out.extend_from_slice(&single.encode());
                } else {
                    out.extend_from_slice(&single.to_text());
                    out.extend_from_slice(CRLF);
                }
            }
        }
    }
    out.extend_from_slice(b"*** end of message\r\n");
    out
}

/// The bytes a reply takes on a text connection (text carrier, `NAME_SERVER` lines).
pub fn reply_text(reply: &Bottle) -> Vec<u8> {
    if is_old_reply(reply) {
        old_form(reply, false)
    } else {
        let mut out = reply.to_text();
        out.extend_from_slice(CRLF);
        out
    }
}

/// The bytes a reply takes on a binary (tcp-family) connection.
pub fn reply_binary(reply: &Bottle) -> Vec<u8> {
    if is_old_reply(reply) {
        old_form(reply, true)
    } else {
        reply.encode()
    }
}
