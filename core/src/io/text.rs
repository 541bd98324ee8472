//! Text helpers the readers share (PLY and OFF bodies, volume headers):
//! numbered lines, tokens, numbers, short error excerpts, progress ticks.

use super::{ParseError, ParseResult};
use crate::progress::Progress;

/// Elements (or lines) between progress updates and cancel checks.
pub(super) const PROGRESS_EVERY: usize = 1 << 16;

/// Lines of a byte buffer with their 1-based numbers; `\r\n` endings are
/// accepted and the bytes after any line stay reachable through [`Lines::pos`]
/// (binary bodies follow text headers).
#[derive(Debug, Clone)]
pub(super) struct Lines<'a> {
    data: &'a [u8],
    pos: usize,
    line: usize,
}

impl<'a> Lines<'a> {
    pub(super) fn new(data: &'a [u8]) -> Self {
        Self {
            data,
            pos: 0,
            line: 0,
        }
    }

    /// Byte offset of the next line.
    pub(super) fn pos(&self) -> usize {
        self.pos
    }

    /// Bytes of the whole buffer.
    pub(super) fn len(&self) -> usize {
        self.data.len()
    }

    /// Number of the last line returned (0 before the first).
    pub(super) fn line(&self) -> usize {
        self.line
    }
}

impl<'a> Iterator for Lines<'a> {
    type Item = (usize, &'a [u8]);

    fn next(&mut self) -> Option<Self::Item> {
        let rest = self.data.get(self.pos..).filter(|r| !r.is_empty())?;
        let (line, used) = match rest.iter().position(|&b| b == b'\n') {
            Some(i) => (&rest[..i], i + 1),
            None => (rest, rest.len()),
        };
        self.pos += used;
        self.line += 1;
        Some((self.line, line.strip_suffix(b"\r").unwrap_or(line)))
    }
}

/// Whitespace-separated tokens of one line.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Tokens<'a>(pub(super) &'a [u8]);

impl<'a> Iterator for Tokens<'a> {
    type Item = &'a [u8];

    fn next(&mut self) -> Option<&'a [u8]> {
        let start = self.0.iter().position(|b| !b.is_ascii_whitespace());
        let Some(start) = start else {
            self.0 = &[];
            return None;
        };
        let rest = &self.0[start..];
        let len = rest
            .iter()
            .position(|b| b.is_ascii_whitespace())
            .unwrap_or(rest.len());
        self.0 = &rest[len..];
        Some(&rest[..len])
    }
}

pub(super) fn parse_f32(tok: &[u8]) -> Option<f32> {
    std::str::from_utf8(tok).ok()?.parse().ok()
}

pub(super) fn parse_f64(tok: &[u8]) -> Option<f64> {
    std::str::from_utf8(tok).ok()?.parse().ok()
}

/// Decimal integer with an optional sign; hand-rolled because indices dominate
/// large ascii files.
pub(super) fn parse_int(tok: &[u8]) -> Option<i64> {
    let (neg, digits) = match tok {
        [b'-', rest @ ..] => (true, rest),
        [b'+', rest @ ..] => (false, rest),
        _ => (false, tok),
    };
    if digits.is_empty() {
        return None;
    }
    let mut v: i64 = 0;
    for &b in digits {
        let d = b.wrapping_sub(b'0');
        if d > 9 {
            return None;
        }
        v = v.checked_mul(10)?.checked_add(i64::from(d))?;
    }
    Some(if neg { -v } else { v })
}

/// A token for an error message: lossy, and short even when the token is not.
pub(super) fn shown(tok: &[u8]) -> String {
    let s = String::from_utf8_lossy(&tok[..tok.len().min(40)]);
    if tok.len() > 40 {
        format!("{s}...")
    } else {
        s.into_owned()
    }
}

/// Publishes the fraction read and turns a cancel request into an error.
pub(super) fn tick(progress: &Progress, pos: usize, total: usize) -> ParseResult<()> {
    progress.set_fraction(pos as f32 / total.max(1) as f32);
    progress.check().map_err(|_| ParseError::file("cancelled"))
}
