//! Start order from `after` dependencies (a stable topological sort), and address parsing.

use crate::config::Module;
use std::net::{SocketAddr, ToSocketAddrs};

#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum PlanError {
    #[error("module {module}: `after` names unknown module {missing}")]
    UnknownDependency { module: String, missing: String },
    #[error("modules depend on each other in a cycle: {0}")]
    Cycle(String),
}

/// Indices of `modules` in an order where each comes after everything it names in
/// `after`; otherwise the file order is kept.
pub fn start_order(modules: &[Module]) -> Result<Vec<usize>, PlanError> {
    let index = |name: &str| modules.iter().position(|m| m.name == name);
    let mut deps = Vec::with_capacity(modules.len());
    for m in modules {
        let mut d = Vec::new();
        for a in &m.after {
            d.push(index(a).ok_or_else(|| PlanError::UnknownDependency {
                module: m.name.clone(),
                missing: a.clone(),
            })?);
        }
        deps.push(d);
    }
    let mut placed = vec![false; modules.len()];
    let mut order = Vec::with_capacity(modules.len());
    while order.len() < modules.len() {
        // The first module in file order whose dependencies are all placed.
        let next = (0..modules.len()).find(|&i| !placed[i] && deps[i].iter().all(|&d| placed[d]));
        match next {
            Some(i) => {
                placed[i] = true;
                order.push(i);
            }
            None => {
                let stuck: Vec<&str> = (0..modules.len())
                    .filter(|&i| !placed[i])
                    .map(|i| modules[i].name.as_str())
                    .collect();
                return Err(PlanError::Cycle(stuck.join(", ")));
            }
        }
    }
    Ok(order)
}

/// Parses `host:port` (names are resolved) into a socket address.
pub fn parse_address(text: &str) -> Result<SocketAddr, String> {
    let (host, port) = text
        .rsplit_once(':')
        .ok_or_else(|| format!("{text:?} is not host:port"))?;
    let port: u16 = port
        .parse()
        .map_err(|_| format!("{text:?}: {port:?} is not a port number"))?;
    (host, port)
        .to_socket_addrs()
        .ok()
        .and_then(|mut a| a.find(SocketAddr::is_ipv4).or_else(|| a.next()))
        .ok_or_else(|| format!("cannot resolve {host:?}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn m(name: &str, after: &[&str]) -> Module {
        let mut m = Module::new(name, "true", &[]);
        m.after = after.iter().map(|s| s.to_string()).collect();
        m
    }

    #[test]
    fn keeps_file_order_when_free() {
        let ms = [m("a", &[]), m("b", &[]), m("c", &[])];
        assert_eq!(start_order(&ms).unwrap(), [0, 1, 2]);
    }

    #[test]
    fn dependencies_come_first() {
        let ms = [
            m("gw", &["dev"]),
            m("dev", &["emu"]),
            m("emu", &[]),
            m("x", &[]),
        ];
        assert_eq!(start_order(&ms).unwrap(), [2, 1, 0, 3]);
    }

    #[test]
    fn errors() {
        let ms = [m("a", &["b"]), m("b", &["a"]), m("c", &[])];
        assert_eq!(start_order(&ms), Err(PlanError::Cycle("a, b".into())));
        let ms = [m("a", &["zz"])];
        assert!(matches!(
            start_order(&ms),
            Err(PlanError::UnknownDependency { .. })
        ));
    }

    #[test]
    fn addresses() {
        assert_eq!(
            parse_address("127.0.0.1:10000").unwrap(),
            "127.0.0.1:10000".parse().unwrap()
        );
        assert!(parse_address("localhost:10").is_ok());
        assert!(parse_address("1.2.3.4").is_err());
        assert!(parse_address("1.2.3.4:x").is_err());
    }
}
