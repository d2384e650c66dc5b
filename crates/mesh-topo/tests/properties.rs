//! Invariants of the half-edge structure on random meshes.

use mesh_topo::testing::arb_mesh;
use mesh_topo::{HalfedgeMesh, binary};
use proptest::prelude::*;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn structure_invariants(soup in arb_mesh()) {
        let mesh = HalfedgeMesh::from_soup(&soup).unwrap();
        mesh.validate().unwrap();
        for h in mesh.halfedges() {
            prop_assert_eq!(h.twin().twin(), h);
            prop_assert_eq!(mesh.prev(mesh.next(h)), h);
            prop_assert_eq!(mesh.origin(mesh.next(h)), mesh.target(h));
            prop_assert_eq!(mesh.origin(h.twin()), mesh.target(h));
        }
        for f in mesh.faces() {
            // The next-cycle closes the face and stays in it.
            let cycle: Vec<_> = mesh.face_halfedges(f).collect();
            prop_assert!(cycle.len() >= 3);
            prop_assert_eq!(mesh.next(*cycle.last().unwrap()), cycle[0]);
            prop_assert!(cycle.iter().all(|&h| mesh.halfedge_face(h) == Some(f)));
        }
        for v in mesh.vertices() {
            // Circulators return to the start.
            let out: Vec<_> = mesh.outgoing_halfedges(v).collect();
            if let Some(&first) = out.first() {
                let last = *out.last().unwrap();
                prop_assert_eq!(mesh.prev(last).twin(), first);
                prop_assert!(out.iter().all(|&h| mesh.origin(h) == v));
            }
        }
    }

    #[test]
    fn euler_from_counts_matches_topology(soup in arb_mesh()) {
        let mesh = HalfedgeMesh::from_soup(&soup).unwrap();
        let stats = mesh.topology_stats();
        let from_counts = soup.vertex_count() as i64 - stats.edges as i64 + soup.face_count() as i64;
        let from_components: i64 = stats.per_component.iter().map(|c| 2 - 2 * c.genus - c.boundary_loops as i64).sum();
        prop_assert_eq!(from_counts, from_components + stats.isolated_vertices.len() as i64);
        // Edges from the soup: corners counted once per interior edge side.
        let corners = soup.indices.len();
        prop_assert_eq!(2 * stats.edges, corners + stats.boundary_edges);
    }

    #[test]
    fn soup_and_binary_round_trips_are_lossless(soup in arb_mesh()) {
        let mesh = HalfedgeMesh::from_soup(&soup).unwrap();
        prop_assert_eq!(&mesh.to_soup(), &soup);
        let bytes = binary::encode_mesh(&mesh).unwrap();
        let back = binary::decode_mesh(&bytes).unwrap();
        prop_assert_eq!(&back, &mesh);
        prop_assert!(back.positions().iter().zip(soup.positions.iter()).all(|(a, b)| a.to_array().map(f64::to_bits) == b.to_array().map(f64::to_bits)));
        // Every strict prefix is an error, never a panic.
        for cut in [0, 5, 11, 12, bytes.len() / 2, bytes.len() - 1] {
            prop_assert!(binary::decode_mesh(&bytes[..cut]).is_err());
        }
    }

    /// Ring distances are the breadth-first layers cut at `rings`: neighbours differ by
    /// at most one ring, and every vertex inside the last ring has all its neighbours
    /// counted. The faces that touch the rings, cut out, name the same vertices at the
    /// same places; a vertex no kept face uses has no number.
    #[test]
    fn rings_and_extracted_faces(soup in arb_mesh(), start in any::<prop::sample::Index>(), rings in 0usize..5) {
        let mesh = HalfedgeMesh::from_soup(&soup).unwrap();
        let start = mesh.vertex(start.index(mesh.vertex_count())).unwrap();
        let distance = mesh.ring_distances(start, rings);
        let unlimited = mesh.ring_distances(start, usize::MAX);
        prop_assert_eq!(distance[start.index()], Some(0));
        for v in mesh.vertices() {
            // The cut layers are the unlimited ones up to `rings`.
            let expected = unlimited[v.index()].filter(|&d| d as usize <= rings);
            prop_assert_eq!(distance[v.index()], expected);
            if let Some(d) = unlimited[v.index()] {
                for w in mesh.vertex_neighbors(v) {
                    let e = unlimited[w.index()].expect("a neighbour is in the same component");
                    prop_assert!(e.abs_diff(d) <= 1);
                }
            }
        }
        // The reached vertices are those of the breadth-first search.
        let reached = unlimited.iter().filter(|d| d.is_some()).count();
        prop_assert_eq!(reached, mesh.vertex_bfs(start).len());

        let touches = |f| mesh.face_vertices(f).any(|v| distance[v.index()].is_some());
        let (cut, new_index) = mesh.extract_faces(touches);
        let kept: Vec<_> = mesh.faces().filter(|&f| touches(f)).collect();
        prop_assert_eq!(cut.face_count(), kept.len());
        for (k, &f) in kept.iter().enumerate() {
            let names: Vec<u32> = mesh.face_vertices(f).map(|v| new_index[v.index()].unwrap()).collect();
            prop_assert_eq!(cut.face(k), &names[..]);
            for v in mesh.face_vertices(f) {
                prop_assert_eq!(cut.positions[new_index[v.index()].unwrap() as usize], mesh.position(v));
            }
        }
        let used = new_index.iter().filter(|i| i.is_some()).count();
        prop_assert_eq!(used, cut.vertex_count());
        // Every face kept: the soup back, in order of first use.
        let (all, _) = mesh.extract_faces(|_| true);
        prop_assert_eq!(all.face_count(), soup.face_count());
    }
}
