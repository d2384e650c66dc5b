//! Writers: OBJ, OFF, PLY (ascii and binary), numbers in shortest round-trip form.
//!
//! The text formats of large meshes are formatted on the threads of the current `rayon`
//! pool while the writer (which need not be `Send`) takes the text in order on the
//! calling thread: the bytes do not depend on the number of threads.

use std::io::{BufWriter, Write};

use rayon::prelude::*;

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
}

impl<W: Write> LineWriter<W> {
    fn new(out: W) -> Self {
        Self { out: BufWriter::with_capacity(BUFFER, out), line: Vec::with_capacity(256) }
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

    /// Writes one line per item `0..count`, each appended to a buffer by
    /// `line(item, buffer, ryu)` and ended here with a newline, in item order.
    ///
    /// Formatting numbers is most of the cost of a large text file, so when the current
    /// `rayon` pool has several threads, pieces of [`PIECE_LINES`] items are formatted
    /// side by side, a batch at a time, while the batch before is written: the bytes
    /// are those of formatting the items one after the other.
    fn lines(
        &mut self,
        count: usize,
        line: impl Fn(usize, &mut Vec<u8>, &mut ryu::Buffer) + Sync,
    ) -> Result<(), IoError> {
        let format = |items: std::ops::Range<usize>, text: &mut Vec<u8>| {
            let mut ryu = ryu::Buffer::new();
            for item in items {
                line(item, text, &mut ryu);
                text.push(b'\n');
            }
        };
        let threads = rayon::current_num_threads();
        if threads == 1 || count < 2 * PIECE_LINES {
            let mut text = Vec::with_capacity(BUFFER);
            let mut start = 0;
            while start < count {
                let end = count.min(start + PIECE_LINES);
                format(start..end, &mut text);
                self.out.write_all(&text).map_err(IoError::Stream)?;
                text.clear();
                start = end;
            }
            return Ok(());
        }
        // Batches of one piece per thread; each batch's pieces are formatted while the
        // batch before is written.
        let batch_lines = threads * PIECE_LINES;
        let format_batch = |start: usize| -> Vec<Vec<u8>> {
            let end = count.min(start + batch_lines);
            (start..end)
                .into_par_iter()
                .step_by(PIECE_LINES)
                .map(|piece| {
                    let mut text = Vec::new();
                    format(piece..end.min(piece + PIECE_LINES), &mut text);
                    text
                })
                .collect()
        };
        let out = &mut self.out;
        let write_batch = |pieces: Vec<Vec<u8>>, out: &mut BufWriter<W>| -> Result<(), IoError> {
            pieces.iter().try_for_each(|text| out.write_all(text).map_err(IoError::Stream))
        };
        let mut batch = format_batch(0);
        let mut start = batch_lines;
        while start < count {
            // The writer stays on this thread (it need not be `Send`); the next batch is
            // formatted by the pool meanwhile.
            let mut next = Vec::new();
            rayon::in_place_scope(|scope| {
                scope.spawn(|_| next = format_batch(start));
                write_batch(batch, out)
            })?;
            batch = next;
            start += batch_lines;
        }
        write_batch(batch, out)
    }

    fn finish(mut self) -> Result<(), IoError> {
        self.out.flush().map_err(IoError::Stream)
    }
}

/// Lines formatted by one task of [`LineWriter::lines`].
const PIECE_LINES: usize = 1 << 14;

/// Appends the three coordinates of `p`, separated by spaces.
#[inline]
fn push_point(text: &mut Vec<u8>, ryu: &mut ryu::Buffer, p: glam::DVec3) {
    push_f64(text, ryu, p.x);
    text.push(b' ');
    push_f64(text, ryu, p.y);
    text.push(b' ');
    push_f64(text, ryu, p.z);
}

/// Appends the corners of `face`, each after a space, adding `base` (1 for OBJ).
#[inline]
fn push_corners(text: &mut Vec<u8>, face: &[u32], base: u32) {
    for &v in face {
        text.push(b' ');
        push_u32(text, v + base);
    }
}

/// Writes a soup as OBJ: one `v x y z` line per vertex, one `f` line per face with
/// 1-based indices, after a comment with the counts.
///
/// ```
/// use mesh_topo::{DVec3, PolygonSoup, io};
///
/// let positions = vec![DVec3::ZERO, DVec3::new(0.5, 0.0, 0.0), DVec3::new(0.0, 0.1, -2.0)];
/// let soup = PolygonSoup::from_faces(positions, [[0u32, 1, 2]]);
/// let mut obj = Vec::new();
/// io::write_obj(&mut obj, &soup)?;
/// assert_eq!(obj, b"# 3 vertices, 1 faces\nv 0 0 0\nv 0.5 0 0\nv 0 0.1 -2\nf 1 2 3\n");
/// assert_eq!(io::read_obj(&obj)?.0, soup);
/// # Ok::<(), mesh_topo::io::IoError>(())
/// ```
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
    w.lines(soup.vertex_count(), |v, text, ryu| {
        text.extend_from_slice(b"v ");
        push_point(text, ryu, soup.positions[v]);
    })?;
    w.lines(soup.face_count(), |f, text, _| {
        text.push(b'f');
        push_corners(text, soup.face(f), 1);
    })?;
    w.finish()
}

/// Writes a soup as OFF (`OFF`, counts with an edge count of 0, vertex lines, face lines).
///
/// ```
/// use mesh_topo::{io, shapes};
///
/// let soup = shapes::icosahedron();
/// let mut off = Vec::new();
/// io::write_off(&mut off, &soup)?;
/// assert!(off.starts_with(b"OFF\n12 20 0\n"));
/// assert_eq!(io::read_off(&off)?.0, soup); // coordinates bit for bit
/// # Ok::<(), mesh_topo::io::IoError>(())
/// ```
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
    w.lines(soup.vertex_count(), |v, text, ryu| push_point(text, ryu, soup.positions[v]))?;
    w.lines(soup.face_count(), |f, text, _| {
        let face = soup.face(f);
        push_u32(text, face.len() as u32);
        push_corners(text, face, 0);
    })
}

/// Writes a soup as PLY: `double` coordinates, faces as `vertex_indices` lists of
/// `uint` (counted by `uchar`, or by `uint` when a face has more than 255 corners).
///
/// ```
/// use mesh_topo::io::{self, PlyEncoding};
/// use mesh_topo::shapes;
///
/// let soup = shapes::cube();
/// let mut ply = Vec::new();
/// io::write_ply(&mut ply, &soup, PlyEncoding::BinaryBigEndian)?;
/// assert!(ply.starts_with(b"ply\nformat binary_big_endian 1.0\nelement vertex 8\n"));
/// let (read, report) = io::read_ply(&ply)?;
/// assert_eq!((read, report.ply_encoding), (soup, Some(PlyEncoding::BinaryBigEndian)));
/// # Ok::<(), mesh_topo::io::IoError>(())
/// ```
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

    /// The OFF text of `soup` line after line, as the writer's sequential form reads.
    fn off_text(soup: &PolygonSoup) -> Vec<u8> {
        let mut text = format!("OFF\n{} {} 0\n", soup.vertex_count(), soup.face_count()).into_bytes();
        for p in &soup.positions {
            let coordinates: Vec<String> = p.to_array().iter().map(|&x| shortest(x)).collect();
            text.extend_from_slice(coordinates.join(" ").as_bytes());
            text.push(b'\n');
        }
        for face in soup.faces() {
            let corners: Vec<String> = face.iter().map(u32::to_string).collect();
            text.extend_from_slice(format!("{} {}\n", face.len(), corners.join(" ")).as_bytes());
        }
        text
    }

    /// A writer that fails once `room` bytes have been written.
    struct Full {
        room: usize,
    }

    impl Write for Full {
        fn write(&mut self, bytes: &[u8]) -> std::io::Result<usize> {
            if bytes.len() > self.room {
                return Err(std::io::Error::other("disk full"));
            }
            self.room -= bytes.len();
            Ok(bytes.len())
        }

        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn pieces_formatted_on_several_threads_make_the_same_bytes() {
        // Enough lines for several batches of pieces, and counts that are not multiples
        // of a piece: the last piece and the last batch are short.
        let mut soup = crate::shapes::torus(211, 197, crate::shapes::CellKind::Mixed).unwrap();
        for (i, p) in soup.positions.iter_mut().enumerate() {
            *p += DVec3::splat(1.0 / (i as f64 + 3.0));
        }
        assert!(soup.vertex_count() > 2 * PIECE_LINES && !soup.face_count().is_multiple_of(PIECE_LINES));
        let write_all = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| {
                let (mut off, mut obj, mut ply) = (Vec::new(), Vec::new(), Vec::new());
                write_off(&mut off, &soup).unwrap();
                write_obj(&mut obj, &soup).unwrap();
                write_ply(&mut ply, &soup, PlyEncoding::Ascii).unwrap();
                (off, obj, ply)
            })
        };
        let one = write_all(1);
        assert!(one.0 == off_text(&soup), "the OFF text is the line-by-line one");
        for threads in [2, 3] {
            assert!(write_all(threads) == one, "{threads} threads");
        }
        // A stream that fails part way: the error, on every thread count.
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let result = pool.install(|| write_obj(Full { room: one.1.len() / 2 }, &soup));
            assert!(matches!(result, Err(IoError::Stream(_))), "{threads} threads");
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
