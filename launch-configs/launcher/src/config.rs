//! The launch-config format (TOML), its command-line overrides and `${var}` expansion.
//!
//! A config names a set of modules (programs), the order they start in, the connections
//! to make between their ports, the name server to use, and what the dashboard shows.
//! The full format is documented in `launch-configs/README.md`; in short:
//!
//! ```toml
//! name = "demo"
//! [vars]                     # defaults for ${name} in strings; --set name=value overrides
//! part = "/demo"
//! [name_server]
//! address = "127.0.0.1:10000"  # where the name server is
//! embedded = true              # start `yarpserver` there when none answers
//! write_conf = true            # record the address in yarp.conf (as `yarp conf`)
//! [dashboard]
//! plot = "${part}/out"         # port whose numbers are plotted
//! [[module]]
//! name = "reader"
//! program = "yarp"             # bare names: YARP_BIN_DIR, cargo target dir, PATH
//! args = ["read", "${part}/in"]
//! ready = { port = "${part}/in", timeout = 10 }
//! restart = "on-failure"
//! [[connection]]
//! from = "${part}/out"
//! to = "${part}/in"
//! carrier = "tcp"
//! ```

use serde::Deserialize;
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Why a config could not be loaded. Every variant names the file or the key at fault.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    #[error("cannot read {path}: {source}")]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: {message}")]
    Syntax { path: PathBuf, message: String },
    #[error("--set {0}: expected key=value")]
    BadOverride(String),
    #[error("--set {key}: {message}")]
    Override { key: String, message: String },
    #[error("{path}: unknown variable ${{{name}}} in {context}")]
    UnknownVar {
        path: PathBuf,
        name: String,
        context: String,
    },
    #[error("{path}: {message}")]
    Invalid { path: PathBuf, message: String },
}

/// When a module that exited is started again.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum RestartPolicy {
    /// Never: the module stays down (the rest keeps running).
    #[default]
    Never,
    /// When it exits with a failure status or is killed by a signal.
    OnFailure,
    /// Whenever it exits.
    Always,
}

/// How the launcher knows a module is up: exactly one of the check fields.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Readiness {
    /// A YARP port is registered and accepts connections (`yarp exists`).
    pub port: Option<String>,
    /// A TCP address accepts connections (`host:port`).
    pub tcp: Option<String>,
    /// The module printed a line containing this text (stdout or stderr).
    pub log: Option<String>,
    /// Just wait this many seconds.
    pub delay: Option<f64>,
    /// Seconds to wait for the check before the start counts as failed.
    #[serde(default = "default_ready_timeout")]
    pub timeout: f64,
}

fn default_ready_timeout() -> f64 {
    20.0
}

/// The single check a [`Readiness`] asks for.
#[derive(Debug, Clone, PartialEq)]
pub enum ReadyCheck {
    Port(String),
    Tcp(String),
    Log(String),
    Delay(Duration),
}

impl Readiness {
    /// The check, or an error message when none or several are given.
    pub fn check(&self) -> Result<ReadyCheck, String> {
        let mut found = Vec::new();
        if let Some(p) = &self.port {
            found.push(ReadyCheck::Port(p.clone()));
        }
        if let Some(t) = &self.tcp {
            found.push(ReadyCheck::Tcp(t.clone()));
        }
        if let Some(l) = &self.log {
            found.push(ReadyCheck::Log(l.clone()));
        }
        if let Some(d) = self.delay {
            if !(0.0..=3600.0).contains(&d) {
                return Err(format!("ready.delay {d} is not between 0 and 3600 seconds"));
            }
            found.push(ReadyCheck::Delay(Duration::from_secs_f64(d)));
        }
        match found.len() {
            1 => Ok(found.remove(0)),
            0 => Err("ready needs one of port, tcp, log, delay".into()),
            _ => Err("ready takes only one of port, tcp, log, delay".into()),
        }
    }

    pub fn timeout(&self) -> Duration {
        Duration::from_secs_f64(self.timeout.clamp(0.0, 3600.0))
    }
}

/// One program to start and supervise.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Module {
    /// Unique name: log prefix and target of `after`.
    pub name: String,
    /// Program to run: a path, or a bare name looked up as [`crate::programs`] says.
    pub program: String,
    #[serde(default)]
    pub args: Vec<String>,
    /// Extra environment variables.
    #[serde(default)]
    pub env: BTreeMap<String, String>,
    /// Working directory (relative to the config file's directory).
    pub cwd: Option<String>,
    /// Modules that must be ready before this one starts.
    #[serde(default)]
    pub after: Vec<String>,
    /// YARP ports that must exist before this one starts (yarpmanager `<dependencies>`).
    #[serde(default)]
    pub wait_ports: Vec<String>,
    pub ready: Option<Readiness>,
    #[serde(default)]
    pub restart: RestartPolicy,
    /// Restarts allowed before the module is given up (0 = unlimited).
    #[serde(default = "default_max_restarts")]
    pub max_restarts: u32,
    /// Seconds allowed for each stop step (SIGINT, then SIGTERM, then SIGKILL).
    #[serde(default = "default_stop_timeout")]
    pub stop_timeout: f64,
    /// Set false to list a module without starting it (e.g. enabled by `--set`).
    #[serde(default = "yes")]
    pub enabled: bool,
}

fn default_max_restarts() -> u32 {
    5
}

fn default_stop_timeout() -> f64 {
    3.0
}

fn yes() -> bool {
    true
}

impl Module {
    /// A module running `program args…` with every option at its default.
    pub fn new(name: &str, program: &str, args: &[&str]) -> Module {
        Module {
            name: name.into(),
            program: program.into(),
            args: args.iter().map(|a| a.to_string()).collect(),
            env: BTreeMap::new(),
            cwd: None,
            after: Vec::new(),
            wait_ports: Vec::new(),
            ready: None,
            restart: RestartPolicy::Never,
            max_restarts: default_max_restarts(),
            stop_timeout: default_stop_timeout(),
            enabled: true,
        }
    }

    pub fn stop_timeout(&self) -> Duration {
        Duration::from_secs_f64(self.stop_timeout.clamp(0.1, 600.0))
    }
}

/// A connection made once both ports exist (and made again if it disappears).
#[derive(Debug, Clone, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConnectionSpec {
    pub from: String,
    pub to: String,
    /// Carrier (`tcp`, `udp`, `fast_tcp`, `text`, ...); default: the port's choice.
    pub carrier: Option<String>,
}

/// Where the name server is and whether the launcher may start one.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NameServerSpec {
    /// `host:port` of the name server.
    #[serde(default = "default_ns_address")]
    pub address: String,
    /// Start `yarpserver` at `address` when no name server answers there.
    #[serde(default = "yes")]
    pub embedded: bool,
    /// Write yarp.conf naming `address` so that every module (and the user's `yarp`
    /// commands) find it.
    #[serde(default = "yes")]
    pub write_conf: bool,
    /// Seconds to wait for the embedded server to answer.
    #[serde(default = "default_ready_timeout")]
    pub timeout: f64,
}

fn default_ns_address() -> String {
    "127.0.0.1:10000".into()
}

impl Default for NameServerSpec {
    fn default() -> Self {
        NameServerSpec {
            address: default_ns_address(),
            embedded: true,
            write_conf: true,
            timeout: default_ready_timeout(),
        }
    }
}

/// What the dashboard shows; every field optional.
#[derive(Debug, Clone, Default, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DashboardSpec {
    /// `host:port` to serve on (the `--dashboard` flag overrides it).
    pub address: Option<String>,
    /// Port whose numeric values are plotted (e.g. `/icub/left_arm/state:o`).
    pub plot: Option<String>,
    /// Control-board RPC port used for joint names (`[get] [axes]`), e.g. `/icub/left_arm/rpc:i`.
    pub plot_rpc: Option<String>,
    /// Frame-grabber image port shown as the camera view.
    pub camera: Option<String>,
    /// Gateway diagnostics port (bridge health).
    pub diagnostics: Option<String>,
}

/// A whole launch config, after overrides and `${var}` expansion.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LaunchConfig {
    #[serde(default)]
    pub name: String,
    #[serde(default)]
    pub description: String,
    /// Defaults for `${name}` expansion.
    #[serde(default)]
    pub vars: BTreeMap<String, toml::Value>,
    #[serde(default)]
    pub name_server: NameServerSpec,
    #[serde(default)]
    pub dashboard: DashboardSpec,
    #[serde(default, rename = "module")]
    pub modules: Vec<Module>,
    #[serde(default, rename = "connection")]
    pub connections: Vec<ConnectionSpec>,
    /// Extra lines printed at start under "what next".
    #[serde(default)]
    pub hints: Vec<String>,
    /// Directory relative paths are resolved against (the config file's directory).
    #[serde(skip)]
    pub base_dir: PathBuf,
}

impl LaunchConfig {
    /// Loads a TOML or yarpmanager XML file (by extension), applying `--set` overrides.
    pub fn load(path: &Path, overrides: &[String]) -> Result<LaunchConfig, ConfigError> {
        let text = std::fs::read_to_string(path).map_err(|source| ConfigError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        let base = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let base = std::fs::canonicalize(&base).unwrap_or(base);
        let doc = if path.extension().is_some_and(|e| e == "xml") {
            crate::xmlapp::to_document(&text).map_err(|message| ConfigError::Syntax {
                path: path.to_path_buf(),
                message,
            })?
        } else {
            text.parse::<toml::Table>()
                .map_err(|e| ConfigError::Syntax {
                    path: path.to_path_buf(),
                    message: e.to_string(),
                })?
        };
        LaunchConfig::from_document(doc, path, &base, overrides)
    }

    /// Builds a config from a parsed TOML document: overrides, deserialization,
    /// expansion, validation.
    pub fn from_document(
        mut doc: toml::Table,
        path: &Path,
        base: &Path,
        overrides: &[String],
    ) -> Result<LaunchConfig, ConfigError> {
        for o in overrides {
            apply_override(&mut doc, o)?;
        }
        let mut cfg: LaunchConfig =
            toml::Value::Table(doc)
                .try_into()
                .map_err(|e: toml::de::Error| ConfigError::Syntax {
                    path: path.to_path_buf(),
                    message: e.to_string(),
                })?;
        cfg.base_dir = base.to_path_buf();
        cfg.expand(path)?;
        cfg.validate(path)?;
        Ok(cfg)
    }

    fn expand(&mut self, path: &Path) -> Result<(), ConfigError> {
        // Built-ins first; `[vars]` may use them and earlier vars; then the name-server
        // address (which may use vars) gives `ns_host` / `ns_port` to everything else.
        let mut vars = HashMap::new();
        vars.insert(
            "config_dir".to_string(),
            self.base_dir.display().to_string(),
        );
        for (k, v) in &self.vars {
            let raw = match v {
                toml::Value::String(s) => s.clone(),
                other => other.to_string(),
            };
            let v = expand_str(&raw, &vars, &self.base_dir, path, &format!("vars.{k}"))?;
            vars.insert(k.clone(), v);
        }
        let base = self.base_dir.clone();
        let base = base.as_path();
        self.name_server.address = expand_str(
            &self.name_server.address,
            &vars,
            base,
            path,
            "name_server.address",
        )?;
        if let Some((host, port)) = self.name_server.address.rsplit_once(':') {
            vars.insert("ns_host".into(), host.to_string());
            vars.insert("ns_port".into(), port.to_string());
        }
        let x = |s: &mut String, ctx: &str| -> Result<(), ConfigError> {
            *s = expand_str(s, &vars, base, path, ctx)?;
            Ok(())
        };
        let d = &mut self.dashboard;
        for (f, ctx) in [
            (&mut d.address, "dashboard.address"),
            (&mut d.plot, "dashboard.plot"),
            (&mut d.plot_rpc, "dashboard.plot_rpc"),
            (&mut d.camera, "dashboard.camera"),
            (&mut d.diagnostics, "dashboard.diagnostics"),
        ] {
            if let Some(s) = f {
                x(s, ctx)?;
            }
        }
        for m in &mut self.modules {
            let ctx = format!("module {}", m.name);
            x(&mut m.program, &ctx)?;
            // An argument that expands to nothing is left out (optional arguments).
            let mut args = Vec::with_capacity(m.args.len());
            for a in &m.args {
                let e = expand_str(a, &vars, base, path, &ctx)?;
                if a.is_empty() || !e.is_empty() {
                    args.push(e);
                }
            }
            m.args = args;
            for v in m.env.values_mut() {
                x(v, &ctx)?;
            }
            if let Some(c) = &mut m.cwd {
                x(c, &ctx)?;
            }
            for p in &mut m.wait_ports {
                x(p, &ctx)?;
            }
            if let Some(r) = &mut m.ready {
                for s in [&mut r.port, &mut r.tcp, &mut r.log].into_iter().flatten() {
                    x(s, &ctx)?;
                }
            }
        }
        for c in &mut self.connections {
            x(&mut c.from, "connection.from")?;
            x(&mut c.to, "connection.to")?;
        }
        for h in &mut self.hints {
            x(h, "hints")?;
        }
        Ok(())
    }

    fn validate(&self, path: &Path) -> Result<(), ConfigError> {
        let bad = |message: String| ConfigError::Invalid {
            path: path.to_path_buf(),
            message,
        };
        crate::plan::parse_address(&self.name_server.address)
            .map_err(|e| bad(format!("name_server.address: {e}")))?;
        let mut names = std::collections::HashSet::new();
        for m in &self.modules {
            if m.name.is_empty() || m.name.contains(char::is_whitespace) {
                return Err(bad(format!(
                    "module name {:?} must be non-empty without spaces",
                    m.name
                )));
            }
            if !names.insert(m.name.as_str()) {
                return Err(bad(format!("module {} is defined twice", m.name)));
            }
            if m.program.is_empty() {
                return Err(bad(format!("module {}: program is empty", m.name)));
            }
            if let Some(r) = &m.ready {
                r.check()
                    .map_err(|e| bad(format!("module {}: {e}", m.name)))?;
            }
        }
        for c in &self.connections {
            for p in [&c.from, &c.to] {
                if !p.starts_with('/') {
                    return Err(bad(format!("connection port {p:?} must start with '/'")));
                }
            }
        }
        crate::plan::start_order(&self.modules).map_err(|e| bad(e.to_string()))?;
        Ok(())
    }

    /// The modules that will be started, in start order.
    pub fn enabled_modules(&self) -> Vec<&Module> {
        let order = crate::plan::start_order(&self.modules).unwrap_or_default();
        order
            .into_iter()
            .map(|i| &self.modules[i])
            .filter(|m| m.enabled)
            .collect()
    }
}

/// Replaces `${name}` in `s`: a variable; `${env:NAME}`, from the environment (empty when
/// unset); `${bin:PROGRAM}`, the path of a program found as modules' programs are;
/// `${robot:NAME}`, a robot's directory of robots-configuration ([`find_robot`]). `$$` is
/// a `$`.
pub fn expand_str(
    s: &str,
    vars: &HashMap<String, String>,
    base: &Path,
    path: &Path,
    context: &str,
) -> Result<String, ConfigError> {
    let mut out = String::with_capacity(s.len());
    let mut rest = s;
    while let Some(i) = rest.find('$') {
        out.push_str(&rest[..i]);
        let after = &rest[i + 1..];
        if let Some(tail) = after.strip_prefix('$') {
            out.push('$');
            rest = tail;
        } else if let Some(body) = after.strip_prefix('{') {
            let end = body.find('}').ok_or_else(|| ConfigError::Invalid {
                path: path.to_path_buf(),
                message: format!("unclosed ${{ in {context}: {s:?}"),
            })?;
            let name = &body[..end];
            let invalid = |message: String| ConfigError::Invalid {
                path: path.to_path_buf(),
                message: format!("{context}: {message}"),
            };
            let value = if let Some(env) = name.strip_prefix("env:") {
                std::env::var(env).unwrap_or_default()
            } else if let Some(robot) = name.strip_prefix("robot:") {
                find_robot(robot, base, &|k| std::env::var(k).ok())
                    .map_err(invalid)?
                    .display()
                    .to_string()
            } else if let Some(prog) = name.strip_prefix("bin:") {
                crate::programs::resolve(prog, base)
                    .map_err(|e| invalid(e.to_string()))?
                    .display()
                    .to_string()
            } else {
                vars.get(name)
                    .cloned()
                    .ok_or_else(|| ConfigError::UnknownVar {
                        path: path.to_path_buf(),
                        name: name.to_string(),
                        context: context.to_string(),
                    })?
            };
            out.push_str(&value);
            rest = &body[end + 1..];
        } else {
            out.push('$');
            rest = after;
        }
    }
    out.push_str(rest);
    Ok(out)
}

/// Applies one `--set key=value`. A key without a dot sets `vars.key`. A dotted key walks
/// tables; after `module` or `connection` the next segment picks the entry by its `name`
/// (modules) or index (both). The value is read as TOML when it parses (numbers, booleans,
/// arrays), else taken as a string.
pub fn apply_override(doc: &mut toml::Table, spec: &str) -> Result<(), ConfigError> {
    let (key, raw) = spec
        .split_once('=')
        .ok_or_else(|| ConfigError::BadOverride(spec.to_string()))?;
    let key = key.trim();
    if key.is_empty() {
        return Err(ConfigError::BadOverride(spec.to_string()));
    }
    let value = parse_value(raw);
    let path: Vec<&str> = if key.contains('.') {
        key.split('.').collect()
    } else {
        vec!["vars", key]
    };
    let err = |message: String| ConfigError::Override {
        key: key.to_string(),
        message,
    };
    let mut table = doc;
    let mut i = 0;
    while i + 1 < path.len() {
        let seg = path[i];
        let entry = table
            .entry(seg.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        table = match entry {
            toml::Value::Table(t) => t,
            toml::Value::Array(items) => {
                i += 1;
                let pick = path[i];
                let found = items
                    .iter()
                    .position(|v| v.get("name").and_then(|n| n.as_str()) == Some(pick));
                let idx = match found.or_else(|| pick.parse::<usize>().ok()) {
                    Some(idx) if idx < items.len() => idx,
                    _ => return Err(err(format!("no {seg} entry named {pick}"))),
                };
                if i + 1 >= path.len() {
                    return Err(err(format!("name a field of {seg} {pick}")));
                }
                match &mut items[idx] {
                    toml::Value::Table(t) => t,
                    _ => return Err(err(format!("{seg} {pick} is not a table"))),
                }
            }
            _ => return Err(err(format!("{seg} is not a table"))),
        };
        i += 1;
    }
    table.insert(path[path.len() - 1].to_string(), value);
    Ok(())
}

fn parse_value(raw: &str) -> toml::Value {
    let probe = format!("v = {raw}");
    match probe.parse::<toml::Table>() {
        Ok(mut t) => t
            .remove("v")
            .unwrap_or_else(|| toml::Value::String(raw.into())),
        Err(_) => toml::Value::String(raw.to_string()),
    }
}

/// The directory of robot `name` as C++'s `ResourceFinder` finds an installed
/// robots-configuration: `robots/<name>` under `YARP_DATA_HOME`, each of `YARP_DATA_DIRS`,
/// then the XDG defaults (`$XDG_DATA_HOME/yarp` or `~/.local/share/yarp`, each of
/// `$XDG_DATA_DIRS` + `/yarp` or `/usr/local/share/yarp` and `/usr/share/yarp`); failing
/// those, the copy beside this repository (`../shared/robots-configuration`, in service or
/// under `robots-icebox/`), relative to the configs' directory `base`.
pub fn find_robot(
    name: &str,
    base: &Path,
    env: &dyn Fn(&str) -> Option<String>,
) -> Result<PathBuf, String> {
    let var = |k: &str| env(k).filter(|v| !v.is_empty());
    let mut data: Vec<PathBuf> = Vec::new();
    data.extend(var("YARP_DATA_HOME").map(PathBuf::from));
    if let Some(dirs) = var("YARP_DATA_DIRS") {
        data.extend(dirs.split(':').filter(|d| !d.is_empty()).map(PathBuf::from));
    }
    match var("XDG_DATA_HOME") {
        Some(d) => data.push(Path::new(&d).join("yarp")),
        None => data.extend(var("HOME").map(|h| Path::new(&h).join(".local/share/yarp"))),
    }
    let xdg = var("XDG_DATA_DIRS").unwrap_or_else(|| "/usr/local/share:/usr/share".into());
    data.extend(
        xdg.split(':')
            .filter(|d| !d.is_empty())
            .map(|d| Path::new(d).join("yarp")),
    );
    let shared = base.join("../../shared/robots-configuration");
    let beside = [shared.clone(), shared.join("robots-icebox")];
    data.iter()
        .map(|d| d.join("robots").join(name))
        .chain(beside.iter().map(|d| d.join(name)))
        .find(|d| d.is_dir())
        .ok_or_else(|| {
            format!(
                "robot {name} not found: no robots/{name} in the YARP data directories \
                 (YARP_DATA_HOME, YARP_DATA_DIRS, ~/.local/share/yarp, /usr/local/share/yarp, \
                 /usr/share/yarp) nor in ../shared/robots-configuration; give its directory \
                 with --set robot_dir=DIR"
            )
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn load(text: &str, overrides: &[&str]) -> Result<LaunchConfig, ConfigError> {
        let doc: toml::Table = text.parse().unwrap();
        let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
        LaunchConfig::from_document(doc, Path::new("t.toml"), Path::new("/base"), &o)
    }

    const DEMO: &str = r#"
name = "demo"
[vars]
part = "/demo"
[name_server]
address = "127.0.0.1:10123"
[[module]]
name = "reader"
program = "yarp"
args = ["read", "${part}/in"]
ready = { port = "${part}/in" }
restart = "on-failure"
[[module]]
name = "writer"
program = "yarp"
args = ["write", "${part}/out"]
after = ["reader"]
[[connection]]
from = "${part}/out"
to = "${part}/in"
carrier = "udp"
"#;

    #[test]
    fn loads_and_expands() {
        let c = load(DEMO, &[]).unwrap();
        assert_eq!(c.modules[0].args, ["read", "/demo/in"]);
        assert_eq!(c.modules[0].restart, RestartPolicy::OnFailure);
        assert_eq!(
            c.modules[0].ready.as_ref().unwrap().check().unwrap(),
            ReadyCheck::Port("/demo/in".into())
        );
        assert_eq!(c.connections[0].carrier.as_deref(), Some("udp"));
        let order: Vec<_> = c.enabled_modules().iter().map(|m| &m.name).collect();
        assert_eq!(order, ["reader", "writer"]);
    }

    #[test]
    fn overrides_vars_tables_and_modules() {
        let c = load(
            DEMO,
            &[
                "part=/other",
                "name_server.address=127.0.0.1:999",
                "module.writer.enabled=false",
                "module.reader.args=[\"read\", \"/x\"]",
            ],
        )
        .unwrap();
        assert_eq!(c.connections[0].from, "/other/out");
        assert_eq!(c.name_server.address, "127.0.0.1:999");
        assert!(!c.modules[1].enabled);
        assert_eq!(c.modules[0].args, ["read", "/x"]);
        assert_eq!(c.enabled_modules().len(), 1);
    }

    #[test]
    fn bad_input_names_the_problem() {
        let e = load(DEMO, &["module.nope.args=1"]).unwrap_err().to_string();
        assert!(e.contains("no module entry named nope"), "{e}");
        let e = load(DEMO, &["novalue"]).unwrap_err().to_string();
        assert!(e.contains("expected key=value"), "{e}");
        let e = load("[[module]]\nname='a'\nprogram='x'\nargs=['${nope}']", &[])
            .unwrap_err()
            .to_string();
        assert!(e.contains("unknown variable ${nope} in module a"), "{e}");
        let e = load("[[module]]\nname='a'\nprogram='x'\nbogus=1", &[])
            .unwrap_err()
            .to_string();
        assert!(e.contains("bogus"), "{e}");
        let e = load(
            "[[module]]\nname='a'\nprogram='x'\nready={port='/a', tcp='h:1'}",
            &[],
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("only one of"), "{e}");
        let e = load(
            "[[module]]\nname='a'\nprogram='x'\n[[module]]\nname='a'\nprogram='y'",
            &[],
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("defined twice"), "{e}");
        let e = load("[name_server]\naddress='nowhere'", &[])
            .unwrap_err()
            .to_string();
        assert!(e.contains("name_server.address"), "{e}");
    }

    #[test]
    fn empty_expansions_drop_arguments() {
        let text = "[vars]\nopt = ''\n[[module]]\nname='a'\nprogram='x'\nargs=['1', '${opt}', '', '${ns_port}']";
        let c = load(text, &[]).unwrap();
        assert_eq!(c.modules[0].args, ["1", "", "10000"]);
        let c = load(text, &["opt=--flag"]).unwrap();
        assert_eq!(c.modules[0].args, ["1", "--flag", "", "10000"]);
        let c = load("[[module]]\nname='a'\nprogram='x'\nargs=['${bin:sh}']", &[]).unwrap();
        assert!(c.modules[0].args[0].ends_with("/sh"));
    }

    #[test]
    fn robots_are_found_as_cpp_finds_them_then_beside_the_repository() {
        let data = tempfile::tempdir().unwrap();
        let installed = data.path().join("robots/ergoCubSN001");
        std::fs::create_dir_all(&installed).unwrap();
        let configs = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let dirs = data.path().display().to_string();
        let env = |k: &str| (k == "YARP_DATA_DIRS").then(|| dirs.clone());
        assert_eq!(
            find_robot("ergoCubSN001", &configs, &env).unwrap(),
            installed
        );
        // not installed: the copy beside the repository, in service or retired (the
        // system's data directories replaced by an empty one)
        let empty = tempfile::tempdir().unwrap();
        let empty = empty.path().display().to_string();
        let none = |k: &str| (k == "XDG_DATA_DIRS").then(|| empty.clone());
        let beside = find_robot("iCubGenova02", &configs, &none).unwrap();
        assert!(beside.ends_with("shared/robots-configuration/iCubGenova02"));
        let err = find_robot("noSuchRobot", &configs, &none).unwrap_err();
        assert!(err.contains("--set robot_dir=DIR"), "{err}");
    }

    #[test]
    fn expansion_rules() {
        let vars = HashMap::from([("a".to_string(), "1".to_string())]);
        let p = Path::new("f");
        assert_eq!(
            expand_str("x${a}y$$z$", &vars, p, p, "t").unwrap(),
            "x1y$z$"
        );
        assert!(expand_str("${a", &vars, p, p, "t").is_err());
    }
}
