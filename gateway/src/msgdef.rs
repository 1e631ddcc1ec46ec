//! ROS 2 interface definitions (`.msg`, `.srv`, `.action`) parsed into type descriptions (pure).
//!
//! The grammar is rosidl's (`rosidl_adapter`'s parser): one field `TYPE NAME [DEFAULT]` or
//! constant `TYPE NAME=VALUE` per line, `#` starts a comment anywhere on a line, types are
//! primitives (`bool byte char int8..uint64 float32 float64 string wstring`, ROS 1's `time`
//! and `duration`), bounded strings `string<=N`, nested messages `pkg/Type` or `Type` (same
//! package), each optionally an array `T[N]`, a bounded sequence `T[<=N]` or a sequence
//! `T[]`. A `.srv` is a request and a response separated by `---`; as rosidl does, it
//! also yields the `_Event` structure and the service description REP-2016 hashes. An
//! `.action` is a goal, a result and a feedback, from which rosidl derives two services,
//! a feedback message and the action description.

use crate::types::{Prim, Shape};

/// What a field holds: a primitive or a nested message (full name `pkg/msg/Type`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum BaseDef {
    Prim(Prim),
    Nested(String),
}

/// One field as defined.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FieldDef {
    pub name: String,
    pub base: BaseDef,
    pub shape: Shape,
    pub string_capacity: u64,
    pub default: Option<String>,
}

/// One constant as defined (`uint8 ARROW=0`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ConstDef {
    pub name: String,
    pub prim: Prim,
    pub value: String,
}

/// One structure: a message, a service's request/response/event, or the service itself.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MsgDef {
    /// Full name: `pkg/msg/Name`, `pkg/srv/Name_Request`, ...
    pub name: String,
    pub fields: Vec<FieldDef>,
    pub constants: Vec<ConstDef>,
}

/// A definition that cannot be used: which line and why.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{type_name} line {line}: {message}")]
pub struct DefError {
    pub type_name: String,
    pub line: usize,
    pub message: String,
}

/// rosidl gives an empty structure this one member (and hashes it).
pub const EMPTY_MEMBER: &str = "structure_needs_at_least_one_member";

/// Parses the `.msg` text of `pkg/msg/name`.
pub fn parse_msg(pkg: &str, name: &str, text: &str) -> Result<MsgDef, DefError> {
    parse_body(&format!("{pkg}/msg/{name}"), pkg, text, 0)
}

/// Parses the `.srv` text of `pkg/srv/name`: `[Name_Request, Name_Response, Name_Event,
/// Name]`, the last being the service description of REP-2016 (`request_message`,
/// `response_message`, `event_message`).
pub fn parse_srv(pkg: &str, name: &str, text: &str) -> Result<Vec<MsgDef>, DefError> {
    let full = format!("{pkg}/srv/{name}");
    let [req, resp] = parse_parts(&full, pkg, text, ["_Request", "_Response"])?;
    Ok(service_structures(&full, req, resp))
}

/// Parses the `.action` text of `pkg/action/name` (goal, result and feedback separated by
/// `---`) into the structures rosidl derives from it: `Name_Goal`, `_Result`, `_Feedback`,
/// the `_SendGoal` and `_GetResult` services (each with its request, response and event),
/// `_FeedbackMessage`, and `Name`, the action description of REP-2016.
pub fn parse_action(pkg: &str, name: &str, text: &str) -> Result<Vec<MsgDef>, DefError> {
    let full = format!("{pkg}/action/{name}");
    let [goal, result, feedback] =
        parse_parts(&full, pkg, text, ["_Goal", "_Result", "_Feedback"])?;
    let field = |n: &str, base: BaseDef| FieldDef {
        name: n.into(),
        base,
        shape: Shape::Single,
        string_capacity: 0,
        default: None,
    };
    let nested = |n: &str, t: &str| field(n, BaseDef::Nested(t.into()));
    let structure = |suffix: &str, fields| MsgDef {
        name: format!("{full}{suffix}"),
        fields,
        constants: Vec::new(),
    };
    let send_goal = service_structures(
        &format!("{full}_SendGoal"),
        structure(
            "_SendGoal_Request",
            vec![nested("goal_id", UUID), nested("goal", &goal.name)],
        ),
        structure(
            "_SendGoal_Response",
            vec![
                field("accepted", BaseDef::Prim(Prim::Bool)),
                nested("stamp", "builtin_interfaces/msg/Time"),
            ],
        ),
    );
    let get_result = service_structures(
        &format!("{full}_GetResult"),
        structure("_GetResult_Request", vec![nested("goal_id", UUID)]),
        structure(
            "_GetResult_Response",
            vec![
                field("status", BaseDef::Prim(Prim::I8)),
                nested("result", &result.name),
            ],
        ),
    );
    let feedback_message = structure(
        "_FeedbackMessage",
        vec![nested("goal_id", UUID), nested("feedback", &feedback.name)],
    );
    let action = structure(
        "",
        vec![
            nested("goal", &goal.name),
            nested("result", &result.name),
            nested("feedback", &feedback.name),
            nested("send_goal_service", &format!("{full}_SendGoal")),
            nested("get_result_service", &format!("{full}_GetResult")),
            nested("feedback_message", &feedback_message.name),
        ],
    );
    let mut all = vec![goal, result, feedback];
    all.extend(send_goal);
    all.extend(get_result);
    all.extend([feedback_message, action]);
    Ok(all)
}

/// A goal's identity in every action structure.
const UUID: &str = "unique_identifier_msgs/msg/UUID";

/// The structures of a `.srv` or `.action` text: its `---`-separated parts, each named
/// `full` + its suffix (as many parts as suffixes, else an error).
fn parse_parts<const N: usize>(
    full: &str,
    pkg: &str,
    text: &str,
    suffixes: [&str; N],
) -> Result<[MsgDef; N], DefError> {
    let lines: Vec<&str> = text.lines().collect();
    let splits: Vec<usize> = lines
        .iter()
        .enumerate()
        .filter(|(_, l)| l.trim_end() == "---")
        .map(|(i, _)| i)
        .collect();
    if splits.len() != N - 1 {
        return Err(DefError {
            type_name: full.to_string(),
            line: 0,
            message: format!(
                "{} needs {} `---` separator{} ({}), found {}",
                if N == 2 { "a service" } else { "an action" },
                N - 1,
                if N == 2 { "" } else { "s" },
                suffixes
                    .iter()
                    .map(|s| s.trim_start_matches('_').to_lowercase())
                    .collect::<Vec<_>>()
                    .join(", "),
                splits.len()
            ),
        });
    }
    let mut parts = Vec::with_capacity(N);
    let mut start = 0;
    for (k, suffix) in suffixes.iter().enumerate() {
        let end = splits.get(k).copied().unwrap_or(lines.len());
        parts.push(parse_body(
            &format!("{full}{suffix}"),
            pkg,
            &lines[start..end].join("\n"),
            start,
        )?);
        start = end + 1;
    }
    Ok(parts
        .try_into()
        .unwrap_or_else(|_| unreachable!("one structure per suffix")))
}

/// A service's request and response with the `_Event` structure and the service
/// description rosidl derives from them: `[Request, Response, Event, service]`.
pub fn service_structures(full: &str, req: MsgDef, resp: MsgDef) -> Vec<MsgDef> {
    let nested = |n: &str, t: String, shape| FieldDef {
        name: n.into(),
        base: BaseDef::Nested(t),
        shape,
        string_capacity: 0,
        default: None,
    };
    let event = MsgDef {
        name: format!("{full}_Event"),
        fields: vec![
            nested(
                "info",
                "service_msgs/msg/ServiceEventInfo".into(),
                Shape::Single,
            ),
            nested("request", req.name.clone(), Shape::BoundedSeq(1)),
            nested("response", resp.name.clone(), Shape::BoundedSeq(1)),
        ],
        constants: Vec::new(),
    };
    let service = MsgDef {
        name: full.to_string(),
        fields: vec![
            nested("request_message", req.name.clone(), Shape::Single),
            nested("response_message", resp.name.clone(), Shape::Single),
            nested("event_message", event.name.clone(), Shape::Single),
        ],
        constants: Vec::new(),
    };
    vec![req, resp, event, service]
}

fn parse_body(
    type_name: &str,
    pkg: &str,
    text: &str,
    first_line: usize,
) -> Result<MsgDef, DefError> {
    let mut def = MsgDef {
        name: type_name.to_string(),
        fields: Vec::new(),
        constants: Vec::new(),
    };
    for (i, raw) in text.lines().enumerate() {
        let err = |message: String| DefError {
            type_name: type_name.to_string(),
            line: first_line + i + 1,
            message,
        };
        let line = raw.replace('\t', " ");
        // rosidl cuts at the first `#`, even inside a quoted default.
        let line = line.split('#').next().unwrap_or_default().trim();
        if line.is_empty() {
            continue;
        }
        let (type_str, rest) = line
            .split_once(' ')
            .ok_or_else(|| err(format!("`{line}` has a type but no name")))?;
        let rest = rest.trim_start();
        if let Some((cname, value)) = rest.split_once('=') {
            let (cname, value) = (cname.trim(), value.trim());
            let prim = match parse_type(type_str, pkg).map_err(|e| err(e.to_string()))? {
                (BaseDef::Prim(p), Shape::Single, _) => p,
                _ => {
                    return Err(err(format!(
                        "constant {cname}: `{type_str}` is not primitive"
                    )))
                }
            };
            check_name(cname, true).map_err(|e| err(e.to_string()))?;
            def.constants.push(ConstDef {
                name: cname.to_string(),
                prim,
                value: value.to_string(),
            });
            continue;
        }
        let (fname, default) = match rest.split_once(' ') {
            Some((n, d)) if !d.trim().is_empty() => (n, Some(d.trim().to_string())),
            Some((n, _)) => (n, None),
            None => (rest, None),
        };
        check_name(fname, false).map_err(|e| err(e.to_string()))?;
        let (base, shape, string_capacity) =
            parse_type(type_str, pkg).map_err(|e| err(e.to_string()))?;
        if default.is_some() && matches!(base, BaseDef::Nested(_)) {
            return Err(err(format!(
                "field {fname}: nested messages take no default value"
            )));
        }
        def.fields.push(FieldDef {
            name: fname.to_string(),
            base,
            shape,
            string_capacity,
            default,
        });
    }
    if def.fields.is_empty() {
        def.fields.push(FieldDef {
            name: EMPTY_MEMBER.into(),
            base: BaseDef::Prim(Prim::U8),
            shape: Shape::Single,
            string_capacity: 0,
            default: None,
        });
    }
    Ok(def)
}

/// Field names are lower-case (`[a-z][a-z0-9_]*`), constants upper-case; no `__`, no
/// trailing `_` (rosidl's patterns).
fn check_name(n: &str, constant: bool) -> Result<(), BadName<'_>> {
    let first_ok = n.chars().next().is_some_and(|c| {
        if constant {
            c.is_ascii_uppercase()
        } else {
            c.is_ascii_lowercase()
        }
    });
    let rest_ok = n.chars().all(|c| {
        c.is_ascii_digit()
            || c == '_'
            || if constant {
                c.is_ascii_uppercase()
            } else {
                c.is_ascii_lowercase()
            }
    });
    if first_ok && rest_ok && !n.contains("__") && !n.ends_with('_') {
        Ok(())
    } else {
        Err(BadName(n, if constant { "constant" } else { "field" }))
    }
}

/// A name [`check_name`] refuses, and whether it was for a constant or a field.
#[derive(Debug, thiserror::Error)]
#[error("`{0}` is not a valid {1} name")]
struct BadName<'a>(&'a str, &'static str);

/// A type [`parse_type`] cannot read.
#[derive(Debug, thiserror::Error)]
#[error("`{0}` is not a type")]
struct BadType<'a>(&'a str);

/// `T`, `T[N]`, `T[<=N]`, `T[]` with `T` a primitive, `string<=N`, `pkg/Type` or `Type`.
fn parse_type<'a>(s: &'a str, pkg: &str) -> Result<(BaseDef, Shape, u64), BadType<'a>> {
    let bad = || BadType(s);
    let (base, shape) = match s.strip_suffix(']') {
        Some(head) => {
            let open = head.rfind('[').ok_or_else(bad)?;
            let inside = &head[open + 1..];
            let shape = if inside.is_empty() {
                Shape::Seq
            } else if let Some(n) = inside.strip_prefix("<=") {
                Shape::BoundedSeq(positive(n).ok_or_else(bad)?)
            } else {
                Shape::Array(positive(inside).ok_or_else(bad)?)
            };
            (&head[..open], shape)
        }
        None => (s, Shape::Single),
    };
    if let Some((kind, bound)) = base.split_once("<=") {
        let prim = match kind {
            "string" => Prim::String,
            "wstring" => Prim::WString,
            _ => return Err(bad()),
        };
        return Ok((BaseDef::Prim(prim), shape, positive(bound).ok_or_else(bad)?));
    }
    let prim = match base {
        "bool" => Prim::Bool,
        "byte" => Prim::Byte,
        // ROS 2 maps the deprecated `char` to uint8.
        "char" | "uint8" => Prim::U8,
        "int8" => Prim::I8,
        "int16" => Prim::I16,
        "uint16" => Prim::U16,
        "int32" => Prim::I32,
        "uint32" => Prim::U32,
        "int64" => Prim::I64,
        "uint64" => Prim::U64,
        "float32" => Prim::F32,
        "float64" => Prim::F64,
        "string" => Prim::String,
        "wstring" => Prim::WString,
        "time" => return Ok((nested("builtin_interfaces/msg/Time"), shape, 0)),
        "duration" => return Ok((nested("builtin_interfaces/msg/Duration"), shape, 0)),
        _ => {
            let (p, t) = base.split_once('/').unwrap_or((pkg, base));
            let type_ok = t.starts_with(|c: char| c.is_ascii_uppercase())
                && t.chars().all(|c| c.is_ascii_alphanumeric());
            let pkg_ok = p.starts_with(|c: char| c.is_ascii_lowercase())
                && p.chars()
                    .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_');
            if !type_ok || !pkg_ok {
                return Err(bad());
            }
            return Ok((BaseDef::Nested(format!("{p}/msg/{t}")), shape, 0));
        }
    };
    Ok((BaseDef::Prim(prim), shape, 0))
}

fn nested(full: &str) -> BaseDef {
    BaseDef::Nested(full.to_string())
}

fn positive(s: &str) -> Option<u64> {
    s.trim().parse().ok().filter(|&n| n > 0)
}

/// Splits an array default `[a, "b,c", d]` into its element texts (quotes kept off).
pub fn split_array_default(text: &str) -> Option<Vec<String>> {
    let inner = text.trim().strip_prefix('[')?.strip_suffix(']')?.trim();
    let mut out = Vec::new();
    let mut chars = inner.chars().peekable();
    while chars.peek().is_some() {
        while chars.peek() == Some(&' ') {
            chars.next();
        }
        let mut item = String::new();
        match chars.peek().copied() {
            Some(q @ ('"' | '\'')) => {
                chars.next();
                let mut escaped = false;
                for c in chars.by_ref() {
                    match c {
                        '\\' if !escaped => escaped = true,
                        c if c == q && !escaped => break,
                        c => {
                            escaped = false;
                            item.push(c)
                        }
                    }
                }
                while chars.peek().is_some_and(|&c| c != ',') {
                    chars.next();
                }
            }
            _ => {
                while let Some(&c) = chars.peek() {
                    if c == ',' {
                        break;
                    }
                    item.push(c);
                    chars.next();
                }
                item = item.trim().to_string();
            }
        }
        chars.next(); // the comma
        out.push(item);
    }
    Some(out)
}

/// A scalar default or constant text without its quotes (strings) as rosidl reads it.
pub fn unquote(text: &str) -> String {
    let t = text.trim();
    for q in ['"', '\''] {
        if t.len() >= 2 && t.starts_with(q) && t.ends_with(q) {
            return t[1..t.len() - 1].replace(&format!("\\{q}"), &q.to_string());
        }
    }
    t.to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn field(d: &MsgDef, name: &str) -> FieldDef {
        d.fields.iter().find(|f| f.name == name).unwrap().clone()
    }

    #[test]
    fn every_form_of_a_field() {
        let text = "\
# file comment

std_msgs/Header header # trailing
Point position
int32 count 5
string<=10 label \"hi\"
wstring w
float64[3] xyz [1.0, 2.0, 3.0]
uint8[] data
byte[<=4] few
string<=5[<=2] names
time t
char c
\tint8\t\ttabbed
";
        let d = parse_msg("geometry_msgs", "Thing", text).unwrap();
        assert_eq!(d.name, "geometry_msgs/msg/Thing");
        let h = field(&d, "header");
        assert_eq!(h.base, BaseDef::Nested("std_msgs/msg/Header".into()));
        assert_eq!(
            field(&d, "position").base,
            BaseDef::Nested("geometry_msgs/msg/Point".into())
        );
        assert_eq!(field(&d, "count").default.as_deref(), Some("5"));
        let l = field(&d, "label");
        assert_eq!(
            (l.string_capacity, l.default.as_deref()),
            (10, Some("\"hi\""))
        );
        assert_eq!(field(&d, "w").base, BaseDef::Prim(Prim::WString));
        assert_eq!(field(&d, "xyz").shape, Shape::Array(3));
        assert_eq!(field(&d, "data").shape, Shape::Seq);
        assert_eq!(field(&d, "few").shape, Shape::BoundedSeq(4));
        assert_eq!(field(&d, "few").base, BaseDef::Prim(Prim::Byte));
        let n = field(&d, "names");
        assert_eq!((n.shape, n.string_capacity), (Shape::BoundedSeq(2), 5));
        assert_eq!(
            field(&d, "t").base,
            BaseDef::Nested("builtin_interfaces/msg/Time".into())
        );
        assert_eq!(field(&d, "c").base, BaseDef::Prim(Prim::U8));
        assert_eq!(field(&d, "tabbed").base, BaseDef::Prim(Prim::I8));
        assert_eq!(d.fields.len(), 12);
    }

    #[test]
    fn constants() {
        let d = parse_msg(
            "visualization_msgs",
            "Marker",
            "int32 ARROW=0\nint32 CUBE = 1 # c\nstring NAME=\"a b\"\nint32 type\n",
        )
        .unwrap();
        assert_eq!(d.constants.len(), 3);
        assert_eq!(d.constants[1].name, "CUBE");
        assert_eq!(d.constants[1].value, "1");
        assert_eq!(unquote(&d.constants[2].value), "a b");
        assert_eq!(d.fields.len(), 1);
    }

    #[test]
    fn empty_message_gets_rosidls_member() {
        let d = parse_msg("std_msgs", "Empty", "# nothing\n").unwrap();
        assert_eq!(d.fields[0].name, EMPTY_MEMBER);
    }

    #[test]
    fn services_give_four_structures() {
        let defs = parse_srv(
            "std_srvs",
            "SetBool",
            "bool data\n---\nbool success\nstring message\n",
        )
        .unwrap();
        let names: Vec<&str> = defs.iter().map(|d| d.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "std_srvs/srv/SetBool_Request",
                "std_srvs/srv/SetBool_Response",
                "std_srvs/srv/SetBool_Event",
                "std_srvs/srv/SetBool"
            ]
        );
        assert_eq!(defs[2].fields[1].shape, Shape::BoundedSeq(1));
        let empty = parse_srv("std_srvs", "Empty", "---\n").unwrap();
        assert_eq!(empty[0].fields[0].name, EMPTY_MEMBER);
        assert!(parse_srv("x", "Y", "int32 a\n").is_err());
    }

    #[test]
    fn actions_give_rosidls_thirteen_structures() {
        let text = "#goal\nint32 order\n---\nint32[] sequence\n---\n# feedback\nint32[] sequence\n";
        let defs = parse_action("test_msgs", "Fibonacci", text).unwrap();
        let names: Vec<&str> = defs.iter().map(|d| d.name.as_str()).collect();
        let p = "test_msgs/action/Fibonacci";
        let want: Vec<String> = [
            "_Goal",
            "_Result",
            "_Feedback",
            "_SendGoal_Request",
            "_SendGoal_Response",
            "_SendGoal_Event",
            "_SendGoal",
            "_GetResult_Request",
            "_GetResult_Response",
            "_GetResult_Event",
            "_GetResult",
            "_FeedbackMessage",
            "",
        ]
        .iter()
        .map(|s| format!("{p}{s}"))
        .collect();
        assert_eq!(names, want);
        let f = |d: &MsgDef| {
            d.fields
                .iter()
                .map(|f| (f.name.clone(), f.base.clone()))
                .collect::<Vec<_>>()
        };
        let nested = |t: &str| BaseDef::Nested(t.into());
        assert_eq!(
            f(&defs[3]),
            [
                ("goal_id".into(), nested(UUID)),
                ("goal".into(), nested(&format!("{p}_Goal")))
            ]
        );
        assert_eq!(
            f(&defs[8]),
            [
                ("status".into(), BaseDef::Prim(Prim::I8)),
                ("result".into(), nested(&format!("{p}_Result")))
            ]
        );
        assert_eq!(defs[12].fields.len(), 6);
        // The feedback is the third part: its comment line counts.
        let e = parse_action("p", "A", "---\n---\nint32 ok\nfloat65 bad\n").unwrap_err();
        assert_eq!((e.type_name.as_str(), e.line), ("p/action/A_Feedback", 4));
        let e = parse_action("p", "A", "int32 a\n---\n").unwrap_err();
        assert!(e.message.contains("goal, result, feedback"), "{e}");
    }

    #[test]
    fn errors_name_the_line() {
        let e = parse_msg("p", "M", "int32 a\nfloat65 b\n").unwrap_err();
        assert_eq!(e.line, 2);
        for bad in [
            "int32",
            "int32 Bad",
            "int32[0] a",
            "int32[x] a",
            "string<=0 a",
            "int32[ a",
            "pkg/lower a",
            "int32[3 a",
            "Header h 5",
            "int32[] X=1",
            "int32 a__b",
        ] {
            assert!(parse_msg("p", "M", bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn array_defaults() {
        assert_eq!(
            split_array_default("[1.0, 2, -3]").unwrap(),
            ["1.0", "2", "-3"]
        );
        assert_eq!(
            split_array_default("[\"a,b\", 'c', d]").unwrap(),
            ["a,b", "c", "d"]
        );
        assert_eq!(split_array_default("[]").unwrap(), Vec::<String>::new());
        assert_eq!(split_array_default("1"), None);
    }
}
