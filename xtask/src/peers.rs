//! Same-run comparison of the `subdivide-*` benchmarks with peer libraries.
//!
//! The peers are small command-line drivers that time the subdivision call alone
//! (reading and writing excluded), like our criterion benchmarks, in one of two protocols:
//! - the C++ drivers around OpenSubdiv, CGAL and OpenMesh:
//!   `<driver> <scheme> <in> <out|-> <level> [repeats] [budget_s]` prints one JSON line
//!   whose `t_sub_best_s` is the best time;
//! - `rust-peers`, one program for the Rust crates (opensubdiv-rs, subdiv-kernels, alum):
//!   `rust-peers <crate> <scheme> <in> <out|-> <level> --repeat N --budget-s S` prints
//!   `crate scheme levels in_faces out_verts out_faces best_ms median_ms`.
//!
//! The drivers are looked up in `$MULTIRES_PEERS_DIR`, `$MULTIRES_PEERS_DIR/build`,
//! `$MULTIRES_PEERS_DIR/rust-peers/target/release` and the `PATH`; a missing driver is
//! skipped with a note, so the command works on a bare machine too.
//!
//! Variants of one of our schemes are compared with the peers' runs of the scheme itself:
//! `loop-reuse` (repeated subdivision into the previous result's memory) with `loop`.
//! Each peer run (driver, scheme, mesh, level) is made once per report and shared by
//! the rows that need it.

use std::collections::BTreeMap;
use std::env;
use std::path::{Path, PathBuf};
use std::process::Command;

/// A peer driver: the library, the program name, how it is called, and which of our
/// schemes it runs under which of its own scheme names.
struct Driver {
    library: &'static str,
    program: &'static str,
    protocol: Protocol,
    schemes: &'static [(&'static str, &'static str)],
    /// Largest output (faces) of a run of `(its scheme, limit)`; other runs are unlimited.
    output_limit: Option<(&'static str, f64)>,
}

impl Driver {
    /// True if the run of `their_scheme` with `faces` output faces is left out.
    fn over_limit(&self, their_scheme: &str, faces: Option<f64>) -> bool {
        matches!((self.output_limit, faces), (Some((scheme, limit)), Some(faces)) if scheme == their_scheme && faces > limit)
    }
}

/// How a driver is called and how its time is read back (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Protocol {
    /// `<driver> <scheme> …` printing a JSON line with `t_sub_best_s`.
    Json,
    /// `rust-peers <crate> <scheme> …` printing one line of fields, `best_ms` seventh.
    RustPeers { krate: &'static str },
}

const DRIVERS: &[Driver] = &[
    Driver {
        library: "OpenSubdiv",
        program: "osd_subdiv",
        protocol: Protocol::Json,
        schemes: &[("loop", "loop")],
        output_limit: None,
    },
    Driver {
        library: "CGAL",
        program: "cgal_subdiv",
        protocol: Protocol::Json,
        schemes: &[("loop", "loop"), ("doo-sabin", "doosabin")],
        output_limit: None,
    },
    Driver {
        library: "OpenMesh",
        program: "openmesh_subdiv",
        protocol: Protocol::Json,
        schemes: &[("loop", "loop")],
        output_limit: None,
    },
    Driver {
        library: "opensubdiv-rs",
        program: "rust-peers",
        protocol: Protocol::RustPeers { krate: "opensubdiv-rs" },
        schemes: &[("loop", "loop")],
        output_limit: None,
    },
    // Its Doo-Sabin keeps the stencil tables of every level: above 8 GiB at 14.5M output
    // faces (level 4 of `bunny00`), so its Doo-Sabin runs above 5M faces are left out
    // (its Loop at 19.3M faces stays under 8 GiB).
    Driver {
        library: "subdiv-kernels",
        program: "rust-peers",
        protocol: Protocol::RustPeers { krate: "subdiv-kernels" },
        schemes: &[("loop", "loop"), ("doo-sabin", "doo-sabin")],
        output_limit: Some(("doo-sabin", 5e6)),
    },
    Driver {
        library: "alum",
        program: "rust-peers",
        protocol: Protocol::RustPeers { krate: "alum" },
        schemes: &[("loop", "loop")],
        output_limit: None,
    },
];

/// One of our measurements: mean time, the time of the fastest sample (if criterion
/// wrote its samples) and output faces.
#[derive(Clone)]
pub struct Measurement {
    pub mean_ns: f64,
    pub best_ns: Option<f64>,
    pub elements: Option<f64>,
}

/// Benchmark variants of our schemes: (suffix of the variant, the scheme the peers run).
/// `loop-reuse` writes into the memory of its previous result; the peers' `loop` runs
/// are the comparison.
const VARIANTS: &[(&str, &str)] = &[("loop-reuse", "loop")];

/// The scheme whose peer runs a benchmark scheme is compared with.
fn peer_scheme(scheme: &str) -> &str {
    VARIANTS.iter().find(|(variant, _)| *variant == scheme).map_or(scheme, |&(_, base)| base)
}

/// Peer runs made so far, so that the same (library, scheme, mesh, level) runs once.
#[derive(Default)]
struct PeerRuns {
    runs: BTreeMap<(String, String, PathBuf, u32), Result<f64, String>>,
}

impl PeerRuns {
    /// The result of `run` for this key, running it only the first time.
    fn get_or_run(
        &mut self,
        library: &str,
        scheme: &str,
        input: &Path,
        level: u32,
        run: impl FnOnce() -> Result<f64, String>,
    ) -> Result<f64, String> {
        self.runs
            .entry((library.to_string(), scheme.to_string(), input.to_path_buf(), level))
            .or_insert_with(run)
            .clone()
    }
}

/// Our time for one (mesh, scheme, level) per thread count: the fastest sample (the
/// mean when there are no samples) and the mean, in seconds.
#[derive(Default)]
struct Ours {
    faces: Option<f64>,
    seconds_by_threads: BTreeMap<usize, OurTimes>,
}

#[derive(Clone, Copy)]
struct OurTimes {
    best: f64,
    mean: f64,
}

/// Markdown section comparing the `subdivide-<mesh>/<scheme>-<n>t/<level>` rows with the
/// peers found on the machine. `mesh_file` maps a benchmark mesh name to its file.
pub fn comparison(rows: &BTreeMap<String, Measurement>, mesh_file: impl Fn(&str) -> Option<PathBuf>) -> String {
    let mut ours: BTreeMap<(String, String, u32), Ours> = BTreeMap::new();
    for (id, measurement) in rows {
        let Some((mesh, scheme, threads, level)) = parse_id(id) else { continue };
        let entry = ours.entry((mesh, scheme, level)).or_default();
        entry.faces = measurement.elements.or(entry.faces);
        let mean = measurement.mean_ns * 1e-9;
        let best = measurement.best_ns.map_or(mean, |ns| ns * 1e-9);
        entry.seconds_by_threads.insert(threads, OurTimes { best, mean });
    }
    if ours.is_empty() {
        return String::from("No `subdivide-*` benchmarks were run: nothing to compare with peers.\n");
    }
    let peers_dir = env::var_os("MULTIRES_PEERS_DIR").map(PathBuf::from);
    let found: Vec<(&Driver, PathBuf)> =
        DRIVERS.iter().filter_map(|d| find_program(d.program, peers_dir.as_deref()).map(|p| (d, p))).collect();
    let mut text = String::from(
        "## Subdivision against peer libraries (same run)\n\n\
         Times of the subdivision call alone: best of up to 3 runs for the peers; for ours the \
         fastest criterion sample (a sample averages several calls) and, in parentheses, the \
         criterion mean. `ratio` = fastest peer time / our time (above 1: we are faster), best \
         against best and, in parentheses, against our mean. `loop-reuse` rows (repeated \
         subdivision into the previous result's memory) are compared with the same peer runs as \
         `loop`. Peer runs above a driver's output limit are left out (subdiv-kernels' \
         Doo-Sabin above 5M faces: more than 8 GiB).\n\n",
    );
    let missing: Vec<&str> =
        DRIVERS.iter().filter(|d| !found.iter().any(|(f, _)| f.program == d.program)).map(|d| d.library).collect();
    if !missing.is_empty() {
        text.push_str(&format!(
            "Not found (skipped): {}. Set `MULTIRES_PEERS_DIR` to the folder holding the peer drivers \
             (`osd_subdiv`, `cgal_subdiv`, `openmesh_subdiv`, `rust-peers`).\n\n",
            missing.join(", ")
        ));
    }
    if let Some(ceiling) = two_thread_ceiling(rows) {
        text.push_str(&ceiling);
    }
    if let Some(wake_up) = wake_up_cost(rows) {
        text.push_str(&wake_up);
    }
    let mut peer_runs = PeerRuns::default();
    text.push_str(
        "| mesh | scheme | level | faces | ours 1 thread | ours 2 threads | 2t / 1t | peers | ratio 1t | ratio 2t |\n",
    );
    text.push_str("|---|---|---:|---:|---:|---:|---:|---|---:|---:|\n");
    for ((mesh, scheme, level), measured) in &ours {
        let one = measured.seconds_by_threads.get(&1).copied();
        let two = measured.seconds_by_threads.get(&2).copied();
        let mut peer_times = Vec::new();
        if let Some(input) = mesh_file(mesh) {
            for (driver, program) in &found {
                let compared = peer_scheme(scheme);
                let Some((_, their_scheme)) = driver.schemes.iter().find(|(our, _)| *our == compared) else {
                    continue;
                };
                if driver.over_limit(their_scheme, measured.faces) {
                    eprintln!("    {}: {their_scheme} level {level} skipped (output above its limit)", driver.library);
                    continue;
                }
                let result = peer_runs.get_or_run(driver.library, their_scheme, &input, *level, || {
                    eprintln!("    {} {their_scheme} {} level {level}", driver.library, input.display());
                    run_driver(program, driver.protocol, their_scheme, &input, *level)
                });
                match result {
                    Ok(seconds) => peer_times.push((driver.library, seconds)),
                    Err(message) => eprintln!("    {}: {message}", driver.library),
                }
            }
        }
        let fastest = peer_times.iter().map(|&(_, t)| t).fold(f64::INFINITY, f64::min);
        let ratio = |ours: Option<OurTimes>| match ours {
            Some(t) if fastest.is_finite() => format!("{:.2} ({:.2})", fastest / t.best, fastest / t.mean),
            _ => "–".into(),
        };
        let rate = |times: Option<OurTimes>| match (times, measured.faces) {
            (Some(t), Some(f)) => {
                format!("{} ({}), {:.1} Mf/s", format_seconds(t.best), format_seconds(t.mean), f / t.best / 1e6)
            }
            (Some(t), None) => format!("{} ({})", format_seconds(t.best), format_seconds(t.mean)),
            _ => "–".into(),
        };
        let peers = if peer_times.is_empty() {
            "–".to_string()
        } else {
            peer_times.iter().map(|(name, t)| format!("{name} {}", format_seconds(*t))).collect::<Vec<_>>().join(", ")
        };
        text.push_str(&format!(
            "| {mesh} | {scheme} | {level} | {} | {} | {} | {} | {peers} | {} | {} |\n",
            measured.faces.map_or("–".into(), |f| format!("{f:.0}")),
            rate(one),
            rate(two),
            speed_up(one, two),
            ratio(one),
            ratio(two),
        ));
    }
    text
}

/// The two-thread speed-up, fastest sample against fastest sample (means in
/// parentheses).
fn speed_up(one: Option<OurTimes>, two: Option<OurTimes>) -> String {
    match (one, two) {
        (Some(one), Some(two)) => format!("{:.2} ({:.2})", one.best / two.best, one.mean / two.mean),
        _ => "–".into(),
    }
}

/// The paragraph on the `machine/stream-<n>t/<MiB>` rows (`benches/machine.rs`): what
/// two threads gain on a plain parallel stream over the same bytes, per working set, the
/// ceiling of the `2t / 1t` column for outputs of that size. `None` without those rows.
fn two_thread_ceiling(rows: &BTreeMap<String, Measurement>) -> Option<String> {
    let mut by_size: BTreeMap<u64, [Option<f64>; 2]> = BTreeMap::new();
    for (id, measurement) in rows {
        let Some(rest) = id.strip_prefix("machine/stream-") else { continue };
        let Some((threads, mib)) = rest.split_once("t/") else { continue };
        let (Ok(threads), Ok(mib)) = (threads.parse::<usize>(), mib.parse::<u64>()) else { continue };
        if let Some(slot) = by_size.entry(mib).or_default().get_mut(threads.wrapping_sub(1)) {
            *slot = Some(measurement.best_ns.unwrap_or(measurement.mean_ns));
        }
    }
    let speed_ups: Vec<String> = by_size
        .iter()
        .filter_map(|(mib, times)| match times {
            [Some(one), Some(two)] => Some(format!("{mib} MiB {:.2}x", one / two)),
            _ => None,
        })
        .collect();
    (!speed_ups.is_empty()).then(|| {
        format!(
            "Two threads on this machine, a plain parallel stream over the same bytes (`machine/stream`, \
             fastest samples, same run): {}. Subdivision of a large mesh moves about as many bytes \
             per operation, so this is the ceiling of its `2t / 1t` column at outputs of that size.\n\n",
            speed_ups.join(", ")
        )
    })
}

/// The paragraph on the `machine/fork-after-idle-<n>t` rows (`benches/machine.rs`): what
/// a fork into two 10 µs halves takes on one thread and on two when the second thread
/// has idled, and so what waking it costs. `None` without both rows.
fn wake_up_cost(rows: &BTreeMap<String, Measurement>) -> Option<String> {
    let micros = |threads: usize| {
        let row = rows.get(&format!("machine/fork-after-idle-{threads}t"))?;
        Some(row.best_ns.unwrap_or(row.mean_ns) / 1e3)
    };
    let (one, two) = (micros(1)?, micros(2)?);
    Some(format!(
        "Waking the second thread (`machine/fork-after-idle`, fastest samples, same run): a fork into two \
         halves of 10 µs of work after the second thread has idled 0.2 ms takes {one:.1} µs on one thread \
         and {two:.1} µs on two (ideally 10 µs), so about {:.0} µs go to the wake-up, which a small level \
         (about 0.1 ms of work) pays whenever its second thread has fallen asleep.\n\n",
        (two - one / 2.0).max(0.0)
    ))
}

/// `subdivide-<mesh>/<scheme>-<threads>t/<level>` → its parts.
fn parse_id(id: &str) -> Option<(String, String, usize, u32)> {
    let mut parts = id.split('/');
    let mesh = parts.next()?.strip_prefix("subdivide-")?;
    let (scheme, threads) = parts.next()?.rsplit_once('-')?;
    let threads = threads.strip_suffix('t')?.parse().ok()?;
    let level = parts.next()?.parse().ok()?;
    parts.next().is_none().then(|| (mesh.to_string(), scheme.to_string(), threads, level))
}

fn find_program(program: &str, peers_dir: Option<&Path>) -> Option<PathBuf> {
    let from_dir = peers_dir.into_iter().flat_map(|d| {
        [d.join(program), d.join("build").join(program), d.join("rust-peers/target/release").join(program)]
    });
    let from_path = env::var_os("PATH").into_iter().flat_map(|p| env::split_paths(&p).collect::<Vec<_>>());
    from_dir.chain(from_path.map(|d| d.join(program))).find(|candidate| candidate.is_file())
}

fn run_driver(program: &Path, protocol: Protocol, scheme: &str, input: &Path, level: u32) -> Result<f64, String> {
    let (input, level) = (input.display().to_string(), level.to_string());
    let args: Vec<&str> = match protocol {
        Protocol::Json => vec![scheme, &input, "-", &level, "3", "20"],
        Protocol::RustPeers { krate } => vec![krate, scheme, &input, "-", &level, "--repeat", "3", "--budget-s", "20"],
    };
    let output =
        Command::new(program).args(&args).output().map_err(|e| format!("cannot start {}: {e}", program.display()))?;
    if !output.status.success() {
        return Err(format!("exit {}: {}", output.status, String::from_utf8_lossy(&output.stderr).trim()));
    }
    let stdout = String::from_utf8_lossy(&output.stdout);
    match protocol {
        Protocol::Json => json_best_seconds(&stdout),
        Protocol::RustPeers { krate } => rust_peers_best_seconds(&stdout, krate),
    }
}

/// `t_sub_best_s` of the last JSON line of a C++ driver's output.
fn json_best_seconds(stdout: &str) -> Result<f64, String> {
    let line = stdout.lines().rev().find(|l| l.trim_start().starts_with('{')).ok_or("no JSON line in the output")?;
    let value: serde_json::Value = serde_json::from_str(line).map_err(|e| format!("bad JSON: {e}"))?;
    value["t_sub_best_s"].as_f64().ok_or_else(|| "no t_sub_best_s in the output".into())
}

/// `best_ms` (in seconds) of the result line of `rust-peers` for `krate`:
/// `crate scheme levels in_faces out_verts out_faces best_ms median_ms`.
fn rust_peers_best_seconds(stdout: &str, krate: &str) -> Result<f64, String> {
    let fields: Vec<&str> = stdout
        .lines()
        .map(|line| line.split_whitespace().collect::<Vec<_>>())
        .find(|fields| fields.len() == 8 && fields[0] == krate)
        .ok_or_else(|| format!("no result line for {krate} in the output"))?;
    let best_ms: f64 = fields[6].parse().map_err(|_| format!("best_ms is not a number: {:?}", fields[6]))?;
    if best_ms.is_finite() && best_ms > 0.0 { Ok(best_ms * 1e-3) } else { Err(format!("best_ms is {best_ms}")) }
}

fn format_seconds(t: f64) -> String {
    match t {
        t if t < 0.01 => format!("{:.3} ms", t * 1e3),
        t if t < 1.0 => format!("{:.1} ms", t * 1e3),
        t => format!("{t:.2} s"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn benchmark_ids_parse() {
        assert_eq!(parse_id("subdivide-bunny00/doo-sabin-2t/3"), Some(("bunny00".into(), "doo-sabin".into(), 2, 3)));
        assert_eq!(parse_id("subdivide-bunny/loop-warren-1t/4").unwrap().1, "loop-warren");
        assert_eq!(
            parse_id("subdivide-bunny00-loop2/doo-sabin-1t/3"),
            Some(("bunny00-loop2".into(), "doo-sabin".into(), 1, 3))
        );
        assert_eq!(parse_id("build/bunny"), None);
        assert_eq!(parse_id("subdivide-bunny/loop/4"), None);
    }

    #[test]
    fn the_stream_rows_give_the_two_thread_ceiling_per_size() {
        let row = |ns: f64| Measurement { mean_ns: 2.0 * ns, best_ns: Some(ns), elements: None };
        let rows: BTreeMap<String, Measurement> = [
            ("machine/stream-1t/2", row(100.0)),
            ("machine/stream-2t/2", row(50.0)),
            ("machine/stream-1t/512", row(300.0)),
            ("machine/stream-2t/512", row(200.0)),
            // A size without its two-thread row is left out.
            ("machine/stream-1t/32", row(10.0)),
            ("subdivide-bunny/loop-1t/1", row(1.0)),
        ]
        .into_iter()
        .map(|(id, m)| (id.to_string(), m))
        .collect();
        let text = two_thread_ceiling(&rows).unwrap();
        assert!(text.contains("2 MiB 2.00x, 512 MiB 1.50x."), "{text}");
        assert!(!text.contains("32 MiB"));
        assert_eq!(two_thread_ceiling(&BTreeMap::new()), None);
        assert_eq!(wake_up_cost(&rows), None);
        let times = |best: f64, mean: f64| Some(OurTimes { best, mean });
        assert_eq!(speed_up(times(4.0, 6.0), times(2.0, 4.0)), "2.00 (1.50)");
        assert_eq!(speed_up(times(4.0, 6.0), None), "–");
    }

    #[test]
    fn the_fork_rows_give_the_wake_up_cost() {
        let row = |ns: f64| Measurement { mean_ns: 2.0 * ns, best_ns: Some(ns), elements: None };
        let mut rows: BTreeMap<String, Measurement> =
            [("machine/fork-after-idle-1t", row(20_400.0)), ("machine/fork-after-idle-2t", row(26_200.0))]
                .into_iter()
                .map(|(id, m)| (id.to_string(), m))
                .collect();
        let text = wake_up_cost(&rows).unwrap();
        // 26.2 µs against the 10.2 µs that half of the one-thread time would be.
        assert!(text.contains("takes 20.4 µs on one thread and 26.2 µs on two"), "{text}");
        assert!(text.contains("about 16 µs go to the wake-up"), "{text}");
        rows.remove("machine/fork-after-idle-1t");
        assert_eq!(wake_up_cost(&rows), None);
    }

    #[test]
    fn reuse_rows_parse_and_compare_with_the_peers_loop() {
        assert_eq!(parse_id("subdivide-bunny00/loop-reuse-2t/4"), Some(("bunny00".into(), "loop-reuse".into(), 2, 4)));
        assert_eq!(parse_id("subdivide-bunny/loop-reuse-1t/1").unwrap().1, "loop-reuse");
        assert_eq!(peer_scheme("loop-reuse"), "loop");
        assert_eq!(peer_scheme("loop"), "loop");
        assert_eq!(peer_scheme("doo-sabin"), "doo-sabin");
    }

    #[test]
    fn peer_outputs_give_their_best_time_in_seconds() {
        let json = "warming up\n{\"t_sub_best_s\": 0.25, \"faces\": 4}\n";
        assert_eq!(json_best_seconds(json), Ok(0.25));
        assert!(json_best_seconds("no json here").is_err());
        let rust = "alum loop 2 3674 29394 58784 14.600 14.900\n";
        assert_eq!(rust_peers_best_seconds(rust, "alum"), Ok(0.0146));
        assert!(rust_peers_best_seconds(rust, "subdiv-kernels").unwrap_err().contains("no result line"));
        assert!(rust_peers_best_seconds("alum loop 2 3674 29394 58784 NaN NaN\n", "alum").is_err());
    }

    #[test]
    fn the_rust_crates_share_one_program_but_run_apart() {
        let rust: Vec<&Driver> = DRIVERS.iter().filter(|d| d.program == "rust-peers").collect();
        assert_eq!(rust.len(), 3);
        let mut libraries: Vec<&str> = DRIVERS.iter().map(|d| d.library).collect();
        libraries.sort_unstable();
        libraries.dedup();
        assert_eq!(libraries.len(), DRIVERS.len(), "runs are remembered by library name");
        assert!(rust.iter().all(|d| matches!(d.protocol, Protocol::RustPeers { krate } if krate == d.library)));
        // Only subdiv-kernels' Doo-Sabin above 5M faces is left out.
        let kernels = DRIVERS.iter().find(|d| d.library == "subdiv-kernels").unwrap();
        assert!(kernels.over_limit("doo-sabin", Some(14.5e6)));
        assert!(!kernels.over_limit("doo-sabin", Some(3.6e6)));
        assert!(!kernels.over_limit("loop", Some(19.3e6)));
        assert!(!kernels.over_limit("doo-sabin", None));
        assert!(DRIVERS.iter().filter(|d| d.library != "subdiv-kernels").all(|d| !d.over_limit("loop", Some(1e9))));
    }

    #[test]
    fn a_peer_run_is_made_once_per_library_mesh_and_level() {
        let mut runs = PeerRuns::default();
        let mut count = 0;
        let mesh = Path::new("bunny.obj");
        for _ in 0..3 {
            let time = runs.get_or_run("OpenSubdiv", "loop", mesh, 2, || {
                count += 1;
                Ok(0.5)
            });
            assert_eq!(time, Ok(0.5));
        }
        assert_eq!(count, 1);
        // Another level, driver or mesh is another run; failures are remembered too.
        let failed = runs.get_or_run("OpenSubdiv", "loop", mesh, 3, || Err("exit 1".into()));
        assert_eq!(failed, Err("exit 1".to_string()));
        assert_eq!(runs.get_or_run("OpenSubdiv", "loop", mesh, 3, || Ok(1.0)), failed);
        assert_eq!(runs.get_or_run("CGAL", "loop", mesh, 2, || Ok(0.25)), Ok(0.25));
        assert_eq!(runs.get_or_run("OpenSubdiv", "loop", Path::new("bunny00.off"), 2, || Ok(2.0)), Ok(2.0));
        assert_eq!(runs.runs.len(), 4);
    }
}
