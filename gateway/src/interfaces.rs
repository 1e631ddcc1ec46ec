//! The run-time type registry: interface definitions found in the ROS installation the
//! gateway runs beside (`AMENT_PREFIX_PATH`: `<prefix>/share/<pkg>/msg/*.msg`,
//! `srv/*.srv`, `action/*.action`) and in directories named on the command line (`--interfaces`) or in a
//! mapping file (`interfaces = [...]`). [`crate::types::lookup`] asks here first and falls
//! back to the built-in catalog, which is all there is when no ROS is installed.
//!
//! Files are only indexed when a directory is added; a type is parsed ([`crate::msgdef`])
//! the first time it is looked up and then kept for the life of the process as a
//! `&'static` [`MsgType`], like the built-in ones.

use crate::msgdef::{self, BaseDef, MsgDef};
use crate::types::{Base, Constant, Field, MsgType};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{OnceLock, RwLock};

/// Where a type's definition is.
#[derive(Debug, Clone, PartialEq)]
enum Source {
    Msg(PathBuf),
    Srv(PathBuf),
    Action(PathBuf),
    /// An `.idl` without a `.msg`/`.srv` beside it.
    Idl(PathBuf),
}

#[derive(Default)]
struct Registry {
    files: HashMap<String, Source>,
    loaded: HashMap<String, &'static MsgType>,
    /// Definitions that did not parse, with why (looked up once, reported by [`problem`]).
    failed: HashMap<String, String>,
}

fn registry() -> &'static RwLock<Registry> {
    static REG: OnceLock<RwLock<Registry>> = OnceLock::new();
    REG.get_or_init(|| {
        let mut r = Registry::default();
        // Earlier prefixes overlay later ones, so the first one indexed last wins.
        if let Some(paths) = std::env::var_os("AMENT_PREFIX_PATH") {
            let prefixes: Vec<PathBuf> = std::env::split_paths(&paths).collect();
            for p in prefixes.iter().rev() {
                index_dir(&mut r, p);
            }
        }
        RwLock::new(r)
    })
}

/// The run-time definition of `name` (`pkg/msg/Name`, `pkg/srv/Name[_Request|...]`), if
/// one was found and parses.
pub fn lookup(name: &str) -> Option<&'static MsgType> {
    let reg = registry();
    let source = {
        let r = reg.read().ok()?;
        if let Some(t) = r.loaded.get(name) {
            return Some(t);
        }
        if r.failed.contains_key(name) {
            return None;
        }
        r.files.get(name)?.clone()
    };
    let (pkg, _, stem) = crate::types::split_name(name)?;
    let parsed = match &source {
        Source::Msg(p) => read(p).and_then(|text| Ok(vec![msgdef::parse_msg(pkg, stem, &text)?])),
        Source::Srv(p) => {
            read(p).and_then(|text| Ok(msgdef::parse_srv(pkg, &file_stem(p), &text)?))
        }
        Source::Action(p) => {
            read(p).and_then(|text| Ok(msgdef::parse_action(pkg, &file_stem(p), &text)?))
        }
        Source::Idl(p) => read(p).and_then(|text| {
            crate::idl::parse(&text).map_err(|e| DefinitionError::Idl(p.clone(), e))
        }),
    };
    let mut r = reg.write().ok()?;
    match parsed {
        Ok(defs) => {
            for d in defs {
                if !r.loaded.contains_key(&d.name) {
                    let t = leak(d);
                    r.loaded.insert(t.name.to_string(), t);
                }
            }
        }
        Err(e) => {
            tracing::warn!("interface definition of {name}: {e}");
            r.failed.insert(name.to_string(), e.to_string());
        }
    }
    r.loaded.get(name).copied()
}

/// Why the definition of `name` could not be used, if it was found but did not parse.
pub fn problem(name: &str) -> Option<String> {
    registry().read().ok()?.failed.get(name).cloned()
}

/// Adds the definitions under `dir` (which take precedence over those found so far):
/// `dir` may be an install prefix (`dir/share/<pkg>/msg`), a directory of packages
/// (`dir/<pkg>/msg`) or one package (`dir/msg`, package name = the directory's name).
/// Returns how many type names it indexed.
pub fn add_dir(dir: &Path) -> usize {
    let Ok(mut r) = registry().write() else {
        return 0;
    };
    index_dir(&mut r, dir)
}

/// Every message type (`pkg/msg/Name`) with a definition on file, sorted.
pub fn message_names() -> Vec<String> {
    let Ok(r) = registry().read() else {
        return Vec::new();
    };
    let mut v: Vec<String> = r
        .files
        .iter()
        .filter(|(n, _)| n.contains("/msg/"))
        .map(|(n, _)| n.clone())
        .collect();
    v.sort();
    v
}

/// Why a definition found on file cannot be used.
#[derive(Debug, thiserror::Error)]
enum DefinitionError {
    #[error("{}: {}", .0.display(), .1)]
    Read(PathBuf, std::io::Error),
    #[error(transparent)]
    Def(#[from] msgdef::DefError),
    #[error("{}: {}", .0.display(), .1)]
    Idl(PathBuf, crate::idl::IdlError),
}

fn read(p: &Path) -> Result<String, DefinitionError> {
    std::fs::read_to_string(p).map_err(|e| DefinitionError::Read(p.into(), e))
}

fn file_stem(p: &Path) -> String {
    p.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

fn index_dir(r: &mut Registry, dir: &Path) -> usize {
    if is_package(dir) {
        let pkg = dir
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        return index_package(r, &pkg, dir);
    }
    let parent = if dir.join("share").is_dir() {
        dir.join("share")
    } else {
        dir.to_path_buf()
    };
    let Ok(entries) = std::fs::read_dir(&parent) else {
        return 0;
    };
    let mut n = 0;
    for e in entries.flatten() {
        let p = e.path();
        if is_package(&p) {
            n += index_package(r, &e.file_name().to_string_lossy(), &p);
        }
    }
    n
}

fn is_package(dir: &Path) -> bool {
    ["msg", "srv", "action"]
        .iter()
        .any(|k| dir.join(k).is_dir())
}

fn index_package(r: &mut Registry, pkg: &str, dir: &Path) -> usize {
    let mut n = 0;
    for kind in ["msg", "srv", "action"] {
        let Ok(entries) = std::fs::read_dir(dir.join(kind)) else {
            continue;
        };
        let mut files: Vec<PathBuf> = entries.flatten().map(|e| e.path()).collect();
        files.sort();
        for p in &files {
            let ext = p.extension().map(|x| x.to_string_lossy().into_owned());
            let source = match ext.as_deref() {
                Some("msg") if kind == "msg" => Source::Msg(p.clone()),
                Some("srv") if kind == "srv" => Source::Srv(p.clone()),
                Some("action") if kind == "action" => Source::Action(p.clone()),
                // `.idl` only where the package has no `.msg`/`.srv` of that name (an
                // action's `.idl` lacks the services rosidl derives: `.action` only)
                Some("idl") if kind != "action" && !p.with_extension(kind).exists() => {
                    Source::Idl(p.clone())
                }
                _ => continue,
            };
            let stem = file_stem(p);
            let suffixes: &[&str] = match kind {
                "msg" => &[""],
                "srv" => &["", "_Request", "_Response", "_Event"],
                _ => ACTION_SUFFIXES,
            };
            for suffix in suffixes {
                let name = format!("{pkg}/{kind}/{stem}{suffix}");
                // A definition from another file replaces one already read (Jazzy's
                // control_msgs after Kilted's): it is parsed again when next looked up.
                if r.files.get(&name).is_some_and(|old| old != &source) {
                    r.loaded.remove(&name);
                    r.failed.remove(&name);
                }
                r.files.insert(name, source.clone());
                n += 1;
            }
        }
    }
    n
}

/// The structures rosidl derives from `pkg/action/Name` are `Name` + each of these.
const ACTION_SUFFIXES: &[&str] = &[
    "",
    "_Goal",
    "_Result",
    "_Feedback",
    "_SendGoal",
    "_SendGoal_Request",
    "_SendGoal_Response",
    "_SendGoal_Event",
    "_GetResult",
    "_GetResult_Request",
    "_GetResult_Response",
    "_GetResult_Event",
    "_FeedbackMessage",
];

/// Gives a parsed definition the `'static` form of the built-in catalog (once per type
/// and process).
fn leak(d: MsgDef) -> &'static MsgType {
    Box::leak(Box::new(to_static(d)))
}

/// A parsed definition as a [`MsgType`], its strings leaked (once per type and process).
pub(crate) fn to_static(d: MsgDef) -> MsgType {
    let fields: Vec<Field> = d
        .fields
        .into_iter()
        .map(|f| Field {
            name: f.name.leak(),
            base: match f.base {
                BaseDef::Prim(p) => Base::Prim(p),
                BaseDef::Nested(n) => Base::Nested(n.leak()),
            },
            shape: f.shape,
            string_capacity: f.string_capacity,
            default: f.default.map(|s| &*s.leak()),
        })
        .collect();
    let constants: Vec<Constant> = d
        .constants
        .into_iter()
        .map(|c| Constant {
            name: c.name.leak(),
            prim: c.prim,
            value: c.value.leak(),
        })
        .collect();
    MsgType {
        name: d.name.leak(),
        fields: fields.leak(),
        constants: constants.leak(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_package_directory_is_indexed_and_parsed_on_demand() {
        let dir = std::env::temp_dir().join(format!("gw-ifaces-{}", std::process::id()));
        let pkg = dir.join("gw_test_pkg");
        std::fs::create_dir_all(pkg.join("msg")).unwrap();
        std::fs::create_dir_all(pkg.join("srv")).unwrap();
        std::fs::create_dir_all(pkg.join("action")).unwrap();
        std::fs::write(
            pkg.join("action/Count.action"),
            "int32 to\n---\nPair last\n---\nint32 at\n",
        )
        .unwrap();
        std::fs::write(pkg.join("action/Count.idl"), "not read").unwrap();
        std::fs::write(
            pkg.join("msg/Pair.msg"),
            "int32 A=1\nstd_msgs/String left\nfloat64 right 2.5\n",
        )
        .unwrap();
        std::fs::write(pkg.join("msg/Broken.msg"), "nonsense\n").unwrap();
        std::fs::write(pkg.join("srv/Ask.srv"), "Pair q\n---\nbool ok\n").unwrap();
        std::fs::write(pkg.join("msg/Pair.idl"), "not read: Pair.msg is there").unwrap();
        std::fs::write(
            pkg.join("msg/OnlyIdl.idl"),
            "module gw_test_pkg { module msg { struct OnlyIdl { double__x v; }; }; };",
        )
        .unwrap();
        std::fs::write(
            pkg.join("msg/Idl.idl"),
            "module gw_test_pkg { module msg { struct Idl { sequence<Pair> p; }; }; };",
        )
        .unwrap();
        assert_eq!(add_dir(&dir), 8 + ACTION_SUFFIXES.len());
        let goal = lookup("gw_test_pkg/action/Count_SendGoal_Request").unwrap();
        assert_eq!(
            goal.fields[0].base,
            Base::Nested("unique_identifier_msgs/msg/UUID")
        );
        assert_eq!(
            goal.fields[1].base,
            Base::Nested("gw_test_pkg/action/Count_Goal")
        );
        let result = lookup("gw_test_pkg/action/Count_Result").unwrap();
        assert_eq!(result.fields[0].base, Base::Nested("gw_test_pkg/msg/Pair"));
        assert!(lookup("gw_test_pkg/action/Count").is_some());
        let idl = lookup("gw_test_pkg/msg/Idl").unwrap();
        assert_eq!(idl.fields[0].base, Base::Nested("gw_test_pkg/msg/Pair"));
        let t = lookup("gw_test_pkg/msg/Pair").unwrap();
        assert_eq!(t.fields.len(), 2);
        assert_eq!(t.fields[0].base, Base::Nested("std_msgs/msg/String"));
        assert_eq!(t.fields[1].default, Some("2.5"));
        assert_eq!(t.constants[0].name, "A");
        assert!(std::ptr::eq(t, lookup("gw_test_pkg/msg/Pair").unwrap()));
        let q = crate::types::lookup("gw_test_pkg/srv/Ask_Request").unwrap();
        assert_eq!(q.fields[0].base, Base::Nested("gw_test_pkg/msg/Pair"));
        assert!(lookup("gw_test_pkg/srv/Ask").is_some());
        assert!(lookup("gw_test_pkg/msg/Broken").is_none());
        assert!(problem("gw_test_pkg/msg/Broken").is_some());
        assert!(message_names().contains(&"gw_test_pkg/msg/Pair".to_string()));
        // the package directory itself works too
        assert_eq!(add_dir(&pkg), 8 + ACTION_SUFFIXES.len());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
