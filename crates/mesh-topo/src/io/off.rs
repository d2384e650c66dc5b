//! OFF (Object File Format) reader.

use super::report::{Counter, DroppedLog};
use super::text::{
    Lines, Tokens, check_finite, coordinate, cut_at_line_ends, invalid_number, parse_i64, show_token, strip_comment,
    tokens,
};
use super::{Format, IoError, Location, ReadReport};
use crate::ids::MAX_ELEMENTS;
use crate::soup::PolygonSoup;
use rayon::prelude::*;

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
/// Files of a megabyte or more are read in one piece per thread of the current `rayon`
/// pool, cut at line ends; the result, and the error of a bad file, are those of one
/// pass (on `bunny00.off` refined by Doo-Sabin twice, 905k vertices and 75 MB: 200 ms
/// on one thread, 115-126 ms on two).
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
pub fn read_off(bytes: &[u8]) -> Result<(PolygonSoup, ReadReport), IoError> {
    read_off_split(bytes, PARALLEL_MIN_BYTES)
}

/// Files whose vertex and face lines take fewer bytes than this are read on the calling
/// thread.
const PARALLEL_MIN_BYTES: usize = 1 << 20;

/// The next content line of `lines` (comments removed, blank lines skipped) and its tokens.
fn next_content<'a>(lines: &mut Lines<'a>) -> Option<(usize, Tokens<'a>)> {
    for (line, raw) in lines.by_ref() {
        let words = tokens(strip_comment(raw));
        if words.clone().next().is_some() {
            return Some((line, words));
        }
    }
    None
}

/// [`read_off`], whose vertex and face lines are read in parallel pieces when they take
/// `parallel_min_bytes` or more and the current `rayon` pool has several threads.
fn read_off_split<'a>(bytes: &'a [u8], parallel_min_bytes: usize) -> Result<(PolygonSoup, ReadReport), IoError> {
    // A UTF-8 byte-order mark, as some Windows tools write, is not content.
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    let mut lines = Lines::new(bytes);
    // The last line, for "file ends early" errors (counted only then).
    let end = || {
        let lines = memchr::memchr_iter(b'\n', bytes).count() + usize::from(!bytes.ends_with(b"\n"));
        Location::Line(lines.max(1))
    };

    let Some((header_line, mut header)) = next_content(&mut lines) else {
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
                next_content(&mut lines).ok_or_else(|| IoError::Truncated { at: end(), expected: what.to_string() })?;
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

    // The vertex and face lines: in parallel pieces when large, else (and whenever a
    // piece finds anything wrong, so that the error is the one met first) in one pass.
    let body = &bytes[lines.offset()..];
    let counts = BodyCounts { vertices: vertex_count, faces: face_count };
    let parallel = (body.len() >= parallel_min_bytes && rayon::current_num_threads() > 1)
        .then(|| read_body_in_pieces(body, lines.line(), counts))
        .flatten();
    let body = match parallel {
        Some(body) => body,
        None => read_body(lines, 0, counts, bytes.len())?,
    };
    if body.items < vertex_count + face_count {
        let expected = if body.items < vertex_count {
            format!("{vertex_count} vertices, found {}", body.items)
        } else {
            format!("{face_count} faces, found {}", body.items - vertex_count)
        };
        return Err(IoError::Truncated { at: end(), expected });
    }
    if let Some(line) = body.trailing_line {
        let what = if face_count > 0 { "face" } else { "vertex" };
        return Err(IoError::TrailingData { at: Location::Line(line), what });
    }
    let Body { soup, extra_vertex_values, face_colours, .. } = body;

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

/// The numbers of vertex and face lines announced by the header.
#[derive(Clone, Copy)]
struct BodyCounts {
    vertices: usize,
    faces: usize,
}

/// What the vertex and face lines of an OFF file (or a piece of them) hold.
struct Body {
    /// The vertices and faces read (face offsets from 0 at the piece's first face).
    soup: PolygonSoup,
    extra_vertex_values: Counter,
    face_colours: Counter,
    /// The number of content lines read as vertices or faces, counted from the file's
    /// first one: the piece's first plus those it read.
    items: usize,
    /// The first content line after the last face, if any.
    trailing_line: Option<usize>,
    /// Whether a blank or comment line came before the first content line, between two
    /// content lines, or after the last one up to the end of the piece.
    skipped_lines: bool,
}

/// Reads the vertex and face lines of `lines`, whose first content line is vertex or
/// face number `first_item` (vertices first, then faces), up to the end of `lines`, the
/// first error, or the first content line after the last face. `file_bytes` bounds what
/// is reserved (a vertex line takes at least 6 bytes, a face line at least 2).
fn read_body(mut lines: Lines<'_>, first_item: usize, counts: BodyCounts, file_bytes: usize) -> Result<Body, IoError> {
    let BodyCounts { vertices: vertex_count, faces: face_count } = counts;
    let (vertices_left, faces_left) = if first_item < vertex_count {
        (vertex_count - first_item, face_count)
    } else {
        (0, (vertex_count + face_count).saturating_sub(first_item))
    };
    let mut soup = PolygonSoup::with_capacity(
        vertices_left.min(file_bytes / 6),
        faces_left.min(file_bytes / 2),
        (3 * faces_left).min(file_bytes / 2),
    );
    let mut extra_vertex_values = Counter::default();
    let mut face_colours = Counter::default();
    let mut item = first_item;
    let mut trailing_line = None;
    let mut previous_line = lines.line();
    let mut skipped_lines = false;
    while let Some((line, mut words)) = next_content(&mut lines) {
        skipped_lines |= line != previous_line + 1;
        previous_line = line;
        if item < vertex_count {
            let vertex = item;
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
        } else if item < vertex_count + face_count {
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
                return Err(IoError::TooLarge {
                    at: Location::Line(line),
                    what: "face corners",
                    max: u32::MAX as usize,
                });
            }
            soup.offsets.push(soup.indices.len() as u32);
        } else {
            trailing_line = Some(line);
            break;
        }
        item += 1;
    }
    if trailing_line.is_none() {
        // The lines after the last content line of the piece, all blank or comments.
        skipped_lines |= lines.line() != previous_line;
    }
    Ok(Body { soup, extra_vertex_values, face_colours, items: item, trailing_line, skipped_lines })
}

/// [`read_body`] of `body` (the bytes after the header, whose first line is line
/// `lines_before + 1` of the file) in one piece per thread, cut at line ends: each piece
/// counts its lines and content lines first, so that every piece knows its first line
/// number and item. `None` when a piece finds an error or trailing data, or the file
/// ends early (the caller then reads it in one pass, which names the first problem), or
/// when the pieces together hold too many corners.
fn read_body_in_pieces(body: &[u8], lines_before: usize, counts: BodyCounts) -> Option<Body> {
    let pieces = cut_at_line_ends(body, rayon::current_num_threads());
    let file_bytes = body.len();
    // Each piece read from where the pieces before it end: their lines (their line ends,
    // as every piece but the last ends with one) and their content lines.
    let read_pieces = |sizes: &[(usize, usize)]| -> Vec<Result<Body, IoError>> {
        let mut starts = Vec::with_capacity(pieces.len());
        let (mut line, mut item) = (lines_before, 0);
        for &(piece_lines, piece_items) in sizes {
            starts.push((line, item));
            line += piece_lines;
            item += piece_items;
        }
        pieces
            .par_iter()
            .zip(starts)
            .map(|(piece, (line, item))| read_body(Lines::starting_after(piece, line), item, counts, file_bytes))
            .collect()
    };
    // First guess: every line is a content line (as in nearly every file). That holds
    // for the pieces before the last if none of them skipped a line, and then every
    // piece started where it should; otherwise the content lines are counted and the
    // pieces read again.
    let line_ends: Vec<(usize, usize)> = pieces
        .par_iter()
        .map(|piece| {
            let ends = memchr::memchr_iter(b'\n', piece).count();
            (ends, ends)
        })
        .collect();
    // The first piece that failed or skipped a line started where it should (no piece
    // before it skipped one): its error is real, and sends the file to the one pass,
    // which names it; a piece that skipped a line before the last moves the start of
    // the pieces after it.
    let guessed = read_pieces(&line_ends);
    let last = guessed.len() - 1;
    let first_doubt = guessed.iter().position(|body| body.as_ref().map_or(true, |body| body.skipped_lines));
    let bodies: Vec<Body> = if first_doubt.is_some_and(|k| k < last && guessed[k].is_ok()) {
        let sizes: Vec<(usize, usize)> = pieces
            .par_iter()
            .map(|piece| {
                let mut lines = Lines::new(piece);
                let content = std::iter::from_fn(|| next_content(&mut lines)).count();
                (lines.line(), content)
            })
            .collect();
        read_pieces(&sizes).into_iter().map(Result::ok).collect::<Option<_>>()?
    } else {
        guessed.into_iter().map(Result::ok).collect::<Option<_>>()?
    };
    let items = bodies.last()?.items;
    let corners: usize = bodies.iter().map(|b| b.soup.indices.len()).sum();
    if bodies.iter().any(|b| b.trailing_line.is_some())
        || items < counts.vertices + counts.faces
        || corners > u32::MAX as usize
    {
        return None;
    }
    // The first piece's arrays, which hold the most of the file, take the others'.
    let mut bodies = bodies.into_iter();
    let Body { mut soup, mut extra_vertex_values, mut face_colours, .. } = bodies.next()?;
    soup.positions.reserve_exact(counts.vertices - soup.positions.len());
    soup.indices.reserve_exact(corners - soup.indices.len());
    soup.offsets.reserve_exact(counts.faces + 1 - soup.offsets.len());
    for body in bodies {
        let base = soup.indices.len() as u32;
        soup.positions.extend_from_slice(&body.soup.positions);
        soup.indices.extend_from_slice(&body.soup.indices);
        soup.offsets.extend(body.soup.offsets[1..].iter().map(|&o| base + o));
        extra_vertex_values.merge(body.extra_vertex_values);
        face_colours.merge(body.face_colours);
    }
    Some(Body { soup, extra_vertex_values, face_colours, items, trailing_line: None, skipped_lines: false })
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

    /// An OFF text of `soup`, with comment and blank lines, extra values on vertex lines
    /// and colours on face lines where `noise` says, then one kind of damage at `at`:
    /// 1 cut short, 2 a line added after the last face, 3 a line replaced by a vertex with
    /// a NaN, 4 a line removed, 5 a token that is not a number.
    fn off_text(soup: &PolygonSoup, noise: &[u8], damage: u8, at: usize) -> String {
        let mut noise = noise.iter().cycle().copied();
        let mut lines = vec!["OFF # keyword".to_string(), format!("{} {} 0", soup.vertex_count(), soup.face_count())];
        let mut add = |line: String, lines: &mut Vec<String>| {
            match noise.next().unwrap_or(0) % 8 {
                0 => lines.push("# a comment".into()),
                1 => lines.push(String::new()),
                2 => lines.push(format!("{line} 0.5 1")),
                _ => {}
            }
            if !lines.last().is_some_and(|last| last.starts_with(&line)) {
                lines.push(line);
            }
            if noise.next().unwrap_or(0) % 8 == 3 {
                lines.push(" # a comment after".into());
            }
        };
        for p in &soup.positions {
            add(format!("{} {} {}", p.x, p.y, p.z), &mut lines);
        }
        for face in soup.faces() {
            let words: Vec<String> = face.iter().map(u32::to_string).collect();
            add(format!("{} {}", face.len(), words.join(" ")), &mut lines);
        }
        let k = 2 + at % (lines.len() - 1);
        match damage {
            2 => lines.push("3 0 1 2".into()),
            3 if k < lines.len() => lines[k] = "nan 0 0".into(),
            4 if k < lines.len() => drop(lines.remove(k)),
            5 if k < lines.len() => lines[k] = lines[k].replacen(' ', " x ", 1),
            _ => {}
        }
        let mut text = lines.join("\n") + "\n";
        if damage == 1 {
            text.truncate(at % text.len());
        }
        text
    }

    proptest::proptest! {
        /// Read in parallel pieces (forced on small files, on two, three and five threads), a
        /// file gives what one pass gives: the same soup and report, or the same error.
        #[test]
        fn pieces_read_as_one_pass(
            soup in crate::testing::arb_mesh(),
            noise in proptest::collection::vec(proptest::prelude::any::<u8>(), 1..16),
            damage in 0u8..6,
            at in proptest::prelude::any::<usize>(),
        ) {
            let text = off_text(&soup, &noise, damage, at);
            crate::io::test_support::pieces_read_as_one_pass(&text, read_off_split)?;
            if damage == 0 {
                proptest::prop_assert_eq!(read_off_split(text.as_bytes(), usize::MAX).unwrap().0.faces().count(), soup.face_count());
            }
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
