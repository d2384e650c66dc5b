//! The checks shared by the reader targets.

use mesh_topo::io::{self, Format, PlyEncoding, WriteOptions};
use mesh_topo::{HalfedgeMesh, PolygonSoup};

const TARGETS: [(Format, PlyEncoding); 5] = [
    (Format::Obj, PlyEncoding::Ascii),
    (Format::Off, PlyEncoding::Ascii),
    (Format::Ply, PlyEncoding::Ascii),
    (Format::Ply, PlyEncoding::BinaryLittleEndian),
    (Format::Ply, PlyEncoding::BinaryBigEndian),
];

fn identical(a: &PolygonSoup, b: &PolygonSoup) -> bool {
    a.positions.len() == b.positions.len()
        && a.positions
            .iter()
            .zip(&b.positions)
            .all(|(p, q)| p.to_array().map(f64::to_bits) == q.to_array().map(f64::to_bits))
        && a.faces().eq(b.faces())
}

/// Reading never panics; errors carry a location (or are about the mesh); a soup that
/// reads is writable in every format and reads back identical; building it never panics
/// and, when it succeeds, gives a valid mesh.
pub fn check_reader(data: &[u8], format: Format) {
    let (soup, report) = match io::read_bytes(data, format) {
        Ok(read) => read,
        Err(error) => {
            assert!(error.location().is_some(), "content error without a location: {error}");
            let _ = error.to_string();
            return;
        }
    };
    let _ = report.to_string();
    if let Ok(mesh) = HalfedgeMesh::from_soup(&soup) {
        mesh.validate().expect("a built mesh is valid");
        let _ = mesh.topology_stats();
    }
    for (target, ply_encoding) in TARGETS {
        let mut bytes = Vec::new();
        io::write_to(&mut bytes, &soup, target, &WriteOptions { ply_encoding }).expect("a read soup is writable");
        let (back, back_report) = io::read_bytes(&bytes, target).expect("a written file reads back");
        assert!(identical(&back, &soup), "{target} {ply_encoding:?} round trip changed the soup");
        assert!(back_report.is_lossless(), "written file reports dropped data: {back_report}");
    }
}
