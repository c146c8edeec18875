//! The command engine's state machine: one `update` over the states of [`EngState`].

use super::*;

// A literal in the kernel (`#[hdl_gen]` takes no paths): the credits.
const _: () = assert!(super::super::pass_queue_rtl::PASS_QUEUE == 8);

impl<const P: usize> Logic for CommandEngine<P> {
    #[hdl_gen]
    fn update(&mut self) {
        dff_setup!(self, clock, state, ret, dlen, cur_cmd, cur_seq, e_code, e_cmd, e_seq, pending, p_cmd, p_seq);
        dff_setup!(self, clock, err_led, faddr, fcount, inbuf, outbuf, ecount, hdr, model_count, scan_count, idx);
        dff_setup!(self, clock, waddr, eval_mode, start_r, wi, ncost, dig_sr, dig_restart);
        dff_setup!(self, clock, pol_count, pol_steps, pol_more, pol_held, pol_starts, hcnt, pol_arm, pol_ready, run_r);
        self.hyps.read_clock.next = self.clock.val();
        self.hyps.write_clock.next = self.clock.val();
        self.hyps.write_enable.next = false;
        self.hyps.write_address.next = self.hcnt.q.val() + 1;
        self.hyps.write_data.next = self.inbuf.q.val();
        self.hyps.read_address.next = self.polish.start_index.val();
        dff_setup!(self, clock, pass_req, pol_pass, outst, occ, pc_seen, pc_cost, quiet);
        self.found.clock.next = self.clock.val();
        self.polish.clock.next = self.clock.val();
        self.model_digest.clock.next = self.clock.val();
        self.nn.clock.next = self.clock.val();
        self.surf.clock.next = self.clock.val();
        self.ws.clock.next = self.clock.val();
        self.filter.clock.next = self.clock.val();
        self.sender.clock.next = self.clock.val();
        self.frame_buf.read_clock.next = self.clock.val();
        self.frame_buf.write_clock.next = self.clock.val();
        self.scan_store.read_clock.next = self.clock.val();
        self.scan_store.write_clock.next = self.clock.val();
        self.aux.read_clock.next = self.clock.val();
        self.aux.write_clock.next = self.clock.val();

        // Outputs.
        self.busy.next = self.state.q.val() != EngState::Idle;
        self.error.next = self.err_led.q.val();
        self.running_l.next = self.filter.running.val() || self.pol_arm.q.val() || self.polish.busy.val();
        self.running.next = self.running_l.val();
        self.tx.next = self.sender.tx.val();
        self.sender.reset.next = self.reset.val();

        // The frame buffer: written by the receiver, read at `faddr`.
        self.frame_buf.write_enable.next = self.fr_we.val();
        self.frame_buf.write_address.next = self.fr_waddr.val();
        self.frame_buf.write_data.next = self.fr_wdata.val();
        self.frame_buf.read_address.next = self.faddr.q.val();

        // Header fields of the current command (after the six-byte fetch).
        self.h.next = self.inbuf.q.val().get_bits::<48>(168);
        self.h_lo.next = self.h.val().get_bits::<16>(0);
        self.h_hi.next = self.h.val().get_bits::<16>(16);
        self.h_n.next = self.h.val().get_bits::<8>(40);
        // first + count of a Nearest (checked to be at most the scan count, so 13 bits).
        self.hdr_end.next = self.hdr.q.val().get_bits::<13>(0) + self.hdr.q.val().get_bits::<13>(16);
        self.pw_count.next = self.inbuf.q.val().get_bits::<16>(168);
        self.sizes_unset.next = !self.model_count.q.val().any() || !self.scan_count.q.val().any();

        // The request's checks (the codes and limits are the protocol's, as constants).
        self.check.cmd.next = self.cur_cmd.q.val();
        self.check.dlen.next = self.dlen.q.val();
        self.check.lo.next = self.h_lo.val();
        self.check.hi.next = self.h_hi.val();
        self.check.n.next = self.h_n.val();
        self.check.clock.next = self.clock.val();
        self.check.ws_count.next = self.ws.count.val();
        self.check.scan_count.next = self.scan_count.q.val();
        self.check.sizes_unset.next = self.sizes_unset.val();

        // The scan stream: launched by the states below or the sequencer's start.
        self.feeder.clock.next = self.clock.val();
        self.feeder.launch.next = false;
        self.feeder.from_index.next = 0.into();
        self.feeder.to_index.next = self.scan_count.q.val();
        self.feeder.ready.next = self.nn.scan_ready.val();
        // During a pass on credit: a point in only while the points in the pipeline and in
        // the queue are fewer than its entries.
        self.feeder.hold.next = self.pol_pass.q.val() && ((self.outst.q.val() + self.occ.q.val()) >= 8);
        self.feeder.read_data.next = self.scan_store.read_data.val();
        self.scan_store.read_address.next = self.feeder.read_address.val();
        self.nn.scan_valid.next = self.feeder.valid.val();
        self.nn.scan_data.next = self.feeder.data.val();
        self.nn.scan_last.next = self.feeder.last.val();

        // Defaults.
        self.model_digest.restart.next = false;
        self.model_digest.feed.next = false;
        self.model_digest.data_in.next = self.frame_buf.read_data.val();
        self.sender.open.next = false;
        self.sender.put.next = false;
        self.sender.put_data.next = self.outbuf.q.val().get_bits::<8>(0);
        self.sender.send.next = false;
        self.nn.model_we.next = false;
        self.nn.model_waddr.next = self.waddr.q.val().get_bits::<12>(0);
        self.nn.model_wdata.next = self.inbuf.q.val().get_bits::<48>(168);
        // The residual stage: written beside the pipeline's model store (LoadModel's words below
        // messages::NORMALS_OFFSET are points, from it normals: address bit 12), fed by the
        // pipeline's results; everything downstream takes its results and costs.
        self.surf.point_we.next = false;
        self.surf.point_waddr.next = self.waddr.q.val().get_bits::<12>(0);
        self.surf.point_wdata.next = self.inbuf.q.val().get_bits::<48>(168);
        self.surf.normal_we.next = false;
        self.surf.normal_waddr.next = self.waddr.q.val().get_bits::<12>(0);
        self.surf.normal_wdata.next = self.inbuf.q.val().get_bits::<48>(168);
        self.surf.in_valid.next = self.nn.nn_valid.val();
        self.surf.in_index.next = self.nn.nn_index.val();
        self.surf.in_dist.next = self.nn.nn_dist.val();
        self.surf.in_point.next = self.nn.nn_point.val();
        self.surf.in_cost_valid.next = self.nn.cost_valid.val();
        self.nn.table_we.next = false;
        self.nn.table_waddr.next = self.waddr.q.val();
        self.nn.table_wdata.next = self.inbuf.q.val().get_bits::<13>(200);
        self.nn.start.next = self.start_r.q.val();
        self.start_r.d.next = false;
        self.nn.pose.next = self.inbuf.q.val();
        // The sequencer: it owns the pipeline while it runs (no other command uses it then).
        self.filter.reset.next = self.reset.val();
        self.filter.cfg_we.next = false;
        self.filter.cfg_addr.next = self.idx.q.val().get_bits::<5>(0);
        self.filter.cfg_data.next = self.inbuf.q.val().get_bits::<48>(168);
        self.filter.go.next = false;
        self.filter.nn_ready.next = !self.nn.busy.val() && !self.feeder.streaming.val() && !self.start_r.q.val();
        self.filter.cost_valid.next = self.surf.cost_valid.val();
        self.filter.cost.next = self.surf.cost.val();
        self.filter.nn_valid.next = self.surf.nn_valid.val();
        // The filter's largest "distance" is the largest residual.
        self.filter.nn_dist.next = bit_cast::<34, 21>(self.surf.nn_resid.val());
        if self.filter.running.val() {
            self.nn.pose.next = self.filter.pose.val();
        } else if self.polish.busy.val() {
            self.nn.pose.next = self.polish.pose.val();
        }
        // The polish: the sequencer's multiplier (idle after the filter), its starts, its passes.
        self.filter.ext_go.next = self.polish.mul_go.val();
        self.filter.ext_a.next = self.polish.mul_a.val();
        self.filter.ext_b.next = self.polish.mul_b.val();
        self.polish.mul_product.next = self.filter.mul_product.val();
        self.polish.reset.next = self.reset.val();
        self.polish.starts.next = self.pol_starts.q.val();
        self.polish.steps.next = self.pol_steps.q.val();
        self.polish.winner_steps.next = self.pol_more.q.val();
        self.polish.scale_held.next = self.pol_held.q.val();
        self.polish.start_pose.next = self.filter.pose.val();
        if self.polish.start_index.val().any() {
            self.polish.start_pose.next = self.hyps.read_data.val();
        }
        // Started once the filter's `running` has fallen after the Run.
        self.run_r.d.next = self.filter.running.val();
        if self.pol_arm.q.val() && self.run_r.q.val() && !self.filter.running.val() {
            self.pol_ready.d.next = true;
        }
        self.polish.go.next = self.pol_ready.q.val() && !self.polish.busy.val();
        if self.polish.busy.val() {
            self.pol_ready.d.next = false;
            self.pol_arm.d.next = false;
        }
        // A pass: asked for, launched when the pipeline is idle, served point by point.
        if self.polish.pass_go.val() {
            self.pass_req.d.next = true;
        }
        if self.pol_pass.q.val() {
            if self.feeder.issued.val() && !self.surf.nn_valid.val() {
                self.outst.d.next = self.outst.q.val() + 1;
            } else if !self.feeder.issued.val() && self.surf.nn_valid.val() {
                self.outst.d.next = self.outst.q.val() - 1;
            }
            if self.surf.cost_valid.val() {
                self.pc_seen.d.next = true;
                self.pc_cost.d.next = self.surf.cost.val();
            }
        }
        // The queue: a found result in, the head to the pass while it takes points.
        self.found.reset.next = self.reset.val();
        self.found.write.next =
            self.pol_pass.q.val() && self.surf.nn_valid.val() && (self.surf.nn_dist.val() < self.cap_d2.val());
        self.found.data_in.next = bit_cast::<109, 48>(self.surf.nn_point.val())
            | (bit_cast::<109, 48>(self.surf.nn_normal.val()) << 48)
            | (bit_cast::<109, 13>(self.surf.nn_s.val().get_bits::<13>(0)) << 96);
        self.polish.in_valid.next = self.pol_pass.q.val() && self.found.valid.val() && self.polish.ready.val();
        self.polish.in_q.next = self.found.data_out.val().get_bits::<48>(0);
        self.polish.in_n.next = self.found.data_out.val().get_bits::<48>(48);
        self.polish.in_s.next = self.found.data_out.val().get_bits::<13>(96);
        self.found.take.next = self.polish.in_valid.val();
        if self.found.write.val() && !self.found.take.val() {
            self.occ.d.next = self.occ.q.val() + 1;
        } else if !self.found.write.val() && self.found.take.val() {
            self.occ.d.next = self.occ.q.val() - 1;
        }
        if self.polish.in_valid.val() {
            self.quiet.d.next = 0.into();
        } else if self.polish.ready.val() && (self.quiet.q.val() != 7) {
            self.quiet.d.next = self.quiet.q.val() + 1;
        }
        self.polish.pass_done.next = false;
        self.polish.pass_cost.next = self.pc_cost.q.val();
        if self.pol_pass.q.val()
            && self.pc_seen.q.val()
            && !self.occ.q.val().any()
            && !self.outst.q.val().any()
            && self.polish.ready.val()
            && (self.quiet.q.val() == 7)
        {
            self.polish.pass_done.next = true;
            self.pol_pass.d.next = false;
            self.pc_seen.d.next = false;
        }
        self.scan_store.write_enable.next = false;
        self.scan_store.write_address.next = self.waddr.q.val().get_bits::<12>(0);
        self.scan_store.write_data.next = self.inbuf.q.val().get_bits::<48>(168);
        self.ws.clear.next = false;
        self.ws.cost_valid.next = self.surf.cost_valid.val() && self.eval_mode.q.val();
        self.ws.cost.next = self.surf.cost.val();
        self.ws.weigh.next = false;
        self.ws.pre_shift.next = self.hdr.q.val().get_bits::<6>(8);
        self.ws.q_mul.next = self.hdr.q.val().get_bits::<17>(16);
        self.aux.write_enable.next = false;
        self.aux.write_address.next = self.wi.q.val().get_bits::<8>(0);
        self.aux.write_data.next =
            bit_cast::<46, 12>(self.surf.nn_index.val()) | (bit_cast::<46, 34>(self.surf.nn_dist.val()) << 12);
        self.aux.read_address.next = self.wi.q.val().get_bits::<8>(0);

        // A valid frame that arrives while busy gets a Busy answer afterwards (the first only).
        if self.frame.val()
            && (self.state.q.val() != EngState::Idle)
            && (self.status.val() == 0)
            && !self.pending.q.val()
        {
            self.pending.d.next = true;
            self.p_cmd.d.next = self.cmd.val();
            self.p_seq.d.next = self.seq.val();
        }

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
