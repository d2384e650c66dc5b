//! Repeated subdivision into the memory of the previous result.

use std::mem::take;
use std::sync::atomic::AtomicU32;

use glam::DVec3;
use mesh_topo::HalfedgeMesh;

use super::kernel::{self, Buffers, Rules};
use super::topology::Topology;
use super::{
    LoopMesh, LoopOptions, check_finite_largest, check_no_overflow, check_output_memory, check_sizes, output_bytes,
};
use crate::LoopError;

/// Loop subdivision that reuses its memory from one call to the next.
///
/// [`subdivide`](super::subdivide) returns fresh arrays on every call. The first write
/// to fresh memory costs a page fault per 4 KiB page (and the kernel zeroing the page),
/// and for Loop subdivision, which does little arithmetic per output byte, these
/// first-touch faults are a large part of the time: about half of it at a few hundred
/// thousand output triangles on one thread. A `Subdivider` writes each call's result
/// into the arrays of the [`LoopMesh`] it is given and keeps the intermediate levels'
/// arrays itself, so a repeated call with the same or a smaller mesh and level (an
/// interactive editor moving vertices, an animation, one stage of a pipeline) allocates
/// nothing and touches only memory that is already mapped.
///
/// The results are bit-identical to [`subdivide`](super::subdivide) with the same
/// options, on any number of threads (the calls run on the current `rayon` pool; small
/// levels run on the calling thread).
///
/// Memory: the output arrays, plus the level before the last (about 40% of the output)
/// and the connectivity of the level before that (about 4%), kept between calls. Arrays
/// never shrink: a call for a smaller mesh keeps the memory of a larger one until the
/// `Subdivider` and the output are dropped.
///
/// ```
/// use mesh_topo::{HalfedgeMesh, shapes};
/// use subdiv_loop::forward::{LoopMesh, LoopOptions, Subdivider, subdivide};
///
/// let mut mesh = HalfedgeMesh::from_soup(&shapes::icosahedron())?;
/// let mut subdivider = Subdivider::new(LoopOptions::default());
/// let mut fine = LoopMesh::default();
/// subdivider.subdivide_into(&mesh, 3, &mut fine)?;
/// assert_eq!(fine, subdivide(&mesh, 3, subdivider.options())?);
///
/// // Move a vertex and subdivide again: the same memory is written again.
/// let (positions, triangles) = (fine.positions.as_ptr(), fine.triangles.as_ptr());
/// mesh.positions_mut()[0].z += 0.5;
/// subdivider.subdivide_into(&mesh, 3, &mut fine)?;
/// assert_eq!((fine.positions.as_ptr(), fine.triangles.as_ptr()), (positions, triangles));
/// assert_eq!(fine, subdivide(&mesh, 3, &LoopOptions::default())?);
/// # Ok::<(), subdiv_loop::LoopError>(())
/// ```
#[derive(Debug)]
pub struct Subdivider {
    options: LoopOptions,
    rules: Rules,
    scratch: Scratch,
}

/// The arrays a [`Subdivider`] keeps between calls.
///
/// The levels' values and triangles alternate between the output's arrays and these:
/// level `l` of `L` lives in the output's when `L - l` is even, so the largest
/// intermediate level (`L - 1`) is here and the ones before it are in the output's
/// arrays, which are larger still. Links and starts are needed for the levels `0 .. L`
/// that are refined further and alternate between two pairs by the parity of the level.
#[derive(Debug, Default)]
struct Scratch {
    /// The half-edge map of [`Topology::rebuild`].
    compact: Vec<AtomicU32>,
    values: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
    links: [Vec<[u32; 4]>; 2],
    starts: [Vec<u32>; 2],
}

impl Default for Subdivider {
    /// A subdivider with the default options (Loop's weights, corners smoothed).
    fn default() -> Self {
        Self::new(LoopOptions::default())
    }
}

impl Subdivider {
    /// A subdivider with these options; it allocates nothing until the first call.
    ///
    /// ```
    /// use subdiv_loop::forward::{LoopOptions, Subdivider};
    /// let subdivider = Subdivider::new(LoopOptions::warren_weights());
    /// assert_eq!(subdivider.options(), &LoopOptions::warren_weights());
    /// ```
    pub fn new(options: LoopOptions) -> Self {
        Self { options, rules: Rules::new(&options), scratch: Scratch::default() }
    }

    /// The options every call uses.
    pub fn options(&self) -> &LoopOptions {
        &self.options
    }

    /// Subdivides `mesh` `levels` times into `out`, reusing the memory of `out` and of
    /// this subdivider's scratch from earlier calls. The result equals, bit for bit,
    /// `subdivide(mesh, levels, self.options())`; the earlier contents of `out` are
    /// discarded.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_loop::forward::{LoopMesh, Subdivider};
    ///
    /// let tetrahedron = HalfedgeMesh::from_soup(&shapes::tetrahedron())?;
    /// let (mut subdivider, mut fine) = (Subdivider::default(), LoopMesh::default());
    /// for levels in [2, 1, 2] {
    ///     subdivider.subdivide_into(&tetrahedron, levels, &mut fine)?;
    ///     assert_eq!(fine.face_count(), 4 * 4usize.pow(levels));
    /// }
    /// # Ok::<(), subdiv_loop::LoopError>(())
    /// ```
    ///
    /// # Errors
    /// The errors of [`subdivide`](super::subdivide), in the same cases and order
    /// (non-finite positions, then non-triangles and pillows, then sizes, then memory:
    /// the output's bytes beyond what `out`'s arrays already hold must be available).
    /// On error `out` is left empty (no vertices, no triangles) and keeps its memory for
    /// the next call.
    pub fn subdivide_into(&mut self, mesh: &HalfedgeMesh, levels: u32, out: &mut LoopMesh) -> Result<(), LoopError> {
        let result = self.run(mesh, levels, out);
        if result.is_err() {
            out.positions.clear();
            out.triangles.clear();
        }
        result
    }

    fn run(&mut self, mesh: &HalfedgeMesh, levels: u32, out: &mut LoopMesh) -> Result<(), LoopError> {
        out.positions.clear();
        out.triangles.clear();
        let largest = check_finite_largest(mesh.positions())?;
        // The output is written into `out`'s arrays: only what they lack must be new.
        let held_bytes =
            output_bytes(out.positions.capacity() as u64, out.triangles.capacity() as u64, size_of::<DVec3>());
        let scratch = &mut self.scratch;
        let mut topology = Topology {
            triangles: take(triangles_of(0, levels, out, scratch)),
            links: take(&mut scratch.links[0]),
            vertex_halfedge: take(&mut scratch.starts[0]),
            ..Topology::default()
        };
        let built = topology
            .rebuild(mesh, &mut scratch.compact)
            .and_then(|()| check_sizes(topology.vertex_count, topology.edge_count, topology.face_count(), levels))
            .and_then(|(vertices, faces)| check_output_memory(vertices, faces, size_of::<DVec3>(), held_bytes));
        if let Err(error) = built {
            park(topology, None, 0, levels, out, scratch);
            return Err(error);
        }
        let mut values: Option<Vec<DVec3>> = None;
        for level in 0..levels {
            let fine = level + 1;
            let last = fine == levels;
            let parity = (fine % 2) as usize;
            let buffers = Buffers {
                values: take(values_of(fine, levels, out, scratch)),
                triangles: take(triangles_of(fine, levels, out, scratch)),
                links: if last { Vec::new() } else { take(&mut scratch.links[parity]) },
                starts: if last { Vec::new() } else { take(&mut scratch.starts[parity]) },
            };
            let step = kernel::step_into(
                &topology,
                values.as_deref().unwrap_or(mesh.positions()),
                &self.rules,
                !last,
                buffers,
            );
            park(topology, values, level, levels, out, scratch);
            values = Some(step.values);
            topology = step.topology;
        }
        // The last level is the output's (`levels - levels` is even); the links and
        // starts of level 0 when nothing was refined.
        match values {
            Some(values) => out.positions = values,
            None => out.positions.extend_from_slice(mesh.positions()),
        }
        let triangles = take(&mut topology.triangles);
        park(topology, None, levels, levels, out, scratch);
        out.triangles = triangles;
        check_no_overflow(&out.positions, largest)?;
        Ok(())
    }
}

/// Where level `level` of `levels` keeps its values.
fn values_of<'a>(level: u32, levels: u32, out: &'a mut LoopMesh, scratch: &'a mut Scratch) -> &'a mut Vec<DVec3> {
    if (levels - level).is_multiple_of(2) { &mut out.positions } else { &mut scratch.values }
}

/// Where level `level` of `levels` keeps its triangles.
fn triangles_of<'a>(level: u32, levels: u32, out: &'a mut LoopMesh, scratch: &'a mut Scratch) -> &'a mut Vec<[u32; 3]> {
    if (levels - level).is_multiple_of(2) { &mut out.triangles } else { &mut scratch.triangles }
}

/// Puts the arrays of a level that is no longer needed back where they came from, so
/// that their memory serves a later level or call. Empty arrays are not put back: a
/// finished level's empty links must not replace the memory kept in their place.
fn park(
    topology: Topology,
    values: Option<Vec<DVec3>>,
    level: u32,
    levels: u32,
    out: &mut LoopMesh,
    scratch: &mut Scratch,
) {
    fn put<T>(place: &mut Vec<T>, vec: Vec<T>) {
        if vec.capacity() > place.capacity() {
            *place = vec;
        }
    }
    let parity = (level % 2) as usize;
    put(triangles_of(level, levels, out, scratch), topology.triangles);
    if let Some(values) = values {
        put(values_of(level, levels, out, scratch), values);
    }
    put(&mut scratch.links[parity], topology.links);
    put(&mut scratch.starts[parity], topology.vertex_halfedge);
}

#[cfg(test)]
mod tests {
    use glam::DVec3;
    use mesh_topo::shapes::{self, CellKind};
    use mesh_topo::{MeshError, PolygonSoup};

    use super::super::{VertexWeights, subdivide};
    use super::*;

    fn meshes() -> Vec<(&'static str, HalfedgeMesh)> {
        let soups = [
            ("tetrahedron", shapes::tetrahedron()),
            ("icosahedron", shapes::icosahedron()),
            ("grid", mesh_topo::testing::scramble(shapes::grid(4, 3, CellKind::Triangles).unwrap(), 7, 0.1)),
            ("torus", mesh_topo::testing::scramble(shapes::torus(5, 4, CellKind::Triangles).unwrap(), 3, 0.1)),
            ("single triangle", PolygonSoup::from_faces(vec![DVec3::ZERO, DVec3::X, DVec3::Y], [[0u32, 1, 2]])),
            (
                "triangle and isolated vertex",
                PolygonSoup::from_faces(vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z], [[0u32, 1, 2]]),
            ),
            // Large enough that its second level takes the parallel path.
            ("large grid", shapes::grid(60, 50, CellKind::Triangles).unwrap()),
        ];
        soups.into_iter().map(|(name, soup)| (name, HalfedgeMesh::from_soup(&soup).unwrap())).collect()
    }

    fn all_options() -> Vec<LoopOptions> {
        let mut options = Vec::new();
        for weights in [VertexWeights::Loop, VertexWeights::Warren] {
            for keep_corners in [false, true] {
                options.push(LoopOptions { weights, keep_corners });
            }
        }
        options
    }

    /// Bitwise equality: `==` on `f64` would let `-0.0 == 0.0` through.
    fn assert_bits(a: &LoopMesh, b: &LoopMesh, what: &str) {
        assert_eq!(a.triangles, b.triangles, "{what}");
        assert_eq!(a.positions.len(), b.positions.len(), "{what}");
        for (i, (p, q)) in a.positions.iter().zip(&b.positions).enumerate() {
            assert_eq!(p.to_array().map(f64::to_bits), q.to_array().map(f64::to_bits), "{what}: vertex {i}");
        }
    }

    #[test]
    fn results_are_bit_identical_to_subdivide_in_any_call_order() {
        let meshes = meshes();
        for options in all_options() {
            // One subdivider and one output for everything: every call reuses the
            // memory of calls on other meshes and levels.
            let mut subdivider = Subdivider::new(options);
            let mut out = LoopMesh::default();
            for levels in [0, 1, 2, 3, 3, 1, 0, 2] {
                for (name, mesh) in &meshes {
                    if *name == "large grid" && levels == 3 {
                        continue;
                    }
                    subdivider.subdivide_into(mesh, levels, &mut out).unwrap();
                    let fresh = subdivide(mesh, levels, &options).unwrap();
                    assert_bits(&out, &fresh, &format!("{name}, level {levels}, {options:?}"));
                }
            }
        }
    }

    #[test]
    fn results_do_not_depend_on_the_thread_count() {
        let (_, mesh) = meshes().pop().unwrap();
        let mut results = Vec::new();
        for threads in [1, 2, 3] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let mut out = LoopMesh::default();
            let mut subdivider = Subdivider::default();
            pool.install(|| {
                subdivider.subdivide_into(&mesh, 2, &mut out).unwrap();
                subdivider.subdivide_into(&mesh, 2, &mut out).unwrap();
            });
            results.push(out);
        }
        assert_bits(&results[0], &results[1], "1 and 2 threads");
        assert_bits(&results[0], &results[2], "1 and 3 threads");
    }

    #[test]
    fn a_repeated_call_reuses_every_array() {
        let (_, mesh) = meshes().pop().unwrap();
        let mut subdivider = Subdivider::default();
        let mut out = LoopMesh::default();
        for levels in [3, 2, 1] {
            subdivider.subdivide_into(&mesh, levels, &mut out).unwrap();
            let addresses = |s: &Subdivider, out: &LoopMesh| {
                let scratch = &s.scratch;
                [
                    out.positions.as_ptr() as usize,
                    out.triangles.as_ptr() as usize,
                    scratch.values.as_ptr() as usize,
                    scratch.triangles.as_ptr() as usize,
                    scratch.links[0].as_ptr() as usize,
                    scratch.links[1].as_ptr() as usize,
                    scratch.starts[0].as_ptr() as usize,
                    scratch.starts[1].as_ptr() as usize,
                    scratch.compact.as_ptr() as usize,
                ]
            };
            let before = addresses(&subdivider, &out);
            subdivider.subdivide_into(&mesh, levels, &mut out).unwrap();
            assert_eq!(addresses(&subdivider, &out), before, "level {levels}");
        }
    }

    #[test]
    fn errors_equal_those_of_subdivide_and_leave_the_output_empty() {
        let mesh = |soup: &PolygonSoup| HalfedgeMesh::from_soup(soup).unwrap();
        let mut nan = mesh(&shapes::octahedron());
        nan.positions_mut()[3].y = f64::NAN;
        let pillow = PolygonSoup::from_faces(vec![DVec3::ZERO, DVec3::X, DVec3::Y], [[0u32, 1, 2], [0, 2, 1]]);
        // A quad mesh with a NaN: the position check comes first, as in `subdivide`.
        let mut quads_nan = mesh(&shapes::cube());
        quads_nan.positions_mut()[5].x = f64::INFINITY;
        let cases = [
            (mesh(&shapes::cube()), 1),
            (nan, 1),
            (quads_nan, 0),
            (mesh(&pillow), 2),
            (mesh(&shapes::tetrahedron()), 20),
        ];
        let mut subdivider = Subdivider::default();
        let mut out = LoopMesh::default();
        let good = mesh(&shapes::icosahedron());
        for (mesh, levels) in cases {
            for before in [0, 2, 3] {
                subdivider.subdivide_into(&good, before, &mut out).unwrap();
                let error = subdivider.subdivide_into(&mesh, levels, &mut out).unwrap_err();
                // Compared as text: a NaN in the error is not equal to itself.
                let expected = subdivide(&mesh, levels, &LoopOptions::default()).unwrap_err();
                assert_eq!(format!("{error:?}"), format!("{expected:?}"));
                assert_eq!((out.vertex_count(), out.face_count()), (0, 0));
                // And the subdivider still works.
                subdivider.subdivide_into(&good, 2, &mut out).unwrap();
                assert_bits(&out, &subdivide(&good, 2, &LoopOptions::default()).unwrap(), "after an error");
            }
        }
        let too_large = subdivider.subdivide_into(&good, 20, &mut out).unwrap_err();
        assert!(matches!(too_large, LoopError::Mesh(MeshError::TooLarge { .. })));
    }

    #[test]
    fn an_output_that_cannot_fit_in_memory_is_refused_before_any_work() {
        // Thirteen levels of the icosahedron: 1.3G triangles, 32 GB (near the most the
        // index range allows: the level refined last may have at most 2^29 edges).
        let icosahedron = HalfedgeMesh::from_soup(&shapes::icosahedron()).unwrap();
        let (vertices, faces) = check_sizes(12, 30, 20, 13).unwrap();
        let needed = output_bytes(vertices, faces, size_of::<DVec3>());
        assert!(needed > 32_000_000_000, "{needed}");
        let mut subdivider = Subdivider::default();
        let mut out = LoopMesh::default();
        subdivider.subdivide_into(&icosahedron, 3, &mut out).unwrap();
        let held = output_bytes(out.positions.capacity() as u64, out.triangles.capacity() as u64, size_of::<DVec3>());
        assert!(held > 0);
        // Tried only where it is sure to be refused (4 GiB to spare: the memory is read
        // again by the call); elsewhere the call would make the 32 GB.
        match mesh_topo::memory::available_bytes() {
            Some(available) if u128::from(available) + (4 << 30) < needed - held => {
                let error = subdivider.subdivide_into(&icosahedron, 13, &mut out).unwrap_err();
                let LoopError::Mesh(MeshError::OutOfMemory { what, needed_bytes, .. }) = error else {
                    panic!("refused for its memory: {error}");
                };
                // What the output's arrays already hold is not asked for again.
                assert_eq!((what, needed_bytes), ("Loop output", needed - held));
                assert_eq!((out.vertex_count(), out.face_count()), (0, 0));
                subdivider.subdivide_into(&icosahedron, 1, &mut out).unwrap();
                assert_eq!(out.face_count(), 80);
            }
            _ => eprintln!("this machine may have room for {needed} bytes: the refusal is not tried"),
        }
    }
}
