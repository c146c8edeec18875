//! The board pin map (`constraints/pinmap.toml`) and the UCF written from it.
//!
//! A pin map names, for every port of the board top, its ball (`LOC`), its `IOSTANDARD`
//! (the board default, LVCMOS33 unless it says otherwise) and optional `PULLUP`/`PULLDOWN`/
//! `KEEPER`, `DRIVE` and `SLEW`; the clock port also carries the oscillator's frequency. The
//! format is in `constraints/README.md`. [`render_ucf`] checks the map against the ports of
//! the Verilog top ([`top_ports`]) and writes one `NET` line per pin, buses as `NET "leds<0>"`,
//! and a `PERIOD` on the clock.

use anyhow::{bail, Context, Result};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

pub use crate::top_ports::{top_ports, Direction, Port};

/// The committed default pin map, embedded so the binary works from any directory.
pub const DEFAULT_PINMAP: &str = include_str!("../../constraints/pinmap.toml");

/// Where [`DEFAULT_PINMAP`] lives in the repository.
pub const DEFAULT_PINMAP_PATH: &str = "constraints/pinmap.toml";

/// Name of the UCF hdl-gen writes into its output directory (and commits as
/// `constraints/pficp_board.ucf` for the default pin map).
pub const UCF_FILE: &str = "pficp_board.ucf";

/// The global-clock (GCLK) input balls of the XC6SLX45 in the FGG484 package, four pairs per
/// bank (UG385, the Xilinx package file): the clock must come in on one of them.
pub const GCLK_PINS: &[&str] = &[
    // bank 0
    "A10", "B10", "A11", "C11", "C12", "D11", "A12", "B12", // bank 1
    "K19", "K20", "H21", "H22", "L19", "M20", "J22", "J20", // bank 2
    "W12", "Y12", "Y13", "AB13", "AA12", "AB12", "Y11", "AB11", // bank 3
    "J1", "J3", "L4", "M3", "K4", "K5", "J4", "K3",
];

/// Single-ended I/O standards of Spartan-6 (UG381) that a pin map may name.
pub const IOSTANDARDS: &[&str] = &[
    "LVTTL",
    "LVCMOS33",
    "LVCMOS25",
    "LVCMOS18",
    "LVCMOS15",
    "LVCMOS12",
    "LVCMOS18_JEDEC",
    "LVCMOS15_JEDEC",
    "LVCMOS12_JEDEC",
    "PCI33_3",
    "PCI66_3",
    "I2C",
    "SMBUS",
    "SDIO",
    "MOBILE_DDR",
    "HSTL_I",
    "HSTL_II",
    "HSTL_III",
    "HSTL_I_18",
    "HSTL_II_18",
    "HSTL_III_18",
    "SSTL3_I",
    "SSTL3_II",
    "SSTL2_I",
    "SSTL2_II",
    "SSTL18_I",
    "SSTL18_II",
    "SSTL15_II",
];

const DRIVES: &[u32] = &[2, 4, 6, 8, 12, 16, 24];
const SLEWS: &[&str] = &["SLOW", "FAST", "QUIETIO"];
const PULLS: &[&str] = &["PULLUP", "PULLDOWN", "KEEPER"];
const VCCAUX: &[&str] = &["2.5", "3.3"];
/// Ball rows of the 22 x 22 FGG484 grid (no I, O, Q, S, X, Z).
const FGG484_ROWS: &[&str] =
    &["A", "B", "C", "D", "E", "F", "G", "H", "J", "K", "L", "M", "N", "P", "R", "T", "U", "V", "W", "Y", "AA", "AB"];

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawPinMap {
    board: RawBoard,
    ports: BTreeMap<String, RawPort>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBoard {
    name: String,
    source: Option<String>,
    iostandard: Option<String>,
    vccaux: Option<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawPort {
    pin: Option<String>,
    pins: Option<Vec<String>>,
    iostandard: Option<String>,
    pull: Option<String>,
    drive: Option<u32>,
    slew: Option<String>,
    frequency_hz: Option<u64>,
    note: Option<String>,
}

/// One port's entry in a pin map.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PortPins {
    /// Balls, bit 0 (the lowest index) first; one for a scalar port.
    pub pins: Vec<String>,
    /// Whether the map gave `pins = [...]` (a bus) rather than `pin = "..."`.
    pub is_bus: bool,
    /// `IOSTANDARD` (the board default when the entry names none).
    pub iostandard: String,
    /// `PULLUP`, `PULLDOWN` or `KEEPER`.
    pub pull: Option<String>,
    /// `DRIVE` in mA (outputs).
    pub drive: Option<u32>,
    /// `SLEW`: `SLOW`, `FAST` or `QUIETIO` (outputs).
    pub slew: Option<String>,
    /// A comment written above the port's lines in the UCF.
    pub note: Option<String>,
}

/// A parsed and checked pin map.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PinMap {
    /// Where it came from (a path, or [`DEFAULT_PINMAP_PATH`] for the embedded default).
    pub origin: String,
    /// The board's name.
    pub board: String,
    /// Where the pin-out comes from.
    pub source: Option<String>,
    /// `CONFIG VCCAUX`, when the board says.
    pub vccaux: Option<String>,
    /// The clock port (the entry with `frequency_hz`).
    pub clock_port: String,
    /// The oscillator's frequency in Hz.
    pub clock_hz: u64,
    /// Every entry, by port name.
    pub ports: BTreeMap<String, PortPins>,
}

fn valid_ball(pin: &str) -> bool {
    let split = pin.find(|c: char| c.is_ascii_digit()).unwrap_or(pin.len());
    let (row, col) = pin.split_at(split);
    FGG484_ROWS.contains(&row)
        && !col.starts_with('0')
        && col.parse::<u32>().map(|c| (1..=22).contains(&c)).unwrap_or(false)
}

impl PinMap {
    /// The committed default ([`DEFAULT_PINMAP`]).
    pub fn default_map() -> PinMap {
        PinMap::parse(DEFAULT_PINMAP, DEFAULT_PINMAP_PATH).expect("the committed constraints/pinmap.toml is valid")
    }

    /// Reads the pin map in `path`, or the embedded default when `path` is `None`.
    pub fn load(path: Option<&Path>) -> Result<PinMap> {
        match path {
            None => Ok(PinMap::default_map()),
            Some(p) => {
                let text = std::fs::read_to_string(p)
                    .with_context(|| format!("could not read the pin map {}", p.display()))?;
                PinMap::parse(&text, &p.display().to_string())
            }
        }
    }

    /// Checks that the design clock is the board's oscillator (the board top has no DCM).
    pub fn check_clock(&self, clock_hz: u64) -> Result<()> {
        if clock_hz != self.clock_hz {
            bail!(
                "the design clock is {clock_hz} Hz but the board's oscillator (port `{}` in the pin map {}) is \
                 {} Hz; the board top has no DCM, so they must agree: pass --clock-hz {} or a pin map for your \
                 board (--pinmap)",
                self.clock_port,
                self.origin,
                self.clock_hz,
                self.clock_hz
            );
        }
        Ok(())
    }

    /// Parses and checks a pin map (TOML). `origin` names it in error messages. Every problem
    /// found is listed in the one error.
    pub fn parse(text: &str, origin: &str) -> Result<PinMap> {
        let raw: RawPinMap = toml::from_str(text).map_err(|e| {
            anyhow::anyhow!("pin map {origin} is not valid ({}):\n{e}", "format: constraints/README.md")
        })?;
        let mut errors = Vec::new();
        let default_std = raw.board.iostandard.clone().unwrap_or_else(|| "LVCMOS33".to_string());
        if !IOSTANDARDS.contains(&default_std.as_str()) {
            errors.push(format!("[board] iostandard = {default_std:?} is not a Spartan-6 single-ended standard"));
        }
        if let Some(v) = &raw.board.vccaux {
            if !VCCAUX.contains(&v.as_str()) {
                errors.push(format!("[board] vccaux = {v:?}: use \"2.5\" or \"3.3\""));
            }
        }
        if raw.ports.is_empty() {
            errors.push("no [ports.NAME] entries".to_string());
        }
        let mut ports = BTreeMap::new();
        let mut clocks = Vec::new();
        let mut used: BTreeMap<String, String> = BTreeMap::new();
        for (name, p) in &raw.ports {
            let pins = match (&p.pin, &p.pins) {
                (Some(pin), None) => vec![pin.clone()],
                (None, Some(pins)) if !pins.is_empty() => pins.clone(),
                (None, Some(_)) => {
                    errors.push(format!("[ports.{name}]: pins = [] is empty"));
                    continue;
                }
                (Some(_), Some(_)) => {
                    errors.push(format!("[ports.{name}]: give either pin (one bit) or pins (a bus), not both"));
                    continue;
                }
                (None, None) => {
                    errors.push(format!("[ports.{name}]: no pin (one bit) or pins (a bus, bit 0 first)"));
                    continue;
                }
            };
            for (i, pin) in pins.iter().enumerate() {
                let bit = if p.pins.is_some() { format!("{name}<{i}>") } else { name.clone() };
                if !valid_ball(pin) {
                    errors.push(format!(
                        "[ports.{name}]: {pin:?} ({bit}) is not a ball of the FGG484 package (rows A..AB without \
                         I, O, Q, S, X, Z; columns 1..22)"
                    ));
                } else if let Some(other) = used.insert(pin.clone(), bit.clone()) {
                    errors.push(format!("ball {pin} is given twice: {other} and {bit}"));
                }
            }
            let iostandard = p.iostandard.clone().unwrap_or_else(|| default_std.clone());
            if !IOSTANDARDS.contains(&iostandard.as_str()) {
                errors.push(format!(
                    "[ports.{name}]: iostandard {iostandard:?} is not a Spartan-6 single-ended standard ({})",
                    IOSTANDARDS.join(", ")
                ));
            }
            if let Some(pull) = &p.pull {
                if !PULLS.contains(&pull.as_str()) {
                    errors.push(format!("[ports.{name}]: pull {pull:?}: use one of {}", PULLS.join(", ")));
                }
            }
            if let Some(drive) = p.drive {
                if !DRIVES.contains(&drive) {
                    errors.push(format!("[ports.{name}]: drive {drive}: use one of {DRIVES:?} (mA)"));
                }
            }
            if let Some(slew) = &p.slew {
                if !SLEWS.contains(&slew.as_str()) {
                    errors.push(format!("[ports.{name}]: slew {slew:?}: use one of {}", SLEWS.join(", ")));
                }
            }
            if let Some(hz) = p.frequency_hz {
                clocks.push((name.clone(), hz));
                if hz == 0 || hz > 1_000_000_000 {
                    errors.push(format!("[ports.{name}]: frequency_hz {hz} is not a clock frequency"));
                }
                if p.pins.is_some() {
                    errors.push(format!("[ports.{name}]: the clock is one pin (pin = \"...\"), not pins = [...]"));
                } else if let Some(pin) = &p.pin {
                    if valid_ball(pin) && !GCLK_PINS.contains(&pin.as_str()) {
                        errors.push(format!(
                            "[ports.{name}]: the clock's ball {pin} is not a global-clock (GCLK) input of the \
                             XC6SLX45-FGG484; use one of {}",
                            GCLK_PINS.join(" ")
                        ));
                    }
                }
            }
            let port = PortPins {
                pins,
                is_bus: p.pins.is_some(),
                iostandard,
                pull: p.pull.clone(),
                drive: p.drive,
                slew: p.slew.clone(),
                note: p.note.clone(),
            };
            ports.insert(name.clone(), port);
        }
        let (clock_port, clock_hz) = match clocks.as_slice() {
            [(n, hz)] => (n.clone(), *hz),
            [] => {
                errors.push("no clock: give the clock port's entry frequency_hz = <oscillator Hz>".to_string());
                (String::new(), 0)
            }
            many => {
                let names: Vec<&str> = many.iter().map(|(n, _)| n.as_str()).collect();
                errors.push(format!("frequency_hz is given for {names:?}; give it for the one clock port only"));
                (String::new(), 0)
            }
        };
        if !errors.is_empty() {
            bail!("pin map {origin} has {} problem(s):\n  - {}", errors.len(), errors.join("\n  - "));
        }
        Ok(PinMap {
            origin: origin.to_string(),
            board: raw.board.name,
            source: raw.board.source,
            vccaux: raw.board.vccaux,
            clock_port,
            clock_hz,
            ports,
        })
    }
}

/// The clock period in ns as the UCF writes it: up to 3 decimals, trailing zeros dropped.
pub fn period_ns(clock_hz: u64) -> String {
    let s = format!("{:.3}", 1e9 / clock_hz as f64);
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// The UCF for a top with `ports` on the board `map` describes, for a design clocked at
/// `clock_hz` (which must be the board's oscillator: the board top has no DCM). Fails, listing
/// every problem, when a port is missing from the map, the map names a port the top does not
/// have, a bus has the wrong number of pins, the clock is not an input, or output-only
/// attributes (`drive`, `slew`) are given for an input.
pub fn render_ucf(map: &PinMap, ports: &[Port], clock_hz: u64) -> Result<String> {
    map.check_clock(clock_hz)?;
    let mut errors = Vec::new();
    for p in ports {
        let Some(e) = map.ports.get(&p.name) else {
            errors.push(format!(
                "port `{}` ({}) of top is missing from the pin map: add [ports.{}] with {}",
                p.name,
                p.describe(),
                p.name,
                if p.range.is_some() {
                    format!("pins = [{} balls, bit 0 first]", p.width())
                } else {
                    "pin = \"<ball>\"".to_string()
                }
            ));
            continue;
        };
        if p.range.is_some() != e.is_bus || e.pins.len() != p.width() {
            errors.push(format!(
                "port `{}` is {} bit(s) wide ({}) but the pin map gives {}",
                p.name,
                p.width(),
                p.describe(),
                if e.is_bus { format!("pins = [{} balls]", e.pins.len()) } else { "one pin".to_string() }
            ));
        }
        if p.direction == Direction::Input && (e.drive.is_some() || e.slew.is_some()) {
            errors.push(format!("port `{}` is an input: drive and slew apply to outputs only", p.name));
        }
        if p.name == map.clock_port && p.direction != Direction::Input {
            errors.push(format!("the clock `{}` must be an input of top", p.name));
        }
    }
    for name in map.ports.keys() {
        if !ports.iter().any(|p| &p.name == name) {
            let names: Vec<&str> = ports.iter().map(|p| p.name.as_str()).collect();
            errors.push(format!("the pin map names `{name}`, which is not a port of top ({})", names.join(", ")));
        }
    }
    if !errors.is_empty() {
        bail!("pin map {} does not fit the top's ports:\n  - {}", map.origin, errors.join("\n  - "));
    }

    let mut s = String::new();
    let _ = writeln!(s, "# {UCF_FILE}: written by hdl-gen (PF-ICP) from the pin map {}.", map.origin);
    let _ = writeln!(s, "# Do not edit: edit the pin map and run hdl-gen again (constraints/README.md).");
    let _ = writeln!(s, "# Board: {}", map.board);
    if let Some(src) = &map.source {
        let _ = writeln!(s, "# Pin-out from: {src}");
    }
    let _ = writeln!(s, "# Device: Spartan-6 XC6SLX45-2FGG484 (ISE 14.7; Vivado does not support Spartan-6).");
    if let Some(v) = &map.vccaux {
        let _ = writeln!(s, "\nCONFIG VCCAUX = \"{v}\";");
    }
    let clock_first =
        ports.iter().filter(|p| p.name == map.clock_port).chain(ports.iter().filter(|p| p.name != map.clock_port));
    for p in clock_first {
        let e = &map.ports[&p.name];
        s.push('\n');
        if let Some(note) = &e.note {
            let _ = writeln!(s, "# {}: {note}", p.name);
        }
        for (net, pin) in p.nets().iter().zip(&e.pins) {
            let mut line = format!("NET \"{net}\" LOC = {pin} | IOSTANDARD = {}", e.iostandard);
            if let Some(d) = e.drive {
                let _ = write!(line, " | DRIVE = {d}");
            }
            if let Some(sl) = &e.slew {
                let _ = write!(line, " | SLEW = {sl}");
            }
            if let Some(pull) = &e.pull {
                let _ = write!(line, " | {pull}");
            }
            let _ = writeln!(s, "{line};");
        }
        if p.name == map.clock_port {
            let _ = writeln!(s, "NET \"{0}\" TNM_NET = \"{0}\";", p.name);
            let _ = writeln!(
                s,
                "TIMESPEC \"TS_{0}\" = PERIOD \"{0}\" {1} ns HIGH 50%;  # {2} Hz",
                p.name,
                period_ns(clock_hz),
                clock_hz
            );
        }
    }
    Ok(s)
}

/// Writes [`render_ucf`] to `dir/`[`UCF_FILE`] and returns the path.
pub fn write_ucf(map: &PinMap, ports: &[Port], clock_hz: u64, dir: &Path) -> Result<PathBuf> {
    let ucf = render_ucf(map, ports, clock_hz)?;
    std::fs::create_dir_all(dir).with_context(|| format!("could not create {}", dir.display()))?;
    let path = dir.join(UCF_FILE);
    std::fs::write(&path, ucf).with_context(|| format!("could not write {}", path.display()))?;
    Ok(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn balls_of_the_fgg484_grid() {
        for ok in ["A1", "AB22", "Y11", "K18", "W12"] {
            assert!(valid_ball(ok), "{ok}");
        }
        for bad in ["", "A0", "A23", "I5", "O3", "AC1", "ab11", "A01", "11", "AB"] {
            assert!(!valid_ball(bad), "{bad}");
        }
        assert_eq!(GCLK_PINS.len(), 32);
        assert!(GCLK_PINS.iter().all(|p| valid_ball(p)));
    }

    #[test]
    fn periods() {
        assert_eq!(period_ns(100_000_000), "10");
        assert_eq!(period_ns(50_000_000), "20");
        assert_eq!(period_ns(125_000_000), "8");
        assert_eq!(period_ns(33_333_333), "30");
        assert_eq!(period_ns(66_000_000), "15.152");
    }

    #[test]
    fn ports_in_both_styles() {
        let non_ansi = "// c\nmodule top(clock,leds,tx);\n input wire clock; /* x */\n output reg [3:0] leds;\n \
                        output wire tx;\nendmodule\nmodule other(a); input a; endmodule\n";
        let ansi = "module top #(parameter N = 2) (input wire clock, output reg [3:0] leds,\n output tx);\nendmodule";
        for v in [non_ansi, ansi] {
            let p = top_ports(v, "top").unwrap();
            assert_eq!(p.len(), 3, "{p:?}");
            assert_eq!(p[0], Port { name: "clock".into(), direction: Direction::Input, range: None });
            assert_eq!(p[1].range, Some((3, 0)));
            assert_eq!(p[1].nets(), ["leds<0>", "leds<1>", "leds<2>", "leds<3>"]);
            assert_eq!(p[2].direction, Direction::Output);
        }
        assert!(top_ports("module other(a); input a; endmodule", "top").is_err());
        assert!(top_ports("module top(a); input [N-1:0] a; endmodule", "top").is_err());
    }

    #[test]
    fn default_map_parses() {
        let m = PinMap::default_map();
        assert_eq!(m.clock_port, "clock");
        assert_eq!(m.clock_hz, 50_000_000);
        assert_eq!(m.ports["leds"].pins.len(), 4);
        assert_eq!(m.ports["uart_rx"].iostandard, "LVCMOS33");
    }
}
