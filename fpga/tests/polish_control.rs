//! `PolishUnitBench` (the polish's control, datapath and pass with a multiplier) in rust_hdl's
//! simulator against [`pficp_fpga::polish::polish_best`]: the test plays the board around
//! the unit (the start poses at `start_index`; on `pass_go` the found points of the scan at
//! the unit's `pose`, as the residual stage would give them, then `pass_done` with the
//! pass's cost). The winning start, its polished pose and its cost must equal the model's,
//! and so must every pass's pose: the unit asks for the model's passes, in the model's
//! order.
#![cfg(feature = "rtl")]

use pficp_fpga::common::format::{pack_point, transform, FxPoint, FxPose};
use pficp_fpga::common::rtl::{pose_word as word, word_pose as unword};
use pficp_fpga::polish::bench_rtl::PolishUnitBench;
use pficp_fpga::polish::cases::{pose, surface, window_scan};
use pficp_fpga::polish::{gate, pass, polish, polish_best, solve, update, within_drift, ScaleStep};
use pficp_fpga::search::grid::{Grid, NONE};
use pficp_fpga::surface::{evaluate, signed_residual, FxNormal};
use rust_hdl::prelude::*;
use std::sync::{Arc, Mutex};

/// The found points of `scan` at `pose`, as the residual stage gives them to the pass:
/// image, normal and signed residual.
fn found(grid: &Grid, normals: &[FxNormal], scan: &[FxPoint], pose: &FxPose) -> Vec<(FxPoint, FxNormal, i64)> {
    scan.iter()
        .filter_map(|&p| {
            let q = transform(pose, p);
            let nr = grid.nearest(q);
            (nr.index != NONE).then(|| {
                let (m, n) = (grid.points[nr.index as usize], normals[nr.index as usize]);
                (q, n, signed_residual(q, m, n))
            })
        })
        .collect()
}

/// The poses of the passes the model runs for `starts`, in order (each start's statistics
/// pass, its gated passes and its cost pass), from the model's steps ([`polish`]'s loop).
fn model_passes(grid: &Grid, normals: &[FxNormal], scan: &[FxPoint], starts: &[FxPose], steps: u32) -> Vec<FxPose> {
    let mut poses = Vec::new();
    for (i, start) in starts.iter().enumerate() {
        let mut pose = *start;
        poses.push(pose);
        let mut last = pass(grid, normals, scan, &pose, None, ScaleStep::Solved);
        for _ in 0..steps {
            let Some(tau2) = gate(&last) else { break };
            poses.push(pose);
            last = pass(grid, normals, scan, &pose, Some(tau2), ScaleStep::Solved);
            let Some(step) = solve(&last) else { break };
            pose = update(&pose, &step);
        }
        assert_eq!(pose, polish(grid, normals, scan, start, steps, ScaleStep::Solved).pose, "the loop is the model's");
        if within_drift(start, &pose) {
            poses.push(pose);
        } else if i == 0 {
            poses.push(*start);
        }
    }
    poses
}

/// Run the unit on `starts`; returns (winner, pose, cost) and the poses of its passes.
fn run_unit(
    grid: Arc<Grid>,
    normals: Arc<Vec<FxNormal>>,
    scan: Arc<Vec<FxPoint>>,
    starts: Vec<FxPose>,
    steps: u32,
) -> ((usize, FxPose, u64), Vec<FxPose>) {
    let result = Arc::new(Mutex::new(None));
    let passes = Arc::new(Mutex::new(Vec::new()));
    let (out, out_passes) = (result.clone(), passes.clone());
    let mut uut = PolishUnitBench::new();
    uut.connect_all();
    let mut sim = Simulation::new();
    sim.add_clock(5, |x: &mut Box<PolishUnitBench>| x.clock.next = !x.clock.val());
    sim.add_testbench(move |mut sim: Sim<PolishUnitBench>| {
        let mut x = sim.init()?;
        x.reset.next = true;
        wait_clock_cycle!(sim, clock, x);
        x.reset.next = false;
        x.starts.next = (starts.len() as u64).into();
        x.steps.next = (steps as u64).into();
        x.start_pose.next = word(&starts[0]);
        x.go.next = true;
        wait_clock_cycle!(sim, clock, x);
        x.go.next = false;
        while !x.done.val() {
            // Until the unit asks for something (checked by the simulator, no handoff a clock).
            let index = x.start_index.val();
            x = sim.watch(move |x| x.pass_go.val() || x.done.val() || x.start_index.val() != index, x)?;
            x.start_pose.next = word(&starts[(x.start_index.val().to_u64() as usize).min(starts.len() - 1)]);
            if x.pass_go.val() {
                let pose = unword(x.pose.val());
                out_passes.lock().unwrap().push(pose);
                wait_clock_cycle!(sim, clock, x);
                for (q, n, s) in found(&grid, &normals, &scan, &pose) {
                    while !x.ready.val() {
                        wait_clock_cycle!(sim, clock, x);
                    }
                    x.in_valid.next = true;
                    x.in_q.next = Bits::<48>::from(pack_point(q));
                    x.in_n.next = Bits::<48>::from(pack_point(n));
                    x.in_s.next = Bits::<13>::from((s as u64) & 0x1fff);
                    wait_clock_cycle!(sim, clock, x);
                    x.in_valid.next = false;
                }
                while !x.ready.val() {
                    wait_clock_cycle!(sim, clock, x);
                }
                // The last point's adds land within a few clocks.
                for _ in 0..8 {
                    wait_clock_cycle!(sim, clock, x);
                }
                x.pass_done.next = true;
                x.pass_cost.next = Bits::<48>::from(evaluate(&grid, &normals, &scan, &pose).cost);
                wait_clock_cycle!(sim, clock, x);
                x.pass_done.next = false;
            } else if !x.done.val() {
                wait_clock_cycle!(sim, clock, x);
            }
        }
        *out.lock().unwrap() =
            Some((x.best_index.val().to_u64() as usize, unword(x.pose.val()), x.best_cost.val().to_u64()));
        sim.done(x)
    });
    sim.run(Box::new(uut), 100_000_000_000).expect("simulation");
    let r = result.lock().unwrap().expect("a result");
    let p = passes.lock().unwrap().clone();
    (r, p)
}

#[test]
fn the_unit_chooses_and_polishes_as_the_model() {
    let (grid, normals) = surface();
    let scan: Vec<FxPoint> = window_scan(&grid).into_iter().step_by(4).collect();
    // A first start in another basin (a quarter turn), which the polish drags beyond the
    // drift bounds, so it stays unpolished; one near the truth, which wins; one at 1.6
    // times the scale, which the polish also drags beyond the bounds, so it drops.
    let starts = vec![pose(1.0, 1.5, [0.0; 3]), pose(0.9, 0.2, [0.05, 0.0, 0.0]), pose(1.6, 0.1, [0.0; 3])];
    let steps = 2;
    let drifts: Vec<bool> = starts
        .iter()
        .map(|s| within_drift(s, &polish(&grid, &normals, &scan, s, steps, ScaleStep::Solved).pose))
        .collect();
    assert_eq!(drifts, [false, true, false], "the case covers a kept and a dropped start beyond the bounds");
    let (best, p, cost) = polish_best(&grid, &normals, &scan, &starts, steps, 0, ScaleStep::Solved).expect("a winner");
    assert_eq!((best, p.steps), (1, steps), "a later start wins after its steps");
    let want_passes = model_passes(&grid, &normals, &scan, &starts, steps);
    let ((i, rtl_pose, rtl_cost), passes) =
        run_unit(Arc::new(grid), Arc::new(normals), Arc::new(scan), starts.clone(), steps);
    eprintln!("winner {i} (model {best}), {} passes (model {})", passes.len(), want_passes.len());
    assert_eq!(passes, want_passes, "the passes' poses");
    assert_eq!((i, rtl_pose, rtl_cost), (best, p.pose, cost));
}

#[test]
fn a_failed_gate_and_a_failed_solve_end_the_steps_as_in_the_model() {
    let (grid, normals) = surface();
    // Five scan points: fewer than the solve's seven inliers.
    let scan: Vec<FxPoint> = window_scan(&grid).into_iter().step_by(60).take(5).collect();
    assert_eq!(scan.len(), 5);
    // A first start far off (nothing found: the gate fails), one near the truth (the
    // solve fails).
    let starts = vec![pose(1.0, 0.0, [3.0, 3.0, 0.0]), pose(1.01, 0.02, [0.0; 3])];
    let stats: Vec<Option<u64>> =
        starts.iter().map(|s| gate(&pass(&grid, &normals, &scan, s, None, ScaleStep::Solved))).collect();
    assert!(stats[0].is_none() && stats[1].is_some(), "the first start finds nothing, the second some");
    for s in &starts {
        assert_eq!(polish(&grid, &normals, &scan, s, 3, ScaleStep::Solved).steps, 0, "no step taken");
    }
    let (best, p, cost) = polish_best(&grid, &normals, &scan, &starts, 3, 0, ScaleStep::Solved).expect("a winner");
    let want_passes = model_passes(&grid, &normals, &scan, &starts, 3);
    let ((i, rtl_pose, rtl_cost), passes) =
        run_unit(Arc::new(grid), Arc::new(normals), Arc::new(scan), starts.clone(), 3);
    assert_eq!(passes, want_passes, "the passes' poses");
    assert_eq!((i, rtl_pose, rtl_cost), (best, p.pose, cost));
}
