//! Reads the yarprobotinterface DTD 3.x (C++ `XMLReaderFileV3`) from an element tree.
//!
//! The rules, as C++ YARP 3.12 applies them:
//! - `<robot name [build] [portprefix] [reverse-shutdown-action-order]>`; `portprefix`
//!   defaults to the name, and a `portprefix` given on the command line wins.
//! - Under the robot: `<device>`, `<devices>` (whose own params are prepended to each of
//!   its devices), or parameters of the robot itself.
//! - Every device first gets `robotName` = the port prefix, then its params in order.
//! - `<param name [extern-name]>text</param>`: `extern-name` takes the value from the
//!   command line when given there; `${portprefix}` in the text becomes the prefix.
//! - `<group name>` holds params (nested groups allowed) -> `(name (k v) ...)`.
//! - `<paramlist name><elem name>text</elem>...` -> `name` = `(e1 e2 ...)` plus one
//!   param per element.
//! - `<subdevice type>` -> `subdevice` = type, followed by its params.
//! - `<params>` is a transparent container (the root of an included params file).
//! - `<action phase level type>` (or several in `<actions>`) with params.

use super::error::{Location, XmlError};
use super::model::*;
use super::tree::{self, Element};
use std::path::Path;
use yarp_proto::{Property, Value};

/// A robot read from XML, with the warnings C++ would print while reading it.
#[derive(Debug, Clone)]
pub struct LoadedRobot {
    pub robot: Robot,
    pub warnings: Vec<String>,
}

/// Reads the robot file `path` and everything it includes. `config` holds the
/// command-line options (`portprefix`, values for `extern-name` params).
pub fn read_robot_file(path: &Path, config: &Property) -> Result<LoadedRobot, XmlError> {
    let doc = tree::load_file(path, &include_tags(config))?;
    read_document(&doc, &path.display().to_string(), config)
}

/// Reads a robot from XML text; includes resolve against `base_dir`.
pub fn read_robot_str(
    text: &str,
    base_dir: &Path,
    config: &Property,
) -> Result<LoadedRobot, XmlError> {
    let doc = tree::load_str(text, "<string>", base_dir, &include_tags(config))?;
    read_document(&doc, "<string>", config)
}

fn read_document(
    doc: &tree::Document,
    file: &str,
    config: &Property,
) -> Result<LoadedRobot, XmlError> {
    let mut reader = Reader {
        config: config.clone(),
        warnings: Vec::new(),
        portprefix: String::new(),
        robot_name: String::new(),
        build: 0,
    };
    reader.check_dtd(doc.doctype.as_deref(), file, &doc.root.at)?;
    let robot = reader.robot(&doc.root)?;
    Ok(LoadedRobot {
        robot,
        warnings: reader.warnings,
    })
}

struct Reader {
    config: Property,
    warnings: Vec<String>,
    portprefix: String,
    robot_name: String,
    build: u32,
}

/// TinyXML's `QueryBoolAttribute` spellings.
fn parse_bool(s: &str) -> Option<bool> {
    match s {
        "true" | "TRUE" | "True" | "yes" | "YES" | "Yes" | "1" => Some(true),
        "false" | "FALSE" | "False" | "no" | "NO" | "No" | "0" => Some(false),
        _ => None,
    }
}

/// TinyXML's `QueryIntAttribute` (leading integer, as `sscanf("%d")`) restricted to >= 0.
fn parse_unsigned(s: &str) -> Option<u32> {
    let t = s.trim_start();
    let digits: String = t
        .char_indices()
        .take_while(|(i, c)| c.is_ascii_digit() || (*i == 0 && (*c == '+' || *c == '-')))
        .map(|(_, c)| c)
        .collect();
    digits
        .parse::<i64>()
        .ok()
        .and_then(|v| u32::try_from(v).ok())
}

/// The command line's `enable_tags` / `disable_tags`: C++ takes a list,
/// `--enable_tags "(enable_ros2 other)"`; a single word is taken as well.
pub fn include_tags(config: &Property) -> tree::IncludeTags {
    let set = |key: &str| {
        config
            .find(key)
            .map(|v| {
                v.to_string_bare()
                    .split_ascii_whitespace()
                    .map(str::to_owned)
                    .collect()
            })
            .unwrap_or_default()
    };
    tree::IncludeTags {
        enable: set("enable_tags"),
        disable: set("disable_tags"),
    }
}

impl Reader {
    fn warn(&mut self, at: &Location, msg: impl AsRef<str>) {
        let line = format!("{at}: {}", msg.as_ref());
        tracing::warn!("{line}");
        self.warnings.push(line);
    }

    /// C++ 3.12 reads DTD 3.x; 1.x is refused unless explicitly allowed, and no DTD
    /// means 3.0 (with a warning).
    fn check_dtd(
        &mut self,
        doctype: Option<&str>,
        file: &str,
        at: &Location,
    ) -> Result<(), XmlError> {
        let Some(doctype) = doctype else {
            self.warn(at, "no DTD found; assuming yarprobotinterface 3.0");
            return Ok(());
        };
        let Some(version) = doctype
            .split("yarprobotinterface")
            .nth(1)
            .and_then(|rest| rest.split_whitespace().next())
            .map(|v| v.trim_end_matches("//EN\"").to_string())
        else {
            self.warn(at, "DOCTYPE is not a yarprobotinterface DTD; assuming 3.0");
            return Ok(());
        };
        let major = version.split(['.', '/']).next().unwrap_or("");
        if major != "3" {
            return Err(XmlError::UnsupportedDtd {
                file: file.to_string(),
                version,
            });
        }
        let kind = doctype
            .trim_start_matches("<!DOCTYPE")
            .split_whitespace()
            .next()
            .unwrap_or("");
        if kind != "robot" {
            self.warn(
                at,
                format!("expected a document of type robot, found {kind}"),
            );
        }
        Ok(())
    }

    fn robot(&mut self, el: &Element) -> Result<Robot, XmlError> {
        if el.name != "robot" {
            return Err(XmlError::syntax(
                &el.at,
                format!("root element should be \"robot\", found \"{}\"", el.name),
            ));
        }
        let name = el
            .attr("name")
            .ok_or_else(|| {
                XmlError::syntax(
                    &el.at,
                    "\"robot\" element should contain the \"name\" attribute",
                )
            })?
            .to_string();
        let build = match el.attr("build").and_then(parse_unsigned) {
            Some(b) => b,
            None => {
                self.warn(
                    &el.at,
                    "\"robot\" element should contain the \"build\" attribute [unsigned int]; assuming 0",
                );
                0
            }
        };
        let portprefix = match self.config.find("portprefix") {
            Some(v) => v.to_string_bare(),
            None => {
                let p = match el.attr("portprefix") {
                    Some(p) => p.to_string(),
                    None => {
                        self.warn(
                            &el.at,
                            "\"robot\" element should contain the \"portprefix\" attribute; using \"name\"",
                        );
                        name.clone()
                    }
                };
                self.config.put("portprefix", Value::from(p.as_str()));
                p
            }
        };
        let reverse = match el.attr("reverse-shutdown-action-order") {
            None => false,
            Some(v) => parse_bool(v).ok_or_else(|| {
                XmlError::syntax(
                    &el.at,
                    "the \"reverse-shutdown-action-order\" attribute should be a bool",
                )
            })?,
        };
        self.portprefix = portprefix.clone();
        self.robot_name = name.clone();
        self.build = build;

        let mut robot = Robot {
            name,
            build,
            portprefix,
            reverse_shutdown_action_order: reverse,
            params: Vec::new(),
            devices: Vec::new(),
        };
        for child in &el.children {
            match child.name.as_str() {
                "device" | "devices" => robot.devices.extend(self.devices(child)?),
                _ => robot.params.extend(self.params(child)?),
            }
        }
        Ok(robot)
    }

    fn devices(&mut self, el: &Element) -> Result<Vec<Device>, XmlError> {
        match el.name.as_str() {
            "device" => Ok(vec![self.device(el)?]),
            "devices" => {
                let mut devices = Vec::new();
                let mut shared = Vec::new();
                for child in &el.children {
                    match child.name.as_str() {
                        "param" | "group" | "paramlist" | "params" => {
                            shared.extend(self.params(child)?)
                        }
                        _ => devices.extend(self.devices(child)?),
                    }
                }
                for d in &mut devices {
                    d.params.splice(0..0, shared.iter().cloned());
                }
                Ok(devices)
            }
            other => Err(self.forbidden_or(el, || {
                format!("expected \"device\" or \"devices\", found \"{other}\"")
            })),
        }
    }

    /// C++ 3.x forbids a `file` element outright; other unknown elements get `msg`.
    fn forbidden_or(&self, el: &Element, msg: impl FnOnce() -> String) -> XmlError {
        if el.name == "file" {
            XmlError::syntax(
                &el.at,
                "'file' is forbidden in yarprobotinterface DTD 3.0 (use xi:include)",
            )
        } else {
            XmlError::syntax(&el.at, msg())
        }
    }

    fn device(&mut self, el: &Element) -> Result<Device, XmlError> {
        let name = el.attr("name").ok_or_else(|| {
            XmlError::syntax(
                &el.at,
                "\"device\" element should contain the \"name\" attribute",
            )
        })?;
        let kind = el.attr("type").ok_or_else(|| {
            XmlError::syntax(
                &el.at,
                format!("\"device\" element {name} should contain the \"type\" attribute"),
            )
        })?;
        let mut device = Device {
            name: name.to_string(),
            kind: kind.to_string(),
            params: vec![Param::new("robotName", self.portprefix.clone())],
            actions: Vec::new(),
            at: el.at.clone(),
        };
        for child in &el.children {
            match child.name.as_str() {
                "action" | "actions" => device.actions.extend(self.actions(child)?),
                _ => device.params.extend(self.params(child)?),
            }
        }
        Ok(device)
    }

    fn params(&mut self, el: &Element) -> Result<Vec<Param>, XmlError> {
        match el.name.as_str() {
            "param" => Ok(vec![self.param(el)?]),
            "group" => Ok(vec![self.group(el)?]),
            "paramlist" => self.paramlist(el),
            "subdevice" => self.subdevice(el),
            "params" => {
                let mut out = Vec::new();
                for child in &el.children {
                    out.extend(self.params(child)?);
                }
                Ok(out)
            }
            other => Err(self.forbidden_or(el, || {
                format!(
                    "expected \"param\", \"group\", \"paramlist\", \"subdevice\", or \"params\", found \"{other}\""
                )
            })),
        }
    }

    fn param(&mut self, el: &Element) -> Result<Param, XmlError> {
        let name = el.attr("name").ok_or_else(|| {
            XmlError::syntax(
                &el.at,
                "\"param\" element should contain the \"name\" attribute",
            )
        })?;
        let text = el.text.as_deref().ok_or_else(|| {
            XmlError::syntax(
                &el.at,
                format!("\"param\" element should have a value [ \"name\" = {name} ]"),
            )
        })?;
        let external = el.attr("extern-name").and_then(|k| self.config.find(k));
        let value = match external {
            Some(Value::List(l)) => format!("({l})"),
            Some(v) => v.to_string_bare(),
            None => text.to_string(),
        };
        let value = value.replace("${portprefix}", &self.portprefix);
        Ok(Param::new(name, value))
    }

    fn group(&mut self, el: &Element) -> Result<Param, XmlError> {
        let name = el.attr("name").ok_or_else(|| {
            XmlError::syntax(
                &el.at,
                "\"group\" element should contain the \"name\" attribute",
            )
        })?;
        let mut members = Vec::new();
        for child in &el.children {
            members.extend(self.params(child)?);
        }
        if members.is_empty() {
            return Err(XmlError::syntax(
                &el.at,
                format!("\"group\" {name} cannot be empty"),
            ));
        }
        let value = members
            .iter()
            .map(|p| format!("({} {})", p.name, p.value))
            .collect::<Vec<_>>()
            .join(" ");
        Ok(Param::group(name, value))
    }

    fn paramlist(&mut self, el: &Element) -> Result<Vec<Param>, XmlError> {
        let name = el.attr("name").ok_or_else(|| {
            XmlError::syntax(
                &el.at,
                "\"paramlist\" element should contain the \"name\" attribute",
            )
        })?;
        let mut elems = Vec::new();
        for child in &el.children {
            if child.name != "elem" {
                return Err(XmlError::syntax(
                    &child.at,
                    format!("expected \"elem\", found \"{}\"", child.name),
                ));
            }
            let elem_name = child.attr("name").ok_or_else(|| {
                XmlError::syntax(
                    &child.at,
                    "\"elem\" element should contain the \"name\" attribute",
                )
            })?;
            let text = child.text.as_deref().ok_or_else(|| {
                XmlError::syntax(
                    &child.at,
                    format!("\"elem\" element should have a value [ \"name\" = {elem_name} ]"),
                )
            })?;
            elems.push(Param::new(elem_name, text));
        }
        let names = elems
            .iter()
            .map(|p| p.name.as_str())
            .collect::<Vec<_>>()
            .join(" ");
        let mut out = vec![Param::new(name, format!("({names})"))];
        out.extend(elems);
        Ok(out)
    }

    fn subdevice(&mut self, el: &Element) -> Result<Vec<Param>, XmlError> {
        let kind = el.attr("type").ok_or_else(|| {
            XmlError::syntax(
                &el.at,
                "\"subdevice\" element should contain the \"type\" attribute",
            )
        })?;
        let mut out = vec![Param::new("subdevice", kind)];
        for child in &el.children {
            // C++ copies name and value only: groups inside a subdevice lose their flag.
            out.extend(
                self.params(child)?
                    .into_iter()
                    .map(|p| Param::new(p.name, p.value)),
            );
        }
        Ok(out)
    }

    fn actions(&mut self, el: &Element) -> Result<Vec<Action>, XmlError> {
        match el.name.as_str() {
            "action" => Ok(vec![self.action(el)?]),
            _ => {
                let robot = el.attr("robot").unwrap_or("");
                if robot != self.robot_name {
                    let msg = format!(
                        "trying to import a file for the wrong robot; found \"{robot}\" instead of \"{}\"",
                        self.robot_name
                    );
                    self.warn(&el.at, msg);
                }
                let build = el.attr("build").and_then(parse_unsigned).unwrap_or(0);
                if build != self.build {
                    let msg = format!(
                        "importing a file for a different robot build; found {build} instead of {}",
                        self.build
                    );
                    self.warn(&el.at, msg);
                }
                let mut out = Vec::new();
                for child in &el.children {
                    out.extend(self.actions(child)?);
                }
                Ok(out)
            }
        }
    }

    fn action(&mut self, el: &Element) -> Result<Action, XmlError> {
        let phase = el.attr("phase").and_then(ActionPhase::parse).ok_or_else(|| {
            XmlError::syntax(
                &el.at,
                "\"action\" element should contain the \"phase\" attribute [startup|interrupt{1,2,3}|shutdown]",
            )
        })?;
        let kind = el.attr("type").and_then(ActionType::parse).ok_or_else(|| {
            XmlError::syntax(
                &el.at,
                "\"action\" element should contain the \"type\" attribute [configure|calibrate|attach|abort|detach|park|custom]",
            )
        })?;
        let level = el.attr("level").and_then(parse_unsigned).ok_or_else(|| {
            XmlError::syntax(
                &el.at,
                "\"action\" element should contain the \"level\" attribute [unsigned int]",
            )
        })?;
        let mut params = Vec::new();
        for child in &el.children {
            params.extend(self.params(child)?);
        }
        Ok(Action {
            phase,
            kind,
            level,
            params,
            at: el.at.clone(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEAD: &str = "<?xml version=\"1.0\"?>\n<!DOCTYPE robot PUBLIC \"-//YARP//DTD yarprobotinterface 3.0//EN\" \"http://www.yarp.it/DTD/yarprobotinterfaceV3.0.dtd\">\n";

    fn read(body: &str) -> Result<LoadedRobot, XmlError> {
        read_robot_str(&format!("{HEAD}{body}"), Path::new("."), &Property::new())
    }

    #[test]
    fn reads_devices_params_and_actions() {
        let r = read(
            r#"<robot name="r" build="2" portprefix="/pre">
  <devices>
    <param name="shared">7</param>
    <device name="mc" type="fakeMotionControl">
      <group name="GENERAL"><param name="Joints">4</param><group name="IN"><param name="x">1</param></group></group>
      <paramlist name="networks"><elem name="a">(0 1 0 1)</elem><elem name="b">( 2 3 0 1 )</elem></paramlist>
      <param name="portname">${portprefix}/mc</param>
    </device>
    <device name="w" type="controlBoard_nws_yarp">
      <action phase="startup" level="5" type="attach"><param name="device">mc</param></action>
      <action phase="shutdown" level="5" type="detach"/>
    </device>
  </devices>
</robot>"#,
        )
        .unwrap();
        let robot = r.robot;
        assert_eq!((robot.name.as_str(), robot.build), ("r", 2));
        assert_eq!(robot.devices.len(), 2);
        let mc = &robot.devices[0];
        let names: Vec<&str> = mc.params.iter().map(|p| p.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "shared",
                "robotName",
                "GENERAL",
                "networks",
                "a",
                "b",
                "portname"
            ]
        );
        assert_eq!(find_param(&mc.params, "robotName"), Some("/pre"));
        assert_eq!(find_param(&mc.params, "networks"), Some("(a b)"));
        assert_eq!(find_param(&mc.params, "portname"), Some("/pre/mc"));
        assert_eq!(
            find_param(&mc.params, "GENERAL"),
            Some("(Joints 4) (IN (x 1))")
        );
        let p = mc.to_property().unwrap();
        assert_eq!(p.find("shared").and_then(|v| v.as_i64()), Some(7));
        let w = &robot.devices[1];
        assert_eq!(w.actions.len(), 2);
        assert_eq!(w.actions[0].phase, ActionPhase::Startup);
        assert_eq!(w.actions[0].kind, ActionType::Attach);
        assert_eq!(w.actions[0].level, 5);
        assert_eq!(robot.levels(ActionPhase::Startup), [5]);
    }

    #[test]
    fn command_line_portprefix_and_extern_name_win() {
        let mut cfg = Property::new();
        cfg.put("portprefix", Value::from("/cli"));
        cfg.merge_text("(ext (1 2))");
        let xml = format!(
            "{HEAD}<robot name=\"r\" portprefix=\"/xml\"><device name=\"d\" type=\"t\">\
             <param name=\"p\" extern-name=\"ext\">0</param>\
             <param name=\"q\" extern-name=\"missing\">5</param></device></robot>"
        );
        let r = read_robot_str(&xml, Path::new("."), &cfg).unwrap().robot;
        assert_eq!(r.portprefix, "/cli");
        assert_eq!(find_param(&r.devices[0].params, "p"), Some("(1 2)"));
        assert_eq!(find_param(&r.devices[0].params, "q"), Some("5"));
    }

    #[test]
    fn errors_name_file_and_line() {
        let e = read("<robot name=\"r\">\n<device name=\"d\">\n</device>\n</robot>")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("<string>:4:"), "{e}");
        assert!(e.contains("\"type\""), "{e}");

        let e = read("<robot name=\"r\">\n<device name=\"d\" type=\"t\">\n<param name=\"p\"></param>\n</device></robot>")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("<string>:5:") && e.contains("= p"), "{e}");

        let e = read("<robot name=\"r\"><device name=\"d\" type=\"t\"><action phase=\"later\" level=\"1\" type=\"park\"/></device></robot>")
            .unwrap_err()
            .to_string();
        assert!(e.contains("phase"), "{e}");

        let e = read("<robot name=\"r\"><devices><file name=\"x\"/></devices></robot>")
            .unwrap_err()
            .to_string();
        assert!(e.contains("forbidden"), "{e}");
    }

    #[test]
    fn v1_dtd_is_refused() {
        let xml = "<!DOCTYPE robot PUBLIC \"-//YARP//DTD yarprobotinterface 1.0//EN\" \"x\">\n<robot name=\"r\"/>";
        let e = read_robot_str(xml, Path::new("."), &Property::new()).unwrap_err();
        assert!(matches!(e, XmlError::UnsupportedDtd { .. }), "{e}");
    }

    #[test]
    fn missing_attributes_fall_back_with_warnings() {
        let xml = "<robot name=\"bot\"><device name=\"d\" type=\"t\"/></robot>";
        let r = read_robot_str(xml, Path::new("."), &Property::new()).unwrap();
        assert_eq!(r.robot.portprefix, "bot");
        assert_eq!(r.robot.build, 0);
        assert_eq!(r.warnings.len(), 3, "{:?}", r.warnings);
    }
}
