//! Commands on plain meshes: `info`, `compare`, `convert`, `render`, and the demo.

use std::borrow::Cow;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::PathBuf;

use clap::{Args, ValueEnum};
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use mesh_topo::graph::UnionFind;
use mesh_topo::io::{Format, PlyEncoding, ReadReport, WriteOptions};
use mesh_topo::{DVec3, HalfedgeMesh, PolygonSoup};
use multires::ElementCounts;
use serde_json::{Value, json};

use super::common::{io_error, note_dropped, print_out, read_file, read_soup, write_soup};
use super::{CliError, CliResult, input_error};

/// Options of `info`.
#[derive(Debug, Args)]
pub struct InfoArgs {
    /// The mesh (OBJ, OFF or PLY), or a `.mres` pyramid (what it stores, level by level).
    pub mesh: PathBuf,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
}

/// Options of `compare`.
#[derive(Debug, Args)]
pub struct CompareArgs {
    /// First mesh (the reference for relative distances).
    pub a: PathBuf,
    /// Second mesh.
    pub b: PathBuf,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
}

/// PLY encodings for `convert`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum PlyEncodingArg {
    /// Text.
    Ascii,
    /// Binary, little-endian.
    BinaryLe,
    /// Binary, big-endian.
    BinaryBe,
}

/// Options of `convert`.
#[derive(Debug, Args)]
pub struct ConvertArgs {
    /// Input mesh.
    pub input: PathBuf,
    /// Output mesh; the format follows the extension.
    pub out: PathBuf,
    /// Encoding of PLY output.
    #[arg(long, value_enum, default_value = "binary-le")]
    pub ply_encoding: PlyEncodingArg,
}

/// Options of `render`.
#[derive(Debug, Args)]
pub struct RenderArgs {
    /// The mesh.
    pub mesh: PathBuf,
    /// Output PNG.
    pub out: PathBuf,
    /// Image size as WxH.
    #[arg(long, default_value = "800x600")]
    pub size: String,
    /// Overlay the wireframe.
    #[arg(long)]
    pub wireframe: bool,
    /// Flat shading (one normal per face) instead of smooth shading.
    #[arg(long)]
    pub flat: bool,
    /// View direction as azimuth,elevation in degrees.
    #[arg(long, default_value = "30,20", allow_hyphen_values = true)]
    pub view: String,
    /// Further meshes rendered side by side with the first.
    #[arg(long, num_args = 1..)]
    pub side_by_side: Vec<PathBuf>,
}

// ---------------------------------------------------------------------------------------
// info

/// Largest number of unreferenced vertex ids listed (the count is always complete).
const LISTED_UNREFERENCED: usize = 100;
/// Largest number of unreferenced vertex ids the text output lists.
const LISTED_IN_TEXT: usize = 10;
/// Largest number of components detailed in the text output (JSON lists all).
const LISTED_COMPONENTS: usize = 10;

/// Everything `info` reports, as one JSON object (the text output renders the same).
///
/// For a soup that does not build into a half-edge mesh, the counts come from the soup
/// (edges are the distinct unordered vertex pairs of consecutive corners), `manifold` is
/// false with the builder's error, and `boundary_loops` and `genus` are null: they are
/// not defined without a manifold surface.
pub fn mesh_info(file: &str, soup: &PolygonSoup, report: &ReadReport) -> Value {
    let dropped: Vec<Value> = report
        .dropped
        .iter()
        .map(|d| json!({ "what": d.what, "count": d.count, "first": d.first.to_string() }))
        .collect();
    let face_sizes = histogram(soup.faces().map(<[u32]>::len));
    let mut info = match HalfedgeMesh::from_soup(soup) {
        Ok(mesh) => {
            let stats = mesh.topology_stats();
            json!({
                "vertices": stats.vertices,
                "edges": stats.edges,
                "faces": stats.faces,
                "face_sizes": stats.face_sizes,
                "valences": stats.valences,
                "boundary_edges": stats.boundary_edges,
                "boundary_loops": stats.boundary_loops,
                "components": stats.components,
                "euler": stats.euler,
                "genus": stats.genus,
                "manifold": true,
                "manifold_error": null,
                "unreferenced_vertices": stats.isolated_vertices.len(),
                "unreferenced_vertex_ids": &stats.isolated_vertices[..stats.isolated_vertices.len().min(LISTED_UNREFERENCED)],
                "per_component": stats.per_component,
            })
        }
        Err(error) => {
            let soup_stats = SoupStats::of(soup);
            json!({
                "vertices": soup.vertex_count(),
                "edges": soup_stats.edges,
                "faces": soup.face_count(),
                "face_sizes": face_sizes,
                "valences": soup_stats.valences,
                "boundary_edges": soup_stats.boundary_edges,
                "boundary_loops": null,
                "components": soup_stats.components,
                "euler": soup.vertex_count() as i64 - soup_stats.edges as i64 + soup.face_count() as i64,
                "genus": null,
                "manifold": false,
                "manifold_error": error.to_string(),
                "unreferenced_vertices": soup_stats.unreferenced.len(),
                "unreferenced_vertex_ids": &soup_stats.unreferenced[..soup_stats.unreferenced.len().min(LISTED_UNREFERENCED)],
                "per_component": [],
            })
        }
    };
    info["file"] = json!(file);
    info["format"] = json!(report.format.to_string());
    info["ply_encoding"] = json!(report.ply_encoding.map(PlyEncoding::header_name));
    info["dropped"] = json!(dropped);
    info
}

fn histogram(values: impl Iterator<Item = usize>) -> BTreeMap<usize, usize> {
    let mut counts = BTreeMap::new();
    for value in values {
        *counts.entry(value).or_insert(0) += 1;
    }
    counts
}

/// Counts of a soup that is not a manifold mesh.
struct SoupStats {
    edges: usize,
    boundary_edges: usize,
    components: usize,
    valences: BTreeMap<usize, usize>,
    unreferenced: Vec<u32>,
}

impl SoupStats {
    fn of(soup: &PolygonSoup) -> Self {
        let n = soup.vertex_count();
        // Every side of every face as an unordered pair; sorted, runs are edges.
        let mut sides: Vec<(u32, u32)> = Vec::with_capacity(soup.indices.len());
        for face in soup.faces() {
            for (k, &a) in face.iter().enumerate() {
                let b = face[(k + 1) % face.len()];
                if a != b {
                    sides.push((a.min(b), a.max(b)));
                }
            }
        }
        sides.sort_unstable();
        let mut valence = vec![0usize; n];
        let mut used = vec![false; n];
        let mut sets = UnionFind::new(n);
        let (mut edges, mut boundary_edges) = (0, 0);
        for run in sides.chunk_by(|x, y| x == y) {
            let (a, b) = run[0];
            edges += 1;
            boundary_edges += usize::from(run.len() == 1);
            valence[a as usize] += 1;
            valence[b as usize] += 1;
            sets.union(a, b);
        }
        for &v in &soup.indices {
            used[v as usize] = true;
        }
        let mut roots: Vec<u32> = (0..n as u32).filter(|&v| used[v as usize]).map(|v| sets.find(v)).collect();
        roots.sort_unstable();
        roots.dedup();
        Self {
            edges,
            boundary_edges,
            components: roots.len(),
            valences: histogram((0..n).filter(|&v| used[v]).map(|v| valence[v])),
            unreferenced: (0..n as u32).filter(|&v| !used[v as usize]).collect(),
        }
    }
}

fn histogram_text(value: &Value) -> String {
    let Some(map) = value.as_object() else { return "-".into() };
    if map.is_empty() {
        return "none".into();
    }
    // JSON object keys are strings; order them numerically.
    let mut pairs: Vec<(u64, &Value)> = map.iter().filter_map(|(k, v)| Some((k.parse().ok()?, v))).collect();
    pairs.sort_by_key(|&(k, _)| k);
    pairs.iter().map(|(k, v)| format!("{k}: {v}")).collect::<Vec<_>>().join(", ")
}

/// The text rendering of [`mesh_info`].
pub fn mesh_info_text(info: &Value) -> String {
    let mut text = String::new();
    let mut line = |label: &str, value: String| {
        let _ = writeln!(text, "{label:<14}{value}");
    };
    let number = |key: &str| info[key].to_string();
    let format = match info["ply_encoding"].as_str() {
        Some(encoding) => format!("{}, {encoding}", info["format"].as_str().unwrap_or("?")),
        None => info["format"].as_str().unwrap_or("?").to_string(),
    };
    line("file", format!("{} ({format})", info["file"].as_str().unwrap_or("?")));
    line("vertices", number("vertices"));
    line("edges", number("edges"));
    line("faces", number("faces"));
    line("face sizes", histogram_text(&info["face_sizes"]));
    line("valences", histogram_text(&info["valences"]));
    let boundary = if info["boundary_loops"].is_null() {
        format!("{} edges (loops undefined: not manifold)", number("boundary_edges"))
    } else {
        format!("{} loops, {} edges", number("boundary_loops"), number("boundary_edges"))
    };
    line("boundary", boundary);
    line("components", number("components"));
    line("euler", number("euler"));
    let genus = if info["genus"].is_null() { "undefined (not manifold)".to_string() } else { number("genus") };
    line("genus", genus);
    let manifold = match info["manifold_error"].as_str() {
        None => "yes".to_string(),
        Some(error) => format!("no: {error}"),
    };
    line("manifold", manifold);
    let unreferenced = info["unreferenced_vertices"].as_u64().unwrap_or(0) as usize;
    let ids: Vec<String> = info["unreferenced_vertex_ids"]
        .as_array()
        .map(|ids| ids.iter().take(LISTED_IN_TEXT).map(Value::to_string).collect())
        .unwrap_or_default();
    let listed = match unreferenced {
        0 => "0".to_string(),
        n if n > ids.len() => format!("{n} (first {}: {}, ...)", ids.len(), ids.join(", ")),
        n => format!("{n} ({})", ids.join(", ")),
    };
    line("unreferenced", listed);
    let dropped = info["dropped"].as_array().cloned().unwrap_or_default();
    if dropped.is_empty() {
        line("not kept", "nothing".into());
    }
    for (i, d) in dropped.iter().enumerate() {
        let what = format!(
            "{} x {} (first at {})",
            d["count"],
            d["what"].as_str().unwrap_or("?"),
            d["first"].as_str().unwrap_or("?")
        );
        line(if i == 0 { "not kept" } else { "" }, what);
    }
    let components = info["per_component"].as_array().cloned().unwrap_or_default();
    if components.len() > 1 {
        for (i, c) in components.iter().take(LISTED_COMPONENTS).enumerate() {
            line(
                if i == 0 { "per component" } else { "" },
                format!(
                    "#{i}: {} vertices, {} edges, {} faces, {} boundary loops, euler {}, genus {}",
                    c["vertices"], c["edges"], c["faces"], c["boundary_loops"], c["euler"], c["genus"]
                ),
            );
        }
        if components.len() > LISTED_COMPONENTS {
            line("", format!("... {} more (see --json)", components.len() - LISTED_COMPONENTS));
        }
    }
    text
}

/// `multires info`: a mesh, or a `.mres` pyramid.
pub fn info(args: &InfoArgs) -> CliResult {
    let is_pyramid = args.mesh.extension().is_some_and(|e| e.eq_ignore_ascii_case("mres"));
    let (info, text): (Value, fn(&Value) -> String) = if is_pyramid {
        let bytes = read_file(&args.mesh)?;
        let pyramid = multires::Pyramid::from_bytes(&bytes)
            .map_err(|e| CliError::Input(format!("{}: {e}", args.mesh.display())))?;
        (pyramid_info(&args.mesh.display().to_string(), bytes.len(), &pyramid), pyramid_info_text)
    } else {
        let (soup, report) = read_soup(&args.mesh)?;
        (mesh_info(&args.mesh.display().to_string(), &soup, &report), mesh_info_text)
    };
    if args.json {
        print_out(&(serde_json::to_string_pretty(&info).expect("internal: JSON of plain values") + "\n"))
    } else {
        print_out(&text(&info))
    }
}

/// What a pyramid holds, level by level, read from the pyramid alone (nothing is
/// rebuilt): the base mesh, then for each level its detail vectors (count, largest and
/// root-mean-square length) and the vertex count they bring the mesh to (coarser
/// vertices plus details: both reversals store exactly one vector per fine vertex),
/// with the face count where the counts of the scheme's steps fix it
/// ([`SurfaceScheme::closed_counts`](multires::SurfaceScheme::closed_counts): on a closed
/// base mesh without isolated vertices, and for Loop on any, as its face count only
/// quadruples) and whether the level keeps a vertex and face order of its own (a mesh
/// that was not in the canonical order when decomposed).
pub fn pyramid_info(file: &str, bytes: usize, pyramid: &multires::Pyramid) -> Value {
    let base = pyramid.base();
    let levels: Vec<(&[DVec3], bool)> = match pyramid {
        multires::Pyramid::Loop(p) => p.levels.iter().map(|l| (&l.details[..], l.order.is_none())).collect(),
        multires::Pyramid::Doo(p) => p.levels.iter().map(|l| (&l.details[..], l.order.is_identity())).collect(),
    };
    // The base's counts, if its faces follow from them at every level.
    let base_counts = HalfedgeMesh::from_soup(base).ok().and_then(|mesh| {
        let closed = mesh.vertices().all(|v| !mesh.is_isolated(v) && !mesh.is_boundary_vertex(v));
        let loop_family = matches!(pyramid, multires::Pyramid::Loop(_));
        (closed || loop_family).then(|| ElementCounts::of(&mesh))
    });
    let mut vertices = base.vertex_count();
    let mut rows = Vec::with_capacity(levels.len());
    for (k, (details, canonical)) in levels.into_iter().enumerate() {
        vertices += details.len();
        let faces = base_counts.map(|counts| pyramid.scheme().closed_counts(counts, k as u32 + 1).faces);
        let (largest_squared, sum_squared) = details
            .iter()
            .map(|d| d.length_squared())
            .fold((0.0f64, 0.0f64), |(largest, sum), squared| (largest.max(squared), sum + squared));
        let rms = if details.is_empty() { 0.0 } else { (sum_squared / details.len() as f64).sqrt() };
        rows.push(json!({
            "level": k + 1,
            "vertices": vertices,
            "faces": faces,
            "details": details.len(),
            "largest_detail": largest_squared.sqrt(),
            "rms_detail": rms,
            "canonical_order": canonical,
        }));
    }
    let boundary = match pyramid {
        multires::Pyramid::Loop(_) => Value::Null,
        multires::Pyramid::Doo(p) => json!(p.boundary.to_string()),
    };
    json!({
        "file": file,
        "bytes": bytes,
        "kind": "pyramid",
        "scheme": pyramid.scheme().name(),
        "boundary_rule": boundary,
        "base": { "vertices": base.vertex_count(), "faces": base.face_count() },
        "levels": rows,
        "details": pyramid.detail_count(),
        "finest_vertices": vertices,
    })
}

/// The text of [`pyramid_info`], laid out as [`mesh_info_text`].
fn pyramid_info_text(info: &Value) -> String {
    let mut text = String::new();
    let mut line = |label: &str, value: String| {
        let _ = writeln!(text, "{label:<14}{value}");
    };
    let levels = info["levels"].as_array().map_or(&[][..], Vec::as_slice);
    let boundary = info["boundary_rule"].as_str().map_or(String::new(), |rule| format!(", {rule} boundary"));
    line("file", format!("{} ({} bytes)", info["file"].as_str().unwrap_or("?"), info["bytes"]));
    let scheme = info["scheme"].as_str().unwrap_or("?");
    line("pyramid", format!("{scheme}{boundary}: a base mesh and {} level(s) of details", levels.len()));
    line("level 0", format!("{} vertices, {} faces (the base mesh)", info["base"]["vertices"], info["base"]["faces"]));
    for row in levels {
        let faces = row["faces"].as_u64().map_or(String::new(), |f| format!(", {f} faces"));
        let order = if row["canonical_order"] == false { "; keeps its own vertex and face order" } else { "" };
        let length = |key: &str| row[key].as_f64().unwrap_or(f64::NAN);
        line(
            &format!("level {}", row["level"]),
            format!(
                "{} vertices{faces}: {} details, largest {:.3e}, rms {:.3e}{order}",
                row["vertices"],
                row["details"],
                length("largest_detail"),
                length("rms_detail")
            ),
        );
    }
    line(
        "details",
        format!(
            "{} in all (base vertices + details = {}, the finest mesh's vertex count)",
            info["details"], info["finest_vertices"]
        ),
    );
    text
}

// ---------------------------------------------------------------------------------------
// compare

/// Nearest-vertex distances from every point of `from` to the set `to`, in `from` order.
fn nearest_distances(from: &[DVec3], to: &[DVec3]) -> CliResult<Vec<f64>> {
    let points: Vec<[f64; 3]> = to.iter().map(|p| p.to_array()).collect();
    let tree: ImmutableKdTree<f64, 3> = ImmutableKdTree::new_from_slice(&points)
        .map_err(|e| input_error("cannot build the spatial index", format!("{e:?}")))?;
    let queries: Vec<[f64; 3]> = from.iter().map(|p| p.to_array()).collect();
    // Batch results are indexed like the queries, whatever the thread count.
    let nearest = tree.query_batch(&queries).nearest_one::<SquaredEuclidean<f64>>().execute();
    Ok(nearest.iter().map(|n| n.distance.sqrt()).collect())
}

/// Max and mean of distances (summed in index order: deterministic).
fn max_and_sum(distances: &[f64]) -> (f64, f64) {
    distances.iter().fold((0.0f64, 0.0f64), |(max, sum), &d| (max.max(d), sum + d))
}

fn bbox_diagonal(points: &[DVec3]) -> f64 {
    let (lo, hi) = points
        .iter()
        .fold((DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    (hi - lo).length()
}

/// The positions of `soup` times `scale` (borrowed when it is 1).
fn scaled_points(soup: &PolygonSoup, scale: f64) -> Cow<'_, [DVec3]> {
    if scale == 1.0 { Cow::Borrowed(&soup.positions) } else { soup.positions.iter().map(|p| *p * scale).collect() }
}

/// The comparison of two meshes' vertex sets, as `compare --json` prints it: for each
/// vertex of one mesh the distance to the nearest vertex of the other (a k-d tree,
/// `kiddo`), both ways; `max_dist` is the larger one-sided maximum (Hausdorff distance
/// of the vertex sets), `mean_dist` the average of the two one-sided means; `rel_*`
/// divide by the diagonal of A's bounding box (null when that box is a point).
pub fn compare_meshes(a_name: &str, a: &PolygonSoup, b_name: &str, b: &PolygonSoup) -> CliResult<Value> {
    for (name, soup) in [(a_name, a), (b_name, b)] {
        if soup.positions.is_empty() {
            return Err(CliError::Input(format!("{name}: the mesh has no vertices to compare")));
        }
    }
    // Measured at unit scale (see `mesh_topo::scale`: two meshes at 1e-181 compared
    // as equal, each box "a point"), reported in the meshes' units.
    let scale = mesh_topo::scale::unit_scale(a.positions.iter().chain(&b.positions));
    let scaled = |soup| scaled_points(soup, scale);
    let (a_points, b_points) = (scaled(a), scaled(b));
    let a_to_b = nearest_distances(&a_points, &b_points)?;
    let b_to_a = nearest_distances(&b_points, &a_points)?;
    let (max_ab, sum_ab) = max_and_sum(&a_to_b);
    let (max_ba, sum_ba) = max_and_sum(&b_to_a);
    let (mean_ab, mean_ba) = (sum_ab / a_to_b.len() as f64, sum_ba / b_to_a.len() as f64);
    // Symmetric: the larger of the two one-sided maxima (the Hausdorff distance between
    // the vertex sets), the average of the two one-sided means (so neither mesh's
    // vertex count weighs more).
    let max_dist = max_ab.max(max_ba);
    let mean_dist = 0.5 * (mean_ab + mean_ba);
    let diagonal = bbox_diagonal(&a_points);
    let relative = |d: f64| if diagonal > 0.0 { json!(d / diagonal) } else { Value::Null };
    let unscaled = |d: f64| d / scale;
    let (max_ab, mean_ab, max_ba, mean_ba) = (unscaled(max_ab), unscaled(mean_ab), unscaled(max_ba), unscaled(mean_ba));
    if let Some(too_far) = [max_ab, max_ba, diagonal / scale].into_iter().find(|d| !d.is_finite()) {
        return Err(CliError::Input(format!(
            "{a_name} and {b_name}: a distance between their vertices is {too_far}, beyond the f64 range \
             (coordinates near f64::MAX); scale both meshes down"
        )));
    }
    Ok(json!({
        "a": { "file": a_name, "vertices": a.vertex_count(), "faces": a.face_count() },
        "b": { "file": b_name, "vertices": b.vertex_count(), "faces": b.face_count() },
        "bbox_diagonal_a": unscaled(diagonal),
        "max_dist": unscaled(max_dist),
        "mean_dist": unscaled(mean_dist),
        "rel_max": relative(max_dist),
        "rel_mean": relative(mean_dist),
        "a_to_b": { "max": max_ab, "mean": mean_ab },
        "b_to_a": { "max": max_ba, "mean": mean_ba },
    }))
}

/// `multires compare`.
pub fn compare(args: &CompareArgs) -> CliResult {
    let (a, a_report) = read_soup(&args.a)?;
    let (b, b_report) = read_soup(&args.b)?;
    note_dropped(&args.a, &a_report);
    note_dropped(&args.b, &b_report);
    let (a_name, b_name) = (args.a.display().to_string(), args.b.display().to_string());
    let result = compare_meshes(&a_name, &a, &b_name, &b)?;
    if args.json {
        return print_out(&(serde_json::to_string_pretty(&result).expect("internal: JSON of plain values") + "\n"));
    }
    let relative = |key: &str| match result[key].as_f64() {
        Some(r) => format!("{r:.3e} of A's bounding-box diagonal"),
        None => "n/a (A's bounding box is a point)".to_string(),
    };
    let mut text = String::new();
    let _ = writeln!(text, "A             {a_name}: {} vertices, {} faces", a.vertex_count(), a.face_count());
    let _ = writeln!(text, "B             {b_name}: {} vertices, {} faces", b.vertex_count(), b.face_count());
    let _ = writeln!(text, "A diagonal    {}", result["bbox_diagonal_a"]);
    let _ = writeln!(
        text,
        "max distance  {:.6e} ({})",
        result["max_dist"].as_f64().unwrap_or(f64::NAN),
        relative("rel_max")
    );
    let _ = writeln!(
        text,
        "mean distance {:.6e} ({})",
        result["mean_dist"].as_f64().unwrap_or(f64::NAN),
        relative("rel_mean")
    );
    let _ = writeln!(
        text,
        "A -> B        max {:.6e}, mean {:.6e}",
        result["a_to_b"]["max"].as_f64().unwrap_or(f64::NAN),
        result["a_to_b"]["mean"].as_f64().unwrap_or(f64::NAN)
    );
    let _ = writeln!(
        text,
        "B -> A        max {:.6e}, mean {:.6e}",
        result["b_to_a"]["max"].as_f64().unwrap_or(f64::NAN),
        result["b_to_a"]["mean"].as_f64().unwrap_or(f64::NAN)
    );
    print_out(&text)
}

// ---------------------------------------------------------------------------------------
// convert

/// `multires convert`.
pub fn convert(args: &ConvertArgs) -> CliResult {
    // Check the output name before reading a possibly large input.
    let format = Format::from_path(&args.out).map_err(|e| io_error(&args.out, e))?;
    let (soup, report) = read_soup(&args.input)?;
    note_dropped(&args.input, &report);
    let ply_encoding = match args.ply_encoding {
        PlyEncodingArg::Ascii => PlyEncoding::Ascii,
        PlyEncodingArg::BinaryLe => PlyEncoding::BinaryLittleEndian,
        PlyEncodingArg::BinaryBe => PlyEncoding::BinaryBigEndian,
    };
    write_soup(&args.out, &soup, &WriteOptions { ply_encoding })?;
    print_out(&format!(
        "wrote {} ({format}): {} vertices, {} faces\n",
        args.out.display(),
        soup.vertex_count(),
        soup.face_count()
    ))
}

// ---------------------------------------------------------------------------------------
// render

/// `multires render`.
pub fn render(args: &RenderArgs) -> CliResult {
    super::render::run(args)
}
