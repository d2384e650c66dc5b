//! Mesh files for the examples and benches, through `mesh_topo::io`.

#![allow(dead_code)]

use std::path::Path;

use glam::DVec3;
use mesh_topo::PolygonSoup;
use mesh_topo::io::{WriteOptions, read_soup, write_soup};

/// Reads an OBJ, OFF or PLY file.
pub fn read_mesh(path: &Path) -> PolygonSoup {
    read_soup(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).0
}

/// Writes positions and triangles (format from the extension).
pub fn write_obj(path: &Path, positions: &[DVec3], triangles: &[[u32; 3]]) {
    let mut soup = PolygonSoup::with_capacity(positions.len(), triangles.len(), 3 * triangles.len());
    soup.positions.extend_from_slice(positions);
    for t in triangles {
        soup.push_face(t);
    }
    write_soup(path, &soup, &WriteOptions::default()).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
}
