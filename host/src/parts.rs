//! Synthetic mechanical parts for the realistic benchmark (`crate::eval::realistic`):
//! boxes, plates, nuts, flanges and shafts built from boxes, cylinders and hexagonal
//! prisms (union and difference), sampled uniformly on their surface.
//!
//! Most are **near-symmetric**: a symmetric body with one small feature (a boss, a notch,
//! a key slot, an extra hole, a flat) that breaks the symmetry, the case where a
//! registration finds a flip or a turn about the symmetry axis that fits almost as well
//! as the truth. Three are **exactly symmetric** (no feature): their pose is only defined
//! up to their symmetry group, which [`Part::symmetries`] lists (rotations about the
//! origin, identity first) and the benchmark scores modulo.
//!
//! Surface sampling of a solid `S = (union of adds) minus (union of subtracts)`: a point on
//! the surface of an added primitive is on `S`'s surface if no other added primitive and
//! no subtracted one contains it; a point on a subtracted primitive's surface is if an
//! added primitive contains it and no other subtracted one does. Points are drawn per
//! primitive in proportion to its area and rejected by that rule, so the density is
//! uniform over the remaining surface.

use nalgebra::{Matrix3, Point3, Rotation3, Vector3};
use rand::Rng;
use std::f64::consts::{FRAC_PI_3, PI, TAU};

/// A solid primitive, axis-aligned (cylinders and prisms along z), centred at `c`.
#[derive(Clone, Copy, Debug)]
enum Primitive {
    /// Half extents `h`.
    Box { c: [f64; 3], h: [f64; 3] },
    /// Radius `r`, half height `hh`.
    Cylinder { c: [f64; 3], r: f64, hh: f64 },
    /// Regular hexagon of circumradius `r` (a vertex on +x), half height `hh`.
    Hex { c: [f64; 3], r: f64, hh: f64 },
}

const EPS: f64 = 1e-9;

impl Primitive {
    fn area(&self) -> f64 {
        match *self {
            Primitive::Box { h, .. } => 8.0 * (h[0] * h[1] + h[1] * h[2] + h[0] * h[2]),
            Primitive::Cylinder { r, hh, .. } => TAU * r * 2.0 * hh + 2.0 * PI * r * r,
            Primitive::Hex { r, hh, .. } => 6.0 * r * 2.0 * hh + 3.0 * 3f64.sqrt() * r * r,
        }
    }

    /// Strictly inside (by more than a tiny margin).
    fn contains(&self, p: &Point3<f64>) -> bool {
        match *self {
            Primitive::Box { c, h } => (0..3).all(|i| (p[i] - c[i]).abs() < h[i] - EPS),
            Primitive::Cylinder { c, r, hh } => {
                let (x, y) = (p.x - c[0], p.y - c[1]);
                x * x + y * y < (r - EPS) * (r - EPS) && (p.z - c[2]).abs() < hh - EPS
            }
            Primitive::Hex { c, r, hh } => {
                let apothem = r * (PI / 6.0).cos();
                let (x, y) = (p.x - c[0], p.y - c[1]);
                (0..3).all(|k| {
                    // Face normals at 30, 90, 150 degrees (a vertex on +x).
                    let a = PI / 6.0 + k as f64 * FRAC_PI_3;
                    (x * a.cos() + y * a.sin()).abs() < apothem - EPS
                }) && (p.z - c[2]).abs() < hh - EPS
            }
        }
    }

    /// A point uniform on the surface.
    fn sample(&self, rng: &mut impl Rng) -> Point3<f64> {
        match *self {
            Primitive::Box { c, h } => {
                let areas = [h[1] * h[2], h[0] * h[2], h[0] * h[1]];
                let mut u = rng.gen_range(0.0..areas.iter().sum::<f64>());
                let mut axis = 2;
                for (i, a) in areas.iter().enumerate() {
                    if u < *a {
                        axis = i;
                        break;
                    }
                    u -= a;
                }
                let mut p = [0.0; 3];
                for i in 0..3 {
                    p[i] = c[i] + rng.gen_range(-h[i]..h[i]);
                }
                p[axis] = c[axis] + if rng.gen_bool(0.5) { h[axis] } else { -h[axis] };
                Point3::from(p)
            }
            Primitive::Cylinder { c, r, hh } => {
                let side = TAU * r * 2.0 * hh;
                let cap = PI * r * r;
                if rng.gen_range(0.0..side + 2.0 * cap) < side {
                    let a = rng.gen_range(0.0..TAU);
                    Point3::new(c[0] + r * a.cos(), c[1] + r * a.sin(), c[2] + rng.gen_range(-hh..hh))
                } else {
                    let (a, rr) = (rng.gen_range(0.0..TAU), r * rng.gen_range(0.0f64..1.0).sqrt());
                    let z = if rng.gen_bool(0.5) { hh } else { -hh };
                    Point3::new(c[0] + rr * a.cos(), c[1] + rr * a.sin(), c[2] + z)
                }
            }
            Primitive::Hex { c, r, hh } => {
                let side = 6.0 * r * 2.0 * hh;
                let cap = 1.5 * 3f64.sqrt() * r * r;
                if rng.gen_range(0.0..side + 2.0 * cap) < side {
                    let k = rng.gen_range(0..6) as f64;
                    let (a0, a1) = (k * FRAC_PI_3, (k + 1.0) * FRAC_PI_3);
                    let t = rng.gen_range(0.0..1.0);
                    let x = r * ((1.0 - t) * a0.cos() + t * a1.cos());
                    let y = r * ((1.0 - t) * a0.sin() + t * a1.sin());
                    Point3::new(c[0] + x, c[1] + y, c[2] + rng.gen_range(-hh..hh))
                } else {
                    let z = if rng.gen_bool(0.5) { hh } else { -hh };
                    let hex = Primitive::Hex { c: [0.0; 3], r, hh: 1.0 };
                    loop {
                        let q = Point3::new(rng.gen_range(-r..r), rng.gen_range(-r..r), 0.0);
                        if hex.contains(&q) {
                            break Point3::new(c[0] + q.x, c[1] + q.y, c[2] + z);
                        }
                    }
                }
            }
        }
    }
}

/// The dihedral group `D_n` about z: `n` turns about z, then `n` half turns about axes in
/// the xy-plane (identity first).
fn dihedral(n: usize) -> Vec<Matrix3<f64>> {
    let about = |axis: Vector3<f64>, angle: f64| {
        Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(axis), angle).into_inner()
    };
    let mut out: Vec<Matrix3<f64>> = (0..n).map(|k| about(Vector3::z(), TAU * k as f64 / n as f64)).collect();
    let flip = about(Vector3::x(), PI);
    out.extend((0..n).map(|k| about(Vector3::z(), TAU * k as f64 / n as f64) * flip));
    out
}

/// The synthetic parts.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Part {
    /// Block 1.0 x 0.6 x 0.3 with a small round boss near one corner of the top (near D2).
    BlockBoss,
    /// Hexagonal nut with one notch in a corner (near D6).
    NutNotch,
    /// Square plate with four corner holes and a fifth small hole near one edge (near D4).
    PlateExtraHole,
    /// Round flange with six bolt holes and a key slot in its bore (near D6).
    FlangeKey,
    /// Block 0.8 x 0.7 x 0.5 (near-equal sides) with one corner notched (near D2).
    NearCubeNotch,
    /// Round shaft with a short flat near one end (near the full turn about its axis).
    ShaftFlat,
    /// Block 1.0 x 0.6 x 0.3: exactly D2 (4 rotations).
    Block,
    /// Hexagonal nut: exactly D6 (12 rotations).
    Nut,
    /// Square plate with four corner holes: exactly D4 (8 rotations).
    Plate,
}

impl Part {
    /// Every part.
    pub const ALL: [Part; 9] = [
        Part::BlockBoss,
        Part::NutNotch,
        Part::PlateExtraHole,
        Part::FlangeKey,
        Part::NearCubeNotch,
        Part::ShaftFlat,
        Part::Block,
        Part::Nut,
        Part::Plate,
    ];

    /// Name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Part::BlockBoss => "block-boss",
            Part::NutNotch => "nut-notch",
            Part::PlateExtraHole => "plate-extra-hole",
            Part::FlangeKey => "flange-key",
            Part::NearCubeNotch => "near-cube-notch",
            Part::ShaftFlat => "shaft-flat",
            Part::Block => "block",
            Part::Nut => "nut",
            Part::Plate => "plate",
        }
    }

    /// (added, subtracted) primitives.
    fn solid(self) -> (Vec<Primitive>, Vec<Primitive>) {
        use Primitive::{Box as B, Cylinder as C, Hex as H};
        let block = B { c: [0.0; 3], h: [0.5, 0.3, 0.15] };
        let nut = H { c: [0.0; 3], r: 0.5, hh: 0.2 };
        let bore = C { c: [0.0; 3], r: 0.22, hh: 0.3 };
        let plate = B { c: [0.0; 3], h: [0.5, 0.5, 0.06] };
        let corner_holes: Vec<Primitive> = [[1.0, 1.0], [-1.0, 1.0], [-1.0, -1.0], [1.0, -1.0]]
            .map(|[x, y]| C { c: [0.33 * x, 0.33 * y, 0.0], r: 0.08, hh: 0.1 })
            .to_vec();
        match self {
            Part::BlockBoss => (vec![block, C { c: [0.3, 0.14, 0.15], r: 0.09, hh: 0.08 }], vec![]),
            Part::NutNotch => (vec![nut], vec![bore, B { c: [0.5, 0.0, 0.2], h: [0.12, 0.12, 0.12] }]),
            Part::PlateExtraHole => {
                let mut subs = corner_holes;
                subs.push(C { c: [0.12, 0.33, 0.0], r: 0.07, hh: 0.1 });
                (vec![plate], subs)
            }
            Part::FlangeKey => {
                let mut subs: Vec<Primitive> = (0..6)
                    .map(|k| {
                        let a = k as f64 * FRAC_PI_3;
                        C { c: [0.36 * a.cos(), 0.36 * a.sin(), 0.0], r: 0.06, hh: 0.2 }
                    })
                    .collect();
                subs.push(C { c: [0.0; 3], r: 0.16, hh: 0.2 });
                // A keyway from the top face halfway down (through, it would keep a half turn).
                subs.push(B { c: [0.0, 0.18, 0.09], h: [0.05, 0.07, 0.09] });
                (vec![C { c: [0.0; 3], r: 0.5, hh: 0.09 }], subs)
            }
            Part::NearCubeNotch => {
                (vec![B { c: [0.0; 3], h: [0.4, 0.35, 0.25] }], vec![B { c: [0.4, 0.35, 0.25], h: [0.12, 0.12, 0.12] }])
            }
            Part::ShaftFlat => {
                (vec![C { c: [0.0; 3], r: 0.2, hh: 0.6 }], vec![B { c: [0.25, 0.0, 0.42], h: [0.1, 0.3, 0.14] }])
            }
            Part::Block => (vec![block], vec![]),
            Part::Nut => (vec![nut], vec![bore]),
            Part::Plate => (vec![plate], corner_holes),
        }
    }

    /// Whether the part has no symmetry-breaking feature.
    pub fn exactly_symmetric(self) -> bool {
        matches!(self, Part::Block | Part::Nut | Part::Plate)
    }

    /// The rotations (about the origin) that map the part onto itself, identity first.
    /// Only the identity for the near-symmetric parts.
    pub fn symmetries(self) -> Vec<Matrix3<f64>> {
        match self {
            Part::Block => dihedral(2),
            Part::Nut => dihedral(6),
            Part::Plate => dihedral(4),
            _ => vec![Matrix3::identity()],
        }
    }

    /// `n` points uniform on the surface.
    pub fn sample_surface(self, n: usize, rng: &mut impl Rng) -> Vec<Point3<f64>> {
        let (adds, subs) = self.solid();
        let prims: Vec<(Primitive, bool)> =
            adds.iter().map(|p| (*p, true)).chain(subs.iter().map(|p| (*p, false))).collect();
        let total: f64 = prims.iter().map(|(p, _)| p.area()).sum();
        let mut out = Vec::with_capacity(n);
        while out.len() < n {
            let mut u = rng.gen_range(0.0..total);
            let mut pick = prims.len() - 1;
            for (i, (p, _)) in prims.iter().enumerate() {
                if u < p.area() {
                    pick = i;
                    break;
                }
                u -= p.area();
            }
            let (prim, added) = prims[pick];
            let q = prim.sample(rng);
            let others = |list: &[Primitive], skip: Option<usize>| {
                list.iter().enumerate().any(|(i, p)| Some(i) != skip && p.contains(&q))
            };
            let keep = if added {
                !others(&adds, Some(pick)) && !others(&subs, None)
            } else {
                let j = pick - adds.len();
                others(&adds, None) && !others(&subs, Some(j))
            };
            if keep {
                out.push(q);
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// The symmetric parts' point sets map onto themselves under every listed rotation
    /// (each mapped point lies near a sampled one), and the near-symmetric ones do not
    /// under their body's symmetry.
    #[test]
    fn symmetries_hold_and_features_break_them() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for part in Part::ALL {
            let pts = part.sample_surface(6000, &mut rng);
            let nn = crate::nn::NearestNeighbours::new(&pts);
            let misfit = |r: &Matrix3<f64>| {
                let d: Vec<f64> = pts.iter().map(|p| nn.closest(&Point3::from(r * p.coords)).dist2.sqrt()).collect();
                d.iter().cloned().fold(0.0, f64::max)
            };
            for r in part.symmetries() {
                assert!(misfit(&r) < 0.05, "{}: a listed symmetry does not hold", part.name());
            }
            if !part.exactly_symmetric() {
                // Every symmetry of the bodies here (turns about z, half turns about axes in
                // the xy-plane) is broken by the feature.
                for r in dihedral(4).iter().chain(&dihedral(6)).skip(1) {
                    if r != &Matrix3::identity() {
                        assert!(misfit(r) > 0.04, "{}: the feature does not break a symmetry", part.name());
                    }
                }
            }
        }
    }

    #[test]
    fn surface_points_lie_on_no_interior_face() {
        // The boss's bottom cap and the block's top under the boss are inside the solid.
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let pts = Part::BlockBoss.sample_surface(20000, &mut rng);
        assert!(!pts.iter().any(|p| (p.x - 0.3).hypot(p.y - 0.14) < 0.06 && (p.z - 0.15).abs() < 1e-9));
        assert!(pts.iter().any(|p| p.z > 0.2));
    }
}
