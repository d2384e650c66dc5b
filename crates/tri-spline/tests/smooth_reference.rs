//! The smooth-data claim of the reference results (issue 6 §3, seed paper 001's Bézier
//! row): 4753 points of the smooth test surface on a regular triangular grid, two
//! reverse-Loop levels, ten iterations. Measured (the crate's `reference` example): LSPIA
//! reaches ε_avg = 2.67e-5 and N_ε = 100 % at k = 10 (hit tolerance 0.002 of the
//! bounding-box diagonal), the seed loop 6.7e-7 (paper: ε_avg 1.253e-3, N_ε 97.956 %).
//! The bounds keep a margin of about 2x on ε_avg.

use mesh_topo::HalfedgeMesh;
use tri_spline::SurfaceKind;
use tri_spline::pipeline::{FitOptions, Method, fit_mesh};
use tri_spline::samples::{smooth_surface, triangle_grid};

#[test]
fn bezier_lspia_beats_the_papers_bezier_row_on_smooth_data() {
    let mesh = HalfedgeMesh::from_soup(&triangle_grid(96, smooth_surface)).unwrap();
    assert_eq!(mesh.vertex_count(), 4753);
    let options = FitOptions {
        surface: SurfaceKind::Bezier,
        method: Method::Lspia,
        reverse_levels: 2,
        iterations: 10,
        least_squares: false,
        ..FitOptions::default()
    };
    let report = fit_mesh(&mesh, &options).unwrap();
    assert_eq!((report.degree, report.control_points), (24, 325));
    let last = report.iterations.last().unwrap();
    assert_eq!(last.k, 10);
    // The data span about unit size (bounding-box diagonal 1.45), as in the paper.
    assert!((report.bbox_diag - 1.45).abs() < 0.05, "{}", report.bbox_diag);
    assert!(last.eps_avg < EPS_AVG_BOUND, "eps_avg {}", last.eps_avg);
    assert!(last.n_eps > 99.0, "N_eps {}", last.n_eps);
    // LSPIA: the residual 2-norm never increases (ALGORITHMS.md §12.3).
    for pair in report.residual_norms.windows(2) {
        assert!(pair[1] <= pair[0] * (1.0 + 1e-12), "{pair:?}");
    }
    assert!(report.spectral_radius.unwrap() < 1.0);

    // The seed loop on the same problem (ALGORITHMS.md §12.4 table: 7.0e-3 -> 6.7e-7).
    let seed = fit_mesh(&mesh, &FitOptions { method: Method::Seed, ..options }).unwrap();
    let (first, last) = (&seed.iterations[0], &seed.iterations[9]);
    assert!((first.eps_avg - 7.03e-3).abs() < 1e-4, "{}", first.eps_avg);
    assert!(last.eps_avg < 1.4e-6 && last.n_eps == 100.0, "{last:?}");
}

/// Twice the measured ε_avg at k = 10 (2.67e-5); the paper reached 1.253e-3.
const EPS_AVG_BOUND: f64 = 5.5e-5;
