//! `ReplySender`: the sending half of the protocol. The command engine appends a reply
//! body byte by byte (`open`, `put`; the CRC runs along), then `send` appends the CRC
//! (little-endian) and transmits `COBS(body ++ crc) ++ 0x00`: for each COBS block it scans
//! ahead in the buffer for the next zero (at most 254 bytes), sends the code byte, then the
//! block's bytes, exactly as `protocol::cobs_encode`.

use super::crc_rtl::Crc16Serial;
use super::uart_rtl::UartTx;
use crate::board::BitPeriod;
use rust_hdl::prelude::*;

/// Sender states.
#[derive(Copy, Clone, Debug, PartialEq, Eq, LogicState)]
pub enum TxState {
    /// Taking `open`, `put` and `send`.
    Idle,
    /// Appending the CRC's low byte (once the CRC is done).
    CrcLo,
    /// Appending its high byte.
    CrcHi,
    /// Starting a COBS block at `pos`.
    ScanStart,
    /// Reading byte `j`.
    ScanAddr,
    /// Looking at byte `j`.
    ScanData,
    /// Sending the block's code byte.
    Code,
    /// Reading block byte `k`.
    DataAddr,
    /// Sending block byte `k`.
    DataByte,
    /// Sending the delimiter.
    Delim,
    /// Waiting for the delimiter to leave.
    Drain,
}

/// The reply buffer, CRC and COBS encoder in front of the UART transmitter.
#[derive(LogicBlock)]
pub struct ReplySender {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// Synchronous reset (abandon the reply).
    pub reset: Signal<In, Bit>,
    /// Start a new reply (idle only).
    pub open: Signal<In, Bit>,
    /// Append `put_data` (when `ready`).
    pub put: Signal<In, Bit>,
    /// The byte.
    pub put_data: Signal<In, Bits<8>>,
    /// Append the CRC and transmit (when `ready`).
    pub send: Signal<In, Bit>,
    /// Idle and the CRC is done: `put` and `send` are taken.
    pub ready: Signal<Out, Bit>,
    /// Transmitting (until the delimiter has left the UART).
    pub busy: Signal<Out, Bit>,
    /// The serial line.
    pub tx: Signal<Out, Bit>,
    state: DFF<TxState>,
    len: DFF<Bits<11>>,
    pos: DFF<Bits<11>>,
    j: DFF<Bits<11>>,
    k: DFF<Bits<11>>,
    run: DFF<Bits<8>>,
    zero_end: DFF<Bit>,
    reply_buf: RAM<Bits<8>, 11>,
    crc_gen: Crc16Serial,
    uart: UartTx,
}

impl ReplySender {
    /// A sender whose UART's bits are `period` clocks.
    pub fn new(period: BitPeriod) -> Self {
        ReplySender {
            clock: Default::default(),
            reset: Default::default(),
            open: Default::default(),
            put: Default::default(),
            put_data: Default::default(),
            send: Default::default(),
            ready: Default::default(),
            busy: Default::default(),
            tx: Default::default(),
            state: Default::default(),
            len: Default::default(),
            pos: Default::default(),
            j: Default::default(),
            k: Default::default(),
            run: Default::default(),
            zero_end: Default::default(),
            reply_buf: Default::default(),
            crc_gen: Default::default(),
            uart: UartTx::new(period),
        }
    }
}

impl Logic for ReplySender {
    #[hdl_gen]
    fn update(&mut self) {
        dff_setup!(self, clock, state, len, pos, j, k, run, zero_end);
        self.crc_gen.clock.next = self.clock.val();
        self.uart.clock.next = self.clock.val();
        self.reply_buf.read_clock.next = self.clock.val();
        self.reply_buf.write_clock.next = self.clock.val();
        self.uart.reset.next = self.reset.val();
        self.tx.next = self.uart.tx.val();
        self.ready.next = (self.state.q.val() == TxState::Idle) && !self.crc_gen.busy.val();
        self.busy.next = self.state.q.val() != TxState::Idle;
        self.crc_gen.init.next = false;
        self.crc_gen.feed.next = false;
        self.crc_gen.data_in.next = self.put_data.val();
        self.reply_buf.write_enable.next = false;
        self.reply_buf.write_address.next = self.len.q.val();
        self.reply_buf.write_data.next = self.put_data.val();
        self.uart.start.next = false;
        self.uart.data.next = self.run.q.val() + 1;
        self.reply_buf.read_address.next = self.k.q.val();
        match self.state.q.val() {
            TxState::Idle => {
                if self.open.val() {
                    self.len.d.next = 0.into();
                    self.crc_gen.init.next = true;
                } else if self.put.val() && !self.crc_gen.busy.val() {
                    self.reply_buf.write_enable.next = true;
                    self.len.d.next = self.len.q.val() + 1;
                    self.crc_gen.feed.next = true;
                } else if self.send.val() && !self.crc_gen.busy.val() {
                    self.state.d.next = TxState::CrcLo;
                }
            }
            TxState::CrcLo => {
                self.reply_buf.write_enable.next = true;
                self.reply_buf.write_data.next = self.crc_gen.crc.val().get_bits::<8>(0);
                self.len.d.next = self.len.q.val() + 1;
                self.state.d.next = TxState::CrcHi;
            }
            TxState::CrcHi => {
                self.reply_buf.write_enable.next = true;
                self.reply_buf.write_data.next = self.crc_gen.crc.val().get_bits::<8>(8);
                self.len.d.next = self.len.q.val() + 1;
                self.pos.d.next = 0.into();
                self.state.d.next = TxState::ScanStart;
            }
            TxState::ScanStart => {
                self.j.d.next = self.pos.q.val();
                self.run.d.next = 0.into();
                self.state.d.next = TxState::ScanAddr;
            }
            TxState::ScanAddr => {
                self.reply_buf.read_address.next = self.j.q.val();
                if self.j.q.val() == self.len.q.val() {
                    self.zero_end.d.next = false;
                    self.state.d.next = TxState::Code;
                } else {
                    self.state.d.next = TxState::ScanData;
                }
            }
            TxState::ScanData => {
                if !self.reply_buf.read_data.val().any() {
                    self.zero_end.d.next = true;
                    self.state.d.next = TxState::Code;
                } else {
                    self.run.d.next = self.run.q.val() + 1;
                    self.j.d.next = self.j.q.val() + 1;
                    if self.run.q.val() == 253 {
                        self.zero_end.d.next = false;
                        self.state.d.next = TxState::Code;
                    } else {
                        self.state.d.next = TxState::ScanAddr;
                    }
                }
            }
            TxState::Code => {
                if !self.uart.busy.val() {
                    self.uart.start.next = true;
                    self.k.d.next = self.pos.q.val();
                    self.state.d.next = TxState::DataAddr;
                }
            }
            TxState::DataAddr => {
                if self.k.q.val() == self.j.q.val() {
                    if self.zero_end.q.val() {
                        self.pos.d.next = self.j.q.val() + 1;
                        self.state.d.next = TxState::ScanStart;
                    } else if self.run.q.val() == 254 {
                        self.pos.d.next = self.j.q.val();
                        self.state.d.next = TxState::ScanStart;
                    } else {
                        self.state.d.next = TxState::Delim;
                    }
                } else {
                    self.state.d.next = TxState::DataByte;
                }
            }
            TxState::DataByte => {
                self.uart.data.next = self.reply_buf.read_data.val();
                if !self.uart.busy.val() {
                    self.uart.start.next = true;
                    self.k.d.next = self.k.q.val() + 1;
                    self.state.d.next = TxState::DataAddr;
                }
            }
            TxState::Delim => {
                self.uart.data.next = 0.into();
                if !self.uart.busy.val() {
                    self.uart.start.next = true;
                    self.state.d.next = TxState::Drain;
                }
            }
            TxState::Drain => {
                if !self.uart.busy.val() {
                    self.state.d.next = TxState::Idle;
                }
            }
            _ => {
                self.state.d.next = TxState::Idle;
            }
        }
        if self.reset.val() {
            self.state.d.next = TxState::Idle;
        }
    }
}
