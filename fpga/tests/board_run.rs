//! The byte-level reference board's on-board filter (`pficp_fpga::board::BoardModel`,
//! docs/protocol.md): Run, Status and Result, their checks, and the filter and the polish
//! over the wire.

mod support;

use support::*;

/// A Run configuration for the grid: centre at the identity, a region of a few hundred
/// LSB (the scan's offsets), `seed` given.
fn run_cfg(particles: u16, iterations: u16, seed: u32) -> PfConfig {
    use pficp_fpga::filter::pf::SCALE_FRAC;
    PfConfig {
        particles,
        iterations,
        temper_exp: 10,
        centre: [0, 0, 0, 1 << SCALE_FRAC, 0, 0, 0],
        sigma0: [20_000, 20_000, 20_000, 1 << 13, 1 << 13, 1 << 13, 1 << 13],
        floor: [100, 100, 100, 10, 10, 10, 10],
        seed,
        thr_cost: 0,
        thr_max: 0,
    }
}

/// A Run of `cfg` with a polish over the first 16 stored scan points, 2 steps, from the
/// filter's pose and one hypothesis (a small shift), then 1 step for the winner.
fn request(cfg: PfConfig) -> RunRequest {
    RunRequest {
        filter: cfg,
        polish: PolishRequest {
            points: 16,
            steps: 2,
            winner_steps: 1,
            scale: pficp_fpga::polish::ScaleStep::Solved,
            hypotheses: vec![shift([40, 0, -40])],
        },
    }
}

/// [`request`] of [`run_cfg`].
fn run_req(particles: u16, iterations: u16, seed: u32) -> RunRequest {
    request(run_cfg(particles, iterations, seed))
}

/// The Run on `board`'s stores, computed directly (not through the command): the filter
/// and the polish over the model's own grid.
fn direct_run(b: &BoardModel, r: &RunRequest) -> RunOutcome {
    let (m, s) = b.sizes();
    let store = |n: usize| b.scan_store()[..n].iter().map(|&w| unpack_point(w)).collect::<Vec<FxPoint>>();
    let model = b.model_store()[..m as usize].iter().map(|&w| unpack_point(w)).collect::<Vec<FxPoint>>();
    let (scan, polish_scan) = (store(s as usize), store(r.polish.points as usize));
    let grid = pficp_fpga::search::grid::Grid::build(&model).unwrap();
    assert_eq!(&grid.first[..], b.table_store(), "the board's table is the model's");
    let normals: Vec<_> = b.normal_store()[..m as usize].iter().map(|&w| unpack_point(w)).collect();
    let search = pficp_fpga::surface::GridSearch { grid: &grid, normals: &normals };
    pficp_fpga::protocol::run_request::execute(
        r,
        |pose| pficp_fpga::surface::evaluate(&grid, &normals, &scan, pose),
        &search,
        &polish_scan,
    )
}

#[test]
fn run_then_status_then_result() {
    let mut b = loaded(20);
    // Before any run: Status says 0, no iterations, cost 2^48 - 1; Result has none.
    let d = ok(&mut b, req(STATUS, 1, vec![]));
    assert_eq!(d, vec![0, 0, 0, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff]);
    rejects(&mut b, req(RESULT, 2, vec![]), ErrorCode::NoResult);
    assert!(b.run_outcome().is_none());
    // Some stored costs, which Run must leave alone.
    ok(&mut b, req(EVALUATE, 3, eval_data(FLAG_FIRST, 0, 0, 2, &[shift([0; 3]), shift([9, 9, 9])])));
    let costs = b.stored_costs().to_vec();
    let cfg = run_req(12, 6, 77);
    let data = cfg.encode();
    assert_eq!(data.len(), pficp_fpga::protocol::run_request::run_bytes(2));
    let d = ok(&mut b, req(RUN, 4, data.clone()));
    assert_eq!(d, vec![12, 0, 6, 0], "particles and iterations echoed");
    assert_eq!(d, data[..4].to_vec());
    let want = direct_run(&b, &cfg);
    assert_eq!(b.run_outcome(), Some(&want));
    assert_eq!(b.stored_costs(), &costs[..], "Run keeps the stored costs");
    let (want, polish) = (want.filter.clone(), want.polish);
    assert!(want.best.cost <= want.start.cost);
    // Status: done, the outcome's iterations and best cost.
    let d = ok(&mut b, req(STATUS, 5, vec![]));
    assert_eq!(d.len(), 9);
    assert_eq!(d[0], 2);
    assert_eq!(le_at(&d, 1, 2), want.iterations as u64);
    assert_eq!(le_at(&d, 3, 6), want.best.cost);
    // Result: iterations, cost, max_d2, the 7 parameters (3 bytes each), the pose; the
    // polish's winner, its cost and pose.
    let d = ok(&mut b, req(RESULT, 6, vec![]));
    assert_eq!(d.len(), 95);
    assert_eq!(le_at(&d, 0, 2), want.iterations as u64);
    assert_eq!(le_at(&d, 2, 6), want.best.cost);
    assert_eq!(le_at(&d, 8, 5), want.best.max_d2);
    for k in 0..7 {
        assert_eq!(pficp_fpga::filter::pf::wrap24(le_at(&d, 13 + 3 * k, 3) as i64), want.params[k], "parameter {k}");
    }
    assert_eq!(&d[34..61], &pose_bytes(&pficp_fpga::filter::pf::pose_of(&want.params))[..]);
    assert_eq!(d[61], polish.winner);
    assert_eq!(le_at(&d, 62, 6), polish.cost);
    assert_eq!(&d[68..], &pose_bytes(&polish.pose)[..]);
    assert_eq!(ResultReply::decode(&d).map(|r| r.polish), Ok(polish));
    // Status and Result read only; Identify's stored count is unchanged.
    let before = snap(&b);
    ok(&mut b, req(RESULT, 7, vec![]));
    ok(&mut b, req(STATUS, 8, vec![]));
    let id = ok(&mut b, req(IDENTIFY, 9, vec![]));
    assert_eq!(le_at(&id, 24, 2), 2);
    assert!(snap(&b) == before);
    // Another run replaces the outcome; the same request gives the same outcome again.
    let want = b.run_outcome().cloned();
    ok(&mut b, req(RUN, 10, run_req(12, 6, 78).encode()));
    assert_ne!(b.run_outcome(), want.as_ref());
    ok(&mut b, req(RUN, 11, data));
    assert_eq!(b.run_outcome(), want.as_ref());
    // Reset forgets it: state 0 and NoResult again; the stores stay.
    b.reset();
    assert_eq!(ok(&mut b, req(STATUS, 12, vec![])), StatusReply::IDLE.encode());
    rejects(&mut b, req(RESULT, 13, vec![]), ErrorCode::NoResult);
    assert_eq!(b.stored_costs(), &costs[..]);
    assert_eq!(b.sizes(), (64, 20));
}

#[test]
fn the_filter_on_the_board_finds_a_shifted_grid() {
    // The scan is the grid shifted by (500, -400, 300) LSB; the model the grid. The
    // filter (region +-625 LSB per axis) must bring the translation near the opposite.
    let mut b = BoardModel::new(BoardConfig::default());
    load_grid(&mut b, &grid());
    let t = [500i16, -400, 300];
    let scan: Vec<FxPoint> = grid().iter().map(|p| std::array::from_fn(|a| p[a] + t[a])).collect();
    ok(&mut b, req(LOAD_SCAN, 2, load_data(0, 64, &scan)));
    ok(&mut b, req(SET_SIZES, 3, u16s(64, 64)));
    ok(&mut b, req(RUN, 4, run_req(40, 15, 5).encode()));
    let o = b.run_outcome().unwrap().filter.clone();
    assert!(o.best.cost * 10 < o.start.cost, "{} vs {}", o.best.cost, o.start.cost);
    for (a, &shift) in t.iter().enumerate() {
        let got = pficp_fpga::filter::pf::translation(o.params[a]);
        assert!((got + shift as i32).abs() < 100, "axis {a}: {got}");
    }
    assert_eq!(o.iterations, 15, "no threshold: every iteration runs");
    // A threshold the start already meets stops after the first iteration.
    let mut cfg = run_cfg(8, 30, 5);
    cfg.thr_cost = (1 << 48) - 1;
    cfg.thr_max = (1 << 34) - 1;
    ok(&mut b, req(RUN, 5, request(cfg).encode()));
    assert_eq!(b.run_outcome().unwrap().filter.iterations, 1);
    assert_eq!(ok(&mut b, req(STATUS, 6, vec![]))[1..3], [1, 0]);
}

#[test]
fn run_checks() {
    use ErrorCode::{BadLength, OverCapacity};
    let good = run_req(4, 2, 1).encode();
    let mut fresh = BoardModel::new(BoardConfig::default());
    let mut b = loaded(20);
    // An earlier outcome, which rejected Runs must keep.
    ok(&mut b, req(RUN, 1, run_req(3, 1, 9).encode()));
    let mut no_hyp = good[..156].to_vec();
    no_hyp[5] = 1;
    for board in [&mut fresh, &mut b] {
        for data in [
            vec![],
            good[..4].to_vec(),
            good[..150].to_vec(),
            good[..156].to_vec(),
            good[..good.len() - 1].to_vec(),
            [good.clone(), vec![0]].concat(),
            // One start: no hypothesis follows.
            [no_hyp.clone(), vec![0; 27]].concat(),
            vec![0; 151],
            // Lengths before capacities: no particles, but one byte short.
            run_req(0, 0, 1).encode()[..182].to_vec(),
        ] {
            rejects(board, req(RUN, 2, data), BadLength);
        }
        for (particles, iterations) in [(0, 5), (257, 5), (0xffff, 5), (4, 0), (0, 0)] {
            rejects(board, req(RUN, 3, run_req(particles, iterations, 1).encode()), OverCapacity);
        }
        // The polish's points: 1 to 4,096.
        for points in [0u16, 4097, 0xffff] {
            let mut r = run_req(4, 2, 1);
            r.polish.points = points;
            rejects(board, req(RUN, 3, r.encode()), OverCapacity);
        }
    }
    // Sizes unset (power-up).
    rejects(&mut fresh, req(RUN, 4, good.clone()), OverCapacity);
    // Only the model loaded is still no sizes.
    ok(&mut fresh, req(LOAD_MODEL, 5, load_data(0, 64, &grid())));
    rejects(&mut fresh, req(RUN, 6, good.clone()), OverCapacity);
    // The limits themselves are accepted: 256 particles, 1 iteration; 1 particle.
    ok(&mut b, req(RUN, 7, run_req(256, 1, 2).encode()));
    assert_eq!(b.run_outcome().unwrap().filter.history[0].particles.len(), 256);
    ok(&mut b, req(RUN, 8, run_req(1, 3, 2).encode()));
    // 4,096 polish points (beyond the sizes: the store's words), three starts.
    let mut r = run_req(2, 1, 2);
    r.polish.points = 4096;
    r.polish.hypotheses.push(shift([0, 9, 0]));
    ok(&mut b, req(RUN, 8, r.encode()));
    assert_eq!(b.run_outcome(), Some(&direct_run(&b, &r)));
    // The most starts, fifteen (the field's four bits), one step each and two for the winner.
    let mut r = run_req(2, 1, 4);
    r.polish.steps = 1;
    r.polish.winner_steps = 2;
    r.polish.hypotheses = (0..14).map(|k| shift([8 * k, -4 * k, 0])).collect();
    let data = r.encode();
    assert_eq!(data.len(), pficp_fpga::protocol::run_request::run_bytes(15));
    ok(&mut b, req(RUN, 8, data.clone()));
    assert_eq!(b.run_outcome(), Some(&direct_run(&b, &r)));
    rejects(&mut b, req(RUN, 8, data[..data.len() - 27].to_vec()), BadLength);
    // The high bits of the starts byte, of temper_exp, of the steps and of the winner's
    // steps are ignored, exactly as RunRequest::decode takes them; 0 starts are 1.
    let mut odd = run_req(5, 2, 3).encode();
    odd[5] = 0xa2;
    odd[4] |= 0xc0;
    odd[152] |= 0xf0;
    odd[153] |= 0xe0;
    ok(&mut b, req(RUN, 9, odd.clone()));
    let r = RunRequest::decode(&odd).unwrap();
    assert_eq!(r, run_req(5, 2, 3));
    assert_eq!(b.run_outcome(), Some(&direct_run(&b, &r)));
    let mut zero = run_req(5, 2, 3);
    zero.polish.hypotheses.clear();
    let mut data = zero.encode();
    data[5] = 0xf0;
    ok(&mut b, req(RUN, 9, data));
    assert_eq!(b.run_outcome(), Some(&direct_run(&b, &zero)));
}

#[test]
fn status_and_result_checks() {
    use ErrorCode::{BadLength, NoResult};
    let mut b = loaded(20);
    for len in [1, 4, 9, 61, 95, 150] {
        rejects(&mut b, req(STATUS, 1, vec![0; len]), BadLength);
        // Lengths before NoResult.
        rejects(&mut b, req(RESULT, 2, vec![0; len]), BadLength);
    }
    rejects(&mut b, req(RESULT, 3, vec![]), NoResult);
    ok(&mut b, req(RUN, 4, run_req(2, 1, 1).encode()));
    for len in [1, 61, 95] {
        rejects(&mut b, req(STATUS, 5, vec![0; len]), BadLength);
        rejects(&mut b, req(RESULT, 6, vec![0; len]), BadLength);
    }
    assert_eq!(ok(&mut b, req(STATUS, 7, vec![]))[0], 2);
}

#[test]
fn reset_forgets_a_partial_frame_and_keeps_the_stores() {
    let mut b = loaded(20);
    ok(&mut b, req(EVALUATE, 1, eval_data(FLAG_FIRST, 0, 0, 2, &[shift([0; 3]); 2])));
    let before = snap(&b);
    let w = wire(&[IDENTIFY, 8]);
    assert!(b.receive_all(&w[..3]).is_empty());
    b.reset();
    assert_eq!(b.receive_all(&w), identify_reply(&b, 8));
    assert!(snap(&b) == before);
}

#[test]
fn run_status_and_result_over_the_wire() {
    let mut b = loaded(20);
    let out = b.receive_all(&wire(&[STATUS, 4]));
    assert_eq!(out, Frame { code: 0x88, seq: 4, data: StatusReply::IDLE.encode() }.encode());
    let out = b.receive_all(&wire(&[RESULT, 5]));
    assert_eq!(out, Frame::error(5, ErrorCode::NoResult, RESULT).encode());
    let cfg = run_req(6, 2, 11);
    let out = b.receive_all(&wire(&[&[RUN, 6][..], &cfg.encode()].concat()));
    assert_eq!(out, Frame { code: 0x87, seq: 6, data: vec![6, 0, 2, 0] }.encode());
    let out = b.receive_all(&wire(&[RESULT, 7]));
    let want = ResultReply::of(b.run_outcome().unwrap());
    assert_eq!(out, Frame { code: 0x89, seq: 7, data: want.encode() }.encode());
}
