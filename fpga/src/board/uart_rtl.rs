//! The UART, 8N1, at a bit period of `clocks / bits` clocks set at generation
//! ([`BitPeriod`], at least 4 clocks): [`UartRx`] samples each bit in its middle through a
//! two-register synchroniser; [`UartTx`] shifts a start bit, eight data bits (LSB first) and
//! a stop bit.
//!
//! **Bit timing, exact on average.** Both count time in a phase accumulator: a
//! [`PHASE_BITS`]-bit register `phase` below `2 clocks` that advances by `2 bits` a clock;
//! when it would reach `2 clocks` it wraps (`phase - (2 clocks - 2 bits)`) and that clock is
//! a *tick*. Started at `phase = s` on the clock of the start edge (clock 0), the `j`-th tick
//! is the first clock `c` with `2 bits c + s >= 2 clocks j`. The transmitter starts at 0: its
//! `k`-th bit boundary is at `ceil(k clocks / bits)` clocks after its start edge, within one
//! clock of the exact time, and the error never accumulates. The receiver starts at
//! `clocks` (half a bit): it samples bit `j` (0 the start bit, 9 the stop bit) at
//! `ceil((j + 1/2) clocks / bits)` clocks after it saw the falling edge.

use crate::board::{BitPeriod, PHASE_BITS};
use rust_hdl::prelude::*;

// The phase registers below are `Bits<24>`.
const _: () = assert!(PHASE_BITS == 24);

/// The phase accumulator's constants for `period`: (step `2 bits`, wrap `2 clocks - 2 bits`,
/// half a bit `clocks`). Panics unless `period` is at least 4 clocks and `2 clocks` fits
/// [`PHASE_BITS`] bits (`BoardConfig::uart_problem` says so first).
fn phase_constants(period: BitPeriod) -> (u64, u64, u64) {
    let (c, b) = (period.clocks as u64, period.bits as u64);
    assert!(c >= 4 * b, "a UART needs at least 4 clocks per bit, not {period}");
    assert!(2 * c < 1 << PHASE_BITS, "the UART bit period {c}/{b} does not fit the {PHASE_BITS}-bit phase");
    (2 * b, 2 * c - 2 * b, c)
}

/// Receiver states.
#[derive(Copy, Clone, Debug, PartialEq, Eq, LogicState)]
pub enum RxState {
    /// Line idle (high): waiting for a start bit.
    Idle,
    /// Half a bit into the start bit: still low, or a glitch.
    Start,
    /// Sampling the eight data bits.
    Data,
    /// Sampling the stop bit.
    Stop,
}

/// UART receiver: one `valid` strobe with `data` per byte whose stop bit is high.
#[derive(LogicBlock)]
pub struct UartRx {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// Synchronous reset (to idle).
    pub reset: Signal<In, Bit>,
    /// The serial line (asynchronous).
    pub rx: Signal<In, Bit>,
    /// A byte arrived (one-clock strobe).
    pub valid: Signal<Out, Bit>,
    /// The byte.
    pub data: Signal<Out, Bits<8>>,
    /// A byte is being received.
    pub active: Signal<Out, Bit>,
    step: Constant<Bits<24>>,
    wrap: Constant<Bits<24>>,
    half: Constant<Bits<24>>,
    /// The synchroniser, stored inverted so that power-up reads as an idle (high) line.
    sync_n: [DFF<Bit>; 2],
    state: DFF<RxState>,
    /// The phase accumulator (module documentation).
    phase: DFF<Bits<24>>,
    /// A sample clock: the phase wraps.
    tick: Signal<Local, Bit>,
    nbit: DFF<Bits<3>>,
    shift: DFF<Bits<8>>,
    valid_r: DFF<Bit>,
    data_r: DFF<Bits<8>>,
    line: Signal<Local, Bit>,
}

impl UartRx {
    /// A receiver for bits of `period` clocks (at least 4).
    pub fn new(period: BitPeriod) -> Self {
        let (step, wrap, half) = phase_constants(period);
        UartRx {
            clock: Default::default(),
            reset: Default::default(),
            rx: Default::default(),
            valid: Default::default(),
            data: Default::default(),
            active: Default::default(),
            step: Constant::new(step.into()),
            wrap: Constant::new(wrap.into()),
            half: Constant::new(half.into()),
            sync_n: Default::default(),
            state: Default::default(),
            phase: Default::default(),
            tick: Default::default(),
            nbit: Default::default(),
            shift: Default::default(),
            valid_r: Default::default(),
            data_r: Default::default(),
            line: Default::default(),
        }
    }
}

impl Logic for UartRx {
    #[hdl_gen]
    fn update(&mut self) {
        dff_setup!(self, clock, state, phase, nbit, shift, valid_r, data_r);
        for i in 0..2 {
            self.sync_n[i].clock.next = self.clock.val();
        }
        self.sync_n[0].d.next = !self.rx.val();
        self.sync_n[1].d.next = self.sync_n[0].q.val();
        self.line.next = !self.sync_n[1].q.val();
        self.valid.next = self.valid_r.q.val();
        self.data.next = self.data_r.q.val();
        self.active.next = self.state.q.val() != RxState::Idle;
        self.valid_r.d.next = false;
        self.tick.next = self.phase.q.val() >= self.wrap.val();
        if self.tick.val() {
            self.phase.d.next = self.phase.q.val() - self.wrap.val();
        } else {
            self.phase.d.next = self.phase.q.val() + self.step.val();
        }
        match self.state.q.val() {
            RxState::Idle => {
                if !self.line.val() {
                    self.state.d.next = RxState::Start;
                    self.phase.d.next = self.half.val();
                }
            }
            RxState::Start => {
                if self.tick.val() {
                    if self.line.val() {
                        self.state.d.next = RxState::Idle;
                    } else {
                        self.state.d.next = RxState::Data;
                        self.nbit.d.next = 0.into();
                    }
                }
            }
            RxState::Data => {
                if self.tick.val() {
                    if self.line.val() {
                        self.shift.d.next = (self.shift.q.val() >> 1) | bits::<8>(128);
                    } else {
                        self.shift.d.next = self.shift.q.val() >> 1;
                    }
                    self.nbit.d.next = self.nbit.q.val() + 1;
                    if self.nbit.q.val().all() {
                        self.state.d.next = RxState::Stop;
                    }
                }
            }
            RxState::Stop => {
                if self.tick.val() {
                    self.state.d.next = RxState::Idle;
                    if self.line.val() {
                        self.valid_r.d.next = true;
                        self.data_r.d.next = self.shift.q.val();
                    }
                }
            }
            _ => {
                self.state.d.next = RxState::Idle;
            }
        }
        if self.reset.val() {
            self.state.d.next = RxState::Idle;
            self.valid_r.d.next = false;
        }
    }
}

/// UART transmitter: `start` with `data` when not `busy`.
#[derive(LogicBlock)]
pub struct UartTx {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// Synchronous reset (line high, idle).
    pub reset: Signal<In, Bit>,
    /// Send `data` (honoured when not busy).
    pub start: Signal<In, Bit>,
    /// The byte.
    pub data: Signal<In, Bits<8>>,
    /// A byte is being sent.
    pub busy: Signal<Out, Bit>,
    /// The serial line.
    pub tx: Signal<Out, Bit>,
    step: Constant<Bits<24>>,
    wrap: Constant<Bits<24>>,
    busy_r: DFF<Bit>,
    /// The phase accumulator (module documentation).
    phase: DFF<Bits<24>>,
    /// A bit boundary: the phase wraps.
    tick: Signal<Local, Bit>,
    left: DFF<Bits<4>>,
    /// Start, data and stop bits still to send, the current one in bit 0.
    shift: DFF<Bits<10>>,
    /// The line, stored inverted so that power-up drives it high.
    tx_n: DFF<Bit>,
}

impl UartTx {
    /// A transmitter for bits of `period` clocks (at least 4).
    pub fn new(period: BitPeriod) -> Self {
        let (step, wrap, _) = phase_constants(period);
        UartTx {
            clock: Default::default(),
            reset: Default::default(),
            start: Default::default(),
            data: Default::default(),
            busy: Default::default(),
            tx: Default::default(),
            step: Constant::new(step.into()),
            wrap: Constant::new(wrap.into()),
            busy_r: Default::default(),
            phase: Default::default(),
            tick: Default::default(),
            left: Default::default(),
            shift: Default::default(),
            tx_n: Default::default(),
        }
    }
}

impl Logic for UartTx {
    #[hdl_gen]
    fn update(&mut self) {
        dff_setup!(self, clock, busy_r, phase, left, shift, tx_n);
        self.busy.next = self.busy_r.q.val();
        self.tx.next = !self.tx_n.q.val();
        self.tick.next = self.phase.q.val() >= self.wrap.val();
        if self.tick.val() {
            self.phase.d.next = self.phase.q.val() - self.wrap.val();
        } else {
            self.phase.d.next = self.phase.q.val() + self.step.val();
        }
        if !self.busy_r.q.val() {
            self.tx_n.d.next = false;
            if self.start.val() {
                self.busy_r.d.next = true;
                self.shift.d.next = (bit_cast::<10, 8>(self.data.val()) << 1) | bits::<10>(512);
                self.tx_n.d.next = true;
                self.phase.d.next = 0.into();
                self.left.d.next = 9.into();
            }
        } else if self.tick.val() {
            if self.left.q.val().any() {
                self.left.d.next = self.left.q.val() - 1;
                self.shift.d.next = self.shift.q.val() >> 1;
                self.tx_n.d.next = !self.shift.q.val().get_bit(1);
            } else {
                self.busy_r.d.next = false;
                self.tx_n.d.next = false;
            }
        }
        if self.reset.val() {
            self.busy_r.d.next = false;
            self.tx_n.d.next = false;
        }
    }
}
