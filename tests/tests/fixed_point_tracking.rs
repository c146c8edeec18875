//! The fixed-point pipeline tracks the host's f64 computation within the bound documented
//! in docs/fixed-point.md, on the paper's models: costs (sums of nearest squared
//! distances) and particle weights.

use nalgebra::Point3;
use pficp::board::quantise::{cost_error_bound, normalised_pose, quantise_pose, Normalisation};
use pficp::datasets::{make, ModelId, Sampling, ScanSpec};
use pficp::geometry::Pose;
use pficp::nn::NearestNeighbours;
use pficp_fpga::common::format::{dist_to_f64, exp_table, WeightScale, DIST_FRAC};
use pficp_fpga::search::pipeline::evaluate;

/// Poses around the truth, as a particle filter would propose them.
fn particles(truth: &Pose, count: usize) -> Vec<Pose> {
    let p = truth.to_params();
    (0..count)
        .map(|k| {
            let f = k as f64 / count as f64 - 0.5;
            let mut q = p;
            q[0] += 0.05 * f;
            q[2] -= 0.03 * f;
            q[3] *= 1.0 + 0.02 * f;
            q[4] += (3.0 * f).to_radians();
            q[6] -= (5.0 * f).to_radians();
            Pose::from_params(&q)
        })
        .collect()
}

#[test]
fn costs_and_weights_track_f64() {
    for id in ModelId::ALL {
        for sampling in [Sampling::Paper, Sampling::Independent { points: 300 }] {
            let truth = id.table1_truth();
            let ds = make(id, 600, &truth, &ScanSpec { sampling, noise: 0.0, seed: 3 });
            let scan = if ds.scan.len() > 300 { ds.scan[..300].to_vec() } else { ds.scan.clone() };
            let (nm, nd) = (Normalisation::of(&scan), Normalisation::of(&ds.model));
            let (scan_q, model_q) = (nm.quantise(&scan), nd.quantise(&ds.model));
            let model_n: Vec<Point3<f64>> =
                ds.model.iter().map(|p| Point3::from((p - nd.centre) / nd.radius)).collect();
            let scan_n: Vec<Point3<f64>> = scan.iter().map(|p| Point3::from((p - nm.centre) / nm.radius)).collect();
            let nn = NearestNeighbours::new(&model_n);
            let mut exact = Vec::new();
            let mut fixed = Vec::new();
            for pose in particles(&truth, 12) {
                let pn = normalised_pose(&pose, &nm, &nd);
                let d: Vec<f64> = pn.apply_all(&scan_n).iter().map(|x| nn.closest(x).dist2.sqrt()).collect();
                let c_exact: f64 = d.iter().map(|x| x * x).sum();
                let c_fixed = dist_to_f64(evaluate(&model_q, &scan_q, &quantise_pose(&pn)).cost);
                let bound = cost_error_bound(&d, pn.scale);
                assert!(
                    (c_fixed - c_exact).abs() <= bound,
                    "{} {sampling:?}: fixed {c_fixed} exact {c_exact} bound {bound}",
                    id.name()
                );
                exact.push((c_exact, bound));
                fixed.push(c_fixed);
            }
            // Weights: exp(-(c - c_min) / 2Q) by the table against f64, 2Q = median excess / 3.
            let cmin = exact.iter().map(|e| e.0).fold(f64::INFINITY, f64::min);
            let mut excess: Vec<f64> = exact.iter().map(|e| e.0 - cmin).collect();
            excess.sort_by(f64::total_cmp);
            let two_q = (excess[excess.len() / 2] / 3.0).max(1e-9);
            let lsb = (1u64 << DIST_FRAC) as f64;
            let scale = WeightScale::for_two_q(two_q * lsb);
            let table = exp_table();
            let fmin = fixed.iter().copied().fold(f64::INFINITY, f64::min);
            for (k, (&(c, bound), &cf)) in exact.iter().zip(&fixed).enumerate() {
                let w_exact = (-(c - cmin) / two_q).exp();
                let excess_fixed = ((cf - fmin) * lsb).round() as u64;
                let w_fixed = table[scale.index(excess_fixed)] as f64 / 65535.0;
                // Table step (1/32 e-fold), the cost error of both costs, q_mul rounding, table tail.
                let exponent_err = 1.0 / 32.0 + 2.0 * 2.0 * bound / two_q + 1e-3;
                let tol = w_exact * (exponent_err.exp() - 1.0) + 1.0 / 65535.0 + (-255.0f64 / 32.0).exp();
                assert!(
                    (w_fixed - w_exact).abs() <= tol,
                    "{} {sampling:?} particle {k}: weight {w_fixed} vs {w_exact} (tol {tol})",
                    id.name()
                );
            }
        }
    }
}
