//! A body read on all cores.
//!
//! The body is read in windows, and each window is cut where its rows end and where an element ends
//! into pieces that know their first row. An ascii row is a line of its own (the reader holds it to
//! one), so a window ends at a line end and its lines that hold a token are counted off against the
//! elements' rows; a binary row's size comes from the header and its lists' lengths. A piece is read by
//! the code that reads a whole body, resumed at the piece's first byte, and the parts are joined in
//! order. The mesh is the one a reading from start to end gives, and so is the first error: while no
//! row before it is wrong, a piece's rows are the ones that reading takes from its bytes. Faces are read
//! once every vertex is (a polygon's triangulation reads the positions). The piece that holds the body's
//! last row reads on to the end of the stream, as does the text where the stream ends or fails, or where
//! a row runs on too long or has a length it cannot have: what follows is read as a whole body reads it.

use std::collections::VecDeque;
use std::io::{self, Cursor, Read};
use std::mem;
use std::ops::{ControlFlow, Range};
use std::path::Path;

use rayon::prelude::*;

use super::{Ascii, Binary, Element, Format, Header, Kind, RowAt, read_rest, read_rows};
use crate::error::Result;
use crate::scene::MeshData;
use crate::scene::lex::{self, Lexer, Position};

/// The bytes read at a time: some 4,000 rows of a mesh, a millisecond or two to read.
const WINDOW: usize = 1 << 17;
/// Windows a core in a batch: pieces small enough beside the batch that the cores finish it together.
const BATCH: usize = 8;
/// How far past a window a row may run before the rest is read as one piece (a row is far shorter).
const LONG_ROW: usize = 1 << 16;

/// Reads the body after the header `lx` has read.
pub(super) fn read(lx: Lexer, header: &Header) -> Result<MeshData> {
    read_in_windows(lx, header, WINDOW)
}

/// Reads the body in windows of `window` bytes (tests take small ones, to cut many pieces).
pub(super) fn read_in_windows(lx: Lexer, header: &Header, window: usize) -> Result<MeshData> {
    // Each batch is read while the next is cut.
    let size = BATCH * window * rayon::current_num_threads();
    let path = lx.path().to_path_buf();
    let mut split = Split::new(lx, header, window);
    let mut mesh = MeshData::default();
    let mut batch = split.batch(size);
    loop {
        let read = |pieces: Vec<Piece>| -> Vec<Result<MeshData>> {
            pieces
                .into_par_iter()
                .map(|piece| piece.read(&path, header, &mesh))
                .collect()
        };
        let (parts, then) = match batch.last {
            Some(last) => (read(batch.pieces), ControlFlow::Break(last)),
            None => {
                let (parts, next) = rayon::join(|| read(batch.pieces), || split.batch(size));
                (parts, ControlFlow::Continue(next))
            }
        };
        for part in parts {
            mesh.append(part?);
        }
        match then {
            ControlFlow::Continue(next) => batch = next,
            ControlFlow::Break(last) => return last.read(&path, header, mesh),
        }
    }
}

/// The rows `rows` of one element, whole, and the position of their first byte.
struct Piece {
    element: usize,
    rows: Range<u64>,
    text: Vec<u8>,
    at: Position,
}

impl Piece {
    /// The rows, as a part to append to `vertices` (which holds every vertex before a face is read).
    fn read(self, path: &Path, header: &Header, vertices: &MeshData) -> Result<MeshData> {
        let mut lx = Lexer::resume(path, Box::new(Cursor::new(self.text)), self.at);
        let mut part = MeshData::default();
        match header.format {
            Format::Ascii => {
                let mut body = Ascii::new(&mut lx, true);
                read_rows(&mut body, header, self.element, self.rows, vertices, &mut part)?;
                body.end_piece()?;
            }
            Format::Binary { big_endian } => {
                let mut body = Binary::new(&mut lx, big_endian);
                read_rows(&mut body, header, self.element, self.rows, vertices, &mut part)?;
            }
        }
        Ok(part)
    }
}

/// The body from row `from` to the end of the stream, `reader`, whose first byte is at `at`.
struct Last {
    from: RowAt,
    reader: Box<dyn Read + Send>,
    at: Position,
}

impl Last {
    fn read(self, path: &Path, header: &Header, mut mesh: MeshData) -> Result<MeshData> {
        let mut lx = Lexer::resume(path, self.reader, self.at);
        read_rest(&mut lx, header, self.from, &mut mesh)?;
        Ok(mesh)
    }
}

/// Pieces to read together, and the last piece if it comes after them.
struct Batch {
    pieces: Vec<Piece>,
    last: Option<Last>,
}

/// The body being cut into pieces.
struct Split<'h> {
    header: &'h Header,
    window: usize,
    /// Bytes read and not yet in a piece, from `at` on.
    text: Vec<u8>,
    at: Position,
    reader: Box<dyn Read + Send>,
    /// The row that the text starts with.
    row: RowAt,
    /// The rows that the body has left; ascii counts only the rows that take a line.
    left: u64,
    /// Pieces cut and not yet in a batch.
    cut: VecDeque<Piece>,
}

/// The rows of an element that hold something: an ascii body has no line for a row without values.
fn rows(format: Format, element: &Element) -> u64 {
    if format == Format::Ascii && element.props.is_empty() {
        0
    } else {
        element.count
    }
}

/// What came of cutting a window.
enum Cut {
    /// Pieces, queued.
    Pieces,
    /// The window holds the body's last row, or a row too strange to size: the rest is the last piece.
    Last,
    /// No row ends within the text read so far.
    More,
}

impl<'h> Split<'h> {
    fn new(lx: Lexer, header: &'h Header, window: usize) -> Self {
        let rest = lx.into_rest();
        Split {
            header,
            window,
            text: rest.bytes,
            at: rest.at,
            reader: rest.reader,
            row: RowAt::default(),
            left: header.elements.iter().map(|e| rows(header.format, e)).sum(),
            cut: VecDeque::new(),
        }
    }

    /// Pieces of some `size` bytes in all; never faces with vertices, whose positions they need.
    fn batch(&mut self, size: usize) -> Batch {
        let (face, vertex) = (self.header.face, self.header.vertex);
        let mut pieces: Vec<Piece> = Vec::new();
        let mut bytes = 0;
        loop {
            let Some(piece) = self.cut.front() else {
                if let Some(last) = self.window() {
                    return Batch {
                        pieces,
                        last: Some(last),
                    };
                }
                continue;
            };
            let waits = piece.element == face && pieces.iter().any(|p| p.element == vertex);
            if waits || bytes >= size {
                return Batch { pieces, last: None };
            }
            bytes += piece.text.len();
            pieces.extend(self.cut.pop_front());
        }
    }

    /// Reads a window and cuts it into pieces; or hands the text from here on to the last piece.
    fn window(&mut self) -> Option<Last> {
        if self.left == 0 {
            return Some(self.last_with_reader());
        }
        let mut want = self.window;
        loop {
            if let Err(tail) = self.read_to(want) {
                return Some(self.last(tail));
            }
            let cut = match self.header.format {
                Format::Ascii => self.cut_lines(),
                Format::Binary { big_endian } => self.cut_records(big_endian),
            };
            match cut {
                Cut::Pieces => return None,
                Cut::Last => return Some(self.last_with_reader()),
                Cut::More if self.text.len() >= self.window + LONG_ROW => {
                    return Some(self.last_with_reader());
                }
                Cut::More => want = self.text.len() + self.window.min(4096),
            }
        }
    }

    /// Cuts the text's whole lines from the window on into pieces (ascii).
    fn cut_lines(&mut self) -> Cut {
        let Some(end) = memchr::memchr(b'\n', self.text.get(self.window - 1..).unwrap_or_default()) else {
            return Cut::More;
        };
        let cut = self.window + end;
        let elements = &self.header.elements;
        let (mut row, mut left) = (self.row, self.left);
        let mut pieces = Vec::new();
        // The first byte of the current piece, its position and row; the current line's start.
        let (mut start, mut start_at, mut first) = (0, self.at, row);
        let (mut line_start, mut line) = (0, self.at.line);
        for end in memchr::memchr_iter(b'\n', &self.text[..cut]) {
            if lex::holds_token(&self.text[line_start..end]) {
                if left == 1 {
                    return Cut::Last;
                }
                if row.row == rows(Format::Ascii, &elements[row.element]) {
                    if row.row > first.row {
                        pieces.push(self.piece(first, row.row, start..line_start, start_at));
                    }
                    // Some element after it has lines, since the body has lines left.
                    row = RowAt {
                        element: row.element + 1,
                        row: 0,
                    };
                    while rows(Format::Ascii, &elements[row.element]) == 0 {
                        row.element += 1;
                    }
                    let offset = self.at.offset + line_start as u64;
                    (start, first) = (line_start, row);
                    start_at = Position { offset, line, col: 1 };
                }
                row.row += 1;
                left -= 1;
            }
            (line_start, line) = (end + 1, line + 1);
        }
        if row.row > first.row {
            pieces.push(self.piece(first, row.row, start..cut, start_at));
        }
        let offset = self.at.offset + cut as u64;
        self.taken(cut, Position { offset, line, col: 1 }, row, left, pieces)
    }

    /// Cuts the text's whole rows that start within the window into pieces (binary).
    fn cut_records(&mut self, big_endian: bool) -> Cut {
        let elements = &self.header.elements;
        let (mut row, mut left) = (self.row, self.left);
        let mut pieces = Vec::new();
        let mut pos = 0;
        loop {
            let element = &elements[row.element];
            let (start, first) = (pos, row);
            let fixed: Option<usize> = element.props.iter().map(|p| p.kind.size()).sum();
            if let Some(size) = fixed {
                // Rows of one size: those the text holds whole that start in the window, at once.
                let fit = match size {
                    0 => u64::MAX,
                    _ => {
                        let whole = (self.text.len() - pos) / size;
                        whole.min(self.window.saturating_sub(pos).div_ceil(size)) as u64
                    }
                };
                let n = fit.min(element.count - row.row);
                if n >= left {
                    return Cut::Last;
                }
                (pos, row.row, left) = (pos + n as usize * size, row.row + n, left - n);
            }
            while row.row < element.count && pos < self.window {
                match record(element, &self.text[pos..], big_endian) {
                    Some(Some(size)) => pos += size,
                    Some(None) => break,
                    None => return Cut::Last,
                }
                row.row += 1;
                left -= 1;
                if left == 0 {
                    return Cut::Last;
                }
            }
            if row.row > first.row {
                let offset = self.at.offset + start as u64;
                let at = Position { offset, ..self.at };
                pieces.push(self.piece(first, row.row, start..pos, at));
            }
            if row.row < element.count {
                break;
            }
            // Some element after it has rows, since the body has rows left.
            row = RowAt {
                element: row.element + 1,
                row: 0,
            };
        }
        let at = Position {
            offset: self.at.offset + pos as u64,
            ..self.at
        };
        self.taken(pos, at, row, left, pieces)
    }

    fn piece(&self, first: RowAt, end: u64, bytes: Range<usize>, at: Position) -> Piece {
        Piece {
            element: first.element,
            rows: first.row..end,
            text: self.text[bytes].to_vec(),
            at,
        }
    }

    /// Queues `pieces`, made of the text's first `cut` bytes, after which the text starts at `at` with
    /// `row`, the body having `left` rows left.
    fn taken(&mut self, cut: usize, at: Position, row: RowAt, left: u64, pieces: Vec<Piece>) -> Cut {
        if pieces.is_empty() && cut == 0 {
            return Cut::More;
        }
        self.text.drain(..cut);
        (self.at, self.row, self.left) = (at, row, left);
        self.cut.extend(pieces);
        Cut::Pieces
    }

    /// Reads until the text holds `len` bytes. Where the stream ends or fails first, returns what the
    /// last piece reads after the text: nothing, or the failure.
    fn read_to(&mut self, len: usize) -> std::result::Result<(), Box<dyn Read + Send>> {
        let Some(want) = len.checked_sub(self.text.len()) else {
            return Ok(());
        };
        match (&mut self.reader).take(want as u64).read_to_end(&mut self.text) {
            Ok(n) if n < want => Err(Box::new(io::empty())),
            Ok(_) => Ok(()),
            Err(e) => Err(Box::new(Failed(Some(e)))),
        }
    }

    /// The text and then the rest of the stream, as the last piece.
    fn last_with_reader(&mut self) -> Last {
        let reader = mem::replace(&mut self.reader, Box::new(io::empty()));
        self.last(reader)
    }

    /// The text and then `tail`, as the last piece.
    fn last(&mut self, tail: Box<dyn Read + Send>) -> Last {
        Last {
            from: self.row,
            reader: Box::new(Cursor::new(mem::take(&mut self.text)).chain(tail)),
            at: self.at,
        }
    }
}

/// The size of the binary row of `element` that `bytes` starts with: `Some(None)` where `bytes` ends
/// first, `None` where a list has a negative length, which the reader reports.
fn record(element: &Element, bytes: &[u8], big_endian: bool) -> Option<Option<usize>> {
    let mut size = 0usize;
    for prop in &element.props {
        match prop.kind {
            Kind::Scalar(ty) => size += ty.size(),
            Kind::List { count, item } => {
                let Some(n) = bytes.get(size..size + count.size()) else {
                    return Some(None);
                };
                // The header holds lengths to integer types: at most 2^32 - 1 items of 8 bytes.
                let n = count.decode(n, big_endian);
                if n < 0.0 {
                    return None;
                }
                size += count.size() + n as usize * item.size();
            }
        }
    }
    Some((size <= bytes.len()).then_some(size))
}

/// The stream's read error, met where a reader of the stream itself would meet it.
struct Failed(Option<io::Error>);

impl Read for Failed {
    fn read(&mut self, _: &mut [u8]) -> io::Result<usize> {
        self.0.take().map_or(Ok(0), Err)
    }
}
