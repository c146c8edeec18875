use pficp::datasets::*;
use pficp::geometry::*;
use pficp::icp::*;
use pficp::nn::NearestNeighbours;
fn main() {
    for id in [ModelId::Model1, ModelId::Model2, ModelId::Model3] {
        let truth = id.table1_truth();
        let ds = make(id, 2000, &truth, &ScanSpec { sampling: Sampling::Paper, noise: 0.0, seed: 1 });
        let nn = NearestNeighbours::new(&ds.model);
        println!("{} diag {:.3} truth {:?}", id.name(), pficp::cloud::bbox_diagonal(&ds.model), truth.euler_deg());
        for (name, s) in [("icp", IcpSettings::default()), ("welsch", IcpSettings::welsch()), ("cauchy", IcpSettings::cauchy())] {
            let r = icp(&nn, &ds.scan, &Pose::identity(), &s);
            let p = r.pose.to_params();
            println!("  {name:7} euler {:?} t [{:.3} {:.3} {:.3}] s {:.4} msd {:.5} it {}", r.pose.euler_deg().map(|x| (x*100.0).round()/100.0), p[0], p[1], p[2], p[3], r.msd, r.iterations);
        }
        // cost landscape in psi around truth
        let mut line = String::new();
        for dpsi in (-180..=180).step_by(15) {
            let mut q = truth.to_params();
            q[6] += (dpsi as f64).to_radians();
            let pose = Pose::from_params(&q);
            let r = icp(&nn, &ds.scan, &pose, &IcpSettings{max_iterations: 30, scale: pficp::svd_match::ScaleRule::Ratio, ..Default::default()});
            line += &format!("{dpsi}:{:.3}/{:.0} ", r.msd, r.pose.euler_deg()[2]-truth.euler_deg()[2]);
        }
        println!("  psi-drift -> icp msd/psi err: {line}");
    }
}
