//! Reference results in the form of seed paper 001's Table 2 (ALGORITHMS.md §12.6):
//! reverse-Loop levels i = 2, k = 10 iterations, for the three surface kinds on
//!
//! * `smooth`: a regular triangular grid of 4753 points (N = 96) sampled from the smooth
//!   test surface of ALGORITHMS.md §12.4 (Bézier and B-patch: degree 24, 325 control
//!   points; triangular B-spline: quadratic DMS over the 576-triangle net);
//! * `bunny`: a disk of the Stanford bunny (`tests/data/bunny.obj`, 6 rings around a
//!   vertex, scaled to unit size) resampled on the same grid through its mean-value
//!   parameterization;
//! * `paper-bspline`: the paper's triangular B-spline setting, a bunny disk of about 52
//!   faces refined twice by Loop subdivision.
//!
//! For each row the three iterations (the seed loop, LSPIA, classical PIA) are run and
//! their tables printed with the spectral radius and the least-squares baseline.
//!
//! Run: `cargo run --release -p tri-spline --example reference [smooth|bunny|paper-bspline]`

use std::path::Path;

use mesh_topo::HalfedgeMesh;
use subdiv_loop::forward::{LoopOptions, subdivide};
use tri_spline::SurfaceKind;
use tri_spline::pipeline::{FitOptions, FitReport, Method, fit_mesh};
use tri_spline::samples::{disk_patch, resample_on_grid, smooth_surface, triangle_grid};

fn print_report(title: &str, report: &FitReport) {
    println!(
        "\n{title}: {} / {}, degree {}, {} control points, {} data points, bbox diagonal {:.4}, hit_tol {:.1e}",
        report.kind.name(),
        report.method.name(),
        report.degree,
        report.control_points,
        report.data_points,
        report.bbox_diag,
        report.hit_tol
    );
    println!("{:>3} {:>12} {:>12} {:>9} {:>10}", "k", "eps_max", "eps_avg", "N_eps %", "seconds");
    for r in &report.iterations {
        println!("{:>3} {:>12.6e} {:>12.6e} {:>9.3} {:>10.4}", r.k, r.eps_max, r.eps_avg, r.n_eps, r.seconds);
    }
    match report.spectral_radius {
        Some(rho) => println!("spectral radius {} = {rho:.9} (1 - {:.3e})", report.spectral_note, 1.0 - rho),
        None => println!("spectral radius {}", report.spectral_note),
    }
    if let Some(ls) = &report.least_squares {
        println!(
            "least squares: eps_max {:.6e}, eps_avg {:.6e}, N_eps {:.3} %, {:.4} s",
            ls.eps_max, ls.eps_avg, ls.n_eps, ls.seconds
        );
    }
    let t = &report.timings;
    println!(
        "times: parameterize {:.4} s, reverse Loop {:.4} s, collocation {:.4} s, spectral {:.4} s, iterations {:.4} s, total {:.4} s",
        t.parameterize, t.reverse_loop, t.collocation, t.spectral, t.iterations, t.total
    );
    for w in &report.warnings {
        println!("warning: {w}");
    }
}

fn run(
    title: &str,
    mesh: &HalfedgeMesh,
    surface: SurfaceKind,
    methods: &[Method],
) -> Result<(), Box<dyn std::error::Error>> {
    for &method in methods {
        let options = FitOptions { surface, method, reverse_levels: 2, iterations: 10, ..FitOptions::default() };
        print_report(title, &fit_mesh(mesh, &options)?);
    }
    Ok(())
}

const ALL: [Method; 3] = [Method::Seed, Method::Lspia, Method::Pia];

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let only = std::env::args().nth(1).unwrap_or_default();
    let smooth = HalfedgeMesh::from_soup(&triangle_grid(96, smooth_surface))?;
    if only.is_empty() || only == "smooth" {
        let note = "smooth grid, 4753 points (paper, k = 1 -> 10: Bezier eps_avg 5.4e-3 -> 1.3e-3, N_eps 69 -> 98 %, < 1 s; B-patch 7.7e-3 -> 3.2e-3, 41 -> 94 %, 12 s; tri B-spline 8.6e-3 -> 3.5e-3, 55 -> 92 %, 68 s)";
        for surface in [SurfaceKind::Bezier, SurfaceKind::Bpatch, SurfaceKind::TriBspline] {
            run(note, &smooth, surface, &ALL)?;
        }
    }

    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/data/bunny.obj");
    let (bunny, _) = mesh_topo::io::read_mesh(&data)?;
    if only.is_empty() || only == "bunny" {
        // A disk of the bunny's surface (6 rings around vertex 100, scaled to unit size),
        // resampled on the regular grid of 4753 points by its mean-value parameterization.
        let region = HalfedgeMesh::from_soup(&disk_patch(&bunny, 100, 6).ok_or("no disk patch found")?)?;
        let stats = region.topology_stats();
        let grid = HalfedgeMesh::from_soup(&resample_on_grid(&region, 96)?)?;
        let note = format!(
            "bunny region ({} vertices, {} faces) resampled on the 4753-point grid",
            stats.vertices, stats.faces
        );
        for surface in [SurfaceKind::Bezier, SurfaceKind::Bpatch, SurfaceKind::TriBspline] {
            run(&note, &grid, surface, &ALL)?;
        }
    }

    if only.is_empty() || only == "paper-bspline" {
        // The paper's triangular B-spline setting: a coarse disk of about 52 faces refined
        // twice by Loop subdivision, so that two reverse-Loop levels give it back.
        let patch = disk_patch(&bunny, 100, 2).ok_or("no disk patch found")?;
        let coarse = HalfedgeMesh::from_soup(&patch)?;
        let stats = coarse.topology_stats();
        let fine =
            subdivide(&coarse, 2, &LoopOptions { keep_corners: true, ..LoopOptions::default() })?.to_halfedge_mesh()?;
        let note = format!(
            "bunny disk ({} vertices, {} faces) refined twice by Loop, {} points (paper: 453 points, eps_avg 8.6e-3 -> 3.5e-3, N_eps 55 -> 92 %, 68 s)",
            stats.vertices,
            stats.faces,
            fine.vertex_count()
        );
        run(&note, &fine, SurfaceKind::TriBspline, &ALL)?;
    }
    Ok(())
}
