//! Named examples: the figures of seed 003 and a few classics, ready to render.

use num_complex::Complex64;

use crate::error::{IfsError, Result};
use crate::ifs::{AffineIfs, AffineMap, BarycentricIfs, ComplexBezierIfs, Ifs};
use crate::matrices::{bezier_split, sierpinski, tensor_patch_split, triangle_patch_split};
use crate::nonlinear::{ExpY, NonlinearIfs, Polar, SquareY, triangle_samples};
use crate::render::Projection;

/// A ready-to-render IFS with its suggested deterministic levels and start set.
pub struct Scene {
    /// Canonical preset name.
    pub name: &'static str,
    /// What it shows (and where it comes from).
    pub description: &'static str,
    /// The system.
    pub ifs: Box<dyn Ifs + Send>,
    /// Suggested number of deterministic levels.
    pub levels: u32,
    /// Start set of the deterministic algorithm (`None`: the IFS default).
    pub start: Option<Vec<f64>>,
    /// How to draw it.
    pub projection: Projection,
}

/// One entry of the preset table: canonical name, aliases, description.
pub type PresetInfo = (&'static str, &'static [&'static str], &'static str);

/// All presets.
pub const PRESETS: &[PresetInfo] = &[
    ("quadratic-bezier", &[], "quadratic Bézier curve (0,0),(1,2),(3,0) as a 2-map IFS (ALGORITHMS.md §15.3)"),
    ("cubic-bezier", &[], "planar cubic Bézier curve, barycentric 4-point form"),
    ("bicubic-patch", &["patch"], "bicubic tensor-product Bézier patch in space, 4 maps on 16 control points"),
    ("triangle-patch", &[], "cubic triangular Bézier patch in space, 4 maps by midpoint quadrisection (blossoms)"),
    ("sierpinski", &[], "Sierpiński gasket, seed form P̂^{-1} S_i P̂"),
    ("sierpinski-polar", &[], "Sierpiński gasket bent by polar coordinates F(r, θ) = (r cos θ, r sin θ)"),
    ("levy", &["levy-c"], "Goldman's complex 2-point scheme, z = (1+i)/2: the Lévy C curve (seed 003 Fig. 3)"),
    ("complex-morph-0", &[], "z = 0.5: the segment (seed 003 Fig. 4, k = 0)"),
    ("complex-morph-1", &[], "z = 0.5 + 0.1i (seed 003 Fig. 4, k = 1)"),
    ("complex-morph-2", &[], "z = 0.5 + 0.2i (seed 003 Fig. 4, k = 2)"),
    ("complex-morph-3", &[], "z = 0.5 + 0.3i (seed 003 Fig. 4, k = 3)"),
    ("complex-morph-4", &[], "z = 0.5 + 0.4i (seed 003 Fig. 4, k = 4)"),
    ("complex-morph-5", &[], "z = 0.5 + 0.5i: the Lévy curve again (seed 003 Fig. 4, k = 5)"),
    ("complex-spiral", &[], "complex 3-point (quadratic) scheme, z = 0.45 + 0.4i, control 0, 1+i, 2"),
    (
        "quartic-bump",
        &["gaussian", "gauss"],
        "the seed's \"Gauss curve\" IFS F∘T_i∘F^{-1}, F(x,w) = (x,w²): really the quartic (25/4)(1-x²)² \
         (ALGORITHMS.md §15.3); drawn from the filled triangle (-1,0),(0,25),(1,0) = F(control triangle)",
    ),
    ("exp-gaussian", &["true-gaussian"], "a true Gaussian y = exp(-x²/2): quadratic Bézier in (x, ln y), F = exp"),
    ("barnsley-fern", &["fern"], "Barnsley's fern (affine, chaos game)"),
];

/// Resolves a preset name or alias to its canonical name.
///
/// # Errors
/// [`IfsError::UnknownPreset`] listing the known names.
///
/// ```
/// use ifs_nonlinear::{IfsError, canonical_preset};
/// assert_eq!(canonical_preset("fern")?, "barnsley-fern"); // an alias
/// assert_eq!(canonical_preset("levy")?, "levy"); // a canonical name
/// let unknown = canonical_preset("mandelbrot").unwrap_err();
/// assert!(matches!(unknown, IfsError::UnknownPreset { .. }) && unknown.to_string().contains("sierpinski-polar"));
/// # Ok::<(), IfsError>(())
/// ```
pub fn canonical_preset(name: &str) -> Result<&'static str> {
    PRESETS
        .iter()
        .find(|(canonical, aliases, _)| *canonical == name || aliases.contains(&name))
        .map(|p| p.0)
        .ok_or_else(|| IfsError::UnknownPreset {
            name: name.to_string(),
            known: PRESETS.iter().map(|p| p.0).collect::<Vec<_>>().join(", "),
        })
}

/// Builds a preset (names and aliases in [`PRESETS`]).
///
/// # Errors
/// [`IfsError::UnknownPreset`].
///
/// ```
/// use ifs_nonlinear::{deterministic_points, preset};
/// let scene = preset("gaussian")?; // alias of the honest name
/// assert_eq!(scene.name, "quartic-bump");
/// let points = deterministic_points(&scene.ifs, scene.start.as_deref(), 4, 1 << 20)?;
/// assert!(!points.is_empty());
/// # Ok::<(), ifs_nonlinear::IfsError>(())
/// ```
pub fn preset(name: &str) -> Result<Scene> {
    let name = canonical_preset(name)?;
    let description = PRESETS.iter().find(|p| p.0 == name).map(|p| p.2).unwrap_or_default();
    let scene = |ifs: Box<dyn Ifs + Send>, levels: u32| Scene {
        name,
        description,
        ifs,
        levels,
        start: None,
        projection: Projection::Xy,
    };
    let levy = |k: u32| -> Result<Box<dyn Ifs + Send>> {
        let control = [Complex64::new(0.0, 0.0), Complex64::new(1.0, 0.0)];
        Ok(Box::new(ComplexBezierIfs::new(Complex64::new(0.5, 0.1 * f64::from(k)), &control)?))
    };
    let orbit = Projection::Orbit { azimuth: 0.6, elevation: 0.45 };
    Ok(match name {
        "quadratic-bezier" => {
            scene(Box::new(BarycentricIfs::new(&bezier_split(2, 0.5)?, &[[0.0, 0.0], [1.0, 2.0], [3.0, 0.0]])?), 12)
        }
        "cubic-bezier" => {
            let control = [[0.0, 0.0], [1.0, 2.0], [2.5, -1.0], [3.0, 1.0]];
            scene(Box::new(BarycentricIfs::new(&bezier_split(3, 0.5)?, &control)?), 12)
        }
        "bicubic-patch" => {
            let control: Vec<[f64; 3]> = (0..16)
                .map(|i| {
                    let (u, v) = ((i / 4) as f64, (i % 4) as f64);
                    [u, v, ((u - 1.5) * (v - 1.5)) * 0.35 + if i == 5 || i == 10 { 1.0 } else { 0.0 }]
                })
                .collect();
            let mut s = scene(Box::new(BarycentricIfs::new(&tensor_patch_split(3, 3)?, &control)?), 6);
            s.projection = orbit;
            s
        }
        "triangle-patch" => {
            let control: Vec<[f64; 3]> = crate::matrices::triangle_multi_indices(3)?
                .into_iter()
                .map(|b| {
                    let (x, y) = (b[1] as f64 + 0.5 * b[2] as f64, 0.866 * b[2] as f64);
                    [x, y, if b == [1, 1, 1] { 1.5 } else { 0.2 * (b[0] * b[1]) as f64 }]
                })
                .collect();
            let mut s = scene(Box::new(BarycentricIfs::new(&triangle_patch_split(3)?, &control)?), 6);
            s.projection = orbit;
            s
        }
        "sierpinski" => {
            let control = [[0.0, 0.0], [1.0, 0.0], [0.5, 3f64.sqrt() / 2.0]];
            scene(Box::new(AffineIfs::from_rule(&sierpinski(), &control)?), 8)
        }
        "sierpinski-polar" => {
            let control = [[1.0, 0.2], [2.0, 0.2], [1.2, 2.6]];
            scene(Box::new(NonlinearIfs::new(AffineIfs::from_rule(&sierpinski(), &control)?, Polar)), 8)
        }
        "levy" | "complex-morph-5" => scene(levy(5)?, 12),
        "complex-morph-0" => scene(levy(0)?, 10),
        "complex-morph-1" => scene(levy(1)?, 10),
        "complex-morph-2" => scene(levy(2)?, 10),
        "complex-morph-3" => scene(levy(3)?, 10),
        "complex-morph-4" => scene(levy(4)?, 10),
        "complex-spiral" => {
            let control = [Complex64::new(0.0, 0.0), Complex64::new(1.0, 1.0), Complex64::new(2.0, 0.0)];
            scene(Box::new(ComplexBezierIfs::new(Complex64::new(0.45, 0.4), &control)?), 12)
        }
        "quartic-bump" => {
            let linear = AffineIfs::from_rule(&bezier_split(2, 0.5)?, &[[-1.0, 0.0], [0.0, 5.0], [1.0, 0.0]])?;
            let mut s = scene(Box::new(NonlinearIfs::new(linear, SquareY)), 6);
            s.start = Some(triangle_samples([-1.0, 0.0], [0.0, 25.0], [1.0, 0.0], 64)?);
            s
        }
        "exp-gaussian" => {
            let linear = AffineIfs::from_rule(&bezier_split(2, 0.5)?, &[[-2.0, -2.0], [0.0, 2.0], [2.0, -2.0]])?;
            scene(Box::new(NonlinearIfs::new(linear, ExpY)), 12)
        }
        "barnsley-fern" => scene(Box::new(barnsley_fern()), 8),
        _ => unreachable!("internal: every canonical preset name is handled"),
    })
}

/// Barnsley's fern, the classic four-map affine IFS.
///
/// ```
/// assert_eq!(ifs_nonlinear::barnsley_fern().maps().len(), 4);
/// ```
pub fn barnsley_fern() -> AffineIfs {
    AffineIfs::new(
        2,
        vec![
            AffineMap::planar(0.0, 0.0, 0.0, 0.16, 0.0, 0.0),
            AffineMap::planar(0.85, 0.04, -0.04, 0.85, 0.0, 1.6),
            AffineMap::planar(0.2, -0.26, 0.23, 0.22, 0.0, 1.6),
            AffineMap::planar(-0.15, 0.28, 0.26, 0.24, 0.0, 0.44),
        ],
    )
    .expect("internal: the fern's maps are finite")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::deterministic_points;

    #[test]
    fn every_preset_builds_and_renders_a_few_levels() {
        for (name, aliases, _) in PRESETS {
            let scene = preset(name).unwrap();
            assert_eq!(scene.name, *name);
            for alias in *aliases {
                assert_eq!(preset(alias).unwrap().name, *name);
            }
            let points = deterministic_points(&scene.ifs, scene.start.as_deref(), 3, 1 << 20).unwrap();
            assert!(points.iter().all(|p| p.iter().all(|v| v.is_finite())), "{name}");
        }
        assert!(matches!(preset("nope"), Err(IfsError::UnknownPreset { .. })));
    }
}
