//! Plain-text tables: a title, a header row, left-aligned first column, right-aligned
//! cells, columns as wide as their widest cell.

/// A table to print.
#[derive(Clone, Debug, Default)]
pub(crate) struct TextTable {
    title: String,
    header: Vec<String>,
    rows: Vec<Vec<String>>,
    notes: Vec<String>,
}

impl TextTable {
    /// A table with `title` and the column headers (first one over the row labels).
    pub(crate) fn new(title: impl Into<String>, header: Vec<String>) -> Self {
        Self { title: title.into(), header, ..Self::default() }
    }

    /// Add a row (label first).
    pub(crate) fn row(&mut self, cells: Vec<String>) {
        self.rows.push(cells);
    }

    /// Add a note printed under the table.
    pub(crate) fn note(&mut self, note: impl Into<String>) {
        self.notes.push(note.into());
    }

    /// The rendered table, ending in a newline.
    pub(crate) fn render(&self) -> String {
        let ncols = std::iter::once(&self.header).chain(&self.rows).map(Vec::len).max().unwrap_or(0);
        let mut width = vec![0usize; ncols];
        for r in std::iter::once(&self.header).chain(&self.rows) {
            for (i, c) in r.iter().enumerate() {
                width[i] = width[i].max(c.chars().count());
            }
        }
        let line = |r: &[String]| -> String {
            let mut s = String::new();
            for (i, w) in width.iter().enumerate() {
                let c = r.get(i).map(String::as_str).unwrap_or("");
                if i == 0 {
                    s += &format!("{c:<w$}");
                } else {
                    s += &format!("  {c:>w$}");
                }
            }
            s.trim_end().to_string() + "\n"
        };
        let total = width.iter().sum::<usize>() + 2 * ncols.saturating_sub(1);
        let mut out = format!("{}\n", self.title);
        out += &"=".repeat(total.max(self.title.chars().count().min(100)));
        out += "\n";
        out += &line(&self.header);
        out += &"-".repeat(total);
        out += "\n";
        for r in &self.rows {
            out += &line(r);
        }
        for n in &self.notes {
            out += &format!("  {n}\n");
        }
        out
    }
}

/// A number for a table cell: fixed with `decimals` places, scientific when tiny or huge.
pub(crate) fn num(x: f64, decimals: usize) -> String {
    if !x.is_finite() {
        return format!("{x}");
    }
    let a = x.abs();
    if a != 0.0 && (a < 0.5 * 10f64.powi(-(decimals as i32)) || a >= 1e6) {
        format!("{x:.2e}")
    } else {
        format!("{x:.decimals$}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn renders_aligned_columns() {
        let mut t = TextTable::new("T", vec!["p".into(), "a".into(), "bb".into()]);
        t.row(vec!["phi (deg)".into(), "1.0".into(), "-22.5".into()]);
        t.note("n");
        let s = t.render();
        assert!(s.starts_with("T\n"));
        assert!(s.contains("phi (deg)  1.0  -22.5\n"), "{s}");
        assert_eq!(num(1e-9, 3), "1.00e-9");
        assert_eq!(num(-0.98, 3), "-0.980");
    }
}
