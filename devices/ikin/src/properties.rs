//! Generic chains described by YARP properties, in the format of iKin's
//! `iKinLimb::fromLinksProperties` / `toLinksProperties`:
//!
//! ```text
//! type right
//! H0 (0 -1 0 0  0 0 -1 0  1 0 0 0  0 0 0 1)
//! HN (1 0 0 0  0 1 0 0  0 0 1 0.05  0 0 0 1)
//! numLinks 2
//! link_0 (A 0.1) (D 0.0) (alpha 90.0) (offset 0.0) (min -90.0) (max 90.0)
//! link_1 (A 0.1) (blocked 10.0)
//! ```
//!
//! Lengths in metres, angles in degrees; `H0`/`HN` are 4×4 matrices by rows
//! (identity when absent). Link defaults are iKin's: `A`, `D`, `alpha`,
//! `offset` 0, `min` −180, `max` 180, released unless `blocked` gives its angle.

use nalgebra::Matrix4;
use yarp_proto::{Bottle, Property, Value};

use crate::chain::Chain;
use crate::error::{KinError, Result};
use crate::link::{Link, DEG2RAD, RAD2DEG};

/// A chain read from links properties, with its `type` (default `"right"`).
#[derive(Debug, Clone, PartialEq)]
pub struct LinksDescription {
    /// The `type` entry.
    pub type_name: String,
    /// The chain.
    pub chain: Chain,
}

fn bad(msg: impl Into<String>) -> KinError {
    KinError::Properties(msg.into())
}

/// Row-major matrix from a list; missing entries are 0 (iKin zeroes the matrix first).
fn matrix(p: &Property, key: &str) -> Result<Matrix4<f64>> {
    let Some(v) = p.find(key) else {
        return Ok(Matrix4::identity());
    };
    let list = v
        .as_list()
        .ok_or_else(|| bad(format!("{key} is not a list")))?;
    let mut m = Matrix4::zeros();
    for (k, item) in list.iter().take(16).enumerate() {
        m[(k / 4, k % 4)] = item
            .as_f64()
            .filter(|x| x.is_finite())
            .ok_or_else(|| bad(format!("{key}[{k}] is not a number")))?;
    }
    Ok(m)
}

fn number(group: &Bottle, link: &str, key: &str, default: f64) -> Result<f64> {
    match group.find(key) {
        None => Ok(default),
        Some(v) => v
            .as_f64()
            .filter(|x| x.is_finite())
            .ok_or_else(|| bad(format!("{link}: {key} is not a number"))),
    }
}

/// Builds a chain from links properties (iKin `fromLinksProperties`).
pub fn from_links_properties(p: &Property) -> Result<LinksDescription> {
    let type_name = p
        .find("type")
        .and_then(|v| v.as_str().map(str::to_owned))
        .unwrap_or_else(|| "right".to_owned());
    let num = p.find("numLinks").and_then(Value::as_i64).unwrap_or(0);
    if num <= 0 {
        return Err(bad("numLinks is missing or not positive"));
    }
    let mut chain = Chain::new();
    chain.set_h0(matrix(p, "H0")?)?;
    chain.set_hn(matrix(p, "HN")?)?;
    for i in 0..num as usize {
        let name = format!("link_{i}");
        let g = p
            .find_group(&name)
            .ok_or_else(|| bad(format!("{name} is missing")))?;
        let link = Link::new(
            number(g, &name, "A", 0.0)?,
            number(g, &name, "D", 0.0)?,
            number(g, &name, "alpha", 0.0)? * DEG2RAD,
            number(g, &name, "offset", 0.0)? * DEG2RAD,
            number(g, &name, "min", -180.0)? * DEG2RAD,
            number(g, &name, "max", 180.0)? * DEG2RAD,
        );
        if link.min > link.max {
            return Err(KinError::InvalidBounds {
                min: link.min,
                max: link.max,
            });
        }
        chain.push_link(link);
        if g.check("blocked") {
            chain.block_link(i, number(g, &name, "blocked", 0.0)? * DEG2RAD)?;
        }
    }
    Ok(LinksDescription { type_name, chain })
}

fn matrix_value(m: &Matrix4<f64>) -> Value {
    // nalgebra stores by columns; the property lists rows.
    Value::List(Bottle::from(
        m.transpose()
            .iter()
            .map(|&x| Value::from(x))
            .collect::<Vec<_>>(),
    ))
}

/// Describes a chain as links properties (iKin `toLinksProperties`).
pub fn to_links_properties(type_name: &str, chain: &Chain) -> Property {
    let mut p = Property::new();
    p.put("type", type_name);
    p.put("numLinks", chain.n() as i64);
    p.put("H0", matrix_value(chain.h0()));
    p.put("HN", matrix_value(chain.hn()));
    for (i, l) in chain.links().iter().enumerate() {
        let mut g = Property::new();
        g.put("A", l.a);
        g.put("D", l.d);
        g.put("alpha", l.alpha * RAD2DEG);
        g.put("offset", l.offset * RAD2DEG);
        g.put("min", l.min * RAD2DEG);
        g.put("max", l.max * RAD2DEG);
        if chain.is_blocked(i).unwrap_or(false) {
            g.put("blocked", chain.all_angles()[i] * RAD2DEG);
        }
        p.put_group(format!("link_{i}"), &g);
    }
    p
}
