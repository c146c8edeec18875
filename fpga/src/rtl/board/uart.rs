//! The UART, 8N1, `bit_clocks` clocks per bit (set at generation): [`UartRx`] samples each
//! bit in its middle through a two-register synchroniser; [`UartTx`] shifts a start bit,
//! eight data bits (LSB first) and a stop bit.

use rust_hdl::prelude::*;

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
    bit_m1: Constant<Bits<16>>,
    half_m1: Constant<Bits<16>>,
    /// The synchroniser, stored inverted so that power-up reads as an idle (high) line.
    sync_n: [DFF<Bit>; 2],
    state: DFF<RxState>,
    count: DFF<Bits<16>>,
    nbit: DFF<Bits<3>>,
    shift: DFF<Bits<8>>,
    valid_r: DFF<Bit>,
    data_r: DFF<Bits<8>>,
    line: Signal<Local, Bit>,
}

impl UartRx {
    /// A receiver for `bit_clocks` clocks per bit (at least 4).
    pub fn new(bit_clocks: u32) -> Self {
        assert!((4..65536).contains(&bit_clocks), "4 to 65535 clocks per bit");
        UartRx {
            clock: Default::default(),
            reset: Default::default(),
            rx: Default::default(),
            valid: Default::default(),
            data: Default::default(),
            active: Default::default(),
            bit_m1: Constant::new((bit_clocks as u64 - 1).into()),
            half_m1: Constant::new((bit_clocks as u64 / 2 - 1).into()),
            sync_n: Default::default(),
            state: Default::default(),
            count: Default::default(),
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
        dff_setup!(self, clock, state, count, nbit, shift, valid_r, data_r);
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
        if self.count.q.val().any() {
            self.count.d.next = self.count.q.val() - 1;
        }
        match self.state.q.val() {
            RxState::Idle => {
                if !self.line.val() {
                    self.state.d.next = RxState::Start;
                    self.count.d.next = self.half_m1.val();
                }
            }
            RxState::Start => {
                if !self.count.q.val().any() {
                    if self.line.val() {
                        self.state.d.next = RxState::Idle;
                    } else {
                        self.state.d.next = RxState::Data;
                        self.count.d.next = self.bit_m1.val();
                        self.nbit.d.next = 0.into();
                    }
                }
            }
            RxState::Data => {
                if !self.count.q.val().any() {
                    if self.line.val() {
                        self.shift.d.next = (self.shift.q.val() >> 1) | bits::<8>(128);
                    } else {
                        self.shift.d.next = self.shift.q.val() >> 1;
                    }
                    self.count.d.next = self.bit_m1.val();
                    self.nbit.d.next = self.nbit.q.val() + 1;
                    if self.nbit.q.val().all() {
                        self.state.d.next = RxState::Stop;
                    }
                }
            }
            RxState::Stop => {
                if !self.count.q.val().any() {
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
    bit_m1: Constant<Bits<16>>,
    busy_r: DFF<Bit>,
    count: DFF<Bits<16>>,
    left: DFF<Bits<4>>,
    /// Start, data and stop bits still to send, the current one in bit 0.
    shift: DFF<Bits<10>>,
    /// The line, stored inverted so that power-up drives it high.
    tx_n: DFF<Bit>,
}

impl UartTx {
    /// A transmitter for `bit_clocks` clocks per bit.
    pub fn new(bit_clocks: u32) -> Self {
        assert!((4..65536).contains(&bit_clocks), "4 to 65535 clocks per bit");
        UartTx {
            clock: Default::default(),
            reset: Default::default(),
            start: Default::default(),
            data: Default::default(),
            busy: Default::default(),
            tx: Default::default(),
            bit_m1: Constant::new((bit_clocks as u64 - 1).into()),
            busy_r: Default::default(),
            count: Default::default(),
            left: Default::default(),
            shift: Default::default(),
            tx_n: Default::default(),
        }
    }
}

impl Logic for UartTx {
    #[hdl_gen]
    fn update(&mut self) {
        dff_setup!(self, clock, busy_r, count, left, shift, tx_n);
        self.busy.next = self.busy_r.q.val();
        self.tx.next = !self.tx_n.q.val();
        if !self.busy_r.q.val() {
            self.tx_n.d.next = false;
            if self.start.val() {
                self.busy_r.d.next = true;
                self.shift.d.next = (bit_cast::<10, 8>(self.data.val()) << 1) | bits::<10>(512);
                self.tx_n.d.next = true;
                self.count.d.next = self.bit_m1.val();
                self.left.d.next = 9.into();
            }
        } else if self.count.q.val().any() {
            self.count.d.next = self.count.q.val() - 1;
        } else if self.left.q.val().any() {
            self.left.d.next = self.left.q.val() - 1;
            self.shift.d.next = self.shift.q.val() >> 1;
            self.tx_n.d.next = !self.shift.q.val().get_bit(1);
            self.count.d.next = self.bit_m1.val();
        } else {
            self.busy_r.d.next = false;
            self.tx_n.d.next = false;
        }
        if self.reset.val() {
            self.busy_r.d.next = false;
            self.tx_n.d.next = false;
        }
    }
}
