//! Real shapes for the realistic benchmark: scanned objects, CAD parts and anatomical
//! surfaces that public packages ship, each stored as 20,000 points sampled uniformly by area on its mesh,
//! centred on its bounding box and scaled to a unit diagonal (`host/data/realistic/`;
//! sources, licences and the script that made them in `SOURCES.md` and `manifest.toml`
//! there; the camera-view shapes are made by `make_camera.py`). The points are compiled
//! into the binary.

use nalgebra::{Matrix3, Point3};
use std::sync::OnceLock;

/// One stored shape.
#[derive(Debug)]
pub struct RealShape {
    /// Name (the file's stem).
    pub name: &'static str,
    /// `scan` (a scanned object), `cad` (a designed part) or `anatomy` (a surface of a body
    /// part: skin or brain surface from MRI, or a bone model).
    pub kind: &'static str,
    /// Held out of tuning: looked at only to report.
    pub held_out: bool,
    /// Added with the camera-view families; the plane-cut families keep their original ten
    /// shapes so their figures stay comparable.
    pub camera_only: bool,
    /// The PLY file's bytes.
    bytes: &'static [u8],
    points: OnceLock<Vec<Point3<f64>>>,
}

impl RealShape {
    /// The stored points (parsed once).
    pub fn points(&self) -> &[Point3<f64>] {
        self.points.get_or_init(|| {
            crate::io::read_points_from_bytes(self.bytes, crate::io::Format::PlyBinary)
                .unwrap_or_else(|e| panic!("built-in shape {} does not parse: {e}", self.name))
        })
    }

    /// Rotations about the origin that map the shape onto itself, identity first (every
    /// stored shape is asymmetric: only the identity).
    pub fn symmetries(&self) -> Vec<Matrix3<f64>> {
        vec![Matrix3::identity()]
    }
}

macro_rules! shape {
    ($name:literal, $kind:literal, $held:expr, $camera_only:expr) => {
        RealShape {
            name: $name,
            kind: $kind,
            held_out: $held,
            camera_only: $camera_only,
            bytes: include_bytes!(concat!("../data/realistic/", $name, ".ply")),
            points: OnceLock::new(),
        }
    };
}

/// The stored shapes (provenance and licences in `host/data/realistic/manifest.toml`).
static SHAPES: [RealShape; 16] = [
    shape!("bunny", "scan", false, false),
    shape!("chinese_dragon", "scan", false, false),
    shape!("b9_lidar", "scan", false, false),
    shape!("armadillo", "scan", true, false),
    shape!("lion_head", "scan", true, false),
    shape!("fandisk", "cad", false, false),
    shape!("mech_holes_shark", "cad", false, false),
    shape!("part", "cad", false, false),
    shape!("joint", "cad", true, false),
    shape!("anchor", "cad", true, false),
    // Camera-view families only.
    shape!("colin_head", "anatomy", false, true),
    shape!("colin_cortex", "anatomy", false, true),
    shape!("dog_skull", "anatomy", false, true),
    shape!("dog_vertebra", "anatomy", false, true),
    shape!("fsaverage_head", "anatomy", true, true),
    shape!("dog_pelvis", "anatomy", true, true),
];

/// Every stored shape.
pub fn all() -> &'static [RealShape] {
    &SHAPES
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The table and the manifest name the same shapes with the same kinds, and every file
    /// parses into 20,000 finite points with a unit diagonal.
    #[test]
    fn the_table_matches_the_manifest_and_the_files_parse() {
        let manifest = include_str!("../data/realistic/manifest.toml");
        let field = |block: &str, key: &str| -> String {
            let line = block.lines().find(|l| l.starts_with(&format!("{key} ="))).unwrap_or("");
            line.split('"').nth(1).unwrap_or("").to_string()
        };
        let listed: Vec<(String, String)> =
            manifest.split("[[shape]]").skip(1).map(|b| (field(b, "name"), field(b, "kind"))).collect();
        let table: Vec<(String, String)> = all().iter().map(|s| (s.name.to_string(), s.kind.to_string())).collect();
        let mut a = listed.clone();
        let mut b = table.clone();
        a.sort();
        b.sort();
        assert_eq!(a, b);
        for s in all() {
            let p = s.points();
            assert_eq!(p.len(), 20_000, "{}", s.name);
            assert!(p.iter().all(|q| q.coords.iter().all(|v| v.is_finite())));
            assert!((crate::cloud::bbox_diagonal(p) - 1.0).abs() < 1e-4, "{}", s.name);
        }
        assert!(all().iter().all(|s| ["scan", "cad", "anatomy"].contains(&s.kind)), "unknown kind");
        let plane_cut: Vec<&RealShape> = all().iter().filter(|s| !s.camera_only).collect();
        assert_eq!(plane_cut.len(), 10, "the plane-cut families keep their ten shapes");
        assert!(plane_cut.iter().filter(|s| s.kind == "scan").count() >= 3);
        assert!(plane_cut.iter().filter(|s| s.kind == "cad").count() >= 3);
        let camera: Vec<&RealShape> = all().iter().filter(|s| s.camera_only).collect();
        let anatomy = |held: bool| camera.iter().filter(|s| s.kind == "anatomy" && s.held_out == held).count();
        assert!(anatomy(false) >= 1 && anatomy(true) >= 1, "anatomy both in tuning and held out");
        assert!(camera.iter().filter(|s| s.kind == "anatomy").count() >= 3);
    }
}
