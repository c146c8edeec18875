//! `Crc16Serial`: CRC-16/CCITT-FALSE (polynomial 0x1021, initial 0xFFFF, MSB first), one
//! bit per clock: a byte takes 8 clocks, far less than the 10 bit periods a UART byte takes.

use rust_hdl::prelude::*;

/// Bit-serial CRC-16/CCITT-FALSE.
#[derive(LogicBlock)]
pub struct Crc16Serial {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// Restart at 0xFFFF (priority over `feed`).
    pub init: Signal<In, Bit>,
    /// Add `byte` (honoured when not busy).
    pub feed: Signal<In, Bit>,
    /// The byte.
    pub data_in: Signal<In, Bits<8>>,
    /// The CRC of the bytes fed so far (valid when not busy).
    pub crc: Signal<Out, Bits<16>>,
    /// Still shifting a byte in.
    pub busy: Signal<Out, Bit>,
    poly: Constant<Bits<16>>,
    /// The CRC, stored inverted so that power-up reads as the initial 0xFFFF.
    crc_n: DFF<Bits<16>>,
    sr: DFF<Bits<8>>,
    left: DFF<Bits<4>>,
    value: Signal<Local, Bits<16>>,
}

impl Default for Crc16Serial {
    fn default() -> Self {
        Crc16Serial {
            clock: Default::default(),
            init: Default::default(),
            feed: Default::default(),
            data_in: Default::default(),
            crc: Default::default(),
            busy: Default::default(),
            poly: Constant::new(0x1021u64.into()),
            crc_n: Default::default(),
            sr: Default::default(),
            left: Default::default(),
            value: Default::default(),
        }
    }
}

impl Logic for Crc16Serial {
    #[hdl_gen]
    fn update(&mut self) {
        dff_setup!(self, clock, crc_n, sr, left);
        self.value.next = !self.crc_n.q.val();
        self.crc.next = self.value.val();
        self.busy.next = self.left.q.val().any();
        if self.left.q.val().any() {
            if self.value.val().get_bit(15) ^ self.sr.q.val().get_bit(7) {
                self.crc_n.d.next = !((self.value.val() << 1) ^ self.poly.val());
            } else {
                self.crc_n.d.next = !(self.value.val() << 1);
            }
            self.sr.d.next = self.sr.q.val() << 1;
            self.left.d.next = self.left.q.val() - 1;
        } else if self.feed.val() {
            self.sr.d.next = self.data_in.val();
            self.left.d.next = 8.into();
        }
        if self.init.val() {
            self.crc_n.d.next = 0.into();
            self.left.d.next = 0.into();
        }
    }
}
