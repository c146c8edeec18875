//! The Verilated `PolishUnit` (the polish's control, datapath and pass as the board
//! instantiates them) against [`pficp_fpga::polish::polish_best`]: the test plays the board
//! around it, as `fpga/tests/polish_control.rs` does in rust_hdl's simulator (the start
//! poses at `start_index`; on `pass_go` the found points of the scan at the unit's `pose`,
//! then `pass_done` with the pass's cost) and is the multiplier (the product of a pair three
//! clocks after the clock that issues it, as the sequencer's `PipeMul`). As on the board, a
//! hypothesis's pose comes a clock after `start_index` names it (the engine's RAM), the
//! filter's (start 0) at once. The winner, its polished pose and cost (after the winner's
//! further steps), and every pass's pose must equal the model's.

use pficp_fpga::common::format::{FxPoint, FxPose};
use pficp_fpga::filter::sequencer::unpack_pose;
use pficp_fpga::polish::cases::{pose, surface, window_scan};
use pficp_fpga::polish::{polish_best, ScaleStep};
use pficp_fpga::search::grid::Grid;
use pficp_fpga::surface::{evaluate, signed_residual, FxNormal};
use pficp_fpga::surface::{GridSearch, Search};
use pficp_sim::{UnitInputs, VerilatedPolishUnit};
use std::collections::VecDeque;

/// The found points of `scan` at `pose` as the residual stage gives them: image, normal,
/// signed residual.
fn found(grid: &Grid, normals: &[FxNormal], scan: &[FxPoint], pose: &FxPose) -> Vec<Found> {
    let search = GridSearch { grid, normals };
    search.found(scan, pose).into_iter().map(|(q, p, n)| (q, n, signed_residual(q, p, n))).collect()
}

/// A found point as the pass takes it: image, normal, signed residual.
type Found = (FxPoint, FxNormal, i64);

fn sign_extend(v: u64, bits: u32) -> i64 {
    ((v << (64 - bits)) as i64) >> (64 - bits)
}

/// Run the unit on `starts`: (winner, pose, cost), the poses of its passes and its clocks.
fn run_unit(
    grid: &Grid,
    normals: &[FxNormal],
    scan: &[FxPoint],
    starts: &[FxPose],
    steps: u8,
    winner_steps: u8,
    scale: ScaleStep,
) -> ((usize, FxPose, u64), Vec<FxPose>, u64) {
    let mut u = VerilatedPolishUnit::new();
    let mut i = UnitInputs { reset: true, ..Default::default() };
    u.step(&i);
    i = UnitInputs {
        go: true,
        starts: starts.len() as u8,
        steps,
        winner_steps,
        scale_held: scale == ScaleStep::Held,
        start_pose: starts[0].pack(),
        ..Default::default()
    };
    u.step(&i);
    i.go = false;
    let mut products: VecDeque<(u64, u64)> = VecDeque::new();
    let mut passes = Vec::new();
    // The pass being served: its found points left, its cost, clocks since the last point.
    let mut serving: Option<(VecDeque<Found>, u64, u32)> = None;
    let mut clock = 0u64;
    // The hypothesis RAM's read: the word `start_index` named a clock before.
    let mut read = starts[0].pack();
    loop {
        let o = u.outputs();
        if o.done && !o.busy {
            return ((o.best_index as usize, unpack_pose(&o.pose), o.best_cost), passes, clock);
        }
        assert!(clock < 50_000_000, "the unit did not finish");
        // The multiplier.
        if o.mul_go {
            let p = sign_extend(o.mul_a, 26) * sign_extend(o.mul_b, 18);
            products.push_back((clock + 3, p as u64 & ((1 << 44) - 1)));
        }
        while products.front().is_some_and(|&(due, _)| due <= clock) {
            i.mul_product = products.pop_front().unwrap().1;
        }
        i.start_pose = if o.start_index == 0 { starts[0].pack() } else { read };
        read = starts[(o.start_index as usize).min(starts.len() - 1)].pack();
        i.in_valid = false;
        i.pass_done = false;
        if o.pass_go {
            assert!(serving.is_none(), "a pass asked for while one is served");
            let at = unpack_pose(&o.pose);
            passes.push(at);
            serving = Some((found(grid, normals, scan, &at).into(), evaluate(grid, normals, scan, &at).cost, 0));
        } else if let Some((points, cost, idle)) = &mut serving {
            if o.ready && *idle > 0 {
                if let Some((q, n, s)) = points.pop_front() {
                    (i.in_valid, i.in_q, i.in_n, i.in_s) = (true, q, n, s & 0x1fff);
                    *idle = 0;
                } else if *idle >= 8 {
                    // The last point's adds are in.
                    (i.pass_done, i.pass_cost) = (true, *cost);
                    serving = None;
                } else {
                    *idle += 1;
                }
            } else if o.ready || *idle == 0 {
                *idle += 1;
            }
        }
        u.step(&i);
        clock += 1;
    }
}

#[test]
fn the_verilated_unit_chooses_and_polishes_as_the_model() {
    let (grid, normals) = surface();
    let scan: Vec<FxPoint> = window_scan(&grid).into_iter().step_by(4).collect();
    // As `polish_control.rs`: a first start dragged beyond the drift bounds (kept
    // unpolished), one near the truth (the winner), one at 1.6 times the scale (dropped).
    let starts = vec![pose(1.0, 1.5, [0.0; 3]), pose(0.9, 0.2, [0.05, 0.0, 0.0]), pose(1.6, 0.1, [0.0; 3])];
    // The last case holds the scale: the winner's scale stays its start's (the model's
    // test: `a_held_scale_stays_and_the_rest_is_polished`).
    let cases = [
        (0u8, 0u8, ScaleStep::Solved),
        (1, 0, ScaleStep::Solved),
        (2, 0, ScaleStep::Solved),
        (1, 2, ScaleStep::Solved),
        (2, 1, ScaleStep::Held),
    ];
    for (steps, winner_steps, scale) in cases {
        let (best, p, cost) =
            polish_best(&grid, &normals, &scan, &starts, steps as u32, winner_steps as u32, scale).expect("a winner");
        let ((i, rtl_pose, rtl_cost), passes, clocks) =
            run_unit(&grid, &normals, &scan, &starts, steps, winner_steps, scale);
        eprintln!(
            "{steps} steps, {winner_steps} for the winner, scale {scale:?}: winner {i} (model {best}), {} passes, {clocks} clocks",
            passes.len()
        );
        assert_eq!(
            (i, rtl_pose, rtl_cost),
            (best, p.pose, cost),
            "{steps} steps, {winner_steps} for the winner, {scale:?}"
        );
    }
    // Six starts (the hypotheses from the board's RAM beyond the first two), the winner late
    // in the order, and its further polish.
    let six = vec![
        pose(1.0, 1.5, [0.0; 3]),
        pose(1.6, 0.1, [0.0; 3]),
        pose(1.0, 0.6, [0.1, 0.0, 0.0]),
        pose(1.2, 0.3, [0.0; 3]),
        pose(0.95, 0.1, [0.02, 0.0, 0.0]),
        pose(0.8, 0.4, [0.0; 3]),
    ];
    let (best, p, cost) = polish_best(&grid, &normals, &scan, &six, 1, 1, ScaleStep::Solved).expect("a winner");
    let ((i, rtl_pose, rtl_cost), passes, clocks) = run_unit(&grid, &normals, &scan, &six, 1, 1, ScaleStep::Solved);
    eprintln!("six starts, 1 + 1 steps: winner {i} (model {best}), {} passes, {clocks} clocks", passes.len());
    assert!(best >= 3, "the winner ({best}) comes from the RAM beyond the first two hypotheses");
    assert_eq!((i, rtl_pose, rtl_cost), (best, p.pose, cost), "six starts");
}
