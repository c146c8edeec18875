//! The sequencer's state machine: the states' arms of [`SeqState`] (the second part of the
//! sequencer's kernel; the first, the children's wiring and the signals the arms read, is
//! `sequencer_signals_rtl.rs`), then the multiplier and divider taking what the arms chose,
//! and the reset. The model's step has them in the same order: `sequencer/model/states.rs`,
//! then the end of `sequencer/model.rs`.

use super::*;
use crate::common::rtl::{logic_in_two_parts, KernelPart};

// The kernel in its two parts, in order (one `always` block, `KernelPart`).
logic_in_two_parts!([] PfSequencer);

impl KernelPart<1> for PfSequencer {
    #[hdl_gen]
    fn update(&mut self) {
        match self.state.q.val() {
            SeqState::Idle => {
                if self.go.val() {
                    self.bank.init.next = true;
                    self.rng.d.next = self.seed.q.val();
                    if !self.seed.q.val().any() {
                        self.rng.d.next = bits::<32>(1);
                    }
                    self.run_r.d.next = true;
                    self.fin_r.d.next = false;
                    self.inflight.d.next = false;
                    self.havep.d.next = false;
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
                self.pose_r.d.next =
                    (self.pose_r.q.val() >> 18) | (bit_cast::<216, 18>(self.translation.t.val()) << 198);
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
                // (The cost and the largest distance are taken above, in any state.)
                if self.cost_valid.val() {
                    self.state.d.next = self.ret2.q.val();
                }
            }
            SeqState::StartDone => {
                self.best_cost_r.d.next = self.costr.q.val();
                self.best_max_r.d.next = self.maxd.q.val();
                self.bank.best_from_cur.next = true;
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
                    self.off.d.next = self.propagate.step.val();
                    self.state.d.next = SeqState::PropClamp;
                }
            }
            SeqState::PropClamp => {
                self.off.d.next = self.propagate.clamped.val();
                self.state.d.next = SeqState::PropWrite;
            }
            SeqState::PropWrite => {
                self.pram.write_enable.next = true;
                self.bank.cur_put.next = true;
                self.pa.d.next = self.pa.q.val() + 1;
                self.pd.d.next = self.pd.q.val() + 1;
                if self.pd.q.val() == 6 {
                    self.pd.d.next = 0.into();
                    self.pa.d.next = self.pa.q.val() + 2;
                    self.cj.d.next = 0.into();
                    self.ret.d.next = SeqState::EvSync;
                    self.state.d.next = SeqState::CorInit;
                } else {
                    self.state.d.next = SeqState::PropAddr;
                }
            }
            SeqState::EvSync => {
                if !self.inflight.q.val() {
                    if self.havep.q.val() {
                        self.state.d.next = SeqState::PartStore;
                    } else if self.i.q.val() == self.n_part.q.val() {
                        // The temperature's binary search over p in 0..=48, from the middle.
                        self.lo.d.next = 0.into();
                        self.hi.d.next = bits::<6>(48);
                        self.p.d.next = bits::<6>(24);
                        self.mask.d.next = bits::<48>(0xff_ffff);
                        self.state.d.next = SeqState::TPass;
                    } else {
                        self.state.d.next = SeqState::EvLaunch;
                    }
                }
            }
            SeqState::EvLaunch => {
                if self.nn_ready.val() {
                    self.start_r.d.next = true;
                    self.maxd.d.next = 0.into();
                    self.inflight.d.next = true;
                    self.havep.d.next = true;
                    self.ie.d.next = self.i.q.val();
                    self.i.d.next = self.i.q.val() + 1;
                    if (self.i.q.val() + 1) == self.n_part.q.val() {
                        self.state.d.next = SeqState::EvSync;
                    } else {
                        self.state.d.next = SeqState::PropAddr;
                    }
                }
            }
            SeqState::PartStore => {
                self.cram.write_enable.next = true;
                self.cram.write_address.next = self.ie.q.val().get_bits::<8>(0);
                if self.costr.q.val() < self.cmin.q.val() {
                    self.cmin.d.next = self.costr.q.val();
                    self.imin.d.next = self.ie.q.val().get_bits::<8>(0);
                }
                self.havep.d.next = false;
                self.state.d.next = SeqState::EvSync;
            }
            // ---- Temperature: the bit length of the excess of rank n / 2.
            SeqState::TPass => {
                self.i.d.next = 0.into();
                self.cnt.d.next = 0.into();
                self.sq.d.next = 0.into();
                self.state.d.next = SeqState::TRun;
            }
            SeqState::TRun => {
                // Streamed: address cost `i` while there is one; count the cost addressed two
                // clocks ago (`sq` bit 1); done when the last is counted.
                self.sq.d.next = (self.sq.q.val() << 1) & bits::<3>(2);
                if self.i.q.val() != self.n_part.q.val() {
                    self.cra.d.next = self.i.q.val().get_bits::<8>(0);
                    self.i.d.next = self.i.q.val() + 1;
                    self.sq.d.next = ((self.sq.q.val() << 1) & bits::<3>(2)) | bits::<3>(1);
                } else if !self.sq.q.val().get_bit(0) {
                    self.state.d.next = SeqState::TCheck;
                }
                if self.sq.q.val().get_bit(1) && !self.ex_masked.val().any() {
                    self.cnt.d.next = self.cnt.q.val() + 1;
                }
            }
            SeqState::TCheck => {
                // More than half the excesses below 2^p: the bit length is at most p (the
                // count grows with p, so a binary search finds the linear search's p).
                if self.cnt.q.val() > (self.n_part.q.val() >> 1) {
                    self.hi.d.next = self.p.q.val();
                } else {
                    self.lo.d.next = self.p.q.val() + 1;
                }
                self.state.d.next = SeqState::TMid;
            }
            SeqState::TMid => {
                if self.lo.q.val() == self.hi.q.val() {
                    self.p.d.next = self.lo.q.val();
                    self.state.d.next = SeqState::TSet;
                } else {
                    self.p.d.next = self.t_mid.val();
                    self.mask.d.next = !(self.all48.val() << self.t_mid.val());
                    self.state.d.next = SeqState::TPass;
                }
            }
            SeqState::TSet => {
                self.weight.temper.next = true;
                self.i.d.next = 0.into();
                self.cnt.d.next = 0.into();
                self.sq.d.next = 0.into();
                self.w_sum.d.next = 0.into();
                self.state.d.next = SeqState::WRun;
            }
            // ---- Weights, streamed: address cost `i` while there is one; shift the excess
            // addressed two clocks ago (`sq` bit 1); store and sum the weight of the one before
            // (bit 2) at `cnt`; done when the last is stored.
            SeqState::WRun => {
                self.sq.d.next = self.sq.q.val() << 1;
                if self.i.q.val() != self.n_part.q.val() {
                    self.cra.d.next = self.i.q.val().get_bits::<8>(0);
                    self.i.d.next = self.i.q.val() + 1;
                    self.sq.d.next = (self.sq.q.val() << 1) | bits::<3>(1);
                } else if !self.sq.q.val().get_bit(0) && !self.sq.q.val().get_bit(1) {
                    self.state.d.next = SeqState::BestCheck;
                }
                if self.sq.q.val().get_bit(1) {
                    self.weight.latch.next = true;
                }
                if self.sq.q.val().get_bit(2) {
                    self.wram.write_enable.next = true;
                    self.wram.write_address.next = self.cnt.q.val().get_bits::<8>(0);
                    self.w_sum.d.next = self.w_sum.q.val() + bit_cast::<24, 16>(self.weight.value.val());
                    self.cnt.d.next = self.cnt.q.val() + 1;
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
                // Parameter 0 is being read; address the next (one parameter a clock).
                self.pa.d.next = self.pa.q.val() + 1;
                self.state.d.next = SeqState::BestData;
            }
            SeqState::BestData => {
                self.bank.best_put.next = true;
                self.bank.data.next = self.pram.read_data.val();
                self.pa.d.next = self.pa.q.val() + 1;
                self.pd.d.next = self.pd.q.val() + 1;
                if self.pd.q.val() == 6 {
                    self.pd.d.next = 0.into();
                    self.spread.d.next = false;
                    self.state.d.next = SeqState::SumBegin;
                }
            }
            // ---- Estimate (spread = 0) and spread (spread = 1), parameter d.
            SeqState::SumBegin => {
                self.acc.d.next = 0.into();
                self.i.d.next = 0.into();
                self.sq.d.next = 0.into();
                self.state.d.next = SeqState::SumRun;
            }
            SeqState::SumRun => {
                // Streamed, a particle a clock: address particle `i` while there is one (`sq`
                // bit 0); its parameter and weight are on the RAMs' outputs a clock later (bit
                // 1) and taken into `x_r` and `w_r`; a clock later (bit 2) their product is
                // started; the multiplier's `valid` marks each product to add. Done when the
                // last is added.
                self.sq.d.next = self.sq.q.val() << 1;
                if self.i.q.val() != self.n_part.q.val() {
                    self.pa.d.next = (bit_cast::<12, 1>(self.half.q.val()) << 11)
                        | (bit_cast::<12, 8>(self.i.q.val().get_bits::<8>(0)) << 3)
                        | bit_cast::<12, 3>(self.pd.q.val());
                    self.wra.d.next = self.i.q.val().get_bits::<8>(0);
                    self.i.d.next = self.i.q.val() + 1;
                    self.sq.d.next = (self.sq.q.val() << 1) | bits::<3>(1);
                } else if !self.sq.q.val().any() && !self.mul.busy.val() {
                    self.state.d.next = SeqState::SumDivGo;
                }
                self.x_r.d.next = self.pram.read_data.val();
                self.w_r.d.next = self.wram.read_data.val();
                if self.sq.q.val().get_bit(2) {
                    self.mul_go.next = true;
                    self.mul_b_in.next = bit_cast::<18, 16>(self.w_r.q.val());
                    if self.spread.q.val() {
                        self.mul_a_in.next = self.propagate.abs_diff.val();
                    } else {
                        self.mul_a_in.next = self.propagate.diff.val();
                    }
                }
                if self.mul.valid.val() {
                    self.acc.d.next = self.acc.q.val()
                        + (bit_cast::<48, 44>(self.mul.product.val() ^ self.sign44.val()) - self.sign48_44.val());
                }
            }
            SeqState::SumDivGo => {
                self.div_go.next = true;
                self.state.d.next = SeqState::SumDivWait;
            }
            SeqState::SumDivWait => {
                if !self.div.busy.val() {
                    if self.spread.q.val() {
                        self.bank.sigma_put.next = true;
                    } else {
                        self.bank.est_put.next = true;
                        self.bank.data.next = self.estimate.value.val();
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
                self.bank.cur_from_est.next = true;
                self.cj.d.next = 0.into();
                self.ret.d.next = SeqState::EvStart;
                self.ret2.d.next = SeqState::EstDone;
                self.state.d.next = SeqState::CorInit;
            }
            SeqState::EstDone => {
                if self.costr.q.val() < self.best_cost_r.q.val() {
                    self.best_cost_r.d.next = self.costr.q.val();
                    self.best_max_r.d.next = self.maxd.q.val();
                    self.bank.best_from_est.next = true;
                }
                self.state.d.next = SeqState::Centre;
            }
            SeqState::Centre => {
                self.bank.centre_from_best.next = true;
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
                self.resample.clear.next = true;
                self.state.d.next = SeqState::RsL;
            }
            SeqState::RsL => {
                if !self.mul.busy.val() {
                    self.resample.set_pointer.next = true;
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
                    self.resample.add_weight.next = true;
                    self.state.d.next = SeqState::RsLoop;
                }
            }
            SeqState::RsLoop => {
                if self.resample.beyond.val() && ((self.i.q.val() + 1) < self.n_part.q.val()) {
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
                // Parameter 0 is being read; address the next (one parameter a clock).
                self.pa.d.next = self.pa.q.val() + 1;
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
                    self.state.d.next = SeqState::CpData;
                }
            }
            SeqState::CpNext => {
                self.resample.advance.next = true;
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
                self.bank.cur_from_best.next = true;
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

        // The multiplier and divider take what the states chose; the multiplier is lent
        // out while no run is in progress.
        self.mul.go.next = self.mul_go.val();
        self.mul.a.next = self.mul_a_in.val();
        self.mul.b.next = self.mul_b_in.val();
        if !self.run_r.q.val() {
            self.mul.go.next = self.ext_go.val();
            self.mul.a.next = self.ext_a.val();
            self.mul.b.next = self.ext_b.val();
        }
        self.mul_product.next = self.mul.product.val();
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
