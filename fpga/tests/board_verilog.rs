//! The board's Verilog: clean under Verilator's lint with the waivers hdl-gen writes down
//! (fails, never skips, without Verilator).
#![cfg(feature = "rtl")]

use pficp_fpga::board::BoardConfig;
use pficp_fpga::common::verilog::board_verilog;

/// `verilator --lint-only -Wall` (with hdl-gen's waivers) on `v`, written to
/// `$CARGO_TARGET_TMPDIR/<name>/<name>.v`; fails the test on any warning.
fn lints_clean(name: &str, v: &str) {
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("{name}_verilog"));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join(format!("{name}.v"));
    std::fs::write(&file, v).unwrap();
    let out = std::process::Command::new("verilator")
        .args(["--lint-only", "-Wall", "-Wno-WIDTH", "-Wno-DECLFILENAME", "-Wno-UNUSEDPARAM", "--top-module", "top"])
        .arg(&file)
        .output()
        .expect("verilator not found: install it with `apt-get install -y verilator yosys` (tests/run-all does)");
    assert!(out.status.success(), "lint of {}:\n{}", file.display(), String::from_utf8_lossy(&out.stderr));
}

#[test]
fn board_verilog_has_the_pins_and_lints_clean() {
    let config = BoardConfig::default();
    let v = board_verilog(&config);
    assert!(v.contains("module top(clock,reset_n,uart_rx,uart_tx,leds);"), "the top's pins");
    assert!(v.contains("output reg  [3:0] leds;"));
    lints_clean("board", &v);
}

#[test]
fn sequencer_verilog_lints_clean() {
    lints_clean("sequencer", &pficp_fpga::common::verilog::sequencer_verilog());
}
