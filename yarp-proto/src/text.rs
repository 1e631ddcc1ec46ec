//! Text form of Bottles, exactly as C++ YARP reads (`BottleImpl::fromString`, `smartAdd`)
//! and prints (`toString`, `toStringNested`) it.
//!
//! The reader reproduces C++'s tokenizer rather than a cleaner grammar, because what a
//! C++ peer does with odd input (unbalanced parentheses, `010`, `1e`, `[abcde]`) is part of
//! the protocol users depend on.

use crate::error::ParseError;
use crate::number;
use crate::value::{Bottle, Value};
use crate::vocab::Vocab32;

/// Nesting limit for parsing, matching the binary decoder's.
pub const MAX_DEPTH: usize = crate::binary::MAX_DEPTH;

/// Parses text as C++ `Bottle::fromString`. Text nested deeper than [`MAX_DEPTH`] gives an
/// empty Bottle (use [`try_parse`] to see why).
pub fn parse(text: &[u8]) -> Bottle {
    try_parse(text).unwrap_or_default()
}

/// Parses text; fails only when nesting exceeds [`MAX_DEPTH`].
pub fn try_parse(text: &[u8]) -> Result<Bottle, ParseError> {
    parse_at(text, 0)
}

fn is_space(ch: u8) -> bool {
    matches!(ch, b' ' | b'\t' | b'\n' | b'\r')
}

fn parse_at(text: &[u8], depth: usize) -> Result<Bottle, ParseError> {
    if depth > MAX_DEPTH {
        return Err(ParseError::TooDeep { limit: MAX_DEPTH });
    }
    let mut out = Bottle::new();
    let mut arg: Vec<u8> = Vec::new();
    let mut quoted = false;
    let mut back = false;
    let mut begun = false;
    let mut nested = 0i64;
    let mut nested_alt = 0i64;
    // C++ appends a space so that the last token is flushed.
    for &ch in text.iter().chain(std::iter::once(&b' ')) {
        if back {
            arg.push(ch);
            back = false;
            continue;
        }
        if !begun && !is_space(ch) {
            begun = true;
        }
        if !begun {
            continue;
        }
        if ch == b'"' {
            quoted = !quoted;
        }
        if !quoted {
            match ch {
                b'(' => nested += 1,
                b')' => nested -= 1,
                b'{' => nested_alt += 1,
                b'}' => nested_alt -= 1,
                _ => {}
            }
        }
        if ch == b'\\' {
            back = true;
            arg.push(ch);
        } else if !quoted && (ch == b',' || is_space(ch)) && nested_alt == 0 && nested == 0 {
            if !arg.is_empty() {
                if arg == b"null" {
                    out.push(Vocab32::new("null"));
                } else {
                    out.push(token_value(&arg, depth)?);
                }
            }
            arg.clear();
            begun = false;
        } else {
            arg.push(ch);
        }
    }
    Ok(out)
}

/// Strips the first and last byte, as C++ `substr(1, len - 2)`.
fn inner(s: &[u8]) -> &[u8] {
    if s.len() >= 2 {
        &s[1..s.len() - 1]
    } else {
        &[]
    }
}

/// C++ `smartAdd`: decides the type of one token and converts it.
fn token_value(s: &[u8], depth: usize) -> Result<Value, ParseError> {
    let ch = s[0];
    let mut number_like = true;
    let mut preamble = true;
    let mut hex_active = false;
    let mut hex_start = 0usize;
    let mut period_count = 0;
    let mut sign_count = 0;
    let mut has_period_or_e = false;
    if s == b"inf" || s == b"-inf" || s == b"nan" {
        has_period_or_e = true;
    } else {
        for (i, &c) in s.iter().enumerate() {
            if c == b'.' {
                has_period_or_e = true;
                period_count += 1;
                if period_count > 1 {
                    number_like = false;
                }
            }
            if !hex_active && (c == b'e' || c == b'E') {
                has_period_or_e = true;
            }
            if preamble && (c == b'x' || c == b'X') {
                hex_active = true;
                hex_start = i;
                continue;
            }
            if preamble && (c == b'0' || c == b'+' || c == b'-') {
                if c != b'0' {
                    sign_count += 1;
                    if sign_count > 1 {
                        number_like = false;
                    }
                }
                continue;
            }
            preamble = false;
            let ok = c.is_ascii_digit()
                || matches!(c, b'.' | b'e' | b'E' | b'+' | b'-')
                || (hex_active && c.is_ascii_hexdigit());
            if !ok {
                number_like = false;
                break;
            }
        }
    }
    if hex_active && s.len() as i64 - (hex_start as i64 + 1) > 8 {
        // C++ only handles 32-bit hexadecimal
        number_like = false;
    }
    let numeric_start = ch.is_ascii_digit() || matches!(ch, b'+' | b'-' | b'.' | b'i' | b'n');
    if number_like && numeric_start && (ch != b'.' || s.len() > 1) {
        if !has_period_or_e {
            let v = number::strtoll_base0(s);
            return Ok(match i32::try_from(v) {
                Ok(small) => Value::Int32(small),
                Err(_) => Value::Int64(v),
            });
        }
        return Ok(Value::Float64(number::parse_float(s)));
    }
    match ch {
        b'(' => Ok(Value::List(parse_at(inner(s), depth + 1)?)),
        b'[' => Ok(Value::Vocab32(Vocab32::encode(inner(s)))),
        b'{' => Ok(Value::Blob(blob_from_text(inner(s), depth)?)),
        _ => {
            let text = unquote(s);
            if ch != b'"' {
                if text == b"true" {
                    return Ok(Value::Vocab32(Vocab32::TRUE));
                }
                if text == b"false" {
                    return Ok(Value::Vocab32(Vocab32::FALSE));
                }
            }
            Ok(Value::String(text))
        }
    }
}

/// C++ `StoreBlob::fromString`: the inner text is parsed as a Bottle and each element's
/// `asInt32` is kept as one byte (so `{256}` is `{0}`).
fn blob_from_text(s: &[u8], depth: usize) -> Result<Vec<u8>, ParseError> {
    let b = parse_at(s, depth + 1)?;
    Ok(b.iter().map(|v| v.as_i32().unwrap_or(0) as u8).collect())
}

/// C++ `StoreString::fromStringNested`: drops surrounding quotes (if the token starts with
/// one) and resolves `\n`, `\r`, `\0`, `\\`; any other escaped byte stands for itself.
fn unquote(src: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(src.len());
    let skip = src.first() == Some(&b'"');
    let len = src.len();
    let mut back = false;
    for (i, &ch) in src.iter().enumerate() {
        if skip && (i == 0 || i == len - 1) {
            continue;
        }
        if ch == b'\\' {
            if back {
                out.push(b'\\');
                back = false;
            } else {
                back = true;
            }
            continue;
        }
        if back {
            out.push(match ch {
                b'n' => b'\n',
                b'r' => b'\r',
                b'0' => 0,
                other => other,
            });
        } else {
            out.push(ch);
        }
        back = false;
    }
    out
}

/// C++ `StoreString::quotedString`: plain words (letters and `_`, then also digits, `.`
/// and `-`) print bare; anything else, empty strings and `true`/`false` are quoted.
pub fn quote_string(x: &[u8], out: &mut Vec<u8>) {
    let mut need_quote = x.is_empty() || x == b"true" || x == b"false";
    if !need_quote {
        for (i, &ch) in x.iter().enumerate() {
            if !(ch.is_ascii_alphabetic() || ch == b'_') {
                if ch.is_ascii_digit() || ch == b'.' || ch == b'-' {
                    if i == 0 {
                        need_quote = true;
                        break;
                    }
                } else {
                    need_quote = true;
                    break;
                }
            }
        }
    }
    if !need_quote {
        out.extend_from_slice(x);
        return;
    }
    out.push(b'"');
    for &ch in x {
        match ch {
            b'\n' => out.extend_from_slice(b"\\n"),
            b'\r' => out.extend_from_slice(b"\\r"),
            0 => out.extend_from_slice(b"\\0"),
            b'\\' | b'"' => {
                out.push(b'\\');
                out.push(ch);
            }
            _ => out.push(ch),
        }
    }
    out.push(b'"');
}

/// Text of a whole Bottle (C++ `Bottle::toString`).
pub fn bottle_to_text(b: &Bottle) -> Vec<u8> {
    let mut out = Vec::with_capacity(b.len() * 8);
    write_bottle(b, &mut out);
    out
}

fn write_bottle(b: &Bottle, out: &mut Vec<u8>) {
    for (i, v) in b.iter().enumerate() {
        if i > 0 {
            out.push(b' ');
        }
        write_value(v, true, out);
    }
}

/// Text of one value; `nested` selects the in-Bottle form (`toStringNested`) over the bare
/// one (`toString`).
pub fn value_to_text(v: &Value, nested: bool) -> Vec<u8> {
    let mut out = Vec::new();
    write_value(v, nested, &mut out);
    out
}

fn write_value(v: &Value, nested: bool, out: &mut Vec<u8>) {
    use std::io::Write;
    match v {
        Value::Int8(x) => {
            let _ = write!(out, "{x}");
        }
        Value::Int16(x) => {
            let _ = write!(out, "{x}");
        }
        Value::Int32(x) => {
            let _ = write!(out, "{x}");
        }
        Value::Int64(x) => {
            let _ = write!(out, "{x}");
        }
        Value::Float32(x) => out.extend_from_slice(number::format_float(*x as f64).as_bytes()),
        Value::Float64(x) => out.extend_from_slice(number::format_float(*x).as_bytes()),
        Value::Vocab32(x) => {
            if nested {
                out.extend(x.to_text())
            } else {
                match *x {
                    Vocab32::FALSE => out.extend_from_slice(b"false"),
                    Vocab32::TRUE => out.extend_from_slice(b"true"),
                    other => out.extend(other.decode()),
                }
            }
        }
        // C++ 4.0's `StoreVocab64`: `[chars]`, 0 and '1' as false and true
        Value::Vocab64(x) => match *x {
            0 => out.extend_from_slice(b"false"),
            0x31 => out.extend_from_slice(b"true"),
            code => {
                if nested {
                    out.push(b'[');
                }
                out.extend(crate::value::vocab64_decode(code));
                if nested {
                    out.push(b']');
                }
            }
        },
        Value::String(s) => {
            if nested {
                quote_string(s, out)
            } else {
                out.extend_from_slice(s)
            }
        }
        Value::Blob(bytes) => {
            if nested {
                out.push(b'{');
            }
            for (i, byte) in bytes.iter().enumerate() {
                if i > 0 {
                    out.push(b' ');
                }
                let _ = write!(out, "{byte}");
            }
            if nested {
                out.push(b'}');
            }
        }
        Value::List(b) | Value::Dict(b) => {
            if nested {
                out.push(b'(');
            }
            write_bottle(b, out);
            if nested {
                out.push(b')');
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn round(s: &str) -> String {
        parse(s.as_bytes()).to_string()
    }

    #[test]
    fn quirks_from_the_cpp_reader() {
        assert_eq!(round("hello 42"), "hello 42");
        assert_eq!(round("[abcde]"), "[abcd]");
        assert_eq!(round("[ok"), "[o]");
        assert_eq!(round("x [] y"), "x false y");
        assert_eq!(round("{256}"), "{0}");
        assert_eq!(round("\"unterminated"), "");
        assert_eq!(round("a\\b"), "ab");
        assert_eq!(round("1,2"), "1 2");
        assert_eq!(round("010 0x10 - +"), "8 16 0 0");
        assert_eq!(round("1e"), "0.0");
        assert_eq!(round("null"), "[null]");
        assert_eq!(round("(a (b c)) d"), "(a (b c)) d");
        assert_eq!(round("\"true\" true"), "\"true\" true");
    }

    #[test]
    fn deep_text_is_bounded() {
        let deep = "(".repeat(5000) + &")".repeat(5000);
        assert!(matches!(
            try_parse(deep.as_bytes()),
            Err(ParseError::TooDeep { .. })
        ));
        assert!(parse(deep.as_bytes()).is_empty());
    }
}
