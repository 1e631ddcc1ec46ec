//! Line reading exactly as C++ `InputStream::readLine` does it, incrementally.
//!
//! C++ drops every NUL, CR and LF byte from the line (not only a trailing CR), keeps a
//! backslash only when something other than the terminator follows it (a run of two or
//! more backslashes is kept whole), and a backslash right before the terminator joins the
//! next line to this one (the backslash and the terminator are both dropped).

/// Incremental line reader with C++ `readLine('\n')` semantics and a length cap.
#[derive(Debug, Clone)]
pub struct LineReader {
    buf: Vec<u8>,
    esc: usize,
    max: usize,
}

/// Result of feeding bytes to a [`LineReader`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum LineStep {
    /// All given bytes were used and the line is not finished.
    Partial,
    /// A line finished after using this many of the given bytes.
    Line { line: Vec<u8>, used: usize },
    /// The line grew beyond the cap.
    TooLong,
}

impl LineReader {
    /// A reader refusing lines longer than `max` bytes.
    pub fn new(max: usize) -> LineReader {
        LineReader {
            buf: Vec::new(),
            esc: 0,
            max,
        }
    }

    /// Whether part of a line is buffered.
    pub fn has_partial(&self) -> bool {
        !self.buf.is_empty() || self.esc > 0
    }

    /// Consumes bytes until a line is complete.
    pub fn push(&mut self, data: &[u8]) -> LineStep {
        for (i, &v) in data.iter().enumerate() {
            if v == b'\\' {
                self.esc += 1;
            }
            if v != 0 && v != b'\r' && v != b'\n' {
                if v != b'\\' || self.esc >= 2 {
                    self.buf.resize(self.buf.len() + self.esc, b'\\');
                    self.esc = 0;
                }
                if v != b'\\' {
                    self.buf.push(v);
                }
                if self.buf.len() + self.esc > self.max {
                    return LineStep::TooLong;
                }
            }
            if v == b'\n' {
                if self.esc == 0 {
                    let line = std::mem::take(&mut self.buf);
                    return LineStep::Line { line, used: i + 1 };
                }
                self.esc = 0;
            }
        }
        LineStep::Partial
    }
}

/// Reads one line from a complete buffer (convenience for tests and tools): the line and
/// the bytes used, or `None` if no terminator arrived.
pub fn read_line(data: &[u8]) -> Option<(Vec<u8>, usize)> {
    match LineReader::new(usize::MAX).push(data) {
        LineStep::Line { line, used } => Some((line, used)),
        _ => None,
    }
}

/// C++ `BottleImpl::isComplete`: whether Bottle text has balanced `()`/`{}` outside
/// quotes and no open quote (text carriers keep reading lines until it does).
pub fn is_complete(text: &[u8]) -> bool {
    let mut c = CompletenessCheck::default();
    c.feed(text);
    c.is_complete()
}

/// [`is_complete`] computed incrementally over text that grows at its end, so that a
/// long multi-line Bottle text is scanned once.
#[derive(Debug, Clone, Default)]
pub struct CompletenessCheck {
    quoted: bool,
    back: bool,
    begun: bool,
    nested: i64,
    nested_alt: i64,
}

impl CompletenessCheck {
    pub fn feed(&mut self, text: &[u8]) {
        for &ch in text {
            if self.back {
                self.back = false;
                continue;
            }
            if !self.begun && !matches!(ch, b' ' | b'\t' | b'\n' | b'\r') {
                self.begun = true;
            }
            if !self.begun {
                continue;
            }
            if ch == b'"' {
                self.quoted = !self.quoted;
            }
            if !self.quoted {
                match ch {
                    b'(' => self.nested += 1,
                    b')' => self.nested -= 1,
                    b'{' => self.nested_alt += 1,
                    b'}' => self.nested_alt -= 1,
                    _ => {}
                }
            }
            if ch == b'\\' {
                self.back = true;
            } else if !self.quoted
                && matches!(ch, b' ' | b'\t' | b'\n' | b'\r')
                && self.nested == 0
                && self.nested_alt == 0
            {
                self.begun = false;
            }
        }
    }

    /// C++ appends one space before deciding; that space cannot change the outcome.
    pub fn is_complete(&self) -> bool {
        self.nested == 0 && self.nested_alt == 0 && !self.quoted
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(s: &[u8]) -> Vec<u8> {
        read_line(s).map(|(l, _)| l).unwrap_or_default()
    }

    #[test]
    fn cpp_readline_rules() {
        assert_eq!(line(b"hello\r\n"), b"hello");
        assert_eq!(line(b"a\rb\0c\n"), b"abc");
        assert_eq!(line(b"a\\b\n"), b"a\\b");
        assert_eq!(line(b"a\\\\b\n"), b"a\\\\b");
        assert_eq!(line(b"\"x \\\"y\\\"\"\n"), b"\"x \\\"y\\\"\"");
        // backslash-newline joins lines
        assert_eq!(line(b"ab\\\ncd\n"), b"abcd");
        assert_eq!(read_line(b"no end"), None);
        assert_eq!(read_line(b"one\ntwo\n").map(|(_, u)| u), Some(4));
    }

    #[test]
    fn segmentation_independent() {
        let data = b"first \\\\ x\\\ny\r\nsecond\n";
        let mut r = LineReader::new(100);
        let mut lines = Vec::new();
        for b in data {
            if let LineStep::Line { line, used } = r.push(std::slice::from_ref(b)) {
                assert_eq!(used, 1);
                lines.push(line);
            }
        }
        assert_eq!(lines, [b"first \\\\ xy".to_vec(), b"second".to_vec()]);
    }

    #[test]
    fn cap() {
        let mut r = LineReader::new(4);
        assert_eq!(r.push(b"abcde"), LineStep::TooLong);
    }

    #[test]
    fn completeness() {
        assert!(is_complete(b"1 2 (3 4)"));
        assert!(!is_complete(b"1 (2"));
        assert!(!is_complete(b"\"open"));
        assert!(is_complete(b"\"(\""));
        assert!(!is_complete(b"{1"));
        assert!(!is_complete(b"a)"));
    }
}
