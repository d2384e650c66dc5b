//! `multires demo` (and `multires` without arguments): a tour of the library on the
//! Stanford bunny embedded in the binary. Every step prints what it did and writes its
//! files into the output directory; `index.html` there shows the pictures and tables.
//!
//! Steps: the input mesh; Loop and Doo-Sabin subdivision to level 3; the two boundary
//! rules of Doo-Sabin on an open grid; decomposition of
//! bumpy level-3 meshes back to the base mesh with details and exact reconstruction;
//! compression by keeping the largest details; triangular splines fitted by LSPIA over
//! reverse-Loop control nets; curves; fractals; a closing summary.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use mesh_topo::io::{self, Format, PlyEncoding, ReadReport, WriteOptions};
use mesh_topo::shapes::{self, CellKind};
use mesh_topo::{DVec3, HalfedgeMesh, PolygonSoup};
use multires::doo::{self, BoundaryRule, DooOptions, FaceRule};
use multires::loop_subdiv::pyramid::bounding_box_diagonal;
use multires::{Depth, Pyramid, SurfaceScheme, decompose};

use super::common::{build_mesh, print_out, write_mesh, write_soup};
use super::mesh_cmds::{mesh_info, mesh_info_text};
use super::render::{Camera, Image, RenderOptions, render_with_camera};
use super::{CliError, CliResult, input_error};

/// Options of `demo`.
#[derive(Debug, Args)]
pub struct DemoArgs {
    /// Output directory.
    #[arg(long, default_value = "multires-out")]
    pub out: PathBuf,
}

impl Default for DemoArgs {
    fn default() -> Self {
        Self { out: PathBuf::from("multires-out") }
    }
}

/// The mesh embedded in the binary for the demo: the Stanford bunny (1839 vertices,
/// 3674 triangles; origin in `tests/data/README.md`).
const DEMO_MESH_NAME: &str = "bunny";
const DEMO_MESH_OBJ: &str = include_str!("../../tests/data/bunny.obj");

/// Levels of the subdivision and decomposition steps.
const LEVELS: u32 = 3;

/// Fractions of the details kept in the compression tables.
const KEPT_FRACTIONS: [f64; 7] = [1.0, 0.5, 0.2, 0.1, 0.05, 0.02, 0.0];

/// Size of one picture panel (pixels).
const PANEL: (u32, u32) = (360, 360);

/// Camera azimuth and elevation (degrees). The renderer's up axis is +z and the bunny
/// file's is +y, so a high elevation looks at the bunny from the front.
const VIEW: (f64, f64) = (20.0, 70.0);

/// State passed from one demo step to the next.
struct Demo {
    out: PathBuf,
    mesh: HalfedgeMesh,
    report: ReadReport,
    /// The bumpy level-3 meshes decomposed by the multiresolution step, per scheme.
    pyramids: Vec<(SurfaceScheme, Pyramid, PolygonSoup)>,
    /// HTML sections, in order.
    html: String,
    /// Closing summary rows: step, result, seconds.
    summary: Vec<(String, String, f64)>,
}

type Step = fn(&mut Demo) -> CliResult<String>;

/// The demo, in order: (title, step). Each step returns its one-line summary.
const STEPS: &[(&str, Step)] = &[
    ("the input mesh", input_mesh),
    ("Loop subdivision", loop_subdivision),
    ("Doo-Sabin subdivision", doo_subdivision),
    ("Doo-Sabin boundaries", doo_boundaries),
    ("decomposition and exact reconstruction", multiresolution),
    ("compression: keeping the largest details", compression),
    ("fitting triangular splines", spline_fit),
    ("a curve", curve),
    ("a fractal", fractal),
];

/// `multires demo` and `multires` without arguments.
pub fn demo(args: &DemoArgs) -> CliResult {
    let started = Instant::now();
    std::fs::create_dir_all(&args.out).map_err(|source| CliError::Io { path: args.out.clone(), source })?;
    let (soup, report) =
        io::read_bytes(DEMO_MESH_OBJ.as_bytes(), Format::Obj).map_err(|e| input_error("embedded mesh", e))?;
    let mesh = build_mesh(Path::new("embedded mesh"), &soup)?;
    let mut demo =
        Demo { out: args.out.clone(), mesh, report, pyramids: Vec::new(), html: String::new(), summary: Vec::new() };
    // The bar draws on stderr only when it is a terminal: tests and pipes see plain text.
    let progress = ProgressBar::new(STEPS.len() as u64).with_style(
        ProgressStyle::with_template("{bar:30} {pos}/{len} {msg} [{elapsed}]")
            .expect("internal: valid progress template"),
    );
    for (i, (title, step)) in STEPS.iter().enumerate() {
        progress.set_message(*title);
        progress.suspend(|| print_out(&format!("\n== {}. {title}\n", i + 1)))?;
        let step_started = Instant::now();
        let line = step(&mut demo)?;
        demo.summary.push((title.to_string(), line, step_started.elapsed().as_secs_f64()));
        progress.inc(1);
    }
    progress.finish_and_clear();
    let total = started.elapsed().as_secs_f64();
    write_index(&demo, total)?;
    print_out(&summary_table(&demo.summary, total))?;
    print_out(&format!("open {} to see the pictures and tables\n", demo.out.join("index.html").display()))
}

// ---------------------------------------------------------------------------------------
// steps

fn input_mesh(demo: &mut Demo) -> CliResult<String> {
    let file = format!("{DEMO_MESH_NAME}.obj");
    let info = mesh_info(&format!("{file} (embedded)"), &demo.mesh.to_soup(), &demo.report);
    let text = mesh_info_text(&info);
    print_out(&text)?;
    let path = demo.out.join(&file);
    write_mesh(&path, &demo.mesh)?;
    let info_path = demo.out.join(format!("{DEMO_MESH_NAME}-info.json"));
    let json = serde_json::to_string_pretty(&info).expect("internal: JSON of plain values");
    write_file(&info_path, (json + "\n").as_bytes())?;
    print_out(&format!("wrote {} and {}\n", path.display(), info_path.display()))?;
    section(demo, "The input mesh", "The Stanford bunny, embedded in the binary.", &[], &text);
    Ok(format!("{} vertices, {} triangles", demo.mesh.vertex_count(), demo.mesh.face_count()))
}

fn loop_subdivision(demo: &mut Demo) -> CliResult<String> {
    subdivision_levels(demo, SurfaceScheme::Loop, "Loop subdivision (Loop's original weights), levels 0 to 3.")
}

fn doo_subdivision(demo: &mut Demo) -> CliResult<String> {
    subdivision_levels(
        demo,
        SurfaceScheme::DooSabin,
        "Doo-Sabin subdivision (original weights), levels 0 to 3: faces from faces, edges and vertices.",
    )
}

/// An open wavy grid refined by Doo-Sabin under its two boundary rules: shrinking (no
/// faces at the boundary) and Chaikin (boundary quads and vertex faces through the
/// Chaikin points), with the distance of each level's boundary to the Chaikin refinement
/// of the grid's outline.
fn doo_boundaries(demo: &mut Demo) -> CliResult<String> {
    use multires::curve::{CurveScheme, Topology};

    let mut grid = shapes::grid(6, 4, CellKind::Quads).map_err(|e| input_error("grid", e))?;
    for p in &mut grid.positions {
        p.z = 0.35 * (1.1 * p.x).sin() * (0.9 * p.y + 0.3).cos();
    }
    let mesh = HalfedgeMesh::from_soup(&grid).map_err(|e| input_error("grid", e))?;
    let outline = boundary_polygon(&mesh);
    let mut table =
        String::from("rule     level  vertices  faces  boundary vertices  max distance to Chaikin outline\n");
    let mut pictures = Vec::new();
    let mut gap = 0.0;
    for boundary in [BoundaryRule::Shrink, BoundaryRule::Chaikin] {
        let mut levels = vec![grid.clone()];
        let options = DooOptions::new(FaceRule::DooSabin, 1).with_boundary(boundary);
        let mut coarse = mesh.clone();
        for level in 1..=LEVELS {
            // One step from the level before (the same mesh as `level` steps from the grid).
            let fine = doo::subdivide(&coarse, &options).map_err(|e| input_error("grid", e))?.into_soup();
            let fine_mesh = HalfedgeMesh::from_soup(&fine).map_err(|e| input_error("grid", e))?;
            let found = boundary_polygon(&fine_mesh);
            // The reference: the outline refined by the curve crate's Chaikin scheme.
            let expected = CurveScheme::chaikin()
                .refine(&outline, Topology::Closed, level)
                .map_err(|e| input_error("grid outline", e))?;
            // Each boundary vertex's distance to the nearest point of the refined outline.
            let distance = found
                .iter()
                .map(|p| expected.iter().map(|q| p.distance(*q)).fold(f64::INFINITY, f64::min))
                .fold(0.0, f64::max);
            if boundary == BoundaryRule::Chaikin {
                gap = f64::max(gap, distance);
            }
            writeln!(
                table,
                "{:<8} {level:>5} {:>9} {:>6} {:>18} {distance:>32.3e}",
                boundary.to_string(),
                fine.vertex_count(),
                fine.face_count(),
                found.len()
            )
            .expect("string");
            levels.push(fine);
            coarse = fine_mesh;
        }
        let picture = format!("doo-sabin-boundary-{boundary}.png");
        write_picture_view(&demo.out.join(&picture), &levels.iter().collect::<Vec<_>>(), (30.0, 55.0))?;
        pictures.push(picture);
    }
    print_out(&table)?;
    let names: Vec<&str> = pictures.iter().map(String::as_str).collect();
    section(
        demo,
        "Doo-Sabin at the boundary",
        "An open wavy grid, levels 0 to 3, under the two boundary rules: shrinking (top: no faces at the boundary, \
         as in the reverse-Doo paper and CGAL) and Chaikin (bottom: boundary quads and vertex faces through the \
         Chaikin points, so that the boundary is the Chaikin refinement of the grid's outline and converges to its \
         quadratic B-spline). Both reverse exactly.",
        &names,
        &table,
    );
    Ok(format!("Chaikin boundary within {gap:.1e} of the refined outline"))
}

/// The positions of the first boundary loop of `mesh`, in order.
fn boundary_polygon(mesh: &HalfedgeMesh) -> Vec<DVec3> {
    let loops = mesh.boundary_loops();
    loops.first().map_or_else(Vec::new, |l| l.iter().map(|&h| mesh.position(mesh.origin(h))).collect())
}

/// Levels 0..=LEVELS of `scheme`: a counts table, the finest mesh as binary PLY, and a
/// side-by-side picture.
fn subdivision_levels(demo: &mut Demo, scheme: SurfaceScheme, caption: &str) -> CliResult<String> {
    let mut levels = vec![demo.mesh.to_soup()];
    let mut table = String::from("level  vertices     faces   time (ms)\n");
    writeln!(table, "{:>5} {:>9} {:>9}", 0, levels[0].vertex_count(), levels[0].face_count()).expect("string");
    for level in 1..=LEVELS {
        let started = Instant::now();
        let fine = scheme.subdivide(&demo.mesh, level).map_err(|e| input_error(scheme, e))?;
        let ms = started.elapsed().as_secs_f64() * 1e3;
        writeln!(table, "{level:>5} {:>9} {:>9} {ms:>11.1}", fine.vertex_count(), fine.face_count()).expect("string");
        levels.push(fine);
    }
    print_out(&table)?;
    let finest = levels.last().expect("internal: levels");
    let mesh_path = demo.out.join(format!("{DEMO_MESH_NAME}-{scheme}-{LEVELS}.ply"));
    write_soup(&mesh_path, finest, &WriteOptions { ply_encoding: PlyEncoding::BinaryLittleEndian })?;
    let picture = format!("{scheme}-levels.png");
    write_picture(&demo.out.join(&picture), &levels.iter().collect::<Vec<_>>())?;
    print_out(&format!("wrote {} and {}\n", mesh_path.display(), demo.out.join(&picture).display()))?;
    let summary = format!("{} faces at level {LEVELS}", finest.face_count());
    section(demo, &format!("{scheme} subdivision"), caption, &[&picture], &table);
    Ok(summary)
}

/// Makes each level-3 mesh bumpy (so that every level has non-zero details), decomposes
/// it back to the bunny by reverse subdivision and rebuilds it from the pyramid.
fn multiresolution(demo: &mut Demo) -> CliResult<String> {
    let mut table = String::from("scheme      levels  base faces  details  fine vertices  max error / bbox diagonal\n");
    let mut worst_overall: f64 = 0.0;
    for scheme in [SurfaceScheme::Loop, SurfaceScheme::DooSabin] {
        let smooth = scheme.subdivide(&demo.mesh, LEVELS).map_err(|e| input_error(scheme, e))?;
        let bumpy = with_bumps(&smooth);
        let fine = build_mesh(Path::new("bumpy mesh"), &bumpy)?;
        let pyramid = decompose(&fine, scheme, Depth::Max).map_err(|e| input_error(scheme, e))?;
        let rebuilt = pyramid.reconstruct(pyramid.level_count()).map_err(|e| input_error(scheme, e))?;
        if rebuilt.indices != bumpy.indices {
            return Err(CliError::Input(format!("{scheme}: the reconstruction changed the faces")));
        }
        let worst = max_distance(&rebuilt.positions, &bumpy.positions) / bounding_box_diagonal(&bumpy.positions);
        worst_overall = worst_overall.max(worst);
        writeln!(
            table,
            "{:<11} {:>6} {:>11} {:>8} {:>14}  {worst:.2e}",
            scheme.name(),
            pyramid.level_count(),
            pyramid.base().face_count(),
            pyramid.detail_count(),
            bumpy.vertex_count(),
        )
        .expect("string");
        let file = demo.out.join(format!("{DEMO_MESH_NAME}-{scheme}-bumpy.mres"));
        write_file(&file, &pyramid.to_bytes().map_err(|e| input_error(scheme, e))?)?;
        demo.pyramids.push((scheme, pyramid, bumpy));
    }
    print_out(&table)?;
    print_out(&format!("max reconstruction error: {worst_overall:.2e} (relative to the bounding-box diagonal)\n"))?;
    section(
        demo,
        "Decomposition and exact reconstruction",
        "Each level-3 mesh gets small bumps, then reverse subdivision takes it back to the 3674-triangle \
         bunny with one detail vector per fine vertex not kept as a coarse vertex (the pyramid files are the \
         <code>.mres</code> files); rebuilding from the base and the details gives the bumpy mesh back.",
        &[],
        &table,
    );
    Ok(format!("max reconstruction error {worst_overall:.1e}"))
}

/// Rate-distortion tables and pictures of reconstructions from a fraction of the details.
fn compression(demo: &mut Demo) -> CliResult<String> {
    let mut text = String::new();
    let mut pictures = Vec::new();
    let mut line = String::new();
    for (scheme, pyramid, _) in &demo.pyramids {
        let rows = pyramid.rate_distortion(&KEPT_FRACTIONS).map_err(|e| input_error(scheme, e))?;
        writeln!(text, "{scheme}: details kept, and the error relative to the bounding-box diagonal").expect("s");
        writeln!(text, "  kept   details       max error       RMS error").expect("string");
        for row in &rows {
            writeln!(
                text,
                "{:>5.0}% {:>9} {:>15.3e} {:>15.3e}",
                100.0 * row.fraction,
                row.kept,
                row.max_error,
                row.rms_error
            )
            .expect("string");
        }
        text.push('\n');
        let top = pyramid.level_count();
        let mut panels = Vec::new();
        for fraction in [1.0, 0.1, 0.0] {
            panels.push(pyramid.reconstruct_keeping(top, fraction).map_err(|e| input_error(scheme, e))?);
        }
        let picture = format!("{scheme}-compression.png");
        write_picture(&demo.out.join(&picture), &panels.iter().collect::<Vec<_>>())?;
        pictures.push(picture);
        if let Some(tenth) = rows.iter().find(|r| r.fraction == 0.1) {
            write!(line, "{scheme}: 10% of details, RMS {:.1e}; ", tenth.rms_error).expect("string");
        }
    }
    print_out(&text)?;
    let picture_refs: Vec<&str> = pictures.iter().map(String::as_str).collect();
    section(
        demo,
        "Compression",
        "Reconstructions keeping all, 10% and none of the details (left to right): the largest details carry \
         the shape.",
        &picture_refs,
        &text,
    );
    Ok(line.trim_end_matches("; ").to_string())
}

/// The seed paper's fitting loop on a smooth height field sampled on a regular triangular
/// grid: control nets from two reverse-Loop levels, ten LSPIA iterations, for the three
/// surface kinds; the convergence table and a picture of data and fitted surface.
fn spline_fit(demo: &mut Demo) -> CliResult<String> {
    use multires::spline::SurfaceKind;
    use multires::spline::index::multi_indices;
    use multires::spline::pipeline::{FitOptions, Method, fit_mesh};
    use multires::spline::surface::grid_triangles;
    let segments = 32;
    let positions: Vec<DVec3> = multi_indices(segments)
        .map(|[_, j, k]| {
            let (u, v) = (j as f64 / segments as f64, k as f64 / segments as f64);
            DVec3::new(u + 0.5 * v, 0.866 * v, 0.25 * (3.0 * u).sin() * (2.5 * v).cos() + 0.1 * (u * v * 6.0).cos())
        })
        .collect();
    let data = HalfedgeMesh::from_faces(positions, grid_triangles(segments, true))
        .map_err(|e| input_error("fitting data", e))?;
    let mut text = format!(
        "data: {} points on a regular triangular grid ({segments} segments per side); control nets from 2 \
         reverse-Loop levels; LSPIA; errors relative to the bounding-box diagonal\n\n",
        data.vertex_count()
    );
    text.push_str("surface      degree  control  k   eps_max     eps_avg     N_eps   least squares eps_avg\n");
    let mut surfaces = Vec::new();
    let mut line = String::new();
    for kind in [SurfaceKind::Bezier, SurfaceKind::Bpatch, SurfaceKind::TriBspline] {
        let options = FitOptions { surface: kind, method: Method::Lspia, reverse_levels: 2, ..FitOptions::default() };
        let report = fit_mesh(&data, &options).map_err(|e| input_error(kind.name(), e))?;
        let diagonal = report.bbox_diag;
        for record in report.iterations.iter().filter(|r| r.k == 1 || r.k == report.iterations.len()) {
            writeln!(
                text,
                "{:<12} {:>6} {:>8} {:>2} {:>10.3e} {:>11.3e} {:>6.1}%  {}",
                kind.name(),
                report.degree,
                report.control_points,
                record.k,
                record.eps_max / diagonal,
                record.eps_avg / diagonal,
                record.n_eps,
                report.least_squares.map_or("-".to_string(), |l| format!("{:.3e}", l.eps_avg / diagonal)),
            )
            .expect("string");
        }
        let last = report.iterations.last().expect("internal: ten iterations");
        write!(line, "{} {:.1}%; ", kind.name(), last.n_eps).expect("string");
        if kind == SurfaceKind::Bezier {
            let (points, triangles) = report.surface.sample(&report.domain, 48);
            surfaces.push(PolygonSoup::from_faces(points, triangles));
        }
    }
    print_out(&text)?;
    let picture = "fit-bezier.png";
    let data_soup = data.to_soup();
    write_picture_view(&demo.out.join(picture), &[&data_soup, &surfaces[0]], (20.0, 55.0))?;
    section(
        demo,
        "Fitting triangular splines",
        "Progressive iterative approximation (LSPIA) of a smooth height field by a triangular Bézier patch, a \
         B-patch and a DMS triangular B-spline whose control nets come from two levels of reverse Loop \
         subdivision of the data mesh; the first and tenth iteration of each, next to the direct least-squares \
         fit. Left: the data mesh; right: the fitted Bézier patch.",
        &[picture],
        &text,
    );
    Ok(format!("N_eps after 10 iterations: {}", line.trim_end_matches("; ")))
}

/// A closed polygon refined by four curve schemes, drawn as SVG.
fn curve(demo: &mut Demo) -> CliResult<String> {
    use multires::curve::select::{SelectionOptions, select_interpolation_points};
    use multires::curve::svg::{Mark, SvgScene, render_svg};
    use multires::curve::{CurveScheme, Framework, Topology};
    // A hand-drawn closed outline with a sharp tip and an inflection.
    let control: Vec<[f64; 2]> = vec![
        [0.0, 0.0],
        [2.0, -0.6],
        [4.0, 0.2],
        [5.5, 2.0],
        [7.0, 1.5],
        [6.0, 4.0],
        [3.5, 3.2],
        [1.5, 4.5],
        [-0.5, 2.5],
    ];
    let levels = 5;
    let mut text = String::from("scheme          points  file\n");
    let mut pictures = Vec::new();
    let schemes = [
        ("chaikin", CurveScheme::chaikin()),
        ("cubic-bspline", CurveScheme::cubic_bspline()),
        ("four-point", CurveScheme::four_point(1.0 / 16.0).map_err(|e| input_error("four-point", e))?),
    ];
    let mut draw = |name: &str, refined: &[[f64; 2]], marks: &[(usize, Mark)]| -> CliResult {
        let svg = render_svg(&SvgScene { control: &control, curve: refined, closed: true, marks });
        let file = format!("curve-{name}.svg");
        write_file(&demo.out.join(&file), svg.as_bytes())?;
        writeln!(text, "{name:<15} {:>6}  {file}", refined.len()).expect("string");
        pictures.push(file);
        Ok(())
    };
    for (name, scheme) in &schemes {
        let refined = scheme.refine(&control, Topology::Closed, levels).map_err(|e| input_error(name, e))?;
        draw(name, &refined, &[])?;
    }
    let selection = select_interpolation_points(&control, Topology::Closed, &SelectionOptions::default())
        .map_err(|e| input_error("point selection", e))?;
    let refined = Framework::published()
        .refine(&control, &selection.flags, Topology::Closed, levels)
        .map_err(|e| input_error("combined", e))?;
    let marks: Vec<(usize, Mark)> = selection.points.iter().map(|&(i, class)| (i, Mark::Chosen(class))).collect();
    draw("combined", &refined, &marks)?;
    let chosen: Vec<String> = selection.points.iter().map(|(i, class)| format!("{i} ({})", class.name())).collect();
    writeln!(text, "combined scheme interpolates the automatically chosen points {}", chosen.join(", "))
        .expect("string");
    print_out(&text)?;
    let refs: Vec<&str> = pictures.iter().map(String::as_str).collect();
    section(
        demo,
        "Curves",
        "One closed polygon, five levels of Chaikin, the cubic B-spline, the four-point scheme (w = 1/16) and \
         the interpolatory-approximating framework with its published parameters (-1/16, 0, 1/8), which \
         interpolates the points chosen from discrete curvature (coloured) and approximates the others.",
        &refs,
        &text,
    );
    Ok(format!("4 schemes, {} interpolated points chosen", selection.points.len()))
}

/// Two attractors of complex-parameter subdivision rendered by the chaos game.
fn fractal(demo: &mut Demo) -> CliResult<String> {
    use multires::ifs::{Canvas, ChaosGame, ToneMap, View, chaos_density, chaos_points, preset};
    let mut text = String::from("preset            points  file\n");
    let mut pictures = Vec::new();
    let points = 400_000;
    for name in ["levy", "complex-spiral"] {
        let scene = preset(name).map_err(|e| input_error(name, e))?;
        let game = ChaosGame { points, seed: 2026, ..ChaosGame::default() };
        // Frame the attractor from a small sample, then splat the full run.
        let sample = chaos_points(scene.ifs.as_ref(), &ChaosGame { points: 20_000, ..game.clone() })
            .map_err(|e| input_error(name, e))?;
        let view = View::fit(&sample, scene.projection, 480, 360, 0.05).map_err(|e| input_error(name, e))?;
        let canvas = Canvas::new(480, 360, view).map_err(|e| input_error(name, e))?.with_projection(scene.projection);
        let density = chaos_density(scene.ifs.as_ref(), &game, &canvas).map_err(|e| input_error(name, e))?;
        let image = density.to_image(ToneMap::Log, [20, 40, 110, 255], [255, 255, 255, 255]);
        let file = format!("fractal-{name}.png");
        let path = demo.out.join(&file);
        image.write_png(&path).map_err(|e| input_error(path.display(), e))?;
        writeln!(text, "{name:<16} {points:>7}  {file}   ({})", scene.description).expect("string");
        pictures.push(file);
    }
    print_out(&text)?;
    let refs: Vec<&str> = pictures.iter().map(String::as_str).collect();
    section(
        demo,
        "Fractals",
        "Goldman's complex-parameter subdivision as an iterated function system: the two-point scheme with \
         z = (1 + i)/2 draws the Lévy C curve; the three-point scheme with z = 0.45 + 0.4i a spiral.",
        &refs,
        &text,
    );
    Ok(format!("2 attractors, {points} points each"))
}

// ---------------------------------------------------------------------------------------
// helpers

/// Deterministic bumps: amplitude 0.3% of the bounding-box diagonal, wavelength about
/// 3% of it, finer than the base mesh can represent, so every level carries details.
fn with_bumps(soup: &PolygonSoup) -> PolygonSoup {
    let diagonal = bounding_box_diagonal(&soup.positions);
    let (amplitude, frequency) = (0.003 * diagonal, std::f64::consts::TAU / (0.03 * diagonal));
    let mut bumpy = soup.clone();
    for p in &mut bumpy.positions {
        let q = *p * frequency;
        *p += DVec3::new((q.y + 0.3).sin(), (q.z + 1.1).sin(), (q.x + 2.3).sin()) * amplitude;
    }
    bumpy
}

fn max_distance(a: &[DVec3], b: &[DVec3]) -> f64 {
    a.iter().zip(b).map(|(p, q)| p.distance(*q)).fold(0.0, f64::max)
}

/// Renders meshes side by side with one shared camera, from the bunny's viewpoint.
fn write_picture(path: &Path, soups: &[&PolygonSoup]) -> CliResult {
    write_picture_view(path, soups, VIEW)
}

/// Renders meshes side by side with one shared camera from `view` (azimuth, elevation).
fn write_picture_view(path: &Path, soups: &[&PolygonSoup], view: (f64, f64)) -> CliResult {
    let options = RenderOptions {
        width: PANEL.0,
        height: PANEL.1,
        azimuth: view.0,
        elevation: view.1,
        wireframe: soups.iter().all(|s| s.face_count() < 20_000),
        ..RenderOptions::default()
    };
    let all: Vec<DVec3> = soups.iter().flat_map(|s| s.positions.iter().copied()).collect();
    let camera = Camera::framing(&all, view.0, view.1, f64::from(PANEL.0), f64::from(PANEL.1));
    let panels: Vec<Image> = soups
        .iter()
        .map(|soup| {
            let wireframe = soup.face_count() < 20_000;
            render_with_camera(soup, &RenderOptions { wireframe, ..options.clone() }, camera)
        })
        .collect::<CliResult<_>>()?;
    Image::side_by_side(&panels).write_png(path).map_err(|source| CliError::Io { path: path.to_path_buf(), source })
}

fn write_file(path: &Path, bytes: &[u8]) -> CliResult {
    std::fs::write(path, bytes).map_err(|source| CliError::Io { path: path.to_path_buf(), source })
}

/// Appends one section to the HTML page.
fn section(demo: &mut Demo, title: &str, caption: &str, pictures: &[&str], table: &str) {
    let html = &mut demo.html;
    writeln!(html, "<section>\n<h2>{}</h2>\n<p>{caption}</p>", escape(title)).expect("string");
    for picture in pictures {
        writeln!(html, "<img src=\"{picture}\" alt=\"{}\">", escape(picture)).expect("string");
    }
    if !table.is_empty() {
        writeln!(html, "<pre>{}</pre>", escape(table)).expect("string");
    }
    html.push_str("</section>\n");
}

fn escape(text: &str) -> String {
    text.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

fn summary_table(rows: &[(String, String, f64)], total: f64) -> String {
    let width = rows.iter().map(|(step, _, _)| step.len()).max().unwrap_or(0);
    let mut text = format!("\n== summary\n{:<width$}  {:>8}  result\n", "step", "time");
    for (step, result, seconds) in rows {
        writeln!(text, "{step:<width$}  {seconds:>7.2}s  {result}").expect("string");
    }
    writeln!(text, "{:<width$}  {total:>7.2}s", "total").expect("string");
    text
}

/// Marks the page's `<body>` once loaded with the number of images and the broken ones,
/// so a headless browser (`cargo xtask html`) can check that every picture displays.
const IMAGE_CHECK: &str = "<script>\nwindow.addEventListener('load', () => {\n  \
    const images = Array.from(document.images);\n  \
    const broken = images.filter(i => !i.complete || i.naturalWidth === 0).map(i => i.getAttribute('src'));\n  \
    document.body.dataset.images = images.length;\n  \
    document.body.dataset.broken = broken.join(' ');\n  \
    document.body.dataset.checked = 'yes';\n});\n</script>\n";

fn write_index(demo: &Demo, total: f64) -> CliResult {
    let summary = escape(&summary_table(&demo.summary, total));
    let page = format!(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>multires demo</title>\n\
         <style>body{{font-family:sans-serif;max-width:1500px;margin:2em auto;padding:0 1em}}\
         img{{max-width:100%;border:1px solid #ddd;margin:4px}}pre{{background:#f6f6f6;padding:1em}}</style>\n\
         </head>\n<body>\n<h1>multires demo</h1>\n{}<section>\n<h2>Summary</h2>\n<pre>{summary}</pre>\n\
         </section>\n{IMAGE_CHECK}</body>\n</html>\n",
        demo.html
    );
    write_file(&demo.out.join("index.html"), page.as_bytes())
}
