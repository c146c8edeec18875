use pficp::datasets::*;
use pficp::nn::NearestNeighbours;
use pficp::pf_icp::*;
use rand::SeedableRng;
fn main() {
    let id = ModelId::Model1;
    let model = id.model_points(2000);
    let diag = pficp::cloud::bbox_diagonal(&model);
    let nn = NearestNeighbours::new(&model);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(77);
    let want: usize = std::env::args().nth(1).unwrap().parse().unwrap();
    for i in 0..=want {
        let truth = random_truth(&mut rng, 45.0, (0.7, 1.3), diag / 2.0);
        if i != want { continue; }
        let ds = make(id, 2000, &truth, &ScanSpec { sampling: Sampling::Independent { points: 2000 }, noise: 0.0, seed: 100 + i as u64 });
        let r = register(&nn, &ds.scan, &PfIcpSettings { seed: i as u64, ..Default::default() });
        println!("truth {:?}", truth.to_params());
        println!("init  {:?}", r.initial.pose.to_params());
        println!("cov sd {:?}", r.covariance.std_dev());
        println!("q {:e} msdmean {:e}", r.covariance.msd_variance, r.covariance.msd_mean);
        for h in &r.filter_history { println!("{:?}", h); }
        println!("final {:?} ang {:.2}", r.registration.pose.to_params(), r.registration.pose.rotation_angle_to(&truth).to_degrees());
        println!("truth cost {:e}", pficp::icp::msd(&nn, &ds.scan, &truth));
    }
}
