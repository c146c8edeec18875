//! The neighbour pipeline's Verilog (`neighbour_pipeline_verilog`): clean under Verilator's
//! lint, at 4 and 16 lanes (fails, never skips, without Verilator). Its behaviour is checked
//! in lockstep with the cycle model under Verilator (sim/tests/neighbour_pipeline.rs).
#![cfg(feature = "rtl")]

use pficp_fpga::common::verilog::neighbour_pipeline_verilog;

#[test]
fn neighbour_pipeline_verilog_lints_clean() {
    for lanes in [4, 16] {
        let v = neighbour_pipeline_verilog(lanes);
        assert!(v.contains("module top(clock,model_we,model_waddr,model_wdata,table_we,table_waddr,table_wdata,"));
        let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("neighbour_verilog");
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join(format!("neighbour_{lanes}.v"));
        std::fs::write(&file, &v).unwrap();
        let out = std::process::Command::new("verilator")
            .args([
                "--lint-only",
                "-Wall",
                "-Wno-WIDTH",
                "-Wno-DECLFILENAME",
                "-Wno-UNUSEDPARAM",
                "--top-module",
                "top",
            ])
            .arg(&file)
            .output()
            .expect("verilator not found: install it with `apt-get install -y verilator yosys`");
        assert!(out.status.success(), "lint of {}:\n{}", file.display(), String::from_utf8_lossy(&out.stderr));
    }
}
