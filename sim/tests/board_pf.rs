//! The on-board particle filter and the polish after it through the Verilated board's serial
//! pins: Run, Status while it runs (progress, not compared: the byte-level reference is
//! timeless), Status and Result after it, byte for byte equal to the reference (so the pose
//! bytes are `pf::run`'s and the polish's those of `polish::polish_best`).

use pficp_fpga::board::BoardConfig;
use pficp_fpga::common::format::FxPoint;
use pficp_fpga::filter::pf::example_surface;
use pficp_fpga::polish::ScaleStep;
use pficp_fpga::protocol::messages::{self, ResultReply, RunState, StatusReply};
use pficp_fpga::protocol::run_request::{example_request, execute, polish_clocks_bound, RunOutcome, RunRequest};
use pficp_fpga::protocol::{Command, Frame};
use pficp_fpga::search::grid::Grid;
use pficp_fpga::surface::GridSearch;
use pficp_fpga::surface::{self, FxNormal};
use pficp_sim::serial::SerialBoard;

/// The scan's offset from the model (LSB): the pose the filter should find translates by it.
const SHIFT: [i16; 3] = [300, -150, 80];

/// Send a request and run until its reply has arrived (not until idle: the filter may run
/// on after the reply).
fn exchange(b: &mut SerialBoard, frame: &Frame) -> Frame {
    b.send(&frame.encode());
    let mut got = Vec::new();
    let mut clocks = 0u64;
    while !got.contains(&0) {
        b.step();
        got.extend(b.take_received());
        clocks += 1;
        assert!(clocks < 50_000_000, "the board went quiet");
    }
    let (compared, mismatch) = b.comparison();
    assert!(mismatch.is_none(), "after {compared} bytes: {}", mismatch.unwrap());
    Frame::decode(&got[..got.len() - 1]).expect("a well-formed reply")
}

/// What the board computes for `run` over `model`'s grid: the filter over the first
/// `filter_points` of `scan`, the polish over all of it.
fn reference(
    run: &RunRequest,
    grid: &Grid,
    normals: &[FxNormal],
    scan: &[FxPoint],
    filter_points: usize,
) -> RunOutcome {
    let search = GridSearch { grid, normals };
    let polish_scan = &scan[..run.polish.points as usize];
    execute(run, |pose| surface::evaluate(grid, normals, &scan[..filter_points], pose), &search, polish_scan)
}

fn req(cmd: Command, seq: u8, data: Vec<u8>) -> Frame {
    Frame { code: cmd as u8, seq, data }
}

/// Upload `model` sorted by cell with the normals the host computes for it
/// (`quantise::stored_normals`) and its cell table; the grid and the normals.
fn load_grid(b: &mut SerialBoard, model: &[FxPoint]) -> (Grid, Vec<FxNormal>) {
    let g = Grid::build(model).expect("the test model fits the grid");
    let normals = pficp::board::quantise::stored_normals(&g);
    for (cmd, data) in messages::grid_upload(&g, &normals) {
        let r = exchange(b, &req(cmd, 1, data));
        assert_eq!(r.code, cmd as u8 | 0x80);
    }
    (g, normals)
}

#[test]
fn the_board_runs_the_filter_and_returns_the_reference_pose() {
    let model = example_surface(80, [0, 0, 0], 0.0);
    let scan = example_surface(30, SHIFT, 0.7);
    let mut b = SerialBoard::new(BoardConfig::FAST_SIM).with_reference();
    b.run(100);
    let (grid, normals) = load_grid(&mut b, &model);
    exchange(&mut b, &req(Command::LoadScan, 2, messages::load_request(0, &scan)));
    // Result before any run: NoResult.
    let r = exchange(&mut b, &req(Command::Result, 3, vec![]));
    assert_eq!((r.code, r.data.first()), (0xff, Some(&7)), "{r:?}");
    // Run before SetSizes: OverCapacity.
    let cfg = example_request(24, 12, 11, 30);
    let r = exchange(&mut b, &req(Command::Run, 4, cfg.encode()));
    assert_eq!((r.code, r.data.first()), (0xff, Some(&4)), "{r:?}");
    exchange(&mut b, &req(Command::SetSizes, 5, messages::two_u16(80, 30)));
    // A polish over no points: OverCapacity, and nothing runs.
    let mut none = cfg.clone();
    none.polish.points = 0;
    let r = exchange(&mut b, &req(Command::Run, 6, none.encode()));
    assert_eq!((r.code, r.data.first()), (0xff, Some(&4)), "{r:?}");
    let r = exchange(&mut b, &req(Command::Run, 6, cfg.encode()));
    assert_eq!(r.code, Command::Run as u8 | 0x80);
    let run_at = b.clocks();
    // While it runs: Status answers (progress).
    let mut polls = 0;
    let mut seq = 7u8;
    loop {
        let r = exchange(&mut b, &req(Command::Status, seq, vec![]));
        seq = seq.wrapping_add(1);
        let st = StatusReply::decode(&r.data).unwrap();
        if st.state == RunState::Done {
            // Within the host's deadline: the filter's bound and the polish's (the Done seen
            // at a poll, so the run itself took no more than this).
            let lanes = BoardConfig::FAST_SIM.lanes;
            let bound =
                pficp::board::run_clocks_bound(24, 12, 30, 80, lanes) + polish_clocks_bound(&cfg.polish, 80, lanes);
            let took = b.clocks() - run_at;
            println!("Run to Done seen: {took} clocks, the host's bound {bound}");
            assert!(took <= bound, "{took} clocks, the bound {bound}");
            break;
        }
        assert_eq!(st.state, RunState::Running);
        polls += 1;
        b.run(20_000);
        assert!(polls < 10_000, "the filter did not finish");
    }
    assert!(b.progress_frames() >= 1, "at least one Status while running");
    let r = exchange(&mut b, &req(Command::Result, seq, vec![]));
    let result = ResultReply::decode(&r.data).unwrap();
    let RunOutcome { filter: outcome, polish } = reference(&cfg, &grid, &normals, &scan, 30);
    // The filter found something: a pose that undoes most of the scan's shift (the start,
    // the identity, misses by all of it) at a lower cost than the start's.
    let miss = |t: [i32; 3]| (0..3).map(|k| ((t[k] - SHIFT[k] as i32) as f64).powi(2)).sum::<f64>().sqrt();
    let (start_miss, found_miss) = (miss([0; 3]), miss(outcome.pose.t));
    println!("cost {} -> {}, miss {start_miss:.0} -> {found_miss:.0} LSB", outcome.start.cost, outcome.best.cost);
    assert!(found_miss * 3.0 < start_miss, "the pose undoes the shift: {:?} against {SHIFT:?}", outcome.pose.t);
    assert!(outcome.best.cost < outcome.start.cost, "{:?} {:?}", outcome.start, outcome.best);
    assert_eq!(result.pose, outcome.pose);
    assert_eq!(result.params, outcome.params);
    assert_eq!((result.iterations, result.cost), (outcome.iterations, outcome.best.cost));
    assert_eq!(result.polish, polish);
    println!("polish: start {} won at cost {}, filter's cost over the 30 points {}", polish.winner, polish.cost, {
        surface::evaluate(&grid, &normals, &scan, &outcome.pose).cost
    });
    // The same Run with the polish holding the scale (protocol 7's flag): the board's
    // choice and pose are the reference's, and the winner keeps its start's scale where the
    // solved polish changed it.
    let mut held = cfg.clone();
    held.polish.scale = ScaleStep::Held;
    let r = exchange(&mut b, &req(Command::Run, seq.wrapping_add(1), held.encode()));
    assert_eq!(r.code, Command::Run as u8 | 0x80);
    let mut seq = seq.wrapping_add(2);
    for _ in 0..10_000 {
        let r = exchange(&mut b, &req(Command::Status, seq, vec![]));
        seq = seq.wrapping_add(1);
        if StatusReply::decode(&r.data).unwrap().state == RunState::Done {
            break;
        }
        b.run(20_000);
    }
    let r = exchange(&mut b, &req(Command::Result, seq, vec![]));
    let held_result = ResultReply::decode(&r.data).unwrap();
    let want = reference(&held, &grid, &normals, &scan, 30);
    assert_eq!(held_result.polish, want.polish, "the held scale's polish");
    assert_eq!(held_result.params, want.filter.params);
    let frobenius = |m: &[i32; 9]| m.iter().map(|&v| (v as f64).powi(2)).sum::<f64>().sqrt();
    let start = if want.polish.winner == 0 { want.filter.pose } else { held.polish.hypotheses[0] };
    let kept = frobenius(&want.polish.pose.m) / frobenius(&start.m);
    println!("held: start {} won, scale kept to {kept:.6}; solved polish's scale {:.6}", want.polish.winner, {
        frobenius(&polish.pose.m) / frobenius(&start.m)
    });
    assert!((kept - 1.0).abs() < 1e-4, "the held scale moved by {kept}");
    let (compared, _) = b.comparison();
    println!("{polls} Status polls while running, {compared} bytes compared, {} clocks", b.clocks());
}

/// While the filter runs, commands that touch the stores, the pipeline or the result get
/// Busy at once (the timeless reference cannot model this: no byte comparison here).
#[test]
fn commands_get_busy_while_the_filter_runs() {
    let model = example_surface(80, [0, 0, 0], 0.0);
    let scan = example_surface(30, SHIFT, 0.7);
    let mut b = SerialBoard::new(BoardConfig::FAST_SIM);
    b.run(100);
    let (grid, normals) = load_grid(&mut b, &model);
    exchange(&mut b, &req(Command::LoadScan, 2, messages::load_request(0, &scan)));
    exchange(&mut b, &req(Command::SetSizes, 3, messages::two_u16(80, 30)));
    exchange(&mut b, &req(Command::Run, 4, example_request(10, 6, 11, 30).encode()));
    let busy = [
        req(Command::LoadScan, 5, messages::load_request(0, &scan[..3])),
        req(Command::LoadTable, 5, messages::table_request(7, &[1, 2, 3])),
        req(Command::SetSizes, 6, messages::two_u16(80, 30)),
        req(Command::Run, 7, example_request(10, 6, 11, 30).encode()),
        req(Command::Result, 8, vec![]),
    ];
    for f in &busy {
        let r = exchange(&mut b, f);
        assert_eq!((r.code, r.seq, r.data.first()), (0xff, f.seq, Some(&5)), "Busy for {:#04x}: {r:?}", f.code);
    }
    let r = exchange(&mut b, &req(Command::Identify, 9, vec![]));
    assert_eq!(r.code, 0x81, "Identify is answered while running");
    let st = StatusReply::decode(&exchange(&mut b, &req(Command::Status, 10, vec![])).data).unwrap();
    assert_eq!(st.state, RunState::Running);
    // The scan store was not touched: the result is the reference's.
    b.run_until_idle(100_000_000).expect("the filter finishes");
    let result = ResultReply::decode(&exchange(&mut b, &req(Command::Result, 11, vec![])).data).unwrap();
    let outcome = reference(&example_request(10, 6, 11, 30), &grid, &normals, &scan, 30);
    assert_eq!((result.pose, result.polish), (outcome.filter.pose, outcome.polish));
}
