//! Building meshes from soups: every kind of bad input gives its own error naming the
//! culprit, and valid input is kept exactly.

use mesh_topo::shapes::{self, CellKind};
use mesh_topo::{DVec3, HalfedgeMesh, MeshError, PolygonSoup};

fn points(n: usize) -> Vec<DVec3> {
    (0..n).map(|i| DVec3::new(i as f64, (i * i) as f64, 0.5 * i as f64)).collect()
}

fn build(n: usize, faces: &[&[u32]]) -> Result<HalfedgeMesh, MeshError> {
    HalfedgeMesh::from_faces(points(n), faces.iter().copied())
}

#[test]
fn index_out_of_range_names_face_and_corner() {
    let err = build(3, &[&[0, 1, 2], &[0, 2, 7]]).unwrap_err();
    assert_eq!(err, MeshError::IndexOutOfRange { face: 1, corner: 2, index: 7, vertex_count: 3 });
    assert!(err.to_string().contains("face 1"));
}

#[test]
fn small_faces_and_repeated_vertices() {
    assert_eq!(build(3, &[&[0, 1]]).unwrap_err(), MeshError::FaceTooSmall { face: 0, len: 2 });
    assert_eq!(build(4, &[&[0, 1, 2], &[]]).unwrap_err(), MeshError::FaceTooSmall { face: 1, len: 0 });
    assert_eq!(build(4, &[&[0, 1, 2, 1]]).unwrap_err(), MeshError::RepeatedVertex { face: 0, vertex: 1 });
}

#[test]
fn non_manifold_edge() {
    // Three triangles on edge (0, 1).
    let err = build(5, &[&[0, 1, 2], &[1, 0, 3], &[0, 1, 4]]).unwrap_err();
    assert_eq!(err, MeshError::NonManifoldEdge { from: 0, to: 1, faces: [0, 1, 2] });
}

#[test]
fn inconsistent_orientation() {
    let err = build(4, &[&[0, 1, 2], &[0, 1, 3]]).unwrap_err();
    assert_eq!(err, MeshError::InconsistentOrientation { from: 0, to: 1, first_face: 0, second_face: 1 });
}

#[test]
fn non_manifold_vertex_through_boundary() {
    // Two triangles touching at vertex 0 only (a bow tie).
    let err = build(5, &[&[0, 1, 2], &[0, 3, 4]]).unwrap_err();
    assert!(matches!(err, MeshError::NonManifoldVertex { vertex: 0, .. }), "{err}");
}

#[test]
fn non_manifold_vertex_two_closed_fans() {
    // Two octahedra glued at one vertex: vertex 0 of each is merged. Both fans are
    // closed, so no boundary half-edge reveals it; the circulation check must.
    let octa = shapes::octahedron();
    let mut positions = octa.positions.clone();
    positions.extend(octa.positions.iter().skip(1).map(|p| *p + DVec3::new(3.0, 0.0, 0.0)));
    let mut faces: Vec<Vec<u32>> = octa.faces().map(<[u32]>::to_vec).collect();
    for face in octa.faces() {
        faces.push(face.iter().map(|&v| if v == 0 { 0 } else { v + 5 }).collect());
    }
    let err = HalfedgeMesh::from_faces(positions, &faces).unwrap_err();
    match err {
        MeshError::NonManifoldVertex { vertex, fans, example_faces } => {
            assert_eq!((vertex, fans), (0, 2));
            assert!(example_faces[0] < 8 && example_faces[1] >= 8);
        }
        other => panic!("unexpected {other}"),
    }
}

#[test]
fn non_finite_coordinates() {
    let mut positions = points(3);
    positions[2].y = f64::NAN;
    let err = HalfedgeMesh::from_faces(positions, [[0u32, 1, 2]]).unwrap_err();
    assert!(matches!(err, MeshError::NonFiniteCoordinate { vertex: 2, axis: 1, .. }));
    let mut positions = points(3);
    positions[1].z = f64::INFINITY;
    let err = HalfedgeMesh::from_faces(positions, [[0u32, 1, 2]]).unwrap_err();
    assert!(matches!(err, MeshError::NonFiniteCoordinate { vertex: 1, axis: 2, .. }));
}

#[test]
fn malformed_offsets_are_an_error_not_a_panic() {
    let soup = PolygonSoup { positions: points(3), offsets: vec![0, 5], indices: vec![0, 1, 2] };
    assert!(HalfedgeMesh::from_soup(&soup).is_err());
    let soup = PolygonSoup { positions: points(3), offsets: vec![], indices: vec![0, 1, 2] };
    assert!(HalfedgeMesh::from_soup(&soup).is_err());
    let soup = PolygonSoup { positions: points(3), offsets: vec![0, 3, 2], indices: vec![0, 1, 2] };
    assert!(HalfedgeMesh::from_soup(&soup).is_err());
}

#[test]
fn isolated_vertices_are_kept() {
    let mesh = build(5, &[&[0, 2, 3]]).unwrap();
    mesh.validate().unwrap();
    let stats = mesh.topology_stats();
    assert_eq!(stats.isolated_vertices, vec![1, 4]);
    assert_eq!(stats.vertices, 5);
    assert_eq!(stats.components, 1);
    assert_eq!(mesh.to_soup().positions, points(5));
    assert_eq!(mesh.valence(mesh.vertex(1).unwrap()), 0);
}

#[test]
fn empty_and_face_free_soups() {
    let mesh = HalfedgeMesh::from_soup(&PolygonSoup::default()).unwrap();
    assert_eq!((mesh.vertex_count(), mesh.face_count()), (0, 0));
    let mesh = HalfedgeMesh::from_faces(points(2), Vec::<[u32; 3]>::new()).unwrap();
    assert_eq!(mesh.topology_stats().isolated_vertices, vec![0, 1]);
}

#[test]
fn circulation_order_is_counter_clockwise() {
    // A hexagonal fan around vertex 0 in the plane.
    let mut positions = vec![DVec3::ZERO];
    for k in 0..6 {
        let a = std::f64::consts::TAU * k as f64 / 6.0;
        positions.push(DVec3::new(a.cos(), a.sin(), 0.0));
    }
    let faces: Vec<[u32; 3]> = (0..6).map(|k| [0, 1 + k, 1 + (k + 1) % 6]).collect();
    let mesh = HalfedgeMesh::from_faces(positions.clone(), faces).unwrap();
    let centre = mesh.vertex(0).unwrap();
    let ring: Vec<u32> = mesh.vertex_neighbors(centre).map(|v| v.raw()).collect();
    // Starts at the first corner's edge and turns counter-clockwise.
    assert_eq!(ring, vec![1, 2, 3, 4, 5, 6]);
    // A boundary vertex starts at its outgoing boundary half-edge.
    let rim = mesh.vertex(1).unwrap();
    let first = mesh.outgoing_halfedges(rim).next().unwrap();
    assert!(mesh.is_boundary_halfedge(first));
    let ring: Vec<u32> = mesh.vertex_neighbors(rim).map(|v| v.raw()).collect();
    // Counter-clockwise from the boundary edge (1, 6): across the hole to 2, then 0.
    assert_eq!(ring, vec![6, 2, 0]);
    let faces: Vec<usize> = mesh.vertex_faces(rim).map(|f| f.index()).collect();
    assert_eq!(faces, vec![0, 5]);
}

#[test]
fn face_traversals_and_loops() {
    let mesh = HalfedgeMesh::from_soup(&shapes::grid(3, 1, CellKind::Quads).unwrap()).unwrap();
    let f0 = mesh.face(0).unwrap();
    let bfs: Vec<usize> = mesh.face_bfs(f0).iter().map(|f| f.index()).collect();
    assert_eq!(bfs, vec![0, 1, 2]);
    let dfs: Vec<usize> = mesh.face_dfs(mesh.face(1).unwrap()).iter().map(|f| f.index()).collect();
    assert_eq!(dfs.len(), 3);
    let loops = mesh.boundary_loops();
    assert_eq!(loops.len(), 1);
    assert_eq!(loops[0].len(), 8);
    assert_eq!(mesh.face_adjacency_graph().edge_count(), 2);
    let v_order = mesh.vertex_bfs(mesh.vertex(0).unwrap());
    assert_eq!(v_order.len(), 8);
}

#[test]
fn several_components_and_genus() {
    let torus = shapes::torus(6, 5, CellKind::Quads).unwrap();
    let cube = shapes::cube();
    let mut soup = torus.clone();
    let offset = torus.positions.len() as u32;
    soup.positions.extend(cube.positions.iter().map(|p| *p + DVec3::splat(5.0)));
    for face in cube.faces() {
        soup.push_face(&face.iter().map(|v| v + offset).collect::<Vec<_>>());
    }
    let mesh = HalfedgeMesh::from_soup(&soup).unwrap();
    let stats = mesh.topology_stats();
    assert_eq!(stats.components, 2);
    assert_eq!(stats.genus, 1);
    assert_eq!(stats.per_component[0].genus, 1);
    assert_eq!(stats.per_component[1].genus, 0);
    assert_eq!(stats.euler, 2);
}
