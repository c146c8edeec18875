//! XYZ and CSV text: one point a line.

use std::io::BufRead;

use nalgebra::Point3;

use super::lines::{check_limit, Lines};
use super::{fmt_float, parse_f64, ParseError};

/// Read whitespace-separated `x y z` lines, at most `limit` points. Everything after `#`
/// is a comment, blank lines are skipped and columns after the third are ignored.
pub(super) fn read_xyz(reader: impl BufRead, limit: usize) -> Result<Vec<Point3<f64>>, ParseError> {
    let mut lines = Lines::new(reader);
    let mut points = Vec::new();
    while let Some((number, raw)) = lines.next_line()? {
        let line = raw.split('#').next().unwrap_or("");
        let fields: Vec<&str> = line.split_whitespace().collect();
        if fields.is_empty() {
            continue;
        }
        check_limit(points.len(), limit)?;
        points.push(point_at(&fields, [0, 1, 2], number)?);
    }
    Ok(points)
}

/// Read comma-separated lines, at most `limit` points. The first non-blank line is a
/// header if none of its fields is a number; if the header names columns `x`, `y` and `z`
/// (any case) those are used, otherwise the first three columns. Blank lines and lines
/// starting with `#` are skipped.
pub(super) fn read_csv(reader: impl BufRead, limit: usize) -> Result<Vec<Point3<f64>>, ParseError> {
    let mut lines = Lines::new(reader);
    let mut columns = [0, 1, 2];
    let mut seen_first = false;
    let mut points = Vec::new();
    while let Some((number, line)) = lines.next_line()? {
        let trimmed = line.trim();
        if trimmed.is_empty() || trimmed.starts_with('#') {
            continue;
        }
        let fields: Vec<&str> = trimmed.split(',').map(unquote).collect();
        if !seen_first {
            seen_first = true;
            if is_header(&fields) {
                columns = header_columns(&fields).unwrap_or(columns);
                continue;
            }
        }
        check_limit(points.len(), limit)?;
        points.push(point_at(&fields, columns, number)?);
    }
    Ok(points)
}

/// Trim spaces and one pair of surrounding double quotes.
fn unquote(field: &str) -> &str {
    let f = field.trim();
    f.strip_prefix('"').and_then(|g| g.strip_suffix('"')).unwrap_or(f).trim()
}

/// A header line has no numeric field.
fn is_header(fields: &[&str]) -> bool {
    fields.iter().all(|f| f.parse::<f64>().is_err())
}

/// Indices of the columns named x, y and z, if all three are present.
fn header_columns(fields: &[&str]) -> Option<[usize; 3]> {
    let find = |name: &str| fields.iter().position(|f| f.eq_ignore_ascii_case(name));
    Some([find("x")?, find("y")?, find("z")?])
}

/// The point in `fields` at `columns`, reporting 1-based `line` on error.
fn point_at(fields: &[&str], columns: [usize; 3], line: usize) -> Result<Point3<f64>, ParseError> {
    let needed = columns.iter().max().map_or(3, |&m| m + 1);
    let mut xyz = [0.0; 3];
    for (slot, &c) in xyz.iter_mut().zip(columns.iter()) {
        let field = fields.get(c).ok_or(ParseError::TooFewColumns { line, found: fields.len(), needed })?;
        *slot = parse_f64(field, line)?;
    }
    Ok(Point3::from(xyz))
}

/// One `x<sep>y<sep>z` line per point, after an optional header line.
pub(super) fn write_delimited(points: &[Point3<f64>], sep: &str, header: Option<&str>) -> Vec<u8> {
    let mut out = String::new();
    if let Some(h) = header {
        out.push_str(h);
        out.push('\n');
    }
    for p in points {
        out.push_str(&fmt_float(p.x));
        out.push_str(sep);
        out.push_str(&fmt_float(p.y));
        out.push_str(sep);
        out.push_str(&fmt_float(p.z));
        out.push('\n');
    }
    out.into_bytes()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn p(x: f64, y: f64, z: f64) -> Point3<f64> {
        Point3::new(x, y, z)
    }

    fn read_xyz_all(bytes: &[u8]) -> Result<Vec<Point3<f64>>, ParseError> {
        read_xyz(bytes, usize::MAX)
    }

    fn read_csv_all(bytes: &[u8]) -> Result<Vec<Point3<f64>>, ParseError> {
        read_csv(bytes, usize::MAX)
    }

    #[test]
    fn the_point_limit_is_checked_before_a_point_is_stored() {
        assert_eq!(read_xyz(&b"1 2 3\n4 5 6\n"[..], 2).unwrap().len(), 2);
        assert_eq!(read_xyz(&b"1 2 3\n4 5 6\n7 8 9\n"[..], 2), Err(ParseError::TooManyPoints { limit: 2 }));
        assert_eq!(read_csv(&b"x,y,z\n1,2,3\n4,5,6\n"[..], 1), Err(ParseError::TooManyPoints { limit: 1 }));
    }

    #[test]
    fn xyz_skips_comments_blanks_and_extra_columns() {
        let text = "# header comment\n\n1 2 3 0.5 255\n  4\t5 6 # trailing\r\n   \n7 8 9\n";
        let pts = read_xyz_all(text.as_bytes()).unwrap();
        assert_eq!(pts, vec![p(1.0, 2.0, 3.0), p(4.0, 5.0, 6.0), p(7.0, 8.0, 9.0)]);
    }

    #[test]
    fn xyz_errors_give_line_numbers() {
        let e = read_xyz_all(b"1 2 3\n\n1 2 three\n").unwrap_err();
        assert_eq!(e, ParseError::BadNumber { line: 3, text: "three".into() });
        assert!(e.to_string().contains("malformed number") && e.to_string().contains("line 3"));
        let e = read_xyz_all(b"1 2 3\n4 5\n").unwrap_err().to_string();
        assert!(e.contains("too few columns") && e.contains("line 2"), "{e}");
        assert!(read_xyz_all(b"# only comments\n\n").unwrap().is_empty());
    }

    #[test]
    fn csv_header_and_named_columns() {
        let pts = read_csv_all(b"1,2,3\n4,5,6\n").unwrap();
        assert_eq!(pts, vec![p(1.0, 2.0, 3.0), p(4.0, 5.0, 6.0)]);
        let pts = read_csv_all(b"a,b,c,d\n1,2,3,4\n").unwrap();
        assert_eq!(pts, vec![p(1.0, 2.0, 3.0)]);
        let text = "id, \"Z\", Y ,intensity,X\r\n7, 3, 2, 0.5, 1\n8,6,5,0.1,4\n";
        let pts = read_csv_all(text.as_bytes()).unwrap();
        assert_eq!(pts, vec![p(1.0, 2.0, 3.0), p(4.0, 5.0, 6.0)]);
        let pts = read_csv_all(b"\n# note\nx,y,z\n1,2,3,label\n").unwrap();
        assert_eq!(pts, vec![p(1.0, 2.0, 3.0)]);
    }

    #[test]
    fn csv_errors() {
        let e = read_csv_all(b"x,y,z\n1,2,3\n1,,3\n").unwrap_err().to_string();
        assert!(e.contains("malformed number") && e.contains("line 3"), "{e}");
        let e = read_csv_all(b"x,y,z\n1,2\n").unwrap_err().to_string();
        assert!(e.contains("too few columns") && e.contains("line 2"), "{e}");
        let e = read_csv_all(b"a,x,y,z\n1,2,3\n").unwrap_err().to_string();
        assert!(e.contains("found 3, need at least 4"), "{e}");
        let e = read_csv_all(b"1,2,3\nx,y,z\n").unwrap_err().to_string();
        assert!(e.contains("malformed number `x` at line 2"), "{e}");
        assert!(read_csv_all(b"x,y,z\n").unwrap().is_empty());
    }

    #[test]
    fn write_then_read_is_exact() {
        let pts = vec![p(0.1, -0.0, 1e-300), p(f64::MAX, f64::MIN_POSITIVE, 2.0 / 3.0)];
        assert_eq!(read_xyz_all(&write_delimited(&pts, " ", None)).unwrap(), pts);
        let csv = write_delimited(&pts, ",", Some("x,y,z"));
        assert!(csv.starts_with(b"x,y,z\n"));
        assert_eq!(read_csv_all(&csv).unwrap(), pts);
    }

    /// Any finite f64, both signs, including subnormals and zeros.
    fn finite() -> impl Strategy<Value = f64> {
        use proptest::num::f64::{NEGATIVE, NORMAL, POSITIVE, SUBNORMAL, ZERO};
        POSITIVE | NEGATIVE | NORMAL | SUBNORMAL | ZERO
    }

    proptest! {
        #[test]
        fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..512)) {
            let _ = read_xyz_all(&bytes);
            let _ = read_csv_all(&bytes);
        }

        #[test]
        fn random_text_never_panics(text in "[0-9xyzXYZ,. #\"eE+\n\r\t-]{0,200}") {
            let _ = read_xyz_all(text.as_bytes());
            let _ = read_csv_all(text.as_bytes());
        }

        #[test]
        fn random_points_round_trip(xs in proptest::collection::vec(finite(), 0..30)) {
            let pts: Vec<_> = xs.chunks_exact(3).map(|c| p(c[0], c[1], c[2])).collect();
            prop_assert_eq!(read_xyz_all(&write_delimited(&pts, " ", None)).unwrap(), pts.clone());
            prop_assert_eq!(read_csv_all(&write_delimited(&pts, ",", Some("x,y,z"))).unwrap(), pts);
        }
    }
}
