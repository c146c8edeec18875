//! Yosys `synth_xilinx -family xc6s` and parsing of what it writes (`stat -json`, `ltp`, `sta`).

use crate::lint::{write_verilog, TOP, VERILOG_FILE};
use crate::report::{PathStep, Resources};
use crate::tools;
use anyhow::{anyhow, bail, Context, Result};
use serde::Deserialize;
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

/// Yosys script hdl-gen writes into the output directory (run there with `yosys -s`).
pub const SCRIPT_FILE: &str = "synth.ys";
/// Yosys's full log.
pub const LOG_FILE: &str = "yosys.log";
/// `stat -json` after synthesis.
pub const STAT_FILE: &str = "yosys_stat.json";
/// `sta` output (7-series delays from cells_sim.v).
pub const STA_FILE: &str = "yosys_sta.txt";
/// `ltp` output after deleting the sequential and hard cells.
pub const LTP_FILE: &str = "yosys_ltp.txt";
/// The names of the remaining (combinational) cells by type, to name the cells on the path.
pub const CELLS_FILE: &str = "yosys_cells.txt";

/// Cells deleted before `ltp`, so that it measures logic levels between them: flip-flops,
/// latches, block and distributed RAM, DSP48A1, shift registers, I/O and clock buffers.
pub const DEPTH_BOUNDARY_CELLS: &str = "t:FD* t:LD* t:RAM* t:DSP48A1 t:SRL* t:IBUF t:OBUF t:OBUFT t:IOBUF t:BUFG*";

/// Combinational cell types whose cell names are listed (to give the type of each cell on
/// the longest path).
pub const PATH_CELL_TYPES: &[&str] =
    &["LUT1", "LUT2", "LUT3", "LUT4", "LUT5", "LUT6", "INV", "CARRY4", "MUXF7", "MUXF8"];

/// Synthesis options.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SynthOptions {
    /// Keep I/O pads and the clock buffer (`synth_xilinx` without `-noiopad -noclkbuf`). Off
    /// by default: the pipeline is a block inside the board top, not the board top.
    pub io_pads: bool,
    /// Top module name.
    pub top: String,
}

impl Default for SynthOptions {
    fn default() -> Self {
        SynthOptions { io_pads: false, top: TOP.to_string() }
    }
}

impl SynthOptions {
    /// The `synth_xilinx` command.
    pub fn synth_command(&self) -> String {
        let pads = if self.io_pads { "" } else { " -noiopad -noclkbuf" };
        format!("synth_xilinx -family xc6s -top {} -flatten{pads}", self.top)
    }

    /// The Yosys script that synthesises `verilog_file` (relative to the directory it runs in).
    pub fn script(&self, verilog_file: &str) -> String {
        let mut s = format!(
            "# Written by hdl-gen. Run in this directory: yosys -q -l {LOG_FILE} -s {SCRIPT_FILE}\n\
             read_verilog {verilog_file}\n\
             {synth}\n\
             tee -o {STAT_FILE} stat -json\n\
             # sta: delays from the 7-series cells_sim.v specify blocks (no Spartan-6 model exists);\n\
             # DSP48A1 and RAMB have no timing arcs.\n\
             read_verilog -lib -specify +/xilinx/cells_sim.v\n\
             tee -o {STA_FILE} sta\n\
             # Logic depth: remove registers and hard blocks, then the longest topological path is\n\
             # the longest LUT/CARRY4/MUXF chain between them (or ports).\n\
             delete {DEPTH_BOUNDARY_CELLS}\n\
             tee -o {LTP_FILE} ltp\n",
            synth = self.synth_command()
        );
        for (i, t) in PATH_CELL_TYPES.iter().enumerate() {
            let redirect = if i == 0 { "-o" } else { "-a" };
            s.push_str(&format!("tee -q {redirect} {CELLS_FILE} log celltype {t}\n"));
            s.push_str(&format!("tee -q -a {CELLS_FILE} select -list t:{t}\n"));
        }
        s
    }
}

#[derive(Deserialize)]
struct StatJson {
    creator: Option<String>,
    design: StatDesign,
}

#[derive(Deserialize)]
struct StatDesign {
    #[serde(default)]
    num_cells_by_type: BTreeMap<String, u64>,
}

/// From Yosys `stat -json`: the creator line (Yosys version) and
/// `design.num_cells_by_type`.
pub fn parse_stat_json(text: &str) -> Result<(String, BTreeMap<String, u64>)> {
    let stat: StatJson = serde_json::from_str(text).context("Yosys `stat -json` output is not as expected")?;
    Ok((stat.creator.unwrap_or_default(), stat.design.num_cells_by_type))
}

/// The longest topological path reported by Yosys `ltp`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LongestPath {
    /// `length=N`: the number of cells on the path.
    pub length: usize,
    /// Step 0 is the start net (no cell); step `i > 0` is the net driven by cell `i`.
    pub steps: Vec<PathStep>,
}

/// Parses `ltp` output (`Longest topological path in top (length=N):` followed by lines
/// `  i: NET (via CELL)`). If several modules are listed, the one named `top` is taken.
pub fn parse_ltp(text: &str, top: &str) -> Result<LongestPath> {
    let mut paths: Vec<(String, LongestPath)> = Vec::new();
    for line in text.lines() {
        let t = line.trim();
        if let Some(rest) = t.strip_prefix("Longest topological path in ") {
            let (module, len) = rest
                .rsplit_once(" (length=")
                .and_then(|(m, l)| Some((m, l.strip_suffix("):")?.parse::<usize>().ok()?)))
                .ok_or_else(|| anyhow!("unexpected ltp line: {t}"))?;
            paths.push((module.to_string(), LongestPath { length: len, steps: Vec::new() }));
            continue;
        }
        let Some((_, path)) = paths.last_mut() else { continue };
        let Some((idx, rest)) = t.split_once(": ") else { continue };
        if idx.parse::<usize>().is_err() {
            continue;
        }
        let (net, cell) = match rest.rsplit_once(" (via ") {
            Some((net, cell)) => (net, Some(cell.strip_suffix(')').unwrap_or(cell).to_string())),
            None => (rest, None),
        };
        path.steps.push(PathStep { net: net.to_string(), cell, cell_type: None });
    }
    let pos = paths.iter().position(|(m, _)| m == top || m.trim_start_matches('\\') == top).unwrap_or(0);
    if paths.is_empty() {
        bail!("no `Longest topological path` in the ltp output");
    }
    Ok(paths.swap_remove(pos).1)
}

/// Parses the cell lists of [`SynthOptions::script`] (`celltype T` then `module/cell` lines)
/// into cell name -> type.
pub fn parse_cell_lists(text: &str) -> HashMap<String, String> {
    let mut map = HashMap::new();
    let mut ty: Option<&str> = None;
    for line in text.lines() {
        if let Some(t) = line.strip_prefix("celltype ") {
            ty = Some(t.trim());
        } else if let (Some(t), Some((_, cell))) = (ty, line.split_once('/')) {
            map.insert(cell.to_string(), t.to_string());
        }
    }
    map
}

/// The `Latest arrival time in 'top' is N` of Yosys `sta`, in ps.
pub fn parse_sta(text: &str) -> Option<u64> {
    text.lines().find_map(|l| {
        let rest = l.trim().strip_prefix("Latest arrival time in ")?;
        let n = rest.rsplit_once(" is ")?.1.trim_end_matches(':');
        n.parse().ok()
    })
}

/// Builds [`Resources`] from the files Yosys wrote into `dir` (see [`SynthOptions::script`]).
pub fn resources_from_dir(dir: &Path, opts: &SynthOptions, yosys_warnings: usize) -> Result<Resources> {
    let read = |name: &str| {
        let p = dir.join(name);
        std::fs::read_to_string(&p).with_context(|| format!("Yosys did not write {}", p.display()))
    };
    let (version, cells) = parse_stat_json(&read(STAT_FILE)?)?;
    let mut path = parse_ltp(&read(LTP_FILE)?, &opts.top)?;
    let types = parse_cell_lists(&read(CELLS_FILE)?);
    for step in &mut path.steps {
        step.cell_type = step.cell.as_ref().and_then(|c| types.get(c)).cloned();
    }
    let mut r = Resources::from_cells(cells);
    r.yosys_version = version;
    r.synth_command = opts.synth_command();
    r.depth = path.length;
    r.depth_path = path.steps;
    r.sta_ps = parse_sta(&read(STA_FILE)?);
    r.yosys_warnings = yosys_warnings;
    Ok(r)
}

/// Writes `verilog` (with the lint waivers) to `dir/`[`VERILOG_FILE`], synthesises it with
/// Yosys for the Spartan-6 (`synth_xilinx -family xc6s -flatten`, see
/// [`SynthOptions::synth_command`]), and returns the resource counts, the logic depth and the
/// `sta` estimate. Yosys runs with `-q`; its log is `dir/`[`LOG_FILE`].
pub fn synthesise(verilog: &str, dir: &Path, opts: &SynthOptions) -> Result<Resources> {
    write_verilog(verilog, dir)?;
    for f in [STAT_FILE, STA_FILE, LTP_FILE, CELLS_FILE] {
        let _ = std::fs::remove_file(dir.join(f));
    }
    std::fs::write(dir.join(SCRIPT_FILE), opts.script(VERILOG_FILE))
        .with_context(|| format!("could not write {}", dir.join(SCRIPT_FILE).display()))?;
    let out = tools::run("yosys", ["-q", "-l", LOG_FILE, "-s", SCRIPT_FILE], dir)?;
    let stderr = String::from_utf8_lossy(&out.stderr);
    if !out.status.success() {
        let log = std::fs::read_to_string(dir.join(LOG_FILE)).unwrap_or_default();
        bail!(
            "Yosys failed on {} (exit code {}); reproduce with `cd {} && yosys -l {LOG_FILE} -s {SCRIPT_FILE}`.\n\
             stderr:\n{}\nlast lines of {LOG_FILE}:\n{}",
            dir.join(VERILOG_FILE).display(),
            out.status.code().map_or("none".to_string(), |c| c.to_string()),
            dir.display(),
            tools::tail(stderr.trim_end(), 40),
            tools::tail(log.trim_end(), 30)
        );
    }
    let warnings = stderr.lines().filter(|l| l.contains("Warning:")).count();
    let mut r = resources_from_dir(dir, opts, warnings)?;
    r.source = VERILOG_FILE.to_string();
    Ok(r)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn synth_command_and_pads() {
        let o = SynthOptions::default();
        assert_eq!(o.synth_command(), "synth_xilinx -family xc6s -top top -flatten -noiopad -noclkbuf");
        let o = SynthOptions { io_pads: true, ..o };
        assert_eq!(o.synth_command(), "synth_xilinx -family xc6s -top top -flatten");
        let s = o.script("x.v");
        assert!(s.contains("read_verilog x.v\nsynth_xilinx"));
        assert!(s.contains(&format!("tee -q -o {CELLS_FILE} log celltype LUT1\n")));
        assert_eq!(s.matches(" -o ").count(), 4, "each output file is truncated once:\n{s}");
    }

    #[test]
    fn ltp_steps_and_module_choice() {
        let text = "\n6. Executing LTP pass (find longest path).\n\n\
                    Longest topological path in sub (length=1):\n    0: \\a\n    1: \\b (via c0)\n\
                    Longest topological path in top (length=2):\n    0: \\y [3]\n    1: n.X [3] (via $abc$1)\n\
                    \x20   2: n.CO [3] (via $auto$x.slice[0].genblk1.carry4)\n";
        let p = parse_ltp(text, "top").unwrap();
        assert_eq!(p.length, 2);
        assert_eq!(p.steps.len(), 3);
        assert_eq!(p.steps[0], PathStep { net: "\\y [3]".into(), cell: None, cell_type: None });
        assert_eq!(p.steps[2].cell.as_deref(), Some("$auto$x.slice[0].genblk1.carry4"));
        assert!(parse_ltp("nothing here", "top").is_err());
    }

    #[test]
    fn sta_arrival() {
        assert_eq!(parse_sta("x\nLatest arrival time in 'top' is 1328:\n    1328 (<unknown>)\n"), Some(1328));
        assert_eq!(parse_sta("no timing"), None);
    }
}
