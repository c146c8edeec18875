//! The `pficp` binary end to end: results on stdout, one-line errors and exit status 1 on
//! bad input, never a panic.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn pficp(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pficp")).args(args).output().expect("run pficp")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Asserts a clean failure: status 1, one `error:` line naming `words`, no panic.
fn assert_error(o: &Output, words: &[&str]) {
    let e = stderr(o);
    assert_eq!(o.status.code(), Some(1), "stderr: {e}");
    assert!(!e.contains("panicked"), "{e}");
    let line = e.lines().find(|l| l.starts_with("error:")).unwrap_or_else(|| panic!("no error line in {e}"));
    for w in words {
        assert!(line.contains(w), "{w:?} not in {line:?}");
    }
    assert!(o.stdout.is_empty(), "stdout must stay empty on error");
}

fn write(dir: &Path, name: &str, body: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, body).unwrap();
    p
}

fn cloud_text(n: usize) -> String {
    (0..n).map(|i| format!("{} {} {}\n", (i as f64 * 0.7).cos(), (i as f64 * 0.3).sin(), i as f64 * 0.01)).collect()
}

fn register(model: &Path, scan: &Path, extra: &[&str]) -> Output {
    let mut args = vec!["register", "--model", model.to_str().unwrap(), "--scan", scan.to_str().unwrap()];
    args.extend_from_slice(extra);
    pficp(&args)
}

#[test]
fn bad_files_give_one_line_errors() {
    let dir = tempfile::tempdir().unwrap();
    let good = write(dir.path(), "good.xyz", cloud_text(300).as_bytes());
    let missing = dir.path().join("nope.ply");
    assert_error(&register(&missing, &good, &[]), &["nope.ply"]);
    let bad_ply = write(dir.path(), "bad.ply", b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n");
    assert_error(&register(&bad_ply, &good, &[]), &["bad.ply"]);
    let truncated = write(
        dir.path(),
        "short.ply",
        b"ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n1 1 1\n",
    );
    assert_error(&register(&good, &truncated, &[]), &["short.ply", "truncated"]);
    let unknown = write(dir.path(), "cloud.foo", b"1 2 3\n");
    assert_error(&register(&unknown, &good, &[]), &["cloud.foo"]);
    let nan = write(dir.path(), "nan.xyz", format!("{}nan 0 0\n", cloud_text(10)).as_bytes());
    assert_error(&register(&good, &nan, &[]), &["nan.xyz", "non-finite"]);
    let inf = write(dir.path(), "inf.csv", b"x,y,z\n1,2,3\ninf,0,0\n4,5,6\n");
    assert_error(&register(&good, &inf, &[]), &["inf.csv", "non-finite"]);
    let empty = write(dir.path(), "empty.xyz", b"# nothing here\n");
    assert_error(&register(&empty, &good, &[]), &["empty.xyz", "empty"]);
    let junk = write(dir.path(), "junk.xyz", b"1 2 3\n4 five 6\n");
    assert_error(&register(&good, &junk, &[]), &["junk.xyz", "line 2"]);
}

#[test]
fn bad_settings_give_one_line_errors() {
    let dir = tempfile::tempdir().unwrap();
    let good = write(dir.path(), "good.xyz", cloud_text(300).as_bytes());
    let small = write(dir.path(), "small.xyz", cloud_text(40).as_bytes());
    assert_error(&register(&good, &small, &["--clusters", "100"]), &["40 points", "100 clusters"]);
    assert_error(&register(&good, &good, &["--particles", "0"]), &["--particles"]);
    assert_error(&register(&good, &good, &["--iterations", "0"]), &["--iterations"]);
    assert_error(&register(&good, &good, &["--clusters", "0"]), &["--clusters"]);
    assert_error(&register(&good, &good, &["--out-aligned", "x.unknown"]), &["x.unknown"]);
    // clap's own errors (unknown method) exit with 2 and no panic.
    let o = register(&good, &good, &["--method", "magic"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(!stderr(&o).contains("panicked"));
}

#[test]
fn gen_then_register_recovers_the_truth() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().to_str().unwrap();
    let o = pficp(&["gen", "--model", "model-2", "--out-dir", d, "--points", "1200"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let files: Vec<String> = String::from_utf8(o.stdout).unwrap().lines().map(String::from).collect();
    assert_eq!(files.len(), 3);
    let truth: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&files[2]).unwrap()).unwrap();
    let aligned = dir.path().join("aligned.xyz");
    let o =
        register(Path::new(&files[0]), Path::new(&files[1]), &["--json", "--out-aligned", aligned.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8(o.stdout).unwrap();
    assert_eq!(out.lines().count(), 1, "one JSON object: {out}");
    let r: serde_json::Value = serde_json::from_str(&out).unwrap();
    for key in ["scale", "rotation", "translation", "euler_deg", "msd", "iterations", "seconds"] {
        assert!(r.get(key).is_some(), "missing {key}");
    }
    for i in 0..3 {
        let (e, t) = (r["euler_deg"][i].as_f64().unwrap(), truth["euler_deg"][i].as_f64().unwrap());
        assert!((e - t).abs() < 0.5, "angle {i}: {e} vs {t}");
        let (e, t) = (r["translation"][i].as_f64().unwrap(), truth["translation"][i].as_f64().unwrap());
        assert!((e - t).abs() < 0.03, "translation {i}: {e} vs {t}");
    }
    assert!((r["scale"].as_f64().unwrap() / truth["scale"].as_f64().unwrap() - 1.0).abs() < 0.005);
    let aligned_text = std::fs::read_to_string(&aligned).unwrap();
    assert_eq!(aligned_text.lines().filter(|l| !l.trim().is_empty() && !l.starts_with('#')).count(), 1200);
}

#[test]
fn same_seed_same_json_pose() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().to_str().unwrap();
    let o = pficp(&[
        "gen",
        "--model",
        "model-1",
        "--out-dir",
        d,
        "--points",
        "800",
        "--sampling",
        "independent",
        "--scan-points",
        "700",
        "--format",
        "csv",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let files: Vec<String> = String::from_utf8(o.stdout).unwrap().lines().map(String::from).collect();
    let run = |seed: &str| {
        let o = register(Path::new(&files[0]), Path::new(&files[1]), &["--json", "--seed", seed, "--clusters", "40"]);
        assert!(o.status.success(), "{}", stderr(&o));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        (v["rotation"].to_string(), v["translation"].to_string(), v["scale"].to_string())
    };
    assert_eq!(run("7"), run("7"));
}
