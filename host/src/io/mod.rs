//! Point-cloud files: PLY (ascii and binary little endian), PCD (ascii, binary and, read
//! only, binary_compressed), XYZ text and CSV.
//!
//! [`read_cloud`] picks the reader from the file extension and validates the
//! points into a [`Cloud`]; [`write_cloud`] writes raw points in a chosen
//! [`Format`]. [`read_points`] streams any reader: one line (at most
//! [`MAX_LINE_BYTES`]) or one binary record at a time, and no more than the point limit
//! ([`crate::cloud::MAX_CLOUD_POINTS`] for files), so a huge file costs at most the limit's
//! points in memory, never the file's size. [`read_points_from_bytes`] and
//! [`write_points_to_bytes`] are the byte-level forms. Every error is an [`IoError`] whose
//! one-line message names the file.

mod lines;
mod pcd;
mod ply;
mod text;

use std::io::BufRead;
use std::path::Path;

pub use lines::MAX_LINE_BYTES;
pub use pcd::{MAX_BODY_BYTES, MAX_RECORD_BYTES};

use nalgebra::Point3;
use thiserror::Error;

use crate::cloud::{Cloud, CloudError};

/// A point-cloud file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// PLY, `format ascii 1.0`.
    PlyAscii,
    /// PLY, `format binary_little_endian 1.0` (written with `double` x y z).
    PlyBinary,
    /// PCD (the Point Cloud Library's format), `DATA ascii`, written with `F 8` x y z.
    PcdAscii,
    /// PCD, `DATA binary` (little endian, `F 8` x y z).
    PcdBinary,
    /// Whitespace-separated `x y z` per line; `#` starts a comment.
    Xyz,
    /// Comma-separated values with an optional header line.
    Csv,
}

/// What is wrong with the contents of a file (the file name is added by [`IoError`]).
#[derive(Debug, Error, PartialEq)]
pub enum ParseError {
    /// The first line is not `ply`.
    #[error("not a PLY file (first line is not `ply`)")]
    NotPly,
    /// The header never ends.
    #[error("malformed PLY header: missing `end_header` line")]
    MissingEndHeader,
    /// No `format` line before `end_header`.
    #[error("malformed PLY header: missing `format` line")]
    MissingFormat,
    /// A PLY format other than ascii and binary little endian.
    #[error("unsupported PLY format `{0}` (only ascii and binary_little_endian are supported)")]
    UnsupportedFormat(String),
    /// A header line that is not understood.
    #[error("malformed PLY header at line {line}: `{text}`")]
    BadHeaderLine {
        /// 1-based line number.
        line: usize,
        /// The line (possibly shortened).
        text: String,
    },
    /// An `element` line whose count is not a non-negative integer.
    #[error("malformed PLY header at line {line}: bad element count `{count}`")]
    BadElementCount {
        /// 1-based line number.
        line: usize,
        /// The count as written.
        count: String,
    },
    /// A property type that is not one of the PLY scalar types.
    #[error("malformed PLY header at line {line}: unsupported property type `{ty}`")]
    UnsupportedType {
        /// 1-based line number.
        line: usize,
        /// The type as written.
        ty: String,
    },
    /// No `vertex` element.
    #[error("malformed PLY header: no `vertex` element")]
    MissingVertexElement,
    /// The vertex element lacks one of x, y, z.
    #[error("malformed PLY header: vertex element has no `{0}` property")]
    MissingProperty(&'static str),
    /// The vertex element has a list property.
    #[error("malformed PLY header: list property `{0}` in the vertex element is unsupported")]
    ListInVertex(String),
    /// The body ends before all declared entries of an element were read.
    #[error("truncated PLY body: read {read} of {declared} declared `{element}` entries")]
    Truncated {
        /// The element being read (`vertex` for the points).
        element: String,
        /// Entries read completely.
        read: usize,
        /// Entries declared in the header.
        declared: usize,
    },
    /// A field that is not a number.
    #[error("malformed number `{text}` at line {line}")]
    BadNumber {
        /// 1-based line number.
        line: usize,
        /// The field (possibly shortened).
        text: String,
    },
    /// More points than the reader was allowed (counted before they are stored).
    #[error("more than {limit} points (the largest cloud the tool reads)")]
    TooManyPoints {
        /// The limit.
        limit: usize,
    },
    /// A line longer than [`MAX_LINE_BYTES`] (a file without line ends?).
    #[error("line {line} is longer than {limit} bytes (is this a point-cloud file?)")]
    LineTooLong {
        /// 1-based line number.
        line: usize,
        /// The limit.
        limit: usize,
    },
    /// The file could not be read to its end.
    #[error("read error: {0}")]
    Read(String),
    /// A PCD header line that is not understood.
    #[error("malformed PCD header at line {line}: `{text}`")]
    PcdBadHeaderLine {
        /// 1-based line number.
        line: usize,
        /// The line (possibly shortened).
        text: String,
    },
    /// A PCD header value that is not a non-negative integer.
    #[error("malformed PCD header at line {line}: bad {key} value `{text}`")]
    PcdBadValue {
        /// 1-based line number.
        line: usize,
        /// The header key.
        key: &'static str,
        /// The value as written.
        text: String,
    },
    /// A PCD header without a line it needs.
    #[error("malformed PCD header: missing `{0}` line")]
    PcdMissingLine(&'static str),
    /// `SIZE`, `TYPE` or `COUNT` with a different number of entries than `FIELDS`.
    #[error("malformed PCD header at line {line}: {key} has {found} entries, FIELDS has {fields}")]
    PcdLengthMismatch {
        /// 1-based line number.
        line: usize,
        /// The header key.
        key: &'static str,
        /// Its entries.
        found: usize,
        /// Entries of `FIELDS`.
        fields: usize,
    },
    /// A PCD field whose `TYPE` and `SIZE` do not name a type.
    #[error("malformed PCD header: field `{field}` has TYPE {ty} SIZE {size} (F takes 4 or 8, I and U 1, 2, 4 or 8)")]
    PcdFieldType {
        /// The field (possibly shortened).
        field: String,
        /// The type as written (possibly shortened).
        ty: String,
        /// The size.
        size: usize,
    },
    /// `FIELDS` lacks one of x, y, z.
    #[error("malformed PCD header: FIELDS has no `{0}`")]
    PcdMissingField(&'static str),
    /// x, y or z is not a single float.
    #[error("PCD field `{axis}` is TYPE {ty} SIZE {size} COUNT {count}: coordinates must be one float (TYPE F, SIZE 4 or 8, COUNT 1)")]
    PcdAxisType {
        /// The coordinate.
        axis: &'static str,
        /// Its type letter.
        ty: char,
        /// Its size.
        size: usize,
        /// Its count.
        count: usize,
    },
    /// `POINTS` is not `WIDTH` × `HEIGHT`.
    #[error(
        "malformed PCD header: POINTS {} is not WIDTH {width} x HEIGHT {height}",
        .points.map_or("(absent)".to_string(), |p| p.to_string())
    )]
    PcdPointCount {
        /// `POINTS`, if given.
        points: Option<usize>,
        /// `WIDTH`.
        width: usize,
        /// `HEIGHT`.
        height: usize,
    },
    /// A `DATA` other than ascii, binary and binary_compressed.
    #[error("unsupported PCD DATA `{0}` (only ascii, binary and binary_compressed are supported)")]
    PcdUnsupportedData(String),
    /// The body ends before all declared points were read.
    #[error("truncated PCD body: read {read} of {declared} declared points")]
    PcdTruncated {
        /// Points read completely.
        read: usize,
        /// Points declared in the header.
        declared: usize,
    },
    /// A `binary_compressed` body that cannot be decompressed to the declared points.
    #[error("corrupt PCD binary_compressed body: {0}")]
    PcdCompressed(String),
    /// A size in a PCD file beyond what the reader takes.
    #[error("PCD {what} of {bytes} bytes is more than the limit of {limit}")]
    PcdTooLarge {
        /// What is too large.
        what: &'static str,
        /// Its size as the file gives it.
        bytes: u128,
        /// The limit.
        limit: usize,
    },
    /// A line with too few fields.
    #[error("too few columns at line {line}: found {found}, need at least {needed}")]
    TooFewColumns {
        /// 1-based line number.
        line: usize,
        /// Fields on the line.
        found: usize,
        /// Fields needed.
        needed: usize,
    },
}

/// Why a point-cloud file could not be read or written. Messages are one line
/// and start with (or contain) the file name.
#[derive(Debug, Error)]
pub enum IoError {
    /// The file could not be opened or read.
    #[error("cannot read {file}: {error}")]
    Read {
        /// The file.
        file: String,
        /// The OS error (in the message, not a separate cause, so it is printed once).
        error: std::io::Error,
    },
    /// The file could not be created or written.
    #[error("cannot write {file}: {error}")]
    Write {
        /// The file.
        file: String,
        /// The OS error (in the message only).
        error: std::io::Error,
    },
    /// A point with a coordinate beyond the `f32` range that PCD files are written in.
    #[error(
        "cannot write {file}: point {index} has a coordinate beyond a PCD float's range (3.4e38); write PLY instead"
    )]
    PcdRange {
        /// The file.
        file: String,
        /// The point's index.
        index: usize,
    },
    /// The extension does not name a known format.
    #[error("{file}: unknown point-cloud format {ext} (expected .ply, .pcd, .xyz, .txt, .pts or .csv)")]
    UnknownFormat {
        /// The file.
        file: String,
        /// The extension as written (or `(no extension)`).
        ext: String,
    },
    /// The contents are malformed.
    #[error("{file}: {problem}")]
    Parse {
        /// The file.
        file: String,
        /// What is wrong.
        problem: ParseError,
    },
    /// The points were read but do not form a valid cloud (empty, NaN, ...).
    #[error("{file}: {problem}")]
    Cloud {
        /// The file.
        file: String,
        /// The validation error (in the message only).
        problem: CloudError,
    },
}

/// The format for a path's extension (case-insensitive): `.ply` gives
/// [`Format::PlyBinary`] and `.pcd` [`Format::PcdBinary`] (readers detect the flavour
/// from the header), `.xyz`, `.txt` and `.pts` give [`Format::Xyz`], `.csv` gives [`Format::Csv`].
pub fn format_from_path(path: &Path) -> Result<Format, IoError> {
    let ext = path.extension().map(|e| e.to_string_lossy().to_lowercase());
    match ext.as_deref() {
        Some("ply") => Ok(Format::PlyBinary),
        Some("pcd") => Ok(Format::PcdBinary),
        Some("xyz" | "txt" | "pts") => Ok(Format::Xyz),
        Some("csv") => Ok(Format::Csv),
        other => Err(IoError::UnknownFormat {
            file: path.display().to_string(),
            ext: other.map_or("(no extension)".into(), |e| format!(".{e}")),
        }),
    }
}

/// Read a point-cloud file (format from its extension) and validate it as a
/// [`Cloud`] called `name`.
pub fn read_cloud(path: &Path, name: &str) -> Result<Cloud, IoError> {
    let file = path.display().to_string();
    let format = format_from_path(path)?;
    let f = std::fs::File::open(path).map_err(|error| IoError::Read { file: file.clone(), error })?;
    let reader = std::io::BufReader::with_capacity(1 << 16, f);
    let points = read_points(reader, format, crate::cloud::MAX_CLOUD_POINTS)
        .map_err(|problem| IoError::Parse { file: file.clone(), problem })?;
    Cloud::new(name, points).map_err(|problem| IoError::Cloud { file, problem })
}

/// Write `points` to `path` in `format`, replacing any existing file. Points
/// are written as given (no validation).
pub fn write_cloud(path: &Path, points: &[Point3<f64>], format: Format) -> Result<(), IoError> {
    if matches!(format, Format::PcdAscii | Format::PcdBinary) {
        if let Some(index) = pcd::f32_range(points) {
            return Err(IoError::PcdRange { file: path.display().to_string(), index });
        }
    }
    std::fs::write(path, write_points_to_bytes(points, format))
        .map_err(|error| IoError::Write { file: path.display().to_string(), error })
}

/// Parse the points `reader` gives, at most `limit` of them (one more is
/// [`ParseError::TooManyPoints`], as is a PLY or PCD header declaring more). Both PLY
/// formats detect ascii or binary from the header, and both PCD formats read any of the
/// three PCD encodings; PCD points with a NaN coordinate (the invalid points of an
/// organised cloud) are skipped. The points are not validated (see [`Cloud::new`]).
pub fn read_points(reader: impl BufRead, format: Format, limit: usize) -> Result<Vec<Point3<f64>>, ParseError> {
    match format {
        Format::PlyAscii | Format::PlyBinary => ply::read(reader, limit),
        Format::PcdAscii | Format::PcdBinary => pcd::read(reader, limit),
        Format::Xyz => text::read_xyz(reader, limit),
        Format::Csv => text::read_csv(reader, limit),
    }
}

/// [`read_points`] of `bytes`, at most [`crate::cloud::MAX_CLOUD_POINTS`].
pub fn read_points_from_bytes(bytes: &[u8], format: Format) -> Result<Vec<Point3<f64>>, ParseError> {
    read_points(bytes, format, crate::cloud::MAX_CLOUD_POINTS)
}

/// Serialise `points` in `format`. Every format round-trips every f64 exactly (text
/// formats write the shortest exact decimal, binary ones `double`/`F 8`).
pub fn write_points_to_bytes(points: &[Point3<f64>], format: Format) -> Vec<u8> {
    match format {
        Format::PlyAscii => ply::write_ascii(points),
        Format::PlyBinary => ply::write_binary(points),
        Format::PcdAscii => pcd::write_ascii(points),
        Format::PcdBinary => pcd::write_binary(points),
        Format::Xyz => text::write_delimited(points, " ", None),
        Format::Csv => text::write_delimited(points, ",", Some("x,y,z")),
    }
}

/// Shortest text that parses back to exactly `v` (an `f64`, or an `f32` read as one):
/// plain decimals for moderate magnitudes, scientific notation for very large or small
/// ones.
fn fmt_float<T: Copy + Into<f64> + std::fmt::Display + std::fmt::LowerExp>(v: T) -> String {
    let a = v.into().abs();
    if a == 0.0 || (1e-5..1e16).contains(&a) || !v.into().is_finite() {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// Parse one numeric field, reporting `line` on failure.
fn parse_f64(field: &str, line: usize) -> Result<f64, ParseError> {
    field.parse::<f64>().map_err(|_| ParseError::BadNumber { line, text: shorten(field) })
}

/// At most 40 characters of `s`, for error messages.
fn shorten(s: &str) -> String {
    let mut out: String = s.chars().take(40).collect();
    if s.chars().nth(40).is_some() {
        out.push_str("...");
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Vec<Point3<f64>> {
        vec![
            Point3::new(0.1, -2.5, 3.0),
            Point3::new(1e-300, 1.7976931348623157e308, -0.0),
            Point3::new(std::f64::consts::PI, -1e-7, 123_456_789.123_456_79),
            Point3::new(5e-324, 1e16, 0.30000000000000004),
        ]
    }

    #[test]
    fn every_format_round_trips_exactly_through_files() {
        let dir = tempfile::tempdir().unwrap();
        for (format, file) in
            [(Format::PlyAscii, "a.ply"), (Format::PlyBinary, "b.ply"), (Format::Xyz, "c.xyz"), (Format::Csv, "d.csv")]
        {
            let path = dir.path().join(file);
            write_cloud(&path, &sample(), format).unwrap();
            // The parser alone: the extremes here are beyond what `Cloud` accepts.
            let points = read_points_from_bytes(&std::fs::read(&path).unwrap(), format).unwrap();
            assert_eq!(points, sample(), "{format:?}");
            for (a, b) in points.iter().zip(sample()) {
                for (x, y) in a.coords.iter().zip(b.coords.iter()) {
                    assert_eq!(x.to_bits(), y.to_bits(), "{format:?}");
                }
            }
        }
    }

    #[test]
    fn pcd_round_trips_as_f32_through_files() {
        // PCD is written as F 4 (pcd.rs): exact for values an f32 holds, the nearest f32
        // otherwise, and a finite value beyond the f32 range is refused before writing.
        let dir = tempfile::tempdir().unwrap();
        let exact: Vec<Point3<f64>> =
            sample().iter().map(|p| p.map(|v| (v as f32).clamp(-1e38, 1e38) as f64)).collect();
        for (format, file) in [(Format::PcdAscii, "e.pcd"), (Format::PcdBinary, "f.pcd")] {
            let path = dir.path().join(file);
            write_cloud(&path, &exact, format).unwrap();
            let points = read_points_from_bytes(&std::fs::read(&path).unwrap(), format).unwrap();
            for (a, b) in points.iter().zip(&exact) {
                for (x, y) in a.coords.iter().zip(b.coords.iter()) {
                    assert_eq!(x.to_bits(), y.to_bits(), "{format:?}");
                }
            }
            assert_eq!(points.len(), exact.len());
            let e = write_cloud(&path, &sample(), format).unwrap_err().to_string();
            assert!(e.contains(file) && e.contains("point 1") && e.contains("PLY"), "{e}");
        }
    }

    #[test]
    fn fmt_float_round_trips() {
        for v in [0.0, -0.0, 1.0, 0.1, 1e-5, 9.99e-6, 1e16, 123.456, 5e-324, f64::MAX] {
            let s = fmt_float(v);
            assert_eq!(s.parse::<f64>().unwrap().to_bits(), v.to_bits(), "{s}");
        }
        assert_eq!(fmt_float(1.5), "1.5");
        assert_eq!(fmt_float(1e300), "1e300");
    }

    #[test]
    fn format_from_extension() {
        assert_eq!(format_from_path(Path::new("a.PLY")).unwrap(), Format::PlyBinary);
        assert_eq!(format_from_path(Path::new("scan.pcd")).unwrap(), Format::PcdBinary);
        assert_eq!(format_from_path(Path::new("scan.PCD")).unwrap(), Format::PcdBinary);
        assert_eq!(format_from_path(Path::new("a.txt")).unwrap(), Format::Xyz);
        assert_eq!(format_from_path(Path::new("a.pts")).unwrap(), Format::Xyz);
        assert_eq!(format_from_path(Path::new("d/a.Csv")).unwrap(), Format::Csv);
        let e = format_from_path(Path::new("scan.obj")).unwrap_err().to_string();
        assert!(e.contains("scan.obj") && e.contains("unknown") && e.contains(".obj"), "{e}");
        let e = format_from_path(Path::new("scan")).unwrap_err().to_string();
        assert!(e.contains("no extension"), "{e}");
    }

    #[test]
    fn missing_file_names_file_and_os_error() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("absent.xyz");
        let e = read_cloud(&path, "scan").unwrap_err();
        assert!(matches!(e, IoError::Read { .. }));
        let msg = e.to_string();
        assert!(msg.contains("absent.xyz") && msg.contains("cannot read"), "{msg}");
        assert!(msg.to_lowercase().contains("no such file"), "{msg}");
    }

    #[test]
    fn unwritable_path_is_a_write_error() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("no_dir").join("out.csv");
        let e = write_cloud(&path, &sample(), Format::Csv).unwrap_err().to_string();
        assert!(e.contains("cannot write") && e.contains("out.csv"), "{e}");
    }

    #[test]
    fn invalid_clouds_map_cloud_errors() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("nan.xyz");
        std::fs::write(&path, "1 2 3\n4 NaN 6\n").unwrap();
        let e = read_cloud(&path, "scan").unwrap_err();
        assert!(matches!(e, IoError::Cloud { .. }));
        let msg = e.to_string();
        assert!(msg.contains("nan.xyz") && msg.contains("non-finite"), "{msg}");

        let path = dir.path().join("inf.csv");
        std::fs::write(&path, "x,y,z\n1,2,inf\n").unwrap();
        let msg = read_cloud(&path, "scan").unwrap_err().to_string();
        assert!(msg.contains("non-finite"), "{msg}");

        let path = dir.path().join("empty.ply");
        write_cloud(&path, &[], Format::PlyAscii).unwrap();
        let msg = read_cloud(&path, "scan").unwrap_err().to_string();
        assert!(msg.contains("empty.ply") && msg.contains("empty"), "{msg}");
    }

    #[test]
    fn parse_errors_name_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bad.xyz");
        std::fs::write(&path, "1 2 3\n1 2 x3\n").unwrap();
        let msg = read_cloud(&path, "scan").unwrap_err().to_string();
        assert!(msg.contains("bad.xyz") && msg.contains("line 2") && msg.contains("x3"), "{msg}");
        assert!(!msg.contains('\n'));
    }
}
