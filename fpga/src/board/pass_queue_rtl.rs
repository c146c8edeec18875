//! `PassQueue`: the polish pass's queue of found points between the residual stage and the
//! pass (the engine, docs/polish-datapath.md, "The pass service and the queue"):
//! [`PASS_QUEUE`] entries in a small RAM, the head in a register. A point written is in the
//! RAM at the next clock; the head is fetched from the RAM (one clock's read) once the last
//! was taken, so the head comes back two clocks after a take. The writer counts the entries
//! (credits): the queue does not guard against a write when full. A reset drops every
//! entry. Test: `fpga/tests/pass_queue.rs`.

use rust_hdl::prelude::*;

/// Entries of the queue (the RAM's eight words); the engine lets a pass's points into the
/// pipeline while those in the pipeline and those here are fewer.
pub const PASS_QUEUE: usize = 8;

/// The queue.
#[derive(LogicBlock, Default)]
pub struct PassQueue {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// Synchronous reset: empty.
    pub reset: Signal<In, Bit>,
    /// Write `data_in` (never when full: the writer counts).
    pub write: Signal<In, Bit>,
    /// A found point: image, normal, signed residual (`q | n << 48 | s << 96`).
    pub data_in: Signal<In, Bits<109>>,
    /// Take the head (while `valid`).
    pub take: Signal<In, Bit>,
    /// The head is there.
    pub valid: Signal<Out, Bit>,
    /// The head.
    pub data_out: Signal<Out, Bits<109>>,
    store: RAM<Bits<109>, 3>,
    wptr: DFF<Bits<3>>,
    rptr: DFF<Bits<3>>,
    /// A fetch is on its way from the RAM; the head is held.
    fv: DFF<Bit>,
    hv: DFF<Bit>,
    hd: DFF<Bits<109>>,
}

const _: () = assert!(PASS_QUEUE == 8);

impl Logic for PassQueue {
    #[hdl_gen]
    fn update(&mut self) {
        dff_setup!(self, clock, wptr, rptr, fv, hv, hd);
        self.store.read_clock.next = self.clock.val();
        self.store.write_clock.next = self.clock.val();
        self.valid.next = self.hv.q.val();
        self.data_out.next = self.hd.q.val();
        self.store.write_enable.next = self.write.val();
        self.store.write_address.next = self.wptr.q.val();
        self.store.write_data.next = self.data_in.val();
        if self.write.val() {
            self.wptr.d.next = self.wptr.q.val() + 1;
        }
        self.store.read_address.next = self.rptr.q.val();
        self.fv.d.next = false;
        if self.take.val() && self.hv.q.val() {
            self.hv.d.next = false;
        }
        // A fetch once the head is gone and none is on its way.
        if !self.hv.q.val() && !self.fv.q.val() && (self.rptr.q.val() != self.wptr.q.val()) {
            self.fv.d.next = true;
            self.rptr.d.next = self.rptr.q.val() + 1;
        }
        if self.fv.q.val() {
            self.hv.d.next = true;
            self.hd.d.next = self.store.read_data.val();
        }
        if self.reset.val() {
            self.rptr.d.next = self.wptr.q.val();
            self.fv.d.next = false;
            self.hv.d.next = false;
            if self.write.val() {
                self.rptr.d.next = self.wptr.q.val() + 1;
            }
        }
    }
}
