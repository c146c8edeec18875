//! `CommandEngine<P>`: executes one received frame at a time (docs/protocol.md): reads the
//! frame buffer, checks the command ([`RequestCheck`]: busy, code, lengths, capacities), drives the
//! nearest-neighbour pipeline and the weight stage, writes the stores, and builds the reply
//! in the [`ReplySender`]. Everything here is sequential and slow next to the pipeline:
//! the UART gives it ~1,000 clocks per byte.
//!
//! Sub-routines (`Fetch*`: read `fcount` frame bytes into `inbuf`; `Emit`: append `ecount`
//! bytes of `outbuf` to the reply) return to the state in `ret`; the states are [`EngState`]
//! (`engine_state_rtl.rs`), the kernel is the wiring (`engine_signals_rtl.rs`) then the states'
//! arms (`engine_kernel_rtl.rs`), the scan stream into the pipeline is the
//! [`ScanFeeder`].
//!
//! After the filter the engine runs the polish ([`PolishUnit`], docs/polish-datapath.md): it lends
//! it the sequencer's multiplier, gives it its starts (the filter's pose, then the Run's
//! hypotheses) and serves its passes: the pipeline at the unit's pose over the first
//! `points` stored scan points, each found result (distance below `CAP_D2`) handed to the
//! pass through a queue ([`PassQueue`], [`PASS_QUEUE`](super::pass_queue::PASS_QUEUE)
//! entries). Points are let in on credit (the feeder's `hold` while the points in the
//! pipeline and in the queue are as many as the queue's entries), so the pipeline's
//! latency overlaps the pass's 15 clocks an inlier.

use super::digest_rtl::ModelDigest;
use super::pass_queue_rtl::PassQueue;
use super::reply_tx_rtl::ReplySender;
use super::request_check_rtl::RequestCheck;
use super::scan_feeder_rtl::ScanFeeder;
use crate::board::BoardConfig;
use crate::filter::pf::{RUN_BYTES, RUN_HEADER_BYTES, RUN_WORD_BYTES};
use crate::filter::sequencer_rtl::PfSequencer;
use crate::filter::weights_rtl::WeightStage;
use crate::polish::unit_rtl::PolishUnit;
use crate::protocol::layout::{POINT_BYTES, POSE_BYTES};
use crate::protocol::messages::{
    Identity, COST_BYTES, DIGEST_BYTES, EVALUATE_HEADER_BYTES, IDENTITY_BYTES, LOAD_HEADER_BYTES, NEAREST_HEAD_BYTES,
    NEAREST_REQUEST_BYTES, NEAREST_RESULT_BYTES, RESULT_HEAD_BYTES, RESULT_PARAMS_BYTES, RESULT_POLISH_HEAD_BYTES,
    RUN_REPLY_BYTES, STATUS_BYTES, TABLE_ENTRY_BYTES, TWO_U16_BYTES, WEIGHT_BYTES, WEIGHT_SUMMARY_BYTES,
};
use crate::protocol::run_request::RUN_BASE_BYTES;
use crate::protocol::Command;
use crate::protocol::{ErrorCode, CRC_BYTES, ERROR_DATA_BYTES, HEADER_BYTES};
use crate::search::neighbour_pipeline_rtl::NeighbourPipeline;
use crate::surface::surface_residual_rtl::SurfaceResidual;
use rust_hdl::prelude::*;

#[path = "engine_kernel_rtl.rs"]
mod kernel;
#[path = "engine_signals_rtl.rs"]
mod signals;

/// A length as a `Fetch` or `Emit` count (`inbuf` and `outbuf` hold 27 bytes; the count
/// is 5 bits).
fn emit_count(bytes: usize) -> Constant<Bits<5>> {
    assert!(bytes <= POSE_BYTES, "{bytes} bytes do not fit the engine's buffers");
    Constant::new(Bits::<5>::from(bytes as u64))
}

/// A frame buffer address (11 bits).
fn frame_address(at: usize) -> Constant<Bits<11>> {
    Constant::new(Bits::<11>::from(at as u64))
}

// The header fetch takes the longest command header (the sums decode from it).
const _: () = assert!(LOAD_HEADER_BYTES <= EVALUATE_HEADER_BYTES && RUN_HEADER_BYTES == EVALUATE_HEADER_BYTES);

// The loads are told apart by their codes' bits: bit 3 LoadTable, else bit 0 LoadScan.
const _: () = assert!(
    (Command::LoadTable as u8) & 8 != 0 && (Command::LoadModel as u8) & 9 == 0 && (Command::LoadScan as u8) & 9 == 1
);
// A table entry arrives in the top 16 bits of `inbuf` (13 used).
const _: () = assert!(TABLE_ENTRY_BYTES == 2);

// The Run, Load and SetSizes replies echo four bytes (`EchoBody`).
const _: () = assert!(RUN_REPLY_BYTES == TWO_U16_BYTES);
#[path = "engine_state_rtl.rs"]
mod state;
pub use state::EngState;

/// The command engine with a `P`-lane pipeline, its stores and the reply sender.
#[derive(LogicBlock)]
pub struct CommandEngine<const P: usize> {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// Synchronous reset (to idle; stores, sizes and costs are kept).
    pub reset: Signal<In, Bit>,
    /// Frame buffer write enable (from the receiver).
    pub fr_we: Signal<In, Bit>,
    /// Frame buffer write address.
    pub fr_waddr: Signal<In, Bits<11>>,
    /// Frame buffer write data.
    pub fr_wdata: Signal<In, Bits<8>>,
    /// A frame ended.
    pub frame: Signal<In, Bit>,
    /// Its status (0 valid, else the error code).
    pub status: Signal<In, Bits<3>>,
    /// Its decoded length (body and CRC).
    pub len: Signal<In, Bits<11>>,
    /// Its command.
    pub cmd: Signal<In, Bits<8>>,
    /// Its sequence number.
    pub seq: Signal<In, Bits<8>>,
    /// Some byte of it arrived while busy.
    pub busy_seen: Signal<In, Bit>,
    /// Executing or answering.
    pub busy: Signal<Out, Bit>,
    /// The last answer was an error reply.
    pub error: Signal<Out, Bit>,
    /// The particle filter is running.
    pub running: Signal<Out, Bit>,
    /// The serial line out.
    pub tx: Signal<Out, Bit>,
    ident: Constant<Bits<216>>,
    state: DFF<EngState>,
    ret: DFF<EngState>,
    dlen: DFF<Bits<11>>,
    cur_cmd: DFF<Bits<8>>,
    cur_seq: DFF<Bits<8>>,
    e_code: DFF<Bits<8>>,
    e_cmd: DFF<Bits<8>>,
    e_seq: DFF<Bits<8>>,
    pending: DFF<Bit>,
    p_cmd: DFF<Bits<8>>,
    p_seq: DFF<Bits<8>>,
    err_led: DFF<Bit>,
    faddr: DFF<Bits<11>>,
    fcount: DFF<Bits<5>>,
    inbuf: DFF<Bits<216>>,
    outbuf: DFF<Bits<216>>,
    ecount: DFF<Bits<5>>,
    hdr: DFF<Bits<48>>,
    model_count: DFF<Bits<13>>,
    scan_count: DFF<Bits<13>>,
    idx: DFF<Bits<16>>,
    /// Store write address (13 bits: the cell table has 4,097 entries).
    waddr: DFF<Bits<13>>,
    eval_mode: DFF<Bit>,
    /// The pipeline's `start`, registered (its outputs feed this block's state machine).
    start_r: DFF<Bit>,
    wi: DFF<Bits<9>>,
    ncost: DFF<Bits<48>>,
    /// A load's header bytes on their way into the digest.
    dig_sr: DFF<Bits<32>>,
    /// The digest restarts with the next byte (a LoadModel at offset 0).
    dig_restart: DFF<Bit>,
    /// The checks' sums, registered a clock before Dispatch (short paths).
    // The scan stream into the pipeline: read-ahead of up to two points.
    frame_buf: RAM<Bits<8>, 11>,
    scan_store: RAM<Bits<48>, 12>,
    /// Nearest results (index | distance << 12) or weights, by particle / point.
    aux: RAM<Bits<46>, 8>,
    nn: NeighbourPipeline<P>,
    /// The residual stage after the pipeline: its results and costs are the board's.
    surf: SurfaceResidual,
    ws: WeightStage,
    filter: PfSequencer,
    sender: ReplySender,
    feeder: ScanFeeder,
    check: RequestCheck,
    model_digest: ModelDigest,
    all48: Constant<Bits<48>>,
    e_busy: Constant<Bits<8>>,
    e_no_result: Constant<Bits<8>>,
    // Frame buffer addresses and fetch lengths (`Fetch*`), from the protocol's layouts.
    a_overhead: Constant<Bits<11>>,
    a_body: Constant<Bits<11>>,
    a_load: Constant<Bits<11>>,
    a_nearest: Constant<Bits<11>>,
    a_run: Constant<Bits<11>>,
    a_eval: Constant<Bits<11>>,
    n_head_fetch: Constant<Bits<5>>,
    n_point: Constant<Bits<5>>,
    n_entry: Constant<Bits<5>>,
    n_word: Constant<Bits<5>>,
    // Reply lengths (`Emit` counts), from the protocol's layouts.
    n_header: Constant<Bits<5>>,
    n_error: Constant<Bits<5>>,
    n_status: Constant<Bits<5>>,
    n_result_head: Constant<Bits<5>>,
    n_result_params: Constant<Bits<5>>,
    n_pose: Constant<Bits<5>>,
    n_identity: Constant<Bits<5>>,
    n_digest: Constant<Bits<5>>,
    n_echo: Constant<Bits<5>>,
    n_cost: Constant<Bits<5>>,
    n_summary: Constant<Bits<5>>,
    n_weight: Constant<Bits<5>>,
    n_nearest_head: Constant<Bits<5>>,
    n_nearest_result: Constant<Bits<5>>,
    h: Signal<Local, Bits<48>>,
    h_lo: Signal<Local, Bits<16>>,
    h_hi: Signal<Local, Bits<16>>,
    h_n: Signal<Local, Bits<8>>,
    sizes_unset: Signal<Local, Bit>,
    hdr_end: Signal<Local, Bits<13>>,
    /// The polish after the filter.
    polish: PolishUnit,
    /// The Run's polish: stored scan points a pass goes over, steps, the winner's further
    /// steps, starts (1 to 15).
    pol_count: DFF<Bits<13>>,
    pol_steps: DFF<Bits<4>>,
    pol_more: DFF<Bits<4>>,
    /// The Run's polish holds the scale (bit 0 of the polish word's fifth byte).
    pol_held: DFF<Bit>,
    pol_starts: DFF<Bits<4>>,
    /// The Run's hypotheses, start `k` at word `k` (1 to 14; read a clock after the
    /// polish's `start_index` names it), and how many are in.
    hyps: RAM<Bits<216>, 4>,
    hcnt: DFF<Bits<4>>,
    /// A Run's polish is to follow its filter; the filter has ended (its `running` fell).
    pol_arm: DFF<Bit>,
    pol_ready: DFF<Bit>,
    /// The filter's `running`, a clock late.
    run_r: DFF<Bit>,
    /// A pass asked for and not yet launched; a pass in progress.
    pass_req: DFF<Bit>,
    pol_pass: DFF<Bit>,
    /// The pass's points let into the pipeline whose results are not out yet.
    outst: DFF<Bits<5>>,
    /// Found results waiting for the pass; how many (written, not yet taken).
    found: PassQueue,
    occ: DFF<Bits<5>>,
    /// The pass's cost is in.
    pc_seen: DFF<Bit>,
    pc_cost: DFF<Bits<48>>,
    /// Clocks the pass has been ready since its last point (to 7).
    quiet: DFF<Bits<3>>,
    cap_d2: Constant<Bits<34>>,
    max_points16: Constant<Bits<16>>,
    e_capacity: Constant<Bits<8>>,
    a_polish: Constant<Bits<11>>,
    a_hyp: Constant<Bits<11>>,
    n_polish_head: Constant<Bits<5>>,
    /// The filter or the polish is running (or about to).
    running_l: Signal<Local, Bit>,
    pw_count: Signal<Local, Bits<16>>,
}

impl<const P: usize> CommandEngine<P> {
    /// The engine of a board with `P` lanes, the clock and the nominal baud rate of
    /// `config` reported by Identify, its UART at `config`'s bit period.
    pub fn new(config: &BoardConfig) -> Self {
        let id = Identity::of_board(P as u8, config.clock_hz, config.baud, 0, 0, 0).encode();
        let mut ident = Bits::<216>::default();
        for (k, &b) in id.iter().take(20).enumerate() {
            ident = ident | (Bits::<216>::from(b as u64) << (8 * k as u64));
        }
        CommandEngine {
            clock: Default::default(),
            reset: Default::default(),
            fr_we: Default::default(),
            fr_waddr: Default::default(),
            fr_wdata: Default::default(),
            frame: Default::default(),
            status: Default::default(),
            len: Default::default(),
            cmd: Default::default(),
            seq: Default::default(),
            busy_seen: Default::default(),
            busy: Default::default(),
            error: Default::default(),
            running: Default::default(),
            tx: Default::default(),
            ident: Constant::new(ident),
            state: Default::default(),
            ret: Default::default(),
            dlen: Default::default(),
            cur_cmd: Default::default(),
            cur_seq: Default::default(),
            e_code: Default::default(),
            e_cmd: Default::default(),
            e_seq: Default::default(),
            pending: Default::default(),
            p_cmd: Default::default(),
            p_seq: Default::default(),
            err_led: Default::default(),
            faddr: Default::default(),
            fcount: Default::default(),
            inbuf: Default::default(),
            outbuf: Default::default(),
            ecount: Default::default(),
            hdr: Default::default(),
            model_count: Default::default(),
            scan_count: Default::default(),
            idx: Default::default(),
            waddr: Default::default(),
            eval_mode: Default::default(),
            start_r: Default::default(),
            wi: Default::default(),
            ncost: Default::default(),
            dig_sr: Default::default(),
            dig_restart: Default::default(),
            frame_buf: Default::default(),
            scan_store: Default::default(),
            aux: Default::default(),
            nn: NeighbourPipeline::new(),
            surf: SurfaceResidual::new(),
            ws: WeightStage::new(),
            filter: PfSequencer::new(),
            sender: ReplySender::new(config.bit_period()),
            feeder: ScanFeeder::new(),
            check: RequestCheck::new(),
            model_digest: ModelDigest::default(),
            all48: Constant::new(Bits::<48>::from((1u64 << 48) - 1)),
            e_busy: Constant::new(Bits::<8>::from(ErrorCode::Busy as u64)),
            e_no_result: Constant::new(Bits::<8>::from(ErrorCode::NoResult as u64)),
            a_overhead: frame_address(HEADER_BYTES + CRC_BYTES),
            a_body: frame_address(HEADER_BYTES),
            a_load: frame_address(HEADER_BYTES + LOAD_HEADER_BYTES),
            a_nearest: frame_address(HEADER_BYTES + NEAREST_REQUEST_BYTES - POSE_BYTES),
            a_run: frame_address(HEADER_BYTES + RUN_HEADER_BYTES),
            a_eval: frame_address(HEADER_BYTES + EVALUATE_HEADER_BYTES),
            n_head_fetch: emit_count(EVALUATE_HEADER_BYTES),
            n_point: emit_count(POINT_BYTES),
            n_entry: emit_count(TABLE_ENTRY_BYTES),
            n_word: emit_count(RUN_WORD_BYTES),
            n_header: emit_count(HEADER_BYTES),
            n_error: emit_count(HEADER_BYTES + ERROR_DATA_BYTES),
            n_status: emit_count(STATUS_BYTES),
            n_result_head: emit_count(RESULT_HEAD_BYTES),
            n_result_params: emit_count(RESULT_PARAMS_BYTES),
            n_pose: emit_count(POSE_BYTES),
            n_identity: emit_count(IDENTITY_BYTES - DIGEST_BYTES),
            n_digest: emit_count(DIGEST_BYTES),
            n_echo: emit_count(TWO_U16_BYTES),
            n_cost: emit_count(COST_BYTES),
            n_summary: emit_count(WEIGHT_SUMMARY_BYTES),
            n_weight: emit_count(WEIGHT_BYTES),
            n_nearest_head: emit_count(NEAREST_HEAD_BYTES),
            n_nearest_result: emit_count(NEAREST_RESULT_BYTES),
            h: Default::default(),
            h_lo: Default::default(),
            h_hi: Default::default(),
            h_n: Default::default(),
            sizes_unset: Default::default(),
            hdr_end: Default::default(),
            polish: PolishUnit::new(),
            pol_count: Default::default(),
            pol_steps: Default::default(),
            pol_more: Default::default(),
            pol_held: Default::default(),
            pol_starts: Default::default(),
            hyps: Default::default(),
            hcnt: Default::default(),
            pol_arm: Default::default(),
            pol_ready: Default::default(),
            run_r: Default::default(),
            pass_req: Default::default(),
            pol_pass: Default::default(),
            outst: Default::default(),
            found: Default::default(),
            occ: Default::default(),
            pc_seen: Default::default(),
            pc_cost: Default::default(),
            quiet: Default::default(),
            cap_d2: Constant::new(Bits::<34>::from(crate::search::grid::CAP_D2)),
            max_points16: Constant::new(Bits::<16>::from(crate::common::format::MAX_POINTS as u64)),
            e_capacity: Constant::new(Bits::<8>::from(ErrorCode::OverCapacity as u64)),
            a_polish: frame_address(HEADER_BYTES + RUN_BYTES),
            a_hyp: frame_address(HEADER_BYTES + RUN_BASE_BYTES),
            n_polish_head: emit_count(RESULT_POLISH_HEAD_BYTES),
            running_l: Default::default(),
            pw_count: Default::default(),
        }
    }
}
