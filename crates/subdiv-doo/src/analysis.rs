//! The local subdivision matrix around an `n`-gon, its spectrum, and Reif's C1 check.
//!
//! After one Doo-Sabin step every vertex has valence 4; the extraordinary elements are
//! the faces with `n != 4` sides. Around such a face the invariant neighbourhood has `4n`
//! control points (specification §4.5): the `n` corners `p_i` of the face, the two outer
//! corners `q_{i,0}`, `q_{i,1}` of the quad on each edge `(p_i, p_{i+1})`, and the outer
//! corner `r_i` of the quad at each corner `p_i`. One step maps these `4n` points to the
//! `4n` points of the same configuration one level finer: the local matrix `S` (rows sum
//! to 1). Its eigenvalues decide smoothness (Reif 1995; specification §1.3):
//!
//! 1. `λ_0 = 1` simple;
//! 2. `λ_1 = λ_2 = λ` real with `0 < λ < 1`, geometric multiplicity 2, and `|λ_3| < λ`;
//! 3. the characteristic map (the limit surface of the planar net given by the two
//!    eigenvectors of `λ`) is regular and injective.
//!
//! In the order `(p, q, r)` the matrix is block lower triangular: new face corners depend
//! only on the face, new edge-quad corners on the face and the edge quads. Its spectrum is
//! therefore the union of the spectra of the three diagonal blocks, which are symmetric
//! (a circulant, 2x2 blocks `[[w1, w2], [w2, w1]]` of the quad weights, and `w2 I`); they
//! are computed with nalgebra's symmetric eigensolver, and the triangular structure is
//! checked first (a general matrix would go to nalgebra's real Schur form, with an
//! iteration limit: its QR iteration does not always converge on these highly repeated
//! spectra). The eigenspace of `λ_1` comes from an SVD of `S - λ_1 I`.
//!
//! [`reif_check`] tests 1 and 2 on this spectrum (tolerances `1e-9` for equal
//! eigenvalues, `1e-6` for the gap, `1e-8` relative for the rank) and approximates 3 by subdividing the characteristic net five times with the
//! same rule and checking that every face keeps one orientation (signed areas of one
//! sign, none near zero) and that the boundary of the net winds once around the centre.
//!
//! Reference spectra (specification §4.5): Doo-Sabin `1, 1/2, 1/2, 1/4, ...` for every
//! `n`; the simple variant has subdominant `1/2 + cos(2π/n)/4`; the centroid contraction
//! with `a = 1/2` has `1/2` with multiplicity `n - 1`, so it fails condition 2 for
//! `n >= 4`.

use glam::DVec3;
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

use crate::DooError;
use crate::forward::{DooOptions, subdivide_soup};
use crate::rule::FaceRule;
use mesh_topo::PolygonSoup;

/// Index of `p_i` in the local numbering.
fn p(n: usize, i: usize) -> usize {
    i % n
}
/// Index of `q_{i,side}`.
fn q(n: usize, i: usize, side: usize) -> usize {
    n + 2 * (i % n) + side
}
/// Index of `r_i`.
fn r(n: usize, i: usize) -> usize {
    3 * n + i % n
}

/// Faces of the local `4n`-point net: the `n`-gon, then the edge quads, then the corner
/// quads, counter-clockwise.
fn local_faces(n: usize) -> Vec<Vec<u32>> {
    let mut faces = vec![(0..n).map(|i| p(n, i) as u32).collect::<Vec<_>>()];
    for i in 0..n {
        faces.push([p(n, i + 1), p(n, i), q(n, i, 0), q(n, i, 1)].map(|x| x as u32).to_vec());
    }
    for i in 0..n {
        faces.push([p(n, i), q(n, i + n - 1, 1), r(n, i), q(n, i, 0)].map(|x| x as u32).to_vec());
    }
    faces
}

fn check_valence(n: usize) -> Result<(), DooError> {
    if !(3..=64).contains(&n) {
        return Err(DooError::InvalidParameter {
            name: "valence",
            value: n as f64,
            reason: "the face size of the local analysis must be between 3 and 64",
        });
    }
    Ok(())
}

/// The `4n x 4n` local subdivision matrix around an `n`-gon (numbering: `p_i` at `i`,
/// `q_{i,0}`, `q_{i,1}` at `n + 2i`, `n + 2i + 1`, `r_i` at `3n + i`).
///
/// ```
/// use subdiv_doo::FaceRule;
/// use subdiv_doo::analysis::local_matrix;
/// let s = local_matrix(FaceRule::DooSabin, 5)?;
/// assert_eq!(s.nrows(), 20);
/// for row in s.row_iter() {
///     assert!((row.sum() - 1.0).abs() < 1e-14);
/// }
/// # Ok::<(), subdiv_doo::DooError>(())
/// ```
///
/// # Errors
/// [`DooError::InvalidParameter`] if `n` is not in `3..=64` or the rule's parameter is
/// out of range.
pub fn local_matrix(rule: FaceRule, n: usize) -> Result<DMatrix<f64>, DooError> {
    rule.validate()?;
    check_valence(n)?;
    let mut s = DMatrix::zeros(4 * n, 4 * n);
    let w = rule.weights(n);
    let quad = rule.weights(4);
    let (w0, w1, w2) = (quad[0], quad[1], quad[2]);
    for i in 0..n {
        for k in 0..n {
            s[(p(n, i), p(n, k))] = w[(k + n - i) % n];
        }
        // Corner p_i of the edge quad (p_{i+1}, p_i, q_{i,0}, q_{i,1}).
        let row = q(n, i, 0);
        s[(row, p(n, i))] += w0;
        s[(row, p(n, i + 1))] += w1;
        s[(row, q(n, i, 0))] += w1;
        s[(row, q(n, i, 1))] += w2;
        // Its corner p_{i+1}.
        let row = q(n, i, 1);
        s[(row, p(n, i + 1))] += w0;
        s[(row, p(n, i))] += w1;
        s[(row, q(n, i, 1))] += w1;
        s[(row, q(n, i, 0))] += w2;
        // Corner p_i of the corner quad (p_i, q_{i-1,1}, r_i, q_{i,0}).
        let row = r(n, i);
        s[(row, p(n, i))] += w0;
        s[(row, q(n, i + n - 1, 1))] += w1;
        s[(row, q(n, i, 0))] += w1;
        s[(row, r(n, i))] += w2;
    }
    Ok(s)
}

/// Result of the characteristic-map check.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CharacteristicMap {
    /// Steps of subdivision applied to the characteristic net.
    pub steps: u32,
    /// Faces checked.
    pub faces: usize,
    /// Smallest signed face area divided by the largest, after orienting the net so that
    /// the total is positive (must be positive for a regular map).
    pub min_area_ratio: f64,
    /// Winding number of the net's boundary around the centre (must be 1 in absolute value).
    pub winding: i64,
    /// True if the map looks regular and injective.
    pub ok: bool,
}

/// Spectrum of the local matrix and Reif's conditions.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReifReport {
    /// The rule.
    pub rule: FaceRule,
    /// The face size `n`.
    pub valence: usize,
    /// All `4n` eigenvalues (real parts), sorted by decreasing modulus.
    pub eigenvalues: Vec<f64>,
    /// Largest imaginary part among them (0 for the rules of this crate).
    pub max_imaginary: f64,
    /// The subdominant eigenvalue `λ_1`.
    pub subdominant: f64,
    /// How many eigenvalues equal `λ_1` (within `1e-9`).
    pub subdominant_multiplicity: usize,
    /// Dimension of the eigenspace of `λ_1`.
    pub geometric_multiplicity: usize,
    /// `λ_1 - |λ_k|` for the first eigenvalue `λ_k` not equal to `λ_1`.
    pub gap: f64,
    /// Condition 1: `λ_0 = 1` is simple.
    pub dominant_simple: bool,
    /// Condition 2: `λ_1 = λ_2` real in `(0, 1)`, geometric multiplicity 2, `|λ_3| < λ_1`.
    pub subdominant_ok: bool,
    /// Condition 3, when conditions 1 and 2 hold (the eigenvectors are then defined).
    pub characteristic_map: Option<CharacteristicMap>,
    /// All three conditions hold.
    pub c1: bool,
    /// What failed, in words.
    pub notes: Vec<String>,
}

/// Spectrum and Reif check of the local matrix around an `n`-gon.
///
/// ```
/// use subdiv_doo::FaceRule;
/// use subdiv_doo::analysis::reif_check;
/// let doo = reif_check(FaceRule::DooSabin, 6)?;
/// assert!(doo.c1 && (doo.subdominant - 0.5).abs() < 1e-12);
/// let centroid = reif_check(FaceRule::CENTROID_HALF, 5)?;
/// assert!(!centroid.c1);
/// assert_eq!(centroid.subdominant_multiplicity, 4);
/// # Ok::<(), subdiv_doo::DooError>(())
/// ```
///
/// # Errors
/// As [`local_matrix`].
pub fn reif_check(rule: FaceRule, n: usize) -> Result<ReifReport, DooError> {
    let s = local_matrix(rule, n)?;
    let dim = s.nrows();
    let mut values = spectrum(&s, &[0, n, 3 * n, dim]).ok_or(DooError::InvalidParameter {
        name: "valence",
        value: n as f64,
        reason: "the eigenvalue iteration did not converge",
    })?;
    values.sort_by(|a, b| {
        let (ma, mb) = (a.0.hypot(a.1), b.0.hypot(b.1));
        mb.total_cmp(&ma).then(b.0.total_cmp(&a.0))
    });
    let max_imaginary = values.iter().map(|v| v.1.abs()).fold(0.0, f64::max);
    let eigenvalues: Vec<f64> = values.iter().map(|v| v.0).collect();
    let mut notes = Vec::new();

    let dominant_simple = (values[0].0 - 1.0).abs() < 1e-9 && values[0].1.abs() < 1e-9 && {
        let second = values[1].0.hypot(values[1].1);
        1.0 - second > 1e-6
    };
    if !dominant_simple {
        notes.push("the eigenvalue 1 is not simple and dominant".into());
    }
    let subdominant = values[1].0;
    let subdominant_multiplicity =
        1 + values[2..].iter().take_while(|v| (v.0 - subdominant).abs() < 1e-9 && v.1.abs() < 1e-9).count();
    let next = values.get(1 + subdominant_multiplicity).map_or(0.0, |v| v.0.hypot(v.1));
    let gap = subdominant - next;
    let shifted = &s - DMatrix::identity(dim, dim) * subdominant;
    let svd =
        nalgebra::SVD::try_new(shifted, false, true, f64::EPSILON, 100_000).ok_or(DooError::InvalidParameter {
            name: "valence",
            value: n as f64,
            reason: "the singular value iteration did not converge",
        })?;
    let largest = svd.singular_values.max().max(1.0);
    let geometric_multiplicity = svd.singular_values.iter().filter(|&&x| x < 1e-8 * largest).count();
    let real = values[1].1.abs() < 1e-9;
    let subdominant_ok = real
        && subdominant > 0.0
        && subdominant < 1.0
        && subdominant_multiplicity == 2
        && geometric_multiplicity == 2
        && gap > 1e-6;
    if !subdominant_ok {
        if subdominant_multiplicity != 2 {
            notes.push(format!(
                "the subdominant eigenvalue {subdominant} has multiplicity {subdominant_multiplicity}, not 2"
            ));
        } else if geometric_multiplicity != 2 {
            notes.push(format!("the eigenspace of {subdominant} has dimension {geometric_multiplicity}, not 2"));
        } else {
            notes.push(format!("subdominant eigenvalue {subdominant}: not real in (0, 1) with a gap to the next"));
        }
    }

    let characteristic_map = if dominant_simple && subdominant_ok {
        let v_t = svd.v_t.expect("internal: V was requested");
        // The right singular vectors of the two smallest singular values span the eigenspace.
        let mut order: Vec<usize> = (0..dim).collect();
        order.sort_by(|&a, &b| svd.singular_values[a].total_cmp(&svd.singular_values[b]));
        let (x, y) = (v_t.row(order[0]), v_t.row(order[1]));
        let positions: Vec<DVec3> = (0..dim).map(|k| DVec3::new(x[k], y[k], 0.0)).collect();
        let map = check_characteristic_map(rule, n, positions)?;
        if !map.ok {
            notes.push(format!(
                "the characteristic map is not regular and injective (area ratio {:.3e}, winding {})",
                map.min_area_ratio, map.winding
            ));
        }
        Some(map)
    } else {
        None
    };
    let c1 = dominant_simple && subdominant_ok && characteristic_map.is_some_and(|m| m.ok);
    Ok(ReifReport {
        rule,
        valence: n,
        eigenvalues,
        max_imaginary,
        subdominant,
        subdominant_multiplicity,
        geometric_multiplicity,
        gap,
        dominant_simple,
        subdominant_ok,
        characteristic_map,
        c1,
        notes,
    })
}

/// Eigenvalues `(re, im)` of `s`, by diagonal blocks if `s` is block lower triangular
/// with the given block boundaries, symmetric blocks by the symmetric eigensolver.
fn spectrum(s: &DMatrix<f64>, bounds: &[usize]) -> Option<Vec<(f64, f64)>> {
    let dim = s.nrows();
    let lower_triangular = bounds.windows(2).all(|w| (w[0]..w[1]).all(|i| (w[1]..dim).all(|j| s[(i, j)] == 0.0)));
    let blocks: Vec<(usize, usize)> =
        if lower_triangular { bounds.windows(2).map(|w| (w[0], w[1] - w[0])).collect() } else { vec![(0, dim)] };
    let mut values = Vec::with_capacity(dim);
    for (start, len) in blocks {
        let block = s.view((start, start), (len, len)).into_owned();
        if block == block.transpose() {
            let eigen = nalgebra::SymmetricEigen::try_new(block, f64::EPSILON, 100_000)?;
            values.extend(eigen.eigenvalues.iter().map(|&x| (x, 0.0)));
        } else {
            let schur = nalgebra::Schur::try_new(block, f64::EPSILON, 100_000)?;
            values.extend(schur.complex_eigenvalues().iter().map(|z| (z.re, z.im)));
        }
    }
    Some(values)
}

/// Subdivides the planar characteristic net and checks orientation and winding.
fn check_characteristic_map(rule: FaceRule, n: usize, positions: Vec<DVec3>) -> Result<CharacteristicMap, DooError> {
    const STEPS: u32 = 5;
    let net = PolygonSoup::from_faces(positions, local_faces(n));
    let fine = subdivide_soup(&net, &DooOptions::new(rule, STEPS))?;
    let points = fine.positions();
    let areas: Vec<f64> = fine
        .faces()
        .map(|face| {
            let mut a = 0.0;
            for k in 0..face.len() {
                let (u, v) = (points[face[k] as usize], points[face[(k + 1) % face.len()] as usize]);
                a += u.x * v.y - u.y * v.x;
            }
            a / 2.0
        })
        .collect();
    let sign = if areas.iter().sum::<f64>() >= 0.0 { 1.0 } else { -1.0 };
    let largest = areas.iter().map(|a| a.abs()).fold(0.0, f64::max).max(f64::MIN_POSITIVE);
    let min_area_ratio = areas.iter().map(|a| sign * a).fold(f64::INFINITY, f64::min) / largest;
    // Winding of the boundary loop around the origin (the centre of the net).
    let mesh = fine.to_mesh()?;
    let loops = mesh.boundary_loops();
    let winding = if loops.len() == 1 {
        let mut angle = 0.0;
        for &h in &loops[0] {
            let (a, b) = (mesh.position(mesh.origin(h)), mesh.position(mesh.target(h)));
            angle += (a.x * b.y - a.y * b.x).atan2(a.x * b.x + a.y * b.y);
        }
        (angle / std::f64::consts::TAU).round() as i64
    } else {
        0
    };
    let ok = min_area_ratio > 1e-6 && winding.abs() == 1;
    Ok(CharacteristicMap { steps: STEPS, faces: areas.len(), min_area_ratio, winding, ok })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn doo_sabin_spectrum_is_one_half_half_quarter() {
        for n in 3..=12 {
            let report = reif_check(FaceRule::DooSabin, n).unwrap();
            let e = &report.eigenvalues;
            assert!((e[0] - 1.0).abs() < 1e-12);
            assert!((e[1] - 0.5).abs() < 1e-12 && (e[2] - 0.5).abs() < 1e-12, "n={n}: {e:?}");
            assert!((e[3] - 0.25).abs() < 1e-9 && (e[4] - 0.25).abs() < 1e-9, "n={n}: {e:?}");
            assert!(report.max_imaginary < 1e-9);
            assert!(report.c1, "n={n}: {:?}", report.notes);
            assert!(report.characteristic_map.unwrap().ok);
        }
        // n = 3: 1, .5, .5, .25, .25, .25, .125, .125 (specification §4.5).
        let e = reif_check(FaceRule::DooSabin, 3).unwrap().eigenvalues;
        let expected = [1.0, 0.5, 0.5, 0.25, 0.25, 0.25, 0.125, 0.125];
        for (a, b) in e.iter().zip(expected) {
            assert!((a - b).abs() < 1e-9, "{e:?}");
        }
    }

    #[test]
    fn simple_variant_subdominant() {
        for (n, expected) in [(3, 0.375), (5, 0.5773), (6, 0.625), (8, 0.6768)] {
            let report = reif_check(FaceRule::Simple, n).unwrap();
            assert!((report.subdominant - expected).abs() < 1e-4, "n={n}: {}", report.subdominant);
            let exact = 0.5 + (std::f64::consts::TAU / n as f64).cos() / 4.0;
            assert!((report.subdominant - exact).abs() < 1e-12);
            assert!(report.c1, "n={n}: {:?}", report.notes);
        }
    }

    #[test]
    fn centroid_contraction_fails_for_four_or_more_sides() {
        for n in [4, 5, 6, 8] {
            let report = reif_check(FaceRule::CENTROID_HALF, n).unwrap();
            assert!((report.subdominant - 0.5).abs() < 1e-12);
            assert_eq!(report.subdominant_multiplicity, n - 1, "n={n}: {:?}", report.eigenvalues);
            assert!(!report.subdominant_ok && !report.c1);
        }
        // Triangles: the contraction with a = 1/2 is Doo-Sabin.
        assert!(reif_check(FaceRule::CENTROID_HALF, 3).unwrap().c1);
    }

    #[test]
    fn block_spectrum_equals_the_characteristic_polynomial() {
        // Every eigenvalue found makes S - λI singular, with the multiplicity found.
        for rule in [FaceRule::DooSabin, FaceRule::Simple, FaceRule::CENTROID_HALF] {
            for n in [3, 5, 7] {
                let s = local_matrix(rule, n).unwrap();
                let report = reif_check(rule, n).unwrap();
                let mut distinct: Vec<f64> = report.eigenvalues.clone();
                distinct.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
                let mut total = 0;
                for &l in &distinct {
                    let shifted = &s - DMatrix::identity(4 * n, 4 * n) * l;
                    let svd = shifted.svd(false, false);
                    let null = svd.singular_values.iter().filter(|&&x| x < 1e-9).count();
                    let algebraic = report.eigenvalues.iter().filter(|&&x| (x - l).abs() < 1e-9).count();
                    assert!(null >= 1 && null <= algebraic, "{rule:?} n={n} λ={l}");
                    total += algebraic;
                }
                assert_eq!(total, 4 * n);
            }
        }
    }

    #[test]
    fn bad_valence_is_an_error() {
        assert!(local_matrix(FaceRule::DooSabin, 2).is_err());
        assert!(local_matrix(FaceRule::DooSabin, 65).is_err());
    }
}
