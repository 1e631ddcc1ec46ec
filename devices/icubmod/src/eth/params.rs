//! The Ethernet parameters every `embObj*` device reads, exactly as robots-configuration
//! writes them and icub-main's `eth::parser::read` / `ServiceParser` read them:
//!
//! - `PC104` (`hardware/electronics/pc104.xml`): `PC104IpAddress`, `PC104IpPort`,
//!   `PC104TXrate`, `PC104RXrate`;
//! - `ETH_BOARD` (`*-eln.xml`): `ETH_BOARD_PROPERTIES` (`IpAddress`, `IpPort`, `Type`,
//!   `maxSizeRXpacket`, `maxSizeROP`), `ETH_BOARD_SETTINGS` (`Name`, `RUNNINGMODE`:
//!   `period`, `maxTimeOfRXactivity`, `maxTimeOfDOactivity`, `maxTimeOfTXactivity`,
//!   `TXrateOfRegularROPs`), `ETH_BOARD_ACTIONS/MONITOR_ITS_PRESENCE` (`enabled`,
//!   `timeout`, `periodOfMissingReport`);
//! - `SERVICE/type` (`*_service.xml`): the service (`eomn_serv_MC_foc`, ...).
//!
//! Defaults and clamps are C++'s: port 12345, 768-byte packets, 384-byte ROPs, a
//! 1000 µs cycle of 400 + 300 + 300 µs (used whenever the three do not add up to the
//! period), TX rate 1..20, presence timeout 20 ms (at most 100 ms), missing-report period
//! 60 s (at most 600 s).

use std::net::Ipv4Addr;
use std::time::Duration;

use icub_eth::entities::boards::EthBoardType;
use icub_eth::entities::mn::{category, service_type, ApplConfig};
use yarp_proto::Property;

use super::config::{Node, ParamError};
use yarp_proto::Value;

yarp_devices::device_params! {
    /// The host's address (`hardware/electronics/pc104.xml`), as every `embObj*` device
    /// reads it.
    pub struct Pc104Params for "embObj" {
        /// The host's address on the robot's network
        "PC104::PC104IpAddress" ip: String = required; check ipv4,
        /// The host's UDP port
        "PC104::PC104IpPort" port: f64 = required,
        /// (1..20)
        "PC104::PC104TXrate" tx_rate: f64 = optional,
        /// (1..20)
        "PC104::PC104RXrate" rx_rate: f64 = optional,
    }
}

yarp_devices::device_params! {
    /// One Ethernet board (`*-eln.xml`), as every `embObj*` device reads it.
    pub struct EthBoardDeclared for "embObj" {
        /// The board's address
        "ETH_BOARD::ETH_BOARD_PROPERTIES::IpAddress" ip: String = required; check ipv4,
        /// The board's UDP port
        "ETH_BOARD::ETH_BOARD_PROPERTIES::IpPort" port: f64 = 12345.0,
        /// The board type (ems4, mc4plus, mc2plus, amc, ...)
        "ETH_BOARD::ETH_BOARD_PROPERTIES::Type" board_type: String = optional,
        /// Largest packet the board receives
        "ETH_BOARD::ETH_BOARD_PROPERTIES::maxSizeRXpacket" max_rx_packet: f64 = 768.0; "bytes",
        /// Largest ROP
        "ETH_BOARD::ETH_BOARD_PROPERTIES::maxSizeROP" max_rop: f64 = 384.0; "bytes",
        /// The board's name in messages (NOT-NAMED when empty)
        "ETH_BOARD::ETH_BOARD_SETTINGS::Name" name: String = optional,
        /// synchronized or besteffort
        "ETH_BOARD::ETH_BOARD_SETTINGS::RUNNINGMODE::execution" execution: String = optional,
        /// The board's cycle (only 1000 so far)
        "ETH_BOARD::ETH_BOARD_SETTINGS::RUNNINGMODE::period" period: f64 = optional; "us",
        /// Safety gap of the cycle
        "ETH_BOARD::ETH_BOARD_SETTINGS::RUNNINGMODE::safetygap" safety_gap: f64 = optional; "us",
        /// Time of the cycle for receiving (5..990; the three add up to the period)
        "ETH_BOARD::ETH_BOARD_SETTINGS::RUNNINGMODE::maxTimeOfRXactivity" max_rx: f64 = optional; "us",
        /// Time of the cycle for doing (5..990)
        "ETH_BOARD::ETH_BOARD_SETTINGS::RUNNINGMODE::maxTimeOfDOactivity" max_do: f64 = optional; "us",
        /// Time of the cycle for transmitting (5..990)
        "ETH_BOARD::ETH_BOARD_SETTINGS::RUNNINGMODE::maxTimeOfTXactivity" max_tx: f64 = optional; "us",
        /// Cycles between two transmissions of the regular ROPs
        "ETH_BOARD::ETH_BOARD_SETTINGS::RUNNINGMODE::TXrateOfRegularROPs" tx_rate: f64 = optional,
        /// Log RX-DO-TX overflows (a boolean; true by default)
        "ETH_BOARD::ETH_BOARD_SETTINGS::RUNNINGMODE::LOGGING::IMMEDIATE::emitRXDOTXoverflow" log_rxdotx_overflow: Value = optional,
        /// Log period overflows (a boolean)
        "ETH_BOARD::ETH_BOARD_SETTINGS::RUNNINGMODE::LOGGING::IMMEDIATE::emitPERIODoverflow" log_period_overflow: Value = optional,
        /// Log RX-DO-TX statistics (older name of emitRXDOTXminavgmax)
        "ETH_BOARD::ETH_BOARD_SETTINGS::RUNNINGMODE::LOGGING::PERIODIC::emitRXDOTXstatistics" log_rxdotx_statistics: Value = optional,
        /// Log RX-DO-TX min, average and max (a boolean)
        "ETH_BOARD::ETH_BOARD_SETTINGS::RUNNINGMODE::LOGGING::PERIODIC::emitRXDOTXminavgmax" log_rxdotx_minavgmax: Value = optional,
        /// Log the period's min, average and max (a boolean)
        "ETH_BOARD::ETH_BOARD_SETTINGS::RUNNINGMODE::LOGGING::PERIODIC::emitPERIODminavgmax" log_period_minavgmax: Value = optional,
        /// Log the period's histogram (a boolean)
        "ETH_BOARD::ETH_BOARD_SETTINGS::RUNNINGMODE::LOGGING::PERIODIC::emitPERIODhistogram" log_period_histogram: Value = optional,
        /// Period of the periodic logs (0..600)
        "ETH_BOARD::ETH_BOARD_SETTINGS::RUNNINGMODE::LOGGING::PERIODIC::period" log_period: f64 = optional; "s",
        /// true: the host watches the board's presence
        "ETH_BOARD::ETH_BOARD_ACTIONS::MONITOR_ITS_PRESENCE::enabled" presence_enabled: String = optional,
        /// Silence after which the board counts as lost (at most 0.1)
        "ETH_BOARD::ETH_BOARD_ACTIONS::MONITOR_ITS_PRESENCE::timeout" presence_timeout: f64 = 0.02; "s",
        /// Period of the reports of a lost board (at most 600)
        "ETH_BOARD::ETH_BOARD_ACTIONS::MONITOR_ITS_PRESENCE::periodOfMissingReport" missing_report_period: f64 = optional; "s",
    }
}

yarp_devices::device_params! {
    /// The service of an `embObj*` device (`*_service.xml`).
    pub struct ServiceParams for "embObj" {
        /// The service: eomn_serv_MC_foc, eomn_serv_AS_strain, ...
        "SERVICE::type" service_type: String = optional,
    }
}

/// An IPv4 address, as the robots' files write it.
fn ipv4(s: &str) -> Result<(), &'static str> {
    match s.trim().trim_matches('"').parse::<Ipv4Addr>() {
        Ok(_) => Ok(()),
        Err(_) => Err("an IPv4 address"),
    }
}

/// A declared read's error in the terms of this module: the path with `/`.
fn param_error(e: yarp_devices::DeviceError) -> ParamError {
    match e {
        yarp_devices::DeviceError::BadParam {
            param,
            expected,
            got,
            ..
        } => ParamError::bad(param.replace("::", "/"), expected, got),
        yarp_devices::DeviceError::MissingParam { param, .. } => {
            ParamError::missing(param.replace("::", "/"), "a value")
        }
        other => ParamError::bad("configuration", "a valid configuration", other.to_string()),
    }
}

/// The host's address (`PC104`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Pc104 {
    pub ip: Ipv4Addr,
    pub port: u16,
    pub tx_rate: u32,
    pub rx_rate: u32,
}

/// One Ethernet board as `ETH_BOARD` describes it.
#[derive(Debug, Clone, PartialEq)]
pub struct EthBoardParams {
    pub ip: Ipv4Addr,
    pub port: u16,
    pub board_type: EthBoardType,
    /// `Type` as written.
    pub type_name: String,
    pub max_rx_packet: usize,
    pub max_rop: usize,
    /// `ETH_BOARD_SETTINGS/Name` (`NOT-NAMED` when empty, as C++).
    pub name: String,
    /// The running cycle (`RUNNINGMODE`) sent as `eOmn_appl_config_t`.
    pub appl: ApplConfig,
    /// `MONITOR_ITS_PRESENCE`: `None` when disabled.
    pub presence_timeout: Option<Duration>,
    pub missing_report_period: Duration,
}

impl EthBoardParams {
    /// How C++ names a board in its messages: `IP (name)`.
    pub fn who(&self) -> String {
        format!("{} ({})", self.ip, self.name)
    }
    /// The period of the board's regular ROPs.
    pub fn regulars_period(&self) -> Duration {
        Duration::from_micros(
            u64::from(self.appl.cycletime) * u64::from(self.appl.txratedivider.max(1)),
        )
    }
}

fn ip_of(s: &str, param: &str) -> Result<Ipv4Addr, ParamError> {
    s.trim()
        .trim_matches('"')
        .parse()
        .map_err(|_| ParamError::bad(param, "an IPv4 address", s))
}

/// `PC104` (C++ `eth::parser::read(cfgtotal, pc104data)`).
pub fn read_pc104(config: &Property) -> Result<Pc104, ParamError> {
    Node::root(config).need_group("PC104")?;
    let p = Pc104Params::parse("embObj", config).map_err(param_error)?;
    let ip = ip_of(&p.ip, "PC104/PC104IpAddress")?;
    let rate = |r: Option<f64>| r.map_or(1, |v| (v as i64).clamp(1, 20) as u32);
    Ok(Pc104 {
        ip,
        port: p.port as u16,
        tx_rate: rate(p.tx_rate),
        rx_rate: rate(p.rx_rate),
    })
}

/// `ETH_BOARD` (C++ `eth::parser::read(cfgtotal, boarddata)`).
pub fn read_eth_board(config: &Property) -> Result<EthBoardParams, ParamError> {
    let board = Node::root(config).need_group("ETH_BOARD")?;
    board.need_group("ETH_BOARD_PROPERTIES")?;
    let settings = board.need_group("ETH_BOARD_SETTINGS")?;
    let p = EthBoardDeclared::parse("embObj", config).map_err(param_error)?;
    let ip = ip_of(&p.ip, "ETH_BOARD_PROPERTIES/IpAddress")?;
    let type_name = p.board_type.clone().unwrap_or_default();
    let board_type = EthBoardType::from_name(&type_name).unwrap_or(EthBoardType::Unknown);
    let name = p
        .name
        .clone()
        .filter(|n| !n.is_empty())
        .unwrap_or_else(|| "NOT-NAMED".into());
    // icub-main's eth::parser: the defaults of boardSettings (synchronized, no logging)
    // unless RUNNINGMODE is given, whose values are checked and mended as C++ does.
    let mut appl = ApplConfig {
        runnermode: RUNNERMODE_SYNCHRONIZED,
        ..ApplConfig::default()
    };
    if settings.group("RUNNINGMODE").is_some() {
        running_mode(&p, &mut appl, ip);
    }
    let mut presence_timeout = Some(Duration::from_millis(20));
    let mut missing_report_period = Duration::from_secs(60);
    if board
        .group("ETH_BOARD_ACTIONS")
        .and_then(|a| a.group("MONITOR_ITS_PRESENCE"))
        .is_some()
    {
        let enabled = p.presence_enabled.as_deref() == Some("true");
        let t = p.presence_timeout.min(0.100);
        presence_timeout = (enabled && t > 0.0).then(|| Duration::from_secs_f64(t));
        if let Some(period) = p.missing_report_period {
            missing_report_period = Duration::from_secs_f64(period.clamp(0.0, 600.0));
        }
    }
    Ok(EthBoardParams {
        ip,
        port: p.port as u16,
        board_type,
        type_name,
        max_rx_packet: p.max_rx_packet as usize,
        max_rop: p.max_rop as usize,
        name,
        appl,
        presence_timeout,
        missing_report_period,
    })
}

/// `eomn_appl_runnermode_synchronized`.
const RUNNERMODE_SYNCHRONIZED: u8 = 1;
/// `eomn_appl_runnermode_besteffort`.
const RUNNERMODE_BESTEFFORT: u8 = 0;

/// `ETH_BOARD_SETTINGS/RUNNINGMODE` as icub-main's `eth::parser::read` takes it: the period
/// is 1000 µs whatever is written, out-of-range activity times fall back to their
/// defaults, the regulars' rate to 1 (<= 0) or 20 (> 200), a sum of activities other than
/// the period to the defaults; `execution` picks the runner's mode; `LOGGING` the board's
/// logs (by default only the RX-DO-TX overflow, as C++).
fn running_mode(p: &EthBoardDeclared, appl: &mut ApplConfig, ip: Ipv4Addr) {
    appl.runnermode = match p.execution.as_deref() {
        Some("besteffort") => RUNNERMODE_BESTEFFORT,
        None | Some("synchronized") => RUNNERMODE_SYNCHRONIZED,
        Some(other) => {
            tracing::warn!(board = %ip, "ETH_BOARD_SETTINGS::RUNNINGMODE::execution has unknown value '{other}', defaulting to 'synchronized'");
            RUNNERMODE_SYNCHRONIZED
        }
    };
    if let Some(period) = p.period {
        if period as i64 != 1000 {
            tracing::warn!(board = %ip, "ETH_BOARD_SETTINGS::RUNNINGMODE::period can be only 1000 (so far) and it was: {period}");
        }
        appl.cycletime = 1000;
    }
    if let Some(g) = p.safety_gap {
        appl.safetygap = g as u16;
    }
    let activity = |key: &str, value: Option<f64>, default: u16| {
        value.map(|v| {
            let v = v as i64;
            if (5..=990).contains(&v) {
                v as u16
            } else {
                tracing::warn!(board = %ip, "ETH_BOARD_SETTINGS::RUNNINGMODE::{key} must be in [5, 990] (so far) and it was: {v}; using the default");
                default
            }
        })
    };
    if let Some(v) = activity("maxTimeOfRXactivity", p.max_rx, 400) {
        appl.maxtime_rx = v;
    }
    if let Some(v) = activity("maxTimeOfDOactivity", p.max_do, 300) {
        appl.maxtime_do = v;
    }
    if let Some(v) = activity("maxTimeOfTXactivity", p.max_tx, 300) {
        appl.maxtime_tx = v;
    }
    if let Some(r) = p.tx_rate {
        let r = r as i64;
        appl.txratedivider = if r <= 0 {
            1
        } else if r > 200 {
            20
        } else {
            r as u8
        };
    }
    let sum = u32::from(appl.maxtime_rx) + u32::from(appl.maxtime_do) + u32::from(appl.maxtime_tx);
    if sum != u32::from(appl.cycletime) {
        tracing::warn!(
            board = %ip,
            "ETH_BOARD_SETTINGS::RUNNINGMODE sum(maxTimeOfRXactivity, maxTimeOfDOactivity, maxTimeOfTXactivity) != period: using default values"
        );
        appl.cycletime = 1000;
        appl.maxtime_rx = 400;
        appl.maxtime_do = 300;
        appl.maxtime_tx = 300;
    }
    // eOmn_appl_log_flags_t bits
    const RXDOTX_OVERFLOW: u16 = 1 << 0;
    const RXDOTX_MINAVGMAX: u16 = 1 << 1;
    const PERIOD_OVERFLOW: u16 = 1 << 2;
    const PERIOD_MINAVGMAX: u16 = 1 << 3;
    const PERIOD_HISTOGRAM: u16 = 1 << 4;
    // C++ takes a flag only where the value is a boolean (`Value::isBool`); in C++'s
    // order: emitRXDOTXminavgmax is the newer name of emitRXDOTXstatistics and wins
    let flags_given = [
        (&p.log_rxdotx_overflow, RXDOTX_OVERFLOW),
        (&p.log_period_overflow, PERIOD_OVERFLOW),
        (&p.log_rxdotx_statistics, RXDOTX_MINAVGMAX),
        (&p.log_rxdotx_minavgmax, RXDOTX_MINAVGMAX),
        (&p.log_period_minavgmax, PERIOD_MINAVGMAX),
        (&p.log_period_histogram, PERIOD_HISTOGRAM),
    ];
    let mut flags = RXDOTX_OVERFLOW;
    for (value, bit) in flags_given {
        let text = value.as_ref().map(yarp_proto::Value::to_string_bare);
        match text.as_deref().map(str::trim) {
            Some("true") => flags |= bit,
            Some("false") => flags &= !bit,
            _ => {}
        }
    }
    appl.logging_flags = flags;
    appl.logging_period10ms = (100.0 * p.log_period.unwrap_or(0.0).clamp(0.0, 600.0)) as u16;
}

/// A service as `SERVICE/type` names it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ServiceKind {
    /// `eOmn_serv_type_t`.
    pub service_type: u8,
    /// `eOmn_serv_category_t`.
    pub category: u8,
}

/// The `eomn_serv_*` names of `SERVICE/type` (C++ `eomn_string2servicetype`).
pub fn service_kind(name: &str) -> Option<ServiceKind> {
    use category as c;
    use service_type as t;
    let (service_type, category) = match name.trim().trim_matches('"') {
        "eomn_serv_MC_generic" => (t::MC_GENERIC, c::MC),
        "eomn_serv_MC_foc" => (t::MC_FOC, c::MC),
        "eomn_serv_MC_mc4" => (t::MC_MC4, c::MC),
        "eomn_serv_MC_mc4plus" => (t::MC_MC4PLUS, c::MC),
        "eomn_serv_MC_mc4plusmais" => (t::MC_MC4PLUSMAIS, c::MC),
        "eomn_serv_MC_mc2plus" => (t::MC_MC2PLUS, c::MC),
        "eomn_serv_MC_mc2pluspsc" => (t::MC_MC2PLUSPSC, c::MC),
        "eomn_serv_MC_mc4plusfaps" => (t::MC_MC4PLUSFAPS, c::MC),
        "eomn_serv_MC_advfoc" => (t::MC_ADVFOC, c::MC),
        "eomn_serv_AS_mais" => (t::AS_MAIS, c::MAIS),
        "eomn_serv_AS_strain" => (t::AS_STRAIN, c::STRAIN),
        "eomn_serv_AS_inertials3" => (t::AS_INERTIALS3, c::INERTIALS3),
        "eomn_serv_AS_temperatures" => (t::AS_TEMPERATURES, c::TEMPERATURES),
        "eomn_serv_AS_psc" => (t::AS_PSC, c::PSC),
        "eomn_serv_AS_pos" => (t::AS_POS, c::POS),
        "eomn_serv_AS_ft" => (t::AS_FT, c::FT),
        "eomn_serv_AS_battery" => (t::AS_BATTERY, c::BATTERY),
        "eomn_serv_SK_skin" => (t::SK_SKIN, c::SKIN),
        _ => return None,
    };
    Some(ServiceKind {
        service_type,
        category,
    })
}

/// `SERVICE/type`.
pub fn read_service(config: &Property) -> Result<ServiceKind, ParamError> {
    Node::root(config).need_group("SERVICE")?;
    let name = ServiceParams::parse("embObj", config)
        .map_err(param_error)?
        .service_type
        .ok_or_else(|| ParamError::missing("SERVICE/type", "an eomn_serv_* service type"))?;
    service_kind(&name)
        .ok_or_else(|| ParamError::bad("SERVICE/type", "an eomn_serv_* service type", name))
}

/// The address map is transport addressing shared with the emulator: it lives in the
/// protocol crate.
pub use icub_eth::addressmap::{AddressMap, ADDRESS_MAP_ENV};

#[cfg(test)]
mod tests {
    use super::*;

    const LEFT_ARM_EB1: &str = "(ETH_BOARD (ETH_BOARD_PROPERTIES (IpAddress \"10.0.1.1\") (IpPort 12345) (Type ems4) (maxSizeRXpacket 768) (maxSizeROP 384)) (ETH_BOARD_SETTINGS (Name left_arm-eb1-j0_3) (RUNNINGMODE (period 1000) (maxTimeOfRXactivity 400) (maxTimeOfDOactivity 300) (maxTimeOfTXactivity 300) (TXrateOfRegularROPs 5))) (ETH_BOARD_ACTIONS (MONITOR_ITS_PRESENCE (enabled true) (timeout 0.02) (periodOfMissingReport 60.0)))) (PC104 (PC104IpAddress \"10.0.1.104\") (PC104IpPort 12345) (PC104TXrate 1) (PC104RXrate 5)) (SERVICE (type eomn_serv_MC_foc))";

    #[test]
    fn icub_genova02_left_arm_board() {
        let p = Property::from_text(LEFT_ARM_EB1);
        let b = read_eth_board(&p).unwrap();
        assert_eq!(b.ip, Ipv4Addr::new(10, 0, 1, 1));
        assert_eq!(b.port, 12345);
        assert_eq!(b.board_type, EthBoardType::Ems4);
        assert_eq!(b.name, "left_arm-eb1-j0_3");
        assert_eq!((b.max_rx_packet, b.max_rop), (768, 384));
        assert_eq!(b.appl.cycletime, 1000);
        assert_eq!(b.appl.txratedivider, 5);
        assert_eq!(b.regulars_period(), Duration::from_millis(5));
        assert_eq!(b.presence_timeout, Some(Duration::from_millis(20)));
        assert_eq!(b.who(), "10.0.1.1 (left_arm-eb1-j0_3)");
        let pc = read_pc104(&p).unwrap();
        assert_eq!(pc.ip, Ipv4Addr::new(10, 0, 1, 104));
        assert_eq!((pc.port, pc.tx_rate, pc.rx_rate), (12345, 1, 5));
        let s = read_service(&p).unwrap();
        assert_eq!(s.category, category::MC);
        assert_eq!(s.service_type, service_type::MC_FOC);
    }

    #[test]
    fn running_mode_that_does_not_add_up_falls_back_to_defaults() {
        let p = Property::from_text("(ETH_BOARD (ETH_BOARD_PROPERTIES (IpAddress \"10.0.1.9\") (Type MC4PLUS)) (ETH_BOARD_SETTINGS (Name \"\") (RUNNINGMODE (period 2000) (maxTimeOfRXactivity 400) (maxTimeOfDOactivity 300) (maxTimeOfTXactivity 300) (TXrateOfRegularROPs 50))) (ETH_BOARD_ACTIONS (MONITOR_ITS_PRESENCE (enabled false))))");
        let b = read_eth_board(&p).unwrap();
        assert_eq!(b.board_type, EthBoardType::Mc4plus);
        assert_eq!(b.appl.cycletime, 1000);
        // C++ says "[1, 20]" but only brings values over 200 down to 20
        assert_eq!(b.appl.txratedivider, 50);
        assert_eq!(b.name, "NOT-NAMED");
        assert_eq!(b.presence_timeout, None);
        assert_eq!(b.port, 12345);
    }

    #[test]
    fn missing_groups_are_named() {
        let e = read_eth_board(&Property::from_text(
            "(ETH_BOARD (ETH_BOARD_SETTINGS (Name x)))",
        ))
        .unwrap_err();
        assert_eq!(e.param, "ETH_BOARD/ETH_BOARD_PROPERTIES");
        let e = read_pc104(&Property::from_text(
            "(PC104 (PC104IpAddress \"10.0.1.x\"))",
        ))
        .unwrap_err();
        assert_eq!(e.param, "PC104/PC104IpAddress");
        assert!(read_service(&Property::from_text("(SERVICE (type eomn_serv_nope))")).is_err());
    }
}
