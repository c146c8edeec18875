//! `RequestCheck`: the command engine's checks of a received request (docs/protocol.md,
//! "Commands"): the command, then its lengths, then its capacities, registered two clocks
//! after the header is in (the sums, then the verdict); the engine adds what depends on
//! the filter's state at the moment it dispatches (Busy first, NoResult last). The codes, lengths and limits are [`Constant`]s built from
//! [`crate::protocol`], [`crate::protocol::messages`], [`crate::common::format`] and [`crate::filter::pf`], the same
//! definitions the byte-level reference [`crate::board::BoardModel`] and the host use (the
//! board's co-simulation compares the replies byte for byte).

use crate::common::format::{MAX_PARTICLES, MAX_POINTS};
use crate::protocol::layout::{POINT_BYTES, POSE_BYTES};
use crate::protocol::messages::{
    EVALUATE_HEADER_BYTES, FLAG_FIRST, FLAG_LAST, LOAD_HEADER_BYTES, MAX_LOAD_ENTRIES, MAX_LOAD_POINTS, MAX_NEAREST,
    MAX_POSES, NEAREST_REQUEST_BYTES, TABLE_ENTRIES, TABLE_ENTRY_BYTES, TWO_U16_BYTES,
};
use crate::protocol::run_request::run_bytes;
use crate::protocol::{Command, ErrorCode};
use rust_hdl::prelude::*;

/// The checks of one request.
#[derive(LogicBlock)]
pub struct RequestCheck {
    /// Clock (the sums the checks need are registered).
    pub clock: Signal<In, Clock>,
    /// The command code.
    pub cmd: Signal<In, Bits<8>>,
    /// The body's length (after the sequence and command bytes).
    pub dlen: Signal<In, Bits<11>>,
    /// The body's first two bytes (little-endian): a Load's offset, SetSizes' model
    /// count, Nearest's first point, Run's particle count; an Evaluate's flags.
    pub lo: Signal<In, Bits<16>>,
    /// The next two: a Load's or Nearest's count, SetSizes' scan count, Run's iterations.
    pub hi: Signal<In, Bits<16>>,
    /// The sixth byte: an Evaluate's pose count, a Run's starts.
    pub n: Signal<In, Bits<8>>,
    /// The weight stage's stored particle count.
    pub ws_count: Signal<In, Bits<9>>,
    /// The scan points in use.
    pub scan_count: Signal<In, Bits<13>>,
    /// SetSizes has not set both sizes.
    pub sizes_unset: Signal<In, Bit>,
    /// 0 if the request passes its length and capacity checks, else its [`ErrorCode`].
    pub code: Signal<Out, Bits<8>>,
    /// The command is one the running filter makes Busy (all but Identify and Status).
    pub busy_class: Signal<Out, Bit>,
    /// The command is Identify.
    pub is_identify: Signal<Out, Bit>,
    /// LoadModel, LoadScan or LoadTable (the engine tells them apart by the code).
    pub is_load: Signal<Out, Bit>,
    /// SetSizes.
    pub is_sizes: Signal<Out, Bit>,
    /// Evaluate.
    pub is_evaluate: Signal<Out, Bit>,
    /// Nearest.
    pub is_nearest: Signal<Out, Bit>,
    /// Run.
    pub is_run: Signal<Out, Bit>,
    /// Status.
    pub is_status: Signal<Out, Bit>,
    /// Result.
    pub is_result: Signal<Out, Bit>,
    c_identify: Constant<Bits<8>>,
    c_load_model: Constant<Bits<8>>,
    c_load_scan: Constant<Bits<8>>,
    c_load_table: Constant<Bits<8>>,
    c_sizes: Constant<Bits<8>>,
    c_evaluate: Constant<Bits<8>>,
    c_nearest: Constant<Bits<8>>,
    c_run: Constant<Bits<8>>,
    c_status: Constant<Bits<8>>,
    c_result: Constant<Bits<8>>,
    e_length: Constant<Bits<8>>,
    e_unknown: Constant<Bits<8>>,
    e_capacity: Constant<Bits<8>>,
    load_header: Constant<Bits<11>>,
    load_header20: Constant<Bits<20>>,
    max_load: Constant<Bits<16>>,
    max_entries: Constant<Bits<16>>,
    table_entries17: Constant<Bits<17>>,
    max_points17: Constant<Bits<17>>,
    model_words17: Constant<Bits<17>>,
    max_points16: Constant<Bits<16>>,
    sizes_body: Constant<Bits<11>>,
    eval_header: Constant<Bits<11>>,
    eval_header20: Constant<Bits<20>>,
    max_poses: Constant<Bits<8>>,
    max_particles10: Constant<Bits<10>>,
    max_particles16: Constant<Bits<16>>,
    nearest_body: Constant<Bits<11>>,
    max_nearest: Constant<Bits<16>>,
    run_body1: Constant<Bits<11>>,
    // Registered a clock after `h` (the engine's Decode state), for timing.
    times6: DFF<Bits<20>>,
    times27: DFF<Bits<20>>,
    /// A Run's length by its starts: one pose a start after the first.
    run_len: DFF<Bits<11>>,
    sum17: DFF<Bits<17>>,
    new_count: DFF<Bits<10>>,
    // The outputs, registered (a clock after the sums).
    code_r: DFF<Bits<8>>,
    busy_r: DFF<Bit>,
    identify_r: DFF<Bit>,
    load_r: DFF<Bit>,
    sizes_r: DFF<Bit>,
    evaluate_r: DFF<Bit>,
    nearest_r: DFF<Bit>,
    run_r: DFF<Bit>,
    status_r: DFF<Bit>,
    result_r: DFF<Bit>,
    c_code: Signal<Local, Bits<8>>,
    c_busy: Signal<Local, Bit>,
    dlen20: Signal<Local, Bits<20>>,
    c_is_identify: Signal<Local, Bit>,
    c_is_load: Signal<Local, Bit>,
    c_is_table: Signal<Local, Bit>,
    c_is_sizes: Signal<Local, Bit>,
    c_is_evaluate: Signal<Local, Bit>,
    c_is_nearest: Signal<Local, Bit>,
    c_is_run: Signal<Local, Bit>,
    c_is_status: Signal<Local, Bit>,
    c_is_result: Signal<Local, Bit>,
    /// A Run's hypotheses: its starts less one (0 starts taken as 1).
    hyps: Signal<Local, Bits<11>>,
}

impl Default for RequestCheck {
    fn default() -> Self {
        Self::new()
    }
}

/// The widths of the kernel's arithmetic: `times6`, `times27` and `run_len` are shifts and
/// adds; a Run's starts are the sixth byte's low four bits.
const _: () = assert!(POINT_BYTES == 6 && POSE_BYTES == 27 && MAX_POINTS <= 4096 && MAX_PARTICLES <= 512);
const _: () = assert!(crate::protocol::run_request::STARTS_BITS == 4);
const _: () = assert!(FLAG_FIRST == 1 && FLAG_LAST == 2);
// A LoadTable's length is `2 count` plus the header (a shift); the busy class's code range
// ends at Result, LoadTable is added to it by name.
const _: () = assert!(TABLE_ENTRY_BYTES == 2 && TABLE_ENTRIES < 1 << 13);
const _: () = assert!((Command::LoadTable as u8) > (Command::Result as u8));

impl RequestCheck {
    /// The constants from the protocol's definitions.
    pub fn new() -> Self {
        let c8 = |v: u8| Constant::new(Bits::<8>::from(v as u64));
        let c11 = |v: usize| Constant::new(Bits::<11>::from(v as u64));
        RequestCheck {
            clock: Default::default(),
            cmd: Default::default(),
            dlen: Default::default(),
            lo: Default::default(),
            hi: Default::default(),
            n: Default::default(),
            ws_count: Default::default(),
            scan_count: Default::default(),
            sizes_unset: Default::default(),
            code: Default::default(),
            busy_class: Default::default(),
            is_identify: Default::default(),
            is_load: Default::default(),
            is_sizes: Default::default(),
            is_evaluate: Default::default(),
            is_nearest: Default::default(),
            is_run: Default::default(),
            is_status: Default::default(),
            is_result: Default::default(),
            c_identify: c8(Command::Identify as u8),
            c_load_model: c8(Command::LoadModel as u8),
            c_load_scan: c8(Command::LoadScan as u8),
            c_load_table: c8(Command::LoadTable as u8),
            c_sizes: c8(Command::SetSizes as u8),
            c_evaluate: c8(Command::Evaluate as u8),
            c_nearest: c8(Command::Nearest as u8),
            c_run: c8(Command::Run as u8),
            c_status: c8(Command::Status as u8),
            c_result: c8(Command::Result as u8),
            e_length: c8(ErrorCode::BadLength as u8),
            e_unknown: c8(ErrorCode::UnknownCommand as u8),
            e_capacity: c8(ErrorCode::OverCapacity as u8),
            load_header: c11(LOAD_HEADER_BYTES),
            load_header20: Constant::new(Bits::<20>::from(LOAD_HEADER_BYTES as u64)),
            max_load: Constant::new(Bits::<16>::from(MAX_LOAD_POINTS as u64)),
            max_entries: Constant::new(Bits::<16>::from(MAX_LOAD_ENTRIES as u64)),
            table_entries17: Constant::new(Bits::<17>::from(TABLE_ENTRIES as u64)),
            max_points17: Constant::new(Bits::<17>::from(MAX_POINTS as u64)),
            model_words17: Constant::new(Bits::<17>::from(crate::protocol::messages::MODEL_WORDS as u64)),
            max_points16: Constant::new(Bits::<16>::from(MAX_POINTS as u64)),
            sizes_body: c11(TWO_U16_BYTES),
            eval_header: c11(EVALUATE_HEADER_BYTES),
            eval_header20: Constant::new(Bits::<20>::from(EVALUATE_HEADER_BYTES as u64)),
            max_poses: c8(MAX_POSES as u8),
            max_particles10: Constant::new(Bits::<10>::from(MAX_PARTICLES as u64)),
            max_particles16: Constant::new(Bits::<16>::from(MAX_PARTICLES as u64)),
            nearest_body: c11(NEAREST_REQUEST_BYTES),
            max_nearest: Constant::new(Bits::<16>::from(MAX_NEAREST as u64)),
            run_body1: c11(run_bytes(1)),
            run_len: Default::default(),
            hyps: Default::default(),
            times6: Default::default(),
            times27: Default::default(),
            sum17: Default::default(),
            new_count: Default::default(),
            code_r: Default::default(),
            busy_r: Default::default(),
            identify_r: Default::default(),
            load_r: Default::default(),
            sizes_r: Default::default(),
            evaluate_r: Default::default(),
            nearest_r: Default::default(),
            run_r: Default::default(),
            status_r: Default::default(),
            result_r: Default::default(),
            c_code: Default::default(),
            c_busy: Default::default(),
            dlen20: Default::default(),
            c_is_identify: Default::default(),
            c_is_load: Default::default(),
            c_is_table: Default::default(),
            c_is_sizes: Default::default(),
            c_is_evaluate: Default::default(),
            c_is_nearest: Default::default(),
            c_is_run: Default::default(),
            c_is_status: Default::default(),
            c_is_result: Default::default(),
        }
    }
}

impl Logic for RequestCheck {
    #[hdl_gen]
    fn update(&mut self) {
        dff_setup!(self, clock, times6, times27, run_len, sum17, new_count, code_r, busy_r);
        dff_setup!(self, clock, identify_r, load_r, sizes_r, evaluate_r, nearest_r, run_r, status_r, result_r);
        // `6 n` and `27 n` as shifts and adds; an Evaluate's particle count after it.
        self.times6.d.next = (bit_cast::<20, 16>(self.hi.val()) << 2) + (bit_cast::<20, 16>(self.hi.val()) << 1);
        self.times27.d.next = (bit_cast::<20, 8>(self.n.val()) << 4)
            + (bit_cast::<20, 8>(self.n.val()) << 3)
            + (bit_cast::<20, 8>(self.n.val()) << 1)
            + bit_cast::<20, 8>(self.n.val());
        self.sum17.d.next = bit_cast::<17, 16>(self.lo.val()) + bit_cast::<17, 16>(self.hi.val());
        if self.lo.val().get_bit(0) {
            self.new_count.d.next = bit_cast::<10, 8>(self.n.val());
        } else {
            self.new_count.d.next = bit_cast::<10, 9>(self.ws_count.val()) + bit_cast::<10, 8>(self.n.val());
        }
        self.dlen20.next = bit_cast::<20, 11>(self.dlen.val());
        self.c_is_identify.next = self.cmd.val() == self.c_identify.val();
        self.c_is_table.next = self.cmd.val() == self.c_load_table.val();
        self.c_is_load.next = (self.cmd.val() == self.c_load_model.val())
            || (self.cmd.val() == self.c_load_scan.val())
            || self.c_is_table.val();
        self.c_is_sizes.next = self.cmd.val() == self.c_sizes.val();
        self.c_is_evaluate.next = self.cmd.val() == self.c_evaluate.val();
        self.c_is_nearest.next = self.cmd.val() == self.c_nearest.val();
        self.c_is_run.next = self.cmd.val() == self.c_run.val();
        self.c_is_status.next = self.cmd.val() == self.c_status.val();
        self.c_is_result.next = self.cmd.val() == self.c_result.val();
        // The outputs come from registers only: a path from this block's inputs to its
        // outputs would be a process loop for Verilator through the engine's block.
        self.code.next = self.code_r.q.val();
        self.busy_class.next = self.busy_r.q.val();
        self.is_identify.next = self.identify_r.q.val();
        self.is_load.next = self.load_r.q.val();
        self.is_sizes.next = self.sizes_r.q.val();
        self.is_evaluate.next = self.evaluate_r.q.val();
        self.is_nearest.next = self.nearest_r.q.val();
        self.is_run.next = self.run_r.q.val();
        self.is_status.next = self.status_r.q.val();
        self.is_result.next = self.result_r.q.val();
        self.c_busy.next = ((self.cmd.val() >= self.c_load_model.val())
            && (self.cmd.val() <= self.c_result.val())
            && !self.c_is_status.val())
            || self.c_is_table.val();
        // A Run's length: one pose (27 bytes) a start after the first (0 starts taken as 1).
        self.hyps.next = 0.into();
        if self.n.val().get_bits::<4>(0).any() {
            self.hyps.next = bit_cast::<11, 4>(self.n.val().get_bits::<4>(0) - 1);
        }
        self.run_len.d.next = self.run_body1.val()
            + (self.hyps.val() << 4)
            + (self.hyps.val() << 3)
            + (self.hyps.val() << 1)
            + self.hyps.val();
        self.c_code.next = 0.into();
        if self.c_is_identify.val() || self.c_is_status.val() {
            if self.dlen.val().any() {
                self.c_code.next = self.e_length.val();
            }
        } else if self.c_is_table.val() {
            // Two bytes an entry: `len = 4 + 2 count`.
            if (self.dlen.val() < self.load_header.val())
                || !self.hi.val().any()
                || (self.hi.val() > self.max_entries.val())
                || (self.dlen20.val() != (bit_cast::<20, 16>(self.hi.val()) << 1) + self.load_header20.val())
            {
                self.c_code.next = self.e_length.val();
            } else if self.sum17.q.val() > self.table_entries17.val() {
                self.c_code.next = self.e_capacity.val();
            }
        } else if self.c_is_load.val() {
            if (self.dlen.val() < self.load_header.val())
                || !self.hi.val().any()
                || (self.hi.val() > self.max_load.val())
                || (self.dlen20.val() != self.times6.q.val() + self.load_header20.val())
            {
                self.c_code.next = self.e_length.val();
            } else if (self.cmd.val() == self.c_load_model.val()) && (self.sum17.q.val() > self.model_words17.val()) {
                // LoadModel's words: the points, then their normals (messages::MODEL_WORDS).
                self.c_code.next = self.e_capacity.val();
            } else if (self.cmd.val() != self.c_load_model.val()) && (self.sum17.q.val() > self.max_points17.val()) {
                self.c_code.next = self.e_capacity.val();
            }
        } else if self.c_is_sizes.val() {
            if self.dlen.val() != self.sizes_body.val() {
                self.c_code.next = self.e_length.val();
            } else if !self.lo.val().any()
                || (self.lo.val() > self.max_points16.val())
                || !self.hi.val().any()
                || (self.hi.val() > self.max_points16.val())
            {
                self.c_code.next = self.e_capacity.val();
            }
        } else if self.c_is_evaluate.val() {
            if (self.dlen.val() < self.eval_header.val())
                || (self.n.val() > self.max_poses.val())
                || (self.dlen20.val() != self.times27.q.val() + self.eval_header20.val())
                || (!self.n.val().any() && !self.lo.val().get_bit(1))
            {
                self.c_code.next = self.e_length.val();
            } else if self.sizes_unset.val()
                || !self.new_count.q.val().any()
                || (self.new_count.q.val() > self.max_particles10.val())
            {
                self.c_code.next = self.e_capacity.val();
            }
        } else if self.c_is_nearest.val() {
            if (self.dlen.val() != self.nearest_body.val())
                || !self.hi.val().any()
                || (self.hi.val() > self.max_nearest.val())
            {
                self.c_code.next = self.e_length.val();
            } else if self.sizes_unset.val() || (self.sum17.q.val() > bit_cast::<17, 13>(self.scan_count.val())) {
                self.c_code.next = self.e_capacity.val();
            }
        } else if self.c_is_run.val() {
            if self.dlen.val() != self.run_len.q.val() {
                self.c_code.next = self.e_length.val();
            } else if !self.lo.val().any()
                || (self.lo.val() > self.max_particles16.val())
                || !self.hi.val().any()
                || self.sizes_unset.val()
            {
                self.c_code.next = self.e_capacity.val();
            }
        } else if self.c_is_result.val() {
            if self.dlen.val().any() {
                self.c_code.next = self.e_length.val();
            }
        } else {
            self.c_code.next = self.e_unknown.val();
        }
        self.code_r.d.next = self.c_code.val();
        self.busy_r.d.next = self.c_busy.val();
        self.identify_r.d.next = self.c_is_identify.val();
        self.load_r.d.next = self.c_is_load.val();
        self.sizes_r.d.next = self.c_is_sizes.val();
        self.evaluate_r.d.next = self.c_is_evaluate.val();
        self.nearest_r.d.next = self.c_is_nearest.val();
        self.run_r.d.next = self.c_is_run.val();
        self.status_r.d.next = self.c_is_status.val();
        self.result_r.d.next = self.c_is_result.val();
    }
}
