//! Driving the `query` example from tests: the binary, scratch files, output rows.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use stochastic_collision::mesh::TriMesh;

/// The example binary that `cargo test` builds next to the test binaries.
pub fn query_exe() -> PathBuf {
    let deps = std::env::current_exe()
        .unwrap()
        .parent()
        .unwrap()
        .to_path_buf();
    let exe = deps
        .parent()
        .unwrap()
        .join("examples")
        .join(format!("query{}", std::env::consts::EXE_SUFFIX));
    assert!(
        exe.is_file(),
        "{} not built (run through `cargo test`)",
        exe.display()
    );
    exe
}

/// A scratch file path in a per-process temporary directory.
pub fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("sc_query_cli_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// Writes `mesh` as OBJ text to `path`.
pub fn write_obj(path: &Path, mesh: &TriMesh) {
    let mut s = String::new();
    for p in mesh.positions() {
        s += &format!("v {} {} {}\n", p.x, p.y, p.z);
    }
    for t in mesh.triangles() {
        s += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    std::fs::write(path, s).unwrap();
}

/// Runs the example with `args`.
pub fn run(args: &[&str]) -> Output {
    Command::new(query_exe()).args(args).output().unwrap()
}

/// The result rows of the example's CSV output (header checked), split at commas.
pub fn rows(stdout: &[u8]) -> Vec<Vec<String>> {
    let text = String::from_utf8(stdout.to_vec()).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("index,collides,probability,time_ns,nodes_visited")
    );
    lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect()
}

/// Runs the example in exact mode on meshes `a`, `b` and the pose file `poses`; asserts that
/// it succeeded and returns its rows.
pub fn run_exact(a: &Path, b: &Path, poses: &Path) -> Vec<Vec<String>> {
    let path = |p: &Path| p.to_str().unwrap().to_owned();
    let (a, b, poses) = (path(a), path(b), path(poses));
    let out = run(&["--a", &a, "--b", &b, "--poses", &poses, "--mode", "exact"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    rows(&out.stdout)
}
