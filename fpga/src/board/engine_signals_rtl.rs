//! The command engine's wiring: the children's ports and the defaults every state starts
//! from, the polish's start and its passes on credit, the Busy answer owed to a frame that
//! arrived while busy (the first part of the engine's kernel; the states' arms follow in
//! `engine_kernel_rtl.rs`).

use super::*;
use crate::common::rtl::KernelPart;

// A literal in the kernel (`#[hdl_gen]` takes no paths): the credits.
const _: () = assert!(super::super::pass_queue_rtl::PASS_QUEUE == 8);

impl<const P: usize> KernelPart<0> for CommandEngine<P> {
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
    }
}
