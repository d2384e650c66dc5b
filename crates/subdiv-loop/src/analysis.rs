//! Local subdivision matrices around an extraordinary vertex, their spectra and Reif's
//! C1 test, for Loop (both weight variants), ternary and quaternary Loop.
//!
//! # Method
//! A disk of regular triangle sectors around one vertex of valence `N` (every other
//! vertex has valence 6) is subdivided once with the scheme's own code
//! ([`crate::forward`], [`crate::mband`]), its sparse subdivision matrix is built
//! through the same stencils, and the rows of the fine vertices within `r` rings of the
//! centre, written in the columns of the coarse vertices within `r` rings (same
//! labelling, one level finer), form the local subdivision matrix. The neighbourhood is
//! checked to be invariant (no weight outside it). `r = 2` is the neighbourhood that
//! determines the limit surface over the vertex's star for all four schemes; its size is
//! `3N + 1`.
//!
//! Reif's sufficient C1 conditions (specification section 1.3), with eigenvalues sorted
//! by decreasing modulus `|l0| >= |l1| >= ...`:
//! 1. `l0 = 1`, simple;
//! 2. `l1 = l2 = lambda` real, `0 < lambda < 1`, geometric multiplicity 2 (no Jordan
//!    block) and `lambda > |l3|` (tolerances `1e-9` and a gap of `1e-6`; rank of
//!    `A - lambda I` with tolerance `1e-8`);
//! 3. the characteristic map is regular and injective: the two eigenvectors of `lambda`
//!    (extended to four rings through the invariance relation) are used as planar
//!    control points, the net is subdivided several times with the scheme (cut back to
//!    two rings around the centre after every step, which leaves everything within one
//!    ring exact), and on the ring between the level-1 and the level-0 star every fine
//!    triangle must have the same orientation and both boundary curves of the ring must
//!    wind exactly once around the origin.
//!
//! The result is numerical evidence (a check of the control net of the characteristic
//! map after a few steps), not a proof.

use std::collections::BTreeMap;
use std::fmt;
use std::str::FromStr;

use glam::{DVec2, DVec3};
use mesh_topo::{HalfedgeMesh, PolygonSoup};
use nalgebra::{Complex, DMatrix, DVector};
use serde::{Deserialize, Serialize};

use crate::LoopError;
use crate::forward::kernel::Rules;
use crate::forward::topology::Topology;
use crate::forward::{LoopOptions, SubdivisionMatrix, refine, subdivision_matrix};
use crate::mband::{TernaryOptions, ternary_levels, ternary_matrix};

/// The schemes this module analyses.
///
/// ```
/// use mesh_topo::{HalfedgeMesh, shapes};
/// use subdiv_loop::analysis::Scheme;
/// use subdiv_loop::mband::{TernaryOptions, ternary_subdivide};
///
/// for scheme in Scheme::ALL {
///     // The command-line name is the `Display` form, and parses back.
///     assert_eq!(scheme.name().parse::<Scheme>()?, scheme);
///     assert_eq!(scheme.to_string(), scheme.name());
/// }
/// assert!("butterfly".parse::<Scheme>().is_err());
/// // One step of arity M splits every triangle into M^2.
/// assert_eq!(Scheme::ALL.map(Scheme::arity), [2, 2, 3, 4]);
/// let tetrahedron = HalfedgeMesh::from_soup(&shapes::tetrahedron())?;
/// let ternary = ternary_subdivide(&tetrahedron, 1, &TernaryOptions::default())?;
/// assert_eq!(ternary.face_count(), 4 * Scheme::TernaryLoop.arity().pow(2) as usize);
/// # Ok::<(), subdiv_loop::LoopError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Scheme {
    /// Loop with Loop's original vertex weights.
    Loop,
    /// Loop with Warren's weights.
    LoopWarren,
    /// Ternary (1-to-9) Loop.
    TernaryLoop,
    /// Quaternary (1-to-16) Loop (two Loop steps).
    QuaternaryLoop,
}

impl Scheme {
    /// All four schemes.
    pub const ALL: [Scheme; 4] = [Scheme::Loop, Scheme::LoopWarren, Scheme::TernaryLoop, Scheme::QuaternaryLoop];

    /// Refinement factor of one step.
    pub fn arity(self) -> u32 {
        match self {
            Scheme::Loop | Scheme::LoopWarren => 2,
            Scheme::TernaryLoop => 3,
            Scheme::QuaternaryLoop => 4,
        }
    }

    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            Scheme::Loop => "loop",
            Scheme::LoopWarren => "loop-warren",
            Scheme::TernaryLoop => "ternary-loop",
            Scheme::QuaternaryLoop => "quaternary-loop",
        }
    }

    fn loop_options(self) -> LoopOptions {
        match self {
            Scheme::LoopWarren => LoopOptions::warren_weights(),
            _ => LoopOptions::default(),
        }
    }
}

impl fmt::Display for Scheme {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Scheme {
    type Err = LoopError;
    fn from_str(s: &str) -> Result<Self, LoopError> {
        Scheme::ALL.into_iter().find(|scheme| scheme.name() == s).ok_or_else(|| LoopError::InvalidParameter {
            name: "scheme",
            reason: format!("unknown scheme {s:?} (loop, loop-warren, ternary-loop, quaternary-loop)"),
        })
    }
}

/// Options of the analysis.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct AnalysisOptions {
    /// `lambda` of the ternary 1-ring rule (see [`TernaryOptions`]).
    pub lambda: f64,
    /// Run the characteristic-map check (without it, [`Analysis::c1`] is false and only
    /// the eigenvalue conditions are known).
    pub characteristic_map: bool,
    /// Steps of the characteristic-map check (default: 4 for Loop, 3 for ternary, 2 for
    /// quaternary: a resolution of 1/16 to 1/27 of the ring). At most 7 for Loop, 4 for
    /// ternary, 3 for quaternary (a resolution of 1/81 to 1/128): each step multiplies
    /// the work by `M^2`, and one step more takes seconds, two take minutes.
    pub characteristic_steps: Option<u32>,
}

impl Default for AnalysisOptions {
    fn default() -> Self {
        Self { lambda: TernaryOptions::default().lambda, characteristic_map: true, characteristic_steps: None }
    }
}

impl AnalysisOptions {
    /// Eigenvalues and eigenvalue conditions only.
    ///
    /// ```
    /// use subdiv_loop::analysis::{AnalysisOptions, Scheme, analyze};
    ///
    /// let options = AnalysisOptions::spectrum_only();
    /// assert!(!options.characteristic_map);
    /// let a = analyze(Scheme::Loop, 5, &options)?;
    /// // Loop's subdominant eigenvalue 3/8 + cos(2 pi / 5) / 4, but no C1 claim without the map.
    /// let lambda = 0.375 + 0.25 * (std::f64::consts::TAU / 5.0).cos();
    /// assert!((a.subdominant - lambda).abs() < 1e-12);
    /// assert!(a.conditions.all() && a.characteristic_map.is_none() && !a.c1);
    /// # Ok::<(), subdiv_loop::LoopError>(())
    /// ```
    pub fn spectrum_only() -> Self {
        Self { characteristic_map: false, ..Self::default() }
    }
}

/// Lattice label of a disk vertex: sector `sector`, position `a e_s + b e_{s+1}` in
/// units of the level's edge length, written with `a >= 1` (the centre is `(0, 0, 0)`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct VertexLabel {
    /// Ring (graph distance to the centre): `a + b`.
    pub ring: u32,
    /// Sector.
    pub sector: u32,
    /// Steps along the sector's second direction.
    pub b: u32,
}

/// A local subdivision matrix and the labels of its rows and columns.
#[derive(Debug, Clone, PartialEq)]
pub struct LocalMatrix {
    /// The scheme.
    pub scheme: Scheme,
    /// Valence of the centre.
    pub valence: usize,
    /// Number of rings in the neighbourhood.
    pub rings: u32,
    /// Row and column labels (rings first, then sectors).
    pub labels: Vec<VertexLabel>,
    /// The matrix: fine neighbourhood (rows) from coarse neighbourhood (columns).
    pub matrix: DMatrix<f64>,
}

/// Reif's eigenvalue conditions.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct EigenConditions {
    /// `l0 = 1`, simple.
    pub dominant_simple: bool,
    /// `l1 = l2` real in `(0, 1)`.
    pub subdominant_real_double: bool,
    /// Geometric multiplicity of `l1` equals its algebraic multiplicity 2.
    pub no_jordan_block: bool,
    /// `l1 > |l3|`.
    pub gap: bool,
}

impl EigenConditions {
    /// All conditions hold.
    ///
    /// ```
    /// use subdiv_loop::analysis::{AnalysisOptions, Scheme, analyze};
    ///
    /// // Ternary Loop's 1-ring spectrum is 1, lambda, lambda, lambda^2, ... (lambda = 1/3).
    /// let a = analyze(Scheme::TernaryLoop, 3, &AnalysisOptions::spectrum_only())?;
    /// assert!((a.subdominant - 1.0 / 3.0).abs() < 1e-12 && a.next_modulus < a.subdominant);
    /// let c = a.conditions;
    /// assert!(c.dominant_simple && c.subdominant_real_double && c.no_jordan_block && c.gap);
    /// assert!(c.all());
    /// # Ok::<(), subdiv_loop::LoopError>(())
    /// ```
    pub fn all(&self) -> bool {
        self.dominant_simple && self.subdominant_real_double && self.no_jordan_block && self.gap
    }
}

/// The numerical check of the characteristic map.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CharacteristicMap {
    /// Subdivision steps applied to the characteristic net.
    pub steps: u32,
    /// Fine triangles of the ring checked.
    pub triangles: usize,
    /// Of them, with positive / negative signed area (after orientation).
    pub positive: usize,
    /// See `positive`.
    pub negative: usize,
    /// Smallest over largest absolute signed area of the ring's triangles.
    pub area_ratio: f64,
    /// Turns of the inner boundary curve of the ring around the origin.
    pub inner_turns: f64,
    /// Turns of the outer boundary curve.
    pub outer_turns: f64,
}

impl CharacteristicMap {
    /// Every triangle has the same orientation (the map is regular).
    ///
    /// ```
    /// use subdiv_loop::analysis::{AnalysisOptions, Scheme, analyze};
    ///
    /// let a = analyze(Scheme::Loop, 5, &AnalysisOptions::default())?;
    /// let map = a.characteristic_map.expect("checked when the eigenvalue conditions hold");
    /// assert!(map.regular() && map.positive == map.triangles);
    /// // Ternary Loop with lambda = 1/2 passes the eigenvalue tests, but its map folds over.
    /// let options = AnalysisOptions { lambda: 0.5, ..AnalysisOptions::default() };
    /// let a = analyze(Scheme::TernaryLoop, 5, &options)?;
    /// let map = a.characteristic_map.expect("checked when the eigenvalue conditions hold");
    /// assert!(a.conditions.all() && map.negative > 0 && !map.regular() && !a.c1);
    /// # Ok::<(), subdiv_loop::LoopError>(())
    /// ```
    pub fn regular(&self) -> bool {
        self.triangles > 0
            && (self.positive == self.triangles || self.negative == self.triangles)
            && self.area_ratio > 0.0
    }

    /// Both boundary curves wind once (with the regularity, the map is injective).
    ///
    /// ```
    /// use subdiv_loop::analysis::{AnalysisOptions, Scheme, analyze};
    ///
    /// let a = analyze(Scheme::Loop, 3, &AnalysisOptions::default())?;
    /// let map = a.characteristic_map.expect("checked when the eigenvalue conditions hold");
    /// assert!((map.inner_turns.abs() - 1.0).abs() < 1e-6);
    /// assert!((map.outer_turns.abs() - 1.0).abs() < 1e-6);
    /// assert!(map.injective() && map.regular() && a.c1);
    /// // Winding once is not enough: this map winds once but folds (see `regular`).
    /// let options = AnalysisOptions { lambda: 0.5, ..AnalysisOptions::default() };
    /// let folded = analyze(Scheme::TernaryLoop, 5, &options)?;
    /// let folded = folded.characteristic_map.expect("the eigenvalue conditions hold");
    /// assert!(folded.injective() && !folded.regular());
    /// # Ok::<(), subdiv_loop::LoopError>(())
    /// ```
    pub fn injective(&self) -> bool {
        (self.inner_turns.abs() - 1.0).abs() < 1e-6 && (self.outer_turns.abs() - 1.0).abs() < 1e-6
    }
}

/// The spectral analysis of one scheme at one valence.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Analysis {
    /// The scheme.
    pub scheme: Scheme,
    /// Valence of the extraordinary vertex.
    pub valence: usize,
    /// Size of the local matrix (`3N + 1`, the two-ring).
    pub size: usize,
    /// Eigenvalues as `[re, im]`, sorted by decreasing modulus (ties: larger real part,
    /// then larger imaginary part first).
    pub eigenvalues: Vec<[f64; 2]>,
    /// The subdominant eigenvalue `l1` (its real part).
    pub subdominant: f64,
    /// Eigenvalues within `1e-7` of `l1`.
    pub algebraic_multiplicity: usize,
    /// Dimension of the kernel of `A - l1 I`.
    pub geometric_multiplicity: usize,
    /// `|l3|`, the largest modulus after `l1, l2`.
    pub next_modulus: f64,
    /// Reif's eigenvalue conditions.
    pub conditions: EigenConditions,
    /// The characteristic-map check (absent when the eigenvalue conditions fail or the
    /// check was not asked for).
    pub characteristic_map: Option<CharacteristicMap>,
    /// All C1 checks passed.
    pub c1: bool,
}

/// Largest valence analysed (the local matrices have `3N + 1` rows).
pub const MAX_VALENCE: usize = 200;

/// The local subdivision matrix of `scheme` around a vertex of valence `valence`, on
/// the `rings`-ring neighbourhood (`1 <= rings <= 4`).
///
/// ```
/// use subdiv_loop::analysis::{AnalysisOptions, Scheme, local_subdivision_matrix};
///
/// let local = local_subdivision_matrix(Scheme::Loop, 5, 1, &AnalysisOptions::default())?;
/// assert_eq!(local.matrix.nrows(), 6);
/// // Loop's vertex row: alpha_5 = 1 - 5 beta_5 on the centre.
/// let beta = (0.625 - (0.375 + 0.25 * (std::f64::consts::TAU / 5.0).cos()).powi(2)) / 5.0;
/// assert!((local.matrix[(0, 0)] - (1.0 - 5.0 * beta)).abs() < 1e-15);
/// # Ok::<(), subdiv_loop::LoopError>(())
/// ```
///
/// # Errors
/// [`LoopError::InvalidParameter`] for a valence outside `3 ..= 200`, `rings` outside
/// `1 ..= 4` or a bad ternary `lambda`.
pub fn local_subdivision_matrix(
    scheme: Scheme,
    valence: usize,
    rings: u32,
    options: &AnalysisOptions,
) -> Result<LocalMatrix, LoopError> {
    check_valence(valence)?;
    if !(1..=4).contains(&rings) {
        return Err(LoopError::InvalidParameter { name: "rings", reason: format!("{rings}; 1 to 4 rings") });
    }
    let disk = SectorDisk::new(valence, 6);
    let matrix = step_matrix(scheme, &disk.mesh, options)?;
    let fine_layout = layout_step(scheme, &disk.mesh, &disk.layout)?;
    let arity = scheme.arity() as f64;
    let coarse: BTreeMap<VertexLabel, usize> =
        disk.layout.iter().enumerate().filter_map(|(i, &p)| Some((label_of(p, valence, 1.0)?, i))).collect();
    let fine: BTreeMap<VertexLabel, usize> =
        fine_layout.iter().enumerate().filter_map(|(i, &p)| Some((label_of(p, valence, arity)?, i))).collect();
    let labels: Vec<VertexLabel> = coarse.keys().copied().filter(|l| l.ring <= rings).collect();
    let column_of: BTreeMap<usize, usize> = labels.iter().enumerate().map(|(k, l)| (coarse[l], k)).collect();
    let mut local = DMatrix::zeros(labels.len(), labels.len());
    for (row, label) in labels.iter().enumerate() {
        let fine_vertex = *fine.get(label).ok_or_else(|| internal(format!("no fine vertex labelled {label:?}")))?;
        let (columns, weights) = matrix.row(fine_vertex);
        for (&c, &w) in columns.iter().zip(weights) {
            match column_of.get(&(c as usize)) {
                Some(&column) => local[(row, column)] = w,
                None if w.abs() > 1e-13 => {
                    return Err(internal(format!("the {rings}-ring is not invariant (weight {w} outside)")));
                }
                None => {}
            }
        }
    }
    Ok(LocalMatrix { scheme, valence, rings, labels, matrix: local })
}

/// Eigenvalues, subdominant eigenvalue and Reif's C1 checks of `scheme` at a vertex of
/// valence `valence` (see the [module docs](self)).
///
/// ```
/// use subdiv_loop::analysis::{AnalysisOptions, Scheme, analyze};
///
/// let a = analyze(Scheme::Loop, 7, &AnalysisOptions::default())?;
/// let lambda = 0.375 + 0.25 * (std::f64::consts::TAU / 7.0).cos();
/// assert!((a.subdominant - lambda).abs() < 1e-12);
/// assert_eq!(a.geometric_multiplicity, 2);
/// assert!(a.c1);
/// # Ok::<(), subdiv_loop::LoopError>(())
/// ```
///
/// # Errors
/// [`LoopError::InvalidParameter`] for a valence outside `3 ..= 200`, a bad ternary
/// `lambda` or more [`AnalysisOptions::characteristic_steps`] than documented there.
pub fn analyze(scheme: Scheme, valence: usize, options: &AnalysisOptions) -> Result<Analysis, LoopError> {
    check_characteristic_steps(scheme, options)?;
    let n = valence;
    let local = local_subdivision_matrix(scheme, n, 4, options)?;
    let size = 1 + 3 * n;
    let a2 = local.matrix.view((0, 0), (size, size)).into_owned();
    let spectrum = fourier_spectrum(&a2, n)?;
    let mut eigenvalues: Vec<[f64; 2]> = spectrum.iter().map(|e| [e.value.re, e.value.im]).collect();
    eigenvalues.sort_by(|x, y| {
        let (mx, my) = (x[0].hypot(x[1]), y[0].hypot(y[1]));
        // Moduli equal to 1e-12 count as ties.
        if (mx - my).abs() > 1e-12 { my.total_cmp(&mx) } else { y[0].total_cmp(&x[0]).then(y[1].total_cmp(&x[1])) }
    });
    let modulus = |k: usize| eigenvalues.get(k).map_or(0.0, |z| z[0].hypot(z[1]));
    let dominant_simple =
        (eigenvalues[0][0] - 1.0).abs() < 1e-9 && eigenvalues[0][1].abs() < 1e-9 && modulus(1) < 1.0 - 1e-9;
    let lambda = eigenvalues[1][0];
    let subdominant_real_double = eigenvalues[1][1].abs() < 1e-9
        && eigenvalues.get(2).is_some_and(|z| z[1].abs() < 1e-9 && (z[0] - lambda).abs() < 1e-9)
        && lambda > 0.0
        && lambda < 1.0;
    let algebraic_multiplicity =
        eigenvalues.iter().filter(|z| (z[0] - lambda).abs() < 1e-7 && z[1].abs() < 1e-7).count();
    let next_modulus = modulus(3);
    let gap = lambda - next_modulus > 1e-6;
    let svd = (&a2 - DMatrix::identity(size, size) * lambda).svd(false, false);
    let scale = svd.singular_values.max().max(1.0);
    let geometric_multiplicity = svd.singular_values.iter().filter(|&&s| s < 1e-8 * scale).count();
    let conditions = EigenConditions {
        dominant_simple,
        subdominant_real_double,
        no_jordan_block: geometric_multiplicity == 2 && algebraic_multiplicity == 2,
        gap,
    };
    // The characteristic map comes from the Fourier mode of the one-ring block that
    // carries lambda (mode 1 for a well-behaved scheme; mode k would wind k times).
    let mode = spectrum.iter().find(|e| e.ring_one && (e.value.re - lambda).abs() < 1e-9 && e.value.im.abs() < 1e-9);
    let characteristic_map = match mode {
        Some(e) if conditions.all() && options.characteristic_map => {
            Some(characteristic_map(scheme, n, lambda, e.mode, &local, options)?)
        }
        _ => None,
    };
    let c1 = conditions.all() && characteristic_map.is_some_and(|m| m.regular() && m.injective());
    Ok(Analysis {
        scheme,
        valence,
        size,
        eigenvalues,
        subdominant: lambda,
        algebraic_multiplicity,
        geometric_multiplicity,
        next_modulus,
        conditions,
        characteristic_map,
        c1,
    })
}

/// An eigenvalue with the Fourier mode and the block it came from.
#[derive(Debug, Clone, Copy)]
struct ModalEigenvalue {
    value: Complex<f64>,
    mode: usize,
    /// From the one-ring block (else from the second-ring block).
    ring_one: bool,
}

/// The eigenvalues of the two-ring matrix by its structure: it is block lower triangular
/// (the one-ring is invariant) and commutes with the rotation by one sector, so the
/// discrete Fourier transform over sectors splits it into a 2 x 2 block (centre and
/// one-ring, mode 0), scalars (one-ring, modes 1 .. N-1) and 2 x 2 blocks (second ring,
/// every mode), whose eigenvalues are closed-form. (General QR iterations stall on the
/// many repeated eigenvalues of these matrices.)
fn fourier_spectrum(a: &DMatrix<f64>, n: usize) -> Result<Vec<ModalEigenvalue>, LoopError> {
    // Indices: centre 0, one-ring 1 + s, second ring 1 + n + 2 s + b.
    let ring1 = |s: usize| 1 + s % n;
    let ring2 = |s: usize, b: usize| 1 + n + 2 * (s % n) + b;
    let rotate = |i: usize| match i {
        0 => 0,
        i if i <= n => ring1(i),
        i => ring2((i - 1 - n) / 2 + 1, (i - 1 - n) % 2),
    };
    let size = a.nrows();
    for i in 0..size {
        for j in 0..size {
            if (a[(rotate(i), rotate(j))] - a[(i, j)]).abs() > 1e-12 {
                return Err(internal(format!("local matrix not rotation invariant at ({i}, {j})")));
            }
        }
        if i <= n && (n + 1..size).any(|j| a[(i, j)].abs() > 1e-13) {
            return Err(internal("the one-ring is not invariant".into()));
        }
    }
    let omega = |k: usize, s: usize| Complex::from_polar(1.0, std::f64::consts::TAU * ((k * s) % n) as f64 / n as f64);
    let quadratic = |m: [[Complex<f64>; 2]; 2]| {
        let trace = m[0][0] + m[1][1];
        let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
        let root = (trace * trace - det * 4.0).sqrt();
        [(trace + root) / 2.0, (trace - root) / 2.0]
    };
    let mut out = Vec::with_capacity(size);
    let real = |x: f64| Complex::new(x, 0.0);
    let ring_sum: f64 = (0..n).map(|s| a[(0, ring1(s))]).sum();
    let back_sum: f64 = (0..n).map(|s| a[(ring1(0), ring1(s))]).sum();
    for value in quadratic([[real(a[(0, 0)]), real(ring_sum)], [real(a[(ring1(0), 0)]), real(back_sum)]]) {
        out.push(ModalEigenvalue { value, mode: 0, ring_one: true });
    }
    for k in 1..n {
        let value = (0..n).map(|s| omega(k, s) * a[(ring1(0), ring1(s))]).sum();
        out.push(ModalEigenvalue { value, mode: k, ring_one: true });
    }
    for k in 0..n {
        let entry = |b: usize, c: usize| (0..n).map(|s| omega(k, s) * a[(ring2(0, b), ring2(s, c))]).sum();
        for value in quadratic([[entry(0, 0), entry(0, 1)], [entry(1, 0), entry(1, 1)]]) {
            out.push(ModalEigenvalue { value, mode: k, ring_one: false });
        }
    }
    Ok(out)
}

fn check_valence(valence: usize) -> Result<(), LoopError> {
    if (3..=MAX_VALENCE).contains(&valence) {
        Ok(())
    } else {
        Err(LoopError::InvalidParameter {
            name: "valence",
            reason: format!("{valence}; the analysis covers valences 3 to {MAX_VALENCE}"),
        })
    }
}

/// The bound of [`AnalysisOptions::characteristic_steps`]: the steps whose refinement
/// `M^steps` stays within 128 (Loop 7, ternary 4, quaternary 3), well under a second at
/// low valence; a step more costs `M^2` times as much (`u32::MAX` steps would exhaust the
/// memory).
fn check_characteristic_steps(scheme: Scheme, options: &AnalysisOptions) -> Result<(), LoopError> {
    let max = match scheme {
        Scheme::Loop | Scheme::LoopWarren => 7,
        Scheme::TernaryLoop => 4,
        Scheme::QuaternaryLoop => 3,
    };
    match options.characteristic_steps {
        Some(steps) if steps > max => Err(LoopError::InvalidParameter {
            name: "characteristic_steps",
            reason: format!("{steps}: at most {max} for {}", scheme.name()),
        }),
        _ => Ok(()),
    }
}

fn internal(reason: String) -> LoopError {
    LoopError::InvalidParameter { name: "analysis", reason: format!("internal: {reason}") }
}

/// A disk of `valence` regular sectors with `rings` rings around vertex 0.
struct SectorDisk {
    mesh: HalfedgeMesh,
    layout: Vec<DVec2>,
}

/// Unit vector of sector side `s` of an `n`-sector disk.
fn side(s: usize, n: usize) -> DVec2 {
    let angle = std::f64::consts::TAU * (s % n) as f64 / n as f64;
    DVec2::new(angle.cos(), angle.sin())
}

impl SectorDisk {
    fn new(n: usize, rings: usize) -> Self {
        // Vertex (s, a, b), a >= 1, ring r = a + b: index 1 + n r (r - 1) / 2 + s r + b.
        let index = |s: usize, a: usize, b: usize| -> u32 {
            if a == 0 && b == 0 {
                return 0;
            }
            let (s, a, b) = if a == 0 { ((s + 1) % n, b, 0) } else { (s % n, a, b) };
            let r = a + b;
            (1 + n * r * (r - 1) / 2 + s * r + b) as u32
        };
        let count = 1 + n * rings * (rings + 1) / 2;
        let mut layout = vec![DVec2::ZERO; count];
        for r in 1..=rings {
            for s in 0..n {
                for b in 0..r {
                    layout[index(s, r - b, b) as usize] = (r - b) as f64 * side(s, n) + b as f64 * side(s + 1, n);
                }
            }
        }
        let mut faces = Vec::new();
        for s in 0..n {
            for a in 0..rings {
                for b in 0..rings - a {
                    faces.push([index(s, a, b), index(s, a + 1, b), index(s, a, b + 1)]);
                    if a + b + 2 <= rings {
                        faces.push([index(s, a + 1, b), index(s, a + 1, b + 1), index(s, a, b + 1)]);
                    }
                }
            }
        }
        let positions = layout.iter().map(|p| p.extend(0.0)).collect();
        let mesh = HalfedgeMesh::from_soup(&PolygonSoup::from_faces(positions, faces))
            .expect("internal: the sector disk is a valid mesh");
        Self { mesh, layout }
    }
}

/// The label of a layout point, in units of `1 / scale` (`None` if it is not a lattice
/// point of that resolution).
fn label_of(p: DVec2, n: usize, scale: f64) -> Option<VertexLabel> {
    if p.length() * scale < 1e-7 {
        return Some(VertexLabel { ring: 0, sector: 0, b: 0 });
    }
    for s in 0..n {
        let (e0, e1) = (side(s, n), side(s + 1, n));
        let det = e0.perp_dot(e1);
        let (a, b) = (p.perp_dot(e1) / det * scale, e0.perp_dot(p) / det * scale);
        if a < -1e-7 || b < -1e-7 {
            continue;
        }
        let (ra, rb) = (a.round(), b.round());
        if (a - ra).abs() > 1e-6 || (b - rb).abs() > 1e-6 {
            return None;
        }
        let (sector, a, b) = if ra == 0.0 { ((s + 1) % n, rb as u32, 0) } else { (s, ra as u32, rb as u32) };
        return Some(VertexLabel { ring: a + b, sector: sector as u32, b });
    }
    None
}

/// Ring distance of a layout point, in coarse units.
fn ring_of(p: DVec2, n: usize) -> f64 {
    for s in 0..n {
        let (e0, e1) = (side(s, n), side(s + 1, n));
        let det = e0.perp_dot(e1);
        let (a, b) = (p.perp_dot(e1) / det, e0.perp_dot(p) / det);
        if a >= -1e-9 && b >= -1e-9 {
            return a + b;
        }
    }
    0.0
}

/// The matrix of one step of `scheme` on `mesh`.
fn step_matrix(scheme: Scheme, mesh: &HalfedgeMesh, options: &AnalysisOptions) -> Result<SubdivisionMatrix, LoopError> {
    match scheme {
        Scheme::Loop | Scheme::LoopWarren => subdivision_matrix(mesh, 1, &scheme.loop_options()),
        Scheme::QuaternaryLoop => subdivision_matrix(mesh, 2, &scheme.loop_options()),
        Scheme::TernaryLoop => ternary_matrix(mesh, 1, &TernaryOptions { lambda: options.lambda }),
    }
}

/// One step of `scheme` on positions: fine positions and triangles.
fn step_positions(
    scheme: Scheme,
    mesh: &HalfedgeMesh,
    positions: &[DVec3],
    options: &AnalysisOptions,
) -> Result<(Vec<DVec3>, Vec<[u32; 3]>), LoopError> {
    match scheme {
        Scheme::Loop | Scheme::LoopWarren | Scheme::QuaternaryLoop => {
            let levels = if scheme == Scheme::QuaternaryLoop { 2 } else { 1 };
            let (values, topology) =
                refine(Topology::from_mesh(mesh)?, positions, levels, &Rules::new(&scheme.loop_options()));
            Ok((values, topology.triangles))
        }
        Scheme::TernaryLoop => ternary_levels(mesh, positions, 1, &TernaryOptions { lambda: options.lambda }),
    }
}

/// Layout (parameter) positions of the fine vertices: the scheme's vertex order with
/// linear interpolation (midpoints, thirds, centroids), as documented for each scheme.
fn layout_step(scheme: Scheme, mesh: &HalfedgeMesh, layout: &[DVec2]) -> Result<Vec<DVec2>, LoopError> {
    let loop_layout = |mesh: &HalfedgeMesh, layout: &[DVec2]| {
        let mut out = layout.to_vec();
        out.extend(mesh.edges().map(|e| {
            let [a, b] = mesh.edge_vertices(e);
            (layout[a.index()] + layout[b.index()]) / 2.0
        }));
        out
    };
    Ok(match scheme {
        Scheme::Loop | Scheme::LoopWarren => loop_layout(mesh, layout),
        Scheme::QuaternaryLoop => {
            let half = loop_layout(mesh, layout);
            let (_, triangles) =
                step_positions(Scheme::Loop, mesh, &vec![DVec3::ZERO; layout.len()], &AnalysisOptions::default())?;
            let half_mesh =
                HalfedgeMesh::from_soup(&PolygonSoup::from_faces(vec![DVec3::ZERO; half.len()], &triangles))?;
            loop_layout(&half_mesh, &half)
        }
        Scheme::TernaryLoop => {
            let mut out = layout.to_vec();
            for e in mesh.edges() {
                let [a, b] = mesh.edge_vertices(e);
                let (a, b) = (layout[a.index()], layout[b.index()]);
                out.push((2.0 * a + b) / 3.0);
                out.push((a + 2.0 * b) / 3.0);
            }
            for f in mesh.faces() {
                out.push(mesh.face_vertices(f).map(|v| layout[v.index()]).sum::<DVec2>() / 3.0);
            }
            out
        }
    })
}

/// Subdivides the characteristic net of Fourier mode `mode` and checks the ring between
/// the level-1 and the level-0 star.
fn characteristic_map(
    scheme: Scheme,
    n: usize,
    lambda: f64,
    mode: usize,
    local: &LocalMatrix,
    options: &AnalysisOptions,
) -> Result<CharacteristicMap, LoopError> {
    // The eigenvector on the one-ring is (cos, sin)(2 pi mode s / n) (zero at the
    // centre); with A4 = [[A1, 0], [B, C]] its outer part w solves (lambda I - C) w = B v.
    let inner = 1 + n;
    let outer = local.labels.len() - inner;
    let b = local.matrix.view((inner, 0), (outer, inner)).into_owned();
    let c = local.matrix.view((inner, inner), (outer, outer)).into_owned();
    let lu = (DMatrix::identity(outer, outer) * lambda - c).lu();
    let mut coordinates = Vec::new();
    for phase in [0.0, std::f64::consts::FRAC_PI_2] {
        let v = DVector::from_fn(inner, |i, _| {
            if i == 0 { 0.0 } else { (std::f64::consts::TAU * (mode * (i - 1)) as f64 / n as f64 - phase).cos() }
        });
        let w = lu.solve(&(&b * &v)).ok_or_else(|| internal("lambda is an eigenvalue of the outer block".into()))?;
        coordinates.push((v, w));
    }
    let mut net: BTreeMap<VertexLabel, DVec2> = BTreeMap::new();
    for (k, label) in local.labels.iter().enumerate() {
        let coordinate = |i: usize| if k < inner { coordinates[i].0[k] } else { coordinates[i].1[k - inner] };
        net.insert(*label, DVec2::new(coordinate(0), coordinate(1)));
    }
    // The disk with the characteristic net inside four rings (zero outside: those points
    // do not reach the ring checked below).
    let disk = SectorDisk::new(n, 6);
    let mut layout = disk.layout.clone();
    let mut positions: Vec<DVec3> = layout
        .iter()
        .map(|&p| label_of(p, n, 1.0).and_then(|l| net.get(&l)).map_or(DVec3::ZERO, |q| q.extend(0.0)))
        .collect();
    let mut mesh = disk.mesh;
    let steps = options.characteristic_steps.unwrap_or(match scheme {
        Scheme::Loop | Scheme::LoopWarren => 4,
        Scheme::TernaryLoop => 3,
        Scheme::QuaternaryLoop => 2,
    });
    for _ in 0..steps {
        let fine_layout = layout_step(scheme, &mesh, &layout)?;
        let (fine_positions, triangles) = step_positions(scheme, &mesh, &positions, options)?;
        // Keep the faces within two rings of the centre (renumbered).
        let mut index = vec![u32::MAX; fine_layout.len()];
        let (mut kept_layout, mut kept_positions, mut faces) = (Vec::new(), Vec::new(), Vec::new());
        for t in &triangles {
            if t.iter().all(|&v| ring_of(fine_layout[v as usize], n) <= 2.0 + 1e-9) {
                faces.push(t.map(|v| {
                    if index[v as usize] == u32::MAX {
                        index[v as usize] = kept_layout.len() as u32;
                        kept_layout.push(fine_layout[v as usize]);
                        kept_positions.push(fine_positions[v as usize]);
                    }
                    index[v as usize]
                }));
            }
        }
        mesh = HalfedgeMesh::from_soup(&PolygonSoup::from_faces(kept_positions.clone(), faces))?;
        layout = kept_layout;
        positions = kept_positions;
    }
    // The ring between the level-1 star (ring 1/M) and the level-0 star (ring 1).
    let inner_ring = 1.0 / scheme.arity() as f64;
    let rings: Vec<f64> = layout.iter().map(|&p| ring_of(p, n)).collect();
    let in_ring = |v: usize| rings[v] >= inner_ring - 1e-9 && rings[v] <= 1.0 + 1e-9;
    let (mut positive, mut negative, mut triangles) = (0, 0, 0);
    let (mut smallest, mut largest) = (f64::INFINITY, 0.0f64);
    for f in mesh.faces() {
        let corners: Vec<usize> = mesh.face_vertices(f).map(|v| v.index()).collect();
        if !corners.iter().all(|&v| in_ring(v)) {
            continue;
        }
        let [p, q, r] = [0, 1, 2].map(|k| positions[corners[k]].truncate());
        let [lp, lq, lr] = [0, 1, 2].map(|k| layout[corners[k]]);
        let area = (q - p).perp_dot(r - p) * (lq - lp).perp_dot(lr - lp).signum();
        triangles += 1;
        if area > 0.0 {
            positive += 1;
        } else if area < 0.0 {
            negative += 1;
        }
        smallest = smallest.min(area.abs());
        largest = largest.max(area.abs());
    }
    let turns = |ring: f64| {
        let mut curve: Vec<(f64, DVec2)> = (0..layout.len())
            .filter(|&v| (rings[v] - ring).abs() < 1e-9)
            .map(|v| (layout[v].y.atan2(layout[v].x), positions[v].truncate()))
            .collect();
        curve.sort_by(|x, y| x.0.total_cmp(&y.0));
        let mut total = 0.0;
        for k in 0..curve.len() {
            let (p, q) = (curve[k].1, curve[(k + 1) % curve.len()].1);
            total += p.perp_dot(q).atan2(p.dot(q));
        }
        total / std::f64::consts::TAU
    };
    Ok(CharacteristicMap {
        steps,
        triangles,
        positive,
        negative,
        area_ratio: if largest > 0.0 { smallest / largest } else { 0.0 },
        inner_turns: turns(inner_ring),
        outer_turns: turns(1.0),
    })
}

#[cfg(test)]
mod tests;
