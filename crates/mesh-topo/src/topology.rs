//! Global topology: boundary loops, connected components, Euler characteristic, genus,
//! histograms, the face-adjacency (dual) graph, searches and ring neighbourhoods.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::graph::{Graph, UnionFind};
use crate::ids::{FaceId, HalfedgeId, VertexId};
use crate::mesh::HalfedgeMesh;

/// Topological summary of one connected component (isolated vertices excluded).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ComponentStats {
    /// Vertices in the component.
    pub vertices: usize,
    /// Edges in the component.
    pub edges: usize,
    /// Faces in the component.
    pub faces: usize,
    /// Boundary loops of the component.
    pub boundary_loops: usize,
    /// `V - E + F` of the component.
    pub euler: i64,
    /// Genus from `V - E + F = 2 - 2g - b` (every component is orientable).
    pub genus: i64,
}

/// Topological summary of a whole mesh, as printed by `multires info`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct TopologyStats {
    /// Number of vertices, isolated ones included.
    pub vertices: usize,
    /// Number of edges.
    pub edges: usize,
    /// Number of faces.
    pub faces: usize,
    /// Number of boundary edges.
    pub boundary_edges: usize,
    /// Number of boundary loops.
    pub boundary_loops: usize,
    /// Number of connected components (isolated vertices not counted).
    pub components: usize,
    /// `V - E + F` over the whole mesh (isolated vertices count, each adds 1).
    pub euler: i64,
    /// Sum of the genera of the components.
    pub genus: i64,
    /// Vertices that no face uses (kept, reported).
    pub isolated_vertices: Vec<u32>,
    /// Face size -> number of faces.
    pub face_sizes: BTreeMap<usize, usize>,
    /// Valence -> number of (non-isolated) vertices.
    pub valences: BTreeMap<usize, usize>,
    /// Per-component summaries, in order of each component's smallest vertex.
    pub per_component: Vec<ComponentStats>,
}

/// Connected components of a mesh.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Components {
    /// Component of each vertex; `u32::MAX` for isolated vertices.
    pub vertex_component: Vec<u32>,
    /// Component of each face.
    pub face_component: Vec<u32>,
    /// Number of components.
    pub count: usize,
}

impl HalfedgeMesh {
    /// The boundary loops, each as its half-edges in order (the hole on their left).
    /// Loops are listed in order of their smallest half-edge index and start there.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, PolygonSoup, shapes};
    ///
    /// let cube = shapes::cube();
    /// assert!(HalfedgeMesh::from_soup(&cube)?.boundary_loops().is_empty());
    /// // Without its last face, the cube is an open box with one square hole.
    /// let open_box = HalfedgeMesh::from_soup(&PolygonSoup::from_faces(cube.positions.clone(), cube.faces().take(5)))?;
    /// let loops = open_box.boundary_loops();
    /// assert_eq!((loops.len(), loops[0].len()), (1, 4));
    /// assert!(loops[0].iter().all(|&h| open_box.is_boundary_halfedge(h)));
    /// assert_eq!(open_box.next(loops[0][3]), loops[0][0]);
    /// # Ok::<(), mesh_topo::MeshError>(())
    /// ```
    pub fn boundary_loops(&self) -> Vec<Vec<HalfedgeId>> {
        let mut seen = vec![false; self.halfedge_count()];
        let mut loops = Vec::new();
        for h in self.halfedges() {
            if seen[h.index()] || !self.is_boundary_halfedge(h) {
                continue;
            }
            let boundary: Vec<HalfedgeId> = self.halfedge_loop(h).collect();
            for b in &boundary {
                seen[b.index()] = true;
            }
            loops.push(boundary);
        }
        loops
    }

    /// Connected components through edges. Isolated vertices belong to none.
    ///
    /// ```
    /// use mesh_topo::{DVec3, HalfedgeMesh};
    ///
    /// // Two separate triangles and an unused vertex 3 (only the connectivity matters here).
    /// let mesh = HalfedgeMesh::from_faces(vec![DVec3::ZERO; 7], [[0u32, 1, 2], [4, 5, 6]])?;
    /// let components = mesh.connected_components();
    /// assert_eq!(components.count, 2);
    /// assert_eq!(components.vertex_component, [0, 0, 0, u32::MAX, 1, 1, 1]);
    /// assert_eq!(components.face_component, [0, 1]);
    /// # Ok::<(), mesh_topo::MeshError>(())
    /// ```
    pub fn connected_components(&self) -> Components {
        let mut sets = UnionFind::new(self.vertex_count());
        for e in self.edges() {
            let [a, b] = self.edge_vertices(e);
            sets.union(a.raw(), b.raw());
        }
        let mut label_of_root = vec![u32::MAX; self.vertex_count()];
        let mut vertex_component = vec![u32::MAX; self.vertex_count()];
        let mut count = 0u32;
        for v in self.vertices() {
            if self.is_isolated(v) {
                continue;
            }
            let root = sets.find(v.raw()) as usize;
            if label_of_root[root] == u32::MAX {
                label_of_root[root] = count;
                count += 1;
            }
            vertex_component[v.index()] = label_of_root[root];
        }
        let face_component =
            self.faces().map(|f| vertex_component[self.origin(self.face_halfedge(f)).index()]).collect();
        Components { vertex_component, face_component, count: count as usize }
    }

    /// `V - E + F`, isolated vertices included.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, MeshError, PolygonSoup};
    /// use mesh_topo::shapes::{self, CellKind};
    ///
    /// let euler = |soup: PolygonSoup| Ok::<_, MeshError>(HalfedgeMesh::from_soup(&soup)?.euler_characteristic());
    /// assert_eq!(euler(shapes::icosahedron())?, 2); // a sphere
    /// assert_eq!(euler(shapes::grid(3, 2, CellKind::Mixed)?)?, 1); // a disk
    /// assert_eq!(euler(shapes::torus(5, 4, CellKind::Triangles)?)?, 0); // a torus
    /// # Ok::<(), MeshError>(())
    /// ```
    pub fn euler_characteristic(&self) -> i64 {
        self.vertex_count() as i64 - self.edge_count() as i64 + self.face_count() as i64
    }

    /// The full topological summary (counts, histograms, loops, components, genus).
    ///
    /// ```
    /// use std::collections::BTreeMap;
    /// use mesh_topo::HalfedgeMesh;
    /// use mesh_topo::shapes::{self, CellKind};
    ///
    /// let mesh = HalfedgeMesh::from_soup(&shapes::torus(4, 3, CellKind::Quads)?)?;
    /// let stats = mesh.topology_stats();
    /// assert_eq!((stats.vertices, stats.edges, stats.faces), (12, 24, 12));
    /// assert_eq!((stats.euler, stats.genus, stats.components, stats.boundary_loops), (0, 1, 1, 0));
    /// assert_eq!(stats.valences, BTreeMap::from([(4, 12)]));
    /// assert_eq!(stats.face_sizes, BTreeMap::from([(4, 12)]));
    /// assert!(stats.isolated_vertices.is_empty());
    /// # Ok::<(), mesh_topo::MeshError>(())
    /// ```
    pub fn topology_stats(&self) -> TopologyStats {
        let components = self.connected_components();
        let loops = self.boundary_loops();
        let mut per_component =
            vec![
                ComponentStats { vertices: 0, edges: 0, faces: 0, boundary_loops: 0, euler: 0, genus: 0 };
                components.count
            ];
        let mut valences = BTreeMap::new();
        let mut isolated_vertices = Vec::new();
        for v in self.vertices() {
            match components.vertex_component[v.index()] {
                u32::MAX => isolated_vertices.push(v.raw()),
                c => {
                    per_component[c as usize].vertices += 1;
                    *valences.entry(self.valence(v)).or_insert(0) += 1;
                }
            }
        }
        let mut boundary_edges = 0;
        for e in self.edges() {
            let c = components.vertex_component[self.edge_vertices(e)[0].index()];
            per_component[c as usize].edges += 1;
            boundary_edges += usize::from(self.is_boundary_edge(e));
        }
        let mut face_sizes = BTreeMap::new();
        for f in self.faces() {
            per_component[components.face_component[f.index()] as usize].faces += 1;
            *face_sizes.entry(self.face_degree(f)).or_insert(0) += 1;
        }
        for boundary in &loops {
            let c = components.vertex_component[self.origin(boundary[0]).index()];
            per_component[c as usize].boundary_loops += 1;
        }
        for c in &mut per_component {
            c.euler = c.vertices as i64 - c.edges as i64 + c.faces as i64;
            c.genus = (2 - c.euler - c.boundary_loops as i64) / 2;
        }
        TopologyStats {
            vertices: self.vertex_count(),
            edges: self.edge_count(),
            faces: self.face_count(),
            boundary_edges,
            boundary_loops: loops.len(),
            components: components.count,
            euler: self.euler_characteristic(),
            genus: per_component.iter().map(|c| c.genus).sum(),
            isolated_vertices,
            face_sizes,
            valences,
            per_component,
        }
    }

    /// The dual graph: one node per face, one edge per interior edge (in edge order).
    ///
    /// ```
    /// use mesh_topo::HalfedgeMesh;
    /// use mesh_topo::shapes::{self, CellKind};
    ///
    /// let cube = HalfedgeMesh::from_soup(&shapes::cube())?;
    /// let dual = cube.face_adjacency_graph();
    /// assert_eq!((dual.node_count(), dual.edge_count()), (6, 12));
    /// assert!((0..6).all(|f| dual.neighbors(f).len() == 4));
    /// // A row of three quads: boundary edges give no dual edge, so the dual is a path.
    /// let row = HalfedgeMesh::from_soup(&shapes::grid(3, 1, CellKind::Quads)?)?.face_adjacency_graph();
    /// assert_eq!((row.edge_count(), row.neighbors(1)), (2, &[0, 2][..]));
    /// # Ok::<(), mesh_topo::MeshError>(())
    /// ```
    pub fn face_adjacency_graph(&self) -> Graph {
        let edges: Vec<(u32, u32)> = self
            .edges()
            .filter_map(|e| {
                let a = self.halfedge_face(e.halfedge(0))?;
                let b = self.halfedge_face(e.halfedge(1))?;
                Some((a.raw(), b.raw()))
            })
            .collect();
        Graph::from_edges(self.face_count(), &edges)
    }

    /// Faces reachable from `start` across interior edges, breadth-first. Neighbours are
    /// visited in the order of each face's half-edges, so the order is deterministic.
    ///
    /// ```
    /// use mesh_topo::HalfedgeMesh;
    /// use mesh_topo::shapes::{self, CellKind};
    ///
    /// // A 2 x 2 grid: cells 0 and 1 at the bottom, 2 and 3 at the top.
    /// let mesh = HalfedgeMesh::from_soup(&shapes::grid(2, 2, CellKind::Quads)?)?;
    /// let order: Vec<u32> = mesh.face_bfs(mesh.face(0).unwrap()).iter().map(|f| f.raw()).collect();
    /// assert_eq!(order, [0, 1, 2, 3]); // 1 and 2 first, then 3, two steps away
    /// # Ok::<(), mesh_topo::MeshError>(())
    /// ```
    ///
    /// # Panics
    /// If `start` is not a face of this mesh (see [Handles](HalfedgeMesh#handles)).
    pub fn face_bfs(&self, start: FaceId) -> Vec<FaceId> {
        let mut visited = vec![false; self.face_count()];
        let mut order = vec![start];
        visited[start.index()] = true;
        let mut head = 0;
        while head < order.len() {
            let f = order[head];
            head += 1;
            for g in self.face_neighbors(f) {
                if !std::mem::replace(&mut visited[g.index()], true) {
                    order.push(g);
                }
            }
        }
        order
    }

    /// Faces reachable from `start` across interior edges, depth-first preorder.
    ///
    /// ```
    /// use mesh_topo::HalfedgeMesh;
    /// use mesh_topo::shapes::{self, CellKind};
    ///
    /// // A 2 x 2 grid: cells 0 and 1 at the bottom, 2 and 3 at the top.
    /// let mesh = HalfedgeMesh::from_soup(&shapes::grid(2, 2, CellKind::Quads)?)?;
    /// let order: Vec<u32> = mesh.face_dfs(mesh.face(0).unwrap()).iter().map(|f| f.raw()).collect();
    /// assert_eq!(order, [0, 1, 3, 2]); // 0's right neighbour 1 first, then on from there
    /// # Ok::<(), mesh_topo::MeshError>(())
    /// ```
    ///
    /// # Panics
    /// If `start` is not a face of this mesh (see [Handles](HalfedgeMesh#handles)).
    pub fn face_dfs(&self, start: FaceId) -> Vec<FaceId> {
        let mut visited = vec![false; self.face_count()];
        let mut order = Vec::new();
        let mut stack = vec![start];
        while let Some(f) = stack.pop() {
            if std::mem::replace(&mut visited[f.index()], true) {
                continue;
            }
            order.push(f);
            let neighbors: Vec<FaceId> = self.face_neighbors(f).filter(|g| !visited[g.index()]).collect();
            stack.extend(neighbors.into_iter().rev());
        }
        order
    }

    /// Vertices reachable from `start` along edges, breadth-first, neighbours in
    /// counter-clockwise circulation order.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, VertexId, shapes};
    ///
    /// // Octahedron: from the top vertex 4, its ring of four, then the bottom vertex 5.
    /// let mesh = HalfedgeMesh::from_soup(&shapes::octahedron())?;
    /// let top = mesh.vertex(4).unwrap();
    /// let order = mesh.vertex_bfs(top);
    /// let ring: Vec<VertexId> = mesh.vertex_neighbors(top).collect();
    /// assert_eq!((order.len(), order[0], order[5].raw()), (6, top, 5));
    /// assert_eq!(order[1..5], ring[..]);
    /// # Ok::<(), mesh_topo::MeshError>(())
    /// ```
    ///
    /// # Panics
    /// If `start` is not a vertex of this mesh (see [Handles](HalfedgeMesh#handles)).
    pub fn vertex_bfs(&self, start: VertexId) -> Vec<VertexId> {
        let mut visited = vec![false; self.vertex_count()];
        let mut order = vec![start];
        visited[start.index()] = true;
        let mut head = 0;
        while head < order.len() {
            let v = order[head];
            head += 1;
            for w in self.vertex_neighbors(v) {
                if !std::mem::replace(&mut visited[w.index()], true) {
                    order.push(w);
                }
            }
        }
        order
    }

    /// The edge distance from `start` of every vertex within `rings` edges of it (the
    /// `k`-ring neighbourhood for `k = rings`): `Some(d)` for the vertices of ring `d`,
    /// `None` for those farther away or in another component. A breadth-first search that
    /// stops after ring `rings` (or when the component is exhausted).
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    ///
    /// // Octahedron: the top vertex 4, its ring of four, then the bottom vertex 5.
    /// let mesh = HalfedgeMesh::from_soup(&shapes::octahedron())?;
    /// let top = mesh.vertex(4).unwrap();
    /// assert_eq!(mesh.ring_distances(top, 1), [Some(1), Some(1), Some(1), Some(1), Some(0), None]);
    /// assert_eq!(mesh.ring_distances(top, 5)[5], Some(2));
    /// // The faces around the top vertex (its star): those with a corner in ring 0.
    /// let near = mesh.ring_distances(top, 0);
    /// let (star, _) = mesh.extract_faces(|f| mesh.face_vertices(f).any(|v| near[v.index()].is_some()));
    /// assert_eq!((star.vertex_count(), star.face_count()), (5, 4));
    /// # Ok::<(), mesh_topo::MeshError>(())
    /// ```
    ///
    /// # Panics
    /// If `start` is not a vertex of this mesh (see [Handles](HalfedgeMesh#handles)).
    pub fn ring_distances(&self, start: VertexId, rings: usize) -> Vec<Option<u32>> {
        let mut distance = vec![None; self.vertex_count()];
        distance[start.index()] = Some(0);
        let mut frontier = vec![start];
        let mut next = Vec::new();
        // (Distances are below the vertex count, so they fit in `u32`.)
        for d in (1..=rings.min(self.vertex_count())).map(|d| d as u32) {
            if frontier.is_empty() {
                break;
            }
            for &v in &frontier {
                for w in self.vertex_neighbors(v) {
                    if distance[w.index()].is_none() {
                        distance[w.index()] = Some(d);
                        next.push(w);
                    }
                }
            }
            std::mem::swap(&mut frontier, &mut next);
            next.clear();
        }
        distance
    }
}
