//! Reference results in the form of seed paper 001's Table 2 (ALGORITHMS.md §12.6):
//! reverse-Loop levels i = 2, k = 10 iterations, on
//!
//! * a Bézier row: a regular triangular grid of 4753 points (N = 96) sampled from the
//!   smooth test surface of ALGORITHMS.md §12.4 (degree 24, 325 control points);
//! * a B-patch row: the same surface on 91 points (N = 12; degree 3, 10 control points);
//! * a triangular B-spline row: a disk of 52 faces cut from the Stanford bunny
//!   (`tests/data/bunny.obj`, scaled to unit size), refined twice by Loop subdivision
//!   (453 points when the cut has 36 vertices and 18 boundary edges, as in the paper).
//!
//! For each row the three iterations (the seed loop, LSPIA, classical PIA) are run and
//! their tables printed with the spectral radius and the least-squares baseline.
//!
//! Run: `cargo run --release -p tri-spline --example reference`

use std::path::Path;

use mesh_topo::HalfedgeMesh;
use subdiv_loop::forward::{LoopOptions, subdivide};
use tri_spline::SurfaceKind;
use tri_spline::pipeline::{FitOptions, FitReport, Method, fit_mesh};
use tri_spline::samples::{disk_patch, smooth_surface, triangle_grid};

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

fn run(title: &str, mesh: &HalfedgeMesh, surface: SurfaceKind) -> Result<(), Box<dyn std::error::Error>> {
    for method in [Method::Seed, Method::Lspia, Method::Pia] {
        let options = FitOptions { surface, method, reverse_levels: 2, iterations: 10, ..FitOptions::default() };
        print_report(title, &fit_mesh(mesh, &options)?);
    }
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let bezier = HalfedgeMesh::from_soup(&triangle_grid(96, smooth_surface))?;
    run(
        "Bezier row (paper: 4753 points, eps_avg 5.4e-3 -> 1.3e-3, N_eps 69 -> 98 %, < 1 s)",
        &bezier,
        SurfaceKind::Bezier,
    )?;

    let bpatch = HalfedgeMesh::from_soup(&triangle_grid(12, smooth_surface))?;
    run(
        "B-patch row (paper: 91 points, eps_avg 7.7e-3 -> 3.2e-3, N_eps 41 -> 94 %, 12 s)",
        &bpatch,
        SurfaceKind::Bpatch,
    )?;

    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/data/bunny.obj");
    let (bunny, _) = mesh_topo::io::read_mesh(&data)?;
    let patch = disk_patch(&bunny, 100, 2).ok_or("no disk patch found")?;
    let coarse = HalfedgeMesh::from_soup(&patch)?;
    let stats = coarse.topology_stats();
    println!(
        "\nbunny patch: {} vertices, {} faces, {} boundary edges",
        stats.vertices,
        stats.faces,
        coarse.halfedges().filter(|&h| coarse.is_boundary_halfedge(h)).count()
    );
    let fine =
        subdivide(&coarse, 2, &LoopOptions { keep_corners: true, ..LoopOptions::default() })?.to_halfedge_mesh()?;
    run(
        "Triangular B-spline row (paper: 453 points, eps_avg 8.6e-3 -> 3.5e-3, N_eps 55 -> 92 %, 68 s)",
        &fine,
        SurfaceKind::TriBspline,
    )?;
    Ok(())
}
