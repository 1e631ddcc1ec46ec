//! XML files as an owned element tree with `xi:include`s already expanded.
//!
//! C++ yarprobotinterface preprocesses the document the same way before reading it
//! (`PerformInclusions`): every `<xi:include href="..."/>` element is replaced by the root
//! element of the named file, whose own includes are resolved relative to its directory.
//! Each element keeps the file and line it came from, so errors can point at the source.
//!
//! Files are parsed as C++'s parser, TinyXML, parses them (`parse` says how): without
//! namespaces (`xi:include` is just the element of that name, so robots that never
//! declare `xmlns:xi` read), unquoted attribute values accepted, and declarations,
//! DOCTYPEs and comments tolerated anywhere. An `href` is joined to the including file's
//! directory as C++ joins it (`dir + "/" + href`), so `href="/x.xml"` is `dir/x.xml`.
//!
//! An include with `enabled_by="a b"` is expanded only when yarprobotinterface runs
//! with one of those tags in `--enable_tags "(a ...)"` (or `enable_all`); one with
//! `disabled_by="c"` is dropped when `--disable_tags "(c ...)"` names it, as C++'s
//! `CheckIfIncludeSectionIsEnabled` decides ([`IncludeTags`]).
//!
//! Differences from C++ (which would hang or crash): include cycles and runaway nesting
//! are errors, and an `href` without a directory part resolves next to the including file
//! (C++ looks for `dir/x.xml/x.xml`). Differences from TinyXML, none met in
//! robots-configuration: an attribute without a value (`<a x/>`) reads as empty, and
//! markup TinyXML would skip as unknown (`<!ELEMENT ...>`, `<` not followed by a name)
//! is an error.

use super::error::{Location, XmlError};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::sync::Arc;

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
    /// The name as written, prefix included (`xi:include`), as TinyXML names it.
    pub name: String,
    /// Every attribute as written (`xmlns:xi` included), values with entities decoded.
    pub attributes: Vec<(String, String)>,
    /// TinyXML's `GetText()`: the first child's text, whitespace condensed (CDATA as
    /// written); `None` when the first child (blank text aside) is not text.
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

fn canonical(path: &Path) -> PathBuf {
    std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf())
}

/// The 1-based line of each byte offset of a text.
struct Lines(Vec<usize>);

impl Lines {
    fn new(text: &str) -> Self {
        Lines(text.match_indices('\n').map(|(i, _)| i).collect())
    }

    fn at(&self, offset: u64) -> u32 {
        let offset = usize::try_from(offset).unwrap_or(usize::MAX);
        (self.0.partition_point(|&nl| nl < offset) + 1) as u32
    }
}

/// An element being read and what its first child (blank text aside) has been so far.
struct Open {
    element: Element,
    first: First,
}

/// TinyXML's `GetText()`: the element's text is its first child when that child is text
/// (blank text is no child at all).
enum First {
    /// No child yet, or only blank text (held, raw).
    None(String),
    /// A text child, raw until the next node ends it.
    Text(String),
    /// Decided: whatever text the element has is in `element.text`.
    Done,
}

impl Open {
    /// Raw text (entity references included) read inside the element.
    fn text(&mut self, raw: &str) {
        match &mut self.first {
            First::None(s) => {
                s.push_str(raw);
                if !s.trim_ascii().is_empty() {
                    self.first = First::Text(std::mem::take(s));
                }
            }
            First::Text(s) => s.push_str(raw),
            First::Done => {}
        }
    }

    /// A node that is not text (element, comment, CDATA, ...) or the end: the text read
    /// so far, if any, was the first child.
    fn node(&mut self, cdata: Option<&str>) {
        match std::mem::replace(&mut self.first, First::Done) {
            First::Text(raw) => self.element.text = Some(condense(&unescape(&raw))),
            First::None(_) => self.element.text = cdata.map(str::to_owned),
            First::Done => {}
        }
    }
}

/// Entity references decoded as TinyXML decodes them: the five XML entities and
/// character references; an `&` that starts none of them stays as it is.
fn unescape(raw: &str) -> std::borrow::Cow<'_, str> {
    if !raw.contains('&') {
        return std::borrow::Cow::Borrowed(raw);
    }
    let mut out = String::with_capacity(raw.len());
    let mut rest = raw;
    while let Some(at) = rest.find('&') {
        out.push_str(&rest[..at]);
        rest = &rest[at..];
        let entity = rest[1..].find(';').map(|end| &rest[1..=end]);
        let decoded = entity.and_then(|name| match name {
            "amp" => Some('&'),
            "lt" => Some('<'),
            "gt" => Some('>'),
            "quot" => Some('"'),
            "apos" => Some('\''),
            _ => {
                let code = match name.strip_prefix("#x") {
                    Some(hex) => u32::from_str_radix(hex, 16).ok(),
                    None => name.strip_prefix('#').and_then(|d| d.parse().ok()),
                };
                code.and_then(char::from_u32)
            }
        });
        match (decoded, entity) {
            (Some(c), Some(name)) => {
                out.push(c);
                rest = &rest[name.len() + 2..];
            }
            _ => {
                out.push('&');
                rest = &rest[1..];
            }
        }
    }
    out.push_str(rest);
    std::borrow::Cow::Owned(out)
}

/// Parses one file as TinyXML (C++ yarprobotinterface's parser) does: names are taken
/// as written, without namespaces (`xi:include` is the element named so, its prefix
/// needs no declaration); attribute values may go unquoted (up to whitespace, `/` or
/// `>`); declarations, DOCTYPEs, comments and processing instructions may stand
/// anywhere; a comment ends at its first `-->`, whatever `--` it holds; the first
/// element is the root, elements after it are read (and must be well formed) but left
/// out, and top-level text after it ends the reading. Tags must still nest and close.
fn parse(text: &str, file: &Arc<str>) -> Result<(Element, Option<String>), XmlError> {
    use quick_xml::events::Event;
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let lines = Lines::new(text);
    let malformed = |offset: u64, message: String| XmlError::Malformed {
        file: file.to_string(),
        line: lines.at(offset),
        message,
    };
    let mut reader = quick_xml::Reader::from_str(text);
    let config = reader.config_mut();
    config.allow_dangling_amp = true;
    // TinyXML skips an end tag at the top level; inside an element it must match.
    config.allow_unmatched_ends = true;
    let mut stack: Vec<Open> = Vec::new();
    let mut root: Option<Element> = None;
    let mut doctype = None;
    loop {
        let start = reader.buffer_position();
        let event = reader
            .read_event()
            .map_err(|e| malformed(reader.error_position(), e.to_string()))?;
        let (empty, tag) = match event {
            Event::Start(tag) => (false, tag),
            Event::Empty(tag) => (true, tag),
            Event::Text(t) => {
                let raw = t.into_inner();
                match stack.last_mut() {
                    Some(open) => open.text(&raw),
                    None if raw.trim_ascii().is_empty() => {}
                    None if root.is_some() => break,
                    None => return Err(malformed(start, "text before the root element".into())),
                }
                continue;
            }
            Event::GeneralRef(r) => {
                match stack.last_mut() {
                    Some(open) => open.text(&format!("&{};", &*r.into_inner())),
                    None if root.is_some() => break,
                    None => return Err(malformed(start, "text before the root element".into())),
                }
                continue;
            }
            Event::CData(c) => {
                if let Some(open) = stack.last_mut() {
                    open.node(Some(&c.into_inner()));
                }
                continue;
            }
            Event::DocType(d) => {
                if stack.is_empty() && doctype.is_none() {
                    doctype = Some(format!("<!DOCTYPE {}>", &*d.into_inner()));
                }
                if let Some(open) = stack.last_mut() {
                    open.node(None);
                }
                continue;
            }
            Event::Comment(_) | Event::Decl(_) | Event::PI(_) => {
                if let Some(open) = stack.last_mut() {
                    open.node(None);
                }
                continue;
            }
            Event::End(_) => {
                // a stray end tag at the top level (quick-xml checks the others)
                let Some(mut open) = stack.pop() else {
                    continue;
                };
                open.node(None);
                match stack.last_mut() {
                    Some(parent) => parent.element.children.push(open.element),
                    None => {
                        root.get_or_insert(open.element);
                    }
                }
                continue;
            }
            Event::Eof => break,
        };
        if tag.name().as_ref().is_empty() {
            return Err(malformed(start, "`<` not followed by a name".into()));
        }
        let at = Location::new(file, lines.at(start));
        let mut attributes = Vec::new();
        for a in tag.html_attributes() {
            let a = a.map_err(|e| malformed(start, e.to_string()))?;
            let key = a.key.as_ref().to_owned();
            attributes.push((key, unescape(&a.value).into_owned()));
        }
        let element = Element {
            name: tag.name().as_ref().to_owned(),
            attributes,
            text: None,
            children: Vec::new(),
            at,
        };
        if let Some(parent) = stack.last_mut() {
            parent.node(None);
        }
        match (empty, stack.last_mut()) {
            (false, _) => stack.push(Open {
                element,
                first: First::None(String::new()),
            }),
            (true, Some(parent)) => parent.element.children.push(element),
            (true, None) => {
                root.get_or_insert(element);
            }
        }
    }
    if let Some(open) = stack.last() {
        let e = &open.element;
        return Err(XmlError::Malformed {
            file: file.to_string(),
            line: e.at.line,
            message: format!("<{}> is not closed before the end of the file", e.name),
        });
    }
    let root = root.ok_or_else(|| malformed(0, "no root element".into()))?;
    Ok((root, doctype))
}

fn load_text(
    text: &str,
    name: &Arc<str>,
    dir: &Path,
    includes: &mut Includes,
) -> Result<Document, XmlError> {
    let (mut root, doctype) = parse(text, name)?;
    expand(&mut root, dir, includes)?;
    Ok(Document { root, doctype })
}

/// Replaces each `xi:include` below `element` by the root of the file it names (or
/// drops it when its tags disable it), as C++ `PerformInclusions` does.
fn expand(element: &mut Element, dir: &Path, includes: &mut Includes) -> Result<(), XmlError> {
    let mut children = Vec::with_capacity(element.children.len());
    for mut child in std::mem::take(&mut element.children) {
        if child.name == "xi:include" {
            if includes
                .tags
                .enabled(child.attr("enabled_by"), child.attr("disabled_by"))
            {
                children.push(include(&child, dir, includes)?);
            }
        } else {
            expand(&mut child, dir, includes)?;
            children.push(child);
        }
    }
    element.children = children;
    Ok(())
}

/// Where C++ looks for an included file: the including file's directory, `/` and the
/// `href` (backslashes read as slashes), so that an `href` starting with `/` is still
/// relative to it.
pub fn include_path(dir: &Path, href: &str) -> PathBuf {
    let href = href.replace('\\', "/");
    dir.join(href.trim_start_matches('/'))
}

/// The root element of the file an `xi:include` names, its own includes expanded.
fn include(node: &Element, dir: &Path, includes: &mut Includes) -> Result<Element, XmlError> {
    let at = node.at.clone();
    let href = node
        .attr("href")
        .ok_or_else(|| XmlError::syntax(&at, "xi:include without an \"href\" attribute"))?;
    let path = include_path(dir, href);
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

    fn parse_str(text: &str) -> Result<Document, XmlError> {
        load_str(text, "t.xml", Path::new("."), &IncludeTags::default())
    }

    fn names(el: &Element) -> Vec<&str> {
        el.children.iter().map(|c| c.name.as_str()).collect()
    }

    #[test]
    fn an_undeclared_xi_prefix_includes_as_in_tinyxml() {
        // iCubGenova07/08, iCubLisboa01: `xi:include` without `xmlns:xi` anywhere.
        let dir = tempfile::tempdir().unwrap();
        let top = write(
            dir.path(),
            "top.xml",
            "<robot name=\"r\">\n<devices>\n<xi:include href=\"sub/a.xml\"/>\n</devices>\n</robot>",
        );
        write(
            dir.path(),
            "sub/a.xml",
            "<device name=\"a\" type=\"t\"><xi:include href=\"p.xml\"/></device>",
        );
        write(dir.path(), "sub/p.xml", "<params><other:x/></params>");
        let doc = load_file(&top, &IncludeTags::default()).unwrap_or_else(|e| panic!("{e}"));
        let dev = &doc.root.children[0].children[0];
        assert_eq!(dev.attr("name"), Some("a"));
        assert_eq!(
            names(&dev.children[0]),
            ["other:x"],
            "any prefix kept as written"
        );
        // a declared one reads the same, its declaration an attribute like any other
        let doc = parse_str(&format!("<robot {XI} name=\"r\"/>")).unwrap();
        assert_eq!(doc.root.attr("xmlns:xi"), Some(XINCLUDE));
    }

    const XINCLUDE: &str = "http://www.w3.org/2001/XInclude";

    #[test]
    fn unquoted_attribute_values_read_as_in_tinyxml() {
        // iCubShanghai01's hardware/inertials/waist-inertial.xml:
        // `<device xmlns:xi="..." name=xsensmt-inertial type="xsensmt">`
        let doc = parse_str(
            "<robot name=r>\n<device name=xsensmt-inertial type=\"xsensmt\">\n<param name=a>1</param>\n<x v=1/>\n</device>\n</robot>",
        )
        .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(doc.root.attr("name"), Some("r"));
        let dev = &doc.root.children[0];
        assert_eq!(dev.attr("name"), Some("xsensmt-inertial"));
        assert_eq!(dev.attr("type"), Some("xsensmt"));
        assert_eq!(dev.children[0].attr("name"), Some("a"));
        assert_eq!(dev.children[1].attr("v"), Some("1"), "ends at `/`");
        // duplicate attributes stay an error (TinyXML's too), with the line
        let e = parse_str("<robot>\n<a x=\"1\" x=\"2\"/>\n</robot>").unwrap_err();
        assert!(e.to_string().starts_with("t.xml:2:"), "{e}");
    }

    #[test]
    fn an_href_is_joined_to_the_including_directory_as_cpp_joins_it() {
        // naoPrague01's `<xi:include href="/nao_client.xml"/>`: C++ builds
        // dir + "/" + href, which is dir/nao_client.xml, not the file system root.
        let dir = tempfile::tempdir().unwrap();
        let top = write(
            dir.path(),
            "top.xml",
            "<robot name=\"r\">\n<xi:include href=\"/a.xml\"/>\n<xi:include href=\"sub\\b.xml\"/>\n</robot>",
        );
        write(dir.path(), "a.xml", "<device name=\"a\" type=\"t\"/>");
        write(dir.path(), "sub/b.xml", "<device name=\"b\" type=\"t\"/>");
        let doc = load_file(&top, &IncludeTags::default()).unwrap_or_else(|e| panic!("{e}"));
        let got: Vec<_> = doc.root.children.iter().map(|c| c.attr("name")).collect();
        assert_eq!(got, [Some("a"), Some("b")]);
        assert_eq!(
            include_path(Path::new("/r"), "/x/y.xml"),
            Path::new("/r/x/y.xml")
        );
        assert_eq!(
            include_path(Path::new("/r"), "..\\y.xml"),
            Path::new("/r/../y.xml")
        );
    }

    #[test]
    fn declarations_doctypes_comments_and_instructions_anywhere() {
        let doc = parse_str(
            "<!-- head -->\n<!DOCTYPE robot PUBLIC \"-//YARP//DTD yarprobotinterface 3.0//EN\" \"http://www.yarp.it/DTD/yarprobotinterfaceV3.0.dtd\">\n\
             <robot name=\"r\">\n<?xml version=\"1.0\"?>\n<!DOCTYPE devices>\n<?pi x?>\n<a/>\n</robot>\n<!-- tail -->\n",
        )
        .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(names(&doc.root), ["a"]);
        assert_eq!(doc.root.children[0].at.line, 7);
        let dtd = doc.doctype.unwrap();
        assert!(
            dtd.starts_with("<!DOCTYPE robot PUBLIC") && dtd.contains("3.0"),
            "{dtd}"
        );
    }

    #[test]
    fn what_follows_the_root_is_left_out_as_in_tinyxml() {
        // iCubEdinburgh01's and iCubSingapore01's icub_all_inertials.xml go on with
        // `<xi:include .../>`s after `</robot>`: TinyXML reads them as further top-level
        // elements, and yarprobotinterface only looks at the first (nor expands them).
        let doc = parse_str(
            "<robot name=\"r\"><a/></robot>\n\n<xi:include href=\"missing.xml\"/>\n</devices>\n<b/>",
        )
        .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(doc.root.name, "robot");
        assert_eq!(names(&doc.root), ["a"]);
        // they must still be well formed, as TinyXML parses them
        let e = parse_str("<robot name=\"r\"/>\n<b>\n<c></b>").unwrap_err();
        assert!(e.to_string().starts_with("t.xml:3:"), "{e}");
        // top-level text after the root ends the reading, before it is an error
        parse_str("<robot name=\"r\"/>\ntrailing words <b></c>").unwrap();
        let e = parse_str("\nwords <robot name=\"r\"/>").unwrap_err();
        assert!(e.to_string().starts_with("t.xml:1:"), "{e}");
        let e = parse_str("<!-- only a comment -->").unwrap_err();
        assert!(e.to_string().contains("no root element"), "{e}");
    }

    #[test]
    fn text_is_the_first_child_as_tinyxml_get_text() {
        let doc = parse_str(
            "<robot>\n<p> a &amp; &lt;b&gt; &#x41;&#66; &unknown; </p>\n<p>\n  <!-- c --> 1</p>\n\
             <p>1<!-- c -->2</p>\n<p><![CDATA[ x  y ]]></p>\n<p>  <q/>t</p>\n<p>\n</p>\n</robot>",
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let texts: Vec<_> = doc
            .root
            .children
            .iter()
            .map(|c| c.text.as_deref())
            .collect();
        assert_eq!(
            texts,
            [
                Some("a & <b> AB &unknown;"),
                None,
                Some("1"),
                Some(" x  y "),
                None,
                None
            ]
        );
        let doc = parse_str("<robot a=\"x &quot;y&quot; &z\"/>").unwrap();
        assert_eq!(doc.root.attr("a"), Some("x \"y\" &z"));
    }

    #[test]
    fn real_syntax_errors_name_file_and_line() {
        for (text, line) in [
            ("<robot>\n<device>\n</robot>", 3),
            ("<robot>\n\n<device name=\"d\">\n", 3),
            ("<robot>\n<a>\n<!-- never closed\n</a></robot>", 3),
            ("<robot>\n<a x=\"1></a>\n</robot>", 2),
            ("<robot>\n\n</a>\n</robot>", 3),
            ("<robot>\n<p>a < b</p>\n</robot>", 2),
        ] {
            let e = parse_str(text).unwrap_err();
            assert!(
                matches!(e, XmlError::Malformed { line: l, .. } if l == line),
                "{text:?}: {e}"
            );
            assert!(e.to_string().starts_with(&format!("t.xml:{line}:")), "{e}");
        }
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
