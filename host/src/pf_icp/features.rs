//! Feature-based start proposals for the global search: FPFH descriptors (Rusu, Blodow,
//! Beetz, ICRA 2009) on subsampled clouds, nearest descriptors as putative
//! correspondences, and RANSAC over triples of them with a similarity (scale included)
//! fitted to each triple.
//!
//! Partial views defeat the other starts: the scan's centroid and principal axes are not
//! the model's, so a start from a rotation set with the centroids' translation converges
//! only from within a few degrees. A triple of correct correspondences gives rotation,
//! translation and scale at once, wherever the view is.
//!
//! - **Clouds**: at most [`FEATURE_POINTS`] points of each (random, seeded), normals from
//!   their 12 nearest neighbours, oriented away from the cloud's centroid.
//! - **Descriptor**: for a point `p` and each of its (at most 47) nearest neighbours `q`
//!   within the radius, the Darboux
//!   frame `u = n_p, v = u x (q - p) / |q - p|, w = u x v` gives
//!   `alpha = v . n_q`, `phi = u . (q - p) / |q - p|`, `theta = atan2(w . n_q, u . n_q)`,
//!   each binned into 11 (SPFH, 33 bins, normalised); FPFH adds the neighbours' SPFH
//!   weighted by the inverse distance. The radius is [`FEATURE_RADIUS`] of the model's
//!   diagonal in the model and that over the scale guess in the scan.
//! - **RANSAC**: [`RANSAC_TRIALS`] triples of correspondences (each scan point with its
//!   nearest model descriptor), kept when the three distance ratios agree within 10% and
//!   lie within a factor 2 of the scale guess; the similarity of the triple
//!   ([`match_pairs`], least squares) is scored by the correspondences it maps within
//!   [`INLIER_FRACTION`] of the diagonal; the best distinct poses are returned.

use crate::cloud::{bbox_diagonal, centroid};
use crate::geometry::Pose;
use crate::nn::NearestNeighbours;
use crate::pf_icp::hypotheses::same_pose;
use crate::registration::svd_match::{match_pairs_within, ScaleRule};
use nalgebra::{Point3, Vector3};
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

/// Points of each cloud the descriptors are computed on.
pub const FEATURE_POINTS: usize = 600;
/// Descriptor radius, as a fraction of the model's diagonal.
pub const FEATURE_RADIUS: f64 = 0.15;
/// RANSAC triples.
pub const RANSAC_TRIALS: usize = 4000;
/// Inlier distance of a correspondence, as a fraction of the model's diagonal.
pub const INLIER_FRACTION: f64 = 0.03;
/// Proposals returned.
pub const PROPOSALS: usize = 12;

const BINS: usize = 11;
const NORMAL_NEIGHBOURS: usize = 12;
const RADIUS_NEIGHBOURS: usize = 48;

/// A subsampled cloud with normals and FPFH descriptors.
struct Described {
    points: Vec<Point3<f64>>,
    descriptors: Vec<[f64; 3 * BINS]>,
}

fn subsample(points: &[Point3<f64>], n: usize, rng: &mut ChaCha8Rng) -> Vec<Point3<f64>> {
    if points.len() <= n {
        return points.to_vec();
    }
    points.choose_multiple(rng, n).copied().collect()
}

fn bin(x: f64, lo: f64, hi: f64) -> usize {
    (((x - lo) / (hi - lo) * BINS as f64).floor().max(0.0) as usize).min(BINS - 1)
}

fn describe(points: Vec<Point3<f64>>, radius: f64) -> Described {
    let nn = NearestNeighbours::new(&points);
    let c = centroid(&points);
    let near: Vec<Vec<(usize, f64)>> = points
        .par_iter()
        .map(|p| {
            nn.nearest_k(p, RADIUS_NEIGHBOURS)
                .into_iter()
                .skip(1)
                .filter(|q| q.dist2 <= radius * radius)
                .map(|q| (q.index, q.dist2.sqrt()))
                .collect()
        })
        .collect();
    let normals: Vec<Vector3<f64>> = points
        .par_iter()
        .map(|p| {
            let idx: Vec<usize> = nn.nearest_k(p, NORMAL_NEIGHBOURS).into_iter().map(|q| q.index).collect();
            let nb: Vec<Point3<f64>> = idx.iter().map(|&i| points[i]).collect();
            let n = crate::pf_icp::surface::least_axis(&nb);
            if n.dot(&(p - c)) < 0.0 {
                -n
            } else {
                n
            }
        })
        .collect();
    let spfh: Vec<[f64; 3 * BINS]> = (0..points.len())
        .into_par_iter()
        .map(|i| {
            let mut h = [0.0; 3 * BINS];
            let (p, u) = (points[i], normals[i]);
            for &(j, d) in &near[i] {
                let dq = (points[j] - p) / d.max(1e-300);
                let v = u.cross(&dq);
                if v.norm() < 1e-12 {
                    continue;
                }
                let v = v.normalize();
                let w = u.cross(&v);
                let nq = normals[j];
                h[bin(v.dot(&nq), -1.0, 1.0)] += 1.0;
                h[BINS + bin(u.dot(&dq), -1.0, 1.0)] += 1.0;
                h[2 * BINS + bin(w.dot(&nq).atan2(u.dot(&nq)), -std::f64::consts::PI, std::f64::consts::PI)] += 1.0;
            }
            let total = near[i].len().max(1) as f64;
            h.iter_mut().for_each(|x| *x /= total);
            h
        })
        .collect();
    let descriptors = (0..points.len())
        .into_par_iter()
        .map(|i| {
            let mut f = spfh[i];
            let k = near[i].len().max(1) as f64;
            for &(j, d) in &near[i] {
                let w = 1.0 / (k * d.max(1e-9 * radius) / radius);
                for b in 0..3 * BINS {
                    f[b] += w * spfh[j][b];
                }
            }
            let s: f64 = f.iter().sum::<f64>().max(1e-300);
            f.iter_mut().for_each(|x| *x /= s);
            f
        })
        .collect();
    Described { points, descriptors }
}

fn nearest_descriptor(d: &[f64; 3 * BINS], set: &[[f64; 3 * BINS]]) -> usize {
    let mut best = (f64::INFINITY, 0);
    for (i, e) in set.iter().enumerate() {
        let dist: f64 = d.iter().zip(e).map(|(a, b)| (a - b) * (a - b)).sum();
        if dist < best.0 {
            best = (dist, i);
        }
    }
    best.1
}

/// Start poses from feature correspondences between `scan` and the model behind `nn`,
/// best first (at most [`PROPOSALS`]); `scale_guess` is a rough scale (scan to model), and
/// every proposal's scale lies in `bounds`.
pub fn proposals(
    nn: &NearestNeighbours,
    scan: &[Point3<f64>],
    scale_guess: f64,
    seed: u64,
    bounds: &crate::geometry::ScaleBounds,
) -> Vec<Pose> {
    let scale_guess = bounds.clamp(scale_guess);
    let diag = bbox_diagonal(nn.points());
    if diag.is_nan() || diag <= 0.0 || scale_guess.is_nan() || scale_guess <= 0.0 || scan.len() < 10 {
        return Vec::new();
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x6670_6668);
    let model_pts = subsample(nn.points(), FEATURE_POINTS, &mut rng);
    let scan_pts = subsample(scan, FEATURE_POINTS, &mut rng);
    let radius = FEATURE_RADIUS * diag;
    let (model, scan_d) = rayon::join(|| describe(model_pts, radius), || describe(scan_pts, radius / scale_guess));
    let pairs: Vec<(usize, usize)> = scan_d
        .descriptors
        .par_iter()
        .enumerate()
        .map(|(i, d)| (i, nearest_descriptor(d, &model.descriptors)))
        .collect();
    if pairs.len() < 3 {
        return Vec::new();
    }
    let tau2 = (INLIER_FRACTION * diag).powi(2);
    let (src, dst): (Vec<Point3<f64>>, Vec<Point3<f64>>) =
        pairs.iter().map(|&(i, j)| (scan_d.points[i], model.points[j])).unzip();
    // Triples drawn sequentially (deterministic), scored in parallel.
    let triples: Vec<[usize; 3]> = (0..RANSAC_TRIALS)
        .map(|_| {
            let a = rng.gen_range(0..pairs.len());
            let b = rng.gen_range(0..pairs.len());
            let c = rng.gen_range(0..pairs.len());
            [a, b, c]
        })
        .collect();
    let mut scored: Vec<(usize, Pose)> = triples
        .par_iter()
        .filter_map(|&[a, b, c]| {
            if a == b || b == c || a == c {
                return None;
            }
            let ratio = |x: usize, y: usize| {
                let m = (src[x] - src[y]).norm();
                if m > 1e-12 {
                    Some((dst[x] - dst[y]).norm() / m)
                } else {
                    None
                }
            };
            let r = [ratio(a, b)?, ratio(b, c)?, ratio(a, c)?];
            let (lo, hi) = (r.iter().cloned().fold(f64::INFINITY, f64::min), r.iter().cloned().fold(0.0, f64::max));
            if hi > 1.1 * lo || lo < 0.5 * scale_guess || hi > 2.0 * scale_guess {
                return None;
            }
            let pose = match_pairs_within(
                &[src[a], src[b], src[c]],
                &[dst[a], dst[b], dst[c]],
                None,
                ScaleRule::LeastSquares,
                bounds,
            )?;
            let inliers = (0..src.len()).filter(|&k| (pose.apply(&src[k]) - dst[k]).norm_squared() <= tau2).count();
            Some((inliers, pose))
        })
        .collect();
    scored.sort_by_key(|x| std::cmp::Reverse(x.0));
    let at = centroid(scan);
    let mut out: Vec<Pose> = Vec::new();
    for (_, p) in scored {
        if out.len() >= PROPOSALS {
            break;
        }
        if !out.iter().any(|q| same_pose(q, &p, &at, diag)) {
            out.push(p);
        }
    }
    out
}
