//! yarpmanager application XML, read into the same document a TOML config gives.
//!
//! Understood: `<application>` with `<name>`, `<description>`; `<module>` with `<name>`
//! (the program), `<parameters>` (split like a shell command line), `<workdir>`,
//! `<environment>` (`A=1 B=2`), `<node>` (only `localhost` / empty: this launcher runs
//! modules on this machine), `<prefix>` (kept in the module's log name only),
//! `<dependencies><port timeout="s">/p</port></dependencies>` (wait for those ports before
//! starting), `<ensure><wait>s</wait></ensure>` (delay after start); `<connection>` with
//! `<from>`, `<to>`, `<protocol>`. Other elements are ignored. Modules start in file order,
//! each after the previous one, as yarpmanager's "run all" does.

use roxmltree::{Document, Node};

fn child<'a>(n: Node<'a, 'a>, tag: &str) -> Option<Node<'a, 'a>> {
    n.children().find(|c| c.has_tag_name(tag))
}

fn text_of(n: Node, tag: &str) -> Option<String> {
    child(n, tag)
        .and_then(|c| c.text())
        .map(|t| t.trim().to_string())
        .filter(|t| !t.is_empty())
}

/// Splits a command line on whitespace, honouring '…' and "…" quoting.
pub fn split_args(s: &str) -> Result<Vec<String>, String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let mut in_word = false;
    let mut quote: Option<char> = None;
    for c in s.chars() {
        match quote {
            Some(q) if c == q => quote = None,
            Some(_) => cur.push(c),
            None if c == '"' || c == '\'' => {
                quote = Some(c);
                in_word = true;
            }
            None if c.is_whitespace() => {
                if in_word {
                    out.push(std::mem::take(&mut cur));
                    in_word = false;
                }
            }
            None => {
                cur.push(c);
                in_word = true;
            }
        }
    }
    if quote.is_some() {
        return Err(format!("unclosed quote in {s:?}"));
    }
    if in_word {
        out.push(cur);
    }
    Ok(out)
}

/// Converts application XML into a TOML document with the launch-config layout.
pub fn to_document(xml: &str) -> Result<toml::Table, String> {
    let doc = Document::parse(xml).map_err(|e| format!("XML: {e}"))?;
    let root = doc.root_element();
    if !root.has_tag_name("application") {
        return Err(format!(
            "root element is <{}>, expected <application>",
            root.tag_name().name()
        ));
    }
    let mut out = toml::Table::new();
    out.insert(
        "name".into(),
        text_of(root, "name").unwrap_or_default().into(),
    );
    if let Some(d) = text_of(root, "description") {
        out.insert("description".into(), d.into());
    }
    let mut modules = Vec::new();
    let mut previous: Option<String> = None;
    for (i, m) in root
        .children()
        .filter(|c| c.has_tag_name("module"))
        .enumerate()
    {
        let program =
            text_of(m, "name").ok_or_else(|| format!("module #{} has no <name>", i + 1))?;
        if let Some(node) = text_of(m, "node") {
            if !matches!(node.as_str(), "localhost" | "127.0.0.1" | "console") {
                tracing::warn!("module {program}: <node>{node}</node> ignored, running locally");
            }
        }
        let base = std::path::Path::new(&program)
            .file_name()
            .map(|f| f.to_string_lossy().into_owned())
            .unwrap_or_else(|| program.clone());
        let label = match text_of(m, "prefix") {
            Some(p) => format!("{}{}", base, p.replace('/', "_")),
            None => base,
        };
        let name = format!("{}-{}", i + 1, label);
        let mut t = toml::Table::new();
        t.insert("name".into(), name.clone().into());
        t.insert("program".into(), program.clone().into());
        let params = text_of(m, "parameters").unwrap_or_default();
        let args = split_args(&params).map_err(|e| format!("module {program}: {e}"))?;
        t.insert(
            "args".into(),
            toml::Value::Array(args.into_iter().map(Into::into).collect()),
        );
        if let Some(w) = text_of(m, "workdir") {
            t.insert("cwd".into(), w.into());
        }
        if let Some(env) = text_of(m, "environment") {
            let mut e = toml::Table::new();
            for kv in split_args(&env).map_err(|e| format!("module {program}: {e}"))? {
                let (k, v) = kv.split_once('=').ok_or_else(|| {
                    format!("module {program}: environment {kv:?} is not KEY=VALUE")
                })?;
                e.insert(k.into(), v.into());
            }
            t.insert("env".into(), e.into());
        }
        if let Some(deps) = child(m, "dependencies") {
            let ports: Vec<toml::Value> = deps
                .children()
                .filter(|c| c.has_tag_name("port"))
                .filter_map(|p| p.text().map(|t| t.trim().to_string().into()))
                .collect();
            t.insert("wait_ports".into(), toml::Value::Array(ports));
        }
        if let Some(wait) = child(m, "ensure").and_then(|e| text_of(e, "wait")) {
            let secs: f64 = wait
                .parse()
                .map_err(|_| format!("module {program}: <wait>{wait}</wait> is not seconds"))?;
            let mut r = toml::Table::new();
            r.insert("delay".into(), secs.into());
            t.insert("ready".into(), r.into());
        }
        if let Some(p) = previous.replace(name) {
            t.insert("after".into(), toml::Value::Array(vec![p.into()]));
        }
        modules.push(toml::Value::Table(t));
    }
    out.insert("module".into(), toml::Value::Array(modules));
    let mut conns = Vec::new();
    for c in root.children().filter(|c| c.has_tag_name("connection")) {
        let from = text_of(c, "from").ok_or("a <connection> has no <from>")?;
        let to = text_of(c, "to").ok_or("a <connection> has no <to>")?;
        let mut t = toml::Table::new();
        t.insert("from".into(), from.into());
        t.insert("to".into(), to.into());
        if let Some(p) = text_of(c, "protocol") {
            t.insert("carrier".into(), p.into());
        }
        conns.push(toml::Value::Table(t));
    }
    out.insert("connection".into(), toml::Value::Array(conns));
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::LaunchConfig;
    use std::path::Path;

    const APP: &str = r#"<application>
  <name>Fake camera</name>
  <module>
    <name>yarpdev</name>
    <parameters>--device fakeFrameGrabber --name /grabber --title "a b"</parameters>
    <node>localhost</node>
    <environment>A=1 B=two</environment>
  </module>
  <module>
    <name>yarp</name>
    <parameters>read /view</parameters>
    <prefix>/demo</prefix>
    <dependencies><port timeout="5">/grabber</port></dependencies>
    <ensure><wait>0.5</wait></ensure>
  </module>
  <connection><from>/grabber</from><to>/view</to><protocol>udp</protocol></connection>
</application>"#;

    #[test]
    fn reads_an_application() {
        let doc = to_document(APP).unwrap();
        let c = LaunchConfig::from_document(doc, Path::new("a.xml"), Path::new("/"), &[]).unwrap();
        assert_eq!(c.name, "Fake camera");
        assert_eq!(c.modules.len(), 2);
        assert_eq!(c.modules[0].name, "1-yarpdev");
        assert_eq!(
            c.modules[0].args,
            [
                "--device",
                "fakeFrameGrabber",
                "--name",
                "/grabber",
                "--title",
                "a b"
            ]
        );
        assert_eq!(c.modules[0].env["B"], "two");
        assert_eq!(c.modules[1].name, "2-yarp_demo");
        assert_eq!(c.modules[1].after, ["1-yarpdev"]);
        assert_eq!(c.modules[1].wait_ports, ["/grabber"]);
        assert_eq!(c.connections[0].carrier.as_deref(), Some("udp"));
    }

    #[test]
    fn bad_xml_is_an_error() {
        assert!(to_document("<application>").unwrap_err().starts_with("XML"));
        assert!(to_document("<app/>")
            .unwrap_err()
            .contains("expected <application>"));
        assert!(to_document("<application><module/></application>")
            .unwrap_err()
            .contains("no <name>"));
        assert!(split_args("a 'b").is_err());
        assert_eq!(split_args(" a  'b c'd \"\" ").unwrap(), ["a", "b cd", ""]);
    }
}
