//! Tensor-product patch IFS (bilinear, biquadratic, bicubic: four quadrant maps) against
//! the closed-form tensor Bézier surface, in the barycentric form and, for the bilinear
//! patch in space, in the seed's homogeneous 4×4 form `P̂^{-1} S_i P̂`.

use ifs_nonlinear::{AffineIfs, BarycentricIfs, IfsError, deterministic_points, tensor_patch_split};

fn binomial(n: usize, k: usize) -> f64 {
    (0..k).fold(1.0, |acc, i| acc * (n - i) as f64 / (i + 1) as f64)
}

fn bernstein(n: usize, i: usize, t: f64) -> f64 {
    binomial(n, i) * t.powi(i as i32) * (1.0 - t).powi((n - i) as i32)
}

/// The tensor Bézier patch of degrees (n, n) at (u, v); control point (i, j) at i (n + 1) + j.
fn patch(control: &[[f64; 3]], n: usize, u: f64, v: f64) -> [f64; 3] {
    let mut p = [0.0; 3];
    for i in 0..=n {
        for j in 0..=n {
            let w = bernstein(n, i, u) * bernstein(n, j, v);
            for k in 0..3 {
                p[k] += w * control[i * (n + 1) + j][k];
            }
        }
    }
    p
}

/// A fixed, non-planar control net of degree n (a warped grid).
fn control_net(n: usize) -> Vec<[f64; 3]> {
    (0..(n + 1) * (n + 1))
        .map(|index| {
            let (i, j) = ((index / (n + 1)) as f64, (index % (n + 1)) as f64);
            [i + 0.3 * j, j - 0.2 * i * i, (0.7 * i - 0.4 * j).sin() + 0.5 * i * j]
        })
        .collect()
}

/// Parameters (u, v) of the lower corner of the sub-patch of output `word` (base-4 letters
/// v_1 … v_k, v_1 most significant = the first map applied, quadrant q = 2 q_u + q_v): the
/// last letter picks the coarsest half, as for curves.
fn word_corner(word: usize, levels: u32) -> (f64, f64) {
    let (mut u, mut v) = (0.0, 0.0);
    for i in 0..levels {
        let letter = (word >> (2 * i)) & 3;
        let scale = 0.5f64.powi(i as i32 + 1);
        u += (letter >> 1) as f64 * scale;
        v += (letter & 1) as f64 * scale;
    }
    (u, v)
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// Row 0 of `S_{v_1} ⋯ S_{v_k} P` (start = the corner control point) is exactly the patch
/// point at the dyadic corner of the sub-patch; the centroid of each sub-net converges to
/// the surface with ratio 1/4 per level (second order).
#[test]
fn patch_attractors_lie_on_the_tensor_bezier_surface() {
    for n in 1..=3 {
        let control = control_net(n);
        let m = control.len();
        let ifs = BarycentricIfs::new(&tensor_patch_split(n, n).unwrap(), &control).unwrap();
        assert!(ifs.contractivity().is_contractive());
        let levels = 5;
        let mut corner = vec![0.0; m];
        corner[0] = 1.0;
        let points = deterministic_points(&ifs, Some(&corner), levels, 1 << 20).unwrap();
        assert_eq!(points.len(), 4usize.pow(levels));
        for (word, q) in points.iter().enumerate() {
            let (u, v) = word_corner(word, levels);
            let exact = patch(&control, n, u, v);
            assert!(distance(*q, exact) < 1e-12, "degree {n}, word {word}: {q:?} vs {exact:?}");
        }
        // Centroid of each sub-net vs the surface at the sub-square's centre.
        let centroid = vec![1.0 / m as f64; m];
        let deviation = |levels: u32| {
            let points = deterministic_points(&ifs, Some(&centroid), levels, 1 << 20).unwrap();
            let half = 0.5f64.powi(levels as i32 + 1);
            points
                .iter()
                .enumerate()
                .map(|(word, q)| {
                    let (u, v) = word_corner(word, levels);
                    distance(*q, patch(&control, n, u + half, v + half))
                })
                .fold(0.0, f64::max)
        };
        let (d4, d6) = (deviation(4), deviation(6));
        let ratio_per_level = (d6 / d4).sqrt();
        if n == 1 {
            // Bilinear: the centroid of a bilinear net is the patch point at the centre.
            assert!(d4 < 1e-12 && d6 < 1e-12, "{d4:e} {d6:e}");
        } else {
            assert!((0.2..0.3).contains(&ratio_per_level), "degree {n}: {d4:e} -> {d6:e}");
        }
    }
}

/// The bilinear patch in space in the seed form: four affinely independent control points,
/// a 4×4 homogeneous control matrix; its maps send the corners to the sub-patch corners,
/// so the attractor (from the corners) is the hyperbolic paraboloid.
#[test]
fn bilinear_patch_in_the_seed_form_4x4() {
    let control = [[0.0, 0.0, 0.0], [0.0, 1.0, 0.2], [1.2, 0.1, 0.0], [1.0, 1.0, 1.0]];
    let rule = tensor_patch_split(1, 1).unwrap();
    let seed = AffineIfs::from_rule(&rule, &control).unwrap();
    assert_eq!(seed.dim(), 3);
    let report = seed.require_contractive().unwrap();
    assert!(report.jsr_upper < 1.0 && report.max_singular_value.is_finite());
    let levels = 5;
    let points = deterministic_points(&seed, Some(&control[0]), levels, 1 << 20).unwrap();
    for (word, q) in points.iter().enumerate() {
        let (u, v) = word_corner(word, levels);
        assert!(distance(*q, patch(&control, 1, u, v)) < 1e-12, "word {word}");
    }
    // The same points as the barycentric form.
    let bary = BarycentricIfs::new(&rule, &control).unwrap();
    let b = deterministic_points(&bary, Some(&[1.0, 0.0, 0.0, 0.0]), levels, 1 << 20).unwrap();
    assert!(points.iter().zip(&b).all(|(p, q)| distance(*p, *q) < 1e-12));
    // Coplanar corners: P̂ is singular.
    let flat = [[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]];
    assert!(matches!(AffineIfs::from_rule(&rule, &flat), Err(IfsError::SingularControl { .. })));
    // More control points than dimension + 1: only the barycentric form applies.
    let bicubic = tensor_patch_split(3, 3).unwrap();
    let net = control_net(3);
    assert!(matches!(AffineIfs::from_rule(&bicubic, &net), Err(IfsError::NotSquare { needed: 4, got: 16, .. })));
}
