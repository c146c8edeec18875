//! `CommandEngine<P>`: executes one received frame at a time (docs/protocol.md): reads the
//! frame buffer, checks the command ([`RequestCheck`]: busy, code, lengths, capacities), drives the
//! nearest-neighbour pipeline and the weight stage, writes the stores, and builds the reply
//! in the [`ReplySender`]. Everything here is sequential and slow next to the pipeline:
//! the UART gives it ~1,000 clocks per byte.
//!
//! Sub-routines (`Fetch*`: read `fcount` frame bytes into `inbuf`; `Emit`: append `ecount`
//! bytes of `outbuf` to the reply) return to the state in `ret`; the states are [`EngState`]
//! (`state.rs`), the state machine is `kernel.rs`, the scan stream into the pipeline is the
//! [`ScanFeeder`].

use super::reply_tx::ReplySender;
use super::request_check::RequestCheck;
use super::scan_feeder::ScanFeeder;
use super::sequencer::PfSequencer;
use crate::messages::Identity;
use crate::protocol::ErrorCode;
use crate::rtl::pipeline::NnPipeline;
use crate::rtl::weights::WeightStage;
use rust_hdl::prelude::*;

mod kernel;
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
    waddr: DFF<Bits<12>>,
    eval_mode: DFF<Bit>,
    /// The pipeline's `start`, registered (its outputs feed this block's state machine).
    start_r: DFF<Bit>,
    wi: DFF<Bits<9>>,
    ncost: DFF<Bits<48>>,
    /// The checks' sums, registered a clock before Dispatch (short paths).
    // The scan stream into the pipeline: read-ahead of up to two points.
    frame_buf: RAM<Bits<8>, 11>,
    scan_store: RAM<Bits<48>, 12>,
    /// Nearest results (index | distance << 12) or weights, by particle / point.
    aux: RAM<Bits<46>, 8>,
    nn: NnPipeline<P>,
    ws: WeightStage,
    filter: PfSequencer,
    sender: ReplySender,
    feeder: ScanFeeder,
    check: RequestCheck,
    all48: Constant<Bits<48>>,
    e_busy: Constant<Bits<8>>,
    e_no_result: Constant<Bits<8>>,
    h: Signal<Local, Bits<48>>,
    h_lo: Signal<Local, Bits<16>>,
    h_hi: Signal<Local, Bits<16>>,
    h_n: Signal<Local, Bits<8>>,
    sizes_unset: Signal<Local, Bit>,
    hdr_end: Signal<Local, Bits<13>>,
}

impl<const P: usize> CommandEngine<P> {
    /// The engine of a board with `P` lanes, `clock_hz` and `baud` reported by Identify,
    /// its UART at `bit_clocks` clocks per bit.
    pub fn new(clock_hz: u32, baud: u32, bit_clocks: u32) -> Self {
        let id = Identity::of_board(P as u8, clock_hz, baud, 0, 0, 0).encode();
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
            frame_buf: Default::default(),
            scan_store: Default::default(),
            aux: Default::default(),
            nn: NnPipeline::new(),
            ws: WeightStage::new(),
            filter: PfSequencer::new(),
            sender: ReplySender::new(bit_clocks),
            feeder: ScanFeeder::new(),
            check: RequestCheck::new(),
            all48: Constant::new(Bits::<48>::from((1u64 << 48) - 1)),
            e_busy: Constant::new(Bits::<8>::from(ErrorCode::Busy as u64)),
            e_no_result: Constant::new(Bits::<8>::from(ErrorCode::NoResult as u64)),
            h: Default::default(),
            h_lo: Default::default(),
            h_hi: Default::default(),
            h_n: Default::default(),
            sizes_unset: Default::default(),
            hdr_end: Default::default(),
        }
    }
}
