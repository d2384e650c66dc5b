//! Writers: OBJ, OFF, PLY (ascii and binary), numbers in shortest round-trip form.

use std::io::{BufWriter, Write};

use super::{IoError, PlyEncoding};
use crate::soup::PolygonSoup;

/// Buffer size of the writers.
const BUFFER: usize = 1 << 17;

/// Fails if the soup cannot be written as a valid file: offsets must start at 0, never
/// decrease and end at the number of indices; indices must name existing vertices;
/// coordinates must be finite (no format can hold NaN in a way readers accept).
pub(crate) fn check_writable(soup: &PolygonSoup) -> Result<(), IoError> {
    let invalid = |reason: String| Err(IoError::InvalidSoup(reason));
    if soup.offsets.is_empty() {
        if !soup.indices.is_empty() {
            return invalid(format!("{} indices but no face offsets", soup.indices.len()));
        }
    } else {
        if soup.offsets[0] != 0 {
            return invalid(format!("the first face offset is {}, not 0", soup.offsets[0]));
        }
        if let Some(face) = soup.offsets.windows(2).position(|w| w[0] > w[1]) {
            return invalid(format!("face {face} ends before it starts"));
        }
        let last = *soup.offsets.last().expect("internal: offsets checked non-empty");
        if last as usize != soup.indices.len() {
            return invalid(format!("the last face offset is {last}, but there are {} indices", soup.indices.len()));
        }
    }
    let vertex_count = soup.positions.len();
    if let Some(corner) = soup.indices.iter().position(|&i| i as usize >= vertex_count) {
        let face = soup.offsets.partition_point(|&o| o as usize <= corner) - 1;
        return invalid(format!(
            "face {face} uses vertex {} but there are {vertex_count} vertices",
            soup.indices[corner]
        ));
    }
    for (vertex, p) in soup.positions.iter().enumerate() {
        if !p.is_finite() {
            return invalid(format!("vertex {vertex} has a non-finite coordinate ({p})"));
        }
    }
    if vertex_count > u32::MAX as usize {
        return invalid(format!("{vertex_count} vertices cannot be indexed with u32"));
    }
    Ok(())
}

/// Appends the shortest decimal form of a finite `x` that parses back to the same bits
/// (`ryu`), without a trailing `.0` (`1` rather than `1.0`, `-0` for negative zero).
#[inline]
pub(crate) fn push_f64(out: &mut Vec<u8>, buffer: &mut ryu::Buffer, x: f64) {
    let text = buffer.format_finite(x).as_bytes();
    out.extend_from_slice(text.strip_suffix(b".0").unwrap_or(text));
}

/// Appends a `u32` in decimal.
#[inline]
pub(crate) fn push_u32(out: &mut Vec<u8>, mut n: u32) {
    let mut digits = [0u8; 10];
    let mut start = digits.len();
    loop {
        start -= 1;
        digits[start] = b'0' + (n % 10) as u8;
        n /= 10;
        if n == 0 {
            break;
        }
    }
    out.extend_from_slice(&digits[start..]);
}

/// A line-oriented output: lines are assembled in a reused `Vec` and written in bulk.
struct LineWriter<W: Write> {
    out: BufWriter<W>,
    line: Vec<u8>,
    ryu: ryu::Buffer,
}

impl<W: Write> LineWriter<W> {
    fn new(out: W) -> Self {
        Self { out: BufWriter::with_capacity(BUFFER, out), line: Vec::with_capacity(256), ryu: ryu::Buffer::new() }
    }

    #[inline]
    fn emit(&mut self) -> Result<(), IoError> {
        self.line.push(b'\n');
        self.out.write_all(&self.line).map_err(IoError::Stream)?;
        self.line.clear();
        Ok(())
    }

    #[inline]
    fn text(&mut self, text: &str) {
        self.line.extend_from_slice(text.as_bytes());
    }

    #[inline]
    fn point(&mut self, p: [f64; 3]) {
        for (axis, x) in p.into_iter().enumerate() {
            if axis > 0 {
                self.line.push(b' ');
            }
            push_f64(&mut self.line, &mut self.ryu, x);
        }
    }

    fn finish(mut self) -> Result<(), IoError> {
        self.out.flush().map_err(IoError::Stream)
    }
}

/// Writes a soup as OBJ: one `v x y z` line per vertex, one `f` line per face with
/// 1-based indices, after a comment with the counts.
///
/// # Errors
/// [`IoError::InvalidSoup`] if the soup cannot be written (see [`write_soup`]),
/// [`IoError::Stream`] if the output fails.
///
/// [`write_soup`]: super::write_soup
pub fn write_obj(out: impl Write, soup: &PolygonSoup) -> Result<(), IoError> {
    check_writable(soup)?;
    let mut w = LineWriter::new(out);
    w.text(&format!("# {} vertices, {} faces", soup.vertex_count(), soup.face_count()));
    w.emit()?;
    for p in &soup.positions {
        w.text("v ");
        w.point(p.to_array());
        w.emit()?;
    }
    for face in soup.faces() {
        w.line.push(b'f');
        for &v in face {
            w.line.push(b' ');
            push_u32(&mut w.line, v + 1);
        }
        w.emit()?;
    }
    w.finish()
}

/// Writes a soup as OFF (`OFF`, counts with an edge count of 0, vertex lines, face lines).
///
/// # Errors
/// As [`write_obj`].
pub fn write_off(out: impl Write, soup: &PolygonSoup) -> Result<(), IoError> {
    check_writable(soup)?;
    let mut w = LineWriter::new(out);
    w.text(&format!("OFF\n{} {} 0", soup.vertex_count(), soup.face_count()));
    w.emit()?;
    write_counted_body(&mut w, soup)?;
    w.finish()
}

/// The body shared by OFF and ASCII PLY: one `x y z` line per vertex, then one line per
/// face, its corner count first.
fn write_counted_body<W: Write>(w: &mut LineWriter<W>, soup: &PolygonSoup) -> Result<(), IoError> {
    for p in &soup.positions {
        w.point(p.to_array());
        w.emit()?;
    }
    for face in soup.faces() {
        push_u32(&mut w.line, face.len() as u32);
        for &v in face {
            w.line.push(b' ');
            push_u32(&mut w.line, v);
        }
        w.emit()?;
    }
    Ok(())
}

/// Writes a soup as PLY: `double` coordinates, faces as `vertex_indices` lists of
/// `uint` (counted by `uchar`, or by `uint` when a face has more than 255 corners).
///
/// # Errors
/// As [`write_obj`].
pub fn write_ply(out: impl Write, soup: &PolygonSoup, encoding: PlyEncoding) -> Result<(), IoError> {
    check_writable(soup)?;
    let widest = soup.offsets.windows(2).map(|w| w[1] - w[0]).max().unwrap_or(0);
    let count_type = if widest <= u8::MAX as u32 { "uchar" } else { "uint" };
    let mut w = LineWriter::new(out);
    w.text(&format!(
        "ply\nformat {} 1.0\nelement vertex {}\nproperty double x\nproperty double y\nproperty double z\n\
         element face {}\nproperty list {count_type} uint vertex_indices\nend_header",
        encoding.header_name(),
        soup.vertex_count(),
        soup.face_count()
    ));
    w.emit()?;
    match encoding {
        PlyEncoding::Ascii => {
            write_counted_body(&mut w, soup)?;
            w.finish()
        }
        PlyEncoding::BinaryLittleEndian | PlyEncoding::BinaryBigEndian => {
            let big = encoding == PlyEncoding::BinaryBigEndian;
            let mut out = w.out;
            let mut put = |bytes: &[u8]| out.write_all(bytes).map_err(IoError::Stream);
            for p in &soup.positions {
                for x in p.to_array() {
                    put(&if big { x.to_be_bytes() } else { x.to_le_bytes() })?;
                }
            }
            for face in soup.faces() {
                let n = face.len() as u32;
                if count_type == "uchar" {
                    put(&[n as u8])?;
                } else {
                    put(&if big { n.to_be_bytes() } else { n.to_le_bytes() })?;
                }
                for &v in face {
                    put(&if big { v.to_be_bytes() } else { v.to_le_bytes() })?;
                }
            }
            out.flush().map_err(IoError::Stream)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    fn shortest(x: f64) -> String {
        let mut out = Vec::new();
        push_f64(&mut out, &mut ryu::Buffer::new(), x);
        String::from_utf8(out).unwrap()
    }

    #[test]
    fn numbers_are_shortest_and_round_trip() {
        assert_eq!(shortest(1.0), "1");
        assert_eq!(shortest(-0.0), "-0");
        assert_eq!(shortest(0.1), "0.1");
        assert_eq!(shortest(100.0), "100");
        for x in [f64::MIN_POSITIVE, 5e-324, f64::MAX, -f64::MAX, 1.0 / 3.0, 1e21, 123456789.125, -0.0] {
            assert_eq!(shortest(x).parse::<f64>().unwrap().to_bits(), x.to_bits(), "{x}");
        }
        let mut out = Vec::new();
        for n in [0, 7, 10, 4294967295] {
            out.clear();
            push_u32(&mut out, n);
            assert_eq!(String::from_utf8(out.clone()).unwrap(), n.to_string());
        }
    }

    #[test]
    fn invalid_soups_are_refused() {
        let triangle = || PolygonSoup::from_faces(vec![DVec3::ZERO, DVec3::X, DVec3::Y], [[0u32, 1, 2]]);
        assert!(check_writable(&triangle()).is_ok());
        assert!(check_writable(&PolygonSoup::default()).is_ok());
        let mut soup = triangle();
        soup.indices[1] = 3;
        assert!(check_writable(&soup).unwrap_err().to_string().contains("face 0 uses vertex 3"));
        let mut soup = triangle();
        soup.positions[2].z = f64::NAN;
        assert!(check_writable(&soup).is_err());
        let mut soup = triangle();
        soup.offsets = vec![0, 2];
        assert!(check_writable(&soup).is_err());
        let mut soup = triangle();
        soup.offsets = vec![1, 3];
        assert!(check_writable(&soup).is_err());
        let mut soup = triangle();
        soup.offsets.clear();
        assert!(check_writable(&soup).is_err());
    }
}
