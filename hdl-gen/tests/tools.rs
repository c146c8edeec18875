//! Real Verilator and Yosys runs (Verilator 5.006, Yosys 0.23). These tests do not skip when
//! the tools are missing: they fail with the install hint (`apt-get install -y verilator yosys`).

use hdl_gen::{lint, lint_file, synthesise, write_verilog, SynthOptions, INSTALL_HINT, VERILOG_FILE};
use std::path::PathBuf;
use std::process::Command;

fn tiny() -> String {
    std::fs::read_to_string(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/tiny_top.v")).unwrap()
}

fn fresh_dir(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// Unwraps, printing the whole error (which carries the install hint if a tool is missing).
fn ok<T>(r: anyhow::Result<T>) -> T {
    r.unwrap_or_else(|e| panic!("{e:#}\n(the HDL tools are required: {INSTALL_HINT})"))
}

#[test]
fn lint_and_synthesise_tiny_design() {
    let dir = fresh_dir("hdl-gen-tiny");
    let v = tiny();
    let report = ok(lint(&v, &dir));
    assert!(report.is_clean(), "{}", report.output);
    assert_eq!(report.file, dir.join(VERILOG_FILE));

    let t = std::time::Instant::now();
    let r = ok(synthesise(&v, &dir, &SynthOptions::default()));
    assert!(t.elapsed().as_secs() < 60, "yosys took {:?}", t.elapsed());
    assert_eq!(r.dsp, 1, "the registered 18 x 18 multiplier is one DSP48A1: {:?}", r.cells_by_type);
    assert!(r.bram16 >= 1.0, "the 1024 x 48 RAM is block RAM: {:?}", r.cells_by_type);
    assert!(r.depth > 0, "logic depth");
    assert_eq!(r.depth_path.len(), r.depth + 1);
    assert!(r.depth_path[1..].iter().all(|s| s.cell_type.is_some()), "{:?}", r.depth_path);
    assert!(r.carry4 > 0 && r.lut > 0 && r.ff > 0);
    assert!(r.sta_ps.is_some());
    assert!(r.yosys_version.starts_with("Yosys "), "{}", r.yosys_version);
    for f in ["yosys.log", "synth.ys", "yosys_stat.json", "yosys_ltp.txt", "yosys_sta.txt", "yosys_cells.txt"] {
        assert!(dir.join(f).is_file(), "{f}");
    }
    let log = std::fs::read_to_string(dir.join("yosys.log")).unwrap();
    assert!(log.contains("Executing SYNTH_XILINX pass"), "the log is complete");
}

#[test]
fn io_pads_option_keeps_the_buffers() {
    let dir = fresh_dir("hdl-gen-tiny-pads");
    let r = ok(synthesise(&tiny(), &dir, &SynthOptions { io_pads: true, ..SynthOptions::default() }));
    assert!(r.io_buffers > 100 && r.bufg == 1, "{:?}", r.cells_by_type);
    assert_eq!(r.dsp, 1);
}

/// Without the waivers, Verilator -Wall reports exactly WIDTH and DECLFILENAME on the tiny
/// design; with them it is clean. (UNUSEDPARAM is needed by the board: `cli_board_one_lane`.)
#[test]
fn waivers_are_needed_and_sufficient() {
    let dir = fresh_dir("hdl-gen-no-waivers");
    std::fs::create_dir_all(&dir).unwrap();
    let raw = dir.join(VERILOG_FILE);
    std::fs::write(&raw, tiny()).unwrap();
    let r = ok(lint_file(&raw));
    assert!(!r.is_clean());
    let mut codes: Vec<&str> = r.messages.iter().filter_map(|m| m.code.as_deref()).collect();
    codes.sort();
    codes.dedup();
    assert_eq!(codes, ["DECLFILENAME", "WIDTH"], "{}", r.output);
    let waived = write_verilog(&tiny(), &dir).unwrap();
    assert!(ok(lint_file(&waived)).is_clean());
}

#[test]
fn lint_failure_shows_verilator_output() {
    let dir = fresh_dir("hdl-gen-lint-fail");
    let bad = "module top(input wire clock, input wire [3:0] d, output reg [3:0] q);\n\
               wire [3:0] spare_bits;\n\
               always @(posedge clock) q <= d;\nendmodule\n";
    let err = format!("{:#}", lint(bad, &dir).unwrap_err());
    assert!(err.contains("Verilator lint of"), "{err}");
    assert!(err.contains("%Warning-UNUSEDSIGNAL"), "{err}");
    assert!(err.contains("spare_bits"), "{err}");
}

#[test]
fn yosys_failure_is_reported() {
    let dir = fresh_dir("hdl-gen-yosys-fail");
    let err = format!(
        "{:#}",
        synthesise("module top(input wire a;\nendmodule\n", &dir, &SynthOptions::default()).unwrap_err()
    );
    assert!(err.contains("Yosys failed"), "{err}");
    assert!(err.contains("ERROR"), "{err}");
    assert!(err.contains("yosys -l yosys.log -s synth.ys"), "{err}");
}

fn hdl_gen(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_hdl-gen")).args(args).output().unwrap();
    (out.status.success(), String::from_utf8_lossy(&out.stdout).into(), String::from_utf8_lossy(&out.stderr).into())
}

#[test]
fn cli_on_a_verilog_file() {
    let dir = fresh_dir("hdl-gen-cli");
    let file = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/tiny_top.v");
    let (okay, stdout, stderr) = hdl_gen(&["--out", dir.to_str().unwrap(), "--verilog", file.to_str().unwrap()]);
    assert!(okay, "{stdout}\n{stderr}");
    assert!(stdout.contains("lint: clean"), "{stdout}");
    assert!(stdout.contains("| DSP48A1 | 1 | 58 | 1.7 % |"), "{stdout}");
    assert!(stdout.contains("**within limits**"), "{stdout}");
    let md = std::fs::read_to_string(dir.join("resources.md")).unwrap();
    assert!(stdout.contains(&md));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("resources.json")).unwrap()).unwrap();
    assert_eq!(json["resources"]["dsp"], 1);
    assert_eq!(json["limits"]["max_dsp"], 58);
    assert!(std::fs::read_to_string(dir.join(VERILOG_FILE)).unwrap().contains("/* verilator lint_off WIDTH */"));
}

#[test]
fn cli_fails_over_limits_but_writes_the_report() {
    let dir = fresh_dir("hdl-gen-cli-limits");
    let file = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/tiny_top.v");
    let (okay, stdout, stderr) = hdl_gen(&[
        "--out",
        dir.to_str().unwrap(),
        "--verilog",
        file.to_str().unwrap(),
        "--no-lint",
        "--max-dsp",
        "0",
        "--max-bram",
        "2.5",
        "--max-levels",
        "0",
    ]);
    assert!(!okay, "{stdout}\n{stderr}");
    assert!(stderr.contains("exceeds the limits: DSP48A1 1 > --max-dsp 0; RAMB16BWER 3 > --max-bram 2.5"), "{stderr}");
    assert!(stderr.contains("logic levels > --max-levels 0"), "{stderr}");
    assert!(!stdout.contains("lint: clean"));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("resources.json")).unwrap()).unwrap();
    assert_eq!(json["limits"]["violations"].as_array().unwrap().len(), 3);
}

#[test]
fn cli_rejects_unsupported_lanes() {
    let dir = fresh_dir("hdl-gen-cli-lanes");
    let (okay, _, stderr) = hdl_gen(&["--out", dir.to_str().unwrap(), "--lanes", "3"]);
    assert!(!okay);
    assert!(stderr.contains("--lanes 3 is not supported"), "{stderr}");
    let (okay, _, stderr) = hdl_gen(&["--out", dir.to_str().unwrap(), "--lanes", "1", "--no-synth"]);
    assert!(!okay);
    assert!(
        stderr.contains("--lanes 1 is not supported: the neighbour pipeline (and so the board) takes one of"),
        "{stderr}"
    );
}

/// The shipped board (the default design at the default P = 8, as `hdl-gen --out DIR`
/// builds it): lints clean with the three waivers, each of which it needs, synthesises with
/// its 8 pins (clock, reset_n, uart_rx, uart_tx, leds[3:0]) and one BUFG, fits the limits
/// (LUT <= 80 %, DSP48A1 <= 58, RAMB16 <= 116, logic levels <= 20: the command fails
/// otherwise), and comes with its UCF and ISE script.
#[test]
fn cli_board_as_shipped() {
    let dir = fresh_dir("hdl-gen-cli-board");
    let (okay, stdout, stderr) = hdl_gen(&["--out", dir.to_str().unwrap()]);
    assert!(okay, "{stdout}\n{stderr}");
    assert!(stdout.contains("pficp_fpga::common::verilog::board_verilog(BoardConfig { lanes: 8,"), "{stdout}");
    assert!(stdout.contains("lint: clean"), "{stdout}");
    assert!(stdout.contains("**within limits**"), "{stdout}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("resources.json")).unwrap()).unwrap();
    let r = &json["resources"];
    eprintln!(
        "board P = 8: LUT {}, FF {}, DSP48A1 {}, RAMB16 {}, {} logic levels",
        r["lut"], r["ff"], r["dsp"], r["bram16"], r["depth"]
    );
    assert_eq!(r["io_buffers"], 8, "{json}");
    assert_eq!(r["bufg"], 1, "{json}");
    // The multipliers are in DSP48A1s, not in LUTs: the transform's 9 and 3 a lane at least.
    let lanes = pficp_fpga::board::BoardConfig::default().lanes as u64;
    assert!(r["dsp"].as_u64().unwrap() >= 9 + 3 * lanes, "{json}");
    assert!(json["limits"]["violations"].as_array().unwrap().is_empty(), "{json}");
    for f in [hdl_gen::UCF_FILE, hdl_gen::ise::TCL_FILE, "resources.md", "yosys.log"] {
        assert!(dir.join(f).is_file(), "{f}");
    }
    // Every waiver is needed by the board: without them, -Wall reports exactly their codes.
    let raw = dir.join("raw_board.v");
    std::fs::write(&raw, pficp_fpga::common::verilog::board_verilog(&pficp_fpga::board::BoardConfig::default()))
        .unwrap();
    let r = ok(lint_file(&raw));
    let mut codes: Vec<&str> = r.messages.iter().filter_map(|m| m.code.as_deref()).collect();
    codes.sort();
    codes.dedup();
    let mut waivers: Vec<&str> = hdl_gen::lint::WAIVERS.iter().map(|(c, _)| *c).collect();
    waivers.sort();
    assert_eq!(codes, waivers, "{}", r.output);
}
