//! The pin map, the UCF and the ISE script: the committed UCF is what hdl-gen writes, every
//! port of the board top is pinned, the PERIOD follows the clock, bad pin maps fail clearly.
//! These runs skip the lint and synthesis (tests/tools.rs runs them on the board).

use hdl_gen::ucf::{render_ucf, top_ports, Direction, DEFAULT_PINMAP};
use hdl_gen::{ise, PinMap, Port, TOP, UCF_FILE, VERILOG_FILE};
use std::path::{Path, PathBuf};
use std::process::Command;

fn fresh_dir(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn repo_file(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..").join(rel)
}

fn hdl_gen(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_hdl-gen")).args(args).output().unwrap();
    (out.status.success(), String::from_utf8_lossy(&out.stdout).into(), String::from_utf8_lossy(&out.stderr).into())
}

/// `hdl-gen --out DIR --lanes 2 --no-lint --no-synth ARGS..`: the board design by default.
fn generate(dir: &Path, args: &[&str]) -> (bool, String, String) {
    let mut all = vec!["--out", dir.to_str().unwrap(), "--lanes", "2", "--no-lint", "--no-synth"];
    all.extend_from_slice(args);
    hdl_gen(&all)
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// The board top's ports, as the RTL writes them.
fn board_ports() -> Vec<Port> {
    top_ports(&pficp_fpga::common::verilog::board_verilog(&Default::default()), TOP).unwrap()
}

/// The default pin map's text with `from` replaced by `to` (which must occur).
fn edited_map(from: &str, to: &str) -> String {
    assert!(DEFAULT_PINMAP.contains(from), "{from:?}");
    DEFAULT_PINMAP.replacen(from, to, 1)
}

/// The default pin map without the entry (and its comments) of `port`.
fn without_port(port: &str) -> String {
    let header = format!("[ports.{port}]");
    let blocks: Vec<&str> = DEFAULT_PINMAP.split("\n\n").collect();
    assert!(blocks.iter().any(|b| b.contains(&header)), "{port}");
    blocks.into_iter().filter(|b| !b.contains(&header)).collect::<Vec<_>>().join("\n\n")
}

fn write_map(dir: &Path, text: &str) -> PathBuf {
    let p = dir.join("pinmap.toml");
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn committed_ucf_is_what_hdl_gen_writes() {
    let dir = fresh_dir("constraints-committed");
    let (ok, stdout, stderr) = generate(&dir, &[]);
    assert!(ok, "{stdout}\n{stderr}");
    let committed = read(&repo_file("constraints/pficp_board.ucf"));
    assert_eq!(
        read(&dir.join(UCF_FILE)),
        committed,
        "constraints/pficp_board.ucf is stale: regenerate it with \
         `cargo run -p hdl-gen -- --out out/hdl --no-lint --no-synth && cp out/hdl/pficp_board.ucf constraints/`"
    );
    // The built-in pin map is the committed file.
    assert_eq!(read(&repo_file("constraints/pinmap.toml")), DEFAULT_PINMAP);
}

#[test]
fn ucf_pins_every_port_of_the_board_top() {
    let dir = fresh_dir("constraints-every-port");
    let (ok, stdout, stderr) = generate(&dir, &[]);
    assert!(ok, "{stdout}\n{stderr}");
    assert!(stdout.contains("board_verilog(BoardConfig { lanes: 2, clock_hz: 50000000, baud: 3000000 })"), "{stdout}");
    assert!(
        stdout.contains("UART: 3000000 baud at 50000000 Hz: 16 2/3 clocks per bit (50/3), exact on average"),
        "{stdout}"
    );
    let ucf = read(&dir.join(UCF_FILE));
    let ports = top_ports(&read(&dir.join(VERILOG_FILE)), TOP).unwrap();
    let names: Vec<&str> = ports.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(names, ["clock", "reset_n", "uart_rx", "uart_tx", "leds"]);
    assert_eq!(ports[4].range, Some((3, 0)));
    assert_eq!(ports[3].direction, Direction::Output);
    let mut balls = Vec::new();
    for net in ports.iter().flat_map(|p| p.nets()) {
        let prefix = format!("NET \"{net}\" LOC = ");
        let lines: Vec<&str> = ucf.lines().filter(|l| l.starts_with(&prefix)).collect();
        assert_eq!(lines.len(), 1, "{net} in\n{ucf}");
        let rest = &lines[0][prefix.len()..];
        let (ball, attrs) = rest.split_once(" | ").unwrap();
        assert!(attrs.starts_with("IOSTANDARD = LVCMOS33") && attrs.ends_with(';'), "{}", lines[0]);
        balls.push(ball.to_string());
    }
    assert_eq!(balls, ["AB11", "A20", "K18", "L17", "B16", "A16", "F16", "A21"]);
    assert!(ucf.contains("NET \"clock\" TNM_NET = \"clock\";\n"), "{ucf}");
    assert!(ucf.contains("TIMESPEC \"TS_clock\" = PERIOD \"clock\" 20 ns HIGH 50%;"), "{ucf}");
    assert!(ucf.contains("NET \"uart_rx\" LOC = K18 | IOSTANDARD = LVCMOS33 | PULLUP;"));
    assert!(ucf.contains("NET \"leds<3>\" LOC = A21 | IOSTANDARD = LVCMOS33 | DRIVE = 24 | SLEW = QUIETIO;"));
    assert_eq!(ucf.matches("PERIOD").count(), 1);
}

/// A board with a 100 MHz oscillator: the PERIOD and the UART divider follow --clock-hz.
#[test]
fn period_follows_the_clock() {
    let dir = fresh_dir("constraints-100mhz");
    let map = write_map(&dir, &edited_map("frequency_hz = 50_000_000", "frequency_hz = 100_000_000"));
    let out = dir.join("out");
    let (ok, stdout, stderr) =
        generate(&out, &["--pinmap", map.to_str().unwrap(), "--clock-hz", "100000000", "--baud", "115200"]);
    assert!(ok, "{stdout}\n{stderr}");
    assert!(stdout.contains("clock_hz: 100000000, baud: 115200"), "{stdout}");
    assert!(stdout.contains("UART: 115200 baud at 100000000 Hz: 868 1/18 clocks per bit (15625/18)"), "{stdout}");
    let ucf = read(&out.join(UCF_FILE));
    assert!(ucf.contains("TIMESPEC \"TS_clock\" = PERIOD \"clock\" 10 ns HIGH 50%;  # 100000000 Hz"), "{ucf}");
    assert!(ucf.contains(&format!("from the pin map {}", map.display())), "{ucf}");
    // --clock-hz defaults to the pin map's oscillator.
    let out2 = dir.join("out2");
    let (ok, stdout, _) = generate(&out2, &["--pinmap", map.to_str().unwrap()]);
    assert!(ok);
    assert!(stdout.contains("clock_hz: 100000000, baud: 3000000"), "{stdout}");
    assert!(read(&out2.join(UCF_FILE)).contains("PERIOD \"clock\" 10 ns"));
}

#[test]
fn clock_other_than_the_oscillator_is_refused() {
    let dir = fresh_dir("constraints-wrong-clock");
    let (ok, stdout, stderr) = generate(&dir, &["--clock-hz", "100000000"]);
    assert!(!ok, "{stdout}");
    assert!(stderr.contains("the design clock is 100000000 Hz but the board's oscillator"), "{stderr}");
    assert!(stderr.contains("no DCM") && stderr.contains("--clock-hz 50000000"), "{stderr}");
    assert!(!dir.join(VERILOG_FILE).exists(), "fails before generating");
    let (ok, _, stderr) = generate(&dir, &["--baud", "20000000"]);
    assert!(!ok);
    assert!(stderr.contains("at least 4 clocks per bit"), "{stderr}");
    // A rate whose bit period does not reduce enough for the UART's phase accumulator.
    let (ok, _, stderr) = generate(&dir, &["--baud", "3000001"]);
    assert!(!ok);
    assert!(stderr.contains("--baud 3000001") && stderr.contains("50000000/3000001"), "{stderr}");
}

#[test]
fn ise_script_names_the_part_and_the_files() {
    let dir = fresh_dir("constraints-ise");
    let (ok, stdout, stderr) = generate(&dir, &[]);
    assert!(ok, "{stdout}\n{stderr}");
    assert!(stdout.contains("xtclsh build_ise.tcl gives top.bit"), "{stdout}");
    let tcl = read(&dir.join(ise::TCL_FILE));
    assert_eq!(tcl, ise::build_script(VERILOG_FILE, UCF_FILE, TOP));
    for line in [
        "project new $project.xise",
        "project set family \"Spartan6\"",
        "project set device \"xc6slx45\"",
        "project set package \"fgg484\"",
        "project set speed \"-2\"",
        "xfile add \"pficp_pipeline.v\"",
        "xfile add \"pficp_board.ucf\"",
        "set top top",
        "project set top $top",
        "process run \"Generate Programming File\"",
        "set status [process get \"Generate Programming File\" status]",
    ] {
        assert!(tcl.lines().any(|l| l.trim() == line), "missing {line:?} in\n{tcl}");
    }
    assert!(tcl.contains("#   xtclsh build_ise.tcl\n"), "how to run");
    assert!(tcl.contains("# Result: top.bit in this folder"));
    assert!(tcl.contains("Vivado does not support Spartan-6"));
    // Balanced braces: a sanity check on the Tcl the format string produced.
    assert_eq!(tcl.matches('{').count(), tcl.matches('}').count());
}

#[test]
fn block_designs_get_no_ucf() {
    for design in ["weights", "surface-residual", "polish-program", "polish-bench", "polish-unit"] {
        let dir = fresh_dir(&format!("constraints-block-{design}"));
        let (ok, stdout, stderr) = generate(&dir, &["--design", design]);
        assert!(ok, "{stdout}\n{stderr}");
        assert!(
            stdout.contains(&format!("no UCF or ISE script: the {design} design is a block without pins")),
            "{stdout}"
        );
        assert!(!dir.join(UCF_FILE).exists() && !dir.join(ise::TCL_FILE).exists());
        let (ok, _, stderr) = generate(&dir, &["--design", design, "--pinmap", "x.toml"]);
        assert!(!ok);
        assert!(stderr.contains(&format!("the {design} design has no pins")), "{stderr}");
        let (ok, _, stderr) = generate(&dir, &["--design", design, "--baud", "115200"]);
        assert!(!ok);
        assert!(stderr.contains("apply to the board"), "{stderr}");
    }
}

/// `--verilog FILE --pinmap MAP` pins a hand-written top; without --pinmap there is no UCF.
#[test]
fn verilog_file_with_a_pin_map() {
    let dir = fresh_dir("constraints-verilog");
    let v = dir.join("board.v");
    std::fs::write(
        &v,
        "module top(input wire clock, input wire reset_n, input wire uart_rx, output wire uart_tx,\n\
         output wire [3:0] leds);\n  assign uart_tx = uart_rx;\n  assign leds = {4{reset_n}};\nendmodule\n",
    )
    .unwrap();
    let map = repo_file("constraints/pinmap.toml");
    let out = dir.join("out");
    let (ok, stdout, stderr) = hdl_gen(&[
        "--out",
        out.to_str().unwrap(),
        "--verilog",
        v.to_str().unwrap(),
        "--pinmap",
        map.to_str().unwrap(),
        "--no-lint",
        "--no-synth",
    ]);
    assert!(ok, "{stdout}\n{stderr}");
    let ucf = read(&out.join(UCF_FILE));
    assert!(ucf.contains("NET \"leds<2>\" LOC = F16"), "{ucf}");
    assert!(out.join(ise::TCL_FILE).exists());
    let out2 = dir.join("out2");
    let (ok, stdout, _) =
        hdl_gen(&["--out", out2.to_str().unwrap(), "--verilog", v.to_str().unwrap(), "--no-lint", "--no-synth"]);
    assert!(ok);
    assert!(stdout.contains("no UCF or ISE script: --verilog without --pinmap"), "{stdout}");
    assert!(!out2.join(UCF_FILE).exists());
}

/// Each kind of bad pin map: the error names the map, the entry and what to do.
#[test]
fn bad_pin_maps_give_clear_errors() {
    let parse = |text: &str| format!("{:#}", PinMap::parse(text, "bad.toml").unwrap_err());
    let e = parse("[board]\nname = \"x\"\n[ports.clock\npin = \"AB11\"\n");
    assert!(e.contains("pin map bad.toml is not valid") && e.contains("line 3"), "{e}");
    let e = parse(&edited_map("pull = \"PULLUP\"", "pul = \"PULLUP\""));
    assert!(e.contains("unknown field `pul`"), "{e}");
    let e = parse(&edited_map("pin = \"AB11\"", "pin = \"AB10\""));
    assert!(e.contains("[ports.clock]: the clock's ball AB10 is not a global-clock (GCLK) input"), "{e}");
    let e = parse(&edited_map("pin = \"K18\"", "pin = \"L17\""));
    assert!(e.contains("ball L17 is given twice: uart_rx and uart_tx"), "{e}");
    let e = parse(&edited_map("pin = \"K18\"", "pin = \"K23\""));
    assert!(e.contains("\"K23\" (uart_rx) is not a ball of the FGG484 package"), "{e}");
    let e = parse(&edited_map("iostandard = \"LVCMOS33\"", "iostandard = \"LVCMOS3\""));
    assert!(e.contains("[board] iostandard = \"LVCMOS3\" is not a Spartan-6 single-ended standard"), "{e}");
    let e = parse(&edited_map("drive = 24", "drive = 20"));
    assert!(e.contains("[ports.leds]: drive 20"), "{e}");
    let e = parse(&edited_map("frequency_hz = 50_000_000\n", ""));
    assert!(e.contains("no clock: give the clock port's entry frequency_hz"), "{e}");
    let e = parse(&edited_map("slew = \"SLOW\"", "slew = \"SLOW\"\nfrequency_hz = 1"));
    assert!(e.contains("give it for the one clock port only"), "{e}");
    let e = parse(&edited_map("pin = \"K18\"", "pins = [\"K18\"]\npin = \"K18\""));
    assert!(e.contains("give either pin (one bit) or pins (a bus), not both"), "{e}");
    // Several problems: all listed at once.
    let e = parse(&edited_map("drive = 24", "drive = 20").replacen("slew = \"SLOW\"", "slew = \"SLOWER\"", 1));
    assert!(e.contains("has 2 problem(s)") && e.contains("drive 20") && e.contains("slew \"SLOWER\""), "{e}");

    // Against the board top's ports.
    let ports = board_ports();
    let fit = |text: &str| {
        format!("{:#}", render_ucf(&PinMap::parse(text, "bad.toml").unwrap(), &ports, 50_000_000).unwrap_err())
    };
    let e = fit(&without_port("uart_tx"));
    assert!(
        e.contains("port `uart_tx` (output uart_tx) of top is missing from the pin map: add [ports.uart_tx]"),
        "{e}"
    );
    let e = fit(&edited_map("pins = [\"B16\", \"A16\", \"F16\", \"A21\"]", "pins = [\"B16\", \"A16\", \"F16\"]"));
    assert!(
        e.contains("port `leds` is 4 bit(s) wide (output [3:0] leds) but the pin map gives pins = [3 balls]"),
        "{e}"
    );
    let e = fit(&format!("{DEFAULT_PINMAP}\n[ports.spare]\npin = \"A4\"\n"));
    assert!(e.contains("the pin map names `spare`, which is not a port of top"), "{e}");
    let e = fit(&edited_map("pin = \"K18\"\npull = \"PULLUP\"", "pin = \"K18\"\nslew = \"FAST\""));
    assert!(e.contains("port `uart_rx` is an input: drive and slew apply to outputs only"), "{e}");
    let map = PinMap::default_map();
    let e = format!("{:#}", render_ucf(&map, &ports, 100_000_000).unwrap_err());
    assert!(e.contains("the board top has no DCM"), "{e}");
}

/// A bad pin map stops the CLI before anything is generated, with a non-zero exit.
#[test]
fn bad_pin_map_fails_the_cli() {
    let dir = fresh_dir("constraints-bad-cli");
    let malformed = write_map(&dir, "[board\nname = 1\n");
    let out = dir.join("out");
    let (ok, _, stderr) = generate(&out, &["--pinmap", malformed.to_str().unwrap()]);
    assert!(!ok);
    assert!(stderr.starts_with("hdl-gen: error: pin map "), "{stderr}");
    assert!(stderr.contains("is not valid"), "{stderr}");
    assert!(!out.join(VERILOG_FILE).exists());

    let missing = write_map(&dir, &without_port("reset_n"));
    let (ok, _, stderr) = generate(&out, &["--pinmap", missing.to_str().unwrap()]);
    assert!(!ok);
    assert!(stderr.contains("port `reset_n` (input reset_n) of top is missing from the pin map"), "{stderr}");
    assert!(!out.join(UCF_FILE).exists());

    let (ok, _, stderr) = generate(&out, &["--pinmap", dir.join("nope.toml").to_str().unwrap()]);
    assert!(!ok);
    assert!(stderr.contains("could not read the pin map"), "{stderr}");
}
