//! `ModelDigest`: the model digest of docs/protocol.md ("Resident model"), CRC-32/MPEG-2
//! (polynomial 0x04C11DB7, MSB first, no reflection) a byte per clock; the reference is
//! [`crate::protocol::digest_update`]. Power-up reads [`crate::protocol::DIGEST_NONE`]
//! (0); `restart` sets [`crate::protocol::DIGEST_INIT`].

use crate::protocol::{DIGEST_INIT, DIGEST_NONE};
use rust_hdl::prelude::*;

/// The polynomial of [`crate::protocol::digest_update`].
const POLY: u64 = 0x04c1_1db7;

const _: () = assert!(DIGEST_NONE == 0 && DIGEST_INIT == u32::MAX);

/// The digest register and its byte-wide update.
#[derive(LogicBlock)]
pub struct ModelDigest {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// Restart at `DIGEST_INIT` (before `feed` in the same clock).
    pub restart: Signal<In, Bit>,
    /// Add `data_in`.
    pub feed: Signal<In, Bit>,
    /// The byte.
    pub data_in: Signal<In, Bits<8>>,
    /// The digest of the bytes fed since the last restart.
    pub digest: Signal<Out, Bits<32>>,
    poly: Constant<Bits<32>>,
    init: Constant<Bits<32>>,
    value: DFF<Bits<32>>,
    /// The CRC before the byte (the register or the restart value), then after each bit.
    c0: Signal<Local, Bits<32>>,
    c1: Signal<Local, Bits<32>>,
    c2: Signal<Local, Bits<32>>,
    c3: Signal<Local, Bits<32>>,
    c4: Signal<Local, Bits<32>>,
    c5: Signal<Local, Bits<32>>,
    c6: Signal<Local, Bits<32>>,
    c7: Signal<Local, Bits<32>>,
    c8: Signal<Local, Bits<32>>,
}

impl Default for ModelDigest {
    fn default() -> Self {
        ModelDigest {
            clock: Default::default(),
            restart: Default::default(),
            feed: Default::default(),
            data_in: Default::default(),
            digest: Default::default(),
            poly: Constant::new(POLY.into()),
            init: Constant::new((DIGEST_INIT as u64).into()),
            value: Default::default(),
            c0: Default::default(),
            c1: Default::default(),
            c2: Default::default(),
            c3: Default::default(),
            c4: Default::default(),
            c5: Default::default(),
            c6: Default::default(),
            c7: Default::default(),
            c8: Default::default(),
        }
    }
}

impl Logic for ModelDigest {
    #[hdl_gen]
    fn update(&mut self) {
        dff_setup!(self, clock, value);
        self.digest.next = self.value.q.val();
        if self.restart.val() {
            self.c0.next = self.init.val();
        } else {
            self.c0.next = self.value.q.val();
        }
        // One bit of the byte a step, MSB first (the reference's inner loop, unrolled).
        if self.c0.val().get_bit(31) ^ self.data_in.val().get_bit(7) {
            self.c1.next = (self.c0.val() << 1) ^ self.poly.val();
        } else {
            self.c1.next = self.c0.val() << 1;
        }
        if self.c1.val().get_bit(31) ^ self.data_in.val().get_bit(6) {
            self.c2.next = (self.c1.val() << 1) ^ self.poly.val();
        } else {
            self.c2.next = self.c1.val() << 1;
        }
        if self.c2.val().get_bit(31) ^ self.data_in.val().get_bit(5) {
            self.c3.next = (self.c2.val() << 1) ^ self.poly.val();
        } else {
            self.c3.next = self.c2.val() << 1;
        }
        if self.c3.val().get_bit(31) ^ self.data_in.val().get_bit(4) {
            self.c4.next = (self.c3.val() << 1) ^ self.poly.val();
        } else {
            self.c4.next = self.c3.val() << 1;
        }
        if self.c4.val().get_bit(31) ^ self.data_in.val().get_bit(3) {
            self.c5.next = (self.c4.val() << 1) ^ self.poly.val();
        } else {
            self.c5.next = self.c4.val() << 1;
        }
        if self.c5.val().get_bit(31) ^ self.data_in.val().get_bit(2) {
            self.c6.next = (self.c5.val() << 1) ^ self.poly.val();
        } else {
            self.c6.next = self.c5.val() << 1;
        }
        if self.c6.val().get_bit(31) ^ self.data_in.val().get_bit(1) {
            self.c7.next = (self.c6.val() << 1) ^ self.poly.val();
        } else {
            self.c7.next = self.c6.val() << 1;
        }
        if self.c7.val().get_bit(31) ^ self.data_in.val().get_bit(0) {
            self.c8.next = (self.c7.val() << 1) ^ self.poly.val();
        } else {
            self.c8.next = self.c7.val() << 1;
        }
        if self.feed.val() {
            self.value.d.next = self.c8.val();
        } else if self.restart.val() {
            self.value.d.next = self.init.val();
        }
    }
}
