//! Project automation, run as `cargo xtask <task>`.
//!
//! - `ci`: everything CI checks, in order, stopping at the first failure: formatting,
//!   clippy with warnings denied, the layering rules, the dependency diet of each library
//!   crate, all tests and doctests, docs (public and internal) with warnings denied, and
//!   that benches compile.
//! - `bench [crate]`: runs the criterion benches and prints a compact table, then compares
//!   the `subdivide-*` benchmarks with the peer libraries found on the machine (see
//!   `peers.rs`; `MULTIRES_PEERS_DIR`); both are written to `target/bench-summary.md`.
//! - `html`: runs the demo and opens its `index.html` in headless Chromium, checking that
//!   every picture on the page loads (part of `ci` when a browser is installed).
//! - `golden [--bless]`: checks the golden files under `tests/golden/`, or re-blesses them
//!   and shows the diff for review.

use std::collections::BTreeMap;
use std::env;
use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};
use std::time::{Duration, Instant, SystemTime};

mod peers;

/// Project crates each crate may depend on (normal dependencies). The facade may use
/// all of them; a crate missing from this table is an error, so new crates must state
/// their place in the layering.
const LAYERS: &[(&str, &[&str])] = &[
    ("mesh-topo", &[]),
    ("subdiv-curve", &[]),
    ("subdiv-loop", &["mesh-topo"]),
    ("subdiv-doo", &["mesh-topo", "subdiv-curve"]),
    ("tri-spline", &["mesh-topo", "subdiv-loop"]),
    ("ifs-nonlinear", &["subdiv-curve"]),
    ("multires", &["mesh-topo", "subdiv-curve", "subdiv-loop", "subdiv-doo", "tri-spline", "ifs-nonlinear"]),
    ("xtask", &[]),
];

/// Heavy application-level crates no library crate may pull in (they belong to the CLI).
const CLI_ONLY_DEPENDENCIES: &[&str] = &["clap", "image", "plotters", "indicatif"];

fn main() -> ExitCode {
    let args: Vec<String> = env::args().skip(1).collect();
    let result = match args.first().map(String::as_str) {
        Some("ci") => ci(),
        Some("bench") => {
            // `bench [crate] [-- criterion arguments]`, e.g. `bench multires -- subdivide-bunny00/loop`.
            let (ours, passed) = args[1..].split_at(args[1..].iter().position(|a| a == "--").unwrap_or(args.len() - 1));
            bench(ours.first().map(String::as_str), passed)
        }
        Some("golden") => golden(args.iter().any(|a| a == "--bless")),
        Some("layering") => layering(),
        Some("html") => browser()
            .ok_or_else(|| "html: no `chromium` or `chromium-browser` on the PATH".to_string())
            .and_then(|b| html(&b)),
        _ => {
            eprintln!("usage: cargo xtask ci | bench [crate] [-- filter] | golden [--bless] | layering | html");
            return ExitCode::from(2);
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("xtask: {message}");
            ExitCode::FAILURE
        }
    }
}

fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().expect("xtask lives in the workspace").to_path_buf()
}

/// Cargo's target directory: `$CARGO_TARGET_DIR` when set, else `target/`.
fn target_dir() -> PathBuf {
    env::var_os("CARGO_TARGET_DIR").map(PathBuf::from).unwrap_or_else(|| workspace_root().join("target"))
}

fn cargo() -> Command {
    let mut command = Command::new(env::var("CARGO").unwrap_or_else(|_| "cargo".into()));
    command.current_dir(workspace_root());
    command
}

fn run(step: &str, command: &mut Command) -> Result<(), String> {
    eprintln!("==> {step}");
    let start = Instant::now();
    let status = command.status().map_err(|e| format!("{step}: cannot start: {e}"))?;
    eprintln!("    {step}: {:.1} s", start.elapsed().as_secs_f64());
    if status.success() { Ok(()) } else { Err(format!("{step} failed ({status})")) }
}

fn ci() -> Result<(), String> {
    let total = Instant::now();
    run("fmt", cargo().args(["fmt", "--all", "--", "--check"]))?;
    run("clippy", cargo().args(["clippy", "--workspace", "--all-targets", "--", "-D", "warnings"]))?;
    layering()?;
    run("test", cargo().args(["test", "--workspace"]))?;
    run("doc", cargo().args(["doc", "--workspace", "--no-deps"]).env("RUSTDOCFLAGS", "-D warnings"))?;
    // The internal docs' links too (a renamed private function left them dangling); the
    // public run above stays, as it is the one that flags public docs linking to private
    // items.
    let private = ["doc", "--workspace", "--no-deps", "--document-private-items"];
    run("doc (private items)", cargo().args(private).env("RUSTDOCFLAGS", "-D warnings"))?;
    // The benches are type-checked by clippy above; this links them too, in the test
    // profile whose dependencies the test step already built (a release build of every
    // bench would double the time of the whole run).
    run("benches build", cargo().args(["test", "--workspace", "--benches", "--no-run"]))?;
    match browser() {
        Some(browser) => html(&browser)?,
        None => eprintln!("==> html: skipped, no headless browser (install Debian's `chromium`)"),
    }
    eprintln!("==> ci passed in {:.0} s", total.elapsed().as_secs_f64());
    Ok(())
}

fn cargo_metadata() -> Result<serde_json::Value, String> {
    let output =
        cargo().args(["metadata", "--format-version", "1"]).output().map_err(|e| format!("cargo metadata: {e}"))?;
    if !output.status.success() {
        return Err(format!("cargo metadata failed: {}", String::from_utf8_lossy(&output.stderr)));
    }
    serde_json::from_slice(&output.stdout).map_err(|e| format!("cargo metadata output: {e}"))
}

/// Checks the dependency arrows between project crates, and that no library crate
/// depends (normally, transitively) on a CLI-only crate.
fn layering() -> Result<(), String> {
    eprintln!("==> layering");
    let metadata = cargo_metadata()?;
    let members: Vec<String> = metadata["workspace_members"]
        .as_array()
        .ok_or("metadata: no workspace_members")?
        .iter()
        .filter_map(|m| m.as_str().map(str::to_string))
        .collect();
    let packages = metadata["packages"].as_array().ok_or("metadata: no packages")?;
    let project_names: Vec<&str> = packages
        .iter()
        .filter(|p| members.iter().any(|m| Some(m.as_str()) == p["id"].as_str()))
        .filter_map(|p| p["name"].as_str())
        .collect();
    let mut problems = Vec::new();
    for package in packages {
        let Some(name) = package["name"].as_str() else { continue };
        if !project_names.contains(&name) {
            continue;
        }
        let Some((_, allowed)) = LAYERS.iter().find(|(crate_name, _)| *crate_name == name) else {
            problems.push(format!("crate `{name}` is not in the layering table (xtask/src/main.rs)"));
            continue;
        };
        for dependency in package["dependencies"].as_array().into_iter().flatten() {
            let dep_name = dependency["name"].as_str().unwrap_or_default();
            let is_normal = dependency["kind"].is_null();
            if is_normal && project_names.contains(&dep_name) && !allowed.contains(&dep_name) {
                problems.push(format!("`{name}` must not depend on `{dep_name}`"));
            }
        }
    }
    // Dependency diet: a user depending on one library crate gets no CLI machinery.
    let library_crates: Vec<&str> =
        project_names.iter().copied().filter(|n| *n != "multires" && *n != "xtask").collect();
    for name in library_crates {
        let output = cargo()
            .args(["tree", "-p", name, "-e", "normal", "--prefix", "none", "--format", "{p}"])
            .output()
            .map_err(|e| format!("cargo tree: {e}"))?;
        let tree = String::from_utf8_lossy(&output.stdout);
        for line in tree.lines() {
            let dep = line.split_whitespace().next().unwrap_or_default();
            if CLI_ONLY_DEPENDENCIES.contains(&dep) {
                problems.push(format!("`{name}` pulls in `{dep}` (a CLI-only dependency)"));
            }
        }
    }
    if problems.is_empty() {
        eprintln!("    layering: ok ({} crates)", project_names.len());
        Ok(())
    } else {
        Err(format!("layering:\n  {}", problems.join("\n  ")))
    }
}

/// Runs the criterion benches (`passed` starts with `--` and goes to criterion, e.g. a
/// filter) and summarises every result under `target/criterion`, including earlier runs';
/// the comparison with the peers takes only this run's results, so that every ratio
/// compares times of the same minutes.
fn bench(krate: Option<&str>, passed: &[String]) -> Result<(), String> {
    // Criterion's files have whole-second times on some file systems.
    let started = SystemTime::now() - Duration::from_secs(1);
    let mut command = cargo();
    command.arg("bench");
    match krate {
        Some(name) => command.args(["-p", name]),
        None => command.arg("--workspace"),
    };
    command.args(passed);
    run("bench", &mut command)?;
    let criterion_dir = target_dir().join("criterion");
    let mut rows = BTreeMap::new();
    let mut written = BTreeMap::new();
    collect_estimates(&criterion_dir, &criterion_dir, &mut rows, &mut written);
    let mut table = String::from("| benchmark | mean | fastest sample | throughput (mean) |\n|---|---:|---:|---:|\n");
    for (name, measurement) in &rows {
        let throughput = measurement.elements.map(|n| format_throughput(n, measurement.mean_ns)).unwrap_or_default();
        let best = measurement.best_ns.map(format_time).unwrap_or_else(|| "–".into());
        table.push_str(&format!("| {name} | {} | {best} | {throughput} |\n", format_time(measurement.mean_ns)));
    }
    println!("{table}");
    // The test meshes, and the ones the benchmarks make (`target/bench-meshes/`).
    let folders = [workspace_root().join("tests/data"), target_dir().join("bench-meshes")];
    let mesh_file = |mesh: &str| {
        folders
            .iter()
            .flat_map(|folder| ["obj", "off", "ply"].map(|ext| folder.join(format!("{mesh}.{ext}"))))
            .find(|p| p.is_file())
    };
    let this_run: BTreeMap<String, peers::Measurement> = rows
        .iter()
        .filter(|(id, _)| written.get(*id).is_some_and(|&time| time >= started))
        .map(|(id, measurement)| (id.clone(), measurement.clone()))
        .collect();
    let comparison = peers::comparison(&this_run, mesh_file);
    println!("{comparison}");
    let summary = target_dir().join("bench-summary.md");
    fs::write(&summary, format!("# Benchmark summary\n\n{table}\n{comparison}"))
        .map_err(|e| format!("{}: {e}", summary.display()))?;
    eprintln!("    written to {}", summary.display());
    Ok(())
}

/// Finds `<id>/new/estimates.json` under the criterion directory: mean time and, when
/// the benchmark declared one, its throughput in elements; and in `written`, when the
/// estimates were written.
fn collect_estimates(
    root: &Path,
    dir: &Path,
    rows: &mut BTreeMap<String, peers::Measurement>,
    written: &mut BTreeMap<String, SystemTime>,
) {
    let Ok(entries) = fs::read_dir(dir) else { return };
    for entry in entries.flatten() {
        let path = entry.path();
        if !path.is_dir() {
            continue;
        }
        if path.file_name().is_some_and(|n| n == "new") {
            let read_json = |name: &str| {
                fs::read_to_string(path.join(name))
                    .ok()
                    .and_then(|s| serde_json::from_str::<serde_json::Value>(&s).ok())
            };
            let Some(mean_ns) = read_json("estimates.json").and_then(|v| v["mean"]["point_estimate"].as_f64()) else {
                continue;
            };
            let elements = read_json("benchmark.json").and_then(|v| v["throughput"]["Elements"].as_f64());
            let best_ns = read_json("sample.json").and_then(|v| fastest_sample_ns(&v));
            let id = dir.strip_prefix(root).unwrap_or(dir).display().to_string();
            if let Ok(time) = fs::metadata(path.join("estimates.json")).and_then(|m| m.modified()) {
                written.insert(id.clone(), time);
            }
            rows.insert(id, peers::Measurement { mean_ns, best_ns, elements });
        } else if path.file_name().is_some_and(|n| n != "report") {
            collect_estimates(root, &path, rows, written);
        }
    }
}

/// The time per iteration of the fastest sample in criterion's `sample.json` (each
/// sample is `iters[i]` iterations taking `times[i]` ns in all): the counterpart of the
/// peers' best-of time, as steady as a best-of gets under load (a sample still averages
/// several calls, so it is never below our fastest single call).
fn fastest_sample_ns(sample: &serde_json::Value) -> Option<f64> {
    let (iters, times) = (sample["iters"].as_array()?, sample["times"].as_array()?);
    iters
        .iter()
        .zip(times)
        .filter_map(|(n, t)| Some(t.as_f64()? / n.as_f64()?))
        .filter(|t| t.is_finite() && *t > 0.0)
        .reduce(f64::min)
}

fn format_throughput(elements: f64, mean_ns: f64) -> String {
    format!("{:.2} M elem/s", elements / (mean_ns * 1e-9) / 1e6)
}

fn format_time(ns: f64) -> String {
    match ns {
        t if t < 1e3 => format!("{t:.1} ns"),
        t if t < 1e6 => format!("{:.2} µs", t / 1e3),
        t if t < 1e9 => format!("{:.2} ms", t / 1e6),
        t => format!("{:.3} s", t / 1e9),
    }
}

fn golden(bless: bool) -> Result<(), String> {
    let mut command = cargo();
    // Every `tests/golden*.rs` target of the facade.
    command.args(["test", "-p", "multires", "--test", "golden*"]);
    if bless {
        command.env("MULTIRES_BLESS", "1");
    }
    run(if bless { "golden --bless" } else { "golden" }, &mut command)?;
    if bless {
        // Show what changed so the re-bless is reviewed, not rubber-stamped.
        let _ =
            Command::new("git").current_dir(workspace_root()).args(["diff", "--stat", "--", "tests/golden"]).status();
        eprintln!("    review the changes with: git diff tests/golden");
    }
    Ok(())
}

/// The headless browser used by [`html`], if one is installed.
fn browser() -> Option<PathBuf> {
    let path = env::var_os("PATH")?;
    env::split_paths(&path)
        .flat_map(|dir| ["chromium", "chromium-browser"].map(|name| dir.join(name)))
        .find(|candidate| candidate.is_file())
}

/// Runs the demo into `target/demo-html` and loads its page in headless Chromium. The page
/// marks its `<body>` with the number of images and the broken ones once loaded.
fn html(browser: &Path) -> Result<(), String> {
    let out = target_dir().join("demo-html");
    let _ = fs::remove_dir_all(&out);
    run("html: demo", cargo().args(["run", "--quiet", "--", "demo", "--out"]).arg(&out))?;
    let page = out.join("index.html");
    let source = fs::read_to_string(&page).map_err(|e| format!("{}: {e}", page.display()))?;
    let expected_images = source.matches("<img ").count();
    eprintln!("==> html: {} in {}", page.display(), browser.display());
    let output = Command::new(browser)
        .args(["--headless", "--no-sandbox", "--disable-gpu", "--allow-file-access-from-files"])
        .args(["--virtual-time-budget=10000", "--dump-dom"])
        .arg(format!("file://{}", page.display()))
        .output()
        .map_err(|e| format!("html: cannot start {}: {e}", browser.display()))?;
    let dom = String::from_utf8_lossy(&output.stdout);
    let attribute = |name: &str| {
        let key = format!("data-{name}=\"");
        dom.find(&key).map(|start| {
            let rest = &dom[start + key.len()..];
            rest[..rest.find('"').unwrap_or(0)].to_string()
        })
    };
    if attribute("checked").as_deref() != Some("yes") {
        return Err(format!("html: the page did not finish loading in the browser: {}", output.status));
    }
    let images: usize = attribute("images").and_then(|n| n.parse().ok()).unwrap_or(0);
    let broken = attribute("broken").unwrap_or_default();
    if images != expected_images || !broken.is_empty() {
        return Err(format!("html: {images} of {expected_images} images found; broken: [{broken}]"));
    }
    eprintln!("    html: all {images} pictures load in the browser");
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fastest_sample_is_the_least_time_per_iteration() {
        let sample =
            serde_json::json!({"sampling_mode": "Linear", "iters": [2.0, 4.0, 6.0], "times": [30.0, 48.0, 90.0]});
        assert_eq!(fastest_sample_ns(&sample), Some(12.0));
        // Missing or malformed samples give nothing rather than a made-up time.
        assert_eq!(fastest_sample_ns(&serde_json::json!({"iters": [1.0]})), None);
        assert_eq!(fastest_sample_ns(&serde_json::json!({"iters": [0.0], "times": [5.0]})), None);
    }
}
