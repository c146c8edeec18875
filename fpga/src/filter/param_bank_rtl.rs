//! `ParamBank`: the filter's seven-parameter vectors (docs/sequencer.md): the centre, the
//! spread's cap and floor (configuration words 0..21), the spread, the estimate, the best
//! particle and the particle being built. The sequencer's states move whole vectors or
//! write parameter `pd`; the bank presents parameter `pd` of each and the pose inputs.
//! Its reference is the `centre`, `sigma`, `estimate`, `best` of [`crate::filter::pf::run`]
//! (test: `fpga/tests/sequencer_blocks.rs`).

use rust_hdl::prelude::*;

/// The parameter vectors.
#[derive(LogicBlock, Default)]
pub struct ParamBank {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// A configuration word is written (addresses 0..7 centre, 7..14 cap, 14..21 floor).
    pub cfg_we: Signal<In, Bit>,
    /// Its address.
    pub cfg_addr: Signal<In, Bits<5>>,
    /// Its data (the low 24 bits of the configuration word).
    pub cfg_data: Signal<In, Bits<24>>,
    /// The parameter the per-parameter operations and the `sel_*` outputs address.
    pub pd: Signal<In, Bits<3>>,
    /// A run starts: `cap = max(cap, floor)`, `sigma = cap`, `cur = centre`.
    pub init: Signal<In, Bit>,
    /// `cur[pd] = data`.
    pub cur_put: Signal<In, Bit>,
    /// `best[pd] = data`.
    pub best_put: Signal<In, Bit>,
    /// `est[pd] = data`.
    pub est_put: Signal<In, Bit>,
    /// `sigma[pd] = sigma_in`.
    pub sigma_put: Signal<In, Bit>,
    /// `cur = est`.
    pub cur_from_est: Signal<In, Bit>,
    /// `best = est`.
    pub best_from_est: Signal<In, Bit>,
    /// `best = cur`.
    pub best_from_cur: Signal<In, Bit>,
    /// `cur = best`.
    pub cur_from_best: Signal<In, Bit>,
    /// `centre = best`.
    pub centre_from_best: Signal<In, Bit>,
    /// The value a `*_put` writes.
    pub data: Signal<In, Bits<24>>,
    /// The spread `sigma_put` writes.
    pub sigma_in: Signal<In, Bits<22>>,
    /// Which angle and translation `angle` and `translation` show (0..3).
    pub axis: Signal<In, Bits<2>>,
    /// `centre[pd]`.
    pub sel_centre: Signal<Out, Bits<24>>,
    /// `sigma[pd]`.
    pub sel_sigma: Signal<Out, Bits<22>>,
    /// `floor[pd]`.
    pub sel_floor: Signal<Out, Bits<22>>,
    /// `cap[pd]`.
    pub sel_cap: Signal<Out, Bits<22>>,
    /// `est[pd]`.
    pub sel_est: Signal<Out, Bits<24>>,
    /// `cur[4 + axis]`: an angle of the particle being built.
    pub angle: Signal<Out, Bits<24>>,
    /// `cur[axis]`: a translation of the particle being built.
    pub translation: Signal<Out, Bits<24>>,
    /// `cur[3]`: its scale.
    pub scale: Signal<Out, Bits<24>>,
    /// The best parameters, 24 bits each, `[a, b, c, s, phi, theta, psi]` from bit 0.
    pub params: Signal<Out, Bits<168>>,
    centre: [DFF<Bits<24>>; 7],
    cap: [DFF<Bits<22>>; 7],
    floor: [DFF<Bits<22>>; 7],
    sigma: [DFF<Bits<22>>; 7],
    est: [DFF<Bits<24>>; 7],
    best: [DFF<Bits<24>>; 7],
    cur: [DFF<Bits<24>>; 7],
}

impl ParamBank {
    /// All zero.
    pub fn new() -> Self {
        Self::default()
    }
}

impl Logic for ParamBank {
    #[hdl_gen]
    fn update(&mut self) {
        for q in 0..7 {
            self.centre[q].clock.next = self.clock.val();
            self.centre[q].d.next = self.centre[q].q.val();
            self.cap[q].clock.next = self.clock.val();
            self.cap[q].d.next = self.cap[q].q.val();
            self.floor[q].clock.next = self.clock.val();
            self.floor[q].d.next = self.floor[q].q.val();
            self.sigma[q].clock.next = self.clock.val();
            self.sigma[q].d.next = self.sigma[q].q.val();
            self.est[q].clock.next = self.clock.val();
            self.est[q].d.next = self.est[q].q.val();
            self.best[q].clock.next = self.clock.val();
            self.best[q].d.next = self.best[q].q.val();
            self.cur[q].clock.next = self.clock.val();
            self.cur[q].d.next = self.cur[q].q.val();
        }
        self.params.next = bit_cast::<168, 24>(self.best[0].q.val())
            | (bit_cast::<168, 24>(self.best[1].q.val()) << 24)
            | (bit_cast::<168, 24>(self.best[2].q.val()) << 48)
            | (bit_cast::<168, 24>(self.best[3].q.val()) << 72)
            | (bit_cast::<168, 24>(self.best[4].q.val()) << 96)
            | (bit_cast::<168, 24>(self.best[5].q.val()) << 120)
            | (bit_cast::<168, 24>(self.best[6].q.val()) << 144);
        self.sel_centre.next = self.centre[0].q.val();
        self.sel_sigma.next = self.sigma[0].q.val();
        self.sel_floor.next = self.floor[0].q.val();
        self.sel_cap.next = self.cap[0].q.val();
        self.sel_est.next = self.est[0].q.val();
        for q in 1..7 {
            if self.pd.val().index() == q {
                self.sel_centre.next = self.centre[q].q.val();
                self.sel_sigma.next = self.sigma[q].q.val();
                self.sel_floor.next = self.floor[q].q.val();
                self.sel_cap.next = self.cap[q].q.val();
                self.sel_est.next = self.est[q].q.val();
            }
        }
        self.angle.next = self.cur[4].q.val();
        self.translation.next = self.cur[0].q.val();
        if self.axis.val() == 1 {
            self.angle.next = self.cur[5].q.val();
            self.translation.next = self.cur[1].q.val();
        }
        if self.axis.val() == 2 {
            self.angle.next = self.cur[6].q.val();
            self.translation.next = self.cur[2].q.val();
        }
        self.scale.next = self.cur[3].q.val();

        // Configuration writes first: a state's operation in the same clock wins.
        if self.cfg_we.val() {
            for q in 0..7 {
                if self.cfg_addr.val().index() == q {
                    self.centre[q].d.next = self.cfg_data.val();
                }
                if self.cfg_addr.val().index() == (q + 7) {
                    self.cap[q].d.next = self.cfg_data.val().get_bits::<22>(0);
                }
                if self.cfg_addr.val().index() == (q + 14) {
                    self.floor[q].d.next = self.cfg_data.val().get_bits::<22>(0);
                }
            }
        }
        for q in 0..7 {
            if self.init.val() {
                self.sigma[q].d.next = self.cap[q].q.val();
                if self.floor[q].q.val() > self.cap[q].q.val() {
                    self.cap[q].d.next = self.floor[q].q.val();
                    self.sigma[q].d.next = self.floor[q].q.val();
                }
                self.cur[q].d.next = self.centre[q].q.val();
            }
            if self.pd.val().index() == q {
                if self.cur_put.val() {
                    self.cur[q].d.next = self.data.val();
                }
                if self.best_put.val() {
                    self.best[q].d.next = self.data.val();
                }
                if self.est_put.val() {
                    self.est[q].d.next = self.data.val();
                }
                if self.sigma_put.val() {
                    self.sigma[q].d.next = self.sigma_in.val();
                }
            }
            if self.cur_from_est.val() {
                self.cur[q].d.next = self.est[q].q.val();
            }
            if self.best_from_est.val() {
                self.best[q].d.next = self.est[q].q.val();
            }
            if self.best_from_cur.val() {
                self.best[q].d.next = self.cur[q].q.val();
            }
            if self.cur_from_best.val() {
                self.cur[q].d.next = self.best[q].q.val();
            }
            if self.centre_from_best.val() {
                self.centre[q].d.next = self.best[q].q.val();
            }
        }
    }
}
