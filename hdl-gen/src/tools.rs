//! Running the external tools (Verilator, Yosys).

use anyhow::{anyhow, Context, Result};
use std::ffi::OsStr;
use std::path::Path;
use std::process::{Command, Output};

/// How to install the tools hdl-gen needs.
pub const INSTALL_HINT: &str = "apt-get install -y verilator yosys";

/// Runs `program args..` in `cwd` and collects its output. A program that is not on `PATH`
/// gives an error that says how to install it.
pub fn run<I, S>(program: &str, args: I, cwd: &Path) -> Result<Output>
where
    I: IntoIterator<Item = S>,
    S: AsRef<OsStr>,
{
    match Command::new(program).args(args).current_dir(cwd).output() {
        Ok(out) => Ok(out),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Err(anyhow!(
            "`{program}` was not found on PATH; install Verilator and Yosys with `{INSTALL_HINT}` \
             (hdl-gen is tested with Verilator 5.006 and Yosys 0.23)"
        )),
        Err(e) => Err(e).with_context(|| format!("could not run `{program}` in {}", cwd.display())),
    }
}

/// stdout and stderr of a finished tool, as one string (stdout first).
pub fn combined_output(out: &Output) -> String {
    let mut s = String::from_utf8_lossy(&out.stdout).into_owned();
    let err = String::from_utf8_lossy(&out.stderr);
    if !s.is_empty() && !err.is_empty() && !s.ends_with('\n') {
        s.push('\n');
    }
    s.push_str(&err);
    s
}

/// The last `n` lines of `text`.
pub fn tail(text: &str, n: usize) -> String {
    let lines: Vec<&str> = text.lines().collect();
    lines[lines.len().saturating_sub(n)..].join("\n")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn missing_tool_gives_the_install_hint() {
        let err = run("hdl-gen-no-such-tool-xyz", ["--version"], Path::new(".")).unwrap_err().to_string();
        assert!(err.contains("hdl-gen-no-such-tool-xyz"), "{err}");
        assert!(err.contains(INSTALL_HINT), "{err}");
    }

    #[test]
    fn tail_keeps_the_last_lines() {
        assert_eq!(tail("a\nb\nc\n", 2), "b\nc");
        assert_eq!(tail("a", 5), "a");
        assert_eq!(tail("", 5), "");
    }
}
