//! ROS 2's command-line arguments (`--ros-args ... [--]`), as rcl reads them, so that
//! `ros2 run`/`ros2 launch` can start the gateway like any ROS node: `-r __node:=NAME`,
//! `-r __ns:=/NS`, name remaps (`-r from:=to`, `-r node:from:=to`), parameters (`-p
//! name:=value`, `--params-file FILE`), `--log-level [name:=]LEVEL`, the SROS2 enclave
//! (`-e`/`--enclave`, [`crate::security`]), and the flags rcl takes that change nothing
//! here (`--disable-*`/`--enable-*` logging) are accepted.

use ros2_client::ParameterValue;
use std::ffi::OsString;
use std::path::PathBuf;

/// One `-r` rule.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Remap {
    /// `node:from:=to` applies to that node only.
    pub node: Option<String>,
    pub from: String,
    pub to: String,
}

/// What `--ros-args` said.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RosArgs {
    pub node_name: Option<String>,
    pub namespace: Option<String>,
    pub remaps: Vec<Remap>,
    pub params: Vec<(String, ParameterValue)>,
    pub params_files: Vec<PathBuf>,
    /// `--log-level`: `(logger, level)`; `None` is the default logger.
    pub log_levels: Vec<(Option<String>, String)>,
    /// `-e`/`--enclave`: the SROS2 enclave of the process ([`crate::security`]).
    pub enclave: Option<String>,
}

#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum RosArgsError {
    #[error("--ros-args: `{0}` needs a value after it")]
    Missing(String),
    #[error("--ros-args: `{flag} {value}`: expected `{expected}`")]
    Bad {
        flag: String,
        value: String,
        expected: &'static str,
    },
    #[error("--ros-args: unknown argument `{0}`")]
    Unknown(String),
    #[error("--params-file {file}: {why}")]
    ParamsFile { file: String, why: String },
}

/// Splits the command line into the program's arguments and the ROS ones (every
/// `--ros-args` up to the next `--` or the end; there may be several).
pub fn split(args: impl IntoIterator<Item = OsString>) -> (Vec<OsString>, Vec<String>) {
    let (mut ours, mut ros) = (Vec::new(), Vec::new());
    let mut in_ros = false;
    for a in args {
        if a == "--ros-args" {
            in_ros = true;
        } else if in_ros && a == "--" {
            in_ros = false;
        } else if in_ros {
            ros.push(a.to_string_lossy().into_owned());
        } else {
            ours.push(a);
        }
    }
    (ours, ros)
}

/// Parses the ROS arguments (what [`split`] returned).
pub fn parse(ros: &[String]) -> Result<RosArgs, RosArgsError> {
    let mut out = RosArgs::default();
    let mut it = ros.iter();
    while let Some(flag) = it.next() {
        let mut value = || {
            it.next()
                .cloned()
                .ok_or_else(|| RosArgsError::Missing(flag.clone()))
        };
        match flag.as_str() {
            "-r" | "--remap" => {
                let v = value()?;
                let (lhs, to) = v
                    .split_once(":=")
                    .ok_or_else(|| bad(flag, &v, "from:=to"))?;
                let (node, from) = match lhs.split_once(':') {
                    Some((n, f)) => (Some(n.to_string()), f),
                    None => (None, lhs),
                };
                match from {
                    "__node" | "__name" => out.node_name = Some(to.to_string()),
                    "__ns" => out.namespace = Some(to.to_string()),
                    _ => out.remaps.push(Remap {
                        node,
                        from: from.to_string(),
                        to: to.to_string(),
                    }),
                }
            }
            "-p" | "--param" => {
                let v = value()?;
                let (name, text) = v
                    .split_once(":=")
                    .ok_or_else(|| bad(flag, &v, "name:=value"))?;
                out.params.push((name.to_string(), parameter_value(text)));
            }
            "--params-file" => out.params_files.push(PathBuf::from(value()?)),
            "--log-level" => {
                let v = value()?;
                match v.split_once(":=") {
                    Some((logger, level)) => out
                        .log_levels
                        .push((Some(logger.to_string()), level.to_string())),
                    None => out.log_levels.push((None, v)),
                }
            }
            "-e" | "--enclave" => out.enclave = Some(value()?),
            "--log-config-file" | "--log-file-name" => {
                value()?;
            }
            f if f.starts_with("--enable-") || f.starts_with("--disable-") => {}
            f => return Err(RosArgsError::Unknown(f.to_string())),
        }
    }
    Ok(out)
}

fn bad(flag: &str, value: &str, expected: &'static str) -> RosArgsError {
    RosArgsError::Bad {
        flag: flag.to_string(),
        value: value.to_string(),
        expected,
    }
}

/// A parameter's value as rcl reads `-p`: a YAML scalar or flow sequence.
pub fn parameter_value(text: &str) -> ParameterValue {
    match yaml_rust2::YamlLoader::load_from_str(text)
        .ok()
        .and_then(|d| d.into_iter().next())
    {
        Some(y) => from_yaml(&y).unwrap_or_else(|| ParameterValue::String(text.to_string())),
        None => ParameterValue::String(text.to_string()),
    }
}

fn from_yaml(y: &yaml_rust2::Yaml) -> Option<ParameterValue> {
    use yaml_rust2::Yaml;
    Some(match y {
        Yaml::Boolean(b) => ParameterValue::Boolean(*b),
        Yaml::Integer(i) => ParameterValue::Integer(*i),
        Yaml::Real(_) => ParameterValue::Double(y.as_f64()?),
        Yaml::String(s) => ParameterValue::String(s.clone()),
        Yaml::Array(a) if a.iter().all(|v| matches!(v, Yaml::Boolean(_))) && !a.is_empty() => {
            ParameterValue::BooleanArray(a.iter().filter_map(Yaml::as_bool).collect())
        }
        Yaml::Array(a) if a.iter().all(|v| matches!(v, Yaml::Integer(_))) && !a.is_empty() => {
            ParameterValue::IntegerArray(a.iter().filter_map(Yaml::as_i64).collect())
        }
        Yaml::Array(a)
            if a.iter()
                .all(|v| matches!(v, Yaml::Real(_) | Yaml::Integer(_)))
                && !a.is_empty() =>
        {
            ParameterValue::DoubleArray(
                a.iter()
                    .filter_map(|v| v.as_f64().or_else(|| v.as_i64().map(|i| i as f64)))
                    .collect(),
            )
        }
        Yaml::Array(a) => ParameterValue::StringArray(
            a.iter()
                .map(|v| v.as_str().map(str::to_string).unwrap_or_default())
                .collect(),
        ),
        _ => return None,
    })
}

/// The parameters a `--params-file` gives node `/ns/name` (rcl's layout: `node:` or `/**:`,
/// then `ros__parameters:`, nested keys joined with `.`).
pub fn params_from_file(
    text: &str,
    fqn: &str,
    file: &str,
) -> Result<Vec<(String, ParameterValue)>, RosArgsError> {
    use yaml_rust2::Yaml;
    let err = |why: String| RosArgsError::ParamsFile {
        file: file.to_string(),
        why,
    };
    let docs = yaml_rust2::YamlLoader::load_from_str(text).map_err(|e| err(e.to_string()))?;
    let mut out = Vec::new();
    let Some(Yaml::Hash(nodes)) = docs.into_iter().next() else {
        return Ok(out);
    };
    let name = fqn.rsplit('/').next().unwrap_or(fqn);
    for (key, body) in nodes {
        let Some(k) = key.as_str() else { continue };
        let matches = k == "/**"
            || k == fqn
            || k == name
            || k.trim_start_matches('/') == fqn.trim_start_matches('/');
        if !matches {
            continue;
        }
        if let Some(Yaml::Hash(params)) = body
            .as_hash()
            .and_then(|h| h.get(&Yaml::String("ros__parameters".into())))
            .cloned()
        {
            flatten("", &params, &mut out);
        }
    }
    Ok(out)
}

fn flatten(prefix: &str, h: &yaml_rust2::yaml::Hash, out: &mut Vec<(String, ParameterValue)>) {
    for (k, v) in h {
        let Some(k) = k.as_str() else { continue };
        let name = if prefix.is_empty() {
            k.to_string()
        } else {
            format!("{prefix}.{k}")
        };
        match v {
            yaml_rust2::Yaml::Hash(inner) => flatten(&name, inner, out),
            v => {
                if let Some(p) = from_yaml(v) {
                    out.push((name, p));
                }
            }
        }
    }
}

impl RosArgs {
    /// A ROS name (topic or service) after the remap rules that apply to node `node_name`
    /// in namespace `ns` (rcl compares names resolved against the node's namespace; the
    /// first rule that matches wins).
    pub fn remap(&self, ns: &str, node_name: &str, name: &str) -> String {
        let resolved = resolve(ns, name);
        for r in &self.remaps {
            if r.node.as_deref().is_some_and(|n| n != node_name) {
                continue;
            }
            if resolve(ns, &r.from) == resolved {
                return resolve(ns, &r.to);
            }
        }
        name.to_string()
    }
}

/// `name` resolved against namespace `ns` (absolute names stay).
fn resolve(ns: &str, name: &str) -> String {
    if name.starts_with('/') {
        name.to_string()
    } else if ns == "/" || ns.is_empty() {
        format!("/{name}")
    } else {
        format!("{}/{name}", ns.trim_end_matches('/'))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(s: &str) -> Vec<String> {
        s.split_whitespace().map(str::to_string).collect()
    }

    #[test]
    fn launch_ros_s_arguments_are_split_off_and_read() {
        let argv = [
            "gw",
            "--mappings",
            "m.toml",
            "--ros-args",
            "-r",
            "__node:=gw2",
            "-r",
            "__ns:=/lab",
            "--enclave",
            "/lab/gw",
            "--",
            "--check",
        ];
        let (ours, ros) = split(argv.iter().map(OsString::from));
        assert_eq!(
            ours,
            ["gw", "--mappings", "m.toml", "--check"]
                .map(OsString::from)
                .to_vec()
        );
        let a = parse(&ros).unwrap();
        assert_eq!(a.node_name.as_deref(), Some("gw2"));
        assert_eq!(a.namespace.as_deref(), Some("/lab"));
        assert_eq!(a.enclave.as_deref(), Some("/lab/gw"));
        let a = parse(&args("-r chatter:=talk -r other:x:=y -p rate:=2.5 -p on:=true -p n:=3 -p s:=hi -p l:=[1,2] --log-level debug -e /e --disable-rosout-logs")).unwrap();
        assert_eq!(a.remaps.len(), 2);
        assert_eq!(a.params[0], ("rate".into(), ParameterValue::Double(2.5)));
        assert_eq!(a.params[1].1, ParameterValue::Boolean(true));
        assert_eq!(a.params[2].1, ParameterValue::Integer(3));
        assert_eq!(a.params[3].1, ParameterValue::String("hi".into()));
        assert_eq!(a.params[4].1, ParameterValue::IntegerArray(vec![1, 2]));
        assert_eq!(a.log_levels, vec![(None, "debug".to_string())]);
        assert!(parse(&args("-r nothing")).is_err());
        assert!(parse(&args("-p")).is_err());
        assert!(parse(&args("--bogus")).is_err());
    }

    #[test]
    fn remaps_compare_resolved_names_and_respect_node_rules() {
        let a = parse(&args("-r chatter:=talk -r other:/x:=/y -r gw:/a:=/b")).unwrap();
        assert_eq!(a.remap("/lab", "gw", "chatter"), "/lab/talk");
        assert_eq!(a.remap("/lab", "gw", "/lab/chatter"), "/lab/talk");
        assert_eq!(a.remap("/", "gw", "/x"), "/x", "another node's rule");
        assert_eq!(a.remap("/", "gw", "/a"), "/b");
        assert_eq!(a.remap("/", "gw", "/untouched"), "/untouched");
    }

    #[test]
    fn a_params_file_gives_the_node_its_parameters() {
        let yaml = "/**:\n  ros__parameters:\n    use_sim_time: false\n/lab/gw:\n  ros__parameters:\n    limits:\n      max: 2.0\n    names: [a, b]\nother:\n  ros__parameters:\n    x: 1\n";
        let p = params_from_file(yaml, "/lab/gw", "f.yaml").unwrap();
        assert_eq!(
            p[0],
            ("use_sim_time".into(), ParameterValue::Boolean(false))
        );
        assert!(p.contains(&("limits.max".into(), ParameterValue::Double(2.0))));
        assert!(p.contains(&(
            "names".into(),
            ParameterValue::StringArray(vec!["a".into(), "b".into()])
        )));
        assert!(!p.iter().any(|(n, _)| n == "x"));
    }
}
