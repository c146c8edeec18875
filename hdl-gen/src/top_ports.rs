//! The ports of a Verilog module ([`top_ports`]): what the UCF ([`crate::ucf`]) pins.

use anyhow::{bail, Context, Result};
use std::collections::BTreeMap;

/// A port's direction.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Direction {
    /// `input`
    Input,
    /// `output`
    Output,
    /// `inout`
    Inout,
}

/// One port of a Verilog module.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Port {
    /// Its name.
    pub name: String,
    /// Its direction.
    pub direction: Direction,
    /// `[msb:lsb]`, or `None` for one bit.
    pub range: Option<(i64, i64)>,
}

impl Port {
    /// Number of bits.
    pub fn width(&self) -> usize {
        self.range.map(|(m, l)| (m - l).unsigned_abs() as usize + 1).unwrap_or(1)
    }

    /// The UCF net names of its bits, lowest index first (`leds<0>`, `leds<1>`, ...).
    pub fn nets(&self) -> Vec<String> {
        match self.range {
            None => vec![self.name.clone()],
            Some((m, l)) => (m.min(l)..=m.max(l)).map(|i| format!("{}<{i}>", self.name)).collect(),
        }
    }

    pub(crate) fn describe(&self) -> String {
        let dir = match self.direction {
            Direction::Input => "input",
            Direction::Output => "output",
            Direction::Inout => "inout",
        };
        match self.range {
            None => format!("{dir} {}", self.name),
            Some((m, l)) => format!("{dir} [{m}:{l}] {}", self.name),
        }
    }
}

fn strip_comments(v: &str) -> String {
    let mut out = String::with_capacity(v.len());
    let mut chars = v.chars().peekable();
    while let Some(c) = chars.next() {
        match (c, chars.peek()) {
            ('/', Some('/')) => {
                for c in chars.by_ref() {
                    if c == '\n' {
                        out.push('\n');
                        break;
                    }
                }
            }
            ('/', Some('*')) => {
                chars.next();
                let mut prev = ' ';
                for c in chars.by_ref() {
                    if prev == '*' && c == '/' {
                        break;
                    }
                    prev = c;
                }
                out.push(' ');
            }
            _ => out.push(c),
        }
    }
    out
}

fn tokens(v: &str) -> Vec<String> {
    let mut t = Vec::new();
    let mut word = String::new();
    for c in v.chars() {
        if c.is_ascii_alphanumeric() || c == '_' || c == '$' || c == '\'' {
            word.push(c);
        } else {
            if !word.is_empty() {
                t.push(std::mem::take(&mut word));
            }
            if !c.is_whitespace() {
                t.push(c.to_string());
            }
        }
    }
    if !word.is_empty() {
        t.push(word);
    }
    t
}

/// The ports of module `top` in `verilog`, in the order of its port list. Reads both styles
/// (`module top(a, b); input wire [3:0] a; ...` and `module top(input wire [3:0] a, ...)`);
/// widths must be integer ranges.
pub fn top_ports(verilog: &str, top: &str) -> Result<Vec<Port>> {
    let t = tokens(&strip_comments(verilog));
    let start = t
        .windows(2)
        .position(|w| w[0] == "module" && w[1] == top)
        .with_context(|| format!("the Verilog has no module `{top}`"))?;
    let end = t[start..].iter().position(|s| s == "endmodule").map(|e| start + e).unwrap_or(t.len());
    let body = &t[start + 2..end];
    // The port list: after an optional #( ... ), the first ( ... ).
    let mut i = 0;
    let skip_parens = |i: &mut usize| -> Result<()> {
        let mut depth = 0;
        while *i < body.len() {
            match body[*i].as_str() {
                "(" => depth += 1,
                ")" => {
                    depth -= 1;
                    if depth == 0 {
                        *i += 1;
                        return Ok(());
                    }
                }
                _ => {}
            }
            *i += 1;
        }
        bail!("module `{top}`: unbalanced parentheses in its header")
    };
    if body.first().map(String::as_str) == Some("#") {
        i = 1;
        skip_parens(&mut i)?;
    }
    let list_start = i;
    if body.get(i).map(String::as_str) != Some("(") {
        bail!("module `{top}` has no port list");
    }
    skip_parens(&mut i)?;
    let header = &body[list_start + 1..i - 1];
    // Port names in header order: identifiers followed by ',' or the end of the list.
    let mut order = Vec::new();
    for (k, tok) in header.iter().enumerate() {
        let next = header.get(k + 1).map(String::as_str);
        if (next == Some(",") || next.is_none()) && tok.chars().next().is_some_and(|c| c.is_alphabetic() || c == '_') {
            order.push(tok.clone());
        }
    }
    // Declarations, in the header (ANSI) or the body.
    let mut decls: BTreeMap<String, Port> = BTreeMap::new();
    let mut k = 0;
    let all: Vec<&String> = header.iter().chain(body[i..].iter()).collect();
    while k < all.len() {
        let direction = match all[k].as_str() {
            "input" => Direction::Input,
            "output" => Direction::Output,
            "inout" => Direction::Inout,
            _ => {
                k += 1;
                continue;
            }
        };
        k += 1;
        while k < all.len() && ["wire", "reg", "logic", "signed", "unsigned", "var"].contains(&all[k].as_str()) {
            k += 1;
        }
        let mut range = None;
        if k < all.len() && all[k] == "[" {
            let close = all[k..].iter().position(|s| *s == "]").map(|c| k + c);
            let parsed = close.and_then(|c| match &all[k + 1..c] {
                [m, colon, l] if *colon == ":" => Some((m.parse::<i64>().ok()?, l.parse::<i64>().ok()?)),
                _ => None,
            });
            match (close, parsed) {
                (Some(c), Some(r)) => {
                    range = Some(r);
                    k = c + 1;
                }
                _ => bail!(
                    "module `{top}`: cannot read a port range near `{}`",
                    all[k..].iter().take(6).map(|s| s.as_str()).collect::<Vec<_>>().join(" ")
                ),
            }
        }
        while k < all.len() {
            let tok = all[k].as_str();
            if [";", ")", "input", "output", "inout"].contains(&tok) {
                break;
            }
            if tok != "," {
                decls.insert(tok.to_string(), Port { name: tok.to_string(), direction, range });
            }
            k += 1;
        }
    }
    let mut ports = Vec::new();
    for name in order {
        match decls.remove(&name) {
            Some(p) => ports.push(p),
            None => bail!("module `{top}`: port `{name}` has no input/output declaration"),
        }
    }
    if ports.is_empty() {
        bail!("module `{top}` has no ports");
    }
    Ok(ports)
}
