//! Fuzz the mesh builder with arbitrary soups (indices out of range, degenerate faces,
//! non-manifold configurations, NaN, malformed offsets): never panic; a mesh that builds
//! is valid, gives back its soup, has consistent topology and survives the binary format.

#![no_main]

use arbitrary::Arbitrary;
use libfuzzer_sys::fuzz_target;
use mesh_topo::{DVec3, HalfedgeMesh, PolygonSoup, binary};

#[derive(Debug, Arbitrary)]
struct Input {
    /// Small integer coordinates keep inputs compact; `nan_at` poisons one.
    positions: Vec<[i8; 3]>,
    nan_at: Option<u8>,
    /// Faces over few vertices, so that shared edges and fans are frequent.
    faces: Vec<Vec<u8>>,
    /// Replaces the offsets array when set (malformed soups built by hand).
    raw_offsets: Option<Vec<u32>>,
}

fuzz_target!(|input: Input| {
    let mut positions: Vec<DVec3> =
        input.positions.iter().map(|p| DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64)).collect();
    if let Some(i) = input.nan_at {
        if let Some(p) = positions.get_mut(i as usize) {
            p.y = f64::NAN;
        }
    }
    let mut soup = PolygonSoup::from_faces(
        positions,
        input.faces.iter().map(|f| f.iter().map(|&v| v as u32).collect::<Vec<u32>>()),
    );
    if let Some(offsets) = input.raw_offsets {
        soup.offsets = offsets;
    }
    let Ok(mesh) = HalfedgeMesh::from_soup(&soup) else { return };
    mesh.validate().expect("a built mesh is valid");
    assert_eq!(mesh.to_soup(), soup, "to_soup gives back the input");
    let stats = mesh.topology_stats();
    assert_eq!(stats.euler, mesh.vertex_count() as i64 - mesh.edge_count() as i64 + mesh.face_count() as i64);
    let from_components: i64 = stats.per_component.iter().map(|c| 2 - 2 * c.genus - c.boundary_loops as i64).sum();
    assert_eq!(stats.euler, from_components + stats.isolated_vertices.len() as i64);
    assert_eq!(2 * stats.edges, soup.indices.len() + stats.boundary_edges);
    for v in mesh.vertices() {
        let ring: Vec<_> = mesh.outgoing_halfedges(v).collect();
        assert!(ring.iter().all(|&h| mesh.origin(h) == v));
    }
    let bytes = binary::encode_mesh(&mesh).expect("encode");
    assert_eq!(binary::decode_mesh(&bytes).expect("decode"), mesh);
});
