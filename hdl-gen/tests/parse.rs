//! Parsing of captured Yosys and Verilator output (tests/data/tiny_*, produced by hdl-gen from
//! tests/data/tiny_top.v with Yosys 0.23 and Verilator 5.006). No tools needed.

use hdl_gen::lint::parse_verilator_output;
use hdl_gen::synth::{self, parse_cell_lists, parse_ltp, parse_sta, parse_stat_json, SynthOptions};
use hdl_gen::{Limits, Resources};
use std::path::PathBuf;

fn data(name: &str) -> String {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(name);
    std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

#[test]
fn stat_json_counts() {
    let (version, cells) = parse_stat_json(&data("tiny_stat.json")).unwrap();
    assert_eq!(version, "Yosys 0.23 (git sha1 7ce5011c24b)");
    let r = Resources::from_cells(cells);
    assert_eq!((r.lut, r.lut_logic, r.srl, r.inv), (12, 12, 0, 0));
    assert_eq!(r.ff, 13, "the 13-bit sum register; a, b and p are absorbed into the DSP48A1");
    assert_eq!(r.dsp, 1);
    assert_eq!((r.ramb16, r.ramb8, r.bram16), (3, 0, 3.0), "1024 x 48 = three 1024 x 18 RAMB16BWER");
    assert_eq!((r.carry4, r.muxf7, r.muxf8, r.io_buffers, r.bufg), (4, 0, 0, 0, 0));
    assert!(r.other_cells().is_empty(), "{:?}", r.other_cells());
}

#[test]
fn stat_json_with_io_pads() {
    let (_, cells) = parse_stat_json(&data("tiny_stat_iopads.json")).unwrap();
    let r = Resources::from_cells(cells);
    // 178 data ports + the clock's IBUF (clock -> BUFG).
    assert_eq!(r.io_buffers, 179);
    assert_eq!(r.bufg, 1);
    assert_eq!(r.dsp, 1);
    assert!(r.render_markdown().contains("| I/O buffers | 179 | 316 |"));
    assert!(r.other_cells().is_empty(), "{:?}", r.other_cells());
}

#[test]
fn stat_json_rejects_garbage() {
    assert!(parse_stat_json("{}").is_err());
    assert!(parse_stat_json("not json").is_err());
}

#[test]
fn ltp_path_with_cell_types() {
    let path = parse_ltp(&data("tiny_ltp.txt"), "top").unwrap();
    assert_eq!(path.length, 5);
    assert_eq!(path.steps.len(), 6);
    assert_eq!(path.steps[0].net, "\\y [3]");
    assert_eq!(path.steps[0].cell, None);
    let types = parse_cell_lists(&data("tiny_cells.txt"));
    assert_eq!(types.values().filter(|t| *t == "LUT2").count(), 12);
    assert_eq!(types.values().filter(|t| *t == "CARRY4").count(), 4);
    let on_path: Vec<&str> = path.steps[1..].iter().map(|s| types[s.cell.as_ref().unwrap()].as_str()).collect();
    assert_eq!(on_path, ["LUT2", "CARRY4", "CARRY4", "CARRY4", "CARRY4"]);
}

#[test]
fn sta_latest_arrival() {
    assert_eq!(parse_sta(&data("tiny_sta.txt")), Some(1328));
}

#[test]
fn verilator_warnings_without_waivers() {
    let m = parse_verilator_output(&data("tiny_verilator_no_waivers.txt"));
    let codes: Vec<&str> = m.iter().map(|m| m.code.as_deref().unwrap()).collect();
    assert_eq!(codes, ["DECLFILENAME", "WIDTH", "WIDTH"]);
    assert_eq!(m[1].location.as_deref(), Some("pficp_pipeline.v:27:21"));
    assert_eq!(m[1].text, "Operator AND expects 13 bits on the LHS, but LHS's VARREF 'x' generates 12 bits.");
    assert!(m.iter().all(|m| m.severity == "Warning"));
    // Every code Verilator reports on the unwaived file is one of hdl-gen's waivers.
    for c in codes {
        assert!(hdl_gen::lint::WAIVERS.iter().any(|(w, _)| *w == c), "{c}");
    }
}

/// The whole report from the captured files, as `synthesise` builds it after running Yosys.
#[test]
fn report_from_captured_files() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("hdl-gen-parse-report");
    std::fs::create_dir_all(&dir).unwrap();
    for (from, to) in [
        ("tiny_stat.json", synth::STAT_FILE),
        ("tiny_ltp.txt", synth::LTP_FILE),
        ("tiny_cells.txt", synth::CELLS_FILE),
        ("tiny_sta.txt", synth::STA_FILE),
    ] {
        std::fs::write(dir.join(to), data(from)).unwrap();
    }
    let mut r = synth::resources_from_dir(&dir, &SynthOptions::default(), 0).unwrap();
    r.source = "tiny_top.v".into();
    assert_eq!((r.dsp, r.bram16, r.depth, r.sta_ps), (1, 3.0, 5, Some(1328)));
    assert_eq!(r.depth_path[5].cell_type.as_deref(), Some("CARRY4"));
    assert_eq!(r.synth_command, "synth_xilinx -family xc6s -top top -flatten -noiopad -noclkbuf");

    let md = r.render_markdown();
    for needle in [
        "# Resources: tiny_top.v on the Spartan-6 XC6SLX45-2FGG484",
        "| LUT | 12 | 27288 | 0.0 % | LUT1..LUT6 12 + INV 0 + shift registers (SRL16E/SRLC32E) 0 + LUT RAM 0 |",
        "| FF | 13 | 54576 | 0.0 % | all FD* types |",
        "| DSP48A1 | 1 | 58 | 1.7 % |  |",
        "| RAMB16BWER | 3 | 116 | 2.6 % | 3 RAMB16BWER + 0 RAMB8BWER counted as half each |",
        "| CARRY4 | 4 | 3411 | 0.1 % |",
        "| MUXF7 | 0 | 6822 | 0.0 % |",
        "| MUXF8 | 0 | 3411 | 0.0 % |",
        "**5 levels**",
        "| 0 | start |  | `y [3]` |",
        "| 1 | LUT2 |",
        "| 5 | CARRY4 |",
        "**1328 ps** with **Xilinx 7-series** cell delays",
    ] {
        assert!(md.contains(needle), "missing {needle:?} in\n{md}");
    }
    assert!(!md.contains("| I/O buffers |"));
    assert!(Limits::default().render_markdown(&r).contains("**within limits**"));

    let j = r.to_json();
    assert_eq!(j["resources"]["dsp"], 1);
    assert_eq!(j["resources"]["bram16"], 3.0);
    assert_eq!(j["resources"]["depth"], 5);
    assert_eq!(j["resources"]["sta_ps"], 1328);
    assert_eq!(j["device_totals"]["LUT6"], 27288);
    assert_eq!(j["utilisation"][2]["resource"], "DSP48A1");
    assert_eq!(j["utilisation"][2]["percent"], 1.7);
    assert!(j["sta_delay_model"].as_str().unwrap().contains("7-series"));
}
