//! The sequencer's state machine: one `update` over the states of [`SeqState`].

use super::*;

impl Logic for PfSequencer {
    #[hdl_gen]
    fn update(&mut self) {
        dff_setup!(
            self,
            clock,
            n_part,
            n_iter,
            tq,
            seed,
            thr_cost,
            thr_max,
            state,
            ret,
            ret2,
            rng,
            k,
            iter_done,
            run_r,
            fin_r,
            first,
            half,
            i,
            j,
            pd,
            spread,
            pa,
            cra,
            wra,
            x_r,
            off,
            start_r,
            pose_r,
            maxd,
            costr,
            cmin,
            imin,
            best_cost_r,
            best_max_r,
            p,
            mask,
            cnt,
            pre,
            sh,
            w_sum,
            acc,
            lft,
            rgt,
            cj
        );
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
        self.params.next = bit_cast::<168, 24>(self.best[0].q.val())
            | (bit_cast::<168, 24>(self.best[1].q.val()) << 24)
            | (bit_cast::<168, 24>(self.best[2].q.val()) << 48)
            | (bit_cast::<168, 24>(self.best[3].q.val()) << 72)
            | (bit_cast::<168, 24>(self.best[4].q.val()) << 96)
            | (bit_cast::<168, 24>(self.best[5].q.val()) << 120)
            | (bit_cast::<168, 24>(self.best[6].q.val()) << 144);

        // Parameter `d` of the vectors.
        self.sel_centre.next = self.centre[0].q.val();
        self.sel_sigma.next = self.sigma[0].q.val();
        self.sel_floor.next = self.floor[0].q.val();
        self.sel_cap.next = self.cap[0].q.val();
        self.sel_est.next = self.est[0].q.val();
        for q in 1..7 {
            if self.pd.q.val().index() == q {
                self.sel_centre.next = self.centre[q].q.val();
                self.sel_sigma.next = self.sigma[q].q.val();
                self.sel_floor.next = self.floor[q].q.val();
                self.sel_cap.next = self.cap[q].q.val();
                self.sel_est.next = self.est[q].q.val();
            }
        }

        // PRNG: xorshift32 (13, 17, 5).
        self.xorshift.x.next = self.rng.q.val();
        self.rng_next.next = self.xorshift.y.val();
        self.u_hi.next = self.rng.q.val().get_bits::<16>(16);

        // Propagation arithmetic.
        self.prod_sh14.next = self.mul.product.val().get_bits::<26>(14);
        self.prod_sh15.next = self.mul.product.val().get_bits::<26>(15);
        self.ref24.next = self.sel_centre.val();
        if self.spread.q.val() {
            self.ref24.next = self.sel_est.val();
        }
        self.diff24.next = self.x_r.q.val() - self.ref24.val();
        self.diff26.next = bit_cast::<26, 24>(self.diff24.val());
        if self.diff24.val().get_bit(23) {
            self.diff26.next = bit_cast::<26, 24>(self.diff24.val()) | bits::<26>(0x300_0000);
        }
        self.lim26.next = bit_cast::<26, 22>(self.sel_sigma.val()) << 1;
        // Negations go through a Local: in a Verilog compare, `0 - x` would be 32 bits wide.
        self.neg_lim26.next = bits::<26>(0) - self.lim26.val();
        self.v24.next = self.sel_centre.val() + self.off.q.val().get_bits::<24>(0);
        self.v_fix.next = self.v24.val();
        if (self.pd.q.val() == 3) && (self.v24.val().get_bit(23) || !self.v24.val().any()) {
            self.v_fix.next = bits::<24>(1);
        }
        self.ex_now.next = self.cram.read_data.val().get_bits::<48>(0) - self.cmin.q.val();
        self.ex_masked.next = self.ex_now.val() & !self.mask.q.val();

        // CORDIC.
        self.ang.next = self.cur[4].q.val();
        if self.cj.q.val() == 1 {
            self.ang.next = self.cur[5].q.val();
        }
        if self.cj.q.val() == 2 {
            self.ang.next = self.cur[6].q.val();
        }
        self.cordic.angle.next = self.ang.val();
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
        self.tr_in.next = self.cur[0].q.val();
        if self.cj.q.val() == 1 {
            self.tr_in.next = self.cur[1].q.val();
        }
        if self.cj.q.val() == 2 {
            self.tr_in.next = self.cur[2].q.val();
        }
        self.tr_in_s25.next = bit_cast::<25, 24>(self.tr_in.val());
        if self.tr_in.val().get_bit(23) {
            self.tr_in_s25.next = bit_cast::<25, 24>(self.tr_in.val()) | bits::<25>(0x100_0000);
        }
        self.tr_y.next = self.tr_in_s25.val() + bits::<25>(32);
        self.tr_t.next = bit_cast::<19, 25>(self.tr_y.val() >> 6);
        self.tr_sat.next = self.tr_t.val().get_bits::<18>(0);
        if (self.tr_t.val() ^ bits::<19>(0x4_0000)) > bits::<19>(0x5_ffff) {
            self.tr_sat.next = bits::<18>(0x1_ffff);
        }
        if (self.tr_t.val() ^ bits::<19>(0x4_0000)) < bits::<19>(0x2_0000) {
            self.tr_sat.next = bits::<18>(0x2_0000);
        }

        // Estimate / spread arithmetic.
        self.acc_abs.next = self.acc.q.val();
        if self.acc.q.val().get_bit(47) {
            self.acc_abs.next = bits::<48>(0) - self.acc.q.val();
        }
        self.q26.next = self.div.quotient.val().get_bits::<26>(0);
        self.mean26.next = self.q26.val();
        if self.acc.q.val().get_bit(47) {
            self.mean26.next = bits::<26>(0) - self.q26.val();
        }
        self.dev26.next = self.q26.val() + (self.q26.val() >> 2);
        self.sig_new.next = self.dev26.val().get_bits::<22>(0);
        if self.dev26.val() > bit_cast::<26, 22>(self.sel_cap.val()) {
            self.sig_new.next = self.sel_cap.val();
        }
        if self.dev26.val() < bit_cast::<26, 22>(self.sel_floor.val()) {
            self.sig_new.next = self.sel_floor.val();
        }
        self.est_v.next = self.sel_centre.val() + bit_cast::<24, 26>(self.mean26.val());
        self.est_fix.next = self.est_v.val();
        if (self.pd.q.val() == 3) && (self.est_v.val().get_bit(23) || !self.est_v.val().any()) {
            self.est_fix.next = bits::<24>(1);
        }
        self.abs26.next = self.diff26.val();
        if self.diff26.val().get_bit(25) {
            self.abs26.next = bits::<26>(0) - self.diff26.val();
        }
        self.maxd_next.next = self.maxd.q.val();
        if self.nn_valid.val() && (self.nn_dist.val() > self.maxd.q.val()) {
            self.maxd_next.next = self.nn_dist.val();
        }
        self.t_entry.next = self.sh.q.val().get_bits::<8>(0);
        if self.sh.q.val() > 255 {
            self.t_entry.next = bits::<8>(255);
        }
        self.exp_rom.address.next = self.t_entry.val();
        self.e_tmp.next = self.tq.q.val();
        if (self.p.q.val() > 2) && ((self.p.q.val() - 2) > self.tq.q.val()) {
            self.e_tmp.next = self.p.q.val() - 2;
        }

        // Sign extensions (a mux on the sign bit, so no carry chain lengthens a path).
        self.u_hi_s18.next = bit_cast::<18, 16>(self.u_hi.val());
        if self.u_hi.val().get_bit(15) {
            self.u_hi_s18.next = bit_cast::<18, 16>(self.u_hi.val()) | bits::<18>(0x3_0000);
        }
        self.cor_v_s26.next = bit_cast::<26, 20>(self.cordic.value.val());
        if self.cordic.value.val().get_bit(19) {
            self.cor_v_s26.next = bit_cast::<26, 20>(self.cordic.value.val()) | bits::<26>(0x3f0_0000);
        }
        self.scale_s26.next = bit_cast::<26, 24>(self.cur[3].q.val());
        if self.cur[3].q.val().get_bit(23) {
            self.scale_s26.next = bit_cast::<26, 24>(self.cur[3].q.val()) | bits::<26>(0x300_0000);
        }

        // Memory defaults.
        self.pram.read_address.next = self.pa.q.val();
        self.pram.write_enable.next = false;
        self.pram.write_address.next = self.pa.q.val();
        self.pram.write_data.next = self.v_fix.val();
        self.cram.read_address.next = self.cra.q.val();
        self.cram.write_enable.next = false;
        self.cram.write_address.next = self.i.q.val().get_bits::<8>(0);
        self.cram.write_data.next =
            bit_cast::<82, 48>(self.costr.q.val()) | (bit_cast::<82, 34>(self.maxd.q.val()) << 48);
        self.wram.read_address.next = self.wra.q.val();
        self.wram.write_enable.next = false;
        self.wram.write_address.next = self.i.q.val().get_bits::<8>(0);
        self.wram.write_data.next = self.exp_rom.data.val();
        self.pose_prog.load.next = false;
        self.pose_prog.load_addr.next = bit_cast::<5, 2>(self.cj.q.val()) << 1;
        self.pose_prog.load_data.next = self.cor_v_s26.val();
        self.start_r.d.next = false;
        self.mul_go.next = false;
        self.mul_a_in.next = bit_cast::<26, 22>(self.sel_sigma.val());
        self.mul_b_in.next = self.u_hi_s18.val();
        self.div_go.next = false;
        self.div_n_in.next = self.acc_abs.val();

        // Configuration writes.
        if self.cfg_we.val() {
            for q in 0..7 {
                if self.cfg_addr.val().index() == q {
                    self.centre[q].d.next = self.cfg_data.val().get_bits::<24>(0);
                }
                if self.cfg_addr.val().index() == (q + 7) {
                    self.cap[q].d.next = self.cfg_data.val().get_bits::<22>(0);
                }
                if self.cfg_addr.val().index() == (q + 14) {
                    self.floor[q].d.next = self.cfg_data.val().get_bits::<22>(0);
                }
            }
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

        match self.state.q.val() {
            SeqState::Idle => {
                if self.go.val() {
                    for q in 0..7 {
                        self.sigma[q].d.next = self.cap[q].q.val();
                        if self.floor[q].q.val() > self.cap[q].q.val() {
                            self.cap[q].d.next = self.floor[q].q.val();
                            self.sigma[q].d.next = self.floor[q].q.val();
                        }
                        self.cur[q].d.next = self.centre[q].q.val();
                    }
                    self.rng.d.next = self.seed.q.val();
                    if !self.seed.q.val().any() {
                        self.rng.d.next = bits::<32>(1);
                    }
                    self.run_r.d.next = true;
                    self.fin_r.d.next = false;
                    // Nothing evaluated yet: Status reports no best cost (not the last run's).
                    self.best_cost_r.d.next = self.all48.val();
                    self.iter_done.d.next = 0.into();
                    self.k.d.next = 0.into();
                    self.half.d.next = 0.into();
                    self.cj.d.next = 0.into();
                    self.ret.d.next = SeqState::EvStart;
                    self.ret2.d.next = SeqState::StartDone;
                    self.state.d.next = SeqState::CorInit;
                }
            }
            // ---- Pose subroutine: `cur` -> `pose_r`, then `ret`.
            SeqState::CorInit => {
                self.cordic.load.next = true;
                self.state.d.next = SeqState::CorStep;
            }
            SeqState::CorStep => {
                self.cordic.step.next = true;
                if self.cordic.last.val() {
                    self.state.d.next = SeqState::CorCos;
                }
            }
            SeqState::CorCos => {
                self.pose_prog.load.next = true;
                self.state.d.next = SeqState::CorSin;
            }
            SeqState::CorSin => {
                self.pose_prog.load.next = true;
                self.pose_prog.load_addr.next = (bit_cast::<5, 2>(self.cj.q.val()) << 1) + 1;
                self.cj.d.next = self.cj.q.val() + 1;
                if self.cj.q.val() == 2 {
                    self.state.d.next = SeqState::PoseScale;
                } else {
                    self.state.d.next = SeqState::CorInit;
                }
            }
            SeqState::PoseScale => {
                self.pose_prog.load.next = true;
                self.pose_prog.load_addr.next = bits::<5>(6);
                self.pose_prog.load_data.next = self.scale_s26.val();
                self.pose_prog.restart.next = true;
                self.cj.d.next = 0.into();
                self.state.d.next = SeqState::OpFetch;
            }
            SeqState::OpFetch => {
                self.pose_prog.fetch.next = true;
                self.state.d.next = SeqState::OpA;
            }
            SeqState::OpA => {
                self.pose_prog.latch.next = true;
                self.state.d.next = SeqState::OpB;
            }
            SeqState::OpB => {
                self.pose_prog.exec.next = true;
                if self.pose_prog.arith.val() {
                    self.state.d.next = SeqState::OpFetch;
                } else {
                    self.mul_go.next = true;
                    self.mul_a_in.next = self.pose_prog.mul_a.val();
                    self.mul_b_in.next = self.pose_prog.mul_b.val();
                    self.state.d.next = SeqState::OpMul;
                }
            }
            SeqState::OpMul => {
                if !self.mul.busy.val() {
                    self.pose_prog.retire.next = true;
                    if self.pose_prog.to_pose.val() {
                        self.pose_r.d.next =
                            (self.pose_r.q.val() >> 18) | (bit_cast::<216, 18>(self.pose_prog.entry.val()) << 198);
                    }
                    if self.pose_prog.last.val() {
                        self.state.d.next = SeqState::PoseT;
                    } else {
                        self.state.d.next = SeqState::OpFetch;
                    }
                }
            }
            SeqState::PoseT => {
                self.pose_r.d.next = (self.pose_r.q.val() >> 18) | (bit_cast::<216, 18>(self.tr_sat.val()) << 198);
                self.cj.d.next = self.cj.q.val() + 1;
                if self.cj.q.val() == 2 {
                    self.state.d.next = self.ret.q.val();
                }
            }
            // ---- Evaluate subroutine: the pipeline on `pose_r`, then `ret2`.
            SeqState::EvStart => {
                if self.nn_ready.val() {
                    self.start_r.d.next = true;
                    self.maxd.d.next = 0.into();
                    self.state.d.next = SeqState::EvWait;
                }
            }
            SeqState::EvWait => {
                self.maxd.d.next = self.maxd_next.val();
                if self.cost_valid.val() {
                    self.costr.d.next = self.cost.val();
                    self.state.d.next = self.ret2.q.val();
                }
            }
            SeqState::StartDone => {
                self.best_cost_r.d.next = self.costr.q.val();
                self.best_max_r.d.next = self.maxd.q.val();
                for q in 0..7 {
                    self.best[q].d.next = self.cur[q].q.val();
                }
                self.state.d.next = SeqState::IterBegin;
            }
            // ---- One iteration.
            SeqState::IterBegin => {
                self.i.d.next = 0.into();
                self.pd.d.next = 0.into();
                self.cmin.d.next = self.all48.val();
                self.imin.d.next = 0.into();
                self.first.d.next = !self.k.q.val().any();
                self.pa.d.next = bit_cast::<12, 1>(self.half.q.val()) << 11;
                self.state.d.next = SeqState::PropAddr;
            }
            SeqState::PropAddr => {
                self.rng.d.next = self.rng_next.val();
                self.state.d.next = SeqState::PropRead;
            }
            SeqState::PropRead => {
                self.mul_go.next = true;
                self.state.d.next = SeqState::PropMul;
            }
            SeqState::PropMul => {
                self.x_r.d.next = self.pram.read_data.val();
                if !self.mul.busy.val() {
                    if self.first.q.val() {
                        self.off.d.next = self.prod_sh14.val();
                    } else {
                        self.off.d.next = self.diff26.val() + self.prod_sh15.val();
                    }
                    self.state.d.next = SeqState::PropClamp;
                }
            }
            SeqState::PropClamp => {
                if (self.off.q.val() ^ bits::<26>(0x200_0000)) > (self.lim26.val() ^ bits::<26>(0x200_0000)) {
                    self.off.d.next = self.lim26.val();
                }
                if (self.off.q.val() ^ bits::<26>(0x200_0000)) < (self.neg_lim26.val() ^ bits::<26>(0x200_0000)) {
                    self.off.d.next = self.neg_lim26.val();
                }
                self.state.d.next = SeqState::PropWrite;
            }
            SeqState::PropWrite => {
                self.pram.write_enable.next = true;
                for q in 0..7 {
                    if self.pd.q.val().index() == q {
                        self.cur[q].d.next = self.v_fix.val();
                    }
                }
                self.pa.d.next = self.pa.q.val() + 1;
                self.pd.d.next = self.pd.q.val() + 1;
                if self.pd.q.val() == 6 {
                    self.pd.d.next = 0.into();
                    self.pa.d.next = self.pa.q.val() + 2;
                    self.cj.d.next = 0.into();
                    self.ret.d.next = SeqState::EvStart;
                    self.ret2.d.next = SeqState::PartStore;
                    self.state.d.next = SeqState::CorInit;
                } else {
                    self.state.d.next = SeqState::PropAddr;
                }
            }
            SeqState::PartStore => {
                self.cram.write_enable.next = true;
                if self.costr.q.val() < self.cmin.q.val() {
                    self.cmin.d.next = self.costr.q.val();
                    self.imin.d.next = self.i.q.val().get_bits::<8>(0);
                }
                self.i.d.next = self.i.q.val() + 1;
                if (self.i.q.val() + 1) == self.n_part.q.val() {
                    self.p.d.next = 0.into();
                    self.mask.d.next = 0.into();
                    self.state.d.next = SeqState::TPass;
                } else {
                    self.state.d.next = SeqState::PropAddr;
                }
            }
            // ---- Temperature: the bit length of the excess of rank n / 2.
            SeqState::TPass => {
                self.i.d.next = 0.into();
                self.cnt.d.next = 0.into();
                self.state.d.next = SeqState::TAddr;
            }
            SeqState::TAddr => {
                self.cra.d.next = self.i.q.val().get_bits::<8>(0);
                self.state.d.next = SeqState::TWait;
            }
            SeqState::TWait => {
                self.state.d.next = SeqState::TData;
            }
            SeqState::TData => {
                if !self.ex_masked.val().any() {
                    self.cnt.d.next = self.cnt.q.val() + 1;
                }
                self.i.d.next = self.i.q.val() + 1;
                if (self.i.q.val() + 1) == self.n_part.q.val() {
                    self.state.d.next = SeqState::TCheck;
                } else {
                    self.state.d.next = SeqState::TAddr;
                }
            }
            SeqState::TCheck => {
                if self.cnt.q.val() > (self.n_part.q.val() >> 1) {
                    self.state.d.next = SeqState::TSet;
                } else {
                    self.p.d.next = self.p.q.val() + 1;
                    self.mask.d.next = (self.mask.q.val() << 1) | bits::<48>(1);
                    self.state.d.next = SeqState::TPass;
                }
            }
            SeqState::TSet => {
                self.pre.d.next = 0.into();
                if self.e_tmp.val() > 5 {
                    self.pre.d.next = self.e_tmp.val() - 5;
                }
                self.i.d.next = 0.into();
                self.w_sum.d.next = 0.into();
                self.state.d.next = SeqState::WAddr;
            }
            // ---- Weights.
            SeqState::WAddr => {
                self.cra.d.next = self.i.q.val().get_bits::<8>(0);
                self.state.d.next = SeqState::WWait;
            }
            SeqState::WWait => {
                self.state.d.next = SeqState::WData;
            }
            SeqState::WData => {
                self.sh.d.next = self.ex_now.val() >> self.pre.q.val();
                self.state.d.next = SeqState::WIdx;
            }
            SeqState::WIdx => {
                self.wram.write_enable.next = true;
                self.w_sum.d.next = self.w_sum.q.val() + bit_cast::<24, 16>(self.exp_rom.data.val());
                self.i.d.next = self.i.q.val() + 1;
                if (self.i.q.val() + 1) == self.n_part.q.val() {
                    self.state.d.next = SeqState::BestCheck;
                } else {
                    self.state.d.next = SeqState::WAddr;
                }
            }
            // ---- The best particle.
            SeqState::BestCheck => {
                self.cra.d.next = self.imin.q.val();
                self.pd.d.next = 0.into();
                if self.cmin.q.val() < self.best_cost_r.q.val() {
                    self.state.d.next = SeqState::BestRec;
                } else {
                    self.spread.d.next = false;
                    self.state.d.next = SeqState::SumBegin;
                }
            }
            SeqState::BestRec => {
                // The cost record of `imin` is on the RAM's output from this clock on.
                self.pa.d.next =
                    (bit_cast::<12, 1>(self.half.q.val()) << 11) | (bit_cast::<12, 8>(self.imin.q.val()) << 3);
                self.state.d.next = SeqState::BestAddr;
            }
            SeqState::BestAddr => {
                self.best_cost_r.d.next = self.cram.read_data.val().get_bits::<48>(0);
                self.best_max_r.d.next = self.cram.read_data.val().get_bits::<34>(48);
                self.state.d.next = SeqState::BestWait;
            }
            SeqState::BestWait => {
                self.state.d.next = SeqState::BestData;
            }
            SeqState::BestData => {
                for q in 0..7 {
                    if self.pd.q.val().index() == q {
                        self.best[q].d.next = self.pram.read_data.val();
                    }
                }
                self.pa.d.next = self.pa.q.val() + 1;
                self.pd.d.next = self.pd.q.val() + 1;
                if self.pd.q.val() == 6 {
                    self.pd.d.next = 0.into();
                    self.spread.d.next = false;
                    self.state.d.next = SeqState::SumBegin;
                } else {
                    self.state.d.next = SeqState::BestWait;
                }
            }
            // ---- Estimate (spread = 0) and spread (spread = 1), parameter d.
            SeqState::SumBegin => {
                self.acc.d.next = 0.into();
                self.i.d.next = 0.into();
                self.state.d.next = SeqState::SumAddr;
            }
            SeqState::SumAddr => {
                self.pa.d.next = (bit_cast::<12, 1>(self.half.q.val()) << 11)
                    | (bit_cast::<12, 8>(self.i.q.val().get_bits::<8>(0)) << 3)
                    | bit_cast::<12, 3>(self.pd.q.val());
                self.wra.d.next = self.i.q.val().get_bits::<8>(0);
                self.state.d.next = SeqState::SumWait;
            }
            SeqState::SumWait => {
                self.state.d.next = SeqState::SumData;
            }
            SeqState::SumData => {
                self.x_r.d.next = self.pram.read_data.val();
                self.state.d.next = SeqState::SumMul;
            }
            SeqState::SumMul => {
                // First clock here: start the multiply (x_r is the particle's parameter).
                self.state.d.next = SeqState::SumDiv;
                self.mul_go.next = true;
                self.mul_b_in.next = bit_cast::<18, 16>(self.wram.read_data.val());
                if self.spread.q.val() {
                    self.mul_a_in.next = self.abs26.val();
                } else {
                    self.mul_a_in.next = self.diff26.val();
                }
            }
            SeqState::SumDiv => {
                if !self.mul.busy.val() {
                    self.acc.d.next = self.acc.q.val()
                        + (bit_cast::<48, 44>(self.mul.product.val() ^ self.sign44.val()) - self.sign48_44.val());
                    self.i.d.next = self.i.q.val() + 1;
                    if (self.i.q.val() + 1) == self.n_part.q.val() {
                        self.state.d.next = SeqState::SumDivGo;
                    } else {
                        self.state.d.next = SeqState::SumAddr;
                    }
                }
            }
            SeqState::SumDivGo => {
                self.div_go.next = true;
                self.state.d.next = SeqState::SumDivWait;
            }
            SeqState::SumDivWait => {
                if !self.div.busy.val() {
                    for q in 0..7 {
                        if self.pd.q.val().index() == q {
                            if self.spread.q.val() {
                                self.sigma[q].d.next = self.sig_new.val();
                            } else {
                                self.est[q].d.next = self.est_fix.val();
                            }
                        }
                    }
                    self.pd.d.next = self.pd.q.val() + 1;
                    self.state.d.next = SeqState::SumBegin;
                    if self.pd.q.val() == 6 {
                        self.pd.d.next = 0.into();
                        if self.spread.q.val() {
                            self.state.d.next = SeqState::EstEval;
                        } else {
                            self.spread.d.next = true;
                        }
                    }
                }
            }
            SeqState::EstEval => {
                self.spread.d.next = false;
                for q in 0..7 {
                    self.cur[q].d.next = self.est[q].q.val();
                }
                self.cj.d.next = 0.into();
                self.ret.d.next = SeqState::EvStart;
                self.ret2.d.next = SeqState::EstDone;
                self.state.d.next = SeqState::CorInit;
            }
            SeqState::EstDone => {
                if self.costr.q.val() < self.best_cost_r.q.val() {
                    self.best_cost_r.d.next = self.costr.q.val();
                    self.best_max_r.d.next = self.maxd.q.val();
                    for q in 0..7 {
                        self.best[q].d.next = self.est[q].q.val();
                    }
                }
                self.state.d.next = SeqState::Centre;
            }
            SeqState::Centre => {
                for q in 0..7 {
                    self.centre[q].d.next = self.best[q].q.val();
                }
                self.iter_done.d.next = self.k.q.val() + 1;
                self.state.d.next = SeqState::StopCheck;
            }
            SeqState::StopCheck => {
                if ((self.best_cost_r.q.val() <= self.thr_cost.q.val())
                    && (self.best_max_r.q.val() <= self.thr_max.q.val()))
                    || (self.iter_done.q.val() == self.n_iter.q.val())
                {
                    self.state.d.next = SeqState::Fin;
                } else {
                    self.rng.d.next = self.rng_next.val();
                    self.state.d.next = SeqState::RsBegin;
                }
            }
            // ---- Systematic resampling into the other half.
            SeqState::RsBegin => {
                self.mul_go.next = true;
                self.mul_a_in.next = bit_cast::<26, 24>(self.w_sum.q.val());
                self.mul_b_in.next = bit_cast::<18, 16>(self.u_hi.val());
                self.wra.d.next = 0.into();
                self.i.d.next = 0.into();
                self.j.d.next = 0.into();
                self.rgt.d.next = 0.into();
                self.state.d.next = SeqState::RsL;
            }
            SeqState::RsL => {
                if !self.mul.busy.val() {
                    self.lft.d.next = bit_cast::<50, 44>(self.mul.product.val());
                    self.state.d.next = SeqState::RsWData;
                }
            }
            SeqState::RsWAddr => {
                self.wra.d.next = self.i.q.val().get_bits::<8>(0);
                self.state.d.next = SeqState::RsWWait;
            }
            SeqState::RsWWait => {
                self.state.d.next = SeqState::RsWData;
            }
            SeqState::RsWData => {
                self.mul_go.next = true;
                self.mul_a_in.next = bit_cast::<26, 9>(self.n_part.q.val());
                self.mul_b_in.next = bit_cast::<18, 16>(self.wram.read_data.val());
                self.state.d.next = SeqState::RsWMul;
            }
            SeqState::RsWMul => {
                if !self.mul.busy.val() {
                    self.rgt.d.next = self.rgt.q.val() + (bit_cast::<50, 44>(self.mul.product.val()) << 16);
                    self.state.d.next = SeqState::RsLoop;
                }
            }
            SeqState::RsLoop => {
                if (self.lft.q.val() > self.rgt.q.val()) && ((self.i.q.val() + 1) < self.n_part.q.val()) {
                    self.i.d.next = self.i.q.val() + 1;
                    self.state.d.next = SeqState::RsWAddr;
                } else {
                    self.pd.d.next = 0.into();
                    self.pa.d.next = (bit_cast::<12, 1>(self.half.q.val()) << 11)
                        | (bit_cast::<12, 8>(self.i.q.val().get_bits::<8>(0)) << 3);
                    self.state.d.next = SeqState::CpWait;
                }
            }
            SeqState::CpWait => {
                self.state.d.next = SeqState::CpData;
            }
            SeqState::CpData => {
                self.pram.write_enable.next = true;
                self.pram.write_address.next = (bit_cast::<12, 1>(!self.half.q.val()) << 11)
                    | (bit_cast::<12, 8>(self.j.q.val().get_bits::<8>(0)) << 3)
                    | bit_cast::<12, 3>(self.pd.q.val());
                self.pram.write_data.next = self.pram.read_data.val();
                self.pa.d.next = self.pa.q.val() + 1;
                self.pd.d.next = self.pd.q.val() + 1;
                if self.pd.q.val() == 6 {
                    self.state.d.next = SeqState::CpNext;
                } else {
                    self.state.d.next = SeqState::CpWait;
                }
            }
            SeqState::CpNext => {
                self.lft.d.next = self.lft.q.val() + (bit_cast::<50, 24>(self.w_sum.q.val()) << 16);
                self.j.d.next = self.j.q.val() + 1;
                if (self.j.q.val() + 1) == self.n_part.q.val() {
                    self.state.d.next = SeqState::RsDone;
                } else {
                    self.state.d.next = SeqState::RsLoop;
                }
            }
            SeqState::RsDone => {
                self.half.d.next = !self.half.q.val();
                self.k.d.next = self.k.q.val() + 1;
                self.state.d.next = SeqState::IterBegin;
            }
            SeqState::Fin => {
                for q in 0..7 {
                    self.cur[q].d.next = self.best[q].q.val();
                }
                self.cj.d.next = 0.into();
                self.ret.d.next = SeqState::FinDone;
                self.state.d.next = SeqState::CorInit;
            }
            SeqState::FinDone => {
                self.run_r.d.next = false;
                self.fin_r.d.next = true;
                self.state.d.next = SeqState::Idle;
            }
            _ => {
                self.state.d.next = SeqState::Idle;
            }
        }

        // The multiplier and divider take what the states chose.
        self.mul.go.next = self.mul_go.val();
        self.mul.a.next = self.mul_a_in.val();
        self.mul.b.next = self.mul_b_in.val();
        self.div.go.next = self.div_go.val();
        self.div.n.next = self.div_n_in.val();
        self.div.d.next = self.w_sum.q.val();

        self.p_we.next = self.pram.write_enable.val();
        self.p_waddr.next = self.pram.write_address.val();
        self.p_wdata.next = self.pram.write_data.val();

        if self.reset.val() {
            self.state.d.next = SeqState::Idle;
            self.run_r.d.next = false;
            self.fin_r.d.next = false;
        }
    }
}
