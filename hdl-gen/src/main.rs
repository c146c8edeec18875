//! `hdl-gen`: writes the pipeline's Verilog, lints it (Verilator) and reports its Spartan-6
//! resources and logic depth (Yosys). See `hdl-gen --help`.

use anyhow::{bail, Context, Result};
use clap::Parser;
use hdl_gen::{lint, synthesise, write_verilog, Limits, SynthOptions, TOP};
use std::path::PathBuf;

/// Writes DIR/pficp_pipeline.v, lints it with `verilator --lint-only -Wall`, synthesises it
/// with Yosys `synth_xilinx -family xc6s -flatten` and writes DIR/resources.md and
/// DIR/resources.json (LUT/FF/DSP48A1/RAMB16/CARRY4/MUXF against the XC6SLX45, the longest
/// logic path, a 7-series `sta` estimate). Exits non-zero if the lint is not clean, a tool
/// is missing or fails, or the design exceeds the limits.
#[derive(Parser, Debug)]
#[command(name = "hdl-gen", version)]
struct Cli {
    /// Output directory (created if missing).
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Number of parallel lanes P of the generated pipeline.
    #[arg(long, value_name = "P", default_value_t = 16, conflicts_with = "verilog")]
    lanes: usize,
    /// Which design to generate: the particle-weight pipeline (nearest-neighbour pipeline
    /// and weight stage), the nearest-neighbour pipeline alone, or the weight stage alone.
    #[arg(long, value_enum, default_value_t = Design::ParticleWeights, conflicts_with = "verilog")]
    design: Design,
    /// Use the Verilog in FILE (top module `top`) instead of generating the pipeline.
    #[arg(long, value_name = "FILE")]
    verilog: Option<PathBuf>,
    /// Skip the Verilator lint.
    #[arg(long)]
    no_lint: bool,
    /// Skip the Yosys synthesis and the resource report.
    #[arg(long)]
    no_synth: bool,
    /// Synthesise with I/O pads and the clock buffer (the default, `-noiopad -noclkbuf`,
    /// suits the pipeline as a block inside the board top).
    #[arg(long)]
    io_pads: bool,
    /// Fail if the design uses more than this percentage of the LUTs.
    #[arg(long, value_name = "PERCENT", default_value_t = 60.0)]
    max_lut_percent: f64,
    /// Fail if the design uses more DSP48A1s than this.
    #[arg(long, value_name = "N", default_value_t = 58)]
    max_dsp: u64,
    /// Fail if the design uses more RAMB16BWER equivalents than this (RAMB8BWER = 0.5).
    #[arg(long, value_name = "N", default_value_t = 116.0)]
    max_bram: f64,
}

/// The generated designs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum Design {
    /// `ParticleWeightPipeline`: the nearest-neighbour pipeline feeding the weight stage.
    ParticleWeights,
    /// `NnPipeline` alone.
    Nn,
    /// `WeightStage` alone.
    Weights,
}

/// The design's Verilog with `lanes` lanes, from the RTL crate, and where it came from.
fn generated_verilog(design: Design, lanes: usize) -> Result<(String, String)> {
    use pficp_fpga::rtl::{particle_weights_verilog, pipeline_verilog, weight_stage_verilog, SUPPORTED_LANES};
    if design != Design::Weights && !SUPPORTED_LANES.contains(&lanes) {
        bail!("--lanes {lanes} is not supported by the RTL; use one of {SUPPORTED_LANES:?}");
    }
    Ok(match design {
        Design::ParticleWeights => {
            (particle_weights_verilog(lanes), format!("pficp_fpga::rtl::particle_weights_verilog({lanes})"))
        }
        Design::Nn => (pipeline_verilog(lanes), format!("pficp_fpga::rtl::pipeline_verilog({lanes})")),
        Design::Weights => (weight_stage_verilog(), "pficp_fpga::rtl::weight_stage_verilog()".to_string()),
    })
}

fn run(cli: &Cli) -> Result<()> {
    let (verilog, source) = match &cli.verilog {
        Some(f) => {
            let v = std::fs::read_to_string(f).with_context(|| format!("could not read --verilog {}", f.display()))?;
            (v, format!("{} (top `{TOP}`)", f.display()))
        }
        None => generated_verilog(cli.design, cli.lanes)?,
    };
    let path = write_verilog(&verilog, &cli.out)?;
    println!("wrote {} ({source})", path.display());

    if !cli.no_lint {
        let report = lint(&verilog, &cli.out)?;
        println!("lint: clean (`{}`)", report.command);
    }
    if cli.no_synth {
        return Ok(());
    }
    let opts = SynthOptions { io_pads: cli.io_pads, ..SynthOptions::default() };
    let mut res = synthesise(&verilog, &cli.out, &opts)?;
    res.source = source;
    let limits = Limits { max_lut_percent: cli.max_lut_percent, max_dsp: cli.max_dsp, max_bram: cli.max_bram };
    let md = res.render_markdown() + &limits.render_markdown(&res);
    let mut json = res.to_json();
    json["limits"] = serde_json::json!({
        "max_lut_percent": limits.max_lut_percent, "max_dsp": limits.max_dsp, "max_bram": limits.max_bram,
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
