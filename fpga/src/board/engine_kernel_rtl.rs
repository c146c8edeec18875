//! The command engine's state machine: the states' arms of [`EngState`] (the second part of
//! the engine's kernel; the first, the children's wiring and the defaults, is
//! `engine_signals_rtl.rs`), then what overrides them (a pass's or the sequencer's launch of
//! the pipeline, the reset).

use super::*;
use crate::common::rtl::{logic_in_two_parts, KernelPart};

// The kernel in its two parts, in order (one `always` block, `KernelPart`).
logic_in_two_parts!([const P: usize] CommandEngine<P>);

impl<const P: usize> KernelPart<1> for CommandEngine<P> {
    #[hdl_gen]
    fn update(&mut self) {
        match self.state.q.val() {
            EngState::Idle => {
                self.eval_mode.d.next = false;
                if self.pending.q.val() {
                    self.pending.d.next = false;
                    self.e_code.d.next = self.e_busy.val();
                    self.e_cmd.d.next = self.p_cmd.q.val();
                    self.e_seq.d.next = self.p_seq.q.val();
                    self.state.d.next = EngState::ErrHeader;
                } else if self.frame.val() {
                    if self.busy_seen.val() {
                        if self.status.val() == 0 {
                            self.e_code.d.next = self.e_busy.val();
                            self.e_cmd.d.next = self.cmd.val();
                            self.e_seq.d.next = self.seq.val();
                            self.state.d.next = EngState::ErrHeader;
                        }
                    } else if self.status.val() != 0 {
                        self.e_code.d.next = bit_cast::<8, 3>(self.status.val());
                        self.e_cmd.d.next = 0.into();
                        self.e_seq.d.next = 0.into();
                        self.state.d.next = EngState::ErrHeader;
                    } else {
                        self.cur_cmd.d.next = self.cmd.val();
                        self.cur_seq.d.next = self.seq.val();
                        self.dlen.d.next = self.len.val() - self.a_overhead.val();
                        self.faddr.d.next = self.a_body.val();
                        self.fcount.d.next = self.n_head_fetch.val();
                        self.ret.d.next = EngState::Decode;
                        self.state.d.next = EngState::FetchAddr;
                    }
                }
            }
            EngState::FetchAddr => {
                self.faddr.d.next = self.faddr.q.val() + 1;
                self.state.d.next = EngState::FetchData;
            }
            EngState::FetchData => {
                // A LoadModel's or LoadTable's data bytes go into the model digest.
                if (self.ret.q.val() == EngState::LoadWrite) && !self.cur_cmd.q.val().get_bit(0) {
                    self.model_digest.feed.next = true;
                }
                self.inbuf.d.next =
                    (self.inbuf.q.val() >> 8) | (bit_cast::<216, 8>(self.frame_buf.read_data.val()) << 208);
                self.fcount.d.next = self.fcount.q.val() - 1;
                if self.fcount.q.val() == 1 {
                    self.state.d.next = self.ret.q.val();
                } else {
                    self.state.d.next = EngState::FetchAddr;
                }
            }
            EngState::Emit => {
                if self.sender.ready.val() {
                    self.sender.put.next = true;
                    self.outbuf.d.next = self.outbuf.q.val() >> 8;
                    self.ecount.d.next = self.ecount.q.val() - 1;
                    if self.ecount.q.val() == 1 {
                        self.state.d.next = self.ret.q.val();
                    }
                }
            }
            EngState::Header => {
                self.sender.open.next = true;
                self.err_led.d.next = false;
                self.outbuf.d.next = bit_cast::<216, 8>(self.cur_cmd.q.val() | bits::<8>(128))
                    | (bit_cast::<216, 8>(self.cur_seq.q.val()) << 8);
                self.ecount.d.next = self.n_header.val();
                self.state.d.next = EngState::Emit;
            }
            EngState::ErrHeader => {
                self.sender.open.next = true;
                self.err_led.d.next = true;
                self.outbuf.d.next = bits::<216>(255)
                    | (bit_cast::<216, 8>(self.e_seq.q.val()) << 8)
                    | (bit_cast::<216, 8>(self.e_code.q.val()) << 16)
                    | (bit_cast::<216, 8>(self.e_cmd.q.val()) << 24);
                self.ecount.d.next = self.n_error.val();
                self.ret.d.next = EngState::Send;
                self.state.d.next = EngState::Emit;
            }
            EngState::Send => {
                if self.sender.ready.val() {
                    self.sender.send.next = true;
                    self.state.d.next = EngState::SendWait;
                }
            }
            EngState::SendWait => {
                if !self.sender.busy.val() {
                    self.state.d.next = EngState::Idle;
                }
            }
            EngState::Decode => {
                self.state.d.next = EngState::Check;
            }
            EngState::Check => {
                self.state.d.next = EngState::Dispatch;
            }
            EngState::Dispatch => {
                self.hdr.d.next = self.h.val();
                self.e_cmd.d.next = self.cur_cmd.q.val();
                self.e_seq.d.next = self.cur_seq.q.val();
                self.state.d.next = EngState::ErrHeader;
                if self.running_l.val() && self.check.busy_class.val() {
                    self.e_code.d.next = self.e_busy.val();
                } else if self.check.code.val().any() {
                    self.e_code.d.next = self.check.code.val();
                } else if self.check.is_result.val() && !(self.filter.finished.val() && self.polish.done.val()) {
                    self.e_code.d.next = self.e_no_result.val();
                } else if self.check.is_identify.val() {
                    self.ret.d.next = EngState::IdBody;
                    self.state.d.next = EngState::Header;
                } else if self.check.is_load.val() {
                    self.idx.d.next = 0.into();
                    self.waddr.d.next = self.h_lo.val().get_bits::<13>(0);
                    self.faddr.d.next = self.a_load.val();
                    if self.cur_cmd.q.val().get_bit(0) {
                        self.state.d.next = EngState::LoadNext;
                    } else {
                        // LoadModel or LoadTable: the header into the digest first.
                        self.dig_sr.d.next = self.h.val().get_bits::<32>(0);
                        self.dig_restart.d.next = !self.cur_cmd.q.val().get_bit(3) && !self.h_lo.val().any();
                        self.wi.d.next = 0.into();
                        self.state.d.next = EngState::DigHead;
                    }
                } else if self.check.is_sizes.val() {
                    self.model_count.d.next = self.h_lo.val().get_bits::<13>(0);
                    self.scan_count.d.next = self.h_hi.val().get_bits::<13>(0);
                    self.ret.d.next = EngState::EchoBody;
                    self.state.d.next = EngState::Header;
                } else if self.check.is_evaluate.val() {
                    self.ret.d.next = EngState::EvBegin;
                    self.state.d.next = EngState::Header;
                } else if self.check.is_nearest.val() {
                    self.faddr.d.next = self.a_nearest.val();
                    self.fcount.d.next = self.n_pose.val();
                    self.ret.d.next = EngState::NrRun;
                    self.state.d.next = EngState::FetchAddr;
                } else if self.check.is_run.val() {
                    // The polish word first: its points are checked before anything is kept.
                    self.faddr.d.next = self.a_polish.val();
                    self.fcount.d.next = self.n_word.val();
                    self.ret.d.next = EngState::RunPolish;
                    self.state.d.next = EngState::FetchAddr;
                } else if self.check.is_status.val() {
                    self.ret.d.next = EngState::StBody;
                    self.state.d.next = EngState::Header;
                } else if self.check.is_result.val() {
                    self.ret.d.next = EngState::ResBody1;
                    self.state.d.next = EngState::Header;
                }
            }
            EngState::RunPolish => {
                if !self.pw_count.val().any() || (self.pw_count.val() > self.max_points16.val()) {
                    self.e_code.d.next = self.e_capacity.val();
                    self.state.d.next = EngState::ErrHeader;
                } else {
                    self.pol_count.d.next = self.pw_count.val().get_bits::<13>(0);
                    self.pol_steps.d.next = self.inbuf.q.val().get_bits::<4>(184);
                    self.pol_more.d.next = self.inbuf.q.val().get_bits::<4>(192);
                    self.pol_held.d.next = self.inbuf.q.val().get_bit(200);
                    self.pol_starts.d.next = self.hdr.q.val().get_bits::<4>(40);
                    if !self.hdr.q.val().get_bits::<4>(40).any() {
                        self.pol_starts.d.next = 1.into();
                    }
                    self.hcnt.d.next = 0.into();
                    self.idx.d.next = 0.into();
                    self.faddr.d.next = self.a_run.val();
                    self.state.d.next = EngState::RunNext;
                }
            }
            EngState::RunNext => {
                if self.idx.q.val() == 24 {
                    self.faddr.d.next = self.a_hyp.val();
                    self.state.d.next = EngState::RunHyp;
                } else {
                    self.fcount.d.next = self.n_word.val();
                    self.ret.d.next = EngState::RunWrite;
                    self.state.d.next = EngState::FetchAddr;
                }
            }
            EngState::RunHyp => {
                if (bit_cast::<5, 4>(self.hcnt.q.val()) + 1) == bit_cast::<5, 4>(self.pol_starts.q.val()) {
                    self.filter.cfg_we.next = true;
                    self.filter.cfg_data.next = self.hdr.q.val();
                    self.state.d.next = EngState::RunGo;
                } else {
                    self.fcount.d.next = self.n_pose.val();
                    self.ret.d.next = EngState::RunHypWrite;
                    self.state.d.next = EngState::FetchAddr;
                }
            }
            EngState::RunHypWrite => {
                self.hyps.write_enable.next = true;
                self.hcnt.d.next = self.hcnt.q.val() + 1;
                self.state.d.next = EngState::RunHyp;
            }
            EngState::RunWrite => {
                self.filter.cfg_we.next = true;
                self.idx.d.next = self.idx.q.val() + 1;
                self.state.d.next = EngState::RunNext;
            }
            EngState::RunGo => {
                self.filter.go.next = true;
                self.pol_arm.d.next = true;
                self.ret.d.next = EngState::EchoBody;
                self.state.d.next = EngState::Header;
            }
            EngState::StBody => {
                if self.running_l.val() {
                    self.outbuf.d.next = bits::<216>(1)
                        | (bit_cast::<216, 16>(self.filter.iterations.val()) << 8)
                        | (bit_cast::<216, 48>(self.filter.best_cost.val()) << 24);
                } else if self.polish.done.val() {
                    self.outbuf.d.next = bits::<216>(2)
                        | (bit_cast::<216, 16>(self.filter.iterations.val()) << 8)
                        | (bit_cast::<216, 48>(self.filter.best_cost.val()) << 24);
                } else {
                    self.outbuf.d.next = bit_cast::<216, 48>(self.all48.val()) << 24;
                }
                self.ecount.d.next = self.n_status.val();
                self.ret.d.next = EngState::Send;
                self.state.d.next = EngState::Emit;
            }
            EngState::ResBody1 => {
                self.outbuf.d.next = bit_cast::<216, 16>(self.filter.iterations.val())
                    | (bit_cast::<216, 48>(self.filter.best_cost.val()) << 16)
                    | (bit_cast::<216, 34>(self.filter.best_max.val()) << 64);
                self.ecount.d.next = self.n_result_head.val();
                self.ret.d.next = EngState::ResBody2;
                self.state.d.next = EngState::Emit;
            }
            EngState::ResBody2 => {
                self.outbuf.d.next = bit_cast::<216, 168>(self.filter.params.val());
                self.ecount.d.next = self.n_result_params.val();
                self.ret.d.next = EngState::ResBody3;
                self.state.d.next = EngState::Emit;
            }
            EngState::ResBody3 => {
                self.outbuf.d.next = self.filter.pose.val();
                self.ecount.d.next = self.n_pose.val();
                self.ret.d.next = EngState::ResBody4;
                self.state.d.next = EngState::Emit;
            }
            EngState::ResBody4 => {
                self.outbuf.d.next = bit_cast::<216, 4>(self.polish.best_index.val())
                    | (bit_cast::<216, 48>(self.polish.best_cost.val()) << 8);
                self.ecount.d.next = self.n_polish_head.val();
                self.ret.d.next = EngState::ResBody5;
                self.state.d.next = EngState::Emit;
            }
            EngState::ResBody5 => {
                self.outbuf.d.next = self.polish.pose.val();
                self.ecount.d.next = self.n_pose.val();
                self.ret.d.next = EngState::Send;
                self.state.d.next = EngState::Emit;
            }
            EngState::DigHead => {
                self.model_digest.restart.next = self.dig_restart.q.val();
                self.model_digest.feed.next = true;
                self.model_digest.data_in.next = self.dig_sr.q.val().get_bits::<8>(0);
                self.dig_restart.d.next = false;
                self.dig_sr.d.next = self.dig_sr.q.val() >> 8;
                self.wi.d.next = self.wi.q.val() + 1;
                if self.wi.q.val() == 3 {
                    self.state.d.next = EngState::LoadNext;
                }
            }
            EngState::IdDigest => {
                self.outbuf.d.next = bit_cast::<216, 32>(self.model_digest.digest.val());
                self.ecount.d.next = self.n_digest.val();
                self.ret.d.next = EngState::Send;
                self.state.d.next = EngState::Emit;
            }
            EngState::IdBody => {
                self.outbuf.d.next = self.ident.val()
                    | (bit_cast::<216, 13>(self.model_count.q.val()) << 160)
                    | (bit_cast::<216, 13>(self.scan_count.q.val()) << 176)
                    | (bit_cast::<216, 9>(self.ws.count.val()) << 192);
                self.ecount.d.next = self.n_identity.val();
                self.ret.d.next = EngState::IdDigest;
                self.state.d.next = EngState::Emit;
            }
            EngState::LoadNext => {
                if self.idx.q.val() == self.hdr.q.val().get_bits::<16>(16) {
                    self.ret.d.next = EngState::EchoBody;
                    self.state.d.next = EngState::Header;
                } else {
                    if self.cur_cmd.q.val().get_bit(3) {
                        self.fcount.d.next = self.n_entry.val();
                    } else {
                        self.fcount.d.next = self.n_point.val();
                    }
                    self.ret.d.next = EngState::LoadWrite;
                    self.state.d.next = EngState::FetchAddr;
                }
            }
            EngState::LoadWrite => {
                if self.cur_cmd.q.val().get_bit(3) {
                    self.nn.table_we.next = true;
                } else if self.cur_cmd.q.val().get_bit(0) {
                    self.scan_store.write_enable.next = true;
                } else if self.waddr.q.val().get_bit(12) {
                    self.surf.normal_we.next = true;
                } else {
                    self.nn.model_we.next = true;
                    self.surf.point_we.next = true;
                }
                self.waddr.d.next = self.waddr.q.val() + 1;
                self.idx.d.next = self.idx.q.val() + 1;
                self.state.d.next = EngState::LoadNext;
            }
            EngState::EchoBody => {
                self.outbuf.d.next = bit_cast::<216, 32>(self.hdr.q.val().get_bits::<32>(0));
                self.ecount.d.next = self.n_echo.val();
                self.ret.d.next = EngState::Send;
                self.state.d.next = EngState::Emit;
            }
            EngState::EvBegin => {
                if !self.ws.busy.val() {
                    if self.hdr.q.val().get_bit(0) {
                        self.ws.clear.next = true;
                    }
                    self.idx.d.next = 0.into();
                    self.faddr.d.next = self.a_eval.val();
                    self.eval_mode.d.next = true;
                    self.state.d.next = EngState::EvNext;
                }
            }
            EngState::EvNext => {
                if self.idx.q.val() == bit_cast::<16, 8>(self.hdr.q.val().get_bits::<8>(40)) {
                    self.state.d.next = EngState::EvDone;
                } else {
                    self.fcount.d.next = self.n_pose.val();
                    self.ret.d.next = EngState::EvRun;
                    self.state.d.next = EngState::FetchAddr;
                }
            }
            EngState::EvRun => {
                if !self.nn.busy.val() && !self.feeder.streaming.val() {
                    self.start_r.d.next = true;
                    self.feeder.launch.next = true;
                    self.state.d.next = EngState::EvWait;
                }
            }
            EngState::EvWait => {
                if self.surf.cost_valid.val() {
                    self.outbuf.d.next = bit_cast::<216, 48>(self.surf.cost.val());
                    self.ecount.d.next = self.n_cost.val();
                    self.ret.d.next = EngState::EvInc;
                    self.state.d.next = EngState::Emit;
                }
            }
            EngState::EvInc => {
                self.idx.d.next = self.idx.q.val() + 1;
                self.state.d.next = EngState::EvNext;
            }
            EngState::EvDone => {
                self.eval_mode.d.next = false;
                if !self.hdr.q.val().get_bit(1) {
                    self.state.d.next = EngState::Send;
                } else if !self.ws.busy.val() {
                    self.ws.weigh.next = true;
                    self.state.d.next = EngState::WeighWait;
                }
            }
            EngState::WeighWait => {
                self.aux.write_address.next = self.ws.w_index.val();
                self.aux.write_data.next = bit_cast::<46, 16>(self.ws.weight.val());
                self.aux.write_enable.next = self.ws.w_valid.val();
                if self.ws.w_done.val() {
                    self.state.d.next = EngState::SumEmit;
                }
            }
            EngState::SumEmit => {
                self.outbuf.d.next = bit_cast::<216, 9>(self.ws.count.val())
                    | (bit_cast::<216, 48>(self.ws.min_cost.val()) << 16)
                    | (bit_cast::<216, 24>(self.ws.w_sum.val()) << 64);
                self.ecount.d.next = self.n_summary.val();
                self.wi.d.next = 0.into();
                self.ret.d.next = EngState::WLoop;
                self.state.d.next = EngState::Emit;
            }
            EngState::WLoop => {
                if self.wi.q.val() == self.ws.count.val() {
                    self.state.d.next = EngState::Send;
                } else {
                    self.state.d.next = EngState::WRead;
                }
            }
            EngState::WRead => {
                self.outbuf.d.next = bit_cast::<216, 16>(self.aux.read_data.val().get_bits::<16>(0));
                self.ecount.d.next = self.n_weight.val();
                self.wi.d.next = self.wi.q.val() + 1;
                self.ret.d.next = EngState::WLoop;
                self.state.d.next = EngState::Emit;
            }
            EngState::NrRun => {
                if !self.nn.busy.val() && !self.feeder.streaming.val() {
                    self.start_r.d.next = true;
                    self.feeder.launch.next = true;
                    self.feeder.from_index.next = self.hdr.q.val().get_bits::<13>(0);
                    self.feeder.to_index.next = self.hdr_end.val();
                    self.wi.d.next = 0.into();
                    self.state.d.next = EngState::NrWait;
                }
            }
            EngState::NrWait => {
                if self.surf.nn_valid.val() {
                    self.aux.write_enable.next = true;
                    self.wi.d.next = self.wi.q.val() + 1;
                }
                if self.surf.cost_valid.val() {
                    self.ncost.d.next = self.surf.cost.val();
                    self.ret.d.next = EngState::NrHead;
                    self.state.d.next = EngState::Header;
                }
            }
            EngState::NrHead => {
                self.outbuf.d.next = bit_cast::<216, 32>(self.hdr.q.val().get_bits::<32>(0))
                    | (bit_cast::<216, 48>(self.ncost.q.val()) << 32);
                self.ecount.d.next = self.n_nearest_head.val();
                self.wi.d.next = 0.into();
                self.ret.d.next = EngState::NrLoop;
                self.state.d.next = EngState::Emit;
            }
            EngState::NrLoop => {
                if bit_cast::<16, 9>(self.wi.q.val()) == self.hdr.q.val().get_bits::<16>(16) {
                    self.state.d.next = EngState::Send;
                } else {
                    self.state.d.next = EngState::NrRead;
                }
            }
            EngState::NrRead => {
                self.outbuf.d.next = bit_cast::<216, 12>(self.aux.read_data.val().get_bits::<12>(0))
                    | (bit_cast::<216, 34>(self.aux.read_data.val().get_bits::<34>(12)) << 16);
                self.ecount.d.next = self.n_nearest_result.val();
                self.wi.d.next = self.wi.q.val() + 1;
                self.ret.d.next = EngState::NrLoop;
                self.state.d.next = EngState::Emit;
            }
            _ => {
                self.state.d.next = EngState::Idle;
            }
        }

        // A pass of the polish starts the pipeline on the unit's pose and its points.
        if self.pass_req.q.val() && !self.nn.busy.val() && !self.feeder.streaming.val() && !self.start_r.q.val() {
            self.pass_req.d.next = false;
            self.pol_pass.d.next = true;
            self.outst.d.next = 0.into();
            self.start_r.d.next = true;
            self.feeder.launch.next = true;
            self.feeder.from_index.next = 0.into();
            self.feeder.to_index.next = self.pol_count.q.val();
        }
        // The sequencer starts the pipeline on its pose and the whole scan store.
        if self.filter.start.val() {
            self.start_r.d.next = true;
            self.feeder.launch.next = true;
            self.feeder.from_index.next = 0.into();
            self.feeder.to_index.next = self.scan_count.q.val();
        }

        if self.reset.val() {
            self.state.d.next = EngState::Idle;
            self.pending.d.next = false;
            self.eval_mode.d.next = false;
            self.pol_arm.d.next = false;
            self.pol_ready.d.next = false;
            self.pass_req.d.next = false;
            self.pol_pass.d.next = false;
            self.pc_seen.d.next = false;
            self.occ.d.next = 0.into();
        }
    }
}
