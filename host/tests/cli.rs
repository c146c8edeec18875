//! The `pficp` binary end to end: results on stdout, one-line errors and exit status 1 on
//! bad input, never a panic.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

mod support;

fn pficp(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pficp")).args(args).output().expect("run pficp")
}

/// `pficp ARGS` with its standard input, output and error piped.
fn pficp_piped(args: &[&str]) -> std::process::Child {
    Command::new(env!("CARGO_BIN_EXE_pficp"))
        .args(args)
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("run pficp")
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

/// `pficp gen --out-dir DIR EXTRA...`: the paths it printed (model, scan, truth).
fn gen(dir: &Path, extra: &[&str]) -> Vec<String> {
    let mut args = vec!["gen", "--out-dir", dir.to_str().unwrap()];
    args.extend_from_slice(extra);
    let o = pficp(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    String::from_utf8(o.stdout).unwrap().lines().map(String::from).collect()
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
    // Beyond the point limit: refused from the header, before the body is read.
    let huge = write(
        dir.path(),
        "huge.ply",
        b"ply\nformat binary_little_endian 1.0\nelement vertex 1000000000000\nproperty float x\nproperty float y\nproperty float z\nend_header\n",
    );
    assert_error(&register(&good, &huge, &[]), &["huge.ply", "more than 10000000 points"]);
    // A file without line ends: refused after one line's limit, not read whole.
    let endless = write(dir.path(), "endless.xyz", &vec![b'7'; pficp::io::MAX_LINE_BYTES + 1]);
    assert_error(&register(&good, &endless, &[]), &["endless.xyz", "line 1 is longer than"]);
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
    for bad in [["--scale", "0"], ["--scale", "-2"], ["--scale", "NaN"], ["--scale", "inf"]] {
        assert_error(&register(&good, &good, &bad), &["--scale"]);
    }
    assert_error(&register(&good, &good, &["--scale-range", "2,1"]), &["--scale-range", "LO <= HI"]);
    assert_error(&register(&good, &good, &["--scale-range", "0,1"]), &["--scale-range"]);
    assert_error(&register(&good, &good, &["--scale-range", "1"]), &["--scale-range", "two numbers"]);
    assert_error(&register(&good, &good, &["--viewpoint", "1,2"]), &["--viewpoint"]);
    assert_error(&register(&good, &good, &["--viewpoint", "1,nan,2"]), &["--viewpoint"]);
    assert_error(&register(&good, &good, &["--method", "em-icp", "--scale", "1"]), &["--scale", "em-icp"]);
    // clap's own errors (unknown method, --scale with --scale-range) exit with 2 and no panic.
    let o = register(&good, &good, &["--scale", "1", "--scale-range", "1,2"]);
    assert_eq!(o.status.code(), Some(2));
    let o = register(&good, &good, &["--method", "magic"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(!stderr(&o).contains("panicked"));
}

#[test]
fn gen_then_register_recovers_the_truth() {
    let dir = tempfile::tempdir().unwrap();
    let files = gen(dir.path(), &["--model", "model-2", "--points", "1200"]);
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

/// With --scale the result has exactly that scale, the settings record it, the reproduce
/// command carries it, and the verdict comes first in the text.
#[test]
fn a_fixed_scale_is_kept_and_recorded() {
    let dir = tempfile::tempdir().unwrap();
    let files = gen(dir.path(), &["--model", "model-2", "--points", "1200"]);
    let truth: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&files[2]).unwrap()).unwrap();
    let s = truth["scale"].as_f64().unwrap().to_string();
    let o = register(Path::new(&files[0]), Path::new(&files[1]), &["--json", "--scale", &s]);
    assert!(o.status.success(), "{}", stderr(&o));
    let r: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(r["scale"].as_f64().unwrap().to_string(), s);
    assert_eq!(r["settings"]["scale"].as_f64().unwrap().to_string(), s);
    assert!(r["command"].as_str().unwrap().contains("--scale"));
    assert!(["confident", "ambiguous", "unreliable"].contains(&r["verdict"].as_str().unwrap()));
    let o = register(Path::new(&files[0]), Path::new(&files[1]), &["--scale-range", "0.9,1.0"]); // the truth 0.8333 below it
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8(o.stdout).unwrap();
    assert!(text.starts_with("verdict      unreliable"), "{text}");
    assert!(text.lines().next().unwrap().contains("bound of --scale-range"), "{text}");
}

#[test]
fn same_seed_same_json_pose() {
    let dir = tempfile::tempdir().unwrap();
    let files = gen(
        dir.path(),
        &[
            "--model",
            "model-1",
            "--points",
            "800",
            "--sampling",
            "independent",
            "--scan-points",
            "700",
            "--format",
            "csv",
        ],
    );
    let run = |seed: &str| {
        let o = register(Path::new(&files[0]), Path::new(&files[1]), &["--json", "--seed", seed, "--clusters", "40"]);
        assert!(o.status.success(), "{}", stderr(&o));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        (v["rotation"].to_string(), v["translation"].to_string(), v["scale"].to_string())
    };
    assert_eq!(run("7"), run("7"));
}

#[test]
fn a_missing_board_port_is_a_clear_error() {
    assert_error(&pficp(&["board", "info", "--port", "/nonexistent"]), &["/nonexistent"]);
    let dir = tempfile::tempdir().unwrap();
    let good = write(dir.path(), "good.xyz", cloud_text(300).as_bytes());
    assert_error(&register(&good, &good, &["--board", "/nonexistent/ttyUSB7"]), &["/nonexistent/ttyUSB7"]);
    assert_error(&register(&good, &good, &["--board", "/nonexistent", "--method", "icp"]), &["--board", "PF-ICP"]);
    assert_error(&register(&good, &good, &["--host-driven"]), &["--host-driven", "--board"]);
    assert_error(&register(&good, &good, &["--board-points", "50"]), &["--board-points", "--board"]);
    let board = support::PtyBoard::reference();
    let p = board.path.as_str();
    assert_error(&register(&good, &good, &["--board", p, "--board-points", "0"]), &["--board-points"]);
    assert_error(
        &register(&good, &good, &["--board", p, "--host-driven", "--board-points", "50"]),
        &["--board-points"],
    );
    assert_error(&register(&good, &good, &["--board", p, "--particles", "300"]), &["300 particles"]);
}

#[test]
fn a_silent_board_is_a_clear_error() {
    let board = support::PtyBoard::serve(Box::new(|_| Some(Vec::new())));
    let start = std::time::Instant::now();
    let o = pficp(&["board", "info", "--port", &board.path, "--timeout-ms", "300"]);
    // Every rate of the probe tried, in order.
    assert_error(&o, &[&board.path, "did not answer", "3000000 (no reply", "921600 (no reply", "115200 (no reply"]);
    assert!(start.elapsed() < std::time::Duration::from_secs(10));
}

#[test]
fn absurd_link_options_are_refused_before_the_port_is_opened() {
    let board = support::PtyBoard::reference();
    let p = board.path.as_str();
    assert_error(&pficp(&["board", "info", "--port", p, "--baud", "1"]), &["--baud 1", "9600 to 12000000"]);
    assert_error(&pficp(&["board", "info", "--port", p, "--baud", "4000000000"]), &["--baud 4000000000"]);
    assert_error(&pficp(&["board", "info", "--port", p, "--timeout-ms", "0"]), &["--timeout-ms 0"]);
    assert_error(&pficp(&["board", "info", "--port", p, "--timeout-ms", "86400000"]), &["--timeout-ms 86400000"]);
}

#[test]
fn an_echoing_port_is_named() {
    let board = support::PtyBoard::serve(Box::new(|bytes| Some(bytes.to_vec())));
    assert_error(&pficp(&["board", "info", "--port", &board.path]), &[&board.path, "loopback"]);
}

#[test]
fn board_info_prints_the_identity() {
    let board = support::PtyBoard::reference();
    let o = pficp(&["board", "info", "--port", &board.path]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8(o.stdout).unwrap();
    let version = format!("protocol version  {}", pficp_fpga::protocol::VERSION);
    let baud = format!("baud              {}", pficp::board::DEFAULT_BAUD);
    for line in [version.as_str(), "lanes             8", "max particles     256", &baud] {
        assert!(out.contains(line), "{line:?} not in {out}");
    }
}

/// Without --baud, `pficp` uses the rate the board answers Identify at (the board's line
/// keeps the rate); with --baud, that rate only.
#[test]
fn board_info_follows_the_boards_rate() {
    let config = pficp_fpga::board::BoardConfig { baud: 921_600, ..Default::default() };
    let board = support::PtyBoard::reference_at_rate(config);
    let o = pficp(&["board", "info", "--port", &board.path, "--timeout-ms", "300"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8(o.stdout).unwrap().contains("baud              921600"));
    let o = pficp(&["board", "info", "--port", &board.path, "--timeout-ms", "300", "--baud", "3000000"]);
    assert_error(&o, &[&board.path, "did not answer", "3000000 baud"]);
}

#[test]
fn register_on_the_board_prints_the_software_form() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().to_str().unwrap();
    let o = pficp(&["gen", "--model", "model-1", "--out-dir", d, "--points", "300"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let files: Vec<String> = String::from_utf8(o.stdout).unwrap().lines().map(String::from).collect();
    let (model, scan) = (Path::new(&files[0]), Path::new(&files[1]));
    let small = ["--clusters", "30", "--particles", "30", "--iterations", "10"];
    let board = support::PtyBoard::reference();
    let mut first = true;
    let mut on_board = |extra: &[&str]| {
        let mut args = vec!["--board", board.path.as_str()];
        args.extend_from_slice(&small);
        args.extend_from_slice(extra);
        let o = register(model, scan, &args);
        assert!(o.status.success(), "{}", stderr(&o));
        // The model goes with its normals and its cell table (protocol 4), counted in data
        // bytes; the next registration finds it on the board (the resident model) and says so.
        let bytes = format!("uploaded the model: {} bytes", 2 * 300 * 6 + 4097 * 2);
        let resident = "the board holds the model already";
        assert_eq!(stderr(&o).contains(&bytes), first, "{}", stderr(&o));
        assert_eq!(stderr(&o).contains(resident), !first, "{}", stderr(&o));
        first = false;
        String::from_utf8(o.stdout).unwrap()
    };
    let json: serde_json::Value = serde_json::from_str(&on_board(&["--json"])).unwrap();
    let host_driven: serde_json::Value = serde_json::from_str(&on_board(&["--json", "--host-driven"])).unwrap();
    let soft = register(model, scan, &[&small[..], &["--json"]].concat());
    let soft: serde_json::Value = serde_json::from_slice(&soft.stdout).unwrap();
    let keys = |v: &serde_json::Value| {
        let mut k: Vec<String> = v.as_object().unwrap().keys().filter(|k| *k != "port").cloned().collect();
        k.sort();
        k
    };
    assert_eq!(keys(&json), keys(&soft), "the same JSON keys");
    assert_eq!(keys(&host_driven), keys(&soft), "the same JSON keys");
    assert_eq!((json["engine"].as_str(), soft["engine"].as_str()), (Some("board"), Some("software")));
    assert_eq!(host_driven["engine"].as_str(), Some("board-host-driven"));
    assert_eq!(json["port"].as_str(), Some(board.path.as_str()));
    assert_eq!(host_driven["port"].as_str(), Some(board.path.as_str()));
    let truth: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&files[2]).unwrap()).unwrap();
    for v in [&json, &host_driven] {
        for i in 0..3 {
            let (e, t) = (v["euler_deg"][i].as_f64().unwrap(), truth["euler_deg"][i].as_f64().unwrap());
            assert!((e - t).abs() < 0.5, "{}: angle {i}: {e} vs {t}", v["engine"]);
        }
    }
    // The on-board filter's sample size is a flag; the run says what it did.
    let mut args = vec!["--board", board.path.as_str(), "--board-points", "64"];
    args.extend_from_slice(&small);
    let o = register(model, scan, &args);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(err.contains("64 scan points") && err.contains("Status polls"), "{err}");
    assert!(err.contains("filter on the board: done"), "{err}");
    let text = on_board(&[]);
    let labels = |t: &str| t.lines().map(|l| l.split_whitespace().next().unwrap_or("").to_string()).collect::<Vec<_>>();
    let soft_text = String::from_utf8(register(model, scan, &small).stdout).unwrap();
    assert_eq!(labels(&text), labels(&soft_text), "the same text form:\n{text}\n{soft_text}");
    assert!(text.contains(&format!("engine       board ({})", board.path)), "{text}");
}

/// A collinear model and scan: a pose with a warning naming what the line cannot fix
/// (translation along it, scale, rotation about it), the same in the JSON, and no NaN.
#[test]
fn collinear_clouds_name_their_undetermined_parameters() {
    let dir = tempfile::tempdir().unwrap();
    let line = |n: usize, a: f64, b: f64, off: f64| -> String {
        (0..n)
            .map(|i| {
                let t = a + (b - a) * i as f64 / (n - 1) as f64;
                format!("{} {} {}\n", t + off, 2.0 * t, 3.0 * t - off)
            })
            .collect()
    };
    let model = write(dir.path(), "line-model.xyz", line(500, -1.0, 1.0, 0.0).as_bytes());
    let scan = write(dir.path(), "line-scan.xyz", line(400, -0.8, 0.8, 0.1).as_bytes());
    let text = register(&model, &scan, &["--clusters", "20"]);
    assert_eq!(text.status.code(), Some(0), "{}", stderr(&text));
    let out = String::from_utf8_lossy(&text.stdout);
    let warning = out.lines().find(|l| l.contains("cannot determine")).unwrap_or_else(|| panic!("no warning in {out}"));
    assert!(warning.contains("scale") && warning.contains("rotation about"), "{warning}");
    assert!(!out.contains("NaN"), "{out}");
    let json = register(&model, &scan, &["--clusters", "20", "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&json.stdout).expect("one JSON object");
    let undetermined: Vec<&str> = v["undetermined"].as_array().unwrap().iter().map(|x| x.as_str().unwrap()).collect();
    // The line runs along (1, 2, 3) / sqrt(14).
    assert_eq!(
        undetermined,
        ["translation along (0.27, 0.53, 0.80)", "scale", "rotation about (0.27, 0.53, 0.80)"],
        "{undetermined:?}"
    );
    let text = String::from_utf8_lossy(&json.stdout);
    assert!(!text.contains("NaN") && !text.contains("inf"), "{text}");
    // Every parameter has a part along one of those motions: no sigma is printed as if it
    // were known.
    assert!(v["sigma"].as_array().unwrap().iter().all(|s| s.is_null()), "{}", v["sigma"]);
}

/// A scan of the exactly symmetric block (D2) says it looks symmetric and lists its other
/// poses in the JSON; the paper's asymmetric model-1 lists none.
#[test]
fn symmetric_shapes_report_their_alternatives() {
    use pficp::parts::Part;
    use rand::SeedableRng;
    let dir = tempfile::tempdir().unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let to_text = |pts: &[nalgebra::Point3<f64>]| -> String {
        pts.iter().map(|p| format!("{} {} {}\n", p.x, p.y, p.z)).collect()
    };
    let model = write(dir.path(), "block.xyz", to_text(&Part::Block.sample_surface(2000, &mut rng)).as_bytes());
    let scan = write(dir.path(), "block-scan.xyz", to_text(&Part::Block.sample_surface(800, &mut rng)).as_bytes());
    let out = register(&model, &scan, &[]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(
        String::from_utf8_lossy(&out.stdout).contains("looks symmetric: 4 poses"),
        "{}",
        String::from_utf8_lossy(&out.stdout)
    );
    let json = register(&model, &scan, &["--json"]);
    let v: serde_json::Value = serde_json::from_slice(&json.stdout).unwrap();
    assert_eq!(v["alternatives"].as_array().unwrap().len(), 3);
    let d = tempfile::tempdir().unwrap();
    let g = pficp(&["gen", "--model", "model-1", "--out-dir", d.path().to_str().unwrap(), "--sampling", "independent"]);
    assert_eq!(g.status.code(), Some(0));
    let json = register(&d.path().join("model-1.ply"), &d.path().join("model-1-scan.ply"), &["--json"]);
    let v: serde_json::Value = serde_json::from_slice(&json.stdout).unwrap();
    assert_eq!(v["alternatives"].as_array().unwrap().len(), 0, "{}", v["alternatives"]);
    assert!(v["fitness"].as_f64().unwrap() > 0.9);
}

/// Huge coordinates, a sensor's sentinel point, absurd counts: one clear line each, exit 1,
/// checked before anything is allocated; and no error says the same thing twice.
#[test]
fn numeric_extremes_and_absurd_options_give_one_line_errors() {
    let dir = tempfile::tempdir().unwrap();
    let good = write(dir.path(), "good.xyz", cloud_text(300).as_bytes());
    let huge: String =
        (0..300).map(|i| format!("{:e} {:e} 1e200\n", (i as f64).cos() * 1e200, (i as f64).sin() * 1e200)).collect();
    let huge = write(dir.path(), "huge.xyz", huge.as_bytes());
    assert_error(&register(&good, &huge, &[]), &["huge.xyz", "point 0", "limit"]);
    let mut lines: Vec<String> = cloud_text(300).lines().map(String::from).collect();
    lines[17] = "1.7976931348623157e308 0 0".to_string();
    let sentinel = write(dir.path(), "sentinel.xyz", lines.join("\n").as_bytes());
    assert_error(&register(&good, &sentinel, &[]), &["sentinel.xyz", "point 17"]);
    lines[17] = "1e9 0 0".to_string();
    let far = write(dir.path(), "far.xyz", lines.join("\n").as_bytes());
    assert_error(&register(&good, &far, &[]), &["far.xyz", "point 17", "median"]);
    for (flag, value) in [("--particles", "4000000000"), ("--iterations", "4000000000"), ("--clusters", "4000000000")] {
        assert_error(&register(&good, &good, &[flag, value]), &[flag, "at most"]);
    }
    let out = dir.path().to_str().unwrap();
    assert_error(
        &pficp(&["gen", "--model", "model-1", "--points", "100000000000", "--out-dir", out]),
        &["--points", "at most"],
    );
    let empty = write(dir.path(), "empty.xyz", b"");
    let o = register(&good, &empty, &[]);
    assert_error(&o, &["empty.xyz", "empty"]);
    let line = stderr(&o);
    assert_eq!(line.matches("is empty").count(), 1, "{line}");
    let o = register(&dir.path().join("missing.xyz"), &good, &[]);
    assert_eq!(stderr(&o).matches("No such file").count(), 1, "{}", stderr(&o));
}

/// The long options a `--help` text lists (option lines only), without `--help`/`--version`.
fn help_options(help: &str) -> std::collections::BTreeSet<String> {
    help.lines()
        .map(str::trim_start)
        .filter(|l| l.starts_with('-'))
        .filter_map(|l| l.split([' ', ',', '=', '<']).find(|w| w.starts_with("--")))
        .map(String::from)
        .filter(|o| o != "--help" && o != "--version")
        .collect()
}

/// Every `--word` in `text`.
fn long_options(text: &str) -> std::collections::BTreeSet<String> {
    text.split(|c: char| !(c.is_ascii_alphanumeric() || c == '-'))
        .filter(|w| w.len() > 2 && w.starts_with("--"))
        .map(String::from)
        .collect()
}

#[test]
fn every_help_has_an_example_and_the_readme_lists_the_same_options() {
    let readme = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../README.md")).unwrap();
    let section = &readme[readme.find("## The `pficp` tool").expect("the README's tool section")..];
    let block = &section[section.find("```sh\n").unwrap() + 6..];
    let block = &block[..block.find("```").unwrap()];
    // The README's synopsis: a line starting with `pficp` names the subcommand, indented
    // lines continue it; `pficp [--quiet] <command>` lists the global options.
    let mut readme_options: std::collections::BTreeMap<String, std::collections::BTreeSet<String>> = Default::default();
    let mut current = String::new();
    for line in block.lines() {
        if let Some(rest) = line.strip_prefix("pficp ") {
            let words: Vec<&str> =
                rest.split_whitespace().take_while(|w| w.chars().all(|c| c.is_ascii_lowercase())).collect();
            current = if words.is_empty() { "(global)".to_string() } else { words.join(" ") };
        }
        let opts = long_options(line.split('#').next().unwrap_or(""));
        readme_options.entry(current.clone()).or_default().extend(opts);
    }
    let global = help_options(&String::from_utf8(pficp(&["--help"]).stdout).unwrap());
    assert!(global.contains("--quiet"), "{global:?}");
    assert_eq!(readme_options.remove("(global)").unwrap_or_default(), global, "global options");
    let subcommands = ["demo", "register", "track", "gen", "eval", "bench", "board info"];
    assert_eq!(
        readme_options.keys().cloned().collect::<std::collections::BTreeSet<_>>(),
        subcommands.iter().map(|s| s.to_string()).collect()
    );
    for sub in subcommands {
        let mut args: Vec<&str> = sub.split(' ').collect();
        args.push("--help");
        let o = pficp(&args);
        assert!(o.status.success(), "{sub}: {}", stderr(&o));
        let help = String::from_utf8(o.stdout).unwrap();
        let example = help.split("Example:").nth(1).unwrap_or_else(|| panic!("{sub} --help has no example:\n{help}"));
        assert!(example.trim_start().starts_with(&format!("pficp {sub}")), "{sub}'s example: {example}");
        let listed: std::collections::BTreeSet<String> = help_options(&help).difference(&global).cloned().collect();
        assert_eq!(readme_options[sub], listed, "{sub}: README (left) against --help (right)");
    }
}

#[test]
fn the_demo_shows_both_cases_with_pf_icps_uncertainty() {
    let o = pficp(&["--quiet", "demo"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(o.stderr.is_empty(), "--quiet leaves stderr empty: {}", stderr(&o));
    let out = String::from_utf8(o.stdout).unwrap();
    let realistic = out.find("\n2. a realistic scan").unwrap_or_else(|| panic!("no realistic case:\n{out}"));
    let (paper, realistic) = out.split_at(realistic);
    assert!(paper.contains("1. the paper's setting"), "{out}");
    for case in [paper, realistic] {
        let success = case.lines().find(|l| l.starts_with("success")).unwrap_or_else(|| panic!("{case}"));
        let cols: Vec<&str> = success.split_whitespace().collect();
        assert_eq!(cols.len(), 3, "{success}");
        assert_eq!(cols[1], "yes", "PF-ICP within the tolerance:\n{case}");
        assert!(case.contains("pf-icp  one sigma"), "{case}");
        assert!(case.contains("truth        inside its 95% region"), "{case}");
    }
}

#[test]
fn a_json_result_reruns_from_its_own_command() {
    let dir = tempfile::tempdir().unwrap();
    let files = gen(
        dir.path(),
        &["--model", "model-2", "--points", "800", "--sampling", "independent", "--scan-points", "600"],
    );
    let o = register(
        Path::new(&files[0]),
        Path::new(&files[1]),
        &["--json", "--seed", "7", "--particles", "30", "--clusters", "40"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let first: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(first["inputs"]["model_points"], 800);
    assert_eq!(first["inputs"]["scan_points"], 600);
    assert_eq!(first["inputs"]["model"], files[0].as_str());
    assert_eq!(first["settings"]["seed"], 7);
    assert_eq!(first["settings"]["particles"], 30);
    assert_eq!(first["settings"]["clusters"], 40);
    assert_eq!(first["settings"]["iterations"], 50);
    assert_eq!(first["settings"]["init"], "auto");
    assert_eq!(first["version"], env!("CARGO_PKG_VERSION"));
    let command = first["command"].as_str().unwrap();
    let words: Vec<&str> = command.split_whitespace().collect();
    assert_eq!(words[..2], ["pficp", "register"], "{command}");
    let mut args = words[1..].to_vec();
    args.push("--json");
    let o = pficp(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let again: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    for key in ["scale", "translation", "rotation", "settings", "inputs", "command"] {
        assert_eq!(first[key], again[key], "{key} after rerunning {command}");
    }
}

/// A scan of something else (a curve, not the model's surface): the evidence rules the
/// first answer out and the rescue search runs (`rescued`); `--no-rescue` skips it and is
/// recorded in the settings and the command. Either way the verdict is `unreliable`.
#[test]
fn the_rescue_is_reported_and_can_be_turned_off() {
    let dir = tempfile::tempdir().unwrap();
    let files = gen(dir.path(), &["--model", "model-2", "--points", "800", "--scan-points", "600"]);
    let foreign = write(dir.path(), "foreign.xyz", cloud_text(600).as_bytes());
    let json = |extra: &[&str]| -> serde_json::Value {
        let mut args = vec!["--json"];
        args.extend_from_slice(extra);
        let o = register(Path::new(&files[0]), &foreign, &args);
        assert!(o.status.success(), "{}", stderr(&o));
        serde_json::from_slice(&o.stdout).unwrap()
    };
    let with = json(&[]);
    assert_eq!(with["verdict"], "unreliable", "{with}");
    assert_eq!(with["rescued"], true);
    assert_eq!(with["settings"]["rescue"], true);
    assert!(!with["command"].as_str().unwrap().contains("--no-rescue"));
    let without = json(&["--no-rescue"]);
    assert_eq!(without["verdict"], "unreliable", "{without}");
    assert_eq!(without["rescued"], false);
    assert_eq!(without["settings"]["rescue"], false);
    assert!(without["command"].as_str().unwrap().ends_with("--no-rescue"), "{}", without["command"]);
    // The model's own scan: nothing ruled out, no rescue.
    let o = register(Path::new(&files[0]), Path::new(&files[1]), &["--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let own: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(own["rescued"], false, "{own}");
}

#[test]
fn pcd_files_go_through_gen_register_and_out_aligned() {
    let dir = tempfile::tempdir().unwrap();
    let files = gen(dir.path(), &["--model", "model-2", "--points", "600", "--format", "pcd"]);
    assert!(files[0].ends_with("model-2.pcd") && files[1].ends_with("model-2-scan.pcd"), "{files:?}");
    let model = std::fs::read(&files[0]).unwrap();
    assert!(String::from_utf8_lossy(&model).contains("\nSIZE 4 4 4\nTYPE F F F\n"));
    let out = dir.path().join("aligned.pcd");
    let o = register(Path::new(&files[0]), Path::new(&files[1]), &["--json", "--out-aligned", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let aligned = pficp::io::read_cloud(&out, "aligned").unwrap();
    let scan = pficp::io::read_cloud(Path::new(&files[1]), "scan").unwrap();
    assert_eq!(aligned.len(), scan.len());
    // An organised cloud's NaN points are skipped; a bad PCD is a one-line error.
    let mut text = String::from("FIELDS x y z\nWIDTH 2\nHEIGHT 151\nPOINTS 302\nDATA ascii\nnan nan nan\n");
    text.push_str(&cloud_text(300));
    text.push_str("nan nan nan\n");
    let organised = write(dir.path(), "organised.pcd", text.as_bytes());
    let o = register(&organised, &organised, &["--method", "icp"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let bad = write(dir.path(), "bad.pcd", b"FIELDS x y\nSIZE 4 4\nTYPE F F\nCOUNT 1 1\nPOINTS 1\nDATA ascii\n1 2\n");
    assert_error(&register(&bad, &organised, &[]), &["bad.pcd", "FIELDS has no `z`"]);
    let bad =
        write(dir.path(), "lzf.pcd", b"FIELDS x y z\nPOINTS 1\nDATA binary_compressed\n\xff\xff\xff\xff\x0c\0\0\0");
    assert_error(&register(&organised, &bad, &[]), &["lzf.pcd", "4294967295 bytes", "more than the limit"]);
}

/// `pficp track` on a folder of frames and on the same frames through standard input: one
/// JSON object a line and a frame with the documented keys, the first frame a global
/// registration, the next ones tracked; the same poses either way.
#[test]
fn track_prints_one_json_line_a_frame_from_a_folder_and_from_standard_input() {
    use pficp::eval::realistic::Shape;
    use std::io::Write;
    let dir = tempfile::tempdir().unwrap();
    let seq = pficp::eval::tracking::sequence::sequence(Shape::Part(pficp::parts::Part::BlockBoss), 3, true);
    let model = dir.path().join("model.ply");
    pficp::io::write_cloud(&model, &seq.model, pficp::io::Format::PlyBinary).unwrap();
    let frames = dir.path().join("frames");
    std::fs::create_dir(&frames).unwrap();
    let n = 6;
    let mut stream = String::new();
    for (k, f) in seq.frames.iter().take(n).enumerate() {
        pficp::io::write_cloud(&frames.join(format!("{k:04}.xyz")), &f.scan, pficp::io::Format::Xyz).unwrap();
        stream += &String::from_utf8(pficp::io::write_points_to_bytes(&f.scan, pficp::io::Format::Xyz)).unwrap();
        stream += "\n";
    }
    let args = ["track", "-q", "--model", model.to_str().unwrap(), "--scale", "1", "--json", "--scans"];
    let o = pficp(&[&args[..], &[frames.to_str().unwrap()]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let lines: Vec<serde_json::Value> =
        String::from_utf8(o.stdout).unwrap().lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    assert_eq!(lines.len(), n);
    for (k, v) in lines.iter().enumerate() {
        for key in [
            "frame",
            "file",
            "scale",
            "rotation",
            "translation",
            "matrix",
            "covariance",
            "sigma",
            "fitness",
            "inlier_rmse",
            "verdict",
            "state",
            "seconds",
        ] {
            assert!(v.get(key).is_some(), "frame {k}: no {key}");
        }
        assert_eq!(v["frame"], k);
        assert!(v["file"].as_str().unwrap().ends_with(&format!("{k:04}.xyz")));
        assert_eq!(v["scale"], 1.0);
    }
    assert_eq!((lines[0]["state"].as_str(), lines[0]["global"].as_bool()), (Some("acquiring"), Some(true)));
    // A frame after one that holds the track is tracked (no global registration); one
    // without a track is a global registration.
    for k in 1..n {
        let (prev, this) = (&lines[k - 1], &lines[k]);
        let held = prev["verdict"] != "unreliable" || prev["state"] == "tracking";
        assert!(["acquiring", "tracking", "lost", "reacquired"].contains(&this["state"].as_str().unwrap()));
        if held && prev["state"] != "lost" {
            assert_eq!(this["global"], false, "frame {k}: {this}");
        }
        if prev["state"] == "acquiring" && prev["verdict"] == "unreliable" {
            assert_eq!(this["global"], true, "frame {k}: {this}");
        }
    }
    // The same frames on standard input.
    let mut child = pficp_piped(&[&args[..], &["-"]].concat());
    child.stdin.take().unwrap().write_all(stream.as_bytes()).unwrap();
    let o = child.wait_with_output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let piped: Vec<serde_json::Value> =
        String::from_utf8(o.stdout).unwrap().lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    assert_eq!(piped.len(), n);
    for (a, b) in lines.iter().zip(&piped) {
        assert_eq!((&a["matrix"], &a["state"]), (&b["matrix"], &b["state"]));
        assert_eq!(b["file"], "-");
    }
    // The tracked frames' filter on the (reference) board behind a pseudo-terminal.
    let board = support::PtyBoard::reference();
    let o = pficp(&[&args[..], &[frames.to_str().unwrap(), "--board", board.path.as_str()]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let on_board: Vec<serde_json::Value> =
        String::from_utf8(o.stdout).unwrap().lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    assert_eq!(on_board.len(), n);
    for v in &on_board {
        assert_eq!((v["engine"].as_str(), v["port"].as_str()), (Some("board"), Some(board.path.as_str())));
    }
    assert!(lines.iter().all(|v| v["engine"] == "software" && v.get("port").is_none()));
    assert_eq!(on_board[0]["matrix"], lines[0]["matrix"], "the acquisition is the host's either way");
}

/// Bad frames and options: one-line errors, no panic.
#[test]
fn track_refuses_bad_frames_and_options() {
    use std::io::Write;
    let dir = tempfile::tempdir().unwrap();
    let model = write(dir.path(), "model.xyz", cloud_text(300).as_bytes());
    let m = model.to_str().unwrap();
    let empty = dir.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    assert_error(&pficp(&["track", "--model", m, "--scans", empty.to_str().unwrap()]), &["no PLY"]);
    assert_error(&pficp(&["track", "--model", m, "--scans", "/nonexistent/frames"]), &["not a folder"]);
    assert_error(&pficp(&["track", "--model", m, "--scans", empty.to_str().unwrap(), "--fps", "0"]), &["--fps"]);
    let bad = dir.path().join("bad");
    std::fs::create_dir(&bad).unwrap();
    write(&bad, "0000.xyz", b"1 2 3\n4 5 nan\n");
    assert_error(&pficp(&["track", "--model", m, "--scans", bad.to_str().unwrap()]), &["0000.xyz"]);
    for (input, words) in
        [("1 2 3\n1 2 x\n", &["frame 0"][..]), ("", &["no frame"][..]), ("1 2 3\n\n", &["frame 0", "at least"][..])]
    {
        let mut child = pficp_piped(&["track", "--model", m, "--scans", "-"]);
        child.stdin.take().unwrap().write_all(input.as_bytes()).unwrap();
        assert_error(&child.wait_with_output().unwrap(), words);
    }
    // A stream that never ends its frame is refused at the points limit, not read on.
    let mut child = pficp_piped(&["track", "--model", m, "--scans", "-"]);
    let mut stdin = child.stdin.take().unwrap();
    let writer = std::thread::spawn(move || {
        let chunk = "0 0 0\n".repeat(100_000);
        // (The reader stops early: a broken pipe ends the writing.)
        for _ in 0..=pficp::cloud::MAX_CLOUD_POINTS / 100_000 {
            if stdin.write_all(chunk.as_bytes()).is_err() {
                return;
            }
        }
    });
    assert_error(&child.wait_with_output().unwrap(), &["frame 0", "without an empty line"]);
    writer.join().unwrap();
}
