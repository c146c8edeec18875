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
//! Points are written as `SIZE 4` `TYPE F` x y z, as PCL and Open3D write them, so that
//! their readers take the file (PCL's typed loaders and Open3D's legacy reader do not take
//! `F 8` coordinates, docs/io.md, "PCD files"): the round trip is exact for values an `f32`
//! holds and rounds others to the nearest `f32` ([`f32_range`] finds what does not fit).

use std::io::{BufRead, Read};

use nalgebra::Point3;

use super::lines::{read_error, Lines};
use super::{fmt_float, shorten, ParseError};

/// The largest `binary_compressed` block (compressed or not) read: 512 MiB, room for
/// [`crate::cloud::MAX_CLOUD_POINTS`] points of 53 bytes.
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
    /// The type for a `TYPE` letter (either case, as PCL takes it) and a `SIZE`.
    fn parse(ty: &str, size: usize) -> Option<Self> {
        Some(match (ty.to_ascii_uppercase().as_str(), size) {
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

/// The header for `n` unorganised points of `bytes`-byte floats with `DATA data`.
fn header(data: &str, n: usize, bytes: usize) -> String {
    format!(
        "# .PCD v0.7 - Point Cloud Data file format (written by pficp)\nVERSION 0.7\nFIELDS x y z\n\
         SIZE {bytes} {bytes} {bytes}\nTYPE F F F\nCOUNT 1 1 1\nWIDTH {n}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\n\
         POINTS {n}\nDATA {data}\n"
    )
}

/// The index of the first point with a finite coordinate beyond the `f32` range (it would
/// be written as an infinity), if any.
pub fn f32_range(points: &[Point3<f64>]) -> Option<usize> {
    points.iter().position(|p| p.iter().any(|v| v.is_finite() && (*v as f32).is_infinite()))
}

/// An ascii PCD of `points` as `F 4`: each coordinate the shortest text of its nearest
/// `f32`.
pub(super) fn write_ascii(points: &[Point3<f64>]) -> Vec<u8> {
    let mut out = header("ascii", points.len(), 4);
    for p in points {
        let [x, y, z] = [p.x, p.y, p.z].map(|v| fmt_float(v as f32));
        out.push_str(&format!("{x} {y} {z}\n"));
    }
    out.into_bytes()
}

/// A binary PCD of `points` as `F 4` x y z (little endian, as PCL writes on every
/// platform it runs on).
pub(super) fn write_binary(points: &[Point3<f64>]) -> Vec<u8> {
    let mut out = header("binary", points.len(), 4).into_bytes();
    out.reserve(points.len() * 12);
    for p in points {
        for v in [p.x, p.y, p.z] {
            out.extend_from_slice(&(v as f32).to_le_bytes());
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn p(x: f64, y: f64, z: f64) -> Point3<f64> {
        Point3::new(x, y, z)
    }

    fn read_all(bytes: &[u8]) -> Result<Vec<Point3<f64>>, ParseError> {
        read(bytes, usize::MAX)
    }

    fn err(bytes: &[u8]) -> String {
        let e = read_all(bytes).unwrap_err().to_string();
        assert!(!e.contains('\n'), "{e}");
        e
    }

    /// A greedy LZF encoder (longest match within liblzf's 8 KiB window, literal runs of
    /// at most 32), to make binary_compressed bodies with back references.
    fn lzf_compress(data: &[u8]) -> Vec<u8> {
        fn flush(out: &mut Vec<u8>, lit: &mut Vec<u8>) {
            for c in lit.chunks(32) {
                out.push(c.len() as u8 - 1);
                out.extend_from_slice(c);
            }
            lit.clear();
        }
        let (mut out, mut lit, mut i) = (Vec::new(), Vec::new(), 0);
        while i < data.len() {
            let mut best = (0, 0);
            for back in 1..=i.min(8192) {
                let from = i - back;
                let mut n = 0;
                while n < 264 && i + n < data.len() && data[from + n] == data[i + n] {
                    n += 1;
                }
                if n > best.0 {
                    best = (n, back);
                }
            }
            let (n, back) = best;
            if n < 3 {
                lit.push(data[i]);
                i += 1;
                continue;
            }
            flush(&mut out, &mut lit);
            let (len, off) = (n - 2, back - 1);
            out.push(((len.min(7) << 5) | (off >> 8)) as u8);
            if len >= 7 {
                out.push((len - 7) as u8);
            }
            out.push((off & 0xff) as u8);
            i += n;
        }
        flush(&mut out, &mut lit);
        out
    }

    /// A binary_compressed file: `header` (up to `DATA`), the sizes and the block.
    fn compressed_file(header: &str, field_major: &[u8]) -> Vec<u8> {
        let block = lzf_compress(field_major);
        let mut b = format!("{header}DATA binary_compressed\n").into_bytes();
        b.extend_from_slice(&(block.len() as u32).to_le_bytes());
        b.extend_from_slice(&(field_major.len() as u32).to_le_bytes());
        b.extend_from_slice(&block);
        b
    }

    /// `points` as our writer's fields, field-major (every x, then every y, then z).
    fn field_major(points: &[Point3<f64>]) -> Vec<u8> {
        (0..3).flat_map(|a| points.iter().flat_map(move |q| q[a].to_le_bytes())).collect()
    }

    /// Our binary header without its `DATA` line.
    fn xyz_header(n: usize) -> String {
        let h = header("binary", n, 8);
        h.strip_suffix("DATA binary\n").unwrap().to_string()
    }

    const ASCII: &str = "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n\
        WIDTH 2\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n";

    #[test]
    fn writers_round_trip_exactly_in_every_encoding() {
        // Values an f32 holds come back exactly; F 8 (read, not written) keeps f64 extremes.
        let f32s = |v: [f32; 3]| p(v[0] as f64, v[1] as f64, v[2] as f64);
        let pts =
            vec![f32s([0.1, -0.0, f32::from_bits(1)]), f32s([f32::MAX, 1e-7, 2.0 / 3.0]), f32s([-1e30, 3.5, 1e16])];
        assert_eq!(read_all(&write_ascii(&pts)).unwrap(), pts);
        let bin = write_binary(&pts);
        assert_eq!(read_all(&bin).unwrap(), pts);
        let s = String::from_utf8_lossy(&bin);
        assert!(s.contains("\nSIZE 4 4 4\nTYPE F F F\n") && s.contains("\nDATA binary\n"), "{s}");
        let wide = vec![p(0.1, -0.0, 5e-324), p(f64::MAX, 1e-7, 2.0 / 3.0), p(-1e300, 3.5, 1e16)];
        let c = compressed_file(&xyz_header(wide.len()), &field_major(&wide));
        assert_eq!(read_all(&c).unwrap(), wide);
        // An f64 value comes back as its nearest f32; one beyond the f32 range is found.
        let back = read_all(&write_binary(&[p(0.1, 1.0 / 3.0, 1e-3)])).unwrap();
        assert_eq!(back, vec![p(0.1f32 as f64, (1.0f32 / 3.0) as f64, 1e-3f32 as f64)]);
        assert_eq!(f32_range(&wide), Some(1));
        assert_eq!(f32_range(&pts), None);
        for w in [write_ascii(&[]), write_binary(&[])] {
            assert!(read_all(&w).unwrap().is_empty());
        }
    }

    #[test]
    fn ascii_honours_counts_types_and_old_headers() {
        // rgb as a float, a descriptor of COUNT 3 before y, F 4 coordinates rounded to f32.
        let text = "VERSION .7\nFIELDS x d y rgb z\nSIZE 4 2 8 4 4\nTYPE F U F F F\nCOUNT 1 3 1 1 1\n\
            WIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA ascii\n0.1 1 2 3 0.25 4.2e-5 -7\n\n1 0 0 0 2 0 3 extra\n";
        let pts = read_all(text.as_bytes()).unwrap();
        assert_eq!(pts, vec![p(f64::from(0.1f32), 0.25, -7.0), p(1.0, 2.0, 3.0)]);
        // PCL's v0.5 headers: COLUMNS, no SIZE/TYPE/COUNT (4, F, 1), no WIDTH/HEIGHT.
        let old = "# .PCD v.5\nVERSION .5\nCOLUMNS x y z i\nPOINTS 1\nDATA ascii\n1.5 2 3 9\n";
        assert_eq!(read_all(old.as_bytes()).unwrap(), vec![p(1.5, 2.0, 3.0)]);
        // WIDTH alone gives POINTS.
        let w = "FIELDS x y z\nTYPE f f f\nWIDTH 1\nDATA ascii\n1 2 3\n";
        assert_eq!(read_all(w.as_bytes()).unwrap(), vec![p(1.0, 2.0, 3.0)]);
    }

    #[test]
    fn binary_with_mixed_types_and_padding() {
        let mut b = b"VERSION 0.7\nFIELDS rgb _ z x y n\nSIZE 4 1 8 4 8 2\nTYPE U U F F F I\nCOUNT 1 3 1 1 1 2\n\
            WIDTH 2\nHEIGHT 1\nVIEWPOINT 1 2 3 1 0 0 0\nPOINTS 2\nDATA binary\n"
            .to_vec();
        for (x, y, z) in [(0.5f32, -1.25f64, 1e300f64), (3.0, 4.0, -5.0)] {
            b.extend_from_slice(&0xff00ffu32.to_le_bytes());
            b.extend_from_slice(&[7, 7, 7]);
            b.extend_from_slice(&z.to_le_bytes());
            b.extend_from_slice(&x.to_le_bytes());
            b.extend_from_slice(&y.to_le_bytes());
            b.extend_from_slice(&[1, 2, 3, 4]);
        }
        assert_eq!(read_all(&b).unwrap(), vec![p(0.5, -1.25, 1e300), p(3.0, 4.0, -5.0)]);
    }

    #[test]
    fn compressed_is_field_major_over_every_field() {
        // FIELDS i x y z: i (U 2) for both points, then x (F 4), then y and z (F 8).
        let mut data = vec![1, 0, 2, 0];
        data.extend([1.5f32, -2.0].iter().flat_map(|v| v.to_le_bytes()));
        data.extend([0.25f64, 8.0, 3.0, 3.0].iter().flat_map(|v| v.to_le_bytes()));
        let h = "FIELDS i x y z\nSIZE 2 4 8 8\nTYPE U F F F\nCOUNT 1 1 1 1\nWIDTH 2\nHEIGHT 1\nPOINTS 2\n";
        assert_eq!(read_all(&compressed_file(h, &data)).unwrap(), vec![p(1.5, 0.25, 3.0), p(-2.0, 8.0, 3.0)]);
    }

    #[test]
    fn lzf_decodes_literals_and_overlapping_back_references() {
        // "abc", then 7 bytes from 3 back (overlapping), then 10 from 1 back (long form).
        let stream = [2, b'a', b'b', b'c', 5 << 5, 2, 7 << 5, 1, 0];
        assert_eq!(lzf_decompress(&stream, 20).unwrap(), b"abcabcabcaaaaaaaaaaa");
        let data: Vec<u8> = (0..5000u32).map(|i| (i % 97 + i / 1000) as u8).collect();
        let packed = lzf_compress(&data);
        assert!(packed.len() < data.len() / 4);
        assert_eq!(lzf_decompress(&packed, data.len()).unwrap(), data);
        assert_eq!(lzf_decompress(&[], 0).unwrap(), Vec::<u8>::new());
    }

    #[test]
    fn corrupt_lzf_streams_are_errors() {
        let e = lzf_decompress(&[2, b'a'], 3).unwrap_err();
        assert!(e.contains("literal run of 3 bytes at input byte 0 passes the block's end"), "{e}");
        let e = lzf_decompress(&[0, b'a', 1 << 5, 1], 4).unwrap_err();
        assert!(e.contains("reaches 2 bytes back from output byte 1"), "{e}");
        let e = lzf_decompress(&[0, b'a', 7 << 5], 20).unwrap_err();
        assert!(e.contains("back reference at input byte 2 passes the block's end"), "{e}");
        let e = lzf_decompress(&[0, b'a', 1 << 5], 20).unwrap_err();
        assert!(e.contains("passes the block's end"), "{e}");
        let e = lzf_decompress(&[1, b'a', b'b'], 1).unwrap_err();
        assert!(e.contains("more than the 1 bytes"), "{e}");
        let e = lzf_decompress(&[0, b'a', 1 << 5, 0], 2).unwrap_err();
        assert!(e.contains("more than the 2 bytes"), "{e}");
        let e = lzf_decompress(&[1, b'a', b'b'], 5).unwrap_err();
        assert!(e.contains("gives 2 bytes, the file says 5"), "{e}");
    }

    #[test]
    fn nan_points_are_skipped_and_other_values_kept() {
        let pts =
            vec![p(1.0, 2.0, 3.0), p(f64::NAN, f64::NAN, f64::NAN), p(4.0, f64::NAN, 6.0), p(f64::INFINITY, 0.0, 0.0)];
        let kept = vec![p(1.0, 2.0, 3.0), p(f64::INFINITY, 0.0, 0.0)];
        assert_eq!(read_all(&write_ascii(&pts)).unwrap(), kept);
        assert_eq!(read_all(&write_binary(&pts)).unwrap(), kept);
        assert_eq!(read_all(&compressed_file(&xyz_header(4), &field_major(&pts))).unwrap(), kept);
        let organised = ASCII.replace("WIDTH 2\nHEIGHT 1", "WIDTH 1\nHEIGHT 2") + "nan nan nan\n1 2 3\n";
        assert_eq!(read_all(organised.as_bytes()).unwrap(), vec![p(1.0, 2.0, 3.0)]);
    }

    #[test]
    fn header_errors() {
        assert!(err(b"").contains("missing `DATA` line"));
        assert!(err(ASCII.replace("DATA ascii\n", "").as_bytes()).contains("missing `DATA` line"));
        assert!(err(b"ply\nformat ascii 1.0\n").contains("malformed PCD header at line 1: `ply`"));
        let e = err(ASCII.replace("FIELDS x y z\n", "").as_bytes());
        assert!(e.contains("missing `FIELDS` line"), "{e}");
        let e = err(ASCII.replace("FIELDS x y z", "FIELDS a y z").as_bytes());
        assert!(e.contains("FIELDS has no `x`"), "{e}");
        let e = err(ASCII.replace("FIELDS x y z", "FIELDS x y").as_bytes());
        assert!(e.contains("line 4: SIZE has 3 entries, FIELDS has 2"), "{e}");
        let e = err(ASCII.replace("TYPE F F F", "TYPE F F").as_bytes());
        assert!(e.contains("line 5: TYPE has 2 entries, FIELDS has 3"), "{e}");
        let e = err(ASCII.replace("COUNT 1 1 1", "COUNT 1 1 1 1").as_bytes());
        assert!(e.contains("line 6: COUNT has 4 entries, FIELDS has 3"), "{e}");
        let e = err(ASCII.replace("SIZE 4 4 4", "SIZE 4 four 4").as_bytes());
        assert!(e.contains("line 4: bad SIZE value `four`"), "{e}");
        let e = err(ASCII.replace("COUNT 1 1 1", "COUNT 1 -1 1").as_bytes());
        assert!(e.contains("bad COUNT value `-1`"), "{e}");
        let e = err(ASCII.replace("SIZE 4 4 4", "SIZE 4 2 4").as_bytes());
        assert!(e.contains("field `y` has TYPE F SIZE 2"), "{e}");
        let e = err(ASCII.replace("TYPE F F F", "TYPE F F Q").as_bytes());
        assert!(e.contains("field `z` has TYPE Q SIZE 4"), "{e}");
        let e = err(ASCII.replace("TYPE F F F", "TYPE U F F").as_bytes());
        assert!(e.contains("`x` is TYPE U SIZE 4 COUNT 1: coordinates must be one float"), "{e}");
        let e = err(ASCII.replace("COUNT 1 1 1", "COUNT 1 1 2").as_bytes());
        assert!(e.contains("`z` is TYPE F SIZE 4 COUNT 2"), "{e}");
        let e = err(ASCII.replace("POINTS 2", "POINTS 3").as_bytes());
        assert!(e.contains("POINTS 3 is not WIDTH 2 x HEIGHT 1"), "{e}");
        let e = err(ASCII.replace("HEIGHT 1", "HEIGHT 2").as_bytes());
        assert!(e.contains("POINTS 2 is not WIDTH 2 x HEIGHT 2"), "{e}");
        let e = err(ASCII.replace("WIDTH 2\n", "").replace("HEIGHT 1", "HEIGHT 2").as_bytes());
        assert!(e.contains("missing `WIDTH` line"), "{e}");
        let e = err(ASCII.replace("WIDTH 2", "WIDTH two").as_bytes());
        assert!(e.contains("line 7: bad WIDTH value `two`"), "{e}");
        let e = err(ASCII.replace("POINTS 2\n", "").replace("HEIGHT 1", &format!("HEIGHT {}", usize::MAX)).as_bytes());
        assert!(e.contains("POINTS (absent) is not WIDTH 2 x HEIGHT"), "{e}");
        let e = err(ASCII.replace("DATA ascii", "DATA binary_lz4").as_bytes());
        assert!(e.contains("unsupported PCD DATA `binary_lz4`"), "{e}");
        let e = err(ASCII.replace("VIEWPOINT 0 0 0 1 0 0 0", "VIEWPOINT 0 0 0").as_bytes());
        assert!(e.contains("line 9: `VIEWPOINT 0 0 0`"), "{e}");
        let e = err(ASCII.replace("VERSION 0.7", "MOOD 0.7").as_bytes());
        assert!(e.contains("malformed PCD header at line 2: `MOOD 0.7`"), "{e}");
    }

    #[test]
    fn body_errors() {
        let e = err(format!("{ASCII}1 2 3\n").as_bytes());
        assert!(e.contains("truncated PCD body: read 1 of 2 declared points"), "{e}");
        let e = err(format!("{ASCII}1 2 3\n4 5\n").as_bytes());
        assert!(e.contains("too few columns at line 13: found 2, need at least 3"), "{e}");
        let e = err(format!("{ASCII}1 2 3\n4 five 6\n").as_bytes());
        assert!(e.contains("malformed number `five` at line 13"), "{e}");
        let bin = write_binary(&[p(1.0, 2.0, 3.0); 3]);
        let e = err(&bin[..bin.len() - 15]); // 12 bytes a point: one and a bit missing
        assert!(e.contains("truncated PCD body: read 1 of 3"), "{e}");
        let pts = vec![p(1.0, 2.0, 3.0); 20];
        let c = compressed_file(&xyz_header(20), &field_major(&pts));
        let e = err(&c[..c.len() - 1]);
        assert!(e.contains("corrupt PCD binary_compressed body: truncated"), "{e}");
        let body = xyz_header(20).len() + "DATA binary_compressed\n".len(); // the sizes' offset
        let e = err(&c[..body + 5]);
        assert!(e.contains("the body ends before its two sizes"), "{e}");
        let mut bad = c.clone();
        bad[body + 8] = 0x3f; // the first token: a back reference 8 KiB before the start
        let e = err(&bad);
        assert!(e.contains("corrupt PCD binary_compressed body: an LZF back reference at input byte 0"), "{e}");
        let mut short = c.clone();
        short[body + 4] -= 8; // the uncompressed size one point short
        let e = err(&short);
        assert!(e.contains("says 472 uncompressed bytes, but 20 points of 24 bytes are 480"), "{e}");
    }

    #[test]
    fn absurd_sizes_are_refused_before_anything_is_allocated() {
        // Sizes of 4 GiB and just over the limit, compressed or not, with no body behind them.
        let h = format!("{}DATA binary_compressed\n", xyz_header(2));
        for (c, u, what) in [
            (u32::MAX, 48, "compressed block of 4294967295 bytes"),
            (10, u32::MAX, "uncompressed block of 4294967295 bytes"),
            (MAX_BODY_BYTES as u32 + 1, 48, "compressed block of 536870913 bytes"),
        ] {
            let mut b = h.clone().into_bytes();
            b.extend_from_slice(&c.to_le_bytes());
            b.extend_from_slice(&u.to_le_bytes());
            let e = err(&b);
            assert!(e.contains(what) && e.contains("more than the limit of 536870912"), "{e}");
        }
        // A compressed size the file does not hold: read as far as it goes, then refused.
        let mut b = h.into_bytes();
        b.extend_from_slice(&400_000_000u32.to_le_bytes());
        b.extend_from_slice(&48u32.to_le_bytes());
        b.extend_from_slice(&[0; 10]);
        assert!(err(&b).contains("truncated: 10 of 400000000 compressed bytes"));
        // A record of 10^12 bytes, POINTS of 2^64 - 1.
        let e = err(ASCII.replace("COUNT 1 1 1", "COUNT 1 1000000000000 1").as_bytes());
        assert!(e.contains("PCD point record of 4000000000008 bytes is more than the limit of 65536"), "{e}");
        let huge = usize::MAX.to_string();
        let e = err(ASCII
            .replace("WIDTH 2", &format!("WIDTH {huge}"))
            .replace("POINTS 2", &format!("POINTS {huge}"))
            .as_bytes());
        assert!(e.contains("truncated PCD body: read 0 of"), "{e}");
    }

    #[test]
    fn a_header_declaring_more_than_the_limit_is_refused_before_the_body() {
        for data in ["ascii", "binary", "binary_compressed"] {
            let h = ASCII.replace("WIDTH 2", "WIDTH 11").replace("POINTS 2", "POINTS 11").replace("ascii", data);
            assert_eq!(read(h.as_bytes(), 10), Err(ParseError::TooManyPoints { limit: 10 }));
        }
        assert_eq!(read(write_binary(&[p(1.0, 2.0, 3.0); 10]).as_slice(), 10).unwrap().len(), 10);
    }

    /// Any finite f64, both signs, including subnormals and zeros.
    fn finite() -> impl Strategy<Value = f64> {
        use proptest::num::f64::{NEGATIVE, NORMAL, POSITIVE, SUBNORMAL, ZERO};
        POSITIVE | NEGATIVE | NORMAL | SUBNORMAL | ZERO
    }

    proptest! {
        #[test]
        fn random_points_round_trip_in_every_encoding(
            xs in proptest::collection::vec(finite(), 0..60),
            ys in proptest::collection::vec(-1e6f64..1e6, 0..60),
        ) {
            // F 8 (read, not written) keeps any f64.
            let wide: Vec<_> = xs.chunks_exact(3).map(|c| p(c[0], c[1], c[2])).collect();
            let c = compressed_file(&xyz_header(wide.len()), &field_major(&wide));
            prop_assert_eq!(read_all(&c).unwrap(), wide);
            // The writers round each coordinate to its nearest f32, the same in both encodings.
            let pts: Vec<_> = ys.chunks_exact(3).map(|c| p(c[0], c[1], c[2])).collect();
            let rounded: Vec<_> = pts.iter().map(|q| q.map(|v| v as f32 as f64)).collect();
            prop_assert_eq!(read_all(&write_ascii(&pts)).unwrap(), rounded.clone());
            prop_assert_eq!(read_all(&write_binary(&pts)).unwrap(), rounded.clone());
            prop_assert_eq!(read_all(&write_binary(&rounded)).unwrap(), rounded);
        }

        #[test]
        fn lzf_round_trips(data in proptest::collection::vec(0u8..4, 0..2000)) {
            prop_assert_eq!(lzf_decompress(&lzf_compress(&data), data.len()).unwrap(), data);
        }

        #[test]
        fn random_lzf_streams_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..300), len in 0usize..2000) {
            if let Ok(out) = lzf_decompress(&bytes, len) {
                prop_assert_eq!(out.len(), len);
            }
        }

        #[test]
        fn random_bodies_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..512)) {
            let _ = read_all(&bytes);
            for data in ["ascii", "binary", "binary_compressed"] {
                let mut b = ASCII.replace("ascii", data).into_bytes();
                b.extend_from_slice(&bytes);
                let _ = read_all(&b);
            }
        }

        #[test]
        fn random_headers_never_panic(text in "((VERSION|FIELDS|COLUMNS|SIZE|TYPE|COUNT|WIDTH|HEIGHT|POINTS|VIEWPOINT|DATA|ascii|binary|binary_compressed|x|y|z|_|F|U|I|[0-9]{1,3}|-1|#| |\n)){0,40}") {
            let _ = read_all(text.as_bytes());
            let mut b = text.into_bytes();
            b.extend_from_slice(&[1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16]);
            let _ = read_all(&b);
        }
    }
}
