//! PLY files: ascii and binary little endian, vertices only.
//!
//! The header is parsed in full (elements, scalar and list properties); the
//! body is read up to the end of the `vertex` element, skipping any elements
//! declared before it. Elements after the vertices (faces, ...) are ignored.

use std::io::{BufRead, Read};

use nalgebra::Point3;

use super::lines::{read_error, Lines};
use super::{fmt_float, parse_f64, shorten, ParseError};

/// A PLY scalar type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    /// The type for a PLY type name (old and new spellings).
    fn parse(name: &str) -> Option<Self> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    /// Bytes in binary encoding.
    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    /// The little-endian value at the start of `b`, if `b` is long enough.
    fn read_le(self, b: &[u8]) -> Option<f64> {
        Some(match self {
            Scalar::I8 => i8::from_le_bytes(take(b)?).into(),
            Scalar::U8 => u8::from_le_bytes(take(b)?).into(),
            Scalar::I16 => i16::from_le_bytes(take(b)?).into(),
            Scalar::U16 => u16::from_le_bytes(take(b)?).into(),
            Scalar::I32 => i32::from_le_bytes(take(b)?).into(),
            Scalar::U32 => u32::from_le_bytes(take(b)?).into(),
            Scalar::F32 => f32::from_le_bytes(take(b)?).into(),
            Scalar::F64 => f64::from_le_bytes(take(b)?),
        })
    }
}

/// The first `N` bytes of `b`.
fn take<const N: usize>(b: &[u8]) -> Option<[u8; N]> {
    b.get(..N)?.try_into().ok()
}

/// A property's type: one scalar, or a length-prefixed list.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Scalar(Scalar),
    List { len: Scalar, item: Scalar },
}

/// One `property` line.
#[derive(Clone, Debug, PartialEq)]
struct Property {
    name: String,
    kind: Kind,
}

/// One `element` line with its properties.
#[derive(Clone, Debug, PartialEq)]
struct Element {
    name: String,
    count: usize,
    props: Vec<Property>,
}

impl Element {
    /// Bytes per entry if every property is a scalar.
    fn fixed_size(&self) -> Option<usize> {
        self.props.iter().try_fold(0, |acc, p| match p.kind {
            Kind::Scalar(s) => Some(acc + s.size()),
            Kind::List { .. } => None,
        })
    }
}

/// Body encoding.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Encoding {
    Ascii,
    BinaryLe,
}

/// A parsed header.
#[derive(Debug)]
struct Header {
    encoding: Encoding,
    elements: Vec<Element>,
}

/// Read the vertex positions of a PLY file of either supported encoding, at most `limit`
/// of them (a header declaring more is refused before the body is read).
pub(super) fn read(reader: impl BufRead, limit: usize) -> Result<Vec<Point3<f64>>, ParseError> {
    let mut lines = Lines::new(reader);
    let header = parse_header(&mut lines)?;
    let v = header.elements.iter().position(|e| e.name == "vertex").ok_or(ParseError::MissingVertexElement)?;
    let vertex = &header.elements[v];
    if let Some(p) = vertex.props.iter().find(|p| matches!(p.kind, Kind::List { .. })) {
        return Err(ParseError::ListInVertex(p.name.clone()));
    }
    if vertex.count > limit {
        return Err(ParseError::TooManyPoints { limit });
    }
    let find =
        |axis: &'static str| vertex.props.iter().position(|p| p.name == axis).ok_or(ParseError::MissingProperty(axis));
    let xyz = [find("x")?, find("y")?, find("z")?];
    let before = &header.elements[..v];
    match header.encoding {
        Encoding::Ascii => read_ascii(lines, before, vertex, xyz),
        Encoding::BinaryLe => read_binary(lines.into_inner(), before, vertex, xyz),
    }
}

/// Parse the header from the first line; `lines` stands just after `end_header`.
fn parse_header<R: BufRead>(lines: &mut Lines<R>) -> Result<Header, ParseError> {
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    while let Some((line_no, line)) = lines.next_line()? {
        let bad_line = || ParseError::BadHeaderLine { line: line_no, text: shorten(line.trim()) };
        let tokens: Vec<&str> = line.split_whitespace().collect();
        if line_no == 1 {
            if tokens != ["ply"] {
                return Err(ParseError::NotPly);
            }
            continue;
        }
        match tokens.as_slice() {
            [] | ["comment", ..] | ["obj_info", ..] => {}
            ["format", name, ..] => {
                encoding = Some(match *name {
                    "ascii" => Encoding::Ascii,
                    "binary_little_endian" => Encoding::BinaryLe,
                    other => return Err(ParseError::UnsupportedFormat(shorten(other))),
                });
            }
            ["element", name, count] => {
                let count =
                    count.parse().map_err(|_| ParseError::BadElementCount { line: line_no, count: shorten(count) })?;
                elements.push(Element { name: name.to_string(), count, props: Vec::new() });
            }
            ["property", "list", len, item, name] => {
                let kind = Kind::List { len: scalar(len, line_no)?, item: scalar(item, line_no)? };
                if matches!(kind, Kind::List { len: Scalar::F32 | Scalar::F64, .. }) {
                    return Err(ParseError::UnsupportedType { line: line_no, ty: format!("list length {len}") });
                }
                push_property(&mut elements, name, kind).ok_or_else(bad_line)?;
            }
            ["property", ty, name] => {
                let kind = Kind::Scalar(scalar(ty, line_no)?);
                push_property(&mut elements, name, kind).ok_or_else(bad_line)?;
            }
            ["end_header"] => {
                return Ok(Header { encoding: encoding.ok_or(ParseError::MissingFormat)?, elements });
            }
            _ => return Err(bad_line()),
        }
    }
    Err(if lines.count() == 0 { ParseError::NotPly } else { ParseError::MissingEndHeader })
}

/// The scalar type named `ty` on header line `line`.
fn scalar(ty: &str, line: usize) -> Result<Scalar, ParseError> {
    Scalar::parse(ty).ok_or_else(|| ParseError::UnsupportedType { line, ty: shorten(ty) })
}

/// Add a property to the last element; `None` if there is no element yet.
fn push_property(elements: &mut [Element], name: &str, kind: Kind) -> Option<()> {
    elements.last_mut()?.props.push(Property { name: name.to_string(), kind });
    Some(())
}

/// The truncation error for `element` after `read` complete entries.
fn truncated(element: &Element, read: usize) -> ParseError {
    ParseError::Truncated { element: element.name.clone(), read, declared: element.count }
}

/// Room reserved for points up front: the declared count, but not more than this (a
/// header may lie; the vector grows if it does not).
const RESERVE: usize = 1 << 16;

/// Ascii body: one entry a non-blank line, numbered on from the header's lines.
fn read_ascii<R: BufRead>(
    mut lines: Lines<R>,
    before: &[Element],
    vertex: &Element,
    xyz: [usize; 3],
) -> Result<Vec<Point3<f64>>, ParseError> {
    // The next non-blank line, or the truncation error of `element` after `read` entries.
    fn entry<'a, R: BufRead>(
        lines: &'a mut Lines<R>,
        element: &Element,
        read: usize,
    ) -> Result<(usize, std::borrow::Cow<'a, str>), ParseError> {
        lines.next_nonblank()?.ok_or_else(|| truncated(element, read))
    }
    for element in before.iter().filter(|e| !e.props.is_empty()) {
        for read in 0..element.count {
            entry(&mut lines, element, read)?;
        }
    }
    let mut points = Vec::with_capacity(vertex.count.min(RESERVE));
    for read in 0..vertex.count {
        let (line, text) = entry(&mut lines, vertex, read)?;
        let fields: Vec<&str> = text.split_whitespace().collect();
        if fields.len() < vertex.props.len() {
            return Err(ParseError::TooFewColumns { line, found: fields.len(), needed: vertex.props.len() });
        }
        let value = |i: usize| parse_f64(fields.get(i).copied().unwrap_or_default(), line);
        points.push(Point3::new(value(xyz[0])?, value(xyz[1])?, value(xyz[2])?));
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

/// Binary little-endian body, one record at a time.
fn read_binary(
    mut reader: impl BufRead,
    before: &[Element],
    vertex: &Element,
    xyz: [usize; 3],
) -> Result<Vec<Point3<f64>>, ParseError> {
    for element in before {
        skip_binary(&mut reader, element)?;
    }
    let mut offsets = Vec::with_capacity(vertex.props.len());
    let mut stride = 0;
    for p in &vertex.props {
        let Kind::Scalar(s) = p.kind else {
            return Err(ParseError::ListInVertex(p.name.clone()));
        };
        offsets.push((stride, s));
        stride += s.size();
    }
    let mut points = Vec::with_capacity(vertex.count.min(RESERVE));
    let mut record = vec![0u8; stride];
    for read in 0..vertex.count {
        if !fill(&mut reader, &mut record)? {
            return Err(truncated(vertex, read));
        }
        let mut c = [0.0; 3];
        for (slot, &i) in c.iter_mut().zip(xyz.iter()) {
            let (off, s) = offsets.get(i).copied().ok_or_else(|| truncated(vertex, read))?;
            let bytes = record.get(off..).unwrap_or_default();
            *slot = s.read_le(bytes).ok_or_else(|| truncated(vertex, read))?;
        }
        points.push(Point3::from(c));
    }
    Ok(points)
}

/// Skip all entries of `element` (streamed: nothing is kept).
fn skip_binary(reader: &mut impl BufRead, element: &Element) -> Result<(), ParseError> {
    fn skip(reader: &mut impl BufRead, n: u64) -> Result<u64, ParseError> {
        std::io::copy(&mut reader.by_ref().take(n), &mut std::io::sink()).map_err(read_error)
    }
    if let Some(size) = element.fixed_size() {
        if size == 0 {
            return Ok(());
        }
        let total = (size as u64).saturating_mul(element.count as u64);
        let skipped = skip(reader, total)?;
        return if skipped == total { Ok(()) } else { Err(truncated(element, (skipped / size as u64) as usize)) };
    }
    for read in 0..element.count {
        for p in &element.props {
            let size = match p.kind {
                Kind::Scalar(s) => s.size() as u64,
                Kind::List { len, item } => {
                    let mut b = [0u8; 8];
                    if !fill(reader, &mut b[..len.size()])? {
                        return Err(truncated(element, read));
                    }
                    // Negative lengths are rejected as truncation: nothing valid follows.
                    match len.read_le(&b).filter(|n| *n >= 0.0) {
                        Some(n) => (n as u64).saturating_mul(item.size() as u64),
                        None => return Err(truncated(element, read)),
                    }
                }
            };
            if skip(reader, size)? != size {
                return Err(truncated(element, read));
            }
        }
    }
    Ok(())
}

/// The header for `n` double-precision vertices in `format`.
fn header(format: &str, n: usize) -> String {
    format!(
        "ply\nformat {format} 1.0\ncomment written by pficp\nelement vertex {n}\n\
         property double x\nproperty double y\nproperty double z\nend_header\n"
    )
}

/// An ascii PLY of `points`, exact to the last bit.
pub(super) fn write_ascii(points: &[Point3<f64>]) -> Vec<u8> {
    let mut out = header("ascii", points.len());
    for p in points {
        out.push_str(&format!("{} {} {}\n", fmt_float(p.x), fmt_float(p.y), fmt_float(p.z)));
    }
    out.into_bytes()
}

/// A binary little-endian PLY of `points` as `double` x y z.
pub(super) fn write_binary(points: &[Point3<f64>]) -> Vec<u8> {
    let mut out = header("binary_little_endian", points.len()).into_bytes();
    out.reserve(points.len() * 24);
    for p in points {
        for v in [p.x, p.y, p.z] {
            out.extend_from_slice(&v.to_le_bytes());
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
        read_all(bytes).unwrap_err().to_string()
    }

    const ASCII_HEADER: &str = "ply\nformat ascii 1.0\nelement vertex 2\n\
        property float x\nproperty float y\nproperty float z\nend_header\n";

    #[test]
    fn ascii_with_extra_properties_and_faces() {
        let text = "ply\r\nformat ascii 1.0\r\ncomment made by hand\nobj_info scanner 3\n\
            element camera 1\nproperty list uchar float params\n\
            element vertex 3\nproperty float nx\nproperty float z\nproperty double y\n\
            property uchar red\nproperty float x\nproperty uchar green\nproperty uchar blue\n\
            element face 1\nproperty list uchar int vertex_indices\nend_header\n\
            3 0.1 0.2 0.3\n\
            0 3 2 255 1 0 0\n\n0 6 5 1 4 0 0 extra\n1 -9 -8 7 -7 1 1\n3 0 1 2\n";
        let pts = read_all(text.as_bytes()).unwrap();
        assert_eq!(pts, vec![p(1.0, 2.0, 3.0), p(4.0, 5.0, 6.0), p(-7.0, -8.0, -9.0)]);
    }

    #[test]
    fn binary_with_mixed_types_and_faces() {
        let mut b = b"ply\nformat binary_little_endian 1.0\ncomment c\n\
            element camera 2\nproperty list uchar int ids\nproperty short k\n\
            element vertex 2\nproperty uchar red\nproperty float y\nproperty int z\n\
            property double x\nproperty ushort flags\n\
            element face 1\nproperty list uchar int vertex_indices\nend_header\n"
            .to_vec();
        // camera: [1 id] k, [0 ids] k
        b.extend_from_slice(&[1, 9, 0, 0, 0, 5, 0, 0, 6, 0]);
        for (x, y, z) in [(0.25f64, -1.5f32, 7i32), (1e300, 2.0, -3)] {
            b.push(200);
            b.extend_from_slice(&y.to_le_bytes());
            b.extend_from_slice(&z.to_le_bytes());
            b.extend_from_slice(&x.to_le_bytes());
            b.extend_from_slice(&7u16.to_le_bytes());
        }
        b.extend_from_slice(&[3, 0, 0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0]);
        assert_eq!(read_all(&b).unwrap(), vec![p(0.25, -1.5, 7.0), p(1e300, 2.0, -3.0)]);
    }

    #[test]
    fn writers_round_trip_exactly() {
        let pts = vec![p(0.1, -0.0, 5e-324), p(f64::MAX, 1e-7, 2.0 / 3.0)];
        assert_eq!(read_all(&write_ascii(&pts)).unwrap(), pts);
        let bin = write_binary(&pts);
        assert_eq!(read_all(&bin).unwrap(), pts);
        let s = String::from_utf8_lossy(&bin);
        assert!(s.contains("format binary_little_endian 1.0") && s.contains("property double z"));
        assert!(read_all(&write_binary(&[])).unwrap().is_empty());
    }

    #[test]
    fn header_errors() {
        let e = err(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n");
        assert!(e.contains("missing `end_header`"), "{e}");
        let e = err(ASCII_HEADER.replace("property float z\n", "").as_bytes());
        assert!(e.contains("no `z` property"), "{e}");
        let e = err(ASCII_HEADER.replace("vertex 2", "vertex -2").as_bytes());
        assert!(e.contains("bad element count `-2`"), "{e}");
        let e = err(ASCII_HEADER.replace("vertex 2", "vertex many").as_bytes());
        assert!(e.contains("bad element count"), "{e}");
        let e = err(ASCII_HEADER.replace("float y", "quad y").as_bytes());
        assert!(e.contains("unsupported property type `quad`") && e.contains("line 5"), "{e}");
        let e = err(ASCII_HEADER.replace("float y", "list uchar float y").as_bytes());
        assert!(e.contains("list property `y`"), "{e}");
        let e = err(ASCII_HEADER.replace("ascii", "binary_big_endian").as_bytes());
        assert!(e.contains("unsupported PLY format `binary_big_endian`"), "{e}");
        let e = err(ASCII_HEADER.replace("format ascii 1.0\n", "").as_bytes());
        assert!(e.contains("missing `format`"), "{e}");
        let e = err(ASCII_HEADER.replace("vertex", "point").as_bytes());
        assert!(e.contains("no `vertex` element"), "{e}");
        let e = err(ASCII_HEADER.replace("end_header", "bogus line\nend_header").as_bytes());
        assert!(e.contains("malformed PLY header at line 7: `bogus line`"), "{e}");
        let e = err(b"ply\nformat ascii 1.0\nproperty float x\nend_header\n");
        assert!(e.contains("line 3"), "{e}");
        assert!(err(b"xyz\n1 2 3\n").contains("not a PLY file"));
        assert!(err(b"").contains("not a PLY file"));
    }

    #[test]
    fn body_errors() {
        let e = err(format!("{ASCII_HEADER}1 2 3\n").as_bytes());
        assert!(e.contains("truncated") && e.contains("read 1 of 2 declared `vertex`"), "{e}");
        let e = err(format!("{ASCII_HEADER}1 2 3\n4 5\n").as_bytes());
        assert!(e.contains("too few columns at line 9"), "{e}");
        let e = err(format!("{ASCII_HEADER}1 2 3\n4 five 6\n").as_bytes());
        assert!(e.contains("malformed number `five` at line 9"), "{e}");
        let bin = write_binary(&[p(1.0, 2.0, 3.0); 3]);
        let e = err(&bin[..bin.len() - 30]);
        assert!(e.contains("truncated") && e.contains("read 1 of 3"), "{e}");
        let mut b = ASCII_HEADER
            .replace("ascii", "binary_little_endian")
            .replace("element vertex", "element pre 1\nproperty list char int l\nelement vertex")
            .into_bytes();
        b.push(0xff); // list length -1
        assert!(err(&b).contains("read 0 of 1 declared `pre`"));
    }

    #[test]
    fn huge_declared_counts_fail_fast() {
        let h = |n: &str| ASCII_HEADER.replace("vertex 2", &format!("vertex {n}"));
        let big = usize::MAX.to_string();
        let e = err(format!("{}1 2 3\n", h(&big)).as_bytes());
        assert!(e.contains(&format!("read 1 of {big}")), "{e}");
        let b = h(&big).replace("ascii", "binary_little_endian");
        assert!(err(b.as_bytes()).contains("read 0 of"));
        let b = b.replace("element vertex", &format!("element e {big}\nproperty int i\nelement vertex"));
        assert!(err(b.as_bytes()).contains("declared `e`"));
    }

    #[test]
    fn a_header_declaring_more_than_the_limit_is_refused_before_the_body() {
        let h = ASCII_HEADER.replace("vertex 2", "vertex 11");
        assert_eq!(read(h.as_bytes(), 10), Err(ParseError::TooManyPoints { limit: 10 }));
        let b = h.replace("ascii", "binary_little_endian");
        assert_eq!(read(b.as_bytes(), 10), Err(ParseError::TooManyPoints { limit: 10 }));
        assert_eq!(read(write_binary(&[p(1.0, 2.0, 3.0); 10]).as_slice(), 10).unwrap().len(), 10);
    }

    proptest! {
        #[test]
        fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..512)) {
            let _ = read_all(&bytes);
            let mut with_header = ASCII_HEADER.replace("ascii", "binary_little_endian").into_bytes();
            with_header.extend_from_slice(&bytes);
            let _ = read_all(&with_header);
            let mut ascii = ASCII_HEADER.as_bytes().to_vec();
            ascii.extend_from_slice(&bytes);
            let _ = read_all(&ascii);
        }

        #[test]
        fn random_headers_never_panic(text in "(ply\n)?((format|element|property|list|end_header|vertex|face|x|y|z|uchar|float|ascii|binary_little_endian|[0-9]{1,3}|-1| |\n)){0,40}") {
            let _ = read_all(text.as_bytes());
            let mut b = text.into_bytes();
            b.extend_from_slice(&[1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12]);
            let _ = read_all(&b);
        }

        #[test]
        fn truncated_binary_is_an_error(cut in 0usize..400, n in 1usize..10) {
            let pts: Vec<_> = (0..n).map(|i| p(i as f64, 0.5, -1.0)).collect();
            let bin = write_binary(&pts);
            let cut = cut.min(bin.len() - 1);
            prop_assert!(read_all(&bin[..cut]).is_err());
            let ascii = write_ascii(&pts);
            let _ = read_all(&ascii[..cut.min(ascii.len())]);
        }

        #[test]
        fn corrupted_binary_never_panics(i in 0usize..400, byte in any::<u8>()) {
            let mut bin = write_binary(&[p(1.0, 2.0, 3.0), p(4.0, 5.0, 6.0)]);
            let len = bin.len();
            if let Some(b) = bin.get_mut(i % len) {
                *b = byte;
            }
            let _ = read_all(&bin);
        }
    }
}
