use pficp::datasets::*;
use pficp::geometry::*;
use pficp::nn::NearestNeighbours;
use pficp::pf_icp::*;
use rand::SeedableRng;
fn ok(est: &Pose, truth: &Pose, diag: f64) -> (bool, f64, f64, f64) {
    let ang = est.rotation_angle_to(truth).to_degrees();
    let dt = (est.translation - truth.translation).norm() / diag;
    let ds = (est.scale / truth.scale - 1.0).abs();
    (ang < 2.0 && dt < 0.02 && ds < 0.01, ang, dt, ds)
}
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let trials: usize = args.get(1).map(|s| s.parse().unwrap()).unwrap_or(20);
    let noise_frac: f64 = args.get(2).map(|s| s.parse().unwrap()).unwrap_or(0.0);
    for id in ModelId::ALL.into_iter().filter(|m| std::env::var("ONLY").map(|o| m.name() == o).unwrap_or(true)) {
        let np: usize = std::env::var("NP").map(|v| v.parse().unwrap()).unwrap_or(2000); let model = id.model_points(np);
        let diag = pficp::cloud::bbox_diagonal(&model);
        // paper setting
        let truth = id.table1_truth();
        let ds = make(id, 2000, &truth, &ScanSpec { sampling: Sampling::Paper, noise: 0.0, seed: 1 });
        let nn = NearestNeighbours::new(&ds.model);
        let t = std::time::Instant::now();
        let r = register(&nn, &ds.scan, &PfIcpSettings::default());
        println!("{} paper: {:?} {:.2?} init {:?}", id.name(), ok(&r.registration.pose, &truth, diag), t.elapsed(), r.initial.pairing);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(77);
        let mut succ = 0;
        let mut init_ok = 0;
        let t = std::time::Instant::now();
        for i in 0..trials {
            let truth = random_truth(&mut rng, 45.0, (0.7, 1.3), diag / 2.0);
            let sampling = if id == ModelId::Model3 && std::env::var("THIN").is_ok() { Sampling::Thin { points: 1000 } } else { Sampling::Independent { points: np } };
            let ds = make(id, np, &truth, &ScanSpec { sampling, noise: noise_frac * diag / truth.scale, seed: 100 + i as u64 });
            let r = register(&nn, &ds.scan, &PfIcpSettings { seed: i as u64, weight_points: std::env::var("WP").map(|v| v.parse().unwrap()).unwrap_or(1000), icp_per_iteration: std::env::var("IPI").map(|v| v.parse().unwrap()).unwrap_or(2), ..Default::default() });
            let o = ok(&r.registration.pose, &truth, diag);
            let oi = ok(&r.initial.pose, &truth, diag);
            if oi.1 < 10.0 { init_ok += 1; }
            if o.0 { succ += 1 } else {
                let ct = pficp::icp::msd(&nn, &ds.scan, &truth);
                let tr = pficp::icp::icp(&nn, &ds.scan, &r.registration.pose, &pficp::icp::IcpSettings{max_iterations: 2000, relative_tolerance: 1e-12, ..Default::default()});
                println!("   fail {i}: ang {:.2} dt {:.4} ds {:.4} | init ang {:.1} | msd est {:.3e} truth {:.3e} icp2000-from-est {:.3e} ang {:.2}", o.1, o.2, o.3, oi.1, r.registration.msd, ct, tr.msd, tr.pose.rotation_angle_to(&truth).to_degrees()); }
        }
        println!("{} independent: {succ}/{trials} (init within 10deg: {init_ok}) {:.2?}", id.name(), t.elapsed());
    }
}
