//! The ISE 14.7 build script (`build_ise.tcl`, for `xtclsh`) of the board design: an ISE
//! project for the Spartan-6 XC6SLX45-2FGG484 with the written Verilog and UCF, run through
//! XST, MAP, PAR and BitGen to `top.bit`. Vivado does not support Spartan-6; ISE 14.7 is the
//! last tool that builds it.

use anyhow::{Context, Result};
use std::path::{Path, PathBuf};

/// Name of the script hdl-gen writes into its output directory.
pub const TCL_FILE: &str = "build_ise.tcl";
/// ISE's device family name.
pub const FAMILY: &str = "Spartan6";
/// The device.
pub const DEVICE: &str = "xc6slx45";
/// The package.
pub const PACKAGE: &str = "fgg484";
/// The speed grade.
pub const SPEED: &str = "-2";
/// The ISE project the script creates (`pficp_board.xise`).
pub const PROJECT: &str = "pficp_board";

/// The bitstream ISE writes: named after the top module.
pub fn bitstream(top: &str) -> String {
    format!("{top}.bit")
}

/// The `xtclsh` script that builds `top` from `verilog_file` and `ucf_file` (both in the
/// script's folder) into `<top>.bit`. It exits 1 if a step fails or PAR reports unmet timing
/// constraints.
pub fn build_script(verilog_file: &str, ucf_file: &str, top: &str) -> String {
    let bit = bitstream(top);
    format!(
        r#"# {TCL_FILE}: written by hdl-gen (PF-ICP). Builds the board top `{top}` for the Spartan-6
# XC6SLX45-2FGG484 with ISE 14.7 (Vivado does not support Spartan-6).
#
# Run it from this folder, with ISE's environment set up, e.g.:
#   source /opt/Xilinx/14.7/ISE_DS/settings64.sh
#   xtclsh {TCL_FILE}
# Result: {bit} in this folder (ISE names the bitstream after the top module). Reports:
# {top}.syr (XST), {top}_map.mrp (MAP), {top}.par (place and route), {top}.twr (timing).
# Exits 1 if a step fails or the timing constraints (the PERIOD in {ucf_file}) are not met.

set project {PROJECT}
set top {top}
foreach f [list {verilog_file} {ucf_file}] {{
    if {{![file exists $f]}} {{
        puts "{TCL_FILE}: $f not found; run xtclsh from the folder hdl-gen wrote"
        exit 1
    }}
}}
# A fresh project on every run.
foreach ext {{xise gise}} {{
    file delete -force $project.$ext
}}

project new $project.xise
project set family "{FAMILY}"
project set device "{DEVICE}"
project set package "{PACKAGE}"
project set speed "{SPEED}"
project set top_level_module_type "HDL"
project set synthesis_tool "XST (VHDL/Verilog)"
project set simulator "ISim (VHDL/Verilog)"
project set "Preferred Language" "Verilog"

xfile add "{verilog_file}"
xfile add "{ucf_file}"
project set top $top

# Synthesis (XST): for speed, flattened, multipliers in DSP48A1 slices.
project set "Optimization Goal" "Speed" -process "Synthesize - XST"
project set "Optimization Effort" "High" -process "Synthesize - XST"
project set "Keep Hierarchy" "No" -process "Synthesize - XST"
project set "Use DSP Block" "Auto" -process "Synthesize - XST"
# MAP and place and route.
project set "Placer Effort Level" "High" -process "Map"
project set "Register Duplication" "On" -process "Map"
project set "Generate Detailed MAP Report" "true" -process "Map"
project set "Place & Route Effort Level (Overall)" "High" -process "Place & Route"
project set "Report Type" "Verbose Report" -process "Generate Post-Place & Route Static Timing"
# Bitstream.
project set "Create Bit File" "true" -process "Generate Programming File"
project set "Enable Cyclic Redundancy Checking (CRC)" "true" -process "Generate Programming File"
project set "Unused IOB Pins" "Pull Down" -process "Generate Programming File"

process run "Generate Programming File"
set status [process get "Generate Programming File" status]
project close

if {{$status ne "up_to_date" && $status ne "warnings"}} {{
    puts "{TCL_FILE}: the build failed (Generate Programming File: $status); see $top.syr, ${{top}}_map.mrp, $top.par"
    exit 1
}}
if {{[catch {{open $top.par r}} fid]}} {{
    puts "{TCL_FILE}: no $top.par, timing not checked"
}} else {{
    set par [read $fid]
    close $fid
    if {{[regexp {{[1-9][0-9]* constraints? not met}} $par]}} {{
        puts "{TCL_FILE}: timing constraints not met; see $top.twr"
        exit 1
    }}
}}
puts "{TCL_FILE}: wrote {bit}"
exit 0
"#
    )
}

/// Writes [`build_script`] to `dir/`[`TCL_FILE`] and returns the path.
pub fn write_script(verilog_file: &str, ucf_file: &str, top: &str, dir: &Path) -> Result<PathBuf> {
    std::fs::create_dir_all(dir).with_context(|| format!("could not create {}", dir.display()))?;
    let path = dir.join(TCL_FILE);
    std::fs::write(&path, build_script(verilog_file, ucf_file, top))
        .with_context(|| format!("could not write {}", path.display()))?;
    Ok(path)
}
