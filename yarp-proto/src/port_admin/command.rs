//! Classifying port commands the way C++ `PortCoreInputUnit` dispatches them.
//!
//! On a text connection every line is a command and its **first character** is the key
//! (`PortCommand::read`: `ch = str[0]`); so `help`, `hello` and `h` all print the help,
//! and a data line sent without a `d` line first is taken as a command. On binary
//! connections the key is the `ch` byte of the 8-byte port command, or the first
//! character of the text that follows when `ch` is 0 (`q`, `*`, `help`, `/port` ...).

/// What a port command asks the port to do.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum TextCommand {
    /// `d` / `D`: user data follows (on text connections: the next line). `reply` is
    /// false only for capital `D` (C++ `suppressReply`); note that `do`, which the help
    /// text calls "data-only", has key `d` and so is plain data in C++ 3.12. `envelope`
    /// is the text after the first two characters when the command text is longer than
    /// two characters (`D 3092 1795297706.58` -> `3092 1795297706.58`).
    Data {
        reply: bool,
        envelope: Option<String>,
    },
    /// `a`: an administrative Bottle follows (the next line in text mode); see
    /// [`super::handle_admin`].
    Admin,
    /// `*`: describe the port ([`super::describe`]).
    Describe,
    /// `?` or any text starting with `h` (`help`): the help text.
    Help,
    /// `q`: close this connection.
    Quit,
    /// `r`: reverse: the connection becomes an output of the port.
    Reverse,
    /// `/port`: add an output to the text as given (the whole text, including the `/`).
    ConnectOutput(String),
    /// `!/port`: remove the output(s) to the text after the `!`.
    DisconnectOutput(String),
    /// `~/port`: remove the input(s) from the text after the `~`.
    DisconnectInput(String),
    /// Any other key (including an empty line and, in release builds, `i`): C++ writes
    /// [`super::NOT_UNDERSTOOD_TEXT`] back on text connections. Holds the text.
    NotUnderstood(String),
}

impl TextCommand {
    /// Classifies one line received on a text connection (trailing `\n` / `\r\n`
    /// removed here if still present).
    pub fn from_line(line: &str) -> TextCommand {
        let line = line.strip_suffix('\n').unwrap_or(line);
        let line = line.strip_suffix('\r').unwrap_or(line);
        Self::classify(line.as_bytes().first().copied().unwrap_or(0), line)
    }

    /// Classifies a binary port command: `ch` is byte 5 of the 8-byte header and `text`
    /// the NUL-terminated text that follows when `ch` is 0 (without the NUL).
    pub fn from_binary(ch: u8, text: &str) -> TextCommand {
        if ch == 0 {
            Self::classify(text.as_bytes().first().copied().unwrap_or(0), text)
        } else {
            Self::classify(ch, text)
        }
    }

    /// The dispatch on the key character, with the command text.
    pub fn classify(key: u8, text: &str) -> TextCommand {
        let rest = || text.get(1..).unwrap_or("").to_string();
        match key {
            b'/' => TextCommand::ConnectOutput(text.to_string()),
            b'!' => TextCommand::DisconnectOutput(rest()),
            b'~' => TextCommand::DisconnectInput(rest()),
            b'*' => TextCommand::Describe,
            b'd' | b'D' => TextCommand::Data {
                reply: key == b'd',
                envelope: (text.len() > 2)
                    .then(|| String::from_utf8_lossy(&text.as_bytes()[2..]).into_owned()),
            },
            b'a' => TextCommand::Admin,
            b'r' => TextCommand::Reverse,
            b'q' => TextCommand::Quit,
            b'?' | b'h' => TextCommand::Help,
            _ => TextCommand::NotUnderstood(text.to_string()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::TextCommand as C;

    #[test]
    fn every_key() {
        assert_eq!(
            C::from_line("d"),
            C::Data {
                reply: true,
                envelope: None
            }
        );
        assert_eq!(
            C::from_line("do\r\n"),
            C::Data {
                reply: true,
                envelope: None
            }
        );
        assert_eq!(
            C::from_line("D\r\n"),
            C::Data {
                reply: false,
                envelope: None
            }
        );
        assert_eq!(
            C::from_binary(0, "D 3092 1795297706.58327"),
            C::Data {
                reply: false,
                envelope: Some("3092 1795297706.58327".into())
            }
        );
        assert_eq!(
            C::from_binary(b'd', ""),
            C::Data {
                reply: true,
                envelope: None
            }
        );
        assert_eq!(C::from_line("a\n"), C::Admin);
        assert_eq!(C::from_binary(b'a', ""), C::Admin);
        assert_eq!(C::from_line("*"), C::Describe);
        assert_eq!(C::from_binary(0, "*"), C::Describe);
        assert_eq!(C::from_line("help"), C::Help);
        assert_eq!(C::from_line("?"), C::Help);
        assert_eq!(C::from_line("hello without d\n"), C::Help);
        assert_eq!(C::from_line("q\r\n"), C::Quit);
        assert_eq!(C::from_binary(0, "q"), C::Quit);
        assert_eq!(C::from_line("r"), C::Reverse);
        assert_eq!(C::from_line("/port"), C::ConnectOutput("/port".into()));
        assert_eq!(
            C::from_line("!/port\r\n"),
            C::DisconnectOutput("/port".into())
        );
        assert_eq!(
            C::from_line("~/cbcap/command:o\r\n"),
            C::DisconnectInput("/cbcap/command:o".into())
        );
        assert_eq!(C::from_line("xyz"), C::NotUnderstood("xyz".into()));
        assert_eq!(C::from_line("i"), C::NotUnderstood("i".into()));
        assert_eq!(C::from_line(""), C::NotUnderstood(String::new()));
        assert_eq!(C::from_line("\r\n"), C::NotUnderstood(String::new()));
        assert_eq!(C::from_binary(0, ""), C::NotUnderstood(String::new()));
        // multi-byte first character: no panic, not understood
        assert_eq!(C::from_line("é!"), C::NotUnderstood("é!".into()));
        assert_eq!(
            C::from_line("dé"),
            C::Data {
                reply: true,
                envelope: Some(String::from_utf8_lossy(&"dé".as_bytes()[2..]).into_owned())
            }
        );
    }
}
