//! PCD files written by two independent writers (Open3D 0.20.0 and pypcd4 1.5.1, see
//! `tests/data/pcd/SOURCES.md`): every DATA kind, extra fields of many types, a `_`
//! padding field, F 4 and F 8 coordinates, organised clouds with NaN points. Each
//! `NAME.pcd` must read to exactly the points of `NAME.xyz`, which the same script wrote
//! from the values it gave the writer (NaN points left out).

use std::path::{Path, PathBuf};

use nalgebra::Point3;
use pficp::io::{read_cloud, read_points_from_bytes, Format};

fn dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/pcd")
}

/// The fixtures: name, DATA kind, declared points.
const FIXTURES: [(&str, &str, usize); 7] = [
    ("open3d_ascii", "ascii", 50),
    ("open3d_binary_normals_rgb", "binary", 60),
    ("open3d_compressed_normals_rgb", "binary_compressed", 200),
    ("pypcd4_fields_ascii", "ascii", 40),
    ("pypcd4_padding_f8_compressed", "binary_compressed", 120),
    ("pypcd4_organised_nan_binary", "binary", 48),
    ("pypcd4_organised_nan_compressed", "binary_compressed", 48),
];

fn expected(name: &str) -> Vec<Point3<f64>> {
    let text = std::fs::read(dir().join(format!("{name}.xyz"))).unwrap();
    read_points_from_bytes(&text, Format::Xyz).unwrap()
}

#[test]
fn independent_writers_files_read_to_their_exact_points() {
    for (name, data, declared) in FIXTURES {
        let bytes = std::fs::read(dir().join(format!("{name}.pcd"))).unwrap();
        let header = String::from_utf8_lossy(&bytes[..bytes.len().min(400)]).into_owned();
        assert!(header.contains(&format!("\nDATA {data}\n")), "{name}: {header}");
        assert!(header.contains(&format!("\nPOINTS {declared}\n")), "{name}: {header}");
        let want = expected(name);
        assert!(!want.is_empty(), "{name}");
        for format in [Format::PcdBinary, Format::PcdAscii] {
            let got = read_points_from_bytes(&bytes, format).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!(got.len(), want.len(), "{name}");
            for (i, (a, b)) in got.iter().zip(&want).enumerate() {
                for (x, y) in a.coords.iter().zip(b.coords.iter()) {
                    assert_eq!(x.to_bits(), y.to_bits(), "{name} point {i}: {a} vs {b}");
                }
            }
        }
    }
}

#[test]
fn organised_clouds_lose_exactly_their_nan_points() {
    for name in ["pypcd4_organised_nan_binary", "pypcd4_organised_nan_compressed"] {
        let bytes = std::fs::read(dir().join(format!("{name}.pcd"))).unwrap();
        assert!(String::from_utf8_lossy(&bytes).contains("\nWIDTH 8\nHEIGHT 6\n"), "{name}");
        let got = read_points_from_bytes(&bytes, Format::PcdBinary).unwrap();
        // The script's count line: `# NAME.pcd: K valid points of 48`.
        let text = std::fs::read_to_string(dir().join(format!("{name}.xyz"))).unwrap();
        let first = text.lines().next().unwrap();
        let valid: usize = first.split_whitespace().nth(2).unwrap().parse().unwrap();
        assert!(first.ends_with("valid points of 48"), "{first}");
        assert!(valid < 48 && valid > 0, "{first}");
        assert_eq!(got.len(), valid, "{name}");
        assert!(got.iter().all(|p| p.coords.iter().all(|v| v.is_finite())), "{name}");
    }
}

#[test]
fn every_fixture_is_a_valid_cloud_for_the_tool() {
    for (name, _, _) in FIXTURES {
        let cloud = read_cloud(&dir().join(format!("{name}.pcd")), "scan").unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(cloud.points(), expected(name).as_slice(), "{name}");
    }
}
