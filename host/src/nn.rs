//! Nearest-neighbour search over a model cloud (the closest-point operator `C(M, D)` of Eq. 2).

use kiddo::immutable::float::kdtree::ImmutableKdTree;
use kiddo::SquaredEuclidean;
use nalgebra::Point3;
use rayon::prelude::*;

/// Below this many queries, a batch runs on one thread.
const PARALLEL_MIN: usize = 512;

/// A k-d tree over the model points (kiddo's immutable tree).
pub struct NearestNeighbours {
    tree: ImmutableKdTree<f64, u32, 3, 32>,
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
            tree: ImmutableKdTree::new_from_slice(&raw),
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
        let nn = self.tree.nearest_one::<SquaredEuclidean>(&[q.x, q.y, q.z]);
        Closest {
            index: nn.item as usize,
            dist2: nn.distance,
        }
    }

    /// Closest model point to each query, in order (parallel for large batches).
    pub fn closest_all(&self, queries: &[Point3<f64>]) -> Vec<Closest> {
        if queries.len() < PARALLEL_MIN {
            queries.iter().map(|q| self.closest(q)).collect()
        } else {
            queries.par_iter().map(|q| self.closest(q)).collect()
        }
    }

    /// Sum of squared closest-point distances of the queries (Eq. 3 with fixed pose).
    pub fn sum_dist2(&self, queries: &[Point3<f64>]) -> f64 {
        if queries.len() < PARALLEL_MIN {
            queries.iter().map(|q| self.closest(q).dist2).sum()
        } else {
            queries.par_iter().map(|q| self.closest(q).dist2).sum()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    #[test]
    fn matches_brute_force() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let mut pt = || {
            Point3::new(
                rng.gen_range(-1.0..1.0),
                rng.gen_range(-1.0..1.0),
                rng.gen_range(-1.0..1.0),
            )
        };
        let model: Vec<_> = (0..500).map(|_| pt()).collect();
        let queries: Vec<_> = (0..700).map(|_| pt()).collect();
        let nn = NearestNeighbours::new(&model);
        for (q, c) in queries.iter().zip(nn.closest_all(&queries)) {
            let best = model
                .iter()
                .map(|m| (m - q).norm_squared())
                .fold(f64::INFINITY, f64::min);
            assert!((best - c.dist2).abs() < 1e-12);
            assert!(((model[c.index] - q).norm_squared() - best).abs() < 1e-12);
        }
    }
}
