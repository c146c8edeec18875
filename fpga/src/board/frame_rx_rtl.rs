//! `FrameReceiver`: the receiving half of the protocol (docs/protocol.md, "Receiving a
//! frame"). COBS-decodes the UART's bytes as they come, writes the body into the frame
//! buffer (not while the engine is busy: it is reading it), runs the CRC two bytes behind
//! (the last two are the CRC itself) and at each delimiter reports the frame's status.

use super::crc_rtl::Crc16Serial;
use crate::protocol::MAX_FRAME;
use rust_hdl::prelude::*;

/// Frame status codes (`status` port): 0 valid, else the protocol's error code.
pub mod status {
    /// A valid frame.
    pub const OK: u64 = 0;
}

/// The frame receiver.
#[derive(LogicBlock)]
pub struct FrameReceiver {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// Synchronous reset (forget the frame in progress).
    pub reset: Signal<In, Bit>,
    /// A byte from the UART.
    pub byte_valid: Signal<In, Bit>,
    /// The byte.
    pub rx_data: Signal<In, Bits<8>>,
    /// The command engine is busy (the frame buffer is in use).
    pub engine_busy: Signal<In, Bit>,
    /// Frame buffer write enable.
    pub wr_en: Signal<Out, Bit>,
    /// Frame buffer write address.
    pub wr_addr: Signal<Out, Bits<11>>,
    /// Frame buffer write data.
    pub wr_data: Signal<Out, Bits<8>>,
    /// A frame ended (one-clock strobe).
    pub frame: Signal<Out, Bit>,
    /// Its status: 0 valid, else BadCrc (1), BadLength (2) or BadFrame (6).
    pub status: Signal<Out, Bits<3>>,
    /// Decoded bytes (body and CRC).
    pub len: Signal<Out, Bits<11>>,
    /// Body byte 0.
    pub cmd: Signal<Out, Bits<8>>,
    /// Body byte 1.
    pub seq: Signal<Out, Bits<8>>,
    /// Some byte of it arrived while the engine was busy.
    pub busy_seen: Signal<Out, Bit>,
    max_frame: Constant<Bits<11>>,
    raw_count: DFF<Bits<11>>,
    overflow: DFF<Bit>,
    code_left: DFF<Bits<8>>,
    prev_ff: DFF<Bit>,
    body_len: DFF<Bits<11>>,
    d1: DFF<Bits<8>>,
    d2: DFF<Bits<8>>,
    cmd_r: DFF<Bits<8>>,
    seq_r: DFF<Bits<8>>,
    seen: DFF<Bit>,
    frame_r: DFF<Bit>,
    status_r: DFF<Bits<3>>,
    len_r: DFF<Bits<11>>,
    fcmd_r: DFF<Bits<8>>,
    fseq_r: DFF<Bits<8>>,
    fseen_r: DFF<Bit>,
    crc_check: Crc16Serial,
    app: Signal<Local, Bit>,
    app_byte: Signal<Local, Bits<8>>,
    got_crc: Signal<Local, Bits<16>>,
}

impl Default for FrameReceiver {
    fn default() -> Self {
        FrameReceiver {
            clock: Default::default(),
            reset: Default::default(),
            byte_valid: Default::default(),
            rx_data: Default::default(),
            engine_busy: Default::default(),
            wr_en: Default::default(),
            wr_addr: Default::default(),
            wr_data: Default::default(),
            frame: Default::default(),
            status: Default::default(),
            len: Default::default(),
            cmd: Default::default(),
            seq: Default::default(),
            busy_seen: Default::default(),
            max_frame: Constant::new((MAX_FRAME as u64).into()),
            raw_count: Default::default(),
            overflow: Default::default(),
            code_left: Default::default(),
            prev_ff: Default::default(),
            body_len: Default::default(),
            d1: Default::default(),
            d2: Default::default(),
            cmd_r: Default::default(),
            seq_r: Default::default(),
            seen: Default::default(),
            frame_r: Default::default(),
            status_r: Default::default(),
            len_r: Default::default(),
            fcmd_r: Default::default(),
            fseq_r: Default::default(),
            fseen_r: Default::default(),
            crc_check: Default::default(),
            app: Default::default(),
            app_byte: Default::default(),
            got_crc: Default::default(),
        }
    }
}

impl Logic for FrameReceiver {
    #[hdl_gen]
    fn update(&mut self) {
        dff_setup!(
            self, clock, raw_count, overflow, code_left, prev_ff, body_len, d1, d2, cmd_r, seq_r, seen, frame_r,
            status_r, len_r, fcmd_r, fseq_r, fseen_r
        );
        self.crc_check.clock.next = self.clock.val();
        self.frame.next = self.frame_r.q.val();
        self.status.next = self.status_r.q.val();
        self.len.next = self.len_r.q.val();
        self.cmd.next = self.fcmd_r.q.val();
        self.seq.next = self.fseq_r.q.val();
        self.busy_seen.next = self.fseen_r.q.val();
        self.frame_r.d.next = false;
        self.crc_check.init.next = false;
        self.crc_check.feed.next = false;
        self.crc_check.data_in.next = self.d2.q.val();
        self.app.next = false;
        self.app_byte.next = self.rx_data.val();
        self.got_crc.next = (bit_cast::<16, 8>(self.d1.q.val()) << 8) | bit_cast::<16, 8>(self.d2.q.val());
        if self.byte_valid.val() {
            if self.engine_busy.val() {
                self.seen.d.next = true;
            }
            if !self.rx_data.val().any() {
                // The delimiter: report (unless nothing came since the last one) and restart.
                if self.raw_count.q.val().any() || self.overflow.q.val() {
                    self.frame_r.d.next = true;
                    self.len_r.d.next = self.body_len.q.val();
                    self.fcmd_r.d.next = self.cmd_r.q.val();
                    self.fseq_r.d.next = self.seq_r.q.val();
                    self.fseen_r.d.next = self.seen.q.val() || self.engine_busy.val();
                    if self.overflow.q.val() {
                        self.status_r.d.next = 2.into();
                    } else if self.code_left.q.val().any() {
                        self.status_r.d.next = 6.into();
                    } else if self.body_len.q.val() < 4 {
                        self.status_r.d.next = 2.into();
                    } else if self.crc_check.busy.val() || (self.crc_check.crc.val() != self.got_crc.val()) {
                        self.status_r.d.next = 1.into();
                    } else {
                        self.status_r.d.next = 0.into();
                    }
                }
                self.raw_count.d.next = 0.into();
                self.overflow.d.next = false;
                self.code_left.d.next = 0.into();
                self.prev_ff.d.next = false;
                self.body_len.d.next = 0.into();
                self.seen.d.next = false;
                self.crc_check.init.next = true;
            } else if self.raw_count.q.val() == self.max_frame.val() {
                self.overflow.d.next = true;
            } else {
                self.raw_count.d.next = self.raw_count.q.val() + 1;
                if !self.code_left.q.val().any() {
                    // A code byte: the block before it ended in a zero unless it was full.
                    if self.raw_count.q.val().any() && !self.prev_ff.q.val() {
                        self.app.next = true;
                        self.app_byte.next = 0.into();
                    }
                    self.code_left.d.next = self.rx_data.val() - 1;
                    self.prev_ff.d.next = self.rx_data.val().all();
                } else {
                    self.app.next = true;
                    self.code_left.d.next = self.code_left.q.val() - 1;
                }
            }
        }
        self.wr_en.next = self.app.val() && !self.engine_busy.val();
        self.wr_addr.next = self.body_len.q.val();
        self.wr_data.next = self.app_byte.val();
        if self.app.val() {
            self.body_len.d.next = self.body_len.q.val() + 1;
            if !self.body_len.q.val().any() {
                self.cmd_r.d.next = self.app_byte.val();
            }
            if self.body_len.q.val() == 1 {
                self.seq_r.d.next = self.app_byte.val();
            }
            self.d1.d.next = self.app_byte.val();
            self.d2.d.next = self.d1.q.val();
            if self.body_len.q.val() >= 2 {
                self.crc_check.feed.next = true;
            }
        }
        if self.reset.val() {
            self.raw_count.d.next = 0.into();
            self.overflow.d.next = false;
            self.code_left.d.next = 0.into();
            self.prev_ff.d.next = false;
            self.body_len.d.next = 0.into();
            self.seen.d.next = false;
            self.frame_r.d.next = false;
            self.crc_check.init.next = true;
        }
    }
}
