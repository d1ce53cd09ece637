//! The record structure of a `.zmx` file: one record per line, a four-letter keyword and its
//! arguments; `SURF n` opens a surface block whose records are indented. Every record keeps
//! the byte offsets of its keyword and arguments for error messages.

use crate::io::LensFileError;
use crate::io::located::Reporter;
use crate::io::text::tokens;

/// One line: keyword, arguments and the raw text after the keyword.
#[derive(Clone, Debug)]
pub(super) struct Record<'a> {
    pub key: &'a str,
    /// Byte offset of the keyword.
    pub pos: usize,
    /// Whitespace-separated arguments with their byte offsets.
    pub args: Vec<(usize, &'a str)>,
    /// Everything after the keyword, trimmed (for `NAME`, `NOTE`, `COMM`).
    pub rest: &'a str,
}

impl Record<'_> {
    /// Byte offset of argument `i`, or of the keyword when it is missing.
    pub fn arg_pos(&self, i: usize) -> usize {
        self.args.get(i).map_or(self.pos, |a| a.0)
    }

    /// Argument `i` as text.
    pub fn arg(&self, i: usize) -> Option<&str> {
        self.args.get(i).map(|a| a.1)
    }

    /// Argument `i` as a finite number; an error names the record when it is missing or not
    /// a number.
    pub fn number(&self, ctx: &Reporter<'_>, i: usize) -> Result<f64, LensFileError> {
        let Some(&(pos, t)) = self.args.get(i) else {
            return Err(ctx.error(
                self.pos,
                self.key,
                format!("`{}` needs a value in position {}", self.key, i + 1),
            ));
        };
        match t.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(ctx.error(
                pos,
                self.key,
                format!("expected a finite number, got `{t}`"),
            )),
        }
    }

    /// Argument `i` as a non-negative integer.
    pub fn integer(&self, ctx: &Reporter<'_>, i: usize) -> Result<usize, LensFileError> {
        let v = self.number(ctx, i)?;
        if v < 0.0 || v.fract() != 0.0 || v > 1e9 {
            return Err(ctx.error(
                self.arg_pos(i),
                self.key,
                format!("expected a whole number ≥ 0, got {v}"),
            ));
        }
        Ok(v as usize)
    }
}

/// A `SURF n` block.
#[derive(Clone, Debug)]
pub(super) struct Block<'a> {
    /// The surface number written after `SURF`.
    pub number: usize,
    /// Byte offset of `SURF`.
    pub pos: usize,
    pub records: Vec<Record<'a>>,
}

impl<'a> Block<'a> {
    /// The first record with this keyword.
    pub fn get(&self, key: &str) -> Option<&Record<'a>> {
        self.records.iter().find(|r| r.key == key)
    }

    /// Every record with this keyword.
    pub fn all<'s>(&'s self, key: &'s str) -> impl Iterator<Item = &'s Record<'a>> + 's {
        self.records.iter().filter(move |r| r.key == key)
    }
}

/// The file split into system records (outside any surface block) and surface blocks.
#[derive(Clone, Debug, Default)]
pub(super) struct Records<'a> {
    pub system: Vec<Record<'a>>,
    pub surfaces: Vec<Block<'a>>,
}

impl<'a> Records<'a> {
    /// The last system record with this keyword (Zemax keeps the last one).
    pub fn get(&self, key: &str) -> Option<&Record<'a>> {
        self.system.iter().rev().find(|r| r.key == key)
    }

    /// Every system record with this keyword, in file order.
    pub fn all<'s>(&'s self, key: &'s str) -> impl Iterator<Item = &'s Record<'a>> + 's {
        self.system.iter().filter(move |r| r.key == key)
    }
}

/// Keywords that belong to a surface even when a hand-edited file lost their indentation.
const SURFACE_KEYS: &[&str] = &[
    "TYPE", "CURV", "DISZ", "GLAS", "DIAM", "CLAP", "FLAP", "STOP", "CONI", "PARM", "XDAT", "COAT",
    "COMM", "SQAP", "ELAP", "OBSC", "OBDC", "SCBD", "IGNR", "HIDE", "MIRR", "SLAB", "POPS", "FIMP",
    "MEMA", "OEMA", "MAZH", "SSID", "VPAR", "VCON", "PPAR", "PZUP", "TCED", "EDGE",
];

/// Splits the text into records. Errors: a `SURF` without a whole number.
pub(super) fn split<'a>(ctx: &Reporter<'_>, text: &'a str) -> Result<Records<'a>, LensFileError> {
    let mut out = Records::default();
    let mut in_block = false;
    let mut start = 0;
    for raw in text.split_inclusive('\n') {
        let line_start = start;
        start += raw.len();
        let toks = tokens(raw);
        let Some(&(key_off, key)) = toks.first() else {
            continue;
        };
        let indented = key_off > 0;
        let after = &raw[key_off + key.len()..];
        let rest = after.trim();
        let record = Record {
            key,
            pos: line_start + key_off,
            args: toks[1..]
                .iter()
                .map(|&(o, t)| (line_start + o, t))
                .collect(),
            rest,
        };
        if key == "SURF" {
            let number = record.integer(ctx, 0)?;
            out.surfaces.push(Block {
                number,
                pos: record.pos,
                records: Vec::new(),
            });
            in_block = true;
            continue;
        }
        // A surface block ends at the first unindented record that is not a surface's.
        in_block &= indented || SURFACE_KEYS.contains(&key);
        match out.surfaces.last_mut() {
            Some(block) if in_block => block.records.push(record),
            _ => out.system.push(record),
        }
    }
    Ok(out)
}
