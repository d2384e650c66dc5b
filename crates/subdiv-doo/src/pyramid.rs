//! Multiresolution pyramids: several reverse Doo-Sabin steps, reconstruction to any
//! level, compression by keeping only the largest details, and `.mres` files.
//!
//! A [`DooPyramid`] holds the coarsest (*base*) mesh and, for each finer level, the
//! detail vectors of [`crate::reverse`](mod@crate::reverse) and the numbering of that level relative to the
//! Doo-Sabin connectivity of the level below ([`FineOrder`], empty when it is the
//! canonical one). That is all reconstruction needs: connectivity is Doo-Sabin
//! connectivity, and positions come from coarse vertices plus details. The base mesh
//! plus all details are exactly as many 3-vectors as the finest mesh has vertices.
//!
//! # Speed
//! A mesh refined several times by [`crate::subdivide`] (or rebuilt from a pyramid) is
//! in the canonical order at every level: the coarse mesh of a canonical reversal is the
//! mesh it was refined from, in its own order. Each level is then reversed by the
//! streaming path of the canonical module, from half-edge arrays built from the previous
//! level's corner arrays in one linear pass, and the general search runs only where
//! that path does not apply (another order, an F_E quad read as F_F that the general
//! search would have to follow further, as on quad meshes, or a level whose best
//! reading cannot go on): the result is the general path's, bit for bit, at every level.
//!
//! # Compression (`keep`)
//! [`DooPyramid::reconstruct`] can keep only a fraction of the detail vectors, the
//! others being set to zero. Details are ranked by their Euclidean norm (the stored
//! prefix-sum vectors `e_j`) times `2^(L - k)` for level `k` of `L` (level `L` the finest):
//! a detail at a coarser level moves a region of the finest mesh about four times larger
//! per level with about the same amplitude, so this weight ranks details by their share
//! of the squared (RMS) error they would cause. Ties keep the earlier level, then the
//! earlier vector. [`DooPyramid::rate_distortion`] measures the result.
//!
//! # File format
//! `.mres` files go through `mesh_topo::binary` (magic [`PYRAMID_MAGIC`], version
//! [`PYRAMID_VERSION`], bincode payload of [`DooPyramid`]). Decoding checks every array
//! length and permutation before use: a corrupted file is an error, never a panic.

use glam::DVec3;
use mesh_topo::{HalfedgeMesh, PolygonSoup, binary};
use serde::{Deserialize, Serialize};

use crate::DooError;
use crate::boundary::{BoundaryRule, Ring, reverse_chaikin_arrays, reverse_chaikin_corner_mesh};
use crate::canonical::CornerHalfedges;
use crate::corner::{CornerMesh, NONE, doo_topology};
use crate::forward::check_finite;
use crate::reverse::{
    CornersByVertex, FineOrder, Level, ReverseOptions, SeedChoice, Session, corners_by_vertex, level_candidates,
    level_from_candidates, reconstruct_level_with,
};
use crate::rule::FaceRule;
use crate::scale::UnitScale;

/// Magic number of a Doo-Sabin `.mres` pyramid.
pub const PYRAMID_MAGIC: [u8; 8] = *b"MRSDOO\0\0";
/// Current version of the Doo-Sabin pyramid format. Version 2 added the boundary rule
/// ([`DooPyramid::boundary`]); version 1 files (always [`BoundaryRule::Shrink`]) are
/// still read.
pub const PYRAMID_VERSION: u32 = 2;

/// True if `bytes` starts like a Doo-Sabin pyramid file.
///
/// Only the first 8 bytes, the magic number [`PYRAMID_MAGIC`], are looked at; decoding
/// ([`DooPyramid::from_bytes`]) checks the rest.
///
/// ```
/// use subdiv_doo::pyramid::{PYRAMID_MAGIC, is_doo_pyramid};
/// assert!(is_doo_pyramid(&[PYRAMID_MAGIC.as_slice(), b"any payload"].concat()));
/// assert!(!is_doo_pyramid(b"ply\nformat ascii 1.0\n"));
/// assert!(!is_doo_pyramid(&PYRAMID_MAGIC[..7])); // too short
/// ```
pub fn is_doo_pyramid(bytes: &[u8]) -> bool {
    bytes.len() >= 8 && bytes[..8] == PYRAMID_MAGIC
}

/// How many levels to decompose.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Depth {
    /// Exactly this many levels (an error if the mesh does not allow them).
    Levels(u32),
    /// As many levels as the connectivity allows (at least one), stopping after a level
    /// that does not coarsen the mesh: a mesh of faces that share no edge (a lone quad,
    /// say) is its own Doo-Sabin refinement, every face an F_F face, and reversing it
    /// again and again would only expand the same faces about their centroids, scaling
    /// round-off by the expansion factor at each level until the pyramid no longer
    /// rebuilds the mesh exactly.
    Max,
}

/// Options of [`decompose`].
#[derive(Debug, Clone, PartialEq)]
pub struct DecomposeOptions {
    /// The per-face rule the mesh is assumed to come from.
    pub rule: FaceRule,
    /// How many levels.
    pub depth: Depth,
    /// Seed faces for the first (finest) reversal; coarser levels use the automatic
    /// choice (their F_F faces are found automatically).
    pub seeds: Vec<usize>,
    /// The boundary rule the mesh is assumed to come from.
    pub boundary: BoundaryRule,
}

impl DecomposeOptions {
    /// `levels` levels with automatic seeds.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_doo::pyramid::{DecomposeOptions, Depth, decompose};
    /// use subdiv_doo::{BoundaryRule, DooOptions, FaceRule, subdivide};
    ///
    /// let options = DecomposeOptions::levels(FaceRule::DooSabin, 2);
    /// assert_eq!((options.depth, options.boundary), (Depth::Levels(2), BoundaryRule::Shrink));
    /// // Two of three levels: the base is the cube refined once (6 + 12 + 8 faces).
    /// let cube = HalfedgeMesh::from_soup(&shapes::cube())?;
    /// let fine = subdivide(&cube, &DooOptions::new(FaceRule::DooSabin, 3))?.to_mesh()?;
    /// let pyramid = decompose(&fine, &options)?.pyramid;
    /// assert_eq!((pyramid.level_count(), pyramid.base.face_count()), (2, 26));
    /// // More levels than the mesh has are an error.
    /// assert!(decompose(&fine, &DecomposeOptions::levels(FaceRule::DooSabin, 4)).is_err());
    /// # Ok::<(), subdiv_doo::DooError>(())
    /// ```
    pub fn levels(rule: FaceRule, levels: u32) -> Self {
        Self { rule, depth: Depth::Levels(levels), seeds: Vec::new(), boundary: BoundaryRule::Shrink }
    }

    /// As many levels as possible, automatic seeds.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_doo::pyramid::{DecomposeOptions, Depth, decompose};
    /// use subdiv_doo::{DooOptions, FaceRule, subdivide};
    ///
    /// let options = DecomposeOptions::max(FaceRule::DooSabin);
    /// assert_eq!(options.depth, Depth::Max);
    /// let cube = HalfedgeMesh::from_soup(&shapes::cube())?;
    /// let fine = subdivide(&cube, &DooOptions::new(FaceRule::DooSabin, 2))?.to_mesh()?;
    /// let decomposition = decompose(&fine, &options)?;
    /// // Down to the cube, which is not a Doo-Sabin refinement: the reason is reported.
    /// assert_eq!(decomposition.pyramid.level_count(), 2);
    /// assert_eq!(decomposition.pyramid.base.face_count(), 6);
    /// assert!(decomposition.stopped.is_some());
    /// # Ok::<(), subdiv_doo::DooError>(())
    /// ```
    pub fn max(rule: FaceRule) -> Self {
        Self { rule, depth: Depth::Max, seeds: Vec::new(), boundary: BoundaryRule::Shrink }
    }

    /// The same options for a mesh made with the boundary rule `boundary`.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes::{self, CellKind}};
    /// use subdiv_doo::pyramid::{DecomposeOptions, decompose};
    /// use subdiv_doo::{BoundaryRule, DooOptions, FaceRule, subdivide};
    ///
    /// let grid = HalfedgeMesh::from_soup(&shapes::grid(2, 2, CellKind::Quads)?)?;
    /// let refine = DooOptions::new(FaceRule::DooSabin, 2).with_boundary(BoundaryRule::Chaikin);
    /// let fine = subdivide(&grid, &refine)?.to_mesh()?;
    /// let shrink = DecomposeOptions::levels(FaceRule::DooSabin, 2);
    /// let chaikin = shrink.clone().with_boundary(BoundaryRule::Chaikin);
    /// let pyramid = decompose(&fine, &chaikin)?.pyramid;
    /// assert_eq!((pyramid.boundary, pyramid.base.face_count()), (BoundaryRule::Chaikin, 4));
    /// assert_eq!(pyramid.base.vertex_count() + pyramid.detail_count(), fine.vertex_count());
    /// // Read with the shrinking rule, the mesh has no two levels.
    /// assert!(decompose(&fine, &shrink).is_err());
    /// # Ok::<(), subdiv_doo::DooError>(())
    /// ```
    pub fn with_boundary(self, boundary: BoundaryRule) -> Self {
        Self { boundary, ..self }
    }
}

/// Details and numbering of one level of a pyramid.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct PyramidLevel {
    /// Detail vectors (see [`crate::reverse`](mod@crate::reverse)).
    pub details: Vec<DVec3>,
    /// Numbering of this level relative to the canonical Doo-Sabin order.
    pub order: FineOrder,
}

/// A multiresolution pyramid: the base mesh and the details of each finer level.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DooPyramid {
    /// The per-face rule.
    pub rule: FaceRule,
    /// The coarsest mesh.
    pub base: PolygonSoup,
    /// Levels from coarse to fine: `levels[0]` rebuilds level 1 from the base.
    pub levels: Vec<PyramidLevel>,
    /// The boundary rule of every level (under [`BoundaryRule::Chaikin`] each level's
    /// details end with two per boundary edge of the mesh it refines).
    pub boundary: BoundaryRule,
}

/// The layout of version 1 files (no boundary rule: [`BoundaryRule::Shrink`]).
#[derive(Deserialize)]
struct DooPyramidV1 {
    rule: FaceRule,
    base: PolygonSoup,
    levels: Vec<PyramidLevel>,
}

/// A pyramid and the reports of the reversals that made it.
#[derive(Debug, Clone, PartialEq)]
pub struct Decomposition {
    /// The pyramid.
    pub pyramid: DooPyramid,
    /// For each level, finest first, the seed choices of its reversal.
    pub choices: Vec<Vec<SeedChoice>>,
    /// Why the decomposition stopped (for [`Depth::Max`]).
    pub stopped: Option<String>,
}

/// One row of a rate-distortion table.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RateDistortion {
    /// Fraction of detail vectors kept.
    pub fraction: f64,
    /// Number of detail vectors kept.
    pub kept: usize,
    /// Largest vertex distance to the exact finest mesh, divided by its bounding-box diagonal.
    pub max_error: f64,
    /// Root-mean-square vertex distance, divided by the same diagonal.
    pub rms_error: f64,
}

/// Levels decomposed by [`Depth::Max`] at most, and by [`Depth::Levels`]: those that
/// [`subdivide`](crate::subdivide) refines.
pub use crate::forward::MAX_LEVELS;

/// Decomposes a mesh into a base mesh and per-level details by repeated reverse
/// Doo-Sabin.
///
/// ```
/// use subdiv_doo::pyramid::{DecomposeOptions, decompose};
/// use subdiv_doo::{DooOptions, FaceRule, subdivide};
/// use mesh_topo::{HalfedgeMesh, shapes};
///
/// let cube = HalfedgeMesh::from_soup(&shapes::cube())?;
/// let mut fine = subdivide(&cube, &DooOptions::new(FaceRule::DooSabin, 3))?.to_mesh()?;
/// fine.positions_mut()[100].z += 0.1;
/// let pyramid = decompose(&fine, &DecomposeOptions::max(FaceRule::DooSabin))?.pyramid;
/// assert_eq!(pyramid.levels.len(), 3);
/// assert_eq!(pyramid.base.face_count(), 6);
/// let rebuilt = pyramid.reconstruct(3, None)?;
/// let error = rebuilt.positions.iter().zip(fine.positions()).map(|(a, b)| (*a - *b).length()).fold(0.0, f64::max);
/// assert!(error < 1e-14);
/// # Ok::<(), subdiv_doo::DooError>(())
/// ```
///
/// # Performance
/// Linear in the size of the mesh. A mesh in the order [`subdivide`](crate::subdivide)
/// writes (or a reconstruction) is read by a fast path that takes the structure from
/// the numbering; a mesh in any other order is searched. A level keeps its scratch and
/// its result alive at once: about 60 bytes per fine vertex at its peak, measured on a
/// triangulated torus. In a program that decomposes large meshes again and again, each
/// call gives that memory back to the allocator, and glibc returns the top of its heap
/// to the system once more than its trim threshold is free there: the next call then
/// takes a page fault for every page again, which cost up to two thirds of a one-level
/// reversal's own time in our measurements, depending on what the process allocated
/// before. With glibc, setting both `MALLOC_MMAP_THRESHOLD_` and
/// `MALLOC_TRIM_THRESHOLD_` high keeps that memory mapped (the trim threshold alone also
/// turns off the adaptive mmap threshold, and then every large array is mapped afresh:
/// slower still).
///
/// # Errors
/// The errors of [`crate::reverse`](mod@crate::reverse) for the first level; for [`Depth::Levels`], also
/// for any further level (the error says which level failed; with [`Depth::Max`] a
/// further level that cannot be reversed, an overflow included, ends the pyramid and
/// says why), and [`DooError::InvalidParameter`] for no level or more than
/// [`MAX_LEVELS`]. Coordinates so large that a reversal overflows are
/// [`DooError::ReversalOverflow`].
pub fn decompose(mesh: &HalfedgeMesh, options: &DecomposeOptions) -> Result<Decomposition, DooError> {
    // Coordinates far from 1: decomposed at unit scale (see `crate::scale`). Its errors
    // and overflows are left to the mesh as given, which reports them as before, from
    // the first level made as given. The canonical path measures the scale as it reads
    // the positions, which then need no pass of their own for it (a pass as long as a
    // twentieth of the reversal).
    let first = first_level(mesh, options);
    let measured = first.as_ref().ok().and_then(Option::as_ref).and_then(|reversal| reversal.fine_unit_scale);
    if let Some(scale) = UnitScale::of_measured(measured, mesh.positions()) {
        let mut scaled = mesh.clone();
        scale.scale_down(scaled.positions_mut());
        if let Some(decomposition) = decompose_as_given(&scaled, options).ok().and_then(|d| scaled_up(d, scale)) {
            return Ok(decomposition);
        }
    }
    decompose_after(mesh, options, first?)
}

/// A decomposition made at unit scale brought back to the input's scale, if it fits.
fn scaled_up(mut decomposition: Decomposition, scale: UnitScale) -> Option<Decomposition> {
    let pyramid = &mut decomposition.pyramid;
    let mut finite = scale.scale_up(&mut pyramid.base.positions);
    for level in &mut pyramid.levels {
        finite = finite && scale.scale_up(&mut level.details);
    }
    decomposition.choices.iter_mut().for_each(|choices| scale.scale_up_choices(choices));
    finite.then_some(decomposition)
}

/// [`decompose`] without the change of scale.
fn decompose_as_given(mesh: &HalfedgeMesh, options: &DecomposeOptions) -> Result<Decomposition, DooError> {
    decompose_after(mesh, options, first_level(mesh, options)?)
}

/// The checks of the level count, then the first level by the canonical path where it
/// applies (`None` where it does not, also when a position is not finite, so that
/// [`decompose_after`] names it).
fn first_level(mesh: &HalfedgeMesh, options: &DecomposeOptions) -> Result<Option<crate::DooReversal>, DooError> {
    if options.depth == Depth::Levels(0) {
        check_finite(mesh.positions())?;
        return Err(DooError::InvalidParameter { name: "levels", value: 0.0, reason: "decompose at least one level" });
    }
    // A mesh whose faces share no edge reverses to itself, level after level: without
    // the limit, `u32::MAX` levels of it overflowed the stack.
    if let Depth::Levels(levels) = options.depth
        && levels > MAX_LEVELS
    {
        check_finite(mesh.positions())?;
        return Err(DooError::InvalidParameter {
            name: "levels",
            value: levels as f64,
            reason: "decompose at most 32 levels (a mesh that grows exceeds u32 indices after 16)",
        });
    }
    // A mesh in the canonical order: the first level without the general search (the
    // same result), by the reversal's own canonical path. The coarser levels try it in
    // turn.
    if !canonical_enabled() {
        return Ok(None);
    }
    Ok(crate::reverse::reverse_canonical(mesh, &reverse_options(options, 0)))
}

/// [`decompose`] from its first level (`first`: what [`first_level`] made of it).
fn decompose_after(
    mesh: &HalfedgeMesh,
    options: &DecomposeOptions,
    first: Option<crate::DooReversal>,
) -> Result<Decomposition, DooError> {
    if first.is_none() {
        check_finite(mesh.positions())?;
    }
    let decomposition = decompose_from(first.map(Step::from_canonical), Some(mesh), mesh.face_count(), options)?;
    Ok(decomposition.expect("internal: with the mesh at hand every path can run"))
}

/// [`decompose`] of a polygon soup, as a mesh file holds it: the result, or the error,
/// of `decompose(&HalfedgeMesh::from_soup(soup)?, options)`.
///
/// A mesh written by [`crate::subdivide`] (or rebuilt by a pyramid) under the shrinking
/// boundary rule, closed or not, and at least one level: the first level is reversed
/// from half-edge arrays computed from the face list by arithmetic (the numbering
/// `from_soup` would give, with every check that makes `from_soup` accept the soup),
/// without building the half-edge mesh, and the coarser levels as [`decompose`]
/// reverses them. Any other soup, or one whose first level the canonical path does not
/// take to the end, goes through `from_soup` and [`decompose`].
///
/// ```
/// use subdiv_doo::pyramid::{DecomposeOptions, decompose, decompose_soup};
/// use subdiv_doo::{DooOptions, FaceRule, subdivide};
/// use mesh_topo::{HalfedgeMesh, shapes};
///
/// let cube = HalfedgeMesh::from_soup(&shapes::cube())?;
/// let mut fine = subdivide(&cube, &DooOptions::new(FaceRule::DooSabin, 2))?.to_soup();
/// fine.positions[7].x += 0.1;
/// let options = DecomposeOptions::levels(FaceRule::DooSabin, 2);
/// let from_soup = decompose_soup(&fine, &options)?.pyramid;
/// let from_mesh = decompose(&HalfedgeMesh::from_soup(&fine)?, &options)?.pyramid;
/// assert_eq!(from_soup, from_mesh);
/// # Ok::<(), subdiv_doo::DooError>(())
/// ```
///
/// # Errors
/// Those of [`HalfedgeMesh::from_soup`] (as [`DooError::Mesh`]) and of [`decompose`].
pub fn decompose_soup(soup: &PolygonSoup, options: &DecomposeOptions) -> Result<Decomposition, DooError> {
    // As in `decompose` (the canonical path measures the scale on the way).
    let first = first_soup_level(soup, options);
    let measured = first.as_ref().and_then(|reversal| reversal.fine_unit_scale);
    if let Some(scale) = UnitScale::of_measured(measured, &soup.positions) {
        let mut scaled = soup.clone();
        scale.scale_down(&mut scaled.positions);
        if let Some(decomposition) = decompose_soup_as_given(&scaled, options).ok().and_then(|d| scaled_up(d, scale)) {
            return Ok(decomposition);
        }
    }
    decompose_soup_after(soup, options, first)
}

/// [`decompose_soup`] without the change of scale.
fn decompose_soup_as_given(soup: &PolygonSoup, options: &DecomposeOptions) -> Result<Decomposition, DooError> {
    decompose_soup_after(soup, options, first_soup_level(soup, options))
}

/// The first level of a soup in the canonical order, read from its face list (`None`
/// where that path does not apply: the soup then goes through `from_soup`). The fine
/// mesh's arrays are freed once its level is reversed.
fn first_soup_level(soup: &PolygonSoup, options: &DecomposeOptions) -> Option<crate::DooReversal> {
    if matches!(options.depth, Depth::Levels(levels) if levels == 0 || levels > MAX_LEVELS)
        || options.boundary != BoundaryRule::Shrink
        || !canonical_enabled()
    {
        return None;
    }
    CornerHalfedges::of_canonical_soup(soup)?.reverse_canonical(&soup.positions, false, &reverse_options(options, 0))
}

/// [`decompose_soup`] once its first level was tried by the face-list path (`first`).
fn decompose_soup_after(
    soup: &PolygonSoup,
    options: &DecomposeOptions,
    first: Option<crate::DooReversal>,
) -> Result<Decomposition, DooError> {
    if let Some(first) = first
        && let Some(decomposition) =
            decompose_from(Some(Step::from_canonical(first)), None, soup.face_count(), options)?
    {
        return Ok(decomposition);
    }
    decompose_as_given(&HalfedgeMesh::from_soup(soup)?, options)
}

/// The levels of [`decompose`] once its first level has been tried by the canonical path
/// (`first`, `None` if that did not apply). `mesh` is the input mesh, which the general
/// path of the first level needs; without it (`None`, a soup read by the canonical path)
/// the result is `Ok(None)` where that path would have to run. `faces`: the input's face
/// count.
fn decompose_from(
    first: Option<Step>,
    mesh: Option<&HalfedgeMesh>,
    faces: usize,
    options: &DecomposeOptions,
) -> Result<Option<Decomposition>, DooError> {
    let mut steps = Vec::new();
    let mut stopped = None;
    match options.depth {
        Depth::Levels(n) => {
            let rest = match &first {
                Some(step) => descend_below(step, options, 0, n).ok(),
                None => None,
            };
            steps = match (first, rest) {
                (Some(step), Some(rest)) => {
                    let mut steps = vec![step];
                    steps.extend(rest);
                    steps
                }
                // The general search over this level's readings (the first of which is
                // the canonical one, if any, which could not go on).
                (first, _) => {
                    let Some(mesh) = mesh else { return Ok(None) };
                    let fine = CornerMesh::from_halfedge(mesh);
                    descend_from(&fine, mesh.positions(), options, 0, n, false, first.is_none())?
                }
            };
        }
        Depth::Max => {
            // The mesh of the current level is the last step's coarse mesh (none yet: the
            // input, whose corner arrays are built only if the general path needs them);
            // once the canonical path has been tried on it, what it gave.
            let mut tried = Some(first);
            // Faces of the mesh that the last step reversed.
            let mut reversed_faces = faces;
            for level in 0..MAX_LEVELS {
                // No F_E and no F_V face: as many coarse faces as fine ones (see `Depth::Max`).
                if let Some(last) = steps.last()
                    && last.coarse.face_count() == reversed_faces
                {
                    stopped = Some(format!(
                        "level {level} did not coarsen the mesh: it has no F_E or F_V face (no two faces share an \
                         edge), so every further level would only expand the same faces"
                    ));
                    break;
                }
                let canonical = match tried.take() {
                    Some(result) => result,
                    None => steps.last().and_then(|last: &Step| {
                        canonical_step(&last.coarse, &last.coarse_positions, options, level, last.connected)
                    }),
                };
                // Kept as `greedy_step` keeps the best reading: when its coarse mesh can be
                // reversed in turn (shown by the canonical path, whose reversal then serves
                // the next level, or by the general search's check).
                let accepted = canonical.filter(|step| {
                    let next = canonical_step(&step.coarse, &step.coarse_positions, options, level + 1, step.connected);
                    let reversible = options.boundary == BoundaryRule::Chaikin
                        || next.is_some()
                        || Session::new(&step.coarse, &step.coarse_positions, &ReverseOptions::auto(options.rule))
                            .is_ok();
                    tried = Some(next);
                    reversible
                });
                let step = match accepted {
                    Some(step) => step,
                    None => {
                        tried = None;
                        let input;
                        let (fine, positions) = match steps.last() {
                            Some(last) => (&last.coarse, last.coarse_positions.as_slice()),
                            None => {
                                let Some(mesh) = mesh else { return Ok(None) };
                                input = CornerMesh::from_halfedge(mesh);
                                (&input, mesh.positions())
                            }
                        };
                        match greedy_step(fine, positions, options, level) {
                            Ok(step) => step,
                            Err(error) if level > 0 => {
                                stopped = Some(format!("level {} is not a Doo-Sabin refinement: {error}", level + 1));
                                break;
                            }
                            Err(error) => return Err(error),
                        }
                    }
                };
                reversed_faces = steps.last().map_or(faces, |last| last.coarse.face_count());
                steps.push(step);
            }
            if stopped.is_none() {
                stopped = Some(format!("reached the limit of {MAX_LEVELS} levels"));
            }
        }
    }
    // Move, do not copy: the base is the last step's coarse mesh.
    let last = steps.last_mut().expect("internal: at least one level");
    let base = PolygonSoup {
        positions: std::mem::take(&mut last.coarse_positions),
        offsets: std::mem::take(&mut last.coarse.offsets),
        indices: std::mem::take(&mut last.coarse.corner_vertex),
    };
    let mut choices = Vec::with_capacity(steps.len());
    let mut levels = Vec::with_capacity(steps.len());
    for step in steps.into_iter().rev() {
        choices.push(step.choices);
        levels.push(PyramidLevel { details: step.details, order: step.order });
    }
    choices.reverse();
    let pyramid = DooPyramid { rule: options.rule, base, levels, boundary: options.boundary };
    Ok(Some(Decomposition { pyramid, choices, stopped }))
}

/// One reversal of a decomposition.
struct Step {
    coarse: CornerMesh,
    coarse_positions: Vec<DVec3>,
    details: Vec<DVec3>,
    order: FineOrder,
    choices: Vec<SeedChoice>,
    /// The coarse mesh is known to be one connected component (the canonical path
    /// checks it); false when not known.
    connected: bool,
}

impl Step {
    /// A step of the general path (whose coarse mesh may have several components).
    fn from_reversal(reversal: crate::DooReversal) -> Self {
        let (coarse, coarse_positions, details, order, choices) = reversal.into_parts();
        Self { coarse, coarse_positions, details, order, choices, connected: false }
    }

    /// A step of the canonical path. Under the shrinking boundary rule its coarse mesh is
    /// one connected component (the path checks it, or knows it from a connected fine
    /// mesh), so that the next level skips that check; under the Chaikin rule the claim
    /// is not made (it holds for the Shrink rule, whose fine faces all lie on coarse
    /// faces, edges or interior vertices).
    fn from_canonical(reversal: crate::DooReversal) -> Self {
        let connected = reversal.boundary == BoundaryRule::Shrink;
        Self { connected, ..Self::from_reversal(reversal) }
    }
}

fn reverse_options(options: &DecomposeOptions, level: u32) -> ReverseOptions {
    ReverseOptions {
        rule: options.rule,
        seeds: if level == 0 { options.seeds.clone() } else { Vec::new() },
        boundary: options.boundary,
    }
}

fn with_level(error: DooError, level: u32) -> DooError {
    match error {
        DooError::NotDooConnectivity { face, reason } if level > 0 => {
            DooError::NotDooConnectivity { face, reason: format!("{reason} (in the mesh after {level} reversal(s))") }
        }
        other => other,
    }
}

/// Exactly `target - level` more levels: depth-first over the readings of each level,
/// best first, backtracking when a reading's coarse mesh cannot be reversed far enough.
///
/// `connected`: `fine` is known to be one connected component (see [`canonical_step`]).
fn descend(
    fine: &CornerMesh,
    positions: &[DVec3],
    options: &DecomposeOptions,
    level: u32,
    target: u32,
    connected: bool,
) -> Result<Vec<Step>, DooError> {
    descend_from(fine, positions, options, level, target, connected, true)
}

/// [`descend`] from the coarse mesh of `step`, the reversal of level `level`.
fn descend_below(step: &Step, options: &DecomposeOptions, level: u32, target: u32) -> Result<Vec<Step>, DooError> {
    descend(&step.coarse, &step.coarse_positions, options, level + 1, target, step.connected)
}

/// [`descend`], first trying the canonical path on this level if `try_canonical` (its
/// reading is the general search's best; if the levels below it cannot all be reversed,
/// the search goes over this level's readings as without it).
fn descend_from(
    fine: &CornerMesh,
    positions: &[DVec3],
    options: &DecomposeOptions,
    level: u32,
    target: u32,
    connected: bool,
    try_canonical: bool,
) -> Result<Vec<Step>, DooError> {
    if level == target {
        return Ok(Vec::new());
    }
    if try_canonical
        && let Some(step) = canonical_step(fine, positions, options, level, connected)
        && let Ok(rest) = descend_below(&step, options, level, target)
    {
        let mut steps = vec![step];
        steps.extend(rest);
        return Ok(steps);
    }
    if options.boundary == BoundaryRule::Chaikin {
        // One reading per level (the best that fits the boundary ring), no backtracking.
        let reversal = reverse_chaikin_corner_mesh(fine, positions, &reverse_options(options, level))
            .map_err(|e| with_level(e, level))?;
        let step = Step::from_reversal(reversal);
        let mut steps = descend_below(&step, options, level, target)?;
        steps.insert(0, step);
        return Ok(steps);
    }
    let mut session =
        Session::new(fine, positions, &reverse_options(options, level)).map_err(|e| with_level(e, level))?;
    let mut first_error = None;
    for picks in session.alternatives() {
        let step = match session.build(picks) {
            Ok(reversal) => Step::from_reversal(reversal),
            Err(error) => {
                first_error.get_or_insert(with_level(error, level));
                continue;
            }
        };
        match descend_below(&step, options, level, target) {
            Ok(rest) => {
                let mut steps = vec![step];
                steps.extend(rest);
                return Ok(steps);
            }
            Err(error) => {
                first_error.get_or_insert(error);
            }
        }
    }
    Err(first_error.expect("internal: there is always a first reading"))
}

/// The reversal of one level's corner mesh by the canonical path (see the canonical
/// module): the general search's best reading, bit for bit, when the mesh is in the
/// canonical order (as the coarse mesh of a canonical reversal of a mesh refined several
/// times is), under either boundary rule; `None` when it does not apply (another order, a
/// broken mesh), and the general path decides.
///
/// `connected`: `fine` is known to be one connected component, as the coarse mesh of a
/// canonical step is (the canonical path checks it). A connected fine mesh that passes
/// the canonical checks has a connected coarse mesh (each fine face lies on a coarse face,
/// edge or interior vertex, and the faces around an interior vertex are joined by its
/// edges), so that check is then skipped.
fn canonical_step(
    fine: &CornerMesh,
    positions: &[DVec3],
    options: &DecomposeOptions,
    level: u32,
    connected: bool,
) -> Option<Step> {
    if !canonical_enabled() || positions.len() != fine.vertex_count {
        return None;
    }
    // The coarse mesh of a canonical reversal of a mesh refined more than once is in the
    // canonical order again: its half-edges by arithmetic, checked as a soup's are
    // (those `of` finds, in fewer scattered reads); any other mesh as it is.
    let halfedges = CornerHalfedges::of_canonical_faces(positions, &fine.offsets, &fine.corner_vertex)
        .or_else(|| CornerHalfedges::of(fine))?;
    let options = reverse_options(options, level);
    let reversal = match options.boundary {
        BoundaryRule::Shrink => halfedges.reverse_canonical(positions, connected, &options),
        BoundaryRule::Chaikin => reverse_chaikin_arrays(&halfedges.view(positions), &options),
    };
    reversal.map(Step::from_canonical)
}

#[cfg(test)]
thread_local! {
    /// Tests: every level by the general path, to compare the canonical path with.
    static GENERAL_ONLY: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

fn canonical_enabled() -> bool {
    #[cfg(test)]
    return !GENERAL_ONLY.get();
    #[cfg(not(test))]
    true
}

/// One level of [`Depth::Max`]: the best reading whose coarse mesh can itself be reversed
/// (one level of look-ahead), else the best reading.
fn greedy_step(
    fine: &CornerMesh,
    positions: &[DVec3],
    options: &DecomposeOptions,
    level: u32,
) -> Result<Step, DooError> {
    if options.boundary == BoundaryRule::Chaikin {
        return reverse_chaikin_corner_mesh(fine, positions, &reverse_options(options, level))
            .map(Step::from_reversal)
            .map_err(|e| with_level(e, level));
    }
    let mut session =
        Session::new(fine, positions, &reverse_options(options, level)).map_err(|e| with_level(e, level))?;
    let mut fallback = None;
    let mut first_error = None;
    for picks in session.alternatives() {
        match session.build(picks) {
            Ok(reversal) => {
                let step = Step::from_reversal(reversal);
                let auto = ReverseOptions::auto(options.rule);
                if Session::new(&step.coarse, &step.coarse_positions, &auto).is_ok() {
                    return Ok(step);
                }
                fallback.get_or_insert(step);
            }
            Err(error) => {
                first_error.get_or_insert(with_level(error, level));
            }
        }
    }
    fallback.ok_or_else(|| first_error.expect("internal: there is always a first reading"))
}

impl DooPyramid {
    /// Number of detail levels (the finest mesh is level `level_count()`, the base is 0).
    pub fn level_count(&self) -> usize {
        self.levels.len()
    }

    /// Total number of detail vectors.
    pub fn detail_count(&self) -> usize {
        self.levels.iter().map(|l| l.details.len()).sum()
    }

    /// Rebuilds level `level` (0 = the base mesh), keeping the fraction `keep` of the
    /// detail vectors (all if `None`; see the module docs for the ranking).
    ///
    /// Each call builds the base mesh's connectivity from its polygon soup first; to
    /// reconstruct several times from one pyramid, [`prepare`](Self::prepare) it once.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_doo::pyramid::{DecomposeOptions, decompose};
    /// use subdiv_doo::{DooOptions, FaceRule, subdivide};
    ///
    /// let cube = HalfedgeMesh::from_soup(&shapes::cube())?;
    /// let mut fine = subdivide(&cube, &DooOptions::new(FaceRule::DooSabin, 2))?.to_mesh()?;
    /// fine.positions_mut()[10].x += 0.2; // a bump: non-zero details
    /// let pyramid = decompose(&fine, &DecomposeOptions::levels(FaceRule::DooSabin, 2))?.pyramid;
    /// assert_eq!(pyramid.reconstruct(0, None)?, pyramid.base);
    /// assert_eq!(pyramid.reconstruct(1, None)?.face_count(), 6 + 12 + 8);
    /// // Keeping every detail is the exact reconstruction; keeping none, Doo-Sabin
    /// // subdivision of the base mesh.
    /// assert_eq!(pyramid.reconstruct(2, Some(1.0))?, pyramid.reconstruct(2, None)?);
    /// let base = HalfedgeMesh::from_soup(&pyramid.base)?;
    /// let smooth = subdivide(&base, &DooOptions::new(FaceRule::DooSabin, 2))?.to_soup();
    /// let none = pyramid.reconstruct(2, Some(0.0))?;
    /// assert!(none.positions.iter().zip(&smooth.positions).all(|(a, b)| a.distance(*b) < 1e-12));
    /// assert!(pyramid.reconstruct(3, None).is_err() && pyramid.reconstruct(2, Some(1.5)).is_err());
    /// # Ok::<(), subdiv_doo::DooError>(())
    /// ```
    ///
    /// Memory: unlike [`subdivide`](crate::subdivide), whose few input bytes can ask for
    /// an output of any size, a reconstruction makes no check against the memory
    /// available: a level's coarse vertices and details are as many as its fine
    /// vertices, so the mesh of a level takes about twice (less than two and a half
    /// times) the pyramid's arrays up to that level, which are in memory already (and
    /// whose lengths are checked first).
    ///
    /// # Errors
    /// [`DooError::InvalidPyramid`] if `level` is out of range, `keep` is not in `[0, 1]`,
    /// or the pyramid is inconsistent (wrong array lengths, bad permutations).
    pub fn reconstruct(&self, level: usize, keep: Option<f64>) -> Result<PolygonSoup, DooError> {
        if let Some(scale) = self.unit_scale() {
            return self.scaled_down(scale).reconstruct(level, keep).map(|soup| scaled_up_soup(soup, scale));
        }
        let kept = self.check_request(level, keep)?;
        // (At the scale as given: the pyramid's values were just measured.)
        self.prepare_at(None)?.reconstruct_checked(level, kept)
    }

    /// The change of scale of a pyramid whose base coordinates and details are far from
    /// 1, under which it is reconstructed (see `crate::scale`).
    fn unit_scale(&self) -> Option<UnitScale> {
        UnitScale::of_values(self.base.positions.iter().chain(self.levels.iter().flat_map(|level| &level.details)))
    }

    /// The pyramid brought to unit scale by `scale`.
    fn scaled_down(&self, scale: UnitScale) -> DooPyramid {
        let mut scaled = self.clone();
        scale.scale_down(&mut scaled.base.positions);
        scaled.levels.iter_mut().for_each(|level| scale.scale_down(&mut level.details));
        scaled
    }

    /// Builds and checks the base mesh's connectivity once, for any number of
    /// reconstructions: the multiresolution counterpart of subdividing a mesh whose
    /// connectivity is already built (a rate-distortion sweep, several levels, an editor
    /// rebuilding after each change of a detail).
    ///
    /// ```
    /// use subdiv_doo::pyramid::{DecomposeOptions, decompose};
    /// use subdiv_doo::{DooOptions, FaceRule, subdivide};
    /// use mesh_topo::{HalfedgeMesh, shapes};
    ///
    /// let cube = HalfedgeMesh::from_soup(&shapes::cube())?;
    /// let fine = subdivide(&cube, &DooOptions::new(FaceRule::DooSabin, 2))?.to_mesh()?;
    /// let pyramid = decompose(&fine, &DecomposeOptions::levels(FaceRule::DooSabin, 2))?.pyramid;
    /// let prepared = pyramid.prepare()?;
    /// for level in 0..=2 {
    ///     assert_eq!(prepared.reconstruct(level, None)?, pyramid.reconstruct(level, None)?);
    /// }
    /// assert_eq!(prepared.reconstruct(2, Some(0.1))?, pyramid.reconstruct(2, Some(0.1))?);
    /// # Ok::<(), subdiv_doo::DooError>(())
    /// ```
    ///
    /// # Errors
    /// [`DooError::InvalidPyramid`] if the base mesh is not a valid polygon mesh;
    /// [`DooError::NonFinite`] naming a base vertex that is NaN or infinite; the rule's
    /// error if its parameter is out of range.
    pub fn prepare(&self) -> Result<PreparedDooPyramid<'_>, DooError> {
        self.prepare_at(self.unit_scale())
    }

    /// [`prepare`](Self::prepare) with the pyramid's change of scale, [`Self::unit_scale`],
    /// known already: the callers that have just measured it do not read every base
    /// position and detail once more (a pass that was 2.5% of a one-level
    /// reconstruction).
    fn prepare_at(&self, unit_scale: Option<UnitScale>) -> Result<PreparedDooPyramid<'_>, DooError> {
        debug_assert_eq!(unit_scale, self.unit_scale(), "internal: the pyramid's change of scale");
        self.rule.validate()?;
        check_finite(&self.base.positions)?;
        let (base, grouping) = CornerMesh::from_soup_grouped(&self.base)
            .map_err(|e| DooError::InvalidPyramid(format!("base mesh: {e}")))?;
        let base_corners = CornersByVertex::from_parts(grouping);
        Ok(PreparedDooPyramid { pyramid: self, base, base_corners, unit_scale })
    }

    /// Checks a reconstruction request; for a `keep` fraction, which details it keeps.
    fn check_request(&self, level: usize, keep: Option<f64>) -> Result<Option<Vec<Vec<bool>>>, DooError> {
        if level > self.levels.len() {
            return Err(DooError::InvalidPyramid(format!(
                "level {level} requested, the pyramid has levels 0 to {}",
                self.levels.len()
            )));
        }
        match keep {
            None => Ok(None),
            Some(f) if (0.0..=1.0).contains(&f) => Ok(Some(self.kept_details(f))),
            Some(f) => Err(DooError::InvalidPyramid(format!("keep fraction {f} is not in [0, 1]"))),
        }
    }

    /// For each level, which detail vectors the fraction `keep` keeps: the
    /// [`kept_count`] largest.
    fn kept_details(&self, keep: f64) -> Vec<Vec<bool>> {
        let levels = self.levels.len();
        let mut ranked: Vec<(f64, usize, usize)> = Vec::with_capacity(self.detail_count());
        for (k, level) in self.levels.iter().enumerate() {
            let weight = (2.0f64).powi((levels - 1 - k) as i32);
            ranked.extend(level.details.iter().enumerate().map(|(i, d)| (d.length() * weight, k, i)));
        }
        let count = kept_count(keep, ranked.len());
        ranked.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
        let mut mask: Vec<Vec<bool>> = self.levels.iter().map(|l| vec![false; l.details.len()]).collect();
        for &(_, k, i) in &ranked[..count] {
            mask[k][i] = true;
        }
        mask
    }

    /// Checks the arrays of level `k` against the mesh it refines.
    fn check_level(&self, k: usize, coarse: &CornerMesh, data: &PyramidLevel) -> Result<(), DooError> {
        let fail = |what: String| Err(DooError::InvalidPyramid(format!("level {}: {what}", k + 1)));
        let ring = match self.boundary {
            BoundaryRule::Shrink => None,
            BoundaryRule::Chaikin => Some(Ring::of(coarse).map_err(|e| DooError::InvalidPyramid(e.to_string()))?),
        };
        let corners = coarse.corner_count() + ring.as_ref().map_or(0, |r| 2 * r.quad_count());
        if data.details.len() + coarse.vertex_count != corners {
            return fail(format!(
                "{} details for {} coarse vertices and {corners} fine vertices",
                data.details.len(),
                coarse.vertex_count
            ));
        }
        if coarse.vertex_corner.as_ref().is_some_and(|v| v.contains(&NONE)) {
            return fail("a coarse vertex is not used by any face".into());
        }
        let order = &data.order;
        if !order.vertices.is_empty() && !is_permutation(&order.vertices, corners) {
            return fail("the vertex order is not a permutation of the fine vertices".into());
        }
        if order.faces.is_empty() && order.rotations.is_empty() {
            return Ok(());
        }
        let mut topology = doo_topology(coarse, false).map_err(|e| DooError::InvalidPyramid(e.to_string()))?;
        if let Some(ring) = &ring {
            ring.append_faces(&mut topology.offsets, None);
        }
        let faces = topology.offsets.len() - 1;
        if !order.faces.is_empty() && !is_permutation(&order.faces, faces) {
            return fail("the face order is not a permutation of the fine faces".into());
        }
        if !order.rotations.is_empty() {
            if order.rotations.len() != faces {
                return fail("wrong number of face rotations".into());
            }
            for (f, &r) in order.rotations.iter().enumerate() {
                if r >= topology.offsets[f + 1] - topology.offsets[f] {
                    return fail(format!("rotation {r} of face {f} exceeds its size"));
                }
            }
        }
        Ok(())
    }

    /// Rate-distortion table of the finest level: for each fraction, the errors of the
    /// reconstruction keeping that fraction of the details, relative to the bounding-box
    /// diagonal of the exact finest mesh.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_doo::pyramid::{DecomposeOptions, decompose};
    /// use subdiv_doo::{DooOptions, FaceRule, subdivide};
    ///
    /// let cube = HalfedgeMesh::from_soup(&shapes::cube())?;
    /// let mut fine = subdivide(&cube, &DooOptions::new(FaceRule::DooSabin, 2))?.to_mesh()?;
    /// fine.positions_mut()[10].x += 0.2; // a bump: non-zero details
    /// let pyramid = decompose(&fine, &DecomposeOptions::levels(FaceRule::DooSabin, 2))?.pyramid;
    /// let rows = pyramid.rate_distortion(&[0.0, 1.0])?;
    /// // Nothing kept: the bump is smoothed away. Everything kept: exact.
    /// assert!(rows[0].kept == 0 && rows[0].max_error > 0.0 && rows[0].rms_error < rows[0].max_error);
    /// assert_eq!(rows[1].kept, pyramid.detail_count());
    /// assert!(rows[1].max_error < 1e-12);
    /// # Ok::<(), subdiv_doo::DooError>(())
    /// ```
    ///
    /// # Errors
    /// As [`reconstruct`](Self::reconstruct).
    pub fn rate_distortion(&self, fractions: &[f64]) -> Result<Vec<RateDistortion>, DooError> {
        // Errors relative to the diagonal do not depend on the scale.
        if let Some(scale) = self.unit_scale() {
            return self.scaled_down(scale).rate_distortion(fractions);
        }
        let finest = self.levels.len();
        // The base connectivity is built once for all the reconstructions (at the scale
        // as given, just measured).
        let prepared = self.prepare_at(None)?;
        let exact = prepared.reconstruct(finest, None)?;
        let (lo, hi) =
            exact.positions.iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)));
        let diagonal = (hi - lo).length().max(f64::MIN_POSITIVE);
        let total = self.detail_count();
        fractions
            .iter()
            .map(|&fraction| {
                let approx = prepared.reconstruct(finest, Some(fraction))?;
                let (mut max, mut sum) = (0.0f64, 0.0f64);
                for (a, b) in approx.positions.iter().zip(&exact.positions) {
                    let d = (*a - *b).length();
                    max = max.max(d);
                    sum += d * d;
                }
                let n = exact.positions.len().max(1) as f64;
                Ok(RateDistortion {
                    fraction,
                    kept: kept_count(fraction, total),
                    max_error: max / diagonal,
                    rms_error: (sum / n).sqrt() / diagonal,
                })
            })
            .collect()
    }

    /// Encodes the pyramid as a `.mres` file.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes::{self, CellKind}};
    /// use subdiv_doo::pyramid::{DecomposeOptions, DooPyramid, PYRAMID_MAGIC, decompose};
    /// use subdiv_doo::{BoundaryRule, DooOptions, FaceRule, subdivide};
    ///
    /// // An open grid under the Chaikin boundary rule: rule and boundary rule are in the file.
    /// let grid = HalfedgeMesh::from_soup(&shapes::grid(2, 2, CellKind::Quads)?)?;
    /// let refine = DooOptions::new(FaceRule::Simple, 1).with_boundary(BoundaryRule::Chaikin);
    /// let fine = subdivide(&grid, &refine)?.to_mesh()?;
    /// let options = DecomposeOptions::levels(FaceRule::Simple, 1).with_boundary(BoundaryRule::Chaikin);
    /// let pyramid = decompose(&fine, &options)?.pyramid;
    /// let bytes = pyramid.to_bytes()?;
    /// assert_eq!(bytes[..8], PYRAMID_MAGIC);
    /// let read = DooPyramid::from_bytes(&bytes)?;
    /// assert_eq!((read.rule, read.boundary), (FaceRule::Simple, BoundaryRule::Chaikin));
    /// assert_eq!(read, pyramid);
    /// # Ok::<(), subdiv_doo::DooError>(())
    /// ```
    ///
    /// # Errors
    /// [`DooError::Binary`] if encoding fails.
    pub fn to_bytes(&self) -> Result<Vec<u8>, DooError> {
        Ok(binary::encode(PYRAMID_MAGIC, PYRAMID_VERSION, self)?)
    }

    /// Decodes a `.mres` file written by [`to_bytes`](Self::to_bytes) and checks it
    /// (every level's arrays against the mesh it refines).
    ///
    /// ```
    /// use subdiv_doo::pyramid::{DecomposeOptions, DooPyramid, decompose, is_doo_pyramid};
    /// use subdiv_doo::{DooOptions, FaceRule, subdivide};
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// let cube = HalfedgeMesh::from_soup(&shapes::cube())?;
    /// let fine = subdivide(&cube, &DooOptions::new(FaceRule::DooSabin, 2))?.to_mesh()?;
    /// let pyramid = decompose(&fine, &DecomposeOptions::levels(FaceRule::DooSabin, 2))?.pyramid;
    /// let bytes = pyramid.to_bytes()?;
    /// assert!(is_doo_pyramid(&bytes));
    /// assert_eq!(DooPyramid::from_bytes(&bytes)?, pyramid);
    /// assert!(DooPyramid::from_bytes(&bytes[..bytes.len() - 3]).is_err());
    /// # Ok::<(), subdiv_doo::DooError>(())
    /// ```
    ///
    /// # Errors
    /// [`DooError::Binary`] for a truncated, corrupted or foreign file;
    /// [`DooError::InvalidPyramid`] if the content is inconsistent.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, DooError> {
        const WHAT: &str = "multires Doo-Sabin pyramid";
        let pyramid: DooPyramid = match binary::decode(bytes, PYRAMID_MAGIC, PYRAMID_VERSION, WHAT) {
            Err(binary::BinaryError::UnsupportedVersion { found: 1, .. }) => {
                let DooPyramidV1 { rule, base, levels } = binary::decode(bytes, PYRAMID_MAGIC, 1, WHAT)?;
                DooPyramid { rule, base, levels, boundary: BoundaryRule::Shrink }
            }
            decoded => decoded?,
        };
        pyramid.validate()?;
        Ok(pyramid)
    }

    /// Checks that the pyramid can be reconstructed (array lengths, permutations), level
    /// by level, without computing positions.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_doo::pyramid::{DecomposeOptions, decompose};
    /// use subdiv_doo::{DooError, DooOptions, FaceRule, subdivide};
    ///
    /// let cube = HalfedgeMesh::from_soup(&shapes::cube())?;
    /// let fine = subdivide(&cube, &DooOptions::new(FaceRule::DooSabin, 2))?.to_mesh()?;
    /// let mut pyramid = decompose(&fine, &DecomposeOptions::levels(FaceRule::DooSabin, 2))?.pyramid;
    /// pyramid.validate()?;
    /// // One detail more than level 2 has fine vertices for: the level is named.
    /// pyramid.levels[1].details.push(glam::DVec3::X);
    /// let error = pyramid.validate().unwrap_err();
    /// assert!(matches!(&error, DooError::InvalidPyramid(message) if message.starts_with("level 2:")));
    /// # Ok::<(), subdiv_doo::DooError>(())
    /// ```
    ///
    /// # Errors
    /// [`DooError::InvalidPyramid`] naming the first inconsistency.
    pub fn validate(&self) -> Result<(), DooError> {
        self.rule.validate()?;
        let mut mesh =
            CornerMesh::from_soup(&self.base).map_err(|e| DooError::InvalidPyramid(format!("base mesh: {e}")))?;
        for (k, data) in self.levels.iter().enumerate() {
            self.check_level(k, &mesh, data)?;
            if k + 1 < self.levels.len() {
                // Connectivity only: zero positions and details.
                let zeros = vec![DVec3::ZERO; mesh.vertex_count];
                let details = vec![DVec3::ZERO; data.details.len()];
                let level = Level { details: &details, order: &data.order, rule: self.rule, boundary: self.boundary };
                mesh = reconstruct_level_with(&mesh, &zeros, &level, true)
                    .map_err(|e| DooError::InvalidPyramid(format!("level {}: {e}", k + 1)))?
                    .0;
            }
        }
        Ok(())
    }
}

/// A [`DooPyramid`] whose base connectivity is built and checked: reconstructions from it
/// skip that step (see [`DooPyramid::prepare`]).
#[derive(Debug)]
pub struct PreparedDooPyramid<'a> {
    pyramid: &'a DooPyramid,
    base: CornerMesh,
    /// The base's corners by vertex, which its check computes anyway.
    base_corners: CornersByVertex,
    /// The pyramid's change of scale, if it is reconstructed at unit scale.
    unit_scale: Option<UnitScale>,
}

/// A soup rebuilt at unit scale brought back by `scale` (what the arithmetic gives: a
/// position beyond `f64` is infinite, as it would be at any scale).
fn scaled_up_soup(mut soup: PolygonSoup, scale: UnitScale) -> PolygonSoup {
    scale.scale_up(&mut soup.positions);
    soup
}

impl PreparedDooPyramid<'_> {
    /// [`DooPyramid::reconstruct`] without building the base connectivity again: the same
    /// result, bit for bit.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_doo::pyramid::{DecomposeOptions, decompose};
    /// use subdiv_doo::{DooOptions, FaceRule, subdivide};
    ///
    /// let cube = HalfedgeMesh::from_soup(&shapes::cube())?;
    /// let fine = subdivide(&cube, &DooOptions::new(FaceRule::DooSabin, 2))?.to_mesh()?;
    /// let pyramid = decompose(&fine, &DecomposeOptions::max(FaceRule::DooSabin))?.pyramid;
    /// let prepared = pyramid.prepare()?;
    /// // F' = F + E + V at each level: 6, then 6 + 12 + 8, then 26 + 48 + 24 faces.
    /// for (level, faces) in [6, 26, 98].into_iter().enumerate() {
    ///     assert_eq!(prepared.reconstruct(level, None)?.face_count(), faces);
    /// }
    /// let rebuilt = prepared.reconstruct(2, None)?;
    /// assert!(rebuilt.positions.iter().zip(fine.positions()).all(|(a, b)| a.distance(*b) < 1e-14));
    /// assert!(prepared.reconstruct(3, None).is_err()); // only two levels
    /// # Ok::<(), subdiv_doo::DooError>(())
    /// ```
    ///
    /// # Errors
    /// As [`DooPyramid::reconstruct`], except the base mesh's errors, which
    /// [`DooPyramid::prepare`] reported.
    pub fn reconstruct(&self, level: usize, keep: Option<f64>) -> Result<PolygonSoup, DooError> {
        if let Some(scale) = self.unit_scale {
            let scaled = self.pyramid.scaled_down(scale);
            return scaled.prepare()?.reconstruct(level, keep).map(|soup| scaled_up_soup(soup, scale));
        }
        let kept = self.pyramid.check_request(level, keep)?;
        self.reconstruct_checked(level, kept)
    }

    fn reconstruct_checked(&self, level: usize, kept: Option<Vec<Vec<bool>>>) -> Result<PolygonSoup, DooError> {
        let pyramid = self.pyramid;
        if level == 0 {
            return Ok(pyramid.base.clone());
        }
        // The finer levels' meshes; the base is borrowed.
        let mut refined: Option<(CornerMesh, Vec<DVec3>)> = None;
        for (k, data) in pyramid.levels[..level].iter().enumerate() {
            let (mesh, positions) = match &refined {
                Some((mesh, positions)) => (mesh, &positions[..]),
                None => (&self.base, &pyramid.base.positions[..]),
            };
            pyramid.check_level(k, mesh, data)?;
            let filtered;
            let details = match &kept {
                None => &data.details,
                Some(mask) => {
                    filtered = data
                        .details
                        .iter()
                        .zip(&mask[k])
                        .map(|(&d, &keep)| if keep { d } else { DVec3::ZERO })
                        .collect::<Vec<_>>();
                    &filtered
                }
            };
            if pyramid.boundary == BoundaryRule::Chaikin {
                // Ring and Chaikin points on top of the Shrink step (a non-finite detail
                // is named; an overflow of finite ones is not an error, as below).
                check_finite(details).map_err(|e| DooError::InvalidPyramid(format!("level {}: detail {e}", k + 1)))?;
                let data = Level { details, order: &data.order, rule: pyramid.rule, boundary: pyramid.boundary };
                let next = reconstruct_level_with(mesh, positions, &data, k + 1 < level)
                    .map_err(|e| DooError::InvalidPyramid(format!("level {}: {e}", k + 1)))?;
                refined = Some(next);
                continue;
            }
            let (candidates, finite) = if k == 0 {
                level_candidates(&self.base_corners, positions, details)
            } else {
                level_candidates(&corners_by_vertex(mesh), positions, details)
            };
            if !finite {
                // Name the offending detail (a non-finite candidate may also come from an
                // overflow, which is not an error).
                check_finite(details).map_err(|e| DooError::InvalidPyramid(format!("level {}: detail {e}", k + 1)))?;
            }
            let with_adjacency = k + 1 < level;
            let next = level_from_candidates(mesh, candidates, &data.order, pyramid.rule, with_adjacency)
                .map_err(|e| DooError::InvalidPyramid(format!("level {}: {e}", k + 1)))?;
            refined = Some(next);
        }
        let (mesh, positions) = refined.expect("internal: level > 0 refines at least once");
        Ok(PolygonSoup { positions, offsets: mesh.offsets, indices: mesh.corner_vertex })
    }
}

fn is_permutation(values: &[u32], n: usize) -> bool {
    if values.len() != n {
        return false;
    }
    let mut seen = vec![false; n];
    values.iter().all(|&v| (v as usize) < n && !std::mem::replace(&mut seen[v as usize], true))
}

/// The number of detail vectors that the fraction `fraction` (in `[0, 1]`) keeps of
/// `total`: `round(fraction × total)`, the one rule of the compression
/// ([`DooPyramid::reconstruct`]) and of its rate-distortion rows.
///
/// ```
/// use subdiv_doo::pyramid::kept_count;
/// assert_eq!(kept_count(0.5, 5), 3);
/// assert_eq!(kept_count(1e-300, 88), 0);
/// assert_eq!(kept_count(1.0, 88), 88);
/// ```
pub fn kept_count(fraction: f64, total: usize) -> usize {
    ((fraction * total as f64).round() as usize).min(total)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::canonical::reverse_canonical_arrays;
    use crate::canonical::tests::without;
    use crate::{DooOptions, subdivide};
    use mesh_topo::shapes;

    /// The bound the docs of [`DooPyramid::reconstruct`] give for making no memory check:
    /// a level's mesh takes about twice the pyramid's arrays up to that level (less than
    /// 2.5 times).
    #[test]
    fn a_reconstruction_takes_about_twice_the_pyramid() {
        let cases = [
            shapes::tetrahedron(),
            shapes::cube(),
            shapes::torus(6, 4, shapes::CellKind::Mixed).unwrap(),
            shapes::grid(8, 8, shapes::CellKind::Quads).unwrap(),
        ];
        let mut largest: f64 = 0.0;
        for soup in cases {
            let coarse = HalfedgeMesh::from_soup(&soup).unwrap();
            let fine = subdivide(&coarse, &DooOptions::new(FaceRule::DooSabin, 3)).unwrap().to_mesh().unwrap();
            let pyramid = decompose(&fine, &DecomposeOptions::levels(FaceRule::DooSabin, 3)).unwrap().pyramid;
            for level in 0..=3 {
                let details: usize = pyramid.levels[..level].iter().map(|l| 24 * l.details.len()).sum();
                let held = pyramid.base.array_bytes() + details as u128;
                let made = pyramid.reconstruct(level, None).unwrap().array_bytes();
                largest = largest.max(made as f64 / held as f64);
            }
        }
        assert!(largest <= 2.5 && largest > 1.5, "{largest}");
    }

    #[test]
    fn version_1_files_are_read_as_shrinking_pyramids() {
        #[derive(Serialize)]
        struct Version1<'a> {
            rule: FaceRule,
            base: &'a PolygonSoup,
            levels: &'a [PyramidLevel],
        }
        let pyramid = cube_pyramid();
        assert_eq!(pyramid.boundary, BoundaryRule::Shrink);
        let old = Version1 { rule: pyramid.rule, base: &pyramid.base, levels: &pyramid.levels };
        let bytes = binary::encode(PYRAMID_MAGIC, 1, &old).unwrap();
        assert_eq!(DooPyramid::from_bytes(&bytes).unwrap(), pyramid);
        // The version is checked before the layout: a version 2 payload under a version 1
        // header is an error, not a misread.
        let mut relabelled = pyramid.to_bytes().unwrap();
        relabelled[8..12].copy_from_slice(&1u32.to_le_bytes());
        assert!(DooPyramid::from_bytes(&relabelled).is_err());
        let mut future = pyramid.to_bytes().unwrap();
        future[8..12].copy_from_slice(&3u32.to_le_bytes());
        assert!(matches!(DooPyramid::from_bytes(&future), Err(DooError::Binary(_))));
    }

    /// `coarse` refined `levels` times, every fine vertex moved (fixed seed).
    fn refined_and_moved(coarse: &PolygonSoup, rule: FaceRule, levels: u32) -> HalfedgeMesh {
        refined_and_moved_with(coarse, rule, levels, BoundaryRule::Shrink)
    }

    fn refined_and_moved_with(
        coarse: &PolygonSoup,
        rule: FaceRule,
        levels: u32,
        boundary: BoundaryRule,
    ) -> HalfedgeMesh {
        let coarse = HalfedgeMesh::from_soup(coarse).unwrap();
        let options = DooOptions { boundary, ..DooOptions::new(rule, levels) };
        let mut fine = subdivide(&coarse, &options).unwrap().to_mesh().unwrap();
        for (i, p) in fine.positions_mut().iter_mut().enumerate() {
            let t = i as f64;
            *p += 1e-3 * DVec3::new((1.3 * t).sin(), (2.1 * t).cos(), (0.7 * t).sin());
        }
        fine
    }

    fn general_only<T>(run: impl FnOnce() -> T) -> T {
        GENERAL_ONLY.set(true);
        let result = run();
        GENERAL_ONLY.set(false);
        result
    }

    #[test]
    fn corner_halfedges_are_those_of_the_half_edge_mesh() {
        let open = shapes::grid(5, 4, shapes::CellKind::Quads).unwrap();
        let holed = without(&shapes::torus(8, 6, shapes::CellKind::Triangles).unwrap(), &[3, 50]);
        for soup in [shapes::cube(), open, holed, shapes::tetrahedron()] {
            let mesh = HalfedgeMesh::from_soup(&soup).unwrap();
            let arrays = CornerHalfedges::of(&CornerMesh::from_halfedge(&mesh)).unwrap();
            let view = arrays.view(mesh.positions());
            let expected = crate::canonical::HalfedgeArrays::of(&mesh);
            assert_eq!(format!("{view:?}"), format!("{expected:?}"));
        }
    }

    #[test]
    fn halfedges_of_a_canonical_soup_are_those_of_from_soup() {
        let holed = without(&shapes::torus(8, 6, shapes::CellKind::Triangles).unwrap(), &[3, 50]);
        let cases = [
            (shapes::cube(), FaceRule::DooSabin, 1),
            (shapes::cube(), FaceRule::Simple, 3),
            (shapes::tetrahedron(), FaceRule::DooSabin, 2),
            (shapes::icosahedron(), FaceRule::Centroid { a: 0.5 }, 2),
            (shapes::torus(6, 4, shapes::CellKind::Triangles).unwrap(), FaceRule::DooSabin, 2),
            (shapes::torus(5, 3, shapes::CellKind::Mixed).unwrap(), FaceRule::DooSabin, 1),
            // With a boundary.
            (shapes::grid(4, 3, shapes::CellKind::Quads).unwrap(), FaceRule::DooSabin, 1),
            (shapes::grid(5, 4, shapes::CellKind::Mixed).unwrap(), FaceRule::Simple, 2),
            (holed, FaceRule::DooSabin, 2),
        ];
        for (coarse, rule, levels) in cases {
            let soup = refined_and_moved(&coarse, rule, levels).to_soup();
            let mesh = HalfedgeMesh::from_soup(&soup).unwrap();
            let arrays = CornerHalfedges::of_canonical_soup(&soup).expect("a canonical soup");
            let view = arrays.view(&soup.positions);
            let expected = crate::canonical::HalfedgeArrays::of(&mesh);
            assert_eq!(format!("{view:?}"), format!("{expected:?}"), "{rule:?} x{levels}");
        }
        // Not taken: the Chaikin ring, a mesh in another order, soups that are not refinements.
        let grid = shapes::grid(4, 3, shapes::CellKind::Quads).unwrap();
        let ringed = refined_and_moved_with(&grid, FaceRule::DooSabin, 1, BoundaryRule::Chaikin);
        let scrambled =
            mesh_topo::testing::scramble(refined_and_moved(&shapes::cube(), FaceRule::DooSabin, 1).to_soup(), 3, 0.0);
        for soup in [ringed.to_soup(), scrambled, shapes::cube(), shapes::torus(4, 4, shapes::CellKind::Quads).unwrap()]
        {
            assert!(CornerHalfedges::of_canonical_soup(&soup).is_none());
        }
    }

    /// The coarse meshes of canonical reversals: by arithmetic when the fine mesh was
    /// refined more than once (the same arrays as the corner walk), not for one step.
    #[test]
    fn halfedges_of_a_canonical_coarse_mesh_are_those_of_the_corner_walk() {
        let holed = without(&shapes::torus(8, 6, shapes::CellKind::Triangles).unwrap(), &[3, 50]);
        // (Whether every level of the mesh is closed.)
        let cases = [
            (shapes::cube(), FaceRule::DooSabin, true),
            (shapes::tetrahedron(), FaceRule::Simple, true),
            (shapes::torus(6, 4, shapes::CellKind::Mixed).unwrap(), FaceRule::DooSabin, true),
            (shapes::grid(5, 4, shapes::CellKind::Mixed).unwrap(), FaceRule::Centroid { a: 0.5 }, false),
            (holed, FaceRule::DooSabin, false),
        ];
        for (base, rule, closed) in cases {
            for levels in 1..=3 {
                let fine = refined_and_moved(&base, rule, levels);
                let mut level_mesh = CornerMesh::from_halfedge(&fine);
                let mut positions = fine.positions().to_vec();
                let mut reversed = 0;
                for level in 0..levels {
                    let halfedges = CornerHalfedges::of(&level_mesh).unwrap();
                    let arithmetic =
                        CornerHalfedges::of_canonical_faces(&positions, &level_mesh.offsets, &level_mesh.corner_vertex);
                    match arithmetic {
                        Some(arithmetic) => assert_eq!(
                            format!("{:?}", arithmetic.view(&positions)),
                            format!("{:?}", halfedges.view(&positions)),
                            "{rule:?} x{levels}, level {level}"
                        ),
                        // The base mesh is in no canonical order, nor is an open coarse
                        // mesh (its boundary vertices are numbered last), whose level the
                        // general path reverses.
                        None => assert!(level == levels - 1 || !closed, "{rule:?} x{levels}, level {level}"),
                    }
                    let seeded = ReverseOptions::with_seed(rule, 0);
                    let Some(reversal) = reverse_canonical_arrays(&halfedges.view(&positions), &seeded) else {
                        break;
                    };
                    let (coarse, coarse_positions, ..) = reversal.into_parts();
                    (level_mesh, positions) = (coarse, coarse_positions);
                    reversed += 1;
                }
                assert!(reversed >= 1 && (!closed || reversed == levels), "{rule:?} x{levels}: {reversed}");
            }
        }
    }

    #[test]
    fn soups_whose_sides_meet_are_left_to_from_soup() {
        // One F_F face whose opposite sides are twinned: every F_E quad and F_V face is
        // well formed, but the F_V face is the F_F face again, each side used twice.
        let positions = vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
        let soup = PolygonSoup::from_faces(positions, [[0, 1, 2, 3], [0, 3, 2, 1], [1, 0, 3, 2], [0, 1, 2, 3]]);
        assert!(CornerHalfedges::of_canonical_soup(&soup).is_none());
        let options = DecomposeOptions::levels(FaceRule::DooSabin, 1);
        assert!(matches!(decompose_soup(&soup, &options), Err(DooError::Mesh(_))));
        // Two triangles and two quads of that form, whose quad sides `4 -> 1` and `1 -> 4`
        // are one edge to `from_soup` (a valid strip) but two in the canonical numbering.
        let positions = (0..6).map(|i| DVec3::new(i as f64, (i * i) as f64, 0.0)).collect();
        let strip =
            PolygonSoup::from_faces(positions, [vec![0, 1, 2], vec![3, 4, 5], vec![0, 5, 4, 1], vec![1, 4, 3, 2]]);
        assert!(HalfedgeMesh::from_soup(&strip).is_ok());
        assert!(CornerHalfedges::of_canonical_soup(&strip).is_none());
        let built = decompose(&HalfedgeMesh::from_soup(&strip).unwrap(), &options);
        assert_eq!(format!("{:?}", decompose_soup(&strip, &options)), format!("{built:?}"));
    }

    #[test]
    fn malformed_soups_are_left_to_from_soup() {
        let fine = refined_and_moved(&shapes::tetrahedron(), FaceRule::DooSabin, 1).to_soup();
        let mut soups = vec![PolygonSoup::default(), PolygonSoup { offsets: vec![0], ..PolygonSoup::default() }];
        let mut edit = |change: &dyn Fn(&mut PolygonSoup)| {
            let mut soup = fine.clone();
            change(&mut soup);
            soups.push(soup);
        };
        edit(&|s| s.offsets[0] = 1);
        edit(&|s| s.offsets[2] = s.offsets[1] - 1);
        edit(&|s| *s.offsets.last_mut().unwrap() += 4);
        edit(&|s| s.offsets.truncate(1));
        edit(&|s| s.offsets.clear());
        edit(&|s| s.indices.truncate(5));
        edit(&|s| s.positions.clear());
        edit(&|s| s.positions.push(DVec3::ZERO));
        let options = DecomposeOptions::max(FaceRule::DooSabin);
        for soup in &soups {
            let built =
                HalfedgeMesh::from_soup(soup).map_err(DooError::from).and_then(|mesh| decompose(&mesh, &options));
            assert_eq!(format!("{:?}", decompose_soup(soup, &options)), format!("{built:?}"));
        }
    }

    /// A soup made by one of a few kinds of damage to `soup` (`kind` picks it, `pick`
    /// where), or `soup` itself; the damaged soup may or may not be a valid mesh.
    fn damaged(mut soup: PolygonSoup, kind: usize, pick: u64) -> PolygonSoup {
        let faces = soup.face_count();
        let face = (pick % faces as u64) as usize;
        let (b, e) = (soup.offsets[face] as usize, soup.offsets[face + 1] as usize);
        let corner = b + (pick / 7) as usize % (e - b);
        let vertex = ((pick / 13) % soup.positions.len() as u64) as u32;
        match kind {
            // A face rotated by one, or reversed.
            1 => soup.indices[b..e].rotate_left(1),
            2 => soup.indices[b..e].reverse(),
            // One corner moved to another vertex.
            3 => soup.indices[corner] = vertex,
            // One face removed, or listed twice.
            4 | 5 => {
                let mut kept: Vec<Vec<u32>> = (0..faces).map(|f| soup.face(f).to_vec()).collect();
                if kind == 4 {
                    kept.remove(face);
                } else {
                    kept.push(kept[face].clone());
                }
                soup = PolygonSoup::from_faces(soup.positions, kept);
            }
            // Two faces swapped.
            6 => {
                let mut all: Vec<Vec<u32>> = (0..faces).map(|f| soup.face(f).to_vec()).collect();
                all.swap(face, (face + 1 + (pick / 3) as usize % (faces - 1)) % faces);
                soup = PolygonSoup::from_faces(soup.positions, all);
            }
            // A position not finite, or the last vertex dropped (an index out of range).
            7 => soup.positions[vertex as usize].y = f64::NAN,
            8 => {
                soup.positions.pop();
            }
            // Every face reversed: a valid mesh, not in the canonical order.
            9 => {
                let all: Vec<Vec<u32>> = (0..faces).map(|f| soup.face(f).iter().rev().copied().collect()).collect();
                soup = PolygonSoup::from_faces(soup.positions, all);
            }
            // One vertex moved far: still canonical, large details.
            10 => soup.positions[vertex as usize] += DVec3::new(0.5, -0.25, 1.0),
            _ => {}
        }
        soup
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(256))]
        /// `decompose_soup` gives what building the mesh and decomposing it gives: the
        /// same decomposition (reports included) or the same error, for refined meshes,
        /// damaged or not, to every depth, automatic and seeded.
        #[test]
        fn soups_decompose_as_their_meshes(
            shape in 0usize..7,
            rule in 0usize..3,
            levels in 1u32..4,
            damage in 0usize..16,
            pick in proptest::prelude::any::<u64>(),
            depth in 0usize..5,
        ) {
            let coarse = match shape {
                0 => shapes::cube(),
                1 => shapes::tetrahedron(),
                2 => shapes::torus(5, 3, shapes::CellKind::Triangles).unwrap(),
                3 => shapes::torus(4, 3, shapes::CellKind::Mixed).unwrap(),
                4 => shapes::grid(3, 2, shapes::CellKind::Quads).unwrap(),
                5 => without(&shapes::torus(6, 4, shapes::CellKind::Triangles).unwrap(), &[2, 30]),
                _ => shapes::icosahedron(),
            };
            let rule = [FaceRule::DooSabin, FaceRule::Simple, FaceRule::Centroid { a: 0.5 }][rule];
            let levels = if shape == 4 { 1 } else { levels.min(if (2..=5).contains(&shape) { 2 } else { 3 }) };
            let soup = damaged(refined_and_moved(&coarse, rule, levels).to_soup(), damage, pick);
            let options = match depth {
                0 => DecomposeOptions::levels(rule, levels),
                1 => DecomposeOptions::levels(rule, 1),
                2 => DecomposeOptions::max(rule),
                3 => DecomposeOptions::levels(rule, levels + 1),
                _ => DecomposeOptions { seeds: vec![(pick % 5) as usize], ..DecomposeOptions::levels(rule, levels) },
            };
            // The arrays alone: a soup they accept is one `from_soup` accepts, numbered alike.
            if let Some(arrays) = CornerHalfedges::of_canonical_soup(&soup) {
                let mesh = HalfedgeMesh::from_soup(&soup);
                proptest::prop_assert!(mesh.is_ok(), "accepted, but {mesh:?}");
                let expected = crate::canonical::HalfedgeArrays::of(mesh.as_ref().unwrap());
                proptest::prop_assert_eq!(format!("{:?}", arrays.view(&soup.positions)), format!("{expected:?}"));
            }
            let direct = decompose_soup(&soup, &options);
            let built = HalfedgeMesh::from_soup(&soup).map_err(DooError::from).and_then(|mesh| decompose(&mesh, &options));
            proptest::prop_assert_eq!(format!("{direct:?}"), format!("{built:?}"));
        }
    }

    /// Decompositions of `fine` (refined `levels` times under `boundary`) to every depth,
    /// seeded and automatic, equal to the general path's (Debug text, bit for bit) and
    /// reconstructing `fine`; and more levels than it has: the same error on both paths.
    fn assert_both_paths_agree(fine: &HalfedgeMesh, rule: FaceRule, levels: u32, boundary: BoundaryRule) {
        for options in [
            DecomposeOptions::levels(rule, levels),
            DecomposeOptions::levels(rule, 1),
            DecomposeOptions::max(rule),
            DecomposeOptions { seeds: vec![0], ..DecomposeOptions::levels(rule, levels) },
        ] {
            let options = options.with_boundary(boundary);
            let fast = decompose(fine, &options).unwrap();
            let general = general_only(|| decompose(fine, &options).unwrap());
            assert_eq!(format!("{fast:?}"), format!("{general:?}"), "{rule:?} {boundary:?} {:?}", options.depth);
            let rebuilt = fast.pyramid.reconstruct(fast.pyramid.level_count(), None).unwrap();
            assert_eq!(rebuilt.indices, fine.to_soup().indices);
            for (p, q) in rebuilt.positions.iter().zip(fine.positions()) {
                assert!(p.distance(*q) < 1e-12, "{p} against {q}");
            }
        }
        let too_deep = DecomposeOptions::levels(rule, levels + 3).with_boundary(boundary);
        let fast = decompose(fine, &too_deep).map(|d| d.pyramid.level_count());
        let general = general_only(|| decompose(fine, &too_deep).map(|d| d.pyramid.level_count()));
        assert_eq!(format!("{fast:?}"), format!("{general:?}"));
    }

    #[test]
    fn coarser_levels_of_a_canonical_mesh_give_the_general_result() {
        // Faces 5, 30, 55, 80 removed: holes that share no vertex.
        let holed = without(&shapes::torus(12, 8, shapes::CellKind::Quads).unwrap(), &[5, 30, 55, 80]);
        // (mesh, rule, levels, whether the automatic choice of every level is the
        // canonical path's: not on quad meshes, where the lowest F_E quad read as F_F
        // finds quads all around it and the general search goes on).
        let cases = [
            (shapes::torus(10, 6, shapes::CellKind::Triangles).unwrap(), FaceRule::DooSabin, 3, true),
            (shapes::icosahedron(), FaceRule::Centroid { a: 0.5 }, 3, true),
            (shapes::cube(), FaceRule::Simple, 3, false),
            (holed, FaceRule::DooSabin, 2, false),
        ];
        for (coarse, rule, levels, canonical_all_the_way) in cases {
            let fine = refined_and_moved(&coarse, rule, levels);
            if canonical_all_the_way {
                let auto = ReverseOptions::auto(rule);
                let first = crate::canonical::reverse_canonical(&fine, &auto).expect("canonical order");
                let mut step = Step::from_reversal(first);
                for level in 1..levels {
                    let options = DecomposeOptions::levels(rule, levels);
                    step = canonical_step(&step.coarse, &step.coarse_positions, &options, level, step.connected)
                        .expect("canonical");
                }
            }
            assert_both_paths_agree(&fine, rule, levels, BoundaryRule::Shrink);
        }
    }

    #[test]
    fn coarser_chaikin_levels_of_a_canonical_mesh_give_the_general_result() {
        let holed = without(&shapes::torus(12, 8, shapes::CellKind::Quads).unwrap(), &[5, 30, 55, 80]);
        let open_triangles = without(&shapes::torus(10, 6, shapes::CellKind::Triangles).unwrap(), &[0, 1]);
        let closed = shapes::torus(6, 4, shapes::CellKind::Triangles).unwrap();
        for (coarse, rule, levels) in
            [(holed, FaceRule::DooSabin, 3), (open_triangles, FaceRule::Simple, 3), (closed, FaceRule::DooSabin, 2)]
        {
            let fine = refined_and_moved_with(&coarse, rule, levels, BoundaryRule::Chaikin);
            // Every level by the canonical path.
            let auto = ReverseOptions { boundary: BoundaryRule::Chaikin, ..ReverseOptions::auto(rule) };
            let first = crate::boundary::reverse_chaikin_canonical(&fine, &auto).expect("canonical order");
            let mut step = Step::from_reversal(first);
            for level in 1..levels {
                let options = DecomposeOptions::levels(rule, levels).with_boundary(BoundaryRule::Chaikin);
                step = canonical_step(&step.coarse, &step.coarse_positions, &options, level, step.connected)
                    .unwrap_or_else(|| panic!("level {level} of {rule:?} by the canonical path"));
            }
            assert_both_paths_agree(&fine, rule, levels, BoundaryRule::Chaikin);
        }
    }

    fn cube_pyramid() -> DooPyramid {
        let cube = HalfedgeMesh::from_soup(&shapes::cube()).unwrap();
        let mut fine = subdivide(&cube, &DooOptions::new(FaceRule::DooSabin, 2)).unwrap().to_mesh().unwrap();
        fine.positions_mut()[40].z += 0.1;
        decompose(&fine, &DecomposeOptions::levels(FaceRule::DooSabin, 2)).unwrap().pyramid
    }

    #[test]
    fn fuzz_regression_max_depth_stops_when_a_level_does_not_coarsen() {
        // A lone quad, and two quads sharing no edge, are their own Doo-Sabin refinement.
        // `Depth::Max` went on to 32 levels, each expanding the faces by 1 / (1 - a) = 10
        // under the centroid rule with a = 0.9: a base of size 7e31 from which the quad
        // came back with an error of 6e14 times its diagonal.
        let lone_quad = PolygonSoup::from_faces(
            vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y],
            [[0u32, 1, 2, 3]],
        );
        let mut two_quads = lone_quad.clone();
        two_quads.positions.extend(lone_quad.positions.iter().map(|p| *p + DVec3::new(3.0, 0.5, 0.25)));
        two_quads.push_face(&[4, 5, 6, 7]);
        for (soup, rule) in [(lone_quad, FaceRule::Centroid { a: 0.9 }), (two_quads, FaceRule::DooSabin)] {
            let mesh = HalfedgeMesh::from_soup(&soup).unwrap();
            let decomposition = decompose(&mesh, &DecomposeOptions::max(rule)).unwrap();
            assert_eq!(decomposition.pyramid.level_count(), 1);
            assert!(
                decomposition.stopped.as_deref().unwrap().contains("did not coarsen"),
                "{:?}",
                decomposition.stopped
            );
            let rebuilt = decomposition.pyramid.reconstruct(1, None).unwrap();
            assert_eq!(rebuilt.indices, soup.indices);
            for (p, q) in rebuilt.positions.iter().zip(&soup.positions) {
                assert!(p.distance(*q) < 1e-12, "{p} against {q}");
            }
            // An explicit depth is still honoured: the user asked for it.
            let deeper = decompose(&mesh, &DecomposeOptions::levels(rule, 3)).unwrap();
            assert_eq!(deeper.pyramid.level_count(), 3);
            // Up to the limit of levels; beyond it an error at once (`u32::MAX` levels
            // overflowed the stack), from the mesh and from its soup.
            let deepest = decompose_soup(&soup, &DecomposeOptions::levels(rule, MAX_LEVELS)).unwrap();
            assert_eq!(deepest.pyramid.level_count(), MAX_LEVELS as usize);
            for levels in [MAX_LEVELS + 1, u32::MAX] {
                let options = DecomposeOptions::levels(rule, levels);
                for error in [decompose(&mesh, &options).unwrap_err(), decompose_soup(&soup, &options).unwrap_err()] {
                    let DooError::InvalidParameter { name: "levels", value, reason } = error else {
                        panic!("{levels} levels: {error}");
                    };
                    assert_eq!(value, levels as f64);
                    assert!(reason.contains(&format!("at most {MAX_LEVELS} levels")), "{reason}");
                }
            }
        }
        // A real refinement still decomposes all the way.
        let cube = HalfedgeMesh::from_soup(&shapes::cube()).unwrap();
        let fine = subdivide(&cube, &DooOptions::new(FaceRule::DooSabin, 2)).unwrap().to_mesh().unwrap();
        let decomposition = decompose(&fine, &DecomposeOptions::max(FaceRule::DooSabin)).unwrap();
        assert_eq!(decomposition.pyramid.level_count(), 2);
    }

    #[test]
    fn a_non_finite_detail_is_named() {
        let mut pyramid = cube_pyramid();
        pyramid.levels[1].details[7].y = f64::NAN;
        pyramid.levels[1].details[9].x = f64::INFINITY;
        // Level 1 does not use the bad details.
        assert!(pyramid.reconstruct(1, None).is_ok());
        match pyramid.reconstruct(2, None) {
            Err(DooError::InvalidPyramid(message)) => {
                assert!(message.starts_with("level 2: detail vertex 7:"), "{message}");
            }
            other => panic!("expected an error, got {other:?}"),
        }
        // The same when the bad detail is kept by the compression.
        assert!(matches!(pyramid.reconstruct(2, Some(1.0)), Err(DooError::InvalidPyramid(_))));
    }

    #[test]
    fn a_prepared_pyramid_reconstructs_the_same_and_checks_the_same() {
        let pyramid = cube_pyramid();
        let prepared = pyramid.prepare().unwrap();
        for level in 0..=2 {
            for keep in [None, Some(0.0), Some(0.3), Some(1.0)] {
                assert_eq!(prepared.reconstruct(level, keep).unwrap(), pyramid.reconstruct(level, keep).unwrap());
            }
        }
        for (level, keep) in [(3, None), (1, Some(1.5)), (1, Some(f64::NAN))] {
            let plain = pyramid.reconstruct(level, keep).unwrap_err().to_string();
            assert_eq!(prepared.reconstruct(level, keep).unwrap_err().to_string(), plain);
        }
        let mut broken = pyramid.clone();
        broken.levels[1].details.pop();
        let plain = broken.reconstruct(2, None).unwrap_err().to_string();
        assert!(plain.contains("level 2: "), "{plain}");
        assert_eq!(broken.prepare().unwrap().reconstruct(2, None).unwrap_err().to_string(), plain);
    }

    #[test]
    fn a_non_finite_base_vertex_is_named() {
        let mut pyramid = cube_pyramid();
        pyramid.base.positions[5].x = f64::NEG_INFINITY;
        for level in 0..=2 {
            assert!(matches!(pyramid.reconstruct(level, None), Err(DooError::NonFinite { vertex: 5, .. })));
        }
        assert!(matches!(pyramid.prepare(), Err(DooError::NonFinite { vertex: 5, .. })));
    }

    #[test]
    fn overflowing_finite_details_are_not_an_error() {
        // Finite details whose sum overflows: the inputs are valid, the result is what
        // the arithmetic gives (no detail to name). (Rebuilt at unit scale, a single
        // detail of `f64::MAX` beside a base vertex there fits: every detail is.)
        let mut pyramid = cube_pyramid();
        pyramid.base.positions[0] = DVec3::splat(f64::MAX);
        pyramid.levels[0].details.fill(DVec3::splat(f64::MAX));
        let rebuilt = pyramid.reconstruct(2, None).unwrap();
        assert!(rebuilt.positions.iter().any(|p| !p.is_finite()));
    }

    /// Finite coordinates so large that the inverse rules' sums overflow are
    /// [`DooError::ReversalOverflow`] on every path (canonical and renumbered meshes, both
    /// boundary rules, `reverse`, `decompose`, `decompose_soup`); they were returned as
    /// infinite and NaN coarse positions. Up to 1e300 the reversal is the scaled one.
    #[test]
    fn overflowing_reversals_are_errors() {
        use mesh_topo::shapes::CellKind;
        let scaled = |soup: &PolygonSoup, largest: f64| {
            let unit = soup.positions.iter().map(|p| p.abs().max_element()).fold(0.0, f64::max);
            let positions = soup.positions.iter().enumerate();
            // Moved a little (non-zero details), then scaled.
            let positions = positions.map(|(i, p)| *p * (1.0 - 1e-3 * (i % 7) as f64) / unit * largest).collect();
            PolygonSoup { positions, ..soup.clone() }
        };
        let mut overflows = 0;
        for boundary in [BoundaryRule::Shrink, BoundaryRule::Chaikin] {
            for coarse in [shapes::icosahedron(), shapes::grid(3, 3, CellKind::Quads).unwrap()] {
                let forward = DooOptions::new(FaceRule::DooSabin, 1).with_boundary(boundary);
                let canonical = subdivide(&HalfedgeMesh::from_soup(&coarse).unwrap(), &forward).unwrap().to_soup();
                let options = DecomposeOptions::levels(FaceRule::DooSabin, 1).with_boundary(boundary);
                for fine in [canonical.clone(), mesh_topo::testing::scramble(canonical.clone(), 5, 0.0)] {
                    let base = |largest: f64| {
                        decompose_soup(&scaled(&fine, largest), &options).map(|d| d.pyramid.base.positions)
                    };
                    let (unit, large) = (base(1.0).unwrap(), base(1e300).unwrap());
                    assert!(unit.iter().zip(&large).all(|(p, q)| (*q / 1e300).distance(*p) < 1e-12), "{boundary:?}");
                    let huge = scaled(&fine, 1.7e308);
                    let mesh = HalfedgeMesh::from_soup(&huge).unwrap();
                    let reverse_options =
                        crate::ReverseOptions { boundary, ..crate::ReverseOptions::auto(FaceRule::DooSabin) };
                    // Each is an overflow, or (reversed at unit scale, where the inverse
                    // rules' partial sums do not overflow) a result that fits in f64 and
                    // rebuilds the input.
                    let max = DecomposeOptions { depth: Depth::Max, ..options.clone() };
                    let rebuilt = |d: Decomposition| d.pyramid.reconstruct(d.pyramid.level_count(), None);
                    for result in [
                        decompose_soup(&huge, &options).and_then(rebuilt),
                        decompose(&mesh, &options).and_then(rebuilt),
                        decompose(&mesh, &max).and_then(rebuilt),
                        crate::reverse(&mesh, &reverse_options).map(|r| r.reconstruct()),
                    ] {
                        match result {
                            Err(DooError::ReversalOverflow { .. }) => overflows += 1,
                            Ok(rebuilt) => {
                                let error = rebuilt
                                    .positions
                                    .iter()
                                    .zip(&huge.positions)
                                    .map(|(p, q)| (*p / 1.7e308 - *q / 1.7e308).abs().max_element());
                                let error = error.fold(0.0, f64::max);
                                assert!(error < 1e-12, "{boundary:?} {error} {:?}", &rebuilt.positions[..4]);
                                assert_eq!(rebuilt.indices, huge.indices);
                            }
                            Err(error) => panic!("{boundary:?}: {error}"),
                        }
                    }
                }
            }
        }
        assert!(overflows >= 8, "{overflows}");
    }
}

#[cfg(test)]
mod scale_tests {
    use super::*;
    use crate::{DooOptions, ReverseOptions, reverse, subdivide};
    use mesh_topo::shapes::{self, CellKind};

    fn scaled_mesh(mesh: &HalfedgeMesh, factor: f64) -> HalfedgeMesh {
        let mut scaled = mesh.clone();
        scaled.positions_mut().iter_mut().for_each(|p| *p *= factor);
        scaled
    }

    fn bits(values: &[DVec3]) -> Vec<[u64; 3]> {
        values.iter().map(|p| p.to_array().map(f64::to_bits)).collect()
    }

    /// Reversing a mesh scaled by a power of two far from 1 gives the reversal of the
    /// unscaled mesh scaled by it, bit for bit, the same readings chosen: the ranking of
    /// the readings squared details of 2^900 into infinities (and of 2^-600 into zeros),
    /// so that every reading looked alike and the first one tried was kept. Likewise the
    /// reconstructions (all details, or the largest kept) and the rate-distortion rows.
    #[test]
    fn reversals_commute_with_powers_of_two() {
        let mut ranking_mattered = 0;
        let cases = [
            (shapes::cube(), BoundaryRule::Shrink),
            (shapes::icosahedron(), BoundaryRule::Shrink),
            (shapes::grid(3, 3, CellKind::Quads).unwrap(), BoundaryRule::Shrink),
            (shapes::grid(3, 3, CellKind::Quads).unwrap(), BoundaryRule::Chaikin),
        ];
        for (coarse, boundary) in cases {
            let coarse = HalfedgeMesh::from_soup(&coarse).unwrap();
            let forward = DooOptions::new(FaceRule::DooSabin, 2).with_boundary(boundary);
            let mut soup = subdivide(&coarse, &forward).unwrap().to_soup();
            // The last face (an F_V face) first, so that the first reading tried (face 0
            // as F_F) is not the best; every vertex moved a little.
            let faces = soup.face_count();
            let order: Vec<usize> = std::iter::once(faces - 1).chain(0..faces - 1).collect();
            soup = PolygonSoup::from_faces(soup.positions.clone(), order.iter().map(|&f| soup.face(f).to_vec()));
            for (i, p) in soup.positions.iter_mut().enumerate() {
                let t = i as f64;
                *p += 1e-2 * DVec3::new((1.3 * t).sin(), (2.1 * t).cos(), (0.7 * t).sin());
            }
            let fine = HalfedgeMesh::from_soup(&soup).unwrap();
            let options = ReverseOptions { boundary, ..ReverseOptions::auto(FaceRule::DooSabin) };
            let levels = DecomposeOptions::max(FaceRule::DooSabin).with_boundary(boundary);
            let unit = reverse(&fine, &options).unwrap();
            let unit_pyramid = decompose(&fine, &levels).unwrap().pyramid;
            let choice = &unit.choices()[0];
            assert!(choice.detail_norm > 0.0 && choice.detail_norm == choice.detail_energy.sqrt());
            if choice.trials.first().is_some_and(|first| first.seed_face != choice.seed_face) {
                ranking_mattered += 1;
            }
            for exponent in [-900, -600, 600, 900] {
                let factor = 2f64.powi(exponent);
                let mesh = scaled_mesh(&fine, factor);
                let scale = |values: &[DVec3]| values.iter().map(|p| *p * factor).collect::<Vec<_>>();
                let reversal = reverse(&mesh, &options).unwrap();
                let seeds = |r: &crate::DooReversal| r.choices().iter().map(|c| c.seed_face).collect::<Vec<_>>();
                assert_eq!(seeds(&reversal), seeds(&unit), "{boundary:?} 2^{exponent}");
                // The detail norm is the unit one scaled (its energy overflows at 2^900
                // and underflows at 2^-600).
                let norms = |r: &crate::DooReversal| r.choices().iter().map(|c| c.detail_norm).collect::<Vec<_>>();
                let unit_norms: Vec<f64> = norms(&unit).iter().map(|n| n * factor).collect();
                assert_eq!(norms(&reversal), unit_norms);
                assert_eq!(bits(reversal.coarse_positions()), bits(&scale(unit.coarse_positions())));
                assert_eq!(bits(reversal.details()), bits(&scale(unit.details())));
                assert_eq!(
                    reversal.coarse(),
                    PolygonSoup { positions: scale(&unit.coarse().positions), ..unit.coarse() }
                );
                let pyramid = decompose(&mesh, &levels).unwrap().pyramid;
                assert_eq!(pyramid.levels.len(), unit_pyramid.levels.len());
                assert_eq!(bits(&pyramid.base.positions), bits(&scale(&unit_pyramid.base.positions)));
                for (level, unit_level) in pyramid.levels.iter().zip(&unit_pyramid.levels) {
                    assert_eq!(bits(&level.details), bits(&scale(&unit_level.details)));
                    assert_eq!(level.order, unit_level.order);
                }
                let soup = decompose_soup(&mesh.to_soup(), &levels).unwrap().pyramid;
                assert_eq!(soup, pyramid);
                // Rebuilt at unit scale too: the same details kept, the same errors.
                let rebuilt = reversal.reconstruct().positions;
                assert_eq!(bits(&rebuilt), bits(&scale(&unit.reconstruct().positions)));
                let finest = pyramid.level_count();
                for keep in [None, Some(0.3)] {
                    let rebuilt = pyramid.reconstruct(finest, keep).unwrap().positions;
                    assert_eq!(
                        bits(&rebuilt),
                        bits(&scale(&unit_pyramid.reconstruct(finest, keep).unwrap().positions))
                    );
                    let prepared = pyramid.prepare().unwrap().reconstruct(finest, keep).unwrap().positions;
                    assert_eq!(bits(&prepared), bits(&rebuilt));
                }
                let fractions = [0.0, 0.3, 1.0];
                assert_eq!(
                    pyramid.rate_distortion(&fractions).unwrap(),
                    unit_pyramid.rate_distortion(&fractions).unwrap()
                );
            }
        }
        assert!(ranking_mattered >= 2, "the meshes exercise the ranking: {ranking_mattered}");
    }

    /// A NaN among coordinates far from 1 is named as at unit scale.
    #[test]
    fn a_nan_among_large_coordinates_is_named() {
        let cube = HalfedgeMesh::from_soup(&shapes::cube()).unwrap();
        let fine = subdivide(&cube, &DooOptions::new(FaceRule::DooSabin, 1)).unwrap().to_mesh().unwrap();
        let options = DecomposeOptions::levels(FaceRule::DooSabin, 1);
        let errors = |factor: f64| {
            let mut mesh = scaled_mesh(&fine, factor);
            mesh.positions_mut()[3].y = f64::NAN;
            let soup = mesh.to_soup();
            let errors = [
                reverse(&mesh, &ReverseOptions::default()).map(drop),
                decompose(&mesh, &options).map(drop),
                decompose_soup(&soup, &options).map(drop),
            ];
            errors.map(|e| e.unwrap_err().to_string().contains("vertex 3"))
        };
        for factor in [1.0, 2f64.powi(900), 2f64.powi(-900)] {
            assert_eq!(errors(factor), [true; 3], "{factor:e}");
        }
    }
}
