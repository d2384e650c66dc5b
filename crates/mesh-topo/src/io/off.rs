//! OFF (Object File Format) reader.

use super::report::{Counter, DroppedLog};
use super::text::{
    Lines, Tokens, check_finite, coordinate, invalid_number, parse_i64, show_token, strip_comment, tokens,
};
use super::{Format, IoError, Location, ReadReport};
use crate::ids::MAX_ELEMENTS;
use crate::soup::PolygonSoup;

/// The optional prefixes of the OFF keyword, `[ST][C][N][4][n]OFF`.
#[derive(Debug, Default, Clone, Copy)]
struct Variant {
    texcoords: bool,
    colours: bool,
    normals: bool,
    homogeneous: bool,
    dimension_given: bool,
}

impl Variant {
    fn parse(keyword: &[u8]) -> Option<Self> {
        let mut rest = keyword.strip_suffix(b"OFF")?;
        let mut take = |prefix: &[u8]| match rest.strip_prefix(prefix) {
            Some(after) => {
                rest = after;
                true
            }
            None => false,
        };
        let variant = Self {
            texcoords: take(b"ST"),
            colours: take(b"C"),
            normals: take(b"N"),
            homogeneous: take(b"4"),
            dimension_given: take(b"n"),
        };
        rest.is_empty().then_some(variant)
    }
}

/// Reads an OFF file from memory.
///
/// The keyword may carry Geomview's prefixes (`COFF`, `NOFF`, `STOFF`, `nOFF` with
/// dimension 3, and combinations); the counts may follow it on the same line. Vertex
/// lines hold `x y z` and optionally normals, colours, texture coordinates; face lines
/// `n i1 .. in` and optionally a colour. Everything after `x y z` and after the indices
/// is reported, not kept. `#` starts a comment anywhere.
///
/// ```
/// let off = b"OFF\n# a triangle\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2 255 0 0\n";
/// let (soup, report) = mesh_topo::io::read_off(off)?;
/// assert_eq!(soup.face(0), &[0, 1, 2]);
/// assert_eq!(report.dropped[0].what, "face colours");
/// # Ok::<(), mesh_topo::io::IoError>(())
/// ```
///
/// # Errors
/// With the line number: a missing or unknown keyword or malformed counts
/// ([`IoError::InvalidHeader`]), binary or homogeneous OFF ([`IoError::Unsupported`]),
/// fewer vertex or face lines than announced ([`IoError::Truncated`]), more data than
/// announced ([`IoError::TrailingData`]), a vertex line with fewer than 3 coordinates or
/// a face line with fewer indices than it announces ([`IoError::CountMismatch`]), a
/// non-numeric token, a NaN or infinite coordinate, an index out of range.
pub fn read_off<'a>(bytes: &'a [u8]) -> Result<(PolygonSoup, ReadReport), IoError> {
    // A UTF-8 byte-order mark, as some Windows tools write, is not content.
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    let mut lines = Lines::new(bytes);
    // Content lines: comments removed, blank lines skipped.
    let mut next_content = move || -> Option<(usize, Tokens<'a>)> {
        for (line, raw) in lines.by_ref() {
            let words = tokens(strip_comment(raw));
            if words.clone().next().is_some() {
                return Some((line, words));
            }
        }
        None
    };
    // The last line, for "file ends early" errors (counted only then).
    let end = || {
        let lines = memchr::memchr_iter(b'\n', bytes).count() + usize::from(!bytes.ends_with(b"\n"));
        Location::Line(lines.max(1))
    };

    let Some((header_line, mut header)) = next_content() else {
        return Err(IoError::InvalidHeader { at: end(), reason: "empty file, expected the `OFF` keyword".into() });
    };
    let keyword = header.next().unwrap_or_default();
    let at = Location::Line(header_line);
    let variant = Variant::parse(keyword).ok_or_else(|| IoError::InvalidHeader {
        at,
        reason: format!("expected the `OFF` keyword, found `{}`", show_token(keyword)),
    })?;
    if variant.homogeneous {
        return Err(IoError::Unsupported { at, what: "homogeneous (`4OFF`) vertices".into() });
    }
    let mut rest: Vec<&[u8]> = header.collect();
    if rest.first().is_some_and(|t| t.eq_ignore_ascii_case(b"BINARY")) {
        return Err(IoError::Unsupported { at, what: "binary OFF".into() });
    }
    let mut counts_line = header_line;
    let mut take_line = |rest: &mut Vec<&'a [u8]>, what: &str| -> Result<(), IoError> {
        if rest.is_empty() {
            let (line, words) =
                next_content().ok_or_else(|| IoError::Truncated { at: end(), expected: what.to_string() })?;
            counts_line = line;
            *rest = words.collect();
        }
        Ok(())
    };
    if variant.dimension_given {
        take_line(&mut rest, "the vertex dimension")?;
        let token = rest.remove(0);
        if token != b"3" {
            return Err(IoError::Unsupported {
                at: Location::Line(counts_line),
                what: format!("vertex dimension `{}` (only 3 is read)", show_token(token)),
            });
        }
    }
    take_line(&mut rest, "the vertex, face and edge counts")?;
    let at = Location::Line(counts_line);
    if rest.len() < 2 || rest.len() > 3 {
        return Err(IoError::InvalidHeader {
            at,
            reason: format!("expected the vertex, face and edge counts, found {} values", rest.len()),
        });
    }
    let count = |token: &[u8], what: &'static str| -> Result<usize, IoError> {
        let value =
            parse_i64(token).filter(|&v| v >= 0).ok_or_else(|| invalid_number(counts_line, token, "a count"))?;
        if value as u64 > MAX_ELEMENTS as u64 {
            return Err(IoError::TooLarge { at, what, max: MAX_ELEMENTS });
        }
        Ok(value as usize)
    };
    let vertex_count = count(rest[0], "vertices")?;
    let face_count = count(rest[1], "faces")?;
    if let Some(&edges) = rest.get(2) {
        // The edge count is informative only (Geomview ignores it); it must still be a number.
        parse_i64(edges).ok_or_else(|| invalid_number(counts_line, edges, "a count"))?;
    }

    // Never reserve more than the file can fill: a vertex line takes at least 6 bytes,
    // a face line at least 2.
    let mut soup = PolygonSoup::with_capacity(
        vertex_count.min(bytes.len() / 6),
        face_count.min(bytes.len() / 2),
        (3 * face_count).min(bytes.len() / 2),
    );
    let mut extra_vertex_values = Counter::default();
    let mut face_colours = Counter::default();

    for vertex in 0..vertex_count {
        let (line, mut words) = next_content().ok_or_else(|| IoError::Truncated {
            at: end(),
            expected: format!("{vertex_count} vertices, found {vertex}"),
        })?;
        let mut p = [0.0; 3];
        let mut found = 0;
        for token in words.by_ref().take(3) {
            p[found] = coordinate(line, token)?;
            found += 1;
        }
        if found < 3 {
            return Err(IoError::CountMismatch {
                at: Location::Line(line),
                what: "coordinates on a vertex line",
                expected: 3,
                found,
            });
        }
        let mut extra = 0;
        for token in words {
            coordinate(line, token)?;
            extra += 1;
        }
        if extra > 0 {
            extra_vertex_values.hit(line);
        }
        check_finite(Location::Line(line), vertex, p)?;
        soup.positions.push(p.into());
    }

    for face in 0..face_count {
        let (line, mut words) = next_content()
            .ok_or_else(|| IoError::Truncated { at: end(), expected: format!("{face_count} faces, found {face}") })?;
        let size_token = words.next().unwrap_or_default();
        let size = parse_i64(size_token)
            .filter(|&n| n >= 0)
            .ok_or_else(|| invalid_number(line, size_token, "a face size"))? as u64;
        let mut found = 0;
        while found < size {
            let Some(token) = words.next() else { break };
            let index = parse_i64(token).ok_or_else(|| invalid_number(line, token, "a vertex index"))?;
            if index < 0 || index as u64 >= vertex_count as u64 {
                return Err(IoError::IndexOutOfRange { at: Location::Line(line), index, vertex_count });
            }
            soup.indices.push(index as u32);
            found += 1;
        }
        if found < size {
            return Err(IoError::CountMismatch {
                at: Location::Line(line),
                what: "vertex indices on a face line (its first number)",
                expected: size as usize,
                found: found as usize,
            });
        }
        let mut colour_values = 0;
        for token in words {
            coordinate(line, token)?;
            colour_values += 1;
        }
        if colour_values > 0 {
            face_colours.hit(line);
        }
        if soup.indices.len() > u32::MAX as usize {
            return Err(IoError::TooLarge { at: Location::Line(line), what: "face corners", max: u32::MAX as usize });
        }
        soup.offsets.push(soup.indices.len() as u32);
    }

    if let Some((line, _)) = next_content() {
        let what = if face_count > 0 { "face" } else { "vertex" };
        return Err(IoError::TrailingData { at: Location::Line(line), what });
    }

    let mut log = DroppedLog::default();
    let vertex_extras = match (variant.normals, variant.colours, variant.texcoords) {
        (false, false, false) => "extra values on vertex lines (colours?)",
        (true, false, false) => "vertex normals (`NOFF`)",
        (false, true, false) => "vertex colours (`COFF`)",
        (false, false, true) => "vertex texture coordinates (`STOFF`)",
        _ => "vertex normals, colours or texture coordinates",
    };
    extra_vertex_values.flush(&mut log, vertex_extras);
    face_colours.flush(&mut log, "face colours");
    Ok((soup, log.into_report(Format::Off, None)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(text: &str) -> Result<(PolygonSoup, ReadReport), IoError> {
        read_off(text.as_bytes())
    }

    const SQUARE: &str = "OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";

    #[test]
    fn plain_and_commented() {
        let (soup, report) = read(SQUARE).unwrap();
        assert_eq!((soup.vertex_count(), soup.face_count()), (4, 1));
        assert!(report.is_lossless());
        let (again, _) =
            read("# lead\n\nOFF # keyword\n# counts next\n4 1 0\n0 0 0\n1 0 0\n\n1 1 0\n0 1 0 # last\n4 0 1 2 3\n\n")
                .unwrap();
        assert_eq!(again, soup);
        let (crlf, _) = read(&SQUARE.replace('\n', "\r\n")).unwrap();
        assert_eq!(crlf, soup);
        let (inline_counts, _) = read("OFF 4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3").unwrap();
        assert_eq!(inline_counts, soup);
        let (no_edge_count, _) = read("OFF\n4 1\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3").unwrap();
        assert_eq!(no_edge_count, soup);
    }

    #[test]
    fn variants_and_colours_are_reported() {
        let (soup, report) =
            read("COFF\n3 1 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n0 1 0 0 0 255 255\n3 0 1 2 0.5 0.5 0.5\n")
                .unwrap();
        assert_eq!(soup.positions[1].x, 1.0);
        let dropped: Vec<(&str, usize)> = report.dropped.iter().map(|d| (d.what.as_str(), d.count)).collect();
        assert_eq!(dropped, vec![("vertex colours (`COFF`)", 3), ("face colours", 1)]);
        let (_, report) = read("NOFF\n3 1 0\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n").unwrap();
        assert_eq!(report.dropped[0].what, "vertex normals (`NOFF`)");
        let (soup, _) = read("nOFF\n3\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n").unwrap();
        assert_eq!(soup.face_count(), 1);
        let (_, report) = read("STCNOFF\n3 1 0\n0 0 0 0 0 1 1 1 1 1 0 0\n1 0 0\n0 1 0\n3 0 1 2\n").unwrap();
        assert_eq!(report.dropped[0].count, 1);
    }

    #[test]
    fn unsupported_variants() {
        for text in ["4OFF\n1 0 0\n0 0 0 1\n", "OFF BINARY\n", "nOFF\n4\n1 0 0\n0 0 0 0\n"] {
            assert!(
                matches!(read(text).unwrap_err(), IoError::Unsupported { at: Location::Line(1 | 2), .. }),
                "{text}"
            );
        }
        for text in ["", "PLY\n", "OFFX\n1 0 0\n", "OFF\n1\n", "OFF\n1 2 3 4\n", "OFF\n-1 0 0\n"] {
            let err = read(text).unwrap_err();
            assert!(matches!(err, IoError::InvalidHeader { .. } | IoError::InvalidNumber { .. }), "{text:?}: {err}");
        }
    }

    #[test]
    fn errors_name_the_line() {
        let cases: [(&str, usize); 9] = [
            ("OFF\n3 1 0\n0 0 0\n1 0 0\n", 4),                          // truncated vertices
            ("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n", 5),                   // truncated faces
            ("OFF\n3 1 0\n0 0 0\n1 0\n0 1 0\n3 0 1 2\n", 4),            // too few coordinates
            ("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n", 6),          // face shorter than announced
            ("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", 6),          // index out of range
            ("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n", 6),         // negative index
            ("OFF\n3 1 0\n0 0 0\n1 0 zero\n0 1 0\n3 0 1 2\n", 4),       // non-numeric
            ("OFF\n3 1 0\n0 0 0\n1 0 NaN\n0 1 0\n3 0 1 2\n", 4),        // NaN
            ("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 2\n", 7), // trailing data
        ];
        for (text, line) in cases {
            let err = read(text).unwrap_err();
            assert_eq!(err.location(), Some(Location::Line(line)), "{text:?}: {err}");
        }
    }

    #[test]
    fn huge_counts_do_not_reserve_memory() {
        let err = read("OFF\n4000000000 4000000000 0\n0 0 0\n").unwrap_err();
        assert!(matches!(err, IoError::Truncated { .. }), "{err}");
        let err = read("OFF\n99999999999 1 0\n").unwrap_err();
        assert!(matches!(err, IoError::TooLarge { .. }), "{err}");
    }
}
