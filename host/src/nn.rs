//! Nearest-neighbour search over a model cloud (the closest-point operator `C(M, D)` of Eq. 2).

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use nalgebra::Point3;
use rayon::prelude::*;
use std::num::NonZeroUsize;

/// Below this many queries, a batch runs on one thread.
const PARALLEL_MIN: usize = 512;

/// A k-d tree over the model points (kiddo's immutable tree).
pub struct NearestNeighbours {
    tree: ImmutableKdTree<f64, 3>,
    points: Vec<Point3<f64>>,
}

/// One closest-point answer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Closest {
    /// Index of the model point.
    pub index: usize,
    /// Squared Euclidean distance.
    pub dist2: f64,
}

impl NearestNeighbours {
    /// Build the tree over `points` (must be non-empty).
    pub fn new(points: &[Point3<f64>]) -> Self {
        let raw: Vec<[f64; 3]> = points.iter().map(|p| [p.x, p.y, p.z]).collect();
        Self {
            tree: ImmutableKdTree::new_from_slice(&raw)
                .expect("k-d tree construction over a validated, non-empty cloud"),
            points: points.to_vec(),
        }
    }

    /// The model points, in their original order.
    pub fn points(&self) -> &[Point3<f64>] {
        &self.points
    }

    /// Closest model point to `q`.
    #[inline]
    pub fn closest(&self, q: &Point3<f64>) -> Closest {
        let nn = self.tree.query(&[q.x, q.y, q.z]).nearest_one::<SquaredEuclidean<f64>>().execute();
        Closest { index: nn.item as usize, dist2: nn.distance }
    }

    /// Closest model point to each query, in order (parallel for large batches).
    pub fn closest_all(&self, queries: &[Point3<f64>]) -> Vec<Closest> {
        if queries.len() < PARALLEL_MIN {
            queries.iter().map(|q| self.closest(q)).collect()
        } else {
            queries.par_iter().map(|q| self.closest(q)).collect()
        }
    }

    /// The `k` closest model points to `q`, nearest first (all of them if the model has
    /// fewer than `k`; empty for `k = 0`).
    pub fn nearest_k(&self, q: &Point3<f64>, k: usize) -> Vec<Closest> {
        if k == 0 {
            return Vec::new();
        }
        let k = NonZeroUsize::new(k.min(self.points.len())).expect("k >= 1 and a non-empty model");
        self.tree
            .query(&[q.x, q.y, q.z])
            .nearest_n::<SquaredEuclidean<f64>>(k)
            .execute()
            .into_iter()
            .map(|nn| Closest { index: nn.item as usize, dist2: nn.distance })
            .collect()
    }

    /// Sum of squared closest-point distances of the queries (Eq. 3 with fixed pose).
    pub fn sum_dist2(&self, queries: &[Point3<f64>]) -> f64 {
        if queries.len() < PARALLEL_MIN {
            queries.iter().map(|q| self.closest(q).dist2).sum()
        } else {
            // Distances in parallel, the sum in order: a parallel float sum's order (and so
            // its rounding) would depend on the threads' scheduling.
            let d: Vec<f64> = queries.par_iter().map(|q| self.closest(q).dist2).collect();
            d.iter().sum()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    #[test]
    fn grid_with_repeated_coordinates() {
        let model: Vec<_> = (0..60).flat_map(|i| (0..40).map(move |j| Point3::new(i as f64, j as f64, 0.0))).collect();
        let nn = NearestNeighbours::new(&model);
        let c = nn.closest(&Point3::new(10.2, 20.9, 0.5));
        assert_eq!(model[c.index], Point3::new(10.0, 21.0, 0.0));
        let k = nn.nearest_k(&Point3::new(10.2, 20.9, 0.0), 3);
        assert_eq!(k.len(), 3);
        assert!(k.windows(2).all(|w| w[0].dist2 <= w[1].dist2));
    }

    #[test]
    fn matches_brute_force() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let mut pt = || Point3::new(rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0));
        let model: Vec<_> = (0..500).map(|_| pt()).collect();
        let queries: Vec<_> = (0..700).map(|_| pt()).collect();
        let nn = NearestNeighbours::new(&model);
        for (q, c) in queries.iter().zip(nn.closest_all(&queries)) {
            let best = model.iter().map(|m| (m - q).norm_squared()).fold(f64::INFINITY, f64::min);
            assert!((best - c.dist2).abs() < 1e-12);
            assert!(((model[c.index] - q).norm_squared() - best).abs() < 1e-12);
        }
    }

    #[test]
    fn nearest_k_matches_brute_force() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let model: Vec<_> = (0..300)
            .map(|_| Point3::new(rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0)))
            .collect();
        let nn = NearestNeighbours::new(&model);
        let q = Point3::new(0.1, -0.2, 0.3);
        let mut d: Vec<f64> = model.iter().map(|m| (m - q).norm_squared()).collect();
        d.sort_by(|a, b| a.total_cmp(b));
        let k = nn.nearest_k(&q, 8);
        assert_eq!(k.len(), 8);
        for (c, &b) in k.iter().zip(&d) {
            assert!((c.dist2 - b).abs() < 1e-12);
            assert!(((model[c.index] - q).norm_squared() - c.dist2).abs() < 1e-12);
        }
        assert_eq!(nn.nearest_k(&q, 1000).len(), 300);
        assert!(nn.nearest_k(&q, 0).is_empty());
    }
}
