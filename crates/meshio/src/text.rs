//! Helpers shared by the text formats: UTF-8 check with a line number, a whitespace tokenizer
//! that knows the line of each token, number parsing with messages that say what was expected,
//! and [`F`], which writes an `f32` so that it reads back bit-identically.

use std::path::Path;
use std::str::FromStr;

use crate::MeshIoError;

/// The bytes as text, or a parse error naming the line of the first byte that is not UTF-8.
pub(crate) fn utf8<'a>(bytes: &'a [u8], path: &Path, format: &str) -> Result<&'a str, MeshIoError> {
    std::str::from_utf8(bytes).map_err(|e| {
        let valid = bytes.get(..e.valid_up_to()).unwrap_or_default();
        MeshIoError::parse(
            path,
            line_of_offset(valid, valid.len()),
            format!(
                "byte {} is not text (not UTF-8): {format} files are text; is this a binary file with the wrong extension?",
                e.valid_up_to()
            ),
        )
    })
}

/// The 1-based line that byte `offset` of `bytes` lies on.
pub(crate) fn line_of_offset(bytes: &[u8], offset: usize) -> usize {
    let upto = bytes.get(..offset).unwrap_or(bytes);
    1 + upto.iter().filter(|&&b| b == b'\n').count()
}

/// Whitespace-separated tokens of a text, each with its 1-based line.
#[derive(Clone)]
pub(crate) struct Tokens<'a> {
    text: &'a str,
    pos: usize,
    /// Line of `pos`.
    pos_line: usize,
    /// Line of the last token returned.
    token_line: usize,
}

impl<'a> Tokens<'a> {
    pub(crate) fn new(text: &'a str) -> Self {
        Tokens {
            text,
            pos: 0,
            pos_line: 1,
            token_line: 1,
        }
    }

    /// Tokens of `text` after its first `skip` lines (which the caller reads itself).
    pub(crate) fn after_lines(text: &'a str, skip: usize) -> Self {
        let mut t = Tokens::new(text);
        for _ in 0..skip {
            match text
                .as_bytes()
                .get(t.pos..)
                .and_then(|r| r.iter().position(|&b| b == b'\n'))
            {
                Some(k) => {
                    t.pos += k + 1;
                    t.pos_line += 1;
                }
                None => t.pos = text.len(),
            }
        }
        t.token_line = t.pos_line;
        t
    }

    /// The next token, or `None` at the end of the text.
    pub(crate) fn next_token(&mut self) -> Option<&'a str> {
        let bytes = self.text.as_bytes();
        while let Some(&b) = bytes.get(self.pos) {
            if !b.is_ascii_whitespace() {
                break;
            }
            if b == b'\n' {
                self.pos_line += 1;
            }
            self.pos += 1;
        }
        let start = self.pos;
        while let Some(&b) = bytes.get(self.pos) {
            if b.is_ascii_whitespace() {
                break;
            }
            self.pos += 1;
        }
        if start == self.pos {
            self.token_line = self.pos_line;
            return None;
        }
        self.token_line = self.pos_line;
        // Both ends sit next to ASCII whitespace or at the ends of the text, so on char
        // boundaries; `get` only avoids a panic path.
        self.text.get(start..self.pos)
    }

    /// The next token without consuming it.
    pub(crate) fn peek(&self) -> Option<&'a str> {
        self.clone().next_token()
    }

    /// The line of the last token returned (or of the end of the text, after `None`).
    pub(crate) fn line(&self) -> usize {
        self.token_line
    }

    /// The rest of the current line (after the last token), trimmed; the next token comes from
    /// the following line.
    pub(crate) fn rest_of_line(&mut self) -> &'a str {
        let bytes = self.text.as_bytes();
        let start = self.pos;
        while let Some(&b) = bytes.get(self.pos) {
            if b == b'\n' {
                break;
            }
            self.pos += 1;
        }
        self.text.get(start..self.pos).unwrap_or_default().trim()
    }

    /// The next token, or an error saying that `what` was expected where the file ends.
    pub(crate) fn need(&mut self, path: &Path, what: &str) -> Result<&'a str, MeshIoError> {
        match self.next_token() {
            Some(t) => Ok(t),
            None => Err(MeshIoError::parse(
                path,
                self.line(),
                format!("the file ends where {what} was expected: is it truncated?"),
            )),
        }
    }

    /// Consumes the next token, which must be `keyword` (ASCII case-insensitive).
    pub(crate) fn expect(&mut self, path: &Path, keyword: &str) -> Result<(), MeshIoError> {
        let t = self.need(path, &format!("`{keyword}`"))?;
        if t.eq_ignore_ascii_case(keyword) {
            Ok(())
        } else {
            Err(MeshIoError::parse(
                path,
                self.line(),
                format!("expected `{keyword}`, found `{}`", shorten(t)),
            ))
        }
    }

    /// The next token parsed as a `T`; `what` names it in the error.
    pub(crate) fn number<T: FromStr>(&mut self, path: &Path, what: &str) -> Result<T, MeshIoError> {
        let t = self.need(path, what)?;
        parse_number(t, path, self.line(), what)
    }
}

/// `token` parsed as a `T`, or an error at `line` saying that `what` was expected.
pub(crate) fn parse_number<T: FromStr>(
    token: &str,
    path: &Path,
    line: usize,
    what: &str,
) -> Result<T, MeshIoError> {
    token.parse().map_err(|_| {
        MeshIoError::parse(
            path,
            line,
            format!("expected {what}, found `{}`", shorten(token)),
        )
    })
}

/// A token cut to a length that fits in an error message.
pub(crate) fn shorten(token: &str) -> String {
    const MAX: usize = 40;
    match token.char_indices().nth(MAX) {
        Some((cut, _)) => format!("{}...", token.get(..cut).unwrap_or_default()),
        None => token.to_string(),
    }
}

/// A starting capacity for `count` items parsed from `available` bytes, each at least
/// `min_bytes` long: never more than the data can hold, so a corrupt count cannot make a huge
/// allocation.
pub(crate) fn capacity(count: usize, available: usize, min_bytes: usize) -> usize {
    count.min(available / min_bytes.max(1))
}

/// Writes `f32` so that parsing the text gives back the same bits (shortest round-trip form).
pub(crate) struct F(pub(crate) f32);

impl std::fmt::Display for F {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        // `Debug` of f32 is the shortest string that parses back to the same value, and uses
        // exponent notation for very small and large magnitudes (`1e-7`), unlike `Display`.
        write!(f, "{:?}", self.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tokens_know_their_lines() {
        let mut t = Tokens::new("solid a b\n\n  facet normal 0 0 1\r\nend");
        assert_eq!(t.next_token(), Some("solid"));
        assert_eq!(t.rest_of_line(), "a b");
        assert_eq!(t.next_token(), Some("facet"));
        assert_eq!(t.line(), 3);
        assert_eq!(t.peek(), Some("normal"));
        assert_eq!(t.next_token(), Some("normal"));
        let p = Path::new("x");
        assert_eq!(t.number::<f32>(p, "x").unwrap(), 0.0);
        assert!(t.expect(p, "0").is_ok());
        assert!(t.expect(p, "2").is_err());
        assert_eq!(t.next_token(), Some("end"));
        assert_eq!(t.line(), 4);
        assert_eq!(t.next_token(), None);
        let e = t.need(p, "a vertex").unwrap_err();
        assert!(e.to_string().contains("line 4"), "{e}");
    }

    #[test]
    fn after_lines_skips_and_counts() {
        let mut t = Tokens::after_lines("a\n\nb c\n", 2);
        assert_eq!(t.next_token(), Some("b"));
        assert_eq!(t.line(), 3);
        let mut t = Tokens::after_lines("a", 2);
        assert_eq!(t.next_token(), None);
    }

    #[test]
    fn non_utf8_names_the_line() {
        let e = utf8(b"ok\nok\n\xff", Path::new("f.vtk"), "VTK").unwrap_err();
        assert!(matches!(e, MeshIoError::Parse { line: 3, .. }), "{e}");
    }

    #[test]
    fn shorten_cuts_long_tokens() {
        assert_eq!(shorten("abc"), "abc");
        assert_eq!(shorten(&"x".repeat(100)).len(), 43);
    }

    #[test]
    fn floats_round_trip_bitwise() {
        for x in [
            0.1f32,
            1.0 / 3.0,
            1e-7,
            -2.5e30,
            f32::MIN_POSITIVE,
            16777217.0,
        ] {
            let s = F(x).to_string();
            assert_eq!(s.parse::<f32>().unwrap().to_bits(), x.to_bits(), "{s}");
        }
        assert_eq!(F(1e-7).to_string(), "1e-7");
    }
}
