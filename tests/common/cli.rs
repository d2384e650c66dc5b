//! Running the `multires` binary from integration tests: `ok` for commands that must
//! succeed, `fails` for commands that must fail with one clear line.

use std::path::Path;
use std::process::{Command, Output};

/// Runs `multires args` in the package root.
pub fn multires(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_multires")).args(args).output().expect("run multires")
}

/// Runs a command that must succeed; returns its stdout.
pub fn ok(args: &[&str]) -> String {
    let out = multires(args);
    assert!(out.status.success(), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8(out.stdout).unwrap()
}

/// Runs a command that must fail with one line on stderr; returns it.
pub fn fails(args: &[&str]) -> String {
    let out = multires(args);
    assert!(!out.status.success(), "{args:?} should fail");
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert_eq!(stderr.lines().count(), 1, "one line: {stderr}");
    stderr
}

/// A path as a command-line argument.
pub fn path(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Runs `multires args` in `dir`.
pub fn multires_in(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_multires")).args(args).current_dir(dir).output().expect("run multires")
}

/// Runs a command in `dir` that must succeed; returns its stdout.
pub fn ok_in(args: &[&str], dir: &Path) -> String {
    let out = multires_in(args, dir);
    assert!(out.status.success(), "{args:?} failed: {}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8(out.stdout).unwrap()
}

/// Runs a command in `dir` that must fail with one `multires: ...` line, without a
/// panic, and write no file `out` there.
pub fn fails_in(args: &[&str], dir: &Path, out: &str) -> String {
    let output = multires_in(args, dir);
    let stderr = String::from_utf8(output.stderr).unwrap();
    assert!(!output.status.success(), "{args:?} succeeded");
    assert_eq!(stderr.lines().count(), 1, "{args:?}: not one line:\n{stderr}");
    assert!(stderr.starts_with("multires: "), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(!dir.join(out).exists(), "{args:?} wrote {out}");
    stderr
}
