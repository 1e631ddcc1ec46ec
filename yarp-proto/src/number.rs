//! Number <-> text conversions that behave like the C library calls C++ YARP makes
//! (`snprintf("%.*g")`, `strtoll(.., 0)`, `strtod`), so text forms match byte for byte.

/// Formats like C's `printf("%.{precision}g", x)` (glibc: correctly rounded).
pub fn format_g(x: f64, precision: usize) -> String {
    if x.is_nan() {
        return if x.is_sign_negative() { "-nan" } else { "nan" }.to_string();
    }
    if x.is_infinite() {
        return if x < 0.0 { "-inf" } else { "inf" }.to_string();
    }
    let p = precision.max(1);
    // Scientific rendering with p significant digits gives the digits and the exponent
    // after rounding, which is what %g decides on.
    let sci = format!("{:.*e}", p - 1, x);
    let (mantissa, exp) = sci.split_once('e').unwrap_or((&sci, "0"));
    let exp: i32 = exp.parse().unwrap_or(0);
    let negative = mantissa.starts_with('-');
    let digits: String = mantissa.chars().filter(|c| c.is_ascii_digit()).collect();
    let mut out = String::with_capacity(p + 8);
    if negative {
        out.push('-');
    }
    if exp < -4 || exp >= p as i32 {
        // scientific: d.ddd e±XX, trailing zeros removed
        out.push_str(&digits[..1]);
        let frac = digits[1..].trim_end_matches('0');
        if !frac.is_empty() {
            out.push('.');
            out.push_str(frac);
        }
        out.push('e');
        out.push(if exp < 0 { '-' } else { '+' });
        let e = exp.unsigned_abs();
        if e < 10 {
            out.push('0');
        }
        out.push_str(&e.to_string());
    } else if exp < 0 {
        // 0.000ddd
        out.push_str("0.");
        for _ in 0..(-exp - 1) {
            out.push('0');
        }
        out.push_str(digits.trim_end_matches('0'));
        if out.ends_with('.') {
            out.pop();
        }
    } else {
        let int_len = exp as usize + 1;
        out.push_str(&digits[..int_len]);
        let frac = digits[int_len..].trim_end_matches('0');
        if !frac.is_empty() {
            out.push('.');
            out.push_str(frac);
        }
    }
    out
}

/// Text of a float64 element as C++ YARP prints it (`yarp::conf::numeric::to_string`):
/// `%.21g` (DECIMAL_DIG on x86-64), plus `.0` when the result looks like an integer.
pub fn format_float(x: f64) -> String {
    let mut s = format_g(x, 21);
    if !s.contains('.') && !s.contains('e') && s != "inf" && s != "-inf" && s != "nan" {
        s.push_str(".0");
    }
    s
}

/// Parses like `strtoll(s, nullptr, 0)`: optional whitespace and sign, `0x` hex, leading-`0`
/// octal, else decimal; stops at the first invalid digit; saturates on overflow; 0 if no digits.
pub fn strtoll_base0(s: &[u8]) -> i64 {
    let mut i = 0;
    while i < s.len() && matches!(s[i], b' ' | b'\t' | b'\n' | b'\r' | 0x0b | 0x0c) {
        i += 1;
    }
    let mut negative = false;
    if i < s.len() && (s[i] == b'+' || s[i] == b'-') {
        negative = s[i] == b'-';
        i += 1;
    }
    let mut base = 10u32;
    if i < s.len() && s[i] == b'0' {
        let hex_prefix = matches!(s.get(i + 1), Some(b'x' | b'X'))
            && s.get(i + 2).is_some_and(|c| c.is_ascii_hexdigit());
        if hex_prefix {
            base = 16;
            i += 2;
        } else {
            base = 8;
        }
    }
    // accumulate as a negative number to reach i64::MIN exactly
    let mut acc: i128 = 0;
    let mut overflow = false;
    while i < s.len() {
        let Some(d) = (s[i] as char).to_digit(base) else {
            break;
        };
        if !overflow {
            acc = acc * base as i128 + d as i128;
            if acc > i64::MAX as i128 + 1 {
                overflow = true;
            }
        }
        i += 1;
    }
    if negative {
        if overflow || acc > i64::MAX as i128 + 1 {
            i64::MIN
        } else {
            (-acc) as i64
        }
    } else if overflow || acc > i64::MAX as i128 {
        i64::MAX
    } else {
        acc as i64
    }
}

/// Parses a float token as C++ YARP 3.12 does (`yarp::conf::numeric::from_string`): `inf`,
/// `-inf`, `nan` by name; otherwise the whole token must be a number, else the value is 0.0
/// (`1e` -> 0.0); out-of-range values become ±inf (`1e400` -> inf).
pub fn parse_float(s: &[u8]) -> f64 {
    match s {
        b"inf" => return f64::INFINITY,
        b"-inf" => return f64::NEG_INFINITY,
        b"nan" => return f64::NAN,
        _ => {}
    }
    // Only the decimal grammar is accepted here; words like "infinity" never reach this
    // function from the Bottle parser, and other callers expect plain numbers.
    if !s
        .iter()
        .all(|&c| c.is_ascii_digit() || matches!(c, b'.' | b'e' | b'E' | b'+' | b'-'))
    {
        return 0.0;
    }
    std::str::from_utf8(s)
        .ok()
        .and_then(|t| t.parse::<f64>().ok())
        .unwrap_or(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn g_format_matches_glibc() {
        assert_eq!(format_g(0.1, 21), "0.100000000000000005551");
        assert_eq!(format_g(1e300, 21), "1.0000000000000000525e+300");
        assert_eq!(format_g(1e-300, 21), "1.00000000000000002506e-300");
        assert_eq!(format_g(1000.0, 21), "1000");
        assert_eq!(format_g(0.0001, 6), "0.0001");
        assert_eq!(format_g(0.00001, 6), "1e-05");
        assert_eq!(format_g(123456.0, 6), "123456");
        assert_eq!(format_g(1234567.0, 6), "1.23457e+06");
        assert_eq!(format_g(-0.0, 6), "-0");
        assert_eq!(format_g(1795297706.58327, 15), "1795297706.58327");
    }

    #[test]
    fn float_text() {
        assert_eq!(format_float(1.0), "1.0");
        assert_eq!(format_float(-0.0), "-0.0");
        assert_eq!(format_float(1e22), "1e+22");
        assert_eq!(format_float(f64::INFINITY), "inf");
        assert_eq!(format_float(f64::NAN), "nan");
        assert_eq!(format_float(1e10), "10000000000.0");
    }

    #[test]
    fn strtoll_like_c() {
        assert_eq!(strtoll_base0(b"010"), 8);
        assert_eq!(strtoll_base0(b"0x10"), 16);
        assert_eq!(strtoll_base0(b"-"), 0);
        assert_eq!(strtoll_base0(b"+5"), 5);
        assert_eq!(strtoll_base0(b"08"), 0);
        assert_eq!(strtoll_base0(b"0x"), 0);
        assert_eq!(strtoll_base0(b"9223372036854775808"), i64::MAX);
        assert_eq!(strtoll_base0(b"-9223372036854775808"), i64::MIN);
        assert_eq!(strtoll_base0(b"-9223372036854775809"), i64::MIN);
        assert_eq!(
            strtoll_base0(b"99999999999999999999999999999999999999999"),
            i64::MAX
        );
        assert_eq!(strtoll_base0(b"12-3"), 12);
    }

    #[test]
    fn float_parse_like_yarp() {
        assert_eq!(parse_float(b"1e"), 0.0);
        assert_eq!(parse_float(b"1."), 1.0);
        assert_eq!(parse_float(b".5"), 0.5);
        assert_eq!(parse_float(b"1e400"), f64::INFINITY);
        assert!(parse_float(b"nan").is_nan());
    }
}
