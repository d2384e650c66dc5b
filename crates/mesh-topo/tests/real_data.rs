//! The real meshes of the workspace's `tests/data/` (scans with holes, a polygonal genus-2
//! surface, the bunny): counts, genus and boundary loops against an independent count,
//! and lossless round trips. Kept apart from `io.rs` because it reads files outside
//! the crate (the published package leaves it out).

use std::path::PathBuf;

use mesh_topo::HalfedgeMesh;
use mesh_topo::io::{self, Format, PlyEncoding};

mod support;
use support::{round_trip, write};

// ---------------------------------------------------------------------------------------
// Real meshes.

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../tests/data").join(name)
}

struct Expected {
    file: &'static str,
    vertices: usize,
    edges: usize,
    boundary_edges: usize,
    faces: usize,
    boundary_loops: usize,
    genus: i64,
    components: usize,
    face_sizes: &'static [(usize, usize)],
}

/// The table of `tests/data/README.md`; edges, boundary edges, components and face sizes
/// as counted independently by a plain Python edge-map script (no half-edges).
const REAL_MESHES: &[Expected] = &[
    Expected {
        file: "bunny.obj",
        vertices: 1839,
        edges: 5511,
        boundary_edges: 0,
        faces: 3674,
        boundary_loops: 0,
        genus: 0,
        components: 1,
        face_sizes: &[(3, 3674)],
    },
    Expected {
        file: "bunny00.off",
        vertices: 37706,
        edges: 113112,
        boundary_edges: 0,
        faces: 75408,
        boundary_loops: 0,
        genus: 0,
        components: 1,
        face_sizes: &[(3, 75408)],
    },
    Expected {
        file: "cow.off",
        vertices: 2904,
        edges: 8706,
        boundary_edges: 0,
        faces: 5804,
        boundary_loops: 0,
        genus: 0,
        components: 1,
        face_sizes: &[(3, 5804)],
    },
    Expected {
        file: "elephant.off",
        vertices: 2775,
        edges: 8337,
        boundary_edges: 0,
        faces: 5558,
        boundary_loops: 0,
        genus: 3,
        components: 1,
        face_sizes: &[(3, 5558)],
    },
    Expected {
        file: "eight.off",
        vertices: 315,
        edges: 951,
        boundary_edges: 0,
        faces: 634,
        boundary_loops: 0,
        genus: 2,
        components: 1,
        face_sizes: &[(3, 634)],
    },
    Expected {
        file: "knot1.off",
        vertices: 3200,
        edges: 9600,
        boundary_edges: 0,
        faces: 6400,
        boundary_loops: 0,
        genus: 1,
        components: 1,
        face_sizes: &[(3, 6400)],
    },
    Expected {
        file: "mannequin-devil.off",
        vertices: 12977,
        edges: 38864,
        boundary_edges: 64,
        faces: 25888,
        boundary_loops: 1,
        genus: 0,
        components: 1,
        face_sizes: &[(3, 25888)],
    },
    Expected {
        file: "elephant-with-holes.off",
        vertices: 2798,
        edges: 7371,
        boundary_edges: 1353,
        faces: 4463,
        boundary_loops: 106,
        genus: 3,
        components: 1,
        face_sizes: &[(3, 4463)],
    },
    Expected {
        file: "open_cube.off",
        vertices: 8,
        edges: 17,
        boundary_edges: 4,
        faces: 10,
        boundary_loops: 1,
        genus: 0,
        components: 1,
        face_sizes: &[(3, 10)],
    },
    Expected {
        file: "double-torus-example.off",
        vertices: 231,
        edges: 453,
        boundary_edges: 0,
        faces: 220,
        boundary_loops: 0,
        genus: 2,
        components: 1,
        face_sizes: &[(4, 202), (5, 12), (6, 4), (7, 2)],
    },
    Expected {
        file: "torus_quad.off",
        vertices: 25,
        edges: 50,
        boundary_edges: 0,
        faces: 25,
        boundary_loops: 0,
        genus: 1,
        components: 1,
        face_sizes: &[(4, 25)],
    },
    Expected {
        file: "cross_quad.off",
        vertices: 40,
        edges: 76,
        boundary_edges: 0,
        faces: 38,
        boundary_loops: 0,
        genus: 0,
        components: 1,
        face_sizes: &[(4, 38)],
    },
    Expected {
        file: "cube_quad.off",
        vertices: 8,
        edges: 12,
        boundary_edges: 0,
        faces: 6,
        boundary_loops: 0,
        genus: 0,
        components: 1,
        face_sizes: &[(4, 6)],
    },
    Expected {
        file: "cube_poly.off",
        vertices: 8,
        edges: 13,
        boundary_edges: 0,
        faces: 7,
        boundary_loops: 0,
        genus: 0,
        components: 1,
        face_sizes: &[(3, 2), (4, 5)],
    },
];

#[test]
fn real_meshes_have_the_documented_topology() {
    for expected in REAL_MESHES {
        let (soup, report) = io::read_soup(data(expected.file)).unwrap();
        assert!(report.is_lossless(), "{}: {report}", expected.file);
        let mesh = HalfedgeMesh::from_soup(&soup).unwrap_or_else(|e| panic!("{}: {e}", expected.file));
        mesh.validate().unwrap();
        let stats = mesh.topology_stats();
        let found = (stats.vertices, stats.edges, stats.faces, stats.boundary_edges, stats.boundary_loops);
        let wanted =
            (expected.vertices, expected.edges, expected.faces, expected.boundary_edges, expected.boundary_loops);
        assert_eq!(found, wanted, "{}: (V, E, F, boundary edges, loops)", expected.file);
        assert_eq!((stats.genus, stats.components), (expected.genus, expected.components), "{}", expected.file);
        assert!(stats.isolated_vertices.is_empty(), "{}", expected.file);
        let sizes: Vec<(usize, usize)> = stats.face_sizes.into_iter().collect();
        assert_eq!(sizes, expected.face_sizes, "{}", expected.file);
        round_trip(&soup);
    }
}

#[test]
fn double_torus_is_polygonal_genus_2() {
    let (mesh, _) = io::read_mesh(data("double-torus-example.off")).unwrap();
    let stats = mesh.topology_stats();
    let sizes: Vec<usize> = stats.face_sizes.keys().copied().collect();
    assert_eq!(sizes, vec![4, 5, 6, 7]);
    assert_eq!(stats.euler, -2);
    assert_eq!(stats.per_component[0].genus, 2);
}

#[test]
fn elephant_with_holes_loops() {
    let (mesh, _) = io::read_mesh(data("elephant-with-holes.off")).unwrap();
    let loops = mesh.boundary_loops();
    assert_eq!(loops.len(), 106);
    let boundary_edges: usize = loops.iter().map(Vec::len).sum();
    assert_eq!(boundary_edges, mesh.topology_stats().boundary_edges);
    // V - E + F = 2 - 2g - b with g = 3, b = 106.
    assert_eq!(mesh.euler_characteristic(), 2 - 2 * 3 - 106);
}

#[test]
fn bunny_obj_rewrites_to_its_own_lines() {
    // The file's numbers are already in shortest form, so writing reproduces every
    // `v` and `f` line byte for byte.
    let original = std::fs::read_to_string(data("bunny.obj")).unwrap();
    let (soup, _) = io::read_bytes(original.as_bytes(), Format::Obj).unwrap();
    let written = String::from_utf8(write(&soup, Format::Obj, PlyEncoding::Ascii)).unwrap();
    let statements = |text: &str| -> Vec<String> {
        text.lines().filter(|l| !l.starts_with('#')).map(|l| l.trim_end().to_string()).collect()
    };
    assert_eq!(statements(&written), statements(&original));
}
