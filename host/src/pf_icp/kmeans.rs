//! K-means clustering (k-means++ start, Lloyd iterations) and cluster pairing
//! (Algorithm 4).
//!
//! Clusters come back in *sequential order*: sorted by the lowest point index among their
//! members (the paper's `Sequential_Sort`). When the scan is the model's own points in the
//! same order (the paper's setting) and both clouds are clustered with the same seed,
//! k-means++ picks the same seed indices (its D^2 probabilities do not change under a
//! similarity) and Lloyd's iterations commute with the similarity, so cluster `i` of the
//! scan pairs with cluster `i` of the model: [`Pairing::Index`].

use nalgebra::Point3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

/// Clusters of one cloud.
#[derive(Clone, Debug)]
pub struct Clustering {
    /// Centroid of each cluster.
    pub centroids: Vec<Point3<f64>>,
    /// Cluster of each point.
    pub labels: Vec<usize>,
    /// Member point indices of each cluster (ascending).
    pub members: Vec<Vec<usize>>,
}

/// Settings for [`kmeans`].
#[derive(Clone, Copy, Debug)]
pub struct KmeansSettings {
    /// Number of clusters `K` (clamped to the number of points).
    pub k: usize,
    /// Lloyd iteration cap.
    pub max_iterations: usize,
    /// Seed of the k-means++ start.
    pub seed: u64,
}

fn nearest(centroids: &[Point3<f64>], p: &Point3<f64>) -> (usize, f64) {
    let mut best = (0, f64::INFINITY);
    for (j, c) in centroids.iter().enumerate() {
        let d = (c - p).norm_squared();
        if d < best.1 {
            best = (j, d);
        }
    }
    best
}

/// Cluster `points` (non-empty) into `settings.k` clusters, none empty.
pub fn kmeans(points: &[Point3<f64>], settings: &KmeansSettings) -> Clustering {
    let n = points.len();
    let k = settings.k.clamp(1, n);
    let mut rng = ChaCha8Rng::seed_from_u64(settings.seed);
    // k-means++ seeding.
    let mut centroids = Vec::with_capacity(k);
    centroids.push(points[rng.gen_range(0..n)]);
    let mut d2: Vec<f64> = points.iter().map(|p| (p - centroids[0]).norm_squared()).collect();
    while centroids.len() < k {
        let total: f64 = d2.iter().sum();
        let pick = if total > 0.0 {
            let mut u = rng.gen_range(0.0..total);
            let mut idx = n - 1;
            for (i, &d) in d2.iter().enumerate() {
                if u < d {
                    idx = i;
                    break;
                }
                u -= d;
            }
            idx
        } else {
            rng.gen_range(0..n)
        };
        let c = points[pick];
        centroids.push(c);
        for (d, p) in d2.iter_mut().zip(points) {
            *d = d.min((p - c).norm_squared());
        }
    }
    // Lloyd iterations.
    let mut labels = vec![usize::MAX; n];
    for _ in 0..settings.max_iterations.max(1) {
        let next: Vec<usize> = points.par_iter().map(|p| nearest(&centroids, p).0).collect();
        let changed = next != labels;
        labels = next;
        let mut sums = vec![nalgebra::Vector3::zeros(); k];
        let mut counts = vec![0usize; k];
        for (p, &l) in points.iter().zip(&labels) {
            sums[l] += p.coords;
            counts[l] += 1;
        }
        for j in 0..k {
            if counts[j] > 0 {
                centroids[j] = Point3::from(sums[j] / counts[j] as f64);
            } else {
                // Re-seed an empty cluster at the point farthest from its centroid.
                let far = (0..n)
                    .max_by(|&a, &b| {
                        let da = (points[a] - centroids[labels[a]]).norm_squared();
                        let db = (points[b] - centroids[labels[b]]).norm_squared();
                        da.total_cmp(&db)
                    })
                    .unwrap_or(0);
                centroids[j] = points[far];
                labels[far] = j;
            }
        }
        if !changed {
            break;
        }
    }
    sequential_sort(points, centroids, labels)
}

/// Seed offset of [`kmeans_sampled`]'s subset (the k-means++ start keeps the plain seed).
const SUBSET_SEED: u64 = 0x6b6d_5375_6273_6574;

/// [`kmeans`] on a seeded random subset of at most `sample` points of a larger cloud (all
/// of them, exactly [`kmeans`], when it has no more), then every point assigned to its
/// nearest centroid: `labels` and `members` cover the whole cloud, each centroid is the
/// mean of its members, and the clusters keep the subset's sequential order (two clouds of
/// the same size draw the same subset, so [`Pairing::Index`] still pairs the paper's
/// setting). Cost `O(sample K iterations + n log K)` instead of `O(n K iterations)`.
pub fn kmeans_sampled(points: &[Point3<f64>], settings: &KmeansSettings, sample: usize) -> Clustering {
    let n = points.len();
    if n <= sample.max(1) {
        return kmeans(points, settings);
    }
    let mut rng = ChaCha8Rng::seed_from_u64(settings.seed ^ SUBSET_SEED);
    let mut idx = rand::seq::index::sample(&mut rng, n, sample.max(1)).into_vec();
    idx.sort_unstable();
    let subset: Vec<Point3<f64>> = idx.iter().map(|&i| points[i]).collect();
    let coarse = kmeans(&subset, settings);
    let tree = crate::nn::NearestNeighbours::new(&coarse.centroids);
    let labels: Vec<usize> = points.par_iter().map(|p| tree.closest(p).index).collect();
    let k = coarse.centroids.len();
    let mut members = vec![Vec::new(); k];
    for (i, &l) in labels.iter().enumerate() {
        members[l].push(i);
    }
    // A cluster that no point is nearest to any more is dropped (order otherwise kept).
    let kept: Vec<usize> = (0..k).filter(|&j| !members[j].is_empty()).collect();
    let mut relabel = vec![0; k];
    for (new, &old) in kept.iter().enumerate() {
        relabel[old] = new;
    }
    let members: Vec<Vec<usize>> = kept.iter().map(|&j| std::mem::take(&mut members[j])).collect();
    let centroids = members
        .par_iter()
        .map(|m| Point3::from(m.iter().fold(nalgebra::Vector3::zeros(), |a, &i| a + points[i].coords) / m.len() as f64))
        .collect();
    Clustering { centroids, labels: labels.iter().map(|&l| relabel[l]).collect(), members }
}

/// Order clusters by their lowest member index and drop any that ended empty.
fn sequential_sort(points: &[Point3<f64>], centroids: Vec<Point3<f64>>, labels: Vec<usize>) -> Clustering {
    let k = centroids.len();
    let mut members = vec![Vec::new(); k];
    for (i, &l) in labels.iter().enumerate() {
        members[l].push(i);
    }
    let mut order: Vec<usize> = (0..k).filter(|&j| !members[j].is_empty()).collect();
    order.sort_by_key(|&j| members[j][0]);
    let mut relabel = vec![0; k];
    for (new, &old) in order.iter().enumerate() {
        relabel[old] = new;
    }
    let members: Vec<Vec<usize>> = order.iter().map(|&j| std::mem::take(&mut members[j])).collect();
    let centroids =
        members.iter().map(|m| crate::cloud::centroid(&m.iter().map(|&i| points[i]).collect::<Vec<_>>())).collect();
    Clustering { centroids, labels: labels.iter().map(|&l| relabel[l]).collect(), members }
}

/// How clusters of the scan are paired with clusters of the model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pairing {
    /// Cluster `i` with cluster `i` (the paper's setting: same points, same order).
    Index,
    /// Each scan centroid with the nearest model centroid under a current pose estimate
    /// (scans sampled independently of the model).
    Nearest,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Pose;

    fn blobs() -> Vec<Point3<f64>> {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let centres = [Point3::new(0.0, 0.0, 0.0), Point3::new(5.0, 0.0, 0.0), Point3::new(0.0, 5.0, 1.0)];
        (0..300)
            .map(|i| {
                let c = centres[i % 3];
                c + nalgebra::Vector3::new(rng.gen_range(-0.5..0.5), rng.gen_range(-0.5..0.5), rng.gen_range(-0.5..0.5))
            })
            .collect()
    }

    #[test]
    fn finds_separated_blobs_and_sorts_sequentially() {
        let pts = blobs();
        let c = kmeans(&pts, &KmeansSettings { k: 3, max_iterations: 50, seed: 1 });
        assert_eq!(c.members.len(), 3);
        for (j, m) in c.members.iter().enumerate() {
            assert_eq!(m.len(), 100);
            assert!(m.iter().all(|&i| i % 3 == j), "cluster {j} mixes blobs");
        }
        assert!(c.members.windows(2).all(|w| w[0][0] < w[1][0]));
    }

    #[test]
    fn clustering_commutes_with_a_similarity() {
        let pts = blobs();
        let pose = Pose::from_params(&[1.0, -2.0, 0.5, 0.7, 0.3, -0.2, 1.0]);
        let moved = pose.apply_all(&pts);
        let s = KmeansSettings { k: 20, max_iterations: 100, seed: 42 };
        let a = kmeans(&pts, &s);
        let b = kmeans(&moved, &s);
        assert_eq!(a.labels, b.labels);
        for (ca, cb) in a.centroids.iter().zip(&b.centroids) {
            assert!((pose.apply(ca) - cb).norm() < 1e-9);
        }
    }

    #[test]
    fn a_sampled_clustering_covers_every_point_and_commutes_with_a_similarity() {
        let pts: Vec<Point3<f64>> = (0..20).flat_map(|_| blobs()).collect();
        let s = KmeansSettings { k: 3, max_iterations: 50, seed: 1 };
        let c = kmeans_sampled(&pts, &s, 500);
        assert_eq!(c.labels.len(), pts.len());
        assert_eq!(c.members.iter().map(Vec::len).sum::<usize>(), pts.len());
        for (j, m) in c.members.iter().enumerate() {
            assert!(m.windows(2).all(|w| w[0] < w[1]));
            assert!(m.iter().all(|&i| c.labels[i] == j && i % 3 == m[0] % 3), "cluster {j} mixes blobs");
        }
        let pose = Pose::from_params(&[1.0, -2.0, 0.5, 0.7, 0.3, -0.2, 1.0]);
        let b = kmeans_sampled(&pose.apply_all(&pts), &s, 500);
        assert_eq!(c.labels, b.labels);
        // At most `sample` points: exactly `kmeans`.
        let small = kmeans_sampled(&pts[..400], &s, 500);
        assert_eq!(small.labels, kmeans(&pts[..400], &s).labels);
    }

    #[test]
    fn more_clusters_than_points_is_clamped() {
        let pts = blobs()[..5].to_vec();
        let c = kmeans(&pts, &KmeansSettings { k: 50, max_iterations: 10, seed: 0 });
        assert!(c.members.len() <= 5);
        assert_eq!(c.labels.len(), 5);
    }
}
