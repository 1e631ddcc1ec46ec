//! Choosing a CAN backend from iCub-style configuration.
//!
//! The iCub XML names a bus with `physDevice` (the adapter driver: `cfw2can`, `ecan`,
//! `pcan`, `socketcan`, …) and `CanDeviceNum` / `canDeviceNum` (which network of the
//! adapter). This crate adds one key, `canBackend`, a URL that overrides `physDevice`:
//!
//! | URL | backend |
//! |-----|---------|
//! | `inproc://NAME` | the in-process bus `NAME` |
//! | `udp://HOST:PORT[?local=HOST:PORT]` | cannelloni peer sending to `HOST:PORT` |
//! | `udp-hub://HOST:PORT` | cannelloni hub bound to `HOST:PORT` (what the emulator uses) |
//! | `socketcan://IFACE` | Linux SocketCAN interface `IFACE` |
//!
//! In any URL, `{n}` is replaced by the device number, and a port written `BASE+n` means
//! `BASE + CanDeviceNum` — so a single line such as `canBackend udp://127.0.0.1:20000+n`
//! serves every network of a robot. `physDevice` may also hold such a URL directly.
//! `physDevice socketcan` opens `CanDeviceName` (default `can{n}`; `%d` works as `{n}`).
//! Adapters without a Linux driver here (`cfw2can`, `ecan`, `pcan`, …) are rejected with
//! an error that says which key to set.

use std::sync::Arc;

use super::inproc::VirtualBus;
use super::udp::UdpBus;
use super::{BusError, CanBus};

/// A parsed backend choice.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum BusSpec {
    InProc(String),
    Udp {
        remote: String,
        local: Option<String>,
    },
    UdpHub(String),
    SocketCan(String),
}

/// Expands `{n}` and `%d`, and a trailing `PORT+n` in the authority.
fn expand(url: &str, num: Option<u32>) -> Result<String, BusError> {
    let needs = url.contains("{n}") || url.contains("%d") || url.contains("+n");
    let n = match (num, needs) {
        (Some(n), _) => n,
        (None, false) => 0,
        (None, true) => {
            return Err(BusError::Config(format!(
                "{url:?} refers to the device number but CanDeviceNum is not set"
            )))
        }
    };
    let mut out = url
        .replace("{n}", &n.to_string())
        .replace("%d", &n.to_string());
    if let Some(pos) = out.find("+n") {
        let digits_start = out[..pos]
            .rfind(|c: char| !c.is_ascii_digit())
            .map_or(0, |i| i + 1);
        let base: u32 = out[digits_start..pos]
            .parse()
            .map_err(|_| BusError::Config(format!("{url:?}: `+n` must follow a port number")))?;
        let port = base + n;
        if port > 65535 {
            return Err(BusError::Config(format!(
                "{url:?}: port {port} out of range"
            )));
        }
        out = format!("{}{}{}", &out[..digits_start], port, &out[pos + 2..]);
    }
    Ok(out)
}

impl BusSpec {
    /// Parses a backend URL, expanding the device number.
    pub fn parse(url: &str, device_num: Option<u32>) -> Result<Self, BusError> {
        let url = expand(url.trim(), device_num)?;
        let (scheme, rest) = url.split_once("://").ok_or_else(|| {
            BusError::Config(format!("{url:?} is not a backend URL (scheme://...)"))
        })?;
        if rest.is_empty() {
            return Err(BusError::Config(format!("{url:?} has no address")));
        }
        match scheme {
            "inproc" => Ok(Self::InProc(rest.to_string())),
            "udp" => {
                let (remote, query) = rest.split_once('?').unwrap_or((rest, ""));
                let mut local = None;
                for kv in query.split('&').filter(|s| !s.is_empty()) {
                    match kv.split_once('=') {
                        Some(("local", v)) => local = Some(v.to_string()),
                        _ => {
                            return Err(BusError::Config(format!("{url:?}: unknown option {kv:?}")))
                        }
                    }
                }
                Ok(Self::Udp {
                    remote: remote.to_string(),
                    local,
                })
            }
            "udp-hub" => Ok(Self::UdpHub(rest.to_string())),
            "socketcan" => Ok(Self::SocketCan(rest.to_string())),
            other => Err(BusError::Config(format!(
                "unknown CAN backend {other:?} (use inproc://, udp://, udp-hub:// or socketcan://)"
            ))),
        }
    }

    /// Picks the backend from configuration keys; `get` looks a key up (exact name).
    pub fn from_params(get: &dyn Fn(&str) -> Option<String>) -> Result<Self, BusError> {
        let first = |keys: &[&str]| {
            keys.iter()
                .find_map(|k| get(k))
                .map(|v| v.trim().trim_matches('"').to_string())
        };
        let num = match first(&["CanDeviceNum", "canDeviceNum", "candevicenum"]) {
            Some(v) => Some(
                v.parse::<u32>()
                    .map_err(|_| BusError::Config(format!("CanDeviceNum {v:?} is not a number")))?,
            ),
            None => None,
        };
        if let Some(url) = first(&["canBackend", "CanBackend"]) {
            return Self::parse(&url, num);
        }
        let phys = first(&["physDevice", "physdevice"])
            .ok_or_else(|| BusError::Config("neither canBackend nor physDevice is set".into()))?;
        if phys.contains("://") {
            return Self::parse(&phys, num);
        }
        match phys.as_str() {
            "socketcan" => {
                let name =
                    first(&["CanDeviceName", "canDeviceName"]).unwrap_or_else(|| "can{n}".into());
                Ok(Self::SocketCan(expand(&name, num.or(Some(0)))?))
            }
            other => Err(BusError::Config(format!(
                "physDevice {other:?} has no driver in this build; set `canBackend` \
                 (e.g. udp://127.0.0.1:20000+n) or `physDevice socketcan`"
            ))),
        }
    }

    /// Opens an endpoint on the chosen bus.
    pub fn open(&self) -> Result<Arc<dyn CanBus>, BusError> {
        Ok(match self {
            Self::InProc(name) => Arc::new(VirtualBus::named(name).endpoint()),
            Self::Udp { remote, local } => Arc::new(UdpBus::connect(remote, local.as_deref())?),
            Self::UdpHub(bind) => Arc::new(UdpBus::hub(bind)?),
            #[cfg(target_os = "linux")]
            Self::SocketCan(iface) => Arc::new(super::socketcan::SocketCanBus::open(iface)?),
            #[cfg(not(target_os = "linux"))]
            Self::SocketCan(_) => {
                return Err(BusError::Config("SocketCAN exists only on Linux".into()))
            }
        })
    }
}

/// Opens the bus described by configuration keys (see the module docs).
pub fn open_from_params(get: &dyn Fn(&str) -> Option<String>) -> Result<Arc<dyn CanBus>, BusError> {
    BusSpec::from_params(get)?.open()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    fn params(kv: &[(&str, &str)]) -> impl Fn(&str) -> Option<String> {
        let m: HashMap<String, String> = kv
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect();
        move |k| m.get(k).cloned()
    }

    #[test]
    fn urls() {
        assert_eq!(
            BusSpec::parse("inproc://head", None).unwrap(),
            BusSpec::InProc("head".into())
        );
        assert_eq!(
            BusSpec::parse("inproc://net{n}", Some(3)).unwrap(),
            BusSpec::InProc("net3".into())
        );
        assert_eq!(
            BusSpec::parse("udp://127.0.0.1:20000+n", Some(4)).unwrap(),
            BusSpec::Udp {
                remote: "127.0.0.1:20004".into(),
                local: None
            }
        );
        assert_eq!(
            BusSpec::parse("udp://127.0.0.1:20000?local=127.0.0.1:20100+n", Some(1)).unwrap(),
            BusSpec::Udp {
                remote: "127.0.0.1:20000".into(),
                local: Some("127.0.0.1:20101".into())
            }
        );
        assert_eq!(
            BusSpec::parse("udp-hub://0.0.0.0:9", None).unwrap(),
            BusSpec::UdpHub("0.0.0.0:9".into())
        );
        assert_eq!(
            BusSpec::parse("socketcan://vcan%d", Some(2)).unwrap(),
            BusSpec::SocketCan("vcan2".into())
        );
        assert!(BusSpec::parse("tcp://x", None).is_err());
        assert!(BusSpec::parse("udp://h:1+n", None).is_err());
        assert!(BusSpec::parse("udp://h:65535+n", Some(1)).is_err());
        assert!(BusSpec::parse("udp://h:1?foo=2", None).is_err());
        assert!(BusSpec::parse("nourl", None).is_err());
    }

    #[test]
    fn icub_keys() {
        let p = params(&[
            ("physDevice", "cfw2can"),
            ("CanDeviceNum", "1"),
            ("canBackend", "inproc://bus{n}"),
        ]);
        assert_eq!(
            BusSpec::from_params(&p).unwrap(),
            BusSpec::InProc("bus1".into())
        );
        let p = params(&[("physDevice", "\"socketcan\""), ("canDeviceNum", "2")]);
        assert_eq!(
            BusSpec::from_params(&p).unwrap(),
            BusSpec::SocketCan("can2".into())
        );
        let p = params(&[
            ("physDevice", "socketcan"),
            ("CanDeviceNum", "0"),
            ("CanDeviceName", "vcan%d"),
        ]);
        assert_eq!(
            BusSpec::from_params(&p).unwrap(),
            BusSpec::SocketCan("vcan0".into())
        );
        let p = params(&[
            ("physDevice", "udp://127.0.0.1:7000+n"),
            ("CanDeviceNum", "2"),
        ]);
        assert!(matches!(
            BusSpec::from_params(&p).unwrap(),
            BusSpec::Udp { .. }
        ));
        let err =
            BusSpec::from_params(&params(&[("physDevice", "cfw2can"), ("CanDeviceNum", "1")]))
                .unwrap_err();
        assert!(err.to_string().contains("canBackend"), "{err}");
        assert!(BusSpec::from_params(&params(&[])).is_err());
        assert!(BusSpec::from_params(&params(&[
            ("physDevice", "socketcan"),
            ("CanDeviceNum", "x")
        ]))
        .is_err());
    }

    #[test]
    fn open_inproc_from_params() {
        let p = params(&[("canBackend", "inproc://cfg-test")]);
        let a = open_from_params(&p).unwrap();
        let b = open_from_params(&p).unwrap();
        a.send(&crate::CanFrame::new(1, &[1]).unwrap()).unwrap();
        assert_eq!(
            b.recv(std::time::Duration::from_secs(1)).unwrap().data(),
            &[1]
        );
    }
}
