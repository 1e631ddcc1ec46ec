//! The texts a port writes back on text-mode connections: the help, the `*`
//! description, and the outcome lines of connection changes. Every line ends with CRLF,
//! as C++ `BufferedConnectionWriter::appendLine` writes it.

use super::{PortSnapshot, TextCommand};

/// What C++ writes back for a text command it does not know (the key is neither a
/// command nor `h`/`?`; release builds also treat `i` this way).
pub const NOT_UNDERSTOOD_TEXT: &str = crate::wire::NOT_UNDERSTOOD;

/// The help text (`?`, `help`, or any line starting with `h`), as a release build of
/// C++ YARP 3.12 writes it (the debug-only `i` line is absent).
pub fn help_text() -> &'static str {
    crate::wire::PORT_HELP
}

/// C++ `Contact::toURI()`: `carrier:/` + `/host:port/` (each part only when known).
pub fn contact_uri(carrier: &str, host: &str, port: i32) -> String {
    let mut s = String::new();
    if !carrier.is_empty() {
        s.push_str(carrier);
        s.push_str(":/");
    }
    if !host.is_empty() && port >= 0 {
        s.push('/');
        s.push_str(host);
        s.push(':');
        s.push_str(&port.to_string());
        s.push('/');
    }
    s
}

/// The `*` description, as written back on a text connection:
///
/// ```text
/// This is /rd at tcp://127.0.0.1:10002/
/// There are no outgoing connections
/// There is an input connection from /w to /rd using tcp
/// ```
/// Outputs read `There is an output connection from /w to /rd using tcp`; with no
/// inputs the last line is `There are no incoming connections`. Inputs with an empty
/// carrier name are not listed.
pub fn describe(state: &PortSnapshot) -> String {
    let mut out = String::new();
    line(
        &mut out,
        &format!(
            "This is {} at {}",
            state.name,
            contact_uri(&state.carrier, &state.host, state.port)
        ),
    );
    for c in &state.outputs {
        let r = &c.route;
        line(
            &mut out,
            &format!(
                "There is an output connection from {} to {} using {}",
                r.from, r.to, r.carrier
            ),
        );
    }
    if state.outputs.is_empty() {
        line(&mut out, "There are no outgoing connections");
    }
    let mut inputs = 0;
    for c in state.inputs.iter().filter(|c| !c.route.carrier.is_empty()) {
        let r = &c.route;
        line(
            &mut out,
            &format!(
                "There is an input connection from {} to {} using {}",
                r.from, r.to, r.carrier
            ),
        );
        inputs += 1;
    }
    if inputs == 0 {
        line(&mut out, "There are no incoming connections");
    }
    out
}

/// What the port owner prints on its stdout when `*` arrives on a binary (tcp-family)
/// connection: the description followed by one more newline (`printf("%s\n")`).
pub fn describe_for_stdout(state: &PortSnapshot) -> String {
    let mut s = describe(state);
    s.push('\n');
    s
}

/// The line written back for `/port` (or printed for an `[add]`) once the I/O layer
/// tried the connection. `dest` is the text as given (e.g. `udp://cbcap/stateExt:i`).
pub fn add_output_text(port_name: &str, dest: &str, outcome: &super::AddOutcome) -> String {
    use super::AddOutcome;
    let mut s = match outcome {
        AddOutcome::Added { note } => format!(
            "Added connection from {port_name} to {dest}{}",
            note.as_deref().unwrap_or("")
        ),
        AddOutcome::AlreadyPresent => {
            format!("Desired connection already present from {port_name} to {dest}")
        }
        AddOutcome::UnknownTarget => format!("Do not know how to connect to {dest}"),
        AddOutcome::NotAllowed(reason) => reason.clone(),
        AddOutcome::CannotConnect => format!("Cannot connect to {dest}"),
    };
    s.push_str("\r\n");
    s
}

/// The line for `!/port` / the output half of `[del]`: `removed` = some connection
/// matched (C++ matches every connection whose route goes *to* `dest`).
pub fn remove_output_text(port_name: &str, dest: &str, removed: bool) -> String {
    if removed {
        format!("Removed connection from {port_name} to {dest}\r\n")
    } else {
        format!("Could not find an outgoing connection to {dest}\r\n")
    }
}

/// The line for `~/port` / the input half of `[del]`: `removed` = some connection
/// matched (C++ matches every connection whose route comes *from* `src`).
pub fn remove_input_text(port_name: &str, src: &str, removed: bool) -> String {
    if removed {
        format!("Removing connection from {src} to {port_name}\r\n")
    } else {
        format!("Could not find an incoming connection from {src}\r\n")
    }
}

/// The text C++ writes back on a *text-mode* connection for commands that answer
/// immediately: help, `*`, and unknown keys. `None` for everything else (data, admin,
/// `q`, `r` write nothing themselves; `/port`, `!/port`, `~/port` answer with
/// [`add_output_text`] / [`remove_output_text`] / [`remove_input_text`] after the I/O
/// layer acted). On binary connections none of these texts is sent back.
pub fn text_reply(cmd: &TextCommand, state: &PortSnapshot) -> Option<String> {
    match cmd {
        TextCommand::Help => Some(help_text().to_string()),
        TextCommand::Describe => Some(describe(state)),
        TextCommand::NotUnderstood(_) => Some(NOT_UNDERSTOOD_TEXT.to_string()),
        _ => None,
    }
}

fn line(out: &mut String, s: &str) {
    out.push_str(s);
    out.push_str("\r\n");
}
