//! ROS 2 `.idl` interface definitions (the OMG IDL subset rosidl uses), for packages that
//! ship no `.msg`/`.srv` (pure).
//!
//! Read: `module`s, `struct`s with members `TYPE NAME;` or `TYPE NAME[N];`, `typedef TYPE
//! NAME[N];`, constants in a `<Name>_Constants` module, `@default (value=...)`
//! annotations (others, such as `@verbatim`, are skipped), `//` and `/* */` comments and
//! `#include` lines. Types: `boolean octet int8..uint64 short long "long long"
//! unsigned... float double string wstring string<N> sequence<T> sequence<T, N>` and
//! scoped names `pkg::msg::Type`. A service's `<Name>_Request` and `<Name>_Response` also
//! yield its `_Event` and service description, as from a `.srv`.

use crate::msgdef::{service_structures, BaseDef, ConstDef, FieldDef, MsgDef};
use crate::types::{Prim, Shape};
use std::collections::HashMap;

#[derive(Debug, Clone, PartialEq)]
enum Tok {
    Ident(String),
    Num(String),
    Str(String),
    Punct(&'static str),
}

/// Why an `.idl` file cannot be used.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct IdlError(pub String);

fn tokenize(text: &str) -> Result<Vec<Tok>, IdlError> {
    let b: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    let mut line_start = true;
    while i < b.len() {
        let c = b[i];
        if c == '\n' {
            line_start = true;
            i += 1;
            continue;
        }
        if c.is_whitespace() {
            i += 1;
            continue;
        }
        if line_start && c == '#' {
            while i < b.len() && b[i] != '\n' {
                i += 1;
            }
            continue;
        }
        line_start = false;
        if c == '/' && b.get(i + 1) == Some(&'/') {
            while i < b.len() && b[i] != '\n' {
                i += 1;
            }
        } else if c == '/' && b.get(i + 1) == Some(&'*') {
            i += 2;
            while i + 1 < b.len() && !(b[i] == '*' && b[i + 1] == '/') {
                i += 1;
            }
            i += 2;
        } else if c == '"' {
            let mut s = String::new();
            i += 1;
            while i < b.len() && b[i] != '"' {
                if b[i] == '\\' && i + 1 < b.len() {
                    i += 1;
                }
                s.push(b[i]);
                i += 1;
            }
            if i >= b.len() {
                return Err(IdlError("unterminated string".into()));
            }
            i += 1;
            out.push(Tok::Str(s));
        } else if c.is_ascii_alphabetic() || c == '_' {
            let start = i;
            while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == '_') {
                i += 1;
            }
            out.push(Tok::Ident(b[start..i].iter().collect()));
        } else if c.is_ascii_digit()
            || ((c == '-' || c == '+' || c == '.')
                && b.get(i + 1).is_some_and(|d| d.is_ascii_digit()))
        {
            let start = i;
            i += 1;
            while i < b.len()
                && (b[i].is_ascii_alphanumeric()
                    || b[i] == '.'
                    || ((b[i] == '-' || b[i] == '+') && matches!(b[i - 1], 'e' | 'E')))
            {
                i += 1;
            }
            out.push(Tok::Num(b[start..i].iter().collect()));
        } else if c == ':' && b.get(i + 1) == Some(&':') {
            out.push(Tok::Punct("::"));
            i += 2;
        } else {
            let p = match c {
                '{' => "{",
                '}' => "}",
                ';' => ";",
                '<' => "<",
                '>' => ">",
                ',' => ",",
                '[' => "[",
                ']' => "]",
                '(' => "(",
                ')' => ")",
                '=' => "=",
                '@' => "@",
                _ => return Err(IdlError(format!("unexpected character `{c}`"))),
            };
            out.push(Tok::Punct(p));
            i += 1;
        }
    }
    Ok(out)
}

/// A member type before scoping: a primitive, a (scoped) name, with its shape.
#[derive(Debug, Clone)]
struct TypeSpec {
    base: Result<Prim, Vec<String>>,
    shape: Shape,
    string_capacity: u64,
}

struct Parser {
    toks: Vec<Tok>,
    pos: usize,
    /// The module path we are in.
    scope: Vec<String>,
    typedefs: HashMap<String, TypeSpec>,
    structs: Vec<MsgDef>,
    /// Constants by the struct they belong to (`pkg/msg/Name`).
    constants: HashMap<String, Vec<ConstDef>>,
}

fn err<T>(m: impl Into<String>) -> Result<T, IdlError> {
    Err(IdlError(m.into()))
}

impl Parser {
    fn peek(&self) -> Option<&Tok> {
        self.toks.get(self.pos)
    }
    fn next(&mut self) -> Result<Tok, IdlError> {
        let t = self.toks.get(self.pos).cloned();
        self.pos += 1;
        t.ok_or_else(|| IdlError("unexpected end of file".into()))
    }
    fn is(&self, p: &str) -> bool {
        matches!(self.peek(), Some(Tok::Punct(q)) if *q == p)
    }
    fn expect(&mut self, p: &str) -> Result<(), IdlError> {
        match self.next()? {
            Tok::Punct(q) if q == p => Ok(()),
            other => err(format!("expected `{p}`, found {other:?}")),
        }
    }
    fn ident(&mut self) -> Result<String, IdlError> {
        match self.next()? {
            Tok::Ident(s) => Ok(s),
            other => err(format!("expected a name, found {other:?}")),
        }
    }
    fn number(&mut self) -> Result<u64, IdlError> {
        match self.next()? {
            Tok::Num(n) => n
                .parse()
                .ok()
                .filter(|&n| n > 0)
                .ok_or_else(|| IdlError(format!("`{n}` is not a size"))),
            other => err(format!("expected a number, found {other:?}")),
        }
    }

    /// Definitions until `}` (or the end of the file at the top level).
    fn definitions(&mut self) -> Result<(), IdlError> {
        loop {
            match self.peek() {
                None => return Ok(()),
                Some(Tok::Punct("}")) => return Ok(()),
                Some(Tok::Punct("@")) => {
                    self.annotation()?;
                }
                Some(Tok::Ident(k)) if k == "module" => {
                    self.pos += 1;
                    let name = self.ident()?;
                    self.expect("{")?;
                    self.scope.push(name);
                    self.definitions()?;
                    self.scope.pop();
                    self.expect("}")?;
                    self.expect(";")?;
                }
                Some(Tok::Ident(k)) if k == "struct" => {
                    self.pos += 1;
                    self.structure()?;
                }
                Some(Tok::Ident(k)) if k == "typedef" => {
                    self.pos += 1;
                    let mut spec = self.type_spec()?;
                    let name = self.ident()?;
                    if self.is("[") {
                        self.pos += 1;
                        spec.shape = Shape::Array(self.number()?);
                        self.expect("]")?;
                    }
                    self.expect(";")?;
                    self.typedefs.insert(name, spec);
                }
                Some(Tok::Ident(k)) if k == "const" => {
                    self.pos += 1;
                    self.constant()?;
                }
                Some(other) => return err(format!("unexpected {other:?}")),
            }
        }
    }

    /// `@name` or `@name (...)`; returns the `value` of `@default`.
    fn annotation(&mut self) -> Result<Option<String>, IdlError> {
        self.expect("@")?;
        let name = self.ident()?;
        if !self.is("(") {
            return Ok(None);
        }
        self.pos += 1;
        let mut depth = 1;
        let mut text = Vec::new();
        while depth > 0 {
            let t = self.next()?;
            match &t {
                Tok::Punct("(") => depth += 1,
                Tok::Punct(")") => depth -= 1,
                _ => {}
            }
            if depth > 0 {
                text.push(t);
            }
        }
        if name != "default" {
            return Ok(None);
        }
        // value=<tokens>
        let value = match text.as_slice() {
            [Tok::Ident(v), Tok::Punct("="), rest @ ..] if v == "value" => rest,
            _ => return Ok(None),
        };
        Ok(Some(tokens_text(value)))
    }

    fn structure(&mut self) -> Result<(), IdlError> {
        let name = self.ident()?;
        self.expect("{")?;
        let full = self.full_name(&name)?;
        let mut fields = Vec::new();
        let mut default = None;
        while !self.is("}") {
            if self.is("@") {
                if let Some(d) = self.annotation()? {
                    default = Some(d);
                }
                continue;
            }
            let spec = self.type_spec()?;
            let fname = self.ident()?;
            let mut shape = spec.shape;
            if self.is("[") {
                self.pos += 1;
                shape = Shape::Array(self.number()?);
                self.expect("]")?;
            }
            self.expect(";")?;
            let base = match spec.base {
                Ok(p) => BaseDef::Prim(p),
                Err(path) => BaseDef::Nested(self.nested_name(&path)?),
            };
            fields.push(FieldDef {
                name: fname,
                base,
                shape,
                string_capacity: spec.string_capacity,
                default: default.take(),
            });
        }
        self.expect("}")?;
        self.expect(";")?;
        self.structs.push(MsgDef {
            name: full,
            fields,
            constants: Vec::new(),
        });
        Ok(())
    }

    fn constant(&mut self) -> Result<(), IdlError> {
        let spec = self.type_spec()?;
        let name = self.ident()?;
        self.expect("=")?;
        let mut value = Vec::new();
        while !self.is(";") {
            value.push(self.next()?);
        }
        self.expect(";")?;
        let Ok(prim) = spec.base else {
            return err(format!("constant {name} is not of a primitive type"));
        };
        // Constants of `Foo` live in the module `Foo_Constants` beside it.
        let owner = self
            .scope
            .last()
            .and_then(|m| m.strip_suffix("_Constants"))
            .map(str::to_string)
            .ok_or_else(|| IdlError(format!("constant {name} outside a _Constants module")))?;
        let parent = &self.scope[..self.scope.len() - 1];
        let full = scoped(parent, &owner)?;
        self.constants.entry(full).or_default().push(ConstDef {
            name,
            prim,
            value: tokens_text(&value),
        });
        Ok(())
    }

    fn full_name(&self, name: &str) -> Result<String, IdlError> {
        scoped(&self.scope, name)
    }

    /// A member's nested type: `pkg::msg::T` as `pkg/msg/T`, a typedef's or a name of
    /// this module.
    fn nested_name(&self, path: &[String]) -> Result<String, IdlError> {
        match path {
            [p, k, t] => Ok(format!("{p}/{k}/{t}")),
            [t] => self.full_name(t),
            _ => err(format!("type `{}` is not pkg::msg::Type", path.join("::"))),
        }
    }

    fn type_spec(&mut self) -> Result<TypeSpec, IdlError> {
        let single = |p| TypeSpec {
            base: Ok(p),
            shape: Shape::Single,
            string_capacity: 0,
        };
        let first = self.ident()?;
        let prim = match first.as_str() {
            "sequence" => {
                self.expect("<")?;
                let inner = self.type_spec()?;
                let shape = if self.is(",") {
                    self.pos += 1;
                    Shape::BoundedSeq(self.number()?)
                } else {
                    Shape::Seq
                };
                self.expect(">")?;
                if inner.shape != Shape::Single {
                    return err("a sequence of arrays is not a ROS type");
                }
                return Ok(TypeSpec { shape, ..inner });
            }
            "string" | "wstring" => {
                let p = if first == "string" {
                    Prim::String
                } else {
                    Prim::WString
                };
                let mut spec = single(p);
                if self.is("<") {
                    self.pos += 1;
                    spec.string_capacity = self.number()?;
                    self.expect(">")?;
                }
                return Ok(spec);
            }
            "boolean" => Prim::Bool,
            "octet" => Prim::Byte,
            "int8" => Prim::I8,
            "uint8" => Prim::U8,
            "int16" | "short" => Prim::I16,
            "uint16" => Prim::U16,
            "int32" => Prim::I32,
            "uint32" => Prim::U32,
            "int64" => Prim::I64,
            "uint64" => Prim::U64,
            "float" => Prim::F32,
            "double" => Prim::F64,
            "long" => {
                if matches!(self.peek(), Some(Tok::Ident(n)) if n == "long") {
                    self.pos += 1;
                    Prim::I64
                } else if matches!(self.peek(), Some(Tok::Ident(n)) if n == "double") {
                    return err("long double is not supported");
                } else {
                    Prim::I32
                }
            }
            "unsigned" => match self.ident()?.as_str() {
                "short" => Prim::U16,
                "long" => {
                    if matches!(self.peek(), Some(Tok::Ident(n)) if n == "long") {
                        self.pos += 1;
                        Prim::U64
                    } else {
                        Prim::U32
                    }
                }
                other => return err(format!("unsigned {other} is not a type")),
            },
            "char" | "wchar" => return err(format!("`{first}` is not supported")),
            _ => {
                let mut path = vec![first];
                while self.is("::") {
                    self.pos += 1;
                    path.push(self.ident()?);
                }
                if let [one] = path.as_slice() {
                    if let Some(t) = self.typedefs.get(one) {
                        return Ok(t.clone());
                    }
                }
                return Ok(TypeSpec {
                    base: Err(path),
                    shape: Shape::Single,
                    string_capacity: 0,
                });
            }
        };
        Ok(single(prim))
    }
}

fn scoped(scope: &[String], name: &str) -> Result<String, IdlError> {
    match scope {
        [p, k] => Ok(format!("{p}/{k}/{name}")),
        _ => err(format!(
            "`{name}` is in module {}, not pkg::msg or pkg::srv",
            scope.join("::")
        )),
    }
}

/// Tokens back to text (`(1, 2)` as `[1, 2]`, the `.msg` form of array defaults).
fn tokens_text(toks: &[Tok]) -> String {
    let mut s = String::new();
    for t in toks {
        match t {
            Tok::Ident(x) | Tok::Num(x) => s.push_str(x),
            Tok::Str(x) => {
                s.push('"');
                s.push_str(&x.replace('"', "\\\""));
                s.push('"');
            }
            Tok::Punct("(") => s.push('['),
            Tok::Punct(")") => s.push(']'),
            Tok::Punct(",") => s.push_str(", "),
            Tok::Punct(p) => s.push_str(p),
        }
    }
    s
}

/// Every structure an `.idl` file defines (a service's with its event and description).
pub fn parse(text: &str) -> Result<Vec<MsgDef>, IdlError> {
    let mut p = Parser {
        toks: tokenize(text)?,
        pos: 0,
        scope: Vec::new(),
        typedefs: HashMap::new(),
        structs: Vec::new(),
        constants: HashMap::new(),
    };
    p.definitions()?;
    if p.pos < p.toks.len() {
        return err("unbalanced `}`");
    }
    let mut out = Vec::new();
    let mut structs = std::mem::take(&mut p.structs);
    for s in &mut structs {
        if let Some(c) = p.constants.remove(&s.name) {
            s.constants = c;
        }
        if s.fields.is_empty() {
            s.fields.push(FieldDef {
                name: crate::msgdef::EMPTY_MEMBER.into(),
                base: BaseDef::Prim(Prim::U8),
                shape: Shape::Single,
                string_capacity: 0,
                default: None,
            });
        }
    }
    // Services: a `_Request` and `_Response` pair under `pkg::srv`.
    let mut rest = Vec::new();
    let mut requests = Vec::new();
    for s in structs {
        if s.name.contains("/srv/") && s.name.ends_with("_Request") {
            requests.push(s);
        } else {
            rest.push(s);
        }
    }
    for req in requests {
        let full = req.name.trim_end_matches("_Request").to_string();
        let Some(i) = rest
            .iter()
            .position(|r| r.name == format!("{full}_Response"))
        else {
            return err(format!("{full}: a _Request without its _Response"));
        };
        let resp = rest.remove(i);
        out.extend(service_structures(&full, req, resp));
    }
    out.extend(rest);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    const IDL: &str = r#"
// generated
#include "std_msgs/msg/Header.idl"
module demo_pkg {
  module msg {
    typedef double double__9[9];
    module Thing_Constants {
      const uint8 MODE_A = 1;
      const string NAME = "x y";
    };
    @verbatim (language="comment", text=
      "A thing (with parentheses)." "\n")
    struct Thing {
      std_msgs::msg::Header header;
      @default (value=5)
      int32 count;
      double__9 covariance;
      sequence<Part> parts;
      sequence<double, 4> few;
      string<10> label;
      unsigned long long big;
      long small;
      octet raw[16];
      /* block
         comment */
      @default (value=FALSE)
      boolean flag;
    };
    struct Part {
      float x;
    };
    struct Nothing {
    };
  };
};
"#;

    #[test]
    fn structs_typedefs_constants_defaults() {
        let defs = parse(IDL).unwrap();
        let t = defs
            .iter()
            .find(|d| d.name == "demo_pkg/msg/Thing")
            .unwrap();
        let f = |n: &str| t.fields.iter().find(|f| f.name == n).unwrap().clone();
        assert_eq!(
            f("header").base,
            BaseDef::Nested("std_msgs/msg/Header".into())
        );
        assert_eq!(f("count").default.as_deref(), Some("5"));
        assert_eq!(f("covariance").shape, Shape::Array(9));
        assert_eq!(f("covariance").base, BaseDef::Prim(Prim::F64));
        assert_eq!(f("parts").base, BaseDef::Nested("demo_pkg/msg/Part".into()));
        assert_eq!(f("parts").shape, Shape::Seq);
        assert_eq!(f("few").shape, Shape::BoundedSeq(4));
        assert_eq!(f("label").string_capacity, 10);
        assert_eq!(f("big").base, BaseDef::Prim(Prim::U64));
        assert_eq!(f("small").base, BaseDef::Prim(Prim::I32));
        assert_eq!(
            (f("raw").base, f("raw").shape),
            (BaseDef::Prim(Prim::Byte), Shape::Array(16))
        );
        assert_eq!(f("flag").default.as_deref(), Some("FALSE"));
        assert_eq!(t.constants.len(), 2);
        assert_eq!(t.constants[1].value, "\"x y\"");
        let n = defs
            .iter()
            .find(|d| d.name == "demo_pkg/msg/Nothing")
            .unwrap();
        assert_eq!(n.fields[0].name, crate::msgdef::EMPTY_MEMBER);
    }

    #[test]
    fn services() {
        let defs = parse(
            "module s { module srv { struct Go_Request { int32 a; }; \
             struct Go_Response { boolean ok; }; }; };",
        )
        .unwrap();
        let names: Vec<&str> = defs.iter().map(|d| d.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "s/srv/Go_Request",
                "s/srv/Go_Response",
                "s/srv/Go_Event",
                "s/srv/Go"
            ]
        );
    }

    #[test]
    fn errors() {
        for bad in [
            "module a { struct X { int32 a; }; };",
            "module a { module msg { struct X { char c; }; }; };",
            "module a { module msg { struct X { int32 a }; }; };",
            "module a { module msg { struct X { int32 a; }; };",
            "module a { module msg { struct X { sequence<int32 a; }; }; };",
            "}",
            "\"open",
            "module a { module srv { struct X_Request { int32 a; }; }; };",
        ] {
            assert!(parse(bad).is_err(), "{bad}");
        }
    }
}
