//! XML files as an owned element tree with `xi:include`s already expanded.
//!
//! C++ yarprobotinterface preprocesses the document the same way before reading it
//! (`PerformInclusions`): every `<xi:include href="..."/>` element is replaced by the root
//! element of the named file, whose own includes are resolved relative to its directory.
//! Each element keeps the file and line it came from, so errors can point at the source.
//!
//! An include with `enabled_by="a b"` is expanded only when yarprobotinterface runs
//! with one of those tags in `--enable_tags "(a ...)"` (or `enable_all`); one with
//! `disabled_by="c"` is dropped when `--disable_tags "(c ...)"` names it, as C++'s
//! `CheckIfIncludeSectionIsEnabled` decides ([`IncludeTags`]).
//!
//! Differences from C++ (which would hang or crash): include cycles and runaway nesting
//! are errors, and an `href` without a directory part resolves next to the including file.

use super::error::{Location, XmlError};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The XInclude namespace, as the robots-configuration files declare `xmlns:xi`.
pub const XINCLUDE_NS: &str = "http://www.w3.org/2001/XInclude";

/// Includes nested deeper than this are refused.
pub const MAX_INCLUDE_DEPTH: usize = 32;

/// At most this many files are read for one robot, so that files including each other
/// several times cannot multiply into an endless load (a whole iCub reads about 70).
pub const MAX_INCLUDED_FILES: usize = 4096;

/// The tags of the command line's `enable_tags` / `disable_tags`.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct IncludeTags {
    pub enable: BTreeSet<String>,
    pub disable: BTreeSet<String>,
}

impl IncludeTags {
    /// Whether an include with these `enabled_by` / `disabled_by` attributes (each a
    /// space-separated list) is expanded: without `enabled_by` it is, with it only when
    /// one of its tags (or `enable_all`) is enabled; any disabled tag drops it.
    pub fn enabled(&self, enabled_by: Option<&str>, disabled_by: Option<&str>) -> bool {
        let words = |s: Option<&str>| {
            s.unwrap_or("")
                .split_ascii_whitespace()
                .map(str::to_owned)
                .collect::<Vec<_>>()
        };
        let by = words(enabled_by);
        let on = by.is_empty()
            || self.enable.contains("enable_all")
            || by.iter().any(|t| self.enable.contains(t));
        on && !words(disabled_by).iter().any(|t| self.disable.contains(t))
    }
}

/// The include chain being expanded, the files read so far and the include tags.
#[derive(Default)]
struct Includes {
    stack: Vec<PathBuf>,
    files_read: usize,
    tags: IncludeTags,
}

/// One element: its name, attributes, condensed text and element children.
#[derive(Debug, Clone, PartialEq)]
pub struct Element {
    /// Local name; elements in a namespace other than none are named `{ns}name`.
    pub name: String,
    pub attributes: Vec<(String, String)>,
    /// The first child's text, whitespace condensed as TinyXML does (`None` when the
    /// element has no leading text child or the text is only whitespace).
    pub text: Option<String>,
    pub children: Vec<Element>,
    pub at: Location,
}

impl Element {
    /// The value of attribute `name`.
    pub fn attr(&self, name: &str) -> Option<&str> {
        self.attributes
            .iter()
            .find(|(k, _)| k == name)
            .map(|(_, v)| v.as_str())
    }
}

/// A loaded document: its root element and the DOCTYPE text, if any.
#[derive(Debug, Clone)]
pub struct Document {
    pub root: Element,
    /// The `<!DOCTYPE ...>` declaration of the top file, verbatim.
    pub doctype: Option<String>,
}

/// Loads `path` and every file it includes (as `tags` enable them).
pub fn load_file(path: &Path, tags: &IncludeTags) -> Result<Document, XmlError> {
    let text = read(path)?;
    let mut includes = Includes {
        stack: vec![canonical(path)],
        files_read: 1,
        tags: tags.clone(),
    };
    let name: Arc<str> = Arc::from(path.display().to_string());
    let dir = path.parent().unwrap_or(Path::new("")).to_path_buf();
    load_text(&text, &name, &dir, &mut includes)
}

/// Parses `text` (named `name` in errors); relative includes resolve against `base_dir`.
pub fn load_str(
    text: &str,
    name: &str,
    base_dir: &Path,
    tags: &IncludeTags,
) -> Result<Document, XmlError> {
    let name: Arc<str> = Arc::from(name);
    let mut includes = Includes {
        tags: tags.clone(),
        ..Includes::default()
    };
    load_text(text, &name, base_dir, &mut includes)
}

fn read(path: &Path) -> Result<String, XmlError> {
    std::fs::read_to_string(path).map_err(|source| XmlError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// An XML declaration after leading blank lines (some robots-configuration files start
/// with an empty line; TinyXML, which C++ uses, accepts them) is blanked out, keeping
/// every line and column where it was.
fn late_declaration_blanked(text: &str) -> std::borrow::Cow<'_, str> {
    let body = text.trim_start();
    if body.len() == text.len() || !body.starts_with("<?xml") {
        return std::borrow::Cow::Borrowed(text);
    }
    let start = text.len() - body.len();
    let Some(end) = body.find("?>").map(|e| start + e + 2) else {
        return std::borrow::Cow::Borrowed(text);
    };
    let blank: String = text[start..end]
        .chars()
        .map(|c| if c == '\n' { '\n' } else { ' ' })
        .collect();
    std::borrow::Cow::Owned(format!("{}{blank}{}", &text[..start], &text[end..]))
}

/// Comments blanked (newlines kept, so lines stay right), each ending at the first `-->`
/// as TinyXML (C++ yarprobotinterface's parser) ends them: robots' files comment out
/// blocks that hold comments of their own (`<!--group ...> <!-- ... --> </group-->`),
/// which a strict XML parser refuses for their `--`.
fn comments_blanked(text: &str) -> std::borrow::Cow<'_, str> {
    if !text.contains("<!--") {
        return std::borrow::Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(start) = rest.find("<!--") {
        out.push_str(&rest[..start]);
        let body = &rest[start..];
        let end = body[4..].find("-->").map_or(body.len(), |e| e + 7);
        out.extend(
            body[..end]
                .chars()
                .map(|c| if c == '\n' { '\n' } else { ' ' }),
        );
        rest = &body[end..];
    }
    out.push_str(rest);
    std::borrow::Cow::Owned(out)
}

fn canonical(path: &Path) -> PathBuf {
    std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf())
}

fn load_text(
    text: &str,
    name: &Arc<str>,
    dir: &Path,
    includes: &mut Includes,
) -> Result<Document, XmlError> {
    let opts = roxmltree::ParsingOptions {
        allow_dtd: true,
        ..Default::default()
    };
    let text = &late_declaration_blanked(text);
    let text = &comments_blanked(text);
    let doc =
        roxmltree::Document::parse_with_options(text, opts).map_err(|e| XmlError::Malformed {
            file: name.to_string(),
            line: e.pos().row,
            message: e.to_string(),
        })?;
    let root = convert(doc.root_element(), &doc, name, dir, includes)?;
    Ok(Document {
        root,
        doctype: doctype_of(text),
    })
}

/// The `<!DOCTYPE ...>` declaration before the root element, if present.
fn doctype_of(text: &str) -> Option<String> {
    let start = text.find("<!DOCTYPE")?;
    let end = start + text[start..].find('>')?;
    Some(text[start..=end].to_string())
}

fn convert(
    node: roxmltree::Node,
    doc: &roxmltree::Document,
    file: &Arc<str>,
    dir: &Path,
    includes: &mut Includes,
) -> Result<Element, XmlError> {
    let at = Location::new(file, doc.text_pos_at(node.range().start).row);
    let tag = node.tag_name();
    let name = match tag.namespace() {
        None => tag.name().to_string(),
        Some(ns) => format!("{{{ns}}}{}", tag.name()),
    };
    let attributes = node
        .attributes()
        .filter(|a| a.namespace().is_none())
        .map(|a| (a.name().to_string(), a.value().to_string()))
        .collect();
    let text = node
        .first_child()
        .filter(|c| c.is_text())
        .and_then(|c| c.text())
        .map(condense)
        .filter(|t| !t.is_empty());
    let mut children = Vec::new();
    for child in node.children().filter(|c| c.is_element()) {
        if is_include(&child) {
            let on = includes.tags.enabled(
                child.attribute("enabled_by"),
                child.attribute("disabled_by"),
            );
            if on {
                children.push(include(&child, doc, file, dir, includes)?);
            }
        } else {
            children.push(convert(child, doc, file, dir, includes)?);
        }
    }
    Ok(Element {
        name,
        attributes,
        text,
        children,
        at,
    })
}

fn is_include(node: &roxmltree::Node) -> bool {
    node.tag_name().namespace() == Some(XINCLUDE_NS) && node.tag_name().name() == "include"
}

/// The root element of the file an `xi:include` names, its own includes expanded.
fn include(
    node: &roxmltree::Node,
    doc: &roxmltree::Document,
    file: &Arc<str>,
    dir: &Path,
    includes: &mut Includes,
) -> Result<Element, XmlError> {
    let at = Location::new(file, doc.text_pos_at(node.range().start).row);
    let href = node
        .attribute("href")
        .ok_or_else(|| XmlError::syntax(&at, "xi:include without an \"href\" attribute"))?;
    let path = dir.join(href);
    let key = canonical(&path);
    if includes.stack.contains(&key) {
        return Err(XmlError::IncludeCycle { at, path });
    }
    if includes.stack.len() >= MAX_INCLUDE_DEPTH {
        return Err(XmlError::IncludeTooDeep {
            at,
            limit: MAX_INCLUDE_DEPTH,
        });
    }
    includes.files_read += 1;
    if includes.files_read > MAX_INCLUDED_FILES {
        return Err(XmlError::syntax(
            &at,
            format!("more than {MAX_INCLUDED_FILES} files included"),
        ));
    }
    let text = std::fs::read_to_string(&path)
        .map_err(|e| XmlError::syntax(&at, format!("cannot include {}: {e}", path.display())))?;
    let name: Arc<str> = Arc::from(path.display().to_string());
    let sub_dir = path.parent().unwrap_or(Path::new("")).to_path_buf();
    includes.stack.push(key);
    let included = load_text(&text, &name, &sub_dir, includes);
    includes.stack.pop();
    Ok(included?.root)
}

/// TinyXML's whitespace condensing: leading and trailing whitespace dropped, inner runs
/// become one space.
pub fn condense(text: &str) -> String {
    text.split_ascii_whitespace().collect::<Vec<_>>().join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_declaration_after_blank_lines_is_accepted_and_lines_kept() {
        // ergoCubSN001's hardware/FT/*-strain.xml start with an empty line.
        let doc = load_str(
            "\n<?xml version=\"1.0\" encoding=\"UTF-8\" ?>\n<robot name=\"r\">\n  <x/>\n</robot>\n",
            "t.xml",
            Path::new("."),
            &IncludeTags::default(),
        )
        .unwrap();
        assert_eq!(doc.root.at.line, 3);
        let e = load_str(
            "\n<?xml version=\"1.0\"?>\n<robot>\n<a></b>\n</robot>",
            "t.xml",
            Path::new("."),
            &IncludeTags::default(),
        )
        .unwrap_err();
        assert!(e.to_string().contains(":4"), "{e}");
    }

    #[test]
    fn a_commented_block_with_comments_inside_ends_at_the_first_close_as_tinyxml() {
        // ergoCubSN001's hardware/skin/*-skinSpec.xml comment out a group that holds
        // comments of its own.
        let doc = load_str(
            "<robot name=\"r\">\n<!--group name=\"g\">\n <!-- inner, -- unclosed\n >\n <p/>\n</group-->\n<x/>\n</robot>\n",
            "t.xml",
            Path::new("."),
            &IncludeTags::default(),
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let names: Vec<&str> = doc.root.children.iter().map(|c| c.name.as_str()).collect();
        assert!(names.contains(&"x") && !names.contains(&"p"), "{names:?}");
        let e = load_str(
            "<robot>\n<!-- a\n b -->\n<a></b>\n</robot>",
            "t.xml",
            Path::new("."),
            &IncludeTags::default(),
        )
        .unwrap_err();
        assert!(e.to_string().contains(":4"), "lines kept: {e}");
    }

    #[test]
    fn include_tags_decide_as_cpp() {
        let tags = |e: &[&str], d: &[&str]| IncludeTags {
            enable: e.iter().map(|s| s.to_string()).collect(),
            disable: d.iter().map(|s| s.to_string()).collect(),
        };
        let none = tags(&[], &[]);
        assert!(none.enabled(None, None));
        assert!(!none.enabled(Some("enable_ros2"), None));
        assert!(none.enabled(None, Some("disable_left_hand")));
        let ros = tags(&["enable_ros2"], &["disable_left_hand"]);
        assert!(ros.enabled(Some("enable_ros2"), None));
        assert!(ros.enabled(Some("other enable_ros2"), None));
        assert!(!ros.enabled(Some("enable_ros2"), Some("disable_left_hand")));
        assert!(!ros.enabled(None, Some("x disable_left_hand")));
        assert!(tags(&["enable_all"], &[]).enabled(Some("anything"), None));
    }

    #[test]
    fn condenses_like_tinyxml() {
        assert_eq!(condense("  1 \n\t 2   3 \n"), "1 2 3");
        assert_eq!(condense(" \n "), "");
    }

    #[test]
    fn records_lines_and_text() {
        let doc = load_str(
            "<robot name=\"r\">\n  <device name=\"d\" type=\"t\">\n    <param name=\"p\">  a\n b </param>\n  </device>\n</robot>\n",
            "mem.xml",
            Path::new("."),
            &IncludeTags::default(),
        )
        .unwrap();
        let dev = &doc.root.children[0];
        assert_eq!(dev.at.line, 2);
        assert_eq!(dev.children[0].text.as_deref(), Some("a b"));
        assert_eq!(dev.children[0].at.to_string(), "mem.xml:3");
    }

    fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
        let p = dir.join(name);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(&p, text).unwrap();
        p
    }

    const XI: &str = "xmlns:xi=\"http://www.w3.org/2001/XInclude\"";

    #[test]
    fn includes_resolve_relative_to_the_including_file() {
        let dir = tempfile::tempdir().unwrap();
        let top = write(
            dir.path(),
            "top.xml",
            &format!("<robot {XI} name=\"r\">\n<xi:include href=\"sub/a.xml\"/>\n</robot>"),
        );
        write(
            dir.path(),
            "sub/a.xml",
            &format!(
                "<device {XI} name=\"a\" type=\"t\">\n  <xi:include href=\"../p.xml\"/>\n</device>"
            ),
        );
        write(
            dir.path(),
            "p.xml",
            "<params><param name=\"x\">1</param></params>",
        );
        let doc = load_file(&top, &IncludeTags::default()).unwrap();
        let dev = &doc.root.children[0];
        assert_eq!(dev.attr("name"), Some("a"));
        assert!(dev.at.file.ends_with("sub/a.xml"));
        assert_eq!(dev.children[0].name, "params");
        assert_eq!(dev.children[0].children[0].text.as_deref(), Some("1"));
    }

    #[test]
    fn include_errors_name_the_including_file_and_line() {
        let dir = tempfile::tempdir().unwrap();
        let top = write(
            dir.path(),
            "top.xml",
            &format!("<robot {XI} name=\"r\">\n\n<xi:include href=\"missing.xml\"/>\n</robot>"),
        );
        let e = load_file(&top, &IncludeTags::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("top.xml:3") && e.contains("missing.xml"), "{e}");

        let cyc = write(
            dir.path(),
            "cycle.xml",
            &format!("<robot {XI} name=\"r\"><xi:include href=\"cycle.xml\"/></robot>"),
        );
        let e = load_file(&cyc, &IncludeTags::default()).unwrap_err();
        assert!(matches!(e, XmlError::IncludeCycle { .. }), "{e}");

        let bad = write(
            dir.path(),
            "bad.xml",
            &format!("<robot {XI}><xi:include/></robot>"),
        );
        let e = load_file(&bad, &IncludeTags::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("href"), "{e}");
    }

    #[test]
    fn repeated_includes_are_bounded() {
        // each level includes the next one twice: 2^20 expansions without a budget
        let dir = tempfile::tempdir().unwrap();
        for i in 0..20 {
            let next = format!("<xi:include href=\"f{}.xml\"/>", i + 1);
            write(
                dir.path(),
                &format!("f{i}.xml"),
                &format!("<params {XI}>{next}{next}</params>"),
            );
        }
        write(dir.path(), "f20.xml", "<params/>");
        let e = load_file(&dir.path().join("f0.xml"), &IncludeTags::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("files included"), "{e}");
    }

    #[test]
    fn malformed_xml_names_file_and_line() {
        let err = load_str(
            "<robot>\n<device>\n</robot>",
            "bad.xml",
            Path::new("."),
            &IncludeTags::default(),
        )
        .unwrap_err();
        let msg = err.to_string();
        assert!(msg.starts_with("bad.xml:"), "{msg}");
    }
}
