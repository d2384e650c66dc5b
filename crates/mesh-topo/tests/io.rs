//! Mesh files: lossless round trips in every format and encoding, and one test per error
//! kind with its line number (or byte offset). The real meshes are in `real_data.rs`.

use std::path::PathBuf;

use mesh_topo::io::{self, Format, IoError, Location, PlyEncoding, WriteOptions};
use mesh_topo::testing::arb_mesh;
use mesh_topo::{DVec3, HalfedgeMesh, MeshError, PolygonSoup};
use proptest::prelude::*;

mod support;
use support::{TARGETS, round_trip, write};

/// Any f64 that a file can hold (finite), from every part of the range.
fn arb_coordinate() -> impl Strategy<Value = f64> {
    prop_oneof![
        any::<f64>().prop_filter("finite", |x| x.is_finite()),
        -1e3..1e3f64,
        Just(0.0),
        Just(-0.0),
        Just(f64::MIN_POSITIVE),
        Just(5e-324),
        Just(f64::MAX),
    ]
}

/// Soups that need not be meshes: any face sizes (0 included), repeated vertices,
/// unreferenced vertices, extreme coordinates. Files must carry them unchanged.
fn arb_soup() -> impl Strategy<Value = PolygonSoup> {
    (1usize..40).prop_flat_map(|n| {
        (
            prop::collection::vec((arb_coordinate(), arb_coordinate(), arb_coordinate()), n),
            prop::collection::vec(prop::collection::vec(0..n as u32, 0..9), 0..20),
        )
            .prop_map(|(points, faces)| {
                PolygonSoup::from_faces(points.into_iter().map(|(x, y, z)| DVec3::new(x, y, z)).collect(), faces)
            })
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn meshes_round_trip_in_every_format(soup in arb_mesh()) {
        round_trip(&soup);
        // And the mesh built from what was read is the mesh built from the original.
        let bytes = write(&soup, Format::Ply, PlyEncoding::BinaryLittleEndian);
        let (back, _) = io::read_bytes(&bytes, Format::Ply).unwrap();
        prop_assert_eq!(HalfedgeMesh::from_soup(&back).unwrap(), HalfedgeMesh::from_soup(&soup).unwrap());
    }

    #[test]
    fn arbitrary_soups_round_trip_in_every_format(soup in arb_soup()) {
        round_trip(&soup);
    }

    #[test]
    fn truncated_files_are_errors_not_panics(soup in arb_mesh(), cut in 0.0..1.0f64) {
        for (format, encoding) in TARGETS {
            let bytes = write(&soup, format, encoding);
            let cut = ((bytes.len() as f64 * cut) as usize).min(bytes.len() - 1);
            // OBJ has no counts: a cut file may be a valid smaller soup.
            // OFF and ascii PLY know how many values to expect, but a cut inside the
            // last line may leave a valid file with a shorter last number. Binary PLY
            // always knows.
            match io::read_bytes(&bytes[..cut], format) {
                Ok(_) => {
                    let lines_cut = bytes[cut..].iter().filter(|&&b| b == b'\n').count();
                    prop_assert!(format == Format::Obj || (encoding == PlyEncoding::Ascii && lines_cut <= 1),
                        "{} {:?} cut at {} of {} reads", format, encoding, cut, bytes.len());
                }
                Err(error) => prop_assert!(error.location().is_some(), "{}", error),
            }
        }
    }
}

#[test]
fn big_faces_and_empty_soups_round_trip() {
    // A 300-gon needs PLY's `uint` list count.
    let n = 300;
    let points: Vec<DVec3> = (0..n).map(|i| DVec3::new((i as f64).cos(), (i as f64).sin(), 0.0)).collect();
    let face: Vec<u32> = (0..n as u32).collect();
    round_trip(&PolygonSoup::from_faces(points, [face]));
    round_trip(&PolygonSoup::default());
    round_trip(&PolygonSoup::from_faces(vec![DVec3::ONE], Vec::<Vec<u32>>::new()));
}

#[test]
fn written_text_is_shortest_form() {
    let soup = PolygonSoup::from_faces(
        vec![DVec3::new(0.1, -2.0, 1e-7), DVec3::new(1.0 / 3.0, 0.0, -0.0), DVec3::new(1e300, 5.5, 100.0)],
        [[0u32, 1, 2]],
    );
    let off = String::from_utf8(write(&soup, Format::Off, PlyEncoding::Ascii)).unwrap();
    assert_eq!(off, "OFF\n3 1 0\n0.1 -2 1e-7\n0.3333333333333333 0 -0\n1e300 5.5 100\n3 0 1 2\n");
}

// ---------------------------------------------------------------------------------------
// One test per error kind, with the location it must report.

fn error(format: Format, text: &str) -> IoError {
    io::read_bytes(text.as_bytes(), format).unwrap_err()
}

#[test]
fn error_truncated() {
    let e = error(Format::Off, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n");
    assert!(matches!(e, IoError::Truncated { at: Location::Line(5), .. }), "{e}");
    assert_eq!(e.to_string(), "line 5: file ends early: expected 1 faces, found 0");
    let e = error(
        Format::Ply,
        "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n1 1\n",
    );
    assert!(matches!(e, IoError::Truncated { at: Location::Line(9), .. }), "{e}");
}

#[test]
fn error_count_mismatch() {
    let e = error(Format::Off, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n");
    assert!(matches!(e, IoError::CountMismatch { at: Location::Line(6), expected: 4, found: 3, .. }), "{e}");
    let e = error(Format::Obj, "v 1 2 3\nv 1 2\n");
    assert!(matches!(e, IoError::CountMismatch { at: Location::Line(2), expected: 3, found: 2, .. }), "{e}");
}

#[test]
fn error_trailing_data() {
    let e = error(Format::Off, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 2 1 0\n");
    assert!(matches!(e, IoError::TrailingData { at: Location::Line(7), .. }), "{e}");
}

#[test]
fn error_non_numeric_token() {
    let e = error(Format::Obj, "v 0 0 0\nv 1 0 0\nv 1,5 0 0\n");
    assert!(matches!(&e, IoError::InvalidNumber { at: Location::Line(3), token, .. } if token == "1,5"), "{e}");
    assert_eq!(e.to_string(), "line 3: `1,5` is not a number");
    let e = error(Format::Off, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 one 2\n");
    assert!(matches!(e, IoError::InvalidNumber { at: Location::Line(6), .. }), "{e}");
}

#[test]
fn error_index_out_of_range() {
    let e = error(Format::Obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\n# face\nf 1 2 4\n");
    assert!(matches!(e, IoError::IndexOutOfRange { at: Location::Line(5), index: 4, vertex_count: 3 }), "{e}");
    assert_eq!(e.to_string(), "line 5: vertex index 4 is out of range (the file has 3 vertices)");
    let e = error(Format::Obj, "v 0 0 0\nf 0 1 1\n");
    assert!(matches!(e, IoError::IndexOutOfRange { at: Location::Line(2), index: 0, .. }), "{e}");
    let e = error(Format::Off, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n");
    assert!(matches!(e, IoError::IndexOutOfRange { at: Location::Line(6), index: 3, .. }), "{e}");
}

#[test]
fn error_index_out_of_range_binary_ply_has_byte_offset() {
    let soup = PolygonSoup::from_faces(vec![DVec3::ZERO, DVec3::X, DVec3::Y], [[0u32, 1, 2]]);
    let mut bytes = write(&soup, Format::Ply, PlyEncoding::BinaryLittleEndian);
    // Last index (u32, little-endian) -> 7.
    let at = bytes.len() - 4;
    bytes[at..].copy_from_slice(&7u32.to_le_bytes());
    let e = io::read_bytes(&bytes, Format::Ply).unwrap_err();
    assert!(matches!(e, IoError::IndexOutOfRange { at: Location::Byte(b), index: 7, .. } if b == at), "{e}");
    assert!(e.to_string().starts_with(&format!("byte {at}: ")), "{e}");
}

#[test]
fn error_non_finite_coordinates() {
    for (format, text, line) in [
        (Format::Obj, "v 0 0 0\nv nan 0 0\n", 2),
        (Format::Obj, "v 0 0 1e400\n", 1),
        (Format::Off, "OFF\n1 0 0\n0 -inf 0\n", 3),
    ] {
        let e = error(format, text);
        assert!(matches!(e, IoError::NonFiniteCoordinate { at: Location::Line(l), .. } if l == line), "{e}");
    }
    let soup = PolygonSoup::from_faces(vec![DVec3::ZERO, DVec3::X, DVec3::Y], [[0u32, 1, 2]]);
    let mut bytes = write(&soup, Format::Ply, PlyEncoding::BinaryBigEndian);
    let header_len = bytes.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    // Vertex 1, y coordinate.
    let at = header_len + 4 * 8;
    bytes[at..at + 8].copy_from_slice(&f64::NAN.to_be_bytes());
    let e = io::read_bytes(&bytes, Format::Ply).unwrap_err();
    assert!(matches!(e, IoError::NonFiniteCoordinate { vertex: 1, at: Location::Byte(_), .. }), "{e}");
}

#[test]
fn error_unsupported_format() {
    let e = io::read_soup("mesh.stl").unwrap_err();
    assert!(matches!(e, IoError::UnknownExtension { .. }), "{e}");
    assert_eq!(e.to_string(), "mesh.stl: unsupported format (the extension must be .obj, .off or .ply)");
    assert!(matches!(error(Format::Off, "OFF BINARY\n1 0 0\n"), IoError::Unsupported { at: Location::Line(1), .. }));
    assert!(matches!(
        error(Format::Ply, "ply\nformat binary_middle_endian 1.0\nend_header\n"),
        IoError::Unsupported { at: Location::Line(2), .. }
    ));
}

#[test]
fn error_invalid_header() {
    let e = error(Format::Off, "# no keyword\n3 1 0\n");
    assert!(matches!(e, IoError::InvalidHeader { at: Location::Line(2), .. }), "{e}");
    let e = error(Format::Ply, "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n0\n");
    assert!(matches!(e, IoError::InvalidHeader { at: Location::Line(3), .. }), "{e}");
}

#[test]
fn error_missing_file() {
    let e = io::read_soup("/nonexistent/mesh.obj").unwrap_err();
    assert!(matches!(e, IoError::File { .. }), "{e}");
    assert!(e.to_string().starts_with("/nonexistent/mesh.obj: "), "{e}");
}

#[test]
fn error_stream_when_the_output_fails() {
    /// A writer whose device is always full.
    struct Full;
    impl std::io::Write for Full {
        fn write(&mut self, _: &[u8]) -> std::io::Result<usize> {
            Err(std::io::Error::new(std::io::ErrorKind::StorageFull, "device full"))
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Err(std::io::Error::new(std::io::ErrorKind::StorageFull, "device full"))
        }
    }
    let soup = PolygonSoup::from_faces(vec![DVec3::ZERO, DVec3::X, DVec3::Y], [[0u32, 1, 2]]);
    for (format, ply_encoding) in TARGETS {
        let e = io::write_to(Full, &soup, format, &WriteOptions { ply_encoding }).unwrap_err();
        assert!(matches!(&e, IoError::Stream(source) if source.kind() == std::io::ErrorKind::StorageFull), "{e}");
    }
}

#[test]
fn error_invalid_soup_is_refused_before_writing() {
    let out_of_range = PolygonSoup::from_faces(vec![DVec3::ZERO, DVec3::X, DVec3::Y], [[0u32, 1, 7]]);
    let mut bad_offsets = PolygonSoup::from_faces(vec![DVec3::ZERO, DVec3::X, DVec3::Y], [[0u32, 1, 2]]);
    bad_offsets.offsets[1] = 2;
    for (soup, expected) in [(&out_of_range, "face 0 uses vertex 7"), (&bad_offsets, "last face offset is 2")] {
        for (format, ply_encoding) in TARGETS {
            let mut bytes = Vec::new();
            let e = io::write_to(&mut bytes, soup, format, &WriteOptions { ply_encoding }).unwrap_err();
            assert!(matches!(&e, IoError::InvalidSoup(reason) if reason.contains(expected)), "{e}");
            assert!(bytes.is_empty(), "{format}: wrote {} bytes before failing", bytes.len());
        }
    }
}

#[test]
fn non_manifold_files_read_as_soups_and_fail_as_meshes() {
    let text = "OFF\n5 3 0\n0 0 0\n1 0 0\n0 1 0\n0 -1 0\n0 0 1\n3 0 1 2\n3 1 0 3\n3 0 1 4\n";
    let (soup, _) = io::read_bytes(text.as_bytes(), Format::Off).unwrap();
    assert_eq!(soup.face_count(), 3);
    let dir = tempfile_dir();
    let path = dir.join("fan.off");
    std::fs::write(&path, text).unwrap();
    let e = io::read_mesh(&path).unwrap_err();
    assert!(matches!(e, IoError::Mesh(MeshError::NonManifoldEdge { from: 0, to: 1, .. })), "{e}");
    std::fs::remove_dir_all(dir).unwrap();
}

fn tempfile_dir() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mesh-topo-io-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}
