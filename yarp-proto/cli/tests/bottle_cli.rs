//! `yarp bottle encode|decode` as a user runs it: real child processes, stdin and arguments.

use std::io::Write;
use std::process::{Command, Stdio};

fn yarp(args: &[&str], stdin: &str) -> (i32, String, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_yarp"))
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn yarp");
    child
        .stdin
        .take()
        .expect("stdin")
        .write_all(stdin.as_bytes())
        .expect("write stdin");
    let out = child.wait_with_output().expect("wait yarp");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn encode_argument_and_stdin_lines() {
    let (code, out, _) = yarp(&["bottle", "encode", "hello", "42"], "");
    assert_eq!(code, 0);
    assert_eq!(
        out,
        "0001000002000000040000000500000068656c6c6f010000002a000000\n"
    );

    let (code, out, _) = yarp(&["bottle", "encode"], "1 2 3\r\n-1\n");
    assert_eq!(code, 0);
    assert_eq!(
        out,
        "0101000003000000010000000200000003000000\n0101000001000000ffffffff\n"
    );
}

#[test]
fn decode_prints_like_yarp_read() {
    let (code, out, _) = yarp(
        &["bottle", "decode"],
        "0a0100000100000059f3f8c21f6ea501\n000100000100000004000000050000006120622263\n",
    );
    assert_eq!(code, 0);
    assert_eq!(out, "1.00000000000000002506e-300\n\"a b\\\"c\"\n");
}

#[test]
fn bad_input_fails_with_a_clear_message() {
    let (code, out, err) = yarp(&["bottle", "decode", "0100000005000000"], "");
    assert_ne!(code, 0);
    assert!(out.is_empty());
    assert!(err.contains("not a valid YARP bottle"), "{err}");
    assert!(err.contains("byte 4"), "{err}");

    let (code, _, err) = yarp(&["bottle", "decode"], "00010000\nzz\n");
    assert_ne!(code, 0);
    assert!(err.contains("stdin line 1"), "{err}");

    let (code, _, err) = yarp(&["bottle", "decode", "0g"], "");
    assert_ne!(code, 0);
    assert!(err.contains("invalid hex"), "{err}");

    let deep = "(".repeat(400) + &")".repeat(400);
    let (code, _, err) = yarp(&["bottle", "encode", &deep], "");
    assert_ne!(code, 0);
    assert!(err.contains("nested deeper"), "{err}");
}
