//! Wavefront OBJ reader.

use super::report::{Counter, DroppedLog};
use super::text::{
    Lines, check_finite, coordinate, invalid_number, parse_i64, show_token, strip_comment, tokens, trim_end,
};
use super::{Format, IoError, Location, ReadReport};
use crate::ids::MAX_ELEMENTS;
use crate::soup::PolygonSoup;
use glam::DVec3;
use rayon::prelude::*;

/// Counters for the statements and values an OBJ file may hold that a soup does not.
#[derive(Default)]
struct ObjDropped {
    weights: Counter,
    vertex_colours: Counter,
    extra_vertex_values: Counter,
    texcoords: Counter,
    normals: Counter,
    parameter_vertices: Counter,
    corner_texcoords: Counter,
    corner_normals: Counter,
    groups: Counter,
    objects: Counter,
    smoothing: Counter,
    materials: Counter,
    material_libraries: Counter,
    lines: Counter,
    points: Counter,
    /// Any other statement, by keyword.
    other: DroppedLog,
}

impl ObjDropped {
    /// What each counter of [`counters_mut`](Self::counters_mut) counts, in its order.
    const COUNTED: [&'static str; 15] = [
        "vertex weights (4th value of `v`)",
        "vertex colours (values 4-6 of `v`)",
        "`v` lines with extra values",
        "texture coordinates (`vt`)",
        "normals (`vn`)",
        "parameter-space vertices (`vp`)",
        "face corners' texture-coordinate references (`f v/vt`)",
        "face corners' normal references (`f v//vn`)",
        "group statements (`g`)",
        "object names (`o`)",
        "smoothing groups (`s`)",
        "material assignments (`usemtl`)",
        "material libraries (`mtllib`)",
        "polyline elements (`l`)",
        "point elements (`p`)",
    ];

    fn counters_mut(&mut self) -> [&mut Counter; 15] {
        [
            &mut self.weights,
            &mut self.vertex_colours,
            &mut self.extra_vertex_values,
            &mut self.texcoords,
            &mut self.normals,
            &mut self.parameter_vertices,
            &mut self.corner_texcoords,
            &mut self.corner_normals,
            &mut self.groups,
            &mut self.objects,
            &mut self.smoothing,
            &mut self.materials,
            &mut self.material_libraries,
            &mut self.lines,
            &mut self.points,
        ]
    }

    /// Adds the counts of `later`, read from lines after all of this one's.
    fn merge(&mut self, mut later: ObjDropped) {
        for (mine, theirs) in self.counters_mut().into_iter().zip(later.counters_mut()) {
            mine.merge(*theirs);
        }
        self.other.merge(later.other);
    }

    fn into_report(mut self) -> ReadReport {
        let mut log = std::mem::take(&mut self.other);
        for (counter, what) in self.counters_mut().into_iter().zip(Self::COUNTED) {
            counter.flush(&mut log, what);
        }
        log.into_report(Format::Obj, None)
    }
}

/// Reads an OBJ file from memory: `v` lines become positions, `f` lines faces (any
/// number of corners, corners as `v`, `v/vt`, `v//vn` or `v/vt/vn`, 1-based or negative
/// indices); everything else is counted in the report.
///
/// Files of a megabyte or more are read in pieces, cut at line ends, on the threads of
/// the current `rayon` pool (negative indices resolved once every piece's vertices are
/// counted); the result, and the error of a bad file, are those of one pass (a file of
/// a million triangles, 53 MB: 122 ms on one thread, 70 ms on two).
///
/// ```
/// let obj = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n";
/// let (soup, report) = mesh_topo::io::read_obj(obj)?;
/// assert_eq!(soup.face(0), &[0, 1, 2]);
/// assert!(report.is_lossless());
/// # Ok::<(), mesh_topo::io::IoError>(())
/// ```
///
/// # Errors
/// With the line number: a non-numeric coordinate or index
/// ([`IoError::InvalidNumber`]), a `v` line with fewer than 3 coordinates
/// ([`IoError::CountMismatch`]), a NaN or infinite coordinate, an index that is 0 or
/// points outside the vertices ([`IoError::IndexOutOfRange`]), more than `u32` indices
/// can address ([`IoError::TooLarge`]).
pub fn read_obj(bytes: &[u8]) -> Result<(PolygonSoup, ReadReport), IoError> {
    read_obj_split(bytes, PARALLEL_MIN_BYTES)
}

/// Files smaller than this are read on the calling thread.
const PARALLEL_MIN_BYTES: usize = 1 << 20;

/// Pieces of a large file per thread (see [`read_in_pieces`]).
const PIECES_PER_THREAD: usize = 8;

/// [`read_obj`], in parallel pieces when the file takes `parallel_min_bytes` or more and
/// the current `rayon` pool has several threads.
fn read_obj_split(bytes: &[u8], parallel_min_bytes: usize) -> Result<(PolygonSoup, ReadReport), IoError> {
    // A UTF-8 byte-order mark, as some Windows tools write, is not content.
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    if bytes.len() >= parallel_min_bytes
        && rayon::current_num_threads() > 1
        && let Some(read) = read_in_pieces(bytes)
    {
        return Ok(read);
    }
    let Statements { soup, dropped, forward_references, .. } = read_statements(Lines::new(bytes), Resolve::Now)?;
    let vertex_count = soup.positions.len();
    if let Some(&(line, index)) = forward_references.iter().find(|&&(_, index)| index as usize > vertex_count) {
        return Err(IoError::IndexOutOfRange { at: Location::Line(line), index, vertex_count });
    }
    Ok((soup, dropped.into_report()))
}

/// How [`read_statements`] resolves negative indices (relative to the vertices defined
/// before the face).
#[derive(Clone, Copy, PartialEq, Eq)]
enum Resolve {
    /// At once: the lines read are the file from its start.
    Now,
    /// Later: the lines are a piece of the file whose earlier vertices are not counted
    /// yet; each negative index is kept in [`Statements::relative`].
    Later,
}

/// What [`read_statements`] reads from a run of lines.
struct Statements {
    /// Positions, and faces whose indices are resolved (or placeholders, see `relative`).
    soup: PolygonSoup,
    dropped: ObjDropped,
    /// With [`Resolve::Now`], positive indices beyond the vertices defined so far, with
    /// their lines: valid if the whole file defines that many.
    forward_references: Vec<(usize, i64)>,
    /// With [`Resolve::Later`], the largest positive index (0 if none): valid if the
    /// whole file defines that many vertices.
    largest_index: i64,
    /// With [`Resolve::Later`], each negative index: its corner, the vertices these lines
    /// defined before it, and the index.
    relative: Vec<(usize, usize, i64)>,
    /// A statement continued on the next line was met (a piece may cut it).
    continued: bool,
}

/// Reads OBJ statements from `lines` (see [`read_obj`]).
fn read_statements(mut lines: Lines<'_>, resolve: Resolve) -> Result<Statements, IoError> {
    let mut soup = PolygonSoup::with_capacity(0, 0, 0);
    let mut dropped = ObjDropped::default();
    let mut forward_references: Vec<(usize, i64)> = Vec::new();
    let mut relative = Vec::new();
    let mut largest_index = 0;
    let mut continued = false;
    let mut joined: Vec<u8> = Vec::new();
    while let Some((line, raw)) = lines.next() {
        let mut content = strip_comment(raw);
        if trim_end(content).ends_with(b"\\") {
            continued = true;
            // A statement continued on the next line(s); errors cite its first line.
            joined.clear();
            let mut part = content;
            loop {
                let trimmed = trim_end(part);
                match trimmed.strip_suffix(b"\\") {
                    Some(head) => {
                        joined.extend_from_slice(head);
                        joined.push(b' ');
                    }
                    None => {
                        joined.extend_from_slice(part);
                        break;
                    }
                }
                match lines.next() {
                    Some((_, more)) => part = strip_comment(more),
                    None => break,
                }
            }
            content = &joined;
        }
        let mut words = tokens(content);
        let Some(keyword) = words.next() else { continue };
        match keyword {
            b"v" => {
                let mut p = [0.0; 3];
                let mut count = 0;
                for token in words {
                    let value = coordinate(line, token)?;
                    if count < 3 {
                        p[count] = value;
                    }
                    count += 1;
                }
                if count < 3 {
                    return Err(IoError::CountMismatch {
                        at: Location::Line(line),
                        what: "coordinates on a `v` line",
                        expected: 3,
                        found: count,
                    });
                }
                match count {
                    3 => {}
                    4 => dropped.weights.hit(line),
                    6 | 7 => dropped.vertex_colours.hit(line),
                    _ => dropped.extra_vertex_values.hit(line),
                }
                let vertex = soup.positions.len();
                check_finite(Location::Line(line), vertex, p)?;
                if vertex >= MAX_ELEMENTS {
                    return Err(IoError::TooLarge { at: Location::Line(line), what: "vertices", max: MAX_ELEMENTS });
                }
                soup.positions.push(p.into());
            }
            b"f" | b"fo" => {
                let defined = soup.positions.len();
                let mut texcoord_refs = false;
                let mut normal_refs = false;
                for corner in words {
                    let mut parts = corner.split(|&b| b == b'/');
                    let vertex = parts.next().unwrap_or_default();
                    let texcoord = parts.next();
                    let normal = parts.next();
                    if parts.next().is_some() {
                        return Err(invalid_number(line, corner, "a face corner (v, v/vt, v//vn or v/vt/vn)"));
                    }
                    let index = parse_i64(vertex).ok_or_else(|| invalid_number(line, corner, "a vertex index"))?;
                    for (reference, seen) in [(texcoord, &mut texcoord_refs), (normal, &mut normal_refs)] {
                        if let Some(reference) = reference.filter(|r| !r.is_empty()) {
                            parse_i64(reference).ok_or_else(|| invalid_number(line, corner, "a face corner index"))?;
                            *seen = true;
                        }
                    }
                    let resolved = match resolve {
                        Resolve::Now => resolve_index(index, defined, line, &mut forward_references)?,
                        // (Any mismatch sends the file to the one pass, which names it.)
                        Resolve::Later if index > 0 && index as u64 <= MAX_ELEMENTS as u64 => {
                            largest_index = largest_index.max(index);
                            (index - 1) as u32
                        }
                        Resolve::Later if index < 0 => {
                            relative.push((soup.indices.len(), defined, index));
                            0
                        }
                        Resolve::Later => return Err(invalid_number(line, corner, "a vertex index in range")),
                    };
                    soup.indices.push(resolved);
                }
                if texcoord_refs {
                    dropped.corner_texcoords.hit(line);
                }
                if normal_refs {
                    dropped.corner_normals.hit(line);
                }
                if soup.indices.len() > u32::MAX as usize {
                    return Err(IoError::TooLarge {
                        at: Location::Line(line),
                        what: "face corners",
                        max: u32::MAX as usize,
                    });
                }
                if soup.offsets.len() > MAX_ELEMENTS {
                    return Err(IoError::TooLarge { at: Location::Line(line), what: "faces", max: MAX_ELEMENTS });
                }
                soup.offsets.push(soup.indices.len() as u32);
            }
            b"vt" => dropped.texcoords.hit(line),
            b"vn" => dropped.normals.hit(line),
            b"vp" => dropped.parameter_vertices.hit(line),
            b"g" => dropped.groups.hit(line),
            b"o" => dropped.objects.hit(line),
            b"s" => dropped.smoothing.hit(line),
            b"usemtl" => dropped.materials.hit(line),
            b"mtllib" => dropped.material_libraries.hit(line),
            b"l" => dropped.lines.hit(line),
            b"p" => dropped.points.hit(line),
            other => dropped.other.add(&format!("`{}` statements", show_token(other)), 1, Location::Line(line)),
        }
    }
    Ok(Statements { soup, dropped, forward_references, largest_index, relative, continued })
}

/// [`read_statements`] of `bytes` in [`PIECES_PER_THREAD`] pieces per thread, cut at line
/// ends, each piece numbering its lines from the line ends before it; the pieces joined
/// (copied side by side on the pool's threads), their negative indices resolved from the
/// vertices before them. `None` when a piece finds an error or
/// a continued statement, or the joined file has an index out of range or is too large
/// (the caller then reads it in one pass, which names the first problem).
fn read_in_pieces(bytes: &[u8]) -> Option<(PolygonSoup, ReadReport)> {
    // Several pieces per thread, taken as threads come free: vertex lines (floats) cost
    // more per byte than face lines, and files list their vertices first.
    let count = PIECES_PER_THREAD * rayon::current_num_threads();
    let mut cuts = vec![0];
    for k in 1..count {
        let target = (bytes.len() * k / count).max(*cuts.last()?);
        let cut = memchr::memchr(b'\n', &bytes[target..]).map_or(bytes.len(), |i| target + i + 1);
        cuts.push(cut);
    }
    cuts.push(bytes.len());
    let pieces: Vec<&[u8]> = cuts.windows(2).map(|w| &bytes[w[0]..w[1]]).collect();
    let line_ends: Vec<usize> = pieces.par_iter().map(|piece| memchr::memchr_iter(b'\n', piece).count()).collect();
    let mut lines_before = Vec::with_capacity(pieces.len());
    let mut line = 0;
    for &ends in &line_ends {
        lines_before.push(line);
        line += ends;
    }
    let read: Vec<Statements> = pieces
        .par_iter()
        .zip(lines_before)
        .map(|(piece, before)| read_statements(Lines::starting_after(piece, before), Resolve::Later).ok())
        .collect::<Option<_>>()?;
    if read.iter().any(|piece| piece.continued) {
        return None;
    }
    // Where each piece's vertices and corners start in the joined arrays.
    let mut starts = Vec::with_capacity(read.len());
    let (mut vertex_count, mut corners, mut faces) = (0, 0, 0);
    for piece in &read {
        starts.push((vertex_count, corners));
        vertex_count += piece.soup.positions.len();
        corners += piece.soup.indices.len();
        faces += piece.soup.face_count();
    }
    let beyond = read.iter().any(|piece| piece.largest_index as u64 > vertex_count as u64);
    if beyond || vertex_count > MAX_ELEMENTS || corners > u32::MAX as usize || faces > MAX_ELEMENTS {
        return None;
    }
    // Each piece copies into its own part of the joined arrays (zeros first: a large
    // `u32` array of zeros is fresh memory, mapped as it is written).
    let mut soup = PolygonSoup {
        positions: vec![DVec3::ZERO; vertex_count],
        indices: vec![0; corners],
        offsets: vec![0; faces + 1],
    };
    let mut parts = Vec::with_capacity(read.len());
    let (mut positions, mut indices, mut offsets) =
        (&mut soup.positions[..], &mut soup.indices[..], &mut soup.offsets[1..]);
    for piece in &read {
        let (p, rest_p) = positions.split_at_mut(piece.soup.positions.len());
        let (i, rest_i) = indices.split_at_mut(piece.soup.indices.len());
        let (o, rest_o) = offsets.split_at_mut(piece.soup.face_count());
        parts.push((p, i, o));
        (positions, indices, offsets) = (rest_p, rest_i, rest_o);
    }
    parts.into_par_iter().zip(&read).zip(starts).try_for_each(
        |(((positions, indices, offsets), piece), (vertex_base, corner_base))| {
            positions.copy_from_slice(&piece.soup.positions);
            indices.copy_from_slice(&piece.soup.indices);
            for (joined, &offset) in offsets.iter_mut().zip(&piece.soup.offsets[1..]) {
                *joined = corner_base as u32 + offset;
            }
            for &(corner, defined, index) in &piece.relative {
                indices[corner] = u32::try_from((vertex_base + defined) as i64 + index).ok()?;
            }
            Some(())
        },
    )?;
    let mut dropped = ObjDropped::default();
    for piece in read {
        dropped.merge(piece.dropped);
    }
    Some((soup, dropped.into_report()))
}

/// The 0-based vertex of an OBJ index (1-based, or negative = relative to the vertices
/// defined so far).
#[inline]
fn resolve_index(index: i64, defined: usize, line: usize, forward: &mut Vec<(usize, i64)>) -> Result<u32, IoError> {
    let out_of_range = || IoError::IndexOutOfRange { at: Location::Line(line), index, vertex_count: defined };
    if index > 0 {
        if index as u64 > MAX_ELEMENTS as u64 {
            return Err(out_of_range());
        }
        if index as usize > defined {
            forward.push((line, index));
        }
        Ok((index - 1) as u32)
    } else if index < 0 {
        let resolved = defined as i64 + index;
        if resolved < 0 {
            return Err(out_of_range());
        }
        Ok(resolved as u32)
    } else {
        Err(out_of_range())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(text: &str) -> Result<(PolygonSoup, ReadReport), IoError> {
        read_obj(text.as_bytes())
    }

    #[test]
    fn all_corner_forms_and_polygons() {
        let (soup, report) = read(
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n\
             f 1 2 3\nf 1/1 3/1 4/1\nf 1//1 2//1 3//1 4//1\nf 4/1/1 3/1/1 2/1/1 1/1/1\n",
        )
        .unwrap();
        assert_eq!(soup.face_count(), 4);
        assert_eq!(soup.face(1), &[0, 2, 3]);
        assert_eq!(soup.face(3), &[3, 2, 1, 0]);
        let whats: Vec<(&str, usize)> = report.dropped.iter().map(|d| (d.what.as_str(), d.count)).collect();
        assert_eq!(
            whats,
            vec![
                ("texture coordinates (`vt`)", 1),
                ("normals (`vn`)", 1),
                ("face corners' texture-coordinate references (`f v/vt`)", 2),
                ("face corners' normal references (`f v//vn`)", 2),
            ]
        );
        assert_eq!(report.dropped[2].first, Location::Line(8));
    }

    #[test]
    fn negative_indices_are_relative_to_vertices_so_far() {
        let (soup, _) = read("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 5 5 5\nf -1 -2 -3\n").unwrap();
        assert_eq!(soup.face(0), &[0, 1, 2]);
        assert_eq!(soup.face(1), &[3, 2, 1]);
    }

    #[test]
    fn forward_references_are_allowed_and_checked_at_the_end() {
        let (soup, _) = read("f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n").unwrap();
        assert_eq!(soup.face(0), &[0, 1, 2]);
        let err = read("v 0 0 0\nf 1 2 3\nf 1 2 9\nv 1 0 0\nv 0 1 0\n").unwrap_err();
        assert!(matches!(err, IoError::IndexOutOfRange { at: Location::Line(3), index: 9, vertex_count: 3 }), "{err}");
    }

    #[test]
    fn crlf_comments_and_continuations() {
        let (soup, report) =
            read("# header\r\nv 0 0 0 # origin\r\nv 1 0 0\r\nv 0 \\\r\n 1 0\r\nf 1 2 \\\n3\r\n").unwrap();
        assert_eq!(soup.positions[2].y, 1.0);
        assert_eq!(soup.face(0), &[0, 1, 2]);
        assert!(report.is_lossless());
    }

    #[test]
    fn other_statements_are_reported_not_lost() {
        let (_, report) =
            read("mtllib a.mtl\no thing\ng part\nusemtl red\ns 1\nv 0 0 0 1\nv 0 0 0 1 0 0\nl 1 2\ncstype bezier\n")
                .unwrap();
        let whats: Vec<&str> = report.dropped.iter().map(|d| d.what.as_str()).collect();
        assert_eq!(
            whats,
            vec![
                "material libraries (`mtllib`)",
                "object names (`o`)",
                "group statements (`g`)",
                "material assignments (`usemtl`)",
                "smoothing groups (`s`)",
                "vertex weights (4th value of `v`)",
                "vertex colours (values 4-6 of `v`)",
                "polyline elements (`l`)",
                "`cstype` statements",
            ]
        );
    }

    #[test]
    fn errors_name_the_line() {
        let cases: [(&str, usize); 7] = [
            ("v 0 0 0\nv 1 x 0\n", 2),
            ("v 0 0\n", 1),
            ("v 0 0 0\nv 0 0 nan\n", 2),
            ("v 0 0 0\n\nf 0 1 1\n", 3),
            ("v 0 0 0\nf -2 1 1\n", 2),
            ("v 0 0 0\nf 1/2/3/4 1 1\n", 2),
            ("v 0 0 0\nf 1/a 1 1\n", 2),
        ];
        for (text, line) in cases {
            let err = read(text).unwrap_err();
            assert_eq!(err.location(), Some(Location::Line(line)), "{text:?}: {err}");
        }
        assert!(matches!(read("v 0 0 inf\n").unwrap_err(), IoError::NonFiniteCoordinate { vertex: 0, .. }));
    }

    #[test]
    fn byte_order_mark_is_skipped() {
        let (soup, report) = read_obj(b"\xEF\xBB\xBFv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
        assert_eq!(soup.vertex_count(), 3);
        assert!(report.is_lossless());
        let (soup, _) = crate::io::read_off(b"\xEF\xBB\xBFOFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n").unwrap();
        assert_eq!(soup.face_count(), 1);
    }

    #[test]
    fn degenerate_faces_are_kept_for_the_builder_to_report() {
        let (soup, _) = read("v 0 0 0\nv 1 0 0\nf 1 2\nf\n").unwrap();
        assert_eq!(soup.face_count(), 2);
        assert_eq!(soup.face(0), &[0, 1]);
        assert!(soup.face(1).is_empty());
    }

    /// An OBJ text of `soup`, vertices and faces interleaved as `noise` says (faces
    /// written once their vertices are, some with negative indices, some with `vt`/`vn`
    /// references), with comments, blank lines, groups, texture coordinates and unknown
    /// statements, then one kind of damage at `at`: 1 cut short, 2 a face with an index
    /// past the last vertex, 3 a vertex with a NaN, 4 a line continued, 5 a token that is
    /// not a number, 6 a negative index before the first vertex, 7 a face before its
    /// vertices (valid: a forward reference).
    fn obj_text(soup: &PolygonSoup, noise: &[u8], damage: u8, at: usize) -> String {
        let mut noise = noise.iter().cycle().copied();
        let mut lines = vec!["# made by a test".to_string(), "mtllib x.mtl".to_string()];
        let mut written = 0usize;
        let mut faces = soup.faces().peekable();
        let mut vertices = soup.positions.iter();
        loop {
            let roll = noise.next().unwrap_or(0);
            match roll % 16 {
                0 => lines.push("# a comment".into()),
                1 => lines.push(String::new()),
                2 => lines.push("g part".into()),
                3 => lines.push("vt 0.5 0.5".into()),
                4 => lines.push("frob 1 2".into()),
                _ => {}
            }
            let face_ready = faces.peek().is_some_and(|f| f.iter().all(|&v| (v as usize) < written));
            if face_ready && (roll % 3 == 0 || vertices.len() == 0) {
                let face = faces.next().unwrap();
                let words: Vec<String> = face
                    .iter()
                    .map(|&v| match roll % 5 {
                        0 => format!("{}", v as i64 - written as i64),
                        1 => format!("{}/1", v + 1),
                        2 => format!("{}//2", v + 1),
                        _ => format!("{}", v + 1),
                    })
                    .collect();
                lines.push(format!("f {}", words.join(" ")));
            } else if let Some(p) = vertices.next() {
                let extra = if roll % 7 == 0 { " 1" } else { "" };
                lines.push(format!("v {} {} {}{extra}", p.x, p.y, p.z));
                written += 1;
            } else if faces.peek().is_none() {
                break;
            } else {
                // A face of vertices no face list of a valid soup has: give up on it.
                faces.next();
            }
        }
        let k = at % lines.len();
        match damage {
            2 => lines.push(format!("f 1 2 {}", soup.vertex_count() + 5)),
            3 => lines[k] = "v nan 0 0".into(),
            4 => lines[k] = format!("{} \\", lines[k]),
            5 => lines[k] = format!("{} x", lines[k]),
            6 => lines.insert(k.min(2), "f -1 -2 -3".into()),
            7 => lines.insert(k.min(2), "f 1 2 3".into()),
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
            damage in 0u8..8,
            at in proptest::prelude::any::<usize>(),
        ) {
            let text = obj_text(&soup, &noise, damage, at);
            crate::io::test_support::pieces_read_as_one_pass(&text, read_obj_split)?;
            if damage == 0 {
                let (read, _) = read_obj_split(text.as_bytes(), usize::MAX).unwrap();
                proptest::prop_assert_eq!(read.face_count(), soup.face_count());
            }
        }
    }

    /// The pieces are really read apart (and the negative indices of a later piece
    /// resolved from the vertices of the earlier ones): a file of many lines, on two
    /// threads, gives the one-pass soup.
    #[test]
    fn negative_indices_of_later_pieces_count_the_earlier_vertices() {
        let mut text = String::new();
        for i in 0..2000 {
            text +=
                &format!("v {i} 0 0\nv {i} 1 0\nv {i} 0 1\nf -3 -2 -1\nf {} {} {}\n", 3 * i + 1, 3 * i + 2, 3 * i + 3);
        }
        let (one_pass, _) = read_obj_split(text.as_bytes(), usize::MAX).unwrap();
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        let (pieces, _) = pool.install(|| read_in_pieces(text.as_bytes())).expect("read in pieces");
        assert_eq!(pieces, one_pass);
        assert_eq!(pieces.face(3999), &[5997, 5998, 5999]);
        assert_eq!(pieces.face(3998), pieces.face(3999));
    }
}
