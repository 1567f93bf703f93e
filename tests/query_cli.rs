//! The `query` example's command-line contract: output format, agreement with parry on every
//! shared mesh, and clean rejection of bad input (exit code 2, one line naming file and line).
mod common;

use std::path::Path;
use std::process::Command;

use common::cli::{query_exe, rows, run, run_exact, scratch, write_obj};

use parry3d::math::Pose as ParryPose;
use parry3d::query::intersection_test;
use parry3d::shape::TriMesh as ParryMesh;
use stochastic_collision::bvh::CollisionMesh;
use stochastic_collision::mesh::{TriMesh, generate};
use stochastic_collision::poses::{near_contact_poses, write_poses_csv};

/// Runs the example on near-contact poses of `mesh_path` against itself and checks every row
/// against parry (poses in the touching band excluded, as in the oracle test).
fn check_against_parry(mesh_path: &Path, count: usize, tag: &str) {
    let mesh = TriMesh::from_obj(mesh_path).unwrap();
    let cm = CollisionMesh::new(mesh.clone());
    let poses = near_contact_poses(&cm, &cm, count, 0.03, 99);
    let poses_path = scratch(&format!("{tag}_poses.csv"));
    write_poses_csv(
        std::fs::File::create(&poses_path).unwrap(),
        poses.iter().map(|p| p.pose),
    )
    .unwrap();
    let out_path = scratch(&format!("{tag}_out.csv"));
    let m = mesh_path.to_str().unwrap();
    let out = run(&[
        "--a",
        m,
        "--b",
        m,
        "--poses",
        poses_path.to_str().unwrap(),
        "--mode",
        "exact",
        "--out",
        out_path.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let rows = rows(&std::fs::read(&out_path).unwrap());
    assert_eq!(rows.len(), poses.len());
    let parry = ParryMesh::new(mesh.positions().to_vec(), mesh.triangles().to_vec()).unwrap();
    let mut compared = 0;
    for (i, (row, p)) in rows.iter().zip(&poses).enumerate() {
        assert_eq!(row[0], i.to_string());
        let collides = row[1] == "1";
        assert_eq!(row[2], if collides { "1" } else { "0" });
        assert!(row[3].parse::<u64>().unwrap() > 0);
        assert!(row[4].parse::<u64>().unwrap() >= 1);
        // Skip the touching band: the answer at the offset must not flip within ±1e-4 of size.
        if p.offset.abs() < 2e-4 * p.size {
            continue;
        }
        let pp = ParryPose::from_parts(p.pose.translation, p.pose.rotation);
        let theirs = intersection_test(&ParryPose::IDENTITY, &parry, &pp, &parry)
            .unwrap()
            .intersecting;
        assert_eq!(
            collides, theirs,
            "{tag}: pose {i} (offset {} of size {})",
            p.offset, p.size
        );
        compared += 1;
    }
    assert!(compared * 10 >= count * 8);
}

#[test]
fn exact_mode_agrees_with_parry_on_generated_meshes() {
    let path = scratch("torus.obj");
    write_obj(&path, &generate::torus(1.0, 0.3, 40, 12));
    check_against_parry(&path, 16, "torus");
}

#[test]
fn exact_mode_agrees_with_parry_on_every_shared_mesh() {
    for file in common::QUERY_MESHES {
        if let Some(path) = common::shared_mesh(file) {
            check_against_parry(&path, 6, file.trim_end_matches(".obj"));
        }
    }
}

#[test]
fn writes_to_stdout_without_out() {
    let mesh = scratch("ball.obj");
    write_obj(&mesh, &generate::icosphere(1.0, 1));
    let poses = scratch("ball_poses.csv");
    std::fs::write(
        &poses,
        "tx,ty,tz,qx,qy,qz,qw\n1.5,0,0,0,0,0,1\n5,0,0,0,0,0,1\n",
    )
    .unwrap();
    let rows = run_exact(&mesh, &mesh, &poses);
    assert_eq!(rows.len(), 2);
    assert_eq!((rows[0][1].as_str(), rows[1][1].as_str()), ("1", "0"));
}

/// Runs with bad input; asserts exit code 2 and a single stderr line containing `needle`.
fn rejects(args: &[&str], needle: &str) {
    let out = run(args);
    assert_eq!(out.status.code(), Some(2), "args {args:?}");
    let err = String::from_utf8(out.stderr).unwrap();
    assert_eq!(err.trim_end().lines().count(), 1, "stderr: {err}");
    assert!(err.contains(needle), "stderr `{err}` lacks `{needle}`");
    assert!(!err.contains("panicked"));
}

#[test]
fn bad_input_exits_2_with_one_clear_line() {
    let mesh = scratch("good.obj");
    write_obj(&mesh, &generate::icosphere(1.0, 1));
    let m = mesh.to_str().unwrap();
    let good = scratch("good_poses.csv");
    std::fs::write(&good, "tx,ty,tz,qx,qy,qz,qw\n0,0,0,0,0,0,1\n").unwrap();
    let g = good.to_str().unwrap();
    let file = |name: &str, text: &str| {
        let p = scratch(name);
        std::fs::write(&p, text).unwrap();
        p.to_str().unwrap().to_string()
    };

    rejects(
        &[
            "--a",
            "/no/such.obj",
            "--b",
            m,
            "--poses",
            g,
            "--mode",
            "exact",
        ],
        "/no/such.obj",
    );
    let bad_obj = file("bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
    rejects(
        &["--a", m, "--b", &bad_obj, "--poses", g, "--mode", "exact"],
        "bad.obj:4",
    );
    rejects(
        &[
            "--a",
            m,
            "--b",
            m,
            "--poses",
            "/no/poses.csv",
            "--mode",
            "exact",
        ],
        "/no/poses.csv",
    );
    let short = file("short.csv", "tx,ty,tz,qx,qy,qz,qw\n0,0,0,0,0,0,1\n1,2,3\n");
    rejects(
        &["--a", m, "--b", m, "--poses", &short, "--mode", "exact"],
        "short.csv:3",
    );
    let nan = file("nan.csv", "tx,ty,tz,qx,qy,qz,qw\nNaN,0,0,0,0,0,1\n");
    rejects(
        &["--a", m, "--b", m, "--poses", &nan, "--mode", "exact"],
        "nan.csv:2",
    );
    let junk = file("junk.csv", "tx,ty,tz,qx,qy,qz,qw\n0,0,zero,0,0,0,1\n");
    rejects(
        &["--a", m, "--b", m, "--poses", &junk, "--mode", "exact"],
        "junk.csv:2",
    );
    let header = file("header.csv", "x,y,z\n0,0,0\n");
    rejects(
        &["--a", m, "--b", m, "--poses", &header, "--mode", "exact"],
        "header.csv:1",
    );
    rejects(
        &["--a", m, "--b", m, "--poses", g, "--mode", "magic"],
        "unknown mode `magic`",
    );
    rejects(&["--a", m, "--b", m, "--poses", g], "missing --mode");
    rejects(
        &[
            "--a",
            m,
            "--b",
            m,
            "--poses",
            g,
            "--mode",
            "exact",
            "--frobnicate",
        ],
        "--frobnicate",
    );
    rejects(
        &["--a", m, "--b", m, "--poses", g, "--mode"],
        "--mode needs a value",
    );
}

#[test]
fn adb_mode_answers_with_confidences_and_node_budgets_are_repeatable() {
    let mesh = scratch("adb_torus.obj");
    write_obj(&mesh, &generate::torus(1.0, 0.3, 40, 12));
    let cm = CollisionMesh::new(TriMesh::from_obj(&mesh).unwrap());
    let poses = near_contact_poses(&cm, &cm, 12, 0.1, 5);
    let poses_path = scratch("adb_poses.csv");
    write_poses_csv(
        std::fs::File::create(&poses_path).unwrap(),
        poses.iter().map(|p| p.pose),
    )
    .unwrap();
    let (m, p) = (mesh.to_str().unwrap(), poses_path.to_str().unwrap());
    let run_adb = |extra: &[&str]| {
        let mut args = vec!["--a", m, "--b", m, "--poses", p, "--mode", "adb"];
        args.extend_from_slice(extra);
        let out = run(&args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        rows(&out.stdout)
    };
    let default = run_adb(&[]);
    assert_eq!(default.len(), poses.len());
    for r in &default {
        let p: f64 = r[2].parse().unwrap();
        assert!((0.0..=1.0).contains(&p));
        assert!(r[1] == "0" || r[1] == "1");
        assert!(r[4].parse::<u64>().unwrap() >= 1);
    }
    // A node budget is deterministic: every column but the time is identical run to run.
    let budgeted = |_: ()| run_adb(&["--budget-nodes", "50", "--p-min", "0.9", "--k-min", "3"]);
    let (x, y) = (budgeted(()), budgeted(()));
    for (a, b) in x.iter().zip(&y) {
        assert_eq!((&a[1], &a[2], &a[4]), (&b[1], &b[2], &b[4]));
    }
    // --collide-at moves only the decision: the same confidences and node pairs, "collision"
    // on at least as many poses when it is lower.
    let eager = run_adb(&["--budget-nodes", "50", "--collide-at", "0.01"]);
    let strict = run_adb(&["--budget-nodes", "50", "--collide-at", "1"]);
    for (a, b) in eager.iter().zip(&strict) {
        assert_eq!((&a[2], &a[4]), (&b[2], &b[4]));
        assert!(a[1] >= b[1], "{a:?} {b:?}");
    }
    // Exact leaves (the default, and asked for with the papers' estimator) with p_min = 1
    // answer exactly.
    let exact = run(&["--a", m, "--b", m, "--poses", p, "--mode", "exact"]);
    let exact = rows(&exact.stdout);
    for flags in [
        &["--p-min", "1"][..],
        &[
            "--leaves",
            "exact",
            "--decision",
            "evidence",
            "--p-min",
            "1",
        ],
        &["--estimator", "paper", "--leaves", "exact", "--p-min", "1"],
        &["--leaves", "exact", "--estimator", "paper", "--p-min", "1"],
        &["--order", "best-first", "--p-min", "1"],
        &["--order", "evidence-first", "--p-min", "1"],
        &[
            "--estimator",
            "paper",
            "--order",
            "evidence-first",
            "--leaves",
            "exact",
            "--p-min",
            "1",
        ],
    ] {
        let hybrid = run_adb(flags);
        for (a, b) in exact.iter().zip(&hybrid) {
            assert_eq!(a[1], b[1], "{flags:?}");
        }
    }
    assert_eq!(run_adb(&["--leaves", "estimated"]).len(), poses.len());
    for estimator in ["paper", "planarity", "calibrated"] {
        assert_eq!(
            run_adb(&["--estimator", estimator, "--budget-us", "50"]).len(),
            poses.len()
        );
    }
}

#[test]
fn adb_flag_errors_exit_2() {
    let mesh = scratch("flags.obj");
    write_obj(&mesh, &generate::icosphere(1.0, 1));
    let m = mesh.to_str().unwrap();
    let poses = scratch("flags_poses.csv");
    std::fs::write(&poses, "tx,ty,tz,qx,qy,qz,qw\n0,0,0,0,0,0,1\n").unwrap();
    let p = poses.to_str().unwrap();
    let base = ["--a", m, "--b", m, "--poses", p];
    let with = |extra: &[&'static str]| {
        let mut v: Vec<&str> = base.to_vec();
        v.extend_from_slice(extra);
        v
    };
    rejects(
        &with(&["--mode", "adb", "--p-min", "2"]),
        "--p-min: invalid value `2`",
    );
    rejects(
        &with(&["--mode", "adb", "--k-min", "0"]),
        "--k-min: invalid value `0`",
    );
    rejects(
        &with(&["--mode", "adb", "--collide-at", "1.5"]),
        "--collide-at: invalid value `1.5`",
    );
    rejects(
        &with(&["--mode", "exact", "--collide-at", "0.2"]),
        "--collide-at",
    );
    rejects(
        &with(&["--mode", "adb", "--budget-us", "-5"]),
        "--budget-us: invalid value `-5`",
    );
    rejects(
        &with(&["--mode", "adb", "--budget-us", "5", "--budget-nodes", "9"]),
        "at most one of",
    );
    rejects(
        &with(&["--mode", "adb", "--estimator", "magic"]),
        "unknown estimator `magic`",
    );
    rejects(
        &with(&["--mode", "adb", "--resolution", "99"]),
        "--resolution: invalid value `99`",
    );
    rejects(
        &with(&["--mode", "adb", "--solid"]),
        "--solid applies to --mode exact only",
    );
    rejects(
        &with(&["--mode", "exact", "--p-min", "0.5"]),
        "--p-min applies to --mode adb only",
    );
    rejects(
        &with(&["--mode", "exact", "--leaves", "exact"]),
        "--leaves applies to --mode adb only",
    );
    rejects(
        &with(&["--mode", "adb", "--leaves", "some"]),
        "--leaves: invalid value `some`",
    );
    rejects(
        &with(&["--mode", "adb", "--decision", "vote"]),
        "--decision: invalid value `vote`",
    );
    rejects(
        &with(&["--mode", "adb", "--order", "random"]),
        "--order: invalid value `random`",
    );
    rejects(
        &with(&["--mode", "exact", "--order", "best-first"]),
        "--order applies to --mode adb only",
    );
    rejects(
        &with(&[
            "--mode",
            "adb",
            "--decision",
            "evidence",
            "--estimator",
            "paper",
        ]),
        "--decision does not apply to --estimator paper",
    );
    rejects(
        &with(&["--mode", "adb", "--budget-us", "1e30"]),
        "--budget-us: invalid value `1e30`",
    );
    // A budget that rounds to no time at all is refused like 0; one too large for a
    // `Duration` (or infinite) is refused, not a panic.
    for tiny in ["0", "1e-300", "0.0004", "0.0009"] {
        rejects(
            &with(&["--mode", "adb", "--budget-us", tiny]),
            &format!("--budget-us: invalid value `{tiny}` (a number of microseconds, at least"),
        );
    }
    rejects(
        &with(&["--mode", "adb", "--budget-us", "1e300"]),
        "--budget-us: invalid value `1e300` (too large",
    );
    rejects(
        &with(&["--mode", "adb", "--budget-us", "1e309"]),
        "--budget-us: invalid value `1e309`",
    );
    // A flag given twice is named, whichever flag it is (the last one no longer wins).
    for (extra, flag) in [
        (
            &["--mode", "adb", "--budget-us", "20", "--budget-us", "30"][..],
            "--budget-us",
        ),
        (
            &[
                "--mode",
                "adb",
                "--budget-nodes",
                "5",
                "--budget-nodes",
                "9",
            ],
            "--budget-nodes",
        ),
        (
            &["--mode", "adb", "--p-min", "0.5", "--p-min", "0.9"],
            "--p-min",
        ),
        (
            &[
                "--mode",
                "adb",
                "--order",
                "best-first",
                "--order",
                "best-first",
            ],
            "--order",
        ),
        (&["--mode", "exact", "--solid", "--solid"], "--solid"),
        (&["--mode", "exact", "--mode", "adb"], "--mode"),
        (&["--mode", "exact", "--a", "/other.obj"], "--a"),
    ] {
        rejects(&with(extra), &format!("{flag} given twice"));
    }
    #[cfg(unix)]
    {
        use std::ffi::OsStr;
        use std::os::unix::ffi::OsStrExt;
        // A path that is not UTF-8 is still a path: refused because the file does not exist.
        let out = Command::new(query_exe())
            .arg("--a")
            .arg(OsStr::from_bytes(b"/tmp/no-such-\xff.obj"))
            .args(["--b", m, "--poses", p, "--mode", "exact"])
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2));
        assert!(String::from_utf8_lossy(&out.stderr).contains("no-such-"));
        // A flag value that is not UTF-8 is refused cleanly.
        let out = Command::new(query_exe())
            .args(["--a", m, "--b", m, "--poses", p, "--mode"])
            .arg(OsStr::from_bytes(b"ad\xffb"))
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2));
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(err.contains("--mode: invalid value"), "{err}");
    }
}

#[test]
fn help_prints_the_usage_to_stdout_and_exits_0() {
    for args in [&["--help"][..], &["-h"], &["--mode", "adb", "--help"]] {
        let out = run(args);
        assert_eq!(out.status.code(), Some(0), "args {args:?}");
        let text = String::from_utf8(out.stdout).unwrap();
        assert!(text.starts_with("usage: query --a A.obj"), "{text}");
        assert!(text.contains("--budget-us"), "{text}");
        assert!(
            out.stderr.is_empty(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    // Bad usage still exits 2 with one line on stderr, nothing on stdout.
    let out = run(&["--bogus"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(out.stdout.is_empty());
    let err = String::from_utf8(out.stderr).unwrap();
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(
        err.starts_with("error: unknown argument `--bogus`; usage:"),
        "{err}"
    );
}

#[test]
fn large_meshes_show_build_progress_on_stderr_and_a_shared_path_builds_once() {
    // 20 480 triangles: at the threshold from which builds show their progress.
    let mesh = generate::icosphere(1.0, 5);
    assert!(mesh.triangle_count() >= 20_000);
    let big = scratch("big_ball.obj");
    write_obj(&big, &mesh);
    let copy = scratch("big_ball_copy.obj");
    std::fs::copy(&big, &copy).unwrap();
    let poses = scratch("big_ball_poses.csv");
    std::fs::write(
        &poses,
        "tx,ty,tz,qx,qy,qz,qw\n1.5,0,0,0,0,0,1\n5,0,0,0,0,0,1\n",
    )
    .unwrap();
    let (big, copy, poses) = (
        big.to_str().unwrap(),
        copy.to_str().unwrap(),
        poses.to_str().unwrap(),
    );
    // Returns the stderr lines naming each mesh's build (`what`); checks the CSV on stdout.
    let builds = |b: &str, mode: &str, what: &str| {
        let out = run(&["--a", big, "--b", b, "--poses", poses, "--mode", mode]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let rows = rows(&out.stdout);
        assert_eq!(rows.len(), 2);
        assert_eq!((rows[0][1].as_str(), rows[1][1].as_str()), ("1", "0"));
        let err = String::from_utf8(out.stderr).unwrap();
        assert!(err.ends_with('\n'), "stderr `{err}` does not end its line");
        assert!(!err.contains("error") && !err.contains("panicked"), "{err}");
        let lines: Vec<String> = err
            .lines()
            .filter(|l| l.contains(what))
            .map(str::to_string)
            .collect();
        assert!(
            lines.iter().all(|l| l.contains("20480 triangles")),
            "{lines:?}"
        );
        lines
    };
    // The same path is loaded and built once (one progress line), another path twice.
    let same = builds(big, "adb", "ADB tree");
    assert_eq!(same.len(), 1, "{same:?}");
    assert!(same[0].contains("big_ball.obj"), "{same:?}");
    let two = builds(copy, "adb", "ADB tree");
    assert_eq!(two.len(), 2, "{two:?}");
    assert!(two[1].contains("big_ball_copy.obj"), "{two:?}");
    assert_eq!(builds(big, "exact", "BVH").len(), 1);
    assert_eq!(builds(copy, "exact", "BVH").len(), 2);

    // A small mesh builds silently: stderr stays empty.
    let small = scratch("small_ball.obj");
    write_obj(&small, &generate::icosphere(1.0, 2));
    let s = small.to_str().unwrap();
    let out = run(&["--a", s, "--b", s, "--poses", poses, "--mode", "adb"]);
    assert!(out.status.success());
    assert!(
        out.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}
