//! The written Verilog file (header and Verilator waivers) and `verilator --lint-only -Wall`.

use crate::tools;
use anyhow::{bail, Context, Result};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Name of the Verilog file hdl-gen writes into its output directory.
pub const VERILOG_FILE: &str = "pficp_pipeline.v";

/// Name of the top module.
pub const TOP: &str = "top";

/// First line of every file hdl-gen writes; [`prepare_verilog`] does not add the header twice.
pub const HEADER_MARK: &str = "// Written by hdl-gen (PF-ICP).";

/// The Verilator lint waivers put at the top of the written file, each with its reason.
/// `-Wall` gives exactly these warning kinds on rust_hdl 0.46 output, all by construction
/// (`UNUSEDPARAM` only on designs with enum state machines, such as the board).
pub const WAIVERS: &[(&str, &str)] = &[
    (
        "WIDTH",
        "rust_hdl sign-extends with $signed(x) sized by the assignment context, and widens or \
         narrows with bit_cast masking (x & N'hmask); both are intended width changes.",
    ),
    (
        "DECLFILENAME",
        "rust_hdl writes one file holding many modules (one per block instance), so module names \
         cannot match the file name.",
    ),
    (
        "UNUSEDPARAM",
        "rust_hdl declares a localparam for every variant of an enum state type in each module \
         that holds one; a module need not name every variant.",
    ),
];

/// The Verilog as hdl-gen writes it: a header, the lint waivers (as `/* verilator lint_off */`
/// comment lines, each after a one-line justification), then `verilog`. Text that already
/// starts with the header is returned unchanged.
pub fn prepare_verilog(verilog: &str) -> String {
    if verilog.starts_with(HEADER_MARK) {
        return verilog.to_string();
    }
    let mut s = String::new();
    s.push_str(HEADER_MARK);
    s.push_str(" Linted with `verilator --lint-only -Wall`; synthesised with Yosys synth_xilinx.\n");
    // (A comment whose text starts with the word "verilator" is a Verilator meta-comment.)
    s.push_str("// Lint waivers for Verilator:\n");
    for (code, why) in WAIVERS {
        s.push_str(&format!("// {code}: {why}\n/* verilator lint_off {code} */\n"));
    }
    s.push('\n');
    s.push_str(verilog);
    if !s.ends_with('\n') {
        s.push('\n');
    }
    s
}

/// Writes [`prepare_verilog`]`(verilog)` to `dir/`[`VERILOG_FILE`] (creating `dir`) and
/// returns the path.
pub fn write_verilog(verilog: &str, dir: &Path) -> Result<PathBuf> {
    std::fs::create_dir_all(dir).with_context(|| format!("could not create {}", dir.display()))?;
    let path = dir.join(VERILOG_FILE);
    std::fs::write(&path, prepare_verilog(verilog)).with_context(|| format!("could not write {}", path.display()))?;
    Ok(path)
}

/// One Verilator diagnostic (`%Warning-CODE: file:line:col: text` or `%Error: ...`).
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct LintMessage {
    /// `Warning` or `Error`.
    pub severity: String,
    /// The warning code (`WIDTH`, `UNUSEDSIGNAL`, ...), if any.
    pub code: Option<String>,
    /// `file:line:col`, if given.
    pub location: Option<String>,
    /// The message text.
    pub text: String,
}

/// Result of one `verilator --lint-only -Wall` run.
#[derive(Debug, Clone, Serialize)]
pub struct LintReport {
    /// The linted file.
    pub file: PathBuf,
    /// The command line that was run (in the file's directory).
    pub command: String,
    /// Verilator's exit code (`None` if killed by a signal).
    pub exit_code: Option<i32>,
    /// Verilator's stdout and stderr.
    pub output: String,
    /// The diagnostics in `output`.
    pub messages: Vec<LintMessage>,
}

impl LintReport {
    /// Exit code 0 and no diagnostics.
    pub fn is_clean(&self) -> bool {
        self.exit_code == Some(0) && self.messages.is_empty()
    }
}

/// Parses Verilator's diagnostics: lines starting with `%Warning` or `%Error` (the
/// continuation lines that show the source and hints are skipped; so is the summary line
/// `%Error: Exiting due to N warning(s)`).
pub fn parse_verilator_output(output: &str) -> Vec<LintMessage> {
    let mut msgs = Vec::new();
    for line in output.lines() {
        let Some(rest) = line.strip_prefix('%') else { continue };
        let Some((head, body)) = rest.split_once(": ") else { continue };
        let (severity, code) = match head.split_once('-') {
            Some((s, c)) => (s, Some(c.to_string())),
            None => (head, None),
        };
        if severity != "Warning" && severity != "Error" {
            continue;
        }
        if code.is_none() && body.starts_with("Exiting due to") {
            continue;
        }
        // `file:line:col: text` (file names here never contain ": ").
        let (location, text) = match body.split_once(": ") {
            Some((loc, text)) if loc.split(':').count() >= 2 && loc.split(':').skip(1).all(is_number) => {
                (Some(loc.to_string()), text.to_string())
            }
            _ => (None, body.to_string()),
        };
        msgs.push(LintMessage { severity: severity.to_string(), code, location, text });
    }
    msgs
}

fn is_number(s: &str) -> bool {
    !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit())
}

/// Runs `verilator --lint-only -Wall --top-module top FILE` on an existing file and reports
/// what it said. Errors only if Verilator cannot be run (e.g. not installed).
pub fn lint_file(file: &Path) -> Result<LintReport> {
    let dir = file.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let name = file.file_name().with_context(|| format!("{} is not a file", file.display()))?;
    let args = ["--lint-only".as_ref(), "-Wall".as_ref(), "--top-module".as_ref(), TOP.as_ref(), name];
    let out = tools::run("verilator", args, dir)?;
    let output = tools::combined_output(&out);
    Ok(LintReport {
        file: file.to_path_buf(),
        command: format!("verilator --lint-only -Wall --top-module {TOP} {}", name.to_string_lossy()),
        exit_code: out.status.code(),
        messages: parse_verilator_output(&output),
        output,
    })
}

/// Writes `verilog` (with the waivers, see [`write_verilog`]) to `dir/`[`VERILOG_FILE`] and
/// lints it with `verilator --lint-only -Wall`. Fails unless the lint is clean (exit 0, no
/// warnings); the error shows Verilator's output.
pub fn lint(verilog: &str, dir: &Path) -> Result<LintReport> {
    let path = write_verilog(verilog, dir)?;
    let report = lint_file(&path)?;
    if !report.is_clean() {
        bail!(
            "Verilator lint of {} is not clean (exit code {}, {} diagnostic(s)); `{}` said:\n{}",
            path.display(),
            report.exit_code.map_or("none".to_string(), |c| c.to_string()),
            report.messages.len(),
            report.command,
            report.output.trim_end()
        );
    }
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn waivers_come_first_each_with_a_reason() {
        let v = prepare_verilog("module top(input wire a);\nendmodule");
        let lines: Vec<&str> = v.lines().collect();
        assert!(lines[0].starts_with(HEADER_MARK));
        for (code, _) in WAIVERS {
            let i = lines.iter().position(|l| *l == format!("/* verilator lint_off {code} */")).unwrap();
            assert!(lines[i - 1].starts_with(&format!("// {code}: ")), "{}", lines[i - 1]);
        }
        let module = lines.iter().position(|l| l.starts_with("module top")).unwrap();
        assert!(lines[..module].iter().all(|l| l.is_empty() || l.starts_with("//") || l.starts_with("/*")));
        assert!(v.ends_with("endmodule\n"));
        assert_eq!(prepare_verilog(&v), v, "the header is added once");
    }

    #[test]
    fn parses_warnings_and_skips_the_summary() {
        let out = "%Warning-WIDTH: t.v:5:12: Operator ADD expects 13 bits on the LHS, but LHS's VARREF 'x' generates 12 bits.\n\
                   \x20   5 |   sum <= x + y;\n\
                   %Warning-DECLFILENAME: t.v:1:8: Filename 't' does not match MODULE name: 'top'\n\
                   %Error: t.v:9:1: syntax error, unexpected endmodule\n\
                   %Error: Exiting due to 2 warning(s)\n";
        let m = parse_verilator_output(out);
        assert_eq!(m.len(), 3);
        assert_eq!(m[0].code.as_deref(), Some("WIDTH"));
        assert_eq!(m[0].location.as_deref(), Some("t.v:5:12"));
        assert!(m[0].text.starts_with("Operator ADD"));
        assert_eq!(m[1].code.as_deref(), Some("DECLFILENAME"));
        assert_eq!(m[2].severity, "Error");
        assert_eq!(m[2].code, None);
        assert_eq!(m[2].location.as_deref(), Some("t.v:9:1"));
    }
}
