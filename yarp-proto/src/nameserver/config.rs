//! Where the name server's address is kept (`yarp.conf`), as C++ `NameConfig` and
//! `yarp::conf::dirs::yarpconfighome()` find and write it. Pure: the environment and the
//! file reader are passed in as closures.
//!
//! * Directory: `$YARP_CONFIG_HOME` if set (even empty); else `$XDG_CONFIG_HOME/yarp`;
//!   else `$HOME/.config/yarp`.
//! * Namespace: the first word of `$YARP_NAMESPACE` if non-empty, else of the file
//!   `yarp_namespace.conf` in that directory, else `/root`.
//! * File: `yarp.conf` for the namespace `/root`; for any other namespace the namespace
//!   with every character outside `[0-9A-Za-z]` replaced by `_`, plus `.conf`
//!   (`/foo` -> `_foo.conf`).
//! * Contents: `<host> <port> <mode>\n` (mode `yarp`); readers also accept just
//!   `<host> <port>` and the bracketed `[name] host ... port ...` form.

use crate::nameserver::registry::atoi;
use crate::value::Bottle;
use std::path::{Path, PathBuf};

/// The file holding the server address for the default namespace.
pub const CONFIG_FILENAME: &str = "yarp.conf";
/// The file naming the namespace(s) when `YARP_NAMESPACE` is not set.
pub const NAMESPACE_FILENAME: &str = "yarp_namespace.conf";

/// The YARP configuration directory (`yarp::conf::dirs::yarpconfighome()` on Linux).
pub fn config_home(env: &dyn Fn(&str) -> Option<String>) -> PathBuf {
    if let Some(d) = env("YARP_CONFIG_HOME") {
        return PathBuf::from(d);
    }
    if let Some(x) = env("XDG_CONFIG_HOME") {
        return PathBuf::from(format!("{x}/yarp"));
    }
    let home = env("HOME").unwrap_or_default();
    PathBuf::from(format!("{home}/.config/yarp"))
}

fn expand(env: &dyn Fn(&str) -> Option<String>, fname: &str) -> PathBuf {
    let root = config_home(env);
    if root.as_os_str().is_empty() {
        PathBuf::from(fname)
    } else {
        root.join(fname)
    }
}

/// The current namespace (`NameConfig::getNamespace`).
pub fn namespace(
    env: &dyn Fn(&str) -> Option<String>,
    read: &dyn Fn(&Path) -> Option<String>,
) -> String {
    let text = match env("YARP_NAMESPACE") {
        Some(s) if !s.is_empty() => s,
        _ => read(&expand(env, NAMESPACE_FILENAME)).unwrap_or_default(),
    };
    let spaces = Bottle::from_text(&text);
    match spaces.get(0).and_then(|v| v.as_str()) {
        Some(s) if !s.is_empty() => s.to_string(),
        _ => "/root".to_string(),
    }
}

/// The path of the address file for the current namespace.
pub fn config_file_name(
    env: &dyn Fn(&str) -> Option<String>,
    read: &dyn Fn(&Path) -> Option<String>,
) -> PathBuf {
    let space = namespace(env, read);
    let fname = if space == "/root" {
        CONFIG_FILENAME.to_string()
    } else {
        let safe: String = space
            .chars()
            .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
            .collect();
        format!("{safe}.conf")
    };
    expand(env, &fname)
}

/// The name server address read from a configuration file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ConfAddress {
    pub host: String,
    pub port: i32,
    /// `yarp` unless the file says otherwise (`ros`...).
    pub mode: String,
}

/// Parses the contents of `yarp.conf` (`NameConfig::fromString`).
pub fn parse_conf(text: &str) -> Option<ConfAddress> {
    let words: Vec<&str> = text.split_whitespace().collect();
    if words.first().is_some_and(|w| w.starts_with('[')) {
        let mut in_name = false;
        let (mut host, mut port, mut mode) = (String::new(), 0, "yarp".to_string());
        for line in text.lines() {
            let t = line.trim();
            if t.starts_with('[') {
                in_name = t == "[name]";
                continue;
            }
            if !in_name {
                continue;
            }
            let mut it = t.split_whitespace();
            match (it.next(), it.next()) {
                (Some("host"), Some(v)) => host = v.to_string(),
                (Some("port"), Some(v)) => port = atoi(v),
                (Some("mode"), Some(v)) => mode = v.to_string(),
                _ => {}
            }
        }
        return (port != 0).then_some(ConfAddress { host, port, mode });
    }
    if words.len() >= 2 {
        return Some(ConfAddress {
            host: words[0].to_string(),
            port: atoi(words[1]),
            mode: words.get(2).unwrap_or(&"yarp").to_string(),
        });
    }
    None
}

/// The contents C++ writes (`NameConfig::toFile`).
pub fn format_conf(host: &str, port: i32, mode: &str) -> String {
    let mode = if mode.is_empty() { "yarp" } else { mode };
    format!("{host} {port} {mode}\n")
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    fn envf<'a>(m: &'a HashMap<&'a str, &'a str>) -> impl Fn(&str) -> Option<String> + 'a {
        move |k| m.get(k).map(|s| s.to_string())
    }

    #[test]
    fn paths() {
        let none = |_: &Path| None;
        let mut m = HashMap::new();
        m.insert("HOME", "/home/u");
        assert_eq!(
            config_file_name(&envf(&m), &none),
            PathBuf::from("/home/u/.config/yarp/yarp.conf")
        );
        m.insert("XDG_CONFIG_HOME", "/x");
        assert_eq!(
            config_file_name(&envf(&m), &none),
            PathBuf::from("/x/yarp/yarp.conf")
        );
        m.insert("YARP_CONFIG_HOME", "/y");
        assert_eq!(
            config_file_name(&envf(&m), &none),
            PathBuf::from("/y/yarp.conf")
        );
        m.insert("YARP_NAMESPACE", "/foo/bar /other");
        assert_eq!(
            config_file_name(&envf(&m), &none),
            PathBuf::from("/y/_foo_bar.conf")
        );
        m.remove("YARP_NAMESPACE");
        let ns = |p: &Path| (p == Path::new("/y/yarp_namespace.conf")).then(|| "/ns\n".to_string());
        assert_eq!(
            config_file_name(&envf(&m), &ns),
            PathBuf::from("/y/_ns.conf")
        );
    }

    #[test]
    fn contents() {
        assert_eq!(
            parse_conf("127.0.0.1 10000 yarp\n"),
            Some(ConfAddress {
                host: "127.0.0.1".into(),
                port: 10000,
                mode: "yarp".into()
            })
        );
        assert_eq!(
            parse_conf("10.0.0.1 10001").map(|a| a.mode),
            Some("yarp".into())
        );
        assert_eq!(parse_conf(""), None);
        assert_eq!(
            parse_conf("[name]\nhost 1.2.3.4\nport 10005\n").map(|a| (a.host, a.port)),
            Some(("1.2.3.4".into(), 10005))
        );
        assert_eq!(
            format_conf("127.0.0.1", 10000, ""),
            "127.0.0.1 10000 yarp\n"
        );
    }
}
