//! Helpers shared by the I/O tests: writing a soup to memory and checking that every
//! format and encoding gives it back bit for bit.

// Each test file uses a part of these.
#![allow(dead_code)]

use mesh_topo::PolygonSoup;
use mesh_topo::io::{self, Format, PlyEncoding, WriteOptions};

/// Every (format, PLY encoding) pair a soup can be written in.
pub const TARGETS: [(Format, PlyEncoding); 5] = [
    (Format::Obj, PlyEncoding::Ascii),
    (Format::Off, PlyEncoding::Ascii),
    (Format::Ply, PlyEncoding::Ascii),
    (Format::Ply, PlyEncoding::BinaryLittleEndian),
    (Format::Ply, PlyEncoding::BinaryBigEndian),
];

pub fn write(soup: &PolygonSoup, format: Format, ply_encoding: PlyEncoding) -> Vec<u8> {
    let mut bytes = Vec::new();
    io::write_to(&mut bytes, soup, format, &WriteOptions { ply_encoding }).unwrap();
    bytes
}

/// Equal soups, positions compared bit for bit (so `-0.0` and `0.0` differ).
pub fn assert_identical(back: &PolygonSoup, soup: &PolygonSoup, context: &str) {
    assert_eq!(back.vertex_count(), soup.vertex_count(), "{context}");
    for (i, (a, b)) in back.positions.iter().zip(&soup.positions).enumerate() {
        assert_eq!(a.to_array().map(f64::to_bits), b.to_array().map(f64::to_bits), "{context}: vertex {i}");
    }
    assert_eq!(back.face_count(), soup.face_count(), "{context}");
    assert!(back.faces().eq(soup.faces()), "{context}: faces differ");
}

pub fn round_trip(soup: &PolygonSoup) {
    for (format, encoding) in TARGETS {
        let bytes = write(soup, format, encoding);
        let (back, report) = io::read_bytes(&bytes, format).unwrap();
        let context = format!("{format} {encoding:?}");
        assert_identical(&back, soup, &context);
        assert!(report.is_lossless(), "{context}: {report}");
        assert_eq!(report.format, format);
    }
}
