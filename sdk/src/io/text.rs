//! Turning a lens file's bytes into text, and byte offsets into 1-based line and column.

use std::borrow::Cow;

/// A file's bytes could not be decoded; `offset` is the byte offset of the first bad byte.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct DecodeError {
    pub offset: usize,
    pub message: String,
}

/// Decodes UTF-8 (with or without a byte-order mark) or UTF-16 with a byte-order mark.
pub(crate) fn decode(bytes: &[u8]) -> Result<Cow<'_, str>, DecodeError> {
    if let Some(rest) = bytes.strip_prefix(b"\xEF\xBB\xBF") {
        return utf8(rest).map(Cow::Borrowed);
    }
    if let Some(rest) = bytes.strip_prefix(b"\xFF\xFE") {
        return utf16(rest, u16::from_le_bytes).map(Cow::Owned);
    }
    if let Some(rest) = bytes.strip_prefix(b"\xFE\xFF") {
        return utf16(rest, u16::from_be_bytes).map(Cow::Owned);
    }
    utf8(bytes).map(Cow::Borrowed)
}

/// How [`decode_legacy`] read the bytes (for warnings).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Encoding {
    Utf8,
    Utf16Le,
    Utf16Be,
    /// ISO-8859-1 (Latin-1): every byte is the code point of the same value.
    Latin1,
}

/// Decodes the text files older tools write (Zemax `.zmx`, PBRT tables): a byte-order mark
/// (UTF-8, UTF-16LE, UTF-16BE) decides; without one, UTF-16 is recognised by a zero byte in
/// the first two, then UTF-8 is tried, and anything that is not valid UTF-8 is read as
/// ISO-8859-1, which every byte sequence is. Returns the text without the mark.
pub(crate) fn decode_legacy(bytes: &[u8]) -> Result<(Cow<'_, str>, Encoding), DecodeError> {
    if let Some(rest) = bytes.strip_prefix(b"\xEF\xBB\xBF") {
        return Ok((Cow::Owned(utf8_or_latin1(rest).0), Encoding::Utf8));
    }
    if let Some(rest) = bytes.strip_prefix(b"\xFF\xFE") {
        return Ok((
            Cow::Owned(utf16(rest, u16::from_le_bytes)?),
            Encoding::Utf16Le,
        ));
    }
    if let Some(rest) = bytes.strip_prefix(b"\xFE\xFF") {
        return Ok((
            Cow::Owned(utf16(rest, u16::from_be_bytes)?),
            Encoding::Utf16Be,
        ));
    }
    match bytes {
        [a, 0, ..] if *a != 0 => {
            return Ok((
                Cow::Owned(utf16(bytes, u16::from_le_bytes)?),
                Encoding::Utf16Le,
            ));
        }
        [0, b, ..] if *b != 0 => {
            return Ok((
                Cow::Owned(utf16(bytes, u16::from_be_bytes)?),
                Encoding::Utf16Be,
            ));
        }
        _ => {}
    }
    match std::str::from_utf8(bytes) {
        Ok(s) => Ok((Cow::Borrowed(s), Encoding::Utf8)),
        Err(_) => Ok((Cow::Owned(latin1(bytes)), Encoding::Latin1)),
    }
}

fn utf8_or_latin1(bytes: &[u8]) -> (String, Encoding) {
    match std::str::from_utf8(bytes) {
        Ok(s) => (s.to_string(), Encoding::Utf8),
        Err(_) => (latin1(bytes), Encoding::Latin1),
    }
}

fn latin1(bytes: &[u8]) -> String {
    bytes.iter().map(|&b| char::from(b)).collect()
}

fn utf8(bytes: &[u8]) -> Result<&str, DecodeError> {
    std::str::from_utf8(bytes).map_err(|e| DecodeError {
        offset: e.valid_up_to(),
        message: "the file is not valid UTF-8 (save it as UTF-8)".into(),
    })
}

fn utf16(bytes: &[u8], unit: fn([u8; 2]) -> u16) -> Result<String, DecodeError> {
    if !bytes.len().is_multiple_of(2) {
        return Err(DecodeError {
            offset: bytes.len(),
            message: "the UTF-16 file has an odd number of bytes".into(),
        });
    }
    let units: Vec<u16> = bytes.chunks_exact(2).map(|c| unit([c[0], c[1]])).collect();
    String::from_utf16(&units).map_err(|_| DecodeError {
        offset: 0,
        message: "the file is not valid UTF-16".into(),
    })
}

/// Whitespace-separated tokens of `s` with their byte offsets in `s`.
pub(crate) fn tokens(s: &str) -> Vec<(usize, &str)> {
    let mut out = Vec::new();
    let mut start = None;
    for (i, c) in s.char_indices() {
        if c.is_whitespace() {
            if let Some(b) = start.take() {
                out.push((b, &s[b..i]));
            }
        } else if start.is_none() {
            start = Some(i);
        }
    }
    if let Some(b) = start {
        out.push((b, &s[b..]));
    }
    out
}

/// Maps byte offsets of a text to 1-based (line, column); columns count characters.
#[derive(Debug)]
pub(crate) struct LineIndex<'a> {
    text: &'a str,
    starts: Vec<usize>,
}

impl<'a> LineIndex<'a> {
    pub fn new(text: &'a str) -> Self {
        let starts = std::iter::once(0)
            .chain(text.match_indices('\n').map(|(i, _)| i + 1))
            .collect();
        LineIndex { text, starts }
    }

    /// Line and column of byte `offset` (clamped to the text).
    pub fn line_col(&self, offset: usize) -> (usize, usize) {
        let offset = offset.min(self.text.len());
        let line = self.starts.partition_point(|&s| s <= offset).max(1);
        let start = self.starts[line - 1];
        let column = match self.text.get(start..offset) {
            Some(prefix) => prefix.chars().count(),
            None => offset - start,
        };
        (line, column + 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_and_column_are_one_based() {
        let idx = LineIndex::new("ab\ncdé\n\nx");
        assert_eq!(idx.line_col(0), (1, 1));
        assert_eq!(idx.line_col(1), (1, 2));
        assert_eq!(idx.line_col(3), (2, 1));
        // 'é' is two bytes but one column.
        assert_eq!(idx.line_col(7), (2, 4));
        assert_eq!(idx.line_col(8), (3, 1));
        assert_eq!(idx.line_col(9), (4, 1));
        assert_eq!(idx.line_col(1000), (4, 2));
    }

    #[test]
    fn decodes_boms_and_reports_bad_utf8() {
        assert_eq!(decode(b"\xEF\xBB\xBF<a/>").unwrap(), "<a/>");
        assert_eq!(decode(b"\xFF\xFE<\0a\0").unwrap(), "<a");
        assert_eq!(decode(b"\xFE\xFF\0<\0a").unwrap(), "<a");
        let e = decode(b"<a>\xE9</a>").unwrap_err();
        assert_eq!(e.offset, 3);
    }

    #[test]
    fn tokens_keep_their_byte_offsets() {
        assert_eq!(
            tokens("  DISZ\t1.5  é x\r"),
            vec![(2, "DISZ"), (7, "1.5"), (12, "é"), (15, "x")]
        );
        assert!(tokens(" \t ").is_empty());
    }

    #[test]
    fn legacy_files_decode_from_every_encoding_zemax_writes() {
        let (t, e) = decode_legacy(b"\xFF\xFEV\0E\0").unwrap();
        assert_eq!((t.as_ref(), e), ("VE", Encoding::Utf16Le));
        let (t, e) = decode_legacy(b"\xFE\xFF\0V\0E").unwrap();
        assert_eq!((t.as_ref(), e), ("VE", Encoding::Utf16Be));
        // UTF-16 without a byte-order mark, either order.
        let (t, e) = decode_legacy(b"V\0E\0").unwrap();
        assert_eq!((t.as_ref(), e), ("VE", Encoding::Utf16Le));
        let (t, e) = decode_legacy(b"\0V\0E").unwrap();
        assert_eq!((t.as_ref(), e), ("VE", Encoding::Utf16Be));
        let (t, e) = decode_legacy("NAME Ø18".as_bytes()).unwrap();
        assert_eq!((t.as_ref(), e), ("NAME Ø18", Encoding::Utf8));
        // 0xD8 alone is not UTF-8: ISO-8859-1 reads it as Ø.
        let (t, e) = decode_legacy(b"NAME \xD818").unwrap();
        assert_eq!((t.as_ref(), e), ("NAME Ø18", Encoding::Latin1));
        let (t, _) = decode_legacy(b"\xEF\xBB\xBFUNIT").unwrap();
        assert_eq!(t, "UNIT");
        assert!(decode_legacy(b"\xFF\xFEV").is_err());
        assert_eq!(decode_legacy(b"").unwrap().0, "");
    }
}
