//! `yarp bottle encode|decode`: YARP text <-> binary Bottle encoding as hex, one bottle per
//! line, for inspecting what goes on the wire.

use anyhow::{bail, Context, Result};
use clap::Subcommand;
use std::io::{BufRead, Write};
use yarp_proto::Bottle;

#[derive(Subcommand)]
pub enum BottleCommand {
    /// YARP text (arguments joined by spaces, or one bottle per stdin line) -> hex encoding.
    Encode {
        /// Bottle text; read lines from stdin when absent.
        text: Vec<String>,
    },
    /// Hex encoding (arguments, or one bottle per stdin line) -> text as `yarp read` prints it.
    Decode {
        /// Hex bytes (whitespace allowed); read lines from stdin when absent.
        hex: Vec<String>,
    },
}

pub fn run(cmd: BottleCommand) -> Result<()> {
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    match cmd {
        BottleCommand::Encode { text } => {
            if text.is_empty() {
                for (n, line) in stdin_lines()?.into_iter().enumerate() {
                    let hex =
                        encode_line(&line).with_context(|| format!("stdin line {}", n + 1))?;
                    writeln!(out, "{hex}")?;
                }
            } else {
                writeln!(out, "{}", encode_line(text.join(" ").as_bytes())?)?;
            }
        }
        BottleCommand::Decode { hex } => {
            if hex.is_empty() {
                for (n, line) in stdin_lines()?.into_iter().enumerate() {
                    let text = decode_line(&String::from_utf8_lossy(&line))
                        .with_context(|| format!("stdin line {}", n + 1))?;
                    out.write_all(&text)?;
                    writeln!(out)?;
                }
            } else {
                out.write_all(&decode_line(&hex.join(""))?)?;
                writeln!(out)?;
            }
        }
    }
    Ok(())
}

fn stdin_lines() -> Result<Vec<Vec<u8>>> {
    let mut lines = Vec::new();
    for line in std::io::stdin().lock().split(b'\n') {
        let mut line = line.context("reading stdin")?;
        if line.last() == Some(&b'\r') {
            line.pop();
        }
        lines.push(line);
    }
    Ok(lines)
}

fn encode_line(text: &[u8]) -> Result<String> {
    let bottle = yarp_proto::text::try_parse(text)?;
    Ok(hex::encode(bottle.encode()))
}

fn decode_line(hex_text: &str) -> Result<Vec<u8>> {
    let compact: String = hex_text.chars().filter(|c| !c.is_whitespace()).collect();
    if compact.is_empty() {
        bail!("no hex bytes given");
    }
    let bytes = hex::decode(&compact).map_err(|e| anyhow::anyhow!("invalid hex: {e}"))?;
    let (bottle, used) = yarp_proto::binary::decode(&bytes)
        .map_err(|e| anyhow::anyhow!("not a valid YARP bottle: {e}"))?;
    if used < bytes.len() {
        // C++ ignores trailing bytes too; say so, since this is a debugging tool
        eprintln!(
            "yarp: note: {} trailing byte(s) after the bottle ignored",
            bytes.len() - used
        );
    }
    Ok(Bottle::to_text(&bottle))
}
