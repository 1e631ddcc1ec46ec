//! The configuration of a skin's MTB boards and triangles (the robots'
//! `hardware/skin/*-skinSpec.xml`), read as icub-main's `SkinConfigReader` reads it and
//! turned into the commands `EmbObjSkin::init` and `initWithSpecialConfig` send:
//!
//! - `defaultCfgBoard` (`period`, `skinType`, `noLoad`, `diagnostic`) and
//!   `defaultCfgTriangle` (`enabled`, `shift`, `cdcOffset`): to every board of every
//!   patch (destination `0xffff 0xffff`, triangles 0-15). Both groups present make the
//!   "new style" configuration; without them nothing is sent and the skin signals the
//!   old way.
//! - `specialCfgBoards/boardSetCfgN` (`patch start end period type noLoad`) and
//!   `specialCfgTriangles/triangleSetCfgN` (`patch board first last enabled shift
//!   cdcOffset`), `numOfSets` of each: to the boards named, by CAN address bit.

use icub_eth::entities::skin::{SkinBoardsConfig, SkinTrianglesConfig};

use super::config::{parse_number, Node, ParamError};

/// One board configuration (`SkinBoardCfgParam`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BoardCfg {
    pub period: u8,
    pub skin_type: u8,
    pub no_load: u8,
}

/// One triangle configuration (`SkinTriangleCfgParam`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TriangleCfg {
    pub enabled: bool,
    pub shift: u8,
    pub cdc_offset: u16,
}

/// A special board set: `patch`, addresses `first..=last`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SpecialBoards {
    pub patch: u8,
    pub first: u8,
    pub last: u8,
    pub cfg: BoardCfg,
}

/// A special triangle set: `patch`, board `addr`, triangles `first..=last`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SpecialTriangles {
    pub patch: u8,
    pub addr: u8,
    pub first: u8,
    pub last: u8,
    pub cfg: TriangleCfg,
}

/// A skin's MTB configuration, when the file gives the new-style one.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SkinSpec {
    pub board: BoardCfg,
    pub triangle: TriangleCfg,
    pub special_boards: Vec<SpecialBoards>,
    pub special_triangles: Vec<SpecialTriangles>,
}

/// A value of `group/key` as an integer (decimal or `0x` hex, as C++ `asInt32`).
fn int(g: &Node, key: &'static str, path: &str) -> Result<i64, ParamError> {
    let s = g
        .string(key)
        .ok_or_else(|| ParamError::missing(format!("{path}/{key}"), "a number"))?;
    parse_number(&s)
        .map(|n| n as i64)
        .ok_or_else(|| ParamError::bad(format!("{path}/{key}"), "a number", s))
}

/// The integers of a `...SetCfgN` line.
fn set_line(g: &Node, key: &str, path: &str, n: usize) -> Result<Vec<i64>, ParamError> {
    let v = g
        .strings(key)
        .ok_or_else(|| ParamError::missing(format!("{path}/{key}"), "a configuration set"))?;
    let nums: Option<Vec<i64>> = v
        .iter()
        .map(|s| parse_number(s).map(|x| x as i64))
        .collect();
    match nums {
        Some(nums) if nums.len() >= n => Ok(nums),
        _ => Err(ParamError::bad(
            format!("{path}/{key}"),
            "a configuration set of numbers",
            v.join(" "),
        )),
    }
}

/// How many sets a special group declares (`numOfSets`, required when the group is).
fn sets(g: &Node, path: &str) -> Result<usize, ParamError> {
    Ok(int(g, "numOfSets", path)?.max(0) as usize)
}

impl SkinSpec {
    /// The new-style configuration of a skin device's file; `None` when it has none (C++
    /// then sends nothing and uses `signal_oldway`).
    pub fn read(root: &Node) -> Result<Option<SkinSpec>, ParamError> {
        let (Some(b), Some(t)) = (
            root.group("defaultCfgBoard"),
            root.group("defaultCfgTriangle"),
        ) else {
            return Ok(None);
        };
        let board = BoardCfg {
            period: int(&b, "period", "defaultCfgBoard")? as u8,
            skin_type: int(&b, "skinType", "defaultCfgBoard")? as u8,
            no_load: int(&b, "noLoad", "defaultCfgBoard")? as u8,
        };
        if !b.has("diagnostic") {
            return Err(ParamError::missing(
                "defaultCfgBoard/diagnostic",
                "true or false",
            ));
        }
        let triangle = TriangleCfg {
            enabled: t.boolean("enabled").ok_or_else(|| {
                ParamError::missing("defaultCfgTriangle/enabled", "true or false")
            })?,
            shift: int(&t, "shift", "defaultCfgTriangle")? as u8,
            cdc_offset: int(&t, "cdcOffset", "defaultCfgTriangle")? as u16,
        };
        let mut special_boards = Vec::new();
        if let Some(g) = root.group("specialCfgBoards") {
            for j in 1..=sets(&g, "specialCfgBoards")? {
                let v = set_line(&g, &format!("boardSetCfg{j}"), "specialCfgBoards", 6)?;
                special_boards.push(SpecialBoards {
                    patch: v[0] as u8,
                    first: v[1] as u8,
                    last: v[2] as u8,
                    cfg: BoardCfg {
                        period: v[3] as u8,
                        skin_type: v[4] as u8,
                        no_load: v[5] as u8,
                    },
                });
            }
        }
        let mut special_triangles = Vec::new();
        if let Some(g) = root.group("specialCfgTriangles") {
            for j in 1..=sets(&g, "specialCfgTriangles")? {
                let v = set_line(&g, &format!("triangleSetCfg{j}"), "specialCfgTriangles", 7)?;
                special_triangles.push(SpecialTriangles {
                    patch: v[0] as u8,
                    addr: v[1] as u8,
                    first: v[2] as u8,
                    last: v[3] as u8,
                    cfg: TriangleCfg {
                        enabled: v[4] == 1,
                        shift: v[5] as u8,
                        cdc_offset: v[6] as u16,
                    },
                });
            }
        }
        Ok(Some(SkinSpec {
            board,
            triangle,
            special_boards,
            special_triangles,
        }))
    }
}

/// `EmbObjSkin`'s check of a CAN address (1..=14).
fn valid_address(a: u8) -> bool {
    (1..=14).contains(&a)
}

/// The default board configuration, for every board of a patch.
pub fn default_boards(b: &BoardCfg) -> SkinBoardsConfig {
    SkinBoardsConfig {
        can_destination: [0xFFFF, 0xFFFF],
        skin_type: b.skin_type,
        period: b.period,
        noload: b.no_load,
    }
}

/// The default triangle configuration, for triangles 0-15 of every board of a patch.
pub fn default_triangles(t: &TriangleCfg) -> SkinTrianglesConfig {
    SkinTrianglesConfig {
        can_destination: [0xFFFF, 0xFFFF],
        id_start: 0,
        id_end: 15,
        enable: u8::from(t.enabled),
        shift: t.shift,
        cdc_offset: t.cdc_offset,
    }
}

/// A special board set's command for the patch on CAN port `port` (1 or 2) whose boards
/// are `addrs`: an error naming the address when one is not on the patch (C++ refuses
/// the configuration).
pub fn special_boards(
    s: &SpecialBoards,
    port: u8,
    addrs: &[u8],
) -> Result<SkinBoardsConfig, ParamError> {
    let mut dest = [0u16; 2];
    for a in s.first..=s.last {
        if !addrs.contains(&a) {
            return Err(ParamError::bad(
                "specialCfgBoards",
                "boards of the patch",
                format!("address {a} on patch {}", s.patch),
            ));
        }
        if valid_address(a) {
            if let Some(d) = dest.get_mut(usize::from(port.saturating_sub(1))) {
                *d |= 1 << a;
            }
        }
    }
    Ok(SkinBoardsConfig {
        can_destination: dest,
        skin_type: s.cfg.skin_type,
        period: s.cfg.period,
        noload: s.cfg.no_load,
    })
}

/// A special triangle set's command (see [`special_boards`]).
pub fn special_triangles(
    s: &SpecialTriangles,
    port: u8,
    addrs: &[u8],
) -> Result<SkinTrianglesConfig, ParamError> {
    if !addrs.contains(&s.addr) {
        return Err(ParamError::bad(
            "specialCfgTriangles",
            "boards of the patch",
            format!("address {} on patch {}", s.addr, s.patch),
        ));
    }
    let mut dest = [0u16; 2];
    if valid_address(s.addr) {
        if let Some(d) = dest.get_mut(usize::from(port.saturating_sub(1))) {
            *d |= 1 << s.addr;
        }
    }
    Ok(SkinTrianglesConfig {
        can_destination: dest,
        id_start: s.first,
        id_end: s.last,
        enable: u8::from(s.cfg.enabled),
        shift: s.cfg.shift,
        cdc_offset: s.cfg.cdc_offset,
    })
}
