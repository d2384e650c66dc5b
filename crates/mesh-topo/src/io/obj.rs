//! Wavefront OBJ reader.

use super::report::{Counter, DroppedLog};
use super::text::{
    Lines, check_finite, coordinate, invalid_number, parse_i64, show_token, strip_comment, tokens, trim_end,
};
use super::{Format, IoError, Location, ReadReport};
use crate::ids::MAX_ELEMENTS;
use crate::soup::PolygonSoup;

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
    fn into_report(self) -> ReadReport {
        let mut log = self.other;
        for (counter, what) in [
            (self.weights, "vertex weights (4th value of `v`)"),
            (self.vertex_colours, "vertex colours (values 4-6 of `v`)"),
            (self.extra_vertex_values, "`v` lines with extra values"),
            (self.texcoords, "texture coordinates (`vt`)"),
            (self.normals, "normals (`vn`)"),
            (self.parameter_vertices, "parameter-space vertices (`vp`)"),
            (self.corner_texcoords, "face corners' texture-coordinate references (`f v/vt`)"),
            (self.corner_normals, "face corners' normal references (`f v//vn`)"),
            (self.groups, "group statements (`g`)"),
            (self.objects, "object names (`o`)"),
            (self.smoothing, "smoothing groups (`s`)"),
            (self.materials, "material assignments (`usemtl`)"),
            (self.material_libraries, "material libraries (`mtllib`)"),
            (self.lines, "polyline elements (`l`)"),
            (self.points, "point elements (`p`)"),
        ] {
            counter.flush(&mut log, what);
        }
        log.into_report(Format::Obj, None)
    }
}

/// Reads an OBJ file from memory: `v` lines become positions, `f` lines faces (any
/// number of corners, corners as `v`, `v/vt`, `v//vn` or `v/vt/vn`, 1-based or negative
/// indices); everything else is counted in the report.
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
    // A UTF-8 byte-order mark, as some Windows tools write, is not content.
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    let mut soup = PolygonSoup::with_capacity(0, 0, 0);
    let mut dropped = ObjDropped::default();
    // Positive indices beyond the vertices defined so far: checked at the end.
    let mut forward_references: Vec<(usize, i64)> = Vec::new();
    let mut lines = Lines::new(bytes);
    let mut joined: Vec<u8> = Vec::new();
    while let Some((line, raw)) = lines.next() {
        let mut content = strip_comment(raw);
        if trim_end(content).ends_with(b"\\") {
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
                    let resolved = resolve(index, defined, line, &mut forward_references)?;
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
    let vertex_count = soup.positions.len();
    if let Some(&(line, index)) = forward_references.iter().find(|&&(_, index)| index as usize > vertex_count) {
        return Err(IoError::IndexOutOfRange { at: Location::Line(line), index, vertex_count });
    }
    Ok((soup, dropped.into_report()))
}

/// The 0-based vertex of an OBJ index (1-based, or negative = relative to the vertices
/// defined so far).
#[inline]
fn resolve(index: i64, defined: usize, line: usize, forward: &mut Vec<(usize, i64)>) -> Result<u32, IoError> {
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
}
