//! `pficp-onboard-bench`: the board time of one PF-ICP registration with the particle filter
//! on the board (the default mode of `pficp register --board`), counted in clocks of the
//! Verilated default board (the generated design: 8 lanes, the UCF's 50 MHz, 3,000,000
//! baud) driven through its serial pins at the UART's exact bit timing; beside the software
//! mode's time on this machine.
//!
//! The same registration on a board generated for 921,600 baud is modelled, not simulated
//! (one Verilated board): the simulated clocks with every byte's wire time (10 bits at the
//! exact nominal rate) taken out and put back at 921,600 baud. The compute clocks do not
//! depend on the baud rate; the Status polls overlap the running filter, so counting their
//! bytes makes the figure an upper bound, by at most their wire time (printed).
//!
//! Two registrations run on the same board: the first uploads the model (sorted by cell)
//! and its cell table, the second finds them resident (Identify's model digest equals
//! the one the upload leaves, as the host's `ensure_grid` checks) and sends only the scan
//! (the filter's sample, then the rest of the scan for the board's polish). Each one's board time is every clock from the first byte of Identify to the last
//! byte of the Result reply: Identify, the loads, SetSizes, Run, the filter, a Status poll
//! every `pficp::board::DEFAULT_POLL` of board time (1 ms, as the host client polls), Status
//! and Result.
//! The board's bytes are compared with the byte-level reference on the way (Status replies
//! of a running filter excepted). The Run is the host's (`OnBoardPlan::run_request`): the
//! filter, then the board's polish from its pose and the prior's hypotheses, so the board's
//! pose alone is the polished one. The prior and the host's optional polish run on the host
//! (not timed here: the host's stages are the software mode's).
//!
//! With `--track N` it times tracked frames instead (docs/tracking.md): the tracking
//! benchmark's dev sequence of the bunny (scale known), tracked by the host with the
//! filter by the board's reference (`pficp::tracking`, `--board-reference`), and every
//! tracked frame's requests among the first N frames (the scan sample, SetSizes, Run,
//! Status every 1 ms, Result; the model uploaded once before) replayed on the Verilated
//! board, whose Result must equal the reference's to the bit; the median frame's clocks,
//! at 3,000,000 baud and modelled at 921,600, with the host's polish and checks.
//!
//! `pficp-onboard-bench [--model-points 2000] [--scan-points 1000] [--board-points 300]
//! [--particles 50] [--iterations 50] [--runs 3] [--seed 1] [--all-iterations]
//! [--polish-steps S] [--winner-steps W] [--polish-starts N] [--polish-points N]`; run in
//! release. The filter stops at the Run's thresholds (the host's, on the surface residual) or
//! at the iteration cap; `--all-iterations` zeroes the thresholds, so every iteration runs.

use anyhow::{bail, Context, Result};
use clap::Parser;
use pficp::board::on_board;
use pficp::cloud::bbox_diagonal;
use pficp::datasets::{make, ModelId, Sampling, ScanSpec};
use pficp::nn::NearestNeighbours;
use pficp::pf_icp::{self, PfIcpSettings};
use pficp::registration::methods::PoseError;
use pficp_fpga::board::{BitPeriod, BoardConfig};
use pficp_fpga::protocol::messages::{self, ResultReply, RunState, StatusReply};
use pficp_fpga::protocol::{Command, Frame};
use pficp_sim::serial::SerialBoard;
use std::time::{Duration, Instant};

#[derive(Parser, Debug)]
#[command(name = "pficp-onboard-bench", about = "Board time of one on-board registration beside the software mode")]
struct Args {
    /// Model points.
    #[arg(long, default_value_t = 2000)]
    model_points: usize,
    /// Scan points.
    #[arg(long, default_value_t = 1000)]
    scan_points: usize,
    /// Scan points on the board (the weight sample).
    #[arg(long, default_value_t = on_board::DEFAULT_BOARD_POINTS)]
    board_points: usize,
    /// Particles.
    #[arg(long, default_value_t = 50)]
    particles: usize,
    /// Iteration cap.
    #[arg(long, default_value_t = 50)]
    iterations: usize,
    /// Software-mode runs (the median is reported).
    #[arg(long, default_value_t = 3)]
    runs: usize,
    /// Seed of the dataset and the registration.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Run every iteration (the Run's stop thresholds zeroed): the filter's worst case.
    #[arg(long)]
    all_iterations: bool,
    /// The on-board polish's Gauss-Newton steps a start [default: the host's].
    #[arg(long)]
    polish_steps: Option<u8>,
    /// The winner's further steps [default: the host's].
    #[arg(long)]
    winner_steps: Option<u8>,
    /// The polish's starts: the filter's pose and the first `N - 1` of the host's hypotheses
    /// [default: the host's].
    #[arg(long)]
    polish_starts: Option<usize>,
    /// Stored scan points the on-board polish runs over [default: the host's, every stored
    /// point].
    #[arg(long)]
    polish_points: Option<u16>,
    /// Time the tracked frames among the first N frames of a tracking sequence instead
    /// (1 to 300).
    #[arg(long, value_name = "N")]
    track: Option<usize>,
}

/// Send one request; run until its reply's delimiter; check the bytes so far.
fn exchange(b: &mut SerialBoard, frame: &Frame) -> Result<Frame> {
    b.send(&frame.encode());
    let mut got = Vec::new();
    let start = b.clocks();
    while !got.contains(&0) {
        b.step();
        got.extend(b.take_received());
        if b.clocks() - start > 2_000_000_000 {
            bail!("the board went quiet");
        }
    }
    if let (compared, Some(m)) = b.comparison() {
        bail!("the board differs from the reference after {compared} bytes: {m}");
    }
    Frame::decode(&got[..got.len() - 1]).map_err(|e| anyhow::anyhow!("a malformed reply: {e:?}"))
}

/// What one registration on the simulated board took.
struct Registration {
    /// The model and table were uploaded (the board's digest did not match).
    uploaded: bool,
    /// Clocks from the first byte of Identify to the last of the Result reply.
    clocks: u64,
    /// Of which Identify, the loads and SetSizes.
    load_clocks: u64,
    /// Bytes both ways, and those of the Status polls.
    bytes: u64,
    poll_bytes: u64,
    polls: usize,
    result: ResultReply,
}

/// One registration as the host's on-board mode makes it: Identify, the model and its
/// cell table unless the board's digest says it holds them, the scan sample, SetSizes,
/// Run, a Status poll every `DEFAULT_POLL` of board time, Result.
fn registration(b: &mut SerialBoard, plan: &on_board::OnBoardPlan, config: BoardConfig) -> Result<Registration> {
    let t0 = b.clocks();
    let bytes0 = b.byte_counts();
    let mut seq = 1u8;
    let mut next = || {
        seq = seq.wrapping_add(1).max(1);
        seq
    };
    let id = exchange(b, &Frame { code: Command::Identify as u8, seq: next(), data: vec![] })?;
    let id = messages::Identity::decode(&id.data)?;
    let uploaded = id.model_digest != messages::grid_digest(&plan.grid, &plan.normals);
    let mut loads = if uploaded { messages::grid_upload(&plan.grid, &plan.normals) } else { Vec::new() };
    for (k, chunk) in plan.stored_scan().chunks(messages::MAX_LOAD_POINTS).enumerate() {
        loads.push((Command::LoadScan, messages::load_request((k * messages::MAX_LOAD_POINTS) as u16, chunk)));
    }
    for (cmd, data) in loads {
        let r = exchange(b, &Frame { code: cmd as u8, seq: next(), data })?;
        if r.code != cmd as u8 | 0x80 {
            bail!("load refused: {r:?}");
        }
    }
    let sizes = messages::two_u16(plan.model.len() as u16, plan.scan.len() as u16);
    exchange(b, &Frame { code: Command::SetSizes as u8, seq: next(), data: sizes })?;
    let load_clocks = b.clocks() - t0;
    let r = exchange(b, &Frame { code: Command::Run as u8, seq: next(), data: plan.run_request().encode() })?;
    if r.code != Command::Run as u8 | 0x80 {
        bail!("Run refused: {r:?}");
    }
    let poll = (config.clock_hz as f64 * pficp::board::DEFAULT_POLL.as_secs_f64()).round() as u64;
    let (mut polls, mut poll_bytes) = (0, 0);
    loop {
        b.run(poll);
        let before = b.byte_counts();
        let st = exchange(b, &Frame { code: Command::Status as u8, seq: next(), data: vec![] })?;
        let after = b.byte_counts();
        polls += 1;
        poll_bytes += (after.0 - before.0) + (after.1 - before.1);
        if StatusReply::decode(&st.data)?.state == RunState::Done {
            break;
        }
    }
    let r = exchange(b, &Frame { code: Command::Result as u8, seq: next(), data: vec![] })?;
    let result = ResultReply::decode(&r.data)?;
    let bytes1 = b.byte_counts();
    let bytes = bytes1.0 - bytes0.0 + bytes1.1 - bytes0.1;
    Ok(Registration { uploaded, clocks: b.clocks() - t0, load_clocks, bytes, poll_bytes, polls, result })
}

/// What one tracked frame took on the simulated board.
struct TrackedFrame {
    clocks: u64,
    /// The tracker's model of the frame's time on the board (`BoardFrame::seconds`).
    modelled_s: f64,
    bytes: u64,
    poll_bytes: u64,
    host_seconds: f64,
}

/// `--track N` (the module doc).
fn track(frames: usize, seed: u64) -> Result<()> {
    use pficp::eval::realistic::Split;
    use pficp::eval::tracking::{sequence, sequence_seed, shapes};
    use pficp::tracking::{TrackSettings, Tracker};
    if !(1..=sequence::FRAMES).contains(&frames) {
        bail!("--track must be 1 to {}", sequence::FRAMES);
    }
    let split = Split::Dev;
    let seq_seed = sequence_seed(seed, split, 1);
    let seq = sequence::sequence(shapes(split)[1], seq_seed, true);
    let nn = NearestNeighbours::new(&seq.model);
    let settings = TrackSettings {
        registration: PfIcpSettings {
            scale: pficp::geometry::ScaleBounds::fixed(1.0),
            seed: seq_seed,
            ..Default::default()
        },
        board_reference: true,
        ..Default::default()
    };
    let mut tracker = Tracker::new(&nn, settings)?;
    let config = BoardConfig::default();
    let mut b = SerialBoard::new(config).with_reference();
    b.run(100);
    let mut seq_no = 1u8;
    let mut next = || {
        seq_no = seq_no.wrapping_add(1).max(1);
        seq_no
    };
    {
        let (grid, normals) = tracker.board_model().context("the board's model")?.stores();
        for (cmd, data) in messages::grid_upload(grid, normals) {
            exchange(&mut b, &Frame { code: cmd as u8, seq: next(), data })?;
        }
    }
    let wall = Instant::now();
    let poll = (config.clock_hz as f64 * pficp::board::DEFAULT_POLL.as_secs_f64()).round() as u64;
    let mut timed = Vec::new();
    for f in seq.frames.iter().take(frames) {
        let frame = tracker.update(&f.scan)?;
        let Some(bf) = frame.board.as_ref().filter(|_| frame.state == pficp::tracking::TrackState::Tracking) else {
            continue;
        };
        let (t0, bytes0) = (b.clocks(), b.byte_counts());
        for (k, chunk) in bf.scan.chunks(messages::MAX_LOAD_POINTS).enumerate() {
            let data = messages::load_request((k * messages::MAX_LOAD_POINTS) as u16, chunk);
            exchange(&mut b, &Frame { code: Command::LoadScan as u8, seq: next(), data })?;
        }
        let sizes = messages::two_u16(bf.model_points as u16, bf.filter_points as u16);
        exchange(&mut b, &Frame { code: Command::SetSizes as u8, seq: next(), data: sizes })?;
        exchange(&mut b, &Frame { code: Command::Run as u8, seq: next(), data: bf.run.encode() })?;
        let mut poll_bytes = 0;
        loop {
            b.run(poll);
            let before = b.byte_counts();
            let st = exchange(&mut b, &Frame { code: Command::Status as u8, seq: next(), data: vec![] })?;
            let after = b.byte_counts();
            poll_bytes += (after.0 - before.0) + (after.1 - before.1);
            if StatusReply::decode(&st.data)?.state == RunState::Done {
                break;
            }
        }
        let r = exchange(&mut b, &Frame { code: Command::Result as u8, seq: next(), data: vec![] })?;
        let result = ResultReply::decode(&r.data)?;
        if result.params != bf.params || result.polish != bf.polish {
            bail!("frame {}: the board's parameters or polish differ from the reference's", frame.frame);
        }
        let bytes1 = b.byte_counts();
        timed.push(TrackedFrame {
            clocks: b.clocks() - t0,
            modelled_s: bf.seconds(config.baud),
            bytes: bytes1.0 - bytes0.0 + bytes1.1 - bytes0.1,
            poll_bytes,
            host_seconds: frame.host_seconds,
        });
    }
    if timed.is_empty() {
        bail!("no frame among the first {frames} was tracked");
    }
    timed.sort_by_key(|t| t.clocks);
    let m = &timed[timed.len() / 2];
    let hz = config.clock_hz as f64;
    let wire_s = |bytes: u64, baud: u32| {
        let p = BitPeriod::new(config.clock_hz, baud);
        (bytes * 10) as f64 * p.clocks as f64 / p.bits as f64 / hz
    };
    let mut host: Vec<f64> = timed.iter().map(|t| t.host_seconds).collect();
    host.sort_by(f64::total_cmp);
    let host_s = host[host.len() / 2];
    let board_s = m.clocks as f64 / hz;
    let slow_s = board_s - wire_s(m.bytes, config.baud) + wire_s(m.bytes, 921_600);
    println!(
        "tracking {} (dev split, seed {seed}, scale known): {} of the first {frames} frames tracked on the Verilated \
         board, every Result equal to the reference's (simulated in {:.1} s)",
        seq.id,
        timed.len(),
        wall.elapsed().as_secs_f64()
    );
    println!(
        "median frame on the board: {board_s:.4} s at {:.0} MHz and {} baud ({} clocks, {} bytes on the wire, {} of \
         them Status polls); at 921600 baud (modelled from the byte counts): {slow_s:.4} s",
        hz / 1e6,
        config.baud,
        m.clocks,
        m.bytes,
        m.poll_bytes
    );
    let mut modelled: Vec<f64> = timed.iter().map(|t| t.modelled_s).collect();
    modelled.sort_by(f64::total_cmp);
    println!(
        "the tracker's model of the same frames on the board: {:.4} s median (its polish and link at their modelled \
         clocks and bytes)",
        modelled[modelled.len() / 2]
    );
    println!(
        "with the host's polish and checks ({host_s:.4} s median): {:.1} frames/s at {} baud, {:.1} at 921600",
        1.0 / (board_s + host_s),
        config.baud,
        1.0 / (slow_s + host_s)
    );
    Ok(())
}

fn main() -> Result<()> {
    let a = Args::parse();
    if let Some(n) = a.track {
        return track(n, a.seed);
    }
    let id = ModelId::Model1;
    let truth = id.table1_truth();
    let spec = ScanSpec { sampling: Sampling::Independent { points: a.scan_points }, noise: 0.0, seed: a.seed };
    let ds = make(id, a.model_points, &truth, &spec);
    let nn = NearestNeighbours::new(&ds.model);
    let diag = bbox_diagonal(&ds.model);
    let settings =
        PfIcpSettings { particles: a.particles, iterations: a.iterations, seed: a.seed, ..Default::default() };

    // Software mode: median wall time of `runs`.
    let mut times = Vec::new();
    let mut soft = None;
    for _ in 0..a.runs.max(1) {
        let t = Instant::now();
        let r = pf_icp::register(&nn, &ds.scan, &settings);
        times.push(t.elapsed());
        soft = Some(r);
    }
    times.sort();
    let soft_time = times[times.len() / 2];
    let soft = soft.context("no software run")?;

    // The board: a first registration with the model's upload, then a second on the same
    // board, whose model digest (Identify) says it holds the model already (the host's
    // `ensure_grid`): only the scan sample, SetSizes, Run, Status polls and Result.
    let mut plan = on_board::plan(&nn, &ds.scan, &settings, a.board_points, 4096)?;
    if a.all_iterations {
        (plan.config.thr_cost, plan.config.thr_max) = (0, 0);
    }
    if let Some(steps) = a.polish_steps {
        if steps > pficp_fpga::protocol::run_request::MAX_STEPS {
            bail!("--polish-steps must be at most {}", pficp_fpga::protocol::run_request::MAX_STEPS);
        }
        plan.polish.steps = steps;
    }
    if let Some(steps) = a.winner_steps {
        if steps > pficp_fpga::protocol::run_request::MAX_STEPS {
            bail!("--winner-steps must be at most {}", pficp_fpga::protocol::run_request::MAX_STEPS);
        }
        plan.polish.winner_steps = steps;
    }
    if let Some(starts) = a.polish_starts {
        if starts == 0 || starts > 1 + plan.polish.hypotheses.len() {
            bail!("--polish-starts must be 1 to {} here", 1 + plan.polish.hypotheses.len());
        }
        plan.polish.hypotheses.truncate(starts - 1);
    }
    if let Some(points) = a.polish_points {
        if points == 0 || points > plan.polish.points {
            bail!("--polish-points must be 1 to {}", plan.polish.points);
        }
        plan.polish.points = points;
    }
    let config = BoardConfig::default();
    let mut b = SerialBoard::new(config).with_reference();
    b.run(100);
    let wall = Instant::now();
    let first = registration(&mut b, &plan, config)?;
    let second = registration(&mut b, &plan, config)?;
    if first.result != second.result || !first.uploaded || second.uploaded {
        bail!("the second registration differs from the first, or the resident model was not recognised");
    }
    let (compared, _) = b.comparison();
    let fin = on_board::finish(&plan, &nn, &ds.scan, &settings, &second.result, Duration::ZERO);
    let hz = config.clock_hz as f64;
    let soft_err = PoseError::between(&soft.registration.pose, &truth, diag);
    let board_err = PoseError::between(&fin.registration.pose, &truth, diag);
    let alone_err = PoseError::between(&fin.filter_pose, &truth, diag);
    println!(
        "model-1, {} model points, {} scan points ({} weighed on the board, {} polished over in {} steps from {} \
         starts, the winner {} more), {} particles, {} iterations cap; {compared} board bytes equal to the reference (simulated in {:.1} s)",
        a.model_points,
        a.scan_points,
        plan.scan.len(),
        plan.polish.points,
        plan.polish.steps,
        1 + plan.polish.hypotheses.len(),
        plan.polish.winner_steps,
        a.particles,
        a.iterations,
        wall.elapsed().as_secs_f64()
    );
    // The same bytes at 921,600 baud: the wire time at the simulated rate out, at 921,600 in.
    let wire_s = |bytes: u64, baud: u32| {
        let p = BitPeriod::new(config.clock_hz, baud);
        (bytes * 10) as f64 * p.clocks as f64 / p.bits as f64 / hz
    };
    const SLOW_BAUD: u32 = 921_600;
    for (name, r) in [("first (model uploaded)", &first), ("resident model", &second)] {
        let board_s = r.clocks as f64 / hz;
        let at_default = wire_s(r.bytes, config.baud);
        let at_slow = wire_s(r.bytes, SLOW_BAUD);
        println!(
            "board, {name}: {board_s:.3} s at {:.0} MHz and {} baud ({} clocks: loads {:.3} s, run to result {:.3} s; \
             {} iterations; {} bytes on the wire, UART {at_default:.3} s; {} Status polls)",
            hz / 1e6,
            config.baud,
            r.clocks,
            r.load_clocks as f64 / hz,
            (r.clocks - r.load_clocks) as f64 / hz,
            r.result.iterations,
            r.bytes,
            r.polls
        );
        println!(
            "  at {SLOW_BAUD} baud (modelled from the byte counts): {:.3} s (an upper bound by at most {:.3} s: the \
             Status polls' {} bytes overlap the filter)",
            board_s - at_default + at_slow,
            wire_s(r.poll_bytes, SLOW_BAUD) - wire_s(r.poll_bytes, config.baud),
            r.poll_bytes
        );
    }
    println!("software: {:.3} s (median of {})", soft_time.as_secs_f64(), times.len());
    println!(
        "accuracy vs truth: board alone {:.3} deg, {:.3}% diagonal; board + polish {:.3} deg, {:.3}% diagonal; \
         software {:.3} deg, {:.3}% diagonal",
        alone_err.rotation_deg,
        100.0 * alone_err.translation_frac,
        board_err.rotation_deg,
        100.0 * board_err.translation_frac,
        soft_err.rotation_deg,
        100.0 * soft_err.translation_frac
    );
    Ok(())
}
