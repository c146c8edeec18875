//! PCD files (the Point Cloud Library's format, v0.7, and the older headers PCL reads):
//! `DATA ascii`, `binary` and `binary_compressed` are read, ascii and binary are written.
//!
//! The header's `FIELDS` may hold any fields besides `x y z` (`rgb`, `intensity`,
//! normals, `_` padding); `SIZE`, `TYPE` and `COUNT` (one entry per field, defaults
//! 4, `F` and 1 as PCL takes them when a line is absent) give each field's bytes, and
//! `x`, `y`, `z` must be single floats (`F` 4 or 8). `WIDTH` × `HEIGHT` must equal
//! `POINTS`. Points whose x, y or z is NaN (what PCL writes for the invalid points of
//! an organised cloud) are skipped, as `pcl::removeNaNFromPointCloud` would; any other
//! value, infinite ones included, is kept for the cloud validation to judge.
//! `binary_compressed` bodies are LZF-compressed and field-major (every point's `x`,
//! then every `y`, ...): both sizes come from the file and are checked against the
//! header and [`MAX_BODY_BYTES`] before anything is read or allocated for them.
//! Points are written as `SIZE 8` `TYPE F` x y z, so the round trip is exact.

use std::io::{BufRead, Read};

use nalgebra::Point3;

use super::lines::{read_error, Lines};
use super::{fmt_f64, shorten, ParseError};

/// The largest `binary_compressed` block (compressed or not) read: 512 MiB, room for
/// [`crate::cloud::MAX_POINTS`] points of 53 bytes.
pub const MAX_BODY_BYTES: usize = 1 << 29;

/// The largest point record (the sum of `SIZE` × `COUNT`): PCL's biggest descriptors
/// are a few kilobytes.
pub const MAX_RECORD_BYTES: usize = 1 << 16;

/// A field's type: `TYPE` and `SIZE` together.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    I64,
    U64,
    F32,
    F64,
}

impl Scalar {
    /// The type for a `TYPE` letter and a `SIZE`.
    fn parse(ty: &str, size: usize) -> Option<Self> {
        Some(match (ty, size) {
            ("I", 1) => Scalar::I8,
            ("U", 1) => Scalar::U8,
            ("I", 2) => Scalar::I16,
            ("U", 2) => Scalar::U16,
            ("I", 4) => Scalar::I32,
            ("U", 4) => Scalar::U32,
            ("I", 8) => Scalar::I64,
            ("U", 8) => Scalar::U64,
            ("F", 4) => Scalar::F32,
            ("F", 8) => Scalar::F64,
            _ => return None,
        })
    }

    /// The `TYPE` letter.
    fn letter(self) -> char {
        match self {
            Scalar::I8 | Scalar::I16 | Scalar::I32 | Scalar::I64 => 'I',
            Scalar::U8 | Scalar::U16 | Scalar::U32 | Scalar::U64 => 'U',
            Scalar::F32 | Scalar::F64 => 'F',
        }
    }

    /// Bytes of one value.
    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::I64 | Scalar::U64 | Scalar::F64 => 8,
        }
    }

    /// The little-endian float at the start of `b` (only the float types are read as
    /// coordinates), if `b` is long enough.
    fn read_float(self, b: &[u8]) -> Option<f64> {
        match self {
            Scalar::F32 => Some(f32::from_le_bytes(b.get(..4)?.try_into().ok()?).into()),
            Scalar::F64 => Some(f64::from_le_bytes(b.get(..8)?.try_into().ok()?)),
            _ => None,
        }
    }

    /// An ascii coordinate of this type (F 4 is read as a float, as PCL reads it).
    fn parse_float(self, text: &str, line: usize) -> Result<f64, ParseError> {
        let bad = || ParseError::BadNumber { line, text: shorten(text) };
        match self {
            Scalar::F32 => text.parse::<f32>().map(f64::from).map_err(|_| bad()),
            _ => text.parse::<f64>().map_err(|_| bad()),
        }
    }
}

/// One entry of `FIELDS` with its type and count.
#[derive(Clone, Debug, PartialEq)]
struct Field {
    name: String,
    scalar: Scalar,
    count: usize,
}

impl Field {
    /// Bytes of this field in one point.
    fn bytes(&self) -> usize {
        self.scalar.size().saturating_mul(self.count)
    }
}

/// The body's encoding.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Data {
    Ascii,
    Binary,
    Compressed,
}

/// Where one coordinate is in a point: its field's index, its byte offset in the record,
/// its value index on an ascii line, and its type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Axis {
    field: usize,
    offset: usize,
    column: usize,
    scalar: Scalar,
}

/// A parsed and checked header.
#[derive(Debug)]
struct Header {
    fields: Vec<Field>,
    /// Bytes of one point (at most [`MAX_RECORD_BYTES`]).
    record: usize,
    /// Values on one ascii line (the sum of the counts).
    columns: usize,
    axes: [Axis; 3],
    points: usize,
    data: Data,
}

/// Read the x y z of a PCD file of any of the three encodings, at most `limit` points
/// (a header declaring more is refused before the body is read); NaN points are skipped.
pub(super) fn read(reader: impl BufRead, limit: usize) -> Result<Vec<Point3<f64>>, ParseError> {
    let mut lines = Lines::new(reader);
    let header = parse_header(&mut lines)?;
    if header.points > limit {
        return Err(ParseError::TooManyPoints { limit });
    }
    if header.points == 0 {
        return Ok(Vec::new());
    }
    match header.data {
        Data::Ascii => read_ascii(lines, &header),
        Data::Binary => read_binary(lines.into_inner(), &header),
        Data::Compressed => read_compressed(lines.into_inner(), &header),
    }
}

/// A header line's values (after the key), with the line's number.
type Values = Option<(usize, Vec<String>)>;

/// Parse the header up to and including its `DATA` line; `lines` stands just after it.
fn parse_header<R: BufRead>(lines: &mut Lines<R>) -> Result<Header, ParseError> {
    let (mut fields, mut sizes, mut types, mut counts): (Values, Values, Values, Values) = (None, None, None, None);
    let (mut width, mut height, mut points) = (None, None, None);
    while let Some((line_no, line)) = lines.next_line()? {
        let text = line.trim();
        if text.is_empty() || text.starts_with('#') {
            continue;
        }
        let bad_line = || ParseError::PcdBadHeaderLine { line: line_no, text: shorten(text) };
        let tokens: Vec<&str> = text.split_whitespace().collect();
        let values = |rest: &[&str]| Some((line_no, rest.iter().map(|s| s.to_string()).collect()));
        let number = |key: &'static str, text: &str| {
            text.parse::<usize>().map_err(|_| ParseError::PcdBadValue { line: line_no, key, text: shorten(text) })
        };
        match tokens.as_slice() {
            ["VERSION", ..] => {}
            ["FIELDS" | "COLUMNS", rest @ ..] if !rest.is_empty() => fields = values(rest),
            ["SIZE", rest @ ..] => sizes = values(rest),
            ["TYPE", rest @ ..] => types = values(rest),
            ["COUNT", rest @ ..] => counts = values(rest),
            ["WIDTH", n] => width = Some(number("WIDTH", n)?),
            ["HEIGHT", n] => height = Some(number("HEIGHT", n)?),
            ["POINTS", n] => points = Some(number("POINTS", n)?),
            ["VIEWPOINT", rest @ ..] if rest.len() == 7 && rest.iter().all(|v| v.parse::<f64>().is_ok()) => {}
            ["DATA", kind] => {
                let data = match *kind {
                    "ascii" => Data::Ascii,
                    "binary" => Data::Binary,
                    "binary_compressed" => Data::Compressed,
                    other => return Err(ParseError::PcdUnsupportedData(shorten(other))),
                };
                let (_, names) = fields.ok_or(ParseError::PcdMissingLine("FIELDS"))?;
                let fields = build_fields(names, sizes, types, counts)?;
                let points = point_count(width, height, points)?;
                return layout(fields, points, data);
            }
            _ => return Err(bad_line()),
        }
    }
    Err(ParseError::PcdMissingLine("DATA"))
}

/// The fields from `FIELDS` and the optional `SIZE`, `TYPE` and `COUNT` lines, each of
/// which must have one entry per field.
fn build_fields(names: Vec<String>, sizes: Values, types: Values, counts: Values) -> Result<Vec<Field>, ParseError> {
    let n = names.len();
    let entries = |key: &'static str, v: Values| -> Result<Option<(usize, Vec<String>)>, ParseError> {
        match v {
            Some((line, vals)) if vals.len() != n => {
                Err(ParseError::PcdLengthMismatch { line, key, found: vals.len(), fields: n })
            }
            other => Ok(other),
        }
    };
    let numbers = |key: &'static str, v: Option<(usize, Vec<String>)>| -> Result<Option<Vec<usize>>, ParseError> {
        v.map(|(line, vals)| {
            vals.iter()
                .map(|t| t.parse::<usize>().map_err(|_| ParseError::PcdBadValue { line, key, text: shorten(t) }))
                .collect()
        })
        .transpose()
    };
    let sizes = numbers("SIZE", entries("SIZE", sizes)?)?;
    let types = entries("TYPE", types)?.map(|(_, t)| t);
    let counts = numbers("COUNT", entries("COUNT", counts)?)?;
    names
        .into_iter()
        .enumerate()
        .map(|(i, name)| {
            let size = sizes.as_ref().and_then(|s| s.get(i).copied()).unwrap_or(4);
            let ty = types.as_ref().and_then(|t| t.get(i).map(String::as_str)).unwrap_or("F");
            let count = counts.as_ref().and_then(|c| c.get(i).copied()).unwrap_or(1);
            let scalar = Scalar::parse(ty, size).ok_or_else(|| ParseError::PcdFieldType {
                field: shorten(&name),
                ty: shorten(ty),
                size,
            })?;
            Ok(Field { name, scalar, count })
        })
        .collect()
}

/// `POINTS`, checked against `WIDTH` × `HEIGHT` (`WIDTH` defaults to `POINTS` and
/// `HEIGHT` to 1, as in PCL's older headers; one of `POINTS` and `WIDTH` is needed).
fn point_count(width: Option<usize>, height: Option<usize>, points: Option<usize>) -> Result<usize, ParseError> {
    let height = height.unwrap_or(1);
    let width = match (width, points) {
        (Some(w), _) => w,
        (None, Some(p)) if height == 1 => p,
        (None, _) => return Err(ParseError::PcdMissingLine("WIDTH")),
    };
    let area = width.checked_mul(height);
    let points = match points {
        Some(p) => p,
        None => area.ok_or(ParseError::PcdPointCount { points: None, width, height })?,
    };
    if area != Some(points) {
        return Err(ParseError::PcdPointCount { points: Some(points), width, height });
    }
    Ok(points)
}

/// Find x, y and z, check them and the record size.
fn layout(fields: Vec<Field>, points: usize, data: Data) -> Result<Header, ParseError> {
    let record = fields.iter().try_fold(0usize, |acc, f| acc.checked_add(f.bytes()));
    let record = record.filter(|&r| r <= MAX_RECORD_BYTES).ok_or_else(|| ParseError::PcdTooLarge {
        what: "point record",
        bytes: fields.iter().fold(0u128, |acc, f| acc + f.scalar.size() as u128 * f.count as u128),
        limit: MAX_RECORD_BYTES,
    })?;
    // Within the record limit, so neither sum overflows.
    let columns = fields.iter().map(|f| f.count).sum();
    let axis = |name: &'static str| -> Result<Axis, ParseError> {
        let i = fields.iter().position(|f| f.name == name).ok_or(ParseError::PcdMissingField(name))?;
        let (field, before) =
            fields.get(..=i).and_then(<[Field]>::split_last).ok_or(ParseError::PcdMissingField(name))?;
        if !matches!(field.scalar, Scalar::F32 | Scalar::F64) || field.count != 1 {
            let (ty, size, count) = (field.scalar.letter(), field.scalar.size(), field.count);
            return Err(ParseError::PcdAxisType { axis: name, ty, size, count });
        }
        Ok(Axis {
            field: i,
            offset: before.iter().map(Field::bytes).sum(),
            column: before.iter().map(|f| f.count).sum(),
            scalar: field.scalar,
        })
    };
    let axes = [axis("x")?, axis("y")?, axis("z")?];
    Ok(Header { fields, record, columns, axes, points, data })
}

/// Keep a point unless one of its coordinates is NaN (an invalid point of an organised
/// cloud).
fn push_valid(points: &mut Vec<Point3<f64>>, c: [f64; 3]) {
    if !c.iter().any(|v| v.is_nan()) {
        points.push(Point3::from(c));
    }
}

/// Room reserved for points up front: the declared count, but not more than this.
const RESERVE: usize = 1 << 16;

/// Ascii body: one point a non-blank line, numbered on from the header's lines.
fn read_ascii<R: BufRead>(mut lines: Lines<R>, h: &Header) -> Result<Vec<Point3<f64>>, ParseError> {
    let mut points = Vec::with_capacity(h.points.min(RESERVE));
    for read in 0..h.points {
        let (line, text) = lines.next_nonblank()?.ok_or(ParseError::PcdTruncated { read, declared: h.points })?;
        let values: Vec<&str> = text.split_whitespace().collect();
        if values.len() < h.columns {
            return Err(ParseError::TooFewColumns { line, found: values.len(), needed: h.columns });
        }
        let mut c = [0.0; 3];
        for (slot, a) in c.iter_mut().zip(h.axes.iter()) {
            *slot = a.scalar.parse_float(values.get(a.column).copied().unwrap_or_default(), line)?;
        }
        push_valid(&mut points, c);
    }
    Ok(points)
}

/// Fill `buf` from `reader`: `Ok(false)` if the body ends first.
fn fill(reader: &mut impl Read, buf: &mut [u8]) -> Result<bool, ParseError> {
    match reader.read_exact(buf) {
        Ok(()) => Ok(true),
        Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => Ok(false),
        Err(e) => Err(read_error(e)),
    }
}

/// Binary body: point records one after another, read one at a time.
fn read_binary(mut reader: impl BufRead, h: &Header) -> Result<Vec<Point3<f64>>, ParseError> {
    let mut points = Vec::with_capacity(h.points.min(RESERVE));
    let mut record = vec![0u8; h.record];
    for read in 0..h.points {
        let truncated = || ParseError::PcdTruncated { read, declared: h.points };
        if !fill(&mut reader, &mut record)? {
            return Err(truncated());
        }
        let mut c = [0.0; 3];
        for (slot, a) in c.iter_mut().zip(h.axes.iter()) {
            *slot = record.get(a.offset..).and_then(|b| a.scalar.read_float(b)).ok_or_else(truncated)?;
        }
        push_valid(&mut points, c);
    }
    Ok(points)
}

/// Binary compressed body: the compressed and uncompressed sizes (u32 little endian),
/// then an LZF block that decompresses to the fields one after another, each for all
/// points.
fn read_compressed(mut reader: impl BufRead, h: &Header) -> Result<Vec<Point3<f64>>, ParseError> {
    let corrupt = |s: String| ParseError::PcdCompressed(s);
    let mut sizes = [0u8; 8];
    if !fill(&mut reader, &mut sizes)? {
        return Err(corrupt("the body ends before its two sizes".into()));
    }
    let [c0, c1, c2, c3, u0, u1, u2, u3] = sizes;
    let compressed = u32::from_le_bytes([c0, c1, c2, c3]) as usize;
    let uncompressed = u32::from_le_bytes([u0, u1, u2, u3]) as usize;
    for (what, bytes) in [("compressed block", compressed), ("uncompressed block", uncompressed)] {
        if bytes > MAX_BODY_BYTES {
            return Err(ParseError::PcdTooLarge { what, bytes: bytes as u128, limit: MAX_BODY_BYTES });
        }
    }
    let need = h.points.checked_mul(h.record);
    if need != Some(uncompressed) {
        return Err(corrupt(format!(
            "the file says {uncompressed} uncompressed bytes, but {} points of {} bytes are {}",
            h.points,
            h.record,
            need.map_or("more than fit in memory".into(), |n| n.to_string())
        )));
    }
    // Grows with what the file holds, never to the declared size up front.
    let mut block = Vec::new();
    (&mut reader).take(compressed as u64).read_to_end(&mut block).map_err(read_error)?;
    if block.len() < compressed {
        return Err(corrupt(format!("truncated: {} of {compressed} compressed bytes", block.len())));
    }
    let data = lzf_decompress(&block, uncompressed).map_err(corrupt)?;
    drop(block);
    // Each field's block starts after the blocks of the fields before it (all within
    // `uncompressed`, so no sum overflows).
    let start = |field: usize| -> usize {
        h.fields.iter().take(field).map(|f| f.bytes().saturating_mul(h.points)).fold(0, usize::saturating_add)
    };
    let starts = h.axes.map(|a| start(a.field));
    let mut points = Vec::with_capacity(h.points.min(RESERVE));
    for k in 0..h.points {
        let mut c = [0.0; 3];
        for ((slot, a), s) in c.iter_mut().zip(h.axes.iter()).zip(starts) {
            let at = s.saturating_add(k.saturating_mul(a.scalar.size()));
            *slot = data.get(at..).and_then(|b| a.scalar.read_float(b)).ok_or_else(|| {
                corrupt(format!("point {k}'s coordinate lies beyond the {} decompressed bytes", data.len()))
            })?;
        }
        push_valid(&mut points, c);
    }
    Ok(points)
}

/// Decompress an LZF block (liblzf's format, as PCL writes it) that must give exactly
/// `len` bytes. Every read and every back reference is checked; the output never grows
/// past `len`.
fn lzf_decompress(input: &[u8], len: usize) -> Result<Vec<u8>, String> {
    // An LZF token of 3 bytes gives at most 264: reserve no more than the input can give.
    let mut out: Vec<u8> = Vec::with_capacity(len.min(input.len().saturating_mul(88)));
    let mut i = 0;
    let too_long =
        |at: usize| format!("the LZF stream gives more than the {len} bytes the file says (at input byte {at})");
    while let Some(&ctrl) = input.get(i) {
        let at = i;
        i += 1;
        if ctrl < 32 {
            let run = usize::from(ctrl) + 1;
            let literal = input.get(i..i.saturating_add(run)).ok_or_else(|| {
                format!("an LZF literal run of {run} bytes at input byte {at} passes the block's end")
            })?;
            if out.len() + run > len {
                return Err(too_long(at));
            }
            out.extend_from_slice(literal);
            i += run;
        } else {
            let end = || format!("an LZF back reference at input byte {at} passes the block's end");
            let mut n = usize::from(ctrl >> 5);
            if n == 7 {
                n += usize::from(*input.get(i).ok_or_else(end)?);
                i += 1;
            }
            let low = *input.get(i).ok_or_else(end)?;
            i += 1;
            let n = n + 2;
            let back = (usize::from(ctrl & 0x1f) << 8) + usize::from(low) + 1;
            let from = out.len().checked_sub(back).ok_or_else(|| {
                format!(
                    "an LZF back reference at input byte {at} reaches {back} bytes back from output byte {}",
                    out.len()
                )
            })?;
            if out.len() + n > len {
                return Err(too_long(at));
            }
            // Byte by byte: the copy may overlap what it writes.
            for k in from..from + n {
                let b = out.get(k).copied().ok_or_else(end)?;
                out.push(b);
            }
        }
    }
    if out.len() != len {
        return Err(format!("the LZF stream gives {} bytes, the file says {len}", out.len()));
    }
    Ok(out)
}

/// The header for `n` unorganised double-precision points with `DATA data`.
fn header(data: &str, n: usize) -> String {
    format!(
        "# .PCD v0.7 - Point Cloud Data file format (written by pficp)\nVERSION 0.7\nFIELDS x y z\n\
         SIZE 8 8 8\nTYPE F F F\nCOUNT 1 1 1\nWIDTH {n}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\nDATA {data}\n"
    )
}

/// An ascii PCD of `points`, exact to the last bit.
pub(super) fn write_ascii(points: &[Point3<f64>]) -> Vec<u8> {
    let mut out = header("ascii", points.len());
    for p in points {
        out.push_str(&format!("{} {} {}\n", fmt_f64(p.x), fmt_f64(p.y), fmt_f64(p.z)));
    }
    out.into_bytes()
}

/// A binary PCD of `points` as `F 8` x y z (little endian, as PCL writes on every
/// platform it runs on).
pub(super) fn write_binary(points: &[Point3<f64>]) -> Vec<u8> {
    let mut out = header("binary", points.len()).into_bytes();
    out.reserve(points.len() * 24);
    for p in points {
        for v in [p.x, p.y, p.z] {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    out
}
