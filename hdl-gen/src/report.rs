//! Resource counts against the XC6SLX45, the resource report (Markdown and JSON) and limits.

use crate::device;
use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// One step of the longest logic path.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct PathStep {
    /// The net (and bit) reached at this step; step 0 is where the path starts.
    pub net: String,
    /// The cell driving `net` (none for step 0).
    pub cell: Option<String>,
    /// Its type (`LUT6`, `CARRY4`, ...), when known.
    pub cell_type: Option<String>,
}

/// Distributed-RAM primitives and the LUTs each one occupies.
pub const LUTRAM_LUTS: &[(&str, u64)] = &[
    ("RAM16X1S", 1),
    ("RAM32X1S", 1),
    ("RAM64X1S", 1),
    ("RAM16X1D", 2),
    ("RAM32X1D", 2),
    ("RAM64X1D", 2),
    ("RAM128X1S", 2),
    ("RAM128X1D", 4),
    ("RAM256X1S", 4),
    ("RAM32M", 4),
    ("RAM64M", 4),
];

/// Shift-register primitives (one LUT each).
pub const SRL_TYPES: &[&str] = &["SRL16", "SRL16E", "SRLC16E", "SRLC32E"];

/// Post-synthesis resources of a design (Yosys `synth_xilinx -family xc6s`, flattened).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Resources {
    /// What was synthesised (file name or generator call).
    pub source: String,
    /// Yosys version line.
    pub yosys_version: String,
    /// The `synth_xilinx` command.
    pub synth_command: String,
    /// LUTs: LUT1..LUT6 + INV + shift registers (SRL16E/SRLC32E, one LUT each) + LUTs used as
    /// distributed RAM.
    pub lut: u64,
    /// LUT1..LUT6 only.
    pub lut_logic: u64,
    /// INV cells (each a LUT1).
    pub inv: u64,
    /// Shift-register LUTs (SRL16E, SRLC32E, ...).
    pub srl: u64,
    /// LUTs used as distributed RAM.
    pub lutram: u64,
    /// Flip-flops: every `FD*` cell type (FDRE, FDSE, FDCE, FDPE, ...).
    pub ff: u64,
    /// Latches (`LD*`): should be 0.
    pub latches: u64,
    /// DSP48A1 slices.
    pub dsp: u64,
    /// RAMB16BWER cells.
    pub ramb16: u64,
    /// RAMB8BWER cells (half a RAMB16BWER each).
    pub ramb8: u64,
    /// 18 Kb block RAM equivalents: `ramb16 + ramb8 / 2`.
    pub bram16: f64,
    /// CARRY4 cells.
    pub carry4: u64,
    /// MUXF7 cells.
    pub muxf7: u64,
    /// MUXF8 cells.
    pub muxf8: u64,
    /// I/O buffers (IBUF, OBUF, ...; 0 without `--io-pads`).
    pub io_buffers: u64,
    /// Global clock buffers (0 without `--io-pads`).
    pub bufg: u64,
    /// Longest logic path between registers, block RAMs, DSP48A1s and ports, in cells
    /// (LUT/INV/CARRY4/MUXF levels; Yosys `ltp`).
    pub depth: usize,
    /// The path: step 0 is the start net, step `i` the net driven by the `i`-th cell.
    pub depth_path: Vec<PathStep>,
    /// Yosys `sta` latest arrival time in ps, with **7-series** cell delays (Yosys has no
    /// Spartan-6 timing); no routing; paths through DSP48A1/RAMB are not timed.
    pub sta_ps: Option<u64>,
    /// Number of warnings Yosys printed.
    pub yosys_warnings: usize,
    /// Every cell type and its count (`stat -json` `num_cells_by_type`).
    pub cells_by_type: BTreeMap<String, u64>,
}

fn is_ff(t: &str) -> bool {
    t.starts_with("FD")
}
fn is_latch(t: &str) -> bool {
    t.starts_with("LD")
}
fn is_lut(t: &str) -> bool {
    matches!(t, "LUT1" | "LUT2" | "LUT3" | "LUT4" | "LUT5" | "LUT6")
}
fn is_io_buffer(t: &str) -> bool {
    matches!(t, "IBUF" | "OBUF" | "OBUFT" | "IOBUF" | "IBUFG" | "IBUFDS" | "OBUFDS")
}
fn lutram_luts(t: &str) -> Option<u64> {
    LUTRAM_LUTS.iter().find(|(n, _)| *n == t).map(|(_, l)| *l)
}

impl Resources {
    /// Counts from `num_cells_by_type` (the other fields empty).
    pub fn from_cells(cells_by_type: BTreeMap<String, u64>) -> Resources {
        let sum = |f: &dyn Fn(&str) -> bool| cells_by_type.iter().filter(|(t, _)| f(t)).map(|(_, n)| n).sum::<u64>();
        let get = |t: &str| cells_by_type.get(t).copied().unwrap_or(0);
        let lut_logic = sum(&is_lut);
        let inv = get("INV");
        let srl = sum(&|t| SRL_TYPES.contains(&t));
        let lutram = cells_by_type.iter().filter_map(|(t, n)| lutram_luts(t).map(|l| l * n)).sum();
        let (ramb16, ramb8) = (get("RAMB16BWER"), get("RAMB8BWER"));
        Resources {
            source: String::new(),
            yosys_version: String::new(),
            synth_command: String::new(),
            lut: lut_logic + inv + srl + lutram,
            lut_logic,
            inv,
            srl,
            lutram,
            ff: sum(&is_ff),
            latches: sum(&is_latch),
            dsp: get("DSP48A1"),
            ramb16,
            ramb8,
            bram16: ramb16 as f64 + ramb8 as f64 / 2.0,
            carry4: get("CARRY4"),
            muxf7: get("MUXF7"),
            muxf8: get("MUXF8"),
            io_buffers: sum(&is_io_buffer),
            bufg: sum(&|t| t.starts_with("BUFG")),
            depth: 0,
            depth_path: Vec::new(),
            sta_ps: None,
            yosys_warnings: 0,
            cells_by_type,
        }
    }

    /// Cell types not covered by the rows of the report (listed under "Other cells").
    pub fn other_cells(&self) -> BTreeMap<String, u64> {
        self.cells_by_type
            .iter()
            .filter(|(t, _)| {
                let t = t.as_str();
                !(is_lut(t)
                    || is_ff(t)
                    || is_io_buffer(t)
                    || t.starts_with("BUFG")
                    || SRL_TYPES.contains(&t)
                    || lutram_luts(t).is_some()
                    || matches!(t, "INV" | "DSP48A1" | "RAMB16BWER" | "RAMB8BWER" | "CARRY4" | "MUXF7" | "MUXF8"))
            })
            .map(|(t, n)| (t.clone(), *n))
            .collect()
    }

    /// LUTs as a percentage of the XC6SLX45's.
    pub fn lut_percent(&self) -> f64 {
        percent(self.lut as f64, device::LUT6)
    }

    /// The utilisation rows: (resource, used, available, note).
    pub fn rows(&self) -> Vec<(&'static str, f64, u64, String)> {
        let mut rows = vec![
            (
                "LUT",
                self.lut as f64,
                device::LUT6,
                format!(
                    "LUT1..LUT6 {} + INV {} + shift registers (SRL16E/SRLC32E) {} + LUT RAM {}",
                    self.lut_logic, self.inv, self.srl, self.lutram
                ),
            ),
            ("FF", self.ff as f64, device::FF, "all FD* types".to_string()),
            ("DSP48A1", self.dsp as f64, device::DSP48A1, String::new()),
            (
                "RAMB16BWER",
                self.bram16,
                device::RAMB16BWER,
                format!("{} RAMB16BWER + {} RAMB8BWER counted as half each", self.ramb16, self.ramb8),
            ),
            ("CARRY4", self.carry4 as f64, device::CARRY4, "one per SLICEL/SLICEM (half of the slices)".to_string()),
            ("MUXF7", self.muxf7 as f64, device::MUXF7, "two per SLICEL/SLICEM".to_string()),
            ("MUXF8", self.muxf8 as f64, device::MUXF8, "one per SLICEL/SLICEM".to_string()),
        ];
        if self.io_buffers > 0 || self.bufg > 0 {
            rows.push(("I/O buffers", self.io_buffers as f64, device::USER_IO, "user I/O of the FGG484".to_string()));
            rows.push(("BUFG", self.bufg as f64, device::BUFG, String::new()));
        }
        rows
    }

    /// The report as Markdown: utilisation table, longest logic path, `sta` estimate.
    pub fn render_markdown(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "# Resources: {} on the {}\n", self.source, device::NAME);
        let _ = writeln!(s, "{}, `{}`.\n", self.yosys_version, self.synth_command);
        let _ = writeln!(s, "| resource | used | available | % | counted as |");
        let _ = writeln!(s, "|---|---:|---:|---:|---|");
        for (name, used, avail, note) in self.rows() {
            let _ = writeln!(s, "| {name} | {} | {avail} | {:.1} % | {note} |", fmt_count(used), percent(used, avail));
        }
        let other = self.other_cells();
        if self.latches > 0 {
            let _ = writeln!(
                s,
                "\n**Warning: {} latch(es) (LD*)**: a combinational signal is not assigned on every path.",
                self.latches
            );
        }
        if !other.is_empty() {
            let list: Vec<String> = other.iter().map(|(t, n)| format!("{t} {n}")).collect();
            let _ = writeln!(s, "\nOther cells: {}.", list.join(", "));
        }
        let _ = writeln!(s, "\n## Longest logic path between registers\n");
        let _ = writeln!(
            s,
            "**{} levels** (cells on the longest path after deleting flip-flops, block/distributed RAM, \
             DSP48A1, shift registers and I/O buffers from the flattened netlist: Yosys `ltp`; DSP48A1 and \
             RAMB count as registered; a path may start or end at a port).\n",
            self.depth
        );
        if self.depth_path.len() > 1 {
            let _ = writeln!(s, "| level | cell type | cell | output net |");
            let _ = writeln!(s, "|---:|---|---|---|");
            for (i, st) in self.depth_path.iter().enumerate() {
                let _ = writeln!(
                    s,
                    "| {i} | {} | {} | `{}` |",
                    if i == 0 { "start" } else { st.cell_type.as_deref().unwrap_or("?") },
                    st.cell.as_deref().map_or(String::new(), |c| format!("`{}`", unescape(c))),
                    unescape(&st.net)
                );
            }
        }
        let _ = writeln!(s, "\n## Timing estimate (Yosys `sta`, 7-series delays)\n");
        match self.sta_ps {
            Some(ps) => {
                let _ = writeln!(
                    s,
                    "Latest arrival time: **{ps} ps** with **Xilinx 7-series** cell delays (Yosys's `cells_sim.v`; \
                     there is no Spartan-6 timing model), no routing delay, and paths through DSP48A1/RAMB \
                     untimed (no timing arcs). For comparing designs only, not a Spartan-6 clock estimate."
                );
            }
            None => {
                let _ = writeln!(s, "Yosys `sta` reported no arrival time.");
            }
        }
        if self.yosys_warnings > 0 {
            let _ = writeln!(s, "\nYosys printed {} warning(s); see yosys.log.", self.yosys_warnings);
        }
        s
    }

    /// The report as JSON: the counts, the device totals, percentages, path and `sta`.
    pub fn to_json(&self) -> serde_json::Value {
        let rows: Vec<serde_json::Value> = self
            .rows()
            .into_iter()
            .map(|(name, used, avail, note)| {
                serde_json::json!({"resource": name, "used": used, "available": avail,
                                   "percent": round1(percent(used, avail)), "counted_as": note})
            })
            .collect();
        serde_json::json!({
            "device": device::NAME,
            "device_totals": {"LUT6": device::LUT6, "FF": device::FF, "DSP48A1": device::DSP48A1,
                              "RAMB16BWER": device::RAMB16BWER, "CARRY4": device::CARRY4,
                              "MUXF7": device::MUXF7, "MUXF8": device::MUXF8},
            "utilisation": rows,
            "resources": self,
            "sta_delay_model": "Xilinx 7-series cells_sim.v specify delays (not Spartan-6), no routing, DSP48A1/RAMB untimed",
        })
    }
}

/// A Yosys name without the backslash that marks public names.
fn unescape(id: &str) -> &str {
    id.strip_prefix('\\').unwrap_or(id)
}

fn percent(used: f64, avail: u64) -> f64 {
    100.0 * used / avail as f64
}

fn round1(x: f64) -> f64 {
    (x * 10.0).round() / 10.0
}

fn fmt_count(x: f64) -> String {
    if x.fract() == 0.0 {
        format!("{x:.0}")
    } else {
        format!("{x:.1}")
    }
}

/// The default bound on logic levels: the board top's longest path is 18 (a 48-bit
/// subtraction's carry chain and a zero test), the command engine's 16; more means a new
/// long combinational path that wants a register (DESIGN: keep every path short).
pub const DEFAULT_MAX_LEVELS: usize = 20;

/// Default LUT budget in percent of the device: issue 13's limit for the whole board top
/// (the rest is left for place and route and for what comes next).
pub const DEFAULT_MAX_LUT_PERCENT: f64 = 80.0;

/// Limits the design must stay within.
#[derive(Debug, Clone, PartialEq)]
pub struct Limits {
    /// Maximum LUTs, in percent of the device's.
    pub max_lut_percent: f64,
    /// Maximum DSP48A1s.
    pub max_dsp: u64,
    /// Maximum RAMB16BWER equivalents.
    pub max_bram: f64,
    /// Maximum logic levels on the longest register-to-register path ([`Resources::depth`]).
    pub max_levels: usize,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            max_lut_percent: DEFAULT_MAX_LUT_PERCENT,
            max_dsp: device::DSP48A1,
            max_bram: device::RAMB16BWER as f64,
            max_levels: DEFAULT_MAX_LEVELS,
        }
    }
}

impl Limits {
    /// The limits the design exceeds, one sentence each (empty: within limits).
    pub fn violations(&self, r: &Resources) -> Vec<String> {
        let mut v = Vec::new();
        if r.lut_percent() > self.max_lut_percent {
            v.push(format!(
                "LUT {} = {:.1} % of {} > --max-lut-percent {}",
                r.lut,
                r.lut_percent(),
                device::LUT6,
                self.max_lut_percent
            ));
        }
        if r.dsp > self.max_dsp {
            v.push(format!("DSP48A1 {} > --max-dsp {}", r.dsp, self.max_dsp));
        }
        if r.bram16 > self.max_bram {
            v.push(format!("RAMB16BWER {} > --max-bram {}", fmt_count(r.bram16), self.max_bram));
        }
        if r.depth > self.max_levels {
            v.push(format!("longest path {} logic levels > --max-levels {}", r.depth, self.max_levels));
        }
        v
    }

    /// A Markdown section stating the limits and whether the design is within them.
    pub fn render_markdown(&self, r: &Resources) -> String {
        let v = self.violations(r);
        let mut s = format!(
            "\n## Limits\n\nLUT <= {} %, DSP48A1 <= {}, RAMB16BWER <= {}, logic levels <= {}: ",
            self.max_lut_percent, self.max_dsp, self.max_bram, self.max_levels
        );
        if v.is_empty() {
            s.push_str("**within limits**.\n");
        } else {
            s.push_str("**exceeded**:\n\n");
            for x in v {
                s.push_str(&format!("- {x}\n"));
            }
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cells(list: &[(&str, u64)]) -> BTreeMap<String, u64> {
        list.iter().map(|(t, n)| (t.to_string(), *n)).collect()
    }

    #[test]
    fn counting_rules() {
        let r = Resources::from_cells(cells(&[
            ("LUT2", 10),
            ("LUT6", 5),
            ("INV", 1),
            ("SRL16E", 2),
            ("SRLC32E", 1),
            ("RAM64X1D", 3),
            ("FDRE", 7),
            ("FDSE", 2),
            ("FDCE", 1),
            ("RAMB16BWER", 2),
            ("RAMB8BWER", 3),
            ("DSP48A1", 4),
            ("CARRY4", 6),
            ("MUXF7", 2),
            ("MUXF8", 1),
            ("XORCY", 9),
        ]));
        assert_eq!((r.lut_logic, r.inv, r.srl, r.lutram), (15, 1, 3, 6));
        assert_eq!(r.lut, 25);
        assert_eq!(r.ff, 10);
        assert_eq!(r.bram16, 3.5);
        assert_eq!((r.dsp, r.carry4, r.muxf7, r.muxf8, r.io_buffers), (4, 6, 2, 1, 0));
        assert_eq!(r.other_cells(), cells(&[("XORCY", 9)]));
        let md = r.render_markdown();
        assert!(
            md.contains("| RAMB16BWER | 3.5 | 116 | 3.0 % | 2 RAMB16BWER + 3 RAMB8BWER counted as half each |"),
            "{md}"
        );
        assert!(md.contains("Other cells: XORCY 9."), "{md}");
        assert!(!md.contains("| I/O buffers |"));
    }

    #[test]
    fn limits() {
        let mut r = Resources::from_cells(cells(&[("LUT6", 21_830), ("DSP48A1", 58), ("RAMB16BWER", 116)]));
        r.depth = DEFAULT_MAX_LEVELS;
        assert!(Limits::default().violations(&r).is_empty(), "21830 LUT = 79.998 %");
        r.lut = 21_831;
        r.dsp = 59;
        r.bram16 = 116.5;
        r.depth = DEFAULT_MAX_LEVELS + 1;
        let v = Limits::default().violations(&r);
        assert_eq!(v.len(), 4, "{v:?}");
        assert!(v[0].starts_with("LUT 21831 = 80.0 % of 27288 > --max-lut-percent 80"), "{}", v[0]);
        assert_eq!(v[3], "longest path 21 logic levels > --max-levels 20");
        assert!(Limits::default().render_markdown(&r).contains("**exceeded**"));
    }
}
