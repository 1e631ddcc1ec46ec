//! The port administration protocol (`yarp_proto::port_admin`) against every admin
//! exchange recorded from C++ YARP 3.12.3: text-mode sessions (`CONNECT`/`CONNACK`, then
//! `help`, `*`, `a` + Bottle, `~/port`, `q`, `r`, data lines), binary `a` messages with
//! their reply Bottles, and binary text port commands (`*`, `help`, `q`, `D <envelope>`).
//!
//! The recordings do not include the live port state, so each exchange is replayed
//! against the state the recording set-up describes (README / record notes): the
//! session's own connection is an input of the port; during the raw tcp cases a
//! `yarp write /w` stays connected to `/rd` over tcp; `[add]` and `~/port` succeeded.
//! Dynamically assigned port numbers (10002..10099) are normalised to `<PORT>`.

use serde_json::Value as Json;
use yarp_interop_tests::{hex_field, id, load_records};
use yarp_proto::port_admin::{
    add_output_text, describe_for_stdout, format_add_result, format_del_result, handle_admin,
    remove_input_text, remove_output_text, reply_text_line, text_reply, AddOutcome, Pending,
    PortSnapshot, Route, TextCommand,
};
use yarp_proto::Bottle;

/// Replaces 5-digit numbers in 10002..=10099 by `<PORT>`, as the recorder did.
fn normalise_ports(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = String::new();
    let mut i = 0;
    while i < b.len() {
        let run = b[i..].iter().take_while(|c| c.is_ascii_digit()).count();
        let boundary = i == 0 || !b[i - 1].is_ascii_digit();
        if run == 5 && boundary {
            let n: u32 = s[i..i + 5].parse().unwrap_or(0);
            if (10002..=10099).contains(&n) {
                out.push_str("<PORT>");
                i += 5;
                continue;
            }
        }
        if run > 0 {
            out.push_str(&s[i..i + run]);
            i += run;
        } else {
            let ch = s[i..].chars().next().unwrap_or('\u{fffd}');
            out.push(ch);
            i += ch.len_utf8().max(1);
        }
    }
    out
}

/// The real port behind a proxied name in the device recordings.
fn real_port(proxied: &str) -> String {
    for (proxy, real) in [
        ("/proxyfake", "/fake"),
        ("/proxygrab", "/grabber"),
        ("/proxyimu", "/imu"),
    ] {
        if let Some(rest) = proxied.strip_prefix(proxy) {
            return format!("{real}{rest}");
        }
    }
    proxied.to_string()
}

fn reply_for_admin(cmd: &Bottle, state: &PortSnapshot) -> Bottle {
    let r = handle_admin(cmd, state);
    match &r.pending {
        Pending::Add { dest } => {
            format_add_result(&state.name, dest, &AddOutcome::Added { note: None })
        }
        Pending::Del { dest } => {
            let out = state.outputs.iter().any(|c| &c.route.to == dest);
            let inp = state.inputs.iter().any(|c| &c.route.from == dest);
            format_del_result(&state.name, dest, out, inp)
        }
        _ => r.reply,
    }
}

struct Replay {
    expected: String,
    exchanges: usize,
    reversed: bool,
}

/// Replays the client side of a text session and builds what the port should send.
fn replay_text_session(c2s: &str, port_name: &str) -> Option<Replay> {
    let mut lines = c2s.split_inclusive('\n');
    let first = lines.next()?;
    let first = first.trim_end_matches(['\r', '\n']);
    let (ack, session) = if let Some(n) = first.strip_prefix("CONNECT ") {
        (false, n)
    } else if let Some(n) = first.strip_prefix("CONNACK ") {
        (true, n)
    } else {
        return None;
    };
    let carrier = if ack { "text_ack" } else { "text" };
    let mut state = PortSnapshot::new(port_name, "tcp", "127.0.0.1", 10002);
    state
        .inputs
        .push(Route::new(session, port_name, carrier).into());
    let mut out = format!("Welcome {session}\r\n");
    let mut exchanges = 0;
    let mut reversed = false;
    while let Some(line) = lines.next() {
        let cmd = TextCommand::from_line(line);
        match &cmd {
            TextCommand::Data { .. } => {
                lines.next();
            }
            TextCommand::Admin => {
                let text = lines.next().unwrap_or("").trim_end_matches(['\r', '\n']);
                let reply = reply_for_admin(&Bottle::from_text(text), &state);
                out.push_str(&String::from_utf8_lossy(&reply_text_line(&reply)));
                exchanges += 1;
            }
            TextCommand::DisconnectInput(src) => {
                // every `~` recorded removed a live connection
                state.inputs.push(Route::new(src, port_name, "udp").into());
                out.push_str(&remove_input_text(port_name, src, true));
                exchanges += 1;
            }
            TextCommand::DisconnectOutput(dest) => {
                out.push_str(&remove_output_text(port_name, dest, true));
                exchanges += 1;
            }
            TextCommand::ConnectOutput(dest) => {
                out.push_str(&add_output_text(
                    port_name,
                    dest,
                    &AddOutcome::Added { note: None },
                ));
                exchanges += 1;
            }
            TextCommand::Quit => {}
            TextCommand::Reverse => {
                reversed = true;
                exchanges += 1;
            }
            other => {
                out.push_str(&text_reply(other, &state).unwrap_or_default());
                exchanges += 1;
            }
        }
        // text_ack: C++ acknowledges every command once handled (`endRead`), `q` and
        // `r` included
        if ack {
            out.push_str("<ACK>\r\n");
        }
        if matches!(cmd, TextCommand::Quit | TextCommand::Reverse) {
            break;
        }
    }
    Some(Replay {
        expected: out,
        exchanges,
        reversed,
    })
}

fn concat(events: &[Json], dir: &str) -> String {
    events
        .iter()
        .filter(|e| e["dir"] == dir)
        .map(|e| hex::decode(e["hex"].as_str().unwrap_or("")).unwrap_or_default())
        .map(|b| String::from_utf8_lossy(&b).into_owned())
        .collect()
}

fn check_session(rid: &str, c2s: &str, s2c: &str, port: &str, failures: &mut Vec<String>) -> usize {
    let Some(r) = replay_text_session(c2s, port) else {
        return 0;
    };
    let want = normalise_ports(s2c);
    let ours = normalise_ports(&r.expected);
    let ok = if r.reversed {
        want.starts_with(&ours)
    } else {
        want == ours
    };
    if !ok {
        failures.push(format!(
            "{rid}: text session\n  ours {ours:?}\n  want {want:?}"
        ));
    }
    r.exchanges
}

#[test]
fn text_sessions_answer_like_cpp() {
    let mut checked = 0;
    let mut sessions = 0;
    let mut failures = Vec::new();
    for rec in load_records("carriers.jsonl") {
        let rid = id(&rec).to_string();
        let kind = rec["kind"].as_str().unwrap_or("");
        let port = if kind == "reverse" { "/wrev" } else { "/rd" };
        let mut transcripts = Vec::new();
        if let Some(events) = rec["events"].as_array() {
            transcripts.push(events.clone());
        }
        for c in rec["connections"].as_array().into_iter().flatten() {
            if let Some(events) = c["events"].as_array() {
                transcripts.push(events.clone());
            }
        }
        for events in transcripts {
            let c2s = concat(&events, "c2s");
            let s2c = concat(&events, "s2c");
            if c2s.starts_with("CONNECT ") || c2s.starts_with("CONNACK ") {
                sessions += 1;
                checked += check_session(&rid, &c2s, &s2c, port, &mut failures);
            }
        }
    }
    for file in ["controlboard.jsonl", "framegrabber.jsonl", "imu.jsonl"] {
        for rec in load_records(file) {
            let rid = id(&rec).to_string();
            let units = rec["units"].as_array().cloned().unwrap_or_default();
            for u in units
                .iter()
                .filter(|u| u["unit"] == "raw" && u["dir"] == "c2s")
            {
                let c2s = u["text"].as_str().unwrap_or("");
                let s2c: String = units
                    .iter()
                    .filter(|v| {
                        v["unit"] == "raw"
                            && v["dir"] == "s2c"
                            && v["port"] == u["port"]
                            && v["conn"] == u["conn"]
                    })
                    .filter_map(|v| v["text"].as_str())
                    .collect();
                let port = real_port(u["port"].as_str().unwrap_or(""));
                sessions += 1;
                checked += check_session(&rid, c2s, &s2c, &port, &mut failures);
            }
        }
    }
    println!(
        "port admin text sessions: {sessions} sessions, {checked} exchanges checked, {} failed",
        failures.len()
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(
        checked >= 15,
        "expected the recorded sessions, got {checked}"
    );
}

#[test]
fn binary_admin_and_port_commands_like_cpp() {
    let mut admin_checked = 0;
    let mut text_cmds = 0;
    let mut data_cmds = 0;
    let mut failures = Vec::new();
    for file in [
        "carriers.jsonl",
        "controlboard.jsonl",
        "framegrabber.jsonl",
        "imu.jsonl",
        "bottles.jsonl",
    ] {
        for rec in load_records(file) {
            let rid = id(&rec).to_string();
            // every port command anywhere classifies as C++ dispatches it
            let mut all_units: Vec<Json> = Vec::new();
            for key in ["units", "c2s_units", "s2c_units", "request", "reply"] {
                all_units.extend(rec[key].as_array().cloned().unwrap_or_default());
            }
            for c in rec["connections"].as_array().into_iter().flatten() {
                for key in ["c2s_units", "s2c_units"] {
                    all_units.extend(c[key].as_array().cloned().unwrap_or_default());
                }
            }
            if rec["port_command_hex"].is_string() {
                all_units.push(rec.clone());
            }
            for u in &all_units {
                let Some(pc) = u["port_command_hex"].as_str() else {
                    continue;
                };
                let pc = hex::decode(pc).unwrap_or_default();
                if pc.len() != 8 || pc[4] != b'~' {
                    failures.push(format!("{rid}: odd port command {pc:02x?}"));
                    continue;
                }
                let text = u["port_command_text"].as_str().unwrap_or("");
                let cmd = TextCommand::from_binary(pc[5], text);
                match (pc[5], &cmd) {
                    (b'D' | b'd', TextCommand::Data { reply, envelope }) => {
                        if *reply != (pc[5] == b'd') || envelope.is_some() {
                            failures.push(format!("{rid}: {cmd:?}"));
                        }
                        data_cmds += 1;
                    }
                    (b'a', TextCommand::Admin) => {}
                    (0, TextCommand::Data { reply, envelope }) => {
                        let want_env = text.get(2..).filter(|_| text.len() > 2);
                        if *reply != text.starts_with('d') || envelope.as_deref() != want_env {
                            failures.push(format!("{rid}: {text:?} -> {cmd:?}"));
                        }
                        data_cmds += 1;
                    }
                    (0, TextCommand::Quit) if text == "q" => text_cmds += 1,
                    (0, TextCommand::Describe) if text == "*" => {
                        text_cmds += 1;
                        let mut state = PortSnapshot::new("/rd", "tcp", "127.0.0.1", 10002);
                        state.inputs.push(Route::new("/w", "/rd", "tcp").into());
                        let sender = sender_name(&rec);
                        state.inputs.push(Route::new(&sender, "/rd", "tcp").into());
                        let printed: Vec<String> = rec["reader_printed"]
                            .as_array()
                            .into_iter()
                            .flatten()
                            .filter_map(|l| l.as_str().map(normalise_ports))
                            .collect();
                        let ours = normalise_ports(&describe_for_stdout(&state));
                        let mut lines: Vec<String> = ours.split('\n').map(String::from).collect();
                        lines.pop();
                        if lines != printed {
                            failures.push(format!("{rid}: * printed {lines:?} want {printed:?}"));
                        }
                        if has_reply(&rec) {
                            failures.push(format!("{rid}: binary * must not reply"));
                        }
                    }
                    (0, TextCommand::Help) if text == "help" => {
                        text_cmds += 1;
                        if has_reply(&rec) {
                            failures.push(format!("{rid}: binary help must not reply"));
                        }
                    }
                    _ => failures.push(format!("{rid}: {pc:02x?} {text:?} -> {cmd:?}")),
                }
            }
            // admin messages with their replies
            if file != "carriers.jsonl" {
                continue;
            }
            let c2s = rec["c2s_units"].as_array().cloned().unwrap_or_default();
            let s2c = rec["s2c_units"].as_array().cloned().unwrap_or_default();
            let replies: Vec<&Json> = s2c.iter().filter(|u| u["unit"] == "reply").collect();
            let admins: Vec<&Json> = c2s
                .iter()
                .filter(|u| u["port_command_hex"].as_str() == Some("000000007e610001"))
                .collect();
            for (i, m) in admins.iter().enumerate() {
                let Some(want) = replies.get(i) else {
                    failures.push(format!("{rid}: admin message without reply"));
                    continue;
                };
                let cmd = match Bottle::decode(&hex_field(m, "payload_hex")) {
                    Ok(b) => b,
                    Err(e) => {
                        failures.push(format!("{rid}: payload: {e}"));
                        continue;
                    }
                };
                let state = binary_state(&rec);
                let ours = reply_for_admin(&cmd, &state);
                let want_bytes = hex_field(want, "payload_hex");
                if ours.encode() != want_bytes {
                    failures.push(format!(
                        "{rid}: {cmd} -> {} want {}",
                        hex::encode(ours.encode()),
                        hex::encode(&want_bytes)
                    ));
                }
                if want["decoded"].as_str() != Some(ours.to_string().as_str()) {
                    failures.push(format!("{rid}: {cmd} -> {ours} want {}", want["decoded"]));
                }
                admin_checked += 1;
            }
        }
    }
    println!(
        "port admin binary: {admin_checked} admin exchanges, {text_cmds} text port commands, \
         {data_cmds} data port commands checked, {} failed",
        failures.len()
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(
        admin_checked >= 5,
        "expected the recorded admin messages, got {admin_checked}"
    );
    assert!(text_cmds >= 3);
}

fn sender_name(rec: &Json) -> String {
    rec["c2s_units"]
        .as_array()
        .into_iter()
        .flatten()
        .find(|u| u["unit"] == "sender")
        .and_then(|u| u["name"].as_str())
        .unwrap_or("")
        .to_string()
}

fn has_reply(rec: &Json) -> bool {
    rec["s2c_units"]
        .as_array()
        .into_iter()
        .flatten()
        .any(|u| u["unit"] == "reply")
}

/// The recorded set-up of the raw tcp cases: `yarp read /rd` with `yarp write /w`
/// connected over tcp, plus the raw client's own connection; the last case talks to
/// `/w` itself, whose one output goes to `/rd`.
fn binary_state(rec: &Json) -> PortSnapshot {
    let sender = sender_name(rec);
    let into_w = rec["note"]
        .as_str()
        .is_some_and(|n| n.contains("yarp write port /w"));
    if into_w {
        let mut s = PortSnapshot::new("/w", "tcp", "127.0.0.1", 10003);
        s.outputs.push(Route::new("/w", "/rd", "tcp").into());
        s.inputs.push(Route::new(&sender, "/w", "tcp").into());
        s
    } else {
        let mut s = PortSnapshot::new("/rd", "tcp", "127.0.0.1", 10002);
        s.inputs.push(Route::new("/w", "/rd", "tcp").into());
        s.inputs.push(Route::new(&sender, "/rd", "tcp").into());
        s
    }
}
