//! Shared helpers of the workspace-level integration tests.

#![allow(dead_code)]

pub mod cli;

use std::path::{Path, PathBuf};

/// Path of a file under `tests/data/`.
pub fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(name)
}

/// Relative tolerance of golden comparisons: numbers must agree to this fraction of
/// their magnitude (or absolutely, for magnitudes below 1).
pub const GOLDEN_TOLERANCE: f64 = 1e-12;

/// Compares `actual` with `tests/golden/<name>`, token by token: numeric tokens within
/// [`GOLDEN_TOLERANCE`], everything else exactly. With `MULTIRES_BLESS=1` (set by
/// `cargo xtask golden --bless`) the file is rewritten instead.
pub fn check_golden(name: &str, actual: &str) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden").join(name);
    if std::env::var_os("MULTIRES_BLESS").is_some() {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, actual).unwrap();
        return;
    }
    let expected = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("{}: {e}; run `cargo xtask golden --bless` and review the diff", path.display()));
    let (expected_lines, actual_lines): (Vec<&str>, Vec<&str>) = (expected.lines().collect(), actual.lines().collect());
    assert_eq!(
        expected_lines.len(),
        actual_lines.len(),
        "{name}: {} lines expected, {} produced",
        expected_lines.len(),
        actual_lines.len()
    );
    for (line_number, (e, a)) in expected_lines.iter().zip(&actual_lines).enumerate() {
        let (e_tokens, a_tokens): (Vec<&str>, Vec<&str>) = (tokens(e), tokens(a));
        let same = e_tokens.len() == a_tokens.len()
            && e_tokens.iter().zip(&a_tokens).all(|(x, y)| match (x.parse::<f64>(), y.parse::<f64>()) {
                (Ok(x), Ok(y)) => (x - y).abs() <= GOLDEN_TOLERANCE * x.abs().max(y.abs()).max(1.0),
                _ => x == y,
            });
        assert!(same, "{name}:{}: expected\n  {e}\nfound\n  {a}", line_number + 1);
    }
}

fn tokens(line: &str) -> Vec<&str> {
    line.split(|c: char| c.is_whitespace() || matches!(c, ',' | ':' | '[' | ']' | '{' | '}' | '"'))
        .filter(|t| !t.is_empty())
        .collect()
}
