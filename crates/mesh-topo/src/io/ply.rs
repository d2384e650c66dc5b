//! PLY (Polygon File Format) reader: ascii, binary little- and big-endian.

use super::report::DroppedLog;
use super::text::{Lines, invalid_number, is_space, parse_f64, parse_i64, show_token, tokens};
use super::{Format, IoError, Location, PlyEncoding, ReadReport};
use crate::ids::MAX_ELEMENTS;
use crate::soup::PolygonSoup;

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

/// A source of PLY values (ascii tokens or binary numbers).
trait Body {
    /// Reads a value as a float (coordinates).
    fn float(&mut self, ty: Scalar) -> Result<f64, IoError>;
    /// Reads an integer value (list counts, indices).
    fn integer(&mut self, ty: Scalar) -> Result<i64, IoError>;
    /// Skips one value.
    fn skip(&mut self, ty: Scalar) -> Result<(), IoError>;
    /// Skips `n` values.
    fn skip_many(&mut self, ty: Scalar, n: u64) -> Result<(), IoError>;
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

impl Body for AsciiBody<'_> {
    #[inline]
    fn float(&mut self, ty: Scalar) -> Result<f64, IoError> {
        let token = self.token()?;
        if ty.is_integer() {
            parse_i64(token).map(|v| v as f64).ok_or_else(|| invalid_number(self.token_line, token, "an integer"))
        } else {
            parse_f64(token).ok_or_else(|| invalid_number(self.token_line, token, "a number"))
        }
    }

    #[inline]
    fn integer(&mut self, _ty: Scalar) -> Result<i64, IoError> {
        let token = self.token()?;
        parse_i64(token).ok_or_else(|| invalid_number(self.token_line, token, "an integer"))
    }

    #[inline]
    fn skip(&mut self, ty: Scalar) -> Result<(), IoError> {
        self.float(ty).map(drop)
    }

    fn skip_many(&mut self, ty: Scalar, n: u64) -> Result<(), IoError> {
        for _ in 0..n {
            self.skip(ty)?;
        }
        Ok(())
    }

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

impl Body for BinaryBody<'_> {
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
            let mut position = [0.0; 3];
            for property in &element.properties {
                let result = match (property.role, property.kind) {
                    (Role::Coordinate(axis), Kind::Scalar(ty)) => body.float(ty).map(|x| position[axis] = x),
                    (Role::FaceIndices, Kind::List { count, item }) => read_face(body, count, item, vertex_count, soup),
                    (_, Kind::Scalar(ty)) => body.skip(ty),
                    (_, Kind::List { count, item }) => body
                        .integer(count)
                        .and_then(|n| {
                            u64::try_from(n).map_err(|_| IoError::InvalidNumber {
                                at: body.location(),
                                token: n.to_string(),
                                expected: "a list length",
                            })
                        })
                        .and_then(|n| body.skip_many(item, n)),
                };
                result.map_err(|e| in_element(e, i))?;
            }
            if is_vertex {
                if let Some(&value) = position.iter().find(|x| !x.is_finite()) {
                    return Err(IoError::NonFiniteCoordinate { at: body.location(), vertex: i as usize, value });
                }
                soup.positions.push(position.into());
            }
        }
    }
    body.finish(last_element)
}

#[inline]
fn read_face<B: Body>(
    body: &mut B,
    count: Scalar,
    item: Scalar,
    vertex_count: u64,
    soup: &mut PolygonSoup,
) -> Result<(), IoError> {
    let n = body.integer(count)?;
    if n < 0 {
        return Err(IoError::InvalidNumber { at: body.location(), token: n.to_string(), expected: "a list length" });
    }
    for _ in 0..n {
        let index = body.integer(item)?;
        if index < 0 || index as u64 >= vertex_count {
            return Err(IoError::IndexOutOfRange { at: body.location(), index, vertex_count: vertex_count as usize });
        }
        soup.indices.push(index as u32);
    }
    if soup.indices.len() > u32::MAX as usize {
        return Err(IoError::TooLarge { at: body.location(), what: "face corners", max: u32::MAX as usize });
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
    let mut header = parse_header(bytes)?;
    let mut dropped = DroppedLog::default();
    let (vertex_count, face_count) = assign_roles(&mut header, &mut dropped)?;
    let data = &bytes[header.data_start..];
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

#[cfg(test)]
mod tests {
    use super::*;

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
}
