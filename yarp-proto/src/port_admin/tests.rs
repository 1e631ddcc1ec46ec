//! Unit tests of the port administration protocol (expected strings from C++ YARP 3.12
//! sources and the recorded vectors).

use super::*;
use crate::{Bottle, Value, Vocab32};

fn rd() -> PortSnapshot {
    let mut p = PortSnapshot::new("/rd", "tcp", "127.0.0.1", 10002);
    p.inputs.push(Route::new("/w", "/rd", "tcp").into());
    p.inputs.push(Route::new("/rawtcp", "/rd", "tcp").into());
    p
}

fn admin(text: &str, state: &PortSnapshot) -> AdminResponse {
    handle_admin(&Bottle::from_text(text), state)
}

fn reply(text: &str, state: &PortSnapshot) -> String {
    admin(text, state).reply.to_string()
}

#[test]
fn help_text_is_exact() {
    let h = help_text();
    assert!(h.starts_with("This is a YARP port.  Here are the commands it responds to:\r\n"));
    assert!(h.contains(
        "do      The same as \"d\" except replies should be suppressed (\"data-only\")\r\n"
    ));
    assert!(h.ends_with("?       Gives this help\r\n"));
    assert_eq!(h.matches("\r\n").count(), 11);
    assert!(!h.contains("\ni "));
}

#[test]
fn describe_forms() {
    let mut p = PortSnapshot::new("/rd", "tcp", "127.0.0.1", 10002);
    assert_eq!(
        describe(&p),
        "This is /rd at tcp://127.0.0.1:10002/\r\nThere are no outgoing connections\r\nThere are no incoming connections\r\n"
    );
    p.inputs.push(Route::new("/rawadmin", "/rd", "text").into());
    p.inputs.push(Route::new("/hidden", "/rd", "").into());
    p.outputs.push(Route::new("/rd", "/x", "udp").into());
    assert_eq!(
        describe(&p),
        "This is /rd at tcp://127.0.0.1:10002/\r\nThere is an output connection from /rd to /x using udp\r\nThere is an input connection from /rawadmin to /rd using text\r\n"
    );
    assert!(describe_for_stdout(&p).ends_with("text\r\n\n"));
    assert_eq!(contact_uri("", "h", 1), "/h:1/");
    assert_eq!(contact_uri("tcp", "", 1), "tcp:/");
    assert_eq!(contact_uri("tcp", "h", -1), "tcp:/");
}

#[test]
fn text_replies() {
    let p = rd();
    assert_eq!(
        text_reply(&TextCommand::from_line("help"), &p).as_deref(),
        Some(help_text())
    );
    assert_eq!(
        text_reply(&TextCommand::from_line("?"), &p).as_deref(),
        Some(help_text())
    );
    assert_eq!(
        text_reply(&TextCommand::from_line("*"), &p),
        Some(describe(&p))
    );
    assert_eq!(
        text_reply(&TextCommand::from_line("xyz"), &p).as_deref(),
        Some("Port command not understood.\r\nType d to send data to the port's owner.\r\nType ? for help.\r\n")
    );
    for l in ["d", "D", "a", "q", "r", "/x", "!/x", "~/x"] {
        assert_eq!(text_reply(&TextCommand::from_line(l), &p), None, "{l}");
    }
    assert_eq!(
        remove_input_text("/fake/command:i", "/cbcap/command:o", true),
        "Removing connection from /cbcap/command:o to /fake/command:i\r\n"
    );
    assert_eq!(
        remove_input_text("/rd", "/zz", false),
        "Could not find an incoming connection from /zz\r\n"
    );
    assert_eq!(
        remove_output_text("/w", "/rd", true),
        "Removed connection from /w to /rd\r\n"
    );
    assert_eq!(
        remove_output_text("/w", "/zz", false),
        "Could not find an outgoing connection to /zz\r\n"
    );
    assert_eq!(
        add_output_text("/w", "/zz", &AddOutcome::UnknownTarget),
        "Do not know how to connect to /zz\r\n"
    );
    assert_eq!(
        add_output_text("/w", "/zz", &AddOutcome::CannotConnect),
        "Cannot connect to /zz\r\n"
    );
}

#[test]
fn help_ver_and_unknown() {
    let p = rd();
    let h = admin("[help]", &p);
    assert_eq!(h.reply.len(), 21);
    assert_eq!(h.reply.get(0), Some(&Value::vocab("many")));
    assert_eq!(h.pending, Pending::None);
    // string "help" is vocab help too (C++ asVocab32 of a string)
    assert_eq!(admin("help", &p).reply, h.reply);
    assert_eq!(reply("[ver]", &p), "[ver] 1 2 3");
    assert_eq!(
        reply("[zzz]", &p),
        "[fail] \"send [help] for list of valid commands\""
    );
    assert_eq!(
        reply("", &p),
        "[fail] \"send [help] for list of valid commands\""
    );
    assert_eq!(
        reply("42", &p),
        "[fail] \"send [help] for list of valid commands\""
    );
    let mut q = rd();
    q.has_admin_reader = true;
    let r = admin("[zzz] 1", &q);
    assert_eq!(r.pending, Pending::Unknown);
    assert_eq!(
        r.actions,
        vec![AdminAction::ForwardToAdminReader {
            cmd: Bottle::from_text("[zzz] 1")
        }]
    );
    assert_eq!(
        format_unknown_result(Some(Bottle::from_text("[ok]"))).to_string(),
        "[ok]"
    );
}

#[test]
fn add_and_del() {
    let p = PortSnapshot::new("/fake/stateExt:o", "tcp", "127.0.0.1", 10005);
    let r = admin("[add] \"udp://cbcap/stateExt:i\"", &p);
    assert_eq!(
        r.pending,
        Pending::Add {
            dest: "udp://cbcap/stateExt:i".into()
        }
    );
    match &r.actions[..] {
        [AdminAction::AddOutput { dest, target }] => {
            assert_eq!(dest, "udp://cbcap/stateExt:i");
            assert_eq!(target.carrier.as_deref(), Some("udp"));
            assert_eq!(target.name, "/cbcap/stateExt:i");
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(
        String::from_utf8(reply_text_line(&r.reply)).unwrap(),
        "0 \"Added connection from /fake/stateExt:o to udp://cbcap/stateExt:i\\r\\n\"\r\n"
    );
    // carrier as second argument
    let r = admin("[add] /x tcp", &p);
    assert_eq!(
        r.pending,
        Pending::Add {
            dest: "tcp://x".into()
        }
    );
    let f = format_add_result(
        "/w",
        "/x",
        &AddOutcome::NotAllowed("Outputs not allowed".into()),
    );
    assert_eq!(f.to_string(), "-1 \"Outputs not allowed\\r\\n\"");
    let f = format_add_result("/w", "/x", &AddOutcome::AlreadyPresent);
    assert_eq!(f.get(0), Some(&Value::Int32(-1)));
    let f = format_add_result(
        "/w",
        "/x",
        &AddOutcome::Added {
            note: Some("; /w will forward messages and replies (if any) to /x".into()),
        },
    );
    assert_eq!(f.get(0), Some(&Value::Int32(0)));

    let mut w = PortSnapshot::new("/w", "tcp", "127.0.0.1", 10003);
    w.outputs.push(Route::new("/w", "/rd", "tcp").into());
    let r = admin("[del] /rd", &w);
    assert_eq!(
        r.actions,
        vec![
            AdminAction::RemoveOutput { to: "/rd".into() },
            AdminAction::RemoveInput { from: "/rd".into() }
        ]
    );
    assert_eq!(
        r.reply.to_string(),
        "0 \"Removed connection from /w to /rd\\r\\n\""
    );
    assert_eq!(
        format_del_result("/w", "/q", false, true).to_string(),
        "0 \"Removing connection from /q to /w\\r\\n\""
    );
    assert_eq!(
        format_del_result("/w", "/q", false, false).to_string(),
        "-1 \"Could not find an outgoing connection to /q\\r\\nCould not find an incoming connection from /q\\r\\n\""
    );
    assert_eq!(
        format_del_result("/w", "/q", true, true).to_string(),
        "0 \"Removed connection from /w to /q\\r\\nRemoving connection from /q to /w\\r\\n\""
    );
    assert_eq!(reply("[del]", &w), "-1 \"Could not find an outgoing connection to \\r\\nCould not find an incoming connection from \\r\\n\"");
}

#[test]
fn list_forms() {
    let mut p = rd();
    p.inputs.push(Route::new("", "/rd", "tcp").into());
    assert_eq!(reply("[list] [in]", &p), "\"/w\" \"/rawtcp\"");
    assert_eq!(reply("[list] [out]", &p), "");
    assert_eq!(
        admin("[list] [out]", &p).reply.encode(),
        hex_bytes("0001000000000000")
    );
    assert_eq!(
        reply("[list] [in] /w", &p),
        "(from \"/w\") (to \"/rd\") (carrier tcp)"
    );
    assert_eq!(reply("[list] [in] /nope", &p), "");
    p.outputs.push(Route::new("/rd", "/u", "udp").into());
    let mut pull = Connection::new(Route::new("/rd", "/h", "http"));
    pull.push = false;
    p.outputs.push(pull);
    assert_eq!(reply("[list] [out]", &p), "\"/u\" \"/h\"");
    assert_eq!(reply("[list]", &p), "\"/u\" \"/h\"");
    assert_eq!(reply("[list] [zz]", &p), "\"/u\" \"/h\"");
    assert_eq!(
        reply("[list] [out] /u", &p),
        "(from \"/rd\") (to \"/u\") (carrier udp) (connectionless 1)"
    );
    assert_eq!(
        reply("[list] [out] /h", &p),
        "(from \"/rd\") (to \"/h\") (carrier http) (push 0)"
    );
}

fn hex_bytes(s: &str) -> Vec<u8> {
    (0..s.len() / 2)
        .map(|i| u8::from_str_radix(&s[2 * i..2 * i + 2], 16).unwrap())
        .collect()
}

#[test]
fn set_get_carrier_params() {
    let mut p = rd();
    p.outputs.push(Route::new("/rd", "/o", "tcp").into());
    assert_eq!(
        reply("[set] [in]", &p),
        "-1 \"target port is not specified.\\r\\n\""
    );
    assert_eq!(
        reply("[get] [out]", &p),
        "-1 \"target port is not specified.\\r\\n\""
    );
    let r = admin("[set] [in] /w (x 1)", &p);
    assert_eq!(
        r.reply.to_string(),
        "0 \"Configured connection from /w\\r\\n\""
    );
    assert!(
        matches!(&r.actions[..], [AdminAction::SetCarrierParams { direction: Direction::In, target, .. }] if target == "/w")
    );
    assert_eq!(
        reply("[set] [out] /o", &p),
        "0 \"Configured connection to /o\\r\\n\""
    );
    assert_eq!(
        reply("[set] [in] /zz", &p),
        "-1 \"Could not find an incoming connection from /zz\\r\\n\""
    );
    assert_eq!(
        reply("[set] [out] /zz", &p),
        "-1 \"Could not find an incoming connection to /zz\\r\\n\""
    );
    assert_eq!(
        reply("[set] [in] /rd", &p),
        "[fail] \"No port modifier is attached to the input\""
    );
    assert_eq!(
        reply("[get] [out] /rd", &p),
        "[fail] \"No port modifier is attached to the output\""
    );
    assert_eq!(
        reply("[get] [in] /zz", &p),
        "-1 \"Could not find an incoming connection from /zz\\r\\n\""
    );
    p.inputs[0].params.insert("b".into(), Value::Int32(2));
    p.inputs[0].params.insert("a".into(), Value::from("x"));
    let r = admin("[get] [in] /w", &p).reply;
    assert_eq!(
        r.get(0)
            .and_then(Value::as_dict)
            .map(|d| d.to_string())
            .as_deref(),
        Some("(a x) (b 2)")
    );
}

#[test]
fn atch_dtch() {
    let p = rd();
    let r = admin("[atch] [in]", &p);
    assert_eq!(
        r.reply.to_string(),
        "[fail] \"Failed to configure the portmonitor plug-in\""
    );
    assert_eq!(r.pending, Pending::Attach);
    assert_eq!(
        reply("[atch] [zz]", &p),
        "[fail] \"attach command must be followed by [out] or [in]\""
    );
    assert_eq!(reply("[dtch] [out]", &p), "[ok]");
    assert_eq!(
        reply("[dtch]", &p),
        "[fail] \"detach command must be followed by [out] or [in]\""
    );
    assert_eq!(format_atch_result(Ok(())).to_string(), "[ok]");
}

#[test]
fn prop_forms() {
    let mut p = rd();
    assert_eq!(reply("[prop] [get]", &p), "");
    assert_eq!(reply_text_line(&admin("[prop] [get]", &p).reply), b"\r\n");
    let r = admin("[prop] [set] color red", &p);
    assert_eq!(r.reply.to_string(), "[ok]");
    assert_eq!(
        r.actions,
        vec![AdminAction::SetProperty {
            key: "color".into(),
            value: Value::from("red")
        }]
    );
    p.properties.insert("color".into(), Value::from("red"));
    p.properties.insert("a".into(), Value::Int32(5));
    assert_eq!(reply("[prop] [get]", &p), "(a 5) (color red)");
    assert_eq!(reply("[prop] [get] color", &p), "red");
    assert_eq!(reply("[prop] [get] nope", &p), "");
    assert_eq!(
        reply("[prop] [zz]", &p),
        "[fail] \"property action not known\""
    );
    assert_eq!(
        reply("[prop] [get] /nope", &p),
        "[fail] \"cannot find any connection to/from /nope\""
    );
    assert_eq!(
        reply("[prop] [get] /w", &p),
        "(sched ((policy -1) (priority -1) (tid 0))) (qos ((tos -1)))"
    );
    p.process = ProcessInfo {
        pid: 42,
        name: "yarp".into(),
        arguments: "read /rd".into(),
        os: "Linux".into(),
        ..Default::default()
    };
    let own = admin("[prop] [get] /rd", &p).reply;
    assert_eq!(own.len(), 4);
    let names: Vec<_> = own
        .iter()
        .map(|g| {
            g.as_list()
                .and_then(|l| l.get(0))
                .and_then(Value::as_str)
                .unwrap_or("")
        })
        .collect();
    assert_eq!(names, ["sched", "process", "platform", "port"]);
    let process = own[1].as_list().unwrap()[1].as_dict().unwrap();
    assert_eq!(process.find("pid"), Some(&Value::Int32(42)));
    assert_eq!(
        process.find("arguments").and_then(Value::as_str),
        Some("read /rd")
    );
    // scheduling / qos forms
    let r = admin("[prop] [set] /w (sched ((priority 30) (policy 1)))", &p);
    assert_eq!(r.pending, Pending::PropSet { action: 1 });
    assert_eq!(
        r.actions[1],
        AdminAction::SetConnectionScheduling {
            name: "/w".into(),
            priority: 30,
            policy: 1
        }
    );
    assert_eq!(format_prop_set_result(false).to_string(), "[fail]");
    let r = admin("[prop] [set] /w (qos ((priority HIGH)))", &p);
    assert_eq!(
        r.actions[1],
        AdminAction::SetTypeOfService {
            name: "/w".into(),
            tos: 144
        }
    );
    let r = admin("[prop] [set] /w (qos ((dscp AF12)))", &p);
    assert_eq!(
        r.actions[1],
        AdminAction::SetTypeOfService {
            name: "/w".into(),
            tos: 48
        }
    );
    let r = admin("[prop] [set] /w (qos ((tos 12)))", &p);
    assert_eq!(
        r.actions[1],
        AdminAction::SetTypeOfService {
            name: "/w".into(),
            tos: 12
        }
    );
    let r = admin("[prop] [set] /w (qos ((priority ZZZ)))", &p);
    assert_eq!(
        (r.reply.to_string().as_str(), r.pending.clone()),
        ("[fail]", Pending::None)
    );
    let r = admin("[prop] [set] /zz (sched ((priority 30)))", &p);
    assert_eq!(r.reply.to_string(), "[fail]");
    let r = admin("[prop] [set] /rd (process ((priority 30) (policy 1)))", &p);
    assert_eq!(
        r.actions[1],
        AdminAction::SetProcessScheduling {
            priority: 30,
            policy: 1
        }
    );
    assert_eq!(r.pending, Pending::PropSet { action: 1 });
}

#[test]
fn ros_and_pray() {
    let mut p = rd();
    p.process.pid = 77;
    let r = admin("getPid /caller", &p);
    assert_eq!(r.reply.to_string(), "1 \"\" 77");
    assert_eq!(r.actions, vec![AdminAction::DropConnection]);
    assert_eq!(reply("getBusInfo", &p), "1 \"\" (())");
    assert_eq!(
        reply("requestTopic /c /t ((TCPROS))", &p),
        "1 \"/rd\" (TCPROS \"127.0.0.1\" 10002)"
    );
    let r = admin("publisherUpdate /c t (\"http://a:1/\")", &p);
    assert_eq!(r.reply.to_string(), "1 ok");
    assert!(
        matches!(&r.actions[0], AdminAction::RosPublisherUpdate { topic, publishers } if topic == "/t" && publishers.len() == 1)
    );
    for seed in 0..200 {
        p.seed = seed;
        let b = admin("[pray]", &p).reply;
        assert!(b.len() >= 3);
        assert_eq!(
            b.get(0).and_then(Value::as_str),
            Some("You begin praying to rd.")
        );
        assert!(!b.to_string().contains('<'));
    }
}

#[test]
fn never_panics_on_odd_input() {
    let p = rd();
    let odd = [
        "",
        "()",
        "[add]",
        "[add] 1 2",
        "[del] (1)",
        "[list] 5 6",
        "[prop]",
        "[prop] [set]",
        "[prop] [set] / (process) (sched) (qos)",
        "[prop] [get] /",
        "[set]",
        "[get]",
        "[atch]",
        "(a b) c",
        "publisherUpdate",
        "requestTopic",
        "{1 2}",
        "[prop] [set] /rd (process 5)",
        "[prop] [set] /w (qos ((dscp 99)))",
        "[prop] [set] /w (qos ((dscp 3)))",
    ];
    for t in odd {
        let _ = admin(t, &p);
    }
    let mut b = Bottle::new();
    b.push(Value::Blob(vec![0xff; 3]))
        .push(Value::String(vec![0xff, 0xfe]));
    let _ = handle_admin(&b, &p);
    let _ = handle_admin(&Bottle::new().with(Vocab32(-1)), &p);
    let _ = handle_admin(&Bottle::new().with(Value::Float64(f64::NAN)), &p);
}

#[test]
fn responder_listing_goes_out_one_line_per_entry() {
    // C++ DeviceResponder::read in text mode: strings keep their quotes, the trailing
    // vocab is a line of its own
    let reply = Bottle::from_text("[many] \"[help]\" \"[get] [axes]\" (1 2) [ok]");
    assert_eq!(
        responder_text_lines(&reply),
        b"\"[help]\"\r\n\"[get] [axes]\"\r\n1 2\r\n[ok]\r\n"
    );
    let plain = Bottle::from_text("[is] [axes] 2 [ok]");
    assert_eq!(responder_text_lines(&plain), b"[is] [axes] 2 [ok]\r\n");
}
