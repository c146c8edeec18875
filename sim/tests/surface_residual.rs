//! The Verilated surface residual stage (`SurfaceResidual`) in lockstep with
//! `SurfaceResidualModel`, every output port every clock (`SurfaceLockstep`), on random
//! particles: results on every clock and with gaps (garbage on the result ports while
//! `in_valid` is low), capped distances, distances just below `CAP_D2` with differences near
//! +-1023, small and random differences, normals at the extremes (`i16::MIN`, `i16::MAX`, 0),
//! random and unit normals, normals in multiples of 2^12 (projections on exact halves, where
//! the rounding shows), writes to both stores during the stream (also to the address a result
//! reads at the same edge: read-first), particles back to back, and now and then a result on
//! the `cost_valid` edge. Each `nn_resid` also equals `fpga::surface::residual` of the point
//! and normal stored when the result was presented, and each `cost` the sum of its particle's
//! residuals (mod 2^48). Seed `PFICP_COSIM_SEED` (default 1), particles `PFICP_SURF_CASES`
//! (default 300).
//!
//! Mutation check (by hand): with the rounding constant `2^13 - 1` instead of `2^13` in
//! `fpga/src/surface/surface_residual_rtl.rs`, seed 1 fails at cycle 91 (`nn_resid` 3,600 for 3,481);
//! without the multiples of 2^12 among the normals it passed.

use pficp_fpga::common::format::{dist2, pack_point, FxPoint, COST_MASK};
use pficp_fpga::search::grid::CAP_D2;
use pficp_fpga::surface::surface_residual::{SurfaceInputs, SURFACE_LATENCY};
use pficp_fpga::surface::{residual, FxNormal, NORMAL_FRAC};
use pficp_sim::SurfaceLockstep;
use std::collections::VecDeque;

mod support;

use support::Rng;

fn between(r: &mut Rng, lo: i64, hi: i64) -> i64 {
    lo + r.below((hi - lo + 1) as u64) as i64
}

fn random_normal(r: &mut Rng) -> FxNormal {
    match r.below(7) {
        // Multiples of 2^12 (0.25): projections on exact halves, where the rounding shows.
        6 => [0; 3].map(|_| 4096 * between(r, -4, 4) as i16),
        // Extremes, mixed with zeros.
        0 | 1 => [0; 3].map(|_| [i16::MIN, i16::MAX, 0, -1, 1, i16::MIN + 1][r.below(6) as usize]),
        // Anything.
        2 => [0; 3].map(|_| r.next() as i16),
        // Unit normals.
        _ => {
            let v = [0; 3].map(|_| r.uniform(-1.0, 1.0));
            let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt().max(1e-9);
            v.map(|c| (c / l * (1 << NORMAL_FRAC) as f64).round().clamp(-32768.0, 32767.0) as i16)
        }
    }
}

fn random_point(r: &mut Rng) -> FxPoint {
    if r.below(8) == 0 {
        [0; 3].map(|_| [i16::MIN, i16::MAX, -8192, 8192][r.below(4) as usize])
    } else {
        [0; 3].map(|_| r.coord(8192))
    }
}

/// A scan point near `p` and its squared distance as the search would give it (capped
/// ones sometimes an arbitrary distance at or above the cap).
fn random_query(r: &mut Rng, p: FxPoint) -> (FxPoint, u64) {
    let off = |p: FxPoint, d: [i64; 3]| -> FxPoint { std::array::from_fn(|k| (p[k] as i64 + d[k]) as i16) };
    let d: [i64; 3] = match r.below(6) {
        // Small.
        0 | 1 => [0; 3].map(|_| between(r, -60, 60)),
        // One axis near +-1023, the others small enough to stay below the cap.
        2 => {
            let mut d = [0; 3].map(|_| between(r, -30, 30));
            let a = r.below(3) as usize;
            d[a] = if r.below(2) == 0 { 1023 - r.below(4) as i64 } else { -1023 + r.below(4) as i64 };
            d
        }
        // Anywhere in the cube of the search's reach (often capped).
        3 => [0; 3].map(|_| between(r, -1023, 1023)),
        // Just around the cap: |d| = 1024 on an axis.
        4 => {
            let mut d = [0; 3].map(|_| between(r, -3, 3));
            d[r.below(3) as usize] = if r.below(2) == 0 { 1024 } else { -1024 };
            d
        }
        // Far.
        _ => [0; 3].map(|_| between(r, -20000, 20000)),
    };
    let q = off(p, d);
    let d2 = dist2(q, p);
    if d2 >= CAP_D2 && r.below(2) == 0 {
        (q, CAP_D2 + r.below((1 << 34) - CAP_D2))
    } else {
        (q, d2)
    }
}

#[test]
fn random_particles_in_lockstep() {
    let seed: u64 = std::env::var("PFICP_COSIM_SEED").ok().and_then(|s| s.parse().ok()).unwrap_or(1);
    let cases: usize = std::env::var("PFICP_SURF_CASES").ok().and_then(|s| s.parse().ok()).unwrap_or(300);
    let mut r = Rng::new(seed ^ 0x5eed_5af1);
    let mut ls = SurfaceLockstep::new();
    // The test's copy of the stores (as the model's, read-first).
    let mut points = vec![[0i16; 3]; 4096];
    let mut normals = vec![[0i16; 3]; 4096];
    // A small working set of addresses, so that writes hit the addresses read.
    let addrs: Vec<u16> = (0..48).map(|_| r.below(4096) as u16).chain([0, 4095]).collect();
    let step = |ls: &mut SurfaceLockstep, i: &SurfaceInputs| {
        if let Err(m) = ls.step(i) {
            panic!("seed {seed}: {m}");
        }
        ls.outputs()
    };
    // Load the working set.
    for &a in &addrs {
        let (p, n) = (random_point(&mut r), random_normal(&mut r));
        points[a as usize] = p;
        normals[a as usize] = n;
        let i = SurfaceInputs {
            point_we: true,
            point_waddr: a,
            point_wdata: pack_point(p),
            normal_we: true,
            normal_waddr: a,
            normal_wdata: pack_point(n),
            ..Default::default()
        };
        step(&mut ls, &i);
    }
    // Expected results (index, dist, residual) and costs, in order.
    let mut expect: VecDeque<(u16, u64, u32)> = VecDeque::new();
    let mut expect_costs: VecDeque<u64> = VecDeque::new();
    let (mut results, mut costs, mut same_edge, mut rw_same, mut capped_res) = (0u64, 0u64, 0u64, 0u64, 0u64);
    let check = |o: pficp_fpga::surface::surface_residual::SurfaceOutputs,
                 expect: &mut VecDeque<(u16, u64, u32)>,
                 expect_costs: &mut VecDeque<u64>| {
        if o.nn_valid {
            let e = expect.pop_front().expect("a result nobody presented");
            assert_eq!((o.nn_index, o.nn_dist, o.nn_resid), e, "seed {seed}: result against fpga::surface::residual");
        }
        if o.cost_valid {
            let c = expect_costs.pop_front().expect("a cost_valid nobody presented");
            assert_eq!(o.cost, c, "seed {seed}: the particle's cost");
        }
    };
    for _ in 0..cases {
        let size = [3, 40, 200][r.below(3) as usize];
        let n = 1 + r.below(size) as usize;
        let density = [1.0, 1.0, 0.6, 0.2][r.below(4) as usize];
        let write_rate = [0.0, 0.05, 0.3][r.below(3) as usize];
        let mut sum = 0u64;
        let mut left = n;
        let mut closed = false;
        while left > 0 {
            let mut i = SurfaceInputs::default();
            if r.chance(density) {
                let a = addrs[r.below(addrs.len() as u64) as usize];
                let p = points[a as usize];
                let (q, d2) = random_query(&mut r, p);
                let res = residual(q, p, normals[a as usize], d2);
                i.in_valid = true;
                i.in_index = a;
                i.in_dist = d2;
                i.in_point = pack_point(q);
                expect.push_back((a, d2, res as u32));
                sum = (sum + res) & COST_MASK;
                results += 1;
                capped_res += (res == CAP_D2) as u64;
                left -= 1;
                // The last result on the cost_valid edge, now and then.
                if left == 0 && r.below(10) == 0 {
                    i.in_cost_valid = true;
                    closed = true;
                    same_edge += 1;
                }
            } else {
                // Garbage on the result ports (passed through, not counted).
                i.in_index = r.below(4096) as u16;
                i.in_dist = r.below(1 << 34);
                i.in_point = r.below(1 << 48);
            }
            if r.chance(write_rate) {
                let a = if i.in_valid && r.below(2) == 0 {
                    i.in_index
                } else {
                    addrs[r.below(addrs.len() as u64) as usize]
                };
                rw_same += (i.in_valid && a == i.in_index) as u64;
                let p = random_point(&mut r);
                i.point_we = true;
                i.point_waddr = a;
                i.point_wdata = pack_point(p);
                points[a as usize] = p;
            }
            if r.chance(write_rate) {
                let a = if i.in_valid && r.below(2) == 0 {
                    i.in_index
                } else {
                    addrs[r.below(addrs.len() as u64) as usize]
                };
                let nrm = random_normal(&mut r);
                i.normal_we = true;
                i.normal_waddr = a;
                i.normal_wdata = pack_point(nrm);
                normals[a as usize] = nrm;
            }
            let o = step(&mut ls, &i);
            check(o, &mut expect, &mut expect_costs);
        }
        expect_costs.push_back(sum);
        costs += 1;
        if !closed {
            // The pipeline's cost_valid: the edge after the last result.
            let o = step(&mut ls, &SurfaceInputs { in_cost_valid: true, ..Default::default() });
            check(o, &mut expect, &mut expect_costs);
        }
        // Idle clocks between particles, or none (back to back).
        for _ in 0..[0, 0, 1, 5][r.below(4) as usize] {
            let o = step(&mut ls, &SurfaceInputs::default());
            check(o, &mut expect, &mut expect_costs);
        }
    }
    // Drain.
    for _ in 0..SURFACE_LATENCY + 2 {
        let o = step(&mut ls, &SurfaceInputs::default());
        check(o, &mut expect, &mut expect_costs);
    }
    assert!(expect.is_empty() && expect_costs.is_empty(), "seed {seed}: results or costs never came out");
    eprintln!(
        "seed {seed}: {} clocks in lockstep, {results} results ({capped_res} capped), {costs} particles \
         ({same_edge} closed on a result's edge), {rw_same} same-address write+read",
        ls.clocks_compared()
    );
    assert!(results > 1000 && same_edge > 0 && rw_same > 0 && capped_res > 0);
}
