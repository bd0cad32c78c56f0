//! A streaming tokenizer for the whitespace-separated text formats (p3f, NFF, ascii PLY, OBJ).
//!
//! It reads through a fixed buffer, so a 30 MB mesh never becomes a 30 MB `String`, let alone a token
//! vector per line; gzip is recognised by its magic bytes, not by the file name. Every token carries its
//! line and column so that every error can say `path:line:col`. A UTF-8 byte-order mark at the start of
//! the text (of the data within a gzip), which some Windows editors write, is skipped.

use std::fmt;
use std::io::{self, BufRead, BufReader, Read};
use std::ops::RangeInclusive;
use std::path::{Path, PathBuf};

use flate2::bufread::MultiGzDecoder;
use glam::Vec3;

use crate::error::{Error, Result};
use crate::files::{io_reason, open_regular};

const BUFFER_SIZE: usize = 1 << 16;
/// No token of any of our formats is this long; binary garbage usually is.
const MAX_TOKEN: usize = 1024;
/// The UTF-8 encoding of U+FEFF, the byte-order mark.
const BOM: &[u8] = b"\xef\xbb\xbf";

/// One token: a run of bytes between whitespace, valid until the next call that advances the lexer.
#[derive(Clone, Copy, Debug)]
pub struct Tok {
    start: usize,
    len: usize,
    /// 1-based line of the token's first byte.
    pub line: u64,
    /// 1-based column (in bytes) of the token's first byte.
    pub col: u64,
}

/// The streaming tokenizer. `#` starts a comment to the end of the line.
pub struct Lexer {
    path: PathBuf,
    // One dynamic call per buffer refill (64 KiB), never per token.
    reader: Box<dyn Read + Send>,
    buf: Vec<u8>,
    pos: usize,
    end: usize,
    eof: bool,
    /// Whether the first read (and the byte-order mark check) is done.
    started: bool,
    /// Absolute offset of `buf[0]` in the decompressed stream.
    consumed: u64,
    line: u64,
    /// Absolute offset of the first byte of the current line.
    line_start: u64,
    peeked: Option<Tok>,
}

/// Opens a file for reading, transparently decompressing gzip (recognised by its magic bytes). Only a
/// regular file is opened ([`open_regular`]).
pub fn open(path: &Path) -> Result<Box<dyn Read + Send>> {
    let file = open_regular(path).map_err(|why| Error::file(path, format!("cannot open: {why}")))?;
    decompressed(path, Box::new(file))
}

/// `reader`, decompressed if it starts with gzip's magic bytes; `path` names it in errors.
pub fn decompressed(path: &Path, reader: Box<dyn Read + Send>) -> Result<Box<dyn Read + Send>> {
    let mut reader = BufReader::with_capacity(BUFFER_SIZE, reader);
    let head = reader
        .fill_buf()
        .map_err(|e| Error::file(path, format!("cannot read: {}", io_reason(&e))))?;
    if head.starts_with(&[0x1f, 0x8b]) {
        Ok(Box::new(MultiGzDecoder::new(reader)))
    } else {
        Ok(Box::new(reader))
    }
}

/// The first bytes of `reader`, up to the end of its first line that is neither blank nor a comment
/// (or 64 KiB, or the end): enough to tell its format ([`super::Format::sniff`]). The caller reads
/// them before the rest.
pub fn head(path: &Path, reader: &mut dyn Read) -> Result<Vec<u8>> {
    const MAX: usize = 64 << 10;
    let mut head = Vec::new();
    let mut chunk = [0u8; 4096];
    loop {
        let statement = head
            .split(|&b| b == b'\n')
            .rev()
            .skip(1)
            .any(|l: &[u8]| !l.trim_ascii().is_empty() && !l.trim_ascii().starts_with(b"#"));
        if statement || head.len() >= MAX {
            return Ok(head);
        }
        match reader.read(&mut chunk) {
            Ok(0) => return Ok(head),
            Ok(n) => head.extend_from_slice(&chunk[..n]),
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => return Err(Error::file(path, format!("cannot read: {}", io_reason(&e)))),
        }
    }
}

/// Shows a found token in an error message: quoted, escaped, and cut short if long.
pub fn show(bytes: &[u8]) -> String {
    let text = String::from_utf8_lossy(&bytes[..bytes.len().min(40)]);
    let mut shown = format!("{text:?}");
    if bytes.len() > 40 {
        shown.push('…');
    }
    shown
}

fn is_space(b: u8) -> bool {
    matches!(b, b' ' | b'\t' | b'\r' | b'\n' | 0x0b | 0x0c)
}

/// Whether the [`Lexer`] finds a token in `line` (a line without its line break): something other
/// than white space before any comment.
pub fn holds_token(line: &[u8]) -> bool {
    line.iter().find(|&&b| !is_space(b)).is_some_and(|&b| b != b'#')
}

/// Where a byte lies in a text: its offset from the start, its line and its column.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Position {
    pub offset: u64,
    pub line: u64,
    pub col: u64,
}

/// What a [`Lexer`] has not read yet: the bytes it read ahead, then the rest of its reader.
pub struct Rest {
    pub bytes: Vec<u8>,
    pub reader: Box<dyn Read + Send>,
    /// The position of the first byte.
    pub at: Position,
}

impl Lexer {
    /// Opens `path` (gzipped or not) for tokenizing.
    pub fn open(path: &Path) -> Result<Self> {
        Ok(Self::new(path, open(path)?))
    }

    /// Tokenizes `reader`; `path` is only used in error messages.
    pub fn new(path: &Path, reader: Box<dyn Read + Send>) -> Self {
        Lexer {
            path: path.to_path_buf(),
            reader,
            buf: vec![0; BUFFER_SIZE],
            pos: 0,
            end: 0,
            eof: false,
            started: false,
            consumed: 0,
            line: 1,
            line_start: 0,
            peeked: None,
        }
    }

    /// Reads `reader` as the text that goes on from `at` (no byte-order mark is looked for).
    pub fn resume(path: &Path, reader: Box<dyn Read + Send>, at: Position) -> Self {
        let mut lx = Self::new(path, reader);
        lx.started = true;
        lx.consumed = at.offset;
        lx.line = at.line;
        lx.line_start = at.offset - (at.col - 1);
        lx
    }

    /// What is left to read, for another lexer to [`resume`](Lexer::resume).
    pub fn into_rest(self) -> Rest {
        debug_assert!(self.peeked.is_none(), "into_rest after peek");
        let (line, col) = self.position();
        let offset = self.offset();
        Rest {
            bytes: self.buf[self.pos..self.end].to_vec(),
            reader: self.reader,
            at: Position { offset, line, col },
        }
    }

    /// The file being read.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Moves the bytes from `keep` on to the front of the buffer and reads more after them.
    /// Returns false at the end of the data.
    fn refill(&mut self, keep: usize) -> Result<bool> {
        if self.eof {
            return Ok(false);
        }
        if !self.started {
            return self.start();
        }
        self.buf.copy_within(keep..self.end, 0);
        self.consumed += keep as u64;
        self.pos -= keep;
        self.end -= keep;
        self.read_more()
    }

    /// The first read, past a byte-order mark: it is not part of the first word, and the first column
    /// is the one after it. Returns false if the data ends first.
    fn start(&mut self) -> Result<bool> {
        debug_assert!(self.end == 0, "the first read");
        self.started = true;
        // A read may stop within the mark.
        while self.end < BOM.len() && self.read_more()? {}
        if self.buf[..self.end].starts_with(BOM) {
            self.pos = BOM.len();
            self.line_start = BOM.len() as u64;
        }
        Ok(self.pos < self.end || self.refill(self.pos)?)
    }

    /// Reads more data after `end`. Returns false at the end of the data.
    fn read_more(&mut self) -> Result<bool> {
        loop {
            match self.reader.read(&mut self.buf[self.end..]) {
                Ok(0) => {
                    self.eof = true;
                    return Ok(false);
                }
                Ok(n) => {
                    self.end += n;
                    return Ok(true);
                }
                Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
                Err(e) => {
                    let (line, col) = self.position();
                    return Err(Error::at(
                        &self.path,
                        line,
                        col,
                        format!("cannot read: {} (truncated or corrupt file?)", io_reason(&e)),
                    ));
                }
            }
        }
    }

    /// Line and column of the read position.
    pub fn position(&self) -> (u64, u64) {
        let abs = self.consumed + self.pos as u64;
        (self.line, abs - self.line_start + 1)
    }

    /// The next token, or `None` at the end of the data.
    pub fn next_token(&mut self) -> Result<Option<Tok>> {
        if let Some(tok) = self.peeked.take() {
            return Ok(Some(tok));
        }
        // Skip whitespace and comments.
        loop {
            if self.pos == self.end && !self.refill(self.pos)? {
                return Ok(None);
            }
            let b = self.buf[self.pos];
            if b == b'\n' {
                self.pos += 1;
                self.line += 1;
                self.line_start = self.consumed + self.pos as u64;
            } else if is_space(b) {
                self.pos += 1;
            } else if b == b'#' {
                while self.pos < self.end || self.refill(self.pos)? {
                    if self.buf[self.pos] == b'\n' {
                        break;
                    }
                    self.pos += 1;
                }
            } else {
                break;
            }
        }
        let (line, col) = self.position();
        let mut start = self.pos;
        loop {
            if self.pos == self.end {
                let kept = self.pos - start;
                if !self.refill(start)? {
                    start = self.pos - kept;
                    break;
                }
                start = 0;
            }
            let b = self.buf[self.pos];
            if is_space(b) || b == b'#' {
                break;
            }
            self.pos += 1;
            if self.pos - start > MAX_TOKEN {
                let long = &self.buf[start..self.pos];
                return Err(Error::at(&self.path, line, col, overlong(long)));
            }
        }
        Ok(Some(Tok {
            start,
            len: self.pos - start,
            line,
            col,
        }))
    }

    /// The next token without consuming it.
    pub fn peek(&mut self) -> Result<Option<Tok>> {
        if self.peeked.is_none() {
            self.peeked = self.next_token()?;
        }
        Ok(self.peeked)
    }

    /// The bytes of a token just returned by `next` or `peek`.
    pub fn text(&self, tok: &Tok) -> &[u8] {
        &self.buf[tok.start..tok.start + tok.len]
    }

    /// An error at a token.
    pub fn error_at(&self, tok: &Tok, message: impl Into<String>) -> Error {
        Error::at(&self.path, tok.line, tok.col, message)
    }

    /// An error at the read position (used at the end of the data).
    pub fn error_here(&self, message: impl Into<String>) -> Error {
        let (line, col) = self.position();
        Error::at(&self.path, line, col, message)
    }

    /// The next token, or an error saying that `what` was expected at the end of the file.
    pub fn expect_token(&mut self, what: impl fmt::Display) -> Result<Tok> {
        match self.next_token()? {
            Some(tok) => Ok(tok),
            None => Err(self.error_here(format!("expected {what}, found the end of the file"))),
        }
    }

    /// The next token, which must be exactly `word`.
    pub fn expect_word(&mut self, word: &str, context: &str) -> Result<Tok> {
        let tok = self.expect_token(format_args!("\"{word}\" {context}"))?;
        if self.text(&tok) != word.as_bytes() {
            return Err(self.error_at(
                &tok,
                format!("expected \"{word}\" {context}, found {}", show(self.text(&tok))),
            ));
        }
        Ok(tok)
    }

    /// A finite number for `what` (NaN and infinities are errors: they poison every later computation).
    pub fn expect_f32(&mut self, what: impl fmt::Display) -> Result<f32> {
        let tok = self.expect_token(format_args!("a number for {what}"))?;
        let text = self.text(&tok);
        match parse_f32(text) {
            Some(v) if v.is_finite() => Ok(v),
            Some(_) => Err(self.error_at(
                &tok,
                format!("expected a finite number for {what}, found {}", show(text)),
            )),
            None => Err(self.error_at(
                &tok,
                format!("expected a number for {what}, found {}", show(text)),
            )),
        }
    }

    /// Three finite numbers.
    pub fn expect_vec3(&mut self, what: impl fmt::Display + Copy) -> Result<Vec3> {
        Ok(Vec3::new(
            self.expect_f32(what)?,
            self.expect_f32(what)?,
            self.expect_f32(what)?,
        ))
    }

    /// A whole number in `range`, which the message names whole, so that a value out of it is told
    /// the one range it must lie in.
    pub fn expect_uint(&mut self, what: impl fmt::Display + Copy, range: RangeInclusive<u64>) -> Result<u64> {
        let (tok, value) = self.expect_int(what)?;
        if !u64::try_from(value).is_ok_and(|v| range.contains(&v)) {
            let (min, max) = (range.start(), range.end());
            return Err(self.error_at(
                &tok,
                format!("expected {what} between {min} and {max}, found {value}"),
            ));
        }
        Ok(value as u64)
    }

    /// A whole number (sign allowed) and its token.
    pub fn expect_int(&mut self, what: impl fmt::Display) -> Result<(Tok, i64)> {
        let tok = self.expect_token(format_args!("a whole number for {what}"))?;
        match parse_int(self.text(&tok)) {
            Some(v) => Ok((tok, v)),
            None => Err(self.error_at(
                &tok,
                format!(
                    "expected a whole number for {what}, found {}",
                    show(self.text(&tok))
                ),
            )),
        }
    }

    /// True if the next token looks like a number (used for optional trailing numbers).
    pub fn peek_is_number(&mut self) -> Result<bool> {
        Ok(match self.peek()? {
            Some(tok) => {
                let text = self.text(&tok);
                // `nan` and `inf` are numbers to a reader, so an optional number that is one is
                // refused as not finite, not taken for the next keyword.
                text.first()
                    .is_some_and(|b| b.is_ascii_digit() || matches!(b, b'-' | b'+' | b'.'))
                    || [&b"nan"[..], b"inf", b"infinity"]
                        .iter()
                        .any(|w| text.eq_ignore_ascii_case(w))
            }
            None => false,
        })
    }

    /// Discards the rest of the current line, including its line break.
    pub fn skip_line(&mut self) -> Result<()> {
        debug_assert!(self.peeked.is_none(), "skip_line after peek");
        while self.pos < self.end || self.refill(self.pos)? {
            let b = self.buf[self.pos];
            self.pos += 1;
            if b == b'\n' {
                self.line += 1;
                self.line_start = self.consumed + self.pos as u64;
                break;
            }
        }
        Ok(())
    }

    /// Absolute byte offset of the read position (for binary data after a text header).
    pub fn offset(&self) -> u64 {
        self.consumed + self.pos as u64
    }

    /// Reads raw bytes (binary PLY after its header). Returns false if the data ends first.
    #[inline]
    pub fn read_exact(&mut self, out: &mut [u8]) -> Result<bool> {
        debug_assert!(self.peeked.is_none(), "read_exact after peek");
        // Most reads are a value of a few bytes that the buffer holds.
        match self.buf[self.pos..self.end].get(..out.len()) {
            Some(bytes) => {
                out.copy_from_slice(bytes);
                self.pos += out.len();
                Ok(true)
            }
            None => self.read_across(out),
        }
    }

    /// [`Lexer::read_exact`] across the end of the buffer.
    fn read_across(&mut self, out: &mut [u8]) -> Result<bool> {
        let mut filled = 0;
        while filled < out.len() {
            if self.pos == self.end && !self.refill(self.pos)? {
                return Ok(false);
            }
            let n = (self.end - self.pos).min(out.len() - filled);
            out[filled..filled + n].copy_from_slice(&self.buf[self.pos..self.pos + n]);
            self.pos += n;
            filled += n;
        }
        Ok(true)
    }
}

/// Parses a decimal float; `None` if the bytes are not one.
pub fn parse_f32(text: &[u8]) -> Option<f32> {
    std::str::from_utf8(text).ok()?.parse().ok()
}

/// Parses a decimal integer with an optional sign; `None` on junk or overflow.
pub fn parse_int(text: &[u8]) -> Option<i64> {
    let (neg, digits) = match text.first()? {
        b'-' => (true, &text[1..]),
        b'+' => (false, &text[1..]),
        _ => (false, text),
    };
    if digits.is_empty() || digits.len() > 18 {
        return None;
    }
    let mut v: i64 = 0;
    for &b in digits {
        if !b.is_ascii_digit() {
            return None;
        }
        v = v * 10 + (b - b'0') as i64;
    }
    Some(if neg { -v } else { v })
}

/// What is wrong with a word longer than [`MAX_TOKEN`] bytes, of which `long` is the start: a number
/// too long, a word too long, or binary data (bytes that are not printable ASCII).
fn overlong(long: &[u8]) -> String {
    let found = show(long);
    if long.iter().all(|b| b.is_ascii_digit() || b"+-.eE".contains(b)) {
        format!("expected a number of at most {MAX_TOKEN} characters, found a longer one: {found}")
    } else if long.iter().all(u8::is_ascii_graphic) {
        format!("expected a keyword or a number, found a word of more than {MAX_TOKEN} characters: {found}")
    } else {
        format!("expected a keyword or a number, found {found} (binary data in a text file?)")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lexer(text: &'static str) -> Lexer {
        Lexer::new(Path::new("t.txt"), Box::new(text.as_bytes()))
    }

    fn words(mut lx: Lexer) -> Vec<(String, u64, u64)> {
        let mut out = vec![];
        while let Some(t) = lx.next_token().unwrap() {
            out.push((String::from_utf8_lossy(lx.text(&t)).into_owned(), t.line, t.col));
        }
        out
    }

    #[test]
    fn tokens_lines_and_columns() {
        let got = words(lexer("ab  c\n# comment\n  d#x\r\ne"));
        let want = [("ab", 1, 1), ("c", 1, 5), ("d", 3, 3), ("e", 4, 1)];
        let want: Vec<_> = want.iter().map(|&(s, l, c)| (s.to_string(), l, c)).collect();
        assert_eq!(got, want);
    }

    /// Tokens that straddle the buffer boundary come out whole, with the right positions.
    #[test]
    fn tokens_across_refills() {
        let mut text = String::new();
        for i in 0..40_000 {
            text.push_str(&format!("{i} "));
            if i % 7 == 0 {
                text.push('\n');
            }
        }
        let text: &'static str = Box::leak(text.into_boxed_str());
        let got = words(lexer(text));
        assert_eq!(got.len(), 40_000);
        for (i, (w, _, _)) in got.iter().enumerate() {
            assert_eq!(w, &i.to_string());
        }
        // A line break follows every multiple of 7 up to 39,998: 5,715 of them.
        assert_eq!(got.last().unwrap().1, 39_999 / 7 + 2);
    }

    /// Lines and columns go on counting past 2^32 (a file of more than 4 billion lines, a line of more
    /// than 4 GiB), through the tokenizer and `skip_line` alike, into the error's location.
    #[test]
    fn positions_past_four_billion() {
        let mut lx = lexer("a x y\nb\n\nc d");
        lx.line = u32::MAX.into();
        let a = lx.next_token().unwrap().unwrap();
        lx.skip_line().unwrap();
        let b = lx.next_token().unwrap().unwrap();
        let c = lx.next_token().unwrap().unwrap();
        assert_eq!([a.line, b.line, c.line], [(1 << 32) - 1, 1 << 32, (1 << 32) + 2]);
        let e = lx.error_at(&c, "x");
        assert_eq!(e.to_string(), "t.txt:4294967298:1: x");
        // The data so far taken for 5 GiB of one line.
        let mut lx = lexer("a b");
        lx.consumed = 5 << 30;
        let b = [lx.next_token().unwrap(), lx.next_token().unwrap()][1].unwrap();
        assert_eq!(b.col, (5 << 30) + 3);
    }

    /// A reader that hands out one byte at a time, as a pipe or a decompressor may.
    struct Trickle(&'static [u8]);

    impl Read for Trickle {
        fn read(&mut self, out: &mut [u8]) -> io::Result<usize> {
            let n = self.0.len().min(out.len()).min(1);
            out[..n].copy_from_slice(&self.0[..n]);
            self.0 = &self.0[n..];
            Ok(n)
        }
    }

    /// A byte-order mark at the start is skipped, whole or read in pieces, and the first column is
    /// the one after it; elsewhere it is part of a word.
    #[test]
    fn a_leading_byte_order_mark_is_skipped() {
        let text = "\u{feff}ply x\n\u{feff}y";
        let want = vec![
            ("ply".to_string(), 1, 1),
            ("x".to_string(), 1, 5),
            ("\u{feff}y".to_string(), 2, 1),
        ];
        assert_eq!(words(lexer(text)), want);
        let trickle = Lexer::new(Path::new("t.txt"), Box::new(Trickle(text.as_bytes())));
        assert_eq!(words(trickle), want);
        for text in ["\u{feff}", "\u{feff} \n # nothing", "\u{feff}\n\n"] {
            assert!(words(lexer(text)).is_empty(), "{text:?}");
        }
        // Only the whole mark: a text that starts with part of one keeps it.
        let got = words(Lexer::new(Path::new("t.txt"), Box::new(&b"\xef\xbba"[..])));
        assert_eq!(got, [("\u{fffd}a".to_string(), 1, 1)]);
        // The binary data after a PLY header is counted from the file's first byte, the mark's.
        let mut lx = lexer("\u{feff}ply\n");
        lx.next_token().unwrap();
        lx.skip_line().unwrap();
        assert_eq!(lx.offset(), 7);
    }

    #[test]
    fn numbers() {
        assert_eq!(parse_int(b"-12"), Some(-12));
        assert_eq!(parse_int(b"1x"), None);
        assert_eq!(parse_int(b"99999999999999999999"), None);
        let mut lx = lexer("1.5 nan 1e99 abc");
        assert_eq!(lx.expect_f32("x").unwrap(), 1.5);
        assert!(lx.expect_f32("x").unwrap_err().message.contains("finite"));
        assert!(lx.expect_f32("x").unwrap_err().message.contains("finite"));
        let e = lx.expect_f32("the radius").unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.txt:1:14: expected a number for the radius, found \"abc\""
        );
        let e = lx.expect_f32("the radius").unwrap_err();
        assert!(e.message.contains("end of the file"), "{e}");
    }

    #[test]
    fn long_garbage_is_an_error() {
        let text: &'static str = Box::leak("x".repeat(5000).into_boxed_str());
        assert!(lexer(text).next_token().is_err());
    }
}
