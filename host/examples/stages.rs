use pficp::datasets::*;
use pficp::nn::NearestNeighbours;
use pficp::pf_icp::*;
fn main() {
    let id = ModelId::Model1;
    let truth = id.table1_truth();
    for sampling in [Sampling::Paper, Sampling::Independent { points: 2000 }] {
        let ds = make(id, 2000, &truth, &ScanSpec { sampling, noise: 0.0, seed: 1 });
        for run in 0..3 {
            let t = std::time::Instant::now();
            let nn = NearestNeighbours::new(&ds.model);
            let r = register(&nn, &ds.scan, &PfIcpSettings { seed: run, ..Default::default() });
            println!("{:?} total {:.3} {:?} iters {}", sampling, t.elapsed().as_secs_f64(), r.times, r.registration.iterations);
        }
    }
}
