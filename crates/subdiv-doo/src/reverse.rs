//! Reverse Doo-Sabin: coarse mesh plus local details from any mesh with the connectivity
//! of one Doo-Sabin step, with exact reconstruction.
//!
//! Method of Mahdavi-Amiri and Samavati (the reverse-Doo paper; specification §5):
//!
//! 1. **Find the F_F faces** by a breadth-first search over the graph whose nodes are the
//!    F_F faces and whose edges are the F_E quads: from an F_F face, the face across each
//!    of its edges must be a quad, and the face across that quad's opposite edge is the
//!    next F_F face. Every fine vertex must end up a corner of exactly one F_F face.
//! 2. **Expand** every F_F face by the inverse of the per-face rule
//!    ([`FaceRule::inverse_weights`]): one *candidate* for a coarse vertex per fine vertex.
//! 3. **Group the candidates**: the candidates of one coarse vertex are the corners of
//!    the F_F faces around it, linked across the F_E quads (the candidate graph; its
//!    connected components are found with union-find).
//! 4. **Coarse vertex = mean of its `r` candidates** (the local least-squares choice);
//!    **details** = the offsets `d_i` of the candidates from the mean, stored in the basis
//!    of the null space of `(1, .., 1)` given by the columns `E_j - E_{j+1}`: the `r - 1`
//!    prefix sums `e_j = d_1 + .. + d_j`. The candidates of a vertex are ordered by their
//!    coarse corner index (face by face, corner by corner), so the coarse mesh alone
//!    fixes the order. Coarse vertices plus details are exactly as many 3-vectors as the
//!    fine mesh has vertices.
//!
//! Reconstruction undoes each step: `d_1 = e_1`, `d_j = e_j - e_{j-1}`, `d_r = -e_{r-1}`,
//! candidates `v + d_i`, then the *forward* rule applied to each coarse face's own
//! candidates (not to the means) gives back every fine vertex; the fine faces are the
//! Doo-Sabin connectivity of the coarse mesh, mapped to the input's vertex and face
//! order by a stored permutation. Everything is exact up to rounding: a mesh that was not
//! produced by Doo-Sabin (moved vertices, noise) is reconstructed to about `1e-15`
//! relative, and `reverse(doo(C))` gives `C` with details at rounding level.
//!
//! # Validation
//! The interpretation is checked completely: after the search, the Doo-Sabin
//! connectivity of the coarse mesh is matched face by face against the input (F_E quads
//! and F_V faces included), and the coarse mesh itself must be a manifold polygon mesh.
//! Any mismatch is a [`DooError::NotDooConnectivity`] naming the input face where the
//! structure breaks; nothing is returned half-done.
//!
//! # Seed faces and the choice among interpretations
//! The answer is not unique: on a closed mesh, starting the search from an F_V face finds
//! all F_V faces and reverses to the *dual* coarse mesh, just as valid topologically; on
//! all-quad meshes even the F_E quads can play the role of F_F faces. A search needs one
//! seed per connected component. [`ReverseOptions::seeds`] may name them; for every
//! component without one, the *automatic* mode tries the classes in turn (the lowest
//! face of the component as an F_F face, else the first of its neighbours that works,
//! else of their neighbours, since an F_F face is at most two faces away; then the
//! lowest face that this reading calls an F_V face; then the lowest F_E quad, and if
//! that reading is valid, the lowest face it calls an F_V face: where the mesh is all
//! quads the F_E quads form two classes, the two directions of a quad grid, and the
//! true reading may be either) and keeps
//! the valid interpretation with the **smallest total squared detail norm**
//! `Σ |d_i|²`, the earliest on ties. An interpretation whose details are all zero to
//! `1e-12` of the component's size is accepted at once (nothing can beat it). The sum of
//! a later reading runs over its coarse vertices in order (each summed as the result sums
//! it, so that a reading's sum is the detail energy of its result, bit for bit) and stops
//! as soon as it reaches the smallest total found before: that reading cannot win (ties
//! go to the earliest), and its trial reports the partial sum as a lower bound
//! ([`SeedTrial::stopped_early`]). A reading stopped this way was searched and its
//! candidates formed, but its boundary groups (if any) were not walked; it ranks after
//! the winner, and should the winner fail the full check, it is checked in full then. To
//! compare readings by their full totals, reverse with each one's seed face given: the
//! result's [`SeedChoice::detail_energy`] is that reading's total.
//! [`DooReversal::choices`] reports what was tried and why the winner won.
//!
//! Squares overflow beyond about `1e154` and underflow below `1e-154`, where every
//! reading would look alike. A mesh whose largest coordinate magnitude lies outside
//! `2^±256` is therefore reversed as a copy scaled by an exact power of two to unit
//! size, and the result scaled back: the reversal of the mesh as given, bit for bit,
//! with the choice it would make if its squares could not overflow (and its inverse
//! rules' partial sums neither, near `f64::MAX`); the energies reported are scaled back
//! too (so they may be infinite or zero), the reason says in what units its figures are.
//! Reconstructions ([`DooReversal::reconstruct`], the pyramid's) of values that far
//! from 1 run at unit scale the same way.
//!
//! # Cost
//! Linear in the size of the fine mesh: the search visits each F_F face once and looks
//! across each of its edges once; the candidate graph has two edges per F_E quad, at
//! most `|NV|` ([`ReverseStats`] counts both, so tests can assert the bound). Every pass
//! works on flat `u32` arrays, without hashing and without per-face allocation: a mesh
//! whose first reading covers every vertex has one component and is not labelled, others
//! are labelled by one traversal and listed by a counting sort; the detail
//! energy of a reading is one streaming pass over its F_F faces in memory order
//! (expansion; the search order is replayed only to name an error) and its F_V
//! faces (each F_V face holds exactly the candidates of one coarse vertex, so no
//! union-find is needed), with scratch arrays reused from reading to reading; the vertex
//! groups of the result are walks around the coarse vertices, numbered through their F_V
//! faces by a counting sort; the automatic mode keeps
//! the F_F faces of its best reading instead of searching again, and the final checks run
//! beside the geometry when rayon has more than one thread. The automatic mode searches
//! every valid class (usually two readings, F_F and F_V) and sums the details of each
//! until it cannot win, so it costs up to twice a reversal with a given seed: less the
//! sooner the losing readings' sums pass the winner's (on a closed mesh in the canonical
//! order, the losing dual reading is expanded only as far as its sum goes).
//!
//! A reading of a closed mesh of one component, in any order, is built in fewer passes,
//! all reading in face order: the coarse twins and the F_E matching come from one pass
//! over the quads of the search (the twins of a quad's corners name its two F_F
//! corners), and the remaining faces, in face order, are the F_V faces, each checked to
//! be the orbit of one coarse vertex (its corners' coarse corners through the fine
//! twins), which numbers the coarse vertices and gives their corners; the manifold
//! checks ride on that pass and on the means. In automatic mode the first reading of
//! such a mesh is built right after its search, its detail energy is the built result's
//! (its groups are not summed twice), and its dual reading is not searched: the built
//! structure says what that search finds (the F_V faces as F_F faces, its groups the
//! F_F faces), so its sum runs over the F_F faces in face order, each F_V face expanded
//! when a group first needs it, until it reaches the first reading's total, as on a
//! canonical mesh. The counters count the searches this stands for. Any mismatch of
//! these passes, or a dual reading that would win, goes to the full build and the full
//! search, which name the face at fault: results, errors and counters are the same.
//!
//! A mesh in the *canonical order* (as written by [`crate::subdivide`] or rebuilt by a
//! pyramid: identity [`FineOrder`]) of one connected coarse mesh is reversed without the
//! corner arrays, the search and the face matching: its numbering says which faces are
//! F_F, F_E and F_V, and three streaming passes over the half-edge arrays check every
//! fine face against it while they build the coarse mesh. This covers a given seed face
//! and the automatic choice (the same readings evaluated with the same sums in the same
//! order; on an open mesh the searches of the other readings, which meet the boundary
//! within a few faces of their seeds, are replayed on the half-edge arrays up to the
//! error they stop at). The result is bit for bit the one of the general path (choice,
//! trials and counters included); any mesh it does not fit (another order, several
//! components, no F_E quads or no interior coarse vertex in automatic mode, another
//! reading that does not fail on an open mesh, a broken mesh) goes to the general path,
//! which names the face at fault.
//!
//! # Boundaries and components
//! Coarse boundary edges are the F_F edges on the fine boundary (the default boundary
//! rule of [`crate::forward`] puts nothing else there). Several connected components are
//! reversed independently, one seed each. A coarse vertex whose faces form two fans would
//! give two candidate groups: it is split into two vertices (which keeps the coarse mesh
//! manifold).
//!
//! # Errata of the seed paper used here
//! The sign in its eq. (6) (expansion of the centroid contraction) is wrong, see
//! [`crate::rule`]; its claim `|F_E| <= |NF| <= |NV|` is false (a cube after one step has
//! 26 faces and 24 vertices) but linearity holds since `|F_E| = |E_int| <= |NV| / 2`.

use glam::DVec3;
use mesh_topo::memory::advised_vec;
use mesh_topo::{HalfedgeMesh, PolygonSoup};
use serde::{Deserialize, Serialize};

use crate::DooError;
use crate::boundary::BoundaryRule;
use crate::canonical::distinct;
use crate::corner::{
    CornerMesh, NONE, VertexCorners, doo_topology, expand_faces, face_points_in_place, faces_of_corners, group_by_key,
    next_of_corners, prev_of_corners, side_by_side,
};
use crate::forward::check_finite;
use crate::rule::{FaceMaps, FaceRule};
use crate::scale::UnitScale;

/// Options of [`reverse`].
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ReverseOptions {
    /// The per-face rule the fine mesh is assumed to come from.
    pub rule: FaceRule,
    /// Seed faces known to be F_F faces, at most one per connected component; components
    /// without a seed are resolved automatically (see the module docs).
    pub seeds: Vec<usize>,
    /// The boundary rule the fine mesh is assumed to come from ([`BoundaryRule`]).
    pub boundary: BoundaryRule,
}

impl ReverseOptions {
    /// Automatic seeds for every component.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_doo::{DooOptions, FaceRule, ReverseOptions, reverse, subdivide};
    ///
    /// assert_eq!(ReverseOptions::auto(FaceRule::DooSabin), ReverseOptions::default());
    /// let cube = HalfedgeMesh::from_soup(&shapes::cube())?;
    /// let fine = subdivide(&cube, &DooOptions::new(FaceRule::CENTROID_HALF, 1))?.to_mesh()?;
    /// let reversal = reverse(&fine, &ReverseOptions::auto(FaceRule::CENTROID_HALF))?;
    /// // The seed was found, not given: face 0 as an F_F face, all details zero.
    /// let choice = &reversal.choices()[0];
    /// assert_eq!((choice.seed_face, choice.given), (0, false));
    /// assert!(reversal.details().iter().all(|d| d.length() < 1e-14));
    /// # Ok::<(), subdiv_doo::DooError>(())
    /// ```
    pub fn auto(rule: FaceRule) -> Self {
        Self { rule, seeds: Vec::new(), boundary: BoundaryRule::Shrink }
    }

    /// One given seed face (for a mesh with one component; other components are
    /// resolved automatically).
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_doo::{DooOptions, FaceRule, ReverseOptions, reverse, subdivide};
    ///
    /// let cube = HalfedgeMesh::from_soup(&shapes::cube())?;
    /// let fine = subdivide(&cube, &DooOptions::default())?.to_mesh()?;
    /// // Face 18 is the F_V face of cube vertex 0. Read as an F_F face it gives the dual
    /// // reading: an octahedron (8 triangles, 6 vertices), with details that are not zero.
    /// let reversal = reverse(&fine, &ReverseOptions::with_seed(FaceRule::DooSabin, 18))?;
    /// assert_eq!((reversal.coarse().face_count(), reversal.coarse().vertex_count()), (8, 6));
    /// assert!(reversal.choices()[0].given);
    /// assert!(reversal.details().iter().any(|d| d.length() > 0.1));
    /// // It still rebuilds the input.
    /// let rebuilt = reversal.reconstruct();
    /// assert!(rebuilt.positions.iter().zip(fine.positions()).all(|(a, b)| a.distance(*b) < 1e-14));
    /// # Ok::<(), subdiv_doo::DooError>(())
    /// ```
    pub fn with_seed(rule: FaceRule, seed: usize) -> Self {
        Self { rule, seeds: vec![seed], boundary: BoundaryRule::Shrink }
    }

    /// The same options for a fine mesh made with the boundary rule `boundary`.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes::{self, CellKind}};
    /// use subdiv_doo::{BoundaryRule, DooOptions, FaceRule, ReverseOptions, reverse, subdivide};
    ///
    /// let grid = HalfedgeMesh::from_soup(&shapes::grid(2, 2, CellKind::Quads)?)?;
    /// let refine = DooOptions::default().with_boundary(BoundaryRule::Chaikin);
    /// let fine = subdivide(&grid, &refine)?.to_mesh()?;
    /// let options = ReverseOptions::auto(FaceRule::DooSabin).with_boundary(BoundaryRule::Chaikin);
    /// let reversal = reverse(&fine, &options)?;
    /// // The 2 x 2 grid again, with zero details.
    /// assert_eq!((reversal.coarse().face_count(), reversal.coarse().vertex_count()), (4, 9));
    /// assert!(reversal.details().iter().all(|d| d.length() < 1e-14));
    /// // The shrinking rule reads the boundary ring as ordinary faces: no zero-detail reading.
    /// let shrink = reverse(&fine, &ReverseOptions::auto(FaceRule::DooSabin))?;
    /// assert!(shrink.details().iter().any(|d| d.length() > 1e-3));
    /// # Ok::<(), subdiv_doo::DooError>(())
    /// ```
    pub fn with_boundary(self, boundary: BoundaryRule) -> Self {
        Self { boundary, ..self }
    }
}

/// How the fine mesh's vertices and faces are numbered relative to the Doo-Sabin
/// connectivity of the coarse mesh (the *canonical* order of [`crate::forward`]).
/// Empty arrays mean the identity (e.g. for a mesh written by [`crate::subdivide`]).
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct FineOrder {
    /// `vertices[c]` = input vertex of canonical vertex `c` (= coarse corner `c`).
    pub vertices: Vec<u32>,
    /// `faces[k]` = input face of canonical face `k`.
    pub faces: Vec<u32>,
    /// `rotations[k]` = `r` such that corner `i` of the input face is corner `(i + r) mod m`
    /// of canonical face `k`.
    pub rotations: Vec<u32>,
}

impl FineOrder {
    /// True if the input order is the canonical one.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, PolygonSoup, shapes};
    /// use subdiv_doo::{DooOptions, FineOrder, ReverseOptions, reverse, subdivide};
    ///
    /// assert!(FineOrder::default().is_identity());
    /// let cube = HalfedgeMesh::from_soup(&shapes::cube())?;
    /// let fine = subdivide(&cube, &DooOptions::default())?.to_soup();
    /// // `subdivide` writes the canonical order...
    /// let reversal = reverse(&HalfedgeMesh::from_soup(&fine)?, &ReverseOptions::default())?;
    /// assert!(reversal.fine_order().is_identity());
    /// // ... which the same faces listed backwards are not.
    /// let faces = (0..26).rev().map(|f| fine.face(f));
    /// let backwards = PolygonSoup::from_faces(fine.positions.clone(), faces);
    /// let reversal = reverse(&HalfedgeMesh::from_soup(&backwards)?, &ReverseOptions::default())?;
    /// assert!(!reversal.fine_order().is_identity());
    /// assert_eq!(reversal.reconstruct().indices, backwards.indices);
    /// # Ok::<(), subdiv_doo::DooError>(())
    /// ```
    pub fn is_identity(&self) -> bool {
        self.vertices.is_empty() && self.faces.is_empty() && self.rotations.is_empty()
    }
}

/// Counters of the traversal, for checking the linear cost.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct ReverseStats {
    /// F_F faces visited by the search (each once), summed over the interpretations tried.
    pub visited_faces: usize,
    /// Edges of F_F faces looked across by the search, summed over the interpretations tried.
    pub edges_crossed: usize,
    /// Edges of the candidate graph of the result (two per F_E quad).
    pub candidate_edges: usize,
    /// Number of interpretations evaluated in full (automatic mode).
    pub interpretations: usize,
}

/// One seed tried for a component.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SeedTrial {
    /// The face tried as an F_F face.
    pub seed_face: usize,
    /// The role of that face in the first interpretation found (`"F_F"`, `"F_V"`,
    /// `"F_E"`), or `"neighbour"` while looking for a first valid one.
    pub class: String,
    /// Total squared detail norm of the interpretation, or why it is not valid; a lower
    /// bound of it when [`Self::stopped_early`].
    pub outcome: Result<f64, String>,
    /// True when the sum of the squared detail norms was stopped as soon as it reached
    /// the smallest total found before: the reading cannot win any more (ties go to the
    /// earliest), so `outcome` is the partial sum, a lower bound of the total, and the
    /// checks that would come after the sum (the boundary groups) were not made.
    #[serde(default)]
    pub stopped_early: bool,
}

impl SeedTrial {
    pub(crate) fn valid(seed_face: usize, class: &str, energy: f64, stopped_early: bool) -> Self {
        SeedTrial { seed_face, class: class.into(), outcome: Ok(energy), stopped_early }
    }

    pub(crate) fn invalid(seed_face: usize, class: &str, error: &DooError) -> Self {
        SeedTrial { seed_face, class: class.into(), outcome: Err(error.to_string()), stopped_early: false }
    }
}

/// Whether a reading's total squared detail norm `energy` is zero at the scale of its
/// mesh (`scale`: bounding-box diagonal; `faces`: its number of faces): below
/// `(1e-12 scale)^2` per face, round-off of an exact refinement.
pub(crate) fn details_are_zero(energy: f64, scale: f64, faces: usize) -> bool {
    energy <= (1e-12 * scale.max(f64::MIN_POSITIVE)).powi(2) * faces as f64
}

/// The reason of a choice whose first reading (`seed` as F_F) has zero details.
pub(crate) fn zero_details_reason(seed: usize) -> String {
    format!("face {seed} as F_F gives all details zero (exact Doo-Sabin refinement); no other reading tried")
}

/// The reason of a choice whose other readings all failed.
pub(crate) fn only_valid_reason(seed: usize) -> String {
    format!("face {seed} as F_F is the only valid reading found")
}

/// Why the automatic mode kept a reading of total squared detail norm `energy` against
/// the other valid ones (`others`: seed face, total or partial sum, stopped early).
pub(crate) fn ranking_reason(energy: f64, others: &[(usize, f64, bool)]) -> String {
    let others: Vec<String> = others
        .iter()
        .map(|&(seed, other, stopped)| {
            if stopped {
                format!("at least {other:.6e} (seed {seed}, its sum stopped there)")
            } else {
                format!("{other:.6e} (seed {seed})")
            }
        })
        .collect();
    format!(
        "smallest total squared detail norm among {} valid readings: {energy:.6e} against {}",
        others.len() + 1,
        others.join(", ")
    )
}

/// Which seed a component was reversed with, and why.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SeedChoice {
    /// The component (numbered in order of its lowest face).
    pub component: usize,
    /// The seed face used.
    pub seed_face: usize,
    /// True if the caller gave it.
    pub given: bool,
    /// Everything tried (empty for a given seed).
    pub trials: Vec<SeedTrial>,
    /// The total squared detail norm of the chosen interpretation.
    pub detail_energy: f64,
    /// Its square root, the detail norm, taken before the energy of a mesh reversed at
    /// unit scale is brought back to the input's units (see the [module docs](self)):
    /// finite where `detail_energy` is infinite or zero only because the squares of
    /// coordinates far from 1 do not fit in `f64`.
    #[serde(default = "unknown_norm")]
    pub detail_norm: f64,
    /// Why this one, in words.
    pub reason: String,
}

/// The detail norm of a choice read without one.
fn unknown_norm() -> f64 {
    f64::NAN
}

impl SeedChoice {
    /// The choice of the automatic mode for `component`: `seed_face` after `trials`, of
    /// total squared detail norm `detail_energy`, for `reason`.
    pub(crate) fn automatic(
        component: usize,
        seed_face: usize,
        trials: Vec<SeedTrial>,
        detail_energy: f64,
        reason: String,
    ) -> Self {
        let detail_norm = detail_energy.sqrt();
        SeedChoice { component, seed_face, given: false, trials, detail_energy, detail_norm, reason }
    }

    pub(crate) fn given(component: usize, seed_face: usize) -> Self {
        SeedChoice {
            component,
            seed_face,
            given: true,
            trials: Vec::new(),
            detail_energy: f64::NAN,
            detail_norm: f64::NAN,
            reason: "seed face given".into(),
        }
    }
}

/// The result of reversing one Doo-Sabin step.
#[derive(Debug, Clone)]
pub struct DooReversal {
    pub(crate) rule: FaceRule,
    pub(crate) coarse: CornerMesh,
    pub(crate) coarse_positions: Vec<DVec3>,
    pub(crate) details: Vec<DVec3>,
    pub(crate) order: FineOrder,
    pub(crate) choices: Vec<SeedChoice>,
    pub(crate) stats: ReverseStats,
    pub(crate) boundary: BoundaryRule,
    /// The unit scale of the fine positions ([`mesh_topo::scale::unit_scale`]) when the
    /// path that made the reversal measured it as it read them (the canonical path), so
    /// that a caller deciding on a change of scale reads the positions no further time.
    pub(crate) fine_unit_scale: Option<f64>,
}

/// Equal when the results are (the unit scale some paths measure on the way is left out:
/// the same reversal is equal whichever path made it).
impl PartialEq for DooReversal {
    fn eq(&self, other: &Self) -> bool {
        let Self { rule, coarse, coarse_positions, details, order, choices, stats, boundary, fine_unit_scale: _ } =
            self;
        *rule == other.rule
            && *coarse == other.coarse
            && *coarse_positions == other.coarse_positions
            && *details == other.details
            && *order == other.order
            && *choices == other.choices
            && *stats == other.stats
            && *boundary == other.boundary
    }
}

impl DooReversal {
    /// A reversal under the Shrink boundary rule, before its seed choices are recorded.
    pub(crate) fn shrink(
        rule: FaceRule,
        coarse: CornerMesh,
        coarse_positions: Vec<DVec3>,
        details: Vec<DVec3>,
        order: FineOrder,
        stats: ReverseStats,
    ) -> Self {
        let choices = Vec::new();
        let boundary = BoundaryRule::Shrink;
        Self { rule, coarse, coarse_positions, details, order, choices, stats, boundary, fine_unit_scale: None }
    }

    /// The coarse mesh: vertices at the means of their candidates, faces in the order of
    /// their F_F faces in the input, each starting at its F_F face's first corner.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, PolygonSoup, shapes};
    /// use subdiv_doo::{DooOptions, ReverseOptions, reverse, subdivide};
    ///
    /// let cube = shapes::cube();
    /// let fine = subdivide(&HalfedgeMesh::from_soup(&cube)?, &DooOptions::default())?.to_mesh()?;
    /// let reversal = reverse(&fine, &ReverseOptions::default())?;
    /// // reverse(subdivide(C)) is C: the same faces, corner by corner, and zero details.
    /// let coarse = reversal.coarse();
    /// assert_eq!(coarse.offsets, cube.offsets);
    /// let corner = |soup: &PolygonSoup, c: usize| soup.positions[soup.indices[c] as usize];
    /// assert!((0..cube.indices.len()).all(|c| corner(&coarse, c).distance(corner(&cube, c)) < 1e-14));
    /// assert!(reversal.details().iter().all(|d| d.length() < 1e-14));
    /// # Ok::<(), subdiv_doo::DooError>(())
    /// ```
    pub fn coarse(&self) -> PolygonSoup {
        PolygonSoup {
            positions: self.coarse_positions.clone(),
            offsets: self.coarse.offsets.clone(),
            indices: self.coarse.corner_vertex.clone(),
        }
    }

    /// Coarse vertex positions.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_doo::{DooOptions, ReverseOptions, reverse, subdivide};
    ///
    /// let tetrahedron = HalfedgeMesh::from_soup(&shapes::tetrahedron())?;
    /// let fine = subdivide(&tetrahedron, &DooOptions::default())?.to_mesh()?;
    /// let reversal = reverse(&fine, &ReverseOptions::default())?;
    /// assert_eq!(reversal.coarse_positions(), reversal.coarse().positions);
    /// // Coarse vertices plus details: as many 3-vectors as fine vertices (4 + 8 = 12).
    /// assert_eq!(reversal.coarse_positions().len(), 4);
    /// assert_eq!(reversal.coarse_positions().len() + reversal.details().len(), fine.vertex_count());
    /// # Ok::<(), subdiv_doo::DooError>(())
    /// ```
    pub fn coarse_positions(&self) -> &[DVec3] {
        &self.coarse_positions
    }

    /// The detail vectors: for every coarse vertex in order, the `r - 1` prefix sums of
    /// its candidates' offsets from the mean (module docs).
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_doo::{DooOptions, ReverseOptions, reverse, subdivide};
    ///
    /// let cube = HalfedgeMesh::from_soup(&shapes::cube())?;
    /// let mut fine = subdivide(&cube, &DooOptions::default())?.to_mesh()?;
    /// // 8 coarse vertices with 3 candidates each (their corners): 8 * (3 - 1) details.
    /// let exact = reverse(&fine, &ReverseOptions::default())?;
    /// assert_eq!(exact.details().len(), 16);
    /// assert!(exact.details().iter().all(|d| d.length() < 1e-14));
    /// // Moving a fine vertex makes the candidates of its coarse vertex disagree.
    /// fine.positions_mut()[5].x += 0.25;
    /// let moved = reverse(&fine, &ReverseOptions::default())?;
    /// assert!(moved.details().iter().any(|d| d.length() > 0.1));
    /// # Ok::<(), subdiv_doo::DooError>(())
    /// ```
    pub fn details(&self) -> &[DVec3] {
        &self.details
    }

    /// The rule assumed.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_doo::{DooOptions, FaceRule, ReverseOptions, reverse, subdivide};
    ///
    /// // On triangles the simple variant is not Doo-Sabin: only its inverse gives zero details.
    /// let tetrahedron = HalfedgeMesh::from_soup(&shapes::tetrahedron())?;
    /// let fine = subdivide(&tetrahedron, &DooOptions::new(FaceRule::Simple, 1))?.to_mesh()?;
    /// let simple = reverse(&fine, &ReverseOptions::auto(FaceRule::Simple))?;
    /// let doo = reverse(&fine, &ReverseOptions::auto(FaceRule::DooSabin))?;
    /// assert_eq!((simple.rule(), doo.rule()), (FaceRule::Simple, FaceRule::DooSabin));
    /// assert!(simple.details().iter().all(|d| d.length() < 1e-14));
    /// assert!(doo.details().iter().any(|d| d.length() > 0.1));
    /// # Ok::<(), subdiv_doo::DooError>(())
    /// ```
    pub fn rule(&self) -> FaceRule {
        self.rule
    }

    /// The boundary rule assumed. Under [`BoundaryRule::Chaikin`] the details end with
    /// two per coarse boundary edge (the offsets of its Chaikin points, see
    /// [`crate::boundary`]).
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes::{self, CellKind}};
    /// use subdiv_doo::{BoundaryRule, DooOptions, FaceRule, ReverseOptions, reverse, subdivide};
    ///
    /// let grid = HalfedgeMesh::from_soup(&shapes::grid(2, 2, CellKind::Quads)?)?;
    /// let refine = DooOptions::default().with_boundary(BoundaryRule::Chaikin);
    /// let fine = subdivide(&grid, &refine)?.to_mesh()?;
    /// let options = ReverseOptions::auto(FaceRule::DooSabin).with_boundary(BoundaryRule::Chaikin);
    /// let reversal = reverse(&fine, &options)?;
    /// assert_eq!(reversal.boundary(), BoundaryRule::Chaikin);
    /// // 16 corners on 9 vertices, then 2 Chaikin offsets for each of the 8 boundary edges.
    /// assert_eq!(reversal.details().len(), (16 - 9) + 2 * 8);
    /// assert_eq!(reversal.coarse_positions().len() + reversal.details().len(), fine.vertex_count());
    /// # Ok::<(), subdiv_doo::DooError>(())
    /// ```
    pub fn boundary(&self) -> BoundaryRule {
        self.boundary
    }

    /// The numbering of the input relative to the canonical Doo-Sabin order.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, PolygonSoup, shapes};
    /// use subdiv_doo::{DooOptions, ReverseOptions, reverse, subdivide};
    ///
    /// let cube = HalfedgeMesh::from_soup(&shapes::cube())?;
    /// let fine = subdivide(&cube, &DooOptions::default())?.to_soup();
    /// // The 26 faces listed backwards: the 6 F_F faces are now faces 20..26, and the coarse
    /// // faces follow their order, so canonical face k (F_F face of coarse face k) is 20 + k.
    /// let faces = (0..26).rev().map(|f| fine.face(f));
    /// let backwards = PolygonSoup::from_faces(fine.positions.clone(), faces);
    /// let reversal = reverse(&HalfedgeMesh::from_soup(&backwards)?, &ReverseOptions::default())?;
    /// let order = reversal.fine_order();
    /// assert_eq!(order.faces[..6], [20, 21, 22, 23, 24, 25]);
    /// let mut faces = order.faces.clone();
    /// faces.sort_unstable();
    /// assert!(faces.into_iter().eq(0..26));
    /// # Ok::<(), subdiv_doo::DooError>(())
    /// ```
    pub fn fine_order(&self) -> &FineOrder {
        &self.order
    }

    /// The seed chosen for each component, with the reasons.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_doo::{DooOptions, ReverseOptions, reverse, subdivide};
    ///
    /// let cube = HalfedgeMesh::from_soup(&shapes::cube())?;
    /// let mut fine = subdivide(&cube, &DooOptions::default())?.to_mesh()?;
    /// fine.positions_mut()[5].x += 0.25; // details are no longer zero: readings are compared
    /// let reversal = reverse(&fine, &ReverseOptions::default())?;
    /// let [choice] = reversal.choices() else { panic!("one component") };
    /// assert_eq!((choice.component, choice.seed_face, choice.given), (0, 0, false));
    /// // Face 0 as F_F (the true reading) beats the dual reading from F_V face 18.
    /// assert!(choice.trials.iter().any(|t| (t.seed_face, t.class.as_str()) == (18, "F_V")));
    /// assert!(choice.trials.iter().all(|t| t.outcome.iter().all(|&e| e >= choice.detail_energy)));
    /// # Ok::<(), subdiv_doo::DooError>(())
    /// ```
    pub fn choices(&self) -> &[SeedChoice] {
        &self.choices
    }

    /// Traversal counters.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_doo::{DooOptions, ReverseOptions, reverse, subdivide};
    ///
    /// let cube = HalfedgeMesh::from_soup(&shapes::cube())?;
    /// let fine = subdivide(&cube, &DooOptions::default())?.to_mesh()?;
    /// let stats = reverse(&fine, &ReverseOptions::default())?.stats();
    /// // One reading (zero details: accepted at once) visiting the 6 F_F faces and crossing
    /// // their 24 edges; two candidate-graph edges per F_E quad.
    /// assert_eq!((stats.interpretations, stats.visited_faces, stats.edges_crossed), (1, 6, 24));
    /// assert_eq!(stats.candidate_edges, 2 * 12);
    /// # Ok::<(), subdiv_doo::DooError>(())
    /// ```
    pub fn stats(&self) -> ReverseStats {
        self.stats
    }

    /// Rebuilds the fine mesh exactly (same vertex and face order as the input).
    ///
    /// ```
    /// use subdiv_doo::{DooOptions, ReverseOptions, reverse, subdivide};
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// let cube = HalfedgeMesh::from_soup(&shapes::cube())?;
    /// let mut fine = subdivide(&cube, &DooOptions::default())?.to_mesh()?;
    /// fine.positions_mut()[5].x += 0.25; // not a Doo-Sabin surface any more
    /// let reversal = reverse(&fine, &ReverseOptions::default())?;
    /// let rebuilt = reversal.reconstruct();
    /// assert_eq!(rebuilt.offsets, fine.to_soup().offsets);
    /// let error = rebuilt.positions.iter().zip(fine.positions()).map(|(a, b)| (*a - *b).length()).fold(0.0, f64::max);
    /// assert!(error < 1e-14);
    /// # Ok::<(), subdiv_doo::DooError>(())
    /// ```
    pub fn reconstruct(&self) -> PolygonSoup {
        // Values far from 1 are rebuilt at unit scale, where the forward sums do not
        // overflow when their results fit (see `crate::scale`).
        let scale = UnitScale::of_values(self.coarse_positions.iter().chain(&self.details));
        let scaled;
        let (coarse_positions, details) = match scale {
            None => (&self.coarse_positions, &self.details),
            Some(scale) => {
                let (mut positions, mut details) = (self.coarse_positions.clone(), self.details.clone());
                scale.scale_down(&mut positions);
                scale.scale_down(&mut details);
                scaled = (positions, details);
                (&scaled.0, &scaled.1)
            }
        };
        let level = Level { details, order: &self.order, rule: self.rule, boundary: self.boundary };
        let (mesh, mut positions) = reconstruct_level_with(&self.coarse, coarse_positions, &level, false)
            .expect("internal: a reversal reconstructs");
        if let Some(scale) = scale {
            scale.scale_up(&mut positions);
        }
        PolygonSoup { positions, offsets: mesh.offsets, indices: mesh.corner_vertex }
    }

    pub(crate) fn into_parts(self) -> (CornerMesh, Vec<DVec3>, Vec<DVec3>, FineOrder, Vec<SeedChoice>) {
        (self.coarse, self.coarse_positions, self.details, self.order, self.choices)
    }
}

/// Reverses one Doo-Sabin step: coarse mesh, details and everything needed to rebuild
/// the input exactly (see the module docs).
///
/// ```
/// use subdiv_doo::{DooOptions, FaceRule, ReverseOptions, reverse, subdivide};
/// use mesh_topo::{HalfedgeMesh, shapes};
/// let cube = HalfedgeMesh::from_soup(&shapes::cube())?;
/// let fine = subdivide(&cube, &DooOptions::default())?.to_mesh()?;
/// let reversal = reverse(&fine, &ReverseOptions::auto(FaceRule::DooSabin))?;
/// // The cube comes back (same faces; its vertices numbered as their F_V faces are
/// // listed, which `subdivide` writes in the cube's vertex order), with all details zero.
/// assert_eq!(reversal.coarse().face_count(), 6);
/// assert!(reversal.details().iter().all(|d| d.length() < 1e-14));
/// assert_eq!(reversal.coarse_positions().len() + reversal.details().len(), fine.vertex_count());
/// # Ok::<(), subdiv_doo::DooError>(())
/// ```
///
/// # Errors
/// [`DooError::NotDooConnectivity`] naming the face where the structure breaks (in
/// automatic mode: the error of the first seed tried in the first component that has no
/// valid interpretation); [`DooError::IsolatedVertex`]; [`DooError::EmptyMesh`] for a
/// mesh without faces; [`DooError::NonFinite`]; [`DooError::SeedOutOfRange`] and [`DooError::DuplicateSeed`] for bad seeds;
/// [`DooError::InvalidParameter`] for a bad centroid parameter;
/// [`DooError::ReversalOverflow`] for finite coordinates so large (near `f64::MAX`) that
/// the coarse positions or details are not.
pub fn reverse(fine: &HalfedgeMesh, options: &ReverseOptions) -> Result<DooReversal, DooError> {
    // Coordinates far from 1: reversed at unit scale (see `crate::scale`). Its errors
    // and overflows are left to the mesh as given, which reports them as before, from
    // the reversal made as given. The canonical path measures the scale as it reads the
    // positions, which then need no pass of their own for it.
    let canonical = reverse_canonical(fine, options);
    let measured = canonical.as_ref().and_then(|reversal| reversal.fine_unit_scale);
    if let Some(scale) = UnitScale::of_measured(measured, fine.positions()) {
        let mut scaled = fine.clone();
        scale.scale_down(scaled.positions_mut());
        if let Ok(mut reversal) = reverse_as_given(&scaled, options)
            && scale.scale_up(&mut reversal.coarse_positions)
            && scale.scale_up(&mut reversal.details)
        {
            scale.scale_up_choices(&mut reversal.choices);
            return Ok(reversal);
        }
    }
    reverse_after(fine, options, canonical)
}

/// [`reverse`] without the change of scale.
fn reverse_as_given(fine: &HalfedgeMesh, options: &ReverseOptions) -> Result<DooReversal, DooError> {
    reverse_after(fine, options, reverse_canonical(fine, options))
}

/// The reversal of a mesh in the canonical order, by its boundary rule; `None` where the
/// canonical path does not apply, also when a position is not finite, so that
/// [`reverse_after`] names it.
pub(crate) fn reverse_canonical(fine: &HalfedgeMesh, options: &ReverseOptions) -> Option<DooReversal> {
    match options.boundary {
        BoundaryRule::Shrink => crate::canonical::reverse_canonical(fine, options),
        BoundaryRule::Chaikin => crate::boundary::reverse_chaikin_canonical(fine, options),
    }
}

/// [`reverse`] once the canonical path was tried (`canonical`, its reversal if it took
/// the mesh).
fn reverse_after(
    fine: &HalfedgeMesh,
    options: &ReverseOptions,
    canonical: Option<DooReversal>,
) -> Result<DooReversal, DooError> {
    if let Some(reversal) = canonical {
        return Ok(reversal);
    }
    check_finite(fine.positions())?;
    let corners = CornerMesh::from_halfedge(fine);
    match options.boundary {
        BoundaryRule::Shrink => reverse_corner_mesh(&corners, fine.positions(), options),
        BoundaryRule::Chaikin => crate::boundary::reverse_chaikin_corner_mesh(&corners, fine.positions(), options),
    }
}

/// [`DooError::ReversalOverflow`] if the coarse positions or details of `reversal` are
/// not all finite: its input (`positions`, finite) is so large that the inverse rules'
/// sums overflow. One pass over the result, on the general path only (the canonical
/// path leaves such a mesh to it).
pub(crate) fn check_reversal_finite(reversal: &DooReversal, positions: &[DVec3]) -> Result<(), DooError> {
    let values = || reversal.coarse_positions.iter().chain(&reversal.details);
    match values().position(|p| !p.is_finite()) {
        None => Ok(()),
        // (The input is finite here: its error, if any, comes first.)
        Some(index) => {
            Err(DooError::ReversalOverflow { index, largest: crate::forward::check_finite_largest(positions)? })
        }
    }
}

/// [`reverse`] on corner arrays.
pub(crate) fn reverse_corner_mesh(
    fine: &CornerMesh,
    positions: &[DVec3],
    options: &ReverseOptions,
) -> Result<DooReversal, DooError> {
    let mut session = Session::new(fine, positions, options)?;
    let best = vec![0; session.readings.len()];
    session.build(best)
}

/// The valid readings of a fine mesh, ranked per component, from which reversals are
/// built on demand (the best one, or alternatives when a multi-level decomposition
/// needs another reading to go on).
/// What [`Search::energy`] finds of a reading.
#[derive(Debug, Clone, Copy)]
struct Energy {
    /// Total squared detail norm, or its partial sum if `stopped_early`.
    energy: f64,
    /// Bounding-box diagonal of the component (the scale of the zero test).
    size: f64,
    /// Whether the sum stopped when it reached the cutoff.
    stopped_early: bool,
    /// Whether the sum was left to the caller (`energy` is NaN then): the reading is
    /// valid as far as the candidates go, its groups are not summed yet (see
    /// [`Search::complete_energy`]).
    deferred: bool,
}

/// The cutoff of a sum that must not stop (no comparison with NaN holds).
const NO_CUTOFF: f64 = f64::NAN;

/// A valid reading found by [`Search::choose`].
struct Found {
    seed: usize,
    energy: f64,
    stopped_early: bool,
    /// Its F_F faces (empty when stopped early: it is never the best).
    ff_faces: Vec<u32>,
    kept: Kept,
}

pub(crate) struct Session<'a> {
    search: Search<'a>,
    rule: FaceRule,
    component_of_face: Vec<u32>,
    given: Vec<u32>,
    /// Per component: (seed face, detail energy), best first.
    readings: Vec<Vec<(usize, f64)>>,
    /// Per component: the F_F faces of its best automatic reading, kept from the ranking
    /// so that building it does not search again (empty for a given seed).
    best_ff_faces: Vec<Vec<u32>>,
    /// Per component: what the ranking (or the check of a given seed) found of its best
    /// reading, when it is numbered as the result will be (a mesh of one component), so
    /// that the first build does not find it again; empty otherwise or once used.
    best_candidates: Vec<Kept>,
    choices: Vec<SeedChoice>,
    /// The roles of the search are those of the given seed of a one-component mesh,
    /// found while checking that it has one component: the first build uses them.
    preclassified: bool,
}

impl<'a> Session<'a> {
    /// Finds and ranks the readings of every component.
    pub(crate) fn new(
        fine: &'a CornerMesh,
        positions: &'a [DVec3],
        options: &ReverseOptions,
    ) -> Result<Self, DooError> {
        options.rule.validate()?;
        let face_count = fine.face_count();
        for &s in &options.seeds {
            if s >= face_count {
                return Err(DooError::SeedOutOfRange { face: s, face_count });
            }
        }
        if let Some(v) = (0..fine.vertex_count).find(|&v| fine.first_corner(v) == NONE) {
            return Err(DooError::IsolatedVertex { vertex: v });
        }
        if face_count == 0 {
            return Err(DooError::EmptyMesh);
        }
        let mut search = Search::new(fine, positions, FaceMaps::new(options.rule));
        let faces = FaceSet::All(face_count as u32);

        // A mesh of one component (the usual case) needs no component labels: it is
        // recognised by the first reading, whose F_F faces then cover every vertex once.
        match options.seeds[..] {
            [] => {
                if let Some(first) = search.first_reading_covers_all(faces) {
                    let (choice, ranked, best, candidates) =
                        search.choose(0, faces, fine.vertex_count, Some(first), options.rule)?;
                    let best = (best, candidates);
                    return Ok(Self::one_component(search, options.rule, NONE, ranked, best, choice, false));
                }
            }
            [seed] if search.seed_covers_all(seed) => {
                let choice = SeedChoice::given(0, seed);
                let ranked = vec![(seed, f64::NAN)];
                let kept = Kept { candidates: Vec::new(), corner_of_vertex: std::mem::take(&mut search.ranks) };
                let best = (Vec::new(), kept);
                return Ok(Self::one_component(search, options.rule, seed as u32, ranked, best, choice, true));
            }
            _ => {}
        }

        // Components of the face graph, numbered by their lowest face.
        let (component_of_face, component_count) = search.face_components();
        let mut given = vec![NONE; component_count];
        for &s in &options.seeds {
            let k = component_of_face[s] as usize;
            if given[k] != NONE {
                return Err(DooError::DuplicateSeed { first: given[k] as usize, second: s });
            }
            given[k] = s as u32;
        }
        // The faces of each component in increasing order (a counting sort: linear).
        let (component_offsets, faces_by_component) = if component_count == 1 {
            (Vec::new(), Vec::new())
        } else {
            group_by_key(&component_of_face, component_count)
        };

        // Per component: the readings to use, best first (a given seed: just that one).
        // The number of vertices of each component (no vertex is isolated).
        let mut vertices_by_component = vec![0usize; component_count];
        if component_count == 1 {
            vertices_by_component[0] = fine.vertex_count;
        } else {
            for v in 0..fine.vertex_count {
                let f = search.corner_face[fine.first_corner(v) as usize];
                vertices_by_component[component_of_face[f as usize] as usize] += 1;
            }
        }
        let mut readings: Vec<Vec<(usize, f64)>> = Vec::with_capacity(component_count);
        let mut choices = Vec::with_capacity(component_count);
        let mut best_ff_faces = Vec::with_capacity(component_count);
        let mut best_candidates = Vec::with_capacity(component_count);
        for k in 0..component_count {
            if given[k] != NONE {
                let seed = given[k] as usize;
                readings.push(vec![(seed, f64::NAN)]);
                choices.push(SeedChoice::given(k, seed));
                best_ff_faces.push(Vec::new());
                best_candidates.push(Kept::default());
            } else {
                let faces = if component_count == 1 {
                    faces
                } else {
                    FaceSet::Listed(
                        &faces_by_component[component_offsets[k] as usize..component_offsets[k + 1] as usize],
                    )
                };
                let (choice, ranked, best, candidates) =
                    search.choose(k, faces, vertices_by_component[k], None, options.rule)?;
                readings.push(ranked);
                choices.push(choice);
                best_ff_faces.push(best);
                best_candidates.push(candidates);
            }
        }
        Ok(Self {
            search,
            rule: options.rule,
            component_of_face,
            given,
            readings,
            best_ff_faces,
            best_candidates,
            choices,
            preclassified: false,
        })
    }

    fn one_component(
        search: Search<'a>,
        rule: FaceRule,
        given: u32,
        ranked: Ranked,
        (best, candidates): (Vec<u32>, Kept),
        choice: SeedChoice,
        preclassified: bool,
    ) -> Self {
        Self {
            search,
            rule,
            component_of_face: Vec::new(),
            given: vec![given],
            readings: vec![ranked],
            best_ff_faces: vec![best],
            best_candidates: vec![candidates],
            choices: vec![choice],
            preclassified,
        }
    }

    /// Alternative choices of readings, best first: all components at their best, then
    /// each component in turn at each of its other readings.
    pub(crate) fn alternatives(&self) -> Vec<Vec<usize>> {
        let best = vec![0; self.readings.len()];
        let mut out = vec![best.clone()];
        for (k, ranked) in self.readings.iter().enumerate() {
            for j in 1..ranked.len() {
                let mut picks = best.clone();
                picks[k] = j;
                out.push(picks);
            }
        }
        out
    }

    /// Builds the reversal for the given readings; if the full check rejects a
    /// component's automatic choice, falls back to its next reading.
    pub(crate) fn build(&mut self, mut pick: Vec<usize>) -> Result<DooReversal, DooError> {
        let component_count = self.readings.len();
        let mut choices = self.choices.clone();
        let search = &mut self.search;
        loop {
            // The best reading of a closed one-component mesh, built by the ranking.
            let prebuilt = match search.prebuilt.take() {
                Some((seed, closed)) if component_count == 1 && pick[0] == 0 && self.readings[0][0].0 == seed => {
                    Some(closed)
                }
                _ => None,
            };
            let result = if let Some(Closed { mut reversal, energies, .. }) = prebuilt {
                // The counters as the build would copy them now.
                reversal.stats = ReverseStats { candidate_edges: reversal.stats.candidate_edges, ..search.stats };
                Ok((reversal, energies))
            } else {
                if std::mem::take(&mut self.preclassified) {
                    // The roles of the given seed are set already.
                } else {
                    search.role.fill(UNKNOWN);
                    search.queue.clear();
                    for ((ranked, &p), best) in self.readings.iter().zip(&pick).zip(&self.best_ff_faces) {
                        if p == 0 && !best.is_empty() {
                            // The best automatic reading, as the ranking found it (only the F_F
                            // roles matter from here on).
                            for &f in best {
                                search.role[f as usize] = FF;
                            }
                        } else {
                            search.classify(ranked[p].0)?;
                        }
                    }
                }
                // The candidates of the result: those of the ranking for the best reading of a
                // one-component mesh, else written into the energy scratch (no reading is
                // evaluated after the ranking).
                let kept = if component_count == 1 && pick[0] == 0 {
                    std::mem::take(&mut self.best_candidates[0])
                } else {
                    Kept::default()
                };
                let ready = !kept.candidates.is_empty();
                let mut buffer = if ready { kept.candidates } else { std::mem::take(&mut search.candidate) };
                let known = kept.corner_of_vertex;
                // A closed mesh of one component in fewer passes; anything else (or any
                // mismatch) through the full build, which names the face at fault.
                let closed = if component_count == 1 {
                    search.finish_closed(self.rule, &mut buffer, ready, &known)
                } else {
                    None
                };
                match closed {
                    Some(Closed { reversal, energies, .. }) => Ok((reversal, energies)),
                    None => search.finish(self.rule, &self.component_of_face, component_count, (buffer, ready), known),
                }
            };
            match result {
                Ok((mut reversal, energies)) => {
                    check_reversal_finite(&reversal, search.positions)?;
                    for (k, choice) in choices.iter_mut().enumerate() {
                        let (seed, _) = self.readings[k][pick[k]];
                        choice.detail_energy = energies[k];
                        choice.detail_norm = energies[k].sqrt();
                        if seed != choice.seed_face && !choice.given {
                            choice.reason = format!(
                                "face {seed} as F_F, reading number {} by detail norm (the better ones were rejected \
                                 by the full check or could not be reversed further); {}",
                                pick[k] + 1,
                                std::mem::take(&mut choice.reason)
                            );
                        }
                        choice.seed_face = seed;
                    }
                    reversal.choices = choices;
                    return Ok(reversal);
                }
                Err(error) => {
                    let face = match &error {
                        DooError::NotDooConnectivity { face, .. } => *face,
                        _ => return Err(error),
                    };
                    let k = if self.component_of_face.is_empty() { 0 } else { self.component_of_face[face] as usize };
                    if self.given[k] != NONE || pick[k] + 1 >= self.readings[k].len() {
                        return Err(error);
                    }
                    choices[k].trials.push(SeedTrial::invalid(self.readings[k][pick[k]].0, "full check", &error));
                    pick[k] += 1;
                }
            }
        }
    }
}

/// The faces of one component, in increasing order: all faces of a one-component mesh
/// (no list needed), or a listed subset.
#[derive(Debug, Clone, Copy)]
enum FaceSet<'s> {
    All(u32),
    Listed(&'s [u32]),
}

impl<'s> FaceSet<'s> {
    fn iter(self) -> impl Iterator<Item = u32> + 's {
        let (all, listed) = match self {
            FaceSet::All(n) => (0..n, &[][..]),
            FaceSet::Listed(faces) => (0..0, faces),
        };
        all.chain(listed.iter().copied())
    }

    fn len(self) -> usize {
        match self {
            FaceSet::All(n) => n as usize,
            FaceSet::Listed(faces) => faces.len(),
        }
    }

    fn first(self) -> u32 {
        match self {
            FaceSet::All(_) => 0,
            FaceSet::Listed(faces) => faces[0],
        }
    }
}

/// What a pass over the F_F faces of a reading of the whole mesh found, kept for
/// [`Search::finish`]: the candidates by coarse corner (the F_F corners in memory order),
/// and the coarse corner of each fine vertex (each empty when not kept).
#[derive(Debug, Default)]
struct Kept {
    candidates: Vec<DVec3>,
    corner_of_vertex: Vec<u32>,
}

/// What [`Search::finish_closed`] builds: the reversal, its energy, and the F_V face of
/// each coarse vertex.
struct Closed {
    reversal: DooReversal,
    energies: Vec<f64>,
    fv_faces: Vec<u32>,
}

/// Readings of one component: (seed face, detail energy), best first.
type Ranked = Vec<(usize, f64)>;

const UNKNOWN: u8 = 0;
pub(crate) const FF: u8 = 1;
pub(crate) const FE: u8 = 2;

// The errors of the search from a seed face (`Search::classify`), also made by its
// replay on canonical meshes (`crate::canonical`), which must word them alike.

/// Face `g`, across an edge of F_F face `f`, is not a quad (it has `m` sides).
#[cold]
#[inline(never)]
pub(crate) fn not_a_quad(f: usize, g: usize, m: usize) -> DooError {
    let reason = format!("it lies across an edge of F_F face {f} but has {m} sides, not 4");
    DooError::NotDooConnectivity { face: g, reason }
}

/// Quad `g`, across an edge of F_F face `f`, has its opposite edge on the boundary.
#[cold]
#[inline(never)]
pub(crate) fn quad_on_boundary(f: usize, g: usize) -> DooError {
    let reason = format!("this F_E quad (next to F_F face {f}) has its opposite edge on the boundary");
    DooError::NotDooConnectivity { face: g, reason }
}

/// F_F face `g` lies across an edge of F_F face `f`, with no quad between.
#[cold]
pub(crate) fn ff_faces_share_an_edge(f: usize, g: usize) -> DooError {
    let reason = format!("F_F faces {f} and {g} share an edge (expected a quad between)");
    DooError::NotDooConnectivity { face: g, reason }
}

/// Face `h`, an F_E quad already, is reached across quad `g` as an F_F face.
#[cold]
pub(crate) fn quad_read_as_ff_face(h: usize, g: usize) -> DooError {
    let reason = format!("it is both an F_E quad and, across quad {g}, an F_F face");
    DooError::NotDooConnectivity { face: h, reason }
}

/// State of the F_F search over the fine mesh.
struct Search<'a> {
    fine: &'a CornerMesh,
    positions: &'a [DVec3],
    maps: FaceMaps,
    corner_face: Vec<u32>,
    /// Role of each face in the current interpretation.
    role: Vec<u8>,
    /// F_F faces of the current interpretation, in search order.
    queue: Vec<u32>,
    /// Scratch of [`Self::energy`], per vertex (reset after each use): the rank of the
    /// F_F corner at the vertex (F_F corners counted in memory order); by rank, whether
    /// its group was summed and its candidate.
    ff_corner_of_vertex: Vec<u32>,
    grouped: Vec<bool>,
    candidate: Vec<DVec3>,
    /// The ranks of the last valid reading of the whole mesh ([`Self::energy`]) or of a
    /// given seed that covers it ([`Self::seed_covers_all`]), by vertex.
    ranks: Vec<u32>,
    /// Scratch of [`Self::energy`]: one face's points, one group.
    points: Vec<DVec3>,
    group: Vec<u32>,
    /// Scratch of [`Self::energy`]: the ranks of the candidates of one group.
    ranks_in_group: Vec<u32>,
    stats: ReverseStats,
    /// The first reading of a closed one-component mesh, built by [`Self::choose`] to
    /// evaluate its dual reading (with its seed face), for the build to use.
    prebuilt: Option<(usize, Closed)>,
}

impl<'a> Search<'a> {
    fn new(fine: &'a CornerMesh, positions: &'a [DVec3], maps: FaceMaps) -> Self {
        Self {
            fine,
            positions,
            maps,
            corner_face: faces_of_corners(&fine.offsets),
            role: vec![UNKNOWN; fine.face_count()],
            queue: Vec::new(),
            ff_corner_of_vertex: Vec::new(),
            grouped: Vec::new(),
            candidate: Vec::new(),
            ranks: Vec::new(),
            points: Vec::new(),
            group: Vec::new(),
            ranks_in_group: Vec::new(),
            stats: ReverseStats::default(),
            prebuilt: None,
        }
    }

    fn face_size(&self, f: usize) -> usize {
        (self.fine.offsets[f + 1] - self.fine.offsets[f]) as usize
    }

    /// Connected components of faces (across interior edges), labelled in order of their
    /// lowest face.
    fn face_components(&self) -> (Vec<u32>, usize) {
        let faces = self.fine.face_count();
        let mut label = vec![NONE; faces];
        let mut stack = Vec::new();
        let mut count = 0u32;
        for s in 0..faces {
            if label[s] != NONE {
                continue;
            }
            label[s] = count;
            stack.push(s as u32);
            while let Some(f) = stack.pop() {
                for c in self.fine.offsets[f as usize]..self.fine.offsets[f as usize + 1] {
                    let t = self.fine.corner_twin[c as usize];
                    if t != NONE {
                        let g = self.corner_face[t as usize] as usize;
                        if label[g] == NONE {
                            label[g] = count;
                            stack.push(g as u32);
                        }
                    }
                }
            }
            count += 1;
        }
        (label, count as usize)
    }

    fn broken(face: usize, reason: String) -> DooError {
        DooError::NotDooConnectivity { face, reason }
    }

    /// The fine corner across the F_E quad from F_F corner `fc` (the corner of the next
    /// F_F face at the far end of the quad), checking the quad on the way.
    #[inline]
    fn across(&self, f: usize, fc: u32) -> Result<Option<u32>, DooError> {
        Ok(self.across_quad(f, fc)?.map(|(_, gt)| gt))
    }

    /// [`Self::across`], also giving the quad crossed.
    #[inline(always)]
    fn across_quad(&self, f: usize, fc: u32) -> Result<Option<(u32, u32)>, DooError> {
        let fine = self.fine;
        let ft = fine.corner_twin[fc as usize];
        if ft == NONE {
            return Ok(None);
        }
        let g = self.corner_face[ft as usize] as usize;
        let first = fine.offsets[g];
        if fine.offsets[g + 1] - first != 4 {
            return Err(not_a_quad(f, g, self.face_size(g)));
        }
        // The opposite corner of the quad, by index arithmetic (corners are face by face).
        let far = first + ((ft - first + 2) & 3);
        let gt = fine.corner_twin[far as usize];
        if gt == NONE {
            return Err(quad_on_boundary(f, g));
        }
        Ok(Some((g as u32, gt)))
    }

    /// Breadth-first search from `seed` as an F_F face; marks the roles. On error the
    /// roles of the component are left partly set: call [`Self::reset`].
    fn classify(&mut self, seed: usize) -> Result<(), DooError> {
        let start = self.queue.len();
        self.role[seed] = FF;
        self.queue.push(seed as u32);
        let mut head = start;
        while head < self.queue.len() {
            let f = self.queue[head] as usize;
            head += 1;
            self.stats.visited_faces += 1;
            for fc in self.fine.offsets[f]..self.fine.offsets[f + 1] {
                self.stats.edges_crossed += 1;
                let Some((g, gt)) = self.across_quad(f, fc)? else { continue };
                let g = g as usize;
                match self.role[g] {
                    FF => return Err(ff_faces_share_an_edge(f, g)),
                    _ => self.role[g] = FE,
                }
                let h = self.corner_face[gt as usize] as usize;
                match self.role[h] {
                    FE => return Err(quad_read_as_ff_face(h, g)),
                    FF => {}
                    _ => {
                        self.role[h] = FF;
                        self.queue.push(h as u32);
                    }
                }
            }
        }
        Ok(())
    }

    /// Clears the roles of one component (its faces `component_faces`) and drops the
    /// queue entries from `queue_start`.
    fn reset(&mut self, component_faces: FaceSet<'_>, queue_start: usize) {
        for f in component_faces.iter() {
            self.role[f as usize] = UNKNOWN;
        }
        self.queue.truncate(queue_start);
    }

    /// The F_F corner before `fc` in its face.
    #[inline]
    fn prev_in_face(&self, fc: u32) -> u32 {
        let f = self.corner_face[fc as usize] as usize;
        if fc == self.fine.offsets[f] { self.fine.offsets[f + 1] - 1 } else { fc - 1 }
    }

    /// What [`Self::energy`] found of a valid reading, kept for the build when the reading
    /// covers the whole mesh (`whole`): its candidates and the coarse corner of each
    /// vertex. Nothing is kept for a reading of one component of several.
    fn keep_reading(&mut self, whole: bool) -> Kept {
        if !whole {
            return Kept::default();
        }
        Kept { candidates: std::mem::take(&mut self.candidate), corner_of_vertex: std::mem::take(&mut self.ranks) }
    }

    /// The squared detail norm of one coarse vertex whose candidates have the ranks
    /// [`Self::ranks_in_group`] (sorted here): summed in rank order, as
    /// [`means_and_details`] sums the vertex in the result (the same operations in the
    /// same order). A rank past the candidates (a vertex on no F_F face, which the callers
    /// rule out first) counts as a zero candidate.
    fn group_energy(&mut self) -> f64 {
        insertion_sort(&mut self.ranks_in_group);
        let ranks = &self.ranks_in_group;
        let candidate = |r: u32| self.candidate.get(r as usize).copied().unwrap_or(DVec3::ZERO);
        let mean = ranks.iter().map(|&r| candidate(r)).sum::<DVec3>() / ranks.len() as f64;
        let mut energy = 0.0;
        for &r in ranks {
            energy += (candidate(r) - mean).length_squared();
        }
        energy
    }

    /// Whether the candidate of vertex `v` is in a group already in [`Self::energy`], marking
    /// it so (by the rank of its F_F corner, as the candidates); `true` for a vertex on no
    /// F_F face (which the callers rule out first).
    #[inline]
    fn mark_grouped(&mut self, v: u32) -> bool {
        let rank = self.ff_corner_of_vertex[v as usize] as usize;
        self.grouped.get_mut(rank).is_none_or(|grouped| std::mem::replace(grouped, true))
    }

    /// Total squared detail norm of the current interpretation of a component (whose F_F
    /// faces are `self.queue[queue_start..]`), and the component's size (bounding-box
    /// diagonal) for the zero test. Also checks that every vertex of the component is a
    /// corner of exactly one F_F face.
    ///
    /// One streaming pass, nothing materialised but per-vertex scratch arrays reused from
    /// call to call: every F_F face is expanded into the candidates of its corners, and
    /// the candidates are grouped by the faces that are neither F_F nor F_E (in a valid
    /// reading these are the F_V faces, whose corners are exactly the candidates of one
    /// coarse vertex). Candidates on no such face (coarse boundary vertices) are grouped
    /// by walking across the F_E quads around their coarse vertex. A reading that is not
    /// valid may get a meaningless energy here; the full check of [`Self::finish`]
    /// rejects it before it is used.
    ///
    /// The groups are summed in face order, and the sum stops as soon as it reaches
    /// `cutoff` (the smallest total of the readings before: this one cannot win, ties go
    /// to the earliest); the third value says whether it stopped.
    fn energy(
        &mut self,
        queue_start: usize,
        component_faces: FaceSet<'_>,
        component_vertices: usize,
        cutoff: f64,
        defer: bool,
    ) -> Result<Energy, DooError> {
        let fine = self.fine;
        if self.ff_corner_of_vertex.len() != fine.vertex_count {
            self.ff_corner_of_vertex = vec![NONE; fine.vertex_count];
        }
        if self.grouped.len() != fine.vertex_count {
            self.grouped = vec![false; fine.vertex_count];
        }
        if self.candidate.len() != fine.vertex_count {
            self.candidate = vec![DVec3::ZERO; fine.vertex_count];
        }
        let result = self.energy_inner(queue_start, component_faces, component_vertices, cutoff, defer);
        if result.is_ok() && matches!(component_faces, FaceSet::All(_)) {
            // A valid reading of the whole mesh: the rank of each vertex's F_F corner is
            // its coarse corner in the result, kept for it (see [`Self::choose`]).
            self.ranks = std::mem::take(&mut self.ff_corner_of_vertex);
            self.grouped.fill(false);
        } else if 4 * component_vertices >= fine.vertex_count {
            // A large component: clearing everything (sequential) is cheaper than visiting
            // the F_F faces again (scattered).
            self.ff_corner_of_vertex.fill(NONE);
            self.grouped.fill(false);
        } else {
            for &f in &self.queue[queue_start..] {
                for fc in fine.offsets[f as usize]..fine.offsets[f as usize + 1] {
                    let v = fine.corner_vertex[fc as usize] as usize;
                    let rank = std::mem::replace(&mut self.ff_corner_of_vertex[v], NONE);
                    if let Some(grouped) = self.grouped.get_mut(rank as usize) {
                        *grouped = false;
                    }
                }
            }
        }
        result
    }

    fn energy_inner(
        &mut self,
        queue_start: usize,
        component_faces: FaceSet<'_>,
        component_vertices: usize,
        cutoff: f64,
        defer: bool,
    ) -> Result<Energy, DooError> {
        let fine = self.fine;
        let positions = self.positions;
        // Every vertex on one F_F face at most; candidates by expansion of each F_F face.
        // The F_F faces in memory order (the search order only decides which of two F_F
        // faces sharing a vertex is named: then the search order is replayed).
        let mut points = std::mem::take(&mut self.points);
        let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        let mut shared = false;
        // First the positions, gathered in F_F corner order (the rank of each F_F corner
        // in memory order, kept per vertex): a tight loop whose scattered reads overlap.
        // The candidates are then indexed by rank, written in order and read in face
        // order. More F_F corners than vertices means a vertex on two F_F faces (`shared`
        // is set then): nothing is written past the end.
        let capacity = self.candidate.len();
        let mut rank = 0usize;
        for f in component_faces.iter() {
            if self.role[f as usize] != FF {
                continue;
            }
            let (b, e) = (fine.offsets[f as usize] as usize, fine.offsets[f as usize + 1] as usize);
            for &v in &fine.corner_vertex[b..e] {
                shared |= std::mem::replace(&mut self.ff_corner_of_vertex[v as usize], rank as u32) != NONE;
                let p = positions[v as usize];
                lo = lo.min(p);
                hi = hi.max(p);
                if rank < capacity {
                    self.candidate[rank] = p;
                }
                rank += 1;
            }
        }
        let ff_corners = rank;
        if !shared {
            // Each F_F face expanded in place.
            let mut start = 0;
            for f in component_faces.iter() {
                if self.role[f as usize] != FF {
                    continue;
                }
                let m = self.face_size(f as usize);
                points.clear();
                points.extend_from_slice(&self.candidate[start..start + m]);
                self.maps.inverse(&points, &mut self.candidate[start..start + m]);
                start += m;
            }
        }
        self.points = points;
        if shared {
            self.ff_corner_of_vertex.fill(NONE);
            return Err(self.shared_vertex_in_search_order(queue_start));
        }
        // Every vertex on one F_F face at least: as no vertex is on two, the F_F faces
        // have as many corners as the component has vertices. Else find the culprit.
        if ff_corners != component_vertices {
            for f in component_faces.iter() {
                for c in fine.offsets[f as usize]..fine.offsets[f as usize + 1] {
                    let v = fine.corner_vertex[c as usize] as usize;
                    if self.ff_corner_of_vertex[v] == NONE {
                        return Err(Self::broken(f as usize, format!("its corner vertex {v} is on no F_F face")));
                    }
                }
            }
        }
        let size = (hi - lo).length();
        if defer {
            return Ok(Energy { energy: f64::NAN, size, stopped_early: false, deferred: true });
        }
        self.group_sum(component_faces, ff_corners, cutoff, size)
    }

    /// Completes a deferred [`Self::energy`] of the whole mesh, whose ranks and
    /// candidates were kept (`kept`, given back with them on success): its sum over the
    /// groups, without a cutoff.
    fn complete_energy(&mut self, kept: &mut Kept, faces: FaceSet<'_>, size: f64) -> Result<f64, DooError> {
        self.ff_corner_of_vertex = std::mem::take(&mut kept.corner_of_vertex);
        self.candidate = std::mem::take(&mut kept.candidates);
        let result = self.group_sum(faces, self.fine.vertex_count, NO_CUTOFF, size);
        if result.is_ok() {
            kept.corner_of_vertex = std::mem::take(&mut self.ff_corner_of_vertex);
            kept.candidates = std::mem::take(&mut self.candidate);
        } else {
            self.ff_corner_of_vertex.fill(NONE);
        }
        self.grouped.fill(false);
        result.map(|reading| reading.energy)
    }

    /// The sum of [`Self::energy`] over the groups of the current reading, whose
    /// candidates are formed (`ff_corners` of them, every vertex on one F_F face; `size`:
    /// the component's size).
    fn group_sum(
        &mut self,
        component_faces: FaceSet<'_>,
        ff_corners: usize,
        cutoff: f64,
        size: f64,
    ) -> Result<Energy, DooError> {
        let fine = self.fine;
        // Groups of interior coarse vertices: the corners of the other faces. Each group is
        // summed in the order of its coarse corners (the ranks), as the result sums its
        // coarse vertex, so that the energy of a whole reading is its detail energy.
        let mut energy = 0.0;
        let mut grouped = 0;
        for f in component_faces.iter() {
            if self.role[f as usize] != UNKNOWN {
                continue;
            }
            let corners = fine.offsets[f as usize] as usize..fine.offsets[f as usize + 1] as usize;
            self.ranks_in_group.clear();
            for &v in &fine.corner_vertex[corners] {
                let rank = self.ff_corner_of_vertex[v as usize];
                self.ranks_in_group.push(rank);
                grouped += usize::from(!self.mark_grouped(v));
            }
            energy += self.group_energy();
            if energy >= cutoff {
                return Ok(Energy { energy, size, stopped_early: true, deferred: false });
            }
        }
        if grouped == ff_corners {
            // No boundary: every candidate is in a group already.
            self.stats.interpretations += 1;
            return Ok(Energy { energy, size, stopped_early: false, deferred: false });
        }
        // Groups of boundary coarse vertices: walk both ways around the coarse vertex
        // (clockwise: across the quad, then the next corner; counter-clockwise: the
        // previous corner, then across), stopping at the boundary or at a grouped vertex.
        // Each is met at its first F_F corner in memory order, the order in which the
        // result numbers the boundary vertices, so that the sum is the result's detail
        // energy (and a canonical mesh sums it without replaying the search order). The
        // search has crossed every F_F edge already: no walk meets a broken quad.
        let mut group = std::mem::take(&mut self.group);
        for f in component_faces.iter() {
            let f = f as usize;
            if self.role[f] != FF {
                continue;
            }
            for fc in fine.offsets[f]..fine.offsets[f + 1] {
                if self.mark_grouped(fine.corner_vertex[fc as usize]) {
                    continue;
                }
                group.clear();
                group.push(fc);
                for clockwise in [true, false] {
                    let mut c = fc;
                    loop {
                        let step = if clockwise {
                            self.across(self.corner_face[c as usize] as usize, c)?.map(|gt| fine.next(gt))
                        } else {
                            let p = self.prev_in_face(c);
                            self.across(self.corner_face[p as usize] as usize, p)?
                        };
                        let Some(d) = step else { break };
                        if self.mark_grouped(fine.corner_vertex[d as usize]) {
                            break;
                        }
                        group.push(d);
                        c = d;
                    }
                }
                self.ranks_in_group.clear();
                for &c in &group {
                    let rank = self.ff_corner_of_vertex[fine.corner_vertex[c as usize] as usize];
                    self.ranks_in_group.push(rank);
                }
                energy += self.group_energy();
                if energy >= cutoff {
                    self.group = group;
                    return Ok(Energy { energy, size, stopped_early: true, deferred: false });
                }
            }
        }
        self.group = group;
        self.stats.interpretations += 1;
        Ok(Energy { energy, size, stopped_early: false, deferred: false })
    }

    /// The first vertex on two F_F faces met in search order (some vertex is), as an error.
    #[cold]
    fn shared_vertex_in_search_order(&mut self, queue_start: usize) -> DooError {
        let fine = self.fine;
        for &f in &self.queue[queue_start..] {
            for fc in fine.offsets[f as usize]..fine.offsets[f as usize + 1] {
                let v = fine.corner_vertex[fc as usize] as usize;
                let other = std::mem::replace(&mut self.ff_corner_of_vertex[v], fc);
                if other != NONE {
                    let g = self.corner_face[other as usize] as usize;
                    let f = f as usize;
                    return Self::broken(
                        f.max(g),
                        format!("vertex {v} is a corner of two F_F faces ({} and {})", f.min(g), f.max(g)),
                    );
                }
            }
        }
        unreachable!("internal: a vertex on two F_F faces is met in any order")
    }

    /// Whether the reading of the lowest face as F_F is valid and its F_F faces cover
    /// every vertex of the mesh once: then the mesh has one component. Returns its
    /// detail energy and size, with the search state as [`Self::choose`] leaves it after
    /// a first trial; otherwise restores the state as it was.
    fn first_reading_covers_all(&mut self, faces: FaceSet<'_>) -> Option<Energy> {
        let saved = self.stats;
        let result = self.classify(0).and_then(|()| self.energy(0, faces, self.fine.vertex_count, NO_CUTOFF, true));
        match result {
            Ok(reading) => Some(reading),
            Err(_) => {
                self.stats = saved;
                self.role.fill(UNKNOWN);
                self.queue.clear();
                None
            }
        }
    }

    /// Whether the reading of `seed` as F_F is valid as far as the search goes and its
    /// F_F faces cover every vertex of the mesh once: then the mesh has one component and
    /// the roles are kept; otherwise the state is restored.
    fn seed_covers_all(&mut self, seed: usize) -> bool {
        let fine = self.fine;
        let saved = self.stats;
        let mut covers = self.classify(seed).is_ok()
            && self.queue.iter().map(|&f| self.face_size(f as usize)).sum::<usize>() == fine.vertex_count;
        if covers {
            // As many F_F corners as vertices: each vertex once iff none twice. The rank of
            // each vertex's F_F corner (in memory order) is its coarse corner in the
            // result, kept for it.
            let mut ranks = vec![NONE; fine.vertex_count];
            let mut rank = 0u32;
            for f in 0..fine.face_count() {
                if self.role[f] == FF {
                    for &v in &fine.corner_vertex[fine.offsets[f] as usize..fine.offsets[f + 1] as usize] {
                        covers &= std::mem::replace(&mut ranks[v as usize], rank) == NONE;
                        rank += 1;
                    }
                }
            }
            if covers {
                self.ranks = ranks;
            }
        }
        if !covers {
            self.stats = saved;
            self.role.fill(UNKNOWN);
            self.queue.clear();
        }
        covers
    }

    /// Automatic choice of the interpretation of component `k` (its faces `faces`, in
    /// increasing order, and its number of vertices `vertices`). Returns the choice, the valid readings ranked best first, and the
    /// F_F faces of the best one.
    ///
    /// `first`: the result of the first trial (the lowest face as F_F) if it was made
    /// already ([`Self::first_reading_covers_all`]).
    fn choose(
        &mut self,
        k: usize,
        faces: FaceSet<'_>,
        vertices: usize,
        mut first: Option<Energy>,
        rule: FaceRule,
    ) -> Result<(SeedChoice, Ranked, Vec<u32>, Kept), DooError> {
        let lowest = faces.first() as usize;
        // A first trial made already is the whole queue.
        let queue_start = if first.is_some() { 0 } else { self.queue.len() };
        let mut trials = Vec::new();

        // A first valid reading: the lowest face, else its neighbours in order, else
        // theirs. On a Doo-Sabin mesh an F_F face is never further away: an F_E quad lies
        // between two F_F faces, and an F_V face (around an inner coarse vertex) is
        // surrounded by F_E quads. Two rings are needed on an open mesh whose lowest face
        // is an F_V face: its F_E neighbours may fail as F_F faces, and so does its own
        // dual reading, whose F_E quads meet the boundary.
        let mut first_error = None;
        let mut candidates: Vec<(usize, &'static str)> = vec![(lowest, "F_F")];
        for ring in 0..2 {
            let inner = if ring == 0 { 0..1 } else { 1..candidates.len() };
            for k in inner {
                let f = candidates[k].0;
                for c in self.fine.offsets[f] as usize..self.fine.offsets[f + 1] as usize {
                    let t = self.fine.corner_twin[c];
                    if t != NONE {
                        let g = self.corner_face[t as usize] as usize;
                        if !candidates.iter().any(|&(s, _)| s == g) {
                            candidates.push((g, "neighbour"));
                        }
                    }
                }
            }
        }
        // Per valid reading: its seed, energy (a lower bound if its sum stopped early), F_F
        // faces and, on a whole mesh, candidates (numbered by F_F corner in memory order:
        // the coarse corners of the result).
        let whole = matches!(faces, FaceSet::All(_));
        let mut found: Vec<Found> = Vec::new();
        let mut other_classes = Vec::new();
        let mut scale = 0.0;
        for (seed, class) in candidates {
            let result = match first.take() {
                Some(reading) => Ok(reading),
                None => self.classify(seed).and_then(|()| self.energy(queue_start, faces, vertices, NO_CUTOFF, whole)),
            };
            match result {
                Ok(Energy { energy, size, deferred, .. }) => {
                    scale = size;
                    // The other classes of this reading.
                    let fv = faces.iter().find(|&f| self.role[f as usize] == UNKNOWN);
                    let fe = faces.iter().find(|&f| self.role[f as usize] == FE);
                    let ff_faces = self.queue[queue_start..].to_vec();
                    let mut kept = self.keep_reading(whole);
                    if whole && fv.is_some() {
                        // A closed mesh: built now, while the roles of the search are set
                        // ([`Self::finish_closed`] reads its F_E quads), also so that its
                        // dual reading is read from the structure ([`Self::dual_energy`]).
                        self.prebuilt = self
                            .finish_closed(rule, &mut kept.candidates, true, &kept.corner_of_vertex)
                            .map(|closed| (seed, closed));
                    }
                    // The sum over the groups, if left to here: the built result's detail
                    // energy (the same sums in the same order), else summed now.
                    let energy = match (deferred, &self.prebuilt) {
                        (false, _) => energy,
                        (true, Some((_, closed))) => {
                            self.stats.interpretations += 1;
                            closed.energies[0]
                        }
                        (true, None) => match self.complete_energy(&mut kept, faces, size) {
                            Ok(energy) => energy,
                            Err(error) => {
                                trials.push(SeedTrial::invalid(seed, class, &error));
                                first_error.get_or_insert(error);
                                self.reset(faces, queue_start);
                                continue;
                            }
                        },
                    };
                    trials.push(SeedTrial::valid(seed, "F_F", energy, false));
                    if let Some(f) = fv {
                        other_classes.push((f as usize, "F_V"));
                    }
                    if let Some(f) = fe {
                        other_classes.push((f as usize, "F_E"));
                    }
                    found.push(Found { seed, energy, stopped_early: false, ff_faces, kept });
                    self.reset(faces, queue_start);
                    break;
                }
                Err(error) => {
                    trials.push(SeedTrial::invalid(seed, class, &error));
                    first_error.get_or_insert(error);
                    self.reset(faces, queue_start);
                }
            }
        }
        let Some(first) = found.first() else {
            return Err(first_error.expect("internal: a failed search leaves an error"));
        };
        let zero = |energy: f64| details_are_zero(energy, scale, faces.len());
        if !zero(first.energy) {
            // The smallest total so far: a reading whose sum reaches it cannot win.
            let mut cutoff = first.energy;
            // The F_E quads of the first reading fall into two classes where the mesh is
            // all quads (the two directions of a quad grid), each a valid reading of its
            // own: the second is the lowest face that the first F_E reading calls an F_V
            // face, queued when that reading is valid.
            let mut second_fe_class_queued = false;
            let mut next = 0;
            while let Some(&(seed, class)) = other_classes.get(next) {
                next += 1;
                if let Some((_, closed)) = self.prebuilt.as_ref().filter(|_| class == "F_V") {
                    // The first reading's candidates are in the built result: their memory
                    // serves as scratch.
                    let Kept { candidates, corner_of_vertex } = &mut found[0].kept;
                    if let Some(energy) = self.dual_energy(closed, corner_of_vertex, candidates, cutoff) {
                        // Stopped early: the search it stands for visits every F_V face and
                        // looks across each of their edges (one per fine vertex).
                        self.stats.visited_faces += closed.fv_faces.len();
                        self.stats.edges_crossed += self.fine.vertex_count;
                        trials.push(SeedTrial::valid(seed, class, energy, true));
                        found.push(Found {
                            seed,
                            energy,
                            stopped_early: true,
                            ff_faces: Vec::new(),
                            kept: Kept::default(),
                        });
                        continue;
                    }
                }
                let result =
                    self.classify(seed).and_then(|()| self.energy(queue_start, faces, vertices, cutoff, false));
                match result {
                    Ok(Energy { energy, stopped_early, .. }) => {
                        trials.push(SeedTrial::valid(seed, class, energy, stopped_early));
                        if class == "F_E"
                            && !second_fe_class_queued
                            && let Some(f) = faces.iter().find(|&f| self.role[f as usize] == UNKNOWN)
                            && !found.iter().any(|found| found.seed == f as usize)
                        {
                            other_classes.push((f as usize, "F_E"));
                            second_fe_class_queued = true;
                        }
                        // A reading stopped early is never the best: nothing of it is kept.
                        let kept = self.keep_reading(whole && !stopped_early);
                        let ff_faces = if stopped_early { Vec::new() } else { self.queue[queue_start..].to_vec() };
                        found.push(Found { seed, energy, stopped_early, ff_faces, kept });
                        if !stopped_early {
                            cutoff = cutoff.min(energy);
                        }
                    }
                    Err(error) => trials.push(SeedTrial::invalid(seed, class, &error)),
                }
                self.reset(faces, queue_start);
            }
        }
        // Smallest energy, earliest on ties (the sort below is stable).
        let mut best = 0;
        for (i, f) in found.iter().enumerate() {
            if f.energy < found[best].energy {
                best = i;
            }
        }
        let (seed, energy) = (found[best].seed, found[best].energy);
        debug_assert!(!found[best].stopped_early, "internal: a reading stopped early is never the best");
        let reason = if found.len() == 1 && zero(energy) {
            zero_details_reason(seed)
        } else if found.len() == 1 {
            only_valid_reason(seed)
        } else {
            let others: Vec<(usize, f64, bool)> =
                found.iter().filter(|f| f.seed != seed).map(|f| (f.seed, f.energy, f.stopped_early)).collect();
            ranking_reason(energy, &others)
        };
        let mut rank: Vec<usize> = (0..found.len()).collect();
        rank.sort_by(|&a, &b| found[a].energy.total_cmp(&found[b].energy));
        let ranked: Vec<(usize, f64)> = rank.iter().map(|&i| (found[i].seed, found[i].energy)).collect();
        let best_ff_faces = std::mem::take(&mut found[rank[0]].ff_faces);
        let best_candidates = std::mem::take(&mut found[rank[0]].kept);
        let choice = SeedChoice::automatic(k, seed, trials, energy, reason);
        Ok((choice, ranked, best_ff_faces, best_candidates))
    }

    /// [`Self::finish`] for a mesh of one component whose reading covers every vertex once
    /// (`canonical_of_vertex`: the coarse corner of each fine vertex) and whose coarse mesh
    /// is closed, in fewer passes, with the roles of the search set (F_F faces and F_E
    /// quads): the coarse twins and the quad matching come from one pass over the quads in
    /// face order (no walk across them), the faces that are neither F_F faces nor F_E
    /// quads are taken in face order as the F_V faces, each checked to be the counter-clockwise orbit
    /// of one coarse vertex, which numbers the coarse vertices as the input numbers their
    /// F_V faces (as [`find_vertex_faces`] and [`coarse_vertex_order`] do), gives each
    /// vertex's corners and the F_V matching; the two checks of the coarse manifold ride
    /// on that pass and on the means. `None` at the first mismatch of any kind: then
    /// [`Self::finish`] runs and names the face at fault. When it gives a result, it is
    /// the one of [`Self::finish`] (same coarse mesh, details, order and energies).
    ///
    /// `buffer`: the candidates by coarse corner if `ready`, else scratch for them.
    fn finish_closed(
        &self,
        rule: FaceRule,
        buffer: &mut Vec<DVec3>,
        ready: bool,
        canonical_of_vertex: &[u32],
    ) -> Option<Closed> {
        let fine = self.fine;
        let faces = fine.face_count();
        if canonical_of_vertex.len() != fine.vertex_count || fine.corner_twin.contains(&NONE) {
            return None;
        }
        // Coarse faces: the F_F faces in increasing order; fine vertex of each coarse corner,
        // and the coarse corner of each F_F face's first corner.
        let mut coarse_offsets = Vec::with_capacity(faces / 3 + 2);
        coarse_offsets.push(0u32);
        let mut ff_faces = Vec::with_capacity(faces / 3 + 1);
        let mut vertex_of = Vec::with_capacity(fine.vertex_count);
        let mut start_of = vec![NONE; faces];
        for (f, start) in start_of.iter_mut().enumerate() {
            if self.role[f] != FF {
                continue;
            }
            *start = vertex_of.len() as u32;
            ff_faces.push(f as u32);
            vertex_of.extend_from_slice(&fine.corner_vertex[fine.offsets[f] as usize..fine.offsets[f + 1] as usize]);
            coarse_offsets.push(vertex_of.len() as u32);
        }
        let coarse_corners = vertex_of.len();
        if coarse_corners != fine.vertex_count || faces >= 1 << 30 {
            return None;
        }
        let coarse_next = next_of_corners(&coarse_offsets);
        // The coarse corner of fine corner `x` if it is on an F_F face, else NONE.
        let ff_corner = |x: u32| {
            let h = self.corner_face[x as usize] as usize;
            match start_of[h] {
                NONE => NONE,
                start => start + (x - fine.offsets[h]),
            }
        };
        // Coarse twins from the F_E quads of the search, in face order, read through the
        // fine twins (no lookup by vertex): quad `(c, next(t), t, next(c))` (rotated by its
        // start `s`) has the twins of F_F corners `c` and `t` at `s + 3` and `s + 1` (the
        // half-edges `next(c) -> c` and `next(t) -> t`), none at `s` and `s + 2`; `c < t`;
        // its corners must be those fine vertices, and every coarse corner on one quad.
        // Then the quad holds the twin of the fine half-edge of F_F corner `c` and,
        // opposite it, the one of `t`: what the search and the full build find across
        // from `c`. Each quad is kept at `c` with its rotation (the quads are listed in
        // order of their smaller corner, as [`match_fine_faces`] does), and its `c` and
        // `s` by face for the F_V faces.
        let mut twins = vec![NONE; coarse_corners];
        let mut quad_at = vec![NONE; coarse_corners];
        let mut quad_corner = vec![NONE; faces];
        let mut quads = 0;
        for (q, _) in self.role.iter().enumerate().filter(|(_, role)| **role == FE) {
            let (b, e) = (fine.offsets[q] as usize, fine.offsets[q + 1] as usize);
            if e - b != 4 {
                return None;
            }
            let y = &fine.corner_vertex[b..e];
            let cc = [0, 1, 2, 3].map(|i| ff_corner(fine.corner_twin[b + i]));
            let s = match cc.map(|c| c != NONE) {
                [false, true, false, true] => 0,
                [true, false, true, false] => 1,
                _ => return None,
            };
            let s = if cc[(s + 3) & 3] < cc[s + 1] { s } else { s + 2 };
            let (c, t) = (cc[(s + 3) & 3] as usize, cc[(s + 1) & 3] as usize);
            let cycle =
                [vertex_of[c], vertex_of[coarse_next[t] as usize], vertex_of[t], vertex_of[coarse_next[c] as usize]];
            if (0..4).any(|k| y[(s + k) & 3] != cycle[k]) || twins[c] != NONE || twins[t] != NONE || c == t {
                return None;
            }
            twins[c] = t as u32;
            twins[t] = c as u32;
            quad_at[c] = (q as u32) << 2 | ((4 - s) & 3) as u32;
            quad_corner[q] = (c as u32) << 2 | s as u32;
            quads += 1;
        }
        drop(start_of);
        if 2 * quads != coarse_corners {
            return None;
        }
        let mut face_order = Vec::with_capacity(faces);
        let mut rotations = Vec::with_capacity(faces);
        face_order.extend_from_slice(&ff_faces);
        rotations.resize(ff_faces.len(), 0);
        for &packed in quad_at.iter().filter(|&&packed| packed != NONE) {
            face_order.push(packed >> 2);
            rotations.push(packed & 3);
        }
        drop(quad_at);

        // The other faces, in face order, are the F_V faces: each the counter-clockwise
        // orbit (`c -> next(twin(c))` backwards) of one coarse vertex, numbered in that
        // order, every coarse corner on exactly one. The corner of such a face at
        // `next(t)` (`t` the twin of `c`) is the twin of quad corner `s` (`c`) of the quad
        // of `c` (or of `s + 2`, the roles of `c` and `t` swapped), and the face's next
        // corner is at `c`: each corner's coarse corner comes through the fine twins, and
        // each one must be the previous corner's counter-clockwise one.
        let mut labels = vec![NONE; coarse_corners];
        let mut vertex_corner = Vec::with_capacity(faces - face_order.len());
        let mut by_vertex_offsets = Vec::with_capacity(faces - face_order.len() + 1);
        by_vertex_offsets.push(0u32);
        let mut by_vertex_corners: Vec<u32> = Vec::with_capacity(coarse_corners);
        let mut fv_faces = Vec::with_capacity(faces - face_order.len());
        for (g, _) in self.role.iter().enumerate().filter(|(_, role)| **role == UNKNOWN) {
            let (b, e) = (fine.offsets[g] as usize, fine.offsets[g + 1] as usize);
            let m = e - b;
            let label = vertex_corner.len() as u32;
            let start = by_vertex_corners.len();
            if m < 3 || start + m > coarse_corners {
                return None;
            }
            // Corner `j` gives its own coarse corner and the one of corner `j + 1`.
            let mut expected = NONE;
            let mut first = NONE;
            for (&x, &ft) in fine.corner_vertex[b..e].iter().zip(&fine.corner_twin[b..e]) {
                let q = self.corner_face[ft as usize] as usize;
                let packed = quad_corner[q];
                if self.role[q] != FE || packed == NONE {
                    return None;
                }
                let (c, s) = (packed >> 2, packed & 3);
                let t = twins[c as usize];
                let (own, next) = match (ft - fine.offsets[q]).wrapping_sub(s) & 3 {
                    0 => (coarse_next[t as usize], c),
                    2 => (coarse_next[c as usize], t),
                    _ => return None,
                };
                if vertex_of[own as usize] != x || (expected != NONE && own != expected) {
                    return None;
                }
                if first == NONE {
                    first = own;
                }
                expected = next;
                // No corner is labelled twice: two faces that are orbits through one
                // corner would be the same orbit, the same directed edges, which a mesh
                // has once.
                labels[own as usize] = label;
                by_vertex_corners.push(own);
            }
            if expected != first {
                return None;
            }
            let corners = &mut by_vertex_corners[start..];
            let (mut smallest, mut at) = (corners[0], 0);
            for (j, &c) in corners.iter().enumerate() {
                if c < smallest {
                    (smallest, at) = (c, j);
                }
            }
            insertion_sort(corners);
            vertex_corner.push(smallest);
            by_vertex_offsets.push(by_vertex_corners.len() as u32);
            face_order.push(g as u32);
            rotations.push(((m - at) % m) as u32);
            fv_faces.push(g as u32);
        }
        if by_vertex_corners.len() != coarse_corners {
            return None;
        }
        let coarse_vertex_count = vertex_corner.len();
        let coarse = CornerMesh {
            offsets: coarse_offsets,
            corner_vertex: labels,
            corner_twin: twins,
            corner_next: coarse_next,
            vertex_count: coarse_vertex_count,
            vertex_corner: Some(vertex_corner),
        };
        // The coarse manifold ([`check_coarse_manifold`]): no face visits a vertex twice;
        // no two edges join the same two vertices (the outgoing half-edges of a vertex are
        // its corners, the mesh being closed), checked beside the means.
        let mut stamp = Vec::new();
        for (k, w) in coarse.offsets.windows(2).enumerate() {
            if !distinct(&coarse.corner_vertex[w[0] as usize..w[1] as usize], &mut stamp, coarse_vertex_count, k as u32)
            {
                return None;
            }
        }
        let by_vertex = CornersByVertex::from_parts((by_vertex_offsets, by_vertex_corners));
        let expanded;
        let candidates = if ready && buffer.len() == coarse_corners {
            &buffer[..]
        } else {
            let scratch = std::mem::take(buffer);
            expanded = expand_faces(&coarse.offsets, &self.maps, |c| self.positions[vertex_of[c] as usize], scratch);
            &expanded[..]
        };
        stamp.fill(NONE);
        let mut manifold = true;
        let mut ends = Vec::new();
        let (coarse_positions, details, vertex_energy) =
            means_and_details_with(&by_vertex, candidates, |u, corners| {
                ends.clear();
                ends.extend(corners.iter().map(|&c| coarse.corner_vertex[coarse.corner_next[c as usize] as usize]));
                manifold &= distinct(&ends, &mut stamp, coarse_vertex_count, u as u32);
            });
        if !manifold {
            return None;
        }
        let identity_vertices = vertex_of.iter().enumerate().all(|(c, &x)| x == c as u32);
        let identity_faces = face_order.iter().enumerate().all(|(k, &g)| g == k as u32);
        let no_rotation = rotations.iter().all(|&r| r == 0);
        let order = FineOrder {
            vertices: if identity_vertices { Vec::new() } else { vertex_of },
            faces: if identity_faces { Vec::new() } else { face_order },
            rotations: if no_rotation { Vec::new() } else { rotations },
        };
        let mut stats = self.stats;
        stats.candidate_edges = coarse_corners;
        let energies = vec![vertex_energy.iter().sum()];
        let reversal = DooReversal::shrink(rule, coarse, coarse_positions, details, order, stats);
        Some(Closed { reversal, energies, fv_faces })
    }

    /// The detail energy of the dual reading of a closed reading built by
    /// [`Self::finish_closed`] (`closed`; `canonical_of_vertex`: the coarse corner of each
    /// fine vertex), as [`Self::energy`] sums it after the search from the lowest F_V face:
    /// that search finds the F_V faces as its F_F faces (the structure is checked), its
    /// candidates are the F_V faces expanded, its groups the F_F faces in face order, each
    /// summed in the order of its corners' F_V faces. Each F_V face is expanded when a
    /// group first needs it, and the sum stops as soon as it reaches `cutoff`: the partial
    /// sum then, `None` if it never does (the dual reading is better: the caller searches
    /// it in full). `dual`: scratch for the candidates, by coarse corner.
    fn dual_energy(
        &self,
        closed: &Closed,
        canonical_of_vertex: &[u32],
        dual: &mut Vec<DVec3>,
        cutoff: f64,
    ) -> Option<f64> {
        let fine = self.fine;
        let coarse = &closed.reversal.coarse;
        dual.resize(coarse.corner_count(), DVec3::ZERO);
        let mut expanded = vec![false; coarse.vertex_count];
        let (mut points, mut out) = (Vec::new(), Vec::new());
        let mut group = Vec::new();
        let mut energy = 0.0;
        for w in coarse.offsets.windows(2) {
            let (b, e) = (w[0] as usize, w[1] as usize);
            for &u in &coarse.corner_vertex[b..e] {
                if std::mem::replace(&mut expanded[u as usize], true) {
                    continue;
                }
                let g = closed.fv_faces[u as usize] as usize;
                let face = &fine.corner_vertex[fine.offsets[g] as usize..fine.offsets[g + 1] as usize];
                points.clear();
                points.extend(face.iter().map(|&x| self.positions[x as usize]));
                out.resize(face.len(), DVec3::ZERO);
                self.maps.inverse(&points, &mut out);
                for (&x, &p) in face.iter().zip(&out) {
                    dual[canonical_of_vertex[x as usize] as usize] = p;
                }
            }
            energy += dual_group_energy(&mut group, b as u32..e as u32, &coarse.corner_vertex, dual, 0);
            if energy >= cutoff {
                return Some(energy);
            }
        }
        None
    }

    /// Builds the coarse mesh, details and fine order from the roles of all components;
    /// also returns the total squared detail norm of each component. `buffer` holds the
    /// candidates by coarse corner if `ready` (and has one per coarse corner), else it is
    /// reused for them. `corner_of_vertex`: the coarse corner of each fine vertex, if a pass over the
    /// same F_F faces in the same order found each vertex on exactly one (else empty).
    fn finish(
        &self,
        rule: FaceRule,
        component_of_face: &[u32],
        component_count: usize,
        (buffer, ready): (Vec<DVec3>, bool),
        corner_of_vertex: Vec<u32>,
    ) -> Result<(DooReversal, Vec<f64>), DooError> {
        let fine = self.fine;
        let faces = fine.face_count();
        // Coarse faces: the F_F faces in increasing order.
        let ff_count = self.role.iter().filter(|&&r| r == FF).count();
        let mut coarse_offsets = Vec::with_capacity(ff_count + 1);
        coarse_offsets.push(0u32);
        let mut fine_corner_of = Vec::with_capacity(fine.vertex_count);
        let mut ff_faces = Vec::with_capacity(ff_count);
        // Fine vertex of each coarse corner; every fine vertex exactly once.
        let mut vertex_of = Vec::with_capacity(fine.vertex_count);
        let known = corner_of_vertex.len() == fine.vertex_count;
        let mut canonical_of_vertex = if known { corner_of_vertex } else { vec![NONE; fine.vertex_count] };
        // The coarse face of each F_F face (read in face order below, not by vertex).
        let mut coarse_face_of = vec![NONE; faces];
        for (f, coarse_face) in coarse_face_of.iter_mut().enumerate() {
            if self.role[f] != FF {
                continue;
            }
            *coarse_face = ff_faces.len() as u32;
            ff_faces.push(f as u32);
            for fc in fine.offsets[f]..fine.offsets[f + 1] {
                let x = fine.corner_vertex[fc as usize];
                let c = vertex_of.len() as u32;
                if known {
                    debug_assert_eq!(canonical_of_vertex[x as usize], c, "internal: the ranks are the coarse corners");
                    fine_corner_of.push(fc);
                    vertex_of.push(x);
                    continue;
                }
                let earlier = std::mem::replace(&mut canonical_of_vertex[x as usize], c);
                if earlier != NONE {
                    let g = self.corner_face[fine_corner_of[earlier as usize] as usize] as usize;
                    return Err(Self::broken(f, format!("vertex {x} is a corner of two F_F faces ({g} and {f})")));
                }
                fine_corner_of.push(fc);
                vertex_of.push(x);
            }
            coarse_offsets.push(vertex_of.len() as u32);
        }
        let coarse_corners = fine_corner_of.len();
        if let Some(x) = (!known).then(|| canonical_of_vertex.iter().position(|&c| c == NONE)).flatten() {
            let f = self.corner_face[fine.first_corner(x) as usize] as usize;
            return Err(Self::broken(f, format!("its corner vertex {x} is on no F_F face")));
        }

        // Coarse twins (through the F_E quads) and the quad of each coarse edge.
        let mut twins = vec![NONE; coarse_corners];
        let mut quad_face = vec![NONE; coarse_corners];
        for (k, &f) in ff_faces.iter().enumerate() {
            let first = coarse_offsets[k] as usize;
            for (c, fc) in (first..).zip(fine.offsets[f as usize]..fine.offsets[f as usize + 1]) {
                if let Some((g, gt)) = self.across_quad(f as usize, fc)? {
                    // The search made the face of `gt` an F_F face: its coarse corner is
                    // the one of `gt`'s position in that face.
                    // (Else, as every fine vertex is on one F_F face, the coarse corner of
                    // its vertex.)
                    let h = self.corner_face[gt as usize] as usize;
                    twins[c] = match coarse_face_of[h] {
                        NONE => canonical_of_vertex[fine.corner_vertex[gt as usize] as usize],
                        k => coarse_offsets[k as usize] + (gt - fine.offsets[h]),
                    };
                    debug_assert_eq!(twins[c], canonical_of_vertex[fine.corner_vertex[gt as usize] as usize]);
                    quad_face[c] = g;
                    debug_assert_eq!(fine_corner_of[twins[c] as usize], gt, "internal: the far face is F_F");
                }
            }
        }
        for c in 0..coarse_corners {
            let t = twins[c];
            if t != NONE && twins[t as usize] != c as u32 {
                return Err(Self::broken(
                    quad_face[c] as usize,
                    "this quad does not join the same two F_F edges from both sides".into(),
                ));
            }
            if t != NONE && quad_face[t as usize] != quad_face[c] {
                return Err(Self::broken(quad_face[c] as usize, "two F_F edges meet through different quads".into()));
            }
        }
        let coarse_next = next_of_corners(&coarse_offsets);

        // Candidate groups = coarse vertices: the corner after the twin is at the same
        // coarse vertex, so each group is one walk around its vertex (both ways on the
        // boundary). Groups are numbered in order of their smallest corner.
        let candidate_edges = twins.iter().filter(|&&t| t != NONE).count();
        let (labels, coarse_vertex_count) = corner_groups(&coarse_offsets, &coarse_next, &twins);
        let mut vertex_corner = vec![NONE; coarse_vertex_count];
        for (c, &l) in labels.iter().enumerate() {
            if vertex_corner[l as usize] == NONE {
                vertex_corner[l as usize] = c as u32;
            }
        }
        let mut coarse = CornerMesh {
            offsets: coarse_offsets,
            corner_vertex: labels,
            corner_twin: twins,
            corner_next: coarse_next,
            vertex_count: coarse_vertex_count,
            vertex_corner: Some(vertex_corner),
        };
        // Number the coarse vertices as the input numbers their F_V faces (interior
        // vertices; on a mesh made by `subdivide` this is the original order), then the
        // boundary vertices in order of first appearance.
        let vertex_face = find_vertex_faces(fine, &self.corner_face, &coarse, &vertex_of, &fine_corner_of)?;
        let new_order = coarse_vertex_order(&coarse, &vertex_face, faces);
        let mut renumber = vec![0u32; coarse_vertex_count];
        for (new, &old) in new_order.iter().enumerate() {
            renumber[old as usize] = new as u32;
        }
        for v in coarse.corner_vertex.iter_mut() {
            *v = renumber[*v as usize];
        }
        let old_corner = coarse.vertex_corner.take().expect("internal: vertex corners");
        coarse.vertex_corner = Some(new_order.iter().map(|&old| old_corner[old as usize]).collect());
        let vertex_face: Vec<u32> = new_order.iter().map(|&old| vertex_face[old as usize]).collect();
        // The remaining checks and the geometry are independent: with several threads they
        // run side by side (each is computed by one task, so the results and the first
        // error reported are those of the sequential order).
        let by_vertex = corners_by_vertex(&coarse);
        let check = || {
            check_coarse_manifold(&coarse, &ff_faces, &by_vertex)?;
            match_fine_faces(fine, &ff_faces, &coarse, &vertex_of, &quad_face, &vertex_face)
        };
        let geometry = || {
            // Candidates, means and details.
            let candidates = if ready && buffer.len() == vertex_of.len() {
                buffer
            } else {
                expand_faces(&coarse.offsets, &self.maps, |c| self.positions[vertex_of[c] as usize], buffer)
            };
            means_and_details(&by_vertex, &candidates)
        };
        let (checked, geometry) =
            if rayon::current_num_threads() > 1 { rayon::join(check, geometry) } else { (check(), geometry()) };
        let order = checked?;
        let (coarse_positions, details, vertex_energy) = geometry;
        debug_assert_eq!(coarse_positions.len() + details.len(), fine.vertex_count);
        let mut energies = vec![0.0; component_count];
        if component_count == 1 {
            energies[0] = vertex_energy.iter().sum();
        } else {
            for (corners, energy) in by_vertex.iter().zip(&vertex_energy) {
                let k = component_of_face[self.corner_face[fine_corner_of[corners[0] as usize] as usize] as usize];
                energies[k as usize] += energy;
            }
        }
        let mut stats = self.stats;
        stats.candidate_edges = candidate_edges;
        let reversal = DooReversal::shrink(rule, coarse, coarse_positions, details, order, stats);
        Ok((reversal, energies))
    }
}

/// The vertex groups of corners given the next corners and the twins: the corners around
/// one vertex, found by walking clockwise (`c -> next(twin(c))`) and, where that stops at
/// the boundary, counter-clockwise (`c -> twin(prev(c))`). Twins must be an involution.
/// Labels `0..count` in order of each group's smallest corner (as union-find would give).
fn corner_groups(offsets: &[u32], next: &[u32], twins: &[u32]) -> (Vec<u32>, usize) {
    let corners = next.len();
    let prev = prev_of_corners(offsets);
    let mut labels = vec![NONE; corners];
    let mut count = 0u32;
    for c in 0..corners as u32 {
        if labels[c as usize] != NONE {
            continue;
        }
        labels[c as usize] = count;
        let mut x = c;
        while twins[x as usize] != NONE {
            x = next[twins[x as usize] as usize];
            if labels[x as usize] != NONE {
                break;
            }
            labels[x as usize] = count;
        }
        let mut x = c;
        while twins[prev[x as usize] as usize] != NONE {
            x = twins[prev[x as usize] as usize];
            if labels[x as usize] != NONE {
                break;
            }
            labels[x as usize] = count;
        }
        count += 1;
    }
    (labels, count as usize)
}

/// Corners of each coarse vertex, in increasing corner order (CSR).
#[derive(Debug, PartialEq)]
pub(crate) struct CornersByVertex {
    offsets: Vec<u32>,
    corners: Vec<u32>,
}

impl CornersByVertex {
    /// From the `(offsets, corners)` of [`group_by_key`] on the corner vertices.
    pub(crate) fn from_parts((offsets, corners): VertexCorners) -> Self {
        Self { offsets, corners }
    }

    fn iter(&self) -> impl Iterator<Item = &[u32]> + '_ {
        self.offsets.windows(2).map(|w| &self.corners[w[0] as usize..w[1] as usize])
    }
}

pub(crate) fn corners_by_vertex(mesh: &CornerMesh) -> CornersByVertex {
    CornersByVertex::from_parts(group_by_key(&mesh.corner_vertex, mesh.vertex_count))
}

/// Start of vertex `v`'s details in the flat detail array (`Σ_{u<v} (r_u - 1)`).
fn details_offset(by_vertex: &CornersByVertex, v: usize) -> usize {
    by_vertex.offsets[v] as usize - v
}

/// Coarse vertex = mean of its candidates; details = prefix sums of the offsets; and each
/// vertex's squared detail norm `Σ |d_i|²` (one pass over the candidates).
pub(crate) fn means_and_details(
    by_vertex: &CornersByVertex,
    candidates: &[DVec3],
) -> (Vec<DVec3>, Vec<DVec3>, Vec<f64>) {
    means_and_details_with(by_vertex, candidates, |_, _| {})
}

/// [`means_and_details`], calling `before(v, corners)` before vertex `v` (of corners
/// `corners`) is summed (so that a caller can read the same candidates, or the same
/// corners, while they are in cache).
pub(crate) fn means_and_details_with(
    by_vertex: &CornersByVertex,
    candidates: &[DVec3],
    before: impl FnMut(usize, &[u32]),
) -> (Vec<DVec3>, Vec<DVec3>, Vec<f64>) {
    let vertices = by_vertex.offsets.len() - 1;
    means_and_details_in(by_vertex, candidates, 0..vertices, vertices, before)
}

/// [`means_and_details_with`] for the vertices `range` only (their means, details and
/// energies, in order), with room for those of `reserve` vertices from `range.start` on
/// (so that the values of the vertices after `range` can be appended without moving
/// these).
pub(crate) fn means_and_details_in(
    by_vertex: &CornersByVertex,
    candidates: &[DVec3],
    range: std::ops::Range<usize>,
    reserve: usize,
    mut before: impl FnMut(usize, &[u32]),
) -> (Vec<DVec3>, Vec<DVec3>, Vec<f64>) {
    let reserve = reserve.max(range.len());
    let (first, end) = (range.start, range.start + reserve);
    let detail_room = details_offset(by_vertex, end) - details_offset(by_vertex, first);
    // (The outputs of a large mesh, written once: on huge pages.)
    let mut means = advised_vec(reserve);
    let mut details = advised_vec(detail_room);
    let mut energies = advised_vec(reserve);
    let offsets = &by_vertex.offsets[range.start..=range.end];
    let mut long = Vec::new();
    for (v, w) in (range.start..).zip(offsets.windows(2)) {
        let corners = &by_vertex.corners[w[0] as usize..w[1] as usize];
        before(v, corners);
        let (mean, energy) = if corners.len() <= GATHERED {
            // Each candidate read once, into registers.
            let mut gathered = [DVec3::ZERO; GATHERED];
            for (slot, &c) in gathered.iter_mut().zip(corners) {
                *slot = candidates[c as usize];
            }
            mean_and_details(&mut gathered[..corners.len()], &mut details)
        } else {
            // Longer lists (vertices of high valence) in one buffer reused across them.
            long.clear();
            long.extend(corners.iter().map(|&c| candidates[c as usize]));
            mean_and_details(&mut long, &mut details)
        };
        means.push(mean);
        energies.push(energy);
    }
    (means, details, energies)
}

/// Vertices of at most this many candidates are summed from a copy on the stack.
const GATHERED: usize = 8;

/// The mean of one vertex's `candidates`, their details (appended) and squared detail
/// norm. The details are written over the candidates first and then appended in one
/// copy: the loop calls nothing and keeps its sums in registers (with a `push` per
/// detail, which may grow the vector, they lived on the stack).
#[inline(always)]
fn mean_and_details(candidates: &mut [DVec3], details: &mut Vec<DVec3>) -> (DVec3, f64) {
    let mean = candidates.iter().sum::<DVec3>() / candidates.len() as f64;
    let (last, rest) = candidates.split_last_mut().expect("a vertex has candidates");
    let mut prefix = DVec3::ZERO;
    let mut energy = 0.0;
    for slot in rest.iter_mut() {
        let offset = *slot - mean;
        energy += offset.length_squared();
        prefix += offset;
        *slot = prefix;
    }
    details.extend_from_slice(rest);
    (mean, energy + (*last - mean).length_squared())
}

/// The coarse vertices sorted by their F_V faces (`vertex_face`, [`NONE`] for boundary
/// vertices), then the boundary vertices by their first corner; equal keys keep the
/// vertex order. Linear: the F_V faces are listed by face (a counting sort with one slot
/// per face), the boundary vertices come in corner order.
fn coarse_vertex_order(coarse: &CornerMesh, vertex_face: &[u32], faces: usize) -> Vec<u32> {
    let mut vertex_of_face = vec![NONE; faces];
    for (v, &f) in vertex_face.iter().enumerate() {
        if f != NONE && std::mem::replace(&mut vertex_of_face[f as usize], v as u32) != NONE {
            // Two vertices claim one F_V face (the structure check rejects this later):
            // the general sort keeps their order.
            let key = |v: u32| match vertex_face[v as usize] {
                NONE => faces as u64 + coarse.first_corner(v as usize) as u64,
                f => f as u64,
            };
            let mut order: Vec<u32> = (0..vertex_face.len() as u32).collect();
            order.sort_by_key(|&v| key(v));
            return order;
        }
    }
    let mut order = Vec::with_capacity(vertex_face.len());
    order.extend(vertex_of_face.iter().copied().filter(|&v| v != NONE));
    if order.len() < vertex_face.len() {
        for (c, &v) in coarse.corner_vertex.iter().enumerate() {
            if vertex_face[v as usize] == NONE && coarse.first_corner(v as usize) == c as u32 {
                order.push(v);
            }
        }
    }
    order
}

/// The coarse mesh must be a valid manifold mesh: no face visits a vertex twice, and no
/// two edges join the same two vertices. `by_vertex`: the corners of each vertex.
pub(crate) fn check_coarse_manifold(
    coarse: &CornerMesh,
    ff_faces: &[u32],
    by_vertex: &CornersByVertex,
) -> Result<(), DooError> {
    let mut stamp = vec![NONE; coarse.vertex_count];
    for (f, &ff) in ff_faces.iter().enumerate() {
        for c in coarse.offsets[f]..coarse.offsets[f + 1] {
            let v = coarse.corner_vertex[c as usize] as usize;
            if stamp[v] == f as u32 {
                return Err(DooError::NotDooConnectivity {
                    face: ff as usize,
                    reason: "as an F_F face it would visit one coarse vertex twice".into(),
                });
            }
            stamp[v] = f as u32;
        }
    }
    let two_edges = |u: usize, w: u32, c: u32| {
        let f = ff_faces[faces_of_corner(coarse, c)] as usize;
        Err(DooError::NotDooConnectivity {
            face: f,
            reason: format!("the coarse mesh would have two edges between coarse vertices {u} and {w}"),
        })
    };
    if !coarse.corner_twin.contains(&NONE) {
        // Closed: the outgoing half-edges of a vertex are its corners, in increasing order.
        stamp.fill(NONE);
        for (u, corners) in by_vertex.iter().enumerate() {
            for &c in corners {
                let w = coarse.corner_vertex[coarse.corner_next[c as usize] as usize];
                if std::mem::replace(&mut stamp[w as usize], u as u32) == u as u32 {
                    return two_edges(u, w, c);
                }
            }
        }
        return Ok(());
    }
    // Outgoing half-edges of each vertex: from its corners, and the boundary half-edges
    // opposite boundary corners.
    let mut out_offsets = vec![0u32; coarse.vertex_count + 1];
    let mut push_count = |from: u32| out_offsets[from as usize + 1] += 1;
    for c in 0..coarse.corner_count() {
        push_count(coarse.corner_vertex[c]);
        if coarse.corner_twin[c] == NONE {
            push_count(coarse.corner_vertex[coarse.corner_next[c] as usize]);
        }
    }
    for v in 0..coarse.vertex_count {
        out_offsets[v + 1] += out_offsets[v];
    }
    let mut fill = out_offsets.clone();
    let mut targets = vec![(0u32, 0u32); out_offsets[coarse.vertex_count] as usize];
    for c in 0..coarse.corner_count() {
        let (u, w) = (coarse.corner_vertex[c], coarse.corner_vertex[coarse.corner_next[c] as usize]);
        targets[fill[u as usize] as usize] = (w, c as u32);
        fill[u as usize] += 1;
        if coarse.corner_twin[c] == NONE {
            targets[fill[w as usize] as usize] = (u, c as u32);
            fill[w as usize] += 1;
        }
    }
    stamp.fill(NONE);
    for u in 0..coarse.vertex_count {
        for &(w, c) in &targets[out_offsets[u] as usize..out_offsets[u + 1] as usize] {
            if stamp[w as usize] == u as u32 {
                return two_edges(u, w, c);
            }
            stamp[w as usize] = u as u32;
        }
    }
    Ok(())
}

fn faces_of_corner(mesh: &CornerMesh, c: u32) -> usize {
    mesh.offsets.partition_point(|&o| o <= c) - 1
}

/// The corners of interior coarse vertex `v`, counter-clockwise from its first corner
/// (empty for a boundary vertex).
fn vertex_cycle(coarse: &CornerMesh, v: usize, cycle: &mut Vec<u32>) {
    let start = coarse.first_corner(v);
    cycle.clear();
    cycle.push(start);
    if coarse.walk_clockwise(start, |c| cycle.push(c)).is_none() {
        cycle.clear();
        return;
    }
    cycle[1..].reverse();
}

/// For every coarse vertex, the input face that is its F_V face (found through the fine
/// half-edge between the first two of its candidates), [`NONE`] for boundary vertices.
fn find_vertex_faces(
    fine: &CornerMesh,
    corner_face: &[u32],
    coarse: &CornerMesh,
    vertex_of: &[u32],
    fine_corner_of: &[u32],
) -> Result<Vec<u32>, DooError> {
    let mut faces = vec![NONE; coarse.vertex_count];
    let mut cycle = Vec::new();
    for (v, slot) in faces.iter_mut().enumerate() {
        vertex_cycle(coarse, v, &mut cycle);
        if cycle.is_empty() {
            continue;
        }
        if cycle.len() == 2 {
            return Err(DooError::NotDooConnectivity {
                face: corner_face[fine_corner_of[cycle[0] as usize] as usize] as usize,
                reason: "a coarse vertex next to this face would have valence 2".into(),
            });
        }
        let to = vertex_of[cycle[1] as usize];
        let first = fine_corner_of[cycle[0] as usize];
        let mut found = None;
        let mut probe = |k: u32| {
            if found.is_none() && fine.corner_vertex[fine.next(k) as usize] == to {
                found = Some(k);
            }
        };
        probe(first);
        fine.walk_clockwise(first, &mut probe);
        match found {
            Some(k) => *slot = corner_face[k as usize],
            None => {
                return Err(DooError::NotDooConnectivity {
                    face: corner_face[first as usize] as usize,
                    reason: format!(
                        "no face has the edge {} -> {to} of the F_V face of a coarse vertex",
                        vertex_of[cycle[0] as usize]
                    ),
                });
            }
        }
    }
    Ok(faces)
}

/// Matches the canonical Doo-Sabin faces of `coarse` with the faces of `fine`, giving the
/// fine order; fails at the first fine face that does not fit.
fn match_fine_faces(
    fine: &CornerMesh,
    ff_faces: &[u32],
    coarse: &CornerMesh,
    vertex_of: &[u32],
    quad_face: &[u32],
    vertex_face: &[u32],
) -> Result<FineOrder, DooError> {
    let faces = fine.face_count();
    let mut matched = vec![false; faces];
    let mut face_order = Vec::with_capacity(faces);
    let mut rotations = Vec::with_capacity(faces);
    // F_F faces: the coarse faces, made of their corners in order (so they fit, without
    // rotation, and each is claimed once).
    for &g in ff_faces {
        matched[g as usize] = true;
    }
    face_order.extend_from_slice(ff_faces);
    rotations.resize(ff_faces.len(), 0);
    let broken = |face: usize, reason: String| DooError::NotDooConnectivity { face, reason };
    // Claims fine face `g` for the canonical face with (fine) vertices `cycle`.
    let mut claim = |g: usize, cycle: &[u32], what: &str| -> Result<(), DooError> {
        let (b, e) = (fine.offsets[g] as usize, fine.offsets[g + 1] as usize);
        let m = e - b;
        if m != cycle.len() {
            return Err(broken(g, format!("expected an {what} with {} sides, found {m}", cycle.len())));
        }
        // Corner `i` of the face must be `cycle[(i + r) mod m]`, `r` the first position of
        // its corner 0 in the cycle.
        let face = &fine.corner_vertex[b..e];
        let r = cycle.iter().position(|&x| x == face[0]);
        let fits = r.is_some_and(|r| {
            let (head, tail) = face.split_at(m - r);
            head.iter().zip(&cycle[r..]).all(|(a, b)| a == b) && tail.iter().zip(&cycle[..r]).all(|(a, b)| a == b)
        });
        if !fits {
            return Err(broken(g, format!("its corners are not those of the expected {what}")));
        }
        if std::mem::replace(&mut matched[g], true) {
            return Err(broken(g, format!("it would be the {what} of two coarse elements")));
        }
        face_order.push(g as u32);
        rotations.push(r.unwrap_or(0) as u32);
        Ok(())
    };
    // F_E quads: (c, next(t), t, next(c)) for each interior coarse edge.
    for c in 0..coarse.corner_count() {
        let t = coarse.corner_twin[c];
        if t == NONE || (c as u32) > t {
            continue;
        }
        let cycle = [
            vertex_of[c],
            vertex_of[coarse.corner_next[t as usize] as usize],
            vertex_of[t as usize],
            vertex_of[coarse.corner_next[c] as usize],
        ];
        claim(quad_face[c] as usize, &cycle, "F_E quad")?;
    }
    // F_V faces: around each interior coarse vertex.
    let mut cycle = Vec::new();
    for (v, &face) in vertex_face.iter().enumerate() {
        if face == NONE {
            continue;
        }
        vertex_cycle(coarse, v, &mut cycle);
        for x in cycle.iter_mut() {
            *x = vertex_of[*x as usize];
        }
        claim(face as usize, &cycle, "F_V face")?;
    }
    if let Some(g) = matched.iter().position(|&m| !m) {
        return Err(broken(g, "it is neither an F_F face, nor an F_E quad, nor an F_V face of this reading".into()));
    }
    // Compress the identity.
    let identity_vertices = vertex_of.iter().enumerate().all(|(c, &x)| x == c as u32);
    let identity_faces = face_order.iter().enumerate().all(|(k, &g)| g == k as u32);
    let no_rotation = rotations.iter().all(|&r| r == 0);
    Ok(FineOrder {
        vertices: if identity_vertices { Vec::new() } else { vertex_of.to_vec() },
        faces: if identity_faces { Vec::new() } else { face_order },
        rotations: if no_rotation { Vec::new() } else { rotations },
    })
}

/// Rebuilds one level: candidates from coarse positions and details, forward rule per
/// coarse face, canonical connectivity, then the fine order. Returns the fine mesh (with
/// adjacency if `with_adjacency`) and its positions.
pub(crate) fn reconstruct_level(
    coarse: &CornerMesh,
    coarse_positions: &[DVec3],
    details: &[DVec3],
    order: &FineOrder,
    rule: FaceRule,
    with_adjacency: bool,
) -> Result<(CornerMesh, Vec<DVec3>), DooError> {
    let (candidates, _) = level_candidates(&corners_by_vertex(coarse), coarse_positions, details);
    level_from_candidates(coarse, candidates, order, rule, with_adjacency)
}

/// What one level adds to its coarse mesh: details, numbering and rules.
pub(crate) struct Level<'a> {
    pub details: &'a [DVec3],
    pub order: &'a FineOrder,
    pub rule: FaceRule,
    pub boundary: BoundaryRule,
}

/// [`reconstruct_level`] under either boundary rule. Under [`BoundaryRule::Chaikin`] the
/// details of the coarse vertices come first (`corners - vertices` of them), then two
/// per coarse boundary edge; the canonical mesh is the Shrink step plus the boundary ring
/// ([`crate::boundary`]).
pub(crate) fn reconstruct_level_with(
    coarse: &CornerMesh,
    coarse_positions: &[DVec3],
    level: &Level<'_>,
    with_adjacency: bool,
) -> Result<(CornerMesh, Vec<DVec3>), DooError> {
    if level.boundary == BoundaryRule::Shrink {
        return reconstruct_level(coarse, coarse_positions, level.details, level.order, level.rule, with_adjacency);
    }
    let vertex_details = coarse.corner_count() - coarse.vertex_count;
    if level.details.len() < vertex_details {
        return Err(DooError::InvalidPyramid(format!(
            "{} details for a coarse mesh of {} corners and {} vertices",
            level.details.len(),
            coarse.corner_count(),
            coarse.vertex_count
        )));
    }
    let (vertex_part, chaikin_part) = level.details.split_at(vertex_details);
    let points = || {
        let (mut positions, _) = level_candidates(&corners_by_vertex(coarse), coarse_positions, vertex_part);
        face_points_in_place(&coarse.offsets, &FaceMaps::new(level.rule), &mut positions);
        positions
    };
    let (topology, mut positions) = side_by_side(coarse.face_count(), || doo_topology(coarse, false), points);
    let topology = topology?;
    let (mut offsets, mut indices) = (topology.offsets, topology.indices);
    crate::boundary::append_ring_level(
        coarse,
        coarse_positions,
        chaikin_part,
        &mut offsets,
        &mut indices,
        &mut positions,
    )?;
    let vertex_count = positions.len();
    let canonical = if with_adjacency {
        CornerMesh::from_faces(offsets, indices, vertex_count).map_err(|reason| {
            DooError::InvalidPyramid(format!("a Chaikin boundary level is not a manifold mesh: {reason}"))
        })?
    } else {
        CornerMesh {
            corner_next: next_of_corners(&offsets),
            offsets,
            corner_vertex: indices,
            vertex_count,
            ..CornerMesh::default()
        }
    };
    if level.order.is_identity() {
        return Ok((canonical, positions));
    }
    Ok(apply_order(canonical, positions, level.order, with_adjacency))
}

/// The candidates of one level (per coarse corner): each coarse vertex plus the offsets
/// `d_1 = e_1`, `d_j = e_j - e_{j-1}`, `d_r = -e_{r-1}` decoded from its details, vertex
/// by vertex. Also tells whether every candidate is finite (so that the caller checks
/// the inputs only when one is not).
pub(crate) fn level_candidates(
    by_vertex: &CornersByVertex,
    coarse_positions: &[DVec3],
    details: &[DVec3],
) -> (Vec<DVec3>, bool) {
    let mut candidates = vec![DVec3::ZERO; by_vertex.corners.len()];
    // `0 x` is zero for a finite `x` and NaN otherwise: one NaN makes the sum NaN.
    let mut probe = DVec3::ZERO;
    for (v, corners) in by_vertex.iter().enumerate() {
        let base = details_offset(by_vertex, v);
        let p = coarse_positions[v];
        let (last, rest) = corners.split_last().expect("internal: a coarse vertex has a corner");
        let mut previous = DVec3::ZERO;
        for (&c, &e) in rest.iter().zip(&details[base..base + rest.len()]) {
            let candidate = p + (e - previous);
            probe += candidate * 0.0;
            candidates[c as usize] = candidate;
            previous = e;
        }
        let candidate = p + (DVec3::ZERO - previous);
        probe += candidate * 0.0;
        candidates[*last as usize] = candidate;
    }
    (candidates, probe == DVec3::ZERO)
}

/// The forward rule on each coarse face's own candidates (in place: fine vertex `c` is
/// coarse corner `c`), the canonical Doo-Sabin connectivity, then the fine order (see
/// [`reconstruct_level`]).
pub(crate) fn level_from_candidates(
    coarse: &CornerMesh,
    mut candidates: Vec<DVec3>,
    order: &FineOrder,
    rule: FaceRule,
    with_adjacency: bool,
) -> Result<(CornerMesh, Vec<DVec3>), DooError> {
    let maps = FaceMaps::new(rule);
    let points = || {
        face_points_in_place(&coarse.offsets, &maps, &mut candidates);
        candidates
    };
    let (topology, canonical_positions) =
        side_by_side(coarse.face_count(), || doo_topology(coarse, with_adjacency), points);
    let topology = topology?;
    let vertex_count = canonical_positions.len();
    let canonical = if with_adjacency {
        topology.into_corner_mesh(vertex_count)
    } else {
        CornerMesh { offsets: topology.offsets, corner_vertex: topology.indices, vertex_count, ..CornerMesh::default() }
    };
    if order.is_identity() {
        return Ok((canonical, canonical_positions));
    }
    Ok(apply_order(canonical, canonical_positions, order, with_adjacency))
}

/// Renumbers a canonical fine mesh into the input order.
fn apply_order(
    canonical: CornerMesh,
    canonical_positions: Vec<DVec3>,
    order: &FineOrder,
    with_adjacency: bool,
) -> (CornerMesh, Vec<DVec3>) {
    let vertices = canonical_positions.len();
    let faces = canonical.face_count();
    let vertex = |c: u32| if order.vertices.is_empty() { c } else { order.vertices[c as usize] };
    let mut positions = vec![DVec3::ZERO; vertices];
    for (c, &p) in canonical_positions.iter().enumerate() {
        positions[vertex(c as u32) as usize] = p;
    }
    // Canonical face of each input face.
    let mut canonical_of = vec![0u32; faces];
    for k in 0..faces {
        let g = if order.faces.is_empty() { k as u32 } else { order.faces[k] };
        canonical_of[g as usize] = k as u32;
    }
    let mut offsets = Vec::with_capacity(faces + 1);
    offsets.push(0u32);
    let mut corner_vertex = Vec::with_capacity(canonical.corner_count());
    // Input corner of each canonical corner (for the twins).
    let mut corner_map = if with_adjacency { vec![0u32; canonical.corner_count()] } else { Vec::new() };
    for &k in &canonical_of {
        let (b, e) = (canonical.offsets[k as usize] as usize, canonical.offsets[k as usize + 1] as usize);
        let m = e - b;
        let r = if order.rotations.is_empty() { 0 } else { order.rotations[k as usize] as usize };
        for i in 0..m {
            let canonical_corner = b + (i + r) % m;
            if with_adjacency {
                corner_map[canonical_corner] = corner_vertex.len() as u32;
            }
            corner_vertex.push(vertex(canonical.corner_vertex[canonical_corner]));
        }
        offsets.push(corner_vertex.len() as u32);
    }
    let mut mesh = CornerMesh {
        corner_next: next_of_corners(&offsets),
        offsets,
        corner_vertex,
        vertex_count: vertices,
        ..CornerMesh::default()
    };
    if with_adjacency {
        let mut twins = vec![NONE; mesh.corner_vertex.len()];
        for (k, &t) in canonical.corner_twin.iter().enumerate() {
            if t != NONE {
                twins[corner_map[k] as usize] = corner_map[t as usize];
            }
        }
        mesh.corner_twin = twins;
        let mut vertex_corner = vec![NONE; vertices];
        for (c, &v) in mesh.corner_vertex.iter().enumerate() {
            if vertex_corner[v as usize] == NONE {
                vertex_corner[v as usize] = c as u32;
            }
        }
        mesh.vertex_corner = Some(vertex_corner);
    }
    (mesh, positions)
}

/// Sorts a short list (a coarse vertex's corners: its valence) in place.
pub(crate) fn insertion_sort(values: &mut [u32]) {
    insertion_sort_by_key(values, |x| x);
}

/// Sorts a short list in place by `key` (stable).
pub(crate) fn insertion_sort_by_key(values: &mut [u32], key: impl Fn(u32) -> u32) {
    for i in 1..values.len() {
        let x = values[i];
        let k = key(x);
        let mut j = i;
        while j > 0 && key(values[j - 1]) > k {
            values[j] = values[j - 1];
            j -= 1;
        }
        values[j] = x;
    }
}

/// The detail energy of one group of the dual reading: the squared distances of its
/// candidates (`dual`, by coarse corner, from corner `base` on) from their mean, the group
/// being the coarse corners `corners` summed in the order of their coarse vertices
/// (`corner_vertex`), as the dual reading's result would sum them. `group` is scratch.
pub(crate) fn dual_group_energy(
    group: &mut Vec<u32>,
    corners: std::ops::Range<u32>,
    corner_vertex: &[u32],
    dual: &[DVec3],
    base: u32,
) -> f64 {
    group.clear();
    group.extend(corners);
    insertion_sort_by_key(group, |c| corner_vertex[c as usize]);
    let value = |c: u32| dual[(c - base) as usize];
    let mean = group.iter().map(|&c| value(c)).sum::<DVec3>() / group.len() as f64;
    let mut energy = 0.0;
    for &c in group.iter() {
        energy += (value(c) - mean).length_squared();
    }
    energy
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{DooOptions, FaceKind, subdivide_soup};
    use mesh_topo::shapes::{self, CellKind};

    /// The refinement of a cube and a torus side by side (two components), one vertex moved.
    fn two_components() -> HalfedgeMesh {
        let mut soup = shapes::cube();
        let torus = shapes::torus(4, 3, CellKind::Mixed).unwrap();
        let base = soup.vertex_count() as u32;
        soup.positions.extend(torus.positions.iter().map(|&p| p + DVec3::splat(5.0)));
        for face in torus.faces() {
            soup.push_face(&face.iter().map(|&v| v + base).collect::<Vec<u32>>());
        }
        let mut fine = subdivide_soup(&soup, &DooOptions::default()).unwrap().to_mesh().unwrap();
        fine.positions_mut()[30].x += 0.05;
        fine
    }

    fn max_distance(a: &[DVec3], b: &[DVec3]) -> f64 {
        a.iter().zip(b).map(|(p, q)| (*p - *q).length()).fold(0.0, f64::max)
    }

    /// Closed refinements (jittered, so that no reading is exact), renumbered and with
    /// rotated faces, and with shuffled faces.
    fn closed_scrambled() -> Vec<HalfedgeMesh> {
        let shapes = [
            shapes::cube(),
            shapes::icosahedron(),
            shapes::torus(6, 5, CellKind::Mixed).unwrap(),
            shapes::torus(5, 4, CellKind::Quads).unwrap(),
        ];
        let mut meshes = Vec::new();
        for (i, coarse) in shapes.iter().enumerate() {
            let mut fine = subdivide_soup(coarse, &DooOptions::default()).unwrap().into_soup();
            for (k, p) in fine.positions.iter_mut().enumerate() {
                *p += 0.01 * DVec3::new((k % 7) as f64, (k % 3) as f64, (k % 5) as f64);
            }
            let scrambled = mesh_topo::testing::scramble(fine.clone(), 3 + i as u64, 0.0);
            let mut faces: Vec<Vec<u32>> = scrambled.faces().map(<[u32]>::to_vec).collect();
            faces.reverse();
            let shuffled = PolygonSoup::from_faces(scrambled.positions.clone(), faces);
            for soup in [scrambled, shuffled] {
                meshes.push(HalfedgeMesh::from_soup(&soup).unwrap());
            }
        }
        meshes
    }

    #[test]
    fn the_closed_build_is_the_full_build() {
        let mut checked = 0;
        for mesh in closed_scrambled() {
            let corners = CornerMesh::from_halfedge(&mesh);
            let rule = FaceRule::DooSabin;
            let seeded = ReverseOptions::with_seed(rule, 0);
            let session = match Session::new(&corners, mesh.positions(), &seeded) {
                Ok(session) if session.preclassified => session,
                // Face 0 is not an F_F face of a reading of the whole mesh.
                _ => continue,
            };
            let known = session.best_candidates[0].corner_of_vertex.clone();
            let fast = session.search.finish_closed(rule, &mut Vec::new(), false, &known).expect("a closed reading");
            let (full, energies) = session.search.finish(rule, &[], 1, (Vec::new(), false), known).unwrap();
            assert_eq!(fast.reversal, full);
            assert_eq!(fast.energies, energies);
            assert!(max_distance(&full.reconstruct().positions, mesh.positions()) < 1e-12);
            checked += 1;
        }
        assert!(checked >= 4, "{checked}");
    }

    #[test]
    fn the_dual_reading_summed_from_the_build_is_the_searched_one() {
        let mut checked = 0;
        for mesh in closed_scrambled() {
            let corners = CornerMesh::from_halfedge(&mesh);
            let reversal = reverse(&mesh, &ReverseOptions::default()).unwrap();
            let trials = &reversal.choices()[0].trials;
            let Some(dual) = trials.iter().find(|t| t.class == "F_V") else { continue };
            if !dual.stopped_early {
                continue;
            }
            // The same reading searched and summed with the same cutoff.
            let cutoff = *trials[0].outcome.as_ref().unwrap();
            let mut search = Search::new(&corners, mesh.positions(), FaceMaps::new(FaceRule::DooSabin));
            search.classify(dual.seed_face).unwrap();
            let faces = FaceSet::All(mesh.face_count() as u32);
            let energy = search.energy(0, faces, mesh.vertex_count(), cutoff, false).unwrap();
            assert!(energy.stopped_early);
            assert_eq!(energy.energy.to_bits(), dual.outcome.as_ref().unwrap().to_bits());
            // The counters count the search it stands for: each trial searched afresh.
            let (mut visited, mut crossed) = (0, 0);
            for trial in trials {
                let mut search = Search::new(&corners, mesh.positions(), FaceMaps::new(FaceRule::DooSabin));
                let _ = search.classify(trial.seed_face);
                visited += search.stats.visited_faces;
                crossed += search.stats.edges_crossed;
            }
            assert_eq!((reversal.stats().visited_faces, reversal.stats().edges_crossed), (visited, crossed));
            checked += 1;
        }
        assert!(checked > 0);
    }

    #[test]
    fn fuzz_regression_an_open_mesh_whose_lowest_face_is_an_f_v_face() {
        // Found by the `reverse_doo` fuzz target: an open mixed grid after one step, with
        // an F_V face first. It is no F_F face of a valid reading (its dual reading meets
        // the boundary), nor were its F_E neighbours, and the automatic mode gave up
        // there; the F_F faces two faces away were never tried.
        let mut tried = 0;
        for (coarse, rule) in [
            (shapes::grid(4, 2, CellKind::Mixed).unwrap(), FaceRule::Simple),
            (shapes::grid(3, 3, CellKind::Triangles).unwrap(), FaceRule::DooSabin),
            (shapes::grid(3, 2, CellKind::Quads).unwrap(), FaceRule::CENTROID_HALF),
        ] {
            let fine = subdivide_soup(&coarse, &DooOptions::new(rule, 1)).unwrap();
            let soup = fine.to_soup();
            for fv in (0..fine.face_count()).filter(|&f| fine.face_kind(f) == FaceKind::Vertex) {
                let mut faces: Vec<Vec<u32>> = soup.faces().map(<[u32]>::to_vec).collect();
                faces.swap(0, fv);
                let moved = PolygonSoup::from_faces(soup.positions.clone(), faces);
                let mesh = HalfedgeMesh::from_soup(&moved).unwrap();
                let reversal = reverse(&mesh, &ReverseOptions::auto(rule)).unwrap();
                assert_eq!(reversal.coarse().face_count(), coarse.face_count());
                assert!(reversal.details().iter().all(|d| d.length() < 1e-12));
                let rebuilt = reversal.reconstruct();
                assert_eq!((&rebuilt.offsets, &rebuilt.indices), (&moved.offsets, &moved.indices));
                assert!(max_distance(&rebuilt.positions, &moved.positions) < 1e-12);
                tried += 1;
            }
        }
        assert!(tried >= 4, "{tried} meshes with an F_V face first");
    }

    #[test]
    fn property_regression_both_classes_of_f_e_quads_are_tried_on_an_all_quad_mesh() {
        // Found by the property `reverse_in_any_order`: a quad torus after one step is a
        // quad grid whose faces fall into four classes (F_F, F_V and the F_E quads of the
        // two directions), each a valid reading. In an order whose lowest face is an F_E
        // quad, the automatic mode tried it, the lowest F_V face of its reading and the
        // lowest of its F_E quads, which may be a true F_V face: the true reading (zero
        // details) was never tried. Forty orders; without the fourth reading the fifth
        // fails.
        let coarse = shapes::torus(6, 5, CellKind::Quads).unwrap();
        let fine = subdivide_soup(&coarse, &DooOptions::default()).unwrap().into_soup();
        let mut found_in_fourth = 0;
        for seed in 1..=40u64 {
            let mut state = seed;
            let shuffled = mesh_topo::testing::shuffle(&fine, |k| {
                state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                ((state >> 33) % (k as u64 + 1)) as usize
            });
            let mesh = HalfedgeMesh::from_soup(&shuffled).unwrap();
            let reversal = reverse(&mesh, &ReverseOptions::auto(FaceRule::DooSabin)).unwrap();
            assert!(reversal.details().iter().all(|d| d.length() < 1e-12), "order {seed}");
            let trials = &reversal.choices()[0].trials;
            found_in_fourth += usize::from(trials.len() == 4 && trials[3].seed_face == reversal.choices()[0].seed_face);
        }
        // Some orders need the fourth reading.
        assert!(found_in_fourth > 0);
    }

    #[test]
    fn an_empty_mesh_is_an_error() {
        let empty = HalfedgeMesh::from_soup(&PolygonSoup::default()).unwrap();
        assert!(matches!(reverse(&empty, &ReverseOptions::default()), Err(DooError::EmptyMesh)));
        let options = crate::DecomposeOptions::levels(FaceRule::DooSabin, 1);
        assert!(matches!(crate::decompose(&empty, &options), Err(DooError::EmptyMesh)));
    }

    #[test]
    fn one_seed_per_component_on_a_multi_component_mesh() {
        let fine = two_components();
        let auto = reverse(&fine, &ReverseOptions::default()).unwrap();
        // The F_F faces come first: face 6 is the torus's first F_F face.
        let torus_face = 6;
        for seeds in [vec![0], vec![torus_face], vec![0, torus_face], vec![torus_face, 0]] {
            let options = ReverseOptions { rule: FaceRule::DooSabin, seeds: seeds.clone(), ..Default::default() };
            let seeded = reverse(&fine, &options).unwrap();
            assert_eq!(seeded.choices().len(), 2);
            assert_eq!(seeded.choices()[0].given, seeds.contains(&0), "{seeds:?}");
            assert_eq!(seeded.choices()[1].given, seeds.contains(&torus_face), "{seeds:?}");
            assert_eq!(seeded.coarse(), auto.coarse(), "{seeds:?}");
            assert_eq!(seeded.details(), auto.details(), "{seeds:?}");
            assert!(max_distance(&seeded.reconstruct().positions, fine.positions()) < 1e-13);
        }
        // Two seeds in one component.
        let options = ReverseOptions { rule: FaceRule::DooSabin, seeds: vec![1, torus_face, 0], ..Default::default() };
        assert!(matches!(reverse(&fine, &options), Err(DooError::DuplicateSeed { first: 1, second: 0 })));
    }

    #[test]
    fn one_component_readings_are_searched_once_each() {
        // An exact refinement: the first reading has zero details, nothing else is tried,
        // and building it does not search again.
        let torus = shapes::torus(6, 5, CellKind::Mixed).unwrap();
        let fine = subdivide_soup(&torus, &DooOptions::default()).unwrap().to_mesh().unwrap();
        let stats = reverse(&fine, &ReverseOptions::default()).unwrap().stats();
        assert_eq!((stats.visited_faces, stats.interpretations), (torus.face_count(), 1));
        let seeded = reverse(&fine, &ReverseOptions::with_seed(FaceRule::DooSabin, 3)).unwrap().stats();
        assert_eq!(seeded.visited_faces, torus.face_count());
    }

    #[test]
    fn a_given_seed_that_does_not_cover_the_mesh_still_names_the_break() {
        // A one-component mesh whose given seed is an F_E quad: the quick one-component
        // test fails and the search's own error is reported.
        let fine = subdivide_soup(&shapes::cube(), &DooOptions::default()).unwrap().to_mesh().unwrap();
        let error = reverse(&fine, &ReverseOptions::with_seed(FaceRule::DooSabin, 6)).unwrap_err();
        assert!(matches!(error, DooError::NotDooConnectivity { .. }), "{error}");
        // A one-component mesh whose lowest face is not an F_F face: the automatic mode
        // still finds the reading (here the F_V triangles of the cube are not F_F faces).
        let soup = subdivide_soup(&shapes::cube(), &DooOptions::default()).unwrap().into_soup();
        let mut faces: Vec<Vec<u32>> = soup.faces().map(<[u32]>::to_vec).collect();
        faces.rotate_right(8);
        let shuffled = HalfedgeMesh::from_soup(&PolygonSoup::from_faces(soup.positions.clone(), faces)).unwrap();
        let reversal = reverse(&shuffled, &ReverseOptions::default()).unwrap();
        assert_eq!(reversal.coarse().face_count(), 6);
        assert!(max_distance(&reversal.reconstruct().positions, shuffled.positions()) < 1e-14);
    }
}
