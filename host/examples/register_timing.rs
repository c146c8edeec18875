//! The Rust call the Python package wraps, timed: `Request::check` and `Request::run` on two
//! cloud files, N times, with METHOD (default `pf-icp`) and its iteration cap (default 50);
//! prints the median wall time in ms. `python/bench/overhead.py` runs it beside
//! `pficp.register` on the same clouds.
//!
//! `cargo run --release -p pficp-host --example register_timing -- MODEL SCAN [N [METHOD ITERATIONS]]`

use anyhow::{Context, Result};
use pficp::io::read_cloud;
use pficp::registration::methods::Method;
use pficp::request::{BoardProgress, Request};
use std::time::Instant;

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [model, scan, rest @ ..] = args.as_slice() else {
        anyhow::bail!("usage: register_timing MODEL SCAN [N [METHOD ITERATIONS]]");
    };
    let n: usize = rest.first().map_or(Ok(30), |s| s.parse()).context("N")?;
    let method = rest.get(1).map_or("pf-icp", |s| s.as_str());
    let method = Method::parse(method).with_context(|| format!("unknown method {method}"))?;
    let model = read_cloud(model.as_ref(), "model")?;
    let scan = read_cloud(scan.as_ref(), "scan")?;
    let mut request = Request::new(method);
    if let Some(i) = rest.get(2) {
        request.settings.iterations = i.parse().context("ITERATIONS")?;
    }
    let mut ms = Vec::with_capacity(n);
    for _ in 0..n.max(1) {
        let t = Instant::now();
        request.check(&model, &scan)?;
        let r = request.run(&model, &scan, None, BoardProgress { on_board: &mut |_, _, _| {} })?;
        ms.push(t.elapsed().as_secs_f64() * 1e3);
        std::hint::black_box(r.outcome.registration.pose);
    }
    ms.sort_by(f64::total_cmp);
    println!("{:.3}", ms[ms.len() / 2]);
    Ok(())
}
