//! Board types and board descriptors (`EoBoards.h`).

use crate::wire::{Entity, Reader, Writer};

/// `eObrd_ethtype_t`: the Ethernet boards.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum EthBoardType {
    Ems4 = 32,
    Mc4plus = 33,
    Mc2plus = 34,
    Amc = 35,
    Amcfoc = 36,
    Amcmj1 = 37,
    None = 254,
    Unknown = 255,
}

impl EthBoardType {
    pub fn from_u8(v: u8) -> Self {
        match v {
            32 => Self::Ems4,
            33 => Self::Mc4plus,
            34 => Self::Mc2plus,
            35 => Self::Amc,
            36 => Self::Amcfoc,
            37 => Self::Amcmj1,
            254 => Self::None,
            _ => Self::Unknown,
        }
    }

    /// The compact string of `eoboards_type2string2(.., eobool_true)`, as
    /// `ETH_BOARD_PROPERTIES/Type` writes it (`ems4`, `mc4plus`, `mc2plus`, `amc`, ...).
    pub fn name(self) -> &'static str {
        match self {
            Self::Ems4 => "ems4",
            Self::Mc4plus => "mc4plus",
            Self::Mc2plus => "mc2plus",
            Self::Amc => "amc",
            Self::Amcfoc => "amcfoc",
            Self::Amcmj1 => "amcmj1",
            Self::None => "none",
            Self::Unknown => "unknown",
        }
    }

    /// Parses the compact (`ems4`) or extended (`eobrd_ems4`) name, case-insensitively
    /// (`ETH_BOARD_PROPERTIES/Type` is written `EMS4`, `MC4PLUS`, ... in robots-configuration).
    pub fn from_name(s: &str) -> Option<Self> {
        let s = s.to_ascii_lowercase();
        let s = s.strip_prefix("eobrd_").unwrap_or(&s);
        Some(match s {
            "ems4" => Self::Ems4,
            "mc4plus" => Self::Mc4plus,
            "mc2plus" => Self::Mc2plus,
            "amc" => Self::Amc,
            "amcfoc" => Self::Amcfoc,
            "amcmj1" => Self::Amcmj1,
            _ => return None,
        })
    }
}

impl std::fmt::Display for EthBoardType {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// `eObrd_info_t` (6 bytes): a (CAN) board's type, firmware and protocol versions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct BoardInfo {
    /// `eObrd_type_t`.
    pub board_type: u8,
    /// major, minor, build.
    pub firmware: [u8; 3],
    /// major, minor.
    pub protocol: [u8; 2],
}

impl Entity for BoardInfo {
    const C_TYPE: &'static str = "eObrd_info_t";
    const SIZE: usize = 6;
    fn write(&self, w: &mut Writer) {
        w.u8(self.board_type);
        w.bytes(&self.firmware);
        w.bytes(&self.protocol);
    }
    fn read(r: &mut Reader) -> Self {
        Self {
            board_type: r.u8(),
            firmware: r.array(),
            protocol: r.array(),
        }
    }
}

/// `eObrd_canlocation_t` (1 byte): port:1, addr:4, insideindex:3 (from bit 0).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct CanLocation {
    pub port: u8,
    pub addr: u8,
    pub inside_index: u8,
}

impl CanLocation {
    pub fn to_byte(self) -> u8 {
        (self.port & 1) | (self.addr & 0xf) << 1 | (self.inside_index & 7) << 5
    }
    pub fn from_byte(b: u8) -> Self {
        Self {
            port: b & 1,
            addr: (b >> 1) & 0xf,
            inside_index: b >> 5,
        }
    }
}
