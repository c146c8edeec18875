//! Where a camera-view registration's time goes: PF-ICP on the first N dev-split cases of
//! the camera families (default 20), the median wall time of the whole call and of each
//! stage ([`pficp::pf_icp::StageTimes`]). The shares in docs/benchmarks.md ("Time and large
//! clouds") come from it.
//!
//! `cargo run --release -p pficp-host --example stage_times -- [N]`

use anyhow::{Context, Result};
use pficp::eval::realistic::{case, Family, Split};
use pficp::nn::NearestNeighbours;
use pficp::pf_icp::PfIcpSettings;
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

fn main() -> Result<()> {
    let n: usize = std::env::args().nth(1).map_or(Ok(20), |s| s.parse()).context("N")?;
    println!("family: median s a case (whole call; the start with k-means and the search; the covariance; the filter; the polish and the conclusion; the rescue)");
    for family in [Family::Camera, Family::CameraAny, Family::CameraMetric, Family::CameraAnyMetric] {
        let mut times: [Vec<f64>; 6] = Default::default();
        for i in 0..n {
            let c = case(family, i, Split::Dev, 1);
            let t0 = Instant::now();
            let nn = NearestNeighbours::new(&c.model);
            let r = pficp::pf_icp::register(&nn, &c.scan, &c.pf_settings(&PfIcpSettings::default()));
            let t = &r.times;
            let stages = [t0.elapsed(), t.clustering, t.covariance, t.filter, t.polish, t.rescue];
            for (v, d) in times.iter_mut().zip(stages) {
                v.push(d.as_secs_f64());
            }
        }
        let [whole, start, covariance, filter, polish, rescue] = times.map(median);
        println!("{}: {whole:.3} ({start:.3}, {covariance:.3}, {filter:.3}, {polish:.3}, {rescue:.3})", family.name());
    }
    Ok(())
}
