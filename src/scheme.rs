//! One name for every surface subdivision scheme of the workspace, so that a comparison
//! over all schemes is a loop rather than a `match` at every call site.

use std::fmt;
use std::str::FromStr;

use mesh_topo::{HalfedgeMesh, PolygonSoup};
use subdiv_doo::{BoundaryRule, DooOptions, FaceRule};
use subdiv_loop::forward::{LoopOptions, VertexWeights};
use subdiv_loop::mband::TernaryOptions;

use crate::{Error, memory};

/// A surface subdivision scheme with its default parameters.
///
/// ```
/// use multires::prelude::*;
///
/// let cube = HalfedgeMesh::from_soup(&shapes::cube())?;
/// for scheme in SurfaceScheme::ALL.into_iter().filter(|s| s.accepts_polygons()) {
///     let fine = scheme.subdivide(&cube, 2)?;
///     println!("{scheme}: {} faces", fine.face_count());
/// }
/// # Ok::<(), multires::Error>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum SurfaceScheme {
    /// Loop subdivision with Loop's original vertex weights (OpenSubdiv's, CGAL's and
    /// OpenMesh's choice).
    Loop,
    /// Loop subdivision with Warren's simplified weights (libigl's choice).
    LoopWarren,
    /// Ternary (1-to-9) Loop subdivision.
    TernaryLoop,
    /// Quaternary (1-to-16) Loop subdivision.
    QuaternaryLoop,
    /// Doo-Sabin subdivision with the original weights.
    DooSabin,
    /// Doo-Sabin's "simple" variant (vertex, edge midpoints and centroid averaged).
    DooSimple,
    /// The centroid contraction `a d + (1 - a) v`, `a = 1/2`, of the reverse Doo-Sabin
    /// paper (not C1 on faces of four or more sides).
    DooCentroid,
}

/// How many vertices, edges and faces a mesh has (see
/// [`SurfaceScheme::closed_counts`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct ElementCounts {
    /// Vertices.
    pub vertices: usize,
    /// Edges (each counted once).
    pub edges: usize,
    /// Faces.
    pub faces: usize,
}

impl ElementCounts {
    /// The counts of `mesh`.
    pub fn of(mesh: &HalfedgeMesh) -> Self {
        ElementCounts { vertices: mesh.vertex_count(), edges: mesh.edge_count(), faces: mesh.face_count() }
    }
}

impl SurfaceScheme {
    /// Every scheme, in a fixed order.
    pub const ALL: [SurfaceScheme; 7] = [
        SurfaceScheme::Loop,
        SurfaceScheme::LoopWarren,
        SurfaceScheme::TernaryLoop,
        SurfaceScheme::QuaternaryLoop,
        SurfaceScheme::DooSabin,
        SurfaceScheme::DooSimple,
        SurfaceScheme::DooCentroid,
    ];

    /// The name used on the command line (`loop`, `doo-sabin`, ...).
    pub fn name(self) -> &'static str {
        match self {
            SurfaceScheme::Loop => "loop",
            SurfaceScheme::LoopWarren => "loop-warren",
            SurfaceScheme::TernaryLoop => "ternary-loop",
            SurfaceScheme::QuaternaryLoop => "quaternary-loop",
            SurfaceScheme::DooSabin => "doo-sabin",
            SurfaceScheme::DooSimple => "doo-simple",
            SurfaceScheme::DooCentroid => "doo-centroid",
        }
    }

    /// True for the schemes that take polygons of any size; the Loop family takes
    /// triangles only.
    pub fn accepts_polygons(self) -> bool {
        matches!(self, SurfaceScheme::DooSabin | SurfaceScheme::DooSimple | SurfaceScheme::DooCentroid)
    }

    /// True if [`decompose`](crate::decompose) can reverse this scheme (Loop with either
    /// weights and the three Doo-Sabin rules; M-band Loop has no reverse yet).
    ///
    /// ```
    /// use multires::prelude::*;
    ///
    /// // A mesh with Loop connectivity: `decompose` succeeds exactly for the reversible schemes.
    /// let octahedron = HalfedgeMesh::from_soup(&shapes::octahedron())?;
    /// let fine = HalfedgeMesh::from_soup(&SurfaceScheme::Loop.subdivide(&octahedron, 1)?)?;
    /// for scheme in SurfaceScheme::ALL.into_iter().filter(|s| !s.accepts_polygons()) {
    ///     let result = decompose(&fine, scheme, Depth::Levels(1));
    ///     assert_eq!(result.is_ok(), scheme.is_reversible(), "{scheme}");
    /// }
    /// let error = decompose(&fine, SurfaceScheme::TernaryLoop, Depth::Max).unwrap_err();
    /// assert!(matches!(error, Error::NotReversible { scheme: SurfaceScheme::TernaryLoop }));
    /// # Ok::<(), multires::Error>(())
    /// ```
    pub fn is_reversible(self) -> bool {
        !matches!(self, SurfaceScheme::TernaryLoop | SurfaceScheme::QuaternaryLoop)
    }

    /// Number of output faces of `levels` steps on a closed mesh with `vertices`,
    /// `edges` and `faces`: `4^k F`, `9^k F`, `16^k F` for the Loop family; for
    /// Doo-Sabin one face per face, edge and vertex at each step (`F' = F + E + V`,
    /// `V' = 2E`, `E' = 4E`), so benchmarks can state throughput before running.
    /// The faces of [`closed_counts`](Self::closed_counts), which saturates at
    /// `usize::MAX`.
    ///
    /// ```
    /// use multires::prelude::*;
    ///
    /// let cube = HalfedgeMesh::from_soup(&shapes::cube())?;
    /// let (v, e, f) = (cube.vertex_count(), cube.edge_count(), cube.face_count());
    /// // Doo-Sabin: 6 -> 6 + 12 + 8 = 26 -> 26 + 48 + 24 = 98 faces, as subdivision makes them.
    /// assert_eq!(SurfaceScheme::DooSabin.closed_face_count(v, e, f, 2), 98);
    /// assert_eq!(SurfaceScheme::DooSabin.subdivide(&cube, 2)?.face_count(), 98);
    /// // The Loop family on the octahedron (8 faces): M^2 faces per face, M = 2, 3, 4.
    /// let schemes = [SurfaceScheme::Loop, SurfaceScheme::TernaryLoop, SurfaceScheme::QuaternaryLoop];
    /// assert_eq!(schemes.map(|s| s.closed_face_count(6, 12, 8, 1)), [32, 72, 128]);
    /// let octahedron = HalfedgeMesh::from_soup(&shapes::octahedron())?;
    /// assert_eq!(SurfaceScheme::TernaryLoop.subdivide(&octahedron, 1)?.face_count(), 72);
    /// # Ok::<(), multires::Error>(())
    /// ```
    pub fn closed_face_count(self, vertices: usize, edges: usize, faces: usize, levels: u32) -> usize {
        self.closed_counts(ElementCounts { vertices, edges, faces }, levels).faces
    }

    /// The vertices, edges and faces after `levels` steps of this scheme on a mesh of
    /// `counts`, computed before any work (to state throughput, or to see whether the
    /// output fits in memory). Each entry saturates at `usize::MAX`.
    ///
    /// The Loop family splits every edge into `M` (M = 2, 3, 4) and every triangle into
    /// `M^2`: `V' = V + (M-1) E + (M-1)(M-2)/2 F`, `E' = M E + 3 M(M-1)/2 F`,
    /// `F' = M^2 F`, exact on any triangle mesh, closed or not. A Doo-Sabin step makes one
    /// vertex per face corner and one face per face, edge and vertex: on a closed mesh
    /// (whose corners are `2E`) `V' = 2E`, `E' = 4E`, `F' = F + E + V`. On a mesh with a
    /// boundary these are upper bounds under the default (shrinking) boundary rule, which
    /// makes no faces at boundary edges and vertices.
    ///
    /// ```
    /// use multires::prelude::*;
    /// use multires::ElementCounts;
    ///
    /// // An open mesh (a 4 x 4 triangle grid): Loop's counts are exact.
    /// let grid = shapes::grid(4, 4, shapes::CellKind::Triangles)?;
    /// let grid = HalfedgeMesh::from_soup(&grid)?;
    /// let counts = ElementCounts::of(&grid);
    /// let fine = HalfedgeMesh::from_soup(&SurfaceScheme::Loop.subdivide(&grid, 2)?)?;
    /// assert_eq!(SurfaceScheme::Loop.closed_counts(counts, 2), ElementCounts::of(&fine));
    /// // Nothing overflows: 4^40 faces per face saturate.
    /// assert_eq!(SurfaceScheme::Loop.closed_counts(counts, 40).faces, usize::MAX);
    /// # Ok::<(), multires::Error>(())
    /// ```
    pub fn closed_counts(self, counts: ElementCounts, levels: u32) -> ElementCounts {
        let mut counts = counts;
        for _ in 0..levels {
            let next = self.counts_after_step(counts);
            // A fixed point (a mesh that does not grow, or counts saturated): every further
            // step gives it again, so a huge level count costs nothing more.
            if next == counts {
                break;
            }
            counts = next;
        }
        counts
    }

    /// [`closed_counts`](Self::closed_counts) of one step.
    fn counts_after_step(self, counts: ElementCounts) -> ElementCounts {
        let ElementCounts { vertices: v, edges: e, faces: f } = counts;
        let arity = match self {
            SurfaceScheme::Loop | SurfaceScheme::LoopWarren => 2,
            SurfaceScheme::TernaryLoop => 3,
            SurfaceScheme::QuaternaryLoop => 4,
            SurfaceScheme::DooSabin | SurfaceScheme::DooSimple | SurfaceScheme::DooCentroid => {
                // Every corner becomes a vertex (V' = 2E) of valence 4 (E' = 2V' = 4E).
                return ElementCounts {
                    vertices: e.saturating_mul(2),
                    edges: e.saturating_mul(4),
                    faces: f.saturating_add(e).saturating_add(v),
                };
            }
        };
        // The member crate's recurrence, on which its own size checks run.
        let [vertices, edges, faces] = subdiv_loop::mband::counts_after_step(arity, [v, e, f].map(|n| n as u64))
            .map(|n| usize::try_from(n).unwrap_or(usize::MAX));
        ElementCounts { vertices, edges, faces }
    }

    /// Bytes an output soup of `counts` holds (see [`Self::closed_counts`]): three `f64`
    /// per vertex, one `u32` index per face corner (3 per triangle for the Loop family,
    /// twice the edges of a closed mesh for Doo-Sabin) and one offset per face. The least
    /// the output takes: making it takes more for a while.
    ///
    /// ```
    /// use multires::prelude::*;
    /// use multires::ElementCounts;
    ///
    /// let octahedron = HalfedgeMesh::from_soup(&shapes::octahedron())?;
    /// let fine = SurfaceScheme::Loop.subdivide(&octahedron, 1)?;
    /// let counts = SurfaceScheme::Loop.closed_counts(ElementCounts::of(&octahedron), 1);
    /// let arrays = 24 * fine.vertex_count() + 4 * fine.indices.len() + 4 * fine.offsets.len();
    /// assert_eq!(SurfaceScheme::Loop.output_bytes(counts), arrays as u128);
    /// # Ok::<(), multires::Error>(())
    /// ```
    pub fn output_bytes(self, counts: ElementCounts) -> u128 {
        memory::soup_bytes(self, counts)
    }

    /// Whether the output of `levels` steps on a mesh of `input` ([`Self::output_bytes`]
    /// of [`Self::closed_counts`]) fits in `available` bytes; if not, the error names
    /// the most levels that would fit. An output past the `u32` index range passes: the
    /// member crates refuse it at once, naming their limit. See [`crate::memory`] for an
    /// example.
    ///
    /// # Errors
    /// [`OutputTooLarge`](memory::OutputTooLarge) when it does not fit.
    pub fn check_output_fits(
        self,
        input: ElementCounts,
        levels: u32,
        available: u64,
    ) -> Result<(), memory::OutputTooLarge> {
        memory::output_fits(self, input, levels, available)
    }

    /// `levels` steps of this scheme on `mesh`, with default parameters.
    ///
    /// ```
    /// use multires::prelude::*;
    ///
    /// // One Loop step: every triangle into four, one new vertex per edge.
    /// let tetrahedron = HalfedgeMesh::from_soup(&shapes::tetrahedron())?;
    /// let fine = SurfaceScheme::Loop.subdivide(&tetrahedron, 1)?;
    /// assert_eq!((fine.face_count(), fine.vertex_count()), (16, 4 + 6));
    /// assert_eq!(fine.indices.len(), 3 * 16); // all triangles
    /// // The Loop family takes triangles only; Doo-Sabin takes the cube's quads.
    /// let cube = HalfedgeMesh::from_soup(&shapes::cube())?;
    /// assert!(!SurfaceScheme::Loop.accepts_polygons());
    /// assert!(matches!(SurfaceScheme::Loop.subdivide(&cube, 1), Err(Error::Loop(_))));
    /// assert_eq!(SurfaceScheme::DooSabin.subdivide(&cube, 1)?.face_count(), 6 + 12 + 8);
    /// # Ok::<(), multires::Error>(())
    /// ```
    ///
    /// An output that would not fit in the memory available is refused before any work
    /// ([`Error::OutputTooLarge`]): outputs above 256 MiB are checked against what the
    /// system says it has ([`memory::available_bytes`]), smaller ones are made without
    /// asking.
    ///
    /// # Errors
    /// The member crate's error ([`Error::Loop`] or [`Error::Doo`]): a non-triangle face
    /// for the Loop family, non-finite positions, a mesh without faces;
    /// [`Error::OutputTooLarge`].
    pub fn subdivide(self, mesh: &HalfedgeMesh, levels: u32) -> Result<PolygonSoup, Error> {
        self.subdivide_with(mesh, levels, &Boundaries::default())
    }

    /// `levels` steps of this scheme on `mesh` with the boundary rules of `boundaries`.
    ///
    /// ```
    /// use multires::prelude::*;
    ///
    /// // An open 3 x 3 quad grid: Doo-Sabin's default rule shrinks it, the Chaikin rule
    /// // keeps a face ring along the boundary.
    /// let grid = HalfedgeMesh::from_soup(&shapes::grid(3, 3, shapes::CellKind::Quads)?)?;
    /// let shrunk = SurfaceScheme::DooSabin.subdivide(&grid, 1)?;
    /// let ringed = SurfaceScheme::DooSabin.subdivide_with(&grid, 1, &Boundaries::chaikin())?;
    /// assert_eq!(shrunk.face_count(), 9 + 12 + 4);
    /// // Plus one face per boundary edge and one per boundary vertex (12 of each).
    /// assert_eq!(ringed.face_count(), 9 + 12 + 4 + 12 + 12);
    /// # Ok::<(), multires::Error>(())
    /// ```
    ///
    /// # Errors
    /// As [`Self::subdivide`], and [`Error::NotApplicable`] for a boundary option of
    /// another family (keeping corners for Doo-Sabin or ternary Loop, the Chaikin rule for
    /// the Loop family).
    pub fn subdivide_with(
        self,
        mesh: &HalfedgeMesh,
        levels: u32,
        boundaries: &Boundaries,
    ) -> Result<PolygonSoup, Error> {
        boundaries.check(self)?;
        self.check_available_memory(ElementCounts::of(mesh), levels)?;
        let soup = match self {
            SurfaceScheme::Loop | SurfaceScheme::LoopWarren => {
                let options = self.loop_options_with(boundaries).expect("internal: Loop family");
                subdiv_loop::forward::subdivide(mesh, levels, &options)?.into_soup()
            }
            SurfaceScheme::TernaryLoop => {
                subdiv_loop::mband::ternary_subdivide(mesh, levels, &TernaryOptions::default())?.into_soup()
            }
            SurfaceScheme::QuaternaryLoop => {
                // Quaternary Loop has Loop's weights; only the corner rule is an option.
                let options = SurfaceScheme::Loop.loop_options_with(boundaries).expect("internal: Loop");
                subdiv_loop::mband::quaternary_subdivide(mesh, levels, &options)?.into_soup()
            }
            SurfaceScheme::DooSabin | SurfaceScheme::DooSimple | SurfaceScheme::DooCentroid => {
                let rule = self.doo_rule().expect("internal: Doo-Sabin family");
                let options = DooOptions::new(rule, levels).with_boundary(boundaries.doo);
                subdiv_doo::subdivide(mesh, &options)?.into_soup()
            }
        };
        Ok(soup)
    }

    /// [`Self::check_output_fits`] against what the system has available now
    /// ([`memory::available_bytes`]), as [`Self::subdivide`] checks before any work: an
    /// output up to 256 MiB passes without asking the system, and where it cannot be
    /// read nothing is refused.
    ///
    /// ```
    /// use multires::prelude::*;
    /// use multires::ElementCounts;
    ///
    /// let bunny = ElementCounts { vertices: 1839, edges: 5511, faces: 3674 };
    /// // Two Loop levels (746 KB): made without asking the system.
    /// assert!(SurfaceScheme::Loop.check_available_memory(bunny, 2).is_ok());
    /// // Five quaternary levels: 108 GB of soup.
    /// match SurfaceScheme::QuaternaryLoop.check_available_memory(bunny, 5) {
    ///     Ok(()) => println!("this machine has room for it"),
    ///     Err(refused) => println!("{refused}"), // ".. (at most 4 level(s) fit)" or fewer
    /// }
    /// ```
    ///
    /// # Errors
    /// [`OutputTooLarge`](memory::OutputTooLarge) when the output does not fit.
    pub fn check_available_memory(self, input: ElementCounts, levels: u32) -> Result<(), memory::OutputTooLarge> {
        if self.output_bytes(self.closed_counts(input, levels)) <= mesh_topo::memory::ALWAYS_FITS_BYTES {
            return Ok(());
        }
        match memory::available_bytes() {
            Some(available) => self.check_output_fits(input, levels, available),
            None => Ok(()),
        }
    }

    /// The per-face rule of a Doo-Sabin-family scheme, `None` for the Loop family.
    ///
    /// ```
    /// use multires::doo::{DooOptions, FaceRule, subdivide};
    /// use multires::prelude::*;
    ///
    /// assert_eq!(SurfaceScheme::DooCentroid.doo_rule(), Some(FaceRule::CENTROID_HALF));
    /// assert_eq!(SurfaceScheme::Loop.doo_rule(), None);
    /// // A Doo-Sabin scheme is the member crate's subdivision with this rule.
    /// let cube = HalfedgeMesh::from_soup(&shapes::cube())?;
    /// let rule = SurfaceScheme::DooSimple.doo_rule().expect("a Doo-Sabin scheme");
    /// let direct = subdivide(&cube, &DooOptions::new(rule, 2))?.into_soup();
    /// assert_eq!(SurfaceScheme::DooSimple.subdivide(&cube, 2)?, direct);
    /// # Ok::<(), multires::Error>(())
    /// ```
    pub fn doo_rule(self) -> Option<FaceRule> {
        match self {
            SurfaceScheme::DooSabin => Some(FaceRule::DooSabin),
            SurfaceScheme::DooSimple => Some(FaceRule::Simple),
            SurfaceScheme::DooCentroid => Some(FaceRule::CENTROID_HALF),
            _ => None,
        }
    }

    /// The Loop rules of a reversible Loop-family scheme, `None` otherwise.
    ///
    /// ```
    /// use multires::loop_subdiv::forward::{VertexWeights, subdivide};
    /// use multires::prelude::*;
    ///
    /// let options = SurfaceScheme::LoopWarren.loop_options().expect("a reversible Loop scheme");
    /// assert_eq!((options.weights, options.keep_corners), (VertexWeights::Warren, false));
    /// assert_eq!(SurfaceScheme::TernaryLoop.loop_options(), None);
    /// assert_eq!(SurfaceScheme::DooSabin.loop_options(), None);
    /// // A Loop scheme is the member crate's subdivision with these options.
    /// let octahedron = HalfedgeMesh::from_soup(&shapes::octahedron())?;
    /// let direct = subdivide(&octahedron, 2, &options)?.into_soup();
    /// assert_eq!(SurfaceScheme::LoopWarren.subdivide(&octahedron, 2)?, direct);
    /// # Ok::<(), multires::Error>(())
    /// ```
    pub fn loop_options(self) -> Option<LoopOptions> {
        self.loop_options_with(&Boundaries::default())
    }

    /// [`Self::loop_options`] with the corner rule of `boundaries`.
    pub(crate) fn loop_options_with(self, boundaries: &Boundaries) -> Option<LoopOptions> {
        let weights = match self {
            SurfaceScheme::Loop => VertexWeights::Loop,
            SurfaceScheme::LoopWarren => VertexWeights::Warren,
            _ => return None,
        };
        Some(LoopOptions { weights, keep_corners: boundaries.keep_corners })
    }
}

/// What the surface schemes do at the boundary of an open mesh. The default is each
/// family's usual rule (Loop: boundary curves are cubic B-splines through smoothed
/// corners; Doo-Sabin: no faces on boundary edges and vertices, so that open meshes
/// shrink, as in CGAL). Each option belongs to one family, and the other families refuse
/// it ([`Error::NotApplicable`]) rather than ignore it.
///
/// ```
/// use multires::prelude::*;
///
/// assert_eq!(Boundaries::default().doo, multires::doo::BoundaryRule::Shrink);
/// assert!(Boundaries::keep_corners().keep_corners);
/// assert_eq!(Boundaries::chaikin().doo, multires::doo::BoundaryRule::Chaikin);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub struct Boundaries {
    /// Loop and quaternary Loop: boundary vertices with one incident face (valence 2)
    /// stay where they are.
    pub keep_corners: bool,
    /// Doo-Sabin family: [`BoundaryRule::Shrink`] (default) or [`BoundaryRule::Chaikin`]
    /// (a face ring along the boundary, which then follows Chaikin's corner cutting).
    pub doo: BoundaryRule,
}

impl Boundaries {
    /// Loop's corner rule: valence-2 boundary vertices stay fixed.
    pub fn keep_corners() -> Self {
        Self { keep_corners: true, ..Self::default() }
    }

    /// Doo-Sabin's Chaikin boundary rule.
    pub fn chaikin() -> Self {
        Self { doo: BoundaryRule::Chaikin, ..Self::default() }
    }

    /// [`Error::NotApplicable`] if an option is set that `scheme` does not have.
    pub(crate) fn check(&self, scheme: SurfaceScheme) -> Result<(), Error> {
        let corners_apply =
            matches!(scheme, SurfaceScheme::Loop | SurfaceScheme::LoopWarren | SurfaceScheme::QuaternaryLoop);
        if self.keep_corners && !corners_apply {
            return Err(Error::NotApplicable { scheme, option: "keep_corners (Loop and quaternary Loop only)" });
        }
        if self.doo != BoundaryRule::Shrink && scheme.doo_rule().is_none() {
            return Err(Error::NotApplicable { scheme, option: "the Chaikin boundary rule (Doo-Sabin family only)" });
        }
        Ok(())
    }
}

impl fmt::Display for SurfaceScheme {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for SurfaceScheme {
    type Err = Error;

    /// Parses a command-line name (`loop`, `loop-warren`, `ternary-loop`,
    /// `quaternary-loop`, `doo-sabin`, `doo-simple`, `doo-centroid`).
    fn from_str(name: &str) -> Result<Self, Error> {
        SurfaceScheme::ALL.into_iter().find(|s| s.name() == name).ok_or_else(|| Error::UnknownScheme {
            name: name.to_owned(),
            known: SurfaceScheme::ALL.map(SurfaceScheme::name).join(", "),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mesh_topo::shapes;

    #[test]
    fn names_round_trip() {
        for scheme in SurfaceScheme::ALL {
            assert_eq!(scheme.name().parse::<SurfaceScheme>().unwrap(), scheme);
        }
        let error = "catmull-clark".parse::<SurfaceScheme>().unwrap_err().to_string();
        assert!(error.contains("catmull-clark") && error.contains("doo-sabin"), "{error}");
    }

    #[test]
    fn predicted_face_counts_match_subdivision() {
        let octahedron = HalfedgeMesh::from_soup(&shapes::octahedron()).unwrap();
        let cube = HalfedgeMesh::from_soup(&shapes::cube()).unwrap();
        for scheme in SurfaceScheme::ALL {
            let mesh = if scheme.accepts_polygons() { &cube } else { &octahedron };
            for levels in 0..3 {
                let fine = scheme.subdivide(mesh, levels).unwrap();
                let expected =
                    scheme.closed_face_count(mesh.vertex_count(), mesh.edge_count(), mesh.face_count(), levels);
                assert_eq!(fine.face_count(), expected, "{scheme} level {levels}");
                // Closed output: Euler characteristic 2 is kept.
                let fine_mesh = HalfedgeMesh::from_soup(&fine).unwrap();
                assert_eq!(fine_mesh.topology_stats().euler, 2, "{scheme} level {levels}");
            }
        }
    }

    #[test]
    fn predicted_counts_match_subdivision() {
        let closed = [shapes::octahedron(), shapes::cube(), shapes::torus(6, 4, shapes::CellKind::Quads).unwrap()];
        let open = [
            shapes::grid(3, 2, shapes::CellKind::Triangles).unwrap(),
            shapes::grid(3, 3, shapes::CellKind::Quads).unwrap(),
        ];
        for scheme in SurfaceScheme::ALL {
            for (soup, is_closed) in closed.iter().map(|s| (s, true)).chain(open.iter().map(|s| (s, false))) {
                let mesh = HalfedgeMesh::from_soup(soup).unwrap();
                if !scheme.accepts_polygons() && soup.faces().any(|f| f.len() != 3) {
                    continue;
                }
                for levels in 0..3 {
                    let fine = HalfedgeMesh::from_soup(&scheme.subdivide(&mesh, levels).unwrap()).unwrap();
                    let (predicted, made) =
                        (scheme.closed_counts(ElementCounts::of(&mesh), levels), ElementCounts::of(&fine));
                    if is_closed || !scheme.accepts_polygons() {
                        // Exact: the Loop family on any mesh, Doo-Sabin on closed ones.
                        assert_eq!(predicted, made, "{scheme} level {levels}");
                    } else {
                        // An open mesh shrinks under Doo-Sabin: an upper bound.
                        assert!(made.vertices <= predicted.vertices && made.edges <= predicted.edges, "{scheme}");
                        assert!(made.faces <= predicted.faces, "{scheme} level {levels}");
                    }
                }
            }
        }
    }

    #[test]
    fn predicted_counts_saturate() {
        let counts = ElementCounts { vertices: 1 << 40, edges: 3 << 40, faces: 2 << 40 };
        for scheme in SurfaceScheme::ALL {
            let far = scheme.closed_counts(counts, 64);
            assert_eq!((far.edges, far.faces), (usize::MAX, usize::MAX), "{scheme}");
            assert_eq!(scheme.closed_face_count(5, 9, 6, u32::MAX), usize::MAX, "{scheme}");
        }
    }

    #[test]
    fn an_output_that_cannot_fit_is_refused_before_any_work() {
        // 2500 vertices, 7500 edges, 5000 triangles: nine Doo-Sabin levels make 43 GB,
        // within the index range (3.9G corners).
        let torus = HalfedgeMesh::from_soup(&shapes::torus(50, 50, shapes::CellKind::Triangles).unwrap()).unwrap();
        let counts = ElementCounts::of(&torus);
        let scheme = SurfaceScheme::DooSabin;
        let fine = scheme.closed_counts(counts, 9);
        let needed = scheme.output_bytes(fine);
        assert_eq!(fine.edges, 7500 << 18);
        assert!(needed > 40_000_000_000, "{needed}");
        // Made only where it is sure to be refused (with room to spare should the memory
        // available change before `subdivide` reads it again); elsewhere only predicted.
        match memory::available_bytes() {
            Some(available) if u128::from(available) < needed / 3 * 2 => {
                let Err(Error::OutputTooLarge(refused)) = scheme.subdivide(&torus, 9) else {
                    panic!("refused");
                };
                assert_eq!(
                    (refused.scheme, refused.levels, refused.counts, refused.needed_bytes),
                    (scheme, 9, fine, needed)
                );
                let fitting = refused.fitting_levels.expect("the input fits");
                assert!(fitting < 9);
                assert!(scheme.check_output_fits(counts, fitting, refused.available_bytes).is_ok());
                assert!(scheme.check_output_fits(counts, fitting + 1, refused.available_bytes).is_err());
                let message = refused.to_string();
                assert!(
                    message.starts_with(&format!("doo-sabin x9 would make up to {} vertices", fine.vertices)),
                    "{message}"
                );
            }
            _ => eprintln!("this machine may have room for {needed} bytes: the refusal is not tried"),
        }
        // Small outputs are made without asking the system.
        assert!(scheme.check_available_memory(counts, 2).is_ok());
    }

    #[test]
    fn loop_family_rejects_quads_naming_the_face() {
        let cube = HalfedgeMesh::from_soup(&shapes::cube()).unwrap();
        for scheme in SurfaceScheme::ALL.into_iter().filter(|s| !s.accepts_polygons()) {
            let error = scheme.subdivide(&cube, 1).unwrap_err();
            assert!(error.to_string().contains("face"), "{scheme}: {error}");
        }
    }

    #[test]
    fn boundary_options_reach_the_member_crates_and_other_families_refuse_them() {
        let triangles = HalfedgeMesh::from_soup(&shapes::grid(3, 2, shapes::CellKind::Triangles).unwrap()).unwrap();
        let quads = HalfedgeMesh::from_soup(&shapes::grid(3, 2, shapes::CellKind::Quads).unwrap()).unwrap();
        // Loop with fixed corners: the same output as the member crate's option.
        for scheme in [SurfaceScheme::Loop, SurfaceScheme::LoopWarren, SurfaceScheme::QuaternaryLoop] {
            let fixed = scheme.subdivide_with(&triangles, 2, &Boundaries::keep_corners()).unwrap();
            let smoothed = scheme.subdivide(&triangles, 2).unwrap();
            let options = LoopOptions { keep_corners: true, ..scheme.loop_options().unwrap_or_default() };
            let direct = match scheme {
                SurfaceScheme::QuaternaryLoop => subdiv_loop::mband::quaternary_subdivide(&triangles, 2, &options),
                _ => subdiv_loop::forward::subdivide(&triangles, 2, &options),
            }
            .unwrap()
            .into_soup();
            assert_eq!(fixed, direct, "{scheme}");
            assert_ne!(fixed.positions, smoothed.positions, "{scheme}: the corners move without the option");
        }
        // Doo-Sabin with the Chaikin rule: the member crate's output.
        for scheme in SurfaceScheme::ALL.into_iter().filter(|s| s.accepts_polygons()) {
            let ringed = scheme.subdivide_with(&quads, 2, &Boundaries::chaikin()).unwrap();
            let options = DooOptions::new(scheme.doo_rule().unwrap(), 2).with_boundary(BoundaryRule::Chaikin);
            assert_eq!(ringed, subdiv_doo::subdivide(&quads, &options).unwrap().into_soup(), "{scheme}");
        }
        // Each option is refused by the families that do not have it, naming the option.
        for scheme in SurfaceScheme::ALL {
            let mesh = if scheme.accepts_polygons() { &quads } else { &triangles };
            let chaikin = scheme.subdivide_with(mesh, 1, &Boundaries::chaikin());
            assert_eq!(chaikin.is_ok(), scheme.accepts_polygons(), "{scheme}");
            let corners = scheme.subdivide_with(mesh, 1, &Boundaries::keep_corners());
            let corners_apply =
                matches!(scheme, SurfaceScheme::Loop | SurfaceScheme::LoopWarren | SurfaceScheme::QuaternaryLoop);
            assert_eq!(corners.is_ok(), corners_apply, "{scheme}");
            for result in [chaikin, corners] {
                if let Err(error) = result {
                    assert!(matches!(error, Error::NotApplicable { .. }), "{scheme}: {error}");
                    assert!(error.to_string().starts_with(&format!("{scheme} does not take ")), "{error}");
                }
            }
        }
    }
}
