//! Where a robot's boards are served: robots-configuration gives each Ethernet board a
//! `10.0.1.x` address; on a laptop (or in tests) the boards, emulated, are served at other
//! addresses, and the host reaches them there. This is transport addressing that both the
//! host (the `embObj*` devices) and the board emulator apply, so it lives with the
//! protocol.

use std::net::Ipv4Addr;

/// Serves or reaches a robot's boards at other addresses than its files give, so that a
/// robot runs unmodified on a laptop without its `10.0.1.x` addresses and without root:
/// `YARP_ICUB_ETH_ADDRESS_MAP=10.0.1.0/24=127.0.1.0/24` (several maps separated by `,`).
/// The devices and `icub-eth-emulator` both honour it; messages keep the robot's
/// addresses.
pub const ADDRESS_MAP_ENV: &str = "YARP_ICUB_ETH_ADDRESS_MAP";

/// A mapping of IPv4 networks (`FROM/len=TO/len`, same prefix length).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct AddressMap {
    rules: Vec<(u32, u32, u32)>,
}

impl AddressMap {
    /// Parses `10.0.1.0/24=127.0.1.0/24[,...]`; empty text is the identity.
    pub fn parse(text: &str) -> Result<Self, String> {
        let mut rules = Vec::new();
        for rule in text.split(',').map(str::trim).filter(|r| !r.is_empty()) {
            let bad = || {
                format!(
                    "address map `{rule}`: expected FROM/LEN=TO/LEN, e.g. 10.0.1.0/24=127.0.1.0/24"
                )
            };
            let (from, to) = rule.split_once('=').ok_or_else(bad)?;
            let net = |s: &str| -> Result<(u32, u32), String> {
                let (a, l) = s.trim().split_once('/').ok_or_else(bad)?;
                let a: Ipv4Addr = a.parse().map_err(|_| bad())?;
                let l: u32 = l.parse().map_err(|_| bad())?;
                if l > 32 {
                    return Err(bad());
                }
                let mask = if l == 0 { 0 } else { u32::MAX << (32 - l) };
                Ok((u32::from(a) & mask, mask))
            };
            let (f, fm) = net(from)?;
            let (t, tm) = net(to)?;
            if fm != tm {
                return Err(bad());
            }
            rules.push((f, t, fm));
        }
        Ok(Self { rules })
    }

    /// The map of [`ADDRESS_MAP_ENV`] (the identity when unset).
    pub fn from_env() -> Result<Self, String> {
        Self::parse(&std::env::var(ADDRESS_MAP_ENV).unwrap_or_default())
    }

    /// Where the robot's address `ip` is served.
    pub fn map(&self, ip: Ipv4Addr) -> Ipv4Addr {
        let a = u32::from(ip);
        for &(f, t, m) in &self.rules {
            if a & m == f {
                return Ipv4Addr::from(t | (a & !m));
            }
        }
        ip
    }

    /// The robot's address of a served address `ip` (inverse of [`Self::map`]).
    pub fn unmap(&self, ip: Ipv4Addr) -> Ipv4Addr {
        let a = u32::from(ip);
        for &(f, t, m) in &self.rules {
            if a & m == t {
                return Ipv4Addr::from(f | (a & !m));
            }
        }
        ip
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn address_map_both_ways() {
        let m = AddressMap::parse("10.0.1.0/24=127.0.1.0/24").unwrap();
        assert_eq!(
            m.map(Ipv4Addr::new(10, 0, 1, 104)),
            Ipv4Addr::new(127, 0, 1, 104)
        );
        assert_eq!(
            m.unmap(Ipv4Addr::new(127, 0, 1, 7)),
            Ipv4Addr::new(10, 0, 1, 7)
        );
        assert_eq!(
            m.map(Ipv4Addr::new(10, 0, 2, 1)),
            Ipv4Addr::new(10, 0, 2, 1)
        );
        assert_eq!(AddressMap::parse("").unwrap(), AddressMap::default());
        assert!(AddressMap::parse("10.0.1.0/24=127.0.0.0/8").is_err());
        assert!(AddressMap::parse("nonsense").is_err());
    }
}
