//! PLY (Polygon File Format) reader: ascii, binary little- and big-endian.

use super::report::DroppedLog;
use super::text::{
    Lines, Tokens, cut_at_line_ends, invalid_number, is_space, parse_f64, parse_i64, show_token, tokens,
};
use super::{Format, IoError, Location, PlyEncoding, ReadReport};
use crate::ids::MAX_ELEMENTS;
use crate::soup::PolygonSoup;
use rayon::prelude::*;

/// A PLY scalar type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(name: &[u8]) -> Option<Self> {
        Some(match name {
            b"char" | b"int8" => Self::I8,
            b"uchar" | b"uint8" => Self::U8,
            b"short" | b"int16" => Self::I16,
            b"ushort" | b"uint16" => Self::U16,
            b"int" | b"int32" => Self::I32,
            b"uint" | b"uint32" => Self::U32,
            b"float" | b"float32" => Self::F32,
            b"double" | b"float64" => Self::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 | Self::F32 => 4,
            Self::F64 => 8,
        }
    }

    fn is_integer(self) -> bool {
        !matches!(self, Self::F32 | Self::F64)
    }
}

#[derive(Debug, Clone, Copy)]
enum Kind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

/// What the reader does with a property.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Role {
    Coordinate(usize),
    FaceIndices,
    Skip,
}

#[derive(Debug)]
struct Property {
    name: Vec<u8>,
    kind: Kind,
    line: usize,
    role: Role,
}

#[derive(Debug)]
struct Element {
    name: Vec<u8>,
    count: u64,
    line: usize,
    properties: Vec<Property>,
}

struct Header {
    encoding: PlyEncoding,
    elements: Vec<Element>,
    /// Byte offset where the data starts.
    data_start: usize,
    /// Line number of the first data line (ascii).
    data_line: usize,
}

fn header_error(line: usize, reason: impl Into<String>) -> IoError {
    IoError::InvalidHeader { at: Location::Line(line), reason: reason.into() }
}

fn parse_header(bytes: &[u8]) -> Result<Header, IoError> {
    let mut lines = Lines::new(bytes);
    match lines.next() {
        Some((_, magic)) if magic.strip_suffix(b"\r").unwrap_or(magic) == b"ply" => {}
        _ => return Err(header_error(1, "the file does not start with `ply`")),
    }
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    for (line, raw) in lines.by_ref() {
        let mut words = tokens(raw);
        let Some(keyword) = words.next() else { continue };
        let rest: Vec<&[u8]> = words.collect();
        match keyword {
            b"comment" | b"obj_info" => {}
            b"format" => {
                let [name, version] = rest[..] else {
                    return Err(header_error(line, "expected `format <encoding> 1.0`"));
                };
                encoding = Some(match name {
                    b"ascii" => PlyEncoding::Ascii,
                    b"binary_little_endian" => PlyEncoding::BinaryLittleEndian,
                    b"binary_big_endian" => PlyEncoding::BinaryBigEndian,
                    other => {
                        return Err(IoError::Unsupported {
                            at: Location::Line(line),
                            what: format!("PLY encoding `{}`", show_token(other)),
                        });
                    }
                });
                if version != b"1.0" {
                    return Err(IoError::Unsupported {
                        at: Location::Line(line),
                        what: format!("PLY version `{}`", show_token(version)),
                    });
                }
            }
            b"element" => {
                let [name, count] = rest[..] else {
                    return Err(header_error(line, "expected `element <name> <count>`"));
                };
                let count =
                    parse_i64(count).filter(|&c| c >= 0).ok_or_else(|| invalid_number(line, count, "a count"))? as u64;
                if elements.iter().any(|e| e.name == name) {
                    return Err(header_error(line, format!("element `{}` is declared twice", show_token(name))));
                }
                elements.push(Element { name: name.to_vec(), count, line, properties: Vec::new() });
            }
            b"property" => {
                let element =
                    elements.last_mut().ok_or_else(|| header_error(line, "`property` before any `element`"))?;
                let type_of = |name: &[u8]| {
                    Scalar::parse(name)
                        .ok_or_else(|| header_error(line, format!("unknown property type `{}`", show_token(name))))
                };
                let (kind, name) = match rest[..] {
                    [b"list", count, item, name] => {
                        let count = type_of(count)?;
                        if !count.is_integer() {
                            return Err(header_error(line, "a list count must have an integer type"));
                        }
                        (Kind::List { count, item: type_of(item)? }, name)
                    }
                    [ty, name] => (Kind::Scalar(type_of(ty)?), name),
                    _ => return Err(header_error(line, "expected `property <type> <name>` or `property list ...`")),
                };
                element.properties.push(Property { name: name.to_vec(), kind, line, role: Role::Skip });
            }
            b"end_header" => {
                let encoding = encoding.ok_or_else(|| header_error(line, "no `format` line before `end_header`"))?;
                return Ok(Header { encoding, elements, data_start: lines.offset(), data_line: line + 1 });
            }
            other => return Err(header_error(line, format!("unknown header keyword `{}`", show_token(other)))),
        }
    }
    Err(IoError::Truncated { at: Location::Line(lines.line().max(1)), expected: "`end_header`".into() })
}

/// Assigns roles (coordinates, face indices) and reports everything else.
fn assign_roles(header: &mut Header, dropped: &mut DroppedLog) -> Result<(u64, u64), IoError> {
    let mut vertex_count = 0;
    let mut face_count = 0;
    for element in &mut header.elements {
        let element_name = show_token(&element.name);
        match &element.name[..] {
            b"vertex" => {
                vertex_count = element.count;
                for (axis, axis_name) in [b"x", b"y", b"z"].iter().enumerate() {
                    let property = element
                        .properties
                        .iter_mut()
                        .find(|p| p.name == axis_name[..] && p.role == Role::Skip)
                        .ok_or_else(|| {
                            header_error(
                                element.line,
                                format!("element `vertex` has no `{}` property", axis_name[0] as char),
                            )
                        })?;
                    if !matches!(property.kind, Kind::Scalar(_)) {
                        return Err(header_error(property.line, "vertex coordinates must be scalars, not lists"));
                    }
                    property.role = Role::Coordinate(axis);
                }
                if vertex_count > MAX_ELEMENTS as u64 {
                    return Err(IoError::TooLarge {
                        at: Location::Line(element.line),
                        what: "vertices",
                        max: MAX_ELEMENTS,
                    });
                }
            }
            b"face" => {
                face_count = element.count;
                let property = element
                    .properties
                    .iter_mut()
                    .find(|p| p.name == b"vertex_indices" || p.name == b"vertex_index")
                    .ok_or_else(|| header_error(element.line, "element `face` has no `vertex_indices` list"))?;
                match property.kind {
                    Kind::List { item, .. } if item.is_integer() => property.role = Role::FaceIndices,
                    _ => return Err(header_error(property.line, "`vertex_indices` must be a list of integers")),
                }
                if face_count > MAX_ELEMENTS as u64 {
                    return Err(IoError::TooLarge {
                        at: Location::Line(element.line),
                        what: "faces",
                        max: MAX_ELEMENTS,
                    });
                }
            }
            _ => {
                dropped.add(
                    &format!("PLY `{element_name}` elements"),
                    element.count.min(usize::MAX as u64) as usize,
                    Location::Line(element.line),
                );
                continue;
            }
        }
        for property in &element.properties {
            if property.role == Role::Skip {
                dropped.add(
                    &format!("PLY {element_name} property `{}` values", show_token(&property.name)),
                    element.count.min(usize::MAX as u64) as usize,
                    Location::Line(property.line),
                );
            }
        }
    }
    Ok((vertex_count, face_count))
}

/// A source of PLY values: ascii tokens or binary numbers of the whole data (a [`Body`]),
/// or the tokens of one line (the pieces of [`read_ascii_in_pieces`]).
trait Values {
    /// What a failed read gives: an [`IoError`] that says where (a [`Body`]), or nothing
    /// (a line, whose file is then read in one pass, which names the problem).
    type Error;
    /// Reads a value as a float (coordinates).
    fn float(&mut self, ty: Scalar) -> Result<f64, Self::Error>;
    /// Reads an integer value (list counts, indices).
    fn integer(&mut self, ty: Scalar) -> Result<i64, Self::Error>;
    /// Skips one value.
    /// Skips one value (read and checked as a text value, by default).
    #[inline]
    fn skip(&mut self, ty: Scalar) -> Result<(), Self::Error> {
        self.float(ty).map(drop)
    }
    /// Skips `n` values (one at a time, by default).
    fn skip_many(&mut self, ty: Scalar, n: u64) -> Result<(), Self::Error> {
        for _ in 0..n {
            self.skip(ty)?;
        }
        Ok(())
    }
    /// The error of a value read but not accepted: `error` at the value read last.
    fn invalid(&self, error: impl FnOnce(Location) -> IoError) -> Self::Error;
}

/// The values of the whole data, read in one pass.
trait Body: Values<Error = IoError> {
    /// Where the value read last starts.
    fn location(&self) -> Location;
    /// Location of the end of the data.
    fn end(&self) -> Location;
    /// Fails if data remains.
    fn finish(&mut self, what: &'static str) -> Result<(), IoError>;
}

struct AsciiBody<'a> {
    bytes: &'a [u8],
    pos: usize,
    line: usize,
    token_line: usize,
}

impl<'a> AsciiBody<'a> {
    #[inline]
    fn token(&mut self) -> Result<&'a [u8], IoError> {
        while let Some(&b) = self.bytes.get(self.pos) {
            if !is_space(b) {
                break;
            }
            if b == b'\n' {
                self.line += 1;
            }
            self.pos += 1;
        }
        if self.pos >= self.bytes.len() {
            return Err(IoError::Truncated { at: self.end(), expected: String::new() });
        }
        let start = self.pos;
        while self.pos < self.bytes.len() && !is_space(self.bytes[self.pos]) {
            self.pos += 1;
        }
        self.token_line = self.line;
        Ok(&self.bytes[start..self.pos])
    }
}

impl Values for AsciiBody<'_> {
    type Error = IoError;

    #[inline]
    fn float(&mut self, ty: Scalar) -> Result<f64, IoError> {
        let token = self.token()?;
        ascii_value(token, ty).ok_or_else(|| {
            invalid_number(self.token_line, token, if ty.is_integer() { "an integer" } else { "a number" })
        })
    }

    #[inline]
    fn integer(&mut self, _ty: Scalar) -> Result<i64, IoError> {
        let token = self.token()?;
        parse_i64(token).ok_or_else(|| invalid_number(self.token_line, token, "an integer"))
    }

    fn invalid(&self, error: impl FnOnce(Location) -> IoError) -> IoError {
        error(self.location())
    }
}

impl Body for AsciiBody<'_> {
    fn location(&self) -> Location {
        Location::Line(self.token_line)
    }

    fn end(&self) -> Location {
        let newlines = self.bytes[self.pos..].iter().filter(|&&b| b == b'\n').count();
        let unterminated = usize::from(!self.bytes.ends_with(b"\n"));
        Location::Line((self.line + newlines + unterminated).saturating_sub(1).max(1))
    }

    fn finish(&mut self, what: &'static str) -> Result<(), IoError> {
        match self.token() {
            Ok(_) => Err(IoError::TrailingData { at: self.location(), what }),
            Err(_) => Ok(()),
        }
    }
}

/// An ascii value of type `ty`, as a float: integer types take integer tokens only.
#[inline]
fn ascii_value(token: &[u8], ty: Scalar) -> Option<f64> {
    if ty.is_integer() { parse_i64(token).map(|v| v as f64) } else { parse_f64(token) }
}

struct BinaryBody<'a> {
    bytes: &'a [u8],
    pos: usize,
    value_start: usize,
    big_endian: bool,
}

impl<'a> BinaryBody<'a> {
    #[inline]
    fn take<const N: usize>(&mut self) -> Result<[u8; N], IoError> {
        let end = self.pos + N;
        let Some(chunk) = self.bytes.get(self.pos..end) else {
            return Err(IoError::Truncated { at: self.end(), expected: String::new() });
        };
        self.value_start = self.pos;
        self.pos = end;
        let mut array: [u8; N] = chunk.try_into().expect("internal: chunk of N bytes");
        if self.big_endian {
            array.reverse();
        }
        Ok(array)
    }
}

impl Values for BinaryBody<'_> {
    type Error = IoError;

    #[inline]
    fn float(&mut self, ty: Scalar) -> Result<f64, IoError> {
        Ok(match ty {
            Scalar::F32 => f32::from_le_bytes(self.take()?) as f64,
            Scalar::F64 => f64::from_le_bytes(self.take()?),
            integer => self.integer(integer)? as f64,
        })
    }

    #[inline]
    fn integer(&mut self, ty: Scalar) -> Result<i64, IoError> {
        Ok(match ty {
            Scalar::I8 => i8::from_le_bytes(self.take()?) as i64,
            Scalar::U8 => u8::from_le_bytes(self.take()?) as i64,
            Scalar::I16 => i16::from_le_bytes(self.take()?) as i64,
            Scalar::U16 => u16::from_le_bytes(self.take()?) as i64,
            Scalar::I32 => i32::from_le_bytes(self.take()?) as i64,
            Scalar::U32 => u32::from_le_bytes(self.take()?) as i64,
            // Float-typed lists of indices are rejected by the header check; a float
            // read as an integer elsewhere is only skipped.
            Scalar::F32 => f32::from_le_bytes(self.take()?) as i64,
            Scalar::F64 => f64::from_le_bytes(self.take()?) as i64,
        })
    }

    #[inline]
    fn skip(&mut self, ty: Scalar) -> Result<(), IoError> {
        self.skip_many(ty, 1)
    }

    #[inline]
    fn skip_many(&mut self, ty: Scalar, n: u64) -> Result<(), IoError> {
        let length = n.checked_mul(ty.size() as u64).filter(|&l| l <= (self.bytes.len() - self.pos) as u64);
        match length {
            Some(length) => {
                self.value_start = self.pos;
                self.pos += length as usize;
                Ok(())
            }
            None => Err(IoError::Truncated { at: self.end(), expected: String::new() }),
        }
    }

    fn invalid(&self, error: impl FnOnce(Location) -> IoError) -> IoError {
        error(self.location())
    }
}

impl Body for BinaryBody<'_> {
    fn location(&self) -> Location {
        Location::Byte(self.value_start)
    }

    fn end(&self) -> Location {
        Location::Byte(self.bytes.len())
    }

    fn finish(&mut self, what: &'static str) -> Result<(), IoError> {
        if self.pos < self.bytes.len() {
            return Err(IoError::TrailingData { at: Location::Byte(self.pos), what });
        }
        Ok(())
    }
}

/// Reads the data of every element, in header order.
fn read_body<B: Body>(body: &mut B, header: &Header, vertex_count: u64, soup: &mut PolygonSoup) -> Result<(), IoError> {
    let mut last_element = "header";
    for element in &header.elements {
        if element.properties.is_empty() {
            // Nothing to read, however many there are.
            continue;
        }
        let is_vertex = element.name == b"vertex";
        let is_face = element.name == b"face";
        last_element = if is_vertex {
            "vertex"
        } else if is_face {
            "face"
        } else {
            "element"
        };
        let in_element = |error: IoError, i: u64| match error {
            IoError::Truncated { at, .. } => IoError::Truncated {
                at,
                expected: format!(
                    "{} `{}` elements, the data stops in element {i}",
                    element.count,
                    show_token(&element.name)
                ),
            },
            other => other,
        };
        for i in 0..element.count {
            read_element(body, element, is_vertex, i, vertex_count, soup).map_err(|e| in_element(e, i))?;
        }
    }
    body.finish(last_element)
}

/// Reads element `i` of `element` (a vertex if `is_vertex`) into `soup`: its position,
/// or its face; every other value is read and dropped.
#[inline]
fn read_element<V: Values>(
    values: &mut V,
    element: &Element,
    is_vertex: bool,
    i: u64,
    vertex_count: u64,
    soup: &mut PolygonSoup,
) -> Result<(), V::Error> {
    let mut position = [0.0; 3];
    for property in &element.properties {
        match (property.role, property.kind) {
            (Role::Coordinate(axis), Kind::Scalar(ty)) => position[axis] = values.float(ty)?,
            (Role::FaceIndices, Kind::List { count, item }) => read_face(values, count, item, vertex_count, soup)?,
            (_, Kind::Scalar(ty)) => values.skip(ty)?,
            (_, Kind::List { count, item }) => {
                let n = list_length(values, count)?;
                values.skip_many(item, n)?;
            }
        }
    }
    if is_vertex {
        if let Some(&value) = position.iter().find(|x| !x.is_finite()) {
            return Err(values.invalid(|at| IoError::NonFiniteCoordinate { at, vertex: i as usize, value }));
        }
        soup.positions.push(position.into());
    }
    Ok(())
}

/// The length of a list, whose count has type `count`.
#[inline]
fn list_length<V: Values>(values: &mut V, count: Scalar) -> Result<u64, V::Error> {
    let n = values.integer(count)?;
    u64::try_from(n).map_err(|_| {
        values.invalid(|at| IoError::InvalidNumber { at, token: n.to_string(), expected: "a list length" })
    })
}

#[inline]
fn read_face<V: Values>(
    values: &mut V,
    count: Scalar,
    item: Scalar,
    vertex_count: u64,
    soup: &mut PolygonSoup,
) -> Result<(), V::Error> {
    for _ in 0..list_length(values, count)? {
        let index = values.integer(item)?;
        if index < 0 || index as u64 >= vertex_count {
            let vertex_count = vertex_count as usize;
            return Err(values.invalid(|at| IoError::IndexOutOfRange { at, index, vertex_count }));
        }
        soup.indices.push(index as u32);
    }
    if soup.indices.len() > u32::MAX as usize {
        return Err(values.invalid(|at| IoError::TooLarge { at, what: "face corners", max: u32::MAX as usize }));
    }
    soup.offsets.push(soup.indices.len() as u32);
    Ok(())
}

/// Reads a PLY file from memory (ascii, binary little- or big-endian).
///
/// The `vertex` element must have `x`, `y`, `z` properties (any numeric type); the
/// `face` element a `vertex_indices` (or `vertex_index`) list of any integer types.
/// Every other property and element is skipped and reported. Elements may come in any
/// order.
///
/// Ascii data of a megabyte or more with one element per line (as nearly every writer
/// puts it) is read in pieces, cut at line ends, on the threads of the current `rayon`
/// pool; the result, and the error of a bad file, are those of one pass (other layouts
/// are read in one pass).
///
/// ```
/// let ply = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
///     property float z\nproperty uchar red\nelement face 1\nproperty list uchar int vertex_indices\n\
///     end_header\n0 0 0 255\n1 0 0 255\n0 1 0 255\n3 0 1 2\n";
/// let (soup, report) = mesh_topo::io::read_ply(ply)?;
/// assert_eq!(soup.face(0), &[0, 1, 2]);
/// assert_eq!(report.dropped[0].what, "PLY vertex property `red` values");
/// # Ok::<(), mesh_topo::io::IoError>(())
/// ```
///
/// # Errors
/// A malformed header ([`IoError::InvalidHeader`], with its line), an unknown encoding
/// or version ([`IoError::Unsupported`]); in the data, with the line (ascii) or byte
/// offset (binary): a file shorter than the header announces ([`IoError::Truncated`]),
/// data after the last element ([`IoError::TrailingData`]), a non-numeric token, a NaN
/// or infinite coordinate, an index out of range, too many elements.
pub fn read_ply(bytes: &[u8]) -> Result<(PolygonSoup, ReadReport), IoError> {
    read_ply_split(bytes, PARALLEL_MIN_BYTES)
}

/// Ascii files whose data takes fewer bytes than this are read on the calling thread.
const PARALLEL_MIN_BYTES: usize = 1 << 20;

/// Pieces of a large ascii file per thread: vertex lines (floats) cost more per byte than
/// face lines, and files list their vertices first, so threads that come free take more.
const PIECES_PER_THREAD: usize = 4;

/// [`read_ply`], whose ascii data is read in parallel pieces when it takes
/// `parallel_min_bytes` or more and the current `rayon` pool has several threads.
fn read_ply_split(bytes: &[u8], parallel_min_bytes: usize) -> Result<(PolygonSoup, ReadReport), IoError> {
    let mut header = parse_header(bytes)?;
    let mut dropped = DroppedLog::default();
    let (vertex_count, face_count) = assign_roles(&mut header, &mut dropped)?;
    let data = &bytes[header.data_start..];
    // The report comes from the header alone: the pieces give the one pass's.
    if header.encoding == PlyEncoding::Ascii
        && data.len() >= parallel_min_bytes
        && rayon::current_num_threads() > 1
        && let Some(soup) = read_ascii_in_pieces(data, &header, vertex_count)
    {
        return Ok((soup, dropped.into_report(Format::Ply, Some(header.encoding))));
    }
    // Never reserve more than the data can fill (3 values per vertex, 1 per face).
    let mut soup = PolygonSoup::with_capacity(
        (vertex_count as usize).min(data.len() / 3),
        (face_count as usize).min(data.len()),
        (3 * face_count as usize).min(data.len()),
    );
    match header.encoding {
        PlyEncoding::Ascii => {
            let mut body =
                AsciiBody { bytes, pos: header.data_start, line: header.data_line, token_line: header.data_line };
            read_body(&mut body, &header, vertex_count, &mut soup)?;
        }
        encoding => {
            let mut body = BinaryBody {
                bytes,
                pos: header.data_start,
                value_start: header.data_start,
                big_endian: encoding == PlyEncoding::BinaryBigEndian,
            };
            read_body(&mut body, &header, vertex_count, &mut soup)?;
        }
    }
    Ok((soup, dropped.into_report(Format::Ply, Some(header.encoding))))
}

/// The ascii data of the elements, read in [`PIECES_PER_THREAD`] pieces per thread cut at
/// line ends, if every data line holds exactly one element (as nearly every writer puts
/// them): then a piece's first line number tells which element it starts at. `None`
/// when the file has not one data line per element, a piece finds a line that is not
/// exactly one element or a value the one pass would reject, or the joined soup is too
/// large (the caller then reads it in one pass, which names the first problem).
fn read_ascii_in_pieces(data: &[u8], header: &Header, vertex_count: u64) -> Option<PolygonSoup> {
    // The elements that take data, each with its first data line (from 0).
    let mut spans = Vec::new();
    let mut data_lines: u64 = 0;
    for element in header.elements.iter().filter(|e| !e.properties.is_empty()) {
        spans.push((element, data_lines));
        data_lines = data_lines.checked_add(element.count)?;
    }
    let pieces = cut_at_line_ends(data, PIECES_PER_THREAD * rayon::current_num_threads());
    let line_ends: Vec<u64> = pieces.par_iter().map(|piece| memchr::memchr_iter(b'\n', piece).count() as u64).collect();
    // Every piece but the last ends with a line end; a last line without one counts.
    let unterminated = u64::from(!data.is_empty() && !data.ends_with(b"\n"));
    // Truncated data, trailing data and blank lines all show here (the common case
    // of a final blank line included, which the one pass accepts).
    if line_ends.iter().sum::<u64>() + unterminated != data_lines {
        return None;
    }
    // The data lines of each piece, from its first to the next piece's first.
    let mut piece_starts = Vec::with_capacity(pieces.len() + 1);
    let mut line = 0;
    for &ends in &line_ends {
        piece_starts.push(line);
        line += ends;
    }
    piece_starts.push(data_lines);
    let read: Vec<PolygonSoup> = pieces
        .par_iter()
        .zip(piece_starts.par_windows(2))
        .map(|(piece, lines)| read_lines_of_one_element(piece, lines[0]..lines[1], &spans, vertex_count))
        .collect::<Option<_>>()?;
    let vertices: usize = read.iter().map(|soup| soup.positions.len()).sum();
    let faces: usize = read.iter().map(PolygonSoup::face_count).sum();
    let corners: usize = read.iter().map(|soup| soup.indices.len()).sum();
    if corners > u32::MAX as usize {
        return None;
    }
    // The first piece's arrays take the others'.
    let mut read = read.into_iter();
    let mut soup = read.next()?;
    soup.positions.reserve_exact(vertices - soup.positions.len());
    soup.indices.reserve_exact(corners - soup.indices.len());
    soup.offsets.reserve_exact(faces + 1 - soup.offsets.len());
    for piece in read {
        let base = soup.indices.len() as u32;
        soup.positions.extend_from_slice(&piece.positions);
        soup.indices.extend_from_slice(&piece.indices);
        soup.offsets.extend(piece.offsets[1..].iter().map(|&o| base + o));
    }
    Some(soup)
}

/// The vertices and faces on the lines of `piece`, data lines `lines` (from 0), if each
/// line holds exactly one element; `spans` are the elements that take data, each with its
/// first data line (face offsets from 0 at the piece's first face).
fn read_lines_of_one_element(
    piece: &[u8],
    lines: std::ops::Range<u64>,
    spans: &[(&Element, u64)],
    vertex_count: u64,
) -> Option<PolygonSoup> {
    let first_line = lines.start;
    // The lines of this piece that hold elements named `name`, for the reservations.
    let lines_of = |name: &[u8]| -> usize {
        let span_lines = spans.iter().filter(|(element, _)| element.name == name).map(|&(element, first)| {
            (first + element.count).min(lines.end).saturating_sub(first.max(first_line)) as usize
        });
        span_lines.sum()
    };
    let faces = lines_of(b"face");
    let mut soup = PolygonSoup::with_capacity(lines_of(b"vertex"), faces, (3 * faces).min(piece.len() / 2));
    let mut lines = Lines::new(piece);
    for &(element, first) in spans.iter().filter(|(element, first)| first + element.count > first_line) {
        let is_vertex = element.name == b"vertex";
        for i in first_line.max(first)..first + element.count {
            let Some((_, line)) = lines.next() else { return Some(soup) };
            // The line holds exactly the element.
            let mut values = LineValues { tokens: tokens(line) };
            read_element(&mut values, element, is_vertex, i - first, vertex_count, &mut soup).ok()?;
            values.tokens.next().is_none().then_some(())?;
        }
    }
    // More lines than elements (not met when the line count matched).
    lines.next().is_none().then_some(soup)
}

/// The values of one line of ascii data: a value missing or malformed is an error
/// without a location (the one pass then names it).
struct LineValues<'a> {
    tokens: Tokens<'a>,
}

impl Values for LineValues<'_> {
    type Error = ();

    #[inline]
    fn float(&mut self, ty: Scalar) -> Result<f64, ()> {
        self.tokens.next().and_then(|token| ascii_value(token, ty)).ok_or(())
    }

    #[inline]
    fn integer(&mut self, _ty: Scalar) -> Result<i64, ()> {
        self.tokens.next().and_then(parse_i64).ok_or(())
    }

    fn invalid(&self, _error: impl FnOnce(Location) -> IoError) {}
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    const HEADER: &str = "ply\nformat ascii 1.0\ncomment made by hand\nelement vertex 3\nproperty double x\n\
        property double y\nproperty double z\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n";

    #[test]
    fn ascii_triangle() {
        let (soup, report) = read_ply(format!("{HEADER}0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n").as_bytes()).unwrap();
        assert_eq!(soup.positions[1].x, 1.0);
        assert_eq!(soup.face(0), &[0, 1, 2]);
        assert!(report.is_lossless());
        assert_eq!(report.ply_encoding, Some(PlyEncoding::Ascii));
    }

    fn binary_triangle(big_endian: bool) -> Vec<u8> {
        let mut bytes = format!(
            "ply\r\nformat {} 1.0\r\nelement vertex 3\r\nproperty float x\r\nproperty short flags\r\n\
             property float y\r\nproperty float z\r\nproperty list uchar float texture\r\nelement edge 1\r\n\
             property int vertex1\r\nproperty int vertex2\r\nelement face 1\r\nproperty uchar quality\r\n\
             property list int short vertex_index\r\nend_header\r\n",
            if big_endian { "binary_big_endian" } else { "binary_little_endian" }
        )
        .into_bytes();
        let mut put = |value: &[u8]| {
            let mut value = value.to_vec();
            if big_endian {
                value.reverse();
            }
            bytes.extend_from_slice(&value);
        };
        for (i, p) in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.5, 0.0]].iter().enumerate() {
            put(&p[0].to_le_bytes());
            put(&(i as i16).to_le_bytes());
            put(&p[1].to_le_bytes());
            put(&p[2].to_le_bytes());
            put(&[2]);
            put(&0.5f32.to_le_bytes());
            put(&0.25f32.to_le_bytes());
        }
        put(&0i32.to_le_bytes());
        put(&1i32.to_le_bytes());
        put(&[7]);
        put(&3i32.to_le_bytes());
        for i in [2i16, 1, 0] {
            put(&i.to_le_bytes());
        }
        bytes
    }

    #[test]
    fn binary_both_endians_with_skipped_properties_and_elements() {
        for big_endian in [false, true] {
            let (soup, report) = read_ply(&binary_triangle(big_endian)).unwrap();
            assert_eq!(soup.positions[2].y, 1.5);
            assert_eq!(soup.face(0), &[2, 1, 0]);
            let dropped: Vec<(&str, usize)> = report.dropped.iter().map(|d| (d.what.as_str(), d.count)).collect();
            assert_eq!(
                dropped,
                vec![
                    ("PLY vertex property `flags` values", 3),
                    ("PLY vertex property `texture` values", 3),
                    ("PLY `edge` elements", 1),
                    ("PLY face property `quality` values", 1),
                ]
            );
        }
    }

    #[test]
    fn every_truncation_of_binary_data_is_an_error_with_its_offset() {
        let bytes = binary_triangle(false);
        let header_end = bytes.windows(12).position(|w| w == b"end_header\r\n").unwrap() + 12;
        for cut in header_end..bytes.len() {
            let err = read_ply(&bytes[..cut]).unwrap_err();
            assert!(matches!(err, IoError::Truncated { at: Location::Byte(at), .. } if at == cut), "{cut}: {err}");
        }
        let mut longer = bytes.clone();
        longer.push(0);
        let err = read_ply(&longer).unwrap_err();
        assert!(matches!(err, IoError::TrailingData { at: Location::Byte(at), .. } if at == bytes.len()), "{err}");
    }

    #[test]
    fn header_errors() {
        let cases = [
            ("plyx\n", 1),
            ("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n", 3),
            ("ply\nformat ascii 1.0\nproperty float x\nend_header\n", 3),
            ("ply\nformat ascii 2.0\nend_header\n", 2),
            ("ply\nformat binary 1.0\nend_header\n", 2),
            ("ply\nelement vertex 0\nend_header\n", 3),
            ("ply\nformat ascii 1.0\nelement face 1\nproperty list uchar float vertex_indices\nend_header\n", 4),
            ("ply\nformat ascii 1.0\nelement face 1\nproperty int flags\nend_header\n", 3),
            ("ply\nformat ascii 1.0\nelement face 1\nproperty list float int vertex_indices\nend_header\n", 4),
            ("ply\nformat ascii 1.0\nelement vertex x\nend_header\n", 3),
            ("ply\nformat ascii 1.0\nelement a 1\nelement a 1\nend_header\n", 4),
            ("ply\nformat ascii 1.0\nelement a 1\nproperty quad q\nend_header\n", 4),
            ("ply\nformat ascii 1.0\nwhat\nend_header\n", 3),
            ("ply\nformat ascii 1.0\n", 2),
        ];
        for (text, line) in cases {
            let err = read_ply(text.as_bytes()).unwrap_err();
            assert_eq!(err.location(), Some(Location::Line(line)), "{text:?}: {err}");
        }
    }

    #[test]
    fn ascii_data_errors_name_the_line() {
        let cases = [
            ("0 0 0\n1 0 0\n0 1 0\n3 0 1 5\n", 14),
            ("0 0 0\n1 0 0\n0 1 0\n3 0 1 -1\n", 14),
            ("0 0 0\n1 x 0\n0 1 0\n3 0 1 2\n", 12),
            ("0 0 0\n1 0 0\n0 1 inf\n3 0 1 2\n", 13),
            ("0 0 0\n1 0 0\n0 1 0\n3 0 1.5 2\n", 14),
            ("0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n9\n", 15),
            ("0 0 0\n1 0 0\n0 1 0\n3 0 1\n", 14),
            ("0 0 0\n1 0 0\n0 1 0\n-3 0 1\n", 14),
        ];
        for (data, line) in cases {
            let err = read_ply(format!("{HEADER}{data}").as_bytes()).unwrap_err();
            assert_eq!(err.location(), Some(Location::Line(line)), "{data:?}: {err}");
        }
    }

    #[test]
    fn empty_elements_and_huge_counts() {
        // Elements without properties take no data, however many are declared.
        let text = "ply\nformat binary_little_endian 1.0\nelement nothing 99999999999\nend_header\n";
        let (soup, report) = read_ply(text.as_bytes()).unwrap();
        assert_eq!(soup.vertex_count(), 0);
        assert_eq!(report.dropped.len(), 1);
        let text = "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\n\
                    property float y\nproperty float z\nend_header\n";
        assert!(matches!(read_ply(text.as_bytes()).unwrap_err(), IoError::Truncated { .. }));
    }

    /// An ascii PLY text of `soup`, with what `extras` picks (bit 0: a `uchar` vertex
    /// property; bit 1: a list vertex property; bit 2: a `float` face property; bit 3: the
    /// faces before the vertices; bits 4-5: an `edge` element first, between the vertices
    /// and the faces, or last), then one kind of damage at `at`: 1 cut short, 2 a token
    /// that is not a number, 3 an index out of range, 4 a NaN, 5 two elements on one line,
    /// 6 an element over two lines, 7 a blank line, 8 both 5 and 6, 9 both 5 and a line
    /// copied (8 and 9 keep as many lines as elements), 10 a line after the last element.
    fn ply_text(soup: &PolygonSoup, extras: u8, damage: u8, at: usize) -> String {
        let vertex_extra = match extras & 3 {
            0 => "",
            1 => " 255",
            2 => " 2 0.5 0.25",
            _ => " 255 2 0.5 0.25",
        };
        let face_extra = if extras & 4 != 0 { " 0.5" } else { "" };
        let mut vertices = vec![format!("element vertex {}", soup.vertex_count()), "property double x".into()];
        vertices.extend(["property double y".into(), "property double z".into()]);
        if extras & 1 != 0 {
            vertices.push("property uchar red".into());
        }
        if extras & 2 != 0 {
            vertices.push("property list uchar float texture".into());
        }
        let mut vertex_lines = Vec::new();
        for (i, p) in soup.positions.iter().enumerate() {
            let p = if damage == 4 && i == at % soup.vertex_count() { DVec3::new(f64::NAN, 0.0, 0.0) } else { *p };
            vertex_lines.push(format!("{} {} {}{vertex_extra}", p.x, p.y, p.z));
        }
        let mut faces = vec![format!("element face {}", soup.face_count())];
        faces.push("property list uchar int vertex_indices".into());
        if extras & 4 != 0 {
            faces.push("property float quality".into());
        }
        let mut face_lines = Vec::new();
        for (i, face) in soup.faces().enumerate() {
            let mut words: Vec<String> = face.iter().map(u32::to_string).collect();
            if damage == 3 && i == at % soup.face_count() {
                words[0] = (soup.vertex_count() + 5).to_string();
            }
            face_lines.push(format!("{} {}{face_extra}", face.len(), words.join(" ")));
        }
        let edges = vec!["element edge 2".into(), "property int vertex1".into(), "property int vertex2".into()];
        let edge_lines = vec!["0 1".to_string(), "1 2".into()];
        let mut sections = vec![(vertices, vertex_lines), (faces, face_lines)];
        if extras & 8 != 0 {
            sections.reverse();
        }
        match (extras >> 4) % 4 {
            1 => sections.insert(0, (edges, edge_lines)),
            2 => sections.insert(1, (edges, edge_lines)),
            3 => sections.push((edges, edge_lines)),
            _ => {}
        }
        let mut header = vec!["ply".to_string(), "format ascii 1.0".into(), "comment pieces".into()];
        let mut data = Vec::new();
        for (declaration, lines) in sections {
            header.extend(declaration);
            data.extend(lines);
        }
        header.push("end_header\n".into());
        let k = at % data.len();
        let j = (at / 7) % data.len();
        let merge = |data: &mut Vec<String>, k: usize| {
            if k + 1 < data.len() {
                let next = data.remove(k + 1);
                data[k] = format!("{} {next}", data[k]);
            }
        };
        match damage {
            2 => data[k] = data[k].replacen(' ', " x ", 1),
            5 => merge(&mut data, k),
            6 => data[k] = data[k].replacen(' ', "\n", 1),
            7 => data.insert(at % (data.len() + 1), String::new()),
            8 => {
                merge(&mut data, k);
                let j = j.min(data.len() - 1);
                data[j] = data[j].replacen(' ', "\n", 1);
            }
            9 => {
                merge(&mut data, k);
                let copy = data[j.min(data.len() - 1)].clone();
                data.insert(j.min(data.len()), copy);
            }
            10 => data.push("0 0 0".into()),
            _ => {}
        }
        let header = header.join("\n");
        let mut text = header.clone() + &data.join("\n") + "\n";
        if damage == 1 {
            text.truncate(header.len() + at % (text.len() - header.len()));
        }
        text
    }

    proptest::proptest! {
        /// Read in parallel pieces (forced on small files, on two, three and five threads), an
        /// ascii file gives what one pass gives: the same soup and report, or the same error.
        #[test]
        fn pieces_read_as_one_pass(
            soup in crate::testing::arb_mesh(),
            extras in proptest::prelude::any::<u8>(),
            damage in 0u8..11,
            at in proptest::prelude::any::<usize>(),
        ) {
            let text = ply_text(&soup, extras, damage, at);
            crate::io::test_support::pieces_read_as_one_pass(&text, read_ply_split)?;
            if damage == 0 {
                let (read, _) = read_ply_split(text.as_bytes(), usize::MAX).unwrap();
                proptest::prop_assert_eq!(read.face_count(), soup.face_count());
                // And the pieces did read it (not the one pass after them).
                proptest::prop_assert_eq!(in_pieces(&text, 3), Some(read));
            }
        }
    }

    /// The pieces of `text` read apart on a pool of `threads`, or `None` where the one
    /// pass must read it.
    fn in_pieces(text: &str, threads: usize) -> Option<PolygonSoup> {
        let mut header = parse_header(text.as_bytes()).unwrap();
        let (vertex_count, _) = assign_roles(&mut header, &mut DroppedLog::default()).unwrap();
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| read_ascii_in_pieces(&text.as_bytes()[header.data_start..], &header, vertex_count))
    }

    /// A file over the threshold is really read in pieces (and gives the one-pass soup);
    /// with one element over two lines it is not, and still reads as one pass.
    #[test]
    fn large_files_are_read_in_pieces() {
        let soup = crate::shapes::torus(150, 150, crate::shapes::CellKind::Triangles).unwrap();
        let text = ply_text(&soup, 0b1_0111, 0, 0);
        assert!(text.len() > PARALLEL_MIN_BYTES);
        let (one_pass, report) = read_ply_split(text.as_bytes(), usize::MAX).unwrap();
        assert_eq!(one_pass.positions, soup.positions);
        assert_eq!(in_pieces(&text, 2).expect("read in pieces"), one_pass);
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        assert_eq!(pool.install(|| read_ply(text.as_bytes())).unwrap(), (one_pass.clone(), report));

        // As this crate's writer writes it.
        let mut written = Vec::new();
        crate::io::write_ply(&mut written, &soup, PlyEncoding::Ascii).unwrap();
        assert_eq!(in_pieces(std::str::from_utf8(&written).unwrap(), 2).expect("read in pieces"), soup);

        let split = ply_text(&soup, 0b1_0111, 6, 30_000);
        assert_eq!(in_pieces(&split, 2), None);
        let read = pool.install(|| read_ply(split.as_bytes())).unwrap().0;
        assert_eq!(read, one_pass);
    }
}
