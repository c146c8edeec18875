//! `ScanFeeder`: streams scan points `from_index .. to_index` of the scan store into the
//! nearest-neighbour pipeline, one a clock while the pipeline takes them, through a
//! two-entry queue that hides the store's one-clock read (the order and the `last` flag
//! are what [`crate::search::neighbour_pipeline::NeighbourPipelineModel`] expects; test:
//! `fpga/tests/scan_feeder.rs`).
//! While `hold` is high it reads no further point from the store (the points already read
//! still go out); `issued` marks each read, so a consumer can count the points it has let in.

use rust_hdl::prelude::*;

/// The scan stream.
#[derive(LogicBlock, Default)]
pub struct ScanFeeder {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// Start streaming `from_index .. to_index` (only when not `streaming`).
    pub launch: Signal<In, Bit>,
    /// First point.
    pub from_index: Signal<In, Bits<13>>,
    /// One past the last point.
    pub to_index: Signal<In, Bits<13>>,
    /// The pipeline takes the presented point.
    pub ready: Signal<In, Bit>,
    /// Read no further point from the store.
    pub hold: Signal<In, Bit>,
    /// A point is read from the store this clock (it will be presented).
    pub issued: Signal<Out, Bit>,
    /// The store's read data (the point at last clock's `read_address`).
    pub read_data: Signal<In, Bits<48>>,
    /// The store's read address.
    pub read_address: Signal<Out, Bits<12>>,
    /// A point is presented.
    pub valid: Signal<Out, Bit>,
    /// The point.
    pub data: Signal<Out, Bits<48>>,
    /// It is the stream's last.
    pub last: Signal<Out, Bit>,
    /// Points are still to come (queued, in flight or unread).
    pub streaming: Signal<Out, Bit>,
    sa: DFF<Bits<13>>,
    send: DFF<Bits<13>>,
    occ: DFF<Bits<2>>,
    q0: DFF<Bits<48>>,
    q0_last: DFF<Bit>,
    q1: DFF<Bits<48>>,
    q1_last: DFF<Bit>,
    inflight: DFF<Bit>,
    inflight_last: DFF<Bit>,
    take: Signal<Local, Bit>,
    issue: Signal<Local, Bit>,
    occ_after: Signal<Local, Bits<2>>,
}

impl ScanFeeder {
    /// Idle, the queue empty.
    pub fn new() -> Self {
        Self::default()
    }
}

impl Logic for ScanFeeder {
    #[hdl_gen]
    fn update(&mut self) {
        dff_setup!(self, clock, sa, send, occ, q0, q0_last, q1, q1_last, inflight, inflight_last);
        self.take.next = self.occ.q.val().any() && self.ready.val();
        self.streaming.next = self.occ.q.val().any() || self.inflight.q.val() || (self.sa.q.val() < self.send.q.val());
        if self.take.val() {
            self.occ_after.next = self.occ.q.val() - 1;
        } else {
            self.occ_after.next = self.occ.q.val();
        }
        // Read point `sa` when the queue will have room for it.
        self.issue.next = (self.sa.q.val() < self.send.q.val())
            && !self.hold.val()
            && (!self.occ_after.val().any() || ((self.occ_after.val() == 1) && !self.inflight.q.val()));
        if self.launch.val() {
            self.sa.d.next = self.from_index.val();
            self.send.d.next = self.to_index.val();
        }
        self.read_address.next = self.sa.q.val().get_bits::<12>(0);
        self.inflight.d.next = self.issue.val();
        self.issued.next = self.issue.val();
        self.inflight_last.d.next = (self.sa.q.val() + 1) == self.send.q.val();
        if self.issue.val() {
            self.sa.d.next = self.sa.q.val() + 1;
        }
        self.valid.next = self.occ.q.val().any();
        self.data.next = self.q0.q.val();
        self.last.next = self.q0_last.q.val();
        if self.take.val() {
            if self.occ.q.val() == 2 {
                self.q0.d.next = self.q1.q.val();
                self.q0_last.d.next = self.q1_last.q.val();
                if self.inflight.q.val() {
                    self.q1.d.next = self.read_data.val();
                    self.q1_last.d.next = self.inflight_last.q.val();
                } else {
                    self.occ.d.next = 1.into();
                }
            } else if self.inflight.q.val() {
                self.q0.d.next = self.read_data.val();
                self.q0_last.d.next = self.inflight_last.q.val();
            } else {
                self.occ.d.next = 0.into();
            }
        } else if self.inflight.q.val() {
            if self.occ.q.val().any() {
                self.q1.d.next = self.read_data.val();
                self.q1_last.d.next = self.inflight_last.q.val();
                self.occ.d.next = 2.into();
            } else {
                self.q0.d.next = self.read_data.val();
                self.q0_last.d.next = self.inflight_last.q.val();
                self.occ.d.next = 1.into();
            }
        }
    }
}
