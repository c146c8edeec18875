//! `hdl-gen`: writes the PF-ICP Verilog (for the board also its UCF and ISE 14.7 script), lints
//! it (Verilator) and reports its Spartan-6 resources and logic depth (Yosys). See `hdl-gen --help`.

use anyhow::{bail, Context, Result};
use clap::Parser;
use hdl_gen::ucf::{top_ports, write_ucf, DEFAULT_PINMAP_PATH};
use hdl_gen::{ise, lint, synthesise, write_verilog, Limits, PinMap, SynthOptions, TOP, VERILOG_FILE};
use pficp_fpga::board::BoardConfig;
use pficp_fpga::designs::{Design, Params, DESIGNS};
use std::path::PathBuf;

/// Writes DIR/pficp_pipeline.v; for the board also DIR/pficp_board.ucf (from the pin map) and
/// DIR/build_ise.tcl (ISE 14.7: `cd DIR && xtclsh build_ise.tcl` gives top.bit; Vivado does not
/// support Spartan-6). Lints the Verilog with `verilator --lint-only -Wall`, synthesises it with
/// Yosys `synth_xilinx -family xc6s -flatten` and writes DIR/resources.md and
/// DIR/resources.json (LUT/FF/DSP48A1/RAMB16/CARRY4/MUXF against the XC6SLX45, the longest
/// logic path, a 7-series `sta` estimate). Exits non-zero if the pin map is malformed or does
/// not fit the top, the lint is not clean, a tool is missing or fails, or the design exceeds
/// the limits.
#[derive(Parser, Debug)]
#[command(name = "hdl-gen", version)]
struct Cli {
    /// Output directory (created if missing).
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Number of parallel lanes P of the generated pipeline (default: the shipped board's).
    #[arg(long, value_name = "P", default_value_t = BoardConfig::default().lanes, conflicts_with = "verilog")]
    lanes: usize,
    /// Which design to generate: the whole board (pins, UART, protocol engine, pipeline), or
    /// one of the board's blocks alone: the neighbour pipeline, the weight stage, the surface
    /// residual stage, the polish's datapath, the polish's blocks with a multiplier, or the
    /// whole polish. Only the board has pins, so only the board gets a UCF and an ISE script.
    #[arg(long, value_parser = design_values(), default_value = "board", conflicts_with = "verilog")]
    design: String,
    /// Use the Verilog in FILE (top module `top`) instead of generating a design; with
    /// --pinmap, also write its UCF and ISE script.
    #[arg(long, value_name = "FILE")]
    verilog: Option<PathBuf>,
    /// The board pin map (TOML, constraints/README.md) [default: the committed
    /// constraints/pinmap.toml, built in].
    #[arg(long, value_name = "FILE")]
    pinmap: Option<PathBuf>,
    /// The board clock in Hz: the oscillator, as the board top has no DCM, so it must be the
    /// pin map's frequency_hz [default: the pin map's (50 MHz on the committed map)].
    #[arg(long, value_name = "HZ")]
    clock_hz: Option<u32>,
    /// The board's UART baud rate, at least 4 clocks per bit; the bit timing is exact on
    /// average at any rate whose bit period `clock / baud` reduces to a numerator below 2^23
    /// (every common rate) [default: 3000000].
    #[arg(long, value_name = "BAUD")]
    baud: Option<u32>,
    /// Skip the Verilator lint.
    #[arg(long)]
    no_lint: bool,
    /// Skip the Yosys synthesis and the resource report.
    #[arg(long)]
    no_synth: bool,
    /// Synthesise with I/O pads and the clock buffer (always on for the board; the default,
    /// `-noiopad -noclkbuf`, suits a block inside the board top).
    #[arg(long)]
    io_pads: bool,
    /// Fail if the design uses more than this percentage of the LUTs.
    #[arg(long, value_name = "PERCENT", default_value_t = hdl_gen::report::DEFAULT_MAX_LUT_PERCENT)]
    max_lut_percent: f64,
    /// Fail if the design uses more DSP48A1s than this.
    #[arg(long, value_name = "N", default_value_t = 58)]
    max_dsp: u64,
    /// Fail if the design uses more RAMB16BWER equivalents than this (RAMB8BWER = 0.5).
    #[arg(long, value_name = "N", default_value_t = 116.0)]
    max_bram: f64,
    /// Fail if the longest register-to-register path has more logic levels than this (Yosys
    /// `ltp` on the flattened netlist; a carry chain counts one level per CARRY4).
    #[arg(long, value_name = "N", default_value_t = hdl_gen::report::DEFAULT_MAX_LEVELS)]
    max_levels: usize,
    /// No spinners on stderr while the design is generated, linted and synthesised (they are
    /// drawn only when stderr is a terminal).
    #[arg(long, short)]
    quiet: bool,
}

/// Run `work` under a spinner labelled `label` (with the elapsed time) when stderr is a
/// terminal and not `--quiet`; the spinner is removed when the work ends.
fn step<T>(cli: &Cli, label: &str, work: impl FnOnce() -> Result<T>) -> Result<T> {
    use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
    use std::io::IsTerminal;
    let spinner = if !cli.quiet && std::io::stderr().is_terminal() {
        let s = ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr());
        s.set_style(
            ProgressStyle::with_template("{spinner} {msg} {elapsed}")
                .unwrap_or_else(|_| ProgressStyle::default_spinner()),
        );
        s.set_message(label.to_string());
        s.enable_steady_tick(std::time::Duration::from_millis(120));
        s
    } else {
        ProgressBar::hidden()
    };
    let result = work();
    spinner.finish_and_clear();
    result
}

/// The `--design` values: the registry's designs that `hdl-gen` writes
/// (`pficp_fpga::designs::DESIGNS`, those with a `cli` name), with their descriptions.
fn design_values() -> clap::builder::PossibleValuesParser {
    // The default, the board, first.
    let (board, blocks): (Vec<&Design>, Vec<&Design>) =
        DESIGNS.iter().partition(|d| matches!(d.params, Params::Board(_)));
    clap::builder::PossibleValuesParser::new(
        board.into_iter().chain(blocks).filter_map(|d| Some(clap::builder::PossibleValue::new(d.cli?).help(d.about))),
    )
}

/// The registry's entry for a `--design` value (one of [`design_values`]).
fn design(cli: &str) -> &'static Design {
    Design::by_cli(cli).expect("clap accepts only the registry's --design values")
}

/// The design's Verilog with `lanes` lanes, from the RTL crate, and where it came from.
fn generated_verilog(design: &Design, lanes: usize, board: &BoardConfig) -> Result<(String, String)> {
    use pficp_fpga::common::rtl::BOARD_LANES;
    let config = match design.params {
        Params::Board(_) => *board,
        Params::Lanes | Params::None => BoardConfig { lanes, ..*board },
    };
    if !matches!(design.params, Params::None) && !BOARD_LANES.contains(&config.lanes) {
        bail!(
            "--lanes {lanes} is not supported: the neighbour pipeline (and so the board) takes one of {BOARD_LANES:?}"
        )
    }
    Ok(((design.verilog)(&config), design.source(&config)))
}

/// The board's generation parameters from the options and the pin map, checked.
fn board_config(cli: &Cli, map: &PinMap) -> Result<BoardConfig> {
    let clock_hz = match cli.clock_hz {
        Some(hz) => hz,
        None => u32::try_from(map.clock_hz)
            .with_context(|| format!("the pin map's frequency_hz {} does not fit the design", map.clock_hz))?,
    };
    map.check_clock(clock_hz as u64)?;
    let config = BoardConfig { lanes: cli.lanes, clock_hz, baud: cli.baud.unwrap_or(BoardConfig::default().baud) };
    if let Some(problem) = config.uart_problem() {
        bail!("--baud {}: {problem}", config.baud);
    }
    Ok(config)
}

fn run(cli: &Cli) -> Result<()> {
    let board = cli.verilog.is_none() && matches!(design(&cli.design).params, Params::Board(_));
    let pins = board || (cli.verilog.is_some() && cli.pinmap.is_some());
    if !pins {
        if cli.pinmap.is_some() {
            bail!(
                "--pinmap applies to the board (--design board) or to --verilog FILE; the {} design has no pins",
                cli.design
            );
        }
        if cli.clock_hz.is_some() || cli.baud.is_some() {
            bail!("--clock-hz and --baud apply to the board (--design board) only");
        }
    }
    if cli.verilog.is_some() && cli.baud.is_some() {
        bail!("--baud applies to the generated board (--design board), not to --verilog");
    }
    // The pin map first: a bad one fails before anything is generated.
    let map = if pins { Some(PinMap::load(cli.pinmap.as_deref())?) } else { None };
    let config = match &map {
        Some(m) if board => board_config(cli, m)?,
        _ => BoardConfig { lanes: cli.lanes, ..BoardConfig::default() },
    };
    let (verilog, source) = match &cli.verilog {
        Some(f) => {
            let v = std::fs::read_to_string(f).with_context(|| format!("could not read --verilog {}", f.display()))?;
            (v, format!("{} (top `{TOP}`)", f.display()))
        }
        None => step(cli, "generating the Verilog", || generated_verilog(design(&cli.design), cli.lanes, &config))?,
    };
    let path = write_verilog(&verilog, &cli.out)?;
    println!("wrote {} ({source})", path.display());
    if board {
        let period = config.bit_period();
        println!(
            "UART: {} baud at {} Hz: {period} clocks per bit ({}/{}), exact on average (every bit \
             boundary within one clock of its exact time)",
            config.baud, config.clock_hz, period.clocks, period.bits
        );
    }
    match &map {
        Some(map) => {
            let clock_hz = cli.clock_hz.map(u64::from).unwrap_or(map.clock_hz);
            let ports = top_ports(&verilog, TOP)?;
            let ucf = write_ucf(map, &ports, clock_hz, &cli.out)?;
            let origin =
                if cli.pinmap.is_none() { format!("{DEFAULT_PINMAP_PATH}, built in") } else { map.origin.clone() };
            println!("wrote {} (pin map {origin}: {})", ucf.display(), map.board);
            let tcl = ise::write_script(VERILOG_FILE, hdl_gen::UCF_FILE, TOP, &cli.out)?;
            println!(
                "wrote {} (ISE 14.7: cd {} && xtclsh {} gives {}; Vivado does not support Spartan-6)",
                tcl.display(),
                cli.out.display(),
                ise::TCL_FILE,
                ise::bitstream(TOP)
            );
        }
        None => println!(
            "no UCF or ISE script: {} is a block without pins (the board, --design board, has them)",
            if cli.verilog.is_some() {
                "--verilog without --pinmap".to_string()
            } else {
                format!("the {} design", cli.design)
            }
        ),
    }

    if !cli.no_lint {
        let report = step(cli, "verilator --lint-only -Wall", || lint(&verilog, &cli.out))?;
        println!("lint: clean (`{}`)", report.command);
    }
    if cli.no_synth {
        return Ok(());
    }
    // The board has real pins: keep its I/O and clock buffers.
    let opts = SynthOptions { io_pads: cli.io_pads || board, ..SynthOptions::default() };
    let mut res = step(cli, "yosys synth_xilinx -family xc6s", || synthesise(&verilog, &cli.out, &opts))?;
    res.source = source;
    let limits = Limits {
        max_lut_percent: cli.max_lut_percent,
        max_dsp: cli.max_dsp,
        max_bram: cli.max_bram,
        max_levels: cli.max_levels,
    };
    let md = res.render_markdown() + &limits.render_markdown(&res);
    let mut json = res.to_json();
    json["limits"] = serde_json::json!({
        "max_lut_percent": limits.max_lut_percent, "max_dsp": limits.max_dsp, "max_bram": limits.max_bram,
        "max_levels": limits.max_levels,
        "violations": limits.violations(&res),
    });
    let (md_path, json_path) = (cli.out.join("resources.md"), cli.out.join("resources.json"));
    std::fs::write(&md_path, &md).with_context(|| format!("could not write {}", md_path.display()))?;
    std::fs::write(&json_path, serde_json::to_string_pretty(&json)? + "\n")
        .with_context(|| format!("could not write {}", json_path.display()))?;
    println!("\n{md}");
    println!(
        "wrote {} and {} (Yosys log: {})",
        md_path.display(),
        json_path.display(),
        cli.out.join("yosys.log").display()
    );
    let v = limits.violations(&res);
    if !v.is_empty() {
        bail!("the design exceeds the limits: {}", v.join("; "));
    }
    Ok(())
}

fn main() {
    let cli = Cli::parse();
    if let Err(e) = run(&cli) {
        eprintln!("hdl-gen: error: {e:#}");
        std::process::exit(1);
    }
}
