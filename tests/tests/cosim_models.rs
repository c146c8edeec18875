//! Subsets of the paper's models 1 to 3 through the Verilated pipeline (16 lanes) in
//! lockstep with the reference, every clock; each cost also tracks the host's f64 cost
//! within the documented bound (docs/fixed-point.md).

use nalgebra::Point3;
use pficp::board::fixed::{cost_error_bound, normalised_pose, quantise_pose, Normalisation};
use pficp::datasets::{make, ModelId, Sampling, ScanSpec};
use pficp::geometry::Pose;
use pficp::nn::NearestNeighbours;
use pficp_fpga::format::dist_to_f64;
use pficp_fpga::pipeline::evaluate;
use pficp_sim::Lockstep;

#[test]
fn model_subsets_in_lockstep() {
    let mut total_clocks = 0;
    let mut ls = Lockstep::new(16);
    for id in ModelId::ALL {
        let truth = id.table1_truth();
        let ds =
            make(id, 1024, &truth, &ScanSpec { sampling: Sampling::Independent { points: 200 }, noise: 0.0, seed: 5 });
        let (nm, nd) = (Normalisation::of(&ds.scan), Normalisation::of(&ds.model));
        let (scan_q, model_q) = (nm.quantise(&ds.scan), nd.quantise(&ds.model));
        let model_n: Vec<Point3<f64>> = ds.model.iter().map(|p| Point3::from((p - nd.centre) / nd.radius)).collect();
        let scan_n: Vec<Point3<f64>> = ds.scan.iter().map(|p| Point3::from((p - nm.centre) / nm.radius)).collect();
        let nn = NearestNeighbours::new(&model_n);
        ls.load_model(&model_q).unwrap_or_else(|m| panic!("{}: {m}", id.name()));
        let mut p = truth.to_params();
        for k in 0..3 {
            p[6] += 0.05 * k as f64;
            p[0] -= 0.02 * k as f64;
            let pn = normalised_pose(&Pose::from_params(&p), &nm, &nd);
            let fx = quantise_pose(&pn);
            let (got, _) = ls
                .particle(model_q.len(), &scan_q, &fx, |c| c % 5 == 0)
                .unwrap_or_else(|m| panic!("{} particle {k}: {m}", id.name()));
            assert_eq!(got, evaluate(&model_q, &scan_q, &fx), "{} particle {k}", id.name());
            let d: Vec<f64> = pn.apply_all(&scan_n).iter().map(|x| nn.closest(x).dist2.sqrt()).collect();
            let exact: f64 = d.iter().map(|x| x * x).sum();
            let fixed = dist_to_f64(got.cost);
            assert!(
                (fixed - exact).abs() <= cost_error_bound(&d, pn.scale),
                "{} particle {k}: {fixed} vs {exact}",
                id.name()
            );
        }
    }
    total_clocks += ls.clocks_compared();
    eprintln!("models 1-3 subsets: {total_clocks} clocks compared in lockstep (P = 16)");
    assert!(total_clocks > 100_000);
}
