//! `CommandEngine<P>`: executes one received frame at a time (docs/protocol.md): reads the
//! frame buffer, checks the command (code, then lengths, then capacities), drives the
//! nearest-neighbour pipeline and the weight stage, writes the stores, and builds the reply
//! in the [`ReplySender`]. Everything here is sequential and slow next to the pipeline:
//! the UART gives it ~1,000 clocks per byte.
//!
//! Sub-routines (`Fetch*`: read `fcount` frame bytes into `inbuf`; `Emit`: append `ecount`
//! bytes of `outbuf` to the reply) return to the state in `ret`.

use super::reply_tx::ReplySender;
use crate::messages::{Identity, MAX_LOAD_POINTS, MAX_NEAREST, MAX_POSES};

// The limits are literals in the kernel (`#[hdl_gen]` takes no paths): keep them equal.
const _: () = assert!(MAX_LOAD_POINTS == 170 && MAX_POSES == 37 && MAX_NEAREST == 144);
use super::sequencer::PfSequencer;
use crate::rtl::pipeline::NnPipeline;
use crate::rtl::weight_stage::WeightStage;
use rust_hdl::prelude::*;

/// Engine states.
#[derive(Copy, Clone, Debug, PartialEq, Eq, LogicState)]
pub enum EngState {
    /// Waiting for a frame (or a pending Busy answer).
    Idle,
    /// The six header bytes are in: register the sums the checks need.
    Decode,
    /// Check and dispatch.
    Dispatch,
    /// Fetch: put the frame buffer address.
    FetchAddr,
    /// Fetch: take the byte.
    FetchData,
    /// Emit: append the next byte of `outbuf` when the sender is ready.
    Emit,
    /// Start a reply: command | 0x80 and sequence.
    Header,
    /// Start an error reply.
    ErrHeader,
    /// Append the CRC and transmit.
    Send,
    /// Wait for the last byte to leave.
    SendWait,
    /// Identify: the 26 data bytes.
    IdBody,
    /// Load: next point or done.
    LoadNext,
    /// Load: write the fetched point.
    LoadWrite,
    /// Load / SetSizes reply: the 4 header bytes back.
    EchoBody,
    /// Evaluate: clear the stored costs with FIRST.
    EvBegin,
    /// Evaluate: next pose or done.
    EvNext,
    /// Evaluate: start the pipeline on the fetched pose.
    EvRun,
    /// Evaluate: wait for the cost.
    EvWait,
    /// Evaluate: count the pose.
    EvInc,
    /// Evaluate: all poses done; weigh with LAST.
    EvDone,
    /// Evaluate: collect the weights.
    WeighWait,
    /// Evaluate: the summary (stored, min cost, weight sum).
    SumEmit,
    /// Evaluate: next weight or done.
    WLoop,
    /// Evaluate: append a weight.
    WRead,
    /// Nearest: start the pipeline on the fetched pose.
    NrRun,
    /// Nearest: collect results and the cost.
    NrWait,
    /// Nearest: first, count, cost.
    NrHead,
    /// Nearest: next result or done.
    NrLoop,
    /// Nearest: append a result.
    NrRead,
    /// Run: next configuration word or the header word.
    RunNext,
    /// Run: write the fetched word.
    RunWrite,
    /// Run: start the sequencer, answer.
    RunGo,
    /// Status: the 9 data bytes.
    StBody,
    /// Result: iterations, cost, largest distance.
    ResBody1,
    /// Result: the parameters.
    ResBody2,
    /// Result: the pose.
    ResBody3,
}

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
    times6_r: DFF<Bits<20>>,
    times27_r: DFF<Bits<20>>,
    sum17_r: DFF<Bits<17>>,
    new_count_r: DFF<Bits<10>>,
    // The scan stream into the pipeline: read-ahead of up to two points.
    sa: DFF<Bits<13>>,
    send: DFF<Bits<13>>,
    occ: DFF<Bits<2>>,
    q0: DFF<Bits<48>>,
    q0_last: DFF<Bit>,
    q1: DFF<Bits<48>>,
    q1_last: DFF<Bit>,
    inflight: DFF<Bit>,
    inflight_last: DFF<Bit>,
    frame_buf: RAM<Bits<8>, 11>,
    scan_store: RAM<Bits<48>, 12>,
    /// Nearest results (index | distance << 12) or weights, by particle / point.
    aux: RAM<Bits<46>, 8>,
    nn: NnPipeline<P>,
    ws: WeightStage,
    filter: PfSequencer,
    sender: ReplySender,
    all48: Constant<Bits<48>>,
    h: Signal<Local, Bits<48>>,
    h_lo: Signal<Local, Bits<16>>,
    h_hi: Signal<Local, Bits<16>>,
    h_n: Signal<Local, Bits<8>>,
    times6: Signal<Local, Bits<20>>,
    times27: Signal<Local, Bits<20>>,
    sum17: Signal<Local, Bits<17>>,
    new_count: Signal<Local, Bits<10>>,
    sizes_unset: Signal<Local, Bit>,
    take: Signal<Local, Bit>,
    issue: Signal<Local, Bit>,
    occ_after: Signal<Local, Bits<2>>,
    hdr_end: Signal<Local, Bits<13>>,
    streaming: Signal<Local, Bit>,
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
            times6_r: Default::default(),
            times27_r: Default::default(),
            sum17_r: Default::default(),
            new_count_r: Default::default(),
            sa: Default::default(),
            send: Default::default(),
            occ: Default::default(),
            q0: Default::default(),
            q0_last: Default::default(),
            q1: Default::default(),
            q1_last: Default::default(),
            inflight: Default::default(),
            inflight_last: Default::default(),
            frame_buf: Default::default(),
            scan_store: Default::default(),
            aux: Default::default(),
            nn: NnPipeline::new(),
            ws: WeightStage::new(),
            filter: PfSequencer::new(),
            sender: ReplySender::new(bit_clocks),
            all48: Constant::new(Bits::<48>::from((1u64 << 48) - 1)),
            h: Default::default(),
            h_lo: Default::default(),
            h_hi: Default::default(),
            h_n: Default::default(),
            times6: Default::default(),
            times27: Default::default(),
            sum17: Default::default(),
            new_count: Default::default(),
            sizes_unset: Default::default(),
            take: Default::default(),
            issue: Default::default(),
            occ_after: Default::default(),
            hdr_end: Default::default(),
            streaming: Default::default(),
        }
    }
}

impl<const P: usize> Logic for CommandEngine<P> {
    #[hdl_gen]
    fn update(&mut self) {
        dff_setup!(
            self,
            clock,
            state,
            ret,
            dlen,
            cur_cmd,
            cur_seq,
            e_code,
            e_cmd,
            e_seq,
            pending,
            p_cmd,
            p_seq,
            err_led,
            faddr,
            fcount,
            inbuf,
            outbuf,
            ecount,
            hdr,
            model_count,
            scan_count,
            idx,
            waddr,
            eval_mode,
            start_r,
            wi,
            ncost,
            times6_r,
            times27_r,
            sum17_r,
            new_count_r,
            sa,
            send,
            occ,
            q0,
            q0_last,
            q1,
            q1_last,
            inflight,
            inflight_last
        );
        self.nn.clock.next = self.clock.val();
        self.ws.clock.next = self.clock.val();
        self.filter.clock.next = self.clock.val();
        self.sender.clock.next = self.clock.val();
        self.frame_buf.read_clock.next = self.clock.val();
        self.frame_buf.write_clock.next = self.clock.val();
        self.scan_store.read_clock.next = self.clock.val();
        self.scan_store.write_clock.next = self.clock.val();
        self.aux.read_clock.next = self.clock.val();
        self.aux.write_clock.next = self.clock.val();

        // Outputs.
        self.busy.next = self.state.q.val() != EngState::Idle;
        self.error.next = self.err_led.q.val();
        self.running.next = self.filter.running.val();
        self.tx.next = self.sender.tx.val();
        self.sender.reset.next = self.reset.val();

        // The frame buffer: written by the receiver, read at `faddr`.
        self.frame_buf.write_enable.next = self.fr_we.val();
        self.frame_buf.write_address.next = self.fr_waddr.val();
        self.frame_buf.write_data.next = self.fr_wdata.val();
        self.frame_buf.read_address.next = self.faddr.q.val();

        // Header fields of the current command (after the six-byte fetch).
        self.h.next = self.inbuf.q.val().get_bits::<48>(168);
        self.h_lo.next = self.h.val().get_bits::<16>(0);
        self.h_hi.next = self.h.val().get_bits::<16>(16);
        self.h_n.next = self.h.val().get_bits::<8>(40);
        self.times6.next = (bit_cast::<20, 16>(self.h_hi.val()) << 2) + (bit_cast::<20, 16>(self.h_hi.val()) << 1);
        self.times27.next = (bit_cast::<20, 8>(self.h_n.val()) << 4)
            + (bit_cast::<20, 8>(self.h_n.val()) << 3)
            + (bit_cast::<20, 8>(self.h_n.val()) << 1)
            + bit_cast::<20, 8>(self.h_n.val());
        self.sum17.next = bit_cast::<17, 16>(self.h_lo.val()) + bit_cast::<17, 16>(self.h_hi.val());
        // first + count of a Nearest (checked to be at most the scan count, so 13 bits).
        self.hdr_end.next = self.hdr.q.val().get_bits::<13>(0) + self.hdr.q.val().get_bits::<13>(16);
        if self.h.val().get_bit(0) {
            self.new_count.next = bit_cast::<10, 8>(self.h_n.val());
        } else {
            self.new_count.next = bit_cast::<10, 9>(self.ws.count.val()) + bit_cast::<10, 8>(self.h_n.val());
        }
        self.times6_r.d.next = self.times6.val();
        self.times27_r.d.next = self.times27.val();
        self.sum17_r.d.next = self.sum17.val();
        self.new_count_r.d.next = self.new_count.val();
        self.sizes_unset.next = !self.model_count.q.val().any() || !self.scan_count.q.val().any();

        // The scan stream's control (its registers are updated after the state machine).
        self.take.next = self.occ.q.val().any() && self.nn.scan_ready.val();
        self.streaming.next = self.occ.q.val().any() || self.inflight.q.val() || (self.sa.q.val() < self.send.q.val());
        if self.take.val() {
            self.occ_after.next = self.occ.q.val() - 1;
        } else {
            self.occ_after.next = self.occ.q.val();
        }
        self.issue.next = (self.sa.q.val() < self.send.q.val())
            && (!self.occ_after.val().any() || ((self.occ_after.val() == 1) && !self.inflight.q.val()));

        // Defaults.
        self.sender.open.next = false;
        self.sender.put.next = false;
        self.sender.put_data.next = self.outbuf.q.val().get_bits::<8>(0);
        self.sender.send.next = false;
        self.nn.model_we.next = false;
        self.nn.model_waddr.next = self.waddr.q.val();
        self.nn.model_wdata.next = self.inbuf.q.val().get_bits::<48>(168);
        self.nn.model_count.next = self.model_count.q.val();
        self.nn.start.next = self.start_r.q.val();
        self.start_r.d.next = false;
        self.nn.pose.next = self.inbuf.q.val();
        // The sequencer: it owns the pipeline while it runs (no other command uses it then).
        self.filter.reset.next = self.reset.val();
        self.filter.cfg_we.next = false;
        self.filter.cfg_addr.next = self.idx.q.val().get_bits::<5>(0);
        self.filter.cfg_data.next = self.inbuf.q.val().get_bits::<48>(168);
        self.filter.go.next = false;
        self.filter.nn_ready.next = !self.nn.busy.val() && !self.streaming.val() && !self.start_r.q.val();
        self.filter.cost_valid.next = self.nn.cost_valid.val();
        self.filter.cost.next = self.nn.cost.val();
        self.filter.nn_valid.next = self.nn.nn_valid.val();
        self.filter.nn_dist.next = self.nn.nn_dist.val();
        if self.filter.running.val() {
            self.nn.pose.next = self.filter.pose.val();
        }
        self.scan_store.write_enable.next = false;
        self.scan_store.write_address.next = self.waddr.q.val();
        self.scan_store.write_data.next = self.inbuf.q.val().get_bits::<48>(168);
        self.ws.clear.next = false;
        self.ws.cost_valid.next = self.nn.cost_valid.val() && self.eval_mode.q.val();
        self.ws.cost.next = self.nn.cost.val();
        self.ws.weigh.next = false;
        self.ws.pre_shift.next = self.hdr.q.val().get_bits::<6>(8);
        self.ws.q_mul.next = self.hdr.q.val().get_bits::<17>(16);
        self.aux.write_enable.next = false;
        self.aux.write_address.next = self.wi.q.val().get_bits::<8>(0);
        self.aux.write_data.next =
            bit_cast::<46, 12>(self.nn.nn_index.val()) | (bit_cast::<46, 34>(self.nn.nn_dist.val()) << 12);
        self.aux.read_address.next = self.wi.q.val().get_bits::<8>(0);

        // A valid frame that arrives while busy gets a Busy answer afterwards (the first only).
        if self.frame.val()
            && (self.state.q.val() != EngState::Idle)
            && (self.status.val() == 0)
            && !self.pending.q.val()
        {
            self.pending.d.next = true;
            self.p_cmd.d.next = self.cmd.val();
            self.p_seq.d.next = self.seq.val();
        }

        match self.state.q.val() {
            EngState::Idle => {
                self.eval_mode.d.next = false;
                if self.pending.q.val() {
                    self.pending.d.next = false;
                    self.e_code.d.next = 5.into();
                    self.e_cmd.d.next = self.p_cmd.q.val();
                    self.e_seq.d.next = self.p_seq.q.val();
                    self.state.d.next = EngState::ErrHeader;
                } else if self.frame.val() {
                    if self.busy_seen.val() {
                        if self.status.val() == 0 {
                            self.e_code.d.next = 5.into();
                            self.e_cmd.d.next = self.cmd.val();
                            self.e_seq.d.next = self.seq.val();
                            self.state.d.next = EngState::ErrHeader;
                        }
                    } else if self.status.val() != 0 {
                        self.e_code.d.next = bit_cast::<8, 3>(self.status.val());
                        self.e_cmd.d.next = 0.into();
                        self.e_seq.d.next = 0.into();
                        self.state.d.next = EngState::ErrHeader;
                    } else {
                        self.cur_cmd.d.next = self.cmd.val();
                        self.cur_seq.d.next = self.seq.val();
                        self.dlen.d.next = self.len.val() - 4;
                        self.faddr.d.next = 2.into();
                        self.fcount.d.next = 6.into();
                        self.ret.d.next = EngState::Decode;
                        self.state.d.next = EngState::FetchAddr;
                    }
                }
            }
            EngState::FetchAddr => {
                self.faddr.d.next = self.faddr.q.val() + 1;
                self.state.d.next = EngState::FetchData;
            }
            EngState::FetchData => {
                self.inbuf.d.next =
                    (self.inbuf.q.val() >> 8) | (bit_cast::<216, 8>(self.frame_buf.read_data.val()) << 208);
                self.fcount.d.next = self.fcount.q.val() - 1;
                if self.fcount.q.val() == 1 {
                    self.state.d.next = self.ret.q.val();
                } else {
                    self.state.d.next = EngState::FetchAddr;
                }
            }
            EngState::Emit => {
                if self.sender.ready.val() {
                    self.sender.put.next = true;
                    self.outbuf.d.next = self.outbuf.q.val() >> 8;
                    self.ecount.d.next = self.ecount.q.val() - 1;
                    if self.ecount.q.val() == 1 {
                        self.state.d.next = self.ret.q.val();
                    }
                }
            }
            EngState::Header => {
                self.sender.open.next = true;
                self.err_led.d.next = false;
                self.outbuf.d.next = bit_cast::<216, 8>(self.cur_cmd.q.val() | bits::<8>(128))
                    | (bit_cast::<216, 8>(self.cur_seq.q.val()) << 8);
                self.ecount.d.next = 2.into();
                self.state.d.next = EngState::Emit;
            }
            EngState::ErrHeader => {
                self.sender.open.next = true;
                self.err_led.d.next = true;
                self.outbuf.d.next = bits::<216>(255)
                    | (bit_cast::<216, 8>(self.e_seq.q.val()) << 8)
                    | (bit_cast::<216, 8>(self.e_code.q.val()) << 16)
                    | (bit_cast::<216, 8>(self.e_cmd.q.val()) << 24);
                self.ecount.d.next = 4.into();
                self.ret.d.next = EngState::Send;
                self.state.d.next = EngState::Emit;
            }
            EngState::Send => {
                if self.sender.ready.val() {
                    self.sender.send.next = true;
                    self.state.d.next = EngState::SendWait;
                }
            }
            EngState::SendWait => {
                if !self.sender.busy.val() {
                    self.state.d.next = EngState::Idle;
                }
            }
            EngState::Decode => {
                self.state.d.next = EngState::Dispatch;
            }
            EngState::Dispatch => {
                self.hdr.d.next = self.h.val();
                self.e_cmd.d.next = self.cur_cmd.q.val();
                self.e_seq.d.next = self.cur_seq.q.val();
                self.state.d.next = EngState::ErrHeader;
                if self.filter.running.val()
                    && (self.cur_cmd.q.val() >= 2)
                    && (self.cur_cmd.q.val() <= 9)
                    && (self.cur_cmd.q.val() != 8)
                {
                    self.e_code.d.next = 5.into();
                } else if self.cur_cmd.q.val() == 1 {
                    if self.dlen.q.val().any() {
                        self.e_code.d.next = 2.into();
                    } else {
                        self.ret.d.next = EngState::IdBody;
                        self.state.d.next = EngState::Header;
                    }
                } else if (self.cur_cmd.q.val() == 2) || (self.cur_cmd.q.val() == 3) {
                    if (self.dlen.q.val() < 4)
                        || !self.h_hi.val().any()
                        || (self.h_hi.val() > 170)
                        || (bit_cast::<20, 11>(self.dlen.q.val()) != self.times6_r.q.val() + 4)
                    {
                        self.e_code.d.next = 2.into();
                    } else if self.sum17_r.q.val() > 4096 {
                        self.e_code.d.next = 4.into();
                    } else {
                        self.idx.d.next = 0.into();
                        self.waddr.d.next = self.h_lo.val().get_bits::<12>(0);
                        self.faddr.d.next = 6.into();
                        self.state.d.next = EngState::LoadNext;
                    }
                } else if self.cur_cmd.q.val() == 4 {
                    if self.dlen.q.val() != 4 {
                        self.e_code.d.next = 2.into();
                    } else if !self.h_lo.val().any()
                        || (self.h_lo.val() > 4096)
                        || !self.h_hi.val().any()
                        || (self.h_hi.val() > 4096)
                    {
                        self.e_code.d.next = 4.into();
                    } else {
                        self.model_count.d.next = self.h_lo.val().get_bits::<13>(0);
                        self.scan_count.d.next = self.h_hi.val().get_bits::<13>(0);
                        self.ret.d.next = EngState::EchoBody;
                        self.state.d.next = EngState::Header;
                    }
                } else if self.cur_cmd.q.val() == 5 {
                    if (self.dlen.q.val() < 6)
                        || (self.h_n.val() > 37)
                        || (bit_cast::<20, 11>(self.dlen.q.val()) != self.times27_r.q.val() + 6)
                        || (!self.h_n.val().any() && !self.h.val().get_bit(1))
                    {
                        self.e_code.d.next = 2.into();
                    } else if self.sizes_unset.val()
                        || !self.new_count_r.q.val().any()
                        || (self.new_count_r.q.val() > 256)
                    {
                        self.e_code.d.next = 4.into();
                    } else {
                        self.ret.d.next = EngState::EvBegin;
                        self.state.d.next = EngState::Header;
                    }
                } else if self.cur_cmd.q.val() == 6 {
                    if (self.dlen.q.val() != 31) || !self.h_hi.val().any() || (self.h_hi.val() > 144) {
                        self.e_code.d.next = 2.into();
                    } else if self.sizes_unset.val()
                        || (self.sum17_r.q.val() > bit_cast::<17, 13>(self.scan_count.q.val()))
                    {
                        self.e_code.d.next = 4.into();
                    } else {
                        self.faddr.d.next = 6.into();
                        self.fcount.d.next = 27.into();
                        self.ret.d.next = EngState::NrRun;
                        self.state.d.next = EngState::FetchAddr;
                    }
                } else if self.cur_cmd.q.val() == 7 {
                    if self.dlen.q.val() != 150 {
                        self.e_code.d.next = 2.into();
                    } else if !self.h_lo.val().any()
                        || (self.h_lo.val() > 256)
                        || !self.h_hi.val().any()
                        || self.sizes_unset.val()
                    {
                        self.e_code.d.next = 4.into();
                    } else {
                        self.idx.d.next = 0.into();
                        self.faddr.d.next = 8.into();
                        self.state.d.next = EngState::RunNext;
                    }
                } else if self.cur_cmd.q.val() == 8 {
                    if self.dlen.q.val().any() {
                        self.e_code.d.next = 2.into();
                    } else {
                        self.ret.d.next = EngState::StBody;
                        self.state.d.next = EngState::Header;
                    }
                } else if self.cur_cmd.q.val() == 9 {
                    if self.dlen.q.val().any() {
                        self.e_code.d.next = 2.into();
                    } else if !self.filter.finished.val() {
                        self.e_code.d.next = 7.into();
                    } else {
                        self.ret.d.next = EngState::ResBody1;
                        self.state.d.next = EngState::Header;
                    }
                } else {
                    self.e_code.d.next = 3.into();
                }
            }
            EngState::RunNext => {
                if self.idx.q.val() == 24 {
                    self.filter.cfg_we.next = true;
                    self.filter.cfg_data.next = self.hdr.q.val();
                    self.state.d.next = EngState::RunGo;
                } else {
                    self.fcount.d.next = 6.into();
                    self.ret.d.next = EngState::RunWrite;
                    self.state.d.next = EngState::FetchAddr;
                }
            }
            EngState::RunWrite => {
                self.filter.cfg_we.next = true;
                self.idx.d.next = self.idx.q.val() + 1;
                self.state.d.next = EngState::RunNext;
            }
            EngState::RunGo => {
                self.filter.go.next = true;
                self.ret.d.next = EngState::EchoBody;
                self.state.d.next = EngState::Header;
            }
            EngState::StBody => {
                if self.filter.running.val() {
                    self.outbuf.d.next = bits::<216>(1)
                        | (bit_cast::<216, 16>(self.filter.iterations.val()) << 8)
                        | (bit_cast::<216, 48>(self.filter.best_cost.val()) << 24);
                } else if self.filter.finished.val() {
                    self.outbuf.d.next = bits::<216>(2)
                        | (bit_cast::<216, 16>(self.filter.iterations.val()) << 8)
                        | (bit_cast::<216, 48>(self.filter.best_cost.val()) << 24);
                } else {
                    self.outbuf.d.next = bit_cast::<216, 48>(self.all48.val()) << 24;
                }
                self.ecount.d.next = 9.into();
                self.ret.d.next = EngState::Send;
                self.state.d.next = EngState::Emit;
            }
            EngState::ResBody1 => {
                self.outbuf.d.next = bit_cast::<216, 16>(self.filter.iterations.val())
                    | (bit_cast::<216, 48>(self.filter.best_cost.val()) << 16)
                    | (bit_cast::<216, 34>(self.filter.best_max.val()) << 64);
                self.ecount.d.next = 13.into();
                self.ret.d.next = EngState::ResBody2;
                self.state.d.next = EngState::Emit;
            }
            EngState::ResBody2 => {
                self.outbuf.d.next = bit_cast::<216, 168>(self.filter.params.val());
                self.ecount.d.next = 21.into();
                self.ret.d.next = EngState::ResBody3;
                self.state.d.next = EngState::Emit;
            }
            EngState::ResBody3 => {
                self.outbuf.d.next = self.filter.pose.val();
                self.ecount.d.next = 27.into();
                self.ret.d.next = EngState::Send;
                self.state.d.next = EngState::Emit;
            }
            EngState::IdBody => {
                self.outbuf.d.next = self.ident.val()
                    | (bit_cast::<216, 13>(self.model_count.q.val()) << 160)
                    | (bit_cast::<216, 13>(self.scan_count.q.val()) << 176)
                    | (bit_cast::<216, 9>(self.ws.count.val()) << 192);
                self.ecount.d.next = 26.into();
                self.ret.d.next = EngState::Send;
                self.state.d.next = EngState::Emit;
            }
            EngState::LoadNext => {
                if self.idx.q.val() == self.hdr.q.val().get_bits::<16>(16) {
                    self.ret.d.next = EngState::EchoBody;
                    self.state.d.next = EngState::Header;
                } else {
                    self.fcount.d.next = 6.into();
                    self.ret.d.next = EngState::LoadWrite;
                    self.state.d.next = EngState::FetchAddr;
                }
            }
            EngState::LoadWrite => {
                if self.cur_cmd.q.val().get_bit(0) {
                    self.scan_store.write_enable.next = true;
                } else {
                    self.nn.model_we.next = true;
                }
                self.waddr.d.next = self.waddr.q.val() + 1;
                self.idx.d.next = self.idx.q.val() + 1;
                self.state.d.next = EngState::LoadNext;
            }
            EngState::EchoBody => {
                self.outbuf.d.next = bit_cast::<216, 32>(self.hdr.q.val().get_bits::<32>(0));
                self.ecount.d.next = 4.into();
                self.ret.d.next = EngState::Send;
                self.state.d.next = EngState::Emit;
            }
            EngState::EvBegin => {
                if !self.ws.busy.val() {
                    if self.hdr.q.val().get_bit(0) {
                        self.ws.clear.next = true;
                    }
                    self.idx.d.next = 0.into();
                    self.faddr.d.next = 8.into();
                    self.eval_mode.d.next = true;
                    self.state.d.next = EngState::EvNext;
                }
            }
            EngState::EvNext => {
                if self.idx.q.val() == bit_cast::<16, 8>(self.hdr.q.val().get_bits::<8>(40)) {
                    self.state.d.next = EngState::EvDone;
                } else {
                    self.fcount.d.next = 27.into();
                    self.ret.d.next = EngState::EvRun;
                    self.state.d.next = EngState::FetchAddr;
                }
            }
            EngState::EvRun => {
                if !self.nn.busy.val() && !self.streaming.val() {
                    self.start_r.d.next = true;
                    self.sa.d.next = 0.into();
                    self.send.d.next = self.scan_count.q.val();
                    self.state.d.next = EngState::EvWait;
                }
            }
            EngState::EvWait => {
                if self.nn.cost_valid.val() {
                    self.outbuf.d.next = bit_cast::<216, 48>(self.nn.cost.val());
                    self.ecount.d.next = 6.into();
                    self.ret.d.next = EngState::EvInc;
                    self.state.d.next = EngState::Emit;
                }
            }
            EngState::EvInc => {
                self.idx.d.next = self.idx.q.val() + 1;
                self.state.d.next = EngState::EvNext;
            }
            EngState::EvDone => {
                self.eval_mode.d.next = false;
                if !self.hdr.q.val().get_bit(1) {
                    self.state.d.next = EngState::Send;
                } else if !self.ws.busy.val() {
                    self.ws.weigh.next = true;
                    self.state.d.next = EngState::WeighWait;
                }
            }
            EngState::WeighWait => {
                self.aux.write_address.next = self.ws.w_index.val();
                self.aux.write_data.next = bit_cast::<46, 16>(self.ws.weight.val());
                self.aux.write_enable.next = self.ws.w_valid.val();
                if self.ws.w_done.val() {
                    self.state.d.next = EngState::SumEmit;
                }
            }
            EngState::SumEmit => {
                self.outbuf.d.next = bit_cast::<216, 9>(self.ws.count.val())
                    | (bit_cast::<216, 48>(self.ws.min_cost.val()) << 16)
                    | (bit_cast::<216, 24>(self.ws.w_sum.val()) << 64);
                self.ecount.d.next = 11.into();
                self.wi.d.next = 0.into();
                self.ret.d.next = EngState::WLoop;
                self.state.d.next = EngState::Emit;
            }
            EngState::WLoop => {
                if self.wi.q.val() == self.ws.count.val() {
                    self.state.d.next = EngState::Send;
                } else {
                    self.state.d.next = EngState::WRead;
                }
            }
            EngState::WRead => {
                self.outbuf.d.next = bit_cast::<216, 16>(self.aux.read_data.val().get_bits::<16>(0));
                self.ecount.d.next = 2.into();
                self.wi.d.next = self.wi.q.val() + 1;
                self.ret.d.next = EngState::WLoop;
                self.state.d.next = EngState::Emit;
            }
            EngState::NrRun => {
                if !self.nn.busy.val() && !self.streaming.val() {
                    self.start_r.d.next = true;
                    self.sa.d.next = self.hdr.q.val().get_bits::<13>(0);
                    self.send.d.next = self.hdr_end.val();
                    self.wi.d.next = 0.into();
                    self.state.d.next = EngState::NrWait;
                }
            }
            EngState::NrWait => {
                if self.nn.nn_valid.val() {
                    self.aux.write_enable.next = true;
                    self.wi.d.next = self.wi.q.val() + 1;
                }
                if self.nn.cost_valid.val() {
                    self.ncost.d.next = self.nn.cost.val();
                    self.ret.d.next = EngState::NrHead;
                    self.state.d.next = EngState::Header;
                }
            }
            EngState::NrHead => {
                self.outbuf.d.next = bit_cast::<216, 32>(self.hdr.q.val().get_bits::<32>(0))
                    | (bit_cast::<216, 48>(self.ncost.q.val()) << 32);
                self.ecount.d.next = 10.into();
                self.wi.d.next = 0.into();
                self.ret.d.next = EngState::NrLoop;
                self.state.d.next = EngState::Emit;
            }
            EngState::NrLoop => {
                if bit_cast::<16, 9>(self.wi.q.val()) == self.hdr.q.val().get_bits::<16>(16) {
                    self.state.d.next = EngState::Send;
                } else {
                    self.state.d.next = EngState::NrRead;
                }
            }
            EngState::NrRead => {
                self.outbuf.d.next = bit_cast::<216, 12>(self.aux.read_data.val().get_bits::<12>(0))
                    | (bit_cast::<216, 34>(self.aux.read_data.val().get_bits::<34>(12)) << 16);
                self.ecount.d.next = 7.into();
                self.wi.d.next = self.wi.q.val() + 1;
                self.ret.d.next = EngState::NrLoop;
                self.state.d.next = EngState::Emit;
            }
            _ => {
                self.state.d.next = EngState::Idle;
            }
        }

        // The sequencer starts the pipeline on its pose and the whole scan store.
        if self.filter.start.val() {
            self.start_r.d.next = true;
            self.sa.d.next = 0.into();
            self.send.d.next = self.scan_count.q.val();
        }

        // The scan stream: read scan point `sa` when the two-entry queue has room for it.
        self.scan_store.read_address.next = self.sa.q.val().get_bits::<12>(0);
        self.inflight.d.next = self.issue.val();
        self.inflight_last.d.next = (self.sa.q.val() + 1) == self.send.q.val();
        if self.issue.val() {
            self.sa.d.next = self.sa.q.val() + 1;
        }
        self.nn.scan_valid.next = self.occ.q.val().any();
        self.nn.scan_data.next = self.q0.q.val();
        self.nn.scan_last.next = self.q0_last.q.val();
        if self.take.val() {
            if self.occ.q.val() == 2 {
                self.q0.d.next = self.q1.q.val();
                self.q0_last.d.next = self.q1_last.q.val();
                if self.inflight.q.val() {
                    self.q1.d.next = self.scan_store.read_data.val();
                    self.q1_last.d.next = self.inflight_last.q.val();
                } else {
                    self.occ.d.next = 1.into();
                }
            } else if self.inflight.q.val() {
                self.q0.d.next = self.scan_store.read_data.val();
                self.q0_last.d.next = self.inflight_last.q.val();
            } else {
                self.occ.d.next = 0.into();
            }
        } else if self.inflight.q.val() {
            if self.occ.q.val().any() {
                self.q1.d.next = self.scan_store.read_data.val();
                self.q1_last.d.next = self.inflight_last.q.val();
                self.occ.d.next = 2.into();
            } else {
                self.q0.d.next = self.scan_store.read_data.val();
                self.q0_last.d.next = self.inflight_last.q.val();
                self.occ.d.next = 1.into();
            }
        }

        if self.reset.val() {
            self.state.d.next = EngState::Idle;
            self.pending.d.next = false;
            self.eval_mode.d.next = false;
        }
    }
}
