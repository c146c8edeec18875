//! The sequencer's wiring: the children's ports and their defaults, the signals the states'
//! arms read (the PRNG's next value, the propagation's and the estimate's operands, the
//! sign extensions), the pipeline's results taken in any state, the memories' defaults and
//! the configuration writes (the first part of the sequencer's kernel; the arms follow in
//! `sequencer_kernel_rtl.rs`). The model's step has it first too: `sequencer/model/signals.rs`
//! and the configuration writes in `sequencer/model.rs`.

use super::*;
use crate::common::rtl::KernelPart;

impl KernelPart<0> for PfSequencer {
    #[hdl_gen]
    fn update(&mut self) {
        dff_setup!(self, clock, n_part, n_iter, tq, seed, thr_cost, thr_max, state, ret, ret2, rng, k, iter_done);
        dff_setup!(self, clock, run_r, fin_r, first, half, i, j, pd, spread, pa, cra, wra, x_r, off, start_r, pose_r);
        dff_setup!(self, clock, maxd, costr, cmin, imin, best_cost_r, best_max_r, p, mask, cnt, w_sum, acc);
        dff_setup!(self, clock, cj, ie, inflight, havep, w_r, sq, lo, hi);
        self.pram.read_clock.next = self.clock.val();
        self.pram.write_clock.next = self.clock.val();
        self.cram.read_clock.next = self.clock.val();
        self.cram.write_clock.next = self.clock.val();
        self.wram.read_clock.next = self.clock.val();
        self.wram.write_clock.next = self.clock.val();
        self.mul.clock.next = self.clock.val();
        self.mul.reset.next = self.reset.val();
        self.div.clock.next = self.clock.val();
        self.div.reset.next = self.reset.val();
        self.cordic.clock.next = self.clock.val();
        self.pose_prog.clock.next = self.clock.val();

        // Outputs (all from registers).
        self.start.next = self.start_r.q.val();
        self.pose.next = self.pose_r.q.val();
        self.running.next = self.run_r.q.val();
        self.finished.next = self.fin_r.q.val();
        self.iterations.next = self.iter_done.q.val();
        self.best_cost.next = self.best_cost_r.q.val();
        self.best_max.next = self.best_max_r.q.val();
        self.params.next = self.bank.params.val();

        // The parameter vectors, parameter `pd` of each.
        self.bank.clock.next = self.clock.val();
        self.bank.cfg_we.next = self.cfg_we.val();
        self.bank.cfg_addr.next = self.cfg_addr.val();
        self.bank.cfg_data.next = self.cfg_data.val().get_bits::<24>(0);
        self.bank.pd.next = self.pd.q.val();
        self.bank.axis.next = self.cj.q.val();
        self.bank.init.next = false;
        self.bank.cur_put.next = false;
        self.bank.best_put.next = false;
        self.bank.est_put.next = false;
        self.bank.sigma_put.next = false;
        self.bank.cur_from_est.next = false;
        self.bank.best_from_est.next = false;
        self.bank.best_from_cur.next = false;
        self.bank.cur_from_best.next = false;
        self.bank.centre_from_best.next = false;
        self.bank.data.next = self.propagate.value.val();
        self.bank.sigma_in.next = self.estimate.spread.val();

        // PRNG: xorshift32 (13, 17, 5).
        self.xorshift.x.next = self.rng.q.val();
        self.rng_next.next = self.xorshift.y.val();
        self.u_hi.next = self.rng.q.val().get_bits::<16>(16);

        // Propagation arithmetic (the reference of `diff` is the estimate for the spread).
        self.propagate.x.next = self.x_r.q.val();
        self.propagate.centre.next = self.bank.sel_centre.val();
        self.propagate.reference.next = self.bank.sel_centre.val();
        if self.spread.q.val() {
            self.propagate.reference.next = self.bank.sel_est.val();
        }
        self.propagate.sigma.next = self.bank.sel_sigma.val();
        self.propagate.product.next = self.mul.product.val().get_bits::<27>(14);
        self.propagate.first.next = self.first.q.val();
        self.propagate.off.next = self.off.q.val();
        self.propagate.scale.next = self.pd.q.val() == 3;
        self.ex_now.next = self.cram.read_data.val().get_bits::<48>(0) - self.cmin.q.val();
        self.ex_masked.next = self.ex_now.val() & !self.mask.q.val();
        // `(lo + hi) / 2` in 6 bits.
        self.t_mid.next =
            (self.lo.q.val() >> 1) + (self.hi.q.val() >> 1) + (self.lo.q.val() & self.hi.q.val() & bits::<6>(1));

        // CORDIC.
        self.cordic.angle.next = self.bank.angle.val();
        self.cordic.sin.next = self.state.q.val() == SeqState::CorSin;
        self.cordic.load.next = false;
        self.cordic.step.next = false;

        // Pose program.
        self.pose_prog.product.next = self.mul.product.val();
        self.pose_prog.restart.next = false;
        self.pose_prog.fetch.next = false;
        self.pose_prog.latch.next = false;
        self.pose_prog.exec.next = false;
        self.pose_prog.retire.next = false;
        self.translation.x.next = self.bank.translation.val();

        // Estimate / spread arithmetic.
        self.estimate.acc.next = self.acc.q.val();
        self.estimate.quotient.next = self.div.quotient.val();
        self.estimate.centre.next = self.bank.sel_centre.val();
        self.estimate.floor.next = self.bank.sel_floor.val();
        self.estimate.cap.next = self.bank.sel_cap.val();
        self.estimate.scale.next = self.pd.q.val() == 3;
        self.maxd_next.next = self.maxd.q.val();
        if self.nn_valid.val() && (self.nn_dist.val() > self.maxd.q.val()) {
            self.maxd_next.next = self.nn_dist.val();
        }
        // The pipeline's results are taken in any state (an evaluation runs while the next
        // particle is propagated): the largest distance, the cost, the end of the flight.
        self.maxd.d.next = self.maxd_next.val();
        if self.cost_valid.val() {
            self.costr.d.next = self.cost.val();
            self.inflight.d.next = false;
        }
        self.resample.clock.next = self.clock.val();
        self.resample.clear.next = false;
        self.resample.set_pointer.next = false;
        self.resample.add_weight.next = false;
        self.resample.advance.next = false;
        self.resample.product.next = self.mul.product.val();
        self.resample.w_sum.next = self.w_sum.q.val();
        self.weight.clock.next = self.clock.val();
        self.weight.temper.next = false;
        self.weight.p.next = self.p.q.val();
        self.weight.tq.next = self.tq.q.val();
        self.weight.latch.next = false;
        self.weight.excess.next = self.ex_now.val();

        // Sign extensions (a mux on the sign bit, so no carry chain lengthens a path).
        self.u_hi_s18.next = bit_cast::<18, 16>(self.u_hi.val());
        if self.u_hi.val().get_bit(15) {
            self.u_hi_s18.next = bit_cast::<18, 16>(self.u_hi.val()) | bits::<18>(0x3_0000);
        }
        self.scale_s26.next = bit_cast::<26, 24>(self.bank.scale.val());
        if self.bank.scale.val().get_bit(23) {
            self.scale_s26.next = bit_cast::<26, 24>(self.bank.scale.val()) | bits::<26>(0x300_0000);
        }

        // Memory defaults.
        self.pram.read_address.next = self.pa.q.val();
        self.pram.write_enable.next = false;
        self.pram.write_address.next = self.pa.q.val();
        self.pram.write_data.next = self.propagate.value.val();
        self.cram.read_address.next = self.cra.q.val();
        self.cram.write_enable.next = false;
        self.cram.write_address.next = self.i.q.val().get_bits::<8>(0);
        self.cram.write_data.next =
            bit_cast::<82, 48>(self.costr.q.val()) | (bit_cast::<82, 34>(self.maxd.q.val()) << 48);
        self.wram.read_address.next = self.wra.q.val();
        self.wram.write_enable.next = false;
        self.wram.write_address.next = self.i.q.val().get_bits::<8>(0);
        self.wram.write_data.next = self.weight.value.val();
        self.pose_prog.load.next = false;
        self.pose_prog.load_addr.next = bit_cast::<5, 2>(self.cj.q.val()) << 1;
        self.pose_prog.load_data.next = self.cordic.value.val();
        self.start_r.d.next = false;
        self.mul_go.next = false;
        self.mul_a_in.next = bit_cast::<26, 22>(self.bank.sel_sigma.val());
        self.mul_b_in.next = self.u_hi_s18.val();
        self.div_go.next = false;
        self.div_n_in.next = self.estimate.magnitude.val();

        // Configuration writes.
        if self.cfg_we.val() {
            if self.cfg_addr.val() == 21 {
                self.seed.d.next = self.cfg_data.val().get_bits::<32>(0);
            }
            if self.cfg_addr.val() == 22 {
                self.thr_cost.d.next = self.cfg_data.val();
            }
            if self.cfg_addr.val() == 23 {
                self.thr_max.d.next = self.cfg_data.val().get_bits::<34>(0);
            }
            if self.cfg_addr.val() == 24 {
                self.n_part.d.next = self.cfg_data.val().get_bits::<9>(0);
                self.n_iter.d.next = self.cfg_data.val().get_bits::<16>(16);
                self.tq.d.next = self.cfg_data.val().get_bits::<6>(32);
            }
        }
    }
}
